//! The box-filtered image pyramid ("mip map"): point-sampled (Dungan, Stenger and Sutty 1978)
//! and trilinear (Williams 1983), as compared in Heckbert 1986, "Comparison of Prefiltering
//! Methods": point-sampled pyramid 1 access / 0 multiplies, trilinear interpolation on a pyramid
//! 8 accesses / 7 multiplies, memory 1.33 ("`1 + 1/4 + 1/16 + ... = 4/3` times that required for
//! an unfiltered texture"); Crow 1984 §2.2 counts the trilinear as 8 reads, 7 multiplicative and
//! 14 additive operations.
//!
//! # The pyramid
//!
//! Level 0 is the texture itself (borrowed, not copied). Level `l + 1` has
//! `ceil(w_l / 2) x ceil(h_l / 2)` texels, down to `1 x 1`; so level `l` is
//! `ceil(w / 2^l) x ceil(h / 2^l)` and texel `(i, j)` of level `l` stands for the base block
//! `[i 2^l, (i + 1) 2^l) x [j 2^l, (j + 1) 2^l)`, *clipped to the texture*. Its value is the
//! average of the base texels of that clipped block (odd and non-power-of-two sizes: the last
//! column/row of a level averages fewer texels), computed from the exact integer sum of the
//! **base** texels (not from the rounded level above) and rounded to nearest, ties up:
//! `round(sum / count) = floor((2 sum + count) / (2 count))`. Every stored texel is within
//! 1/2 LSB of the exact box average of the base texture; the error does not accumulate down the
//! pyramid. The coarse levels live in caller storage of the texture's own texel type
//! ([`MipPyramid::storage_needed`] elements), so the memory is the survey's 4/3 of the texture
//! for square power-of-two sizes: `(4^(k+1) - 1) / 3` texels for a `2^k x 2^k` texture
//! ([`MipPyramid::pyramid_texels`]); other sizes are `4/3 + O(1/n)` (255 x 255: 1.3359;
//! 640 x 480: 1.33336). Elongated textures cost more once the short side has reached 1 and only
//! the long axis halves: a `1 x n` pyramid approaches `2 n` texels (1 x 300: 603, ratio 2.01).
//!
//! Build cost (not a per-sample cost, not counted): every base texel is read once per coarse
//! level, `w h (levels - 1)` texel reads, because each level is summed from the base texels.
//! Per-level sums are exact in `u64` (refused with [`Error::TooWide`] if `2^(B+1) w h` could
//! reach `2^64`: at least `2^47` texels of `u16`, `2^55` of `u8`).
//!
//! # Sampling
//!
//! The footprint `[x0, x1) x [y0, y1)` (fixed point, `F <= 24` fractional bits) gives the centre
//! `c = ((x0 + x1) / 2, (y0 + y1) / 2)` and the diameter `d = max(W, H)` with `W = x1 - x0`,
//! `H = y1 - y0` in texels (Heckbert: "the recommended formula for the diameter `d` of the
//! square is the maximum of the side lengths"). The level of detail is
//! `L = log2(d)` in fixed point with [`LOD_FRAC_BITS`] fraction bits from
//! [`crate::filters::level::log2_fixed`] (the exact `floor(256 log2 d)` or one below it), clamped
//! to `[0, top]` (`top` = the `1 x 1` level); `d = 0` and magnification (`d <= 1`) give level 0.
//! See [`MipPyramid::lod`].
//!
//! * [`MipPyramid::point_sample`]: level `round(L) = (L_q + 128) >> 8` (ties up on the fixed
//!   value; as `L_q` may be one unit low, a `log2 d` whose fraction is in `[0.5, 0.5 + 2^-7)` may
//!   take the lower level), then the nearest texel of that level: index `floor(c / 2^l)`.
//!   1 read, 0 multiplies, 0 additive operations. Exact output (`texel << 16`).
//! * [`MipPyramid::trilinear`]: Williams' trilinear interpolation. Levels `l0 = floor(L)` and
//!   `l1 = min(l0 + 1, top)`, lerp weight `t = frac(L)` (8 bits, exact). In each level a bilinear
//!   interpolation at `c`: level texel centres are at `(i + 0.5) 2^l` in base coordinates, so
//!   `u = c / 2^l - 1/2`, taps `floor(u)` and `floor(u) + 1` (per axis, through the boundary mode
//!   at the level's own size), weight `a = frac(u)`.
//!
//! # Arithmetic of the trilinear, and its error bound
//!
//! Every lerp is Crow's `b + (c - b) alpha` (1 multiply, 2 additive operations); a bilinear is 3
//! lerps (two along x, one along y), the trilinear two bilinears and one lerp: **8 reads,
//! 7 multiplies, 14 additive operations** per channel of arithmetic (reads count all channels
//! together; multiplies and additions count once per channel, as everywhere in the crate). The
//! scale of `b` by a power of two is a shift (wiring) and not counted; nor is the final rounding
//! to the output (as in [`crate::BoxSum::mean_rounded`]).
//!
//! The position weights are the fractions `a`, `b` truncated to [`weight_bits`]`(B)` bits:
//! 24 for `u8` texels, 20 for `u16` (`alpha = floor(a 2^W)`; exact whenever `F + 1 + l <= W`);
//! the level weight is the exact 8-bit `frac(L)`. `W = (64 - 8 - B) / 2` is the most that keeps
//! every intermediate of the trilinear below `2^64`: taps are below `2^B`, the row lerps below
//! `2^(B + W)`, the column lerp below `2^(B + 2W)`, the level lerp below `2^(B + 2W + 8) <= 2^64`.
//! Each lerp is a convex combination of non-negative values, computed in wrapping `u64`
//! arithmetic (exact, as the result is below `2^64`; the pyramid module's `lerp`), and the result,
//! in units of `2^-(2W + 8)`, is rounded to nearest (ties up) to `2^-16`; the rounding add stays
//! below `2^64` too. No integer wider than 64 bits, no division: one `32 x 32`-bit `log2` loop
//! for the level, shifts and masks for the positions, 7 multiplies.
//!
//! Whenever the weights are exact (`F + 1 + l <= W`: every level of a texture up to `2^15`
//! texels at `F = 8` for `u8`, `2^11` for `u16`), the result is bit for bit that of the crate's
//! earlier formulation with 32-bit weights in `i128` (unit test
//! `bit_for_bit_with_the_i128_formulation`): both are the exact value, rounded once.
//!
//! **Bound.** Against the same filter in exact (or `f64`) arithmetic on the same stored pyramid
//! with the same `L`: a bilinear interpolation is linear in each weight with slope at most
//! `m = 2^B - 1` (texel values lie in `[0, m]`), so truncating `a` and `b` by less than `2^-W`
//! each moves it by less than `m 2^(1-W)`; the level lerp is a convex combination and does not
//! enlarge that; the output rounding adds at most `2^-17`. Hence
//! `|trilinear / 2^16 - exact| < m 2^(1-W) + 2^-17` texel units ([`trilinear_error_bound`]):
//! below `2.5` output units for `u8` (`255 * 2^-23 + 2^-17`) and `8192.5` for `u16`
//! (`65535 * 2^-19 + 2^-17` texel units, an eighth of a texel step; `2e-6` of the range). Against
//! the ideal (unrounded) box pyramid add the storage rounding, 1/2 LSB (convex combinations of
//! texels each within 1/2).
//!
//! # Boundary modes
//!
//! A tap outside a level uses [`EdgeKind::texel_index`](crate::EdgeKind::texel_index)`(i, n_l)` with that level's size `n_l`;
//! under [`crate::Border`] it reads zero. For [`crate::Repeat`] and [`crate::MirroredRepeat`]
//! each level wraps (reflects) at its own size: level `l` repeats with period `n_l 2^l` base
//! texels, which is `n` only when `2^l` divides `n`. For other (odd, non-power-of-two) sizes the
//! coarse levels are therefore an approximation of the filtered repeated texture near the seam
//! (the last, clipped, block is a full texel of the level). Likewise the clipped edge texel's
//! centre `(n_l - 1/2) 2^l` may lie past the texture's edge `n`.
//!
//! Costs are constant: a tap outside under [`crate::Border`] is still counted as a read (the unit
//! issues the fetch slot), and at the top level (or when `L` is clamped there) the trilinear still
//! evaluates both bilinears, reading the top level twice with `t = 0`: always 8 reads.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::cost::{per_channel, Counter, Region};
use crate::edge::{EdgeKind, EdgeMode};
use crate::error::{Error, Quantity};
use crate::filters::pyramid::{
    check_dims, count_reads, fill_box_level, footprint_raw, lerp, level_count, level_len,
    level_position, split_level, split_position, tap_index, Footprint,
};
use crate::filters::{pyramid, u64_from_usize, Sample, OUT_FRAC_BITS};
use crate::rect::{Coord, FracBits, Rect};
use crate::texel::Texel;
use crate::texture::Texture;
#[cfg(test)]
use crate::texture::MAX_DIMENSION;
use crate::width::bits_of_u64;

