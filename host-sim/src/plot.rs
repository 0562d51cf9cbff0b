//! Figures of a run, drawn with plotters into bitmaps, with DejaVu Sans embedded
//! in the binary (the `dejavu` crate) and registered through plotters' `ab_glyph`
//! backend: no system font, fontconfig or freetype is needed.
//!
//! * `map.png` ([`map_png`]): obstacles, CoM path, left/right footsteps, start,
//!   goal; equal axis scales.
//! * `states.png` ([`states_png`]): the four state panels of the report's figure 4,
//!   world frame, against time: position error to the goal (`p - g`, and its
//!   norm), CoM velocity `vx, vy`, heading `theta`, turning rate `omega` (the rate
//!   in force in the plant).
//! * `frames.png` ([`frames_png`]): six moments of the walk like the report's
//!   figure 5 (with LiDAR, also that cycle's scan and inferred polygons):
//!   obstacles, path so far, footsteps, the robot (a triangle along its
//!   heading), and for the control cycle at that moment each active LDCBF
//!   half-plane `h_j(p) = eta_j'(p - c_j) - delta >= 0` (light), their
//!   intersection (dark), each `c_j` (red dot) and `eta_j` (red arrow).
//! * `walk.gif` ([`walk_gif`]): the same drawing for the control cycle at the
//!   start of every step (decimated to at most `gif_max_frames` frames), with one
//!   palette for the whole animation.
//! * `planner.png` ([`planner_png`], runs with `planner = "rrt_star"`): the
//!   report's figure 8: the occupancy grid (inflated obstacles, grey), the true
//!   obstacles, the RRT* tree, the RRT* path (red), the subgoals (orange), the
//!   start (red dot) and the goal (blue star).
//! * `perception.png` ([`perception_png`], runs with `perception = "lidar"`): the
//!   report's figure 12: six frames with the LiDAR hit points (green), the
//!   sensor range (red circle), the inferred polygons (blue) and the true map
//!   (faded).
//!
//! With subgoals, the map-like figures also draw the subgoal polyline and the
//! subgoals (orange; in a frame the current one is ringed). With LiDAR, the
//! true obstacles are drawn faded and, in frames, the scan of that cycle on top.

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{HalfPlane, Side};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::scenario::Perception;
use crate::sim::{CycleRecord, ScanRecord, SimResult};

/// Figure options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlotOptions {
    /// Write `walk.gif`.
    pub gif: bool,
    /// Upper bound on the GIF's frames.
    pub gif_max_frames: usize,
    /// GIF width and height, pixels.
    pub gif_size: u32,
    /// Delay between GIF frames, ms.
    pub gif_delay_ms: u32,
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions {
            gif: true,
            gif_max_frames: 150,
            gif_size: 480,
            gif_delay_ms: 100,
        }
    }
}

const FONT: &str = "sans-serif";
const OBSTACLE: RGBColor = RGBColor(235, 140, 52);
const OBSTACLE_EDGE: RGBColor = RGBColor(160, 80, 10);
const LEFT: RGBColor = RGBColor(40, 90, 220);
const RIGHT: RGBColor = RGBColor(20, 150, 60);
const PATH: RGBColor = RGBColor(30, 30, 30);
const SAFE: RGBColor = RGBColor(70, 110, 200);
const GOAL: RGBColor = RGBColor(210, 30, 30);
const SUBGOAL: RGBColor = RGBColor(245, 150, 0);
const SCAN: RGBColor = RGBColor(0, 170, 60);
const INFERRED: RGBColor = RGBColor(40, 80, 220);
const TREE: RGBColor = RGBColor(120, 150, 200);
const GRID_OCC: RGBColor = RGBColor(200, 200, 200);

fn ensure_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Both calls only fail on a corrupt font, which the crate's bytes are not.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

fn e<E: core::fmt::Display>(err: E) -> anyhow::Error {
    anyhow!("plot: {err}")
}

/// Writes all figures into `dir`; returns the file names written.
pub fn render_all(r: &SimResult, dir: &Path, opts: &PlotOptions) -> Result<Vec<String>> {
    ensure_fonts();
    let scene = Scene::new(r);
    map_png(&scene, &dir.join("map.png"))?;
    states_png(r, &dir.join("states.png"))?;
    frames_png(&scene, &dir.join("frames.png"))?;
    let mut files = vec!["map.png".into(), "states.png".into(), "frames.png".into()];
    if r.navigation.plan.is_some() {
        planner_png(r, &dir.join("planner.png"))?;
        files.push("planner.png".into());
    }
    if r.scenario.perception == Perception::Lidar && !r.scans.is_empty() {
        perception_png(&scene, &dir.join("perception.png"))?;
        files.push("perception.png".into());
    }
    if opts.gif {
        walk_gif(&scene, &dir.join("walk.gif"), opts)?;
        files.push("walk.gif".into());
    }
    Ok(files)
}

