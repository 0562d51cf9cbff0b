//! The npz layout of the external test set (mpc_qpbenchmark): reading and
//! writing a [`DenseProblem`], and the `.npy` parser behind it.

use std::path::Path;

use crate::problem::{DenseProblem, ProblemError};

impl DenseProblem {
    /// Reads `P, q, G, h` from an `.npz` file of the mpc_qpbenchmark layout (other
    /// keys, pickled `None`s, are ignored): float64 arrays of shapes `[n, n]`,
    /// `[n]`, `[m, n]`, `[m]` (C or Fortran order). Errors name the file and the
    /// key: not a zip archive, a missing key, a truncated or corrupted member
    /// (the zip CRC is checked), another dtype, a wrong shape.
    pub fn from_npz(path: &Path) -> Result<Self, ProblemError> {
        let name = path.display().to_string();
        let fail = |m: String| ProblemError(format!("{name}: {m}"));
        if path.is_dir() {
            return Err(fail("is a directory, not an npz file".into()));
        }
        let mut npz = npyz::npz::NpzArchive::open(path).map_err(|e| {
            fail(match e.kind() {
                std::io::ErrorKind::NotFound => "no such file".into(),
                std::io::ErrorKind::InvalidData => {
                    format!("not an npz file (a zip archive of .npy arrays): {e}")
                }
                _ => format!("cannot open: {e}"),
            })
        })?;
        let mut read = |key: &str| -> Result<(Vec<u64>, Vec<f64>), ProblemError> {
            let bytes =
                read_npz_member(&mut npz, key).map_err(|m| fail(format!("key `{key}`: {m}")))?;
            let (shape, fortran, data) =
                parse_npy_f64(&bytes).map_err(|m| fail(format!("key `{key}`: {m}")))?;
            let data = if fortran && shape.len() == 2 {
                let (r, c) = (shape[0] as usize, shape[1] as usize);
                let mut t = vec![0.0; r * c];
                for i in 0..r {
                    for j in 0..c {
                        t[i * c + j] = data[j * r + i];
                    }
                }
                t
            } else {
                data
            };
            Ok((shape, data))
        };
        let (ps, P) = read("P")?;
        let (qs, q) = read("q")?;
        let (gs, G) = read("G")?;
        let (hs, h) = read("h")?;
        let bad = |key: &str, got: &[u64], want: String| {
            Err(fail(format!(
                "key `{key}` has shape {got:?}, expected {want}"
            )))
        };
        let [n, n2] = ps[..] else {
            return bad("P", &ps, "[n, n]".into());
        };
        if n != n2 {
            return bad("P", &ps, "[n, n]".into());
        }
        if qs[..] != [n] {
            return bad("q", &qs, format!("[{n}] (the size of `P`)"));
        }
        let [m, n3] = gs[..] else {
            return bad("G", &gs, format!("[m, {n}]"));
        };
        if n3 != n {
            return bad("G", &gs, format!("[m, {n}]"));
        }
        if hs[..] != [m] {
            return bad("h", &hs, format!("[{m}] (the rows of `G`)"));
        }
        let (n, m) = (n as usize, m as usize);
        Ok(DenseProblem { n, m, P, q, G, h })
    }

    /// Writes `P, q, G, h` (float64, C order, shapes `[n, n]`, `[n]`, `[m, n]`,
    /// `[m]`) to an `.npz` file, the layout [`DenseProblem::from_npz`] reads and
    /// `numpy.load` opens. (The mpc_qpbenchmark files also carry pickled `None`s
    /// for `A, b, lb, ub`; they are not written.) Errors name the file.
    pub fn write_npz(&self, path: &Path) -> Result<(), ProblemError> {
        use npyz::WriterBuilder;
        let name = path.display().to_string();
        let err = |e: std::io::Error| ProblemError(format!("{name}: cannot write npz: {e}"));
        let mut npz = npyz::npz::NpzWriter::create(path).map_err(err)?;
        let (n, m) = (self.n as u64, self.m as u64);
        let arrays: [(&str, Vec<u64>, &[f64]); 4] = [
            ("P", vec![n, n], &self.P),
            ("q", vec![n], &self.q),
            ("G", vec![m, n], &self.G),
            ("h", vec![m], &self.h),
        ];
        for (key, shape, data) in arrays {
            let mut w = npz
                .array::<f64>(key, Default::default())
                .map_err(err)?
                .default_dtype()
                .shape(&shape)
                .begin_nd()
                .map_err(err)?;
            w.extend(data.iter().copied()).map_err(err)?;
            w.finish().map_err(err)?;
        }
        Ok(())
    }
}

