#!/usr/bin/env python3
"""Executed instructions per call, from a QEMU exec log of the `texsat-count` firmware.

    count_insns.py ELF LOG --llvm-bin DIR [--reps 11] [--texels 4096] [--mip]

The log comes from `qemu-system-arm -singlestep -d exec,nochain`: one TB per instruction, one
`Trace` line per executed TB, whose second bracketed field is the PC. The firmware (src/count.rs)
calls per entry point: a mark, the call once, a mark, the call REPS times, a mark. So the regions
between consecutive marks come in triples (setup since the last mark, 1 call, REPS calls) and
(count(REPS) - count(1)) / (REPS - 1) is the per-call count without the setup; the baseline
entry (an empty wrapper of the same shape) is subtracted from the others.
"""
import argparse
import shutil
import re
import subprocess
import sys

# (key, label, key of the hand-written baseline measured for the same behaviour or None), in the
# order src/count.rs measures them. Keys starting with `hand_` are baselines, shown beside texsat's.
ENTRIES = [
    ("baseline", "harness overhead per call (empty wrapper: loop, `bl`, `bx lr`, `black_box` of the arguments)", None),
    ("int_border", "1. `Sat::box_sum_int` Border, interior box (4 reads)", "hand_int_border"),
    ("hand_int_border", "", None),
    ("inside", "1b. `Sat::box_sum_inside`, a box known inside (4 reads, no edge handling)", "hand_inside"),
    ("hand_inside", "", None),
    ("stable_border", "2. `Sat::box_sum` Stable Border, interior box", "hand_border"),
    ("hand_border", "", None),
    ("stable_repeat_first", "3a. `Sat::box_sum` Stable Repeat, inside the first period", None),
    ("stable_repeat_in", "3b. `Sat::box_sum` Stable Repeat, inside one period (not the first)", "hand_repeat_in"),
    ("hand_repeat_in", "", None),
    ("stable_repeat_cross", "4. `Sat::box_sum` Stable Repeat, crossing the right edge", None),
    ("mean_rounded", "`BoxSum::mean_rounded(0, 8, ..)` alone", "hand_mean"),
    ("hand_mean", "", None),
    ("stable_border_mean", "5. 2 + `BoxSum::mean_rounded(0, 8, ..)`", "hand_border_mean"),
    ("hand_border_mean", "", None),
    ("sat_build", "6. `Sat::build`", "hand_build"),
    ("hand_build", "", None),
    ("tiled_int_border", "7a. `Tiled` 8x8 tiles `box_sum_int` Border (4 corners)", None),
    ("tiled_stable_border", "7b. `Tiled` 8x8 tiles `box_sum` Stable Border", None),
]
MIP_ENTRIES = [
    ("mip_trilinear", "8a. `MipPyramid::trilinear` Border (20.25 x 15.25 box)", None),
    ("mip_trilinear_repeat", "8b. `MipPyramid::trilinear` Repeat (same box, 2nd period)", None),
]

TRACE = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/")


def symbol_addr(llvm_bin, elf, name):
    out = subprocess.run([f"{llvm_bin}/llvm-nm", elf], capture_output=True, text=True, check=True)
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == name:
            return int(parts[0], 16) & ~1
    sys.exit(f"count_insns: symbol {name} not found in {elf}")


def symbols(llvm_bin, elf):
    out = subprocess.run(
        [f"{llvm_bin}/llvm-nm", "-C", "--defined-only", "--numeric-sort", elf],
        capture_output=True,
        text=True,
        check=True,
    )
    syms = []
    for line in out.stdout.splitlines():
        parts = line.split(None, 2)
        if len(parts) == 3 and parts[1] in "tTwW":
            syms.append((int(parts[0], 16) & ~1, parts[2]))
    return syms


def profile(a, entries, pcs):
    """Instructions per call in each function, from the REPS region of each entry point."""
    import bisect
    from collections import Counter

    syms = symbols(a.llvm_bin, a.elf)
    addrs = [s[0] for s in syms]
    for i, (key, label, _) in enumerate(entries):
        c = Counter()
        for pc in pcs[3 * i + 2]:
            j = bisect.bisect_right(addrs, pc) - 1
            c[syms[j][1] if j >= 0 else "?"] += 1
        print(f"profile {key} ({a.reps} calls, instructions per call by function):", file=sys.stderr)
        for name, n in c.most_common():
            name = re.sub(r"::<.*", "::<..>", name) if len(name) > 110 else name
            print(f"  {n / a.reps:10.1f}  {name}", file=sys.stderr)


