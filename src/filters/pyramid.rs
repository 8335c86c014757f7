//! What the three image pyramids share: the mip map (`mip`), the ripmap (`rip`) and the dipmap
//! (`dip`). Each keeps its own layout, level selection and blend; this module holds the
//! mechanisms they have in common, written once:
//!
//! * level sizes: level `l` of an axis of `n` texels has `ceil(n / 2^l)` texels, down to 1
//!   ([`level_len`], [`level_count`]);
//! * the box-average level build: texel `(i, j)` of a level that shrinks x by `2^sx` and y by
//!   `2^sy` is the average of the base texels of `[i 2^sx, (i+1) 2^sx) x [j 2^sy, (j+1) 2^sy)`
//!   *clipped to the texture*, computed from the exact integer sum of the **base** texels (never
//!   from another level) and rounded to nearest, ties up:
//!   `round(sum / count) = floor((2 sum + count) / (2 count))`. Every stored texel is within
//!   1/2 LSB of the exact box average; nothing accumulates from level to level
//!   ([`fill_box_level`]);
//! * the footprint: validated raw corners, centre and side lengths ([`footprint`]), and the level
//!   position `L = clamp(log2_fixed(side), 0, top)` split into `floor(L)`,
//!   `min(floor(L) + 1, top)` and `frac(L)` ([`level_position`], [`split_level`]);
//! * the bilinear taps: level texel `i` covers base `[i 2^s, (i+1) 2^s)`, so its centre is
//!   `(i + 1/2) 2^s` and a probe at centre `c` interpolates the texels around `c / 2^s - 1/2`:
//!   left tap `floor(c / 2^s - 1/2)`, weight its fraction truncated to a filter's weight bits
//!   ([`split_position`]);
//! * Crow's lerp `b + (c - b) alpha` (1 multiply, 2 additive operations per channel, §2.2; a
//!   bilinear is 3 lerps) in `u64` ([`lerp`]), and the read count (all channels of a texel
//!   together, [`count_reads`]);
//! * for the rip and dip maps, which store every level in caller storage: the storage layout
//!   helpers, the build checks, and the stored level with its bilinear probe (`LevelView`).
//!
//! ## Widths (no integer wider than 64 bits)
//!
//! Raw corners are `i64` with `F <= 24` fraction bits. The centre is kept as
//! `floor((x0 + x1) / 2)` and the parity of `x0 + x1` ([`Centre`]), both exact in `i64` for any
//! corners (`(x0 >> 1) + (x1 >> 1) + (x0 & x1 & 1)` cannot overflow), so the doubled centre
//! `x0 + x1` (65 bits) is never formed. Sides `x1 - x0` are exact in `u64`. A level position
//! `c / 2^l - 1/2` with `s = F + 1 + l <= 56` fraction bits splits into a left tap in `i64` and a
//! fraction below `2^56`; the one tap index that leaves `i64` (the corners `x0 = x1 = i64::MIN`
//! at `F = 0`, level 0) is [`Error::CoordinateOutOfRange`]. Level texels are below `2^16` and
//! every lerp is a convex combination of non-negative values, computed in wrapping `u64`
//! arithmetic: exact whenever the result is below `2^64` (each filter states its bound).
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::cost::Counter;
use crate::edge::EdgeKind;
use crate::error::Error;
use crate::filters::level::log2_fixed;
use crate::filters::{per_channel, u64_from_usize};
#[cfg(test)]
use crate::rect::Coord;
use crate::rect::{FracBits, Rect};
use crate::texel::Texel;
use crate::texture::Texture;
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
use crate::{edge::EdgeMode, error::Quantity, filters::Sample, width::bits_of_u64};
use core::num::NonZeroU64;

/// The most levels an axis can have: sides up to `2^31 - 1` texels halve to 1 in 31 steps, so
/// they need levels `0..=31`.
pub(crate) const MAX_LEVELS: usize = 32;

/// Coarse columns summed together in one pass of the level build (stack accumulators).
const CHUNK: usize = 16;

/// `ceil(n / 2^l)` for `n >= 1` (1 for `n = 0`, which no texture has).
#[inline(always)]
pub(crate) fn level_len(n: usize, l: usize) -> usize {
    #[allow(clippy::as_conversions, reason = "usize::BITS <= 64: lossless")]
    let bits = usize::BITS as usize;
    if l >= bits {
        1
    } else {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "n.saturating_sub(1) <= usize::MAX - 1, so + 1 cannot overflow"
        )]
        let len = (n.saturating_sub(1) >> l) + 1;
        len
    }
}

/// Levels of an axis of `n >= 1` texels: `ceil(log2 n) + 1`.
#[inline(always)]
pub(crate) fn level_count(n: usize) -> usize {
    #[allow(
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "leading_zeros <= usize::BITS <= 64: the difference is in [0, 64], + 1 <= 65"
    )]
    let count = (usize::BITS - n.saturating_sub(1).leading_zeros()) as usize + 1;
    count
}

/// Refuses dimensions a texture could not have: the crate's one size check
/// ([`crate::texture`]'s `check_dimensions`, one channel).
#[inline]
pub(crate) fn check_dims(width: usize, height: usize) -> Result<(), Error> {
    crate::texture::check_dimensions(width, height, 1)
}

