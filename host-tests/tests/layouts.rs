//! Every table layout gives the flat table's box sums, bit for bit.
//!
//! * [`Tiled`] (flat packed, one level of tiles, tiles within tiles, non-square mixes): every
//!   corner value and every integer box of small textures (`1 x 1`, `1 x N`, `N x 1`, sizes that
//!   are not multiples of the tile), 1 and 3 channels, `u8`/`u16` texels, `u16`/`u32`/`u64`
//!   values (refused, like the flat table, where the value type cannot hold the worst case),
//!   random and all-maximum texels; the fields read per corner are the non-zero digit pairs;
//! * fractional corners (`I28F4`, `I24F8`), both forms, every boundary mode, boxes far outside
//!   and across many periods (proptest): equal to the flat table and to the exact reference;
//! * [`Modular`] and the tiled+modular combination: exact within the bound, and every box
//!   beyond it refused with `TooWide { what: ModularBox, .. }` (exhaustive for integer corners;
//!   the stated rule for fractional corners: `m * cells_x * cells_y < 2^k`, plus `2F` bits for
//!   Paper; boxes crossing the edge under clamp, repeat and mirror are split into in-range
//!   pieces and need nothing extra in Stable);
//!   `k = 16` for boxes up to 257 cells on a 300 x 200 texture;
//! * the streaming builders against `build` (words bit for bit), and their typed refusals;
//! * the all-255 `u8` texture at 4104 x 4104, the largest square whose worst case fits `u32`, in
//!   tiles 8 x 8 and modular `k = 16`; 4105 x 4105 refused;
//! * costs: 4 fields per corner for tiles 8 x 8, 1 for packed and modular; the targets
//!   for bits per entry at 2048 x 2048.

use std::sync::Mutex;

use fixed::types::{I24F8, I28F4};
use proptest::prelude::*;
use texsat::layouts::{
    modulus_bits_for, AxisLevels, Modular, ModularBuilder, Tiled, TiledBuilder, TiledSpec,
};
use texsat::width::{bits_of, entry_bits_worst_case};
use texsat::{
    Border, BoxLookup, BoxSum, ClampToEdge, Coord, Counter, Entry, Error, Layout, MirroredRepeat,
    NoCount, Paper, Quantity, Rect, Repeat, Sat, Shortcut, ShortcutMean, Stable, Tally, Texture,
    Wide,
};
use texsat_host_tests::strategies::{arb_form, arb_interval, arb_mode, arb_texture};
use texsat_host_tests::{build_sat, rect_from_raw, RefForm, RefMode, RefTexel, RefTexture, RngExt};

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// Serialises the tests that allocate tens of megabytes.
static BIG: Mutex<()> = Mutex::new(());

fn big_lock() -> std::sync::MutexGuard<'static, ()> {
    BIG.lock().unwrap_or_else(|e| e.into_inner())
}

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        ..ProptestConfig::default()
    }
}

/// The specs every exact-layout test runs.
fn specs() -> Vec<(&'static str, TiledSpec)> {
    vec![
        ("flat packed", TiledSpec::FLAT_PACKED),
        ("tiles 3x5", TiledSpec::tiles(3, 5).unwrap()),
        ("tiles 4x4", TiledSpec::tiles(4, 4).unwrap()),
        ("tiles 8x2", TiledSpec::tiles(8, 2).unwrap()),
        ("2 in 4", TiledSpec::square(&[2, 4]).unwrap()),
        ("2 in 6 in 12", TiledSpec::square(&[2, 6, 12]).unwrap()),
        (
            "2 in 4 in 8 in 16",
            TiledSpec::square(&[2, 4, 8, 16]).unwrap(),
        ),
        (
            "x 4, y 2 in 6",
            TiledSpec {
                x: AxisLevels::new(&[4]).unwrap(),
                y: AxisLevels::new(&[2, 6]).unwrap(),
                modulus: None,
            },
        ),
        (
            "x 3, y flat",
            TiledSpec {
                x: AxisLevels::new(&[3]).unwrap(),
                y: AxisLevels::FLAT,
                modulus: None,
            },
        ),
    ]
}

/// Builds `spec` over `tex` (texels as `T`) with [`Tiled::build`] and returns the words.
fn tiled_words<T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
    spec: TiledSpec,
) -> Result<Vec<u32>, Error> {
    let texels = tex.texels_as::<T>();
    let t = Texture::<T, C>::new(&texels, tex.width, tex.height)?;
    let mut words = vec![0u32; Tiled::<E, C>::words_needed(spec, tex.width, tex.height, T::BITS)?];
    let mut scratch = vec![E::ZERO; Tiled::<E, C>::scratch_needed(spec, tex.width)?];
    Tiled::<E, C>::build(&t, spec, &mut words, &mut scratch)?;
    Ok(words)
}

/// Builds the modular layout of `tex` at `k` bits with [`Modular::build`] and returns the words.
fn modular_words<T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
    k: u32,
) -> Result<Vec<u32>, Error> {
    let texels = tex.texels_as::<T>();
    let t = Texture::<T, C>::new(&texels, tex.width, tex.height)?;
    let mut words = vec![0u32; Modular::<E, C>::words_needed(tex.width, tex.height, k)?];
    let mut row = vec![E::ZERO; tex.width * C];
    Modular::<E, C>::build(&t, k, &mut words, &mut row)?;
    Ok(words)
}

/// Mixed-radix digits of `x` for the block sizes `blocks` (independent of texsat): `d_p =
/// (x mod b_{p+1}) / b_p`, the top digit `x / b_L`. Returns how many are non-zero.
fn nonzero_digits(blocks: &[u32], x: usize) -> u64 {
    let mut b = 1usize;
    let mut n = 0;
    for p in 0..=blocks.len() {
        let d = match blocks.get(p) {
            Some(&nb) => (x % nb as usize) / b,
            None => x / b,
        };
        n += (d != 0) as u64;
        if let Some(&nb) = blocks.get(p) {
            b = nb as usize;
        }
    }
    n
}

/// [`BoxLookup::box_sum_int`] under a run-time mode, for any layout.
fn lsum_int<L: BoxLookup<C>, const C: usize, K: Counter>(
    l: &L,
    r: [i32; 4],
    mode: RefMode,
    k: &mut K,
) -> Result<BoxSum<u128, C>, Error> {
    let r = Rect::new(r[0], r[1], r[2], r[3]);
    match mode {
        RefMode::Border => l.box_sum_int(&r, Border, k),
        RefMode::Clamp => l.box_sum_int(&r, ClampToEdge, k),
        RefMode::Repeat => l.box_sum_int(&r, Repeat, k),
        RefMode::Mirror => l.box_sum_int(&r, MirroredRepeat, k),
    }
    .map(|s| s.to_u128())
}

/// [`BoxLookup::box_sum`] under a run-time form and mode, for any layout.
fn lsum<L: BoxLookup<C>, X: Coord, const C: usize, K: Counter>(
    l: &L,
    r: &Rect<X>,
    form: RefForm,
    mode: RefMode,
    k: &mut K,
) -> Result<BoxSum<u128, C>, Error> {
    macro_rules! go {
        ($form:expr) => {
            match mode {
                RefMode::Border => l.box_sum(r, $form, Border, k),
                RefMode::Clamp => l.box_sum(r, $form, ClampToEdge, k),
                RefMode::Repeat => l.box_sum(r, $form, Repeat, k),
                RefMode::Mirror => l.box_sum(r, $form, MirroredRepeat, k),
            }
            .map(|s| s.to_u128())
        };
    }
    match form {
        RefForm::Paper => go!(Paper),
        RefForm::Stable => go!(Stable),
    }
}

/// [`BoxLookup::box_mean_shortcut`] under a run-time form and mode, for any layout.
fn lmean_shortcut<L: BoxLookup<C>, X: Coord, const C: usize>(
    l: &L,
    r: &Rect<X>,
    form: RefForm,
    mode: RefMode,
    s: &Shortcut,
    g: u32,
) -> Result<ShortcutMean<u128, C>, Error> {
    let k = &mut NoCount;
    macro_rules! go {
        ($form:expr) => {
            match mode {
                RefMode::Border => l.box_mean_shortcut(r, $form, Border, s, g, k),
                RefMode::Clamp => l.box_mean_shortcut(r, $form, ClampToEdge, s, g, k),
                RefMode::Repeat => l.box_mean_shortcut(r, $form, Repeat, s, g, k),
                RefMode::Mirror => l.box_mean_shortcut(r, $form, MirroredRepeat, s, g, k),
            }
            .map(|s| s.to_u128())
        };
    }
    match form {
        RefForm::Paper => go!(Paper),
        RefForm::Stable => go!(Stable),
    }
}

/// Corner values of a layout as `u128` (residues for a modular layout).
fn corner128<L: Layout<C>, const C: usize, K: Counter>(
    l: &L,
    x: usize,
    y: usize,
    k: &mut K,
) -> [u128; C] {
    l.corner(x, y, k).map(|v| v.to_u128())
}

/// Every integer box inside the texture, Border: the layout's result equals the flat table's.
/// Returns the number of boxes.
fn every_int_box_equal<L: BoxLookup<C>, E: Entry, const C: usize>(
    l: &L,
    flat: &Sat<'_, E, C>,
    what: &str,
) -> usize {
    let (w, h) = (flat.width() as i32, flat.height() as i32);
    let mut n = 0;
    for y0 in 0..=h {
        for y1 in y0..=h {
            for x0 in 0..=w {
                for x1 in x0..=w {
                    let r = [x0, y0, x1, y1];
                    let want = lsum_int(flat, r, RefMode::Border, &mut NoCount).unwrap();
                    let got = lsum_int(l, r, RefMode::Border, &mut NoCount);
                    assert_eq!(got, Ok(want), "{what}: box {r:?}");
                    n += 1;
                }
            }
        }
    }
    n
}

// ---------------------------------------------------------------------------------------------
// Tiled: exhaustive, integer corners
// ---------------------------------------------------------------------------------------------

