//! Tests of scenario loading and validation.

use super::*;
use ldcbf_controller::closest_point_point_polygon;

const OK: &str = r#"
name = "t"
start = { x = 0.0, y = 0.0 }
goal = [5.0, 5.0]

[controller]
delta = 0.2

[[obstacles]]
vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]

[[obstacles]]
regular = { center = [4.0, 2.0], radius = 1.0, sides = 25 }
"#;

#[test]
fn parses_a_valid_file() {
    let s = parse_str(OK, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(s.obstacles.len(), 2);
    assert_eq!(s.obstacles[1].len(), 25);
    assert_eq!(s.config.delta, 0.2);
    assert_eq!(s.stance, Side::Left);
    assert_eq!(s.time_limit, 120.0);
}

#[test]
fn non_convex_obstacle_is_named_with_its_line() {
    let text = OK.replace(
        "[[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]",
        "[[1.0, 1.0], [3.0, 1.0], [2.0, 1.5], [3.0, 3.0], [1.0, 3.0]]",
    );
    let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "obstacles[0].vertices");
    assert_eq!(e.line, Some(10), "{e}");
    assert!(e.message.contains("hull = true"), "{e}");
    // With hull = true it is accepted.
    let text = text.replace(
        "vertices = [[1.0, 1.0], [3.0",
        "hull = true\nvertices = [[1.0, 1.0], [3.0",
    );
    assert!(parse_str(&text, "t.toml", &LoadOptions::default()).is_ok());
}

#[test]
fn type_errors_name_the_field_and_line() {
    let text = OK.replace("goal = [5.0, 5.0]", "goal = [5.0, \"x\"]");
    let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
    assert!(e.field.starts_with("goal"), "{e}");
    assert_eq!(e.line, Some(4), "{e}");
    let text = OK.replace("delta = 0.2", "deltaa = 0.2");
    let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
    assert!(e.field.starts_with("controller"), "{e}");
    assert_eq!(e.line, Some(7), "{e}");
    let text = OK.replace("delta = 0.2", "gamma = 2.0");
    let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "controller.gamma");
    assert_eq!(e.line, Some(7), "{e}");
}

#[test]
fn set_overrides_apply_and_are_checked() {
    let o = LoadOptions {
        seed: None,
        sets: vec![
            ("delta".into(), "0.3".into()),
            ("time_limit".into(), "50".into()),
            ("stance".into(), "right".into()),
        ],
    };
    let s = parse_str(OK, "t.toml", &o).unwrap();
    assert_eq!(s.config.delta, 0.3);
    assert_eq!(s.time_limit, 50.0);
    assert_eq!(s.stance, Side::Right);
    let o = LoadOptions {
        seed: None,
        sets: vec![("bogus".into(), "1".into())],
    };
    let e = parse_str(OK, "t.toml", &o).unwrap_err();
    assert_eq!(e.field, "bogus");
    // The [robot] table as one key, as well as its fields.
    let o = LoadOptions::with_sets(&[("robot", "{ body_radius = 0.2 }")]);
    let s = parse_str(OK, "t.toml", &o).unwrap();
    assert_eq!(s.robot.body_radius, 0.2);
}

