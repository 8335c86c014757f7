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
//! * the footprint: validated raw corners, doubled centre and side lengths ([`footprint`]), and
//!   the level position `L = clamp(log2_fixed(side), 0, top)` split into
//!   `floor(L)`, `min(floor(L) + 1, top)` and `frac(L)` ([`level_position`], [`split_level`]);
//! * the bilinear taps: level texel `i` covers base `[i 2^s, (i+1) 2^s)`, so its centre is
//!   `(i + 1/2) 2^s` and a probe at centre `c` interpolates the texels around `c / 2^s - 1/2`:
//!   left tap `floor(c / 2^s - 1/2)`, weight its fraction truncated to a filter's weight bits
//!   ([`split_position`]);
//! * Crow's lerp `b + (c - b) alpha` (1 multiply, 2 additive operations per channel, §2.2; a
//!   bilinear is 3 lerps), in `i64` or `i128` ([`lerp`]), and the read count (all channels of a
//!   texel together, [`count_reads`]);
//! * for the rip and dip maps, which store every level in caller storage: the storage layout
//!   helpers, the build checks, and the stored level with its bilinear probe (`LevelView`,
//!   `resolve`: indices beyond `i64` fold onto the mode's period).

use crate::cost::Counter;
use crate::error::Error;
use crate::filters::level::log2_fixed;
use crate::rect::{Coord, Rect};
use crate::texel::{Acc, Texel};
use crate::texture::{Texture, MAX_DIMENSION};
use crate::width::MAX_FRAC_BITS;
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
use crate::{edge::EdgeMode, error::Quantity, filters::Sample, width::bits_of};

/// The most levels an axis can have: sides up to `2^31 - 1` texels halve to 1 in 31 steps, so
/// they need levels `0..=31`.
pub(crate) const MAX_LEVELS: usize = 32;

/// Coarse columns summed together in one pass of the level build (stack accumulators).
const CHUNK: usize = 16;

/// `ceil(n / 2^l)` for `n >= 1`.
#[inline(always)]
pub(crate) fn level_len(n: usize, l: usize) -> usize {
    if l >= usize::BITS as usize {
        1
    } else {
        ((n - 1) >> l) + 1
    }
}

/// Levels of an axis of `n >= 1` texels: `ceil(log2 n) + 1`.
#[inline(always)]
pub(crate) fn level_count(n: usize) -> usize {
    (usize::BITS - (n - 1).leading_zeros()) as usize + 1
}

/// Refuses dimensions a texture could not have: [`Error::EmptyTexture`] for a zero side,
/// [`Error::TextureTooLarge`] past `2^31 - 1`.
pub(crate) fn check_dims(width: usize, height: usize) -> Result<(), Error> {
    if width == 0 || height == 0 {
        return Err(Error::EmptyTexture);
    }
    if width > MAX_DIMENSION || height > MAX_DIMENSION {
        return Err(Error::TextureTooLarge {
            dimension: width.max(height),
        });
    }
    Ok(())
}

/// Fills `out` (`lw * lh * C` elements, row-major, `lw = ceil(w / 2^sx)`, `lh = ceil(h / 2^sy)`)
/// with the box averages of the base blocks of `2^sx x 2^sy` texels, clipped to the texture,
/// each `round(sum / count) = floor((2 sum + count) / (2 count))` (ties up) of the exact sum in
/// `u64`, `CHUNK` coarse columns per pass over the block's base rows. Every base texel is read
/// once per level.
///
/// The caller proved `2 sum + count < 2^64` for every block (the rip and dip builds: `(2m + 1) w h
/// < 2^64`; the mip build: `2^(B+1) w h < 2^64`), and `sx, sy <= 31` (levels of a side below
/// `2^31`).
pub(crate) fn fill_box_level<T: Texel, const C: usize>(
    texture: &Texture<'_, T, C>,
    out: &mut [T],
    sx: usize,
    sy: usize,
) -> Result<(), Error> {
    let (w, h) = (texture.width(), texture.height());
    let (lw, lh) = (level_len(w, sx), level_len(h, sy));
    // Block bounds in base texels: i < ceil(n / 2^s), so i 2^s < n <= 2^31 and (i + 1) 2^s
    // < 2^33 (s <= 31): all in u64, the clipped ends in usize.
    let span = |i: usize, s: usize, n: usize| -> (usize, usize) {
        let lo = (i as u64) << s;
        let hi = (((i as u64) + 1) << s).min(n as u64);
        (lo as usize, hi as usize)
    };
    for j in 0..lh {
        let (y_lo, y_hi) = span(j, sy, h);
        let mut i0 = 0;
        while i0 < lw {
            let n = CHUNK.min(lw - i0);
            let mut acc = [[0u64; C]; CHUNK];
            for y in y_lo..y_hi {
                // y < h and the block columns lie below w: rows and slices always exist (the
                // errors are unreachable; they stand in for panics).
                let row = texture.row(y).ok_or(Error::EmptyTexture)?;
                for (ci, a) in acc[..n].iter_mut().enumerate() {
                    let (x_lo, x_hi) = span(i0 + ci, sx, w);
                    let px = row.get(x_lo * C..x_hi * C).ok_or(Error::EmptyTexture)?;
                    for texel in px.chunks_exact(C) {
                        for (s, t) in a.iter_mut().zip(texel) {
                            *s += t.to_u16() as u64;
                        }
                    }
                }
            }
            for (ci, a) in acc[..n].iter().enumerate() {
                let (x_lo, x_hi) = span(i0 + ci, sx, w);
                let cnt = ((x_hi - x_lo) * (y_hi - y_lo)) as u64;
                let at = (j * lw + i0 + ci) * C;
                let len = out.len();
                let dst = out.get_mut(at..at + C).ok_or(Error::StorageTooSmall {
                    needed: at + C,
                    got: len,
                })?;
                for (d, &s) in dst.iter_mut().zip(a.iter()) {
                    // 2 s + cnt < 2^64 (the caller's proof); the mean is at most m = 2^B - 1.
                    let mean = (2 * s + cnt) / (2 * cnt);
                    *d = T::from_u16_clamped(mean as u16);
                }
            }
            i0 += n;
        }
    }
    Ok(())
}

