#!/usr/bin/env python3
"""A tiled build against the flat build in three orders of jobs, for two or more servers (issue 13).

`build_speed.py` times every job once per round in a shuffled order: a job often follows one of
4,096^2, which leaves nothing of its own data in the caches. This script separates the two
regimes that mix in that figure, for builds of `build_speed.rs` (the servers, passed as
`name=path`, as `build_speed.py --servers` takes them):

  hot    N tiled builds back to back, then N flat builds (`build`): the data in cache
  cold   N times: `floor 4096`, `build 1024`, `floor 4096`, `tiled 1024` (the floor of 4,096^2
         reads 16 MiB and writes 64 MiB: nothing of the 1,024^2 build is left in L2 or L3)
  mixed  N rounds of the 6 jobs floor, build, tiled x 1,024^2, 4,096^2, shuffled (the same
         order for every server), as `build_speed.py` does without Python and OpenCV between

Each server runs K times, the servers in turn, so that a slow spell of the machine hits all of
them. Prints per server the medians over the K runs of the tiled and flat builds' medians (ns
per texel) and of their ratio, and per run the ratio; then each server's tiled time over the
first server's, run by run. Builds are checked against `Sat::build` by the server, as in
`build_speed.py`. One process per run: a server's memory is its own, which on the 2-vCPU VM of
2026-12-06 moved the floor of one server against another's by up to 1.35x in one harness run.

    cargo build --release --locked -p texsat-tools --example build_speed --features simd,parallel
    cp target/release/examples/build_speed /tmp/after
    python3 tools/examples/build_orders.py --order cold --runs 6 --builds 25 \\
        before=/tmp/before after=/tmp/after
"""

import argparse
import os
import random
import statistics
import subprocess


def requests(order, n, seed):
    """The request lines of one run and, per line, the (method, side) it times."""
    if order == "hot":
        jobs = [("tiled", 1024)] * n + [("build", 1024)] * n
    elif order == "cold":
        jobs = [("floor", 4096), ("build", 1024), ("floor", 4096), ("tiled", 1024)] * n
    else:
        six = [(m, s) for m in ("floor", "build", "tiled") for s in (1024, 4096)]
        rng = random.Random(seed)
        jobs = []
        for _ in range(n):
            rng.shuffle(six)
            jobs += six
    return jobs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("servers", nargs="+", help="name=path of a build_speed server")
    ap.add_argument("--order", choices=["hot", "cold", "mixed"], required=True)
    ap.add_argument("--runs", type=int, default=6, help="runs per server (K)")
    ap.add_argument("--builds", type=int, default=25, help="builds or rounds per run (N)")
    ap.add_argument("--cpu", type=int, default=1, help="the CPU every server runs on")
    ap.add_argument("--pages", choices=["4k", "thp"], default="4k")
    args = ap.parse_args()
    servers = [s.split("=", 1) for s in args.servers]
    env = dict(os.environ, TEXSAT_BS_PAGES=args.pages)
    sides = (4096, 1024) if args.order == "mixed" else (1024,)
    runs = {name: [] for name, _ in servers}
    for k in range(args.runs):
        jobs = requests(args.order, args.builds, k)
        # One untimed pass first: storage paged in, every method checked once.
        warm = sorted(set(jobs))
        lines = "".join(f"{m} {s}\n" for m, s in warm + jobs)
        for name, path in servers:
            out = subprocess.run(["taskset", "-c", str(args.cpu), path], input=lines,
                                 capture_output=True, text=True, env=env, check=True)
            times = [float(x) for x in out.stdout.split()][len(warm):]
            got = {}
            for job, t in zip(jobs, times):
                got.setdefault(job, []).append(t)
            runs[name].append({s: (statistics.median(got[("tiled", s)]),
                                   statistics.median(got[("build", s)])) for s in sides})
    for s in sides:
        print(f"{args.order}, {s}^2, {args.runs} runs of {args.builds}, pages {args.pages}")
        for name, _ in servers:
            r = [x[s] for x in runs[name]]
            ratios = [t / b for t, b in r]
            print(f"  {name}: tiled {statistics.median(t for t, _ in r):.3f}, "
                  f"build {statistics.median(b for _, b in r):.3f}, "
                  f"tiled/build {statistics.median(ratios):.2f} "
                  f"[{' '.join(f'{x:.2f}' for x in ratios)}]")
        first = servers[0][0]
        for name, _ in servers[1:]:
            rel = [x[s][0] / y[s][0] for x, y in zip(runs[name], runs[first])]
            print(f"  {name} tiled / {first} tiled: {statistics.median(rel):.3f} "
                  f"[{' '.join(f'{x:.2f}' for x in rel)}]")


if __name__ == "__main__":
    main()
