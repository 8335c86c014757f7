//! The triangle filter by repeated integration (texsat `filters::tent`) and the box variance
//! (`filters::variance`) against the references of `src/filter_ref_tentvar.rs` (direct
//! convolution and direct summation, exact integers and `f64`):
//!
//! * the order-2 table equals its closed form for every size up to 7 x 7 (and 1 x 40, 40 x 1),
//!   `u8`/`u16`, 1 and 3 channels, `u32`/`u64`/`u128` entries;
//! * `sample_int`: every integer centre and half-width on small textures (odd sizes, 1 x N,
//!   N x 1), every mode: bit-equal to the exact reference, within `2^-17` of `f64`;
//! * `sample_exact`: grids of fixed-point footprints (smaller than a texel, a few texels, larger
//!   than the texture), `F` = 0, 4, 8, every mode, 1 and 2 channels: bit-equal to the exact
//!   reference; `sample` (bilinear) within `paper_error_bound` (+ rounding) of it, the bound
//!   approached; proptest of both;
//! * costs: "9,4", "36,31" and the exact variant's 81 reads / 72 + 1, in every mode;
//! * widths at the limits: `u64` holds 16 399 x 16 399 8-bit texels, 16 400 is refused before
//!   anything is written; the squares table in `u32` holds 257 x 257, refuses 258 x 258;
//! * variance: every integer box on small textures in every mode, fractional boxes in both
//!   forms, proptest: bit-equal to the exact reference, within `2^-17` (+ f64 noise) of `f64`;
//!   costs 8 reads, 4 multiplies, 1 divide.

use texsat_host_tests::filter_ref_tentvar as reference;

use fixed::types::{I24F8, I28F4, I32F0};
use proptest::prelude::*;
use reference::{
    footprint, paper_bound, tent_f64, tent_rounded, tent_table, variance_f64, variance_rounded,
};
use texsat::filters::tent::{
    paper_error_bound, tent_entry_bits, tent_line_bits, TentEntry, TentLines, TentTable,
};
use texsat::filters::variance::{squares_entry_bits, VarianceTables};
use texsat::filters::OUT_FRAC_BITS;
use texsat::{
    Border, ClampToEdge, Coord, Entry, Error, MirroredRepeat, Paper, Quantity, Rect, Repeat,
    Stable, Tally, Texture,
};
use texsat_host_tests::strategies::{arb_mode, arb_texture};
use texsat_host_tests::{rect_from_raw, RefMode, RefTexel, RefTexture};

const ONE: f64 = (1u64 << OUT_FRAC_BITS) as f64;

/// The texsat mode type for a run-time mode, as a generic call.
macro_rules! with_mode {
    ($mode:expr, $m:ident => $body:expr) => {
        match $mode {
            RefMode::Border => {
                let $m = Border;
                $body
            }
            RefMode::Clamp => {
                let $m = ClampToEdge;
                $body
            }
            RefMode::Repeat => {
                let $m = Repeat;
                $body
            }
            RefMode::Mirror => {
                let $m = MirroredRepeat;
                $body
            }
        }
    };
}

/// Texels, order-2 table and line tables of one reference texture.
struct Tent<T: RefTexel, E: TentEntry> {
    w: usize,
    h: usize,
    texels: Vec<T>,
    table: Vec<E>,
    lines: Vec<E>,
}

impl<T: RefTexel, E: TentEntry> Tent<T, E> {
    fn new<const C: usize>(tex: &RefTexture) -> Self {
        let texels = tex.texels_as::<T>();
        let (w, h) = (tex.width, tex.height);
        let mut table = vec![E::ZERO; TentTable::<E, C>::storage_needed(w, h).unwrap()];
        let mut lines = vec![E::ZERO; TentLines::<E, C>::storage_needed(w, h).unwrap()];
        {
            let texture = Texture::<T, C>::new(&texels, w, h).unwrap();
            TentTable::build(&texture, &mut table).unwrap();
            TentLines::build(&texture, &mut lines).unwrap();
        }
        Tent {
            w,
            h,
            texels,
            table,
            lines,
        }
    }