/// Largest `.npy` member read from an npz file, bytes (the QPs of this project
/// are a few kB; the cap keeps a corrupt size field from exhausting memory).
const MAX_NPY_BYTES: u64 = 1 << 28;

/// The bytes of `<key>.npy` in `npz`, read to the end so that the zip CRC is
/// checked (a truncated or corrupted member is an error, not wrong numbers).
fn read_npz_member<R: std::io::Read + std::io::Seek>(
    npz: &mut npyz::npz::NpzArchive<R>,
    key: &str,
) -> Result<Vec<u8>, String> {
    use std::io::Read as _;
    if !npz.array_names().any(|n| n == key) {
        return Err("is missing".into());
    }
    let member = npz
        .zip_archive()
        .by_name(&format!("{key}.npy"))
        .map_err(|e| format!("cannot read: {e}"))?;
    if member.size() > MAX_NPY_BYTES {
        return Err(format!(
            "{} bytes, more than the {MAX_NPY_BYTES} read",
            member.size()
        ));
    }
    let mut bytes = Vec::new();
    member
        .take(MAX_NPY_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("truncated or corrupted ({e})"))?;
    Ok(bytes)
}

/// The value text after `'key':` in an `.npy` header dict.
fn npy_header_value<'a>(header: &'a str, key: &str) -> Result<&'a str, String> {
    let at = header
        .find(&format!("'{key}'"))
        .or_else(|| header.find(&format!("\"{key}\"")))
        .ok_or_else(|| format!("the .npy header has no `{key}`"))?;
    let rest = header[at + key.len() + 2..].trim_start();
    rest.strip_prefix(':')
        .map(str::trim_start)
        .ok_or_else(|| format!("malformed .npy header near `{key}`"))
}

/// Parses one `.npy` array of float64 (`<f8` or `>f8`): its shape, whether it
/// is in Fortran order, and the values in file order. Every size is checked
/// against the bytes present, so no header makes this allocate more than the
/// member holds.
pub(crate) fn parse_npy_f64(bytes: &[u8]) -> Result<(Vec<u64>, bool, Vec<f64>), String> {
    let not_npy = || "not an .npy array (no NPY header)".to_string();
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(not_npy());
    }
    let (len, start) = match bytes[6] {
        1 => (
            usize::from(u16::from_le_bytes([bytes[8], bytes[9]])),
            10usize,
        ),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy format version {v}")),
    };
    let header = bytes
        .get(start..start.saturating_add(len))
        .and_then(|h| core::str::from_utf8(h).ok())
        .ok_or_else(|| "truncated or malformed .npy header".to_string())?;
    let descr = npy_header_value(header, "descr")?;
    let big_endian = if descr.starts_with("'<f8'") || descr.starts_with("\"<f8\"") {
        false
    } else if descr.starts_with("'>f8'") || descr.starts_with("\">f8\"") {
        true
    } else {
        let shown: String = descr.chars().take_while(|&c| c != ',').collect();
        return Err(format!("dtype {shown} is not float64 ('<f8')"));
    };
    let order = npy_header_value(header, "fortran_order")?;
    let fortran = if order.starts_with("True") {
        true
    } else if order.starts_with("False") {
        false
    } else {
        return Err("malformed `fortran_order` in the .npy header".into());
    };
    let shape_text = npy_header_value(header, "shape")?;
    let shape_text = shape_text
        .strip_prefix('(')
        .and_then(|t| t.split_once(')'))
        .map(|(inside, _)| inside)
        .ok_or_else(|| "malformed `shape` in the .npy header".to_string())?;
    let mut shape = Vec::new();
    for d in shape_text
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
    {
        shape.push(
            d.parse::<u64>()
                .map_err(|_| format!("malformed `shape` ({shape_text}) in the .npy header"))?,
        );
    }
    let data = &bytes[start + len..];
    let need = shape
        .iter()
        .try_fold(8u64, |acc, &d| acc.checked_mul(d))
        .filter(|&b| b <= data.len() as u64);
    if need != Some(data.len() as u64) {
        return Err(format!(
            "shape {shape:?} does not match the {} bytes of data (truncated or malformed array)",
            data.len()
        ));
    }
    let values = data
        .chunks_exact(8)
        .map(|c| {
            let mut b = [0u8; 8];
            b.copy_from_slice(c);
            if big_endian {
                f64::from_be_bytes(b)
            } else {
                f64::from_le_bytes(b)
            }
        })
        .collect();
    Ok((shape, fortran, values))
}
