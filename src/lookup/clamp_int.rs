//! [`crate::ClampToEdge`] at integer corners in 32-bit coordinates: the 4-read lookup of every
//! integer box under clamp on a layout without a modulus, what a plan with integer boxes under
//! clamp needs and nothing else.
//!
//! Per axis the box `[lo, hi)` of an `n`-texel side has at most three pieces (Crow §2.4): the
//! run left of the texture, `[lo, min(hi, 0))`, which repeats the first texel column
//! `min(hi, 0) - lo` times; the part inside, `[max(lo, 0), min(hi, n))`, once; the run right of
//! it, `[max(lo, n), hi)`, which repeats the last column `hi - max(lo, n)` times. The box sum is
//!
//! `sum_(a, b) mult_a mult_b S4(piece_a x piece_b)`,
//!
//! each `S4` an ordinary in-range 4-read lookup (a one-texel-wide run reads the column or row of
//! width one). A box inside the texture is its own single piece. These are exactly the pieces,
//! order, counted costs and refusals of the general driver with its split path
//! ([`super::sum_raw`] and [`super::split`] at `F = 0`), which stays the path of every other
//! mode and of the modular layouts; this one works in 32-bit coordinates with one
//! 32 x 32 -> 64 multiply of the two multiplicities, and leaves out the general placement
//! (64-bit coordinates, every mode's pieces) and the driver's second, inlined copy of the
//! in-range reads. On a Cortex-M4 the smallest plan (build, clamp lookup, 32-bit mean) is
//! 1.08x the flash of a hand-written clamp lookup (docs/firmware.md). Tested against the
//! general path, results and counts, exhaustively on small textures (`lookup::tests`).
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use super::sealed::FormImpl;
use super::split::overflow;
use super::{check_acc, corners4::Corners4, BoxSum, WideOf};
use crate::cost::{per_channel, Counter};
use crate::error::Error;
use crate::layouts::Layout;
use crate::rect::{RawBox, Rect};
use crate::texel::Acc;
use crate::wide::Wide;

/// One piece of an axis: `[lo, hi)` inside the texture, counted `mult` times (0: absent).
#[derive(Clone, Copy)]
struct Piece {
    lo: u32,
    hi: u32,
    mult: u32,
}

/// Piece `which` (0 left, 1 inside, 2 right) of `[lo, hi)` (`hi >= lo`) on a side of `n >= 1`
/// texels, as [`crate::edge`]'s clamp pieces at `F = 0`.
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "hi >= lo, so hi - lo as a wrapping u32 difference is the exact width (< 2^32); each \
              run's width is at most that; n >= 1 where n - 1 is formed"
)]
fn piece(lo: i32, hi: i32, n: u32, which: u32) -> Piece {
    const NONE: Piece = Piece {
        lo: 0,
        hi: 0,
        mult: 0,
    };
    // The width of [a, b) for b >= a: the wrapping difference of the bit patterns.
    let width = |a: i32, b: i32| b.cast_unsigned().wrapping_sub(a.cast_unsigned());
    let n_i = n.cast_signed();
    match which {
        0 if lo < 0 => Piece {
            lo: 0,
            hi: 1,
            mult: width(lo, hi.min(0)),
        },
        1 => {
            let (a, b) = (lo.max(0), hi.min(n_i));
            if a < b {
                Piece {
                    lo: a.cast_unsigned(),
                    hi: b.cast_unsigned(),
                    mult: 1,
                }
            } else {
                NONE
            }
        }
        2 if hi > n_i => Piece {
            lo: n - 1,
            hi: n,
            mult: width(lo.max(n_i), hi),
        },
        _ => NONE,
    }
}

/// The clamp-to-edge sum of the integer box `r` on a layout without a modulus (the caller
/// checks both): the general driver's result for this box, reads and operations counted alike.
#[inline(never)]
#[allow(
    clippy::as_conversions,
    reason = "width and height <= 2^31 - 1 (check_dimensions): lossless as u32 and i32, and as \
              usize for the in-range box (usize has at least 32 bits: MAX_DIMENSION)"
)]
pub(crate) fn sum<L: Layout<C>, K: Counter, const C: usize>(
    layout: &L,
    r: &Rect<i32>,
    k: &mut K,
) -> Result<BoxSum<WideOf<L, C>, C>, Error> {
    if r.x1 < r.x0 || r.y1 < r.y0 {
        return Err(Error::InvertedBox);
    }
    let (w, h) = (
        r.x1.cast_unsigned().wrapping_sub(r.x0.cast_unsigned()),
        r.y1.cast_unsigned().wrapping_sub(r.y0.cast_unsigned()),
    );
    let mut out = BoxSum {
        sums: [<WideOf<L, C> as Wide>::ZERO; C],
        frac_bits: 0,
        width_raw: u64::from(w),
        height_raw: u64::from(h),
    };
    if w == 0 || h == 0 {
        return Ok(out);
    }
    check_acc(layout, Corners4, 0)?;
    let (n, m) = (layout.width() as u32, layout.height() as u32);
    let mut first = true;
    for ka in 0..3 {
        let a = piece(r.x0, r.x1, n, ka);
        if a.mult == 0 {
            continue;
        }
        for kb in 0..3 {
            let b = piece(r.y0, r.y1, m, kb);
            if b.mult == 0 {
                continue;
            }
            let placed = RawBox {
                x0: i64::from(a.lo),
                y0: i64::from(b.lo),
                x1: i64::from(a.hi),
                y1: i64::from(b.hi),
            };
            let acc = Corners4.in_range(layout, &placed, 0, k);
            k.muls(match (a.mult != 1, b.mult != 1) {
                (false, false) => 0,
                (true, true) => const { per_channel(2, C) },
                _ => const { per_channel(1, C) },
            });
            if !first {
                k.adds(const { per_channel(1, C) });
            }
            first = false;
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "a product of two u32 values fits u64"
            )]
            let mult = u64::from(a.mult) * u64::from(b.mult);
            for (o, v) in out.sums.iter_mut().zip(acc) {
                let v = v.to_wide().ok_or(Error::CorruptStorage)?;
                let t = v
                    .checked_mul_u64(mult)
                    .ok_or_else(overflow::<WideOf<L, C>>)?;
                *o = o.checked_add(t).ok_or_else(overflow::<WideOf<L, C>>)?;
            }
        }
    }
    Ok(out)
}