/// Fills `out` (`lw * lh * C` elements, row-major, `lw = ceil(w / 2^sx)`, `lh = ceil(h / 2^sy)`)
/// with the box averages of the base blocks of `2^sx x 2^sy` texels, clipped to the texture,
/// each `round(sum / count) = floor((2 sum + count) / (2 count))` (ties up) of the exact sum in
/// `u64`, `CHUNK` coarse columns per pass over the block's base rows. Every base texel is read
/// once per level.
///
/// The caller proved `2 sum + count < 2^64` for every block (the rip and dip builds: `(2m + 1) w h
/// < 2^64`; the mip build: `2^(B+1) w h < 2^64`), and `sx, sy <= 31` (levels of a side below
/// `2^31`). A block is never empty (`i < ceil(n / 2^s)` gives `i 2^s < n`), so `count >= 1`; the
/// division is by a [`NonZeroU64`] all the same.
pub(crate) fn fill_box_level<T: Texel, const C: usize>(
    texture: &Texture<'_, T, C>,
    out: &mut [T],
    sx: usize,
    sy: usize,
) -> Result<(), Error> {
    let (w, h) = (texture.width(), texture.height());
    let (lw, lh) = (level_len(w, sx), level_len(h, sy));
    #[allow(clippy::as_conversions, reason = "both <= 63: lossless")]
    let (sx, sy) = (sx.min(63) as u32, sy.min(63) as u32);
    // Block bounds in base texels: i < ceil(n / 2^s), so i 2^s < n <= 2^31 and (i + 1) 2^s
    // < 2^33 (s <= 31): all in u64, the clipped ends in usize.
    let span = |i: usize, s: u32, n: usize| -> (usize, usize) {
        let (i, n64) = (u64_from_usize(i), u64_from_usize(n));
        let lo = i.checked_shl(s).unwrap_or(u64::MAX).min(n64);
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "i < ceil(n / 2^s) <= 2^31 (the level's size): i + 1 <= 2^31"
        )]
        let hi = (i + 1).checked_shl(s).unwrap_or(u64::MAX).min(n64);
        #[allow(
            clippy::as_conversions,
            reason = "lo, hi <= n, a usize (the min above): lossless"
        )]
        let ends = (lo as usize, hi as usize);
        ends
    };
    let needed = lw.saturating_mul(lh).saturating_mul(C);
    let got = out.len();
    let out = out
        .get_mut(..needed)
        .ok_or(Error::StorageTooSmall { needed, got })?;
    let mut dst_rows = out.chunks_exact_mut(lw.saturating_mul(C).max(1));
    for j in 0..lh {
        let (y_lo, y_hi) = span(j, sy, h);
        let dst_row = dst_rows.next().ok_or(Error::EmptyTexture)?;
        let mut i0 = 0;
        // (A compile-time constant: a channel count whose chunk overflows usize stops the build.)
        for dst in dst_row.chunks_mut(const { CHUNK * C }) {
            let mut acc = [[0u64; C]; CHUNK];
            for y in y_lo..y_hi {
                // y < h and the block columns lie below w: rows and slices always exist (the
                // errors are unreachable; they stand in for panics).
                let row = texture.row(y).ok_or(Error::EmptyTexture)?;
                #[allow(
                    clippy::arithmetic_side_effects,
                    reason = "C >= 1 (a Texture exists: check_dimensions refuses 0 channels)"
                )]
                let texels = dst.len() / C;
                for (ci, a) in acc.iter_mut().take(texels).enumerate() {
                    #[allow(
                        clippy::arithmetic_side_effects,
                        reason = "i0 + ci < lw <= 2^31 (a coarse column of this level)"
                    )]
                    let (x_lo, x_hi) = span(i0 + ci, sx, w);
                    #[allow(
                        clippy::arithmetic_side_effects,
                        reason = "x_lo <= x_hi <= w and w * C fits (Texture::with_stride's \
                                  checked_mul)"
                    )]
                    let px = row.get(x_lo * C..x_hi * C).ok_or(Error::EmptyTexture)?;
                    for texel in px.chunks_exact(C) {
                        for (s, t) in a.iter_mut().zip(texel) {
                            *s = s.wrapping_add(u64::from(t.to_u16()));
                        }
                    }
                }
            }
            for (ci, (a, d)) in acc.iter().zip(dst.chunks_exact_mut(C)).enumerate() {
                #[allow(
                    clippy::arithmetic_side_effects,
                    reason = "i0 + ci < lw <= 2^31 (a coarse column of this level); span's ends \
                              are monotone in i, so x_lo <= x_hi and y_lo <= y_hi"
                )]
                let cnt = {
                    let (x_lo, x_hi) = span(i0 + ci, sx, w);
                    u64_from_usize(x_hi - x_lo).wrapping_mul(u64_from_usize(y_hi - y_lo))
                };
                let den = NonZeroU64::new(cnt.wrapping_mul(2)).ok_or(Error::EmptyTexture)?;
                for (d, &s) in d.iter_mut().zip(a.iter()) {
                    // 2 s + cnt < 2^64 (the caller's proof); the mean is at most m = 2^B - 1.
                    let mean = s.wrapping_mul(2).wrapping_add(cnt) / den;
                    *d = T::from_u16_clamped(u16::try_from(mean).unwrap_or(u16::MAX));
                }
            }
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "i0 < lw <= 2^31 before the step: i0 + 16 fits usize"
            )]
            {
                i0 += CHUNK;
            }
        }
    }
    Ok(())
}

