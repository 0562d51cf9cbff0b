//! The firmware under QEMU: build it, run it (`-icount`), parse what it
//! prints, and read the ELF's section and symbol sizes.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use super::{ICOUNT_SHIFT, QEMU_TIMEOUT, workspace_root};

/// Builds the firmware (its own crate and target directory) and returns the ELF.
pub(crate) fn build_firmware() -> PathBuf {
    let dir = workspace_root().join("firmware");
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    // The firmware's .cargo/config.toml sets the target, the rustflags (linker
    // script, cortex-m7) and the runner: variables that would override them go.
    // Not `--locked`: firmware/Cargo.lock pins the versions it has, but a new
    // dependency of the controller must not break this test (commit the
    // updated lock file then).
    let out = Command::new(cargo)
        .args(["build", "--release"])
        .current_dir(&dir)
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("CARGO_BUILD_TARGET")
        .env_remove("CARGO_BUILD_TARGET_DIR")
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("CARGO_BUILD_RUSTFLAGS")
        .output()
        .expect("run cargo to build the firmware");
    assert!(
        out.status.success(),
        "building the firmware failed (is the target installed? `rustup target add \
         thumbv7em-none-eabihf`):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let elf = dir.join("target/thumbv7em-none-eabihf/release/ldcbf-firmware");
    assert!(elf.is_file(), "no firmware ELF at {}", elf.display());
    elf
}

/// Runs the firmware in `qemu-system-arm` (mps2-an500, Cortex-M7, semihosting,
/// deterministic `-icount`) and returns its standard output. Panics if QEMU is
/// missing, fails, or runs past [`QEMU_TIMEOUT`].
pub(crate) fn run_qemu(elf: &Path) -> String {
    let icount = format!("shift={ICOUNT_SHIFT},align=off,sleep=off");
    let mut child = Command::new("qemu-system-arm")
        .args(["-M", "mps2-an500", "-cpu", "cortex-m7", "-nographic"])
        .args(["-monitor", "none", "-serial", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-icount", &icount, "-kernel"])
        .arg(elf)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| {
            panic!(
                "cannot start qemu-system-arm ({e}): install Debian's `qemu-system-arm` \
                 (.ci/embedded.sh does)"
            )
        });
    // Drain the pipes on threads so a chatty run cannot block on a full pipe.
    let mut stdout = child.stdout.take().expect("piped stdout");
    let mut stderr = child.stderr.take().expect("piped stderr");
    let out_reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut s).map(|_| s)
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut stderr, &mut s).map(|_| s)
    });
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait for qemu") {
            break status;
        }
        if started.elapsed() > QEMU_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("qemu-system-arm did not exit within {QEMU_TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let out = out_reader
        .join()
        .expect("stdout reader")
        .expect("read stdout");
    let err = err_reader
        .join()
        .expect("stderr reader")
        .expect("read stderr");
    assert!(
        status.success(),
        "the firmware failed in QEMU ({status}):\nstderr:\n{err}\nstdout (tail):\n{}",
        out.lines().rev().take(5).collect::<Vec<_>>().join("\n")
    );
    out
}

/// One `cycle` line of the firmware.
#[derive(Clone, Debug)]
pub(crate) struct FirmwareCycle {
    pub(crate) index: usize,
    pub(crate) foot: [f64; 2],
    pub(crate) turning_rate: f64,
    pub(crate) status: String,
    pub(crate) iterations: u32,
    pub(crate) ticks: u64,
    pub(crate) stack: u64,
}

/// The parsed output of a firmware run.
#[derive(Debug)]
pub(crate) struct FirmwareRun {
    pub(crate) empty_ticks: u64,
    pub(crate) nop256_ticks: u64,
    pub(crate) startup_stack_peak: u64,
    pub(crate) main_stack_depth: u64,
    pub(crate) cycles: Vec<FirmwareCycle>,
}

