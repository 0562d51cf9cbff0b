//! The QP of one cycle (docs/maths.md §2.1-2.5): from the validated input,
//! the prediction of `x_0`, the headings, the active obstacles, the cost and
//! every row (gait, LDCBF, foot clearance), each named by its [`RowId`].

use super::{Assembly, Core, CycleInput, InputError, Prediction};
use crate::constraints::{
    GaitBounds, RowId, RowKind, StepSpan, push_foot_row, push_gait_rows, push_ldcbf_row,
};
use crate::geometry::ConvexPolygon;
use crate::heading::{plan_heading, wrap_angle};

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// docs/maths.md §2.1-2.5 into `out`, the obstacles being `obstacles`:
    /// `(index in input.obstacles, polygon)` in the order the selection sees
    /// them (all of `input.obstacles`, or a caller's candidates).
    pub(super) fn assemble<'o, const V: usize, const NOBS: usize>(
        &self,
        input: &CycleInput<'_, V>,
        obstacles: impl Iterator<Item = (usize, &'o ConvexPolygon<V>)>,
        out: &mut Assembly<N, NV, NC, NOBS>,
    ) -> Result<(), InputError> {
        let (p0, v0, tau) = self.end_of_step(input, &mut out.time_clamped)?;
        let cfg = &self.config;
        let t_step = cfg.step_duration;
        let theta0 = wrap_angle(input.heading + input.turning_rate * tau);
        if !theta0.is_finite() {
            return Err(InputError::State);
        }
        // 2. Headings.
        let heading = plan_heading::<N>(
            theta0,
            [p0.x, p0.y],
            [input.goal.x, input.goal.y],
            t_step,
            cfg.omega_max,
            cfg.heading_freeze_radius,
        );
        let first_side = input.stance_side.opposite();
        out.prediction = Prediction {
            p0,
            v0,
            heading,
            first_side,
            goal: input.goal,
            time_to_p0: tau,
        };

        // 3. Active obstacles: within r_active of p_0 (one closing in faster
        // than vx_max: farther by the excess over the horizon), nearest first,
        // at most NOBS.
        let horizon = tau + N as f64 * t_step;
        let way = cfg.turn_vertex_normals.then_some(super::select::Way {
            goal: &input.goal,
            heading: theta0,
            margin: self.barrier_margin,
        });
        out.select_obstacles(
            &p0,
            way,
            (cfg, &self.limits),
            horizon,
            obstacles,
            (input.obstacle_velocities, input.obstacle_velocity_radii),
        )?;

        // 4-5. Cost and rows.
        out.qp.clear();
        let (q, c) = self.model.gradient::<NV>(&input.goal);
        out.qp.q = q;
        out.cost_constant = c;
        // Near a moving obstacle (or one of uncertain velocity), no faster
        // than the robot can stop in one step, reached as fast as it can
        // brake.
        let vx_max = self.forward_speed_bounds(
            &out.obstacles[..out.n_obstacles.min(NOBS)],
            input.obstacle_velocities,
            tau,
            &v0,
            heading.omega_bar,
        );
        // The host's speed cap tightens the longitudinal upper bound only
        // (`CycleInput::speed_cap`); no cap keeps the bounds above bit for bit.
        let cap = if input.speed_cap >= 0.0 {
            input.speed_cap
        } else {
            0.0
        };
        let mut bounds = GaitBounds {
            vx_min: cfg.vx_min,
            vx_max: cfg.vx_max,
            vy_min: cfg.vy_min,
            vy_max: cfg.vy_max,
            l_max: cfg.l_max,
            alpha: cfg.alpha,
        };
        // Capacity is guaranteed by the compile-time check NC >= 8N + N NOBS and by
        // `new` for the foot rows; a failed push would only drop rows, so it is
        // checked anyway and reported as a numerical failure by the caller.
        let mut ok = true;
        let mut side = first_side;
        for (k, &vx) in vx_max.iter().enumerate() {
            let m_before = out.qp.m;
            bounds.vx_max = if cap < vx { cap.max(cfg.vx_min) } else { vx };
            ok &= push_gait_rows(
                &mut out.qp,
                &self.model,
                &bounds,
                k,
                heading.theta[k],
                side.sign(),
                heading.omega_bar,
                &p0,
                &v0,
            )
            .is_ok();
            for (r, kind) in RowKind::GAIT.iter().enumerate() {
                if let Some(slot) = out.rows.get_mut(m_before + r) {
                    *slot = RowId {
                        kind: *kind,
                        k: k as u8,
                    };
                }
            }
            side = side.opposite();
        }
        // Step end k is at t_k = tau + k T from the input; a moving obstacle's
        // half-plane is taken there (`HalfPlane::h_at`).
        let step = |k: usize| StepSpan {
            k,
            times: (tau + k as f64 * t_step, tau + (k + 1) as f64 * t_step),
            p0,
            v0,
        };
        let lim = &self.limits;
        for ob in &out.obstacles[..out.n_obstacles.min(NOBS)] {
            for k in 0..N {
                let i = out.qp.m;
                ok &= push_ldcbf_row(
                    &mut out.qp,
                    &self.model,
                    &ob.half_plane,
                    lim,
                    cfg.gamma,
                    self.barrier_margin,
                    &step(k),
                )
                .is_ok();
                if let Some(slot) = out.rows.get_mut(i) {
                    *slot = RowId {
                        kind: RowKind::Ldcbf(ob.index),
                        k: k as u8,
                    };
                }
            }
        }
        if cfg.foot_clearance.is_some() {
            for ob in &out.obstacles[..out.n_obstacles.min(NOBS)] {
                for k in 0..N {
                    let i = out.qp.m;
                    let df = cfg.foot_margin(&ob.half_plane.eta, heading.theta[k]);
                    ok &=
                        push_foot_row(&mut out.qp, &self.model, &ob.half_plane, lim, df, &step(k))
                            .is_ok();
                    if let Some(slot) = out.rows.get_mut(i) {
                        *slot = RowId {
                            kind: RowKind::FootClearance(ob.index),
                            k: k as u8,
                        };
                    }
                }
            }
        }
        debug_assert!(ok, "row capacity exceeded despite compile-time check");
        Ok(())
    }
}
