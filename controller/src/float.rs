//! The square root the controller uses.
//!
//! [`sqrt`] is `libm::sqrt` (IEEE 754 correctly rounded, in software on targets
//! without a hardware square root in `core`), or, with the crate feature
//! `hw-sqrt` on 32-bit Arm, the FPU's `VSQRT.F64` instruction. Both are correctly
//! rounded, so the results are bit for bit the same; the instruction is one
//! instruction (14 cycles on a Cortex-M7) where libm's software square root is
//! about a hundred. The feature needs a double-precision FPU (Cortex-M7 with
//! FPv5-D16, e.g. `-C target-cpu=cortex-m7`); the assembler rejects it
//! elsewhere. The firmware (`firmware/`) turns it on.

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

#[cfg(test)]
mod tests {
    use super::sqrt;

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
