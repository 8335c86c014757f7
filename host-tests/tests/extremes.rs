//! Extremes: the largest `u8` texture a `u32` table holds (4104 x 4104) and the first one it
//! does not (4105 x 4105), the data-dependent build at that size, accumulator limits at
//! `F = 16`, coordinates at the limits of their fixed-point types under every mode, float
//! conversion errors, inverted and zero-area boxes, boxes far outside under Border, and the
//! shortcut's error bound reached by its worst case.
//!
//! The big tests allocate ~85 MB each; a lock runs them one at a time to bound peak memory.

use std::sync::Mutex;

use fixed::traits::Fixed;
use fixed::types::{I16F16, I24F8, I32F32, I40F24, I48F16};
use texsat::width::bits_of;
use texsat::{
    Border, ClampToEdge, Coord, Error, MirroredRepeat, NoCount, Paper, Quantity, Rect, Repeat,
    RowStreamBuilder, Sat, Shortcut, Stable, Tally, Texture,
};
use texsat_host_tests::{
    build_sat, expected_sums, is_rounded_mean, mean_error, mean_shortcut, rect_from_raw, sum_fixed,
    sum_int, RefForm, RefMode, RefTexture, RngExt,
};

/// Serialises the tests that allocate tens of megabytes.
static BIG: Mutex<()> = Mutex::new(());

fn big_lock() -> std::sync::MutexGuard<'static, ()> {
    BIG.lock().unwrap_or_else(|e| e.into_inner())
}

#[test]
fn largest_u8_texture_in_u32_entries() {
    let _g = big_lock();
    const N: usize = 4104;
    let texels = vec![255u8; N * N];
    let t = Texture::<u8>::new(&texels, N, N).unwrap();
    let mut st = vec![0u32; N * N];
    let sat = Sat::build(&t, &mut st).unwrap();
    let total = 255 * (N as u128) * (N as u128);
    assert_eq!(sat.total()[0] as u128, total);
    assert_eq!(sat.total_bits(), 32);
    assert_eq!(sat.corner(N, N).unwrap()[0] as u128, total);
    assert_eq!(sat.corner(N, 1).unwrap()[0] as u128, 255 * N as u128);
    assert_eq!(sat.corner(N + 1, N), None);
    assert_eq!(sat.table_bytes(), N * N * 4);

    let n = N as i32;
    // Integer boxes at the far corner, and the whole texture.
    let int = |r: [i32; 4]| {
        sum_int(&sat, r, RefMode::Border, &mut NoCount)
            .unwrap()
            .sum()
    };
    assert_eq!(int([n - 1, n - 1, n, n]), 255);
    assert_eq!(int([n - 2, n - 3, n, n]), 255 * 6);
    assert_eq!(int([0, 0, n, n]), total);
    assert_eq!(int([1, 1, n, n]), 255 * (N as u128 - 1).pow(2));

    // Fractional boxes at the far corner, F = 8: 1/256 x 1/256 is 255 units of 2^-16.
    let e = (N as i64) << 8;
    let cases: [([i64; 4], u128); 4] = [
        ([e - 1, e - 1, e, e], 255),
        ([e - 384, e - 3, e - 64, e], 255 * 320 * 3),
        ([e - 1, 0, e, e], 255 * e as u128),
        ([0, 0, e, e], total << 16),
    ];
    for (b, want) in cases {
        let r = rect_from_raw::<I24F8>(b);
        for form in RefForm::ALL {
            let mut k = Tally::new();
            let s = sum_fixed(&sat, &r, form, RefMode::Border, &mut k).unwrap();
            assert_eq!(s.sum(), want, "{form:?} {b:?}");
            assert_eq!(s.mean_rounded(0, 4, &mut NoCount).unwrap(), 255 << 4);
        }
    }
    // The tiny corner box is interior: Crow's 16 reads.
    let mut k = Tally::new();
    let r = rect_from_raw::<I24F8>([e - 1, e - 1, e, e]);
    sat.box_sum(&r, Paper, Border, &mut k).unwrap();
    assert_eq!((k.reads, k.bits_read), (16, 16 * 32));

    // Other modes across the far edge: the extended texture is 255 everywhere except Border.
    let r = rect_from_raw::<I24F8>([e - 1, e - 1, e + 1, e + 1]);
    for mode in [RefMode::Clamp, RefMode::Repeat, RefMode::Mirror] {
        for form in RefForm::ALL {
            let s = sum_fixed(&sat, &r, form, mode, &mut NoCount).unwrap();
            assert_eq!(s.sum(), 255 * 4, "{mode:?} {form:?}");
        }
    }
    let s = sum_fixed(&sat, &r, RefForm::Paper, RefMode::Border, &mut NoCount).unwrap();
    assert_eq!(s.sum(), 255);
    assert_eq!(s.mean_rounded(0, 2, &mut NoCount).unwrap(), 255); // 255 / 4 in 1/4 units
}

