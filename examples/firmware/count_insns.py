#!/usr/bin/env python3
"""Executed instructions per call, from a QEMU run of the `texsat-count` (or `texsat-demo`) firmware.

    count_insns.py ELF (--plugin-log LOG | --exec-log LOG) --llvm-bin DIR [--reps 10]
                   [--texels 4096] [--mip] [--demo] [--regions-out FILE]

Two sources, the same figures (count-insns.sh COUNT_METHOD=both checks that they agree to the
instruction on every region):
- `--plugin-log`: the output of the TCG plugin plugin/insn_count.c, a `mark ADDR TOTAL` line
  each time the marker's first instruction runs (TOTAL: instructions executed so far, markers
  not included) and, with the plugin's `pcs=on`, `pc ADDR N` lines before each mark line;
- `--exec-log`: the log of `qemu-system-arm -singlestep -d exec,nochain`: one TB per
  instruction, one `Trace` line per executed TB, whose second bracketed field is the PC.
The harness (src/count.rs) calls per entry point one out-of-line loop twice: a mark, the call
REPS times, a mark; then a mark, the call 2 REPS times, a mark. So the regions between
consecutive marks come in fours (setup since the last mark, REPS calls, the gap between the
loops, 2 REPS calls) and (count(2 REPS) - count(REPS)) / REPS is the per-call count, exactly
(the two regions run the same code and differ by REPS calls: this script fails if the
difference is not a multiple of REPS); the baseline entry (an empty wrapper of the same shape)
is subtracted from the others. First comes the self-check `texsat_count_selftest` (assembly,
three marks): its two regions must hold exactly the instructions its disassembly shows, else
this script fails.
`--demo` prints run.sh's DEMO_COUNT table instead (marker `texsat_demo_mark`).
"""
import argparse
import re
import shutil
import subprocess
import sys
from collections import Counter

# (key, label, key of the hand-written baseline measured for the same behaviour or None), in the
# order src/count.rs measures them. Keys starting with `hand_` are baselines, shown beside texsat's.
ENTRIES = [
    ("selftest", "", None),
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
    ("within_in", "3c. `Sat::box_sum` Stable `RepeatWithinPeriod` (a plan's boxes at most the texture), as 3b", "hand_repeat_in"),
    ("within_cross", "4b. `Sat::box_sum` Stable `RepeatWithinPeriod`, crossing the right edge, as 4", None),
    ("mean_rounded", "`BoxSum::mean_rounded(0, 8, ..)` alone", "hand_mean"),
    ("hand_mean", "", None),
    ("mean_rounded_u32", "`BoxSum::mean_rounded_u32(0, 8, ..)` alone (a plan's 32-bit mean)", "hand_mean"),
    ("stable_border_mean", "5. 2 + `BoxSum::mean_rounded(0, 8, ..)`", "hand_border_mean"),
    ("hand_border_mean", "", None),
    ("sat_build", "6. `Sat::build`", "hand_build"),
    ("hand_build", "", None),
    ("stream_build", "6b. `RowStreamBuilder::push_row_into`, row by row", "hand_build"),
    ("modular_build", "6c. `Modular::build`, k = 20", None),
    ("modular_build_u16", "6d. `Modular::build` into `u16` values, k = 12", None),
    ("sat_build_u16", "6e. `Sat::build`", "hand_build_u16"),
    ("hand_build_u16", "", None),
    ("tiled_int_border", "7a. `Tiled` 8x8 tiles `box_sum_int` Border (4 corners)", None),
    ("tiled_stable_border", "7b. `Tiled` 8x8 tiles `box_sum` Stable Border", None),
]
# The builds beside a hand-written build: the table printed and its entries (None: --texels;
# 256: count.rs's SMALL, the 64 x 4 u16 table).
BUILDS = {
    "sat_build": ("64x64 u32", None),
    "stream_build": ("64x64 u32", None),
    "sat_build_u16": ("64x4 u16", 256),
}
MIP_ENTRIES = [
    ("mip_trilinear", "8a. `MipPyramid::trilinear` Border (20.25 x 15.25 box)", None),
    ("mip_trilinear_repeat", "8b. `MipPyramid::trilinear` Repeat (same box, 2nd period)", None),
]

