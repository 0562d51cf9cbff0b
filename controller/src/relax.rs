//! The priority scheme for infeasible cycles: which rows give way, and by how
//! little.
//!
//! Rows fall in three classes ([`RowClass`]): leg **reachability** (physical: never
//! relaxed), **safety** (LDCBF and foot clearance), and **gait** (walking velocity
//! and maneuverability). A fourth bound, **capturability** (optional,
//! [`crate::Config::capture_fraction`], on by default; below), shares the gait
//! rows' left-hand sides.
//!
//! # Units
//!
//! Every relaxation is in the physical units of the relaxed rows' right-hand
//! sides, as [`crate::constraints`] builds them: a gait row `a'v_{k+1} <= b`
//! (`a` a body-frame axis of step `k`) relaxed by `eps_gait` is
//! `a'v_{k+1} <= b + eps_gait`, m/s of that velocity component, on every step of the horizon
//! alike; an LDCBF row `h(p_{k+1}) - (1 - gamma) h(p_k) >= 0` relaxed by
//! `eps_safety` is `>= -eps_safety`, m of `h` (a foot-clearance row likewise,
//! m); the capturability bound relaxed by `eps_capture` is `|a'v_{k+1}| <=
//! speed + eps_capture`, m/s. (In the decision variables the rows have norms
//! from 1 to about 13, so a relaxation per unit row norm, as before, was not in
//! these units: the 0.1 cap let a first-step velocity row give way by about
//! 0.56 m/s and a second-step one by about 1.26 m/s.) [`class_violation`]
//! measures violations in the same units.
//!
//! # Stages
//!
//! When the nominal QP is infeasible the controller solves, lexicographically:
//!
//! 1. **Gait relaxed.** Keep reachability, safety and capturability; relax
//!    every gait row by the same amount `eps_gait` (m/s), the smallest that
//!    makes the problem feasible, but at most
//!    [`crate::Config::max_gait_relaxation`]; then minimise the nominal cost
//!    under that relaxation.
//! 2. **Safety relaxed** (when stage 1 needs more than the cap): keep
//!    reachability, capturability and the gait rows relaxed by the cap; find
//!    the smallest uniform relaxation `eps_safety` (m) of the safety rows,
//!    then, with safety relaxed by exactly that, the smallest `eps_gait` (<=
//!    cap), then minimise the cost. This is the least-violating reachable step
//!    in the sense of the largest LDCBF violation.
//! 3. **Gait unbounded** (only when reachability, capturability and the capped
//!    gait rows alone conflict, i.e. the robot already moves faster than the
//!    capped limits): as stage 2 with no cap on the gait rows, which then give
//!    way up to the capturability bound.
//! 4. **Capturability relaxed** (bound on, and reachability alone cannot meet
//!    it: the robot already moves too fast to keep within it): the smallest
//!    uniform relaxation `eps_capture` (m/s) of the bound with reachability
//!    alone, then as stage 3 under the bound relaxed by that. Reported in
//!    [`Relaxed::eps_capture`] and `CycleInfo::relax_capture`: never silent.
//!
//! So the priority order, most important first: reachability, capturability,
//! gait up to the cap, safety, gait beyond the cap.
//!
//! Why the cap: the gait rows bound the CoM velocity at the end of each step,
//! which is what keeps the pendulum capturable with steps inside the
//! reachability box. Relaxing them without bound let cycles that keep meeting
//! an infeasible LDCBF (an obstacle appearing from behind another under LiDAR)
//! speed the robot up, cycle after cycle, past about 0.96 m/s, where no
//! reachable step can stop it, and it fell. With the cap (0.1 m/s by default,
//! so at most 0.9 m/s forward) the safety rows give way first, by the least
//! amount.
//!
//! # Capturability
//!
//! Per body axis, with the heading fixed, the step map of
//! [`crate::constraints`] gives `v_{k+1} = cosh(beta T) v_k - beta sinh(beta
//! T) d_k` for the foot offset `d_k = f_k - p_k`, `|d_k| <= l_max` (leg
//! reachability). The best step against `v_k > 0` (`d_k = l_max`) slows the
//! robot iff `v_k < |kappa| l_max` with `|kappa| = beta sinh(beta T) /
//! (cosh(beta T) - 1) = beta coth(beta T / 2)`; from any `|v_k| < |kappa|
//! l_max` the robot can stop in finitely many steps within reach (N-step
//! capturability of the LIP with reach `l_max` and step time `T`, as in
//! Koolen et al., IJRR 2012), from any faster state it cannot and falls.
//! For Table I (`beta = 3.13 /s`, `T = 0.4 s`, `l_max = 0.173 m`) the limit
//! is `|kappa| l_max = 5.64 x 0.173 = 0.976 m/s`. The bound keeps every
//! body-frame component of every predicted `v_{k+1}` within `speed =
//! capture_fraction |kappa| l_max` (default 0.92: 0.898 m/s, just below the
//! capped forward gait `vx_max + 0.1 = 0.9 m/s`, leaving 8 % for turns, which
//! rotate the body frame by up to `omega_max T = 0.2 rad` per step, and for
//! model error). The nominal gait rows of Table I imply it (0.8 and 0.4 m/s),
//! so it changes nothing on cycles that meet them; it binds only when the gait
//! rows give way. Each of its rows has the left-hand side of one gait velocity
//! row, so it is applied as a per-row ceiling on that row's relaxation
//! (`h + min(eps_gait, headroom + eps_capture)`, headroom = `speed` minus the
//! row's nominal bound, at least 0) rather than as extra rows: the QP keeps
//! its size.
//!
//! Reachability alone is always feasible (each `f_k` may sit at `p_k`), so
//! stage 4 (and, without the bound, stage 3) always has an answer up to
//! numerical failure or budget exhaustion.
//!
//! # Finding the smallest relaxation
//!
//! Each smallest uniform relaxation is the optimal value of a linear program
//! (minimise `t` subject to the soft rows at `h + t` and the others as
//! fixed), whose dual is: maximise `-y'h` over Farkas certificates `y >= 0`,
//! `G'y = 0`, normalised by `y'|g|_soft = 1`. The dual active-set solver
//! returns such a certificate with every infeasible solve, and one certificate
//! holds for every relaxation of the same rows: with the gait rows at `e_g`
//! and the safety rows at `e_s`, `y'h + e_g sum_gait y + e_s sum_safety y < 0`
//! proves the relaxed problem empty (a gait row at its capturability ceiling
//! counts with its headroom in `y'h` and towards `e_c`; the linear form is
//! never below the true `y'h(e)`, so the proof stays valid). So each search
//! runs from below:
//!
//! * the last certificate gives a lower bound `b` on `t` (in the first search
//!   the nominal solve's, which the controller hands over; without one its
//!   first solve is the unrelaxed problem restricted to the
//!   rows of the first step, `k = 0`, which is usually already infeasible and
//!   about a third of the rows; a certificate of a subset of the rows is one
//!   of all of them; only if it is feasible is the whole unrelaxed problem
//!   solved);
//! * the next solve goes just above the bound, at `b (1 + 1e-9) + 1e-9`, with
//!   the certificate's rows marked as the warm start (they are the tight rows
//!   at the minimum); the first feasible solve ends the search with the
//!   optimal plan under that relaxation; an infeasible one brings a new
//!   certificate and a higher bound;
//! * a bound that proves every `t` (up to the cap) infeasible ends the stage
//!   without a solve: stage 2 starts from the certificate stage 1 ended with,
//!   and its gait search from the one its safety search ended with, which
//!   usually proves at once that less than the cap is infeasible.
//!
//! On the firmware's recorded infeasible cycles (all stage 1) this is two
//! solves per cycle, the nominal one included: the nominal certificate proves
//! the bound, and the solve just above it is feasible (three when the first
//! certificate came from the first-step solve, 4 or 15 with the bisection this
//! replaces); see `docs/fallback.md`.
//!
//! Tolerance: a reported `eps` is at most `b (1 + 1e-9) + 1e-9`, `b` the lower
//! bound its certificate proves (up to rounding in `y'h`). At a degenerate
//! minimum, where the relaxed feasible set is a single point that rounding can
//! declare empty, a probe at the padded bound can come back infeasible with no
//! higher bound: the padding then grows a hundredfold per probe. A search
//! makes at most [`crate::Config::relax_bisections`] probes (the name is
//! historical: it now counts probes, not halvings) and the whole scheme at
//! most twice that many; a search that runs out solves the most relaxed
//! problem once more and reports that plan with its own violation (feasible,
//! not minimal). Stage 3 with the capturability bound on starts with one
//! solve of reachability and the bound alone (counted as a probe): infeasible,
//! it goes to stage 4 with that certificate; feasible, its plan bounds stage
//! 3's safety search from above. So one infeasible cycle makes at most `2
//! relax_bisections + 6` solves after the nominal one (six searches at most:
//! stage 1, the safety searches of stages 2, 3 and 4, the capturability
//! search of stage 4, one gait search), each drawing on the cycle's
//! iteration budget ([`crate::Config::max_iter_cycle`]); if that runs out the
//! controller falls back to the previous plan or the capture step.