#[test]
fn first_u8_texture_too_wide_for_u32_is_refused_before_writing() {
    let _g = big_lock();
    const N: usize = 4105;
    const SENTINEL: u32 = 0xDEAD_BEEF;
    let texels = vec![255u8; N * N];
    let t = Texture::<u8>::new(&texels, N, N).unwrap();
    let want = Error::TooWide {
        what: Quantity::Entry,
        bits_needed: 33,
        bits_available: 32,
    };
    let mut st = vec![SENTINEL; N * N];
    assert_eq!(Sat::build(&t, &mut st).unwrap_err(), want);
    assert!(st.iter().all(|&v| v == SENTINEL), "storage was written");
    // The width proof comes before the storage check, too.
    assert_eq!(Sat::build(&t, &mut [0u32; 4]).unwrap_err(), want);
    let mut row = vec![0u32; N];
    assert_eq!(
        RowStreamBuilder::<u32>::new(N, N, 8, &mut row).unwrap_err(),
        want
    );
    // u64 entries hold it.
    drop(st);
    let mut st64 = vec![0u64; N * N];
    let sat = Sat::build(&t, &mut st64).unwrap();
    assert_eq!(sat.total()[0], 255 * (N as u64) * (N as u64));
    assert_eq!(sat.total_bits(), 33);
}

#[test]
fn checked_build_at_4105_squared() {
    let _g = big_lock();
    const N: usize = 4105;
    // Mostly zeros: a few maximal texels, total far below 2^32.
    let mut texels = vec![0u8; N * N];
    for &(x, y) in &[(0, 0), (N - 1, N - 1), (17, 4000), (4000, 17)] {
        texels[y * N + x] = 255;
    }
    let t = Texture::<u8>::new(&texels, N, N).unwrap();
    let mut st = vec![0u32; N * N];
    assert!(matches!(
        Sat::build(&t, &mut st),
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 33,
            bits_available: 32
        })
    ));
    let sat = Sat::build_checked(&t, &mut st).unwrap();
    assert_eq!(sat.total(), [4 * 255]);
    let n = N as i32;
    let int = |r: [i32; 4]| {
        sum_int(&sat, r, RefMode::Border, &mut NoCount)
            .unwrap()
            .sum()
    };
    assert_eq!(int([n - 1, n - 1, n, n]), 255);
    assert_eq!(int([1, 1, n - 1, n - 1]), 2 * 255);
    assert_eq!(int([17, 4000, 18, 4001]), 255);
    let e = (N as i64) << 8;
    let r = rect_from_raw::<I24F8>([e - 128, e - 64, e, e]);
    let s = sat.box_sum(&r, Stable, Border, &mut NoCount).unwrap();
    assert_eq!(s.sum(), 255 * 128 * 64);
    drop(st);

    // The all-255 texture of the same size: refused with the bits its data needs.
    texels.fill(255);
    let t = Texture::<u8>::new(&texels, N, N).unwrap();
    let mut st = vec![0u32; N * N];
    assert_eq!(
        Sat::build_checked(&t, &mut st).unwrap_err(),
        Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 33,
            bits_available: 32
        }
    );
}

