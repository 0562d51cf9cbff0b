//! The npz layout of the external test set (mpc_qpbenchmark): reading and
//! writing a [`DenseProblem`], and the `.npy` parser behind it.

use std::path::Path;

use crate::npy_header::{NpyHeader, parse_npy_header};
use crate::problem::{DenseProblem, ProblemError};

impl DenseProblem {
    /// Reads an `.npz` file of the qpbenchmark layout: float64 arrays `P`
    /// `[n, n]`, `q` `[n]` (both required), `G` `[m, n]` with `h` `[m]`, `A`
    /// `[me, n]` with `b` `[me]`, `lb` `[n]`, `ub` `[n]` (C or Fortran order).
    /// Each of the last six may be absent: missing, an empty array, or a pickled
    /// `None` (a 0-d object array holding `None`, matched byte-wise, never
    /// unpickled); `G` and `h` (`A` and `b`) must be both absent or both
    /// present. Other keys are ignored. The values are checked as by
    /// [`DenseProblem::validate`] (no NaN; infinities only as absent bounds;
    /// `lb <= ub`). Errors name the file and the key: not a zip archive, a
    /// missing key, a truncated or corrupted member (the zip CRC is checked),
    /// another dtype, a wrong shape, a bad value.
    pub fn from_npz(path: &Path) -> Result<Self, ProblemError> {
        let name = path.display().to_string();
        let fail = |reason: String| ProblemError::File {
            file: name.clone(),
            reason,
        };
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
        let mut left = MAX_NPZ_BYTES;
        let mut read = |key: &str, required: bool| -> Result<Member, ProblemError> {
            let at = |m: String| fail(format!("key `{key}`: {m}"));
            if !required && !npz.array_names().any(|n| n == key) {
                return Ok(Err("is missing"));
            }
            let bytes = read_npz_member(&mut npz, key, &mut left).map_err(at)?;
            if !required && is_pickled_none(&bytes) {
                return Ok(Err("is a pickled None"));
            }
            let (shape, fortran, data) = parse_npy_f64(&bytes).map_err(at)?;
            if !required && data.is_empty() {
                return Ok(Err("is empty"));
            }
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
            Ok(Ok((shape, data)))
        };
        let (ps, P) = read("P", true)?.unwrap_or_default();
        let (qs, q) = read("q", true)?.unwrap_or_default();
        let g = read("G", false)?;
        let h = read("h", false)?;
        let a = read("A", false)?;
        let b = read("b", false)?;
        let lb = read("lb", false)?;
        let ub = read("ub", false)?;
        let bad = |key: &str, got: &[u64], want: String| {
            fail(format!("key `{key}` has shape {got:?}, expected {want}"))
        };
        let [n, n2] = ps[..] else {
            return Err(bad("P", &ps, "[n, n]".into()));
        };
        if n != n2 {
            return Err(bad("P", &ps, "[n, n]".into()));
        }
        if n > MAX_QP_VARIABLES {
            return Err(fail(format!(
                "key `P`: {n} variables, more than the {MAX_QP_VARIABLES} a QP file may have"
            )));
        }
        if qs[..] != [n] {
            return Err(bad("q", &qs, format!("[{n}] (the size of `P`)")));
        }
        // A matrix and its right-hand side: both absent, or [r, n] and [r].
        let pair = |rows: &str,
                    (mk, mat): (&str, Member),
                    (vk, vec): (&str, Member)|
         -> Result<(usize, Vec<f64>, Vec<f64>), ProblemError> {
            let (ms, mat, vs, vec) = match (mat, vec) {
                (Err(_), Err(_)) => return Ok((0, Vec::new(), Vec::new())),
                (Ok((ms, mat)), Ok((vs, vec))) => (ms, mat, vs, vec),
                (Ok((ms, _)), Err(how)) => {
                    return Err(fail(format!(
                        "key `{vk}`: {how}, but `{mk}` is given (shape {ms:?})"
                    )));
                }
                (Err(how), Ok((vs, _))) => {
                    return Err(fail(format!(
                        "key `{mk}`: {how}, but `{vk}` is given (shape {vs:?})"
                    )));
                }
            };
            let [r, c] = ms[..] else {
                return Err(bad(mk, &ms, format!("[{rows}, {n}]")));
            };
            if c != n {
                return Err(bad(mk, &ms, format!("[{rows}, {n}]")));
            }
            if r > MAX_QP_ROWS {
                return Err(fail(format!(
                    "key `{mk}`: {r} rows, more than the {MAX_QP_ROWS} a QP file may have"
                )));
            }
            if vs[..] != [r] {
                return Err(bad(vk, &vs, format!("[{r}] (the rows of `{mk}`)")));
            }
            Ok((r as usize, mat, vec))
        };
        let (m, G, h) = pair("m", ("G", g), ("h", h))?;
        let (me, A, b) = pair("me", ("A", a), ("b", b))?;
        let bound = |key: &str, v: Member| match v {
            Err(_) => Ok(Vec::new()),
            Ok((s, v)) if s[..] == [n] => Ok(v),
            Ok((s, _)) => Err(bad(key, &s, format!("[{n}] (the size of `P`)"))),
        };
        let (lb, ub) = (bound("lb", lb)?, bound("ub", ub)?);
        let p = DenseProblem {
            n: n as usize,
            m,
            me,
            P,
            q,
            G,
            h,
            A,
            b,
            lb,
            ub,
        };
        p.check("key").map_err(|e| ProblemError::InFile {
            file: name.clone(),
            error: Box::new(e),
        })?;
        Ok(p)
    }

