//! The raw file types (as `serde` reads them, with spans), `--set` overrides
//! applied to the parsed table, and the line and dotted field path of a TOML
//! error.

use std::collections::BTreeMap;

use serde::Deserialize;
use toml::Spanned;

use super::limits::{MAX_ECHO, Xy, check_key, field_name, shorten};
use super::{ControllerOverrides, ScenarioError, SideSpec, controller_fields};
use crate::plan::{Planner, RrtParams};
use crate::plant::disturbance::DisturbanceParams;
use crate::sense::{LidarParams, Perception};
use crate::world::crowd::Policy;
use crate::world::random::RandomParams;
use crate::world::robot::RobotParams;

// ---------------------------------------------------------------- raw file types

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScenario {
    pub(super) name: String,
    #[serde(default)]
    pub(super) description: String,
    #[serde(default)]
    pub(super) note: String,
    pub(super) start: Spanned<RawStart>,
    #[serde(default)]
    pub(super) stance: SideSpec,
    pub(super) goal: Spanned<Xy>,
    #[serde(default = "default_time_limit")]
    pub(super) time_limit: Spanned<f64>,
    #[serde(default = "default_success_radius")]
    pub(super) success_radius: Spanned<f64>,
    #[serde(default = "default_stuck_window")]
    pub(super) stuck_window: Spanned<f64>,
    #[serde(default = "spanned_default")]
    pub(super) planner: Spanned<Planner>,
    #[serde(default = "spanned_default")]
    pub(super) perception: Spanned<Perception>,
    #[serde(default)]
    pub(super) seed: u64,
    #[serde(default = "spanned_default")]
    pub(super) controller: Spanned<ControllerOverrides>,
    #[serde(default)]
    pub(super) obstacles: Vec<Spanned<RawObstacle>>,
    #[serde(default)]
    pub(super) people: Vec<Spanned<RawPerson>>,
    #[serde(default)]
    pub(super) generator: Option<Spanned<RandomParams>>,
    #[serde(default = "spanned_default")]
    pub(super) rrt_star: Spanned<RrtParams>,
    #[serde(default = "spanned_default")]
    pub(super) lidar: Spanned<LidarParams>,
    #[serde(default = "spanned_default")]
    pub(super) disturbance: Spanned<DisturbanceParams>,
    #[serde(default = "spanned_default")]
    pub(super) robot: Spanned<RobotParams>,
}

fn spanned_default<T: Default>() -> Spanned<T> {
    Spanned::new(0..0, T::default())
}
fn default_time_limit() -> Spanned<f64> {
    Spanned::new(0..0, 120.0)
}
fn default_success_radius() -> Spanned<f64> {
    Spanned::new(0..0, 0.15)
}
fn default_stuck_window() -> Spanned<f64> {
    Spanned::new(0..0, 30.0)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStart {
    pub(super) x: f64,
    pub(super) y: f64,
    #[serde(default)]
    pub(super) heading: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawObstacle {
    #[serde(default)]
    pub(super) vertices: Option<Spanned<Vec<Xy>>>,
    #[serde(default)]
    pub(super) regular: Option<Spanned<RegularSpec>>,
    #[serde(default)]
    pub(super) hull: bool,
    /// Constant velocity, m/s, world frame (at rest when absent).
    #[serde(default)]
    pub(super) velocity: Option<Spanned<Vec<f64>>>,
    /// Optional label, for humans.
    #[serde(default)]
    #[allow(dead_code)]
    pub(super) name: Option<String>,
}

/// A `[[people]]` entry: a person who walks to a goal
/// ([`crate::world::crowd::Person`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPerson {
    pub(super) start: Xy,
    pub(super) goal: Xy,
    #[serde(default = "default_person_speed")]
    pub(super) speed: f64,
    #[serde(default = "default_person_radius")]
    pub(super) radius: f64,
    #[serde(default)]
    pub(super) policy: Policy,
    #[serde(default = "default_true")]
    pub(super) visible_robot: bool,
    #[serde(default)]
    pub(super) group: Option<u32>,
    #[serde(default)]
    pub(super) stops: Vec<Xy>,
    /// Optional label, for humans.
    #[serde(default)]
    #[allow(dead_code)]
    pub(super) name: Option<String>,
}

fn default_person_speed() -> f64 {
    crate::world::people::NOMINAL_SPEED
}
fn default_person_radius() -> f64 {
    crate::world::crowd::families::HUMAN_RADIUS
}
fn default_true() -> bool {
    true
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RegularSpec {
    pub(super) center: Xy,
    pub(super) radius: f64,
    pub(super) sides: u32,
    #[serde(default)]
    pub(super) rotation: f64,
}

/// Applies one `--set key=value` to the parsed table.
pub(super) fn apply_set(table: &mut toml::Table, key: &str, value: &str) -> Result<(), String> {
    let top_level = [
        "name",
        "description",
        "note",
        "start",
        "stance",
        "goal",
        "time_limit",
        "success_radius",
        "stuck_window",
        "planner",
        "perception",
        "seed",
        "controller",
        "obstacles",
        "people",
        "generator",
        "rrt_star",
        "lidar",
        "disturbance",
        "robot",
    ];
    check_key(key)?;
    let mut parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("empty key component".into());
    }
    if parts.len() == 1 && !top_level.contains(&parts[0]) {
        if controller_fields().any(|f| f == parts[0]) {
            parts.insert(0, "controller");
        } else {
            return Err(format!(
                "unknown key (scenario keys: {}; controller fields: {})",
                top_level.join(", "),
                controller_fields().collect::<Vec<_>>().join(", ")
            ));
        }
    }
    // A value that looks like a list or a table must parse as one; anything
    // else that is not a TOML value is taken as a string.
    let parsed: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {value}")) {
        Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(value.into())),
        Err(e) if value.trim_start().starts_with(['[', '{']) => {
            return Err(format!(
                "value {} is not a TOML list or table: {}",
                shorten(value, MAX_ECHO),
                shorten(e.message().trim(), MAX_ECHO)
            ));
        }
        Err(_) => toml::Value::String(value.into()),
    };
    let (last, dirs) = parts.split_last().expect("non-empty");
    let mut cur = table;
    for d in dirs {
        let entry = cur
            .entry(d.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = entry
            .as_table_mut()
            .ok_or_else(|| format!("`{d}` is not a table"))?;
    }
    cur.insert(last.to_string(), parsed);
    Ok(())
}

