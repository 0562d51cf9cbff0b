//! Obstacle selection (docs/maths.md §2.3): the obstacles whose signed
//! distance to `p_0` is at most [`Config::r_active`] (a moving one closing in
//! at a speed `c` above [`Config::vx_max`]: at most `r_active + (c - vx_max)
//! (tau + N T)`, so that over the horizon it comes no closer than one closing
//! in at `vx_max` from `r_active`), nearest first, at most `NOBS`, each
//! linearised as the half-plane at its boundary point closest to `p_0`
//! ([`ActiveObstacle`]). For a caller whose map is too large to scan
//! every cycle: the disk that holds every obstacle a cycle can select
//! ([`ObstacleQuery`], [`Controller::obstacle_query`]) and the candidates a
//! spatial index returns for it (`among`, the `candidates` of
//! [`Controller::step`]).

use nalgebra::Vector2;

use super::{Assembly, Config, Controller, CycleInput, InputError, MAX_RATE};
use crate::constraints::HalfPlane;
use crate::geometry::{ConvexPolygon, closest_point_point_polygon};
use crate::qp::QpBackend;
use crate::reach::{Reach, ReachLimits};

/// The disk, world frame W, that holds every obstacle a cycle can select:
/// [`Controller::obstacle_query`] for a caller that keeps its map in a spatial
/// index and passes only the candidates to [`Controller::step`].
///
/// A cycle selects obstacle `j` only if `closest_point_point_polygon(center,
/// P_j).signed_distance <= radius` (`center` is the cycle's `p_0`, `radius` is
/// [`Config::r_active`]), except a moving obstacle closing in faster than
/// [`Config::vx_max`], selected up to `radius + (c - vx_max) (tau + N T)` (`c
/// = eta'u`, m/s, its velocity `u` along the normal `eta` towards `center`):
/// a caller passes such obstacles whatever the query. A polygon within
/// `radius` has a point within `radius` of `center` (its closest point, or
/// `center` itself when inside), so its axis-aligned bounding box is within
/// `radius` of `center` too: an index query for the boxes within
/// [`ObstacleQuery::padded_radius`] of `center` returns every other obstacle
/// the cycle can select (the padding covers the rounding of both distance
/// computations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleQuery {
    /// The cycle's `p_0`, the predicted CoM position at the end of the current
    /// step, m (world frame W): exactly the point the selection measures from.
    pub center: Vector2<f64>,
    /// [`Config::r_active`], m.
    pub radius: f64,
}

impl ObstacleQuery {
    /// `radius` plus a margin for rounding, m: `radius (1 + 1e-9) + 1e-9 (1 +
    /// |center|_inf)`, i.e. about 1e-7 m for a centre 100 m from the origin.
    /// The controller's signed distance and an index's box distance are each
    /// within a few units in the last place of the true distance (relative
    /// error about 1e-15 for coordinates up to 1e6 m), far inside this margin,
    /// so a box within the true `radius` is always within `padded_radius` as
    /// computed. A larger query only passes a few more candidates, which the
    /// controller tests exactly.
    pub fn padded_radius(&self) -> f64 {
        let scale = 1.0 + self.center.x.abs().max(self.center.y.abs());
        self.radius * (1.0 + 1e-9) + 1e-9 * scale
    }
}

/// An obstacle used in this cycle's QP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveObstacle {
    /// Index in the caller's obstacle slice [`CycleInput::obstacles`] (also
    /// with the `candidates` of [`Controller::step`], which are such indices).
    pub index: u32,
    /// Signed distance from `p_0`, m.
    pub distance: f64,
    /// The LDCBF half-plane.
    pub half_plane: HalfPlane,
}

impl ActiveObstacle {
    /// All-zero placeholder (index 0, distance 0, zero half-plane).
    pub(super) const ZERO: ActiveObstacle = ActiveObstacle {
        index: 0,
        distance: 0.0,
        half_plane: HalfPlane {
            c: Vector2::new(0.0, 0.0),
            eta: Vector2::new(0.0, 0.0),
            rate: 0.0,
            reach: Reach::NONE,
        },
    };

