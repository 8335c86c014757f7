//! Box lookups: exact box sums and means from the table.
//!
//! * [`Sat::box_sum_int`]: integer corners, 4 reads (Crow §2.1).
//! * [`Sat::box_sum`]: fixed-point corners with `F` fractional bits, 16 reads, in one of two
//!   [`Form`]s: [`Paper`] (Crow §2.1–2.2) or [`Stable`].
//! * [`Sat::box_mean_shortcut`]: Crow's 4-read shortcut for large footprints (§2.2) with a proven
//!   bound, else the 16-read lookup.
//!
//! The corner function `S(x, y) = integral over [0, x) x [0, y)` of the piecewise-constant texture
//! is *bilinear* inside every texel cell, so bilinear interpolation of the table (Crow's corner
//! interpolation) is exact: with `x = i + A / 2^F`, `y = j + B / 2^F`,
//! `2^2F S(x, y) = (2^F - A)(2^F - B) S(i, j) + A (2^F - B) S(i+1, j) + (2^F - A) B S(i, j+1)
//! + A B S(i+1, j+1)`, an integer. Box sums are therefore returned exactly, scaled by `2^2F`
//! ([`BoxSum`]); the only rounding is the final division of the mean.

mod corners4;
mod paper;
mod shortcut;
mod stable;
mod weighted;

pub use shortcut::{Shortcut, ShortcutMean};

use crate::cost::Counter;
use crate::edge::{place, EdgeMode, Placement};
use crate::error::{Error, Quantity};
use crate::layouts::Layout;
use crate::rect::{Coord, RawBox, Rect};
use crate::table::Sat;
use crate::texel::{Acc, Entry};
use crate::width::{self, bits_of};

/// A box-sum formulation: how the 16 table values of a fractional-corner box are combined.
pub trait Form: Copy + Default {
    /// A short name (`paper`, `stable`).
    const NAME: &'static str;
    /// Accumulator value bits a table with whole-texture sums of `total_bits` bits needs at `F`.
    fn acc_bits(total_bits: u32, frac_bits: u32) -> u32;
    /// Extra bits a modular layout needs above the box sum's bits: the form's result is only
    /// known modulo `2^k`, so it must be below `2^k`.
    fn modular_headroom_bits(frac_bits: u32) -> u32;
    /// The box integral scaled by `2^2F`, for a box inside `[0, w] x [0, h]` (raw units).
    #[doc(hidden)]
    fn in_range<L: Layout<C>, const C: usize, K: Counter>(
        layout: &L,
        b: &RawBox,
        frac_bits: u32,
        k: &mut K,
    ) -> [u128; C];
}

/// Crow's formulation (§2.1–2.2): bilinear interpolation of the table at each corner, with each
/// lerp done as `b + (c - b) * alpha` (1 multiply, 2 additive operations), then
/// `V(x1,y1) - V(x1,y0) - V(x0,y1) + V(x0,y0)`.
///
/// Per box: 16 reads, 12 multiplies and 27 additive operations; the mean adds the area multiply
/// and the divide: 14 multiplicative operations, Crow's count. Multiplier data operands grow with
/// the *table*: see [`width::paper_multiplies`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Paper;

/// Differences first: the integer box, the four edge strips and the four corner texels are
/// formed from the 16 table values by subtraction, and only then multiplied by the fractions:
///
/// `2^2F I = 2^2F Bint + 2^F (A1 Rt - A0 L + B1 Bm - B0 T)
///         + A1 B1 t11 - A1 B0 t10 - A0 B1 t01 + A0 B0 t00`
///
/// where `Bint` is the sum over the integer box `[i0, i1) x [j0, j1)`, `L`/`Rt` the columns
/// `i0`/`i1` and `T`/`Bm` the rows `j0`/`j1` restricted to the box, `t..` the corner texels and
/// `A0, A1, B0, B1` the corner fractions. Multiplier data operands are bounded by the box's edge
/// strips, not the table ([`width::stable_multiplies`]), and the accumulator by the box sum.
/// Per box: 16 reads, 12 multiplies, 31 additive operations (mean: 14 multiplicative).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stable;

/// An exact box sum: per channel, the integral over the box scaled by `2^2F` (`F = 0` for integer
/// corners), with the box's side lengths for the mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoxSum<const C: usize> {
    sums: [u128; C],
    frac_bits: u32,
    width_raw: u128,
    height_raw: u128,
}

