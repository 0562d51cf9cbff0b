//! The node's logic without DDS: conversions, the cycle's trigger, the
//! messages, the parameter file, the recorded run.

mod common;

use common::{gait_at, goal};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{CycleStatus, RobotController};
use ldcbf_ros2::msgs::{FootstepCommand, GaitState, Time};
use ldcbf_ros2::node::{NavNode, input_of, quaternion, yaw};
use ldcbf_ros2::params::Params;
use ldcbf_ros2::record::{odometry, play};
use ldcbf_sim::scenario::{LoadOptions, load};

fn stamp(t: f64) -> Time {
    Time::from_secs(t)
}

fn gait(t: f64) -> GaitState {
    gait_at(stamp(t), [0.0, 3.0])
}

fn circles() -> (RobotController, Vec<ldcbf_sim::world::Polygon>) {
    let sc = load("circles", &LoadOptions::default()).unwrap();
    (RobotController::new(sc.config).unwrap(), sc.obstacles)
}

#[test]
fn yaw_and_body_twist_round_trip() {
    for psi in [0.0, 0.3, -2.0, 3.0] {
        assert!((yaw(&quaternion(psi)) - psi).abs() < 1e-12);
        let v = Vector2::new(0.4, -0.1);
        let o = odometry(stamp(1.0), "map", Vector2::new(1.0, 2.0), v, psi, 0.2);
        let (_, obs) = circles();
        let inp = input_of(&o, &gait(1.0), Vector2::new(5.0, 5.0), &obs, &[], &[]);
        assert!((inp.com_velocity - v).norm() < 1e-12, "{psi}");
        assert!((inp.heading - psi).abs() < 1e-12);
        assert_eq!(inp.com_position, Vector2::new(1.0, 2.0));
        assert_eq!(inp.stance_side, ldcbf_controller::Side::Left);
    }
}

/// A gait state runs its cycle only with a goal and an odometry at least as
/// recent; the command is the controller's own on the same input, bit for bit.
#[test]
fn gait_state_waits_for_its_odometry() {
    let (ctl, obs) = circles();
    let mut twin = ctl.clone();
    let mut nav = NavNode::new(ctl, obs.clone(), "map");
    let odom = |t: f64| {
        odometry(
            stamp(t),
            "map",
            Vector2::new(0.0, 3.0),
            Vector2::new(0.1, 0.0),
            0.0,
            0.0,
        )
    };
    assert!(nav.on_gait(gait(0.5)).is_none(), "no goal, no odometry");
    assert!(nav.on_goal(&goal(9.0, 3.0)).is_none(), "no odometry");
    assert!(
        nav.on_odom(odom(0.45)).is_none(),
        "odometry older than the gait state"
    );
    let m = nav.on_odom(odom(0.5)).expect("its odometry arrived");
    assert!(
        nav.on_odom(odom(0.55)).is_none(),
        "one cycle per gait state"
    );
    assert!(
        nav.on_gait(gait(0.5)).is_none(),
        "a repeated gait state is ignored"
    );
    let o = odom(0.5);
    let want = twin.step(
        &input_of(&o, &gait(0.5), Vector2::new(9.0, 3.0), &obs, &[], &[]),
        None,
    );
    let c = &m.command;
    assert_eq!(c.header.stamp, stamp(0.5));
    assert_eq!(
        (c.foot_target.x.to_bits(), c.foot_target.y.to_bits()),
        (want.foot_target.x.to_bits(), want.foot_target.y.to_bits())
    );
    assert_eq!(c.turning_rate.to_bits(), want.turning_rate.to_bits());
    assert_eq!(c.planned_feet.len(), want.plan.feet.len());
    assert_eq!(c.predicted_com.len(), want.plan.feet.len() + 1);
    assert_eq!(
        (c.result, c.status.as_str()),
        (FootstepCommand::SOLVED, "optimal")
    );
    assert_eq!(m.footsteps.poses.len(), want.plan.feet.len());
    assert!(m.markers.markers.iter().any(|k| k.ns == "obstacles"));
    assert_eq!(m.diagnostics.status[0].level, 0);
}

