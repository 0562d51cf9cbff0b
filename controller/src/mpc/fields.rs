//! [`Config`]'s fields by name: their names ([`Config::FIELDS`]), their
//! values ([`Config::field_values`]) and setting one ([`Config::set_field`]),
//! for hosts that read or write the settings by name (the scenario files' logs,
//! the Python package). The list of fields is written once, here.

use super::config::Config;

/// The value of one [`Config`] field, tagged by the field's type. Units as in
/// [`Config`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldValue {
    /// An `f64` field.
    Real(f64),
    /// A `u32` field (an iteration or bisection count).
    Count(u32),
    /// A `bool` field.
    Flag(bool),
    /// An `Option<f64>` field; `None` turns the option off.
    Optional(Option<f64>),
}

/// Why [`Config::set_field`] refused a value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldError {
    /// No field has that name.
    Unknown,
    /// The field exists but holds another type (the value's variant is not the
    /// field's).
    WrongType,
}

/// The fields in declaration order, each with its [`FieldValue`] variant.
macro_rules! config_fields {
    ($($f:ident: $kind:ident),* $(,)?) => {
        impl Config {
            /// The names of every field, in declaration order (for hosts that
            /// read or set them by name: the scenario files, the Python package).
            pub const FIELDS: [&'static str; FIELD_COUNT] = [$(stringify!($f)),*];

            /// Every field with its value, in [`Config::FIELDS`] order.
            ///
            /// ```
            /// use ldcbf_controller::{Config, FieldValue};
            ///
            /// let c = Config::default();
            /// let (name, value) = c.field_values()[11];
            /// assert_eq!((name, value), ("delta", FieldValue::Real(c.delta)));
            /// ```
            pub fn field_values(&self) -> [(&'static str, FieldValue); FIELD_COUNT] {
                [$((stringify!($f), FieldValue::$kind(self.$f))),*]
            }

            /// Sets the field `name` to `value` (not validated: call
            /// [`Config::validate`] after the last one).
            ///
            /// ```
            /// use ldcbf_controller::{Config, FieldError, FieldValue};
            ///
            /// let mut c = Config::default();
            /// c.set_field("max_iter", FieldValue::Count(40)).unwrap();
            /// assert_eq!(c.max_iter, 40);
            /// assert_eq!(c.set_field("max_iter", FieldValue::Real(40.0)), Err(FieldError::WrongType));
            /// assert_eq!(c.set_field("speed", FieldValue::Real(1.0)), Err(FieldError::Unknown));
            /// ```
            pub fn set_field(&mut self, name: &str, value: FieldValue) -> Result<(), FieldError> {
                match (name, value) {
                    $( (stringify!($f), FieldValue::$kind(v)) => self.$f = v, )*
                    _ if Self::FIELDS.contains(&name) => return Err(FieldError::WrongType),
                    _ => return Err(FieldError::Unknown),
                }
                Ok(())
            }
        }
    };
}

/// The number of [`Config`] fields.
const FIELD_COUNT: usize = 30;

config_fields!(
    gravity: Real,
    com_height: Real,
    step_duration: Real,
    vx_min: Real,
    vx_max: Real,
    vy_min: Real,
    vy_max: Real,
    l_max: Real,
    alpha: Real,
    omega_max: Real,
    gamma: Real,
    delta: Real,
    r_active: Real,
    foot_clearance: Optional,
    body_radius: Real,
    foot_length: Real,
    foot_width: Real,
    heading_freeze_radius: Real,
    max_iter: Count,
    max_iter_cycle: Count,
    relax_bisections: Count,
    max_gait_relaxation: Real,
    capture_fraction: Optional,
    warm_start: Flag,
    tol_primal: Real,
    turn_vertex_normals: Flag,
    velocity_margin: Flag,
    person_speed_max: Real,
    person_accel_max: Real,
    person_reach_time: Real,
);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every field read by name is the field, and setting it by name to
    /// another value of its type changes that field alone.
    #[test]
    fn every_field_reads_and_sets_by_name() {
        let base = Config::default();
        for (i, (name, value)) in base.field_values().into_iter().enumerate() {
            assert_eq!(name, Config::FIELDS[i]);
            let other = match value {
                FieldValue::Real(v) => FieldValue::Real(v + 1.5),
                FieldValue::Count(v) => FieldValue::Count(v + 3),
                FieldValue::Flag(v) => FieldValue::Flag(!v),
                FieldValue::Optional(v) => FieldValue::Optional(v.map_or(Some(0.25), |_| None)),
            };
            let mut c = base;
            c.set_field(name, other).unwrap();
            assert_ne!(c, base, "{name}");
            for (j, (n, v)) in c.field_values().into_iter().enumerate() {
                assert_eq!(n, Config::FIELDS[j]);
                assert_eq!(
                    v,
                    if i == j {
                        other
                    } else {
                        base.field_values()[j].1
                    },
                    "{n}"
                );
            }
            let wrong = match value {
                FieldValue::Real(_) => FieldValue::Flag(true),
                _ => FieldValue::Real(1.0),
            };
            assert_eq!(c.set_field(name, wrong), Err(FieldError::WrongType));
        }
        let mut c = base;
        assert_eq!(
            c.set_field("Gravity", FieldValue::Real(1.0)),
            Err(FieldError::Unknown)
        );
        assert_eq!(c, base);
    }
}
