//! Moving obstacles ([`CycleInput::obstacle_velocities`]): the input checks,
//! the static controller kept bit for bit at rest, and the time-varying
//! barrier (each step end's half-plane is that of the obstacle moved to that
//! step end's time).

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    Assembly, CommandSource, Config, ConvexPolygon, CycleInput, CycleStatus, InputError,
    PaperController, Side,
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
    }
}

#[test]
fn velocities_of_another_length_are_an_input_error() {
    let obstacles = [rect(1.0, 1.5, -0.5, 0.5), rect(2.0, 2.5, 1.0, 1.5)];
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let out = ctl.step(&walking(&obstacles, &[v(0.0, 0.0)]));
    assert_eq!(
        out.status,
        CycleStatus::InvalidInput(InputError::ObstacleVelocityCount)
    );
    assert_eq!(out.info.source, CommandSource::Hold);
    assert!(out.foot_target.x.is_finite() && out.foot_target.y.is_finite());
    // Velocities without obstacles are of another length too.
    let out = ctl.step(&walking(&[], &[v(0.0, 0.0)]));
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
    // The second obstacle is beyond r_active = 4 m: its velocity is not read.
    let obstacles = [rect(1.0, 1.5, -0.5, 0.5), rect(20.0, 21.0, 0.0, 1.0)];
    let mut ctl = Ctl::new(Config::default()).unwrap();
    for bad in [
        v(f64::NAN, 0.0),
        v(0.0, f64::INFINITY),
        v(100.0, 1.0),
        v(-70.8, 70.8),
    ] {
        let out = ctl.step(&walking(&obstacles, &[bad, v(0.0, 0.0)]));
        assert_eq!(
            out.status,
            CycleStatus::InvalidInput(InputError::ObstacleVelocity),
            "{bad:?}"
        );
        assert_eq!(out.info.source, CommandSource::Hold);
        let mut asm = Asm::EMPTY;
        assert_eq!(
            ctl.assemble(&walking(&obstacles, &[bad, v(0.0, 0.0)]), &mut asm),
            Err(InputError::ObstacleVelocity)
        );
        let far = ctl.step(&walking(&obstacles, &[v(0.2, 0.0), bad]));
        assert!(
            !matches!(far.status, CycleStatus::InvalidInput(_)),
            "{bad:?}: {:?}",
            far.status
        );
    }
    // 100 m/s exactly is accepted.
    let out = ctl.step(&walking(&obstacles, &[v(100.0, 0.0), v(0.0, 0.0)]));
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
            ..ia
        };
        let (oa, ob) = (a.step(&ia), b.step(&ib));
        assert_eq!(format!("{oa:?}"), format!("{ob:?}"), "t = {t}");
        a.assemble(&ia, &mut asm_a).unwrap();
        b.assemble(&ib, &mut asm_b).unwrap();
        assert_eq!(format!("{asm_a:?}"), format!("{asm_b:?}"), "t = {t}");
    }
}
