//! Limits on hostile input, checked before anything recurses or allocates by
//! the input's size: the nesting depth of a value, the parts and length of a
//! `--set` key, the magnitude of every number of a scenario, exact list
//! lengths, and the length of the text an error message echoes.

use serde::{Deserialize, Deserializer};

use crate::world::exact::exact;

/// Deepest nesting of tables and arrays in a scenario value (a file has at
/// most 5: `obstacles[i].vertices[j][k]`). Also the bound on Python objects
/// converted to scenario values (cycles included).
pub const MAX_DEPTH: usize = 16;

/// Most dotted parts of a `--set` key (real keys have one or two:
/// `delta`, `controller.delta`, `disturbance.push_time`).
pub const MAX_KEY_PARTS: usize = 8;

/// Longest `--set` key, bytes.
pub const MAX_KEY_LEN: usize = 256;

/// Largest magnitude of any number in a scenario (coordinates in m, times in
/// s, gains): 1e6. Anything larger is a typo or an attack, refused with the
/// field named before the controller turns it into an overflow elsewhere.
/// Integers (seeds, counts) are not bound here; their own fields check them.
pub const MAX_MAGNITUDE: f64 = 1e6;

/// Largest scenario file, `deadline --instructions` CSV or study
/// `summary.json`, bytes (the shipped scenarios have a few kB; large maps come
/// from a `[generator]`). Read by [`read_regular_file`].
pub const MAX_FILE_BYTES: u64 = 1 << 24;

/// Largest `runs.csv` of a study directory (`table`, `merge`) and npz file
/// (`qp solve`; what it decompresses to is capped apart), bytes: a row of
/// `runs.csv` has under 300 bytes, so the 1,000,000 seeds of the largest
/// study fit.
pub const MAX_TABLE_BYTES: u64 = 1 << 29;

/// The one rule for every file the tools read (scenarios, `qp solve`'s npz
/// files, `deadline --instructions`, the files of a study directory): a
/// regular file (a symbolic link to one is followed) of at most `max_bytes`.
/// A directory, a device, a FIFO or a socket is refused before it is opened,
/// so nothing blocks on a FIFO or reads a device for ever. Returns the size,
/// bytes. The error's kind is `NotFound` for a missing file; its message says
/// what is wrong, without the path (the caller names it).
pub fn check_regular_file(path: &std::path::Path, max_bytes: u64) -> std::io::Result<u64> {
    check_metadata(&std::fs::metadata(path)?, max_bytes)
}

/// [`check_regular_file`] on metadata already read.
fn check_metadata(meta: &std::fs::Metadata, max_bytes: u64) -> std::io::Result<u64> {
    if meta.is_dir() {
        return Err(refuse("is a directory, not a file".into()));
    }
    if !meta.is_file() {
        return Err(refuse(
            "is not a regular file (a device, a FIFO or a socket)".into(),
        ));
    }
    if meta.len() > max_bytes {
        return Err(too_big(meta.len(), max_bytes));
    }
    Ok(meta.len())
}

/// An error of [`check_regular_file`]: the input is refused.
fn refuse(message: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message)
}

/// The error of a file of `len` bytes over `max_bytes`.
fn too_big(len: u64, max_bytes: u64) -> std::io::Error {
    refuse(format!(
        "is {len} bytes, more than the {max_bytes} bytes read from one file"
    ))
}

/// Reads the file at `path` after [`check_regular_file`]; the opened file is
/// checked again and the read stops after `max_bytes + 1` bytes, so a file
/// swapped or grown between the check and the read is refused too.
pub fn read_regular_file(path: &std::path::Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
    check_regular_file(path, max_bytes)?;
    let file = std::fs::File::open(path)?;
    check_metadata(&file.metadata()?, max_bytes)?;
    let mut bytes = Vec::new();
    file.take(max_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_big(bytes.len() as u64, max_bytes));
    }
    Ok(bytes)
}

/// Most obstacles with a velocity (people) in one scenario: each is checked
/// against the body and the feet at every 1 kHz tick, cast by every LiDAR ray
/// and predicted by the controller, so the wall time grows with their number
/// (docs/cli-errors.md gives the measured cost).
pub const MAX_MOVING_OBSTACLES: usize = 1000;

/// Largest `lidar.map.resolution` with the LiDAR perception, m, whatever the
/// body (docs/cli-errors.md gives the runs that set it; [`max_map_cell`]).
pub const MAX_MAP_CELL: f64 = 0.1;

/// Largest `lidar.map.resolution` for a robot whose CoM the controller keeps
/// `barrier_margin` (m) from every piece of the map: [`MAX_MAP_CELL`], and a
/// cell's diagonal at most the barrier margin (`r sqrt 2 <= m`) when it is
/// positive. A piece is a whole cell, so the cell holding the CoM must never
/// hold a wall while the body keeps its margin: a wall point in it is within a
/// diagonal of the CoM. (A point robot at `delta = 0` has no margin; the
/// fixed bound alone applies.)
pub fn max_map_cell(barrier_margin: f64) -> f64 {
    if barrier_margin > 0.0 {
        MAX_MAP_CELL.min(barrier_margin / core::f64::consts::SQRT_2)
    } else {
        MAX_MAP_CELL
    }
}

