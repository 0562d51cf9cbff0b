//! The priority scheme for infeasible cycles: which rows give way, and by how
//! little.
//!
//! Rows fall in three classes ([`RowClass`]): leg **reachability** (physical: never
//! relaxed), **safety** (LDCBF and foot clearance), and **gait** (walking velocity
//! and maneuverability). A fourth bound, **capturability** (optional,
//! [`crate::Config::capture_fraction`], on by default; below), shares the gait
//! rows' left-hand sides.
//!
//! # Units
//!
//! Every relaxation is in the physical units of the relaxed rows' right-hand
//! sides, as [`crate::constraints`] builds them: a gait row `a'v_{k+1} <= b`
//! (`a` a body-frame axis of step `k`) relaxed by `eps_gait` is
//! `a'v_{k+1} <= b + eps_gait`, m/s of that velocity component, on every step of the horizon
//! alike; an LDCBF row `h(p_{k+1}) - (1 - gamma) h(p_k) >= 0` relaxed by
//! `eps_safety` is `>= -eps_safety`, m of `h` (a foot-clearance row likewise,
//! m); the capturability bound relaxed by `eps_capture` is `|a'v_{k+1}| <=
//! speed + eps_capture`, m/s. (In the decision variables the rows have norms
//! from 1 to about 13, so a relaxation per unit row norm, as before, was not in
//! these units: the 0.1 cap let a first-step velocity row give way by about
//! 0.56 m/s and a second-step one by about 1.26 m/s.) [`class_violation`]
//! measures violations in the same units.
//!
//! # Stages
//!
//! When the nominal QP is infeasible the controller solves, lexicographically:
//!
//! 1. **Gait relaxed.** Keep reachability, safety and capturability; relax
//!    every gait row by the same amount `eps_gait` (m/s), the smallest that
//!    makes the problem feasible, but at most
//!    [`crate::Config::max_gait_relaxation`]; then minimise the nominal cost
//!    under that relaxation.
//! 2. **Safety relaxed** (when stage 1 needs more than the cap): keep
//!    reachability, capturability and the gait rows relaxed by the cap; find
//!    the smallest uniform relaxation `eps_safety` (m) of the safety rows,
//!    then, with safety relaxed by exactly that, the smallest `eps_gait` (<=
//!    cap), then minimise the cost. This is the least-violating reachable step
//!    in the sense of the largest LDCBF violation.
//! 3. **Gait unbounded** (only when reachability, capturability and the capped
//!    gait rows alone conflict, i.e. the robot already moves faster than the
//!    capped limits): as stage 2 with no cap on the gait rows, which then give
//!    way up to the capturability bound.
//! 4. **Capturability relaxed** (bound on, and reachability alone cannot meet
//!    it: the robot already moves too fast to keep within it): the smallest
//!    uniform relaxation `eps_capture` (m/s) of the bound with reachability
//!    alone, then as stage 3 under the bound relaxed by that. Reported in
//!    [`Relaxed::eps_capture`] and `CycleInfo::relax_capture`: never silent.
//!
//! So the priority order, most important first: reachability, capturability,
//! gait up to the cap, safety, gait beyond the cap. Within the safety class,
//! on a cycle that gives way to a person the rows of obstacles at rest come
//! before the rows of moving ones, and the rows outside the conflict come
//! before the rows in it (both below).
//!
//! # Rows outside the conflict
//!
//! The least uniform relaxation `eps_safety` is proven by a Farkas
//! certificate; the safety rows it weighs are in conflict (say a wall
//! fragment ahead against reachability and the gait rows), and so are those
//! the cycle's earlier certificates weighed (the nominal solve's, each
//! infeasible probe's): the conflict starts as all of them. Relaxing every
//! safety row by `eps_safety` would also let the plan use that much of the
//! margin of rows that take no part in it (a side wall), and the cost's pull
//! towards the goal does. So, once `eps_safety` is known, the scheme wants
//! the optimal plan of the same problem with only the conflict's safety rows
//! at `h + eps_safety` and every other safety row at its nominal `h`. When
//! the uniform relaxation's plan already keeps every row outside the
//! conflict, that is it, with no solve (the confined feasible set lies in
//! the uniform one and holds that plan). Otherwise it is solved; an
//! infeasible solve's certificate must weigh a safety row outside the
//! conflict (otherwise it would prove the uniform relaxation empty too), so
//! its safety rows join the conflict and the check and the solve are
//! repeated: the conflict only grows, and in the worst case it becomes every
//! safety row, the uniform relaxation. The
//! relaxation stays the least (relaxing fewer rows by the same amount is a
//! smaller feasible set, and the uniform one was already the least), the
//! gait search that follows runs under the confined relaxation, and the
//! rows that took it are reported ([`Relaxed::conflict`]). These
//! solves draw on the scheme's probes; when the probes run out (or a
//! certificate adds no row, which only rounding can do) the uniform plan
//! stands. Stage 1 relaxes no safety row and is unchanged; no solve is added
//! to a feasible cycle.
//!
//! # Moving rows first
//!
//! A wall does not move out of the way; a person can. On a cycle that gives
//! way to a person (`Params::give_way`: a moving obstacle's safety row in
//! the nominal certificate) whose QP also holds safety rows of obstacles at
//! rest, each of stages 2 to 4 first searches for the least uniform
//! relaxation of the moving obstacles' safety rows alone
//! (`Params::moving`; at most 1 m of `h`), with every static safety row
//! kept at its nominal right-hand side, as the confinement above keeps the
//! rows outside the conflict (a certificate of that search counts the static
//! rows in `y'h` only). When that is feasible its plan stands, and the
//! moving rows are the rows reported in [`Relaxed::conflict`]; only when a
//! certificate proves it infeasible (the walls take part in the conflict:
//! the robot cannot keep their full margin whatever the people's rows allow)
//! does the stage relax every safety row as above, starting from that
//! certificate with the static rows counted as relaxed. The search draws on
//! the scheme's probes, so the bound on solves per cycle is unchanged. The
//! relaxation of the moving rows can exceed the uniform one (fewer rows give
//! way): the robot keeps the wall's margin and the person, who can, steps
//! aside or walks into a robot that is giving way. Cycles without a moving
//! obstacle in the conflict, or without a static safety row, are unchanged.
//!
//! Why the cap: the gait rows bound the CoM velocity at the end of each step,
//! which is what keeps the pendulum capturable with steps inside the
//! reachability box. Relaxing them without bound let cycles that keep meeting
//! an infeasible LDCBF (an obstacle appearing from behind another under LiDAR)
//! speed the robot up, cycle after cycle, past about 0.96 m/s, where no
//! reachable step can stop it, and it fell. With the cap (0.1 m/s by default,
//! so at most 0.9 m/s forward) the safety rows give way first, by the least
//! amount.
//!
//! # Capturability
//!
//! Per body axis, with the heading fixed, the step map of
//! [`crate::constraints`] gives `v_{k+1} = cosh(beta T) v_k - beta sinh(beta
//! T) d_k` for the foot offset `d_k = f_k - p_k`, `|d_k| <= l_max` (leg
//! reachability). The best step against `v_k > 0` (`d_k = l_max`) slows the
//! robot iff `v_k < |kappa| l_max` with `|kappa| = beta sinh(beta T) /
//! (cosh(beta T) - 1) = beta coth(beta T / 2)`; from any `|v_k| < |kappa|
//! l_max` the robot can stop in finitely many steps within reach (N-step
//! capturability of the LIP with reach `l_max` and step time `T`, as in
//! Koolen et al., IJRR 2012), from any faster state it cannot and falls.
//! For Table I (`beta = 3.13 /s`, `T = 0.4 s`, `l_max = 0.173 m`) the limit
//! is `|kappa| l_max = 5.64 x 0.173 = 0.976 m/s`. The bound keeps every
//! body-frame component of every predicted `v_{k+1}` within `speed =
//! capture_fraction |kappa| l_max` (default 0.92: 0.898 m/s, just below the
//! capped forward gait `vx_max + 0.1 = 0.9 m/s`, leaving 8 % for turns, which
//! rotate the body frame by up to `omega_max T = 0.2 rad` per step, and for
//! model error). The nominal gait rows of Table I imply it (0.8 and 0.4 m/s),
//! so it changes nothing on cycles that meet them; it binds only when the gait
//! rows give way. Each of its rows has the left-hand side of one gait velocity
//! row, so it is applied as a per-row ceiling on that row's relaxation
//! (`h + min(eps_gait, headroom + eps_capture)`, headroom = `speed` minus the
//! row's nominal bound, at least 0) rather than as extra rows: the QP keeps
//! its size.
//!
//! Reachability alone is always feasible (each `f_k` may sit at `p_k`), so
//! stage 4 (and, without the bound, stage 3) always has an answer up to
//! numerical failure or budget exhaustion.
//!
//! # Finding the smallest relaxation
//!
//! Each smallest uniform relaxation is the optimal value of a linear program
//! (minimise `t` subject to the soft rows at `h + t` and the others as
//! fixed), whose dual is: maximise `-y'h` over Farkas certificates `y >= 0`,
//! `G'y = 0`, normalised by `y'|g|_soft = 1`. The dual active-set solver
//! returns such a certificate with every infeasible solve, and one certificate
//! holds for every relaxation of the same rows: with the gait rows at `e_g`
//! and the safety rows at `e_s`, `y'h + e_g sum_gait y + e_s sum_safety y < 0`
//! proves the relaxed problem empty (a gait row at its capturability ceiling
//! counts with its headroom in `y'h` and towards `e_c`; the linear form is
//! never below the true `y'h(e)`, so the proof stays valid). So each search
//! runs from below:
//!
//! * the last certificate gives a lower bound `b` on `t` (in the first search
//!   the nominal solve's, which the controller hands over; without one the
//!   first probe is the unrelaxed problem itself);
//! * the next solve goes just above the bound, at `b (1 + 1e-9) + 1e-9`; the
//!   first feasible solve ends the search with the optimal plan under that
//!   relaxation; an infeasible one brings a new certificate and a higher
//!   bound;
//! * a bound that proves every `t` (up to the cap) infeasible ends the stage
//!   without a solve: stage 2 starts from the certificate stage 1 ended with,
//!   and its gait search from the one its safety search ended with, which
//!   usually proves at once that less than the cap is infeasible.
//!
//! Every probe solves the same rows `G` with the same Hessian (and, within
//! one run, the same `q`); only the right-hand sides and which classes are
//! left out change. So the probes share one [`Reprobe`]
//! ([`QpBackend::solve_reprobe`], `qp/reprobe.rs`): the row norms are
//! computed once per cycle, and each probe continues from the factor of the
//! active rows the solve before it ended with (the nominal solve's, for the
//! first), as DAQP's parametric hot start: the minimiser on those rows for
//! the new right-hand sides, the rows with negative multipliers (and those
//! the probe leaves out) dropped, then the dual iteration as usual. A probe
//! whose bound moved a little takes 0 to 3 iterations instead of rebuilding
//! its active set from the unconstrained minimiser; the optimum is the same,
//! the rounding and which certificate an infeasible probe returns may
//! differ. On a cycle that gives way to a person (`Params::give_way`) the
//! cost is another one than the nominal solve's, whose active rows are then
//! a poor start: the first probe starts from scratch, adding the marked rows
//! (the warm start: the rows active at the last cycle's relaxed plan) first
//! among those it finds violated (`docs/fallback.md`).
//!
//! On the firmware's recorded infeasible cycles (all stage 1) this is two
//! solves per cycle, the nominal one included: the nominal certificate proves
//! the bound, and the solve just above it is feasible; see
//! `docs/fallback.md`.
//!
//! Tolerance: a reported `eps` is at most `b (1 + 1e-9) + 1e-9`, `b` the lower
//! bound its certificate proves (up to rounding in `y'h`). At a degenerate
//! minimum, where the relaxed feasible set is a single point that rounding can
//! declare empty, a probe at the padded bound can come back infeasible with no
//! higher bound: the padding then grows a hundredfold per probe. A search
//! makes at most [`crate::Config::relax_bisections`] probes (the name is
//! historical: it now counts probes, not halvings) and the whole scheme at
//! most twice that many; a search that runs out solves the most relaxed
//! problem once more and reports that plan with its own violation (feasible,
//! not minimal). Stage 3 with the capturability bound on starts with one
//! solve of reachability and the bound alone (counted as a probe): infeasible,
//! it goes to stage 4 with that certificate; feasible, its plan bounds stage
//! 3's safety search from above. So one infeasible cycle makes at most `2
//! relax_bisections + 6` solves after the nominal one (six searches at most:
//! stage 1, the safety searches of stages 2, 3 and 4, the capturability
//! search of stage 4, one gait search), each drawing on the cycle's
//! iteration budget ([`crate::Config::max_iter_cycle`]); if that runs out the
//! controller falls back to the previous plan or the capture step.
//!
//! # Files
//!
//! * `rows`: the row classes, their violation, the capturability bound and
//!   the rows a relaxed problem keeps;
//! * `search`: the certificate-driven search for one smallest relaxation;
//! * `confine`: the safety relaxation confined to the rows in conflict, and
//!   to the moving obstacles' rows first;
//! * this file: the stages, in priority order, and their results.

