//! Where a solve keeps its factor `J`, `R` ([`Store`]): a single solve
//! (`solve`, `solve_prepared`, `solve_bounded`) holds it in its own frame,
//! started from scratch and dropped at its end ([`Local`]); a probe of the
//! relaxation holds it in the [`Carry`] it shares with the probes before and
//! after it (`qp/reprobe.rs`). `DualActiveSetOf::solve_with` is generic over
//! the two, so a single solve compiles as a solve with its factor in local
//! variables: no `Carry` built, moved or read through a pointer, no kept
//! rows to test, and nothing left for a next solve. The controller's cycle
//! solves only probes, so its builds (and the firmware's) hold only the
//! [`Carry`] instance.

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

use super::guess::GuessWork;
use super::reprobe::Carry;
use super::resolve::Kept;
use super::{DualActiveSetOf, QpAllocator};
use crate::active_set::Iterate;
use crate::solution::QpStatus;

/// The factor of a solve: `J`, `R`, the active rows it may resume from and
/// the hot start's guess's kept workspace (`None`: the guess's own zeroed
/// matrices, `qp/guess.rs`).
pub(super) type Parts<'s, NV> = (
    &'s mut OMatrix<f64, NV, NV>,
    &'s mut OMatrix<f64, NV, NV>,
    Option<&'s Kept<NV>>,
    Option<&'s mut GuessWork<NV>>,
);

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
    /// ends the solve (`Carry::start`; from scratch: the unconstrained
    /// minimiser, no drops).
    #[allow(clippy::too_many_arguments)]
    fn start<NC: Dim>(
        &mut self,
        own: &mut Self::Own,
        solver: &DualActiveSetOf<NV, NC>,
        q: &OVector<f64, NV>,
        h: &OVector<f64, NC>,
        blocked: &mut OVector<bool, NC>,
        me: usize,
        max_iter: u32,
    ) -> Result<(OVector<f64, NV>, u32), QpStatus>
    where
        DefaultAllocator: QpAllocator<NV, NC>;

    /// The factor and the rows to resume from (after [`Store::start`]).
    fn parts<'s>(&'s mut self, own: &'s mut Self::Own) -> Parts<'s, NV>;

    /// The end of the solve: its iteration, `None` when it stopped on a
    /// numerical error.
    fn keep(&mut self, it: Option<&Iterate<NV>>);
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
    fn start<NC: Dim>(
        &mut self,
        _own: &mut Self::Own,
        solver: &DualActiveSetOf<NV, NC>,
        q: &OVector<f64, NV>,
        _h: &OVector<f64, NC>,
        _blocked: &mut OVector<bool, NC>,
        _me: usize,
        _max_iter: u32,
    ) -> Result<(OVector<f64, NV>, u32), QpStatus>
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        Ok((solver.unconstrained_minimiser(q), 0))
    }

    #[inline(always)]
    fn parts<'s>(&'s mut self, own: &'s mut Self::Own) -> Parts<'s, NV> {
        (&mut own.0, &mut own.1, None, None)
    }

    #[inline(always)]
    fn keep(&mut self, _it: Option<&Iterate<NV>>) {}
}

impl<NV: Dim> Store<NV> for &mut Carry<NV>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV> + nalgebra::allocator::Allocator<NV, NV>,
{
    /// Nothing: the factor is the carry's.
    type Own = ();

    const RESUMES: bool = true;

    #[inline(always)]
    fn own<NC: Dim>(&self, _solver: &DualActiveSetOf<NV, NC>) -> Self::Own
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
    }

    #[inline(always)]
    fn start<NC: Dim>(
        &mut self,
        _own: &mut Self::Own,
        solver: &DualActiveSetOf<NV, NC>,
        q: &OVector<f64, NV>,
        h: &OVector<f64, NC>,
        blocked: &mut OVector<bool, NC>,
        me: usize,
        max_iter: u32,
    ) -> Result<(OVector<f64, NV>, u32), QpStatus>
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        Carry::start(self, solver, q, h, blocked, me, max_iter)
    }

    #[inline(always)]
    fn parts<'s>(&'s mut self, _own: &'s mut Self::Own) -> Parts<'s, NV> {
        let carry = &mut **self;
        #[cfg(not(target_os = "none"))]
        let guess = Some(&mut carry.guess);
        #[cfg(target_os = "none")]
        let guess = None;
        let Carry {
            J, R, kept, valid, ..
        } = carry;
        (J, R, if *valid { Some(&*kept) } else { None }, guess)
    }

    #[inline(always)]
    fn keep(&mut self, it: Option<&Iterate<NV>>) {
        match it {
            Some(it) => Carry::keep(self, it),
            None => self.valid = false,
        }
    }
}