/// What every map-like figure needs, precomputed once.
pub struct Scene<'r> {
    r: &'r SimResult,
    /// View window `(x0, x1, y0, y1)`, m, square.
    bounds: (f64, f64, f64, f64),
    /// CoM path decimated to 50 Hz: `(t, x, y)`.
    path: Vec<(f64, f64, f64)>,
}

impl<'r> Scene<'r> {
    /// Precomputes the view window (obstacles, start, goal and path, plus a
    /// margin, made square) and the decimated path.
    pub fn new(r: &'r SimResult) -> Self {
        let sc = &r.scenario;
        let mut pts: Vec<Vector2<f64>> = vec![sc.start, sc.goal];
        for o in &sc.obstacles {
            pts.extend(o.vertices().iter().copied());
        }
        let path: Vec<(f64, f64, f64)> = r
            .samples
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 20 == 0 || *i + 1 == r.samples.len())
            .map(|(_, s)| (s.time, s.position.x, s.position.y))
            .collect();
        pts.extend(path.iter().map(|p| Vector2::new(p.1, p.2)));
        pts.extend(r.navigation.subgoals.iter().copied());
        pts.extend(r.footsteps.iter().map(|f| f.position));
        let (mut x0, mut x1, mut y0, mut y1) = pts.iter().fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), p| (a.min(p.x), b.max(p.x), c.min(p.y), d.max(p.y)),
        );
        let m = 0.5;
        (x0, x1, y0, y1) = (x0 - m, x1 + m, y0 - m, y1 + m);
        let (w, h) = (x1 - x0, y1 - y0);
        if w > h {
            let c = 0.5 * (y0 + y1);
            (y0, y1) = (c - 0.5 * w, c + 0.5 * w);
        } else {
            let c = 0.5 * (x0 + x1);
            (x0, x1) = (c - 0.5 * h, c + 0.5 * h);
        }
        Scene {
            r,
            bounds: (x0, x1, y0, y1),
            path,
        }
    }

    fn heading_at(&self, t: f64) -> f64 {
        let s = &self.r.samples;
        let i = ((t / crate::sim::PLANT_DT).round() as usize).min(s.len().saturating_sub(1));
        s.get(i).map_or(0.0, |x| x.heading)
    }

    fn pose_at(&self, t: f64) -> (Vector2<f64>, f64) {
        let s = &self.r.samples;
        let i = ((t / crate::sim::PLANT_DT).round() as usize).min(s.len().saturating_sub(1));
        s.get(i)
            .map_or((self.r.scenario.start, 0.0), |x| (x.position, x.heading))
    }
}

/// Layout of a square map chart inside a cell: sizes in pixels.
#[derive(Clone, Copy)]
struct MapLayout {
    title_h: u32,
    margin: u32,
    x_label: u32,
    y_label: u32,
    font: u32,
    /// Draw the fine (minor) grid lines.
    fine_grid: bool,
}

impl MapLayout {
    fn for_side(side: u32) -> Self {
        let font = (side / 40).clamp(11, 20);
        MapLayout {
            title_h: font * 2,
            margin: font / 2 + 4,
            x_label: font * 3,
            y_label: font * 3 + 6,
            font,
            fine_grid: side >= 600,
        }
    }
    /// Cell size whose plotting area is `side` x `side`.
    fn cell(&self, side: u32) -> (u32, u32) {
        (
            side + 2 * self.margin + self.y_label,
            side + 2 * self.margin + self.x_label + self.title_h,
        )
    }
}

/// Clips a convex polygon to the half-plane `eta'(p - c) >= delta`
/// (Sutherland-Hodgman, one plane).
fn clip(poly: &[(f64, f64)], hp: &HalfPlane, delta: f64) -> Vec<(f64, f64)> {
    let h = |p: &(f64, f64)| hp.eta.x * (p.0 - hp.c.x) + hp.eta.y * (p.1 - hp.c.y) - delta;
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (ha, hb) = (h(&a), h(&b));
        if ha >= 0.0 {
            out.push(a);
        }
        if (ha >= 0.0) != (hb >= 0.0) {
            let t = ha / (ha - hb);
            out.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
        }
    }
    out
}

/// What a map-like drawing shows of one moment of the run.
#[derive(Clone, Copy)]
struct Moment<'a> {
    /// Path and footsteps up to this time, s.
    until: f64,
    /// The control cycle whose LDCBF half-planes are drawn.
    cycle: Option<&'a CycleRecord>,
    /// The LiDAR scan drawn on top.
    scan: Option<&'a ScanRecord>,
}