mod confine;
mod rows;
mod search;
#[cfg(test)]
mod tests;

pub use rows::{CaptureBounds, ClassViolation, RowClass, class_violation};

use nalgebra::SVector;

use crate::constraints::RowId;
use crate::qp::{DenseQp, DualActiveSet, QpBackend, Reprobe};
use rows::{Keep, Soft};
use search::{Ctx, Probe};

/// Which stage produced the relaxed plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RelaxLevel {
    /// Stage 1: gait rows relaxed, safety and reachability kept.
    Gait,
    /// Stage 2: safety (and gait) rows relaxed, reachability kept.
    Safety,
}

/// A relaxed plan.
#[derive(Clone, Copy, Debug)]
pub struct Relaxed<const NV: usize, const NC: usize> {
    /// Footsteps.
    pub u: SVector<f64, NV>,
    /// Stage that produced it.
    pub level: RelaxLevel,
    /// Uniform relaxation of the gait rows, m/s (0 if none was needed).
    pub eps_gait: f64,
    /// Uniform relaxation of the safety rows, m of `h` (0 at stage 1).
    pub eps_safety: f64,
    /// The safety rows relaxed by `eps_safety` (the rows in conflict, by row
    /// of the nominal QP); every other safety row keeps its nominal
    /// right-hand side. None when `eps_safety` is 0.
    pub conflict: [bool; NC],
    /// Uniform relaxation of the capturability bound, m/s (0 unless stage 4).
    pub eps_capture: f64,
    /// Solver iterations spent.
    pub iterations: u32,
}

