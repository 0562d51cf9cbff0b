//! The figures of a run, one function each (see the module docs of [`super`]).

use super::scene::{draw_scene, outcome_text};
use super::*;

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
    let file = std::fs::File::create(path).map_err(|source| PlotError::Create {
        path: path.to_path_buf(),
        source,
    })?;
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