/// A footprint centre along one axis, `(x0 + x1) / 2` in raw units, kept as
/// `mid = floor((x0 + x1) / 2)` and `odd = (x0 + x1) mod 2`: exact in `i64` for any `i64`
/// corners, where the sum `x0 + x1` itself needs 65 bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Centre {
    /// `floor((x0 + x1) / 2)`.
    pub(crate) mid: i64,
    /// `(x0 + x1) mod 2`: 0 or 1.
    pub(crate) odd: u64,
}

impl Centre {
    /// The centre of `[lo, hi)`, without overflow.
    #[inline(always)]
    pub(crate) fn of(lo: i64, hi: i64) -> Centre {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "lo >> 1 and hi >> 1 lie in [-2^62, 2^62 - 1]: their sum in [-2^63, 2^63 - 2], \
                      plus 0 or 1, stays in i64"
        )]
        let mid = (lo >> 1) + (hi >> 1) + (lo & hi & 1);
        Centre {
            mid,
            odd: ((lo ^ hi) & 1).cast_unsigned(),
        }
    }

    /// `floor(c / 2^s) = floor((x0 + x1) / 2^(s + 1))`: the index of the texel of a level that
    /// shrinks by `2^(s - F)` holding the centre (`s >= 0`).
    #[cfg(any(feature = "filter-mip", test))]
    #[inline(always)]
    pub(crate) fn index(self, s: u32) -> i64 {
        self.mid >> s.min(63)
    }
}

/// A validated footprint `[x0, x1) x [y0, y1)`, raw fixed-point values with `f` fraction bits.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Footprint {
    /// The centre along x.
    pub(crate) cx: Centre,
    /// The centre along y.
    pub(crate) cy: Centre,
    /// The width `W = x1 - x0` (raw), exact in `u64`.
    pub(crate) w: u64,
    /// The height `H = y1 - y0` (raw).
    pub(crate) h: u64,
    /// Fraction bits `F` of the corners (at most 24).
    pub(crate) f: u32,
}

/// Validates a footprint: [`Error::FracBitsUnsupported`] for `F > 24`, [`Error::InvertedBox`]
/// for `x1 < x0` or `y1 < y0`. Returns its centre and sides (never overflows: [`Centre`]).
#[cfg(test)]
pub(crate) fn footprint<X: Coord>(rect: &Rect<X>) -> Result<Footprint, Error> {
    footprint_raw(&rect.to_raw(), FracBits::of::<X>()?)
}

/// [`footprint`] of raw corners with `F` given as a value.
#[inline(always)]
pub(crate) fn footprint_raw(rect: &Rect<i64>, f: FracBits) -> Result<Footprint, Error> {
    let f = f.get();
    let (x0, y0, x1, y1) = (rect.x0, rect.y0, rect.x1, rect.y1);
    if x1 < x0 || y1 < y0 {
        return Err(Error::InvertedBox);
    }
    Ok(Footprint {
        cx: Centre::of(x0, x1),
        cy: Centre::of(y0, y1),
        w: x1.cast_unsigned().wrapping_sub(x0.cast_unsigned()),
        h: y1.cast_unsigned().wrapping_sub(y0.cast_unsigned()),
        f,
    })
}

/// The level position of a side of `side / 2^f` texels (`side` raw) with `frac_bits` fraction
/// bits: `log2_fixed` (the exact `floor` or one unit below; exact at powers of two) clamped to
/// `[0, top 2^frac_bits]`; `0` for a side of 0 (and at most one texel). `top <= 31` and
/// `frac_bits <= 16`, so the result fits comfortably in 32 bits.
#[inline(always)]
pub(crate) fn level_position(side: u64, f: u32, frac_bits: u32, top: u32) -> u32 {
    let max = top.min(31).cast_signed() << frac_bits.min(16);
    // In [0, max]: non-negative, so the reinterpretation is the value.
    log2_fixed(side, f, frac_bits)
        .unwrap_or(0)
        .max(0)
        .min(max)
        .cast_unsigned()
}

/// Splits a level position `L` (`frac_bits` fraction bits, at most `top 2^frac_bits`) into
/// `(lo, hi, frac)`: `lo = floor(L)`, `hi = min(lo + 1, top)`, `frac = frac(L)` (exact).
#[inline(always)]
pub(crate) fn split_level(pos: u32, frac_bits: u32, top: u32) -> (u32, u32, u64) {
    let fb = frac_bits.min(31);
    let lo = pos >> fb;
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "fb <= 31: 2^fb >= 1; pos <= top 2^frac_bits (level_position), so lo <= 31"
    )]
    let (mask, hi) = ((1 << fb) - 1, (lo + 1).min(top));
    (lo, hi, u64::from(pos & mask))
}

