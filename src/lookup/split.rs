//! The split path: a box that crosses the texture's edge under [`crate::ClampToEdge`],
//! [`crate::Repeat`] or [`crate::MirroredRepeat`] is the sum of at most 3 x 3 in-range boxes with
//! multiplicities (Crow §2.4; the pieces come from [`crate::edge`]).
//!
//! `2^2F I = sum_(a, b) mult_a mult_b (2^2F I(piece_a x piece_b)) / 2^(F (unit_a + unit_b))`
//!
//! Every piece is an ordinary in-range lookup in the form's own narrow accumulator (its width
//! proof holds for any in-range box), every term is non-negative and at most the box's sum, and
//! the terms are added in the result word with checked arithmetic: a box whose sum does not fit
//! is [`Error::TooWide`], never a wrapped sum. The divisions by `2^F` are exact (a one-texel-wide
//! piece's integral is a multiple of `2^F`) and are shifts.
//!
//! On a modular layout each piece's sum is at most the box's, so the driver's check that the
//! box's sum stays below `2^k` makes every piece exact too: no extra bits for the split path.
//!
//! Cost: the pieces' own reads and operations, plus per channel one multiply per multiplicity
//! other than 1 and one addition per piece after the first.

use super::sealed::FormImpl;
use super::{in_range_wide, WideOf};
use crate::cost::Counter;
use crate::edge::{AxisPlan, EdgeMode};
use crate::error::{Error, Quantity};
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::wide::Wide;

fn overflow<W: Wide>() -> Error {
    Error::TooWide {
        what: Quantity::LookupAccumulator,
        bits_needed: W::BITS + 1,
        bits_available: W::BITS,
    }
}

/// The sum over the product of both axes' pieces. Not inlined: the common in-range case stays
/// small; this one is compiled once per layout, form, mode and counter, with only the mode's
/// own pieces.
#[inline(never)]
pub(crate) fn sum<L: Layout<C>, Fm: FormImpl, M: EdgeMode, K: Counter, const C: usize>(
    layout: &L,
    px: AxisPlan,
    py: AxisPlan,
    f: u32,
    form: Fm,
    mode: M,
    k: &mut K,
) -> Result<[WideOf<L, C>; C], Error> {
    let kind = mode.kind();
    let (pw, ph) = ((layout.width() as i64) << f, (layout.height() as i64) << f);
    let xs = px.prepare(kind, pw);
    let ys = py.prepare(kind, ph);
    let mut acc = [<WideOf<L, C> as Wide>::ZERO; C];
    let mut terms = 0u32;
    for ka in 0..3 {
        let a = xs.piece(ka, pw, f);
        if a.mult == 0 {
            continue;
        }
        for kb in 0..3 {
            let b = ys.piece(kb, ph, f);
            if b.mult == 0 {
                continue;
            }
            let piece = RawBox {
                x0: a.lo,
                y0: b.lo,
                x1: a.hi,
                y1: b.hi,
            };
            let v = in_range_wide(layout, &piece, f, form, k)?;
            let shift = f * (a.unit as u32 + b.unit as u32);
            let muls = (a.mult != 1) as u32 + (b.mult != 1) as u32;
            k.muls(muls * C as u32);
            if terms > 0 {
                k.adds(C as u32);
            }
            terms += 1;
            for (o, v) in acc.iter_mut().zip(v) {
                let t = v
                    .shr(shift)
                    .checked_mul_u64(a.mult)
                    .and_then(|t| t.checked_mul_u64(b.mult))
                    .ok_or_else(overflow::<WideOf<L, C>>)?;
                *o = o.checked_add(t).ok_or_else(overflow::<WideOf<L, C>>)?;
            }
        }
    }
    Ok(acc)
}
