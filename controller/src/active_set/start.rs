//! How a solve starts before the first row scan of [`super::iterate`]: the
//! equality rows held active ([`equalities`]), and the hot start by the
//! marked rows ([`hot_start`]).

use super::{ActiveSetFactor, AddError, remove_at};
use crate::solution::QpStatus;

/// The iteration's state that [`equalities`] and [`hot_start`] set up (slices
/// of the vectors of [`iterate`]).
pub(super) struct Start<'a> {
    pub(super) blocked: &'a mut [bool],
    pub(super) act: &'a mut [u16],
    pub(super) mult: &'a mut [f64],
    pub(super) r: &'a mut [f64],
    pub(super) nact: &'a mut usize,
    pub(super) iters: &'a mut u32,
}

/// Why [`equalities`] stopped the solve.
pub(super) enum EqStop {
    /// A non-finite number, or a factor that could not take a row.
    Numerical,
    /// The factor asked for a restart with another representation.
    Restart,
    /// The budget ran out.
    Budget,
    /// Equality row `p` depends on the others and contradicts them; the sign
    /// of its certificate entry, `-r` in the iteration's `r`.
    Infeasible(usize, f64),
}

impl EqStop {
    pub(super) fn status(&self) -> QpStatus {
        match self {
            EqStop::Numerical | EqStop::Restart => QpStatus::NumericalError,
            EqStop::Budget => QpStatus::IterationLimit,
            EqStop::Infeasible(..) => QpStatus::Infeasible,
        }
    }
}

/// The equality rows `0..neq`, held active for the whole solve (as DAQP and
/// qpOASES hold them): each enters the factor in turn without a step
/// ([`ActiveSetFactor::hot_add`], one iteration each), the iterate moves to
/// the minimiser on them with their multipliers (either sign), and they
/// stay blocked, so no scan adds them again and, at the head of the active
/// list, no ratio test drops them. A row whose normal depends on those
/// before is redundant when it holds there to the tolerance (blocked, never
/// active) and proves the equalities inconsistent otherwise (Farkas
/// certificate from its dependence on the active rows). Returns the number
/// of equality rows made active.
#[inline(always)]
pub(super) fn equalities<F: ActiveSetFactor>(
    factor: &mut F,
    m: usize,
    neq: usize,
    max_iter: u32,
    st: &mut Start<'_>,
) -> Result<usize, EqStop> {
    let neq = neq.min(m);
    let nv = st.act.len();
    let mut nact = 0usize;
    let mut dependent = false;
    for p in 0..neq {
        let Some(flag) = st.blocked.get_mut(p) else {
            break;
        };
        if *flag {
            continue; // left out
        }
        *flag = true;
        if nact >= nv {
            dependent = true;
            continue;
        }
        if *st.iters >= max_iter {
            return Err(EqStop::Budget);
        }
        match factor.hot_add(p, st.act, nact) {
            Ok(false) => dependent = true,
            Ok(true) => {
                if let Some(a) = st.act.get_mut(nact) {
                    *a = p as u16;
                }
                nact += 1;
                *st.iters += 1;
            }
            Err(AddError::Restart) => return Err(EqStop::Restart),
            Err(AddError::Numerical) => return Err(EqStop::Numerical),
        }
    }
    *st.nact = nact;
    if nact > 0 {
        if !factor.hot_multipliers(st.act, nact, st.mult) {
            return Err(EqStop::Numerical);
        }
        factor.hot_move(st.act, nact);
    }
    if dependent {
        // The rows left out of the factor must hold at the minimiser on the
        // others; otherwise they contradict them.
        let act_rows = st.act.get(..nact).unwrap_or(&[]);
        for p in 0..neq {
            if act_rows.iter().any(|&a| usize::from(a) == p) {
                continue;
            }
            let (slack, tol2) = factor.slack(p);
            if slack.is_nan() {
                return Err(EqStop::Numerical);
            }
            if slack * slack <= tol2 {
                continue;
            }
            // g_p = sum_j r_j g_act[j]: y = s (e_p - sum_j r_j e_act[j]),
            // with s the sign that makes h'y = s (h_p - g_p x) negative.
            st.r.fill(0.0);
            if factor.direction(p, st.act, nact, st.r).is_none() {
                return Err(EqStop::Numerical);
            }
            let sign = if slack < 0.0 { 1.0 } else { -1.0 };
            for v in st.r.iter_mut() {
                *v *= sign;
            }
            return Err(EqStop::Infeasible(p, sign));
        }
    }
    Ok(nact)
}