/// A failed relaxation: why, and the solver iterations it spent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RelaxError {
    /// Why it gave up.
    pub kind: RelaxFailure,
    /// Solver iterations spent before giving up.
    pub iterations: u32,
}

/// Why the relaxation gave up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RelaxFailure {
    /// The per-cycle iteration budget ran out.
    Budget,
    /// A solve reported a numerical error.
    Numerical,
}

/// What one run of the priority scheme may spend and relax, and what it
/// starts from (the arguments of [`relax`] besides the problem).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Params<'a, const NC: usize> {
    /// Solver iterations of one solve at most.
    pub max_iter: u32,
    /// Solver iterations left in this cycle.
    pub budget: u32,
    /// The largest number of solves of one search for a smallest relaxation
    /// (the scheme makes at most `2 probes + 6` solves after the nominal one,
    /// see the module docs).
    pub probes: u32,
    /// The largest relaxation of the gait rows (m/s) allowed before the
    /// safety rows give way.
    pub gait_cap: f64,
    /// The capturability bound (`None`: off).
    pub capture: Option<CaptureBounds>,
    /// A Farkas certificate of the nominal QP (one weight per row of `qp`, as
    /// [`crate::qp::QpSolution::lambda`] of its infeasible solve), used as the
    /// first search's starting certificate when it proves the nominal QP
    /// empty (`y'h < 0`); it spares the first probe.
    pub certificate: Option<&'a SVector<f64, NC>>,
    /// A person in the conflict (docs/safety.md "The policy toward people"):
    /// after a safety relaxation, no search for the least gait relaxation
    /// under it; the plan of the safety search (feasible with the gait rows
    /// at the cap, or at its own gait violation in stages 3 and 4) stands,
    /// and that is the reported `eps_gait`. It saves that search's solves
    /// (one to three) on the cycles where a person walks into the robot; the
    /// cost, which then pulls away from the person, chooses the plan.
    /// `Some(marks)`: the first probe starts from scratch (the give-way goal
    /// changed the cost, so the nominal solve's factor is a poor start),
    /// adding the rows `marks` first (the warm start: the rows active at the
    /// last cycle's relaxed plan).
    pub give_way: Option<&'a [bool; NC]>,
    /// The safety rows of moving obstacles (by row of the nominal QP; see
    /// "Moving rows first" in the module docs). Used only with `give_way`:
    /// then, in stages 2 to 4, these rows give way before the static ones.
    /// `None`, or no static safety row in `qp`: every safety row alike.
    pub moving: Option<&'a [bool; NC]>,
}

