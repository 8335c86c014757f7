//! Texel and table-entry types.
//!
//! A [`Texel`] is an unsigned integer sample (`u8`, `u16`). An [`Entry`] is the unsigned integer a
//! table stores per channel (`u16`, `u32`, `u64`); each entry type names a signed accumulator
//! ([`Entry::Acc`]) exactly as wide as the width analysis needs: `i32` for `u16`, `i64` for
//! `u32`, and `i128` only for `u64` entries.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use core::ops::{Add, Mul, Shl, Sub};

/// An unsigned texel sample: `u8` or `u16`. Sealed: the builds' width proofs rely on every
/// texel being at most `2^BITS - 1`, which a foreign implementation could break.
pub trait Texel: Copy + 'static + sealed::TexelSealed {
    /// Bits per texel; the largest texel is `2^BITS - 1`.
    const BITS: u32;
    /// The texel as `u16` (lossless: texels have at most 16 bits).
    fn to_u16(self) -> u16;
    /// The texel of value `v`: exact for `v <= 2^BITS - 1`; larger values saturate to
    /// `2^BITS - 1`. (What a build that writes texels, such as a pyramid's rounded box averages,
    /// needs: the inverse of [`Texel::to_u16`] on the texel range.)
    fn from_u16_clamped(v: u16) -> Self;
}

impl sealed::TexelSealed for u8 {}
impl sealed::TexelSealed for u16 {}

impl Texel for u8 {
    const BITS: u32 = 8;
    #[inline(always)]
    fn to_u16(self) -> u16 {
        u16::from(self)
    }
    #[inline(always)]
    fn from_u16_clamped(v: u16) -> Self {
        u8::try_from(v).unwrap_or(u8::MAX)
    }
}

impl Texel for u16 {
    const BITS: u32 = 16;
    #[inline(always)]
    fn to_u16(self) -> u16 {
        self
    }
    #[inline(always)]
    fn from_u16_clamped(v: u16) -> Self {
        v
    }
}

/// The signed accumulator of the lookups: `i32` for `u16` tables, `i64` for `u32` tables,
/// `i128` only for `u64` tables (where the width proof shows 64 bits cannot hold an
/// intermediate). Sealed: the crate's width proofs are written for these three.
///
/// Only the ring operations are used; the width analysis proves before each lookup that no
/// intermediate leaves the type's range (see `docs/design.md`, "Lookup widths").
pub trait Acc:
    Copy
    + Ord
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Shl<u32, Output = Self>
    + sealed::Sealed
    + 'static
{
    /// Value bits (the sign bit excluded): 31, 63 or 127.
    const VALUE_BITS: u32;
    /// Zero.
    const ZERO: Self;
    /// The unsigned word a non-negative result is returned in ([`BoxSum`](crate::BoxSum)'s
    /// sums and means): `u64` for `i32` and `i64`, `u128` for `i128`.
    type Wide: Wide;
    /// A small non-negative integer (a fraction numerator, at most `2^24`).
    fn from_u32(v: u32) -> Self;
    /// The value as [`Acc::Wide`], or `None` if it is negative.
    fn to_wide(self) -> Option<Self::Wide>;
    /// Wrapping addition (used only where the width proof rules out wrapping, or where the
    /// arithmetic is modular on purpose, or on corrupt lent storage, where it keeps the no-panic
    /// guarantee).
    fn wrapping_add(self, o: Self) -> Self;
    /// Wrapping subtraction (see [`Acc::wrapping_add`]).
    fn wrapping_sub(self, o: Self) -> Self;
    /// Wrapping multiplication (see [`Acc::wrapping_add`]).
    fn wrapping_mul(self, o: Self) -> Self;
    /// Wrapping left shift by `s < VALUE_BITS` (see [`Acc::wrapping_add`]).
    fn wrapping_shl(self, s: u32) -> Self;
    /// The low `k` bits, as a non-negative value (`k` below the type's width).
    fn low_bits(self, k: u32) -> Self;
}

macro_rules! impl_acc {
    ($t:ty, $vb:expr, $wide:ty) => {
        impl sealed::Sealed for $t {}
        impl Acc for $t {
            const VALUE_BITS: u32 = $vb;
            const ZERO: Self = 0;
            type Wide = $wide;
            #[inline(always)]
            #[allow(
                clippy::as_conversions,
                reason = "v <= 2^24 by the trait's contract (a fraction numerator, F <= MAX_FRAC_BITS \
                          = 24), which i32 holds; lossless into i64 and i128"
            )]
            fn from_u32(v: u32) -> Self {
                v as $t
            }
            #[inline(always)]
            fn to_wide(self) -> Option<$wide> {
                // `None` exactly when negative; a non-negative value always fits the unsigned
                // word of the same or twice the width.
                <$wide>::try_from(self).ok()
            }
            #[inline(always)]
            fn wrapping_add(self, o: Self) -> Self {
                <$t>::wrapping_add(self, o)
            }
            #[inline(always)]
            fn wrapping_sub(self, o: Self) -> Self {
                <$t>::wrapping_sub(self, o)
            }
            #[inline(always)]
            fn wrapping_mul(self, o: Self) -> Self {
                <$t>::wrapping_mul(self, o)
            }
            #[inline(always)]
            fn wrapping_shl(self, s: u32) -> Self {
                <$t>::wrapping_shl(self, s)
            }
            #[inline(always)]
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "BITS - 1: BITS >= 32; (1 << k) - 1: k < BITS - 1, so 1 << k is positive and \
                          in range and subtracting 1 leaves it >= 0"
            )]
            fn low_bits(self, k: u32) -> Self {
                if k >= <$t>::BITS - 1 {
                    self
                } else {
                    self & ((1 << k) - 1)
                }
            }
        }
    };
}

