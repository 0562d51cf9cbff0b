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
//! * `mapping.png` ([`mapping_png`], runs with `perception = "lidar"`): the
//!   true map and the walk next to the perceived occupancy map (occupied,
//!   free, unknown cells) and the plans made on it.
//!
//! With subgoals, the map-like figures also draw the subgoal polyline and the
//! subgoals (orange; in a frame the current one is ringed). With LiDAR, the
//! true obstacles are drawn faded and, in frames, the scan of that cycle on top.

use std::path::Path;
use std::sync::Once;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{HalfPlane, Side};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::sense::Perception;
use crate::sim::{CycleRecord, ScanRecord, SimResult};

mod figures;
mod mapping;
mod planner;
mod scene;

pub use figures::{frames_png, map_png, perception_png, states_png, walk_gif};
pub use mapping::mapping_png;
pub use planner::planner_png;

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

/// Why a figure was not written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// plotters or the GIF encoder failed (drawing, encoding or writing).
    #[error("{0}")]
    Draw(String),
    /// The file could not be created.
    #[error("cannot create {}: {source}", path.display())]
    Create {
        /// The figure's path.
        path: std::path::PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A figure of [`render_all`] failed: its file name and why.
    #[error("plot {file}: {source}")]
    Figure {
        /// The figure's file name in the output directory.
        file: &'static str,
        /// Why.
        source: Box<PlotError>,
    },
}

/// The result of drawing a figure.
pub type Result<T> = std::result::Result<T, PlotError>;

fn e<E: core::fmt::Display>(err: E) -> PlotError {
    PlotError::Draw(err.to_string())
}

/// Writes all figures into `dir`; returns the file names written. An error
/// names the figure's file ([`PlotError::Figure`]).
pub fn render_all(r: &SimResult, dir: &Path, opts: &PlotOptions) -> Result<Vec<String>> {
    ensure_fonts();
    let scene = Scene::new(r);
    let mut files = Vec::new();
    let mut figure = |file: &'static str, draw: &dyn Fn(&Path) -> Result<()>| {
        draw(&dir.join(file)).map_err(|source| PlotError::Figure {
            file,
            source: Box::new(source),
        })?;
        files.push(file.to_string());
        Ok::<(), PlotError>(())
    };
    figure("map.png", &|p| map_png(&scene, p))?;
    figure("states.png", &|p| states_png(r, p))?;
    figure("frames.png", &|p| frames_png(&scene, p))?;
    if r.navigation.plan.is_some() {
        figure("planner.png", &|p| planner_png(r, p))?;
    }
    if r.scenario.perception == Perception::Lidar && !r.scans.is_empty() {
        figure("perception.png", &|p| perception_png(&scene, p))?;
    }
    if r.mapping.is_some() {
        figure("mapping.png", &|p| mapping_png(&scene, p))?;
    }
    if opts.gif {
        figure("walk.gif", &|p| walk_gif(&scene, p, opts))?;
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

/// A map chart in metres ([`map_chart`]).
type MapChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The legend of a map chart: its series' labels in the upper left, on a
/// white box, in the layout's font.
fn map_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut MapChart<'a, DB>,
    layout: &MapLayout,
) -> Result<()> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font((FONT, layout.font))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(e)
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
