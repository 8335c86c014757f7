//! Crow's §3.0 bit-saving scheme taken literally ([`CrowLiteral`]: per-region local sums plus
//! one corner value per region) is wrong for boxes whose corners fall in different regions;
//! texsat's exact [`Tiled`] layout with the same tiles is right for every box.
//!
//! * the stated bits per entry (Crow's 16 and 14 bits);
//! * the error of every reconstructed corner value is exactly the two missing strips
//!   `T(x) + L(y)`, and corner values are right only in the first region;
//! * hand-checked failing boxes (all-ones textures: `S(x, y) = x y`), and failing boxes found
//!   on random 32 x 32 (`R = 16`) and printable 8 x 8 (`R = 4`) textures;
//! * exhaustively on 8 x 8 (`R = 4`) and 13 x 7 (`R = 4`, partial regions): every box whose
//!   corners lie in one region is exact, and the others are wrong (8 x 8 random: 1040 of the
//!   1296 boxes with positive area, 80.2 %, are not in one region, and all 1040 are wrong;
//!   all-ones: 984 wrong; 32 x 32 random with R = 16: 213247 of 278784, 76.5 %);
//! * the same boxes through `Tiled` with `TiledSpec::tiles(R, R)` equal the flat table and the
//!   direct sums.
//!
//! Region rule (from the implementation: the entry of texel `(x - 1, y - 1)` answers the corner
//! `(x, y)`): corner coordinate `x >= 1` belongs to region column `(x - 1) / R`, so a coordinate
//! on a region boundary belongs to the region to its left (above), and `x = 0` to column 0.

use texsat::layouts::{Tiled, TiledSpec};
use texsat::{Border, BoxLookup, Layout, NoCount, Rect, Sat, Texture};
use texsat_host_tests::crow_literal::CrowLiteral;
use texsat_host_tests::RefTexture;

/// The exact corner function from the naive table (independent of texsat).
struct Exact {
    w: usize,
    ch: usize,
    table: Vec<u128>,
}

impl Exact {
    fn new(tex: &RefTexture) -> Self {
        Exact {
            w: tex.width,
            ch: tex.channels,
            table: tex.naive_table(),
        }
    }
    fn s(&self, x: usize, y: usize, c: usize) -> u128 {
        if x == 0 || y == 0 {
            0
        } else {
            self.table[((y - 1) * self.w + x - 1) * self.ch + c]
        }
    }
    fn box_sum(&self, x0: usize, y0: usize, x1: usize, y1: usize, c: usize) -> i128 {
        let s = |x, y| self.s(x, y, c) as i128;
        s(x1, y1) - s(x1, y0) - s(x0, y1) + s(x0, y0)
    }
}

/// A random texture with every texel in `1..=255` (so every non-empty strip sum is positive).
fn positive(w: usize, h: usize, ch: usize, seed: u64) -> RefTexture {
    let t = RefTexture::random(w, h, ch, 254, seed);
    RefTexture::new(w, h, ch, t.texels.iter().map(|v| v + 1).collect())
}

/// `t(i, j) = (3 i + 5 j) % 10`: small enough to print and check by hand.
fn printable_8x8() -> RefTexture {
    let mut t = Vec::new();
    for j in 0..8u32 {
        for i in 0..8u32 {
            t.push((3 * i + 5 * j) % 10);
        }
    }
    RefTexture::new(8, 8, 1, t)
}

fn print_texture(tex: &RefTexture) {
    for j in 0..tex.height {
        let row: Vec<String> = (0..tex.width)
            .map(|i| format!("{:3}", tex.texel(i, j, 0)))
            .collect();
        println!("  {}", row.join(""));
    }
}

/// Every box `[x0, x1) x [y0, y1)` with positive area inside a `w x h` texture.
fn boxes(w: usize, h: usize) -> impl Iterator<Item = (usize, usize, usize, usize)> {
    (0..w).flat_map(move |x0| {
        (x0 + 1..=w).flat_map(move |x1| {
            (0..h).flat_map(move |y0| (y0 + 1..=h).map(move |y1| (x0, y0, x1, y1)))
        })
    })
}

