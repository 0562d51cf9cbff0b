//! The condensed MPC in pre-stabilised variables: predictions, footsteps, the
//! cost, and every constraint row of docs/maths.md §2.5 as affine functions of the
//! predicted CoM positions.
//!
//! ## Decision variables
//!
//! `NV = 2N` entries, metres, world frame W, interleaved:
//! `z = [p_1x, p_1y, p_2x, p_2y, ..., p_Nx, p_Ny]`: the predicted CoM positions
//! at the ends of the planned steps (`p_k` = position of `x_k`, the state at the
//! start of step `k`). This is an exact, invertible change of variables of the
//! QP of docs/maths.md §2.4 (whose variables are the footsteps `f_0 .. f_{N-1}`):
//! both QPs have the same feasible set and cost under the map below, so they
//! have the same optimal footsteps, which the controller recovers exactly
//! (`reference/tests/reparam.rs` checks this against the foot-variable QP built from the
//! spec's formulas and solved by Clarabel).
//!
//! ## The map (per axis, both axes share it)
//!
//! With `c = cosh(beta T)`, `s = sinh(beta T)`, the step map
//! `p_{k+1} = c p_k + (s/beta) v_k + (1-c) f_k`,
//! `v_{k+1} = beta s p_k + c v_k - beta s f_k` solved for the foot gives
//!
//! ```text
//! f_k     = (p_{k+1} - c p_k - (s/beta) v_k) / (1 - c)
//! v_{k+1} = -v_k + kappa (p_k - p_{k+1}),      kappa = beta s / (1 - c) = -beta coth(beta T / 2)
//! ```
//!
//! (substituting: `c + s^2/(1-c) = (c - c^2 + s^2)/(1-c) = -1`, and
//! `beta s (1 + c/(1-c)) = beta s / (1-c)`). So, from the fixed `(p_0, v_0)`,
//! `v_k` is `(-1)^k`-alternating sums of `kappa (p_j - p_{j+1})`: every weight of
//! `z` in `v_k` is `0`, `+-kappa` or `+-2 kappa`, whatever `N`. Every row (velocity
//! on `v_{k+1}`, reachability on `f_k - p_k`, LDCBF on `p_{k+1}` and `p_k`, foot
//! clearance on `f_k`) is thus an affine function of `z` with weights bounded
//! independently of the horizon, and the cost `sum_{k=1..N} |p_k - g|^2` is
//! `sum_k |z_k - g|^2`: Hessian exactly `2 I`.
//!
//! ## Why (conditioning)
//!
//! With the footsteps as variables the CoM depends on `f_j` through
//! `A_d^(k-1-j) B_d`, whose entries grow like `e^{beta T k}` (`e^{beta T} = 3.50`
//! for the paper's `T = 0.4 s`, `H = 1 m`), so the Hessian `2 S_p' S_p` of the
//! cost is ill-conditioned. Measured (`cargo test --release -p ldcbf-reference --test reparam --
//! --nocapture`, 2-norm condition number of the per-axis Hessian):
//!
//! | N | foot variables | these variables |
//! |---|---|---|
//! | 3 | 2.7e4 | 1 |
//! | 5 | 1.4e7 | 1 |
//! | 10 | 1.8e13 | 1 |
//! | 14 | 8.3e17 | 1 |
//! | 20 | 6.9e18, a computed eigenvalue of -2.5e2: not positive definite in floating point (Cholesky fails) | 1 |
//!
//! In the new variables `H = 2 I` for every `N`, and the rows' normals stay of
//! moderate size (`|kappa| = 5.6` 1/s), so the dual active-set solver works at
//! `N = 10` and `N = 20` as at `N = 3`. Alternative considered: footsteps as
//! offsets `d_k = f_k - xi_k` from the capture point (DCM) `xi = p + v/beta`
//! also remove the growth (`xi_{k+1} = xi_k - (e^{beta T} - 1) d_k`), but each
//! `p_k` is then a cumulative sum of all earlier `d_j`, so the cost's Hessian is
//! dense and its condition number still grows with `N` (like `N^2` for such sums);
//! the positions make the cost diagonal (nothing to factor), keep the LDCBF rows
//! (which act on positions) two-term, and the inverse map is only marginally
//! stable (weights at most `2 |kappa|`).
//!
//! ## Rows
//!
//! A predicted world vector `Q` (a position `p_k`, a velocity `v_k`, a foot `f_k`
//! or foot offset `f_k - p_k`) is `Q = sum_j w_j z_j + Q0` with scalar weights
//! `w_j` (`z_j = p_{j+1}` as a world vector) and a constant `Q0` from `(p_0, v_0)`,
//! and a row `a' Q <= b` with a world direction `a` becomes
//! `sum_j w_j (a_x z_jx + a_y z_jy) <= b - a' Q0`.
//! [`Condensed`] produces the weights and constants; [`push_row`] writes the row.
//!
//! Rows for step `k = 0..N-1`, in this order (8 per step), with
//! `lon = (cos theta_k, sin theta_k)`, `lat = (-sin theta_k, cos theta_k)`:
//!
//! | kind | row |
//! |---|---|
//! | [`RowKind::VelLonUpper`] | `lon' v_{k+1} <= min(vx_max, vx_max - alpha/pi |omega_bar|)` (velocity and maneuverability share this row) |
//! | [`RowKind::VelLonLower`] | `-lon' v_{k+1} <= -vx_min` |
//! | [`RowKind::VelLatUpper`] | `s_k lat' v_{k+1} <= vy_max` |
//! | [`RowKind::VelLatLower`] | `-s_k lat' v_{k+1} <= -vy_min` |
//! | [`RowKind::ReachLonUpper`] .. [`RowKind::ReachLatLower`] | `+-lon'(f_k - p_k) <= l_max`, `+-lat'(f_k - p_k) <= l_max` |
//!
//! then, per active obstacle `j` (nearest first) and step `k`, the LDCBF row
//! `h_j(p_{k+1}) >= (1 - gamma) h_j(p_k)` written as
//! `-eta' p_{k+1} + (1 - gamma) eta' p_k <= -gamma (eta' c + delta)`, and, when
//! enabled, the foot-clearance rows `-eta' f_k <= -eta' c - delta_foot`.
//!
//! The maneuverability bound `lon' v_{k+1} <= vx_max - alpha/pi |omega_bar|` has the
//! same left-hand side as the upper walking-velocity bound, so the two are one row
//! with the smaller right-hand side: identical feasible set, no duplicated
//! (linearly dependent) rows for the solver.
//!
//! Every row's right-hand side is in physical units: m/s of a body-frame
//! velocity component for the velocity rows, m for the reachability rows, m of
//! `h` for the LDCBF and foot-clearance rows. The priority scheme of
//! [`crate::relax`] relaxes rows in these units (`h_i + eps`). The rows' norms
//! in these variables (the unit of the solver's tolerance) differ: e.g. `1` for
//! the `k = 0` LDCBF rows, `sqrt(1 + (1 - gamma)^2)` for the others, `|kappa| =
//! 5.64` for a first-step velocity row and about 12.6 for a second-step one
//! (Table I).
#![allow(non_snake_case)]

