//! The policy toward people (docs/safety.md, "A person walking into the
//! robot"): a person closing in faster than the robot can step away makes the
//! QP infeasible, and the relaxed command then steps away from them, never
//! towards them; near a moving obstacle the forward speed is bounded by the
//! one-step stopping speed.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    CommandSource, Config, ConvexPolygon, CycleInput, CycleOutput, CycleStatus, PaperController,
    Side,
};

type Poly = ConvexPolygon<16>;

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

/// A square person of side 0.4 m centred at `c`.
fn person(c: Vector2<f64>) -> Poly {
    let r = 0.2;
    Poly::new(&[
        [c.x - r, c.y - r],
        [c.x + r, c.y - r],
        [c.x + r, c.y + r],
        [c.x - r, c.y + r],
    ])
    .unwrap()
}

/// At rest at the origin, facing +x, the stance foot under the CoM, at the
/// end of a step (so `p_0` is the origin), goal `goal`.
fn standing<'a>(
    goal: Vector2<f64>,
    obstacles: &'a [Poly],
    velocities: &'a [Vector2<f64>],
) -> CycleInput<'a, 16> {
    CycleInput {
        com_position: v(0.0, 0.0),
        com_velocity: v(0.0, 0.0),
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: v(0.0, 0.0),
        stance_side: Side::Right,
        time_in_step: Config::default().step_duration,
        goal,
        obstacles,
        obstacle_velocities: velocities,
        obstacle_velocity_radii: &[],
        speed_cap: ldcbf_controller::NO_SPEED_CAP,
    }
}

/// The largest displacement of the planned CoM (every step end) along `dir`
/// from `p_0`, m. (Not the feet: to move the CoM back the LIP places the foot
/// ahead of it.)
fn largest_move(out: &CycleOutput<3>, dir: Vector2<f64>) -> f64 {
    let p0 = out.plan.x0.position;
    out.plan
        .states
        .iter()
        .map(|s| dir.dot(&(s.position - p0)))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// A person walks at the robot along its path (the goal is behind them) at
/// 1 m/s, ten times the robot's backward speed: the QP is infeasible and the
/// relaxed plan's CoM moves away from the person at every step end, although the goal lies beyond the person.
#[test]
fn a_person_closing_in_head_on_is_not_stepped_towards() {
    let people = [person(v(0.9, 0.0))];
    let vel = [v(-1.0, 0.0)];
    let mut ctl = PaperController::new(Config::default()).unwrap();
    let out = ctl.step(&standing(v(5.0, 0.0), &people, &vel), None);
    assert_eq!(out.status, CycleStatus::Infeasible);
    assert_eq!(out.info.source, CommandSource::RelaxedSafety);
    let towards = largest_move(&out, v(1.0, 0.0));
    assert!(towards <= 1e-9, "moves {towards} m towards the person");
    // It steps back: the last planned CoM is behind p_0.
    assert!(out.plan.states[2].position.x < out.plan.x0.position.x - 0.05);
}

/// A person comes from the left across the path, at 1.2 m/s, while the goal
/// lies ahead: the relaxed plan moves to the right, away from them.
#[test]
fn a_person_closing_in_from_the_side_is_not_stepped_towards() {
    let people = [person(v(0.2, 0.75))];
    let vel = [v(0.0, -1.2)];
    let mut ctl = PaperController::new(Config::default()).unwrap();
    let out = ctl.step(&standing(v(5.0, 0.0), &people, &vel), None);
    assert_eq!(out.status, CycleStatus::Infeasible);
    let towards = largest_move(&out, v(0.0, 1.0));
    assert!(towards <= 1e-9, "moves {towards} m towards the person");
}

/// Walking at 0.5 m/s with a person 1.3 m ahead and to the left, crossing, the planned forward
/// velocity stays within the one-step stopping speed `beta tanh(beta T)
/// l_max`; with the same obstacle at rest the robot keeps its pace.
#[test]
fn near_a_moving_person_the_robot_walks_no_faster_than_it_can_stop() {
    let cfg = Config::default();
    let beta = (cfg.gravity / cfg.com_height).sqrt();
    let stop = beta * (beta * cfg.step_duration).tanh() * cfg.l_max;
    assert!((stop - 0.46).abs() < 0.01, "{stop}");
    let people = [person(v(1.2, 1.0))];
    let fast = |velocities: &[Vector2<f64>]| {
        let mut ctl = PaperController::new(cfg).unwrap();
        let input = CycleInput {
            com_velocity: v(0.5, 0.0),
            ..standing(v(8.0, 0.0), &people, velocities)
        };
        let out = ctl.step(&input, None);
        assert_eq!(out.status, CycleStatus::Optimal);
        out.plan
            .states
            .iter()
            .map(|s| s.velocity.x)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let moving = fast(&[v(0.0, -0.5)]);
    assert!(moving <= stop + 1e-9, "{moving} > {stop}");
    let at_rest = fast(&[v(0.0, 0.0)]);
    assert!(at_rest > stop + 0.1, "{at_rest}");
}