use nalgebra::SVector;

use crate::constraints::{RowId, RowKind};
use crate::qp::{DenseQp, DualActiveSet, QpBackend, QpStatus};

/// Priority class of a row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowClass {
    /// Leg reachability: never relaxed.
    Reach,
    /// LDCBF and foot clearance.
    Safety,
    /// Walking velocity and maneuverability.
    Gait,
}

impl RowClass {
    /// The class of a row kind.
    pub fn of(kind: RowKind) -> RowClass {
        match kind {
            RowKind::ReachLonUpper
            | RowKind::ReachLonLower
            | RowKind::ReachLatUpper
            | RowKind::ReachLatLower => RowClass::Reach,
            RowKind::Ldcbf(_) | RowKind::FootClearance(_) => RowClass::Safety,
            RowKind::VelLonUpper
            | RowKind::VelLonLower
            | RowKind::VelLatUpper
            | RowKind::VelLatLower => RowClass::Gait,
        }
    }
}

/// Largest violation of each row class by a plan, in the rows' physical units
/// (the units of their right-hand sides: m/s of a body-frame velocity component
/// for gait rows, m for reachability rows, m of `h` for LDCBF and foot-clearance
/// rows); 0 when the class holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassViolation {
    /// Leg reachability rows.
    pub reach: f64,
    /// LDCBF and foot-clearance rows.
    pub safety: f64,
    /// Walking velocity and maneuverability rows.
    pub gait: f64,
}

impl ClassViolation {
    /// The violation of one class.
    pub fn of(&self, class: RowClass) -> f64 {
        match class {
            RowClass::Reach => self.reach,
            RowClass::Safety => self.safety,
            RowClass::Gait => self.gait,
        }
    }

    /// The largest over all classes.
    pub fn max(&self) -> f64 {
        self.reach.max(self.safety).max(self.gait)
    }
}

/// Measures [`ClassViolation`] of the plan `u` on `qp` (rows identified by `rows`).
/// A non-finite plan gets infinite violations.
// One out-of-line copy (it has five callers; inlined, each costs flash on the
// Cortex-M7 for no measurable time).
#[inline(never)]
pub fn class_violation<const NV: usize, const NC: usize>(
    qp: &DenseQp<NV, NC>,
    rows: &[RowId; NC],
    u: &SVector<f64, NV>,
) -> ClassViolation {
    let mut v = ClassViolation {
        reach: 0.0,
        safety: 0.0,
        gait: 0.0,
    };
    for ((g, h), id) in qp.rows().zip(rows) {
        // A zero row (|g| = 0, i.e. |g|^2 = 0) constrains nothing; no square
        // root needed to tell.
        if g.norm_squared() == 0.0 {
            continue;
        }
        let e = g.dot(u) - h;
        let e = if e.is_nan() { f64::INFINITY } else { e };
        let slot = match RowClass::of(id.kind) {
            RowClass::Reach => &mut v.reach,
            RowClass::Safety => &mut v.safety,
            RowClass::Gait => &mut v.gait,
        };
        *slot = slot.max(e);
    }
    v
}

/// The capturability bound (see the module docs): every body-frame component
/// of every predicted end-of-step velocity `v_{k+1}` within `+-speed`. It
/// shares its left-hand sides with the gait velocity rows, so it is applied as
/// a per-row ceiling on their relaxation rather than as extra rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaptureBounds {
    /// Largest capturable velocity component, m/s (body frame of step `k`).
    pub speed: f64,
    /// `speed` minus the nominal bound of each gait row, m/s, clamped at 0
    /// (the capturability bound never tightens a nominal row), in the order
    /// `VelLonUpper, VelLonLower, VelLatUpper, VelLatLower`.
    pub headroom: [f64; 4],
}

