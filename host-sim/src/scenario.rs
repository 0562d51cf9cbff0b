//! Scenario files: TOML under `scenarios/`, their validation, `--set`
//! overrides, and the seeded `random` family.
//!
//! # File format
//!
//! All coordinates are in the world frame W, metres; angles in radians.
//!
//! ```toml
//! name = "simple"                      # required: letters, digits, - and _
//! description = "one line for `list`"  # optional
//! note = "free text: overrides and why" # optional
//! start = { x = 0.0, y = 0.0, heading = 0.0 }  # heading optional (0)
//! stance = "left"          # initial stance foot, "left" (default) or "right"
//! goal = [5.0, 5.0]
//! time_limit = 120.0       # s of simulated time (default 120)
//! success_radius = 0.15    # m, goal reached when |p - goal| <= this (default 0.15, SPEC 4)
//! stuck_window = 30.0      # s: stop as "stuck" when the best distance to the goal
//!                          # has not improved by 5 cm for this long; 0 disables (default 30)
//!                          # (with a planner: no 5 cm decrease of the remaining path length)
//! planner = "none"         # "none" (walk to the goal) or "rrt_star" (subgoals, SPEC 5)
//! perception = "known"     # "known" (true polygons) or "lidar" (LiDAR + DBSCAN, SPEC 6)
//! seed = 0                 # seed of the generator, the planner and the LiDAR noise
//!                          # (overridden by --seed)
//!
//! [controller]             # overrides of ldcbf_controller::Config fields
//! delta = 0.3
//! foot_clearance = 0.02    # m the feet keep beyond their footprint (default 0)
//!
//! [robot]                  # optional: the body and feet (crate::robot::RobotParams)
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
//!
//! [generator]              # optional: adds seeded random convex obstacles
//! kind = "random_polygons" # or a family (crate::families: corridor, doorway,
//!                          # cup, wall_start, clutter, thin), which also draws
//!                          # the start, heading and goal (the file's are replaced)
//! count = 8
//! min_gap = 0.0            # optional: minimum distance between two polygons, m
//!
//! [rrt_star]               # optional: planner settings (crate::planner::RrtParams)
//! iterations = 3000
//! margin = 0.4
//!
//! [lidar]                  # optional: perception settings (crate::perception::LidarParams)
//! range = 3.0
//! min_points = 3
//!
//! [disturbance]            # optional, all off by default (crate::disturbance)
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
//! ```
//!
//! `--set disturbance.<field>=value` sets one of them (e.g.
//! `--set disturbance.push_time=2.0 --set disturbance.push_lateral=0.3`).
//!
//! `planner = "rrt_star"` needs a known map: it is refused together with
//! `perception = "lidar"` (planning on the perceived map is not implemented).
//!
//! A scenario the robot cannot stand in is an error: a start or goal inside an
//! obstacle, or within `robot.body_radius` of one, names the field (`start`,
//! `goal`) and the obstacle (`obstacles[i]`, or the generated one and the seed).
//!
//! Without `hull = true` a vertex list must already be a convex polygon
//! ([`ConvexPolygon::new`]); a non-convex list is an error naming the obstacle.
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

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Config, ConvexPolygon, Side, closest_point_point_polygon};
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::disturbance::DisturbanceParams;
use crate::perception::LidarParams;
use crate::planner::RrtParams;
use crate::robot::RobotParams;

/// Vertex capacity of scenario polygons.
pub const MAX_VERTICES: usize = 32;

/// The polygon type used by the simulator (world frame, metres).
pub type Polygon = ConvexPolygon<MAX_VERTICES>;

/// Global planner (SPEC 5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Planner {
    /// Walk straight to the goal (the MPC alone).
    #[default]
    None,
    /// RRT* on the known map; its path's nodes are subgoals ([`crate::planner`]).
    #[value(name = "rrt_star")]
    RrtStar,
}

impl Planner {
    /// The name used in files (`none`, `rrt_star`).
    pub fn name(self) -> &'static str {
        match self {
            Planner::None => "none",
            Planner::RrtStar => "rrt_star",
        }
    }
}

/// Obstacle perception (SPEC 6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Perception {
    /// The controller gets the true obstacle polygons.
    #[default]
    Known,
    /// The controller gets only the obstacles inferred from a simulated LiDAR
    /// by DBSCAN ([`crate::perception`]).
    Lidar,
}