/// A validated footprint `[x0, x1) x [y0, y1)`, raw fixed-point values with `f` fraction bits.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Footprint {
    /// The doubled centre `x0 + x1` (raw), in `[-2^64, 2^64 - 2]`.
    pub(crate) px: i128,
    /// The doubled centre `y0 + y1` (raw).
    pub(crate) py: i128,
    /// The width `W = x1 - x0` (raw), in `[0, 2^64 - 1]`.
    pub(crate) w: i128,
    /// The height `H = y1 - y0` (raw).
    pub(crate) h: i128,
    /// Fraction bits `F` of the corners (at most 24).
    pub(crate) f: u32,
}

/// Validates a footprint: [`Error::FracBitsUnsupported`] for `F > 24`, [`Error::InvertedBox`]
/// for `x1 < x0` or `y1 < y0`. Returns its doubled centre and sides.
pub(crate) fn footprint<X: Coord>(rect: &Rect<X>) -> Result<Footprint, Error> {
    let f = X::FRAC_BITS;
    if f > MAX_FRAC_BITS {
        return Err(Error::FracBitsUnsupported {
            frac_bits: f,
            max: MAX_FRAC_BITS,
        });
    }
    let (x0, y0, x1, y1) = (
        rect.x0.raw() as i128,
        rect.y0.raw() as i128,
        rect.x1.raw() as i128,
        rect.y1.raw() as i128,
    );
    if x1 < x0 || y1 < y0 {
        return Err(Error::InvertedBox);
    }
    Ok(Footprint {
        px: x0 + x1,
        py: y0 + y1,
        w: x1 - x0,
        h: y1 - y0,
        f,
    })
}

/// The level position of a side of `side / 2^f` texels (`side` raw, in `[0, 2^64 - 1]`) with
/// `frac_bits` fraction bits: `log2_fixed` (the exact `floor` or one unit below; exact at powers
/// of two) clamped to `[0, top 2^frac_bits]`; `0` for a side of 0 (and at most one texel).
pub(crate) fn level_position(side: i128, f: u32, frac_bits: u32, top: u32) -> u32 {
    let raw = u64::try_from(side).unwrap_or(u64::MAX);
    log2_fixed(raw, f, frac_bits)
        .unwrap_or(0)
        .clamp(0, (top as i32) << frac_bits) as u32
}

/// Splits a level position `L` (`frac_bits` fraction bits, at most `top 2^frac_bits`) into
/// `(lo, hi, frac)`: `lo = floor(L)`, `hi = min(lo + 1, top)`, `frac = frac(L)` (exact).
pub(crate) fn split_level(pos: u32, frac_bits: u32, top: u32) -> (u32, u32, i64) {
    let lo = pos >> frac_bits;
    let frac = (pos & ((1 << frac_bits) - 1)) as i64;
    (lo, (lo + 1).min(top), frac)
}

