//! Tests of cases, cost statistics, instruction files and the report.

use super::*;

#[test]
fn cases_parse_and_print_back() {
    for s in SHIPPED_CASES {
        let c: Case = s.parse().unwrap();
        assert_eq!(c.label(), s);
    }
    let c: Case = "trap+rrt_star@3".parse().unwrap();
    assert_eq!(
        c,
        Case {
            scenario: "trap".into(),
            planner: Some(Planner::RrtStar),
            seed: Some(3)
        }
    );
    let c: Case = "dir/my+file.toml".parse().unwrap();
    assert_eq!((c.scenario.as_str(), c.planner), ("dir/my+file.toml", None));
    assert!("maze+astar".parse::<Case>().unwrap_err().contains("astar"));
    assert!("random@x".parse::<Case>().is_err());
    assert!("@3".parse::<Case>().is_err());
    assert_eq!(random_cases(2)[1].label(), "random@1");
}

fn cycle(index: usize, status: CycleStatus, iterations: u32, ns: u64) -> CycleCost {
    CycleCost {
        index,
        time: index as f64 * 0.05,
        status,
        source: if status.is_optimal() {
            CommandSource::Optimal
        } else {
            CommandSource::RelaxedGait
        },
        iterations,
        compute_ns: ns,
    }
}

#[test]
fn stats_find_the_worst_cycles() {
    let run = |label: &str, cycles| CaseRun {
        case: Case::new(label),
        label: label.into(),
        seed: 0,
        max_iter: 64,
        max_iter_cycle: 2048,
        outcome: Outcome::GoalReached,
        cycles,
    };
    let a = run(
        "a",
        vec![
            cycle(0, CycleStatus::Optimal, 5, 1000),
            cycle(1, CycleStatus::Infeasible, 300, 9000),
        ],
    );
    let b = run(
        "b",
        vec![
            cycle(0, CycleStatus::Optimal, 12, 2000),
            cycle(1, CycleStatus::Optimal, 12, 300_000),
        ],
    );
    let st = cost_stats(&[&a, &b], 250_000);
    assert_eq!((st.runs, st.cycles, st.non_optimal), (2, 4, 1));
    assert_eq!(st.over_deadline, 1);
    let wo = st.worst_optimal.unwrap();
    assert_eq!((wo.value, wo.label.as_str(), wo.cycle), (12, "b", 0));
    assert_eq!(st.worst_all.unwrap().value, 300);
    assert_eq!(st.compute.max_ns, 300_000);
    let sl = st.slowest.unwrap();
    assert_eq!(
        (sl.compute_ns, sl.label.as_str(), sl.cycle, sl.iterations),
        (300_000, "b", 1, 12)
    );
    assert_eq!(sl.to_string(), "b cycle 1 (t = 0.05 s, optimal, 12 it)");
    let sa = cost_stats(&[&a], 250_000).slowest.unwrap();
    assert_eq!((sa.cycle, sa.status), (1, CycleStatus::Infeasible));
    assert!(cost_stats(&[], 250_000).slowest.is_none());
    assert_eq!((st.fallback, st.budget_exhausted), (0, 0));
}

#[test]
fn instruction_files_are_read_and_checked() {
    let dir = std::env::temp_dir().join(format!("ldcbf-instr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("i.csv");
    std::fs::write(
        &p,
        format!(
            "{INSTRUCTIONS_HEADER}\n0,optimal,4,40000\n1,infeasible,300,500000\n2,optimal,9,90000\n"
        ),
    )
    .unwrap();
    let fw = read_instructions(&p).unwrap();
    assert_eq!((fw.cycles, fw.non_optimal), (3, 1));
    assert_eq!((fw.max_optimal, fw.max_all), (Some(90_000), 500_000));
    assert_eq!((fw.iterations_optimal, fw.iterations_all), (Some(9), 300));
    assert_eq!(
        (fw.max_all_cycle, fw.max_all_status.as_str()),
        (1, "infeasible")
    );
    std::fs::write(&p, format!("{INSTRUCTIONS_HEADER}\n0,optimal,4\n")).unwrap();
    let e = read_instructions(&p).unwrap_err().to_string();
    assert!(e.contains(":2:"), "{e}");
    std::fs::write(&p, "a,b\n").unwrap();
    assert!(read_instructions(&p).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}
