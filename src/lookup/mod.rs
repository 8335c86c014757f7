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
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

mod batch;
mod clamp_int;
mod corners4;
mod paper;
mod shortcut;
mod split;
mod stable;

pub use batch::BatchLookup;
pub use shortcut::{Shortcut, ShortcutMean};

use crate::cost::Counter;
use crate::edge::{place_axis, width_u64, AxisPlan, EdgeMode};
use crate::error::{Error, Quantity};
use crate::layouts::Layout;
use crate::rect::{Coord, FracBits, RawBox, Rect};
use crate::table::Sat;
use crate::texel::{Acc, Entry};
use crate::wide::Wide;
use crate::width;

/// The accumulator of a layout's lookups (`i32`, `i64` or `i128`, after its value type).
pub(crate) type AccOf<L, const C: usize> = <<L as Layout<C>>::Value as Entry>::Acc;
/// The result word of a layout's lookups (`u64`, or `u128` for `u64` values).
pub type WideOf<L, const C: usize> = <AccOf<L, C> as Acc>::Wide;

/// Which formulation, as a run-time value ([`Paper`] or [`Stable`] fixed at compile time are the
/// zero-sized choices). Implements [`Form`] by a `match`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FormKind {
    /// [`Paper`].
    Paper,
    /// [`Stable`].
    #[default]
    Stable,
}

impl FormKind {
    /// A short name: `paper`, `stable`.
    pub const fn name(self) -> &'static str {
        match self {
            FormKind::Paper => "paper",
            FormKind::Stable => "stable",
        }
    }

    /// Accumulator value bits this form needs on a table whose largest entry has `total_bits`
    /// bits, at `F = frac_bits` ([`width::paper_acc_bits`], [`width::stable_acc_bits`]).
    pub const fn acc_bits(self, total_bits: u32, frac_bits: u32) -> u32 {
        match self {
            FormKind::Paper => width::paper_acc_bits(total_bits, frac_bits),
            FormKind::Stable => width::stable_acc_bits(total_bits, frac_bits),
        }
    }

    /// Extra bits a modular layout needs above the box sum's bits in this form: `2F` for
    /// [`Paper`] (its corner values are only known modulo `2^k`), 0 for [`Stable`] (it reduces
    /// box-bounded differences first).
    pub const fn modular_headroom_bits(self, frac_bits: u32) -> u32 {
        match self {
            FormKind::Paper => frac_bits.saturating_mul(2),
            FormKind::Stable => 0,
        }
    }

    /// The form named by [`FormKind::name`].
    pub fn from_name(name: &str) -> Option<FormKind> {
        [FormKind::Paper, FormKind::Stable]
            .into_iter()
            .find(|k| k.name() == name)
    }
}

mod sealed {
    use super::AccOf;
    use crate::cost::Counter;
    use crate::layouts::Layout;
    use crate::rect::RawBox;

    /// The behaviour of a form (sealed: the width proofs cover exactly these).
    pub trait FormImpl: Copy {
        /// Whether the lookups call this form's in-range code out of line (one copy for the
        /// in-range and the split paths): the 16-read forms.
        const OUTLINE: bool = true;
        /// Accumulator value bits a table with whole-texture sums of `total_bits` bits needs.
        fn acc_bits(self, total_bits: u32, frac_bits: u32) -> u32;
        /// Extra bits a modular layout needs above the box sum's bits.
        fn modular_headroom_bits(self, frac_bits: u32) -> u32;
        /// The box integral scaled by `2^2F` for a box inside `[0, w] x [0, h]` (raw units); on
        /// a valid table never negative.
        fn in_range<L: Layout<C>, const C: usize, K: Counter>(
            self,
            layout: &L,
            b: &RawBox,
            frac_bits: u32,
            k: &mut K,
        ) -> [AccOf<L, C>; C];
    }
}