impl Perception {
    /// The name used in files (`known`, `lidar`).
    pub fn name(self) -> &'static str {
        match self {
            Perception::Known => "known",
            Perception::Lidar => "lidar",
        }
    }
}

/// Foot side as written in a file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SideSpec {
    /// Left foot.
    #[default]
    Left,
    /// Right foot.
    Right,
}

impl From<SideSpec> for Side {
    fn from(s: SideSpec) -> Side {
        match s {
            SideSpec::Left => Side::Left,
            SideSpec::Right => Side::Right,
        }
    }
}

/// Overrides of [`Config`] fields (the `[controller]` table). Unset fields keep
/// the paper's defaults ([`Config::default`]). Units as in [`Config`].
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)] // one field per Config field, documented there
pub struct ControllerOverrides {
    pub gravity: Option<f64>,
    pub com_height: Option<f64>,
    pub step_duration: Option<f64>,
    pub vx_min: Option<f64>,
    pub vx_max: Option<f64>,
    pub vy_min: Option<f64>,
    pub vy_max: Option<f64>,
    pub l_max: Option<f64>,
    pub alpha: Option<f64>,
    pub omega_max: Option<f64>,
    pub gamma: Option<f64>,
    pub delta: Option<f64>,
    pub r_active: Option<f64>,
    pub foot_clearance: Option<f64>,
    pub heading_freeze_radius: Option<f64>,
    pub max_iter: Option<u32>,
    pub max_iter_cycle: Option<u32>,
    pub relax_bisections: Option<u32>,
    pub max_gait_relaxation: Option<f64>,
    /// `Config::capture_fraction`; 0 turns the capturability bound off.
    pub capture_fraction: Option<f64>,
    pub warm_start: Option<bool>,
    pub tol_primal: Option<f64>,
}

/// The robot's fields of [`Config`]: set in `[robot]`
/// ([`crate::robot::RobotParams`]), not in `[controller]`.
pub const ROBOT_FIELDS: [&str; 3] = ["body_radius", "foot_length", "foot_width"];

/// Names of the [`Config`] fields that `[controller]` (and `--set`) accept:
/// [`Config::FIELDS`] but the robot's.
pub fn controller_fields() -> impl Iterator<Item = &'static str> {
    Config::FIELDS
        .into_iter()
        .filter(|f| !ROBOT_FIELDS.contains(f))
}

impl ControllerOverrides {
    /// `base` with every set field replaced.
    pub fn apply(&self, base: Config) -> Config {
        let mut c = base;
        macro_rules! set {
            ($($f:ident),*) => { $( if let Some(v) = self.$f { c.$f = v; } )* };
        }
        set!(
            gravity,
            com_height,
            step_duration,
            vx_min,
            vx_max,
            vy_min,
            vy_max,
            l_max,
            alpha,
            omega_max,
            gamma,
            delta,
            r_active,
            heading_freeze_radius,
            max_iter,
            max_iter_cycle,
            relax_bisections,
            max_gait_relaxation,
            warm_start,
            tol_primal
        );
        if let Some(r) = self.capture_fraction {
            c.capture_fraction = (r != 0.0).then_some(r);
        }
        if self.foot_clearance.is_some() {
            c.foot_clearance = self.foot_clearance;
        }
        c
    }
}

/// Parameters of the seeded random-obstacle generator (the `[generator]` table;
/// the paper's random test by default: 8 convex polygons in the 10 m x 10 m
/// square, start and goal kept clear by 1 m).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RandomParams {
    /// Generator kind: `"random_polygons"` (the fields below), or a family of
    /// [`crate::families`] (`corridor`, `doorway`, `cup`, `wall_start`,
    /// `clutter`, `thin`), which draws the start, heading, goal and obstacles
    /// itself and ignores the other fields.
    #[serde(default = "default_kind")]
    pub kind: String,
    /// Number of polygons: at most [`MAX_COUNT`], or [`MAX_COUNT_WITH_GAP`]
    /// with `min_gap > 0` (each polygon is then checked against every earlier
    /// one).
    #[serde(default = "default_count")]
    pub count: usize,
    /// Lower-left corner of the area where centres are drawn, m.
    #[serde(default = "default_area_min")]
    pub area_min: [f64; 2],
    /// Upper-right corner of that area, m.
    #[serde(default = "default_area_max")]
    pub area_max: [f64; 2],
    /// Range of the circumradius `[min, max]`, m.
    #[serde(default = "default_radius")]
    pub radius: [f64; 2],
    /// Range of the number of sampled points `[min, max]` (the polygon is their hull).
    #[serde(default = "default_points")]
    pub points: [u32; 2],
    /// Minimum distance from the start and from the goal to every polygon, m.
    #[serde(default = "default_clearance")]
    pub clearance: f64,
    /// Minimum distance between two polygons, m (0 = they may touch or overlap,
    /// the paper's test). A polygon closer than this to an earlier one is drawn
    /// again; with 0 the generator draws exactly as before this field existed.
    #[serde(default)]
    pub min_gap: f64,
}

