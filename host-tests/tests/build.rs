//! Crow's cost table (§2.2) asserted with `Tally`, the width analysis' examples (§3.0), and the
//! build's refusals.

use fixed::types::{I16F16, I24F8, I28F4};
use texsat::width::{self, bits_of};
use texsat::{
    Border, Entry, Error, MirroredRepeat, NoCount, Paper, Quantity, Rect, Repeat, RowStreamBuilder,
    Sat, Shortcut, Stable, Tally, Texture,
};
use texsat_host_tests::{
    acc_value_bits_for_entry, build_sat, mean_shortcut, rect_from_raw, sum_fixed, sum_int, RefForm,
    RefMode, RefTexel, RefTexture, RngExt,
};

// Crow §3.0 and the exact width proof, checked at compile time.
const _: () = assert!(width::entry_bits_worst_case(8, 4104, 4104) == 32);
const _: () = assert!(width::entry_bits_worst_case(8, 4105, 4105) == 33);
const _: () = assert!(width::entry_bits_naive(8, 4104, 4104) == 33);
const _: () = assert!(width::check_entry_worst_case(8, 4104, 4104, 32).is_ok());
const _: () = assert!(width::check_entry_worst_case(8, 4105, 4105, 32).is_err());
const _: () = assert!(width::entry_bits_worst_case(8, 1024, 1024) == 28);
const _: () = assert!(width::entry_bits_worst_case(8, 256, 256) == 24);

/// `(reads, bits_read, muls, divs, adds)`.
fn counts(k: &Tally) -> (u64, u64, u64, u64, u64) {
    (k.reads, k.bits_read, k.muls, k.divs, k.adds)
}

/// Crow's table for an interior box, single channel, entry type `E`:
/// integer corners 4 reads / 1 mul + 1 div / 3 adds; Paper 16 / 13 + 1 / 27; Stable
/// 16 / 13 + 1 / 31; `bits_read = reads * E::BITS`.
fn crow_table_c1<E: Entry>() {
    let tex = RefTexture::random(9, 7, 1, 255, 1);
    let mut st = vec![E::ZERO; 63];
    let sat = build_sat::<u8, E, 1>(&tex, &mut st).unwrap();
    let eb = E::BITS as u64;
    let mut rng = texsat_host_tests::rng(2);
    let mut refused = 0;
    for _ in 0..50 {
        // Interior: every corner off row and column 0.
        let x0: i64 = rng.random_range(1..=8);
        let y0: i64 = rng.random_range(1..=6);
        let r = [
            x0,
            y0,
            rng.random_range(x0 + 1..=9),
            rng.random_range(y0 + 1..=7),
        ];
        let ri = r.map(|v| v as i32);
        let mut k = Tally::new();
        let s = sum_int(&sat, ri, RefMode::Border, &mut k).unwrap();
        s.mean_rounded(0, 8, &mut k).unwrap();
        assert_eq!(counts(&k), (4, 4 * eb, 1, 1, 3), "{ri:?}");
        assert_eq!(k.multiplicative(), 2);

        // Fractional corners, any F, both forms.
        let f = [4u32, 8, 16][rng.random_range(0..3) as usize];
        let one = 1i64 << f;
        let x0 = rng.random_range(one..=8 * one);
        let y0 = rng.random_range(one..=6 * one);
        let b = [
            x0,
            y0,
            rng.random_range(x0 + 1..=9 * one),
            rng.random_range(y0 + 1..=7 * one),
        ];
        for (form, adds) in [(RefForm::Paper, 27), (RefForm::Stable, 31)] {
            let mut k = Tally::new();
            let s = match f {
                4 => sum_fixed(
                    &sat,
                    &rect_from_raw::<I28F4>(b),
                    form,
                    RefMode::Border,
                    &mut k,
                ),
                8 => sum_fixed(
                    &sat,
                    &rect_from_raw::<I24F8>(b),
                    form,
                    RefMode::Border,
                    &mut k,
                ),
                _ => sum_fixed(
                    &sat,
                    &rect_from_raw::<I16F16>(b),
                    form,
                    RefMode::Border,
                    &mut k,
                ),
            };
            // A u16 table computes in i32 (31 value bits): Paper needs `total_bits + 2F`, Stable
            // one more; this texture's total has 14 bits, so F = 16 is refused on u16 (and
            // costs nothing), F = 4 and 8 fit. (Before the i32 accumulator every F was answered.)
            let needed = bits_of(tex.total(0)) + 2 * f + (form == RefForm::Stable) as u32;
            let acc = acc_value_bits_for_entry(E::BITS);
            if needed > acc {
                assert_eq!(E::BITS, 16);
                assert_eq!(
                    s.unwrap_err(),
                    Error::TooWide {
                        what: Quantity::LookupAccumulator,
                        bits_needed: needed,
                        bits_available: acc
                    }
                );
                assert_eq!(counts(&k), (0, 0, 0, 0, 0), "{form:?} {b:?}");
                refused += 1;
                continue;
            }
            let s = s.unwrap();
            assert_eq!(counts(&k), (16, 16 * eb, 12, 0, adds), "{form:?} {b:?}");
            s.mean_rounded(0, 8, &mut k).unwrap();
            assert_eq!(counts(&k), (16, 16 * eb, 13, 1, adds), "{form:?} {b:?}");
            assert_eq!(k.multiplicative(), 14);
        }
    }
    // Only the u16 table refuses (F = 16), and the draws reach it.
    assert_eq!(refused > 0, E::BITS == 16, "{refused} refusals");
}

