//! # texsat — exact summed-area tables for firmware and hardware models
//!
//! A reference implementation of Crow's summed-area table (SAT, SIGGRAPH 1984) in integer and
//! fixed-point arithmetic, for `no_std` firmware, FPGA models and the host test benches that
//! check them.
//!
//! * [`Sat::build`] turns a texture ([`Texture`]: `u8` or `u16` texels, 1–4 interleaved channels,
//!   any row stride) into a table in caller-provided storage (`&mut [E]`, `E` = `u16`, `u32` or
//!   `u64`) with Crow's two additions per entry (§3.0). Before it writes anything it proves that
//!   no entry can overflow ([`width`]); [`Sat::build_checked`] accepts any table whose *actual*
//!   values fit. [`RowStreamBuilder`] builds from one row at a time, bit-identically.
//! * [`Sat::box_sum_int`] sums a box with integer corners from 4 reads; [`Sat::box_sum`] sums a
//!   box with fixed-point corners (any [`fixed`] type, `F` fractional bits) from 16 reads, *exactly*
//!   (the result is an integer multiple of `2^-2F`). Two formulations: [`Paper`] (Crow §2.1:
//!   bilinear interpolation at each corner) and [`Stable`] (differences first; multiplier operands
//!   bounded by the box's edge strips). [`Sat::box_mean_shortcut`] is Crow's 4-read shortcut for
//!   large footprints with a proven error bound.
//! * Boundary modes ([`Border`], [`ClampToEdge`], [`Repeat`], [`MirroredRepeat`], Crow §2.4, and
//!   [`RepeatWithinPeriod`] for a plan's boxes at most the texture) are zero-sized type
//!   parameters: a build that uses one mode compiles no code for the others.
//! * Every lookup takes a [`Counter`]: [`NoCount`] compiles away, [`Tally`] counts reads,
//!   multiplies, divides and additive operations the way Crow §2.2 counts them.
//!
//! Conventions (see `docs/design.md`): x to the right, y down; texel `(i, j)` covers
//! `[i, i+1) x [j, j+1)`; a box is `[x0, x1) x [y0, y1)`. The stored table is *inclusive*:
//! entry `(i, j)` holds the sum of texels `(i', j')` with `i' <= i`, `j' <= j`, so the corner
//! function `S(x, y)` (the integral over `[0, x) x [0, y)`) is entry `(x-1, y-1)` and zero on the
//! row `y = 0` and column `x = 0`, which cost no read.
//!
//! ```
//! use texsat::{Sat, Texture, Rect, Paper, Border, NoCount, Tally};
//! use fixed::types::I24F8;
//!
//! let texels: [u8; 12] = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]; // 4 x 3
//! let texture = Texture::<u8>::new(&texels, 4, 3).unwrap();
//! let mut storage = [0u32; 12];
//! let sat = Sat::build(&texture, &mut storage).unwrap();
//!
//! // Integer corners: the 2 x 2 box at (1, 1): 6 + 7 + 10 + 11.
//! let sum = sat.box_sum_int(&Rect::new(1, 1, 3, 3), Border, &mut NoCount).unwrap();
//! assert_eq!(sum.sum(), 34);
//!
//! // Fractional corners: [0.5, 1.5) x [0, 1) covers half of texel 1 and half of texel 2.
//! let r = Rect::new(I24F8::from_num(0.5), I24F8::ZERO, I24F8::from_num(1.5), I24F8::ONE);
//! let mut tally = Tally::new();
//! let s = sat.box_sum(&r, Paper, Border, &mut tally).unwrap();
//! assert_eq!(s.scaled_sum(0), (1 + 2) * 128 * 256); // (0.5 * 1 + 0.5 * 2) * 2^16
//! assert_eq!(s.mean_rounded(0, 1, &mut tally).unwrap(), 3); // mean 1.5 = 3 / 2^1
//! ```
#![no_std]
// No `unsafe` anywhere, except the vectorized build rows behind the `simd` feature, which live in
// two modules (`src/simd.rs` for x86-64, `src/dsp.rs` for ARMv7E-M) and the slice casts both
// share (`src/cast.rs`), each with its safety argument; denied everywhere else.
#![cfg_attr(not(feature = "simd"), forbid(unsafe_code))]
#![cfg_attr(feature = "simd", deny(unsafe_code))]
// docs.rs (and `RUSTDOCFLAGS="--cfg docsrs" cargo +nightly doc --all-features`) shows which
// cargo feature each gated item needs.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]
// No panic path and no silent arithmetic (docs/guarantees.md): every index, arithmetic
// operation, unwrap and `as` conversion in the core is either checked, or carries an `allow`
// whose `reason` states the proof that it cannot panic, wrap or truncate. (Each module also
// denies them itself; test modules allow them.)
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

#[cfg(all(feature = "simd", any(target_arch = "x86_64", texsat_armv7em)))]
mod cast;
pub mod cost;
mod div;
#[cfg(all(feature = "simd", texsat_armv7em))]
mod dsp;
pub mod edge;
mod error;
pub mod filters;
pub mod layouts;
pub mod lookup;
pub mod plan;
mod rect;
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
mod simd;
pub mod table;
pub mod texel;
mod texture;
pub mod wide;
pub mod width;

pub use cost::{Counter, NoCount, Region, Tally};
pub use edge::{
    Border, ClampToEdge, EdgeKind, EdgeMode, MirroredRepeat, Repeat, RepeatWithinPeriod,
};
pub use error::{Error, Quantity};
pub use layouts::Layout;
pub use lookup::{
    BoxLookup, BoxSum, Form, FormKind, Paper, Shortcut, ShortcutMean, Stable, WideOf,
};
pub use rect::{Coord, FracBits, Rect};
pub use table::{RowStreamBuilder, Sat};
pub use texel::{Acc, Entry, Texel};
pub use texture::Texture;
pub use wide::Wide;

/// The build kernel in use: `"avx512vnni"`, `"avx2"` or `"sse2"` on x86-64 with the `simd`
/// feature (the widest this CPU runs, detected once at run time), `"portable"` otherwise.
pub fn build_kernel() -> &'static str {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    {
        simd::kernel_name()
    }
    #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
    {
        "portable"
    }
}

/// The default corner type: `F = 8` fractional bits, like a GPU's sub-texel precision
/// (`fixed::types::I24F8`, range about +-8.4 million texels). Any `fixed` type whose raw bits fit
/// `i64` works; its `FRAC_NBITS` is the `F` of the lookup.
pub type DefaultCoord = fixed::types::I24F8;

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
