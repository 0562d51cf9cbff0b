//! Row spans: the entries `lo..hi` of a row of `G` outside which it is zero,
//! so the row's dot products (the scan's slack `g_i'x`, the projection
//! `J' g_p` of an add) run over the span only. Structured QPs have short
//! spans: the non-condensed MPC's dynamics rows touch two consecutive ticks,
//! a bound one variable. `lo` is rounded down to even, so each product keeps
//! the parity of its index, hence its partial sum in [`dot`](crate::linalg::dot)
//! and [`dot_d`](crate::linalg::dot_d): the products left out are exact
//! zeros (`0 * x_k` for a finite `x_k`), which leave a sum that starts at +0
//! as it is, so a dot product over the span has the bits of the full one.

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

use super::bounds::BoundRows;
use crate::linalg::columns;

/// The packed span of a row: `lo | hi << 16` (`n <= u16::MAX`).
pub(super) type Span = u32;

/// The spans of the first `m` rows of `G` (the columns of `gt`, `NV x NC`):
/// `lo` (even) and `hi` bound every entry that is not `+-0` (NaN included);
/// a zero row has the span `0..0`, and so has a bound row of `skip`
/// (`qp/bounds.rs`; their spans are not used).
pub(super) fn row_spans<NV: Dim, NC: Dim>(
    gt: &OMatrix<f64, NV, NC>,
    m: usize,
    skip: impl BoundRows,
) -> OVector<Span, NC>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NC> + nalgebra::allocator::Allocator<NC>,
{
    let (nv, nc) = gt.shape_generic();
    let n = nv.value();
    let mut out = OVector::<Span, NC>::zeros_generic(nc, U1);
    for (i, (g, s)) in columns(gt.as_slice(), n)
        .zip(out.as_mut_slice().iter_mut())
        .take(m)
        .enumerate()
    {
        if skip.bound(i).is_some() {
            continue;
        }
        let lo = g.iter().position(|&v| v != 0.0);
        let hi = g.iter().rposition(|&v| v != 0.0);
        if let (Some(lo), Some(hi)) = (lo, hi) {
            *s = ((lo & !1) as Span) | (((hi + 1) as Span) << 16);
        }
    }
    out
}

/// `(lo, hi)` of a packed span.
#[inline(always)]
pub(super) fn unpack(s: Span) -> (usize, usize) {
    ((s & 0xffff) as usize, (s >> 16) as usize)
}
