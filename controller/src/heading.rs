//! Heading pre-processing (docs/maths.md §2.2): the turning rate is fixed before the QP so
//! every constraint is linear.
//!
//! `theta* = atan2(g_y - p_y0, g_x - p_x0)`, `d = wrap(theta* - theta_0)` in
//! `(-pi, pi]`, `omega_bar = clamp(d / (N T), -omega_max, omega_max)`, the same for
//! every step of the horizon, and `theta_{k+1} = theta_k + omega_bar T`.
//!
//! Near the goal the bearing `theta*` is ill-conditioned (it swings by up to pi for
//! centimetre moves), so within `freeze_radius` of the goal the heading is frozen:
//! `omega_bar = 0`.

use core::f64::consts::PI;

/// Wraps an angle (rad) into `(-pi, pi]`. `pi` stays `pi`, `-pi` becomes `pi`.
/// A non-finite input gives NaN.
pub fn wrap_angle(a: f64) -> f64 {
    if !a.is_finite() {
        return f64::NAN;
    }
    let mut r = rem_two_pi(a + PI);
    if r <= 0.0 {
        r += 2.0 * PI;
    }
    r - PI
}

/// `fmod(x, 2 pi)`, exactly (the remainder of a floating-point
/// division is always representable, so this is bit for bit `libm::fmod(x, 2.0
/// * PI)`; the sign is `x`'s).
///
/// Binary long division: subtract `y 2^j` for `j` from the largest with `y 2^j
/// <= |x|` down to 0. Each subtraction has `t <= r < 2t`, so it is exact
/// (Sterbenz), and doubling or halving `t >= y` is exact. At most about 1024
/// doublings and as many halvings for `|x|` near `f64::MAX`; 0 to 2 of each
/// for the headings the controller sees. Replaces `libm::fmod`, whose general
/// form (any divisor, subnormals) took 2.9 KiB of the Cortex-M7 firmware's flash
/// with its 64-bit division.
fn rem_two_pi(x: f64) -> f64 {
    let y = 2.0 * PI;
    if !x.is_finite() {
        // (fmod's result; it also keeps the doubling below finite.)
        return f64::NAN;
    }
    let ax = x.abs();
    if ax < y {
        // |x| < 2 pi: the remainder is x itself.
        return x;
    }
    let mut t = y;
    while t <= 0.5 * ax {
        t *= 2.0;
    }
    let mut r = ax;
    loop {
        if r >= t {
            r -= t;
        }
        if t <= y {
            break;
        }
        t *= 0.5;
    }
    r.copysign(x)
}

/// The fixed headings over the horizon. Angles in rad, world frame, measured from
/// the world x axis counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadingPlan<const N: usize> {
    /// Turning rate used for the whole horizon, rad/s.
    pub omega_bar: f64,
    /// `theta_0 .. theta_{N-1}`: heading during step `k` (rows of step k use it).
    pub theta: [f64; N],
    /// `theta_N`, the heading at the end of the horizon.
    pub theta_end: f64,
}

