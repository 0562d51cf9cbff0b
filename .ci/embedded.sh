#!/usr/bin/env bash
# Embedded and cross-target checks, called by .ci/run (or on its own:
# `bash .ci/embedded.sh`, as root or with the tools already installed):
#   1. the Cortex-M7 firmware (firmware/) in qemu-system-arm (mps2-an500):
#      its commands equal the host's to 1e-9, instruction counts per cycle
#      (deterministic, -icount), flash/RAM/stack budgets (tests/firmware_qemu.rs);
#   2. the link-time no-panic proof (nopanic/check.sh);
#   3. the controller's tests cross-built for aarch64-unknown-linux-gnu and run
#      under qemu-aarch64;
#   4. the C API (ffi/) cross-built for aarch64: its unit tests under
#      qemu-aarch64, and the C example walk.c cross-compiled and run under
#      qemu-aarch64, its cycles equal to the Rust controller's bit for bit.
set -euo pipefail
cd "$(dirname "$0")/.."

# shellcheck source=.ci/section.sh
source .ci/section.sh

section "embedded tools (Debian packages, rustup targets)"
need=()
command -v qemu-system-arm >/dev/null || need+=(qemu-system-arm)
command -v qemu-aarch64 >/dev/null || need+=(qemu-user)
command -v aarch64-linux-gnu-gcc >/dev/null || need+=(gcc-aarch64-linux-gnu)
[ -e /usr/aarch64-linux-gnu/lib/crt1.o ] || need+=(libc6-dev-arm64-cross)
if ((${#need[@]})); then
    echo "installing: ${need[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
rustup target add thumbv7em-none-eabihf aarch64-unknown-linux-gnu
qemu-system-arm --version | head -n 1
qemu-aarch64 --version | head -n 1
aarch64-linux-gnu-gcc --version | head -n 1

section "firmware on qemu-system-arm mps2-an500 (Cortex-M7): equals host, instructions, memory"
cargo test --locked --test firmware_qemu -- --ignored --exact firmware_matches_host_in_qemu --nocapture

section "link-time proof that Controller::step cannot panic (nopanic/, panic-never)"
bash nopanic/check.sh

section "controller tests on aarch64-unknown-linux-gnu (qemu-aarch64)"
CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc \
CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu" \
    cargo test --locked -p ldcbf-controller --target aarch64-unknown-linux-gnu

section "C API (ffi/) on aarch64-unknown-linux-gnu: unit tests, walk.c equals Rust bit for bit"
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu"
cargo test --locked -p ldcbf-ffi --lib --target aarch64-unknown-linux-gnu
cargo build --locked --release -p ldcbf-ffi --target aarch64-unknown-linux-gnu
ffi_out="$(mktemp -d)"
aarch64-linux-gnu-gcc -std=c11 -O2 -Wall -Wextra -Wpedantic -Werror -ffp-contract=off \
    -I ffi/include ffi/examples/walk.c \
    target/aarch64-unknown-linux-gnu/release/libldcbf_ffi.a -lm -lpthread -ldl \
    -o "$ffi_out/walk-aarch64"
qemu-aarch64 -L /usr/aarch64-linux-gnu "$ffi_out/walk-aarch64" | tail -n 1
qemu-aarch64 -L /usr/aarch64-linux-gnu "$ffi_out/walk-aarch64" --hex >"$ffi_out/walk-aarch64.txt"
# Compared on the host with the Rust controller run there.
LDCBF_WALK_HEX="$ffi_out/walk-aarch64.txt" \
    cargo test --locked -p ldcbf-ffi --test walk_c -- --nocapture
rm -rf "$ffi_out"
