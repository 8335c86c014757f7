//! Exhaustive sweeps on small textures, compared exactly with the reference:
//!
//! * every integer box inside several textures (`1 x 1`, `1 x N`, `N x 1`, `3 x 5`, `7 x 4`) in
//!   `u16`/`u32`/`u64` entries, 1 and 3 channels, with the read count of each lookup;
//! * every box whose corners lie on the `1/16` grid (`F = 4`, `I28F4`) of a small texture, in
//!   both forms;
//! * every boundary mode with boxes reaching 2–3 periods outside on each side, integer corners
//!   and `F = 4`.

use fixed::types::I28F4;
use texsat::{Entry, NoCount, Tally};
use texsat_host_tests::{
    axis_weights, build_sat, rect_from_raw, sum_fixed, sum_int, RefForm, RefMode, RefTexel,
    RefTexture,
};

/// All intervals `[a, b)` with `a <= b` from the sorted coordinate list.
fn intervals(coords: &[i64]) -> Vec<(i64, i64)> {
    let mut out = Vec::new();
    for (k, &a) in coords.iter().enumerate() {
        for &b in &coords[k..] {
            out.push((a, b));
        }
    }
    out
}

/// Per-channel exact integral from precomputed axis weights (the reference's closed form).
fn weighted(tex: &RefTexture, wx: &[u128], wy: &[u128]) -> Vec<u128> {
    let mut out = vec![0u128; tex.channels];
    for (j, &b) in wy.iter().enumerate() {
        for (i, &a) in wx.iter().enumerate() {
            for (c, o) in out.iter_mut().enumerate() {
                *o += tex.texel(i, j, c) as u128 * a * b;
            }
        }
    }
    out
}

