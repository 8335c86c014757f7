//! The unsigned result words of the lookups ([`Wide`]: `u64` for `u16` and `u32` tables, `u128`
//! for `u64` tables) and the one rounded division of the mean.
//!
//! The mean is `round(sum * 2^g / (W * H))` with the sum scaled by `2^2F` and the box sides `W`,
//! `H` in units of `2^-F`. For `u64` results the common case is one `u64` division: when
//! `sum * 2^g` and `W * H` both fit 64 bits. Otherwise (a huge [`crate::Border`] box, many output
//! bits) the same rounded quotient is found by restoring long division on two 64-bit words, so
//! no 128-bit integer operation is ever emitted for a `u16` or `u32` table (a 128-bit divide is a
//! software loop of about 1,200 instructions on a Cortex-M4).

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
    /// The full product `a * b`, from 32-bit halves (no 128-bit operation).
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
            hi: self.hi.wrapping_sub(o.hi).wrapping_sub(borrow as u64),
            lo,
        }
    }

    /// `(self << 1) | bit` and the bit shifted out.
    fn shl1(self, bit: bool) -> (Pair, bool) {
        let out = self.hi >> 63 != 0;
        (
            Pair {
                hi: (self.hi << 1) | (self.lo >> 63),
                lo: (self.lo << 1) | bit as u64,
            },
            out,
        )
    }
}

/// `round(num * 2^g / (w * h))` by restoring long division over the bits of `num` followed by
/// `g` zero bits, against the 128-bit divisor `w * h` (the cold path of the `u64` mean).
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

/// `(n / d, n % d)` for a 64-bit `n` and a 32-bit `d` whose quotient fits 32 bits
/// (`n >> 32 < d`); `None` otherwise (and for `d = 0`).
///
/// Why: a Cortex-M4 divides 32 by 32 bits in hardware but has no 64-bit divide, so `u64 / u64`
/// is a library loop (`__aeabi_uldivmod`). The mean's denominator, the area `W H` in units of
/// `2^-2F`, is below `2^32` for any box on a texture a microcontroller holds, and its quotient
/// (the mean times `2^g`) fits 32 bits, so schoolbook division by 16-bit digits does it with
/// two hardware divides (Knuth, TAOCP vol. 2, §4.3.1, Algorithm D, with `b = 2^16`, `n = 2`,
/// `m = 2`; as in Warren, *Hacker's Delight*, §9-4): normalize `d` so its top bit is set, then
/// estimate each 16-bit quotient digit from the top 32 bits of the partial remainder divided
/// by the top 16-bit digit of `d`; the estimate is at most 2 too large, and the test against
/// the second digit corrects it (at most two steps per digit). No 64-bit divide, no loop of
/// more than two steps. Exhaustively checked against `u64` division on small sizes and by
/// random tests at every normalization shift (tests below).
#[cfg_attr(all(target_pointer_width = "64", not(test)), allow(dead_code))]
#[inline]
pub(crate) fn div_u64_by_u32(n: u64, d: u32) -> Option<(u32, u32)> {
    const B: u32 = 1 << 16;
    if d == 0 || (n >> 32) >= u64::from(d) {
        return None;
    }
    let s = d.leading_zeros();
    let v = d << s;
    // `n << s` does not overflow: `n >> 32 < d < 2^(32 - s)`.
    let n_norm = n << s;
    let un32 = (n_norm >> 32) as u32;
    let un10 = n_norm as u32;
    let (vn1, vn0) = (v >> 16, v & 0xFFFF);
    let (un1, un0) = (un10 >> 16, un10 & 0xFFFF);
    // `vn1 >= 2^15` (the top bit of `v` is set): never zero.
    let vn1_nz = core::num::NonZeroU32::new(vn1)?;
    // One quotient digit of `top / v`, where `top` is the two-digit remainder `hi` followed
    // by the digit `lo`, with `hi < v`; and the new remainder.
    let digit = |hi: u32, lo: u32| -> (u32, u32) {
        let mut q = hi / vn1_nz;
        let mut rhat = hi - q * vn1;
        // At most two corrections (Knuth's Theorem B). `q < B` before the product: no wrap;
        // `rhat < B` in the comparison: no wrap.
        for _ in 0..2 {
            if q >= B || q * vn0 > (rhat << 16 | lo) {
                q -= 1;
                rhat += vn1;
                if rhat < B {
                    continue;
                }
            }
            break;
        }
        // The remainder is below `v`: the wrapping arithmetic gives it exactly.
        let rem = (hi << 16).wrapping_add(lo).wrapping_sub(q.wrapping_mul(v));
        (q, rem)
    };
    let (q1, r1) = digit(un32, un1);
    let (q0, r0) = digit(r1, un0);
    Some((q1 << 16 | q0, r0 >> s))
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
    #[inline]
    fn div_round_area(self, g: u32, w: u64, h: u64) -> Result<u64, Error> {
        if self == 0 {
            return Ok(0);
        }
        // Sides below 2^32 (any box on a texture a microcontroller holds, at any F): the area is
        // one 32 x 32 -> 64 multiply, no overflow check.
        if let (Ok(w32), Ok(h32)) = (u32::try_from(w), u32::try_from(h)) {
            let area = u64::from(w32) * u64::from(h32);
            if area != 0 && g < 64 && bits64(self) + g <= 64 {
                let n = self << g;
                // On 32-bit cores, an area below 2^32 and a quotient below 2^32 (the usual
                // mean): two hardware divides instead of the `u64` division routine. (Also in
                // the host's unit tests, so they check this path against the reference.)
                #[cfg(any(not(target_pointer_width = "64"), test))]
                if let Some((q, r)) = u32::try_from(area)
                    .ok()
                    .and_then(|a| div_u64_by_u32(n, a))
                {
                    let (q, r) = (u64::from(q), u64::from(r));
                    return Ok(if r >= area - r { q + 1 } else { q });
                }
                let (q, r) = (n / area, n % area);
                return Ok(if r >= area - r { q + 1 } else { q });
            }
        }
        if let Some(area) = w.checked_mul(h) {
            if area != 0 && g < 64 && bits64(self) + g <= 64 {
                // The common case: one u64 division (quotient and remainder together).
                let n = self << g;
                let (q, r) = (n / area, n % area);
                return Ok(if r >= area - r { q + 1 } else { q });
            }
        }
        if w == 0 || h == 0 {
            return Err(Error::ZeroArea);
        }
        if g > 128 {
            return Err(too_wide(bits64(self).saturating_add(g), 64));
        }
        div_round_long(self, g, w, h)
    }
}

