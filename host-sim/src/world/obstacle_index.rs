//! A spatial index of a known map, so that a control cycle costs the same
//! whatever the map's size (issue 14, part 2).
//!
//! Every cycle the controller selects the obstacles within `r_active` of `p_0`
//! (its predicted CoM at the end of the current step). Scanning the whole map
//! for them costs about 30 ns per obstacle, 300 µs for 10,000 obstacles: over
//! the 250 µs deadline before the QP is even built. Instead the host keeps the
//! map's axis-aligned bounding boxes in an R-tree ([`rstar`], bulk-loaded once
//! when the run starts) and, each cycle, asks the controller where it will
//! look ([`Controller::obstacle_query`]: `p_0` and `r_active`), takes the
//! boxes within that disk (queried from the tree `r_active` +
//! [`CANDIDATE_MARGIN`] around `p_0` and reused while they cover later cycles,
//! [`Candidates`]), sorted by index, and passes them to
//! [`Controller::step`] as its `candidates`, which tests only those. `benches/map_scaling.rs`
//! and `docs/benchmarks.md` give the cost against the map's size.
//!
//! # Why the results are bit for bit those of a full scan
//!
//! * Every obstacle the controller can select is a candidate: it selects `j`
//!   only if its signed distance from `p_0` is at most `r_active`; then a point
//!   of the polygon, hence of its bounding box, lies within `r_active` of
//!   `p_0`, and the query uses [`ObstacleQuery::padded_radius`], which covers
//!   the rounding of both distance computations.
//! * The query's centre is the controller's own `p_0` (the same function on
//!   the same input), so no margin for the robot's travel is needed: the
//!   query is made every cycle, from the state that cycle measures.
//! * The candidates are sorted by index, so the controller sees the selected
//!   obstacles in the map's order (it breaks distance ties by that order) and
//!   names them by their index in the map (its row identities and warm start
//!   do not change); obstacles that are not selected are skipped without side
//!   effect.
//!
//! # Which side owns the index
//!
//! The host. The controller is `no_std` without a heap and sized at compile
//! time; a map of thousands of polygons lives where the map is built (a mapping
//! stack, the simulator's scenario), which also rebuilds the index when the
//! map changes. The controller only tells the caller where it will look
//! ([`ObstacleQuery`]) and accepts a list of candidate indices: the firmware,
//! whose obstacle list is small and fixed, keeps calling `step` on its whole
//! list, and a firmware with a large map would query its own index the same
//! way. Perceived obstacles (LiDAR) are few per scan (their count is bounded by
//! the sensor's range, not by the map), so the simulator passes them whole
//! to `step`; `benches/map_scaling.rs` measures an index rebuilt per scan
//! against that.
//!
//! [`Controller::obstacle_query`]: ldcbf_controller::Controller::obstacle_query
//! [`Controller::step`]: ldcbf_controller::Controller::step

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{ObstacleQuery, closest_point_point_polygon};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

use crate::world::Polygon;
use crate::world::robot::{RobotParams, signed_distance_convex};

/// One indexed obstacle: its bounding box (m, world frame) and its index in
/// the map.
type Entry = GeomWithData<Rectangle<[f64; 2]>, u32>;

/// An R-tree over the bounding boxes of a fixed list of obstacles (world frame
/// W, m), answering "which obstacles may lie within `r` of `c`" in time
/// logarithmic in the list's length plus the number of answers.
#[derive(Clone, Debug)]
pub struct ObstacleIndex {
    tree: RTree<Entry>,
    len: usize,
}

/// Axis-aligned bounding box of a polygon, `([x_min, y_min], [x_max, y_max])`, m.
pub fn bounding_box(poly: &Polygon) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for v in poly.vertices() {
        lo = [lo[0].min(v.x), lo[1].min(v.y)];
        hi = [hi[0].max(v.x), hi[1].max(v.y)];
    }
    (lo, hi)
}

/// Squared distance from `c` to the box `(lo, hi)`, m² (0 inside), computed as
/// [`rstar`] computes it for a [`Rectangle`].
fn box_distance_2(c: &Vector2<f64>, lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let aabb = AABB::from_corners(lo, hi);
    rstar::Envelope::distance_2(&aabb, &[c.x, c.y])
}

