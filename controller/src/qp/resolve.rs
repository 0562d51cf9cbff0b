//! The resumed start of a solve: from a kept factor, the pair the dual
//! method starts from (Goldfarb & Idnani's S-pair). The proximal iterations
//! after the first (`qp/proximal.rs`) keep the
//! active set's factor: the Hessian `H + eps I` and the rows are the same in
//! every proximal solve, only the linear term `q_k = q - eps x_k` changes, so
//! the orthogonal factor `J = L^-T Q`, `R` of the last solve's active rows
//! still holds. As DAQP between its proximal iterations (it keeps its LDL'
//! factor and only updates the linear term), the next solve starts from it:
//!
//! * [`minimiser_on`]: the minimiser on the active rows held as equalities
//!   for the new linear term and its multipliers, from the factor alone
//!   (`O(NV^2)`, no add);
//! * [`resolve`]: while an inequality row's multiplier is negative, the row
//!   with the most negative one is dropped (Givens rotations, as a drop of
//!   the iteration) and the minimiser formed again. That is a pair the dual
//!   method starts from (Goldfarb & Idnani's S-pair: `x` optimal on the
//!   active rows, multipliers `>= 0`);
//! * `Orthogonal` (`qp/orthogonal.rs`) with the kept rows (`qp/kept.rs`): the factor handed to
//!   [`crate::active_set::iterate`], which continues from that pair with its
//!   normal scans, adds and drops (only where a row is violated).
//!
//! With `J' H J = I` and `J' N = [R; 0]` (`N` the active normals `n_j =
//! -g_j`, `N'x = b`, `b_j = -h_j`), `x = J y` solves `H x + q = N u`,
//! `N'x = b` with `R' y_1 = b`, `y_2 = -J_2' q` and `u = R^-1 (y_1 + J_1'
//! q)`.

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

use super::kept::Kept;
use super::settings::proximal_capable;
use super::updates::{back_substitute, back_substitute_by_columns, givens_drop};
use crate::active_set::remove_at;
use crate::linalg::{column, columns, dot_d};
use crate::solution::QpAllocator;

/// The minimiser on the `nact` active rows `act` held as equalities, for the
/// linear term `q`, from the factor `J`, `R` of those rows (module docs):
/// written to `x`, its multipliers (in the units of `G`, either sign) to
/// `mult[..nact]`. `h` is the right-hand side. False when a number is not
/// finite.
#[allow(clippy::too_many_arguments)]
pub(super) fn minimiser_on<NV: Dim, NC: Dim>(
    J: &OMatrix<f64, NV, NV>,
    R: &OMatrix<f64, NV, NV>,
    h: &OVector<f64, NC>,
    act: &[u16],
    nact: usize,
    q: &OVector<f64, NV>,
    x: &mut OVector<f64, NV>,
    mult: &mut OVector<f64, NV>,
) -> bool
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    let nv = J.shape_generic().0;
    let n = nv.value();
    let nact = nact.min(n);
    // c = J' q.
    let mut c = OVector::<f64, NV>::zeros_generic(nv, nalgebra::U1);
    for (cj, col) in c.as_mut_slice().iter_mut().zip(columns(J.as_slice(), n)) {
        *cj = dot_d::<NV>(col, q.as_slice());
    }
    // y_1 = R^-T b (forward substitution), y_2 = -c_2.
    let mut y = OVector::<f64, NV>::zeros_generic(nv, nalgebra::U1);
    for j in 0..nact {
        let Some(&a) = act.get(j) else {
            return false;
        };
        let Some(&ha) = h.as_slice().get(usize::from(a)) else {
            return false;
        };
        let Some(rcol) = column(R.as_slice(), n, j) else {
            return false;
        };
        let mut acc = -ha;
        for (&rij, &yi) in rcol.iter().zip(y.as_slice()).take(j) {
            acc -= rij * yi;
        }
        let (Some(&rjj), Some(yj)) = (rcol.get(j), y.as_mut_slice().get_mut(j)) else {
            return false;
        };
        *yj = acc / rjj;
    }
    for (yj, &cj) in y.as_mut_slice().iter_mut().zip(c.as_slice()).skip(nact) {
        *yj = -cj;
    }
    // x = J y.
    let xs = x.as_mut_slice();
    xs.fill(0.0);
    for (col, &yj) in columns(J.as_slice(), n).zip(y.as_slice()) {
        for (xk, &jk) in xs.iter_mut().zip(col) {
            *xk += jk * yj;
        }
    }
    // u = R^-1 (y_1 + c_1).
    for (yj, &cj) in y.as_mut_slice().iter_mut().zip(c.as_slice()).take(nact) {
        *yj += cj;
    }
    mult.as_mut_slice().fill(0.0);
    if proximal_capable::<NV>() {
        back_substitute_by_columns(R, y.as_slice(), nact, mult.as_mut_slice());
    } else {
        // The small static sizes (the relaxation's probes, `qp/reprobe.rs`):
        // the iteration's own back substitution, one copy in flash.
        back_substitute(R, y.as_slice(), nact, mult.as_mut_slice());
    }
    xs.iter()
        .chain(mult.as_slice().iter().take(nact))
        .all(|v| v.is_finite())
}