impl CaptureBounds {
    /// The bound of `cfg` (`None` when [`crate::Config::capture_fraction`] is
    /// off): `speed = fraction |kappa| l_max` with `kappa` (1/s) of the step
    /// map (`|kappa| = beta coth(beta T / 2)`), and `omega_bar` (rad/s) the
    /// cycle's turning rate (it lowers the `VelLonUpper` row's nominal bound).
    pub fn new(cfg: &crate::Config, kappa: f64, omega_bar: f64) -> Option<CaptureBounds> {
        let speed = cfg.capture_fraction? * kappa.abs() * cfg.l_max;
        let lon_upper = cfg
            .vx_max
            .min(cfg.vx_max - cfg.alpha / core::f64::consts::PI * omega_bar.abs());
        let room = |b: f64| (speed - b).max(0.0);
        let cb = CaptureBounds {
            speed,
            headroom: [
                room(lon_upper),
                room(-cfg.vx_min),
                room(cfg.vy_max),
                room(-cfg.vy_min),
            ],
        };
        cb.headroom.iter().all(|h| h.is_finite()).then_some(cb)
    }

    /// The headroom of a row of kind `kind` (`None`: not a velocity row).
    fn of(&self, kind: RowKind) -> Option<f64> {
        let i = match kind {
            RowKind::VelLonUpper => 0,
            RowKind::VelLonLower => 1,
            RowKind::VelLatUpper => 2,
            RowKind::VelLatLower => 3,
            _ => return None,
        };
        self.headroom.get(i).copied()
    }
}

/// What a search relaxes: one of the row classes, or the capturability bound
/// (which acts on the gait rows).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Soft {
    Safety,
    Gait,
    Capture,
}

/// Which rows a relaxed problem keeps, and by how much each class is relaxed
/// (`None`: the class is left out); `first_step`: only the rows of the first
/// step (`k = 0`). A gait row's right-hand side is `h + min(gait, headroom +
/// capture)` (each term only when present; the row is left out when neither
/// is).
#[derive(Clone, Copy, Debug)]
struct Keep {
    safety: Option<f64>,
    gait: Option<f64>,
    capture: Option<f64>,
    first_step: bool,
}

impl Keep {
    fn eps(&self, c: Soft) -> Option<f64> {
        match c {
            Soft::Safety => self.safety,
            Soft::Gait => self.gait,
            Soft::Capture => self.capture,
        }
    }

    fn with(self, c: Soft, eps: f64) -> Keep {
        match c {
            Soft::Safety => Keep {
                safety: Some(eps),
                ..self
            },
            Soft::Gait => Keep {
                gait: Some(eps),
                ..self
            },
            Soft::Capture => Keep {
                capture: Some(eps),
                ..self
            },
        }
    }

    /// The relaxed right-hand side of a row of kind `kind` with nominal
    /// right-hand side `h`, and whether it is the capturability ceiling
    /// (`None`: left out).
    fn rhs(&self, kind: RowKind, h: f64, capture: Option<&CaptureBounds>) -> Option<(f64, bool)> {
        match RowClass::of(kind) {
            RowClass::Reach => Some((h, false)),
            RowClass::Safety => self.safety.map(|e| (h + e, false)),
            RowClass::Gait => {
                let by_gait = self.gait.map(|e| h + e);
                let by_capture = match (capture.and_then(|c| c.of(kind)), self.capture) {
                    (Some(room), Some(e)) => Some(h + room + e),
                    _ => None,
                };
                match (by_gait, by_capture) {
                    (Some(a), Some(b)) if b < a => Some((b, true)),
                    (Some(a), _) => Some((a, false)),
                    (None, Some(b)) => Some((b, true)),
                    (None, None) => None,
                }
            }
        }
    }
}

/// Which stage produced the relaxed plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RelaxLevel {
    /// Stage 1: gait rows relaxed, safety and reachability kept.
    Gait,
    /// Stage 2: safety (and gait) rows relaxed, reachability kept.
    Safety,
}

/// A relaxed plan.
#[derive(Clone, Copy, Debug)]
pub struct Relaxed<const NV: usize> {
    /// Footsteps.
    pub u: SVector<f64, NV>,
    /// Stage that produced it.
    pub level: RelaxLevel,
    /// Uniform relaxation of the gait rows, m/s (0 if none was needed).
    pub eps_gait: f64,
    /// Uniform relaxation of the safety rows, m of `h` (0 at stage 1).
    pub eps_safety: f64,
    /// Uniform relaxation of the capturability bound, m/s (0 unless stage 4).
    pub eps_capture: f64,
    /// Solver iterations spent.
    pub iterations: u32,
}

/// A failed relaxation: why, and the solver iterations it spent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RelaxError {
    /// Why it gave up.
    pub kind: RelaxFailure,
    /// Solver iterations spent before giving up.
    pub iterations: u32,
}

/// Why the relaxation gave up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RelaxFailure {
    /// The per-cycle iteration budget ran out.
    Budget,
    /// A solve reported a numerical error.
    Numerical,
}

/// Runs the priority scheme on the nominal QP `qp` (rows identified by `rows`;
/// each probe solves a selection of its rows in place, with no copy).
/// `budget` is the number of solver iterations left in this cycle; `probes`
/// the largest number of solves of one search for a smallest relaxation (the scheme makes at most `2 probes + 4` solves in all,
/// see the module docs); `gait_cap` the largest relaxation of the gait rows
/// (m/s) allowed before the safety rows give way; `capture` the
/// capturability bound (`None`: off). `certificate`: a Farkas certificate of
/// the nominal QP (one weight per row of `qp`, as
/// [`crate::qp::QpSolution::lambda`] of its infeasible solve), used as the
/// first search's starting certificate when it proves the nominal QP empty
/// (`y'h < 0`); it replaces the first-step solve.
#[allow(clippy::too_many_arguments)]
pub(crate) fn relax<const NV: usize, const NC: usize, B: QpBackend<NV, NC>>(
    solver: &DualActiveSet<NV, NC>,
    backend: &mut B,
    qp: &DenseQp<NV, NC>,
    rows: &[RowId; NC],
    max_iter: u32,
    budget: u32,
    probes: u32,
    gait_cap: f64,
    capture: Option<CaptureBounds>,
    certificate: Option<&SVector<f64, NC>>,
) -> Result<Relaxed<NV>, RelaxError> {
    let mut norms = [0.0f64; NC];
    for (n, g) in norms.iter_mut().zip(qp.gt.column_iter().take(qp.m)) {
        *n = crate::float::sqrt(g.norm_squared());
    }
    let mut ctx = Ctx {
        norms,
        solver,
        backend,
        qp,
        rows,
        max_iter,
        budget,
        used: 0,
        probes,
        probes_left: probes.saturating_mul(2),
        cert: None,
        marks: [false; NC],
        capture,
    };
    if let Some(y) = certificate {
        // The nominal QP is the first probe's problem (stage 1 at no
        // relaxation) without the first-step restriction.
        let nominal = Keep {
            safety: Some(0.0),
            gait: Some(0.0),
            capture: capture.map(|_| 0.0),
            first_step: false,
        };
        ctx.take_certificate(y, nominal);
        if !ctx.cert.is_some_and(|c| c.yh < 0.0) {
            ctx.cert = None;
            ctx.marks = [false; NC];
        }
    }
    let out = run_stages(&mut ctx, gait_cap);
    out.map_err(|kind| RelaxError {
        kind,
        iterations: ctx.used,
    })
}

