//! The robot's body and feet: the scenario's `[robot]` table.
//!
//! The controller's barrier keeps a body DISK (radius `body_radius` around the
//! CoM, horizontal plane) out of every obstacle, and, with `keep_feet_clear`,
//! every footstep's FOOTPRINT (a `foot_length` x `foot_width` rectangle centred
//! on the footstep, long side along the heading at landing) off them. The
//! simulator measures the clearance of those shapes against the TRUE map, not
//! of the point CoM ([`crate::report`]).
//!
//! Defaults are an adult-size humanoid:
//!
//! * `body_radius = 0.25` m: a 0.5 m wide envelope, the shoulder breadth of an
//!   adult (about 0.40-0.46 m in anthropometric surveys such as ANSUR II) with
//!   room for the arms' swing. Humanoids built for human spaces (Digit, H1,
//!   Atlas) are of that width.
//! * `foot_length = 0.22`, `foot_width = 0.10` m: a human-size sole; a
//!   Digit-like robot foot is smaller, so this is on the safe side.
//!
//! The paper's and the report's reproductions set all three to 0 (a point CoM,
//! point feet) and say so in their file's `note`, so their figures stay
//! comparable with the sources.

use ldcbf_controller::Config;
use serde::{Deserialize, Serialize};

/// The `[robot]` table. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotParams {
    /// Radius of the body disk around the CoM, m (>= 0; 0 = a point CoM).
    pub body_radius: f64,
    /// Footprint length along the heading, m (>= 0).
    pub foot_length: f64,
    /// Footprint width across the heading, m (>= 0).
    pub foot_width: f64,
    /// Keep every footstep's footprint off the obstacles: the controller's
    /// foot-clearance rows (`controller.foot_clearance`, default 0 m of extra
    /// clearance). `false` = the paper's QP, no foot rows (and then the
    /// continuous CoM path between step ends is not guaranteed, only the step
    /// ends: [`ldcbf_controller::Config::barrier_margin`]).
    pub keep_feet_clear: bool,
}

impl Default for RobotParams {
    fn default() -> Self {
        RobotParams {
            body_radius: 0.25,
            foot_length: 0.22,
            foot_width: 0.10,
            keep_feet_clear: true,
        }
    }
}

impl RobotParams {
    /// A point robot with point feet and no foot rows (the paper's model).
    pub const POINT: RobotParams = RobotParams {
        body_radius: 0.0,
        foot_length: 0.0,
        foot_width: 0.0,
        keep_feet_clear: false,
    };

    /// Checks every field: the error names it and says what it must satisfy.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let ok = |v: f64, hi: f64| v.is_finite() && (0.0..=hi).contains(&v);
        if !ok(self.body_radius, 5.0) {
            return Err(("body_radius", "must be in [0, 5] m".into()));
        }
        if !ok(self.foot_length, 1.0) {
            return Err(("foot_length", "must be in [0, 1] m".into()));
        }
        if !ok(self.foot_width, 1.0) {
            return Err(("foot_width", "must be in [0, 1] m".into()));
        }
        Ok(())
    }

    /// `config` with the body and feet of this robot: `body_radius`,
    /// `foot_length`, `foot_width`, and the foot rows on (`foot_clearance`
    /// kept when the file set it, else 0) or off.
    pub fn apply(&self, config: Config) -> Config {
        Config {
            body_radius: self.body_radius,
            foot_length: self.foot_length,
            foot_width: self.foot_width,
            foot_clearance: if self.keep_feet_clear {
                Some(config.foot_clearance.unwrap_or(0.0))
            } else {
                None
            },
            ..config
        }
    }

    /// Half-diagonal of the footprint, m: the radius of the disk that holds
    /// the foot whatever its orientation.
    pub fn foot_reach(&self) -> f64 {
        0.5 * self.foot_length.hypot(self.foot_width)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn apply_sets_body_and_feet() {
        let c = RobotParams::default().apply(Config::default());
        assert_eq!(c.body_radius, 0.25);
        assert_eq!(c.foot_clearance, Some(0.0));
        let with = Config {
            foot_clearance: Some(0.05),
            ..Config::default()
        };
        assert_eq!(
            RobotParams::default().apply(with).foot_clearance,
            Some(0.05)
        );
        assert_eq!(RobotParams::POINT.apply(with).foot_clearance, None);
        assert_eq!(RobotParams::POINT.apply(with).body_radius, 0.0);
    }

    #[test]
    fn validate_names_the_field() {
        let bad = RobotParams {
            foot_width: -0.1,
            ..RobotParams::default()
        };
        assert_eq!(bad.validate().unwrap_err().0, "foot_width");
        let bad = RobotParams {
            body_radius: f64::NAN,
            ..RobotParams::default()
        };
        assert_eq!(bad.validate().unwrap_err().0, "body_radius");
    }
}
