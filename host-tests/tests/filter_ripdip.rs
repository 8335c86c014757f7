//! The ripmap (`texsat::filters::rip`) and the dipmap (`texsat::filters::dip`) against the `f64`
//! reference in `src/filter_ref_ripdip.rs`:
//!
//! * levels: every stored texel equals the correctly rounded block average (exact integer
//!   reference) and lies within 1/2 of the exact average: every size up to 12 x 12 (odd sizes,
//!   `1 x N`, `N x 1`), `u8` and `u16` texels (random, all-max), 1 and 3 channels;
//! * sampling: exhaustive footprint grids (centres inside and outside the texture, sides 0,
//!   smaller than a texel, larger than the texture) on small textures in every boundary mode,
//!   and proptest cases at `F` = 4, 8, 16: the output is within the documented arithmetic bound
//!   (`2^(b+1)` output units) of the same filter in `f64` on the stored levels with the same
//!   fixed-point level positions; the ripmap and the trilinear dipmap are also within the
//!   documented level-selection bound of the exact-`log2` filter, and all variants within
//!   `1/2 + bounds` of the filter on the *exact* (unrounded) levels;
//! * operation counts on every sample: ripmap 16 reads, 15 multiplies, 30 additive; dipmap
//!   bilinear 8, 6, 13; trilinear 16, 14, 29 (reads fewer only under `Border` off the levels);
//! * memory: the measured storage ratios (ripmap -> 4, dipmap -> 3) against the formulas.

use texsat_host_tests::filter_ref_ripdip as reference;

use fixed::traits::Fixed;
use fixed::types::{I16F16, I24F8, I28F4, I40F24};
use proptest::prelude::*;
use reference::{dip_sample, rip_sample, DipVariant, LevelSel, RefDip, RefRip};
use texsat::filters::dip::{self, DipFilter, DipMap, DipPyramid};
use texsat::filters::rip::{self, RipMap};
use texsat::filters::Sample;
use texsat::{Border, ClampToEdge, Coord, MirroredRepeat, Rect, Repeat, Tally, Texel, Texture};
use texsat_host_tests::strategies::{arb_interval, arb_mode, arb_texture};
use texsat_host_tests::{rect_from_raw, RefMode, RefTexel, RefTexture, RngExt};

const OUT: f64 = 65536.0;

fn rip_mode<X: Coord, T: Texel, const C: usize>(
    map: &RipMap<'_, T, C>,
    r: &Rect<X>,
    mode: RefMode,
    k: &mut Tally,
) -> Sample<C> {
    match mode {
        RefMode::Border => map.sample(r, Border, k),
        RefMode::Clamp => map.sample(r, ClampToEdge, k),
        RefMode::Repeat => map.sample(r, Repeat, k),
        RefMode::Mirror => map.sample(r, MirroredRepeat, k),
    }
    .expect("valid footprint")
}

fn dip_mode<X: Coord, T: Texel, const C: usize>(
    map: &DipMap<'_, T, C>,
    r: &Rect<X>,
    filter: DipFilter,
    mode: RefMode,
    k: &mut Tally,
) -> Sample<C> {
    match mode {
        RefMode::Border => map.sample(r, filter, Border, k),
        RefMode::Clamp => map.sample(r, filter, ClampToEdge, k),
        RefMode::Repeat => map.sample(r, filter, Repeat, k),
        RefMode::Mirror => map.sample(r, filter, MirroredRepeat, k),
    }
    .expect("valid footprint")
}

/// Worst error seen, as a fraction of its bound, per check.
#[derive(Debug, Default, Clone, Copy)]
struct Worst {
    arith: f64,
    level_sel: f64,
    end_to_end: f64,
}

impl Worst {
    fn merge(&mut self, o: Worst) {
        self.arith = self.arith.max(o.arith);
        self.level_sel = self.level_sel.max(o.level_sel);
        self.end_to_end = self.end_to_end.max(o.end_to_end);
    }
}