#[test]
fn crow_cost_table_u16_entries() {
    crow_table_c1::<u16>();
}

#[test]
fn crow_cost_table_u32_entries() {
    crow_table_c1::<u32>();
}

#[test]
fn crow_cost_table_u64_entries() {
    crow_table_c1::<u64>();
}

/// Three channels: reads (and the area multiply) do not scale with the channel count; value
/// arithmetic does; Stable's four fraction products are shared (`4 + 8C` multiplies).
fn crow_table_c3<T: RefTexel, E: Entry>(max: u32) {
    let tex = RefTexture::random(6, 5, 3, max, 3);
    let mut st = vec![E::ZERO; 90];
    let sat = build_sat::<T, E, 3>(&tex, &mut st).unwrap();
    let bits = E::BITS as u64 * 3;

    let mut k = Tally::new();
    let s = sum_int(&sat, [1, 2, 5, 4], RefMode::Border, &mut k).unwrap();
    assert_eq!(counts(&k), (4, 4 * bits, 0, 0, 9));
    s.mean_rounded(2, 0, &mut k).unwrap();
    assert_eq!(counts(&k), (4, 4 * bits, 1, 1, 9));
    s.means_rounded(0, &mut k).unwrap();
    assert_eq!(counts(&k), (4, 4 * bits, 2, 4, 9));

    let r = Rect::<I24F8>::from_f64(1.25, 1.5, 4.75, 3.125).unwrap();
    let mut k = Tally::new();
    let s = sat.box_sum(&r, Paper, Border, &mut k).unwrap();
    assert_eq!(counts(&k), (16, 16 * bits, 36, 0, 81));
    s.means_rounded(8, &mut k).unwrap();
    assert_eq!(counts(&k), (16, 16 * bits, 37, 3, 81));

    let mut k = Tally::new();
    let s = sat.box_sum(&r, Stable, Border, &mut k).unwrap();
    assert_eq!(counts(&k), (16, 16 * bits, 4 + 8 * 3, 0, 93));
    s.means_rounded(8, &mut k).unwrap();
    assert_eq!(counts(&k), (16, 16 * bits, 4 + 8 * 3 + 1, 3, 93));
}

#[test]
fn crow_cost_table_three_channels() {
    crow_table_c3::<u8, u16>(255);
    crow_table_c3::<u8, u32>(255);
    crow_table_c3::<u16, u32>(65535);
    crow_table_c3::<u16, u64>(65535);
}