impl<const C: usize> BoxSum<C> {
    /// Channel `c`'s integral times `2^2F` (exact). Channels past `C` read as 0.
    pub fn scaled_sum(&self, c: usize) -> u128 {
        self.sums.get(c).copied().unwrap_or(0)
    }

    /// All channels' integrals times `2^2F`.
    pub fn scaled_sums(&self) -> [u128; C] {
        self.sums
    }

    /// Channel 0's integral times `2^2F`: for integer corners (`F = 0`), the box sum itself.
    pub fn sum(&self) -> u128 {
        self.scaled_sum(0)
    }

    /// `F`: the sums are in units of `2^-2F`.
    pub fn frac_bits(&self) -> u32 {
        self.frac_bits
    }

    /// The box's side lengths in units of `2^-F` (the unclipped box, also for [`crate::Border`]).
    pub fn sides_raw(&self) -> (u128, u128) {
        (self.width_raw, self.height_raw)
    }

    /// The box area in units of `2^-2F` (one multiply).
    fn area_raw<K: Counter>(&self, k: &mut K) -> Result<u128, Error> {
        k.muls(1);
        let area = self
            .width_raw
            .checked_mul(self.height_raw)
            .ok_or(Error::TooWide {
                what: Quantity::MeanNumerator,
                bits_needed: bits_of(self.width_raw) + bits_of(self.height_raw),
                bits_available: 128,
            })?;
        if area == 0 {
            Err(Error::ZeroArea)
        } else {
            Ok(area)
        }
    }