/// Runs the priority scheme on the nominal QP `qp` (rows identified by `rows`;
/// each probe solves a selection of its rows in place, with no copy), within
/// the limits of `p`. The probes share `reprobe`
/// ([`QpBackend::solve_reprobe`]: the row norms, and the factor of the
/// active rows each probe continues from): the state of the nominal solve
/// of `qp`'s rows (whose factor the first probe continues from), or a new
/// one.
pub(crate) fn relax<const NV: usize, const NC: usize, B: QpBackend<NV, NC>>(
    solver: &DualActiveSet<NV, NC>,
    backend: &mut B,
    qp: &DenseQp<NV, NC>,
    rows: &[RowId; NC],
    p: Params<'_, NC>,
    reprobe: &mut Reprobe<NV, NC>,
) -> Result<Relaxed<NV, NC>, RelaxError> {
    let Params {
        max_iter,
        budget,
        probes,
        gait_cap,
        capture,
        certificate,
        give_way,
        moving,
    } = p;
    let mut ctx = Ctx {
        solver,
        backend,
        qp,
        rows,
        max_iter,
        budget,
        used: 0,
        probes,
        probes_left: probes.saturating_mul(2),
        cert: None,
        support: [false; NC],
        conflict: [false; NC],
        confined: false,
        capture,
        reprobe,
        prefer: give_way.unwrap_or(&[false; NC]),
    };
    if let Some(y) = certificate {
        // The nominal QP is the first probe's problem (stage 1 at no
        // relaxation).
        let nominal = Keep {
            safety: Some(0.0),
            gait: Some(0.0),
            capture: capture.map(|_| 0.0),
        };
        ctx.take_certificate(y, nominal);
        if !ctx.cert.is_some_and(|c| c.yh < 0.0) {
            ctx.cert = None;
            ctx.support = [false; NC];
        }
    }
    if give_way.is_some() {
        // The give-way goal changed the cost: the factor of the nominal
        // solve's active rows is a poor start (docs/fallback.md).
        ctx.reprobe.forget();
    }
    let moving = if give_way.is_some() { moving } else { None };
    let out = run_stages(&mut ctx, gait_cap, give_way.is_some(), moving);
    out.map_err(|kind| RelaxError {
        kind,
        iterations: ctx.used,
    })
}

