//! The set a person can reach over the horizon (docs/maths.md §2.7): an
//! obstacle whose velocity is known only up to a radius `u` around an
//! estimate `v_hat`, who walks at most `v_max` and accelerates at most
//! `a_max`, is after `t` seconds somewhere in the intersection of two disks
//! (world frame W, metres, seconds):
//!
//! * the disk of radius [`Reach::radius`] `r(t)` around where the estimate
//!   puts it, `x(0) + v_hat t`: its velocity strays from `v_hat` by at most
//!   `min(u + a_max s, v_max + |v_hat|)` at time `s`, and `r(t)` is that
//!   bound's integral;
//! * the disk of radius `v_max t` around where it is now, `x(0)`.
//!
//! Along a unit normal `eta` (from the obstacle to the robot) the set
//! reaches at most [`Reach::shift`]`(eta'v_hat, t) = min(eta'v_hat t +
//! r(t), v_max t)` beyond where the obstacle is now: the barrier's
//! half-plane moves by that much ([`crate::HalfPlane::h_at`]).
//!
//! The set grows over [`ReachLimits::grow`] seconds
//! ([`Config::person_reach_time`](crate::mpc::Config::person_reach_time)):
//! after that its radius stays `r(grow)` and it travels with the estimate.
//! The default grows it over the whole horizon; a shorter time (0.8 s: the
//! step being taken and the one that can stop the robot) stops the rows of a
//! person standing still from asking the robot to back away within 2.5 m,
//! but measured on unseen seeds it let the robot walk into people
//! (docs/maths.md §2.7).

/// What is known of an obstacle's velocity, for the set it can reach
/// (module docs). `spread = 0` is an obstacle whose velocity is known and
/// constant ([`Reach::NONE`]): it reaches only its predicted path. The
/// bounds every person shares are the [`ReachLimits`] (from the
/// configuration), passed to each method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// `u`: the radius around the estimate that holds the true velocity,
    /// m/s (world frame), `>= 0`.
    pub spread: f64,
    /// `|v_hat|`: the estimated speed, m/s.
    pub speed: f64,
}

/// The bounds of every person of uncertain velocity (module docs;
/// [`Config::reach_limits`](crate::mpc::Config::reach_limits)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReachLimits {
    /// `v_max`: the largest speed, m/s, `> 0`
    /// ([`Config::person_speed_max`](crate::mpc::Config::person_speed_max)).
    pub speed_max: f64,
    /// `a_max`: the largest acceleration, m/s^2, `>= 0`
    /// ([`Config::person_accel_max`](crate::mpc::Config::person_accel_max)).
    pub accel: f64,
    /// The time over which the set grows, s (finite, `> 0`): beyond it its
    /// radius stays `r(grow)` (module docs;
    /// [`Config::person_reach_time`](crate::mpc::Config::person_reach_time)).
    pub grow: f64,
}

impl Reach {
    /// A known, constant velocity: no spread, the predicted path alone.
    pub const NONE: Reach = Reach {
        spread: 0.0,
        speed: 0.0,
    };

    /// Whether the velocity is uncertain (`spread > 0`): otherwise the set is
    /// the predicted path alone and [`Reach::shift`] is not used.
    pub fn is_uncertain(&self) -> bool {
        self.spread > 0.0
    }

    /// `r(t)`, m: the radius around the predicted position `x(0) + v_hat t`
    /// that holds every position reachable at time `t` (s, `>= 0`; 0 before).
    /// With `w = v_max + |v_hat|` (the largest difference between a velocity
    /// of speed at most `v_max` and `v_hat`) and `u' = min(u, w)`: `u' t +
    /// a_max t^2 / 2` up to `t* = (w - u') / a_max`, then `w t - (w -
    /// u')^2 / (2 a_max)`; `u' t` when `a_max = 0` or `u' = w`. Beyond
    /// [`ReachLimits::grow`] it stays `r(grow)`.
    // Not inlined: one copy in the firmware's flash (64 KiB), not one per row.
    #[inline(never)]
    pub fn radius(&self, lim: &ReachLimits, t: f64) -> f64 {
        if t.is_nan() || t <= 0.0 {
            return 0.0;
        }
        let t = if t > lim.grow { lim.grow } else { t };
        let w = lim.speed_max + self.speed;
        let u = self.spread.min(w);
        let gap = w - u;
        if !(gap > 0.0 && lim.accel > 0.0) {
            return u * t;
        }
        if t * lim.accel <= gap {
            u * t + 0.5 * lim.accel * t * t
        } else {
            w * t - 0.5 * gap * gap / lim.accel
        }
    }