/// A map chart in metres (x right, y up) on `chart_area`, with `title`
/// (text, size relative to the layout's font) centred in `title_area`: the
/// axes, the labels and the grid of `layout` (`bold`: the major grid colour).
fn map_chart<'a, DB: DrawingBackend>(
    title_area: &DrawingArea<DB, Shift>,
    chart_area: &'a DrawingArea<DB, Shift>,
    layout: &MapLayout,
    (title, scale): (&str, f64),
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    bold: RGBColor,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>> {
    let (w, _) = title_area.dim_in_pixel();
    title_area
        .draw_text(
            title,
            &(FONT, layout.font as f64 * scale)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
            (w as i32 / 2, layout.title_h as i32 / 2),
        )
        .map_err(e)?;
    let mut chart = ChartBuilder::on(chart_area)
        .margin(layout.margin)
        .x_label_area_size(layout.x_label)
        .y_label_area_size(layout.y_label)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style((FONT, layout.font))
        .axis_desc_style((FONT, layout.font))
        .light_line_style(if layout.fine_grid {
            RGBColor(235, 235, 235).stroke_width(1)
        } else {
            TRANSPARENT.stroke_width(0)
        })
        .bold_line_style(bold)
        .draw()
        .map_err(e)?;
    Ok(chart)
}

