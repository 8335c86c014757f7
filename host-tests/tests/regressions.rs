//! Regression tests for the narrow-arithmetic core (`BoxSum<W, C>`, `i32`/`i64` accumulators for
//! `u16`/`u32` tables, `u64` sums and means, boxes crossing the edge split into in-range pieces,
//! `FracBits` and `box_sum_raw`), each against a reference written here or in the library that
//! never looks at a summed-area table:
//!
//! * the mean of a `u32` table, computed in 64 bits (one `u64` division, or the two-word long
//!   division for huge areas), equals `round(sum * 2^g / area)` computed independently in
//!   `u128`, over proptest inputs including huge Border boxes (area above `2^64` raw units) and
//!   `g` up to 40;
//! * raw coordinates at the `i64` limits (`I40F24::MIN`/`MAX` and beyond, every `F` from 0 to
//!   24) on `u16`, `u32` and `u64` tables, every mode and form: exactly the documented result or
//!   typed error ([`expected_sums`]), never a panic; the means and the shortcut likewise;
//! * inverted and empty boxes on every layout, mode, form and `F`: `InvertedBox` and zero sums
//!   with no reads, `ZeroArea` for their means;
//! * the split path (which replaced the weighted path): boxes crossing the edge exact against
//!   the reference for every mode, form, table word and layout, also over many periods; sums
//!   that do not fit the `u64` result word refused with `TooWide` at exactly the right box; and
//!   a `Modular` table whose `k` is just the box's bound answering a crossing box under Repeat
//!   in the Stable form exactly (no `2F` extra bits), while Paper still needs them.

use fixed::types::I40F24;
use proptest::prelude::*;
use texsat::layouts::{modulus_bits_for, Modular, Tiled, TiledSpec};
use texsat::width::bits_of;
use texsat::{
    BoxLookup, BoxSum, EdgeKind, Entry, Error, FormKind, FracBits, NoCount, Quantity, Rect, Sat,
    Shortcut, Tally, Texture,
};
use texsat_host_tests::strategies::{arb_form, arb_interval, arb_mode, arb_texture};
use texsat_host_tests::{
    acc_value_bits_for_entry, build_sat, expected_sums, is_rounded_mean, rng, wide_bits_for_entry,
    RefForm, RefMode, RefTexel, RefTexture, RngExt,
};

fn raw_rect(b: [i64; 4]) -> Rect<i64> {
    Rect::new(b[0], b[1], b[2], b[3])
}

fn fb(f: u32) -> FracBits {
    FracBits::new(f).unwrap()
}

/// `round(sum * 2^g / (w * h))`, ties up, in `u128` (the test's own arithmetic): `None` for a
/// zero area. `sum < 2^64`, `g <= 40` and `w, h < 2^64` keep every step inside `u128`.
fn mean_u128(sum: u128, g: u32, w: u64, h: u64) -> Option<u128> {
    assert!(sum <= u64::MAX as u128 && g <= 40);
    let area = w as u128 * h as u128;
    if area == 0 {
        return None;
    }
    let n = sum << g;
    let (q, r) = (n / area, n % area);
    Some(if r >= area - r { q + 1 } else { q })
}

/// Checks a `u64` result word's means against [`mean_u128`]: the value where it fits 64 bits,
/// else `TooWide { MeanNumerator, .. }`; `ZeroArea` for a zero area.
fn check_u64_means<const C: usize>(
    s: &BoxSum<u64, C>,
    want: &[u128],
    g: u32,
) -> Result<(), TestCaseError> {
    let (w, h) = s.sides_raw();
    for (c, &sum) in want.iter().enumerate() {
        let got = s.mean_rounded(c, g, &mut NoCount);
        match mean_u128(sum, g, w, h) {
            None => prop_assert_eq!(got, Err(Error::ZeroArea)),
            Some(m) if m <= u64::MAX as u128 => {
                prop_assert_eq!(got, Ok(m as u64), "sum {} g {} sides {:?}", sum, g, (w, h));
                prop_assert!(is_rounded_mean(sum, w as u128 * h as u128, g, m));
            }
            Some(m) => prop_assert!(
                matches!(
                    got,
                    Err(Error::TooWide {
                        what: Quantity::MeanNumerator,
                        ..
                    })
                ),
                "mean {} does not fit u64, got {:?}",
                m,
                got
            ),
        }
    }
    let all = s.means_rounded(g, &mut NoCount);
    if let Ok(all) = all {
        for (c, m) in all.iter().enumerate() {
            prop_assert_eq!(Ok(*m), s.mean_rounded(c, g, &mut NoCount));
        }
    }
    Ok(())
}

