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
        },
    };
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
    /// Writes `obstacles`, `n_obstacles` and `obstacles_truncated`.
    /// `Err(InputError::ObstacleVelocity)` when a selected obstacle's
    /// velocity is missing, not finite or faster than [`MAX_RATE`] (the
    /// selection is then incomplete and must not be used).
    pub(super) fn select_obstacles<'o, const V: usize>(
        &mut self,
        p0: &Vector2<f64>,
        cfg: &Config,
        horizon: f64,
        obstacles: impl Iterator<Item = (usize, &'o ConvexPolygon<V>)>,
        velocities: &[Vector2<f64>],
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
            if !within(cfg.r_active) {
                // Beyond `r_active` (which holds an obstacle closing in no
                // faster than the robot walks), one closing in faster than
                // `vx_max` gains the excess over the horizon.
                let closing = velocities.get(idx).map_or(0.0, |u| cp.normal.dot(u));
                let excess = (closing - cfg.vx_max).max(0.0);
                if !within(cfg.r_active + excess * horizon) {
                    continue;
                }
            }
            let rate = if velocities.is_empty() {
                0.0
            } else {
                let u = velocities.get(idx).ok_or(InputError::ObstacleVelocity)?;
                let speed = crate::linalg::sqrt(u.norm_squared());
                if speed.is_nan() || speed > MAX_RATE {
                    return Err(InputError::ObstacleVelocity);
                }
                // `+ 0.0` turns the -0 of a zero velocity into +0, so that an
                // obstacle at rest is recorded as with an empty slice.
                cp.normal.dot(u) + 0.0
            };
            let cand = ActiveObstacle {
                index,
                distance: cp.signed_distance,
                half_plane: HalfPlane {
                    c: cp.point,
                    eta: cp.normal,
                    rate,
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
                    *dst = *src;
                    dst = src;
                }
                *dst = cand;
            }
            self.n_obstacles = len;
        }
        Ok(())
    }
}