/// Splits the level position `u = c / 2^s - 1/2` of a centre `c` (raw, [`Centre`]; `s = F + l`
/// for level `l`, so `u` has `s + 1 <= 56` fraction bits) into the left texel of the bilinear
/// pair, `floor(u)`, and the weight of the right one, `frac(u)` truncated to `weight_bits` bits
/// (exact when `s + 1 <= weight_bits`).
///
/// With `mid = q 2^s + r` (`0 <= r < 2^s`) the doubled position is
/// `2 u 2^s = (x0 + x1) - 2^s = q 2^(s+1) + (2r + odd - 2^s)`, so the left tap is `q` or `q - 1`
/// after one comparison; `q - 1` leaves `i64` only for `mid = i64::MIN` at `s = 0`:
/// [`Error::CoordinateOutOfRange`].
#[inline(always)]
pub(crate) fn split_position(c: Centre, s: u32, weight_bits: u32) -> Result<(i64, u64), Error> {
    // The common case on a microcontroller's texture, in 32-bit words (the same steps; a
    // Cortex-M4 shifts a 64-bit word by a variable amount in about six instructions, a 32-bit
    // one in one): a centre that fits `i32` and `s <= 30`, so `2 r + odd < 2^31`, `frac <
    // 2^(s + 1) <= 2^31`; and `weight_bits <= 32`, so the weight, below `2^weight_bits`,
    // is shifted in 32 bits either way. `q - 1` is formed in `i64` (no overflow).
    if let (Ok(mid), true, true) = (i32::try_from(c.mid), s <= 30, weight_bits <= 32) {
        #[allow(
            clippy::arithmetic_side_effects,
            clippy::as_conversions,
            reason = "s <= 30: 2^s >= 1, r < 2^30 and odd is 0 or 1 (so its u32 is lossless), \
                      twice < 2^31 and twice + half < 2^31 + 2^30; twice - half only when \
                      twice >= half; q - 1 in i64 from an i32; bits = s + 1 <= 31 and each \
                      difference of bits and weight_bits is taken on the side where it is >= 0"
        )]
        let (i0, a) = {
            let q = mid >> s;
            let r = mid.cast_unsigned() & ((1u32 << s) - 1);
            let twice = 2 * r + c.odd as u32;
            let half = 1u32 << s;
            let (i0, frac) = if twice >= half {
                (i64::from(q), twice - half)
            } else {
                (i64::from(q) - 1, twice + half)
            };
            let bits = s + 1;
            let a = if bits >= weight_bits {
                frac >> (bits - weight_bits).min(31)
            } else {
                frac << (weight_bits - bits).min(31)
            };
            (i0, a)
        };
        return Ok((i0, u64::from(a)));
    }
    let s = s.min(62);
    let q = c.mid >> s;
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "s <= 62: 2^s >= 1; r < 2^62 and odd <= 1, so twice < 2^63 + 1 and \
                  twice + half < 2^63 + 2^62; twice - half only when twice >= half"
    )]
    let (twice, half) = {
        // Masked to s bits: non-negative, so the reinterpretation is the value.
        let r = (c.mid & ((1i64 << s) - 1)).cast_unsigned();
        (2 * r + c.odd, 1u64 << s) // twice < 2^(s+1)
    };
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "twice - half only when twice >= half; twice + half < 2^(s+1) + 2^s <= 2^64"
    )]
    let (i0, frac) = if twice >= half {
        (q, twice - half)
    } else {
        (
            q.checked_sub(1).ok_or(Error::CoordinateOutOfRange)?,
            twice + half,
        )
    };
    // frac has s + 1 fraction bits.
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "s <= 62: bits <= 63; each difference is taken on the side where it is >= 0"
    )]
    let a = {
        let bits = s + 1;
        if bits >= weight_bits {
            frac >> (bits - weight_bits)
        } else {
            frac << (weight_bits - bits)
        }
    };
    Ok((i0, a))
}

/// The texel index the mode `kind` shows at `i` on an axis of `n` texels
/// ([`EdgeKind::texel_index`]), with the in-range case (the common one) decided here by one
/// comparison: every mode shows texel `i` for `0 <= i < n`.
#[inline(always)]
pub(crate) fn tap_index(kind: EdgeKind, i: i64, n: usize) -> Option<usize> {
    if i.cast_unsigned() < u64_from_usize(n) {
        #[allow(
            clippy::as_conversions,
            reason = "0 <= i < n, a usize (the comparison above): lossless"
        )]
        Some(i as usize)
    } else {
        kind.texel_index(i, n)
    }
}

/// Crow's lerp `b * 2^bits + (c - b) * a` per channel (`a` a weight with `bits` fraction bits,
/// `a <= 2^bits`): 1 multiply and 2 additive operations per channel; the scale by `2^bits` is a
/// shift (wiring). In wrapping `u64` arithmetic: the result `b (2^bits - a) + c a` is exact
/// whenever it is below `2^64` (the difference `c - b` may wrap; the sum is right modulo `2^64`
/// and lies in `[0, 2^64)`), i.e. whenever `max(b, c) 2^bits < 2^64`.
#[inline(always)]
pub(crate) fn lerp<K: Counter, const C: usize>(
    b: [u64; C],
    c: [u64; C],
    a: u64,
    bits: u32,
    k: &mut K,
) -> [u64; C] {
    k.muls(const { per_channel(1, C) });
    k.adds(const { per_channel(2, C) });
    let bits = bits.min(63);
    let mut out = b;
    for (o, c) in out.iter_mut().zip(c) {
        *o = (*o << bits).wrapping_add(c.wrapping_sub(*o).wrapping_mul(a));
    }
    out
}