/// A box-sum formulation: how the 16 table values of a fractional-corner box are combined.
/// [`Paper`], [`Stable`], or [`FormKind`] at run time. Sealed.
pub trait Form: sealed::FormImpl {
    /// Which form this is.
    fn kind(self) -> FormKind;
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

impl Form for Paper {
    #[inline(always)]
    fn kind(self) -> FormKind {
        FormKind::Paper
    }
}

impl Form for Stable {
    #[inline(always)]
    fn kind(self) -> FormKind {
        FormKind::Stable
    }
}

impl Form for FormKind {
    #[inline(always)]
    fn kind(self) -> FormKind {
        self
    }
}

impl sealed::FormImpl for FormKind {
    #[inline(always)]
    fn acc_bits(self, total_bits: u32, frac_bits: u32) -> u32 {
        match self {
            FormKind::Paper => Paper.acc_bits(total_bits, frac_bits),
            FormKind::Stable => Stable.acc_bits(total_bits, frac_bits),
        }
    }
    #[inline(always)]
    fn modular_headroom_bits(self, frac_bits: u32) -> u32 {
        match self {
            FormKind::Paper => Paper.modular_headroom_bits(frac_bits),
            FormKind::Stable => Stable.modular_headroom_bits(frac_bits),
        }
    }
    #[inline(always)]
    fn in_range<L: Layout<C>, const C: usize, K: Counter>(
        self,
        layout: &L,
        b: &RawBox,
        frac_bits: u32,
        k: &mut K,
    ) -> [AccOf<L, C>; C] {
        match self {
            FormKind::Paper => Paper.in_range(layout, b, frac_bits, k),
            FormKind::Stable => Stable.in_range(layout, b, frac_bits, k),
        }
    }
}

use sealed::FormImpl;

/// An exact box sum: per channel, the integral over the box scaled by `2^2F` (`F = 0` for integer
/// corners), with the box's side lengths for the mean. `W` is the result word: `u64` for `u16`
/// and `u32` tables, `u128` for `u64` tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoxSum<W, const C: usize> {
    sums: [W; C],
    frac_bits: u32,
    width_raw: u64,
    height_raw: u64,
}

impl<W: Wide, const C: usize> BoxSum<W, C> {
    /// Channel `c`'s integral times `2^2F` (exact). Channels past `C` read as 0.
    pub fn scaled_sum(&self, c: usize) -> W {
        self.sums.get(c).copied().unwrap_or(W::ZERO)
    }

    /// All channels' integrals times `2^2F`.
    pub fn scaled_sums(&self) -> [W; C] {
        self.sums
    }

    /// Channel 0's integral times `2^2F`: for integer corners (`F = 0`), the box sum itself.
    pub fn sum(&self) -> W {
        self.scaled_sum(0)
    }

    /// `F`: the sums are in units of `2^-2F`.
    pub fn frac_bits(&self) -> u32 {
        self.frac_bits
    }

    /// The box's side lengths in units of `2^-F` (the unclipped box, also for [`crate::Border`]).
    pub fn sides_raw(&self) -> (u64, u64) {
        (self.width_raw, self.height_raw)
    }