    /// Channel `c`'s mean over the box as a fixed-point number with `out_frac_bits` fractional
    /// bits: `round(sum * 2^g / area)`, rounding to nearest with ties up (away from zero). The
    /// result is within `2^-(g+1)` of the exact mean. Costs one multiply (the area) and one divide.
    pub fn mean_rounded<K: Counter>(
        &self,
        c: usize,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<u128, Error> {
        if c >= C {
            return Err(Error::NoSuchChannel);
        }
        let area = self.area_raw(k)?;
        k.divs(1);
        div_round(self.sums[c], out_frac_bits, area)
    }

    /// Every channel's mean (see [`BoxSum::mean_rounded`]): one multiply, `C` divides.
    pub fn means_rounded<K: Counter>(
        &self,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<[u128; C], Error> {
        let area = self.area_raw(k)?;
        let mut out = [0u128; C];
        for (o, &s) in out.iter_mut().zip(self.sums.iter()) {
            k.divs(1);
            *o = div_round(s, out_frac_bits, area)?;
        }
        Ok(out)
    }
}

/// `round(num * 2^g / den)`, ties up, refusing a numerator that does not fit `u128`.
pub(crate) fn div_round(num: u128, g: u32, den: u128) -> Result<u128, Error> {
    let needed = bits_of(num).saturating_add(g);
    if needed > 128 || g >= 128 {
        return Err(Error::TooWide {
            what: Quantity::MeanNumerator,
            bits_needed: needed,
            bits_available: 128,
        });
    }
    let n = num << g;
    let (q, r) = (n / den, n % den);
    Ok(if r >= den - r { q + 1 } else { q })
}

/// Box lookups over any [`Layout`]: implemented for every layout, so every mode and form works
/// on each. ([`Sat`] also has these as inherent methods, so the flat table needs no import.)
pub trait BoxLookup<const C: usize>: Layout<C> + Sized {
    /// The exact sum over the box `[x0, x1) x [y0, y1)` with integer corners, under boundary mode
    /// `M`. An in-range (or placeable, see [`crate::edge`]) box costs 4 corner reads and 3
    /// additive operations per channel; corners on the zero row or column cost no read. Zero-area
    /// boxes sum to 0 with no reads; inverted boxes are [`Error::InvertedBox`].
    fn box_sum_int<M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i32>,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<C>, Error> {
        let _ = mode;
        let b = RawBox {
            x0: r.x0 as i128,
            y0: r.y0 as i128,
            x1: r.x1 as i128,
            y1: r.y1 as i128,
        };
        sum_raw::<Self, corners4::Corners4, M, K, C>(self, b, 0, k)
    }

    /// The exact integral over the box with fixed-point corners (`X` has `F` fractional bits,
    /// `F <= 24`), scaled by `2^2F`, in formulation `Fm` under boundary mode `M`. An in-range box
    /// costs 16 corner reads (fewer on the zero row and column).
    ///
    /// Refused with [`Error::TooWide`] if the accumulator cannot hold the formulation's
    /// intermediates for this table ([`Form::acc_bits`]), e.g. `u32` entries holding 32-bit
    /// sums at `F = 16`, or, on a modular layout, if the box's sum may reach `2^k`.
    fn box_sum<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<C>, Error> {
        let _ = (form, mode);
        let f = X::FRAC_BITS;
        if f > width::MAX_FRAC_BITS {
            return Err(Error::FracBitsUnsupported {
                frac_bits: f,
                max: width::MAX_FRAC_BITS,
            });
        }
        let b = RawBox {
            x0: r.x0.raw() as i128,
            y0: r.y0.raw() as i128,
            x1: r.x1.raw() as i128,
            y1: r.y1.raw() as i128,
        };
        sum_raw::<Self, Fm, M, K, C>(self, b, f, k)
    }

    /// See [`shortcut`](crate::lookup::Shortcut): the mean by the 4-read shortcut when both
    /// sides are at least `shortcut.min_side()` texels, else by the exact 16-read lookup.
    fn box_mean_shortcut<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        shortcut: &Shortcut,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<ShortcutMean<C>, Error> {
        shortcut::mean(self, r, form, mode, shortcut, out_frac_bits, k)
    }
}

impl<const C: usize, L: Layout<C>> BoxLookup<C> for L {}

impl<E: Entry, const C: usize> Sat<'_, E, C> {
    /// [`BoxLookup::box_sum_int`] on the flat table: 4 reads, exact.
    pub fn box_sum_int<M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i32>,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<C>, Error> {
        BoxLookup::box_sum_int(self, r, mode, k)
    }

    /// [`BoxLookup::box_sum`] on the flat table: 16 reads, exact, scaled by `2^2F`.
    pub fn box_sum<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<C>, Error> {
        BoxLookup::box_sum(self, r, form, mode, k)
    }

    /// [`BoxLookup::box_mean_shortcut`] on the flat table.
    pub fn box_mean_shortcut<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        shortcut: &Shortcut,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<ShortcutMean<C>, Error> {
        BoxLookup::box_mean_shortcut(self, r, form, mode, shortcut, out_frac_bits, k)
    }
}

/// Texel columns (rows) a raw interval `[lo, hi)` overlaps: `ceil(hi) - floor(lo)`.
fn cells(lo: i128, hi: i128, f: u32) -> u128 {
    let s = 1i128 << f;
    (((hi + s - 1) >> f) - (lo >> f)).max(0) as u128
}

/// Refuses, on a modular layout, a box whose sum (with `headroom` extra bits) may reach `2^k`.
fn check_modular<L: Layout<C>, const C: usize>(
    layout: &L,
    b: &RawBox,
    f: u32,
    headroom: u32,
) -> Result<(), Error> {
    let Some(k) = layout.modulus() else {
        return Ok(());
    };
    let m = width::max_texel(layout.texel_bits());
    let area = cells(b.x0, b.x1, f).saturating_mul(cells(b.y0, b.y1, f));
    let needed = bits_of(m.saturating_mul(area)) + headroom;
    if needed > k {
        return Err(Error::TooWide {
            what: Quantity::ModularBox,
            bits_needed: needed,
            bits_available: k,
        });
    }
    Ok(())
}

/// The common driver: validate, place the box for the mode, then the in-range form or the
/// weighted path.
pub(crate) fn sum_raw<L: Layout<C>, Fm: Form, M: EdgeMode, K: Counter, const C: usize>(
    layout: &L,
    b: RawBox,
    f: u32,
    k: &mut K,
) -> Result<BoxSum<C>, Error> {
    if b.x1 < b.x0 || b.y1 < b.y0 {
        return Err(Error::InvertedBox);
    }
    let mut out = BoxSum {
        sums: [0; C],
        frac_bits: f,
        width_raw: (b.x1 - b.x0) as u128,
        height_raw: (b.y1 - b.y0) as u128,
    };
    if b.x1 == b.x0 || b.y1 == b.y0 {
        return Ok(out);
    }
    match place::<M>(b, layout.width(), layout.height(), f) {
        Placement::Empty => {}
        Placement::InRange(ib) => {
            check_modular(layout, &ib, f, Fm::modular_headroom_bits(f))?;
            width::check_acc(
                Fm::acc_bits(layout.value_bits(), f),
                <<L::Value as Entry>::Acc as Acc>::VALUE_BITS,
            )?;
            out.sums = Fm::in_range(layout, &ib, f, k);
        }
        Placement::Outside(ob) => {
            check_modular(layout, &ob, f, 2 * f)?;
            out.sums = weighted::sum::<M, L, K, C>(layout, &ob, f, k)?;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
