//! The fallback commands (the rules are in the module docs of [`crate::mpc`]):
//! when the priority scheme cannot finish, the previous cycle's plan (shifted)
//! or the capture steps, chosen by this cycle's rows, rolled out on the LIP;
//! for an invalid input, the hold command.

use nalgebra::{SVector, Vector2};

use super::{
    Assembly, CommandSource, Core, CycleInfo, CycleInput, CycleOutput, CycleStatus, InputError,
    LipState, Memory, Plan, Prediction,
};
use crate::relax;

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// The fallback command (see the module docs): of the previous plan (shifted)
    /// and the capture steps, the first that satisfies every row of this cycle's
    /// QP; otherwise the one that keeps leg reachability with the smaller largest
    /// safety-row violation (the previous plan on ties). So the fallback never
    /// violates an LDCBF row that the other candidate satisfies.
    pub(super) fn fallback<const NOBS: usize>(
        &self,
        memory: &Memory<NV>,
        shift: usize,
        work: &Assembly<N, NV, NC, NOBS>,
    ) -> (SVector<f64, NV>, SVector<f64, NV>, CommandSource) {
        let tol = 10.0 * self.config.tol_primal;
        let pred = &work.prediction;
        let capture = self.capture_step(pred);
        let cap_z = self.model.variables_from_feet(&pred.p0, &pred.v0, &capture);
        let cap_v = relax::class_violation(&work.qp, &work.rows, &cap_z);
        let Some(prev) = self.previous_plan(memory, shift) else {
            return (capture, cap_z, CommandSource::CaptureStep);
        };
        let prev_z = self.model.variables_from_feet(&pred.p0, &pred.v0, &prev);
        let prev_v = relax::class_violation(&work.qp, &work.rows, &prev_z);
        let all = |v: &relax::ClassViolation| v.max() <= tol;
        let use_prev = if all(&prev_v) {
            true
        } else if all(&cap_v) {
            false
        } else if (prev_v.reach <= tol) != (cap_v.reach <= tol) {
            prev_v.reach <= tol
        } else {
            prev_v.safety <= cap_v.safety
        };
        if use_prev {
            (prev, prev_z, CommandSource::PreviousPlan)
        } else {
            (capture, cap_z, CommandSource::CaptureStep)
        }
    }

    /// The previous plan shifted by `shift` steps (the last foot extrapolated by
    /// the last stride); `None` without a finite previous plan.
    fn previous_plan(&self, memory: &Memory<NV>, shift: usize) -> Option<SVector<f64, NV>> {
        if !memory.has_plan {
            return None;
        }
        let old = &memory.plan;
        let mut u = SVector::<f64, NV>::zeros();
        for k in 0..N {
            let src = k + shift;
            let (x, y) = if src < N {
                (old[2 * src], old[2 * src + 1])
            } else if N >= 2 {
                let last = N - 1;
                (
                    2.0 * old[2 * last] - old[2 * last - 2],
                    2.0 * old[2 * last + 1] - old[2 * last - 1],
                )
            } else {
                (old[0], old[1])
            };
            u[2 * k] = x;
            u[2 * k + 1] = y;
        }
        u.iter().all(|v| v.is_finite()).then_some(u)
    }

    /// Capture steps: `f_k = p_k + clamp_box(R(theta_k)' v_k / beta, l_max)` for
    /// `k = 0..N-1`, each from the state the previous capture step leads to, so
    /// every foot honours leg reachability.
    fn capture_step(&self, pred: &Prediction<N>) -> SVector<f64, NV> {
        let l = self.config.l_max;
        let (mut p, mut v) = (pred.p0, pred.v0);
        let mut u = SVector::<f64, NV>::zeros();
        for k in 0..N {
            let th = pred.heading.theta[k];
            let (s, c) = libm::sincos(th);
            let xi = v / self.lip.beta;
            let lon = crate::linalg::clamp(c * xi.x + s * xi.y, -l, l);
            let lat = crate::linalg::clamp(-s * xi.x + c * xi.y, -l, l);
            let f = p + Vector2::new(c * lon - s * lat, s * lon + c * lat);
            u[2 * k] = f.x;
            u[2 * k + 1] = f.y;
            (p, v) = self.lip.propagate(&p, &v, &f, self.config.step_duration);
        }
        u
    }

    /// The plan of a fallback given by its feet `u` (interleaved): the LIP rolled
    /// forward from `x_0`.
    pub(super) fn rollout(
        &self,
        pred: &Prediction<N>,
        u: &SVector<f64, NV>,
        omega: f64,
    ) -> Plan<N> {
        let mut states = [LipState::default(); N];
        let mut feet = [Vector2::zeros(); N];
        let (mut p, mut v) = (pred.p0, pred.v0);
        let mut th = pred.heading.theta[0];
        for k in 0..N {
            let f = Vector2::new(u[2 * k], u[2 * k + 1]);
            (p, v) = self.lip.propagate(&p, &v, &f, self.config.step_duration);
            th += omega * self.config.step_duration;
            states[k] = LipState {
                position: p,
                velocity: v,
                heading: th,
            };
            feet[k] = f;
        }
        pred.plan(states, feet)
    }
}

// Cold and not inlined: its two call sites (an invalid input, a non-finite
// output) are off the cycle path; one copy saves flash, and as a cold call
// the optimiser lays the cycle path out for the other branches (firmware:
// fewer instructions on every recorded cycle, firmware/README.md).
#[cold]
#[inline(never)]
pub(super) fn hold<const N: usize, const NV: usize, const V: usize>(
    memory: &mut Memory<NV>,
    input: &CycleInput<'_, V>,
    e: InputError,
) -> CycleOutput<N> {
    let finite2 = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
    let target = match memory.last_target {
        Some(t) if finite2(&t) => t,
        _ if finite2(&input.stance_foot) => input.stance_foot,
        _ => Vector2::zeros(),
    };
    memory.n_active = 0;
    memory.has_plan = false;
    let st = LipState {
        position: target,
        velocity: Vector2::zeros(),
        heading: 0.0,
    };
    CycleOutput {
        foot_target: target,
        turning_rate: 0.0,
        plan: Plan {
            x0: st,
            states: [st; N],
            feet: [target; N],
            first_side: input.stance_side.opposite(),
        },
        status: CycleStatus::InvalidInput(e),
        info: CycleInfo {
            qp_status: None,
            iterations: 0,
            active_set_size: 0,
            active_obstacles: 0,
            obstacles_truncated: false,
            inside_obstacle: false,
            time_clamped: false,
            warm_started: false,
            source: CommandSource::Hold,
            cost: f64::NAN,
            max_violation: f64::NAN,
            min_h0: f64::INFINITY,
            relax_gait: 0.0,
            relax_safety: 0.0,
            relax_capture: 0.0,
        },
    }
}
