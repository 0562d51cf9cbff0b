//! Seeded scenario families for a robot with a body: corridors, doorways,
//! cups, starts facing a wall, clutter around the goal, thin walls and
//! needles (the `[generator]` kinds `corridor`, `doorway`, `cup`,
//! `wall_start`, `clutter`, `thin`), and the families with people who walk
//! (`crossing`, `headon`, `crowd`, `room_crossing`: [`crate::world::people`];
//! `group_crossing`, `headon_offset`, `occluded_person`, people hard to
//! track: [`crate::world::people_hard`]).
//!
//! Each family draws, from a ChaCha8 generator seeded by the scenario's seed,
//! the start (position and heading), the goal and the obstacles (convex
//! polygons; a wall is a rectangle, a cup three). World frame W, metres,
//! radians. Every layout is valid for a body of radius `r`
//! ([`crate::world::robot::RobotParams::body_radius`]):
//!
//! * the start and the goal are at least `r + 0.05` m from every obstacle;
//! * the goal is reachable by the body: on an occupancy grid of the obstacles
//!   at rest (people of [`crate::world::people`] move, and are not counted)
//!   inflated by `r + 0.05` m (0.05 m cells), the start's and the goal's cells
//!   are connected ([`crate::world::grid::connected`]), so a path of free cell
//!   centres keeps more than `r` from every obstacle; the drawn passage widths
//!   below are at least 0.7 m;
//!
//! a draw that fails a check is drawn again (at most 200 times, then an error).
//!
//! | family | what is drawn |
//! |---|---|
//! | `corridor` | a corridor 0.7-1.6 m wide between walls 0.05-0.3 m thick, straight for 8-20 m, then (half the seeds) a 90-degree bend left or right and 4-10 m more; start 0.5 m inside the entrance, goal 0.5 m before the far end |
//! | `doorway` | a closed room split by a wall 0.05-0.3 m thick, 3-6 m ahead, with one door 0.7-1.6 m wide offset up to 2.5 m from the start's line; goal 2-5 m behind the wall, up to 3 m to either side |
//! | `cup` | a U of three walls (inner width 1.2-3 m, depth 1-2.5 m, 0.1-0.3 m thick) 3-5 m ahead, open toward the start (a trap for the MPC alone) or away from it; goal 3-6 m behind it |
//! | `wall_start` | the start facing a wall 2-6 m long, its face 0.3-0.6 m (never less than `r + 0.05`) ahead; goal 2-5 m behind the wall or beside it |
//! | `clutter` | 10-20 small convex polygons (0.1-0.4 m across) within 2.5 m of a goal 8-12 m away |
//! | `thin` | 3-8 thin walls (0.02-0.05 m thick, 1-4 m long) and 2-6 needles (thin triangles 0.5-2 m long, 0.02-0.05 m at the base) between the start and a goal 10 m away |

use ldcbf_controller::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};

use crate::world::Polygon;
use crate::world::{people, people_hard};

/// The family names (`[generator] kind`).
pub const FAMILIES: &[&str] = &[
    "corridor",
    "doorway",
    "cup",
    "wall_start",
    "clutter",
    "thin",
    "crossing",
    "headon",
    "crowd",
    "room_crossing",
    "group_crossing",
    "headon_offset",
    "occluded_person",
];

/// Largest number of draws before a family gives up.
pub const MAX_DRAWS: usize = 200;

/// A generated layout.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Start CoM position, m.
    pub start: Vector2<f64>,
    /// Start heading, rad.
    pub heading: f64,
    /// Goal, m.
    pub goal: Vector2<f64>,
    /// Obstacles, world frame (at t = 0 for the moving ones).
    pub obstacles: Vec<Polygon>,
    /// The first obstacles' velocities, m/s, world frame; the obstacles past
    /// the end of this list are at rest ([`crate::world::moving`]).
    pub velocities: Vec<Vector2<f64>>,
}

impl Layout {
    /// One velocity per obstacle (zero for those at rest), m/s.
    pub fn velocities_padded(&self) -> Vec<Vector2<f64>> {
        let mut v = self.velocities.clone();
        v.resize(self.obstacles.len(), Vector2::zeros());
        v
    }
}

pub(super) struct Draw(ChaCha8Rng);

