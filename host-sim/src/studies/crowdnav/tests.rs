use super::*;

fn req(robot: RobotPolicy, visible: bool) -> CrowdNavRequest {
    CrowdNavRequest {
        layout: CrowdNavLayout::Circle,
        humans: 5,
        cases: 0..3,
        robot_visible: visible,
        perception: Perception::Known,
        robot,
        jobs: 1,
    }
}

#[test]
fn the_time_limit_is_scaled_with_the_speed() {
    assert!((time_limit() * NOMINAL_SPEED - 25.0).abs() < 1e-12);
}

#[test]
fn a_case_is_the_seeded_layout_with_the_visibility_asked() {
    for visible in [false, true] {
        let r = req(RobotPolicy::Controller, visible);
        let a = case_scenario(&r, 4).unwrap();
        let b = case_scenario(&r, 4).unwrap();
        assert_eq!(a.people, b.people);
        assert_eq!(a.people.len(), 5);
        assert!(a.people.iter().all(|p| p.sees_robot == visible));
        assert_eq!(a.obstacles.len(), 5, "the humans' bodies only");
        assert_eq!(a.people_from(), 0);
        assert_eq!(a.goal, Vector2::new(0.0, 4.0));
        assert!((a.time_limit - time_limit()).abs() < 1e-2);
    }
    let ten = CrowdNavRequest {
        humans: 10,
        ..req(RobotPolicy::Controller, false)
    };
    assert_eq!(case_scenario(&ten, 0).unwrap().obstacles.len(), 10);
}

#[test]
fn the_orca_robot_is_deterministic_and_reaches_an_empty_goal() {
    let r = req(RobotPolicy::Orca, true);
    let a = orca_robot::case(&r, 1);
    assert_eq!(a, orca_robot::case(&r, 1));
    let empty = CrowdNavRequest {
        humans: 0,
        ..req(RobotPolicy::Orca, true)
    };
    let e = orca_robot::case(&empty, 0);
    assert!(e.success && !e.collision);
    // 7.4 m at 0.6 m/s, then (goal - p) slows it from 0.6 m to the goal
    // radius 0.3 m in ln 2 s; within a decision period.
    let t = e.nav_time.unwrap();
    let expected = 7.4 / NOMINAL_SPEED + 2f64.ln();
    assert!((t - expected).abs() < 0.06, "{t} {expected}");
}

#[test]
fn the_summary_counts_each_outcome() {
    let row = |seed, reached: Option<f64>, contacts, sep: f64| {
        CaseRow::new(seed, reached, contacts, &[sep, sep.max(0.5)], 0.5)
    };
    let rows = [
        row(0, Some(10.0), (false, false), 0.1),
        row(1, Some(12.0), (true, false), -0.1),
        row(2, None, (true, true), -0.2),
        row(3, None, (false, false), 1.0),
    ];
    let s = summarize(&rows);
    assert_eq!(s.cases, 4);
    assert_eq!(
        (s.success, s.collision, s.robot_collision, s.timeout),
        (0.25, 0.5, 0.25, 0.25)
    );
    assert_eq!(s.nav_time, 10.0, "successes only");
    // Below 0.2 m: one half of case 0, one of case 1, one of case 2.
    assert_eq!(s.discomfort, 3.0 / 8.0);
    assert_eq!(s.min_separation, -0.2);
}
