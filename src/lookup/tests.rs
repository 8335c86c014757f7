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