impl Draw {
    /// The families' generator for `seed`.
    pub(super) fn seeded(seed: u64) -> Draw {
        Draw(ChaCha8Rng::seed_from_u64(seed ^ 0x4641_4d49_4c59)) // "FAMILY"
    }
    pub(super) fn unif(&mut self, lo: f64, hi: f64) -> f64 {
        let u = (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        lo + (hi - lo) * u
    }
    pub(super) fn coin(&mut self) -> bool {
        self.unif(0.0, 1.0) < 0.5
    }
    pub(super) fn int(&mut self, lo: usize, hi: usize) -> usize {
        (self.unif(lo as f64, hi as f64 + 1.0).floor() as usize).min(hi)
    }
}

/// An axis-aligned rectangle `[x0, x1] x [y0, y1]` (corners in any order).
pub(super) fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Polygon {
    let (xa, xb) = (x0.min(x1), x0.max(x1));
    let (ya, yb) = (y0.min(y1), y0.max(y1));
    Polygon::new(&[[xa, ya], [xb, ya], [xb, yb], [xa, yb]]).expect("a rectangle is convex")
}

/// A rectangle centred at `c`, `length` along the angle `a`, `width` across.
fn bar(c: Vector2<f64>, length: f64, width: f64, a: f64) -> Polygon {
    let u = Vector2::new(a.cos(), a.sin()) * (0.5 * length);
    let v = Vector2::new(-a.sin(), a.cos()) * (0.5 * width);
    let p = [c - u - v, c + u - v, c + u + v, c - u + v];
    Polygon::new(&p.map(|q| [q.x, q.y])).expect("a rectangle is convex")
}

/// Rotates `p` by `a` about the origin.
fn rot(p: Vector2<f64>, a: f64) -> Vector2<f64> {
    Vector2::new(a.cos() * p.x - a.sin() * p.y, a.sin() * p.x + a.cos() * p.y)
}

/// `poly` rotated by `a` about the origin.
fn rotated(poly: &Polygon, a: f64) -> Polygon {
    let v: Vec<[f64; 2]> = poly
        .vertices()
        .iter()
        .map(|p| {
            let q = rot(*p, a);
            [q.x, q.y]
        })
        .collect();
    Polygon::new(&v).expect("a rotation keeps a convex polygon convex")
}

fn corridor(d: &mut Draw) -> Layout {
    let w = d.unif(0.7, 1.6);
    let t1 = d.unif(0.05, 0.3);
    let t2 = d.unif(0.05, 0.3);
    let l1 = d.unif(8.0, 20.0);
    let h = 0.5 * w;
    let mut obstacles = Vec::new();
    let start = Vector2::new(0.5, 0.0);
    let goal = if d.coin() {
        // Straight.
        obstacles.push(rect(0.0, -h - t1, l1, -h));
        obstacles.push(rect(0.0, h, l1, h + t2));
        Vector2::new(l1 - 0.5, 0.0)
    } else {
        // An L: along x to the bend, then along +y (or -y) for l2.
        let l2 = d.unif(4.0, 10.0);
        let s = if d.coin() { 1.0 } else { -1.0 };
        // Inner wall (on the side of the turn) ends at the inner corner; the
        // outer wall runs to the outer corner and up the second leg.
        let inner_y = s * h;
        let outer_y = -s * h;
        obstacles.push(rect(0.0, inner_y, l1 - w, inner_y + s * t2));
        obstacles.push(rect(0.0, outer_y, l1 + t1, outer_y - s * t1));
        // Second leg: walls at x = l1 - w (inner) and x = l1 (outer).
        obstacles.push(rect(l1 - w - t2, inner_y, l1 - w, s * (h + l2)));
        obstacles.push(rect(l1, outer_y, l1 + t1, s * (h + l2)));
        Vector2::new(l1 - h, s * (h + l2 - 0.5))
    };
    Layout {
        start,
        heading: 0.0,
        goal,
        obstacles,
        velocities: Vec::new(),
    }
}

pub(super) fn doorway(d: &mut Draw) -> Layout {
    let x = d.unif(3.0, 6.0);
    let t = d.unif(0.05, 0.3);
    let w = d.unif(0.7, 1.6);
    let yc = d.unif(-2.5, 2.5);
    let gx = x + t + d.unif(2.0, 5.0);
    let gy = d.unif(-3.0, 3.0);
    let (x0, x1, y0, y1) = (-1.5, gx + 1.5, -5.0, 5.0);
    let wt = 0.2;
    let obstacles = vec![
        rect(x, y0, x + t, yc - 0.5 * w),
        rect(x, yc + 0.5 * w, x + t, y1),
        // The room.
        rect(x0 - wt, y0 - wt, x1 + wt, y0),
        rect(x0 - wt, y1, x1 + wt, y1 + wt),
        rect(x0 - wt, y0, x0, y1),
        rect(x1, y0, x1 + wt, y1),
    ];
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal: Vector2::new(gx, gy),
        obstacles,
        velocities: Vec::new(),
    }
}

