//! Checks of the caller's pointers and arrays (NULL, alignment, overlap with
//! the controller, the controller's tag, the obstacle arrays read into
//! polygons) and the controller's last error, for `ldcbf_last_error`.

use core::mem::size_of;
use core::ptr::addr_of;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{ConfigError, ConvexPolygon, GeometryError};

use super::types::LdcbfResult;
use super::{LDCBF_MAX_OBSTACLES, LDCBF_MAX_POINTS, LDCBF_MAX_VERTICES, LdcbfController, MAGIC};
// Named in the doc comments only (intra-doc links).
#[cfg(doc)]
use super::{ldcbf_init, ldcbf_last_error, ldcbf_step, ldcbf_step_moving};

/// The last error recorded in a controller, for [`ldcbf_last_error`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum LastError {
    None,
    Config(ConfigError),
    Flag(&'static str),
    Argument(&'static str),
    Pointer(&'static str),
    TooManyObstacles(u32),
    TooManyPoints(u32, u32),
    Obstacle(u32, GeometryError),
}

impl core::fmt::Display for LastError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LastError::None => f.write_str("no error"),
            LastError::Config(e) => write!(f, "{e}"),
            LastError::Flag(field) => {
                write!(f, "invalid controller setting `{field}`: must be 0 or 1")
            }
            LastError::Argument(what) => write!(f, "invalid argument: {what}"),
            LastError::Pointer(name) => write!(
                f,
                "pointer argument `{name}` is NULL, misaligned or overlaps the controller"
            ),
            LastError::TooManyObstacles(n) => write!(
                f,
                "{n} obstacles given, at most {LDCBF_MAX_OBSTACLES} (LDCBF_MAX_OBSTACLES) are accepted"
            ),
            LastError::TooManyPoints(i, n) => write!(
                f,
                "obstacle {i}: {n} points given, at most {LDCBF_MAX_POINTS} (LDCBF_MAX_POINTS) are accepted"
            ),
            LastError::Obstacle(i, e) => write!(f, "obstacle {i}: {e}"),
        }
    }
}

// ---------------------------------------------------------------------------
// Pointer checks

/// `Ok` if `p` is non-NULL and aligned for `T`.
pub(crate) fn check_ptr<T>(p: *const T) -> Result<(), LdcbfResult> {
    if p.is_null() {
        Err(LdcbfResult::NullPointer)
    } else if !p.is_aligned() {
        Err(LdcbfResult::Misaligned)
    } else {
        Ok(())
    }
}

/// Whether the byte ranges `[a, a + a_len)` and `[b, b + b_len)` intersect
/// (addresses only; lengths saturate).
pub(crate) fn overlaps(a: usize, a_len: usize, b: usize, b_len: usize) -> bool {
    a < b.saturating_add(b_len) && b < a.saturating_add(a_len) && a_len > 0 && b_len > 0
}

/// `Ok` if the `bytes` bytes at `p` do not overlap the controller at `ctl`.
pub(crate) fn check_disjoint<T>(
    p: *const T,
    bytes: usize,
    ctl: *const LdcbfController,
) -> Result<(), LdcbfResult> {
    if overlaps(
        p as usize,
        bytes,
        ctl as usize,
        size_of::<LdcbfController>(),
    ) {
        Err(LdcbfResult::Overlap)
    } else {
        Ok(())
    }
}

/// `Ok` if `ctl` is non-NULL, aligned and tagged by [`ldcbf_init`].
///
/// # Safety
/// If `ctl` is non-NULL and aligned it must be valid for reads of a
/// `LdcbfController` (the storage passed to [`ldcbf_init`]).
pub(crate) unsafe fn check_controller(ctl: *const LdcbfController) -> Result<(), LdcbfResult> {
    check_ptr(ctl)?;
    // SAFETY: `ctl` is non-NULL and aligned, and valid for reads by the
    // caller's contract; `magic` is a plain `u64` (any bits are a value), read
    // without forming a reference to the rest of the controller.
    let magic = unsafe { addr_of!((*ctl).magic).read_volatile() };
    if magic == MAGIC {
        Ok(())
    } else {
        Err(LdcbfResult::NotInitialized)
    }
}

// ---------------------------------------------------------------------------
// Obstacle arrays

/// The point count of each obstacle and all their points `{x, y}`.
type ObstacleSlices<'a> = (&'a [u32], &'a [[f64; 2]]);

/// The caller's obstacle arrays as slices: `n` point counts and the points
/// they add up to, checked for NULL, alignment, size and overlap with the
/// controller.
///
/// # Safety
/// As [`ldcbf_step`] for `points` and `counts`.
pub(crate) unsafe fn obstacle_slices<'a>(
    ctl: *const LdcbfController,
    points: *const f64,
    counts: *const u32,
    n: u32,
) -> Result<ObstacleSlices<'a>, (LdcbfResult, LastError)> {
    if n == 0 {
        return Ok((&[], &[]));
    }
    let bad = |r: LdcbfResult, what: &'static str| (r, LastError::Pointer(what));
    if usize::try_from(n).map_or(true, |n| n > LDCBF_MAX_OBSTACLES) {
        return Err((
            LdcbfResult::TooManyObstacles,
            LastError::TooManyObstacles(n),
        ));
    }
    let n = n as usize; // <= LDCBF_MAX_OBSTACLES, checked above
    check_ptr(counts)
        .and(check_disjoint(
            counts,
            n.saturating_mul(size_of::<u32>()),
            ctl,
        ))
        .map_err(|r| bad(r, "point_counts"))?;
    // SAFETY: non-NULL, aligned, readable for `n` values by contract, at most
    // `LDCBF_MAX_OBSTACLES * 4` bytes, outside the controller.
    let counts = unsafe { core::slice::from_raw_parts(counts, n) };
    let mut total = 0usize;
    for (i, &c) in (0u32..).zip(counts) {
        if c as usize > LDCBF_MAX_POINTS {
            return Err((LdcbfResult::InvalidObstacle, LastError::TooManyPoints(i, c)));
        }
        // At most LDCBF_MAX_OBSTACLES * LDCBF_MAX_POINTS: cannot overflow.
        total = total.saturating_add(c as usize);
    }
    if total == 0 {
        // Every obstacle is empty: reported by `load_obstacles`.
        return Ok((counts, &[]));
    }
    let pts = points.cast::<[f64; 2]>();
    check_ptr(pts)
        .and(check_disjoint(
            pts,
            total.saturating_mul(size_of::<[f64; 2]>()),
            ctl,
        ))
        .map_err(|r| bad(r, "points"))?;
    // SAFETY: non-NULL, aligned (`[f64; 2]` has the alignment of `f64`),
    // readable for `2 * total` doubles by contract, at most
    // `LDCBF_MAX_OBSTACLES * LDCBF_MAX_POINTS * 16` bytes (1 MiB), outside the
    // controller.
    let pts = unsafe { core::slice::from_raw_parts(pts, total) };
    Ok((counts, pts))
}

