//! Disturbances of the closed loop (the `[disturbance]` table of a scenario,
//! `--set disturbance.<field>=value`): what the plant and the controller's
//! measurement do that the controller's model does not predict.
//!
//! * **Push**: a CoM velocity impulse `(push_forward, push_lateral)` (m/s) in the
//!   robot's body frame at the moment of the push (x along the heading, y to its
//!   left), rotated into the world frame and added to the plant's CoM velocity at
//!   the first plant tick whose time is at or after `push_time` (s), then every
//!   `push_period` s after it (0 = once). With `push_alternate`, every second
//!   push is reversed (left, right, left, ...). The position is continuous: only
//!   the velocity jumps, by exactly the impulse.
//! * **CoM height mismatch**: `plant_com_height` (m) is the plant's true CoM
//!   height; the controller keeps its model's `controller.com_height`. The
//!   plant's `beta = sqrt(g / plant_com_height)` then differs from the model's.
//! * **Foot placement error**: every landed swing foot lands at the controller's
//!   target plus an isotropic Gaussian error with standard deviation
//!   `foot_sigma` (m) per world axis. The landed foot is the plant's stance foot
//!   and is what the controller measures next (a robot knows where its foot is).
//! * **State estimation noise**: each control cycle, the CoM position, velocity
//!   and heading handed to the controller are the true ones plus independent
//!   Gaussian noise of standard deviation `noise_position` (m, per world axis),
//!   `noise_velocity` (m/s, per world axis) and `noise_heading` (rad). The plant,
//!   the end conditions, the LiDAR and the clearance use the true state.
//! * **Wrong people's velocities**: with known velocities (`perception =
//!   "known"`), each moving obstacle's velocity handed to the controller is
//!   off by `velocity_error` (m/s) in a direction drawn once per obstacle
//!   (uniform), and the controller is given `velocity_error` as that
//!   obstacle's velocity uncertainty radius
//!   (`ldcbf_controller::CycleInput::obstacle_velocity_radii`): an estimate
//!   wrong by up to the radius the tracker states, as the barrier's reachable
//!   set assumes (docs/maths.md §2.7).
//!
//! Randomness: a ChaCha8 generator (as the scenario generator) seeded from both
//! the scenario seed and the disturbance `seed`
//! ([`disturbance_rng`]); the foot errors and the estimation noise use two
//! separate streams of it, so turning one on does not change the other's draws,
//! and a run is the same whatever the thread it runs on. With every field at
//! its default (no push, the model's height, zero sigmas) nothing is drawn and
//! the run is bit for bit the undisturbed one.

use ldcbf_controller::nalgebra::Vector2;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::world::moving::MAX_SPEED;
use crate::world::setting::SettingError;

/// Settings of the disturbances (the `[disturbance]` table; all off by default).
/// Frames and units in the module docs.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DisturbanceParams {
    /// Seed of the foot-error and noise streams, combined with the scenario seed.
    #[serde(default)]
    pub seed: u64,
    /// Time of the first push, s (no push when absent).
    #[serde(default)]
    pub push_time: Option<f64>,
    /// Time between pushes, s (0 = a single push).
    #[serde(default)]
    pub push_period: f64,
    /// Push: CoM velocity change along the heading, m/s (body frame).
    #[serde(default)]
    pub push_forward: f64,
    /// Push: CoM velocity change to the left of the heading, m/s (body frame).
    #[serde(default)]
    pub push_lateral: f64,
    /// Reverse every second push (the 2nd, 4th, ... push is `-impulse`).
    #[serde(default)]
    pub push_alternate: bool,
    /// The plant's true CoM height, m (absent = the controller's `com_height`).
    #[serde(default)]
    pub plant_com_height: Option<f64>,
    /// Standard deviation of the landing error per world axis, m.
    #[serde(default)]
    pub foot_sigma: f64,
    /// Standard deviation of the measured CoM position per world axis, m.
    #[serde(default)]
    pub noise_position: f64,
    /// Standard deviation of the measured CoM velocity per world axis, m/s.
    #[serde(default)]
    pub noise_velocity: f64,
    /// Standard deviation of the measured heading, rad.
    #[serde(default)]
    pub noise_heading: f64,
    /// Error of each moving obstacle's velocity handed to the controller
    /// with known velocities, m/s (module docs; 0 = exact).
    #[serde(default)]
    pub velocity_error: f64,
}

/// Names of the `[disturbance]` fields (for `--set` help and messages).
pub const DISTURBANCE_FIELDS: &[&str] = &[
    "seed",
    "push_time",
    "push_period",
    "push_forward",
    "push_lateral",
    "push_alternate",
    "plant_com_height",
    "foot_sigma",
    "noise_position",
    "noise_velocity",
    "noise_heading",
    "velocity_error",
];

