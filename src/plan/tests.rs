//! Plans against the layouts they name: the sizes agree with the layouts' own `words_needed`,
//! the chosen table is the smallest candidate that serves, the lookup follows the facts, and a
//! table built as planned answers every box within the facts.
extern crate std;
use super::*;
use crate::layouts::{Modular, Tiled};
use crate::{BoxLookup, FracBits, NoCount, Sat, Stable, Texture};
use std::vec;
use std::vec::Vec;

fn facts(w: usize, h: usize, f: u32, max: u64, edge: EdgeKind) -> SceneFacts {
    SceneFacts {
        max_box: [max << f, max << f],
        ..SceneFacts::new(w, h, 8, f, edge)
    }
}

/// Words (or entries) the real layout needs for the plan (one channel).
fn real_storage(p: &Plan) -> usize {
    let f = p.facts();
    match p.layout() {
        PlanLayout::Flat => Sat::<u32>::entries_needed(f.width, f.height).unwrap(),
        PlanLayout::Modular { k } => match p.entry() {
            EntryWord::U32 => Modular::<u32>::words_needed(f.width, f.height, k).unwrap(),
            _ => Modular::<u64>::words_needed(f.width, f.height, k).unwrap(),
        },
        l => Tiled::<u32>::words_needed(l.tiled_spec().unwrap(), f.width, f.height, 8).unwrap(),
    }
}

#[test]
fn sizes_agree_with_the_layouts_and_the_smallest_wins() {
    for (w, h) in [
        (16usize, 16usize),
        (33, 20),
        (64, 64),
        (256, 256),
        (1000, 3),
    ] {
        for f in [0u32, 4, 8] {
            for max in [2u64, 8, 16, 64, 1024] {
                for edge in EdgeKind::ALL {
                    let facts = facts(w, h, f, max.min(w.min(h) as u64), edge);
                    let p = Plan::for_scene(&facts).unwrap();
                    assert_eq!(p.storage_len(), real_storage(&p), "{facts:?}");
                    let unit = match p.layout() {
                        PlanLayout::Flat => p.entry().bits() as u64 / 8,
                        _ => 4,
                    };
                    assert_eq!(p.table_bytes(), p.storage_len() as u64 * unit);
                    for r in p.rejected() {
                        if let RejectReason::Larger { bytes } = r.why {
                            assert!(bytes >= p.table_bytes(), "{r:?} beats {p:?}");
                        }
                    }
                    // Never larger than the flat u32 table.
                    assert!(p.table_bytes() <= (w * h * 4) as u64);
                    assert_eq!(p.lookup() == PlanLookup::Int4, f == 0);
                }
            }
        }
    }
}

#[test]
fn a_planned_table_answers_every_box_within_its_facts() {
    let (w, h) = (40usize, 24usize);
    let texels: Vec<u8> = (0..w * h).map(|i| (i * 97 % 256) as u8).collect();
    let tex = Texture::<u8>::new(&texels, w, h).unwrap();
    let mut flat = vec![0u32; w * h];
    let sat = Sat::build(&tex, &mut flat).unwrap();
    // Under Miri (about 10^4 times slower) the smallest and the largest box only.
    let maxes: &[u64] = if cfg!(miri) {
        &[3, 24]
    } else {
        &[3, 6, 12, 24]
    };
    for &max in maxes {
        for f in [0u32, 4] {
            let facts = facts(w, h, f, max, EdgeKind::Border);
            let p = Plan::for_scene(&facts).unwrap();
            let mut words = vec![0u32; p.storage_len()];
            let one = 1i64 << f;
            // Every 5th start in x and 7th in y; under Miri (about 10^4 times slower) only the
            // first, the middle and the last start in x, the first and the last in y.
            let starts = |end: i64, step: usize, under_miri: &[i64]| -> Vec<i64> {
                if cfg!(miri) {
                    let mut v: Vec<i64> = under_miri
                        .iter()
                        .copied()
                        .filter(|s| (0..end).contains(s))
                        .collect();
                    v.dedup();
                    v
                } else {
                    (0..end).step_by(step).collect()
                }
            };
            let (x_end, y_end) = ((w as i64 - max as i64) * one, (h as i64 - max as i64) * one);
            let xs = starts(x_end, 5, &[0, x_end / 2, x_end - 1]);
            let ys = starts(y_end, 7, &[0, y_end - 1]);
            let check = |l: &dyn Fn(&Rect<i64>) -> Result<u128, Error>| {
                for &x0 in &xs {
                    for &y0 in &ys {
                        for (dw, dh) in [
                            (one, one),
                            (max as i64 * one, max as i64 * one - (one >> 1)),
                        ] {
                            let r = Rect::new(x0, y0, x0 + dw, y0 + dh);
                            assert_eq!(p.check_box(&r), Ok(()));
                            let want = sat
                                .box_sum_raw(
                                    &r,
                                    FracBits::new(f).unwrap(),
                                    Stable,
                                    crate::Border,
                                    &mut NoCount,
                                )
                                .unwrap()
                                .to_u128()
                                .sum();
                            assert_eq!(l(&r), Ok(want), "{} {r:?}", p.layout());
                        }
                    }
                }
            };
            let fb = FracBits::new(f).unwrap();
            match p.layout() {
                PlanLayout::Flat => {}
                PlanLayout::Modular { k } => {
                    let mut row = vec![0u32; w];
                    let m = Modular::<u32>::build(&tex, k, &mut words, &mut row).unwrap();
                    check(&|r| {
                        m.box_sum_raw(r, fb, Stable, crate::Border, &mut NoCount)
                            .map(|s| s.to_u128().sum())
                    });
                }
                l => {
                    let spec = l.tiled_spec().unwrap();
                    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
                    let t = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).unwrap();
                    check(&|r| {
                        t.box_sum_raw(r, fb, Stable, crate::Border, &mut NoCount)
                            .map(|s| s.to_u128().sum())
                    });
                }
            }
        }
    }
}