#[test]
fn corners_on_the_zero_row_and_column_cost_no_read() {
    let tex = RefTexture::random(5, 4, 1, 255, 4);
    let mut st = vec![0u32; 20];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    let int_reads = |r: [i32; 4]| {
        let mut k = Tally::new();
        sum_int(&sat, r, RefMode::Border, &mut k).unwrap();
        (k.reads, k.adds)
    };
    assert_eq!(int_reads([0, 0, 3, 3]), (1, 3));
    assert_eq!(int_reads([0, 1, 3, 3]), (2, 3));
    assert_eq!(int_reads([2, 0, 5, 4]), (2, 3));
    assert_eq!(int_reads([2, 1, 5, 4]), (4, 3));
    // Fractional: corner (0.5, 0.5) is cell (0, 0): only S(1, 1) is read. The corner
    // (3.5, 0.5) reads S(3, 1), S(4, 1); (0.5, 2.5) reads S(1, 2), S(1, 3); (3.5, 2.5) all 4.
    let r = Rect::<I24F8>::from_f64(0.5, 0.5, 3.5, 2.5).unwrap();
    for (form, adds) in [(RefForm::Paper, 27), (RefForm::Stable, 31)] {
        let mut k = Tally::new();
        sum_fixed(&sat, &r, form, RefMode::Border, &mut k).unwrap();
        assert_eq!((k.reads, k.muls, k.adds), (9, 12, adds), "{form:?}");
    }
}

#[test]
fn placed_boxes_cost_the_same_as_interior_ones() {
    let tex = RefTexture::random(5, 4, 1, 255, 5);
    let mut st = vec![0u32; 20];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    // [1.25, 3.5) x [1.5, 2.75) shifted by 7 periods (Repeat) and reflected (Mirror).
    let base = [320i64, 384, 896, 704];
    let (pw, ph) = (5 * 256, 4 * 256);
    let repeat = [
        base[0] + 7 * pw,
        base[1] - 3 * ph,
        base[2] + 7 * pw,
        base[3] - 3 * ph,
    ];
    // Mirror: x -> 2w - x maps [a, b) to [2w - b, 2w - a); plus 2 double periods.
    let mirror = [
        2 * pw - base[2] + 4 * pw,
        base[1],
        2 * pw - base[0] + 4 * pw,
        base[3],
    ];
    for (mode, b) in [
        (RefMode::Border, base),
        (RefMode::Repeat, repeat),
        (RefMode::Mirror, mirror),
    ] {
        for (form, adds) in [(RefForm::Paper, 27), (RefForm::Stable, 31)] {
            let mut k = Tally::new();
            let s = sum_fixed(&sat, &rect_from_raw::<I24F8>(b), form, mode, &mut k).unwrap();
            assert_eq!(
                (k.reads, k.muls, k.adds),
                (16, 12, adds),
                "{mode:?} {form:?}"
            );
            assert_eq!(s.sum(), tex.exact_integral(RefMode::Border, base, 8, 0));
        }
    }
    // A box with no in-range equivalent is split into at most 3 x 3 in-range pieces
    // (src/edge.rs, src/lookup/split.rs). The removed weighted path was only bounded here
    // (`1 <= reads <= 36`); the split path's counts follow from its pieces, worked out by hand:
    // each piece is an ordinary in-range lookup, plus per channel one multiply per multiplicity
    // other than 1 and one addition per piece after the first.
    //
    // Integer corners, Repeat, [-12, 13) x [-9, 11) on 5 x 4: x = [3, 5) + 4 x [0, 5) + [0, 3),
    // y = [3, 4) + 4 x [0, 4) + [0, 3). A 4-read piece reads the corners off row and column 0:
    // per axis 2, 1, 1 of them, so (2 + 1 + 1)^2 = 16 reads; 9 pieces x 3 additions + 8 to
    // combine = 35; multiplies: the 3 pieces with x multiplicity 4 and the 3 with y
    // multiplicity 4: 6.
    let xs = [(3, 5, 1u128), (0, 5, 4), (0, 3, 1)];
    let ys = [(3, 4, 1u128), (0, 4, 4), (0, 3, 1)];
    let mut k = Tally::new();
    let r = Rect::new(-12, -9, 13, 11);
    let s = sat.box_sum_int(&r, Repeat, &mut k).unwrap();
    let want = tex.int_sums(RefMode::Repeat, [-12, -9, 13, 11])[0];
    assert_eq!(u128::from(s.sum()), want);
    assert_eq!((k.reads, k.muls, k.divs, k.adds), (16, 6, 0, 35), "{k:?}");
    // The pieces themselves (Border lookups inside the texture) sum to the same.
    let mut by_pieces = 0u128;
    for &(x0, x1, mx) in &xs {
        for &(y0, y1, my) in &ys {
            let p = sum_int(&sat, [x0, y0, x1, y1], RefMode::Border, &mut NoCount).unwrap();
            by_pieces += mx * my * p.sum();
        }
    }
    assert_eq!(by_pieces, want);

    // F = 8, Stable, MirroredRepeat, [-3000, 4000) x [-2000, 3000) raw on 5 x 4 (half periods
    // 1280 x 1024 raw): x starts in an odd (reflected) half at 840: head [840, 1280) reflected
    // to [0, 440), 5 whole halves [0, 1280), tail 160 in an odd half, reflected to [1120, 1280);
    // y starts in an even half at 48: [48, 1024), 3 x [0, 1024), tail [0, 952). A 16-read piece
    // reads, per corner, the table values of cells i and i + 1 off row and column 0 (the right
    // edge n 2^F is cell n - 1 with fraction 1): per axis and piece 1 + 2, 1 + 2, 2 + 2 (x) and
    // 1 + 2, 1 + 2, 1 + 2 (y): (3 + 3 + 4) (3 + 3 + 3) = 90 reads; 9 x 12 + 6 = 114
    // multiplies; 9 x 31 + 8 = 287 additions.
    let xs = [(0i64, 440i64, 1u128), (0, 1280, 5), (1120, 1280, 1)];
    let ys = [(48i64, 1024i64, 1u128), (0, 1024, 3), (0, 952, 1)];
    let b = [-3000, -2000, 4000, 3000];
    let mut k = Tally::new();
    let r = rect_from_raw::<I24F8>(b);
    let s = sat.box_sum(&r, Stable, MirroredRepeat, &mut k).unwrap();
    let want = tex.exact_integral(RefMode::Mirror, b, 8, 0);
    assert_eq!(u128::from(s.sum()), want);
    assert_eq!(
        (k.reads, k.muls, k.divs, k.adds),
        (90, 114, 0, 287),
        "{k:?}"
    );
    let mut by_pieces = 0u128;
    let mut piece_reads = 0;
    for &(x0, x1, mx) in &xs {
        for &(y0, y1, my) in &ys {
            let mut pk = Tally::new();
            let r = rect_from_raw::<I24F8>([x0, y0, x1, y1]);
            let p = sum_fixed(&sat, &r, RefForm::Stable, RefMode::Border, &mut pk).unwrap();
            by_pieces += mx * my * p.sum();
            piece_reads += pk.reads;
        }
    }
    assert_eq!(by_pieces, want);
    assert_eq!(piece_reads, 90);
}

