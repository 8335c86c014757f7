//! `Sat::box_sum_inside` (the 4-read lookup of a plan whose boxes lie inside the texture)
//! against a brute-force sum of the texels, for every box of small textures, every entry
//! word and 1 to 4 channels. The lookup reads with wrapping indices (the zero row wraps past
//! the table, the zero column is one test), so these sweeps cover every corner on the zero
//! row and column, every empty box (which must cancel to exactly zero) and every box one
//! texel past an edge (which must be refused, never read from the next row).

use texsat::{Entry, Error, Rect, Sat, Texture};

/// Deterministic texels, full 8-bit range.
fn texels(n: usize, seed: u32) -> Vec<u8> {
    texsat_host_tests::random_bytes(n, u64::from(seed))
}

/// Every box `[x0, x1) x [y0, y1)` with corners in `0..=w + 1`, `0..=h + 1`.
fn sweep<E: Entry + TryFrom<u64> + std::fmt::Debug, const C: usize>(w: usize, h: usize) {
    let data = texels(w * h * C, (w * 31 + h * 7 + C) as u32);
    let tex = Texture::<u8, C>::new(&data, w, h).unwrap();
    let mut table = vec![E::ZERO; w * h * C];
    let sat = Sat::<E, C>::build(&tex, &mut table).unwrap();
    let brute = |x0: usize, y0: usize, x1: usize, y1: usize, ch: usize| -> u64 {
        let mut s = 0u64;
        for y in y0..y1 {
            for x in x0..x1 {
                s += u64::from(data[(y * w + x) * C + ch]);
            }
        }
        s
    };
    for x0 in 0..=w + 1 {
        for x1 in 0..=w + 1 {
            for y0 in 0..=h + 1 {
                for y1 in 0..=h + 1 {
                    let r = Rect::new(x0 as u32, y0 as u32, x1 as u32, y1 as u32);
                    let got = sat.box_sum_inside(&r);
                    if x0 <= x1 && y0 <= y1 && x1 <= w && y1 <= h {
                        let want: [E; C] = std::array::from_fn(|ch| {
                            E::try_from(brute(x0, y0, x1, y1, ch))
                                .ok()
                                .expect("a box sum fits the entry word")
                        });
                        assert_eq!(got, Ok(want), "{w}x{h} C={C} {r:?}");
                    } else {
                        assert_eq!(got, Err(Error::CoordinateOutOfRange), "{w}x{h} C={C} {r:?}");
                    }
                }
            }
        }
    }
}

fn sizes<E: Entry + TryFrom<u64> + std::fmt::Debug, const C: usize>() {
    for (w, h) in [(1, 1), (1, 5), (5, 1), (2, 3), (4, 4), (7, 3), (3, 6)] {
        sweep::<E, C>(w, h);
    }
}

#[test]
fn u16_entries_every_box_every_channel_count() {
    sizes::<u16, 1>();
    sizes::<u16, 2>();
    sizes::<u16, 3>();
    sizes::<u16, 4>();
}

#[test]
fn u32_entries_every_box_every_channel_count() {
    sizes::<u32, 1>();
    sizes::<u32, 2>();
    sizes::<u32, 3>();
    sizes::<u32, 4>();
}

#[test]
fn u64_entries_every_box_every_channel_count() {
    sizes::<u64, 1>();
    sizes::<u64, 3>();
}

#[test]
fn far_coordinates_are_refused() {
    // Corners near u32::MAX: the wrapping indices must never turn them into a read.
    let data = texels(12, 5);
    let tex = Texture::<u8>::new(&data, 4, 3).unwrap();
    let mut table = [0u32; 12];
    let sat = Sat::<u32>::build(&tex, &mut table).unwrap();
    for v in [5, 1 << 16, u32::MAX / 2, u32::MAX - 1, u32::MAX] {
        for r in [
            Rect::new(0, 0, v, 3),
            Rect::new(0, 0, 4, v),
            Rect::new(v, 0, v, 3),
            Rect::new(0, v, 4, v),
            Rect::new(v, v, v, v),
            Rect::new(1, 1, v, v),
        ] {
            assert_eq!(
                sat.box_sum_inside(&r),
                Err(Error::CoordinateOutOfRange),
                "{r:?}"
            );
        }
    }
}
