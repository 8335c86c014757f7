//! The numerical stability study (`texsat_host_tests::stability`), at the quick size: texsat's
//! integer tables are exact, float32 tables lose digits as the table grows, and centring helps.

use texsat_host_tests::scenes::SceneSize;
use texsat_host_tests::stability::{
    float32_error_vs_size, largest_u32_square, stability_rows, BuildOrder, FloatSat, StabilityRow,
};

fn row<'a>(rows: &'a [StabilityRow], case: &str, method: &str) -> &'a StabilityRow {
    rows.iter()
        .find(|r| r.case.starts_with(case) && r.method.starts_with(method))
        .unwrap_or_else(|| panic!("no row {case:?} / {method:?}"))
}

#[test]
fn largest_u32_square_is_4104() {
    assert_eq!(largest_u32_square(8), 4104);
    assert_eq!(texsat::width::entry_bits_worst_case(8, 4104, 4104), 32);
    assert_eq!(texsat::width::entry_bits_worst_case(8, 4105, 4105), 33);
}

#[test]
fn float_sat_matches_integer_sums_when_small() {
    // 3x2 texture: every value and partial sum is exact in f32; both build orders agree.
    let t = [1u8, 2, 3, 4, 5, 6];
    for order in [BuildOrder::RowsThenColumns, BuildOrder::ColumnsThenRows] {
        let s = FloatSat::<f32>::build(&t, 3, 2, 0.0, order);
        assert_eq!(s.at(3, 2), 21.0);
        assert_eq!(s.at(2, 1), 3.0);
        assert_eq!(s.at(0, 2), 0.0);
        assert_eq!(s.corner(1.5, 1.0), 2.0);
        assert_eq!(s.box_mean(1.0, 0.0, 3.0, 2.0), 4.0);
        // Repeat: the box [2, 4) x [0, 1) shows texels 3 and 1.
        assert_eq!(s.box_mean_repeat(2.0, 0.0, 4.0, 1.0), 2.0);
        // Centred on 3.5: the same means.
        let c = FloatSat::<f32>::build(&t, 3, 2, 3.5, order);
        assert_eq!(c.box_mean(1.0, 0.0, 3.0, 2.0), 4.0);
        assert_eq!(c.box_mean_repeat(2.0, 0.0, 4.0, 1.0), 2.0);
    }
}

#[test]
fn quick_study() {
    let rows = stability_rows(SceneSize::Quick);
    assert!(rows.len() > 30, "{} rows", rows.len());
    for r in &rows {
        assert!(
            r.max_abs_error.is_finite() && r.rms_error.is_finite() && r.max_rel_error.is_finite(),
            "{r:?}"
        );
        assert!(
            r.max_abs_error >= 0.0 && r.rms_error <= r.max_abs_error + 1e-12,
            "{r:?}"
        );
        assert!(
            !r.note.is_empty() && !r.case.is_empty() && r.size > 0,
            "{r:?}"
        );
    }

    // texsat's integer rows are exact everywhere, repeat included.
    let texsat: Vec<_> = rows
        .iter()
        .filter(|r| r.method.starts_with("texsat"))
        .collect();
    assert!(texsat.len() >= 20);
    for r in texsat {
        assert_eq!(r.max_abs_error, 0.0, "{r:?}");
        assert!(r.note.starts_with("exact"), "{r:?}");
    }

    // float32 without an offset: exact for integer boxes at 256 (all sums below 2^24),
    // measurable at 1024, larger at 4104.
    let f32 = "float32 SAT (GPU build";
    let small = |n: usize| {
        row(
            &rows,
            &format!("all-255 {n}x{n}: small boxes anywhere"),
            f32,
        )
        .max_abs_error
    };
    assert_eq!(small(256), 0.0);
    assert!(small(1024) > 0.1, "{}", small(1024));
    assert!(
        small(4104) > 2.0 * small(1024),
        "{} {}",
        small(1024),
        small(4104)
    );
    let quarter = |n: usize| row(&rows, &format!("all-255 {n}x{n}: 0.25x0.25"), f32).max_abs_error;
    assert!(quarter(256) > 0.0 && quarter(4104) > quarter(1024));
    let far = |n: usize| row(&rows, &format!("all-255 {n}x{n}: 1x1"), f32).max_abs_error;
    assert!(far(256) == 0.0 && far(1024) > 0.0 && far(4104) > 0.0);

    // f64 is exact for integer boxes at these sizes.
    assert_eq!(
        row(&rows, "all-255 4104x4104: 1x1", "f64").max_abs_error,
        0.0
    );

    // Centring on the mean helps on the large-mean noise.
    for case in [
        "noise 200..=255 1024x1024: small integer",
        "noise 200..=255 1024x1024: 1x1",
    ] {
        let plain = row(&rows, case, f32).max_abs_error;
        let centred = row(&rows, case, "float32 SAT centred on the texture mean").max_abs_error;
        assert!(
            plain > 0.0 && centred < plain / 4.0,
            "{case}: {plain} {centred}"
        );
    }

    // Far away under repeat, float32 loses all digits; centring helps there too.
    let far = row(&rows, "repeat 64x64: 1x1 boxes 10000", f32);
    assert!(far.max_rel_error > 0.5, "{far:?}");
    let near = row(&rows, "repeat 64x64: 1x1 boxes 1 ", f32);
    assert!(near.max_abs_error < far.max_abs_error, "{near:?}");
}

#[test]
fn quick_curves() {
    let curves = float32_error_vs_size(SceneSize::Quick);
    assert_eq!(curves.len(), 6);
    for c in &curves {
        let sides: Vec<usize> = c.points.iter().map(|p| p.0).collect();
        assert_eq!(sides, [16, 32, 64, 128, 256, 512], "{}", c.method);
        assert!(c.points.iter().all(|p| p.1.is_finite() && p.1 >= 0.0));
        if c.method.starts_with("texsat") {
            assert!(c.points.iter().all(|p| p.1 == 0.0), "{c:?}");
        }
    }
    let f32 = &curves[0];
    assert!(f32.method.starts_with("float32 SAT (GPU"));
    // Grows with the table; centring on the mean keeps far more digits.
    assert!(f32.points[5].1 > 100.0 * f32.points[0].1, "{f32:?}");
    let centred = &curves[1];
    assert!(centred.method.contains("mean"));
    assert!(centred.points[5].1 < f32.points[5].1 / 100.0, "{centred:?}");
}