/// Largest [`RandomParams::count`] (large maps: `scenarios/large-map.toml`
/// draws 10,000 polygons in about 30 ms).
pub const MAX_COUNT: usize = 1_000_000;

/// Largest [`RandomParams::count`] with `min_gap > 0` (quadratic check).
pub const MAX_COUNT_WITH_GAP: usize = 1000;

fn default_kind() -> String {
    "random_polygons".into()
}
fn default_count() -> usize {
    8
}
fn default_area_min() -> [f64; 2] {
    [0.0, 0.0]
}
fn default_area_max() -> [f64; 2] {
    [10.0, 10.0]
}
fn default_radius() -> [f64; 2] {
    [0.3, 1.0]
}
fn default_points() -> [u32; 2] {
    [3, 8]
}
fn default_clearance() -> f64 {
    1.0
}

impl Default for RandomParams {
    fn default() -> Self {
        RandomParams {
            kind: default_kind(),
            count: default_count(),
            area_min: default_area_min(),
            area_max: default_area_max(),
            radius: default_radius(),
            points: default_points(),
            clearance: default_clearance(),
            min_gap: 0.0,
        }
    }
}

impl RandomParams {
    /// Checks the ranges; the error names the bad field.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if self.kind != "random_polygons"
            && !crate::families::FAMILIES.contains(&self.kind.as_str())
        {
            return Err((
                "kind",
                format!(
                    "unknown generator kind {:?} (\"random_polygons\" or a family: {})",
                    self.kind,
                    crate::families::FAMILIES.join(", ")
                ),
            ));
        }
        let fin = |a: &[f64]| a.iter().all(|v| v.is_finite());
        if !(fin(&self.area_min)
            && fin(&self.area_max)
            && self.area_min[0] < self.area_max[0]
            && self.area_min[1] < self.area_max[1])
        {
            return Err((
                "area_max",
                "area_min and area_max must be finite with area_min < area_max".into(),
            ));
        }
        if !(fin(&self.radius) && self.radius[0] > 0.0 && self.radius[0] <= self.radius[1]) {
            return Err(("radius", "must be [min, max] with 0 < min <= max".into()));
        }
        if !(self.points[0] >= 3
            && self.points[0] <= self.points[1]
            && self.points[1] as usize <= MAX_VERTICES)
        {
            return Err((
                "points",
                format!("must be [min, max] with 3 <= min <= max <= {MAX_VERTICES}"),
            ));
        }
        if !(self.clearance.is_finite() && self.clearance >= 0.0) {
            return Err(("clearance", "must be finite and >= 0".into()));
        }
        if !(self.min_gap.is_finite() && self.min_gap >= 0.0) {
            return Err(("min_gap", "must be finite and >= 0".into()));
        }
        if self.min_gap > 0.0 && self.count > MAX_COUNT_WITH_GAP {
            return Err((
                "count",
                format!("must be <= {MAX_COUNT_WITH_GAP} with min_gap > 0"),
            ));
        }
        if self.count > MAX_COUNT {
            return Err(("count", format!("must be <= {MAX_COUNT}")));
        }
        Ok(())
    }
}

