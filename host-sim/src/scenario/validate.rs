//! Semantic validation of a parsed scenario file: ranges, combinations, the
//! obstacles, the generator, and a start and goal the robot can stand at.

use core::ops::Range;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Config, closest_point_point_polygon};
use toml::Spanned;

use super::parse::{RawObstacle, RawScenario, line_of};
use super::{ControllerOverrides, Scenario, ScenarioError};
use crate::world::crowd::families as crowd_families;
use crate::world::crowd::{MAX_PEOPLE, Person};
use crate::world::families;
use crate::world::moving::parse_velocity;
use crate::world::random::{random_obstacles, regular_polygon};
use crate::world::robot::RobotParams;
use crate::world::{MAX_VERTICES, Polygon};

/// Where a scenario's text came from, for the line and file of its errors.
#[derive(Clone, Copy)]
struct Source<'a> {
    /// The file's text (lines of spans); `None` for re-serialised `--set`
    /// text, whose spans do not match the file.
    text: Option<&'a str>,
    /// The file's name as the user gave it.
    file: &'a str,
}

impl Source<'_> {
    /// An error at `field`, on the line of `span` when the text is the file's.
    fn err(&self, field: &str, span: Option<Range<usize>>, message: String) -> ScenarioError {
        let line = match (self.text, span) {
            (Some(t), Some(s)) if s.end > s.start => Some(line_of(t, s.start)),
            _ => None,
        };
        ScenarioError {
            file: self.file.into(),
            field: field.into(),
            line,
            message,
        }
    }

    /// An error at `table.key`, on the line of that key (found by a text scan).
    fn table_err(&self, table: &str, key: &str, message: String) -> ScenarioError {
        ScenarioError {
            file: self.file.into(),
            field: format!("{table}.{key}"),
            line: self.text.and_then(|t| find_key_line(t, table, key)),
            message,
        }
    }
}

/// Semantic validation. `text` (the file's text) gives lines to spans; `None`
/// for re-serialised `--set` text, whose spans do not match the file. The
/// checks run in the order of the file's sections; the first failure is the
/// error.
pub(super) fn validate(
    raw: RawScenario,
    text: Option<&str>,
    file: &str,
    seed: Option<u64>,
) -> Result<Scenario, ScenarioError> {
    let src = Source { text, file };
    check_name(&raw, src)?;
    check_scalars(&raw, src)?;
    check_settings(&raw, src)?;
    let (config, overrides, robot) = controller_config(&raw, src)?;
    check_map_holds_robot(&raw, &config, src)?;
    let st = raw.start.get_ref();
    let g = raw.goal.get_ref().0;
    let mut start = Vector2::new(st.x, st.y);
    let mut start_heading = st.heading;
    let mut goal = Vector2::new(g[0], g[1]);
    let (mut obstacles, mut velocities) = file_obstacles(&raw, src)?;
    let mut people = file_people(&raw, src)?;
    let seed = seed.unwrap_or(raw.seed);
    let generator = match &raw.generator {
        None => None,
        Some(gs) => {
            let p = gs.get_ref().clone();
            if let Err(e) = p.validate() {
                return Err(src.err(
                    &format!("generator.{}", e.field),
                    Some(gs.span()),
                    e.requirement,
                ));
            }
            if p.kind == "random_polygons" {
                let extra = random_obstacles(seed, &p, start, goal)
                    .map_err(|m| src.err("generator", Some(gs.span()), m))?;
                velocities.resize(obstacles.len() + extra.len(), Vector2::zeros());
                obstacles.extend(extra);
            } else if let Some(c) = crowd_families::generate(&p.kind, seed, robot.body_radius) {
                let c = c.map_err(|m| src.err("generator", Some(gs.span()), m))?;
                start = c.layout.start;
                start_heading = c.layout.heading;
                goal = c.layout.goal;
                velocities.extend(c.layout.velocities_padded());
                obstacles.extend(c.layout.obstacles);
                people.extend(c.people);
            } else {
                let layout = families::generate(&p.kind, seed, robot.body_radius)
                    .map_err(|m| src.err("generator", Some(gs.span()), m))?;
                start = layout.start;
                start_heading = layout.heading;
                goal = layout.goal;
                velocities.extend(layout.velocities_padded());
                obstacles.extend(layout.obstacles);
            }
            Some(p)
        }
    };
    // The people who react follow every other obstacle, at their starts,
    // with their initial preferred velocities (crate::world::crowd).
    let people_from = obstacles.len();
    for p in &people {
        obstacles.push(p.polygon_at(p.start));
        velocities.push(p.initial_velocity());
    }
    let ends = [
        ("start", start, raw.start.span()),
        ("goal", goal, raw.goal.span()),
    ];
    let names = Names {
        n_file: raw.obstacles.len(),
        people_from,
        seed,
    };
    check_room_to_stand(&ends, &obstacles, &names, &robot, src)?;
    // (The people who react steer: their paths are not straight lines.)
    check_paths_in_range(
        obstacles.get(..people_from).unwrap_or(&obstacles),
        velocities.get(..people_from).unwrap_or(&velocities),
        &raw,
        src,
    )?;
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
        stuck_window: *raw.stuck_window.get_ref(),
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
        people,
    })
}