/// Counts `N` texel reads: all channels of a texel together (`T::BITS * C` bits), and the
/// 32-bit words they take; all compile-time constants ([`per_channel`]: a product past `u32`
/// stops the build).
#[inline(always)]
pub(crate) fn count_reads<T: Texel, const C: usize, const N: u32, K: Counter>(k: &mut K) {
    k.reads(N, const { per_channel(T::BITS, C) });
    k.words(const { N * per_channel(T::BITS, C).div_ceil(32) });
}

/// Prefix sums of the level lengths of an axis of `n` texels (`1 <= n <= 2^31 - 1`, so
/// `levels <= 32` and the total `< 2n + 32` fits `usize`): `cum[l] = sum_{k < l} ceil(n / 2^k)`
/// for `l = 0..=levels`, so the number of levels is `cum.len() - 1`.
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) fn prefix(n: usize) -> heapless::Vec<usize, { MAX_LEVELS + 1 }> {
    let mut cum = heapless::Vec::new();
    let mut total = 0usize;
    // A full vector only drops levels past 32, which no side below 2^31 has.
    let _ = cum.push(0);
    for l in 0..level_count(n).min(MAX_LEVELS) {
        total = total.saturating_add(level_len(n, l));
        let _ = cum.push(total);
    }
    cum
}

/// `sum_l ceil(n / 2^l)` over the levels of an axis, saturating.
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) fn axis_total(n: usize) -> usize {
    let mut t = 0usize;
    for l in 0..level_count(n) {
        t = t.saturating_add(level_len(n, l));
    }
    t
}

/// `2^e`, or `u64::MAX` for `e >= 64`, where it does not fit: the rip and dip maps' error
/// bounds, which must only grow with the texel width.
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) const fn pow2_or_max(e: u32) -> u64 {
    match 1u64.checked_shl(e) {
        Some(v) => v,
        None => u64::MAX,
    }
}

/// `(2^bits - 1) 2^s`, or `u64::MAX` where it does not fit `u64` (`bits + s > 64`, `bits > 0`).
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) const fn mask_shl_or_max(bits: u32, s: u32) -> u64 {
    let m = match 1u64.checked_shl(bits) {
        #[allow(clippy::arithmetic_side_effects, reason = "p = 2^bits >= 1")]
        Some(p) => p - 1,
        None => u64::MAX,
    };
    match u64::MAX.checked_shr(s) {
        Some(room) if m <= room => m << s,
        _ => u64::MAX,
    }
}

/// Refuses storage shorter than `needed`: [`Error::StorageTooSmall`].
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) fn check_storage(needed: usize, got: usize) -> Result<(), Error> {
    if got < needed {
        return Err(Error::StorageTooSmall { needed, got });
    }
    Ok(())
}

/// The checks of a rip or dip build, in order: the dimensions ([`check_dims`]); that
/// `2 * sum + count` of any block fits `u64`, `(2m + 1) w h < 2^64` with `m = 2^texel_bits - 1`
/// (else [`Error::TooWide`], `Quantity::Entry`, 64 bits available); the storage length.
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) fn check_build(
    texel_bits: u32,
    width: usize,
    height: usize,
    needed: usize,
    got: usize,
) -> Result<(), Error> {
    check_dims(width, height)?;
    // texel_bits <= 16 and w, h < 2^31: (2m + 1) < 2^17 and w h < 2^62, so only the last
    // product can overflow u64.
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "2^min(bits, 16) >= 1, so m < 2^16 and 2m + 1 < 2^17; w, h < 2^31 \
                  (check_dims): w h < 2^62"
    )]
    let (a, area) = {
        let m = (1u64 << texel_bits.min(16)) - 1;
        (2 * m + 1, u64_from_usize(width) * u64_from_usize(height))
    };
    if a.checked_mul(area).is_none() {
        // The exact bits of a * area (< 2^79) from 32-bit halves of area: no 128-bit product.
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "a < 2^17 and area < 2^62: lo < 2^49, hi < 2^47 + 2^17, 32 + bits <= 96"
        )]
        let bits_needed = {
            let lo = a * (area & 0xFFFF_FFFF);
            let hi = a * (area >> 32) + (lo >> 32);
            32 + bits_of_u64(hi)
        };
        return Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed,
            bits_available: 64,
        });
    }
    check_storage(needed, got)
}

/// Level position of a side of `side_raw / 2^f` texels on an axis whose top level is `top`:
/// `(lo, hi, frac)` with `L = clamp(log2_fixed(side), 0, top)`, `lo = floor(L)`,
/// `hi = min(lo + 1, top)`, `frac` in `frac_bits` bits ([`level_position`], [`split_level`]).
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
#[inline(always)]
pub(crate) fn level_split(side_raw: u64, f: u32, frac_bits: u32, top: u32) -> (u32, u32, u64) {
    split_level(level_position(side_raw, f, frac_bits, top), frac_bits, top)
}

