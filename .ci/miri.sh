#!/usr/bin/env bash
# Miri (undefined behaviour, and arithmetic overflow in every build of the interpreted code) over
# the core's unit tests and doctests, without features and with the comparison filters, and over
# a fast subset of host-tests. Needs the nightly toolchain; without it Miri is skipped, loudly,
# with exit status 0.
#
# Tests whose sizes make them take more than a minute each under Miri (Miri is about 10^4 times
# slower than a native debug build on these integer loops) are skipped here by name until their
# sizes shrink under `cfg(miri)`; each is listed below with what it measured. Remove a name from
# SLOW once its test is smaller under Miri. Measured on the 2-core CI machine: the whole script
# takes about 10 minutes (see the report in fuzz/README.md).
#
#   bash .ci/miri.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}"

step() { printf '\n=== %s ===\n' "$*"; }

if ! rustup toolchain list | grep -q '^nightly'; then
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  echo "!!! WARNING: no nightly toolchain: Miri is SKIPPED."
  echo "!!! (rustup toolchain install nightly, then run bash .ci/miri.sh)"
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  exit 0
fi
rustup component add miri rust-src --toolchain nightly
cargo +nightly miri --version
cargo +nightly miri setup

# Tests skipped under Miri until their sizes shrink under cfg(miri). Each took more than 60 s
# under Miri (measured one at a time); the native debug time in brackets, times about 10^4, is
# the estimate of the full Miri time.
SLOW=(
  # core, no features
  div::tests::div_euclid_i64_matches_native                    # 501 s measured [0.047 s]
  div::tests::div_u64_by_u32_is_exact_or_refuses               # [0.100 s]
  div::tests::divrem_u64_matches_native                        # [0.018 s]
  edge::tests::pieces_sum_like_the_extended_texture            # [0.012 s]
  layouts::packed::tests::read_matches_u128_reference          # [0.005 s]
  layouts::tests::fuzz_corrupt_words_never_panic               # [0.68 s]
  layouts::tests::pow2_digits_equal_division_digits            # [0.025 s]
  layouts::tests::pow2_fast_path_equals_general_path_every_box # [1.6 s]
  layouts::tests::tiled_equals_flat_every_box                  # [0.56 s]
  lookup::tests::corrupt_tiled_storage_never_panics            # [0.058 s]
  lookup::tests::split_boxes_match_direct_sums                 # [0.057 s]
  plan::tests::a_planned_table_answers_every_box_within_its_facts # [0.11 s]
  wide::tests::u64_mean_matches_reference_fast_and_long_paths  # [0.072 s]
  # core, --features filters
  filters::dip::tests::bit_for_bit_with_the_i128_formulation   # [0.20 s]
  filters::dip::tests::within_bound_of_f64_and_costs           # [0.063 s]
  filters::level::tests::bit_for_bit_with_the_u128_formulation # [1.0 s]
  filters::level::tests::square_u64_matches_u128               # [0.023 s]
  filters::mip::tests::bit_for_bit_with_the_i128_formulation   # [0.028 s]
  filters::mip::tests::point_sample_matches_the_i128_formulation # [0.018 s]
  filters::mip::tests::trilinear_weight_truncation_approaches_bound_u16 # [0.008 s]
  filters::mip::tests::trilinear_within_bound_of_f64_u8        # [0.031 s]
  filters::point::tests::centre_index_matches_the_i128_formulation # [0.024 s]
  filters::pyramid::tests::centres_and_positions_match_the_i128_formulation # [0.34 s]
  filters::pyramid::tests::lerp_matches_the_signed_formulation # [1.05 s]
  filters::rip::tests::bit_for_bit_with_the_i128_formulation   # [0.16 s]
  filters::rip::tests::within_bound_of_f64_and_costs           # [0.041 s]
  filters::tent::tests::exact_matches_direct_every_mode        # [0.35 s]
  filters::tent::tests::integer_exact_every_mode               # [3.3 s]
  filters::tent::tests::widths_and_refusals                    # [0.009 s]
  filters::variance::tests::integer_boxes_every_mode           # [0.032 s]
  filters::variance::tests::u64_formulation_matches_u128_exhaustive_small # [0.083 s]
  filters::variance::tests::u64_formulation_matches_u128_random_large # [0.054 s]
  filters::variance::tests::widths_and_refusals                # [0.015 s]
)
skip=()
for t in "${SLOW[@]}"; do
  skip+=(--skip "$t")
done

start=$(date +%s)
step "Miri: the core's unit tests, no features"
cargo +nightly miri test -p texsat --lib --locked -- "${skip[@]}"

step "Miri: the core's doctests, no features"
cargo +nightly miri test -p texsat --doc --locked

step "Miri: the comparison filters' unit tests (--features filters)"
# Only the filters' own tests: the rest of the core ran above.
cargo +nightly miri test -p texsat --lib --features filters --locked -- filters:: "${skip[@]}"

step "Miri: the core's doctests with --features filters"
cargo +nightly miri test -p texsat --doc --features filters --locked

step "Miri: a fast subset of host-tests"
# Files whose tests run in seconds each under Miri; proptest-driven files are left out (256
# cases each, and they read their regression files, which Miri's isolation forbids).
HOST_TESTS=(build)
host=()
for t in "${HOST_TESTS[@]}"; do
  host+=(--test "$t")
done
cargo +nightly miri test -p texsat-host-tests --locked "${host[@]}" -- "${skip[@]}"

echo
echo "Miri: passed in $(($(date +%s) - start)) s (${#SLOW[@]} slow tests skipped by name)"
