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
//! and the flags of blocked rows (length `NC`): nalgebra vectors over the
//! dimension types `NV`, `NC` (`Const` arrays on the stack, or `Dyn` on the
//! heap with the feature `alloc`), read through slices whose lengths are the
//! constants for `Const`, so the static instances compile as loops over
//! fixed-size arrays.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector, U1};

use crate::solution::{QpAllocator, QpSolutionOf, QpStatus};

mod start;
use start::{EqStop, Start, equalities, hot_start};

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
/// in the order of the active list `act`. The slices `act`, `r` and `mult`
/// have length `NV` (the number of variables).
pub(crate) trait ActiveSetFactor {
    /// The violation of row `i` (`i < m`) at the current iterate: `None` when
    /// the row is `blocked` (active, left out or a zero equality row; the
    /// representation tests this where it is cheapest: before a dot product,
    /// or after the sign of a stored slack) or holds to the primal tolerance,
    /// else its (negative) slack in the metric of `H^-1`,
    /// `slack_i / |L^-1 g_i|` (the most negative is added; a zero row
    /// `g_i = 0`, never added, may give `+0`, which the scan's start of 0
    /// never takes), or NaN when the
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
    fn direction(&mut self, p: usize, act: &[u16], nact: usize, r: &mut [f64]) -> Option<f64>;

    /// Moves the primal iterate by a step of length `t` along the direction of
    /// the last [`ActiveSetFactor::direction`] (nothing when `p` was
    /// dependent).
    fn advance(&mut self, p: usize, t: f64, r: &[f64], act: &[u16], nact: usize);

    /// Appends row `p` as active row `nact` after a full step.
    fn add(&mut self, p: usize, r: &[f64], nact: usize) -> Result<(), AddError>;

    /// Removes active row `l` of `nact`.
    fn drop(&mut self, l: usize, nact: usize);

    /// Whether [`iterate`] may hot-start this representation (the methods
    /// below); when false (and [`ActiveSetFactor::equalities_capable`] too)
    /// they are never called. Constant for the static sizes, so the code
    /// behind it is left out of their builds when false.
    fn hot_start_capable(&self) -> bool {
        false
    }

    /// Whether the representation holds equality rows (with
    /// [`ActiveSetFactor::hot_add`], [`ActiveSetFactor::hot_multipliers`],
    /// [`ActiveSetFactor::hot_move`] and [`ActiveSetFactor::slack`]).
    fn equalities_capable(&self) -> bool {
        false
    }

    /// The slack `h_i - g_i x` of row `i` at the current iterate and the
    /// squared tolerance it is held to, `tol_primal^2 |g_i|^2` (for the
    /// equality rows).
    fn slack(&self, _i: usize) -> (f64, f64) {
        (f64::NAN, 0.0)
    }

    /// Hot start, a guess first: whether the minimiser on the `k` rows `act`
    /// held as equalities is the solution (its multipliers `>= 0`, written to
    /// `mult[..k]`, and every row not `blocked` holds to the tolerance); then
    /// it is the iterate, and the factor need not be built. False leaves the
    /// iterate as it was.
    fn hot_guess(&mut self, _act: &[u16], _k: usize, _mult: &mut [f64], _blocked: &[bool]) -> bool {
        false
    }

    /// Hot start, first phase: appends row `p` as active row `nact` (after
    /// the `nact` rows `act`) without a step (the iterate stays). `Ok(false)`
    /// when `p`'s normal depends on the active ones (not added).
    fn hot_add(&mut self, _p: usize, _act: &[u16], _nact: usize) -> Result<bool, AddError> {
        Err(AddError::Numerical)
    }

    /// Hot start, second phase: the multipliers `mult[..nact]` of the
    /// minimiser on the `nact` active rows `act` held as equalities, less
    /// those of the current iterate (which is the unconstrained minimiser, or
    /// the minimiser on the leading equality rows: [`hot_start`] adds theirs
    /// back); what [`ActiveSetFactor::hot_move`] needs is kept. False when
    /// not finite.
    fn hot_multipliers(&mut self, _act: &[u16], _nact: usize, _mult: &mut [f64]) -> bool {
        false
    }