/// Most levels a pyramid can have: sizes up to `2^31 - 1` halve to 1 in 31 steps, plus level 0.
pub const MAX_LEVELS: usize = pyramid::MAX_LEVELS;

/// Fractional bits of the level of detail `L` ([`MipPyramid::lod`]).
pub const LOD_FRAC_BITS: u32 = 8;

/// Fractional bits `W` of the bilinear position weights of [`MipPyramid::trilinear`]
/// (truncated) for texels of `texel_bits` bits: `(64 - LOD_FRAC_BITS - B) / 2`, the most that
/// keeps the whole trilinear below `2^64` (module docs): 24 for `u8`, 20 for `u16`.
pub const fn weight_bits(texel_bits: u32) -> u32 {
    let b = if texel_bits < 1 {
        1
    } else if texel_bits > 16 {
        16
    } else {
        texel_bits
    };
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "1 <= b <= 16 (clamped above): 64 - 8 - b is in [40, 55]"
    )]
    let w = (64 - LOD_FRAC_BITS - b) / 2;
    w
}

/// The error bound of [`MipPyramid::trilinear`] in texel units against the same filter computed
/// exactly on the same stored pyramid with the same level of detail: `m 2^(1-W) + 2^-17` with
/// `m = 2^texel_bits - 1` and `W = ` [`weight_bits`]`(texel_bits)` (module docs, "Arithmetic of
/// the trilinear"). The bound is strict for the weight part; the rounding part `2^-17` is
/// reached.
pub fn trilinear_error_bound(texel_bits: u32) -> f64 {
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "2^min(b, 16) >= 1; weight_bits is in [20, 27] (its clamp), so w - 1 >= 19"
    )]
    let (m, half_step) = (
        f64::from((1u32 << texel_bits.min(16)) - 1),
        f64::from(1u32 << (weight_bits(texel_bits) - 1)),
    );
    m / half_step + 1.0 / f64::from(1u32 << 17)
}

/// A box-filtered 2x2 pyramid over a borrowed texture: level 0 is the texture, the coarse levels
/// live in caller storage (module docs).
#[derive(Debug, Clone)]
pub struct MipPyramid<'a, T: Texel, const C: usize = 1> {
    base: Texture<'a, T, C>,
    coarse: &'a [T],
    /// `(width, height)` of each level, level 0 first; at least one level.
    sizes: heapless::Vec<(usize, usize), MAX_LEVELS>,
    /// Start of each level in `coarse` (elements; level 0, the texture, has 0 and is not there).
    offsets: heapless::Vec<usize, MAX_LEVELS>,
}

/// Level sizes `(ceil(w / 2^l), ceil(h / 2^l))` down to `1 x 1`.
fn level_sizes(w: usize, h: usize) -> Result<heapless::Vec<(usize, usize), MAX_LEVELS>, Error> {
    check_dims(w, h)?;
    // w, h <= 2^31 - 1: at most 31 halvings reach 1, so count <= MAX_LEVELS and every push
    // fits.
    let mut sizes = heapless::Vec::new();
    for l in 0..level_count(w.max(h)).min(MAX_LEVELS) {
        let _ = sizes.push((level_len(w, l), level_len(h, l)));
    }
    Ok(sizes)
}

/// One level of a pyramid as the sampling loop reads it: its texels (`None` for level 0, the
/// texture) and size.
#[derive(Clone, Copy)]
struct LevelRef<'a, T> {
    coarse: Option<&'a [T]>,
    w: usize,
    h: usize,
    /// Index of the level's first texel in the pyramid's storage (0 for level 0, the texture).
    first: usize,
}

impl<'a, T: Texel, const C: usize> MipPyramid<'a, T, C> {
    /// Texels per channel of the whole pyramid of a `width x height` texture, level 0 included:
    /// `sum_l ceil(w / 2^l) ceil(h / 2^l)`. For `2^k x 2^k` this is `(4^(k+1) - 1) / 3`; the
    /// ratio to `w h` is the memory cost of the survey's table (4/3 for square textures).
    pub fn pyramid_texels(width: usize, height: usize) -> Result<usize, Error> {
        let sizes = level_sizes(width, height)?;
        let mut total = 0usize;
        for &(w, h) in &sizes {
            total = w.checked_mul(h).and_then(|a| total.checked_add(a)).ok_or(
                Error::TextureTooLarge {
                    dimension: width.max(height),
                },
            )?;
        }
        Ok(total)
    }

    /// Elements of `T` the coarse levels (1 and up) need: `(pyramid_texels - w h) * C`. Level 0
    /// is the texture and takes no storage.
    pub fn storage_needed(width: usize, height: usize) -> Result<usize, Error> {
        let too_large = Error::TextureTooLarge {
            dimension: width.max(height),
        };
        let total = Self::pyramid_texels(width, height)?;
        // pyramid_texels succeeded, so w h <= total does not overflow.
        total
            .saturating_sub(width.saturating_mul(height))
            .checked_mul(C)
            .ok_or(too_large)
    }

    /// The level sizes `(width, height)`, level 0 (the texture) first, down to `(1, 1)`.
    pub fn levels(&self) -> &[(usize, usize)] {
        &self.sizes
    }

    /// The number of levels (`1 + ceil(log2(max(w, h)))`).
    pub fn level_count(&self) -> usize {
        self.sizes.len()
    }

