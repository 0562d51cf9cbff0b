//! The condensed MPC: predictions as affine functions of the footsteps, the cost,
//! and every constraint row of SPEC 2.5.
//!
//! Decision vector (`NV = 2N` entries, metres, world frame W), interleaved:
//! `u = [f_0x, f_0y, f_1x, f_1y, ..., f_{N-1}x, f_{N-1}y]`.
//!
//! Both axes share the same LIP coefficients, so every predicted world vector
//! `Q` (a position `p_k`, a velocity `v_k`, a foot offset `f_k - p_k`) is
//! `Q = sum_j w_j f_j + Q0` with scalar weights `w_j`, and a row `a' Q <= b` with a
//! world direction `a` becomes `sum_j w_j (a_x f_jx + a_y f_jy) <= b - a' Q0`.
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
#![allow(non_snake_case)]

use nalgebra::{SMatrix, SVector, Vector2};

use crate::lip::Lip;
use crate::qp::DenseQp;

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
    /// LDCBF row of the obstacle with this index in the caller's obstacle slice.
    Ldcbf(u16),
    /// Foot clearance row of the obstacle with this index in the caller's slice.
    FootClearance(u16),
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

impl Default for RowId {
    fn default() -> Self {
        RowId {
            kind: RowKind::VelLonUpper,
            k: 0,
        }
    }
}

/// The LIP predictions over the horizon as affine maps of the footsteps.
///
/// `p_k = P_p[k-1] (p0, v0) + sum_j S_p[k-1, j] f_j` (per axis, `k = 1..N`), and the
/// same for velocities with `P_v`, `S_v`. `S_p`, `S_v` are lower triangular.
/// Depends only on `(T, H, g, N)`: built once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Condensed<const N: usize> {
    /// Row `k-1`: coefficients of `(p0, v0)` in `p_k` (first row of `A_d^k`).
    pub P_p: [Vector2<f64>; N],
    /// Row `k-1`: coefficients of `(p0, v0)` in `v_k` (second row of `A_d^k`).
    pub P_v: [Vector2<f64>; N],
    /// `S_p[k-1, j]`: weight of `f_j` in `p_k`.
    pub S_p: SMatrix<f64, N, N>,
    /// `S_v[k-1, j]`: weight of `f_j` in `v_k`.
    pub S_v: SMatrix<f64, N, N>,
}

impl<const N: usize> Condensed<N> {
    /// Builds the prediction matrices from the step model.
    pub fn new(lip: &Lip) -> Self {
        let a = lip.A_d();
        let b = lip.B_d();
        // gam[m] = A^m B
        let mut gam = [Vector2::zeros(); N];
        let mut g = b;
        for gm in gam.iter_mut() {
            *gm = g;
            g = a * g;
        }
        let mut P_p = [Vector2::zeros(); N];
        let mut P_v = [Vector2::zeros(); N];
        let mut ak = a;
        for k in 0..N {
            P_p[k] = Vector2::new(ak[(0, 0)], ak[(0, 1)]);
            P_v[k] = Vector2::new(ak[(1, 0)], ak[(1, 1)]);
            ak = a * ak;
        }
        let mut S_p = SMatrix::<f64, N, N>::zeros();
        let mut S_v = SMatrix::<f64, N, N>::zeros();
        for k in 1..=N {
            for j in 0..k {
                S_p[(k - 1, j)] = gam[k - 1 - j][0];
                S_v[(k - 1, j)] = gam[k - 1 - j][1];
            }
        }
        Condensed { P_p, P_v, S_p, S_v }
    }

    /// Free response (all feet zero) of `p_k`, `k = 1..=N`, from `(p0, v0)`.
    pub fn free_position(&self, k: usize, p0: &Vector2<f64>, v0: &Vector2<f64>) -> Vector2<f64> {
        let c = self.P_p[k - 1];
        p0 * c[0] + v0 * c[1]
    }

    /// Free response of `v_k`, `k = 1..=N`.
    pub fn free_velocity(&self, k: usize, p0: &Vector2<f64>, v0: &Vector2<f64>) -> Vector2<f64> {
        let c = self.P_v[k - 1];
        p0 * c[0] + v0 * c[1]
    }

    /// Weights of the footsteps in `p_k` (zero for `k = 0`).
    pub fn position_weights(&self, k: usize) -> SVector<f64, N> {
        if k == 0 {
            SVector::zeros()
        } else {
            self.S_p.row(k - 1).transpose()
        }
    }

    /// Weights of the footsteps in `v_k`, `k >= 1`.
    pub fn velocity_weights(&self, k: usize) -> SVector<f64, N> {
        self.S_v.row(k - 1).transpose()
    }

