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
#                                               sample, per plan (the TCG plugin plugin/insn_count.c,
#                                               built with gcc, installed with apt when missing;
#                                               COUNT_METHOD as in count-insns.sh)
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
  # The insn_count TCG plugin (plugin/insn_count.c, built with gcc) counts every executed
  # instruction and prints the running count at each `texsat_demo_mark`; count_insns.py --demo
  # turns the differences into the table. COUNT_METHOD as in count-insns.sh: auto (default: the
  # plugin, falling back loudly to QEMU's -singlestep exec log if it cannot be built or
  # loaded), plugin, singlestep, or both (fails unless both give the same count in every region).
  METHOD=${COUNT_METHOD:-auto}
  case "$METHOD" in
    auto | plugin | singlestep | both) ;;
    *)
      STEP="count instructions"
      die "COUNT_METHOD must be auto, plugin, singlestep or both (got $METHOD)"
      ;;
  esac
  QEMU_COUNT=("$QEMU" -M mps2-an386 -display none -monitor none -serial none
    -semihosting-config enable=on,target=native -kernel "$ELF")
  PARSE=(python3 "$HERE/count_insns.py" "$ELF" --llvm-bin "$LLVM_BIN" --demo)
  STEP="count instructions: find texsat_demo_mark"
  MARK=$("$LLVM_BIN/llvm-nm" "$ELF" | awk '$3 == "texsat_demo_mark" { print $1 }')
  [ -n "$MARK" ] || die "texsat_demo_mark not found"
  use_singlestep=0
  if [ "$METHOD" != singlestep ]; then
    STEP="count instructions: build the insn_count plugin (gcc)"
    PLOG=$OUT/insn_count.log
    if SO=$(bash "$HERE/plugin/build.sh" "$OUT"); then
      STEP="count instructions: run under QEMU with the plugin"
      rm -f "$PLOG"
      status=0
      timeout 120 "${QEMU_COUNT[@]}" -plugin "$SO,mark=0x$MARK,out=$PLOG" >/dev/null 2>"$OUT/qemu-count.log" ||
        status=$?
      if head -n 1 "$PLOG" 2>/dev/null | grep -qx 'insn_count 1'; then
        [ "$status" = 0 ] || { cat "$OUT/qemu-count.log" >&2; die "QEMU exited with status $status"; }
        STEP="count instructions: read the plugin's log"
        "${PARSE[@]}" --plugin-log "$PLOG" --regions-out "$OUT/regions.plugin" || die "count_insns.py failed"
      else
        cat "$OUT/qemu-count.log" >&2
        [ "$METHOD" = auto ] || die "QEMU did not load the plugin (status $status)"
        use_singlestep=1
      fi
    else
      [ "$METHOD" = auto ] || die "the plugin could not be built"
      use_singlestep=1
    fi
    if [ "$use_singlestep" = 1 ]; then
      printf '%s\n' "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!" \
        "!!! run.sh: WARNING: the insn_count TCG plugin could not be built or loaded (see above):" \
        "!!! counting from QEMU's -singlestep exec log instead (same counts, much slower)" \
        "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!" >&2
    fi
  fi
  if [ "$METHOD" = singlestep ] || [ "$METHOD" = both ] || [ "$use_singlestep" = 1 ]; then
    # One TB per instruction, one log line per executed TB, read through a FIFO (about 1.1 GB).
    STEP="count instructions: run under QEMU -singlestep -d exec,nochain"
    FIFO=$OUT/exec.fifo
    rm -f "$FIFO"
    mkfifo "$FIFO"
    timeout 600 "${QEMU_COUNT[@]}" -singlestep -d exec,nochain -D "$FIFO" >/dev/null &
    QPID=$!
    table=/dev/stdout
    [ "$METHOD" = both ] && table=$OUT/table.singlestep
    status=0
    "${PARSE[@]}" --exec-log "$FIFO" --regions-out "$OUT/regions.singlestep" >"$table" || status=$?
    qstatus=0
    wait "$QPID" || qstatus=$?
    rm -f "$FIFO"
    [ "$qstatus" = 0 ] || die "QEMU exited with status $qstatus"
    [ "$status" = 0 ] || die "count_insns.py failed"
  fi
  if [ "$METHOD" = both ]; then
    STEP="count instructions: compare the plugin with the -singlestep exec log"
    diff "$OUT/regions.plugin" "$OUT/regions.singlestep" >&2 ||
      die "the two methods disagree (regions between marks: $OUT/regions.plugin, $OUT/regions.singlestep)"
    echo "run.sh: the plugin and the -singlestep exec log agree on all" \
      "$(wc -l <"$OUT/regions.plugin") regions between marks" >&2
  fi
fi
echo "run.sh: OK"
