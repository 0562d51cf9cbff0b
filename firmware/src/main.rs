//! Cortex-M7 firmware for QEMU's `mps2-an500`: replays the recorded control
//! cycles of `recorded.rs` through the paper's controller ([`PaperController`])
//! in order, as the host did, then twice more (each after a reset) with the
//! obstacles moving at the velocities of `moving.rs` (cycle indices `n ..
//! 2n`: `VELOCITIES`, away from the path; `2n .. 3n`: `WALK_INTO`, into
//! it), and prints over semihosting, per cycle, the
//! command (exact `f64` bits in hex), the status, the solver iterations, the
//! SysTick ticks the cycle took and its stack high-water mark. Exits QEMU
//! through semihosting (status 0 on success, 1 on a panic, fault or a cycle too
//! long to measure).
//!
//! Output (one line each, space separated; `tests/firmware_qemu.rs` parses it):
//!
//! ```text
//! ldcbf-firmware cycles <n>
//! calibration empty_ticks <t0> nop256_ticks <t1>
//! stack startup_peak <bytes> main_depth <bytes>
//! cycle <i> <foot_x bits> <foot_y bits> <turning_rate bits> <status> <iterations> <ticks> <stack bytes>
//! done max_ticks <t> max_stack <b>
//! ```
//!
//! SysTick runs on the processor clock (25 MHz on this board). Under QEMU with
//! `-icount shift=S` every instruction advances the virtual clock by `2^S` ns,
//! so a cycle's instructions are `(ticks - empty_ticks) * 40 / 2^S` (README.md);
//! `empty_ticks` is the cost of the measurement itself and `nop256_ticks` that
//! of 256 `nop`s, printed so that the conversion can be checked. On hardware
//! the same ticks are core clock cycles.
//!
//! Stack: the free stack is painted at reset; `startup_peak` is the deepest use
//! up to the end of configuring the controller (in place, in its `static`:
//! [`PaperController::UNCONFIGURED`] then `configure`), `main_depth` the stack in use by
//! `main` in the control loop. Before each cycle 32 KiB below the stack pointer
//! are painted again; a cycle's `<stack bytes>` is the depth below `main`'s
//! frame that the cycle (`Controller::step`) reached.
#![no_std]
#![no_main]

mod moving;
mod recorded;

use core::arch::asm;
use core::hint::black_box;
use core::mem::MaybeUninit;
use core::panic::PanicInfo;
use core::sync::atomic::{Ordering, compiler_fence};

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{ExceptionFrame, entry, exception};
use cortex_m_semihosting::{debug, hio};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Config, ConvexPolygon, PaperController, RecordedInput};

/// Vertex capacity of the obstacle polygons (as in the host benches).
type Poly = ConvexPolygon<8>;

/// Pattern painted below the stack pointer before each cycle.
const PAINT: u32 = 0x5AA5_C33C;
/// Words painted below the stack pointer (32 KiB, twice the RAM budget).
const PAINT_WORDS: usize = 8 * 1024;
/// SysTick is a 24-bit down-counter.
const SYST_MASK: u32 = 0x00FF_FFFF;

/// The controller, in `.bss` (the unconfigured value is all zero bytes, so it
/// costs no flash); configured in place by [`init_state`].
static mut CONTROLLER: PaperController = PaperController::UNCONFIGURED;

/// The obstacle polygons: zero-initialised `.bss`, written once by [`init_state`].
static mut OBSTACLES: MaybeUninit<[Poly; recorded::OBSTACLES.len()]> = MaybeUninit::uninit();

/// Everything the controller needs between cycles.
struct State {
    controller: &'static mut PaperController,
    obstacles: &'static [Poly],
}

unsafe extern "C" {
    /// Top of the stack (end of RAM), from cortex-m-rt's `link.x`.
    static _stack_start: u32;
    /// Lowest address the stack may grow to (end of `.bss`/`.uninit`).
    static _stack_end: u32;
}

