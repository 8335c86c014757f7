//! Exact decimal input and output of fixed-point numbers (no floating point anywhere).
//!
//! Every dyadic rational `v / 2^k` has a finite decimal expansion (`k` digits at most after the
//! point), so sums and means are printed exactly; coordinates are parsed exactly and either
//! refused or rounded when they are not multiples of `2^-F`.

/// The exact decimal expansion of `v / 2^k`: every digit, no trailing zeros after the point, no
/// point for an integer. `k <= 124` (so `10 * (2^k - 1)` fits `u128`).
pub fn fixed_decimal(v: u128, k: u32) -> String {
    assert!(k <= 124, "fixed_decimal: k = {k} > 124");
    let mut out = (v >> k).to_string();
    let mask = (1u128 << k) - 1;
    let mut frac = v & mask;
    if frac != 0 {
        out.push('.');
        while frac != 0 {
            frac *= 10;
            out.push(char::from(b'0' + (frac >> k) as u8));
            frac &= mask;
        }
    }
    out
}

/// `n` with thousands separators (`16,711,680`), for the demo's prose.
pub fn grouped(n: u128) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

/// How [`parse_fixed`] treats a decimal that is not a multiple of `2^-F`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Inexact {
    /// Refuse it (the default: a test bench should not be rounded behind its back).
    Refuse,
    /// Round to the nearest multiple of `2^-F`, ties toward +infinity.
    Round,
}

/// Parses a decimal number `[+-]digits[.digits]` (at least one digit) *exactly* and returns
/// `value * 2^f` as an `i64` (the raw bits of a fixed-point number with `f` fractional bits,
/// `f <= 24`, else an error). A value that is not a multiple of `2^-f` is refused or rounded per
/// `inexact`.
pub fn parse_fixed(s: &str, f: u32, inexact: Inexact) -> Result<i64, String> {
    if f > 24 {
        return Err(format!("{f} fractional bits are outside 0..=24"));
    }
    let (neg, body) = match s.as_bytes().first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    let (int_str, frac_str) = match body.split_once('.') {
        Some((i, fr)) => (i, fr),
        None => (body, ""),
    };
    let all_digits = |t: &str| t.bytes().all(|b| b.is_ascii_digit());
    if int_str.len() + frac_str.len() == 0 || !all_digits(int_str) || !all_digits(frac_str) {
        return Err(format!("'{s}' is not a decimal number"));
    }
    let out_of_range = || format!("'{s}' is out of range");
    let mut int: u128 = 0;
    for b in int_str.bytes() {
        int = int
            .checked_mul(10)
            .and_then(|v| v.checked_add(u128::from(b - b'0')))
            .filter(|&v| v < 1 << 100)
            .ok_or_else(out_of_range)?;
    }
    // floor(x * 2^(f+1)) of the fraction x = 0.d1 d2 ... dn, and whether the product is an
    // integer, by long multiplication from the last digit: exact for any number of digits.
    let m: u64 = 1 << (f + 1);
    let mut carry: u64 = 0;
    let mut rest_zero = true;
    for b in frac_str.bytes().rev() {
        let t = u64::from(b - b'0') * m + carry;
        rest_zero &= t.is_multiple_of(10);
        carry = t / 10;
    }
    let (mut q, half, above_half) = (carry >> 1, carry & 1 == 1, !rest_zero);
    let exact = !half && rest_zero;
    if !exact {
        if inexact == Inexact::Refuse {
            return Err(format!(
                "'{s}' is not a multiple of 2^-{f} (not representable with {f} fractional bits; \
                 use --round or more --frac-bits)"
            ));
        }
        // Round the magnitude: up above one half; at exactly one half, toward +infinity.
        let tie = half && !above_half;
        if (half && above_half) || (tie && !neg) {
            q += 1;
        }
    }
    let magnitude = (int << f) + u128::from(q);
    let signed = if neg {
        -(magnitude as i128)
    } else {
        magnitude as i128
    };
    i64::try_from(signed).map_err(|_| out_of_range())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_output() {
        assert_eq!(fixed_decimal(0, 16), "0");
        assert_eq!(fixed_decimal(3 << 16, 16), "3");
        assert_eq!(fixed_decimal(3, 1), "1.5");
        assert_eq!(fixed_decimal(1, 24), "0.000000059604644775390625");
        let near_one = fixed_decimal(u128::MAX >> 4, 124); // 1 - 2^-124: 124 digits
        assert!(near_one.starts_with("0.99999999") && near_one.ends_with('5'));
        assert_eq!(near_one.len(), 126);
        assert_eq!(grouped(16711680), "16,711,680");
        assert_eq!(grouped(999), "999");
    }

    #[test]
    fn decimal_input() {
        let r = Inexact::Refuse;
        assert_eq!(parse_fixed("1.25", 8, r), Ok(320));
        assert_eq!(parse_fixed("-1.25", 8, r), Ok(-320));
        assert_eq!(parse_fixed("+3", 0, r), Ok(3));
        assert_eq!(parse_fixed(".5", 1, r), Ok(1));
        assert_eq!(parse_fixed("2.", 1, r), Ok(4));
        assert_eq!(
            parse_fixed("0.500000000000000000000000000000000000000000", 1, r),
            Ok(1)
        );
        assert!(parse_fixed("0.3", 8, r).is_err());
        assert!(parse_fixed("0.5", 0, r).is_err());
        assert!(parse_fixed("1e3", 8, r).is_err());
        assert!(parse_fixed("", 8, r).is_err());
        assert!(parse_fixed(".", 8, r).is_err());
        assert!(parse_fixed("-", 8, r).is_err());
        assert!(parse_fixed("nan", 8, r).is_err());
        assert!(parse_fixed("99999999999999999999", 8, r).is_err());
        assert!(parse_fixed("1", 25, r).is_err());
        assert!(parse_fixed("1", u32::MAX, r).is_err());
        assert_eq!(parse_fixed("1", 24, r), Ok(1 << 24));
        let n = Inexact::Round;
        assert_eq!(parse_fixed("0.3", 2, n), Ok(1)); // 1.2 -> 1
        assert_eq!(parse_fixed("0.4", 2, n), Ok(2)); // 1.6 -> 2
        assert_eq!(parse_fixed("0.125", 2, n), Ok(1)); // tie 0.5 -> up
        assert_eq!(parse_fixed("-0.125", 2, n), Ok(0)); // tie -0.5 -> toward +inf
        assert_eq!(
            parse_fixed("-0.1250000000000000000000000000001", 2, n),
            Ok(-1)
        );
        assert_eq!(
            parse_fixed("0.1249999999999999999999999999999", 2, n),
            Ok(0)
        );
        assert_eq!(parse_fixed("2.5", 0, n), Ok(3));
        assert_eq!(parse_fixed("-2.5", 0, n), Ok(-2));
        assert_eq!(parse_fixed("0.99999999999", 4, n), Ok(16));
    }
}
