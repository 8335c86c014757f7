#!/usr/bin/env bash
# Executed instructions per call of texsat entry points on the emulated Cortex-M4F (QEMU
# `mps2-an386`), for 8-bit texels, u32 entries, I24F8 corners, NoCount, a 64 x 64 random texture.
#
#   examples/firmware/count-insns.sh            prints a markdown table
#   COUNT_PROFILE=1 examples/firmware/count-insns.sh   also instructions per call by function (stderr)
#   COUNT_FEATURES=simd ...                the texsat features too (simd: the DSP row scan)
#   COUNT_LINES=mip_trilinear ...          also that entry point's instructions per call by source line
#   COUNT_ANNOTATE=tiled_stable_border ... also the disassembly of what that entry point runs,
#                                          each instruction with its count per call (stderr)
#   COUNT_METHOD=both ...                  counts with the plugin and with the -singlestep exec log and
#                                          fails unless every region agrees to the instruction
#   COUNT_METHOD=plugin|singlestep ...     one method only (default `auto`: the plugin, falling back
#                                          loudly to -singlestep if it cannot be built or loaded)
#   COUNT_KEEP_LOG=1 ...                        keeps QEMU's -singlestep exec log (23 GB!) in
#                                               target/count-insns/ (methods singlestep, both)
#
# How: builds the `texsat-count` binary (src/count.rs, feature `count`, plus `filter-mip`) with
# the firmware's release profile (opt-level "s", fat LTO, the link gate's panic handler: it links
# only if panic-free) and the TCG plugin plugin/insn_count.c (gcc, plugin/build.sh), runs the
# binary under `qemu-system-arm -plugin insn_count.so,mark=ADDR` (ADDR: `texsat_count_mark`; the
# plugin counts every executed instruction with a per-instruction inline add and prints the
# running count at each mark) and count_insns.py counts the instructions between the harness's
# `texsat_count_mark` calls: (20 calls - 10 calls) / 10, both runs through the same
# out-of-line loop (so the difference is exactly 10 calls), minus the same for an empty wrapper. It
# first checks the self-check region (assembly, count known from the disassembly) and fails
# if it is off. The fallback, `-singlestep -d exec,nochain` (one TB per instruction, one log line
# per executed TB), gives the same counts, several times slower. Not part of the link gate; does
# not touch its builds' outputs.
set -euo pipefail
cd "$(dirname "$0")"
HERE=$(pwd)

TARGET=thumbv7em-none-eabihf
BIN=texsat-count
FEATURES=count,filter-mip
# COUNT_FEATURES=simd adds texsat features (simd: the ARMv7E-M row scan, src/dsp.rs).
[ -n "${COUNT_FEATURES:-}" ] && FEATURES="$FEATURES,$COUNT_FEATURES"
QEMU=${QEMU:-qemu-system-arm}

die() {
  printf 'count-insns: ERROR: %s\n' "$*" >&2
  exit 1
}
METHOD=${COUNT_METHOD:-auto}
case "$METHOD" in
  auto | plugin | singlestep | both) ;;
  *) die "COUNT_METHOD must be auto, plugin, singlestep or both (got $METHOD)" ;;
esac
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
# With simd the build's row scan must be the ARMv7E-M one (texsat's src/dsp.rs), else the
# harness's check of it (count.rs, builds_agree) would pass on the portable loop.
if [[ ",${COUNT_FEATURES:-}," == *",simd,"* ]]; then
  DISASM=$("$LLVM_BIN/llvm-objdump" -d "$ELF")
  UXTAB=$(grep -cw uxtab <<<"$DISASM" || true)
  UXTB16=$(grep -cw uxtb16 <<<"$DISASM" || true)
  [ "${UXTAB:-0}" -gt 0 ] && [ "${UXTB16:-0}" -gt 0 ] ||
    die "COUNT_FEATURES=simd, but the binary has $UXTAB UXTAB and $UXTB16 UXTB16: texsat's ARMv7E-M row scans (src/dsp.rs, u32 and u16) are not both compiled in"
  echo "count-insns: simd: $UXTAB UXTAB and $UXTB16 UXTB16 instructions in the binary (texsat's src/dsp.rs)" >&2
fi

loud() {
  printf '%s\n' "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!" \
    "!!! count-insns: WARNING: $*" \
    "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!" >&2
}

MARK=$("$LLVM_BIN/llvm-nm" "$ELF" | awk '$3 == "texsat_count_mark" { print $1 }')
[ -n "$MARK" ] || die "texsat_count_mark not found in $ELF"
QEMU_ARGS=(-M mps2-an386 -display none -monitor none -serial none -semihosting -kernel "$ELF")
PARSE_ARGS=(--llvm-bin "$LLVM_BIN" --reps 10 --texels 4096 --mip)
PCS=""
if [ -n "${COUNT_PROFILE:-}" ]; then
  PARSE_ARGS+=(--profile)
  PCS=",pcs=on"