    /// `*self = *other`, field by field: on the Cortex-M7 a copy of the whole
    /// struct (88 bytes) is a call to `memcpy`, about 110 instructions
    /// against a few dozen loads and stores (the insertion in
    /// `select_obstacles` makes several copies a cycle; firmware/README.md).
    #[inline(always)]
    fn assign(&mut self, other: &Self) {
        let (h, o) = (&mut self.half_plane, &other.half_plane);
        self.index = other.index;
        self.distance = other.distance;
        h.c.x = o.c.x;
        h.c.y = o.c.y;
        h.eta.x = o.eta.x;
        h.eta.y = o.eta.y;
        h.rate = o.rate;
        h.reach.spread = o.reach.spread;
        h.reach.speed = o.reach.speed;
    }
}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize, B: QpBackend<NV, NC>>
    Controller<N, NV, NC, NOBS, B>
{
    /// Where this cycle will look for obstacles: its `p_0` (the CoM predicted
    /// at the end of the current step, computed exactly as [`Controller::step`]
    /// computes it) and [`Config::r_active`]. For a caller whose map is too
    /// large to scan every cycle: query a spatial index with it, then call
    /// [`Controller::step`] with the result as `candidates`. `Err` when `step` would
    /// reject the input (the obstacles do not matter then). Costs one LIP
    /// propagation; reads no obstacle.
    pub fn obstacle_query<const V: usize>(
        &self,
        input: &CycleInput<'_, V>,
    ) -> Result<ObstacleQuery, InputError> {
        let mut time_clamped = false;
        let (p0, _, _) = self.core.end_of_step(input, &mut time_clamped)?;
        Ok(ObstacleQuery {
            center: p0,
            radius: self.core.config.r_active,
        })
    }
}