/// One axis for the mean property: near the texture (up to 1000 periods out), huge (from below
/// `-2^40` to above `2^40` raw, so that two such axes make an area above `2^80`), anywhere in
/// `i64`, or long from near the texture.
fn arb_axis(n: usize, f: u32) -> impl Strategy<Value = (i64, i64)> {
    let end = (n as i64) << f;
    prop_oneof![
        2 => arb_interval(n, f, 1000, i64::MIN, i64::MAX),
        2 => (i64::MIN..=-(1i64 << 40), (1i64 << 40)..=i64::MAX),
        1 => (any::<i64>(), any::<i64>()).prop_map(|(a, b)| (a.min(b), a.max(b))),
        1 => (-end..=end, 0i64..(1i64 << 62)).prop_map(|(a, len)| (a, a.saturating_add(len))),
    ]
}

type MeanCase = (RefTexture, u32, Vec<([i64; 4], RefMode, RefForm, u32)>);

fn arb_mean_case() -> impl Strategy<Value = MeanCase> {
    (
        arb_texture(6, 6, 2, 255),
        prop::sample::select(vec![0u32, 1, 4, 8, 12, 16, 20, 24]),
    )
        .prop_flat_map(|(t, f)| {
            let bx = (
                arb_axis(t.width, f),
                arb_axis(t.height, f),
                prop_oneof![3 => Just(RefMode::Border), 1 => arb_mode()],
                arb_form(),
                prop_oneof![1 => Just(40u32), 3 => 0u32..=40],
            )
                .prop_map(|((x0, x1), (y0, y1), m, form, g)| ([x0, y0, x1, y1], m, form, g));
            (Just(t), Just(f), prop::collection::vec(bx, 1..8))
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// The `u64` mean of a `u32` table (6 x 6, 2 channels, `u8` texels: totals below `2^14`, so
    /// every `F` up to 24 fits the `i64` accumulator) against the `u128` computation, with the
    /// sums themselves against the documented result ([`expected_sums`]).
    #[test]
    fn u32_table_mean_in_u64_matches_u128((tex, f, boxes) in arb_mean_case()) {
        let mut st = vec![0u32; tex.width * tex.height * 2];
        let sat = build_sat::<u8, u32, 2>(&tex, &mut st).unwrap();
        for (b, mode, form, g) in boxes {
            let got = sat.box_sum_raw(&raw_rect(b), fb(f), form.kind(), mode.kind(), &mut NoCount);
            let want = expected_sums(&tex, mode, b, f, Some(form), 63, 64);
            prop_assert_eq!(
                got.map(|s| s.to_u128().scaled_sums().to_vec()),
                want.clone(),
                "{:?} {:?} {:?} F={}", mode, form, b, f
            );
            if let (Ok(s), Ok(want)) = (got, want) {
                let sides = (
                    (b[2] as i128 - b[0] as i128) as u64,
                    (b[3] as i128 - b[1] as i128) as u64,
                );
                prop_assert_eq!(s.sides_raw(), sides);
                check_u64_means(&s, &want, g)?;
            }
        }
    }
}

/// Deterministic companions of the property: huge Border boxes whose area is far above `2^64`
/// raw units and whose mean is non-zero and checked, at `g` up to 40.
#[test]
fn huge_border_box_means_in_u64() {
    let tex = RefTexture::random(5, 4, 1, 255, 31);
    let mut st = vec![0u32; 20];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    let total = tex.total(0);
    let mut checked = 0;
    for f in [0u32, 8, 16, 24] {
        for (lo, hi) in [
            (-(1i64 << 40), 1i64 << 40),
            (-(1i64 << 50), 1i64 << 33),
            (i64::MIN, i64::MAX),
            (i64::MIN / 3, i64::MAX / 5),
        ] {
            let b = [lo, lo / 2, hi, hi / 3];
            for form in [FormKind::Paper, FormKind::Stable] {
                let s = sat
                    .box_sum_raw(&raw_rect(b), fb(f), form, EdgeKind::Border, &mut NoCount)
                    .unwrap();
                // The box covers the whole texture: the sum is its total, scaled by 2^2F.
                assert_eq!(u128::from(s.sum()), total << (2 * f));
                let (w, h) = s.sides_raw();
                assert!(w as u128 * h as u128 > 1u128 << 64, "{b:?}");
                for g in [0u32, 1, 17, 33, 40] {
                    check_u64_means(&s, &[total << (2 * f)], g).unwrap();
                    checked += 1;
                }
            }
        }
    }
    // At least one of them has a non-zero mean: 2^40 x 2^40 raw at F = 24 and g = 40.
    let s = sat
        .box_sum_raw(
            &raw_rect([0, 0, 1 << 40, 1 << 40]),
            fb(24),
            FormKind::Stable,
            EdgeKind::Border,
            &mut NoCount,
        )
        .unwrap();
    // sum * 2^40 / 2^80 = total * 2^48 / 2^40 = total * 2^8.
    assert_eq!(s.mean_rounded(0, 40, &mut NoCount), Ok((total as u64) << 8));
    assert!(checked > 100);
}

/// Raw corners at the `i64` limits for a table of entry type `E`: every combination, every mode
/// and form, `F` from 0 to 24; the result equals the documented one exactly (a result or a
/// typed error); the means and the shortcut return a result or a typed error.
fn i64_limits<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture) -> usize {
    let mut st = vec![E::ZERO; tex.width * tex.height * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    let (acc, wide) = (
        acc_value_bits_for_entry(E::BITS),
        wide_bits_for_entry(E::BITS),
    );
    let mut answered = 0;
    for f in [0u32, 1, 7, 8, 15, 16, 23, 24] {
        let one = 1i64 << f;
        let n = (tex.width as i64) << f;
        let vals = [
            i64::MIN,
            i64::MIN + 1,
            I40F24::MIN.to_bits() / 2,
            -one,
            0,
            one + 3,
            n,
            i64::MAX / 2,
            i64::MAX - 1,
            i64::MAX,
        ];
        let ys = [
            (i64::MIN, i64::MAX),
            (0, one),
            (i64::MAX - 1, i64::MAX),
            (i64::MIN, 0),
            (-one, one),
            (i64::MIN, i64::MIN + 1),
        ];
        for &x0 in &vals {
            for &x1 in vals.iter().filter(|&&v| v >= x0) {
                for &(y0, y1) in &ys {
                    let b = [x0, y0, x1, y1];
                    for mode in RefMode::ALL {
                        for form in RefForm::ALL {
                            let got = sat.box_sum_raw(
                                &raw_rect(b),
                                fb(f),
                                form.kind(),
                                mode.kind(),
                                &mut NoCount,
                            );
                            let want = expected_sums(tex, mode, b, f, Some(form), acc, wide);
                            assert_eq!(
                                got.map(|s| s.to_u128().scaled_sums().to_vec()),
                                want,
                                "E=u{} {mode:?} {form:?} {b:?} F={f}",
                                E::BITS
                            );
                            if let (Ok(s), Ok(want)) = (got, want) {
                                answered += 1;
                                let (w, h) = s.sides_raw();
                                let area = w as u128 * h as u128;
                                for g in [0u32, 8, 40, 64, 127, 200] {
                                    match s.mean_rounded(0, g, &mut NoCount) {
                                        // The reference works in 256 bits: checkable when
                                        // sum 2^(g+1) fits them.
                                        Ok(m) if (128 - want[0].leading_zeros()) + g < 256 => {
                                            assert!(
                                                is_rounded_mean(want[0], area, g, m.into()),
                                                "{b:?} g={g}"
                                            )
                                        }
                                        Ok(_) => {}
                                        Err(Error::TooWide {
                                            what: Quantity::MeanNumerator,
                                            ..
                                        }) => {}
                                        Err(Error::ZeroArea) if area == 0 => {}
                                        Err(e) => panic!("{b:?} g={g}: {e:?}"),
                                    }
                                }
                            }
                            let sc = Shortcut::with_min_side(2);
                            match sat.box_mean_shortcut_raw(
                                &raw_rect(b),
                                fb(f),
                                form.kind(),
                                mode.kind(),
                                &sc,
                                8,
                                &mut NoCount,
                            ) {
                                Ok(_)
                                | Err(Error::TooWide { .. })
                                | Err(Error::CoordinateOutOfRange)
                                | Err(Error::ZeroArea) => {}
                                Err(e) => panic!("shortcut {mode:?} {form:?} {b:?} F={f}: {e:?}"),
                            }
                        }
                    }
                }
            }
        }
    }
    answered
}

#[test]
fn i64_limit_coordinates_flat_tables() {
    // u16 table: total 11 bits, so F <= 9 (Stable) or 10 (Paper) fit its i32 accumulator; the
    // higher F here are refused with the exact bit counts.
    let small = RefTexture::random(3, 2, 1, 255, 41);
    assert!(i64_limits::<u8, u16, 1>(&small) > 100);
    assert!(i64_limits::<u8, u32, 1>(&small) > 100);
    assert!(i64_limits::<u8, u64, 1>(&small) > 100);
    let three = RefTexture::random(2, 3, 3, 65535, 42);
    assert!(i64_limits::<u16, u32, 3>(&three) > 100);
    assert!(i64_limits::<u16, u64, 3>(&three) > 100);
}

/// The same limits on a tiled and a modular layout: a result (then exact) or a typed error,
/// never a panic.
#[test]
fn i64_limit_coordinates_tiled_and_modular() {
    let tex = RefTexture::random(9, 7, 1, 255, 43);
    let texels = tex.texels_as::<u8>();
    let texture = Texture::<u8>::new(&texels, 9, 7).unwrap();
    let spec = TiledSpec::tiles(4, 4).unwrap();
    let mut tw = vec![0u32; Tiled::<u32>::words_needed(spec, 9, 7, 8).unwrap()];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, 9).unwrap()];
    let tiled = Tiled::<u32>::build(&texture, spec, &mut tw, &mut scratch).unwrap();
    let mut mw = vec![0u32; Modular::<u32>::words_needed(9, 7, 20).unwrap()];
    let mut row = vec![0u32; 9];
    let modular = Modular::<u32>::build(&texture, 20, &mut mw, &mut row).unwrap();
    let mut answered = 0;
    for f in [0u32, 8, 15, 24] {
        let vals = [
            i64::MIN,
            i64::MIN + 1,
            -1,
            0,
            5 << f,
            i64::MAX - 1,
            i64::MAX,
        ];
        for &x0 in &vals {
            for &x1 in vals.iter().filter(|&&v| v >= x0) {
                for &y0 in &vals {
                    for &y1 in vals.iter().filter(|&&v| v >= y0) {
                        let b = [x0, y0, x1, y1];
                        for mode in EdgeKind::ALL {
                            for form in [FormKind::Paper, FormKind::Stable] {
                                let r = raw_rect(b);
                                let results = [
                                    tiled.box_sum_raw(&r, fb(f), form, mode, &mut NoCount),
                                    modular.box_sum_raw(&r, fb(f), form, mode, &mut NoCount),
                                ];
                                for got in results {
                                    match got {
                                        Ok(s) => {
                                            let m = ref_mode(mode);
                                            let want = tex.exact_integrals(m, b, f);
                                            assert_eq!(u128::from(s.sum()), want[0], "{b:?}");
                                            answered += 1;
                                        }
                                        Err(Error::TooWide { .. })
                                        | Err(Error::CoordinateOutOfRange) => {}
                                        Err(e) => panic!("{mode:?} {form:?} {b:?} F={f}: {e:?}"),
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(answered > 100);
}

/// Inverted boxes (also by one raw unit, also with the other axis empty, also at the `i64`
/// limits) are `InvertedBox` with no reads; empty boxes (zero width or height, anywhere) sum to
/// zero with no reads, keep their sides, and have no mean (`ZeroArea`), on every layout, mode,
/// form and `F`.
fn inverted_and_empty<L: BoxLookup<C>, const C: usize>(l: &L, name: &str) {
    let inverted: [[i64; 4]; 7] = [
        [2, 1, 1, 2],
        [1, 2, 2, 1],
        [3, 3, -3, -3],
        [1, 2, 1, 1],
        [i64::MAX, 0, i64::MIN, 1],
        [0, i64::MAX, 1, i64::MIN],
        [5, 5, 4, 5],
    ];
    let empty: [[i64; 4]; 6] = [
        [1, 1, 1, 3],
        [0, 2, 4, 2],
        [-9, 7, -9, 7],
        [i64::MIN, 0, i64::MIN, 9],
        [0, i64::MAX, i64::MAX, i64::MAX],
        [i64::MIN, i64::MIN, i64::MAX, i64::MIN],
    ];
    for f in [0u32, 4, 8, 24] {
        for mode in EdgeKind::ALL {
            for form in [FormKind::Paper, FormKind::Stable] {
                let sc = Shortcut::with_min_side(2);
                for b in inverted {
                    let r = raw_rect(b.map(|v| v.saturating_mul(1 << f)));
                    let mut k = Tally::new();
                    let got = l.box_sum_raw(&r, fb(f), form, mode, &mut k);
                    assert_eq!(got.err(), Some(Error::InvertedBox), "{name} {b:?}");
                    assert_eq!(k, Tally::new());
                    let got = l.box_mean_shortcut_raw(&r, fb(f), form, mode, &sc, 8, &mut k);
                    assert_eq!(got.err(), Some(Error::InvertedBox), "{name} {b:?}");
                    assert_eq!(k, Tally::new());
                }
                // One raw unit inverted at F > 0.
                if f > 0 {
                    let r = raw_rect([(1 << f) + 1, 0, 1 << f, 1 << f]);
                    let got = l.box_sum_raw(&r, fb(f), form, mode, &mut NoCount);
                    assert_eq!(got.err(), Some(Error::InvertedBox), "{name}");
                }
                for b in empty {
                    let r = raw_rect(b);
                    let mut k = Tally::new();
                    let s = l.box_sum_raw(&r, fb(f), form, mode, &mut k).unwrap();
                    for v in s.scaled_sums() {
                        let v: u128 = v.into();
                        assert_eq!(v, 0, "{name} {b:?}");
                    }
                    assert_eq!(k, Tally::new(), "{name} {b:?}: no reads");
                    let sides = (
                        (b[2] as i128 - b[0] as i128) as u64,
                        (b[3] as i128 - b[1] as i128) as u64,
                    );
                    assert_eq!(s.sides_raw(), sides);
                    assert_eq!(s.frac_bits(), f);
                    assert_eq!(s.mean_rounded(0, 8, &mut k), Err(Error::ZeroArea));
                    assert_eq!(s.means_rounded(8, &mut k).err(), Some(Error::ZeroArea));
                    assert_eq!(
                        l.box_mean_shortcut_raw(&r, fb(f), form, mode, &sc, 8, &mut NoCount)
                            .err(),
                        Some(Error::ZeroArea),
                        "{name} {b:?}"
                    );
                }
            }
        }
        // Integer corners too.
        if f == 0 {
            for mode in EdgeKind::ALL {
                for b in [[2, 1, 1, 2], [1, 2, 2, 1], [i32::MAX, 0, i32::MIN, 0]] {
                    let r = Rect::new(b[0], b[1], b[2], b[3]);
                    assert_eq!(
                        l.box_sum_int(&r, mode, &mut NoCount).err(),
                        Some(Error::InvertedBox)
                    );
                }
                let s = l
                    .box_sum_int(&Rect::new(i32::MIN, 3, i32::MAX, 3), mode, &mut NoCount)
                    .unwrap();
                let z: u128 = s.sum().into();
                assert_eq!(z, 0);
                assert_eq!(s.sides_raw(), (u32::MAX as u64, 0));
            }
        }
    }
}

#[test]
fn inverted_and_empty_boxes_every_layout() {
    let tex = RefTexture::random(9, 7, 1, 255, 44);
    let texels = tex.texels_as::<u8>();
    let texture = Texture::<u8>::new(&texels, 9, 7).unwrap();
    let mut s16 = vec![0u16; 63];
    inverted_and_empty(&Sat::build(&texture, &mut s16).unwrap(), "u16");
    let mut s32 = vec![0u32; 63];
    inverted_and_empty(&Sat::build(&texture, &mut s32).unwrap(), "u32");
    let mut s64 = vec![0u64; 63];
    inverted_and_empty(&Sat::build(&texture, &mut s64).unwrap(), "u64");
    let spec = TiledSpec::tiles(4, 4).unwrap();
    let mut tw = vec![0u32; Tiled::<u32>::words_needed(spec, 9, 7, 8).unwrap()];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, 9).unwrap()];
    inverted_and_empty(
        &Tiled::<u32>::build(&texture, spec, &mut tw, &mut scratch).unwrap(),
        "tiled",
    );
    let mut mw = vec![0u32; Modular::<u32>::words_needed(9, 7, 16).unwrap()];
    let mut row = vec![0u32; 9];
    inverted_and_empty(
        &Modular::<u32>::build(&texture, 16, &mut mw, &mut row).unwrap(),
        "modular",
    );
}

// ---------------------------------------------------------------------------------------------
// The split path
// ---------------------------------------------------------------------------------------------

/// Raw boxes crossing the texture's edges at `F = f` on a `w x h` texture: across each edge,
/// each corner, the whole texture, one and several periods, far outside, and many periods long.
fn crossing_boxes(w: usize, h: usize, f: u32, seed: u64) -> Vec<[i64; 4]> {
    let (ew, eh) = ((w as i64) << f, (h as i64) << f);
    let one = 1i64 << f;
    let mut v = vec![
        [-one / 2, one, ew / 2, eh - one / 3],            // left edge
        [ew / 2, one / 4, ew + 3 * one / 2, eh / 2],      // right edge
        [one, -eh / 2, ew - one, one + 1],                // top edge
        [one / 3, eh - one, ew / 2, eh + 5 * one / 4],    // bottom edge
        [ew - one / 2, eh - one / 3, ew + one, eh + one], // bottom-right corner
        [-one - 3, -one - 5, one / 2 + 1, one / 3 + 7],   // top-left corner
        [-ew - 1, -eh - 1, 2 * ew + 1, 2 * eh + 1],       // whole texture and more
        [3 * ew + 7, -5 * eh + 3, 4 * ew + one, -4 * eh + one], // one period, shifted
        [-40 * ew - 1, 7, 37 * ew + 5, eh - 2],           // many periods in x
        [-1000 * ew + 3, -999 * eh - 1, 1001 * ew, 998 * eh + 9], // many in both
    ];
    let mut r = rng(seed);
    for _ in 0..60 {
        let x0 = r.random_range(-3 * ew..=4 * ew);
        let y0 = r.random_range(-3 * eh..=4 * eh);
        v.push([
            x0,
            y0,
            x0 + r.random_range(1..=5 * ew),
            y0 + r.random_range(1..=5 * eh),
        ]);
    }
    // On one-texel axes some of the fixed boxes above come out inverted: not crossing boxes.
    v.retain(|b| b[0] <= b[2] && b[1] <= b[3]);
    v
}

/// Every crossing box, every mode and form, on a layout: equal to the exact reference; at most 9
/// in-range pieces of at most 16 corner reads each, a corner read costing up to
/// `fields_per_corner` reads (1 for flat tables, the non-zero digits for tiled layouts).
fn check_crossing<L: BoxLookup<C>, const C: usize>(
    l: &L,
    tex: &RefTexture,
    f: u32,
    fields_per_corner: u64,
    name: &str,
) -> usize {
    let mut n = 0;
    for b in crossing_boxes(tex.width, tex.height, f, 45 + f as u64) {
        for mode in RefMode::ALL {
            let want = tex.exact_integrals(mode, b, f);
            for form in RefForm::ALL {
                let mut k = Tally::new();
                let got = l
                    .box_sum_raw(&raw_rect(b), fb(f), form.kind(), mode.kind(), &mut k)
                    .unwrap_or_else(|e| panic!("{name} {mode:?} {form:?} {b:?} F={f}: {e:?}"));
                let got: Vec<u128> = got.scaled_sums().iter().map(|&v| v.into()).collect();
                assert_eq!(got, want, "{name} {mode:?} {form:?} {b:?} F={f}");
                assert!(
                    k.reads <= 9 * 16 * fields_per_corner,
                    "{name} {mode:?} {b:?}: {k:?}"
                );
                n += 1;
            }
        }
    }
    n
}

#[test]
fn crossing_boxes_exact_every_mode_form_word_and_layout() {
    for (w, h, seed) in [(5usize, 4usize, 46u64), (1, 7, 47), (6, 1, 48), (1, 1, 49)] {
        let tex = RefTexture::random(w, h, 1, 255, seed);
        let texels = tex.texels_as::<u8>();
        let texture = Texture::<u8>::new(&texels, w, h).unwrap();
        let mut s16 = vec![0u16; w * h];
        let mut s32 = vec![0u32; w * h];
        let mut s64 = vec![0u64; w * h];
        let t16 = Sat::build(&texture, &mut s16).unwrap();
        let t32 = Sat::build(&texture, &mut s32).unwrap();
        let t64 = Sat::build(&texture, &mut s64).unwrap();
        let spec = TiledSpec::tiles(2, 3).unwrap();
        let mut tw = vec![0u32; Tiled::<u32>::words_needed(spec, w, h, 8).unwrap()];
        let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
        let tiled = Tiled::<u32>::build(&texture, spec, &mut tw, &mut scratch).unwrap();
        let fields = tiled.max_fields_per_corner() as u64;
        let mut n = 0;
        // u16 tables compute in i32: F = 4 fits these small totals in both forms.
        n += check_crossing(&t16, &tex, 0, 1, "u16");
        n += check_crossing(&t16, &tex, 4, 1, "u16");
        for f in [0u32, 4, 8, 12] {
            n += check_crossing(&t32, &tex, f, 1, "u32");
            n += check_crossing(&tiled, &tex, f, fields, "tiled");
        }
        n += check_crossing(&t64, &tex, 8, 1, "u64");
        n += check_crossing(&t64, &tex, 24, 1, "u64");
        assert!(n > 1000);
    }
    // Three channels, u16 texels.
    let tex = RefTexture::random(4, 3, 3, 65535, 50);
    let texels = tex.texels_as::<u16>();
    let texture = Texture::<u16, 3>::new(&texels, 4, 3).unwrap();
    let mut s32 = vec![0u32; 36];
    let mut s64 = vec![0u64; 36];
    check_crossing(
        &Sat::build(&texture, &mut s32).unwrap(),
        &tex,
        8,
        1,
        "u32 c3",
    );
    check_crossing(
        &Sat::build(&texture, &mut s64).unwrap(),
        &tex,
        16,
        1,
        "u64 c3",
    );
}

/// A constant texture of value `v` makes the extended texture constant under Clamp, Repeat and
/// Mirror, so a box of `W x H` raw units sums to `v W H` (scaled by `2^2F`, raw units already
/// are): on a `u32` table (`u64` result word) the box is answered exactly up to the largest
/// `W` with `v W H <= 2^64 - 1` and refused with `TooWide { LookupAccumulator, 65, 64 }` from
/// `W + 1` on; a `u64` table (`u128` result word) answers both. The same boxes used to be
/// answered in `i128` for every table: the `u64` refusal is the intended change.
#[test]
fn many_periods_u64_overflow_refused_at_the_exact_box() {
    let v = 200u32;
    let tex = RefTexture::constant(3, 2, 1, v);
    let mut s32 = vec![0u32; 6];
    let mut s64 = vec![0u64; 6];
    let t32 = build_sat::<u8, u32, 1>(&tex, &mut s32).unwrap();
    let t64 = build_sat::<u8, u64, 1>(&tex, &mut s64).unwrap();
    let refused = Error::TooWide {
        what: Quantity::LookupAccumulator,
        bits_needed: 65,
        bits_available: 64,
    };
    let mut n = 0;
    for f in [0u32, 8] {
        for h in [1i64 << 20, (1i64 << 33) + 7, 3 << 40] {
            // Largest W with v W h <= u64::MAX.
            let w_max = (u64::MAX / (v as u64 * h as u64)) as i64;
            for x0 in [-5 * (3i64 << f) - 1, 7, -(w_max / 2)] {
                let y0 = -(h / 3) - 1;
                for mode in [RefMode::Clamp, RefMode::Repeat, RefMode::Mirror] {
                    for form in RefForm::ALL {
                        let fits = [x0, y0, x0 + w_max, y0 + h];
                        let over = [x0, y0, x0 + w_max + 1, y0 + h];
                        let sum = |b: [i64; 4]| v as u128 * (b[2] - b[0]) as u128 * h as u128;
                        let get = |t: &Sat<'_, u32, 1>, b: [i64; 4]| {
                            t.box_sum_raw(
                                &raw_rect(b),
                                fb(f),
                                form.kind(),
                                mode.kind(),
                                &mut NoCount,
                            )
                        };
                        let s = get(&t32, fits).unwrap();
                        assert_eq!(u128::from(s.sum()), sum(fits), "{mode:?} {fits:?}");
                        assert_eq!(get(&t32, over), Err(refused), "{mode:?} {over:?}");
                        for b in [fits, over] {
                            let s = t64
                                .box_sum_raw(
                                    &raw_rect(b),
                                    fb(f),
                                    form.kind(),
                                    mode.kind(),
                                    &mut NoCount,
                                )
                                .unwrap();
                            assert_eq!(s.sum(), sum(b), "u64 table {mode:?} {b:?}");
                        }
                        n += 1;
                    }
                }
            }
        }
    }
    assert_eq!(n, 2 * 3 * 3 * 3 * 2);
    // Under Border the same boxes clip to the texture: answered on both tables.
    let b = [-(1i64 << 62), -(1i64 << 62), 1i64 << 62, 1i64 << 62];
    let s = t32
        .box_sum_raw(
            &raw_rect(b),
            fb(8),
            FormKind::Stable,
            EdgeKind::Border,
            &mut NoCount,
        )
        .unwrap();
    assert_eq!(u128::from(s.sum()), (v as u128 * 6) << 16);
}

/// Modular layouts need no `2F` extra bits under Repeat (nor Clamp, Mirror) in the Stable form:
/// the split pieces each sum to at most the box, so a `Modular` table whose `k` is exactly the
/// bound of the box (`modulus_bits_for(8, cells)`) answers a box crossing the edge exactly; one
/// more column of cells is refused (the bound is tight), and Paper still needs `2F` more.
/// (Before the split path these boxes needed `2F` extra bits in Stable too.)
#[test]
fn modular_k_at_box_bound_answers_crossing_boxes_in_stable() {
    let tex = RefTexture::constant(40, 30, 1, 255);
    let rnd = RefTexture::random(40, 30, 1, 255, 51);
    let mut n = 0;
    for t in [&tex, &rnd] {
        let texels = t.texels_as::<u8>();
        let texture = Texture::<u8>::new(&texels, 40, 30).unwrap();
        for f in [4u32, 8] {
            let q = |v: f64| (v * (1u64 << f) as f64) as i64;
            // Cells: ceil(hi) - floor(lo) per axis.
            // Cells `ceil(hi) - floor(lo)` per axis, chosen so that `255 cx cy` is just below a
            // power of two (64 cells: 16320 < 2^14; 32 cells: 8160 < 2^13) and one more column
            // of cells crosses it.
            for (b, cx, cy) in [
                ([q(36.5), q(3.25), q(43.5), q(10.75)], 8u64, 8u64), // crosses x = 40
                ([q(-2.5), q(26.5), q(0.75), q(41.5)], 4, 16),       // crosses x = 0, y = 30
                ([q(36.0), q(28.5), q(44.0), q(31.5)], 8, 4),        // crosses both far edges
            ] {
                let k = modulus_bits_for(8, cx * cy);
                assert_eq!(k, bits_of(255 * (cx * cy) as u128));
                let mut mw = vec![0u32; Modular::<u32>::words_needed(40, 30, k).unwrap()];
                let mut row = vec![0u32; 40];
                let m = Modular::<u32>::build(&texture, k, &mut mw, &mut row).unwrap();
                for mode in [RefMode::Repeat, RefMode::Clamp, RefMode::Mirror] {
                    let want = t.exact_integral(mode, b, f, 0);
                    let s = m
                        .box_sum_raw(
                            &raw_rect(b),
                            fb(f),
                            FormKind::Stable,
                            mode.kind(),
                            &mut NoCount,
                        )
                        .unwrap_or_else(|e| panic!("{mode:?} {b:?} F={f} k={k}: {e:?}"));
                    assert_eq!(u128::from(s.sum()), want, "{mode:?} {b:?} F={f}");
                    // Paper: 2F more bits than k has.
                    assert_eq!(
                        m.box_sum_raw(
                            &raw_rect(b),
                            fb(f),
                            FormKind::Paper,
                            mode.kind(),
                            &mut NoCount
                        ),
                        Err(Error::TooWide {
                            what: Quantity::ModularBox,
                            bits_needed: k + 2 * f,
                            bits_available: k,
                        })
                    );
                    // One more column of cells: 255 (cx + 1) cy needs more than k bits
                    // (for these sizes), refused in Stable too.
                    let wider = [b[0], b[1], b[2] + (1 << f), b[3]];
                    let needed = bits_of(255 * ((cx + 1) * cy) as u128);
                    assert!(needed > k);
                    assert_eq!(
                        m.box_sum_raw(
                            &raw_rect(wider),
                            fb(f),
                            FormKind::Stable,
                            mode.kind(),
                            &mut NoCount
                        ),
                        Err(Error::TooWide {
                            what: Quantity::ModularBox,
                            bits_needed: needed,
                            bits_available: k,
                        })
                    );
                    n += 1;
                }
            }
        }
    }
    assert_eq!(n, 2 * 2 * 3 * 3);
}

/// `u16` tables compute fractional lookups in `i32`: on a table whose total uses 16 bits, `F = 7`
/// is the largest accepted in both forms and `F = 8` is refused with the exact bit counts
/// (Paper `16 + 16 = 32`, Stable 33, of 31); a `u32` table answers the same lookup exactly.
#[test]
fn u16_table_frac_bits_limit() {
    // 257 texels of 255: total 65535, 16 bits.
    let tex = RefTexture::constant(257, 1, 1, 255);
    let mut s16 = vec![0u16; 257];
    let mut s32 = vec![0u32; 257];
    let t16 = build_sat::<u8, u16, 1>(&tex, &mut s16).unwrap();
    let t32 = build_sat::<u8, u32, 1>(&tex, &mut s32).unwrap();
    assert_eq!(t16.total_bits(), 16);
    for f in [7u32, 8] {
        let b = [3 << (f - 1), 0, 250 << f, 1 << f];
        let want = tex.exact_integral(RefMode::Border, b, f, 0);
        for form in [FormKind::Paper, FormKind::Stable] {
            let got16 = t16.box_sum_raw(&raw_rect(b), fb(f), form, EdgeKind::Border, &mut NoCount);
            let got32 = t32.box_sum_raw(&raw_rect(b), fb(f), form, EdgeKind::Border, &mut NoCount);
            assert_eq!(u128::from(got32.unwrap().sum()), want);
            if f == 7 {
                assert_eq!(u128::from(got16.unwrap().sum()), want);
            } else {
                let extra = (form == FormKind::Stable) as u32;
                assert_eq!(
                    got16,
                    Err(Error::TooWide {
                        what: Quantity::LookupAccumulator,
                        bits_needed: 16 + 2 * f + extra,
                        bits_available: 31,
                    })
                );
            }
        }
    }
    // F above 24 is not a FracBits at all.
    assert_eq!(
        FracBits::new(25),
        Err(Error::FracBitsUnsupported {
            frac_bits: 25,
            max: 24
        })
    );
}

/// The run-time mode and form values name the same things as the reference's.
#[test]
fn run_time_kinds_round_trip() {
    for (m, name) in RefMode::ALL
        .into_iter()
        .zip(["border", "clamp", "repeat", "mirror"])
    {
        assert_eq!(m.kind().name(), name);
        assert_eq!(EdgeKind::from_name(name), Some(m.kind()));
    }
    for (f, name) in RefForm::ALL.into_iter().zip(["paper", "stable"]) {
        assert_eq!(f.kind().name(), name);
        assert_eq!(FormKind::from_name(name), Some(f.kind()));
    }
    // The extended texture's index, against the reference's.
    for n in 1..6usize {
        for i in -20i64..20 {
            for m in RefMode::ALL {
                assert_eq!(m.kind().texel_index(i, n), m.index(i, n), "{m:?} {i} {n}");
            }
        }
    }
}

/// The reference's mode for a run-time mode value.
fn ref_mode(k: EdgeKind) -> RefMode {
    let m = RefMode::ALL
        .into_iter()
        .find(|m| m.kind() == k)
        .expect("every kind has a reference mode");
    assert_eq!(m.kind(), k);
    m
}
