//! The 3D linear inverted pendulum (LIP) with heading (docs/maths.md §1).
//!
//! Per horizontal axis, with stance foot `f`, during a step the CoM obeys
//! `p'' = beta^2 (p - f)`, `beta = sqrt(g / H)`. Over a duration `tau`, with
//! `c = cosh(beta tau)` and `s = sinh(beta tau)`:
//!
//! ```text
//! p+ = c p + (s / beta) v + (1 - c) f
//! v+ = beta s p + c v - beta s f
//! ```
//!
//! The step-to-step model is `x_{k+1} = A_L x_k + B_L u_k` with
//! `x = [p_x, v_x, p_y, v_y, theta]` (world frame W: m, m/s, rad) and
//! `u = [f_x, f_y, omega]` (m, m, rad/s), built from `A_d`, `B_d` at `tau = T`.
#![allow(non_snake_case)]

use nalgebra::{Matrix2, SMatrix, SVector, Vector2};

/// Physical parameters of the LIP and the precomputed step coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lip {
    /// `beta = sqrt(g / H)`, 1/s.
    pub beta: f64,
    /// Step duration `T`, s.
    pub step_duration: f64,
    /// `cosh(beta T)`.
    pub cosh_bt: f64,
    /// `sinh(beta T)`.
    pub sinh_bt: f64,
}

impl Lip {
    /// All-zero placeholder (`beta = T = 0`, not a model): for `const` and
    /// `static` initialisers, e.g. an unconfigured controller. Build real
    /// models with [`Lip::new`].
    pub const ZERO: Lip = Lip {
        beta: 0.0,
        step_duration: 0.0,
        cosh_bt: 0.0,
        sinh_bt: 0.0,
    };

    /// Builds the model for gravity `g` (m/s^2), CoM height `H` (m) and step
    /// duration `T` (s). The caller validates that all three are positive and finite.
    pub fn new(gravity: f64, com_height: f64, step_duration: f64) -> Self {
        let beta = crate::linalg::sqrt(gravity / com_height);
        Lip {
            beta,
            step_duration,
            cosh_bt: libm::cosh(beta * step_duration),
            sinh_bt: libm::sinh(beta * step_duration),
        }
    }

    /// Closed-form flow of one axis over `tau` seconds with stance foot at `f`:
    /// returns `(p, v)` at the end. Units: m, m/s, s.
    pub fn propagate_axis(&self, p: f64, v: f64, f: f64, tau: f64) -> (f64, f64) {
        let c = libm::cosh(self.beta * tau);
        let s = libm::sinh(self.beta * tau);
        (
            c * p + (s / self.beta) * v + (1.0 - c) * f,
            self.beta * s * p + c * v - self.beta * s * f,
        )
    }

    /// Closed-form flow of both axes (world frame) over `tau` seconds with stance
    /// foot `f`: returns `(p, v)` at the end.
    pub fn propagate(
        &self,
        p: &Vector2<f64>,
        v: &Vector2<f64>,
        f: &Vector2<f64>,
        tau: f64,
    ) -> (Vector2<f64>, Vector2<f64>) {
        let (px, vx) = self.propagate_axis(p.x, v.x, f.x, tau);
        let (py, vy) = self.propagate_axis(p.y, v.y, f.y, tau);
        (Vector2::new(px, py), Vector2::new(vx, vy))
    }

    /// `A_d = [[c, s/beta], [beta s, c]]` at `tau = T` (state `(p, v)` of one axis).
    pub fn A_d(&self) -> Matrix2<f64> {
        Matrix2::new(
            self.cosh_bt,
            self.sinh_bt / self.beta,
            self.beta * self.sinh_bt,
            self.cosh_bt,
        )
    }

    /// `B_d = [1 - c, -beta s]` at `tau = T` (input: the stance foot of one axis).
    pub fn B_d(&self) -> Vector2<f64> {
        Vector2::new(1.0 - self.cosh_bt, -self.beta * self.sinh_bt)
    }

    /// `A_L = blkdiag(A_d, A_d, 1)` for `x = [p_x, v_x, p_y, v_y, theta]`.
    pub fn A_L(&self) -> SMatrix<f64, 5, 5> {
        let mut a = SMatrix::<f64, 5, 5>::zeros();
        let ad = self.A_d();
        a.fixed_view_mut::<2, 2>(0, 0).copy_from(&ad);
        a.fixed_view_mut::<2, 2>(2, 2).copy_from(&ad);
        a[(4, 4)] = 1.0;
        a
    }