#[test]
fn boxes_outside_the_facts_are_refused() {
    let facts = SceneFacts {
        min_box: [2 << 8, 2 << 8],
        ..facts(64, 32, 8, 8, EdgeKind::Clamp)
    };
    let p = Plan::for_scene(&facts).unwrap();
    let limit = |l| Err(Error::OutsidePlan { limit: l });
    assert_eq!(p.check_box(&Rect::new(0, 0, 2 << 8, 8 << 8)), Ok(()));
    assert_eq!(
        p.check_box(&Rect::new(0, 0, 1 << 8, 8 << 8)),
        limit(PlanLimit::BoxTooSmall)
    );
    assert_eq!(
        p.check_box(&Rect::new(0, 0, 9 << 8, 8 << 8)),
        limit(PlanLimit::BoxTooLarge)
    );
    assert_eq!(
        p.check_box(&Rect::new(-1, 0, 4 << 8, 4 << 8)),
        limit(PlanLimit::LeavesTexture)
    );
    assert_eq!(
        p.check_box(&Rect::new(60 << 8, 0, (60 << 8) + 1025, 4 << 8)),
        limit(PlanLimit::LeavesTexture)
    );
    assert_eq!(p.check_box(&Rect::new(5, 0, 4, 4)), Err(Error::InvertedBox));
    let leaves = Plan::for_scene(&SceneFacts {
        leaves_texture: true,
        ..facts
    })
    .unwrap();
    assert_eq!(leaves.check_box(&Rect::new(-1, 0, 4 << 8, 4 << 8)), Ok(()));
}

#[test]
fn the_read_bound_and_the_tolerance_steer_the_plan() {
    let base = facts(512, 512, 8, 512, EdgeKind::Border);
    // Smallest table: tiles (4 fields per corner, 64 reads).
    let p = Plan::for_scene(&base).unwrap();
    assert!(matches!(p.layout(), PlanLayout::Tiled { .. }));
    assert_eq!(p.costs().reads, 64);
    // At most 16 reads: a one-field layout (packed at the exact width beats flat u32).
    let p16 = Plan::for_scene(&SceneFacts {
        max_reads: 16,
        ..base
    })
    .unwrap();
    assert_eq!(p16.layout(), PlanLayout::Packed);
    assert!(p16
        .rejected()
        .any(|r| matches!(r.why, RejectReason::TooManyReads { reads: 64 })));
    // At most 4 reads: only the shortcut, which needs a tolerance and large boxes.
    assert_eq!(
        Plan::for_scene(&SceneFacts {
            max_reads: 4,
            ..base
        }),
        Err(Error::NoPlan)
    );
    let big = SceneFacts {
        min_box: [256 << 8, 256 << 8],
        tolerance: 16,
        max_reads: 4,
        mean_frac_bits: 0,
        ..base
    };
    let ps = Plan::for_scene(&big).unwrap();
    assert_eq!(ps.lookup(), PlanLookup::Shortcut { min_side: 256 });
    // 255 (1/255 + 1/255) + 1/2 = 2.5 units: (2 * 255 * 510 + 255^2) / (2 * 255^2).
    assert_eq!(ps.max_error(), (2 * 255 * 510 + 255 * 255, 2 * 255 * 255));
    // The same tolerance with small boxes: exact lookups.
    let small = SceneFacts {
        min_box: [8 << 8, 8 << 8],
        max_reads: 0,
        ..big
    };
    assert_eq!(
        Plan::for_scene(&small).unwrap().lookup(),
        PlanLookup::Stable
    );
}

