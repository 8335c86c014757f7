//! The build's row scan on ARMv7E-M (Cortex-M4, M7; `thumbv7em-*` targets) with the DSP
//! extension, under the `simd` feature: `u8` texels into `u32` or `u16` entries, one channel,
//! four entries per turn (issue 13: "a vectorized scan ... for Cortex-M's DSP instructions, if
//! it pays there").
//!
//! A row of Crow's table (§2) is `out[x] = above[x] + (t[0] + ... + t[x])`, the first row
//! without `above`. The portable loop spends about 7 instructions per entry on the Cortex-M4 (a
//! byte load, a load of the entry above, two adds, a store, the count and the branch;
//! `examples/firmware/count-insns.sh`), because LLVM splits a word load of four texels back
//! into byte loads and does not merge the rows' words into multiple loads and stores. Per four
//! entries the turns here take:
//!
//! * `u32`, 13 instructions: one word load of four texels; one `LDM` (Thumb-2) of the four
//!   entries of the row above; per texel one `UXTAB` (the DSP extension's "extract a byte,
//!   rotated, and add": the running sum plus texel `j`), and for the last a plain add of the
//!   word shifted right by 24; four adds of the row above; one `STM` of the four entries (two
//!   for [`build_row_in_place`] with a copy); the count and the branch. A table's first row
//!   takes the portable loop (why: [`build_row`]).
//! * `u16` (two entries a word), 17: the word of texels; `UXTB16` twice, texels 0 and 2, then
//!   1 and 3, one per 16-bit half (the DSP extension's "extract two bytes into halves"); three
//!   adds give the prefix sums in halves, `(p0, p2)` and `(p1, p3)`: the pairs' sums `(t0 + t1,
//!   t2 + t3)`, then `(t0, t2) + (pairs << 16)` and `pairs + (pairs << 16)`; two `UADD16` (add
//!   halves) add the running sum, kept in both halves; `PKHBT` and `PKHTB` (pack halves) put the
//!   entries in order, `(p0, p1)` and `(p2, p3)`, and one more `PKHTB` copies `p3` into both
//!   halves of the running sum; one `LDM` of the two words above and two `UADD16`; one `STM`
//!   (two with a copy); the count and the branch. A table's first row, 14 (no row above). Rows
//!   of fewer than [`U16_MIN_ROW`] (16) entries take the portable loop, where the turns do not
//!   pay for the row's checks. `u16` tables of 8-bit texels are small (the width proof: at most
//!   257 entries), so this is mostly for the modular layout's `u16` rows, which wrap.
//!
//! The rest of a row (fewer than 4 entries, and for `u16` a first entry that puts the row on a
//! word) goes one entry at a time in safe Rust here ([`tail`], [`scalar`]); other types and the
//! checked builds take the portable loop in `table.rs`. Used by `Sat::build`,
//! `Sat::build_strips`, `RowStreamBuilder` and the modular layout's rows (`Modular::build`,
//! `ModularBuilder`, in place: [`build_row_in_place`]).
//!
//! Exactness: the same additions as the portable loop, in the same order, on 32-bit registers
//! (`u32`) or 16-bit halves of them (`u16`). The table builds run it only where the width proof
//! holds (`CHECKED = false`: every running sum and entry is the sum of a sub-rectangle, at most
//! `255 w h < 2^BITS`), so no addition wraps; the modular rows want their sums modulo
//! `2^BITS` (they keep the low `k` bits), which is what the registers' additions give, as the
//! portable `wrapping_add` does. For `u16`: `UADD16` adds each half modulo `2^16`, with no
//! carry from the low half into the high one; the three plain adds stay inside their halves
//! (texel pairs at most 510, prefix sums of a turn at most 1,020) or, shifted into the high
//! half, lose only the carry out of bit 31: modulo `2^16` in each half, as wanted.
//!
//! Targets: the assembly needs the DSP extension (`UXTAB`, `UXTB16`, `UADD16`, `PKHBT`), which
//! every ARMv7E-M core has; a build for a `thumbv7em-*` target with `-C target-cpu=cortex-m3`
//! (or `-C target-feature=-dsp`) and `simd` fails to assemble, loudly.
//!
//! # Safety argument
//! 1. *Type casts.* [`build_row`] and [`build_row_in_place`] see `&[T]` as `&[u8]` and `&[E]`
//!    / `&mut [E]` as `&[u32]` / `&mut [u32]` or `&[u16]` / `&mut [u16]` through `crate::cast`
//!    (safe functions whose own safety argument is `TypeId` equality: `T = u8` and `E = u32` or
//!    `E = u16`, the same type, the same length), and take them only for one channel (`C = 1`).
//! 2. *Bounds.* The slices have the same length `n` (checked); from entry `h` on (`h` = 0, or
//!    for `u16` 0 or 1, see 3), the assembly runs `q = (n - h) / 4` turns, each reading 4 bytes
//!    of the texels and 4 entries of the row above (16 bytes, or 8 for `u16`) and writing 4
//!    entries of the row out (and of the copy) at the turn's offset: all inside the slices
//!    from `h`. The callers run it only for `q >= 1` (`turns > 0`): the count is decremented
//!    before its test, so `q = 0` would run `2^32` turns.
//! 3. *Alignment.* `LDM` and `STM` need word-aligned addresses. `u32` rows are. A `u16` row may
//!    start 2 bytes off a word: then its first entry goes the portable way (`h` = 1), and the
//!    turns start on a word; if the row above or the copy is not on a word from the same entry
//!    (an odd width: in a table every row after the first, in the streaming builder every
//!    other row), the row is declined (the caller's portable loop; nothing written). The
//!    texels' word loads (from texel `h`) may be unaligned, which ARMv7-M's single `LDR` allows
//!    unless the program sets `CCR.UNALIGN_TRP` (then a row of texels not on a 4-byte boundary,
//!    or a `u16` row 2 bytes off a word, whose loads start one texel in, takes a UsageFault: a
//!    fault, not undefined behaviour; documented with the feature). Texels in Device memory (which faults on unaligned access on the Cortex-M7) are
//!    not supported.
//! 4. *Aliasing.* In [`build_row`], `out` is a `&mut` borrow, so it overlaps neither the texels
//!    nor the row above. In place, the row above and the row out are one `&mut` slice: each
//!    turn's `LDM` reads its bytes before its `STM` writes them, and turns move forward, so
//!    every entry is read as the row above before it is overwritten; the copy is another `&mut`
//!    borrow, disjoint from both.
//! 5. *Registers.* The entries live in `r0` to `r3` (`u16`: the two words out in `r2`, `r3`,
//!    the two above in `r0`, `r1`, which first hold a prefix sum), named as outputs (clobbered): `LDM` and `STM` take their
//!    register lists in ascending order, so the lowest register holds the lowest address, as
//!    the code assumes. They are early-clobber outputs (`out`, not `lateout`), so no input
//!    shares them: no base register of an `LDM` or `STM` is in its own list, and the texel
//!    word's register `w` (also `out`) is never the texel pointer `t` (`LDR w,
//!    [t], #4` with `w = t` is UNPREDICTABLE). The pointers and the count are in-out operands
//!    the assembly advances (their final values discarded), the running sum an in-out operand
//!    (`u16`: its value in both halves).
//! 6. *Effects.* The flags are clobbered (`SUBS`; `UADD16` sets `APSR.GE`), which `asm!` assumes
//!    without `preserves_flags`; no stack is used (`nostack`); without `nomem` or `readonly`
//!    the compiler treats the block as reading and writing any memory, as it does.
#![allow(unsafe_code)]
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use core::arch::asm;
use core::ops::Range;

