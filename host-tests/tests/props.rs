//! Property tests against the exact reference.
//!
//! * box sums at `F` = 4, 8, 12, 16 (`I28F4`, `I24F8`, `I20F12`, `I16F16`) and integer corners,
//!   inside and far outside (many periods for Repeat and Mirror), every mode, both forms,
//!   `u16`/`u32`/`u64` entries, `u8`/`u16` texels, 1 and 3 channels: exact equality, or the
//!   documented refusal where the accumulator (`i32` for `u16` tables, so `F = 8` on a table
//!   whose total has 15 or 16 bits) or the `u64` result word of `u16`/`u32` tables is too
//!   narrow ([`expected_sums`]); `Paper == Stable` where both answer; `mean_rounded`, in the
//!   table's own result word, is the correctly rounded mean (checked by the defining inequality
//!   in integers);
//! * the shortcut: taken exactly when both sides reach `min_side`, then the exactly rounded mean
//!   of the box with rounded corners, within `error_bound + 2^-(g+1)` of the exact mean;
//! * the streaming builder's rows, `build_checked`, and `from_table` against `Sat::build` and the
//!   naive table.
//!
//! Case counts are kept small enough for `cargo test` in debug on a small CI machine.

use fixed::traits::Fixed;
use fixed::types::{I16F16, I20F12, I24F8, I28F4};
use proptest::prelude::*;
use texsat::width::bits_of;
use texsat::{Coord, Entry, Error, NoCount, Quantity, RowStreamBuilder, Sat, Shortcut, Texture};
use texsat_host_tests::strategies::{arb_form, arb_interval, arb_mode, arb_texture};
use texsat_host_tests::{
    acc_value_bits_for_entry, build_sat, build_sat_checked, expected_sums, invalid_texels,
    is_rounded_mean, mean_error, mean_shortcut, rect_from_raw, sum_fixed_native, sum_int_native,
    wide_bits_for_entry, RefForm, RefMode, RefTexel, RefTexture,
};

/// Cases per property (each case checks several boxes).
const CASES: u32 = 256;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        ..ProptestConfig::default()
    }
}

/// The raw range of the corner type `X`.
fn raw_range<X: Fixed + Coord>() -> (i64, i64) {
    (X::MIN.raw(), X::MAX.raw())
}

/// A texture and a few boxes (raw corners, mode, output fraction bits) for it.
#[allow(clippy::type_complexity)]
fn arb_case(
    max_w: usize,
    max_h: usize,
    channels: usize,
    max: u32,
    f: u32,
    far_periods: i64,
    raw: (i64, i64),
) -> impl Strategy<Value = (RefTexture, Vec<([i64; 4], RefMode, u32)>)> {
    arb_texture(max_w, max_h, channels, max).prop_flat_map(move |t| {
        let bx = (
            arb_interval(t.width, f, far_periods, raw.0, raw.1),
            arb_interval(t.height, f, far_periods, raw.0, raw.1),
            arb_mode(),
            0u32..=20,
        )
            .prop_map(|((x0, x1), (y0, y1), m, g)| ([x0, y0, x1, y1], m, g));
        (Just(t), prop::collection::vec(bx, 1..6))
    })
}

