# The link gate's call-graph check on the optimised LLVM IR (link-gate.sh, ir_check): every
# gate_* function that may not reach 128-bit arithmetic must not, through any chain of calls.
#
#   awk -v allow_gates=REGEX -f ir-reach.awk FILE.ll
#
# A function "holds i128" if a line of its body names an i128 value (the per-function test of
# link-gate.sh). A function reaches every function its body names (`call`, `invoke`, a function
# pointer stored or passed: any `@symbol`), transitively; that over-approximates the calls, so a
# pass is a proof for the direct and pointer calls the IR shows. Roots: every defined function
# whose name contains `gate_` and does not match allow_gates (the gates allowed to reach 128-bit
# code: the u128-signature width helpers, the float conversions, the tent lookups), and the
# firmware's main; the search does not enter the allowed gates (main calls them). Prints one
# line per offending gate, `GATE -> FUNCTION` for the first 128-bit function found (breadth
# first, so a shortest chain), and nothing if none reaches one.
/^define/ {
  fn = ""
  if (match($0, /@[A-Za-z0-9_.$]+/)) fn = substr($0, RSTART + 1, RLENGTH - 1)
  defined[fn] = 1
  next
}
/^}/ { fn = ""; next }
fn != "" && /^[^;!#]/ && !/#dbg/ {
  if ($0 ~ /[ (<{\[]i128[ ,)>}\]*]/) wide[fn] = 1
  s = $0
  while (match(s, /@[A-Za-z0-9_.$]+/)) {
    callee = substr(s, RSTART + 1, RLENGTH - 1)
    if (callee != fn && !((fn, callee) in seen_edge)) {
      seen_edge[fn, callee] = 1
      edges[fn] = edges[fn] " " callee
    }
    s = substr(s, RSTART + RLENGTH)
  }
}
END {
  for (root in defined) {
    if ((root !~ /gate_/ && root !~ /cortex_m_rt_main/) || root ~ allow_gates) continue
    # Breadth-first search from root.
    delete visited
    head = 0; tail = 0
    queue[tail++] = root; visited[root] = 1
    hit = ""
    while (head < tail && hit == "") {
      f = queue[head++]
      if (wide[f]) { hit = f; break }
      n = split(edges[f], cs, " ")
      for (i = 1; i <= n; i++) {
        c = cs[i]
        if (c == "" || (c in visited) || !(c in defined) || c ~ allow_gates) continue
        visited[c] = 1
        queue[tail++] = c
      }
    }
    if (hit != "") print root " -> " hit
  }
}
