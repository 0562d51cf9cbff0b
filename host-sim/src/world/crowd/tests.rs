use ldcbf_controller::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;

use super::families::{CrowdNavLayout, FAMILIES, crowdnav_case, generate};
use super::*;
use crate::world::families::rect;

const DT: f64 = 0.01;

/// Runs `crowd` for `t` seconds (with `robot` standing or walking at its
/// velocity); the smallest surface gap between two people and the smallest
/// wall clearance minus the radius seen at any step, m.
fn run(crowd: &mut Crowd, t: f64, mut robot: Option<RobotBody>) -> (f64, f64) {
    let walls = crowd.walls.clone();
    let (mut gap, mut wall) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..(t / DT).round() as usize {
        crowd.step(DT, robot.as_ref());
        if let Some(r) = robot.as_mut() {
            r.position += r.velocity * DT;
        }
        let (p, people) = (crowd.positions(), crowd.people());
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                gap = gap.min((p[i] - p[j]).norm() - people[i].radius - people[j].radius);
            }
            for w in &walls {
                wall = wall
                    .min(closest_point_point_polygon(&p[i], w).signed_distance - people[i].radius);
            }
        }
    }
    (gap, wall)
}

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn with(policy: Policy, start: Vector2<f64>, goal: Vector2<f64>) -> Person {
    Person {
        policy,
        ..Person::new(start, goal, 0.6)
    }
}

#[test]
fn orca_people_walking_head_on_pass_without_touching() {
    for offset in [0.0, 0.05, 0.3] {
        let mut c = Crowd::new(
            vec![
                with(Policy::Orca, v(-4.0, 0.0), v(4.0, offset)),
                with(Policy::Orca, v(4.0, offset), v(-4.0, 0.0)),
            ],
            &[],
        );
        let (gap, _) = run(&mut c, 30.0, None);
        assert!(gap >= -1e-3, "offset {offset}: gap {gap}");
        let at = (c.positions()[0], c.positions()[1]);
        assert!(
            (at.0 - v(4.0, offset)).norm() < 0.05,
            "offset {offset}: {at:?}"
        );
        assert!(
            (at.1 - v(-4.0, 0.0)).norm() < 0.05,
            "offset {offset}: {at:?}"
        );
    }
}

#[test]
fn orca_people_keep_off_the_walls() {
    // A wall across the way: ORCA is local, so the person stops in front of
    // it (or slides round it), but never enters it.
    let wall = rect(1.0, -0.6, 1.3, 0.6);
    let mut c = Crowd::new(
        vec![
            with(Policy::Orca, v(-2.0, 0.0), v(4.0, 0.0)),
            with(Policy::Orca, v(-2.0, 3.0), v(4.0, 0.5)),
        ],
        &[wall],
    );
    let (gap, wall_gap) = run(&mut c, 30.0, None);
    assert!(wall_gap >= -0.02, "into the wall by {wall_gap}");
    assert!(gap >= -1e-3, "gap {gap}");
    assert!(c.positions()[0].x < 1.0 || c.positions()[0].y.abs() > 0.6);
}

#[test]
fn social_force_people_avoid_each_other_and_the_walls() {
    let mut c = Crowd::new(
        vec![
            with(Policy::SocialForce, v(-4.0, 0.0), v(4.0, 0.1)),
            with(Policy::SocialForce, v(4.0, 0.1), v(-4.0, 0.0)),
        ],
        &[],
    );
    let (gap, _) = run(&mut c, 30.0, None);
    assert!(gap >= 0.0, "head on: gap {gap}");
    assert!((c.positions()[0] - v(4.0, 0.1)).norm() < 0.3, "arrived");
    // Along a corridor 1.2 m wide: the walls push the person to the middle.
    let walls = [rect(-1.0, 0.6, 8.0, 0.8), rect(-1.0, -0.8, 8.0, -0.6)];
    let mut c = Crowd::new(
        vec![with(Policy::SocialForce, v(0.0, 0.25), v(7.0, 0.25))],
        &walls,
    );
    let (_, wall_gap) = run(&mut c, 20.0, None);
    assert!(wall_gap >= 0.0, "into the wall by {wall_gap}");
}

#[test]
fn a_visible_robot_is_avoided_an_invisible_one_is_not() {
    let robot = RobotBody {
        position: v(0.0, 0.0),
        velocity: Vector2::zeros(),
        radius: 0.25,
    };
    for (policy, sees) in [
        (Policy::Orca, true),
        (Policy::SocialForce, true),
        (Policy::Orca, false),
    ] {
        let mut c = Crowd::new(
            vec![Person {
                sees_robot: sees,
                ..with(policy, v(-4.0, 0.02), v(4.0, 0.02))
            }],
            &[],
        );
        let mut closest = f64::INFINITY;
        for _ in 0..3000 {
            c.step(DT, Some(&robot));
            closest = closest.min((c.positions()[0] - robot.position).norm() - 0.3 - 0.25);
        }
        if sees {
            assert!(closest >= -1e-3, "{policy:?}: {closest}");
        } else {
            assert!(
                closest < -0.5,
                "walks through the invisible robot: {closest}"
            );
        }
    }
}