use crate::cast;
use crate::texel::{Entry, Texel};

/// The turn loop (the module's doc): one word of texels per turn, then `$body` (which ends
/// with the turn's stores); `$t` the texels' pointer, `$turns` the turns (at least 1), `$run`
/// the running sum (read and updated); the entries in `r0` to `r3`; the caller names the row
/// pointers its loads and stores use (and any register of its own).
macro_rules! turns {
    ($t:expr, $turns:expr, $run:ident; [$($body:literal),+ $(,)?]; $($operands:tt)*) => {
        asm!(
            "2:",
            "ldr {w}, [{t}], #4",
            $($body,)+
            "subs {n}, {n}, #1",
            "bne 2b",
            $($operands)*
            t = inout(reg) $t => _,
            n = inout(reg) $turns => _,
            run = inout(reg) $run,
            w = out(reg) _,
            out("r0") _,
            out("r1") _,
            out("r2") _,
            out("r3") _,
            options(nostack),
        )
    };
}

/// [`turns!`] for `u32` entries with a row above, which `$load` puts in `r0` to `r3`.
macro_rules! turns32 {
    ($t:expr, $turns:expr, $run:ident; $load:literal; [$($store:literal),+]; $($operands:tt)*) => {
        turns!($t, $turns, $run; [
            $load,
            "uxtab {run}, {run}, {w}",
            "add r0, r0, {run}",
            "uxtab {run}, {run}, {w}, ror #8",
            "add r1, r1, {run}",
            "uxtab {run}, {run}, {w}, ror #16",
            "add r2, r2, {run}",
            "add {run}, {run}, {w}, lsr #24",
            "add r3, r3, {run}",
            $($store),+
        ]; $($operands)*)
    };
}