    /// Channel `c`'s mean over the box as a fixed-point number with `out_frac_bits` fractional
    /// bits: `round(sum * 2^g / area)`, rounding to nearest with ties up (away from zero). The
    /// result is within `2^-(g+1)` of the exact mean. Costs one multiply (the area) and one
    /// divide; for `u64` results one `u64` division in the common case (see [`crate::wide`]'s
    /// docs), never a 128-bit operation. A zero-area box is [`Error::ZeroArea`].
    pub fn mean_rounded<K: Counter>(
        &self,
        c: usize,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<W, Error> {
        let Some(&s) = self.sums.get(c) else {
            return Err(Error::NoSuchChannel);
        };
        self.check_area()?;
        k.muls(1);
        k.divs(1);
        s.div_round_area(out_frac_bits, self.width_raw, self.height_raw)
    }

    /// [`BoxSum::mean_rounded`] as a 32-bit word, for firmware whose boxes keep the area and the
    /// mean narrow: the same value, `round(sum * 2^g / area)` with ties up, computed by one
    /// 64-by-32-bit division (two hardware divides on a Cortex-M3/M4, no library routine), and
    /// refused as [`Error::TooWide`] where [`BoxSum::mean_rounded`] would need more: `sum * 2^g`
    /// past 64 bits ([`Quantity::MeanNumerator`]), the area
    /// `W H` (in units of `2^-2F`) past 32 bits ([`Quantity::MeanArea`])
    /// or the mean itself past 32 bits ([`Quantity::Mean`]).
    ///
    /// Why: the general mean carries fallbacks for huge areas and numerators (a 64-bit divisor,
    /// long division), about 1.1 KiB of Cortex-M4 code a firmware never runs when its plan
    /// proves every box narrow ([`crate::plan::Plan::mean_fits_u32`]); calling this instead
    /// leaves them out. Counted as one multiply and one divide, like [`BoxSum::mean_rounded`].
    pub fn mean_rounded_u32<K: Counter>(
        &self,
        c: usize,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<u32, Error> {
        let Some(&s) = self.sums.get(c) else {
            return Err(Error::NoSuchChannel);
        };
        self.check_area()?;
        k.muls(1);
        k.divs(1);
        crate::wide::div_round_area_u32(s, out_frac_bits, self.width_raw, self.height_raw)
    }

    /// Every channel's mean (see [`BoxSum::mean_rounded`]): one multiply, `C` divides.
    pub fn means_rounded<K: Counter>(
        &self,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<[W; C], Error> {
        self.check_area()?;
        k.muls(1);
        let mut out = [W::ZERO; C];
        for (o, &s) in out.iter_mut().zip(self.sums.iter()) {
            k.divs(1);
            *o = s.div_round_area(out_frac_bits, self.width_raw, self.height_raw)?;
        }
        Ok(out)
    }

    /// The same sums as `u128` (a host-side convenience for comparing with wide references;
    /// firmware never needs it).
    pub fn to_u128(&self) -> BoxSum<u128, C> {
        BoxSum {
            sums: self.sums.map(Into::into),
            frac_bits: self.frac_bits,
            width_raw: self.width_raw,
            height_raw: self.height_raw,
        }
    }

    fn check_area(&self) -> Result<(), Error> {
        if self.width_raw == 0 || self.height_raw == 0 {
            Err(Error::ZeroArea)
        } else {
            Ok(())
        }
    }
}

/// Box lookups over any [`Layout`]: implemented for every layout, so every mode and form works
/// on each. ([`Sat`] also has these as inherent methods, so the flat table needs no import.)
pub trait BoxLookup<const C: usize>: Layout<C> + Sized {
    /// The exact sum over the box `[x0, x1) x [y0, y1)` with integer corners, under boundary mode
    /// `M`. An in-range (or placeable, see [`crate::edge`]) box costs 4 corner reads and 3
    /// additive operations per channel; corners on the zero row or column cost no read. Zero-area
    /// boxes sum to 0 with no reads; inverted boxes are [`Error::InvertedBox`].
    #[inline(always)]
    fn box_sum_int<M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i32>,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<WideOf<Self, C>, C>, Error> {
        sum_int(self, r, mode, k)
    }

    /// The exact integral over the box with raw fixed-point corners (`value * 2^F`, `F` given as a
    /// value), scaled by `2^2F`, in formulation `form` under boundary mode `mode`. An in-range box
    /// costs 16 corner reads (fewer on the zero row and column); a box that crosses the texture's
    /// edge under a wrapping or clamping mode is split into at most 9 in-range boxes (see
    /// [`crate::edge`]).
    ///
    /// Refused with [`Error::TooWide`] if the accumulator cannot hold the formulation's
    /// intermediates for this table (see [`width::max_frac_bits`]), if the sum of a box that
    /// covers many periods does not fit the result word, or, on a modular layout, if the box's
    /// sum may reach `2^k`.
    #[inline]
    fn box_sum_raw<Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i64>,
        frac_bits: FracBits,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<WideOf<Self, C>, C>, Error> {
        sum_raw(self, r, frac_bits.get(), form, mode, k)
    }

    /// [`BoxLookup::box_sum_raw`] with the corners as a `fixed` type `X` (`F = X::FRAC_BITS`,
    /// at most [`width::MAX_FRAC_BITS`]).
    #[inline]
    fn box_sum<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<WideOf<Self, C>, C>, Error> {
        sum_raw(self, &r.to_raw(), FracBits::of::<X>()?.get(), form, mode, k)
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
    ) -> Result<ShortcutMean<WideOf<Self, C>, C>, Error> {
        shortcut::mean(
            self,
            &r.to_raw(),
            FracBits::of::<X>()?,
            form,
            mode,
            shortcut,
            out_frac_bits,
            k,
        )
    }

    /// [`BoxLookup::box_mean_shortcut`] with raw corners and `F` as a value.
    #[allow(clippy::too_many_arguments)]
    fn box_mean_shortcut_raw<Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i64>,
        frac_bits: FracBits,
        form: Fm,
        mode: M,
        shortcut: &Shortcut,
        out_frac_bits: u32,
        k: &mut K,
    ) -> Result<ShortcutMean<WideOf<Self, C>, C>, Error> {
        shortcut::mean(self, r, frac_bits, form, mode, shortcut, out_frac_bits, k)
    }
}

impl<const C: usize, L: Layout<C>> BoxLookup<C> for L {}

impl<E: Entry, const C: usize> Sat<'_, E, C> {
    /// [`BoxLookup::box_sum_int`] on the flat table: 4 reads, exact.
    #[inline(always)]
    pub fn box_sum_int<M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i32>,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<<E::Acc as Acc>::Wide, C>, Error> {
        BoxLookup::box_sum_int(self, r, mode, k)
    }

    /// [`BoxLookup::box_sum`] on the flat table: 16 reads, exact, scaled by `2^2F`.
    #[inline]
    pub fn box_sum<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<<E::Acc as Acc>::Wide, C>, Error> {
        BoxLookup::box_sum(self, r, form, mode, k)
    }

    /// [`BoxLookup::box_sum_raw`] on the flat table.
    #[inline]
    pub fn box_sum_raw<Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i64>,
        frac_bits: FracBits,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<BoxSum<<E::Acc as Acc>::Wide, C>, Error> {
        BoxLookup::box_sum_raw(self, r, frac_bits, form, mode, k)
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
    ) -> Result<ShortcutMean<<E::Acc as Acc>::Wide, C>, Error> {
        BoxLookup::box_mean_shortcut(self, r, form, mode, shortcut, out_frac_bits, k)
    }
}

/// Splits an in-range raw coordinate `0 <= x <= n 2^F` into cell `i <= n - 1` and fraction
/// `a <= 2^F` (the right edge `x = n` is cell `n - 1` with `a = 2^F`, so `i + 1 <= n`).
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "0 <= x <= n 2^F (placed) and f <= MAX_FRAC_BITS = 24: x >> f <= n <= 2^31 - 1 \
              (check_dimensions) fits usize (at least 32 bits: MAX_DIMENSION); 1 << f >= 1, so \
              (1 << f) - 1 does not wrap, and x & (2^f - 1) < 2^24 fits u32"
)]
pub(crate) fn split_coord(x: i64, n: usize, f: u32) -> (usize, u32) {
    let i = (x >> f) as usize;
    if i >= n {
        (n.saturating_sub(1), 1u32 << f)
    } else {
        (i, (x & ((1i64 << f) - 1)) as u32)
    }
}

