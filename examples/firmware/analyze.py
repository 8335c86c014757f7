#!/usr/bin/env python3
"""Flash per gate and panic paths of a link-gate firmware ELF (called by link-gate.sh).

Usage: analyze.py ELF --llvm-bin DIR --src-root REPO [--sizes-only]

From `llvm-nm` and `llvm-objdump -d` of the ELF (Python standard library only):

* flash: per `gate_*` function its own size (`self`, what `llvm-nm --print-size` says) and
  `reach`, the bytes of every function it can reach through direct calls (itself, the texsat
  functions LLVM kept out of line, compiler-builtins), not counting the panic machinery;
* panic paths (a build with the `diagnose` panic handler): the panic machinery, i.e. every
  function that can reach the panic handler and is not texsat or firmware code; every call site
  of it in texsat/firmware code, with the source location the panic would report (decoded from
  the `core::panic::Location` the call passes: for indexing, `unwrap`, division and the like
  this is the line in texsat's `src/`, thanks to `#[track_caller]`) and the enclosing `fn` read
  from that source file; and, per `gate_*` function, which of these sites it reaches.

Indirect calls (`blx rN`) are not followed; texsat makes none in these builds.
"""

import argparse
import os
import re
import struct
import subprocess
import sys
from collections import defaultdict, deque

BRANCH = re.compile(r"^(bl|blx|b)(eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le|al)?(\.w|\.n)?$")
HEADER = re.compile(r"^([0-9a-f]{8}) <(.*)>:$")
INSN = re.compile(r"^\s+([0-9a-f]+):\s+(\S+)\s*(.*)$")
MOVW = re.compile(r"^(movw)\s+(r\d+|r1[0-2]|lr|ip), #(0x[0-9a-f]+|\d+)")
MOVT = re.compile(r"^(movt)\s+(r\d+|r1[0-2]|lr|ip), #(0x[0-9a-f]+|\d+)")
LDR_LIT = re.compile(r"^ldr(?:\.w)?\s+(r\d+), \[pc, #[^\]]*\]\s+@ 0x([0-9a-f]+)")
HASH = re.compile(r"::h[0-9a-f]{16}$")
# Where the panic machinery starts: the handler (a loop in the diagnose build) and panic_fmt.
ROOTS = re.compile(r"rust_begin_unwind|^core::panicking::panic_fmt$|^core::panicking::panic_nounwind_fmt")


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def short(name):
    """The name without its legacy-mangling hash."""
    return HASH.sub("", name)


def compact(name, keep_depth=2):
    """A shorter name for listings: module paths dropped (`texsat::lookup::sum_raw` ->
    `sum_raw`), generic arguments nested deeper than `keep_depth` shown as `..`."""
    name = re.sub(r"\b(?:[a-z_][a-z0-9_]*::)+(?=[A-Za-z_])", "", short(name))
    out, depth = [], 0
    for ch in name:
        if ch == "<":
            depth += 1
            if depth == keep_depth + 1:
                out.append("..")
            if depth > keep_depth:
                continue
        elif ch == ">":
            depth -= 1
            if depth >= keep_depth:
                continue
        elif depth > keep_depth:
            continue
        out.append(ch)
    return "".join(out)


def own_code(name):
    """texsat or firmware code (everything else reached from the handler is panic machinery)."""
    return "texsat" in name


class Elf:
    """Just enough ELF32 little-endian to read bytes at a virtual address."""

    def __init__(self, path):
        with open(path, "rb") as f:
            self.data = f.read()
        d = self.data
        if d[:4] != b"\x7fELF" or d[4] != 1 or d[5] != 1:
            raise SystemExit(f"{path}: not a 32-bit little-endian ELF")
        shoff, = struct.unpack_from("<I", d, 0x20)
        shentsize, shnum = struct.unpack_from("<HH", d, 0x2E)
        self.sections = []
        for i in range(shnum):
            (_, sh_type, flags, addr, off, size) = struct.unpack_from("<IIIIII", d, shoff + i * shentsize)
            if flags & 0x2 and sh_type == 1 and size:  # SHF_ALLOC, PROGBITS
                self.sections.append((addr, off, size))

    def read(self, addr, n):
        for a, off, size in self.sections:
            if a <= addr and addr + n <= a + size:
                return self.data[off + addr - a: off + addr - a + n]
        return None

    def location(self, addr):
        """A `core::panic::Location` at `addr` (file ptr, file len, line, col), or None."""
        raw = self.read(addr, 16)
        if raw is None:
            return None
        ptr, ln, line, col = struct.unpack("<IIII", raw)
        if not (0 < ln < 1024 and 0 < line < 1_000_000 and col < 10_000):
            return None
        s = self.read(ptr, ln)
        if s is None:
            return None
        s = s.rstrip(b"\0")
        if not s.endswith(b".rs") or any(c < 0x20 or c > 0x7E for c in s):
            return None
        return (s.decode(), line, col)