/// Draws a map-like scene into `area`: title, axes, (half-planes of `cycle`),
/// obstacles, path and footsteps up to `until` (s), robot, start and goal.
fn draw_scene<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scene: &Scene<'_>,
    layout: MapLayout,
    moment: Moment<'_>,
    title: &str,
    legend: bool,
) -> Result<()> {
    let Moment { until, cycle, scan } = moment;
    let r = scene.r;
    let lidar = sc_perception(r) == Perception::Lidar;
    let sc = &r.scenario;
    let (x0, x1, y0, y1) = scene.bounds;
    let (title_area, chart_area) = area.split_vertically(layout.title_h);
    let mut chart = map_chart(
        &title_area,
        &chart_area,
        &layout,
        (title, 1.2),
        (x0, x1, y0, y1),
        RGBColor(210, 210, 210),
    )?;

    // LDCBF half-planes of the cycle: each safe side light, intersection dark.
    if let Some(c) = cycle {
        let delta = sc.config.delta;
        let rect = vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)];
        let mut inter = rect.clone();
        for hp in &c.half_planes {
            let p = clip(&rect, &hp.half_plane, delta);
            if p.len() >= 3 {
                chart
                    .draw_series(std::iter::once(Polygon::new(p, SAFE.mix(0.10).filled())))
                    .map_err(e)?;
            }
            inter = clip(&inter, &hp.half_plane, delta);
        }
        if !c.half_planes.is_empty() && inter.len() >= 3 {
            let mut closed = inter.clone();
            closed.push(inter[0]);
            chart
                .draw_series(std::iter::once(Polygon::new(
                    inter,
                    SAFE.mix(0.30).filled(),
                )))
                .map_err(e)?;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    closed,
                    SAFE.stroke_width(1),
                )))
                .map_err(e)?;
        }
    }

    // Obstacles (the true map; faded when the controller only perceives it).
    let fill = if lidar { 0.30 } else { 0.85 };
    for (i, o) in sc.obstacles.iter().enumerate() {
        let v: Vec<(f64, f64)> = o.vertices().iter().map(|p| (p.x, p.y)).collect();
        let mut closed = v.clone();
        closed.push(v[0]);
        let s = chart
            .draw_series(std::iter::once(Polygon::new(
                v,
                OBSTACLE.mix(fill).filled(),
            )))
            .map_err(e)?;
        if legend && i == 0 {
            let label = if lidar {
                "true obstacle (unknown)"
            } else {
                "obstacle"
            };
            s.label(label).legend(move |(x, y)| {
                Rectangle::new(
                    [(x - 6, y - 6), (x + 6, y + 6)],
                    OBSTACLE.mix(fill).filled(),
                )
            });
        }
        chart
            .draw_series(std::iter::once(PathElement::new(closed, OBSTACLE_EDGE)))
            .map_err(e)?;
    }

    // LiDAR scan: range, inferred polygons, hit points.
    if let Some(sc_rec) = scan {
        let rng = sc.lidar.range;
        let ring: Vec<(f64, f64)> = (0..=96)
            .map(|i| {
                let a = core::f64::consts::TAU * f64::from(i) / 96.0;
                (
                    sc_rec.origin.x + rng * a.cos(),
                    sc_rec.origin.y + rng * a.sin(),
                )
            })
            .collect();
        chart
            .draw_series(std::iter::once(PathElement::new(
                ring,
                GOAL.stroke_width(1),
            )))
            .map_err(e)?;
        for o in &sc_rec.obstacles {
            let v: Vec<(f64, f64)> = o.vertices().iter().map(|p| (p.x, p.y)).collect();
            let mut closed = v.clone();
            closed.push(v[0]);
            chart
                .draw_series(std::iter::once(Polygon::new(
                    v,
                    INFERRED.mix(0.45).filled(),
                )))
                .map_err(e)?;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    closed,
                    INFERRED.stroke_width(2),
                )))
                .map_err(e)?;
        }
        chart
            .draw_series(
                sc_rec
                    .points
                    .iter()
                    .map(|p| Circle::new((p.x, p.y), 1, SCAN.filled())),
            )
            .map_err(e)?;
    }

    // Subgoals: the polyline from the start and the points.
    if r.navigation.plan.is_some() {
        let mut line = vec![(sc.start.x, sc.start.y)];
        line.extend(r.navigation.subgoals.iter().map(|p| (p.x, p.y)));
        chart
            .draw_series(std::iter::once(PathElement::new(
                line,
                SUBGOAL.mix(0.8).stroke_width(2),
            )))
            .map_err(e)?;
        let s = chart
            .draw_series(
                r.navigation
                    .subgoals
                    .iter()
                    .map(|p| Circle::new((p.x, p.y), 5, SUBGOAL.filled())),
            )
            .map_err(e)?;
        if legend {
            s.label("subgoals (RRT*)")
                .legend(|(x, y)| Circle::new((x, y), 5, SUBGOAL.filled()));
        }
        if let Some(c) = cycle
            && let Some(p) = r.navigation.subgoals.get(c.subgoal)
        {
            chart
                .draw_series(std::iter::once(Circle::new(
                    (p.x, p.y),
                    9,
                    SUBGOAL.stroke_width(2),
                )))
                .map_err(e)?;
        }
    }

    // c_j and eta_j on top of the obstacles.
    if let Some(c) = cycle {
        let len = 0.08 * (x1 - x0);
        for hp in &c.half_planes {
            let (cp, eta) = (hp.half_plane.c, hp.half_plane.eta);
            let tip = cp + eta * len;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(cp.x, cp.y), (tip.x, tip.y)],
                    GOAL.stroke_width(2),
                )))
                .map_err(e)?;
            let head = |ang: f64| {
                let d = Vector2::new(
                    -eta.x * ang.cos() + eta.y * ang.sin(),
                    -eta.x * ang.sin() - eta.y * ang.cos(),
                ) * (0.3 * len);
                (tip.x + d.x, tip.y + d.y)
            };
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![head(0.4), (tip.x, tip.y), head(-0.4)],
                    GOAL.stroke_width(2),
                )))
                .map_err(e)?;
            chart
                .draw_series(std::iter::once(Circle::new((cp.x, cp.y), 3, GOAL.filled())))
                .map_err(e)?;
        }
    }

    // Path so far.
    let path: Vec<(f64, f64)> = scene
        .path
        .iter()
        .take_while(|p| p.0 <= until + 1e-9)
        .map(|p| (p.1, p.2))
        .collect();
    let s = chart
        .draw_series(LineSeries::new(path, PATH.stroke_width(1)))
        .map_err(e)?;
    if legend {
        s.label("CoM path")
            .legend(|(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], PATH.stroke_width(2)));
    }

    // Footsteps: oriented rectangles 0.16 m x 0.08 m along the heading at landing.
    let foot = |p: Vector2<f64>, th: f64| {
        let (c, s) = (th.cos(), th.sin());
        [(0.08, 0.04), (-0.08, 0.04), (-0.08, -0.04), (0.08, -0.04)]
            .iter()
            .map(|(a, b)| (p.x + c * a - s * b, p.y + s * a + c * b))
            .collect::<Vec<_>>()
    };
    for (side, color, label) in [
        (Side::Left, LEFT, "left foot"),
        (Side::Right, RIGHT, "right foot"),
    ] {
        let feet: Vec<_> = r
            .footsteps
            .iter()
            .filter(|f| f.side == side && f.time <= until + 1e-9)
            .map(|f| Polygon::new(foot(f.position, scene.heading_at(f.time)), color.filled()))
            .collect();
        let s = chart.draw_series(feet).map_err(e)?;
        if legend {
            s.label(label).legend(move |(x, y)| {
                Rectangle::new([(x - 7, y - 4), (x + 7, y + 4)], color.filled())
            });
        }
    }

    // Start, goal (with the success radius).
    let s = chart
        .draw_series(std::iter::once(Circle::new(
            (sc.start.x, sc.start.y),
            5,
            BLACK.filled(),
        )))
        .map_err(e)?;
    if legend {
        s.label("start")
            .legend(|(x, y)| Circle::new((x, y), 5, BLACK.filled()));
    }
    let ring: Vec<(f64, f64)> = (0..=48)
        .map(|i| {
            let a = core::f64::consts::TAU * f64::from(i) / 48.0;
            (
                sc.goal.x + sc.success_radius * a.cos(),
                sc.goal.y + sc.success_radius * a.sin(),
            )
        })
        .collect();
    chart
        .draw_series(std::iter::once(PathElement::new(
            ring,
            GOAL.stroke_width(2),
        )))
        .map_err(e)?;
    let s = chart
        .draw_series(std::iter::once(Cross::new(
            (sc.goal.x, sc.goal.y),
            7,
            GOAL.stroke_width(3),
        )))
        .map_err(e)?;
    if legend {
        s.label("goal")
            .legend(|(x, y)| Cross::new((x, y), 6, GOAL.stroke_width(3)));
    }

    // Robot: isosceles triangle along the heading.
    if cycle.is_some() || !legend {
        let (p, th) = scene.pose_at(until);
        let d = Vector2::new(th.cos(), th.sin());
        let n = Vector2::new(-d.y, d.x);
        let sz = 0.025 * (x1 - x0);
        let tip = p + d * (1.6 * sz);
        let b1 = p - d * sz + n * sz;
        let b2 = p - d * sz - n * sz;
        chart
            .draw_series(std::iter::once(Polygon::new(
                vec![(tip.x, tip.y), (b1.x, b1.y), (b2.x, b2.y)],
                RGBColor(120, 40, 160).filled(),
            )))
            .map_err(e)?;
    }

    if legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, layout.font))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
    }
    Ok(())
}

