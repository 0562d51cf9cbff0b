//! Where a solve keeps its factor `J`, `R` ([`Store`]): a single solve
//! (`solve`, `solve_prepared`, `solve_bounded`) holds it in its own frame,
//! started from scratch and dropped at its end ([`Local`]); a probe of the
//! relaxation holds it in the `Carry` it shares with the probes before and
//! after it (`qp/reprobe.rs`, with its `Store`). `DualActiveSetOf::solve_with` is generic over
//! the two, so a single solve compiles as a solve with its factor in local
//! variables: no `Carry` built, moved or read through a pointer, no kept
//! rows to test, and nothing left for a next solve. The controller's cycle
//! solves only probes, so its builds (and the firmware's) hold only the
//! `Carry` instance.

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

use super::gram::GuessWork;
use super::kept::{Kept, Pending};
use super::solver::DualActiveSetOf;
use crate::active_set::Iterate;
use crate::solution::{QpAllocator, QpStatus};

/// The factor of a solve: `J`, `R`, the active rows it may resume from,
/// the hot start's guess's kept workspace (`None`: the guess's own zeroed
/// matrices, `qp/guess.rs`) and the start from scratch still to be set
/// (`None`: nothing to set, `qp/reprobe.rs`).
pub(super) type Parts<'s, NV> = (
    &'s mut OMatrix<f64, NV, NV>,
    &'s mut OMatrix<f64, NV, NV>,
    Option<&'s Kept<NV>>,
    Option<&'s mut GuessWork<NV>>,
    Option<&'s mut Pending>,
);

/// What [`Store::start`] starts a solve from: the linear term `q`, the
/// right-hand side `h`, the rows `blocked` left out (the first `me` rows
/// equalities; a start from kept rows marks them and the equality rows
/// blocked) and the iteration budget `max_iter` (of which the drops made
/// resuming take their part).
pub(super) struct Begin<'b, NV: Dim, NC: Dim>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The solver (for `L^-1` and the unconstrained minimiser).
    pub solver: &'b DualActiveSetOf<NV, NC>,
    /// The linear term.
    pub q: &'b OVector<f64, NV>,
    /// The right-hand side.
    pub h: &'b OVector<f64, NC>,
    /// The rows left out of the scans.
    pub blocked: &'b mut OVector<bool, NC>,
    /// The number of equality rows, at the head.
    pub me: usize,
    /// The iteration budget.
    pub max_iter: u32,
}

/// Where a solve keeps its factor (module docs).
pub(super) trait Store<NV: Dim>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV> + nalgebra::allocator::Allocator<NV, NV>,
{
    /// The storage the solve holds in its own frame.
    type Own;

    /// Whether a solve may start from kept active rows (else always from
    /// scratch, on the plain factor).
    const RESUMES: bool;

    /// The solve's own storage, at the start from scratch where it holds the
    /// factor.
    fn own<NC: Dim>(&self, solver: &DualActiveSetOf<NV, NC>) -> Self::Own
    where
        DefaultAllocator: QpAllocator<NV, NC>;

    /// The starting iterate and the drops made resuming, or the status that
    /// ends the solve (`Carry`'s, `qp/reprobe.rs`; from scratch, this default: the
    /// unconstrained minimiser, no drops).
    #[inline(always)]
    fn start<NC: Dim>(&mut self, at: Begin<'_, NV, NC>) -> Result<(OVector<f64, NV>, u32), QpStatus>
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        Ok((at.solver.unconstrained_minimiser(at.q), 0))
    }

    /// The factor and the rows to resume from (after [`Store::start`]).
    fn parts<'s>(&'s mut self, own: &'s mut Self::Own) -> Parts<'s, NV>;

    /// The end of the solve: its iteration, `None` when it stopped on a
    /// numerical error; `guessed`: the hot start's guess ended it (no
    /// factor of its active rows formed, `J` and `R` as they were).
    fn keep(&mut self, it: Option<&Iterate<NV>>, guessed: bool);
}

/// A single solve's factor, in its own frame, from scratch (module docs).
pub(super) struct Local;

impl<NV: Dim> Store<NV> for Local
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV> + nalgebra::allocator::Allocator<NV, NV>,
{
    /// `J = L^-T`, `R = 0`.
    type Own = (OMatrix<f64, NV, NV>, OMatrix<f64, NV, NV>);

    const RESUMES: bool = false;

    #[inline(always)]
    fn own<NC: Dim>(&self, solver: &DualActiveSetOf<NV, NC>) -> Self::Own
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        let nv = solver.nv();
        (solver.J0.clone(), OMatrix::zeros_generic(nv, nv))
    }

    #[inline(always)]
    fn parts<'s>(&'s mut self, own: &'s mut Self::Own) -> Parts<'s, NV> {
        (&mut own.0, &mut own.1, None, None, None)
    }

    #[inline(always)]
    fn keep(&mut self, _it: Option<&Iterate<NV>>, _guessed: bool) {}
}
