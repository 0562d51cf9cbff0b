#!/usr/bin/env bash
# Link-time proof that the controller cannot panic (see README.md).
#
#   bash nopanic/check.sh          build the harness with panic-never; exit 1 if
#                                  the link fails (a panicking branch survived),
#                                  after listing the surviving panic call sites
#   bash nopanic/check.sh --list   only list the panic call sites (panic-halt build)
#
# Needs the thumbv7em-none-eabihf target; the listing also needs the llvm-tools
# rustup component (llvm-objdump), binutils' addr2line and python3.
set -euo pipefail
cd "$(dirname "$0")"

TARGET=thumbv7em-none-eabihf
ELFS=("target/$TARGET/release/ldcbf-nopanic" "target/$TARGET/release/ldcbf-nopanic-ffi")

list_sites() {
    echo "Building with panic-halt to list the surviving panic call sites..."
    cargo build --release --locked --no-default-features 2>&1 | tail -n 3
    local objdump
    objdump="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/llvm-objdump"
    if [[ ! -x "$objdump" ]] || ! command -v addr2line >/dev/null || ! command -v python3 >/dev/null; then
        echo "Listing needs llvm-objdump (rustup component add llvm-tools), addr2line and python3." >&2
        echo "See README.md, 'Finding a regression', for the manual recipe." >&2
        return 2
    fi
    local status=0 elf
    for elf in "${ELFS[@]}"; do
        echo "== $elf"
        python3 list_panics.py "$objdump" addr2line "$elf" || status=1
    done
    return $status
}

if [[ "${1:-}" == "--list" ]]; then
    list_sites
    exit $?
fi

LOG="$(mktemp)"
trap 'rm -f "$LOG"' EXIT

echo "Linking the no-panic harness ($TARGET, release, panic-never)..."
if cargo build --release --locked 2>"$LOG"; then
    echo "OK: no panicking branch is reachable from Controller::new, Controller::configure, Controller::step,"
    echo "    Controller::step (with and without candidates), Controller::obstacle_query,"
    echo "    ConvexPolygon::new, ConvexPolygon::hull, or DualActiveSet::new and LdpSolver (NV = 16, NC = 32),"
    echo "    nor from any function of the C API (ffi/: ldcbf_init, ldcbf_configure, ldcbf_step, ...)"
    echo "    in the release build for Cortex-M7."
    exit 0
fi

if grep -q "error(panic-never)" "$LOG"; then
    cat >&2 <<'EOF'

FAILED: the controller or the C API (ffi/) has a reachable panicking branch.
The optimised release build for Cortex-M7 still calls the panic handler, so for
some input `Controller::step`, `Controller::new`, `ConvexPolygon::new` or
`ConvexPolygon::hull` could panic (usually an index the optimiser cannot prove in
bounds, an `assert!`, `unwrap`/`expect`, `f64::clamp` with run-time bounds, or a
division by an integer that may be zero). The sites follow; fix them as described
in nopanic/README.md.
EOF
    list_sites >&2 || true
else
    echo "FAILED: the harness did not build (not a panic-never link error):" >&2
    cat "$LOG" >&2
fi
exit 1