/// Hot start (the warm start by active set of DAQP and qpOASES), at the start
/// of a solve, on the first marked rows in row order (as many as fit beside
/// the `neq` active equality rows). First a guess
/// ([`ActiveSetFactor::hot_guess`], only without equality rows): if the
/// minimiser on them held as equalities has multipliers `>= 0` and violates
/// no row, it is the solution (one iteration per row is counted, as if each
/// had been added). Otherwise they enter the active set in turn without
/// scans or steps ([`ActiveSetFactor::hot_add`]; rows dependent on those
/// before are left to the iteration); then, while a multiplier of an
/// inequality row of the minimiser on the active rows held as equalities is
/// negative, the row with the most negative one is dropped; the iterate moves
/// to that minimiser. The result is the pair the dual method starts from and
/// keeps (Goldfarb & Idnani's S-pair: `x` optimal on the active rows,
/// multipliers `>= 0`). Each add and each drop counts as an iteration.
/// `Some(status)` stops the solve: [`QpStatus::NumericalError`] on a failed
/// add or non-finite multipliers, [`QpStatus::IterationLimit`] when the
/// budget runs out with a negative multiplier left (the iterate is then the
/// minimiser on the active rows).
#[inline(always)]
pub(super) fn hot_start<F: ActiveSetFactor>(
    factor: &mut F,
    m: usize,
    neq: usize,
    prefer: &[bool],
    max_iter: u32,
    st: &mut Start<'_>,
) -> Option<QpStatus> {
    let nv = st.act.len();
    // The marked rows, in row order, after the equality rows.
    let mut k = neq;
    for (i, (&mark, &flag)) in prefer.iter().zip(st.blocked.iter()).enumerate().take(m) {
        if mark && !flag {
            let Some(a) = st.act.get_mut(k) else {
                break;
            };
            *a = i as u16;
            k += 1;
        }
    }
    if k == neq {
        return None;
    }
    // The guess: they are the optimal active set.
    if neq == 0
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
    let mut nact = neq;
    let mut iters = *st.iters;
    for j in neq..k {
        let Some(&a) = st.act.get(j) else {
            break;
        };
        if iters >= max_iter {
            break;
        }
        match factor.hot_add(usize::from(a), st.act, nact) {
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
    // The iterate is the minimiser on the equality rows, with their
    // multipliers `mu`; `hot_multipliers` gives the change from there, so
    // the equality rows' multipliers are `mu` plus it (`r` holds `mu`).
    for (r, &u) in st.r.iter_mut().zip(st.mult.iter()).take(neq) {
        *r = u;
    }
    let stop = loop {
        let n = nact.min(nv);
        if n == 0 {
            break None;
        }
        if !factor.hot_multipliers(st.act, n, st.mult) {
            break Some(QpStatus::NumericalError);
        }
        for (u, &mu) in st.mult.iter_mut().zip(st.r.iter()).take(neq) {
            *u += mu;
        }
        let mut worst: Option<usize> = None;
        let mut worst_u = 0.0;
        for (i, &u) in st.mult.iter().enumerate().take(n).skip(neq) {
            if u < worst_u {
                worst_u = u;
                worst = Some(i);
            }
        }
        let Some(l) = worst else {
            factor.hot_move(st.act, n);
            break None;
        };
        if iters >= max_iter {
            factor.hot_move(st.act, n);
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
        remove_at(st.act, l, n);
        nact = n - 1;
        iters += 1;
    };
    *st.nact = nact;
    *st.iters = iters;
    stop
}