#[test]
fn checked_build_reports_exact_bits() {
    // 1000 x 1000 u16 texels of 65535: total 65535e6 needs 36 bits.
    let tex = RefTexture::constant(1000, 1000, 1, 65535);
    assert_eq!(bits_of(tex.total(0)), 36);
    let texels = tex.texels_as::<u16>();
    let t = Texture::<u16>::new(&texels, 1000, 1000).unwrap();
    let mut st = vec![0u32; 1000 * 1000];
    let want = Error::TooWide {
        what: Quantity::Entry,
        bits_needed: 36,
        bits_available: 32,
    };
    assert_eq!(Sat::build_checked(&t, &mut st).unwrap_err(), want);
    // Worst case and data agree for a constant-maximum texture.
    assert_eq!(Sat::build(&t, &mut st).unwrap_err(), want);
    // Three channels: the widest channel counts.
    let mut texels3 = vec![0u16; 300 * 300 * 3];
    for px in texels3.chunks_exact_mut(3) {
        px[1] = 65535; // channel 1: 65535 * 90000 needs 33 bits
        px[2] = 1;
    }
    let t3 = Texture::<u16, 3>::new(&texels3, 300, 300).unwrap();
    let mut st3 = vec![0u32; 300 * 300 * 3];
    assert_eq!(
        Sat::build_checked(&t3, &mut st3).unwrap_err(),
        Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 33,
            bits_available: 32
        }
    );
}

/// A table of `u16` texels of 65535, `w x h`, in entry type `E`.
fn max_u16_table<E: texsat::Entry>(w: usize, h: usize, st: &mut Vec<E>) -> Sat<'_, E> {
    let tex = RefTexture::constant(w, h, 1, 65535);
    *st = vec![E::ZERO; w * h];
    build_sat::<u16, E, 1>(&tex, st).unwrap()
}

#[test]
fn accumulator_limits_at_f16() {
    let r = Rect::new(
        I16F16::from_num(1.5),
        I16F16::from_num(2.25),
        I16F16::from_num(100.75),
        I16F16::from_num(128.5),
    );
    // Exact: 65535 * 99.25 * 126.25, scaled by 2^32.
    let want = 65535u128 * (99.25 * 4.0) as u128 * (126.25 * 4.0) as u128 * (1 << 28);

    // Total needs 32 bits: Paper needs 32 + 32 = 64 > 63, Stable 65 > 63 in u32 entries.
    let mut st = Vec::new();
    let sat = max_u16_table::<u32>(256, 129, &mut st);
    assert_eq!(sat.total_bits(), 32);
    let paper = sat.box_sum(&r, Paper, Border, &mut NoCount).unwrap_err();
    assert_eq!(
        paper,
        Error::TooWide {
            what: Quantity::LookupAccumulator,
            bits_needed: 64,
            bits_available: 63
        }
    );
    assert_eq!(
        sat.box_sum(&r, Stable, Border, &mut NoCount).unwrap_err(),
        Error::TooWide {
            what: Quantity::LookupAccumulator,
            bits_needed: 65,
            bits_available: 63
        }
    );
    // The same lookup at F = 8 fits (48 bits), and integer corners always do.
    let r8 = Rect::<I24F8>::from_f64(1.5, 2.25, 100.75, 128.5).unwrap();
    let s = sat.box_sum(&r8, Paper, Border, &mut NoCount).unwrap();
    assert_eq!(u128::from(s.sum()), want >> 16);
    let s = sat
        .box_sum_int(&Rect::new(0, 0, 256, 129), Border, &mut NoCount)
        .unwrap();
    assert_eq!(s.sum(), 65535 * 256 * 129);

    // u64 entries (i128 accumulator) accept the F = 16 lookup, exactly.
    let mut st64 = Vec::new();
    let sat64 = max_u16_table::<u64>(256, 129, &mut st64);
    for form in RefForm::ALL {
        let s = sum_fixed(&sat64, &r, form, RefMode::Border, &mut NoCount).unwrap();
        assert_eq!(s.sum(), want, "{form:?}");
    }

    // Total of 31 bits: Paper needs exactly 63 (accepted), Stable 64 (refused).
    let mut st31 = Vec::new();
    let sat31 = max_u16_table::<u32>(128, 129, &mut st31);
    assert_eq!(sat31.total_bits(), 31);
    let r31 = Rect::new(
        I16F16::from_num(1.5),
        I16F16::from_num(2.25),
        I16F16::from_num(100.75),
        I16F16::from_num(128.5),
    );
    let s = sat31.box_sum(&r31, Paper, Border, &mut NoCount).unwrap();
    assert_eq!(u128::from(s.sum()), want);
    // The whole table at F = 16: the largest value the accumulator ever holds.
    let whole = Rect::new(
        I16F16::ZERO,
        I16F16::ZERO,
        I16F16::from_num(128),
        I16F16::from_num(129),
    );
    let s = sat31.box_sum(&whole, Paper, Border, &mut NoCount).unwrap();
    assert_eq!(u128::from(s.sum()), (65535u128 * 128 * 129) << 32);
    assert_eq!(
        sat31
            .box_sum(&r31, Stable, Border, &mut NoCount)
            .unwrap_err(),
        Error::TooWide {
            what: Quantity::LookupAccumulator,
            bits_needed: 64,
            bits_available: 63
        }
    );
}

