//! The 4-D image pyramid ("ripmap"): `u` and `v` prefiltered independently (Heckbert 1986,
//! "Comparison of Prefiltering Methods": *4-D pyramid (scaling u and v)*, box filter, rectangle,
//! 16 accesses and 15 multiplies per pixel, memory 4).
//!
//! # Levels
//!
//! Level `(lx, ly)` has `ceil(w / 2^lx) x ceil(h / 2^ly)` texels for every `lx` in
//! `0..=ceil(log2 w)` and `ly` in `0..=ceil(log2 h)` (the last level of an axis is 1 texel
//! wide). Its texel `(i, j)` is the box average of the base texels in
//! `[i 2^lx, (i+1) 2^lx) x [j 2^ly, (j+1) 2^ly)` *clipped to the texture* (the last column and
//! row of a level of a non-power-of-two texture average fewer texels). Every stored texel is
//! computed from the exact integer sum of its block, `round(sum / count)` to nearest, ties up:
//! it is within 1/2 LSB of the exact average, and the error does not accumulate from level to
//! level (no level is computed from another).
//!
//! Storage: all levels, level `(0, 0)` (a copy of the texture) included, in caller storage
//! `&mut [T]`, band `ly` after band `ly - 1`, the levels of a band side by side. The element
//! count is [`RipMap::storage_needed`] `= C * (sum_lx ceil(w / 2^lx)) * (sum_ly ceil(h / 2^ly))`;
//! for a power-of-two texture that is `C (2w - 1)(2h - 1)`, so the ratio to the texture tends to
//! the survey's 4 (measured: 1024 x 1024 gives 3.996; 5 x 3 gives 11 * 6 / 15 = 4.4).
//!
//! # Sampling (Heckbert's 4-D pyramid, trilinear generalised to two level axes)
//!
//! The footprint is the rectangle bounding it, `W x H` texels. The level positions are
//! `Lx = log2(W)`, `Ly = log2(H)` in fixed point with [`LEVEL_FRAC_BITS`] fractional bits
//! ([`crate::filters::level::log2_fixed`]: the exact `floor` or one unit below it; exact at
//! powers of two), clamped to `[0, top]` (`top = ceil(log2 n)`, the 1-texel level; a side of at
//! most one texel, including 0, is level 0). With `lo = floor(L)`, `hi = min(lo + 1, top)` and
//! `f = frac(L)` per axis, four bilinear probes at the footprint centre, in levels
//! `(lo_x, lo_y)`, `(hi_x, lo_y)`, `(lo_x, hi_y)`, `(hi_x, hi_y)`, are blended bilinearly by
//! `(f_x, f_y)`. The result is continuous in the centre and in `(Lx, Ly)`.
//!
//! A bilinear probe at centre `(cx, cy)` in level `(lx, ly)` interpolates the four level texels
//! around `(cx / 2^lx - 1/2, cy / 2^ly - 1/2)` (level texel `i` covers base
//! `[i 2^lx, (i+1) 2^lx)`, so its centre is `(i + 1/2) 2^lx`). Indices outside a level are
//! resolved by the boundary mode on *that level's* grid (`mode.kind().texel_index(i, level_width)`):
//! for non-power-of-two textures the coarse levels of `Repeat`/`MirroredRepeat` repeat with the
//! level's own period (as GPUs do); `Border` reads zero outside.
//!
//! # Arithmetic and error bound
//!
//! Integer throughout, 64 bits (`u64`: every value is a non-negative convex combination). A probe's position fraction is truncated to [`WEIGHT_BITS`] bits
//! (exact when the level position has at most that many bits: `F + 1 + l <= 16`); the three
//! lerps `b * 2^16 + (c - b) a` are exact, so the probe is exact for the truncated weights, at
//! `2 * WEIGHT_BITS` fraction bits; it is truncated (a shift, floor) to [`OUT_FRAC_BITS`] bits.
//! The level blend (three lerps with `LEVEL_FRAC_BITS`-bit fractions) is exact, and the output is
//! truncated (floor) to `OUT_FRAC_BITS` bits: the rounding adds that round-to-nearest would need
//! are not in the survey's count, so this filter floors instead (documented exception to
//! "round to nearest").
//!
//! **Bound** (against the same filter in `f64` on the stored levels, with the same fixed-point
//! `Lx`, `Ly`, exact positions and weights): with `m = 2^b - 1` the largest texel,
//! `|out - 2^16 * exact| < 2^(b+1)` output units, i.e. `< (m + 1) 2^-15` texel units.
//! Derivation: a probe is bilinear in its weights `(ax, ay)` with corners in `[0, m]`, so
//! truncating each weight by less than `2^-16` moves it by less than `m 2^-16` per axis, less
//! than `m 2^-15` together; the truncation to 16 bits adds `(-2^-16, 0]`; the blend is a convex
//! combination, so the bounds carry over; the final floor adds `(-2^-16, 0]`. Total:
//! `(-(m 2^-15 + 2^-15), m 2^-15)`. The bound is approached (within 1%) by weights just below a
//! multiple of `2^-16` on both axes and a single bright corner texel (unit test
//! `error_bound_is_approached`). See [`arithmetic_error_bound`].
//!
//! Against the same filter with the *exact* `log2` (the level selection's own rounding): the
//! blend is Lipschitz with constant `m` in `Lx` and in `Ly` (a lerp between values in `[0, m]`),
//! and `log2_fixed` is below the exact value by less than 2 units of `2^-LEVEL_FRAC_BITS`, so the
//! level selection adds less than `m 2^(2 - LEVEL_FRAC_BITS)` texel units (see
//! [`level_selection_error_bound`]).
//!
//! Widths: texels `< 2^16`, weights `< 2^16`: a probe is `< 2^48` before and `< 2^32` after the
//! truncation; the blend is `< 2^(32 + 2 * 12) = 2^56`. All in `u64`, no overflow possible; the
//! footprint's centre and sides are exact in `i64`/`u64` for any `i64` corners (the pyramid
//! module's `Centre`), and the only refusal is [`Error::CoordinateOutOfRange`] for a probe whose
//! left tap index would be below `i64::MIN` (`F = 0`, `y0 = y1 = i64::MIN`, or the same in x).
//!
//! # Cost (counted as the survey and Crow §2.2 count)
//!
//! A lerp `b + (c - b) a` is 1 multiply and 2 additive operations; a bilinear probe is 4 reads
//! and 3 lerps; the blend of the four probes is 3 lerps. Per sample: **16 reads, 15 multiplies,
//! 30 additive operations** (4 * 6 + 6), per channel for the arithmetic; reads are per texel, all
//! channels together (`T::BITS * C` bits). This is the survey's 16 accesses and 15 multiplies.
//! Reads that `Border` resolves to zero outside a level fetch nothing and are not counted
//! (the arithmetic is). The probe of a clamped level (`hi == lo` at the top, or `f = 0`) is still
//! fetched and counted: the cost is per sample, constant, as in the survey. The weight and level
//! computations (shifts, masks, the `log2`) belong to the address unit and are not counted.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::cost::Counter;
use crate::edge::EdgeMode;
use crate::error::Error;
#[cfg(test)]
use crate::filters::level::log2_fixed;
use crate::filters::pyramid::{
    axis_total, check_build, check_dims, check_storage, fill_box_level, floor_sample,
    footprint_raw, lerp, level_len, level_split, prefix, truncate, LevelView,
};
use crate::filters::{pyramid, u64_from_usize, Sample, OUT_FRAC_BITS};
use crate::rect::{Coord, FracBits, Rect};
use crate::texel::Texel;
use crate::texture::Texture;