    /// `B_L = blkdiag(B_d, B_d, T)` for `u = [f_x, f_y, omega]`.
    pub fn B_L(&self) -> SMatrix<f64, 5, 3> {
        let mut b = SMatrix::<f64, 5, 3>::zeros();
        let bd = self.B_d();
        b.fixed_view_mut::<2, 1>(0, 0).copy_from(&bd);
        b.fixed_view_mut::<2, 1>(2, 1).copy_from(&bd);
        b[(4, 2)] = self.step_duration;
        b
    }

    /// One step of the step-to-step model: `x_{k+1} = A_L x_k + B_L u_k`.
    pub fn step(&self, x: &SVector<f64, 5>, u: &SVector<f64, 3>) -> SVector<f64, 5> {
        self.A_L() * x + self.B_L() * u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> Lip {
        Lip::new(9.81, 1.0, 0.4)
    }

    #[test]
    fn coefficients_match_hand_values() {
        let m = paper();
        // beta = sqrt(9.81) = 3.132091952673165; beta T = 1.252836781069266
        assert!((m.beta - 3.132_091_952_673_165).abs() < 1e-14);
        // cosh(1.252836781069266) = 1.8930..., sinh = 1.6073... (computed by hand
        // from e^x = 3.50009...: (e^x + e^-x)/2, (e^x - e^-x)/2)
        let ex = libm::exp(1.252_836_781_069_266);
        assert!((m.cosh_bt - 0.5 * (ex + 1.0 / ex)).abs() < 1e-14);
        assert!((m.sinh_bt - 0.5 * (ex - 1.0 / ex)).abs() < 1e-14);
        assert!((m.cosh_bt - 1.893_0).abs() < 1e-3);
        assert!((m.sinh_bt - 1.607_3).abs() < 1e-3);
        let ad = m.A_d();
        assert_eq!(ad[(0, 0)], m.cosh_bt);
        assert!((ad[(0, 1)] - m.sinh_bt / m.beta).abs() < 1e-15);
        assert!((ad[(1, 0)] - m.beta * m.sinh_bt).abs() < 1e-15);
        // det(A_d) = c^2 - s^2 = 1
        assert!((ad.determinant() - 1.0).abs() < 1e-13);
        let bd = m.B_d();
        assert!((bd[0] - (1.0 - m.cosh_bt)).abs() < 1e-15);
        assert!((bd[1] + m.beta * m.sinh_bt).abs() < 1e-15);
    }

    #[test]
    fn flow_matches_ode_solution() {
        // p(t) = f + A e^{bt} + B e^{-bt}; check against the closed form.
        let m = paper();
        let (p0, v0, f, tau) = (0.3, -0.2, 0.1, 0.27);
        let a = 0.5 * ((p0 - f) + v0 / m.beta);
        let b = 0.5 * ((p0 - f) - v0 / m.beta);
        let e = libm::exp(m.beta * tau);
        let p_exact = f + a * e + b / e;
        let v_exact = m.beta * (a * e - b / e);
        let (p, v) = m.propagate_axis(p0, v0, f, tau);
        assert!((p - p_exact).abs() < 1e-14);
        assert!((v - v_exact).abs() < 1e-14);
        // Fixed point: CoM over the foot at rest stays.
        assert_eq!(m.propagate_axis(0.5, 0.0, 0.5, 0.4), (0.5, 0.0));
    }

    #[test]
    fn step_model_equals_flow_over_t() {
        let m = paper();
        let x = SVector::<f64, 5>::from([0.1, 0.2, -0.3, 0.05, 0.7]);
        let u = SVector::<f64, 3>::from([0.15, -0.25, 0.3]);
        let xn = m.step(&x, &u);
        let (px, vx) = m.propagate_axis(0.1, 0.2, 0.15, 0.4);
        let (py, vy) = m.propagate_axis(-0.3, 0.05, -0.25, 0.4);
        assert!((xn[0] - px).abs() < 1e-15 && (xn[1] - vx).abs() < 1e-15);
        assert!((xn[2] - py).abs() < 1e-15 && (xn[3] - vy).abs() < 1e-15);
        assert!((xn[4] - (0.7 + 0.3 * 0.4)).abs() < 1e-15);
    }
}
