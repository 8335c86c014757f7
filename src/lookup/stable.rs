//! The differences-first 16-read lookup (see [`Stable`]).
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use super::sealed::FormImpl;
use super::{split_coord, AccOf, Stable};
use crate::cost::{per_channel, Counter};
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::texel::{Acc, Entry};
use crate::width;

/// What one corner's 4 reads give per channel, in the value type: `S(i, j)`, the column strip
/// `S(i+1, j) - S(i, j)`, the row strip `S(i, j+1) - S(i, j)` and the texel `(i, j)`.
#[derive(Clone, Copy)]
struct Part<V> {
    s: V,
    col: V,
    row: V,
    texel: V,
}

/// One corner: its parts per channel and its fractions. 4 reads, 4 additive operations.
struct CornerParts<V, A, const C: usize> {
    parts: [Part<V>; C],
    frac_x: A,
    frac_y: A,
}

#[inline(always)]
fn corner<L: Layout<C>, const C: usize, K: Counter>(
    t: &L,
    x: i64,
    y: i64,
    f: u32,
    k: &mut K,
) -> CornerParts<L::Value, AccOf<L, C>, C> {
    let (i, a) = split_coord(x, t.width(), f);
    let (j, b) = split_coord(y, t.height(), f);
    let [q00, q10, q01, q11] = t.cell_corners_placed(i, j, k);
    k.adds(const { per_channel(4, C) });
    let z = <L::Value as Entry>::ZERO;
    let mut parts = [Part {
        s: z,
        col: z,
        row: z,
        texel: z,
    }; C];
    for (c, p) in parts.iter_mut().enumerate() {
        let (Some(&s00), Some(&s10), Some(&s01), Some(&s11)) =
            (q00.get(c), q10.get(c), q01.get(c), q11.get(c))
        else {
            continue;
        };
        // Monotone tables: no subtraction wraps. Modular tables: they wrap on purpose; only the
        // small differences below are used, after reduction modulo 2^k.
        let col0 = s10.wrapping_sub(s00);
        let col1 = s11.wrapping_sub(s01);
        *p = Part {
            s: s00,
            col: col0,
            row: s01.wrapping_sub(s00),
            texel: col1.wrapping_sub(col0),
        };
    }
    CornerParts {
        parts,
        frac_x: AccOf::<L, C>::from_u32(a),
        frac_y: AccOf::<L, C>::from_u32(b),
    }
}

impl FormImpl for Stable {
    #[inline(always)]
    fn acc_bits(self, total_bits: u32, frac_bits: u32) -> u32 {
        width::stable_acc_bits(total_bits, frac_bits)
    }
    #[inline(always)]
    fn modular_headroom_bits(self, _frac_bits: u32) -> u32 {
        // Every quantity reduced modulo 2^k is a sum over part of the box's cells.
        0
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
        let p11 = corner(t, b.x1, b.y1, f, k);
        let p10 = corner(t, b.x1, b.y0, f, k);
        let p01 = corner(t, b.x0, b.y1, f, k);
        let p00 = corner(t, b.x0, b.y0, f, k);
        let (a0, a1, b0, b1) = (p00.frac_x, p11.frac_x, p00.frac_y, p11.frac_y);
        // Fraction products, shared by the channels.
        let (w11, w10, w01, w00) = (
            a1.wrapping_mul(b1),
            a1.wrapping_mul(b0),
            a0.wrapping_mul(b1),
            a0.wrapping_mul(b0),
        );
        k.muls(4);
        // Per channel: Bint 3, strips 4, edge term 3, corner term 3, total 2 additive; edge 4
        // and corner 4 multiplies.
        k.adds(const { per_channel(15, C) });
        k.muls(const { per_channel(8, C) });
        let modulus = t.modulus();
        // The box-bounded quantities: exact values on every layout.
        let small = |v: L::Value| -> AccOf<L, C> {
            match modulus {
                Some(m) => v.low_bits(m).to_acc(),
                None => v.to_acc(),
            }
        };
        // Wrapping operations: on a valid table the width proof rules out any wrap (so they are
        // the plain operations); on corrupt lent storage they keep the no-panic guarantee (the
        // fuzz finding at this line before: an overflow panic from a corrupted `Tiled`).
        let mut out = [<AccOf<L, C> as Acc>::ZERO; C];
        for (c, o) in out.iter_mut().enumerate() {
            let (Some(p11), Some(p10), Some(p01), Some(p00)) = (
                p11.parts.get(c),
                p10.parts.get(c),
                p01.parts.get(c),
                p00.parts.get(c),
            ) else {
                continue;
            };
            let bint = small(
                p11.s
                    .wrapping_sub(p10.s)
                    .wrapping_sub(p01.s.wrapping_sub(p00.s)),
            );
            let right = small(p11.col.wrapping_sub(p10.col));
            let left = small(p01.col.wrapping_sub(p00.col));
            let bottom = small(p11.row.wrapping_sub(p01.row));
            let top = small(p10.row.wrapping_sub(p00.row));
            let (t11, t10) = (small(p11.texel), small(p10.texel));
            let (t01, t00) = (small(p01.texel), small(p00.texel));
            let edges = (a1.wrapping_mul(right).wrapping_sub(a0.wrapping_mul(left)))
                .wrapping_add(b1.wrapping_mul(bottom).wrapping_sub(b0.wrapping_mul(top)));
            let corners = (w11.wrapping_mul(t11).wrapping_sub(w10.wrapping_mul(t10)))
                .wrapping_sub(w01.wrapping_mul(t01).wrapping_sub(w00.wrapping_mul(t00)));
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "2 * f: f <= MAX_FRAC_BITS = 24 (FracBits)"
            )]
            let two_f = 2 * f;
            *o = bint
                .wrapping_shl(two_f)
                .wrapping_add(edges.wrapping_shl(f))
                .wrapping_add(corners);
        }
        out
    }
}