TRACE = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/")
INSN = re.compile(r"^\s+([0-9a-f]+):\s+(\S+)\s*(.*)$")
BRANCH = re.compile(r"^(b|bl|blx|bx|cbn?z|tb[bh]|it[te]*|b(eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le))(\.[wn])?$")


def symbol_addr(llvm_bin, elf, name):
    out = subprocess.run([f"{llvm_bin}/llvm-nm", elf], capture_output=True, text=True, check=True)
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == name:
            return int(parts[0], 16) & ~1
    sys.exit(f"count_insns: symbol {name} not found in {elf}")


def read_exec_log(path, mark, want_pcs):
    """Instructions (and, if wanted, the PCs) between consecutive marks, from a -singlestep exec log."""
    between, pcs = [], []
    cur, cur_pcs = None, None
    with open(path, errors="replace") as f:
        for line in f:
            m = TRACE.match(line)
            if not m:
                continue
            pc = int(m.group(1), 16)
            if pc == mark:
                if cur is not None:
                    between.append(cur)
                    pcs.append(cur_pcs)
                cur, cur_pcs = 0, Counter()
            elif cur is not None:
                cur += 1
                if want_pcs:
                    cur_pcs[pc] += 1
    return between, pcs


def read_plugin_log(path, mark, want_pcs):
    """The same, from the plugin's output (`mark ADDR TOTAL` lines, `pc ADDR N` with pcs=on)."""
    between, pcs = [], []
    last, cur_pcs, header, ended = None, Counter(), False, False
    with open(path) as f:
        for line in f:
            w = line.split()
            if w[:2] == ["insn_count", "1"]:
                header = True
            elif w[0] == "pc":
                cur_pcs[int(w[1], 16)] += int(w[2])
            elif w[0] == "mark" and int(w[1], 16) == mark:
                total = int(w[2])
                if last is not None:
                    between.append(total - last)
                    pcs.append(cur_pcs)
                last, cur_pcs = total, Counter()
            elif w[0] == "end":
                ended = True
    if not header or not ended:
        sys.exit(f"count_insns: {path} is not a complete insn_count plugin log (header {header}, end {ended})")
    if want_pcs and not any(pcs):
        sys.exit("count_insns: no `pc` lines in the plugin log: run the plugin with pcs=on")
    return between, pcs


def disassembly(llvm_bin, elf, names):
    """Instructions of each named function: {name: [(address, mnemonic, operands)]}."""
    out = subprocess.run(
        [f"{llvm_bin}/llvm-objdump", "-d", "--no-show-raw-insn", f"--disassemble-symbols={','.join(names)}", elf],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    funcs, cur = {}, None
    for line in out.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.+)>:$", line)
        if m:
            cur = funcs.setdefault(m.group(1), [])
            continue
        m = INSN.match(line)
        if m and cur is not None:
            cur.append((int(m.group(1), 16), m.group(2), m.group(3)))
    return funcs


def selftest_expected(llvm_bin, elf):
    """The instruction counts of the self-check's two regions, from the disassembly alone.

    A region starts after the first instruction of `texsat_count_mark` (the marker itself, not
    counted) and ends with the `bl` to the next mark: the marker's other instructions (it is
    straight-line code: no branch before its return), then the self-check's instructions after
    one `bl texsat_count_mark` up to and including the next.
    """
    f = disassembly(llvm_bin, elf, ["texsat_count_mark", "texsat_count_selftest"])
    mark, test = f.get("texsat_count_mark"), f.get("texsat_count_selftest")
    if not mark or not test:
        sys.exit("count_insns: texsat_count_mark or texsat_count_selftest not found in the disassembly")
    if any(BRANCH.match(mn) or re.search(r"\bpc\b", ops) for _, mn, ops in mark[:-1]):
        sys.exit(f"count_insns: texsat_count_mark is not straight-line code: {mark}")
    calls = [i for i, (_, mn, ops) in enumerate(test) if mn == "bl" and "<texsat_count_mark>" in ops]
    if len(calls) != 3:
        sys.exit(f"count_insns: expected 3 calls of texsat_count_mark in texsat_count_selftest, found {len(calls)}")
    return [len(mark) - 1 + (b - a) for a, b in zip(calls, calls[1:])]


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


