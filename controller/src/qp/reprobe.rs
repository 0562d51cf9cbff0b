//! Solves that continue from the factor of the solve before them: the
//! probes of the relaxation scheme ([`crate::relax`]) solve the same QP
//! (same `H`, rows `G` and `q`) again and again, each with other right-hand
//! sides `h` and a selection of its rows. As DAQP's parametric hot start,
//! each probe starts from the active rows the last one ended with, not from
//! the unconstrained minimiser:
//!
//! * the Euclidean row norms are computed once for all the probes of a QP,
//!   and the `H^-1` norms once per row, when a probe first finds it
//!   violated ([`ReprobeOf`]);
//! * the factor `J`, `R` of the last probe's active rows (after a feasible
//!   solve its optimal active set; after an infeasible one the rows active
//!   at its Farkas certificate) is kept ([`Carry`]); rows the next probe
//!   leaves out are dropped from it (Givens rotations, as a drop of the
//!   iteration);
//! * the next probe forms the minimiser on the kept rows held as equalities
//!   for its `h` and their multipliers, drops the row with the most negative
//!   multiplier until none is negative (`qp/resolve.rs`, as between the
//!   proximal iterations), and the dual iteration continues from that pair
//!   (Goldfarb & Idnani's S-pair: `x` optimal on the active rows,
//!   multipliers `>= 0`) with its usual scans, adds and drops.
//!
//! Any such pair is a valid start of the dual method, so each probe ends at
//! the same optimum (unique, `H` definite) or proves the same emptiness as a
//! solve from scratch; the path, hence the rounding and which Farkas
//! certificate an infeasible probe returns, may differ. The drops made when
//! resuming count as iterations.
//!
//! A single solve (`solve`, `solve_prepared`, `solve_bounded`) keeps its
//! factor in its own frame instead (`qp/store.rs`).

use nalgebra::allocator::Allocator;
use nalgebra::{
    ArrayStorage, Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector, U1,
};

#[cfg(not(target_os = "none"))]
use super::guess::GuessWork;
use super::resolve::{Kept, ResolveStop, resolve};
use super::store::Begin;
use super::{DenseQpOf, DualActiveSetOf, QpAllocator, RowNormsOf};
use crate::active_set::Iterate;
use crate::solution::{QpSolutionOf, QpStatus};

/// A start from scratch (`J = L^-T`, `R = 0`) not yet written: on hosts,
/// for the sizes with the hot start, a solve from scratch sets `J` and `R`
/// only when it first needs them (`Orthogonal::settle`: before its first
/// direction, add, drop or hot-start step), so a solve the hot start's
/// guess ends (which reads neither) writes nothing, and a restart of the
/// controller's next QP ([`ReprobeOf::restart`]) copies nothing.
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

/// The factor of a solve's active rows: storage for the solve, and what it
/// leaves for the next one of the same QP's rows (module docs).
#[derive(Clone, Debug)]
pub(super) struct Carry<NV: Dim>
where
    DefaultAllocator: Allocator<NV> + Allocator<NV, NV>,
{
    /// `J = L^-T Q` of the active rows `kept` (when `valid`).
    pub J: OMatrix<f64, NV, NV>,
    /// Upper-triangular `R` of the active rows `kept` (when `valid`).
    pub R: OMatrix<f64, NV, NV>,
    /// The active rows the last solve ended with.
    pub kept: Kept<NV>,
    /// `J`, `R` and `kept` hold the factor of a finished solve (solved or
    /// proven infeasible); else the next solve starts from scratch.
    pub valid: bool,
    /// `J = L^-T` and `R = 0` already (a start from scratch need not set
    /// them again).
    pub pristine: bool,
    /// The start from scratch left to the solve that first needs the factor
    /// ([`Pending`]).
    pub pending: Pending,
    /// The hot start's guess's matrices (`qp/guess.rs`), kept (not
    /// cleared) from solve to solve. Not on bare-metal targets (the
    /// firmware's N = 3 has no hot start; a guess there zeroes matrices of
    /// its own).
    #[cfg(not(target_os = "none"))]
    pub guess: GuessWork<NV>,
}

