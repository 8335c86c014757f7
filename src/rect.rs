//! Boxes and their corner coordinates.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::error::Error;
use fixed::traits::Fixed;

/// The box `[x0, x1) x [y0, y1)` in texel units (x to the right, y down).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rect<T> {
    /// Left edge (inclusive).
    pub x0: T,
    /// Top edge (inclusive).
    pub y0: T,
    /// Right edge (exclusive).
    pub x1: T,
    /// Bottom edge (exclusive).
    pub y1: T,
}

impl<T> Rect<T> {
    /// The box `[x0, x1) x [y0, y1)`.
    pub const fn new(x0: T, y0: T, x1: T, y1: T) -> Self {
        Rect { x0, y0, x1, y1 }
    }
}

/// A fixed-point corner coordinate: any [`fixed`] type whose raw bits fit `i64`
/// (`FixedI8`..`FixedI64`, `FixedU8`..`FixedU32`). `F = FRAC_BITS`; the value is `raw / 2^F`.
pub trait Coord: Copy {
    /// Fractional bits `F`.
    const FRAC_BITS: u32;
    /// The raw integer `value * 2^F`.
    fn raw(self) -> i64;
}

impl<X: Fixed> Coord for X
where
    X::Bits: Into<i64>,
{
    const FRAC_BITS: u32 = X::FRAC_NBITS;
    #[inline(always)]
    fn raw(self) -> i64 {
        self.to_bits().into()
    }
}

impl<X: Fixed> Rect<X> {
    /// Converts float corners to the fixed-point type `X`, rounding to nearest. NaN or infinite
    /// input is [`Error::NotFinite`]; a value outside `X`'s range is
    /// [`Error::CoordinateOutOfRange`].
    pub fn from_f64(x0: f64, y0: f64, x1: f64, y1: f64) -> Result<Self, Error> {
        let conv = |v: f64| -> Result<X, Error> {
            if !v.is_finite() {
                return Err(Error::NotFinite);
            }
            X::checked_from_num(v).ok_or(Error::CoordinateOutOfRange)
        };
        Ok(Rect::new(conv(x0)?, conv(y0)?, conv(x1)?, conv(y1)?))
    }

    /// [`Rect::from_f64`] for `f32` corners.
    pub fn from_f32(x0: f32, y0: f32, x1: f32, y1: f32) -> Result<Self, Error> {
        Self::from_f64(f64::from(x0), f64::from(y0), f64::from(x1), f64::from(y1))
    }
}

/// The fractional bits `F` of a lookup's corners, checked once: `0 <= F <=`
/// [`MAX_FRAC_BITS`](crate::width::MAX_FRAC_BITS).
///
/// The lookups take corners as raw fixed-point integers (`value * 2^F`, [`Rect<i64>`]) with
/// their `F` as a value ([`crate::BoxLookup::box_sum_raw`]), so one compiled lookup serves every
/// `F`; the `fixed`-typed API ([`crate::BoxLookup::box_sum`]) is a thin wrapper that takes `F`
/// from the type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FracBits(u32);

impl FracBits {
    /// Integer corners (`F = 0`).
    pub const ZERO: FracBits = FracBits(0);

    /// `F`, refused with [`Error::FracBitsUnsupported`] above
    /// [`MAX_FRAC_BITS`](crate::width::MAX_FRAC_BITS).
    pub const fn new(frac_bits: u32) -> Result<Self, Error> {
        if frac_bits > crate::width::MAX_FRAC_BITS {
            Err(Error::FracBitsUnsupported {
                frac_bits,
                max: crate::width::MAX_FRAC_BITS,
            })
        } else {
            Ok(FracBits(frac_bits))
        }
    }

    /// `F` of the coordinate type `X`.
    pub const fn of<X: Coord>() -> Result<Self, Error> {
        Self::new(X::FRAC_BITS)
    }

    /// `F`.
    pub const fn get(self) -> u32 {
        self.0
    }
}

impl<X: Coord> Rect<X> {
    /// The corners as raw integers (`value * 2^F`), for [`crate::BoxLookup::box_sum_raw`].
    #[inline(always)]
    pub fn to_raw(&self) -> Rect<i64> {
        Rect::new(self.x0.raw(), self.y0.raw(), self.x1.raw(), self.y1.raw())
    }
}

impl Rect<i32> {
    /// The corners as `i64` (integer corners are raw coordinates with `F = 0`).
    #[inline(always)]
    pub fn to_raw_int(&self) -> Rect<i64> {
        Rect::new(
            i64::from(self.x0),
            i64::from(self.y0),
            i64::from(self.x1),
            i64::from(self.y1),
        )
    }
}

/// (Crate-internal: public in a private module, so unnameable outside.) A box in raw fixed-point units (`value * 2^F`) inside
/// `[0, w 2^F] x [0, h 2^F]` once placed (at most `2^31 * 2^24`, far inside `i64`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawBox {
    pub x0: i64,
    pub y0: i64,
    pub x1: i64,
    pub y1: i64,
}
