//! The aggregate of a set of runs and the Markdown table of several sets.

use serde::{Deserialize, Serialize};

use super::{BatchMeta, RunRow};

/// Aggregate of a set of runs (the Markdown table's rows).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Aggregate {
    /// Runs.
    pub runs: usize,
    /// Successful runs (goal reached, no collision).
    pub success: usize,
    /// Runs that reached the goal (with or without a collision).
    pub reached: usize,
    /// Runs whose body touched a true obstacle.
    pub collisions: usize,
    /// Runs with a footprint overlapping a true obstacle.
    pub foot_collisions: usize,
    /// Contacts where the robot moved into an obstacle, over all runs
    /// (`crate::sim::ContactCause::Robot`; controller failures).
    #[serde(default)]
    pub contacts_robot: u64,
    /// Contacts where a moving obstacle moved into a robot that was not moving
    /// toward it, over all runs (`crate::sim::ContactCause::Obstacle`).
    #[serde(default)]
    pub contacts_person: u64,
    /// Runs that ended stuck.
    pub stuck: usize,
    /// Runs that hit the time limit.
    pub timeouts: usize,
    /// Runs that diverged (controller input out of range).
    pub diverged: usize,
    /// Runs whose planner failed.
    pub planner_failures: usize,
    /// Mean steps to the goal over successful runs.
    #[serde(deserialize_with = "f64_or_nan")]
    pub mean_steps: f64,
    /// Median steps to the goal over successful runs.
    #[serde(deserialize_with = "f64_or_nan")]
    pub median_steps: f64,
    /// Mean time to the goal over successful runs, s.
    #[serde(deserialize_with = "f64_or_nan")]
    pub mean_time: f64,
    /// Median time to the goal over successful runs, s.
    #[serde(deserialize_with = "f64_or_nan")]
    pub median_time: f64,
    /// Smallest CoM clearance to the true obstacles over all runs, m.
    #[serde(deserialize_with = "f64_or_nan")]
    pub min_com_clearance: f64,
    /// Smallest body clearance over all runs, m.
    #[serde(deserialize_with = "f64_or_nan")]
    pub min_body_clearance: f64,
    /// Smallest footprint clearance over all runs, m.
    #[serde(deserialize_with = "f64_or_nan")]
    pub min_footstep_clearance: f64,
    /// Runs with some non-optimal (relaxed or fallback) cycle.
    pub runs_with_non_optimal: usize,
    /// Median over runs of each run's compute p99, ns.
    pub compute_p99_median_ns: u64,
    /// Largest per-run compute p99, ns.
    pub compute_p99_max_ns: u64,
    /// Slowest controller call of all runs, ns.
    pub compute_max_ns: u64,
}

/// JSON has no NaN or infinity: serde_json writes them as `null`. Reads a
/// `null` back as NaN (a mean over no runs, a clearance without obstacles).
fn f64_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Aggregates rows.
pub fn aggregate(rows: &[RunRow]) -> Aggregate {
    let ok: Vec<&RunRow> = rows.iter().filter(|r| r.success).collect();
    let mean = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let mut steps: Vec<f64> = ok.iter().map(|r| r.steps as f64).collect();
    let mut times: Vec<f64> = ok.iter().map(|r| r.sim_time).collect();
    let mut p99: Vec<f64> = rows.iter().map(|r| r.compute_p99_ns as f64).collect();
    let count = |f: &dyn Fn(&RunRow) -> bool| rows.iter().filter(|r| f(r)).count();
    Aggregate {
        runs: rows.len(),
        success: ok.len(),
        reached: count(&|r| r.outcome == "goal_reached"),
        collisions: count(&|r| r.collision),
        foot_collisions: count(&|r| r.foot_collision),
        contacts_robot: rows.iter().map(|r| r.contacts_robot).sum(),
        contacts_person: rows.iter().map(|r| r.contacts_person).sum(),
        stuck: count(&|r| r.outcome == "stuck"),
        timeouts: count(&|r| r.outcome == "time_limit"),
        diverged: count(&|r| r.outcome == "diverged"),
        planner_failures: count(&|r| r.planner_failed),
        mean_steps: mean(&steps),
        median_steps: median(&mut steps),
        mean_time: mean(&times),
        median_time: median(&mut times),
        min_com_clearance: rows
            .iter()
            .map(|r| r.min_com_clearance)
            .fold(f64::INFINITY, f64::min),
        min_body_clearance: rows
            .iter()
            .map(|r| r.min_body_clearance)
            .fold(f64::INFINITY, f64::min),
        min_footstep_clearance: rows
            .iter()
            .map(|r| r.min_footstep_clearance)
            .fold(f64::INFINITY, f64::min),
        runs_with_non_optimal: count(&|r| r.non_optimal_cycles > 0),
        compute_p99_median_ns: median(&mut p99).max(0.0) as u64,
        compute_p99_max_ns: rows.iter().map(|r| r.compute_p99_ns).max().unwrap_or(0),
        compute_max_ns: rows.iter().map(|r| r.compute_max_ns).max().unwrap_or(0),
    }
}