#[test]
fn words_follow_values_and_accumulators() {
    // 8 x 8 texture of 8-bit texels: totals fit 14 bits. Integer corners: u16. F = 8 needs
    // 14 + 16 + 1 = 31 accumulator bits: still u16 (i32 holds 31). F = 9: u32.
    let p = Plan::for_scene(&SceneFacts::new(8, 8, 8, 0, EdgeKind::Border)).unwrap();
    assert_eq!(p.entry(), EntryWord::U16);
    let p = Plan::for_scene(&SceneFacts::new(8, 8, 8, 8, EdgeKind::Border)).unwrap();
    assert_eq!(p.entry(), EntryWord::U16);
    assert_eq!(p.acc_bits(), 31);
    let p = Plan::for_scene(&SceneFacts::new(8, 8, 8, 9, EdgeKind::Border)).unwrap();
    assert_eq!(p.entry(), EntryWord::U32);
}

#[test]
fn invalid_facts_are_refused() {
    let ok = SceneFacts::new(8, 8, 8, 8, EdgeKind::Border);
    assert_eq!(
        Plan::for_scene(&SceneFacts { width: 0, ..ok }),
        Err(Error::EmptyTexture)
    );
    assert_eq!(
        Plan::for_scene(&SceneFacts {
            texel_bits: 17,
            ..ok
        }),
        Err(Error::InvalidTexelBits { bits: 17 })
    );
    assert_eq!(
        Plan::for_scene(&SceneFacts {
            frac_bits: 25,
            ..ok
        }),
        Err(Error::FracBitsUnsupported {
            frac_bits: 25,
            max: 24
        })
    );
    assert_eq!(
        Plan::for_scene(&SceneFacts {
            min_box: [1 << 20, 1],
            ..ok
        }),
        Err(Error::InvertedBox)
    );
    assert_eq!(
        Plan::for_scene(&SceneFacts { channels: 0, ..ok }),
        Err(Error::NoSuchChannel)
    );
}

/// `mean_fits_u32` says exactly when the largest box's area and the largest mean fit 32 bits,
/// and where it says so, `mean_rounded_u32` answers the worst box of the scene (the largest
/// box, reaching outside a texture of all-maximum texels under clamp, so the mean is the
/// largest) with `mean_rounded`'s value; where the area or the mean is one bit too wide, it
/// refuses that box.
#[test]
fn the_u32_mean_serves_every_box_of_a_plan_that_says_so() {
    let (w, h) = (8usize, 6usize);
    for (bits, g, side_texels, f) in [
        (8u32, 8u32, 8u64, 8u32), // the demo's plans: small
        (8, 24, 8, 8),            // mean exactly 32 bits
        (8, 25, 8, 8),            // mean 33 bits: wide
        (16, 16, 8, 0),           // 16-bit texels, 16 output bits: 32 bits
        (8, 8, 256, 8),           // area (256 2^8)^2 = 2^32: wide
        (8, 8, 255, 8),           // area just below 2^32
    ] {
        let facts = SceneFacts {
            texel_bits: bits,
            mean_frac_bits: g,
            max_box: [side_texels << f, side_texels << f],
            leaves_texture: true,
            ..SceneFacts::new(w, h, bits, f, EdgeKind::Clamp)
        };
        let p = Plan::for_scene(&facts).unwrap();
        let area = (side_texels << f) * (side_texels << f);
        let fits = area <= u64::from(u32::MAX) && bits + g <= 32;
        assert_eq!(p.mean_fits_u32(), fits, "{bits} {g} {side_texels} {f}");
        let side = (side_texels << f) as i64;
        let r = Rect::new(-3 << f, -2 << f, side - (3 << f), side - (2 << f));
        assert_eq!(p.check_box(&r), Ok(()));
        let fb = FracBits::new(f).unwrap();
        let mut t = vec![0u64; w * h];
        let (t8, t16) = (vec![u8::MAX; w * h], vec![u16::MAX; w * h]);
        let s = if bits == 8 {
            let sat = Sat::build(&Texture::<u8>::new(&t8, w, h).unwrap(), &mut t).unwrap();
            sat.box_sum_raw(&r, fb, Stable, crate::ClampToEdge, &mut NoCount)
        } else {
            let sat = Sat::build(&Texture::<u16>::new(&t16, w, h).unwrap(), &mut t).unwrap();
            sat.box_sum_raw(&r, fb, Stable, crate::ClampToEdge, &mut NoCount)
        }
        .unwrap();
        let wide = s.mean_rounded(0, g, &mut NoCount).unwrap();
        let narrow = s.mean_rounded_u32(0, g, &mut NoCount);
        if fits {
            assert_eq!(narrow.map(u128::from), Ok(wide));
        } else {
            assert!(matches!(narrow, Err(Error::TooWide { .. })), "{narrow:?}");
        }
    }
}