/// Random boxes on tables at the accumulator limit (`u32` entries, `i64` accumulator, `F = 16`):
/// a 31-bit total for Paper (63 bits exactly) and a 30-bit total for Stable (63 bits exactly).
/// Debug builds trap any intermediate overflow; the sums must be exact.
#[test]
fn accumulator_limit_random_boxes() {
    let mut rng = texsat_host_tests::rng(12);
    for (w, form, other) in [
        (128usize, RefForm::Paper, RefForm::Stable),
        (64, RefForm::Stable, RefForm::Paper),
    ] {
        let h = 129;
        let texels = (0..w * h)
            .map(|_| rng.random_range(65100..=65535) as u32)
            .collect();
        let tex = RefTexture::new(w, h, 1, texels);
        let mut st = vec![0u32; w * h];
        let sat = build_sat::<u16, u32, 1>(&tex, &mut st).unwrap();
        let tb = sat.total_bits();
        assert_eq!(tb, if form == RefForm::Paper { 31 } else { 30 });
        let (ew, eh) = ((w as i64) << 16, (h as i64) << 16);
        let mut boxes = vec![[0, 0, ew, eh], [0, 0, ew - 1, eh - 1], [1, 1, ew, eh]];
        for _ in 0..150 {
            let x0 = rng.random_range(0..=ew);
            let y0 = rng.random_range(0..=eh);
            boxes.push([x0, y0, rng.random_range(x0..=ew), rng.random_range(y0..=eh)]);
        }
        for b in boxes {
            let r = rect_from_raw::<I16F16>(b);
            let s = sum_fixed(&sat, &r, form, RefMode::Border, &mut NoCount).unwrap();
            assert_eq!(
                s.sum(),
                tex.exact_integral(RefMode::Border, b, 16, 0),
                "{form:?} {b:?}"
            );
            // The other form needs one bit more (Stable) or is well inside (Paper).
            let o = sum_fixed(&sat, &r, other, RefMode::Border, &mut NoCount);
            if other == RefForm::Stable && b[0] < b[2] && b[1] < b[3] {
                assert!(
                    matches!(
                        o,
                        Err(Error::TooWide {
                            bits_needed: 64,
                            ..
                        })
                    ),
                    "{o:?}"
                );
            } else if other == RefForm::Paper {
                assert_eq!(o.unwrap(), s);
            }
        }
    }
}

#[test]
fn frac_bits_above_24_are_refused() {
    let tex = RefTexture::random(3, 3, 1, 255, 1);
    let mut st = vec![0u64; 9];
    let sat = build_sat::<u8, u64, 1>(&tex, &mut st).unwrap();
    let r = Rect::<I32F32>::from_f64(0.5, 0.5, 1.5, 1.5).unwrap();
    let want = Error::FracBitsUnsupported {
        frac_bits: 32,
        max: 24,
    };
    assert_eq!(
        sat.box_sum(&r, Paper, Border, &mut NoCount).unwrap_err(),
        want
    );
    assert_eq!(
        sat.box_mean_shortcut(
            &r,
            Stable,
            Repeat,
            &Shortcut::with_min_side(2),
            4,
            &mut NoCount
        )
        .unwrap_err(),
        want
    );
    // F = 24 is accepted and exact.
    let r = Rect::<I40F24>::from_f64(0.5, 0.25, 1.5, 2.0).unwrap();
    let s = sat.box_sum(&r, Stable, Border, &mut NoCount).unwrap();
    let b = [1 << 23, 1 << 22, 3 << 23, 2 << 24];
    assert_eq!(s.sum(), tex.exact_integral(RefMode::Border, b, 24, 0));
}

