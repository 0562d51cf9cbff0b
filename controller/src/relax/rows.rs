//! The rows of the priority scheme: their classes ([`RowClass`]), their
//! violation by a plan in physical units ([`class_violation`]), the
//! capturability bound on the gait velocity rows ([`CaptureBounds`]), and
//! which rows a relaxed problem keeps with which right-hand sides (`Keep`).

use nalgebra::{SVector, SVectorView};

use crate::constraints::{RowId, RowKind};
use crate::linalg::columns;
use crate::qp::DenseQp;

/// Priority class of a row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowClass {
    /// Leg reachability: never relaxed.
    Reach,
    /// LDCBF and foot clearance.
    Safety,
    /// Walking velocity and maneuverability.
    Gait,
}

impl RowClass {
    /// The class of a row kind.
    pub fn of(kind: RowKind) -> RowClass {
        match kind {
            RowKind::ReachLonUpper
            | RowKind::ReachLonLower
            | RowKind::ReachLatUpper
            | RowKind::ReachLatLower => RowClass::Reach,
            RowKind::Ldcbf(_) | RowKind::FootClearance(_) => RowClass::Safety,
            RowKind::VelLonUpper
            | RowKind::VelLonLower
            | RowKind::VelLatUpper
            | RowKind::VelLatLower => RowClass::Gait,
        }
    }
}

/// Largest violation of each row class by a plan, in the rows' physical units
/// (the units of their right-hand sides: m/s of a body-frame velocity component
/// for gait rows, m for reachability rows, m of `h` for LDCBF and foot-clearance
/// rows); 0 when the class holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassViolation {
    /// Leg reachability rows.
    pub reach: f64,
    /// LDCBF and foot-clearance rows.
    pub safety: f64,
    /// Walking velocity and maneuverability rows.
    pub gait: f64,
}

impl ClassViolation {
    /// The violation of one class.
    pub fn of(&self, class: RowClass) -> f64 {
        match class {
            RowClass::Reach => self.reach,
            RowClass::Safety => self.safety,
            RowClass::Gait => self.gait,
        }
    }

    /// The largest over all classes.
    pub fn max(&self) -> f64 {
        self.reach.max(self.safety).max(self.gait)
    }
}

/// Measures [`ClassViolation`] of the plan `u` on `qp` (rows identified by `rows`).
/// A non-finite plan gets infinite violations.
// One out-of-line copy (it has five callers; inlined, each costs flash on the
// Cortex-M7 for no measurable time).
#[inline(never)]
pub fn class_violation<const NV: usize, const NC: usize>(
    qp: &DenseQp<NV, NC>,
    rows: &[RowId; NC],
    u: &SVector<f64, NV>,
) -> ClassViolation {
    let mut v = ClassViolation {
        reach: 0.0,
        safety: 0.0,
        gait: 0.0,
    };
    let m = qp.m.min(NC);
    let rows_g = columns(qp.gt.as_slice(), NV);
    for ((g, &h), id) in rows_g.zip(qp.h.as_slice()).zip(rows).take(m) {
        // nalgebra's `dot` on a view of the row in place (no copy of each
        // row, as `DenseQp::rows` makes): the bits of `g.dot(u)`.
        let e = SVectorView::<f64, NV>::from_slice(g).dot(u) - h;
        let e = if e.is_nan() { f64::INFINITY } else { e };
        let slot = match RowClass::of(id.kind) {
            RowClass::Reach => &mut v.reach,
            RowClass::Safety => &mut v.safety,
            RowClass::Gait => &mut v.gait,
        };
        // A zero row (|g| = 0, i.e. |g|^2 = 0: no entry with a nonzero
        // square) constrains nothing; no square root needed to tell, and no
        // test at all unless the row would raise the class's violation.
        if e > *slot && g.iter().any(|&x| x * x != 0.0) {
            *slot = e;
        }
    }
    v
}