def lines(a, entries, pcs, key):
    """Instructions per call by source line (innermost inlined frame) for one entry point."""
    from collections import Counter

    for i, (k, _label, _) in enumerate(entries):
        if k != key:
            continue
        c = Counter(pcs[3 * i + 2])
        addrs = sorted(c)
        # llvm-symbolizer (the system's, or the toolchain's llvm-tools if it ships one): for
        # each address its inlined frames, innermost first, a blank line after each address.
        sym = shutil.which("llvm-symbolizer") or f"{a.llvm_bin}/llvm-symbolizer"
        out = subprocess.run(
            [sym, f"--obj={a.elf}"],
            input="\n".join(hex(pc) for pc in addrs),
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip().split("\n\n")
        per_line = Counter()
        for pc, frames in zip(addrs, out):
            f = frames.splitlines()
            loc = f[1] if len(f) > 1 else "?"
            loc = re.sub(r"^.*/(src|library)/", r"\1/", loc)
            per_line[loc] += c[pc]
        print(f"lines {key} ({a.reps} calls, instructions per call by source line):", file=sys.stderr)
        for loc, n in per_line.most_common(60):
            print(f"  {n / a.reps:8.1f}  {loc}", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("elf")
    ap.add_argument("log")
    ap.add_argument("--llvm-bin", required=True)
    ap.add_argument("--reps", type=int, default=11)
    ap.add_argument("--texels", type=int, default=64 * 64)
    ap.add_argument("--mip", action="store_true")
    ap.add_argument(
        "--lines",
        metavar="ENTRY",
        help="also print the instructions per call of this entry point by source line",
    )
    ap.add_argument("--raw", action="store_true", help="also print the raw region counts")
    ap.add_argument(
        "--profile",
        action="store_true",
        help="also print, per entry point, the instructions per call in each function (symbol)",
    )
    a = ap.parse_args()

    mark = symbol_addr(a.llvm_bin, a.elf, "texsat_count_mark")
    regions = []  # instruction counts between consecutive mark entries
    pcs = []  # per region: the PCs executed (only with --profile)
    cur = None
    with open(a.log, errors="replace") as f:
        for line in f:
            m = TRACE.match(line)
            if not m:
                continue
            pc = int(m.group(1), 16)
            if pc == mark:
                if cur is not None:
                    regions.append(cur)
                cur = 0
                if a.profile or a.lines:
                    pcs.append([])
            elif cur is not None:
                cur += 1
                if a.profile or a.lines:
                    pcs[-1].append(pc)
    entries = ENTRIES + (MIP_ENTRIES if a.mip else [])
    regions.insert(0, 0)  # the first setup region precedes the first mark
    pcs.insert(0, [])  # the same for the captured PCs: pcs[3 i + 2] is entry i's REPS region
    if len(regions) != 3 * len(entries):
        sys.exit(
            f"count_insns: expected {3 * len(entries)} regions between marks, found {len(regions)} "
            "(did the firmware run to the end? is the log complete?)"
        )
    per_call = {}
    for i, (key, _, _) in enumerate(entries):
        c1, cr = regions[3 * i + 1], regions[3 * i + 2]
        d = cr - c1
        if d % (a.reps - 1):
            print(f"warning: {key}: {cr} - {c1} not divisible by {a.reps - 1}", file=sys.stderr)
        per_call[key] = d / (a.reps - 1)
        if a.raw:
            print(f"raw {key}: 1 call region {c1}, {a.reps} calls region {cr}", file=sys.stderr)
    if a.profile:
        profile(a, entries, pcs)
    if a.lines:
        lines(a, entries, pcs, a.lines)
    base = per_call["baseline"]
    print("| entry point | texsat, instructions per call | hand-written, same behaviour |")
    print("|---|---:|---:|")
    for key, label, hand in entries:
        if key.startswith("hand_"):
            continue
        v = per_call[key] - base
        h = f"{per_call[hand] - base:g}" if hand else ""
        if key == "baseline":
            print(f"| {label} | {per_call[key]:g} (subtracted from the rows below) | |")
        elif key == "sat_build":
            hv = per_call[hand] - base
            print(
                f"| {label}, 64x64 u32 table: per build / **per entry** | {v:g} / **{v / a.texels:.2f}** "
                f"| {hv:g} / **{hv / a.texels:.2f}** |"
            )
        else:
            print(f"| {label} | {v:g} | {h} |")


if __name__ == "__main__":
    main()