/// The caller's `n` obstacle velocities (`2 n` doubles at `velocities`, m/s)
/// copied into `buf`: empty when `velocities` is NULL or `n` is 0 (every
/// obstacle at rest), else checked for alignment and overlap with the
/// controller.
///
/// # Safety
/// As [`ldcbf_step_moving`] for `velocities`; `n <= LDCBF_MAX_OBSTACLES`.
pub(crate) unsafe fn obstacle_velocities(
    ctl: *const LdcbfController,
    velocities: *const f64,
    n: usize,
    buf: &mut [Vector2<f64>; LDCBF_MAX_OBSTACLES],
) -> Result<&[Vector2<f64>], LdcbfResult> {
    if velocities.is_null() || n == 0 {
        return Ok(&[]);
    }
    let v = velocities.cast::<[f64; 2]>();
    check_ptr(v).and(check_disjoint(
        v,
        n.saturating_mul(size_of::<[f64; 2]>()),
        ctl,
    ))?;
    let Some(buf) = buf.get_mut(..n) else {
        return Err(LdcbfResult::TooManyObstacles);
    };
    // SAFETY: non-NULL, aligned (`[f64; 2]` has the alignment of `f64`),
    // readable for `2 n` doubles by contract, at most
    // `LDCBF_MAX_OBSTACLES * 16` bytes, outside the controller.
    let given = unsafe { core::slice::from_raw_parts(v, n) };
    for (dst, src) in buf.iter_mut().zip(given) {
        *dst = Vector2::new(src[0], src[1]);
    }
    Ok(buf)
}

/// The caller's `n` obstacle velocity uncertainty radii (`n` doubles at
/// `radii`, m/s) copied into `buf`: empty when `radii` is NULL or `n` is 0
/// (every radius 0), else checked for alignment and overlap with the
/// controller (the values are the controller's to check).
///
/// # Safety
/// As [`ldcbf_step_uncertain`](crate::ldcbf_step_uncertain) for `radii`;
/// `n <= LDCBF_MAX_OBSTACLES`.
pub(crate) unsafe fn obstacle_radii(
    ctl: *const LdcbfController,
    radii: *const f64,
    n: usize,
    buf: &mut [f64; LDCBF_MAX_OBSTACLES],
) -> Result<&[f64], LdcbfResult> {
    if radii.is_null() || n == 0 {
        return Ok(&[]);
    }
    check_ptr(radii).and(check_disjoint(
        radii,
        n.saturating_mul(size_of::<f64>()),
        ctl,
    ))?;
    let Some(buf) = buf.get_mut(..n) else {
        return Err(LdcbfResult::TooManyObstacles);
    };
    // SAFETY: non-NULL, aligned, readable for `n` doubles by contract, at
    // most `LDCBF_MAX_OBSTACLES * 8` bytes, outside the controller.
    let given = unsafe { core::slice::from_raw_parts(radii, n) };
    buf.copy_from_slice(given);
    Ok(buf)
}

/// Validates the obstacles (convex hulls) into `buf`.
pub(crate) fn load_obstacles(
    buf: &mut heapless::Vec<ConvexPolygon<LDCBF_MAX_VERTICES>, LDCBF_MAX_OBSTACLES, usize>,
    counts: &[u32],
    mut pts: &[[f64; 2]],
) -> Result<(), LastError> {
    buf.clear();
    for (i, &c) in (0u32..).zip(counts) {
        // `pts` holds exactly the sum of the counts (`obstacle_slices`).
        let Some((these, rest)) = pts.split_at_checked(c as usize) else {
            return Err(LastError::TooManyPoints(i, c));
        };
        pts = rest;
        let poly = ConvexPolygon::hull(these).map_err(|e| LastError::Obstacle(i, e))?;
        if buf.push(poly).is_err() {
            return Err(LastError::TooManyObstacles(i));
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Last-error message

/// A `fmt::Write` into a byte buffer that keeps the last byte for a NUL,
/// drops what does not fit and counts everything.
pub(crate) struct Truncating<'a> {
    pub(crate) buf: &'a mut [u8],
    pub(crate) len: usize,
}

impl core::fmt::Write for Truncating<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let room = self.buf.len().saturating_sub(1);
        for &b in s.as_bytes() {
            if self.len < room
                && let Some(slot) = self.buf.get_mut(self.len)
            {
                *slot = b;
            }
            self.len = self.len.saturating_add(1);
        }
        Ok(())
    }
}