use nalgebra::{ArrayStorage, SMatrix, SVector, Vector2};

use crate::lip::Lip;
use crate::qp::DenseQp;

mod obstacle;
pub use obstacle::{HalfPlane, StepSpan, push_foot_row, push_ldcbf_row};

/// Kind of a constraint row; see the module docs for the formulas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RowKind {
    /// Longitudinal velocity upper bound, merged with maneuverability.
    VelLonUpper,
    /// Longitudinal velocity lower bound.
    VelLonLower,
    /// Lateral velocity upper bound (with stance sign `s_k`).
    VelLatUpper,
    /// Lateral velocity lower bound (with stance sign `s_k`).
    VelLatLower,
    /// Leg reachability, `+lon'(f_k - p_k) <= l_max`.
    ReachLonUpper,
    /// Leg reachability, `-lon'(f_k - p_k) <= l_max`.
    ReachLonLower,
    /// Leg reachability, `+lat'(f_k - p_k) <= l_max`.
    ReachLatUpper,
    /// Leg reachability, `-lat'(f_k - p_k) <= l_max`.
    ReachLatLower,
    /// LDCBF row of the obstacle with this index in the caller's obstacle slice
    /// (`CycleInput::obstacles`, also when the caller passes candidates).
    Ldcbf(u32),
    /// Foot clearance row of the obstacle with this index in the caller's slice.
    FootClearance(u32),
}

