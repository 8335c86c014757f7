//! The unsigned result words of the lookups ([`Wide`]: `u64` for `u16` and `u32` tables, `u128`
//! for `u64` tables) and the one rounded division of the mean.
//!
//! The mean is `round(sum * 2^g / (W * H))` with the sum scaled by `2^2F` and the box sides `W`,
//! `H` in units of `2^-F`. For `u64` results the common case is one `u64` division: when
//! `sum * 2^g` and `W * H` both fit 64 bits. Otherwise (a huge [`crate::Border`] box, many output
//! bits) the same rounded quotient is found by restoring long division on two 64-bit words, so
//! no 128-bit integer operation is ever emitted for a `u16` or `u32` table (a 128-bit divide is a
//! software loop of about 1,200 instructions on a Cortex-M4).
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::error::{Error, Quantity};

/// An unsigned result word: `u64` or `u128`. Sealed.
pub trait Wide:
    Copy + Ord + Default + core::fmt::Debug + core::fmt::Display + Into<u128> + sealed::Sealed + 'static
{
    /// Bits of the word.
    const BITS: u32;
    /// Zero.
    const ZERO: Self;
    /// Bits needed to hold the value (`0` for `0`).
    fn bits(self) -> u32;
    /// `self >> s` for `s < BITS`.
    fn shr(self, s: u32) -> Self;
    /// Checked `self * m`.
    fn checked_mul_u64(self, m: u64) -> Option<Self>;
    /// Checked `self + o`.
    fn checked_add(self, o: Self) -> Option<Self>;
    /// `round(self * 2^g / (w * h))`, ties up; `w, h >= 1`. Refuses (as
    /// [`Quantity::MeanNumerator`]) a result that does not fit the word.
    fn div_round_area(self, g: u32, w: u64, h: u64) -> Result<Self, Error>;
    /// The value as `u64`, if it fits.
    fn to_u64(self) -> Option<u64>;
}

mod sealed {
    /// Keeps [`super::Wide`] closed.
    pub trait Sealed {}
    impl Sealed for u64 {}
    impl Sealed for u128 {}
}

fn too_wide(bits_needed: u32, bits_available: u32) -> Error {
    Error::TooWide {
        what: Quantity::MeanNumerator,
        bits_needed,
        bits_available,
    }
}

/// `floor(log2 v) + 1`, 0 for 0.
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "leading_zeros of a u64 is at most 64"
)]
const fn bits64(v: u64) -> u32 {
    64 - v.leading_zeros()
}

/// A 128-bit unsigned value as two `u64` halves, with just what restoring division needs.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Pair {
    hi: u64,
    lo: u64,
}

impl Pair {
    /// Bits of the value (0 for 0).
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "bits64 <= 64, so 64 + bits64 <= 128"
    )]
    fn bits(self) -> u32 {
        if self.hi != 0 {
            64 + bits64(self.hi)
        } else {
            bits64(self.lo)
        }
    }

    /// The full product `a * b`, from 32-bit halves (no 128-bit operation).
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "schoolbook multiplication on 32-bit halves: each partial product is below 2^64; \
                  mid is below 3 * 2^32; hi + carries is the high word of a * b < 2^128, so no sum wraps"
    )]
    fn mul(a: u64, b: u64) -> Pair {
        let (a1, a0) = (a >> 32, a & 0xFFFF_FFFF);
        let (b1, b0) = (b >> 32, b & 0xFFFF_FFFF);
        let p00 = a0 * b0;
        let p01 = a0 * b1;
        let p10 = a1 * b0;
        let p11 = a1 * b1;
        // Middle column: the high half of p00 plus the low halves of the cross terms; below 3 * 2^32.
        let mid = (p00 >> 32) + (p01 & 0xFFFF_FFFF) + (p10 & 0xFFFF_FFFF);
        let lo = (p00 & 0xFFFF_FFFF) | (mid << 32);
        let hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
        Pair { hi, lo }
    }

    /// `self - o` for `self >= o`.
    fn sub(self, o: Pair) -> Pair {
        let (lo, borrow) = self.lo.overflowing_sub(o.lo);
        Pair {
            hi: self.hi.wrapping_sub(o.hi).wrapping_sub(u64::from(borrow)),
            lo,
        }
    }

    /// `(self << 1) | bit` and the bit shifted out.
    fn shl1(self, bit: bool) -> (Pair, bool) {
        let out = self.hi >> 63 != 0;
        (
            Pair {
                hi: (self.hi << 1) | (self.lo >> 63),
                lo: (self.lo << 1) | u64::from(bit),
            },
            out,
        )
    }
}