/// Every spec over `tex`: the value type refuses exactly when the worst case does not fit (as the
/// flat table does); otherwise every corner value, the fields read per corner, and every integer
/// box equal the flat table's.
fn exhaustive_tiled<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture) -> usize {
    let (w, h) = (tex.width, tex.height);
    let mut fst = vec![0u64; w * h * C];
    let flat = build_sat::<T, u64, C>(tex, &mut fst).unwrap();
    let worst = entry_bits_worst_case(T::BITS, w, h);
    let fits = worst <= E::BITS;
    // The flat table in E refuses exactly when the tiled layouts do.
    let mut est = vec![E::ZERO; w * h * C];
    assert_eq!(build_sat::<T, E, C>(tex, &mut est).is_ok(), fits);
    let mut boxes = 0;
    for (name, spec) in specs() {
        let what = format!("{name} {w}x{h} C={C} u{}->u{}", T::BITS, E::BITS);
        let words = match tiled_words::<T, E, C>(tex, spec) {
            Ok(words) => {
                assert!(
                    fits,
                    "{what}: accepted a value type narrower than the worst case"
                );
                words
            }
            Err(e) => {
                assert!(!fits, "{what}: {e}");
                assert_eq!(
                    e,
                    Error::TooWide {
                        what: Quantity::Entry,
                        bits_needed: worst,
                        bits_available: E::BITS
                    },
                    "{what}"
                );
                continue;
            }
        };
        let l = Tiled::<E, C>::from_words(&words, spec, w, h, T::BITS).unwrap();
        assert_eq!((l.width(), l.height(), l.texel_bits()), (w, h, T::BITS));
        assert_eq!(l.value_bits(), worst, "{what}");
        assert_eq!(l.modulus(), None);
        assert_eq!(l.spec(), spec);
        assert_eq!(words.len() as u64, l.storage_bits().div_ceil(32), "{what}");
        assert_eq!(
            l.max_fields_per_corner(),
            (spec.x.components() * spec.y.components()),
            "{what}"
        );
        for y in 0..=h {
            for x in 0..=w {
                let mut k = Tally::new();
                let got = corner128(&l, x, y, &mut k);
                let want = flat.corner(x, y).unwrap().map(|v| v as u128);
                assert_eq!(got, want, "{what}: corner ({x}, {y})");
                let fields =
                    nonzero_digits(spec.x.blocks(), x) * nonzero_digits(spec.y.blocks(), y);
                assert_eq!(k.reads, fields, "{what}: fields read at ({x}, {y})");
                // A read of C fields of at most 64 bits touches at most ceil((31 + 64 C) / 32) words.
                let per_read = (31 + 64 * C as u64).div_ceil(32);
                assert!(
                    k.words >= k.reads && k.words <= per_read * k.reads,
                    "{what}: {k:?}"
                );
                assert_eq!(k.adds, fields.saturating_sub(1) * C as u64, "{what}: {k:?}");
            }
        }
        boxes += every_int_box_equal(&l, &flat, &what);
    }
    boxes
}

fn exhaustive_sizes<T: RefTexel, E: Entry, const C: usize>(sizes: &[(usize, usize)], seed: u64) {
    let max = ((1u64 << T::BITS) - 1) as u32;
    let mut boxes = 0;
    for (n, &(w, h)) in sizes.iter().enumerate() {
        boxes += exhaustive_tiled::<T, E, C>(&RefTexture::random(w, h, C, max, seed + n as u64));
        boxes += exhaustive_tiled::<T, E, C>(&RefTexture::constant(w, h, C, max));
    }
    assert!(boxes > 0);
}

#[test]
fn tiled_every_box_u8_u32_c1() {
    exhaustive_sizes::<u8, u32, 1>(
        &[
            (1, 1),
            (1, 13),
            (13, 1),
            (13, 7),
            (7, 13),
            (16, 16),
            (17, 11),
            (25, 4),
        ],
        100,
    );
}

#[test]
fn tiled_every_box_u8_u64_c3() {
    exhaustive_sizes::<u8, u64, 3>(&[(1, 9), (9, 1), (13, 7), (12, 12)], 200);
}

#[test]
fn tiled_every_box_u8_u16_c1() {
    // 255 * w * h < 2^16 up to 257 texels: 16 x 16 and 17 x 15 fit, 17 x 16 does not.
    exhaustive_sizes::<u8, u16, 1>(
        &[(1, 13), (13, 7), (16, 16), (17, 15), (17, 16), (30, 9)],
        300,
    );
}

#[test]
fn tiled_every_box_u16_u32_c1() {
    exhaustive_sizes::<u16, u32, 1>(&[(1, 11), (11, 1), (13, 7), (16, 16)], 400);
}

#[test]
fn tiled_every_box_u16_u64_c3() {
    exhaustive_sizes::<u16, u64, 3>(&[(1, 1), (5, 9), (13, 7)], 500);
}

#[test]
fn tiled_u16_texels_u16_values() {
    // Only a single 16-bit texel fits 16-bit values.
    exhaustive_sizes::<u16, u16, 1>(&[(1, 1), (1, 2), (3, 3)], 600);
}

#[test]
fn tiled_refuses_invalid_specs() {
    assert_eq!(AxisLevels::new(&[1]), Err(Error::InvalidLevels));
    assert_eq!(AxisLevels::new(&[4, 6]), Err(Error::InvalidLevels));
    assert_eq!(AxisLevels::new(&[4, 4]), Err(Error::InvalidLevels));
    assert_eq!(AxisLevels::new(&[8, 4]), Err(Error::InvalidLevels));
    assert_eq!(
        AxisLevels::new(&[2, 4, 8, 16, 32]),
        Err(Error::InvalidLevels)
    );
    assert_eq!(TiledSpec::tiles(0, 4), Err(Error::InvalidLevels));
    assert_eq!(TiledSpec::square(&[3, 4]), Err(Error::InvalidLevels));
    assert_eq!(AxisLevels::new(&[]), Ok(AxisLevels::FLAT));
    assert_eq!(TiledSpec::square(&[]), Ok(TiledSpec::FLAT_PACKED));
    let spec = TiledSpec::tiles(4, 4).unwrap();
    assert_eq!(
        Tiled::<u32>::words_needed(spec, 0, 4, 8),
        Err(Error::EmptyTexture)
    );
    assert_eq!(
        Tiled::<u32>::words_needed(spec, 4, 4, 0),
        Err(Error::InvalidTexelBits { bits: 0 })
    );
    assert_eq!(
        Tiled::<u32>::words_needed(spec, 4, 4, 17),
        Err(Error::InvalidTexelBits { bits: 17 })
    );
    // A modulus below the texel width, or wider than the value type.
    assert_eq!(
        Tiled::<u32>::words_needed(spec.with_modulus(7), 4, 4, 8),
        Err(Error::InvalidModulus { bits: 7 })
    );
    assert_eq!(
        Tiled::<u16>::from_words(&[0; 64], spec.with_modulus(17), 4, 4, 8).unwrap_err(),
        Error::InvalidModulus { bits: 17 }
    );
}

