#!/usr/bin/env bash
# Smoke run of every cargo fuzz target in fuzz/ (fuzz/README.md): each runs for a short time
# (FUZZ_SMOKE_SECONDS, default 10) starting from its committed corpus, and any crash or mismatch
# fails the script. New inputs go to a temporary directory, so the committed corpora stay as
# they are. Needs the nightly toolchain (libFuzzer's instrumentation); without it the smoke is
# skipped, loudly, with exit status 0.
#
#   bash .ci/fuzz-smoke.sh                 # every target, 10 s each
#   FUZZ_SMOKE_SECONDS=60 bash .ci/fuzz-smoke.sh lookup layouts
set -euo pipefail
cd "$(dirname "$0")/.."

SECONDS_EACH="${FUZZ_SMOKE_SECONDS:-10}"
# cargo fuzz's own build directory (not the workspace's: the instrumented build differs).
TARGET_DIR="${FUZZ_TARGET_DIR:-$PWD/fuzz/target}"

if ! rustup toolchain list | grep -q '^nightly'; then
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  echo "!!! WARNING: no nightly toolchain: the fuzz smoke is SKIPPED."
  echo "!!! (rustup toolchain install nightly, then run bash .ci/fuzz-smoke.sh)"
  echo "!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!"
  exit 0
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
  cargo +nightly install cargo-fuzz --locked
fi
cargo fuzz --version

if [ "$#" -gt 0 ]; then
  targets=("$@")
else
  mapfile -t targets < <(cargo +nightly fuzz list --fuzz-dir fuzz)
fi

# No sanitizer: the core is forbid(unsafe_code) and the targets check answers, not memory; the
# long runs (fuzz/README.md) use the same build. Every target at once when none is named: one
# cargo run builds the binaries side by side (on a 2-core Zen 3 the six builds took 4.9
# minutes at once, 5.6 one at a time).
if [ "$#" -gt 0 ]; then
  for t in "${targets[@]}"; do
    cargo +nightly fuzz build --fuzz-dir fuzz --target-dir "$TARGET_DIR" -s none "$t"
  done
else
  cargo +nightly fuzz build --fuzz-dir fuzz --target-dir "$TARGET_DIR" -s none
fi

scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
# One target's run: libFuzzer on one core, its output to $scratch/<target>.log, its exit status
# to $scratch/<target>.status.
smoke() {
  local t=$1 status=0
  mkdir -p "$scratch/$t" "fuzz/corpus/$t"
  # -entropic=0: the default power schedule spends most of the time on its own bookkeeping
  # with these targets (measured: 6x fewer executions per second).
  cargo +nightly fuzz run --fuzz-dir fuzz --target-dir "$TARGET_DIR" -s none "$t" \
    "$scratch/$t" "fuzz/corpus/$t" -- \
    -max_total_time="$SECONDS_EACH" -entropic=0 -max_len=4096 -timeout=20 \
    -rss_limit_mb=2048 -malloc_limit_mb=512 -print_final_stats=1 \
    >"$scratch/$t.log" 2>&1 || status=$?
  echo "$status" >"$scratch/$t.status"
}
# Two targets at a time (each run is one process on one core: the machine has two), the next
# started as soon as either ends; the reports are printed in the targets' order after all.
running=0
for t in "${targets[@]}"; do
  if [ "$running" -ge 2 ]; then
    wait -n || true
    running=$((running - 1))
  fi
  smoke "$t" &
  running=$((running + 1))
done
wait
failed=0
for t in "${targets[@]}"; do
  printf '\n=== fuzz smoke: %s, %s s ===\n' "$t" "$SECONDS_EACH"
  status=$(cat "$scratch/$t.status" 2>/dev/null || echo missing)
  grep -E '^(#[0-9]+ +DONE|stat::number_of_executed_units)' "$scratch/$t.log" || true
  if [ "$status" != 0 ]; then
    tail -n 60 "$scratch/$t.log"
    echo "fuzz smoke: $t FAILED (exit $status; the input is under fuzz/artifacts/$t/)"
    failed=$((failed + 1))
  fi
done
if [ "$failed" -ne 0 ]; then
  echo
  echo "fuzz smoke: $failed of ${#targets[@]} targets FAILED (reports above)"
  exit 1
fi
echo
echo "fuzz smoke: ${#targets[@]} targets, no crash"
