//! Scenario files: TOML under `scenarios/`, their validation, `--set`
//! overrides, and the seeded `random` family. The room above `world`, `sense`,
//! `plan` and `plant`, whose settings (`[robot]`, `[lidar]`, `[rrt_star]`,
//! `[disturbance]`) it reads; below the closed loop.
//!
//! # File format
//!
//! All coordinates are in the world frame W, metres; angles in radians.
//!
//! ```toml
//! name = "simple"                      # required: letters, digits, - and _
//! description = "one line for `list`"  # optional
//! note = "free text: overrides and why" # optional
//! start = { x = 0.0, y = 0.0, heading = 0.0 }  # heading optional (0), in [-2 pi, 2 pi]
//! stance = "left"          # initial stance foot, "left" (default) or "right"
//! goal = [5.0, 5.0]
//! time_limit = 120.0       # s of simulated time (default 120)
//! success_radius = 0.15    # m, goal reached when |p - goal| <= this (default 0.15, docs/maths.md §4)
//! stuck_window = 30.0      # s: stop as "stuck" when the best distance to the goal
//!                          # has not improved by 5 cm for this long; 0 disables (default 30)
//!                          # (with a planner: no 5 cm decrease of the remaining path length)
//! planner = "none"         # "none" (walk to the goal) or "rrt_star" (subgoals, docs/maths.md §5)
//! perception = "known"     # "known" (true polygons) or "lidar" (LiDAR + DBSCAN, docs/maths.md §6)
//! seed = 0                 # seed of the generator, the planner and the LiDAR noise
//!                          # (overridden by --seed)
//!
//! [controller]             # overrides of ldcbf_controller::Config fields
//! delta = 0.3
//! foot_clearance = 0.02    # m the feet keep beyond their footprint (default 0)
//!
//! [robot]                  # optional: the body and feet (crate::world::robot::RobotParams)
//! body_radius = 0.25       # m, body disk around the CoM (0 = a point CoM)
//! foot_length = 0.22       # m, footprint along the heading
//! foot_width = 0.10        # m, footprint across the heading
//! keep_feet_clear = true   # foot rows on (false = the paper's QP, no foot rows)
//!
//! [[obstacles]]            # a convex polygon, vertices in either order ...
//! vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]
//!
//! [[obstacles]]            # ... or the convex hull of a point set ...
//! vertices = [[1.0, 1.5], [2.5, 2.5], [3.5, 3.5], [3.0, 5.0]]
//! hull = true
//!
//! [[obstacles]]            # ... or a regular polygon (circle approximation)
//! regular = { center = [4.0, 2.0], radius = 1.0, sides = 20, rotation = 0.0 }
//! velocity = [0.0, -0.5]   # any obstacle: constant velocity, m/s, world frame
//!                          # (default at rest; speed <= 5 m/s; crate::world::moving)
//!
//! [[people]]               # a person who walks to a goal and reacts (crate::world::crowd)
//! start = [6.0, -3.0]      # m, body centre at t = 0
//! goal = [6.0, 3.0]        # m
//! speed = 0.5              # m/s, preferred speed (default 0.6, the robot's nominal speed)
//! radius = 0.3             # m (default 0.3, CrowdNav's)
//! policy = "orca"          # "orca" (default), "social_force" or "constant_velocity"
//! visible_robot = true     # the person sees the robot and avoids it (default true)
//! group = 1                # optional: people of one group walk abreast
//! stops = [[2.0, 4.0]]     # optional: intervals [t0, t1) of simulated time, s, standing
//!
//! [generator]              # optional: adds seeded random convex obstacles
//! kind = "random_polygons" # or a family (crate::world::families: corridor, doorway,
//!                          # cup, wall_start, clutter, thin, the people families, and
//!                          # those of crate::world::crowd::families), which also draws
//!                          # the start, heading and goal (the file's are replaced)
//! count = 8
//! min_gap = 0.0            # optional: minimum distance between two polygons, m
//!
//! [rrt_star]               # optional: planner settings (crate::plan::RrtParams)
//! iterations = 3000
//! margin = 0.4
//!
//! [lidar]                  # optional: perception settings (crate::sense::LidarParams)
//! range = 3.0
//! min_points = 3
//!
//! [disturbance]            # optional, all off by default (crate::plant::disturbance)
//! seed = 0                 # seed of the foot-error and noise draws (with `seed` above)
//! push_time = 2.0          # s, first push (none when absent)
//! push_period = 0.0        # s between pushes (0 = one push; else >= 0.01)
//! push_forward = 0.0       # m/s, CoM velocity change along the heading (body frame)
//! push_lateral = 0.3       # m/s, CoM velocity change to the left of the heading
//! push_alternate = false   # reverse every second push
//! plant_com_height = 1.0   # m, the plant's true CoM height (default: controller.com_height)
//! foot_sigma = 0.0         # m, std. dev. of the landing error per world axis
//! noise_position = 0.0     # m, std. dev. of the measured CoM position per world axis
//! noise_velocity = 0.0     # m/s, std. dev. of the measured CoM velocity per world axis
//! noise_heading = 0.0      # rad, std. dev. of the measured heading
//! velocity_error = 0.0     # m/s, known velocities handed over this wrong (and this uncertain)
//! ```
//!
//! `--set disturbance.<field>=value` sets one of them (e.g.
//! `--set disturbance.push_time=2.0 --set disturbance.push_lateral=0.3`).
//!
//! `planner = "rrt_star"` with `perception = "lidar"` plans with A* on the
//! map seen so far and replans as it grows (`crate::plan::on_map`); the map's
//! settings are the `[lidar.map]` table (`crate::sense::MapParams`).
//!
//! A scenario the robot cannot stand in is an error: a start or goal inside an
//! obstacle, or within `robot.body_radius` of one (moving obstacles at their
//! t = 0 positions), names the field (`start`, `goal`) and the obstacle
//! (`obstacles[i]`, or the generated one and the seed).
//!
//! Without `hull = true` a vertex list must already be a convex polygon
//! ([`ConvexPolygon::new`](ldcbf_controller::ConvexPolygon::new)); a non-convex list is an error naming the obstacle.
//! Unknown keys are errors. Every error names the file, the field and, when it
//! is known, the line ([`ScenarioError`]).
//!
//! # Initial condition
//!
//! The robot starts at rest: CoM at `start` with zero velocity, the stance foot
//! (`stance`) directly under the CoM, at the start of a step, turning rate 0
//! (an equilibrium of the LIP; the first MPC cycle starts the walk).
//!
//! # Loading by name
//!
//! `run maze` loads `scenarios/maze.toml` from the current directory, or from the
//! repository's `scenarios/` (the directory next to this crate, fixed at build
//! time) when the current directory has none. An argument containing a `/` or
//! ending in `.toml` is a path.

