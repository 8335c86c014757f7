//! Variance over a box from summed-area tables of the texture and of its squares (Heckbert's
//! survey, "summed area table": "A more accurate method for computing rectangle variance would be
//! to pre-compute summed area tables of the texture values and their squares. Using these two
//! tables variance can be computed as `σ^2 = Σ x_i^2 / n - (Σ x_i / n)^2`"; Glassner 1986 uses
//! rectangle variance to drive adaptive refinement).
//!
//! [`VarianceTables`] holds the core's [`Sat`] of the values and a [`SquaresTable`] of the
//! squares, both in caller storage and built with Crow's two additions per entry. The squares
//! table implements [`Layout`], so every box lookup of the core ([`BoxLookup::box_sum_int`],
//! [`BoxLookup::box_sum`] in both forms, every boundary mode) runs on it unchanged.
//!
//! ## Exact arithmetic
//!
//! With `n` the box area, `S` the sum and `Q` the sum of squares (for fixed-point corners all
//! three scaled by `2^2F`, as [`crate::BoxSum`] returns them; `n` is the unclipped box's, so
//! under [`crate::Border`] the zeros outside count), the variance is
//!
//! `σ^2 = Q/n - (S/n)^2 = (n Q - S^2) / n^2`,
//!
//! computed exactly: `n Q - S^2 >= 0` (Cauchy–Schwarz for the integrals of a piecewise-constant
//! function), rounded to nearest with ties up, with [`OUT_FRAC_BITS`] fraction bits. The result
//! is the variance of the extended piecewise-constant texture over the box, exact before that
//! rounding (so within `2^-17`).
//!
//! **`u16` and `u32` tables: 64-bit words only.** Their box sums are `u64`. `n Q` and `S^2` need
//! up to 128 bits, so they are never formed; instead, with `S = a n + r` (`0 <= r < n`):
//!
//! * `Q' = Q - a (S + r) = sum A_i (t_i - a)^2` (the second moment about `a = floor(mean)`,
//!   `A_i` the texels' areas in the box) is `0 <= Q' <= Q < 2^64`, and
//!   `n Q - S^2 = n Q' - r^2` (variance does not move with the mean);
//! * `Q' = b n + t`, `r^2 = e n + f` (`r^2 / n` by shift-and-add when `r >= 2^32`: no
//!   `64 x 64 -> 128` product), so `σ^2 = b + (t - e) / n - f / n^2`, normalised to
//!   `B + (h + φ / n) / n` with `0 <= h, φ < n`;
//! * `round(2^16 σ^2) = 2^16 B + floor((2^17 h + floor(2^17 φ / n) + n) / (2n))` (the dropped
//!   `frac(2^17 φ / n) < 1` cannot carry an integer numerator past a multiple of `2n`), each
//!   quotient by one `u64` division or by 17 steps of restoring division.
//!
//! Every intermediate is below `2^64` when `n < 2^62` (the doubled remainders are below `4n`):
//! boxes of up to `2^62` raw area units, i.e. `2^46` texels² at `F = 8` (`2^23 x 2^23`), `2^14`
//! at `F = 24`. Larger boxes are [`Error::TooWide`] (`MeanNumerator`, 62 bits available, the
//! bits of `n` needed). The result is bit for bit the `u128` formulation's (unit tests: an
//! exhaustive sweep of small `n`, `S`, `Q` and random large ones).
//!
//! **`u64` tables: 128 bits, because the sums are.** Their box sums are `u128` words
//! ([`crate::BoxSum`] of a `u64` table: sums scaled by `2^2F` exceed 64 bits), so `S`, `Q` and
//! `n Q` are computed in `u128`: the numerator `n Q` must fit `u128` and `n^2` must be below
//! `2^127`, else [`Error::TooWide`] (`MeanNumerator`).
//!
//! ## Costs
//!
//! Integer corners, interior box, one channel: 8 reads (4 per table), 4 multiplies (the area
//! `w h`, `n^2`, `n Q`, `S^2`) and 1 divide, 7 additive operations (3 per box sum and
//! `n Q - S^2`). Fixed-point corners: 32 reads and each box sum's 12 multiplies and 27 (Paper) or
//! 31 (Stable) additive operations, plus the same 4 multiplies, 1 divide and 1 subtraction. With
//! `C` channels the area and `n^2` are shared: `2 + 2C` multiplies, `C` divides.
//!
//! ## Widths
//!
//! Values: [`crate::width::entry_bits_worst_case`] (`Sat::build` checks it). Squares:
//! [`squares_entry_bits`] `= bits_of(m^2 w h)`, exact by the same argument (the all-`m` texture
//! reaches it). Both tables use the entry type `E`; 8-bit 256 x 256 needs 32 bits for the
//! squares (24 for the values); `u32` holds squares up to 257 x 257.
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
use crate::error::{Error, Quantity};
use crate::filters::{per_channel, u64_from_usize, Sample, OUT_FRAC_BITS};
use crate::layouts::Layout;
use crate::lookup::{BoxLookup, BoxSum, Form};
use crate::rect::{Coord, FracBits, Rect};
use crate::table::Sat;
use crate::texel::{Entry, Texel};
use crate::texture::Texture;
use crate::wide::Wide;
use crate::width::{bits_of, bits_of_u64, check_texel_bits, max_texel_u64};
use core::num::NonZeroU64;

