//! Exact list lengths for `serde`: a fixed-size array read from a list of
//! exactly that many values (a list of another length is an error, not cut or
//! padded), for the pairs of the scenario file (`[generator]`'s ranges here,
//! the points of `crate::scenario`).

use serde::{Deserialize, Deserializer};

/// Deserializes exactly `N` values (a list of another length is an error,
/// not cut or padded).
pub fn exact<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v: Vec<T> = Vec::deserialize(d)?;
    let got = v.len();
    v.try_into().map_err(|_| {
        serde::de::Error::custom(format!("expected a list of exactly {N} numbers, got {got}"))
    })
}