fn sc_perception(r: &SimResult) -> Perception {
    r.scenario.perception
}

fn outcome_text(r: &SimResult) -> String {
    let s = crate::report::summarize(r);
    format!(
        "{}: {} after {:.1} s, {} steps, min CoM clearance {}",
        r.scenario.name,
        s.outcome.replace('_', " "),
        s.sim_time,
        s.steps,
        s.min_com_clearance
            .map_or("n/a".into(), |c| format!("{c:.3} m"))
    )
}

/// Figure (a): the map of the whole run.
pub fn map_png(scene: &Scene<'_>, path: &Path) -> Result<()> {
    ensure_fonts();
    let side = 760;
    let layout = MapLayout::for_side(side);
    let (w, h) = layout.cell(side);
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let end = scene.r.sim_time();
    draw_scene(
        &root,
        scene,
        layout,
        Moment {
            until: end,
            cycle: None,
            scan: None,
        },
        &outcome_text(scene.r),
        true,
    )?;
    root.present().map_err(e)?;
    Ok(())
}

/// A named, coloured series of `(t, value)` points.
type Series<'a> = (&'a str, RGBColor, Vec<(f64, f64)>);

/// One panel of `states.png`: several named series against time.
fn line_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    y_desc: &str,
    t_end: f64,
    series: &[Series<'_>],
    legend_at: SeriesLabelPosition,
) -> Result<()> {
    let (mut lo, mut hi) = series
        .iter()
        .flat_map(|s| s.2.iter().map(|p| p.1))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.06).max(1e-3);
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end.max(1e-3), (lo - pad)..(hi + pad))
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc(y_desc)
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(e)?;
    for (name, color, pts) in series {
        let color = *color;
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(1)))
            .map_err(e)?
            .label(*name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x - 8, y), (x + 8, y)], color.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(legend_at)
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    Ok(())
}

