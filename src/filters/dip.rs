//! Du and Wan's dipmap ("Dipmap: A New Texture Filtering Method for Texture Mapping"): a *row
//! pyramid* and a *column pyramid*, each prefiltered along one axis only, sampled independently
//! at the footprint's two scaling ratios and averaged.
//!
//! # The two pyramids, in x/y terms
//!
//! The paper (§II-B): "the row pyramid is obtained by 1 x 2 downsampling of the original texture
//! image until image height is one, while column pyramid is obtained by 2 x 1 downsampling ...
//! until image width is one" (their sizes are column count first, §II-A). §II-A: "a row sampling
//! in row pyramid level determined by row scaling ratio `L_y = log2(S_y)` and a column sampling in
//! column pyramid level determined by column scaling ratio `L_x = log2(S_x)`". So, with x to the
//! right and y down:
//!
//! * [`DipPyramid::Row`]: level `l` is `w x ceil(h / 2^l)`, each texel the average of up to `2^l`
//!   vertically adjacent base texels (the levels shrink **y**). It is sampled at level
//!   `Ly = log2(H)`, `H` the footprint's height in texels.
//! * [`DipPyramid::Column`]: level `l` is `ceil(w / 2^l) x h`, averaging horizontally (the levels
//!   shrink **x**). It is sampled at level `Lx = log2(W)`.
//!
//! That is: the pyramid whose levels shrink an axis is sampled at the log2 of the footprint's
//! side along that axis. (The paper's step 3 in §II-C swaps the two names, "`L_x` for row
//! sampling"; §II-A, §II-B and the row pyramid's 1 x 2 construction agree with the mapping
//! above, which is also the only one under which each pyramid filters the footprint's own side.)
//!
//! Every stored texel is `round(sum / count)` (to nearest, ties up) of the exact integer sum of
//! its block of *base* texels, clipped to the texture: within 1/2 LSB of the exact average, and no
//! level is computed from another, so nothing accumulates.
//!
//! # Memory
//!
//! Level 0 of both pyramids is the texture itself, stored once. Storage (caller `&mut [T]`):
//! the row pyramid's levels `0..=ceil(log2 h)`, then the column pyramid's levels
//! `1..=ceil(log2 w)`: [`DipMap::storage_needed`] `= C (w * sum_l ceil(h / 2^l) + h * (sum_l
//! ceil(w / 2^l) - w))`. For powers of two that is `C (w (2h - 1) + h (w - 1)) = C (3wh - w - h)`:
//! the row pyramid is 2x the texture, the column pyramid 2x, sharing level 0 gives the paper's 3x
//! (measured: 1024 x 1024 gives 2.998; 5 x 3 gives `5 * (3 + 2 + 1) + 3 * (3 + 2 + 1) = 48`
//! texels, 3.2x, since odd sides round every level up). Ripmap is 4x, mipmap 4/3.
//!
//! # Sampling
//!
//! Level positions `Lx = log2(W)`, `Ly = log2(H)` in fixed point with [`LEVEL_FRAC_BITS`]
//! fractional bits ([`crate::filters::level::log2_fixed`]: the exact floor or one unit below,
//! exact at powers of two), clamped to `[0, top]` (`top = ceil(log2 n)`, the 1-texel level; a side
//! of at most one texel, or zero, is level 0). A bilinear probe at the footprint centre in a level
//! that shrinks x by `2^sx` and y by `2^sy` interpolates the four level texels around
//! `(cx / 2^sx - 1/2, cy / 2^sy - 1/2)`; indices outside the level are resolved by the boundary
//! mode on the level's own grid (`Border`: zero).
//!
//! * [`DipFilter::Bilinear`], the variant the paper measures (§III-A: "we use the bilinear
//!   interpolation in the single pyramid level, the lower pyramid level, both for row sampling and
//!   column sampling"): one bilinear probe in column level `floor(Lx)`, one in row level
//!   `floor(Ly)`, averaged.
//! * [`DipFilter::Trilinear`], the paper's general form (§III-B: "two trilinear interpolations and
//!   a linear interpolation"): per pyramid, probes in `floor(L)` and `hi = min(floor(L) + 1, top)`
//!   lerped by `frac(L)`; the two results averaged.
//!
//! The average `(a + b) / 2` is one add and a shift (a fixed weight of 1/2 needs no multiplier).
//!
//! # Arithmetic and error bound
//!
//! Integer, 64 bits (`u64`), as in the ripmap (`filters::rip`), with the same footprint
//! arithmetic and the same single refusal ([`Error::CoordinateOutOfRange`] for a centre at the
//! very bottom of `i64` at `F = 0`): probe weights truncated to [`WEIGHT_BITS`]
//! bits, each probe exact for its truncated weights at `2 * WEIGHT_BITS` fraction bits.
//! `Bilinear`: `(a + b) >> 17` (floor) to [`OUT_FRAC_BITS`] bits. `Trilinear`: each probe
//! truncated to 16 fraction bits, the level lerp exact at `16 + LEVEL_FRAC_BITS` bits, then
//! `(a + b) >> (LEVEL_FRAC_BITS + 1)` (floor). Output is floored, not rounded: a rounding add
//! is not in the paper's operation count.
//!
//! **Bound** (against the same filter in `f64` on the stored levels with the same fixed-point
//! `Lx`, `Ly`, exact positions and weights), both variants: `|out - 2^16 * exact| < 2^(b+1)`
//! output units (`< (m + 1) 2^-15` texel units, `m = 2^b - 1`). Derivation: truncating a probe's
//! two weights by less than `2^-16` each moves it by less than `m 2^-15` (it is bilinear in the
//! weights with corners in `[0, m]`); the 16-bit truncation (trilinear) adds `(-2^-16, 0]`; lerps
//! and the average are convex combinations; the final floor adds `(-2^-16, 0]`. Total
//! `(-(m + 1) 2^-15, m 2^-15)`. See [`arithmetic_error_bound`]; the unit tests approach it.
//!
//! Against the exact `log2`: `Trilinear` is Lipschitz with constant `m / 2` in each of `Lx`, `Ly`
//! (a lerp between values in `[0, m]`, halved by the average), and `log2_fixed` is low by less
//! than 2 units of `2^-12`: less than `m 2^(1 - LEVEL_FRAC_BITS)` texel units more
//! ([`level_selection_error_bound`]). `Bilinear` is not continuous in `L` (it jumps at integer
//! levels, as the paper intends); it can pick the level below the exact `floor(L)` only when the
//! exact `L` lies less than `2^-12` above an integer (never at exact powers of two).
//!
//! # Cost, and how it compares with the survey's rows
//!
//! Counted as Crow §2.2 counts: a lerp is 1 multiply and 2 additive operations, a bilinear probe
//! 4 reads and 3 lerps. Reads are per texel, all channels together; the arithmetic per channel.
//!
//! | filter | reads | multiplies | additive |
//! |---|---|---|---|
//! | mipmap, trilinear (survey: 8, 7) | 8 | 7 | 14 |
//! | **dipmap `Bilinear`** (2 bilinear + average) | **8** | **6** | **13** (2 * 6 + 1) |
//! | **dipmap `Trilinear`** (2 trilinear + average) | **16** | **14** | **29** (2 * 14 + 1) |
//! | ripmap (survey: 16, 15) | 16 | 15 | 30 |
//!
//! The survey has no dipmap row. The paper argues (§III-B) that its measured variant "and Mipmap
//! have the same filtering efficiency": two bilinear interpolations plus the "linear
//! interpolation" between the row and column samples equal one trilinear interpolation. Counted
//! the survey's way that is 8 reads and 7 multiplies if the average is done as a lerp with
//! weight 1/2; as a fixed average it is an add and a shift, so 8 reads and 6 multiplies: the same
//! texel traffic as trilinear mipmap and one multiply less. The trilinear dipmap reads as many
//! texels as the ripmap (16) and saves one multiply and one add (the ripmap's third blend lerp
//! becomes the fixed average). The paper's timings (Table I: dipmap 1.1x mipmap, ripmap 2.1x)
//! match the bilinear variant's counts. Reads that `Border` resolves to zero outside a level
//! fetch nothing and are not counted; clamped probes (`hi == lo` at the top level) are fetched
//! and counted, so the cost is constant per sample as in the survey.
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
use crate::filters::{per_channel, pyramid, u64_from_usize, Sample, OUT_FRAC_BITS};
use crate::rect::{Coord, FracBits, Rect};
use crate::texel::Texel;
use crate::texture::Texture;

