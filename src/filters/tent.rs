//! Repeated integration of order 2: the triangle (tent) filter over a rectangle (Heckbert 1986,
//! "Filtering by Repeated Integration"; Perlin 1985; Ferrari et al. 1986; survey section
//! "repeated integration filtering", row "repeated integration (order 2): 36,31; or 9,4").
//!
//! ## What is stored
//!
//! Per axis, with `t` the piecewise-constant texture line (texel `i` covers `[i, i+1)`), let
//! `S1(x) = integral_0^x t` (the SAT's corner function) and `S2(x) = integral_0^x S1`. At integer
//! points `S2` is a multiple of `1/2` (trapezoid rule, exact because `S1` is linear in each cell):
//!
//! `s(X) := 2 S2(X) = sum_{i < X} (2X - 2i - 1) t(i)`.
//!
//! The table stores the tensor product of this in x and y, `Q(X, Y) = 4 T2(X, Y)` with
//! `T2(X, Y) = integral_0^X integral_0^Y S(u, v) du dv` (`S` the corner function): an exact
//! integer, the least integer multiple of `T2`. `Q` is stored for the texture *padded with one
//! zero column and row*, `1 <= X <= w + 1`, `1 <= Y <= h + 1` (`Q(0, .) = Q(., 0) = 0` are not
//! stored and cost no read, as in the SAT). The padding gives the slopes the extended texture
//! needs outside: `S1(n) = S2(n + 1) - S2(n)`, `t(n - 1) = 2 (S2(n+1) - 2 S2(n) + S2(n-1))`.
//!
//! Build: per axis `W(X+1) = W(X) + 2 V(X) + t(X)`, `V(X+1) = V(X) + t(X)` (`V` the running
//! first integral): 3 additions per entry and axis (the doubling is a shift), 6 per entry in all.
//! Two additions per pass are not possible for an *exact* `Q`: the generating function of `s` is
//! `z (1 + z) / (1 - z)^2`, two integrators plus the trapezoid's `(1 + z)`. (Storing the plain
//! discrete double prefix sum `D(X) = sum (X - i) t(i)` would take 2 additions per axis, but
//! `s(X) = D(X) + D(X - 1)`, so every lookup point would need 4 reads instead of 1.) The running
//! column sums of the y pass live in the table's last row until that row is written, so the
//! build needs no scratch storage.
//!
//! ## The filter
//!
//! The footprint rectangle `[x0, x1) x [y0, y1)` gives the centre `c = (x0 + x1) / 2` and the
//! half-widths `a = (x1 - x0) / 2`, `b = (y1 - y0) / 2`. The triangle of half-width `a` is
//! `box(a) * box(a)` normalised, `K(u) = (a - |u - c|)+ / a^2`, and per axis
//! `integral t K = (S2(c + a) - 2 S2(c) + S2(c - a)) / a^2`. In 2-D the sample is the second
//! central difference of `T2` over the 3 x 3 points `(c + {-a, 0, a}, c' + {-b, 0, b})` with
//! weights `(1, -2, 1) x (1, -2, 1)`, divided by `a^2 b^2`:
//!
//! * [`TentTable::sample_int`]: integer centre and half-widths: 9 reads, 3 multiplies (`a^2`,
//!   `b^2`, `a^2 b^2`) and 1 divide per sample, 8 additive operations per channel — the survey's
//!   "9,4". The weights 2 and 4 are shifts.
//! * [`TentTable::sample`]: fixed-point corners (`F` fractional bits; the centre and half-widths
//!   then have `G = F + 1`). Paper-faithful: 9 bilinear interpolations of `Q` (Crow form, 4 reads
//!   and 3 multiplies each), then the same combination: 36 reads, 27 + 3 multiplies and 1 divide
//!   (the survey's "36,31"), 62 additive operations per channel.
//!   **Bilinear interpolation of `T2` is not exact**: `S2` is quadratic in every cell. Per axis
//!   `S2(i + α) = (1 - α^2) S2(i) + α^2 S2(i+1) + α (1 - α) S1(i)`, so the lerp overshoots by
//!   `α (1 - α) t(i) / 2`. The result's error against the exact filter is bounded by
//!   [`paper_error_bound`]: `m/4 (1/a^2 + 1/b^2 + 1/(2 a^2 b^2))` texel units (`m = 2^b - 1`);
//!   the separable part `m / (4 a^2)` is reached (tests). Results below zero are clamped to 0.
//! * [`TentTable::sample_exact`]: the exact filter for fixed-point corners. Per point,
//!   `Q_exact = L_x L_y Q - α(1-α) L_y Cy - β(1-β) L_x Rx + α(1-α) β(1-β) t` where `L` is the
//!   lerp, `Cy` the per-column order-2 integral in y ([`TentLines`]), `Rx` the per-row one in x,
//!   and `t` the texel of the point's cell. That is 9 reads per point (4 of `Q`, 2 of `Cy`, 2 of
//!   `Rx`, 1 texel): 81 reads per sample. Folding the fraction products out of the second
//!   differences: 27 (paper) + 6 (fraction products `α(1-α)`) + 12 (columns) + 12 (rows) + 12
//!   (texels) + 3 (`a^2 b^2`) = 72 multiplies and 1 divide. The result is exact before the
//!   final rounding: `round(value * 2^16)`, ties up.
//!
//! ## Boundary modes
//!
//! Every mode of [`crate::edge`] is exact, in bounded arithmetic. Per axis the extended
//! `2 S2_ext(X)` at an integer `X` is an integer combination of at most 3 stored values:
//!
//! * Border (zero outside): `0` for `X <= 0`; `s(X)` up to `n + 1`; beyond, linear:
//!   `(n + 1 - X) s(n) + (X - n) s(n + 1)`. Bilinear interpolation is exact there, so the paper
//!   form lerps cell `n` with an extended fraction (still 4 reads per point).
//! * ClampToEdge: `X^2 s(1)` for `X <= 0` (`s(1) = t(0)`); for `X = n + d > n`:
//!   `s(n) + d (s(n+1) - s(n)) + d^2 (s(n+1) - 2 s(n) + s(n-1))`.
//! * Repeat (`X = q n + r`): `s(r) + q s(n) + q (n (q - 1) + 2 r) / 2 * (s(n+1) - s(n))`.
//! * MirroredRepeat (`X = q 2n + r`): `s_ext(r) + (2n q^2 + 2 q r) (s(n+1) - s(n))` with
//!   `s_ext(r) = s(r)` for `r <= n`, `2 (r - n)(s(n+1) - s(n)) + s(2n - r)` above.
//!
//! These grow with `X`, so the centre is first moved by whole texels or periods to where the
//! weights stay small, which changes neither the exact nor the bilinear result: Border
//! footprints entirely outside return 0 with no reads; clamp footprints entirely left of 0
//! (right of `n`) move to touch the edge (`S2_ext` is one quadratic there); repeat and mirror
//! centres move into the first period (`S2_ext(x + P) - S2_ext(x)` is linear in `x`, which the
//! second difference annihilates; the corners are moved first, in `i64`, so that no sum of two
//! corners is formed before). Points outside the table then cost more reads and multiplies
//! than the survey's interior figures (counted as performed: one multiply per weight that is not
//! a power of two). All lookup arithmetic is checked in the entry type's accumulator (next
//! section); a footprint too large for it is [`Error::TooWide`] (`LookupAccumulator`, or
//! `MeanNumerator` for `a^2 b^2` past the accumulator), never a wrapped value.
//!
//! The mode's behaviour comes from the crate's one mapping, [`EdgeMode::kind`]: the lookups take
//! any `M: EdgeMode` and the extension formulas above match on the [`EdgeKind`] (the texel a
//! position shows is [`EdgeKind::texel_index`]).
//!
//! ## How wide the lookups compute
//!
//! The accumulator follows the entry type at compile time: [`TentEntry::Acc`] is `i64` for
//! `u32` entries and `i128` for `u64` and `u128` ones. The lookups are one generic
//! implementation over [`TentAcc`] (the checked operations they use, sealed), so the lookups of
//! a `u32` table, monomorphised, hold no 128-bit operation at all (the firmware link gate
//! proves it on its `u32` tent gates, `examples/firmware/link-gate.sh`), and its rounded
//! division is a 64-bit restoring division. The crate's rule (docs/wide-arithmetic.md): `u32`
//! tables compute in 64 bits, and only `u64`/`u128`-entry tables keep 128-bit arithmetic.
//!
//! Those need it: order-2 integrals take `u64` entries for any texture worth filtering (8-bit
//! 256 x 256 already needs 41 bits), and a lookup scales them further: by `s^2 = 2^(2G)`
//! (`G = F + 1`) in the paper form and by `s^4 = 2^(4G)` in the exact form, times
//! second-difference and extension weights. At `F = 8` a 41-bit entry times `2^36` is 77 bits
//! before any weight. An `i128` lookup checks every product and refuses (`LookupAccumulator`,
//! 128 bits needed) only where one overflows.
//!
//! **The width proof of `u32` tables.** An `i64` lookup proves its width *before it reads*:
//! once the footprint is placed (centres, extension weights) it bounds every intermediate it
//! is about to form, over every texture of the table's size and texel width, and refuses where
//! that bound passes 63 bits with [`Error::TooWide`] `{ what: LookupAccumulator, bits_needed,
//! bits_available: 63 }` (`bits_needed` the bound's bits; 65 where the bound itself passes 64
//! bits, a lower bound). So whether a `u32` table refuses a footprint for its width never
//! depends on the texels, and its answers equal the `u64` table's (tests). (The output
//! division can still refuse a rounded mean past 64 bits, `MeanNumerator`, for some texels: a
//! sub-texel paper-form footprint at large `F`, on `u64` tables alike.) The bound:
//!
//! * each stored value is bounded where it is read: per axis `sum_{i < min(X, n)} (2X - 2i - 1)
//!   = L_n(X) = k (2X - k)`, `k = min(X, n)`, so `Q(X, Y) <= m L_w(X) L_h(Y)` and a line
//!   table's `2 S2` at `X` is at most `m L_n(X)` (`m = 2^b - 1`; reached by the all-`m`
//!   texture);
//! * each axis of a point multiplies that by its mass: Crow's lerp `v0 s + (v1 - v0) α s` on
//!   non-negative values by `s max(L(i), L(i + 1))`, on signed ones by
//!   `s L(i) + α s (L(i) + L(i + 1))`; extension terms by `sum |w| L(index)`;
//! * the second difference `(1, -2, 1)` of non-negative values `V_p` by
//!   `max(2 V_1, V_0 + V_2)`, of signed ones `V_0 + 2 V_1 + V_2`: at most 8 in all;
//! * the exact form adds `P s^2` (`P` that bound of the paper numerator) to the line tables'
//!   and texels' corrections, `(X sa + Y sb) s + m sa sb` (`sa = sum |w_p| α_p(1 - α_p) s^2`).
//!
//! Before it, the normaliser `a^2 b^2` (half-widths in units `2^-G`) must be below `2^63`
//! (else `MeanNumerator`, `bits_needed = 2 bits(a) + 2 bits(b)`), and an extension weight
//! past `i64` (footprints reaching far outside under ClampToEdge, say) is `LookupAccumulator`
//! with 64 bits needed (a lower bound). Every `i64` operation stays checked as a safety net
//! (which a table, line table and texture of the same texture never reach).
//!
//! Which `(E, F)` a `u32` table answers, `E` = [`tent_entry_bits`], `Q_max < 2^E`, for
//! footprints inside the table (`0 <= x0 < x1 <= w`, likewise in y):
//!
//! | lookup | bound inside the table | answers every footprint inside if | e.g. `E = 32` (16-bit 13 x 13) | `E = 25` (8-bit 16 x 16) |
//! |---|---|---|---|---|
//! | [`TentTable::sample_int`] (`G = 0`) | `8 Q_max` | always (`E + 3 <= 35`) | always | always |
//! | [`TentTable::sample`], [`TentTable::sample_raw`] | `8 s^2 Q_max`: `E + 2G + 3` bits | `E + 2F <= 58` | `F <= 13` | `F <= 16` |
//! | [`TentTable::sample_exact`], [`TentTable::sample_exact_raw`] | `12 s^4 Q_max + m s^4 + ...`: `E + 4G + 4` bits | `E + 4F <= 55` | `F <= 5` | `F <= 7` |
//!
//! Every lookup also needs its normaliser below `2^63`: half-widths of `A x B` texels need
//! `(A B)^2 2^(4G) < 2^63` (at `F = 8`, `A B < 2^13.5`; the whole 63 x 63 texture, the largest
//! 8-bit one a `u32` table holds, up to `F = 9`).
//!
//! Past those a footprint is answered if its own bound fits (a footprint far from the table's
//! last row and column reads smaller values) and refused otherwise; one reaching outside the
//! table adds its extension weights and is refused earlier. Before this proof a `u32` table
//! computed in `i128` and answered all of these, so these refusals are new: **take `u64`
//! entries for them** (the same lookups in `i128`, refused only where 127 bits overflow).
//!
//! How close the bound is to the need (tests, which measure every intermediate with a tracking
//! accumulator on the `u64` table and check that the bound is never below it): on the whole
//! all-maximum texture within 2 bits in the paper form and 6 in the exact form; for any refused
//! footprint inside the table within 3 bits in the paper form. It is looser where the interval
//! bound cannot see cancellations: the exact form of narrow footprints (up to 25 bits: the
//! paper numerator, a second difference, is far below its bound `P` when `a` is a texel or less,
//! which only the paper form's error analysis could show) and footprints outside the table
//! (up to 12 bits in the paper form, 22 in the exact form: the extension terms cancel); the
//! integer form's within 6 bits. (These are the largest gaps on the tests' footprints, and the
//! tests hold the bound to them.)
//!
//! ## Widths and memory
//!
//! The largest entry is `Q(w+1, h+1) = m w (w + 2) h (h + 2)` for the all-`m` texture (each
//! axis: `sum_{i<w} (2w + 1 - 2i) = w (w + 2)`), so [`tent_entry_bits`] is exact. Entries are
//! [`TentEntry`]: `u32`, `u64` or `u128` (at most 127 bits used, so any entry converts to its
//! lookups' accumulator: `i64` for `u32`, `i128` for the others). 8-bit texels: `u32` holds up
//! to 63 x 63, `u64` up to 16 399 x 16 399 (16 400 is refused); 16-bit texels: 15 x 15 and
//! 4 095 x 4 095. 256 x 256 at 8 bits needs 41 bits. Memory for 8-bit
//! 256 x 256 in `u64`: `257^2 * 64` bits over `256^2 * 8` = 8.06x the texture (5.2x at the exact
//! 41 bits; the survey says 2-6x). The exact variant adds [`TentLines`] (`w (h+1) + (w+1) h`
//! entries of [`tent_line_bits`] bits, its own entry type: 25 bits at 256 x 256, so `u32`,
//! another 8.03x) and reads the texture itself.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::cost::Counter;
use crate::edge::{EdgeKind, EdgeMode};
use crate::error::{Error, Quantity};
use crate::filters::{per_channel, u64_from_usize, Sample, OUT_FRAC_BITS};
use crate::rect::{Coord, FracBits, Rect};
use crate::texel::Texel;
use crate::texture::Texture;
use crate::width::{
    bits_of, bits_of_product_n, bits_of_u64, check_texel_bits, max_texel, max_texel_u64,
};

/// An unsigned entry of the order-2 tables: `u32`, `u64` or `u128`.
///
/// Local to this module because the core's [`crate::Entry`] stops at `u64`, and `Q` outgrows
/// `u64` from 16 400 x 16 400 8-bit texels (4 096 x 4 096 16-bit texels) on.
pub trait TentEntry: Copy + Default + PartialEq + core::fmt::Debug + 'static {
    /// Storage bits per entry and channel.
    const BITS: u32;
    /// Value bits the width check allows: `BITS`, but 127 for `u128` so every entry converts
    /// losslessly to the lookups' `i128`.
    const VALUE_BITS: u32;
    /// Zero.
    const ZERO: Self;
    /// The lookups' accumulator, chosen by the entry type at compile time (module docs, "How
    /// wide the lookups compute"): `i64` for `u32` entries, `i128` for `u64` and `u128` ones.
    type Acc: TentAcc;
    /// A texel.
    fn from_u16(v: u16) -> Self;
    /// Addition; the build only adds where [`tent_entry_bits`] has proved the sum fits (it
    /// wraps, so even a wrong proof could not panic).
    fn plus(self, o: Self) -> Self;
    /// The entry as `i128` (lossless below `2^VALUE_BITS`).
    fn to_i128(self) -> i128;
    /// The entry as `i64`, `None` from `2^63` on (for `u32` entries a plain widening: no
    /// 128-bit operation).
    fn to_i64(self) -> Option<i64>;
}

