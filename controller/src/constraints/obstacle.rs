//! The rows of an obstacle (docs/maths.md §2.5): the linearised obstacle, a
//! half-plane that may move along its normal ([`HalfPlane`]), and the two
//! rows it gives each step of the horizon ([`StepSpan`]): the LDCBF row on
//! the CoM positions ([`push_ldcbf_row`]) and the foot-clearance row on the
//! footstep ([`push_foot_row`]), affine in the condensed variables
//! ([`Condensed`], module docs of `constraints.rs`).

use nalgebra::Vector2;

use super::{Condensed, push_row};
use crate::qp::DenseQp;
use crate::reach::{Reach, ReachLimits};

/// A linearised obstacle: the half-plane `h(p) = eta'(p - c) - delta >= 0`,
/// moving along its normal at `rate` (see [`HalfPlane::h_at`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfPlane {
    /// `c`: closest boundary point to `p_0` of the obstacle where it is at
    /// the time of the cycle's input (m, world).
    pub c: Vector2<f64>,
    /// `eta`: unit normal towards the safe side.
    pub eta: Vector2<f64>,
    /// `eta'u`, m/s: the obstacle's velocity `u` (world frame) along the
    /// normal; > 0 when it moves towards the safe side. 0 for an obstacle at
    /// rest. The half-plane at time `t` from the input is the one through
    /// `c + u t`, the same normal.
    pub rate: f64,
    /// What is known of the obstacle's velocity ([`Reach`]): with a spread,
    /// the half-plane at time `t` is moved by [`Reach::shift`] instead (it
    /// holds every position the obstacle can reach by then, up to
    /// [`ReachLimits::grow`]; the limits are the methods' `lim`).
    pub reach: Reach,
}

impl HalfPlane {
    /// `h(p) = eta'(p - c) - delta` (m): the half-plane at the input's time.
    pub fn h(&self, p: &Vector2<f64>, delta: f64) -> f64 {
        self.eta.dot(&(p - self.c)) - delta
    }

    /// `h_t(p) = eta'(p - c - u t) - delta = h(p) - rate t` (m): the
    /// half-plane of the obstacle moved for `t` seconds from the input's time
    /// (with an uncertain velocity, moved by [`Reach::shift`] within `lim`).
    /// Equal to [`HalfPlane::h`] bit for bit when `rate` is 0 and the
    /// velocity is known.
    pub fn h_at(&self, lim: &ReachLimits, p: &Vector2<f64>, delta: f64, t: f64) -> f64 {
        self.h(p, delta) - self.shift(lim, t)
    }

    /// How far the obstacle moves into the safe side by time `t` (m): `rate
    /// t`, exactly `+0` when `rate` is 0 (of either sign), so that
    /// subtracting it changes no bit of a static row; with an uncertain
    /// velocity the farthest its reachable set gets, [`Reach::shift`].
    pub(crate) fn shift(&self, lim: &ReachLimits, t: f64) -> f64 {
        if self.reach.is_uncertain() {
            self.reach.shift(lim, self.rate, t)
        } else if self.rate == 0.0 {
            0.0
        } else {
            self.rate * t
        }
    }

    /// The largest [`HalfPlane::shift`] over the times `[t0, t1]` (s), or a
    /// bound above it (m): a foot that stands through them must clear it.
    pub(crate) fn shift_over(&self, lim: &ReachLimits, t0: f64, t1: f64) -> f64 {
        if self.reach.is_uncertain() {
            self.reach.shift_over(lim, self.rate, (t0, t1))
        } else {
            self.shift(lim, t0).max(self.shift(lim, t1))
        }
    }

    /// Whether the obstacle may move: a nonzero `rate` or an uncertain
    /// velocity ([`Reach::is_uncertain`]).
    pub fn moves(&self) -> bool {
        self.rate != 0.0 || self.reach.is_uncertain()
    }
}

/// Step `k` of the horizon as an obstacle's rows see it: the predicted
/// state `x_0 = (p0, v0)` at the start of step 0 (m, m/s, world) the rows
/// are affine in, and the times `(t0, t1)` of step ends `k` and `k + 1` from
/// the cycle's input, s (where a moving half-plane is taken).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepSpan {
    /// The step, `0..N`.
    pub k: usize,
    /// `(t0, t1)`: times of step ends `k` and `k + 1` from the input, s.
    pub times: (f64, f64),
    /// `p_0`: predicted CoM position at the start of step 0, m, world.
    pub p0: Vector2<f64>,
    /// `v_0`: predicted CoM velocity at the start of step 0, m/s, world.
    pub v0: Vector2<f64>,
}

/// Appends the LDCBF row `h_{t1}(p_{k+1}) >= (1 - gamma) h_{t0}(p_k)` for
/// the step `step` (its `k`, `(t0, t1)` and `x_0`), with `h_t` the
/// half-plane moved to time `t` ([`HalfPlane::h_at`] with the person bounds
/// `lim`; the times do not matter for an obstacle at rest, whose row is the
/// static one bit for bit).
#[allow(clippy::result_unit_err)]
pub fn push_ldcbf_row<const N: usize, const NV: usize, const NC: usize>(
    qp: &mut DenseQp<NV, NC>,
    model: &Condensed<N>,
    hp: &HalfPlane,
    lim: &ReachLimits,
    gamma: f64,
    delta: f64,
    step: &StepSpan,
) -> Result<(), ()> {
    let StepSpan {
        k,
        times: (t0, t1),
        p0,
        v0,
    } = step;
    let k = *k;
    // Quantity Q = -p_{k+1} + (1 - gamma) p_k, bound -gamma (eta'c + delta)
    // - (rate t1 - (1 - gamma) rate t0).
    let (w1, c1) = model.position(k + 1, p0, v0);
    let (w0, c0) = model.position(k, p0, v0);
    let w = -w1 + w0 * (1.0 - gamma);
    let q0 = -c1 + c0 * (1.0 - gamma);
    let motion = hp.shift(lim, *t1) - (1.0 - gamma) * hp.shift(lim, *t0);
    push_row(
        qp,
        &hp.eta,
        &w,
        &q0,
        -gamma * (hp.eta.dot(&hp.c) + delta) - motion,
    )
}

/// Appends the foot-clearance row `eta'(f_k - c) >= delta_foot + max(rate t0,
/// rate t1)` for the step `step`: the foot `f_k` stands from step end `k` to
/// step end `k + 1` (times `t0`, `t1`), and the moving half-plane is nearest
/// to it at one of the two (the static row when `rate` is 0).
#[allow(clippy::result_unit_err)]
pub fn push_foot_row<const N: usize, const NV: usize, const NC: usize>(
    qp: &mut DenseQp<NV, NC>,
    model: &Condensed<N>,
    hp: &HalfPlane,
    lim: &ReachLimits,
    delta_foot: f64,
    step: &StepSpan,
) -> Result<(), ()> {
    let (t0, t1) = step.times;
    let (w, f_const) = model.foot(step.k, &step.p0, &step.v0);
    let motion = hp.shift_over(lim, t0, t1);
    push_row(
        qp,
        &hp.eta,
        &-w,
        &-f_const,
        -hp.eta.dot(&hp.c) - delta_foot - motion,
    )
}