/// Texel cells a raw interval `[lo, hi)` overlaps, `ceil(hi) - floor(lo)`, exact in `u64`.
#[inline(always)]
pub(crate) fn cells(lo: i64, hi: i64, f: u32) -> u64 {
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "f <= MAX_FRAC_BITS = 24: 1 << f >= 1, so subtracting 1 does not wrap"
    )]
    let mask = (1i64 << f) - 1;
    let frac = u64::from(hi & mask != 0);
    width_u64(lo >> f, hi >> f).wrapping_add(frac)
}

/// Refuses, on a modular layout, a box whose sum (with `headroom` extra bits) may reach `2^k`.
#[inline(always)]
fn check_modular<L: Layout<C>, const C: usize>(
    layout: &L,
    b: &Rect<i64>,
    f: u32,
    headroom: u32,
) -> Result<(), Error> {
    let Some(k) = layout.modulus() else {
        return Ok(());
    };
    let m = width::max_texel_u64(layout.texel_bits());
    let bound = cells(b.x0, b.x1, f)
        .checked_mul(cells(b.y0, b.y1, f))
        .and_then(|a| a.checked_mul(m));
    let needed = match bound {
        Some(v) => width::bits_of_u64(v),
        None => 65,
    }
    .saturating_add(headroom);
    if needed > k {
        return Err(Error::TooWide {
            what: Quantity::ModularBox,
            bits_needed: needed,
            bits_available: k,
        });
    }
    Ok(())
}

/// Refuses, for [`crate::RepeatWithinPeriod`], a non-empty box of raw sides `w x h` longer than
/// one period (the texture's side, `n 2^F` raw units) on some axis.
#[inline(always)]
pub(crate) fn refuse_longer_than_period<L: Layout<C>, const C: usize>(
    layout: &L,
    w: u64,
    h: u64,
    f: u32,
) -> Result<(), Error> {
    #[allow(
        clippy::as_conversions,
        reason = "sides <= 2^31 - 1 (check_dimensions) and f <= MAX_FRAC_BITS = 24: lossless, and \
                  the shifted values stay below 2^55"
    )]
    let (pw, ph) = ((layout.width() as u64) << f, (layout.height() as u64) << f);
    if w != 0 && h != 0 && (w > pw || h > ph) {
        return Err(Error::OutsidePlan {
            limit: crate::plan::PlanLimit::LongerThanPeriod,
        });
    }
    Ok(())
}

