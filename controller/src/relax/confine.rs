//! Confining a safety relaxation to some of the safety rows: to the rows in
//! conflict (see "Rows outside the conflict" in the module docs of
//! [`crate::relax`]), and to the rows of moving obstacles first ("Moving rows
//! first").

use nalgebra::SVector;

use super::RelaxFailure;
use super::rows::{Keep, RowClass, Soft};
use super::search::{Ctx, Probe};
use crate::linalg::{columns, dot};
use crate::qp::QpBackend;

impl<const NV: usize, const NC: usize, B: QpBackend<NV, NC>> Ctx<'_, NV, NC, B> {
    /// Adds the safety rows that a certificate of this cycle weighed
    /// ([`Ctx::support`]) to the conflict; the number added.
    fn grow_conflict(&mut self) -> u32 {
        let mut added = 0u32;
        for ((c, &s), id) in self
            .conflict
            .iter_mut()
            .zip(&self.support)
            .zip(self.rows)
            .take(self.qp.m)
        {
            if s && !*c && RowClass::of(id.kind) == RowClass::Safety {
                *c = true;
                added += 1;
            }
        }
        added
    }

    /// Whether the plan `u` keeps every safety row outside the conflict at
    /// its nominal right-hand side, to the solver's tolerance (`g'u - h <=
    /// tol_primal |g|`, the test of its scan).
    fn keeps_outside(&self, u: &SVector<f64, NV>) -> bool {
        let tol = self.solver.settings().tol_primal;
        columns(self.qp.gt.as_slice(), NV)
            .zip(self.qp.h.as_slice())
            .zip(self.rows)
            .zip(&self.conflict)
            .enumerate()
            .take(self.qp.m)
            .all(|(i, (((g, &h), id), &c))| {
                c || RowClass::of(id.kind) != RowClass::Safety
                    || dot(g, u.as_slice()) - h <= tol * self.reprobe.norm(i)
            })
    }

    /// With `keep` (its safety relaxation the least uniform one, feasible),
    /// the optimal plan when only the safety rows in conflict take that
    /// relaxation and every other safety row keeps its nominal right-hand
    /// side (the conflict is left in `self.conflict`). The conflict starts as the safety
    /// rows that the cycle's certificates weighed (the nominal solve's and
    /// each infeasible probe's, among them the one that proved the relaxation
    /// minimal) and grows by the safety rows of each infeasible probe's
    /// certificate; each probe draws on the scheme's probes. No probe is
    /// needed when `uniform`, the optimal plan under the uniform relaxation,
    /// already keeps every safety row outside the conflict at its nominal
    /// right-hand side: the confined problem's feasible set lies in the
    /// uniform one's and holds that plan, so it is the confined optimum too,
    /// and it is returned as it is. `Ok(None)` (the uniform relaxation
    /// stands, and the confinement is off again) when the probes run out or
    /// a certificate adds no row (rounding).
    ///
    /// On success the confinement stays on (for the gait search that follows
    /// under the same safety relaxation), and the last certificate stays valid
    /// for it: its safety rows are all in the conflict.
    pub(super) fn confine(
        &mut self,
        keep: Keep,
        uniform: &SVector<f64, NV>,
    ) -> Result<Option<SVector<f64, NV>>, RelaxFailure> {
        self.conflict = [false; NC];
        self.grow_conflict();
        self.confined = true;
        while self.probes_left > 0 {
            if self.keeps_outside(uniform) {
                return Ok(Some(*uniform));
            }
            self.probes_left -= 1;
            match self.solve(keep)? {
                Probe::Feasible(u) => return Ok(Some(u)),
                Probe::Infeasible => {
                    if self.grow_conflict() == 0 {
                        break;
                    }
                    self.cert = self.cert.map(|c| c.with_conflict_grown());
                }
            }
        }
        // A certificate found under the confinement undercounts the
        // relaxation of the rows outside the conflict: not valid without it.
        self.confined = false;
        self.cert = None;
        Ok(None)
    }

    /// With `reach` kept (the safety rows left to this search), the least
    /// uniform relaxation of the safety rows of moving obstacles (`moving`,
    /// by row of the nominal QP) alone, every static safety row at its
    /// nominal right-hand side, at most [`MOVING_CAP`]; its optimal plan and
    /// the rows that took it (none when it is 0). `Ok(None)` (nothing
    /// spent but probes; the uniform relaxation of every safety row
    /// follows) when the QP has no static or no moving safety row, or no
    /// such relaxation up to the cap is feasible (the static rows take part
    /// in the conflict).
    pub(super) fn moving_first(
        &mut self,
        reach: Keep,
        moving: &[bool; NC],
    ) -> Result<Option<Yielded<NV, NC>>, RelaxFailure> {
        let mut rows = [false; NC];
        let mut fixed = false;
        for ((r, &m), id) in rows.iter_mut().zip(moving).zip(self.rows).take(self.qp.m) {
            if RowClass::of(id.kind) == RowClass::Safety {
                *r = m;
                fixed |= !m;
            }
        }
        if !fixed || !rows.contains(&true) {
            return Ok(None);
        }
        // (A certificate of the unconfined problem stays a valid, if weaker,
        // bound here: it counts the static rows as relaxed too.)
        self.conflict = rows;
        self.confined = true;
        // (Out of probes, `minimal` reports the plan at the cap with its own
        // violation: feasible with every static row kept, not the least.)
        let out = self
            .minimal(reach, Soft::Safety, MOVING_CAP, None)?
            .map(|(u, eps)| (u, eps, if eps > 0.0 { rows } else { [false; NC] }));
        self.confined = false;
        self.conflict = [false; NC];
        if out.is_none() {
            // The last certificate, found under the confinement, counts the
            // static rows in `y'h` only: with every safety row relaxed they
            // take the relaxation too.
            self.cert = self.cert.map(|c| c.with_conflict_grown());
        }
        Ok(out)
    }
}

/// A plan with the moving obstacles' rows relaxed first: the plan, the
/// relaxation (m of `h`) and the rows that took it.
pub(super) type Yielded<const NV: usize, const NC: usize> = (SVector<f64, NV>, f64, [bool; NC]);

/// The largest relaxation of the moving obstacles' safety rows alone, m of
/// `h` ([`Ctx::moving_first`]): beyond it the static rows give way too. A
/// person who overlaps the robot's body by a whole metre is past any plan.
pub(super) const MOVING_CAP: f64 = 1.0;
