#!/usr/bin/env bash
# texsat's link gate: builds the Cortex-M4F firmware in examples/firmware once per feature set
# and FAILS (exit 1) if any of them does not link, which with this firmware's panic handler means
# a panic path remains in texsat (see README.md here).
#
#   examples/firmware/link-gate.sh               all feature sets
#   examples/firmware/link-gate.sh none filters  only these ("none" = no features)
#
# On success: the flash of each gate_* function and the total .text of each feature set.
# On failure: the linker's undefined-symbol lines, then a diagnostics build (feature `diagnose`:
# a panic handler that links) and, from its disassembly, the panic machinery left, every call
# site of it in texsat (the source line the panic would report and the enclosing fn) and which
# gate_* functions reach it.
#
# Environment: LINK_GATE_DIAGNOSE=always also runs the diagnostics for feature sets that link;
# CARGO_TARGET_DIR is honoured (default: examples/firmware/target).
set -euo pipefail
cd "$(dirname "$0")"
HERE=$(pwd)
REPO=$(cd ../.. && pwd)

TARGET=thumbv7em-none-eabihf
BIN=texsat-link-gate
UNDEF=texsat_link_gate_a_panic_path_remains
ALL_SETS=(none filter-point filter-mip filter-rip filter-dip filter-tent filter-variance filters filters,defmt simd filters,defmt,simd)

banner() { printf '\n=== %s ===\n' "$*"; }
die() {
  printf '\nlink-gate: ERROR: %s\n' "$*" >&2
  exit 1
}

# --- tools -----------------------------------------------------------------------------------
command -v cargo >/dev/null || die "cargo not found"
if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
  echo "link-gate: installing the $TARGET target"
  rustup target add "$TARGET" || die "could not install the $TARGET target (rustup target add $TARGET)"