/// Splits a level position `u = p / 2^s - 1/2` (`p` a doubled raw centre coordinate `x0 + x1`,
/// `s = F + 1 + l >= 1`) into the left texel of the bilinear pair, `floor(u)`, and the weight of
/// the right one, `frac(u)` truncated to `weight_bits` bits (exact when `s <= weight_bits`).
#[inline(always)]
pub(crate) fn split_position(p: i128, s: u32, weight_bits: u32) -> (i128, i64) {
    let t = p - (1i128 << (s - 1));
    let i0 = t >> s;
    let frac = t & ((1i128 << s) - 1); // in [0, 2^s)
    let a = if s >= weight_bits {
        frac >> (s - weight_bits)
    } else {
        frac << (weight_bits - s)
    };
    (i0, a as i64)
}

/// Crow's lerp `b * 2^bits + (c - b) * a` per channel (`a` a weight with `bits` fraction bits):
/// 1 multiply and 2 additive operations per channel; the scale by `2^bits` is a shift (wiring).
#[inline(always)]
pub(crate) fn lerp<A: Acc, K: Counter, const C: usize>(
    b: [A; C],
    c: [A; C],
    a: A,
    bits: u32,
    k: &mut K,
) -> [A; C] {
    k.muls(C as u32);
    k.adds(2 * C as u32);
    core::array::from_fn(|i| (b[i] << bits) + (c[i] - b[i]) * a)
}

/// Counts `n` texel reads: all channels of a texel together (`T::BITS * C` bits), and the
/// 32-bit words they take.
#[inline(always)]
pub(crate) fn count_reads<T: Texel, const C: usize, K: Counter>(n: u32, k: &mut K) {
    k.reads(n, T::BITS * C as u32);
    k.words(n * (T::BITS * C as u32).div_ceil(32));
}

/// Prefix sums of the level lengths of an axis of `n` texels (`1 <= n <= 2^31 - 1`, so
/// `levels <= 32` and the total `< 2n + 32` fits `usize`).
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) fn prefix(n: usize) -> (usize, [usize; MAX_LEVELS + 1]) {
    let levels = level_count(n).min(MAX_LEVELS);
    let mut cum = [0usize; MAX_LEVELS + 1];
    for l in 0..levels {
        cum[l + 1] = cum[l].saturating_add(level_len(n, l));
    }
    (levels, cum)
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
    let m = (1u128 << texel_bits) - 1;
    let worst = (2 * m + 1) * width as u128 * height as u128;
    if worst > u64::MAX as u128 {
        return Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: bits_of(worst),
            bits_available: 64,
        });
    }
    check_storage(needed, got)
}

/// Level position of a side of `side_raw / 2^f` texels on an axis whose top level is `top`:
/// `(lo, hi, frac)` with `L = clamp(log2_fixed(side), 0, top)`, `lo = floor(L)`,
/// `hi = min(lo + 1, top)`, `frac` in `frac_bits` bits ([`level_position`], [`split_level`]).
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) fn level_split(side_raw: i128, f: u32, frac_bits: u32, top: u32) -> (u32, u32, i64) {
    split_level(level_position(side_raw, f, frac_bits, top), frac_bits, top)
}

/// Each channel shifted right by `s` (a truncation, floor).
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
#[inline(always)]
pub(crate) fn truncate<const C: usize>(v: [i64; C], s: u32) -> [i64; C] {
    v.map(|c| c >> s)
}

/// The output sample `floor(v / 2^shift)` per channel (negative values, which a convex
/// combination of texels cannot give, read as 0).
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
pub(crate) fn floor_sample<const C: usize>(v: [i64; C], shift: u32) -> Sample<C> {
    Sample {
        values: v.map(|v| (v.max(0) >> shift) as u64),
    }
}