/// `round(num * 2^g / (w * h))` by restoring long division over the bits of `num` followed by
/// `g` zero bits, against the 128-bit divisor `w * h` (the cold path of the `u64` mean).
#[allow(
    clippy::arithmetic_side_effects,
    reason = "g <= 128 (the caller refuses more), so total = 64 + g <= 192; 63 - i only for i < 64; \
              total - i + 64 with i < total is at most 256"
)]
fn div_round_long(num: u64, g: u32, w: u64, h: u64) -> Result<u64, Error> {
    let den = Pair::mul(w, h);
    let total = 64 + g;
    let mut rem = Pair { hi: 0, lo: 0 };
    let mut q: u64 = 0;
    for i in 0..total {
        let bit = if i < 64 {
            (num >> (63 - i)) & 1 != 0
        } else {
            false
        };
        let (shifted, out) = rem.shl1(bit);
        // q's top bit would be lost: the quotient has more than 64 bits.
        if q >> 63 != 0 {
            return Err(too_wide(total - i + 64, 64));
        }
        q <<= 1;
        if out || shifted >= den {
            rem = shifted.sub(den);
            q |= 1;
        } else {
            rem = shifted;
        }
    }
    // Round to nearest, ties up: up iff 2 rem >= den, i.e. rem >= den - rem.
    if rem >= den.sub(rem) {
        q = q.checked_add(1).ok_or(too_wide(65, 64))?;
    }
    Ok(q)
}

/// `round(n * 2^g / (w * h))`, ties up, as a 32-bit word: the mean of
/// [`crate::BoxSum::mean_rounded_u32`]. `w, h >= 1` (the caller checks).
///
/// Only the narrow case exists here: the numerator `n 2^g` fits 64 bits, the area `w h` fits 32
/// bits and so does the rounded quotient. Then the quotient and remainder come from one
/// 64-by-32-bit division ([`crate::div::div_u64_by_u32`]: two hardware 32-bit divides on a
/// 32-bit core, one instruction on a 64-bit host) and the rounding is one comparison,
/// `r >= area - r` (that is `2 r >= area` without forming `2 r`). Anything wider is refused with
/// the quantity and the bits it needs, so the general fallbacks of [`Wide::div_round_area`]
/// (a 64-bit divisor, restoring long division) are never linked into a firmware that calls only
/// this: a plan whose facts keep every box's area and mean below `2^32`
/// ([`crate::plan::Plan::mean_fits_u32`]) uses it.
#[inline]
pub(crate) fn div_round_area_u32<W: Wide>(n: W, g: u32, w: u64, h: u64) -> Result<u32, Error> {
    narrow_round_area(n, g, w, h).ok_or_else(|| refuse_u32(n, g, w, h))
}

/// The narrow case of [`div_round_area_u32`] inline with no bit counting (`None` past it: the
/// cold [`refuse_u32`] then works out which quantity and how many bits).
#[inline(always)]
#[allow(clippy::arithmetic_side_effects, reason = "r < area, so area - r >= 1")]
fn narrow_round_area<W: Wide>(n: W, g: u32, w: u64, h: u64) -> Option<u32> {
    let n = n.to_u64()?;
    if n == 0 {
        return Some(0);
    }
    // `n << g` keeps every bit: g < 64 and the top g bits are zero.
    if g >= 64 || n.leading_zeros() < g {
        return None;
    }
    let num = n << g;
    let area = u32::try_from(w).ok()?.checked_mul(u32::try_from(h).ok()?)?;
    #[cfg(any(not(target_pointer_width = "64"), test))]
    let (q, r) = crate::div::div_u64_by_u32(num, area)?;
    #[cfg(all(target_pointer_width = "64", not(test)))]
    let (q, r) = div_u64_native(num, u64::from(area))?;
    if r >= area - r {
        q.checked_add(1)
    } else {
        Some(q)
    }
}