/// At most [`super::limits::MAX_MOVING_OBSTACLES`] obstacles move, and every
/// moving obstacle stays inside the coordinate limit
/// ([`ldcbf_controller::geometry::MAX_COORDINATE`], 1e6 m, what a polygon may
/// hold) until `time_limit`: a person who would cross it is refused here, not
/// moved back to their start during the run.
fn check_paths_in_range(
    obstacles: &[Polygon],
    velocities: &[Vector2<f64>],
    raw: &RawScenario,
    src: Source<'_>,
) -> Result<(), ScenarioError> {
    use ldcbf_controller::geometry::MAX_COORDINATE;
    let moving = velocities
        .iter()
        .filter(|v| **v != Vector2::zeros())
        .count();
    if moving > super::limits::MAX_MOVING_OBSTACLES {
        return Err(src.err(
            "obstacles",
            None,
            format!(
                "{moving} moving obstacles, more than the {} a scenario may hold (each is \
                 checked at every 1 kHz tick)",
                super::limits::MAX_MOVING_OBSTACLES
            ),
        ));
    }
    let t = *raw.time_limit.get_ref();
    for (i, (o, v)) in obstacles.iter().zip(velocities).enumerate() {
        if *v == Vector2::zeros() {
            continue;
        }
        // The first time a vertex reaches the limit, s.
        let leaves = o
            .vertices()
            .iter()
            .flat_map(|p| [(p.x, v.x), (p.y, v.y)])
            .filter(|&(_, vc)| vc != 0.0)
            .map(|(c, vc)| (MAX_COORDINATE * vc.signum() - c) / vc)
            .fold(f64::INFINITY, f64::min);
        if leaves < t {
            let (field, span) = match raw.obstacles.get(i) {
                Some(ob) => (format!("obstacles[{i}].velocity"), Some(ob.span())),
                None => ("generator".to_string(), None),
            };
            return Err(src.err(
                &field,
                span,
                format!(
                    "obstacle {i} moving at [{}, {}] m/s crosses the coordinate limit \
                     {MAX_COORDINATE:e} m at t = {leaves:.3} s, before time_limit = {t} s",
                    v.x, v.y
                ),
            ));
        }
    }
    Ok(())
}

/// `name`: it names the output directory.
fn check_name(raw: &RawScenario, src: Source<'_>) -> Result<(), ScenarioError> {
    if raw.name.is_empty()
        || !raw
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(ScenarioError {
            file: src.file.into(),
            field: "name".into(),
            line: src.text.and_then(|t| {
                t.lines()
                    .position(|l| l.trim_start().starts_with("name"))
                    .map(|i| i + 1)
            }),
            message: "must be non-empty and use only ASCII letters, digits, `-` and `_` \
                      (it names the output directory)"
                .into(),
        });
    }
    Ok(())
}

