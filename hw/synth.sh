#!/usr/bin/env bash
# Synthesizes texsat's reference datapaths with Yosys for a Xilinx 7-series part
# (`synth_xilinx -family xc7`) and prints LUTs, flip-flops and DSP48E1 blocks as a markdown
# table: the 4-read box sum, and the 16-read lookup in the Paper and the Stable form at
# F = 4, 8 and 12, for the table of a 1024 x 1024 8-bit texture (28-bit entries, the width
# texsat's width proof gives it) and boxes of any size on it (Stable strips of
# bits_of(255 x 1025) = 18 bits). Installs yosys (Debian package) if missing.
#
#   bash hw/synth.sh
set -euo pipefail
cd "$(dirname "$0")"
OUT=${CARGO_TARGET_DIR:-../target}/hw-synth
mkdir -p "$OUT"
if ! command -v yosys >/dev/null; then
  echo "hw/synth.sh: installing yosys" >&2
  { apt-get update -qq && apt-get install -y -qq yosys >/dev/null; } ||
    { echo "hw/synth.sh: ERROR: could not install yosys" >&2; exit 1; }
fi
TEX=1024
W_E=28
B=8
W_STRIP=18

# synth NAME TOP FILES PARAMS: prints "LUTs FFs DSPs CARRY4s".
synth() {
  local name=$1 top=$2 files=$3 params=$4
  yosys -q -l "$OUT/$name.log" -p "read_verilog -I. $files; chparam $params $top; synth_xilinx -family xc7 -top $top; tee -o $OUT/$name.stat stat" >/dev/null ||
    { echo "hw/synth.sh: ERROR: yosys failed on $name (log: $OUT/$name.log)" >&2; exit 1; }
  # The last block of `stat` is the whole design (the hierarchy flattened into the top).
  awk '
    /Number of cells/ { luts = 0; ffs = 0; dsps = 0; carry = 0 }
    $1 ~ /^LUT[1-6]$/ { luts += $2 }
    $1 ~ /^FD/ { ffs += $2 }
    $1 == "DSP48E1" { dsps += $2 }
    $1 == "CARRY4" { carry += $2 }
    END { print luts, ffs, dsps, carry }' "$OUT/$name.stat"
}

echo "| datapath | F | multiplies | LUTs | flip-flops | DSP48E1 | CARRY4 |"
echo "|---|---:|---:|---:|---:|---:|---:|"
read -r l f d c < <(synth box4 sat_box4 "sat_box4.v" "-set TEX_W $TEX -set TEX_H $TEX -set W_E $W_E")
echo "| 4-read box sum | 0 | 0 | $l | $f | $d | $c |"
for F in 4 8 12; do
  read -r l f d c < <(synth "paper-f$F" sat_paper16 "sat_cells16.v sat_paper16.v" \
    "-set TEX_W $TEX -set TEX_H $TEX -set W_E $W_E -set F $F")
  echo "| 16-read Paper | $F | 12 | $l | $f | $d | $c |"
  read -r l f d c < <(synth "stable-f$F" sat_stable16 "sat_cells16.v sat_stable16.v" \
    "-set TEX_W $TEX -set TEX_H $TEX -set W_E $W_E -set F $F -set B $B -set W_STRIP $W_STRIP")
  echo "| 16-read Stable | $F | 12 | $l | $f | $d | $c |"
done
