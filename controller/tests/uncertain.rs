//! Obstacles of uncertain velocity ([`CycleInput::obstacle_velocity_radii`],
//! docs/maths.md §2.7): the input checks, zero radii (and the margin off)
//! kept bit for bit, each LDCBF row moved by the reachable set's shift at
//! its step end, and the one-step stopping speed near such an obstacle.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    Assembly, CommandSource, Config, ConvexPolygon, CycleInput, CycleStatus, InputError,
    PaperController, Reach, RecordedInput, RowId, RowKind, Side,
};

type Ctl = PaperController;
type Poly = ConvexPolygon<16>;
type Asm = Assembly<3, 6, 48, 8>;

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

/// The rectangle `[x0, x1] x [y0, y1]`.
fn rect(x0: f64, x1: f64, y0: f64, y1: f64) -> Poly {
    Poly::new(&[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]).unwrap()
}

/// Walking at 0.3 m/s along x, 0.1 s into the step, goal 5 m ahead.
fn walking<'a>(
    obstacles: &'a [Poly],
    velocities: &'a [Vector2<f64>],
    radii: &'a [f64],
) -> CycleInput<'a, 16> {
    CycleInput {
        com_position: v(0.0, 0.0),
        com_velocity: v(0.3, 0.05),
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: v(-0.02, -0.1),
        stance_side: Side::Right,
        time_in_step: 0.1,
        goal: v(5.0, 0.0),
        obstacles,
        obstacle_velocities: velocities,
        obstacle_velocity_radii: radii,
        speed_cap: ldcbf_controller::NO_SPEED_CAP,
    }
}

#[test]
fn radii_of_another_length_are_an_input_error() {
    let obstacles = [rect(1.0, 1.5, -0.5, 0.5), rect(2.0, 2.5, 1.0, 1.5)];
    let mut ctl = Ctl::new(Config::default()).unwrap();
    for radii in [&[0.1][..], &[0.1, 0.2, 0.3]] {
        let input = walking(&obstacles, &[], radii);
        let out = ctl.step(&input, None);
        assert_eq!(
            out.status,
            CycleStatus::InvalidInput(InputError::ObstacleVelocityRadiusCount)
        );
        assert_eq!(out.info.source, CommandSource::Hold);
        assert!(out.foot_target.x.is_finite() && out.foot_target.y.is_finite());
        assert_eq!(
            ctl.obstacle_query(&input),
            Err(InputError::ObstacleVelocityRadiusCount)
        );
    }
}

#[test]
fn bad_radii_of_selected_obstacles_are_an_input_error() {
    // The second obstacle is 20 m away: not selected, its radius not read
    // (unless it is large enough to reach within r_active: see below).
    let obstacles = [rect(1.0, 1.5, -0.5, 0.5), rect(20.0, 21.0, 0.0, 1.0)];
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let velocities = [v(0.2, 0.0), v(0.0, 0.0)];
    for bad in [f64::NAN, -0.1, -f64::MIN_POSITIVE, f64::INFINITY, 100.5] {
        for cfg in [
            Config::default(),
            Config {
                velocity_margin: false,
                ..Config::default()
            },
        ] {
            ctl.configure(cfg).unwrap();
            let out = ctl.step(&walking(&obstacles, &velocities, &[bad, 0.0]), None);
            assert_eq!(
                out.status,
                CycleStatus::InvalidInput(InputError::ObstacleVelocityRadius),
                "{bad}"
            );
            assert_eq!(out.info.source, CommandSource::Hold);
            let mut asm = Asm::EMPTY;
            assert_eq!(
                ctl.assemble(
                    &walking(&obstacles, &velocities, &[bad, 0.0]),
                    None,
                    &mut asm
                ),
                Err(InputError::ObstacleVelocityRadius)
            );
        }
        // Far away and not selected: not read.
        ctl.configure(Config::default()).unwrap();
        let far = ctl.step(&walking(&obstacles, &velocities, &[0.1, bad]), None);
        assert!(
            !matches!(far.status, CycleStatus::InvalidInput(_)),
            "{bad}: {:?}",
            far.status
        );
    }
    // Without velocities a radius is around rest; 100 m/s exactly is accepted.
    let out = ctl.step(&walking(&obstacles, &[], &[100.0, 0.0]), None);
    assert!(!matches!(out.status, CycleStatus::InvalidInput(_)));
}

#[test]
fn zero_radii_and_the_margin_off_are_the_known_velocities_bit_for_bit() {
    let obstacles = [
        rect(1.0, 1.5, -0.5, 0.5),
        rect(0.4, 0.9, 0.6, 1.0),
        rect(-1.0, -0.5, -1.0, -0.4),
    ];
    let velocities = [v(-0.3, 0.1), v(0.0, 0.0), v(0.2, 0.2)];
    let zeros = [0.0, -0.0, 0.0];
    let radii = [0.4, 1.5, 0.2];
    let off = Config {
        velocity_margin: false,
        ..Config::default()
    };
    let mut a = Ctl::new(Config::default()).unwrap();
    let mut b = Ctl::new(Config::default()).unwrap();
    let mut c = Ctl::new(off).unwrap();
    let mut d = Ctl::new(off).unwrap();
    let mut asm = [Asm::EMPTY; 4];
    for t in [0.0, 0.1, 0.25, 0.4] {
        let mut known = walking(&obstacles, &velocities, &[]);
        known.time_in_step = t;
        let zero = CycleInput {
            obstacle_velocity_radii: &zeros,
            ..known
        };
        let given = CycleInput {
            obstacle_velocity_radii: &radii,
            ..known
        };
        let outs = [
            a.step(&known, None),
            b.step(&zero, None),
            c.step(&given, None),
            d.step(&known, None),
        ];
        for o in &outs[1..] {
            assert_eq!(format!("{:?}", outs[0]), format!("{o:?}"), "t = {t}");
        }
        a.assemble(&known, None, &mut asm[0]).unwrap();
        b.assemble(&zero, None, &mut asm[1]).unwrap();
        c.assemble(&given, None, &mut asm[2]).unwrap();
        d.assemble(&known, None, &mut asm[3]).unwrap();
        for x in &asm[1..] {
            assert_eq!(format!("{:?}", asm[0]), format!("{x:?}"), "t = {t}");
        }
    }
}