/// The safety rows of `qp` (all of them take a uniform relaxation).
fn safety_rows<const NV: usize, const NC: usize>(
    qp: &DenseQp<NV, NC>,
    rows: &[RowId; NC],
) -> [bool; NC] {
    let mut out = [false; NC];
    for (o, id) in out.iter_mut().zip(rows).take(qp.m) {
        *o = RowClass::of(id.kind) == RowClass::Safety;
    }
    out
}

/// The stages of the scheme (see the module docs).
fn run_stages<const NV: usize, const NC: usize, B: QpBackend<NV, NC>>(
    ctx: &mut Ctx<'_, NV, NC, B>,
    gait_cap: f64,
    give_way: bool,
    moving: Option<&[bool; NC]>,
) -> Result<Relaxed<NV, NC>, RelaxFailure> {
    // The capturability bound, when on, is kept through stages 1-3.
    let capture0 = ctx.capture.map(|_| 0.0);
    // Stage 1: reachability, safety and capturability hard, gait soft up to the cap.
    let safe = Keep {
        safety: Some(0.0),
        gait: None,
        capture: capture0,
    };
    if let Some((u, eps)) = ctx.minimal(safe, Soft::Gait, gait_cap, None)? {
        return Ok(Relaxed {
            u,
            level: RelaxLevel::Gait,
            eps_gait: eps,
            eps_safety: 0.0,
            conflict: [false; NC],
            eps_capture: 0.0,
            iterations: ctx.used,
        });
    }
    // Stage 2: reachability and the capped gait rows hard, safety soft; then, with
    // safety relaxed by exactly that much, the least gait relaxation (<= cap).
    // Stage 3, when even reachability and the capped gait rows conflict (the
    // robot already moves faster than the capped limits allow): the same with
    // the gait rows unbounded (but under the capturability bound, when on).
    // Stage 4 (capturability on, and reachability and the bound conflict: the
    // robot is already too fast to stay within it): first the least uniform
    // relaxation of the capturability bound, then as stage 3 under it.
    for stage in 2..=4u8 {
        let cap = if stage == 2 { gait_cap } else { f64::INFINITY };
        let mut capture = capture0;
        let mut known_s = None;
        if stage == 3 && ctx.capture.is_some() && ctx.probes_left > 0 {
            // One solve tells whether reachability and the capturability bound
            // alone are feasible: if not, stage 4 (with this certificate); if
            // so, the plan bounds stage 3's safety search from above.
            let free = Keep {
                safety: None,
                gait: None,
                capture: Some(0.0),
            };
            ctx.probes_left -= 1;
            match ctx.solve(free)? {
                Probe::Feasible(u) => {
                    known_s = Some((ctx.violation(Soft::Safety, &u).max(0.0), u));
                }
                Probe::Infeasible => continue,
            }
        }
        if stage == 4 {
            if ctx.capture.is_none() {
                break;
            }
            let free = Keep {
                safety: None,
                gait: None,
                capture: None,
            };
            let Some((u_c, eps_c)) = ctx.minimal(free, Soft::Capture, f64::INFINITY, None)? else {
                break;
            };
            capture = Some(eps_c);
            known_s = Some((ctx.violation(Soft::Safety, &u_c).max(0.0), u_c));
        }
        let reach = Keep {
            safety: None,
            gait: if cap.is_finite() { Some(cap) } else { None },
            capture,
        };
        // A person moves out of the way, a wall does not: the moving rows
        // first, every static safety row at its full margin.
        let first = match moving {
            Some(mv) => ctx.moving_first(reach, mv)?,
            None => None,
        };
        let (u_s, eps_s, conflict) = match first {
            Some((u, eps, rows)) => (u, eps, Some(rows)),
            None => {
                let Some((u, eps)) = ctx.minimal(reach, Soft::Safety, f64::INFINITY, known_s)?
                else {
                    continue;
                };
                (u, eps, None)
            }
        };
        // Only the rows in conflict give way; the others keep their margin.
        let (u_s, conflict) = if let Some(rows) = conflict {
            (u_s, rows)
        } else if eps_s > 0.0 {
            match ctx.confine(reach.with(Soft::Safety, eps_s), &u_s)? {
                Some(u) => (u, ctx.conflict),
                None => (u_s, safety_rows(ctx.qp, ctx.rows)),
            }
        } else {
            (u_s, [false; NC])
        };
        let fixed = Keep {
            safety: Some(eps_s),
            gait: None,
            capture,
        };
        // The plan just found is feasible with the gait rows at the cap (or
        // without them: then at its own gait violation).
        let known = if cap.is_finite() {
            cap
        } else {
            ctx.violation(Soft::Gait, &u_s).max(0.0)
        };
        let (u, eps_g) = if give_way {
            (u_s, known)
        } else {
            ctx.minimal(fixed, Soft::Gait, cap, Some((known, u_s)))?
                .ok_or(RelaxFailure::Numerical)?
        };
        // Without any safety relaxation this is still a gait relaxation (beyond
        // the cap: the robot moves too fast already).
        let level = if eps_s > 0.0 {
            RelaxLevel::Safety
        } else {
            RelaxLevel::Gait
        };
        return Ok(Relaxed {
            u,
            level,
            eps_gait: eps_g,
            eps_safety: eps_s,
            conflict,
            eps_capture: capture.unwrap_or(0.0),
            iterations: ctx.used,
        });
    }
    // Reachability alone is always feasible: only numerics get here.
    Err(RelaxFailure::Numerical)
}