/// Fraction bits of a bilinear probe's weights (positions truncated to `2^-16` level texels).
pub const WEIGHT_BITS: u32 = 16;

/// Fraction bits of the level positions `Lx`, `Ly` (and so of the trilinear level weights).
pub const LEVEL_FRAC_BITS: u32 = 12;

/// The most levels a pyramid can have: sides up to `2^31 - 1` texels need levels `0..=31`.
pub const MAX_LEVELS: usize = pyramid::MAX_LEVELS;

/// The arithmetic error bound of both variants in output units:
/// `|out - 2^16 * exact| < 2^(texel_bits + 1)` (module docs). `exact` is the same filter in real
/// arithmetic on the stored levels with the same fixed-point level positions.
///
/// For texel widths whose bound does not fit `u64` (63 bits and more; every [`Texel`] has at
/// most 16) the result is `u64::MAX`: the bound never shrinks as the width grows.
pub const fn arithmetic_error_bound(texel_bits: u32) -> u64 {
    pyramid::pow2_or_max(texel_bits.saturating_add(1))
}

/// The extra error of [`DipFilter::Trilinear`], in output units, of the fixed-point level
/// positions against the exact `log2`: less than `m 2^(1 - LEVEL_FRAC_BITS) * 2^16`,
/// `m = 2^texel_bits - 1` (module docs). [`DipFilter::Bilinear`] has no such bound.
///
/// `u64::MAX` where the bound does not fit `u64` (texel widths of more than 59 bits; every
/// [`Texel`] has at most 16): the bound never shrinks as the width grows.
pub const fn level_selection_error_bound(texel_bits: u32) -> u64 {
    pyramid::mask_shl_or_max(texel_bits, OUT_FRAC_BITS + 1 - LEVEL_FRAC_BITS)
}