/// `(n / d, n % d)` as 32-bit words by the host's native 64-bit division; `None` for `d = 0`
/// or a quotient past 32 bits.
#[cfg(all(target_pointer_width = "64", not(test)))]
#[inline(always)]
fn div_u64_native(n: u64, d: u64) -> Option<(u32, u32)> {
    let d = core::num::NonZeroU64::new(d)?;
    Some((u32::try_from(n / d).ok()?, u32::try_from(n % d).ok()?))
}

/// Why [`div_round_area_u32`] refuses `n 2^g / (w h)`: the numerator past 64 bits, else the
/// area past 32 bits, else the rounded mean past 32 bits, with the bits each needs (for the
/// mean a lower bound: the quotient is at least `2^(bits(n 2^g) - 1 - bits(area))`, so it needs
/// at least `bits(n 2^g) - bits(area)` bits, and 33 once it does not fit).
#[cold]
#[inline(never)]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "bits64 <= 64 and g < 64 (checked first) in the sums of bit counts; w, h >= 1 (the \
              caller checks), so bits64(w) + bits64(h) >= 2"
)]
fn refuse_u32<W: Wide>(n: W, g: u32, w: u64, h: u64) -> Error {
    let too = |what, bits_needed: u32| Error::TooWide {
        what,
        bits_needed,
        bits_available: 32,
    };
    let Some(n) = n.to_u64() else {
        return too_wide(n.bits().saturating_add(g), 64);
    };
    if g >= 64 || bits64(n) + g > 64 {
        return too_wide(bits64(n).saturating_add(g), 64);
    }
    let (Ok(w32), Ok(h32)) = (u32::try_from(w), u32::try_from(h)) else {
        return too(Quantity::MeanArea, bits64(w) + bits64(h) - 1);
    };
    let area = u64::from(w32) * u64::from(h32);
    if area > u64::from(u32::MAX) {
        return too(Quantity::MeanArea, bits64(area));
    }
    too(
        Quantity::Mean,
        bits64(n << g).saturating_sub(bits64(area)).max(33),
    )
}

impl Wide for u64 {
    const BITS: u32 = 64;
    const ZERO: Self = 0;
    #[inline(always)]
    fn bits(self) -> u32 {
        bits64(self)
    }
    #[inline(always)]
    fn shr(self, s: u32) -> Self {
        self >> (s & 63)
    }
    #[inline(always)]
    fn checked_mul_u64(self, m: u64) -> Option<Self> {
        self.checked_mul(m)
    }
    #[inline(always)]
    fn checked_add(self, o: Self) -> Option<Self> {
        u64::checked_add(self, o)
    }
    #[inline(always)]
    fn to_u64(self) -> Option<u64> {
        Some(self)
    }
    #[inline]
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "w, h < 2^32: the area fits u64; bits64 <= 64 and g < 64 (checked first): their sum \
                  does not wrap; r < area, so area - r >= 1; rounding up needs 2 r >= area with \
                  r >= 1, so area >= 2 and q <= n / 2 < 2^63: q + 1 fits"
    )]
    fn div_round_area(self, g: u32, w: u64, h: u64) -> Result<u64, Error> {
        if self == 0 {
            return Ok(0);
        }
        // Sides below 2^32 (any box on a texture a microcontroller holds, at any F): the area is
        // one 32 x 32 -> 64 multiply, no overflow check, and the quotient and remainder come
        // from `div::divrem_u64` (hardware 32-bit divides on a 32-bit core, never the 64-bit
        // library routine).
        if let (Ok(w32), Ok(h32)) = (u32::try_from(w), u32::try_from(h)) {
            let area = u64::from(w32) * u64::from(h32);
            if g < 64 && bits64(self) + g <= 64 {
                let n = self << g;
                // The usual mean (area and quotient below 2^32) inline on a 32-bit core: two
                // hardware divides; anything else out of line.
                #[cfg(any(not(target_pointer_width = "64"), test))]
                if let Some((q, r)) = u32::try_from(area)
                    .ok()
                    .and_then(|a| crate::div::div_u64_by_u32(n, a))
                {
                    let (q, r) = (u64::from(q), u64::from(r));
                    return Ok(if r >= area - r { q + 1 } else { q });
                }
                if let Some((q, r)) = crate::div::divrem_u64(n, area) {
                    return Ok(if r >= area - r { q + 1 } else { q });
                }
            }
        }
        if w == 0 || h == 0 {
            return Err(Error::ZeroArea);
        }
        // The quotient is at least 2^(bits(sum) - 1 + g - bits(area)): from 2^64 on, it does
        // not fit. Below, g < 65 + bits(area) <= 193, so the long division takes at most 257
        // steps, and a huge area may bring a huge g back under 2^64.
        let area_bits = Pair::mul(w, h).bits();
        if bits64(self).saturating_add(g) >= area_bits.saturating_add(65) {
            return Err(too_wide(bits64(self).saturating_add(g) - area_bits, 64));
        }
        div_round_long(self, g, w, h)
    }
}

