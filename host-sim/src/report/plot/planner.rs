//! `planner.png`, the report's figure 8: the RRT* tree over the occupancy
//! grid, with the path, the subgoals, the start and the goal.

use super::*;
use crate::plan::{Route, Tree};
use crate::scenario::Scenario;
use crate::world::grid::OccupancyGrid;

/// Figure 8 of the report: the RRT* tree over the occupancy grid. Does nothing
/// for a run without a plan.
pub fn planner_png(r: &SimResult, path: &Path) -> Result<()> {
    ensure_fonts();
    let Some(plan) = r.navigation.plan.as_ref() else {
        return Ok(());
    };
    let sc = &r.scenario;
    let (x0, x1, y0, y1) = square_extent(&plan.grid);
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
    draw_grid(&mut chart, &plan.grid, plan.inflation)?;
    draw_true_obstacles(&mut chart, sc)?;
    draw_tree(&mut chart, &plan.tree)?;
    draw_route(&mut chart, plan, sc, 0.025 * (x1 - x0))?;
    map_legend(&mut chart, &layout)?;
    root.present().map_err(e)?;
    Ok(())
}

/// The grid's box widened along its shorter side to a square, centred:
/// `(x0, x1, y0, y1)`, m.
fn square_extent(g: &OccupancyGrid) -> (f64, f64, f64, f64) {
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
    (x0, x1, y0, y1)
}

/// The planning box and the occupied cells (each row's runs as rectangles),
/// obstacles inflated by `inflation` (m).
fn draw_grid<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    g: &OccupancyGrid,
    inflation: f64,
) -> Result<()> {
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
        .label(format!("occupied cell (obstacle + {inflation:.3} m)"))
        .legend(|(x, y)| Rectangle::new([(x - 6, y - 6), (x + 6, y + 6)], GRID_OCC.filled()));
    Ok(())
}

/// The scenario's true obstacles.
fn draw_true_obstacles<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    sc: &Scenario,
) -> Result<()> {
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
    Ok(())
}

/// The RRT* tree: an edge from each node to its parent.
fn draw_tree<DB: DrawingBackend>(chart: &mut MapChart<'_, DB>, t: &Tree) -> Result<()> {
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
    Ok(())
}

/// The RRT* path, the subgoal polyline and the subgoals, the start and the
/// goal (a star of outer radius `star_size`, m).
fn draw_route<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    plan: &Route,
    sc: &Scenario,
    star_size: f64,
) -> Result<()> {
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
    chart
        .draw_series(std::iter::once(Polygon::new(
            star((sc.goal.x, sc.goal.y), star_size),
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
    Ok(())
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