/// Smallest `push_period`, s: at most one push per 10 ms.
pub const MIN_PUSH_PERIOD: f64 = 0.01;

impl DisturbanceParams {
    /// Checks every field; the error names the bad one and says why.
    pub fn validate(&self) -> Result<(), SettingError> {
        if let Some(t) = self.push_time
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(SettingError::new("push_time", "must be finite and >= 0 s"));
        }
        let p = self.push_period;
        if !(p.is_finite() && (p == 0.0 || p >= MIN_PUSH_PERIOD)) {
            return Err(SettingError::new(
                "push_period",
                format!("must be 0 (one push) or finite and >= {MIN_PUSH_PERIOD} s"),
            ));
        }
        if !self.push_forward.is_finite() {
            return Err(SettingError::new("push_forward", "must be finite (m/s)"));
        }
        if !self.push_lateral.is_finite() {
            return Err(SettingError::new("push_lateral", "must be finite (m/s)"));
        }
        if self.push_time.is_none()
            && (self.push_forward != 0.0 || self.push_lateral != 0.0 || self.push_period != 0.0)
        {
            return Err(SettingError::new(
                "push_time",
                "a push (push_forward, push_lateral or push_period) needs push_time",
            ));
        }
        if let Some(h) = self.plant_com_height
            && !(h.is_finite() && h > 0.0)
        {
            return Err(SettingError::new(
                "plant_com_height",
                "must be finite and > 0 m",
            ));
        }
        let e = self.velocity_error;
        if !(e.is_finite() && (0.0..=MAX_SPEED).contains(&e)) {
            return Err(SettingError::new(
                "velocity_error",
                format!("must be finite, >= 0 and <= {MAX_SPEED} m/s"),
            ));
        }
        let sigma = |v: f64| v.is_finite() && v >= 0.0;
        for (name, v) in [
            ("foot_sigma", self.foot_sigma),
            ("noise_position", self.noise_position),
            ("noise_velocity", self.noise_velocity),
            ("noise_heading", self.noise_heading),
        ] {
            if !sigma(v) {
                return Err(SettingError::new(
                    name,
                    "a standard deviation must be finite and >= 0",
                ));
            }
        }
        Ok(())
    }

    /// True when some push is configured with a non-zero impulse.
    pub fn has_push(&self) -> bool {
        self.push_time.is_some() && (self.push_forward != 0.0 || self.push_lateral != 0.0)
    }

    /// True when the state the controller sees is noisy.
    pub fn has_noise(&self) -> bool {
        self.noise_position > 0.0 || self.noise_velocity > 0.0 || self.noise_heading > 0.0
    }

    /// True when any disturbance is on (`model_com_height` is the controller's).
    pub fn is_active(&self, model_com_height: f64) -> bool {
        self.has_push()
            || self.has_noise()
            || self.foot_sigma > 0.0
            || self.velocity_error > 0.0
            || self.plant_com_height.is_some_and(|h| h != model_com_height)
    }
}

/// The generator of one stream (`stream` 0: foot errors, 1: estimation
/// noise, 2: the directions of the people's velocity errors)
/// for a scenario seed and a disturbance seed: ChaCha8 with the 32-byte key
/// `scenario_seed | disturbance_seed | "DISTURB\0" | 0` (little endian), so it
/// is independent of the scenario generator's and the LiDAR's streams.
pub fn disturbance_rng(scenario_seed: u64, disturbance_seed: u64, stream: u64) -> ChaCha8Rng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&scenario_seed.to_le_bytes());
    key[8..16].copy_from_slice(&disturbance_seed.to_le_bytes());
    key[16..24].copy_from_slice(b"DISTURB\0");
    key[24..].copy_from_slice(&stream.to_le_bytes());
    ChaCha8Rng::from_seed(key)
}

/// One push as applied.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PushEvent {
    /// Plant tick at which it was applied.
    pub tick: u64,
    /// Its time, s.
    pub time: f64,
    /// The velocity change, m/s, world frame.
    pub delta_v: [f64; 2],
    /// The heading it was rotated with, rad.
    pub heading: f64,
}

/// What the disturbances did during a run (for the logs and the summary).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DisturbanceLog {
    /// The settings.
    pub params: DisturbanceParams,
    /// The plant's CoM height, m.
    pub plant_com_height: f64,
    /// The controller model's CoM height, m.
    pub model_com_height: f64,
    /// Every push applied, in order.
    pub pushes: Vec<PushEvent>,
    /// Landings with a placement error.
    pub foot_errors: usize,
    /// Largest landing error, m (0 without).
    pub max_foot_error: f64,
    /// Root mean square of the landing errors, m (0 without).
    pub rms_foot_error: f64,
    /// Control cycles fed a noisy state.
    pub noisy_cycles: usize,
    /// Largest position error handed to the controller, m.
    pub max_position_error: f64,
    /// Largest velocity error handed to the controller, m/s.
    pub max_velocity_error: f64,
}