/// `start`, `goal`, `time_limit`, `success_radius` and `stuck_window`.
fn check_scalars(raw: &RawScenario, src: Source<'_>) -> Result<(), ScenarioError> {
    let finite = |v: f64| v.is_finite();
    let st = raw.start.get_ref();
    if !(finite(st.x) && finite(st.y) && finite(st.heading)) {
        return Err(src.err(
            "start",
            Some(raw.start.span()),
            "x, y and heading must be finite".into(),
        ));
    }
    // An angle: the run adds its turns to it, and the controller refuses a
    // heading beyond 1e6 rad as a corrupted measurement.
    if st.heading.abs() > 2.0 * core::f64::consts::PI {
        return Err(src.err(
            "start",
            Some(raw.start.span()),
            format!("heading {} rad is not in [-2 pi, 2 pi]", st.heading),
        ));
    }
    let g = raw.goal.get_ref().0;
    if !(finite(g[0]) && finite(g[1])) {
        return Err(src.err("goal", Some(raw.goal.span()), "must be finite".into()));
    }
    if !positive(*raw.time_limit.get_ref()) || *raw.time_limit.get_ref() > 1e5 {
        return Err(src.err(
            "time_limit",
            Some(raw.time_limit.span()),
            "must be in (0, 1e5] s".into(),
        ));
    }
    if !positive(*raw.success_radius.get_ref()) {
        return Err(src.err(
            "success_radius",
            Some(raw.success_radius.span()),
            "must be finite and > 0".into(),
        ));
    }
    let sw = *raw.stuck_window.get_ref();
    if !(sw.is_finite() && sw >= 0.0) {
        return Err(src.err(
            "stuck_window",
            Some(raw.stuck_window.span()),
            "must be finite and >= 0 (0 disables)".into(),
        ));
    }
    Ok(())
}

/// Finite and > 0.
fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// The settings tables of the rooms below: `[rrt_star]`, `[lidar]`,
/// `[disturbance]`, `[robot]`.
fn check_settings(raw: &RawScenario, src: Source<'_>) -> Result<(), ScenarioError> {
    let checks = [
        ("rrt_star", raw.rrt_star.get_ref().validate()),
        ("lidar", raw.lidar.get_ref().validate()),
        ("disturbance", raw.disturbance.get_ref().validate()),
        ("robot", raw.robot.get_ref().validate()),
    ];
    for (table, check) in checks {
        if let Err(e) = check {
            return Err(src.table_err(table, e.field, e.requirement));
        }
    }
    Ok(())
}

/// With `perception = "lidar"`, the `[lidar.map]` settings under which the
/// map's frontier holds the robot (docs/safety.md, "The map's edge"; the
/// bounds in docs/cli-errors.md). `m` below is the barrier margin, the
/// distance the controller keeps the CoM from every piece
/// ([`Config::barrier_margin`]: body radius, `delta` and the arc between
/// step ends), and `r` the cell side:
///
/// * `padding >= m + 2 r`: the first box (start and goal grown by `padding`)
///   holds the start and the goal with the box's outermost ring, never
///   cleared, at least `m` and a cell away, so the robot starts inside a
///   frontier it cannot cross. A box that cannot grow (`grow = false`, or a
///   `max_cells` that refuses the growth) is that box for the whole run; with
///   `padding = 0` and start and goal on one row the map is one row of ring
///   cells, with no frontier at all, and the robot walked through a wall the
///   LiDAR saw.
/// * `unknown_radius >= m + 2 r`: a frontier cell is handed to the controller
///   before the CoM is within `m` of it (0, "never", turns the frontier off).
/// * `resolution <=` [`super::limits::max_map_cell`]`(m)`.
fn check_map_holds_robot(
    raw: &RawScenario,
    config: &Config,
    src: Source<'_>,
) -> Result<(), ScenarioError> {
    if *raw.perception.get_ref() != crate::sense::Perception::Lidar {
        return Ok(());
    }
    let map = &raw.lidar.get_ref().map;
    let m = config.barrier_margin();
    let r = map.resolution;
    let need = m + 2.0 * r;
    let why = |what: &str, got: f64| {
        format!(
            "{got} m is less than the {need:.4} m the frontier needs to hold the robot ({what}: \
             the barrier margin {m:.4} m (body radius, delta, the CoM's arc) plus two cells \
             of {r} m)"
        )
    };
    let max_cell = super::limits::max_map_cell(m);
    if r > max_cell {
        return Err(src.table_err(
            "lidar",
            "map.resolution",
            format!(
                "{r} m is above the {max_cell:.4} m a map cell may have for the safety \
                 promise with a barrier margin of {m:.4} m (docs/cli-errors.md)"
            ),
        ));
    }
    if map.padding < need {
        return Err(src.table_err(
            "lidar",
            "map.padding",
            why("the first box's edge", map.padding),
        ));
    }
    if map.unknown_radius < need {
        return Err(src.table_err(
            "lidar",
            "map.unknown_radius",
            why("the frontier handed to the controller", map.unknown_radius),
        ));
    }
    Ok(())
}

