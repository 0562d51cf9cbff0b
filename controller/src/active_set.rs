//! The Goldfarb–Idnani dual active-set iteration, written once for both
//! representations of the active set: the orthogonal factor `J = L^-T Q`,
//! `R` of [`DualActiveSet::solve`](crate::qp::DualActiveSet::solve)
//! (`qp.rs`) and the Cholesky factor of `M_A M_A'` of
//! [`LdpSolver::solve`](crate::ldp::LdpSolver::solve) (`ldp.rs`).
//!
//! [`iterate`] holds everything the two share: the choice of the row to add
//! (most violated in the metric of `H^-1`, marked rows first), the budget, the
//! partial (dual) step length with its ratio test and the row to drop, the
//! choice between a partial and a full step, the multiplier update, the active
//! list and its add/drop bookkeeping, the termination and status, and the
//! Farkas certificate when no multiplier can decrease. What depends on the
//! representation is behind [`ActiveSetFactor`]: how a row's violation is
//! measured, how the step direction `r = (N_A' H^-1 N_A)^-1 N_A' H^-1 n_p`
//! and the full step length are found, how the iterate moves, and how an add
//! or a drop updates the factor. [`Iterate::solution`] turns the result into
//! a [`QpSolution`] (multipliers and certificate in the units of `G`).
//!
//! Speed: [`iterate`] and the hot methods of both factors are
//! `#[inline(always)]`, so each solver compiles to one function as when the
//! loop was written out in each (see `docs/solvers.md`, "One iteration for
//! both representations", for the measurements). The state shared by the loop
//! is only the active list, its multipliers, the direction `r` (length `NV`)
//! and the flags of blocked rows (length `NC`); a solver generic over nalgebra
//! dimensions would make these its storage types and the trait generic over
//! the same dimensions, the loop itself unchanged.

use nalgebra::SVector;

use crate::qp::{QpSolution, QpStatus};

/// Why [`ActiveSetFactor::add`] did not add the row.
pub(crate) enum AddError {
    /// The factor could not take the row (full, zero or non-finite pivot).
    Numerical,
    /// The factor would lose too much accuracy: the caller restarts with
    /// another representation ([`iterate`] returns `None`).
    Restart,
}

/// One representation of the active set and of the primal iterate, as the
/// dual iteration of [`iterate`] needs it. Active rows are numbered `0..nact`
/// in the order of the active list `act`.
pub(crate) trait ActiveSetFactor<const NV: usize> {
    /// The violation of row `i` (`i < m`) at the current iterate: `None` when
    /// the row is `blocked` (active, left out or a zero row; the
    /// representation tests this where it is cheapest: before a dot product,
    /// or after the sign of a stored slack) or holds to the primal tolerance,
    /// else its (negative) slack in the metric of `H^-1`,
    /// `slack_i / |L^-1 g_i|` (the most negative is added), or NaN when the
    /// slack is not finite (the solve stops with
    /// [`QpStatus::NumericalError`]). An `Option` with early returns keeps the
    /// common case, a row that holds, one compare and branch (a three-way
    /// enum was compiled branch-free and made the scan 4x longer).
    fn violation(&mut self, i: usize, blocked: bool) -> Option<f64>;

    /// The step for adding row `p` with `nact` active rows `act`: writes the
    /// dual direction into `r` (entries `0..nact`, the change of the active
    /// multipliers per unit multiplier of `p` is `-r`; `r` comes zeroed) and
    /// returns the full (primal) step length `t2` (infinite when `p`'s normal
    /// lies in the span of the active normals). `None` when row `p` does not
    /// exist. The factor keeps what [`ActiveSetFactor::advance`] and
    /// [`ActiveSetFactor::add`] need.
    fn direction(
        &mut self,
        p: usize,
        act: &[u16; NV],
        nact: usize,
        r: &mut [f64; NV],
    ) -> Option<f64>;

    /// Moves the primal iterate by a step of length `t` along the direction of
    /// the last [`ActiveSetFactor::direction`] (nothing when `p` was
    /// dependent).
    fn advance(&mut self, p: usize, t: f64, r: &[f64; NV], act: &[u16; NV], nact: usize);

    /// Appends row `p` as active row `nact` after a full step.
    fn add(&mut self, p: usize, r: &[f64; NV], nact: usize) -> Result<(), AddError>;