impl<NV: Dim> Carry<NV>
where
    DefaultAllocator: Allocator<NV> + Allocator<NV, NV>,
{
    /// Empty storage: the solve starts from scratch.
    pub(super) fn fresh(nv: NV) -> Self {
        Self::holding(OMatrix::zeros_generic(nv, nv), false)
    }

    /// Storage holding the start from scratch of `solver`'s solves (`J =
    /// L^-T`, `R = 0`), so that the first solve need not set it again (on
    /// hosts; on bare-metal targets [`Carry::fresh`], one start in flash).
    pub(super) fn scratch<NC: Dim>(solver: &DualActiveSetOf<NV, NC>) -> Self
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        if cfg!(target_os = "none") {
            return Carry::fresh(solver.nv());
        }
        Self::holding(solver.J0.clone(), true)
    }

    /// [`Carry::scratch`] in place: the storage set to the start from
    /// scratch of `solver`'s solves (on hosts `J = L^-T`, `R = 0`, written
    /// where they are; on bare-metal targets left to the first solve, as
    /// [`Carry::fresh`]), nothing kept.
    pub(super) fn restart<NC: Dim>(&mut self, solver: &DualActiveSetOf<NV, NC>)
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        self.valid = false;
        self.kept.nact = 0;
        self.kept.neq = 0;
        if cfg!(target_os = "none") {
            self.pristine = false;
            return;
        }
        if self.J.shape() != solver.J0.shape() {
            // Storage of another size (run-time sizes): new storage.
            *self = Carry::scratch(solver);
            return;
        }
        if lazy(solver) {
            // Set by the solve that needs it (`Pending`).
            self.pristine = false;
            return;
        }
        // Slices (a `memcpy` and a `memset`), not nalgebra's entry loops.
        for (j, &j0) in self.J.as_mut_slice().iter_mut().zip(solver.J0.as_slice()) {
            *j = j0;
        }
        self.R.as_mut_slice().fill(0.0);
        self.pristine = true;
    }

    /// `J`, `R = 0`, no kept rows; `pristine` as given.
    fn holding(J: OMatrix<f64, NV, NV>, pristine: bool) -> Self {
        let nv = J.shape_generic().0;
        Carry {
            J,
            R: OMatrix::zeros_generic(nv, nv),
            kept: Kept {
                act: OVector::zeros_generic(nv, U1),
                mult: OVector::zeros_generic(nv, U1),
                nact: 0,
                neq: 0,
            },
            valid: false,
            pristine,
            pending: Pending::NONE,
            #[cfg(not(target_os = "none"))]
            guess: GuessWork::zeros(nv),
        }
    }

    /// The start of a solve with the linear term `q`, the right-hand side
    /// `h` and the rows `blocked` left out (the first `me` rows equalities):
    /// from scratch (`J = L^-T`, `R = 0`, the unconstrained minimiser), or,
    /// when `valid` and no equality row is left out, from the kept active
    /// rows (module docs: those `blocked` dropped, then [`resolve`] within
    /// `max_iter` drops; the kept rows and the equality rows are marked in
    /// `blocked`). The starting
    /// iterate and the drops made, or the status that ends the solve.
    pub(super) fn start<NC: Dim>(
        &mut self,
        at: Begin<'_, NV, NC>,
    ) -> Result<(OVector<f64, NV>, u32), QpStatus>
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        let Begin {
            solver,
            q,
            h,
            blocked,
            me,
            max_iter,
        } = at;
        let nv = solver.nv();
        let n = nv.value();
        // Equality rows stay in the factor: one left out (or a zero one)
        // means a start from scratch (`me` is 0 where they are not compiled
        // in).
        if blocked.as_slice().iter().take(me).any(|&b| b) {
            self.valid = false;
        }
        if !self.valid {
            if !self.pristine {
                if lazy(solver) {
                    self.pending.unset = true;
                } else {
                    self.J.clone_from(&solver.J0);
                    self.R.fill(0.0);
                }
            }
            self.pristine = false;
            return Ok((solver.unconstrained_minimiser(q), 0));
        }
        // Kept rows this solve leaves out are dropped first.
        let kept = &mut self.kept;
        let b = blocked.as_mut_slice();
        let mut x = OVector::<f64, NV>::zeros_generic(nv, U1);
        let leave = |a: u16| b.get(usize::from(a)).copied().unwrap_or(true);
        let drops = match resolve(
            &mut self.J,
            &mut self.R,
            h,
            kept,
            q,
            &mut x,
            max_iter,
            leave,
        ) {
            Ok(drops) => drops,
            Err(ResolveStop::Budget) => return Err(QpStatus::IterationLimit),
            Err(ResolveStop::Numerical) => return Err(QpStatus::NumericalError),
        };
        // The kept rows and every equality row (active, or redundant) stay
        // out of the scans.
        for v in b.iter_mut().take(me) {
            *v = true;
        }
        for &a in kept.act.as_slice().iter().take(kept.nact.min(n)) {
            if let Some(v) = b.get_mut(usize::from(a)) {
                *v = true;
            }
        }
        Ok((x, drops))
    }

    /// Keeps the active rows the iteration `it` ended with; the factor is
    /// valid for the next solve when it solved the QP or proved it empty.
    pub(super) fn keep(&mut self, it: &Iterate<NV>) {
        // Columns past `nact` are zero, but for the column `nact` of an add
        // that failed. (Read on hosts only, `Pending`.)
        if cfg!(not(target_os = "none")) {
            self.pending.r_cols = (it.nact + 1).min(self.R.ncols());
        }
        self.kept.act.clone_from(&it.act);
        self.kept.nact = it.nact;
        self.kept.neq = it.neq;
        self.valid = matches!(it.status, QpStatus::Solved | QpStatus::Infeasible);
    }
}

