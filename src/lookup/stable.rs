//! The differences-first 16-read lookup (see [`Stable`]).

use super::{Form, Stable};
use crate::cost::Counter;
use crate::edge::split;
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::texel::{Acc, Entry};
use crate::width;

/// What one corner's 4 reads give, in the value type: `S(i, j)`, the column strip
/// `S(i+1, j) - S(i, j)`, the row strip `S(i, j+1) - S(i, j)` and the texel `(i, j)`.
/// 4 reads, 4 additive operations.
struct CornerParts<V, A, const C: usize> {
    s: [V; C],
    col: [V; C],
    row: [V; C],
    texel: [V; C],
    frac_x: A,
    frac_y: A,
}

#[inline(always)]
fn corner<L: Layout<C>, const C: usize, K: Counter>(
    t: &L,
    x: i128,
    y: i128,
    f: u32,
    k: &mut K,
) -> CornerParts<L::Value, <L::Value as Entry>::Acc, C> {
    let (i, a) = split(x, t.width(), f);
    let (j, b) = split(y, t.height(), f);
    let q00 = t.corner(i, j, k);
    let q10 = t.corner(i + 1, j, k);
    let q01 = t.corner(i, j + 1, k);
    let q11 = t.corner(i + 1, j + 1, k);
    k.adds(4 * C as u32);
    let z = [<L::Value as Entry>::ZERO; C];
    let mut p = CornerParts {
        s: q00,
        col: z,
        row: z,
        texel: z,
        frac_x: <L::Value as Entry>::Acc::from_u32(a),
        frac_y: <L::Value as Entry>::Acc::from_u32(b),
    };
    for c in 0..C {
        // Monotone tables: no subtraction wraps. Modular tables: they wrap on purpose; only the
        // small differences below are used, after reduction modulo 2^k.
        let col0 = q10[c].wrapping_sub(q00[c]);
        let col1 = q11[c].wrapping_sub(q01[c]);
        p.col[c] = col0;
        p.row[c] = q01[c].wrapping_sub(q00[c]);
        p.texel[c] = col1.wrapping_sub(col0);
    }
    p
}

impl Form for Stable {
    const NAME: &'static str = "stable";
    fn acc_bits(total_bits: u32, frac_bits: u32) -> u32 {
        width::stable_acc_bits(total_bits, frac_bits)
    }
    fn modular_headroom_bits(_frac_bits: u32) -> u32 {
        // Every quantity reduced modulo 2^k is a sum over part of the box's cells.
        0
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
        let p11 = corner(t, b.x1, b.y1, f, k);
        let p10 = corner(t, b.x1, b.y0, f, k);
        let p01 = corner(t, b.x0, b.y1, f, k);
        let p00 = corner(t, b.x0, b.y0, f, k);
        let (a0, a1, b0, b1) = (p00.frac_x, p11.frac_x, p00.frac_y, p11.frac_y);
        // Fraction products, shared by the channels.
        let (w11, w10, w01, w00) = (a1 * b1, a1 * b0, a0 * b1, a0 * b0);
        k.muls(4);
        // Per channel: Bint 3, strips 4, edge term 3, corner term 3, total 2 additive; edge 4
        // and corner 4 multiplies.
        k.adds(15 * C as u32);
        k.muls(8 * C as u32);
        let modulus = t.modulus();
        // The box-bounded quantities: exact values on every layout.
        let small = |v: L::Value| -> <L::Value as Entry>::Acc {
            match modulus {
                Some(m) => v.low_bits(m).to_acc(),
                None => v.to_acc(),
            }
        };
        let mut out = [0u128; C];
        for (c, o) in out.iter_mut().enumerate() {
            let bint = small(
                p11.s[c]
                    .wrapping_sub(p10.s[c])
                    .wrapping_sub(p01.s[c].wrapping_sub(p00.s[c])),
            );
            let right = small(p11.col[c].wrapping_sub(p10.col[c]));
            let left = small(p01.col[c].wrapping_sub(p00.col[c]));
            let bottom = small(p11.row[c].wrapping_sub(p01.row[c]));
            let top = small(p10.row[c].wrapping_sub(p00.row[c]));
            let (t11, t10) = (small(p11.texel[c]), small(p10.texel[c]));
            let (t01, t00) = (small(p01.texel[c]), small(p00.texel[c]));
            let edges = (a1 * right - a0 * left) + (b1 * bottom - b0 * top);
            let corners = (w11 * t11 - w10 * t10) - (w01 * t01 - w00 * t00);
            *o = ((bint << (2 * f)) + (edges << f) + corners).to_i128() as u128;
        }
        out
    }
}