use std::path::{Path, PathBuf};

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Config, Side};

use crate::plan::{Planner, RrtParams};
use crate::plant::disturbance::DisturbanceParams;
use crate::sense::{LidarParams, Perception};
use crate::world::Polygon;
use crate::world::random::{RandomParams, random_obstacles};
use crate::world::robot::RobotParams;

pub mod limits;
mod overrides;
mod parse;
#[cfg(test)]
mod people_tests;
#[cfg(test)]
mod tests;
mod validate;
#[cfg(test)]
mod velocity_tests;

pub use overrides::{
    ControllerOverrides, ROBOT_FIELDS, SideSpec, config_map, controller_fields, overrides_map,
};
use parse::{RawScenario, apply_set, toml_error};
use validate::validate;

/// Whether `planner` with `perception` plans on the perceived map
/// ([`crate::plan::on_map`]: RRT* with LiDAR, the occupancy map's mode).
pub fn plans_on_map(planner: crate::plan::Planner, perception: crate::sense::Perception) -> bool {
    planner == crate::plan::Planner::RrtStar && perception == crate::sense::Perception::Lidar
}

/// The paper's random test as a ready scenario: start (0, 0) heading 0, goal
/// (10, 10), [`RandomParams::default`] obstacles from `seed`, default controller.
/// For batch evaluations that do not want to read `scenarios/random.toml`.
pub fn random_scenario(seed: u64) -> Scenario {
    let params = RandomParams::default();
    let (start, goal) = (Vector2::new(0.0, 0.0), Vector2::new(10.0, 10.0));
    let obstacles =
        random_obstacles(seed, &params, start, goal).expect("default generator always places");
    Scenario {
        name: "random".into(),
        description: "8 random convex polygons, start (0,0), goal (10,10)".into(),
        note: String::new(),
        source: "<builtin random>".into(),
        start,
        start_heading: 0.0,
        stance: Side::Left,
        goal,
        time_limit: 120.0,
        success_radius: 0.15,
        stuck_window: 30.0,
        planner: Planner::None,
        perception: Perception::Known,
        seed,
        generator: Some(params),
        controller: ControllerOverrides::default(),
        config: RobotParams::default().apply(Config::default()),
        rrt: RrtParams::default(),
        lidar: LidarParams::default(),
        disturbance: DisturbanceParams::default(),
        robot: RobotParams::default(),
        velocities: vec![Vector2::zeros(); obstacles.len()],
        obstacles,
        people: Vec::new(),
    }
}