/// Draws `params.count` random convex polygons with a ChaCha8 generator seeded by
/// `seed` (the same seed gives the same polygons on every platform). Each polygon
/// is the convex hull of `points` random points at random angles and radii in
/// `[0.5, 1] * r` around a uniform centre in the area, `r` uniform in `radius`;
/// a polygon closer than `clearance` to `start` or `goal` is drawn again.
pub fn random_obstacles(
    seed: u64,
    params: &RandomParams,
    start: Vector2<f64>,
    goal: Vector2<f64>,
) -> Result<Vec<Polygon>, String> {
    params.validate().map_err(|(f, m)| format!("{f}: {m}"))?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut unif = |lo: f64, hi: f64| {
        let u = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        lo + (hi - lo) * u
    };
    let mut out = Vec::with_capacity(params.count);
    let mut attempts = 0usize;
    while out.len() < params.count {
        attempts += 1;
        if attempts > 1000 * params.count.max(1) {
            return Err(format!(
                "could not place {} polygons clear of start and goal after {} attempts",
                params.count,
                attempts - 1
            ));
        }
        let cx = unif(params.area_min[0], params.area_max[0]);
        let cy = unif(params.area_min[1], params.area_max[1]);
        let r = unif(params.radius[0], params.radius[1]);
        let n = unif(
            f64::from(params.points[0]),
            f64::from(params.points[1]) + 1.0,
        )
        .floor()
        .min(f64::from(params.points[1])) as usize;
        let mut pts = Vec::with_capacity(n);
        for _ in 0..n {
            let a = unif(0.0, core::f64::consts::TAU);
            let rr = r * unif(0.5, 1.0);
            pts.push([cx + rr * a.cos(), cy + rr * a.sin()]);
        }
        let Ok(poly) = Polygon::hull(&pts) else {
            continue;
        };
        let clear = |p: Vector2<f64>| {
            closest_point_point_polygon(&p, &poly).signed_distance >= params.clearance
        };
        if clear(start)
            && clear(goal)
            && (params.min_gap <= 0.0
                || out
                    .iter()
                    .all(|o| polygon_distance(o, &poly) >= params.min_gap))
        {
            out.push(poly);
        }
    }
    Ok(out)
}

