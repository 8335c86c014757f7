//! The `sat` CLI's text parsing against exact references: `parse_fixed` and `fixed_decimal`
//! (`tools/examples/sat/num.rs`, compiled in by `#[path]`), `parse_box` (the query-line parser,
//! copied out of `tools/examples/sat.rs` by `build.rs`), and `budget::parse_amount` (the
//! `--max-memory`/`--max-work` parser, from the tools' library).
//!
//! References, in big integers: a decimal `[+-]digits[.digits]` is the rational `N / 10^d`; its
//! raw value at `F` fractional bits is `N 2^F / 10^d`, refused when not an integer (or rounded to
//! nearest, ties toward +infinity, with `Inexact::Round`) and when outside `i64`.
#![no_main]

#[path = "../../tools/examples/sat/num.rs"]
#[allow(dead_code)]
mod num;

/// `parse_box`, as the CLI has it.
mod sat {
    use crate::num::{parse_fixed, Inexact};
    include!(concat!(env!("OUT_DIR"), "/parse_box.rs"));
}

use arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use num::{fixed_decimal, parse_fixed, Inexact};
use num_bigint::{BigInt, BigUint};

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = run(&mut u);
});

/// A string that is usually a decimal (sign, up to 60 integer digits, a point, up to 40
/// fraction digits), sometimes with a stray character, sometimes arbitrary.
fn decimal(u: &mut Unstructured<'_>) -> Result<String> {
    if u.ratio(1u8, 8)? {
        return u.arbitrary();
    }
    let mut s = String::new();
    s.push_str(u.choose(&["", "", "-", "+"])?);
    let digits = |u: &mut Unstructured<'_>, s: &mut String, max: usize| -> Result<()> {
        let n = if u.ratio(1u8, 8)? {
            u.int_in_range(0..=max)?
        } else {
            u.int_in_range(0..=6)?
        };
        for _ in 0..n {
            s.push(char::from(b'0' + u.int_in_range(0..=9)?));
        }
        Ok(())
    };
    digits(u, &mut s, 60)?;
    if u.ratio(2u8, 3)? {
        s.push('.');
        digits(u, &mut s, 40)?;
    }
    if u.ratio(1u8, 16)? {
        let at = u.int_in_range(0..=s.len())?;
        let c = *u.choose(&['.', '-', '+', 'e', ' ', '\u{e9}', '0', '5', '_'])?;
        s.insert(at, c);
    }
    Ok(s)
}

/// The reference: `Some(raw)` or `None` (refused).
fn parse_ref(s: &str, f: u32, round: bool) -> Option<i64> {
    let (neg, body) = match s.as_bytes().first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    let (int, frac) = body.split_once('.').unwrap_or((body, ""));
    let digits = |t: &str| t.bytes().all(|b| b.is_ascii_digit());
    if int.len() + frac.len() == 0 || !digits(int) || !digits(frac) {
        return None;
    }
    let all = format!("{int}{frac}");
    let n = if all.is_empty() {
        BigUint::ZERO
    } else {
        all.parse::<BigUint>().ok()?
    };
    let num = n << f;
    let den = BigUint::from(10u8).pow(frac.len() as u32);
    let (q, r) = (&num / &den, &num % &den);
    let mag = if r == BigUint::ZERO {
        q
    } else if !round {
        return None;
    } else {
        // Nearest, ties toward +infinity: a tie rounds the magnitude up only when positive.
        let twice = &r * 2u8;
        if twice > den || (twice == den && !neg) {
            q + 1u8
        } else {
            q
        }
    };
    let v = if neg {
        -BigInt::from(mag)
    } else {
        BigInt::from(mag)
    };
    i64::try_from(v).ok()
}

