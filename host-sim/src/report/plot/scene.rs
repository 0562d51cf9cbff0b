//! The map-like scene every map figure is made of: obstacles, path, footsteps,
//! the robot, start and goal, and for one control cycle its LDCBF half-planes,
//! scan and subgoals.

use super::*;
use crate::world::moving::vertex_centre;

/// Draws a map-like scene into `area`: title, axes, (half-planes of `cycle`),
/// obstacles, path and footsteps up to `until` (s), robot, start and goal.
/// Layers are drawn bottom first, in the order of the legend.
pub(super) fn draw_scene<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scene: &Scene<'_>,
    layout: MapLayout,
    moment: Moment<'_>,
    title: &str,
    legend: bool,
) -> Result<()> {
    let Moment { until, cycle, scan } = moment;
    let r = scene.r;
    let sc = &r.scenario;
    let (title_area, chart_area) = area.split_vertically(layout.title_h);
    let mut chart = map_chart(
        &title_area,
        &chart_area,
        &layout,
        (title, 1.2),
        scene.bounds,
        RGBColor(210, 210, 210),
    )?;
    if let Some(c) = cycle {
        draw_half_planes(&mut chart, c, sc.config.delta, scene.bounds)?;
    }
    draw_obstacles(&mut chart, r, until, legend)?;
    if let Some(rec) = scan {
        draw_scan(&mut chart, rec, sc.lidar.range)?;
    }
    if r.navigation.plan.is_some() {
        draw_subgoals(&mut chart, r, cycle, legend)?;
    }
    if let Some(c) = cycle {
        draw_normals(&mut chart, c, 0.08 * (scene.bounds.1 - scene.bounds.0))?;
    }
    draw_path(&mut chart, scene, until, legend)?;
    draw_footsteps(&mut chart, scene, until, legend)?;
    draw_start_goal(&mut chart, sc, legend)?;
    if cycle.is_some() || !legend {
        draw_robot(&mut chart, scene, until)?;
    }
    if legend {
        map_legend(&mut chart, &layout)?;
    }
    Ok(())
}

/// The cycle's LDCBF half-planes (shifted by `delta`, m) clipped to the view
/// `bounds`: each safe side light, their intersection dark.
fn draw_half_planes<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    c: &CycleRecord,
    delta: f64,
    (x0, x1, y0, y1): (f64, f64, f64, f64),
) -> Result<()> {
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
    Ok(())
}

/// The obstacles of the true map (faded when the controller only perceives
/// it), each where the run recorded it at the last cycle up to `until` (s),
/// and the trace of the centre of each that moved since t = 0
/// ([`SimResult::obstacle_centres`]: people who react stop, turn and wait).
fn draw_obstacles<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    r: &SimResult,
    until: f64,
    legend: bool,
) -> Result<()> {
    let lidar = sc_perception(r) == Perception::Lidar;
    let fill = if lidar { 0.30 } else { 0.85 };
    let recorded = recorded_until(r, until);
    let positions = obstacles_at(r, recorded.last());
    if let (Some(first), Some(last)) = (recorded.first(), recorded.last()) {
        for (i, _) in first
            .iter()
            .zip(last)
            .enumerate()
            .filter(|(_, (a, b))| a != b)
        {
            let trace: Vec<(f64, f64)> = recorded.iter().map(|c| (c[i].x, c[i].y)).collect();
            chart
                .draw_series(std::iter::once(PathElement::new(
                    trace,
                    OBSTACLE_EDGE.mix(0.6).stroke_width(2),
                )))
                .map_err(e)?;
        }
    }
    for (i, o) in positions.iter().enumerate() {
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
    Ok(())
}

/// A LiDAR scan: its range circle (`range`, m), the inferred polygons and the
/// hit points.
fn draw_scan<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    rec: &ScanRecord,
    range: f64,
) -> Result<()> {
    let ring: Vec<(f64, f64)> = (0..=96)
        .map(|i| {
            let a = core::f64::consts::TAU * f64::from(i) / 96.0;
            (
                rec.origin.x + range * a.cos(),
                rec.origin.y + range * a.sin(),
            )
        })
        .collect();
    chart
        .draw_series(std::iter::once(PathElement::new(
            ring,
            GOAL.stroke_width(1),
        )))
        .map_err(e)?;
    for o in &rec.obstacles {
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
            rec.points
                .iter()
                .map(|p| Circle::new((p.x, p.y), 1, SCAN.filled())),
        )
        .map_err(e)?;
    Ok(())
}

