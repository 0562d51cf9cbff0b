//! Hostile and careless inputs (issue 38): each class ends in a counted,
//! logged refusal with a defined command (`INVALID_INPUT`), or in the
//! simulator's behaviour. Without DDS (the same messages over Cyclone DDS:
//! `ros2/tests/python/test_hostile_dds.py`).

mod common;

use common::{gait_at, goal};
use ldcbf_controller::RobotController;
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_ros2::msgs::{FootstepCommand, GaitState, LaserScan, Odometry, Time};
use ldcbf_ros2::node::{CycleMessages, NavNode};
use ldcbf_ros2::params::Params;
use ldcbf_ros2::record::{odometry, play};
use ldcbf_sim::scenario::{LoadOptions, load};

fn at(t: f64) -> Time {
    Time::from_secs(t)
}

fn odom(stamp: Time) -> Odometry {
    odometry(
        stamp,
        "map",
        Vector2::new(0.0, 0.0),
        Vector2::zeros(),
        0.0,
        0.0,
    )
}

fn gait(stamp: Time) -> GaitState {
    gait_at(stamp, [0.0, 0.1])
}

/// A full turn of `n` rays, every one at `r` m (a ring around the robot).
fn ring(stamp: Time, n: usize, r: f32) -> LaserScan {
    ldcbf_ros2::scan::full_turn(stamp, vec![r; n], 3.0)
}

/// The LiDAR node of `crowded`, with a goal.
fn lidar_node() -> NavNode {
    let sc = load("crowded", &LoadOptions::default()).unwrap();
    let ctl = RobotController::new(sc.config).unwrap();
    let mut nav = NavNode::new(ctl, Vec::new(), "map").with_lidar(sc.lidar.clone());
    assert!(nav.on_goal(&goal(5.0, 0.0)).is_none());
    nav
}

/// The known-map node of `circles`, with a goal.
fn map_node() -> NavNode {
    let sc = load("circles", &LoadOptions::default()).unwrap();
    let ctl = RobotController::new(sc.config).unwrap();
    let mut nav = NavNode::new(ctl, sc.obstacles, "map");
    assert!(nav.on_goal(&goal(9.0, 3.0)).is_none());
    nav
}

/// One LiDAR cycle at `t`: odometry, `scan`, gait state; the answer.
fn cycle(nav: &mut NavNode, t: Time, scan: LaserScan) -> Option<CycleMessages> {
    assert!(nav.on_odom(odom(t)).is_none());
    assert!(nav.on_scan(scan).is_none());
    nav.on_gait(gait(t))
}

#[test]
fn a_scan_it_cannot_read_is_answered_invalid_input_never_solved() {
    type Spoil = fn(&mut LaserScan);
    let spoils: [(&str, Spoil); 12] = [
        ("angle_min", |s| s.angle_min = f32::NAN),
        ("angle_min", |s| s.angle_min = 1e30),
        ("angle_max", |s| s.angle_max = f32::INFINITY),
        ("angle_increment", |s| s.angle_increment = f32::NAN),
        ("angle_increment", |s| {
            s.angle_increment = -s.angle_increment
        }),
        ("angle_increment", |s| s.angle_increment = 1e30),
        ("range_min", |s| s.range_min = f32::NAN),
        ("range_min", |s| s.range_min = -1.0),
        ("range_max", |s| s.range_max = f32::NAN),
        ("range_max", |s| s.range_max = 0.0),
        ("scan_time", |s| s.scan_time = f32::NAN),
        ("intensities", |s| s.intensities = vec![1.0; 5]),
    ];
    let mut nav = lidar_node();
    let mut t = 1.0;
    for (k, (field, spoil)) in spoils.iter().enumerate() {
        let mut bad = ring(at(t), 360, 0.6);
        spoil(&mut bad);
        let m = cycle(&mut nav, at(t), bad).expect("the cycle is answered");
        assert_eq!(m.command.result, FootstepCommand::INVALID_INPUT, "{field}");
        assert_eq!(m.command.status, "invalid_input");
        assert_eq!(m.command.header.stamp, at(t));
        assert_eq!(m.diagnostics.status[0].level, 2);
        assert!(
            m.diagnostics.status[0].message.contains(field),
            "{}",
            m.diagnostics.status[0].message
        );
        assert_eq!(nav.rejections().scans, k as u64 + 1);
        // The next good cycle: planned on the ring it sees.
        t += 0.05;
        let m = cycle(&mut nav, at(t), ring(at(t), 360, 0.6)).unwrap();
        assert_ne!(m.command.result, FootstepCommand::INVALID_INPUT, "{field}");
        assert!(m.command.active_obstacles > 0, "{field}");
        t += 0.05;
    }
    // The first ten refusals are logged (then each power of two).
    let log = nav.take_log();
    assert_eq!(log.len(), 10);
    assert!(log.iter().all(|l| l.starts_with("scan refused: /scan: ")));
}

