//! Simple bounds: the inequality rows of a QP that are `x_j <= u` (the unit
//! row `e_j`) or `-x_j <= -l` (`-e_j`), found once per `G` by
//! [`SimpleBoundsOf::detect`] and handled as bounds by
//! [`DualActiveSetOf::solve_bounded`](super::DualActiveSetOf::solve_bounded),
//! as DAQP handles its simple bounds: a bound's squared norm is 1 (no dot
//! product), its slack at `x` one subtraction (`h_i -+ x_j`), its projection
//! `J' g_p` of an add the row `j` of `J` (no dot products), and its norm in
//! the metric of `H^-1` that of column `j` of `L^-1` (no product with `L^-1`).
//! The rows stay in the QP, so the active set, the multipliers and the Farkas
//! certificate are those of the rows, and every operation gives the bits of
//! the dot products it replaces (module docs of `qp/spans.rs`: products with
//! the zero entries are exact zeros), so a solve with bounds returns what
//! [`DualActiveSetOf::solve`](super::DualActiveSetOf::solve) returns.

#[cfg(feature = "alloc")]
use nalgebra::Dyn;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OVector, U1};

use super::dense::DenseQpOf;
use crate::linalg::columns;

/// Which rows of a QP's `G` are simple bounds, for any row capacity `NC`
/// (see [`SimpleBounds`] for the static sizes): built by
/// [`SimpleBoundsOf::detect`] from the QP, valid for QPs with the same rows
/// of `G` (`q` and `h` may change, as with
/// [`DualActiveSetOf::prepare_rows`](super::DualActiveSetOf::prepare_rows)).
#[derive(Clone, Debug)]
pub struct SimpleBoundsOf<NC: Dim>
where
    DefaultAllocator: Allocator<NC>,
{
    /// Per row: 0 for a general row, else `1 + 2 j + s` for the bound row
    /// `e_j` (`s = 0`, an upper bound) or `-e_j` (`s = 1`, a lower bound).
    pub(super) code: OVector<u32, NC>,
    /// Rows covered (the `m` of the QP detected from).
    pub(super) m: usize,
    /// Number of bound rows.
    count: usize,
}

/// [`SimpleBoundsOf`] with the row capacity as a constant.
pub type SimpleBounds<const NC: usize> = SimpleBoundsOf<Const<NC>>;

/// [`SimpleBoundsOf`] with run-time sizes (feature `alloc`).
#[cfg(feature = "alloc")]
pub type SimpleBoundsDyn = SimpleBoundsOf<Dyn>;

impl<NC: Dim> SimpleBoundsOf<NC>
where
    DefaultAllocator: Allocator<NC>,
{
    /// The bound rows of `qp`: its inequality rows (`i >= me`) with exactly
    /// one non-zero entry, which is `1` or `-1` (the rows
    /// `DenseProblem::stacked` of the reference writes for `ub` and `lb`).
    /// One pass over `G` (`O(m n)`): do it once per `G`, outside the solves.
    pub fn detect<NV: Dim>(qp: &DenseQpOf<NV, NC>) -> Self
    where
        DefaultAllocator: Allocator<NV> + Allocator<NV, NC>,
    {
        let nc = qp.h.shape_generic().0;
        let m = qp.m.min(nc.value());
        let mut code = OVector::<u32, NC>::zeros_generic(nc, U1);
        let mut count = 0;
        for (i, (g, c)) in columns(qp.gt.as_slice(), qp.gt.nrows())
            .zip(code.as_mut_slice().iter_mut())
            .take(m)
            .enumerate()
        {
            if i < qp.me {
                continue;
            }
            let mut nz = g.iter().enumerate().filter(|(_, v)| **v != 0.0);
            if let (Some((j, &v)), None) = (nz.next(), nz.next())
                && (v == 1.0 || v == -1.0)
                && let Ok(j) = u32::try_from(j)
                && j < u32::MAX / 4
            {
                *c = 1 + 2 * j + u32::from(v < 0.0);
                count += 1;
            }
        }
        SimpleBoundsOf { code, m, count }
    }

    /// Number of bound rows found.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Rows covered (the number of rows of the QP detected from).
    pub fn rows(&self) -> usize {
        self.m
    }

    /// Row `i` as a bound: `(j, s)` for the row `s e_j` (`s = 1.0` for an
    /// upper bound, `-1.0` for a lower one), `None` for a general row.
    pub fn bound(&self, i: usize) -> Option<(usize, f64)> {
        unit(*self.code.as_slice().get(i)?)
    }
}

/// The bound of a row code (see [`SimpleBoundsOf::code`]).
#[inline(always)]
pub(super) fn unit(c: u32) -> Option<(usize, f64)> {
    let c = c.checked_sub(1)?;
    let s = if c & 1 == 1 { -1.0 } else { 1.0 };
    Some(((c >> 1) as usize, s))
}

/// The bound rows as an [`Orthogonal`](super::orthogonal::Orthogonal) factor
/// reads them: `()` for a solve without bounds (a zero-size type, so those
/// solves compile as they would without this module), the row codes of a
/// [`SimpleBoundsOf`] otherwise.
pub(super) trait BoundRows: Copy {
    /// Row `i` as a bound `(j, s)` (the row `s e_j`), `None` for a general
    /// row.
    fn bound(&self, i: usize) -> Option<(usize, f64)>;
}

impl BoundRows for () {
    #[inline(always)]
    fn bound(&self, _i: usize) -> Option<(usize, f64)> {
        None
    }
}

impl<NC: Dim> BoundRows for &OVector<u32, NC>
where
    DefaultAllocator: Allocator<NC>,
{
    #[inline(always)]
    fn bound(&self, i: usize) -> Option<(usize, f64)> {
        unit(*self.as_slice().get(i)?)
    }
}
