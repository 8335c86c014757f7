#!/usr/bin/env bash
# Miri over the core: its unit tests (no features and with every filter) and its doctests, on
# the nightly toolchain (`rustup component add miri rust-src --toolchain nightly`). Says so
# loudly and exits 0 when nightly or Miri cannot be had.
#
#   bash .ci/miri.sh
#
# Thirteen unit tests sweep thousands of cases each and take more than a minute apiece under
# Miri (docs/guarantees.md, "Miri"); they are skipped here until
# their sizes shrink under cfg(miri). Everything else runs.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}/miri"

if ! rustup toolchain list | grep -q '^nightly'; then
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  echo "!!! WARNING: no nightly toolchain: Miri is SKIPPED."
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  exit 0
fi
if ! rustup component add miri rust-src --toolchain nightly >/dev/null 2>&1; then
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  echo "!!! WARNING: could not add the miri component: Miri is SKIPPED."
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  exit 0
fi
cargo +nightly miri setup >/dev/null

SLOW=(
  div::tests::div_euclid_i64_matches_native
  div::tests::div_u64_by_u32_is_exact_or_refuses
  div::tests::divrem_u64_matches_native
  edge::tests::pieces_sum_like_the_extended_texture
  layouts::packed::tests::read_matches_u128_reference
  layouts::tests::fuzz_corrupt_words_never_panic
  layouts::tests::pow2_digits_equal_division_digits
  layouts::tests::pow2_fast_path_equals_general_path_every_box
  layouts::tests::tiled_equals_flat_every_box
  lookup::tests::corrupt_tiled_storage_never_panics
  lookup::tests::split_boxes_match_direct_sums
  plan::tests::a_planned_table_answers_every_box_within_its_facts
  wide::tests::u64_mean_matches_reference_fast_and_long_paths
)
skips=()
for t in "${SLOW[@]}"; do
  skips+=(--skip "$t")
done

start=$(date +%s)
cargo +nightly miri test -p texsat --lib -- "${skips[@]}"
cargo +nightly miri test -p texsat --doc
echo "miri: core unit tests (less ${#SLOW[@]} slow sweeps) and doctests passed in $(( $(date +%s) - start )) s"