#[test]
fn a_crowd_of_orca_people_crossing_a_circle_never_overlaps() {
    for seed in 0..10 {
        let case = crowdnav_case(CrowdNavLayout::Circle, 10, seed, 0.25);
        let mut c = Crowd::new(case.people, &[]);
        let (gap, _) = run(&mut c, 40.0, None);
        assert!(gap >= -0.02, "seed {seed}: gap {gap}");
    }
}

#[test]
fn constant_velocity_people_walk_through_and_stop_when_told() {
    let mut a = Person {
        stops: vec![[1.0, 2.0]],
        ..with(Policy::ConstantVelocity, v(0.0, 0.0), v(3.0, 0.0))
    };
    let b = with(Policy::ConstantVelocity, v(3.0, 0.0), v(0.0, 0.0));
    let mut c = Crowd::new(vec![a.clone(), b], &[]);
    let (gap, _) = run(&mut c, 1.5, None);
    assert!(
        (c.positions()[0].x - 0.6).abs() < 0.04,
        "{}",
        c.positions()[0]
    );
    run(&mut c, 0.45, None);
    assert!((c.positions()[0].x - 0.6).abs() < 0.04, "standing");
    let (gap2, _) = run(&mut c, 10.0, None);
    assert!(gap.min(gap2) < -0.5, "they walk through each other");
    assert!(
        (c.positions()[0] - v(3.0, 0.0)).norm() < 0.01,
        "at its goal"
    );
    a.stops = vec![[2.0, 1.0]];
    assert_eq!(a.validate().unwrap_err().field, "stops");
}

#[test]
fn a_group_walks_abreast() {
    let members: Vec<Person> = [0.0, 0.6, 1.2]
        .iter()
        .enumerate()
        .map(|(k, &x)| Person {
            group: Some(1),
            radius: 0.25,
            // The middle one would walk faster alone.
            speed: if k == 1 { 0.9 } else { 0.5 },
            ..with(Policy::Orca, v(x, -4.0), v(x, 4.0))
        })
        .collect();
    let mut c = Crowd::new(members, &[]);
    for _ in 0..800 {
        c.step(DT, None);
        let y: Vec<f64> = c.positions().iter().map(|p| p.y).collect();
        let spread =
            y.iter().cloned().fold(f64::MIN, f64::max) - y.iter().cloned().fold(f64::MAX, f64::min);
        assert!(spread < 0.7, "spread {spread} at {}", c.time());
    }
}

#[test]
fn the_families_are_seeded_deterministic_and_valid() {
    for kind in FAMILIES {
        for seed in 0..20 {
            let a = generate(kind, seed, 0.25).unwrap().unwrap();
            let b = generate(kind, seed, 0.25).unwrap().unwrap();
            assert_eq!(a.people, b.people, "{kind} {seed}");
            assert!(!a.people.is_empty(), "{kind} {seed}");
            for p in &a.people {
                p.validate().unwrap();
            }
        }
        assert_ne!(
            generate(kind, 1, 0.25).unwrap().unwrap().people,
            generate(kind, 2, 0.25).unwrap().unwrap().people,
            "{kind}"
        );
    }
    assert!(generate("corridor", 0, 0.25).is_none());
}

#[test]
fn crowdnav_cases_follow_the_protocol() {
    for seed in 0..50 {
        let c = crowdnav_case(CrowdNavLayout::Circle, 5, seed, 0.25);
        assert_eq!(c.people.len(), 5);
        assert_eq!(c.layout.start, v(0.0, -4.0));
        assert_eq!(c.layout.goal, v(0.0, 4.0));
        for (i, p) in c.people.iter().enumerate() {
            assert_eq!(p.goal, -p.start, "to the opposite point");
            assert!((p.start.norm() - 4.0).abs() <= 0.5 * 2f64.sqrt() + 1e-9);
            assert!(!p.sees_robot && p.radius == 0.3 && p.policy == Policy::Orca);
            for q in &c.people[..i] {
                assert!((p.start - q.start).norm() >= 0.8 - 1e-12);
            }
        }
        let s = crowdnav_case(CrowdNavLayout::Square, 20, seed, 0.25);
        assert_eq!(s.people.len(), 20);
        for p in &s.people {
            assert!(p.start.x * p.goal.x <= 0.0, "to the other half");
            assert!(p.start.abs().max() <= 5.0 && p.goal.abs().max() <= 5.0);
        }
    }
    let a = crowdnav_case(CrowdNavLayout::Circle, 5, 7, 0.25);
    let b = crowdnav_case(CrowdNavLayout::Circle, 5, 7, 0.25);
    assert_eq!(a.people, b.people);
}
