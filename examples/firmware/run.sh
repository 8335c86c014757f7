#!/usr/bin/env bash
# The firmware demo on the emulated Cortex-M4F: builds `texsat-demo` (src/demo.rs: tables sized
# by scene plans at compile time, footprints computed on the device, three plans and trilinear mip sampled) with
# DEFMT_LOG=info, runs it under qemu-system-arm (mps2-an386) with a time limit, decodes the
# defmt frames it writes to the semihosting console with defmt-print, and compares the lines
# with the host's (tools/examples/firmware_scene.rs, the same scene code). Exits non-zero on any
# mismatch, and says which step failed. Installs qemu-system-arm (apt), defmt-print (cargo
# install --locked) and the rustup target when missing.
#
#   bash examples/firmware/run.sh               build, run, compare; flash and RAM
#   DEMO_COUNT=1 bash examples/firmware/run.sh  also instructions per table entry built and per
#                                               sample, per plan (QEMU -singlestep exec log)
set -euo pipefail
cd "$(dirname "$0")"
HERE=$(pwd)
ROOT=$(cd ../.. && pwd)
TARGET=thumbv7em-none-eabihf
QEMU=${QEMU:-qemu-system-arm}

die() {
  printf 'run.sh: FAILED at step "%s": %s\n' "$STEP" "$*" >&2
  exit 1
}

STEP="tools"
if ! command -v "$QEMU" >/dev/null; then
  echo "run.sh: installing qemu-system-arm (apt-get)" >&2
  { apt-get update -qq && apt-get install -y -qq qemu-system-arm >/dev/null; } ||
    die "could not install qemu-system-arm (Debian package qemu-system-arm)"
fi
if ! command -v defmt-print >/dev/null; then
  echo "run.sh: installing defmt-print (cargo install defmt-print --locked)" >&2
  cargo install defmt-print --locked >&2 || die "could not install defmt-print"
fi
if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
  rustup target add "$TARGET" >&2 || die "could not install the $TARGET target"
fi
find_llvm_bin() {
  local d
  for d in "$(rustc --print sysroot)"/lib/rustlib/*/bin; do
    if [ -x "$d/llvm-size" ]; then
      echo "$d"
      return 0
    fi
  done
  return 1
}
if ! LLVM_BIN=$(find_llvm_bin); then
  rustup component add llvm-tools >&2 || die "could not install llvm-tools"
  LLVM_BIN=$(find_llvm_bin) || die "llvm-size not found"
fi

TARGET_DIR=${CARGO_TARGET_DIR:-$HERE/target}
OUT=$TARGET_DIR/demo
mkdir -p "$OUT"

STEP="build the firmware"
# defmt logs only errors unless DEFMT_LOG is set when the firmware is built.
DEFMT_LOG=info CARGO_TARGET_DIR=$TARGET_DIR cargo build --release --locked --target "$TARGET" --bin texsat-demo \
  --features demo >"$OUT/build.log" 2>&1 || { tail -n 30 "$OUT/build.log" >&2; die "see $OUT/build.log"; }
ELF=$TARGET_DIR/$TARGET/release/texsat-demo

STEP="run under QEMU"
status=0
# The firmware opens the semihosting console (":tt"), which QEMU maps to its own stdout: the
# binary defmt frames, and nothing else (QEMU's messages go to stderr).
timeout 120 "$QEMU" -M mps2-an386 -display none -monitor none -serial none \
  -semihosting-config enable=on,target=native -kernel "$ELF" >"$OUT/frames.bin" 2>"$OUT/qemu.log" ||
  status=$?
[ "$status" = 0 ] || { cat "$OUT/qemu.log" >&2; die "QEMU exited with status $status (124: time limit)"; }

STEP="decode the defmt frames"
defmt-print -e "$ELF" --log-format "{s}" stdin <"$OUT/frames.bin" >"$OUT/decoded.txt" ||
  die "defmt-print failed"
grep '^plan ' "$OUT/decoded.txt" >"$OUT/device.txt" || { cat "$OUT/decoded.txt" >&2; die "no plan lines in the log"; }

STEP="the host's lines"
(cd "$ROOT" && cargo run -q --locked -p texsat-tools --example firmware_scene) >"$OUT/host.txt" ||
  die "the host program failed"

STEP="compare"
echo "device (Cortex-M4F, QEMU $("$QEMU" --version | head -n 1 | awk '{print $4}')):"
sed 's/^/  /' "$OUT/device.txt"
if ! diff -u "$OUT/host.txt" "$OUT/device.txt" >"$OUT/diff.txt"; then
  cat "$OUT/diff.txt" >&2
  die "the device's results differ from the host's"
fi
[ "$(grep -c '^plan ' "$OUT/device.txt")" = 4 ] || die "expected 4 plan lines (3 plans and mip)"
echo "host: the same $(wc -l <"$OUT/host.txt") lines: checksums and first values match"

STEP="sizes"
"$LLVM_BIN/llvm-size" -A "$ELF" | awk '
  $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" { flash += $2 }
  $1 == ".data" { flash += $2; ram += $2 }
  $1 == ".bss" || $1 == ".uninit" { ram += $2 }
  END { printf "flash (.vector_table + .text + .rodata + .data): %d bytes; RAM (.data + .bss): %d bytes\n", flash, ram }'

if [ -n "${DEMO_COUNT:-}" ]; then
  STEP="count instructions"
  MARK=$("$LLVM_BIN/llvm-nm" "$ELF" | awk '$3 == "texsat_demo_mark" { print $1 }')
  [ -n "$MARK" ] || die "texsat_demo_mark not found"
  FIFO=$OUT/exec.fifo
  rm -f "$FIFO"
  mkfifo "$FIFO"
  timeout 600 "$QEMU" -M mps2-an386 -display none -monitor none -serial none \
    -semihosting-config enable=on,target=native \
    -singlestep -d exec,nochain -D "$FIFO" -kernel "$ELF" >/dev/null &
  QPID=$!
  python3 - "$FIFO" "$MARK" <<'PY'
import re, sys
mark = int(sys.argv[2], 16) & ~1
trace = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/")
regions, cur = [], None
with open(sys.argv[1], errors="replace") as f:
    for line in f:
        m = trace.match(line)
        if not m:
            continue
        pc = int(m.group(1), 16)
        if pc == mark:
            if cur is not None:
                regions.append(cur)
            cur = 0
        elif cur is not None:
            cur += 1
entries, samples = 64 * 64, 32 * 24
print("| plan | build: instructions per entry | render: instructions per sample (footprint, lookup, mean, checksum) |")
print("|---|---:|---:|")
for i, name in enumerate(["small", "repeat", "tiled", "mip (for comparison)"]):
    b, r = regions[3 * i], regions[3 * i + 1]
    print(f"| {name} | {b / entries:.2f} | {r / samples:.1f} |")
PY
  wait "$QPID" || die "QEMU (counting run) failed"
  rm -f "$FIFO"
fi
echo "run.sh: OK"