fn run(u: &mut Unstructured<'_>) -> Result<()> {
    let f = u.int_in_range(0..=24)?;
    let round = u.arbitrary::<bool>()?;
    let inexact = if round {
        Inexact::Round
    } else {
        Inexact::Refuse
    };
    match u.int_in_range(0u8..=3)? {
        0 => {
            let s = decimal(u)?;
            let got = parse_fixed(&s, f, inexact);
            assert_eq!(
                got.as_ref().ok().copied(),
                parse_ref(&s, f, round),
                "{s:?} F={f} {inexact:?}: {got:?}"
            );
        }
        1 => {
            // A query line: fields separated by ASCII or Unicode white space.
            let mut line = String::new();
            for _ in 0..u.int_in_range(0..=6)? {
                line.push_str(u.choose(&[" ", "  ", "\t", "\u{a0}", "\u{2003}", " \r"])?);
                line.push_str(&decimal(u)?);
            }
            if u.arbitrary()? {
                line.push_str(u.choose(&[" ", "\n", "\r\n", "\t"])?);
            }
            let got = sat::parse_box(&line, f, inexact);
            let fields: Vec<&str> = line
                .split(char::is_whitespace)
                .filter(|t| !t.is_empty())
                .collect();
            let want = if fields.len() == 4 {
                fields
                    .iter()
                    .map(|t| parse_ref(t, f, round))
                    .collect::<Option<Vec<i64>>>()
            } else {
                None
            };
            assert_eq!(
                got.as_ref().ok().map(|v| v.to_vec()),
                want,
                "{line:?} F={f}: {got:?}"
            );
        }
        2 => {
            // Exact decimal output, and parsing it back.
            let k = u.int_in_range(0..=124)?;
            let v: u128 = u.arbitrary()?;
            let s = fixed_decimal(v, k);
            let (int, frac) = s.split_once('.').unwrap_or((&s, ""));
            assert!(
                !int.is_empty() && int.bytes().all(|b| b.is_ascii_digit()),
                "{s}"
            );
            assert!(
                frac.bytes().all(|b| b.is_ascii_digit()) && !frac.ends_with('0'),
                "{s}"
            );
            assert!(!(s.contains('.') && frac.is_empty()), "{s}");
            // N / 10^d == v / 2^k  <=>  N 2^k == v 10^d.
            let n: BigUint = format!("{int}{frac}").parse().expect("digits");
            assert_eq!(
                n << k,
                BigUint::from(v) * BigUint::from(10u8).pow(frac.len() as u32),
                "fixed_decimal({v}, {k}) = {s}"
            );
            if k <= 24 && v <= i64::MAX as u128 {
                assert_eq!(parse_fixed(&s, k, Inexact::Refuse), Ok(v as i64), "{s}");
                let neg = format!("-{s}");
                assert_eq!(
                    parse_fixed(&neg, k, Inexact::Refuse),
                    Ok(-(v as i64)),
                    "{neg}"
                );
            }
        }
        _ => {
            // --max-memory / --max-work amounts.
            let s: String = if u.arbitrary()? {
                u.arbitrary()?
            } else {
                format!(
                    "{}{}{}{}",
                    u.choose(&["", " ", "\t"])?,
                    decimal(u)?.replace(['.', '-', '+'], ""),
                    u.choose(&[
                        "", "k", "K", "kb", "KiB", "m", "MB", "mib", "g", "G", "GiB", "t", "TB",
                        "tib", "b", "B", "x", "kk", "iB"
                    ])?,
                    u.choose(&["", " ", "\n"])?
                )
            };
            let got = texsat_tools::budget::parse_amount(&s);
            let t = s.trim();
            let end = t.bytes().take_while(u8::is_ascii_digit).count();
            let (digits, suffix) = t.split_at(end);
            let shift = match suffix.to_ascii_lowercase().as_str() {
                "" | "b" => Some(0u32),
                "k" | "kb" | "kib" => Some(10),
                "m" | "mb" | "mib" => Some(20),
                "g" | "gb" | "gib" => Some(30),
                "t" | "tb" | "tib" => Some(40),
                _ => None,
            };
            let want = match (digits.is_empty(), shift) {
                (false, Some(sh)) => {
                    let v = digits.parse::<BigUint>().expect("digits") << sh;
                    u64::try_from(v).ok().filter(|&v| v > 0)
                }
                _ => None,
            };
            assert_eq!(got.as_ref().ok().copied(), want, "{s:?}: {got:?}");
            let v: u128 = u.arbitrary()?;
            let _ = (
                texsat_tools::budget::show_bytes(v),
                texsat_tools::budget::show_work(v),
                texsat_tools::budget::suggest(v),
            );
        }
    }
    Ok(())
}
