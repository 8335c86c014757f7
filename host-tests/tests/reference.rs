//! Tests of the references themselves (hand-computed values, the closed-form exact integral
//! against direct summation, the f64 reference against the exact one, the wide-integer helpers),
//! and texsat against the *f64* reference through `Rect::from_f64`.

use fixed::types::I24F8;
use texsat::{NoCount, Rect};
use texsat_host_tests::{
    axis_weights, build_sat, invalid_texels, is_rounded_mean, mean_error, sum_fixed, RefForm,
    RefMode, RefTexture, Rng, RngExt, TestRng, U256,
};

/// The 4 x 3 texture `1..=12` of the crate docs.
fn doc_texture() -> RefTexture {
    RefTexture::new(4, 3, 1, (1..=12).collect())
}

#[test]
fn index_maps_by_hand() {
    let n = 3;
    let expect = |mode: RefMode, table: &[(i64, Option<usize>)]| {
        for &(i, want) in table {
            assert_eq!(mode.index(i, n), want, "{mode:?} index {i}");
        }
    };
    expect(
        RefMode::Border,
        &[
            (-1, None),
            (0, Some(0)),
            (2, Some(2)),
            (3, None),
            (-100, None),
        ],
    );
    expect(
        RefMode::Clamp,
        &[
            (-5, Some(0)),
            (0, Some(0)),
            (1, Some(1)),
            (2, Some(2)),
            (9, Some(2)),
        ],
    );
    expect(
        RefMode::Repeat,
        &[
            (-4, Some(2)),
            (-3, Some(0)),
            (-1, Some(2)),
            (3, Some(0)),
            (7, Some(1)),
        ],
    );
    // Period 6: 0 1 2 | 2 1 0 | 0 1 2 ...
    expect(
        RefMode::Mirror,
        &[
            (0, Some(0)),
            (2, Some(2)),
            (3, Some(2)),
            (4, Some(1)),
            (5, Some(0)),
            (6, Some(0)),
            (-1, Some(0)),
            (-2, Some(1)),
            (-3, Some(2)),
            (-4, Some(2)),
            (-6, Some(0)),
            (-7, Some(0)),
        ],
    );
}

#[test]
fn hand_computed_integrals() {
    let t = doc_texture();
    // [0.5, 1.5) x [0, 1): half of texel 1 and half of texel 2 -> 1.5.
    assert_eq!(t.box_integral(RefMode::Border, 0.5, 0.0, 1.5, 1.0, 0), 1.5);
    assert_eq!(
        t.exact_integral(RefMode::Border, [128, 0, 384, 256], 8, 0),
        3 * 128 * 256
    );
    // 2 x 2 box at (1, 1): 6 + 7 + 10 + 11.
    assert_eq!(t.int_sums(RefMode::Border, [1, 1, 3, 3]), vec![34]);
    // Whole texture 78; under Repeat three periods in x and two in y -> 6 * 78.
    assert_eq!(t.int_sums(RefMode::Repeat, [-4, -3, 8, 3]), vec![6 * 78]);
    assert_eq!(t.int_sums(RefMode::Mirror, [-8, 0, 8, 6]), vec![8 * 78]);
    // Clamp: the column left of the texture repeats column 0 (1 + 5 + 9 = 15).
    assert_eq!(t.int_sums(RefMode::Clamp, [-3, 0, 0, 3]), vec![45]);
    // Clamp: the corner region beyond (w, h) is the corner texel 12.
    assert_eq!(t.int_sums(RefMode::Clamp, [4, 3, 6, 7]), vec![12 * 8]);
    // Border: nothing outside.
    assert_eq!(t.int_sums(RefMode::Border, [-5, -5, 0, 9]), vec![0]);
    // Mirror: x in [4, 5) shows column 3 (4 + 8 + 12 = 24), [-1, 0) shows column 0.
    assert_eq!(t.int_sums(RefMode::Mirror, [4, 0, 5, 3]), vec![24]);
    assert_eq!(t.int_sums(RefMode::Mirror, [-1, 0, 0, 3]), vec![15]);
    // A quarter texel at the corner of texel (3, 2) = 12 / 4, F = 1.
    assert_eq!(t.exact_integral(RefMode::Border, [7, 5, 8, 6], 1, 0), 12);
}

