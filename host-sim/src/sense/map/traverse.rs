//! Amanatides-Woo traversal of the cells a segment passes through.

use ldcbf_controller::nalgebra::Vector2;

use super::OccupancyMap;

impl OccupancyMap {
    /// Calls `f` with the index of every cell the segment from `o` along the
    /// unit direction `d` to length `len` (m) passes through, in order, inside
    /// the map (Amanatides-Woo traversal; the segment is clipped to the map).
    pub fn traverse(
        &mut self,
        o: Vector2<f64>,
        d: Vector2<f64>,
        len: f64,
        mut f: impl FnMut(&mut Self, usize),
    ) {
        let r = self.resolution;
        let size = Vector2::new(self.width as f64, self.height as f64) * r;
        // Clip [0, len] to the map box (slab test).
        let (mut t0, mut t1) = (0.0f64, len);
        for a in 0..2 {
            let (p, v, hi) = (o[a] - self.origin[a], d[a], size[a]);
            if v.abs() < 1e-15 {
                if p < 0.0 || p >= hi {
                    return;
                }
            } else {
                let (ta, tb) = ((0.0 - p) / v, (hi - p) / v);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 >= t1 {
            return;
        }
        let start = o + d * t0 - self.origin;
        let clampi = |x: f64, n: usize| ((x / r).floor().max(0.0) as usize).min(n - 1);
        let (mut i, mut j) = (clampi(start.x, self.width), clampi(start.y, self.height));
        let step = |v: f64| if v > 0.0 { 1isize } else { -1 };
        let (si, sj) = (step(d.x), step(d.y));
        let next = |c: usize, s: isize, v: f64, p: f64| {
            if v.abs() < 1e-15 {
                f64::INFINITY
            } else {
                let b = (c as f64 + if s > 0 { 1.0 } else { 0.0 }) * r;
                t0 + (b - p) / v
            }
        };
        let mut tx = next(i, si, d.x, start.x);
        let mut ty = next(j, sj, d.y, start.y);
        let dtx = if d.x.abs() < 1e-15 {
            f64::INFINITY
        } else {
            r / d.x.abs()
        };
        let dty = if d.y.abs() < 1e-15 {
            f64::INFINITY
        } else {
            r / d.y.abs()
        };
        // At most one cell per crossing of a grid line, plus the first.
        let max_cells = self.width + self.height + 2;
        for _ in 0..max_cells {
            f(self, j * self.width + i);
            if tx < ty {
                if tx >= t1 {
                    return;
                }
                tx += dtx;
                match i.checked_add_signed(si) {
                    Some(n) if n < self.width => i = n,
                    _ => return,
                }
            } else {
                if ty >= t1 {
                    return;
                }
                ty += dty;
                match j.checked_add_signed(sj) {
                    Some(n) if n < self.height => j = n,
                    _ => return,
                }
            }
        }
    }
}
