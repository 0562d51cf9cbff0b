//! One step of the dual iteration on the orthogonal factor, as
//! [`crate::active_set::iterate`] asks for it ([`ActiveSetFactor`]): the
//! scan's rate of a row, the direction `d = J' n_p` and the primal step
//! `z`, the move of `x`, the add of a row (one Householder reflection) or
//! the drop of one (Givens rotations; both `qp/updates.rs`), and the hot
//! start's steps (the guess, `qp/guess.rs`; the adds without a step; the
//! multipliers and the move onto the marked rows).

#[cfg(not(target_os = "none"))]
use nalgebra::OVector;
use nalgebra::{DefaultAllocator, Dim, OMatrix};

use super::bounds::BoundRows;
use super::kept::{Kept, Resume};
use super::orthogonal::Orthogonal;
use super::updates::{back_substitute, back_substitute_by_columns, givens_drop, householder_add};
use crate::active_set::{ActiveSetFactor, AddError};
use crate::linalg::{columns, columns_in, dot};
use crate::solution::QpAllocator;

impl<NV: Dim, NC: Dim, Bd: BoundRows, Rs: Resume<NV>> ActiveSetFactor
    for Orthogonal<'_, NV, NC, Bd, Rs>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The scan's rate of row `i` (over all of the row, or over
    /// the row's span for a solve that may resume).
    #[inline(always)]
    fn violation(&mut self, i: usize, blocked: bool) -> Option<f64> {
        // Without spans (every solve but the proximal ones) on hosts the
        // iteration's own scan: a constant-length dot product for the static
        // sizes (bare-metal targets: the resumed solves' code below, one copy
        // in flash).
        if !Rs::RESUMES || (cfg!(not(target_os = "none")) && self.span.is_none()) {
            return self.violation_over::<false>(i, blocked);
        }
        self.violation_over::<true>(i, blocked)
    }

    #[inline(always)]
    fn direction(&mut self, p: usize, _act: &[u16], nact: usize, r: &mut [f64]) -> Option<f64> {
        self.settle();
        let n = self.n();
        let (gp, hp) = self.row(p)?;
        // d = J' n_p with the GI normal n_p = -g_p (n_p'x >= -h_p).
        self.project(gp, p);
        // < 0 while violated
        let slack_p = match self.bound(p) {
            Some((j, s)) => hp - self.bound_dot(j, s),
            None => hp - dot(gp, self.x.as_slice()),
        };
        // z = J2 d2: component of the step outside the active span. For the
        // static sizes on hosts accumulated in a local vector (kept in vector
        // registers) and stored after the loop: accumulated in the field, all
        // of `z` was stored after every column. Run-time sizes (no allocation
        // per direction) and bare-metal targets (whose scalar code this does
        // not shorten) accumulate in the field.
        #[cfg(not(target_os = "none"))]
        let mut local = NV::try_to_usize()
            .map(|_| OVector::<f64, NV>::zeros_generic(self.solver.nv(), nalgebra::U1));
        #[cfg(not(target_os = "none"))]
        let z = match local.as_mut() {
            Some(l) => l.as_mut_slice(),
            None => self.z.as_mut_slice(),
        };
        #[cfg(target_os = "none")]
        let z = self.z.as_mut_slice();
        z.fill(0.0);
        let mut d2sq = 0.0;
        let d2 = self.d.as_slice().get(nact..).unwrap_or(&[]);
        for (col, &dj) in columns_in(self.J.as_slice(), n, nact, n).zip(d2) {
            for (zk, c) in z.iter_mut().zip(col) {
                *zk += c * dj; // column j of J, j >= nact
            }
            d2sq += dj * dj;
        }
        #[cfg(not(target_os = "none"))]
        if let Some(l) = &local {
            crate::linalg::copy(self.z.as_mut_slice(), l.as_slice());
        }
        if self.reordered() {
            back_substitute_by_columns(self.R, self.d.as_slice(), nact, r);
        } else {
            back_substitute(self.R, self.d.as_slice(), nact, r);
        }
        // Full (primal) step length t2.
        let dn = crate::linalg::sqrt(dot(self.d.as_slice(), self.d.as_slice()));
        let dependent = crate::linalg::sqrt(d2sq) <= self.solver.settings.tol_dependence * dn;
        let t2 = if dependent {
            f64::INFINITY
        } else {
            -slack_p / d2sq
        };
        self.dependent = dependent;
        Some(t2)
    }

    #[inline(always)]
    fn advance(&mut self, _p: usize, t: f64, _r: &[f64], _act: &[u16], _nact: usize) {
        if !self.dependent {
            for (xk, zk) in self
                .x
                .as_mut_slice()
                .iter_mut()
                .zip(self.z.as_slice().iter())
            {
                *xk += t * zk;
            }
        }
    }

    /// Adds row `p` (see [`householder_add`]).
    #[inline(always)]
    fn add(&mut self, _p: usize, _r: &[f64], nact: usize) -> Result<(), AddError> {
        self.settle();
        let added = if self.reordered() {
            householder_add::<NV, true>(self.J, self.R, nact, self.d.as_slice())
        } else {
            householder_add::<NV, false>(self.J, self.R, nact, self.d.as_slice())
        };
        if added {
            Ok(())
        } else {
            Err(AddError::Numerical)
        }
    }

    /// Removes active row `l` (see [`givens_drop`]).
    #[inline(always)]
    fn drop(&mut self, l: usize, nact: usize) {
        self.settle();
        givens_drop(self.J, self.R, nact, l);
    }

    #[inline(always)]
    fn hot_start_capable(&self) -> bool {
        self.solver.hot_start_capable()
    }

    #[inline(always)]
    fn equalities_capable(&self) -> bool {
        self.solver.equalities_capable()
    }

    #[inline(always)]
    fn slack(&self, i: usize) -> (f64, f64) {
        match (self.row(i), self.norm2.as_slice().get(i)) {
            (Some((g, hi)), Some(&n2)) => (hi - dot(g, self.x.as_slice()), self.tol2 * n2),
            _ => (f64::NAN, 0.0),
        }
    }

    /// On the normal equations of the marked rows: `M = G_A L^-T` (rows
    /// `m_j = L^-1 g_j`), `K = M M'` by Cholesky (a pivot below `1e-10` of its
    /// diagonal entry, i.e. nearly dependent rows, gives up),
    /// `K lambda = G_A x0 - h_A`, `x = x0 - L^-T M' lambda`; then one pass
    /// over all rows. Cheaper than the adds of `J` and `R` (`O(k^2 NV)`
    /// against `O(k NV^2)`), which are only needed if an iteration follows.
    fn hot_guess(&mut self, act: &[u16], k: usize, mult: &mut [f64], blocked: &[bool]) -> bool {
        // In the kept workspace (written where read, `qp/guess.rs`), or in
        // zeroed matrices of its own.
        let held = match self.guess.take() {
            Some(work) => {
                let held = self.guess_in(&mut work.M, &mut work.T, act, k, mult, blocked);
                self.guess = Some(work);
                held
            }
            None => {
                let nv = self.solver.nv();
                let mut M = OMatrix::<f64, NV, NV>::zeros_generic(nv, nv);
                let mut T = OMatrix::<f64, NV, NV>::zeros_generic(nv, nv);
                self.guess_in(&mut M, &mut T, act, k, mult, blocked)
            }
        };
        self.guessed = held;
        held
    }

    /// `d = J' n_p`, then the add of [`householder_add`] unless the part of
    /// `d` outside the active span is below `tol_dependence |d|`.
    fn hot_add(&mut self, p: usize, _act: &[u16], nact: usize) -> Result<bool, AddError> {
        self.settle();
        let Some((gp, _)) = self.row(p) else {
            return Err(AddError::Numerical);
        };
        self.project(gp, p);
        let mut d2sq = 0.0;
        for &dj in self.d.as_slice().iter().skip(nact) {
            d2sq += dj * dj;
        }
        let outside = crate::linalg::sqrt(d2sq);
        let dn = crate::linalg::sqrt(dot(self.d.as_slice(), self.d.as_slice()));
        if outside.is_nan() || outside <= self.solver.settings.tol_dependence * dn {
            return Ok(false);
        }
        let added = if self.reordered() {
            householder_add::<NV, true>(self.J, self.R, nact, self.d.as_slice())
        } else {
            householder_add::<NV, false>(self.J, self.R, nact, self.d.as_slice())
        };
        if added {
            Ok(true)
        } else {
            Err(AddError::Numerical)
        }
    }

    /// With the active normals `N = [-g_a]` (`J' N = [R; 0]`) and `x` the
    /// current iterate: `R' w = c`, `c_j = g_j'x - h_j` (forward
    /// substitution; `w` kept in `d`), and `mult = R^-1 w`; the minimiser on
    /// the active rows is `x + J1 w` ([`ActiveSetFactor::hot_move`]).
    fn hot_multipliers(&mut self, act: &[u16], nact: usize, mult: &mut [f64]) -> bool {
        self.settle();
        let n = nact.min(self.n());
        self.d.as_mut_slice().fill(0.0);
        for j in 0..n {
            let Some(&a) = act.get(j) else {
                return false;
            };
            let Some((g, ha)) = self.row(usize::from(a)) else {
                return false;
            };
            let mut acc = dot(g, self.x.as_slice()) - ha;
            for k in 0..j {
                if let (Some(&rkj), Some(&wk)) = (self.R.get((k, j)), self.d.as_slice().get(k)) {
                    acc -= rkj * wk;
                }
            }
            let (Some(&rjj), Some(wj)) = (self.R.get((j, j)), self.d.as_mut_slice().get_mut(j))
            else {
                return false;
            };
            *wj = acc / rjj;
        }
        mult.fill(0.0);
        back_substitute(self.R, self.d.as_slice(), n, mult);
        mult.iter()
            .chain(self.d.as_slice().iter())
            .all(|v| v.is_finite())
    }

    fn hot_move(&mut self, _act: &[u16], nact: usize) {
        self.settle();
        let n = self.n();
        for (col, &wj) in columns(self.J.as_slice(), n)
            .zip(self.d.as_slice().iter())
            .take(nact)
        {
            for (xk, c) in self.x.as_mut_slice().iter_mut().zip(col) {
                *xk += c * wj;
            }
        }
    }

    fn resume(&mut self, act: &mut [u16], mult: &mut [f64]) -> Option<(usize, usize)> {
        let kept: &Kept<NV> = self.kept.kept()?;
        for (a, &k) in act.iter_mut().zip(kept.act.as_slice()) {
            *a = k;
        }
        for (u, &k) in mult.iter_mut().zip(kept.mult.as_slice()) {
            *u = k;
        }
        Some((kept.nact, kept.neq))
    }
}