/// Asserts `|got - OUT * want| < bound` per channel; returns the worst `error / bound`.
fn check(got: &[u64], want: &[f64], bound: f64, what: impl Fn() -> String) -> f64 {
    let mut worst = 0.0f64;
    for (g, w) in got.iter().zip(want) {
        let err = (*g as f64 - w * OUT).abs();
        assert!(
            err < bound,
            "{}: got {g}, want {}, err {err} >= {bound}",
            what(),
            w * OUT
        );
        worst = worst.max(err / bound);
    }
    worst
}

/// Builds a ripmap of `tex` and checks its levels; returns the storage.
fn build_rip<T: RefTexel + TryFrom<u16>, const C: usize>(tex: &RefTexture) -> Vec<T> {
    assert_eq!(tex.channels, C);
    let texels: Vec<T> = tex.texels_as();
    let t = Texture::<T, C>::new(&texels, tex.width, tex.height).unwrap();
    let mut st = vec![T::from_u32(0); RipMap::<T, C>::storage_needed(tex.width, tex.height)];
    RipMap::build(&t, &mut st).unwrap();
    st
}

fn build_dip<T: RefTexel + TryFrom<u16>, const C: usize>(tex: &RefTexture) -> Vec<T> {
    assert_eq!(tex.channels, C);
    let texels: Vec<T> = tex.texels_as();
    let t = Texture::<T, C>::new(&texels, tex.width, tex.height).unwrap();
    let mut st = vec![T::from_u32(0); DipMap::<T, C>::storage_needed(tex.width, tex.height)];
    DipMap::build(&t, &mut st).unwrap();
    st
}

/// The stored ripmap levels as reference levels.
fn rip_stored<T: Texel, const C: usize>(map: &RipMap<'_, T, C>) -> RefRip {
    RefRip::from_fn(map.width(), map.height(), C, |lx, ly, i, j, c| {
        map.level_texel(lx, ly, i, j).unwrap()[c].to_u16() as f64
    })
}

fn dip_stored<T: Texel, const C: usize>(map: &DipMap<'_, T, C>) -> RefDip {
    let get = |p: DipPyramid| {
        move |l: usize, i: usize, j: usize, c: usize| {
            map.level_texel(p, l, i, j).unwrap()[c].to_u16() as f64
        }
    };
    RefDip::from_fn(
        map.width(),
        map.height(),
        C,
        get(DipPyramid::Row),
        get(DipPyramid::Column),
    )
}

/// Levels: stored == correctly rounded reference, and within 1/2 of the exact average.
fn check_levels<T: RefTexel + TryFrom<u16>, const C: usize>(tex: &RefTexture) {
    let (w, h) = (tex.width, tex.height);
    let st = build_rip::<T, C>(tex);
    let map = RipMap::<T, C>::from_storage(&st, w, h).unwrap();
    let exact = RefRip::build(&tex.texels, w, h, C, false);
    let rounded = RefRip::build(&tex.texels, w, h, C, true);
    let stored = rip_stored(&map);
    assert_eq!(
        (map.levels_x(), map.levels_y()),
        (exact.levels_x, exact.levels_y)
    );
    for (s, (r, e)) in stored
        .levels
        .iter()
        .zip(rounded.levels.iter().zip(&exact.levels))
    {
        assert_eq!(s, r, "{w}x{h} ripmap level");
        for (a, b) in s.v.iter().zip(&e.v) {
            assert!((a - b).abs() <= 0.5);
        }
    }
    let st = build_dip::<T, C>(tex);
    let map = DipMap::<T, C>::from_storage(&st, w, h).unwrap();
    let exact = RefDip::build(&tex.texels, w, h, C, false);
    let rounded = RefDip::build(&tex.texels, w, h, C, true);
    let stored = dip_stored(&map);
    assert_eq!(stored.row, rounded.row, "{w}x{h} row pyramid");
    assert_eq!(stored.col, rounded.col, "{w}x{h} column pyramid");
    for (s, e) in stored
        .row
        .iter()
        .chain(&stored.col)
        .zip(exact.row.iter().chain(&exact.col))
    {
        for (a, b) in s.v.iter().zip(&e.v) {
            assert!((a - b).abs() <= 0.5);
        }
    }
}