impl Wide for u128 {
    const BITS: u32 = 128;
    const ZERO: Self = 0;
    #[inline(always)]
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "leading_zeros of a u128 is at most 128"
    )]
    fn bits(self) -> u32 {
        128 - self.leading_zeros()
    }
    #[inline(always)]
    fn shr(self, s: u32) -> Self {
        self >> (s & 127)
    }
    #[inline(always)]
    fn checked_mul_u64(self, m: u64) -> Option<Self> {
        self.checked_mul(u128::from(m))
    }
    #[inline(always)]
    fn checked_add(self, o: Self) -> Option<Self> {
        u128::checked_add(self, o)
    }
    #[inline(always)]
    fn to_u64(self) -> Option<u64> {
        u64::try_from(self).ok()
    }
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "w, h < 2^64: the area fits u128; area != 0 (checked) for / and %; r < area, so \
                  area - r >= 1; rounding up needs 2 r >= area with r >= 1, so area >= 2 and \
                  q <= n / 2 < 2^127: q + 1 fits"
    )]
    fn div_round_area(self, g: u32, w: u64, h: u64) -> Result<u128, Error> {
        // A zero sum has a zero mean at any number of output bits.
        if self == 0 {
            return Ok(0);
        }
        let area = u128::from(w) * u128::from(h);
        if area == 0 {
            return Err(Error::ZeroArea);
        }
        let needed = self.bits().saturating_add(g);
        if needed <= 128 && g < 128 {
            let n = self << g;
            let (q, r) = (n / area, n % area);
            return Ok(if r >= area - r { q + 1 } else { q });
        }
        // sum 2^g past 128 bits: the quotient is at least 2^(needed - 1 - bits(area)); from
        // 2^128 on it does not fit. Below, g < 129 + bits(area) <= 257, and restoring division
        // over the bits of the sum followed by g zeros takes at most 385 steps.
        let area_bits = 128 - area.leading_zeros();
        if needed >= area_bits.saturating_add(129) {
            return Err(too_wide(needed - area_bits, 128));
        }
        div_round_long_u128(self, g, area)
    }
}

/// `round(num 2^g / den)`, ties up, for `den >= 1` and a quotient below `2^128` (else
/// [`Error::TooWide`]), by restoring division over the bits of `num` followed by `g` zero bits;
/// the remainder stays below `den`, and the bit shifted out of it on each step is kept (the
/// cold path of the `u128` mean: `num 2^g` past 128 bits).
#[allow(
    clippy::arithmetic_side_effects,
    reason = "i < total keeps 127 - i in range; rem < den, so (rem << 1 | bit) - den with the \
              shifted-out bit (out) is the true remainder, below den, and wrapping_sub gives it; \
              q << 1 is taken only when q's top bit is clear; den - rem >= 1"
)]
fn div_round_long_u128(num: u128, g: u32, den: u128) -> Result<u128, Error> {
    let total = 128 + g;
    let (mut rem, mut q) = (0u128, 0u128);
    for i in 0..total {
        let bit = i < 128 && (num >> (127 - i)) & 1 != 0;
        let out = rem >> 127 != 0;
        let shifted = (rem << 1) | u128::from(bit);
        if q >> 127 != 0 {
            return Err(too_wide(total - i + 128, 128));
        }
        q <<= 1;
        if out || shifted >= den {
            rem = shifted.wrapping_sub(den);
            q |= 1;
        } else {
            rem = shifted;
        }
    }
    if rem >= den - rem {
        q = q.checked_add(1).ok_or(too_wide(129, 128))?;
    }
    Ok(q)
}