    /// Hot start, last step: moves the iterate to the minimiser of the last
    /// [`ActiveSetFactor::hot_multipliers`].
    fn hot_move(&mut self, _act: &[u16], _nact: usize) {}

    /// A factor that already holds an active set with its iterate (the
    /// proximal iterations' resolve, `qp/resolve.rs`): writes its rows and
    /// multipliers to `act` and `mult` and returns `(nact, neq)`, the number
    /// of active rows and of equality rows at their head; [`iterate`] then
    /// starts from there (no equality phase, no hot start; the caller has
    /// marked the active rows, and every equality row, as blocked). `None`
    /// (the default): a fresh factor.
    fn resume(&mut self, _act: &mut [u16], _mult: &mut [f64]) -> Option<(usize, usize)> {
        None
    }
}

/// Where [`iterate`] stopped.
pub(crate) struct Iterate<NV: Dim>
where
    DefaultAllocator: Allocator<NV>,
{
    /// Outcome of the iteration (before the finiteness check of the result).
    pub status: QpStatus,
    /// Active rows; the first `nact` are valid, of which the first `neq` are
    /// equality rows.
    pub act: OVector<u16, NV>,
    /// Multipliers of the active rows, in the representation's scaling.
    pub mult: OVector<f64, NV>,
    /// Number of active rows (`<= NV`).
    pub nact: usize,
    /// Number of equality rows at the head of the active list (never dropped,
    /// multipliers of either sign).
    pub neq: usize,
    /// Adds plus drops.
    pub iters: u32,
    /// On [`QpStatus::Infeasible`]: the row that could not be added, the sign
    /// of its certificate entry (+1, or -1 for an equality row violated from
    /// below) and `-r`, the certificate's weights of the active rows.
    pub farkas: Option<(usize, f64, OVector<f64, NV>)>,
    /// The row being added when the iteration stopped, with its multiplier so
    /// far (part of the dual iterate; `None` after a completed add).
    pub adding: Option<(usize, f64)>,
}