fn cup(d: &mut Draw) -> Layout {
    let c = d.unif(3.0, 5.0);
    let inner = d.unif(1.2, 3.0);
    let depth = d.unif(1.0, 2.5);
    let t = d.unif(0.1, 0.3);
    let off = d.unif(-0.5, 0.5);
    let open_to_start = d.coin();
    let h = 0.5 * inner;
    // The back wall at the far side (open toward the start) or the near side.
    let (back0, back1, arm0, arm1) = if open_to_start {
        (c + depth, c + depth + t, c, c + depth + t)
    } else {
        (c, c + t, c, c + depth + t)
    };
    let obstacles = vec![
        rect(back0, off - h - t, back1, off + h + t),
        rect(arm0, off + h, arm1, off + h + t),
        rect(arm0, off - h - t, arm1, off - h),
    ];
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal: Vector2::new(c + depth + t + d.unif(3.0, 6.0), d.unif(-1.0, 1.0)),
        obstacles,
        velocities: Vec::new(),
    }
}

fn wall_start(d: &mut Draw, r: f64) -> Layout {
    let heading = d.unif(-core::f64::consts::PI, core::f64::consts::PI);
    let gap = d.unif(0.3, 0.6).max(r + 0.05);
    let len = d.unif(2.0, 6.0);
    let t = d.unif(0.05, 0.3);
    let along = d.unif(-0.5 * len + 0.3, 0.5 * len - 0.3);
    // In the start's frame: the wall face at x = gap, the start at the origin.
    let wall = rect(gap, -0.5 * len + along, gap + t, 0.5 * len + along);
    let goal_local = if d.coin() {
        Vector2::new(gap + t + d.unif(2.0, 5.0), d.unif(-1.0, 1.0))
    } else {
        let side = if d.coin() { 1.0 } else { -1.0 };
        Vector2::new(
            gap + t + d.unif(0.5, 2.0),
            side * (0.5 * len + d.unif(1.0, 3.0)),
        )
    };
    Layout {
        start: Vector2::zeros(),
        heading,
        goal: rot(goal_local, heading),
        obstacles: vec![rotated(&wall, heading)],
        velocities: Vec::new(),
    }
}

fn small_polygon(d: &mut Draw, c: Vector2<f64>, size: [f64; 2]) -> Option<Polygon> {
    let s = d.unif(size[0], size[1]);
    let n = d.int(3, 7);
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|_| {
            let a = d.unif(0.0, core::f64::consts::TAU);
            let rr = 0.5 * s * d.unif(0.6, 1.0);
            [c.x + rr * a.cos(), c.y + rr * a.sin()]
        })
        .collect();
    Polygon::hull(&pts).ok()
}

fn clutter(d: &mut Draw) -> Layout {
    let goal = Vector2::new(d.unif(8.0, 12.0), d.unif(-2.0, 2.0));
    let n = d.int(10, 20);
    let mut obstacles = Vec::new();
    for _ in 0..n {
        let a = d.unif(0.0, core::f64::consts::TAU);
        let rr = 2.5 * d.unif(0.0, 1.0).sqrt();
        if let Some(p) = small_polygon(d, goal + Vector2::new(a.cos(), a.sin()) * rr, [0.1, 0.4]) {
            obstacles.push(p);
        }
    }
    Layout {
        start: Vector2::zeros(),
        heading: d.unif(-0.5, 0.5),
        goal,
        obstacles,
        velocities: Vec::new(),
    }
}

fn thin(d: &mut Draw) -> Layout {
    let goal = Vector2::new(10.0, d.unif(-2.0, 2.0));
    let mut obstacles = Vec::new();
    for _ in 0..d.int(3, 8) {
        let c = Vector2::new(d.unif(1.5, 8.5), d.unif(-3.0, 3.0));
        obstacles.push(bar(
            c,
            d.unif(1.0, 4.0),
            d.unif(0.02, 0.05),
            d.unif(0.0, core::f64::consts::PI),
        ));
    }
    for _ in 0..d.int(2, 6) {
        let c = Vector2::new(d.unif(1.5, 8.5), d.unif(-3.0, 3.0));
        let a = d.unif(0.0, core::f64::consts::TAU);
        let l = d.unif(0.5, 2.0);
        let b = d.unif(0.02, 0.05);
        let u = Vector2::new(a.cos(), a.sin());
        let v = Vector2::new(-a.sin(), a.cos());
        let (p, q, tip) = (c + v * (0.5 * b), c - v * (0.5 * b), c + u * l);
        if let Ok(poly) = Polygon::hull(&[[p.x, p.y], [q.x, q.y], [tip.x, tip.y]]) {
            obstacles.push(poly);
        }
    }
    Layout {
        start: Vector2::zeros(),
        heading: d.unif(-0.5, 0.5),
        goal,
        obstacles,
        velocities: Vec::new(),
    }
}