#[entry]
fn main() -> ! {
    // Paint the whole free stack first: the deepest use during start-up
    // (building the controller) is measured after `init_state`.
    let stack_top = &raw const _stack_start as usize;
    let stack_limit = &raw const _stack_end as usize;
    paint(
        stack_limit,
        (cortex_m::register::msp::read() as usize - 64) & !3,
    );
    let Ok(mut out) = hio::hstdout() else {
        fail();
    };
    let Some(cp) = cortex_m::Peripherals::take() else {
        fail();
    };
    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYST_MASK);
    syst.clear_current();
    syst.enable_counter();

    let state = init_state();
    let startup_peak = stack_top - lowest_touched(stack_limit);
    let main_depth = stack_top - cortex_m::register::msp::read() as usize;

    let ((), empty) = measure(&mut syst, || ());
    let ((), nop256) = measure(&mut syst, || {
        // SAFETY: 256 `nop`s: no memory, stack or flag effects.
        unsafe {
            asm!(
                ".rept 256",
                "nop",
                ".endr",
                options(nomem, nostack, preserves_flags)
            )
        }
    });

    let mut line = Line::new();
    line.str("ldcbf-firmware cycles ")
        .dec(3 * recorded::CYCLES.len() as u32);
    line.flush(&mut out);
    line.str("calibration empty_ticks ").dec(empty);
    line.str(" nop256_ticks ").dec(nop256);
    line.flush(&mut out);
    line.str("stack startup_peak ").dec(startup_peak as u32);
    line.str(" main_depth ").dec(main_depth as u32);
    line.flush(&mut out);

    let goal = Vector2::new(recorded::GOAL[0], recorded::GOAL[1]);
    let away = moving::VELOCITIES.map(|[x, y]| Vector2::new(x, y));
    let into = moving::WALK_INTO.map(|[x, y]| Vector2::new(x, y));
    let (mut max_ticks, mut max_stack) = (0u32, 0usize);
    let n = recorded::CYCLES.len();
    for i in 0..3 * n {
        let moving: &[Vector2<f64>] = match i / n {
            0 => &[],
            1 => &away,
            _ => &into,
        };
        if i == n || i == 2 * n {
            state.controller.reset();
        }
        let rec = &recorded::CYCLES[i % n];
        let input = RecordedInput::from_bits(black_box(rec), goal)
            .input_moving(state.obstacles, black_box(moving));
        let sp = cortex_m::register::msp::read() as usize;
        let bottom = paint_stack();
        let (cmd, ticks) = measure(&mut syst, || state.controller.step(black_box(&input), None));
        let lowest = lowest_touched(bottom);
        if lowest == bottom {
            // The cycle used the whole painted window: the mark is unknown.
            line.str("stack window of ").dec((PAINT_WORDS * 4) as u32);
            line.str(" bytes exhausted");
            line.flush(&mut out);
            fail();
        }
        let stack = sp - lowest;
        max_ticks = max_ticks.max(ticks);
        max_stack = max_stack.max(stack);
        line.str("cycle ").dec(i as u32);
        line.str(" ").hex(cmd.foot_target.x.to_bits());
        line.str(" ").hex(cmd.foot_target.y.to_bits());
        line.str(" ").hex(cmd.turning_rate.to_bits());
        line.str(" ").str(cmd.status.name());
        line.str(" ").dec(cmd.info.iterations);
        line.str(" ").dec(ticks);
        line.str(" ").dec(stack as u32);
        line.flush(&mut out);
    }
    line.str("done max_ticks ").dec(max_ticks);
    line.str(" max_stack ").dec(max_stack as u32);
    line.flush(&mut out);
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::bkpt();
    }
}

/// Configures [`CONTROLLER`] in place and builds the obstacle polygons into
/// [`OBSTACLES`] (once), so that no controller is assembled on the stack.
#[inline(never)]
fn init_state() -> State {
    // SAFETY: called once from `main` before any other access to CONTROLLER
    // and OBSTACLES, so these are the only references to them; every
    // obstacle is written before the `assume_init_ref`.
    unsafe {
        let controller = &mut *core::ptr::addr_of_mut!(CONTROLLER);
        if controller.configure(Config::default()).is_err() {
            fail();
        }
        let obstacles = (*core::ptr::addr_of_mut!(OBSTACLES)).as_mut_ptr();
        // Through `black_box`, the obstacle count is unknown to the optimiser:
        // the loop stays a loop with one copy of `hull`, instead of being
        // unrolled with `hull` inlined once per obstacle (about 4 KiB of flash).
        let recorded_obstacles: &[_] = black_box(&recorded::OBSTACLES[..]);
        // (Zipped, not indexed: no bounds-check panic, whose message
        // formatting would bring `core::fmt`'s integer printing into flash.)
        if recorded_obstacles.len() > (*obstacles).len() {
            fail();
        }
        for (slot, verts) in (*obstacles).iter_mut().zip(recorded_obstacles) {
            match Poly::hull(verts) {
                Ok(p) => *slot = p,
                Err(_) => fail(),
            }
        }
        State {
            controller,
            obstacles: (*core::ptr::addr_of!(OBSTACLES)).assume_init_ref(),
        }
    }
}