/// Checks that the form's accumulator holds its intermediates on this table.
#[inline(always)]
fn check_acc<L: Layout<C>, Fm: FormImpl, const C: usize>(
    layout: &L,
    form: Fm,
    f: u32,
) -> Result<(), Error> {
    width::check_acc(
        form.acc_bits(layout.value_bits(), f),
        <AccOf<L, C> as Acc>::VALUE_BITS,
    )
}

/// One in-range box through the form, as result words (a negative result can only come from
/// corrupt lent storage). The 16-read forms are called out of line ([`FormImpl::OUTLINE`]):
/// one copy serves the in-range path and every piece of the split path (Stable + Repeat on the
/// Cortex-M4: 850 bytes of flash less, 20 to 30 instructions more per lookup); the 4-read
/// lookup, a few instructions, stays inline.
#[inline(always)]
pub(crate) fn in_range_wide<L: Layout<C>, Fm: FormImpl, K: Counter, const C: usize>(
    layout: &L,
    b: &RawBox,
    f: u32,
    form: Fm,
    k: &mut K,
) -> Result<[WideOf<L, C>; C], Error> {
    if Fm::OUTLINE {
        in_range_wide_outlined(layout, b, f, form, k)
    } else {
        in_range_wide_inline(layout, b, f, form, k)
    }
}

#[inline(never)]
fn in_range_wide_outlined<L: Layout<C>, Fm: FormImpl, K: Counter, const C: usize>(
    layout: &L,
    b: &RawBox,
    f: u32,
    form: Fm,
    k: &mut K,
) -> Result<[WideOf<L, C>; C], Error> {
    in_range_wide_inline(layout, b, f, form, k)
}

#[inline(always)]
fn in_range_wide_inline<L: Layout<C>, Fm: FormImpl, K: Counter, const C: usize>(
    layout: &L,
    b: &RawBox,
    f: u32,
    form: Fm,
    k: &mut K,
) -> Result<[WideOf<L, C>; C], Error> {
    let acc = form.in_range(layout, b, f, k);
    let mut out = [<WideOf<L, C> as Wide>::ZERO; C];
    for (o, a) in out.iter_mut().zip(acc) {
        *o = a.to_wide().ok_or(Error::CorruptStorage)?;
    }
    Ok(out)
}

/// The 4-read driver: an in-range box (the common case, the same in every mode) is placed with
/// 32-bit comparisons (two instructions fewer per comparison than 64-bit ones on a 32-bit core);
/// anything else takes the general driver, out of line.
#[inline(always)]
fn sum_int<L: Layout<C>, M: EdgeMode, K: Counter, const C: usize>(
    layout: &L,
    r: &Rect<i32>,
    mode: M,
    k: &mut K,
) -> Result<BoxSum<WideOf<L, C>, C>, Error> {
    // Clamp to edge on a layout without a modulus: every box through the one 32-bit clamp
    // path (an in-range box is its single piece), as a hand-written clamp lookup does; no
    // second, inlined copy of the in-range reads (smallest plan on a Cortex-M4: docs/firmware.md).
    if mode.kind() == crate::EdgeKind::Clamp && layout.modulus().is_none() {
        return clamp_int::sum(layout, r, k);
    }
    // `cast_unsigned` of a non-negative `i32` (checked first: `&&` short-circuits) is its value.
    #[allow(
        clippy::as_conversions,
        reason = "u32 -> usize is lossless: usize has at least 32 bits (MAX_DIMENSION)"
    )]
    let in_range = r.x0 >= 0
        && r.y0 >= 0
        && r.x1 >= r.x0
        && r.y1 >= r.y0
        && r.x1.cast_unsigned() as usize <= layout.width()
        && r.y1.cast_unsigned() as usize <= layout.height();
    if !in_range {
        return sum_int_general(layout, r, mode, k);
    }
    let (x0, y0, x1, y1) = (
        r.x0.cast_unsigned(),
        r.y0.cast_unsigned(),
        r.x1.cast_unsigned(),
        r.y1.cast_unsigned(),
    );
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "in range: x1 >= x0 and y1 >= y0 (checked above)"
    )]
    let (w, h) = (x1 - x0, y1 - y0);
    let mut out = BoxSum {
        sums: [<WideOf<L, C> as Wide>::ZERO; C],
        frac_bits: 0,
        width_raw: u64::from(w),
        height_raw: u64::from(h),
    };
    if x1 == x0 || y1 == y0 {
        return Ok(out);
    }
    if layout.modulus().is_some() {
        check_modular(layout, &r.to_raw_int(), 0, 0)?;
    }
    let b = RawBox {
        x0: i64::from(x0),
        y0: i64::from(y0),
        x1: i64::from(x1),
        y1: i64::from(y1),
    };
    out.sums = in_range_wide(layout, &b, 0, corners4::Corners4, k)?;
    Ok(out)
}

