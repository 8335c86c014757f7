//! Every layout against the flat table, every box of small textures.

use super::*;
use crate::{Border, BoxLookup, NoCount, Paper, Rect, Repeat, Sat, Stable, Tally, Texture};
use fixed::types::I28F4;

fn texture(w: usize, h: usize, seed: u32) -> [u8; 4096] {
    let mut t = [0u8; 4096];
    let mut s = seed.wrapping_mul(2654435761).wrapping_add(12345);
    for v in t.iter_mut().take(w * h) {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        *v = (s >> 8) as u8;
    }
    t
}

fn check_all_boxes<L: BoxLookup<1>>(l: &L, flat: &Sat<'_, u32, 1>)
where
    crate::WideOf<L, 1>: Into<u128>,
{
    let (w, h) = (flat.width() as i32, flat.height() as i32);
    for x0 in 0..=w {
        for x1 in x0..=w {
            for y0 in 0..=h {
                for y1 in y0..=h {
                    let r = Rect::new(x0, y0, x1, y1);
                    let a = flat.box_sum_int(&r, Border, &mut NoCount).unwrap();
                    let b = l.box_sum_int(&r, Border, &mut NoCount).unwrap();
                    assert_eq!(a.to_u128(), b.to_u128(), "{r:?}");
                }
            }
        }
    }
}

#[test]
fn tiled_equals_flat_every_box() {
    for (w, h) in [(1usize, 7usize), (7, 1), (9, 10), (16, 13), (17, 17)] {
        let tex = texture(w, h, (w * 31 + h) as u32);
        let t = Texture::<u8>::new(&tex[..w * h], w, h).unwrap();
        let mut flat_st = [0u32; 4096];
        let flat = Sat::build(&t, &mut flat_st).unwrap();
        for spec in [
            TiledSpec::FLAT_PACKED,
            TiledSpec::tiles(4, 4).unwrap(),
            TiledSpec::tiles(3, 5).unwrap(),
            TiledSpec::tiles(8, 2).unwrap(),
            TiledSpec::square(&[2, 4]).unwrap(),
            TiledSpec::square(&[2, 6, 12]).unwrap(),
        ] {
            let mut words = [0u32; 4096];
            let mut scratch = [0u32; 512];
            let tiled = Tiled::<u32>::build(&t, spec, &mut words, &mut scratch).unwrap();
            for y in 0..=h {
                for x in 0..=w {
                    assert_eq!(
                        tiled.corner(x, y, &mut NoCount),
                        flat.corner(x, y).unwrap(),
                        "{spec:?} {w}x{h} at ({x},{y})"
                    );
                }
            }
            check_all_boxes(&tiled, &flat);
        }
    }
}

#[test]
fn modular_exact_within_bound_refused_beyond() {
    let (w, h) = (12usize, 9usize);
    let tex = texture(w, h, 7);
    let t = Texture::<u8>::new(&tex[..w * h], w, h).unwrap();
    let mut flat_st = [0u32; 4096];
    let flat = Sat::build(&t, &mut flat_st).unwrap();
    let k = modulus_bits_for(8, 16); // boxes up to 16 cells: 12 bits
    assert_eq!(k, 12);
    let mut words = [0u32; 4096];
    let mut row = [0u32; 64];
    let m = Modular::<u32>::build(&t, k, &mut words, &mut row).unwrap();
    assert_eq!(m.bits_per_entry(), 12.0);
    for x0 in 0..=w as i32 {
        for x1 in x0..=w as i32 {
            for y0 in 0..=h as i32 {
                for y1 in y0..=h as i32 {
                    let r = Rect::new(x0, y0, x1, y1);
                    let area = (x1 - x0) * (y1 - y0);
                    let got = m.box_sum_int(&r, Border, &mut NoCount);
                    if (255 * area as u32) < (1 << k) {
                        assert_eq!(
                            got.unwrap(),
                            flat.box_sum_int(&r, Border, &mut NoCount).unwrap()
                        );
                    } else {
                        assert!(matches!(got, Err(crate::Error::TooWide { .. })), "{r:?}");
                    }
                }
            }
        }
    }
    // Fractional corners: Stable works at k bits; Paper needs 2F more.
    let r = Rect::new(
        I28F4::from_num(2.25),
        I28F4::from_num(3.5),
        I28F4::from_num(4.75),
        I28F4::from_num(4.5),
    );
    let exact = flat.box_sum(&r, Stable, Border, &mut NoCount).unwrap();
    assert_eq!(m.box_sum(&r, Stable, Border, &mut NoCount).unwrap(), exact);
    assert!(m.box_sum(&r, Paper, Border, &mut NoCount).is_err());
    // Repeat across the right edge, integer corners.
    let r = Rect::new(11, 2, 13, 4);
    assert_eq!(
        m.box_sum_int(&r, Repeat, &mut NoCount).unwrap(),
        flat.box_sum_int(&r, Repeat, &mut NoCount).unwrap()
    );
}

#[test]
fn tiled_counts_fields_and_words() {
    let (w, h) = (32usize, 32usize);
    let tex = texture(w, h, 3);
    let t = Texture::<u8>::new(&tex[..w * h], w, h).unwrap();
    let mut words = [0u32; 4096];
    let mut scratch = [0u32; 512];
    let tiled = Tiled::<u32>::build(
        &t,
        TiledSpec::tiles(8, 8).unwrap(),
        &mut words,
        &mut scratch,
    )
    .unwrap();
    // A corner strictly inside a tile, not in the first tile row or column: 4 fields.
    let mut k = Tally::new();
    tiled.corner(13, 19, &mut k);
    assert_eq!(k.reads, 4, "{k:?}");
    assert!(k.words >= 4 && k.words <= 8, "{k:?}");
    assert_eq!(k.adds, 3);
}

#[test]
fn tiled_modular_combination() {
    let (w, h) = (20usize, 18usize);
    let tex = texture(w, h, 11);
    let t = Texture::<u8>::new(&tex[..w * h], w, h).unwrap();
    let mut flat_st = [0u32; 4096];
    let flat = Sat::build(&t, &mut flat_st).unwrap();
    let k = modulus_bits_for(8, 25); // boxes of up to 25 cells
    for spec in [
        TiledSpec::tiles(4, 4).unwrap().with_modulus(k),
        TiledSpec::square(&[2, 6]).unwrap().with_modulus(k),
    ] {
        let mut words = [0u32; 4096];
        let mut scratch = [0u16; 512];
        // u16 values suffice: only k = 13 bits are ever held.
        let l = Tiled::<u16>::build(&t, spec, &mut words, &mut scratch).unwrap();
        assert!(l.bits_per_entry() < k as f64, "{}", l.bits_per_entry());
        for x0 in 0..=w as i32 {
            for x1 in x0..=w as i32 {
                for (y0, y1) in [(0, 5), (3, 8), (13, 18), (7, 8), (0, 18)] {
                    let r = Rect::new(x0, y0, x1, y1);
                    let area = (x1 - x0) * (y1 - y0);
                    let got = l.box_sum_int(&r, Border, &mut NoCount);
                    if area <= 25 {
                        let want = flat.box_sum_int(&r, Border, &mut NoCount).unwrap();
                        assert_eq!(got.unwrap().sum(), want.sum(), "{spec:?} {r:?}");
                    } else if (255 * area as u32) >= (1 << k) {
                        assert!(got.is_err(), "{r:?}");
                    }
                }
            }
        }
    }
}