fi
find_llvm_bin() {
  local d
  for d in "$(rustc --print sysroot)"/lib/rustlib/*/bin; do
    if [ -x "$d/llvm-nm" ] && [ -x "$d/llvm-size" ] && [ -x "$d/llvm-objdump" ]; then
      echo "$d"
      return 0
    fi
  done
  return 1
}
if ! LLVM_BIN=$(find_llvm_bin); then
  echo "link-gate: installing the llvm-tools component"
  rustup component add llvm-tools || die "could not install llvm-tools (rustup component add llvm-tools)"
  LLVM_BIN=$(find_llvm_bin) || die "llvm-nm/llvm-size/llvm-objdump not found under $(rustc --print sysroot)/lib/rustlib/*/bin"
fi
PYTHON=$(command -v python3 || true)

TARGET_DIR=${CARGO_TARGET_DIR:-$HERE/target}
ELF=$TARGET_DIR/$TARGET/release/$BIN
OUT=$TARGET_DIR/link-gate
mkdir -p "$OUT"

if [ $# -gt 0 ]; then SETS=("$@"); else SETS=("${ALL_SETS[@]}"); fi

# build FEATURES LOG [ir]: one release build of the firmware; returns cargo's status. With
# `ir`, the same build also writes its optimized (fat-LTO) LLVM IR for ir_check
# (`--emit=llvm-ir,link`: one build per feature set, not a second one for the IR).
build() {
  local features=$1 log=$2 ir=${3:-}
  local args=(rustc --release --locked --target "$TARGET" --bin "$BIN" --no-default-features)
  [ -n "$features" ] && args+=(--features "$features")
  if [ -n "$ir" ]; then
    rm -f "$TARGET_DIR/$TARGET/release/deps/"*.ll
    touch "$HERE/src/main.rs" # cargo would skip a build it thinks fresh, and emit no IR
    args+=(-- --emit=llvm-ir,link)
  fi
  CARGO_TARGET_DIR=$TARGET_DIR cargo "${args[@]}" >"$log" 2>&1
}

# sizes ELF: flash per gate_* and the sections' sizes.
sizes() {
  local elf=$1
  if [ -n "$PYTHON" ]; then
    "$PYTHON" "$HERE/analyze.py" "$elf" --llvm-bin "$LLVM_BIN" --src-root "$REPO" --sizes-only
  else
    echo "  (python3 not found: own sizes only, from llvm-nm)"
    "$LLVM_BIN/llvm-nm" --print-size --size-sort -C "$elf" | grep 'gate_' | sed 's/^/  /'
  fi
  echo
  local text
  text=$("$LLVM_BIN/llvm-size" -A "$elf" | awk '$1 == ".text" {print $2}')
  echo "  .text section: $text bytes   (llvm-size: text = .vector_table + .text + .rodata)"
  "$LLVM_BIN/llvm-size" "$elf" | sed 's/^/  /'
}

# diagnose FEATURES NAME: the diagnostics build and its report.
diagnose() {
  local features=$1 name=$2 dir=$OUT/$2
  local feats=diagnose
  [ -n "$features" ] && feats="$features,diagnose"
  echo
  echo "--- diagnostics ($name + diagnose: the same firmware with a panic handler that links) ---"
  if ! build "$feats" "$dir/diagnose.log"; then
    tail -n 40 "$dir/diagnose.log"
    echo "  (the diagnostics build failed too: see $dir/diagnose.log)"
    return
  fi
  cp "$ELF" "$dir/diagnose.elf"
  echo "  (flash below is of the diagnostics build: it includes the panic call sites' code, and the"
  echo "   panic machinery is listed separately, not counted per gate)"
  if [ -n "$PYTHON" ]; then
    "$PYTHON" "$HERE/analyze.py" "$dir/diagnose.elf" --llvm-bin "$LLVM_BIN" --src-root "$REPO" |
      tee "$dir/diagnostics.txt"
    echo
    "$LLVM_BIN/llvm-size" "$dir/diagnose.elf" | sed 's/^/  /'
  else
    echo "  python3 not found: panic symbols and their direct callers only"
    "$LLVM_BIN/llvm-nm" -C "$dir/diagnose.elf" |
      grep -E 'core::panicking|panic_bounds_check|slice_.*fail|div_by_zero|rem_by_zero|unwrap_failed|expect_failed' || true
    "$LLVM_BIN/llvm-objdump" -d -C --no-show-raw-insn "$dir/diagnose.elf" | awk '
      /^[0-9a-f]+ <.*>:$/ { fn = $0; sub(/^[0-9a-f]+ </, "", fn); sub(/>:$/, "", fn) }
      /\tbl?(\.w)?\t.*<core::(panicking|slice::index|option|result)::/ {
        t = $0; sub(/.*</, "", t); sub(/>.*/, "", t)
        if (t !~ /\+0x/ && index(fn, "core::") != 1) print "  " fn "  ->  " t }' | sort | uniq -c
  fi
}

# --- self-test: the gate must pass a panic-free firmware and fail one with a panic path ------
banner "link gate self-test"
mkdir -p "$OUT/selftest"
if ! build selftest "$OUT/selftest/clean.log"; then
  tail -n 30 "$OUT/selftest/clean.log"
  die "self-test: a panic-free firmware (feature selftest) did not link: the gate itself is broken (log: $OUT/selftest/clean.log)"
fi
if build selftest-panic "$OUT/selftest/panic.log"; then
  die "self-test: a firmware with an out-of-bounds index (feature selftest-panic) LINKED: the gate no longer catches panic paths"
fi
grep -q "undefined symbol: $UNDEF" "$OUT/selftest/panic.log" ||
  die "self-test: the selftest-panic build failed, but not with 'undefined symbol: $UNDEF' (log: $OUT/selftest/panic.log)"
echo "ok: a panic-free firmware links; one with [0u8; 4][black_box(9)] fails with 'undefined symbol: $UNDEF'"

# --- IR check: no 128-bit integer operation on the paths of u16/u32 tables ---------------------
# The gate's tables are u32 and u16 (flat, tiled, modular; u16: flat and modular, gate_u16_*;
# and its filters' u8/u16 texels; the tent filter's order-2 tables are u32 too, tent_gates::Te),
# so the optimized, fat-LTO IR of a linking firmware must hold no i128 anywhere except in the
# helpers whose *signature* is 128-bit (gate_width_u128: width::bits_of(u128) and friends,
# host/compile-time analysis; gate_tent_width_u128: the tent filter's tent_entry_bits,
# tent_line_bits with their saturating u128 fallbacks and paper_error_bound) and the fixed
# crate's float conversion behind Rect::from_f64/from_f32 (host conveniences). The tent lookups
# on u32 tables compute in i64 (TentEntry::Acc; src/filters/tent.rs, docs/wide-arithmetic.md),
# so none of their functions is allowed: only u64/u128 tent tables, which no gate builds, keep
# i128. The deny list keeps the tent builds and their width proofs (build_entry_bits,
# build_line_bits: 64-bit and limb arithmetic) out even of the allowed names. main is not
# allowed: it holds no 128-bit value (gate_width_u128 forms its u128 from two u64 halves). Then
# the call graph (ir-reach.awk): only gate_width_u128, gate_tent_width_u128 and
# gate_rect_from_f64 may reach a function that holds i128, so no other gate (nor main, outside
# those gates) gets one through an allowed callee either. (On 32-bit ARM a 128-bit division is
# inlined, so symbol names cannot show it: the IR is the proof.)
ir_check() {
  local name=$1 ll
  # The IR of the build that just linked (build ... ir).
  ll=$(ls -t "$TARGET_DIR/$TARGET/release/deps/"*.ll 2>/dev/null | head -n 1)
  [ -n "$ll" ] || { echo "!!! IR CHECK: no .ll file produced"; return 1; }
  awk '/^define/{fn=$0; seen=0} /^}/{fn=""} fn != "" && !/^define/ && /^[^;!#]/ && !/#dbg/ && /[ (<{\[]i128[ ,)>}\]*]/ {if(!seen){print fn; seen=1}}' "$ll" \
    | grep -oE '@[^(]+' | sed 's/^@//' >"$OUT/$name/i128-functions.txt"
  local bad
  local allow='gate_width_u128|6texsat4rect.*from_f(64|32)|10tent_gates[0-9]+gate_tent_width_u128|7filters4tent[0-9]+(tent_entry_bits|tent_line_bits|entry_bits_u128|line_bits_u128|side_product|paper_error_bound)'
  local deny='7filters4tent.*(5build|build_entry_bits|build_line_bits|limb_bits)'
  bad=$({ grep -vE "$allow" "$OUT/$name/i128-functions.txt"; grep -E "$deny" "$OUT/$name/i128-functions.txt"; } || true)
  local allowed
  allowed=$(grep -cE "$allow" "$OUT/$name/i128-functions.txt" || true)
  if [ -n "$bad" ]; then
    echo "!!! IR CHECK FAILED for '$name': 128-bit integer operations in the optimized IR of:"
    echo "$bad" | sed 's/^/!!!   /'
    return 1
  fi
  # The same through calls: no other gate may reach a function that holds i128 (an allowed one
  # included), through any chain of calls the IR shows (ir-reach.awk).
  local allow_gates='gate_width_u128|gate_rect_from_f64|10tent_gates[0-9]+gate_tent_width_u128'
  awk -v allow_gates="$allow_gates" -f "$HERE/ir-reach.awk" "$ll" >"$OUT/$name/i128-reach.txt"
  if [ -s "$OUT/$name/i128-reach.txt" ]; then
    echo "!!! IR CHECK FAILED for '$name': gates that reach a function holding i128 (gate -> function):"
    sed 's/^/!!!   /' "$OUT/$name/i128-reach.txt"
    return 1
  fi
  echo "IR check: no i128 on any u16/u32 path ($allowed allowed function(s) with a 128-bit signature or float conversion; list: $OUT/$name/i128-functions.txt); no other gate reaches one through calls"
}

declare -A STATUS
FAILED=()
for set in "${SETS[@]}"; do
  name=${set//,/+}
  features=$set
  [ "$set" = none ] && features=""
  dir=$OUT/$name
  mkdir -p "$dir"
  banner "link gate: ${name} (texsat features: ${features:-none})"
  if build "$features" "$dir/build.log" ir; then
    cp "$ELF" "$dir/gate.elf"
    STATUS[$name]="links: no panic path"
    echo "LINKS: no panic path remains. Flash (release, opt-level s, fat LTO):"
    sizes "$dir/gate.elf"
    if ! ir_check "$name"; then
      STATUS[$name]="FAILS: i128 in the IR"
      FAILED+=("$name")
    else
      STATUS[$name]="links: no panic path; no i128 on u16/u32 paths"
    fi
    if [ "${LINK_GATE_DIAGNOSE:-}" = always ]; then diagnose "$features" "$name"; fi
  elif grep -q "undefined symbol: $UNDEF" "$dir/build.log"; then
    STATUS[$name]="FAILS: a panic path remains"
    FAILED+=("$name")
    echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
    echo "!!! LINK GATE FAILED for '$name': a panic path remains in the firmware."
    echo "!!! The panic handler is reachable, so the linker needs the undefined symbol:"
    grep -E "undefined symbol|>>> referenced by|>>>  " "$dir/build.log" | sed 's/^[[:space:]]*= note:[[:space:]]*//; s/^[[:space:]]*/!!!   /'
    echo "!!! (full log: $dir/build.log)"
    echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
    diagnose "$features" "$name"
  else
    STATUS[$name]="FAILS: build error"
    FAILED+=("$name")
    echo "!!! LINK GATE FAILED for '$name': the build itself failed (not a panic path):"
    grep -E "^(error|warning: unused)" -A 12 "$dir/build.log" | head -n 60 || tail -n 40 "$dir/build.log"
    echo "!!! (full log: $dir/build.log)"
  fi
done

banner "link gate summary"
for set in "${SETS[@]}"; do
  name=${set//,/+}
  printf '  %-28s %s\n' "$name" "${STATUS[$name]}"
done
if [ ${#FAILED[@]} -gt 0 ]; then
  echo
  echo "LINK GATE FAILED: ${FAILED[*]}"
  echo "Diagnostics per feature set: $OUT/<set>/diagnostics.txt"
  exit 1
fi
echo
echo "LINK GATE PASSED: no panic path in any feature set."