/// `(index, obstacle)` for each in-range index of `candidates`, in order.
pub(super) fn among<'a, const V: usize>(
    obstacles: &'a [ConvexPolygon<V>],
    candidates: &'a [u32],
) -> impl Iterator<Item = (usize, &'a ConvexPolygon<V>)> + 'a {
    candidates.iter().filter_map(move |&i| {
        let i = i as usize;
        obstacles.get(i).map(|p| (i, p))
    })
}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>
    Assembly<N, NV, NC, NOBS>
{
    /// Selects the active obstacles of `obstacles` (`(index in
    /// input.obstacles, polygon)`, in the order the selection sees them):
    /// those whose signed distance to `p0` (m, world) is at most
    /// [`Config::r_active`], and each moving one closing in faster than
    /// [`Config::vx_max`] (`c = eta'u > vx_max`, `u` its velocity
    /// `velocities[index]`, m/s, world, `eta` the unit normal from it towards
    /// `p0`; a NaN `c` counts as at rest) whose signed distance is at most
    /// `r_active + (c - vx_max) horizon` (`horizon = tau + N T`, s: the radius
    /// grows by the distance such an obstacle gains over the horizon on one
    /// closing in at `vx_max`), nearest first (ties in the order seen), at
    /// most `NOBS` (the farthest drop out: [`Assembly::obstacles_truncated`]).
    /// Each is linearised where it is now; its half-plane moves with the
    /// obstacle's velocity `velocities[index]` (at rest when `velocities` is
    /// empty), whose component along the normal is [`HalfPlane::rate`].
    /// With `turn` ([`Config::turn_vertex_normals`]) the half-plane of an
    /// obstacle at rest whose point closest to `p0` is a vertex is turned
    /// along the cycle's [`Way`] (`turned_normal`).
    /// With [`Config::velocity_margin`], an obstacle of velocity uncertainty
    /// radius `radii[index] > 0` (m/s; none: 0) is also selected up to
    /// `r_active` plus the excess of its reach over the horizon
    /// ([`Reach::shift`] within `lim`, the controller's [`ReachLimits`],
    /// along the normal minus `vx_max horizon`), and its half-plane carries
    /// that [`Reach`] (docs/maths.md §2.7).
    /// Writes `obstacles`, `n_obstacles` and `obstacles_truncated`.
    /// `Err(InputError::ObstacleVelocity)` when a selected obstacle's
    /// velocity is missing, not finite or faster than [`MAX_RATE`],
    /// `Err(InputError::ObstacleVelocityRadius)` when its radius is missing,
    /// negative, not finite or larger than [`MAX_RATE`] (the selection is
    /// then incomplete and must not be used).
    pub(super) fn select_obstacles<'o, const V: usize>(
        &mut self,
        p0: &Vector2<f64>,
        turn: Option<Way<'_>>,
        (cfg, lim): (&Config, &ReachLimits),
        horizon: f64,
        obstacles: impl Iterator<Item = (usize, &'o ConvexPolygon<V>)>,
        (velocities, radii): (&[Vector2<f64>], &[f64]),
    ) -> Result<(), InputError> {
        self.n_obstacles = 0;
        self.obstacles_truncated = false;
        for (idx, poly) in obstacles {
            let Ok(index) = u32::try_from(idx) else {
                self.obstacles_truncated = true;
                break;
            };
            let cp = closest_point_point_polygon(p0, poly);
            // False for a NaN distance (impossible for validated polygons):
            // such an obstacle is skipped.
            let within = |radius: f64| cp.signed_distance <= radius;
            let velocity = velocities.get(idx);
            // The radius as given (validated once selected; NaN counts as 0
            // until then).
            let spread = if cfg.velocity_margin {
                radii.get(idx).copied().unwrap_or(0.0)
            } else {
                0.0
            };
            if !within(cfg.r_active) {
                // Beyond `r_active` (which holds an obstacle closing in no
                // faster than the robot walks), one closing in faster than
                // `vx_max` gains the excess over the horizon; one of
                // uncertain velocity the excess of its reach.
                let closing = velocity.map_or(0.0, |u| cp.normal.dot(u));
                let excess = (closing - cfg.vx_max).max(0.0);
                let mut gain = excess * horizon;
                if spread > 0.0 {
                    let speed = velocity.map_or(0.0, |u| crate::linalg::sqrt(u.norm_squared()));
                    let far =
                        Reach { spread, speed }.shift(lim, closing, horizon) - cfg.vx_max * horizon;
                    gain = gain.max(far);
                }
                if !within(cfg.r_active + gain) {
                    continue;
                }
            }
            let (rate, speed) = if velocities.is_empty() {
                (0.0, 0.0)
            } else {
                let u = velocity.ok_or(InputError::ObstacleVelocity)?;
                let speed = crate::linalg::sqrt(u.norm_squared());
                if speed.is_nan() || speed > MAX_RATE {
                    return Err(InputError::ObstacleVelocity);
                }
                // `+ 0.0` turns the -0 of a zero velocity into +0, so that an
                // obstacle at rest is recorded as with an empty slice.
                (cp.normal.dot(u) + 0.0, speed)
            };
            if !radii.is_empty() {
                let r = radii.get(idx).ok_or(InputError::ObstacleVelocityRadius)?;
                // `!(..)` is also true for NaN.
                if !(*r >= 0.0 && *r <= MAX_RATE) {
                    return Err(InputError::ObstacleVelocityRadius);
                }
            }
            let reach = if spread > 0.0 {
                Reach { spread, speed }
            } else {
                Reach::NONE
            };
            // (A moving obstacle's rate is along the closest-point normal.)
            let eta = match &turn {
                Some(w) if rate == 0.0 && !reach.is_uncertain() => {
                    turned_normal(p0, w.goal, w.heading, poly, &cp, w.margin)
                }
                _ => cp.normal,
            };
            let cand = ActiveObstacle {
                index,
                distance: cp.signed_distance,
                half_plane: HalfPlane {
                    c: cp.point,
                    eta,
                    rate,
                    reach,
                },
            };
            // Insertion into the sorted list (bounded by NOBS), after every kept
            // obstacle that is not farther.
            let n = self.n_obstacles.min(NOBS);
            let pos = self.obstacles[..n]
                .iter()
                .rposition(|o| o.distance <= cand.distance)
                .map_or(0, |i| i + 1);
            if pos >= NOBS {
                self.obstacles_truncated = true; // full; not nearer than the farthest
                continue;
            }
            let len = if n == NOBS {
                self.obstacles_truncated = true; // the farthest drops out
                n
            } else {
                n + 1
            };
            // Put it at `pos`; each farther one moves one slot back (from the
            // end, each slot takes its predecessor's obstacle).
            let mut slots = self.obstacles[pos.min(len)..len].iter_mut().rev();
            if let Some(mut dst) = slots.next() {
                for src in slots {
                    dst.assign(src);
                    dst = src;
                }
                dst.assign(&cand);
            }
            self.n_obstacles = len;
        }
        Ok(())
    }
}

/// Where a cycle goes, for turning the half-planes at vertices
/// ([`Config::turn_vertex_normals`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Way<'a> {
    /// The cycle's goal (or subgoal), m, world.
    pub goal: &'a Vector2<f64>,
    /// The body's heading at `p_0`, rad.
    pub heading: f64,
    /// [`Config::barrier_margin`], m (the controller's, computed once).
    pub margin: f64,
}