/// The controller's configuration: the defaults, the `[controller]` table's
/// overrides, then the robot's; checked field by field and as a whole (the
/// controller's own checks, at load time rather than mid-run). Returns the
/// configuration, the overrides and the robot.
fn controller_config(
    raw: &RawScenario,
    src: Source<'_>,
) -> Result<(Config, ControllerOverrides, RobotParams), ScenarioError> {
    let robot = raw.robot.get_ref().clone();
    let overrides = raw.controller.get_ref().clone();
    // On the map of grid cells, walking to a planned path's subgoals, the
    // half-planes at vertices are turned (`Config::turn_vertex_normals`,
    // docs/safety.md) unless the file says.
    let base = Config {
        turn_vertex_normals: super::plans_on_map(*raw.planner.get_ref(), *raw.perception.get_ref()),
        ..Config::default()
    };
    let config = robot.apply(overrides.apply(base));
    if let Err(e) = config.validate() {
        return Err(src.table_err("controller", e.field, e.requirement.into()));
    }
    // The controller's own checks of the combination (e.g. the step map of
    // gravity, com_height and step_duration).
    if let Err(e) = ldcbf_controller::RobotController::new(config) {
        let beta_t = (config.gravity / config.com_height).sqrt() * config.step_duration;
        return Err(src.table_err(
            "controller",
            e.field,
            format!(
                "{} (with gravity {} m/s^2, com_height {} m, step_duration {} s: beta T = {beta_t:.3e})",
                e.requirement, config.gravity, config.com_height, config.step_duration
            ),
        ));
    }
    if overrides.foot_clearance.is_some() && !robot.keep_feet_clear {
        return Err(src.err(
            "controller.foot_clearance",
            Some(raw.controller.span()),
            "sets the feet's extra clearance, but robot.keep_feet_clear = false turns the foot rows off"
                .into(),
        ));
    }
    Ok((config, overrides, robot))
}

/// The file's `[[obstacles]]`: their polygons and velocities, m and m/s.
fn file_obstacles(
    raw: &RawScenario,
    src: Source<'_>,
) -> Result<(Vec<Polygon>, Vec<Vector2<f64>>), ScenarioError> {
    let mut obstacles = Vec::with_capacity(raw.obstacles.len());
    let mut velocities = Vec::with_capacity(raw.obstacles.len());
    for (i, ob) in raw.obstacles.iter().enumerate() {
        obstacles.push(obstacle_polygon(i, ob, src)?);
        velocities.push(match &ob.get_ref().velocity {
            None => Vector2::zeros(),
            Some(v) => parse_velocity(v.get_ref())
                .map_err(|m| src.err(&format!("obstacles[{i}].velocity"), Some(v.span()), m))?,
        });
    }
    Ok((obstacles, velocities))
}