/// Each channel shifted right by `s` (a truncation, floor).
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
#[inline(always)]
pub(crate) fn truncate<const C: usize>(v: [u64; C], s: u32) -> [u64; C] {
    v.map(|c| c >> s.min(63))
}

/// The output sample `floor(v / 2^shift)` per channel.
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
#[inline(always)]
pub(crate) fn floor_sample<const C: usize>(v: [u64; C], shift: u32) -> Sample<C> {
    Sample {
        values: truncate(v, shift),
    }
}

/// One stored level of a rip or dip map: `w x h` texels, row-major, `C` channels.
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
#[derive(Clone, Copy)]
pub(crate) struct LevelView<'a, T, const C: usize> {
    /// The level's texels (empty if the storage does not hold them).
    pub(crate) data: &'a [T],
    /// Width in texels.
    pub(crate) w: usize,
    /// Height in texels.
    pub(crate) h: usize,
}

#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
impl<T: Texel, const C: usize> LevelView<'_, T, C> {
    /// Stored texel `(i, j)` (all channels), or `None` outside the level (or the storage).
    #[inline(always)]
    pub(crate) fn texel(&self, i: usize, j: usize) -> Option<[T; C]> {
        if i >= self.w || j >= self.h {
            return None;
        }
        let base = j.checked_mul(self.w)?.checked_add(i)?.checked_mul(C)?;
        self.data.get(base..base.checked_add(C)?)?.try_into().ok()
    }

    /// Texel `(i, j)` of the level under mode `M`, or zeros; counts one read if fetched.
    #[inline(always)]
    fn fetch<M: EdgeMode, K: Counter>(&self, mode: M, i: i64, j: i64, k: &mut K) -> [u64; C] {
        let kind = mode.kind();
        let t = match (tap_index(kind, i, self.w), tap_index(kind, j, self.h)) {
            (Some(x), Some(y)) => self.texel(x, y),
            _ => None,
        };
        match t {
            Some(texel) => {
                count_reads::<T, C, 1, K>(k);
                texel.map(|t| u64::from(t.to_u16()))
            }
            None => [0; C],
        }
    }

    /// The bilinear probe at the footprint's centre (base texels) in a level that shrinks x by
    /// `2^sx` and y by `2^sy`: 4 reads, 3 lerps; weights truncated to `weight_bits`, the result
    /// with `2 * weight_bits` fraction bits (below `2^(16 + 2 weight_bits)`).
    #[inline(always)]
    pub(crate) fn bilinear<M: EdgeMode, K: Counter>(
        &self,
        mode: M,
        fp: &Footprint,
        sx: u32,
        sy: u32,
        weight_bits: u32,
        k: &mut K,
    ) -> Result<[u64; C], Error> {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "f <= 24 (FracBits) and sx, sy <= 31 (a level of an axis below 2^31)"
        )]
        let (s_x, s_y) = (fp.f + sx, fp.f + sy);
        let (i0, ax) = split_position(fp.cx, s_x, weight_bits)?;
        let (j0, ay) = split_position(fp.cy, s_y, weight_bits)?;
        // i0, j0 <= i64::MAX >> 1 or a left tap of an odd doubled centre: + 1 stays in i64.
        let i1 = i0.checked_add(1).ok_or(Error::CoordinateOutOfRange)?;
        let j1 = j0.checked_add(1).ok_or(Error::CoordinateOutOfRange)?;
        let t00 = self.fetch(mode, i0, j0, k);
        let t10 = self.fetch(mode, i1, j0, k);
        let t01 = self.fetch(mode, i0, j1, k);
        let t11 = self.fetch(mode, i1, j1, k);
        let r0 = lerp(t00, t10, ax, weight_bits, k);
        let r1 = lerp(t01, t11, ax, weight_bits, k);
        Ok(lerp(r0, r1, ay, weight_bits, k))
    }
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]
mod tests {
    extern crate std;
    use super::*;
    use crate::cost::Tally;
    use crate::texture::MAX_DIMENSION;
    use fixed::types::{I24F8, I32F32, I64F0};
    use std::vec;
    use std::vec::Vec;

    #[test]
    fn level_sizes_and_counts() {
        for n in 1..=70usize {
            let count = level_count(n);
            assert_eq!(level_len(n, count - 1), 1);
            assert!(count == 1 || level_len(n, count - 2) > 1);
            for l in 0..count + 2 {
                assert_eq!(level_len(n, l), n.div_ceil(1 << l));
            }
        }
        assert_eq!(level_count(MAX_DIMENSION), MAX_LEVELS);
        assert_eq!(level_len(5, 200), 1);
        // Regression: n = 0 (no texture has it) no longer underflows.
        assert_eq!((level_len(0, 3), level_count(0)), (1, 1));
        assert_eq!(check_dims(0, 3), Err(Error::EmptyTexture));
        assert_eq!(
            check_dims(3, MAX_DIMENSION + 1),
            Err(Error::TextureTooLarge {
                dimension: MAX_DIMENSION + 1
            })
        );
    }

    #[test]
    fn texels_from_u16_are_exact_in_range_and_saturate() {
        assert_eq!(u8::from_u16_clamped(200), 200);
        assert_eq!(u8::from_u16_clamped(255), 255);
        assert_eq!(u8::from_u16_clamped(256), 255);
        assert_eq!(u16::from_u16_clamped(65535), 65535);
        for v in 0..=255u16 {
            assert_eq!(u8::from_u16_clamped(v).to_u16(), v);
        }
    }