/// Longest piece of user text an error message repeats, characters.
pub const MAX_ECHO: usize = 80;

/// `s` for an error message: whole when it has at most `max` characters,
/// otherwise its first `max` characters, `...` and its size ([`MAX_ECHO`] for
/// a key or a value, more for a parser's whole message).
pub fn shorten(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        None => s.to_string(),
        Some((cut, _)) => format!("{}... ({} bytes in all)", &s[..cut], s.len()),
    }
}

/// A key as the `field` of an error: [`shorten`]ed, and `""` for the empty
/// key (TOML's `"" = 1`, `--set =1`) so that the message shows one.
pub fn field_name(key: &str) -> String {
    if key.is_empty() {
        "\"\"".into()
    } else {
        shorten(key, MAX_ECHO)
    }
}

/// Checks a `--set` key before it is split: at most [`MAX_KEY_LEN`] bytes and
/// [`MAX_KEY_PARTS`] dotted parts.
pub fn check_key(key: &str) -> Result<(), String> {
    if key.len() > MAX_KEY_LEN {
        return Err(format!(
            "key too long ({} bytes; at most {MAX_KEY_LEN})",
            key.len()
        ));
    }
    let parts = key.split('.').count();
    if parts > MAX_KEY_PARTS {
        return Err(format!(
            "key has {parts} dotted parts (at most {MAX_KEY_PARTS})"
        ));
    }
    Ok(())
}

/// Checks every value of `table` without recursion: nesting depth at most
/// [`MAX_DEPTH`], every finite float of magnitude at most [`MAX_MAGNITUDE`]
/// (NaN and infinities are left to the fields' own checks, which say what the
/// field needs). The error is `(dotted path, message)`.
pub fn check_table(table: &toml::Table) -> Result<(), (String, String)> {
    let mut stack: Vec<(String, usize, &toml::Value)> =
        table.iter().map(|(k, v)| (k.clone(), 1, v)).collect();
    while let Some((path, depth, v)) = stack.pop() {
        if depth > MAX_DEPTH {
            return Err((
                path,
                format!("nested more than {MAX_DEPTH} tables or arrays deep"),
            ));
        }
        match v {
            toml::Value::Float(x) if x.is_finite() && x.abs() > MAX_MAGNITUDE => {
                return Err((
                    path,
                    format!("{x:e} is out of range (magnitude at most {MAX_MAGNITUDE:e})"),
                ));
            }
            toml::Value::Table(t) => {
                stack.extend(t.iter().map(|(k, v)| (format!("{path}.{k}"), depth + 1, v)));
            }
            toml::Value::Array(a) => stack.extend(
                a.iter()
                    .enumerate()
                    .map(|(i, v)| (format!("{path}[{i}]"), depth + 1, v)),
            ),
            _ => {}
        }
    }
    Ok(())
}

/// A point `[x, y]` as written in a file: exactly two numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Xy(pub [f64; 2]);

impl<'de> Deserialize<'de> for Xy {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        exact(d).map(Xy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shorten_keeps_short_text_and_cuts_long_text() {
        assert_eq!(shorten("abc", MAX_ECHO), "abc");
        let long = "é".repeat(10_000);
        let s = shorten(&long, MAX_ECHO);
        assert!(s.starts_with(&"é".repeat(MAX_ECHO)), "{s}");
        assert!(s.ends_with("... (20000 bytes in all)"), "{s}");
    }

    #[test]
    fn only_regular_files_within_the_size_are_read() {
        let dir = std::env::temp_dir().join(format!("ldcbf-limits-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("f.txt");
        std::fs::write(&f, "12345").unwrap();
        assert_eq!(read_regular_file(&f, 5).unwrap(), b"12345");
        let big = read_regular_file(&f, 4).unwrap_err();
        assert!(
            big.to_string().contains("5 bytes, more than the 4"),
            "{big}"
        );
        let d = read_regular_file(&dir, 100).unwrap_err();
        assert!(d.to_string().contains("is a directory"), "{d}");
        let dev = check_regular_file(std::path::Path::new("/dev/null"), 100).unwrap_err();
        assert!(dev.to_string().contains("not a regular file"), "{dev}");
        let missing = read_regular_file(&dir.join("no"), 100).unwrap_err();
        assert_eq!(missing.kind(), std::io::ErrorKind::NotFound);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn keys_are_bounded_before_splitting() {
        assert!(check_key("controller.delta").is_ok());
        assert!(check_key(&["a"; 20_000].join(".")).is_err());
        assert!(check_key(&"a".repeat(MAX_KEY_LEN + 1)).is_err());
    }

    #[test]
    fn depth_and_magnitude_name_the_path() {
        let t: toml::Table = toml::from_str("goal = [1e300, 5.0]").unwrap();
        let (p, m) = check_table(&t).unwrap_err();
        assert_eq!(p, "goal[0]");
        assert!(m.contains("out of range"), "{m}");
        let mut v = toml::Value::Float(1.0);
        for _ in 0..MAX_DEPTH {
            v = toml::Value::Array(vec![v]);
        }
        let mut t = toml::Table::new();
        t.insert("x".into(), v);
        assert!(check_table(&t).unwrap_err().1.contains("nested"));
    }
}
