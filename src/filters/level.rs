//! Level and footprint math in fixed point: `log2` from the leading zeros plus fraction bits by
//! repeated squaring, no floats, no integer wider than 64 bits.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

/// `log2(raw / 2^f)` as a fixed-point number with `out_frac` fractional bits (`out_frac <= 16`),
/// or `None` for `raw == 0` (and for `out_frac > 16` or `f > 63`).
///
/// The integer part comes from the position of the highest set bit; each fraction bit from one
/// squaring of the normalised mantissa `M` in `[1, 2)` (repeated squaring: `M^2` in `[2, 4)`
/// gives a one bit and is halved). Rounding: the result is the exact
/// `floor(log2(x) * 2^out_frac)` or one unit below it (the truncations only ever lower the
/// mantissa); tested against `f64` in the unit tests.
///
/// **Arithmetic.** The result is bit for bit that of squaring a Q1.63 mantissa with truncation
/// after each squaring and halving (the crate's earlier 128-bit formulation), computed in 64-bit
/// words:
///
/// * the hot path squares a Q1.31 mantissa in `u64` (`m < 2^32`, so `m^2 < 2^64`: one
///   `32 x 32 -> 64` multiply per fraction bit, a single `UMULL` on a Cortex-M4);
/// * it can differ from the Q1.63 result only where the Q1.63 squaring would set a bit that the
///   Q1.31 one misses by its extra truncation, and then the Q1.31 mantissa ends just below 2
///   (proof below). A final mantissa of at least `2 (1 - 2^-13)` therefore falls back to the
///   Q1.63 squaring done in 64-bit halves (three `32 x 32 -> 64` multiplies per bit, no `u128`);
///   a fraction of about `2^-13` of all inputs takes it.
///
/// *Proof of the fallback test.* Write `φ_j` (Q1.31) and `ω_j` (Q1.63) for the mantissas after
/// `j` bits. Truncating to `2^-31` instead of `2^-63` can only lower a value, and squaring is
/// monotone, so `φ_j <= ω_j` while the bits agree. Per step the Q1.31 path loses at most a factor
/// `(1 - 2^-31)` to the squaring's truncation and one more to the halving's, so with
/// `ε_j = log2(ω_j / φ_j)`: `ε_0 <= 1.443 * 2^-31` (the first truncation of `raw`),
/// `ε_{j+1} <= 2 ε_j + 2.886 * 2^-31`, hence `ε_16 < 2^16 * 4.33 * 2^-31 < 2^-12.8`. If the
/// first disagreement is at bit `j` (it can only be Q1.63 one, Q1.31 zero, as `φ <= ω`), then
/// `φ_j^2 >= 2^(2 - 2 ε)`-ish: the unhalved Q1.31 mantissa is at least `2^(1 - ε_j)`; every later
/// squaring of a value that close to 2 is at least 2 again, so it stays at least
/// `2^(1 - ε_k) > 2 (1 - 2^-13)` to the end. So a final Q1.31 mantissa below `2 (1 - 2^-13)`
/// proves that no bit disagreed.
#[inline]
pub fn log2_fixed(raw: u64, f: u32, out_frac: u32) -> Option<i32> {
    if raw == 0 || out_frac > 16 || f > 63 {
        return None;
    }
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "raw != 0: leading_zeros <= 63"
    )]
    let e = 63 - raw.leading_zeros(); // raw in [2^e, 2^(e+1))
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "e, f <= 63: the difference is in [-63, 63]"
    )]
    let int_part = e.cast_signed() - f.cast_signed();
    // Q1.31: the top 32 significant bits of raw, in [2^31, 2^32).
    #[allow(
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "each subtraction is guarded by its branch (e <= 63); raw in [2^e, 2^(e+1)) \
                  shifted to [2^31, 2^32) fits u32"
    )]
    let mut m = (if e >= 31 {
        raw >> (e - 31)
    } else {
        raw << (31 - e)
    }) as u32;
    let mut frac = 0i32;
    for _ in 0..out_frac {
        // The square in Q2.62, one `32 x 32 -> 64` multiply: in [2^62, 2^64). At least 2
        // (2^63) gives a one bit and the halved square `p >> 32`; else the square `p >> 31`,
        // below 2^32. (The same truncations as squaring to Q1.31 in `u64` and halving: both
        // are `floor(p / 2^32)` and `floor(p / 2^31)`.) All in 32-bit words: the high word's
        // top bit decides.
        #[allow(clippy::arithmetic_side_effects, reason = "m < 2^32: m^2 < 2^64")]
        let p = u64::from(m) * u64::from(m);
        #[allow(clippy::as_conversions, reason = "p >> 32 < 2^32: lossless")]
        let hi = (p >> 32) as u32;
        if hi >> 31 != 0 {
            frac = (frac << 1) | 1;
            m = hi;
        } else {
            frac <<= 1;
            #[allow(
                clippy::as_conversions,
                reason = "the high word's top bit is clear: p < 2^63, so p >> 31 < 2^32"
            )]
            let low = (p >> 31) as u32;
            m = low;
        }
    }
    if u64::from(m) >= FALLBACK_FROM {
        #[allow(clippy::arithmetic_side_effects, reason = "e <= 63")]
        let mantissa = raw << (63 - e);
        frac = frac_q63(mantissa, out_frac);
    }
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "|int_part| <= 63 and out_frac <= 16: |int_part << out_frac| < 2^22, and \
                  0 <= frac < 2^16"
    )]
    let log = (int_part << out_frac) + frac;
    Some(log)
}

