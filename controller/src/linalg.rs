//! The solver's small kernels, for any slice lengths (for the static sizes
//! the lengths are constants, so the loops unroll and vectorise without
//! bounds checks): dot products ([`dot`], [`dot_d`]), copies ([`copy`]),
//! Givens rotations ([`givens`]), clamping ([`clamp`]), the square root
//! ([`sqrt`]) and column access to nalgebra's column-major storage
//! ([`column`], [`columns`] and their ranges). Below everything else in the
//! crate: it imports nothing from it.
//!
//! The square root: [`sqrt`] is `libm::sqrt` (IEEE 754 correctly rounded, in
//! software on targets without a hardware square root in `core`), or, with
//! the crate feature `hw-sqrt` on 32-bit Arm, the FPU's `VSQRT.F64`
//! instruction. Both are correctly rounded, so the results are bit for bit
//! the same; the instruction is one instruction (14 cycles on a Cortex-M7)
//! where libm's software square root is about a hundred. The feature needs a
//! double-precision FPU (Cortex-M7 with FPv5-D16, e.g.
//! `-C target-cpu=cortex-m7`); the assembler rejects it elsewhere. The
//! firmware (`firmware/`) turns it on.

use nalgebra::Dim;

/// `dst[k] = src[k]` over the shorter length (`copy_from_slice` without its
/// length assertion).
#[inline(always)]
pub(crate) fn copy(dst: &mut [f64], src: &[f64]) {
    for (a, &b) in dst.iter_mut().zip(src) {
        *a = b;
    }
}

/// `a . b` over the shorter length, with two partial sums (independent add
/// chains; for the static sizes the lengths are constants, so the loop
/// unrolls and vectorises without bounds checks).
#[inline(always)]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 2];
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        acc[k % 2] += x * y;
    }
    acc[0] + acc[1]
}

/// [`dot`] for vectors of the dimension `D` (slices of the same length, at
/// most `D`): the same operations in the same order (the even and the odd
/// products each summed in order, then added), so the same bits. Written as
/// pairs on hosts and for run-time sizes (`Dyn`): on hosts each pair of
/// products becomes one two-lane multiply and one two-lane add (SSE2 on
/// x86-64: the even products in one lane, the odd ones in the other), where
/// [`dot`]'s loop by index stays scalar for the longer rows; for run-time
/// sizes the two chains stay in registers (13 % off `solve` at n = 50). On
/// bare-metal targets the static sizes use [`dot`] itself (fully unrolled:
/// the form the Cortex-M7 runs fastest).
#[inline(always)]
pub(crate) fn dot_d<D: Dim>(a: &[f64], b: &[f64]) -> f64 {
    if cfg!(target_os = "none") && D::try_to_usize().is_some() {
        return dot(a, b);
    }
    let (mut even, mut odd) = (0.0f64, 0.0f64);
    let (mut pa, mut pb) = (a.chunks_exact(2), b.chunks_exact(2));
    for (x, y) in pa.by_ref().zip(pb.by_ref()) {
        if let ([x0, x1], [y0, y1]) = (x, y) {
            even += x0 * y0;
            odd += x1 * y1;
        }
    }
    if let (Some(x), Some(y)) = (pa.remainder().first(), pb.remainder().first()) {
        even += x * y;
    }
    even + odd
}

/// Givens rotation `(c, s, r)` with `c a + s b = r`, `-s a + c b = 0`.
pub(crate) fn givens(a: f64, b: f64) -> (f64, f64, f64) {
    // sqrt(a^2 + b^2) is within an ulp or two of hypot; hypot (slower, no
    // overflow or underflow) only when the squares leave the normal range.
    let r2 = a * a + b * b;
    let r = if (1e-280..=1e280).contains(&r2) {
        sqrt(r2)
    } else {
        libm::hypot(a, b)
    };
    if r == 0.0 {
        return (1.0, 0.0, 0.0);
    }
    (a / r, b / r, r)
}

/// `x` limited to `[lo, hi]`: `f64::clamp` without its `lo <= hi` assertion.
///
/// The controller's bounds come from a validated [`Config`], which the optimiser
/// cannot see, so `f64::clamp` would keep a panicking branch in `step` (see
/// `nopanic/`). Same steps as `f64::clamp`, so the same result whenever
/// `lo <= hi`; a NaN `x` stays NaN; with `lo > hi` the result is `hi`.
pub(crate) fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    let mut x = x;
    if x < lo {
        x = lo;
    }
    if x > hi {
        x = hi;
    }
    x
}

/// `sqrt(x)` for `x >= 0`; NaN for a negative or NaN `x`; `+inf` for `+inf`.
#[cfg(not(all(feature = "hw-sqrt", target_arch = "arm")))]
#[inline(always)]
pub(crate) fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}

/// `sqrt(x)` for `x >= 0`; NaN for a negative or NaN `x`; `+inf` for `+inf`
/// (`VSQRT.F64`, IEEE 754 correctly rounded).
#[cfg(all(feature = "hw-sqrt", target_arch = "arm"))]
#[inline(always)]
#[allow(unsafe_code)]
pub(crate) fn sqrt(x: f64) -> f64 {
    let r: f64;
    // SAFETY: one `vsqrt.f64` between two double-precision registers: it reads
    // no memory, writes no memory and no stack, and leaves the APSR flags alone
    // (it only sets FPSCR's cumulative exception bits, as any f64 arithmetic
    // does). It cannot trap: FP exceptions are not enabled on Cortex-M by
    // default, and an invalid operation gives the default NaN.
    unsafe {
        core::arch::asm!(
            "vsqrt.f64 {r}, {x}",
            x = in(dreg_low16) x,
            r = lateout(dreg_low16) r,
            options(pure, nomem, nostack, preserves_flags),
        );
    }
    r
}