/// The capturability bound (see the module docs): every body-frame component
/// of every predicted end-of-step velocity `v_{k+1}` within `+-speed`. It
/// shares its left-hand sides with the gait velocity rows, so it is applied as
/// a per-row ceiling on their relaxation rather than as extra rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaptureBounds {
    /// Largest capturable velocity component, m/s (body frame of step `k`).
    pub speed: f64,
    /// `speed` minus the nominal bound of each gait row, m/s, clamped at 0
    /// (the capturability bound never tightens a nominal row), in the order
    /// `VelLonUpper, VelLonLower, VelLatUpper, VelLatLower`.
    pub headroom: [f64; 4],
}

impl CaptureBounds {
    /// The bound of `cfg` (`None` when [`crate::Config::capture_fraction`] is
    /// off): `speed = fraction |kappa| l_max` with `kappa` (1/s) of the step
    /// map (`|kappa| = beta coth(beta T / 2)`), and `omega_bar` (rad/s) the
    /// cycle's turning rate (it lowers the `VelLonUpper` row's nominal bound).
    pub fn new(cfg: &crate::Config, kappa: f64, omega_bar: f64) -> Option<CaptureBounds> {
        let speed = cfg.capture_fraction? * kappa.abs() * cfg.l_max;
        let lon_upper = cfg
            .vx_max
            .min(cfg.vx_max - cfg.alpha / core::f64::consts::PI * omega_bar.abs());
        let room = |b: f64| (speed - b).max(0.0);
        let cb = CaptureBounds {
            speed,
            headroom: [
                room(lon_upper),
                room(-cfg.vx_min),
                room(cfg.vy_max),
                room(-cfg.vy_min),
            ],
        };
        cb.headroom.iter().all(|h| h.is_finite()).then_some(cb)
    }

    /// The headroom of a row of kind `kind` (`None`: not a velocity row).
    pub(super) fn of(&self, kind: RowKind) -> Option<f64> {
        let i = match kind {
            RowKind::VelLonUpper => 0,
            RowKind::VelLonLower => 1,
            RowKind::VelLatUpper => 2,
            RowKind::VelLatLower => 3,
            _ => return None,
        };
        self.headroom.get(i).copied()
    }
}

/// What a search relaxes: one of the row classes, or the capturability bound
/// (which acts on the gait rows).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Soft {
    Safety,
    Gait,
    Capture,
}

/// Which rows a relaxed problem keeps, and by how much each class is relaxed
/// (`None`: the class is left out). A gait row's right-hand side is `h +
/// min(gait, headroom + capture)` (each term only when present; the row is
/// left out when neither is).
#[derive(Clone, Copy, Debug)]
pub(super) struct Keep {
    pub(super) safety: Option<f64>,
    pub(super) gait: Option<f64>,
    pub(super) capture: Option<f64>,
}

impl Keep {
    pub(super) fn eps(&self, c: Soft) -> Option<f64> {
        match c {
            Soft::Safety => self.safety,
            Soft::Gait => self.gait,
            Soft::Capture => self.capture,
        }
    }

    pub(super) fn with(self, c: Soft, eps: f64) -> Keep {
        match c {
            Soft::Safety => Keep {
                safety: Some(eps),
                ..self
            },
            Soft::Gait => Keep {
                gait: Some(eps),
                ..self
            },
            Soft::Capture => Keep {
                capture: Some(eps),
                ..self
            },
        }
    }

    /// The relaxed right-hand side of a row of kind `kind` with nominal
    /// right-hand side `h`, and whether it is the capturability ceiling
    /// (`None`: left out).
    pub(super) fn rhs(
        &self,
        kind: RowKind,
        h: f64,
        capture: Option<&CaptureBounds>,
    ) -> Option<(f64, bool)> {
        match RowClass::of(kind) {
            RowClass::Reach => Some((h, false)),
            RowClass::Safety => self.safety.map(|e| (h + e, false)),
            RowClass::Gait => {
                let by_gait = self.gait.map(|e| h + e);
                let by_capture = match (capture.and_then(|c| c.of(kind)), self.capture) {
                    (Some(room), Some(e)) => Some(h + room + e),
                    _ => None,
                };
                match (by_gait, by_capture) {
                    (Some(a), Some(b)) if b < a => Some((b, true)),
                    (Some(a), _) => Some((a, false)),
                    (None, Some(b)) => Some((b, true)),
                    (None, None) => None,
                }
            }
        }
    }
}
