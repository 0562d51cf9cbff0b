//! Tests of seed ranges, shards, rows and the aggregate.

use super::*;

#[test]
fn seed_ranges_and_shards_parse() {
    assert_eq!("0..200".parse::<SeedRange>().unwrap().len(), 200);
    assert_eq!(
        "3..=5".parse::<SeedRange>().unwrap(),
        SeedRange { start: 3, end: 6 }
    );
    assert_eq!("7".parse::<SeedRange>().unwrap().len(), 1);
    assert!("5..2".parse::<SeedRange>().is_err());
    assert!("a..b".parse::<SeedRange>().is_err());
    assert!("3/2".parse::<Shard>().is_err());
    assert!("0/2".parse::<Shard>().is_err());
    let r = SeedRange { start: 10, end: 17 };
    let a: Vec<u64> = (1..=3)
        .flat_map(|i| Shard { index: i, count: 3 }.seeds(r))
        .collect();
    let mut s = a.clone();
    s.sort_unstable();
    assert_eq!(s, (10..17).collect::<Vec<_>>());
    assert_eq!(Shard { index: 2, count: 3 }.seeds(r), vec![11, 14]);
}

#[test]
fn rows_round_trip_through_csv() {
    let r = RunRow {
        seed: 3,
        outcome: "goal_reached".into(),
        success: true,
        collision: false,
        steps: 52,
        sim_time: 20.99,
        final_distance: 0.1499,
        min_com_clearance: 0.34,
        min_footstep_clearance: f64::INFINITY,
        max_violation: 2.3e-13,
        cycles: 420,
        non_optimal_cycles: 0,
        compute_p50_ns: 1500,
        compute_p99_ns: 4000,
        compute_max_ns: 97000,
        planner_failed: false,
        subgoals: 1,
        plan_time_ms: 0.0,
        obstacles_seen_mean: 8.0,
        wall_ms: 12.5,
        foot_collision: true,
        min_body_clearance: 0.09,
        contacts_robot: 1,
        contacts_person: 2,
        replans: 4,
        plan_failures: 1,
        map_update_p50_ms: 0.2,
        map_update_max_ms: 31.5,
        plan_p50_ms: 120.0,
        plan_max_ms: 650.25,
    };
    assert_eq!(RunRow::parse(&r.csv()).unwrap(), r);
}

#[test]
fn shards_and_ranges_read_from_a_file_are_checked_as_when_parsed() {
    let shard = |j: &str| serde_json::from_str::<Shard>(j);
    assert_eq!(
        shard(r#"{"index": 2, "count": 3}"#).unwrap(),
        Shard { index: 2, count: 3 }
    );
    for bad in [
        r#"{"index": 0, "count": 3}"#,
        r#"{"index": 5, "count": 3}"#,
        r#"{"index": 1, "count": 0}"#,
    ] {
        let e = shard(bad).unwrap_err().to_string();
        assert!(e.contains("out of range"), "{bad}: {e}");
    }
    let range = |j: &str| serde_json::from_str::<SeedRange>(j);
    assert_eq!(range(r#"{"start": 3, "end": 7}"#).unwrap().len(), 4);
    assert!(range(r#"{"start": 3, "end": 3}"#).is_err());
    assert!(range(r#"{"start": 0, "end": 1000001}"#).is_err());
    // Shard::items counts what Shard::seeds lists.
    for count in 1..5 {
        for index in 1..=count {
            let s = Shard { index, count };
            for len in 0..9 {
                let r = SeedRange {
                    start: 10,
                    end: 10 + len,
                };
                assert_eq!(s.items(len), s.seeds(r).len() as u64, "{s} of {len}");
            }
        }
    }
}