#[test]
fn shortcut_costs_four_reads() {
    let tex = RefTexture::random(40, 30, 3, 255, 6);
    let mut st = vec![0u32; 1200 * 3];
    let sat = build_sat::<u8, u32, 3>(&tex, &mut st).unwrap();
    let r = Rect::<I24F8>::from_f64(2.3, 3.7, 31.1, 27.9).unwrap();
    let sc = Shortcut::with_min_side(16);
    let mut k = Tally::new();
    let m = mean_shortcut(&sat, &r, RefForm::Paper, RefMode::Border, &sc, 8, &mut k).unwrap();
    assert!(m.shortcut);
    assert_eq!(counts(&k), (4, 4 * 96, 1, 3, 9));
    // Below min_side: the 16-read lookup and its mean.
    let sc = Shortcut::with_min_side(25);
    let mut k = Tally::new();
    let m = mean_shortcut(&sat, &r, RefForm::Stable, RefMode::Border, &sc, 8, &mut k).unwrap();
    assert!(!m.shortcut);
    assert_eq!(counts(&k), (16, 16 * 96, 4 + 24 + 1, 3, 93));
}

#[test]
fn no_count_is_free() {
    assert_eq!(std::mem::size_of::<NoCount>(), 0);
    assert_eq!(Tally::new(), Tally::default());
}