/// Final Q1.31 mantissas from `2^32 (1 - 2^-13)` up may hide a bit the Q1.63 squaring sets
/// ([`log2_fixed`]'s proof).
const FALLBACK_FROM: u64 = (1 << 32) - (1 << 19);

/// The fraction bits of `log2` of the Q1.63 mantissa `m` in `[2^63, 2^64)`: square, truncate to
/// 63 fraction bits, take the bit at `2^64`, halve (truncating); the square's upper 65 bits come
/// from three `32 x 32 -> 64` products.
#[inline(never)]
#[cold]
fn frac_q63(mut m: u64, out_frac: u32) -> i32 {
    let mut frac = 0i32;
    for _ in 0..out_frac {
        let (hi, lo) = square_u64(m);
        // (m^2) >> 63 has 65 bits: hi << 1 | lo >> 63. Its top bit is hi's top bit.
        let bit = hi >> 63 != 0;
        frac = (frac << 1) | i32::from(bit);
        m = if bit { hi } else { (hi << 1) | (lo >> 63) };
    }
    frac
}

/// `m^2` as `(high, low)` 64-bit words, from the 32-bit halves of `m` (no 128-bit operation).
#[inline(always)]
fn square_u64(m: u64) -> (u64, u64) {
    let (mh, ml) = (m >> 32, m & 0xFFFF_FFFF);
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "mh, ml < 2^32: each product < 2^64"
    )]
    let (hh, hl, ll) = (mh * mh, mh * ml, ml * ml);
    // hl is counted twice: 2 hl 2^32 = (hl >> 31) 2^64 + (hl << 33).
    let (lo, carry) = ll.overflowing_add(hl << 33);
    // m^2 < 2^128: the high word cannot overflow.
    let hi = hh.wrapping_add(hl >> 31).wrapping_add(u64::from(carry));
    (hi, lo)
}

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
    use std::vec::Vec;

    /// The earlier formulation, Q1.63 squared in `u128`: the reference the 64-bit one must match
    /// bit for bit.
    fn log2_fixed_u128(raw: u64, f: u32, out_frac: u32) -> Option<i32> {
        if raw == 0 || out_frac > 16 || f > 63 {
            return None;
        }
        let e = 63 - raw.leading_zeros();
        let int_part = e as i32 - f as i32;
        let mut m: u128 = (raw as u128) << (63 - e);
        let mut frac = 0i32;
        for _ in 0..out_frac {
            m = (m * m) >> 63;
            frac <<= 1;
            if m >= 1u128 << 64 {
                frac |= 1;
                m >>= 1;
            }
        }
        Some((int_part << out_frac) + frac)
    }

    #[test]
    fn powers_of_two_are_exact() {
        for e in 0..40u32 {
            assert_eq!(log2_fixed(1u64 << e, 8, 8), Some(((e as i32) - 8) << 8));
        }
        assert_eq!(log2_fixed(0, 0, 8), None);
        assert_eq!(log2_fixed(5, 0, 17), None);
        assert_eq!(log2_fixed(5, 64, 8), None);
    }

    #[test]
    fn square_u64_matches_u128() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        // Under Miri (about 10^4 times slower) 1000 random values (the extremes run every round).
        for _ in 0..if cfg!(miri) { 1_000 } else { 100_000 } {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            for m in [x, x | 1 << 63, u64::MAX, 1 << 63, x >> 32] {
                let (hi, lo) = square_u64(m);
                assert_eq!(((hi as u128) << 64) | lo as u128, m as u128 * m as u128);
            }
        }
    }

    #[test]
    fn bit_for_bit_with_the_u128_formulation() {
        // Exhaustive below 2^20 for every output width the filters use, and the fraction
        // widths 1..=16 on a smaller range. Under Miri (about 10^4 times slower) every input
        // below `dense`, the neighbours of every power of two up to the limit, every
        // `stride`-th input, and 300 random ones.
        let inputs = |limit: u64, dense: u64, stride: usize| -> Vec<u64> {
            if !cfg!(miri) {
                return (1..limit).collect();
            }
            let mut v: Vec<u64> = (1..dense)
                .chain((1..64 - limit.leading_zeros()).flat_map(|k| {
                    let p = 1u64 << k;
                    [p - 1, p, p + 1]
                }))
                .chain((dense..limit).step_by(stride))
                .filter(|&v| v < limit)
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        for raw in inputs(1 << 20, 64, 8191) {
            for out in [8u32, 12, 16] {
                assert_eq!(
                    log2_fixed(raw, 0, out),
                    log2_fixed_u128(raw, 0, out),
                    "{raw} {out}"
                );
            }
        }
        for raw in inputs(1 << 12, 16, 257) {
            for out in 0..=16u32 {
                assert_eq!(log2_fixed(raw, 5, out), log2_fixed_u128(raw, 5, out));
            }
        }
        // Inputs where the Q1.31 squaring alone gives one unit less (found by a sweep below
        // 2^26): the fallback must catch each.
        for (raw, out) in [(14_812_507u64, 8u32), (1_391_023, 12), (14_917, 16)] {
            assert_eq!(
                log2_fixed(raw, 0, out),
                log2_fixed_u128(raw, 0, out),
                "{raw}"
            );
        }
        // Random 64-bit inputs of every magnitude.
        let mut s = 1u64;
        for _ in 0..if cfg!(miri) { 300 } else { 300_000 } {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let raw = s >> (s % 61);
            for out in [8u32, 12, 16] {
                assert_eq!(
                    log2_fixed(raw, 24, out),
                    log2_fixed_u128(raw, 24, out),
                    "{raw}"
                );
            }
        }
        for raw in [
            u64::MAX,
            u64::MAX - 1,
            (1 << 63) + 1,
            (1 << 32) - 1,
            1 << 32,
        ] {
            for out in 0..=16u32 {
                assert_eq!(log2_fixed(raw, 3, out), log2_fixed_u128(raw, 3, out));
            }
        }
    }

    #[test]
    fn within_one_ulp_below_f64() {
        let mut x = 1u64;
        // Under Miri (about 10^4 times slower) 400 random inputs.
        for _ in 0..if cfg!(miri) { 400 } else { 2000 } {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let raw = (x >> 20) | 1;
            for f in [0u32, 8, 16] {
                for out in [4u32, 8, 12] {
                    let got = log2_fixed(raw, f, out).unwrap() as f64;
                    let want = ((raw as f64).log2() - f as f64) * (1u64 << out) as f64;
                    assert!(
                        got <= want.floor() + 1e-9 && got >= want.floor() - 1.0,
                        "{raw} {f} {out}: {got} vs {want}"
                    );
                }
            }
        }
    }
}