/// Whether `solver`'s solves from scratch set `J` and `R` when they first
/// need them ([`Pending`]): on hosts with the hot start (whose guess may end
/// a solve without the factor); elsewhere every solve needs it.
#[inline(always)]
fn lazy<NV: Dim, NC: Dim>(solver: &DualActiveSetOf<NV, NC>) -> bool
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    cfg!(not(target_os = "none")) && solver.hot_start_capable()
}

/// What the probes of one QP share (module docs): its row norms and the
/// factor of the last probe's active rows. Build one per QP with
/// [`ReprobeOf::new`] and pass it to every
/// [`DualActiveSetOf::solve_reprobe`] of that QP's `H` and rows `G` (`q`
/// and `h` may differ from solve to solve).
#[derive(Clone, Debug)]
pub struct ReprobeOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// Euclidean row norms of the QP and the `H^-1` norms found so far.
    norms: RowNormsOf<NC>,
    /// The factor of the last probe.
    pub(super) carry: Carry<NV>,
}

/// [`ReprobeOf`] with the sizes as constants (stack only, `no_std`).
pub type Reprobe<const NV: usize, const NC: usize> = ReprobeOf<Const<NV>, Const<NC>>;

impl<const NV: usize, const NC: usize> ReprobeOf<Const<NV>, Const<NC>> {
    /// All storage zero, nothing carried, no rows: for `const` and `static`
    /// initialisers (the controller's, set for each QP with
    /// [`ReprobeOf::restart`]).
    pub const EMPTY: Self = ReprobeOf {
        norms: RowNormsOf {
            norm2: SVector::from_array_storage(ArrayStorage([[0.0; NC]; 1])),
            inv_hnorm: SVector::from_array_storage(ArrayStorage([[0.0; NC]; 1])),
            m: 0,
            finite: false,
        },
        carry: Carry {
            J: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
            R: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
            kept: Kept {
                act: SVector::from_array_storage(ArrayStorage([[0; NV]; 1])),
                mult: SVector::from_array_storage(ArrayStorage([[0.0; NV]; 1])),
                nact: 0,
                neq: 0,
            },
            valid: false,
            pristine: false,
            pending: Pending::NONE,
            #[cfg(not(target_os = "none"))]
            guess: GuessWork::EMPTY,
        },
    };
}

