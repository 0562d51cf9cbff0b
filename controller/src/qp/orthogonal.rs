//! The factor of the active set as Goldfarb and Idnani keep it, for one
//! solve ([`Orthogonal`]): `J = L^-T Q` and the upper-triangular `R` of
//! `L^-1 N_A = Q [R; 0]`, with the primal iterate `x` and the rows; the
//! scan's rate of a row ([`rate`]) and the projection `J' g_p` of one. One
//! Householder reflection per add, Givens rotations per drop (no
//! re-factorisation, no normal equations): the updates are
//! `qp/updates.rs`, the steps of the iteration on this factor
//! `qp/step.rs`, the hot start's guess `qp/guess.rs`. The iteration itself
//! is [`crate::active_set::iterate`].

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

use super::bounds::BoundRows;
use super::dense::DenseQpOf;
use super::gram::GuessWork;
use super::kept::{Pending, Resume};
use super::norms::RowNormsOf;
use super::settings::{ZERO_ROW2, proximal_capable};
use super::solver::DualActiveSetOf;
use super::spans::{Span, unpack};
use crate::linalg::{column, columns, dot_d};
use crate::solution::QpAllocator;

/// The factor `J`, `R` a solve works on and its direction workspace `d`
/// (the caller's, [`Orthogonal::J`]).
pub(super) type FactorMut<'a, NV> = (
    &'a mut OMatrix<f64, NV, NV>,
    &'a mut OMatrix<f64, NV, NV>,
    &'a mut OVector<f64, NV>,
);

/// The orthogonal factor of the active set, the iterate and the rows, for one
/// solve. Slices of length `NV` or `NC` as named (constants for the static
/// sizes).
pub(super) struct Orthogonal<'a, NV: Dim, NC: Dim, Bd: BoundRows, Rs: Resume<NV>>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The solver (for `L^-1`, the tolerances and the `H^-1` row norms).
    pub solver: &'a DualActiveSetOf<NV, NC>,
    /// `G'` (`NV x NC`): column `i` is row `i` of `G`. (References to the
    /// nalgebra storage, not slices: their lengths are the types' constants
    /// for the static sizes even where this struct stays in memory.)
    pub rows: &'a OMatrix<f64, NV, NC>,
    /// Right-hand side.
    pub h: &'a OVector<f64, NC>,
    /// `|g_i|^2`.
    pub norm2: &'a OVector<f64, NC>,
    /// `1 / |L^-1 g_i|`, filled on demand (`+0` = not computed yet, `-0`
    /// for a zero row).
    pub inv_hnorm: &'a mut OVector<f64, NC>,
    /// `tol_primal^2`: a row is violated when `slack < 0` and
    /// `slack^2 > tol2 |g_i|^2`.
    pub tol2: f64,
    /// The primal iterate.
    pub x: OVector<f64, NV>,
    /// `J = L^-T Q`: columns `0..nact` span the active normals in the metric
    /// of `H^-1`, the others their complement. (The factors are the caller's
    /// locals, not fields: their addresses go to the add and drop, which the
    /// compiler may leave out of line, and an escaping field would keep every
    /// other field of this struct in memory.)
    pub J: &'a mut OMatrix<f64, NV, NV>,
    /// Upper-triangular `R` (leading `nact x nact` block).
    pub R: &'a mut OMatrix<f64, NV, NV>,
    /// `d = J' n_p` of the last direction (`n_p = -g_p`; the caller's
    /// local, as `J`).
    pub d: &'a mut OVector<f64, NV>,
    /// The primal step direction of the last direction (held here, not
    /// borrowed: the accumulation over the columns of `J` then stays in
    /// registers for the static sizes).
    pub z: OVector<f64, NV>,
    /// The last row `p` was linearly dependent on the active rows.
    pub dependent: bool,
    /// The rows' spans (`qp/spans.rs`): the scan's and the adds' dot
    /// products run over them (the same bits); `None`: over all `NV`
    /// entries.
    pub span: Option<&'a OVector<Span, NC>>,
    /// The proximal iterations' solves (`qp/proximal.rs`), whose rounding
    /// is not tied to earlier results: the adds skip the zero entries of
    /// the Householder vector and the direction's back substitution runs by
    /// columns (`resolve::back_substitute_by_columns`), both faster for
    /// large `NV`; false: the definite path's operations, bit for bit.
    pub reorder: bool,
    /// The rows that are simple bounds (`qp/bounds.rs`): `()` without
    /// (a zero-size type: the solves without bounds compile without a test).
    pub bounds: Bd,
    /// The hot start's guess's kept workspace (`qp/guess.rs`); `None`: the
    /// guess zeroes matrices of its own.
    pub guess: Option<&'a mut GuessWork<NV>>,
    /// The hot start's guess ended the solve: `x` and the multipliers are
    /// the optimum on the marked rows, but `J` and `R` were never formed
    /// for them (still `L^-T` and 0), so the factor must not be kept for a
    /// next probe.
    pub guessed: bool,
    /// The active rows the solve resumes from (`()`: none, from scratch;
    /// `qp/resolve.rs`).
    pub kept: Rs,
    /// The start from scratch `J = L^-T`, `R = 0` still to be set before
    /// `J` or `R` is first read ([`Orthogonal::settle`]; `qp/reprobe.rs`);
    /// `None`: set already.
    pub pending: Option<&'a mut Pending>,
}

