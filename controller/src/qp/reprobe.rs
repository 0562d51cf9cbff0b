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
//! factor in its own frame instead (`qp/store.rs`). The probes' entry point,
//! `DualActiveSetOf::solve_reprobe`, is `qp/solve.rs`.

use nalgebra::allocator::Allocator;
use nalgebra::{
    ArrayStorage, Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector, U1,
};

use super::dense::DenseQpOf;
#[cfg(not(target_os = "none"))]
use super::gram::GuessWork;
use super::kept::{Kept, Pending};
use super::norms::RowNormsOf;
use super::resolve::{ResolveStop, resolve};
use super::solver::DualActiveSetOf;
use super::store::{Begin, Parts, Store};
use crate::active_set::Iterate;
use crate::solution::{QpAllocator, QpStatus};

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
    pub(super) norms: RowNormsOf<NC>,
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
    fn start<NC: Dim>(&mut self, at: Begin<'_, NV, NC>) -> Result<(OVector<f64, NV>, u32), QpStatus>
    where
        DefaultAllocator: QpAllocator<NV, NC>,
    {
        Carry::start(self, at)
    }

    #[inline(always)]
    fn parts<'s>(&'s mut self, _own: &'s mut Self::Own) -> Parts<'s, NV> {
        let carry = &mut **self;
        #[cfg(not(target_os = "none"))]
        let guess = Some(&mut carry.guess);
        #[cfg(target_os = "none")]
        let guess = None;
        let Carry {
            J,
            R,
            kept,
            valid,
            pending,
            ..
        } = carry;
        let kept = if *valid { Some(&*kept) } else { None };
        (J, R, kept, guess, Some(pending))
    }

    #[inline(always)]
    fn keep(&mut self, it: Option<&Iterate<NV>>, guessed: bool) {
        match it {
            Some(it) if !guessed => Carry::keep(self, it),
            // The guess wrote nothing to `J` and `R`.
            Some(_) => self.valid = false,
            None => {
                self.valid = false;
                if cfg!(not(target_os = "none")) {
                    self.pending.r_cols = self.R.ncols();
                }
            }
        }
    }
}