    /// `(weights, constant)` of `p_k` for `k = 0..=N` (`p_0` is the constant itself).
    pub fn position(
        &self,
        k: usize,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
    ) -> (SVector<f64, N>, Vector2<f64>) {
        if k == 0 {
            (SVector::zeros(), *p0)
        } else {
            (self.position_weights(k), self.free_position(k, p0, v0))
        }
    }

    /// Per-axis Hessian of `sum_k |p_k - g|^2` in `1/2 u'Hu` form: `2 S_p' S_p`.
    pub fn axis_hessian(&self) -> SMatrix<f64, N, N> {
        self.S_p.transpose() * self.S_p * 2.0
    }

    /// Full Hessian for the interleaved decision vector (`NV = 2N`).
    pub fn hessian<const NV: usize>(&self) -> SMatrix<f64, NV, NV> {
        const { assert!(NV == 2 * N, "NV must equal 2 N") };
        let ha = self.axis_hessian();
        let mut h = SMatrix::<f64, NV, NV>::zeros();
        for i in 0..N {
            for j in 0..N {
                h[(2 * i, 2 * j)] = ha[(i, j)];
                h[(2 * i + 1, 2 * j + 1)] = ha[(i, j)];
            }
        }
        h
    }

    /// Gradient `q = 2 S_p' (P_p x0 - g)` (interleaved) of the cost
    /// `sum_{k=1..N} |p_k - g|^2` in `1/2 u'Hu + q'u` form. Also returns the constant
    /// `sum_k |free p_k - g|^2` so that cost = `1/2 u'Hu + q'u + constant`.
    pub fn gradient<const NV: usize>(
        &self,
        p0: &Vector2<f64>,
        v0: &Vector2<f64>,
        goal: &Vector2<f64>,
    ) -> (SVector<f64, NV>, f64) {
        const { assert!(NV == 2 * N, "NV must equal 2 N") };
        let mut q = SVector::<f64, NV>::zeros();
        let mut constant = 0.0;
        for k in 1..=N {
            let e = self.free_position(k, p0, v0) - goal;
            constant += e.norm_squared();
            for j in 0..k {
                let w = 2.0 * self.S_p[(k - 1, j)];
                q[2 * j] += w * e.x;
                q[2 * j + 1] += w * e.y;
            }
        }
        (q, constant)
    }
}

/// Appends the row `a' Q <= ub` with `Q = sum_j w_j f_j + q0` to `qp`. Returns
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
    let (s, c) = (libm::sin(theta_k), libm::cos(theta_k));
    let lon = Vector2::new(c, s);
    let lat = Vector2::new(-s, c);
    let wv = model.velocity_weights(k + 1);
    let v_free = model.free_velocity(k + 1, p0, v0);
    let lon_upper = b
        .vx_max
        .min(b.vx_max - b.alpha / core::f64::consts::PI * omega_bar.abs());
    push_row(qp, &lon, &wv, &v_free, lon_upper)?;
    push_row(qp, &-lon, &wv, &v_free, -b.vx_min)?;
    push_row(qp, &(lat * s_k), &wv, &v_free, b.vy_max)?;
    push_row(qp, &(lat * -s_k), &wv, &v_free, -b.vy_min)?;
    // f_k - p_k
    let (wp, p_const) = model.position(k, p0, v0);
    let mut wd = -wp;
    wd[k] += 1.0;
    let d_const = -p_const;
    push_row(qp, &lon, &wd, &d_const, b.l_max)?;
    push_row(qp, &-lon, &wd, &d_const, b.l_max)?;
    push_row(qp, &lat, &wd, &d_const, b.l_max)?;
    push_row(qp, &-lat, &wd, &d_const, b.l_max)
}

/// A linearised obstacle: the half-plane `h(p) = eta'(p - c) - delta >= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfPlane {
    /// `c`: closest boundary point to `p_0` (m, world).
    pub c: Vector2<f64>,
    /// `eta`: unit normal towards the safe side.
    pub eta: Vector2<f64>,
}

impl HalfPlane {
    /// `h(p) = eta'(p - c) - delta` (m).
    pub fn h(&self, p: &Vector2<f64>, delta: f64) -> f64 {
        self.eta.dot(&(p - self.c)) - delta
    }
}

/// Appends the LDCBF row `h(p_{k+1}) >= (1 - gamma) h(p_k)` for step `k`.
#[allow(clippy::result_unit_err, clippy::too_many_arguments)]
pub fn push_ldcbf_row<const N: usize, const NV: usize, const NC: usize>(
    qp: &mut DenseQp<NV, NC>,
    model: &Condensed<N>,
    hp: &HalfPlane,
    gamma: f64,
    delta: f64,
    k: usize,
    p0: &Vector2<f64>,
    v0: &Vector2<f64>,
) -> Result<(), ()> {
    // Quantity Q = -p_{k+1} + (1 - gamma) p_k, bound -gamma (eta'c + delta).
    let (w1, c1) = model.position(k + 1, p0, v0);
    let (w0, c0) = model.position(k, p0, v0);
    let w = -w1 + w0 * (1.0 - gamma);
    let q0 = -c1 + c0 * (1.0 - gamma);
    push_row(qp, &hp.eta, &w, &q0, -gamma * (hp.eta.dot(&hp.c) + delta))
}

