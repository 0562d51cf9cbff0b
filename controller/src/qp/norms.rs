//! Per-row data of a QP's constraint matrix: the Euclidean row norms every
//! solve's scan uses, and the row norms in the metric of `H^-1` that scale
//! its choice of the row to add ([`RowNormsOf`],
//! [`DualActiveSetOf::prepare_rows`]).

#[cfg(feature = "alloc")]
use nalgebra::Dyn;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OVector, U1};

use super::bounds::SimpleBoundsOf;
use super::dense::DenseQpOf;
use super::settings::ZERO_ROW2;
use super::solver::DualActiveSetOf;
use crate::linalg::{column, columns, dot_d};
use crate::solution::QpAllocator;

/// Per-row data of a constraint matrix `G` used by a solve: squared Euclidean
/// norms `|g_i|^2` and reciprocal norms in the metric of `H^-1`,
/// `1 / |L^-1 g_i|` (0 and `+0` or `-0` for a zero row). Built by
/// [`DualActiveSetOf::prepare_rows`] for [`DualActiveSetOf::solve_prepared`].
#[derive(Clone, Debug)]
pub struct RowNormsOf<NC: Dim>
where
    DefaultAllocator: Allocator<NC>,
{
    /// `|g_i|^2`, in the units of `G` squared (no square root or division, so
    /// the pass over all rows is cheap; the violation test squares the slack).
    pub(super) norm2: OVector<f64, NC>,
    /// `1 / |L^-1 g_i|`, `+0` = not computed yet, `-0` for a zero row (set
    /// by the scan when it first finds the row violated).
    pub(super) inv_hnorm: OVector<f64, NC>,
    /// Rows covered.
    pub(super) m: usize,
    /// Every entry of the covered rows is finite.
    pub(super) finite: bool,
}

/// [`RowNormsOf`] with the row capacity as a constant.
pub type RowNorms<const NC: usize> = RowNormsOf<Const<NC>>;

impl<NC: Dim> RowNormsOf<NC>
where
    DefaultAllocator: Allocator<NC>,
{
    /// Squared Euclidean norms of the used rows of `qp` (H^-1 norms not
    /// computed).
    pub(super) fn euclidean<NV: Dim>(qp: &DenseQpOf<NV, NC>) -> Self
    where
        DefaultAllocator: Allocator<NV> + Allocator<NV, NC>,
    {
        let nc = qp.h.shape_generic().0;
        let mut rows = RowNormsOf {
            norm2: OVector::zeros_generic(nc, U1),
            inv_hnorm: OVector::zeros_generic(nc, U1),
            m: qp.m.min(nc.value()),
            finite: true,
        };
        rows.finite = squared_norms(qp, rows.norm2.as_mut_slice(), rows.m);
        rows
    }

    /// [`RowNormsOf::euclidean`] in place, in storage of `qp`'s capacity
    /// (the controller's, kept from cycle to cycle): no new storage moved
    /// into place.
    pub(super) fn set_euclidean<NV: Dim>(&mut self, qp: &DenseQpOf<NV, NC>)
    where
        DefaultAllocator: Allocator<NV> + Allocator<NV, NC>,
    {
        let nc = qp.h.shape_generic().0.value();
        let m = qp.m.min(nc);
        let sized = self.norm2.len() == nc && self.inv_hnorm.len() == nc;
        self.inv_hnorm.as_mut_slice().fill(0.0);
        let norm2 = self.norm2.as_mut_slice();
        if let Some(past) = norm2.get_mut(m..) {
            past.fill(0.0);
        }
        let finite = squared_norms(qp, norm2, m);
        self.m = m;
        self.finite = sized && finite;
    }

    /// [`RowNormsOf::euclidean`] with `|g_i|^2 = 1` for the bound rows of
    /// `bounds` (row codes of [`SimpleBoundsOf`]): no dot product for them.
    pub(super) fn euclidean_except<NV: Dim>(
        qp: &DenseQpOf<NV, NC>,
        bounds: &SimpleBoundsOf<NC>,
    ) -> Self
    where
        DefaultAllocator: Allocator<NV> + Allocator<NV, NC>,
    {
        let nc = qp.h.shape_generic().0;
        let m = qp.m.min(nc.value());
        let mut rows = RowNormsOf {
            norm2: OVector::zeros_generic(nc, U1),
            inv_hnorm: OVector::zeros_generic(nc, U1),
            m,
            finite: true,
        };
        for ((g, n2), &c) in columns(qp.gt.as_slice(), qp.gt.nrows())
            .zip(rows.norm2.as_mut_slice().iter_mut())
            .zip(bounds.code.as_slice())
            .take(m)
        {
            *n2 = if c != 0 { 1.0 } else { dot_d::<NV>(g, g) };
            if !n2.is_finite() {
                rows.finite = false;
            }
        }
        rows
    }
}

