//! The 4-read lookup at integer corners (Crow §2.1): `S(x1,y1) - S(x1,y0) - S(x0,y1) + S(x0,y0)`.

use super::Form;
use crate::cost::Counter;
use crate::rect::RawBox;
use crate::table::Sat;
use crate::texel::Entry;

/// Integer corners; only used with `F = 0`. Computed in the entry type itself: the table is
/// monotone, so `S(x1,y1) - S(x1,y0)` and `S(x0,y1) - S(x0,y0)` are non-negative column-band sums
/// and the first is at least the second. No intermediate exceeds the largest entry.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Corners4;

impl Form for Corners4 {
    const NAME: &'static str = "int";
    fn acc_bits(total_bits: u32, _frac_bits: u32) -> u32 {
        // Computed in `E`; report the need against the accumulator for uniformity (always fits).
        total_bits
    }
    #[inline]
    fn in_range<E: Entry, const C: usize, K: Counter>(
        sat: &Sat<'_, E, C>,
        b: &RawBox,
        _frac_bits: u32,
        k: &mut K,
    ) -> [u128; C] {
        let (x0, y0, x1, y1) = (b.x0 as usize, b.y0 as usize, b.x1 as usize, b.y1 as usize);
        let d = sat.read(x1, y1, k);
        let c_ = sat.read(x1, y0, k);
        let b_ = sat.read(x0, y1, k);
        let a = sat.read(x0, y0, k);
        k.adds(3 * C as u32);
        let mut out = [0u128; C];
        for c in 0..C {
            out[c] = ((d[c] - c_[c]) - (b_[c] - a[c])).to_u128();
        }
        out
    }
}