impl RowKind {
    /// The eight gait rows of one step, in row order.
    pub const GAIT: [RowKind; 8] = [
        RowKind::VelLonUpper,
        RowKind::VelLonLower,
        RowKind::VelLatUpper,
        RowKind::VelLatLower,
        RowKind::ReachLonUpper,
        RowKind::ReachLonLower,
        RowKind::ReachLatUpper,
        RowKind::ReachLatLower,
    ];

    /// True for the LDCBF (safety) rows.
    pub fn is_ldcbf(self) -> bool {
        matches!(self, RowKind::Ldcbf(_))
    }
}

/// Identity of a constraint row: its kind and the horizon step `k` it belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RowId {
    /// What the row bounds.
    pub kind: RowKind,
    /// Horizon step, `0..N`.
    pub k: u8,
}

impl RowId {
    /// The default row identity (`VelLonUpper`, `k = 0`), as a constant.
    pub const DEFAULT: RowId = RowId {
        kind: RowKind::VelLonUpper,
        k: 0,
    };
}

impl Default for RowId {
    fn default() -> Self {
        RowId::DEFAULT
    }
}

/// The LIP predictions over the horizon as affine maps of the decision vector
/// `z = (p_1, .., p_N)` (see the module docs).
///
/// Per axis, `v_k = V0[k-1] . (p0, v0) + sum_j V_w[k-1, j] z_j` for `k = 1..N`
/// (`z_j = p_{j+1}`), and the feet follow from positions and velocities by
/// `f_k = (p_{k+1} - c p_k - (s/beta) v_k) / (1 - c)`. Depends only on
/// `(T, H, g, N)`: built once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Condensed<const N: usize> {
    /// `c = cosh(beta T)`.
    pub c: f64,
    /// `s / beta = sinh(beta T) / beta`, s.
    pub s_over_beta: f64,
    /// `beta s = beta sinh(beta T)`, 1/s.
    pub beta_s: f64,
    /// `kappa = beta s / (1 - c)`, 1/s: `v_{k+1} = -v_k + kappa (p_k - p_{k+1})`.
    pub kappa: f64,
    /// Row `k-1`: coefficients of `(p0, v0)` in `v_k` (1/s, 1).
    pub V0: [Vector2<f64>; N],
    /// `V_w[k-1, j]`: weight (1/s) of `z_j = p_{j+1}` in `v_k`; zero for `j >= k`.
    pub V_w: SMatrix<f64, N, N>,
}

impl<const N: usize> Condensed<N> {
    /// All-zero placeholder (every coefficient 0, not a model): for `const` and
    /// `static` initialisers, e.g. an unconfigured controller. Build real maps
    /// with [`Condensed::new`].
    pub const ZERO: Self = Condensed {
        c: 0.0,
        s_over_beta: 0.0,
        beta_s: 0.0,
        kappa: 0.0,
        V0: [Vector2::new(0.0, 0.0); N],
        V_w: SMatrix::from_array_storage(ArrayStorage([[0.0; N]; N])),
    };

    /// Builds the maps from the step model.
    pub fn new(lip: &Lip) -> Self {
        let c = lip.cosh_bt;
        let beta_s = lip.beta * lip.sinh_bt;
        let kappa = beta_s / (1.0 - c);
        let mut V0 = [Vector2::zeros(); N];
        let mut V_w = SMatrix::<f64, N, N>::zeros();
        // v_1 = kappa p0 - v0 - kappa p_1.
        if N >= 1 {
            V0[0] = Vector2::new(kappa, -1.0);
            V_w[(0, 0)] = -kappa;
        }
        // v_{k+1} = -v_k + kappa p_k - kappa p_{k+1}, k = 1..N-1.
        for k in 1..N {
            V0[k] = -V0[k - 1];
            for j in 0..k {
                V_w[(k, j)] = -V_w[(k - 1, j)];
            }
            V_w[(k, k - 1)] += kappa;
            V_w[(k, k)] -= kappa;
        }
        Condensed {
            c,
            s_over_beta: lip.sinh_bt / lip.beta,
            beta_s,
            kappa,
            V0,
            V_w,
        }
    }