#[test]
fn a_scan_over_the_ray_cap_is_refused_and_one_at_the_cap_is_read() {
    use ldcbf_ros2::scan::MAX_RAYS;
    let mut nav = lidar_node();
    // 100,000 rays on a ring of 0.6 m (the scan that made DBSCAN ask for
    // 4 GiB): refused before the perception.
    let m = cycle(&mut nav, at(1.0), ring(at(1.0), 100_000, 0.6)).unwrap();
    assert_eq!(m.command.result, FootstepCommand::INVALID_INPUT);
    assert!(m.diagnostics.status[0].message.contains("rays (3 to 4096)"));
    assert_eq!(nav.rejections().scans, 1);
    let m = cycle(&mut nav, at(1.1), ring(at(1.1), MAX_RAYS + 1, 0.6)).unwrap();
    assert_eq!(m.command.result, FootstepCommand::INVALID_INPUT);
    // At the cap, every point within eps of hundreds of others: read.
    let m = cycle(&mut nav, at(1.2), ring(at(1.2), MAX_RAYS, 0.6)).unwrap();
    assert_ne!(m.command.result, FootstepCommand::INVALID_INPUT);
    assert!(m.command.active_obstacles > 0);
    assert_eq!(nav.rejections().scans, 2);
}

#[test]
fn a_far_future_stamp_costs_one_cycle_and_a_clock_jump_resets() {
    let mut nav = map_node();
    let solved = |m: Option<CycleMessages>| {
        let m = m.expect("answered");
        assert_ne!(m.command.result, FootstepCommand::INVALID_INPUT);
        m
    };
    assert!(nav.on_odom(odom(at(1.0))).is_none());
    solved(nav.on_gait(gait(at(1.0))));
    // A gait state (and its odometry) stamped sec = 2^31 - 1 ...
    let future = Time {
        sec: i32::MAX,
        nanosec: 0,
    };
    assert!(nav.on_odom(odom(future)).is_none());
    solved(nav.on_gait(gait(future)));
    // ... then normal stamps: the odometry is a jump back (reset), and the
    // next gait state is planned on.
    assert!(nav.on_odom(odom(at(1.05))).is_none());
    assert_eq!(nav.rejections().clock_jumps, 1);
    let m = solved(nav.on_gait(gait(at(1.05))));
    assert_eq!(m.command.header.stamp, at(1.05));
    // A far-future gait state alone waits for its odometry; the next normal
    // one is a jump back and is planned on with the next odometry.
    assert!(nav.on_gait(gait(future)).is_none());
    assert!(nav.on_gait(gait(at(1.1))).is_none());
    assert_eq!(nav.rejections().clock_jumps, 2);
    solved(nav.on_odom(odom(at(1.1))));
    // A simulation restarted (a bag replayed): time 0 again.
    assert!(nav.on_odom(odom(at(0.0))).is_none());
    solved(nav.on_gait(gait(at(0.0))));
    assert!(nav.on_odom(odom(at(0.05))).is_none());
    solved(nav.on_gait(gait(at(0.05))));
    assert_eq!(nav.rejections().clock_jumps, 3);
    // A stamp that is not a time: refused, counted, answered INVALID_INPUT.
    let bad = Time {
        sec: 2,
        nanosec: 2_000_000_000,
    };
    let m = nav.on_gait(gait(bad)).expect("answered at once");
    assert_eq!(m.command.result, FootstepCommand::INVALID_INPUT);
    assert!(nav.on_odom(odom(bad)).is_none());
    assert_eq!(
        (nav.rejections().gait_states, nav.rejections().odometry),
        (1, 1)
    );
    let log = nav.take_log();
    assert_eq!(
        log.iter()
            .filter(|l| l.starts_with("clock jumped back"))
            .count(),
        3,
        "{log:?}"
    );
}

#[test]
fn a_stance_side_other_than_left_or_right_is_refused() {
    let mut nav = map_node();
    assert!(nav.on_odom(odom(at(1.0))).is_none());
    let mut g = gait(at(1.0));
    g.stance_side = 7;
    let m = nav.on_gait(g).expect("answered at once");
    assert_eq!(m.command.result, FootstepCommand::INVALID_INPUT);
    assert!(m.diagnostics.status[0].message.contains("stance_side = 7"));
    assert_eq!(nav.rejections().gait_states, 1);
    // The same stamp with a valid side is then planned on.
    let m = nav.on_gait(gait(at(1.0))).unwrap();
    assert_ne!(m.command.result, FootstepCommand::INVALID_INPUT);
}