    /// (integer sample, tally)
    fn int<const C: usize, M: texsat::EdgeMode>(
        &mut self,
        c: (i32, i32),
        ab: (u32, u32),
        mode: M,
    ) -> (Result<[u64; C], Error>, Tally) {
        let texture = Texture::<T, C>::new(&self.texels, self.w, self.h).unwrap();
        let tt = TentTable::<E, C>::build(&texture, &mut self.table).unwrap();
        let mut k = Tally::new();
        let r = tt.sample_int(c.0, c.1, ab.0, ab.1, mode, &mut k);
        (r.map(|s| s.values), k)
    }

    /// (paper, exact) samples and the exact variant's tally.
    #[allow(clippy::type_complexity)]
    fn fixed<const C: usize, X: Coord + fixed::traits::Fixed, M: texsat::EdgeMode>(
        &mut self,
        b: [i64; 4],
        mode: M,
    ) -> (Result<[u64; C], Error>, Result<[u64; C], Error>, Tally) {
        let texture = Texture::<T, C>::new(&self.texels, self.w, self.h).unwrap();
        let tt = TentTable::<E, C>::build(&texture, &mut self.table).unwrap();
        let lines = TentLines::<E, C>::build(&texture, &mut self.lines).unwrap();
        let r = rect_from_raw::<X>(b);
        let p = tt.sample(&r, mode, &mut Tally::new()).map(|s| s.values);
        let mut k = Tally::new();
        let e = tt
            .sample_exact(&lines, &texture, &r, mode, &mut k)
            .map(|s| s.values);
        (p, e, k)
    }
}

// ---------------------------------------------------------------------------------------------
// The table.

fn check_table<T: RefTexel, E: TentEntry + Into<u128>, const C: usize>(tex: &RefTexture) {
    let texels = tex.texels_as::<T>();
    let texture = Texture::<T, C>::new(&texels, tex.width, tex.height).unwrap();
    let mut st = vec![E::ZERO; TentTable::<E, C>::storage_needed(tex.width, tex.height).unwrap()];
    let tt = TentTable::build(&texture, &mut st).unwrap();
    for c in 0..C {
        let want = tent_table(tex, c);
        for y in 0..=tex.height {
            for x in 0..=tex.width {
                let got: u128 = tt.corner(x + 1, y + 1).unwrap()[c].into();
                assert_eq!(
                    got,
                    want[y * (tex.width + 1) + x],
                    "{}x{} ({x},{y})",
                    tex.width,
                    tex.height
                );
            }
        }
        assert_eq!(tt.corner(0, 1).map(|v| v[c].into()), Some(0u128));
    }
    assert!(tt.corner(tex.width + 2, 0).is_none());
}

#[test]
fn table_equals_closed_form() {
    for w in 1..=7 {
        for h in 1..=7 {
            let t = RefTexture::random(w, h, 1, 255, (w * 31 + h) as u64);
            check_table::<u8, u32, 1>(&t);
            check_table::<u8, u64, 1>(&t);
            let t3 = RefTexture::random(w, h, 3, 65535, (w * 17 + h) as u64);
            check_table::<u16, u64, 3>(&t3);
            check_table::<u16, u128, 3>(&t3);
        }
    }
    for (w, h) in [(1, 40), (40, 1)] {
        check_table::<u8, u64, 1>(&RefTexture::constant(w, h, 1, 255));
        check_table::<u16, u128, 1>(&RefTexture::constant(w, h, 1, 65535));
    }
}

// ---------------------------------------------------------------------------------------------
// Integer samples.

