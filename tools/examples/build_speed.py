#!/usr/bin/env python3
"""Build speed of texsat against the widen-copy floor and OpenCV, side by side in one run (issue 13).

Builds `tools/examples/build_speed.rs` in up to three variants, each in its own target directory
under $CARGO_TARGET_DIR (default `target`)/build-speed/:

  portable  no `simd` feature, default target (x86-64 baseline): the forbid(unsafe_code) build
  simd      `--features simd`, default target: the widest kernel the CPU runs, chosen at run time
            (the floor, compiled by LLVM, is baseline SSE2 code)
  native    `--features simd` with RUSTFLAGS="-C target-cpu=native": the same kernel; the floor
            and the rest of the code compiled for this CPU (AVX-512 here)

(each also with `parallel`, for the all-cores build)

starts each as a server, and times every (variant, method, side) and OpenCV's `cv2.integral`
(32-bit signed sums into a reused output array, (w+1) x (h+1)) in interleaved rounds: each round
runs every measurement once, in a shuffled order. Reports medians in ns per texel, each figure's
ratio to its variant's floor and to OpenCV, and how loaded the machine was (/proc/loadavg and the
time the processes spent waiting for a CPU, from /proc/<pid>/schedstat).

    pip install opencv-python-headless numpy
    python3 tools/examples/build_speed.py                     # all variants, 1024^2 and 4096^2
    python3 tools/examples/build_speed.py --variants native --rounds 41 --methods floor,build
    python3 tools/examples/build_speed.py --json out.json     # also the raw samples

Before and after a change, in one run: build the example at each commit, copy the binaries, and
pass them as servers instead of variants (the ratios to the first server's same method are then
printed as well):

    python3 tools/examples/build_speed.py --servers before=/tmp/a,after=/tmp/b \
        --methods build,tiled --rounds 41 --no-opencv

Every method's table is compared with `Sat::build`'s before it is timed (in the server), and
OpenCV's with the texsat table (here).

Pages: numpy advises transparent huge pages (MADV_HUGEPAGE) for arrays of 4 MiB and more, so
OpenCV's output (and at 4096^2 its image) lies in 2 MiB pages wherever the kernel's THP setting
is `madvise` or `always`, while a Rust `Vec` lies in 4 KiB pages under `madvise`. By default
(`--pages 4k`) this script turns numpy's advice off, so that both sides run on the same pages;
`--pages thp` leaves it on and has the servers advise their outputs (all of them: a tiled
layout of 1,024^2 is 2.3 MiB) and their textures of 4 MiB and more the same way
(`TEXSAT_BS_PAGES=thp`). The report prints how much of each side's memory the
kernel gave huge pages (/proc/<pid>/smaps).

Texture placement: `--texture-page-offset B` puts each server's texture at byte B of a 4 KiB
page (so every row of 4,096 texels starts there too; `imageproc` keeps its own copy, and
OpenCV's image is numpy's); without it the texture lies where its storage starts (a page
boundary for the `thp` maps, 16 bytes past one for glibc's large heap blocks). On the Zen 3
machine of 2026-12-07 a tiled build of 4,096^2 with its rows starting mid-page (B = 2048) took
1.07x to 1.13x the time of one with them on a page boundary, back to back in one server, and
1.33x the flat build in one run of this script against 1.19x in another without the option;
the flat build did not move back to back (the others were not measured so), nor the tiled
build of 1,024^2 (docs/benchmarks.md, twenty-second session).

On a VM whose virtual CPUs are not equally quiet, `--cpu N` runs everything on CPU N: on the
2-vCPU machine of 2026-11-28 a server that the scheduler kept on CPU 0 ran the same code up to
1.4x slower than one on CPU 1 (median of the best of 5 builds), which made binaries and
variants differ by more than the changes they were compared for.
"""

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

VARIANTS = {
    "portable": (["--features", "parallel"], ""),
    "simd": (["--features", "simd,parallel"], ""),
    "native": (["--features", "simd,parallel"], "-C target-cpu=native"),
}


def build(variant):
    features, rustflags = VARIANTS[variant]
    base = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    target = os.path.join(base, "build-speed", variant)
    env = dict(os.environ, CARGO_TARGET_DIR=target)
    if rustflags:
        env["RUSTFLAGS"] = rustflags
    else:
        env.pop("RUSTFLAGS", None)
    cmd = ["cargo", "build", "--release", "--locked", "-p", "texsat-tools", "--example",
           "build_speed"] + features
    print(f"[{variant}] {' '.join(cmd)}" + (f"  (RUSTFLAGS={rustflags!r})" if rustflags else ""),
          file=sys.stderr)
    subprocess.run(cmd, cwd=ROOT, env=env, check=True)
    return os.path.join(target, "release", "examples", "build_speed")