#[test]
fn levels_exhaustive_small_sizes() {
    for w in 1..=12 {
        for h in 1..=12 {
            let seed = (w * 100 + h) as u64;
            check_levels::<u8, 1>(&RefTexture::random(w, h, 1, 255, seed));
            check_levels::<u16, 1>(&RefTexture::random(w, h, 1, 65535, seed));
            check_levels::<u16, 1>(&RefTexture::constant(w, h, 1, 65535));
            check_levels::<u8, 3>(&RefTexture::random(w, h, 3, 255, seed + 7));
        }
    }
    for (w, h) in [(1, 37), (37, 1), (33, 17), (64, 3)] {
        check_levels::<u8, 1>(&RefTexture::random(w, h, 1, 255, 5));
    }
}

/// Samples every footprint of `rects` (raw, `F = f`) in every mode with every filter and checks
/// bounds and counts. Returns the worst ratios (ripmap, dipmap bilinear, dipmap trilinear).
fn check_samples<X: Coord + Fixed, T: RefTexel + TryFrom<u16>, const C: usize>(
    tex: &RefTexture,
    rects: &[[i64; 4]],
    modes: &[RefMode],
) -> [Worst; 3] {
    let (w, h) = (tex.width, tex.height);
    let f = X::FRAC_BITS;
    let arith = rip::arithmetic_error_bound(T::BITS) as f64;
    assert_eq!(arith, dip::arithmetic_error_bound(T::BITS) as f64);
    let half = OUT / 2.0;
    let rip_sel = rip::level_selection_error_bound(T::BITS) as f64;
    let dip_sel = dip::level_selection_error_bound(T::BITS) as f64;
    let bits = T::BITS as u64 * C as u64;

    let rst = build_rip::<T, C>(tex);
    let rmap = RipMap::<T, C>::from_storage(&rst, w, h).unwrap();
    let rstored = rip_stored(&rmap);
    let rexact = RefRip::build(&tex.texels, w, h, C, false);
    let dst = build_dip::<T, C>(tex);
    let dmap = DipMap::<T, C>::from_storage(&dst, w, h).unwrap();
    let dstored = dip_stored(&dmap);
    let dexact = RefDip::build(&tex.texels, w, h, C, false);

    let mut worst = [Worst::default(); 3];
    for &b in rects {
        let r = rect_from_raw::<X>(b);
        for &mode in modes {
            let idx = move |i: i64, n: usize| mode.index(i, n);
            let what = || format!("{w}x{h} {mode:?} {b:?} F={f}");

            // Ripmap.
            let mut k = Tally::new();
            let got = rip_mode(&rmap, &r, mode, &mut k).values;
            let c = C as u64;
            assert_eq!((k.muls, k.divs, k.adds), (15 * c, 0, 30 * c), "{}", what());
            if mode == RefMode::Border {
                assert!(k.reads <= 16, "{}", what());
            } else {
                assert_eq!(k.reads, 16, "{}", what());
            }
            assert_eq!(k.bits_read, k.reads * bits);
            let mut o = Worst::default();
            let want = rip_sample(&rstored, b, f, LevelSel::Fixed, &idx);
            o.arith = check(&got, &want, arith, || format!("rip arith {}", what()));
            let want = rip_sample(&rstored, b, f, LevelSel::Exact, &idx);
            o.level_sel = check(&got, &want, arith + rip_sel, || {
                format!("rip sel {}", what())
            });
            let want = rip_sample(&rexact, b, f, LevelSel::Exact, &idx);
            let bound = half + arith + rip_sel;
            o.end_to_end = check(&got, &want, bound, || format!("rip e2e {}", what()));
            worst[0].merge(o);

            // Dipmap, both variants.
            for (i, (filter, variant, cost)) in [
                (DipFilter::Bilinear, DipVariant::Bilinear, (8, 6, 13)),
                (DipFilter::Trilinear, DipVariant::Trilinear, (16, 14, 29)),
            ]
            .into_iter()
            .enumerate()
            {
                let mut k = Tally::new();
                let got = dip_mode(&dmap, &r, filter, mode, &mut k).values;
                assert_eq!(
                    (k.muls, k.divs, k.adds),
                    (cost.1 * c, 0, cost.2 * c),
                    "{}",
                    what()
                );
                if mode == RefMode::Border {
                    assert!(k.reads <= cost.0, "{}", what());
                } else {
                    assert_eq!(k.reads, cost.0, "{}", what());
                }
                assert_eq!(k.bits_read, k.reads * bits);
                let mut o = Worst::default();
                let want = dip_sample(&dstored, b, f, variant, LevelSel::Fixed, &idx);
                o.arith = check(&got, &want, arith, || {
                    format!("dip {variant:?} arith {}", what())
                });
                if variant == DipVariant::Trilinear {
                    let want = dip_sample(&dstored, b, f, variant, LevelSel::Exact, &idx);
                    let bound = arith + dip_sel;
                    o.level_sel = check(&got, &want, bound, || format!("dip sel {}", what()));
                    let want = dip_sample(&dexact, b, f, variant, LevelSel::Exact, &idx);
                    let bound = half + arith + dip_sel;
                    o.end_to_end = check(&got, &want, bound, || format!("dip e2e {}", what()));
                } else {
                    let want = dip_sample(&dexact, b, f, variant, LevelSel::Fixed, &idx);
                    let bound = half + arith;
                    o.end_to_end = check(&got, &want, bound, || format!("dip e2e {}", what()));
                }
                worst[1 + i].merge(o);
            }
        }
    }
    worst
}