impl_acc!(i32, 31, u64);
impl_acc!(i64, 63, u64);
impl_acc!(i128, 127, u128);

pub use crate::wide::Wide;

pub(crate) mod sealed {
    /// Keeps the numeric traits closed: the width proofs cover exactly the implemented types.
    pub trait Sealed {}
    /// Keeps [`super::Texel`] closed.
    pub trait TexelSealed {}
}

/// An unsigned table entry.
pub trait Entry:
    Copy
    + Default
    + Ord
    + Add<Output = Self>
    + Sub<Output = Self>
    + From<u16>
    + sealed::Sealed
    + 'static
{
    /// Bits per entry and channel.
    const BITS: u32;
    /// The zero entry.
    const ZERO: Self;
    /// The signed accumulator the lookups use for this entry type.
    type Acc: Acc;
    /// Checked addition (the data-dependent build).
    fn checked_add(self, other: Self) -> Option<Self>;
    /// Checked subtraction (validating lent tables).
    fn checked_sub(self, other: Self) -> Option<Self>;
    /// The largest texel of `texel_bits` bits, `2^b - 1`, saturating at the entry's maximum.
    fn max_texel(texel_bits: u32) -> Self;
    /// The entry in the accumulator type (always lossless).
    fn to_acc(self) -> Self::Acc;
    /// The entry as `u128` (always lossless).
    fn to_u128(self) -> u128;
    /// The low bits of a `u64` (a packed field of at most `BITS` bits).
    fn from_u64_truncating(v: u64) -> Self;
    /// The entry as `u64` (lossless for `u16`, `u32`, `u64`).
    fn to_u64(self) -> u64;
    /// Wrapping subtraction (modular layouts; elsewhere only where no wrap is possible).
    fn wrapping_sub(self, o: Self) -> Self;
    /// Wrapping addition (modular layouts).
    fn wrapping_add(self, o: Self) -> Self;
    /// The low `k` bits (`k <= BITS`).
    fn low_bits(self, k: u32) -> Self;
}

macro_rules! impl_entry {
    ($t:ty, $acc:ty) => {
        impl sealed::Sealed for $t {}
        impl Entry for $t {
            const BITS: u32 = <$t>::BITS;
            const ZERO: Self = 0;
            type Acc = $acc;
            #[inline(always)]
            fn checked_add(self, other: Self) -> Option<Self> {
                <$t>::checked_add(self, other)
            }
            #[inline(always)]
            fn checked_sub(self, other: Self) -> Option<Self> {
                <$t>::checked_sub(self, other)
            }
            #[inline(always)]
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "texel_bits < BITS here, so 1 << texel_bits is in range and >= 1"
            )]
            fn max_texel(texel_bits: u32) -> Self {
                if texel_bits >= <$t>::BITS {
                    <$t>::MAX
                } else {
                    (1 << texel_bits) - 1
                }
            }
            #[inline(always)]
            fn to_acc(self) -> $acc {
                <$acc>::from(self)
            }
            #[inline(always)]
            fn to_u128(self) -> u128 {
                u128::from(self)
            }
            #[inline(always)]
            #[allow(
                clippy::as_conversions,
                reason = "truncation to the low BITS bits is this function's documented purpose"
            )]
            fn from_u64_truncating(v: u64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn to_u64(self) -> u64 {
                u64::from(self)
            }
            #[inline(always)]
            fn wrapping_sub(self, o: Self) -> Self {
                <$t>::wrapping_sub(self, o)
            }
            #[inline(always)]
            fn wrapping_add(self, o: Self) -> Self {
                <$t>::wrapping_add(self, o)
            }
            #[inline(always)]
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "k < BITS here, so 1 << k is in range and >= 1"
            )]
            fn low_bits(self, k: u32) -> Self {
                if k >= <$t>::BITS {
                    self
                } else {
                    self & ((1 << k) - 1)
                }
            }
        }
    };
}

impl_entry!(u16, i32);
impl_entry!(u32, i64);
impl_entry!(u64, i128);