#[test]
fn width_examples_4104_and_4105() {
    assert_eq!(
        width::check_entry_worst_case(8, 4105, 4105, 32),
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 33,
            bits_available: 32
        })
    );
    assert_eq!(
        width::worst_case_total(8, 4104, 4104),
        4_294_918_080,
        "255 * 4104^2 < 2^32"
    );
    assert_eq!(width::worst_case_total(8, 4105, 4105), 4_297_011_375);
    // The streaming builder needs only a row: the same decision at full size, cheaply.
    let mut row = vec![0u32; 4105];
    assert!(RowStreamBuilder::<u32>::new(4104, 4104, 8, &mut row).is_ok());
    assert_eq!(
        RowStreamBuilder::<u32>::new(4105, 4105, 8, &mut row).unwrap_err(),
        Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 33,
            bits_available: 32
        }
    );
    // Non-square at the boundary: 4104 x 4105 needs 255 * 4104 * 4105 = 4 295 964 600 >= 2^32.
    assert_eq!(width::entry_bits_worst_case(8, 4104, 4105), 33);
    // The exact rule against a brute-force sum of the all-max texture, and the naive bound.
    for b in [1u32, 3, 8, 16] {
        for (w, h) in [
            (1usize, 1usize),
            (2, 3),
            (16, 16),
            (16, 17),
            (257, 1),
            (258, 1),
        ] {
            let exact = width::entry_bits_worst_case(b, w, h);
            let total = ((1u128 << b) - 1) * (w * h) as u128;
            assert_eq!(exact, bits_of(total));
            let naive = width::entry_bits_naive(b, w, h);
            assert!(naive == exact || naive == exact + 1);
        }
    }
}

#[test]
fn u16_entries_at_their_boundary() {
    // 255 * 257 = 65535 fits u16; 255 * 258 does not.
    let ok = RefTexture::constant(257, 1, 1, 255);
    let mut st = vec![0u16; 258];
    let sat = build_sat::<u8, u16, 1>(&ok, &mut st).unwrap();
    assert_eq!(sat.total(), [65535]);
    let bad = RefTexture::constant(258, 1, 1, 255);
    let mut st = vec![7u16; 258];
    assert_eq!(
        build_sat::<u8, u16, 1>(&bad, &mut st).unwrap_err(),
        Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 17,
            bits_available: 16
        }
    );
    assert!(st.iter().all(|&v| v == 7), "nothing written");
    // 16 x 16 fits, 16 x 17 does not.
    assert!(build_sat::<u8, u16, 1>(&RefTexture::constant(16, 16, 1, 0), &mut st).is_ok());
    let mut st = vec![0u16; 272];
    assert!(build_sat::<u8, u16, 1>(&RefTexture::constant(16, 17, 1, 0), &mut st).is_err());
    // The lookup accumulator rules.
    assert_eq!(width::paper_acc_bits(32, 16), 64);
    assert_eq!(width::stable_acc_bits(31, 16), 64);
    assert_eq!(width::MAX_FRAC_BITS, 24);
}

#[test]
fn build_refusals() {
    let data = [1u8; 12];
    assert_eq!(
        Texture::<u8>::new(&data, 0, 3).unwrap_err(),
        Error::EmptyTexture
    );
    assert_eq!(
        Texture::<u8>::new(&data, 3, 0).unwrap_err(),
        Error::EmptyTexture
    );
    assert_eq!(
        Texture::<u8>::with_stride(&data, 4, 2, 3).unwrap_err(),
        Error::StrideTooSmall {
            stride: 3,
            needed: 4
        }
    );
    assert_eq!(
        Texture::<u8, 3>::new(&data, 2, 3).unwrap_err(),
        Error::TextureDataTooShort {
            needed: 18,
            got: 12
        }
    );
    assert_eq!(
        Texture::<u8>::with_stride(&data, 3, 3, 5).unwrap_err(),
        Error::TextureDataTooShort {
            needed: 13,
            got: 12
        }
    );
    assert_eq!(
        Texture::<u8>::new(&data, 1 << 31, 1).unwrap_err(),
        Error::TextureTooLarge { dimension: 1 << 31 }
    );
    let t = Texture::<u8>::new(&data, 4, 3).unwrap();
    let mut short = [9u32; 11];
    assert_eq!(
        Sat::build(&t, &mut short).unwrap_err(),
        Error::StorageTooSmall {
            needed: 12,
            got: 11
        }
    );
    assert!(short.iter().all(|&v| v == 9), "nothing written");
    assert_eq!(
        Sat::build_checked(&t, &mut short).unwrap_err(),
        Error::StorageTooSmall {
            needed: 12,
            got: 11
        }
    );
    // Longer storage: only the first w * h * C entries are used.
    let mut long = [9u32; 15];
    let sat = Sat::build(&t, &mut long).unwrap();
    assert_eq!(sat.entries().len(), 12);
    assert_eq!(sat.entries()[11], 12);
    assert_eq!(&long[12..], &[9, 9, 9]);
}