    /// Removes active row `l` of `nact`.
    fn drop(&mut self, l: usize, nact: usize);

    /// Whether [`iterate`] may hot-start this representation (the three
    /// methods below); when false they are never called.
    const HOT_START: bool = false;

    /// Hot start, a guess first: whether the minimiser on the `k` rows `act`
    /// held as equalities is the solution (its multipliers `>= 0`, written to
    /// `mult[..k]`, and every row not `blocked` holds to the tolerance); then
    /// it is the iterate, and the factor need not be built. False leaves the
    /// iterate as it was.
    fn hot_guess(
        &mut self,
        _act: &[u16; NV],
        _k: usize,
        _mult: &mut [f64; NV],
        _blocked: &[bool],
    ) -> bool {
        false
    }

    /// Hot start, first phase: appends row `p` as active row `nact` without a
    /// step (the iterate stays). `Ok(false)` when `p`'s normal depends on the
    /// active ones (not added).
    fn hot_add(&mut self, _p: usize, _nact: usize) -> Result<bool, AddError> {
        Err(AddError::Numerical)
    }

    /// Hot start, second phase: the multipliers `mult[..nact]` of the
    /// minimiser on the `nact` active rows `act` held as equalities, from the
    /// current iterate (the unconstrained minimiser); what
    /// [`ActiveSetFactor::hot_move`] needs is kept. False when not finite.
    fn hot_multipliers(&mut self, _act: &[u16; NV], _nact: usize, _mult: &mut [f64; NV]) -> bool {
        false
    }

    /// Hot start, last step: moves the iterate to the minimiser of the last
    /// [`ActiveSetFactor::hot_multipliers`].
    fn hot_move(&mut self, _nact: usize) {}
}

/// Where [`iterate`] stopped.
pub(crate) struct Iterate<const NV: usize> {
    /// Outcome of the iteration (before the finiteness check of the result).
    pub status: QpStatus,
    /// Active rows; the first `nact` are valid.
    pub act: [u16; NV],
    /// Multipliers of the active rows, in the representation's scaling.
    pub mult: [f64; NV],
    /// Number of active rows (`<= NV`).
    pub nact: usize,
    /// Adds plus drops.
    pub iters: u32,
    /// On [`QpStatus::Infeasible`]: the row that could not be added and `-r`,
    /// the certificate's weights of the active rows.
    pub farkas: Option<(usize, [f64; NV])>,
    /// The row being added when the iteration stopped, with its multiplier so
    /// far (part of the dual iterate; `None` after a completed add).
    pub adding: Option<(usize, f64)>,
}