    /// `(weights, constant)` of `p_k`, `k = 0..=N` (`p_0` is the constant itself,
    /// `p_k` for `k >= 1` is the variable `z_{k-1}`).
    pub fn position(
        &self,
        k: usize,
        p0: &Vector2<f64>,
        _v0: &Vector2<f64>,
    ) -> (SVector<f64, N>, Vector2<f64>) {
        let mut w = SVector::<f64, N>::zeros();
        if k == 0 {
            return (w, *p0);
        }
        if let Some(e) = w.get_mut(k - 1) {
            *e = 1.0;
        }
        (w, Vector2::zeros())
    }

    /// `(weights, constant)` of `v_k`, `k = 0..=N`.
    pub fn velocity(
        &self,
        k: usize,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
    ) -> (SVector<f64, N>, Vector2<f64>) {
        if k == 0 || k > N {
            return (SVector::zeros(), *v0);
        }
        let c = self.V0[k - 1];
        (self.V_w.row(k - 1).transpose(), p0 * c[0] + v0 * c[1])
    }

    /// `(weights, constant)` of the foot `f_k`, `k = 0..N-1`:
    /// `(p_{k+1} - c p_k - (s/beta) v_k) / (1 - c)`.
    pub fn foot(
        &self,
        k: usize,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
    ) -> (SVector<f64, N>, Vector2<f64>) {
        self.foot_less(k, self.c, p0, v0)
    }

    /// `(weights, constant)` of the foot offset `f_k - p_k`, `k = 0..N-1`:
    /// `(p_{k+1} - p_k - (s/beta) v_k) / (1 - c)`.
    pub fn foot_offset(
        &self,
        k: usize,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
    ) -> (SVector<f64, N>, Vector2<f64>) {
        self.foot_less(k, 1.0, p0, v0)
    }

    /// `(weights, constant)` of `(p_{k+1} - a p_k - (s/beta) v_k) / (1 - c)`:
    /// the foot `f_k` for `a = c`, the offset `f_k - p_k` for `a = 1` (the
    /// factor 1 is exact, so the offset's bits are those of its own formula).
    fn foot_less(
        &self,
        k: usize,
        a: f64,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
    ) -> (SVector<f64, N>, Vector2<f64>) {
        let (w1, c1) = self.position(k + 1, p0, v0);
        let (wp, cp) = self.position(k, p0, v0);
        let (wv, cv) = self.velocity(k, p0, v0);
        let d = 1.0 / (1.0 - self.c);
        (
            (w1 - wp * a - wv * self.s_over_beta) * d,
            (c1 - cp * a - cv * self.s_over_beta) * d,
        )
    }

    /// Per-axis Hessian of `sum_k |p_k - g|^2` in `1/2 z'Hz` form: `2 I`.
    pub fn axis_hessian(&self) -> SMatrix<f64, N, N> {
        SMatrix::<f64, N, N>::identity() * 2.0
    }

    /// Full Hessian for the interleaved decision vector (`NV = 2N`): `2 I`.
    pub fn hessian<const NV: usize>(&self) -> SMatrix<f64, NV, NV> {
        const { assert!(NV == 2 * N, "NV must equal 2 N") };
        SMatrix::<f64, NV, NV>::identity() * 2.0
    }

    /// Gradient `q = -2 (g, .., g)` (interleaved) of the cost
    /// `sum_{k=1..N} |p_k - g|^2` in `1/2 z'Hz + q'z` form, and the constant
    /// `N |g|^2`, so that cost = `1/2 z'Hz + q'z + constant`.
    pub fn gradient<const NV: usize>(&self, goal: &Vector2<f64>) -> (SVector<f64, NV>, f64) {
        const { assert!(NV == 2 * N, "NV must equal 2 N") };
        let mut q = SVector::<f64, NV>::zeros();
        for k in 0..N {
            q[2 * k] = -2.0 * goal.x;
            q[2 * k + 1] = -2.0 * goal.y;
        }
        (q, N as f64 * goal.norm_squared())
    }