#[test]
fn axis_weights_conserve_length() {
    let mut rng = texsat_host_tests::rng(1);
    for _ in 0..2000 {
        let n = rng.random_range(1..=6) as usize;
        let f = rng.random_range(0..=6) as u32;
        let end = (n as i64) << f;
        let lo = rng.random_range(-5 * end..=6 * end);
        let hi = lo + rng.random_range(0..=8 * end);
        for mode in RefMode::ALL {
            let w = axis_weights(mode, lo, hi, n, f);
            let total: u128 = w.iter().sum();
            let want = match mode {
                RefMode::Border => (hi.min(end) - lo.max(0)).max(0) as u128,
                _ => (hi - lo) as u128,
            };
            assert_eq!(total, want, "{mode:?} n={n} f={f} [{lo}, {hi})");
        }
    }
    // Mirror over exactly one period gives every texel two cells; Repeat one.
    assert_eq!(axis_weights(RefMode::Mirror, -6, 0, 3, 0), vec![2, 2, 2]);
    assert_eq!(axis_weights(RefMode::Repeat, 3, 6, 3, 0), vec![1, 1, 1]);
    // Mirror [3, 4): the cell right of the edge shows texel 2.
    assert_eq!(axis_weights(RefMode::Mirror, 3, 4, 3, 0), vec![0, 0, 1]);
}

