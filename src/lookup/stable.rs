//! The differences-first 16-read lookup (see [`Stable`]).

use super::{Form, Stable};
use crate::cost::Counter;
use crate::edge::split;
use crate::rect::RawBox;
use crate::table::Sat;
use crate::texel::{Acc, Entry};
use crate::width;

/// What one corner's 4 reads give: `S(i, j)`, the column strip `S(i+1, j) - S(i, j)`, the row
/// strip `S(i, j+1) - S(i, j)` and the texel `(i, j)`. 4 reads, 4 additive operations.
struct CornerParts<A, const C: usize> {
    s: [A; C],
    col: [A; C],
    row: [A; C],
    texel: [A; C],
    frac_x: A,
    frac_y: A,
}

#[inline(always)]
fn corner<E: Entry, const C: usize, K: Counter>(
    sat: &Sat<'_, E, C>,
    x: i128,
    y: i128,
    f: u32,
    k: &mut K,
) -> CornerParts<E::Acc, C> {
    let (i, a) = split(x, sat.width(), f);
    let (j, b) = split(y, sat.height(), f);
    let q00 = sat.read(i, j, k);
    let q10 = sat.read(i + 1, j, k);
    let q01 = sat.read(i, j + 1, k);
    let q11 = sat.read(i + 1, j + 1, k);
    k.adds(4 * C as u32);
    let z = [E::Acc::ZERO; C];
    let mut p = CornerParts {
        s: z,
        col: z,
        row: z,
        texel: z,
        frac_x: E::Acc::from_u32(a),
        frac_y: E::Acc::from_u32(b),
    };
    for c in 0..C {
        let s00 = q00[c].to_acc();
        let col0 = q10[c].to_acc() - s00;
        let col1 = q11[c].to_acc() - q01[c].to_acc();
        p.s[c] = s00;
        p.col[c] = col0;
        p.row[c] = q01[c].to_acc() - s00;
        p.texel[c] = col1 - col0;
    }
    p
}

impl Form for Stable {
    const NAME: &'static str = "stable";
    fn acc_bits(total_bits: u32, frac_bits: u32) -> u32 {
        width::stable_acc_bits(total_bits, frac_bits)
    }
    #[inline]
    fn in_range<E: Entry, const C: usize, K: Counter>(
        sat: &Sat<'_, E, C>,
        b: &RawBox,
        f: u32,
        k: &mut K,
    ) -> [u128; C] {
        let p11 = corner(sat, b.x1, b.y1, f, k);
        let p10 = corner(sat, b.x1, b.y0, f, k);
        let p01 = corner(sat, b.x0, b.y1, f, k);
        let p00 = corner(sat, b.x0, b.y0, f, k);
        let (a0, a1, b0, b1) = (p00.frac_x, p11.frac_x, p00.frac_y, p11.frac_y);
        // Fraction products, shared by the channels.
        let (w11, w10, w01, w00) = (a1 * b1, a1 * b0, a0 * b1, a0 * b0);
        k.muls(4);
        // Per channel: Bint 3, strips 4, edge term 3, corner term 3, total 2 additive; edge 4
        // and corner 4 multiplies.
        k.adds(15 * C as u32);
        k.muls(8 * C as u32);
        let mut out = [0u128; C];
        for (c, o) in out.iter_mut().enumerate() {
            let bint = (p11.s[c] - p10.s[c]) - (p01.s[c] - p00.s[c]);
            let right = p11.col[c] - p10.col[c];
            let left = p01.col[c] - p00.col[c];
            let bottom = p11.row[c] - p01.row[c];
            let top = p10.row[c] - p00.row[c];
            let edges = (a1 * right - a0 * left) + (b1 * bottom - b0 * top);
            let corners = (w11 * p11.texel[c] - w10 * p10.texel[c])
                - (w01 * p01.texel[c] - w00 * p00.texel[c]);
            *o = ((bint << (2 * f)) + (edges << f) + corners).to_i128() as u128;
        }
        out
    }
}