def regions_of(i):
    """Indices of entry i's REPS-call and 2 REPS-call regions (i >= 1: the self-check, entry 0,
    has three marks, every other entry four)."""
    base = 3 + 4 * (i - 1)
    return base + 1, base + 3


def per_call_pcs(pcs, i):
    """Entry i's executed count per instruction address for REPS calls: its 2 REPS region less
    its REPS region (the same code: what both ran once, the loop's setup, cancels)."""
    r1, r2 = regions_of(i)
    c = Counter(pcs[r2])
    c.subtract(pcs[r1])
    return Counter({pc: n for pc, n in c.items() if n > 0})


def profile(a, entries, pcs):
    """Instructions per call in each function (the difference of each entry point's regions)."""
    import bisect

    syms = symbols(a.llvm_bin, a.elf)
    addrs = [s[0] for s in syms]
    for i, (key, label, _) in enumerate(entries):
        if key == "selftest":
            continue
        c = Counter()
        for pc, n in per_call_pcs(pcs, i).items():
            j = bisect.bisect_right(addrs, pc) - 1
            c[syms[j][1] if j >= 0 else "?"] += n
        print(f"profile {key} ({a.reps} calls, instructions per call by function):", file=sys.stderr)
        for name, n in c.most_common():
            name = re.sub(r"::<.*", "::<..>", name) if len(name) > 110 else name
            print(f"  {n / a.reps:10.1f}  {name}", file=sys.stderr)