/// Both forms on every box: the result the documented rules give ([`expected_sums`]: exact
/// sums, or the typed refusal where the accumulator or the result word is too narrow),
/// `Paper == Stable` where both answer, sides, rounded means in the table's own result word.
fn check_fixed<X: Fixed + Coord, T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
    boxes: &[([i64; 4], RefMode, u32)],
) -> Result<(), TestCaseError> {
    let f = X::FRAC_BITS;
    let mut st = vec![E::ZERO; tex.width * tex.height * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    let (acc, wide) = (
        acc_value_bits_for_entry(E::BITS),
        wide_bits_for_entry(E::BITS),
    );
    for &(b, mode, g) in boxes {
        let r = rect_from_raw::<X>(b);
        let mut answered = Vec::new();
        for form in RefForm::ALL {
            // In the table's own result word: the means below run its own division (u64 for u16
            // and u32 tables); the sums are compared as u128 with the u128 reference.
            let got = sum_fixed_native(&sat, &r, form, mode, &mut NoCount);
            let want = expected_sums(tex, mode, b, f, Some(form), acc, wide);
            prop_assert_eq!(
                got.map(|s| s.to_u128().scaled_sums().to_vec()),
                want.clone(),
                "{:?} {:?} {:?} F={}",
                form,
                mode,
                b,
                f
            );
            if let (Ok(p), Ok(want)) = (got, want) {
                answered.push((p, want));
            }
        }
        if let [(p, _), (s, _)] = &answered[..] {
            prop_assert_eq!(p, s, "paper != stable, {:?} {:?}", mode, b);
        }
        for (p, want) in answered {
            prop_assert_eq!(p.frac_bits(), f);
            let sides = ((b[2] - b[0]) as u64, (b[3] - b[1]) as u64);
            prop_assert_eq!(p.sides_raw(), sides);
            let area = sides.0 as u128 * sides.1 as u128;
            if area == 0 {
                prop_assert_eq!(p.mean_rounded(0, g, &mut NoCount), Err(Error::ZeroArea));
                continue;
            }
            let all = p.means_rounded(g, &mut NoCount).unwrap();
            for (c, &sum) in want.iter().enumerate() {
                let m = p.mean_rounded(c, g, &mut NoCount).unwrap();
                let m: u128 = m.into();
                prop_assert!(
                    is_rounded_mean(sum, area, g, m),
                    "mean {} of {}/{} at g={} ({:?} {:?})",
                    m,
                    sum,
                    area,
                    g,
                    mode,
                    b
                );
                prop_assert_eq!(all[c].into(), m);
                check_mean_u32(&p, c, g, sum, area, m)?;
            }
            prop_assert_eq!(
                p.mean_rounded(C, g, &mut NoCount),
                Err(Error::NoSuchChannel)
            );
        }
    }
    Ok(())
}

/// `mean_rounded_u32` gives `mean_rounded`'s value `m` where the numerator `sum 2^g` fits 64
/// bits and the area and `m` fit 32 bits, and otherwise refuses with the quantity that does not
/// fit (the numerator first, then the area, then the mean).
fn check_mean_u32<W: texsat::wide::Wide, const C: usize>(
    p: &texsat::BoxSum<W, C>,
    c: usize,
    g: u32,
    sum: u128,
    area: u128,
    m: u128,
) -> Result<(), TestCaseError> {
    let got = p.mean_rounded_u32(c, g, &mut NoCount);
    let numerator_fits = sum == 0 || bits_of(sum) + g <= 64;
    let what = if !numerator_fits {
        Some(Quantity::MeanNumerator)
    } else if sum != 0 && area > u128::from(u32::MAX) {
        Some(Quantity::MeanArea)
    } else if m > u128::from(u32::MAX) {
        Some(Quantity::Mean)
    } else {
        None
    };
    match what {
        None => prop_assert_eq!(got, Ok(m as u32)),
        Some(q) => prop_assert!(
            matches!(got, Err(Error::TooWide { what, bits_needed, .. }) if what == q && bits_needed > if q == Quantity::MeanNumerator { 64 } else { 32 }),
            "{:?} for sum {} area {} g {}: {:?}",
            q,
            sum,
            area,
            g,
            got
        ),
    }
    Ok(())
}

macro_rules! fixed_props {
    ($($name:ident: $x:ty, $t:ty, $e:ty, $c:expr, max_dim = $d:expr, max = $m:expr, far = $far:expr;)*) => {
        proptest! {
            #![proptest_config(config(CASES))]
            $(
                #[test]
                fn $name(
                    (tex, boxes) in arb_case(
                        $d, $d, $c, $m, <$x as Fixed>::FRAC_NBITS, $far, raw_range::<$x>(),
                    )
                ) {
                    check_fixed::<$x, $t, $e, $c>(&tex, &boxes)?;
                }
            )*
        }
    };
}

fixed_props! {
    f4_u8_u32_c1: I28F4, u8, u32, 1, max_dim = 40, max = 255, far = 1000;
    f8_u8_u32_c1: I24F8, u8, u32, 1, max_dim = 40, max = 255, far = 1000;
    f12_u8_u32_c1: I20F12, u8, u32, 1, max_dim = 40, max = 255, far = 1000;
    f16_u8_u32_c1: I16F16, u8, u32, 1, max_dim = 40, max = 255, far = 1000;
    f4_u16_u64_c3: I28F4, u16, u64, 3, max_dim = 24, max = 65535, far = 1000;
    f8_u16_u64_c3: I24F8, u16, u64, 3, max_dim = 24, max = 65535, far = 1000;
    f12_u8_u64_c3: I20F12, u8, u64, 3, max_dim = 24, max = 255, far = 1000;
    f16_u16_u64_c1: I16F16, u16, u64, 1, max_dim = 40, max = 65535, far = 1000;
    f16_u16_u32_c1: I16F16, u16, u32, 1, max_dim = 40, max = 65535, far = 200;
    f8_u16_u32_c3: I24F8, u16, u32, 3, max_dim = 24, max = 65535, far = 100;
    f4_u8_u16_tiny: I28F4, u8, u16, 1, max_dim = 16, max = 255, far = 50;
    f8_u8_u16_tiny_c3: I24F8, u8, u16, 3, max_dim = 16, max = 255, far = 50;
}

/// Integer corners (`box_sum_int`), the whole `i32` range reachable: exact sums (or the typed
/// refusal where a sum does not fit the result word), rounded means in the table's own word.
fn check_int<T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
    boxes: &[([i64; 4], RefMode, u32)],
) -> Result<(), TestCaseError> {
    let mut st = vec![E::ZERO; tex.width * tex.height * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    for &(b, mode, g) in boxes {
        let r = b.map(|v| v as i32);
        let want = expected_sums(
            tex,
            mode,
            b,
            0,
            None,
            acc_value_bits_for_entry(E::BITS),
            wide_bits_for_entry(E::BITS),
        );
        let got = sum_int_native(&sat, r, mode, &mut NoCount);
        prop_assert_eq!(
            got.map(|s| s.to_u128().scaled_sums().to_vec()),
            want.clone(),
            "{:?} {:?}",
            mode,
            r
        );
        let (Ok(got), Ok(want)) = (got, want) else {
            continue;
        };
        prop_assert_eq!(got.frac_bits(), 0);
        let area = (b[2] - b[0]) as u128 * (b[3] - b[1]) as u128;
        if area > 0 {
            let m = got.mean_rounded(0, g, &mut NoCount).unwrap();
            prop_assert!(is_rounded_mean(want[0], area, g, m.into()));
            check_mean_u32(&got, 0, g, want[0], area, m.into())?;
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(CASES))]

    #[test]
    fn int_u8_u32_c1(
        (tex, boxes) in arb_case(40, 40, 1, 255, 0, 1_000_000, (i32::MIN as i64, i32::MAX as i64))
    ) {
        check_int::<u8, u32, 1>(&tex, &boxes)?;
    }

    #[test]
    fn int_u16_u64_c3(
        (tex, boxes) in arb_case(24, 24, 3, 65535, 0, 1_000_000, (i32::MIN as i64, i32::MAX as i64))
    ) {
        check_int::<u16, u64, 3>(&tex, &boxes)?;
    }

    #[test]
    fn int_u8_u16_tiny(
        (tex, boxes) in arb_case(16, 16, 1, 255, 0, 1000, (i32::MIN as i64, i32::MAX as i64))
    ) {
        check_int::<u8, u16, 1>(&tex, &boxes)?;
    }
}

/// A box for the shortcut: sides from a bit below `s` texels to far above, at `F = 8`.
fn arb_shortcut_case(
    channels: usize,
) -> impl Strategy<Value = (RefTexture, u64, [i64; 4], RefMode, RefForm, u32)> {
    (arb_texture(24, 24, channels, 255), 2u64..=12).prop_flat_map(|(t, s)| {
        let lo = ((s as i64) << 8) - 300;
        let side = prop_oneof![
            1 => (lo.max(0))..((s as i64) << 8),
            3 => ((s as i64) << 8)..((s as i64 + 40) << 8),
        ];
        let start = -(60i64 << 8)..(60i64 << 8);
        (
            Just(t),
            Just(s),
            (start.clone(), start, side.clone(), side)
                .prop_map(|(x, y, w, h)| [x, y, x + w, y + h]),
            arb_mode(),
            arb_form(),
            0u32..=16,
        )
    })
}

/// Round a raw coordinate to the nearest integer, ties up (toward +infinity).
fn round_ties_up(raw: i64, f: u32) -> i64 {
    (raw + (1 << (f - 1))).div_euclid(1 << f)
}

fn check_shortcut<const C: usize>(
    tex: &RefTexture,
    s: u64,
    b: [i64; 4],
    mode: RefMode,
    form: RefForm,
    g: u32,
) -> Result<(), TestCaseError> {
    let f = 8;
    let mut st = vec![0u32; tex.width * tex.height * C];
    let sat = build_sat::<u8, u32, C>(tex, &mut st).unwrap();
    let sc = Shortcut::with_min_side(s);
    prop_assert_eq!(sc.min_side(), s);
    let r = rect_from_raw::<I24F8>(b);
    let got = mean_shortcut(&sat, &r, form, mode, &sc, g, &mut NoCount).unwrap();
    let (wr, hr) = ((b[2] - b[0]) as u128, (b[3] - b[1]) as u128);
    let took = wr >= (s as u128) << f && hr >= (s as u128) << f;
    prop_assert_eq!(got.shortcut, took, "{:?} s={}", b, s);
    let exact = tex.exact_integrals(mode, b, f);
    let area = wr * hr;
    if took {
        // Exactly the rounded mean over the box with rounded corners ...
        let rb = b.map(|v| round_ties_up(v, f));
        let rsum = tex.exact_integrals(mode, rb, 0);
        let rarea = ((rb[2] - rb[0]) * (rb[3] - rb[1])) as u128;
        // ... within the proven bound of the exact mean.
        let bound = Shortcut::error_bound(8, wr as f64 / 256.0, hr as f64 / 256.0)
            + 0.5 / (1u64 << g) as f64;
        for c in 0..C {
            let m = got.means[c];
            prop_assert!(is_rounded_mean(rsum[c], rarea, g, m), "{:?} -> {:?}", b, rb);
            let err = mean_error(exact[c], area, g, m);
            prop_assert!(
                err <= bound * (1.0 + 1e-12),
                "error {} > bound {} for {:?}",
                err,
                bound,
                b
            );
        }
    } else {
        for (&sum, &m) in exact.iter().zip(got.means.iter()) {
            prop_assert!(is_rounded_mean(sum, area, g, m));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(2 * CASES))]

    #[test]
    fn shortcut_c1((tex, s, b, mode, form, g) in arb_shortcut_case(1)) {
        check_shortcut::<1>(&tex, s, b, mode, form, g)?;
    }

    #[test]
    fn shortcut_c3((tex, s, b, mode, form, g) in arb_shortcut_case(3)) {
        check_shortcut::<3>(&tex, s, b, mode, form, g)?;
    }
}

/// The streaming builder's rows are bit-identical to `Sat::build`'s (and to the naive table).
fn check_stream<T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
) -> Result<(), TestCaseError> {
    let (w, h) = (tex.width, tex.height);
    let mut st = vec![E::ZERO; w * h * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    let naive = tex.naive_table();
    let built: Vec<u128> = sat.entries().iter().map(|e| e.to_u128()).collect();
    prop_assert_eq!(&built, &naive);
    let texels = tex.texels_as::<T>();
    let mut row = vec![E::ZERO; w * C];
    let mut sb = RowStreamBuilder::<E, C>::new(w, h, T::BITS, &mut row).unwrap();
    for y in 0..h {
        let out = sb.push_row(&texels[y * w * C..(y + 1) * w * C]).unwrap();
        prop_assert!(
            out == &sat.entries()[y * w * C..(y + 1) * w * C],
            "row {}",
            y
        );
        prop_assert_eq!(sb.rows_done(), y + 1);
    }
    prop_assert!(matches!(
        sb.push_row(&texels[..w * C]),
        Err(Error::TooManyRows)
    ));
    let last = sb.finish().unwrap();
    prop_assert!(last == &sat.entries()[(h - 1) * w * C..]);
    let total: Vec<u128> = sat.total().iter().map(|e| e.to_u128()).collect();
    let want: Vec<u128> = (0..C).map(|c| tex.total(c)).collect();
    prop_assert_eq!(total, want);
    Ok(())
}

/// `build_checked` equals `build` where both accept; it accepts exactly the textures whose
/// totals fit `E`, with the naive table, and otherwise names the bits the data needs.
fn check_checked<T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
) -> Result<(), TestCaseError> {
    let n = tex.width * tex.height * C;
    let mut st = vec![E::ZERO; n];
    let plain = build_sat::<T, E, C>(tex, &mut st).map(|s| s.entries().to_vec());
    let mut st2 = vec![E::ZERO; n];
    let checked = build_sat_checked::<T, E, C>(tex, &mut st2);
    let need = (0..C).map(|c| bits_of(tex.total(c))).max().unwrap();
    let worst = texsat::width::entry_bits_worst_case(T::BITS, tex.width, tex.height);
    match &plain {
        Ok(_) => prop_assert!(worst <= E::BITS),
        Err(e) => prop_assert_eq!(
            *e,
            Error::TooWide {
                what: Quantity::Entry,
                bits_needed: worst,
                bits_available: E::BITS
            }
        ),
    }
    match checked {
        Ok(sat) => {
            prop_assert!(need <= E::BITS);
            let got: Vec<u128> = sat.entries().iter().map(|e| e.to_u128()).collect();
            prop_assert_eq!(got, tex.naive_table());
            if let Ok(p) = plain {
                prop_assert!(p == sat.entries());
            }
        }
        Err(e) => {
            prop_assert!(need > E::BITS);
            prop_assert_eq!(
                e,
                Error::TooWide {
                    what: Quantity::Entry,
                    bits_needed: need,
                    bits_available: E::BITS
                }
            );
        }
    }
    Ok(())
}