pub(crate) fn parse_run(out: &str) -> FirmwareRun {
    let mut run = FirmwareRun {
        empty_ticks: 0,
        nop256_ticks: 0,
        startup_stack_peak: 0,
        main_stack_depth: 0,
        cycles: Vec::new(),
    };
    let mut announced = None;
    let mut done = false;
    for line in out.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| -> u64 {
            w.get(i)
                .and_then(|s| s.parse().ok())
                .unwrap_or_else(|| panic!("bad number in firmware line {line:?}"))
        };
        let bits = |i: usize| -> f64 {
            let s = w.get(i).unwrap_or_else(|| panic!("short line {line:?}"));
            f64::from_bits(
                u64::from_str_radix(s, 16).unwrap_or_else(|_| panic!("bad hex in {line:?}")),
            )
        };
        match w.first().copied() {
            Some("ldcbf-firmware") => announced = Some(num(2) as usize),
            Some("calibration") => {
                run.empty_ticks = num(2);
                run.nop256_ticks = num(4);
            }
            Some("stack") => {
                run.startup_stack_peak = num(2);
                run.main_stack_depth = num(4);
            }
            Some("cycle") => {
                assert_eq!(w.len(), 9, "firmware line {line:?}");
                run.cycles.push(FirmwareCycle {
                    index: num(1) as usize,
                    foot: [bits(2), bits(3)],
                    turning_rate: bits(4),
                    status: w[5].to_string(),
                    iterations: num(6) as u32,
                    ticks: num(7),
                    stack: num(8),
                });
            }
            Some("done") => done = true,
            _ => panic!("unexpected firmware output line {line:?}"),
        }
    }
    assert!(done, "the firmware output has no `done` line:\n{out}");
    assert_eq!(announced, Some(run.cycles.len()), "cycle count");
    run
}

/// Berkeley sizes of an ELF32 file (as `size`/`llvm-size`): `text` = allocated
/// and executable or read-only sections, `data` = allocated, writable, with
/// contents, `bss` = allocated without contents; plus the size of the symbol
/// whose mangled name contains `symbol`.
pub(crate) fn elf_sizes(path: &Path, symbol: &str) -> (u64, u64, u64, u64) {
    let b = std::fs::read(path).expect("read ELF");
    assert!(
        b.len() > 52 && &b[..4] == b"\x7fELF" && b[4] == 1 && b[5] == 1,
        "not an ELF32 LE file"
    );
    let u16_at = |o: usize| u64::from(u16::from_le_bytes([b[o], b[o + 1]]));
    let u32_at = |o: usize| u64::from(u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]));
    let (shoff, shentsize, shnum) = (
        u32_at(0x20) as usize,
        u16_at(0x2e) as usize,
        u16_at(0x30) as usize,
    );
    let sh = |i: usize| {
        let o = shoff + i * shentsize;
        // (type, flags, offset, size, link)
        (
            u32_at(o + 4),
            u32_at(o + 8),
            u32_at(o + 16) as usize,
            u32_at(o + 20),
            u32_at(o + 24) as usize,
        )
    };
    const SHT_SYMTAB: u64 = 2;
    const SHT_NOBITS: u64 = 8;
    const SHF_WRITE: u64 = 1;
    const SHF_ALLOC: u64 = 2;
    const SHF_EXECINSTR: u64 = 4;
    let (mut text, mut data, mut bss, mut sym) = (0, 0, 0, 0);
    for i in 0..shnum {
        let (ty, flags, offset, size, link) = sh(i);
        if flags & SHF_ALLOC != 0 {
            if flags & SHF_EXECINSTR != 0 || flags & SHF_WRITE == 0 {
                text += size;
            } else if ty == SHT_NOBITS {
                bss += size;
            } else {
                data += size;
            }
        }
        if ty == SHT_SYMTAB {
            let (_, _, stroff, _, _) = sh(link);
            for k in 0..(size as usize / 16) {
                let e = offset + 16 * k;
                let name_at = stroff + u32_at(e) as usize;
                let end = b[name_at..].iter().position(|&c| c == 0).unwrap_or(0);
                if std::str::from_utf8(&b[name_at..name_at + end]).is_ok_and(|n| n.contains(symbol))
                {
                    sym = sym.max(u32_at(e + 8));
                }
            }
        }
    }
    (text, data, bss, sym)
}