/// One rounded division `round(num 2^shift / den)`, ties up, per word width: restoring
/// division in the word itself (no intermediate wider than `2 den`).
macro_rules! div_round_shift_word {
    ($(#[$doc:meta])* $name:ident, $t:ty, $nz:ty) => {
        $(#[$doc])*
        #[allow(dead_code)] // used only by some filter features
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "restoring division: r < den <= 2^(BITS - 1) throughout (checked first), so \
                      r << 1 loses nothing, r -= den only when r >= den, and den - r >= 1; q += 1 \
                      in the loop follows q * 2 (even, so below the word's maximum)"
        )]
        pub(crate) fn $name(num: $t, shift: u32, den: $t) -> Result<u64, Error> {
            let wide = || too_wide(65, 64);
            let Some(den) = <$nz>::new(den) else {
                return Err(Error::ZeroArea);
            };
            if den.get() > 1 << (<$t>::BITS - 1) {
                return Err(wide());
            }
            if num == 0 {
                // Rounds to 0 at any shift (and the loop below would run `shift` times).
                return Ok(0);
            }
            let mut q = num / den;
            let mut r = num % den;
            let den = den.get();
            for _ in 0..shift {
                q = q.checked_mul(2).ok_or_else(wide)?;
                r <<= 1;
                if r >= den {
                    r -= den;
                    q += 1;
                }
            }
            if r >= den - r {
                q = q.checked_add(1).ok_or_else(wide)?;
            }
            u64::try_from(q).map_err(|_| wide())
        }
    };
}

div_round_shift_word!(
    /// `round(num * 2^shift / den)`, ties up, for `0 < den <= 2^127`; a quotient above `u64`
    /// or a larger `den` is [`Error::TooWide`], a zero `den` [`Error::ZeroArea`]. The 128-bit
    /// rounded division, for the quantities that are 128-bit by nature (the tent filter's
    /// order-2 sums on `u64` tables, the variance of `u64` tables).
    div_round_shift_u128,
    u128,
    core::num::NonZeroU128
);
div_round_shift_word!(
    /// [`div_round_shift_u128`] for `0 < den <= 2^63` in `u64` (the tent filter's `i64`
    /// lookups on `u32` tables): the same quotient, or the same refusal.
    div_round_shift_u64,
    u64,
    core::num::NonZeroU64
);

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
mod tests {
    use super::*;

    fn reference(num: u64, g: u32, w: u64, h: u64) -> Option<u128> {
        // Exact in u128 where it fits (the test's own arithmetic, not the code under test).
        let n = (num as u128)
            .checked_shl(g)
            .filter(|v| v >> g == num as u128)?;
        let a = w as u128 * h as u128;
        let (q, r) = (n / a, n % a);
        Some(if r >= a - r { q + 1 } else { q })
    }

    #[test]
    fn pair_mul_matches_u128() {
        let vals = [
            0u64,
            1,
            2,
            0xFFFF_FFFF,
            0x1_0000_0000,
            u64::MAX,
            u64::MAX - 1,
            0x8000_0000_0000_0000,
            0x1234_5678_9ABC_DEF0,
        ];
        for &a in &vals {
            for &b in &vals {
                let p = Pair::mul(a, b);
                let want = a as u128 * b as u128;
                assert_eq!(((p.hi as u128) << 64) | p.lo as u128, want, "{a} {b}");
            }
        }
    }

    #[test]
    fn u64_mean_matches_reference_fast_and_long_paths() {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        // Under Miri (about 10^4 times slower) 300 random cases.
        let cases = if cfg!(miri) { 300 } else { 20_000 };
        for i in 0..cases {
            let num = next() >> (next() % 64);
            let g = (next() % 40) as u32;
            let w = (next() >> (next() % 64)).max(1);
            let h = (next() >> (next() % 64)).max(1);
            let want = reference(num, g, w, h);
            let got = num.div_round_area(g, w, h);
            match want {
                Some(v) if v <= u64::MAX as u128 => {
                    assert_eq!(got, Ok(v as u64), "{i}: {num} {g} {w} {h}")
                }
                Some(_) => assert!(got.is_err(), "{i}: {num} {g} {w} {h}"),
                None => {}
            }
            // The long path alone agrees too.
            if let Some(v) = want.filter(|&v| v <= u64::MAX as u128) {
                assert_eq!(div_round_long(num, g, w, h), Ok(v as u64));
            }
        }
    }