/// The stages of the scheme (see the module docs).
fn run_stages<const NV: usize, const NC: usize, B: QpBackend<NV, NC>>(
    ctx: &mut Ctx<'_, NV, NC, B>,
    gait_cap: f64,
) -> Result<Relaxed<NV>, RelaxFailure> {
    // The capturability bound, when on, is kept through stages 1-3.
    let capture0 = ctx.capture.map(|_| 0.0);
    // Stage 1: reachability, safety and capturability hard, gait soft up to the cap.
    let safe = Keep {
        safety: Some(0.0),
        gait: None,
        capture: capture0,
        first_step: false,
    };
    if let Some((u, eps)) = ctx.minimal(safe, Soft::Gait, gait_cap, None)? {
        return Ok(Relaxed {
            u,
            level: RelaxLevel::Gait,
            eps_gait: eps,
            eps_safety: 0.0,
            eps_capture: 0.0,
            iterations: ctx.used,
        });
    }
    // Stage 2: reachability and the capped gait rows hard, safety soft; then, with
    // safety relaxed by exactly that much, the least gait relaxation (<= cap).
    // Stage 3, when even reachability and the capped gait rows conflict (the
    // robot already moves faster than the capped limits allow): the same with
    // the gait rows unbounded (but under the capturability bound, when on).
    // Stage 4 (capturability on, and reachability and the bound conflict: the
    // robot is already too fast to stay within it): first the least uniform
    // relaxation of the capturability bound, then as stage 3 under it.
    for stage in 2..=4u8 {
        let cap = if stage == 2 { gait_cap } else { f64::INFINITY };
        let mut capture = capture0;
        let mut known_s = None;
        if stage == 3 && ctx.capture.is_some() && ctx.probes_left > 0 {
            // One solve tells whether reachability and the capturability bound
            // alone are feasible: if not, stage 4 (with this certificate); if
            // so, the plan bounds stage 3's safety search from above.
            let free = Keep {
                safety: None,
                gait: None,
                capture: Some(0.0),
                first_step: false,
            };
            ctx.probes_left -= 1;
            match ctx.solve(free)? {
                Probe::Feasible(u) => {
                    known_s = Some((ctx.violation(Soft::Safety, &u).max(0.0), u));
                }
                Probe::Infeasible => continue,
            }
        }
        if stage == 4 {
            if ctx.capture.is_none() {
                break;
            }
            let free = Keep {
                safety: None,
                gait: None,
                capture: None,
                first_step: false,
            };
            let Some((u_c, eps_c)) = ctx.minimal(free, Soft::Capture, f64::INFINITY, None)? else {
                break;
            };
            capture = Some(eps_c);
            known_s = Some((ctx.violation(Soft::Safety, &u_c).max(0.0), u_c));
        }
        let reach = Keep {
            safety: None,
            gait: if cap.is_finite() { Some(cap) } else { None },
            capture,
            first_step: false,
        };
        let Some((u_s, eps_s)) = ctx.minimal(reach, Soft::Safety, f64::INFINITY, known_s)? else {
            continue;
        };
        let fixed = Keep {
            safety: Some(eps_s),
            gait: None,
            capture,
            first_step: false,
        };
        // The plan just found is feasible with the gait rows at the cap (or
        // without them: then at its own gait violation).
        let known = if cap.is_finite() {
            cap
        } else {
            ctx.violation(Soft::Gait, &u_s).max(0.0)
        };
        let (u, eps_g) = ctx
            .minimal(fixed, Soft::Gait, cap, Some((known, u_s)))?
            .ok_or(RelaxFailure::Numerical)?;
        // Without any safety relaxation this is still a gait relaxation (beyond
        // the cap: the robot moves too fast already).
        let level = if eps_s > 0.0 {
            RelaxLevel::Safety
        } else {
            RelaxLevel::Gait
        };
        return Ok(Relaxed {
            u,
            level,
            eps_gait: eps_g,
            eps_safety: eps_s,
            eps_capture: capture.unwrap_or(0.0),
            iterations: ctx.used,
        });
    }
    // Reachability alone is always feasible: only numerics get here.
    Err(RelaxFailure::Numerical)
}

/// The sums of a Farkas certificate `y` (`y >= 0`, `G'y = 0`) that matter for
/// every relaxation of the same rows: with the gait rows at `h + e_g` and
/// the safety rows at `h + e_s`, `y'h(e) = yh + e_g yg + e_s ys (+ e_c yc)`,
/// and the relaxed problem is infeasible whenever that is negative. A gait row
/// whose right-hand side was the capturability ceiling `h + room + e_c` counts
/// in `yh` (with `y room`) and `yc`: since each gait row's right-hand side is
/// the smaller of its two forms, this linear form is never below the true
/// `y'h(e)`, so it still proves emptiness wherever it is negative.
#[derive(Clone, Copy, Debug)]
struct Certificate {
    /// `y'h` at no relaxation (with the capturability ceilings' headroom).
    yh: f64,
    /// Sum of `y` over the gait rows in their gait form (0: they take no part).
    yg: f64,
    /// Sum of `y` over the safety rows.
    ys: f64,
    /// Sum of `y` over the gait rows in their capturability form.
    yc: f64,
    /// `y' |g|` over all rows (scale for "zero").
    yn: f64,
}

/// What a certificate says about the relaxation `t` of one class, the others
/// fixed.
enum Bound {
    /// Infeasible for every `t` below this (m of `h` or m/s).
    Below(f64),
    /// Infeasible for every `t`: relaxing this class cannot help.
    Never,
    /// Nothing (the certificate uses rows the problem leaves out, or does not
    /// prove anything here).
    Unknown,
}

impl Certificate {
    /// The bound on the relaxation of `soft` when the other classes are as in
    /// `fixed` (`None`: left out).
    fn bound(&self, fixed: Keep, soft: Soft) -> Bound {
        let mut a = self.yh;
        let mut b = 0.0;
        for (class, y) in [
            (Soft::Gait, self.yg),
            (Soft::Safety, self.ys),
            (Soft::Capture, self.yc),
        ] {
            if class == soft {
                b = y;
            } else {
                match fixed.eps(class) {
                    Some(e) => a += e * y,
                    // Leaving rows out is fine only if `y` does not use them.
                    None if y > 0.0 => return Bound::Unknown,
                    None => {}
                }
            }
        }
        // Rounding leaves `y'|g|` of unused rows at ~1e-16 of the whole.
        let zero = 1e-12 * self.yn;
        if b > zero {
            let t = -a / b;
            if t.is_finite() {
                Bound::Below(t)
            } else {
                Bound::Unknown
            }
        } else if a < -1e-9 * self.yn {
            // (A certificate whose `a` is zero up to its accuracy, e.g. at a
            // relaxation found just at its bound, proves nothing.)
            Bound::Never
        } else {
            Bound::Unknown
        }
    }
}

