//! The simulated robot: the continuous 3D-LIP of docs/maths.md §1, integrated in
//! closed form on a fixed tick (1 ms by default).
//!
//! State (world frame W, SI units): CoM position `p` (m) and velocity `v` (m/s),
//! heading `theta` (rad, counter-clockwise from the world x axis, not wrapped),
//! the turning rate in force during the current step (rad/s), the stance foot
//! (position, side) and the number of ticks already spent in the current step.
//!
//! During a step, per axis, `p'' = beta^2 (p - f)` with `f` the stance foot;
//! one tick of `dt` is the exact flow
//! `p+ = c p + (s/beta) v + (1 - c) f`, `v+ = beta s p + c v - beta s f` with
//! `c = cosh(beta dt)`, `s = sinh(beta dt)`. The plant computes this itself
//! (not through the controller's code) so that it is an independent check of the
//! controller's prediction.
//!
//! Step events: a step lasts exactly `ticks_per_step` ticks (`T / dt`, which must
//! be an integer). At the end of a step the caller lands the swing foot with
//! [`Plant::land`]: the landed foot becomes the stance foot, the stance side
//! flips, the tick counter of the step restarts at 0 and the turning rate of the
//! new step takes effect. The heading integrates the turning rate in force at
//! every tick (`theta += omega dt`).
//!
//! The room also holds what is done to the plant and to the controller's
//! measurement that the controller's model does not predict ([`disturbance`]).
//! It depends on no other room; the scenario reads its `[disturbance]`
//! settings, the closed loop ([`crate::sim`]) drives it.

use ldcbf_controller::Side;
use ldcbf_controller::nalgebra::Vector2;

pub mod disturbance;

/// Physical parameters of the plant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantParams {
    /// Gravity `g`, m/s^2.
    pub gravity: f64,
    /// CoM height `H`, m.
    pub com_height: f64,
    /// Step duration `T`, s (a whole number of ticks).
    pub step_duration: f64,
    /// Integration tick `dt`, s (1e-3 for the 1 kHz plant).
    pub dt: f64,
}

/// Why [`PlantParams`] are not usable.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlantError {
    /// A parameter is not finite or not positive (m/s^2, m, s, s).
    #[error(
        "plant parameters must be finite and > 0 (g = {gravity}, H = {com_height}, T = {step_duration}, dt = {dt})"
    )]
    NotPositive {
        /// `gravity`, m/s^2.
        gravity: f64,
        /// `com_height`, m.
        com_height: f64,
        /// `step_duration`, s.
        step_duration: f64,
        /// `dt`, s.
        dt: f64,
    },
    /// `step_duration` is not a whole number of ticks `dt` (both s).
    #[error("step duration {step_duration} s is not a whole number of plant ticks of {dt} s")]
    StepNotWholeTicks {
        /// `step_duration`, s.
        step_duration: f64,
        /// `dt`, s.
        dt: f64,
    },
}

/// The LIP plant (see the module docs).
#[derive(Clone, Debug)]
pub struct Plant {
    /// CoM position, m (world).
    pub position: Vector2<f64>,
    /// CoM velocity, m/s (world).
    pub velocity: Vector2<f64>,
    /// Heading, rad (world, accumulated, not wrapped).
    pub heading: f64,
    /// Turning rate in force during the current step, rad/s.
    pub turning_rate: f64,
    /// Current stance foot, m (world).
    pub stance_foot: Vector2<f64>,
    /// Which foot is the stance foot.
    pub stance_side: Side,
    /// Ticks already spent in the current step, `0..=ticks_per_step`.
    pub tick_in_step: u32,
    /// Ticks since the start of the run.
    pub tick: u64,
    /// Completed steps (landings) since the start.
    pub steps: u32,
    ticks_per_step: u32,
    dt: f64,
    beta: f64,
    cosh_dt: f64,
    sinh_dt: f64,
}