class Server:
    def __init__(self, variant, path):
        self.variant = variant
        self.proc = subprocess.Popen([path], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, bufsize=1)
        self.kernel = self.ask("kernel")
        self.methods = self.ask("methods").split()

    def ask(self, line):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        answer = self.proc.stdout.readline()
        if not answer:
            raise RuntimeError(f"{self.variant}: server exited on {line!r}")
        return answer.strip()

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def schedstat(pid):
    """(ns on a CPU, ns waiting for a CPU) of a process, or None."""
    try:
        with open(f"/proc/{pid}/schedstat") as f:
            run, wait, _ = f.read().split()
            return int(run), int(wait)
    except OSError:
        return None


def huge_kb(pid, ranges=None):
    """(kB in huge pages, kB resident) of a process's maps overlapping `ranges`
    ([(start, end)] addresses; all of it if None), from /proc/<pid>/smaps; None if unreadable."""
    huge = rss = 0
    inside = False
    try:
        with open(f"/proc/{pid}/smaps") as f:
            for line in f:
                head = line.split(" ", 1)[0]
                if "-" in head and not head.endswith(":"):
                    lo, hi = (int(x, 16) for x in head.split("-"))
                    inside = ranges is None or any(lo < b and hi > a for a, b in ranges)
                elif inside and head == "AnonHugePages:":
                    huge += int(line.split()[1])
                elif inside and head == "Rss:":
                    rss += int(line.split()[1])
    except OSError:
        return None
    return huge, rss


