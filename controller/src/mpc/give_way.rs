//! The policy toward a person who walks into the robot (docs/safety.md, "A
//! person walking into the robot"): when the nominal QP is infeasible and its
//! infeasibility certificate weighs a safety row of a moving obstacle, the
//! robot gives way. The priority scheme of [`crate::relax`] then plans with the
//! goal replaced by a point behind the robot, away from the people in the
//! conflict ([`Core::give_way_goal`]): the cost no longer pulls towards the
//! goal (which would spend the relaxed margin on walking into the person) but
//! away from them, so the relaxed plan steps back or aside as far as the gait
//! rows allow, or stands when it cannot.
//!
//! The rows, the relaxation amounts and the stages are unchanged (the smallest
//! relaxation does not depend on the cost); only the choice among the plans
//! of the relaxed problem changes, and only on cycles whose conflict holds a
//! moving obstacle, so no cycle with obstacles at rest changes by a bit. The
//! nominal cost is restored before the cycle reports it.

use nalgebra::{SVector, Vector2};

use super::{ActiveObstacle, Assembly, Core};
use crate::constraints::RowKind;

/// How far behind `p_0` the give-way goal lies, m, along the mean normal from
/// the people in the conflict to the robot: far enough that every step of the
/// horizon moves away at the speed the gait rows allow (`vx_min` backwards,
/// the lateral bounds sideways: at most about 0.4 m/s over `3 T = 1.2 s`).
pub const GIVE_WAY_DISTANCE: f64 = 1.0;

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// The forward speed bound of each step's gait rows, m/s (body frame;
    /// entry `k` bounds `v_{k+1}`): [`Config::vx_max`](super::Config::vx_max)
    /// for every step, unless a selected obstacle moves and robot and
    /// obstacle could meet within the horizon (its signed distance from
    /// `p_0` is at most `(|u| + vx_max) (tau + N T)`, `u` its velocity,
    /// `velocities[index]`, world frame W, none or zero: at rest; `tau` the
    /// time to `p_0`, s; for an obstacle of uncertain velocity at most
    /// `vx_max (tau + N T)` plus the farthest it may walk by then,
    /// [`Reach::travel`](crate::reach::Reach::travel)). Then the bound comes down to the one-step stopping
    /// speed `stop = beta tanh(beta T) l_max` (0.46 m/s for Table I) as fast
    /// as the robot can brake: entry `k` is `min(vx_max, max(stop, s_{k+1} +
    /// turn + 0.02))` with `s_0 = |v_0|`, `s_{k+1} = cosh(beta T) s_k - beta
    /// sinh(beta T) l_max` (the step map of [`crate::relax`] with the foot at
    /// the edge of reach: the fastest braking) and `turn = alpha |omega_bar|
    /// / pi` (the turning term the forward row subtracts), so the lowered
    /// rows never make a cycle infeasible by themselves.
    ///
    /// From `v <= stop` one step with the foot at the edge of reach brings
    /// the LIP to rest (`cosh(beta T) v - beta sinh(beta T) l_max <= 0`): near
    /// people the robot walks no faster than it can stop within one step.
    /// Without moving obstacles every bound is `vx_max` (the static rows bit
    /// for bit).
    pub(super) fn forward_speed_bounds(
        &self,
        active: &[ActiveObstacle],
        velocities: &[Vector2<f64>],
        tau: f64,
        v0: &Vector2<f64>,
        omega_bar: f64,
    ) -> [f64; N] {
        let cfg = &self.config;
        let mut out = [cfg.vx_max; N];
        let horizon = tau + N as f64 * cfg.step_duration;
        let lim = &self.limits;
        let near = active.iter().any(|o| {
            let reach = &o.half_plane.reach;
            if reach.is_uncertain() {
                // Within the farthest the person may walk, plus the robot.
                return o.distance <= cfg.vx_max * horizon + reach.travel(lim, horizon);
            }
            velocities.get(o.index as usize).is_some_and(|u| {
                let speed = crate::linalg::sqrt(u.norm_squared());
                speed > 0.0 && o.distance <= (speed + cfg.vx_max) * horizon
            })
        });
        if !near {
            return out;
        }
        let lip = &self.lip;
        let stop = lip.beta * (lip.sinh_bt / lip.cosh_bt) * cfg.l_max;
        let cosh = lip.cosh_bt;
        let brake = lip.beta * lip.sinh_bt * cfg.l_max;
        let turn = cfg.alpha / core::f64::consts::PI * omega_bar.abs();
        let mut s = crate::linalg::sqrt(v0.norm_squared());
        for b in &mut out {
            s = cosh * s - brake;
            let ramp = s + turn + 0.02;
            let bound = if ramp > stop { ramp } else { stop };
            if bound < cfg.vx_max {
                *b = bound;
            }
        }
        out
    }

    /// The safety rows (LDCBF and foot clearance) of `work.qp` that belong to
    /// a moving obstacle ([`HalfPlane::moves`](crate::HalfPlane::moves): a
    /// nonzero rate or an uncertain velocity), by row: on a cycle that
    /// gives way they are relaxed before the static ones
    /// ([`crate::relax`], "Moving rows first").
    pub(super) fn moving_rows<const NOBS: usize>(work: &Assembly<N, NV, NC, NOBS>) -> [bool; NC] {
        let active = work.active_obstacles();
        let mut out = [false; NC];
        for (o, id) in out.iter_mut().zip(&work.rows).take(work.qp.m) {
            if let RowKind::Ldcbf(j) | RowKind::FootClearance(j) = id.kind {
                *o = active
                    .iter()
                    .any(|ob| ob.index == j && ob.half_plane.moves());
            }
        }
        out
    }

    /// The goal the priority scheme plans towards on an infeasible cycle
    /// whose infeasibility certificate `certificate` (one weight per row of
    /// `work.qp`, as [`crate::qp::QpSolution::lambda`] of the infeasible
    /// solve) weighs a safety row (LDCBF or foot clearance) of a moving
    /// obstacle ([`HalfPlane::moves`](crate::HalfPlane::moves)): `p_0 + GIVE_WAY_DISTANCE a`, `a`
    /// the unit vector along the certificate-weighted sum of those rows'
    /// normals `eta` (from the obstacle to the robot, world frame W); `p_0`
    /// itself (stand) when that sum vanishes. `None` when no such row is
    /// weighed: the cycle keeps its goal.
    pub(super) fn give_way_goal<const NOBS: usize>(
        &self,
        work: &Assembly<N, NV, NC, NOBS>,
        certificate: &SVector<f64, NC>,
    ) -> Option<Vector2<f64>> {
        let active = work.active_obstacles();
        let mut away = Vector2::zeros();
        let mut moving = false;
        for (id, &y) in work.rows.iter().zip(certificate.iter()).take(work.qp.m) {
            let index = match id.kind {
                RowKind::Ldcbf(j) | RowKind::FootClearance(j) => j,
                _ => continue,
            };
            // Zero, negative and NaN weights are not in the conflict.
            if y.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
                continue;
            }
            if let Some(ob) = active
                .iter()
                .find(|o| o.index == index && o.half_plane.moves())
            {
                moving = true;
                away += ob.half_plane.eta * y;
            }
        }
        if !moving {
            return None;
        }
        let p0 = work.prediction.p0;
        let norm = crate::linalg::sqrt(away.norm_squared());
        if norm > 0.0 && norm.is_finite() {
            Some(p0 + away * (GIVE_WAY_DISTANCE / norm))
        } else {
            Some(p0)
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{SVector, Vector2};

    use crate::constraints::{RowId, RowKind};
    use crate::geometry::ConvexPolygon;
    use crate::mpc::{Assembly, Config, PaperController, RecordedInput};

    const NC: usize = 48;

    /// A person of side 0.4 m at (1.2, 0) ahead of a robot at rest at the
    /// origin (end of a step, so `p_0` is the origin) with its goal beyond
    /// them; `velocity` theirs.
    fn assembled(velocity: Vector2<f64>) -> (PaperController, Assembly<3, 6, NC, 8>) {
        let person = [
            ConvexPolygon::<8>::new(&[[1.0, -0.2], [1.4, -0.2], [1.4, 0.2], [1.0, 0.2]]).unwrap(),
        ];
        let velocities = [velocity];
        let cfg = Config::default();
        let input = RecordedInput {
            time_in_step: cfg.step_duration,
            ..RecordedInput::at_rest(Vector2::new(5.0, 0.0))
        }
        .input_moving(&person, &velocities);
        let ctl = PaperController::new(cfg).unwrap();
        let mut asm = Assembly::EMPTY;
        ctl.assemble(&input, None, &mut asm).unwrap();
        (ctl, asm)
    }

    /// A certificate of weight 1 on the rows of kind `kind` at step 0.
    fn weight_on(asm: &Assembly<3, 6, NC, 8>, kind: RowKind) -> SVector<f64, NC> {
        let mut y = SVector::<f64, NC>::zeros();
        for (w, id) in y.iter_mut().zip(&asm.rows).take(asm.qp.m) {
            if *id == (RowId { kind, k: 0 }) {
                *w = 1.0;
            }
        }
        assert!(y.sum() > 0.0, "no row {kind:?}");
        y
    }

    #[test]
    fn a_person_in_the_conflict_moves_the_goal_behind_the_robot() {
        let (ctl, asm) = assembled(Vector2::new(-1.0, 0.0));
        let y = weight_on(&asm, RowKind::Ldcbf(0));
        let goal = ctl.core.give_way_goal(&asm, &y).unwrap();
        let p0 = asm.prediction.p0;
        // Straight back, away from the person ahead, GIVE_WAY_DISTANCE behind p_0.
        let expected = p0 + Vector2::new(-super::GIVE_WAY_DISTANCE, 0.0);
        assert!((goal - expected).norm() < 1e-12, "{goal:?}");
    }

    #[test]
    fn without_a_moving_row_in_the_conflict_the_goal_stays() {
        // The same person at rest: their rows are static ones.
        let (ctl, asm) = assembled(Vector2::zeros());
        let y = weight_on(&asm, RowKind::Ldcbf(0));
        assert_eq!(ctl.core.give_way_goal(&asm, &y), None);
        // Moving, but the certificate weighs only gait rows.
        let (ctl, asm) = assembled(Vector2::new(-1.0, 0.0));
        let y = weight_on(&asm, RowKind::VelLonUpper);
        assert_eq!(ctl.core.give_way_goal(&asm, &y), None);
    }
}