/// Runs `f` between two reads of the SysTick counter; returns its result and
/// the ticks elapsed. The counter is restarted from its top first, so a
/// measurement has the full 24-bit range; if it ran out (COUNTFLAG set: more
/// than 2^24 ticks) the firmware fails rather than report a wrapped count.
#[inline(never)]
fn measure<R>(syst: &mut SYST, f: impl FnOnce() -> R) -> (R, u32) {
    syst.clear_current();
    let _ = syst.has_wrapped(); // reading COUNTFLAG clears it
    let start = SYST::get_current();
    compiler_fence(Ordering::SeqCst);
    let r = f();
    compiler_fence(Ordering::SeqCst);
    let end = SYST::get_current();
    if syst.has_wrapped() {
        if let Ok(mut err) = hio::hstderr() {
            let _ = err.write_all(b"measured region exceeded the 24-bit SysTick range\n");
        }
        fail();
    }
    (r, start.wrapping_sub(end) & SYST_MASK)
}

/// Paints [`PAINT_WORDS`] words below this function's own frame; returns the
/// lowest painted address. Nothing lives below the stack pointer (no
/// interrupts are enabled), so the painting cannot clobber live data.
#[inline(never)]
fn paint_stack() -> usize {
    let top = (cortex_m::register::msp::read() as usize - 64) & !3;
    let bottom = top - PAINT_WORDS * 4;
    paint(bottom, top);
    bottom
}

/// Writes [`PAINT`] to the words of `[bottom, top)`, which must be free stack
/// (below the stack pointer, above `_stack_end`).
#[inline(always)]
fn paint(bottom: usize, top: usize) {
    let mut a = bottom;
    while a < top {
        // SAFETY: `a` is word aligned, in RAM between the end of the statics
        // and the stack pointer: memory no live value occupies.
        unsafe { (a as *mut u32).write_volatile(PAINT) };
        a += 4;
    }
}

/// Lowest address at or above `bottom` whose painted word was overwritten.
#[inline(never)]
fn lowest_touched(bottom: usize) -> usize {
    let mut a = bottom;
    // SAFETY: reads words painted by `paint`, in RAM between `bottom` and the
    // caller's stack pointer; the scan stops at the first changed word, which
    // exists because this function's own frame overwrote the paint.
    while unsafe { (a as *const u32).read_volatile() } == PAINT {
        a += 4;
    }
    a
}

/// A line of output, formatted without `core::fmt` (keeps flash small).
struct Line {
    buf: [u8; 256],
    len: usize,
}

impl Line {
    fn new() -> Self {
        Line {
            buf: [0; 256],
            len: 0,
        }
    }

    fn byte(&mut self, b: u8) {
        self.bytes(&[b]);
    }

    /// Appends `s` (what fits in the buffer). Every other writer goes
    /// through this one copy (flash).
    #[inline(never)]
    fn bytes(&mut self, s: &[u8]) {
        for (slot, &b) in self.buf.iter_mut().skip(self.len).zip(s) {
            *slot = b;
            self.len += 1;
        }
    }

    fn str(&mut self, s: &str) -> &mut Self {
        self.bytes(s.as_bytes());
        self
    }

    #[inline(never)]
    fn dec(&mut self, mut v: u32) -> &mut Self {
        let mut digits = [0u8; 10];
        let mut n = digits.len();
        for slot in digits.iter_mut().rev() {
            *slot = b'0' + (v % 10) as u8;
            n -= 1;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        self.bytes(digits.get(n..).unwrap_or(&[]));
        self
    }

    /// 16 lower-case hex digits.
    #[inline(never)]
    fn hex(&mut self, v: u64) -> &mut Self {
        let mut digits = [0u8; 16];
        for (i, slot) in digits.iter_mut().enumerate() {
            let d = ((v >> (60 - 4 * i)) & 0xF) as u8;
            *slot = if d < 10 { b'0' + d } else { b'a' + d - 10 };
        }
        self.bytes(&digits);
        self
    }

    #[inline(never)]
    fn flush(&mut self, out: &mut hio::HostStream) {
        self.byte(b'\n');
        // (`get`: no slice-index panic path, whose message formatting would
        // bring `core::fmt`'s integer printing into flash.)
        if out
            .write_all(self.buf.get(..self.len).unwrap_or(&[]))
            .is_err()
        {
            fail();
        }
        self.len = 0;
    }
}

/// Leaves QEMU with a failure status (never hangs the test).
fn fail() -> ! {
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let mut line = Line::new();
        line.str("panic");
        if let Some(loc) = info.location() {
            line.str(" at ").str(loc.file()).str(":").dec(loc.line());
        }
        line.flush(&mut err);
    }
    fail();
}

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let _ = err.write_all(b"hard fault\n");
    }
    fail();
}

#[exception]
unsafe fn DefaultHandler(irq: i16) {
    if let Ok(mut err) = hio::hstderr() {
        let mut line = Line::new();
        line.str("unexpected exception ")
            .dec(u32::from(irq.unsigned_abs()));
        line.flush(&mut err);
    }
    fail();
}