/// A grid of footprints on a `w x h` texture at `F = 8`: centres every 7/8 texel from 1.5
/// texels outside to 1.5 inside the far edge, sides 0, 1/4, 3/4, 1, 1.5, 2.5, 4, larger than the
/// texture, and 64.
fn grid(w: usize, h: usize) -> Vec<[i64; 4]> {
    let f = 8;
    let s = 1i64 << f;
    let sides = |n: usize| {
        vec![
            0,
            s / 4,
            3 * s / 4,
            s,
            3 * s / 2,
            5 * s / 2,
            4 * s,
            (2 * n as i64 + 3) * s,
            64 * s,
        ]
    };
    let centres = |n: usize| {
        let mut v = vec![];
        let mut c = -3 * s / 2;
        while c <= (n as i64) * s + 3 * s / 2 {
            v.push(c);
            c += 7 * s / 8;
        }
        v
    };
    let mut out = vec![];
    for cx in centres(w) {
        for cy in centres(h) {
            for sw in sides(w) {
                for sh in sides(h) {
                    out.push([cx - sw / 2, cy - sh / 2, cx - sw / 2 + sw, cy - sh / 2 + sh]);
                }
            }
        }
    }
    out
}

#[test]
fn sampling_exhaustive_grid_every_mode() {
    let mut worst = [Worst::default(); 3];
    let sizes = [
        (1, 1),
        (1, 5),
        (6, 1),
        (2, 3),
        (3, 2),
        (5, 3),
        (4, 4),
        (7, 5),
    ];
    for (n, &(w, h)) in sizes.iter().enumerate() {
        let rects = grid(w, h);
        let tex = RefTexture::random(w, h, 1, 255, 40 + n as u64);
        let ws = check_samples::<I24F8, u8, 1>(&tex, &rects, &RefMode::ALL);
        for (a, b) in worst.iter_mut().zip(ws) {
            a.merge(b);
        }
        let tex = RefTexture::random(w, h, 1, 65535, 50 + n as u64);
        let ws = check_samples::<I24F8, u16, 1>(&tex, &rects, &RefMode::ALL);
        for (a, b) in worst.iter_mut().zip(ws) {
            a.merge(b);
        }
    }
    // Three channels on one odd size.
    let tex = RefTexture::random(5, 3, 3, 255, 99);
    check_samples::<I24F8, u8, 3>(&tex, &grid(5, 3), &[RefMode::Border, RefMode::Mirror]);
    println!("worst error / bound (rip, dip bilinear, dip trilinear): {worst:?}");
}