/// A person on the path walks off it at 1 m/s: the node moves the known
/// map's person as the simulator does and gives the controller its
/// velocity, so its commands are the simulator's.
#[test]
fn people_of_the_known_map_move_as_in_the_simulator() {
    let dir = std::env::temp_dir().join(format!("ldcbf-ros2-people-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("walk-off.toml");
    std::fs::write(
        &file,
        r#"name = "walk-off"
start = { x = 0.0, y = 0.0, heading = 0.0 }
goal = [5.0, 0.0]
time_limit = 30.0
planner = "none"

[[obstacles]]
regular = { center = [2.0, 0.0], radius = 0.25, sides = 8 }
velocity = [0.0, 1.0]
"#,
    )
    .unwrap();
    let spec = file.display().to_string();
    let p = play(&spec, &[], "map").unwrap();
    let sc = load(&spec, &LoadOptions::default()).unwrap();
    let sim = ldcbf_sim::run(&sc, ldcbf_sim::SimOptions::default()).unwrap();
    let n = p.cycles.len();
    assert_eq!(n, sim.cycles.len());
    let active = |k: usize| p.cycles[k].command.active_obstacles;
    let node_active = (0..n).filter(|&k| active(k) > 0).count();
    let sim_active = sim
        .cycles
        .iter()
        .filter(|c| c.output.info.active_obstacles > 0)
        .count();
    assert!(
        node_active < n && node_active.abs_diff(sim_active) <= n / 50,
        "the person is active in {node_active} of {n} cycles, {sim_active} in the simulator"
    );
    // The odometry's body-frame twist and quaternion move the last bits of
    // the input (`circles`: 213 of 292 commands equal the run's); without
    // the people's motion, 72 of 178 did.
    eprintln!(
        "person active in {node_active} of {n} cycles ({sim_active} in the simulator); \
         {} of {n} commands equal the simulator's",
        p.same_as_run
    );
    assert!(
        p.same_as_run * 10 >= n * 6,
        "{} of {n} commands equal the simulator's",
        p.same_as_run
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// With LiDAR and `lidar.track_moving`, a person walking past the standing
/// robot is tracked as in the simulator: handed to the controller with a
/// velocity near the person's.
#[test]
fn lidar_node_tracks_people() {
    use ldcbf_sim::sense::Lidar;
    use ldcbf_sim::world::moving::MovingMap;
    let sc = load(
        "crossing",
        &LoadOptions::with_sets(&[("perception", "\"lidar\"")]),
    )
    .unwrap();
    assert!(sc.lidar.track_moving);
    let ctl = RobotController::new(sc.config).unwrap();
    let mut nav = NavNode::new(ctl, Vec::new(), "map").with_lidar(sc.lidar.clone());
    assert!(nav.on_goal(&goal(5.0, 0.0)).is_none());
    let person = ldcbf_sim::world::Polygon::new(&ldcbf_sim::world::random::regular_polygon(
        [1.5, -1.0],
        0.25,
        8,
        0.0,
    ))
    .unwrap();
    let v = Vector2::new(0.0, 0.5);
    let mut map = MovingMap::new(&[person], &[v]).unwrap();
    let mut lidar = Lidar::new(sc.lidar.clone(), 1).unwrap();
    let mut best = None::<f64>;
    for k in 0..40 {
        let t = 0.05 * f64::from(k);
        map.set_time(t);
        let hits = lidar.scan_rays(Vector2::zeros(), 0.0, map.obstacles());
        let scan = ldcbf_ros2::scan::laser_scan(at(t), Vector2::zeros(), &hits, sc.lidar.range);
        let m = cycle(&mut nav, at(t), scan).expect("answered");
        assert_ne!(m.command.result, FootstepCommand::INVALID_INPUT);
        let (_, vel) = nav.obstacles();
        if let Some(e) = vel
            .iter()
            .filter(|u| u.norm() > 0.1)
            .map(|u| (u - v).norm())
            .reduce(f64::min)
        {
            best = Some(best.map_or(e, |b: f64| b.min(e)));
        }
    }
    let e = best.expect("the person was handed over moving");
    assert!(e < 0.2, "velocity error {e} m/s");
}

fn parse(text: &str) -> anyhow::Result<Params> {
    Params::parse("f.yaml", text)
}

#[test]
fn parameter_files_refuse_bombs_and_take_the_ros2_keys() {
    // Billion laughs: refused at the first alias, before any expansion.
    let mut bomb = String::from("a: &a [x, x, x, x, x, x, x, x, x]\n");
    for (k, prev) in ["b", "c", "d", "e", "f", "g", "h", "i"]
        .iter()
        .zip(["a", "b", "c", "d", "e", "f", "g", "h"])
    {
        bomb += &format!("{k}: &{k} [{}]\n", vec![format!("*{prev}"); 9].join(", "));
    }
    bomb += "ldcbf_nav:\n  ros__parameters:\n    sets: *i\n";
    let e = parse(&bomb).unwrap_err();
    assert!(format!("{e:#}").contains("line 2: a YAML alias"), "{e:#}");
    let e = parse("ldcbf_nav:\n  ros__parameters:\n    map: circles\n---\nx: 1\n").unwrap_err();
    assert!(format!("{e:#}").contains("a second YAML document"), "{e:#}");
    let deep = format!("ldcbf_nav: {}1{}\n", "[".repeat(40), "]".repeat(40));
    let e = parse(&deep).unwrap_err();
    assert!(format!("{e:#}").contains("nested more than 16"), "{e:#}");
    // The standard node keys: `/**` first, the node's own over it.
    let p = parse(
        "/**:\n  ros__parameters:\n    use_sim_time: true\n    map: simple\n    frame_id: odom\n\
         /ldcbf_nav:\n  ros__parameters:\n    map: circles\n\
         other_node:\n  ros__parameters:\n    anything: 1\n",
    )
    .unwrap();
    assert_eq!((p.map.as_str(), p.frame_id.as_str()), ("circles", "odom"));
    assert_eq!(
        parse("/**:\n  ros__parameters:\n    map: maze\n")
            .unwrap()
            .map,
        "maze"
    );
    // Two message types on one topic name.
    let e = parse("ldcbf_nav:\n  ros__parameters:\n    topics: {scan: /odom}\n").unwrap_err();
    assert!(
        format!("{e:#}").contains("topics.scan and topics.odom are both /odom"),
        "{e:#}"
    );
    for bad in ["/a//b", "/9lives", "/a/", "/a b"] {
        let e = parse(&format!(
            "ldcbf_nav:\n  ros__parameters:\n    topics: {{odom: \"{bad}\"}}\n"
        ))
        .unwrap_err();
        assert!(format!("{e:#}").contains("not an absolute ROS 2 topic name"));
    }
}

#[test]
fn parameter_files_must_be_small_regular_files() {
    use std::path::Path;
    let e = Params::load(Path::new("/dev/zero")).unwrap_err();
    assert!(format!("{e:#}").contains("not a regular file"), "{e:#}");
    let dir = std::env::temp_dir().join(format!("ldcbf-ros2-params-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("fifo.yaml");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    // Refused without opening it (opening a FIFO blocks without a writer).
    let e = Params::load(&fifo).unwrap_err();
    assert!(format!("{e:#}").contains("not a regular file"), "{e:#}");
    let big = dir.join("big.yaml");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(ldcbf_sim::scenario::limits::MAX_FILE_BYTES + 1)
        .unwrap();
    let e = Params::load(&big).unwrap_err();
    assert!(
        format!("{e:#}").contains("more than the 16777216 bytes"),
        "{e:#}"
    );
    let e = Params::load(&dir).unwrap_err();
    assert!(format!("{e:#}").contains("is a directory"), "{e:#}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn record_refuses_devices_and_directories_and_leaves_nothing_behind() {
    let bin = env!("CARGO_BIN_EXE_ldcbf-ros2");
    let dir = std::env::temp_dir().join(format!("ldcbf-ros2-record-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("taken")).unwrap();
    std::fs::write(dir.join("notes.txt"), "keep").unwrap();
    let record = |out: &std::path::Path| {
        std::process::Command::new(bin)
            .args(["record", "circles"])
            .arg(out)
            .output()
            .unwrap()
    };
    for (out, why) in [
        (std::path::PathBuf::from("/dev/full"), "not a regular file"),
        (dir.join("taken"), "is a directory"),
        (dir.join("notes.txt"), "not a previous output"),
    ] {
        let o = record(&out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{out:?}");
        assert!(err.contains(why) && err.contains("error:"), "{err}");
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("notes.txt")).unwrap(),
        "keep"
    );
    // A new file, then the same file again (an earlier recording).
    let out = dir.join("played.json");
    assert!(record(&out).status.success());
    assert!(record(&out).status.success());
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["notes.txt", "played.json", "taken"]);
    std::fs::remove_dir_all(&dir).unwrap();
}