/// Every stored bit is read: flipping any one bit of the fields changes some corner value, and
/// flipping a padding bit after the last field changes none. So the comparisons above see every
/// bit of a layout (a corrupted or misplaced field cannot hide).
#[test]
fn tiled_every_stored_bit_is_read() {
    let tex = RefTexture::random(13, 7, 1, 255, 31);
    let (w, h) = (13usize, 7usize);
    let mut fst = vec![0u64; w * h];
    let flat = build_sat::<u8, u64, 1>(&tex, &mut fst).unwrap();
    for (name, spec) in specs() {
        let words = tiled_words::<u8, u32, 1>(&tex, spec).unwrap();
        let bits = Tiled::<u32>::from_words(&words, spec, w, h, 8)
            .unwrap()
            .storage_bits();
        for bit in 0..words.len() as u64 * 32 {
            let mut bad = words.clone();
            bad[(bit / 32) as usize] ^= 1 << (bit % 32);
            let l = Tiled::<u32>::from_words(&bad, spec, w, h, 8).unwrap();
            let differs = (0..=h).any(|y| {
                (0..=w).any(|x| {
                    l.corner(x, y, &mut NoCount)[0] as u64 != flat.corner(x, y).unwrap()[0]
                })
            });
            assert_eq!(differs, bit < bits, "{name}: bit {bit} of {bits}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tiled: fractional corners, every mode (proptest)
// ---------------------------------------------------------------------------------------------

/// Raw boxes at `F = f` for a `w x h` texture: near and far (up to `far` periods).
fn arb_raw_boxes(w: usize, h: usize, f: u32, far: i64) -> impl Strategy<Value = Vec<[i64; 4]>> {
    let (lo, hi) = (i32::MIN as i64, i32::MAX as i64);
    prop::collection::vec(
        (
            arb_interval(w, f, far, lo, hi),
            arb_interval(h, f, far, lo, hi),
        )
            .prop_map(|((x0, x1), (y0, y1))| [x0, y0, x1, y1]),
        1..5,
    )
}

type FracCase = (RefTexture, Vec<[i64; 4]>, Vec<[i64; 4]>, Vec<[i32; 4]>);

/// A texture with boxes at `F = 4`, `F = 8` and integer corners.
fn arb_frac_case(
    max_w: usize,
    max_h: usize,
    ch: usize,
    max: u32,
) -> impl Strategy<Value = FracCase> {
    arb_texture(max_w, max_h, ch, max).prop_flat_map(|t| {
        let (w, h) = (t.width, t.height);
        (
            Just(t),
            arb_raw_boxes(w, h, 4, 10_000),
            arb_raw_boxes(w, h, 8, 10_000),
            arb_raw_boxes(w, h, 0, 1_000_000)
                .prop_map(|v| v.into_iter().map(|b| b.map(|c| c as i32)).collect()),
        )
    })
}

/// Every box of the case in every mode and form (and the shortcut) on every spec: equal to the
/// flat table, which equals the exact reference.
fn check_frac<T: RefTexel, E: Entry, const C: usize>(case: &FracCase) -> Result<(), TestCaseError> {
    let (tex, b4, b8, bi) = case;
    let mut fst = vec![0u64; tex.width * tex.height * C];
    let flat = build_sat::<T, u64, C>(tex, &mut fst).unwrap();
    let layouts: Vec<(&str, TiledSpec, Vec<u32>)> = specs()
        .into_iter()
        .map(|(n, s)| (n, s, tiled_words::<T, E, C>(tex, s).unwrap()))
        .collect();
    let shortcut = Shortcut::with_min_side(3);
    for mode in RefMode::ALL {
        for b in bi {
            let want = lsum_int(&flat, *b, mode, &mut NoCount);
            if let Ok(s) = &want {
                let exact = tex.exact_integrals(mode, b.map(|v| v as i64), 0);
                prop_assert_eq!(s.scaled_sums().to_vec(), exact, "flat {:?} {:?}", mode, b);
            }
            for (name, spec, words) in &layouts {
                let l = Tiled::<E, C>::from_words(words, *spec, tex.width, tex.height, T::BITS)
                    .unwrap();
                let got = lsum_int(&l, *b, mode, &mut NoCount);
                prop_assert_eq!(got, want, "{} {:?} {:?}", name, mode, b);
            }
        }
        for form in RefForm::ALL {
            macro_rules! fixed_boxes {
                ($x:ty, $boxes:expr, $f:expr) => {
                    for b in $boxes {
                        let r = rect_from_raw::<$x>(*b);
                        let want = lsum(&flat, &r, form, mode, &mut NoCount);
                        let exact = tex.exact_integrals(mode, *b, $f);
                        prop_assert_eq!(
                            want.map(|s| s.scaled_sums().to_vec()),
                            Ok(exact),
                            "flat {:?} {:?} {:?}",
                            form,
                            mode,
                            b
                        );
                        let want_mean = lmean_shortcut(&flat, &r, form, mode, &shortcut, 6);
                        for (name, spec, words) in &layouts {
                            let l = Tiled::<E, C>::from_words(
                                words,
                                *spec,
                                tex.width,
                                tex.height,
                                T::BITS,
                            )
                            .unwrap();
                            let got = lsum(&l, &r, form, mode, &mut NoCount);
                            prop_assert_eq!(got, want, "{} {:?} {:?} {:?}", name, form, mode, b);
                            let got_mean = lmean_shortcut(&l, &r, form, mode, &shortcut, 6);
                            prop_assert_eq!(got_mean, want_mean, "{} shortcut {:?}", name, b);
                        }
                    }
                };
            }
            fixed_boxes!(I28F4, b4, 4);
            fixed_boxes!(I24F8, b8, 8);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(64))]

    #[test]
    fn tiled_fractional_u8_u32_c1(case in arb_frac_case(14, 11, 1, 255)) {
        check_frac::<u8, u32, 1>(&case)?;
    }

    #[test]
    fn tiled_fractional_u16_u64_c3(case in arb_frac_case(9, 7, 3, 65535)) {
        check_frac::<u16, u64, 3>(&case)?;
    }
}

// ---------------------------------------------------------------------------------------------
// Modular and tiled+modular
// ---------------------------------------------------------------------------------------------

/// What the stated rule says a modular layout does with the raw box `b` at `F = f`: `Ok(())`
/// (answer exactly) or the refusal. Bound: `m * cells_x * cells_y` with `cells = ceil(hi) -
/// floor(lo)` of the box (clipped to the texture under Border), plus `2F` bits for Paper (in
/// every mode; a box crossing the edge needs nothing extra in Stable).
fn modular_rule(
    mode: RefMode,
    paper: bool,
    b: [i64; 4],
    (w, h): (usize, usize),
    f: u32,
    texel_bits: u32,
    k: u32,
) -> Result<(), Error> {
    let [x0, y0, x1, y1] = b.map(|v| v as i128);
    if x1 == x0 || y1 == y0 {
        return Ok(());
    }
    let s = 1i128 << f;
    let cells = |lo: i128, hi: i128| ((hi + s - 1).div_euclid(s) - lo.div_euclid(s)) as u128;
    let (cx, cy) = if mode == RefMode::Border {
        let clip = |lo: i128, hi: i128, n: usize| {
            let end = (n as i128) << f;
            (lo.clamp(0, end), hi.clamp(0, end))
        };
        let ((a, b_), (c, d)) = (clip(x0, x1, w), clip(y0, y1, h));
        if a >= b_ || c >= d {
            return Ok(()); // nothing left: sum 0
        }
        (cells(a, b_), cells(c, d))
    } else {
        (cells(x0, x1), cells(y0, y1))
    };
    // Paper's corner values are only known modulo 2^k: it needs 2F bits above the box's. Stable
    // needs none, also for a box that crosses the texture's edge under clamp, repeat or mirror:
    // such a box is split into in-range pieces each summing to at most the box (src/edge.rs).
    // (The removed weighted path needed 2F bits there too; the rule changed with it.)
    let headroom = if paper { 2 * f } else { 0 };
    let m = (1u128 << texel_bits) - 1;
    let needed = bits_of(m.saturating_mul(cx.saturating_mul(cy))) + headroom;
    if needed > k {
        Err(Error::TooWide {
            what: Quantity::ModularBox,
            bits_needed: needed,
            bits_available: k,
        })
    } else {
        Ok(())
    }
}

/// Every integer box of a small texture, inside and up to one texture size outside, every mode:
/// the modular layout (and tiled+modular layouts) answer exactly what the rule admits, and
/// refuse the rest with `ModularBox`.
fn exhaustive_modular<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture, k: u32) -> usize {
    let (w, h) = (tex.width, tex.height);
    let mut fst = vec![0u64; w * h * C];
    let flat = build_sat::<T, u64, C>(tex, &mut fst).unwrap();
    let mw = modular_words::<T, E, C>(tex, k).unwrap();
    let m = Modular::<E, C>::from_words(&mw, w, h, T::BITS, k).unwrap();
    assert_eq!(m.value_bits(), k);
    assert_eq!(m.modulus(), Some(k));
    assert_eq!(m.bits_per_entry(), k as f64);
    assert_eq!(
        u128::from(m.max_exact_area()),
        ((1u128 << k) - 1) / ((1u128 << T::BITS) - 1)
    );
    let tw_a =
        tiled_words::<T, E, C>(tex, TiledSpec::tiles(4, 4).unwrap().with_modulus(k)).unwrap();
    let ta = Tiled::<E, C>::from_words(
        &tw_a,
        TiledSpec::tiles(4, 4).unwrap().with_modulus(k),
        w,
        h,
        T::BITS,
    )
    .unwrap();
    let spec_b = TiledSpec {
        x: AxisLevels::new(&[2, 6]).unwrap(),
        y: AxisLevels::new(&[3]).unwrap(),
        modulus: Some(k),
    };
    let tw_b = tiled_words::<T, E, C>(tex, spec_b).unwrap();
    let tb = Tiled::<E, C>::from_words(&tw_b, spec_b, w, h, T::BITS).unwrap();
    assert_eq!((ta.modulus(), ta.value_bits()), (Some(k), k));
    // Corner values are S mod 2^k.
    let mask = (1u128 << k) - 1;
    for y in 0..=h {
        for x in 0..=w {
            let want = flat.corner(x, y).unwrap().map(|v| v as u128 & mask);
            assert_eq!(
                corner128(&m, x, y, &mut NoCount),
                want,
                "modular k={k} ({x},{y})"
            );
            assert_eq!(
                corner128(&ta, x, y, &mut NoCount),
                want,
                "tiles k={k} ({x},{y})"
            );
            assert_eq!(
                corner128(&tb, x, y, &mut NoCount),
                want,
                "mixed k={k} ({x},{y})"
            );
        }
    }
    let (wi, hi) = (w as i32, h as i32);
    let mut n = 0;
    for mode in RefMode::ALL {
        for y0 in -hi..=2 * hi {
            for y1 in y0..=2 * hi {
                for x0 in -wi..=2 * wi {
                    for x1 in x0..=2 * wi {
                        let b = [x0, y0, x1, y1];
                        let rule =
                            modular_rule(mode, false, b.map(|v| v as i64), (w, h), 0, T::BITS, k);
                        let want = rule.and_then(|()| lsum_int(&flat, b, mode, &mut NoCount));
                        if rule.is_ok() {
                            assert!(want.is_ok(), "{mode:?} {b:?}");
                        }
                        for (name, got) in [
                            ("modular", lsum_int(&m, b, mode, &mut NoCount)),
                            ("tiles 4x4 mod", lsum_int(&ta, b, mode, &mut NoCount)),
                            ("x 2 in 6 y 3 mod", lsum_int(&tb, b, mode, &mut NoCount)),
                        ] {
                            assert_eq!(got, want, "{name} k={k} {mode:?} {b:?}");
                        }
                        n += 1;
                    }
                }
            }
        }
    }
    n
}

#[test]
fn modular_every_int_box_u8() {
    for (w, h, seed) in [(5usize, 4usize, 1u64), (1, 9, 2), (9, 1, 3)] {
        for tex in [
            RefTexture::random(w, h, 1, 255, seed),
            RefTexture::constant(w, h, 1, 255),
        ] {
            for k in [8, 9, 11, 12, 16] {
                exhaustive_modular::<u8, u32, 1>(&tex, k);
            }
            // u16 values suffice for k <= 16 whatever the texture size.
            exhaustive_modular::<u8, u16, 1>(&tex, 12);
        }
    }
}

#[test]
fn modular_every_int_box_u16_c3() {
    let tex = RefTexture::random(5, 4, 3, 65535, 9);
    for k in [16, 19, 21] {
        exhaustive_modular::<u16, u32, 3>(&tex, k);
    }
    exhaustive_modular::<u16, u64, 3>(&RefTexture::constant(5, 4, 3, 65535), 20);
}

/// The tiled+modular combination with `u16` values on a texture whose total needs 17 bits
/// (so exact tiled `u16` layouts and flat `u16` tables are refused): every integer box inside,
/// exact within the bound, refused beyond.
#[test]
fn tiled_modular_u16_every_box() {
    let (w, h) = (20usize, 18usize);
    for tex in [
        RefTexture::random(w, h, 1, 255, 77),
        RefTexture::constant(w, h, 1, 255),
    ] {
        let mut fst = vec![0u32; w * h];
        let flat = build_sat::<u8, u32, 1>(&tex, &mut fst).unwrap();
        let mut st16 = vec![0u16; w * h];
        assert!(build_sat::<u8, u16, 1>(&tex, &mut st16).is_err());
        assert_eq!(
            tiled_words::<u8, u16, 1>(&tex, TiledSpec::tiles(4, 4).unwrap()),
            Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: 17,
                bits_available: 16
            })
        );
        for k in [9, 13, 16] {
            for (name, spec) in [
                ("tiles 4x4", TiledSpec::tiles(4, 4).unwrap()),
                ("2 in 6", TiledSpec::square(&[2, 6]).unwrap()),
                ("flat packed", TiledSpec::FLAT_PACKED),
                (
                    "x 5, y 3 in 9",
                    TiledSpec {
                        x: AxisLevels::new(&[5]).unwrap(),
                        y: AxisLevels::new(&[3, 9]).unwrap(),
                        modulus: None,
                    },
                ),
            ] {
                let spec = spec.with_modulus(k);
                let words = tiled_words::<u8, u16, 1>(&tex, spec).unwrap();
                let l = Tiled::<u16>::from_words(&words, spec, w, h, 8).unwrap();
                // Every field at most k bits.
                for p in 0..spec.x.components() {
                    for q in 0..spec.y.components() {
                        assert!(l.field_bits(p, q).unwrap() <= k);
                    }
                }
                assert!(
                    l.bits_per_entry() <= k as f64,
                    "{name} {}",
                    l.bits_per_entry()
                );
                let (mut exact, mut refused) = (0, 0);
                for y0 in 0..=h as i32 {
                    for y1 in y0..=h as i32 {
                        for x0 in 0..=w as i32 {
                            for x1 in x0..=w as i32 {
                                let b = [x0, y0, x1, y1];
                                let area = ((x1 - x0) * (y1 - y0)) as u128;
                                let got = lsum_int(&l, b, RefMode::Border, &mut NoCount);
                                if 255 * area < 1 << k {
                                    let want = lsum_int(&flat, b, RefMode::Border, &mut NoCount);
                                    assert_eq!(got, want, "{name} k={k} {b:?}");
                                    exact += 1;
                                } else {
                                    assert_eq!(
                                        got,
                                        Err(Error::TooWide {
                                            what: Quantity::ModularBox,
                                            bits_needed: bits_of(255 * area),
                                            bits_available: k
                                        }),
                                        "{name} k={k} {b:?}"
                                    );
                                    refused += 1;
                                }
                            }
                        }
                    }
                }
                assert!(exact > 0 && refused > 0);
            }
        }
    }
}

/// A small box near or inside the texture: side up to 3 texels.
fn arb_small_interval(n: usize, f: u32) -> impl Strategy<Value = (i64, i64)> {
    let end = (n as i64) << f;
    (-end..=2 * end, 0..=(3i64 << f)).prop_map(|(lo, len)| (lo, lo + len))
}

fn arb_interval_mix(n: usize, f: u32) -> impl Strategy<Value = (i64, i64)> {
    prop_oneof![
        2 => arb_small_interval(n, f),
        1 => arb_interval(n, f, 1000, i32::MIN as i64, i32::MAX as i64),
    ]
}

type ModCase = (
    RefTexture,
    u32,
    Vec<([i64; 4], RefMode, RefForm)>,
    Vec<([i64; 4], RefMode, RefForm)>,
);

fn arb_mod_case() -> impl Strategy<Value = ModCase> {
    (arb_texture(10, 8, 1, 255), 8u32..=32).prop_flat_map(|(t, k)| {
        let (w, h) = (t.width, t.height);
        let bx = move |f: u32| {
            prop::collection::vec(
                (
                    arb_interval_mix(w, f),
                    arb_interval_mix(h, f),
                    arb_mode(),
                    arb_form(),
                )
                    .prop_map(|((x0, x1), (y0, y1), m, fm)| ([x0, y0, x1, y1], m, fm)),
                1..8,
            )
        };
        (Just(t), Just(k), bx(4), bx(8))
    })
}

fn check_mod_case(case: &ModCase) -> Result<(), TestCaseError> {
    let (tex, k, b4, b8) = case;
    let (w, h, k) = (tex.width, tex.height, *k);
    let mut fst = vec![0u64; w * h];
    let flat = build_sat::<u8, u64, 1>(tex, &mut fst).unwrap();
    let mw = modular_words::<u8, u32, 1>(tex, k).unwrap();
    let m = Modular::<u32>::from_words(&mw, w, h, 8, k).unwrap();
    let spec = TiledSpec::tiles(3, 3).unwrap().with_modulus(k);
    let tw = tiled_words::<u8, u32, 1>(tex, spec).unwrap();
    let t = Tiled::<u32>::from_words(&tw, spec, w, h, 8).unwrap();
    macro_rules! run {
        ($x:ty, $boxes:expr, $f:expr) => {
            for &(b, mode, form) in $boxes {
                let r = rect_from_raw::<$x>(b);
                let rule = modular_rule(mode, form == RefForm::Paper, b, (w, h), $f, 8, k);
                let want = rule.and_then(|()| lsum(&flat, &r, form, mode, &mut NoCount));
                if rule.is_ok() {
                    prop_assert!(want.is_ok(), "flat refused {:?}", b);
                }
                prop_assert_eq!(
                    lsum(&m, &r, form, mode, &mut NoCount),
                    want,
                    "modular k={} {:?} {:?} {:?}",
                    k,
                    form,
                    mode,
                    b
                );
                prop_assert_eq!(
                    lsum(&t, &r, form, mode, &mut NoCount),
                    want,
                    "tiles 3x3 mod k={} {:?} {:?} {:?}",
                    k,
                    form,
                    mode,
                    b
                );
            }
        };
    }
    run!(I28F4, b4, 4);
    run!(I24F8, b8, 8);
    Ok(())
}

proptest! {
    #![proptest_config(config(128))]

    #[test]
    fn modular_fractional_rule(case in arb_mod_case()) {
        check_mod_case(&case)?;
    }
}

/// The fractional rule by hand: `k = 16`, 8-bit texels. Stable: exact iff `255 cells < 2^16`
/// (up to 257 cells); Paper needs `2F` more bits: at `F = 4` one cell (`8 + 8 = 16`), at
/// `F = 8` none.
#[test]
fn modular_fractional_rule_by_hand() {
    let tex = RefTexture::random(40, 30, 1, 255, 5);
    let mut fst = vec![0u64; 40 * 30];
    let flat = build_sat::<u8, u64, 1>(&tex, &mut fst).unwrap();
    let mw = modular_words::<u8, u32, 1>(&tex, 16).unwrap();
    let m = Modular::<u32>::from_words(&mw, 40, 30, 8, 16).unwrap();
    let refused = |needed| {
        Err(Error::TooWide {
            what: Quantity::ModularBox,
            bits_needed: needed,
            bits_available: 16,
        })
    };
    // [2.5, 18.5) x [3.25, 18.25): 17 x 16 = 272 cells: 255 * 272 needs 17 bits.
    let r = Rect::new(
        I24F8::from_num(2.5),
        I24F8::from_num(3.25),
        I24F8::from_num(18.5),
        I24F8::from_num(18.25),
    );
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Border, &mut NoCount)),
        refused(17)
    );
    // [2.5, 17.5) x [3.25, 18.25): 16 x 16 = 256 cells: exact in Stable.
    let r = Rect::new(
        I24F8::from_num(2.5),
        I24F8::from_num(3.25),
        I24F8::from_num(17.5),
        I24F8::from_num(18.25),
    );
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Border, &mut NoCount)),
        u128s(flat.box_sum(&r, Stable, Border, &mut NoCount))
    );
    assert_eq!(
        u128s(m.box_sum(&r, Paper, Border, &mut NoCount)),
        refused(16 + 16)
    );
    // Integer-aligned 257 x 1 cells exact, 258 refused; 16 x 16 at integers is 256 cells.
    let tex = RefTexture::random(300, 2, 1, 255, 6);
    let mut fst = vec![0u64; 600];
    let flat = build_sat::<u8, u64, 1>(&tex, &mut fst).unwrap();
    let mw = modular_words::<u8, u32, 1>(&tex, 16).unwrap();
    let m = Modular::<u32>::from_words(&mw, 300, 2, 8, 16).unwrap();
    let q = |v: f64| I24F8::from_num(v);
    let r = Rect::new(q(10.0), q(0.0), q(267.0), q(1.0));
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Border, &mut NoCount)),
        u128s(flat.box_sum(&r, Stable, Border, &mut NoCount))
    );
    let r = Rect::new(q(10.0), q(0.0), q(267.5), q(1.0));
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Border, &mut NoCount)),
        refused(17)
    );
    // One cell at F = 4: Paper fits exactly (8 + 8 bits); at F = 8 it does not.
    let r4 = Rect::new(
        I28F4::from_num(5.25),
        I28F4::from_num(0.5),
        I28F4::from_num(5.75),
        I28F4::from_num(1.0),
    );
    assert_eq!(
        u128s(m.box_sum(&r4, Paper, Border, &mut NoCount)),
        u128s(flat.box_sum(&r4, Paper, Border, &mut NoCount))
    );
    let r8 = Rect::new(q(5.25), q(0.5), q(5.75), q(1.0));
    assert_eq!(
        u128s(m.box_sum(&r8, Paper, Border, &mut NoCount)),
        refused(24)
    );
    assert_eq!(
        u128s(m.box_sum(&r8, Stable, Border, &mut NoCount)),
        u128s(flat.box_sum(&r8, Stable, Border, &mut NoCount))
    );
    // Under Repeat a box straddling the right edge is split into in-range pieces (src/edge.rs);
    // each piece's sum is at most the box's, so the Stable form needs no bits beyond the box's
    // own: the rule is `m * cells_x * cells_y < 2^k` as for a box inside. (Before the split path
    // these took a weighted path that needed 2F more bits even in Stable and were refused with
    // 9 + 8 and 12 + 8 bits; those expectations no longer hold.)
    // 2 cells (255 * 2 needs 9 bits): exact.
    let r = Rect::new(q4(298.5), q4(0.0), q4(299.5), q4(1.0));
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Repeat, &mut NoCount)),
        u128s(flat.box_sum(&r, Stable, Repeat, &mut NoCount))
    );
    let r = Rect::new(q4(299.5), q4(0.0), q4(300.5), q4(1.0));
    let want = tex.exact_integrals(RefMode::Repeat, raw4(&r), 4);
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Repeat, &mut NoCount)).map(|s| s.scaled_sums().to_vec()),
        Ok(want)
    );
    // 11 cells (255 * 11 needs 12 bits): exact too.
    let r = Rect::new(q4(290.5), q4(0.0), q4(300.5), q4(1.0));
    let want = tex.exact_integrals(RefMode::Repeat, raw4(&r), 4);
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Repeat, &mut NoCount)).map(|s| s.scaled_sums().to_vec()),
        Ok(want)
    );
    // Paper still needs its 2F: 12 + 8 bits > 16 on the same crossing box.
    assert_eq!(
        u128s(m.box_sum(&r, Paper, Repeat, &mut NoCount)),
        refused(12 + 8)
    );
    // Crossing the edge, the bound is still the box's: 1 x 258 cells (255 * 258 >= 2^16) is
    // refused in Stable (17 bits), 257 cells is exact.
    let r = Rect::new(q4(200.5), q4(0.0), q4(457.0), q4(1.0));
    let want = tex.exact_integrals(RefMode::Repeat, raw4(&r), 4);
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Repeat, &mut NoCount)).map(|s| s.scaled_sums().to_vec()),
        Ok(want)
    );
    let r = Rect::new(q4(200.5), q4(0.0), q4(457.5), q4(1.0));
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Repeat, &mut NoCount)),
        refused(17)
    );
    // Shifted by whole periods it is the same box (cells are invariant), in range again.
    let r = Rect::new(q4(-1.5), q4(4.0), q4(-0.5), q4(5.0));
    assert_eq!(
        u128s(m.box_sum(&r, Stable, Repeat, &mut NoCount)),
        u128s(flat.box_sum(&r, Stable, Repeat, &mut NoCount))
    );
}