impl Plant {
    /// A plant at rest: CoM at `position` with zero velocity, heading `heading`
    /// (rad), stance foot `stance_side` directly under the CoM (an equilibrium of
    /// the LIP), turning rate 0, at the start of a step.
    pub fn new(
        params: PlantParams,
        position: Vector2<f64>,
        heading: f64,
        stance_side: Side,
    ) -> Result<Self, PlantError> {
        let PlantParams {
            gravity,
            com_height,
            step_duration,
            dt,
        } = params;
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(gravity) && ok(com_height) && ok(step_duration) && ok(dt)) {
            return Err(PlantError::NotPositive {
                gravity,
                com_height,
                step_duration,
                dt,
            });
        }
        let ratio = step_duration / dt;
        let ticks = ratio.round();
        if (ratio - ticks).abs() > 1e-6 || ticks < 1.0 || ticks > f64::from(u32::MAX) {
            return Err(PlantError::StepNotWholeTicks { step_duration, dt });
        }
        let beta = (gravity / com_height).sqrt();
        Ok(Plant {
            position,
            velocity: Vector2::zeros(),
            heading,
            turning_rate: 0.0,
            stance_foot: position,
            stance_side,
            tick_in_step: 0,
            tick: 0,
            steps: 0,
            ticks_per_step: ticks as u32,
            dt,
            beta,
            cosh_dt: (beta * dt).cosh(),
            sinh_dt: (beta * dt).sinh(),
        })
    }

    /// Tick length, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Ticks per step, `T / dt`.
    pub fn ticks_per_step(&self) -> u32 {
        self.ticks_per_step
    }

    /// `beta = sqrt(g / H)`, 1/s.
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// Time since the start, s.
    pub fn time(&self) -> f64 {
        self.tick as f64 * self.dt
    }

    /// Time already spent in the current step, s, in `[0, T]`.
    pub fn time_in_step(&self) -> f64 {
        f64::from(self.tick_in_step) * self.dt
    }

    /// True when the current step is over and the swing foot must land.
    pub fn step_over(&self) -> bool {
        self.tick_in_step >= self.ticks_per_step
    }

    /// Advances one tick: exact LIP flow over `dt` with the current stance foot;
    /// the heading integrates the turning rate in force.
    pub fn tick(&mut self) {
        let (c, s, b) = (self.cosh_dt, self.sinh_dt, self.beta);
        let (p, v, f) = (self.position, self.velocity, self.stance_foot);
        self.position = p * c + v * (s / b) + f * (1.0 - c);
        self.velocity = p * (b * s) + v * c - f * (b * s);
        self.heading += self.turning_rate * self.dt;
        self.tick += 1;
        self.tick_in_step += 1;
    }

    /// A push: adds `delta_v` (m/s, world) to the CoM velocity at once (the
    /// position is continuous). Used by [`crate::plant::disturbance`].
    pub fn push(&mut self, delta_v: Vector2<f64>) {
        self.velocity += delta_v;
    }

    /// Ends the current step: the swing foot lands at `foot` (m, world) and becomes
    /// the stance foot, the stance side flips, the step clock restarts and
    /// `turning_rate` (rad/s) is in force during the new step.
    pub fn land(&mut self, foot: Vector2<f64>, turning_rate: f64) {
        self.stance_foot = foot;
        self.stance_side = self.stance_side.opposite();
        self.tick_in_step = 0;
        self.turning_rate = turning_rate;
        self.steps += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ldcbf_controller::Lip;

    fn params() -> PlantParams {
        PlantParams {
            gravity: 9.81,
            com_height: 1.0,
            step_duration: 0.4,
            dt: 1e-3,
        }
    }

    #[test]
    fn rest_over_the_stance_foot_is_an_equilibrium() {
        let mut p = Plant::new(params(), Vector2::new(1.0, 2.0), 0.3, Side::Left).unwrap();
        for _ in 0..400 {
            p.tick();
        }
        assert!(p.step_over());
        assert_eq!(p.position, Vector2::new(1.0, 2.0));
        assert_eq!(p.velocity, Vector2::zeros());
        assert_eq!(p.heading, 0.3);
    }

    #[test]
    fn ticks_compose_to_the_step_flow() {
        let mut p = Plant::new(params(), Vector2::new(0.0, 0.0), 0.0, Side::Left).unwrap();
        p.velocity = Vector2::new(0.3, -0.2);
        p.stance_foot = Vector2::new(0.05, 0.1);
        p.turning_rate = 0.2;
        let lip = Lip::new(9.81, 1.0, 0.4);
        let (pe, ve) = lip.propagate(&p.position, &p.velocity, &p.stance_foot, 0.4);
        for _ in 0..400 {
            p.tick();
        }
        assert!(
            (p.position - pe).amax() < 1e-12,
            "{:?} {:?}",
            p.position,
            pe
        );
        assert!((p.velocity - ve).amax() < 1e-12);
        assert!((p.heading - 0.08).abs() < 1e-12);
        p.land(Vector2::new(0.4, -0.1), -0.1);
        assert_eq!(p.stance_side, Side::Right);
        assert_eq!(p.tick_in_step, 0);
        assert_eq!(p.steps, 1);
    }

    #[test]
    fn push_adds_the_impulse_and_the_flow_goes_on_from_it() {
        let mut p = Plant::new(params(), Vector2::new(0.0, 0.0), 0.0, Side::Left).unwrap();
        p.velocity = Vector2::new(0.2, 0.1);
        let before = (p.position, p.velocity);
        p.push(Vector2::new(0.0, 0.3));
        assert_eq!(p.position, before.0);
        assert_eq!(p.velocity, before.1 + Vector2::new(0.0, 0.3));
        // Same as a plant started with the pushed velocity.
        let mut q = Plant::new(params(), Vector2::new(0.0, 0.0), 0.0, Side::Left).unwrap();
        q.velocity = Vector2::new(0.2, 0.1) + Vector2::new(0.0, 0.3);
        for _ in 0..100 {
            p.tick();
            q.tick();
        }
        assert_eq!(p.position, q.position);
        assert_eq!(p.velocity, q.velocity);
    }

    #[test]
    fn com_height_sets_beta() {
        let low = PlantParams {
            com_height: 0.8,
            ..params()
        };
        let p = Plant::new(low, Vector2::zeros(), 0.0, Side::Left).unwrap();
        assert_eq!(p.beta(), (9.81f64 / 0.8).sqrt());
        let q = Plant::new(params(), Vector2::zeros(), 0.0, Side::Left).unwrap();
        assert!(p.beta() > q.beta());
        // A lower CoM diverges faster from the same offset over the foot.
        let (mut p, mut q) = (p, q);
        p.position.x = 0.05;
        q.position.x = 0.05;
        for _ in 0..400 {
            p.tick();
            q.tick();
        }
        assert!(p.position.x > q.position.x);
    }

    #[test]
    fn step_must_be_whole_ticks() {
        let bad = PlantParams {
            step_duration: 0.4005,
            ..params()
        };
        assert!(Plant::new(bad, Vector2::zeros(), 0.0, Side::Left).is_err());
    }
}