    /// Writes the problem to an `.npz` file, the layout
    /// [`DenseProblem::from_npz`] reads and `numpy.load` opens: float64, C
    /// order, `P` `[n, n]`, `q` `[n]`, `G` `[m, n]` and `h` `[m]` always (also
    /// when `m = 0`, for readers that expect them), `A` `[me, n]` and `b` `[me]`
    /// when `me > 0`, `lb` and `ub` `[n]` when present. Absent members are not
    /// written (the qpbenchmark files carry pickled `None`s instead), so a round
    /// trip gives the same problem. Errors name the file.
    pub fn write_npz(&self, path: &Path) -> Result<(), ProblemError> {
        use npyz::WriterBuilder;
        let name = path.display().to_string();
        let err = |e: std::io::Error| ProblemError::File {
            file: name.clone(),
            reason: format!("cannot write npz: {e}"),
        };
        let mut npz = npyz::npz::NpzWriter::create(path).map_err(err)?;
        let (n, m, me) = (self.n as u64, self.m as u64, self.me as u64);
        let arrays: [(&str, Vec<u64>, &[f64], bool); 8] = [
            ("P", vec![n, n], &self.P, true),
            ("q", vec![n], &self.q, true),
            ("G", vec![m, n], &self.G, true),
            ("h", vec![m], &self.h, true),
            ("A", vec![me, n], &self.A, me > 0),
            ("b", vec![me], &self.b, me > 0),
            ("lb", vec![n], &self.lb, !self.lb.is_empty()),
            ("ub", vec![n], &self.ub, !self.ub.is_empty()),
        ];
        for (key, shape, data, present) in arrays {
            if !present {
                continue;
            }
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

/// An optional member as read: its shape and values (row-major), or how it is
/// absent (`is missing`, `is a pickled None`, `is empty`).
type Member = Result<(Vec<u64>, Vec<f64>), &'static str>;

/// Most bytes the `.npy` members of one npz file may decompress to, all
/// members together: 64 MiB (the QPs of this project have a few kB). A member over what is left is refused from its declared size,
/// before it is read, and its read stops there whatever it declares, so a
/// small compressed file cannot make the reader allocate more.
pub const MAX_NPZ_BYTES: u64 = 64 << 20;

/// Most variables `n` of a QP read from an npz file (the dense solver's
/// factor is `n x n`; the project's QPs have at most 60).
pub const MAX_QP_VARIABLES: u64 = 1000;

/// Most constraint rows (`m` of `G`, `me` of `A`, each) of a QP read from an
/// npz file.
pub const MAX_QP_ROWS: u64 = 8000;

/// The bytes of `<key>.npy` in `npz`, read to the end so that the zip CRC is
/// checked (a truncated or corrupted member is an error, not wrong numbers).
fn read_npz_member<R: std::io::Read + std::io::Seek>(
    npz: &mut npyz::npz::NpzArchive<R>,
    key: &str,
    left: &mut u64,
) -> Result<Vec<u8>, String> {
    use std::io::Read as _;
    if !npz.array_names().any(|n| n == key) {
        return Err("is missing".into());
    }
    let member = npz
        .zip_archive()
        .by_name(&format!("{key}.npy"))
        .map_err(|e| format!("cannot read: {e}"))?;
    let too_big = |size: u64| {
        format!(
            "decompresses to {size} bytes, more than the {} bytes left of the \
             {MAX_NPZ_BYTES} one npz file may decompress to",
            *left
        )
    };
    if member.size() > *left {
        return Err(too_big(member.size()));
    }
    let mut bytes = Vec::new();
    member
        .take(*left + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("truncated or corrupted ({e})"))?;
    if bytes.len() as u64 > *left {
        return Err(too_big(bytes.len() as u64));
    }
    *left -= bytes.len() as u64;
    Ok(bytes)
}

/// The header dict of an `.npy` array, parsed, and the offset of its data.
fn npy_header(bytes: &[u8]) -> Result<(NpyHeader, usize), String> {
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
    Ok((parse_npy_header(header)?, start + len))
}

/// Whether an `.npy` member is a pickled `None`, the qpbenchmark marker of an
/// absent member: dtype `|O`, shape `()`, and a pickle that is `None` itself
/// (`[PROTO v] [FRAME len] N .`) or numpy's 0-d object array holding `None`
/// (its element list `] [memo] N a`, then the end `.`). The pickle is matched
/// byte-wise, never executed.
fn is_pickled_none(bytes: &[u8]) -> bool {
    let Ok((header, start)) = npy_header(bytes) else {
        return false;
    };
    if header.descr != "|O" || !header.shape.is_empty() {
        return false;
    }
    let mut data = &bytes[start..];
    if let [0x80, _, rest @ ..] = data {
        data = rest; // PROTO
    }
    if let [0x95, rest @ ..] = data
        && rest.len() >= 8
    {
        data = &rest[8..]; // FRAME
    }
    if data == b"N." {
        return true;
    }
    // `]` EMPTY_LIST, an optional memo op (BINPUT `q n`, LONG_BINPUT `r nnnn`,
    // MEMOIZE 0x94), `N` NONE, `a` APPEND: a one-element list holding None.
    let list_of_none = |after: &[u8]| {
        let memo = match after.first() {
            Some(b'q') => 2,
            Some(b'r') => 5,
            Some(0x94) => 1,
            _ => 0,
        };
        after.get(memo..memo + 2) == Some(b"Na")
    };
    data.ends_with(b".") && (0..data.len()).any(|i| data[i] == b']' && list_of_none(&data[i + 1..]))
}

/// Parses one `.npy` array of float64 (`<f8` or `>f8`): its shape, whether it
/// is in Fortran order, and the values in file order. Every size is checked
/// against the bytes present, so no header makes this allocate more than the
/// member holds.
pub(crate) fn parse_npy_f64(bytes: &[u8]) -> Result<(Vec<u64>, bool, Vec<f64>), String> {
    let (header, start) = npy_header(bytes)?;
    let big_endian = match header.descr.as_str() {
        "<f8" => false,
        ">f8" => true,
        other => {
            return Err(format!(
                "dtype '{}' is not float64 ('<f8')",
                other.chars().take(40).collect::<String>()
            ));
        }
    };
    let (shape, fortran) = (header.shape, header.fortran_order);
    let data = &bytes[start..];
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