#[test]
fn stream_builder_refusals() {
    let mut row = [0u32; 8];
    assert_eq!(
        RowStreamBuilder::<u32>::new(0, 2, 8, &mut row).unwrap_err(),
        Error::EmptyTexture
    );
    assert_eq!(
        RowStreamBuilder::<u32, 3>::new(3, 2, 8, &mut row).unwrap_err(),
        Error::StorageTooSmall { needed: 9, got: 8 }
    );
    let mut sb = RowStreamBuilder::<u32>::new(4, 2, 8, &mut row).unwrap();
    assert_eq!(
        sb.push_row(&[1u8, 2, 3]).unwrap_err(),
        Error::RowLength {
            expected: 4,
            got: 3
        }
    );
    assert_eq!(sb.push_row(&[1u8, 2, 3, 4]).unwrap(), &[1, 3, 6, 10]);
    assert_eq!(sb.rows_done(), 1);
    let mut row2 = [0u32; 4];
    let mut sb2 = RowStreamBuilder::<u32>::new(4, 2, 8, &mut row2).unwrap();
    sb2.push_row(&[0u8; 4]).unwrap();
    assert_eq!(
        sb2.finish().unwrap_err(),
        Error::MissingRows {
            got: 1,
            expected: 2
        }
    );
    assert_eq!(sb.push_row(&[1u8, 1, 1, 1]).unwrap(), &[2, 5, 9, 14]);
    assert_eq!(
        sb.push_row(&[1u8, 1, 1, 1]).unwrap_err(),
        Error::TooManyRows
    );
    assert_eq!(sb.finish().unwrap(), &[2, 5, 9, 14]);
}

#[test]
fn from_table_refusals() {
    let tex = RefTexture::random(4, 3, 1, 255, 7);
    let mut st = vec![0u32; 12];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    let table = sat.entries().to_vec();
    assert!(Sat::<u32>::from_table(&table, 4, 3, 8).is_ok());
    for bits in [0u32, 17] {
        assert_eq!(
            Sat::<u32>::from_table(&table, 4, 3, bits).unwrap_err(),
            Error::InvalidTexelBits { bits }
        );
    }
    assert_eq!(
        Sat::<u32>::from_table(&table[..11], 4, 3, 8).unwrap_err(),
        Error::StorageTooSmall {
            needed: 12,
            got: 11
        }
    );
    assert_eq!(
        Sat::<u32>::from_table(&table, 4, 0, 8).unwrap_err(),
        Error::EmptyTexture
    );
    // A table of 8-bit texels is not one of 4-bit texels unless every texel is below 16.
    let max = tex.max_texel();
    assert_eq!(
        Sat::<u32>::from_table(&table, 4, 3, 4).is_ok(),
        max < 16,
        "max texel {max}"
    );
    // Swapping two entries of a strictly increasing row breaks monotonicity.
    let ramp = RefTexture::constant(4, 3, 1, 1);
    let mut st = vec![0u32; 12];
    let sat = build_sat::<u8, u32, 1>(&ramp, &mut st).unwrap();
    let mut bad = sat.entries().to_vec();
    bad.swap(5, 6);
    assert_eq!(
        Sat::<u32>::from_table(&bad, 4, 3, 8).unwrap_err(),
        Error::InvalidTable {
            x: 2,
            y: 1,
            channel: 0
        }
    );
}