macro_rules! impl_tent_entry {
    ($t:ty, $vb:expr, $acc:ty, $v:ident => $to_i128:expr) => {
        impl TentEntry for $t {
            const BITS: u32 = <$t>::BITS;
            const VALUE_BITS: u32 = $vb;
            const ZERO: Self = 0;
            type Acc = $acc;
            #[inline(always)]
            fn from_u16(v: u16) -> Self {
                <$t>::from(v)
            }
            #[inline(always)]
            fn plus(self, o: Self) -> Self {
                self.wrapping_add(o)
            }
            #[inline(always)]
            fn to_i128(self) -> i128 {
                let $v = self;
                $to_i128
            }
            #[inline(always)]
            fn to_i64(self) -> Option<i64> {
                i64::try_from(self).ok()
            }
        }
    };
}

impl_tent_entry!(u32, 32, i64, v => i128::from(v));
impl_tent_entry!(u64, 64, i128, v => i128::from(v));
impl_tent_entry!(u128, 127, i128, v => {
    #[allow(
        clippy::as_conversions,
        reason = "VALUE_BITS = 127: the builds' width proofs keep every entry below 2^127, \
                  where the cast is lossless (documented on to_i128)"
    )]
    let i = v as i128;
    i
});

mod sealed {
    /// Only `i64` and `i128` are tent accumulators.
    pub trait Sealed {}
    impl Sealed for i64 {}
    impl Sealed for i128 {}
}

/// The signed accumulator of the tent lookups, [`TentEntry::Acc`]: `i64` (for `u32` tables) or
/// `i128` (for `u64` and `u128` tables). Sealed: the checked operations the lookups use, so
/// that one generic implementation compiles to 64-bit arithmetic for `u32` tables and to
/// 128-bit arithmetic only for the wider ones.
pub trait TentAcc: Copy + Ord + Default + core::fmt::Debug + 'static + sealed::Sealed {
    /// Magnitude bits a value may use: 63 (`i64`) or 127 (`i128`).
    const BITS_AVAILABLE: u32;
    /// Whether a lookup proves its width before it reads (module docs): `true` for `i64`, whose
    /// lookups refuse up front what could pass 63 bits; `i128` lookups rely on their checked
    /// operations alone, as they always have.
    const PROVES_FIRST: bool;
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// Lossless.
    fn from_i64(v: i64) -> Self;
    /// `None` past the type.
    fn from_u64(v: u64) -> Option<Self>;
    /// A line or table entry (`None` past the type).
    fn from_entry<L: TentEntry>(e: L) -> Option<Self>;
    /// Checked `+`.
    fn checked_add(self, o: Self) -> Option<Self>;
    /// Checked `-`.
    fn checked_sub(self, o: Self) -> Option<Self>;
    /// Checked `*`.
    fn checked_mul(self, o: Self) -> Option<Self>;
    /// Checked Euclidean division.
    fn checked_div_euclid(self, o: Self) -> Option<Self>;
    /// Checked Euclidean remainder.
    fn checked_rem_euclid(self, o: Self) -> Option<Self>;
    /// `self * 2^g`, `None` past the type.
    fn checked_shl(self, g: u32) -> Option<Self>;
    /// `floor(self / 2^g)` (`g` below the type's bits).
    fn floor_shr(self, g: u32) -> Self;
    /// `None` past `i64`.
    fn to_i64(self) -> Option<i64>;
    /// `|self|` as `u64`, `None` past it.
    fn abs_u64(self) -> Option<u64>;
    /// Whether `|self|` is a power of two (a weight that costs a shift, not a multiply).
    fn abs_is_power_of_two(self) -> bool;
    /// The normaliser `a^2 b^2` of half-widths `a`, `b >= 1`, or [`Error::TooWide`]
    /// (`MeanNumerator`, `bits_needed = 2 bits(a) + 2 bits(b)`) from `2^BITS_AVAILABLE` on.
    fn normaliser(a: u64, b: u64) -> Result<Self, Error>;
    /// `round(num 2^shift / den)`, ties up, for `num >= 0` and `0 < den < 2^BITS_AVAILABLE`;
    /// a quotient past `u64` is [`Error::TooWide`], a zero `den` [`Error::ZeroArea`].
    fn div_round_shift(num: Self, shift: u32, den: Self) -> Result<u64, Error>;
}

/// The checked binary operations of [`TentAcc`], each the primitive type's own.
macro_rules! forward_checked {
    ($t:ty: $($name:ident),*) => {
        $(
            #[inline(always)]
            fn $name(self, o: Self) -> Option<Self> {
                <$t>::$name(self, o)
            }
        )*
    };
}

macro_rules! impl_tent_acc {
    (
        $t:ty, $u:ty, $bits:expr, $proves:expr,
        $e:ident => $from_entry:expr,
        $div:path
    ) => {
        impl TentAcc for $t {
            const BITS_AVAILABLE: u32 = $bits;
            const PROVES_FIRST: bool = $proves;
            const ZERO: Self = 0;
            const ONE: Self = 1;
            #[inline(always)]
            fn from_i64(v: i64) -> Self {
                <$t>::from(v)
            }
            #[inline(always)]
            fn from_u64(v: u64) -> Option<Self> {
                <$t>::try_from(v).ok()
            }
            #[inline(always)]
            fn from_entry<L: TentEntry>($e: L) -> Option<Self> {
                $from_entry
            }
            forward_checked!($t: checked_add, checked_sub, checked_mul, checked_div_euclid,
                checked_rem_euclid);
            #[inline(always)]
            fn checked_shl(self, g: u32) -> Option<Self> {
                let p = <Self as TentAcc>::ONE.checked_shl(g).filter(|&p| p > 0)?;
                self.checked_mul(p)
            }
            #[inline(always)]
            fn floor_shr(self, g: u32) -> Self {
                // Arithmetic shift: the floor; g past the bits saturates to the sign.
                self.checked_shr(g).unwrap_or(if self < 0 { -1 } else { 0 })
            }
            #[inline(always)]
            fn to_i64(self) -> Option<i64> {
                i64::try_from(self).ok()
            }
            #[inline(always)]
            fn abs_u64(self) -> Option<u64> {
                u64::try_from(self.unsigned_abs()).ok()
            }
            #[inline(always)]
            fn abs_is_power_of_two(self) -> bool {
                self.unsigned_abs().is_power_of_two()
            }
            #[inline]
            fn normaliser(a: u64, b: u64) -> Result<Self, Error> {
                // a^2 b^2 in the unsigned word of the same width, then into the signed one.
                let (wa, wb) = (<$u>::from(a), <$u>::from(b));
                wa.checked_mul(wa)
                    .and_then(|a2| wb.checked_mul(wb).and_then(|b2| a2.checked_mul(b2)))
                    .and_then(|d| <$t>::try_from(d).ok())
                    .ok_or_else(|| normaliser_too_wide(bits_of_u64(a), bits_of_u64(b), $bits))
            }
            #[inline]
            fn div_round_shift(n: Self, s: u32, d: Self) -> Result<u64, Error> {
                $div(n.max(0).unsigned_abs(), s, d.max(0).unsigned_abs())
            }
        }
    };
}

impl_tent_acc!(i64, u64, 63, true, e => e.to_i64(), div_round_shift_u64);
impl_tent_acc!(i128, u128, 127, false, e => Some(e.to_i128()), div_round_shift);

/// The normaliser's refusal: `2 bits(a) + 2 bits(b)` bits needed.
fn normaliser_too_wide(a_bits: u32, b_bits: u32, bits_available: u32) -> Error {
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "bits of u64 values (`bits_of_u64`) are at most 64: the sum is at most 256"
    )]
    let bits_needed = 2 * a_bits + 2 * b_bits;
    Error::TooWide {
        what: Quantity::MeanNumerator,
        bits_needed,
        bits_available,
    }
}

/// Exact bits of the largest `Q` entry of a `w x h` texture of `b`-bit texels:
/// `bits_of((2^b - 1) * w (w + 2) * h (h + 2))` (saturating at 128 bits, which no entry holds).
///
/// Proof: `Q(X, Y) = sum_{i<X, j<Y} (2X - 2i - 1)(2Y - 2j - 1) t(i, j)` has non-negative
/// coefficients growing with `X` and `Y`, so the largest entry is `Q(w+1, h+1)` (the padded
/// corner) of the all-`m` texture, and each axis sums `sum_{i<w} (2w + 1 - 2i) = w (w + 2)`.
/// Every intermediate of the build is bounded by an entry (see [`TentTable::build`]).
///
/// Computed from 32-bit limbs ([`crate::width`]'s exact products), so a build's width proof
/// has no 128-bit operation; texel widths past 64 bits (which no texel has) and sides past
/// `2^64 - 3` take the saturating `u128` product.
pub const fn tent_entry_bits(texel_bits: u32, width: usize, height: usize) -> u32 {
    if texel_bits <= 64 {
        if let Some(bits) = build_entry_bits(texel_bits, width, height) {
            return bits;
        }
    }
    entry_bits_u128(texel_bits, width, height)
}

/// [`tent_entry_bits`] for `texel_bits <= 64` (the builds check `<= 16` first) from 32-bit limbs
/// only: `None` for sides past `2^64 - 3`. What [`TentTable::build`] calls, apart from the
/// public function's `u128` fallback so that the link gate can refuse any 128-bit operation
/// in it by name (`examples/firmware/link-gate.sh`).
const fn build_entry_bits(texel_bits: u32, width: usize, height: usize) -> Option<u32> {
    let (w, h) = (u64_from_usize(width), u64_from_usize(height));
    let (Some(w2), Some(h2)) = (w.checked_add(2), h.checked_add(2)) else {
        return None;
    };
    limb_bits(&[max_texel_u64(texel_bits), w, w2, h, h2])
}

/// The bits of a product of at most six factors (`None` past six), saturated at 128 as the
/// `u128` formulation has them.
const fn limb_bits(factors: &[u64]) -> Option<u32> {
    match bits_of_product_n(factors) {
        Some(bits) => Some(saturate_128(bits)),
        None => None,
    }
}

/// [`tent_entry_bits`] in saturating `u128` arithmetic (its fallback, and the tests' reference).
const fn entry_bits_u128(texel_bits: u32, width: usize, height: usize) -> u32 {
    let (wx, hy) = (side_product(width), side_product(height));
    bits_of(max_texel(texel_bits).saturating_mul(wx).saturating_mul(hy))
}

/// Bits of an exact product as the saturating `u128` product has them: at most 128.
const fn saturate_128(bits: u32) -> u32 {
    if bits > 128 {
        128
    } else {
        bits
    }
}

/// `n (n + 2)` in `u128`, saturating (it never does: `n < 2^64`).
const fn side_product(n: usize) -> u128 {
    #[allow(
        clippy::as_conversions,
        clippy::arithmetic_side_effects,
        reason = "usize -> u128 is lossless (usize has at most 64 bits; From is not const), and \
                  n + 2 < 2^65"
    )]
    let (n, n2) = (u64_from_usize(n) as u128, u64_from_usize(n) as u128 + 2);
    n.saturating_mul(n2)
}

/// Exact bits of the largest entry of the per-line order-2 integrals of [`TentLines`] for lines
/// of `n` texels: `bits_of((2^b - 1) * n (n + 2))`.
/// From 32-bit limbs as [`tent_entry_bits`] (the same fallback past 64-bit texels).
pub const fn tent_line_bits(texel_bits: u32, n: usize) -> u32 {
    if texel_bits <= 64 {
        if let Some(bits) = build_line_bits(texel_bits, n) {
            return bits;
        }
    }
    line_bits_u128(texel_bits, n)
}

/// [`tent_line_bits`] for `texel_bits <= 64` from 32-bit limbs only, as [`build_entry_bits`]:
/// what [`TentLines::build`] calls.
const fn build_line_bits(texel_bits: u32, n: usize) -> Option<u32> {
    let n64 = u64_from_usize(n);
    let Some(n2) = n64.checked_add(2) else {
        return None;
    };
    limb_bits(&[max_texel_u64(texel_bits), n64, n2])
}

/// [`tent_line_bits`] in saturating `u128` arithmetic (its fallback, and the tests' reference).
const fn line_bits_u128(texel_bits: u32, n: usize) -> u32 {
    bits_of(max_texel(texel_bits).saturating_mul(side_product(n)))
}

/// The error bound of [`TentTable::sample`] (bilinear interpolation of `T2`, the survey's
/// "36,31") against the exact triangle filter, in texel units, for half-widths `a`, `b` in texels:
/// `m/4 * (1/a^2 + 1/b^2 + 1/(2 a^2 b^2))`, `m = 2^b - 1` (plus the output rounding
/// `2^-17`).
///
/// Derivation: per axis the lerp of `s = 2 S2` exceeds the exact value by `δ = α(1-α) t(i)`.
/// `L_x L_y - E_x E_y = δ_x E_y + E_x δ_y + δ_x δ_y`; under the second differences the first term
/// is `2 sum_p w_p α_p(1-α_p) Ψ_p` with `Ψ_p in [0, m b^2]` the exact triangle integral in y of
/// column `i_p`, hence in `[-m b^2, m b^2]`; likewise the second; the third is
/// `sum w_p w_q α_p(1-α_p) β_q(1-β_q) t` with positive and negative weights summing to 8 each,
/// in `[-m/2, m/2]`. Divided by `4 a^2 b^2`. The first term alone reaches `m / (4 a^2)`: columns
/// `i_{-1}`, `i_1` full, column `i_0` empty, all fractions `1/2`.
pub fn paper_error_bound(texel_bits: u32, a: f64, b: f64) -> f64 {
    #[allow(
        clippy::as_conversions,
        reason = "u128 -> f64 has no From: exact up to 53-bit texels, nearest above (a bound in \
                  f64 either way)"
    )]
    let m = max_texel(texel_bits.min(64)) as f64;
    m / 4.0 * (1.0 / (a * a) + 1.0 / (b * b) + 1.0 / (2.0 * a * a * b * b))
}

/// An accumulator past `A`: [`Error::TooWide`] (`LookupAccumulator`) with one bit more than
/// `A` holds as `bits_needed` (a lower bound: a checked operation knows no more).
fn acc_overflow<A: TentAcc>() -> Error {
    Error::TooWide {
        what: Quantity::LookupAccumulator,
        bits_needed: A::BITS_AVAILABLE.saturating_add(1),
        bits_available: A::BITS_AVAILABLE,
    }
}

/// A checked result or [`acc_overflow`].
#[inline]
fn ck<A: TentAcc>(v: Option<A>) -> Result<A, Error> {
    v.ok_or_else(acc_overflow::<A>)
}

fn entries_needed<const C: usize>(cols: usize, rows: usize) -> Result<usize, Error> {
    cols.checked_mul(rows)
        .and_then(|v| v.checked_mul(C))
        .ok_or(Error::TextureTooLarge {
            dimension: cols.max(rows),
        })
}

/// The second-order integrated table `Q = 4 T2` of a texture padded with one zero column and row.
#[derive(Debug, Clone, Copy)]
pub struct TentTable<'a, E: TentEntry, const C: usize = 1> {
    table: &'a [E],
    width: usize,
    height: usize,
    texel_bits: u32,
}

impl<'a, E: TentEntry, const C: usize> TentTable<'a, E, C> {
    /// Entries the table of a `width x height` texture needs: `(w + 1)(h + 1) C`.
    pub fn storage_needed(width: usize, height: usize) -> Result<usize, Error> {
        entries_needed::<C>(width.saturating_add(1), height.saturating_add(1))
    }