/// At `F = 24` the probe positions have more than 16 fraction bits, so the weights are
/// truncated: the arithmetic error reaches a good part of its bound (the unit tests in
/// `src/filters/{rip,dip}.rs` construct a case within 1% of it).
#[test]
fn arithmetic_bound_is_approached_at_f24() {
    let mut rng = texsat_host_tests::rng(24);
    let (w, h) = (6, 5);
    // High-contrast texture: 0 or max.
    let texels = (0..w * h)
        .map(|_| {
            if rng.random_range(0..2) == 0 {
                0
            } else {
                65535
            }
        })
        .collect();
    let tex = RefTexture::new(w, h, 1, texels);
    let rects: Vec<[i64; 4]> = (0..3000)
        .map(|_| {
            let x0 = rng.random_range(-(2 << 24)..=8 << 24);
            let y0 = rng.random_range(-(2 << 24)..=7 << 24);
            let sw = rng.random_range(0..=3 << 24);
            let sh = rng.random_range(0..=3 << 24);
            [x0, y0, x0 + sw, y0 + sh]
        })
        .collect();
    let worst = check_samples::<I40F24, u16, 1>(&tex, &rects, &[RefMode::Repeat]);
    println!(
        "F = 24, worst arithmetic error / bound: {:?}",
        worst.map(|w| w.arith)
    );
    for wst in worst {
        assert!(wst.arith > 0.3, "{worst:?}");
    }
}

#[test]
fn constant_textures_are_exact() {
    for (w, h) in [(1, 1), (1, 7), (7, 1), (5, 3), (8, 8)] {
        for v in [0u32, 1, 200, 255] {
            let tex = RefTexture::constant(w, h, 1, v);
            let st = build_rip::<u8, 1>(&tex);
            let rmap = RipMap::<u8, 1>::from_storage(&st, w, h).unwrap();
            let dst = build_dip::<u8, 1>(&tex);
            let dmap = DipMap::<u8, 1>::from_storage(&dst, w, h).unwrap();
            for b in grid(w, h).into_iter().step_by(7) {
                let r = rect_from_raw::<I24F8>(b);
                for mode in [RefMode::Clamp, RefMode::Repeat, RefMode::Mirror] {
                    let want = (v as u64) << 16;
                    let k = &mut Tally::new();
                    assert_eq!(rip_mode(&rmap, &r, mode, k).values[0], want);
                    for filter in [DipFilter::Bilinear, DipFilter::Trilinear] {
                        assert_eq!(dip_mode(&dmap, &r, filter, mode, k).values[0], want);
                    }
                }
            }
        }
    }
}

