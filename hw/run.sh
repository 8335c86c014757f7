#!/usr/bin/env bash
# Simulates texsat's reference datapaths (hw/*.v) with Icarus Verilog against golden vectors
# written by `sat vectors`, and fails on any mismatch.
#
#   bash hw/run.sh          every case below
#
# Cases: the 4-read box sum at integer corners; the 16-read lookup in both forms (Stable, Paper)
# at F = 4, 8 and 12; u32 and u64 tables; three textures. Each case: `sat vectors` writes the
# table image, the stimulus and the expected sums and reads; the testbench (hw/tb.v) drives the
# datapath and compares every sum and read count. Installs iverilog (Debian package) if missing.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target}
OUT=$CARGO_TARGET_DIR/hw
mkdir -p "$OUT"

die() {
  printf 'hw/run.sh: ERROR: %s\n' "$*" >&2
  exit 1
}

if ! command -v iverilog >/dev/null || ! command -v vvp >/dev/null; then
  echo "hw/run.sh: installing iverilog"
  { apt-get update -qq && apt-get install -y -qq iverilog >/dev/null; } ||
    die "could not install iverilog (apt-get install iverilog)"
fi

echo "hw/run.sh: building the sat tool"
cargo build --locked -q -p texsat-tools --example sat || die "could not build the sat tool"
SAT=$CARGO_TARGET_DIR/debug/examples/sat

fails=0
# case NAME DUT VECTOR-ARGS...: vectors, compile, simulate, check.
case_() {
  local name=$1 dut=$2
  shift 2
  local dir=$OUT/$name
  rm -rf "$dir"
  "$SAT" vectors --out "$dir" "$@" 2>"$dir.gen.log" || {
    cat "$dir.gen.log" >&2
    die "$name: sat vectors failed"
  }
  local srcs=(hw/tb.v)
  case $dut in
    DUT_BOX4) srcs+=(hw/sat_box4.v) ;;
    DUT_STABLE) srcs+=(hw/sat_cells16.v hw/sat_stable16.v) ;;
    DUT_PAPER) srcs+=(hw/sat_cells16.v hw/sat_paper16.v) ;;
  esac
  iverilog -g2005 -Wall -I "$dir" -I hw -D "$dut" -o "$dir/tb.vvp" "${srcs[@]}" 2>"$dir/iverilog.log" ||
    {
      cat "$dir/iverilog.log" >&2
      die "$name: iverilog failed"
    }
  local result
  result=$(vvp -n "$dir/tb.vvp" | tee "$dir/sim.log" | grep '^tb: ' | tail -n 1)
  printf '%-28s %s\n' "$name" "$result"
  case $result in
    "tb: PASS "*) ;;
    *)
      grep '^tb: sample' "$dir/sim.log" | head -n 5 >&2 || true
      fails=$((fails + 1))
      ;;
  esac
}

case_ box4-noise DUT_BOX4 --scene noise --frac-bits 0 --count 500 --seed 1
case_ box4-zone-u64 DUT_BOX4 --scene zone-plate --frac-bits 0 --entry u64 --count 300 --seed 2
for f in 4 8 12; do
  case_ "stable-f$f-noise" DUT_STABLE --scene noise --frac-bits "$f" --form stable --count 400 --seed "$f"
  case_ "paper-f$f-noise" DUT_PAPER --scene noise --frac-bits "$f" --form paper --count 400 --seed "$f"
done
case_ stable-f8-checker-u64 DUT_STABLE --scene heckbert-checker-plane --frac-bits 8 --entry u64 --count 300 --seed 3
case_ paper-f8-zone DUT_PAPER --scene zone-plate --frac-bits 8 --form paper --count 300 --seed 4

if [ "$fails" -ne 0 ]; then
  die "$fails case(s) failed (logs in $OUT)"
fi
echo "hw/run.sh: every case passed"