/// Exact bits per entry of the squares table: `bits_of((2^b - 1)^2 * w * h)` (texel widths
/// above 32 bits saturate `(2^b - 1)^2` at `2^64 - 1`), without 128-bit arithmetic
/// ([`crate::width::bits_of_product`]).
pub const fn squares_entry_bits(texel_bits: u32, width: usize, height: usize) -> u32 {
    let m = max_texel_u64(texel_bits);
    crate::width::bits_of_product(
        m.saturating_mul(m),
        u64_from_usize(width),
        u64_from_usize(height),
    )
}

/// [`squares_entry_bits`] for what a build sees (`texel_bits <= 16`, sides below `2^31`), in
/// 64-bit words: `m^2 < 2^32` times `w h < 2^62` from 32-bit halves of `w h` (the product is
/// below `2^94`; the high half `m^2 floor(w h / 2^32) + carry` stays below `2^64`).
fn squares_bits_u64(texel_bits: u32, width: usize, height: usize) -> u32 {
    let m = max_texel_u64(texel_bits.min(16));
    let b = u64_from_usize(width).saturating_mul(u64_from_usize(height));
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "m < 2^16, so a = m^2 <= 2^32 - 2^17 + 1: lo < 2^64, and a (b >> 32) + (lo >> 32) \
                  <= (2^32 - 2^17 + 1)(2^32 - 1) + 2^32 - 1 < 2^64 for any b; 32 + bits <= 96"
    )]
    let bits = {
        let a = m * m;
        let lo = a * (b & 0xFFFF_FFFF);
        let hi = a * (b >> 32) + (lo >> 32);
        if hi == 0 {
            bits_of_u64(lo)
        } else {
            32 + bits_of_u64(hi)
        }
    };
    bits
}

/// A summed-area table of the squared texels (inclusive storage, like [`Sat`]).
#[derive(Debug, Clone, Copy)]
pub struct SquaresTable<'a, E: Entry, const C: usize = 1> {
    table: &'a [E],
    width: usize,
    height: usize,
    texel_bits: u32,
    total_bits: u32,
}

impl<'a, E: Entry, const C: usize> SquaresTable<'a, E, C> {
    /// Builds the table of `t^2` into `storage` after proving [`squares_entry_bits`] fits `E`;
    /// nothing is written on refusal. Two additions per entry (running row sum, plus the entry
    /// above), as Crow §3.0; squaring is one multiply per texel.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
    ) -> Result<Self, Error> {
        let (w, h) = Self::check::<T>(texture, storage.len())?;
        // check() proved w h C fits and the storage holds it.
        let row_len = w.saturating_mul(C);
        let needed = row_len.saturating_mul(h);
        let got = storage.len();
        let table = storage
            .get_mut(..needed)
            .ok_or(Error::StorageTooSmall { needed, got })?;
        let mut rows = table.chunks_exact_mut(row_len.max(1));
        let mut above: Option<&[E]> = None;
        for y in 0..h {
            let texels = texture.row(y).ok_or(Error::EmptyTexture)?;
            let out = rows.next().ok_or(Error::StorageTooSmall { needed, got })?;
            let mut run = [E::ZERO; C];
            for (xi, (px, o)) in texels
                .chunks_exact(C)
                .zip(out.chunks_exact_mut(C))
                .enumerate()
            {
                for (c, ((r, t), o)) in run.iter_mut().zip(px).zip(o.iter_mut()).enumerate() {
                    let t = u64::from(t.to_u16());
                    // t^2 <= m^2 <= the worst-case total, which fits E (check()): no wrap.
                    #[allow(clippy::arithmetic_side_effects, reason = "t < 2^16: t^2 < 2^32")]
                    let square = t * t;
                    *r = r.wrapping_add(E::from_u64_truncating(square));
                    #[allow(
                        clippy::arithmetic_side_effects,
                        reason = "xi < w and c < C, and w C fits (check's storage_needed)"
                    )]
                    let at = xi * C + c;
                    let up = above.and_then(|a| a.get(at)).copied().unwrap_or(E::ZERO);
                    *o = r.wrapping_add(up);
                }
            }
            above = Some(out);
        }
        let table: &'a [E] = storage.get(..needed).unwrap_or(&[]);
        let last = table.get(needed.saturating_sub(C)..).unwrap_or(&[]);
        let total_bits = last
            .iter()
            .map(|e| bits_of_u64(e.to_u64()))
            .max()
            .unwrap_or(0);
        Ok(SquaresTable {
            table,
            width: w,
            height: h,
            texel_bits: T::BITS,
            total_bits,
        })
    }

    /// The refusals of [`SquaresTable::build`], before anything is written.
    fn check<T: Texel>(texture: &Texture<'_, T, C>, got: usize) -> Result<(usize, usize), Error> {
        let (w, h) = (texture.width(), texture.height());
        check_texel_bits(T::BITS)?;
        let bits = squares_bits_u64(T::BITS, w, h);
        if bits > E::BITS {
            return Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: bits,
                bits_available: E::BITS,
            });
        }
        let needed = storage_needed::<C>(w, h)?;
        if got < needed {
            return Err(Error::StorageTooSmall { needed, got });
        }
        Ok((w, h))
    }

    /// Bits per texel of the source texture (the squares have twice as many).
    pub fn source_texel_bits(&self) -> u32 {
        self.texel_bits
    }

    /// The stored entries, row-major, channels interleaved.
    pub fn entries(&self) -> &'a [E] {
        self.table
    }

    /// Table bytes as stored.
    pub fn table_bytes(&self) -> usize {
        core::mem::size_of_val(self.table)
    }
}

