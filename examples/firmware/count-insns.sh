#!/usr/bin/env bash
# Executed instructions per call of texsat entry points on the emulated Cortex-M4F (QEMU
# `mps2-an386`), for 8-bit texels, u32 entries, I24F8 corners, NoCount, a 64 x 64 random texture.
#
#   examples/firmware/count-insns.sh            prints a markdown table
#   COUNT_PROFILE=1 examples/firmware/count-insns.sh   also instructions per call by function (stderr)
#   COUNT_LINES=mip_trilinear ...          also that entry point's instructions per call by source line
#   COUNT_KEEP_LOG=1 ...                        keeps QEMU's exec log (about 300 MB) in target/count-insns/
#
# How: builds the `texsat-count` binary (src/count.rs, feature `count`, plus `filter-mip`) with
# the firmware's release profile (opt-level "s", fat LTO, the link gate's panic handler: it links
# only if panic-free), runs it under `qemu-system-arm -singlestep -d exec,nochain` (one TB per
# instruction, one log line per executed TB: no TCG plugins needed) and count_insns.py counts the
# instructions between the harness's `texsat_count_mark` calls: (11 calls - 1 call) / 10, minus
# the same for an empty wrapper. Not part of the link gate; does not touch its builds' outputs.
set -euo pipefail
cd "$(dirname "$0")"
HERE=$(pwd)

TARGET=thumbv7em-none-eabihf
BIN=texsat-count
FEATURES=count,filter-mip
QEMU=${QEMU:-qemu-system-arm}

die() {
  printf 'count-insns: ERROR: %s\n' "$*" >&2
  exit 1
}
command -v cargo >/dev/null || die "cargo not found"
command -v python3 >/dev/null || die "python3 not found"
command -v "$QEMU" >/dev/null || die "$QEMU not found (Debian: apt-get install qemu-system-arm)"
if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
  rustup target add "$TARGET" >&2 || die "could not install the $TARGET target"
fi
find_llvm_bin() {
  local d
  for d in "$(rustc --print sysroot)"/lib/rustlib/*/bin; do
    if [ -x "$d/llvm-nm" ]; then
      echo "$d"
      return 0
    fi
  done
  return 1
}
if ! LLVM_BIN=$(find_llvm_bin); then
  rustup component add llvm-tools >&2 || die "could not install llvm-tools"
  LLVM_BIN=$(find_llvm_bin) || die "llvm-nm not found under $(rustc --print sysroot)/lib/rustlib/*/bin"
fi

TARGET_DIR=${CARGO_TARGET_DIR:-$HERE/target}
OUT=$TARGET_DIR/count-insns
mkdir -p "$OUT"
ELF=$OUT/$BIN.elf

if ! CARGO_TARGET_DIR=$TARGET_DIR cargo build --release --locked --target "$TARGET" --bin "$BIN" \
  --no-default-features --features "$FEATURES" >"$OUT/build.log" 2>&1; then
  tail -n 40 "$OUT/build.log" >&2
  die "build failed (log: $OUT/build.log)"
fi
cp "$TARGET_DIR/$TARGET/release/$BIN" "$ELF"

QEMU_ARGS=(-M mps2-an386 -display none -monitor none -serial none -semihosting
  -singlestep -d exec,nochain -kernel "$ELF")
PARSE_ARGS=("$ELF" --llvm-bin "$LLVM_BIN" --reps 11 --texels 4096 --mip)
[ -n "${COUNT_PROFILE:-}" ] && PARSE_ARGS+=(--profile)
[ -n "${COUNT_LINES:-}" ] && PARSE_ARGS+=(--lines "$COUNT_LINES")

echo "count-insns: $("$QEMU" --version | head -n 1); $QEMU ${QEMU_ARGS[*]} -D <log>" >&2
if [ -n "${COUNT_KEEP_LOG:-}" ]; then
  LOG=$OUT/exec.log
  rm -f "$LOG"
  timeout 600 "$QEMU" "${QEMU_ARGS[@]}" -D "$LOG" || die "QEMU failed or timed out (status $?)"
  python3 "$HERE/count_insns.py" "${PARSE_ARGS[0]}" "$LOG" "${PARSE_ARGS[@]:1}"
else
  # The log is read through a FIFO, so its ~300 MB never reach the disk.
  FIFO=$OUT/exec.fifo
  rm -f "$FIFO"
  mkfifo "$FIFO"
  timeout 600 "$QEMU" "${QEMU_ARGS[@]}" -D "$FIFO" &
  QPID=$!
  status=0
  python3 "$HERE/count_insns.py" "${PARSE_ARGS[0]}" "$FIFO" "${PARSE_ARGS[@]:1}" || status=$?
  qstatus=0
  wait "$QPID" || qstatus=$?
  rm -f "$FIFO"
  [ "$qstatus" -eq 0 ] || die "QEMU failed or timed out (status $qstatus)"
  [ "$status" -eq 0 ] || die "count_insns.py failed (status $status)"
fi