#[test]
fn crow_bits_per_entry_figures() {
    // "regions of 16 pixels square ... limit the sum within such a region to 16 bits".
    assert_eq!(CrowLiteral::local_bits_for(8, 16), 16);
    assert_eq!(
        CrowLiteral::nominal_bits_per_entry(8, 16),
        16.0 + 32.0 / 256.0
    );
    // "a 32-bit quantity for each group of 16 entries ... effective 14 bits per entry".
    assert_eq!(CrowLiteral::local_bits_for(8, 4), 12);
    assert_eq!(CrowLiteral::nominal_bits_per_entry(8, 4), 14.0);
    let tex = RefTexture::random(32, 32, 1, 255, 1);
    assert_eq!(CrowLiteral::build(&tex, 16, 8).bits_per_entry(), 16.125);
    assert_eq!(CrowLiteral::build(&tex, 4, 8).bits_per_entry(), 14.0);
    // Partial regions: 13 x 7 with R = 4 has 4 x 2 regions for 91 entries.
    let tex = RefTexture::random(13, 7, 1, 255, 2);
    let lit = CrowLiteral::build(&tex, 4, 8);
    assert_eq!(lit.regions(), (4, 2));
    assert_eq!(lit.bits_per_entry(), 12.0 + 8.0 * 32.0 / 91.0);
}

/// `S(x, y) - S_lit(x, y) = T(x) + L(y)` for every corner, with `T(x) = S(x, Y0) - S(X0, Y0)`
/// and `L(y) = S(X0, y) - S(X0, Y0)` for the corner's region origin `(X0, Y0)`; and the value is
/// right (on a texture of positive texels) exactly in the first region and on the zero row and
/// column.
#[test]
fn corner_error_is_exactly_the_missing_strips() {
    for (w, h, r, ch, seed) in [
        (32, 32, 16, 1, 11),
        (8, 8, 4, 1, 12),
        (13, 7, 4, 3, 13),
        (9, 20, 3, 1, 14),
    ] {
        let tex = positive(w, h, ch, seed);
        let lit = CrowLiteral::build(&tex, r, 8);
        let ex = Exact::new(&tex);
        for c in 0..ch {
            for y in 0..=h {
                for x in 0..=w {
                    let (rx, ry) = lit.region_of_corner(x, y);
                    let (x0, y0) = (rx * r, ry * r);
                    let t = ex.s(x, y0, c) - ex.s(x0, y0, c);
                    let l = ex.s(x0, y, c) - ex.s(x0, y0, c);
                    let s = ex.s(x, y, c);
                    let s_lit = lit.corner(x, y, c);
                    assert_eq!(
                        s - s_lit,
                        t + l,
                        "{w}x{h} R={r} corner ({x},{y}) channel {c}"
                    );
                    let right = x == 0 || y == 0 || (rx == 0 && ry == 0);
                    assert_eq!(s == s_lit, right, "{w}x{h} R={r} corner ({x},{y})");
                    if x > 0 && y > 0 {
                        // The stored parts: region corner S(X0, Y0) and the local sum.
                        assert_eq!(lit.region_corner(rx, ry, c), ex.s(x0, y0, c));
                        let local =
                            ex.s(x, y, c) + ex.s(x0, y0, c) - ex.s(x, y0, c) - ex.s(x0, y, c);
                        assert_eq!(lit.local(x - 1, y - 1, c) as u128, local);
                    }
                }
            }
        }
    }
}