/// Why [`resolve`] stopped the solve.
pub(super) enum ResolveStop {
    /// A number was not finite.
    Numerical,
    /// The budget ran out with a negative multiplier left.
    Budget,
}

/// The start of a proximal solve after the first (and of a probe resumed
/// from the one before, `qp/reprobe.rs`): the kept rows with `leave(row)`
/// dropped first (from `J`, `R` and `kept`; rows the solve leaves out),
/// then the minimiser on the kept active rows for the linear term `q`
/// ([`minimiser_on`], into `x` and `kept.mult`), then, while an inequality
/// row's multiplier is negative, the row with the most negative one dropped
/// and the minimiser formed again, at most `budget` drops in all. Returns
/// the drops made.
#[allow(clippy::too_many_arguments)]
pub(super) fn resolve<NV: Dim, NC: Dim>(
    J: &mut OMatrix<f64, NV, NV>,
    R: &mut OMatrix<f64, NV, NV>,
    h: &OVector<f64, NC>,
    kept: &mut Kept<NV>,
    q: &OVector<f64, NV>,
    x: &mut OVector<f64, NV>,
    budget: u32,
    leave: impl Fn(u16) -> bool,
) -> Result<u32, ResolveStop>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    let n = J.nrows();
    // At most `n` drops (the active rows), then one more minimiser.
    for drops in 0..=(n as u32) {
        let nact = kept.nact.min(n);
        // (Equality rows stay.)
        let left_out = kept
            .act
            .as_slice()
            .iter()
            .take(nact)
            .skip(kept.neq)
            .position(|&a| leave(a))
            .map(|j| j + kept.neq);
        let l = match left_out {
            Some(l) => l,
            None => {
                if !minimiser_on(J, R, h, kept.act.as_slice(), nact, q, x, &mut kept.mult) {
                    return Err(ResolveStop::Numerical);
                }
                let mut worst: Option<usize> = None;
                let mut worst_u = 0.0;
                for (j, &u) in kept
                    .mult
                    .as_slice()
                    .iter()
                    .enumerate()
                    .take(nact)
                    .skip(kept.neq)
                {
                    if u < worst_u {
                        worst_u = u;
                        worst = Some(j);
                    }
                }
                let Some(l) = worst else {
                    return Ok(drops);
                };
                l
            }
        };
        if drops >= budget {
            return Err(ResolveStop::Budget);
        }
        givens_drop(J, R, nact, l);
        remove_at(kept.act.as_mut_slice(), l, nact);
        kept.nact = nact - 1;
    }
    Err(ResolveStop::Numerical)
}