    #[test]
    fn box_levels_are_rounded_means_of_clipped_blocks() {
        // Also sizes wider than one chunk of coarse columns.
        let (w, h) = (37usize, 5usize);
        let data: Vec<u8> = (0..w * h).map(|v| (v * 97 % 256) as u8).collect();
        let tex = Texture::<u8>::new(&data, w, h).unwrap();
        for (sx, sy) in [(0, 0), (1, 0), (0, 2), (3, 1), (6, 3)] {
            let (lw, lh) = (level_len(w, sx), level_len(h, sy));
            let mut out = vec![0u8; lw * lh];
            fill_box_level(&tex, &mut out, sx, sy).unwrap();
            for j in 0..lh {
                for i in 0..lw {
                    let (mut s, mut n) = (0u64, 0u64);
                    for y in (j << sy)..((j + 1) << sy).min(h) {
                        for x in (i << sx)..((i + 1) << sx).min(w) {
                            s += data[y * w + x] as u64;
                            n += 1;
                        }
                    }
                    assert_eq!(out[j * lw + i] as u64, (2 * s + n) / (2 * n));
                }
            }
            let mut short = vec![0u8; lw * lh - 1];
            assert_eq!(
                fill_box_level(&tex, &mut short, sx, sy),
                Err(Error::StorageTooSmall {
                    needed: lw * lh,
                    got: lw * lh - 1
                })
            );
        }
    }

    /// The earlier formulation: the doubled centre `p = x0 + x1` in `i128`, `s = F + 1 + l`.
    fn split_position_i128(p: i128, s: u32, weight_bits: u32) -> (i128, i64) {
        let t = p - (1i128 << (s - 1));
        let i0 = t >> s;
        let frac = t & ((1i128 << s) - 1);
        let a = if s >= weight_bits {
            frac >> (s - weight_bits)
        } else {
            frac << (weight_bits - s)
        };
        (i0, a as i64)
    }

