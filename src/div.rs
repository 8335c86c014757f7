//! Integer division on 32-bit cores without the 64-bit library routine.
//!
//! A Cortex-M4 divides 32 by 32 bits in hardware (`UDIV`, 2 to 12 cycles) but has no 64-bit
//! divide: `u64 / u64` in Rust calls `__aeabi_uldivmod`, a loop of a few hundred instructions that
//! also links about 1 KiB of `compiler_builtins` into the firmware. The lookups divide 64-bit
//! values in a few places (the mean by the box's area, the whole periods of a [`crate::Repeat`]
//! box), almost always by a divisor below `2^32`; these functions do that with hardware 32-bit
//! divides, and the rare divisor of 33 to 64 bits with a bounded shift-and-subtract loop, so the
//! library routine is never linked.
//!
//! On 64-bit hosts (outside this module's tests) they are the native operations: there `u64 /
//! u64` is one instruction.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

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
#[cfg(any(not(target_pointer_width = "64"), test))]
#[inline]
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "one proof, Knuth's Algorithm D with b = 2^16 (Theorem B), covers the function, step by \
              step in the comments: n << s loses no bit (n >> 32 < d < 2^(32 - s)); the two casts take \
              the high and low 32-bit words; q <= hi / vn1 so hi - q vn1 >= 0; q < B and rhat < B where \
              q vn0 and rhat << 16 are formed (no wrap); q is decremented only while it is too large \
              (q >= 1), rhat + vn1 < 2^17; digits q1, q0 < 2^16, so q1 << 16 | q0 loses nothing"
)]
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

/// `(n / d, n % d)` for any `n` and `d != 0`; `None` for `d = 0`.
///
/// Divisor below `2^32`: the high word by one hardware divide, then the rest (remainder
/// followed by the low word, whose quotient fits 32 bits) by [`div_u64_by_u32`]. Divisor of 33
/// to 64 bits: the quotient is below `2^32`, found bit by bit from the top (at most 32 steps of
/// a comparison and a subtraction).
#[inline]
pub(crate) fn divrem_u64(n: u64, d: u64) -> Option<(u64, u64)> {
    #[cfg(all(target_pointer_width = "64", not(test)))]
    {
        divrem_native(n, d)
    }
    #[cfg(any(not(target_pointer_width = "64"), test))]
    {
        divrem_u64_narrow(n, d)
    }
}

/// `(n / d, n % d)` by the host's native 64-bit division; `None` for `d = 0`.
#[cfg(all(target_pointer_width = "64", not(test)))]
#[inline(always)]
fn divrem_native(n: u64, d: u64) -> Option<(u64, u64)> {
    let d = core::num::NonZeroU64::new(d)?;
    Some((n / d, n % d))
}

/// [`divrem_u64`] as a 32-bit core computes it (also compiled on hosts for the tests).
#[cfg(any(not(target_pointer_width = "64"), test))]
#[inline]
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "the cast takes the high 32-bit word (n >> 32 < 2^32); the shifts move 32-bit \
              words into place"
)]
fn divrem_u64_narrow(n: u64, d: u64) -> Option<(u64, u64)> {
    if let Ok(d32) = u32::try_from(d) {
        let d32 = core::num::NonZeroU32::new(d32)?;
        let hi = (n >> 32) as u32;
        let (q_hi, r_hi) = (hi / d32, hi % d32);
        // r_hi < d: the quotient of `r_hi 2^32 + lo` fits 32 bits.
        let (q_lo, r) = div_u64_by_u32(u64::from(r_hi) << 32 | (n & 0xFFFF_FFFF), d32.get())?;
        return Some((u64::from(q_hi) << 32 | u64::from(q_lo), u64::from(r)));
    }
    // d >= 2^32: q < 2^32, found bit by bit (at most 32 steps).
    divrem_u64_bits(n, d)
}

/// `(n / d, n % d)` for any `n` and `d != 0` (`None` for `d = 0`) in the least code: on a
/// 32-bit core restoring division, one quotient bit per step from the top (`bits(n) - bits(d) +
/// 1` steps of a compare and a subtract, at most 64), native on 64-bit hosts.
///
/// Why: the boundary modes divide 64-bit operands only for coordinates or box widths past 32
/// bits (a firmware's `i32` corners never reach them), yet [`divrem_u64`]'s fast path for such
/// operands (two 16-bit digit steps and a hardware divide, inlined) costs about 440 bytes of
/// Cortex-M4 flash in every firmware that places Repeat or Mirror boxes; this loop, out of
/// line, about 210 (Stable + Repeat firmware: 228 bytes less, docs/benchmarks.md).
#[inline(never)]
pub(crate) fn divrem_u64_small(n: u64, d: u64) -> Option<(u64, u64)> {
    #[cfg(all(target_pointer_width = "64", not(test)))]
    {
        divrem_native(n, d)
    }
    #[cfg(any(not(target_pointer_width = "64"), test))]
    {
        divrem_u64_bits(n, d)
    }
}

