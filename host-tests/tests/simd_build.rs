//! The build rows against an independent reference, sized and valued to exercise the vectorized
//! kernels (feature `simd`, src/simd.rs): every width across several 16-texel blocks and their
//! tails, texels biased to 0 and 255 (the 16-bit in-block sums at their largest), tall tables
//! whose entries approach the width proof's bound. Without the feature the same tests check the
//! portable path. Run with the kernels: `cargo test -p texsat-host-tests --features simd --test
//! simd_build` (the widest kernel this CPU runs; the core's unit tests run every one).

use proptest::prelude::*;
use texsat::layouts::{Modular, ModularBuilder, Tiled, TiledSpec};
use texsat::{Layout, NoCount, RowStreamBuilder, Sat, Texture};
use texsat_host_tests::RngExt;

/// Inclusive 2-D prefix sums in `u64`, one channel: the textbook recurrence, nothing shared
/// with the crate.
fn reference(t: &[u8], w: usize, h: usize) -> Vec<u64> {
    let mut s = vec![0u64; w * h];
    for y in 0..h {
        for x in 0..w {
            let left = if x > 0 { s[y * w + x - 1] } else { 0 };
            let up = if y > 0 { s[(y - 1) * w + x] } else { 0 };
            let diag = if x > 0 && y > 0 {
                s[(y - 1) * w + x - 1]
            } else {
                0
            };
            s[y * w + x] = u64::from(t[y * w + x]) + left + up - diag;
        }
    }
    s
}

fn texel() -> impl Strategy<Value = u8> {
    prop_oneof![Just(0u8), Just(255u8), any::<u8>()]
}

fn case() -> impl Strategy<Value = (usize, usize, Vec<u8>)> {
    (1usize..=100, 1usize..=12)
        .prop_flat_map(|(w, h)| (Just(w), Just(h), proptest::collection::vec(texel(), w * h)))
}

/// Builds with `Sat::build` and with `RowStreamBuilder`, into storage that starts dirty, and
/// compares both with the reference.
fn check(w: usize, h: usize, t: &[u8]) -> Result<(), TestCaseError> {
    let want = reference(t, w, h);
    let texture = Texture::<u8>::new(t, w, h).unwrap();
    let mut storage = vec![0xDEAD_BEEFu32; w * h + 3];
    let built = Sat::build(&texture, &mut storage)
        .unwrap()
        .entries()
        .to_vec();
    for (i, (&got, &want)) in built.iter().zip(&want).enumerate() {
        prop_assert_eq!(u64::from(got), want, "entry {} of {}x{}", i, w, h);
    }
    prop_assert_eq!(&storage[w * h..], &[0xDEAD_BEEF; 3], "wrote past the table");
    let mut row = vec![0x5555_5555u32; w];
    let mut b = RowStreamBuilder::<u32>::new(w, h, 8, &mut row).unwrap();
    let mut row2 = vec![0x5555_5555u32; w];
    let mut b2 = RowStreamBuilder::<u32>::new(w, h, 8, &mut row2).unwrap();
    let mut table = vec![0xDEAD_BEEFu32; w * h];
    for y in 0..h {
        let texels = &t[y * w..(y + 1) * w];
        b2.push_row_into(texels, &mut table[y * w..(y + 1) * w])
            .unwrap();
        let got = b.push_row(texels).unwrap();
        for (x, (&got, &want)) in got.iter().zip(&want[y * w..(y + 1) * w]).enumerate() {
            prop_assert_eq!(
                u64::from(got),
                want,
                "streamed ({}, {}) of {}x{}",
                x,
                y,
                w,
                h
            );
        }
    }
    prop_assert_eq!(b2.finish().unwrap(), b.finish().unwrap());
    prop_assert_eq!(table, built, "push_row_into's table");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn builds_equal_the_reference((w, h, t) in case()) {
        check(w, h, &t)?;
    }
}