#[test]
fn memory_ratios() {
    assert_eq!(rip::LEVEL_FRAC_BITS, reference::LEVEL_FRAC_BITS);
    assert_eq!(dip::LEVEL_FRAC_BITS, reference::LEVEL_FRAC_BITS);
    println!("| size | ripmap elements | ratio | dipmap elements | ratio |");
    println!("|---|---|---|---|---|");
    let mut last = (0.0, 0.0);
    for e in 0..=12 {
        let n = 1usize << e;
        let rip_n = RipMap::<u8, 1>::storage_needed(n, n);
        let dip_n = DipMap::<u8, 1>::storage_needed(n, n);
        assert_eq!(rip_n, (2 * n - 1) * (2 * n - 1));
        assert_eq!(dip_n, 3 * n * n - 2 * n);
        let (rr, dr) = (rip_n as f64 / (n * n) as f64, dip_n as f64 / (n * n) as f64);
        println!("| {n} x {n} | {rip_n} | {rr:.4} | {dip_n} | {dr:.4} |");
        assert!(rr >= last.0 && dr >= last.1);
        last = (rr, dr);
    }
    assert!((4.0 - last.0) < 1e-3 && (3.0 - last.1) < 1e-3);
    for (w, h) in [(5, 3), (1, 1), (1, 9), (9, 1), (640, 480), (1000, 1)] {
        let rip_n = RipMap::<u8, 1>::storage_needed(w, h);
        let dip_n = DipMap::<u8, 1>::storage_needed(w, h);
        let ax = |n: usize| {
            (0..reference::level_count(n))
                .map(|l| reference::level_len(n, l))
                .sum::<usize>()
        };
        assert_eq!(rip_n, ax(w) * ax(h));
        assert_eq!(dip_n, w * ax(h) + h * (ax(w) - w));
        println!(
            "| {w} x {h} | {rip_n} | {:.4} | {dip_n} | {:.4} |",
            rip_n as f64 / (w * h) as f64,
            dip_n as f64 / (w * h) as f64
        );
    }
    // Built maps use exactly that much, and report it in bits.
    let tex = RefTexture::random(64, 48, 3, 65535, 3);
    let st = build_rip::<u16, 3>(&tex);
    let map = RipMap::<u16, 3>::from_storage(&st, 64, 48).unwrap();
    assert_eq!(map.storage_len(), 3 * 127 * (48 + 24 + 12 + 6 + 3 + 2 + 1));
    assert_eq!(map.storage_bits(), map.storage_len() as u64 * 16);
    let st = build_dip::<u16, 3>(&tex);
    let map = DipMap::<u16, 3>::from_storage(&st, 64, 48).unwrap();
    assert_eq!(map.storage_len(), 3 * (64 * 96 + 48 * 63));
    assert_eq!(map.storage_bits(), map.storage_len() as u64 * 16);
}

fn arb_case(
    f: u32,
    max: u32,
    channels: usize,
) -> impl Strategy<Value = (RefTexture, Vec<[i64; 4]>, RefMode)> {
    arb_texture(9, 9, channels, max).prop_flat_map(move |t| {
        let r = (
            arb_interval(t.width, f, 4, -(1 << 30), 1 << 30),
            arb_interval(t.height, f, 4, -(1 << 30), 1 << 30),
        )
            .prop_map(|((x0, x1), (y0, y1))| [x0, y0, x1, y1]);
        (Just(t), prop::collection::vec(r, 1..8), arb_mode())
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn prop_u8_f8((t, rects, mode) in arb_case(8, 255, 1)) {
        check_samples::<I24F8, u8, 1>(&t, &rects, &[mode]);
    }

    #[test]
    fn prop_u16_f4((t, rects, mode) in arb_case(4, 65535, 1)) {
        check_samples::<I28F4, u16, 1>(&t, &rects, &[mode]);
    }

    #[test]
    fn prop_u8x2_f16((t, rects, mode) in arb_case(16, 255, 2)) {
        check_samples::<I16F16, u8, 2>(&t, &rects, &[mode]);
    }

    #[test]
    fn prop_u16_f24((t, rects, mode) in arb_case(24, 65535, 1)) {
        check_samples::<I40F24, u16, 1>(&t, &rects, &[mode]);
    }

    #[test]
    fn prop_levels((t, _, _) in arb_case(8, 65535, 1)) {
        check_levels::<u16, 1>(&t);
    }
}