/// All-ones textures: `S(x, y) = x y`, so everything can be checked by hand.
///
/// `R = 4` on 8 x 8, box `[3, 5) x [3, 5)` (2 x 2 texels around the corner where four regions
/// meet): exact sum 4. The literal reconstruction:
/// * `S_lit(5, 5)`: region (1, 1), corner `S(4, 4) = 16`, local `(5-4)(5-4) = 1`: 17 (true 25);
/// * `S_lit(5, 3)`: region (1, 0), corner `S(4, 0) = 0`, local `(5-4) 3 = 3`: 3 (true 15);
/// * `S_lit(3, 5)`: region (0, 1), corner `S(0, 4) = 0`, local `3 (5-4) = 3`: 3 (true 15);
/// * `S_lit(3, 3)`: region (0, 0), local `9`: 9 (true 9).
///
/// Box: `17 - 3 - 3 + 9 = 20` instead of 4. In general the box `[R-1, R+1)^2` of an all-ones
/// texture comes out as `2 R^2 - 4 R + 4` (452 for Crow's `R = 16`) instead of 4.
#[test]
fn all_ones_hand_checked() {
    let tex = RefTexture::constant(8, 8, 1, 1);
    let lit = CrowLiteral::build(&tex, 4, 8);
    assert_eq!(
        [
            lit.corner(5, 5, 0),
            lit.corner(5, 3, 0),
            lit.corner(3, 5, 0),
            lit.corner(3, 3, 0)
        ],
        [17, 3, 3, 9]
    );
    assert_eq!(lit.box_sum(3, 3, 5, 5, 0), 20);
    assert_eq!(Exact::new(&tex).box_sum(3, 3, 5, 5, 0), 4);
    // Inside one region (region (1, 1): corners 5..=8): right.
    assert_eq!(lit.box_sum(5, 5, 8, 8, 0), 9);
    // A boundary coordinate belongs to the region before it: [0, 4) x [0, 4) is region (0, 0).
    assert!(lit.box_in_one_region(0, 0, 4, 4));
    assert_eq!(lit.box_sum(0, 0, 4, 4, 0), 16);
    // [3, 7) x [3, 7) spans four regions: S_lit(7,7) = 16 + 9 = 25, S_lit(7,3) = S_lit(3,7)
    // = 3 * 3 = 9, S_lit(3,3) = 9: 25 - 9 - 9 + 9 = 16, right by coincidence. For an all-ones
    // texture the error of a box spanning regions (0, 0) to (1, 1) is
    // 4 ((x1 - x0 - 4) + (y1 - y0 - 4)), zero whenever the sides add up to 2 R; on random
    // data no such luck (see the exhaustive test).
    assert!(!lit.box_in_one_region(3, 3, 7, 7));
    assert_eq!(lit.box_sum(3, 3, 7, 7, 0), 16);
    assert_eq!(Exact::new(&tex).box_sum(3, 3, 7, 7, 0), 16);
    // [4, 8) x [4, 8): corner 4 is region column (row) 0, corner 8 is column (row) 1; error
    // 4 (0 + 0) = 0 again, while [4, 7) x [4, 8) is off by 4 (-1 + 0) = -4.
    assert!(!lit.box_in_one_region(4, 4, 8, 8));
    assert_eq!(lit.box_sum(4, 4, 8, 8, 0), 16);
    assert_eq!(lit.box_sum(4, 4, 7, 8, 0), 12 + 4);
    assert_eq!(Exact::new(&tex).box_sum(4, 4, 7, 8, 0), 12);

    // Crow's R = 16 on 32 x 32.
    let tex = RefTexture::constant(32, 32, 1, 1);
    let lit = CrowLiteral::build(&tex, 16, 8);
    assert_eq!(lit.box_sum(15, 15, 17, 17, 0), 452);
    assert_eq!(Exact::new(&tex).box_sum(15, 15, 17, 17, 0), 4);
    for r in [2usize, 3, 4, 5, 8, 16] {
        let n = 2 * r;
        let tex = RefTexture::constant(n, n, 1, 1);
        let lit = CrowLiteral::build(&tex, r, 8);
        let r2 = (r * r) as i128;
        assert_eq!(
            lit.box_sum(r - 1, r - 1, r + 1, r + 1, 0),
            2 * r2 - 4 * r as i128 + 4,
            "R = {r}"
        );
    }
}