    /// How far the set reaches along a unit normal `eta` beyond the
    /// obstacle's position now, at time `t` (s), m: `min(rate t + r(t),
    /// v_max t)` with `rate = eta'v_hat` (m/s).
    // Not inlined: one copy in the firmware's flash (64 KiB), not one per row.
    #[inline(never)]
    pub fn shift(&self, lim: &ReachLimits, rate: f64, t: f64) -> f64 {
        let t = if t > 0.0 { t } else { 0.0 };
        let predicted = rate * t + self.radius(lim, t);
        let farthest = lim.speed_max * t;
        if predicted < farthest {
            predicted
        } else {
            farthest
        }
    }

    /// The largest of [`Reach::shift`] over the times `[t0, t1]` (s), or a
    /// bound above it, m: `min(max(f(t0), f(t1), f(grow)), v_max t1)` with
    /// `f(t) = rate t + r(t)`, which is convex up to [`ReachLimits::grow`]
    /// and affine after it (so its largest value on the interval is at an end
    /// or at `grow`, counted when inside) while `v_max t` grows.
    // Not inlined: one copy in the firmware's flash (64 KiB), not one per row.
    #[inline(never)]
    pub fn shift_over(&self, lim: &ReachLimits, rate: f64, (t0, t1): (f64, f64)) -> f64 {
        let t0 = if t0 > 0.0 { t0 } else { 0.0 };
        let t1 = if t1 > t0 { t1 } else { t0 };
        let f = |t: f64| rate * t + self.radius(lim, t);
        let (a, b) = (f(t0), f(t1));
        let mut predicted = if a > b { a } else { b };
        if t0 < lim.grow && lim.grow < t1 {
            let c = f(lim.grow);
            if c > predicted {
                predicted = c;
            }
        }
        let farthest = lim.speed_max * t1;
        if predicted < farthest {
            predicted
        } else {
            farthest
        }
    }