    /// Means whose numerator `sum 2^g` leaves the word but whose quotient fits: areas that are
    /// `2^k` or `3 2^k`, where the exact mean is `sum 2^(g - k)` or that over 3 (computed here in
    /// `u128` without the code under test).
    #[test]
    fn huge_output_bits_over_huge_areas() {
        // Under Miri (about 10^4 times slower) two sums and two shifts.
        let sums: &[u64] = if cfg!(miri) {
            &[3, 4_177_920]
        } else {
            &[1, 3, 255, 265_200, 4_177_920, 0xFFFF_FFFF, u64::MAX >> 1]
        };
        let ds: &[u32] = if cfg!(miri) {
            &[0, 40]
        } else {
            &[0, 1, 5, 20, 40]
        };
        for &sum in sums {
            for (i, j) in [(60u32, 60u32), (63, 63), (40, 63), (63, 1)] {
                let k = i + j;
                for &d in ds {
                    let g = k + d;
                    // u64 result: area 2^k.
                    let want = u128::from(sum) << d;
                    let got = sum.div_round_area(g, 1 << i, 1 << j);
                    if want <= u128::from(u64::MAX) {
                        assert_eq!(got, Ok(want as u64), "{sum} g={g} 2^{i} 2^{j}");
                    } else {
                        assert!(got.is_err(), "{sum} g={g}");
                    }
                    // u128 result: area 3 2^k (w = 3 2^(i-2), h = 2^(j+2) when i >= 2).
                    if i >= 2 && j + 2 <= 63 {
                        let (w, h) = (3u64 << (i - 2), 1u64 << (j + 2));
                        let n = u128::from(sum) << d;
                        let (q, r) = (n / 3, n % 3);
                        let want = if r >= 3 - r { q + 1 } else { q };
                        let got = u128::from(sum).div_round_area(g, w, h);
                        assert_eq!(got, Ok(want), "u128 {sum} g={g} 3x2^{k}");
                    }
                }
            }
        }
        // The fuzz findings: bits(sum) + g past the word with a mean that fits.
        // u128: sum 265200, g = 119, sides 26 x 40: mean = 265200 2^119 / 1040 < 2^128.
        // 265200 = 255 x 1040, so the mean is exactly 255 2^119.
        assert_eq!(265_200u128.div_round_area(119, 26, 40), Ok(255u128 << 119));
        // And a rounded one: 265201 2^119 / 1040 = 255 2^119 + 2^119 / 1040, whose quotient and
        // remainder come from 2^119 = 1040 q + r (in range here).
        let (q, r) = ((1u128 << 119) / 1040, (1u128 << 119) % 1040);
        let want = (255u128 << 119) + if r >= 1040 - r { q + 1 } else { q };
        assert_eq!(265_201u128.div_round_area(119, 26, 40), Ok(want));
        // u64: g = 131 over sides near 2^62 x 2^61: the mean is small.
        let got = 4_177_920u64.div_round_area(131, 1 << 62, 1 << 61);
        assert_eq!(got, Ok((4_177_920u128 << 8) as u64));
        // Still refused when the quotient itself leaves the word.
        assert!(u64::MAX.div_round_area(200, 1, 1).is_err());
        assert!(u128::MAX.div_round_area(300, 1, 1).is_err());
        assert_eq!(
            u128::MAX
                .div_round_area(127, u64::MAX, u64::MAX)
                .map(|_| ()),
            Ok(())
        );
        assert!(u128::MAX.div_round_area(128, u64::MAX, u64::MAX).is_err());
    }

