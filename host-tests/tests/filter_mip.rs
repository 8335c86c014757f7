//! Point sampling and the box-filtered pyramid (texsat `filters::point`, `filters::mip`) against
//! the `f64` references of `src/filter_ref_mip.rs`:
//!
//! * the build: every stored texel is the exact box average of its clipped base block rounded
//!   to nearest, ties up (integer equality), within 1/2 of the `f64` pyramid; all sizes up to
//!   20 x 20 plus 1 x 300, 300 x 1, 33 x 65, 255 x 255;
//! * memory: `storage_needed`, `pyramid_texels`, the ratio to the texture (exactly
//!   `(4^(k+1) - 1) / 3 / 4^k` for `2^k x 2^k`, tending to 4/3; about 2 for `1 x n`);
//! * sampling, on grids of footprints (smaller than a texel, a few texels, larger than the
//!   texture, points), odd sizes, `1 x N`, `N x 1`, every mode, `F` = 4, 8, 16, `u8`/`u16`, 1 to 3
//!   channels, and by proptest: `point` and `point_sample` exactly equal to the references; the
//!   level of detail within one unit below `floor(256 log2 d)`; `trilinear` within
//!   `m 2^(1-W) + 2^-17` (`W` = 24 weight bits for `u8`, 20 for `u16`) of the `f64` trilinear on
//!   the *stored* pyramid (the bound is approached), within `1/2 + m 2^(1-W) + 2^-17` of the
//!   `f64` trilinear on the exact pyramid; the costs
//!   (1 / 0 / 0 and 8 reads, 7 multiplies, 14 additive operations per channel).

use texsat_host_tests::filter_ref_mip as reference;
use texsat_host_tests::RngExt;

use fixed::traits::Fixed;
use fixed::types::{I16F16, I24F8, I28F4, I40F24};
use proptest::prelude::*;
use reference::{
    exact_pyramid, lod_in_range, memory_ratio, point_ref, point_sample_ref, pyramid_from_levels,
    pyramid_texels, rounded_pyramid, trilinear_bound, trilinear_ref, RefImage,
};
use texsat::filters::mip::{trilinear_error_bound, MipPyramid};
use texsat::filters::point::point;
use texsat::filters::OUT_FRAC_BITS;
use texsat::{
    Border, ClampToEdge, Coord, EdgeMode, Error, MirroredRepeat, Repeat, Tally, Texel, Texture,
};
use texsat_host_tests::strategies::{arb_interval, arb_mode, arb_texture};
use texsat_host_tests::{rect_from_raw, RefMode, RefTexel, RefTexture};

const ONE: f64 = (1u64 << OUT_FRAC_BITS) as f64;

/// The stored levels of a pyramid, read back through `level_texel`.
fn stored_levels<T: Texel, const C: usize>(p: &MipPyramid<'_, T, C>) -> Vec<Vec<u32>> {
    p.levels()
        .iter()
        .enumerate()
        .map(|(l, &(w, h))| {
            let mut v = Vec::with_capacity(w * h * C);
            for y in 0..h {
                for x in 0..w {
                    let px = p.level_texel(l, x, y).expect("texel inside the level");
                    v.extend(px.iter().map(|t| t.to_u16() as u32));
                }
            }
            v
        })
        .collect()
}

/// Worst errors seen (texel units).
#[derive(Default, Debug)]
struct Stats {
    samples: u64,
    worst_stored: f64,
    worst_exact: f64,
}

/// Everything one texture needs for the checks.
struct Case<'a, T: Texel, const C: usize> {
    texture: Texture<'a, T, C>,
    pyramid: MipPyramid<'a, T, C>,
    base: RefImage,
    stored: Vec<RefImage>,
    exact: Vec<RefImage>,
    bits: u32,
}