/// [`sum_int`] for a box that is inverted or reaches outside the texture.
#[inline(never)]
fn sum_int_general<L: Layout<C>, M: EdgeMode, K: Counter, const C: usize>(
    layout: &L,
    r: &Rect<i32>,
    mode: M,
    k: &mut K,
) -> Result<BoxSum<WideOf<L, C>, C>, Error> {
    sum_raw(layout, &r.to_raw_int(), 0, corners4::Corners4, mode, k)
}

/// The common driver: validate, place the box for the mode, then one in-range lookup (the
/// common case) or the split path.
#[inline(always)]
pub(crate) fn sum_raw<L: Layout<C>, Fm: FormImpl, M: EdgeMode, K: Counter, const C: usize>(
    layout: &L,
    r: &Rect<i64>,
    f: u32,
    form: Fm,
    mode: M,
    k: &mut K,
) -> Result<BoxSum<WideOf<L, C>, C>, Error> {
    sum_raw_with::<L, Fm, M, K, _, C, false>(
        layout,
        r,
        f,
        form,
        mode,
        || check_acc(layout, form, f),
        k,
    )
}

/// [`sum_raw`] with the accumulator check given as `acc` (evaluated only where a box needs it,
/// so errors come in the same order; the batch passes the result it computed once), and with
/// `INLINE` the in-range lookup inlined into the caller instead of its one out-of-line copy.
#[inline(always)]
#[allow(
    clippy::too_many_arguments,
    reason = "sum_raw's arguments plus the acc check"
)]
pub(crate) fn sum_raw_with<
    L: Layout<C>,
    Fm: FormImpl,
    M: EdgeMode,
    K: Counter,
    A: Fn() -> Result<(), Error>,
    const C: usize,
    const INLINE: bool,
>(
    layout: &L,
    r: &Rect<i64>,
    f: u32,
    form: Fm,
    mode: M,
    acc: A,
    k: &mut K,
) -> Result<BoxSum<WideOf<L, C>, C>, Error> {
    if r.x1 < r.x0 || r.y1 < r.y0 {
        return Err(Error::InvertedBox);
    }
    let mut out = BoxSum {
        sums: [<WideOf<L, C> as Wide>::ZERO; C],
        frac_bits: f,
        width_raw: width_u64(r.x0, r.x1),
        height_raw: width_u64(r.y0, r.y1),
    };
    if out.width_raw == 0 || out.height_raw == 0 {
        return Ok(out);
    }
    let kind = mode.kind();
    let px = place_axis(kind, r.x0, r.x1, layout.width(), f)?;
    let py = place_axis(kind, r.y0, r.y1, layout.height(), f)?;
    match (px, py) {
        (AxisPlan::Empty, _) | (_, AxisPlan::Empty) => {}
        // RepeatWithinPeriod takes an in-range box through `split::sum_within` too (its one
        // piece): one lookup call site, one copy of the checks (Stable + Repeat firmware on the
        // Cortex-M4: docs/firmware.md).
        (AxisPlan::InRange(x0, x1), AxisPlan::InRange(y0, y1)) if !M::WITHIN_PERIOD => {
            let b = RawBox { x0, y0, x1, y1 };
            let placed = Rect::new(x0, y0, x1, y1);
            check_modular(layout, &placed, f, form.modular_headroom_bits(f))?;
            acc()?;
            out.sums = if INLINE {
                in_range_wide_inline(layout, &b, f, form, k)?
            } else {
                in_range_wide(layout, &b, f, form, k)?
            };
        }
        (px, py) => {
            if M::WITHIN_PERIOD {
                // Only a box crossing the edge can be longer than a period (one placed in range
                // never is, so the test never refuses it).
                refuse_longer_than_period(layout, out.width_raw, out.height_raw, f)?;
            }
            check_modular(layout, r, f, form.modular_headroom_bits(f))?;
            acc()?;
            out.sums = if M::WITHIN_PERIOD {
                split::sum_within(layout, px, py, f, form, k)?
            } else {
                split::sum(layout, px, py, f, form, mode, k)?
            };
        }
    }
    Ok(out)
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions,
    reason = "tests: a panic is a failed test"
)]
mod tests;
