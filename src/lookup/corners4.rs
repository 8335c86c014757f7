//! The 4-read lookup at integer corners (Crow §2.1): `S(x1,y1) - S(x1,y0) - S(x0,y1) + S(x0,y0)`.

use super::Form;
use crate::cost::Counter;
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::texel::Entry;

/// Integer corners; only used with `F = 0`. Computed in the value type itself: on a flat or tiled
/// table `S` is monotone, so `S(x1,y1) - S(x1,y0)` and `S(x0,y1) - S(x0,y0)` are non-negative
/// column-band sums, the first at least the second, and no subtraction wraps. On a modular
/// layout the subtractions wrap on purpose and the result is reduced modulo `2^k`, exact because
/// the driver has checked that the box sum is below `2^k`.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Corners4;

impl Form for Corners4 {
    const NAME: &'static str = "int";
    fn acc_bits(total_bits: u32, _frac_bits: u32) -> u32 {
        // Computed in the value type; report the need against the accumulator for uniformity.
        total_bits
    }
    fn modular_headroom_bits(_frac_bits: u32) -> u32 {
        0
    }
    // Inlined: an out-of-line call returning i128 sums through memory dominated the lookup
    // (docs/benchmarks.md, finding 1).
    #[inline(always)]
    fn in_range<L: Layout<C>, const C: usize, K: Counter>(
        t: &L,
        b: &RawBox,
        _frac_bits: u32,
        k: &mut K,
    ) -> [u128; C] {
        let (x0, y0, x1, y1) = (b.x0 as usize, b.y0 as usize, b.x1 as usize, b.y1 as usize);
        let d = t.corner(x1, y1, k);
        let c_ = t.corner(x1, y0, k);
        let b_ = t.corner(x0, y1, k);
        let a = t.corner(x0, y0, k);
        k.adds(3 * C as u32);
        let mut out = [0u128; C];
        for c in 0..C {
            let mut v = d[c]
                .wrapping_sub(c_[c])
                .wrapping_sub(b_[c].wrapping_sub(a[c]));
            if let Some(m) = t.modulus() {
                v = v.low_bits(m);
            }
            out[c] = v.to_u128();
        }
        out
    }
}
