//! Crow's 16-read lookup: bilinear interpolation of the table at each corner (§2.1), each lerp
//! as `b * 2^F + (c - b) * alpha` (§2.2's cheaper form; the scale by `2^F` is a shift).

use super::{Form, Paper};
use crate::cost::Counter;
use crate::edge::split;
use crate::rect::RawBox;
use crate::table::Sat;
use crate::texel::{Acc, Entry};
use crate::width;

/// `2^2F S(i + A/2^F, j + B/2^F)` per channel: 4 reads, 3 multiplies, 6 additive operations.
#[inline(always)]
fn corner<E: Entry, const C: usize, K: Counter>(
    sat: &Sat<'_, E, C>,
    x: i128,
    y: i128,
    f: u32,
    k: &mut K,
) -> [E::Acc; C] {
    let (i, a) = split(x, sat.width(), f);
    let (j, b) = split(y, sat.height(), f);
    let q00 = sat.read(i, j, k);
    let q10 = sat.read(i + 1, j, k);
    let q01 = sat.read(i, j + 1, k);
    let q11 = sat.read(i + 1, j + 1, k);
    k.muls(3 * C as u32);
    k.adds(6 * C as u32);
    let (a, b) = (E::Acc::from_u32(a), E::Acc::from_u32(b));
    let mut v = [E::Acc::ZERO; C];
    for c in 0..C {
        let (s00, s10) = (q00[c].to_acc(), q10[c].to_acc());
        let (s01, s11) = (q01[c].to_acc(), q11[c].to_acc());
        let r0 = (s00 << f) + (s10 - s00) * a;
        let r1 = (s01 << f) + (s11 - s01) * a;
        v[c] = (r0 << f) + (r1 - r0) * b;
    }
    v
}

impl Form for Paper {
    const NAME: &'static str = "paper";
    fn acc_bits(total_bits: u32, frac_bits: u32) -> u32 {
        width::paper_acc_bits(total_bits, frac_bits)
    }
    #[inline]
    fn in_range<E: Entry, const C: usize, K: Counter>(
        sat: &Sat<'_, E, C>,
        b: &RawBox,
        f: u32,
        k: &mut K,
    ) -> [u128; C] {
        let v11 = corner(sat, b.x1, b.y1, f, k);
        let v10 = corner(sat, b.x1, b.y0, f, k);
        let v01 = corner(sat, b.x0, b.y1, f, k);
        let v00 = corner(sat, b.x0, b.y0, f, k);
        k.adds(3 * C as u32);
        let mut out = [0u128; C];
        for c in 0..C {
            out[c] = ((v11[c] - v10[c]) - (v01[c] - v00[c])).to_i128() as u128;
        }
        out
    }
}
