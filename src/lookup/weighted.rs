//! The weighted path for boxes with no in-range equivalent (clamp, repeat and mirror boxes that
//! straddle an edge of the texture).
//!
//! `2^2F S_ext(x, y) = sum_a sum_b wx_a wy_b S(cx_a, cy_b)` with each axis' terms from
//! [`EdgeMode::axis_terms`] (at most 3 per axis, so at most 9 reads per corner and 36 per box;
//! zero weights and the zero row and column are skipped; `docs/design.md` lists the counts). The
//! weights grow with the number of periods a box covers, so this path runs in checked `i128`
//! arithmetic: a box too large for it is [`Error::TooWide`], never a wrapped sum.

use crate::cost::Counter;
use crate::edge::EdgeMode;
use crate::error::{Error, Quantity};
use crate::layouts::Layout;
use crate::rect::RawBox;
use crate::texel::Entry;

fn overflow() -> Error {
    Error::TooWide {
        what: Quantity::LookupAccumulator,
        bits_needed: 128,
        bits_available: 127,
    }
}

/// On a modular layout the values are residues: the sum runs in wrapping `i128` arithmetic and is
/// reduced modulo `2^k` at the end, exact because the driver has checked that the scaled box sum
/// (`box sum * 2^2F`) is below `2^k`.
pub(crate) fn sum<M: EdgeMode, L: Layout<C>, K: Counter, const C: usize>(
    t: &L,
    b: &RawBox,
    f: u32,
    k: &mut K,
) -> Result<[u128; C], Error> {
    let (w, h) = (t.width(), t.height());
    let modulus = t.modulus();
    let xs = [M::axis_terms(b.x0, w, f), M::axis_terms(b.x1, w, f)];
    let ys = [M::axis_terms(b.y0, h, f), M::axis_terms(b.y1, h, f)];
    let mut acc = [0i128; C];
    for (xi, xt) in xs.iter().enumerate() {
        for (yi, yt) in ys.iter().enumerate() {
            // + for (x1, y1) and (x0, y0), - for the mixed corners.
            let positive = xi == yi;
            for &(cx, wx) in xt.as_slice() {
                for &(cy, wy) in yt.as_slice() {
                    let e = t.corner(cx, cy, k);
                    k.muls(1 + C as u32);
                    k.adds(C as u32);
                    if modulus.is_some() {
                        let weight = wx.wrapping_mul(wy);
                        for c in 0..C {
                            let term = weight.wrapping_mul(e[c].to_u128() as i128);
                            acc[c] = if positive {
                                acc[c].wrapping_add(term)
                            } else {
                                acc[c].wrapping_sub(term)
                            };
                        }
                        continue;
                    }
                    let weight = wx.checked_mul(wy).ok_or_else(overflow)?;
                    for c in 0..C {
                        let term = weight
                            .checked_mul(e[c].to_u128() as i128)
                            .ok_or_else(overflow)?;
                        acc[c] = if positive {
                            acc[c].checked_add(term)
                        } else {
                            acc[c].checked_sub(term)
                        }
                        .ok_or_else(overflow)?;
                    }
                }
            }
        }
    }
    let mut out = [0u128; C];
    for c in 0..C {
        out[c] = if let Some(m) = modulus {
            (acc[c] as u128) & ((1u128 << m) - 1)
        } else {
            // The extended texture is non-negative, so a proper box integral is >= 0.
            u128::try_from(acc[c]).map_err(|_| overflow())?
        };
    }
    Ok(out)
}