impl ObstacleIndex {
    /// Indexes `obstacles` (bulk load, `O(n log n)`). `Err` if there are more
    /// than `u32::MAX + 1` of them (the controller names obstacles by `u32`).
    pub fn new(obstacles: &[Polygon]) -> Result<Self, String> {
        if u32::try_from(obstacles.len().saturating_sub(1)).is_err() {
            return Err(format!(
                "{} obstacles: an index holds at most 2^32",
                obstacles.len()
            ));
        }
        let entries: Vec<Entry> = obstacles
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (lo, hi) = bounding_box(p);
                GeomWithData::new(Rectangle::from_corners(lo, hi), i as u32)
            })
            .collect();
        Ok(ObstacleIndex {
            tree: RTree::bulk_load(entries),
            len: obstacles.len(),
        })
    }

    /// Number of indexed obstacles.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No obstacle is indexed.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Writes into `out` (cleared first), in increasing order, the indices of
    /// the obstacles whose bounding box is within `radius` (m) of `center` (m,
    /// world): box distance `d` with `d^2 <= radius^2` as computed by
    /// [`rstar`]. Exactly the obstacles [`scan_within`] finds.
    pub fn within_into(&self, center: &Vector2<f64>, radius: f64, out: &mut Vec<u32>) {
        out.clear();
        out.extend(
            self.tree
                .locate_within_distance([center.x, center.y], radius * radius)
                .map(|e| e.data),
        );
        out.sort_unstable();
    }

    /// `min_j f(j)` over the indexed obstacles (`+inf` without any), for an
    /// `f` that cannot be below `d_j - reach` (`d_j`: distance from `p` to
    /// obstacle `j`, m) and is at most 0 only for `d_j <= reach`: a signed
    /// clearance from a shape within `reach` (m) of `p`. Visits the obstacles
    /// by increasing bounding-box distance from `p` and stops at the first box
    /// farther than `max(best, 0) + reach` (padded for rounding as in
    /// [`ObstacleQuery::padded_radius`]): no obstacle left can give less. The
    /// minimum of a set does not depend on the order it is taken in, so this
    /// is the linear scan's value (both skip NaN; of two zeros of opposite sign
    /// either may come out, as in the scan).
    pub fn min_near(&self, p: &Vector2<f64>, reach: f64, mut f: impl FnMut(usize) -> f64) -> f64 {
        let mut best = f64::INFINITY;
        for (e, d2) in self.tree.nearest_neighbor_iter_with_distance_2([p.x, p.y]) {
            let limit = ObstacleQuery {
                center: *p,
                radius: best.max(0.0) + reach,
            }
            .padded_radius();
            if d2 > limit * limit {
                break;
            }
            best = best.min(f(e.data as usize));
        }
        best
    }

    /// Signed distance from `p` (m, world) to the nearest of `obstacles` (the
    /// list this index was built from), m (negative inside, `+inf` without
    /// obstacles): [`crate::world::clearance`]'s value through
    /// [`ObstacleIndex::min_near`].
    pub fn clearance(&self, p: &Vector2<f64>, obstacles: &[Polygon]) -> f64 {
        self.min_near(p, 0.0, |j| {
            obstacles.get(j).map_or(f64::INFINITY, |o| {
                closest_point_point_polygon(p, o).signed_distance
            })
        })
    }

    /// The footprint's signed clearance to the nearest of `obstacles` (the
    /// list this index was built from), m: the value of
    /// [`RobotParams::foot_clearance`] through [`ObstacleIndex::min_near`]
    /// (the footprint lies within its half-diagonal of its centre).
    pub fn foot_clearance(
        &self,
        robot: &RobotParams,
        center: Vector2<f64>,
        heading: f64,
        obstacles: &[Polygon],
    ) -> f64 {
        let foot = robot.footprint(center, heading);
        let reach = foot.iter().map(|c| (c - center).norm()).fold(0.0, f64::max);
        self.min_near(&center, reach, |j| {
            obstacles
                .get(j)
                .map_or(f64::INFINITY, |o| signed_distance_convex(&foot, o))
        })
    }

    /// The candidates of one control cycle, in increasing order, into `out`:
    /// the obstacles within [`ObstacleQuery::padded_radius`] of
    /// [`ObstacleQuery::center`], a superset of those the controller can
    /// select (see the module docs), for the `candidates` of `Controller::step`.
    pub fn candidates_into(&self, query: &ObstacleQuery, out: &mut Vec<u32>) {
        self.within_into(&query.center, query.padded_radius(), out);
    }
}

/// Margin of [`Candidates`], m: the list is queried `r_active + 0.5` m around
/// the `p_0` of the cycle that queried it, and reused while later `p_0` stay
/// within 0.5 m of it (about one step of walking).
pub const CANDIDATE_MARGIN: f64 = 0.5;

/// A cycle's candidates, reused from cycle to cycle while they still cover
/// the cycle's disk: one R-tree query every step or so instead of every
/// cycle. A list queried at `c` within `R` holds every box within `R - |p -
/// c|` of any `p` (triangle inequality), so while `|p_0 - c| +`
/// [`ObstacleQuery::padded_radius`] `<= R` it still holds every obstacle the
/// cycle can select, in increasing order: the controller's result is the
/// same bit for bit (it tests each candidate exactly); it only tests a few
/// more (the disk's area grows by `((r + m) / r)^2`, 1.27 for `r_active = 4`
/// m and the margin 0.5 m).
#[derive(Clone, Debug, Default)]
pub struct Candidates {
    list: Vec<u32>,
    center: Vector2<f64>,
    reach: f64,
    valid: bool,
}