/// The dual active-set iteration (Goldfarb & Idnani 1983) on the `m` rows of
/// `factor`, starting from the unconstrained minimiser with no active row:
/// rows with `blocked[i]` are never added (left out, or zero rows),
/// `prefer[i]` marks rows to add first among the violated ones (and, with
/// `hot` and [`ActiveSetFactor::HOT_START`], rows that enter the active set
/// together before the first scan, see [`hot_start`]), at most `max_iter`
/// adds plus drops. `None` when [`ActiveSetFactor::add`] asked for a restart.
#[inline(always)]
pub(crate) fn iterate<F: ActiveSetFactor<NV>, const NV: usize, const NC: usize>(
    factor: &mut F,
    m: usize,
    mut blocked: [bool; NC],
    prefer: &[bool; NC],
    max_iter: u32,
    hot: bool,
) -> Option<Iterate<NV>> {
    let m = m.min(NC);
    let mut mult = [0.0f64; NV];
    let mut act = [0u16; NV];
    let mut nact: usize = 0;
    let mut iters: u32 = 0;
    let mut farkas: Option<(usize, [f64; NV])> = None;
    let mut adding: Option<(usize, f64)> = None;
    // Marked rows are preferred, so while one of them is violated the scan of
    // all rows would choose among them alone: each choice scans the marked
    // rows first, and all rows only when none of those is violated (the same
    // choice, without the other rows' slacks).
    let any_marked = prefer.iter().zip(&blocked).take(m).any(|(&p, &b)| p && !b);
    let mut stop = None;
    if F::HOT_START && hot {
        let mut start = Start {
            blocked: &mut blocked,
            act: &mut act,
            mult: &mut mult,
            nact: &mut nact,
            iters: &mut iters,
        };
        stop = hot_start(factor, m, prefer, max_iter, &mut start);
    }

    let status = 'outer: loop {
        if let Some(status) = stop {
            break status;
        }
        // Step 1: the most violated row in the H^-1 metric (marked rows first).
        let mut marked_only = any_marked;
        let p = loop {
            let mut best: Option<usize> = None;
            let mut best_v = 0.0;
            let mut best_pref: Option<usize> = None;
            let mut best_pref_v = 0.0;
            for i in 0..m {
                if marked_only && !prefer[i] {
                    continue;
                }
                // `i < m <= NC`: every index below is in bounds.
                let Some(s) = factor.violation(i, blocked[i]) else {
                    continue;
                };
                if s.is_nan() {
                    break 'outer QpStatus::NumericalError;
                }
                if s < best_v {
                    best_v = s;
                    best = Some(i);
                }
                if prefer[i] && s < best_pref_v {
                    best_pref_v = s;
                    best_pref = Some(i);
                }
            }
            match best_pref.or(best) {
                Some(p) => break p,
                None if marked_only => marked_only = false,
                None => break 'outer QpStatus::Solved,
            }
        };
        adding = Some((p, 0.0));
        let mut u_new: f64 = 0.0; // multiplier of p

        // Step 2: move until p holds (full step) or a row must be dropped.
        loop {
            if iters >= max_iter {
                break 'outer QpStatus::IterationLimit;
            }
            // Invariant: nact <= NV (a row is only added when there is room);
            // the `min` states it for the compiler.
            let nact_c = nact.min(NV);
            let mut r = [0.0f64; NV];
            let Some(t2) = factor.direction(p, &act, nact_c, &mut r) else {
                break 'outer QpStatus::NumericalError;
            };
            // Partial (dual) step length t1 and the row to drop.
            let mut t1 = f64::INFINITY;
            let mut drop: Option<usize> = None;
            let rmax = r[..nact_c].iter().fold(0.0f64, |a, b| a.max(b.abs()));
            for i in 0..nact_c {
                if r[i] > 1e-14 * rmax.max(1.0) {
                    let t = mult[i] / r[i];
                    if t < t1 {
                        t1 = t;
                        drop = Some(i);
                    }
                }
            }
            if !(t1.is_finite() || t2.is_finite()) {
                if t1.is_nan() || t2.is_nan() {
                    break 'outer QpStatus::NumericalError;
                }
                // n_p = sum_j r_j n_act[j] with every r_j <= 0 (no row can be
                // dropped), and the active rows hold with equality while row
                // p is violated: y_p = 1, y_act[j] = -r_j is a Farkas
                // certificate (G'y = 0, h'y = h_p - g_p'x < 0).
                let mut neg_r = r;
                for y in neg_r.iter_mut() {
                    *y = -*y;
                }
                farkas = Some((p, neg_r));
                break 'outer QpStatus::Infeasible;
            }
            let t = t1.min(t2);
            iters += 1;
            // Multipliers move along (-r, 1).
            for i in 0..nact_c {
                mult[i] -= t * r[i];
            }
            u_new += t;
            adding = Some((p, u_new));
            factor.advance(p, t, &r, &act, nact_c);
            if t2 <= t1 {
                // Full step: p becomes active.
                match factor.add(p, &r, nact_c) {
                    Ok(()) => {}
                    Err(AddError::Numerical) => break 'outer QpStatus::NumericalError,
                    Err(AddError::Restart) => return None,
                }
                let (Some(a), Some(un), Some(flag)) = (
                    act.get_mut(nact_c),
                    mult.get_mut(nact_c),
                    blocked.get_mut(p),
                ) else {
                    break 'outer QpStatus::NumericalError;
                };
                *a = p as u16;
                *un = u_new;
                *flag = true;
                nact = nact_c + 1;
                adding = None;
                continue 'outer;
            }
            // Partial step: drop active row `l` (< nact), then retry the same p.
            let Some((l, &row_l)) = drop.and_then(|l| Some((l, act.get(l)?))) else {
                break 'outer QpStatus::NumericalError;
            };
            if let Some(flag) = blocked.get_mut(usize::from(row_l)) {
                *flag = false;
            }
            factor.drop(l, nact_c);
            // Close the gap at `l` in the active list and its multipliers.
            let last = nact_c.saturating_sub(1);
            for i in l..last {
                act[i] = act[i + 1];
                mult[i] = mult[i + 1];
            }
            nact = last;
        }
    };
    Some(Iterate {
        status,
        act,
        mult,
        nact: nact.min(NV),
        iters,
        farkas,
        adding,
    })
}