/// `repeat_within_period` holds exactly for Repeat facts whose largest box is at most the
/// texture on both axes, and then `RepeatWithinPeriod` answers the boxes `check_box` accepts
/// (a grid of starts and sizes, leaving the texture included) with Repeat's sum.
#[test]
fn repeat_within_period_follows_the_facts() {
    let (w, h) = (12usize, 7usize);
    for f in [0u32, 3] {
        let within = |max: [u64; 2], edge| {
            let facts = SceneFacts {
                max_box: max,
                leaves_texture: true,
                ..SceneFacts::new(w, h, 8, f, edge)
            };
            Plan::for_scene(&facts).unwrap().repeat_within_period()
        };
        let (pw, ph) = ((w as u64) << f, (h as u64) << f);
        assert!(within([pw, ph], EdgeKind::Repeat));
        assert!(within([1 << f, 1 << f], EdgeKind::Repeat));
        assert!(!within([pw + 1, ph], EdgeKind::Repeat));
        assert!(!within([pw, ph + 1], EdgeKind::Repeat));
        for edge in [EdgeKind::Border, EdgeKind::Clamp, EdgeKind::Mirror] {
            assert!(!within([pw, ph], edge));
        }
    }
    let texels: Vec<u8> = (0..w * h).map(|i| (i * 53 % 251) as u8).collect();
    let tex = Texture::<u8>::new(&texels, w, h).unwrap();
    let mut flat = vec![0u32; w * h];
    let sat = Sat::build(&tex, &mut flat).unwrap();
    let f = 2u32;
    let facts = SceneFacts {
        max_box: [(w as u64) << f, (h as u64) << f],
        leaves_texture: true,
        ..SceneFacts::new(w, h, 8, f, EdgeKind::Repeat)
    };
    let p = Plan::for_scene(&facts).unwrap();
    assert!(p.repeat_within_period());
    let fb = FracBits::new(f).unwrap();
    let step = if cfg!(miri) { 5 } else { 1 };
    let mut n = 0;
    for x0 in (-60i64..60).step_by(step * 7) {
        for bw in (1i64..60).step_by(step * 3) {
            for y0 in (-40i64..40).step_by(step * 5) {
                for bh in (1i64..36).step_by(step * 2) {
                    let r = Rect::new(x0, y0, x0 + bw, y0 + bh);
                    let want = sat.box_sum_raw(&r, fb, Stable, crate::Repeat, &mut NoCount);
                    let got =
                        sat.box_sum_raw(&r, fb, Stable, crate::RepeatWithinPeriod, &mut NoCount);
                    match p.check_box(&r) {
                        Ok(()) => {
                            assert_eq!(got, want, "{r:?}");
                            n += 1;
                        }
                        Err(_) => assert_eq!(
                            got.is_err(),
                            bw > (w as i64) << f || bh > (h as i64) << f,
                            "{r:?}"
                        ),
                    }
                }
            }
        }
    }
    assert!(n > if cfg!(miri) { 50 } else { 1000 }, "{n}");
}