impl Candidates {
    /// The candidates for `query` (a superset of the obstacles the cycle can
    /// select, increasing indices), queried from `index` again only when the
    /// last list does not cover the query's disk. `index` must be the same
    /// index on every call (else [`Candidates::clear`] first).
    pub fn update(&mut self, index: &ObstacleIndex, query: &ObstacleQuery) -> &[u32] {
        let need = query.padded_radius();
        let covered = self.valid && (query.center - self.center).norm() + need <= self.reach;
        if !covered {
            self.center = query.center;
            self.reach = need + CANDIDATE_MARGIN;
            // Padded once more for the rounding of the query itself.
            let r = ObstacleQuery {
                center: self.center,
                radius: self.reach,
            }
            .padded_radius();
            index.within_into(&self.center, r, &mut self.list);
            self.valid = true;
        }
        &self.list
    }

    /// Forgets the list (the next [`Candidates::update`] queries).
    pub fn clear(&mut self) {
        self.list.clear();
        self.valid = false;
    }

    /// The current list (empty after [`Candidates::clear`]).
    pub fn list(&self) -> &[u32] {
        &self.list
    }
}

/// The linear scan that [`ObstacleIndex::within_into`] replaces: indices, in
/// increasing order, of the obstacles whose bounding box is within `radius` (m)
/// of `center` (m, world). For tests and benchmarks.
pub fn scan_within(obstacles: &[Polygon], center: &Vector2<f64>, radius: f64) -> Vec<u32> {
    obstacles
        .iter()
        .enumerate()
        .filter(|(_, p)| {
            let (lo, hi) = bounding_box(p);
            box_distance_2(center, lo, hi) <= radius * radius
        })
        .map(|(i, _)| i as u32)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(cx: f64, cy: f64, h: f64) -> Polygon {
        crate::world::square([cx, cy], h)
    }

    #[test]
    fn a_grid_query_finds_the_boxes_within_the_radius_in_order() {
        // Unit squares of half-size 0.1 on a 1 m grid, 0..10 x 0..10.
        let map: Vec<Polygon> = (0..100)
            .map(|i| square(f64::from(i % 10), f64::from(i / 10), 0.1))
            .collect();
        let index = ObstacleIndex::new(&map).unwrap();
        assert_eq!(index.len(), 100);
        let mut out = Vec::new();
        let c = Vector2::new(5.0, 5.0);
        // Within 0.95 m of (5, 5): the centre and its 4 neighbours (box
        // distance 0.9); the diagonal ones are at sqrt(2) * 0.9 > 0.95.
        index.within_into(&c, 0.95, &mut out);
        assert_eq!(out, vec![45, 54, 55, 56, 65]);
        assert_eq!(out, scan_within(&map, &c, 0.95));
        // Clearance: the linear minimum, inside a square too.
        for p in [c, Vector2::new(5.05, 5.0), Vector2::new(-3.0, 12.5)] {
            assert_eq!(
                index.clearance(&p, &map).to_bits(),
                crate::world::clearance(&p, &map).to_bits()
            );
        }
        assert!((index.clearance(&Vector2::new(5.05, 5.0), &map) + 0.05).abs() < 1e-12);
        // Foot clearance: the linear minimum, overlapping or apart.
        let robot = RobotParams::default();
        for (p, h) in [
            (c, 0.3),
            (Vector2::new(5.1, 5.12), 1.0),
            (Vector2::new(5.5, 5.5), 0.0),
        ] {
            assert_eq!(
                index.foot_clearance(&robot, p, h, &map).to_bits(),
                robot.foot_clearance(p, h, &map).to_bits()
            );
        }
        // Far outside the map: nothing.
        index.within_into(&Vector2::new(100.0, 100.0), 4.0, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn candidates_are_reused_while_they_cover_the_disk() {
        let map: Vec<Polygon> = (0..400)
            .map(|i| square(f64::from(i % 20), f64::from(i / 20), 0.1))
            .collect();
        let index = ObstacleIndex::new(&map).unwrap();
        let mut cache = Candidates::default();
        let q = |x: f64| ObstacleQuery {
            center: Vector2::new(x, 10.0),
            radius: 4.0,
        };
        let first = cache.update(&index, &q(5.0)).to_vec();
        assert_eq!(cache.center.x, 5.0);
        let mut exact = Vec::new();
        for x in [5.2, 5.49, 4.6] {
            // Within the margin: the same list, which holds the exact query's.
            assert_eq!(cache.update(&index, &q(x)), &first[..]);
            assert_eq!(cache.center.x, 5.0);
            index.candidates_into(&q(x), &mut exact);
            assert!(exact.iter().all(|j| first.binary_search(j).is_ok()));
            assert!(exact.len() < first.len());
        }
        // Past it: queried again around the new centre.
        cache.update(&index, &q(5.6));
        assert_eq!(cache.center.x, 5.6);
        cache.clear();
        assert!(cache.list().is_empty());
        cache.update(&index, &q(5.6));
        assert!(!cache.list().is_empty());
    }

    #[test]
    fn an_empty_map_has_an_empty_index() {
        let index = ObstacleIndex::new(&[]).unwrap();
        assert!(index.is_empty());
        let mut out = vec![7];
        index.within_into(&Vector2::zeros(), 10.0, &mut out);
        assert!(out.is_empty());
        assert_eq!(index.clearance(&Vector2::zeros(), &[]), f64::INFINITY);
    }
}