/// The polygon of `obstacles[i]`: its `vertices` (or their hull) or a
/// `regular` polygon, convex.
fn obstacle_polygon(
    i: usize,
    ob: &Spanned<RawObstacle>,
    src: Source<'_>,
) -> Result<Polygon, ScenarioError> {
    let field = format!("obstacles[{i}]");
    let span = Some(ob.span());
    let o = ob.get_ref();
    let (poly, field, span) = match (&o.vertices, &o.regular) {
        (Some(_), Some(_)) => {
            return Err(src.err(
                &field,
                span,
                "give `vertices` or `regular`, not both".into(),
            ));
        }
        (None, None) => {
            return Err(src.err(&field, span, "needs `vertices` or `regular`".into()));
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
                return Err(src.err(
                    &format!("{f}.sides"),
                    Some(rs.span()),
                    format!("must be in 3..={MAX_VERTICES}"),
                ));
            }
            if !(positive(r.radius)
                && r.center.0.iter().all(|c| c.is_finite())
                && r.rotation.is_finite())
            {
                return Err(src.err(
                    &f,
                    Some(rs.span()),
                    "center and rotation must be finite, radius > 0".into(),
                ));
            }
            let poly = Polygon::new(&regular_polygon(r.center.0, r.radius, r.sides, r.rotation));
            (poly, f, Some(rs.span()))
        }
    };
    poly.map_err(|e| {
        let hint = if matches!(e, ldcbf_controller::GeometryError::NotConvex) {
            " (set `hull = true` to use the convex hull of the points)"
        } else {
            ""
        };
        src.err(&field, span, format!("{e}{hint}"))
    })
}

/// How the obstacles of a scenario are named in messages: the first
/// `n_file` are the file's `obstacles[i]`, those from `people_from` on are
/// `people[j]`, the others generated with `seed`.
struct Names {
    n_file: usize,
    people_from: usize,
    seed: u64,
}

impl Names {
    fn of(&self, i: usize) -> String {
        if i < self.n_file {
            format!("obstacles[{i}]")
        } else if i >= self.people_from {
            format!("people[{}]", i - self.people_from)
        } else {
            format!(
                "generated obstacle {} (seed {})",
                i - self.n_file,
                self.seed
            )
        }
    }
}

/// The file's `[[people]]`, checked (the error names `people[i].field`).
fn file_people(raw: &RawScenario, src: Source<'_>) -> Result<Vec<Person>, ScenarioError> {
    if raw.people.len() > MAX_PEOPLE {
        return Err(src.err(
            "people",
            raw.people.first().map(|p| p.span()),
            format!("{} people; at most {MAX_PEOPLE}", raw.people.len()),
        ));
    }
    let mut out = Vec::with_capacity(raw.people.len());
    for (i, rp) in raw.people.iter().enumerate() {
        let r = rp.get_ref();
        let p = Person {
            start: Vector2::new(r.start.0[0], r.start.0[1]),
            goal: Vector2::new(r.goal.0[0], r.goal.0[1]),
            speed: r.speed,
            radius: r.radius,
            policy: r.policy,
            sees_robot: r.visible_robot,
            group: r.group,
            stops: r.stops.iter().map(|s| s.0).collect(),
        };
        p.validate().map_err(|e| {
            src.err(
                &format!("people[{i}].{}", e.field),
                Some(rp.span()),
                e.requirement,
            )
        })?;
        out.push(p);
    }
    Ok(out)
}

/// Impossible scenarios: the body (`robot.body_radius`) must fit at the start
/// and at the goal. `ends` are `(field, position, span)`.
fn check_room_to_stand(
    ends: &[(&str, Vector2<f64>, Range<usize>)],
    obstacles: &[Polygon],
    names: &Names,
    robot: &RobotParams,
    src: Source<'_>,
) -> Result<(), ScenarioError> {
    for (what, p, span) in ends {
        if let Some((i, d)) = obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| (i, closest_point_point_polygon(p, o).signed_distance))
            .find(|&(_, d)| d <= robot.body_radius)
        {
            let name = names.of(i);
            let how = if d <= 0.0 {
                format!("is inside {name} ({:.3} m deep)", -d)
            } else {
                format!(
                    "is {d:.3} m from {name}, within the robot's body radius {} m (robot.body_radius)",
                    robot.body_radius
                )
            };
            return Err(src.err(
                what,
                Some(span.clone()),
                format!("{how}: the robot cannot stand there"),
            ));
        }
    }
    Ok(())
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