impl<'a, NV: Dim, NC: Dim, Bd: BoundRows, Rs: Resume<NV>> Orthogonal<'a, NV, NC, Bd, Rs>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The factor of a solve of `qp`'s rows with the right-hand side `h`,
    /// the row norms `norms`, the primal tolerance `tol`, from the iterate
    /// `x` and the factor `J`, `R` (`d` the direction's workspace), the
    /// bound rows `bounds` and the kept rows `kept`: no spans, the definite
    /// path's order of operations, no guess workspace (set the fields
    /// [`Orthogonal::span`], [`Orthogonal::reorder`] and
    /// [`Orthogonal::guess`] after).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn new(
        solver: &'a DualActiveSetOf<NV, NC>,
        qp: &'a DenseQpOf<NV, NC>,
        h: &'a OVector<f64, NC>,
        norms: &'a mut RowNormsOf<NC>,
        tol: f64,
        x: OVector<f64, NV>,
        (J, R, d): FactorMut<'a, NV>,
        bounds: Bd,
        kept: Rs,
    ) -> Self {
        Orthogonal {
            solver,
            rows: &qp.gt,
            h,
            norm2: &norms.norm2,
            inv_hnorm: &mut norms.inv_hnorm,
            tol2: tol * tol,
            x,
            J,
            R,
            d,
            z: OVector::zeros_generic(solver.nv(), nalgebra::U1),
            dependent: false,
            span: None,
            reorder: false,
            bounds,
            guess: None,
            guessed: false,
            kept,
            pending: None,
        }
    }

    /// Sets the start from scratch if it is still [`Orthogonal::pending`]:
    /// before the first read of `J` or `R` (every step but the scan and the
    /// hot start's guess). Nothing on bare-metal targets and below the hot
    /// start's sizes (never pending there).
    #[inline(always)]
    pub(super) fn settle(&mut self) {
        // (A constant for the static sizes: nothing below the hot start's
        // sizes either, which never leave it pending.)
        if cfg!(target_os = "none") || !self.solver.hot_start_capable() {
            return;
        }
        if let Some(p) = self.pending.as_deref_mut()
            && p.unset
        {
            set_scratch(self.J, self.R, &self.solver.J0, p.r_cols);
            *p = Pending::NONE;
        }
    }

    /// Number of variables (a constant for the static sizes).
    #[inline(always)]
    pub(super) fn n(&self) -> usize {
        self.solver.nv().value()
    }

    /// Row `i` of `G` and `h_i`.
    #[inline(always)]
    pub(super) fn row(&self, i: usize) -> Option<(&'a [f64], f64)> {
        Some((
            column(self.rows.as_slice(), self.n(), i)?,
            *self.h.as_slice().get(i)?,
        ))
    }

    /// The span of row `i`: `None` without spans, and always (a constant)
    /// for the static sizes without the proximal iterations.
    #[inline(always)]
    fn span_of(&self, i: usize) -> Option<(usize, usize)> {
        if !proximal_capable::<NV>() {
            return None;
        }
        let s = self.span?.as_slice().get(i)?;
        Some(unpack(*s))
    }

    /// [`Orthogonal::reorder`], a constant `false` for the static sizes
    /// without the proximal iterations.
    #[inline(always)]
    pub(super) fn reordered(&self) -> bool {
        proximal_capable::<NV>() && self.reorder
    }

    /// Row `i` as a simple bound `(j, s)` (the row `s e_j`): always `None`
    /// without bounds.
    #[inline(always)]
    pub(super) fn bound(&self, i: usize) -> Option<(usize, f64)> {
        self.bounds.bound(i)
    }

    /// `g_i'x` of the bound row `s e_j`: `s x_j`, as the dot product over
    /// the row gives it (the other products are exact zeros; `0.0 +` turns
    /// a `-0` into the `+0` the sum of the partial sums gives).
    #[inline(always)]
    pub(super) fn bound_dot(&self, j: usize, s: f64) -> f64 {
        0.0 + s * self.x.as_slice().get(j).copied().unwrap_or(f64::NAN)
    }

    /// [`ActiveSetFactor::violation`] of row `i` when it is a bound (one
    /// subtraction, `|g_i|^2 = 1`, `1 / |L^-1 g_i|` from column `j` of
    /// `L^-1`); `None` for a general row (always without bounds).
    #[inline(always)]
    pub(super) fn bound_violation(&mut self, i: usize, blocked: bool) -> Option<Option<f64>> {
        let (j, s) = self.bound(i)?;
        let gx = self.bound_dot(j, s);
        let solver = self.solver;
        let (Some(&hi), Some(&n2), Some(ihn)) = (
            self.h.as_slice().get(i),
            self.norm2.as_slice().get(i),
            self.inv_hnorm.as_mut_slice().get_mut(i),
        ) else {
            return Some(None);
        };
        if blocked {
            return Some(None);
        }
        Some(rate_by(self.tol2, n2, ihn, hi - gx, || {
            solver.inv_hnorm_unit(j)
        }))
    }

    /// [`ActiveSetFactor::violation`] with the slack's dot product over all
    /// of the row (`SPANNED` false) or over the row's span (the same bits).
    // Row norms: Euclidean for the scale-free violation test, and in the
    // metric of H^-1 (|J0' g_i| = |L^-1 g_i|) for choosing which row to add:
    // `s_i / |L^-1 g_i|` is the square root of the cost increase of enforcing
    // row i alone, which picks rows that matter and roughly halves the
    // add/drop count on the controller's QPs compared with the Euclidean rule.
    // A row is violated when `slack / |g| < -tol`, tested without the square
    // root as `slack < 0` and `slack^2 > tol^2 |g|^2`.
    #[inline(always)]
    pub(super) fn violation_over<const SPANNED: bool>(
        &mut self,
        i: usize,
        blocked: bool,
    ) -> Option<f64> {
        if let Some(v) = self.bound_violation(i, blocked) {
            return v;
        }
        let n = self.n();
        let (Some(g), Some(&hi), Some(&n2), Some(ihn)) = (
            column(self.rows.as_slice(), n, i),
            self.h.as_slice().get(i),
            self.norm2.as_slice().get(i),
            self.inv_hnorm.as_mut_slice().get_mut(i),
        ) else {
            return None;
        };
        if blocked {
            return None;
        }
        let gx = if SPANNED {
            // (Spans only where the proximal iterations are compiled in: a
            // constant full range for the small static sizes.)
            let (lo, up) = self
                .span
                .filter(|_| proximal_capable::<NV>())
                .and_then(|sp| sp.as_slice().get(i))
                .map_or((0, n), |&s| unpack(s));
            dot_d::<NV>(
                g.get(lo..up).unwrap_or(&[]),
                self.x.as_slice().get(lo..up).unwrap_or(&[]),
            )
        } else {
            // (`dot_d`: as pairs for run-time sizes, the scan over all rows.)
            dot_d::<NV>(g, self.x.as_slice())
        };
        rate(self.solver, self.tol2, g, n2, ihn, hi - gx)
    }

    /// `d = J' n_p = -J' g_p` (`g_p` row `p`).
    #[inline(always)]
    pub(super) fn project(&mut self, gp: &[f64], p: usize) {
        let n = self.n();
        if let Some((j, s)) = self.bound(p) {
            // Row j of J (column-major): entry (j, k) of column k.
            let js = self.J.as_slice();
            for (k, dk) in self.d.as_mut_slice().iter_mut().enumerate() {
                let jk = k.checked_mul(n).and_then(|a| js.get(a + j)).copied();
                *dk = -(0.0 + s * jk.unwrap_or(f64::NAN));
            }
            return;
        }
        if let Some((lo, hi)) = self.span_of(p) {
            let g = gp.get(lo..hi).unwrap_or(&[]);
            for (dj, col) in self
                .d
                .as_mut_slice()
                .iter_mut()
                .zip(columns(self.J.as_slice(), n))
            {
                *dj = -dot_d::<NV>(col.get(lo..hi).unwrap_or(&[]), g);
            }
            return;
        }
        for (dj, col) in self
            .d
            .as_mut_slice()
            .iter_mut()
            .zip(columns(self.J.as_slice(), n))
        {
            *dj = -dot_d::<NV>(col, gp);
        }
    }
}

