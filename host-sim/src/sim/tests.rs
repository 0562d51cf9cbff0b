//! Tests of the closed loop: timing repeats and disturbances.

use super::*;
use crate::scenario::{LoadOptions, load};

/// `simple`, cut to `time_limit` s, with `--set` overrides.
fn simple(time_limit: f64, sets: &[(&str, &str)]) -> Scenario {
    let mut all = vec![("time_limit".to_string(), time_limit.to_string())];
    all.extend(sets.iter().map(|(k, v)| (k.to_string(), v.to_string())));
    load(
        "simple",
        &LoadOptions {
            seed: None,
            sets: all,
        },
    )
    .unwrap()
}

fn go(sc: &Scenario) -> SimResult {
    let opts = SimOptions {
        record_scans: false,
        ..SimOptions::default()
    };
    run(sc, opts).unwrap()
}

fn same_walk(a: &SimResult, b: &SimResult) -> bool {
    a.samples == b.samples
        && a.footsteps == b.footsteps
        && a.cycles.len() == b.cycles.len()
        && a.cycles
            .iter()
            .zip(&b.cycles)
            .all(|(x, y)| x.output.foot_target == y.output.foot_target)
}

#[test]
fn timing_repeats_leave_the_run_unchanged() {
    let sc = simple(3.0, &[]);
    let once = go(&sc);
    for solver in [Solver::Own, Solver::Clarabel] {
        let opts = |k| SimOptions {
            record_scans: false,
            solver,
            timing_repeats: k,
            ..SimOptions::default()
        };
        let a = run(&sc, opts(1)).unwrap();
        let b = run(&sc, opts(3)).unwrap();
        assert!(same_walk(&a, &b), "{solver:?}");
        assert!(
            a.cycles
                .iter()
                .zip(&b.cycles)
                .all(|(x, y)| x.output == y.output),
            "{solver:?}"
        );
        assert!(b.cycles.iter().all(|c| c.compute_ns > 0));
        let err = run(&sc, opts(0)).map(|_| ()).unwrap_err();
        assert_eq!(err, SimError::NoTimingRepeats);
        assert!(err.to_string().contains(">= 1"), "{err}");
        let err = run(&sc, opts(MAX_TIMING_REPEATS + 1))
            .map(|_| ())
            .unwrap_err();
        assert_eq!(err, SimError::TooManyTimingRepeats(MAX_TIMING_REPEATS + 1));
    }
    assert!(same_walk(
        &once,
        &run(
            &sc,
            SimOptions {
                timing_repeats: 5,
                ..SimOptions::default()
            }
        )
        .unwrap()
    ));
}

#[test]
fn zero_disturbance_is_the_undisturbed_run_bit_for_bit() {
    let base = go(&simple(3.0, &[]));
    let zero = go(&simple(
        3.0,
        &[
            ("disturbance.seed", "9"),
            ("disturbance.push_time", "1.0"),
            ("disturbance.push_period", "0.5"),
            ("disturbance.plant_com_height", "1.0"),
            ("disturbance.foot_sigma", "0.0"),
            ("disturbance.noise_position", "0.0"),
        ],
    ));
    assert!(same_walk(&base, &zero));
    assert!(zero.disturbance.pushes.is_empty());
    assert_eq!(zero.disturbance.foot_errors, 0);
}

#[test]
fn a_push_changes_the_velocity_by_the_impulse_at_its_tick() {
    let base = go(&simple(2.0, &[]));
    let pushed = go(&simple(
        2.0,
        &[
            ("disturbance.push_time", "1.234"),
            ("disturbance.push_forward", "0.1"),
            ("disturbance.push_lateral", "0.3"),
        ],
    ));
    let log = &pushed.disturbance;
    assert_eq!(log.pushes.len(), 1);
    assert_eq!(log.pushes[0].tick, 1234);
    let n = 1234;
    assert_eq!(base.samples[..n], pushed.samples[..n]);
    let dv = Vector2::new(log.pushes[0].delta_v[0], log.pushes[0].delta_v[1]);
    // The impulse in the body frame, rotated by the heading at the push.
    let (s, c) = base.samples[n].heading.sin_cos();
    let expected = Vector2::new(c * 0.1 - s * 0.3, s * 0.1 + c * 0.3);
    assert!((dv - expected).amax() < 1e-15);
    assert_eq!(pushed.samples[n].position, base.samples[n].position);
    assert_eq!(pushed.samples[n].velocity, base.samples[n].velocity + dv);
    assert_ne!(pushed.samples[n + 1], base.samples[n + 1]);
}

#[test]
fn height_mismatch_changes_the_plant_only() {
    let base = go(&simple(2.0, &[]));
    let low = go(&simple(2.0, &[("disturbance.plant_com_height", "0.9")]));
    assert_eq!(low.disturbance.plant_com_height, 0.9);
    assert_eq!(low.disturbance.model_com_height, 1.0);
    assert_eq!(low.scenario.config.com_height, 1.0);
    // The first cycle sees the same (rest) state, so plans the same step.
    assert_eq!(
        low.cycles[0].output.foot_target,
        base.cycles[0].output.foot_target
    );
    assert_ne!(low.samples[1500], base.samples[1500]);
}

#[test]
fn foot_errors_and_noise_are_seeded() {
    let sets = |seed: &'static str| {
        vec![
            ("disturbance.seed", seed),
            ("disturbance.foot_sigma", "0.02"),
            ("disturbance.noise_position", "0.01"),
            ("disturbance.noise_velocity", "0.02"),
            ("disturbance.noise_heading", "0.01"),
        ]
    };
    let a = go(&simple(2.0, &sets("1")));
    let b = go(&simple(2.0, &sets("1")));
    let c = go(&simple(2.0, &sets("2")));
    assert!(same_walk(&a, &b));
    assert!(!same_walk(&a, &c));
    let log = &a.disturbance;
    assert_eq!(log.foot_errors, a.steps());
    assert!(log.max_foot_error > 0.0 && log.noisy_cycles == a.cycles.len());
    // Every landed foot is its target plus an error no larger than the largest.
    let targets: Vec<Vector2<f64>> = a
        .cycles
        .iter()
        .filter(|c| c.landed)
        .map(|c| c.output.foot_target)
        .collect();
    assert_eq!(targets.len(), a.steps());
    for (f, t) in a.footsteps[1..].iter().zip(&targets) {
        let e = (f.position - t).norm();
        assert!(e > 0.0 && e <= log.max_foot_error + 1e-15);
    }
    // The controller saw a noisy state: its x0 is not the true sample.
    let c0 = &a.cycles[1];
    let tick = (c0.time / PLANT_DT).round() as usize;
    assert_ne!(c0.output.plan.x0.position, a.samples[tick].position);
}