#[test]
fn bad_input_is_a_typed_result() {
    let (ctl, obs) = circles();
    let mut nav = NavNode::new(ctl, obs, "map");
    let _ = nav.on_goal(&goal(9.0, 3.0));
    let mut o = odometry(
        stamp(0.0),
        "map",
        Vector2::new(0.0, 3.0),
        Vector2::zeros(),
        0.0,
        0.0,
    );
    o.pose.pose.position.x = f64::NAN;
    nav.on_odom(o);
    let m = nav.on_gait(gait(0.0)).unwrap();
    assert_eq!(m.command.result, FootstepCommand::INVALID_INPUT);
    assert_eq!(
        m.command.status,
        CycleStatus::InvalidInput(ldcbf_controller::InputError::State).name()
    );
    assert_eq!(m.diagnostics.status[0].level, 2);
    assert!(m.command.foot_target.x.is_finite());
}

#[test]
fn parameter_file() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/config/ldcbf_nav.yaml"
    ))
    .unwrap();
    let p = Params::parse("ldcbf_nav.yaml", &text).unwrap();
    assert_eq!((p.map.as_str(), p.frame_id.as_str()), ("circles", "map"));
    assert_eq!(p.topics.command, "/footstep_command");
    assert!(!p.lidar && p.topics.scan == "/scan");
    let e = Params::parse(
        "f.yaml",
        "ldcbf_nav:\n  ros__parameters:\n    perception: sonar\n",
    )
    .unwrap_err();
    assert!(
        format!("{e:#}").contains("perception: expected map or lidar"),
        "{e:#}"
    );
    let e = Params::parse("f.yaml", "ldcbf_nav:\n  ros__parameters:\n    mapp: x\n").unwrap_err();
    assert!(
        format!("{e:#}").contains("f.yaml: ldcbf_nav.ros__parameters.mapp: unknown"),
        "{e:#}"
    );
    let e = Params::parse(
        "f.yaml",
        "ldcbf_nav:\n  ros__parameters:\n    domain_id: 999\n",
    )
    .unwrap_err();
    assert!(
        format!("{e:#}").contains("domain_id: expected 0..=232"),
        "{e:#}"
    );
    let e = Params::parse("f.yaml", "other:\n  ros__parameters: {}\n").unwrap_err();
    assert!(format!("{e:#}").contains("no `ldcbf_nav:`"), "{e:#}");
    let e = Params::parse(
        "f.yaml",
        "ldcbf_nav:\n  ros__parameters:\n    topics: {odom: odom}\n",
    )
    .unwrap_err();
    assert!(
        format!("{e:#}").contains("topics.odom: `odom` is not an absolute ROS 2 topic name"),
        "{e:#}"
    );
}

/// The recorded run: a command for every cycle, most equal to the run's.
#[test]
fn recorded_run_as_messages() {
    let p = play("circles", &[], "map").unwrap();
    assert!(p.cycles.len() > 100);
    assert!(
        p.same_as_run > p.cycles.len() / 2,
        "{} of {}",
        p.same_as_run,
        p.cycles.len()
    );
    assert!(
        p.cycles
            .iter()
            .all(|c| c.command.header.stamp == c.gait.header.stamp)
    );
    assert!(
        play("maze", &[], "map").is_err(),
        "maze walks to RRT* subgoals"
    );
}

/// The stand-in and the node closed in one process (no DDS): the walk of
/// `ldcbf-sim run circles`, to the goal in about as many cycles.
#[test]
fn stand_in_closes_the_loop() {
    let sc = load("circles", &LoadOptions::default()).unwrap();
    let (ctl, obs) = circles();
    let (end, cycles) = closed_loop(&sc, NavNode::new(ctl, obs, "map"));
    assert_eq!(end, ldcbf_ros2::robot::End::GoalReached);
    let sim = ldcbf_sim::run(&sc, ldcbf_sim::SimOptions::default()).unwrap();
    let n = sim.cycles.len();
    assert!(
        cycles.abs_diff(n) <= n / 50,
        "{cycles} cycles, ldcbf-sim {n}"
    );
}