/// The index the mode shows at (possibly huge) level index `i`. Indices outside `i64` (only
/// reachable with 64-bit raw corners near their limits) are first moved by a multiple of `2n`
/// to `+-(2^61 rounded to a multiple of 2n) + (i mod 2n)`: still far outside on the same side,
/// and congruent modulo the period of `Repeat` and `MirroredRepeat`, so every mode answers as
/// for `i`.
#[cfg(any(feature = "filter-rip", feature = "filter-dip"))]
#[inline(always)]
fn resolve<M: EdgeMode>(mode: M, i: i128, n: usize) -> Option<usize> {
    let idx = match i64::try_from(i) {
        Ok(v) => v,
        Err(_) => {
            let period = 2 * n as i128;
            let far = ((1i128 << 61) / period) * period;
            let r = i.rem_euclid(period);
            (if i > 0 { far + r } else { r - far }) as i64
        }
    };
    mode.kind().texel_index(idx, n).filter(|&v| v < n)
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
    /// Stored texel `(i, j)` (all channels), or `None` outside the level.
    pub(crate) fn texel(&self, i: usize, j: usize) -> Option<[T; C]> {
        if i >= self.w || j >= self.h {
            return None;
        }
        let base = (j * self.w + i) * C;
        self.data.get(base..base + C)?.try_into().ok()
    }

    /// Texel `(i, j)` of the level under mode `M`, or zeros; counts one read if fetched.
    #[inline(always)]
    fn fetch<M: EdgeMode, K: Counter>(&self, mode: M, i: i128, j: i128, k: &mut K) -> [i64; C] {
        let mut out = [0i64; C];
        if let (Some(x), Some(y)) = (resolve(mode, i, self.w), resolve(mode, j, self.h)) {
            let base = (y * self.w + x) * C;
            if let Some(texel) = self.data.get(base..base + C) {
                count_reads::<T, C, K>(1, k);
                for (o, t) in out.iter_mut().zip(texel) {
                    *o = t.to_u16() as i64;
                }
            }
        }
        out
    }

    /// The bilinear probe at the footprint's centre `(px, py) / 2^(F+1)` (base texels) in a
    /// level that shrinks x by `2^sx` and y by `2^sy`: 4 reads, 3 lerps; weights truncated to
    /// `weight_bits`, the result with `2 * weight_bits` fraction bits.
    #[inline(always)]
    pub(crate) fn bilinear<M: EdgeMode, K: Counter>(
        &self,
        mode: M,
        fp: &Footprint,
        sx: u32,
        sy: u32,
        weight_bits: u32,
        k: &mut K,
    ) -> [i64; C] {
        let (i0, ax) = split_position(fp.px, fp.f + 1 + sx, weight_bits);
        let (j0, ay) = split_position(fp.py, fp.f + 1 + sy, weight_bits);
        let t00 = self.fetch(mode, i0, j0, k);
        let t10 = self.fetch(mode, i0 + 1, j0, k);
        let t01 = self.fetch(mode, i0, j0 + 1, k);
        let t11 = self.fetch(mode, i0 + 1, j0 + 1, k);
        let r0 = lerp(t00, t10, ax, weight_bits, k);
        let r1 = lerp(t01, t11, ax, weight_bits, k);
        lerp(r0, r1, ay, weight_bits, k)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::cost::Tally;
    use fixed::types::{I24F8, I32F32};
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

    #[test]
    fn positions_split_into_floor_and_truncated_fraction() {
        for p in -300i128..300 {
            for s in 1..=6u32 {
                for bits in [2u32, 4, 16] {
                    let (i0, a) = split_position(p, s, bits);
                    // u = p / 2^s - 1/2 = (2p - 2^s) / 2^(s+1).
                    let num = 2 * p - (1i128 << s);
                    let den = 1i128 << (s + 1);
                    assert_eq!(i0, num.div_euclid(den));
                    let frac = num.rem_euclid(den); // fraction * den
                    assert_eq!(a as i128, (frac << bits) / den);
                }
            }
        }
    }

    #[test]
    fn level_positions_clamp_and_split() {
        // 4 texels at F = 8: log2 = 2 exactly; clamped to the top.
        assert_eq!(level_position(4 << 8, 8, 12, 5), 2 << 12);
        assert_eq!(level_position(4 << 8, 8, 12, 1), 1 << 12);
        assert_eq!(level_position(0, 8, 12, 5), 0);
        assert_eq!(level_position(1 << 7, 8, 12, 5), 0); // magnification
        assert_eq!(split_level((2 << 8) + 77, 8, 5), (2, 3, 77));
        assert_eq!(split_level(5 << 8, 8, 5), (5, 5, 0));
    }

    #[test]
    fn footprints_are_validated() {
        let r = Rect::<I24F8>::from_f64(1.0, 2.0, 3.5, 2.0).unwrap();
        let fp = footprint(&r).unwrap();
        assert_eq!((fp.px, fp.py, fp.w, fp.h, fp.f), (1152, 1024, 640, 0, 8));
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
    }

    #[test]
    fn lerp_is_crows_and_counts_per_channel() {
        let mut k = Tally::new();
        let v = lerp([10i64, 0, 7], [20, 255, 7], 3, 2, &mut k);
        // b 4 + (c - b) 3 with weight 3/4.
        assert_eq!(v, [40 + 30, 765, 28]);
        assert_eq!((k.muls, k.adds), (3, 6));
        let w = lerp([1i128 << 80], [0], 1 << 8, 8, &mut k);
        assert_eq!(w, [0]);
        let mut k = Tally::new();
        count_reads::<u16, 3, _>(4, &mut k);
        assert_eq!((k.reads, k.bits_read, k.words), (4, 4 * 48, 8));
    }
}