/// Fraction bits of a bilinear probe's weights (positions truncated to `2^-16` level texels).
pub const WEIGHT_BITS: u32 = 16;

/// Fraction bits of the level positions `Lx`, `Ly` (and so of the level-blend weights).
pub const LEVEL_FRAC_BITS: u32 = 12;

/// The most levels an axis can have: sides up to `2^31 - 1` texels need levels `0..=31`.
pub const MAX_LEVELS: usize = pyramid::MAX_LEVELS;

/// The arithmetic error bound in output units: `|out - 2^16 * exact| < 2^(texel_bits + 1)`
/// (module docs, "Arithmetic and error bound"). `exact` is the same filter in real arithmetic
/// on the stored levels with the same fixed-point level positions.
///
/// For texel widths whose bound does not fit `u64` (63 bits and more; every [`Texel`] has at
/// most 16) the result is `u64::MAX`: the bound never shrinks as the width grows.
pub const fn arithmetic_error_bound(texel_bits: u32) -> u64 {
    pyramid::pow2_or_max(texel_bits.saturating_add(1))
}

/// The extra error, in output units, of the fixed-point level positions against the exact
/// `log2`: less than `m * 2^(2 - LEVEL_FRAC_BITS) * 2^16` with `m = 2^texel_bits - 1` (module
/// docs); that is exactly `m << (OUT_FRAC_BITS + 2 - LEVEL_FRAC_BITS)`.
///
/// `u64::MAX` where the bound does not fit `u64` (texel widths of more than 58 bits; every
/// [`Texel`] has at most 16): the bound never shrinks as the width grows.
pub const fn level_selection_error_bound(texel_bits: u32) -> u64 {
    pyramid::mask_shl_or_max(texel_bits, OUT_FRAC_BITS + 2 - LEVEL_FRAC_BITS)
}

/// A ripmap over caller storage: every level `(lx, ly)` of the 4-D pyramid (module docs).
#[derive(Debug, Clone)]
pub struct RipMap<'a, T: Texel, const C: usize> {
    data: &'a [T],
    width: usize,
    height: usize,
    /// `wcum[l] = sum_{k < l} ceil(w / 2^k)` for `l = 0..=levels_x`; the last is the band width.
    wcum: heapless::Vec<usize, { MAX_LEVELS + 1 }>,
    /// `hcum[l] = sum_{k < l} ceil(h / 2^k)` for `l = 0..=levels_y`.
    hcum: heapless::Vec<usize, { MAX_LEVELS + 1 }>,
}

