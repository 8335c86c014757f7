#!/usr/bin/env python3
"""Instructions per texel of each build method on the host, counted by Valgrind (issue 13).

Wall times on a shared VM move by 10 to 80 percent between runs (docs/benchmarks.md); the
instructions a build executes repeat to within 0.1 %. This script runs the build-speed server
(`tools/examples/build_speed.rs`, built with `--features simd,parallel` like the `simd`
variant of `build_speed.py`) under Valgrind's `cachegrind` tool without its cache model, twice
per (method, side): with `n >= 1` builds and with `n + extra`, and reports the difference over
`extra >= 1` builds, per texel. The server's own setup (the texture, the reference table, the
first build's check against it) is in both runs and cancels. Valgrind emulates AVX2 at most, so
on a CPU with AVX-512 the kernel counted is not the one a native run picks: the script asks the
server under Valgrind which kernel it runs there and prints it. The counts repeat to within
0.1 % (allocation addresses and the hash seed of the server's bookkeeping differ per run).

What the count says: a build that runs from caches (a 1,024^2 table that stays in L3 between
builds) takes time about in proportion to it; one bound by memory (4,096^2, or any table that
does not stay in cache) does not, and only `build_speed.py` measures that. The server is built
by `build_speed.py`'s own `build("simd")`.

    apt-get install valgrind
    python3 tools/examples/build_insns.py            # floor,build,stream_into,tiled,modular, 1024^2
    python3 tools/examples/build_insns.py --methods build,tiled --sides 256,1024 --server BIN
"""

import argparse
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import build_speed  # noqa: E402  (the sibling script: its `build(variant)`)


def instructions(server, requests):
    """Instructions Valgrind counted for the server answering `requests` (lines)."""
    run = subprocess.run(
        ["valgrind", "--tool=cachegrind", "--cache-sim=no", "--cachegrind-out-file=/dev/null",
         server],
        input="".join(r + "\n" for r in requests), capture_output=True, text=True, check=True)
    m = re.search(r"I\s+refs:\s+([\d,]+)", run.stderr)
    if not m:
        raise RuntimeError("no instruction count in valgrind's output:\n" + run.stderr[-2000:])
    return int(m.group(1).replace(",", ""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--methods", default="floor,build,stream_into,tiled,modular")
    ap.add_argument("--sides", default="1024")
    ap.add_argument("--builds", type=int, default=1, help="builds in the first run (n)")
    ap.add_argument("--extra", type=int, default=3, help="builds added in the second run")
    ap.add_argument("--server", help="a prebuilt build_speed binary (default: build it)")
    args = ap.parse_args()
    if args.builds < 1 or args.extra < 1:
        sys.exit("--builds and --extra must be at least 1 (the first build also runs the check)")
    if subprocess.run(["valgrind", "--version"], capture_output=True).returncode != 0:
        sys.exit("valgrind not found (apt-get install valgrind)")
    server = args.server or build_speed.build("simd")
    native = subprocess.run([server], input="kernel\n", capture_output=True, text=True,
                            check=True).stdout.strip()
    counted = subprocess.run(["valgrind", "-q", "--tool=none", server], input="kernel\n",
                             capture_output=True, text=True, check=True).stdout.strip()
    methods = args.methods.split(",")
    sides = [int(s) for s in args.sides.split(",")]
    print(f"server: {server}\nkernel counted (under valgrind): {counted}; native run: {native}\n")
    print("| method | " + " | ".join(f"{s}^2 insns/texel | x build" for s in sides) + " |")
    print("|---|" + "---|---|" * len(sides))
    per = {}
    for side in sides:
        for method in methods:
            req = f"{method} {side}"
            a = instructions(server, [req] * args.builds)
            b = instructions(server, [req] * (args.builds + args.extra))
            per[(method, side)] = (b - a) / args.extra / (side * side)
    for method in methods:
        cells = []
        for side in sides:
            v = per[(method, side)]
            ref = per.get(("build", side))
            cells.append(f"{v:.3f} | " + (f"{v / ref:.2f}" if ref else ""))
        print(f"| {method} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
