//! The deadline report as Markdown.

use super::*;

fn pct(part: f64, whole: f64) -> String {
    if whole > 0.0 {
        format!("{:.0} %", 100.0 * part / whole)
    } else {
        "n/a".into()
    }
}

/// The report as Markdown: a few header lines, the table (one row per case,
/// the pooled random seeds, `all`), the worst cases and the budgets.
pub fn markdown(rep: &DeadlineReport) -> String {
    let mut s = String::new();
    let budget = rep.instruction_budget();
    header(&mut s, rep, budget);
    table(&mut s, rep);
    totals(&mut s, rep);
    instructions_note(&mut s, rep, budget);
    s
}

/// The first line: the deadline, how compute is timed, the build and the
/// machine.
fn header(s: &mut String, rep: &DeadlineReport, budget: u64) {
    let timing = if rep.repeat > 1 {
        format!(
            "compute = wall clock around the controller call only, each cycle's minimum of {} timings \
             on the same input and state (preemption filtered: the max is the hardest cycle)",
            rep.repeat
        )
    } else {
        "compute = wall clock around the controller call only, one timing per cycle (a preemption \
         shows as the max; --repeat K takes each cycle's minimum of K)"
            .to_string()
    };
    let _ = writeln!(
        s,
        "deadline {} ns per control cycle (= {budget} instructions at {} MHz); {timing}; {} build, \
         {} job(s), this machine (indicative; the iteration counts are deterministic); study wall \
         time {:.1} s",
        rep.deadline_ns,
        rep.clock_mhz,
        if cfg!(debug_assertions) {
            "DEBUG"
        } else {
            "release"
        },
        rep.jobs,
        rep.wall_time_s
    );
    s.push('\n');
}

/// The table: a row per case and, with `--instructions`, the firmware's.
fn table(s: &mut String, rep: &DeadlineReport) {
    *s += "| case | runs | reached | cycles | non-optimal | compute p50 [ns] | p99 [ns] | max [ns] \
          | max at | over deadline | iterations max: optimal / all | instructions max | margin [ns] |\n";
    *s += "|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---|---:|\n";
    let it = |w: &Option<Worst>| w.as_ref().map_or("-".to_string(), |w| w.value.to_string());
    for row in &rep.rows {
        let st = &row.stats;
        let margin = rep.deadline_ns as i64 - st.compute.max_ns as i64;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | n/a | {margin} ({}){} |",
            row.label,
            st.runs,
            st.reached,
            st.cycles,
            st.non_optimal,
            st.compute.p50_ns,
            st.compute.p99_ns,
            st.compute.max_ns,
            st.slowest
                .as_ref()
                .map_or("-".to_string(), ToString::to_string),
            st.over_deadline,
            it(&st.worst_optimal),
            it(&st.worst_all),
            pct(margin as f64, rep.deadline_ns as f64),
            if margin < 0 { " MISSED" } else { "" },
        );
    }
    if let Some(fw) = &rep.instructions {
        let max_ns = fw.max_all as f64 * 1e3 / rep.clock_mhz;
        let margin = rep.deadline_ns as f64 - max_ns;
        let _ = writeln!(
            s,
            "| firmware (QEMU, recorded cycles) | 1 | - | {} | {} | - | - | {:.0} at {} MHz | cycle {} ({}) | - | {} / {} | {} / {} | {:.0} ({}){} |",
            fw.cycles,
            fw.non_optimal,
            max_ns,
            rep.clock_mhz,
            fw.max_all_cycle,
            fw.max_all_status,
            fw.iterations_optimal
                .map_or("-".to_string(), |v| v.to_string()),
            fw.iterations_all,
            fw.max_optimal.map_or("-".to_string(), |v| v.to_string()),
            fw.max_all,
            margin,
            pct(margin, rep.deadline_ns as f64),
            if margin < 0.0 { " MISSED" } else { "" },
        );
    }
    s.push('\n');
}

/// The notes on the last row (all cases): the worst iteration counts, the
/// non-optimal cycles and the slowest cycle.
fn totals(s: &mut String, rep: &DeadlineReport) {
    if let Some(total) = rep.rows.last().map(|r| &r.stats) {
        let worst = |w: &Option<Worst>, budget: u32| match w {
            Some(w) => format!(
                "{w}: {} of {budget}, margin {} ({})",
                w.value,
                i64::from(budget) - i64::from(w.value),
                pct(f64::from(budget) - f64::from(w.value), f64::from(budget))
            ),
            None => "none".into(),
        };
        let _ = writeln!(
            s,
            "- iterations (adds + drops), worst optimal cycle (one QP solve, budget `max_iter` = {}): {}",
            total.max_iter,
            worst(&total.worst_optimal, total.max_iter)
        );
        let _ = writeln!(
            s,
            "- iterations, worst cycle (priority scheme included, budget `max_iter_cycle` = {}): {}",
            total.max_iter_cycle,
            worst(&total.worst_all, total.max_iter_cycle)
        );
        let _ = writeln!(
            s,
            "- non-optimal cycles {} of {}: budget_exhausted {}, numerical_failure {}, invalid_input {}; fallback commands (previous plan / capture step) {}; their compute p50 {} ns, max {} ns",
            total.non_optimal,
            total.cycles,
            total.budget_exhausted,
            total.numerical_failure,
            total.invalid_input,
            total.fallback,
            total.compute_non_optimal.p50_ns,
            total.compute_non_optimal.max_ns
        );
        if let Some(w) = &total.slowest {
            let _ = writeln!(
                s,
                "- slowest cycle: {} ns, {w} (`ldcbf-sim run` of that case logs it in cycles.csv: \
                 data row {}, `t` = {:.3}){}",
                w.compute_ns,
                w.cycle + 1,
                w.time,
                if rep.repeat > 1 {
                    format!("; minimum of {} timings", rep.repeat)
                } else {
                    "; one timing, maybe a preemption".to_string()
                }
            );
        }
    }
}

/// Where the instruction counts come from, or why there are none.
fn instructions_note(s: &mut String, rep: &DeadlineReport, budget: u64) {
    match &rep.instructions {
        Some(fw) => {
            let _ = writeln!(
                s,
                "- instructions: {} ({} cycles replayed by the firmware in QEMU, `-icount`, deterministic); budget {budget} per cycle",
                fw.source.display(),
                fw.cycles
            );
        }
        None => {
            *s += "- instructions max: n/a (see firmware/README.md; `--instructions FILE` reads the \
                  per-cycle CSV that tests/firmware_qemu.rs writes to firmware/target/instructions.csv)\n";
        }
    }
}