/// [`turns!`] for `u16` entries, two a word: the prefix sums in `r0` (`(p0, p2)`) and `{w}`
/// (`(p1, p3)`), the entries' words in `r2` and `r3`; then `$load` (none for the first row)
/// puts the two words above in `r0`, `r1` and `$add` adds them. `$run` holds the running sum
/// in both halves. No register beyond [`turns!`]'s: with one more, more of the row's state
/// spilled to the stack (about 4 instructions a row).
macro_rules! turns16 {
    ($t:expr, $turns:expr, $run:ident; [$($load:literal),*]; [$($add:literal),*];
     [$($store:literal),+]; $($operands:tt)*) => {
        turns!($t, $turns, $run; [
            "uxtb16 r0, {w}",
            "uxtb16 {w}, {w}, ror #8",
            "add {w}, r0, {w}",
            "add r0, r0, {w}, lsl #16",
            "add {w}, {w}, {w}, lsl #16",
            "uadd16 r0, r0, {run}",
            "uadd16 {w}, {w}, {run}",
            "pkhtb {run}, {w}, {w}, asr #16",
            "pkhbt r2, r0, {w}, lsl #16",
            "pkhtb r3, {w}, r0, asr #16",
            $($load,)*
            $($add,)*
            $($store),+
        ]; $($operands)*)
    };
}

/// Where a row's entries above come from.
#[derive(Clone, Copy)]
enum Up<'a, E> {
    /// The first row: nothing above.
    Zero,
    /// A separate row, as long as the row out.
    Row(&'a [E]),
    /// The row out holds the row above (in place).
    InPlace,
}

/// `texels` as `u8` when `T` is `u8` and there is one channel ([`cast::u8s`]).
fn texels_u8<T: Texel, const C: usize>(texels: &[T]) -> Option<&[u8]> {
    if C == 1 {
        cast::u8s(texels)
    } else {
        None
    }
}

/// The last `n % 4` entries, one by one, after `done = n - n % 4` by the turns: `out[x] =
/// above[x] + run` (`above` `None`: in place, `out` holds it), written to `copy` too.
fn tail(t: &[u8], above: Option<&[u32]>, out: &mut [u32], copy: Option<&mut [u32]>, mut run: u32) {
    let done = out.len() & !3;
    let (Some(t), Some(out)) = (t.get(done..), out.get_mut(done..)) else {
        return;
    };
    let above = above.and_then(|a| a.get(done..));
    let mut copy = copy.and_then(|c| c.get_mut(done..));
    for (x, (o, &v)) in out.iter_mut().zip(t).enumerate() {
        // No wrap: the caller's width proof (the module's doc).
        run = run.wrapping_add(u32::from(v));
        let up = match above {
            Some(a) => a.get(x).copied().unwrap_or(0),
            None => *o,
        };
        *o = run.wrapping_add(up);
        if let Some(c) = copy.as_deref_mut().and_then(|c| c.get_mut(x)) {
            *c = *o;
        }
    }
}

