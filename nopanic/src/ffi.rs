//! Link-time proof that the C API (`ffi/`) cannot panic.
//!
//! The C API's source (`ffi/src/lib.rs`, with its modules `types.rs` and
//! `checks.rs`) is compiled into this binary as a module (its crate builds a `staticlib`, which would need its own panic
//! handler as a dependency) and every exported function is called with
//! arguments read with `read_volatile` from statics the optimiser knows
//! nothing about: every pointer (NULL, misaligned, anywhere), every size and
//! count, every configuration field, flag and input number. The binary is
//! linked with `panic-never`: if a panicking branch survives optimisation in
//! any of them, the link fails. The binary is never run (the pointers are
//! arbitrary bits); the link is the proof. See `README.md`.
#![no_std]
#![no_main]

use core::ffi::{c_char, c_void};
use core::ptr::{addr_of, addr_of_mut, read_volatile, write_volatile};

use cortex_m_rt::entry;

#[cfg(not(feature = "never"))]
use panic_halt as _;
#[cfg(feature = "never")]
use panic_never as _;

#[allow(
    dead_code,
    unused_attributes,
    unexpected_cfgs,
    clippy::all,
    missing_docs
)]
#[path = "../../ffi/src/lib.rs"]
mod ldcbf_ffi;

use ldcbf_ffi::{
    LdcbfConfig, LdcbfController, LdcbfInput, LdcbfOutput, ldcbf_config_default, ldcbf_configure,
    ldcbf_cycle_status_name, ldcbf_init, ldcbf_last_error, ldcbf_lip_propagate, ldcbf_reset,
    ldcbf_result_name, ldcbf_step, ldcbf_step_moving,
};

/// Opaque words: pointer values, sizes, counts, scalars.
static mut WORDS: [usize; 32] = [0; 32];
/// Opaque doubles.
static mut REALS: [f64; 8] = [0.0; 8];
/// Outputs, written so that nothing is dead code.
static mut OUT: [usize; 8] = [0; 8];

fn words() -> [usize; 32] {
    // SAFETY: plain volatile read of a static that is never referenced.
    unsafe { read_volatile(addr_of!(WORDS)) }
}

fn reals() -> [f64; 8] {
    // SAFETY: as above.
    unsafe { read_volatile(addr_of!(REALS)) }
}

fn publish(v: [usize; 8]) {
    // SAFETY: plain volatile write of a static that is never referenced.
    unsafe { write_volatile(addr_of_mut!(OUT), v) }
}

#[entry]
fn main() -> ! {
    loop {
        let w = words();
        let r = reals();
        // Arbitrary pointers: any bits, NULL and misaligned included.
        let ctl = w[0] as *mut LdcbfController;
        let config = w[1] as *mut LdcbfConfig;
        let input = w[2] as *const LdcbfInput;
        let out = w[3] as *mut LdcbfOutput;
        let points = w[4] as *const f64;
        let counts = w[5] as *const u32;
        let buf = w[6] as *mut c_char;
        let storage = w[7] as *mut c_void;
        let handle_out = w[8] as *mut *mut LdcbfController;
        let p = w[9] as *const f64;
        let p_out = w[10] as *mut f64;
        let mut res = [0usize; 8];
        // SAFETY: never executed (the binary is only linked); every call is
        // made with arbitrary arguments so that no branch can be folded away.
        unsafe {
            res[0] = ldcbf_init(storage, w[11], handle_out) as usize;
            res[1] = ldcbf_config_default(config) as usize;
            res[2] = ldcbf_configure(ctl, config) as usize;
            res[3] = ldcbf_step(ctl, input, points, counts, w[12] as u32, out) as usize
                ^ ldcbf_step_moving(
                    ctl,
                    input,
                    points,
                    counts,
                    w[17] as u32,
                    w[18] as *const f64,
                    out,
                ) as usize;
            res[4] = ldcbf_lip_propagate(ctl, p, p, p, r[0], p_out, p_out) as usize;
            res[5] = ldcbf_last_error(ctl, buf, w[13]);
            if w[14] > 0 {
                res[6] = ldcbf_reset(ctl) as usize;
            }
            res[7] = ldcbf_result_name(w[15] as u32) as usize
                ^ ldcbf_cycle_status_name(w[16] as u32) as usize;
        }
        publish(res);
    }
}