/// Distance between two convex polygons, m (0 when they touch or overlap): the
/// smallest vertex-to-polygon distance either way, or 0 if two edges cross.
pub fn polygon_distance(a: &Polygon, b: &Polygon) -> f64 {
    let cross = |o: Vector2<f64>, p: Vector2<f64>, q: Vector2<f64>| {
        (p.x - o.x) * (q.y - o.y) - (p.y - o.y) * (q.x - o.x)
    };
    let (va, vb) = (a.vertices(), b.vertices());
    for i in 0..va.len() {
        let (p1, p2) = (va[i], va[(i + 1) % va.len()]);
        for j in 0..vb.len() {
            let (q1, q2) = (vb[j], vb[(j + 1) % vb.len()]);
            let d1 = cross(p1, p2, q1);
            let d2 = cross(p1, p2, q2);
            let d3 = cross(q1, q2, p1);
            let d4 = cross(q1, q2, p2);
            if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 {
                return 0.0;
            }
        }
    }
    let d = |v: &[Vector2<f64>], p: &Polygon| {
        v.iter()
            .map(|q| closest_point_point_polygon(q, p).signed_distance)
            .fold(f64::INFINITY, f64::min)
    };
    d(va, b).min(d(vb, a)).max(0.0)
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
        obstacles,
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
    /// table; all off by default, [`crate::disturbance`]).
    pub disturbance: DisturbanceParams,
    /// The robot's body and feet (the `[robot]` table, [`crate::robot`]);
    /// already applied to `config`.
    pub robot: RobotParams,
    /// Obstacles, world frame: the file's, then the generated ones (the TRUE map).
    pub obstacles: Vec<Polygon>,
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

// ---------------------------------------------------------------- raw file types

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    note: String,
    start: Spanned<RawStart>,
    #[serde(default)]
    stance: SideSpec,
    goal: Spanned<[f64; 2]>,
    #[serde(default = "default_time_limit")]
    time_limit: Spanned<f64>,
    #[serde(default = "default_success_radius")]
    success_radius: Spanned<f64>,
    #[serde(default = "default_stuck_window")]
    stuck_window: Spanned<f64>,
    #[serde(default = "spanned_default")]
    planner: Spanned<Planner>,
    #[serde(default = "spanned_default")]
    perception: Spanned<Perception>,
    #[serde(default)]
    seed: u64,
    #[serde(default = "spanned_default")]
    controller: Spanned<ControllerOverrides>,
    #[serde(default)]
    obstacles: Vec<Spanned<RawObstacle>>,
    #[serde(default)]
    generator: Option<Spanned<RandomParams>>,
    #[serde(default = "spanned_default")]
    rrt_star: Spanned<RrtParams>,
    #[serde(default = "spanned_default")]
    lidar: Spanned<LidarParams>,
    #[serde(default = "spanned_default")]
    disturbance: Spanned<DisturbanceParams>,
    #[serde(default = "spanned_default")]
    robot: Spanned<RobotParams>,
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
struct RawStart {
    x: f64,
    y: f64,
    #[serde(default)]
    heading: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObstacle {
    #[serde(default)]
    vertices: Option<Spanned<Vec<[f64; 2]>>>,
    #[serde(default)]
    regular: Option<Spanned<RegularSpec>>,
    #[serde(default)]
    hull: bool,
    /// Optional label, for humans.
    #[serde(default)]
    #[allow(dead_code)]
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RegularSpec {
    center: [f64; 2],
    radius: f64,
    sides: u32,
    #[serde(default)]
    rotation: f64,
}

/// Vertices of a regular polygon: vertex `i` at angle `rotation + 2 pi i / sides`
/// around `center`, at distance `radius` (m, rad).
pub fn regular_polygon(center: [f64; 2], radius: f64, sides: u32, rotation: f64) -> Vec<[f64; 2]> {
    (0..sides)
        .map(|i| {
            let a = rotation + core::f64::consts::TAU * f64::from(i) / f64::from(sides);
            [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
        })
        .collect()
}

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
    let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
        file: file.clone(),
        field: "(file)".into(),
        line: None,
        message: format!("cannot read: {e}"),
    })?;
    parse_str(&text, &file, opts)
}

/// Parses and validates scenario text; `file` names it in errors.
pub fn parse_str(text: &str, file: &str, opts: &LoadOptions) -> Result<Scenario, ScenarioError> {
    let raw: RawScenario = toml::from_str(text).map_err(|e| toml_error(&e, text, file))?;
    let mut sc = validate(raw, Some(text), file, opts.seed)?;
    if !opts.sets.is_empty() {
        let mut table: toml::Table =
            toml::from_str(text).map_err(|e| toml_error(&e, text, file))?;
        for (k, v) in &opts.sets {
            apply_set(&mut table, k, v).map_err(|message| ScenarioError {
                file: "--set".into(),
                field: k.clone(),
                line: None,
                message,
            })?;
        }
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

/// Applies one `--set key=value` to the parsed table.
fn apply_set(table: &mut toml::Table, key: &str, value: &str) -> Result<(), String> {
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
        "generator",
        "rrt_star",
        "lidar",
        "disturbance",
        "robot",
    ];
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
    let parsed: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {value}")) {
        Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(value.into())),
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

fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Converts a TOML/serde error into a [`ScenarioError`] with the line and the
/// dotted path of the innermost key whose value contains the error.
fn toml_error(e: &toml::de::Error, text: &str, file: &str) -> ScenarioError {
    let span = e.span();
    let line = span.as_ref().map(|s| line_of(text, s.start));
    let field = span
        .as_ref()
        .and_then(|s| path_at(text, s.start).or_else(|| key_near(text, s.start)))
        .unwrap_or_else(|| "(document)".into());
    ScenarioError {
        file: file.into(),
        field,
        line,
        message: e.message().trim().to_string(),
    }
}

/// For text that does not parse: the `key` of the nearest `key = ...` line at or
/// before `offset`, prefixed by the table header above it (`[t]` gives `t.key`,
/// the n-th `[[t]]` gives `t[n].key`). A text scan, for messages only.
fn key_near(text: &str, offset: usize) -> Option<String> {
    let upto = &text[..offset.min(text.len())];
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
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            consider(k.span(), &path, offset, best);
            consider(v.span(), &path, offset, best);
            walk_value(v, &path, offset, best);
        }
    }
    let doc = DeTable::parse(text).ok()?;
    let mut best = None;
    walk_table(doc.get_ref(), "", offset, &mut best);
    best.map(|(_, p)| p)
}

