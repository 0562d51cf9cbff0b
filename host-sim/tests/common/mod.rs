//! Helpers shared by the CLI tests: run the `ldcbf-sim` binary, check a
//! failing command, and build npz files byte by byte.
#![allow(dead_code)] // each test file uses its own subset

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `ldcbf-sim` with `args` in `cwd`.
pub fn sim(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("binary runs")
}

/// Output bytes as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Runs a command that must fail: non-zero exit, nothing on stdout, exactly one
/// `error:` line on stderr containing `needle`, and an empty working directory
/// afterwards.
pub fn fails(args: &[&str], needle: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(args, tmp.path());
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(out.is_empty(), "{args:?} printed {out}");
    assert!(err.contains(needle), "{args:?}: {err}");
    let errors = err.lines().filter(|l| l.starts_with("error")).count();
    assert_eq!(errors, 1, "{args:?}: {err}");
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "{args:?} wrote something"
    );
}

/// Every directory (`None`) and file (its bytes) under `dir`, by relative path.
pub fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
    fn walk(root: &Path, p: &Path, out: &mut BTreeMap<PathBuf, Option<Vec<u8>>>) {
        for e in std::fs::read_dir(p).unwrap() {
            let path = e.unwrap().path();
            let rel = path.strip_prefix(root).unwrap().to_path_buf();
            if path.is_dir() {
                out.insert(rel, None);
                walk(root, &path, out);
            } else {
                out.insert(rel, Some(std::fs::read(&path).unwrap()));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Runs a command in `dir` that must fail cleanly on bad input: exit status 1
/// (not a panic's 101), nothing on stdout, exactly one stderr line, which
/// starts with `error: ` and contains every needle, and `dir` exactly as before
/// (nothing created, nothing half-written, nothing changed). Returns the line.
pub fn fails_in(dir: &Path, args: &[&str], needles: &[&str]) -> String {
    let before = snapshot(dir);
    let o = sim(args, dir);
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(out.is_empty(), "{args:?} printed {out}");
    assert_eq!(err.lines().count(), 1, "{args:?}: one line: {err}");
    assert!(err.starts_with("error: "), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: no {n:?} in {err}");
    }
    let after = snapshot(dir);
    let changed: Vec<_> = before
        .keys()
        .chain(after.keys())
        .filter(|k| before.get(*k) != after.get(*k))
        .collect();
    assert!(changed.is_empty(), "{args:?} changed {changed:?}");
    err.trim_end().to_string()
}

/// A version 1.0 `.npy` array: `descr` (e.g. `<f8`), `shape` as written in the
/// header, then `data` as is.
pub fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
    let fortran = if fortran { "True" } else { "False" };
    let mut h = format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}");
    while (10 + h.len() + 1) % 64 != 0 {
        h.push(' ');
    }
    h.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&u16::try_from(h.len()).unwrap().to_le_bytes());
    b.extend_from_slice(h.as_bytes());
    b.extend_from_slice(data);
    b
}

/// A float64 `.npy` array in C order.
pub fn npy_f64(shape: &[usize], values: &[f64]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    npy("<f8", false, &shape, &data)
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 == 1 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// An uncompressed zip archive of `members` (name, bytes): what `numpy.savez`
/// writes when the members are `.npy` arrays.
pub fn zip(members: &[(&str, Vec<u8>)]) -> Vec<u8> {
    let (mut out, mut central) = (Vec::new(), Vec::new());
    for (name, data) in members {
        let offset = u32::try_from(out.len()).unwrap();
        let (crc, len) = (crc32(data), u32::try_from(data.len()).unwrap());
        let name_len = u16::try_from(name.len()).unwrap();
        // Local header: signature, version, flags, method 0 (stored), time, date.
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        out.extend_from_slice(&[20, 0, 0, 0, 0, 0, 0, 0, 0x21, 0]);
        for v in [crc, len, len] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&name_len.to_le_bytes());
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(data);
        // Central directory entry.
        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        central.extend_from_slice(&[20, 0, 20, 0, 0, 0, 0, 0, 0, 0, 0x21, 0]);
        for v in [crc, len, len] {
            central.extend_from_slice(&v.to_le_bytes());
        }
        central.extend_from_slice(&name_len.to_le_bytes());
        central.extend_from_slice(&[0; 12]); // extra, comment, disk, attributes
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let (cd_offset, cd_len) = (
        u32::try_from(out.len()).unwrap(),
        u32::try_from(central.len()).unwrap(),
    );
    let count = u16::try_from(members.len()).unwrap();
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    out.extend_from_slice(&[0, 0, 0, 0]);
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&cd_len.to_le_bytes());
    out.extend_from_slice(&cd_offset.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out
}

/// A small valid QP: `min sum (x_i - 1)^2` over 6 variables with
/// `x_0 + x_1 <= 1` (`n = 6`, `m = 1`; optimum `x = (0.5, 0.5, 1, 1, 1, 1)`,
/// objective -5.5 in the `1/2 x'Px + q'x` form).
pub fn small_qp() -> ldcbf_reference::DenseProblem {
    let mut p = ldcbf_reference::DenseProblem::inequalities(
        6,
        vec![0.0; 36],
        vec![-2.0; 6],
        vec![1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        vec![1.0],
    );
    for i in 0..6 {
        p.P[i * 6 + i] = 2.0;
    }
    p
}