/// Figure (b): the four state panels (world frame) against time.
pub fn states_png(r: &SimResult, path: &Path) -> Result<()> {
    ensure_fonts();
    let root = BitMapBackend::new(path, (1400, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let g = r.scenario.goal;
    let dec: Vec<_> = r
        .samples
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 10 == 0 || *i + 1 == r.samples.len())
        .map(|(_, s)| s)
        .collect();
    let t_end = r.sim_time();
    let ser = |f: &dyn Fn(&crate::sim::Sample) -> f64| -> Vec<(f64, f64)> {
        dec.iter().map(|s| (s.time, f(s))).collect()
    };
    let panels = root.split_evenly((2, 2));
    let blue = RGBColor(31, 119, 180);
    let orange = RGBColor(255, 127, 14);
    let gray = RGBColor(60, 60, 60);
    line_panel(
        &panels[0],
        "position error to the goal",
        "p - g [m]",
        t_end,
        &[
            ("x error", blue, ser(&|s| s.position.x - g.x)),
            ("y error", orange, ser(&|s| s.position.y - g.y)),
            ("|p - g|", gray, ser(&|s| (s.position - g).norm())),
        ],
        SeriesLabelPosition::UpperRight,
    )?;
    line_panel(
        &panels[1],
        "CoM velocity",
        "v [m/s]",
        t_end,
        &[
            ("vx", blue, ser(&|s| s.velocity.x)),
            ("vy", orange, ser(&|s| s.velocity.y)),
        ],
        SeriesLabelPosition::UpperRight,
    )?;
    line_panel(
        &panels[2],
        "heading",
        "theta [rad]",
        t_end,
        &[("theta", blue, ser(&|s| s.heading))],
        SeriesLabelPosition::LowerRight,
    )?;
    line_panel(
        &panels[3],
        "turning rate",
        "omega [rad/s]",
        t_end,
        &[("omega", blue, ser(&|s| s.turning_rate))],
        SeriesLabelPosition::UpperRight,
    )?;
    root.present().map_err(e)?;
    Ok(())
}

/// The control cycles shown as frames: `n` cycles evenly spread in time, each
/// the first cycle at or after its target time.
fn pick_cycles(r: &SimResult, n: usize) -> Vec<&CycleRecord> {
    let t_end = r.sim_time();
    let mut out: Vec<&CycleRecord> = Vec::new();
    for i in 0..n {
        let t = t_end * i as f64 / (n.max(2) - 1) as f64;
        let c = r
            .cycles
            .iter()
            .rev()
            .find(|c| c.time <= t + 1e-9)
            .or(r.cycles.first());
        if let Some(c) = c
            && out.last().is_none_or(|l| l.index != c.index)
        {
            out.push(c);
        }
    }
    out
}

/// Figure (c): six frames of the walk with the LDCBF half-planes.
pub fn frames_png(scene: &Scene<'_>, path: &Path) -> Result<()> {
    six_frames(scene, path, true, |c, _| {
        format!(
            "t = {:.1} s, {} active obstacle{}",
            c.time,
            c.half_planes.len(),
            if c.half_planes.len() == 1 { "" } else { "s" }
        )
    })
}

/// Six cycles of the run ([`pick_cycles`]) in a 3 x 2 grid of map cells, each
/// drawn up to its time with its scan (if recorded) and, with `half_planes`,
/// its LDCBF half-planes; `title` names a cell from its cycle and scan.
fn six_frames(
    scene: &Scene<'_>,
    path: &Path,
    half_planes: bool,
    title: impl Fn(&CycleRecord, Option<&ScanRecord>) -> String,
) -> Result<()> {
    ensure_fonts();
    let side = 440;
    let layout = MapLayout::for_side(side);
    let (cw, ch) = layout.cell(side);
    let (cols, rows) = (3u32, 2u32);
    let root = BitMapBackend::new(path, (cw * cols, ch * rows)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let cells = root.split_evenly((rows as usize, cols as usize));
    let picks = pick_cycles(scene.r, (cols * rows) as usize);
    for (cell, c) in cells.iter().zip(picks) {
        let scan = scan_of(scene.r, c);
        draw_scene(
            cell,
            scene,
            layout,
            Moment {
                until: c.time,
                cycle: half_planes.then_some(c),
                scan,
            },
            &title(c, scan),
            false,
        )?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// Figure (d): the animated walk. One frame per step (the cycle at the start of
/// each step), decimated to at most `opts.gif_max_frames`, plus the final state.
/// One palette (NeuQuant, trained on the last frame) for all frames.
pub fn walk_gif(scene: &Scene<'_>, path: &Path, opts: &PlotOptions) -> Result<()> {
    ensure_fonts();
    let r = scene.r;
    let starts: Vec<&CycleRecord> = r
        .cycles
        .iter()
        .filter(|c| c.time_in_step.abs() < 1e-9)
        .collect();
    let every = starts.len().div_ceil(opts.gif_max_frames.max(2) - 1).max(1);
    let mut frames: Vec<&CycleRecord> = starts.iter().step_by(every).copied().collect();
    if let Some(last) = r.cycles.last()
        && frames.last().is_none_or(|f| f.index != last.index)
    {
        frames.push(last);
    }
    let side = opts.gif_size.max(200);
    let layout = MapLayout::for_side(side);
    let (w, h) = layout.cell(side);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let render = |buf: &mut [u8], c: &CycleRecord, until: f64| -> Result<()> {
        let root = BitMapBackend::with_buffer(buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(e)?;
        let title = format!("{}  t = {:.1} s", r.scenario.name, until);
        let scan = scan_of(r, c);
        draw_scene(
            &root,
            scene,
            layout,
            Moment {
                until,
                cycle: Some(c),
                scan,
            },
            &title,
            false,
        )?;
        root.present().map_err(e)?;
        Ok(())
    };
    let Some(last) = frames.last() else {
        return Ok(());
    };
    // Palette from the final frame (it has every colour the walk uses).
    render(&mut buf, last, r.sim_time())?;
    let rgba: Vec<u8> = buf
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let nq = color_quant::NeuQuant::new(10, 256, &rgba);
    let lut: Vec<u8> = (0..32768u32)
        .map(|k| {
            let (r5, g5, b5) = ((k >> 10) & 31, (k >> 5) & 31, k & 31);
            let px = [
                (r5 << 3 | r5 >> 2) as u8,
                (g5 << 3 | g5 >> 2) as u8,
                (b5 << 3 | b5 >> 2) as u8,
                255,
            ];
            nq.index_of(&px) as u8
        })
        .collect();
    let file = std::fs::File::create(path)?;
    let mut enc = gif::Encoder::new(
        std::io::BufWriter::new(file),
        w as u16,
        h as u16,
        &nq.color_map_rgb(),
    )
    .map_err(e)?;
    enc.set_repeat(gif::Repeat::Infinite).map_err(e)?;
    let n = frames.len();
    for (i, c) in frames.iter().enumerate() {
        let until = if i + 1 == n { r.sim_time() } else { c.time };
        render(&mut buf, c, until)?;
        let idx: Vec<u8> = buf
            .chunks_exact(3)
            .map(|p| {
                let k = (usize::from(p[0] >> 3) << 10)
                    | (usize::from(p[1] >> 3) << 5)
                    | usize::from(p[2] >> 3);
                lut[k]
            })
            .collect();
        let mut frame = gif::Frame::from_indexed_pixels(w as u16, h as u16, &idx, None);
        frame.delay = if i + 1 == n {
            300
        } else {
            (opts.gif_delay_ms / 10).max(2) as u16
        };
        enc.write_frame(&frame).map_err(e)?;
    }
    Ok(())
}

/// The scan that fed cycle `c`, if recorded.
fn scan_of<'a>(r: &'a SimResult, c: &CycleRecord) -> Option<&'a ScanRecord> {
    r.scans
        .binary_search_by_key(&c.index, |s| s.cycle)
        .ok()
        .map(|i| &r.scans[i])
}

/// Figure 12 of the report: six frames of a LiDAR run with the scan of each.
pub fn perception_png(scene: &Scene<'_>, path: &Path) -> Result<()> {
    six_frames(scene, path, false, |c, scan| {
        format!(
            "t = {:.1} s: {} hits, {} inferred",
            c.time,
            scan.map_or(0, |s| s.points.len()),
            scan.map_or(0, |s| s.obstacles.len())
        )
    })
}

/// A five-pointed star around `c` (data units), outer radius `r`.
fn star(c: (f64, f64), r: f64) -> Vec<(f64, f64)> {
    (0..10)
        .map(|i| {
            let a = core::f64::consts::FRAC_PI_2 + core::f64::consts::PI * f64::from(i) / 5.0;
            let rr = if i % 2 == 0 { r } else { 0.4 * r };
            (c.0 + rr * a.cos(), c.1 + rr * a.sin())
        })
        .collect()
}

/// Figure 8 of the report: the RRT* tree over the occupancy grid. Does nothing
/// for a run without a plan.
pub fn planner_png(r: &SimResult, path: &Path) -> Result<()> {
    ensure_fonts();
    let Some(plan) = r.navigation.plan.as_ref() else {
        return Ok(());
    };
    let sc = &r.scenario;
    let g = &plan.grid;
    let (mut x0, mut y0) = (g.origin.x, g.origin.y);
    let (mut x1, mut y1) = (
        x0 + g.width as f64 * g.resolution,
        y0 + g.height as f64 * g.resolution,
    );
    let (w, h) = (x1 - x0, y1 - y0);
    if w > h {
        y0 -= 0.5 * (w - h);
        y1 += 0.5 * (w - h);
    } else {
        x0 -= 0.5 * (h - w);
        x1 += 0.5 * (h - w);
    }
    let side = 760;
    let layout = MapLayout::for_side(side);
    let (cw, chh) = layout.cell(side);
    let root = BitMapBackend::new(path, (cw, chh)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let (title_area, chart_area) = root.split_vertically(layout.title_h);
    let title = format!(
        "{}: RRT* {} nodes, {} subgoals, path {:.2} m (grid {} m, inflation {:.3} m)",
        sc.name,
        plan.tree.nodes.len(),
        plan.subgoals.len(),
        plan.subgoal_length(sc.start),
        plan.grid.resolution,
        plan.inflation
    );
    let mut chart = map_chart(
        &title_area,
        &chart_area,
        &MapLayout {
            fine_grid: false,
            ..layout
        },
        (&title, 1.1),
        (x0, x1, y0, y1),
        RGBColor(225, 225, 225),
    )?;
    // Planning box and occupied cells (row runs as rectangles).
    let (gx0, gy0) = (g.origin.x, g.origin.y);
    let gx1 = gx0 + g.width as f64 * g.resolution;
    let gy1 = gy0 + g.height as f64 * g.resolution;
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(gx0, gy0), (gx1, gy0), (gx1, gy1), (gx0, gy1), (gx0, gy0)],
            BLACK.stroke_width(1),
        )))
        .map_err(e)?;
    let mut cells = Vec::new();
    for j in 0..g.height {
        let mut i = 0;
        while i < g.width {
            if g.is_occupied(i, j) {
                let start = i;
                while i < g.width && g.is_occupied(i, j) {
                    i += 1;
                }
                let (ya, yb) = (
                    gy0 + j as f64 * g.resolution,
                    gy0 + (j + 1) as f64 * g.resolution,
                );
                cells.push(Rectangle::new(
                    [
                        (gx0 + start as f64 * g.resolution, ya),
                        (gx0 + i as f64 * g.resolution, yb),
                    ],
                    GRID_OCC.filled(),
                ));
            } else {
                i += 1;
            }
        }
    }
    chart
        .draw_series(cells)
        .map_err(e)?
        .label(format!(
            "occupied cell (obstacle + {:.3} m)",
            plan.inflation
        ))
        .legend(|(x, y)| Rectangle::new([(x - 6, y - 6), (x + 6, y + 6)], GRID_OCC.filled()));
    for (i, o) in sc.obstacles.iter().enumerate() {
        let v: Vec<(f64, f64)> = o.vertices().iter().map(|p| (p.x, p.y)).collect();
        let s = chart
            .draw_series(std::iter::once(Polygon::new(v, OBSTACLE.mix(0.9).filled())))
            .map_err(e)?;
        if i == 0 {
            s.label("obstacle").legend(|(x, y)| {
                Rectangle::new([(x - 6, y - 6), (x + 6, y + 6)], OBSTACLE.filled())
            });
        }
    }
    // Tree.
    let t = &plan.tree;
    chart
        .draw_series((1..t.nodes.len()).filter_map(|k| {
            t.parent[k].map(|p| {
                PathElement::new(
                    vec![(t.nodes[p].x, t.nodes[p].y), (t.nodes[k].x, t.nodes[k].y)],
                    TREE.stroke_width(1),
                )
            })
        }))
        .map_err(e)?
        .label("RRT* tree")
        .legend(|(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], TREE.stroke_width(2)));
    // Path, subgoals, start, goal.
    chart
        .draw_series(std::iter::once(PathElement::new(
            plan.path.iter().map(|p| (p.x, p.y)).collect::<Vec<_>>(),
            GOAL.stroke_width(3),
        )))
        .map_err(e)?
        .label("RRT* path")
        .legend(|(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], GOAL.stroke_width(3)));
    let mut line = vec![(sc.start.x, sc.start.y)];
    line.extend(plan.subgoals.iter().map(|p| (p.x, p.y)));
    chart
        .draw_series(std::iter::once(PathElement::new(
            line,
            SUBGOAL.stroke_width(2),
        )))
        .map_err(e)?;
    chart
        .draw_series(
            plan.subgoals
                .iter()
                .map(|p| Circle::new((p.x, p.y), 6, SUBGOAL.filled())),
        )
        .map_err(e)?
        .label("subgoals (shortcut path)")
        .legend(|(x, y)| Circle::new((x, y), 6, SUBGOAL.filled()));
    chart
        .draw_series(std::iter::once(Circle::new(
            (sc.start.x, sc.start.y),
            7,
            GOAL.filled(),
        )))
        .map_err(e)?
        .label("start")
        .legend(|(x, y)| Circle::new((x, y), 6, GOAL.filled()));
    let blue = RGBColor(30, 60, 200);
    let sz = 0.025 * (x1 - x0);
    chart
        .draw_series(std::iter::once(Polygon::new(
            star((sc.goal.x, sc.goal.y), sz),
            blue.filled(),
        )))
        .map_err(e)?
        .label("goal")
        .legend(move |(x, y)| {
            Polygon::new(
                star((f64::from(x), f64::from(y)), 7.0)
                    .into_iter()
                    .map(|(a, b)| (a as i32, b as i32))
                    .collect::<Vec<_>>(),
                blue.filled(),
            )
        });
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font((FONT, layout.font))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}