    /// Builds `Q` into `storage` (its first `(w+1)(h+1) C` entries) after proving from the texel
    /// width that no entry overflows `E` ([`tent_entry_bits`] against [`TentEntry::VALUE_BITS`]);
    /// nothing is written if the proof or the storage size fails.
    ///
    /// Per entry and channel: x pass `W += 2V + t`, `V += t` (3 additions, the doubling a
    /// shift), y pass `Q = Q_above + 2 Vy + W`, `Vy += W` (3 additions). Every intermediate is at
    /// most an entry: `V(X) <= W(X+1)`, `W_j(X) <= Q(X, Y)` for `j < Y`, `Vy_Y <= Q(X, Y)`,
    /// `2 Vy + W + Q_above = Q`. The running column sums `Vy` are kept in the last table row
    /// until it is written.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
    ) -> Result<Self, Error> {
        let (w, h) = (texture.width(), texture.height());
        check_texel_bits(T::BITS)?;
        // T::BITS <= 16 (checked): the limb proof; sides past 2^64 - 3 (no texture has them)
        // need 128 bits, as the saturating product says.
        let bits = build_entry_bits(T::BITS, w, h).unwrap_or(128);
        if bits > E::VALUE_BITS {
            return Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: bits,
                bits_available: E::VALUE_BITS,
            });
        }
        let needed = Self::storage_needed(w, h)?;
        if storage.len() < needed {
            return Err(Error::StorageTooSmall {
                needed,
                got: storage.len(),
            });
        }
        // (w + 1)(h + 1) C fits (storage_needed): none of these products overflow.
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "(w + 1)(h + 1) C fits usize (storage_needed succeeded)"
        )]
        let (row_len, body_len) = ((w + 1) * C, h * (w + 1) * C);
        let got = storage.len();
        let (body, last) = storage
            .get_mut(..needed)
            .and_then(|t| t.split_at_mut_checked(body_len))
            .ok_or(Error::StorageTooSmall { needed, got })?;
        last.fill(E::ZERO);
        for y in 0..=h {
            let texels = if y < h {
                Some(texture.row(y).ok_or(Error::EmptyTexture)?)
            } else {
                None
            };
            let mut v = [E::ZERO; C];
            let mut wx = [E::ZERO; C];
            for xi in 0..=w {
                for (c, (wxc, vc)) in wx.iter_mut().zip(v.iter_mut()).enumerate() {
                    #[allow(
                        clippy::arithmetic_side_effects,
                        reason = "xi <= w, y <= h and c < C: below (w + 1)(h + 1) C, which fits \
                                  usize (storage_needed)"
                    )]
                    let (idx, above_at, at) = {
                        let idx = xi * C + c;
                        let above_at = y.checked_sub(1).map(|ya| ya * row_len + idx);
                        (idx, above_at, y * row_len + idx)
                    };
                    let t = match texels {
                        Some(r) if xi < w => {
                            r.get(idx).map_or(E::ZERO, |t| E::from_u16(t.to_u16()))
                        }
                        _ => E::ZERO,
                    };
                    *wxc = wxc.plus(vc.plus(*vc)).plus(t);
                    *vc = vc.plus(t);
                    let above = match above_at {
                        Some(i) => body.get(i).copied().unwrap_or(E::ZERO),
                        None => E::ZERO,
                    };
                    let Some(vy) = last.get_mut(idx) else {
                        continue;
                    };
                    let q = above.plus(vy.plus(*vy)).plus(*wxc);
                    if y < h {
                        *vy = vy.plus(*wxc);
                        if let Some(b) = body.get_mut(at) {
                            *b = q;
                        }
                    } else {
                        *vy = q;
                    }
                }
            }
        }
        let table: &'a [E] = storage;
        Ok(TentTable {
            table: table.get(..needed).unwrap_or(&[]),
            width: w,
            height: h,
            texel_bits: T::BITS,
        })
    }

    /// Width of the texture in texels (the table has `w + 1` columns).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height of the texture in texels (the table has `h + 1` rows).
    pub fn height(&self) -> usize {
        self.height
    }

    /// Bits per texel of the source texture.
    pub fn texel_bits(&self) -> u32 {
        self.texel_bits
    }

    /// The stored entries `Q(X, Y)`, `1 <= X <= w+1`, `1 <= Y <= h+1`, row-major, channels
    /// interleaved.
    pub fn entries(&self) -> &'a [E] {
        self.table
    }

    /// Table bytes as stored.
    pub fn table_bytes(&self) -> usize {
        core::mem::size_of_val(self.table)
    }

    /// `Q(X, Y) = 4 T2(X, Y)` for `X <= w + 1`, `Y <= h + 1` (`None` outside); zero on `X = 0`
    /// and `Y = 0`.
    pub fn corner(&self, x: usize, y: usize) -> Option<[E; C]> {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w, h < 2^31 (the texture's)"
        )]
        let (xmax, ymax) = (self.width + 1, self.height + 1);
        if x > xmax || y > ymax {
            return None;
        }
        let mut out = [E::ZERO; C];
        if x != 0 && y != 0 {
            let (at, end) = self.entry_range(x, y);
            for (o, &e) in out.iter_mut().zip(self.table.get(at..end)?) {
                *o = e;
            }
        }
        Some(out)
    }

    /// The element range of `Q(x, y)`, `1 <= x <= w + 1`, `1 <= y <= h + 1`.
    #[inline(always)]
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "callers check 1 <= x <= w + 1 and 1 <= y <= h + 1: inside the (w + 1)(h + 1) C \
                  entries, a count that fits usize (storage_needed); w < 2^31"
    )]
    fn entry_range(&self, x: usize, y: usize) -> (usize, usize) {
        let at = ((y - 1) * (self.width + 1) + (x - 1)) * C;
        (at, at + C)
    }

    /// `Q(x, y)` in the accumulator `A`, with the read counted (free on the zero row and
    /// column). An entry past `A` (which no table built by [`TentTable::build`] has: its width
    /// proof bounds every entry by `2^E::VALUE_BITS`, and `E::Acc` holds that) is refused.
    fn read<A: TentAcc, K: Counter>(&self, x: usize, y: usize, k: &mut K) -> Result<[A; C], Error> {
        let mut out = [A::ZERO; C];
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w, h < 2^31 (the texture's)"
        )]
        let (xmax, ymax) = (self.width + 1, self.height + 1);
        if x != 0 && y != 0 && x <= xmax && y <= ymax {
            k.reads(1, const { per_channel(E::BITS, C) });
            k.words(const { per_channel(E::BITS, C).div_ceil(32) });
            // x <= w + 1, y <= h + 1: inside the (w + 1)(h + 1) C entries, no overflow.
            let (at, end) = self.entry_range(x, y);
            for (o, &e) in out.iter_mut().zip(self.table.get(at..end).unwrap_or(&[])) {
                *o = ck(A::from_entry(e))?;
            }
        }
        Ok(out)
    }

    /// What the width proofs start from: the largest texel and the table's sides
    /// ([`Worst`]).
    fn worst(&self) -> Worst {
        Worst {
            m: max_texel_u64(self.texel_bits),
            w: self.width,
            h: self.height,
        }
    }

    /// The triangle filter with integer centre `(cx, cy)` and integer half-widths `a`, `b`
    /// (support `[cx - a, cx + a] x [cy - b, cy + b]`), under boundary mode `M`, exact before
    /// the output rounding (`round(value * 2^16)`, ties up).
    ///
    /// In range: 9 reads, 3 multiplies + 1 divide (the survey's "9,4"), 8 additive operations
    /// per channel. Zero half-widths are [`Error::ZeroArea`]. On a `u32` table a footprint
    /// whose worst case could pass 63 bits is [`Error::TooWide`] before any read (module docs,
    /// "How wide the lookups compute").
    pub fn sample_int<M: EdgeMode, K: Counter>(
        &self,
        cx: i32,
        cy: i32,
        a: u32,
        b: u32,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.sample_int_in::<E::Acc, M, K>(cx, cy, a, b, mode, k)
    }

    /// [`TentTable::sample_int`] in the accumulator `A`.
    fn sample_int_in<A: TentAcc, M: EdgeMode, K: Counter>(
        &self,
        cx: i32,
        cy: i32,
        a: u32,
        b: u32,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let kind = mode.kind();
        if a == 0 || b == 0 {
            return Err(Error::ZeroArea);
        }
        let (au, bu) = (u64::from(a), u64::from(b));
        let (a, b) = (A::from_i64(i64::from(a)), A::from_i64(i64::from(b)));
        let Some(cx) = canonical_centre(kind, A::from_i64(i64::from(cx)), a, self.width, 0)? else {
            return Ok(Sample { values: [0; C] });
        };
        let Some(cy) = canonical_centre(kind, A::from_i64(i64::from(cy)), b, self.height, 0)?
        else {
            return Ok(Sample { values: [0; C] });
        };
        let d = A::normaliser(au, bu)?;
        let (ax, ay) = (
            int_axes(kind, cx, a, self.width)?,
            int_axes(kind, cy, b, self.height)?,
        );
        prove::<A>(|| paper_bound(&ax, &ay, 1, self.worst()))?;
        let n = self.paper_numerator(&ax, &ay, A::ONE, k)?;
        // value = N / (4 a^2 b^2); output = round(N 2^(16 - 2) / (a^2 b^2)).
        finish(&n, d, OUT_FRAC_BITS - 2, k)
    }

    /// The paper-faithful triangle filter over the footprint rectangle `r` (fixed-point corners,
    /// `F <= 24` fractional bits): 9 bilinear interpolations of `Q`, then the second
    /// differences. In range: 36 reads, 30 multiplies + 1 divide (the survey's "36,31"), 62
    /// additive operations per channel. Not exact: within [`paper_error_bound`] of
    /// [`TentTable::sample_exact`]; negative results are clamped to 0.
    ///
    /// Inverted rectangles are [`Error::InvertedBox`], zero-width or zero-height ones
    /// [`Error::ZeroArea`]. On a `u32` table a footprint whose worst case could pass 63 bits is
    /// [`Error::TooWide`] before any read (every footprint inside the table is answered if
    /// `E + 2F <= 58` and its `a^2 b^2 < 2^63`; module docs).
    pub fn sample<X: Coord, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.sample_raw(&r.to_raw(), FracBits::of::<X>()?, mode, k)
    }

    /// [`TentTable::sample`] with raw corners (`value * 2^F`) and `F` as a value, checked once
    /// by [`FracBits::new`]: one compiled sampler serves every `F`.
    pub fn sample_raw<M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i64>,
        frac_bits: FracBits,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.sample_raw_in::<E::Acc, M, K>(r, frac_bits, mode, k)
    }

    /// [`TentTable::sample_raw`] in the accumulator `A`.
    fn sample_raw_in<A: TentAcc, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i64>,
        frac_bits: FracBits,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let Some(fp) = self.footprint::<A>(r, frac_bits, mode.kind())? else {
            return Ok(Sample { values: [0; C] });
        };
        prove::<A>(|| paper_bound(&fp.ax, &fp.ay, fp.s.abs_u64()?, self.worst()))?;
        let n = self.paper_numerator(&fp.ax, &fp.ay, fp.s, k)?;
        // value = N 2^2G / (4 a^2 b^2) (N scaled by s^2, a and b in units 2^-G).
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "g = F + 1 <= 25 (FracBits): the shift is at most 64"
        )]
        let shift = 2 * fp.g + OUT_FRAC_BITS - 2;
        finish(&n, fp.d, shift, k)
    }

    /// The exact triangle filter over the footprint rectangle `r` (fixed-point corners,
    /// `F <= 24`): the paper lookup plus the exact in-cell correction from `lines` (built from
    /// the same texture; its entry type may be narrower than the table's) and the texels of
    /// `texture` (module docs). In range: 81 reads
    /// (36 of `Q`, 18 of each line table, 9 texels), 72 multiplies + 1 divide. The result is
    /// `round(value * 2^16)` of the exact filtered value, ties up.
    ///
    /// The intermediates are scaled by `2^4G` (`G = F + 1`). With `u64` entries they fit
    /// `i128` for `F <= 8` and tables up to the `u64` limit; larger combinations may be refused
    /// with [`Error::TooWide`]. With `u32` entries they are `i64`, and a footprint whose worst
    /// case could pass 63 bits is refused before any read (every footprint inside the table is
    /// answered if `E + 4F <= 55` and its `a^2 b^2 < 2^63`; module docs). A `lines` or
    /// `texture` of other dimensions than the table is [`Error::RowLength`] (expected the
    /// table's `width * C`, or `height` for heights).
    pub fn sample_exact<T: Texel, L: TentEntry, X: Coord, M: EdgeMode, K: Counter>(
        &self,
        lines: &TentLines<'_, L, C>,
        texture: &Texture<'_, T, C>,
        r: &Rect<X>,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.sample_exact_raw(lines, texture, &r.to_raw(), FracBits::of::<X>()?, mode, k)
    }

    /// [`TentTable::sample_exact`] with raw corners (`value * 2^F`) and `F` as a value, checked
    /// once by [`FracBits::new`]: one compiled sampler serves every `F`.
    pub fn sample_exact_raw<T: Texel, L: TentEntry, M: EdgeMode, K: Counter>(
        &self,
        lines: &TentLines<'_, L, C>,
        texture: &Texture<'_, T, C>,
        r: &Rect<i64>,
        frac_bits: FracBits,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        self.sample_exact_raw_in::<E::Acc, T, L, M, K>(lines, texture, r, frac_bits, mode, k)
    }

    /// [`TentTable::sample_exact_raw`] in the accumulator `A`.
    fn sample_exact_raw_in<A: TentAcc, T: Texel, L: TentEntry, M: EdgeMode, K: Counter>(
        &self,
        lines: &TentLines<'_, L, C>,
        texture: &Texture<'_, T, C>,
        r: &Rect<i64>,
        frac_bits: FracBits,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let kind = mode.kind();
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "each width is a texture's (or a table built from one), whose width * C \
                      fits usize (Texture::with_stride's checked_mul)"
        )]
        let widths = [
            (lines.width * C, self.width * C),
            (texture.width() * C, self.width * C),
        ];
        for (got, expected) in widths
            .into_iter()
            .chain([(lines.height, self.height), (texture.height(), self.height)])
        {
            if got != expected {
                return Err(Error::RowLength { expected, got });
            }
        }
        let Some(fp) = self.footprint::<A>(r, frac_bits, kind)? else {
            return Ok(Sample { values: [0; C] });
        };
        let s = fp.s;
        let g = fp.g;
        let w = weights::<A>();
        // Cells and fraction products α(1-α) (scaled by s^2) of the three x and y positions:
        // the fraction x - (i << g) is in [0, s) with s = 2^g <= 2^25, so the product is at
        // most s^2 / 4 <= 2^48.
        let frac_product = |x: A| -> Result<A, Error> {
            let fa = ck(x.checked_sub(ck(x.floor_shr(g).checked_shl(g))?))?;
            ck(fa.checked_mul(ck(s.checked_sub(fa))?))
        };
        let (ix, iy) = (fp.px.map(|x| x.floor_shr(g)), fp.py.map(|y| y.floor_shr(g)));
        let mut pa = [A::ZERO; 3];
        let mut pb = [A::ZERO; 3];
        for (((pa, pb), &x), &y) in pa.iter_mut().zip(&mut pb).zip(&fp.px).zip(&fp.py) {
            (*pa, *pb) = (frac_product(x)?, frac_product(y)?);
        }
        prove::<A>(|| exact_bound(&fp, &pa, &pb, self.worst(), max_texel_u64(T::BITS)))?;
        let paper = self.paper_numerator(&fp.ax, &fp.ay, s, k)?;
        k.muls(6);
        let cols: [Option<usize>; 3] = ix.map(|i| texel_at(kind, i, self.width));
        let rows: [Option<usize>; 3] = iy.map(|i| texel_at(kind, i, self.height));
        // Per-channel counts: compile-time constants.
        let (c1, c2, c3) = (
            const { per_channel(1, C) },
            const { per_channel(2, C) },
            const { per_channel(3, C) },
        );
        // sX = sum_p w_p pa_p sum_q w_q L_y Cy(col_p)(y_q)   (scale s^3)
        // (Index loops over the three points: the compiler proves every index in range and
        // emits smaller code for them than for the zipped iterators.)
        let mut sx = [A::ZERO; C];
        #[allow(
            clippy::indexing_slicing,
            reason = "p < 3 indexes the [_; 3] arrays, c < C the [_; C] ones"
        )]
        for p in 0..3 {
            let mut xp = [A::ZERO; C];
            if let Some(col) = cols[p] {
                for (ayq, &wq) in fp.ay.iter().zip(&w) {
                    let v = eval1::<A, C, K>(ayq, s, &mut |iyy, k| lines.col(col, iyy, k), k)?;
                    for c in 0..C {
                        xp[c] = ck(xp[c].checked_add(ck(v[c].checked_mul(wq))?))?;
                    }
                }
            }
            k.adds(c2);
            k.muls(c1);
            k.adds(c1);
            for c in 0..C {
                let t = ck(ck(xp[c].checked_mul(pa[p]))?.checked_mul(w[p]))?;
                sx[c] = ck(sx[c].checked_add(t))?;
            }
        }
        let mut sy = [A::ZERO; C];
        #[allow(
            clippy::indexing_slicing,
            reason = "q < 3 indexes the [_; 3] arrays, c < C the [_; C] ones"
        )]
        for q in 0..3 {
            let mut yq = [A::ZERO; C];
            if let Some(row) = rows[q] {
                for (axp, &wp) in fp.ax.iter().zip(&w) {
                    let v = eval1::<A, C, K>(axp, s, &mut |ixx, k| lines.row(ixx, row, k), k)?;
                    for c in 0..C {
                        yq[c] = ck(yq[c].checked_add(ck(v[c].checked_mul(wp))?))?;
                    }
                }
            }
            k.adds(c2);
            k.muls(c1);
            k.adds(c1);
            for c in 0..C {
                let t = ck(ck(yq[c].checked_mul(pb[q]))?.checked_mul(w[q]))?;
                sy[c] = ck(sy[c].checked_add(t))?;
            }
        }
        // Texel term: sum_p w_p pa_p sum_q w_q pb_q t(i_p, j_q)   (scale s^4)
        let mut st = [A::ZERO; C];
        #[allow(
            clippy::indexing_slicing,
            reason = "p, q < 3 index the [_; 3] arrays, c < C the [_; C] ones"
        )]
        for p in 0..3 {
            let mut inner = [A::ZERO; C];
            for q in 0..3 {
                if let (Some(col), Some(row)) = (cols[p], rows[q]) {
                    k.reads(1, const { per_channel(T::BITS, C) });
                    let texels = texture.row(row).ok_or(Error::EmptyTexture)?;
                    for (c, inner) in inner.iter_mut().enumerate() {
                        #[allow(
                            clippy::arithmetic_side_effects,
                            reason = "col < w (texel_at), c < C, and w C fits usize (the \
                                      texture's checked width * C)"
                        )]
                        let at = col * C + c;
                        let t = texels
                            .get(at)
                            .map_or(A::ZERO, |t| A::from_i64(i64::from(t.to_u16())));
                        let term = ck(t.checked_mul(pb[q]))?;
                        *inner = ck(inner.checked_add(ck(term.checked_mul(w[q]))?))?;
                    }
                }
                k.muls(c1);
            }
            k.adds(c3);
            k.muls(c1);
            for c in 0..C {
                let t = ck(ck(inner[c].checked_mul(pa[p]))?.checked_mul(w[p]))?;
                st[c] = ck(st[c].checked_add(t))?;
            }
        }
        k.adds(c3);
        let s2 = ck(s.checked_mul(s))?;
        let mut n = [A::ZERO; C];
        for ((((nc, p), x), y), t) in n.iter_mut().zip(paper).zip(sx).zip(sy).zip(st) {
            let hi = ck(p.checked_mul(s2))?;
            let mid = ck(ck(x.checked_add(y))?.checked_mul(s))?;
            *nc = ck(ck(hi.checked_sub(mid))?.checked_add(t))?;
        }
        // value = N / (4 a^2 b^2) (N scaled by s^4).
        finish(&n, fp.d, OUT_FRAC_BITS - 2, k)
    }

    /// Validates a fixed-point footprint and places its three x and y positions (`None`: a
    /// Border footprint entirely outside, whose sample is 0). The corners are first moved by
    /// whole texels or periods in `i64` ([`reduce_corner`]) so that the centre and the
    /// positions stay small in every accumulator; then the normaliser `a^2 b^2` is formed (or
    /// refused) before any weight.
    fn footprint<A: TentAcc>(
        &self,
        r: &Rect<i64>,
        frac_bits: FracBits,
        kind: EdgeKind,
    ) -> Result<Option<Footprint<A>>, Error> {
        let f = frac_bits.get();
        if r.x1 < r.x0 || r.y1 < r.y0 {
            return Err(Error::InvertedBox);
        }
        if r.x1 == r.x0 || r.y1 == r.y0 {
            return Err(Error::ZeroArea);
        }
        // The half-widths in units 2^-G: the corners' differences, below 2^64 (exact in u64).
        let (au, bu) = (r.x1.abs_diff(r.x0), r.y1.abs_diff(r.y0));
        let Some(x0) = reduce_corner(kind, r.x0, r.x1, self.width, f) else {
            return Ok(None);
        };
        let Some(y0) = reduce_corner(kind, r.y0, r.y1, self.height, f) else {
            return Ok(None);
        };
        let d = A::normaliser(au, bu)?;
        #[allow(clippy::arithmetic_side_effects, reason = "f <= 24 (FracBits)")]
        let g = f + 1;
        let s = ck(A::ONE.checked_shl(g))?;
        let (a, b) = (ck(A::from_u64(au))?, ck(A::from_u64(bu))?);
        // The centre 2 x0 + a (units 2^-G) of the reduced corners, then the one mapping of
        // centres (which leaves reduced ones where they are but for the period's remainder).
        let two = A::from_i64(2);
        let cx = ck(ck(A::from_i64(x0).checked_mul(two))?.checked_add(a))?;
        let cy = ck(ck(A::from_i64(y0).checked_mul(two))?.checked_add(b))?;
        let Some(cx) = canonical_centre(kind, cx, a, self.width, g)? else {
            return Ok(None);
        };
        let Some(cy) = canonical_centre(kind, cy, b, self.height, g)? else {
            return Ok(None);
        };
        let px = [ck(cx.checked_sub(a))?, cx, ck(cx.checked_add(a))?];
        let py = [ck(cy.checked_sub(b))?, cy, ck(cy.checked_add(b))?];
        let mut ax = [Axis::Zero, Axis::Zero, Axis::Zero];
        let mut ay = [Axis::Zero, Axis::Zero, Axis::Zero];
        for ((axp, ayp), (&x, &y)) in ax.iter_mut().zip(ay.iter_mut()).zip(px.iter().zip(&py)) {
            *axp = axis_paper(kind, x, self.width, g)?;
            *ayp = axis_paper(kind, y, self.height, g)?;
        }
        Ok(Some(Footprint {
            ax,
            ay,
            px,
            py,
            d,
            g,
            s,
        }))
    }

    /// `N = sum_{p,q} w_p w_q V(p, q)` with `V` the (bilinear or integer) value of `Q` at each
    /// of the 9 points, scaled by `s^2`. Counts the 8 additive operations of the combination.
    fn paper_numerator<A: TentAcc, K: Counter>(
        &self,
        ax: &[Axis<A>; 3],
        ay: &[Axis<A>; 3],
        s: A,
        k: &mut K,
    ) -> Result<[A; C], Error> {
        let w = weights::<A>();
        let mut n = [A::ZERO; C];
        for (ayq, &wq) in ay.iter().zip(&w) {
            let mut row = [A::ZERO; C];
            for (axp, &wp) in ax.iter().zip(&w) {
                let v = eval1::<A, C, K>(
                    ayq,
                    s,
                    &mut |iyy, k| eval1::<A, C, K>(axp, s, &mut |ixx, k| self.read(ixx, iyy, k), k),
                    k,
                )?;
                for (r, v) in row.iter_mut().zip(v) {
                    *r = ck(r.checked_add(ck(v.checked_mul(wp))?))?;
                }
            }
            for (n, r) in n.iter_mut().zip(row) {
                *n = ck(n.checked_add(ck(r.checked_mul(wq))?))?;
            }
        }
        k.adds(const { per_channel(8, C) });
        Ok(n)
    }
}