    #[test]
    fn ties_round_up_and_huge_areas() {
        assert_eq!(1u64.div_round_area(0, 2, 1), Ok(1));
        assert_eq!(1u64.div_round_area(0, 3, 1), Ok(0));
        // Area 2^64 * 2^63 (cold path): 2^63 * 2^64 / 2^127 = 1.
        assert_eq!((1u64 << 63).div_round_area(64, 1 << 63, 1 << 63), Ok(2));
        assert_eq!(u64::MAX.div_round_area(64, u64::MAX, u64::MAX), Ok(1));
        assert!(u64::MAX.div_round_area(8, 1, 1).is_err());
        assert_eq!(0u64.div_round_area(200, 1, 1), Ok(0));
    }

    /// The 32-bit mean: equal to the reference wherever the numerator fits 64 bits and the area
    /// and the rounded mean fit 32 bits, refused (with the quantity that does not fit) exactly
    /// where one of them does not.
    fn check_u32(num: u64, g: u32, w: u64, h: u64) {
        let got = div_round_area_u32(num, g, w, h);
        let n_fits = num == 0 || (g < 64 && 64 - num.leading_zeros() + g <= 64);
        let area = w as u128 * h as u128;
        let want = reference(num, g, w, h);
        if num == 0 {
            assert_eq!(got, Ok(0));
        } else if !n_fits {
            assert!(
                matches!(
                    got,
                    Err(Error::TooWide {
                        what: Quantity::MeanNumerator,
                        ..
                    })
                ),
                "{num} {g} {w} {h}: {got:?}"
            );
        } else if area > u32::MAX as u128 {
            assert!(
                matches!(got, Err(Error::TooWide { what: Quantity::MeanArea, bits_needed, bits_available: 32 }) if bits_needed > 32),
                "{num} {g} {w} {h}: {got:?}"
            );
        } else {
            match want {
                Some(v) if v <= u32::MAX as u128 => {
                    assert_eq!(got, Ok(v as u32), "{num} {g} {w} {h}")
                }
                _ => assert!(
                    matches!(got, Err(Error::TooWide { what: Quantity::Mean, bits_needed, bits_available: 32 }) if bits_needed > 32),
                    "{num} {g} {w} {h}: {got:?}"
                ),
            }
        }
        // Where it answers, the general mean answers the same.
        if let Ok(v) = got {
            assert_eq!(num.div_round_area(g, w, h), Ok(u64::from(v)));
        }
    }

    #[test]
    fn u32_mean_exhaustive_small() {
        // Under Miri (about 10^4 times slower) a coarse grid.
        let (nums, step) = if cfg!(miri) { (40u64, 7) } else { (300, 1) };
        for num in (0..nums).step_by(step) {
            for g in 0..6 {
                for w in 1..=20 {
                    for h in (1..=20).step_by(step) {
                        check_u32(num, g, w, h);
                    }
                }
            }
        }
    }

    #[test]
    fn u32_mean_random_and_edges() {
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let cases = if cfg!(miri) { 300 } else { 50_000 };
        for _ in 0..cases {
            let num = next() >> (next() % 64);
            let g = (next() % 40) as u32;
            let w = (next() >> (next() % 64)).max(1);
            let h = (next() >> (next() % 64)).max(1);
            check_u32(num, g, w, h);
        }
        let max = u64::from(u32::MAX);
        for (num, g, w, h) in [
            (max, 0, 1, 1),           // the largest mean
            (max, 1, 2, 1),           // the same, scaled
            (2 * max, 0, 2, 1),       // 2^33 - 2 over 2: fits
            (2 * max + 1, 0, 2, 1),   // a tie just above 2^32 - 1: refused
            (max, 0, max, 1),         // the largest area
            (max, 0, 65_536, 65_536), // area 2^32: refused
            (1, 0, 1 << 32, 1),       // a side past 32 bits
            (u64::MAX, 0, max, max),  // the numerator at 64 bits
            (u64::MAX, 1, max, max),  // ... and one past
        ] {
            check_u32(num, g, w, h);
        }
        // A u128 sum past 64 bits is refused as the numerator.
        assert!(matches!(
            div_round_area_u32(1u128 << 64, 0, 1, 1),
            Err(Error::TooWide {
                what: Quantity::MeanNumerator,
                ..
            })
        ));
        assert_eq!(div_round_area_u32(1000u128, 3, 10, 10), Ok(80));
    }
}