impl<E: Entry, const C: usize> Layout<C> for SquaresTable<'_, E, C> {
    type Value = E;
    fn width(&self) -> usize {
        self.width
    }
    fn height(&self) -> usize {
        self.height
    }
    /// The squares' width: twice the source texel bits (what the shortcut's bound uses).
    fn texel_bits(&self) -> u32 {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "texel_bits <= 16 (check's check_texel_bits)"
        )]
        let bits = 2 * self.texel_bits;
        bits
    }
    fn value_bits(&self) -> u32 {
        self.total_bits
    }
    /// Saturates at `u64::MAX`, which only a table of `2^61` bytes could reach.
    fn storage_bits(&self) -> u64 {
        u64_from_usize(self.table_bytes()).saturating_mul(8)
    }
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        let mut out = [E::ZERO; C];
        if x != 0 && y != 0 && x <= self.width && y <= self.height {
            k.reads(1, const { per_channel(E::BITS, C) });
            k.words(const { per_channel(E::BITS, C).div_ceil(32) });
            // x <= w, y <= h and w h C fits (the build's check): no wrap.
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "x != 0 and y != 0 (the test above)"
            )]
            let (xm, ym) = (x - 1, y - 1);
            let base = (ym.wrapping_mul(self.width).wrapping_add(xm)).wrapping_mul(C);
            if let Some(src) = self.table.get(base..base.wrapping_add(C)) {
                for (o, &e) in out.iter_mut().zip(src) {
                    *o = e;
                }
            }
        }
        out
    }
}

/// Entries each table of a `width x height` texture needs: `w h C`.
pub fn storage_needed<const C: usize>(width: usize, height: usize) -> Result<usize, Error> {
    width
        .checked_mul(height)
        .and_then(|v| v.checked_mul(C))
        .ok_or(Error::TextureTooLarge {
            dimension: width.max(height),
        })
}

/// The SATs of the values and of the squares of one texture.
#[derive(Debug, Clone, Copy)]
pub struct VarianceTables<'a, E: Entry, const C: usize = 1> {
    values: Sat<'a, E, C>,
    squares: SquaresTable<'a, E, C>,
}

impl<'a, E: Entry, const C: usize> VarianceTables<'a, E, C> {
    /// Entries each of the two storages needs: `w h C`.
    pub fn storage_needed(width: usize, height: usize) -> Result<usize, Error> {
        storage_needed::<C>(width, height)
    }