/// Whether `layout` is valid for a body of radius `r` (see the module docs;
/// the passage is checked on the obstacles at rest, the clearances of the
/// start and the goal on every obstacle at t = 0).
pub fn is_valid(layout: &Layout, r: f64) -> bool {
    let velocities = layout.velocities_padded();
    let rest: Vec<Polygon> = layout
        .obstacles
        .iter()
        .zip(&velocities)
        .filter(|(_, v)| v.norm() == 0.0)
        .map(|(o, _)| *o)
        .collect();
    let clear = |p: &Vector2<f64>| {
        layout
            .obstacles
            .iter()
            .all(|o| closest_point_point_polygon(p, o).signed_distance >= r + 0.05)
    };
    clear(&layout.start)
        && clear(&layout.goal)
        && crate::world::grid::connected(layout.start, layout.goal, &rest, r + 0.05, 0.05)
}

/// The layout of family `kind` for `seed` and a body of radius
/// `body_radius` (m): the first valid draw of the seeded generator.
pub fn generate(kind: &str, seed: u64, body_radius: f64) -> Result<Layout, String> {
    let mut d = Draw::seeded(seed);
    for _ in 0..MAX_DRAWS {
        let layout = match kind {
            "corridor" => corridor(&mut d),
            "doorway" => doorway(&mut d),
            "cup" => cup(&mut d),
            "wall_start" => wall_start(&mut d, body_radius),
            "clutter" => clutter(&mut d),
            "thin" => thin(&mut d),
            "crossing" => people::crossing(&mut d),
            "headon" => people::headon(&mut d),
            "crowd" => people::crowd(&mut d, body_radius),
            "room_crossing" => people::room_crossing(&mut d),
            "group_crossing" => people_hard::group_crossing(&mut d),
            "headon_offset" => people_hard::headon_offset(&mut d),
            "occluded_person" => people_hard::occluded_person(&mut d),
            _ => {
                return Err(format!(
                    "unknown family {kind:?} (one of {})",
                    FAMILIES.join(", ")
                ));
            }
        };
        if is_valid(&layout, body_radius) {
            return Ok(layout);
        }
    }
    Err(format!(
        "no valid {kind} layout for a body of radius {body_radius} m in {MAX_DRAWS} draws"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_family_gives_valid_deterministic_layouts() {
        let r = 0.25;
        for kind in FAMILIES {
            for seed in 0..50 {
                let a = generate(kind, seed, r).unwrap_or_else(|e| panic!("{kind} {seed}: {e}"));
                assert!(is_valid(&a, r), "{kind} {seed}");
                assert!(!a.obstacles.is_empty(), "{kind} {seed}");
                let b = generate(kind, seed, r).unwrap();
                assert_eq!(a.obstacles, b.obstacles, "{kind} {seed}: deterministic");
                assert_eq!((a.start, a.goal, a.heading), (b.start, b.goal, b.heading));
            }
            let a = generate(kind, 1, r).unwrap();
            let b = generate(kind, 2, r).unwrap();
            assert_ne!(
                a.obstacles, b.obstacles,
                "{kind}: another seed, another layout"
            );
        }
    }

    #[test]
    fn the_passage_check_rejects_a_closed_door() {
        let layout = Layout {
            start: Vector2::zeros(),
            heading: 0.0,
            goal: Vector2::new(4.0, 0.0),
            // A room split by a wall whose door is 0.4 m: narrower than the body.
            obstacles: vec![
                rect(2.0, -5.0, 2.1, -0.2),
                rect(2.0, 0.2, 2.1, 5.0),
                rect(-1.0, -5.2, 6.0, -5.0),
                rect(-1.0, 5.0, 6.0, 5.2),
                rect(-1.2, -5.2, -1.0, 5.2),
                rect(6.0, -5.2, 6.2, 5.2),
            ],
            velocities: Vec::new(),
        };
        assert!(!is_valid(&layout, 0.25));
        assert!(is_valid(&layout, 0.1), "a narrower body fits");
    }

    #[test]
    fn unknown_family_is_an_error() {
        assert!(generate("maze", 0, 0.25).unwrap_err().contains("corridor"));
    }
}