#[test]
fn relaxation_settings_are_overridable() {
    let set = |sets: &[(&str, &str)]| LoadOptions {
        seed: None,
        sets: sets
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
    };
    let s = parse_str(OK, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(
        s.config.capture_fraction,
        Config::default().capture_fraction
    );
    assert!(s.config.capture_fraction.is_some());
    let o = set(&[("max_gait_relaxation", "0.25"), ("capture_fraction", "0")]);
    let s = parse_str(OK, "t.toml", &o).unwrap();
    assert_eq!(s.config.max_gait_relaxation, 0.25);
    assert_eq!(s.config.capture_fraction, None);
    let text = OK.replace("delta = 0.2", "delta = 0.2\ncapture_fraction = 0.8");
    let s = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(s.config.capture_fraction, Some(0.8));
    let e = parse_str(OK, "t.toml", &set(&[("capture_fraction", "1.5")])).unwrap_err();
    assert_eq!(e.field, "controller.capture_fraction", "{e}");
    let m = crate::scenario::config_map(&s.config);
    assert_eq!(m["capture_fraction"], serde_json::json!(0.8));
    assert_eq!(m["max_gait_relaxation"], serde_json::json!(0.1));
}

#[test]
fn disturbance_table_parses_and_is_validated() {
    let text = format!(
        "{OK}\n[disturbance]\nseed = 4\npush_time = 2.0\npush_lateral = 0.3\nfoot_sigma = 0.02\n"
    );
    let s = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(s.disturbance.seed, 4);
    assert_eq!(s.disturbance.push_time, Some(2.0));
    assert_eq!(s.disturbance.push_lateral, 0.3);
    assert_eq!(s.disturbance.foot_sigma, 0.02);
    assert!(s.disturbance.is_active(1.0));
    // Absent: all off.
    let s = parse_str(OK, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(s.disturbance, DisturbanceParams::default());
    // A negative sigma names the field and its line.
    let bad = text.replace("foot_sigma = 0.02", "foot_sigma = -0.02");
    let e = parse_str(&bad, "t.toml", &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "disturbance.foot_sigma");
    assert_eq!(e.line, Some(19), "{e}");
    // Unknown field.
    let bad = text.replace("foot_sigma", "foot_sgima");
    let e = parse_str(&bad, "t.toml", &LoadOptions::default()).unwrap_err();
    assert!(e.field.starts_with("disturbance"), "{e}");
    assert!(e.message.contains("foot_sgima"), "{e}");
    // Through --set, including a non-finite value.
    let o = |k: &str, v: &str| LoadOptions {
        seed: None,
        sets: vec![(k.into(), v.into())],
    };
    let s = parse_str(OK, "t.toml", &o("disturbance.plant_com_height", "0.9")).unwrap();
    assert_eq!(s.disturbance.plant_com_height, Some(0.9));
    let e = parse_str(OK, "t.toml", &o("disturbance.noise_velocity", "nan")).unwrap_err();
    assert_eq!(e.field, "disturbance.noise_velocity", "{e}");
    let e = parse_str(OK, "t.toml", &o("disturbance.push_lateral", "0.3")).unwrap_err();
    assert_eq!(e.field, "disturbance.push_time", "{e}");
    let e = parse_str(OK, "t.toml", &o("disturbance.bogus", "1")).unwrap_err();
    assert!(e.message.contains("bogus"), "{e}");
}

#[test]
fn random_family_is_seeded_and_keeps_start_and_goal_clear() {
    let a = random_scenario(7);
    let b = random_scenario(7);
    let c = random_scenario(8);
    assert_eq!(a.obstacles, b.obstacles);
    assert_ne!(a.obstacles, c.obstacles);
    assert_eq!(a.obstacles.len(), 8);
    for p in &a.obstacles {
        for q in [a.start, a.goal] {
            assert!(closest_point_point_polygon(&q, p).signed_distance >= 1.0);
        }
    }
}

/// `controller.turn_vertex_normals` is on with `perception = "lidar"` and
/// `planner = "rrt_star"` (the occupancy map, walking to a planned path's
/// subgoals) and off otherwise (the paper's normal), unless the file or
/// `--set` says.
#[test]
fn vertex_normals_turn_on_the_map_with_a_plan_unless_set() {
    let set = LoadOptions::with_sets;
    let s = parse_str(OK, "t.toml", &LoadOptions::default()).unwrap();
    assert!(!s.config.turn_vertex_normals);
    let lidar = ("perception", "\"lidar\"");
    let s = parse_str(OK, "t.toml", &set(&[lidar])).unwrap();
    assert!(!s.config.turn_vertex_normals);
    let plan = ("planner", "\"rrt_star\"");
    let s = parse_str(OK, "t.toml", &set(&[lidar, plan])).unwrap();
    assert!(s.config.turn_vertex_normals);
    let off = ("turn_vertex_normals", "false");
    let s = parse_str(OK, "t.toml", &set(&[lidar, plan, off])).unwrap();
    assert!(!s.config.turn_vertex_normals);
    let on = ("turn_vertex_normals", "true");
    let s = parse_str(OK, "t.toml", &set(&[on])).unwrap();
    assert!(s.config.turn_vertex_normals);
}