/// The iteration's state that [`hot_start`] sets up.
struct Start<'a, const NV: usize, const NC: usize> {
    blocked: &'a mut [bool; NC],
    act: &'a mut [u16; NV],
    mult: &'a mut [f64; NV],
    nact: &'a mut usize,
    iters: &'a mut u32,
}

/// Hot start (the warm start by active set of DAQP and qpOASES), at the start
/// of a solve, on the first `NV` marked rows in row order. First a guess
/// ([`ActiveSetFactor::hot_guess`]): if the minimiser on them held as
/// equalities has multipliers `>= 0` and violates no row, it is the solution
/// (one iteration per row is counted, as if each had been added). Otherwise
/// they enter the active set in turn without scans or steps
/// ([`ActiveSetFactor::hot_add`]; rows dependent on those before are left to
/// the iteration); then, while a multiplier of the minimiser on the active
/// rows held as equalities is negative, the row with the most negative one is
/// dropped; the iterate moves to that minimiser. The result is the pair the
/// dual method starts from and keeps (Goldfarb & Idnani's S-pair: `x` optimal
/// on the active rows, multipliers `>= 0`). Each add and each drop counts as
/// an iteration. `Some(status)` stops the solve: [`QpStatus::NumericalError`]
/// on a failed add or non-finite multipliers, [`QpStatus::IterationLimit`]
/// when the budget runs out with a negative multiplier left (the iterate is
/// then the minimiser on the active rows).
#[inline(always)]
fn hot_start<F: ActiveSetFactor<NV>, const NV: usize, const NC: usize>(
    factor: &mut F,
    m: usize,
    prefer: &[bool; NC],
    max_iter: u32,
    st: &mut Start<'_, NV, NC>,
) -> Option<QpStatus> {
    // The marked rows, in row order; at most `NV` (no more can be active at
    // once; marks beyond them are still preferred by the scans).
    let mut k = 0usize;
    for (i, (&mark, &flag)) in prefer.iter().zip(st.blocked.iter()).enumerate().take(m) {
        if mark && !flag {
            let Some(a) = st.act.get_mut(k) else {
                break;
            };
            *a = i as u16;
            k += 1;
        }
    }
    // The guess: they are the optimal active set.
    if k > 0
        && k as u64 <= u64::from(max_iter)
        && factor.hot_guess(st.act, k, st.mult, st.blocked.get(..m).unwrap_or(&[]))
    {
        for &a in st.act.iter().take(k) {
            if let Some(flag) = st.blocked.get_mut(usize::from(a)) {
                *flag = true;
            }
        }
        *st.nact = k;
        *st.iters = k as u32;
        return Some(QpStatus::Solved);
    }
    // Otherwise each enters the factor in turn (the list is compacted in
    // place over the rows left to the iteration as dependent).
    let mut nact = 0usize;
    let mut iters = 0u32;
    for j in 0..k {
        let Some(&a) = st.act.get(j) else {
            break;
        };
        if iters >= max_iter {
            break;
        }
        match factor.hot_add(usize::from(a), nact) {
            Ok(false) => continue,
            Ok(true) => {}
            Err(_) => return Some(QpStatus::NumericalError),
        }
        let (Some(slot), Some(flag)) = (st.act.get_mut(nact), st.blocked.get_mut(usize::from(a)))
        else {
            return Some(QpStatus::NumericalError);
        };
        *slot = a;
        *flag = true;
        nact += 1;
        iters += 1;
    }
    for a in st.act.iter_mut().skip(nact) {
        *a = 0;
    }
    let stop = loop {
        let n = nact.min(NV);
        if n == 0 {
            break None;
        }
        if !factor.hot_multipliers(st.act, n, st.mult) {
            break Some(QpStatus::NumericalError);
        }
        let mut worst: Option<usize> = None;
        let mut worst_u = 0.0;
        for (i, &u) in st.mult.iter().enumerate().take(n) {
            if u < worst_u {
                worst_u = u;
                worst = Some(i);
            }
        }
        let Some(l) = worst else {
            factor.hot_move(n);
            break None;
        };
        if iters >= max_iter {
            factor.hot_move(n);
            break Some(QpStatus::IterationLimit);
        }
        if let Some(flag) = st
            .act
            .get(l)
            .and_then(|&a| st.blocked.get_mut(usize::from(a)))
        {
            *flag = false;
        }
        factor.drop(l, n);
        for i in l..n - 1 {
            st.act[i] = st.act[i + 1];
        }
        nact = n - 1;
        iters += 1;
    };
    *st.nact = nact;
    *st.iters = iters;
    stop
}