/// Entries `range` of a row one by one, from the running sum `run` (returned after them):
/// `out[x] = above[x] + run`, written to `copy` too; the rest of a row the turns leave.
/// Wrapping additions, as the turns' (the module's doc). Indices are checked: a range past a
/// slice writes nothing past it.
/// The `u16` rows' head and tail. ([`tail`] stays for `u32`: this in its place, called only for
/// rows with a tail, took `Sat::build` of 64 x 64 from 4.07 to 4.16 instructions an entry on
/// the Cortex-M4.)
fn scalar<E: Entry>(
    t: &[u8],
    up: Up<'_, E>,
    out: &mut [E],
    copy: Option<&mut [E]>,
    range: Range<usize>,
    mut run: E,
) -> E {
    let (Some(t), Some(out)) = (t.get(range.clone()), out.get_mut(range.clone())) else {
        return run;
    };
    let above = match up {
        Up::Row(a) => a.get(range.clone()),
        Up::Zero | Up::InPlace => None,
    };
    let mut copy = copy.and_then(|c| c.get_mut(range));
    for (x, (o, &v)) in out.iter_mut().zip(t).enumerate() {
        run = run.wrapping_add(E::from(u16::from(v)));
        let above = match up {
            Up::Zero => E::ZERO,
            Up::Row(_) => above.and_then(|a| a.get(x)).copied().unwrap_or(E::ZERO),
            Up::InPlace => *o,
        };
        *o = run.wrapping_add(above);
        if let Some(c) = copy.as_deref_mut().and_then(|c| c.get_mut(x)) {
            *c = *o;
        }
    }
    run
}

/// The shortest `u16` row the turns take: shorter rows decline (the caller's portable loop).
/// The turns save about 2.75 instructions an entry; a row's checks, head and tail cost more
/// than the portable loop's. On the Cortex-M4, `Sat::build` of `u16` tables of 256 entries,
/// instructions per entry with the turns off (this constant past any row) / on, in the same
/// binary (`COUNT_FEATURES=simd examples/firmware/count-insns.sh`, row 6e at each shape;
/// docs/benchmarks.md, twenty-sixth session): 4 x 64 16.61 / 18.61, 8 x 32 11.96 / 12.96
/// (declined: the portable loop beside this code keeps fewer registers), 16 x 16 9.58 / 9.16,
/// 32 x 8 8.30 / 6.89, 64 x 4 7.47 / 5.69, 128 x 2 6.68 / 4.95. Taken below 16 too, 8 x 32
/// took 14.11 and 4 x 64 23.50.
const U16_MIN_ROW: usize = 16;

/// A row of `u16` entries (all slices `n` long: the callers check): the first entry one by
/// one if `out` starts off a word, then four entries per turn, then the rest one by one.
/// `false` (nothing written) if the row above or the copy is not on a word where `out` is
/// (the safety argument, 3). Inlined into its two callers, each case with its own known
/// [`Up`] (kept as an enum for the rest of the row, it took registers and instructions).
#[inline(always)]
fn row16(t: &[u8], up: Up<'_, u16>, out: &mut [u16], copy: Option<&mut [u16]>) -> bool {
    match up {
        Up::Zero => first_row16(t, out, copy),
        Up::Row(a) => turns_row16(t, Up::Row(a), out, copy),
        Up::InPlace => turns_row16(t, Up::InPlace, out, copy),
    }
}

/// [`row16`] for a table's first row, out of line: inlined, its cases took registers from the
/// other rows' turns.
#[inline(never)]
fn first_row16(t: &[u8], out: &mut [u16], copy: Option<&mut [u16]>) -> bool {
    turns_row16(t, Up::Zero, out, copy)
}