/// Computes the heading plan from the predicted heading `theta0` (rad) and position
/// `p0` (m, world) at the start of step 0, the goal (m, world), the step duration
/// `step_duration` (s), the bound `omega_max` (rad/s) and the freeze radius (m).
pub fn plan_heading<const N: usize>(
    theta0: f64,
    p0: [f64; 2],
    goal: [f64; 2],
    step_duration: f64,
    omega_max: f64,
    freeze_radius: f64,
) -> HeadingPlan<N> {
    let (dx, dy) = (goal[0] - p0[0], goal[1] - p0[1]);
    let omega_bar = if libm::hypot(dx, dy) <= freeze_radius {
        0.0
    } else {
        let d = wrap_angle(libm::atan2(dy, dx) - theta0);
        crate::linalg::clamp(d / (N as f64 * step_duration), -omega_max, omega_max)
    };
    let mut theta = [0.0; N];
    let mut th = theta0;
    for t in theta.iter_mut() {
        *t = th;
        th += omega_bar * step_duration;
    }
    HeadingPlan {
        omega_bar,
        theta,
        theta_end: th,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rem_two_pi_is_libm_fmod_bit_for_bit() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            state
        };
        let check = |x: f64| {
            assert_eq!(
                rem_two_pi(x).to_bits(),
                libm::fmod(x, 2.0 * PI).to_bits(),
                "x = {x:e}"
            );
        };
        for x in [
            0.0,
            -0.0,
            PI,
            -PI,
            2.0 * PI,
            -2.0 * PI,
            4.0 * PI,
            6.0 * PI,
            -6.0 * PI,
            2.0 * PI * (1.0 + f64::EPSILON),
            2.0 * PI * (1.0 - f64::EPSILON / 2.0),
            1e-320,
            f64::MAX,
            -f64::MAX,
            f64::MIN_POSITIVE,
        ] {
            check(x);
        }
        for _ in 0..200_000 {
            // Uniform over the exponents of |x| in [2^-20, 2^1024), both signs,
            // and the headings' range.
            let bits = next();
            let exp = 1003 + (bits >> 53) % 1044;
            let x = f64::from_bits((exp << 52) | (bits & ((1 << 52) - 1)));
            check(x);
            check(-x);
            check((next() >> 11) as f64 / (1u64 << 53) as f64 * 40.0 - 20.0);
        }
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(rem_two_pi(x).is_nan() && libm::fmod(x, 2.0 * PI).is_nan());
        }
    }

    #[test]
    fn wrap_is_half_open_at_pi() {
        assert_eq!(wrap_angle(PI), PI);
        assert_eq!(wrap_angle(-PI), PI);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(-3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(-PI + 1e-9) - (-PI + 1e-9)).abs() < 1e-12);
        assert!((wrap_angle(1.5 * PI) - (-0.5 * PI)).abs() < 1e-12);
        assert!((wrap_angle(-1.5 * PI) - 0.5 * PI).abs() < 1e-12);
        assert_eq!(wrap_angle(0.0), 0.0);
        assert!(wrap_angle(f64::NAN).is_nan());
        assert!(wrap_angle(f64::INFINITY).is_nan());
        for i in -100..100 {
            let a = i as f64 * 0.37;
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI);
            assert!((libm::sin(w) - libm::sin(a)).abs() < 1e-12);
            assert!((libm::cos(w) - libm::cos(a)).abs() < 1e-12);
        }
    }

    #[test]
    fn plan_clamps_and_accumulates() {
        let om = 0.156 * PI;
        // Goal straight behind-left: d = 3/4 pi, d/(3*0.4) = 1.96 > om -> clamped.
        let h = plan_heading::<3>(0.0, [0.0, 0.0], [-1.0, 1.0], 0.4, om, 0.3);
        assert_eq!(h.omega_bar, om);
        assert_eq!(h.theta[0], 0.0);
        assert!((h.theta[1] - om * 0.4).abs() < 1e-15);
        assert!((h.theta[2] - 2.0 * om * 0.4).abs() < 1e-15);
        assert!((h.theta_end - 3.0 * om * 0.4).abs() < 1e-15);
        // Small correction, unclamped: goal at bearing 0.3 rad, heading 0.
        let g = [libm::cos(0.3) * 5.0, libm::sin(0.3) * 5.0];
        let h = plan_heading::<3>(0.0, [0.0, 0.0], g, 0.4, om, 0.3);
        assert!((h.omega_bar - 0.3 / 1.2).abs() < 1e-14);
        // Wrap across pi: heading 3.0, goal bearing -3.0 -> d = 2pi - 6 > 0 (left).
        let g = [libm::cos(-3.0), libm::sin(-3.0)];
        let h = plan_heading::<3>(3.0, [0.0, 0.0], g, 0.4, om, 0.3);
        assert!((h.omega_bar - (2.0 * PI - 6.0) / 1.2).abs() < 1e-12);
        // Frozen near the goal.
        let h = plan_heading::<3>(1.0, [0.0, 0.0], [0.1, -0.2], 0.4, om, 0.3);
        assert_eq!(h.omega_bar, 0.0);
        assert_eq!(h.theta, [1.0; 3]);
    }
}