/// The half-plane's normal at a vertex `c` closest to `p0` (outside): of the
/// supporting half-planes at `c` (normals in the vertex's normal cone), the
/// one turned from `eta* = (p0 - c)/|p0 - c|` towards the edge normal that
/// blocks the way to `goal` least (docs/maths.md §2.3). The turn stops at
/// the first of: that edge normal; across the way to the goal (`eta'd = 0`);
/// where `p0` would keep less than half of its clearance beyond `margin`
/// (its distance to `c` minus `margin`); and where the
/// half-plane would block the way along `heading` (rad, the body's, where
/// the robot's momentum goes) more than `eta*` does, or at all if `eta*`
/// does not. Elsewhere (on an edge, inside, the goal's way not blocked, or
/// a turn that would block it more at first) the closest-point normal.
fn turned_normal<const V: usize>(
    p0: &Vector2<f64>,
    goal: &Vector2<f64>,
    heading: f64,
    poly: &ConvexPolygon<V>,
    cp: &crate::geometry::ClosestPoint,
    margin: f64,
) -> Vector2<f64> {
    let eta = cp.normal;
    if cp.location != crate::geometry::PointLocation::Outside {
        return eta;
    }
    let to_goal = goal - p0;
    let len = crate::linalg::sqrt(to_goal.norm_squared());
    if len.is_nan() || len <= 1e-6 {
        return eta;
    }
    let d = to_goal / len;
    let ed = eta.dot(&d);
    if ed.is_nan() || ed >= 0.0 {
        return eta;
    }
    let Some((n_in, n_out)) = poly.edge_normals_at(&cp.point) else {
        return eta;
    };
    let ne = if n_in.dot(&d) >= n_out.dot(&d) {
        n_in
    } else {
        n_out
    };
    // Unit tangent from eta towards ne: `eta(a) = cos a eta + sin a t`.
    let t = ne - eta * ne.dot(&eta);
    let tl = crate::linalg::sqrt(t.norm_squared());
    if tl.is_nan() || tl <= 1e-12 {
        return eta;
    }
    let t = t / tl;
    // `eta(a)'d = cos a eta'd + sin a t'd` must grow from `eta'd < 0`.
    let td = t.dot(&d);
    if td.is_nan() || td <= 0.0 {
        return eta;
    }
    // The four limits, as angles of turn (rad, each >= 0).
    let edge = libm::atan2(ne.dot(&t), ne.dot(&eta));
    let across = libm::atan2(td, ed) - core::f64::consts::FRAC_PI_2;
    let rho = cp.signed_distance;
    // `p0` keeps at least half of its clearance beyond the margin.
    let keep = if rho > margin {
        libm::acos((0.5 * (margin + rho)) / rho)
    } else {
        0.0
    };
    // Along the heading `u`: `eta(a)'u = R cos(a - alpha) >= min(eta'u, 0)`
    // holds at `a = 0` and up to `alpha + acos(min(eta'u, 0) / R)`.
    let (sh, ch) = libm::sincos(heading);
    let u = Vector2::new(ch, sh);
    let (eu, tu) = (eta.dot(&u), t.dot(&u));
    let r = crate::linalg::sqrt(eu * eu + tu * tu);
    let momentum = if r > 1e-12 {
        libm::atan2(tu, eu) + libm::acos((eu.min(0.0) / r).clamp(-1.0, 1.0))
    } else {
        f64::INFINITY
    };
    let a = edge.min(across).min(keep).min(momentum);
    if a.is_nan() || a <= 0.0 {
        return eta;
    }
    let (sa, ca) = libm::sincos(a);
    let out = eta * ca + t * sa;
    out / crate::linalg::sqrt(out.norm_squared())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::PointLocation;
    use proptest::prelude::*;

    fn cell(x: f64, y: f64, side: f64) -> ConvexPolygon<4> {
        ConvexPolygon::new(&[[x, y], [x + side, y], [x + side, y + side], [x, y + side]]).unwrap()
    }

    /// A one-cell piece just in front of a corridor's right wall, 0.33 m
    /// ahead of the CoM, with the goal straight ahead (corridor 209 of the
    /// second unseen set): the closest-point normal points back at the robot
    /// (a half-plane across the corridor); turned until the CoM keeps half
    /// of its clearance beyond the margin, 13 degrees from the cell's
    /// top-face normal, walking 0.3 m ahead costs 7 cm of `h` instead of
    /// 20 cm.
    #[test]
    fn a_cell_ahead_gives_a_half_plane_along_the_way() {
        let p0 = Vector2::new(0.9, 0.0);
        let goal = Vector2::new(5.0, 0.0);
        let bump = cell(1.225, -0.375, 0.025);
        let cp = closest_point_point_polygon(&p0, &bump);
        assert_eq!(cp.location, PointLocation::Outside);
        let margin = 0.3506;
        let eta = turned_normal(&p0, &goal, 0.0, &bump, &cp, margin);
        // p0 keeps half of its clearance beyond the margin, exactly.
        let rho = cp.signed_distance;
        let kept = eta.dot(&(p0 - cp.point));
        assert!((kept - 0.5 * (margin + rho)).abs() < 1e-12, "{eta}");
        let ahead = Vector2::new(0.3, 0.0);
        let drop_closest = -cp.normal.dot(&ahead);
        let drop_turned = -eta.dot(&ahead);
        assert!(drop_closest > 0.2, "{drop_closest}");
        assert!(drop_turned < 0.07, "{drop_turned}");
        // Moving away (goal behind), or on an edge: the closest-point normal.
        let back = Vector2::new(-5.0, 0.0);
        assert_eq!(
            turned_normal(&p0, &back, 0.0, &bump, &cp, margin),
            cp.normal
        );
        let beside = Vector2::new(1.2375, 0.0);
        let cp2 = closest_point_point_polygon(&beside, &bump);
        assert_eq!(
            turned_normal(&beside, &goal, 0.0, &bump, &cp2, margin),
            cp2.normal
        );
    }

    proptest! {
        /// Whatever the polygon, point, goal and heading: the turned normal
        /// is a unit vector whose half-plane at `c` holds the whole polygon
        /// (every vertex on its far side), keeps `p0` at least `min(d, (d +
        /// margin) / 2)` from it (`d` its distance to the polygon), and
        /// blocks neither the way to the goal more than the closest-point
        /// normal nor the heading more than `min(eta*'u, 0)`.
        #[test]
        fn the_turned_half_plane_still_separates(
            pts in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 3..8),
            p in (-3.0f64..3.0, -3.0f64..3.0),
            g in (-5.0f64..5.0, -5.0f64..5.0),
            margin in 0.0f64..1.0,
            heading in -4.0f64..4.0,
        ) {
            let pts: heapless::Vec<[f64; 2], 8> = pts.iter().map(|&(x, y)| [x, y]).collect();
            let Ok(poly) = ConvexPolygon::<8>::hull(&pts) else { return Ok(()) };
            let p0 = Vector2::new(p.0, p.1);
            let goal = Vector2::new(g.0, g.1);
            let cp = closest_point_point_polygon(&p0, &poly);
            let eta = turned_normal(&p0, &goal, heading, &poly, &cp, margin);
            prop_assert!((eta.norm() - 1.0).abs() < 1e-9, "{eta}");
            for v in poly.vertices() {
                prop_assert!(eta.dot(&(v - cp.point)) <= 1e-9, "vertex {v} beyond {eta}");
            }
            if cp.location == PointLocation::Outside {
                let rho = cp.signed_distance;
                let keep = rho.min(0.5 * (margin + rho));
                prop_assert!(eta.dot(&(p0 - cp.point)) >= keep - 1e-9);
                let d = goal - p0;
                prop_assert!(eta.dot(&d) >= cp.normal.dot(&d) - 1e-9 * (1.0 + d.norm()));
                let u = Vector2::new(heading.cos(), heading.sin());
                prop_assert!(eta.dot(&u) >= cp.normal.dot(&u).min(0.0) - 1e-9);
            } else {
                prop_assert_eq!(eta, cp.normal);
            }
        }
    }
}
