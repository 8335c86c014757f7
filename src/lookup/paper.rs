//! Crow's 16-read lookup: bilinear interpolation of the table at each corner (§2.1), each lerp
//! as `b * 2^F + (c - b) * alpha` (§2.2's cheaper form; the scale by `2^F` is a shift).

use super::{Form, Paper};
use crate::cost::Counter;
use crate::edge::split;
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::texel::{Acc, Entry};
use crate::width;

/// `2^2F S(i + A/2^F, j + B/2^F)` per channel: 4 reads, 3 multiplies, 6 additive operations.
/// Wrapping operations: on flat and tiled tables the width proof rules out any wrap (so they are
/// the plain operations); on a modular table the result is only needed modulo `2^k`.
#[inline(always)]
fn corner<L: Layout<C>, const C: usize, K: Counter>(
    t: &L,
    x: i128,
    y: i128,
    f: u32,
    k: &mut K,
) -> [<L::Value as Entry>::Acc; C] {
    let (i, a) = split(x, t.width(), f);
    let (j, b) = split(y, t.height(), f);
    let q00 = t.corner(i, j, k);
    let q10 = t.corner(i + 1, j, k);
    let q01 = t.corner(i, j + 1, k);
    let q11 = t.corner(i + 1, j + 1, k);
    k.muls(3 * C as u32);
    k.adds(6 * C as u32);
    let a = <L::Value as Entry>::Acc::from_u32(a);
    let b = <L::Value as Entry>::Acc::from_u32(b);
    let mut v = [<L::Value as Entry>::Acc::ZERO; C];
    for c in 0..C {
        let (s00, s10) = (q00[c].to_acc(), q10[c].to_acc());
        let (s01, s11) = (q01[c].to_acc(), q11[c].to_acc());
        let r0 = (s00 << f).wrapping_add(s10.wrapping_sub(s00).wrapping_mul(a));
        let r1 = (s01 << f).wrapping_add(s11.wrapping_sub(s01).wrapping_mul(a));
        v[c] = (r0 << f).wrapping_add(r1.wrapping_sub(r0).wrapping_mul(b));
    }
    v
}

impl Form for Paper {
    const NAME: &'static str = "paper";
    fn acc_bits(total_bits: u32, frac_bits: u32) -> u32 {
        width::paper_acc_bits(total_bits, frac_bits)
    }
    fn modular_headroom_bits(frac_bits: u32) -> u32 {
        // Corner values are known mod 2^k only, so the whole scaled result must be below 2^k.
        2 * frac_bits
    }
    // Inlined: an out-of-line call returning i128 sums through memory dominated the lookup
    // (docs/benchmarks.md, finding 1).
    #[inline(always)]
    fn in_range<L: Layout<C>, const C: usize, K: Counter>(
        t: &L,
        b: &RawBox,
        f: u32,
        k: &mut K,
    ) -> [u128; C] {
        let v11 = corner(t, b.x1, b.y1, f, k);
        let v10 = corner(t, b.x1, b.y0, f, k);
        let v01 = corner(t, b.x0, b.y1, f, k);
        let v00 = corner(t, b.x0, b.y0, f, k);
        k.adds(3 * C as u32);
        let mut out = [0u128; C];
        for c in 0..C {
            let mut v = v11[c]
                .wrapping_sub(v10[c])
                .wrapping_sub(v01[c].wrapping_sub(v00[c]));
            if let Some(m) = t.modulus() {
                v = v.low_bits(m);
            }
            out[c] = v.to_i128() as u128;
        }
        out
    }
}