/// The dual active-set iteration (Goldfarb & Idnani 1983) on the `m` rows of
/// `factor`, starting from the unconstrained minimiser with no active row:
/// the first `neq` rows are equalities (held active from the start, see
/// [`equalities`]), rows with `blocked[i]` are never added (left out, or
/// zero rows), `prefer[i]` marks rows to add first among the violated ones
/// (and, with `hot` and [`ActiveSetFactor::hot_start_capable`], rows that
/// enter the active set together before the first scan, see [`hot_start`]),
/// at most `max_iter` adds plus drops. `None` when [`ActiveSetFactor::add`]
/// asked for a restart. `nv` is the number of variables, `blocked` and
/// `prefer` have the row capacity as length; `marked` false says that no
/// entry of `prefer` is set (the marks are then not scanned).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn iterate<F: ActiveSetFactor, NV: Dim, NC: Dim>(
    factor: &mut F,
    nv: NV,
    m: usize,
    neq: usize,
    mut blocked: OVector<bool, NC>,
    prefer: &OVector<bool, NC>,
    marked: bool,
    max_iter: u32,
    hot: bool,
) -> Option<Iterate<NV>>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    let nvv = nv.value();
    let m = m.min(blocked.len()).min(prefer.len());
    let mut mult = OVector::<f64, NV>::zeros_generic(nv, U1);
    let mut act = OVector::<u16, NV>::zeros_generic(nv, U1);
    let mut r = OVector::<f64, NV>::zeros_generic(nv, U1);
    let mut nact: usize = 0;
    let mut neq_act: usize = 0;
    let mut iters: u32 = 0;
    let mut farkas: Option<(usize, f64, OVector<f64, NV>)> = None;
    let mut adding: Option<(usize, f64)> = None;
    let mut stop = None;
    let resumed = factor.resume(act.as_mut_slice(), mult.as_mut_slice());
    if let Some((n, e)) = resumed {
        nact = n.min(nvv);
        neq_act = e.min(nact);
    }
    if neq > 0 && resumed.is_none() {
        if !factor.equalities_capable() {
            stop = Some(QpStatus::NumericalError);
        } else {
            let mut start = Start {
                blocked: blocked.as_mut_slice(),
                act: act.as_mut_slice(),
                mult: mult.as_mut_slice(),
                r: r.as_mut_slice(),
                nact: &mut nact,
                iters: &mut iters,
            };
            match equalities(factor, m, neq, max_iter, &mut start) {
                Ok(n) => neq_act = n,
                Err(EqStop::Restart) => return None,
                Err(e) => {
                    // The certificate's entries of the active equality rows
                    // keep their sign.
                    neq_act = nact;
                    if let EqStop::Infeasible(p, sign) = e {
                        let mut neg_r = r.clone();
                        for v in neg_r.as_mut_slice() {
                            *v = -*v;
                        }
                        farkas = Some((p, sign, neg_r));
                    }
                    stop = Some(e.status());
                }
            }
        }
    }
    let blocked_s = blocked.as_mut_slice();
    let prefer = prefer.as_slice();
    let m = m.min(blocked_s.len()).min(prefer.len());
    let act_s = act.as_mut_slice();
    let mult_s = mult.as_mut_slice();
    let r_s = r.as_mut_slice();
    // Marked rows are preferred, so while one of them is violated the scan of
    // all rows would choose among them alone: each choice scans the marked
    // rows first, and all rows only when none of those is violated (the same
    // choice, without the other rows' slacks).
    let any_marked = marked
        && prefer
            .iter()
            .zip(blocked_s.iter())
            .take(m)
            .any(|(&p, &b)| p && !b);
    if stop.is_none() && hot && resumed.is_none() && factor.hot_start_capable() {
        let mut start = Start {
            blocked: &mut *blocked_s,
            act: &mut *act_s,
            mult: &mut *mult_s,
            r: &mut *r_s,
            nact: &mut nact,
            iters: &mut iters,
        };
        stop = hot_start(factor, m, neq_act, prefer, max_iter, &mut start);
    }

    let status = 'outer: loop {
        if let Some(status) = stop {
            break status;
        }
        // Step 1: the most violated row in the H^-1 metric (marked rows first).
        let p = 'choose: {
            // Without marks the same scan without their bookkeeping (`marked` is
            // true as a constant where that is shorter, and this loop left out).
            if !marked {
                let mut best: Option<usize> = None;
                let mut best_v = 0.0;
                for i in 0..m {
                    let Some(s) = factor.violation(i, blocked_s[i]) else {
                        continue;
                    };
                    if s.is_nan() {
                        break 'outer QpStatus::NumericalError;
                    }
                    if s < best_v {
                        best_v = s;
                        best = Some(i);
                    }
                }
                match best {
                    Some(p) => break 'choose p,
                    None => break 'outer QpStatus::Solved,
                }
            }
            let mut marked_only = any_marked;
            loop {
                let mut best: Option<usize> = None;
                let mut best_v = 0.0;
                let mut best_pref: Option<usize> = None;
                let mut best_pref_v = 0.0;
                for i in 0..m {
                    // `m <= len` of both: no bounds checks.
                    let pref = prefer[i];
                    if marked_only && !pref {
                        continue;
                    }
                    let Some(s) = factor.violation(i, blocked_s[i]) else {
                        continue;
                    };
                    if s.is_nan() {
                        break 'outer QpStatus::NumericalError;
                    }
                    if s < best_v {
                        best_v = s;
                        best = Some(i);
                    }
                    if pref && s < best_pref_v {
                        best_pref_v = s;
                        best_pref = Some(i);
                    }
                }
                match best_pref.or(best) {
                    Some(p) => break 'choose p,
                    None if marked_only => marked_only = false,
                    None => break 'outer QpStatus::Solved,
                }
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
            let nact_c = nact.min(nvv).min(r_s.len()).min(mult_s.len());
            r_s.fill(0.0);
            let Some(t2) = factor.direction(p, act_s, nact_c, r_s) else {
                break 'outer QpStatus::NumericalError;
            };
            // Partial (dual) step length t1 and the row to drop (equality
            // rows are never dropped).
            let mut t1 = f64::INFINITY;
            let mut drop: Option<usize> = None;
            let rmax = r_s[..nact_c]
                .iter()
                .skip(neq_act)
                .fold(0.0f64, |a, b| a.max(b.abs()));
            for i in neq_act..nact_c {
                if r_s[i] > 1e-14 * rmax.max(1.0) {
                    let t = mult_s[i] / r_s[i];
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
                // n_p = sum_j r_j n_act[j] with every r_j <= 0 of an
                // inequality row (no row can be dropped), and the active rows
                // hold with equality while row p is violated: y_p = 1,
                // y_act[j] = -r_j is a Farkas certificate (G'y = 0,
                // h'y = h_p - g_p'x < 0; entries of equality rows may have
                // either sign).
                let mut neg_r = r.clone();
                for v in neg_r.as_mut_slice() {
                    *v = -*v;
                }
                farkas = Some((p, 1.0, neg_r));
                break 'outer QpStatus::Infeasible;
            }
            let t = t1.min(t2);
            iters += 1;
            // Multipliers move along (-r, 1).
            for i in 0..nact_c {
                mult_s[i] -= t * r_s[i];
            }
            u_new += t;
            adding = Some((p, u_new));
            factor.advance(p, t, r_s, act_s, nact_c);
            if t2 <= t1 {
                // Full step: p becomes active.
                match factor.add(p, r_s, nact_c) {
                    Ok(()) => {}
                    Err(AddError::Numerical) => break 'outer QpStatus::NumericalError,
                    Err(AddError::Restart) => return None,
                }
                let (Some(a), Some(un), Some(flag)) = (
                    act_s.get_mut(nact_c),
                    mult_s.get_mut(nact_c),
                    blocked_s.get_mut(p),
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
            let Some((l, &row_l)) = drop.and_then(|l| Some((l, act_s.get(l)?))) else {
                break 'outer QpStatus::NumericalError;
            };
            if let Some(flag) = blocked_s.get_mut(usize::from(row_l)) {
                *flag = false;
            }
            factor.drop(l, nact_c);
            // Close the gap at `l` in the active list and its multipliers.
            remove_at(act_s, l, nact_c);
            remove_at(mult_s, l, nact_c);
            nact = nact_c.saturating_sub(1);
        }
    };
    Some(Iterate {
        status,
        act,
        mult,
        nact: nact.min(nvv),
        neq: neq_act,
        iters,
        farkas,
        adding,
    })
}

impl<NV: Dim> Iterate<NV>
where
    DefaultAllocator: Allocator<NV>,
{
    /// The end of an iteration that found no row violated at the
    /// unconstrained minimiser: solved, no active row, no iteration.
    pub(crate) fn unconstrained(nv: NV) -> Self {
        Iterate {
            status: QpStatus::Solved,
            act: OVector::zeros_generic(nv, U1),
            mult: OVector::zeros_generic(nv, U1),
            nact: 0,
            neq: 0,
            iters: 0,
            farkas: None,
            adding: None,
        }
    }

    /// The solution with primal `x` and its objective: the multipliers (or
    /// the Farkas certificate, whose entry of the row that could not be added
    /// is 1 or, for an equality row violated from below, -1) in the units of
    /// `G`, row `i`'s multiplier being `scale(i)` times the representation's;
    /// negative rounding clipped to 0 on inequality rows (equality rows keep
    /// their sign). The status becomes [`QpStatus::NumericalError`] when `x`
    /// or the objective is not finite. `nc` is the row capacity.
    #[inline(always)]
    pub(crate) fn solution<NC: Dim>(
        self,
        nc: NC,
        x: OVector<f64, NV>,
        objective: f64,
        scale: impl Fn(usize) -> f64,
    ) -> QpSolutionOf<NV, NC>
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        let mut lambda = OVector::<f64, NC>::zeros_generic(nc, U1);
        let nact = self.nact.min(self.act.len());
        let neq = self.neq;
        let clip = |j: usize, v: f64| if j < neq { v } else { v.max(0.0) };
        match &self.farkas {
            Some((p, sign, neg_r)) => {
                let sp = scale(*p);
                if let Some(y) = lambda.get_mut(*p) {
                    *y = *sign;
                }
                for (j, (&a, &y)) in self
                    .act
                    .as_slice()
                    .iter()
                    .zip(neg_r.as_slice().iter())
                    .take(nact)
                    .enumerate()
                {
                    let a = usize::from(a);
                    if let Some(l) = lambda.get_mut(a) {
                        *l = clip(j, y * scale(a) / sp);
                    }
                }
            }
            None => {
                for (j, (&a, &w)) in self
                    .act
                    .as_slice()
                    .iter()
                    .zip(self.mult.as_slice().iter())
                    .take(nact)
                    .enumerate()
                {
                    let a = usize::from(a);
                    if let Some(l) = lambda.get_mut(a) {
                        *l = clip(j, w * scale(a));
                    }
                }
            }
        }
        let finite = x.as_slice().iter().all(|v| v.is_finite()) && objective.is_finite();
        QpSolutionOf {
            x,
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

/// Removes entry `l` of the first `n` of `s` (the entries after it move up
/// one place; entry `n - 1` is left as it was).
#[inline(always)]
pub(crate) fn remove_at<T: Copy>(s: &mut [T], l: usize, n: usize) {
    for i in l..n.min(s.len()).saturating_sub(1) {
        if let Some(&next) = s.get(i + 1)
            && let Some(cur) = s.get_mut(i)
        {
            *cur = next;
        }
    }
}

/// The result of a solve that stopped before iterating: `status`, `x = 0`, no
/// active row, no multiplier.
pub(crate) fn stopped<NV: Dim, NC: Dim>(nv: NV, nc: NC, status: QpStatus) -> QpSolutionOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    QpSolutionOf {
        x: OVector::zeros_generic(nv, U1),
        lambda: OVector::zeros_generic(nc, U1),
        objective: 0.0,
        status,
        iterations: 0,
        active: OVector::zeros_generic(nv, U1),
        n_active: 0,
    }
}

/// Whether the zero row `i` (`0'x <= h_i`, or `0'x = h_i` for an equality
/// row) contradicts itself at the tolerance `tol`.
pub(crate) fn zero_row_contradicts(h_i: f64, tol: f64, equality: bool) -> bool {
    h_i < -tol || (equality && h_i > tol)
}

/// The answer for a zero row `i` that contradicts itself
/// ([`zero_row_contradicts`]): [`QpStatus::Infeasible`] with the certificate
/// `y = e_i` (`h_i < 0`) or `y = -e_i` (an equality row with `h_i > 0`).
pub(crate) fn zero_row_infeasible<NV: Dim, NC: Dim>(
    nv: NV,
    nc: NC,
    i: usize,
    h_i: f64,
) -> QpSolutionOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    let mut sol = stopped(nv, nc, QpStatus::Infeasible);
    if let Some(y) = sol.lambda.get_mut(i) {
        *y = if h_i > 0.0 { -1.0 } else { 1.0 };
    }
    sol
}

/// The warm-start marks `prefer` (any length; missing entries `false`) as a
/// vector of the row capacity, whose length the scan's bounds are taken from.
pub(crate) fn marks<NC: Dim>(nc: NC, prefer: &[bool]) -> OVector<bool, NC>
where
    DefaultAllocator: Allocator<NC>,
{
    let mut out = OVector::<bool, NC>::from_element_generic(nc, U1, false);
    for (d, &s) in out.as_mut_slice().iter_mut().zip(prefer) {
        *d = s;
    }
    out
}