/// The disturbances of one run, as the simulator applies them.
#[derive(Clone, Debug)]
pub struct Disturber {
    params: DisturbanceParams,
    /// Tick of the next push, if any.
    next_push: Option<u64>,
    period_ticks: u64,
    dt: f64,
    foot_rng: ChaCha8Rng,
    noise_rng: ChaCha8Rng,
    sum_sq_foot: f64,
    /// The record of what was applied.
    pub log: DisturbanceLog,
}

/// First tick at or after `t` (s) on a grid of `dt` (s), tolerant of rounding.
fn tick_at(t: f64, dt: f64) -> u64 {
    (t / dt - 1e-9).ceil().max(0.0) as u64
}

impl Disturber {
    /// The disturbances of `params` for a run with scenario seed `scenario_seed`
    /// on a plant tick of `dt` s; the heights go to the log.
    pub fn new(
        params: &DisturbanceParams,
        scenario_seed: u64,
        dt: f64,
        model_com_height: f64,
    ) -> Self {
        let next_push = if params.has_push() {
            params.push_time.map(|t| tick_at(t, dt))
        } else {
            None
        };
        let period_ticks = if params.push_period > 0.0 {
            ((params.push_period / dt).round() as u64).max(1)
        } else {
            0
        };
        Disturber {
            params: params.clone(),
            next_push,
            period_ticks,
            dt,
            foot_rng: disturbance_rng(scenario_seed, params.seed, 0),
            noise_rng: disturbance_rng(scenario_seed, params.seed, 1),
            sum_sq_foot: 0.0,
            log: DisturbanceLog {
                params: params.clone(),
                plant_com_height: params.plant_com_height.unwrap_or(model_com_height),
                model_com_height,
                ..DisturbanceLog::default()
            },
        }
    }

    /// The plant's CoM height, m.
    pub fn plant_com_height(&self) -> f64 {
        self.log.plant_com_height
    }

    /// The push due at plant tick `tick` (heading `heading`, rad), as a world
    /// velocity change in m/s, or `None`. Call once per tick, ticks ascending.
    pub fn push_at(&mut self, tick: u64, heading: f64) -> Option<Vector2<f64>> {
        self.next_push.filter(|&n| n <= tick)?;
        self.next_push = (self.period_ticks > 0).then(|| tick + self.period_ticks);
        let sign = if self.params.push_alternate && self.log.pushes.len() % 2 == 1 {
            -1.0
        } else {
            1.0
        };
        let (s, c) = heading.sin_cos();
        let (f, l) = (self.params.push_forward, self.params.push_lateral);
        let dv = Vector2::new(c * f - s * l, s * f + c * l) * sign;
        self.log.pushes.push(PushEvent {
            tick,
            time: tick as f64 * self.dt,
            delta_v: [dv.x, dv.y],
            heading,
        });
        Some(dv)
    }

    /// Where a swing foot aimed at `target` (m, world) actually lands.
    pub fn land(&mut self, target: Vector2<f64>) -> Vector2<f64> {
        let sigma = self.params.foot_sigma;
        if sigma <= 0.0 {
            return target;
        }
        let e = Vector2::new(
            sigma * gauss(&mut self.foot_rng),
            sigma * gauss(&mut self.foot_rng),
        );
        let n = e.norm();
        self.log.foot_errors += 1;
        self.log.max_foot_error = self.log.max_foot_error.max(n);
        self.sum_sq_foot += n * n;
        self.log.rms_foot_error = (self.sum_sq_foot / self.log.foot_errors as f64).sqrt();
        target + e
    }

    /// The velocity errors of `n` obstacles (m/s, world frame): each of
    /// length `velocity_error` in a uniform direction, drawn from stream 2 of
    /// this run's seeds (module docs); zeros when `velocity_error` is 0.
    pub fn velocity_errors(&self, scenario_seed: u64, n: usize) -> Vec<Vector2<f64>> {
        let e = self.params.velocity_error;
        if e <= 0.0 {
            return vec![Vector2::zeros(); n];
        }
        let mut rng = disturbance_rng(scenario_seed, self.params.seed, 2);
        (0..n)
            .map(|_| {
                let a = rand_distr::Uniform::new(0.0, core::f64::consts::TAU)
                    .map_or(0.0, |u| u.sample(&mut rng));
                Vector2::new(a.cos(), a.sin()) * e
            })
            .collect()
    }