#[test]
fn corner_function_is_the_naive_table_shifted() {
    let tex = RefTexture::random(6, 5, 3, 65535, 8);
    let mut st = vec![0u64; 90];
    let sat = build_sat::<u16, u64, 3>(&tex, &mut st).unwrap();
    let naive = tex.naive_table();
    for y in 0..=5 {
        for x in 0..=6 {
            let got = sat.corner(x, y).unwrap();
            for (c, &g) in got.iter().enumerate() {
                let want = if x == 0 || y == 0 {
                    0
                } else {
                    naive[((y - 1) * 6 + (x - 1)) * 3 + c]
                };
                assert_eq!(g as u128, want, "S({x}, {y}) channel {c}");
            }
        }
    }
    assert_eq!(sat.corner(7, 0), None);
    assert_eq!(sat.corner(0, 6), None);
    assert_eq!((sat.width(), sat.height(), sat.texel_bits()), (6, 5, 16));
    assert_eq!(sat.table_bytes(), 90 * 8);
}

// ---- Regressions: input the docs promise to refuse with an error, never a panic -------------
// docs/design.md: "No public function panics on any input".

/// `width::max_texel` computes `(1u128 << texel_bits) - 1`, which overflows for
/// `texel_bits >= 128`; `RowStreamBuilder::new` passes its `texel_bits` argument straight in
/// (it does not check `1..=16` as `Sat::from_table` does), so it panics in debug builds
/// ("attempt to shift left with overflow") instead of returning an error; in release the shift
/// amount wraps and the width decision is garbage. `texel_bits = 100` with large dimensions
/// overflows the `u128` product in `width::worst_case_total` the same way.
#[test]
fn stream_builder_rejects_absurd_texel_bits_without_panicking() {
    let mut row = [0u32; 4];
    let r = std::panic::catch_unwind(move || {
        let mut row = row;
        RowStreamBuilder::<u32>::new(1, 1, 128, &mut row).map(|_| ())
    });
    assert!(matches!(r, Ok(Err(_))), "panicked or accepted: {r:?}");
    let r = std::panic::catch_unwind(move || {
        let mut row = row;
        RowStreamBuilder::<u32>::new((1 << 31) - 1, (1 << 31) - 1, 100, &mut row).map(|_| ())
    });
    assert!(matches!(r, Ok(Err(_))), "panicked or accepted: {r:?}");
    let _ = &mut row;
}

/// `BoxSum::mean_rounded` / `means_rounded` compute `bits_of(num) + g` in `u32` before checking
/// `g`, so a huge output precision (`g = u32::MAX`) with a non-zero sum panics in debug builds
/// ("attempt to add with overflow") instead of returning `TooWide { MeanNumerator, .. }`.
#[test]
fn mean_rounded_rejects_huge_precision_without_panicking() {
    let tex = RefTexture::constant(2, 2, 1, 3);
    let mut st = vec![0u32; 4];
    let sat = build_sat::<u8, u32, 1>(&tex, &mut st).unwrap();
    let s = sat
        .box_sum_int(&Rect::new(0, 0, 2, 2), Border, &mut NoCount)
        .unwrap();
    assert_eq!(s.sum(), 12);
    let r = std::panic::catch_unwind(|| s.mean_rounded(0, u32::MAX, &mut NoCount));
    assert!(
        matches!(
            r,
            Ok(Err(Error::TooWide {
                what: Quantity::MeanNumerator,
                ..
            }))
        ),
        "{r:?}"
    );
}

/// `Sat::from_table` computes `width * height * C` unchecked before comparing with the table
/// length, so dimensions whose product overflows `usize` panic in debug builds instead of being
/// refused (`StorageTooSmall`). On a 64-bit host this needs `C >= 5` at the maximum dimensions;
/// on a 32-bit target (the firmware target) any `width * height >= 2^32` does it, e.g. a corrupt
/// 70000 x 70000 header of a table in flash.
#[test]
fn from_table_rejects_overflowing_dimensions_without_panicking() {
    let r = std::panic::catch_unwind(|| {
        Sat::<u16, 5>::from_table(&[], (1 << 31) - 1, (1 << 31) - 1, 8).map(|_| ())
    });
    assert!(matches!(r, Ok(Err(_))), "{r:?}");
}