/// [`RowNormsOf`] with run-time sizes (feature `alloc`).
#[cfg(feature = "alloc")]
pub type RowNormsDyn = RowNormsOf<Dyn>;

impl<NV: Dim, NC: Dim> DualActiveSetOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The per-row data of `qp`'s constraint matrix that [`DualActiveSetOf::solve`]
    /// otherwise computes in every call (`m` Euclidean and `m` H^-1 row norms):
    /// prepare it once when `G` stays the same over many solves (only `q` and `h`
    /// change, as in a linear MPC with fixed constraints) and pass it to
    /// [`DualActiveSetOf::solve_prepared`].
    pub fn prepare_rows(&self, qp: &DenseQpOf<NV, NC>) -> RowNormsOf<NC> {
        let mut rows = RowNormsOf::euclidean(qp);
        let m = rows.m;
        for ((g, &n2), inv_hn) in columns(qp.gt.as_slice(), qp.gt.nrows())
            .zip(rows.norm2.as_slice().iter())
            .zip(rows.inv_hnorm.as_mut_slice().iter_mut())
            .take(m)
        {
            if n2 > ZERO_ROW2 {
                *inv_hn = self.inv_hnorm(g, n2);
            }
        }
        rows
    }

    /// `1 / |L^-1 g|` for a row with `|g|^2 = n2 > 0`; `-0` for a zero row
    /// (`n2 <= ZERO_ROW2`), whose rate in the scan, `slack * -0`, is then
    /// `+0`: never added, and cached (`+0` is "not computed yet").
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(super) fn inv_hnorm(&self, g: &[f64], n2: f64) -> f64 {
        if n2 <= ZERO_ROW2 {
            return -0.0;
        }
        let w = self.linv_mul(g);
        let hn = crate::linalg::sqrt(dot_d::<NV>(w.as_slice(), w.as_slice()));
        // L^-1 is nonsingular, so hn > 0 for a non-zero row (barring underflow,
        // where the Euclidean norm stands in).
        if hn > 0.0 {
            1.0 / hn
        } else {
            1.0 / crate::linalg::sqrt(n2)
        }
    }

    /// `1 / |L^-1 e_j|`, the norm of column `j` of `L^-1`: the bits of
    /// [`DualActiveSetOf::inv_hnorm`] for the row `+-e_j` (the products
    /// with its zero entries are exact zeros).
    #[inline(always)]
    pub(super) fn inv_hnorm_unit(&self, j: usize) -> f64 {
        let n = self.nv().value();
        let col = column(self.Linv.as_slice(), n, j).unwrap_or(&[]);
        let hn = crate::linalg::sqrt(dot_d::<NV>(col, col));
        if hn > 0.0 { 1.0 / hn } else { 1.0 }
    }
}

/// `norm2[i] = |g_i|^2` for the rows `i < m` of `qp`; whether all are
/// finite.
#[inline(always)]
fn squared_norms<NV: Dim, NC: Dim>(qp: &DenseQpOf<NV, NC>, norm2: &mut [f64], m: usize) -> bool
where
    DefaultAllocator: Allocator<NV> + Allocator<NC> + Allocator<NV, NC>,
{
    let mut finite = true;
    for (g, n2) in columns(qp.gt.as_slice(), qp.gt.nrows())
        .zip(norm2.iter_mut())
        .take(m)
    {
        *n2 = dot_d::<NV>(g, g);
        // A NaN or infinite entry makes `n2` non-finite, and so does a row
        // whose squared norm overflows (|g| > ~1e154): both are numerical
        // errors.
        if !n2.is_finite() {
            finite = false;
        }
    }
    finite
}
