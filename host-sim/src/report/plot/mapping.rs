//! `mapping.png` ([`mapping_png`], runs with `perception = "lidar"`): the true
//! map and the walk (left) next to the map the robot built (right): occupied
//! cells (dark), cells seen free (white), unknown cells (grey), the CoM path,
//! and every plan made on the perceived map (the last one orange, earlier
//! ones faded).

use super::scene::{draw_scene, outcome_text};
use super::*;
use crate::sense::CellState;

const UNKNOWN: RGBColor = RGBColor(190, 190, 190);
const OCCUPIED: RGBColor = RGBColor(40, 40, 40);

/// Writes `mapping.png` (module docs); nothing without a map.
pub fn mapping_png(scene: &Scene<'_>, path: &Path) -> Result<()> {
    ensure_fonts();
    let r = scene.r;
    let Some(log) = r.mapping.as_ref() else {
        return Ok(());
    };
    let side = 620;
    let layout = MapLayout::for_side(side);
    let (w, h) = layout.cell(side);
    let root = BitMapBackend::new(path, (2 * w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let (left, right) = root.split_horizontally(w);
    let moment = Moment {
        until: r.sim_time(),
        cycle: None,
        scan: None,
    };
    draw_scene(&left, scene, layout, moment, &outcome_text(r), false)?;
    let (title_area, chart_area) = right.split_vertically(layout.title_h);
    let (x0, x1, y0, y1) = scene.bounds;
    let m = &log.map;
    let title = format!(
        "perceived map: {} plans ({} failed), cell {} m",
        log.plans.len(),
        log.failures(),
        m.resolution
    );
    let mut chart = map_chart(
        &title_area,
        &chart_area,
        &layout,
        (&title, 1.2),
        (x0, x1, y0, y1),
        RGBColor(210, 210, 210),
    )?;
    // Cells in view, as row runs of one state (free cells stay white).
    let cell = |x: f64, o: f64, n: usize| {
        ((((x - o) / m.resolution).floor()).clamp(0.0, n as f64)) as usize
    };
    let (i0, i1) = (cell(x0, m.origin.x, m.width), cell(x1, m.origin.x, m.width));
    let (j0, j1) = (
        cell(y0, m.origin.y, m.height),
        cell(y1, m.origin.y, m.height),
    );
    let mut rects = Vec::new();
    for j in j0..j1 {
        let mut i = i0;
        while i < i1 {
            let s = m.state(i, j);
            let a = i;
            while i < i1 && m.state(i, j) == s {
                i += 1;
            }
            let colour = match s {
                CellState::Free => continue,
                CellState::Unknown => UNKNOWN,
                CellState::Occupied => OCCUPIED,
            };
            let p0 = m.origin + Vector2::new(a as f64, j as f64) * m.resolution;
            let p1 = m.origin + Vector2::new(i as f64, (j + 1) as f64) * m.resolution;
            rects.push(Rectangle::new(
                [(p0.x, p0.y), (p1.x, p1.y)],
                colour.filled(),
            ));
        }
    }
    chart.draw_series(rects).map_err(e)?;
    // Plans (earlier ones faded), CoM path, start and goal.
    for (k, p) in log.plans.iter().enumerate() {
        if p.subgoals.is_empty() {
            continue;
        }
        let last = k + 1 == log.plans.len();
        let from = r
            .samples
            .iter()
            .find(|s| s.time >= p.time)
            .map_or(r.scenario.start, |s| s.position);
        let mut line = vec![(from.x, from.y)];
        line.extend(p.subgoals.iter().map(|q| (q.x, q.y)));
        let style = if last {
            SUBGOAL.stroke_width(3)
        } else {
            SUBGOAL.mix(0.35).stroke_width(1)
        };
        chart
            .draw_series(std::iter::once(PathElement::new(line, style)))
            .map_err(e)?;
    }
    chart
        .draw_series(std::iter::once(PathElement::new(
            scene
                .path
                .iter()
                .map(|&(_, x, y)| (x, y))
                .collect::<Vec<_>>(),
            SAFE.stroke_width(2),
        )))
        .map_err(e)?;
    let sc = &r.scenario;
    chart
        .draw_series([
            Circle::new((sc.start.x, sc.start.y), 6, GOAL.filled()),
            Circle::new((sc.goal.x, sc.goal.y), 6, RGBColor(30, 60, 200).filled()),
        ])
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}