/// Which of the two pyramids.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DipPyramid {
    /// The paper's row pyramid: "1 x 2 downsampling ... until image height is one". Level `l`
    /// is `w x ceil(h / 2^l)` (shrinks y); sampled at `log2(H)`.
    Row,
    /// The paper's column pyramid: "2 x 1 downsampling ... until image width is one". Level `l`
    /// is `ceil(w / 2^l) x h` (shrinks x); sampled at `log2(W)`.
    Column,
}

/// Which dipmap filter to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DipFilter {
    /// The paper's measured variant: bilinear in the lower level `floor(L)` of each pyramid,
    /// averaged. 8 reads, 6 multiplies, 13 additive operations (per channel).
    Bilinear,
    /// Trilinear in each pyramid (levels `floor(L)` and `floor(L) + 1`), averaged. 16 reads, 14
    /// multiplies, 29 additive operations (per channel).
    Trilinear,
}

/// A dipmap over caller storage: the row and the column pyramid (module docs).
#[derive(Debug, Clone)]
pub struct DipMap<'a, T: Texel, const C: usize> {
    data: &'a [T],
    width: usize,
    height: usize,
    /// `wcum[l] = sum_{k < l} ceil(w / 2^k)` for `l = 0..=levels_x` (column pyramid widths).
    wcum: heapless::Vec<usize, { MAX_LEVELS + 1 }>,
    /// `hcum[l] = sum_{k < l} ceil(h / 2^k)` for `l = 0..=levels_y` (row pyramid heights).
    hcum: heapless::Vec<usize, { MAX_LEVELS + 1 }>,
}

impl<'a, T: Texel, const C: usize> DipMap<'a, T, C> {
    /// Elements of `T` both pyramids of a `width x height` texture need, level 0 shared:
    /// `C (w * sum_l ceil(h / 2^l) + h * (sum_l ceil(w / 2^l) - w))` (`C (3wh - w - h)` for
    /// powers of two). Saturates at `usize::MAX` (the build then refuses); 0 for an empty texture.
    pub fn storage_needed(width: usize, height: usize) -> usize {
        if width == 0 || height == 0 {
            return 0;
        }
        let rows = width.saturating_mul(axis_total(height));
        let cols = height.saturating_mul(axis_total(width).saturating_sub(width));
        rows.saturating_add(cols).saturating_mul(C)
    }

    /// Builds both pyramids from the exact block sums of `texture` into `storage`.
    ///
    /// Errors: [`Error::StorageTooSmall`] if `storage` is shorter than
    /// [`DipMap::storage_needed`]; [`Error::TooWide`] (`Quantity::Entry`, 64 bits available) if a
    /// block sum could overflow the `u64` accumulator (`(2m + 1) w h >= 2^64`; checked, not
    /// assumed).
    ///
    /// Cost: one pass over the texture per level (not counted: prefiltering is off the
    /// per-sample path).
    pub fn build(texture: &Texture<'_, T, C>, storage: &'a mut [T]) -> Result<Self, Error> {
        let (w, h) = (texture.width(), texture.height());
        let needed = Self::storage_needed(w, h);
        check_build(T::BITS, w, h, needed, storage.len())?;
        let mut map = Self::layout(&[], w, h);
        let levels = [
            (DipPyramid::Row, 0, map.levels(DipPyramid::Row)),
            (DipPyramid::Column, 1, map.levels(DipPyramid::Column)),
        ];
        for (pyramid, first, count) in levels {
            for l in first..count {
                let (start, len) = map.level_range(pyramid, l);
                let out = storage
                    .get_mut(start..start.saturating_add(len))
                    .ok_or(Error::StorageTooSmall { needed, got: start })?;
                let (sx, sy) = match pyramid {
                    DipPyramid::Row => (0, l),
                    DipPyramid::Column => (l, 0),
                };
                fill_box_level(texture, out, sx, sy)?;
            }
        }
        let data: &'a [T] = storage;
        map.data = data.get(..needed).unwrap_or(&[]);
        Ok(map)
    }