def parse_symbols(nm, elf):
    sizes = {}
    for line in run([nm, "--print-size", "--defined-only", "-C", elf]).splitlines():
        parts = line.split(None, 3)
        if len(parts) == 4 and parts[2] in "tTwW":
            sizes[parts[3]] = int(parts[1], 16)
    return sizes


def parse_disassembly(objdump, elf):
    """Functions (start -> name, instructions) and direct call/branch edges between them."""
    funcs = {}  # start -> name
    insns = defaultdict(list)  # start -> [(addr, mnemonic, operands)]
    cur = None
    for line in run([objdump, "-d", "-C", "--no-show-raw-insn", elf]).splitlines():
        m = HEADER.match(line)
        if m:
            cur = int(m.group(1), 16)
            funcs[cur] = m.group(2)
            continue
        m = INSN.match(line)
        if m and cur is not None:
            insns[cur].append((int(m.group(1), 16), m.group(2), m.group(3)))
    edges = defaultdict(list)  # caller start -> [(callee start, insn index)]
    for s, body in insns.items():
        for i, (addr, mnem, ops) in enumerate(body):
            if not BRANCH.match(mnem):
                continue
            m = re.match(r"0x([0-9a-f]+)", ops)
            if not m:
                continue
            # Calls and tail calls go to a function's first instruction; a branch into the middle
            # of another function is alignment padding decoded as an instruction.
            t = int(m.group(1), 16)
            if t in funcs and t != s:
                edges[s].append((t, i))
    return funcs, insns, edges


def location_of_call(elf, body, i):
    """The panic Location passed by the call at body[i]: movw/movt pairs or literal loads in the
    instructions just before it (stopping at a return or an unconditional branch)."""
    lo, hi, lit = {}, {}, {}
    for j in range(i - 1, max(-1, i - 24), -1):
        _, mnem, ops = body[j]
        if mnem in ("b", "b.w", "b.n", "bx") or (mnem.startswith("pop") and "pc" in ops):
            break
        text = f"{mnem} {ops}"
        m = MOVW.match(text)
        if m:
            lo.setdefault(m.group(2), int(m.group(3), 0))
        m = MOVT.match(text)
        if m:
            hi.setdefault(m.group(2), int(m.group(3), 0))
        m = LDR_LIT.match(text)
        if m:
            word = elf.read(int(m.group(2), 16), 4)
            if word:
                lit.setdefault(m.group(1), struct.unpack("<I", word)[0])
    cands = [(hi[r] << 16) | lo[r] for r in lo if r in hi] + list(lit.values())
    for c in cands:
        loc = elf.location(c)
        if loc:
            return loc
    return None


