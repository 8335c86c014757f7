#!/usr/bin/env bash
# Flash per plan on the Cortex-M4F: builds the `texsat-flash` firmware (src/flash.rs) once per
# configuration (release profile: opt-level "s", fat LTO, the link gate's panic handler, so
# every variant links only if panic-free) and prints what each adds over the empty harness
# (`.text` + `.rodata`, from llvm-size), texsat beside the hand-written version of the same
# behaviour.
#
#   examples/firmware/flash.sh            prints a markdown table
#
# CARGO_TARGET_DIR is honoured (default: examples/firmware/target).
set -euo pipefail
cd "$(dirname "$0")"
HERE=$(pwd)
TARGET=thumbv7em-none-eabihf
BIN=texsat-flash

die() {
  printf 'flash: ERROR: %s\n' "$*" >&2
  exit 1
}
command -v cargo >/dev/null || die "cargo not found"
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
OUT=$TARGET_DIR/flash
mkdir -p "$OUT"

# flash FEATURES: .text + .rodata of the variant, in bytes.
flash() {
  local features=$1 log=$OUT/build-$1.log
  if ! CARGO_TARGET_DIR=$TARGET_DIR cargo build --release --locked --target "$TARGET" \
    --bin "$BIN" --no-default-features --features "$features" >"$log" 2>&1; then
    tail -n 30 "$log" >&2
    die "build of $features failed (log: $log)"
  fi
  cp "$TARGET_DIR/$TARGET/release/$BIN" "$OUT/$features.elf"
  "$LLVM_BIN/llvm-size" -A "$OUT/$features.elf" |
    awk '$1 == ".text" || $1 == ".rodata" { s += $2 } END { print s + 0 }'
}

base=$(flash flash)
row() {
  local label=$1 ours=$2 hand=${3:-}
  local a b
  a=$(($(flash "$ours") - base))
  if [ -n "$hand" ]; then
    b=$(($(flash "$hand") - base))
    printf '| %s | %d | %d | %s |\n' "$label" "$a" "$b" "$(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.2f", a / b }')"
  else
    printf '| %s | %d | | |\n' "$label" "$a"
  fi
}
echo "flash: empty harness (cortex-m-rt, the loop, black_box): $base bytes of .text + .rodata" >&2
echo "| configuration (64 x 64 u8 texels, u32 table, opt-level \"s\") | texsat, bytes added | hand-written, bytes added | ratio |"
echo "|---|---:|---:|---:|"
row 'build + 4-read `box_sum_int` ClampToEdge + mean (the smallest plan'"'"'s lookup)' flash-int4 flash-int4-hand
row 'build + `box_sum_inside` (boxes known inside)' flash-inside flash-inside-hand
row 'build + 16-read Stable Repeat + mean (hand-written: boxes inside one period only)' flash-stable-repeat flash-stable-repeat-hand
row 'every cargo feature enabled (`filters`, `defmt`), the Stable Repeat plan used: what features cost unused' flash-stable-repeat,filters,defmt
row 'every cargo feature: Stable Repeat plan + `box_sum_raw` + every filter'"'"'s raw sampler and build' flash-all