fi
if [ -n "${COUNT_ANNOTATE:-}" ]; then
  PARSE_ARGS+=(--annotate "$COUNT_ANNOTATE")
  PCS=",pcs=on"
fi
if [ -n "${COUNT_LINES:-}" ]; then
  PARSE_ARGS+=(--lines "$COUNT_LINES")
  PCS=",pcs=on"
fi
echo "count-insns: $("$QEMU" --version | head -n 1)" >&2

# The plugin: build it, run, parse. Returns 2 when the plugin could not be built or loaded
# (the caller may fall back), dies on any other failure.
count_plugin() {
  local so plog="$OUT/insn_count.log" status=0
  so=$(bash "$HERE/plugin/build.sh" "$OUT") || return 2
  rm -f "$plog"
  echo "count-insns: $QEMU ${QEMU_ARGS[*]} -plugin $so,mark=0x$MARK,out=$plog$PCS" >&2
  timeout 600 "$QEMU" "${QEMU_ARGS[@]}" -plugin "$so,mark=0x$MARK,out=$plog$PCS" 2>"$OUT/qemu.log" ||
    status=$?
  if ! head -n 1 "$plog" 2>/dev/null | grep -qx 'insn_count 1'; then
    cat "$OUT/qemu.log" >&2
    echo "count-insns: QEMU did not load the plugin (status $status)" >&2
    return 2
  fi
  [ "$status" -eq 0 ] || { cat "$OUT/qemu.log" >&2; die "QEMU with the plugin failed or timed out (status $status)"; }
  python3 "$HERE/count_insns.py" "$ELF" --plugin-log "$plog" "${PARSE_ARGS[@]}" "$@" ||
    die "count_insns.py failed on the plugin's log"
}

# The -singlestep exec log (one TB per instruction), read through a FIFO so that it never
# reaches the disk (unless COUNT_KEEP_LOG is set): 23 GB in 198 million lines on 2026-12-07,
# which QEMU writes a line per system call (about 4 minutes here, most of it in the kernel).
count_singlestep() {
  local log status=0 qstatus=0 qpid
  echo "count-insns: $QEMU ${QEMU_ARGS[*]} -singlestep -d exec,nochain -D <log>" >&2
  if [ -n "${COUNT_KEEP_LOG:-}" ]; then
    log=$OUT/exec.log
    rm -f "$log"
    timeout 600 "$QEMU" "${QEMU_ARGS[@]}" -singlestep -d exec,nochain -D "$log" ||
      die "QEMU failed or timed out (status $?)"
    python3 "$HERE/count_insns.py" "$ELF" --exec-log "$log" "${PARSE_ARGS[@]}" "$@" ||
      die "count_insns.py failed (status $?)"
  else
    log=$OUT/exec.fifo
    rm -f "$log"
    mkfifo "$log"
    timeout 600 "$QEMU" "${QEMU_ARGS[@]}" -singlestep -d exec,nochain -D "$log" &
    qpid=$!
    python3 "$HERE/count_insns.py" "$ELF" --exec-log "$log" "${PARSE_ARGS[@]}" "$@" || status=$?
    wait "$qpid" || qstatus=$?
    rm -f "$log"
    [ "$qstatus" -eq 0 ] || die "QEMU failed or timed out (status $qstatus)"
    [ "$status" -eq 0 ] || die "count_insns.py failed (status $status)"
  fi
}

case "$METHOD" in
  singlestep) count_singlestep ;;
  plugin) count_plugin || die "the insn_count plugin could not be built or loaded (COUNT_METHOD=plugin: no fallback)" ;;
  auto)
    status=0
    count_plugin || status=$?
    if [ "$status" -eq 2 ]; then
      loud "the insn_count TCG plugin could not be built or loaded (see above):" \
        "counting from QEMU's -singlestep exec log instead (same counts, much slower)"
      count_singlestep
    fi
    ;;
  both)
    count_plugin --regions-out "$OUT/regions.plugin" ||
      die "the insn_count plugin could not be built or loaded (COUNT_METHOD=both)"
    count_singlestep --regions-out "$OUT/regions.singlestep" >"$OUT/table.singlestep"
    if ! diff "$OUT/regions.plugin" "$OUT/regions.singlestep" >"$OUT/regions.diff"; then
      head -n 20 "$OUT/regions.diff" >&2
      die "the plugin and the -singlestep exec log disagree" \
        "(instructions per region between marks, one a line: $OUT/regions.plugin, $OUT/regions.singlestep)"
    fi
    echo "count-insns: the plugin and the -singlestep exec log agree on all" \
      "$(wc -l <"$OUT/regions.plugin") regions between marks" >&2
    ;;
esac