/// What one solve of a (relaxed) problem gave.
enum Probe<const NV: usize> {
    /// Feasible, with the optimal plan.
    Feasible(SVector<f64, NV>),
    /// Infeasible (the certificate is kept in [`Ctx::cert`]).
    Infeasible,
}

struct Ctx<'a, const NV: usize, const NC: usize, B> {
    /// Euclidean norms of the nominal rows.
    norms: [f64; NC],
    /// The capturability bound (`None`: off).
    capture: Option<CaptureBounds>,
    solver: &'a DualActiveSet<NV, NC>,
    backend: &'a mut B,
    qp: &'a DenseQp<NV, NC>,
    rows: &'a [RowId; NC],
    max_iter: u32,
    budget: u32,
    used: u32,
    /// Probes per search.
    probes: u32,
    /// Probes left for the whole scheme.
    probes_left: u32,
    /// The certificate of the last infeasible probe.
    cert: Option<Certificate>,
    /// Rows of the nominal QP in the support of the last certificate: the rows
    /// that are tight at the smallest relaxation, tried first by the next solve.
    marks: [bool; NC],
}

/// Relative and absolute padding of a probe above a proven lower bound.
const PAD: f64 = 1e-9;

impl<const NV: usize, const NC: usize, B: QpBackend<NV, NC>> Ctx<'_, NV, NC, B> {
    /// Solves the problem `keep`: the nominal QP's rows that `keep` keeps, with
    /// its right-hand sides, in place ([`QpBackend::solve_selected`]: no copy of
    /// the rows), the marked rows first. An infeasible solve leaves its
    /// certificate in `self.cert` and its support in `self.marks`. Not inlined:
    /// one copy of the solver call in flash.
    #[inline(never)]
    fn solve(&mut self, keep: Keep) -> Result<Probe<NV>, RelaxFailure> {
        let left = self.budget.saturating_sub(self.used);
        if left == 0 {
            return Err(RelaxFailure::Budget);
        }
        let mut h = SVector::<f64, NC>::zeros();
        let mut enabled = [false; NC];
        for (((&h0, id), hi), on) in self
            .qp
            .h
            .iter()
            .zip(self.rows)
            .zip(h.iter_mut())
            .zip(&mut enabled)
            .take(self.qp.m)
        {
            if keep.first_step && id.k != 0 {
                continue;
            }
            if let Some((rhs, _)) = keep.rhs(id.kind, h0, self.capture.as_ref()) {
                *hi = rhs;
                *on = true;
            }
        }
        let sol = self.backend.solve_selected(
            self.solver,
            self.qp,
            &h,
            &enabled,
            &self.marks,
            self.max_iter.min(left),
        );
        self.used = self.used.saturating_add(sol.iterations);
        match sol.status {
            QpStatus::Solved => Ok(Probe::Feasible(sol.x)),
            QpStatus::Infeasible => {
                self.take_certificate(&sol.lambda, keep);
                Ok(Probe::Infeasible)
            }
            QpStatus::IterationLimit => Err(RelaxFailure::Budget),
            QpStatus::NumericalError => Err(RelaxFailure::Numerical),
        }
    }

    /// Keeps the Farkas certificate `lambda` (one weight per nominal row) of an
    /// infeasible solve of the problem `keep`: its sums in [`Ctx::cert`] and its
    /// support (but the lightest row) in [`Ctx::marks`].
    fn take_certificate(&mut self, lambda: &SVector<f64, NC>, keep: Keep) {
        let mut c = Certificate {
            yh: 0.0,
            yg: 0.0,
            ys: 0.0,
            yc: 0.0,
            yn: 0.0,
        };
        self.marks = [false; NC];
        let m = self.qp.m.min(NC);
        // Weights at rounding level (~1e-17 of the largest) are not
        // part of the certificate's support.
        let floor = 1e-12 * lambda.amax();
        for (o, &y) in lambda.iter().enumerate().take(m) {
            let (Some(&h), Some(&n), Some(id)) =
                (self.qp.h.get(o), self.norms.get(o), self.rows.get(o))
            else {
                continue;
            };
            // (NaN weights are skipped too.)
            if y.partial_cmp(&floor) != Some(core::cmp::Ordering::Greater) {
                continue;
            }
            if let Some(mk) = self.marks.get_mut(o) {
                *mk = true;
            }
            c.yh += y * h;
            c.yn += y * n;
            match RowClass::of(id.kind) {
                RowClass::Gait => {
                    let capped = keep
                        .rhs(id.kind, h, self.capture.as_ref())
                        .is_some_and(|(_, capped)| capped);
                    match self.capture.as_ref().and_then(|c| c.of(id.kind)) {
                        Some(room) if capped => {
                            c.yh += y * room;
                            c.yc += y;
                        }
                        _ => c.yg += y,
                    }
                }
                RowClass::Safety => c.ys += y,
                RowClass::Reach => {}
            }
        }
        // The support's normals are linearly dependent (`G'y = 0`):
        // marking all of them makes the next solve add one too many
        // and drop it again. Leave out the lightest.
        let mut lightest: Option<(usize, f64)> = None;
        for (o, &y) in lambda.iter().enumerate().take(m) {
            let w = y * self.norms.get(o).copied().unwrap_or(0.0);
            if self.marks.get(o).copied().unwrap_or(false) && lightest.is_none_or(|(_, lw)| w < lw)
            {
                lightest = Some((o, w));
            }
        }
        if let Some(mk) = lightest.and_then(|(o, _)| self.marks.get_mut(o)) {
            *mk = false;
        }
        self.cert = (c.yh.is_finite() && c.yn.is_finite()).then_some(c);
    }

    /// Largest violation at `u` (physical units) of the safety rows, the gait
    /// rows, or the capturability bound.
    fn violation(&self, soft: Soft, u: &SVector<f64, NV>) -> f64 {
        match soft {
            Soft::Safety => class_violation(self.qp, self.rows, u).safety,
            Soft::Gait => class_violation(self.qp, self.rows, u).gait,
            Soft::Capture => {
                let mut v: f64 = 0.0;
                for ((g, h), id) in self.qp.rows().zip(self.rows) {
                    if let Some(room) = self.capture.as_ref().and_then(|c| c.of(id.kind)) {
                        let e = g.dot(u) - h - room;
                        v = if e.is_nan() { f64::INFINITY } else { v.max(e) };
                    }
                }
                v
            }
        }
    }

    /// With `fixed` kept, the smallest uniform relaxation of `soft`, at most
    /// `cap` (`f64::INFINITY`: unbounded), and the optimal plan under it.
    /// `Ok(None)` when no relaxation up to `cap` is feasible. `known`: a
    /// relaxation already known feasible, with its optimal plan.
    ///
    /// Search from below: each infeasible probe's certificate proves a lower
    /// bound (and the last certificate of an earlier search often proves one
    /// before any probe); the next probe goes just above it (`PAD`), so the
    /// first feasible probe is the answer. When a probe at the padded bound is
    /// still infeasible without raising the bound (rounding at a degenerate
    /// minimum, where the feasible set is a single point), the padding grows
    /// a hundredfold per probe. After `probes` probes, the most relaxed
    /// problem is solved and its plan returned with its own violation.
    fn minimal(
        &mut self,
        fixed: Keep,
        soft: Soft,
        cap: f64,
        known: Option<(f64, SVector<f64, NV>)>,
    ) -> Result<Option<(SVector<f64, NV>, f64)>, RelaxFailure> {
        let with = |eps: f64| fixed.with(soft, eps);
        // `lo`: proven infeasible below; `pad`: the margin of the next probe.
        let mut lo: f64 = 0.0;
        let mut pad = 0.0;
        for i in 0..=self.probes {
            match self.cert.map_or(Bound::Unknown, |c| c.bound(fixed, soft)) {
                Bound::Never => return Ok(None),
                Bound::Below(b) if b > cap => return Ok(None),
                Bound::Below(b) if b > lo => {
                    lo = b;
                    pad = PAD;
                }
                // No progress from the last probe: widen (not before the first).
                _ if i > 0 => pad = if pad == 0.0 { PAD } else { pad * 100.0 },
                _ => {}
            }
            let eps = (lo * (1.0 + pad) + pad).min(cap);
            if let Some((k, u)) = known
                && k <= eps
            {
                return Ok(Some((u, k)));
            }
            if i == self.probes || self.probes_left == 0 || !eps.is_finite() {
                break;
            }
            self.probes_left -= 1;
            if self.cert.is_none() && eps == 0.0 {
                // No certificate yet: the rows of the first step alone are
                // often already infeasible, and any certificate of a subset
                // is one of the whole; a smaller problem is cheaper to solve.
                let first = Keep {
                    first_step: true,
                    ..with(0.0)
                };
                if let Probe::Infeasible = self.solve(first)? {
                    continue;
                }
                if self.probes_left == 0 {
                    break;
                }
                self.probes_left -= 1;
            }
            if let Probe::Feasible(u) = self.solve(with(eps))? {
                return Ok(Some((u, eps)));
            }
        }
        // Out of probes: the most relaxed problem, and its plan's own violation.
        let top = if cap.is_finite() { with(cap) } else { fixed };
        match self.solve(top)? {
            Probe::Feasible(u) => {
                let v = self.violation(soft, &u).max(lo).min(cap);
                if !v.is_finite() {
                    return Err(RelaxFailure::Numerical);
                }
                Ok(Some((u, v)))
            }
            Probe::Infeasible => Ok(None),
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::{Assembly, Config, ConvexPolygon, CycleInput, PaperController, Side};
    use nalgebra::Vector2;

    const NC: usize = crate::constraint_capacity(3, 8, false);
    /// Random cycles (about 4 in 5 are infeasible).
    const CASES: usize = 1000;

    /// Counts the solves of the priority scheme.
    struct Counting(usize);
    impl QpBackend<6, NC> for Counting {
        fn solve_qp(
            &mut self,
            solver: &DualActiveSet<6, NC>,
            qp: &DenseQp<6, NC>,
            prefer: &[bool; NC],
            max_iter: u32,
        ) -> crate::qp::QpSolution<6, NC> {
            self.0 += 1;
            solver.solve(qp, prefer, max_iter)
        }
    }

    /// Deterministic uniform numbers in [0, 1) (64-bit LCG, top bits).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }
    }

    /// The nominal QP with the gait and safety rows relaxed by `gait` and
    /// `safety` (`None`: left out) is empty, as proven by a Farkas
    /// certificate checked here independently of the solver (`y >= 0`,
    /// `G'y = 0` to 1e-9, `h'y < 0`).
    fn certified_empty(
        solver: &DualActiveSet<6, NC>,
        asm: &Assembly<3, 6, NC, 8>,
        gait: Option<f64>,
        safety: Option<f64>,
        capture: Option<(CaptureBounds, f64)>,
    ) -> bool {
        let keep = Keep {
            safety,
            gait,
            capture: capture.map(|c| c.1),
            first_step: false,
        };
        let bounds = capture.map(|c| c.0);
        let mut qp = DenseQp::<6, NC>::with_q(asm.qp.q);
        for ((g, h), id) in asm.qp.rows().zip(&asm.rows) {
            if let Some((rhs, _)) = keep.rhs(id.kind, h, bounds.as_ref()) {
                qp.push_row(&g, rhs).unwrap();
            }
        }
        let sol = solver.solve(&qp, &[false; NC], 500);
        if sol.status != QpStatus::Infeasible {
            return false;
        }
        let y = &sol.lambda;
        let mut gty = SVector::<f64, 6>::zeros();
        let mut hty = 0.0;
        for (i, (g, h)) in qp.rows().enumerate() {
            assert!(y[i] >= 0.0);
            gty += g * y[i];
            hty += h * y[i];
        }
        gty.amax() <= 1e-9 * (1.0 + y.amax()) && hty < 0.0
    }

    /// On random cycles of a robot walking into nearby boxes, every infeasible
    /// nominal QP gets a relaxed plan that keeps reachability and each class
    /// within its reported relaxation, and each reported relaxation is
    /// minimal in the priority order: 1e-6 (relative, plus 1e-6 absolute) less
    /// is certified infeasible, a safety relaxation comes only when the gait
    /// rows at the cap cannot make the problem feasible, and (half of the
    /// cases run with the capturability bound on) the bound is relaxed only
    /// when reachability alone cannot meet it.
    #[test]
    fn relaxations_are_minimal_in_priority_order() {
        let mut rng = Lcg(0x005e_ed0f_5afe);
        let mut ctl = PaperController::new(Config::default()).unwrap();
        let cap = ctl.config().max_gait_relaxation;
        let mut asm = Assembly::default();
        let (mut infeasible, mut stage1, mut stage2, mut stage3, mut stage4) = (0, 0, 0, 0, 0);
        let less = |e: f64| e - 1e-6 * (1.0 + e);
        let mut solves = [0usize; 32];
        let kappa =
            crate::constraints::Condensed::<3>::new(&crate::lip::Lip::new(9.81, 1.0, 0.4)).kappa;
        for case in 0..CASES {
            let delta = if rng.next() < 0.5 { 0.0 } else { 0.2 };
            let capture_fraction = if case % 2 == 0 { Some(0.92) } else { None };
            ctl = PaperController::new(Config {
                delta,
                capture_fraction,
                ..Config::default()
            })
            .unwrap();
            let th = rng.range(-3.0, 3.0);
            let dir = Vector2::new(libm::cos(th), libm::sin(th));
            let side = Vector2::new(-dir.y, dir.x);
            let speed = rng.range(0.2, 1.2);
            let v = dir * speed + side * rng.range(-0.3, 0.3);
            let mut obstacles =
                [ConvexPolygon::<8>::new(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap(); 3];
            let n_obs = 1 + (rng.next() * 3.0) as usize;
            for o in obstacles.iter_mut().take(n_obs) {
                let c = dir * rng.range(0.3, 1.6) + side * rng.range(-0.8, 0.8);
                let (a, b) = (rng.range(0.1, 0.8), rng.range(0.1, 0.8));
                *o = ConvexPolygon::hull(&[
                    [c.x - a, c.y - b],
                    [c.x + a, c.y - b],
                    [c.x + a, c.y + b],
                    [c.x - a, c.y + b],
                ])
                .unwrap();
            }
            let input = CycleInput {
                com_position: Vector2::zeros(),
                com_velocity: v,
                heading: th + rng.range(-0.3, 0.3),
                turning_rate: rng.range(-0.3, 0.3),
                stance_foot: dir * rng.range(-0.2, 0.2) + side * rng.range(-0.15, 0.15),
                stance_side: if rng.next() < 0.5 {
                    Side::Left
                } else {
                    Side::Right
                },
                time_in_step: rng.range(0.0, 0.4),
                goal: dir * 10.0,
                obstacles: &obstacles[..n_obs],
            };
            ctl.assemble(&input, &mut asm).unwrap();
            let solver = ctl.solver();
            let nominal = solver.solve(&asm.qp, &[false; NC], 64);
            if !nominal.status.is_infeasible() {
                continue;
            }
            infeasible += 1;
            // The nominal solve's certificate is one of the nominal QP
            // (`y >= 0` on the used rows, 0 beyond, `G'y = 0`, `h'y < 0`), so
            // of every relaxation the scheme bounds with it. Every other case
            // hands it over (as the controller does), the rest run without.
            let y = &nominal.lambda;
            let m = asm.qp.m;
            assert!(y.iter().take(m).all(|&v| v >= 0.0), "case {case}");
            assert!(y.iter().skip(m).all(|&v| v == 0.0), "case {case}");
            let scale: f64 = (0..m).map(|i| y[i] * asm.qp.row(i).norm()).sum();
            let gty = (0..m).fold(nalgebra::SVector::<f64, 6>::zeros(), |acc, i| {
                acc + asm.qp.row(i) * y[i]
            });
            assert!(gty.amax() <= 1e-9 * scale, "case {case}: G'y = {gty:?}");
            let yh: f64 = (0..m).map(|i| y[i] * asm.qp.h[i]).sum();
            assert!(yh < 0.0, "case {case}: y'h = {yh}");
            let certificate = (case % 2 == 0).then_some(y);
            let cb = CaptureBounds::new(ctl.config(), kappa, asm.prediction.heading.omega_bar);
            assert_eq!(cb.is_some(), capture_fraction.is_some());
            let mut count = Counting(0);
            let r = relax(
                solver,
                &mut count,
                &asm.qp,
                &asm.rows,
                64,
                2048,
                12,
                cap,
                cb,
                certificate,
            )
            .unwrap_or_else(|e| panic!("case {case}: {e:?}"));
            solves[count.0.min(31)] += 1;
            let v = class_violation(&asm.qp, &asm.rows, &r.u);
            let (eg, es, ec) = (r.eps_gait, r.eps_safety, r.eps_capture);
            // The capturability bound, relaxed by `ec`, holds.
            let with_capture = |e: f64| cb.map(|c| (c, e));
            if let Some(c) = cb {
                for ((g, h), id) in asm.qp.rows().zip(&asm.rows) {
                    if let Some(room) = c.of(id.kind) {
                        let e = g.dot(&r.u) - h - room;
                        assert!(e <= ec * (1.0 + 1e-9) + 1e-9, "case {case}: {e} {r:?}");
                    }
                }
            } else {
                assert_eq!(ec, 0.0);
            }
            assert!(v.reach <= 1e-9, "case {case}: {v:?}");
            assert!(
                v.gait <= eg * (1.0 + 1e-9) + 1e-9,
                "case {case}: {v:?} {r:?}"
            );
            assert!(
                v.safety <= es * (1.0 + 1e-9) + 1e-9,
                "case {case}: {v:?} {r:?}"
            );
            if ec > 0.0 {
                // Stage 4: the least relaxation of the capturability bound
                // with reachability alone, then the least safety and gait
                // relaxations under it.
                assert!(
                    certified_empty(solver, &asm, None, None, with_capture(less(ec))),
                    "case {case}: {r:?}: capture not minimal"
                );
                if es > 1e-6 {
                    assert!(
                        certified_empty(solver, &asm, None, Some(less(es)), with_capture(ec)),
                        "case {case}: {r:?}: safety not minimal"
                    );
                }
                if eg > 1e-6 {
                    assert!(
                        certified_empty(solver, &asm, Some(less(eg)), Some(es), with_capture(ec)),
                        "case {case}: {r:?}: gait not minimal"
                    );
                }
                stage4 += 1;
                continue;
            }
            if es == 0.0 {
                // Stage 1 (or stage 3 without a safety relaxation): the least
                // gait relaxation with safety kept.
                assert_eq!(r.level, RelaxLevel::Gait);
                assert!(eg > 0.0, "case {case}: the nominal QP is infeasible");
                assert!(
                    certified_empty(solver, &asm, Some(less(eg)), Some(0.0), with_capture(0.0)),
                    "case {case}: {r:?} not minimal"
                );
                stage1 += 1;
                continue;
            }
            assert_eq!(r.level, RelaxLevel::Safety);
            // Safety gives way only when the capped gait rows cannot help.
            assert!(
                certified_empty(solver, &asm, Some(cap), Some(0.0), with_capture(0.0)),
                "case {case}"
            );
            // The least safety relaxation with the gait rows at the cap
            // (stage 2) or left out (stage 3; under the capturability bound
            // when on).
            let gait_bound = (eg <= cap * (1.0 + 1e-9)).then_some(cap);
            assert!(
                certified_empty(solver, &asm, gait_bound, Some(less(es)), with_capture(0.0)),
                "case {case}: {r:?}: safety not minimal"
            );
            // Then the least gait relaxation under that safety relaxation.
            if eg > 1e-6 {
                assert!(
                    certified_empty(solver, &asm, Some(less(eg)), Some(es), with_capture(0.0)),
                    "case {case}: {r:?}: gait not minimal"
                );
            }
            if gait_bound.is_some() {
                stage2 += 1;
            } else {
                stage3 += 1;
            }
        }
        std::println!(
            "{infeasible} infeasible: {stage1} stage 1, {stage2} stage 2, {stage3} stage 3, \
             {stage4} stage 4; solves of the priority scheme (count: cycles): {:?}",
            solves
                .iter()
                .enumerate()
                .filter(|(_, n)| **n > 0)
                .collect::<std::vec::Vec<_>>()
        );
        assert!(
            stage1 >= 20 && stage2 >= 50 && stage3 >= 20 && stage4 >= 10,
            "{stage1} {stage2} {stage3} {stage4}"
        );
    }

    /// The largest body-frame velocity component of a plan's `v_1 .. v_N`
    /// (each in its step's heading frame), m/s.
    fn fastest_component(out: &crate::CycleOutput<3>) -> f64 {
        out.plan
            .states
            .iter()
            .map(|s| {
                let (c, sn) = (libm::cos(s.heading), libm::sin(s.heading));
                let lon = c * s.velocity.x + sn * s.velocity.y;
                let lat = -sn * s.velocity.x + c * s.velocity.y;
                lon.abs().max(lat.abs())
            })
            .fold(0.0, f64::max)
    }

    /// A robot at the end of a step, walking at `vx_max` along x, pushed
    /// sideways to `lateral` m/s, no obstacles, goal far ahead.
    fn pushed(capture_fraction: Option<f64>, forward: f64, lateral: f64) -> crate::CycleOutput<3> {
        let mut ctl = PaperController::new(Config {
            capture_fraction,
            ..Config::default()
        })
        .unwrap();
        let input = CycleInput::<8> {
            com_position: Vector2::zeros(),
            com_velocity: Vector2::new(forward, lateral),
            heading: 0.0,
            turning_rate: 0.0,
            stance_foot: Vector2::new(-0.1, -0.1),
            stance_side: Side::Right,
            time_in_step: 0.4,
            goal: Vector2::new(20.0, 0.0),
            obstacles: &[],
        };
        ctl.step(&input)
    }

    /// Pushed to 0.75 m/s sideways (beyond `vy_max` = 0.4 m/s, but below the
    /// capturable 0.92 |kappa| l_max = 0.898 m/s): the gait rows give way
    /// beyond their cap (stage 3). Without the capturability bound the uniform
    /// relaxation also lets the forward velocity exceed what any step within
    /// reach can stop; with it every planned component stays capturable and
    /// the bound itself is not relaxed.
    #[test]
    fn capturable_push_keeps_the_plan_capturable() {
        let kappa =
            crate::constraints::Condensed::<3>::new(&crate::lip::Lip::new(9.81, 1.0, 0.4)).kappa;
        let limit = kappa.abs() * Config::default().l_max;
        let speed = 0.92 * limit;
        let on = pushed(Some(0.92), 0.8, 0.75);
        let off = pushed(None, 0.8, 0.75);
        std::println!(
            "on: {:?} fastest {:.3}; off: {:?} fastest {:.3}; limit {limit:.3}",
            on.info,
            fastest_component(&on),
            off.info,
            fastest_component(&off)
        );
        assert!(on.info.relax_gait > 0.1, "{:?}", on.info);
        assert_eq!(on.info.relax_capture, 0.0);
        assert!(fastest_component(&on) <= speed + 1e-9);
        assert!(fastest_component(&off) > limit, "{:?}", off.plan);
    }

    /// Pushed forward beyond the bound. At 0.95 m/s (above the bound's
    /// 0.898 m/s, below `|kappa| l_max` = 0.976 m/s) no step within reach
    /// meets the bound at once (`v_1 >= cosh(beta T) v_0 - beta sinh(beta T)
    /// l_max` = 0.927 m/s): the bound is relaxed (stage 4, reported in
    /// `relax_capture`) by just that excess, no planned velocity exceeds the
    /// relaxed bound, and from the planned `v_1` the bound holds again. At
    /// 1.1 m/s the LIP cannot be stopped: the relaxation is reported,
    /// large, and the plan (the slowest possible) still speeds up.
    #[test]
    fn push_beyond_the_bound_is_detected() {
        let lip = crate::lip::Lip::new(9.81, 1.0, 0.4);
        let l_max = Config::default().l_max;
        let kappa = crate::constraints::Condensed::<3>::new(&lip).kappa;
        let speed = 0.92 * kappa.abs() * l_max;
        let bs = lip.beta * lip.sinh_bt;
        // The slowest reachable velocities from v_0.
        let slowest = |v0: f64| {
            let v1 = lip.cosh_bt * v0 - bs * l_max;
            [v1, lip.cosh_bt * v1 - bs * l_max]
        };
        let out = pushed(Some(0.92), 0.95, 0.0);
        let v: std::vec::Vec<f64> = out.plan.states.iter().map(|s| s.velocity.x).collect();
        std::println!("0.95 m/s: {:?} {v:?}", out.info);
        assert!(
            (out.info.relax_capture - (slowest(0.95)[0] - speed)).abs() < 1e-6,
            "{:?}",
            out.info
        );
        let relaxed = speed + out.info.relax_capture + 1e-9;
        assert!(v[0] < 0.95 && v.iter().all(|&x| x <= relaxed), "{v:?}");
        let next = pushed(Some(0.92), v[0], 0.0);
        assert_eq!(next.info.relax_capture, 0.0, "{:?}", next.info);
        let out = pushed(Some(0.92), 1.1, 0.0);
        let v: std::vec::Vec<f64> = out.plan.states.iter().map(|s| s.velocity.x).collect();
        std::println!("1.1 m/s: {:?} {v:?}", out.info);
        assert!(out.info.relax_capture > slowest(1.1)[1] - speed - 1e-6);
        assert!(v[0] > 1.1 && v[1] > v[0], "{v:?}");
        // Not reported when the robot is within the bound.
        let within = pushed(Some(0.92), 0.85, 0.0);
        assert_eq!(within.info.relax_capture, 0.0, "{:?}", within.info);
    }
}
