//! The 4-read lookup at integer corners (Crow §2.1): `S(x1,y1) - S(x1,y0) - S(x0,y1) + S(x0,y0)`.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use super::sealed::FormImpl;
use super::AccOf;
use crate::cost::{per_channel, Counter};
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::texel::{Acc, Entry};

/// Integer corners; only used with `F = 0`. Computed in the value type itself: on a flat or tiled
/// table `S` is monotone, so `S(x1,y1) - S(x1,y0)` and `S(x0,y1) - S(x0,y0)` are non-negative
/// column-band sums, the first at least the second, and no subtraction wraps. On a modular
/// layout the subtractions wrap on purpose and the result is reduced modulo `2^k`, exact because
/// the driver has checked that the box sum is below `2^k`. (On corrupt lent storage the
/// subtractions may wrap: a wrong sum, never a panic.)
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Corners4;

impl FormImpl for Corners4 {
    // Four reads and three additions: cheaper inline than a call.
    const OUTLINE: bool = false;
    #[inline(always)]
    fn acc_bits(self, _total_bits: u32, _frac_bits: u32) -> u32 {
        // Computed in the value type, which holds every entry.
        0
    }
    #[inline(always)]
    fn modular_headroom_bits(self, _frac_bits: u32) -> u32 {
        0
    }
    // Inlined: an out-of-line call returning the sums through memory dominated the lookup
    // (docs/benchmarks.md, finding 1).
    #[inline(always)]
    fn in_range<L: Layout<C>, const C: usize, K: Counter>(
        self,
        t: &L,
        b: &RawBox,
        _frac_bits: u32,
        k: &mut K,
    ) -> [AccOf<L, C>; C] {
        #[allow(
            clippy::as_conversions,
            reason = "an in-range box at F = 0: 0 <= x0 <= x1 <= w and 0 <= y0 <= y1 <= h, sides at most \
                      2^31 - 1 (check_dimensions), so each fits usize (at least 32 bits: MAX_DIMENSION)"
        )]
        let (x0, y0, x1, y1) = (b.x0 as usize, b.y0 as usize, b.x1 as usize, b.y1 as usize);
        let [a, c_, b_, d] = t.quad_placed(x0, x1, y0, y1, k);
        k.adds(const { per_channel(3, C) });
        let modulus = t.modulus();
        let mut out = [<AccOf<L, C> as Acc>::ZERO; C];
        for (c, o) in out.iter_mut().enumerate() {
            let (Some(d), Some(c_), Some(b_), Some(a)) = (d.get(c), c_.get(c), b_.get(c), a.get(c))
            else {
                continue;
            };
            let mut v = d.wrapping_sub(*c_).wrapping_sub(b_.wrapping_sub(*a));
            if let Some(m) = modulus {
                v = v.low_bits(m);
            }
            *o = v.to_acc();
        }
        out
    }
}