pub(super) fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Converts a TOML/serde error into a [`ScenarioError`] with the line and the
/// dotted path of the innermost key whose value contains the error.
pub(super) fn toml_error(e: &toml::de::Error, text: &str, file: &str) -> ScenarioError {
    let span = e.span();
    let line = span.as_ref().map(|s| line_of(text, s.start));
    let field = span
        .as_ref()
        .and_then(|s| {
            let duplicate = e.message().contains("duplicate key");
            path_at(text, s.start).or_else(|| key_near(text, s.start, duplicate))
        })
        .unwrap_or_else(|| "(document)".into());
    ScenarioError {
        file: file.into(),
        field,
        line,
        message: shorten(e.message().trim(), 4 * MAX_ECHO),
    }
}

/// For text that does not parse: the `key` of the nearest `key = ...` line at or
/// before `offset` (with `its_line`, up to the end of the line holding
/// `offset`: a duplicate key's error points at the key's first byte), prefixed
/// by the table header above it (`[t]` gives `t.key`, the n-th `[[t]]` gives
/// `t[n].key`). A text scan, for messages only.
fn key_near(text: &str, offset: usize, its_line: bool) -> Option<String> {
    let offset = offset.min(text.len());
    let end = match text.get(offset..) {
        Some(rest) if its_line => rest.find('\n').map_or(text.len(), |i| offset + i),
        _ => offset,
    };
    let upto = text.get(..end).unwrap_or(text);
    let mut table = String::new();
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut key: Option<String> = None;
    for line in upto.lines() {
        let l = line.trim();
        if let Some(h) = l.strip_prefix("[[") {
            let name = h.trim_end_matches("]]").trim().to_string();
            let n = counts.entry(name.clone()).or_insert(0);
            table = format!("{name}[{n}]");
            *n += 1;
            key = None;
        } else if let Some(h) = l.strip_prefix('[') {
            table = h.trim_end_matches(']').trim().to_string();
            key = None;
        } else if let Some((k, _)) = l.split_once('=') {
            let k = k.trim();
            if !k.is_empty()
                && k.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
            {
                key = Some(k.to_string());
            }
        }
    }
    match (table.is_empty(), key) {
        (true, None) => None,
        (true, Some(k)) => Some(k),
        (false, Some(k)) => Some(format!("{table}.{k}")),
        (false, None) => Some(table),
    }
}

/// Dotted path of the innermost key or value whose span contains `offset`.
fn path_at(text: &str, offset: usize) -> Option<String> {
    use toml::de::{DeTable, DeValue};
    fn walk_value(
        v: &Spanned<DeValue<'_>>,
        path: &str,
        offset: usize,
        best: &mut Option<(usize, String)>,
    ) {
        match v.get_ref() {
            DeValue::Table(t) => walk_table(t, path, offset, best),
            DeValue::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    let p = format!("{path}[{i}]");
                    consider(e.span(), &p, offset, best);
                    walk_value(e, &p, offset, best);
                }
            }
            _ => {}
        }
    }
    fn consider(
        span: core::ops::Range<usize>,
        path: &str,
        offset: usize,
        best: &mut Option<(usize, String)>,
    ) {
        if span.start <= offset && offset < span.end.max(span.start + 1) {
            let len = span.end - span.start;
            if best.as_ref().is_none_or(|(l, _)| len <= *l) {
                *best = Some((len, path.to_string()));
            }
        }
    }
    fn walk_table(
        t: &DeTable<'_>,
        prefix: &str,
        offset: usize,
        best: &mut Option<(usize, String)>,
    ) {
        for (k, v) in t.iter() {
            let (key_span, k) = (k.span(), field_name(k.get_ref()));
            let path = if prefix.is_empty() {
                k
            } else {
                format!("{prefix}.{k}")
            };
            consider(key_span, &path, offset, best);
            consider(v.span(), &path, offset, best);
            walk_value(v, &path, offset, best);
        }
    }
    let doc = DeTable::parse(text).ok()?;
    let mut best = None;
    walk_table(doc.get_ref(), "", offset, &mut best);
    best.map(|(_, p)| p)
}