/// Appends the foot-clearance row `eta'(f_k - c) >= delta_foot` for step `k`.
#[allow(clippy::result_unit_err)]
pub fn push_foot_row<const N: usize, const NV: usize, const NC: usize>(
    qp: &mut DenseQp<NV, NC>,
    hp: &HalfPlane,
    delta_foot: f64,
    k: usize,
) -> Result<(), ()> {
    let mut w = SVector::<f64, N>::zeros();
    w[k] = -1.0;
    push_row(
        qp,
        &hp.eta,
        &w,
        &Vector2::zeros(),
        -hp.eta.dot(&hp.c) - delta_foot,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

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
        for k in 1..=3 {
            let (w, c) = m.position(k, &p0, &v0);
            let p = c + f
                .iter()
                .enumerate()
                .fold(Vector2::zeros(), |acc, (j, fj)| acc + fj * w[j]);
            assert!((p - traj[k].0).amax() < 1e-14, "p_{k}");
            let wv = m.velocity_weights(k);
            let v = m.free_velocity(k, &p0, &v0)
                + f.iter()
                    .enumerate()
                    .fold(Vector2::zeros(), |acc, (j, fj)| acc + fj * wv[j]);
            assert!((v - traj[k].1).amax() < 1e-13, "v_{k}");
        }
        // Lower triangular with (1 - c) on the diagonal.
        assert_eq!(m.S_p[(0, 1)], 0.0);
        assert!((m.S_p[(1, 1)] - (1.0 - lip.cosh_bt)).abs() < 1e-15);
        assert!((m.S_v[(2, 2)] + lip.beta * lip.sinh_bt).abs() < 1e-15);
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
        let (q, c) = m.gradient::<6>(&p0, &v0, &goal);
        let u = u_of(&f);
        let quad = 0.5 * (h * u).dot(&u) + q.dot(&u) + c;
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
        let u = u_of(&f);
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
        // k = 0: reachability involves f_0 and the fixed p_0 only.
        let mut qp0 = DenseQp::<6, 16>::default();
        push_gait_rows(&mut qp0, &m, &b, 0, 0.0, 1.0, 0.0, &p0, &v0).unwrap();
        let r = qp0.row(4);
        assert_eq!(
            (r[0], r[1], r[2], r[3], r[4], r[5]),
            (1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        );
        assert!((qp0.h[4] - (b.l_max + p0.x)).abs() < 1e-15);
        // omega = 0: the merged row is the plain velocity bound.
        assert!((row_value(&qp0, 0, &u) - (traj[1].1.x - 0.8)).abs() < 1e-13);
    }

    #[test]
    fn ldcbf_and_foot_rows_equal_their_formulas() {
        let (lip, m) = model();
        let (p0, v0) = (Vector2::from(P0), Vector2::from(V0));
        let f = feet();
        let traj = rollout(&lip, p0, v0, &f);
        let u = u_of(&f);
        let hp = HalfPlane {
            c: Vector2::new(1.0, 1.0),
            eta: Vector2::new(-0.6, -0.8),
        };
        let (gamma, delta) = (0.3, 0.2);
        let mut qp = DenseQp::<6, 16>::default();
        for k in 0..3 {
            push_ldcbf_row(&mut qp, &m, &hp, gamma, delta, k, &p0, &v0).unwrap();
        }
        for k in 0..3 {
            // row value = -(h(p_{k+1}) - (1-gamma) h(p_k))
            let e = -(hp.h(&traj[k + 1].0, delta) - (1.0 - gamma) * hp.h(&traj[k].0, delta));
            assert!((row_value(&qp, k, &u) - e).abs() < 1e-13, "k={k}");
        }
        // gamma = 1: plain h(p_{k+1}) >= 0.
        let mut qp1 = DenseQp::<6, 16>::default();
        push_ldcbf_row(&mut qp1, &m, &hp, 1.0, delta, 1, &p0, &v0).unwrap();
        assert!((row_value(&qp1, 0, &u) + hp.h(&traj[2].0, delta)).abs() < 1e-13);
        let mut qpf = DenseQp::<6, 16>::default();
        push_foot_row::<3, 6, 16>(&mut qpf, &hp, 0.05, 2).unwrap();
        let e = -(hp.eta.dot(&(f[2] - hp.c)) - 0.05);
        assert!((row_value(&qpf, 0, &u) - e).abs() < 1e-14);
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