/// The node and the stand-in, one cycle after the other; (end, cycles).
fn closed_loop(sc: &ldcbf_sim::Scenario, mut nav: NavNode) -> (ldcbf_ros2::robot::End, usize) {
    let mut robot = ldcbf_ros2::robot::Robot::new(sc, "map").unwrap();
    let _ = nav.on_goal(&robot.goal());
    let mut cycles = 0usize;
    loop {
        let (o, g, scan) = robot.sense();
        assert!(nav.on_odom(o).is_none());
        if let Some(s) = scan {
            assert!(nav.on_scan(s).is_none(), "the gait state comes last");
        }
        let m = nav.on_gait(g).expect("one cycle per gait state");
        robot.apply(&m.command);
        cycles += 1;
        if let Some(end) = robot.advance() {
            if end == ldcbf_ros2::robot::End::GoalReached {
                assert!((robot.position() - sc.goal).norm() <= sc.success_radius);
                assert!(robot.steps() > 10);
            }
            return (end, cycles);
        }
    }
}

/// `/scan` through the project's perception: the LiDAR scenario `crowded`
/// walked to its goal by the node on the stand-in's scans alone.
#[test]
fn lidar_node_walks_crowded_on_scans() {
    let sc = load("crowded", &LoadOptions::default()).unwrap();
    assert_eq!(sc.perception, ldcbf_sim::sense::Perception::Lidar);
    let ctl = RobotController::new(sc.config).unwrap();
    let nav = NavNode::new(ctl, sc.obstacles.clone(), "map").with_lidar(sc.lidar.clone());
    let (end, _) = closed_loop(&sc, nav);
    assert_eq!(end, ldcbf_ros2::robot::End::GoalReached);
}

/// A scan's hit points are where the LiDAR saw them (to f32 ranges), and the
/// perception refuses a scan that is not a full turn.
#[test]
fn scan_rays_and_refusal() {
    use ldcbf_ros2::scan::{laser_scan, rays};
    use ldcbf_sim::sense::Lidar;
    let sc = load("crowded", &LoadOptions::default()).unwrap();
    // Without noise: a range carries no error across the ray.
    let params = ldcbf_sim::sense::LidarParams {
        noise_sigma: 0.0,
        ..sc.lidar.clone()
    };
    let mut lidar = Lidar::new(params, 1).unwrap();
    let (origin, heading) = (sc.start, 0.7);
    let hits = lidar.scan_rays(origin, heading, &sc.obstacles);
    let scan = laser_scan(stamp(0.0), origin, &hits, sc.lidar.range);
    let back = rays(&scan, origin, heading).unwrap();
    assert_eq!(back.len(), hits.len());
    assert!(hits.iter().any(Option::is_some) && hits.iter().any(Option::is_none));
    for (a, b) in hits.iter().zip(&back) {
        match (a, b) {
            (Some(a), Some(b)) => assert!((a - b).norm() < 1e-5, "{a} vs {b}"),
            (None, None) => {}
            _ => panic!("a hit lost or made up"),
        }
    }
    let mut half = scan.clone();
    half.ranges.truncate(scan.ranges.len() / 2);
    let e = rays(&half, origin, heading).unwrap_err();
    assert!(format!("{e}").contains("not a full turn"), "{e}");
    let ctl = RobotController::new(sc.config).unwrap();
    let mut nav = NavNode::new(ctl, Vec::new(), "map").with_lidar(sc.lidar.clone());
    assert!(nav.on_scan(half).is_none());
    assert_eq!(nav.rejections().scans, 1);
}
