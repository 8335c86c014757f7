//! Level and footprint math in fixed point: `log2` from the leading zeros plus fraction bits by
//! repeated squaring, no floats.

/// `log2(raw / 2^f)` as a fixed-point number with `out_frac` fractional bits (`out_frac <= 16`),
/// or `None` for `raw == 0`.
///
/// The integer part comes from the position of the highest set bit; each fraction bit from one
/// squaring of the normalised mantissa (in `[1, 2)`, 63 fraction bits, truncated after each
/// squaring). Rounding: the result is the exact `floor(log2(x) * 2^out_frac)` or one unit below
/// it (the truncations only ever lower the mantissa); tested against `f64` in the unit tests.
pub fn log2_fixed(raw: u64, f: u32, out_frac: u32) -> Option<i32> {
    if raw == 0 || out_frac > 16 || f > 63 {
        return None;
    }
    let e = 63 - raw.leading_zeros(); // raw in [2^e, 2^(e+1))
    let int_part = e as i32 - f as i32;
    // Mantissa raw / 2^e in Q1.63.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powers_of_two_are_exact() {
        for e in 0..40u32 {
            assert_eq!(log2_fixed(1u64 << e, 8, 8), Some(((e as i32) - 8) << 8));
        }
        assert_eq!(log2_fixed(0, 0, 8), None);
    }

    #[test]
    fn within_one_ulp_below_f64() {
        let mut x = 1u64;
        for _ in 0..2000 {
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
