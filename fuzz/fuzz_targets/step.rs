//! Fuzz target: `Controller::step` on arbitrary inputs.
//!
//! Every f64 of the input is arbitrary (NaN, infinities, huge and tiny values),
//! obstacles are arbitrary vertex lists (built with `ConvexPolygon::new` or
//! `ConvexPolygon::hull`; rejected lists are skipped, as a caller would), the
//! configuration's gamma and delta vary, and several cycles run in a row so the
//! warm-start and fallback memory is exercised. Checked: no panic, and every
//! output is finite; a non-`Hold` command satisfies the leg-reachability rows of
//! its own QP.
#![no_main]

use arbitrary::Arbitrary;
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::relax::RowClass;
use ldcbf_controller::{
    CommandSource, Config, ConvexPolygon, CycleInput, CycleOutput, PaperController, Side,
};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Cycle {
    p: [f64; 2],
    v: [f64; 2],
    heading: f64,
    omega: f64,
    foot: [f64; 2],
    right: bool,
    t_in: f64,
    goal: [f64; 2],
    speed_cap: f64,
}

#[derive(Arbitrary, Debug)]
struct Case {
    gamma: f64,
    delta: f64,
    hull: bool,
    obstacles: Vec<Vec<[f64; 2]>>,
    cycles: Vec<Cycle>,
}

fn finite(o: &CycleOutput<3>) -> bool {
    let f2 = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
    f2(&o.foot_target)
        && o.turning_rate.is_finite()
        && f2(&o.plan.x0.position)
        && f2(&o.plan.x0.velocity)
        && o.plan.states.iter().all(|s| f2(&s.position) && f2(&s.velocity) && s.heading.is_finite())
        && o.plan.feet.iter().all(f2)
}

fuzz_target!(|case: Case| {
    let cfg = Config {
        gamma: if case.gamma.is_finite() { case.gamma.abs().clamp(0.01, 1.0) } else { 0.3 },
        delta: if case.delta.is_finite() { case.delta.abs().min(1.0) } else { 0.0 },
        ..Config::default()
    };
    let mut ctl = PaperController::new(cfg).expect("valid config");
    let polys: Vec<ConvexPolygon<16>> = case
        .obstacles
        .iter()
        .take(40)
        .filter_map(|v| {
            if case.hull {
                ConvexPolygon::hull(v).ok()
            } else {
                ConvexPolygon::new(v).ok()
            }
        })
        .collect();
    for c in case.cycles.iter().take(16) {
        let input = CycleInput {
            com_position: Vector2::from(c.p),
            com_velocity: Vector2::from(c.v),
            heading: c.heading,
            turning_rate: c.omega,
            stance_foot: Vector2::from(c.foot),
            stance_side: if c.right { Side::Right } else { Side::Left },
            time_in_step: c.t_in,
            goal: Vector2::from(c.goal),
            obstacles: &polys,
            obstacle_velocities: &[],
            speed_cap: c.speed_cap,
        };
        let out = ctl.step(&input, None);
        assert!(finite(&out), "non-finite output {out:?} for {c:?}");
        if out.info.source != CommandSource::Hold {
            // Reachability rows of this cycle's QP hold for the returned plan.
            let asm = ctl.last_assembly();
            // The QP's variables are the planned positions (see `constraints`).
            let u = ctl.variables_of(&out.plan);
            for ((g, h, n), id) in asm.qp.rows_with_norm().zip(&asm.rows) {
                if RowClass::of(id.kind) == RowClass::Reach {
                    let viol = (g.dot(&u) - h) / n;
                    let scale = 1.0 + h.abs();
                    assert!(viol <= 1e-6 * scale, "reach row violated by {viol:e}: {out:?} for {c:?}");
                }
            }
        }
    }
});