#[test]
fn every_integer_centre_and_half_width() {
    let mut count = 0u64;
    for (w, h) in [(1, 1), (1, 5), (5, 1), (3, 3), (5, 4), (2, 7)] {
        let tex = RefTexture::random(w, h, 1, 255, (w * 100 + h) as u64);
        let mut t = Tent::<u8, u64>::new::<1>(&tex);
        for mode in RefMode::ALL {
            for cx in -(2 * w as i32 + 3)..=(3 * w as i32 + 3) {
                for cy in -(h as i32 + 2)..=(2 * h as i32 + 2) {
                    for a in 1..=(w as u32 + 3) {
                        for b in [1u32, 2, h as u32 + 2] {
                            let (got, _) =
                                with_mode!(mode, m => t.int::<1, _>((cx, cy), (a, b), m));
                            let got = got.unwrap()[0];
                            let want = tent_rounded(
                                &tex,
                                mode,
                                (cx as i128, a as i128),
                                (cy as i128, b as i128),
                                0,
                                0,
                            );
                            assert_eq!(got, want, "{mode:?} {w}x{h} c=({cx},{cy}) a={a} b={b}");
                            let f = tent_f64(
                                &tex,
                                mode,
                                [
                                    (cx - a as i32) as f64,
                                    (cy - b as i32) as f64,
                                    (cx + a as i32) as f64,
                                    (cy + b as i32) as f64,
                                ],
                                0,
                            );
                            assert!(
                                (got as f64 / ONE - f).abs() <= 0.5 / ONE + 1e-9,
                                "{got} vs {f}"
                            );
                            count += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(count > 50_000, "{count}");
}

// ---------------------------------------------------------------------------------------------
// Fixed-point samples.

/// Raw footprints on an axis of `n` texels at `F = f`: smaller than a texel, a few texels, the
/// whole texture and more, far outside.
fn intervals(n: usize, f: u32) -> Vec<(i64, i64)> {
    let s = 1i64 << f;
    let n = n as i64;
    let starts = [
        -3 * n * s - s / 3,
        -s - 1,
        -s / 2,
        0,
        1,
        s / 3,
        s,
        n * s / 2,
        n * s - 1,
        n * s,
        2 * n * s + 5,
    ];
    let lens = [
        1,
        s / 4 + 1,
        s / 2,
        s,
        s + s / 3,
        2 * s,
        3 * s + 1,
        n * s,
        3 * n * s + s / 2,
    ];
    let mut v = Vec::new();
    for &a in &starts {
        for &l in &lens {
            if l > 0 {
                v.push((a, a + l));
            }
        }
    }
    v.sort();
    v.dedup();
    v
}

fn fixed_grid<X: Coord + fixed::traits::Fixed>(f: u32) -> (u64, f64) {
    let mut count = 0u64;
    let mut worst_ratio = 0f64;
    for (w, h) in [(1, 1), (1, 4), (4, 1), (3, 5), (6, 4)] {
        let tex = RefTexture::random(w, h, 2, 255, (w * 7 + h + f as usize) as u64);
        let mut t = Tent::<u8, u64>::new::<2>(&tex);
        let (xs, ys) = (intervals(w, f), intervals(h, f));
        for mode in RefMode::ALL {
            for &(x0, x1) in &xs {
                for &(y0, y1) in ys.iter().step_by(2) {
                    let b = [x0, y0, x1, y1];
                    let (p, e, _) = with_mode!(mode, m => t.fixed::<2, X, _>(b, m));
                    let (p, e) = (p.unwrap(), e.unwrap());
                    let (fx, fy) = footprint(b);
                    let a_t = (x1 - x0) as f64 / (2u64 << f) as f64;
                    let b_t = (y1 - y0) as f64 / (2u64 << f) as f64;
                    let bound = paper_bound(255.0, a_t, b_t);
                    assert_eq!(bound, paper_error_bound(8, a_t, b_t));
                    for c in 0..2 {
                        let want = tent_rounded(&tex, mode, fx, fy, f + 1, c);
                        assert_eq!(e[c], want, "{mode:?} {w}x{h} {b:?} F={f} c={c}");
                        let err = (p[c] as f64 - e[c] as f64).abs() / ONE;
                        assert!(
                            err <= bound + 1.0 / ONE,
                            "paper {err} > {bound} {mode:?} {b:?}"
                        );
                        if bound < 1e6 {
                            worst_ratio = worst_ratio.max(err / bound);
                        }
                    }
                    count += 1;
                }
            }
        }
    }
    (count, worst_ratio)
}

#[test]
fn fixed_point_grids_every_mode() {
    let (n0, _) = fixed_grid::<I32F0>(0);
    let (n4, r4) = fixed_grid::<I28F4>(4);
    let (n8, r8) = fixed_grid::<I24F8>(8);
    assert!(n0 + n4 + n8 > 10_000);
    // The bound is approached on these grids (it is reached only in the separable limit).
    assert!(r4.max(r8) > 0.3, "{r4} {r8}");
}

#[test]
fn f64_agrees_with_exact() {
    let tex = RefTexture::random(6, 5, 1, 255, 42);
    let mut t = Tent::<u8, u64>::new::<1>(&tex);
    for mode in RefMode::ALL {
        for &(x0, x1) in &intervals(6, 8) {
            let b = [x0, -300, x1, 700];
            let (_, e, _) = with_mode!(mode, m => t.fixed::<1, I24F8, _>(b, m));
            let r = b.map(|v| v as f64 / 256.0);
            let f = tent_f64(&tex, mode, r, 0);
            let got = e.unwrap()[0] as f64 / ONE;
            assert!(
                (got - f).abs() <= 0.5 / ONE + 1e-9 * f.max(1.0),
                "{mode:?} {b:?}: {got} vs {f}"
            );
        }
    }
}

#[test]
fn paper_bound_is_reached_in_the_separable_limit() {
    // Columns c - a and c + a full, column c empty, centre on a texel centre.
    for a in 1..=5usize {
        let w = 2 * a + 1;
        let mut texels = vec![0u32; w * 2];
        for y in 0..2 {
            texels[y * w] = 255;
            texels[y * w + w - 1] = 255;
        }
        let tex = RefTexture::new(w, 2, 1, texels);
        let mut t = Tent::<u8, u64>::new::<1>(&tex);
        let c = 2 * a as i64 + 1; // centre a + 0.5 in units 2^-1 ... as raw F = 8:
        let b = [
            (c * 128) - (a as i64) * 256,
            -1000 * 256,
            (c * 128) + (a as i64) * 256,
            1001 * 256,
        ];
        let (p, e, _) = t.fixed::<1, I24F8, _>(b, ClampToEdge);
        let err = (p.unwrap()[0] as f64 - e.unwrap()[0] as f64) / ONE;
        let bound = paper_error_bound(8, a as f64, 1000.5);
        assert!(
            err <= bound && err >= 0.999 * bound,
            "a={a}: {err} vs {bound}"
        );
    }
}

#[test]
fn costs_every_mode() {
    let tex = RefTexture::random(16, 12, 1, 255, 5);
    let mut t = Tent::<u8, u64>::new::<1>(&tex);
    for mode in RefMode::ALL {
        let (_, k) = with_mode!(mode, m => t.int::<1, _>((8, 6), (3, 4), m));
        assert_eq!((k.reads, k.muls, k.divs, k.adds), (9, 3, 1, 8), "{mode:?}");
        let b = [3 * 256 + 77, 2 * 256 + 3, 11 * 256 + 200, 9 * 256 + 1];
        let texels = tex.texels_as::<u8>();
        let texture = Texture::<u8>::new(&texels, 16, 12).unwrap();
        let tt = TentTable::<u64>::build(&texture, &mut t.table).unwrap();
        let mut k = Tally::new();
        with_mode!(mode, m => tt.sample(&rect_from_raw::<I24F8>(b), m, &mut k)).unwrap();
        assert_eq!(
            (k.reads, k.muls, k.divs, k.multiplicative(), k.adds),
            (36, 30, 1, 31, 62)
        );
        let (_, _, k) = with_mode!(mode, m => t.fixed::<1, I24F8, _>(b, m));
        assert_eq!((k.reads, k.muls, k.divs), (81, 72, 1), "{mode:?}");
    }
}

#[test]
fn widths_at_the_limits() {
    // u64, 8-bit texels: 16 399 x 16 399 is the largest square; 16 400 is refused.
    assert_eq!(tent_entry_bits(8, 16399, 16399), 64);
    assert_eq!(tent_entry_bits(8, 16400, 16400), 65);
    assert_eq!(tent_entry_bits(8, 16400, 16398), 64);
    assert_eq!(tent_entry_bits(16, 4095, 4095), 64);
    assert_eq!(tent_entry_bits(16, 4096, 4096), 65);
    assert_eq!(tent_line_bits(8, 256), 25);
    let big = vec![0u8; 16400 * 16400];
    let texture = Texture::<u8>::new(&big, 16400, 16400).unwrap();
    let mut none: [u64; 0] = [];
    assert_eq!(
        TentTable::<u64>::build(&texture, &mut none).err(),
        Some(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 65,
            bits_available: 64
        })
    );
    // 16 399 passes the width proof and stops only at the (empty) storage.
    let texture = Texture::<u8>::new(&big, 16399, 16399).unwrap();
    assert_eq!(
        TentTable::<u64>::build(&texture, &mut none).err(),
        Some(Error::StorageTooSmall {
            needed: 16400 * 16400,
            got: 0
        })
    );
    // u128 accepts it.
    let mut none128: [u128; 0] = [];
    let texture = Texture::<u8>::new(&big, 16400, 16400).unwrap();
    assert!(matches!(
        TentTable::<u128>::build(&texture, &mut none128),
        Err(Error::StorageTooSmall { .. })
    ));
    // The all-255 texture reaches the bound exactly: Q(w+1, h+1) = 255 w (w+2) h (h+2).
    for (w, h) in [(1usize, 1usize), (3, 8), (17, 2)] {
        let texels = vec![255u8; w * h];
        let texture = Texture::<u8>::new(&texels, w, h).unwrap();
        let mut st = vec![0u64; TentTable::<u64>::storage_needed(w, h).unwrap()];
        let tt = TentTable::build(&texture, &mut st).unwrap();
        let top = tt.corner(w + 1, h + 1).unwrap()[0];
        assert_eq!(top as u128, 255 * (w * (w + 2) * h * (h + 2)) as u128);
        assert_eq!(64 - top.leading_zeros(), tent_entry_bits(8, w, h));
    }
    // Memory of 8-bit 256 x 256 in u64: 8.06 bytes per texel byte (5.2x at the exact 41 bits).
    let texels = vec![9u8; 256 * 256];
    let texture = Texture::<u8>::new(&texels, 256, 256).unwrap();
    let mut st = vec![0u64; TentTable::<u64>::storage_needed(256, 256).unwrap()];
    let tt = TentTable::build(&texture, &mut st).unwrap();
    assert!((tt.table_bytes() as f64 / 65536.0 - 8.0627).abs() < 1e-3);
    let exact_ratio = 257.0 * 257.0 * tent_entry_bits(8, 256, 256) as f64 / (65536.0 * 8.0);
    assert!((exact_ratio - 5.165).abs() < 1e-2, "{exact_ratio}");
    // Squares table: u32 holds 257 x 257 at 8 bits, refuses 258 x 258 without writing.
    assert_eq!(squares_entry_bits(8, 257, 257), 32);
    let t = vec![255u8; 258 * 258];
    let texture = Texture::<u8>::new(&t, 258, 258).unwrap();
    let mut a = vec![1u32; 258 * 258];
    let mut b = vec![1u32; 258 * 258];
    assert_eq!(
        VarianceTables::build(&texture, &mut a, &mut b).err(),
        Some(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 33,
            bits_available: 32
        })
    );
    assert!(a.iter().chain(&b).all(|&v| v == 1));
    let texture = Texture::<u8>::new(&t[..257 * 257], 257, 257).unwrap();
    let vt = VarianceTables::build(&texture, &mut a, &mut b).unwrap();
    assert_eq!(vt.squares().entries()[257 * 257 - 1], 255 * 255 * 257 * 257);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn prop_tent_exact_and_paper(
        tex in arb_texture(9, 9, 1, 255),
        mode in arb_mode(),
        x0 in -600i64..600, y0 in -600i64..600,
        wl in 1i64..900, hl in 1i64..900,
    ) {
        let b = [x0, y0, x0 + wl, y0 + hl];
        let mut t = Tent::<u8, u64>::new::<1>(&tex);
        let (p, e, _) = with_mode!(mode, m => t.fixed::<1, I28F4, _>(b, m));
        let (fx, fy) = footprint(b);
        let want = tent_rounded(&tex, mode, fx, fy, 5, 0);
        prop_assert_eq!(e.unwrap()[0], want);
        let bound = paper_error_bound(8, wl as f64 / 32.0, hl as f64 / 32.0);
        let err = (p.unwrap()[0] as f64 - want as f64).abs() / ONE;
        prop_assert!(err <= bound + 1.0 / ONE, "{} > {}", err, bound);
    }

    #[test]
    fn prop_tent_int_16_bit(
        tex in arb_texture(7, 7, 1, 65535),
        mode in arb_mode(),
        cx in -20i32..20, cy in -20i32..20, a in 1u32..12, b in 1u32..12,
    ) {
        let mut t = Tent::<u16, u128>::new::<1>(&tex);
        let (got, _) = with_mode!(mode, m => t.int::<1, _>((cx, cy), (a, b), m));
        let want = tent_rounded(&tex, mode, (cx as i128, a as i128), (cy as i128, b as i128), 0, 0);
        prop_assert_eq!(got.unwrap()[0], want);
    }

    #[test]
    fn prop_variance(
        tex in arb_texture(9, 9, 2, 255),
        mode in arb_mode(),
        x0 in -700i64..700, y0 in -700i64..700,
        wl in 1i64..900, hl in 1i64..900,
    ) {
        let b = [x0, y0, x0 + wl, y0 + hl];
        let texels = tex.texels_as::<u8>();
        let texture = Texture::<u8, 2>::new(&texels, tex.width, tex.height).unwrap();
        let n = tex.width * tex.height * 2;
        let (mut vs, mut qs) = (vec![0u32; n], vec![0u32; n]);
        let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
        let r = rect_from_raw::<I28F4>(b);
        let p = with_mode!(mode, m => vt.variance(&r, Paper, m, &mut Tally::new())).unwrap();
        let s = with_mode!(mode, m => vt.variance(&r, Stable, m, &mut Tally::new())).unwrap();
        for c in 0..2 {
            let want = variance_rounded(&tex, mode, b, 4, c);
            prop_assert_eq!(p.values[c], want);
            prop_assert_eq!(s.values[c], want);
            let f = variance_f64(&tex, mode, b.map(|v| v as f64 / 16.0), c);
            prop_assert!((want as f64 / ONE - f).abs() <= 0.5 / ONE + 1e-7 * f.max(1.0));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Variance.

fn every_variance_box<T: RefTexel, E: Entry, const C: usize>(tex: &RefTexture) -> u64 {
    let texels = tex.texels_as::<T>();
    let texture = Texture::<T, C>::new(&texels, tex.width, tex.height).unwrap();
    let n = VarianceTables::<E, C>::storage_needed(tex.width, tex.height).unwrap();
    let (mut vs, mut qs) = (vec![E::ZERO; n], vec![E::ZERO; n]);
    let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
    let (w, h) = (tex.width as i32, tex.height as i32);
    let mut count = 0;
    for mode in RefMode::ALL {
        for x0 in -w - 1..=w + 1 {
            for x1 in x0 + 1..=2 * w + 2 {
                for y0 in -2..=h {
                    for y1 in y0 + 1..=h + 2 {
                        let r = Rect::new(x0, y0, x1, y1);
                        let mut k = Tally::new();
                        let got = with_mode!(mode, m => vt.variance_int(&r, m, &mut k)).unwrap();
                        for c in 0..C {
                            let b = [x0 as i64, y0 as i64, x1 as i64, y1 as i64];
                            assert_eq!(
                                got.values[c],
                                variance_rounded(tex, mode, b, 0, c),
                                "{mode:?} {r:?}"
                            );
                        }
                        count += 1;
                    }
                }
            }
        }
    }
    count
}

#[test]
fn variance_every_integer_box() {
    let mut count = 0;
    for (w, h) in [(1, 1), (1, 6), (6, 1), (3, 5), (5, 3)] {
        count +=
            every_variance_box::<u8, u32, 1>(&RefTexture::random(w, h, 1, 255, (w + 9 * h) as u64));
        count += every_variance_box::<u16, u64, 3>(&RefTexture::random(
            w,
            h,
            3,
            65535,
            (w + 5 * h) as u64,
        ));
    }
    assert!(count > 20_000, "{count}");
}

#[test]
fn variance_fixed_grids_and_costs() {
    for (w, h) in [(1, 4), (4, 1), (5, 3)] {
        let tex = RefTexture::random(w, h, 1, 255, 77);
        let texels = tex.texels_as::<u8>();
        let texture = Texture::<u8>::new(&texels, w, h).unwrap();
        let (mut vs, mut qs) = (vec![0u32; w * h], vec![0u32; w * h]);
        let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
        for mode in RefMode::ALL {
            for &(x0, x1) in &intervals(w, 8) {
                for &(y0, y1) in &intervals(h, 8) {
                    let b = [x0, y0, x1, y1];
                    let r = rect_from_raw::<I24F8>(b);
                    let got = with_mode!(mode, m => vt.variance(&r, Stable, m, &mut Tally::new()))
                        .unwrap();
                    assert_eq!(
                        got.values[0],
                        variance_rounded(&tex, mode, b, 8, 0),
                        "{mode:?} {b:?}"
                    );
                }
            }
        }
    }
    let tex = RefTexture::random(10, 10, 1, 255, 1);
    let texels = tex.texels_as::<u8>();
    let texture = Texture::<u8>::new(&texels, 10, 10).unwrap();
    let (mut vs, mut qs) = (vec![0u32; 100], vec![0u32; 100]);
    let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
    for mode in RefMode::ALL {
        let mut k = Tally::new();
        with_mode!(mode, m => vt.variance_int(&Rect::new(2, 3, 7, 9), m, &mut k)).unwrap();
        assert_eq!((k.reads, k.muls, k.divs, k.adds), (8, 4, 1, 7), "{mode:?}");
    }
    // Zero-area and inverted boxes.
    assert_eq!(
        vt.variance_int(&Rect::new(2, 3, 2, 9), Border, &mut Tally::new()),
        Err(Error::ZeroArea)
    );
    assert_eq!(
        vt.variance_int(&Rect::new(3, 3, 2, 9), Border, &mut Tally::new()),
        Err(Error::InvertedBox)
    );
    // A box far too large for the u128 numerator is refused, not wrapped.
    let huge = Rect::new(I24F8::MIN, I24F8::MIN, I24F8::MAX, I24F8::MAX);
    for mode in RefMode::ALL {
        let r = with_mode!(mode, m => vt.variance(&huge, Paper, m, &mut Tally::new()));
        assert!(
            matches!(r, Ok(_) | Err(Error::TooWide { .. })),
            "{mode:?} {r:?}"
        );
    }
}