/// The per-line order-2 integrals the exact variant needs: for every texel column `i` the
/// column's `2 S2` in y at `Y = 1..=h+1`, and for every texel row `j` the row's `2 S2` in x at
/// `X = 1..=w+1` (each line padded with one zero texel, like [`TentTable`]).
#[derive(Debug, Clone, Copy)]
pub struct TentLines<'a, E: TentEntry, const C: usize = 1> {
    cols: &'a [E],
    rows: &'a [E],
    width: usize,
    height: usize,
}

impl<'a, E: TentEntry, const C: usize> TentLines<'a, E, C> {
    /// Entries needed: `(w (h + 1) + (w + 1) h) C`.
    pub fn storage_needed(width: usize, height: usize) -> Result<usize, Error> {
        let a = entries_needed::<C>(width, height.saturating_add(1))?;
        let b = entries_needed::<C>(width.saturating_add(1), height)?;
        a.checked_add(b).ok_or(Error::TextureTooLarge {
            dimension: width.max(height),
        })
    }

    /// Builds both line tables into `storage` after proving that the longer line's worst case
    /// ([`tent_line_bits`]) fits `E`. 3 additions per entry (`W += 2V + t`, `V += t`); the
    /// column pass keeps its running sums in its last row until that row is written.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
    ) -> Result<Self, Error> {
        let (w, h) = (texture.width(), texture.height());
        check_texel_bits(T::BITS)?;
        // As in TentTable::build.
        let bits = build_line_bits(T::BITS, w.max(h)).unwrap_or(128);
        if bits > E::VALUE_BITS {
            return Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: bits,
                bits_available: E::VALUE_BITS,
            });
        }
        let needed = Self::storage_needed(w, h)?;
        if storage.len() < needed {
            return Err(Error::StorageTooSmall {
                needed,
                got: storage.len(),
            });
        }
        // w (h + 1) C + (w + 1) h C fits (storage_needed): none of these products overflow.
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w (h + 1) C + (w + 1) h C fits usize (storage_needed succeeded)"
        )]
        let (ncols, row_len, body_len, rlen) = (w * (h + 1) * C, w * C, h * w * C, (w + 1) * C);
        let got = storage.len();
        let (cols, rest) = storage
            .get_mut(..needed)
            .and_then(|t| t.split_at_mut_checked(ncols))
            .ok_or(Error::StorageTooSmall { needed, got })?;
        // Columns: row Y-1 of `cols` is Y; the last row holds the running sums V until written.
        let (body, last) = cols
            .split_at_mut_checked(body_len)
            .ok_or(Error::StorageTooSmall { needed, got })?;
        last.fill(E::ZERO);
        for y in 0..=h {
            let texels = if y < h {
                Some(texture.row(y).ok_or(Error::EmptyTexture)?)
            } else {
                None
            };
            for (idx, v) in last.iter_mut().enumerate() {
                let t = match texels {
                    Some(r) => r.get(idx).map_or(E::ZERO, |t| E::from_u16(t.to_u16())),
                    None => E::ZERO,
                };
                #[allow(
                    clippy::arithmetic_side_effects,
                    reason = "y <= h and idx < w C: below (h + 1) w C, which fits usize \
                              (storage_needed)"
                )]
                let (above_at, at) = (
                    y.checked_sub(1).map(|ya| ya * row_len + idx),
                    y * row_len + idx,
                );
                let above = match above_at {
                    Some(i) => body.get(i).copied().unwrap_or(E::ZERO),
                    None => E::ZERO,
                };
                let q = above.plus(v.plus(*v)).plus(t);
                if y < h {
                    *v = v.plus(t);
                    if let Some(b) = body.get_mut(at) {
                        *b = q;
                    }
                } else {
                    *v = q;
                }
            }
        }
        // Rows.
        for (y, out) in rest.chunks_exact_mut(rlen.max(1)).take(h).enumerate() {
            let texels = texture.row(y).ok_or(Error::EmptyTexture)?;
            let mut v = [E::ZERO; C];
            let mut acc = [E::ZERO; C];
            for (xi, o) in out.chunks_exact_mut(C).enumerate() {
                for (c, ((o, a), v)) in o.iter_mut().zip(&mut acc).zip(&mut v).enumerate() {
                    let t = if xi < w {
                        #[allow(
                            clippy::arithmetic_side_effects,
                            reason = "xi < w and c < C: below w C, which fits usize (the \
                                      texture's checked width * C)"
                        )]
                        let at = xi * C + c;
                        texels.get(at).map_or(E::ZERO, |t| E::from_u16(t.to_u16()))
                    } else {
                        E::ZERO
                    };
                    *a = a.plus(v.plus(*v)).plus(t);
                    *v = v.plus(t);
                    *o = *a;
                }
            }
        }
        let storage: &'a [E] = storage;
        let (cols, rows) = storage
            .get(..needed)
            .and_then(|t| t.split_at_checked(ncols))
            .unwrap_or((&[], &[]));
        Ok(TentLines {
            cols,
            rows,
            width: w,
            height: h,
        })
    }

    /// Table bytes as stored (both line tables).
    pub fn table_bytes(&self) -> usize {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "each is the size of a slice, at most isize::MAX: the sum is below usize::MAX"
        )]
        let bytes = core::mem::size_of_val(self.cols) + core::mem::size_of_val(self.rows);
        bytes
    }

    /// Column `i`'s `2 S2` at `Y` (`Y <= h + 1`; 0 at `Y = 0`) in the accumulator `A`, read
    /// counted (an entry past `A` is refused, as in [`TentTable::read`]).
    fn col<A: TentAcc, K: Counter>(&self, i: usize, y: usize, k: &mut K) -> Result<[A; C], Error> {
        let mut out = [A::ZERO; C];
        #[allow(clippy::arithmetic_side_effects, reason = "h < 2^31 (the texture's)")]
        let ymax = self.height + 1;
        if y != 0 && y <= ymax && i < self.width {
            k.reads(1, const { per_channel(E::BITS, C) });
            k.words(const { per_channel(E::BITS, C).div_ceil(32) });
            // i < w, y <= h + 1: inside the table, no overflow.
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "1 <= y <= h + 1 and i < w: inside the w (h + 1) C entries, a count that \
                          fits usize (storage_needed)"
            )]
            let (at, end) = {
                let base = ((y - 1) * self.width + i) * C;
                (base, base + C)
            };
            for (o, &e) in out.iter_mut().zip(self.cols.get(at..end).unwrap_or(&[])) {
                *o = ck(A::from_entry(e))?;
            }
        }
        Ok(out)
    }

    /// Row `j`'s `2 S2` at `X` (`X <= w + 1`; 0 at `X = 0`) in the accumulator `A`, read
    /// counted.
    fn row<A: TentAcc, K: Counter>(&self, x: usize, j: usize, k: &mut K) -> Result<[A; C], Error> {
        let mut out = [A::ZERO; C];
        #[allow(clippy::arithmetic_side_effects, reason = "w < 2^31 (the texture's)")]
        let xmax = self.width + 1;
        if x != 0 && x <= xmax && j < self.height {
            k.reads(1, const { per_channel(E::BITS, C) });
            k.words(const { per_channel(E::BITS, C).div_ceil(32) });
            // j < h, x <= w + 1: inside the table, no overflow.
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "j < h and 1 <= x <= w + 1: inside the (w + 1) h C entries, a count that \
                          fits usize (storage_needed)"
            )]
            let (at, end) = {
                let base = (j * (self.width + 1) + x - 1) * C;
                (base, base + C)
            };
            for (o, &e) in out.iter_mut().zip(self.rows.get(at..end).unwrap_or(&[])) {
                *o = ck(A::from_entry(e))?;
            }
        }
        Ok(out)
    }
}

/// A placed fixed-point footprint: the three positions per axis (units `2^-G`), their axis
/// evaluations, the normaliser `a^2 b^2` (`a`, `b` the half-widths in units `2^-G`) and `G`,
/// `s = 2^G`.
struct Footprint<A: TentAcc> {
    ax: [Axis<A>; 3],
    ay: [Axis<A>; 3],
    px: [A; 3],
    py: [A; 3],
    d: A,
    g: u32,
    s: A,
}

/// The second-difference weights `(1, -2, 1)`.
fn weights<A: TentAcc>() -> [A; 3] {
    [A::ONE, A::from_i64(-2), A::ONE]
}

/// The texel the extended texture shows at integer position `i` (`None`: zero).
fn texel_at<A: TentAcc>(kind: EdgeKind, i: A, n: usize) -> Option<usize> {
    kind.texel_index(i.to_i64()?, n)
}

/// Up to 6 `(index, weight)` pairs: `value = sum weight * f(index)`; index 0 (a zero value) and
/// zero weights are dropped.
#[derive(Debug, Clone, Default)]
struct Terms<A: TentAcc> {
    t: heapless::Vec<(usize, A), 6>,
}

impl<A: TentAcc> Terms<A> {
    fn push(&mut self, idx: usize, w: A) -> Result<(), Error> {
        if w == A::ZERO || idx == 0 {
            return Ok(());
        }
        if let Some(e) = self.t.iter_mut().find(|e| e.0 == idx) {
            e.1 = ck(e.1.checked_add(w))?;
        } else {
            self.t.push((idx, w)).map_err(|_| acc_overflow::<A>())?;
        }
        Ok(())
    }

    fn add_scaled(&mut self, o: &Terms<A>, s: A) -> Result<(), Error> {
        for &(i, w) in &o.t {
            self.push(i, ck(w.checked_mul(s))?)?;
        }
        Ok(())
    }
}

/// How one axis of one point is evaluated.
#[derive(Debug, Clone)]
enum Axis<A: TentAcc> {
    /// The value is 0 (Border, left of the texture): no reads.
    Zero,
    /// Crow's lerp `f(i) s + (f(i+1) - f(i)) a`: 2 reads, 1 multiply, 2 additive operations.
    Crow { i: usize, a: A },
    /// A general weighted sum (weights already scaled by `s`).
    Terms(Terms<A>),
}

/// A line of values `index -> f(index)` that counts its own reads.
type LineFn<'f, A, K, const C: usize> = dyn FnMut(usize, &mut K) -> Result<[A; C], Error> + 'f;