    /// Builds both tables. The squares' width and storage are checked first, then
    /// [`Sat::build`] checks and builds the values, then the squares are built: a refusal
    /// writes nothing.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        values: &'a mut [E],
        squares: &'a mut [E],
    ) -> Result<Self, Error> {
        SquaresTable::<E, C>::check::<T>(texture, squares.len())?;
        let values = Sat::build(texture, values)?;
        let squares = SquaresTable::build(texture, squares)?;
        Ok(VarianceTables { values, squares })
    }

    /// The values' table.
    pub fn values(&self) -> &Sat<'a, E, C> {
        &self.values
    }

    /// The squares' table.
    pub fn squares(&self) -> &SquaresTable<'a, E, C> {
        &self.squares
    }

    /// Bytes of both tables.
    pub fn table_bytes(&self) -> usize {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "each is the size of a slice, at most isize::MAX: the sum is below usize::MAX"
        )]
        let bytes = self.values.table_bytes() + self.squares.table_bytes();
        bytes
    }

    /// The variance over the box `[x0, x1) x [y0, y1)` with integer corners under mode `M`:
    /// `round((n Q - S^2) 2^16 / n^2)` per channel, ties up (exact before the rounding).
    /// Interior box: 8 reads, 4 multiplies, 1 divide, 7 additive operations (one channel).
    /// Zero-area boxes are [`Error::ZeroArea`], inverted ones [`Error::InvertedBox`].
    pub fn variance_int<M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i32>,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let s = self.values.box_sum_int(r, mode, k)?;
        let q = BoxLookup::box_sum_int(&self.squares, r, mode, k)?;
        finish(&s, &q, k)
    }

    /// The variance over the box with fixed-point corners (`F <= 24`), box sums in form `Fm`,
    /// under mode `M`: the exact variance of the piecewise-constant texture over the box, rounded
    /// as [`VarianceTables::variance_int`]. Interior box: 32 reads, the two box sums' operations,
    /// plus 4 multiplies, 1 divide and 1 subtraction per channel.
    pub fn variance<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.variance_raw(&r.to_raw(), FracBits::of::<X>()?, form, mode, k)
    }

    /// [`VarianceTables::variance`] with raw corners (`value * 2^F`) and `F` as a value,
    /// checked once by [`FracBits::new`]: one compiled lookup serves every `F`.
    pub fn variance_raw<Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i64>,
        frac_bits: FracBits,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let s = self.values.box_sum_raw(r, frac_bits, form, mode, k)?;
        let q = BoxLookup::box_sum_raw(&self.squares, r, frac_bits, form, mode, k)?;
        finish(&s, &q, k)
    }
}

/// `(n Q - S^2) / n^2` per channel, rounded (module docs), with its operations counted: in
/// 64-bit words for `u64` sums ([`variance_u64`]), in `u128` for the `u128` sums of `u64`
/// tables ([`variance_u128`]).
fn finish<W: Wide, const C: usize, K: Counter>(
    s: &BoxSum<W, C>,
    q: &BoxSum<W, C>,
    k: &mut K,
) -> Result<Sample<C>, Error> {
    let (wr, hr) = s.sides_raw();
    k.muls(2);
    if wr == 0 || hr == 0 {
        return Err(Error::ZeroArea);
    }
    let mut out = [0u64; C];
    for (c, o) in out.iter_mut().enumerate() {
        k.muls(2);
        k.adds(1);
        k.divs(1);
        let (sc, qc) = (s.scaled_sum(c), q.scaled_sum(c));
        // Dispatched by the word's width (a constant per instantiation): `u64` words (`u16` and
        // `u32` tables) take the 64-bit formulation, whose `to_u64` is the word itself, and
        // never reach the `u128` one (docs/wide-arithmetic.md).
        *o = match (W::BITS <= 64, sc.to_u64(), qc.to_u64()) {
            (true, Some(sc), Some(qc)) => variance_u64(sc, qc, wr, hr, c)?,
            _ => variance_u128(sc.into(), qc.into(), wr, hr, c)?,
        };
    }
    Ok(Sample { values: out })
}

fn mean_too_wide(needed: u32, available: u32) -> Error {
    Error::TooWide {
        what: Quantity::MeanNumerator,
        bits_needed: needed,
        bits_available: available,
    }
}

/// Largest raw area `n` [`variance_u64`] takes: below `2^62`, so `4n < 2^64`.
const AREA_LIMIT_BITS: u32 = 62;

