//! Unit tests of the lookups against a direct sum (the full f64 comparisons live in host-tests).

use crate::{
    Border, ClampToEdge, MirroredRepeat, NoCount, Paper, Rect, Repeat, Sat, Stable, Tally, Texture,
};
use fixed::types::I24F8;

const W: usize = 5;
const H: usize = 4;
const TEX: [u8; W * H] = [
    1, 2, 3, 4, 5, //
    6, 7, 8, 9, 10, //
    11, 12, 13, 14, 15, //
    16, 17, 18, 19, 20,
];

fn direct(x0: usize, y0: usize, x1: usize, y1: usize) -> u64 {
    let mut s = 0;
    for y in y0..y1 {
        for x in x0..x1 {
            s += TEX[y * W + x] as u64;
        }
    }
    s
}

#[test]
fn every_integer_box() {
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    for x0 in 0..=W {
        for x1 in x0..=W {
            for y0 in 0..=H {
                for y1 in y0..=H {
                    let r = Rect::new(x0 as i32, y0 as i32, x1 as i32, y1 as i32);
                    let s = sat.box_sum_int(&r, Border, &mut NoCount).unwrap();
                    assert_eq!(s.sum(), direct(x0, y0, x1, y1));
                }
            }
        }
    }
}

#[test]
fn crow_counts() {
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    let mut k = Tally::new();
    let s = sat
        .box_sum_int(&Rect::new(1, 1, 3, 3), Border, &mut k)
        .unwrap();
    s.mean_rounded(0, 0, &mut k).unwrap();
    assert_eq!((k.reads, k.multiplicative(), k.adds), (4, 2, 3));

    let r = Rect::new(
        I24F8::from_num(1.25),
        I24F8::from_num(1.5),
        I24F8::from_num(3.75),
        I24F8::from_num(2.5),
    );
    let mut k = Tally::new();
    let s = sat.box_sum(&r, Paper, Border, &mut k).unwrap();
    s.mean_rounded(0, 8, &mut k).unwrap();
    assert_eq!((k.reads, k.muls, k.divs, k.adds), (16, 13, 1, 27));
    let mut k2 = Tally::new();
    let s2 = sat.box_sum(&r, Stable, Border, &mut k2).unwrap();
    s2.mean_rounded(0, 8, &mut k2).unwrap();
    assert_eq!((k2.reads, k2.muls, k2.divs, k2.adds), (16, 13, 1, 31));
    assert_eq!(s, s2);
}

#[test]
fn modes_agree_with_integer_periods() {
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    let total = direct(0, 0, W, H);
    // Three whole periods in x, two in y, starting at a negative multiple of the period.
    let r = Rect::new(-(W as i32), -2 * H as i32, 2 * W as i32, 0);
    let s = sat.box_sum_int(&r, Repeat, &mut NoCount).unwrap();
    assert_eq!(s.sum(), 6 * total);
    let s = sat.box_sum_int(&r, MirroredRepeat, &mut NoCount).unwrap();
    assert_eq!(s.sum(), 6 * total);
    // Clamp: a box left of the texture sees column 0.
    let s = sat
        .box_sum_int(&Rect::new(-3, 0, 0, H as i32), ClampToEdge, &mut NoCount)
        .unwrap();
    assert_eq!(s.sum(), 3 * direct(0, 0, 1, H));
}