#[test]
fn closed_form_matches_direct_summation() {
    let mut rng = texsat_host_tests::rng(2);
    for case in 0..400 {
        let (w, h) = (
            rng.random_range(1..=5) as usize,
            rng.random_range(1..=5) as usize,
        );
        let ch = if case % 3 == 0 { 3 } else { 1 };
        let t = RefTexture::random(w, h, ch, 255, case);
        let f = [0u32, 1, 2, 4][case as usize % 4];
        let (ex, ey) = ((w as i64) << f, (h as i64) << f);
        for _ in 0..8 {
            let x0 = rng.random_range(-6 * ex..=6 * ex);
            let y0 = rng.random_range(-6 * ey..=6 * ey);
            let b = [
                x0,
                y0,
                x0 + rng.random_range(0..=5 * ex),
                y0 + rng.random_range(0..=5 * ey),
            ];
            for mode in RefMode::ALL {
                let closed = t.exact_integrals(mode, b, f);
                for (c, &v) in closed.iter().enumerate() {
                    assert_eq!(
                        v,
                        t.exact_integral_direct(mode, b, f, c),
                        "{mode:?} {b:?} f={f} c={c} {t:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn f64_reference_matches_exact() {
    let mut rng = texsat_host_tests::rng(3);
    for case in 0..200 {
        let (w, h) = (
            rng.random_range(1..=6) as usize,
            rng.random_range(1..=6) as usize,
        );
        let t = RefTexture::random(w, h, 1, 255, 100 + case);
        let f = 6;
        let scale = (1u64 << f) as f64;
        let (ex, ey) = ((w as i64) << f, (h as i64) << f);
        for _ in 0..6 {
            let x0 = rng.random_range(-3 * ex..=3 * ex);
            let y0 = rng.random_range(-3 * ey..=3 * ey);
            let b = [
                x0,
                y0,
                x0 + rng.random_range(0..=3 * ex),
                y0 + rng.random_range(0..=3 * ey),
            ];
            for mode in RefMode::ALL {
                let exact = t.exact_integral(mode, b, f, 0) as f64 / (scale * scale);
                let [x0, y0, x1, y1] = b.map(|v| v as f64 / scale);
                let float = t.box_integral(mode, x0, y0, x1, y1, 0);
                // Dyadic overlaps and small sums: the f64 sum is exact here.
                assert_eq!(float, exact, "{mode:?} {b:?}");
            }
        }
    }
}

#[test]
fn naive_table_by_hand() {
    let t = doc_texture();
    assert_eq!(
        t.naive_table(),
        vec![1, 3, 6, 10, 6, 14, 24, 36, 15, 33, 54, 78]
    );
    let three = RefTexture::new(2, 1, 3, vec![1, 2, 3, 10, 20, 30]);
    assert_eq!(three.naive_table(), vec![1, 2, 3, 11, 22, 33]);
    assert!(invalid_texels(&t.naive_table(), 4, 3, 1, 4).is_empty());
    // 12 does not fit 3 bits: texel (3, 2) is the only invalid one.
    assert_eq!(invalid_texels(&t.naive_table(), 4, 3, 1, 3), {
        let mut v = Vec::new();
        for (i, x) in (1..=12u32).enumerate() {
            if x > 7 {
                v.push((i % 4, i / 4, 0));
            }
        }
        v
    });
}

#[test]
fn wide_integers() {
    let max = u128::MAX;
    assert_eq!(U256::mul(max, max), U256 { hi: max - 1, lo: 1 });
    assert_eq!(U256::mul(1 << 64, 1 << 64), U256 { hi: 1, lo: 0 });
    assert_eq!(
        U256::shl(3, 127),
        U256 {
            hi: 1,
            lo: 1 << 127
        }
    );
    let mut rng = texsat_host_tests::rng(4);
    for _ in 0..1000 {
        let a = rng.next_u64() as u128;
        let b = rng.next_u64() as u128;
        assert_eq!(U256::mul(a, b), U256 { hi: 0, lo: a * b });
        let (a2, b2) = (a << 40 | 7, b << 50 | 3);
        let p = U256::mul(a2, b2);
        // Check against a split multiplication by 2^64 limbs done differently.
        let q = U256::mul(b2, a2);
        assert_eq!(p, q);
    }
    assert_eq!(
        U256::abs_diff(U256 { hi: 1, lo: 0 }, U256 { hi: 0, lo: 1 }),
        U256 { hi: 0, lo: max }
    );
}

#[test]
fn rounded_mean_inequality_by_brute_force() {
    for sum in 0u128..60 {
        for area in 1u128..20 {
            for g in 0..4 {
                let n = sum << g;
                // Round half up by the textbook formula floor((2n + area) / (2 area)).
                let m = (2 * n + area) / (2 * area);
                assert!(is_rounded_mean(sum, area, g, m), "{sum} {area} {g}");
                assert!(!is_rounded_mean(sum, area, g, m + 1));
                if m > 0 {
                    assert!(!is_rounded_mean(sum, area, g, m - 1));
                }
                assert!(mean_error(sum, area, g, m) <= 0.5 / (1u64 << g) as f64);
            }
        }
    }
    // Ties round up: 1 / 2 at g = 0 is 1; 3 / 2 is 2.
    assert!(is_rounded_mean(1, 2, 0, 1));
    assert!(is_rounded_mean(3, 2, 0, 2));
    // Large operands do not overflow.
    assert!(is_rounded_mean(u128::MAX >> 1, u128::MAX >> 1, 60, 1 << 60));
}

/// texsat against the f64 reference: corners from floats (multiples of 1/256, so `from_f64` is
/// exact), the scaled sum divided by 2^16 equals the f64 integral, and the mean is within
/// 2^-(g+1) of the f64 mean.
#[test]
fn texsat_matches_f64_reference() {
    let mut rng = texsat_host_tests::rng(5);
    for case in 0..60u64 {
        let (w, h) = (
            rng.random_range(1..=9) as usize,
            rng.random_range(1..=9) as usize,
        );
        let t = RefTexture::random(w, h, 1, 255, 200 + case);
        let mut st = vec![0u32; w * h];
        let sat = build_sat::<u8, u32, 1>(&t, &mut st).unwrap();
        for _ in 0..10 {
            let q = |rng: &mut TestRng, n: usize| {
                rng.random_range(-3 * 256 * n as i64..=4 * 256 * n as i64) as f64 / 256.0
            };
            let (a, b) = (q(&mut rng, w), q(&mut rng, w));
            let (c, d) = (q(&mut rng, h), q(&mut rng, h));
            let (x0, x1, y0, y1) = (a.min(b), a.max(b), c.min(d), c.max(d));
            let r = Rect::<I24F8>::from_f64(x0, y0, x1, y1).unwrap();
            for mode in RefMode::ALL {
                let want = t.box_integral(mode, x0, y0, x1, y1, 0);
                for form in RefForm::ALL {
                    let s = sum_fixed(&sat, &r, form, mode, &mut NoCount).unwrap();
                    let got = s.sum() as f64 / 65536.0;
                    assert_eq!(got, want, "{mode:?} {form:?} [{x0},{x1})x[{y0},{y1})");
                    let area = (x1 - x0) * (y1 - y0);
                    if area > 0.0 {
                        let g = 10;
                        let m = s.mean_rounded(0, g, &mut NoCount).unwrap();
                        let err = (m as f64 / 1024.0 - want / area).abs();
                        assert!(err <= 0.5 / 1024.0 + 1e-9, "{mode:?} mean error {err}");
                    }
                }
            }
        }
    }
}
