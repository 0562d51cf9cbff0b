//! The priority scheme for infeasible cycles: which rows give way, and by how
//! little.
//!
//! Rows fall in three classes ([`RowClass`]): leg **reachability** (physical: never
//! relaxed), **safety** (LDCBF and foot clearance), and **gait** (walking velocity
//! and maneuverability). When the nominal QP is infeasible the controller solves,
//! lexicographically:
//!
//! 1. **Gait relaxed.** Keep reachability and safety; relax every gait row by the
//!    same amount `eps_gait` (m/s, on unit-norm rows: `g_i u <= h_i + eps |g_i|`),
//!    the smallest that makes the problem feasible, but at most
//!    [`crate::Config::max_gait_relaxation`]; then minimise the nominal cost
//!    under that relaxation.
//! 2. **Safety relaxed** (when stage 1 needs more than the cap): keep
//!    reachability and the gait rows relaxed by the cap; find the smallest
//!    uniform relaxation `eps_safety` (m) of the safety rows, then, with safety
//!    relaxed by exactly that, the smallest `eps_gait` (<= cap), then minimise
//!    the cost. This is the least-violating reachable step in the sense of the
//!    largest LDCBF violation.
//! 3. **Gait unbounded** (only when reachability and the capped gait rows alone
//!    conflict, i.e. the robot already moves faster than the capped limits): as
//!    stage 2 with no cap.
//!
//! Why the cap: the gait rows bound the CoM velocity at the end of each step,
//! which is what keeps the pendulum capturable with steps inside the
//! reachability box. Relaxing them without bound let cycles that keep meeting
//! an infeasible LDCBF (an obstacle appearing from behind another under LiDAR)
//! speed the robot up, cycle after cycle, past about 0.96 m/s, where no
//! reachable step can stop it, and it fell. With the cap (0.1 m/s by default,
//! so at most 0.9 m/s forward) the safety rows give way first, by the least
//! amount, and the robot stays capturable.
//!
//! Reachability alone is always feasible (each `f_k` may sit at `p_k`), so stage 3
//! always has an answer up to numerical failure or budget exhaustion.
//!
//! Each smallest relaxation is found by a bracketing search between 0 and the
//! violation of the most relaxed solution (feasible): every infeasible probe
//! returns the solver's Farkas certificate `y` (`G'y = 0`, `h'y < 0`), which
//! proves infeasibility for every relaxation below
//! `eps - y'h / (y' |g|_soft)`; the next probe goes just above that bound (and
//! plain bisection takes over when a certificate is unusable). At most
//! [`crate::Config::relax_bisections`] probes; usually two or three, and the
//! reported `eps` is then within about 1e-9 (relative) of the true minimum.
//! Every solve draws on one per-cycle iteration
//! budget ([`crate::Config::max_iter_cycle`]); if it runs out the controller falls
//! back to the previous plan or the capture step.

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