/// Every combination of the limits of `X` as box corners, every mode and form: exactly what the
/// documented rules give ([`expected_sums`]: the exact integral, or `TooWide` when it does not
/// fit the `u128` result word, or `CoordinateOutOfRange` for the Repeat/Mirror widths near
/// `2^64` that the core cannot place), never a panic; the mean and the shortcut likewise.
/// (Before the split path, errors here could only be `TooWide`; see the report of the change
/// that made these expectations exact.)
fn limits<X: Fixed + Coord>(tex: &RefTexture, expect_all_ok: bool) {
    let mut st = vec![0u64; tex.width * tex.height];
    let sat = build_sat::<u8, u64, 1>(tex, &mut st).unwrap();
    let (lo, hi) = (X::MIN.raw(), X::MAX.raw());
    let f = X::FRAC_BITS;
    let one = 1i64 << f;
    let vals = [lo, lo + 1, -one, 0, 1, one + 3, hi - 1, hi];
    let mut checked = 0;
    for &x0 in &vals {
        for &x1 in vals.iter().filter(|&&v| v >= x0) {
            for (y0, y1) in [(lo, hi), (0, one), (hi - 1, hi), (lo, 0), (-one, one)] {
                let b = [x0, y0, x1, y1];
                let r = rect_from_raw::<X>(b);
                for mode in RefMode::ALL {
                    for form in RefForm::ALL {
                        // u64 entries: i128 accumulator, u128 result word.
                        let want = expected_sums(tex, mode, b, f, Some(form), 127, 128);
                        let got = sum_fixed(&sat, &r, form, mode, &mut NoCount);
                        assert_eq!(
                            got.map(|s| s.scaled_sums().to_vec()),
                            want,
                            "{mode:?} {form:?} {b:?}"
                        );
                        match (&got, &want) {
                            (Ok(s), Ok(w)) => {
                                checked += 1;
                                if let Ok(m) = s.mean_rounded(0, 8, &mut NoCount) {
                                    let area = (x1 as i128 - x0 as i128) as u128
                                        * (y1 as i128 - y0 as i128) as u128;
                                    assert!(is_rounded_mean(w[0], area, 8, m), "{b:?}");
                                }
                            }
                            (Err(e), _) => {
                                assert!(!expect_all_ok, "{mode:?} {form:?} {b:?}: {e:?}");
                            }
                            (Ok(_), Err(_)) => unreachable!("compared above"),
                        }
                    }
                    let sc = Shortcut::with_min_side(2);
                    if let Ok(m) =
                        mean_shortcut(&sat, &r, RefForm::Paper, mode, &sc, 0, &mut NoCount)
                    {
                        if m.shortcut {
                            let rb =
                                b.map(|v| (v as i128 + (1 << (f - 1))).div_euclid(1 << f) as i64);
                            let rs = tex.exact_integrals_checked(mode, rb, 0);
                            let area = (rb[2] as i128 - rb[0] as i128) as u128
                                * (rb[3] as i128 - rb[1] as i128) as u128;
                            if let Some(rs) = rs {
                                assert!(is_rounded_mean(rs[0], area, 0, m.means[0]), "{b:?}");
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(checked > 0);
}

#[test]
fn corner_type_limits_i24f8() {
    // I24F8 spans +-2^23 texels: everything fits.
    limits::<I24F8>(&RefTexture::random(3, 2, 1, 255, 2), true);
    limits::<I24F8>(&RefTexture::random(1, 1, 1, 255, 3), true);
    limits::<I16F16>(&RefTexture::random(2, 5, 1, 255, 4), true);
}

#[test]
fn corner_type_limits_i64_raw() {
    // Raw coordinates at +-2^63: the integral itself may not fit; typed errors allowed.
    limits::<I40F24>(&RefTexture::random(3, 2, 1, 255, 5), false);
    limits::<I48F16>(&RefTexture::random(2, 3, 1, 255, 6), false);
}

/// Integer corners over the whole `i32` range, every mode, on a `u32` table: the exact sums, or
/// (new with the `u64` result word of `u32` tables) `TooWide { LookupAccumulator, 65, 64 }`
/// where a sum over a box of up to `2^64` texels does not fit 64 bits. Which boxes those are
/// follows from the exact reference; before the change every box here was answered in `i128`.
#[test]
fn integer_corner_limits() {
    let tex = RefTexture::random(3, 2, 3, 255, 7);
    let mut st = vec![0u32; 18];
    let sat = build_sat::<u8, u32, 3>(&tex, &mut st).unwrap();
    let vals = [i32::MIN, i32::MIN + 1, -1, 0, 2, i32::MAX - 1, i32::MAX];
    let (mut answered, mut refused) = (0, 0);
    for &x0 in &vals {
        for &x1 in vals.iter().filter(|&&v| v >= x0) {
            for (y0, y1) in [
                (i32::MIN, i32::MAX),
                (0, 2),
                (-5, 1),
                (i32::MAX - 3, i32::MAX),
            ] {
                let r = [x0, y0, x1, y1];
                for mode in RefMode::ALL {
                    let got = sum_int(&sat, r, mode, &mut NoCount);
                    let exact = tex.int_sums(mode, r);
                    let want = if exact.iter().all(|&v| v <= u64::MAX as u128) {
                        answered += 1;
                        Ok(exact)
                    } else {
                        refused += 1;
                        Err(Error::TooWide {
                            what: Quantity::LookupAccumulator,
                            bits_needed: 65,
                            bits_available: 64,
                        })
                    };
                    assert_eq!(
                        got.map(|s| s.scaled_sums().to_vec()),
                        want,
                        "{mode:?} {r:?}"
                    );
                }
            }
        }
    }
    assert!(answered > 100 && refused > 10, "{answered} {refused}");
}

#[test]
fn float_conversion_errors() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(
            Rect::<I24F8>::from_f64(bad, 0.0, 1.0, 1.0).unwrap_err(),
            Error::NotFinite
        );
        assert_eq!(
            Rect::<I24F8>::from_f64(0.0, 0.0, 1.0, bad).unwrap_err(),
            Error::NotFinite
        );
        assert_eq!(
            Rect::<I16F16>::from_f32(0.0, bad as f32, 1.0, 1.0).unwrap_err(),
            Error::NotFinite
        );
    }
    assert_eq!(
        Rect::<I24F8>::from_f64(0.0, 0.0, 1e10, 1.0).unwrap_err(),
        Error::CoordinateOutOfRange
    );
    assert_eq!(
        Rect::<I16F16>::from_f32(-40000.0, 0.0, 1.0, 1.0).unwrap_err(),
        Error::CoordinateOutOfRange
    );
    // Rounds to nearest.
    let r = Rect::<I24F8>::from_f64(0.5 + 0.4 / 256.0, 0.0, 1.0 - 0.6 / 256.0, 1.0).unwrap();
    assert_eq!((r.x0.to_bits(), r.x1.to_bits()), (128, 255));
}

#[test]
fn inverted_and_zero_area_boxes() {
    let tex = RefTexture::random(4, 3, 1, 255, 8);
    let mut st = vec![0u32; 12];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    for mode in RefMode::ALL {
        for r in [
            [2, 1, 1, 2],
            [1, 2, 2, 1],
            [3, 3, -3, -3],
            [1, 2, 1, 1],
            [2, 1, 1, 1],
        ] {
            let mut k = Tally::new();
            assert_eq!(
                sum_int(&sat, r, mode, &mut k).unwrap_err(),
                Error::InvertedBox
            );
            assert_eq!(k, Tally::new());
            let rf = rect_from_raw::<I24F8>(r.map(|v| (v as i64) << 8));
            for form in RefForm::ALL {
                assert_eq!(
                    sum_fixed(&sat, &rf, form, mode, &mut NoCount).unwrap_err(),
                    Error::InvertedBox
                );
                let sc = Shortcut::with_min_side(2);
                assert_eq!(
                    mean_shortcut(&sat, &rf, form, mode, &sc, 0, &mut NoCount).unwrap_err(),
                    Error::InvertedBox
                );
            }
        }
        // Slightly inverted at F = 8: one raw unit.
        let rf = rect_from_raw::<I24F8>([257, 0, 256, 512]);
        assert_eq!(
            sum_fixed(&sat, &rf, RefForm::Stable, mode, &mut NoCount).unwrap_err(),
            Error::InvertedBox
        );
        // Zero area: sum 0, no reads, no mean.
        for r in [[1, 1, 1, 3], [0, 2, 4, 2], [-9, 7, -9, 7], [2, 2, 2, 2]] {
            let mut k = Tally::new();
            let s = sum_int(&sat, r, mode, &mut k).unwrap();
            assert_eq!((s.sum(), k.reads), (0, 0), "{mode:?} {r:?}");
            assert_eq!(s.mean_rounded(0, 8, &mut k).unwrap_err(), Error::ZeroArea);
            let rf = rect_from_raw::<I24F8>(r.map(|v| (v as i64) << 8 | 3));
            for form in RefForm::ALL {
                let mut k = Tally::new();
                let s = sum_fixed(&sat, &rf, form, mode, &mut k).unwrap();
                assert_eq!((s.sum(), k.reads), (0, 0));
                assert_eq!(s.means_rounded(3, &mut k).unwrap_err(), Error::ZeroArea);
            }
        }
    }
}

#[test]
fn border_far_outside_is_zero_with_no_reads() {
    let tex = RefTexture::constant(5, 4, 1, 255);
    let mut st = vec![0u32; 20];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    let boxes = [
        [-100, -100, -1, 50],
        [5, 0, 9, 4],
        [0, 4, 5, 1000],
        [-1_000_000, -1_000_000, 0, 0],
        [i32::MIN, i32::MIN, -5, i32::MAX],
        [5, 4, i32::MAX, i32::MAX],
    ];
    for r in boxes {
        let mut k = Tally::new();
        let s = sat
            .box_sum_int(&Rect::new(r[0], r[1], r[2], r[3]), Border, &mut k)
            .unwrap();
        assert_eq!((s.sum(), k.reads), (0, 0), "{r:?}");
        assert_eq!(s.mean_rounded(0, 8, &mut NoCount).unwrap(), 0);
        if r.iter().all(|v| v.unsigned_abs() < 1 << 22) {
            // Shrunk by 5/256 on every side: still outside, with fractional corners.
            let [x0, y0, x1, y1] = r.map(|v| (v as i64) << 8);
            let rf = rect_from_raw::<I24F8>([x0 + 5, y0 + 5, x1 - 5, y1 - 5]);
            for form in RefForm::ALL {
                let mut k = Tally::new();
                let s = sum_fixed(&sat, &rf, form, RefMode::Border, &mut k).unwrap();
                assert_eq!((s.sum(), k.reads), (0, 0), "{r:?}");
            }
        }
    }
    // Border keeps the unclipped area: the box [-5, 10) x [0, 4) has mean 255 * 5 / 15.
    let s = sat
        .box_sum_int(&Rect::new(-5, 0, 10, 4), Border, &mut NoCount)
        .unwrap();
    assert_eq!(s.sum(), 255 * 20);
    assert_eq!(s.sides_raw(), (15, 4));
    assert_eq!(s.mean_rounded(0, 0, &mut NoCount).unwrap(), 85);
    // ... while Clamp sees the edge texels.
    let s = sat
        .box_sum_int(&Rect::new(-5, 0, 10, 4), ClampToEdge, &mut NoCount)
        .unwrap();
    assert_eq!(s.sum(), 255 * 60);
}

/// The shortcut's worst case: every edge of the box rounds inward by (almost) 1/2, the texture is
/// the maximum `m` exactly under the dropped strips and 0 elsewhere. The rounded box sees only
/// zeros; the true box's mean is `m |B \ R| / |B|`, close to the bound `m (1/(W-1) + 1/(H-1))`.
#[test]
fn shortcut_bound_is_reached() {
    let (a, b) = (1usize, 10usize); // dropped columns/rows: a and b
    let n = 12;
    let mut texels = vec![0u32; n * n];
    for j in 0..n {
        for i in 0..n {
            if i == a || i == b || j == a || j == b {
                texels[j * n + i] = 255;
            }
        }
    }
    let tex = RefTexture::new(n, n, 1, texels);
    let mut st = vec![0u32; n * n];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    let f = 8;
    // Left/top edge at a + 1/2: ties round up (inward). Right/bottom at b + 1/2 - 2^-8: down.
    let lo = ((2 * a + 1) as i64) << (f - 1);
    let hi = (((2 * b + 1) as i64) << (f - 1)) - 1;
    let bx = [lo, lo, hi, hi];
    let r = rect_from_raw::<I24F8>(bx);
    let side = (hi - lo) as f64 / 256.0;
    let sc = Shortcut::with_min_side(8);
    assert!(side >= 8.0);
    let bound = Shortcut::error_bound(8, side, side);
    let exact = tex.exact_integral(RefMode::Border, bx, f, 0);
    let area = ((hi - lo) as u128).pow(2);
    let g = 12;
    for mode in RefMode::ALL {
        for form in RefForm::ALL {
            let mut k = Tally::new();
            let m = mean_shortcut(&sat, &r, form, mode, &sc, g, &mut k).unwrap();
            assert!(m.shortcut);
            assert_eq!(m.means[0], 0, "the rounded box sees only zeros");
            assert_eq!((k.reads, k.muls, k.divs, k.adds), (4, 1, 1, 3));
            let err = mean_error(exact, area, g, m.means[0]);
            assert!(err <= bound + 0.5 / 4096.0, "{err} > {bound}");
            assert!(err >= 0.4 * bound, "{err} < 0.4 x {bound}");
            // (W - 1)/W of the bound, up to the second-order term: about 0.84 here.
            assert!(err >= 0.8 * bound, "{err} vs {bound}");
        }
    }
    // Below min_side the exact 16-read mean is returned instead.
    let m = mean_shortcut(
        &sat,
        &r,
        RefForm::Stable,
        RefMode::Border,
        &Shortcut::with_min_side(10),
        g,
        &mut NoCount,
    )
    .unwrap();
    assert!(!m.shortcut);
    assert!(is_rounded_mean(exact, area, g, m.means[0]));
    // for_tolerance: the side from which the bound is within the tolerance.
    let s = Shortcut::for_tolerance(8, 1, 4); // 1/4 texel unit: ceil(2 * 255 * 4) + 1
    assert_eq!(s.min_side(), 2041);
    assert!(Shortcut::error_bound(8, 2041.0, 2041.0) <= 0.25);
    assert!(Shortcut::error_bound(8, 2040.0, 2040.0) > 0.25);
    assert_eq!(Shortcut::for_tolerance(8, 0, 1).min_side(), u64::MAX);
    assert_eq!(Shortcut::with_min_side(0).min_side(), 2);
}

#[test]
fn modes_share_code_paths_at_texture_scale() {
    // Sanity on the mode types themselves (used directly, not through the dispatch helpers).
    let tex = RefTexture::random(4, 3, 1, 255, 11);
    let mut st = vec![0u32; 12];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    let r = Rect::new(-7, -5, 13, 9);
    let sums = [
        sat.box_sum_int(&r, Border, &mut NoCount).unwrap().sum(),
        sat.box_sum_int(&r, ClampToEdge, &mut NoCount)
            .unwrap()
            .sum(),
        sat.box_sum_int(&r, Repeat, &mut NoCount).unwrap().sum(),
        sat.box_sum_int(&r, MirroredRepeat, &mut NoCount)
            .unwrap()
            .sum(),
    ];
    let want: Vec<u128> = RefMode::ALL
        .iter()
        .map(|&m| tex.int_sums(m, [-7, -5, 13, 9])[0])
        .collect();
    assert_eq!(sums.map(u128::from).to_vec(), want);
}