def loadavg():
    try:
        with open("/proc/loadavg") as f:
            return f.read().strip()
    except OSError:
        return "n/a"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--variants", default="portable,simd,native")
    ap.add_argument("--methods", default="floor,build,checked,stream,stream_nocopy,stream_into,tiled,modular,imageproc,strips_seq,parallel",
                    help="server methods to time (comma-separated)")
    ap.add_argument("--sides", default="1024,4096")
    ap.add_argument("--rounds", type=int, default=21, help="interleaved rounds (medians over these)")
    ap.add_argument("--rounds-large", type=int, default=None,
                    help="rounds for sides above 2048 (default: --rounds)")
    ap.add_argument("--no-opencv", action="store_true")
    ap.add_argument("--json", help="write medians and raw samples here")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--servers", help="NAME=PATH,... of prebuilt build_speed binaries to time "
                    "instead of building --variants (e.g. two commits' binaries)")
    ap.add_argument("--pages", choices=["4k", "thp"], default="4k",
                    help="4k: numpy's huge-page advice off, the servers on heap memory (both "
                    "sides on 4 KiB pages); thp: numpy's advice on and the servers' outputs and "
                    "textures of 4 MiB and more advised the same way (see Pages above)")
    ap.add_argument("--texture-page-offset", type=int, default=None,
                    help="place each server's texture at this byte (0 to 4095) of a 4 KiB "
                    "page (TEXSAT_BS_TEXTURE_PAGE_OFFSET; OpenCV's image is numpy's, wherever "
                    "numpy puts it)")
    ap.add_argument("--cpu", type=int, default=None,
                    help="run this script, OpenCV and every server on this one CPU (they take "
                    "turns: one measurement at a time), so that all figures share one core")
    args = ap.parse_args()
    if args.texture_page_offset is not None and not 0 <= args.texture_page_offset < 4096:
        sys.exit("--texture-page-offset: 0 to 4095")

    sides = [int(s) for s in args.sides.split(",")]
    methods = args.methods.split(",")
    if args.servers:
        paths = [kv.split("=", 1) for kv in args.servers.split(",")]
    else:
        paths = [(v, build(v)) for v in args.variants.split(",")]
    if args.cpu is not None:
        # After the builds (cargo keeps every CPU); inherited by the servers started below.
        os.sched_setaffinity(0, {args.cpu})
    os.environ["TEXSAT_BS_PAGES"] = args.pages  # inherited by the servers
    # Inherited by the servers; one set in the caller's shell is not (the report names the
    # placement the servers got).
    if args.texture_page_offset is not None:
        os.environ["TEXSAT_BS_TEXTURE_PAGE_OFFSET"] = str(args.texture_page_offset)
    else:
        os.environ.pop("TEXSAT_BS_TEXTURE_PAGE_OFFSET", None)
    servers = [Server(name, path) for name, path in paths]
    for s in servers:
        unknown = set(methods) - set(s.methods)
        if unknown:
            sys.exit(f"{s.variant}: unknown methods {sorted(unknown)}")

    cv2 = np = None
    if not args.no_opencv:
        try:
            import cv2  # noqa: F811
            import numpy as np  # noqa: F811
        except ImportError:
            sys.exit("OpenCV missing: pip install opencv-python-headless numpy (or --no-opencv)")
        cv2.setNumThreads(1)  # integral is single-threaded anyway; keep it so
        advice = getattr(getattr(np, "_core", getattr(np, "core", None)), "multiarray", None)
        if hasattr(advice, "_set_madvise_hugepage"):
            advice._set_madvise_hugepage(args.pages == "thp")
        else:
            print(f"numpy {np.__version__} cannot set its huge-page advice: OpenCV's arrays "
                  "follow its default (see the pages line)", file=sys.stderr)

    # The same texture as the server's: it writes it to a file on request.
    def texture(n):
        path = os.path.join(os.path.dirname(servers[0].ask("path")), f"texture-{n}.u8")
        assert servers[0].ask(f"dump {n} {path}") == "ok"
        with open(path, "rb") as f:
            data = f.read()
        os.remove(path)
        assert len(data) == n * n
        return data

    images, outs = {}, {}
    if cv2 is not None:
        for n in sides:
            img = np.frombuffer(texture(n), dtype=np.uint8).reshape(n, n).copy()
            out = np.zeros((n + 1, n + 1), dtype=np.int32)
            cv2.integral(img, out, sdepth=cv2.CV_32S)
            # Exact against texsat's inclusive table: S(x, y) = out[y][x], spot-checked here on
            # the last row and column and a diagonal (the server checks its own methods fully).
            ref = out.astype(np.int64)
            col = np.cumsum(np.cumsum(img.astype(np.int64), axis=0), axis=1)
            assert (ref[1:, 1:] == col).all(), f"cv2.integral {n}: not the summed-area table"
            images[n], outs[n] = img, out

    jobs = [(s, m, n) for s in servers for m in methods for n in sides]
    if cv2 is not None:
        jobs += [(None, "cv2.integral", n) for n in sides]
    samples = {(s.variant if s else "opencv", m, n): [] for s, m, n in jobs}

    def run(job):
        s, m, n = job
        if s is None:
            t0 = time.perf_counter_ns()
            cv2.integral(images[n], outs[n], sdepth=cv2.CV_32S)
            return (time.perf_counter_ns() - t0) / (n * n)
        return float(s.ask(f"{m} {n}"))

    pids = [os.getpid()] + [s.proc.pid for s in servers]
    load0, sched0, wall0 = loadavg(), {p: schedstat(p) for p in pids}, time.monotonic_ns()
    for job in jobs:  # warm-up: page in storage, check every method's output once
        run(job)
    rng = random.Random(args.seed)
    for r in range(max(args.rounds, args.rounds_large or 0)):
        order = [j for j in jobs if j[2] <= 2048 and r < args.rounds
                 or j[2] > 2048 and r < (args.rounds_large or args.rounds)]
        rng.shuffle(order)
        for job in order:
            s, m, n = job
            samples[(s.variant if s else "opencv", m, n)].append(run(job))
    wall = time.monotonic_ns() - wall0
    load1, sched1 = loadavg(), {p: schedstat(p) for p in pids}
    # (who, kB in huge pages, kB of memory it is out of): a server's resident memory (its
    # untimed reference table and imageproc's image, on 4 KiB pages, included), the arrays' own
    # size for OpenCV (the maps around them hold the interpreter's memory too; whole maps are
    # counted, so its figure is an upper bound).
    pages = []
    for s in servers:
        p = huge_kb(s.proc.pid)
        pages.append((s.variant, p[0] if p else None, p[1] if p else None))
    if cv2 is not None:
        arrays = [a for n in sides for a in (images[n], outs[n])]
        p = huge_kb("self", [(a.ctypes.data, a.ctypes.data + a.nbytes) for a in arrays])
        total_kb = sum(a.nbytes for a in arrays) // 1024
        pages.append(("opencv's arrays", min(p[0], total_kb) if p else None, total_kb))
    for s in servers:
        s.close()

    med = {k: statistics.median(v) for k, v in samples.items()}
    print(f"\nkernels: " + ", ".join(f"{s.variant} = {s.kernel}" for s in servers))
    print(f"rounds: {args.rounds} (sides > 2048: {args.rounds_large or args.rounds}); "
          f"wall {wall / 1e9:.1f} s")
    print(f"loadavg before: {load0}; after: {load1}")
    print("cpus: " + (f"all on CPU {args.cpu}" if args.cpu is not None else "any (no --cpu)"))
    print("servers' textures: " + (f"at byte {args.texture_page_offset} of a 4 KiB page"
                                   if args.texture_page_offset is not None
                                   else "where their storage starts"))
    print(f"pages ({args.pages}), MiB in 2 MiB pages: " + "; ".join(
        f"{who} {h / 1024:.0f} of {t / 1024:.0f}" if h is not None else f"{who} n/a"
        for who, h, t in pages))
    for p in pids:
        a, b = sched0.get(p), sched1.get(p)
        if a and b:
            run_ns, wait_ns = b[0] - a[0], b[1] - a[1]
            who = "driver (python, opencv)" if p == os.getpid() else \
                next(s.variant for s in servers if s.proc.pid == p)
            print(f"schedstat {who}: on CPU {run_ns / 1e9:.2f} s, waiting for a CPU "
                  f"{wait_ns / 1e9:.3f} s ({100 * wait_ns / max(run_ns, 1):.1f}% of its CPU time)")

    print("\nmedian ns per texel (u8 -> u32); x floor = / the same variant's floor; "
          "x cv2 = / cv2.integral")
    header = "| variant | method | " + " | ".join(
        f"{n}^2 ns | x floor | x cv2" for n in sides) + " |"
    print(header)
    print("|" + "---|" * (2 + 3 * len(sides)))
    rows = [(s.variant, m) for s in servers for m in methods]
    if cv2 is not None:
        rows.append(("opencv", "cv2.integral"))
    for v, m in rows:
        cells = []
        for n in sides:
            x = med[(v, m, n)]
            fl = med.get((v, "floor", n))
            cv = med.get(("opencv", "cv2.integral", n))
            cells += [f"{x:.3f}", f"{x / fl:.2f}" if fl else "", f"{x / cv:.2f}" if cv else ""]
        print(f"| {v} | {m} | " + " | ".join(cells) + " |")
    # Paired ratios: the same round's two figures divided, then the median and quartiles over
    # the rounds (robust to the machine's drift between rounds).
    def paired(a, b):
        xs, ys = samples.get(a), samples.get(b)
        if not xs or not ys:
            return None
        r = sorted(x / y for x, y in zip(xs, ys))
        q = statistics.quantiles(r, n=4) if len(r) >= 2 else [r[0]] * 3
        return q[0], statistics.median(r), q[2]

    print("\npaired ratios, median over rounds [quartiles]; per side: / floor, / cv2.integral, "
          "/ the same variant's build (Sat::build)")
    for v, m in rows:
        if v == "opencv":
            continue
        cells = []
        for n in sides:
            for ref in [(v, "floor", n), ("opencv", "cv2.integral", n), (v, "build", n)]:
                pr = paired((v, m, n), ref)
                cells.append(f"{pr[1]:.2f} [{pr[0]:.2f}, {pr[2]:.2f}]" if pr else "")
        print(f"| {v} | {m} | " + " | ".join(cells) + " |")
    if args.servers and len(servers) > 1:
        first = servers[0].variant
        print(f"\npaired ratios to {first}'s same method, median over rounds [quartiles], per side")
        for s in servers[1:]:
            for m in methods:
                cells = []
                for n in sides:
                    pr = paired((s.variant, m, n), (first, m, n))
                    cells.append(f"{pr[1]:.3f} [{pr[0]:.2f}, {pr[2]:.2f}]" if pr else "")
                print(f"| {s.variant} / {first} | {m} | " + " | ".join(cells) + " |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"kernels": {s.variant: s.kernel for s in servers},
                       "pages": {"mode": args.pages,
                                 "huge_kb_of_kb": {who: [h, t] for who, h, t in pages}},
                       "texture_page_offset": args.texture_page_offset,
                       "loadavg": [load0, load1],
                       "medians": {f"{v}/{m}/{n}": x for (v, m, n), x in med.items()},
                       "samples": {f"{v}/{m}/{n}": x for (v, m, n), x in samples.items()}},
                      f, indent=1)


if __name__ == "__main__":
    main()