/// A validated scenario, ready to simulate.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Name (used for the default output directory).
    pub name: String,
    /// One-line description.
    pub description: String,
    /// Free-text note (overrides and their reasons).
    pub note: String,
    /// Where it came from (file path, or `<builtin random>`).
    pub source: String,
    /// Start CoM position, m.
    pub start: Vector2<f64>,
    /// Start heading, rad.
    pub start_heading: f64,
    /// Initial stance foot.
    pub stance: Side,
    /// Goal, m.
    pub goal: Vector2<f64>,
    /// Simulated-time limit, s.
    pub time_limit: f64,
    /// Goal radius, m.
    pub success_radius: f64,
    /// Stuck detection window, s (0 = off): the run ends as stuck when the
    /// remaining path length (the distance to the goal without a planner) has
    /// not decreased by 5 cm for this long.
    pub stuck_window: f64,
    /// Global planner.
    pub planner: Planner,
    /// What the controller knows of the obstacles.
    pub perception: Perception,
    /// Seed of the generator, of the RRT* samples and of the LiDAR noise.
    pub seed: u64,
    /// The generator parameters, when the scenario has random obstacles.
    pub generator: Option<RandomParams>,
    /// The overrides as given (for the summary).
    pub controller: ControllerOverrides,
    /// The validated controller configuration (defaults + overrides).
    pub config: Config,
    /// Planner settings (the `[rrt_star]` table; used with `planner = "rrt_star"`).
    pub rrt: RrtParams,
    /// LiDAR and clustering settings (the `[lidar]` table; used with
    /// `perception = "lidar"`).
    pub lidar: LidarParams,
    /// Disturbances of the plant and of the measured state (the `[disturbance]`
    /// table; all off by default, [`crate::plant::disturbance`]).
    pub disturbance: DisturbanceParams,
    /// The robot's body and feet (the `[robot]` table, [`crate::world::robot`]);
    /// already applied to `config`.
    pub robot: RobotParams,
    /// Obstacles, world frame: the file's, then the generated ones (the TRUE map
    /// at t = 0).
    pub obstacles: Vec<Polygon>,
    /// Each obstacle's constant velocity, m/s, world frame (zero at rest), one
    /// per obstacle ([`crate::world::moving`]).
    pub velocities: Vec<Vector2<f64>>,
    /// The people who react ([`crate::world::crowd`]): the last
    /// `people.len()` entries of `obstacles` are their bodies at their
    /// starts, with `velocities` toward their goals at their speeds; the
    /// closed loop steps them ([`crate::world::crowd::Crowd`]).
    pub people: Vec<crate::world::crowd::Person>,
}

impl Scenario {
    /// Index in `obstacles` of the first person who reacts.
    pub fn people_from(&self) -> usize {
        self.obstacles.len() - self.people.len()
    }
}

/// A scenario that cannot be used: which file, which field, which line, why.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioError {
    /// The file (path as given), or `<--set>` for an override.
    pub file: String,
    /// Dotted path of the field, e.g. `obstacles[3]` or `controller.gamma`.
    pub field: String,
    /// 1-based line in the file, when known.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl core::fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.field.starts_with('(') {
            return match self.line {
                Some(l) => write!(f, "{}:{}: {}", self.file, l, self.message),
                None => write!(f, "{}: {}", self.file, self.message),
            };
        }
        match self.line {
            Some(l) => write!(
                f,
                "{}:{}: field `{}`: {}",
                self.file, l, self.field, self.message
            ),
            None => write!(f, "{}: field `{}`: {}", self.file, self.field, self.message),
        }
    }
}

impl std::error::Error for ScenarioError {}

// ---------------------------------------------------------------- loading

/// Options applied while loading a scenario.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Seed for the generator (overrides the file's `seed`).
    pub seed: Option<u64>,
    /// `--set key=value` overrides, in order. `key` is a dotted path into the
    /// file (`time_limit`, `controller.delta`, `goal`); a bare controller field
    /// name (`delta`) means `controller.<name>`. `value` is a TOML value
    /// (`0.3`, `[1, 2]`, `"right"`, `true`); anything that does not parse as one
    /// is taken as a string.
    pub sets: Vec<(String, String)>,
}

impl LoadOptions {
    /// No seed override and the `--set` pairs `sets`, in order (e.g.
    /// `&[("planner", "\"none\"")]`).
    pub fn with_sets(sets: &[(&str, &str)]) -> LoadOptions {
        LoadOptions {
            seed: None,
            sets: sets
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
        }
    }
}