/// Column `j` of a column-major matrix with `n` rows stored in `s`.
#[inline(always)]
pub(crate) fn column(s: &[f64], n: usize, j: usize) -> Option<&[f64]> {
    // One test, `j < columns` (for the static sizes a compare with the
    // constant NC, as indexing an array of columns); then `j n + n <= len`
    // cannot overflow, and the slice's length is visibly `n` (a constant
    // there too), so loops over the column unroll.
    if n == 0 || j >= s.len() / n {
        return None;
    }
    let start = j * n;
    s.get(start..start + n)
}

/// Column `j` of a column-major matrix with `n` rows stored in `s`, mutable.
#[inline(always)]
pub(crate) fn column_mut(s: &mut [f64], n: usize, j: usize) -> Option<&mut [f64]> {
    if n == 0 || j >= s.len() / n {
        return None;
    }
    let start = j * n;
    s.get_mut(start..start + n)
}

/// The columns of a column-major matrix with `n > 0` rows stored in `s`
/// (nothing for `n = 0`).
#[inline(always)]
pub(crate) fn columns(s: &[f64], n: usize) -> core::slice::ChunksExact<'_, f64> {
    // `n.max(1)`: a zero chunk size would panic; with n = 0 the slice is empty.
    s.chunks_exact(n.max(1))
}

/// Columns `j0..j1` of a column-major matrix with `n > 0` rows stored in `s`
/// (fewer when `s` ends before; no `skip` or `take` on the chunks, which the
/// compiler may leave as an out-of-line `nth`).
#[inline(always)]
pub(crate) fn columns_in(
    s: &[f64],
    n: usize,
    j0: usize,
    j1: usize,
) -> core::slice::ChunksExact<'_, f64> {
    let end = j1.saturating_mul(n).min(s.len());
    let start = j0.saturating_mul(n).min(end);
    columns(s.get(start..end).unwrap_or(&[]), n)
}

/// [`columns_in`], mutable.
#[inline(always)]
pub(crate) fn columns_in_mut(
    s: &mut [f64],
    n: usize,
    j0: usize,
    j1: usize,
) -> core::slice::ChunksExactMut<'_, f64> {
    let end = j1.saturating_mul(n).min(s.len());
    let start = j0.saturating_mul(n).min(end);
    columns_mut(s.get_mut(start..end).unwrap_or(&mut []), n)
}

/// [`columns`], mutable.
#[inline(always)]
pub(crate) fn columns_mut(s: &mut [f64], n: usize) -> core::slice::ChunksExactMut<'_, f64> {
    s.chunks_exact_mut(n.max(1))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::{dot, dot_d, sqrt};
    use nalgebra::{Const, Dyn};

    /// `libm::sincos` is `(libm::sin, libm::cos)` bit for bit (the gait
    /// rows and the fallback take one `sincos` of a heading, so that the
    /// firmware links one kernel, not three): headings of every magnitude
    /// the controller accepts, and the multiples of pi / 4 where the
    /// argument reduction switches quadrant.
    #[test]
    fn sincos_is_sin_and_cos_bit_for_bit() {
        let mut next = mixed(7);
        let quarter = core::f64::consts::FRAC_PI_4;
        let angles = (0..200_000)
            .map(|_| next() * 1e2)
            .chain((-400..400).map(|k| f64::from(k) * quarter))
            .chain([0.0, -0.0, 1e6, -1e6, 3.0e5, f64::MIN_POSITIVE]);
        for a in angles {
            let (s, c) = libm::sincos(a);
            assert_eq!(s.to_bits(), libm::sin(a).to_bits(), "sin {a}");
            assert_eq!(c.to_bits(), libm::cos(a).to_bits(), "cos {a}");
        }
    }

    /// Seeded numbers of mixed signs and magnitudes (`1e-4` to `1e4`), so
    /// that the sums of dot products round: for tests that compare the
    /// bits of two orders of the same operations.
    pub(crate) fn mixed(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            (u - 0.5) * 10f64.powi((state % 9) as i32 - 4)
        }
    }

    /// [`dot_d`] in each of its forms (by index, as pairs) has the bits of
    /// [`dot`]: every length up to the dimension, odd ones included, with
    /// entries of mixed signs and magnitudes (rounding in every sum).
    #[test]
    fn dot_d_has_the_bits_of_dot() {
        let mut rnd = mixed(0x2545_f491_4f6c_dd1d);
        for len in 0..=40 {
            for _ in 0..20 {
                let a: [f64; 40] = core::array::from_fn(|_| rnd());
                let b: [f64; 40] = core::array::from_fn(|_| rnd());
                let (a, b) = (&a[..len], &b[..len]);
                let want = dot(a, b).to_bits();
                assert_eq!(dot_d::<Const<40>>(a, b).to_bits(), want, "len {len}");
                assert_eq!(dot_d::<Const<20>>(a, b).to_bits(), want, "len {len}");
                assert_eq!(dot_d::<Dyn>(a, b).to_bits(), want, "len {len}");
            }
        }
    }

    #[test]
    fn matches_libm_bit_for_bit() {
        let mut x = 1.0e-300_f64;
        while x < 1.0e300 {
            for y in [x, x * 1.000_000_1, x * 3.7] {
                assert_eq!(sqrt(y).to_bits(), libm::sqrt(y).to_bits(), "{y}");
            }
            x *= 1.7;
        }
        assert_eq!(sqrt(0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(sqrt(-0.0).to_bits(), (-0.0f64).to_bits());
        assert!(sqrt(-1.0).is_nan());
        assert!(sqrt(f64::NAN).is_nan());
        assert_eq!(sqrt(f64::INFINITY), f64::INFINITY);
    }
}