/// [`row16`]'s head, turns and rest.
#[inline(always)]
fn turns_row16(t: &[u8], up: Up<'_, u16>, out: &mut [u16], mut copy: Option<&mut [u16]>) -> bool {
    let n = out.len();
    let head = usize::from(!out.as_ptr().cast::<u32>().is_aligned()).min(n);
    let on_word = |p: *const u16| p.wrapping_add(head).cast::<u32>().is_aligned();
    let above_on_word = match up {
        Up::Row(a) => on_word(a.as_ptr()),
        Up::Zero | Up::InPlace => true,
    };
    if !above_on_word || copy.as_deref().is_some_and(|c| !on_word(c.as_ptr())) {
        return false;
    }
    // A separate row above comes without a copy ([`build_row16`]); declined otherwise, so that
    // the turns need no case for both.
    if matches!(up, Up::Row(_)) && copy.is_some() {
        return false;
    }
    let mut run = 0;
    if head > 0 {
        run = scalar(t, up, out, copy.as_deref_mut(), 0..head, run);
    }
    let rest = n.saturating_sub(head);
    let turns = rest / 4;
    let mut done = head;
    if turns > 0 {
        // Each slice from `head` (`head <= n`, every slice `n` long).
        let (tp, o) = (
            t.as_ptr().wrapping_add(head),
            out.as_mut_ptr().wrapping_add(head),
        );
        let c = copy
            .as_deref_mut()
            .map(|c| c.as_mut_ptr().wrapping_add(head));
        let mut run2 = u32::from(run).wrapping_mul(0x0001_0001);
        // SAFETY: the safety argument, 2 to 6: `turns >= 1` turns of 4 texels, 4 entries above
        // and 4 out (and copied), inside the slices from `head`, `n - head >= 4 turns` long;
        // those rows start on a word (checked above; `out` by `head`); `out` and the copy
        // `&mut` borrows, disjoint from the rest.
        unsafe {
            match (up, c) {
                (Up::Zero, None) => turns16!(
                    tp, turns, run2; []; []; ["stm {o}!, {{r2, r3}}"];
                    o = inout(reg) o => _,
                ),
                (Up::Zero, Some(c)) => turns16!(
                    tp, turns, run2; []; [];
                    ["stm {o}!, {{r2, r3}}", "stm {c}!, {{r2, r3}}"];
                    o = inout(reg) o => _,
                    c = inout(reg) c => _,
                ),
                // No copy here (declined above).
                (Up::Row(a), _) => turns16!(
                    tp, turns, run2; ["ldm {a}!, {{r0, r1}}"];
                    ["uadd16 r2, r2, r0", "uadd16 r3, r3, r1"]; ["stm {o}!, {{r2, r3}}"];
                    a = inout(reg) a.as_ptr().wrapping_add(head) => _,
                    o = inout(reg) o => _,
                ),
                (Up::InPlace, None) => turns16!(
                    tp, turns, run2; ["ldm {o}, {{r0, r1}}"];
                    ["uadd16 r2, r2, r0", "uadd16 r3, r3, r1"]; ["stm {o}!, {{r2, r3}}"];
                    o = inout(reg) o => _,
                ),
                (Up::InPlace, Some(c)) => turns16!(
                    tp, turns, run2; ["ldm {o}, {{r0, r1}}"];
                    ["uadd16 r2, r2, r0", "uadd16 r3, r3, r1"];
                    ["stm {o}!, {{r2, r3}}", "stm {c}!, {{r2, r3}}"];
                    o = inout(reg) o => _,
                    c = inout(reg) c => _,
                ),
            }
        }
        let [b0, b1, _, _] = run2.to_le_bytes();
        run = u16::from_le_bytes([b0, b1]);
        done = head.saturating_add(rest & !3);
    }
    if done < n {
        scalar(t, up, out, copy, done..n, run);
    }
    true
}

/// `out = above + prefix sums of texels` for `u8` texels and one channel, four entries per
/// turn (the module's doc): `u32` entries with a row above; `u16` entries, rows of
/// [`U16_MIN_ROW`] and more ([`build_row16`]);
/// `false` (nothing written) otherwise, and the caller takes the portable loop. The caller has
/// proved that no sum exceeds the entry type. (`u32`'s first row by turns, tried: 2.25 instead
/// of about 5 instructions an entry, but the other rows spent more on choosing, and on the
/// Cortex-M4 `Sat::build` of 64 x 64 took 4.08 instead of 4.07 instructions an entry, in 256
/// more bytes of flash: docs/benchmarks.md, twenty-sixth session.)
pub(crate) fn build_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    above: Option<&[E]>,
    out: &mut [E],
) -> bool {
    if let Some(o) = cast::u16s_mut(out) {
        return o.len() >= U16_MIN_ROW && build_row16::<T, E, C>(texels, above, o);
    }
    let (Some(t), Some(a)) = (texels_u8::<T, C>(texels), above.and_then(cast::u32s)) else {
        return false;
    };
    let n = out.len();
    let Some(o) = cast::u32s_mut(out) else {
        return false;
    };
    if t.len() != n || a.len() != n {
        return false;
    }
    let mut run = 0u32;
    let turns = n / 4;
    if turns > 0 {
        // SAFETY: the safety argument, 2 to 6: `turns >= 1` turns of 4 texels, 4 entries above
        // and 4 out, inside the three slices of length n >= 4 turns; the rows word-aligned;
        // `o` disjoint from `t` and `a`.
        unsafe {
            turns32!(
                t.as_ptr(), turns, run; "ldm {a}!, {{r0, r1, r2, r3}}";
                ["stm {o}!, {{r0, r1, r2, r3}}"];
                a = inout(reg) a.as_ptr() => _,
                o = inout(reg) o.as_mut_ptr() => _,
            );
        }
    }
    tail(t, Some(a), o, None, run);
    true
}