/// Regression (fuzz finding: `lookup/stable.rs:110-112` before the narrow-arithmetic rewrite): a
/// corrupted `Tiled::from_words` storage made the Stable lookup's multiplies and shifts overflow,
/// a panic in builds with overflow checks. Corrupt lent storage must give a wrong sum or
/// `CorruptStorage`, never a panic, for every form, mode and box.
#[test]
fn corrupt_tiled_storage_never_panics() {
    use crate::layouts::{Tiled, TiledSpec};
    use crate::{BoxLookup, EdgeKind, Error, FormKind, FracBits};
    let spec = TiledSpec::tiles(4, 4).unwrap();
    let (w, h) = (9usize, 7usize);
    let mut words = [0u32; 256];
    let need = Tiled::<u32>::words_needed(spec, w, h, 8).unwrap();
    let mut s = 0x2545_F491_4F6C_DD1Du64;
    // Under Miri (about 10^4 times slower) two rounds: one of random words, one of all ones.
    let rounds = if cfg!(miri) { 2 } else { 40 };
    let mut case = 0u32;
    for round in 0..rounds {
        for v in words.iter_mut() {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            *v = if round % 2 == 0 { s as u32 } else { u32::MAX };
        }
        let t = Tiled::<u32>::from_words(&words[..need], spec, w, h, 8).unwrap();
        for f in [0u32, 4, 8, 15] {
            let fb = FracBits::new(f).unwrap();
            for mode in EdgeKind::ALL {
                for form in [FormKind::Paper, FormKind::Stable] {
                    // Under Miri every 3rd case of the round.
                    case += 1;
                    if cfg!(miri) && case % 3 != 1 {
                        continue;
                    }
                    for b in [
                        [0i64, 0, 9, 7],
                        [1, 1, 3, 2],
                        [-3, -2, 12, 20],
                        [5, 6, 40, 7],
                    ] {
                        let r = Rect::new(b[0] << f, b[1] << f, (b[2] << f) + 3, b[3] << f);
                        match t.box_sum_raw(&r, fb, form, mode, &mut NoCount) {
                            Ok(_) | Err(Error::CorruptStorage) | Err(Error::TooWide { .. }) => {}
                            Err(e) => panic!("unexpected {e:?}"),
                        }
                    }
                }
            }
        }
    }
}

