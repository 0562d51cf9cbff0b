//! The search for a smallest uniform relaxation (see "Finding the smallest
//! relaxation" in the module docs of [`crate::relax`]): Farkas certificates
//! of infeasible solves ([`Certificate`]) and the lower bounds they prove,
//! and the probes of the relaxed problems ([`Ctx::minimal`]).

use nalgebra::SVector;

use super::RelaxFailure;
use super::rows::{CaptureBounds, Keep, RowClass, Soft, class_violation};
use crate::constraints::RowId;
use crate::qp::{DenseQp, DualActiveSet, QpBackend, QpStatus, Reprobe};

/// The sums of a Farkas certificate `y` (`y >= 0`, `G'y = 0`) that matter for
/// every relaxation of the same rows: with the gait rows at `h + e_g` and
/// the safety rows at `h + e_s`, `y'h(e) = yh + e_g yg + e_s ys (+ e_c yc)`,
/// and the relaxed problem is infeasible whenever that is negative. A gait row
/// whose right-hand side was the capturability ceiling `h + room + e_c` counts
/// in `yh` (with `y room`) and `yc`: since each gait row's right-hand side is
/// the smaller of its two forms, this linear form is never below the true
/// `y'h(e)`, so it still proves emptiness wherever it is negative.
#[derive(Clone, Copy, Debug)]
pub(super) struct Certificate {
    /// `y'h` at no relaxation (with the capturability ceilings' headroom).
    pub(super) yh: f64,
    /// Sum of `y` over the gait rows in their gait form (0: they take no part).
    yg: f64,
    /// Sum of `y` over the safety rows.
    ys: f64,
    /// Sum of `y` over the gait rows in their capturability form.
    yc: f64,
    /// Sum of `y` over the safety rows outside the conflict while confined
    /// (not relaxed: they count in `yh` only).
    yo: f64,
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
    /// The certificate once every safety row of its support has joined the
    /// conflict (they take the safety relaxation from then on).
    pub(super) fn with_conflict_grown(self) -> Certificate {
        Certificate {
            ys: self.ys + self.yo,
            yo: 0.0,
            ..self
        }
    }

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
pub(super) enum Probe<const NV: usize> {
    /// Feasible, with the optimal plan.
    Feasible(SVector<f64, NV>),
    /// Infeasible (the certificate is kept in [`Ctx::cert`]).
    Infeasible,
}

pub(super) struct Ctx<'a, const NV: usize, const NC: usize, B> {
    /// The capturability bound (`None`: off).
    pub(super) capture: Option<CaptureBounds>,
    pub(super) solver: &'a DualActiveSet<NV, NC>,
    pub(super) backend: &'a mut B,
    pub(super) qp: &'a DenseQp<NV, NC>,
    pub(super) rows: &'a [RowId; NC],
    pub(super) max_iter: u32,
    pub(super) budget: u32,
    pub(super) used: u32,
    /// Probes per search.
    pub(super) probes: u32,
    /// Probes left for the whole scheme.
    pub(super) probes_left: u32,
    /// The certificate of the last infeasible probe.
    pub(super) cert: Option<Certificate>,
    /// Rows of the nominal QP in the support of any certificate of this
    /// cycle (the nominal solve's, when it proves the nominal QP empty, and
    /// each infeasible probe's): every row some certificate weighed.
    pub(super) support: [bool; NC],
    /// While `confined`: the safety rows that take the safety relaxation (the
    /// conflict); every other safety row keeps its nominal right-hand side.
    pub(super) conflict: [bool; NC],
    /// Whether the safety relaxation applies to the `conflict` rows only.
    pub(super) confined: bool,
    /// What the probes share: the row norms and the factor of the last
    /// probe's active rows, which the next continues from
    /// ([`QpBackend::solve_reprobe`]).
    pub(super) reprobe: &'a mut Reprobe<NV, NC>,
    /// Rows a probe adds first among violated ones (the marks of
    /// [`QpBackend::solve_reprobe`]): on a cycle that gives way, the rows
    /// active at the last cycle's relaxed plan; else none.
    pub(super) prefer: &'a [bool; NC],
}