/// Every integer box inside the texture, in mode Border, against the reference; also the read
/// count: one per corner off the zero row and column, none for a zero-area box.
fn all_int_boxes<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture) {
    let mut st = vec![E::ZERO; tex.width * tex.height * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    let xs: Vec<i64> = (0..=tex.width as i64).collect();
    let ys: Vec<i64> = (0..=tex.height as i64).collect();
    let mut n = 0;
    for (y0, y1) in intervals(&ys) {
        for (x0, x1) in intervals(&xs) {
            // Direct summation over the covered texels (independent of the closed form).
            let want: Vec<u128> = (0..C)
                .map(|c| tex.exact_integral_direct(RefMode::Border, [x0, y0, x1, y1], 0, c))
                .collect();
            let r = [x0, y0, x1, y1].map(|v| v as i32);
            let mut k = Tally::new();
            let got = sum_int(&sat, r, RefMode::Border, &mut k).unwrap();
            assert_eq!(got.scaled_sums().to_vec(), want, "box {r:?} of {tex:?}");
            let corners = if x0 == x1 || y0 == y1 {
                0
            } else {
                [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
                    .iter()
                    .filter(|&&(x, y)| x > 0 && y > 0)
                    .count() as u64
            };
            assert_eq!(k.reads, corners, "reads of box {r:?}");
            assert_eq!(k.bits_read, corners * E::BITS as u64 * C as u64);
            n += 1;
        }
    }
    let (w, h) = (tex.width, tex.height);
    assert_eq!(n, (w + 1) * (w + 2) / 2 * (h + 1) * (h + 2) / 2);
}

fn int_shapes() -> Vec<(usize, usize)> {
    vec![(1, 1), (1, 9), (9, 1), (3, 5), (7, 4)]
}

#[test]
fn every_integer_box_u8_texels() {
    for (s, (w, h)) in int_shapes().into_iter().enumerate() {
        let t1 = RefTexture::random(w, h, 1, 255, 10 + s as u64);
        all_int_boxes::<u8, u16, 1>(&t1);
        all_int_boxes::<u8, u32, 1>(&t1);
        all_int_boxes::<u8, u64, 1>(&t1);
        let t3 = RefTexture::random(w, h, 3, 255, 20 + s as u64);
        all_int_boxes::<u8, u16, 3>(&t3);
        all_int_boxes::<u8, u32, 3>(&t3);
        all_int_boxes::<u8, u64, 3>(&t3);
        // The extremes: all-max (every entry as large as the worst case allows) and all-zero.
        all_int_boxes::<u8, u16, 1>(&RefTexture::constant(w, h, 1, 255));
        all_int_boxes::<u8, u32, 3>(&RefTexture::constant(w, h, 3, 255));
        all_int_boxes::<u8, u32, 1>(&RefTexture::constant(w, h, 1, 0));
    }
}

#[test]
fn every_integer_box_u16_texels() {
    for (s, (w, h)) in int_shapes().into_iter().enumerate() {
        let t1 = RefTexture::random(w, h, 1, 65535, 30 + s as u64);
        all_int_boxes::<u16, u32, 1>(&t1);
        all_int_boxes::<u16, u64, 1>(&t1);
        let t3 = RefTexture::random(w, h, 3, 65535, 40 + s as u64);
        all_int_boxes::<u16, u32, 3>(&t3);
        all_int_boxes::<u16, u64, 3>(&t3);
        all_int_boxes::<u16, u32, 1>(&RefTexture::constant(w, h, 1, 65535));
    }
    // u16 texels fit u16 entries only for a single texel.
    all_int_boxes::<u16, u16, 1>(&RefTexture::constant(1, 1, 1, 65535));
}

/// Every box with corners on the `1/16` grid of `[0, w] x [0, h]`, both forms, exact.
fn fine_grid<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture, step: i64) {
    let f = 4;
    let mut st = vec![E::ZERO; tex.width * tex.height * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    let xs: Vec<i64> = (0..=(tex.width as i64) << f)
        .step_by(step as usize)
        .collect();
    let ys: Vec<i64> = (0..=(tex.height as i64) << f)
        .step_by(step as usize)
        .collect();
    let xi: Vec<_> = intervals(&xs)
        .into_iter()
        .map(|(a, b)| (a, b, axis_weights(RefMode::Border, a, b, tex.width, f)))
        .collect();
    let yi: Vec<_> = intervals(&ys)
        .into_iter()
        .map(|(a, b)| (a, b, axis_weights(RefMode::Border, a, b, tex.height, f)))
        .collect();
    for (y0, y1, wy) in &yi {
        for (x0, x1, wx) in &xi {
            let want = weighted(tex, wx, wy);
            let r = rect_from_raw::<I28F4>([*x0, *y0, *x1, *y1]);
            let p = sum_fixed(&sat, &r, RefForm::Paper, RefMode::Border, &mut NoCount).unwrap();
            let s = sum_fixed(&sat, &r, RefForm::Stable, RefMode::Border, &mut NoCount).unwrap();
            assert_eq!(p.scaled_sums().to_vec(), want, "paper {r:?}");
            assert_eq!(s.scaled_sums().to_vec(), want, "stable {r:?}");
            assert_eq!(p.frac_bits(), 4);
            assert_eq!(p.sides_raw(), ((x1 - x0) as u64, (y1 - y0) as u64), "sides");
        }
    }
}

#[test]
fn every_sixteenth_offset_2x2() {
    // 33 x 33 grid points: 561 x-intervals times 561 y-intervals, every corner fraction.
    fine_grid::<u8, u32, 1>(&RefTexture::random(2, 2, 1, 255, 50), 1);
}

#[test]
fn every_sixteenth_offset_thin_and_wide_entries() {
    fine_grid::<u8, u32, 1>(&RefTexture::random(1, 3, 1, 255, 51), 1);
    fine_grid::<u8, u32, 1>(&RefTexture::random(3, 1, 1, 255, 52), 1);
    // u16 texels in u64 entries (i128 accumulator), 3 channels, every third 1/16 (still every
    // fraction, as gcd(3, 16) = 1 and the grid spans several texels).
    fine_grid::<u16, u64, 3>(&RefTexture::random(3, 2, 3, 65535, 53), 3);
    // u8 texels in u16 entries.
    fine_grid::<u8, u16, 1>(&RefTexture::constant(3, 2, 1, 255), 3);
}

/// Every integer box with corners in `[-k w, (k + 1) w] x [-k h, (k + 1) h]` under every mode.
fn int_modes<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture, k: i64) {
    let mut st = vec![E::ZERO; tex.width * tex.height * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    let (w, h) = (tex.width as i64, tex.height as i64);
    let xs: Vec<i64> = (-k * w..=(k + 1) * w).collect();
    let ys: Vec<i64> = (-k * h..=(k + 1) * h).collect();
    for mode in RefMode::ALL {
        let xi: Vec<_> = intervals(&xs)
            .into_iter()
            .map(|(a, b)| (a, b, axis_weights(mode, a, b, tex.width, 0)))
            .collect();
        let yi: Vec<_> = intervals(&ys)
            .into_iter()
            .map(|(a, b)| (a, b, axis_weights(mode, a, b, tex.height, 0)))
            .collect();
        for (y0, y1, wy) in &yi {
            for (x0, x1, wx) in &xi {
                let want = weighted(tex, wx, wy);
                let r = [*x0, *y0, *x1, *y1].map(|v| v as i32);
                let got = sum_int(&sat, r, mode, &mut NoCount).unwrap();
                assert_eq!(got.scaled_sums().to_vec(), want, "{mode:?} {r:?} {tex:?}");
            }
        }
    }
}

#[test]
fn every_mode_integer_boxes_three_periods_out() {
    // Mirror's period is 2n, so k = 6 texels of a 2-texel axis is 3 mirror periods.
    int_modes::<u8, u32, 1>(&RefTexture::random(2, 3, 1, 255, 60), 5);
    int_modes::<u8, u16, 1>(&RefTexture::random(1, 1, 1, 255, 61), 12);
    int_modes::<u8, u64, 3>(&RefTexture::random(3, 1, 3, 255, 62), 6);
    int_modes::<u16, u32, 1>(&RefTexture::random(1, 4, 1, 65535, 63), 6);
}

/// Under every mode and both forms: every x-interval of a `step/16` grid over
/// `[-k w, (k + 1) w]` against a fixed set of y-intervals, and the transpose.
fn f4_modes<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture, k: i64, step: i64) {
    let f = 4;
    let mut st = vec![E::ZERO; tex.width * tex.height * C];
    let sat = build_sat::<T, E, C>(tex, &mut st).unwrap();
    let grid = |n: usize| -> Vec<i64> {
        let n = (n as i64) << f;
        (-k * n..=(k + 1) * n).step_by(step as usize).collect()
    };
    // A few intervals per axis: inside, straddling each edge, one and several periods out,
    // zero-length, long.
    let few = |n: usize| -> Vec<(i64, i64)> {
        let e = (n as i64) << f;
        vec![
            (0, e),
            (3, e - 5),
            (-7, 9),
            (e - 9, e + 11),
            (-e - 3, -1),
            (e + 1, 2 * e + 7),
            (-2 * e - 5, 3 * e + 3),
            (-3 * e, -e),
            (5, 5),
            (-k * e, (k + 1) * e),
            (2 * e - 1, 4 * e + 13),
            (-e + 8, e - 8),
        ]
    };
    let (xs, ys) = (grid(tex.width), grid(tex.height));
    for mode in RefMode::ALL {
        let mut boxes = Vec::new();
        for (x0, x1) in intervals(&xs) {
            for &(y0, y1) in &few(tex.height) {
                boxes.push([x0, y0, x1, y1]);
            }
        }
        for (y0, y1) in intervals(&ys) {
            for &(x0, x1) in &few(tex.width) {
                boxes.push([x0, y0, x1, y1]);
            }
        }
        for b in boxes {
            let want = weighted(
                tex,
                &axis_weights(mode, b[0], b[2], tex.width, f),
                &axis_weights(mode, b[1], b[3], tex.height, f),
            );
            let r = rect_from_raw::<I28F4>(b);
            for form in RefForm::ALL {
                let got = sum_fixed(&sat, &r, form, mode, &mut NoCount).unwrap();
                assert_eq!(got.scaled_sums().to_vec(), want, "{mode:?} {form:?} {b:?}");
            }
        }
    }
}

#[test]
fn every_mode_f4_boxes_three_periods_out() {
    f4_modes::<u8, u32, 1>(&RefTexture::random(2, 2, 1, 255, 70), 6, 11);
    f4_modes::<u8, u64, 3>(&RefTexture::random(3, 1, 3, 255, 71), 6, 13);
    f4_modes::<u16, u32, 1>(&RefTexture::random(1, 2, 1, 65535, 72), 6, 7);
}