/// The tiled build (`Tiled::build`, whose row step has its own kernels: `simd::tiled_row`,
/// the local sums of 8 x 8 tiles packed in the kernel) against the reference: every corner,
/// for tiles of 8 x 8, 8 x 4, 4 x 8 and 16 x 2 (the kernel's tile widths; rows of many blocks
/// and tails; row starts on and off byte boundaries), into words that start dirty.
fn check_tiled(w: usize, h: usize, t: &[u8]) -> Result<(), TestCaseError> {
    let want = reference(t, w, h);
    let texture = Texture::<u8>::new(t, w, h).unwrap();
    for (tx, ty) in [(8, 8), (8, 4), (4, 8), (16, 2)] {
        let spec = TiledSpec::tiles(tx, ty).unwrap();
        let mut words = vec![0xA5A5_A5A5u32; Tiled::<u32>::words_needed(spec, w, h, 8).unwrap()];
        let mut scratch = vec![0x5555_5555u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
        let tiled = Tiled::<u32>::build(&texture, spec, &mut words, &mut scratch).unwrap();
        for y in 0..=h {
            for x in 0..=w {
                let s = if x == 0 || y == 0 {
                    0
                } else {
                    want[(y - 1) * w + x - 1]
                };
                prop_assert_eq!(
                    u64::from(tiled.corner(x, y, &mut NoCount)[0]),
                    s,
                    "{:?} corner ({}, {}) of {}x{}",
                    (tx, ty),
                    x,
                    y,
                    w,
                    h
                );
            }
        }
    }
    Ok(())
}

fn tiled_case() -> impl Strategy<Value = (usize, usize, Vec<u8>)> {
    (1usize..=200, 1usize..=20)
        .prop_flat_map(|(w, h)| (Just(w), Just(h), proptest::collection::vec(texel(), w * h)))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn tiled_builds_equal_the_reference((w, h, t) in tiled_case()) {
        check_tiled(w, h, &t)?;
    }
}

/// The tiled build of every width from 1 to 100 (six blocks and a tail), 17 rows, texels all
/// 255 and a ramp: the largest local sums, pairs and odd blocks of the packing kernel.
#[test]
fn tiled_builds_of_every_width() {
    for w in 1..=100 {
        let h = 17;
        check_tiled(w, h, &vec![255u8; w * h]).unwrap();
        let ramp: Vec<u8> = (0..w * h).map(|i| (i * 7 % 256) as u8).collect();
        check_tiled(w, h, &ramp).unwrap();
    }
}

/// The tiled and modular layout combined (8 x 8 tiles, every field modulo `2^m`): the local
/// sums of 8-bit texels are 14 bits, so at `m` = 8 to 12 the packing kernel stores `m`-bit
/// fields whose sums it must mask (`m` = 14, 16: the fields as they are, or too wide to pack).
/// Every corner against the reference modulo `2^m`, widths around one, two and three pairs of
/// blocks and beyond, heights with and without a tile row's end, saturated and random texels,
/// into dirty words.
#[test]
fn tiled_modular_builds_equal_the_reference() {
    let mut rng = texsat_host_tests::rng(0x7113);
    for m in [8u32, 10, 12, 14, 16] {
        let spec = TiledSpec::tiles(8, 8).unwrap().with_modulus(m);
        for w in [1usize, 31, 32, 33, 47, 64, 65, 96, 100, 131] {
            for h in [3usize, 9, 17] {
                let random: Vec<u8> = (0..w * h).map(|_| rng.random_range(0..=255u8)).collect();
                for t in [vec![255u8; w * h], random] {
                    let want = reference(&t, w, h);
                    let texture = Texture::<u8>::new(&t, w, h).unwrap();
                    let mut words =
                        vec![0xA5A5_A5A5u32; Tiled::<u32>::words_needed(spec, w, h, 8).unwrap()];
                    let mut scratch =
                        vec![0x5555_5555u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
                    let tiled =
                        Tiled::<u32>::build(&texture, spec, &mut words, &mut scratch).unwrap();
                    let low = (1u64 << m) - 1;
                    for y in 1..=h {
                        for x in 1..=w {
                            assert_eq!(
                                u64::from(tiled.corner(x, y, &mut NoCount)[0]) & low,
                                want[(y - 1) * w + x - 1] & low,
                                "m {m}, {w}x{h}, corner ({x}, {y})"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// Every width from 1 to 80 (five blocks) at a few heights, all texels 255: the largest sums
/// every lane can see.
#[test]
fn saturated_textures_of_every_width() {
    for w in 1..=80 {
        for h in [1, 2, 17] {
            check(w, h, &vec![255u8; w * h]).unwrap();
        }
    }
}

/// Wide rows (4104 texels, the widest square the width proof accepts for u32 entries, Crow §3.0)
/// of mostly 255: hundreds of blocks per row carrying one running sum. (Entries near 2^32, where
/// a wrap would show, are covered by the unit tests in src/simd.rs, whose rows above are.)
#[test]
fn wide_rows() {
    let (w, h) = (4104, 64);
    let t: Vec<u8> = (0..w * h)
        .map(|i| if i % 97 == 0 { 0 } else { 255 })
        .collect();
    check(w, h, &t).unwrap();
}

/// Tables of 32 MiB and more, which `Sat::build` and `RowStreamBuilder::push_row_into` write by
/// non-temporal stores with `simd` (`Sat::build`: through its working row, rows of at most
/// 4,096 entries, each row whose copy starts on 16 bytes; docs/benchmarks.md, sixth and eighth
/// sessions): 4,096 x 2,048 and 4,092 x 2,052 (a tail of 12 after the blocks) take that path,
/// 4,100 x 2,048 does not (too wide: the row-by-row build); a table 4 bytes off 16 takes the
/// working row with plain stores (and `push_row_into`'s copy plain stores); random texels.
/// Every entry against the reference, through `check`.
#[test]
fn large_tables() {
    let mut rng = texsat_host_tests::rng(0x5717);
    for (w, h) in [(4096, 2048), (4092, 2052), (4100, 2048)] {
        let t: Vec<u8> = (0..w * h).map(|_| rng.random_range(0..=255u8)).collect();
        check(w, h, &t).unwrap();
    }
    let (w, h) = (4096, 2048);
    let t: Vec<u8> = (0..w * h).map(|_| rng.random_range(0..=255u8)).collect();
    let want = reference(&t, w, h);
    let texture = Texture::<u8>::new(&t, w, h).unwrap();
    let mut storage = vec![0xDEAD_BEEFu32; w * h + 4];
    // The first index whose address is 4 bytes past a multiple of 16.
    let off = (0..4)
        .find(|&i| (storage.as_ptr() as usize + 4 * i) % 16 == 4)
        .unwrap();
    let built = Sat::build(&texture, &mut storage[off..off + w * h]).unwrap();
    assert!(built
        .entries()
        .iter()
        .zip(&want)
        .all(|(&g, &w)| u64::from(g) == w));
    // Nothing written around the table.
    let around = |s: &[u32]| {
        s[..off]
            .iter()
            .chain(&s[off + w * h..])
            .all(|&v| v == 0xDEAD_BEEF)
    };
    assert!(around(&storage));
    let mut row = vec![0u32; w];
    let mut b = RowStreamBuilder::<u32>::new(w, h, 8, &mut row).unwrap();
    let mut whole = vec![0xDEAD_BEEFu32; w * h + 4];
    let table = &mut whole[off..off + w * h];
    for (src, dst) in t.chunks_exact(w).zip(table.chunks_exact_mut(w)) {
        b.push_row_into(src, dst).unwrap();
    }
    assert!(table.iter().zip(&want).all(|(&g, &w)| u64::from(g) == w));
    assert!(around(&whole));
}

/// `push_row_into` on the portable path (u16 texels, 3 channels, u64 entries): the same rows as
/// `push_row` and a copy, and a refused `out` (wrong length) leaves `out` and the builder as they
/// were.
#[test]
fn push_row_into_equals_push_row_and_a_copy() {
    let (w, h) = (13, 5);
    let mut rng = texsat_host_tests::rng(7);
    let t: Vec<u16> = (0..w * h * 3)
        .map(|_| rng.random_range(0..=u16::MAX))
        .collect();
    let mut row = vec![0u64; w * 3];
    let mut row2 = vec![0u64; w * 3];
    let mut a = RowStreamBuilder::<u64, 3>::new(w, h, 16, &mut row).unwrap();
    let mut b = RowStreamBuilder::<u64, 3>::new(w, h, 16, &mut row2).unwrap();
    for y in 0..h {
        let texels = &t[y * w * 3..(y + 1) * w * 3];
        let mut short = vec![7u64; w * 3 - 1];
        assert!(b.push_row_into(texels, &mut short).is_err());
        assert!(short.iter().all(|&v| v == 7));
        let mut out = vec![7u64; w * 3];
        b.push_row_into(texels, &mut out).unwrap();
        assert_eq!(out, a.push_row(texels).unwrap(), "row {y}");
    }
    assert!(b
        .push_row_into(&t[..w * 3], &mut vec![0u64; w * 3])
        .is_err());
    assert_eq!(a.finish().unwrap(), b.finish().unwrap());
}

/// Modular builds of widths that take the fused AVX2 row (`simd` on an AVX2 or AVX-512 CPU: at
/// least 256 texels, `w k` a multiple of 32; passes of 256 and a tail) and
/// of widths beside them that do not: every corner against the reference modulo `2^k`, into
/// dirty words and a dirty working row; texels all 255 and random.
#[test]
fn modular_builds_equal_the_reference() {
    let mut rng = texsat_host_tests::rng(0x3d0d);
    let cases: &[(usize, &[u32])] = &[
        (256, &[11, 12, 13, 16, 17, 21, 24, 27, 31, 32]),
        (288, &[11, 21, 32]),
        (300, &[16, 24, 32, 21]),
        (552, &[11, 21, 23]),
        (255, &[21]),
        (800, &[21]),
    ];
    for &(w, ks) in cases {
        for &k in ks {
            for h in [1usize, 6] {
                let random: Vec<u8> = (0..w * h).map(|_| rng.random_range(0..=255u8)).collect();
                for t in [vec![255u8; w * h], random] {
                    let want = reference(&t, w, h);
                    let texture = Texture::<u8>::new(&t, w, h).unwrap();
                    let mut words =
                        vec![0xA5A5_A5A5u32; Modular::<u32>::words_needed(w, h, k).unwrap() + 2];
                    let mut row = vec![0x5555_5555u32; w];
                    let m = Modular::<u32>::build(&texture, k, &mut words, &mut row).unwrap();
                    let low = if k == 32 {
                        u64::from(u32::MAX)
                    } else {
                        (1u64 << k) - 1
                    };
                    for y in 1..=h {
                        for x in 1..=w {
                            assert_eq!(
                                u64::from(m.corner(x, y, &mut NoCount)[0]),
                                want[(y - 1) * w + x - 1] & low,
                                "k {k}, {w}x{h}, corner ({x}, {y})"
                            );
                        }
                    }
                    let n = Modular::<u32>::words_needed(w, h, k).unwrap();
                    assert_eq!(&words[n..], &[0xA5A5_A5A5; 2], "wrote past the table");
                }
            }
        }
    }
}

/// Modular layouts of 32 MiB and more, whose fused rows (`simd`, on a CPU with AVX-512 VL)
/// store their words by non-temporal stores where a row starts on 16 bytes and by plain stores
/// where it does not: 4,096 x 3,200 (`k` = 21, every row on 16 bytes when the layout is, and
/// 4 bytes off 16 when it is not) and 4,128 x 3,104 (each row 4 bytes further off 16 than the
/// one before: both kinds of row in one build). Every corner against the reference modulo
/// `2^k`; nothing written around the layout.
#[test]
fn large_modular_layouts() {
    let mut rng = texsat_host_tests::rng(0x1a7e);
    let k = 21;
    for (w, h, offs) in [(4096, 3200, &[0usize, 1][..]), (4128, 3104, &[0][..])] {
        let t: Vec<u8> = (0..w * h).map(|_| rng.random_range(0..=255u8)).collect();
        let want = reference(&t, w, h);
        let texture = Texture::<u8>::new(&t, w, h).unwrap();
        let n = Modular::<u32>::words_needed(w, h, k).unwrap();
        assert!(4 * n >= 32 << 20, "{w}x{h}: {} bytes, under 32 MiB", 4 * n);
        let mut row = vec![0x5555_5555u32; w];
        let mut words = vec![0xA5A5_A5A5u32; n + 8];
        // The first index on 16 bytes, then `off` words past it.
        let on16 = (0..4)
            .find(|&i| (words.as_ptr() as usize + 4 * i).is_multiple_of(16))
            .unwrap();
        for &off in offs {
            words.fill(0xA5A5_A5A5);
            let at = on16 + off;
            let m = Modular::<u32>::build(&texture, k, &mut words[at..at + n], &mut row).unwrap();
            for y in 1..=h {
                for x in 1..=w {
                    let got = u64::from(m.corner(x, y, &mut NoCount)[0]);
                    if got != want[(y - 1) * w + x - 1] & ((1 << k) - 1) {
                        panic!("{w}x{h}, off {off}: corner ({x}, {y}) is {got}");
                    }
                }
            }
            assert!(words[..at].iter().all(|&v| v == 0xA5A5_A5A5));
            assert!(words[at + n..].iter().all(|&v| v == 0xA5A5_A5A5));
        }
    }
}

/// A modular build whose rows change texel type part-way (`u8`, then `u16` with the same
/// values, then `u8`): the fused row takes the `u8` rows until a `u16` row arrives, then the
/// working row goes back to position order and the portable row takes the rest; the table
/// equals the reference.
#[test]
fn modular_builds_across_texel_types() {
    let mut rng = texsat_host_tests::rng(0x51de);
    let (w, h, k) = (512usize, 5usize, 21u32);
    let t: Vec<u8> = (0..w * h).map(|_| rng.random_range(0..=255u8)).collect();
    let want = reference(&t, w, h);
    let mut words = vec![0u32; Modular::<u32>::words_needed(w, h, k).unwrap()];
    let mut row = vec![7u32; w];
    let mut b = ModularBuilder::<u32>::new(w, h, 8, k, &mut words, &mut row).unwrap();
    for y in 0..h {
        let r = &t[y * w..][..w];
        if y == 2 {
            let wide: Vec<u16> = r.iter().map(|&v| u16::from(v)).collect();
            b.push_row(&wide).unwrap();
        } else {
            b.push_row(r).unwrap();
        }
    }
    let m = b.finish().unwrap();
    for y in 1..=h {
        for x in 1..=w {
            assert_eq!(
                u64::from(m.corner(x, y, &mut NoCount)[0]),
                want[(y - 1) * w + x - 1] & ((1 << k) - 1),
                "corner ({x}, {y})"
            );
        }
    }
}

/// The tiled builder's band rows (`simd::band_row`: the rows inside a tile row of tiles 8
/// wide kept as 16-bit column sums, turned back into the accumulator before a row that ends a
/// tile row): tile heights 2, 4, 8, 16 and 32 (a tile's sum of saturated texels just below
/// 2^16) and two levels per axis (`[8, 32]`, rows that end both levels), tile heights 33 and
/// 36 (a tile's sum past 2^16, local sums within 16 bits: no band), y without levels (no
/// band), widths around one and several blocks and a tail, saturated and random texels, tile
/// rows all of `u8` and rows of `u16` texels (the same values) at the start, inside and at the
/// end of a tile row (the band left and entered again). Every corner against the reference,
/// into dirty words.
#[test]
fn tiled_band_rows_equal_the_reference() {
    use texsat::layouts::{AxisLevels, TiledBuilder};
    let mut rng = texsat_host_tests::rng(0xba2d);
    let specs = [
        TiledSpec::tiles(8, 8).unwrap(),
        TiledSpec::tiles(8, 2).unwrap(),
        TiledSpec::tiles(8, 4).unwrap(),
        TiledSpec::tiles(8, 16).unwrap(),
        // A tile's sum of u8 texels at the 16-bit bound (8 x 32: 65,280, band rows) and past
        // it (8 x 33, 8 x 36: the reference path), though the local sums fit 16 bits.
        TiledSpec::tiles(8, 32).unwrap(),
        TiledSpec::tiles(8, 33).unwrap(),
        TiledSpec::tiles(8, 36).unwrap(),
        TiledSpec::square(&[8, 32]).unwrap(),
        TiledSpec {
            x: AxisLevels::new(&[8]).unwrap(),
            y: AxisLevels::FLAT,
            modulus: None,
        },
    ];
    for spec in specs {
        for w in [16usize, 17, 23, 31, 32, 40, 47, 64, 100, 263] {
            for (h, wide_rows) in [
                (21usize, &[][..]),
                (40, &[][..]),
                (40, &[0usize, 3, 7, 8, 15, 33][..]),
            ] {
                for full in [true, false] {
                    let t: Vec<u8> = (0..w * h)
                        .map(|_| {
                            if full {
                                255
                            } else {
                                rng.random_range(0..=255u8)
                            }
                        })
                        .collect();
                    let want = reference(&t, w, h);
                    let mut words =
                        vec![0xA5A5_A5A5u32; Tiled::<u32>::words_needed(spec, w, h, 8).unwrap()];
                    let mut scratch =
                        vec![0x5555_5555u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
                    let mut b =
                        TiledBuilder::<u32>::new(spec, w, h, 8, &mut words, &mut scratch).unwrap();
                    for y in 0..h {
                        let r = &t[y * w..][..w];
                        if wide_rows.contains(&y) {
                            let wide: Vec<u16> = r.iter().map(|&v| u16::from(v)).collect();
                            b.push_row(&wide).unwrap();
                        } else {
                            b.push_row(r).unwrap();
                        }
                    }
                    let tiled = b.finish().unwrap();
                    for y in 1..=h {
                        for x in 1..=w {
                            assert_eq!(
                                u64::from(tiled.corner(x, y, &mut NoCount)[0]),
                                want[(y - 1) * w + x - 1],
                                "{spec:?} {w}x{h} corner ({x}, {y})"
                            );
                        }
                    }
                }
            }
        }
    }
}