/// Finds the failing box of smallest area (then first in scan order), prints it and its numbers.
fn smallest_failing_box(tex: &RefTexture, r: usize) -> ((usize, usize, usize, usize), i128, i128) {
    let lit = CrowLiteral::build(tex, r, 8);
    let ex = Exact::new(tex);
    let (b, got, want) = boxes(tex.width, tex.height)
        .map(|(x0, y0, x1, y1)| {
            (
                (x0, y0, x1, y1),
                lit.box_sum(x0, y0, x1, y1, 0),
                ex.box_sum(x0, y0, x1, y1, 0),
            )
        })
        .filter(|(_, got, want)| got != want)
        .min_by_key(|((x0, y0, x1, y1), _, _)| (x1 - x0) * (y1 - y0))
        .expect("a failing box");
    let (x0, y0, x1, y1) = b;
    println!(
        "{}x{} R={r}: box [{x0},{x1}) x [{y0},{y1}): Crow literal {got}, exact {want}",
        tex.width, tex.height
    );
    for (x, y) in [(x1, y1), (x1, y0), (x0, y1), (x0, y0)] {
        println!(
            "  S({x},{y}): literal {} exact {} (region {:?})",
            lit.corner(x, y, 0),
            ex.s(x, y, 0),
            lit.region_of_corner(x, y)
        );
    }
    assert_ne!(got, want);
    assert!(!lit.box_in_one_region(x0, y0, x1, y1));
    (b, got, want)
}

#[test]
fn failing_boxes_exhibited() {
    // Random 32 x 32, Crow's R = 16: the smallest failing box is a single texel next to a
    // region boundary.
    let tex = RefTexture::random(32, 32, 1, 255, 2024);
    let (b, got, want) = smallest_failing_box(&tex, 16);
    let (x0, y0, x1, y1) = b;
    assert_eq!((x1 - x0) * (y1 - y0), 1, "{b:?}");
    // Its true sum is the texel itself.
    assert_eq!(want, tex.texel(x0, y0, 0) as i128);
    assert_ne!(got, want);
    // For this seed: box [0, 1) x [16, 17), texel t = (0, 16). S_lit(1, 17) = S(0, 16) + local
    // = 0 + t misses the strip above, T(1) = S(1, 16) (column 0, rows 0..16), which
    // S_lit(1, 16) (first region, exact) subtracts: t - T(1) instead of t. (With the seeded
    // ChaCha8 texture, t = 65 and T(1) = 2363: -2298 instead of 65; the numbers are derived
    // here from the texture rather than written down, so only the box depends on the seed.)
    let t = tex.texel(0, 16, 0) as i128;
    let strip: i128 = (0..16).map(|j| tex.texel(0, j, 0) as i128).sum();
    assert_eq!((b, got, want), ((0, 16, 1, 17), t - strip, t));
    assert_eq!((t, strip), (65, 2363));

    // A printable 8 x 8 example with R = 4.
    let tex = printable_8x8();
    println!("t(i, j) = (3 i + 5 j) % 10:");
    print_texture(&tex);
    let (b, got, want) = smallest_failing_box(&tex, 4);
    // Box [0, 1) x [4, 5) is texel (0, 4) = 20 % 10 = 0. Corners:
    // * S_lit(1, 5): region (0, 1), corner S(0, 4) = 0, local t(0, 4) = 0: 0; the true
    //   S(1, 5) = t(0, 0..=4) = 0 + 5 + 0 + 5 + 0 = 10; the missing strip above the region is
    //   T(1) = S(1, 4) - S(0, 4) = 10 (and L = 0: the region is in column 0);
    // * S_lit(1, 4): region (0, 0), exact: 0 + 5 + 0 + 5 = 10;
    // * S_lit(0, 5) = S_lit(0, 4) = 0.
    // Literal box: 0 - 10 - 0 + 0 = -10, a negative sum, instead of 0.
    assert_eq!((b, got, want), ((0, 4, 1, 5), -10, 0));
    let lit = CrowLiteral::build(&tex, 4, 8);
    assert_eq!(
        [
            lit.corner(1, 5, 0),
            lit.corner(1, 4, 0),
            lit.corner(0, 5, 0),
            lit.corner(0, 4, 0)
        ],
        [0, 10, 0, 0]
    );
    assert_eq!(Exact::new(&tex).s(1, 5, 0), 10);
}