/// The raw corners of a box as `[x0, y0, x1, y1]`.
fn raw4<X: Coord>(r: &Rect<X>) -> [i64; 4] {
    let r = r.to_raw();
    [r.x0, r.y0, r.x1, r.y1]
}

/// A lookup's result with its sums as `u128` (to compare tables with different result words).
fn u128s<W: Wide, const C: usize>(
    r: Result<BoxSum<W, C>, Error>,
) -> Result<BoxSum<u128, C>, Error> {
    r.map(|s| s.to_u128())
}

fn q4(v: f64) -> I28F4 {
    I28F4::from_num(v)
}

/// `k = 16` (`modulus_bits_for(8, 256)`) on a 300 x 200 random texture: random boxes of at most
/// 257 cells exact (255 * 257 = 2^16 - 1), every larger one refused; the same for the tiled
/// combination with `u16` values.
#[test]
fn modular_k16_boxes_up_to_16x16() {
    let (w, h) = (300usize, 200usize);
    let k = modulus_bits_for(8, 256);
    assert_eq!(k, 16);
    assert_eq!(modulus_bits_for(8, 257), 16);
    assert_eq!(modulus_bits_for(8, 258), 17);
    assert_eq!(Modular::<u32>::bits_for_max_area(8, 256), 16);
    for tex in [
        RefTexture::random(w, h, 1, 255, 16),
        RefTexture::constant(w, h, 1, 255),
    ] {
        let mut fst = vec![0u32; w * h];
        let flat = build_sat::<u8, u32, 1>(&tex, &mut fst).unwrap();
        let mw = modular_words::<u8, u16, 1>(&tex, k).unwrap();
        let m = Modular::<u16>::from_words(&mw, w, h, 8, k).unwrap();
        assert_eq!(m.max_exact_area(), 257);
        let spec = TiledSpec::tiles(4, 4).unwrap().with_modulus(k);
        let tw = tiled_words::<u8, u16, 1>(&tex, spec).unwrap();
        let t = Tiled::<u16>::from_words(&tw, spec, w, h, 8).unwrap();
        assert!(t.bits_per_entry() < 16.0);
        let mut rng = texsat_host_tests::rng(1234);
        let (mut exact, mut refused) = (0, 0);
        for n in 0..4000 {
            // Half the boxes within 257 cells, half larger.
            let (bw, bh) = if n % 2 == 0 {
                let bw = rng.random_range(1..=257);
                (bw, rng.random_range(1..=(257 / bw).min(h as i64)))
            } else {
                let bw = rng.random_range(1..=w as i64);
                let lo = (258 + bw - 1) / bw;
                if lo > h as i64 {
                    continue;
                }
                (bw, rng.random_range(lo..=h as i64))
            };
            let x0 = rng.random_range(0..=w as i64 - bw) as i32;
            let y0 = rng.random_range(0..=h as i64 - bh) as i32;
            let b = [x0, y0, x0 + bw as i32, y0 + bh as i32];
            let area = (bw * bh) as u128;
            for (name, got) in [
                ("modular", lsum_int(&m, b, RefMode::Border, &mut NoCount)),
                ("tiles mod", lsum_int(&t, b, RefMode::Border, &mut NoCount)),
            ] {
                if area <= 257 {
                    assert_eq!(
                        got,
                        lsum_int(&flat, b, RefMode::Border, &mut NoCount),
                        "{name} {b:?}"
                    );
                } else {
                    assert_eq!(
                        got,
                        Err(Error::TooWide {
                            what: Quantity::ModularBox,
                            bits_needed: bits_of(255 * area),
                            bits_available: 16
                        }),
                        "{name} {b:?}"
                    );
                }
            }
            if area <= 257 {
                exact += 1;
            } else {
                refused += 1;
            }
        }
        assert!(exact > 1000 && refused > 1000);
        // The boundary: 257 x 1 and 16 x 16 exact (all-255: 65535 and 65280), 258 x 1 refused.
        for (b, ok) in [
            ([10, 7, 267, 8], true),
            ([100, 50, 116, 66], true),
            ([10, 7, 268, 8], false),
            ([100, 50, 117, 66], false),
        ] {
            let got = m.box_sum_int(&Rect::new(b[0], b[1], b[2], b[3]), Border, &mut NoCount);
            assert_eq!(got.is_ok(), ok, "{b:?}");
            if ok {
                assert_eq!(
                    u128s(got),
                    lsum_int(&flat, b, RefMode::Border, &mut NoCount)
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Streaming builders
// ---------------------------------------------------------------------------------------------

/// `TiledBuilder` fed row by row gives the words of `Tiled::build`, bit for bit; building into
/// dirty storage changes nothing but the padding bits after the last field.
fn check_tiled_stream<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture, spec: TiledSpec) {
    let (w, h) = (tex.width, tex.height);
    let built = tiled_words::<T, E, C>(tex, spec).unwrap();
    let texels = tex.texels_as::<T>();
    let rows: Vec<&[T]> = texels.chunks_exact(w * C).collect();
    for fill in [0u32, 0xA5A5_A5A5, u32::MAX] {
        let mut words = vec![fill; built.len()];
        let mut scratch = vec![E::ZERO; Tiled::<E, C>::scratch_needed(spec, w).unwrap() + 3];
        let storage_bits = {
            let mut b =
                TiledBuilder::<E, C>::new(spec, w, h, T::BITS, &mut words, &mut scratch).unwrap();
            for row in &rows {
                b.push_row(row).unwrap();
            }
            b.finish().unwrap().storage_bits()
        };
        let full = (storage_bits / 32) as usize;
        assert_eq!(words[..full], built[..full], "{spec:?} fill {fill:#x}");
        let rest = (storage_bits % 32) as u32;
        if rest > 0 {
            let mask = (1u32 << rest) - 1;
            assert_eq!(words[full] & mask, built[full] & mask, "{spec:?} last word");
        }
        if fill == 0 {
            assert_eq!(words, built);
        }
    }
}

#[test]
fn tiled_builder_equals_build() {
    for (w, h, seed) in [(13usize, 7usize, 1u64), (1, 9, 2), (9, 1, 3), (24, 17, 4)] {
        let tex = RefTexture::random(w, h, 1, 255, seed);
        let tex3 = RefTexture::random(w, h, 3, 65535, seed);
        for (_, spec) in specs() {
            check_tiled_stream::<u8, u32, 1>(&tex, spec);
            check_tiled_stream::<u16, u64, 3>(&tex3, spec);
            check_tiled_stream::<u8, u16, 1>(&tex, spec.with_modulus(13));
        }
    }
}

#[test]
fn modular_builder_equals_build() {
    for (w, h, seed) in [(13usize, 7usize, 1u64), (1, 9, 2), (9, 1, 3)] {
        let tex = RefTexture::random(w, h, 3, 255, seed);
        for k in [8, 13, 16, 31] {
            let built = modular_words::<u8, u32, 3>(&tex, k).unwrap();
            let texels = tex.texels_as::<u8>();
            let mut words = vec![0u32; built.len()];
            let mut row = vec![0u32; w * 3];
            let mut b = ModularBuilder::<u32, 3>::new(w, h, 8, k, &mut words, &mut row).unwrap();
            for r in texels.chunks_exact(w * 3) {
                b.push_row(r).unwrap();
            }
            let m = b.finish().unwrap();
            assert_eq!(m.storage_bits(), (w * h * 3) as u64 * k as u64);
            assert_eq!(words, built, "k={k}");
        }
    }
}

#[test]
fn tiled_builder_refusals() {
    let (w, h) = (10usize, 6usize);
    let tex = RefTexture::random(w, h, 1, 255, 42);
    let texels = tex.texels_as::<u8>();
    let spec = TiledSpec::square(&[2, 4]).unwrap();
    let need = Tiled::<u32>::words_needed(spec, w, h, 8).unwrap();
    let sneed = Tiled::<u32>::scratch_needed(spec, w).unwrap();
    assert_eq!(sneed, (spec.y.components() + 1) * (w + 1));
    let built = tiled_words::<u8, u32, 1>(&tex, spec).unwrap();

    // Short storage, short scratch.
    let mut words = vec![0u32; need];
    let mut scratch = vec![0u32; sneed];
    assert_eq!(
        TiledBuilder::<u32>::new(spec, w, h, 8, &mut words[..need - 1], &mut scratch).unwrap_err(),
        Error::StorageTooSmall {
            needed: need,
            got: need - 1
        }
    );
    assert_eq!(
        TiledBuilder::<u32>::new(spec, w, h, 8, &mut words, &mut scratch[..sneed - 1]).unwrap_err(),
        Error::StorageTooSmall {
            needed: sneed,
            got: sneed - 1
        }
    );
    assert_eq!(
        Tiled::<u32>::from_words(&built[..need - 1], spec, w, h, 8).unwrap_err(),
        Error::StorageTooSmall {
            needed: need,
            got: need - 1
        }
    );
    // The value type must hold the worst case: 255 * 20 * 20 needs 17 bits, more than u16.
    let mut s16 = vec![0u16; Tiled::<u16>::scratch_needed(spec, 20).unwrap()];
    let mut big = vec![0u32; Tiled::<u16>::words_needed(spec, 20, 20, 8).unwrap()];
    assert_eq!(
        TiledBuilder::<u16>::new(spec, 20, 20, 8, &mut big, &mut s16).unwrap_err(),
        Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 17,
            bits_available: 16
        }
    );
    assert_eq!(
        TiledBuilder::<u32>::new(spec, 0, 5, 8, &mut words, &mut scratch).unwrap_err(),
        Error::EmptyTexture
    );

    // Wrong row length (refused without consuming the row), too many rows, missing rows.
    let mut b = TiledBuilder::<u32>::new(spec, w, h, 8, &mut words, &mut scratch).unwrap();
    assert_eq!(
        b.push_row(&texels[..w - 1]).unwrap_err(),
        Error::RowLength {
            expected: w,
            got: w - 1
        }
    );
    assert_eq!(
        b.push_row(&texels[..w + 1]).unwrap_err(),
        Error::RowLength {
            expected: w,
            got: w + 1
        }
    );
    for r in texels.chunks_exact(w).take(h - 1) {
        b.push_row(r).unwrap();
    }
    assert_eq!(
        b.finish().unwrap_err(),
        Error::MissingRows {
            got: h - 1,
            expected: h
        }
    );

    let mut b = TiledBuilder::<u32>::new(spec, w, h, 8, &mut words, &mut scratch).unwrap();
    assert_eq!(
        b.push_row::<u8>(&[]).unwrap_err(),
        Error::RowLength {
            expected: w,
            got: 0
        }
    );
    for r in texels.chunks_exact(w) {
        b.push_row(r).unwrap();
    }
    assert_eq!(b.push_row(&texels[..w]).unwrap_err(), Error::TooManyRows);
    // The refused rows changed nothing.
    b.finish().unwrap();
    assert_eq!(words, built);

    // Three channels: the row length counts channels.
    let mut words3 = vec![0u32; Tiled::<u32, 3>::words_needed(spec, w, h, 8).unwrap()];
    let mut scratch3 = vec![0u32; Tiled::<u32, 3>::scratch_needed(spec, w).unwrap()];
    let mut b = TiledBuilder::<u32, 3>::new(spec, w, h, 8, &mut words3, &mut scratch3).unwrap();
    assert_eq!(
        b.push_row(&texels[..w]).unwrap_err(),
        Error::RowLength {
            expected: 3 * w,
            got: w
        }
    );
}

#[test]
fn modular_builder_refusals() {
    let (w, h, k) = (10usize, 6usize, 12u32);
    let tex = RefTexture::random(w, h, 1, 255, 43);
    let texels = tex.texels_as::<u8>();
    let need = Modular::<u32>::words_needed(w, h, k).unwrap();
    assert_eq!(need, (w * h * k as usize).div_ceil(32));
    let built = modular_words::<u8, u32, 1>(&tex, k).unwrap();
    let mut words = vec![0u32; need];
    let mut row = vec![0u32; w];
    assert_eq!(
        ModularBuilder::<u32>::new(w, h, 8, k, &mut words[..need - 1], &mut row).unwrap_err(),
        Error::StorageTooSmall {
            needed: need,
            got: need - 1
        }
    );
    assert_eq!(
        ModularBuilder::<u32>::new(w, h, 8, k, &mut words, &mut row[..w - 1]).unwrap_err(),
        Error::StorageTooSmall {
            needed: w,
            got: w - 1
        }
    );
    assert_eq!(
        Modular::<u32>::from_words(&built[..need - 1], w, h, 8, k).unwrap_err(),
        Error::StorageTooSmall {
            needed: need,
            got: need - 1
        }
    );
    for bad in [0, 7, 33] {
        assert_eq!(
            ModularBuilder::<u32>::new(w, h, 8, bad, &mut words, &mut row).unwrap_err(),
            Error::InvalidModulus { bits: bad }
        );
    }
    assert_eq!(
        ModularBuilder::<u16>::new(w, h, 8, 17, &mut words, &mut vec![0u16; w]).unwrap_err(),
        Error::InvalidModulus { bits: 17 }
    );
    assert_eq!(
        ModularBuilder::<u32>::new(w, 0, 8, k, &mut words, &mut row).unwrap_err(),
        Error::EmptyTexture
    );
    let mut b = ModularBuilder::<u32>::new(w, h, 8, k, &mut words, &mut row).unwrap();
    assert_eq!(
        b.push_row(&texels[..w + 2]).unwrap_err(),
        Error::RowLength {
            expected: w,
            got: w + 2
        }
    );
    for r in texels.chunks_exact(w).take(2) {
        b.push_row(r).unwrap();
    }
    assert_eq!(
        b.finish().unwrap_err(),
        Error::MissingRows {
            got: 2,
            expected: h
        }
    );
    let mut b = ModularBuilder::<u32>::new(w, h, 8, k, &mut words, &mut row).unwrap();
    for r in texels.chunks_exact(w) {
        b.push_row(r).unwrap();
    }
    assert_eq!(b.push_row(&texels[..w]).unwrap_err(), Error::TooManyRows);
    b.finish().unwrap();
    assert_eq!(words, built);
    // A texel wider than the declared texel bits.
    let wide: Vec<u16> = vec![300; w];
    let mut b = ModularBuilder::<u32>::new(w, h, 8, k, &mut words, &mut row).unwrap();
    assert_eq!(
        b.push_row(&wide).unwrap_err(),
        Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 9,
            bits_available: 8
        }
    );
}

/// Texels wider than the declared `texel_bits` must be refused by `TiledBuilder` as they are by
/// `ModularBuilder`: the widths of the fields, `value_bits` and (with a modulus) the box bound of
/// the lookups all rest on `m = 2^texel_bits - 1`.
#[test]
fn tiled_builder_refuses_texels_wider_than_declared() {
    let (w, h) = (20usize, 18usize);
    let k = 13;
    let spec = TiledSpec::tiles(4, 4).unwrap().with_modulus(k);
    let mut words = vec![0u32; Tiled::<u16>::words_needed(spec, w, h, 8).unwrap()];
    let mut scratch = vec![0u16; Tiled::<u16>::scratch_needed(spec, w).unwrap()];
    let wide = vec![300u16; w];
    let mut b = TiledBuilder::<u16>::new(spec, w, h, 8, &mut words, &mut scratch).unwrap();
    let first = b.push_row(&wide);
    if first.is_ok() {
        // Show the consequence: build the rest and ask for an admitted box.
        for _ in 1..h {
            b.push_row(&wide).unwrap();
        }
        let l = b.finish().unwrap();
        // 32 cells: 255 * 32 = 8160 < 2^13, so the lookup admits the box; the true sum is
        // 300 * 32 = 9600 >= 2^13.
        let got = l.box_sum_int(&Rect::new(0, 0, 8, 4), Border, &mut NoCount);
        panic!("wide texel accepted; box [0,8)x[0,4) = {got:?}, true sum 9600");
    }
    assert_eq!(
        first.unwrap_err(),
        Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 9,
            bits_available: 8
        }
    );
}

// ---------------------------------------------------------------------------------------------
// Extremes
// ---------------------------------------------------------------------------------------------

/// The largest square `u8` texture whose worst case fits `u32`, all 255: tiles 8 x 8 accepted
/// and exact at the far corner; 4105 x 4105 refused; modular `k = 16` on it.
#[test]
fn extreme_4104_all_255() {
    let _g = big_lock();
    const N: usize = 4104;
    assert_eq!(entry_bits_worst_case(8, N, N), 32);
    assert_eq!(entry_bits_worst_case(8, N + 1, N + 1), 33);
    let spec = TiledSpec::tiles(8, 8).unwrap();
    let texels = vec![255u8; N * N];
    let t = Texture::<u8>::new(&texels, N, N).unwrap();
    let total = 255 * (N as u128) * (N as u128);
    let n = N as i32;
    let e = (N as i64) << 8;
    {
        let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, N, N, 8).unwrap()];
        let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, N).unwrap()];
        let l = Tiled::<u32>::build(&t, spec, &mut words, &mut scratch).unwrap();
        assert_eq!(l.value_bits(), 32);
        assert!(l.bits_per_entry() < 16.5, "{}", l.bits_per_entry());
        assert_eq!(l.corner(N, N, &mut NoCount)[0] as u128, total);
        assert_eq!(
            l.corner(N, N - 1, &mut NoCount)[0] as u128,
            255 * (N * (N - 1)) as u128
        );
        // Integer boxes: 255 * area, under every mode (the texture is constant).
        for (b, area) in [
            ([n - 1, n - 1, n, n], 1u128),
            ([n - 2, n - 3, n, n], 6),
            ([n - 9, n - 17, n - 1, n], 8 * 17),
            ([1, 1, n, n], (N as u128 - 1).pow(2)),
            ([0, 0, n, n], (N * N) as u128),
            ([n - 1, n - 1, n + 1, n + 1], 4),
        ] {
            for mode in RefMode::ALL {
                let s = lsum_int(&l, b, mode, &mut NoCount).unwrap().sum();
                let want = if mode == RefMode::Border && b[2] > n {
                    255
                } else {
                    255 * area
                };
                assert_eq!(s, want, "{mode:?} {b:?}");
            }
        }
        // 1/256-wide boxes at the far corner, F = 8: sums in units of 2^-16.
        for (b, want) in [
            ([e - 1, e - 1, e, e], 255u128),
            ([e - 384, e - 3, e - 64, e], 255 * 320 * 3),
            ([e - 1, 0, e, e], 255 * e as u128),
            ([0, 0, e, e], total << 16),
        ] {
            let r = rect_from_raw::<I24F8>(b);
            for form in RefForm::ALL {
                for mode in RefMode::ALL {
                    let s = lsum(&l, &r, form, mode, &mut NoCount).unwrap();
                    assert_eq!(s.sum(), want, "{form:?} {mode:?} {b:?}");
                }
            }
        }
        // Straddling the far corner: clamp, repeat and mirror see 255 everywhere.
        let r = rect_from_raw::<I24F8>([e - 1, e - 1, e + 1, e + 1]);
        for mode in [RefMode::Clamp, RefMode::Repeat, RefMode::Mirror] {
            for form in RefForm::ALL {
                assert_eq!(
                    lsum(&l, &r, form, mode, &mut NoCount).unwrap().sum(),
                    255 * 4
                );
            }
        }
        assert_eq!(
            lsum(&l, &r, RefForm::Stable, RefMode::Border, &mut NoCount)
                .unwrap()
                .sum(),
            255
        );
    }
    // 4105 x 4105: refused before anything is written (the check needs no storage).
    let refused = Error::TooWide {
        what: Quantity::Entry,
        bits_needed: 33,
        bits_available: 32,
    };
    assert_eq!(
        TiledBuilder::<u32>::new(spec, N + 1, N + 1, 8, &mut [], &mut []).unwrap_err(),
        refused
    );
    assert_eq!(
        Tiled::<u32>::from_words(&[], spec, N + 1, N + 1, 8).unwrap_err(),
        refused
    );
    {
        let texels = vec![255u8; (N + 1) * (N + 1)];
        let t = Texture::<u8>::new(&texels, N + 1, N + 1).unwrap();
        assert_eq!(
            Tiled::<u32>::build(&t, spec, &mut [], &mut []).unwrap_err(),
            refused
        );
    }
    // u64 values take it.
    assert!(Tiled::<u64>::from_words(&[], spec, N + 1, N + 1, 8)
        .is_err_and(|e| matches!(e, Error::StorageTooSmall { .. })));

    // Modular k = 16 on the same texture.
    let k = 16;
    let mut words = vec![0u32; Modular::<u32>::words_needed(N, N, k).unwrap()];
    let mut row = vec![0u32; N];
    let m = Modular::<u32>::build(&t, k, &mut words, &mut row).unwrap();
    assert_eq!(m.max_exact_area(), 257);
    for (b, area) in [
        ([n - 1, n - 1, n, n], 1u128),
        ([n - 16, n - 16, n, n], 256),
        ([n - 257, n - 1, n, n], 257),
        ([n - 1, n - 257, n, n], 257),
    ] {
        for mode in RefMode::ALL {
            assert_eq!(
                lsum_int(&m, b, mode, &mut NoCount).unwrap().sum(),
                255 * area,
                "{b:?}"
            );
        }
    }
    let refused = |needed| {
        Err(Error::TooWide {
            what: Quantity::ModularBox,
            bits_needed: needed,
            bits_available: k,
        })
    };
    assert_eq!(
        lsum_int(&m, [n - 258, n - 1, n, n], RefMode::Border, &mut NoCount),
        refused(17)
    );
    assert_eq!(
        lsum_int(&m, [0, 0, n, n], RefMode::Border, &mut NoCount),
        refused(32)
    );
    // 1/256 x 1/256 at the far corner: Stable exact (255 units of 2^-16), Paper needs 8 + 16.
    let r = rect_from_raw::<I24F8>([e - 1, e - 1, e, e]);
    for mode in RefMode::ALL {
        assert_eq!(
            lsum(&m, &r, RefForm::Stable, mode, &mut NoCount)
                .unwrap()
                .sum(),
            255
        );
        assert_eq!(
            lsum(&m, &r, RefForm::Paper, mode, &mut NoCount),
            refused(24)
        );
    }
    // At F = 4 one cell fits Paper: 8 + 8 = 16 bits.
    let e4 = (N as i64) << 4;
    let r = rect_from_raw::<I28F4>([e4 - 1, e4 - 1, e4, e4]);
    assert_eq!(
        lsum(&m, &r, RefForm::Paper, RefMode::Border, &mut NoCount)
            .unwrap()
            .sum(),
        255
    );
}

