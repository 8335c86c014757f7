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
//! of four texels; one `LDM` of four entries of the row above; per texel one `UXTAB` (the DSP
//! extension's "extract a byte, rotated, and add": the running sum plus texel `j`), and for the
//! last a plain add of the word shifted right by 24; four adds of the row above; one `STM` of
//! the four entries; the count and the branch. The rest of the row (fewer than 4 entries) and
//! rows without a row above (the first) take the portable loop.
//!
//! Exactness: the same additions as the portable loop, in the same order, on 32-bit registers.
//! The caller runs it only where the width proof holds (`CHECKED = false`: every running sum
//! and entry is the sum of a sub-rectangle, at most `255 w h < 2^32`), so no addition wraps.
//!
//! # Safety argument
//! 1. *Type casts.* [`build_row`] casts `&[T]` to `&[u8]`, `&[E]` to `&[u32]` and `&mut [E]` to
//!    `&mut [u32]` only after `TypeId` equality shows `T = u8` and `E = u32` (and `C = 1`): the
//!    same type, the same length.
//! 2. *Bounds.* The three slices have the same length `n` (checked); the assembly runs `q = n /
//!    4` turns, each reading 4 bytes of `t` and 16 of `above` and writing 16 of `out` at the
//!    turn's offset (`4 j`, `16 j`): all inside the slices. It runs only for `q >= 1` (the
//!    count is decremented before the test).
//! 3. *Alignment.* `LDM` and `STM` need word-aligned addresses: `above` and `out` are `u32`
//!    slices. The texels' word load may be unaligned, which ARMv7-M's `LDR` allows (unless the
//!    program sets `CCR.UNALIGN_TRP`, which would fault every unaligned access of compiled
//!    code too).
//! 4. *Aliasing.* `out` is a `&mut` borrow, so it overlaps neither `t` nor `above`.
//! 5. *Registers.* The four entries live in `r0` to `r3`, named as outputs (clobbered): `LDM`
//!    and `STM` take their register lists in ascending order, so the lowest register holds the
//!    lowest address, as the code assumes. The pointers and the count are in-out operands the
//!    assembly advances (their final values discarded), the running sum an in-out operand. The
//!    flags are clobbered (`SUBS`), which `asm!` assumes without `preserves_flags`; no stack is
//!    used (`nostack`).
#![allow(unsafe_code)]

use core::any::TypeId;
use core::arch::asm;

use crate::texel::{Entry, Texel};

/// `out = above + prefix sums of texels` for `u8` texels, `u32` entries and one channel with a
/// row above, four entries per turn (the module's doc); `false` (nothing written) otherwise,
/// and the caller takes the portable loop. The caller has proved that no sum exceeds `u32`.
pub(crate) fn build_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    above: Option<&[E]>,
    out: &mut [E],
) -> bool {
    let Some(above) = above else {
        return false;
    };
    if C != 1
        || TypeId::of::<T>() != TypeId::of::<u8>()
        || TypeId::of::<E>() != TypeId::of::<u32>()
        || texels.len() != out.len()
        || above.len() != out.len()
    {
        return false;
    }
    // SAFETY: T is u8 and E is u32 (TypeId equality): the same layout and length (the safety
    // argument, 1); the mutable borrow of `out` is moved into the cast.
    let (t, a, o) = unsafe {
        (
            core::slice::from_raw_parts(texels.as_ptr().cast::<u8>(), texels.len()),
            core::slice::from_raw_parts(above.as_ptr().cast::<u32>(), above.len()),
            core::slice::from_raw_parts_mut(out.as_mut_ptr().cast::<u32>(), out.len()),
        )
    };
    scan(t, a, o);
    true
}

/// The row scan over slices of one length `n` (checked by the caller): `n / 4` turns of the
/// assembly loop, then the last `n % 4` entries one by one.
fn scan(t: &[u8], above: &[u32], out: &mut [u32]) {
    let n = out.len();
    let turns = n / 4;
    let mut run = 0u32;
    if turns > 0 && t.len() == n && above.len() == n {
        // SAFETY: the safety argument, 2 to 5: `turns >= 1` turns of 4 texels, 4 entries above
        // and 4 entries out, all inside the three slices of length n >= 4 turns; `above` and
        // `out` word-aligned; `out` disjoint from both.
        unsafe {
            asm!(
                "2:",
                "ldr {w}, [{t}], #4",
                "ldm {a}!, {{r0, r1, r2, r3}}",
                "uxtab {run}, {run}, {w}",
                "add r0, r0, {run}",
                "uxtab {run}, {run}, {w}, ror #8",
                "add r1, r1, {run}",
                "uxtab {run}, {run}, {w}, ror #16",
                "add r2, r2, {run}",
                "add {run}, {run}, {w}, lsr #24",
                "add r3, r3, {run}",
                "stm {o}!, {{r0, r1, r2, r3}}",
                "subs {n}, {n}, #1",
                "bne 2b",
                t = inout(reg) t.as_ptr() => _,
                a = inout(reg) above.as_ptr() => _,
                o = inout(reg) out.as_mut_ptr() => _,
                n = inout(reg) turns => _,
                run = inout(reg) run,
                w = out(reg) _,
                out("r0") _,
                out("r1") _,
                out("r2") _,
                out("r3") _,
                options(nostack),
            );
        }
    }
    // The last n % 4 entries (all of them if the slices differ, which the caller rules out).
    let done = if t.len() == n && above.len() == n {
        turns.saturating_mul(4)
    } else {
        0
    };
    let rest = out.iter_mut().zip(t).zip(above).skip(done);
    for ((o, &v), &u) in rest {
        // No wrap: the caller's width proof (the module's doc).
        run = run.wrapping_add(u32::from(v));
        *o = run.wrapping_add(u);
    }
}