impl Wide for u128 {
    const BITS: u32 = 128;
    const ZERO: Self = 0;
    #[inline(always)]
    fn bits(self) -> u32 {
        128 - self.leading_zeros()
    }
    #[inline(always)]
    fn shr(self, s: u32) -> Self {
        self >> (s & 127)
    }
    #[inline(always)]
    fn checked_mul_u64(self, m: u64) -> Option<Self> {
        self.checked_mul(m as u128)
    }
    #[inline(always)]
    fn checked_add(self, o: Self) -> Option<Self> {
        u128::checked_add(self, o)
    }
    fn div_round_area(self, g: u32, w: u64, h: u64) -> Result<u128, Error> {
        let area = w as u128 * h as u128;
        if area == 0 {
            return Err(Error::ZeroArea);
        }
        let needed = self.bits().saturating_add(g);
        if needed > 128 || g >= 128 {
            return Err(too_wide(needed, 128));
        }
        let n = self << g;
        let (q, r) = (n / area, n % area);
        Ok(if r >= area - r { q + 1 } else { q })
    }
}

/// `round(num * 2^shift / den)`, ties up, for `0 < den < 2^127`, by restoring division (no
/// intermediate wider than `2 den`); a quotient above `u64` is [`Error::TooWide`], a zero `den`
/// [`Error::ZeroArea`]. The one 128-bit rounded division of the crate, for the quantities that
/// are 128-bit by nature (the tent filter's order-2 sums, the variance of `u64` tables).
#[allow(dead_code)] // used only by some filter features
pub(crate) fn div_round_shift_u128(num: u128, shift: u32, den: u128) -> Result<u64, Error> {
    let wide = || too_wide(65, 64);
    let Some(den) = core::num::NonZeroU128::new(den) else {
        return Err(Error::ZeroArea);
    };
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
        q += 1;
    }
    u64::try_from(q).map_err(|_| wide())
}

#[cfg(test)]
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
        for i in 0..20_000 {
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

    #[test]
    fn div_u64_by_u32_is_exact_or_refuses() {
        let check = |n: u64, d: u32| {
            let got = div_u64_by_u32(n, d);
            if d == 0 || n / u64::from(d) > u64::from(u32::MAX) {
                assert_eq!(got, None, "{n} / {d}");
            } else {
                let (q, r) = (n / u64::from(d), n % u64::from(d));
                assert_eq!(got, Some((q as u32, r as u32)), "{n} / {d}");
            }
        };
        // Exhaustive over small dividends and divisors.
        for d in 0..=300u32 {
            for n in 0..=3000u64 {
                check(n, d);
            }
        }
        // Every normalization shift, the extremes of each digit, and random values.
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for shift in 0..32 {
            for _ in 0..20_000 {
                let d = ((next() as u32) >> shift).max(1);
                // A quotient that fits: n < d 2^32.
                let n = next() % (u64::from(d) << 32);
                check(n, d);
                check(u64::from(d) << 32, d); // quotient 2^32: refused
                check((u64::from(d) << 32) - 1, d); // the largest accepted
                check(next(), d);
            }
        }
        for d in [1, 2, 0xFFFF, 0x1_0000, 0x1_0001, 0x8000_0000, 0xFFFF_FFFF] {
            for n in [0, 1, u64::from(d) - 1, u64::from(d), u64::MAX, u64::MAX >> 1] {
                check(n, d);
            }
        }
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
}
