//! Moving obstacles ([`CycleInput::obstacle_velocities`]): the input checks,
//! the static controller kept bit for bit at rest, and the time-varying
//! barrier (each step end's half-plane is that of the obstacle moved to that
//! step end's time).

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    Assembly, CommandSource, Config, ConvexPolygon, CycleInput, CycleStatus, InputError,
    PaperController, RobotController, RowKind, Side, closest_point_point_polygon,
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
fn walking<'a>(obstacles: &'a [Poly], velocities: &'a [Vector2<f64>]) -> CycleInput<'a, 16> {
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
        obstacle_velocity_radii: &[],
        speed_cap: ldcbf_controller::NO_SPEED_CAP,
    }
}

#[test]
fn velocities_of_another_length_are_an_input_error() {
    let obstacles = [rect(1.0, 1.5, -0.5, 0.5), rect(2.0, 2.5, 1.0, 1.5)];
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let out = ctl.step(&walking(&obstacles, &[v(0.0, 0.0)]), None);
    assert_eq!(
        out.status,
        CycleStatus::InvalidInput(InputError::ObstacleVelocityCount)
    );
    assert_eq!(out.info.source, CommandSource::Hold);
    assert!(out.foot_target.x.is_finite() && out.foot_target.y.is_finite());
    // Velocities without obstacles are of another length too.
    let out = ctl.step(&walking(&[], &[v(0.0, 0.0)]), None);
    assert_eq!(
        out.status,
        CycleStatus::InvalidInput(InputError::ObstacleVelocityCount)
    );
    let three = [v(0.0, 0.0); 3];
    let input = walking(&obstacles, &three);
    assert_eq!(
        ctl.obstacle_query(&input),
        Err(InputError::ObstacleVelocityCount)
    );
}

#[test]
fn bad_velocities_of_selected_obstacles_are_an_input_error() {
    // The second obstacle is beyond r_active = 4 m: selected only when it
    // closes in faster than vx_max (a person running at the robot).
    let obstacles = [rect(1.0, 1.5, -0.5, 0.5), rect(20.0, 21.0, 0.0, 1.0)];
    let mut ctl = Ctl::new(Config::default()).unwrap();
    for bad in [
        v(f64::NAN, 0.0),
        v(0.0, f64::INFINITY),
        v(100.0, 1.0),
        v(-70.8, 70.8),
    ] {
        let out = ctl.step(&walking(&obstacles, &[bad, v(0.0, 0.0)]), None);
        assert_eq!(
            out.status,
            CycleStatus::InvalidInput(InputError::ObstacleVelocity),
            "{bad:?}"
        );
        assert_eq!(out.info.source, CommandSource::Hold);
        let mut asm = Asm::EMPTY;
        assert_eq!(
            ctl.assemble(&walking(&obstacles, &[bad, v(0.0, 0.0)]), None, &mut asm),
            Err(InputError::ObstacleVelocity)
        );
        // Far away, the velocity is read only to see whether it closes in
        // faster than vx_max; these do not (NaN, across, away from the robot).
        let away = v(bad.x.abs(), bad.y);
        let far = ctl.step(&walking(&obstacles, &[v(0.2, 0.0), away]), None);
        assert!(
            !matches!(far.status, CycleStatus::InvalidInput(_)),
            "{away:?}: {:?}",
            far.status
        );
    }
    // One that closes in on the robot fast enough to be selected from 16 m
    // away (70.8 m/s) is checked as any selected obstacle's: 100.1 m/s is
    // too fast.
    let far = ctl.step(&walking(&obstacles, &[v(0.2, 0.0), v(-70.8, 70.8)]), None);
    assert_eq!(
        far.status,
        CycleStatus::InvalidInput(InputError::ObstacleVelocity)
    );
    // 100 m/s exactly is accepted.
    let out = ctl.step(&walking(&obstacles, &[v(100.0, 0.0), v(0.0, 0.0)]), None);
    assert!(!matches!(out.status, CycleStatus::InvalidInput(_)));
}

