//! Tests of the `[[people]]` entries (people who react).

use super::*;
use crate::world::crowd::Policy;

const PEOPLE: &str = r#"
name = "t"
start = { x = 0.0, y = 0.0 }
goal = [8.0, 0.0]

[[obstacles]]
vertices = [[3.0, 2.0], [4.0, 2.0], [3.5, 3.0]]

[[people]]
start = [4.0, -3.0]
goal = [4.0, 3.0]
speed = 0.5
policy = "social_force"
visible_robot = false
stops = [[1.0, 2.0]]

[[people]]
start = [6.0, -3.0]
goal = [6.0, 3.0]
group = 2
"#;

fn load_err(text: &str) -> ScenarioError {
    parse_str(text, "t.toml", &LoadOptions::default()).unwrap_err()
}

#[test]
fn people_are_read_with_their_defaults_and_follow_the_obstacles() {
    let s = parse_str(PEOPLE, "t.toml", &LoadOptions::default()).unwrap();
    assert_eq!(s.people.len(), 2);
    assert_eq!(s.obstacles.len(), 3, "the wall, then the two people");
    assert_eq!(s.people_from(), 1);
    let (a, b) = (&s.people[0], &s.people[1]);
    assert_eq!(a.policy, Policy::SocialForce);
    assert!(!a.sees_robot);
    assert_eq!(a.stops, vec![[1.0, 2.0]]);
    assert_eq!(b.policy, Policy::Orca, "the default policy");
    assert!(b.sees_robot, "the robot is visible by default");
    assert_eq!(b.group, Some(2));
    assert_eq!(b.radius, 0.3);
    assert_eq!(s.velocities[1], Vector2::new(0.0, 0.5), "toward the goal");
    assert_eq!(s.obstacles[1], a.polygon_at(a.start));
}

#[test]
fn bad_people_are_errors_naming_the_file_and_the_field() {
    for (from, to, field, what) in [
        ("speed = 0.5", "speed = -1.0", "people[0].speed", "(0, 5]"),
        ("speed = 0.5", "speed = 9.0", "people[0].speed", "(0, 5]"),
        (
            "speed = 0.5",
            "radius = 0.0",
            "people[0].radius",
            "[0.05, 1]",
        ),
        ("[[1.0, 2.0]]", "[[2.0, 1.0]]", "people[0].stops", "t0 < t1"),
        ("\"social_force\"", "\"sfm\"", "people[0].policy", "orca"),
        ("group = 2", "group = -1", "people[1].group", ""),
        ("group = 2", "gruop = 2", "people[1]", "gruop"),
        ("goal = [6.0, 3.0]", "goal = [6.0]", "people[1].goal", ""),
    ] {
        let text = PEOPLE.replace(from, to);
        let e = load_err(&text);
        assert_eq!(e.file, "t.toml");
        assert!(e.field.starts_with(field), "{to}: {e}");
        assert!(e.message.contains(what), "{to}: {e}");
        assert!(e.line.is_some(), "{to}: {e}");
    }
    // A person standing on the robot's start.
    let e = load_err(&PEOPLE.replace("start = [6.0, -3.0]", "start = [0.2, 0.0]"));
    assert_eq!(e.field, "start");
    assert!(e.message.contains("people[1]"), "{e}");
}

#[test]
fn the_crowd_families_load_as_generators() {
    for kind in crate::world::crowd::families::FAMILIES {
        let text = format!(
            "name = \"t\"\nstart = {{ x = 0.0, y = 0.0 }}\ngoal = [1.0, 0.0]\n[generator]\nkind = \"{kind}\"\n"
        );
        let s = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap();
        assert!(!s.people.is_empty(), "{kind}");
        assert_eq!(s.obstacles.len(), s.velocities.len());
    }
}