/// The directory of the shipped scenarios: `./scenarios` when it exists,
/// otherwise the repository's `scenarios/` next to this crate.
pub fn scenario_dir() -> PathBuf {
    let local = PathBuf::from("scenarios");
    if local.is_dir() {
        return local;
    }
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    repo.canonicalize().unwrap_or(repo)
}

/// Resolves a scenario argument: a path (contains `/` or ends in `.toml`), or a
/// name looked up as `<scenario_dir()>/<name>.toml`.
pub fn resolve(spec: &str) -> Result<PathBuf, ScenarioError> {
    let is_path = spec.contains('/') || spec.contains('\\') || spec.ends_with(".toml");
    let path = if is_path {
        PathBuf::from(spec)
    } else {
        scenario_dir().join(format!("{spec}.toml"))
    };
    if path.is_file() {
        Ok(path)
    } else {
        let known: Vec<String> = list().into_iter().map(|(n, _, _)| n).collect();
        Err(ScenarioError {
            file: path.display().to_string(),
            field: "(file)".into(),
            line: None,
            message: if path.is_dir() {
                "is a directory, not a scenario file".into()
            } else if path.exists() {
                "is not a regular file (a device, a FIFO or a socket), not a scenario file".into()
            } else if is_path {
                "no such file".into()
            } else {
                format!(
                    "no scenario named {spec:?} (known: {})",
                    if known.is_empty() {
                        "none".into()
                    } else {
                        known.join(", ")
                    }
                )
            },
        })
    }
}

/// The shipped scenarios: `(name, description, path)`, sorted by name. A file
/// that does not parse is listed with its error as the description.
pub fn list() -> Vec<(String, String, PathBuf)> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(scenario_dir()) else {
        return out;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.extension().and_then(|s| s.to_str()) != Some("toml") {
            continue;
        }
        let name = p
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("?")
            .to_string();
        let desc = match load_path(&p, &LoadOptions::default()) {
            Ok(s) => s.description,
            Err(e) => format!("(invalid: {e})"),
        };
        out.push((name, desc, p));
    }
    out.sort();
    out
}

/// Loads a scenario by name or path ([`resolve`]) and validates it.
pub fn load(spec: &str, opts: &LoadOptions) -> Result<Scenario, ScenarioError> {
    load_path(&resolve(spec)?, opts)
}

/// Loads and validates the scenario file at `path`.
pub fn load_path(path: &Path, opts: &LoadOptions) -> Result<Scenario, ScenarioError> {
    let file = path.display().to_string();
    let fail = |message: String| ScenarioError {
        file: file.clone(),
        field: "(file)".into(),
        line: None,
        message,
    };
    let bytes = limits::read_regular_file(path, limits::MAX_FILE_BYTES).map_err(|e| {
        fail(match e.kind() {
            std::io::ErrorKind::InvalidInput => e.to_string(),
            _ => format!("cannot read: {e}"),
        })
    })?;
    let text = String::from_utf8(bytes)
        .map_err(|_| fail("cannot read: stream did not contain valid UTF-8".into()))?;
    parse_str(&text, &file, opts)
}

/// [`limits::check_table`] as a [`ScenarioError`] of `file`.
fn check_limits(table: &toml::Table, file: &str) -> Result<(), ScenarioError> {
    limits::check_table(table).map_err(|(field, message)| ScenarioError {
        file: file.into(),
        field,
        line: None,
        message,
    })
}

/// Parses and validates scenario text; `file` names it in errors.
pub fn parse_str(text: &str, file: &str, opts: &LoadOptions) -> Result<Scenario, ScenarioError> {
    let mut table: toml::Table = toml::from_str(text).map_err(|e| toml_error(&e, text, file))?;
    check_limits(&table, file)?;
    let raw: RawScenario = toml::from_str(text).map_err(|e| toml_error(&e, text, file))?;
    let mut sc = validate(raw, Some(text), file, opts.seed)?;
    if !opts.sets.is_empty() {
        for (k, v) in &opts.sets {
            apply_set(&mut table, k, v).map_err(|message| ScenarioError {
                file: "--set".into(),
                field: limits::field_name(k),
                line: None,
                message,
            })?;
        }
        check_limits(&table, "--set")?;
        let patched = toml::to_string(&table).map_err(|e| ScenarioError {
            file: "--set".into(),
            field: "(all)".into(),
            line: None,
            message: e.to_string(),
        })?;
        let label = format!("{file} (with --set)");
        let raw: RawScenario = toml::from_str(&patched).map_err(|e| {
            let mut err = toml_error(&e, &patched, &label);
            err.line = None;
            err
        })?;
        sc = validate(raw, None, &label, opts.seed)?;
    }
    sc.source = file.to_string();
    Ok(sc)
}