/// `from_table` accepts a built table (same entries and totals) and rejects corruptions: adding
/// `2^b` to entry `(x, y)` makes texel `(x, y)` too large, the first invalid texel in any scan
/// order; an arbitrary replacement is accepted exactly when the reference finds no invalid
/// implied texel, and a rejection names one of the invalid texels.
fn check_from_table<T: RefTexel, const C: usize>(
    tex: &RefTexture,
    pos: usize,
    replacement: u64,
) -> Result<(), TestCaseError> {
    let (w, h) = (tex.width, tex.height);
    let mut st = vec![0u64; w * h * C];
    let sat = build_sat::<T, u64, C>(tex, &mut st).unwrap();
    let table = sat.entries().to_vec();
    let again = Sat::<u64, C>::from_table(&table, w, h, T::BITS).unwrap();
    prop_assert!(again.entries() == sat.entries());
    prop_assert_eq!(again.total(), sat.total());
    prop_assert_eq!(again.texel_bits(), T::BITS);
    let pos = pos % table.len();
    let (x, y, c) = ((pos / C) % w, pos / C / w, pos % C);

    let mut bad = table.clone();
    bad[pos] += 1 << T::BITS;
    prop_assert_eq!(
        Sat::<u64, C>::from_table(&bad, w, h, T::BITS).unwrap_err(),
        Error::InvalidTable { x, y, channel: c }
    );

    let mut other = table.clone();
    other[pos] = replacement;
    let wide: Vec<u128> = other.iter().map(|&v| v as u128).collect();
    let invalid = invalid_texels(&wide, w, h, C, T::BITS);
    match Sat::<u64, C>::from_table(&other, w, h, T::BITS) {
        Ok(_) => prop_assert!(invalid.is_empty(), "accepted, but {:?} invalid", invalid),
        Err(Error::InvalidTable { x, y, channel }) => {
            prop_assert!(
                invalid.contains(&(x, y, channel)),
                "{:?} not in {:?}",
                (x, y),
                invalid
            )
        }
        Err(e) => return Err(TestCaseError::fail(format!("{e:?}"))),
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(CASES))]

    #[test]
    fn stream_u8_u32_c1(tex in arb_texture(40, 40, 1, 255)) {
        check_stream::<u8, u32, 1>(&tex)?;
    }

    #[test]
    fn stream_u16_u64_c3(tex in arb_texture(24, 24, 3, 65535)) {
        check_stream::<u16, u64, 3>(&tex)?;
    }

    #[test]
    fn stream_u8_u16_c3(tex in arb_texture(16, 16, 3, 255)) {
        check_stream::<u8, u16, 3>(&tex)?;
    }

    #[test]
    fn checked_u8_u32(tex in arb_texture(40, 40, 1, 255)) {
        check_checked::<u8, u32, 1>(&tex)?;
    }

    /// `u16` entries: the worst case refuses most of these sizes, the data often fits.
    #[test]
    fn checked_u8_u16_c1(tex in arb_texture(40, 40, 1, 255)) {
        check_checked::<u8, u16, 1>(&tex)?;
    }

    #[test]
    fn checked_u8_u16_c3(tex in arb_texture(30, 30, 3, 255)) {
        check_checked::<u8, u16, 3>(&tex)?;
    }

    #[test]
    fn checked_u16_u16_c1(tex in arb_texture(12, 12, 1, 65535)) {
        check_checked::<u16, u16, 1>(&tex)?;
    }

    #[test]
    fn from_table_u8_c1(tex in arb_texture(30, 30, 1, 255), pos in any::<usize>(), v in 0u64..70000) {
        check_from_table::<u8, 1>(&tex, pos, v)?;
    }

    #[test]
    fn from_table_u16_c3(tex in arb_texture(16, 16, 3, 65535), pos in any::<usize>(), v in any::<u64>()) {
        check_from_table::<u16, 3>(&tex, pos, v >> (v % 64))?;
    }
}

/// A texture with stride: the table equals the packed texture's.
#[test]
fn strided_texture_builds_the_same_table() {
    let tex = RefTexture::random(5, 4, 3, 255, 9);
    let packed = tex.texels_as::<u8>();
    let stride = 5 * 3 + 7;
    let mut padded = vec![0xAAu8; stride * 3 + 15];
    for y in 0..4 {
        padded[y * stride..y * stride + 15].copy_from_slice(&packed[y * 15..(y + 1) * 15]);
    }
    let t = Texture::<u8, 3>::with_stride(&padded, 5, 4, stride).unwrap();
    let mut st = vec![0u32; 60];
    let sat = Sat::build(&t, &mut st).unwrap();
    let got: Vec<u128> = sat.entries().iter().map(|&e| e as u128).collect();
    assert_eq!(got, tex.naive_table());
}