/// Semantic validation. `text` (the file's text) gives lines to spans; `None`
/// for re-serialised `--set` text, whose spans do not match the file.
fn validate(
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
    let g = raw.goal.get_ref();
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
    if *raw.planner.get_ref() == Planner::RrtStar && *raw.perception.get_ref() == Perception::Lidar
    {
        return Err(err(
            "planner",
            Some(raw.planner.span()),
            "planner = \"rrt_star\" plans on the known map and cannot be combined with \
             perception = \"lidar\" (planning on the perceived map is not implemented)"
                .into(),
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
                let poly = if o.hull {
                    Polygon::hull(v.get_ref())
                } else {
                    Polygon::new(v.get_ref())
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
                    && r.center.iter().all(|c| c.is_finite())
                    && r.rotation.is_finite())
                {
                    return Err(err(
                        &f,
                        Some(rs.span()),
                        "center and rotation must be finite, radius > 0".into(),
                    ));
                }
                let poly = Polygon::new(&regular_polygon(r.center, r.radius, r.sides, r.rotation));
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
                obstacles.extend(extra);
            } else {
                let layout = crate::families::generate(&p.kind, seed, robot.body_radius)
                    .map_err(|m| err("generator", Some(gs.span()), m))?;
                start = layout.start;
                start_heading = layout.heading;
                goal = layout.goal;
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

/// Summary of the overrides that differ from the defaults, `field -> value`
/// (for logs).
pub fn overrides_map(o: &ControllerOverrides) -> BTreeMap<String, serde_json::Value> {
    match serde_json::to_value(o) {
        Ok(serde_json::Value::Object(m)) => m.into_iter().filter(|(_, v)| !v.is_null()).collect(),
        _ => BTreeMap::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OK: &str = r#"
name = "t"
start = { x = 0.0, y = 0.0 }
goal = [5.0, 5.0]

[controller]
delta = 0.2

[[obstacles]]
vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]

[[obstacles]]
regular = { center = [4.0, 2.0], radius = 1.0, sides = 25 }
"#;

    #[test]
    fn parses_a_valid_file() {
        let s = parse_str(OK, "t.toml", &LoadOptions::default()).unwrap();
        assert_eq!(s.obstacles.len(), 2);
        assert_eq!(s.obstacles[1].len(), 25);
        assert_eq!(s.config.delta, 0.2);
        assert_eq!(s.stance, Side::Left);
        assert_eq!(s.time_limit, 120.0);
    }

    #[test]
    fn non_convex_obstacle_is_named_with_its_line() {
        let text = OK.replace(
            "[[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]",
            "[[1.0, 1.0], [3.0, 1.0], [2.0, 1.5], [3.0, 3.0], [1.0, 3.0]]",
        );
        let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
        assert_eq!(e.field, "obstacles[0].vertices");
        assert_eq!(e.line, Some(10), "{e}");
        assert!(e.message.contains("hull = true"), "{e}");
        // With hull = true it is accepted.
        let text = text.replace(
            "vertices = [[1.0, 1.0], [3.0",
            "hull = true\nvertices = [[1.0, 1.0], [3.0",
        );
        assert!(parse_str(&text, "t.toml", &LoadOptions::default()).is_ok());
    }

    #[test]
    fn type_errors_name_the_field_and_line() {
        let text = OK.replace("goal = [5.0, 5.0]", "goal = [5.0, \"x\"]");
        let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
        assert!(e.field.starts_with("goal"), "{e}");
        assert_eq!(e.line, Some(4), "{e}");
        let text = OK.replace("delta = 0.2", "deltaa = 0.2");
        let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
        assert!(e.field.starts_with("controller"), "{e}");
        assert_eq!(e.line, Some(7), "{e}");
        let text = OK.replace("delta = 0.2", "gamma = 2.0");
        let e = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap_err();
        assert_eq!(e.field, "controller.gamma");
        assert_eq!(e.line, Some(7), "{e}");
    }

    #[test]
    fn set_overrides_apply_and_are_checked() {
        let o = LoadOptions {
            seed: None,
            sets: vec![
                ("delta".into(), "0.3".into()),
                ("time_limit".into(), "50".into()),
                ("stance".into(), "right".into()),
            ],
        };
        let s = parse_str(OK, "t.toml", &o).unwrap();
        assert_eq!(s.config.delta, 0.3);
        assert_eq!(s.time_limit, 50.0);
        assert_eq!(s.stance, Side::Right);
        let o = LoadOptions {
            seed: None,
            sets: vec![("bogus".into(), "1".into())],
        };
        let e = parse_str(OK, "t.toml", &o).unwrap_err();
        assert_eq!(e.field, "bogus");
        // The [robot] table as one key, as well as its fields.
        let o = LoadOptions::with_sets(&[("robot", "{ body_radius = 0.2 }")]);
        let s = parse_str(OK, "t.toml", &o).unwrap();
        assert_eq!(s.robot.body_radius, 0.2);
    }

    #[test]
    fn relaxation_settings_are_overridable() {
        let set = |sets: &[(&str, &str)]| LoadOptions {
            seed: None,
            sets: sets
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
        };
        let s = parse_str(OK, "t.toml", &LoadOptions::default()).unwrap();
        assert_eq!(
            s.config.capture_fraction,
            Config::default().capture_fraction
        );
        assert!(s.config.capture_fraction.is_some());
        let o = set(&[("max_gait_relaxation", "0.25"), ("capture_fraction", "0")]);
        let s = parse_str(OK, "t.toml", &o).unwrap();
        assert_eq!(s.config.max_gait_relaxation, 0.25);
        assert_eq!(s.config.capture_fraction, None);
        let text = OK.replace("delta = 0.2", "delta = 0.2\ncapture_fraction = 0.8");
        let s = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap();
        assert_eq!(s.config.capture_fraction, Some(0.8));
        let e = parse_str(OK, "t.toml", &set(&[("capture_fraction", "1.5")])).unwrap_err();
        assert_eq!(e.field, "controller.capture_fraction", "{e}");
        let m = crate::report::config_map(&s.config);
        assert_eq!(m["capture_fraction"], serde_json::json!(0.8));
        assert_eq!(m["max_gait_relaxation"], serde_json::json!(0.1));
    }

    #[test]
    fn disturbance_table_parses_and_is_validated() {
        let text = format!(
            "{OK}\n[disturbance]\nseed = 4\npush_time = 2.0\npush_lateral = 0.3\nfoot_sigma = 0.02\n"
        );
        let s = parse_str(&text, "t.toml", &LoadOptions::default()).unwrap();
        assert_eq!(s.disturbance.seed, 4);
        assert_eq!(s.disturbance.push_time, Some(2.0));
        assert_eq!(s.disturbance.push_lateral, 0.3);
        assert_eq!(s.disturbance.foot_sigma, 0.02);
        assert!(s.disturbance.is_active(1.0));
        // Absent: all off.
        let s = parse_str(OK, "t.toml", &LoadOptions::default()).unwrap();
        assert_eq!(s.disturbance, DisturbanceParams::default());
        // A negative sigma names the field and its line.
        let bad = text.replace("foot_sigma = 0.02", "foot_sigma = -0.02");
        let e = parse_str(&bad, "t.toml", &LoadOptions::default()).unwrap_err();
        assert_eq!(e.field, "disturbance.foot_sigma");
        assert_eq!(e.line, Some(19), "{e}");
        // Unknown field.
        let bad = text.replace("foot_sigma", "foot_sgima");
        let e = parse_str(&bad, "t.toml", &LoadOptions::default()).unwrap_err();
        assert!(e.field.starts_with("disturbance"), "{e}");
        assert!(e.message.contains("foot_sgima"), "{e}");
        // Through --set, including a non-finite value.
        let o = |k: &str, v: &str| LoadOptions {
            seed: None,
            sets: vec![(k.into(), v.into())],
        };
        let s = parse_str(OK, "t.toml", &o("disturbance.plant_com_height", "0.9")).unwrap();
        assert_eq!(s.disturbance.plant_com_height, Some(0.9));
        let e = parse_str(OK, "t.toml", &o("disturbance.noise_velocity", "nan")).unwrap_err();
        assert_eq!(e.field, "disturbance.noise_velocity", "{e}");
        let e = parse_str(OK, "t.toml", &o("disturbance.push_lateral", "0.3")).unwrap_err();
        assert_eq!(e.field, "disturbance.push_time", "{e}");
        let e = parse_str(OK, "t.toml", &o("disturbance.bogus", "1")).unwrap_err();
        assert!(e.message.contains("bogus"), "{e}");
    }

    #[test]
    fn random_family_is_seeded_and_keeps_start_and_goal_clear() {
        let a = random_scenario(7);
        let b = random_scenario(7);
        let c = random_scenario(8);
        assert_eq!(a.obstacles, b.obstacles);
        assert_ne!(a.obstacles, c.obstacles);
        assert_eq!(a.obstacles.len(), 8);
        for p in &a.obstacles {
            for q in [a.start, a.goal] {
                assert!(closest_point_point_polygon(&q, p).signed_distance >= 1.0);
            }
        }
    }
}