/// Relative and absolute padding of a probe above a proven lower bound.
const PAD: f64 = 1e-9;

impl<const NV: usize, const NC: usize, B: QpBackend<NV, NC>> Ctx<'_, NV, NC, B> {
    /// Solves the problem `keep`: the nominal QP's rows that `keep` keeps, with
    /// its right-hand sides, in place ([`QpBackend::solve_reprobe`]: no copy of
    /// the rows), continuing from the active rows of the solve before. An
    /// infeasible solve leaves its certificate in `self.cert` and its support
    /// in `self.support`. Not inlined: one copy of the solver call in flash.
    #[inline(never)]
    pub(super) fn solve(&mut self, keep: Keep) -> Result<Probe<NV>, RelaxFailure> {
        let left = self.budget.saturating_sub(self.used);
        if left == 0 {
            return Err(RelaxFailure::Budget);
        }
        let mut h = SVector::<f64, NC>::zeros();
        let mut enabled = [false; NC];
        for ((((&h0, id), hi), on), &c) in self
            .qp
            .h
            .as_slice()
            .iter()
            .zip(self.rows)
            .zip(h.as_mut_slice().iter_mut())
            .zip(&mut enabled)
            .zip(&self.conflict)
            .take(self.qp.m)
        {
            if let Some((rhs, _)) = keep.rhs(id.kind, h0, self.capture.as_ref()) {
                // While confined, safety rows outside the conflict keep their
                // full margin.
                let outside = self.confined && !c && RowClass::of(id.kind) == RowClass::Safety;
                *hi = if outside { h0 } else { rhs };
                *on = true;
            }
        }
        // The probe continues from the last one's active rows (or, the first
        // of a cycle that gives way, starts from scratch with the marks).
        let sol = self.backend.solve_reprobe(
            self.solver,
            self.qp,
            &h,
            &enabled,
            self.prefer,
            self.max_iter.min(left),
            self.reprobe,
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
    /// infeasible solve of the problem `keep`: its sums in [`Ctx::cert`], and
    /// its support added to [`Ctx::support`].
    pub(super) fn take_certificate(&mut self, lambda: &SVector<f64, NC>, keep: Keep) {
        let mut c = Certificate {
            yh: 0.0,
            yg: 0.0,
            ys: 0.0,
            yc: 0.0,
            yo: 0.0,
            yn: 0.0,
        };
        let m = self.qp.m.min(NC);
        let lambda = lambda.as_slice();
        // Weights at rounding level (~1e-17 of the largest) are not
        // part of the certificate's support.
        let floor = 1e-12 * lambda.iter().fold(0.0f64, |a, y| a.max(y.abs()));
        for (o, ((&y, &h), id)) in lambda
            .iter()
            .zip(self.qp.h.as_slice())
            .zip(self.rows)
            .enumerate()
            .take(m)
        {
            // (NaN weights are skipped too.)
            if y.partial_cmp(&floor) != Some(core::cmp::Ordering::Greater) {
                continue;
            }
            if let Some(s) = self.support.get_mut(o) {
                *s = true;
            }
            c.yh += y * h;
            c.yn += y * self.reprobe.norm(o);
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
                // A confined safety row outside the conflict is not relaxed:
                // its weight is in `yh` only.
                RowClass::Safety
                    if self.confined && !self.conflict.get(o).copied().unwrap_or(false) =>
                {
                    c.yo += y
                }
                RowClass::Safety => c.ys += y,
                RowClass::Reach => {}
            }
        }
        self.cert = (c.yh.is_finite() && c.yn.is_finite()).then_some(c);
    }

    /// Largest violation at `u` (physical units) of the safety rows, the gait
    /// rows, or the capturability bound.
    pub(super) fn violation(&self, soft: Soft, u: &SVector<f64, NV>) -> f64 {
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
    pub(super) fn minimal(
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