impl<NV: Dim, NC: Dim> ReprobeOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The shared state of the probes of `qp`'s rows: their squared
    /// Euclidean norms, and no factor yet (the first probe starts from
    /// scratch).
    pub fn new(qp: &DenseQpOf<NV, NC>) -> Self {
        ReprobeOf {
            norms: RowNormsOf::euclidean(qp),
            carry: Carry::fresh(qp.gt.shape_generic().0),
        }
    }

    /// [`ReprobeOf::new`] with the factor already at the start from scratch
    /// of `solver`'s solves (`J = L^-T`, `R = 0`): the first probe does not
    /// set it again.
    pub fn for_solver(solver: &DualActiveSetOf<NV, NC>, qp: &DenseQpOf<NV, NC>) -> Self {
        ReprobeOf {
            norms: RowNormsOf::euclidean(qp),
            carry: Carry::scratch(solver),
        }
    }

    /// [`ReprobeOf::for_solver`] in place, for the probes of `qp`'s rows:
    /// the storage of a `state` kept from one QP to the next (the
    /// controller's, cycle to cycle) is written where it is, instead of a new
    /// one built and moved into place (the factor alone is `2 NV^2` numbers).
    /// `qp` must have the capacity `state` was built for.
    pub fn restart(&mut self, solver: &DualActiveSetOf<NV, NC>, qp: &DenseQpOf<NV, NC>) {
        self.norms.set_euclidean(qp);
        self.carry.restart(solver);
    }

    /// The rows (indices into the QP's rows) the last probe ended with
    /// active: its optimal active set, or the rows active at its Farkas
    /// certificate; empty when no probe left a factor (none ran, or the last
    /// one stopped on its budget or a numerical error).
    pub fn active(&self) -> &[u16] {
        let kept = &self.carry.kept;
        let n = if self.carry.valid { kept.nact } else { 0 };
        kept.act.as_slice().get(..n).unwrap_or(&[])
    }

    /// Forgets the factor of the last probe: the next one starts from
    /// scratch (the unconstrained minimiser), with the row norms kept.
    pub fn forget(&mut self) {
        self.carry.valid = false;
    }

    /// The Euclidean norm `|g_i|` of row `i` (0 past the rows).
    pub(crate) fn norm(&self, i: usize) -> f64 {
        // (0 past the rows: `RowNormsOf::euclidean` leaves them so.)
        self.norms
            .norm2
            .as_slice()
            .get(i)
            .map_or(0.0, |&n2| crate::linalg::sqrt(n2))
    }
}

impl<NV: Dim, NC: Dim> DualActiveSetOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// [`DualActiveSetOf::solve_selected`] (the rows `enabled` of `qp` with
    /// the right-hand side `h`, at most `budget` adds plus drops) as one of
    /// a series of probes of the same QP that share `state` (module docs):
    /// the row norms are computed once, by [`ReprobeOf::new`], and each probe
    /// after the first continues from the factor of the active rows the one
    /// before ended with. The same optimum, or the same proof of emptiness
    /// (a Farkas certificate, possibly another one), as `solve_selected`; the
    /// marks `prefer` choose among violated rows as there. `state` must
    /// have been built for this `qp`'s rows `G` (and `m`) and used only with
    /// this solver's `H`.
    /// Where the proximal iterations run (a semidefinite `H`), each probe is
    /// `solve_selected` with the shared row norms.
    pub fn solve_reprobe(
        &self,
        qp: &DenseQpOf<NV, NC>,
        h: &OVector<f64, NC>,
        enabled: &[bool],
        prefer: &[bool],
        budget: u32,
        state: &mut ReprobeOf<NV, NC>,
    ) -> QpSolutionOf<NV, NC> {
        let nc = qp.h.shape_generic().0;
        let mut excluded = OVector::<bool, NC>::from_element_generic(nc, U1, true);
        for (x, &on) in excluded.as_mut_slice().iter_mut().zip(enabled) {
            *x = !on;
        }
        let max_iter = budget.min(self.settings.max_iter);
        if self.proximal() {
            return self.solve_proximal(qp, h, excluded, &mut state.norms, (), prefer, max_iter);
        }
        self.solve_with(
            qp,
            &qp.q,
            h,
            excluded,
            &mut state.norms,
            (),
            prefer,
            max_iter,
            &mut state.carry,
        )
    }
}