#[test]
fn at_rest_is_the_static_controller_bit_for_bit() {
    let obstacles = [
        rect(1.0, 1.5, -0.5, 0.5),
        rect(0.4, 0.9, 0.6, 1.0),
        rect(-1.0, -0.5, -1.0, -0.4),
    ];
    let zeros = [v(0.0, 0.0), v(-0.0, 0.0), v(0.0, -0.0)];
    let mut a = Ctl::new(Config::default()).unwrap();
    let mut b = Ctl::new(Config::default()).unwrap();
    let (mut asm_a, mut asm_b) = (Asm::EMPTY, Asm::EMPTY);
    for t in [0.0, 0.1, 0.25, 0.4] {
        let mut ia = walking(&obstacles, &[]);
        ia.time_in_step = t;
        let ib = CycleInput {
            obstacle_velocities: &zeros,
            obstacle_velocity_radii: &[],
            speed_cap: ldcbf_controller::NO_SPEED_CAP,
            ..ia
        };
        let (oa, ob) = (a.step(&ia, None), b.step(&ib, None));
        assert_eq!(format!("{oa:?}"), format!("{ob:?}"), "t = {t}");
        a.assemble(&ia, None, &mut asm_a).unwrap();
        b.assemble(&ib, None, &mut asm_b).unwrap();
        assert_eq!(format!("{asm_a:?}"), format!("{asm_b:?}"), "t = {t}");
    }
}

/// The polygon moved by `d` (m, world).
fn moved(poly: &Poly, d: Vector2<f64>) -> Poly {
    let pts: Vec<[f64; 2]> = poly
        .vertices()
        .iter()
        .map(|p| [p.x + d.x, p.y + d.y])
        .collect();
    Poly::new(&pts).unwrap()
}