    /// The decision vector of a plan given by its feet: the LIP rolled forward
    /// from `(p0, v0)` over the feet `f_0 .. f_{N-1}` (interleaved, m), keeping
    /// the positions `p_1 .. p_N`.
    pub fn variables_from_feet<const NV: usize>(
        &self,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
        feet: &SVector<f64, NV>,
    ) -> SVector<f64, NV> {
        const { assert!(NV == 2 * N, "NV must equal 2 N") };
        let (mut p, mut v) = (*p0, *v0);
        let mut z = SVector::<f64, NV>::zeros();
        for k in 0..N {
            let f = Vector2::new(feet[2 * k], feet[2 * k + 1]);
            let pn = p * self.c + v * self.s_over_beta + f * (1.0 - self.c);
            v = (p - f) * self.beta_s + v * self.c;
            p = pn;
            z[2 * k] = p.x;
            z[2 * k + 1] = p.y;
        }
        z
    }

    /// The feet `f_0 .. f_{N-1}` and velocities `v_1 .. v_N` of the decision
    /// vector `z` from `(p0, v0)`, by the inverse map of the module docs (each
    /// foot from `p_k`, `v_k`, `p_{k+1}`; no forward propagation, so no growth of
    /// rounding errors along the horizon).
    pub fn feet_from_variables<const NV: usize>(
        &self,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
        z: &SVector<f64, NV>,
    ) -> ([Vector2<f64>; N], [Vector2<f64>; N]) {
        const { assert!(NV == 2 * N, "NV must equal 2 N") };
        let mut feet = [Vector2::zeros(); N];
        let mut vel = [Vector2::zeros(); N];
        let (mut p, mut v) = (*p0, *v0);
        let d = 1.0 / (1.0 - self.c);
        for k in 0..N {
            let pn = Vector2::new(z[2 * k], z[2 * k + 1]);
            feet[k] = (pn - p * self.c - v * self.s_over_beta) * d;
            v = -v + (p - pn) * self.kappa;
            vel[k] = v;
            p = pn;
        }
        (feet, vel)
    }
}

/// Appends the row `a' Q <= ub` with `Q = sum_j w_j z_j + q0` (`z_j = p_{j+1}`) to `qp`. Returns
/// `Err(())` when the QP is full (nothing written).
#[allow(clippy::result_unit_err)]
pub fn push_row<const N: usize, const NV: usize, const NC: usize>(
    qp: &mut DenseQp<NV, NC>,
    a: &Vector2<f64>,
    w: &SVector<f64, N>,
    q0: &Vector2<f64>,
    ub: f64,
) -> Result<(), ()> {
    const { assert!(NV == 2 * N, "NV must equal 2 N") };
    let mut g = SVector::<f64, NV>::zeros();
    for j in 0..N {
        g[2 * j] = w[j] * a.x;
        g[2 * j + 1] = w[j] * a.y;
    }
    qp.push_row(&g, ub - a.dot(q0))
}

/// Gait bounds used by [`push_gait_rows`] (values from the validated configuration).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitBounds {
    /// Longitudinal velocity bounds, m/s.
    pub vx_min: f64,
    /// Longitudinal velocity upper bound, m/s.
    pub vx_max: f64,
    /// Lateral velocity bounds (with stance sign), m/s.
    pub vy_min: f64,
    /// Lateral velocity upper bound, m/s.
    pub vy_max: f64,
    /// Leg reachability half-width, m.
    pub l_max: f64,
    /// Maneuverability coefficient `alpha`, m/rad (so `alpha/pi |omega|` is m/s).
    pub alpha: f64,
}