class Sources:
    """Maps `file:line` of texsat's sources to the enclosing `fn` (with its `impl`, if any)."""

    FN = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+)?(?:unsafe\s+)?fn\s+(\w+)")
    IMPL = re.compile(r"^impl\b.*?\b(?:for\s+)?([A-Z]\w*)(?:<[^{]*)?\s*(?:where.*)?\{?\s*$")

    def __init__(self, roots):
        self.roots = roots
        self.cache = {}

    def path(self, file):
        if os.path.isabs(file):
            return file if os.path.exists(file) else None
        for r in self.roots:
            p = os.path.join(r, file)
            if os.path.exists(p):
                return p
        return None

    def display(self, file):
        p = self.path(file)
        if p is None:
            return file
        for r in self.roots:
            rel = os.path.relpath(p, r)
            if not rel.startswith(".."):
                return rel
        return file

    def lines(self, file):
        p = self.path(file)
        if p is None:
            return None
        if p not in self.cache:
            with open(p, encoding="utf-8", errors="replace") as f:
                self.cache[p] = f.read().splitlines()
        return self.cache[p]

    def text(self, file, line, width=60):
        lines = self.lines(file)
        if not lines or not 0 < line <= len(lines):
            return ""
        t = lines[line - 1].strip()
        return t if len(t) <= width else t[: width - 3] + "..."

    def function(self, file, line):
        lines = self.lines(file)
        if lines is None:
            return None
        fn_line, fn = None, None
        for k in range(min(line, len(lines)) - 1, -1, -1):
            m = self.FN.match(lines[k])
            if m:
                fn_line, fn = k, m.group(1)
                break
        if fn is None:
            return None
        # The enclosing `impl` block: the nearest `impl` at column 0 above, unless a `}` at
        # column 0 (the end of an item) comes between.
        for k in range(fn_line - 1, -1, -1):
            text = lines[k]
            if text.startswith("}"):
                break
            if text.startswith("impl"):
                m = re.search(r"\bfor\s+([A-Za-z_]\w*)", text) or re.match(
                    r"impl(?:<.*?>)?\s+([A-Za-z_]\w*)", text
                )
                if m:
                    return f"{m.group(1)}::{fn}"
                break
            if re.match(r"^(pub\s+)?(trait|mod)\b", text):
                m = re.match(r"^(?:pub\s+)?(?:trait|mod)\s+(\w+)", text)
                return f"{m.group(1)}::{fn}" if m else fn
        return fn


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("elf")
    ap.add_argument("--llvm-bin", required=True)
    ap.add_argument("--src-root", required=True, action="append")
    ap.add_argument("--sizes-only", action="store_true")
    a = ap.parse_args()
    nm = os.path.join(a.llvm_bin, "llvm-nm")
    objdump = os.path.join(a.llvm_bin, "llvm-objdump")

    elf = Elf(a.elf)
    sizes = parse_symbols(nm, a.elf)
    funcs, insns, edges = parse_disassembly(objdump, a.elf)
    size_of = {s: sizes.get(n, 0) for s, n in funcs.items()}

    # Panic machinery: what reaches a root, minus texsat/firmware code.
    callers = defaultdict(set)
    for s, es in edges.items():
        for t, _ in es:
            callers[t].add(s)
    reach_handler = {s for s, n in funcs.items() if ROOTS.search(n)}
    todo = deque(reach_handler)
    while todo:
        t = todo.popleft()
        for s in callers[t]:
            if s not in reach_handler:
                reach_handler.add(s)
                todo.append(s)
    gates = sorted((s for s, n in funcs.items() if re.search(r"(^|::)gate_\w+$", short(n))),
                   key=lambda s: short(funcs[s]).split("::")[-1])
    # Startup code (reset handler, cortex-m-rt's `main` trampoline) reaches the handler through
    # the gates: it is not panic machinery.
    startup, todo = set(gates), deque(gates)
    while todo:
        t = todo.popleft()
        for s in callers[t]:
            if s not in startup:
                startup.add(s)
                todo.append(s)
    machinery = {s for s in reach_handler if not own_code(funcs[s]) and s not in startup}

    # Panic call sites: own code calling machinery.
    src = Sources(a.src_root)
    sites = defaultdict(list)  # caller -> [site]
    for s, es in edges.items():
        if s in machinery:
            continue
        for t, i in es:
            if t in machinery:
                loc = location_of_call(elf, insns[s], i)
                if loc:
                    file, line, col = loc
                    where = (src.display(file), line, col)
                    fn = src.function(file, line)
                    text = src.text(file, line)
                else:
                    where, fn, text = ("?", 0, 0), None, ""
                panic = compact(funcs[t])
                sites[s].append({"panic": panic, "where": where, "fn": fn, "text": text,
                                 "in": compact(funcs[s]), "addr": insns[s][i][0]})

    def reach(g):
        seen, todo = {g}, deque([g])
        while todo:
            s = todo.popleft()
            for t, _ in edges.get(s, ()):
                if t not in seen and t not in machinery:
                    seen.add(t)
                    todo.append(t)
        return seen

    def gname(s):
        return short(funcs[s]).split("::")[-1]

    # Flash per gate.
    print(f"  {'gate':<42} {'self':>7} {'reach':>7}   (bytes; reach = with out-of-line callees, no panic machinery)")
    for g in gates:
        r = reach(g)
        print(f"  {gname(g):<42} {size_of[g]:>7} {sum(size_of[s] for s in r):>7}")
    if a.sizes_only:
        return 0

    print()
    if not machinery:
        print("  no panic machinery in this binary")
        return 0
    print("  panic machinery present (reaches the panic handler):")
    for s in sorted(machinery, key=lambda s: short(funcs[s])):
        print(f"    {size_of[s]:>6} B  {short(funcs[s])}")

    def fmt(site):
        file, line, col = site["where"]
        where = f"{file}:{line}:{col}" if line else "(no Location found)"
        fn = f"fn {site['fn']}" if site["fn"] else ""
        return f"{site['panic']:<24} {where:<30} {fn:<30} | {site['text']}"

    print()
    print("  panic call sites per gate: panic function, the Location it reports, enclosing fn | source")
    all_sites = {}
    for g in gates:
        found = {}
        for s in sorted(reach(g)):
            for site in sites.get(s, ()):
                key = (site["where"], site["panic"])
                found.setdefault(key, site)
                all_sites.setdefault(key, (site, set(), set()))
                all_sites[key][1].add(gname(g))
                all_sites[key][2].add(site["in"])
        if not found:
            print(f"  {gname(g)}: none")
            continue
        print(f"  {gname(g)}: {len(found)} site(s)")
        for key in sorted(found):
            print(f"    {fmt(found[key])}")

    print()
    print("  distinct panic sites (all gates), the gates that reach them and the binary functions holding the call:")
    for key in sorted(all_sites):
        site, gs, ins = all_sites[key]
        print(f"    {fmt(site)}")
        print(f"        gates: {', '.join(sorted(gs))}")
        print(f"        in:    {'; '.join(sorted(ins))}")
    own_sites = [x for xs in sites.values() for x in xs]
    for x in own_sites:
        if (x["where"], x["panic"]) not in all_sites:
            print(f"    {fmt(x)}")
            print(f"        (not under a gate_* function: in {x['in']})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
