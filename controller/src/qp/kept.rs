//! What a solve starts its factor from, below the factor
//! (`qp/orthogonal.rs`): the active rows kept from the solve before
//! ([`Kept`], and [`Resume`], whether a solve may resume from them), or the
//! start from scratch `J = L^-T`, `R = 0` not yet written ([`Pending`]).
//! The resumed start itself is `qp/resolve.rs`; who keeps them from solve to
//! solve, `qp/store.rs` and `qp/reprobe.rs`.

use nalgebra::{DefaultAllocator, Dim, OVector};

/// The active rows a proximal solve ended with (the order of the factor's
/// columns), `nact` of them, the first `neq` equality rows.
#[derive(Clone, Debug)]
pub(super) struct Kept<NV: Dim>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV>,
{
    /// Active rows (first `nact` valid).
    pub act: OVector<u16, NV>,
    /// Their multipliers at the start of the next solve (formed by
    /// `resolve`, `qp/resolve.rs`).
    pub mult: OVector<f64, NV>,
    /// Number of active rows.
    pub nact: usize,
    /// Number of equality rows at their head.
    pub neq: usize,
}

/// The active rows a solve resumes from, as a type parameter of
/// `Orthogonal` (`qp/orthogonal.rs`; as [`BoundRows`](super::bounds::BoundRows) for the
/// bounds): `()` for a solve that iterates from scratch (no resume hook, and
/// the iteration's own scan with no test for spans), `Option<&Kept>` for the
/// proximal iterations' solves and the probes (`qp/reprobe.rs`), whose scan
/// reads the rows' spans where they are given and which resume from the
/// kept rows ([`ActiveSetFactor::resume`](crate::active_set::ActiveSetFactor::resume)).
pub(super) trait Resume<NV: Dim>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV>,
{
    /// Whether the solve may resume (and its scan reads spans).
    const RESUMES: bool;

    /// The rows and multipliers to resume from, if any.
    fn kept(&self) -> Option<&Kept<NV>>;
}

impl<NV: Dim> Resume<NV> for ()
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV>,
{
    const RESUMES: bool = false;

    #[inline(always)]
    fn kept(&self) -> Option<&Kept<NV>> {
        None
    }
}

impl<NV: Dim> Resume<NV> for Option<&Kept<NV>>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV>,
{
    const RESUMES: bool = true;

    #[inline(always)]
    fn kept(&self) -> Option<&Kept<NV>> {
        *self
    }
}

/// A start from scratch (`J = L^-T`, `R = 0`) not yet written: on hosts,
/// for the sizes with the hot start, a solve from scratch sets `J` and `R`
/// only when it first needs them (`Orthogonal::settle`: before its first
/// direction, add, drop or hot-start step), so a solve the hot start's
/// guess ends (which reads neither) writes nothing, and a restart of the
/// controller's next QP (`ReprobeOf::restart`, `qp/reprobe.rs`) copies nothing.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pending {
    /// `J` and `R` still hold what an earlier solve left; the start from
    /// scratch is to be set before they are read.
    pub unset: bool,
    /// The columns `0..r_cols` of `R` may be nonzero, the others are zero
    /// (an add writes column `nact` of `R`, a drop zeroes the column it
    /// vacates): setting `R = 0` zeroes only those.
    pub r_cols: usize,
}

impl Pending {
    /// Nothing to set, `R = 0`.
    pub(super) const NONE: Pending = Pending {
        unset: false,
        r_cols: 0,
    };
}