/// Every box of an 8 x 8 texture with R = 4: exact iff (on random data) its corners lie in one
/// region; and the counts of wrong boxes.
#[test]
fn exhaustive_8x8_r4_one_region_exact_others_wrong() {
    for (name, tex) in [
        ("random", RefTexture::random(8, 8, 1, 255, 7)),
        ("ones", RefTexture::constant(8, 8, 1, 1)),
        ("printable", printable_8x8()),
    ] {
        let lit = CrowLiteral::build(&tex, 4, 8);
        let ex = Exact::new(&tex);
        let (mut total, mut one_region, mut wrong) = (0, 0, 0);
        for (x0, y0, x1, y1) in boxes(8, 8) {
            total += 1;
            let got = lit.box_sum(x0, y0, x1, y1, 0);
            let want = ex.box_sum(x0, y0, x1, y1, 0);
            if lit.box_in_one_region(x0, y0, x1, y1) {
                one_region += 1;
                assert_eq!(got, want, "{name}: one-region box {:?}", (x0, y0, x1, y1));
            } else if got != want {
                wrong += 1;
            }
        }
        println!(
            "{name} 8x8 R=4: {wrong} of {total} boxes wrong ({:.1}%), {one_region} in one region",
            100.0 * wrong as f64 / total as f64
        );
        assert_eq!(total, 36 * 36);
        assert_eq!(one_region, 16 * 16);
        assert!(wrong > 0);
        match name {
            // Random data: every box not in one region is wrong.
            "random" => assert_eq!(wrong, total - one_region),
            // All ones: 56 of those 1040 are right by coincidence (see `all_ones_hand_checked`).
            "ones" => assert_eq!(wrong, 984),
            _ => {}
        }
    }
}

/// Partial regions and 3 channels: one-region boxes stay exact.
#[test]
fn exhaustive_13x7_r4_partial_regions() {
    let tex = RefTexture::random(13, 7, 3, 255, 8);
    let lit = CrowLiteral::build(&tex, 4, 8);
    let ex = Exact::new(&tex);
    let mut wrong = 0;
    for (x0, y0, x1, y1) in boxes(13, 7) {
        for c in 0..3 {
            let (got, want) = (
                lit.box_sum(x0, y0, x1, y1, c),
                ex.box_sum(x0, y0, x1, y1, c),
            );
            if lit.box_in_one_region(x0, y0, x1, y1) {
                assert_eq!(got, want, "{:?} channel {c}", (x0, y0, x1, y1));
            } else if got != want {
                wrong += 1;
            }
        }
    }
    assert!(wrong > 0);
}

/// The same boxes through texsat's exact `Tiled` layout with `R x R` tiles: every box equals
/// the flat table and the direct sum, including every box the literal scheme gets wrong.
#[test]
fn tiled_with_same_tiles_is_exact_for_every_box() {
    for (w, h, r, seed) in [
        (8usize, 8usize, 4usize, 7u64),
        (32, 32, 16, 2024),
        (13, 7, 4, 9),
    ] {
        let tex = RefTexture::random(w, h, 1, 255, seed);
        let texels = tex.texels_as::<u8>();
        let t = Texture::<u8>::new(&texels, w, h).unwrap();
        let mut flat_st = vec![0u32; w * h];
        let flat = Sat::build(&t, &mut flat_st).unwrap();
        let spec = TiledSpec::tiles(r as u32, r as u32).unwrap();
        let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, w, h, 8).unwrap()];
        let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
        let tiled = Tiled::<u32>::build(&t, spec, &mut words, &mut scratch).unwrap();
        let lit = CrowLiteral::build(&tex, r, 8);
        let ex = Exact::new(&tex);
        for y in 0..=h {
            for x in 0..=w {
                assert_eq!(tiled.corner(x, y, &mut NoCount)[0] as u128, ex.s(x, y, 0));
            }
        }
        let (mut lit_wrong, mut n) = (0, 0);
        for (x0, y0, x1, y1) in boxes(w, h) {
            let rect = Rect::new(x0 as i32, y0 as i32, x1 as i32, y1 as i32);
            let a = tiled.box_sum_int(&rect, Border, &mut NoCount).unwrap();
            let b = flat.box_sum_int(&rect, Border, &mut NoCount).unwrap();
            assert_eq!(a, b, "{w}x{h} tiles {r}: {rect:?}");
            let want = ex.box_sum(x0, y0, x1, y1, 0);
            assert_eq!(a.sum() as i128, want);
            n += 1;
            if lit.box_sum(x0, y0, x1, y1, 0) != want {
                lit_wrong += 1;
            }
        }
        println!("{w}x{h} R={r}: tiled exact on all {n} boxes; Crow literal wrong on {lit_wrong}");
        assert!(lit_wrong > 0);
    }
}
