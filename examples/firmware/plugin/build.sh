#!/usr/bin/env bash
# Builds the insn_count TCG plugin (insn_count.c, qemu_plugin_api.h) into DIR/insn_count.so with
# gcc and prints the path of the .so. Installs gcc (apt-get) when missing. On failure it says
# which step failed and exits non-zero (count-insns.sh and run.sh then fall back to QEMU's
# -singlestep exec log, or fail when told to use the plugin only).
#
#   bash examples/firmware/plugin/build.sh DIR
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
OUT=${1:?usage: build.sh DIR}
CC=${CC:-gcc}

fail() {
  printf 'plugin/build.sh: FAILED at step "%s": %s\n' "$1" "$2" >&2
  exit 1
}

if ! command -v "$CC" >/dev/null; then
  [ "$CC" = gcc ] || fail "find the C compiler" "CC=$CC not found"
  echo "plugin/build.sh: installing gcc (apt-get)" >&2
  { apt-get update -qq && apt-get install -y -qq gcc >/dev/null; } ||
    fail "install gcc" "apt-get install gcc failed (set CC to another C compiler)"
fi
mkdir -p "$OUT" || fail "create $OUT" "mkdir failed"
SO=$OUT/insn_count.so
# No glib, no QEMU headers: the API declarations are in qemu_plugin_api.h. Only
# qemu_plugin_install and qemu_plugin_version are exported (-fvisibility=hidden).
"$CC" -shared -fPIC -O2 -Wall -Wextra -fvisibility=hidden -o "$SO.tmp" "$HERE/insn_count.c" ||
  fail "compile" "$CC -shared -fPIC -O2 $HERE/insn_count.c failed"
mv "$SO.tmp" "$SO"
echo "$SO"
