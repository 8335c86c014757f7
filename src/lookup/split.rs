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
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use super::sealed::FormImpl;
use super::{in_range_wide, WideOf};
use crate::cost::{per_channel, Counter};
use crate::edge::{AxisPlan, AxisSplit, EdgeMode};
use crate::error::{Error, Quantity};
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::wide::Wide;

/// The refusal of a sum past the result word `W` (also the clamp path's, `clamp_int`).
#[allow(
    clippy::arithmetic_side_effects,
    reason = "W::BITS is 64 or 128 (Wide is sealed): + 1 does not wrap"
)]
pub(super) fn overflow<W: Wide>() -> Error {
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
    #[allow(
        clippy::as_conversions,
        reason = "sides <= 2^31 - 1 (check_dimensions) and f <= MAX_FRAC_BITS = 24: lossless, and the \
                  shifted values stay below 2^55"
    )]
    let (pw, ph) = ((layout.width() as i64) << f, (layout.height() as i64) << f);
    let xs = px.prepare(kind, pw);
    let ys = py.prepare(kind, ph);
    let mut acc = [<WideOf<L, C> as Wide>::ZERO; C];
    let mut first = true;
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
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "f <= MAX_FRAC_BITS = 24, times at most 2"
            )]
            let shift = f * (u32::from(a.unit) + u32::from(b.unit));
            // One multiply per multiplicity other than 1, per channel.
            k.muls(match (a.mult != 1, b.mult != 1) {
                (false, false) => 0,
                (true, true) => const { per_channel(2, C) },
                _ => const { per_channel(1, C) },
            });
            if !first {
                k.adds(const { per_channel(1, C) });
            }
            first = false;
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

/// The pieces of a Repeat axis whose box is at most one period `p` long (the driver has refused
/// a longer one), as `[a, b)` and `[0, c)` (`c = 0`: none): an in-range axis is its one piece;
/// a split one is the head `[r0, p)` of the first period and the tail `[0, rest)` of the next
/// (`rest <= r0` for a box at most `p` long).
#[inline(always)]
fn within_pieces(plan: AxisPlan, p: i64) -> (i64, i64, i64) {
    match plan {
        AxisPlan::InRange(lo, hi) => (lo, hi, 0),
        // rest <= r0 < p <= 2^55: the bit pattern is the value.
        AxisPlan::Split(AxisSplit::Periodic { r0, rest, .. }) => (r0, p, rest.cast_signed()),
        _ => (0, 0, 0),
    }
}

/// [`sum`] for [`crate::RepeatWithinPeriod`]: a box at most one period long on each axis
/// crossing the edge is at most 2 x 2 in-range pieces, each of multiplicity 1 (Crow §2.4's
/// pieces with no whole periods): no division, no multiply. The driver has refused a longer
/// box ([`super::refuse_longer_than_period`]). The pieces are visited in [`sum`]'s order (`x`
/// outer, `y` inner), so the reads come in the same sequence, and their sums are added with
/// checked arithmetic, as in [`sum`]. It also takes a box placed in range (the driver sends
/// every `RepeatWithinPeriod` box here): that is its one piece, read by one call and no loop.
/// Inlined into the driver, so a firmware holds one call site of the lookup and one copy of
/// the driver's checks (Stable + `RepeatWithinPeriod` on the Cortex-M4: 224 bytes less than an
/// in-range branch of its own beside an out-of-line `sum_within`, 12 instructions more per
/// in-period lookup; docs/firmware.md).
#[inline(always)]
pub(crate) fn sum_within<L: Layout<C>, Fm: FormImpl, K: Counter, const C: usize>(
    layout: &L,
    px: AxisPlan,
    py: AxisPlan,
    f: u32,
    form: Fm,
    k: &mut K,
) -> Result<[WideOf<L, C>; C], Error> {
    #[allow(
        clippy::as_conversions,
        reason = "sides <= 2^31 - 1 (check_dimensions) and f <= MAX_FRAC_BITS = 24: lossless, and \
                  the shifted values stay below 2^55"
    )]
    let (pw, ph) = ((layout.width() as i64) << f, (layout.height() as i64) << f);
    let (xa, xb, xc) = within_pieces(px, pw);
    let (ya, yb, yc) = within_pieces(py, ph);
    if xc == 0 && yc == 0 {
        // Both axes in range (a split axis has a tail, `rest > 0`): the one piece, non-empty
        // (the driver returns before any lookup for an empty box).
        let one = RawBox {
            x0: xa,
            y0: ya,
            x1: xb,
            y1: yb,
        };
        return in_range_wide(layout, &one, f, form, k);
    }
    let mut acc = [<WideOf<L, C> as Wide>::ZERO; C];
    let mut first = true;
    // Piece i: x head (i & 2 == 0) or tail, y head (i & 1 == 0) or tail. No tail on an axis:
    // its tail pieces are skipped without a visit (an in-range box is one iteration).
    let (step, end) = (if yc > 0 { 1 } else { 2 }, if xc > 0 { 4 } else { 2 });
    let mut i = 0u32;
    while i < end {
        let (x0, x1) = if i & 2 == 0 { (xa, xb) } else { (0, xc) };
        let (y0, y1) = if i & 1 == 0 { (ya, yb) } else { (0, yc) };
        i = i.saturating_add(step);
        if x1 <= x0 || y1 <= y0 {
            continue;
        }
        let v = in_range_wide(layout, &RawBox { x0, y0, x1, y1 }, f, form, k)?;
        if !first {
            k.adds(const { per_channel(1, C) });
        }
        first = false;
        for (o, v) in acc.iter_mut().zip(v) {
            *o = o.checked_add(v).ok_or_else(overflow::<WideOf<L, C>>)?;
        }
    }
    Ok(acc)
}
