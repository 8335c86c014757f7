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

/// One corner: its parts per channel and its fractions.
struct CornerParts<V, A, const C: usize> {
    parts: [Part<V>; C],
    frac_x: A,
    frac_y: A,
}

/// One corner's parts from the 4 corners of its cell (read by the caller,
/// [`Layout::cells4_placed`]) and its fractions `a`, `b`: 4 additive operations.
#[inline(always)]
fn corner<L: Layout<C>, const C: usize, K: Counter>(
    cell: [[L::Value; C]; 4],
    a: u32,
    b: u32,
    k: &mut K,
) -> CornerParts<L::Value, AccOf<L, C>, C> {
    let [q00, q10, q01, q11] = cell;
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
        // Each coordinate split once (not once per corner that uses it: 422 -> 359 instructions
        // for a Border lookup on the Cortex-M4), the four cells read through one call a layout
        // may share work in.
        let (i0, a0) = split_coord(b.x0, t.width(), f);
        let (i1, a1) = split_coord(b.x1, t.width(), f);
        let (j0, b0) = split_coord(b.y0, t.height(), f);
        let (j1, b1) = split_coord(b.y1, t.height(), f);
        let [c11, c10, c01, c00] = t.cells4_placed([i0, i1], [j0, j1], k);
        let p11 = corner::<L, C, K>(c11, a1, b1, k);
        let p10 = corner::<L, C, K>(c10, a1, b0, k);
        let p01 = corner::<L, C, K>(c01, a0, b1, k);
        let p00 = corner::<L, C, K>(c00, a0, b0, k);
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