impl<const NV: usize> Iterate<NV> {
    /// The solution with primal `x` and its objective: the multipliers (or
    /// the Farkas certificate, whose entry of the row that could not be added
    /// is 1) in the units of `G`, row `i`'s multiplier being
    /// `scale(i)` times the representation's; negative rounding clipped to 0.
    /// The status becomes [`QpStatus::NumericalError`] when `x` or the
    /// objective is not finite.
    #[inline(always)]
    pub(crate) fn solution<const NC: usize>(
        &self,
        x: [f64; NV],
        objective: f64,
        scale: impl Fn(usize) -> f64,
    ) -> QpSolution<NV, NC> {
        let mut lambda = SVector::<f64, NC>::zeros();
        let nact = self.nact.min(NV);
        match self.farkas {
            Some((p, neg_r)) => {
                let sp = scale(p);
                if let Some(y) = lambda.get_mut(p) {
                    *y = 1.0;
                }
                for (&a, &y) in self.act.iter().zip(&neg_r).take(nact) {
                    let a = usize::from(a);
                    if let Some(l) = lambda.get_mut(a) {
                        *l = (y * scale(a) / sp).max(0.0);
                    }
                }
            }
            None => {
                for (&a, &w) in self.act.iter().zip(&self.mult).take(nact) {
                    let a = usize::from(a);
                    if let Some(l) = lambda.get_mut(a) {
                        *l = (w * scale(a)).max(0.0);
                    }
                }
            }
        }
        let finite = x.iter().all(|v| v.is_finite()) && objective.is_finite();
        QpSolution {
            x: SVector::from(x),
            lambda,
            objective,
            status: if finite {
                self.status
            } else {
                QpStatus::NumericalError
            },
            iterations: self.iters,
            active: self.act,
            n_active: nact,
        }
    }
}

/// The result of a solve that stopped before iterating: `status`, `x = 0`, no
/// active row; for [`QpStatus::Infeasible`] with `zero_row = Some(i)` (the
/// zero row `0'x <= h_i` with `h_i < 0`) the certificate `y = e_i`.
pub(crate) fn stopped<const NV: usize, const NC: usize>(
    status: QpStatus,
    zero_row: Option<usize>,
) -> QpSolution<NV, NC> {
    let mut sol = QpSolution::<NV, NC> {
        x: SVector::zeros(),
        lambda: SVector::zeros(),
        objective: 0.0,
        status,
        iterations: 0,
        active: [0; NV],
        n_active: 0,
    };
    if let Some(y) = zero_row.and_then(|i| sol.lambda.get_mut(i)) {
        *y = 1.0;
    }
    sol
}

/// `a . b` with four partial sums (independent add chains; `N` is a constant, so
/// the loop unrolls and vectorises without bounds checks).
#[inline(always)]
pub(crate) fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut acc = [0.0f64; 2];
    for k in 0..N {
        acc[k % 2] += a[k] * b[k];
    }
    acc[0] + acc[1]
}

/// Givens rotation `(c, s, r)` with `c a + s b = r`, `-s a + c b = 0`.
pub(crate) fn givens(a: f64, b: f64) -> (f64, f64, f64) {
    // sqrt(a^2 + b^2) is within an ulp or two of hypot; hypot (slower, no
    // overflow or underflow) only when the squares leave the normal range.
    let r2 = a * a + b * b;
    let r = if (1e-280..=1e280).contains(&r2) {
        crate::float::sqrt(r2)
    } else {
        libm::hypot(a, b)
    };
    if r == 0.0 {
        return (1.0, 0.0, 0.0);
    }
    (a / r, b / r, r)
}