/// `round(2^16 (n Q - S^2) / n^2)`, ties up, with `n = wr hr` (`wr, hr >= 1`), in 64-bit words
/// (module docs, "Exact arithmetic"). [`Error::TooWide`] for `n >= 2^62`;
/// [`Error::InvalidTable`] (channel `c`) where `n Q < S^2`, which tables of a texture never give.
fn variance_u64(s: u64, q: u64, wr: u64, hr: u64, c: usize) -> Result<u64, Error> {
    let invalid = Error::InvalidTable {
        x: 0,
        y: 0,
        channel: c,
    };
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "wr, hr >= 1: each has 1 to 64 bits, so the sum is in [2, 128]"
    )]
    let product_bits = bits_of_u64(wr) + bits_of_u64(hr) - 1;
    let n = wr
        .checked_mul(hr)
        .ok_or(mean_too_wide(product_bits, AREA_LIMIT_BITS))?;
    if bits_of_u64(n) > AREA_LIMIT_BITS {
        return Err(mean_too_wide(bits_of_u64(n), AREA_LIMIT_BITS));
    }
    let nz = NonZeroU64::new(n).ok_or(Error::ZeroArea)?;
    let (a, r) = (s / nz, s % nz);
    // Q' = Q - a (S + r) >= 0 for a table of a texture; a (S + r) past u64 is past Q.
    let qp = s
        .checked_add(r)
        .and_then(|v| v.checked_mul(a))
        .and_then(|v| q.checked_sub(v))
        .ok_or(invalid)?;
    let (b, t) = (qp / nz, qp % nz);
    let (e, f) = square_div_rem(r, nz);
    // σ^2 = b + (g n - f) / n^2 with g = t - e in (-n, n): as B + (h + φ / n) / n.
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "each difference is taken on the side where it is >= 0"
    )]
    let (g_neg, g_abs) = if t >= e {
        (false, t - e)
    } else {
        (true, e - t)
    };
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "t, e < n, so |g| < n: g_abs - 1 only for g_abs >= 1, g_abs + 1 <= n; f = r^2 \
                  mod n < n"
    )]
    let (h0_neg, h0_abs, phi) = match (f == 0, g_neg) {
        (true, _) => (g_neg, g_abs, 0),
        // g - 1 for g >= 1; -1 for g = 0; -(|g| + 1) for g < 0.
        (false, false) if g_abs >= 1 => (false, g_abs - 1, n - f),
        (false, _) => (true, g_abs + 1, n - f),
    };
    #[allow(clippy::arithmetic_side_effects, reason = "h0 in [-n, 0): h0_abs <= n")]
    let (big_b, h) = if h0_neg && h0_abs > 0 {
        // h0 in [-n, 0): borrow one from b.
        (b.checked_sub(1).ok_or(invalid)?, n - h0_abs)
    } else {
        (b, h0_abs)
    };
    // round(2^16 (h + φ/n) / n) = floor((2^17 h + floor(2^17 φ / n) + n) / (2n)).
    let (phi2, _) = shl_div_rem(phi, 17, nz);
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "n < 2^62 (AREA_LIMIT_BITS above): 2n < 2^63"
    )]
    let d = NonZeroU64::new(2 * n).ok_or(Error::ZeroArea)?;
    let (mut quot, rem) = shl_div_rem(h, 17, d);
    // rem < 2n, phi2 < 2^17, n < 2^62: the sum is below 2^64.
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "rem < 2n, phi2 < 2^17 and n < 2^62: the sum is below 2^64; the total is \
                  round(2^16 (h + φ/n) / n) with 0 <= h, φ < n, at most 2^16"
    )]
    {
        quot += (rem + phi2 + n) / d;
    }
    big_b
        .checked_mul(1 << OUT_FRAC_BITS)
        .and_then(|v| v.checked_add(quot))
        .ok_or(mean_too_wide(65, 64))
}

/// `(floor(x 2^k / d), x 2^k mod d)` for `x < d < 2^62`: one `u64` division when `x 2^k` fits
/// 64 bits, else `k` steps of restoring division (the remainder stays below `d`, its double
/// below `2^63`).
#[inline]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "rem -= d only when rem >= d (restoring division): rem stays below d"
)]
fn shl_div_rem(x: u64, k: u32, d: NonZeroU64) -> (u64, u64) {
    if x.leading_zeros() >= k {
        let v = x << k;
        return (v / d, v % d);
    }
    let d = d.get();
    let (mut q, mut rem) = (0u64, x);
    for _ in 0..k {
        rem <<= 1;
        q <<= 1;
        if rem >= d {
            rem -= d;
            q |= 1;
        }
    }
    (q, rem)
}

/// `(floor(r^2 / n), r^2 mod n)` for `r < n < 2^62`: one `u64` division when `r < 2^32`, else
/// shift-and-add over the bits of `r` keeping `r^2 = q n + rem` with `rem < n` (every
/// intermediate below `2n < 2^63`; `q <= r`).
#[inline]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "r < 2^32 on the first path: r^2 < 2^64; then leading_zeros <= 64, rem -= n only \
              when rem >= n, rem < n before rem += r (so below 2n < 2^63), q <= r"
)]
fn square_div_rem(r: u64, n: NonZeroU64) -> (u64, u64) {
    if r >> 32 == 0 {
        let v = r * r;
        return (v / n, v % n);
    }
    let n = n.get();
    let (mut q, mut rem) = (0u64, 0u64);
    for i in (0..64 - r.leading_zeros()).rev() {
        q <<= 1;
        rem <<= 1;
        if rem >= n {
            rem -= n;
            q += 1;
        }
        if (r >> i) & 1 == 1 {
            rem += r;
            if rem >= n {
                rem -= n;
                q += 1;
            }
        }
    }
    (q, rem)
}