    /// Wraps pyramids built elsewhere (flash, an earlier [`DipMap::build`]) in the layout
    /// `build` writes. Every `T` value is a valid texel, so only the length is checked.
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
        DipMap {
            data,
            width,
            height,
            wcum: prefix(width),
            hcum: prefix(height),
        }
    }

    /// `(width, height)` of level `l` of `pyramid` (no range check).
    fn size(&self, pyramid: DipPyramid, l: usize) -> (usize, usize) {
        match pyramid {
            DipPyramid::Row => (self.width, level_len(self.height, l)),
            DipPyramid::Column => (level_len(self.width, l), self.height),
        }
    }

    /// Start and length (elements) of level `l` of `pyramid`. Column level 0 is row level 0 (the
    /// texture). Within the levels the sums fit (they are below `storage_needed`); saturating
    /// arithmetic and the `usize::MAX` start of a level past the top only make it empty.
    fn level_range(&self, pyramid: DipPyramid, l: usize) -> (usize, usize) {
        let (lw, lh) = self.size(pyramid, l);
        let start = match pyramid {
            DipPyramid::Column if l > 0 => {
                let (Some(&rows), Some(&wc)) = (self.hcum.last(), self.wcum.get(l)) else {
                    return (usize::MAX, 0);
                };
                self.width
                    .saturating_mul(rows)
                    .saturating_add(self.height.saturating_mul(wc.saturating_sub(self.width)))
                    .saturating_mul(C)
            }
            _ => {
                let Some(&hc) = self.hcum.get(l) else {
                    return (usize::MAX, 0);
                };
                self.width.saturating_mul(hc).saturating_mul(C)
            }
        };
        (start, lw.saturating_mul(lh).saturating_mul(C))
    }

    fn view(&self, pyramid: DipPyramid, l: usize) -> LevelView<'a, T, C> {
        let (start, len) = self.level_range(pyramid, l);
        let (w, h) = self.size(pyramid, l);
        LevelView {
            data: self
                .data
                .get(start..start.saturating_add(len))
                .unwrap_or(&[]),
            w,
            h,
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

    /// Levels of `pyramid`: `ceil(log2 h) + 1` for [`DipPyramid::Row`], `ceil(log2 w) + 1` for
    /// [`DipPyramid::Column`].
    pub fn levels(&self, pyramid: DipPyramid) -> usize {
        match pyramid {
            DipPyramid::Row => self.hcum.len().saturating_sub(1),
            DipPyramid::Column => self.wcum.len().saturating_sub(1),
        }
    }

    /// `(width, height)` of level `l` of `pyramid`, or `None` past its levels.
    pub fn level_size(&self, pyramid: DipPyramid, l: usize) -> Option<(usize, usize)> {
        (l < self.levels(pyramid)).then(|| self.size(pyramid, l))
    }

    /// Stored texel `(i, j)` of level `l` of `pyramid` (all channels), or `None` outside.
    pub fn level_texel(&self, pyramid: DipPyramid, l: usize, i: usize, j: usize) -> Option<[T; C]> {
        self.level_size(pyramid, l)?;
        self.view(pyramid, l).texel(i, j)
    }

    /// Elements of `T` stored (both pyramids, level 0 once).
    pub fn storage_len(&self) -> usize {
        self.data.len()
    }

    /// Bits stored: `storage_len() * T::BITS`; against the texture's `w * h * C * T::BITS` this
    /// is the paper's "three times" (module docs).
    ///
    /// Saturates at `u64::MAX`, which only a storage of `2^61` bytes of `u8` or `u16` texels
    /// could reach.
    pub fn storage_bits(&self) -> u64 {
        u64_from_usize(self.data.len()).saturating_mul(u64::from(T::BITS))
    }

    /// Filters the footprint bounded by `rect` (module docs): a sample of the column pyramid at
    /// `log2(W)` and of the row pyramid at `log2(H)`, both at the footprint centre, averaged.
    /// Output per channel `floor(value * 2^16)` of the fixed-point filter, within
    /// [`arithmetic_error_bound`] of the exact filter on the stored levels.
    ///
    /// Cost per sample (reads fewer only where `Border` reads zero outside a level):
    /// `Bilinear` 8 reads, 6 multiplies, 13 additive; `Trilinear` 16 reads, 14 multiplies, 29
    /// additive (arithmetic per channel).
    ///
    /// Errors: [`Error::InvertedBox`] if `x1 < x0` or `y1 < y0`;
    /// [`Error::FracBitsUnsupported`] if `X` has more than 24 fractional bits. A zero-area
    /// footprint samples level 0 of both pyramids (bilinear on the texture), not an error.
    pub fn sample<X: Coord, M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<X>,
        filter: DipFilter,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.sample_raw(&rect.to_raw(), FracBits::of::<X>()?, filter, mode, k)
    }

    /// [`DipMap::sample`] with raw corners (`value * 2^F`) and `F` as a value, checked once by
    /// [`FracBits::new`]: one compiled sampler serves every `F`.
    pub fn sample_raw<M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<i64>,
        frac_bits: FracBits,
        filter: DipFilter,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let fp = footprint_raw(rect, frac_bits)?;
        #[allow(
            clippy::as_conversions,
            reason = "at most MAX_LEVELS = 32 levels per pyramid (prefix's capacity is 33): lossless"
        )]
        let (top_x, top_y) = (
            self.levels(DipPyramid::Column).saturating_sub(1) as u32,
            self.levels(DipPyramid::Row).saturating_sub(1) as u32,
        );
        let (lox, hix, fx) = level_split(fp.w, fp.f, LEVEL_FRAC_BITS, top_x);
        let (loy, hiy, fy) = level_split(fp.h, fp.f, LEVEL_FRAC_BITS, top_y);
        #[allow(
            clippy::as_conversions,
            reason = "l <= top_x or top_y < 32 (level_split): lossless"
        )]
        let column = |l: u32, k: &mut K| {
            self.view(DipPyramid::Column, l as usize)
                .bilinear(mode, &fp, l, 0, WEIGHT_BITS, k)
        };
        #[allow(
            clippy::as_conversions,
            reason = "l <= top_x or top_y < 32 (level_split): lossless"
        )]
        let row = |l: u32, k: &mut K| {
            self.view(DipPyramid::Row, l as usize)
                .bilinear(mode, &fp, 0, l, WEIGHT_BITS, k)
        };
        let (a, b, shift) = match filter {
            DipFilter::Bilinear => (
                column(lox, k)?,
                row(loy, k)?,
                2 * WEIGHT_BITS - OUT_FRAC_BITS + 1,
            ),
            DipFilter::Trilinear => {
                let t = 2 * WEIGHT_BITS - OUT_FRAC_BITS;
                let (c0, c1) = (truncate(column(lox, k)?, t), truncate(column(hix, k)?, t));
                let a = lerp(c0, c1, fx, LEVEL_FRAC_BITS, k);
                let (r0, r1) = (truncate(row(loy, k)?, t), truncate(row(hiy, k)?, t));
                let b = lerp(r0, r1, fy, LEVEL_FRAC_BITS, k);
                (a, b, LEVEL_FRAC_BITS + 1)
            }
        };
        // The average (a + b) / 2: one add and a shift.
        k.adds(const { per_channel(1, C) });
        // Both below 2^(16 + 32) (bilinear) or 2^(16 + 16 + 12) (trilinear): no wrap.
        let mut sum = a;
        for (s, b) in sum.iter_mut().zip(b) {
            *s = s.wrapping_add(b);
        }
        Ok(floor_sample(sum, shift))
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
    use fixed::types::{I24F8, I40F24, I56F8, I64F0};
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
            let level = (b < 128 - 5).then(|| ((1u128 << b) - 1) << 5);
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

    const BOTH: [DipPyramid; 2] = [DipPyramid::Row, DipPyramid::Column];

    #[test]
    fn storage_and_ratio() {
        assert_eq!(DipMap::<u8, 1>::storage_needed(5, 3), 48);
        assert_eq!(DipMap::<u8, 2>::storage_needed(1, 1), 2);
        assert_eq!(
            DipMap::<u8, 1>::storage_needed(1024, 1024),
            3 * 1024 * 1024 - 2048
        );
        assert_eq!(DipMap::<u8, 1>::storage_needed(4, 0), 0);
        let r = DipMap::<u8, 1>::storage_needed(1 << 12, 1 << 12) as f64 / (1u64 << 24) as f64;
        assert!((r - 3.0).abs() < 1e-3, "{r}");
        let t = vec![0u8; 15];
        let tex = Texture::<u8>::new(&t, 5, 3).unwrap();
        let mut st = vec![0u8; 47];
        assert_eq!(
            DipMap::build(&tex, &mut st).unwrap_err(),
            Error::StorageTooSmall {
                needed: 48,
                got: 47
            }
        );
    }

    #[test]
    fn levels_are_rounded_one_axis_averages() {
        for (w, h) in [(5usize, 3usize), (1, 7), (6, 1), (8, 8), (7, 9)] {
            let t: Vec<u8> = texels(w * h * 2, 255, (w * 31 + h) as u64)
                .iter()
                .map(|&v| v as u8)
                .collect();
            let tex = Texture::<u8, 2>::new(&t, w, h).unwrap();
            let mut st = vec![0u8; DipMap::<u8, 2>::storage_needed(w, h)];
            let map = DipMap::build(&tex, &mut st).unwrap();
            // The last level of each pyramid is 1 texel along its axis, the one before is not.
            let (ly, lx) = (map.levels(DipPyramid::Row), map.levels(DipPyramid::Column));
            assert_eq!(map.level_size(DipPyramid::Row, ly - 1), Some((w, 1)));
            assert_eq!(map.level_size(DipPyramid::Column, lx - 1), Some((1, h)));
            assert!(ly == 1 || map.level_size(DipPyramid::Row, ly - 2).unwrap().1 > 1);
            assert!(lx == 1 || map.level_size(DipPyramid::Column, lx - 2).unwrap().0 > 1);
            for p in BOTH {
                for l in 0..map.levels(p) {
                    let (lw, lh) = map.level_size(p, l).unwrap();
                    let (sx, sy) = if p == DipPyramid::Row { (0, l) } else { (l, 0) };
                    assert_eq!((lw, lh), (((w - 1) >> sx) + 1, ((h - 1) >> sy) + 1));
                    for j in 0..lh {
                        for i in 0..lw {
                            let got = map.level_texel(p, l, i, j).unwrap();
                            for c in 0..2 {
                                let (mut s, mut n) = (0u64, 0u64);
                                for y in (j << sy)..((j + 1) << sy).min(h) {
                                    for x in (i << sx)..((i + 1) << sx).min(w) {
                                        s += t[(y * w + x) * 2 + c] as u64;
                                        n += 1;
                                    }
                                }
                                let v = got[c] as u64;
                                assert!(2 * n * v <= 2 * s + n && 2 * s + n < 2 * n * v + 2 * n);
                            }
                        }
                    }
                }
                assert_eq!(map.level_texel(p, map.levels(p), 0, 0), None);
            }
            assert_eq!(map.level_texel(DipPyramid::Row, 0, w, 0), None);
        }
    }

    /// The f64 filter on the stored levels, with the same fixed-point level positions.
    fn reference(
        map: &DipMap<'_, u16, 1>,
        r: [i64; 4],
        f: u32,
        mode: u8,
        filter: DipFilter,
    ) -> f64 {
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
        let probe = |p: DipPyramid, l: usize| {
            let (lw, lh) = map.level_size(p, l).unwrap();
            let (sx, sy) = if p == DipPyramid::Row { (0, l) } else { (l, 0) };
            let u = cx / (1u64 << sx) as f64 - 0.5;
            let v = cy / (1u64 << sy) as f64 - 0.5;
            let (i0, j0) = (u.floor(), v.floor());
            let (a, b) = (u - i0, v - j0);
            let t = |i: f64, j: f64| match (idx(i as i64, lw), idx(j as i64, lh)) {
                (Some(x), Some(y)) => map.level_texel(p, l, x, y).unwrap()[0] as f64,
                _ => 0.0,
            };
            let r0 = t(i0, j0) * (1.0 - a) + t(i0 + 1.0, j0) * a;
            let r1 = t(i0, j0 + 1.0) * (1.0 - a) + t(i0 + 1.0, j0 + 1.0) * a;
            r0 * (1.0 - b) + r1 * b
        };
        let (lox, hix, fx) = split(r[2] - r[0], map.levels(DipPyramid::Column) - 1);
        let (loy, hiy, fy) = split(r[3] - r[1], map.levels(DipPyramid::Row) - 1);
        let (a, b) = match filter {
            DipFilter::Bilinear => (probe(DipPyramid::Column, lox), probe(DipPyramid::Row, loy)),
            DipFilter::Trilinear => (
                probe(DipPyramid::Column, lox) * (1.0 - fx) + probe(DipPyramid::Column, hix) * fx,
                probe(DipPyramid::Row, loy) * (1.0 - fy) + probe(DipPyramid::Row, hiy) * fy,
            ),
        };
        (a + b) / 2.0
    }

    fn sample_mode<X: Coord>(
        map: &DipMap<'_, u16, 1>,
        r: &Rect<X>,
        filter: DipFilter,
        mode: u8,
        k: &mut Tally,
    ) -> u64 {
        match mode {
            0 => map.sample(r, filter, Border, k),
            1 => map.sample(r, filter, ClampToEdge, k),
            2 => map.sample(r, filter, Repeat, k),
            _ => map.sample(r, filter, MirroredRepeat, k),
        }
        .unwrap()
        .values[0]
    }

    #[test]
    fn within_bound_of_f64_and_costs() {
        let mut seed = 11u64;
        for (w, h) in [(5usize, 3usize), (1, 6), (9, 1), (8, 8), (13, 7)] {
            let t = texels(w * h, 65535, (w * 7 + h) as u64);
            let tex = Texture::<u16>::new(&t, w, h).unwrap();
            let mut st = vec![0u16; DipMap::<u16, 1>::storage_needed(w, h)];
            let map = DipMap::build(&tex, &mut st).unwrap();
            // Under Miri (about 10^4 times slower) 3 random boxes per texture.
            for _ in 0..if cfg!(miri) { 3 } else { 400 } {
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
                    for (filter, cost) in [
                        (DipFilter::Bilinear, (8, 6, 13)),
                        (DipFilter::Trilinear, (16, 14, 29)),
                    ] {
                        let mut k = Tally::new();
                        let got = sample_mode(&map, &rect, filter, mode, &mut k);
                        let want = reference(&map, r, 8, mode, filter) * 65536.0;
                        let err = (got as f64 - want).abs();
                        assert!(err < arithmetic_error_bound(16) as f64, "{err}");
                        assert_eq!((k.muls, k.adds), (cost.1, cost.2));
                        if mode != 0 {
                            assert_eq!(k.reads, cost.0);
                        } else {
                            assert!(k.reads <= cost.0);
                        }
                    }
                }
            }
        }
    }

    /// The earlier formulation: doubled centre and positions in `i128`, lerps in `i64`.
    fn sample_i128(
        map: &DipMap<'_, u16, 1>,
        r: [i64; 4],
        f: u32,
        filter: DipFilter,
        kind: crate::EdgeKind,
    ) -> u64 {
        let (px, py) = (r[0] as i128 + r[2] as i128, r[1] as i128 + r[3] as i128);
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
        let (lox, hix, fx) = split(r[2] - r[0], map.levels(DipPyramid::Column) as u32 - 1);
        let (loy, hiy, fy) = split(r[3] - r[1], map.levels(DipPyramid::Row) as u32 - 1);
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
        let probe = |p: DipPyramid, l: u32| -> i64 {
            let (lw, lh) = map.level_size(p, l as usize).unwrap();
            let (sx, sy) = if p == DipPyramid::Row { (0, l) } else { (l, 0) };
            let (i0, ax) = pos(px, f + 1 + sx);
            let (j0, ay) = pos(py, f + 1 + sy);
            let t = |i: i128, j: i128| match (
                kind.texel_index(i as i64, lw),
                kind.texel_index(j as i64, lh),
            ) {
                (Some(x), Some(y)) => map.level_texel(p, l as usize, x, y).unwrap()[0] as i64,
                _ => 0,
            };
            let r0 = lerp(t(i0, j0), t(i0 + 1, j0), ax, WEIGHT_BITS);
            let r1 = lerp(t(i0, j0 + 1), t(i0 + 1, j0 + 1), ax, WEIGHT_BITS);
            lerp(r0, r1, ay, WEIGHT_BITS)
        };
        let t = 2 * WEIGHT_BITS - OUT_FRAC_BITS;
        let (a, b, shift) = match filter {
            DipFilter::Bilinear => (
                probe(DipPyramid::Column, lox),
                probe(DipPyramid::Row, loy),
                t + 1,
            ),
            DipFilter::Trilinear => (
                lerp(
                    probe(DipPyramid::Column, lox) >> t,
                    probe(DipPyramid::Column, hix) >> t,
                    fx,
                    LEVEL_FRAC_BITS,
                ),
                lerp(
                    probe(DipPyramid::Row, loy) >> t,
                    probe(DipPyramid::Row, hiy) >> t,
                    fy,
                    LEVEL_FRAC_BITS,
                ),
                LEVEL_FRAC_BITS + 1,
            ),
        };
        ((a + b).max(0) >> shift) as u64
    }

    #[test]
    fn bit_for_bit_with_the_i128_formulation() {
        let mut seed = 37u64;
        for (w, h) in [(5usize, 3usize), (1, 6), (9, 1), (13, 7)] {
            let t = texels(w * h, 65535, (w * 3 + h) as u64);
            let tex = Texture::<u16>::new(&t, w, h).unwrap();
            let mut st = vec![0u16; DipMap::<u16, 1>::storage_needed(w, h)];
            let map = DipMap::build(&tex, &mut st).unwrap();
            // Under Miri (about 10^4 times slower) 4 random boxes per texture.
            for _ in 0..if cfg!(miri) { 4 } else { 1500 } {
                let f = [0u32, 8, 24][(lcg(&mut seed) % 3) as usize];
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
                    for filter in [DipFilter::Bilinear, DipFilter::Trilinear] {
                        let got = match f {
                            0 => map.sample(
                                &Rect::new(
                                    I64F0::from_bits(r[0]),
                                    I64F0::from_bits(r[1]),
                                    I64F0::from_bits(r[2]),
                                    I64F0::from_bits(r[3]),
                                ),
                                filter,
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
                                filter,
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
                                filter,
                                kind,
                                &mut NoCount,
                            ),
                        };
                        assert_eq!(
                            got.unwrap().values[0],
                            sample_i128(&map, r, f, filter, kind),
                            "{w}x{h} {r:?} F={f} {filter:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn three_channels_count_arithmetic_per_channel() {
        let t: Vec<u8> = (0..6 * 5 * 3).map(|v| (v * 7 % 256) as u8).collect();
        let tex = Texture::<u8, 3>::new(&t, 6, 5).unwrap();
        let mut st = vec![0u8; DipMap::<u8, 3>::storage_needed(6, 5)];
        let map = DipMap::build(&tex, &mut st).unwrap();
        let r = Rect::<I24F8>::from_f64(1.3, 0.7, 4.1, 2.2).unwrap();
        let mut k = Tally::new();
        map.sample(&r, DipFilter::Bilinear, Repeat, &mut k).unwrap();
        assert_eq!((k.reads, k.bits_read, k.muls, k.adds), (8, 8 * 24, 18, 39));
        let mut k = Tally::new();
        map.sample(&r, DipFilter::Trilinear, Repeat, &mut k)
            .unwrap();
        assert_eq!(
            (k.reads, k.bits_read, k.muls, k.adds),
            (16, 16 * 24, 42, 87)
        );
    }

    #[test]
    fn orientation_row_pyramid_follows_height() {
        // Vertical stripes: columns alternate 0 and 200, constant down each column.
        let (w, h) = (8usize, 8usize);
        let t: Vec<u8> = (0..w * h)
            .map(|i| if i % 2 == 0 { 0 } else { 200 })
            .collect();
        let tex = Texture::<u8>::new(&t, w, h).unwrap();
        let mut st = vec![0u8; DipMap::<u8, 1>::storage_needed(w, h)];
        let map = DipMap::build(&tex, &mut st).unwrap();
        // Row pyramid levels average vertically: the stripes survive.
        assert_eq!(map.level_texel(DipPyramid::Row, 3, 1, 0), Some([200]));
        // Column pyramid levels average horizontally: grey.
        assert_eq!(map.level_texel(DipPyramid::Column, 1, 0, 5), Some([100]));
        for filter in [DipFilter::Bilinear, DipFilter::Trilinear] {
            // Tall, narrow footprint on column 1 (W = 1, H = 8): both samples see 200.
            let r = Rect::<I24F8>::from_f64(1.0, 0.0, 2.0, 8.0).unwrap();
            let s = map
                .sample(&r, filter, ClampToEdge, &mut Tally::new())
                .unwrap();
            assert_eq!(s.values[0], 200 << 16);
            // Wide, short footprint (W = 8, H = 1) centred on column 1's centre: the column
            // pyramid gives the mean 100, the row pyramid the stripe 200: 150.
            let r = Rect::<I24F8>::from_f64(-2.5, 3.0, 5.5, 4.0).unwrap();
            let s = map
                .sample(&r, filter, ClampToEdge, &mut Tally::new())
                .unwrap();
            assert_eq!(s.values[0], 150 << 16);
        }
    }

    #[test]
    fn constant_texture_is_exact() {
        let t = vec![200u8; 7 * 5];
        let tex = Texture::<u8>::new(&t, 7, 5).unwrap();
        let mut st = vec![0u8; DipMap::<u8, 1>::storage_needed(7, 5)];
        let map = DipMap::build(&tex, &mut st).unwrap();
        for (x0, x1) in [(0.0, 0.0), (-3.0, 20.0), (2.5, 2.75), (1.0, 5.0)] {
            let r = Rect::<I24F8>::from_f64(x0, 1.0, x1, 3.0).unwrap();
            for filter in [DipFilter::Bilinear, DipFilter::Trilinear] {
                let s = map
                    .sample(&r, filter, MirroredRepeat, &mut Tally::new())
                    .unwrap();
                assert_eq!(s.values[0], 200 << 16);
            }
        }
    }

    #[test]
    fn error_bound_is_approached() {
        // As in the ripmap test: weights just below 2^-16 on both axes, one bright texel.
        let mut t = vec![0u16; 4 * 4];
        t[4 + 1] = 65535;
        let tex = Texture::<u16>::new(&t, 4, 4).unwrap();
        let mut st = vec![0u16; DipMap::<u16, 1>::storage_needed(4, 4)];
        let map = DipMap::build(&tex, &mut st).unwrap();
        let c = (3i64 << 23) + ((1 << 9) - 2) / 2;
        let b = I40F24::from_bits(c);
        let r = Rect::new(b, b, b, b);
        let a = ((1 << 9) - 2) as f64 / (1u64 << 25) as f64;
        let exact = 65535.0 * (1.0 - a) * (1.0 - a) * 65536.0;
        let bound = arithmetic_error_bound(16) as f64;
        for filter in [DipFilter::Bilinear, DipFilter::Trilinear] {
            let got = map
                .sample(&r, filter, Border, &mut Tally::new())
                .unwrap()
                .values[0] as f64;
            let err = (got - exact).abs();
            assert!(err < bound && err > 0.99 * bound, "{err} vs {bound}");
        }
    }

    #[test]
    fn refusals_and_extremes_do_not_panic() {
        let t = vec![9u8; 6];
        let tex = Texture::<u8>::new(&t, 3, 2).unwrap();
        let mut st = vec![0u8; DipMap::<u8, 1>::storage_needed(3, 2)];
        let map = DipMap::build(&tex, &mut st).unwrap();
        let f = DipFilter::Trilinear;
        let r = Rect::<I24F8>::from_f64(2.0, 0.0, 1.0, 1.0).unwrap();
        assert_eq!(
            map.sample(&r, f, Border, &mut Tally::new()).unwrap_err(),
            Error::InvertedBox
        );
        type X = fixed::types::I32F32;
        let r = Rect::<X>::from_f64(0.0, 0.0, 1.0, 1.0).unwrap();
        assert!(matches!(
            map.sample(&r, f, Border, &mut Tally::new()),
            Err(Error::FracBitsUnsupported { .. })
        ));
        type Z = fixed::types::I64F0;
        for r in [
            Rect::new(Z::MIN, Z::MIN, Z::MAX, Z::MAX),
            Rect::new(
                Z::MAX,
                Z::from_bits(i64::MIN + 1),
                Z::MAX,
                Z::from_bits(i64::MIN + 1),
            ),
        ] {
            for f in [DipFilter::Bilinear, DipFilter::Trilinear] {
                for v in [
                    map.sample(&r, f, Border, &mut Tally::new()),
                    map.sample(&r, f, ClampToEdge, &mut Tally::new()),
                    map.sample(&r, f, Repeat, &mut Tally::new()),
                    map.sample(&r, f, MirroredRepeat, &mut Tally::new()),
                ] {
                    assert!(v.unwrap().values[0] <= 9 << 16);
                }
            }
        }
        // y0 = y1 = i64::MIN at F = 0: the row probe's upper tap is below i64::MIN (before the
        // 64-bit positions it was folded from an i128 index; now a typed refusal).
        let r = Rect::new(Z::MAX, Z::MIN, Z::MAX, Z::MIN);
        for f in [DipFilter::Bilinear, DipFilter::Trilinear] {
            assert_eq!(
                map.sample(&r, f, Repeat, &mut Tally::new()),
                Err(Error::CoordinateOutOfRange)
            );
        }
        assert!(DipMap::<u8, 1>::from_storage(&st, 3, 2).is_ok());
        assert!(DipMap::<u8, 1>::from_storage(&st[..5], 3, 2).is_err());
        assert_eq!(
            DipMap::<u8, 1>::from_storage(&st, 3, 0).unwrap_err(),
            Error::EmptyTexture
        );
    }
}