/// Largest violation of each row class by a plan, per unit row norm (m/s for
/// gait rows, m for reachability and safety rows); 0 when the class holds.
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
    for ((g, h, n), id) in qp.rows_with_norm().zip(rows) {
        if n == 0.0 {
            continue;
        }
        let e = (g.dot(u) - h) / n;
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

/// Which rows a relaxed problem keeps, and by how much each class is relaxed
/// (`None`: the class is left out).
#[derive(Clone, Copy, Debug)]
struct Keep {
    safety: Option<f64>,
    gait: Option<f64>,
}

impl Keep {
    fn eps(&self, c: RowClass) -> Option<f64> {
        match c {
            RowClass::Reach => Some(0.0),
            RowClass::Safety => self.safety,
            RowClass::Gait => self.gait,
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
    /// Uniform relaxation of the safety rows, m (0 at stage 1).
    pub eps_safety: f64,
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

/// Runs the priority scheme on the nominal QP `qp` (rows identified by `rows`),
/// using `scratch` as workspace. `budget` is the number of solver iterations left
/// in this cycle; `bisections` the number of halvings per relaxation;
/// `gait_cap` the largest relaxation of the gait rows (m/s) allowed before the
/// safety rows give way.
#[allow(clippy::too_many_arguments)]
pub(crate) fn relax<const NV: usize, const NC: usize, B: QpBackend<NV, NC>>(
    solver: &DualActiveSet<NV, NC>,
    backend: &mut B,
    qp: &DenseQp<NV, NC>,
    rows: &[RowId; NC],
    scratch: &mut DenseQp<NV, NC>,
    max_iter: u32,
    budget: u32,
    bisections: u32,
    gait_cap: f64,
) -> Result<Relaxed<NV>, RelaxError> {
    let mut ctx = Ctx {
        solver,
        backend,
        qp,
        rows,
        scratch,
        max_iter,
        budget,
        used: 0,
        bisections,
    };
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
    // Stage 1: reachability and safety hard, gait soft up to the cap.
    let safe = Keep {
        safety: Some(0.0),
        gait: None,
    };
    if let Some((u, eps)) = ctx.minimal(safe, RowClass::Gait, gait_cap)? {
        return Ok(Relaxed {
            u,
            level: RelaxLevel::Gait,
            eps_gait: eps,
            eps_safety: 0.0,
            iterations: ctx.used,
        });
    }
    // Stage 2: reachability and the capped gait rows hard, safety soft; then, with
    // safety relaxed by exactly that much, the least gait relaxation (<= cap).
    // Stage 3, when even reachability and the capped gait rows conflict (the
    // robot already moves faster than the capped limits allow): the same with
    // the gait rows unbounded.
    for cap in [gait_cap, f64::INFINITY] {
        let reach = Keep {
            safety: None,
            gait: if cap.is_finite() { Some(cap) } else { None },
        };
        let Some((_, eps_s)) = ctx.minimal(reach, RowClass::Safety, f64::INFINITY)? else {
            continue;
        };
        let fixed = Keep {
            safety: Some(eps_s),
            gait: None,
        };
        let (u, eps_g) = ctx
            .minimal(fixed, RowClass::Gait, cap)?
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
            iterations: ctx.used,
        });
    }
    // Reachability alone is always feasible: only numerics get here.
    Err(RelaxFailure::Numerical)
}

/// What one solve of a (relaxed) problem gave.
enum Probe<const NV: usize> {
    /// Feasible, with the optimal plan.
    Feasible(SVector<f64, NV>),
    /// Infeasible, with the certificate's lower bound on the soft relaxation
    /// (`None` without a usable certificate).
    Infeasible(Option<f64>),
}

struct Ctx<'a, const NV: usize, const NC: usize, B> {
    solver: &'a DualActiveSet<NV, NC>,
    backend: &'a mut B,
    qp: &'a DenseQp<NV, NC>,
    rows: &'a [RowId; NC],
    scratch: &'a mut DenseQp<NV, NC>,
    max_iter: u32,
    budget: u32,
    used: u32,
    bisections: u32,
}

impl<const NV: usize, const NC: usize, B: QpBackend<NV, NC>> Ctx<'_, NV, NC, B> {
    /// Builds the problem `keep` into the scratch QP and solves it. When it is
    /// infeasible and `soft` names the class being relaxed, the solver's Farkas
    /// certificate `y` gives a lower bound on the relaxation of that class: with
    /// the soft rows at `h + eps |g|`, `y'h(eps) < 0` certifies infeasibility for
    /// every `eps < eps_now - y'h(eps_now) / (y'|g|_soft)`.
    fn solve(&mut self, keep: Keep, soft: Option<RowClass>) -> Result<Probe<NV>, RelaxFailure> {
        let left = self.budget.saturating_sub(self.used);
        if left == 0 {
            return Err(RelaxFailure::Budget);
        }
        self.scratch.clear();
        self.scratch.q = self.qp.q;
        let mut soft_norm = [0.0f64; NC];
        let mut k = 0usize;
        for ((g, h, n), id) in self.qp.rows_with_norm().zip(self.rows) {
            let class = RowClass::of(id.kind);
            if let Some(eps) = keep.eps(class) {
                // Capacity cannot be exceeded: the scratch QP has the same
                // capacity and receives a subset of the rows.
                if self.scratch.push_row(&g, h + eps * n).is_ok() {
                    if let Some(s) = soft_norm.get_mut(k) {
                        *s = if Some(class) == soft { n } else { 0.0 };
                    }
                    k += 1;
                }
            }
        }
        let sol = self.backend.solve_qp(
            self.solver,
            self.scratch,
            &[false; NC],
            self.max_iter.min(left),
        );
        self.used = self.used.saturating_add(sol.iterations);
        match sol.status {
            QpStatus::Solved => Ok(Probe::Feasible(sol.x)),
            QpStatus::Infeasible => {
                let eps_now = soft.and_then(|c| keep.eps(c)).unwrap_or(0.0);
                let (mut yh, mut yn) = (0.0, 0.0);
                for ((y, (_, h)), n) in sol.lambda.iter().zip(self.scratch.rows()).zip(&soft_norm) {
                    yh += y * h;
                    yn += y * n;
                }
                let lb = eps_now - yh / yn;
                Ok(Probe::Infeasible(
                    (yn > 0.0 && lb.is_finite()).then_some(lb),
                ))
            }
            QpStatus::IterationLimit => Err(RelaxFailure::Budget),
            QpStatus::NumericalError => Err(RelaxFailure::Numerical),
        }
    }

    /// Largest violation of the rows of `class` at `u`, per unit row norm.
    fn violation(&self, class: RowClass, u: &SVector<f64, NV>) -> f64 {
        class_violation(self.qp, self.rows, u).of(class)
    }

    /// With `fixed` kept, the smallest uniform relaxation of `soft`, at most
    /// `cap` (`f64::INFINITY`: unbounded), and the optimal plan under it.
    /// `Ok(None)` when no relaxation up to `cap` is feasible.
    fn minimal(
        &mut self,
        fixed: Keep,
        soft: RowClass,
        cap: f64,
    ) -> Result<Option<(SVector<f64, NV>, f64)>, RelaxFailure> {
        let with = |eps: f64| match soft {
            RowClass::Gait => Keep {
                gait: Some(eps),
                ..fixed
            },
            RowClass::Safety => Keep {
                safety: Some(eps),
                ..fixed
            },
            RowClass::Reach => fixed,
        };
        // The most relaxed problem first: the soft rows at `cap`, or left out.
        let top = if cap.is_finite() { with(cap) } else { fixed };
        let Probe::Feasible(u_top) = self.solve(top, None)? else {
            return Ok(None);
        };
        let mut hi = self.violation(soft, &u_top).min(cap);
        if !hi.is_finite() {
            return Err(RelaxFailure::Numerical);
        }
        if hi <= 0.0 {
            // The most relaxed solution already satisfies the soft rows, so it is
            // also optimal without relaxation.
            return Ok(Some((u_top, 0.0)));
        }
        // Search [lo, hi] (lo: proven infeasible below, hi: feasible). Each
        // infeasible probe's certificate raises `lo` to a proven bound and the
        // next probe goes just above it; without a certificate, bisection. The
        // first probe, eps = 0, is exact when it is feasible.
        let mut lo: f64 = 0.0;
        let mut best: Option<SVector<f64, NV>> = None;
        let mut next: f64 = 0.0;
        for _ in 0..self.bisections {
            let eps = crate::clamp(next, lo, hi);
            match self.solve(with(eps), Some(soft))? {
                Probe::Feasible(u) => {
                    hi = eps;
                    best = Some(u);
                    next = 0.5 * (lo + hi);
                }
                Probe::Infeasible(bound) => {
                    lo = lo.max(eps);
                    next = match bound {
                        Some(b) if b >= lo && b < hi => {
                            lo = b;
                            b * (1.0 + 1e-9) + 1e-12
                        }
                        _ => 0.5 * (lo + hi),
                    };
                }
            }
            if hi - lo <= 1e-9 * (1.0 + hi) {
                break;
            }
        }
        let u = match best {
            Some(u) => u,
            None => {
                // No probe was feasible: `hi` is where `u_top` is feasible, but at
                // the exact minimum the feasible set can shrink to a point that
                // rounding declares empty, so widen it by a hair if needed.
                let mut found = None;
                for pad in [0.0, 1e-9, 1e-7, 1e-5] {
                    let eps = hi * (1.0 + pad) + pad;
                    if let Probe::Feasible(u) = self.solve(with(eps), None)? {
                        hi = eps;
                        found = Some(u);
                        break;
                    }
                }
                found.ok_or(RelaxFailure::Numerical)?
            }
        };
        Ok(Some((u, hi)))
    }
}
