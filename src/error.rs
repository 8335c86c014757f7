//! The one error type of the crate: every refusal says what was wrong, with the numbers.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use core::fmt;

/// What a width error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Quantity {
    /// A table entry (the largest is the whole-texture sum).
    Entry,
    /// The accumulator of a lookup (corner values scaled by `2^2F`, or sums over whole periods).
    LookupAccumulator,
    /// The mean's numerator, the sum scaled by the requested output fraction bits.
    MeanNumerator,
    /// A box sum on a modular layout: it must stay below `2^k` to be recovered exactly.
    ModularBox,
    /// A field of a packed layout.
    Field,
    /// The rounded mean itself, for [`crate::BoxSum::mean_rounded_u32`]: it must fit 32 bits.
    Mean,
    /// The mean's divisor, the box's area in units of `2^-2F`, for
    /// [`crate::BoxSum::mean_rounded_u32`]: it must fit 32 bits (one hardware divide step).
    MeanArea,
}

/// Why a build or a lookup was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// Width or height is zero.
    EmptyTexture,
    /// Too large to handle: a side above `2^31 - 1` texels (coordinates must fit `i32`-like
    /// arithmetic), or a size derived from the sides (entries, storage words or bits, scratch)
    /// that overflows `u64` or this target's `usize`.
    TextureTooLarge {
        /// the offending side (for a derived size, the side it was computed from)
        dimension: usize,
    },
    /// The row stride (in elements) is shorter than `width * channels`.
    StrideTooSmall {
        /// elements per row given
        stride: usize,
        /// `width * channels`
        needed: usize,
    },
    /// The texel slice is shorter than `stride * (height - 1) + width * channels`.
    TextureDataTooShort {
        /// elements needed
        needed: usize,
        /// elements given
        got: usize,
    },
    /// The table storage is shorter than `width * height * channels` entries.
    StorageTooSmall {
        /// entries needed
        needed: usize,
        /// entries given
        got: usize,
    },
    /// A quantity needs more bits than its type has. Carries both numbers.
    TooWide {
        /// which quantity
        what: Quantity,
        /// bits the worst case (or the actual data) needs; where that number is itself past
        /// 64-bit arithmetic (the sum of a box over about 2^64 texels on the split path, the
        /// modular bound of a box of more than 2^64 cells) it is 65: a lower bound, still above
        /// every word's bits, and enough to refuse
        bits_needed: u32,
        /// bits the chosen type holds
        bits_available: u32,
    },
    /// The fixed-point corner type has more fractional bits than the lookups support.
    FracBitsUnsupported {
        /// `F` of the corner type
        frac_bits: u32,
        /// the largest `F` supported
        max: u32,
    },
    /// `x1 < x0` or `y1 < y0`.
    InvertedBox,
    /// The box has zero area, so it has no mean (its sum is 0).
    ZeroArea,
    /// An integer-corner box reaches outside the coordinate range the mode supports.
    CoordinateOutOfRange,
    /// A float coordinate is NaN or infinite.
    NotFinite,
    /// A table given to [`crate::Sat::from_table`] is not the SAT of any texture with the stated
    /// texel width: the texel it implies at `(x, y)` (channel `channel`) is negative or too large.
    InvalidTable {
        /// column of the offending texel
        x: usize,
        /// row of the offending texel
        y: usize,
        /// channel of the offending texel
        channel: usize,
    },
    /// A streamed row has the wrong number of elements.
    RowLength {
        /// `width * channels`
        expected: usize,
        /// elements given
        got: usize,
    },
    /// More rows were pushed than the texture has.
    TooManyRows,
    /// The streaming build was finished before every row arrived.
    MissingRows {
        /// rows pushed
        got: usize,
        /// rows expected
        expected: usize,
    },
    /// The channel index is not below the channel count.
    NoSuchChannel,
    /// Tile levels must ascend, each a multiple of the one before, at least 2, and at most
    /// [`crate::layouts::MAX_LEVELS`] per axis.
    InvalidLevels,
    /// A modular layout's `k` must be at least the texel bits and at most the value type's bits.
    InvalidModulus {
        /// `k` given
        bits: u32,
    },
    /// A lookup on lent storage (a table or layout wrapped without full validation, such as
    /// [`crate::layouts::Tiled::from_words`]) produced a negative box sum: the storage is
    /// corrupt. Valid storage never gives this.
    CorruptStorage,
    /// Texel widths must be 1 to 16 bits.
    InvalidTexelBits {
        /// the width given
        bits: u32,
    },
    /// No candidate table fits the scene's facts (a word for its values and accumulator, and
    /// its read bound): see [`crate::plan::Plan::for_scene`].
    NoPlan,
    /// A box outside the facts its plan was made for ([`crate::plan::Plan::check_box`]), or
    /// longer than a period under [`crate::RepeatWithinPeriod`] (the lookups).
    OutsidePlan {
        /// Which fact it breaks.
        limit: crate::plan::PlanLimit,
    },
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Quantity::Entry => "table entry",
            Quantity::LookupAccumulator => "lookup accumulator",
            Quantity::MeanNumerator => "mean numerator",
            Quantity::ModularBox => "box sum on the modular layout",
            Quantity::Field => "packed field",
            Quantity::Mean => "32-bit mean",
            Quantity::MeanArea => "32-bit mean's area",
        })
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::EmptyTexture => write!(f, "texture has zero width or height"),
            Error::TextureTooLarge { dimension } => {
                write!(
                    f,
                    "texture too large at dimension {dimension}: a side above 2^31 - 1, or a \
                     storage size that overflows this target's address space"
                )
            }
            Error::StrideTooSmall { stride, needed } => write!(
                f,
                "row stride {stride} is shorter than width x channels = {needed}"
            ),
            Error::TextureDataTooShort { needed, got } => {
                write!(f, "texture data has {got} elements, needs {needed}")
            }
            Error::StorageTooSmall { needed, got } => {
                write!(f, "table storage has {got} entries, needs {needed}")
            }
            Error::TooWide {
                what,
                bits_needed,
                bits_available,
            } => write!(
                f,
                "{what} needs {bits_needed} bits but only {bits_available} are available"
            ),
            Error::FracBitsUnsupported { frac_bits, max } => write!(
                f,
                "corner type has {frac_bits} fractional bits; at most {max} are supported"
            ),
            Error::InvertedBox => write!(f, "box is inverted (x1 < x0 or y1 < y0)"),
            Error::ZeroArea => write!(f, "box has zero area, so it has no mean"),
            Error::CoordinateOutOfRange => write!(f, "box coordinate out of the supported range"),
            Error::NotFinite => write!(f, "coordinate is NaN or infinite"),
            Error::InvalidTable { x, y, channel } => write!(
                f,
                "table is not a summed-area table: texel ({x}, {y}) channel {channel} would be out of range"
            ),
            Error::RowLength { expected, got } => {
                write!(f, "row has {got} elements, expected {expected}")
            }
            Error::TooManyRows => write!(f, "more rows pushed than the texture has"),
            Error::MissingRows { got, expected } => {
                write!(f, "build finished after {got} of {expected} rows")
            }
            Error::NoSuchChannel => write!(f, "channel index out of range"),
            Error::InvalidLevels => write!(
                f,
                "tile levels must ascend, each a multiple of the previous, at least 2, at most 4 per axis"
            ),
            Error::InvalidModulus { bits } => write!(
                f,
                "modular width {bits} must be at least the texel bits and at most the value type's bits"
            ),
            Error::CorruptStorage => write!(
                f,
                "lookup gave a negative box sum: the lent table storage is corrupt"
            ),
            Error::InvalidTexelBits { bits } => {
                write!(f, "texel width {bits} bits is outside 1..=16")
            }
            Error::NoPlan => f.write_str(
                "no table fits the scene: no entry word holds its values and the lookup's \
                 accumulator within its read bound",
            ),
            Error::OutsidePlan { limit } => write!(f, "box outside the plan's facts: {limit}"),
        }
    }
}

impl core::error::Error for Error {}