/// Evaluates one axis over `f`; the result is scaled by `s`.
fn eval1<A: TentAcc, const C: usize, K: Counter>(
    ax: &Axis<A>,
    s: A,
    f: &mut LineFn<'_, A, K, C>,
    k: &mut K,
) -> Result<[A; C], Error> {
    let cu = const { per_channel(1, C) };
    let mut out = [A::ZERO; C];
    match ax {
        Axis::Zero => {}
        &Axis::Crow { i, a } => {
            let v0 = f(i, k)?;
            let v1 = f(i.wrapping_add(1), k)?;
            k.muls(cu);
            k.adds(const { per_channel(2, C) });
            for ((o, v0), v1) in out.iter_mut().zip(v0).zip(v1) {
                let d = ck(v1.checked_sub(v0))?;
                *o = ck(ck(v0.checked_mul(s))?.checked_add(ck(d.checked_mul(a))?))?;
            }
        }
        Axis::Terms(t) => {
            // A Terms holds at most 6 terms: the adds below are at most 5 C, a compile-time
            // constant that fits u32.
            let _ = const { per_channel(5, C) };
            let mut used = 0u32;
            for &(idx, w) in &t.t {
                if w == A::ZERO {
                    continue;
                }
                let v = f(idx, k)?;
                if !w.abs_is_power_of_two() {
                    k.muls(cu);
                }
                #[allow(
                    clippy::arithmetic_side_effects,
                    reason = "at most 6 terms (the heapless capacity)"
                )]
                {
                    used += 1;
                }
                for (o, v) in out.iter_mut().zip(v) {
                    *o = ck(o.checked_add(ck(v.checked_mul(w))?))?;
                }
            }
            if used > 1 {
                #[allow(
                    clippy::arithmetic_side_effects,
                    reason = "2 <= used <= 6: (used - 1) C <= 5 C, which fits u32 (the \
                              compile-time per_channel(5, C) above)"
                )]
                let adds = (used - 1) * cu;
                k.adds(adds);
            }
        }
    }
    Ok(out)
}

/// The three integer points `c - a`, `c`, `c + a` of [`TentTable::sample_int`] as terms.
fn int_axes<A: TentAcc>(kind: EdgeKind, c: A, a: A, n: usize) -> Result<[Axis<A>; 3], Error> {
    let x = [ck(c.checked_sub(a))?, c, ck(c.checked_add(a))?];
    Ok([
        Axis::Terms(s2_terms(kind, x[0], n)?),
        Axis::Terms(s2_terms(kind, x[1], n)?),
        Axis::Terms(s2_terms(kind, x[2], n)?),
    ])
}

/// `2 S2_ext(X)` at an integer `X` as terms over the padded line values `s(0..=n+1)`
/// (module docs, "Boundary modes"). Every operation is checked in `A`: a weight past it is
/// [`Error::TooWide`] (`LookupAccumulator`).
fn s2_terms<A: TentAcc>(kind: EdgeKind, x: A, n: usize) -> Result<Terms<A>, Error> {
    if n == 0 {
        // No table has an empty axis; an empty line sums to zero.
        return Ok(Terms::default());
    }
    let nn = ck(A::from_u64(u64_from_usize(n)))?;
    let (one, two) = (A::ONE, A::from_i64(2));
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "n < 2^31 (a texture's side)"
    )]
    let n1 = n + 1;
    let nn1 = ck(nn.checked_add(one))?;
    let mut t = Terms::default();
    match kind {
        EdgeKind::Border => {
            if x <= A::ZERO {
            } else if x <= nn1 {
                t.push(index(x)?, one)?;
            } else {
                t.push(n, ck(nn1.checked_sub(x))?)?;
                t.push(n1, ck(x.checked_sub(nn))?)?;
            }
        }
        EdgeKind::Clamp => {
            if x <= A::ZERO {
                t.push(1, ck(x.checked_mul(x))?)?;
            } else if x <= nn {
                t.push(index(x)?, one)?;
            } else {
                let d = ck(x.checked_sub(nn))?;
                let d2 = ck(d.checked_mul(d))?;
                t.push(n1, ck(d.checked_add(d2))?)?;
                t.push(
                    n,
                    ck(ck(one.checked_sub(d))?.checked_sub(ck(d2.checked_mul(two))?))?,
                )?;
                t.push(n.saturating_sub(1), d2)?;
            }
        }
        EdgeKind::Repeat => {
            // nn >= 1: neither can fail; checked all the same.
            let q = ck(x.checked_div_euclid(nn))?;
            let r = ck(x.checked_rem_euclid(nn))?;
            // q (n (q - 1) + 2 r) is even: n q (q - 1) and 2 q r are (so the division is exact).
            let (q1, r2) = (ck(q.checked_sub(one))?, ck(r.checked_mul(two))?);
            let c1 = ck(q.checked_mul(ck(ck(nn.checked_mul(q1))?.checked_add(r2))?))?;
            let c1 = ck(c1.checked_div_euclid(two))?;
            t.push(n1, c1)?;
            t.push(n, ck(q.checked_sub(c1))?)?;
            t.push(index(r)?, one)?;
        }
        EdgeKind::Mirror => {
            let p = ck(nn.checked_mul(two))?;
            let q = ck(x.checked_div_euclid(p))?;
            let r = ck(x.checked_rem_euclid(p))?;
            let mut c = ck(ck(p.checked_mul(q))?.checked_mul(q))?;
            c = ck(c.checked_add(ck(ck(q.checked_mul(two))?.checked_mul(r))?))?;
            let idx = if r <= nn {
                r
            } else {
                c = ck(c.checked_add(ck(ck(r.checked_sub(nn))?.checked_mul(two))?))?;
                ck(p.checked_sub(r))?
            };
            t.push(n1, c)?;
            t.push(n, ck(A::ZERO.checked_sub(c))?)?;
            t.push(index(idx)?, one)?;
        }
    }
    Ok(t)
}

/// Moves the corners `lo < hi` (units `2^-F`) of one axis by whole texels (clamp) or whole
/// periods (repeat, mirror), in `i64`, to where the centre and the positions are small: the
/// move [`canonical_centre`] makes, done on the corners so that no sum of two `i64` corners is
/// formed first. Returns the moved `lo` (`hi` moves with it); `None` for a Border footprint
/// entirely outside `[0, n]` (a zero sample).
#[allow(
    clippy::arithmetic_side_effects,
    reason = "n < 2^31 and f <= 24: end < 2^55; hi > lo >= i64::MIN, so -hi fits; \
              k = ((-hi) >> f) << f is in [0, -hi], so lo + k is in [lo, hi + k] and \
              hi + k <= 0; lo - end does not overflow (end >= 0) and k' = ((lo - end) >> f) << f \
              is in [0, lo - end], so lo - k' >= end"
)]
fn reduce_corner(kind: EdgeKind, lo: i64, hi: i64, n: usize, f: u32) -> Option<i64> {
    let end = i64::try_from(u64_from_usize(n)).ok()? << f;
    match kind {
        EdgeKind::Border => {
            if hi <= 0 || lo >= end {
                None
            } else {
                Some(lo)
            }
        }
        EdgeKind::Clamp => {
            if hi <= 0 {
                Some(lo + (((-hi) >> f) << f))
            } else if lo >= end {
                Some(lo - (((lo - end) >> f) << f))
            } else {
                Some(lo)
            }
        }
        // end = 0 only on an empty axis (no table has one): a zero sample.
        EdgeKind::Repeat => lo.checked_rem_euclid(end),
        EdgeKind::Mirror => lo.checked_rem_euclid(end.checked_mul(2)?),
    }
}

/// Moves the centre `c` (units `2^-g`, half-width `a`) to an equivalent position with small
/// weights (module docs); `None` for a Border footprint entirely outside `[0, n]`.
fn canonical_centre<A: TentAcc>(
    kind: EdgeKind,
    c: A,
    a: A,
    n: usize,
    g: u32,
) -> Result<Option<A>, Error> {
    let end = ck(ck(A::from_u64(u64_from_usize(n)))?.checked_shl(g))?;
    let (hi, lo) = (ck(c.checked_add(a))?, ck(c.checked_sub(a))?);
    Ok(match kind {
        EdgeKind::Border => {
            if hi <= A::ZERO || lo >= end {
                None
            } else {
                Some(c)
            }
        }
        EdgeKind::Clamp => {
            if hi <= A::ZERO {
                let k = ck(ck(A::ZERO.checked_sub(hi))?.floor_shr(g).checked_shl(g))?;
                Some(ck(c.checked_add(k))?)
            } else if lo >= end {
                let k = ck(ck(lo.checked_sub(end))?.floor_shr(g).checked_shl(g))?;
                Some(ck(c.checked_sub(k))?)
            } else {
                Some(c)
            }
        }
        // end = 0 only on an empty axis (no table has one): a zero sample.
        EdgeKind::Repeat => c.checked_rem_euclid(end),
        EdgeKind::Mirror => c.checked_rem_euclid(ck(end.checked_mul(A::from_i64(2)))?),
    })
}

/// The paper (bilinear) evaluation of one axis at `x` (units `2^-g`).
fn axis_paper<A: TentAcc>(kind: EdgeKind, x: A, n: usize, g: u32) -> Result<Axis<A>, Error> {
    let s = ck(A::ONE.checked_shl(g))?;
    let i = x.floor_shr(g);
    let a = ck(x.checked_sub(ck(i.checked_shl(g))?))?;
    let nn = ck(A::from_u64(u64_from_usize(n)))?;
    Ok(match kind {
        EdgeKind::Border => {
            if i < A::ZERO {
                Axis::Zero
            } else if i > nn {
                // Linear beyond n: the lerp of cell n with an extended fraction is exact.
                Axis::Crow {
                    i: n,
                    a: ck(x.checked_sub(ck(nn.checked_shl(g))?))?,
                }
            } else {
                Axis::Crow { i: index(i)?, a }
            }
        }
        _ => {
            if A::ZERO <= i && i < nn {
                Axis::Crow { i: index(i)?, a }
            } else if i == nn && a == A::ZERO {
                Axis::Crow {
                    i: n.saturating_sub(1),
                    a: s,
                }
            } else {
                let mut t = Terms::default();
                t.add_scaled(&s2_terms(kind, i, n)?, ck(s.checked_sub(a))?)?;
                t.add_scaled(&s2_terms(kind, ck(i.checked_add(A::ONE))?, n)?, a)?;
                Axis::Terms(t)
            }
        }
    })
}

/// A line index `0 <= i <= n + 1` (`n` a texture's side, below `2^31`) as `usize`: every caller
/// has compared `i` with `0` and `n + 1` (or `n`); anything else is refused, never wrapped.
#[inline(always)]
fn index<A: TentAcc>(i: A) -> Result<usize, Error> {
    i.to_i64()
        .and_then(|v| usize::try_from(v).ok())
        .ok_or_else(acc_overflow::<A>)
}

// ---------------------------------------------------------------------------------------------
// The width proof of the i64 lookups (module docs, "How wide the lookups compute")

/// Refuses a lookup whose worst case `bound` (`None`: at least `2^64`) could pass the
/// accumulator: [`Error::TooWide`] (`LookupAccumulator`, `bits_needed` the bound's bits, 65
/// for `None`: a lower bound). Only where `A` proves first (`i64`); `bound` is not even
/// computed for `i128`.
#[inline(always)]
fn prove<A: TentAcc>(bound: impl FnOnce() -> Option<u64>) -> Result<(), Error> {
    if !A::PROVES_FIRST {
        return Ok(());
    }
    let bits = bound().map_or(65, bits_of_u64);
    if bits > A::BITS_AVAILABLE {
        return Err(Error::TooWide {
            what: Quantity::LookupAccumulator,
            bits_needed: bits,
            bits_available: A::BITS_AVAILABLE,
        });
    }
    Ok(())
}

/// What the width proofs know of a table before reading it: its largest texel `m` and its
/// sides. Per axis `sum_{i < min(X, n)} (2X - 2i - 1) = k (2X - k)` with `k = min(X, n)`
/// ([`line_max`]), so every stored value is bounded where it is read: `Q(X, Y) <= m
/// line_max(w, X) line_max(h, Y)`, a column's `2 S2` at `Y` by `m line_max(h, Y)`, a row's at
/// `X` by `m line_max(w, X)`. Reached by the all-`m` texture.
#[derive(Debug, Clone, Copy)]
struct Worst {
    m: u64,
    w: usize,
    h: usize,
}

/// `k (2X - k)`, `k = min(X, n)`: the largest `2 S2(X)` of a line of `n` texels of value 1
/// (`X <= n + 1 < 2^31 + 1`, so exact; saturating past that, which no index reaches).
fn line_max(n: usize, x: usize) -> u64 {
    let (n, x) = (u64_from_usize(n), u64_from_usize(x));
    let k = x.min(n);
    k.saturating_mul(x.saturating_mul(2).saturating_sub(k))
}

/// `(M, nonneg)`: every intermediate of [`eval1`] over `ax` and its result are at most `M V` in
/// magnitude for inputs `|f(i)| <= V line_max(n, i)`, and the result is non-negative if
/// `nonneg` (given non-negative inputs if `nonneg_in`). With `b_i = line_max(n, i)`: Crow's
/// lerp `v0 s + (v1 - v0) a` with `0 <= a <= s` on non-negative inputs, `M = s max(b_i,
/// b_(i+1))`, non-negative; otherwise `M = b_i s + (b_i + b_(i+1)) |a|`. Terms: `M = sum |w|
/// b_idx`, non-negative when every weight is and the inputs are. `None`: past `u64`.
fn axis_mass<A: TentAcc>(ax: &Axis<A>, s: u64, nonneg_in: bool, n: usize) -> Option<(u64, bool)> {
    match ax {
        Axis::Zero => Some((0, true)),
        &Axis::Crow { i, a } => {
            let au = a.abs_u64()?;
            let (b0, b1) = (line_max(n, i), line_max(n, i.saturating_add(1)));
            if nonneg_in && a >= A::ZERO && au <= s {
                Some((s.checked_mul(b0.max(b1))?, true))
            } else {
                let d = b0.checked_add(b1)?.checked_mul(au)?;
                Some((b0.checked_mul(s)?.checked_add(d)?, false))
            }
        }
        Axis::Terms(t) => {
            let mut m = 0u64;
            let mut nonneg = nonneg_in;
            for &(idx, w) in &t.t {
                nonneg &= w >= A::ZERO;
                m = m.checked_add(w.abs_u64()?.checked_mul(line_max(n, idx))?)?;
            }
            Some((m, nonneg))
        }
    }
}

/// The largest partial sum or product of the second difference `v0 - 2 v1 + v2` over inputs of
/// magnitude at most `v[p]`: `max(2 v1, v0 + v2)` when the inputs are non-negative, else
/// `v0 + 2 v1 + v2`. `None`: past `u64`.
fn comb(v: [u64; 3], nonneg: bool) -> Option<u64> {
    let [v0, v1, v2] = v;
    if nonneg {
        Some(v1.checked_mul(2)?.max(v0.checked_add(v2)?))
    } else {
        v0.checked_add(v1.checked_mul(2)?)?.checked_add(v2)
    }
}

/// The worst case over textures of every intermediate of [`TentTable::paper_numerator`] for
/// the placed axes: per point `V(p, q) = m M_x(p) M_y(q)` ([`axis_mass`] over the table's
/// columns, then its rows), per row `R(q) = comb(V(., q))`, in all `comb(R)` ([`comb`]). At
/// most `8 s^2 Q_max` inside the table (Crow's lerps, `a < s`; `Q_max = m w (w + 2) h (h + 2)`,
/// [`tent_entry_bits`]).
fn paper_bound<A: TentAcc>(ax: &[Axis<A>; 3], ay: &[Axis<A>; 3], s: u64, t: Worst) -> Option<u64> {
    let mut mx = [(0u64, true); 3];
    for (m, axp) in mx.iter_mut().zip(ax) {
        *m = axis_mass(axp, s, true, t.w)?;
    }
    let mut rows = [0u64; 3];
    for (row, ayq) in rows.iter_mut().zip(ay) {
        let mut v = [0u64; 3];
        let mut nonneg = true;
        for (vp, &(m, nonneg_p)) in v.iter_mut().zip(&mx) {
            let (my, nonneg_q) = axis_mass(ayq, s, nonneg_p, t.h)?;
            *vp = t.m.checked_mul(m)?.checked_mul(my)?;
            nonneg &= nonneg_q;
        }
        *row = comb(v, nonneg)?;
    }
    comb(rows, false)
}