impl<'a, T: Texel, const C: usize> RipMap<'a, T, C> {
    /// Elements of `T` the levels of a `width x height` texture need:
    /// `C * (sum_lx ceil(w / 2^lx)) * (sum_ly ceil(h / 2^ly))` (`C (2w - 1)(2h - 1)` for powers
    /// of two). Saturates at `usize::MAX` (no slice is that long, so the build then refuses);
    /// 0 for an empty texture.
    pub fn storage_needed(width: usize, height: usize) -> usize {
        if width == 0 || height == 0 {
            return 0;
        }
        axis_total(width)
            .saturating_mul(axis_total(height))
            .saturating_mul(C)
    }

    /// Builds every level from the exact block sums of `texture` into `storage`.
    ///
    /// Errors: [`Error::StorageTooSmall`] if `storage` is shorter than
    /// [`RipMap::storage_needed`]; [`Error::TooWide`] (`Quantity::Entry`, 64 bits available) if a
    /// block sum could overflow the `u64` accumulator (`(2m + 1) w h >= 2^64`; no texture that
    /// fits memory gets there with 4x storage, but it is checked, not assumed).
    ///
    /// Cost: `(levels_x * levels_y)` passes over the texture, each texel added once per level
    /// (not counted: prefiltering is done once, off the per-sample path).
    pub fn build(texture: &Texture<'_, T, C>, storage: &'a mut [T]) -> Result<Self, Error> {
        let (w, h) = (texture.width(), texture.height());
        let needed = Self::storage_needed(w, h);
        check_build(T::BITS, w, h, needed, storage.len())?;
        let mut map = Self::layout(&[], w, h);
        for ly in 0..map.levels_y() {
            for lx in 0..map.levels_x() {
                let (start, len) = map.level_range(lx, ly);
                let out = storage
                    .get_mut(start..start.saturating_add(len))
                    .ok_or(Error::StorageTooSmall { needed, got: start })?;
                fill_box_level(texture, out, lx, ly)?;
            }
        }
        let data: &'a [T] = storage;
        map.data = data.get(..needed).unwrap_or(&[]);
        Ok(map)
    }

    /// Wraps levels built elsewhere (flash, an earlier [`RipMap::build`]) in the layout `build`
    /// writes. Every `T` value is a valid texel, so only the length is checked.
    pub fn from_storage(storage: &'a [T], width: usize, height: usize) -> Result<Self, Error> {
        check_dims(width, height)?;
        let needed = Self::storage_needed(width, height);
        check_storage(needed, storage.len())?;
        Ok(Self::layout(
            storage.get(..needed).unwrap_or(&[]),
            width,
            height,
        ))
    }

    fn layout(data: &'a [T], width: usize, height: usize) -> Self {
        RipMap {
            data,
            width,
            height,
            wcum: prefix(width),
            hcum: prefix(height),
        }
    }

    /// Start and length (elements) of level `(lx, ly)`. Within the map's levels the sums fit
    /// (they are below `storage_needed`); saturating arithmetic and the `usize::MAX` start of a
    /// level past the top only make the level empty ([`RipMap::view`]).
    fn level_range(&self, lx: usize, ly: usize) -> (usize, usize) {
        let (Some(&band), Some(&hc), Some(&wc)) =
            (self.wcum.last(), self.hcum.get(ly), self.wcum.get(lx))
        else {
            return (usize::MAX, 0);
        };
        let lh = level_len(self.height, ly);
        let start = hc
            .saturating_mul(band)
            .saturating_add(lh.saturating_mul(wc))
            .saturating_mul(C);
        let len = lh
            .saturating_mul(level_len(self.width, lx))
            .saturating_mul(C);
        (start, len)
    }