/// A Markdown table with one column per `(label, aggregate)`.
pub fn markdown_table(cols: &[(String, Aggregate)]) -> String {
    let pct = |a: usize, n: usize| {
        if n == 0 {
            "n/a".to_string()
        } else {
            format!("{:.1} % ({a}/{n})", 100.0 * a as f64 / n as f64)
        }
    };
    let f1 = |v: f64| {
        if v.is_finite() {
            format!("{v:.1}")
        } else {
            "n/a".into()
        }
    };
    let us = |ns: u64| format!("{:.1} us", ns as f64 / 1e3);
    type Row<'a> = (&'a str, Box<dyn Fn(&Aggregate) -> String + 'a>);
    let rows: Vec<Row<'_>> = vec![
        ("runs", Box::new(|a: &Aggregate| a.runs.to_string())),
        (
            "success rate (goal, no body or foot collision)",
            Box::new(move |a: &Aggregate| pct(a.success, a.runs)),
        ),
        (
            "collisions (the body touched a true obstacle)",
            Box::new(|a: &Aggregate| a.collisions.to_string()),
        ),
        (
            "foot collisions (a footprint on a true obstacle)",
            Box::new(|a: &Aggregate| a.foot_collisions.to_string()),
        ),
        (
            "contacts: the robot moved into an obstacle",
            Box::new(|a: &Aggregate| a.contacts_robot.to_string()),
        ),
        (
            "contacts: a person moved into the standing robot",
            Box::new(|a: &Aggregate| a.contacts_person.to_string()),
        ),
        ("stuck", Box::new(|a: &Aggregate| a.stuck.to_string())),
        (
            "time limit",
            Box::new(|a: &Aggregate| a.timeouts.to_string()),
        ),
        ("diverged", Box::new(|a: &Aggregate| a.diverged.to_string())),
        (
            "planner failures",
            Box::new(|a: &Aggregate| a.planner_failures.to_string()),
        ),
        (
            "steps to goal, mean / median",
            Box::new(move |a: &Aggregate| format!("{} / {}", f1(a.mean_steps), f1(a.median_steps))),
        ),
        (
            "time to goal, mean / median [s]",
            Box::new(move |a: &Aggregate| format!("{} / {}", f1(a.mean_time), f1(a.median_time))),
        ),
        (
            "min body / foot clearance [m]",
            Box::new(|a: &Aggregate| {
                let m = |v: f64| {
                    if v.is_finite() {
                        format!("{v:.3}")
                    } else {
                        "n/a".into()
                    }
                };
                format!(
                    "{} / {}",
                    m(a.min_body_clearance),
                    m(a.min_footstep_clearance)
                )
            }),
        ),
        (
            "min CoM clearance [m]",
            Box::new(|a: &Aggregate| {
                if a.min_com_clearance.is_finite() {
                    format!("{:.3}", a.min_com_clearance)
                } else {
                    "n/a".into()
                }
            }),
        ),
        (
            "runs with a relaxed/fallback cycle",
            Box::new(|a: &Aggregate| a.runs_with_non_optimal.to_string()),
        ),
        (
            "compute p99, median / max over runs",
            Box::new(move |a: &Aggregate| {
                format!(
                    "{} / {}",
                    us(a.compute_p99_median_ns),
                    us(a.compute_p99_max_ns)
                )
            }),
        ),
        (
            "compute max",
            Box::new(move |a: &Aggregate| us(a.compute_max_ns)),
        ),
    ];
    let mut s = String::from("| |");
    for (label, _) in cols {
        s += &format!(" {label} |");
    }
    s += "\n|---|";
    for _ in cols {
        s += "---|";
    }
    s += "\n";
    for (name, f) in &rows {
        s += &format!("| {name} |");
        for (_, a) in cols {
            s += &format!(" {} |", f(a));
        }
        s += "\n";
    }
    s
}

/// Column label of a study: `planner / perception` and any `--set`.
pub fn label(meta: &BatchMeta) -> String {
    let extra: Vec<String> = meta
        .sets
        .iter()
        .filter(|(k, _)| k != "planner" && k != "perception")
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    let mut l = format!("{} / {}", meta.planner, meta.perception);
    if !extra.is_empty() {
        l += &format!(" ({})", extra.join(", "));
    }
    l
}
