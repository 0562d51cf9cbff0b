//! `ldcbf-sim deadline` from the command line, on the small `simple` scenario:
//! the table and its deterministic columns, the firmware row from an
//! instruction CSV, and one clear error (non-zero exit, nothing written) on bad
//! input.

mod common;
use common::{fails, sim, text};

use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sim::{SimOptions, run};

/// The cells of the table row whose first cell is `label`.
fn row(out: &str, label: &str) -> Vec<String> {
    let line = out
        .lines()
        .find(|l| l.starts_with(&format!("| {label} |")))
        .unwrap_or_else(|| panic!("no row {label}:\n{out}"));
    line.trim_matches('|')
        .split('|')
        .map(|c| c.trim().to_string())
        .collect()
}

#[test]
fn deadline_reports_simple() {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(&["deadline", "simple"], tmp.path());
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("deadline 250000 ns per control cycle (= 100000 instructions at 400 MHz)"),
        "{out}"
    );
    assert!(out.contains("| case | runs | reached | cycles |"), "{out}");
    assert!(
        out.contains("instructions max: n/a (see firmware/README.md"),
        "{out}"
    );
    assert!(out.contains("budget `max_iter` = 64"), "{out}");
    // One case: no `all` row.
    assert!(!out.contains("| all |"), "{out}");

    // The deterministic columns equal an in-process run of the same scenario.
    let sc = load("simple", &LoadOptions::default()).unwrap();
    let r = run(&sc, SimOptions::default()).unwrap();
    let max_it = r
        .cycles
        .iter()
        .map(|c| c.output.info.iterations)
        .max()
        .unwrap();
    let non_optimal = r
        .cycles
        .iter()
        .filter(|c| !c.output.status.is_optimal())
        .count();
    let cells = row(&out, "simple");
    assert_eq!(cells.len(), 12, "{cells:?}");
    assert_eq!(cells[1], "1");
    assert_eq!(cells[2], "1", "simple reaches its goal");
    assert_eq!(cells[3], r.cycles.len().to_string());
    assert_eq!(cells[4], non_optimal.to_string());
    assert_eq!(cells[9], format!("{max_it} / {max_it}"), "all optimal");
    assert_eq!(cells[10], "n/a");
    // p50 <= p99 <= max, and margin = deadline - max.
    let ns: Vec<i64> = cells[5..8].iter().map(|c| c.parse().unwrap()).collect();
    assert!(ns[0] > 0 && ns[0] <= ns[1] && ns[1] <= ns[2], "{ns:?}");
    let margin: i64 = cells[11]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(margin, 250_000 - ns[2]);
    // Nothing written.
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

#[test]
fn deadline_random_seeds_and_firmware_row() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("instructions.csv");
    std::fs::write(
        &csv,
        "cycle,status,iterations,instructions\n0,optimal,12,45000\n1,infeasible,70,560000\n\
         2,optimal,20,92000\n",
    )
    .unwrap();
    // A 1 ns deadline: every cycle misses it.
    let o = sim(
        &[
            "deadline",
            "simple",
            "--random",
            "2",
            "--deadline-us",
            "0.001",
            "--instructions",
            "instructions.csv",
        ],
        tmp.path(),
    );
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "{out}\n{err}");
    let simple = row(&out, "simple");
    let random = row(&out, "random@0..2");
    let all = row(&out, "all");
    assert_eq!(random[1], "2");
    assert_eq!(all[1], "3");
    let n = |c: &Vec<String>, i: usize| c[i].parse::<u64>().unwrap();
    assert_eq!(n(&all, 3), n(&simple, 3) + n(&random, 3));
    for r in [&simple, &random, &all] {
        assert_eq!(r[8], r[3], "every cycle over a 1 ns deadline: {r:?}");
        assert!(r[11].ends_with("MISSED"), "{r:?}");
    }
    // The firmware row: 1 ns = 0.4 instructions at 400 MHz.
    let fw = row(&out, "firmware (QEMU, recorded cycles)");
    assert_eq!((fw[3].as_str(), fw[4].as_str()), ("3", "1"));
    assert_eq!(fw[9], "20 / 70");
    assert_eq!(fw[10], "92000 / 560000");
    assert_eq!(fw[7], "1400000 at 400 MHz");
    assert!(
        out.contains("- instructions: instructions.csv (3 cycles"),
        "{out}"
    );
}

#[test]
fn bad_deadline_arguments_fail_cleanly() {
    fails(&["deadline", "nope"], "no scenario named \"nope\"");
    fails(&["deadline", "maze+astar"], "astar");
    fails(&["deadline", "random@x"], "random@x");
    fails(
        &["deadline", "simple", "--deadline-us", "0"],
        "--deadline-us",
    );
    fails(&["deadline", "simple", "--deadline-us", "abc"], "abc");
    fails(&["deadline", "simple", "--clock-mhz", "0"], "--clock-mhz");
    fails(&["deadline", "simple", "--jobs", "0"], "--jobs");
    fails(&["deadline", "simple", "--set", "delta=-1"], "delta");
    fails(&["deadline", "simple", "--random", "-3"], "-3");
    fails(
        &["deadline", "simple", "--instructions", "missing.csv"],
        "missing.csv",
    );
    // A planner with LiDAR is refused by the scenario's validation.
    fails(&["deadline", "crowded+rrt_star"], "rrt_star");
}

#[test]
fn a_malformed_instruction_file_names_its_line() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("i.csv"),
        "cycle,status,iterations,instructions\n0,optimal,x,5\n",
    )
    .unwrap();
    let o = sim(
        &["deadline", "simple", "--instructions", "i.csv"],
        tmp.path(),
    );
    let err = text(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("i.csv:2: bad iterations"), "{err}");
    assert!(o.stdout.is_empty());
}