    fn view(&self, lx: usize, ly: usize) -> LevelView<'a, T, C> {
        let (start, len) = self.level_range(lx, ly);
        LevelView {
            data: self
                .data
                .get(start..start.saturating_add(len))
                .unwrap_or(&[]),
            w: level_len(self.width, lx),
            h: level_len(self.height, ly),
        }
    }

    /// Base width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Base height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Levels along x: `ceil(log2 w) + 1` (level `levels_x() - 1` is 1 texel wide).
    pub fn levels_x(&self) -> usize {
        self.wcum.len().saturating_sub(1)
    }

    /// Levels along y: `ceil(log2 h) + 1`.
    pub fn levels_y(&self) -> usize {
        self.hcum.len().saturating_sub(1)
    }

    /// `(ceil(w / 2^lx), ceil(h / 2^ly))`, or `None` past the levels.
    pub fn level_size(&self, lx: usize, ly: usize) -> Option<(usize, usize)> {
        (lx < self.levels_x() && ly < self.levels_y())
            .then(|| (level_len(self.width, lx), level_len(self.height, ly)))
    }

    /// Stored texel `(i, j)` of level `(lx, ly)` (all channels), or `None` outside.
    pub fn level_texel(&self, lx: usize, ly: usize, i: usize, j: usize) -> Option<[T; C]> {
        self.level_size(lx, ly)?;
        self.view(lx, ly).texel(i, j)
    }

    /// Elements of `T` stored (all levels, level `(0, 0)` included).
    pub fn storage_len(&self) -> usize {
        self.data.len()
    }

    /// Bits stored: `storage_len() * T::BITS`. The texture itself is `w * h * C * T::BITS`; the
    /// ratio is the survey's "memory" column (4 for large powers of two).
    ///
    /// Saturates at `u64::MAX`, which only a storage of `2^61` bytes of `u8` or `u16` texels
    /// could reach.
    pub fn storage_bits(&self) -> u64 {
        u64_from_usize(self.data.len()).saturating_mul(u64::from(T::BITS))
    }

    /// Filters the footprint bounded by `rect` (module docs): 4 bilinear probes at its centre in
    /// the levels around `(log2 W, log2 H)`, blended bilinearly. Output per channel
    /// `floor(value * 2^16)` of the fixed-point filter, within [`arithmetic_error_bound`] of the
    /// exact filter on the stored levels.
    ///
    /// Cost: 16 reads (fewer only where `Border` reads zero outside a level), 15 multiplies and
    /// 30 additive operations per channel.
    ///
    /// Errors: [`Error::InvertedBox`] if `x1 < x0` or `y1 < y0`;
    /// [`Error::FracBitsUnsupported`] if `X` has more than 24 fractional bits;
    /// [`Error::CoordinateOutOfRange`] only for a centre at the very bottom of `i64` (module
    /// docs). A zero-area footprint is a point sample of level 0 (bilinear), not an error.
    pub fn sample<X: Coord, M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<X>,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.sample_raw(&rect.to_raw(), FracBits::of::<X>()?, mode, k)
    }

    /// [`RipMap::sample`] with raw corners (`value * 2^F`) and `F` as a value, checked once by
    /// [`FracBits::new`]: one compiled sampler serves every `F`.
    pub fn sample_raw<M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<i64>,
        frac_bits: FracBits,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let fp = footprint_raw(rect, frac_bits)?;
        #[allow(
            clippy::as_conversions,
            reason = "at most MAX_LEVELS = 32 levels per axis (prefix's capacity is 33): lossless"
        )]
        let (top_x, top_y) = (
            self.levels_x().saturating_sub(1) as u32,
            self.levels_y().saturating_sub(1) as u32,
        );
        let (lox, hix, fx) = level_split(fp.w, fp.f, LEVEL_FRAC_BITS, top_x);
        let (loy, hiy, fy) = level_split(fp.h, fp.f, LEVEL_FRAC_BITS, top_y);
        let shift = 2 * WEIGHT_BITS - OUT_FRAC_BITS;
        let probe = |lx: u32, ly: u32, k: &mut K| -> Result<[u64; C], Error> {
            #[allow(
                clippy::as_conversions,
                reason = "lx <= top_x, ly <= top_y < 32 (level_split): lossless"
            )]
            let level = self.view(lx as usize, ly as usize);
            Ok(truncate(
                level.bilinear(mode, &fp, lx, ly, WEIGHT_BITS, k)?,
                shift,
            ))
        };
        let v00 = probe(lox, loy, k)?;
        let v10 = probe(hix, loy, k)?;
        let v01 = probe(lox, hiy, k)?;
        let v11 = probe(hix, hiy, k)?;
        let b0 = lerp(v00, v10, fx, LEVEL_FRAC_BITS, k);
        let b1 = lerp(v01, v11, fx, LEVEL_FRAC_BITS, k);
        let out = lerp(b0, b1, fy, LEVEL_FRAC_BITS, k);
        Ok(floor_sample(out, 2 * LEVEL_FRAC_BITS))
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
    use crate::cost::NoCount;
    use crate::cost::Tally;
    use crate::edge::{Border, ClampToEdge, MirroredRepeat, Repeat};
    use fixed::types::{I24F8, I40F24, I48F16, I56F8, I60F4, I64F0};
    use std::vec;
    use std::vec::Vec;

    /// The error bounds are the documented values wherever they fit `u64` and `u64::MAX`
    /// past that: no panic, no wrap, never smaller for a wider texel.
    #[test]
    fn error_bounds_saturate_and_never_shrink() {
        let want = |exact: Option<u128>| match exact {
            Some(v) if v <= u64::MAX as u128 => v as u64,
            _ => u64::MAX,
        };
        let mut prev = (0u64, 0u64);
        for b in (0..=130u32).chain([u32::MAX - 1, u32::MAX]) {
            let arith = (b < 127).then(|| 1u128 << (b + 1));
            let level = (b < 128 - 6).then(|| ((1u128 << b) - 1) << 6);
            let got = (arithmetic_error_bound(b), level_selection_error_bound(b));
            assert_eq!(got, (want(arith), want(level)), "{b}");
            assert!(got.0 >= prev.0 && got.1 >= prev.1, "{b}");
            prev = got;
        }
    }

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *seed >> 33
    }

    fn texels(n: usize, max: u64, seed: u64) -> Vec<u16> {
        let mut s = seed;
        (0..n).map(|_| (lcg(&mut s) % (max + 1)) as u16).collect()
    }

    #[test]
    fn storage_and_ratio() {
        assert_eq!(RipMap::<u8, 1>::storage_needed(5, 3), 11 * 6);
        assert_eq!(RipMap::<u8, 3>::storage_needed(1, 1), 3);
        assert_eq!(RipMap::<u8, 1>::storage_needed(1024, 1024), 2047 * 2047);
        assert_eq!(RipMap::<u8, 1>::storage_needed(0, 4), 0);
        let r = RipMap::<u8, 1>::storage_needed(1 << 12, 1 << 12) as f64 / (1u64 << 24) as f64;
        assert!((r - 4.0).abs() < 1e-3, "{r}");
        let t = vec![0u8; 15];
        let tex = Texture::<u8>::new(&t, 5, 3).unwrap();
        let mut st = vec![0u8; 65];
        assert_eq!(
            RipMap::build(&tex, &mut st).unwrap_err(),
            Error::StorageTooSmall {
                needed: 66,
                got: 65
            }
        );
    }

    #[test]
    fn levels_are_rounded_block_averages() {
        for (w, h) in [(5usize, 3usize), (1, 7), (6, 1), (8, 8), (7, 9)] {
            let t: Vec<u8> = texels(w * h * 2, 255, (w * 31 + h) as u64)
                .iter()
                .map(|&v| v as u8)
                .collect();
            let tex = Texture::<u8, 2>::new(&t, w, h).unwrap();
            let mut st = vec![0u8; RipMap::<u8, 2>::storage_needed(w, h)];
            let map = RipMap::build(&tex, &mut st).unwrap();
            for ly in 0..map.levels_y() {
                for lx in 0..map.levels_x() {
                    let (lw, lh) = map.level_size(lx, ly).unwrap();
                    for j in 0..lh {
                        for i in 0..lw {
                            let got = map.level_texel(lx, ly, i, j).unwrap();
                            for c in 0..2 {
                                let (mut s, mut n) = (0u64, 0u64);
                                for y in (j << ly)..((j + 1) << ly).min(h) {
                                    for x in (i << lx)..((i + 1) << lx).min(w) {
                                        s += t[(y * w + x) * 2 + c] as u64;
                                        n += 1;
                                    }
                                }
                                // v = floor(s / n + 1/2): 2 n v <= 2 s + n < 2 n v + 2 n.
                                let v = got[c] as u64;
                                assert!(2 * n * v <= 2 * s + n, "{w}x{h} ({lx},{ly}) {i},{j}");
                                assert!(2 * s + n < 2 * n * v + 2 * n);
                            }
                        }
                    }
                }
            }
            assert_eq!(map.level_texel(map.levels_x(), 0, 0, 0), None);
            assert_eq!(map.level_size(0, map.levels_y()), None);
        }
    }

    /// The f64 filter on the stored levels, with the same fixed-point level positions.
    fn reference(map: &RipMap<'_, u16, 1>, r: [i64; 4], f: u32, mode: u8) -> f64 {
        let idx = |i: i64, n: usize| -> Option<usize> {
            match mode {
                0 => crate::EdgeKind::Border.texel_index(i, n),
                1 => crate::EdgeKind::Clamp.texel_index(i, n),
                2 => crate::EdgeKind::Repeat.texel_index(i, n),
                _ => crate::EdgeKind::Mirror.texel_index(i, n),
            }
        };
        let split = |side: i64, top: usize| {
            let l = log2_fixed(side as u64, f, LEVEL_FRAC_BITS)
                .unwrap_or(0)
                .clamp(0, (top as i32) << LEVEL_FRAC_BITS);
            let lo = (l >> LEVEL_FRAC_BITS) as usize;
            (
                lo,
                (lo + 1).min(top),
                (l & ((1 << LEVEL_FRAC_BITS) - 1)) as f64 / (1 << LEVEL_FRAC_BITS) as f64,
            )
        };
        let s = (1u64 << f) as f64;
        let (cx, cy) = (
            (r[0] + r[2]) as f64 / 2.0 / s,
            (r[1] + r[3]) as f64 / 2.0 / s,
        );
        let probe = |lx: usize, ly: usize| {
            let (lw, lh) = map.level_size(lx, ly).unwrap();
            let u = cx / (1u64 << lx) as f64 - 0.5;
            let v = cy / (1u64 << ly) as f64 - 0.5;
            let (i0, j0) = (u.floor(), v.floor());
            let (a, b) = (u - i0, v - j0);
            let t = |i: f64, j: f64| match (idx(i as i64, lw), idx(j as i64, lh)) {
                (Some(x), Some(y)) => map.level_texel(lx, ly, x, y).unwrap()[0] as f64,
                _ => 0.0,
            };
            let r0 = t(i0, j0) * (1.0 - a) + t(i0 + 1.0, j0) * a;
            let r1 = t(i0, j0 + 1.0) * (1.0 - a) + t(i0 + 1.0, j0 + 1.0) * a;
            r0 * (1.0 - b) + r1 * b
        };
        let (lox, hix, fx) = split(r[2] - r[0], map.levels_x() - 1);
        let (loy, hiy, fy) = split(r[3] - r[1], map.levels_y() - 1);
        let b0 = probe(lox, loy) * (1.0 - fx) + probe(hix, loy) * fx;
        let b1 = probe(lox, hiy) * (1.0 - fx) + probe(hix, hiy) * fx;
        b0 * (1.0 - fy) + b1 * fy
    }

    fn sample_mode(map: &RipMap<'_, u16, 1>, r: &Rect<I24F8>, mode: u8, k: &mut Tally) -> u64 {
        match mode {
            0 => map.sample(r, Border, k),
            1 => map.sample(r, ClampToEdge, k),
            2 => map.sample(r, Repeat, k),
            _ => map.sample(r, MirroredRepeat, k),
        }
        .unwrap()
        .values[0]
    }

    #[test]
    fn within_bound_of_f64_and_costs() {
        let mut seed = 7u64;
        for (w, h) in [(5usize, 3usize), (1, 6), (9, 1), (8, 8), (13, 7)] {
            let t = texels(w * h, 65535, (w * 7 + h) as u64);
            let tex = Texture::<u16>::new(&t, w, h).unwrap();
            let mut st = vec![0u16; RipMap::<u16, 1>::storage_needed(w, h)];
            let map = RipMap::build(&tex, &mut st).unwrap();
            let mut worst = 0.0f64;
            // Under Miri (about 10^4 times slower) 6 random boxes per texture.
            for _ in 0..if cfg!(miri) { 6 } else { 400 } {
                let x0 = (lcg(&mut seed) % 5000) as i64 - 1500;
                let y0 = (lcg(&mut seed) % 5000) as i64 - 1500;
                let wr = (lcg(&mut seed) % 6000) as i64;
                let hr = (lcg(&mut seed) % 6000) as i64;
                let r = [x0, y0, x0 + wr, y0 + hr];
                let rect = Rect::new(
                    I24F8::from_bits(r[0] as i32),
                    I24F8::from_bits(r[1] as i32),
                    I24F8::from_bits(r[2] as i32),
                    I24F8::from_bits(r[3] as i32),
                );
                for mode in 0..4u8 {
                    let mut k = Tally::new();
                    let got = sample_mode(&map, &rect, mode, &mut k);
                    let want = reference(&map, r, 8, mode) * 65536.0;
                    let err = (got as f64 - want).abs();
                    worst = worst.max(err);
                    assert!(err < arithmetic_error_bound(16) as f64, "{err}");
                    assert_eq!((k.muls, k.adds), (15, 30));
                    if mode != 0 {
                        assert_eq!(k.reads, 16);
                    } else {
                        assert!(k.reads <= 16);
                    }
                }
            }
            assert!(worst > 0.0);
        }
    }

    /// The earlier formulation: doubled centre and positions in `i128`, lerps in `i64`.
    fn sample_i128(map: &RipMap<'_, u16, 1>, r: [i64; 4], f: u32, kind: crate::EdgeKind) -> u64 {
        let (px, py) = (r[0] as i128 + r[2] as i128, r[1] as i128 + r[3] as i128);
        let top_x = map.levels_x() as u32 - 1;
        let top_y = map.levels_y() as u32 - 1;
        let split = |side: i64, top: u32| {
            let l = log2_fixed(side as u64, f, LEVEL_FRAC_BITS)
                .unwrap_or(0)
                .clamp(0, (top as i32) << LEVEL_FRAC_BITS) as u32;
            let lo = l >> LEVEL_FRAC_BITS;
            (
                lo,
                (lo + 1).min(top),
                (l & ((1 << LEVEL_FRAC_BITS) - 1)) as i64,
            )
        };
        let (lox, hix, fx) = split(r[2] - r[0], top_x);
        let (loy, hiy, fy) = split(r[3] - r[1], top_y);
        let pos = |p: i128, s: u32| {
            let t = p - (1i128 << (s - 1));
            let frac = t & ((1i128 << s) - 1);
            let a = if s >= WEIGHT_BITS {
                frac >> (s - WEIGHT_BITS)
            } else {
                frac << (WEIGHT_BITS - s)
            };
            (t >> s, a as i64)
        };
        let lerp = |b: i64, c: i64, a: i64, bits: u32| (b << bits) + (c - b) * a;
        let probe = |lx: u32, ly: u32| -> i64 {
            let (lw, lh) = map.level_size(lx as usize, ly as usize).unwrap();
            let (i0, ax) = pos(px, f + 1 + lx);
            let (j0, ay) = pos(py, f + 1 + ly);
            let t = |i: i128, j: i128| match (
                kind.texel_index(i as i64, lw),
                kind.texel_index(j as i64, lh),
            ) {
                (Some(x), Some(y)) => {
                    map.level_texel(lx as usize, ly as usize, x, y).unwrap()[0] as i64
                }
                _ => 0,
            };
            let r0 = lerp(t(i0, j0), t(i0 + 1, j0), ax, WEIGHT_BITS);
            let r1 = lerp(t(i0, j0 + 1), t(i0 + 1, j0 + 1), ax, WEIGHT_BITS);
            lerp(r0, r1, ay, WEIGHT_BITS) >> (2 * WEIGHT_BITS - OUT_FRAC_BITS)
        };
        let b0 = lerp(probe(lox, loy), probe(hix, loy), fx, LEVEL_FRAC_BITS);
        let b1 = lerp(probe(lox, hiy), probe(hix, hiy), fx, LEVEL_FRAC_BITS);
        (lerp(b0, b1, fy, LEVEL_FRAC_BITS).max(0) >> (2 * LEVEL_FRAC_BITS)) as u64
    }

    #[test]
    fn bit_for_bit_with_the_i128_formulation() {
        let mut seed = 31u64;
        for (w, h) in [(5usize, 3usize), (1, 6), (9, 1), (13, 7)] {
            let t = texels(w * h, 65535, (w * 5 + h) as u64);
            let tex = Texture::<u16>::new(&t, w, h).unwrap();
            let mut st = vec![0u16; RipMap::<u16, 1>::storage_needed(w, h)];
            let map = RipMap::build(&tex, &mut st).unwrap();
            // Under Miri (about 10^4 times slower) 4 random boxes per texture.
            for _ in 0..if cfg!(miri) { 4 } else { 1500 } {
                let f = [0u32, 4, 8, 16, 24][(lcg(&mut seed) % 5) as usize];
                let span = (w.max(h) as i64 * 3) << f;
                let x0 = (lcg(&mut seed) as i64 % span) - span / 3;
                let y0 = (lcg(&mut seed) as i64 % span) - span / 3;
                let r = [
                    x0,
                    y0,
                    x0 + (lcg(&mut seed) as i64 % span),
                    y0 + (lcg(&mut seed) as i64 % span),
                ];
                for kind in crate::EdgeKind::ALL {
                    let got = match f {
                        0 => map.sample(
                            &Rect::new(
                                I64F0::from_bits(r[0]),
                                I64F0::from_bits(r[1]),
                                I64F0::from_bits(r[2]),
                                I64F0::from_bits(r[3]),
                            ),
                            kind,
                            &mut NoCount,
                        ),
                        4 => map.sample(
                            &Rect::new(
                                I60F4::from_bits(r[0]),
                                I60F4::from_bits(r[1]),
                                I60F4::from_bits(r[2]),
                                I60F4::from_bits(r[3]),
                            ),
                            kind,
                            &mut NoCount,
                        ),
                        8 => map.sample(
                            &Rect::new(
                                I56F8::from_bits(r[0]),
                                I56F8::from_bits(r[1]),
                                I56F8::from_bits(r[2]),
                                I56F8::from_bits(r[3]),
                            ),
                            kind,
                            &mut NoCount,
                        ),
                        16 => map.sample(
                            &Rect::new(
                                I48F16::from_bits(r[0]),
                                I48F16::from_bits(r[1]),
                                I48F16::from_bits(r[2]),
                                I48F16::from_bits(r[3]),
                            ),
                            kind,
                            &mut NoCount,
                        ),
                        _ => map.sample(
                            &Rect::new(
                                I40F24::from_bits(r[0]),
                                I40F24::from_bits(r[1]),
                                I40F24::from_bits(r[2]),
                                I40F24::from_bits(r[3]),
                            ),
                            kind,
                            &mut NoCount,
                        ),
                    };
                    assert_eq!(
                        got.unwrap().values[0],
                        sample_i128(&map, r, f, kind),
                        "{w}x{h} {r:?} F={f}"
                    );
                }
            }
        }
    }

    #[test]
    fn three_channels_count_arithmetic_per_channel() {
        let t: Vec<u8> = (0..6 * 5 * 3).map(|v| (v * 7 % 256) as u8).collect();
        let tex = Texture::<u8, 3>::new(&t, 6, 5).unwrap();
        let mut st = vec![0u8; RipMap::<u8, 3>::storage_needed(6, 5)];
        let map = RipMap::build(&tex, &mut st).unwrap();
        let mut k = Tally::new();
        let r = Rect::<I24F8>::from_f64(1.3, 0.7, 4.1, 2.2).unwrap();
        map.sample(&r, Repeat, &mut k).unwrap();
        assert_eq!(
            (k.reads, k.bits_read, k.muls, k.adds),
            (16, 16 * 24, 45, 90)
        );
    }

    #[test]
    fn constant_texture_is_exact_and_magnification_is_bilinear() {
        let t = vec![200u8; 7 * 5];
        let tex = Texture::<u8>::new(&t, 7, 5).unwrap();
        let mut st = vec![0u8; RipMap::<u8, 1>::storage_needed(7, 5)];
        let map = RipMap::build(&tex, &mut st).unwrap();
        for (x0, x1) in [(0.0, 0.0), (-3.0, 20.0), (2.5, 2.75), (1.0, 5.0)] {
            let r = Rect::<I24F8>::from_f64(x0, 1.0, x1, 3.0).unwrap();
            let s = map.sample(&r, ClampToEdge, &mut Tally::new()).unwrap();
            assert_eq!(s.values[0], 200 << 16);
        }
        // Point footprint on a texel centre of level 0 reads exactly that texel.
        let t: Vec<u8> = (0..35).map(|v| v as u8).collect();
        let tex = Texture::<u8>::new(&t, 7, 5).unwrap();
        let map = RipMap::build(&tex, &mut st).unwrap();
        let r = Rect::<I24F8>::from_f64(3.5, 2.5, 3.5, 2.5).unwrap();
        let s = map.sample(&r, Border, &mut Tally::new()).unwrap();
        assert_eq!(s.values[0], 17 << 16);
    }

    #[test]
    fn error_bound_is_approached() {
        // Weights just below 2^-16 on both axes (F = 24: 25 position bits at level 0) and a
        // single bright texel at the top-left of the probe: the truncated weights (0, 0) read
        // it fully; the exact ones read m (1 - a)(1 - b).
        let mut t = vec![0u16; 4 * 4];
        t[4 + 1] = 65535;
        let tex = Texture::<u16>::new(&t, 4, 4).unwrap();
        let mut st = vec![0u16; RipMap::<u16, 1>::storage_needed(4, 4)];
        let map = RipMap::build(&tex, &mut st).unwrap();
        // centre (1.5 + a) with a = (2^9 - 2) / 2^25 < 2^-16 ; raw x0 = x1 = centre * 2^24.
        let c = (3i64 << 23) + ((1 << 9) - 2) / 2;
        let b = I40F24::from_bits(c);
        let r = Rect::new(b, b, b, b);
        let got = map.sample(&r, Border, &mut Tally::new()).unwrap().values[0] as f64;
        let a = ((1 << 9) - 2) as f64 / (1u64 << 25) as f64;
        let exact = 65535.0 * (1.0 - a) * (1.0 - a) * 65536.0;
        let err = (got - exact).abs();
        let bound = arithmetic_error_bound(16) as f64;
        assert!(err < bound && err > 0.99 * bound, "{err} vs {bound}");
    }

    #[test]
    fn refusals_and_extremes_do_not_panic() {
        let t = vec![9u8; 6];
        let tex = Texture::<u8>::new(&t, 3, 2).unwrap();
        let mut st = vec![0u8; RipMap::<u8, 1>::storage_needed(3, 2)];
        let map = RipMap::build(&tex, &mut st).unwrap();
        let r = Rect::<I24F8>::from_f64(2.0, 0.0, 1.0, 1.0).unwrap();
        assert_eq!(
            map.sample(&r, Border, &mut Tally::new()).unwrap_err(),
            Error::InvertedBox
        );
        type X = fixed::types::I32F32;
        let r = Rect::<X>::from_f64(0.0, 0.0, 1.0, 1.0).unwrap();
        assert!(matches!(
            map.sample(&r, Border, &mut Tally::new()),
            Err(Error::FracBitsUnsupported { .. })
        ));
        type Z = fixed::types::I64F0;
        let r = Rect::new(Z::MIN, Z::MIN, Z::MAX, Z::MAX);
        for v in [
            map.sample(&r, Border, &mut Tally::new()),
            map.sample(&r, ClampToEdge, &mut Tally::new()),
            map.sample(&r, Repeat, &mut Tally::new()),
            map.sample(&r, MirroredRepeat, &mut Tally::new()),
        ] {
            assert!(v.unwrap().values[0] <= 9 << 16);
        }
        let r = Rect::new(
            Z::MAX,
            Z::from_bits(i64::MIN + 1),
            Z::MAX,
            Z::from_bits(i64::MIN + 1),
        );
        assert!(map.sample(&r, Repeat, &mut Tally::new()).is_ok());
        // y0 = y1 = i64::MIN at F = 0: the probe's upper tap is below i64::MIN (before the
        // 64-bit positions it was folded from an i128 index; now a typed refusal).
        let r = Rect::new(Z::MAX, Z::MIN, Z::MAX, Z::MIN);
        assert_eq!(
            map.sample(&r, Repeat, &mut Tally::new()),
            Err(Error::CoordinateOutOfRange)
        );
        assert!(RipMap::<u8, 1>::from_storage(&st, 3, 2).is_ok());
        assert!(RipMap::<u8, 1>::from_storage(&st[..5], 3, 2).is_err());
        assert_eq!(
            RipMap::<u8, 1>::from_storage(&st, 0, 2).unwrap_err(),
            Error::EmptyTexture
        );
    }
}
