//! Crow's 16-read lookup: bilinear interpolation of the table at each corner (§2.1), each lerp
//! as `b * 2^F + (c - b) * alpha` (§2.2's cheaper form; the scale by `2^F` is a shift).
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use super::sealed::FormImpl;
use super::{split_coord, AccOf, Paper};
use crate::cost::{per_channel, Counter};
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::texel::{Acc, Entry};
use crate::width;

/// `2^2F S(i + A/2^F, j + B/2^F)` per channel from the 4 corners of cell `(i, j)` (read by the
/// caller, [`Layout::cells4_placed`]): 3 multiplies, 6 additive operations.
/// Wrapping operations: on flat and tiled tables the width proof rules out any wrap (so they are
/// the plain operations); on a modular table the result is only needed modulo `2^k`.
#[inline(always)]
fn corner<L: Layout<C>, const C: usize, K: Counter>(
    cell: [[L::Value; C]; 4],
    a: u32,
    b: u32,
    f: u32,
    k: &mut K,
) -> [AccOf<L, C>; C] {
    let [q00, q10, q01, q11] = cell;
    k.muls(const { per_channel(3, C) });
    k.adds(const { per_channel(6, C) });
    let a = AccOf::<L, C>::from_u32(a);
    let b = AccOf::<L, C>::from_u32(b);
    let mut v = [AccOf::<L, C>::ZERO; C];
    for (c, o) in v.iter_mut().enumerate() {
        let (Some(s00), Some(s10), Some(s01), Some(s11)) =
            (q00.get(c), q10.get(c), q01.get(c), q11.get(c))
        else {
            continue;
        };
        let (s00, s10) = (s00.to_acc(), s10.to_acc());
        let (s01, s11) = (s01.to_acc(), s11.to_acc());
        let r0 = s00
            .wrapping_shl(f)
            .wrapping_add(s10.wrapping_sub(s00).wrapping_mul(a));
        let r1 = s01
            .wrapping_shl(f)
            .wrapping_add(s11.wrapping_sub(s01).wrapping_mul(a));
        *o = r0
            .wrapping_shl(f)
            .wrapping_add(r1.wrapping_sub(r0).wrapping_mul(b));
    }
    v
}

impl FormImpl for Paper {
    #[inline(always)]
    fn acc_bits(self, total_bits: u32, frac_bits: u32) -> u32 {
        width::paper_acc_bits(total_bits, frac_bits)
    }
    #[inline(always)]
    fn modular_headroom_bits(self, frac_bits: u32) -> u32 {
        // Corner values are known mod 2^k only, so the whole scaled result must be below 2^k.
        crate::FormKind::Paper.modular_headroom_bits(frac_bits)
    }
    // Inlined: an out-of-line call returning the sums through memory dominated the lookup
    // (docs/benchmarks.md, finding 1).
    #[inline(always)]
    fn in_range<L: Layout<C>, const C: usize, K: Counter>(
        self,
        t: &L,
        b: &RawBox,
        f: u32,
        k: &mut K,
    ) -> [AccOf<L, C>; C] {
        // Each coordinate split once (not once per corner that uses it), the four cells read
        // through one call a layout may share work in.
        let (i0, a0) = split_coord(b.x0, t.width(), f);
        let (i1, a1) = split_coord(b.x1, t.width(), f);
        let (j0, b0) = split_coord(b.y0, t.height(), f);
        let (j1, b1) = split_coord(b.y1, t.height(), f);
        let [c11, c10, c01, c00] = t.cells4_placed([i0, i1], [j0, j1], k);
        let v11 = corner::<L, C, K>(c11, a1, b1, f, k);
        let v10 = corner::<L, C, K>(c10, a1, b0, f, k);
        let v01 = corner::<L, C, K>(c01, a0, b1, f, k);
        let v00 = corner::<L, C, K>(c00, a0, b0, f, k);
        k.adds(const { per_channel(3, C) });
        let modulus = t.modulus();
        let mut out = [AccOf::<L, C>::ZERO; C];
        for ((((o, v11), v10), v01), v00) in out.iter_mut().zip(v11).zip(v10).zip(v01).zip(v00) {
            let mut v = v11.wrapping_sub(v10).wrapping_sub(v01.wrapping_sub(v00));
            if let Some(m) = modulus {
                v = v.low_bits(m);
            }
            *o = v;
        }
        out
    }
}