    /// The storage elements in use (a prefix of the slice given to [`MipPyramid::build`]).
    pub fn storage_len(&self) -> usize {
        self.coarse.len()
    }

    /// Level `l` for the sampling loop (an empty `1 x 1`-less level past the top: every texel
    /// read of it is `None`).
    #[inline(always)]
    fn level(&self, l: usize) -> LevelRef<'a, T> {
        let (w, h) = self.sizes.get(l).copied().unwrap_or((0, 0));
        let (coarse, first) = if l == 0 {
            (None, 0)
        } else {
            let at = self.offsets.get(l).copied().unwrap_or(usize::MAX);
            (Some(self.coarse.get(at..).unwrap_or(&[])), at)
        };
        LevelRef {
            coarse,
            w,
            h,
            first,
        }
    }

    /// Texel `(x, y)` (all channels) of `level`, `x < w`, `y < h`, or `None` if the storage does
    /// not hold it.
    #[inline(always)]
    fn texel_in(&self, level: LevelRef<'a, T>, x: usize, y: usize) -> Option<&'a [T]> {
        let (at, data) = match level.coarse {
            // x < w, y < h and w h C fits (storage_needed): no overflow; wrapping all the same.
            Some(data) => (y.wrapping_mul(level.w).wrapping_add(x), data),
            None => (x, self.base.row(y)?),
        };
        let at = at.wrapping_mul(C);
        data.get(at..at.wrapping_add(C))
    }

    /// Texel `(x, y)` of level `l` (all channels), or `None` outside the level or past the top.
    pub fn level_texel(&self, l: usize, x: usize, y: usize) -> Option<[T; C]> {
        let level = self.level(l);
        if x >= level.w || y >= level.h {
            return None;
        }
        self.texel_in(level, x, y)?.try_into().ok()
    }

    /// The level of detail of `rect`: `log2(max(W, H))` with [`LOD_FRAC_BITS`] fraction bits from
    /// [`log2_fixed`](crate::filters::level::log2_fixed) (exact floor or one unit below), clamped
    /// to `[0, (levels - 1) 2^8]`; `0` when the footprint is a point or a segment of length 0
    /// (`d = 0`).
    ///
    /// Errors: [`Error::FracBitsUnsupported`] for `F > 24`, [`Error::InvertedBox`].
    pub fn lod<X: Coord>(&self, rect: &Rect<X>) -> Result<u32, Error> {
        self.lod_raw(&rect.to_raw(), FracBits::of::<X>()?)
    }

    /// [`MipPyramid::lod`] with raw corners (`value * 2^F`) and `F` as a value.
    pub fn lod_raw(&self, rect: &Rect<i64>, frac_bits: FracBits) -> Result<u32, Error> {
        Ok(self.footprint(rect, frac_bits)?.1)
    }

    /// The validated footprint (centre, sides) and its clamped level of detail.
    #[inline(always)]
    fn footprint(&self, rect: &Rect<i64>, frac_bits: FracBits) -> Result<(Footprint, u32), Error> {
        let fp = footprint_raw(rect, frac_bits)?;
        let lod = level_position(fp.w.max(fp.h), fp.f, LOD_FRAC_BITS, self.top());
        Ok((fp, lod))
    }

    /// The top level's index (at most 31).
    #[inline(always)]
    fn top(&self) -> u32 {
        #[allow(
            clippy::as_conversions,
            reason = "at most MAX_LEVELS = 32 levels (the heapless capacity): lossless"
        )]
        let top = self.sizes.len().saturating_sub(1) as u32;
        top
    }

    /// Texel of `level` at extended index `(i, j)` under the mode `kind`, per channel (0 where
    /// the mode gives no texel).
    #[inline(always)]
    fn tap<K: Counter>(
        &self,
        kind: EdgeKind,
        level: LevelRef<'a, T>,
        i: i64,
        j: i64,
        k: &mut K,
    ) -> [u64; C] {
        let px = match (tap_index(kind, i, level.w), tap_index(kind, j, level.h)) {
            (Some(x), Some(y)) => {
                // Where the read is, for traffic and cache models (dead code under NoCount):
                // level 0 in the texture (tightly packed rows), the others in the pyramid.
                let (region, index) = match level.coarse {
                    Some(_) => (
                        Region::Filter,
                        level
                            .first
                            .wrapping_add(y.wrapping_mul(level.w).wrapping_add(x)),
                    ),
                    None => (Region::Texture, y.wrapping_mul(level.w).wrapping_add(x)),
                };
                let bits = const { per_channel(T::BITS, C) };
                k.read_at(
                    region,
                    u64_from_usize(index).wrapping_mul(u64::from(bits)),
                    bits,
                );
                self.texel_in(level, x, y)
            }
            _ => None,
        };
        let mut out = [0u64; C];
        if let Some(px) = px {
            for (o, t) in out.iter_mut().zip(px) {
                *o = u64::from(t.to_u16());
            }
        }
        out
    }

    /// Dungan's point-sampled pyramid: the nearest texel of level `round(L)` to the footprint's
    /// centre. 1 read, 0 multiplies, 0 additive operations (survey: "point sampled pyramid 1,0").
    ///
    /// Level `l = min((L_q + 128) >> 8, top)` with `L_q` = [`MipPyramid::lod`]; texel index
    /// `floor(c / 2^l) = floor((x0 + x1) / 2^(F + 1 + l))` per axis (a centre on a level-texel
    /// boundary takes the texel to the right / below), mapped by `M` at the level's size. Exact
    /// output: `texel << 16`. Any `i64` corners are accepted (the centre is exact in `i64`).
    ///
    /// Errors: [`Error::FracBitsUnsupported`] (`F > 24`), [`Error::InvertedBox`].
    pub fn point_sample<X: Coord, M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<X>,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.point_sample_raw(&rect.to_raw(), FracBits::of::<X>()?, mode, k)
    }

    /// [`MipPyramid::point_sample`] with raw corners (`value * 2^F`) and `F` as a value, checked
    /// once by [`FracBits::new`]: one compiled sampler serves every `F`.
    pub fn point_sample_raw<M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<i64>,
        frac_bits: FracBits,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let (fp, lod) = self.footprint(rect, frac_bits)?;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "lod <= 31 * 2^8 (level_position clamps to top <= 31): no overflow"
        )]
        let l = ((lod + (1 << (LOD_FRAC_BITS - 1))) >> LOD_FRAC_BITS).min(self.top());
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "f <= 24 (FracBits) and l <= top <= 31"
        )]
        let s = fp.f + l;
        let (i, j) = (fp.cx.index(s), fp.cy.index(s));
        count_reads::<T, C, 1, K>(k);
        #[allow(clippy::as_conversions, reason = "l <= top <= 31: lossless")]
        let level = self.level(l as usize);
        let px = self.tap(mode.kind(), level, i, j, k);
        Ok(Sample {
            values: px.map(|v| v << OUT_FRAC_BITS),
        })
    }

    /// Williams' trilinear interpolation: bilinear at the footprint's centre in levels
    /// `floor(L)` and `min(floor(L) + 1, top)`, then a lerp by `frac(L)`. 8 reads, 7 multiplies,
    /// 14 additive operations per channel (survey "trilinear interp. on pyramid 8,7"; Crow §2.2).
    ///
    /// Output: per channel `round(v 2^16)` (ties up) of the fixed-point evaluation, within
    /// [`trilinear_error_bound`] texel units of the same filter in exact arithmetic (module docs).
    /// All in 64-bit integers.
    ///
    /// Errors: [`Error::FracBitsUnsupported`] (`F > 24`), [`Error::InvertedBox`], and
    /// [`Error::CoordinateOutOfRange`] only for a footprint centred at the very bottom of `i64`
    /// (`F = 0`, `x0 = x1 = i64::MIN`), whose left tap index is below `i64::MIN`.
    pub fn trilinear<X: Coord, M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<X>,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.trilinear_raw(&rect.to_raw(), FracBits::of::<X>()?, mode, k)
    }

    /// [`MipPyramid::trilinear`] with raw corners (`value * 2^F`) and `F` as a value, checked
    /// once by [`FracBits::new`]: one compiled sampler serves every `F`.
    pub fn trilinear_raw<M: EdgeMode, K: Counter>(
        &self,
        rect: &Rect<i64>,
        frac_bits: FracBits,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let (fp, lod) = self.footprint(rect, frac_bits)?;
        // lod <= top 2^8, so at the top t = 0.
        let (l0, l1, t) = split_level(lod, LOD_FRAC_BITS, self.top());
        let wb = const { weight_bits(T::BITS) };
        let v0 = self.bilinear(mode.kind(), l0, &fp, wb, k)?;
        let v1 = self.bilinear(mode.kind(), l1, &fp, wb, k)?;
        // Level lerp: units 2^-(2W + 8), below 2^(B + 2W + 8) <= 2^64 (module docs).
        let v = lerp(v0, v1, t, LOD_FRAC_BITS, k);
        // Constants of the compiled sampler: W in [20, 27], so shift in [32, 46].
        let shift = const { 2 * weight_bits(T::BITS) + LOD_FRAC_BITS - OUT_FRAC_BITS };
        let half = const { 1u64 << (2 * weight_bits(T::BITS) + LOD_FRAC_BITS - OUT_FRAC_BITS - 1) };
        // v <= m 2^(2W + 8), and m 2^(2W + 8) + half < 2^64: no wrap.
        Ok(Sample {
            values: v.map(|v| v.wrapping_add(half) >> shift),
        })
    }

    /// Bilinear interpolation of level `l` at the footprint centre: 4 reads, 3 lerps per channel;
    /// per channel the value in units of `2^-2W`, below `2^(B + 2W)`.
    #[inline(always)]
    fn bilinear<K: Counter>(
        &self,
        kind: EdgeKind,
        l: u32,
        fp: &Footprint,
        wb: u32,
        k: &mut K,
    ) -> Result<[u64; C], Error> {
        // Position fraction bits F + 1 + l: at most 24 + 1 + 31 = 56.
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "f <= 24 (FracBits) and l <= top <= 31 (split_level)"
        )]
        let s = fp.f + l;
        let (i, a) = split_position(fp.cx, s, wb)?;
        let (j, b) = split_position(fp.cy, s, wb)?;
        // i, j <= 2^63 - 2 (split_position), so + 1 cannot overflow; checked anyway.
        let i1 = i.checked_add(1).ok_or(Error::CoordinateOutOfRange)?;
        let j1 = j.checked_add(1).ok_or(Error::CoordinateOutOfRange)?;
        #[allow(clippy::as_conversions, reason = "l <= top <= 31: lossless")]
        let level = self.level(l as usize);
        count_reads::<T, C, 4, K>(k);
        let p00 = self.tap(kind, level, i, j, k);
        let p10 = self.tap(kind, level, i1, j, k);
        let p01 = self.tap(kind, level, i, j1, k);
        let p11 = self.tap(kind, level, i1, j1, k);
        // Row lerps, units 2^-W: below 2^(B + W).
        let r0 = lerp(p00, p10, a, wb, k);
        let r1 = lerp(p01, p11, a, wb, k);
        // Column lerp, units 2^-2W: below 2^(B + 2W).
        Ok(lerp(r0, r1, b, wb, k))
    }

    /// Builds the coarse levels of `texture` into `storage` (the first
    /// [`MipPyramid::storage_needed`] elements; the rest is untouched).
    ///
    /// Each coarse texel is the exact box average of its clipped base block, rounded to nearest
    /// with ties up (module docs). Errors: [`Error::StorageTooSmall`]; [`Error::TooWide`]
    /// (`Quantity::Entry`) if `2^(B+1) w h >= 2^64`, where the exact sums could overflow `u64`.
    pub fn build(texture: &Texture<'a, T, C>, storage: &'a mut [T]) -> Result<Self, Error> {
        let (w, h) = (texture.width(), texture.height());
        let sizes = level_sizes(w, h)?;
        let needed = Self::storage_needed(w, h)?;
        let got = storage.len();
        let store = storage
            .get_mut(..needed)
            .ok_or(Error::StorageTooSmall { needed, got })?;
        // w, h < 2^31: w h < 2^62 in u64. (Saturating: a texel type claiming nearly 2^32 bits
        // is refused as TooWide rather than overflowing the count.)
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w, h <= 2^31 - 1 (level_sizes' check_dims): w h < 2^62"
        )]
        let area = u64_from_usize(w) * u64_from_usize(h);
        let bits_needed = bits_of_u64(area).saturating_add(T::BITS).saturating_add(1);
        if bits_needed > 64 {
            return Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed,
                bits_available: 64,
            });
        }
        let mut offsets = heapless::Vec::new();
        let mut at = 0usize;
        for (l, &(lw, lh)) in sizes.iter().enumerate() {
            // Same length as `sizes`: every push fits.
            let _ = offsets.push(at);
            if l > 0 {
                // Within `needed`, which did not overflow.
                at = at.saturating_add(lw.saturating_mul(lh).saturating_mul(C));
            }
        }
        for (l, &at) in offsets.iter().enumerate().skip(1) {
            // Level l averages blocks of 2^l x 2^l base texels; 2 sum + count <= 2^(B+1) w h,
            // below 2^64 (checked above).
            let out = store
                .get_mut(at..)
                .ok_or(Error::StorageTooSmall { needed, got })?;
            fill_box_level(texture, out, l, l)?;
        }
        let coarse: &'a [T] = store;
        Ok(MipPyramid {
            base: *texture,
            coarse,
            sizes,
            offsets,
        })
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
    use crate::cost::{NoCount, Tally};
    use crate::edge::{Border, ClampToEdge, MirroredRepeat, Repeat};
    use fixed::types::{I16F16, I24F8, I32F32, I40F24, I64F0};
    use std::vec;
    use std::vec::Vec;

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *seed >> 33
    }

    fn r8(x0: f64, y0: f64, x1: f64, y1: f64) -> Rect<I24F8> {
        Rect::from_f64(x0, y0, x1, y1).unwrap()
    }

    /// The same trilinear in f64 on the stored pyramid, same lod; `mode` maps indices.
    fn tri_f64<T: Texel, const C: usize>(
        p: &MipPyramid<'_, T, C>,
        raw: [i64; 4],
        f: u32,
        lod: u32,
        idx: fn(i64, usize) -> Option<usize>,
    ) -> Vec<f64> {
        let top = p.level_count() - 1;
        let l0 = (lod >> 8) as usize;
        let l1 = (l0 + 1).min(top);
        let t = (lod & 255) as f64 / 256.0;
        let cx = (raw[0] as f64 + raw[2] as f64) / 2f64.powi(f as i32 + 1);
        let cy = (raw[1] as f64 + raw[3] as f64) / 2f64.powi(f as i32 + 1);
        let bil = |l: usize| -> Vec<f64> {
            let (w, h) = p.levels()[l];
            let s = (1u64 << l) as f64;
            let (u, v) = (cx / s - 0.5, cy / s - 0.5);
            let (i, j) = (u.floor(), v.floor());
            let (a, b) = (u - i, v - j);
            let get = |x: f64, y: f64, c: usize| -> f64 {
                match (idx(x as i64, w), idx(y as i64, h)) {
                    (Some(x), Some(y)) => p.level_texel(l, x, y).unwrap()[c].to_u16() as f64,
                    _ => 0.0,
                }
            };
            (0..C)
                .map(|c| {
                    let r0 = get(i, j, c) * (1.0 - a) + get(i + 1.0, j, c) * a;
                    let r1 = get(i, j + 1.0, c) * (1.0 - a) + get(i + 1.0, j + 1.0, c) * a;
                    r0 * (1.0 - b) + r1 * b
                })
                .collect()
        };
        let (v0, v1) = (bil(l0), bil(l1));
        (0..C).map(|c| v0[c] * (1.0 - t) + v1[c] * t).collect()
    }

    #[test]
    fn sizes_and_memory() {
        let lv = |w: usize, h: usize| level_sizes(w, h).unwrap().to_vec();
        assert_eq!(lv(1, 1), vec![(1, 1)]);
        assert_eq!(lv(5, 3), vec![(5, 3), (3, 2), (2, 1), (1, 1)]);
        assert_eq!(lv(1, 300).len(), 10);
        assert_eq!(lv(MAX_DIMENSION, 1).len(), 32);
        for k in 0..=12u32 {
            let n = 1usize << k;
            let total = MipPyramid::<u8>::pyramid_texels(n, n).unwrap();
            assert_eq!(total, ((1usize << (2 * k + 2)) - 1) / 3);
            assert_eq!(
                MipPyramid::<u8, 3>::storage_needed(n, n).unwrap(),
                (total - n * n) * 3
            );
        }
        assert_eq!(MipPyramid::<u8>::pyramid_texels(1, 300).unwrap(), 603);
        assert_eq!(
            MipPyramid::<u8>::storage_needed(0, 3),
            Err(Error::EmptyTexture)
        );
        // 2^31 - 1 squared overflows a 32-bit usize but not a 64-bit one.
        let big = MipPyramid::<u8, 4>::storage_needed(MAX_DIMENSION, MAX_DIMENSION);
        assert!(
            big.is_ok()
                || big
                    == Err(Error::TextureTooLarge {
                        dimension: MAX_DIMENSION
                    })
        );
    }

    #[test]
    fn levels_are_rounded_box_averages_of_the_base() {
        let mut seed = 7;
        for (w, h) in [
            (1, 1),
            (1, 7),
            (7, 1),
            (5, 3),
            (6, 6),
            (9, 13),
            (16, 16),
            (17, 5),
        ] {
            let data: Vec<u8> = (0..w * h * 2).map(|_| lcg(&mut seed) as u8).collect();
            let t = Texture::<u8, 2>::new(&data, w, h).unwrap();
            let mut st = vec![0u8; MipPyramid::<u8, 2>::storage_needed(w, h).unwrap() + 3];
            let p = MipPyramid::build(&t, &mut st).unwrap();
            assert_eq!(p.levels()[0], (w, h));
            for (l, &(lw, lh)) in p.levels().iter().enumerate() {
                for y in 0..lh {
                    for x in 0..lw {
                        let got = p.level_texel(l, x, y).unwrap();
                        for c in 0..2 {
                            let (mut s, mut n) = (0u64, 0u64);
                            for by in (y << l)..((y + 1) << l).min(h) {
                                for bx in (x << l)..((x + 1) << l).min(w) {
                                    s += data[(by * w + bx) * 2 + c] as u64;
                                    n += 1;
                                }
                            }
                            assert_eq!(got[c] as u64, (2 * s + n) / (2 * n), "{w}x{h} l{l}");
                        }
                    }
                }
                assert_eq!(p.level_texel(l, lw, 0), None);
            }
            assert_eq!(p.level_texel(p.level_count(), 0, 0), None);
        }
    }

    #[test]
    fn build_refusals() {
        let data = [0u16; 12];
        let t = Texture::<u16>::new(&data, 4, 3).unwrap();
        let need = MipPyramid::<u16>::storage_needed(4, 3).unwrap();
        assert_eq!(need, 2 * 2 + 1);
        let mut st = vec![0u16; need - 1];
        assert_eq!(
            MipPyramid::build(&t, &mut st).err(),
            Some(Error::StorageTooSmall {
                needed: need,
                got: need - 1
            })
        );
    }

    #[test]
    fn costs_are_the_surveys() {
        let data: Vec<u8> = (0..64 * 3).map(|v| v as u8).collect();
        let t = Texture::<u8, 3>::new(&data, 8, 8).unwrap();
        let mut st = vec![0u8; MipPyramid::<u8, 3>::storage_needed(8, 8).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        for r in [
            r8(1.0, 1.0, 3.5, 2.0),
            r8(-20.0, -20.0, 40.0, 40.0),
            r8(2.0, 2.0, 2.0, 2.0),
            r8(7.9, 0.2, 8.4, 0.3),
        ] {
            let mut k = Tally::new();
            p.point_sample(&r, Border, &mut k).unwrap();
            assert_eq!((k.reads, k.muls, k.divs, k.adds), (1, 0, 0, 0));
            assert_eq!(k.bits_read, 24);
            let mut k = Tally::new();
            p.trilinear(&r, Repeat, &mut k).unwrap();
            // 8 reads; 7 multiplies and 14 additive operations per channel.
            assert_eq!((k.reads, k.muls, k.divs, k.adds), (8, 21, 0, 42));
        }
        let d1: Vec<u16> = (0..36).collect();
        let t1 = Texture::<u16>::new(&d1, 6, 6).unwrap();
        let mut st1 = vec![0u16; MipPyramid::<u16>::storage_needed(6, 6).unwrap()];
        let p1 = MipPyramid::build(&t1, &mut st1).unwrap();
        let mut k = Tally::new();
        p1.trilinear(&r8(1.0, 1.0, 3.5, 2.0), ClampToEdge, &mut k)
            .unwrap();
        assert_eq!((k.reads, k.multiplicative(), k.adds), (8, 7, 14));
        assert_eq!(k.bits_read, 8 * 16);
    }

    #[test]
    fn lod_selection() {
        let data = [0u8; 256];
        let t = Texture::<u8>::new(&data, 16, 16).unwrap();
        let mut st = vec![0u8; MipPyramid::<u8>::storage_needed(16, 16).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        assert_eq!(p.level_count(), 5);
        assert_eq!(p.lod(&r8(0.0, 0.0, 0.5, 0.25)).unwrap(), 0); // magnification
        assert_eq!(p.lod(&r8(1.0, 1.0, 1.0, 1.0)).unwrap(), 0); // a point
        assert_eq!(p.lod(&r8(0.0, 0.0, 4.0, 1.0)).unwrap(), 2 << 8); // max side
        assert_eq!(p.lod(&r8(0.0, 0.0, 1.0, 8.0)).unwrap(), 3 << 8);
        assert_eq!(p.lod(&r8(0.0, 0.0, 1000.0, 1.0)).unwrap(), 4 << 8); // clamped
        let l = p.lod(&r8(0.0, 0.0, 3.0, 1.0)).unwrap() as f64 / 256.0;
        assert!((l - 3f64.log2()).abs() < 2.0 / 256.0);
        assert_eq!(p.lod(&r8(1.0, 0.0, 0.0, 1.0)), Err(Error::InvertedBox));
        let r = Rect::new(I32F32::ZERO, I32F32::ZERO, I32F32::ONE, I32F32::ONE);
        assert_eq!(
            p.lod(&r),
            Err(Error::FracBitsUnsupported {
                frac_bits: 32,
                max: 24
            })
        );
    }

    #[test]
    fn point_sample_picks_level_and_texel() {
        // 8 x 1 ramp 0, 10, .., 70: level 1 = [5, 25, 45, 65], level 2 = [15, 55], level 3 = 35.
        let data: Vec<u8> = (0..8).map(|v| v * 10).collect();
        let t = Texture::<u8>::new(&data, 8, 1).unwrap();
        let mut st = vec![0u8; MipPyramid::<u8>::storage_needed(8, 1).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        assert_eq!(p.levels(), &[(8, 1), (4, 1), (2, 1), (1, 1)]);
        let v = |r: Rect<I24F8>| {
            p.point_sample(&r, ClampToEdge, &mut NoCount)
                .unwrap()
                .values[0]
        };
        assert_eq!(v(r8(2.5, 0.0, 3.0, 0.5)), 20 << 16); // level 0, texel 2
        assert_eq!(v(r8(2.0, 0.0, 4.0, 0.5)), 25 << 16); // d = 2: level 1, texel 1
        assert_eq!(p.level_texel(1, 1, 0), Some([25]));
        // d = 2.75: log2 = 1.46 -> level 1; d = 2.875: 1.52 -> level 2.
        assert_eq!(v(r8(0.0, 0.0, 2.75, 0.5)), 5 << 16);
        assert_eq!(v(r8(0.0, 0.0, 2.875, 0.5)), 15 << 16); // level 2 texel 0: (0+..+30)/4
                                                           // Level 0 equals point sampling of the texture.
        #[cfg(feature = "filter-point")]
        for r in [
            r8(0.2, 0.0, 0.9, 0.7),
            r8(-3.0, 2.0, -2.5, 2.5),
            r8(7.6, 0.1, 8.5, 0.2),
        ] {
            use crate::filters::point::point;
            let mut k = NoCount;
            assert_eq!(
                p.point_sample(&r, Repeat, &mut k),
                point(&t, &r, Repeat, &mut k)
            );
            assert_eq!(
                p.point_sample(&r, Border, &mut k),
                point(&t, &r, Border, &mut k)
            );
            let (a, b) = (
                p.point_sample(&r, MirroredRepeat, &mut k),
                point(&t, &r, MirroredRepeat, &mut k),
            );
            assert_eq!(a, b);
        }
    }

    #[test]
    fn trilinear_exact_cases() {
        // Constant texture: every filter returns the constant exactly (Clamp; Repeat).
        let data = [77u8; 35];
        let t = Texture::<u8>::new(&data, 7, 5).unwrap();
        let mut st = vec![0u8; MipPyramid::<u8>::storage_needed(7, 5).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        for r in [
            r8(0.3, 0.1, 0.6, 0.9),
            r8(-9.0, 3.0, 30.0, 4.0),
            r8(2.0, 2.0, 5.3, 4.1),
        ] {
            assert_eq!(
                p.trilinear(&r, ClampToEdge, &mut NoCount).unwrap().values,
                [77 << 16]
            );
            assert_eq!(
                p.trilinear(&r, Repeat, &mut NoCount).unwrap().values,
                [77 << 16]
            );
            assert_eq!(
                p.trilinear(&r, MirroredRepeat, &mut NoCount)
                    .unwrap()
                    .values,
                [77 << 16]
            );
        }
        // A texel centre at level 0 with d <= 1 returns that texel.
        let data: Vec<u8> = (0..35).map(|v| v * 7).collect();
        let t = Texture::<u8>::new(&data, 7, 5).unwrap();
        let mut st = vec![0u8; MipPyramid::<u8>::storage_needed(7, 5).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        let s = p
            .trilinear(&r8(3.25, 2.25, 3.75, 2.75), Border, &mut NoCount)
            .unwrap();
        assert_eq!(s.values, [(data[2 * 7 + 3] as u64) << 16]);
        // Halfway between texels 3 and 4 on row 2: the mean.
        let s = p
            .trilinear(&r8(3.75, 2.25, 4.25, 2.75), Border, &mut NoCount)
            .unwrap();
        assert_eq!(
            s.values,
            [(((data[17] as u64) + data[18] as u64) << 16) / 2]
        );
    }

    #[test]
    fn trilinear_within_bound_of_f64_u8() {
        let mut seed = 11;
        let mut worst = 0f64;
        for (w, h) in [(1, 1), (1, 9), (9, 1), (5, 3), (8, 8), (13, 6)] {
            let data: Vec<u8> = (0..w * h).map(|_| lcg(&mut seed) as u8).collect();
            let t = Texture::<u8>::new(&data, w, h).unwrap();
            let mut st = vec![0u8; MipPyramid::<u8>::storage_needed(w, h).unwrap()];
            let p = MipPyramid::build(&t, &mut st).unwrap();
            // Under Miri (about 10^4 times slower) 10 random boxes per texture.
            for _ in 0..if cfg!(miri) { 10 } else { 400 } {
                let x0 = (lcg(&mut seed) % 8000) as i64 - 3000;
                let y0 = (lcg(&mut seed) % 8000) as i64 - 3000;
                let ww = (lcg(&mut seed) % 6000) as i64;
                let hh = (lcg(&mut seed) % 6000) as i64;
                let raw = [x0, y0, x0 + ww, y0 + hh];
                let r = Rect::new(
                    I24F8::from_bits(raw[0] as i32),
                    I24F8::from_bits(raw[1] as i32),
                    I24F8::from_bits(raw[2] as i32),
                    I24F8::from_bits(raw[3] as i32),
                );
                let lod = p.lod(&r).unwrap();
                let mut check = |got: Sample<1>, idx: fn(i64, usize) -> Option<usize>| {
                    let want = tri_f64(&p, raw, 8, lod, idx)[0];
                    let err = (got.value_f64(0).unwrap() - want).abs();
                    assert!(err <= trilinear_error_bound(8) + 1e-12, "{err}");
                    worst = worst.max(err);
                };
                check(p.trilinear(&r, Border, &mut NoCount).unwrap(), |i, n| {
                    crate::EdgeKind::Border.texel_index(i, n)
                });
                check(
                    p.trilinear(&r, ClampToEdge, &mut NoCount).unwrap(),
                    |i, n| crate::EdgeKind::Clamp.texel_index(i, n),
                );
                check(p.trilinear(&r, Repeat, &mut NoCount).unwrap(), |i, n| {
                    crate::EdgeKind::Repeat.texel_index(i, n)
                });
                check(
                    p.trilinear(&r, MirroredRepeat, &mut NoCount).unwrap(),
                    |i, n| crate::EdgeKind::Mirror.texel_index(i, n),
                );
            }
        }
        // The rounding half of the bound is reached.
        assert!(worst >= 0.99 / (1u64 << 17) as f64, "{worst}");
    }

    #[test]
    fn trilinear_weight_truncation_approaches_bound_u16() {
        // Level l alternates 0 / 65535 in blocks of 2^l; F = 24 and l = 10 give
        // F + 1 + l = 35 > 20 fraction bits, 15 of them truncated. Under Border the single row's
        // vertical taps are 0 and the row, so both axes lose weight bits on a difference near m.
        // Under Miri (about 10^4 times slower) l = 6 (a 256-texel row, still 11 bits cut)
        // instead of the 4096-texel row of l = 10.
        let l = if cfg!(miri) { 6 } else { 10u32 };
        let wb = weight_bits(16);
        assert_eq!(wb, 20);
        let cut = 24 + 1 + l - wb; // truncated bits
        let (w, h) = (1usize << (l + 2), 1usize);
        let data: Vec<u16> = (0..w)
            .map(|x| if (x >> l).is_multiple_of(2) { 0 } else { 65535 })
            .collect();
        let t = Texture::<u16>::new(&data, w, h).unwrap();
        let mut st = vec![0u16; MipPyramid::<u16>::storage_needed(w, h).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        assert_eq!(p.level_texel(l as usize, 1, 0), Some([65535]));
        let mut seed = 3;
        let mut worst = 0f64;
        let bound = trilinear_error_bound(16);
        // Under Miri (about 10^4 times slower) 40 random boxes.
        for _ in 0..if cfg!(miri) { 40 } else { 3000 } {
            // x0 = 2^(cut-1) - 1 (mod 2^(cut-1)), x1 = x0 + 2^(l+24) + 1: the low `cut` bits of
            // x0 + x1 are all ones, so the truncated bits of both weights are; the side
            // 2^l + 2^-24 still has lod = l << 8 (t = 0).
            let mut rnd = |n: u64| ((lcg(&mut seed) << 31) ^ lcg(&mut seed)) % n;
            let step = 1i64 << (cut - 1);
            let x0 = rnd(((w as u64) << 24) >> (cut - 1)) as i64 * step + step - 1;
            let y0 = rnd(1u64 << (l + 25 - cut)) as i64 * step - (1i64 << (l + 24)) + step - 1;
            let side = (1i64 << (l + 24)) + 1;
            let raw = [x0, y0, x0 + side, y0 + side];
            let r = Rect::new(
                I40F24::from_bits(raw[0]),
                I40F24::from_bits(raw[1]),
                I40F24::from_bits(raw[2]),
                I40F24::from_bits(raw[3]),
            );
            let lod = p.lod(&r).unwrap();
            assert_eq!(lod, l << 8);
            let got = p.trilinear(&r, Border, &mut NoCount).unwrap();
            let want = tri_f64(&p, raw, 24, lod, |i, n| {
                crate::EdgeKind::Border.texel_index(i, n)
            })[0];
            let err = (got.value_f64(0).unwrap() - want).abs();
            assert!(err <= bound + 1e-9, "{err} > {bound}");
            worst = worst.max(err);
        }
        // Beyond the rounding part the weight truncation shows, most of the way to the bound.
        assert!(worst > 0.8 * bound, "{worst} vs {bound}");
    }

    /// The earlier formulation: 32-bit weights, the column and level lerps in `i128`, the doubled
    /// centre in `i128`; the reference the 64-bit trilinear must match bit for bit whenever its
    /// own weights are exact.
    fn trilinear_i128<T: Texel, const C: usize, M: EdgeMode>(
        p: &MipPyramid<'_, T, C>,
        raw: [i64; 4],
        f: u32,
        mode: M,
    ) -> [u64; C] {
        let lod = level_position(
            (raw[2] - raw[0]).max(raw[3] - raw[1]) as u64,
            f,
            LOD_FRAC_BITS,
            p.top(),
        );
        let (l0, l1, t) = split_level(lod, LOD_FRAC_BITS, p.top());
        let (px, py) = (
            raw[0] as i128 + raw[2] as i128,
            raw[1] as i128 + raw[3] as i128,
        );
        let bil = |l: u32| -> [i128; C] {
            let s = f + 1 + l;
            let split = |p: i128| {
                let t = p - (1i128 << (s - 1));
                let frac = t & ((1i128 << s) - 1);
                let a = if s >= 32 {
                    frac >> (s - 32)
                } else {
                    frac << (32 - s)
                };
                (t >> s, a)
            };
            let ((i, a), (j, b)) = (split(px), split(py));
            let (w, h) = p.levels()[l as usize];
            let tap = |i: i128, j: i128| -> [i128; C] {
                let k = mode.kind();
                match (k.texel_index(i as i64, w), k.texel_index(j as i64, h)) {
                    (Some(x), Some(y)) => p
                        .level_texel(l as usize, x, y)
                        .unwrap()
                        .map(|v| v.to_u16() as i128),
                    _ => [0; C],
                }
            };
            let lerp = |x: [i128; C], y: [i128; C], w: i128| -> [i128; C] {
                core::array::from_fn(|c| (x[c] << 32) + (y[c] - x[c]) * w)
            };
            let r0 = lerp(tap(i, j), tap(i + 1, j), a);
            let r1 = lerp(tap(i, j + 1), tap(i + 1, j + 1), a);
            lerp(r0, r1, b)
        };
        let (v0, v1) = (bil(l0), bil(l1));
        core::array::from_fn(|c| {
            let v = (v0[c] << 8) + (v1[c] - v0[c]) * t as i128;
            ((v + (1i128 << 55)) >> 56) as u64
        })
    }

    #[test]
    fn bit_for_bit_with_the_i128_formulation() {
        // Every footprint of a grid of corners (F = 8 and F = 16 with exact weights: F + 1 + l is
        // at most 14 and 20) over odd-sized textures, every mode, u8 and u16.
        let mut seed = 5;
        for (w, h) in [(5usize, 3usize), (7, 9), (1, 6)] {
            let d8: Vec<u8> = (0..w * h * 2).map(|_| lcg(&mut seed) as u8).collect();
            let t8 = Texture::<u8, 2>::new(&d8, w, h).unwrap();
            let mut s8 = vec![0u8; MipPyramid::<u8, 2>::storage_needed(w, h).unwrap()];
            let p8 = MipPyramid::build(&t8, &mut s8).unwrap();
            let d16: Vec<u16> = (0..w * h).map(|_| lcg(&mut seed) as u16).collect();
            let t16 = Texture::<u16>::new(&d16, w, h).unwrap();
            let mut s16 = vec![0u16; MipPyramid::<u16>::storage_needed(w, h).unwrap()];
            let p16 = MipPyramid::build(&t16, &mut s16).unwrap();
            let mut n = 0;
            // Under Miri (about 10^4 times slower) every 27th corner, and the sides 0, 1, 256 and 3000.
            let step = if cfg!(miri) { 27 } else { 3 };
            let sides: &[i64] = if cfg!(miri) {
                &[0, 1, 256, 3000]
            } else {
                &[0, 1, 37, 128, 255, 256, 700, 2047, 3000]
            };
            for x0 in (-40i64..40).step_by(step) {
                for &side in sides {
                    let y0 = (x0 * 7) % 23 - 5;
                    let raw = [x0 * 37, y0 * 29, x0 * 37 + side, y0 * 29 + side / 3];
                    let r8 = Rect::new(
                        I24F8::from_bits(raw[0] as i32),
                        I24F8::from_bits(raw[1] as i32),
                        I24F8::from_bits(raw[2] as i32),
                        I24F8::from_bits(raw[3] as i32),
                    );
                    macro_rules! check {
                        ($mode:expr) => {
                            assert_eq!(
                                p8.trilinear(&r8, $mode, &mut NoCount).unwrap().values,
                                trilinear_i128(&p8, raw, 8, $mode),
                                "{w}x{h} {raw:?}"
                            );
                            assert_eq!(
                                p16.trilinear(&r8, $mode, &mut NoCount).unwrap().values,
                                trilinear_i128(&p16, raw, 8, $mode),
                                "{w}x{h} {raw:?}"
                            );
                        };
                    }
                    check!(Border);
                    check!(ClampToEdge);
                    check!(Repeat);
                    check!(MirroredRepeat);
                    check!(crate::EdgeKind::Mirror);
                    n += 1;
                }
            }
            assert!(n > if cfg!(miri) { 10 } else { 200 });
            // F = 16 (I16F16): F + 1 + l <= 20 for these sizes (l <= 3).
            for x0 in (-3000i64..3000).step_by(if cfg!(miri) { 1500 } else { 211 }) {
                let raw = [
                    x0 * 97,
                    x0 * 53 + 7,
                    x0 * 97 + 1 + (x0 & 0x7FFFF).abs() * 13,
                    x0 * 53 + 70_001,
                ];
                let r = Rect::new(
                    I16F16::from_bits(raw[0] as i32),
                    I16F16::from_bits(raw[1] as i32),
                    I16F16::from_bits(raw[2] as i32),
                    I16F16::from_bits(raw[3] as i32),
                );
                assert_eq!(
                    p16.trilinear(&r, Repeat, &mut NoCount).unwrap().values,
                    trilinear_i128(&p16, raw, 16, Repeat)
                );
                assert_eq!(
                    p8.trilinear(&r, ClampToEdge, &mut NoCount).unwrap().values,
                    trilinear_i128(&p8, raw, 16, ClampToEdge)
                );
            }
        }
    }

    #[test]
    fn point_sample_matches_the_i128_formulation() {
        let data: Vec<u8> = (0..45).map(|v| (v * 37 % 256) as u8).collect();
        let t = Texture::<u8>::new(&data, 9, 5).unwrap();
        let mut st = vec![0u8; MipPyramid::<u8>::storage_needed(9, 5).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        let mut seed = 17;
        // Under Miri (about 10^4 times slower) 600 random boxes.
        for _ in 0..if cfg!(miri) { 600 } else { 20_000 } {
            let x0 = (lcg(&mut seed) as i64 % 9000) - 3000;
            let y0 = (lcg(&mut seed) as i64 % 9000) - 3000;
            let raw = [
                x0,
                y0,
                x0 + (lcg(&mut seed) % 5000) as i64,
                y0 + (lcg(&mut seed) % 900) as i64,
            ];
            let r = Rect::new(
                I24F8::from_bits(raw[0] as i32),
                I24F8::from_bits(raw[1] as i32),
                I24F8::from_bits(raw[2] as i32),
                I24F8::from_bits(raw[3] as i32),
            );
            let lod = p.lod(&r).unwrap();
            let l = ((lod + 128) >> 8).min(p.top());
            let shift = 8 + 1 + l;
            let i = ((raw[0] as i128 + raw[2] as i128) >> shift) as i64;
            let j = ((raw[1] as i128 + raw[3] as i128) >> shift) as i64;
            let (w, h) = p.levels()[l as usize];
            let k = crate::EdgeKind::Repeat;
            let want = match (k.texel_index(i, w), k.texel_index(j, h)) {
                (Some(x), Some(y)) => (p.level_texel(l as usize, x, y).unwrap()[0] as u64) << 16,
                _ => 0,
            };
            assert_eq!(
                p.point_sample(&r, Repeat, &mut NoCount).unwrap().values,
                [want]
            );
        }
    }

    #[test]
    fn top_level_and_extremes() {
        let data: Vec<u8> = (0..15).map(|v| v * 17).collect();
        let t = Texture::<u8>::new(&data, 5, 3).unwrap();
        let mut st = vec![0u8; MipPyramid::<u8>::storage_needed(5, 3).unwrap()];
        let p = MipPyramid::build(&t, &mut st).unwrap();
        let top = p.level_count() - 1;
        let m = p.level_texel(top, 0, 0).unwrap()[0] as u64;
        // d >= 8 puts L at (or clamps it to) the top: the 1 x 1 level, read by both bilinears.
        for r in [r8(-1.5, -2.5, 6.5, 5.5), r8(-100.0, -100.0, 100.0, 100.0)] {
            let mut k = Tally::new();
            let s = p.trilinear(&r, ClampToEdge, &mut k).unwrap();
            assert_eq!(s.values, [m << 16]);
            assert_eq!(k.reads, 8);
        }
        // Extreme corners of the widest type: no panic; the single bad case is refused.
        let all = Rect::new(I64F0::MIN, I64F0::MIN, I64F0::MAX, I64F0::MAX);
        assert!(p.trilinear(&all, Repeat, &mut NoCount).is_ok());
        assert!(p.point_sample(&all, MirroredRepeat, &mut NoCount).is_ok());
        let hi = Rect::new(I64F0::MAX, I64F0::MAX, I64F0::MAX, I64F0::MAX);
        assert!(p.trilinear(&hi, Repeat, &mut NoCount).is_ok());
        let lo = Rect::new(I64F0::MIN, I64F0::MIN, I64F0::MIN, I64F0::MIN);
        assert_eq!(
            p.trilinear(&lo, Repeat, &mut NoCount),
            Err(Error::CoordinateOutOfRange)
        );
        assert!(p.point_sample(&lo, Repeat, &mut NoCount).is_ok());
    }
}