/// The worst case over textures of every intermediate of [`TentTable::sample_exact_raw`]:
/// `hi + mid + st` plus the small line and texel sums, with `hi = P s^2` (`P` the
/// [`paper_bound`]), `mid = (X sa + Y sb) s` (`X`, `Y` the bounds of the line tables' second
/// differences; `sa = sum |w_p| α_p(1-α_p)`, `sb` likewise), `st = m_t sb sa` (`m_t` the
/// texture's largest texel). At most `12 s^4 Q_max + m_t s^4` and a little inside the table.
fn exact_bound<A: TentAcc>(
    fp: &Footprint<A>,
    pa: &[A; 3],
    pb: &[A; 3],
    t: Worst,
    m_t: u64,
) -> Option<u64> {
    let s = fp.s.abs_u64()?;
    let hi = paper_bound(&fp.ax, &fp.ay, s, t)?.checked_mul(s.checked_mul(s)?)?;
    let line = |axes: &[Axis<A>; 3], n: usize| -> Option<u64> {
        let mut v = [0u64; 3];
        let mut nonneg = true;
        for (vp, axp) in v.iter_mut().zip(axes) {
            let (mass, nonneg_p) = axis_mass(axp, s, true, n)?;
            *vp = t.m.checked_mul(mass)?;
            nonneg &= nonneg_p;
        }
        comb(v, nonneg)
    };
    let weighted = |f: &[A; 3]| -> Option<u64> {
        let [f0, f1, f2] = f.map(|v| v.abs_u64());
        f0?.checked_add(f1?.checked_mul(2)?)?.checked_add(f2?)
    };
    // Columns are second differences in y (the y axes), rows in x.
    let (x, y) = (line(&fp.ay, t.h)?, line(&fp.ax, t.w)?);
    let (sa, sb) = (weighted(pa)?, weighted(pb)?);
    let mid = x
        .checked_mul(sa)?
        .checked_add(y.checked_mul(sb)?)?
        .checked_mul(s)?;
    let inner = m_t.checked_mul(sb)?;
    let st = inner.checked_mul(sa)?;
    hi.checked_add(mid)?
        .checked_add(st)?
        .checked_add(x)?
        .checked_add(y)?
        .checked_add(inner)
}

/// Per channel `round(N * 2^shift / d)` with `d = a^2 b^2` (negative `N` gives 0), counting
/// `a^2`, `b^2`, `a^2 b^2` and one divide per channel.
fn finish<A: TentAcc, const C: usize, K: Counter>(
    n: &[A; C],
    d: A,
    shift: u32,
    k: &mut K,
) -> Result<Sample<C>, Error> {
    k.muls(3);
    let mut out = [0u64; C];
    for (o, &n) in out.iter_mut().zip(n) {
        k.divs(1);
        // Clamped to >= 0.
        *o = A::div_round_shift(n.max(A::ZERO), shift, d)?;
    }
    Ok(Sample { values: out })
}