// ---------------------------------------------------------------------------------------------
// Costs
// ---------------------------------------------------------------------------------------------

#[test]
fn lookup_costs() {
    let (w, h) = (64usize, 64usize);
    let tex = RefTexture::random(w, h, 1, 255, 99);
    let mut fst = vec![0u32; w * h];
    let flat = build_sat::<u8, u32, 1>(&tex, &mut fst).unwrap();
    // Corners 13, 27 (x) and 19, 42 (y): both digits non-zero for tiles of 8.
    let b = [13, 19, 27, 42];
    for v in b {
        assert!(v % 8 != 0 && v / 8 != 0);
    }
    let mut kf = Tally::new();
    let want = lsum_int(&flat, b, RefMode::Border, &mut kf).unwrap();
    assert_eq!((kf.reads, kf.adds), (4, 3));

    let spec = TiledSpec::tiles(8, 8).unwrap();
    let words = tiled_words::<u8, u32, 1>(&tex, spec).unwrap();
    let l = Tiled::<u32>::from_words(&words, spec, w, h, 8).unwrap();
    let mut k = Tally::new();
    assert_eq!(lsum_int(&l, b, RefMode::Border, &mut k), Ok(want));
    assert_eq!(k.reads, 16, "{k:?}");
    assert_eq!(k.adds, 3 + 4 * 3, "{k:?}");
    assert!(k.words >= k.reads && k.words <= 3 * k.reads, "{k:?}");
    let field_sum: u32 = (0..2)
        .flat_map(|p| (0..2).map(move |q| (p, q)))
        .map(|(p, q)| l.field_bits(p, q).unwrap())
        .sum();
    assert_eq!(k.bits_read, 4 * field_sum as u64);
    assert_eq!(l.field_bits(2, 0), None);
    assert_eq!(l.max_fields_per_corner(), 4);
    // Field widths for 64 x 64, tiles 8: local 7 x 7 cells, strips 7 x 64, corners 64 x 64.
    assert_eq!(l.field_bits(0, 0), Some(bits_of(255 * 49)));
    assert_eq!(l.field_bits(1, 0), Some(bits_of(255 * 7 * 64)));
    assert_eq!(l.field_bits(0, 1), Some(bits_of(255 * 7 * 64)));
    assert_eq!(l.field_bits(1, 1), Some(bits_of(255 * 64 * 64)));
    // A corner on tile boundaries reads only the corner field.
    let mut k = Tally::new();
    l.corner(16, 24, &mut k);
    assert_eq!((k.reads, k.adds), (1, 0));

    // Fractional corners with every cell inside one tile, off its left and top edges (cells
    // 13 and 27 on x, 19 and 42 on y: digits 5, 3, 3, 2 of 8, all tiles past the first): each
    // cell's four corners share the tile-level fields, 4 local sums + 2 strips above + 2
    // strips left + 1 tile corner = 9 fields (not 4 x 4), and 10 additions (4 + 4 + 2).
    let r = Rect::new(q4(13.5), q4(19.5), q4(27.25), q4(42.75));
    for form in [RefForm::Paper, RefForm::Stable] {
        let mut kf = Tally::new();
        let want = lsum(&flat, &r, form, RefMode::Border, &mut kf).unwrap();
        let mut k = Tally::new();
        assert_eq!(lsum(&l, &r, form, RefMode::Border, &mut k), Ok(want));
        assert_eq!(kf.reads, 16);
        assert_eq!(k.reads, 4 * 9, "{form:?} {k:?}");
        assert_eq!(k.adds, kf.adds + 4 * 10, "{form:?}");
        assert_eq!((k.muls, k.divs), (kf.muls, kf.divs), "{form:?}");
    }
    // A cell on a tile's left edge (cell 16: digit 0) takes the general path: each corner's
    // fields read once per distinct field, 16 corners' worth of values, the same sums.
    let r = Rect::new(q4(16.5), q4(19.5), q4(27.25), q4(42.75));
    for form in [RefForm::Paper, RefForm::Stable] {
        let mut kf = Tally::new();
        let want = lsum(&flat, &r, form, RefMode::Border, &mut kf).unwrap();
        let mut k = Tally::new();
        assert_eq!(lsum(&l, &r, form, RefMode::Border, &mut k), Ok(want));
        // Cell 16 (digit 0, tile 2) with cell 17 (digit 1): the local sums and strips above of
        // column 16 are not stored (digit 0); x = 16, 17 share the tile-level fields. Per cell
        // (16, j): corners (16, j), (16, j+1) read the strip left and the tile corner (2
        // fields, the corner shared: 3), (17, j), (17, j+1) the local sums and strips above
        // (4, the strip above shared along y: 3) and share the left strips and corner: 6.
        assert_eq!(k.reads, 2 * 6 + 2 * 9, "{form:?} {k:?}");
    }

    // Flat packed and modular: one field per corner.
    let words = tiled_words::<u8, u32, 1>(&tex, TiledSpec::FLAT_PACKED).unwrap();
    let p = Tiled::<u32>::from_words(&words, TiledSpec::FLAT_PACKED, w, h, 8).unwrap();
    assert_eq!(p.field_bits(0, 0), Some(entry_bits_worst_case(8, w, h)));
    let mut k = Tally::new();
    assert_eq!(lsum_int(&p, b, RefMode::Border, &mut k), Ok(want));
    assert_eq!((k.reads, k.adds), (4, 3));
    assert!(k.words >= 4);
    let mw = modular_words::<u8, u32, 1>(&tex, 16).unwrap();
    let m = Modular::<u32>::from_words(&mw, w, h, 8, 16).unwrap();
    let small = [13, 19, 27, 29];
    let mut k = Tally::new();
    assert_eq!(
        lsum_int(&m, small, RefMode::Border, &mut k),
        lsum_int(&flat, small, RefMode::Border, &mut NoCount)
    );
    assert_eq!((k.reads, k.adds, k.bits_read), (4, 3, 64));
    assert!(k.words >= 4 && k.words <= 8);
}

