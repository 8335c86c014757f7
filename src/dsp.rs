//! The build's row scan on ARMv7E-M (Cortex-M4, M7; `thumbv7em-*` targets) with the DSP
//! extension, under the `simd` feature: `u8` texels into `u32` entries, one channel, four entries
//! per turn (issue 13: "a vectorized scan ... for Cortex-M's DSP instructions, if it pays
//! there").
//!
//! A row of Crow's table (§2) is `out[x] = above[x] + (t[0] + ... + t[x])`. The portable loop
//! spends about 7 instructions per entry on the Cortex-M4 (a byte load, a word load, two adds, a
//! store, the count and the branch: `examples/firmware/count-insns.sh`), because LLVM splits a
//! word load of four texels back into byte loads and does not merge the rows' words into
//! multiple loads and stores. Per four entries this loop takes 13 instructions: one word load
//! of four texels; one `LDM` (Thumb-2) of the four entries of the row above; per texel one
//! `UXTAB` (the DSP extension's "extract a byte, rotated, and add": the running sum plus texel
//! `j`), and for the last a plain add of the word shifted right by 24; four adds of the row
//! above; one `STM` of the four entries (two for [`build_row_in_place`] with a copy); the
//! count and the branch. The rest of a row (fewer than 4 entries) goes one entry at a time in
//! safe Rust here (`tail`); the first row of a table, other types and the checked builds take
//! the portable loop in `table.rs`. Used by `Sat::build`, `Sat::build_strips`,
//! `RowStreamBuilder` and the modular layout's rows (`Modular::build`, `ModularBuilder`: in
//! place, [`build_row_in_place`]).
//!
//! Exactness: the same additions as the portable loop, in the same order, on 32-bit registers.
//! The table builds run it only where the width proof holds (`CHECKED = false`: every running
//! sum and entry is the sum of a sub-rectangle, at most `255 w h < 2^32`), so no addition
//! wraps; the modular rows want their sums modulo `2^32` (they keep the low `k` bits), which
//! is what the registers' additions give, as the portable `wrapping_add` does.
//!
//! Targets: the assembly needs the DSP extension (`UXTAB`), which every ARMv7E-M core has; a
//! build for a `thumbv7em-*` target with `-C target-cpu=cortex-m3` (or `-C
//! target-feature=-dsp`) and `simd` fails to assemble, loudly.
//!
//! # Safety argument
//! 1. *Type casts.* [`build_row`] and [`build_row_in_place`] see `&[T]` as `&[u8]` and `&[E]`
//!    / `&mut [E]` as `&[u32]` / `&mut [u32]` through `crate::cast` (safe functions whose own
//!    safety argument is `TypeId` equality: `T = u8` and `E = u32`, the same type, the same
//!    length), and take them only for one channel (`C = 1`).
//! 2. *Bounds.* The slices have the same length `n` (checked); the assembly runs `q = n / 4`
//!    turns, each reading 4 bytes of the texels and 16 of the row above and writing 16 of the
//!    row out (and of the copy) at the turn's offset (`4 j`, `16 j`): all inside the slices. It
//!    runs only for `q >= 1` (the count is decremented before the test).
//! 3. *Alignment.* `LDM` and `STM` need word-aligned addresses: the rows are `u32` slices. The
//!    texels' word load may be unaligned, which ARMv7-M's single `LDR` allows unless the
//!    program sets `CCR.UNALIGN_TRP` (then a row of texels not on a 4-byte boundary takes a
//!    UsageFault: a fault, not undefined behaviour; documented with the feature). Texels in
//!    Device memory (which faults on unaligned access on the Cortex-M7) are not supported.
//! 4. *Aliasing.* In [`build_row`], `out` is a `&mut` borrow, so it overlaps neither the texels
//!    nor the row above. In place, the row above and the row out are one `&mut` slice: each
//!    turn's `LDM` reads its 16 bytes before its `STM` writes them, and turns move forward, so
//!    every entry is read as the row above before it is overwritten; the copy is another `&mut`
//!    borrow, disjoint from both.
//! 5. *Registers.* The four entries live in `r0` to `r3`, named as outputs (clobbered): `LDM` and
//!    `STM` take their register lists in ascending order, so the lowest register holds the
//!    lowest address, as the code assumes. They are early-clobber outputs (`out`, not
//!    `lateout`), so no input shares them: no base register of an `LDM` or `STM` is in its own
//!    list, and the texel word's register `w` (also `out`) is never the texel pointer `t`
//!    (`LDR w, [t], #4` with `w = t` is UNPREDICTABLE). The pointers and the count are in-out
//!    operands the assembly advances (their final values discarded), the running sum an in-out
//!    operand.
//! 6. *Effects.* The flags are clobbered (`SUBS`), which `asm!` assumes without
//!    `preserves_flags`; no stack is used (`nostack`); without `nomem` or `readonly` the
//!    compiler treats the block as reading and writing any memory, as it does.
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

use crate::cast;
use crate::texel::{Entry, Texel};

/// The turn loop around one load of the row above and one or two stores (the module's doc):
/// `$t` the texels' pointer, `$turns` the turns (at least 1), `$run` the running sum (read and
/// updated), the entries in `r0` to `r3`; the caller names the row pointers its load and stores
/// use.
macro_rules! scan_turns {
    ($t:expr, $turns:expr, $run:ident; $load:literal, $($store:literal),+; $($operands:tt)*) => {
        asm!(
            "2:",
            "ldr {w}, [{t}], #4",
            $load,
            "uxtab {run}, {run}, {w}",
            "add r0, r0, {run}",
            "uxtab {run}, {run}, {w}, ror #8",
            "add r1, r1, {run}",
            "uxtab {run}, {run}, {w}, ror #16",
            "add r2, r2, {run}",
            "add {run}, {run}, {w}, lsr #24",
            "add r3, r3, {run}",
            $($store,)+
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

/// `out = above + prefix sums of texels` for `u8` texels, `u32` entries and one channel with a
/// row above, four entries per turn (the module's doc); `false` (nothing written) otherwise,
/// and the caller takes the portable loop. The caller has proved that no sum exceeds `u32`.
pub(crate) fn build_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    above: Option<&[E]>,
    out: &mut [E],
) -> bool {
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
            scan_turns!(
                t.as_ptr(), turns, run;
                "ldm {a}!, {{r0, r1, r2, r3}}",
                "stm {o}!, {{r0, r1, r2, r3}}";
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
/// builder's rows). `false` (nothing written) for the first row (`first`: nothing above) and
/// for other types, and the caller takes the portable loop.
pub(crate) fn build_row_in_place<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    row: &mut [E],
    first: bool,
    copy: Option<&mut [E]>,
) -> bool {
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
                Some(c) => scan_turns!(
                    t.as_ptr(), turns, run;
                    "ldm {r}, {{r0, r1, r2, r3}}",
                    "stm {r}!, {{r0, r1, r2, r3}}",
                    "stm {c}!, {{r0, r1, r2, r3}}";
                    r = inout(reg) r.as_mut_ptr() => _,
                    c = inout(reg) c.as_mut_ptr() => _,
                ),
                None => scan_turns!(
                    t.as_ptr(), turns, run;
                    "ldm {r}, {{r0, r1, r2, r3}}",
                    "stm {r}!, {{r0, r1, r2, r3}}";
                    r = inout(reg) r.as_mut_ptr() => _,
                ),
            }
        }
    }
    tail(t, None, r, copy, run);
    true
}