/// Deterministic points `z` around the assembly's `p_0` (a small LCG).
fn trial_points(p0: Vector2<f64>, n: usize) -> Vec<[Vector2<f64>; 3]> {
    let mut s: u64 = 0x2545_f491_4f6c_dd1d;
    let mut r = || {
        s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    (0..n)
        .map(|_| [1.0, 2.0, 3.0].map(|k| p0 + v(0.3 * k + 0.4 * r(), 0.6 * r())))
        .collect()
}

/// Checks every LDCBF and foot row of obstacle 0 of the assembly of `input`
/// against the static half-plane of the polygon moved to each step end's time
/// (linearised from `p_0` moved with it, the same point relative to the
/// polygon as in the input), evaluated at trial plans.
fn rows_follow_the_moved_polygon<const NC: usize>(
    ctl: &ldcbf_controller::Controller<3, 6, NC, 8>,
    input: &CycleInput<'_, 16>,
) {
    let mut asm = Assembly::<3, 6, NC, 8>::EMPTY;
    ctl.assemble(input, None, &mut asm).unwrap();
    let cfg = ctl.config();
    let (t_step, gamma, margin) = (cfg.step_duration, cfg.gamma, cfg.barrier_margin());
    let pred = asm.prediction;
    let tau = t_step - input.time_in_step;
    assert_eq!(pred.time_to_p0, tau);
    let u = input.obstacle_velocities[0];
    let ob = asm.obstacles[..asm.n_obstacles]
        .iter()
        .find(|o| o.index == 0)
        .expect("obstacle 0 is selected");
    assert_eq!(ob.half_plane.rate, ob.half_plane.eta.dot(&u));
    // The static half-plane of the polygon at step end k (time t_k).
    let half_plane = |k: usize| {
        let t = tau + k as f64 * t_step;
        let cp =
            closest_point_point_polygon(&(pred.p0 + u * t), &moved(&input.obstacles[0], u * t));
        assert!(
            (cp.point - (ob.half_plane.c + u * t)).amax() < 1e-12,
            "c at k = {k}"
        );
        assert!(
            (cp.normal - ob.half_plane.eta).amax() < 1e-12,
            "eta at k = {k}"
        );
        (cp.point, cp.normal)
    };
    let h = |k: usize, p: &Vector2<f64>| {
        let (c, eta) = half_plane(k);
        eta.dot(&(p - c)) - margin
    };
    let (mut ldcbf, mut foot) = (0, 0);
    for z in trial_points(pred.p0, 20) {
        let zv = ldcbf_controller::nalgebra::SVector::<f64, 6>::from([
            z[0].x, z[0].y, z[1].x, z[1].y, z[2].x, z[2].y,
        ]);
        let feet = ctl.feet_of(&pred, &zv);
        let p = |k: usize| if k == 0 { pred.p0 } else { z[k - 1] };
        for i in 0..asm.qp.m {
            let value = asm.qp.row(i).dot(&zv) - asm.qp.h[i];
            let k = asm.rows[i].k as usize;
            let expect = match asm.rows[i].kind {
                RowKind::Ldcbf(0) => {
                    ldcbf += 1;
                    -(h(k + 1, &p(k + 1)) - (1.0 - gamma) * h(k, &p(k)))
                }
                RowKind::FootClearance(0) => {
                    foot += 1;
                    let df = cfg.foot_margin(&ob.half_plane.eta, pred.heading.theta[k]);
                    let clear = |j: usize| {
                        let (c, eta) = half_plane(j);
                        eta.dot(&(feet[k] - c)) - df
                    };
                    -clear(k).min(clear(k + 1))
                }
                _ => continue,
            };
            assert!(
                (value - expect).abs() < 1e-9,
                "row {i} ({:?}): {value} vs {expect}",
                asm.rows[i]
            );
        }
    }
    assert_eq!(ldcbf, 3 * 20);
    assert_eq!(
        foot,
        if cfg.foot_clearance.is_some() {
            3 * 20
        } else {
            0
        }
    );
}

#[test]
fn each_step_end_sees_the_polygon_moved_to_its_time() {
    let obstacles = [rect(1.2, 1.6, 0.1, 0.6), rect(0.5, 0.9, -1.2, -0.8)];
    let robot = Config {
        body_radius: 0.25,
        foot_clearance: Some(0.0),
        foot_length: 0.22,
        foot_width: 0.10,
        ..Config::default()
    };
    let paper = Ctl::new(Config::default()).unwrap();
    let robot = RobotController::new(robot).unwrap();
    for u in [v(-0.5, 0.0), v(0.2, -0.4), v(0.0, 0.6), v(-1.2, -0.7)] {
        let velocities = [u, v(0.1, 0.1)];
        for t_in in [0.0, 0.15, 0.4] {
            let mut input = walking(&obstacles, &velocities);
            input.time_in_step = t_in;
            rows_follow_the_moved_polygon(&paper, &input);
            rows_follow_the_moved_polygon(&robot, &input);
        }
    }
}

/// A person running at the robot faster than it walks (`vx_max`, 0.8 m/s) is
/// selected beyond `r_active`: up to `r_active + (c - vx_max) (tau + N T)`,
/// `c` the closing speed (here `tau + N T = 0.3 + 1.2 = 1.5 s`); one closing
/// in at most at `vx_max`, at rest, crossing or walking away only within
/// `r_active` (4 m).
#[test]
fn a_person_running_at_the_robot_is_selected_beyond_r_active() {
    let ctl = Ctl::new(Config::default()).unwrap();
    let cfg = Config::default();
    // About 5.9 m ahead of p_0, beyond r_active.
    let obstacles = [rect(6.0, 6.5, -0.25, 0.25)];
    let velocities = [v(0.0, 0.0)];
    let p0 = ctl
        .obstacle_query(&walking(&obstacles, &velocities))
        .unwrap()
        .center;
    let cp = closest_point_point_polygon(&p0, &obstacles[0]);
    assert!(cp.signed_distance > cfg.r_active + 1.0, "{cp:?}");
    let horizon = (cfg.step_duration - 0.1) + 3.0 * cfg.step_duration;
    // The closing speed at which it is selected from exactly its distance.
    let threshold = cfg.vx_max + (cp.signed_distance - cfg.r_active) / horizon;
    let selected = |u: Vector2<f64>| {
        let mut asm = Asm::EMPTY;
        ctl.assemble(&walking(&obstacles, &[u]), None, &mut asm)
            .unwrap();
        asm.active_obstacles().len()
    };
    // Head-on (the normal is -x): just above the threshold selected, just
    // below not; running away, across, at rest or at vx_max: not.
    assert_eq!(selected(v(-1.01 * threshold, 0.0)), 1);
    assert_eq!(selected(v(-4.0, 0.0)), 1);
    assert_eq!(selected(v(-0.99 * threshold, 0.0)), 0);
    assert_eq!(selected(v(-cfg.vx_max, 0.0)), 0);
    assert_eq!(selected(v(0.0, 0.0)), 0);
    assert_eq!(selected(v(4.0, 0.0)), 0);
    assert_eq!(selected(v(0.0, 4.0)), 0);
    // Selected, its half-plane moves at its closing speed.
    let mut asm = Asm::EMPTY;
    ctl.assemble(&walking(&obstacles, &[v(-4.0, 0.0)]), None, &mut asm)
        .unwrap();
    assert!((asm.active_obstacles()[0].half_plane.rate - 4.0).abs() < 1e-12);
}
