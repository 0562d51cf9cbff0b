//! Semantic validation of a parsed scenario file: ranges, combinations, the
//! obstacles, the generator, and a start and goal the robot can stand at.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Config, closest_point_point_polygon};

use super::Scenario;
use super::ScenarioError;
use super::parse::{RawScenario, line_of};
use crate::world::families;
use crate::world::moving::parse_velocity;
use crate::world::random::{random_obstacles, regular_polygon};
use crate::world::{MAX_VERTICES, Polygon};

/// Semantic validation. `text` (the file's text) gives lines to spans; `None`
/// for re-serialised `--set` text, whose spans do not match the file.
pub(super) fn validate(
    raw: RawScenario,
    text: Option<&str>,
    file: &str,
    seed: Option<u64>,
) -> Result<Scenario, ScenarioError> {
    let err = |field: &str, span: Option<core::ops::Range<usize>>, message: String| {
        let line = match (text, span) {
            (Some(t), Some(s)) if s.end > s.start => Some(line_of(t, s.start)),
            _ => None,
        };
        ScenarioError {
            file: file.into(),
            field: field.into(),
            line,
            message,
        }
    };
    let finite = |v: f64| v.is_finite();
    if raw.name.is_empty()
        || !raw
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(ScenarioError {
            file: file.into(),
            field: "name".into(),
            line: text.and_then(|t| {
                t.lines()
                    .position(|l| l.trim_start().starts_with("name"))
                    .map(|i| i + 1)
            }),
            message: "must be non-empty and use only ASCII letters, digits, `-` and `_` \
                      (it names the output directory)"
                .into(),
        });
    }
    let st = raw.start.get_ref();
    if !(finite(st.x) && finite(st.y) && finite(st.heading)) {
        return Err(err(
            "start",
            Some(raw.start.span()),
            "x, y and heading must be finite".into(),
        ));
    }
    let g = raw.goal.get_ref().0;
    if !(finite(g[0]) && finite(g[1])) {
        return Err(err("goal", Some(raw.goal.span()), "must be finite".into()));
    }
    let pos = |v: f64| v.is_finite() && v > 0.0;
    if !pos(*raw.time_limit.get_ref()) || *raw.time_limit.get_ref() > 1e5 {
        return Err(err(
            "time_limit",
            Some(raw.time_limit.span()),
            "must be in (0, 1e5] s".into(),
        ));
    }
    if !pos(*raw.success_radius.get_ref()) {
        return Err(err(
            "success_radius",
            Some(raw.success_radius.span()),
            "must be finite and > 0".into(),
        ));
    }
    let sw = *raw.stuck_window.get_ref();
    if !(sw.is_finite() && sw >= 0.0) {
        return Err(err(
            "stuck_window",
            Some(raw.stuck_window.span()),
            "must be finite and >= 0 (0 disables)".into(),
        ));
    }
    if let Err((f, m)) = raw.rrt_star.get_ref().validate() {
        let line = text.and_then(|t| find_key_line(t, "rrt_star", f));
        return Err(ScenarioError {
            file: file.into(),
            field: format!("rrt_star.{f}"),
            line,
            message: m,
        });
    }
    if let Err((f, m)) = raw.lidar.get_ref().validate() {
        let line = text.and_then(|t| find_key_line(t, "lidar", f));
        return Err(ScenarioError {
            file: file.into(),
            field: format!("lidar.{f}"),
            line,
            message: m,
        });
    }
    if let Err((f, m)) = raw.disturbance.get_ref().validate() {
        let line = text.and_then(|t| find_key_line(t, "disturbance", f));
        return Err(ScenarioError {
            file: file.into(),
            field: format!("disturbance.{f}"),
            line,
            message: m,
        });
    }
    if let Err((f, m)) = raw.robot.get_ref().validate() {
        let line = text.and_then(|t| find_key_line(t, "robot", f));
        return Err(ScenarioError {
            file: file.into(),
            field: format!("robot.{f}"),
            line,
            message: m,
        });
    }
    let robot = raw.robot.get_ref().clone();
    let overrides = raw.controller.get_ref().clone();
    let config = robot.apply(overrides.apply(Config::default()));
    if let Err(e) = config.validate() {
        let field = format!("controller.{}", e.field);
        // The span of the `[controller]` table; the field line is found by key.
        let line = text.and_then(|t| find_key_line(t, "controller", e.field));
        return Err(ScenarioError {
            file: file.into(),
            field,
            line,
            message: e.requirement.into(),
        });
    }
    // The controller's own checks of the combination (e.g. the step map of
    // gravity, com_height and step_duration), at load time, not mid-run.
    if let Err(e) = ldcbf_controller::RobotController::new(config) {
        let line = text.and_then(|t| find_key_line(t, "controller", e.field));
        let beta_t = (config.gravity / config.com_height).sqrt() * config.step_duration;
        return Err(ScenarioError {
            file: file.into(),
            field: format!("controller.{}", e.field),
            line,
            message: format!(
                "{} (with gravity {} m/s^2, com_height {} m, step_duration {} s: beta T = {beta_t:.3e})",
                e.requirement, config.gravity, config.com_height, config.step_duration
            ),
        });
    }
    if overrides.foot_clearance.is_some() && !robot.keep_feet_clear {
        return Err(err(
            "controller.foot_clearance",
            Some(raw.controller.span()),
            "sets the feet's extra clearance, but robot.keep_feet_clear = false turns the foot rows off"
                .into(),
        ));
    }
    let mut start = Vector2::new(st.x, st.y);
    let mut start_heading = st.heading;
    let mut goal = Vector2::new(g[0], g[1]);
    let mut obstacles = Vec::with_capacity(raw.obstacles.len());
    let mut velocities = Vec::with_capacity(raw.obstacles.len());
    for (i, ob) in raw.obstacles.iter().enumerate() {
        let field = format!("obstacles[{i}]");
        let span = Some(ob.span());
        let o = ob.get_ref();
        let (poly, field, span) = match (&o.vertices, &o.regular) {
            (Some(_), Some(_)) => {
                return Err(err(
                    &field,
                    span,
                    "give `vertices` or `regular`, not both".into(),
                ));
            }
            (None, None) => {
                return Err(err(&field, span, "needs `vertices` or `regular`".into()));
            }
            (Some(v), None) => {
                let pts: Vec<[f64; 2]> = v.get_ref().iter().map(|p| p.0).collect();
                let poly = if o.hull {
                    Polygon::hull(&pts)
                } else {
                    Polygon::new(&pts)
                };
                (poly, format!("{field}.vertices"), Some(v.span()))
            }
            (None, Some(rs)) => {
                let r = rs.get_ref();
                let f = format!("{field}.regular");
                if !(r.sides >= 3 && r.sides as usize <= MAX_VERTICES) {
                    return Err(err(
                        &format!("{f}.sides"),
                        Some(rs.span()),
                        format!("must be in 3..={MAX_VERTICES}"),
                    ));
                }
                if !(pos(r.radius)
                    && r.center.0.iter().all(|c| c.is_finite())
                    && r.rotation.is_finite())
                {
                    return Err(err(
                        &f,
                        Some(rs.span()),
                        "center and rotation must be finite, radius > 0".into(),
                    ));
                }
                let poly =
                    Polygon::new(&regular_polygon(r.center.0, r.radius, r.sides, r.rotation));
                (poly, f, Some(rs.span()))
            }
        };
        let poly = poly.map_err(|e| {
            let hint = if matches!(e, ldcbf_controller::GeometryError::NotConvex) {
                " (set `hull = true` to use the convex hull of the points)"
            } else {
                ""
            };
            err(&field, span.clone(), format!("{e}{hint}"))
        })?;
        obstacles.push(poly);
        velocities.push(match &ob.get_ref().velocity {
            None => Vector2::zeros(),
            Some(v) => parse_velocity(v.get_ref())
                .map_err(|m| err(&format!("obstacles[{i}].velocity"), Some(v.span()), m))?,
        });
    }
    let seed = seed.unwrap_or(raw.seed);
    let generator = match &raw.generator {
        None => None,
        Some(gs) => {
            let p = gs.get_ref().clone();
            if let Err((f, m)) = p.validate() {
                return Err(err(&format!("generator.{f}"), Some(gs.span()), m));
            }
            if p.kind == "random_polygons" {
                let extra = random_obstacles(seed, &p, start, goal)
                    .map_err(|m| err("generator", Some(gs.span()), m))?;
                velocities.resize(obstacles.len() + extra.len(), Vector2::zeros());
                obstacles.extend(extra);
            } else {
                let layout = families::generate(&p.kind, seed, robot.body_radius)
                    .map_err(|m| err("generator", Some(gs.span()), m))?;
                start = layout.start;
                start_heading = layout.heading;
                goal = layout.goal;
                velocities.extend(layout.velocities_padded());
                obstacles.extend(layout.obstacles);
            }
            Some(p)
        }
    };
    // Impossible scenarios: the body must fit at the start and at the goal.
    let n_file = raw.obstacles.len();
    for (what, p, span) in [
        ("start", start, raw.start.span()),
        ("goal", goal, raw.goal.span()),
    ] {
        if let Some((i, d)) = obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| (i, closest_point_point_polygon(&p, o).signed_distance))
            .find(|&(_, d)| d <= robot.body_radius)
        {
            let name = if i < n_file {
                format!("obstacles[{i}]")
            } else {
                format!("generated obstacle {} (seed {seed})", i - n_file)
            };
            let how = if d <= 0.0 {
                format!("is inside {name} ({:.3} m deep)", -d)
            } else {
                format!(
                    "is {d:.3} m from {name}, within the robot's body radius {} m (robot.body_radius)",
                    robot.body_radius
                )
            };
            return Err(err(
                what,
                Some(span),
                format!("{how}: the robot cannot stand there"),
            ));
        }
    }
    Ok(Scenario {
        name: raw.name,
        description: raw.description,
        note: raw.note,
        source: file.into(),
        start,
        start_heading,
        stance: raw.stance.into(),
        goal,
        time_limit: *raw.time_limit.get_ref(),
        success_radius: *raw.success_radius.get_ref(),
        stuck_window: sw,
        planner: *raw.planner.get_ref(),
        perception: *raw.perception.get_ref(),
        seed,
        generator,
        controller: overrides,
        config,
        rrt: raw.rrt_star.get_ref().clone(),
        lidar: raw.lidar.get_ref().clone(),
        disturbance: raw.disturbance.get_ref().clone(),
        robot,
        obstacles,
        velocities,
    })
}

/// Line of `key = ...` inside `[table]` (or `table.key = ...`, or an inline
/// `table = { key = ... }`), by a plain text scan. Best effort, for messages.
fn find_key_line(text: &str, table: &str, key: &str) -> Option<usize> {
    let mut in_table = false;
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.starts_with('[') {
            in_table = l.trim_start_matches('[').trim_end_matches(']').trim() == table;
            continue;
        }
        let starts = |prefix: &str| {
            l.strip_prefix(prefix)
                .is_some_and(|r| r.trim_start().starts_with('='))
        };
        if (in_table && starts(key))
            || starts(&format!("{table}.{key}"))
            || (l.starts_with(table) && l.contains(&format!("{key} =")))
        {
            return Some(i + 1);
        }
    }
    None
}