fn with_case<T: RefTexel, const C: usize, R>(
    tex: &RefTexture,
    bits: u32,
    f: impl FnOnce(&Case<'_, T, C>) -> R,
) -> R {
    let texels = tex.texels_as::<T>();
    let (w, h) = (tex.width, tex.height);
    let texture = Texture::<T, C>::new(&texels, w, h).unwrap();
    let mut storage = vec![texels[0]; MipPyramid::<T, C>::storage_needed(w, h).unwrap()];
    let pyramid = MipPyramid::build(&texture, &mut storage).unwrap();
    let stored = pyramid_from_levels(pyramid.levels(), C, &stored_levels(&pyramid));
    let exact = exact_pyramid(&tex.texels, w, h, C);
    let case = Case {
        texture,
        pyramid,
        base: exact[0].clone(),
        stored,
        exact,
        bits,
    };
    f(&case)
}

/// Checks one footprint (raw corners at `X`'s `F`) under mode `M` (= `mode`).
fn check_one<T: Texel, const C: usize, X: Fixed + Coord, M: EdgeMode>(
    case: &Case<'_, T, C>,
    raw: [i64; 4],
    mode: RefMode,
    m: M,
    stats: &mut Stats,
) {
    assert_eq!(m.kind(), mode.kind(), "mode value and reference mode agree");
    let f = X::FRAC_BITS;
    let r = rect_from_raw::<X>(raw);
    let index = |i: i64, n: usize| mode.index(i, n);
    let p = &case.pyramid;
    let ctx = || format!("{}x{} {raw:?} F={f} {mode:?}", case.base.w, case.base.h);

    // Point sampling: exact.
    let mut k = Tally::new();
    let got = point(&case.texture, &r, m, &mut k).unwrap();
    let want = point_ref(&case.base, raw, f, &index);
    assert_eq!(want.len(), C);
    for (g, w) in got.values.iter().zip(&want) {
        assert_eq!(*g as f64, w * ONE, "point {}", ctx());
    }
    assert_eq!((k.reads, k.muls, k.divs, k.adds), (1, 0, 0, 0));

    // Level of detail.
    let lod = p.lod(&r).unwrap();
    assert!(
        lod_in_range(lod, raw, f, p.level_count()),
        "lod {lod} {}",
        ctx()
    );

    // Point-sampled pyramid: exact on the stored pyramid.
    let mut k = Tally::new();
    let got = p.point_sample(&r, m, &mut k).unwrap();
    let want = point_sample_ref(&case.stored, raw, f, lod, &index);
    assert_eq!(want.len(), C);
    for (g, w) in got.values.iter().zip(&want) {
        assert_eq!(*g as f64, w * ONE, "point_sample {}", ctx());
    }
    assert_eq!((k.reads, k.muls, k.divs, k.adds), (1, 0, 0, 0));

    // Trilinear: within the bound of the same filter in f64 on the stored pyramid.
    let mut k = Tally::new();
    let got = p.trilinear(&r, m, &mut k).unwrap();
    assert_eq!(
        (k.reads, k.muls, k.divs, k.adds),
        (8, 7 * C as u64, 0, 14 * C as u64)
    );
    assert_eq!(k.bits_read, 8 * T::BITS as u64 * C as u64);
    let want = trilinear_ref(&case.stored, raw, f, lod, &index);
    let ideal = trilinear_ref(&case.exact, raw, f, lod, &index);
    let bound = trilinear_bound(case.bits);
    for c in 0..C {
        let v = got.values[c] as f64 / ONE;
        let e = (v - want[c]).abs();
        assert!(e <= bound + 1e-12, "trilinear {e} > {bound} {}", ctx());
        let e2 = (v - ideal[c]).abs();
        assert!(e2 <= 0.5 + bound + 1e-12, "vs exact pyramid {e2} {}", ctx());
        stats.worst_stored = stats.worst_stored.max(e);
        stats.worst_exact = stats.worst_exact.max(e2);
    }
    stats.samples += 1;
}

fn check<T: Texel, const C: usize, X: Fixed + Coord>(
    case: &Case<'_, T, C>,
    raw: [i64; 4],
    mode: RefMode,
    stats: &mut Stats,
) {
    match mode {
        RefMode::Border => check_one::<T, C, X, Border>(case, raw, mode, Border, stats),
        RefMode::Clamp => check_one::<T, C, X, ClampToEdge>(case, raw, mode, ClampToEdge, stats),
        RefMode::Repeat => check_one::<T, C, X, Repeat>(case, raw, mode, Repeat, stats),
        RefMode::Mirror => {
            check_one::<T, C, X, MirroredRepeat>(case, raw, mode, MirroredRepeat, stats)
        }
    }
}

/// Footprint sides (in texels) of the grids: a point, sub-texel, about a texel, a few texels,
/// larger than the texture.
fn sides(n: usize) -> Vec<f64> {
    vec![
        0.0,
        0.125,
        0.5,
        1.0,
        1.375,
        2.0,
        3.75,
        n as f64 + 0.5,
        2.0 * n as f64 + 3.0,
    ]
}

/// A grid of footprints over `[-n - 1, 2n + 1]` per axis, every mode.
fn grid<T: Texel, const C: usize, X: Fixed + Coord>(
    case: &Case<'_, T, C>,
    step_x: f64,
    step_y: f64,
    stats: &mut Stats,
) {
    let (w, h) = (case.base.w, case.base.h);
    let f = X::FRAC_BITS;
    let s = (1i64 << f) as f64;
    let (sw, sh) = (sides(w), sides(h));
    let mut pick = 0usize;
    let mut y = -(h as f64) - 1.0;
    while y <= 2.0 * h as f64 + 1.0 {
        let mut x = -(w as f64) - 1.0;
        while x <= 2.0 * w as f64 + 1.0 {
            for _ in 0..2 {
                pick += 1;
                let (a, b) = (sw[pick % sw.len()], sh[(pick / sw.len() + pick) % sh.len()]);
                let raw = [
                    (x * s).round() as i64,
                    (y * s).round() as i64,
                    ((x + a) * s).round() as i64,
                    ((y + b) * s).round() as i64,
                ];
                for mode in RefMode::ALL {
                    check::<T, C, X>(case, raw, mode, stats);
                }
            }
            x += step_x;
        }
        y += step_y;
    }
}

const GRID_SIZES: [(usize, usize); 14] = [
    (1, 1),
    (1, 2),
    (2, 1),
    (1, 7),
    (7, 1),
    (2, 2),
    (3, 3),
    (5, 3),
    (3, 5),
    (4, 4),
    (6, 7),
    (9, 2),
    (1, 16),
    (8, 8),
];

#[test]
fn grids_u8_one_channel_f8() {
    let mut stats = Stats::default();
    for (n, &(w, h)) in GRID_SIZES.iter().enumerate() {
        let tex = RefTexture::random(w, h, 1, 255, 100 + n as u64);
        with_case::<u8, 1, _>(&tex, 8, |case| {
            grid::<u8, 1, I24F8>(case, 0.3125, 0.4375, &mut stats);
        });
    }
    eprintln!("u8 C=1 F=8: {stats:?}, bound {}", trilinear_bound(8));
    // The rounding part 2^-17 of the bound is reached; the weight part (255 2^-23) cannot show
    // at F = 8 on these sizes (weights exact while F + 1 + l <= 24).
    assert!(stats.worst_stored >= 0.99 * 2f64.powi(-17), "{stats:?}");
    // Against the unrounded pyramid the storage rounding (up to 1/2) dominates.
    assert!(stats.worst_exact >= 0.45, "{stats:?}");
}

#[test]
fn grids_u16_three_channels_f4_and_f16() {
    let mut stats = Stats::default();
    for (n, &(w, h)) in GRID_SIZES.iter().enumerate().step_by(2) {
        let tex = RefTexture::random(w, h, 3, 65535, 200 + n as u64);
        with_case::<u16, 3, _>(&tex, 16, |case| {
            grid::<u16, 3, I28F4>(case, 0.5625, 0.6875, &mut stats);
        });
    }
    for (n, &(w, h)) in GRID_SIZES.iter().enumerate().skip(1).step_by(2) {
        let tex = RefTexture::random(w, h, 2, 65535, 300 + n as u64);
        with_case::<u16, 2, _>(&tex, 16, |case| {
            grid::<u16, 2, I16F16>(case, 0.5625, 0.6875, &mut stats);
        });
    }
    eprintln!("u16 F=4/16: {stats:?}, bound {}", trilinear_bound(16));
    assert!(stats.worst_stored >= 0.99 * 2f64.powi(-17), "{stats:?}");
}

#[test]
fn bound_matches_texsat_constant() {
    for bits in [8, 16] {
        assert_eq!(trilinear_bound(bits), trilinear_error_bound(bits));
    }
}

#[test]
fn weight_truncation_u16_approaches_bound() {
    // Level 10 alternates 0 / 65535 in blocks of 2^10; F = 24 gives F + 1 + l = 35 fraction
    // bits, 15 of them truncated (W = 20). Border: the single row's vertical taps are 0 and the
    // row.
    let l = 10u32;
    let w = 1usize << (l + 2);
    let texels: Vec<u32> = (0..w)
        .map(|x| if (x >> l).is_multiple_of(2) { 0 } else { 65535 })
        .collect();
    let tex = RefTexture::new(w, 1, 1, texels);
    let mut stats = Stats::default();
    let mut rng = texsat_host_tests::rng(9);
    with_case::<u16, 1, _>(&tex, 16, |case| {
        for _ in 0..3000 {
            // x0 = -1 (mod 2^14) and x1 = x0 + 2^(l+24) + 1 make x0 + x1 = -1 (mod 2^15): the
            // 15 truncated bits of each weight are all ones (nearly the largest truncation). The
            // side is 2^l + 2^-24 texels, whose lod is still exactly l.
            let x0 = rng.random_range(0..=((w as i64) << 10) - 1) * (1 << 14) + (1 << 14) - 1;
            let y0 = rng.random_range(-(1i64 << (l + 10))..=1i64 << (l + 10)) * (1 << 14)
                + (1 << 14)
                - 1;
            let side = (1i64 << (l + 24)) + 1;
            let raw = [x0, y0, x0 + side, y0 + side];
            assert_eq!(
                case.pyramid.lod(&rect_from_raw::<I40F24>(raw)).unwrap(),
                l << 8
            );
            check_one::<u16, 1, I40F24, Border>(case, raw, RefMode::Border, Border, &mut stats);
        }
    });
    let bound = trilinear_bound(16);
    eprintln!("u16 F=24 level 10: {stats:?}, bound {bound}");
    // Reachable here: nearly all of the weight part.
    assert!(stats.worst_stored > 0.8 * bound, "{stats:?}");
}

#[test]
fn build_is_the_rounded_exact_box_average() {
    let mut sizes: Vec<(usize, usize)> = Vec::new();
    for w in 1..=20 {
        for h in 1..=20 {
            sizes.push((w, h));
        }
    }
    sizes.extend([(1, 300), (300, 1), (33, 65), (255, 255)]);
    for (n, &(w, h)) in sizes.iter().enumerate() {
        let tex = RefTexture::random(w, h, 2, 255, n as u64);
        with_case::<u8, 2, _>(&tex, 8, |case| {
            let want = rounded_pyramid(&tex.texels, w, h, 2);
            let got = stored_levels(&case.pyramid);
            assert_eq!(got, want, "{w}x{h}");
            for (s, e) in case.stored.iter().zip(&case.exact) {
                for (a, b) in s.data.iter().zip(&e.data) {
                    assert!((a - b).abs() <= 0.5, "{w}x{h}");
                }
            }
        });
    }
    // u16 extremes, and the tie rule: [0, 1] -> 0.5 -> 1 (ties up); [0, 0, 1] -> 1/3 -> 0.
    let tex = RefTexture::constant(7, 5, 1, 65535);
    with_case::<u16, 1, _>(&tex, 16, |case| {
        assert!(stored_levels(&case.pyramid)
            .iter()
            .all(|l| l.iter().all(|&v| v == 65535)));
    });
    let tex = RefTexture::new(2, 1, 1, vec![0, 1]);
    with_case::<u8, 1, _>(&tex, 8, |case| {
        assert_eq!(case.pyramid.level_texel(1, 0, 0), Some([1]));
    });
    let tex = RefTexture::new(3, 1, 1, vec![0, 0, 1]);
    with_case::<u8, 1, _>(&tex, 8, |case| {
        // Level 1: [0, 0] -> 0 and the clipped block [1] -> 1; level 2: 1/3 -> 0 (from the
        // base, not from level 1's rounded (0 + 1) / 2 -> 1).
        assert_eq!(case.pyramid.level_texel(1, 1, 0), Some([1]));
        assert_eq!(case.pyramid.level_texel(2, 0, 0), Some([0]));
    });
}

#[test]
fn memory_is_four_thirds() {
    eprintln!("size        pyramid texels  storage (C=1)  ratio");
    for (w, h) in [
        (256, 256),
        (255, 255),
        (257, 257),
        (1, 300),
        (300, 1),
        (640, 480),
        (1000, 1000),
        (1024, 1024),
        (4096, 4096),
    ] {
        let total = MipPyramid::<u8>::pyramid_texels(w, h).unwrap();
        let storage = MipPyramid::<u8>::storage_needed(w, h).unwrap();
        assert_eq!(total, pyramid_texels(w, h));
        assert_eq!(storage, total - w * h);
        assert_eq!(
            MipPyramid::<u16, 3>::storage_needed(w, h).unwrap(),
            3 * storage
        );
        eprintln!(
            "{w:>4} x {h:<4}  {total:>14}  {storage:>13}  {:.6}",
            memory_ratio(w, h)
        );
    }
    // Exact for 2^k x 2^k: (4^(k+1) - 1) / 3 texels, ratio (4^(k+1) - 1) / (3 4^k) -> 4/3.
    let mut last = 0.0;
    for k in 0..=15u32 {
        let n = 1usize << k;
        let total = MipPyramid::<u8>::pyramid_texels(n, n).unwrap();
        assert_eq!(total, ((1usize << (2 * k + 2)) - 1) / 3);
        let ratio = total as f64 / (n * n) as f64;
        assert!(ratio > last && ratio < 4.0 / 3.0);
        last = ratio;
    }
    assert!((last - 4.0 / 3.0).abs() < 1e-9);
    // Any n x n: sum ceil(n/2^l)^2 <= sum (n/2^l + 1)^2, so the ratio is 4/3 + O(1/n).
    for n in 16..=2048usize {
        let r = memory_ratio(n, n);
        assert!((r - 4.0 / 3.0).abs() <= 5.0 / n as f64, "{n}: {r}");
    }
    // 1 x n halves one axis only: the ratio tends to 2.
    assert!((memory_ratio(1, 1 << 20) - 2.0).abs() < 1e-5);
    assert_eq!(pyramid_texels(1, 300), 603);
}

#[test]
fn storage_too_small_and_inverted() {
    let texels = [1u8; 15];
    let t = Texture::<u8>::new(&texels, 5, 3).unwrap();
    let need = MipPyramid::<u8>::storage_needed(5, 3).unwrap();
    let mut st = vec![0u8; need - 1];
    assert_eq!(
        MipPyramid::build(&t, &mut st).err(),
        Some(Error::StorageTooSmall {
            needed: need,
            got: need - 1
        })
    );
    let mut st = vec![0u8; need];
    let p = MipPyramid::build(&t, &mut st).unwrap();
    let r = rect_from_raw::<I24F8>([10, 0, 9, 5]);
    assert_eq!(
        p.trilinear(&r, Border, &mut Tally::new()),
        Err(Error::InvertedBox)
    );
    assert_eq!(
        p.point_sample(&r, Border, &mut Tally::new()),
        Err(Error::InvertedBox)
    );
    assert_eq!(
        point(&t, &r, Border, &mut Tally::new()),
        Err(Error::InvertedBox)
    );
}

fn arb_rect(
    w: usize,
    h: usize,
    f: u32,
    raw_min: i64,
    raw_max: i64,
) -> impl Strategy<Value = [i64; 4]> {
    (
        arb_interval(w, f, 6, raw_min, raw_max),
        arb_interval(h, f, 6, raw_min, raw_max),
    )
        .prop_map(|((x0, x1), (y0, y1))| [x0, y0, x1, y1])
}

fn arb_u8_case() -> impl Strategy<Value = (RefTexture, Vec<([i64; 4], RefMode)>)> {
    arb_texture(24, 24, 1, 255).prop_flat_map(|tex| {
        let (w, h) = (tex.width, tex.height);
        let rects =
            prop::collection::vec((arb_rect(w, h, 8, -(1 << 20), 1 << 20), arb_mode()), 1..8);
        (Just(tex), rects)
    })
}

fn arb_u16_case() -> impl Strategy<Value = (RefTexture, Vec<([i64; 4], RefMode)>)> {
    arb_texture(20, 20, 3, 65535).prop_flat_map(|tex| {
        let (w, h) = (tex.width, tex.height);
        let rects =
            prop::collection::vec((arb_rect(w, h, 12, -(1 << 24), 1 << 24), arb_mode()), 1..8);
        (Just(tex), rects)
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn prop_u8_f8((tex, rects) in arb_u8_case()) {
        let mut stats = Stats::default();
        with_case::<u8, 1, _>(&tex, 8, |case| {
            for &(raw, mode) in &rects {
                check::<u8, 1, I24F8>(case, raw, mode, &mut stats);
            }
        });
    }

    #[test]
    fn prop_u16_three_channels_f12((tex, rects) in arb_u16_case()) {
        let mut stats = Stats::default();
        with_case::<u16, 3, _>(&tex, 16, |case| {
            for &(raw, mode) in &rects {
                check::<u16, 3, fixed::types::I20F12>(case, raw, mode, &mut stats);
            }
        });
    }
}
