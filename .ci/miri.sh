#!/usr/bin/env bash
# Miri (undefined behaviour, and overflow checks in every interpreted build) over the core's unit
# tests and doctests, without features and with the comparison filters, and over a fast subset of
# host-tests (build.rs and the hostile catalogue). Needs the nightly toolchain and the miri
# component; without them Miri is skipped, loudly, with exit status 0.
#
#   bash .ci/miri.sh
#
# Miri runs these integer sweeps about 10^4 times slower than a native debug build, so tests
# that sweep thousands of cases take more than a minute each; they are skipped here by name
# (SLOW, with the native debug time they take, times about 10^4 for the Miri estimate) until
# their sizes shrink under cfg(miri) (remove a name once its test is smaller). BUDGET lists
# tests that pass under Miri in 10 to 60 s each and are skipped only to keep this script near 10
# minutes on a 2-core machine. Measured one test at a time: /work/helpers/fuzz-report.md.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}/miri"

step() { printf '\n=== %s ===\n' "$*"; }

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
cargo +nightly miri --version
cargo +nightly miri setup >/dev/null

SLOW=(
  # core (more than 60 s under Miri each; native debug time in brackets)
  div::tests::div_euclid_i64_matches_native                     # 501 s [0.047 s]
  div::tests::div_u64_by_u32_is_exact_or_refuses                # [0.10 s]
  div::tests::divrem_u64_matches_native                         # [0.018 s]
  edge::tests::pieces_sum_like_the_extended_texture             # [0.012 s]
  layouts::packed::tests::read_matches_u128_reference           # [0.005 s]
  layouts::tests::fuzz_corrupt_words_never_panic                # [0.68 s]
  layouts::tests::pow2_digits_equal_division_digits             # [0.025 s]
  layouts::tests::pow2_fast_path_equals_general_path_every_box  # [1.6 s]
  layouts::tests::tiled_equals_flat_every_box                   # [0.56 s]
  lookup::tests::corrupt_tiled_storage_never_panics             # [0.058 s]
  lookup::tests::split_boxes_match_direct_sums                  # [0.057 s]
  plan::tests::a_planned_table_answers_every_box_within_its_facts  # [0.11 s]
  wide::tests::u64_mean_matches_reference_fast_and_long_paths   # [0.072 s]
  # core, --features filters
  filters::dip::tests::bit_for_bit_with_the_i128_formulation    # [0.20 s]
  filters::dip::tests::within_bound_of_f64_and_costs            # [0.063 s]
  filters::level::tests::bit_for_bit_with_the_u128_formulation  # [1.0 s]
  filters::level::tests::square_u64_matches_u128                # [0.023 s]
  filters::mip::tests::bit_for_bit_with_the_i128_formulation    # [0.028 s]
  filters::mip::tests::point_sample_matches_the_i128_formulation  # [0.018 s]
  filters::mip::tests::trilinear_weight_truncation_approaches_bound_u16  # [0.008 s]
  filters::mip::tests::trilinear_within_bound_of_f64_u8         # [0.031 s]
  filters::point::tests::centre_index_matches_the_i128_formulation  # [0.024 s]
  filters::pyramid::tests::centres_and_positions_match_the_i128_formulation  # [0.34 s]
  filters::pyramid::tests::lerp_matches_the_signed_formulation  # [1.05 s]
  filters::rip::tests::bit_for_bit_with_the_i128_formulation    # [0.16 s]
  filters::rip::tests::within_bound_of_f64_and_costs            # [0.041 s]
  filters::tent::tests::exact_matches_direct_every_mode         # [0.35 s]
  filters::tent::tests::integer_exact_every_mode                # [3.3 s]
  filters::tent::tests::widths_and_refusals                     # [0.009 s]
  filters::variance::tests::integer_boxes_every_mode            # [0.032 s]
  filters::variance::tests::u64_formulation_matches_u128_exhaustive_small  # [0.083 s]
  filters::variance::tests::u64_formulation_matches_u128_random_large  # [0.054 s]
  filters::variance::tests::widths_and_refusals                 # [0.015 s]
  # host-tests/tests/hostile.rs
  corrupt_lent_layouts_never_panic                              # [0.043 s]
  finding_corrupt_storage_too_wide                              # [0.041 s]
  hostile_boxes_packed_tiled_and_modular                        # [0.012 s]
  plan_boxes_outside_their_facts                                # [0.030 s]
  sat_and_tiled_at_4105_refused_before_writing                  # [0.046 s]
  shortcut_within_its_bound_and_at_the_limits                   # [0.025 s]
  width_proof_at_4104_and_4105                                  # [1.1 s]
)
BUDGET=(
  layouts::packed::tests::round_trip_every_width_and_offset     # 51 s under Miri
  layouts::tests::tiled_modular_combination                     # 42 s
  hostile_boxes_flat_tables                                     # 40 s
  frac_bits_too_large_for_the_word                              # 40 s
  i64_limit_corners_every_layout                                # 18 s
  modular_boxes_beyond_their_bound                              # 15 s
)
skip=()
for t in "${SLOW[@]}" "${BUDGET[@]}"; do
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

step "Miri: the simd feature's unsafe kernels (SSE2, AVX2, AVX-512 VNNI; 0.5 to 2 min each)"
# src/simd.rs is the crate's only unsafe code: its exhaustive small-size tests under Miri, which
# emulates the intrinsics (the CPU need not have them) but not CPUID, so the kernels are those the
# target features enable: each run tests every kernel up to its flags, in its own target dir.
cargo +nightly miri test -p texsat --lib --features simd --locked -- simd::
for flags in "-C target-feature=+avx2" "-C target-feature=+avx512f,+avx512vnni"; do
  RUSTFLAGS="$flags" CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}/miri-$(echo "$flags" | tr -cd 'a-z0-9')" \
    cargo +nightly miri test -p texsat --lib --features simd --locked -- simd::
done

step "Miri: host-tests build.rs and hostile.rs"
# The rest of host-tests is left out: proptest files read their regression files, which Miri's
# isolation refuses; the others sweep thousands of boxes per test.
cargo +nightly miri test -p texsat-host-tests --locked --test build --test hostile -- "${skip[@]}"

echo
echo "miri: passed in $(($(date +%s) - start)) s (skipped by name: ${#SLOW[@]} slow, ${#BUDGET[@]} for time)"