    /// The measured CoM position (m), velocity (m/s) and heading (rad) for the
    /// true ones (all world frame).
    pub fn measure(
        &mut self,
        position: Vector2<f64>,
        velocity: Vector2<f64>,
        heading: f64,
    ) -> (Vector2<f64>, Vector2<f64>, f64) {
        if !self.params.has_noise() {
            return (position, velocity, heading);
        }
        let (sp, sv, sh) = (
            self.params.noise_position,
            self.params.noise_velocity,
            self.params.noise_heading,
        );
        // Always five draws per cycle, so one sigma does not shift the others' draws.
        let r = &mut self.noise_rng;
        let ep = Vector2::new(sp * gauss(r), sp * gauss(r));
        let ev = Vector2::new(sv * gauss(r), sv * gauss(r));
        let eh = sh * gauss(r);
        self.log.noisy_cycles += 1;
        self.log.max_position_error = self.log.max_position_error.max(ep.norm());
        self.log.max_velocity_error = self.log.max_velocity_error.max(ev.norm());
        (position + ep, velocity + ev, heading + eh)
    }
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_field() {
        let ok = DisturbanceParams::default();
        assert!(ok.validate().is_ok());
        assert!(!ok.is_active(1.0));
        let bad = |f: &dyn Fn(&mut DisturbanceParams)| {
            let mut p = DisturbanceParams::default();
            f(&mut p);
            p.validate().unwrap_err().field
        };
        assert_eq!(bad(&|p| p.foot_sigma = -0.01), "foot_sigma");
        assert_eq!(bad(&|p| p.noise_velocity = f64::NAN), "noise_velocity");
        assert_eq!(bad(&|p| p.noise_heading = f64::INFINITY), "noise_heading");
        assert_eq!(bad(&|p| p.noise_position = -1.0), "noise_position");
        assert_eq!(bad(&|p| p.velocity_error = -0.1), "velocity_error");
        assert_eq!(bad(&|p| p.velocity_error = f64::NAN), "velocity_error");
        assert_eq!(bad(&|p| p.plant_com_height = Some(0.0)), "plant_com_height");
        assert_eq!(bad(&|p| p.push_lateral = 0.3), "push_time");
        assert_eq!(
            bad(&|p| {
                p.push_time = Some(1.0);
                p.push_period = 0.001;
            }),
            "push_period"
        );
        assert_eq!(bad(&|p| p.push_time = Some(-1.0)), "push_time");
        assert_eq!(
            bad(&|p| {
                p.push_time = Some(1.0);
                p.push_forward = f64::NAN;
            }),
            "push_forward"
        );
    }

    #[test]
    fn pushes_follow_the_schedule_in_the_body_frame() {
        let p = DisturbanceParams {
            push_time: Some(0.5),
            push_period: 0.25,
            push_lateral: 0.3,
            push_alternate: true,
            ..DisturbanceParams::default()
        };
        let mut d = Disturber::new(&p, 0, 1e-3, 1.0);
        let half_pi = core::f64::consts::FRAC_PI_2;
        let mut got = Vec::new();
        for tick in 0..1001 {
            if let Some(dv) = d.push_at(tick, half_pi) {
                got.push((tick, dv));
            }
        }
        let ticks: Vec<u64> = got.iter().map(|g| g.0).collect();
        assert_eq!(ticks, vec![500, 750, 1000]);
        // Heading +90 deg: "left" is world -x; the second push is reversed.
        assert!((got[0].1 - Vector2::new(-0.3, 0.0)).amax() < 1e-15);
        assert!((got[1].1 - Vector2::new(0.3, 0.0)).amax() < 1e-15);
        assert_eq!(d.log.pushes.len(), 3);
        assert_eq!(d.log.pushes[0].time, 0.5);
    }

    #[test]
    fn streams_are_seeded_and_independent() {
        let p = DisturbanceParams {
            foot_sigma: 0.02,
            noise_position: 0.01,
            ..DisturbanceParams::default()
        };
        let draw = |scen: u64, seed: u64, noise: bool| {
            let q = DisturbanceParams {
                seed,
                noise_position: if noise { 0.01 } else { 0.0 },
                ..p.clone()
            };
            let mut d = Disturber::new(&q, scen, 1e-3, 1.0);
            let mut v = Vec::new();
            for _ in 0..5 {
                let _ = d.measure(Vector2::zeros(), Vector2::zeros(), 0.0);
                v.push(d.land(Vector2::zeros()));
            }
            v
        };
        assert_eq!(draw(3, 1, true), draw(3, 1, true));
        assert_ne!(draw(3, 1, true), draw(3, 2, true));
        assert_ne!(draw(3, 1, true), draw(4, 1, true));
        // The noise stream does not shift the foot errors.
        assert_eq!(draw(3, 1, true), draw(3, 1, false));
    }
}