/// Appends the 8 gait rows of step `k` (order of [`RowKind::GAIT`]) with heading
/// `theta_k` (rad), stance sign `s_k` (+1 right, -1 left) and turning rate
/// `omega_bar` (rad/s). `x0 = (p0, v0)` is the predicted state at the start of step 0.
#[allow(clippy::too_many_arguments, clippy::result_unit_err)]
pub fn push_gait_rows<const N: usize, const NV: usize, const NC: usize>(
    qp: &mut DenseQp<NV, NC>,
    model: &Condensed<N>,
    b: &GaitBounds,
    k: usize,
    theta_k: f64,
    s_k: f64,
    omega_bar: f64,
    p0: &Vector2<f64>,
    v0: &Vector2<f64>,
) -> Result<(), ()> {
    let (s, c) = libm::sincos(theta_k);
    let lon = Vector2::new(c, s);
    let lat = Vector2::new(-s, c);
    let (wv, v_free) = model.velocity(k + 1, p0, v0);
    let lon_upper = b
        .vx_max
        .min(b.vx_max - b.alpha / core::f64::consts::PI * omega_bar.abs());
    push_row(qp, &lon, &wv, &v_free, lon_upper)?;
    push_row(qp, &-lon, &wv, &v_free, -b.vx_min)?;
    push_row(qp, &(lat * s_k), &wv, &v_free, b.vy_max)?;
    push_row(qp, &(lat * -s_k), &wv, &v_free, -b.vy_min)?;
    let (wd, d_const) = model.foot_offset(k, p0, v0);
    push_row(qp, &lon, &wd, &d_const, b.l_max)?;
    push_row(qp, &-lon, &wd, &d_const, b.l_max)?;
    push_row(qp, &lat, &wd, &d_const, b.l_max)?;
    push_row(qp, &-lat, &wd, &d_const, b.l_max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reach::{Reach, ReachLimits};

    const LIM: ReachLimits = ReachLimits {
        speed_max: 1.5,
        accel: 0.5,
        grow: 0.8,
    };

    fn model() -> (Lip, Condensed<3>) {
        let lip = Lip::new(9.81, 1.0, 0.4);
        (lip, Condensed::new(&lip))
    }

    /// Rolls the LIP forward with explicit feet: reference for the condensed form.
    fn rollout(
        lip: &Lip,
        p0: Vector2<f64>,
        v0: Vector2<f64>,
        f: &[Vector2<f64>; 3],
    ) -> [(Vector2<f64>, Vector2<f64>); 4] {
        let mut out = [(p0, v0); 4];
        for k in 0..3 {
            let (p, v) = out[k];
            out[k + 1] = lip.propagate(&p, &v, &f[k], 0.4);
        }
        out
    }

    fn u_of(f: &[Vector2<f64>; 3]) -> SVector<f64, 6> {
        SVector::<f64, 6>::from([f[0].x, f[0].y, f[1].x, f[1].y, f[2].x, f[2].y])
    }

    /// The decision vector `z = (p_1, p_2, p_3)` of a rollout.
    fn z_of(traj: &[(Vector2<f64>, Vector2<f64>); 4]) -> SVector<f64, 6> {
        let p = |k: usize| traj[k].0;
        SVector::<f64, 6>::from([p(1).x, p(1).y, p(2).x, p(2).y, p(3).x, p(3).y])
    }

    fn eval<const N: usize>(
        (w, c): (SVector<f64, N>, Vector2<f64>),
        z: &SVector<f64, 6>,
    ) -> Vector2<f64> {
        (0..N).fold(c, |acc, j| {
            acc + Vector2::new(z[2 * j], z[2 * j + 1]) * w[j]
        })
    }

    const P0: [f64; 2] = [0.3, -0.2];
    const V0: [f64; 2] = [0.4, 0.15];

    fn feet() -> [Vector2<f64>; 3] {
        [
            Vector2::new(0.35, -0.1),
            Vector2::new(0.6, -0.3),
            Vector2::new(0.9, -0.05),
        ]
    }

    #[test]
    fn condensed_prediction_equals_rollout() {
        let (lip, m) = model();
        let (p0, v0) = (Vector2::from(P0), Vector2::from(V0));
        let f = feet();
        let traj = rollout(&lip, p0, v0, &f);
        let z = m.variables_from_feet(&p0, &v0, &u_of(&f));
        assert!((z - z_of(&traj)).amax() < 1e-14);
        for k in 0..=3 {
            let p = eval(m.position(k, &p0, &v0), &z);
            assert!((p - traj[k].0).amax() < 1e-14, "p_{k}");
            let v = eval(m.velocity(k, &p0, &v0), &z);
            assert!((v - traj[k].1).amax() < 1e-13, "v_{k}");
        }
        for k in 0..3 {
            let fk = eval(m.foot(k, &p0, &v0), &z);
            assert!((fk - f[k]).amax() < 1e-13, "f_{k}");
            let d = eval(m.foot_offset(k, &p0, &v0), &z);
            assert!((d - (f[k] - traj[k].0)).amax() < 1e-13, "f_{k} - p_{k}");
        }
        let (fs, vs) = m.feet_from_variables(&p0, &v0, &z);
        for k in 0..3 {
            assert!((fs[k] - f[k]).amax() < 1e-13);
            assert!((vs[k] - traj[k + 1].1).amax() < 1e-13);
        }
        // kappa = -beta coth(beta T / 2).
        let x = 0.5 * lip.beta * 0.4;
        let coth = libm::cosh(x) / libm::sinh(x);
        assert!((m.kappa + lip.beta * coth).abs() < 1e-13);
    }

    #[test]
    fn weights_stay_bounded_over_long_horizons() {
        // The point of the variables: no weight grows with the horizon.
        let lip = Lip::new(9.81, 1.0, 0.4);
        let m = Condensed::<20>::new(&lip);
        let bound = 2.0 * m.kappa.abs() * (1.0 + 1e-15);
        assert!(m.V_w.amax() <= bound, "{}", m.V_w.amax());
        assert!(m.V0.iter().all(|c| c.amax() <= m.kappa.abs()));
        // Round trip over 20 steps of a capture-like walk: exact to rounding.
        let (p0, v0) = (Vector2::new(0.3, -0.2), Vector2::new(0.4, 0.15));
        let mut feet = SVector::<f64, 40>::zeros();
        let (mut p, mut v) = (p0, v0);
        for k in 0..20 {
            let f = p + v / lip.beta + Vector2::new(0.05, if k % 2 == 0 { 0.1 } else { -0.1 });
            feet[2 * k] = f.x;
            feet[2 * k + 1] = f.y;
            (p, v) = lip.propagate(&p, &v, &f, 0.4);
        }
        let z = m.variables_from_feet(&p0, &v0, &feet);
        let (fs, _) = m.feet_from_variables(&p0, &v0, &z);
        for (k, fk) in fs.iter().enumerate() {
            assert!((fk.x - feet[2 * k]).abs() < 1e-12 && (fk.y - feet[2 * k + 1]).abs() < 1e-12);
        }
        assert_eq!(m.hessian::<40>(), SMatrix::<f64, 40, 40>::identity() * 2.0);
    }

    #[test]
    fn cost_matches_sum_of_squares() {
        let (lip, m) = model();
        let (p0, v0) = (Vector2::from(P0), Vector2::from(V0));
        let goal = Vector2::new(5.0, 5.0);
        let f = feet();
        let traj = rollout(&lip, p0, v0, &f);
        let direct: f64 = (1..=3).map(|k| (traj[k].0 - goal).norm_squared()).sum();
        let h = m.hessian::<6>();
        let (q, c) = m.gradient::<6>(&goal);
        let z = z_of(&traj);
        let quad = 0.5 * (h * z).dot(&z) + q.dot(&z) + c;
        assert!((quad - direct).abs() < 1e-12 * direct.max(1.0));
        assert!(h.cholesky().is_some());
    }

    fn row_value(qp: &DenseQp<6, 16>, i: usize, u: &SVector<f64, 6>) -> f64 {
        qp.row(i).dot(u) - qp.h[i]
    }

    #[test]
    fn gait_rows_equal_their_formulas() {
        let (lip, m) = model();
        let (p0, v0) = (Vector2::from(P0), Vector2::from(V0));
        let f = feet();
        let traj = rollout(&lip, p0, v0, &f);
        let u = z_of(&traj);
        let b = GaitBounds {
            vx_min: -0.1,
            vx_max: 0.8,
            vy_min: 0.1,
            vy_max: 0.4,
            l_max: 0.1 * libm::sqrt(3.0),
            alpha: 1.44,
        };
        let (k, theta, s_k, om) = (1usize, 0.7, -1.0, 0.3);
        let mut qp = DenseQp::<6, 16>::default();
        push_gait_rows(&mut qp, &m, &b, k, theta, s_k, om, &p0, &v0).unwrap();
        assert_eq!(qp.m, 8);
        let (c, s) = (libm::cos(theta), libm::sin(theta));
        let v = traj[k + 1].1;
        let lon_v = c * v.x + s * v.y;
        let lat_v = -s * v.x + c * v.y;
        let d = f[k] - traj[k].0;
        let lon_d = c * d.x + s * d.y;
        let lat_d = -s * d.x + c * d.y;
        let man = 0.8 - 1.44 / core::f64::consts::PI * 0.3;
        let expect = [
            lon_v - man,
            -lon_v + (-0.1),
            s_k * lat_v - 0.4,
            -s_k * lat_v + 0.1,
            lon_d - b.l_max,
            -lon_d - b.l_max,
            lat_d - b.l_max,
            -lat_d - b.l_max,
        ];
        for (i, e) in expect.iter().enumerate() {
            assert!(
                (row_value(&qp, i, &u) - e).abs() < 1e-13,
                "row {i}: {} vs {e}",
                row_value(&qp, i, &u)
            );
        }
        // k = 0: reachability involves p_1 and the fixed (p_0, v_0) only:
        // f_0 - p_0 = (p_1 - p_0 - (s/beta) v_0) / (1 - c).
        let mut qp0 = DenseQp::<6, 16>::default();
        push_gait_rows(&mut qp0, &m, &b, 0, 0.0, 1.0, 0.0, &p0, &v0).unwrap();
        let r = qp0.row(4);
        let d = 1.0 / (1.0 - lip.cosh_bt);
        assert_eq!((r[1], r[2], r[3], r[4], r[5]), (0.0, 0.0, 0.0, 0.0, 0.0));
        assert!((r[0] - d).abs() < 1e-15);
        let h4 = b.l_max + d * (p0.x + lip.sinh_bt / lip.beta * v0.x);
        assert!((qp0.h[4] - h4).abs() < 1e-15);
        // omega = 0: the merged row is the plain velocity bound.
        assert!((row_value(&qp0, 0, &u) - (traj[1].1.x - 0.8)).abs() < 1e-13);
    }

    #[test]
    fn ldcbf_and_foot_rows_equal_their_formulas() {
        let (lip, m) = model();
        let (p0, v0) = (Vector2::from(P0), Vector2::from(V0));
        let f = feet();
        let traj = rollout(&lip, p0, v0, &f);
        let u = z_of(&traj);
        let hp = HalfPlane {
            c: Vector2::new(1.0, 1.0),
            eta: Vector2::new(-0.6, -0.8),
            rate: 0.0,
            reach: Reach::NONE,
        };
        let (gamma, delta) = (0.3, 0.2);
        let at = |k| StepSpan {
            k,
            times: (0.0, 0.0),
            p0,
            v0,
        };
        let mut qp = DenseQp::<6, 16>::default();
        for k in 0..3 {
            push_ldcbf_row(&mut qp, &m, &hp, &LIM, gamma, delta, &at(k)).unwrap();
        }
        for k in 0..3 {
            // row value = -(h(p_{k+1}) - (1-gamma) h(p_k))
            let e = -(hp.h(&traj[k + 1].0, delta) - (1.0 - gamma) * hp.h(&traj[k].0, delta));
            assert!((row_value(&qp, k, &u) - e).abs() < 1e-13, "k={k}");
        }
        // gamma = 1: plain h(p_{k+1}) >= 0.
        let mut qp1 = DenseQp::<6, 16>::default();
        push_ldcbf_row(&mut qp1, &m, &hp, &LIM, 1.0, delta, &at(1)).unwrap();
        assert!((row_value(&qp1, 0, &u) + hp.h(&traj[2].0, delta)).abs() < 1e-13);
        let mut qpf = DenseQp::<6, 16>::default();
        push_foot_row(&mut qpf, &m, &hp, &LIM, 0.05, &at(2)).unwrap();
        let e = -(hp.eta.dot(&(f[2] - hp.c)) - 0.05);
        assert!((row_value(&qpf, 0, &u) - e).abs() < 1e-13);
    }

    #[test]
    fn full_qp_rejects_rows() {
        let (_, m) = model();
        let mut qp = DenseQp::<6, 7>::default();
        let b = GaitBounds {
            vx_min: -0.1,
            vx_max: 0.8,
            vy_min: 0.1,
            vy_max: 0.4,
            l_max: 0.17,
            alpha: 1.44,
        };
        let z = Vector2::zeros();
        assert!(push_gait_rows(&mut qp, &m, &b, 0, 0.0, 1.0, 0.0, &z, &z).is_err());
        assert_eq!(qp.m, 7);
    }
}
