//! The filters the SAT is compared with (Heckbert 1986, "Comparison of Prefiltering Methods";
//! Du and Wan, "Dipmap"), in the same fixed-point arithmetic and with the same cost counters.
//!
//! Each filter is its own module behind its own cargo feature, so a firmware build compiles in
//! only what its scene needs:
//!
//! | feature | module | filter |
//! |---|---|---|
//! | `filter-point` | `point` | nearest texel |
//! | `filter-mip` | `mip` | box-filtered 2x2 pyramid: point-sampled and trilinear (Williams) |
//! | `filter-rip` | `rip` | 4-D pyramid (ripmap): u and v scaled independently, 4 bilinear probes |
//! | `filter-dip` | `dip` | row and column pyramids (dipmap), bilinear and trilinear variants |
//! | `filter-tent` | `tent` | repeated integration of order 2: the triangle filter |
//! | `filter-variance` | `variance` | variance over a box from SATs of values and squares |
//!
//! (`filters` enables them all.) Every filter takes the footprint as the rectangle that bounds it
//! ([`crate::Rect`] with fixed-point corners, as the box lookups do), a boundary mode, and a
//! [`crate::Counter`]; it returns a [`Sample`]: per channel the filtered value in texel units with
//! [`OUT_FRAC_BITS`] fractional bits. Costs are counted as Crow counts them (§2.2): texel or table
//! reads, multiplies, divides, additive operations; level selection and addressing belong to the
//! address unit and are not counted (Crow: "the necessary computation appears small next to the
//! texture intensity calculation").
//!
//! ## Widths and panics
//!
//! Arithmetic is as wide as each filter's proof needs, no wider. For `u8`/`u16` texels and
//! `u16`/`u32` tables everything runs in 32- and 64-bit integers: the footprint (an exact `i64`
//! centre, `u64` sides, whatever the `i64` corners), the level choice (`log2_fixed`, one
//! `32 x 32 -> 64` multiply per fraction bit), the positions and weights, every lerp (`u64`, with
//! each filter's bound on the result), and the variance's rounded quotient (`variance`: 64-bit
//! words up to `2^62` raw area units, [`crate::Error::TooWide`] above). 128-bit arithmetic is
//! left where the quantities are 128-bit: the order-2 tables of `tent` (their docs say why) and
//! the variance over `u64` tables, whose box sums are `u128` words. No filter panics on any
//! input, lent storage included: every index is checked (`get`, iterators) or proven in range,
//! every division is by a value known non-zero, and a result that cannot be represented is a
//! typed [`crate::Error`].
//!
//! The filter modules deny clippy's `indexing_slicing`, `arithmetic_side_effects`,
//! `unwrap_used`, `expect_used`, `panic` and `as_conversions`: each plain operation or cast left
//! carries an `allow` whose reason names the check or bound that makes it exact. Per-channel cost
//! counts are compile-time constants, so a channel count whose count would not fit the
//! counter's `u32` stops the build instead of wrapping.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

#[cfg(any(
    feature = "filter-mip",
    feature = "filter-rip",
    feature = "filter-dip",
    feature = "filter-tent"
))]
#[cfg_attr(
    docsrs,
    doc(cfg(any(
        feature = "filter-mip",
        feature = "filter-rip",
        feature = "filter-dip",
        feature = "filter-tent"
    )))
)]
pub mod level;

#[cfg(any(feature = "filter-mip", feature = "filter-rip", feature = "filter-dip"))]
pub(crate) mod pyramid;

#[cfg(feature = "filter-point")]
#[cfg_attr(docsrs, doc(cfg(feature = "filter-point")))]
pub mod point;

#[cfg(feature = "filter-mip")]
#[cfg_attr(docsrs, doc(cfg(feature = "filter-mip")))]
pub mod mip;

#[cfg(feature = "filter-rip")]
#[cfg_attr(docsrs, doc(cfg(feature = "filter-rip")))]
pub mod rip;

#[cfg(feature = "filter-dip")]
#[cfg_attr(docsrs, doc(cfg(feature = "filter-dip")))]
pub mod dip;

#[cfg(feature = "filter-tent")]
#[cfg_attr(docsrs, doc(cfg(feature = "filter-tent")))]
pub mod tent;

#[cfg(feature = "filter-variance")]
#[cfg_attr(docsrs, doc(cfg(feature = "filter-variance")))]
pub mod variance;

/// The per-channel cost counts of the filters: [`crate::cost::per_channel`] (a compile-time
/// constant at each use; a channel count whose product does not fit `u32` stops the build).
#[cfg(any(
    feature = "filter-point",
    feature = "filter-mip",
    feature = "filter-rip",
    feature = "filter-dip",
    feature = "filter-tent",
    feature = "filter-variance"
))]
pub(crate) use crate::cost::per_channel;

/// `n` as a `u64`: lossless, as `usize` is at most 64 bits wide (asserted at compile time
/// below); `From` does not exist for it and is not `const`.
#[cfg(any(
    feature = "filter-mip",
    feature = "filter-rip",
    feature = "filter-dip",
    feature = "filter-tent",
    feature = "filter-variance"
))]
#[inline(always)]
pub(crate) const fn u64_from_usize(n: usize) -> u64 {
    const _: () = assert!(usize::BITS <= u64::BITS);
    #[allow(
        clippy::as_conversions,
        reason = "usize::BITS <= 64 (asserted above): lossless"
    )]
    let v = n as u64;
    v
}

/// Fractional bits of every filter's output value.
pub const OUT_FRAC_BITS: u32 = 16;

/// A filtered value per channel: `value * 2^OUT_FRAC_BITS`, rounded as the filter documents.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample<const C: usize> {
    /// Per channel, the value in texel units times `2^OUT_FRAC_BITS`.
    pub values: [u64; C],
}

impl<const C: usize> Sample<C> {
    /// Channel `c` as `f64` texel units (host-side convenience; `None` past the channels).
    pub fn value_f64(&self, c: usize) -> Option<f64> {
        self.values.get(c).map(|&v| {
            #[allow(
                clippy::as_conversions,
                reason = "u64 -> f64 has no From: rounds to nearest above 2^53, which this \
                              host-side convenience accepts"
            )]
            let v = v as f64;
            v / f64::from(1u32 << OUT_FRAC_BITS)
        })
    }
}