/// The row `h_{t1}(p_{k+1}) >= (1 - gamma) h_{t0}(p_k)` of an obstacle of
/// radius `u` is the one of the same obstacle with a known velocity, its
/// bound lowered by `(S(t1) - rate t1) - (1 - gamma) (S(t0) - rate t0)`:
/// the half-plane at each step end moved on by the reachable set's shift.
#[test]
fn each_barrier_row_moves_by_the_reachable_set() {
    let obstacles = [rect(1.2, 1.6, -0.2, 0.2)];
    let velocities = [v(-0.5, 0.3)];
    let cfg = Config::default();
    let ctl = Ctl::new(cfg).unwrap();
    for u in [0.05, 0.3, 1.0, 1.5, 3.0] {
        let (mut known, mut given) = (Asm::EMPTY, Asm::EMPTY);
        let radii = [u];
        ctl.assemble(&walking(&obstacles, &velocities, &[]), None, &mut known)
            .unwrap();
        ctl.assemble(&walking(&obstacles, &velocities, &radii), None, &mut given)
            .unwrap();
        assert_eq!(known.qp.m, given.qp.m);
        let hp = given.active_obstacles()[0].half_plane;
        assert_eq!(hp.rate, known.active_obstacles()[0].half_plane.rate);
        let reach = Reach {
            spread: u,
            speed: velocities[0].norm(),
        };
        let lim = cfg.reach_limits();
        assert_eq!(hp.reach, reach);
        let tau = given.prediction.time_to_p0;
        let extra = |t: f64| reach.shift(&lim, hp.rate, t) - hp.rate * t;
        let mut seen = 0;
        for (i, id) in given.rows.iter().enumerate().take(given.qp.m) {
            assert_eq!(*id, known.rows[i]);
            let RowId {
                kind: RowKind::Ldcbf(0),
                k,
            } = *id
            else {
                assert_eq!(given.qp.h[i], known.qp.h[i], "row {i}");
                continue;
            };
            let t0 = tau + f64::from(k) * cfg.step_duration;
            let t1 = t0 + cfg.step_duration;
            let lowered = extra(t1) - (1.0 - cfg.gamma) * extra(t0);
            let d = known.qp.h[i] - given.qp.h[i];
            assert!((d - lowered).abs() < 1e-12, "u {u} k {k}: {d} vs {lowered}");
            // The set grows: each later row is moved more than at rest.
            assert!(extra(t1) >= extra(t0) - 1e-15);
            seen += 1;
        }
        assert_eq!(seen, 3);
    }
}

/// Near an obstacle of uncertain velocity the robot plans no forward speed
/// above the one-step stopping speed; with the same obstacle known at rest,
/// or far enough that it cannot meet the robot within the horizon, it walks
/// faster. (A person who may accelerate by at most 0 m/s^2 with a velocity
/// within 0.2 m/s of rest: a set that grows slowly, so the QP stays feasible.)
#[test]
fn near_an_uncertain_obstacle_the_robot_walks_no_faster_than_one_step_stops_it() {
    let cfg = Config {
        person_accel_max: 0.0,
        ..Config::default()
    };
    let beta = (cfg.gravity / cfg.com_height).sqrt();
    let stop = beta * (beta * cfg.step_duration).tanh() * cfg.l_max;
    // 1.3 m ahead and to the left, off the way; the robot at rest.
    let near = [rect(1.0, 1.4, 0.8, 1.2)];
    let far = [rect(2.2, 2.6, 0.8, 1.2)];
    let fastest = |obstacles: &[Poly], radii: &[f64]| {
        let mut ctl = Ctl::new(cfg).unwrap();
        let out = ctl.step(
            &CycleInput {
                obstacle_velocity_radii: radii,
                ..RecordedInput::at_rest(v(8.0, 0.0)).input(obstacles)
            },
            None,
        );
        assert_eq!(out.status, CycleStatus::Optimal, "{radii:?}");
        out.plan
            .states
            .iter()
            .map(|s| s.velocity.x)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let known = fastest(&near, &[]);
    let unsure = fastest(&near, &[0.2]);
    assert!(known > stop + 0.1, "known at rest: {known}");
    assert!(unsure <= stop + 1e-9, "uncertain: {unsure} > {stop}");
    // Beyond the farthest it may walk within the horizon (0.2 m/s for at
    // most 1.6 s) plus the robot's walk (0.8 m/s): no cap.
    let top = fastest(&far, &[0.2]);
    assert!(top > stop + 0.1, "far: {top}");
}
