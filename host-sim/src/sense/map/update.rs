//! Adding a scan to the map (ray-cast marking and clearing, decay) and
//! clearing the cells of something that moves (module docs of [`super`]).

use ldcbf_controller::nalgebra::Vector2;

use super::OccupancyMap;
use crate::world::Polygon;

impl OccupancyMap {
    /// Adds one scan taken from `origin` (m) with the sensor's zero angle along
    /// `heading` (rad): `rays[k]` is ray `k`'s hit point or `None` (as
    /// [`crate::sense::Lidar::scan_rays`] returns them), `range` the LiDAR's
    /// range and `tol` its free-space tolerance (m), `dt` the time since the
    /// last update (s, for `decay`).
    pub fn update(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        rays: &[Option<Vector2<f64>>],
        range: f64,
        tol: f64,
        dt: f64,
    ) {
        self.update_keeping_out(origin, heading, rays, range, tol, dt, &[]);
    }

    /// [`OccupancyMap::update`] with the hits of the rays flagged in
    /// `kept_out` (one flag per ray; missing flags are `false`) left out:
    /// those rays still clear the cells in front of their hits, but give no
    /// hit (a tracked person, [`crate::sense::movers`], is not a wall).
    #[allow(clippy::too_many_arguments)]
    pub fn update_keeping_out(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        rays: &[Option<Vector2<f64>>],
        range: f64,
        tol: f64,
        dt: f64,
        kept_out: &[bool],
    ) {
        let free: Vec<f64> = rays
            .iter()
            .map(|p| p.map_or(range, |p| (p - origin).norm() - tol))
            .collect();
        self.update_scan(origin, heading, rays, &free, dt, kept_out);
    }

    /// [`OccupancyMap::update_keeping_out`] with each ray's free length
    /// given: ray `k` gives a miss to every cell it passes through up to
    /// `free[k]` (m) from `origin` (a missing length: none), e.g. from
    /// [`crate::sense::faces::free_lengths`].
    pub fn update_scan(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        rays: &[Option<Vector2<f64>>],
        free: &[f64],
        dt: f64,
        kept_out: &[bool],
    ) {
        if self.params.decay > 0.0 && dt > 0.0 {
            let f = (-self.params.decay * dt).exp() as f32;
            for l in &mut self.log_odds {
                *l *= f;
            }
        }
        self.grow_to_scan(origin, rays, free);
        self.scans = self.scans.wrapping_add(1).max(1);
        let scan = self.scans;
        // Hits first: they win over this scan's misses.
        for (k, p) in rays.iter().enumerate() {
            let Some(p) = p else { continue };
            if kept_out.get(k).copied().unwrap_or(false) {
                continue;
            }
            if let Some((i, j)) = self.cell_of(*p) {
                let k = j * self.width + i;
                if self.stamp[k] != scan {
                    self.stamp[k] = scan;
                    // The misses before are of other lines through the
                    // cell (`hit_overrides_misses`, module docs).
                    let before = if self.params.hit_overrides_misses && !self.near_occupied(i, j) {
                        self.log_odds[k].max(0.0)
                    } else {
                        self.log_odds[k]
                    };
                    self.log_odds[k] = (before + self.hit).clamp(self.lo, self.hi);
                }
            }
        }
        let n = rays.len();
        for k in 0..n {
            let d = crate::sense::ray_direction(heading, k, n);
            let len = free.get(k).copied().unwrap_or(0.0);
            if len > 0.0 {
                self.traverse(origin, d, len, |map, c| {
                    if map.stamp[c] != scan && !map.on_edge(c) {
                        map.stamp[c] = scan;
                        map.log_odds[c] = (map.log_odds[c] + map.miss).clamp(map.lo, map.hi);
                    }
                });
            }
        }
    }

    /// Whether a cell other than `(i, j)` within `hit_noise_band` of it
    /// (whole cells along each axis) is occupied.
    fn near_occupied(&self, i: usize, j: usize) -> bool {
        let reach = (self.params.hit_noise_band / self.resolution).ceil() as usize;
        let (i0, i1) = (i.saturating_sub(reach), (i + reach).min(self.width - 1));
        let (j0, j1) = (j.saturating_sub(reach), (j + reach).min(self.height - 1));
        (j0..=j1)
            .any(|b| (i0..=i1).any(|a| (a, b) != (i, j) && self.log_odds[b * self.width + a] > 0.0))
    }

    /// Clears the occupied cells whose centre is within `margin` (m) of
    /// `poly` (world frame): their log-odds become one miss's (free, not
    /// sure). For the cells of something that moves and was mapped before it
    /// was known to ([`crate::sense::movers`]: a person at the edge of the
    /// range, or seen in one cluster with a wall).
    pub fn clear_polygon(&mut self, poly: &Polygon, margin: f64) {
        let (lo, hi) = crate::world::obstacle_index::bounding_box(poly);
        let (lo, hi) = (Vector2::from(lo), Vector2::from(hi));
        let m = Vector2::repeat(margin);
        let (lo, hi) = (lo - m, hi + m);
        if hi.x < self.origin.x || hi.y < self.origin.y {
            return;
        }
        let ((i0, i1), (j0, j1)) = self.cell_range(lo, hi);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * self.width + i;
                if self.log_odds[k] > 0.0
                    && !self.on_edge(k)
                    && ldcbf_controller::closest_point_point_polygon(&self.centre(i, j), poly)
                        .signed_distance
                        <= margin
                {
                    self.log_odds[k] = self.miss;
                }
            }
        }
    }
}