/// [`build_row`] in place: `row` holds the row above on entry and the new row on exit, and with
/// `copy` (as long as `row`) the new row is written there too, in the same pass (the streaming
/// builder's rows). `false` (nothing written) for a `u32` table's first row (`first`: nothing
/// above) and for other types, and the caller takes the portable loop; `u16` rows
/// ([`build_row_in_place16`]) the first row too.
pub(crate) fn build_row_in_place<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    row: &mut [E],
    first: bool,
    copy: Option<&mut [E]>,
) -> bool {
    if let Some(r) = cast::u16s_mut(row) {
        return r.len() >= U16_MIN_ROW && build_row_in_place16::<T, E, C>(texels, r, first, copy);
    }
    let Some(t) = texels_u8::<T, C>(texels) else {
        return false;
    };
    let n = row.len();
    if first || t.len() != n {
        return false;
    }
    let mut copy = match copy {
        Some(c) => match cast::u32s_mut(c) {
            Some(c) if c.len() == n => Some(c),
            _ => return false,
        },
        None => None,
    };
    let Some(r) = cast::u32s_mut(row) else {
        return false;
    };
    let mut run = 0u32;
    let turns = n / 4;
    if turns > 0 {
        // SAFETY: the safety argument, 2 to 6: `turns >= 1` turns of 4 texels and 4 entries of
        // the row (read, then written back) and of the copy, inside slices of length n >= 4
        // turns; the rows word-aligned; the copy a separate `&mut` borrow.
        unsafe {
            match copy.as_deref_mut() {
                Some(c) => turns32!(
                    t.as_ptr(), turns, run; "ldm {r}, {{r0, r1, r2, r3}}";
                    ["stm {r}!, {{r0, r1, r2, r3}}", "stm {c}!, {{r0, r1, r2, r3}}"];
                    r = inout(reg) r.as_mut_ptr() => _,
                    c = inout(reg) c.as_mut_ptr() => _,
                ),
                None => turns32!(
                    t.as_ptr(), turns, run; "ldm {r}, {{r0, r1, r2, r3}}";
                    ["stm {r}!, {{r0, r1, r2, r3}}"];
                    r = inout(reg) r.as_mut_ptr() => _,
                ),
            }
        }
    }
    tail(t, None, r, copy, run);
    true
}

/// [`build_row`] for `u16` entries (`out`, `E` being `u16`). Inlined by the compiler: out of
/// line, `Sat::build` of a 64 x 4 `u16` table took 6.00 instead of 5.69 instructions an entry.
fn build_row16<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    above: Option<&[E]>,
    out: &mut [u16],
) -> bool {
    let Some(t) = texels_u8::<T, C>(texels) else {
        return false;
    };
    let n = out.len();
    match above.map(cast::u16s) {
        _ if t.len() != n => false,
        None => row16(t, Up::Zero, out, None),
        Some(Some(a)) if a.len() == n => row16(t, Up::Row(a), out, None),
        Some(_) => false,
    }
}

/// [`build_row_in_place`] for `u16` entries (`row`, `E` being `u16`), the first row too
/// (inlined, as [`build_row16`]).
fn build_row_in_place16<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    row: &mut [u16],
    first: bool,
    copy: Option<&mut [E]>,
) -> bool {
    let Some(t) = texels_u8::<T, C>(texels) else {
        return false;
    };
    let n = row.len();
    let up = if first { Up::Zero } else { Up::InPlace };
    match copy.map(cast::u16s_mut) {
        _ if t.len() != n => false,
        None => row16(t, up, row, None),
        Some(Some(c)) if c.len() == n => row16(t, up, row, Some(c)),
        Some(_) => false,
    }
}