def annotate(a, entries, pcs, key):
    """The disassembly of every function one entry point runs, each instruction with its executed
    count per call (a blank count: not executed), for finding where its instructions go."""
    import bisect

    syms = symbols(a.llvm_bin, a.elf)
    addrs = [s[0] for s in syms]
    for i, (k, _label, _) in enumerate(entries):
        if k != key:
            continue
        c = per_call_pcs(pcs, i)
        # The whole text once (generic names hold commas, which --disassemble-symbols splits
        # on), each instruction filed under its function by address.
        out = subprocess.run(
            [f"{a.llvm_bin}/llvm-objdump", "-d", "--no-show-raw-insn", a.elf],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        funcs = {}
        for line in out.splitlines():
            m = INSN.match(line)
            if m:
                pc = int(m.group(1), 16)
                j = bisect.bisect_right(addrs, pc) - 1
                if j >= 0:
                    funcs.setdefault(syms[j][1], []).append((pc, m.group(2), m.group(3)))
        ran = {syms[bisect.bisect_right(addrs, pc) - 1][1] for pc in c}
        for name in sorted(ran):
            insns = funcs.get(name, [])
            total = sum(c[pc] for pc, _, _ in insns)
            print(f"annotate {key}: {name}: {total / a.reps:g} per call", file=sys.stderr)
            for pc, mnem, ops in insns:
                n = f"{c[pc] / a.reps:g}" if c[pc] else ""
                print(f"  {n:>6}  {pc:6x}  {mnem:8} {ops}", file=sys.stderr)


def lines(a, entries, pcs, key):
    """Instructions per call by source line (innermost inlined frame) for one entry point."""
    for i, (k, _label, _) in enumerate(entries):
        if k != key:
            continue
        c = per_call_pcs(pcs, i)
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


def demo_table(between):
    """run.sh's DEMO_COUNT table: per plan, build (per entry) and render (per sample)."""
    entries, samples = 64 * 64, 32 * 24
    plans = ["small", "repeat", "tiled", "mip (for comparison)"]
    # Per plan: a mark, the build, a mark, the render, a mark, the report (the last plan's report
    # ends at exit, with no mark after it).
    if len(between) != 3 * len(plans) - 1:
        sys.exit(f"count_insns: expected {3 * len(plans) - 1} regions between demo marks, found {len(between)}")
    print("| plan | build: instructions per entry | render: instructions per sample (footprint, lookup, mean, checksum) |")
    print("|---|---:|---:|")
    for i, name in enumerate(plans):
        b, r = between[3 * i], between[3 * i + 1]
        print(f"| {name} | {b / entries:.2f} | {r / samples:.1f} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("elf")
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--plugin-log", metavar="LOG", help="output of the insn_count TCG plugin")
    src.add_argument("--exec-log", metavar="LOG", help="log of qemu-system-arm -singlestep -d exec,nochain")
    ap.add_argument("--llvm-bin", required=True)
    ap.add_argument("--reps", type=int, default=10)
    ap.add_argument("--texels", type=int, default=64 * 64)
    ap.add_argument("--mip", action="store_true")
    ap.add_argument("--demo", action="store_true", help="the texsat-demo firmware: print run.sh's table")
    ap.add_argument(
        "--regions-out",
        metavar="FILE",
        help="also write the instruction count of every region between marks, one a line",
    )
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
    ap.add_argument(
        "--annotate",
        metavar="KEY",
        help="also print the disassembly of what entry point KEY runs, with counts per call",
    )
    a = ap.parse_args()

    mark = symbol_addr(a.llvm_bin, a.elf, "texsat_demo_mark" if a.demo else "texsat_count_mark")
    want_pcs = bool(a.profile or a.lines or a.annotate)
    if a.plugin_log:
        between, pcs = read_plugin_log(a.plugin_log, mark, want_pcs)
    else:
        between, pcs = read_exec_log(a.exec_log, mark, want_pcs)
    if a.regions_out:
        with open(a.regions_out, "w") as f:
            f.writelines(f"{n}\n" for n in between)
    if a.demo:
        demo_table(between)
        return

    entries = ENTRIES + (MIP_ENTRIES if a.mip else [])
    # The first setup region precedes the first mark: regions[1] and regions[2] are the
    # self-check's, then regions_of(i) entry i's REPS-call and 2 REPS-call regions (pcs[...] the
    # same for their PCs).
    regions = [0] + between
    pcs = [Counter()] + pcs
    want = 3 + 4 * (len(entries) - 1)
    if len(regions) != want:
        sys.exit(
            f"count_insns: expected {want} regions between marks, found {len(regions)} "
            "(did the firmware run to the end? is the log complete?)"
        )
    expected = selftest_expected(a.llvm_bin, a.elf)
    if regions[1:3] != expected:
        sys.exit(
            f"count_insns: SELF-CHECK FAILED: the self-check's regions count {regions[1:3]} instructions, "
            f"its disassembly {expected}"
        )
    print(
        f"count_insns: self-check passed: {regions[1]} and {regions[2]} instructions, as disassembled",
        file=sys.stderr,
    )
    per_call = {}
    for i, (key, _, _) in enumerate(entries):
        if key == "selftest":
            continue
        r1, r2 = regions_of(i)
        c1, c2 = regions[r1], regions[r2]
        d = c2 - c1
        if d % a.reps:
            sys.exit(
                f"count_insns: {key}: the {2 * a.reps}-call region ({c2}) less the {a.reps}-call "
                f"region ({c1}) is not a multiple of {a.reps}: the two regions did not run the same code"
            )
        per_call[key] = d // a.reps
        if a.raw:
            print(f"raw {key}: {a.reps} calls region {c1}, {2 * a.reps} calls region {c2}", file=sys.stderr)
    if a.profile:
        profile(a, entries, pcs)
    if a.lines:
        lines(a, entries, pcs, a.lines)
    if a.annotate:
        annotate(a, entries, pcs, a.annotate)
    base = per_call["baseline"]
    print("| entry point | texsat, instructions per call | hand-written, same behaviour |")
    print("|---|---:|---:|")
    for key, label, hand in entries:
        if key.startswith("hand_") or key == "selftest":
            continue
        v = per_call[key] - base
        h = f"{per_call[hand] - base:g}" if hand else ""
        if key == "baseline":
            print(f"| {label} | {per_call[key]:g} (subtracted from the rows below) | |")
        elif key in BUILDS:
            table, n = BUILDS[key]
            n = n or a.texels
            hv = per_call[hand] - base
            print(
                f"| {label}, {table} table: per build / **per entry** | {v:g} / **{v / n:.2f}** "
                f"| {hv:g} / **{hv / n:.2f}** |"
            )
        elif key in ("modular_build", "modular_build_u16"):
            print(f"| {label}, 64x64: per build / **per entry** | {v:g} / **{v / a.texels:.2f}** | |")
        else:
            print(f"| {label} | {v:g} | {h} |")


if __name__ == "__main__":
    main()
