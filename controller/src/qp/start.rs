//! The checks every solve starts with (`solve_start!`), shared by
//! `DualActiveSetOf::solve_with` (`qp/dual.rs`) and the proximal
//! iterations (`qp/proximal.rs`).

/// The checks every solve starts with, written once for
/// `DualActiveSetOf::solve_with` and the proximal iterations
/// (`qp/proximal.rs`): binds the names after `=>` (the variables and row
/// capacity as dimensions, the rows used, the linear term as a slice, the
/// primal tolerance, the equality rows at the head, 0 where they are not
/// compiled in, and the rows blocked from the start: `excluded` and the zero
/// equality rows), or returns the answer from the enclosing function when
/// the solve ends there (sizes, a non-finite `q`, `h` or row, an equality
/// row where they are not compiled in, a zero row that contradicts itself).
/// A macro, not a function: the static instances compile exactly as with the
/// checks written out in place.
macro_rules! solve_start {
    ($s:ident, $qp:ident, $qv:expr, $hv:ident, $excluded:ident, $norms:ident =>
     $nv:ident, $nc:ident, $m:ident, $q:ident, $tol:ident, $me:ident, $blocked:ident) => {
        let $nv = $s.nv();
        let n = $nv.value();
        let $nc = $qp.h.shape_generic().0;
        let $m = $qp.m.min($nc.value());
        let $q = $qv.as_slice();
        let (h, norm2) = ($hv.as_slice(), $norms.norm2.as_slice());
        if h.len() != $nc.value()
            || norm2.len() != $nc.value()
            || $norms.inv_hnorm.len() != $nc.value()
        {
            return $crate::active_set::stopped(
                $nv,
                $nc,
                $crate::solution::QpStatus::NumericalError,
            );
        }
        if !$norms.finite
            || $qp.gt.nrows() != n
            || $q.len() != n
            || !$q.iter().all(|v| v.is_finite())
            || !h
                .iter()
                .zip($excluded.as_slice().iter())
                .take($m)
                .all(|(v, &out)| out || v.is_finite())
        {
            return $crate::active_set::stopped(
                $nv,
                $nc,
                $crate::solution::QpStatus::NumericalError,
            );
        }
        let $tol = $s.settings.tol_primal;
        // Equality rows only where they are compiled in (module docs): for
        // the small static sizes `me` is the constant 0 from here on.
        let capable = $s.equalities_capable();
        if !capable && $qp.me > 0 {
            return $crate::active_set::stopped(
                $nv,
                $nc,
                $crate::solution::QpStatus::NumericalError,
            );
        }
        let $me = if capable { $qp.me.min($m) } else { 0 };
        let zero_infeasible = h
            .iter()
            .zip(norm2.iter())
            .zip($excluded.as_slice().iter())
            .take($m)
            .enumerate()
            .position(|(i, ((&hi, &n2), &out))| {
                !out && n2 <= $crate::qp::settings::ZERO_ROW2
                    && $crate::active_set::zero_row_contradicts(hi, $tol, i < $me)
            });
        if let Some(i) = zero_infeasible {
            // Nothing satisfies it: y = e_i (or -e_i) certifies it.
            let hi = h.get(i).copied().unwrap_or(0.0);
            return $crate::active_set::zero_row_infeasible($nv, $nc, i, hi);
        }
        let mut $blocked = $excluded;
        // Zero rows are never added (an equality zero row holds here).
        for (b, &n2) in $blocked
            .as_mut_slice()
            .iter_mut()
            .zip(norm2.iter())
            .take($me)
        {
            if n2 <= $crate::qp::settings::ZERO_ROW2 {
                *b = true;
            }
        }
    };
}