/// Whether `slack` is `+0` or positive and finite (the common case of the
/// scan, a row that holds): the sign bit clear and the exponent below that of
/// infinity and NaN, one integer compare of the high word instead of the two
/// floating-point compares (each with its flags transfer on the M7) of the
/// finiteness and sign tests. Every other slack (`-0`, negative, infinite or
/// NaN) takes those tests as before, so the answer of [`rate`] is unchanged.
#[inline(always)]
fn holds(slack: f64) -> bool {
    ((slack.to_bits() >> 32) as u32) < 0x7ff0_0000
}

/// The end of [`ActiveSetFactor::violation`] for row `g` (`|g|^2 = n2`, its
/// cached `1 / |L^-1 g|` in `ihn`, `+0` = not yet) with the slack `slack`:
/// `None` when it holds to the tolerance, NaN when the slack is not finite,
/// else the slack in the metric of `H^-1`, which is `+0` for a zero row
/// (`n2 = 0`; [`DualActiveSetOf::inv_hnorm`] gives it `-0`): never below the
/// scan's start of 0, so a zero row is never added. No test of `n2` here on
/// bare-metal targets: LLVM moves one before the dot product of every row of
/// the scan, even when it is written after the test that the row holds.
#[inline(always)]
pub(super) fn rate<NV: Dim, NC: Dim>(
    solver: &DualActiveSetOf<NV, NC>,
    tol2: f64,
    g: &[f64],
    n2: f64,
    ihn: &mut f64,
    slack: f64,
) -> Option<f64>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    if holds(slack) {
        return None;
    }
    // On hosts the test of a zero row here keeps the vectorised scan shorter
    // (the lipmwalk solves of `tools/icount.py`: 9 % fewer instructions).
    if cfg!(not(target_os = "none")) && n2 <= ZERO_ROW2 {
        return None;
    }
    if !slack.is_finite() {
        return Some(f64::NAN);
    }
    if slack >= 0.0 || slack * slack <= tol2 * n2 {
        return None; // satisfied to tolerance
    }
    // (A zero row gets here only with `-tol <= slack < 0`: one that
    // contradicts itself ended the solve at its start.)
    if ihn.to_bits() == 0 {
        *ihn = solver.inv_hnorm(g, n2);
    }
    // Not NaN: `slack` is finite and nonzero, and `*ihn` positive (possibly
    // infinite) or, for a zero row, `-0`.
    Some(slack * *ihn)
}

