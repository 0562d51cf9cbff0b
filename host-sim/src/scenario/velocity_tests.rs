//! Tests of the `velocity` key of `[[obstacles]]`.

use super::*;

const MOVING: &str = r#"
name = "t"
start = { x = 0.0, y = 0.0 }
goal = [5.0, 0.0]

[[obstacles]]
regular = { center = [2.5, -2.0], radius = 0.25, sides = 8 }
velocity = [0.0, 0.5]

[[obstacles]]
vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]
"#;

fn load_err(text: &str, sets: &[(&str, &str)]) -> ScenarioError {
    parse_str(text, "t.toml", &LoadOptions::with_sets(sets)).unwrap_err()
}

#[test]
fn velocity_is_read_and_defaults_to_rest() {
    let s = parse_str(MOVING, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(
        s.velocities,
        vec![Vector2::new(0.0, 0.5), Vector2::zeros()],
        "one velocity per obstacle, the second at rest"
    );
    let ints = MOVING.replace("[0.0, 0.5]", "[1, 0]");
    let s = parse_str(&ints, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(s.velocities[0], Vector2::new(1.0, 0.0), "integers are m/s");
}

#[test]
fn bad_velocities_are_errors_naming_the_field_and_line() {
    for (bad, what) in [
        ("[0.5]", "exactly 2"),
        ("[0.5, 0.0, 1.0]", "exactly 2"),
        ("[nan, 0.0]", "finite"),
        ("[inf, 0.0]", "finite"),
        ("[4.0, 3.1]", "above 5"),
    ] {
        let e = load_err(&MOVING.replace("[0.0, 0.5]", bad), &[]);
        assert_eq!(e.field, "obstacles[0].velocity", "{bad}: {e}");
        assert_eq!(e.line, Some(8), "{bad}: {e}");
        assert!(e.message.contains(what), "{bad}: {e}");
    }
    let e = load_err(&MOVING.replace("[0.0, 0.5]", "\"fast\""), &[]);
    assert!(e.field.starts_with("obstacles[0].velocity"), "{e}");
    let e = load_err(&MOVING.replace("velocity", "speed"), &[]);
    assert!(e.message.contains("unknown field `speed`"), "{e}");
}

#[test]
fn velocity_through_set_overrides() {
    let s = parse_str(
        MOVING,
        "t.toml",
        &LoadOptions::with_sets(&[(
            "obstacles",
            "[{ vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]], velocity = [0.3, 0.0] }]",
        )]),
    )
    .unwrap();
    assert_eq!(s.velocities, vec![Vector2::new(0.3, 0.0)]);
    let e = load_err(
        MOVING,
        &[(
            "obstacles",
            "[{ vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]], velocity = [9.0, 0.0] }]",
        )],
    );
    assert_eq!(e.field, "obstacles[0].velocity", "{e}");
    assert_eq!(e.file, "t.toml (with --set)");
    assert!(e.message.contains("above 5"), "{e}");
}

#[test]
fn a_start_inside_a_moving_obstacle_at_t0_is_an_error() {
    let text = MOVING.replace("center = [2.5, -2.0]", "center = [0.1, 0.0]");
    let e = load_err(&text, &[]);
    assert_eq!(e.field, "start");
    assert!(e.message.contains("obstacles[0]"), "{e}");
    // Moving away does not make it valid: the check is at t = 0.
    let e = load_err(&text.replace("[0.0, 0.5]", "[0.0, -5.0]"), &[]);
    assert_eq!(e.field, "start");
}

#[test]
fn the_people_families_carry_their_velocities() {
    for name in ["crossing", "headon", "crowd", "room-crossing"] {
        let s = load(name, &LoadOptions::default()).unwrap();
        assert_eq!(s.velocities.len(), s.obstacles.len(), "{name}");
        assert!(s.velocities.iter().any(|v| v.norm() > 0.0), "{name}");
    }
}