/// Boxes crossing the edge are split (edge.rs) and agree with a direct sum over the extended
/// texture for every mode, integer and fractional corners, any number of periods.
#[test]
fn split_boxes_match_direct_sums() {
    use crate::{EdgeKind, FormKind, FracBits};
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    // Direct integral of the extended texture at F = 2, scaled by 2^4, by sub-texel cells.
    let direct_f = |mode: EdgeKind, b: [i64; 4]| -> u64 {
        let mut sum = 0u64;
        for y in b[1]..b[3] {
            for x in b[0]..b[2] {
                let (i, j) = (x.div_euclid(4), y.div_euclid(4));
                if let (Some(i), Some(j)) = (mode.texel_index(i, W), mode.texel_index(j, H)) {
                    sum += TEX[j * W + i] as u64;
                }
            }
        }
        sum
    };
    let fb = FracBits::new(2).unwrap();
    let (mut n, mut case) = (0, 0u32);
    // Under Miri (about 10^4 times slower) coarser steps of the starts (still negative, inside
    // and past the texture), the shortest, a middle and the longest widths and heights, and of
    // those boxes every 4th.
    let (x_step, y_step) = if cfg!(miri) { (21, 15) } else { (7, 5) };
    let widths: &[i64] = if cfg!(miri) {
        &[1, 9, 45]
    } else {
        &[1, 3, 9, 21, 45]
    };
    let heights: &[i64] = if cfg!(miri) {
        &[2, 33]
    } else {
        &[2, 5, 17, 33]
    };
    for mode in EdgeKind::ALL {
        for x0 in (-30i64..30).step_by(x_step) {
            for &w in widths {
                for y0 in (-22i64..22).step_by(y_step) {
                    for &h in heights {
                        case += 1;
                        if cfg!(miri) && case % 4 != 1 {
                            continue;
                        }
                        let b = [x0, y0, x0 + w, y0 + h];
                        let want = direct_f(mode, b);
                        for form in [FormKind::Paper, FormKind::Stable] {
                            let got = sat
                                .box_sum_raw(
                                    &Rect::new(b[0], b[1], b[2], b[3]),
                                    fb,
                                    form,
                                    mode,
                                    &mut NoCount,
                                )
                                .unwrap();
                            assert_eq!(got.sum(), want, "{mode:?} {form:?} {b:?}");
                            n += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(n > if cfg!(miri) { 40 } else { 1000 });
}

/// `RepeatWithinPeriod` gives Repeat's sums and counted costs for boxes at most one period long
/// on each axis (in the first period, in another, crossing an edge or a corner: starts and sizes
/// on a grid at F = 2 on a 5 x 4 texture, every x start and width, every third y start and
/// second height, both forms; every integer box through the 4-read lookup), and refuses the
/// longer ones with `OutsidePlan { LongerThanPeriod }`.
#[test]
fn repeat_within_period_equals_repeat_and_refuses_longer_boxes() {
    use crate::plan::PlanLimit;
    use crate::{Error, FormKind, FracBits, RepeatWithinPeriod};
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    let fb = FracBits::new(2).unwrap();
    let (pw, ph) = ((W as i64) << 2, (H as i64) << 2);
    let longer = Err(Error::OutsidePlan {
        limit: PlanLimit::LongerThanPeriod,
    });
    let (mut same, mut refused) = (0u32, 0u32);
    // Under Miri (about 10^4 times slower) every 7th start and size.
    let step = if cfg!(miri) { 7 } else { 1 };
    for x0 in (-pw - 3..2 * pw).step_by(step) {
        for bw in (0..pw + 3).step_by(step) {
            for y0 in (-ph - 2..2 * ph).step_by(step * 3) {
                for bh in (0..ph + 2).step_by(step * 2) {
                    let r = Rect::new(x0, y0, x0 + bw, y0 + bh);
                    for form in [FormKind::Paper, FormKind::Stable] {
                        let (mut k0, mut k1) = (Tally::new(), Tally::new());
                        let want = sat.box_sum_raw(&r, fb, form, Repeat, &mut k0);
                        let got = sat.box_sum_raw(&r, fb, form, RepeatWithinPeriod, &mut k1);
                        if (bw > pw || bh > ph) && bw > 0 && bh > 0 {
                            assert_eq!(got, longer, "{r:?}");
                            refused += 1;
                        } else {
                            assert_eq!(got, want, "{form:?} {r:?}");
                            assert_eq!(k1, k0, "{form:?} {r:?}");
                            same += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(same > if cfg!(miri) { 50 } else { 5000 } && refused > 10);
    // Integer corners: the 4-read lookup.
    for x0 in -(W as i32) - 1..2 * W as i32 {
        for bw in 0..W as i32 + 2 {
            for y0 in (-(H as i32) - 1..2 * H as i32).step_by(step) {
                for bh in 0..H as i32 + 2 {
                    let r = Rect::new(x0, y0, x0 + bw, y0 + bh);
                    let (mut k0, mut k1) = (Tally::new(), Tally::new());
                    let want = sat.box_sum_int(&r, Repeat, &mut k0);
                    let got = sat.box_sum_int(&r, RepeatWithinPeriod, &mut k1);
                    if (bw > W as i32 || bh > H as i32) && bw > 0 && bh > 0 {
                        assert_eq!(got, longer, "{r:?}");
                    } else {
                        assert_eq!(got, want, "{r:?}");
                        assert_eq!(k1, k0, "{r:?}");
                    }
                }
            }
        }
    }
}

/// `RepeatWithinPeriod` reads the table in Repeat's order (a counter that records each read's
/// address, as a cache model does, sees the same sequence) for boxes crossing an edge and a
/// corner.
#[test]
fn repeat_within_period_reads_in_repeats_order() {
    use crate::cost::{Counter, Region};
    use crate::RepeatWithinPeriod;
    extern crate std;
    #[derive(Default, PartialEq, Debug)]
    struct Trace(std::vec::Vec<u64>);
    impl Counter for Trace {
        fn reads(&mut self, _: u32, _: u32) {}
        fn muls(&mut self, _: u32) {}
        fn divs(&mut self, _: u32) {}
        fn adds(&mut self, _: u32) {}
        fn read_at(&mut self, _: Region, offset: u64, _: u32) {
            self.0.push(offset);
        }
    }
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    let q = |v: f64| I24F8::from_num(v);
    for b in [
        [3.5, 1.25, 6.5, 2.5],
        [3.5, 2.25, 6.5, 5.5],
        [-1.5, -2.0, 2.5, 1.75],
    ] {
        let r = Rect::new(q(b[0]), q(b[1]), q(b[2]), q(b[3]));
        let (mut a, mut c) = (Trace::default(), Trace::default());
        let want = sat.box_sum(&r, Stable, Repeat, &mut a);
        let got = sat.box_sum(&r, Stable, RepeatWithinPeriod, &mut c);
        assert_eq!(got, want, "{b:?}");
        assert!(a.0.len() > 16, "{b:?}: {a:?}");
        assert_eq!(c, a, "{b:?}");
    }
}

/// `RepeatWithinPeriod` refuses a longer box with `OutsidePlan { LongerThanPeriod }` before the
/// checks that come after placement (a modular layout's bound on the box's sum, here `k = 10`
/// on a 5 x 4 texture of 8-bit texels, which such a box breaks too) and before the shortcut
/// rounds the box to whole texels (a box 5.39 texels wide would round to one period); a box at
/// most a period long gets Repeat's answer on both paths.
#[test]
fn repeat_within_period_refuses_first_on_every_path() {
    use crate::layouts::Modular;
    use crate::plan::PlanLimit;
    use crate::{BoxLookup, EdgeKind, Error, FracBits, RepeatWithinPeriod, Shortcut};
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let longer = Err(Error::OutsidePlan {
        limit: PlanLimit::LongerThanPeriod,
    });
    let fb = FracBits::new(8).unwrap();
    let q = |v: f64| (v * 256.0) as i64;
    let mut words = [0u32; 64];
    let mut row = [0u32; W];
    let m = Modular::<u32>::build(&t, 10, &mut words, &mut row).unwrap();
    // Crossing the right edge, 6 texels wide: Repeat says the modular bound, the mode its own.
    let r = Rect::new(q(3.5), q(1.0), q(9.5), q(3.0));
    assert!(matches!(
        m.box_sum_raw(&r, fb, Stable, Repeat, &mut NoCount),
        Err(Error::TooWide { .. })
    ));
    assert_eq!(
        m.box_sum_raw(&r, fb, Stable, RepeatWithinPeriod, &mut NoCount)
            .map(|_| ()),
        longer
    );
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    let sc = Shortcut::with_min_side(1);
    let shortcut = |r: &Rect<i64>, mode| {
        sat.box_mean_shortcut_raw(r, fb, Stable, mode, &sc, 8, &mut NoCount)
            .map(|s| s.means)
    };
    let long = Rect::new(0, 0, q(5.39), q(2.0));
    assert!(sat
        .box_mean_shortcut_raw(&long, fb, Stable, Repeat, &sc, 8, &mut NoCount)
        .is_ok());
    assert_eq!(
        sat.box_mean_shortcut_raw(&long, fb, Stable, RepeatWithinPeriod, &sc, 8, &mut NoCount)
            .map(|s| s.means),
        longer.map(|()| [0u64])
    );
    for r in [
        Rect::new(0, 0, q(5.0), q(2.0)),
        Rect::new(q(3.4), q(2.6), q(8.3), q(6.5)),
        Rect::new(q(-7.5), q(-1.25), q(-2.5), q(2.75)),
    ] {
        assert_eq!(
            shortcut(&r, EdgeKind::Repeat),
            sat.box_mean_shortcut_raw(&r, fb, Stable, RepeatWithinPeriod, &sc, 8, &mut NoCount)
                .map(|s| s.means),
            "{r:?}"
        );
    }
}

/// Counted costs of a split box: a Repeat box crossing the right edge is two in-range lookups,
/// one addition per channel to combine them; crossing a corner, four.
#[test]
fn split_costs() {
    let t = Texture::<u8>::new(&TEX, W, H).unwrap();
    let mut st = [0u32; W * H];
    let sat = Sat::build(&t, &mut st).unwrap();
    let q = |v: f64| I24F8::from_num(v);
    let mut k = Tally::new();
    sat.box_sum(
        &Rect::new(q(3.5), q(1.25), q(6.5), q(2.5)),
        Stable,
        Repeat,
        &mut k,
    )
    .unwrap();
    let mut one = Tally::new();
    sat.box_sum(
        &Rect::new(q(1.5), q(1.25), q(2.5), q(2.5)),
        Stable,
        Repeat,
        &mut one,
    )
    .unwrap();
    assert!(k.reads <= 2 * 16 && k.adds == 2 * 31 + 1, "{k:?}");
    let mut c = Tally::new();
    sat.box_sum(
        &Rect::new(q(3.5), q(2.25), q(6.5), q(5.5)),
        Stable,
        Repeat,
        &mut c,
    )
    .unwrap();
    assert_eq!(c.adds, 4 * 31 + 3, "{c:?}");
    assert_eq!(one.adds, 31);
}

#[test]
fn box_sum_inside_equals_box_sum_int_and_refuses_outside() {
    // Every box of a 5 x 4 texture: the inside lookup equals the 4-read lookup; every box that
    // reaches outside or is inverted is refused, never clipped.
    let texels: [u8; 20] = core::array::from_fn(|i| (i as u8).wrapping_mul(37).wrapping_add(5));
    let tex = crate::Texture::<u8>::new(&texels, 5, 4).unwrap();
    let mut table = [0u32; 20];
    let sat = crate::Sat::build(&tex, &mut table).unwrap();
    for x0 in 0..7u32 {
        for x1 in 0..7u32 {
            for y0 in 0..6u32 {
                for y1 in 0..6u32 {
                    let r = crate::Rect::new(x0, y0, x1, y1);
                    let got = sat.box_sum_inside(&r);
                    if x0 <= x1 && y0 <= y1 && x1 <= 5 && y1 <= 4 {
                        let ri = crate::Rect::new(x0 as i32, y0 as i32, x1 as i32, y1 as i32);
                        let want = sat
                            .box_sum_int(&ri, crate::Border, &mut crate::NoCount)
                            .unwrap()
                            .sum();
                        assert_eq!(got, Ok([want as u32]), "{r:?}");
                    } else {
                        assert_eq!(got, Err(crate::Error::CoordinateOutOfRange), "{r:?}");
                    }
                }
            }
        }
    }
}

/// The 32-bit clamp path (`clamp_int`: every integer box under `ClampToEdge` on a layout
/// without a modulus) against the general driver (`sum_raw` with the 4-read form and the
/// general split path it replaces there): the same result (sums, sides, refusals) and the same
/// counted costs for every box with corners in `-3..=n + 3` on textures of 1 to 5 texels a
/// side, 1 and 2 channels, `u16` and `u32` entries, and for boxes out to the `i32` limits
/// (sums past the `u64` result word: refused alike).
#[test]
fn clamp_int_matches_the_general_split_path() {
    fn check<E: crate::Entry, const C: usize>(w: usize, h: usize, limits: bool) {
        let data: [u8; 50] = core::array::from_fn(|i| (i as u8).wrapping_mul(37).wrapping_add(11));
        let t = Texture::<u8, C>::new(&data[..w * h * C], w, h).unwrap();
        let mut st = [E::ZERO; 50];
        let sat = Sat::<E, C>::build(&t, &mut st[..w * h * C]).unwrap();
        let compare = |r: Rect<i32>| {
            let (mut k1, mut k2) = (Tally::new(), Tally::new());
            let got = super::clamp_int::sum(&sat, &r, &mut k1);
            let want = super::sum_raw(
                &sat,
                &r.to_raw_int(),
                0,
                super::corners4::Corners4,
                ClampToEdge,
                &mut k2,
            );
            assert_eq!(got, want, "{w}x{h} C={C} {r:?}");
            assert_eq!(k1, k2, "{w}x{h} C={C} {r:?}");
            // The public entry point takes it.
            assert_eq!(sat.box_sum_int(&r, ClampToEdge, &mut NoCount), want);
        };
        let (wi, hi) = (w as i32, h as i32);
        // Under Miri (about 10^4 times slower) corners one texel past the edges.
        let m = if cfg!(miri) { 1 } else { 3 };
        for x0 in -m..=wi + m {
            for x1 in -m..=wi + m {
                for y0 in -m..=hi + m {
                    for y1 in -m..=hi + m {
                        compare(Rect::new(x0, y0, x1, y1));
                    }
                }
            }
        }
        if limits {
            let far: &[i32] = if cfg!(miri) {
                &[i32::MIN, -1, 70_000, i32::MAX]
            } else {
                &[i32::MIN, i32::MIN + 1, -70_000, -1, 0, 1, 70_000, i32::MAX]
            };
            for &x0 in far {
                for &x1 in far {
                    for &y0 in far {
                        for &y1 in far {
                            compare(Rect::new(x0, y0, x1, y1));
                        }
                    }
                }
            }
        }
    }
    // Under Miri (about 10^4 times slower) two shapes.
    if cfg!(miri) {
        check::<u32, 1>(2, 3, true);
        check::<u16, 2>(1, 2, false);
        return;
    }
    let sides: &[usize] = &[1, 2, 3, 5];
    for &w in sides {
        for &h in sides {
            check::<u32, 1>(w, h, w == 3 && h == 3);
            check::<u16, 2>(w, h, w == 1 && h == 5);
        }
    }
}