/// [`rate`] with the `1 / |L^-1 g|` of the row from `inv_hnorm` (called
/// when not cached yet).
#[inline(always)]
pub(super) fn rate_by(
    tol2: f64,
    n2: f64,
    ihn: &mut f64,
    slack: f64,
    inv_hnorm: impl FnOnce() -> f64,
) -> Option<f64> {
    if holds(slack) {
        return None;
    }
    // A zero row is never added (one that contradicts itself ended the solve
    // at its start): tested here, after the common case, not before the dot
    // product.
    if n2 <= ZERO_ROW2 {
        return None;
    }
    if !slack.is_finite() {
        return Some(f64::NAN);
    }
    if slack >= 0.0 || slack * slack <= tol2 * n2 {
        return None; // satisfied to tolerance
    }
    if *ihn == 0.0 {
        *ihn = inv_hnorm();
    }
    // Not NaN: `slack` is finite and `*ihn` positive (possibly infinite).
    Some(slack * *ihn)
}

/// `J = J0` and the columns `0..r_cols` of `R` zeroed (the others are zero
/// already): the start from scratch of a solve ([`Orthogonal::settle`]).
/// Out of line: at most once per solve.
#[inline(never)]
fn set_scratch<NV: Dim>(
    J: &mut OMatrix<f64, NV, NV>,
    R: &mut OMatrix<f64, NV, NV>,
    J0: &OMatrix<f64, NV, NV>,
    r_cols: usize,
) where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    crate::linalg::copy(J.as_mut_slice(), J0.as_slice());
    let n = R.nrows();
    let end = r_cols.min(R.ncols()).saturating_mul(n);
    if let Some(cols) = R.as_mut_slice().get_mut(..end) {
        cols.fill(0.0);
    }
}