    #[test]
    fn centres_and_positions_match_the_i128_formulation() {
        let edge = [
            i64::MIN,
            i64::MIN + 1,
            i64::MIN + 2,
            -3,
            -2,
            -1,
            0,
            1,
            2,
            3,
            // The edges of the 32-bit path.
            i32::MIN as i64 - 1,
            i32::MIN as i64,
            i32::MIN as i64 + 1,
            i32::MAX as i64 - 1,
            i32::MAX as i64,
            i32::MAX as i64 + 1,
            i64::MAX - 2,
            i64::MAX - 1,
            i64::MAX,
        ];
        let mut pairs: Vec<(i64, i64)> = Vec::new();
        // Under Miri (about 10^4 times slower) every 9th start, every 7th width, 40 random pairs and the shifts
        // 0, 1, every 7th, 31, 32 and 55, 56 (every edge pair runs).
        let (x_step, w_step, rounds) = if cfg!(miri) {
            (9, 7, 40)
        } else {
            (1, 1, 20_000)
        };
        for x0 in (-40i64..40).step_by(x_step) {
            for x1 in (x0..x0 + 40).step_by(w_step) {
                pairs.push((x0, x1));
            }
        }
        for &a in &edge {
            for &b in &edge {
                if a <= b {
                    pairs.push((a, b));
                }
            }
        }
        let mut s = 5u64;
        for _ in 0..rounds {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let a = s as i64 >> (s % 64);
            let b = a.saturating_add((s >> 7) as i64 >> (s % 61));
            pairs.push((a, b));
        }
        for &(x0, x1) in &pairs {
            let c = Centre::of(x0, x1);
            let p = x0 as i128 + x1 as i128;
            assert_eq!(2 * c.mid as i128 + c.odd as i128, p, "{x0} {x1}");
            let shifts = (0..=56u32).filter(|s| {
                !cfg!(miri) || s.is_multiple_of(7) || matches!(s, 1 | 31 | 32 | 55 | 56)
            });
            for s in shifts {
                assert_eq!(c.index(s) as i128, p >> (s + 1));
                for bits in [4u32, 16, 20, 24, 32] {
                    let (i_old, a_old) = split_position_i128(p, s + 1, bits);
                    match split_position(c, s, bits) {
                        Ok((i, a)) => {
                            assert_eq!((i as i128, a), (i_old, a_old as u64), "{x0} {x1} {s}")
                        }
                        // The one case outside i64: x0 = x1 = i64::MIN at s = 0.
                        Err(e) => {
                            assert_eq!(e, Error::CoordinateOutOfRange);
                            assert!(i_old < i64::MIN as i128, "{x0} {x1} {s}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn build_checks_name_the_exact_bits() {
        // (2m + 1) w h against 2^64, bits as the u128 product has them.
        for (bits, w, h) in [
            (16u32, MAX_DIMENSION, MAX_DIMENSION),
            (16, 1 << 24, 1 << 23),
            (8, MAX_DIMENSION, 1 << 20),
            (1, MAX_DIMENSION, MAX_DIMENSION),
        ] {
            let worst = ((2u128 << bits) - 1) * w as u128 * h as u128;
            let got = check_build(bits, w, h, 0, 0);
            if worst >> 64 == 0 {
                assert_eq!(got, Ok(()));
            } else {
                assert_eq!(
                    got,
                    Err(Error::TooWide {
                        what: Quantity::Entry,
                        bits_needed: 128 - worst.leading_zeros(),
                        bits_available: 64
                    })
                );
            }
        }
        assert_eq!(
            check_build(8, 3, 3, 10, 9),
            Err(Error::StorageTooSmall { needed: 10, got: 9 })
        );
    }

    #[test]
    fn level_positions_clamp_and_split() {
        // 4 texels at F = 8: log2 = 2 exactly; clamped to the top.
        assert_eq!(level_position(4 << 8, 8, 12, 5), 2 << 12);
        assert_eq!(level_position(4 << 8, 8, 12, 1), 1 << 12);
        assert_eq!(level_position(0, 8, 12, 5), 0);
        assert_eq!(level_position(1 << 7, 8, 12, 5), 0); // magnification
        assert_eq!(level_position(u64::MAX, 0, 12, 31), 31 << 12);
        assert_eq!(split_level((2 << 8) + 77, 8, 5), (2, 3, 77));
        assert_eq!(split_level(5 << 8, 8, 5), (5, 5, 0));
    }

    #[test]
    fn footprints_are_validated() {
        let r = Rect::<I24F8>::from_f64(1.0, 2.0, 3.5, 2.0).unwrap();
        let fp = footprint(&r).unwrap();
        assert_eq!(
            (fp.cx.mid, fp.cx.odd, fp.cy.mid, fp.cy.odd),
            (576, 0, 512, 0)
        );
        assert_eq!((fp.w, fp.h, fp.f), (640, 0, 8));
        let r = Rect::<I24F8>::from_f64(3.0, 0.0, 1.0, 1.0).unwrap();
        assert_eq!(footprint(&r).err(), Some(Error::InvertedBox));
        let r = Rect::<I32F32>::from_f64(0.0, 0.0, 1.0, 1.0).unwrap();
        assert_eq!(
            footprint(&r).err(),
            Some(Error::FracBitsUnsupported {
                frac_bits: 32,
                max: 24
            })
        );
        // The widest corners: exact centre and side, no overflow.
        let r = Rect::new(I64F0::MIN, I64F0::MIN, I64F0::MAX, I64F0::MIN);
        let fp = footprint(&r).unwrap();
        assert_eq!((fp.cx.mid, fp.cx.odd, fp.w), (-1, 1, u64::MAX));
        assert_eq!((fp.cy.mid, fp.cy.odd, fp.h), (i64::MIN, 0, 0));
    }

    #[test]
    fn lerp_is_crows_and_counts_per_channel() {
        let mut k = Tally::new();
        let v = lerp([10u64, 0, 7], [20, 255, 7], 3, 2, &mut k);
        // b 4 + (c - b) 3 with weight 3/4.
        assert_eq!(v, [40 + 30, 765, 28]);
        assert_eq!((k.muls, k.adds), (3, 6));
        // A falling difference wraps and comes back: exact below 2^64.
        let w = lerp([65535 << 40], [0], 1 << 8, 8, &mut k);
        assert_eq!(w, [0]);
        let w = lerp([(1u64 << 56) - 1], [3], 1, 8, &mut k);
        assert_eq!(w, [((1u64 << 56) - 1) * 255 + 3]);
        let mut k = Tally::new();
        count_reads::<u16, 3, 4, _>(&mut k);
        assert_eq!((k.reads, k.bits_read, k.words), (4, 4 * 48, 8));
    }

    #[test]
    fn lerp_matches_the_signed_formulation() {
        // Every pair of 8-bit values, every 8-bit weight; and 16-bit values against i128.
        let mut k = crate::cost::NoCount;
        // Under Miri (about 10^4 times slower) the values 0, 1, 254, 255 and every 37th, the weights 0, 1, 128, 255,
        // 256 and every 41st, and 300 random 16-bit cases.
        let value = |v: &u64| !cfg!(miri) || *v <= 1 || *v >= 254 || v.is_multiple_of(37);
        let weight =
            |a: &u64| !cfg!(miri) || *a <= 1 || *a >= 255 || *a == 128 || a.is_multiple_of(41);
        for b in (0..=255u64).filter(value) {
            for c in (0..=255u64).filter(value) {
                for a in (0..=256u64).filter(weight) {
                    let want = ((b as i64) << 8) + (c as i64 - b as i64) * a as i64;
                    assert_eq!(lerp([b], [c], a, 8, &mut k), [want as u64]);
                }
            }
        }
        let mut s = 9u64;
        for _ in 0..if cfg!(miri) { 300 } else { 100_000 } {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let (b, c) = ((s >> 16) & 0xFFFF_FFFF_FFFF, (s >> 8) & 0xFFFF_FFFF_FFFF);
            for bits in [8u32, 12, 16] {
                let a = (s >> 3) & ((1 << bits) - 1);
                let want = ((b as i128) << bits) + (c as i128 - b as i128) * a as i128;
                assert_eq!(lerp([b], [c], a, bits, &mut k), [want as u64]);
            }
        }
    }
}
