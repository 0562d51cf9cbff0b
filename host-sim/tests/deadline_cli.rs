//! `ldcbf-sim deadline` from the command line, on the small `simple` scenario:
//! the table and its deterministic columns, the firmware row from an
//! instruction CSV, and one clear error (non-zero exit, nothing written) on bad
//! input.

mod common;
use common::{fails, fails_in, sim, text};

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
    assert_eq!(cells.len(), 13, "{cells:?}");
    assert_eq!(cells[1], "1");
    assert_eq!(cells[2], "1", "simple reaches its goal");
    assert_eq!(cells[3], r.cycles.len().to_string());
    assert_eq!(cells[4], non_optimal.to_string());
    assert_eq!(cells[10], format!("{max_it} / {max_it}"), "all optimal");
    assert_eq!(cells[11], "n/a");
    // p50 <= p99 <= max, and margin = deadline - max.
    let ns: Vec<i64> = cells[5..8].iter().map(|c| c.parse().unwrap()).collect();
    assert!(ns[0] > 0 && ns[0] <= ns[1] && ns[1] <= ns[2], "{ns:?}");
    // The cycle of the max: `simple cycle I (t = T s, STATUS, N it)`, a real
    // cycle of the run with that time, status and iteration count.
    let at = &cells[8];
    let i: usize = at
        .strip_prefix("simple cycle ")
        .and_then(|r| r.split_whitespace().next())
        .and_then(|i| i.parse().ok())
        .unwrap_or_else(|| panic!("max at: {at}"));
    let c = &r.cycles[i];
    assert_eq!(
        at,
        &format!(
            "simple cycle {i} (t = {:.2} s, {}, {} it)",
            c.time,
            c.output.status.name(),
            c.output.info.iterations
        )
    );
    assert!(
        out.contains(&format!("- slowest cycle: {} ns, simple cycle {i} ", ns[2])),
        "{out}"
    );
    assert!(out.contains("one timing per cycle"), "{out}");
    let margin: i64 = cells[12]
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
        assert_eq!(r[9], r[3], "every cycle over a 1 ns deadline: {r:?}");
        assert!(r[12].ends_with("MISSED"), "{r:?}");
    }
    assert!(simple[8].starts_with("simple cycle "), "{simple:?}");
    assert!(random[8].starts_with("random@"), "{random:?}");
    // The firmware row: 1 ns = 0.4 instructions at 400 MHz.
    let fw = row(&out, "firmware (QEMU, recorded cycles)");
    assert_eq!((fw[3].as_str(), fw[4].as_str()), ("3", "1"));
    assert_eq!(fw[10], "20 / 70");
    assert_eq!(fw[11], "92000 / 560000");
    assert_eq!(fw[7], "1400000 at 400 MHz");
    assert_eq!(fw[8], "cycle 1 (infeasible)");
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
    fails(&["deadline", "simple", "--repeat", "-1"], "-1");
    fails(&["deadline", "simple", "--repeat", "x"], "--repeat");
    fails(&["deadline", "simple", "--set", "delta=-1"], "delta");
    fails(&["deadline", "simple", "--random", "-3"], "-3");
    fails(
        &["deadline", "simple", "--instructions", "missing.csv"],
        "missing.csv",
    );
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

/// `--repeat K` times each cycle K times on clones of the controller: the
/// closed loops (cycles, statuses, iterations, reached) are those of one
/// timing; only the times and the header change. No timing is asserted.
#[test]
fn repeat_keeps_the_closed_loops() {
    let tmp = tempfile::tempdir().unwrap();
    let args = ["deadline", "simple", "trap+rrt_star", "--random", "2"];
    let one = sim(&args, tmp.path());
    let three = sim(&[&args[..], &["--repeat", "3"]].concat(), tmp.path());
    let (a, b) = (text(&one.stdout), text(&three.stdout));
    assert!(one.status.success() && three.status.success(), "{a}\n{b}");
    assert!(a.contains("one timing per cycle"), "{a}");
    assert!(b.contains("each cycle's minimum of 3 timings"), "{b}");
    assert!(b.contains("; minimum of 3 timings"), "{b}");
    for label in ["simple", "trap+rrt_star", "random@0..2", "all"] {
        let (x, y) = (row(&a, label), row(&b, label));
        assert_eq!(y.len(), 13, "{y:?}");
        // runs, reached, cycles, non-optimal; iterations; instructions.
        for i in [1, 2, 3, 4, 10, 11] {
            assert_eq!(x[i], y[i], "{label} column {i}: {x:?} vs {y:?}");
        }
        let ns: Vec<u64> = y[5..8].iter().map(|c| c.parse().unwrap()).collect();
        assert!(ns[0] > 0 && ns[0] <= ns[1] && ns[1] <= ns[2], "{ns:?}");
    }
    // The worst-iteration lines name the same cycles.
    let worst = |s: &str| -> Vec<String> {
        s.lines()
            .filter(|l| l.starts_with("- iterations") || l.starts_with("- non-optimal cycles"))
            .map(|l| l.split("; their compute").next().unwrap().to_string())
            .collect()
    };
    assert_eq!(worst(&a), worst(&b));
    assert_eq!(worst(&a).len(), 3, "{a}");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

/// `--repeat 0`: one `error:` line naming the option, exit status 1, nothing
/// printed or written.
#[test]
fn repeat_zero_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let line = fails_in(
        tmp.path(),
        &["deadline", "simple", "--repeat", "0"],
        &["--repeat", ">= 1"],
    );
    assert_eq!(
        line,
        "error: --repeat must be >= 1 (timings of each control cycle), got 0"
    );
}
