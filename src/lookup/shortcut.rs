//! Crow's large-footprint shortcut (§2.2): "where the texture is highly compressed ... the effect
//! of interpolation at the corners [is] negligible", so 4 reads replace 16.
//!
//! ## The bound
//! Round each corner to the nearest integer (ties up), giving the box `R` for the true box `B`.
//! Let `I = B ∩ R`, `m = 2^b - 1` the largest texel, and `W, H >= 2` the sides of `B`. Each edge
//! moves by at most 1/2, so `I` has sides at least `W - 1` and `H - 1`, and
//! `|B \ I| / |B| <= 1/W + 1/H`, `|R \ I| / |R| <= 1/(W-1) + 1/(H-1)` (as `R`'s sides are at least
//! `W - 1`, `H - 1`). Writing both means as convex combinations of the mean over `I` (`c`) and of
//! their own remainders, `mean_B - mean_R = wB (u - c) - wR (v - c)` with all means in `[0, m]`,
//! which is at most `m * max(wB, wR)` in magnitude. Hence
//!
//! `|mean_B - mean_R| <= m * (1/(W-1) + 1/(H-1)) <= 2m / (s - 1)` when `W, H >= s`,
//!
//! plus the output rounding of the mean (`2^-(g+1)`). The bound is reached up to a factor
//! `(s-1)/s`: a box whose four edges all round inward by 1/2 over a texture that is `m` exactly
//! under the lost strips and 0 elsewhere (tested in `host-tests`).
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use super::corners4::Corners4;
use super::{sum_raw, Form, WideOf};
use crate::cost::Counter;
use crate::edge::{width_u64, EdgeMode};
use crate::error::Error;
use crate::layouts::Layout;
use crate::rect::{FracBits, Rect};
use crate::width::max_texel_u64;

/// When to take the 4-read shortcut: boxes whose sides are both at least `min_side` texels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Shortcut {
    min_side: u64,
}

impl Shortcut {
    /// Shortcut for sides of at least `min_side` texels (at least 2).
    pub const fn with_min_side(min_side: u64) -> Self {
        Shortcut {
            min_side: if min_side < 2 { 2 } else { min_side },
        }
    }

    /// The smallest side length for which the shortcut's mean error is at most
    /// `tol_num / tol_den` texel units (excluding the output rounding), for `texel_bits`-bit
    /// texels: `s = ceil(2 m tol_den / tol_num) + 1`. A zero tolerance never takes the shortcut.
    pub const fn for_tolerance(texel_bits: u32, tol_num: u64, tol_den: u64) -> Self {
        if tol_num == 0 {
            return Shortcut { min_side: u64::MAX };
        }
        let need = max_texel_u64(texel_bits)
            .saturating_mul(2)
            .saturating_mul(tol_den);
        let s = need.div_ceil(tol_num).saturating_add(1);
        Shortcut {
            min_side: if s < 2 { 2 } else { s },
        }
    }

    /// The side length from which the shortcut is taken.
    pub const fn min_side(&self) -> u64 {
        self.min_side
    }

    /// The proven bound `m (1/(W-1) + 1/(H-1))` on the shortcut's mean error for a box of sides
    /// `W, H >= 2` texels, as `f64` (for reports and tests).
    #[allow(
        clippy::as_conversions,
        reason = "a float bound for reports: exact for texel widths up to 53 bits (the crate's texels \
                  have at most 16), rounded to nearest above (no From<u64> for f64)"
    )]
    pub fn error_bound(texel_bits: u32, w: f64, h: f64) -> f64 {
        max_texel_u64(texel_bits) as f64 * (1.0 / (w - 1.0) + 1.0 / (h - 1.0))
    }
}

/// A mean from [`crate::Sat::box_mean_shortcut`], and whether the shortcut answered it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShortcutMean<W, const C: usize> {
    /// Per channel, the mean times `2^g`, rounded to nearest (ties up).
    pub means: [W; C],
    /// True if the 4-read shortcut was taken.
    pub shortcut: bool,
}

impl<W: Into<u128> + Copy, const C: usize> ShortcutMean<W, C> {
    /// The same means as `u128` (host-side convenience).
    pub fn to_u128(&self) -> ShortcutMean<u128, C> {
        ShortcutMean {
            means: self.means.map(Into::into),
            shortcut: self.shortcut,
        }
    }
}

/// Rounds a raw coordinate to the nearest integer, ties up (toward +infinity); `None` past
/// the `i64` range.
fn round_raw(x: i64, f: u32) -> Option<i64> {
    if f == 0 {
        Some(x)
    } else {
        #[allow(clippy::arithmetic_side_effects, reason = "f >= 1 in this branch")]
        let half = 1i64 << (f - 1);
        Some(x.checked_add(half)? >> f)
    }
}

/// [`crate::BoxLookup::box_mean_shortcut`]: the mean over the box with `out_frac_bits`
/// fractional bits, by the 4-read shortcut when both sides are at least `shortcut.min_side()`
/// texels (then within the bound in the module docs of the exact mean), else by the exact
/// 16-read lookup in form `Fm`.
///
/// Shortcut cost: 4 reads, 3 additive, 1 multiply (area), 1 divide per channel: Crow's
/// "4 texture accesses, two multiplicative operations and 3 additive operations".
#[allow(clippy::too_many_arguments)]
pub(crate) fn mean<L: Layout<C>, Fm: Form, M: EdgeMode, K: Counter, const C: usize>(
    layout: &L,
    r: &Rect<i64>,
    frac_bits: FracBits,
    form: Fm,
    mode: M,
    shortcut: &Shortcut,
    out_frac_bits: u32,
    k: &mut K,
) -> Result<ShortcutMean<WideOf<L, C>, C>, Error> {
    let f = frac_bits.get();
    if r.x1 < r.x0 || r.y1 < r.y0 {
        return Err(Error::InvertedBox);
    }
    if M::WITHIN_PERIOD {
        // Before the rounding to whole texels, which could shorten a longer box to a period.
        super::refuse_longer_than_period(layout, width_u64(r.x0, r.x1), width_u64(r.y0, r.y1), f)?;
    }
    let min_raw = shortcut.min_side.saturating_mul(1u64 << f);
    if width_u64(r.x0, r.x1) >= min_raw && width_u64(r.y0, r.y1) >= min_raw {
        let round = |v: i64| round_raw(v, f).ok_or(Error::CoordinateOutOfRange);
        let b = Rect::new(round(r.x0)?, round(r.y0)?, round(r.x1)?, round(r.y1)?);
        let sum = sum_raw(layout, &b, 0, Corners4, mode, k)?;
        let means = sum.means_rounded(out_frac_bits, k)?;
        return Ok(ShortcutMean {
            means,
            shortcut: true,
        });
    }
    let sum = sum_raw(layout, r, f, form, mode, k)?;
    Ok(ShortcutMean {
        means: sum.means_rounded(out_frac_bits, k)?,
        shortcut: false,
    })
}