/// The targets, from `words_needed` (nothing built): tiles 8 x 8 at 2048 x 2048 within
/// 16.5 bits per entry, 2-in-16 within 14; next to Crow's literal (and inexact) 16.125 and 14.
#[test]
fn bits_per_entry_targets() {
    let n = 2048usize;
    let bpe = |spec: TiledSpec| {
        Tiled::<u32>::words_needed(spec, n, n, 8).unwrap() as f64 * 32.0 / (n * n) as f64
    };
    let t8 = bpe(TiledSpec::tiles(8, 8).unwrap());
    let t2_16 = bpe(TiledSpec::square(&[2, 16]).unwrap());
    println!("2048 x 2048: tiles 8x8 {t8:.3}, 2 in 16 {t2_16:.3} bits per entry");
    assert!(t8 <= 16.5, "{t8}");
    assert!(t2_16 <= 14.0, "{t2_16}");
    // The flat table packed at its exact width: 30 bits.
    assert_eq!(bpe(TiledSpec::FLAT_PACKED), 30.0);
    // Modular k = 16 is 16 bits, tiled mod 2^16 less.
    assert_eq!(
        Modular::<u32>::words_needed(n, n, 16).unwrap() as f64 * 32.0 / (n * n) as f64,
        16.0
    );
    assert!(bpe(TiledSpec::tiles(4, 4).unwrap().with_modulus(16)) < 16.0);
}

