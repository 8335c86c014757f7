#!/usr/bin/env python3
"""A tiled build against the flat build in three orders of jobs, for one or more servers (issue 13).

`build_speed.py` times every job once per round in a shuffled order: a job often follows one of
4,096^2, which leaves nothing of its own data in the caches. This script separates the two
regimes that mix in that figure, for builds of `build_speed.rs` (the servers, each a separate
argument `name=path`; `build_speed.py --servers` takes the same pairs as one comma-separated
list):

  hot    N tiled builds back to back, then N flat builds (`build`): the data in cache
  cold   N times: `floor 4096`, `build 1024`, `floor 4096`, `tiled 1024` (the floor of 4,096^2
         reads 16 MiB and writes 64 MiB: nothing of the 1,024^2 build is left in L2 or L3)
  mixed  N rounds of the 6 jobs floor, build, tiled x 1,024^2, 4,096^2, shuffled (the same
         order for every server), as `build_speed.py` does without Python and OpenCV between

Each server runs K times as a new process, the servers in turn (the first one rotating), so
that a slow spell of the machine hits all of them, and so does where a process's memory lands:
on the 2-vCPU VM of 2026-12-06 the identical floor of one server read 0.73x and 1.35x of
another's in one `build_speed.py` run. Prints per server the medians over the K runs of the
floor's, the flat build's and the tiled build's medians (ns per texel), and the median of the
runs' tiled/flat ratios with each run's; then each server's tiled time (and floor) over the
first server's, run by run. Compare servers by those and by tiled/flat, and run a server twice
(`a=/tmp/a a2=/tmp/a`) to see what the same binary reads. Builds are checked against
`Sat::build` by the server, as in `build_speed.py`. The pages are asked of the servers
(`TEXSAT_BS_PAGES`), not checked (`build_speed.py` reports them).

    cargo build --release --locked -p texsat-tools --example build_speed --features simd,parallel
    cp target/release/examples/build_speed /tmp/after    # and the same at the base: /tmp/before
    python3 tools/examples/build_orders.py --order cold --runs 6 --builds 25 \\
        before=/tmp/before after=/tmp/after              # every server on CPU 1 (--cpu)
"""

import argparse
import os
import random
import statistics
import subprocess


def requests(order, n, seed):
    """The (method, side) of every request of one run, in order."""
    if order == "hot":
        return [("tiled", 1024)] * n + [("build", 1024)] * n
    if order == "cold":
        return [("floor", 4096), ("build", 1024), ("floor", 4096), ("tiled", 1024)] * n
    six = [(m, s) for m in ("floor", "build", "tiled") for s in (1024, 4096)]
    rng = random.Random(seed)
    jobs = []
    for _ in range(n):
        rng.shuffle(six)
        jobs += six
    return jobs


def run(path, jobs, cpu, env):
    """One server process: an untimed pass over the distinct jobs (storage paged in, every
    method checked once), then `jobs`; each (method, side)'s times."""
    warm = sorted(set(jobs))
    lines = "".join(f"{m} {s}\n" for m, s in warm + jobs)
    out = subprocess.run(["taskset", "-c", str(cpu), path], input=lines, text=True, env=env,
                         stdout=subprocess.PIPE, check=True).stdout.split()
    if len(out) != len(warm) + len(jobs):
        raise SystemExit(f"{path}: {len(out)} answers to {len(warm) + len(jobs)} requests")
    got = {}
    for job, t in zip(jobs, out[len(warm):]):
        got.setdefault(job, []).append(float(t))
    return got


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("servers", nargs="+", help="name=path of a build_speed server")
    ap.add_argument("--order", choices=["hot", "cold", "mixed"], required=True)
    ap.add_argument("--runs", type=int, default=6, help="runs per server (K)")
    ap.add_argument("--builds", type=int, default=25, help="builds or rounds per run (N)")
    ap.add_argument("--cpu", type=int, default=1, help="the CPU every server runs on")
    ap.add_argument("--pages", choices=["4k", "thp"], default="4k")
    args = ap.parse_args()
    if args.runs < 1 or args.builds < 1:
        ap.error("--runs and --builds must be at least 1")
    servers = []
    for s in args.servers:
        name, sep, path = s.partition("=")
        if not sep or not name or not path:
            ap.error(f"{s!r}: expected name=path")
        if any(name == n for n, _ in servers):
            ap.error(f"{name!r}: named twice")
        servers.append((name, os.path.abspath(path)))
    env = dict(os.environ, TEXSAT_BS_PAGES=args.pages)
    sides = (4096, 1024) if args.order == "mixed" else (1024,)
    runs = {name: [] for name, _ in servers}
    for k in range(args.runs):
        jobs = requests(args.order, args.builds, k)
        turn = servers[k % len(servers):] + servers[:k % len(servers)]
        for name, path in turn:
            got = run(path, jobs, args.cpu, env)
            med = {job: statistics.median(v) for job, v in got.items()}
            runs[name].append({s: (med[("tiled", s)], med[("build", s)], med.get(("floor", s)))
                               for s in sides})
    for s in sides:
        print(f"{args.order}, {s}^2, {args.runs} runs of {args.builds}, pages {args.pages}: "
              "medians over the runs, ns per texel; tiled/flat the median of the runs' ratios")
        for name, _ in servers:
            r = [x[s] for x in runs[name]]
            ratios = [t / b for t, b, _ in r]
            floor = "" if r[0][2] is None else f"floor {statistics.median(f for *_, f in r):.3f}, "
            print(f"  {name}: {floor}flat (build) {statistics.median(b for _, b, _ in r):.3f}, "
                  f"tiled {statistics.median(t for t, _, _ in r):.3f}, "
                  f"tiled/flat {statistics.median(ratios):.2f} "
                  f"[{' '.join(f'{x:.2f}' for x in ratios)}]")
        first = servers[0][0]
        for name, _ in servers[1:]:
            for what, i in (("tiled", 0), ("floor", 2)):
                if runs[name][0][s][i] is None:
                    continue
                rel = [x[s][i] / y[s][i] for x, y in zip(runs[name], runs[first])]
                print(f"  {name} {what} / {first} {what}: {statistics.median(rel):.3f} "
                      f"[{' '.join(f'{x:.2f}' for x in rel)}]")


if __name__ == "__main__":
    main()