/// The `u128` formulation, for the `u128` sums of `u64` tables: `round((n Q - S^2) 2^16 / n^2)`
/// with `n Q` in `u128` and `n^2 < 2^127` (module docs: those sums are 128-bit words already).
#[allow(
    clippy::arithmetic_side_effects,
    reason = "the products are checked_mul; the plain arithmetic is on bit counts of u128 \
              values (each <= 128), whose sums and doubles are at most 256"
)]
fn variance_u128(sc: u128, qc: u128, wr: u64, hr: u64, c: usize) -> Result<u64, Error> {
    let (wr, hr) = (u128::from(wr), u128::from(hr));
    // wr, hr < 2^64: the product fits u128.
    let n = wr.wrapping_mul(hr);
    let nn = n
        .checked_mul(n)
        .filter(|&v| v < 1u128 << 127)
        .ok_or(mean_too_wide(2 * bits_of(n), 127))?;
    let nq = n
        .checked_mul(qc)
        .ok_or(mean_too_wide(bits_of(n) + bits_of(qc), 128))?;
    let ss = sc
        .checked_mul(sc)
        .ok_or(mean_too_wide(2 * bits_of(sc), 128))?;
    // n Q >= S^2 for any tables built from a texture (Cauchy–Schwarz); a table that violates it
    // was not.
    let num = nq.checked_sub(ss).ok_or(Error::InvalidTable {
        x: 0,
        y: 0,
        channel: c,
    })?;
    div_round_shift(num, OUT_FRAC_BITS, nn)
}

