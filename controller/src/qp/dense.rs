//! The QP the solver takes, [`DenseQpOf`]: `q`, the rows of `G` (equality
//! rows first) and `h`, stored with a capacity of `NC` rows for any dimension
//! types.

use crate::linalg::{column, column_mut, columns};
#[cfg(feature = "alloc")]
use nalgebra::Dyn;
use nalgebra::allocator::Allocator;
use nalgebra::{
    ArrayStorage, Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector, U1,
};

/// A QP of the form solved here, for any dimension types (see [`DenseQp`]
/// for the static sizes), stored with a capacity of `NC` rows of which the
/// first `m` are used; the first `me` of those are equalities
/// `g_i'x = h_i`, the others inequalities `g_i'x <= h_i`. `gt` holds `G`
/// transposed (one constraint normal per column) so each row of `G` is
/// contiguous.
#[derive(Clone, Debug)]
pub struct DenseQpOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: Allocator<NV> + Allocator<NC> + Allocator<NV, NC>,
{
    /// Linear cost term `q`.
    pub q: OVector<f64, NV>,
    /// `G` transposed: column `i` is row `i` of `G`.
    pub gt: OMatrix<f64, NV, NC>,
    /// Right-hand side `h`.
    pub h: OVector<f64, NC>,
    /// Number of rows in use.
    pub m: usize,
    /// Number of equality rows (rows `0..me`; `me <= m`).
    pub me: usize,
}

/// [`DenseQpOf`] with the sizes as constants (stack only).
pub type DenseQp<const NV: usize, const NC: usize> = DenseQpOf<Const<NV>, Const<NC>>;

impl<const NV: usize, const NC: usize> Default for DenseQpOf<Const<NV>, Const<NC>> {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl<const NV: usize, const NC: usize> DenseQpOf<Const<NV>, Const<NC>> {
    /// An empty QP (no rows, `q = 0`), all storage zero: usable in `const` and
    /// `static` initialisers (a `static` holding it lands in `.bss`).
    pub const EMPTY: Self = DenseQpOf {
        q: SVector::from_array_storage(ArrayStorage([[0.0; NV]; 1])),
        gt: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NC])),
        h: SVector::from_array_storage(ArrayStorage([[0.0; NC]; 1])),
        m: 0,
        me: 0,
    };

    /// An empty QP with linear term `q`.
    pub fn with_q(q: SVector<f64, NV>) -> Self {
        DenseQpOf { q, ..Self::EMPTY }
    }

    /// Row `i` of `G` (a column of `gt`).
    ///
    /// # Panics
    ///
    /// If `i >= NC`; see [`DenseQpOf::get_row`] for the non-panicking form.
    pub fn row(&self, i: usize) -> SVector<f64, NV> {
        self.gt.column(i).into_owned()
    }
}

#[cfg(feature = "alloc")]
impl DenseQpOf<Dyn, Dyn> {
    /// An empty QP with linear term `q` and room for `nc` rows (all zero).
    pub fn with_capacity(q: nalgebra::DVector<f64>, nc: usize) -> Self {
        Self::with_q_generic(q, Dyn(nc))
    }
}

impl<NV: Dim, NC: Dim> DenseQpOf<NV, NC>
where
    DefaultAllocator: Allocator<NV> + Allocator<NC> + Allocator<NV, NC>,
{
    /// An empty QP with linear term `q` and room for `nc` rows (all zero),
    /// for any dimension types.
    pub fn with_q_generic(q: OVector<f64, NV>, nc: NC) -> Self {
        let nv = q.shape_generic().0;
        DenseQpOf {
            q,
            gt: OMatrix::zeros_generic(nv, nc),
            h: OVector::zeros_generic(nc, U1),
            m: 0,
            me: 0,
        }
    }

    /// Removes all rows and zeroes `q`.
    pub fn clear(&mut self) {
        self.q.as_mut_slice().fill(0.0);
        self.m = 0;
        self.me = 0;
    }

    /// Row capacity (`NC`).
    pub fn capacity(&self) -> usize {
        self.gt.ncols()
    }

    /// Appends the row `g' x <= h`. Returns `Err(())` (and changes nothing)
    /// when the capacity `NC` is full.
    #[allow(clippy::result_unit_err)]
    pub fn push_row(&mut self, g: &OVector<f64, NV>, h: f64) -> Result<(), ()> {
        let nv = self.gt.nrows();
        // `gt` is column-major: column `m` of `gt` is row `m` of `G`.
        let (Some(col), Some(rhs)) = (
            column_mut(self.gt.as_mut_slice(), nv, self.m),
            self.h.as_mut_slice().get_mut(self.m),
        ) else {
            return Err(());
        };
        crate::linalg::copy(col, g.as_slice());
        *rhs = h;
        self.m += 1;
        Ok(())
    }

    /// Appends the equality row `g' x = h`. Equality rows come first:
    /// `Err(())` (and nothing changes) when an inequality row is already
    /// there or the capacity is full.
    #[allow(clippy::result_unit_err)]
    pub fn push_equality(&mut self, g: &OVector<f64, NV>, h: f64) -> Result<(), ()> {
        if self.me != self.m {
            return Err(());
        }
        self.push_row(g, h)?;
        self.me += 1;
        Ok(())
    }

    /// Row `i` as `(g_i, h_i)`, or `None` when `i >= NC` (rows `m..NC` are unused
    /// but exist).
    pub fn get_row(&self, i: usize) -> Option<(OVector<f64, NV>, f64)> {
        let h = *self.h.as_slice().get(i)?;
        let g = column(self.gt.as_slice(), self.gt.nrows(), i)?;
        Some((self.owned_row(g), h))
    }

    /// A row of `G` (a column of `gt`) as a vector (no allocation for static
    /// sizes, no panic: entries copied pairwise).
    fn owned_row(&self, g: &[f64]) -> OVector<f64, NV> {
        let mut v = OVector::zeros_generic(self.q.shape_generic().0, U1);
        for (a, &b) in v.as_mut_slice().iter_mut().zip(g) {
            *a = b;
        }
        v
    }

    /// The rows in use, `(g_i, h_i)` for `i = 0..m`, in order.
    pub fn rows(&self) -> impl Iterator<Item = (OVector<f64, NV>, f64)> + '_ {
        let m = self.m.min(self.gt.ncols());
        columns(self.gt.as_slice(), self.gt.nrows())
            .zip(self.h.as_slice().iter())
            .take(m)
            .map(|(g, h)| (self.owned_row(g), *h))
    }

    /// The used rows with their Euclidean norms: `(g_i, h_i, |g_i|)`.
    pub fn rows_with_norm(&self) -> impl Iterator<Item = (OVector<f64, NV>, f64, f64)> + '_ {
        self.rows().map(|(g, h)| {
            let n = g.norm();
            (g, h, n)
        })
    }

    /// Largest violation over the used rows, unscaled: `(g_i x - h_i)^+` of
    /// the inequality rows, `|g_i x - h_i|` of the equality rows.
    pub fn max_violation(&self, x: &OVector<f64, NV>) -> f64 {
        let mut worst: f64 = 0.0;
        for (i, (g, h)) in self.rows().enumerate() {
            let mut v = g.dot(x) - h;
            if i < self.me {
                v = v.abs();
            }
            if v > worst {
                worst = v;
            }
        }
        worst
    }
}

/// [`DenseQpOf`] with run-time sizes (feature `alloc`).
#[cfg(feature = "alloc")]
pub type DenseQpDyn = DenseQpOf<Dyn, Dyn>;