    /// The farthest the obstacle gets from where it is now within `t` (s),
    /// in any direction, as the set of [`Reach::shift`] goes, m:
    /// `min(|v_hat| t + r(t), v_max t)`.
    pub fn travel(&self, lim: &ReachLimits, t: f64) -> f64 {
        self.shift(lim, self.speed, t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;
    use proptest::prelude::*;

    /// No cap within the tests' times.
    const LIM: ReachLimits = ReachLimits {
        speed_max: 1.5,
        accel: 1.0,
        grow: 1e6,
    };

    fn reach(spread: f64, speed: f64) -> Reach {
        Reach { spread, speed }
    }

    #[test]
    fn the_radius_grows_as_the_acceleration_allows_then_at_the_largest_gap() {
        // u = 0.3, |v_hat| = 0.5: w = 2, t* = 1.7 s.
        let r = reach(0.3, 0.5);
        assert_eq!(r.radius(&LIM, 0.0), 0.0);
        assert_eq!(r.radius(&LIM, -1.0), 0.0);
        assert!((r.radius(&LIM, 1.0) - (0.3 + 0.5)).abs() < 1e-15);
        let t_star = 1.7;
        let at = 0.3 * t_star + 0.5 * t_star * t_star;
        assert!((r.radius(&LIM, t_star) - at).abs() < 1e-12);
        // Beyond t*, it grows at w.
        assert!((r.radius(&LIM, 3.0) - (at + 2.0 * (3.0 - t_star))).abs() < 1e-12);
        // A spread at least w: w t from the start.
        assert_eq!(reach(5.0, 0.5).radius(&LIM, 2.0), 4.0);
        // No acceleration: u t.
        let still = ReachLimits { accel: 0.0, ..LIM };
        assert!((reach(0.3, 0.5).radius(&still, 2.0) - 0.6).abs() < 1e-15);
    }

    #[test]
    fn the_shift_is_capped_by_the_largest_speed() {
        // An unconfirmed cluster: at rest, spread at the walking speed.
        let r = reach(1.5, 0.0);
        for t in [0.0, 0.4, 0.8, 1.6] {
            assert!((r.shift(&LIM, 0.0, t) - 1.5 * t).abs() < 1e-15, "{t}");
        }
        // Walking at 1 m/s towards the robot: the predicted path plus r(t),
        // never more than v_max t.
        let r = reach(0.1, 1.0);
        let s = r.shift(&LIM, 1.0, 0.4);
        assert!((s - (0.4 + 0.04 + 0.08)).abs() < 1e-12, "{s}");
        assert!((r.shift(&LIM, 1.0, 2.0) - 3.0).abs() < 1e-12);
        // Away from the robot: still up to the reach of a turn back.
        assert!(r.shift(&LIM, -1.0, 1.0) > -1.0 && r.shift(&LIM, -1.0, 1.0) < 0.0);
        assert_eq!(r.travel(&LIM, 0.0), 0.0);
    }

    #[test]
    fn the_shift_over_a_step_bounds_the_shift_inside_it() {
        let capped = ReachLimits { grow: 0.5, ..LIM };
        let r = reach(0.2, 1.2);
        for lim in [LIM, capped] {
            for rate in [-1.2, -0.6, 0.0, 0.7, 1.2] {
                let over = r.shift_over(&lim, rate, (0.3, 0.7));
                for k in 0..=100 {
                    let t = 0.3 + 0.4 * f64::from(k) / 100.0;
                    assert!(r.shift(&lim, rate, t) <= over + 1e-12, "{rate} {t}");
                }
            }
        }
    }

    #[test]
    fn the_set_grows_until_its_grow_time_then_travels_with_the_estimate() {
        let r = reach(0.47, 0.0);
        let capped = ReachLimits { grow: 0.8, ..LIM };
        for t in [0.0, 0.2, 0.5, 0.8] {
            assert_eq!(r.radius(&capped, t), r.radius(&LIM, t), "{t}");
        }
        for t in [0.9, 1.6, 3.0] {
            assert_eq!(r.radius(&capped, t), r.radius(&LIM, 0.8), "{t}");
            assert!(r.radius(&capped, t) < r.radius(&LIM, t));
        }
        // Receding at 1 m/s: the shift peaks at the grow time, and the shift
        // over a step around it counts that peak.
        let r = reach(0.47, 1.0);
        let peak = r.shift(&capped, -1.0, 0.8);
        assert!(peak > r.shift(&capped, -1.0, 0.6) && peak > r.shift(&capped, -1.0, 1.0));
        let over = r.shift_over(&capped, -1.0, (0.6, 1.0));
        assert!(over >= peak && over <= peak + 1e-15, "{over} {peak}");
    }

    proptest! {
        /// A person whose speed and acceleration stay within the bounds and
        /// whose velocity starts within `u` of the estimate stays, every
        /// 0.05 s up to the grow time (at most 2 s), within `r(t)` of the
        /// predicted position, within `travel(t)` of where they are now and
        /// within `shift(eta'v_hat, t)` of it along any normal `eta`. The walk: random accelerations (each held for 0.05 s,
        /// integrated exactly) scaled to `a_max` and clipped to keep the speed
        /// within `v_max`, from a random start velocity in the disk.
        #[test]
        fn the_person_stays_inside_the_predicted_set(
            v_hat in (0.0f64..1.5, 0.0f64..core::f64::consts::TAU),
            spread in 0.0f64..2.0,
            start in (0.0f64..1.0, 0.0f64..core::f64::consts::TAU),
            accel in 0.0f64..2.0,
            pushes in proptest::collection::vec((0.0f64..1.0, 0.0f64..core::f64::consts::TAU), 40),
            normal in 0.0f64..core::f64::consts::TAU,
            grow in 0.05f64..2.5,
        ) {
            let speed_max = 1.5;
            let v_hat = Vector2::new(v_hat.1.cos(), v_hat.1.sin()) * v_hat.0;
            let reach = Reach { spread, speed: v_hat.norm() };
            let lim = ReachLimits { speed_max, accel, grow };
            // True start velocity: within `spread` of v_hat, then projected
            // onto the disk of speed v_max (which holds v_hat: the projection
            // keeps it within `spread` of v_hat).
            let mut v = v_hat + Vector2::new(start.1.cos(), start.1.sin()) * (start.0 * spread);
            if v.norm() > speed_max {
                v *= speed_max / v.norm();
            }
            prop_assert!((v - v_hat).norm() <= spread + 1e-12);
            let eta = Vector2::new(normal.cos(), normal.sin());
            let dt = 0.05;
            let mut x = Vector2::zeros();
            let mut t = 0.0;
            for (mag, dir) in &pushes {
                let a = Vector2::new(dir.cos(), dir.sin()) * (mag * accel);
                // Exact integration of a constant acceleration over dt; the
                // speed bound is kept by shortening the push where it would
                // break it (the speed is convex along the step).
                // (Projecting the end velocity onto the disk of v_max, which
                // holds `v`, shortens the push: still within a_max.)
                let mut a_used = a;
                let v_end = v + a * dt;
                if v_end.norm() > speed_max {
                    a_used = (v_end * (speed_max / v_end.norm()) - v) / dt;
                }
                prop_assert!(a_used.norm() <= accel + 1e-9);
                x += v * dt + a_used * (0.5 * dt * dt);
                v += a_used * dt;
                t += dt;
                let predicted = v_hat * t;
                if t > grow {
                    break;
                }
                prop_assert!((x - predicted).norm() <= reach.radius(&lim, t) + 1e-9,
                    "t {t}: off by {} > r {}", (x - predicted).norm(), reach.radius(&lim, t));
                prop_assert!(x.norm() <= reach.travel(&lim, t) + 1e-9,
                    "t {t}: {} beyond the travel {}", x.norm(), reach.travel(&lim, t));
                let along = eta.dot(&x);
                prop_assert!(along <= reach.shift(&lim, eta.dot(&v_hat), t) + 1e-9,
                    "t {t}: {along} beyond {}", reach.shift(&lim, eta.dot(&v_hat), t));
            }
        }
    }
}