// ---------------------------------------------------------------------------------------------
// Timing (by hand)
// ---------------------------------------------------------------------------------------------

/// Nanoseconds per 16-read `Stable` lookup on the flat table, tiles 8 x 8 (`TIMING_SPEC` sets
/// others) and modular `k = 16`
/// over a 1024 x 1024 random `u8` texture (`TIMING_N` sets another side): 10^6 random boxes of fractional corners (`F = 4`),
/// sides up to 15 texels (at most 256 cells, so the modular layout answers every one). Run by
/// hand, in release:
///
/// `cargo test -p texsat-host-tests --release --test layouts -- --ignored --nocapture timing`
#[test]
#[ignore]
fn timing_stable_lookups() {
    use std::hint::black_box;
    use std::time::Instant;
    let _g = big_lock();
    // TIMING_N=256 for a texture whose tables fit the L2 cache.
    let n: usize = std::env::var("TIMING_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1024);
    const LOOKUPS: usize = 1_000_000;
    let tex = RefTexture::random(n, n, 1, 255, 2024);
    let mut fst = vec![0u32; n * n];
    let flat = build_sat::<u8, u32, 1>(&tex, &mut fst).unwrap();
    // TIMING_SPEC=2,16 (or 3,5 ...: block sizes on both axes) times another tiled spec.
    let spec = match std::env::var("TIMING_SPEC") {
        Ok(v) => {
            let blocks: Vec<u32> = v.split(',').map(|b| b.trim().parse().unwrap()).collect();
            TiledSpec::square(&blocks).unwrap()
        }
        Err(_) => TiledSpec::tiles(8, 8).unwrap(),
    };
    let tw = tiled_words::<u8, u32, 1>(&tex, spec).unwrap();
    let tiled = Tiled::<u32>::from_words(&tw, spec, n, n, 8).unwrap();
    let k = 16;
    let mw = modular_words::<u8, u32, 1>(&tex, k).unwrap();
    let modular = Modular::<u32>::from_words(&mw, n, n, 8, k).unwrap();
    let mut rng = texsat_host_tests::rng(77);
    let end = (n as i64) << 4;
    let boxes: Vec<Rect<I28F4>> = (0..LOOKUPS)
        .map(|_| {
            let (bw, bh): (i64, i64) = (rng.random_range(1..15 << 4), rng.random_range(1..15 << 4));
            let x0 = rng.random_range(0..end - bw);
            let y0 = rng.random_range(0..end - bh);
            rect_from_raw::<I28F4>([x0, y0, x0 + bw, y0 + bh])
        })
        .collect();
    fn run<L: BoxLookup<1>>(l: &L, boxes: &[Rect<I28F4>]) -> (f64, u128, Tally) {
        let mut t = Tally::new();
        for r in boxes.iter().take(10_000) {
            l.box_sum(r, Stable, Border, &mut t).unwrap();
        }
        let mut best = f64::MAX;
        let mut acc = 0u128;
        for _ in 0..3 {
            let start = Instant::now();
            for r in boxes {
                let s = black_box(l).box_sum(black_box(r), Stable, Border, &mut NoCount);
                acc = acc.wrapping_add(s.map(|s| s.sum().into()).unwrap_or(1));
            }
            best = best.min(start.elapsed().as_secs_f64() * 1e9 / boxes.len() as f64);
        }
        (best, black_box(acc), t)
    }
    // TIMING_ONLY=flat|tiled|modular times one layout (for `perf stat`).
    let only = std::env::var("TIMING_ONLY").unwrap_or_default();
    let skip = |name: &str| !only.is_empty() && only != name;
    let none = || (f64::NAN, 0u128, Tally::new());
    let (nf, sf, tf) = if skip("flat") {
        none()
    } else {
        run(&flat, &boxes)
    };
    let (nt, st, tt) = if skip("tiled") {
        none()
    } else {
        run(&tiled, &boxes)
    };
    let (nm, sm, tm) = if skip("modular") {
        none()
    } else {
        run(&modular, &boxes)
    };
    if only.is_empty() {
        assert_eq!(sf, st);
        assert_eq!(sf, sm);
    }
    let per_read = |ns: f64, t: &Tally| ns / (t.reads as f64 / 10_000.0);
    println!(
        "flat    {nf:8.1} ns/lookup  {:5.2} reads/lookup  {:6.2} ns/read",
        tf.reads as f64 / 1e4,
        per_read(nf, &tf)
    );
    println!(
        "tiled   {nt:8.1} ns/lookup  {:5.2} reads/lookup  {:6.2} ns/read  ({:.2}x flat per read)",
        tt.reads as f64 / 1e4,
        per_read(nt, &tt),
        per_read(nt, &tt) / per_read(nf, &tf)
    );
    println!(
        "modular {nm:8.1} ns/lookup  {:5.2} reads/lookup  {:6.2} ns/read  ({:.2}x flat per read)",
        tm.reads as f64 / 1e4,
        per_read(nm, &tm),
        per_read(nm, &tm) / per_read(nf, &tf)
    );
    // The corner reads alone, at the 16 integer corners each lookup reads (no lookup arithmetic).
    let corners: Vec<(usize, usize)> = boxes
        .iter()
        .flat_map(|r| {
            let xs = [r.x0, r.x1].map(|v| (v.to_bits() >> 4) as usize);
            let ys = [r.y0, r.y1].map(|v| (v.to_bits() >> 4) as usize);
            let c = move |v: usize| [v, (v + 1).min(n)];
            xs.into_iter()
                .flat_map(c)
                .flat_map(move |x| ys.into_iter().flat_map(c).map(move |y| (x, y)))
        })
        .collect();
    fn run_corners<L: Layout<1>>(l: &L, corners: &[(usize, usize)]) -> (f64, u64) {
        let mut best = f64::MAX;
        let mut acc = 0u64;
        for _ in 0..3 {
            let start = Instant::now();
            for &(x, y) in corners {
                let v = black_box(l).corner(x, y, &mut NoCount);
                acc = acc.wrapping_add(v[0].to_u64());
            }
            best = best.min(start.elapsed().as_secs_f64() * 1e9 / corners.len() as f64);
        }
        (best, black_box(acc))
    }
    if only.is_empty() {
        let (cf, _) = run_corners(&flat, &corners);
        let (ct, _) = run_corners(&tiled, &corners);
        let (cm, _) = run_corners(&modular, &corners);
        println!(
            "corner  flat {cf:.2} ns, tiled {ct:.2} ns ({:.2}x per field: {:.2} fields), modular {cm:.2} ns ({:.2}x)",
            ct / cf / (tt.reads as f64 / tf.reads as f64),
            tt.reads as f64 / tf.reads as f64,
            cm / cf
        );
    }
}