/// The crate's one 128-bit rounded division ([`crate::wide`]).
pub(crate) use crate::wide::div_round_shift_u128 as div_round_shift;

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
    use crate::{Border, ClampToEdge, MirroredRepeat, NoCount, Paper, Repeat, Stable, Tally};
    use fixed::types::I24F8;
    use std::vec;
    use std::vec::Vec;

    fn tex(w: usize, h: usize, seed: u64) -> Vec<u8> {
        let mut s = seed;
        (0..w * h)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 33) as u8
            })
            .collect()
    }

    /// Direct: n, S, Q over the extended texture, then the same rounding.
    fn direct<M: EdgeMode>(mode: M, t: &[u8], w: usize, h: usize, r: &Rect<i32>) -> u64 {
        let (mut s, mut q, mut n) = (0u128, 0u128, 0u128);
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                n += 1;
                if let (Some(i), Some(j)) = (
                    mode.kind().texel_index(x as i64, w),
                    mode.kind().texel_index(y as i64, h),
                ) {
                    let v = t[j * w + i] as u128;
                    s += v;
                    q += v * v;
                }
            }
        }
        div_round_shift(n * q - s * s, 16, n * n).unwrap()
    }

    fn every_box<M: EdgeMode>(mode: M) {
        for (w, h) in [(1, 1), (1, 5), (5, 1), (4, 3)] {
            let t = tex(w, h, (w * 7 + h) as u64);
            let texture = Texture::<u8>::new(&t, w, h).unwrap();
            let mut vs = vec![0u32; w * h];
            let mut qs = vec![0u32; w * h];
            let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
            // Under Miri (about 10^4 times slower) every 61st box of the sweep (the first included).
            let mut case = 0u32;
            for x0 in -3..=w as i32 + 2 {
                for x1 in x0 + 1..=w as i32 + 3 {
                    for y0 in -2..=h as i32 + 1 {
                        for y1 in y0 + 1..=h as i32 + 2 {
                            case += 1;
                            if cfg!(miri) && case % 61 != 1 {
                                continue;
                            }
                            let r = Rect::new(x0, y0, x1, y1);
                            let got = vt.variance_int(&r, mode, &mut NoCount).unwrap();
                            assert_eq!(
                                got.values[0],
                                direct(mode, &t, w, h, &r),
                                "{} {r:?}",
                                mode.kind().name()
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn integer_boxes_every_mode() {
        every_box(Border);
        every_box(ClampToEdge);
        every_box(Repeat);
        every_box(MirroredRepeat);
    }

    #[test]
    fn fractional_boxes_are_exact() {
        // Half-texel box over two texels a, b: mean (a+b)/2, variance ((a-b)/2)^2.
        let t = [10u8, 30, 0, 0];
        let texture = Texture::<u8>::new(&t, 2, 2).unwrap();
        let mut vs = [0u32; 4];
        let mut qs = [0u32; 4];
        let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
        let r = Rect::new(
            I24F8::from_num(0.5),
            I24F8::ZERO,
            I24F8::from_num(1.5),
            I24F8::ONE,
        );
        for v in [
            vt.variance(&r, Paper, Border, &mut NoCount).unwrap(),
            vt.variance(&r, Stable, Border, &mut NoCount).unwrap(),
        ] {
            assert_eq!(v.values[0], 100 << 16);
        }
        // A quarter of texel 0 and three quarters of texel 1: var = 1/4 * 3/4 * 20^2 = 75.
        let r = Rect::new(
            I24F8::from_num(0.75),
            I24F8::ZERO,
            I24F8::from_num(1.75),
            I24F8::ONE,
        );
        let v = vt.variance(&r, Stable, Border, &mut NoCount).unwrap();
        assert_eq!(v.values[0], 75 << 16);
    }

    #[test]
    fn costs() {
        let t = tex(8, 8, 1);
        let texture = Texture::<u8>::new(&t, 8, 8).unwrap();
        let mut vs = [0u32; 64];
        let mut qs = [0u32; 64];
        let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
        let mut k = Tally::new();
        vt.variance_int(&Rect::new(2, 2, 6, 7), Border, &mut k)
            .unwrap();
        assert_eq!((k.reads, k.muls, k.divs, k.adds), (8, 4, 1, 7));
        let mut k = Tally::new();
        let r = Rect::new(
            I24F8::from_num(1.3),
            I24F8::from_num(2.2),
            I24F8::from_num(6.1),
            I24F8::from_num(5.9),
        );
        vt.variance(&r, Paper, Border, &mut k).unwrap();
        assert_eq!((k.reads, k.muls, k.divs, k.adds), (32, 28, 1, 55));
    }

    #[test]
    fn squares_bits_in_u64_match_the_u128_proof() {
        for bits in [1u32, 7, 8, 12, 16] {
            for w in (1usize..70).chain([255, 256, 257, 258, 4095, 65536, (1 << 31) - 1]) {
                for h in [1usize, 2, 3, 255, 256, 257, 1 << 20, (1 << 31) - 1] {
                    assert_eq!(
                        squares_bits_u64(bits, w, h),
                        squares_entry_bits(bits, w, h),
                        "{bits} {w}x{h}"
                    );
                }
            }
        }
    }

    #[test]
    fn widths_and_refusals() {
        assert_eq!(squares_entry_bits(8, 256, 256), 32);
        // Largest square in u32 at 8 bits: 257 x 257 (255^2 * 257^2 < 2^32); 258 is refused.
        assert_eq!(squares_entry_bits(8, 257, 257), 32);
        assert_eq!(squares_entry_bits(8, 258, 258), 33);
        assert_eq!(squares_entry_bits(16, 1, 1), 32);
        let t = vec![0u8; 258 * 258];
        let texture = Texture::<u8>::new(&t, 258, 258).unwrap();
        let mut vs = vec![7u32; 258 * 258];
        let mut qs = vec![7u32; 258 * 258];
        assert_eq!(
            VarianceTables::build(&texture, &mut vs, &mut qs).err(),
            Some(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: 33,
                bits_available: 32
            })
        );
        // Under Miri (about 10^4 times slower) every 257th entry is probed, and the u64 tables
        // are built for a 16 x 16 texture instead of 258 x 258.
        let stride = if cfg!(miri) { 257 } else { 1 };
        assert!(vs.iter().chain(qs.iter()).step_by(stride).all(|&v| v == 7));
        let mut short = vec![0u64; 10];
        let n = if cfg!(miri) { 16 } else { 258 };
        let t64 = vec![0u8; n * n];
        let texture64 = Texture::<u8>::new(&t64, n, n).unwrap();
        let mut vs64 = vec![0u64; n * n];
        let mut qs64 = vec![0u64; n * n];
        assert!(VarianceTables::build(&texture64, &mut vs64, &mut qs64).is_ok());
        let mut vs2 = vec![0u64; 258 * 258];
        assert!(matches!(
            VarianceTables::build(&texture, &mut vs2, &mut short),
            Err(Error::StorageTooSmall { .. })
        ));
        // 16-bit texels: squares need u64.
        let t16 = vec![65535u16; 9];
        let texture = Texture::<u16>::new(&t16, 3, 3).unwrap();
        let mut a = [0u64; 9];
        let mut b = [0u64; 9];
        let vt = VarianceTables::build(&texture, &mut a, &mut b).unwrap();
        let v = vt
            .variance_int(&Rect::new(-1, 0, 3, 3), Border, &mut NoCount)
            .unwrap();
        // 3/4 of the box is 65535, 1/4 zero: variance = 65535^2 * 3/16.
        let want = (65535f64 * 65535.0 * 3.0 / 16.0 * 65536.0).round() as u64;
        assert_eq!(v.values[0], want);
        assert_eq!(
            vt.variance_int(&Rect::new(1, 1, 1, 3), Border, &mut NoCount),
            Err(Error::ZeroArea)
        );
    }

    #[test]
    fn u64_formulation_matches_u128_exhaustive_small() {
        // Every area 1..=40 (as w x h), every sum S <= 3n + 2 and square sum Q <= 9n + 5,
        // valid or not: the same value, or both InvalidTable.
        for wr in 1..=8u64 {
            for hr in 1..=5u64 {
                let n = wr * hr;
                // Under Miri (about 10^4 times slower) every area, but the sums in steps of n and the square
                // sums in steps of n + 1, each with its largest value.
                let (s_step, q_step) = if cfg!(miri) { (n, n + 1) } else { (1, 1) };
                let svs = (0..=3 * n + 2)
                    .step_by(s_step as usize)
                    .chain(cfg!(miri).then_some(3 * n + 2));
                for sv in svs {
                    let qvs = (0..=9 * n + 5)
                        .step_by(q_step as usize)
                        .chain(cfg!(miri).then_some(9 * n + 5));
                    for qv in qvs {
                        let old = variance_u128(sv as u128, qv as u128, wr, hr, 0);
                        let new = variance_u64(sv, qv, wr, hr, 0);
                        assert_eq!(new, old, "S={sv} Q={qv} n={wr}x{hr}");
                    }
                }
            }
        }
    }

    #[test]
    fn u64_formulation_matches_u128_random_large() {
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut paths = [0u32; 3];
        // Under Miri (about 10^4 times slower) 1500 random cases.
        let (rounds, per_path) = if cfg!(miri) {
            (1_500, 10)
        } else {
            (200_000, 1000)
        };
        for i in 0..rounds {
            let wr = (next() >> (next() % 64)).max(1);
            let hr = (next() >> (next() % 64)).max(1);
            let (wr, hr) = if i % 3 == 0 {
                (wr >> 33, hr >> 33)
            } else {
                (wr, hr)
            };
            let (wr, hr) = (wr.max(1), hr.max(1));
            let n = wr as u128 * hr as u128;
            // Valid sums: mean in [0, m], second moment between mean^2 and m^2.
            let m = (next() % 65536) as u128;
            let cap = u64::MAX as u128;
            let sv = (next() as u128 * (m.saturating_mul(n).min(cap) + 1)) >> 64;
            let lo = (sv * sv).div_ceil(n);
            let hi = (m * m).saturating_mul(n).min(cap);
            let qv = if hi > lo {
                lo + ((next() as u128 * (hi - lo)) >> 64)
            } else {
                lo
            };
            let qv = match i % 7 {
                0 => lo,
                1 if lo > 0 => lo - 1, // just invalid
                _ => qv,
            };
            let (Ok(sv), Ok(qv)) = (u64::try_from(sv), u64::try_from(qv)) else {
                continue;
            };
            let old = variance_u128(sv as u128, qv as u128, wr, hr, 0);
            let new = variance_u64(sv, qv, wr, hr, 0);
            if n >= 1 << 62 {
                assert!(matches!(
                    new,
                    Err(Error::TooWide {
                        bits_available: 62,
                        ..
                    })
                ));
                paths[0] += 1;
            } else {
                assert_eq!(new, old, "S={sv} Q={qv} n={wr}x{hr}");
                paths[if n >> 32 == 0 { 1 } else { 2 }] += 1;
            }
        }
        assert!(paths.iter().all(|&p| p > per_path), "{paths:?}");
        // Ties round up on both paths, and the largest areas.
        assert_eq!(variance_u64(1, 1, 2, 1, 0), Ok(1 << 14)); // var of {0, 1} = 1/4
        let n = (1u64 << 62) - 1;
        assert_eq!(
            variance_u64(n, n, n, 1, 0),
            variance_u128(n as u128, n as u128, n, 1, 0)
        );
        assert_eq!(
            variance_u64(3 * (n / 2), 9 * (n / 4), n, 1, 0),
            variance_u128(3 * (n / 2) as u128, 9 * (n / 4) as u128, n, 1, 0)
        );
        assert_eq!(
            variance_u64(1, 1, 1 << 31, 1 << 31, 0),
            Err(Error::TooWide {
                what: Quantity::MeanNumerator,
                bits_needed: 63,
                bits_available: 62
            })
        );
        assert!(variance_u64(u64::MAX, u64::MAX, u64::MAX, u64::MAX, 0).is_err());
    }

    #[test]
    fn channels() {
        let t = tex(5, 4, 9);
        let texture = Texture::<u8, 2>::new(&t[..20], 5, 2).unwrap();
        let mut a = [0u32; 20];
        let mut b = [0u32; 20];
        let vt = VarianceTables::build(&texture, &mut a, &mut b).unwrap();
        let mut k = Tally::new();
        let v = vt
            .variance_int(&Rect::new(1, 0, 4, 2), Repeat, &mut k)
            .unwrap();
        for c in 0..2 {
            let ch: Vec<u8> = t[..20].iter().skip(c).step_by(2).copied().collect();
            assert_eq!(
                v.values[c],
                direct(Repeat, &ch, 5, 2, &Rect::new(1, 0, 4, 2))
            );
        }
        assert_eq!((k.muls, k.divs), (6, 2));
    }
}
