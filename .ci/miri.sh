#!/usr/bin/env bash
# Miri (undefined behaviour, and overflow checks in every interpreted build). Needs the nightly
# toolchain and the miri component; without them Miri is skipped, loudly, with exit status 0.
#
#   bash .ci/miri.sh              the CI tier: the crate's only unsafe code on x86-64
#                                 (src/simd.rs and src/cast.rs, the `simd::` and `cast::`
#                                 tests) once per instruction set, and the core's
#                                 doctests (about 12 minutes on 2 cores)
#   MIRI_FULL=1 bash .ci/miri.sh  also the core's unit tests without features, the comparison
#                                 filters' unit tests and doctests, and host-tests' build.rs and
#                                 hostile.rs (30 minutes and more on 2 cores)
#
# Why the split: the core is forbid(unsafe_code), so what Miri adds over the native tests (run
# with overflow checks in debug and without them in release) is the dependencies' unsafe as the
# core uses it; the full tier ran past CI's 90 minutes together with the rest of .ci/run.
#
# Miri runs the integer sweeps about 10^4 times slower than a native debug build, so every test
# that sweeps thousands of cases takes a smaller, strided subset of the same cases under
# cfg(miri) (the ends, limits and width boundaries kept; see docs/guarantees.md, "Miri"); the
# native tests are unchanged. Nothing is skipped by name: every test in the files a tier runs.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}/miri"

# Each step prints the seconds since the script started and since the step before: the budget
# is 90 minutes on a clean clone, and these say where the time goes.
T0=$(date +%s)
TPREV=$T0
step() {
  local now
  now=$(date +%s)
  printf '\n[%s s total, %s s in the step before]\n=== %s ===\n' "$((now - T0))" "$((now - TPREV))" "$*"
  TPREV=$now
}

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

start=$(date +%s)

if [ -n "${MIRI_FULL:-}" ]; then
  step "Miri (full tier): the core's unit tests, no features"
  cargo +nightly miri test -p texsat --lib --locked

  step "Miri (full tier): the comparison filters' unit tests (--features filters)"
  # Only the filters' own tests: the rest of the core ran above.
  cargo +nightly miri test -p texsat --lib --features filters --locked -- filters::

  step "Miri (full tier): the core's doctests with --features filters"
  cargo +nightly miri test -p texsat --doc --features filters --locked
fi

step "Miri: the simd feature's unsafe kernels (SSE2, AVX2, AVX-512 VNNI, AVX-512 VBMI packing; 0.5 to 2.5 min each) and the core's doctests, no features"
# src/simd.rs (with the slice casts of src/cast.rs) is the crate's only unsafe code on x86-64: its
# exhaustive small-size tests (and cast.rs's) under Miri, which
# emulates the intrinsics (the CPU need not have them) but not CPUID, so the kernels are those the
# target features enable, each run in its own target dir. Each run tests only the widest kernel
# its flags allow (`Kernel::available` under cfg(miri)): the narrower ones are the earlier
# sets', so every kernel runs once (on a Zen 3 the VBMI set's tests took 501 s with all three
# kernels, 290 s with its own; the whole script 925 s).
# The last set adds AVX-512BW, DQ and VBMI: the tiled kernels that pack their local sums in the row
# step, tiled512::kernel8_packed, band512::row_packed and band512::end_row_packed (Miri emulates
# their loads and stores; the word and byte permutes it cannot emulate are computed field by
# field under cfg(miri), src/simd.rs). Miri is single-threaded: two sets run at a time, each in
# its own target dir with its own log, the longest first and the next set started as soon as
# either slot frees (on a Zen 3 the sets' tests take 125, 227, 267 and 327 s by Miri's own
# clock, which counts interpreted work and reads the same in every run: 452 and 494 s per slot
# this way, against 227 + 327 s when the sets went in fixed pairs); the logs are printed in the
# sets' order when all are done. The core's doctests (no features, about 40 s when they ran alone
# before the sets, in Miri's default target dir) are the queue's last and shortest job: they
# take the slot that frees first (after 452 s of the sets' work).
simd_pass() {
  local flags=$1 log=$2
  RUSTFLAGS="$flags" CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}/miri-$(echo "x$flags" | tr -cd 'a-z0-9')" \
    cargo +nightly miri test -p texsat --lib --features simd --locked -- simd:: cast:: >"$log" 2>&1
}
# From the narrowest set to the widest; the queue below starts them from the last.
sets=(
  ""
  "-C target-feature=+avx2"
  "-C target-feature=+avx512f,+avx512vl,+avx512vnni"
  "-C target-feature=+avx512f,+avx512vl,+avx512vnni,+avx512bw,+avx512dq,+avx512vbmi"
)
doc_pass() {
  cargo +nightly miri test -p texsat --doc --locked >"$1" 2>&1
}
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
running=0
# The sets from the widest, then the doctests (job "doc").
for job in $(seq $((${#sets[@]} - 1)) -1 0) doc; do
  if [ "$running" -ge 2 ]; then
    # A slot frees when either job ends (its status is in its file, read below).
    wait -n || true
    running=$((running - 1))
  fi
  if [ "$job" = doc ]; then
    { s=0; doc_pass "$logs/doc.log" || s=$?; echo "$s" >"$logs/doc.status"; } &
  else
    { s=0; simd_pass "${sets[$job]}" "$logs/$job.log" || s=$?; echo "$s" >"$logs/$job.status"; } &
  fi
  running=$((running + 1))
done
wait
failed=0
s=$(cat "$logs/doc.status" 2>/dev/null || echo missing)
printf -- '--- Miri, the core'"'"'s doctests, no features (exit %s) ---\n' "$s"
cat "$logs/doc.log"
if [ "$s" != 0 ]; then failed=1; fi
for i in "${!sets[@]}"; do
  s=$(cat "$logs/$i.status" 2>/dev/null || echo missing)
  printf -- '--- Miri, simd::, RUSTFLAGS="%s" (exit %s) ---\n' "${sets[$i]}" "$s"
  cat "$logs/$i.log"
  if [ "$s" != 0 ]; then failed=1; fi
done
if [ "$failed" -ne 0 ]; then
  echo "miri: the doctests or the simd kernels FAILED under Miri (logs above)"
  exit 1
fi

if [ -n "${MIRI_FULL:-}" ]; then
  step "Miri (full tier): host-tests build.rs and hostile.rs"
  # The rest of host-tests is left out: proptest files read their regression files, which Miri's
  # isolation refuses; reference.rs's mean_error uses f64::powi, whose precision Rust leaves
  # unspecified and Miri perturbs; crow_literal.rs searches every box of a 32 x 32 texture and
  # stability.rs runs the library's study (neither can shrink in test code alone); the others sweep
  # thousands of boxes per test.
  cargo +nightly miri test -p texsat-host-tests --locked --test build --test hostile
fi

echo
echo "miri: passed in $(($(date +%s) - start)) s (${MIRI_FULL:+full tier}${MIRI_FULL:-CI tier; MIRI_FULL=1 for the full tier})"