/// The subgoals: the polyline from the start and the points, the `cycle`'s
/// current one ringed.
fn draw_subgoals<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    r: &SimResult,
    cycle: Option<&CycleRecord>,
    legend: bool,
) -> Result<()> {
    let sc = &r.scenario;
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
    Ok(())
}

/// The cycle's closest points `c_j` and normals `eta_j` (arrows `len` m long),
/// on top of the obstacles.
fn draw_normals<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    c: &CycleRecord,
    len: f64,
) -> Result<()> {
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
    Ok(())
}

/// The CoM path up to `until`, s.
fn draw_path<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    scene: &Scene<'_>,
    until: f64,
    legend: bool,
) -> Result<()> {
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
    Ok(())
}

/// The footsteps landed by `until` (s): oriented rectangles 0.16 m x 0.08 m
/// along the heading at landing.
fn draw_footsteps<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    scene: &Scene<'_>,
    until: f64,
    legend: bool,
) -> Result<()> {
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
        let feet: Vec<_> = scene
            .r
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
    Ok(())
}

/// The start, and the goal with its success radius.
fn draw_start_goal<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    sc: &crate::scenario::Scenario,
    legend: bool,
) -> Result<()> {
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
    Ok(())
}

/// The robot at `until` (s): an isosceles triangle along the heading, sized
/// to the view.
fn draw_robot<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    scene: &Scene<'_>,
    until: f64,
) -> Result<()> {
    let (p, th) = scene.pose_at(until);
    let d = Vector2::new(th.cos(), th.sin());
    let n = Vector2::new(-d.y, d.x);
    let sz = 0.025 * (scene.bounds.1 - scene.bounds.0);
    let tip = p + d * (1.6 * sz);
    let b1 = p - d * sz + n * sz;
    let b2 = p - d * sz - n * sz;
    chart
        .draw_series(std::iter::once(Polygon::new(
            vec![(tip.x, tip.y), (b1.x, b1.y), (b2.x, b2.y)],
            RGBColor(120, 40, 160).filled(),
        )))
        .map_err(e)?;
    Ok(())
}

fn sc_perception(r: &SimResult) -> Perception {
    r.scenario.perception
}

pub(super) fn outcome_text(r: &SimResult) -> String {
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

/// The recorded obstacle centres ([`SimResult::obstacle_centres`]) of the
/// cycles up to time `t` (s): empty when none were recorded.
fn recorded_until(r: &SimResult, t: f64) -> &[Vec<Vector2<f64>>] {
    let n = r
        .cycles
        .iter()
        .take(r.obstacle_centres.len())
        .take_while(|c| c.time <= t)
        .count();
    &r.obstacle_centres[..n]
}

/// Every obstacle of the scenario moved to its recorded centre `centres`
/// (one per obstacle, [`SimResult::obstacle_centres`]); where it was at t = 0
/// without one (a map at rest records none).
fn obstacles_at(r: &SimResult, centres: Option<&Vec<Vector2<f64>>>) -> Vec<crate::world::Polygon> {
    r.scenario
        .obstacles
        .iter()
        .enumerate()
        .map(|(i, o)| match centres.and_then(|c| c.get(i)) {
            Some(c) => crate::world::moving::translated(o, c - vertex_centre(o)),
            None => *o,
        })
        .collect()
}