/// [`divrem_u64_small`] as a 32-bit core computes it (also compiled on hosts for the tests).
#[cfg(any(not(target_pointer_width = "64"), test))]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "lz(d) - lz(n) >= 0 as n >= d; d << i loses no bit (i <= lz(d) - lz(n) <= lz(d)) and \
              1 << i has i <= 63; r -= step only when r >= step"
)]
fn divrem_u64_bits(n: u64, d: u64) -> Option<(u64, u64)> {
    if d == 0 {
        return None;
    }
    if n < d {
        return Some((0, n));
    }
    // Align d's top bit with n's, then one quotient bit per step, the step and its bit shifted
    // right by one each time (constant shifts: a 64-bit shift by a variable amount is a
    // branchy sequence on a 32-bit core); the low bits of `d << i` are zero, so the shifts are
    // exact and the steps are d 2^i, ..., d.
    let i = d.leading_zeros() - n.leading_zeros();
    let (mut step, mut bit) = (d << i, 1u64 << i);
    let (mut q, mut r) = (0u64, n);
    while bit != 0 {
        if r >= step {
            r -= step;
            q |= bit;
        }
        step >>= 1;
        bit >>= 1;
    }
    Some((q, r))
}

/// `(floor(x / p), x mod p)` (so `0 <= x mod p < p`) for `p > 0`; `None` for `p <= 0`. By
/// [`divrem_u64_small`] on `|x|` (its callers divide 64-bit operands only in rare cases).
#[inline]
pub(crate) fn div_euclid_i64(x: i64, p: i64) -> Option<(i64, i64)> {
    if p <= 0 {
        return None;
    }
    // p > 0: the bit pattern is the value.
    let (q, r) = divrem_u64_small(x.unsigned_abs(), p.cast_unsigned())?;
    // |x| <= 2^63 and p >= 1: q <= 2^63, r < p; both fit i64 except q = 2^63 for x = i64::MIN,
    // p = 1, where -q is i64::MIN itself (the reinterpretation gives i64::MIN, and its wrapping
    // negation is i64::MIN again).
    let (q, r) = (q.cast_signed(), r.cast_signed());
    Some(if x >= 0 {
        (q, r)
    } else if r == 0 {
        (q.wrapping_neg(), 0)
    } else {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "0 < r < p: p - r is in (0, p)"
        )]
        let rest = p - r;
        (q.wrapping_neg().wrapping_sub(1), rest)
    })
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
mod tests {
    use super::*;

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
        // Exhaustive over small dividends and divisors (under Miri, which interprets each check
        // about 10^4 times slower, a smaller square and fewer random rounds per shift: every
        // shift and every edge below still runs).
        let (max_d, max_n, rounds) = if cfg!(miri) {
            (16, 80, 8)
        } else {
            (300, 3000, 20_000)
        };
        for d in 0..=max_d {
            for n in 0..=max_n {
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
            for _ in 0..rounds {
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
            for n in [
                0,
                1,
                u64::from(d) - 1,
                u64::from(d),
                u64::MAX,
                u64::MAX >> 1,
            ] {
                check(n, d);
            }
        }
    }

    #[test]
    fn divrem_u64_matches_native() {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let check = |n: u64, d: u64| {
            let want = n.checked_div(d).zip(n.checked_rem(d));
            assert_eq!(divrem_u64_narrow(n, d), want, "{n} / {d}");
            assert_eq!(divrem_u64_bits(n, d), want, "bits: {n} / {d}");
        };
        // Under Miri (about 10^4 times slower) a smaller square and fewer random pairs; the
        // edges below run in full.
        let (small, rounds) = if cfg!(miri) {
            (24u64, 1_500)
        } else {
            (300, 200_000)
        };
        for n in 0..small {
            for d in 0..small {
                check(n, d);
            }
        }
        let edges = [
            0u64,
            1,
            2,
            u32::MAX as u64 - 1,
            u32::MAX as u64,
            1 << 32,
            (1 << 32) + 1,
            u64::MAX >> 1,
            (u64::MAX >> 1) + 1,
            u64::MAX - 1,
            u64::MAX,
        ];
        for &n in &edges {
            for &d in &edges {
                check(n, d);
            }
        }
        for _ in 0..rounds {
            let (n, d) = (next() >> (next() % 64), next() >> (next() % 64));
            check(n, d);
        }
    }

    #[test]
    fn div_euclid_i64_matches_native() {
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let check = |x: i64, p: i64| {
            let want = if p <= 0 {
                None
            } else {
                Some((x.div_euclid(p), x.rem_euclid(p)))
            };
            assert_eq!(div_euclid_i64(x, p), want, "{x} / {p}");
        };
        // Under Miri (about 10^4 times slower) a smaller square and fewer random pairs; the
        // extremes below run in full.
        let (small, rounds) = if cfg!(miri) {
            (24i64, 1_500)
        } else {
            (300, 200_000)
        };
        for x in -small..small {
            for p in -3i64..small {
                check(x, p);
            }
        }
        for &x in &[i64::MIN, i64::MIN + 1, -1, 0, 1, i64::MAX - 1, i64::MAX] {
            for &p in &[1i64, 2, 3, u32::MAX as i64, 1 << 32, i64::MAX] {
                check(x, p);
            }
        }
        for _ in 0..rounds {
            let x = (next() as i64) >> (next() % 64);
            let p = ((next() >> 1) >> (next() % 63)).max(1) as i64;
            check(x, p);
        }
    }
}