/// The crate's rounded divisions ([`crate::wide`], one implementation per word width): the
/// `i128` accumulator's and the `i64` accumulator's.
pub(crate) use crate::wide::{div_round_shift_u128 as div_round_shift, div_round_shift_u64};

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
    use crate::edge::{Border, ClampToEdge, MirroredRepeat, Repeat};
    use crate::{NoCount, Tally};
    use fixed::types::{I16F16, I24F8, I28F4};
    use std::format;
    use std::vec;
    use std::vec::Vec;

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *seed >> 33
    }

    /// `2 s^2 R_i(x)`: the second integral of texel `i`'s indicator at `x` (units `2^-g`).
    fn r2(i: i128, x: i128, g: u32) -> i128 {
        let s = 1i128 << g;
        let d = x - i * s;
        if d <= 0 {
            0
        } else if d <= s {
            d * d
        } else {
            2 * d * s - s * s
        }
    }

    /// Direct convolution: `N = sum_ij t_ext(i, j) WX_i WY_j` with per-texel weights scaled by
    /// `2 s^2` each; the exact output is `round(N 2^14 / (a^2 b^2))`.
    fn direct<M: EdgeMode>(
        mode: M,
        tex: &[u8],
        w: usize,
        h: usize,
        c: (i128, i128),
        ab: (i128, i128),
        g: u32,
    ) -> u64 {
        let s = 1i128 << g;
        let wts = |cc: i128, a: i128| -> Vec<(i128, i128)> {
            let lo = ((cc - a) >> g) - 1;
            let hi = ((cc + a) >> g) + 1;
            (lo..=hi)
                .map(|i| (i, r2(i, cc + a, g) - 2 * r2(i, cc, g) + r2(i, cc - a, g)))
                .filter(|&(_, v)| v != 0)
                .collect()
        };
        let _ = s;
        let (wx, wy) = (wts(c.0, ab.0), wts(c.1, ab.1));
        let mut n = 0i128;
        for &(j, vy) in &wy {
            let Some(jj) = mode.kind().texel_index(j as i64, h) else {
                continue;
            };
            for &(i, vx) in &wx {
                let Some(ii) = mode.kind().texel_index(i as i64, w) else {
                    continue;
                };
                n += tex[jj * w + ii] as i128 * vx * vy;
            }
        }
        div_round_shift(n as u128, 14, (ab.0 * ab.0 * ab.1 * ab.1) as u128).unwrap()
    }

    fn tex(w: usize, h: usize, seed: u64) -> Vec<u8> {
        let mut s = seed;
        (0..w * h).map(|_| lcg(&mut s) as u8).collect()
    }

    #[test]
    fn table_matches_formula() {
        for (w, h) in [(1, 1), (1, 5), (5, 1), (3, 4), (7, 5)] {
            let t = tex(w, h, 7);
            let texture = Texture::<u8>::new(&t, w, h).unwrap();
            let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
            let tt = TentTable::build(&texture, &mut st).unwrap();
            for y in 0..=h + 1 {
                for x in 0..=w + 1 {
                    let mut want = 0u64;
                    for j in 0..h.min(y) {
                        for i in 0..w.min(x) {
                            want += (2 * (x - i) as u64 - 1)
                                * (2 * (y - j) as u64 - 1)
                                * t[j * w + i] as u64;
                        }
                    }
                    assert_eq!(tt.corner(x, y).unwrap()[0], want, "{w}x{h} at {x},{y}");
                }
            }
        }
    }

    fn every_int<M: EdgeMode>(mode: M) {
        for (w, h) in [(1, 1), (1, 4), (4, 1), (3, 5), (5, 3)] {
            let t = tex(w, h, (w * 10 + h) as u64);
            let texture = Texture::<u8>::new(&t, w, h).unwrap();
            let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
            let tt = TentTable::build(&texture, &mut st).unwrap();
            // Every centre from 8 texels before to 8 past the texture, every half-width 1..=7
            // and 1, 2, 5; under Miri (about 10^4 times slower) two of them per size: the
            // widest tent across the top-left corner, a narrow one on the right edge.
            let (wi, hi) = (w as i32, h as i32);
            let cases: Vec<(i32, i32, u32, u32)> = if cfg!(miri) {
                vec![(-1, -1, 7, 5), (wi, hi / 2, 2, 1)]
            } else {
                (-8i32..=wi + 8)
                    .flat_map(|cx| (-7i32..=hi + 7).map(move |cy| (cx, cy)))
                    .flat_map(|(cx, cy)| (1u32..=7).map(move |a| (cx, cy, a)))
                    .flat_map(|(cx, cy, a)| [1u32, 2, 5].map(|b| (cx, cy, a, b)))
                    .collect()
            };
            for (cx, cy, a, b) in cases {
                let got = tt.sample_int(cx, cy, a, b, mode, &mut NoCount).unwrap();
                let want = direct(
                    mode,
                    &t,
                    w,
                    h,
                    (cx as i128, cy as i128),
                    (a as i128, b as i128),
                    0,
                );
                assert_eq!(
                    got.values[0],
                    want,
                    "{} {w}x{h} c=({cx},{cy}) a={a} b={b}",
                    mode.kind().name()
                );
            }
        }
    }

    #[test]
    fn integer_exact_every_mode() {
        every_int(Border);
        every_int(ClampToEdge);
        every_int(Repeat);
        every_int(MirroredRepeat);
        // The run-time mode is the same lookup (one description of a mode: EdgeMode::kind);
        // under Miri (about 10^4 times slower) the static modes above only.
        for kind in EdgeKind::ALL.into_iter().filter(|_| !cfg!(miri)) {
            every_int(kind);
        }
    }

    #[test]
    fn div_round_shift_refuses_a_zero_divisor() {
        // Regression: a zero divisor was a division panic path; now a typed error.
        assert_eq!(div_round_shift(5, 3, 0), Err(Error::ZeroArea));
        assert_eq!(div_round_shift(5, 1, 2), Ok(5));
        assert_eq!(
            s2_terms(EdgeKind::Repeat, 7i128, 0).map(|t| t.t.len()),
            Ok(0)
        );
        assert_eq!(div_round_shift_u64(5, 3, 0), Err(Error::ZeroArea));
        assert_eq!(canonical_centre(EdgeKind::Mirror, 7i64, 1, 0, 3), Ok(None));
        assert_eq!(canonical_centre(EdgeKind::Mirror, 7i128, 1, 0, 3), Ok(None));
        assert_eq!(reduce_corner(EdgeKind::Mirror, 7, 9, 0, 3), None);
    }

    fn exact_random<M: EdgeMode>(mode: M) {
        let mut seed = 99u64;
        for (w, h) in [(1, 1), (1, 6), (6, 1), (5, 4), (9, 7)] {
            let t = tex(w, h, (w * 3 + h) as u64);
            let texture = Texture::<u8>::new(&t, w, h).unwrap();
            let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
            let tt = TentTable::build(&texture, &mut st).unwrap();
            let mut ls = vec![0u64; TentLines::<u64>::storage_needed(w, h).unwrap()];
            let lines = TentLines::build(&texture, &mut ls).unwrap();
            // Under Miri (about 10^4 times slower) 1 random box per texture and mode.
            for _ in 0..if cfg!(miri) { 1 } else { 400 } {
                let span = 16 * 4 * (w.max(h) as i64 + 4);
                let x0 = -2 * span / 3 + (lcg(&mut seed) as i64 % span);
                let y0 = -2 * span / 3 + (lcg(&mut seed) as i64 % span);
                let x1 = x0 + 1 + (lcg(&mut seed) as i64 % (span / 2));
                let y1 = y0 + 1 + (lcg(&mut seed) as i64 % (span / 2));
                let r = Rect::new(
                    I28F4::from_bits(x0 as i32),
                    I28F4::from_bits(y0 as i32),
                    I28F4::from_bits(x1 as i32),
                    I28F4::from_bits(y1 as i32),
                );
                let got = tt
                    .sample_exact(&lines, &texture, &r, mode, &mut NoCount)
                    .unwrap();
                let want = direct(
                    mode,
                    &t,
                    w,
                    h,
                    ((x0 + x1) as i128, (y0 + y1) as i128),
                    ((x1 - x0) as i128, (y1 - y0) as i128),
                    5,
                );
                assert_eq!(got.values[0], want, "{} {w}x{h} {r:?}", mode.kind().name());
                // Paper within its bound of the exact value.
                let p = tt.sample(&r, mode, &mut NoCount).unwrap();
                let a = (x1 - x0) as f64 / 32.0;
                let b = (y1 - y0) as f64 / 32.0;
                let bound = paper_error_bound(8, a, b) + 2.0 / 65536.0;
                let err = (p.values[0] as f64 - got.values[0] as f64).abs() / 65536.0;
                assert!(
                    err <= bound,
                    "{} paper err {err} > {bound} for {r:?}",
                    mode.kind().name()
                );
            }
        }
    }

    #[test]
    fn exact_matches_direct_every_mode() {
        exact_random(Border);
        exact_random(ClampToEdge);
        exact_random(Repeat);
        exact_random(MirroredRepeat);
    }

    #[test]
    fn costs_9_4_and_36_31() {
        let (w, h) = (16, 16);
        let t = tex(w, h, 3);
        let texture = Texture::<u8>::new(&t, w, h).unwrap();
        let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
        let tt = TentTable::build(&texture, &mut st).unwrap();
        let mut k = Tally::new();
        tt.sample_int(8, 7, 3, 4, Border, &mut k).unwrap();
        assert_eq!(
            (k.reads, k.muls, k.divs, k.multiplicative(), k.adds),
            (9, 3, 1, 4, 8)
        );
        let mut k = Tally::new();
        let r = Rect::new(
            I24F8::from_num(3.3),
            I24F8::from_num(4.1),
            I24F8::from_num(9.7),
            I24F8::from_num(8.6),
        );
        tt.sample(&r, Border, &mut k).unwrap();
        assert_eq!(
            (k.reads, k.muls, k.divs, k.multiplicative(), k.adds),
            (36, 30, 1, 31, 62)
        );
        let mut ls = vec![0u64; TentLines::<u64>::storage_needed(w, h).unwrap()];
        let lines = TentLines::build(&texture, &mut ls).unwrap();
        let mut k = Tally::new();
        let e64 = tt
            .sample_exact(&lines, &texture, &r, Border, &mut k)
            .unwrap();
        assert_eq!((k.reads, k.muls, k.divs), (81, 72, 1));
        // Narrower line tables give the same result.
        let mut ls32 = vec![0u32; TentLines::<u32>::storage_needed(w, h).unwrap()];
        let lines32 = TentLines::build(&texture, &mut ls32).unwrap();
        let e32 = tt
            .sample_exact(&lines32, &texture, &r, Border, &mut NoCount)
            .unwrap();
        assert_eq!(e32, e64);
        // Same counts in every mode for an interior footprint.
        let mut k2 = Tally::new();
        tt.sample(&r, MirroredRepeat, &mut k2).unwrap();
        assert_eq!((k2.reads, k2.multiplicative()), (36, 31));
    }

    #[test]
    fn paper_error_bound_is_approached() {
        // Columns i-a and i+a full, column i empty, centre on a texel centre: every fraction is
        // 1/2 and the error is m / (4 a^2) (b large, ClampToEdge makes the columns infinite).
        let (w, h) = (9usize, 3usize);
        for a in 1..=4i32 {
            let mut t = vec![0u8; w * h];
            for y in 0..h {
                t[y * w + (4 - a) as usize] = 255;
                t[y * w + (4 + a) as usize] = 255;
            }
            let texture = Texture::<u8>::new(&t, w, h).unwrap();
            let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
            let tt = TentTable::build(&texture, &mut st).unwrap();
            let mut ls = vec![0u64; TentLines::<u64>::storage_needed(w, h).unwrap()];
            let lines = TentLines::build(&texture, &mut ls).unwrap();
            let b = 400.0;
            let r = Rect::new(
                I24F8::from_num(4.5 - a as f64),
                I24F8::from_num(1.5 - b),
                I24F8::from_num(4.5 + a as f64),
                I24F8::from_num(1.5 + b),
            );
            let p = tt.sample(&r, ClampToEdge, &mut NoCount).unwrap().values[0] as f64;
            let e = tt
                .sample_exact(&lines, &texture, &r, ClampToEdge, &mut NoCount)
                .unwrap()
                .values[0] as f64;
            let err = (p - e) / 65536.0;
            let bound = paper_error_bound(8, a as f64, b);
            let sep = 255.0 / (4.0 * (a * a) as f64);
            assert!((err - sep).abs() < 2.0 / 65536.0, "a={a}: {err} vs {sep}");
            assert!(
                err <= bound && err >= 0.99 * bound,
                "a={a}: {err} vs bound {bound}"
            );
        }
    }

    #[test]
    fn integer_footprints_agree() {
        // A rectangle with even integer sides has an integer centre: paper = exact = integer.
        let (w, h) = (7, 6);
        let t = tex(w, h, 5);
        let texture = Texture::<u8>::new(&t, w, h).unwrap();
        let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
        let tt = TentTable::build(&texture, &mut st).unwrap();
        let mut ls = vec![0u64; TentLines::<u64>::storage_needed(w, h).unwrap()];
        let lines = TentLines::build(&texture, &mut ls).unwrap();
        let r = Rect::new(
            I16F16::from_num(1),
            I16F16::from_num(0),
            I16F16::from_num(5),
            I16F16::from_num(6),
        );
        let a = tt.sample_int(3, 3, 2, 3, Repeat, &mut NoCount).unwrap();
        let b = tt.sample(&r, Repeat, &mut NoCount).unwrap();
        let c = tt
            .sample_exact(&lines, &texture, &r, Repeat, &mut NoCount)
            .unwrap();
        assert_eq!(a, b);
        assert_eq!(a, c);
    }

    #[test]
    fn constant_texture_is_reproduced() {
        let (w, h) = (5, 4);
        let t = vec![200u8; w * h];
        let texture = Texture::<u8>::new(&t, w, h).unwrap();
        let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
        let tt = TentTable::build(&texture, &mut st).unwrap();
        let mut ls = vec![0u64; TentLines::<u64>::storage_needed(w, h).unwrap()];
        let lines = TentLines::build(&texture, &mut ls).unwrap();
        let r = Rect::new(
            I24F8::from_num(-3.3),
            I24F8::from_num(1.1),
            I24F8::from_num(40.7),
            I24F8::from_num(2.6),
        );
        for v in [
            tt.sample_exact(&lines, &texture, &r, ClampToEdge, &mut NoCount)
                .unwrap(),
            tt.sample_exact(&lines, &texture, &r, Repeat, &mut NoCount)
                .unwrap(),
            tt.sample_exact(&lines, &texture, &r, MirroredRepeat, &mut NoCount)
                .unwrap(),
        ] {
            assert_eq!(v.values[0], 200 << 16);
        }
    }

    #[test]
    fn widths_and_refusals() {
        // u64 at 8-bit texels: 16399 x 16399 fits, 16400 x 16400 does not; 16-bit: 4095.
        assert_eq!(tent_entry_bits(8, 16399, 16399), 64);
        // The limb computation against the saturating u128 one, across sizes and texel widths
        // (past 128 bits both say 128).
        let sides = [
            0usize,
            1,
            2,
            3,
            255,
            256,
            4095,
            4096,
            16_399,
            16_400,
            65_535,
            (1 << 31) - 1,
            usize::MAX / 2,
            usize::MAX - 2,
            usize::MAX,
        ];
        for b in [0, 1, 8, 16, 33, 63, 64, 65, 127, 128, 200] {
            for &w in &sides {
                assert_eq!(tent_line_bits(b, w), line_bits_u128(b, w), "{b} {w}");
                for &h in &sides {
                    assert_eq!(
                        tent_entry_bits(b, w, h),
                        entry_bits_u128(b, w, h),
                        "{b} {w} {h}"
                    );
                }
            }
        }
        assert_eq!(tent_entry_bits(8, 16400, 16400), 65);
        assert_eq!(tent_entry_bits(16, 4095, 4095), 64);
        assert_eq!(tent_entry_bits(16, 4096, 4096), 65);
        assert_eq!(tent_entry_bits(8, 256, 256), 41);
        assert_eq!(tent_line_bits(8, 256), 25);
        let texture = Texture::<u16>::new(&[0u16; 64 * 64], 64, 64).unwrap();
        let mut st = vec![0u32; TentTable::<u32>::storage_needed(64, 64).unwrap()];
        assert_eq!(
            TentTable::build(&texture, &mut st).err(),
            Some(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: tent_entry_bits(16, 64, 64),
                bits_available: 32
            })
        );
        assert!(st.iter().all(|&v| v == 0));
        let mut st = vec![0u128; TentTable::<u128>::storage_needed(64, 64).unwrap()];
        assert!(TentTable::build(&texture, &mut st).is_ok());
        let mut short = vec![0u64; 10];
        assert!(matches!(
            TentTable::build(&texture, &mut short),
            Err(Error::StorageTooSmall { .. })
        ));
        // Memory: 8-bit 256 x 256 in u64, 8 (n + 1)^2 / n^2 = 8.06 bytes per texel. Under Miri
        // (about 10^4 times slower) 64 x 64, 8 (65 / 64)^2 = 8.25.
        let (n, per_texel) = if cfg!(miri) { (64, 8.25) } else { (256, 8.06) };
        let t = vec![1u8; n * n];
        let texture = Texture::<u8>::new(&t, n, n).unwrap();
        let mut st = vec![0u64; TentTable::<u64>::storage_needed(n, n).unwrap()];
        let tt = TentTable::build(&texture, &mut st).unwrap();
        let ratio = tt.table_bytes() as f64 / (n * n) as f64;
        assert!((ratio - per_texel).abs() < 0.01, "{ratio}");
    }

    #[test]
    fn channels_u128_and_16_bit() {
        // Two channels of 16-bit texels in u128 entries agree with each channel alone in u64.
        let (w, h) = (5usize, 3usize);
        let mut seed = 11u64;
        let t: Vec<u16> = (0..w * h * 2).map(|_| lcg(&mut seed) as u16).collect();
        let texture = Texture::<u16, 2>::new(&t, w, h).unwrap();
        let mut st = vec![0u128; TentTable::<u128, 2>::storage_needed(w, h).unwrap()];
        let tt = TentTable::build(&texture, &mut st).unwrap();
        let mut ls = vec![0u128; TentLines::<u128, 2>::storage_needed(w, h).unwrap()];
        let lines = TentLines::build(&texture, &mut ls).unwrap();
        let r = Rect::new(
            I24F8::from_num(-0.7),
            I24F8::from_num(0.3),
            I24F8::from_num(4.1),
            I24F8::from_num(2.9),
        );
        let mut k = Tally::new();
        let both = tt
            .sample_exact(&lines, &texture, &r, MirroredRepeat, &mut k)
            .unwrap();
        let both_p = tt.sample(&r, MirroredRepeat, &mut NoCount).unwrap();
        for c in 0..2 {
            let ch: Vec<u16> = t.iter().skip(c).step_by(2).copied().collect();
            let tex1 = Texture::<u16>::new(&ch, w, h).unwrap();
            let mut st1 = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
            let t1 = TentTable::build(&tex1, &mut st1).unwrap();
            let mut ls1 = vec![0u64; TentLines::<u64>::storage_needed(w, h).unwrap()];
            let l1 = TentLines::build(&tex1, &mut ls1).unwrap();
            let one = t1
                .sample_exact(&l1, &tex1, &r, MirroredRepeat, &mut NoCount)
                .unwrap();
            assert_eq!(both.values[c], one.values[0]);
            let one_p = t1.sample(&r, MirroredRepeat, &mut NoCount).unwrap();
            assert_eq!(both_p.values[c], one_p.values[0]);
        }
        // Mismatched lines are refused.
        let mut ls2 = vec![0u128; TentLines::<u128, 2>::storage_needed(w, h + 1).unwrap()];
        let t2: Vec<u16> = vec![0; w * (h + 1) * 2];
        let tex2 = Texture::<u16, 2>::new(&t2, w, h + 1).unwrap();
        let lines2 = TentLines::build(&tex2, &mut ls2).unwrap();
        assert!(matches!(
            tt.sample_exact(&lines2, &texture, &r, Border, &mut NoCount),
            Err(Error::RowLength { .. })
        ));
    }

    #[test]
    fn errors_and_degenerate() {
        let t = [1u8, 2, 3, 4];
        let texture = Texture::<u8>::new(&t, 2, 2).unwrap();
        let mut st = [0u64; 9];
        let tt = TentTable::build(&texture, &mut st).unwrap();
        assert_eq!(
            tt.sample_int(0, 0, 0, 1, Border, &mut NoCount),
            Err(Error::ZeroArea)
        );
        let inv = Rect::new(I24F8::ONE, I24F8::ZERO, I24F8::ZERO, I24F8::ONE);
        assert_eq!(
            tt.sample(&inv, Border, &mut NoCount),
            Err(Error::InvertedBox)
        );
        let zero = Rect::new(I24F8::ONE, I24F8::ZERO, I24F8::ONE, I24F8::ONE);
        assert_eq!(tt.sample(&zero, Border, &mut NoCount), Err(Error::ZeroArea));
        // Far outside under Border: 0 with no reads.
        let mut k = Tally::new();
        let far = tt.sample_int(i32::MIN, 0, 3, 3, Border, &mut k).unwrap();
        assert_eq!((far.values[0], k.reads), (0, 0));
        // Huge footprints: a value or a typed refusal, never a panic.
        for mode_i in 0..4 {
            let r = Rect::new(I24F8::MIN, I24F8::MIN, I24F8::MAX, I24F8::MAX);
            let res = match mode_i {
                0 => tt.sample(&r, Border, &mut NoCount),
                1 => tt.sample(&r, ClampToEdge, &mut NoCount),
                2 => tt.sample(&r, Repeat, &mut NoCount),
                _ => tt.sample(&r, MirroredRepeat, &mut NoCount),
            };
            let _ = res;
            let res = match mode_i {
                0 => tt.sample_int(i32::MAX, i32::MIN, u32::MAX, u32::MAX, Border, &mut NoCount),
                1 => tt.sample_int(
                    i32::MAX,
                    i32::MIN,
                    u32::MAX,
                    u32::MAX,
                    ClampToEdge,
                    &mut NoCount,
                ),
                2 => tt.sample_int(i32::MAX, i32::MIN, u32::MAX, u32::MAX, Repeat, &mut NoCount),
                _ => tt.sample_int(
                    i32::MAX,
                    i32::MIN,
                    u32::MAX,
                    u32::MAX,
                    MirroredRepeat,
                    &mut NoCount,
                ),
            };
            let _ = res;
        }
    }

    // --- u32 tables: i64 lookups, the width proof and its refusals ----------------------------

    std::thread_local! {
        /// The largest magnitude (bits) a [`Track`] operation has produced on this thread.
        static PEAK: core::cell::Cell<u32> = const { core::cell::Cell::new(0) };
    }

    /// An `i128` accumulator that records the bits of every checked result ([`PEAK`]): what a
    /// lookup really needs, to compare with the width proof's bound.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
    struct Track(i128);

    impl sealed::Sealed for Track {}

    fn seen(v: Option<i128>) -> Option<Track> {
        if let Some(x) = v {
            PEAK.with(|p| p.set(p.get().max(bits_of(x.unsigned_abs()))));
        }
        v.map(Track)
    }

    impl TentAcc for Track {
        const BITS_AVAILABLE: u32 = 127;
        const PROVES_FIRST: bool = false;
        const ZERO: Self = Track(0);
        const ONE: Self = Track(1);
        fn from_i64(v: i64) -> Self {
            Track(i128::from(v))
        }
        fn from_u64(v: u64) -> Option<Self> {
            Some(Track(i128::from(v)))
        }
        fn from_entry<L: TentEntry>(e: L) -> Option<Self> {
            Some(Track(e.to_i128()))
        }
        fn checked_add(self, o: Self) -> Option<Self> {
            seen(self.0.checked_add(o.0))
        }
        fn checked_sub(self, o: Self) -> Option<Self> {
            seen(self.0.checked_sub(o.0))
        }
        fn checked_mul(self, o: Self) -> Option<Self> {
            seen(self.0.checked_mul(o.0))
        }
        fn checked_div_euclid(self, o: Self) -> Option<Self> {
            seen(self.0.checked_div_euclid(o.0))
        }
        fn checked_rem_euclid(self, o: Self) -> Option<Self> {
            seen(self.0.checked_rem_euclid(o.0))
        }
        fn checked_shl(self, g: u32) -> Option<Self> {
            seen(TentAcc::checked_shl(self.0, g))
        }
        fn floor_shr(self, g: u32) -> Self {
            Track(self.0.floor_shr(g))
        }
        fn to_i64(self) -> Option<i64> {
            TentAcc::to_i64(self.0)
        }
        fn abs_u64(self) -> Option<u64> {
            self.0.abs_u64()
        }
        fn abs_is_power_of_two(self) -> bool {
            self.0.abs_is_power_of_two()
        }
        fn normaliser(a: u64, b: u64) -> Result<Self, Error> {
            <i128 as TentAcc>::normaliser(a, b).map(Track)
        }
        fn div_round_shift(num: Self, shift: u32, den: Self) -> Result<u64, Error> {
            <i128 as TentAcc>::div_round_shift(num.0, shift, den.0)
        }
    }

    /// Runs a lookup and returns the bits it needed ([`Track`]): at least 128 if it was
    /// refused.
    fn peak<R>(f: impl FnOnce() -> Result<R, Error>) -> u32 {
        PEAK.with(|p| p.set(0));
        let r = f();
        let bits = PEAK.with(|p| p.get());
        if r.is_err() {
            bits.max(128)
        } else {
            bits
        }
    }

    /// The bits of the exact form's bound ([`exact_bound`]) of a placed footprint, 65 past
    /// `u64`.
    fn exact_bound_bits(fp: &Footprint<i64>, t: Worst, m_t: u64) -> u32 {
        let frac = |x: i64| (x & (fp.s - 1)) * (fp.s - (x & (fp.s - 1)));
        let (pa, pb) = (fp.px.map(frac), fp.py.map(frac));
        exact_bound(fp, &pa, &pb, t, m_t).map_or(65, bits_of_u64)
    }

    /// The bits the exact form needs on the `u64` table ([`peak`]).
    fn exact_need<T: Texel>(
        t64: &TentTable<'_, u64>,
        lines: &TentLines<'_, u32>,
        texture: &Texture<'_, T>,
        r: &Rect<i64>,
        fb: FracBits,
        kind: EdgeKind,
    ) -> u32 {
        peak(|| {
            t64.sample_exact_raw_in::<Track, _, _, _, _>(lines, texture, r, fb, kind, &mut NoCount)
        })
    }

    /// What a lookup on both tables gave: `(answers, refusals)` so far.
    #[derive(Default, Debug)]
    struct Outcomes {
        answered: usize,
        refused: usize,
        both_refused: usize,
        interior_refused: usize,
        /// On the all-maximum texture, the largest `bound - need` in bits of a refusal by the
        /// proof: paper form inside the table, anywhere; exact form inside, anywhere; integer.
        slack: [u32; 5],
    }

    /// Compares a `u32` table's answer with the `u64` table's: equal where it answers; where it
    /// refuses, the `u64` table answers and the refusal is the width proof's (`bits_needed` =
    /// the bound's bits, above 63; or 64 for a weight past `i64`, which the lookup really
    /// needs) or the normaliser's (`a^2 b^2 >= 2^63`). The bound (`None`: the normaliser or a
    /// weight refused before it) is never below what the lookup needs on this texture (`need`,
    /// from [`Track`]).
    fn compare(
        got32: Result<Sample<1>, Error>,
        got64: Result<Sample<1>, Error>,
        bound_bits: Option<u32>,
        need: u32,
        ab: (u64, u64),
        what: &str,
        out: &mut Outcomes,
    ) {
        // (A bound of 0: a zero sample with no reads, whose centres only were computed; 65: at
        // least 2^64, a lower bound.)
        if let Some(b) = bound_bits.filter(|&b| b > 0 && b < 65) {
            assert!(need <= b, "{what}: needs {need} bits, bound {b}");
            if what.contains(" worst") && b > 63 {
                let form = if what.contains(" int ") {
                    4
                } else {
                    2 * usize::from(what.starts_with("exact"))
                        + usize::from(!what.contains(" inside"))
                };
                out.slack[form] = out.slack[form].max(b - need);
            }
        }
        let norm_bits = bits_of(u128::from(ab.0).pow(2) * u128::from(ab.1).pow(2));
        match (got32, got64) {
            (Ok(a), Ok(b)) => {
                assert_eq!(a, b, "{what}");
                // (A Border footprint entirely outside is 0 before its normaliser is formed.)
                let zero = bound_bits == Some(0);
                assert!(bound_bits.is_some_and(|b| b <= 63), "{what}");
                assert!(norm_bits <= 63 || zero, "{what}");
                out.answered += 1;
            }
            (
                Err(Error::TooWide {
                    what: q,
                    bits_needed,
                    bits_available: 63,
                }),
                got64,
            ) => {
                // The u64 table answers, or refuses too (its i128 past 127 bits: the exact
                // form's 2^4G scale at large F).
                match got64 {
                    Ok(_) => out.refused += 1,
                    Err(Error::TooWide { .. }) => out.both_refused += 1,
                    Err(e) => panic!("{what}: u64 {e:?}"),
                }
                if q == Quantity::MeanNumerator {
                    assert!(
                        norm_bits > 63,
                        "{what}: refused a^2 b^2 of {norm_bits} bits"
                    );
                    let (a, b) = (bits_of_u64(ab.0), bits_of_u64(ab.1));
                    assert_eq!(bits_needed, 2 * a + 2 * b, "{what}");
                } else {
                    assert_eq!(q, Quantity::LookupAccumulator, "{what}");
                    assert!(norm_bits <= 63, "{what}");
                    match bound_bits {
                        Some(b) => assert_eq!(bits_needed, b, "{what}"),
                        None => assert!(bits_needed == 64 && need > 63, "{what}: {need}"),
                    }
                    assert!(bits_needed > 63, "{what}");
                }
            }
            (a, b) => panic!("{what}: u32 {a:?}, u64 {b:?}"),
        }
    }

    /// Every lookup of a `u32` table against the `u64` table of the same texture, for every `F`
    /// (under Miri three), every mode and random footprints inside and around the texture
    /// (module docs, "How wide the lookups compute").
    fn u32_against_u64<T: Texel>(t: &[T], w: usize, h: usize, seed: u64, out: &mut Outcomes) {
        let texture = Texture::<T>::new(t, w, h).unwrap();
        let mut s32 = vec![0u32; TentTable::<u32>::storage_needed(w, h).unwrap()];
        let t32 = TentTable::build(&texture, &mut s32).unwrap();
        let mut s64 = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
        let t64 = TentTable::build(&texture, &mut s64).unwrap();
        let mut ls = vec![0u32; TentLines::<u32>::storage_needed(w, h).unwrap()];
        let lines = TentLines::build(&texture, &mut ls).unwrap();
        let e = tent_entry_bits(T::BITS, w, h);
        assert!(e <= 32);
        let all_max = t
            .iter()
            .all(|v| u64::from(v.to_u16()) == max_texel_u64(T::BITS));
        let worst = if all_max { " worst" } else { "" };
        let (q, m) = (t32.worst(), max_texel_u64(T::BITS));
        let qmax = max_texel_u64(T::BITS) * (w * (w + 2) * h * (h + 2)) as u64;
        let mut seed = seed;
        let n = w.max(h) as i64;
        let fs: Vec<u32> = if cfg!(miri) {
            vec![0, 9, 24]
        } else {
            (0..=24).collect()
        };
        let per = if cfg!(miri) { 1 } else { 12 };
        for f in fs {
            let fb = FracBits::new(f).unwrap();
            let g = f + 1;
            let unit = 1i64 << f;
            for kind in EdgeKind::ALL {
                for i in 0..per {
                    // Half the footprints inside the table (0 <= x0 < x1 <= w), the others
                    // anywhere from 2n + 3 texels left of it to 3n + 3 right, up to 3n + 2 wide.
                    let inside = i % 2 == 0;
                    let mut corner = |len: usize| -> (i64, i64) {
                        if inside {
                            let len = len as i64 * unit;
                            let x0 = lcg(&mut seed) as i64 % len;
                            (x0, x0 + 1 + lcg(&mut seed) as i64 % (len - x0))
                        } else {
                            let x0 =
                                lcg(&mut seed) as i64 % ((5 * n + 6) * unit) - (2 * n + 3) * unit;
                            (x0, x0 + 1 + lcg(&mut seed) as i64 % ((3 * n + 2) * unit))
                        }
                    };
                    let ((x0, x1), (y0, y1)) = (corner(w), corner(h));
                    let r = Rect::new(x0, y0, x1, y1);
                    let ab = ((x1 - x0) as u64, (y1 - y0) as u64);
                    let what = format!(
                        "{w}x{h} {}-bit F={f} {} {r:?}{worst}{}",
                        T::BITS,
                        kind.name(),
                        if inside { " inside" } else { "" }
                    );
                    let fp = t32.footprint::<i64>(&r, fb, kind);
                    let bits = |b: Option<u64>| b.map_or(65, bits_of_u64);
                    // Paper form.
                    let bound = match &fp {
                        Ok(None) => Some(0),
                        Ok(Some(fp)) => Some(bits(paper_bound(&fp.ax, &fp.ay, fp.s as u64, q))),
                        Err(_) => None,
                    };
                    let need =
                        peak(|| t64.sample_raw_in::<Track, _, _>(&r, fb, kind, &mut NoCount));
                    let (got32, got64) = (
                        t32.sample_raw(&r, fb, kind, &mut NoCount),
                        t64.sample_raw(&r, fb, kind, &mut NoCount),
                    );
                    // The closed form inside the table: 8 q s^2, E + 2G + 3 bits (where the
                    // normaliser is not refused first).
                    if let (true, Ok(Some(fp))) = (inside, &fp) {
                        let b = paper_bound(&fp.ax, &fp.ay, fp.s as u64, q);
                        let at_most = u128::from(qmax) << (2 * g + 3);
                        let ok = b.map_or(at_most >> 64 != 0, |b| u128::from(b) <= at_most);
                        assert!(ok, "{what}");
                        assert!(bound.unwrap() <= e + 2 * g + 3, "{what}");
                        out.interior_refused += usize::from(got32.is_err());
                    }
                    compare(got32, got64, bound, need, ab, &what, out);
                    // Exact form.
                    let bound = match &fp {
                        Ok(None) => Some(0),
                        Ok(Some(fp)) => Some(exact_bound_bits(fp, q, m)),
                        Err(_) => None,
                    };
                    let need = exact_need(&t64, &lines, &texture, &r, fb, kind);
                    let (got32, got64) = (
                        t32.sample_exact_raw(&lines, &texture, &r, fb, kind, &mut NoCount),
                        t64.sample_exact_raw(&lines, &texture, &r, fb, kind, &mut NoCount),
                    );
                    if let (true, Ok(Some(_))) = (inside, &fp) {
                        // Inside the table: at most 12 s^4 Q_max + m s^4 and the line and texel
                        // sums, E + 4G + 4 bits.
                        assert!(bound.unwrap() <= e + 4 * g + 4, "{what}");
                        out.interior_refused += usize::from(got32.is_err());
                    }
                    compare(got32, got64, bound, need, ab, &format!("exact {what}"), out);
                }
                // The integer form at every F's worth of footprints: centres around the
                // texture, half-widths up to 3n + 2 and a few huge ones (the normaliser).
                let cx = (lcg(&mut seed) as i64 % (5 * n + 6) - 2 * n - 3) as i32;
                let cy = (lcg(&mut seed) as i64 % (5 * n + 6) - 2 * n - 3) as i32;
                let huge = [1u32 << 15, 1 << 16, 1 << 20, u32::MAX];
                let a = if f % 5 == 4 {
                    huge[(f / 5) as usize % 4]
                } else {
                    1 + (lcg(&mut seed) % (3 * n as u64 + 2)) as u32
                };
                let b = 1 + (lcg(&mut seed) % (3 * n as u64 + 2)) as u32;
                let what = format!(
                    "{w}x{h} {}-bit int {} ({cx},{cy}) {a} {b}{worst}",
                    T::BITS,
                    kind.name()
                );
                // As sample_int_in: centres, normaliser, weights, then the proof.
                let bound = (|| {
                    let (ca, cb) = (i64::from(a), i64::from(b));
                    let Some(cxx) = canonical_centre(kind, i64::from(cx), ca, w, 0).ok()? else {
                        return Some(0);
                    };
                    let Some(cyy) = canonical_centre(kind, i64::from(cy), cb, h, 0).ok()? else {
                        return Some(0);
                    };
                    <i64 as TentAcc>::normaliser(u64::from(a), u64::from(b)).ok()?;
                    let ax = int_axes(kind, cxx, ca, w).ok()?;
                    let ay = int_axes(kind, cyy, cb, h).ok()?;
                    Some(paper_bound(&ax, &ay, 1, q).map_or(65, bits_of_u64))
                })();
                let need =
                    peak(|| t64.sample_int_in::<Track, _, _>(cx, cy, a, b, kind, &mut NoCount));
                compare(
                    t32.sample_int(cx, cy, a, b, kind, &mut NoCount),
                    t64.sample_int(cx, cy, a, b, kind, &mut NoCount),
                    bound,
                    need,
                    (u64::from(a), u64::from(b)),
                    &what,
                    out,
                );
            }
        }
    }

    #[test]
    fn u32_tables_answer_as_u64_or_refuse_by_the_proof() {
        // Entry widths 12 (1 x 1), 18 (5 x 4), 25 (16 x 16) bits of 8-bit texels; 23 (3 x 2)
        // and 32 (13 x 13: the most a u32 table holds) of 16-bit ones. Random texels, then
        // the all-maximum texture (the worst case the proof bounds).
        let mut out = Outcomes::default();
        let sizes8: &[(usize, usize)] = if cfg!(miri) {
            &[(1, 1)]
        } else {
            &[(1, 1), (5, 4), (16, 16)]
        };
        let sizes16: &[(usize, usize)] = if cfg!(miri) {
            &[(13, 13)]
        } else {
            &[(3, 2), (13, 13)]
        };
        for &(w, h) in sizes8 {
            u32_against_u64(&tex(w, h, 5), w, h, 1, &mut out);
            u32_against_u64(&vec![255u8; w * h], w, h, 2, &mut out);
        }
        for &(w, h) in sizes16 {
            let mut s = 9u64;
            let t: Vec<u16> = (0..w * h).map(|_| lcg(&mut s) as u16).collect();
            u32_against_u64(&t, w, h, 3, &mut out);
            u32_against_u64(&vec![u16::MAX; w * h], w, h, 4, &mut out);
        }
        assert_eq!(tent_entry_bits(16, 13, 13), 32);
        // The largest square u32 tables (module docs): 8-bit 63 x 63, 16-bit 15 x 15.
        let widths = [(8, 63), (8, 64), (16, 15), (16, 16)].map(|(b, n)| tent_entry_bits(b, n, n));
        assert_eq!(widths, [32, 33, 32, 33]);
        // Inside the table the bound of the Crow form is within 3 bits of what the worst-case
        // texture needs where it refuses; the exact form's within 25 (narrow footprints),
        // outside the table the Crow form's within 12 and the exact form's within 22, the
        // integer form's within 6 (module docs, measured here and on Miri's smaller set).
        let [paper_in, paper_out, exact_in, exact_out, int] = out.slack;
        assert!(
            paper_in <= 3 && paper_out <= 12 && exact_in <= 25 && exact_out <= 22 && int <= 6,
            "{out:?}"
        );
        // Both outcomes happen, inside the table too.
        assert!(
            out.answered > 0 && out.refused > 0 && out.interior_refused > 0,
            "{out:?}"
        );
    }

    /// Footprints at the extremes of `i64` (corners from `i64::MIN` to `i64::MAX`, widths up to
    /// `2^64 - 1` raw units) and of `sample_int`'s `i32` centres and `u32` half-widths: a `u32`
    /// table answers as the `u64` table does or refuses with [`Error::TooWide`], never a
    /// different value, and never answers where the `u64` table refuses.
    #[test]
    fn u32_tables_on_extreme_footprints() {
        let (w, h) = (5usize, 4usize);
        let t = tex(w, h, 11);
        let texture = Texture::<u8>::new(&t, w, h).unwrap();
        let mut s32 = vec![0u32; TentTable::<u32>::storage_needed(w, h).unwrap()];
        let t32 = TentTable::build(&texture, &mut s32).unwrap();
        let mut s64 = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
        let t64 = TentTable::build(&texture, &mut s64).unwrap();
        let mut ls = vec![0u32; TentLines::<u32>::storage_needed(w, h).unwrap()];
        let lines = TentLines::build(&texture, &mut ls).unwrap();
        // Answers and refusals of the u32 table.
        let mut seen = [0usize; 2];
        let mut same = |got32: Result<Sample<1>, Error>, got64, what: &str| match (got32, got64) {
            (Ok(a), Ok(b)) => {
                assert_eq!(a, b, "{what}");
                seen[0] += 1;
            }
            (Err(Error::TooWide { .. }), _) => seen[1] += 1,
            (Err(a), Err(b)) => assert_eq!(a, b, "{what}"),
            (a, b) => panic!("{what}: u32 {a:?}, u64 {b:?}"),
        };
        let edges: &[i64] = if cfg!(miri) {
            &[i64::MIN, -1, 3, i64::MAX]
        } else {
            &[
                i64::MIN,
                i64::MIN + 1,
                -(1 << 62),
                -(1 << 40),
                -(1 << 20),
                -1,
                0,
                1,
                3,
                1 << 20,
                1 << 40,
                1 << 62,
                i64::MAX - 1,
                i64::MAX,
            ]
        };
        let fs: &[u32] = if cfg!(miri) { &[8] } else { &[0, 1, 8, 24] };
        for &f in fs {
            let fb = FracBits::new(f).unwrap();
            let (pw, ph) = ((w as i64) << f, (h as i64) << f);
            for kind in EdgeKind::ALL {
                for &lo in edges {
                    for &hi in edges.iter().filter(|&&hi| hi > lo) {
                        for r in [Rect::new(lo, 0, hi, ph), Rect::new(0, lo, pw, hi)] {
                            let what = format!("F={f} {} {r:?}", kind.name());
                            same(
                                t32.sample_raw(&r, fb, kind, &mut NoCount),
                                t64.sample_raw(&r, fb, kind, &mut NoCount),
                                &what,
                            );
                            same(
                                t32.sample_exact_raw(&lines, &texture, &r, fb, kind, &mut NoCount),
                                t64.sample_exact_raw(&lines, &texture, &r, fb, kind, &mut NoCount),
                                &format!("exact {what}"),
                            );
                        }
                    }
                }
            }
        }
        let centres = [i32::MIN, -7, 0, 2, 9, i32::MAX];
        let halves = [1u32, 3, 1 << 16, u32::MAX];
        for kind in EdgeKind::ALL {
            for (&c, &a) in centres
                .iter()
                .flat_map(|c| halves.iter().map(move |a| (c, a)))
            {
                let what = format!("int {} ({c}, 1) {a} x 2", kind.name());
                same(
                    t32.sample_int(c, 1, a, 2, kind, &mut NoCount),
                    t64.sample_int(c, 1, a, 2, kind, &mut NoCount),
                    &what,
                );
            }
        }
        assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
    }

    #[test]
    fn u32_proof_is_near_the_need_on_the_whole_texture() {
        // The whole all-maximum texture (16-bit 13 x 13: 32-bit entries), every F and mode
        // until the normaliser a^2 b^2 passes 63 bits: the width proof's bound is never below
        // what the lookup computes (Track on the u64 table, same values) and at most 2 bits
        // above it in the Crow form (the outer second difference of rows that could be as
        // large as 2 V, which a texture's rows are not), 6 in the exact form; a u32 table
        // answers exactly where the bound fits 63 bits.
        let (w, h) = (13usize, 13usize);
        let t = vec![u16::MAX; w * h];
        let texture = Texture::<u16>::new(&t, w, h).unwrap();
        let mut s64 = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
        let t64 = TentTable::build(&texture, &mut s64).unwrap();
        let mut s32 = vec![0u32; TentTable::<u32>::storage_needed(w, h).unwrap()];
        let t32 = TentTable::build(&texture, &mut s32).unwrap();
        let mut ls = vec![0u32; TentLines::<u32>::storage_needed(w, h).unwrap()];
        let lines = TentLines::build(&texture, &mut ls).unwrap();
        let e = tent_entry_bits(16, w, h);
        let (mut answered, mut refused) = (0, 0);
        let fs: Vec<u32> = if cfg!(miri) {
            vec![0, 7]
        } else {
            (0..=24).collect()
        };
        for f in fs {
            let g = f + 1;
            let r = Rect::new(0, 0, (w as i64) << f, (h as i64) << f);
            let fb = FracBits::new(f).unwrap();
            for kind in EdgeKind::ALL {
                let fp = match t32.footprint::<i64>(&r, fb, kind) {
                    Ok(fp) => fp.unwrap(),
                    Err(Error::TooWide {
                        what: Quantity::MeanNumerator,
                        ..
                    }) => {
                        assert!(4 * bits_of_u64((w as u64) << f) > 63, "F={f}");
                        continue;
                    }
                    Err(e) => panic!("F={f}: {e:?}"),
                };
                let bound = paper_bound(&fp.ax, &fp.ay, fp.s as u64, t32.worst());
                let bound = bound.map_or(65, bits_of_u64);
                let need = peak(|| t64.sample_raw_in::<Track, _, _>(&r, fb, kind, &mut NoCount));
                assert!(bound <= e + 2 * g + 3, "F={f}");
                assert!(
                    need <= bound && bound <= need + 2,
                    "F={f}: need {need}, bound {bound}"
                );
                let got = t32.sample_raw(&r, fb, kind, &mut NoCount);
                assert_eq!(got.is_ok(), bound <= 63, "F={f}");
                let bound = exact_bound_bits(&fp, t32.worst(), 65535);
                let need = exact_need(&t64, &lines, &texture, &r, fb, kind);
                assert!(bound <= e + 4 * g + 4, "F={f}");
                assert!(
                    (need <= bound && bound <= need + 6) || (bound == 65 && need > 63),
                    "exact F={f}: need {need}, bound {bound}"
                );
                let got = t32.sample_exact_raw(&lines, &texture, &r, fb, kind, &mut NoCount);
                assert_eq!(got.is_ok(), bound <= 63, "exact F={f}");
                if got.is_ok() {
                    answered += 1;
                } else {
                    refused += 1;
                }
            }
        }
        assert!(answered > 0 && refused > 0);
    }

    #[test]
    fn div_round_shift_u64_matches_the_u128_division() {
        // The i64 accumulator's rounded division against the i128 one: exhaustive over small
        // values (ties included), then the edges (den up to 2^63, shifts to 64, quotients past
        // u64 refused alike). Under Miri a corner of the small values.
        let (nums, shifts, dens) = if cfg!(miri) {
            (12, 4, 6)
        } else {
            (160, 20, 40)
        };
        for num in 0..nums {
            for shift in 0..=shifts {
                for den in 0..=dens {
                    assert_eq!(
                        div_round_shift_u64(num, shift, den),
                        div_round_shift(u128::from(num), shift, u128::from(den)),
                        "{num} {shift} {den}"
                    );
                }
            }
        }
        let edges = [
            0,
            1,
            2,
            3,
            (1 << 31) - 1,
            1 << 31,
            (1 << 62) + 1,
            (1 << 63) - 1,
            1 << 63,
        ];
        for &num in &edges {
            for shift in [0, 1, 13, 14, 31, 32, 50, 63, 64] {
                for &den in &edges {
                    assert_eq!(
                        div_round_shift_u64(num, shift, den),
                        div_round_shift(u128::from(num), shift, u128::from(den)),
                        "{num} {shift} {den}"
                    );
                }
            }
        }
        // Past 2^63 the i64 normaliser never gives a divisor: refused, not wrapped.
        assert!(div_round_shift_u64(5, 1, (1 << 63) + 1).is_err());
    }
}
