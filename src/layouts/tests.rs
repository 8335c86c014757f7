//! Every layout against the flat table, every box of small textures.

extern crate std;
use super::*;
use crate::{Border, BoxLookup, NoCount, Paper, Rect, Repeat, Sat, Stable, Tally, Texture};
use fixed::types::I28F4;
use std::vec::Vec;

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

/// `n` bytes of xorshift64 noise from `seed` (the wide layout tests' textures, which pass
/// [`texture`]'s 4,096 texels).
pub(super) fn noise_bytes(n: usize, seed: u64) -> Vec<u8> {
    let mut s = 0x2545_f491_4f6c_dd1du64 ^ seed;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 32) as u8
        })
        .collect()
}

/// The coordinates a sweep visits from `lo` to `hi` (inclusive): all of them natively; under
/// Miri, which interprets about 10^4 times slower, only both ends, their neighbours and the
/// middle, so the sweeps still meet the empty, the one-cell, the edge and the whole-axis boxes.
fn span(lo: i32, hi: i32) -> impl Iterator<Item = i32> + Clone {
    let mid = lo + (hi - lo) / 2;
    (lo..=hi).filter(move |&v| !cfg!(miri) || v <= lo + 1 || v >= hi - 1 || v == mid)
}

/// [`span`] over `usize` coordinates.
fn span_usize(lo: usize, hi: usize) -> impl Iterator<Item = usize> + Clone {
    span(lo as i32, hi as i32).map(|v| v as usize)
}

fn check_all_boxes<L: BoxLookup<1>>(l: &L, flat: &Sat<'_, u32, 1>)
where
    crate::WideOf<L, 1>: Into<u128>,
{
    let (w, h) = (flat.width() as i32, flat.height() as i32);
    // Under Miri every 13th box of the spans (the first included).
    let mut case = 0u32;
    for x0 in span(0, w) {
        for x1 in span(x0, w) {
            for y0 in span(0, h) {
                for y1 in span(y0, h) {
                    case += 1;
                    if cfg!(miri) && case % 13 != 1 {
                        continue;
                    }
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
    // Under Miri (about 10^4 times slower) every 5th combination of size and spec (5 is coprime
    // to the 6 specs, so each spec still runs once, on a different size).
    let mut combo = 0u32;
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
            combo += 1;
            if cfg!(miri) && combo % 5 != 1 {
                continue;
            }
            let mut words = [0u32; 4096];
            let mut scratch = [0u32; 512];
            let tiled = Tiled::<u32>::build(&t, spec, &mut words, &mut scratch).unwrap();
            for y in span_usize(0, h) {
                for x in span_usize(0, w) {
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
        for x0 in span(0, w as i32) {
            for x1 in span(x0, w as i32) {
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

// ---------------------------------------------------------------------------------------------
// Firmware-grade core: the fuzz findings, the const sizes, the power-of-two digits
// ---------------------------------------------------------------------------------------------

use super::modular::Sizes;
use super::packed::words_for_checked;
use super::tiled::{Axis, Geometry};
use crate::Error;

const MAX32: u64 = u32::MAX as u64;

/// `bits_of` in `u128` (tests may use it).
fn bits128(v: u128) -> u32 {
    128 - v.leading_zeros()
}

/// Stored positions of component `p` on an axis of `n` texels, by a formula other than the
/// layout's: the multiples of `b_p` up to `n` minus those of `b_{p+1}`.
fn count128(blocks: &[u32], p: usize, n: u128) -> u128 {
    let b = if p == 0 { 1 } else { blocks[p - 1] as u128 };
    match blocks.get(p) {
        Some(&nb) => n / b - n / nb as u128,
        None => n / b,
    }
}

fn max_len128(blocks: &[u32], p: usize, n: u128) -> u128 {
    let b = if p == 0 { 1 } else { blocks[p - 1] as u128 };
    match blocks.get(p) {
        Some(&nb) if n >= nb as u128 => nb as u128 - b,
        _ => n / b * b,
    }
}

/// Checks `g` against sizes and offsets computed independently in `u128`: every component
/// starts where the previous one ends, its last entry ends inside it (the lookups' `u64`
/// offsets do not wrap), and the total is the sum. Returns the total bits.
fn check_geometry_u128(g: &Geometry, channels: usize) -> u128 {
    let (bx, by) = (g.spec.x.blocks(), g.spec.y.blocks());
    let m = (1u128 << g.texel_bits) - 1;
    let mut offset = 0u128;
    for p in 0..g.spec.x.components() {
        for q in 0..g.spec.y.components() {
            let (cx, cy) = (
                count128(bx, p, g.width as u128),
                count128(by, q, g.height as u128),
            );
            let len = max_len128(bx, p, g.width as u128) * max_len128(by, q, g.height as u128);
            let mut bits = bits128(m * len);
            if let Some(k) = g.spec.modulus {
                bits = bits.min(k);
            }
            let c = &g.comps[p][q];
            let what = (g.spec, g.width, g.height, p, q);
            assert_eq!(c.offset_bits as u128, offset, "{what:?}");
            assert_eq!(c.bits, bits, "{what:?}");
            let stride = bits as u128 * channels as u128;
            assert_eq!(c.stride_bits as u128, stride, "{what:?}");
            assert_eq!(c.row_bits as u128, cx * stride, "{what:?}");
            let size = cx * cy * stride;
            if cx > 0 && cy > 0 {
                let last = c.offset((cx - 1) as u32, (cy - 1) as u32) as u128;
                assert_eq!(last + stride, offset + size, "{what:?}: last entry");
                // Row by row: the next x entry is the next field group, the next y a row on.
                let first = c.offset(0, 0) as u128;
                assert_eq!(first, offset, "{what:?}: first entry");
                if cx > 1 {
                    assert_eq!(c.offset(1, 0) as u128, first + stride, "{what:?}: next x");
                }
                if cy > 1 {
                    assert_eq!(
                        c.offset(0, 1) as u128,
                        first + cx * stride,
                        "{what:?}: next y"
                    );
                }
            }
            offset += size;
        }
    }
    assert_eq!(g.total_bits as u128, offset);
    assert_eq!(g.words as u128, offset.div_ceil(32));
    offset
}

/// Fuzz finding "the tiled size arithmetic can overflow and accept too-short storage"
/// (`Geometry::new`'s `offset += ...`): a layout of exactly `2^64` bits (`2^29 x 2^29` fields
/// of 64 bits, a modulus of `2^64`) wrapped to 0 bits in release builds, so `from_words`
/// accepted an empty slice. Every size is now checked in `u64`: `TextureTooLarge`.
#[test]
fn fuzz_tiled_size_overflow_refused() {
    // Tiles of 2 x 2: 2^30 x 2^30 texels, 2^58 tiles of 16 + 2 * 46 + 64 bits.
    for (n, spec) in [
        (1usize << 29, TiledSpec::FLAT_PACKED.with_modulus(64)),
        (1 << 30, TiledSpec::tiles(2, 2).unwrap().with_modulus(64)),
    ] {
        let too_large = Err(Error::TextureTooLarge { dimension: n });
        assert_eq!(Tiled::<u64>::words_needed(spec, n, n, 16), too_large);
        assert_eq!(
            Tiled::<u64>::from_words(&[], spec, n, n, 16).map(|_| ()),
            too_large.map(|_: usize| ())
        );
        assert_eq!(
            TiledBuilder::<u64>::new(spec, n, n, 16, &mut [], &mut []).map(|_| ()),
            too_large.map(|_: usize| ())
        );
    }
    // Channels multiply: 2^28 x 2^28 x 64 bits x 4 channels = 2^64 bits.
    let n4 = 1usize << 28;
    assert_eq!(
        Tiled::<u64, 4>::words_needed(TiledSpec::FLAT_PACKED.with_modulus(64), n4, n4, 16),
        Err(Error::TextureTooLarge { dimension: n4 })
    );
    // One row less fits u64 bits: the exact word count (on a 64-bit target), and short storage
    // is refused with it.
    let n = 1usize << 29;
    let spec = TiledSpec::FLAT_PACKED.with_modulus(64);
    let g = Geometry::new_for(spec, n, n - 1, 16, 1, u64::MAX).unwrap();
    assert_eq!(check_geometry_u128(&g, 1), (n * (n - 1)) as u128 * 64);
    #[cfg(target_pointer_width = "64")]
    assert_eq!(
        Tiled::<u64>::from_words(&[0; 8], spec, n, n - 1, 16).unwrap_err(),
        Error::StorageTooSmall {
            needed: n * (n - 1) * 2,
            got: 8
        }
    );
    // Texture sides past 2^31 - 1, and fields past 64 bits, as before.
    assert_eq!(
        Tiled::<u64>::words_needed(spec, 1 << 31, 1, 8),
        Err(Error::TextureTooLarge { dimension: 1 << 31 })
    );
    assert_eq!(
        Tiled::<u64>::words_needed(TiledSpec::FLAT_PACKED, (1 << 31) - 1, (1 << 31) - 1, 16),
        Err(Error::TooWide {
            what: crate::Quantity::Field,
            bits_needed: 78,
            bits_available: 64
        })
    );
    // The scratch size is checked too.
    assert_eq!(
        Tiled::<u32, 2>::scratch_needed(TiledSpec::tiles(4, 4).unwrap(), usize::MAX / 2),
        Err(Error::TextureTooLarge {
            dimension: usize::MAX / 2
        })
    );
    assert_eq!(
        Tiled::<u32>::scratch_needed(TiledSpec::tiles(4, 4).unwrap(), usize::MAX),
        Err(Error::TextureTooLarge {
            dimension: usize::MAX
        })
    );
}

/// Fuzz findings "`words()`'s `as usize`" and "`field_offset` in `usize`" of the tiled layout:
/// on a 32-bit target the word count was truncated and the entry index `ix * count_y + iy`
/// wrapped. The geometry is computed in `u64` and the word count checked against the target's
/// `usize` (`Geometry::new_for` with `u32::MAX` is the 32-bit target's check, run here on any
/// host), with sides whose products overflow `u32`.
#[test]
fn fuzz_tiled_sizes_on_32_bit_targets() {
    let m64 = u64::MAX;
    // 65536 x 65536 16-bit texels, flat packed: 48-bit fields, 3 * 2^31 words: exact in u64,
    // refused on a 32-bit target (the old `as usize` kept 0 of it).
    let flat = TiledSpec::FLAT_PACKED;
    let g = Geometry::new_for(flat, 65536, 65536, 16, 1, m64).unwrap();
    assert_eq!(check_geometry_u128(&g, 1), 48 << 32);
    assert_eq!(g.words as u128, 3 << 31);
    assert_eq!(
        Geometry::new_for(flat, 65536, 65536, 16, 1, MAX32),
        Err(Error::TextureTooLarge { dimension: 65536 })
    );
    // Offsets whose entry index and bit offset overflow u32, for every kind of spec.
    let specs = [
        TiledSpec::tiles(8, 8).unwrap(),
        TiledSpec::tiles(3, 5).unwrap(),
        TiledSpec::square(&[2, 16]).unwrap(),
        TiledSpec::square(&[2, 6, 12]).unwrap(),
        TiledSpec::square(&[2, 4, 8, 16]).unwrap(),
        TiledSpec::tiles(8, 8).unwrap().with_modulus(20),
    ];
    for spec in specs {
        for (w, h, b) in [
            (65536usize, 65536usize, 16u32),
            (46341, 46341, 8),
            ((1 << 31) - 1, 3, 8),
            (3, (1 << 31) - 1, 16),
            (4104, 4104, 8),
            (100_000, 70_000, 1),
        ] {
            let g = Geometry::new_for(spec, w, h, b, 1, m64).unwrap();
            let total = check_geometry_u128(&g, 1);
            let g3 = Geometry::new_for(spec, w, h, b, 3, m64).unwrap();
            check_geometry_u128(&g3, 3);
            // The 32-bit target takes it iff the words fit u32.
            let on32 = Geometry::new_for(spec, w, h, b, 1, MAX32);
            if total.div_ceil(32) <= MAX32 as u128 {
                assert_eq!(on32, Ok(g), "{spec:?} {w}x{h}");
            } else {
                assert_eq!(
                    on32,
                    Err(Error::TextureTooLarge {
                        dimension: w.max(h)
                    }),
                    "{spec:?} {w}x{h}"
                );
            }
        }
    }
    // Just below and just above 2^32 - 1 words on a 32-bit target: 32-bit fields (modulus 32)
    // at 65536 x 65535 (2^32 - 2^16 words) and 65536 x 65536 (2^32 words).
    let spec = TiledSpec::FLAT_PACKED.with_modulus(32);
    assert!(Geometry::new_for(spec, 65536, 65535, 16, 1, MAX32).is_ok());
    assert_eq!(
        Geometry::new_for(spec, 65536, 65536, 16, 1, MAX32),
        Err(Error::TextureTooLarge { dimension: 65536 })
    );
}

/// Fuzz finding "the modular size arithmetic is unchecked on 32-bit targets": `words_needed`'s
/// `width * height * C`, `storage_bits`, the corner's and the builder's offsets were `usize`
/// products (2^17 x 2^16 wrapped to 2^33 mod 2^32 = 0 entries on a 32-bit target). The sizes
/// are computed once in `u64` with checks (`Sizes::new` with `u32::MAX` words is the 32-bit
/// target's check) and the offsets of valid corners stay below them.
#[test]
fn fuzz_modular_sizes_checked() {
    let s = Sizes::new(1 << 17, 1 << 16, 32, 1, u64::MAX).unwrap();
    assert_eq!((s.total_bits, s.words as u64), (1 << 38, 1 << 33));
    assert_eq!(
        Sizes::new(1 << 17, 1 << 16, 32, 1, MAX32),
        Err(Error::TextureTooLarge { dimension: 1 << 17 })
    );
    // 2^32 - 2^16 words fit a 32-bit target, 2^32 do not.
    assert_eq!(
        Sizes::new(65536, 65535, 32, 1, MAX32).map(|s| s.words as u64),
        Ok((1 << 32) - (1 << 16))
    );
    assert!(Sizes::new(65536, 65536, 32, 1, MAX32).is_err());
    // u64 bits overflow: (2^31 - 1)^2 entries x 64 bits x 4 channels.
    let n = (1usize << 31) - 1;
    assert_eq!(
        Modular::<u64, 4>::words_needed(n, n, 64),
        Err(Error::TextureTooLarge { dimension: n })
    );
    assert!(Modular::<u64, 4>::from_words(&[], n, n, 8, 64).is_err());
    assert!(ModularBuilder::<u64, 4>::new(n, n, 8, 64, &mut [], &mut []).is_err());
    // k is checked against the value type; dimensions as for every layout.
    assert_eq!(
        Modular::<u16>::words_needed(4, 4, 17),
        Err(Error::InvalidModulus { bits: 17 })
    );
    assert_eq!(
        Modular::<u32>::words_needed(4, 4, 0),
        Err(Error::InvalidModulus { bits: 0 })
    );
    assert_eq!(
        Modular::<u32>::words_needed(0, 4, 8),
        Err(Error::EmptyTexture)
    );
    // Exact products, checked against u128, and the same as the packed helper.
    for (w, h, k, c) in [
        (65536usize, 65536usize, 16u32, 1usize),
        (46341, 46341, 31, 3),
        (n, 1, 64, 4),
        (1, n, 17, 2),
        (12, 9, 12, 1),
    ] {
        let s = Sizes::new(w, h, k, c, u64::MAX).unwrap();
        let total = w as u128 * h as u128 * k as u128 * c as u128;
        assert_eq!(s.total_bits as u128, total);
        assert_eq!(s.words as u128, total.div_ceil(32));
        assert_eq!(s.row_bits as u128, w as u128 * k as u128 * c as u128);
        assert_eq!(s.entry_bits as u128, k as u128 * c as u128);
        assert_eq!(words_for_checked(w * h * c, k), Some(s.words));
    }
    // storage_bits is the checked total.
    let mut words = [0u32; 64];
    let m = Modular::<u32, 3>::from_words(&words, 7, 5, 8, 19).unwrap();
    assert_eq!(m.storage_bits(), 7 * 5 * 3 * 19);
    words[0] = 1;
    assert_eq!(words[0], 1);
}

/// Fuzz finding "the modular builder ignores `write_bits`'s result": a write that does not fit
/// the storage is now an error. (With valid sizes no write fails; the test moves the second
/// row's fields past the end of the storage to make one fail.)
#[test]
fn fuzz_modular_builder_failed_write_is_an_error() {
    let (w, h, k) = (5usize, 3usize, 12u32);
    let tex = texture(w, h, 1);
    let mut words = [0u32; 64];
    let mut row = [0u32; 8];
    let mut b = ModularBuilder::<u32>::new(w, h, 8, k, &mut words, &mut row).unwrap();
    b.push_row(&tex[..w]).unwrap();
    // Row 1 would start at bit 64 * 32: word 64, past the 64 words.
    b.sizes_mut().row_bits = 64 * 32;
    assert_eq!(
        b.push_row(&tex[w..2 * w]),
        Err(Error::StorageTooSmall {
            needed: (64 * 32 + 12u64).div_ceil(32) as usize,
            got: 64
        })
    );
}

/// Xorshift words: a corrupted flash image.
fn noise(n: usize, seed: u32) -> [u32; 4096] {
    let mut out = [0u32; 4096];
    let mut s = seed.wrapping_mul(2654435761) | 1;
    for v in out.iter_mut().take(n) {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        *v = s;
    }
    out
}

/// Every corner (in range, on the edges and far outside) and every integer box under every
/// mode, and fractional boxes inside: must not panic. Returns a checksum so nothing is
/// optimized away.
fn poke<L: BoxLookup<C>, const C: usize>(l: &L) -> u64 {
    let (w, h) = (l.width(), l.height());
    let mut sum = 0u64;
    let mut k = Tally::new();
    for y in span_usize(0, h + 2).chain([usize::MAX, usize::MAX / 2, 1 << 31, 1 << 32]) {
        for x in span_usize(0, w + 2).chain([usize::MAX, usize::MAX / 2, 1 << 31, 1 << 32]) {
            let v = l.corner(x, y, &mut k);
            if x > w || y > h || x == 0 || y == 0 {
                assert!(v.iter().all(|e| e.to_u64() == 0), "({x}, {y})");
            }
            sum = v.iter().fold(sum, |s, e| s.wrapping_add(e.to_u64()));
        }
    }
    // Every box on the small textures; on the larger ones, boxes from the corner.
    let (wi, hi) = (w as i32, h as i32);
    let lo = if w * h <= 35 { -1 } else { wi - 1 };
    // Under Miri every 29th box of the spans (the first included).
    let mut case = 0u32;
    for x0 in span(lo, wi + 1) {
        for x1 in span(x0, wi + 1) {
            for y0 in span(-1, hi + 1) {
                for y1 in span(y0, hi + 1) {
                    case += 1;
                    if cfg!(miri) && case % 29 != 1 {
                        continue;
                    }
                    let r = Rect::new(x0, y0, x1, y1);
                    for s in [
                        l.box_sum_int(&r, Border, &mut k),
                        l.box_sum_int(&r, Repeat, &mut k),
                    ]
                    .into_iter()
                    .flatten()
                    {
                        sum = sum.wrapping_add(Into::<u128>::into(s.sum()) as u64);
                    }
                }
            }
        }
    }
    let f = |v: f64| I28F4::from_num(v);
    for (x0, y0, x1, y1) in [(0.0, 0.0, w as f64, h as f64), (0.25, 0.5, 0.75, 0.5625)] {
        let r = Rect::new(f(x0), f(y0), f(x1), f(y1));
        if let Ok(s) = l.box_sum(&r, Stable, Border, &mut k) {
            sum = sum.wrapping_add(Into::<u128>::into(s.sum()) as u64);
        }
    }
    sum
}

/// Fuzz finding "`Tiled::from_words` with corrupted words must never panic": random words,
/// all ones, and storage one word longer than needed, under every spec, value type and channel
/// count; every corner (also out of range: those give 0) and every integer box. Modular too.
#[test]
fn fuzz_corrupt_words_never_panic() {
    let specs = [
        TiledSpec::FLAT_PACKED,
        TiledSpec::tiles(4, 4).unwrap(),
        TiledSpec::tiles(3, 5).unwrap(),
        TiledSpec::square(&[2, 6, 12]).unwrap(),
        TiledSpec::square(&[2, 4, 8, 16]).unwrap(),
        TiledSpec::tiles(4, 4).unwrap().with_modulus(13),
    ];
    let mut check = 0u64;
    // Under Miri (about 10^4 times slower) every 9th combination of size, spec and fill, and
    // the modular layouts on the first and last sizes only.
    let mut combo = 0u32;
    for (size, (w, h)) in [(1usize, 1usize), (7, 5), (16, 16), (13, 17)]
        .into_iter()
        .enumerate()
    {
        for (n, spec) in specs.iter().enumerate() {
            for fill in 0..3u32 {
                combo += 1;
                if cfg!(miri) && combo % 9 != 1 {
                    continue;
                }
                let words = |need: usize| -> [u32; 4096] {
                    match fill {
                        0 => noise(need + 1, (w * 97 + h * 13 + n) as u32),
                        1 => [u32::MAX; 4096],
                        _ => noise(4096, 7),
                    }
                };
                let need = Tiled::<u32>::words_needed(*spec, w, h, 8).unwrap();
                let ws = words(need);
                let t = Tiled::<u32>::from_words(&ws[..need], *spec, w, h, 8).unwrap();
                check = check.wrapping_add(poke(&t));
                // 16-bit texels (refused under the 13-bit modulus), 3 channels, u64 values.
                if let Ok(need) = Tiled::<u64, 3>::words_needed(*spec, w, h, 16) {
                    let ws = words(need);
                    let t = Tiled::<u64, 3>::from_words(&ws[..need], *spec, w, h, 16).unwrap();
                    check = check.wrapping_add(poke(&t));
                }
                // 1-bit texels, u16 values.
                let need = Tiled::<u16>::words_needed(*spec, w, h, 1).unwrap();
                let ws = words(need);
                let t = Tiled::<u16>::from_words(&ws[..need], *spec, w, h, 1).unwrap();
                check = check.wrapping_add(poke(&t));
            }
        }
        if cfg!(miri) && size % 3 != 0 {
            continue;
        }
        for k in [8u32, 13, 32] {
            let need = Modular::<u32>::words_needed(w, h, k).unwrap();
            let ws = noise(need, k);
            let m = Modular::<u32>::from_words(&ws[..need], w, h, 8, k).unwrap();
            check = check.wrapping_add(poke(&m));
        }
        for k in [16u32, 40, 64] {
            let need = Modular::<u64, 3>::words_needed(w, h, k).unwrap();
            let ws = [u32::MAX; 4096];
            let m = Modular::<u64, 3>::from_words(&ws[..need], w, h, 16, k).unwrap();
            check = check.wrapping_add(poke(&m));
        }
    }
    assert_ne!(check, 0);
}

/// The power-of-two digits (shifts and masks) equal the division digits and the definition
/// `d_p = (x mod b_{p+1}) / b_p` (top: `x / b_L`), with the index of `trunc_p(x)` equal to
/// the number of stored positions of component `p` in `[1, trunc_p(x)]` minus one, for every
/// `x` up to 5000 and a few far ones; `step` gives the same level by level.
#[test]
fn pow2_digits_equal_division_digits() {
    let pow2: [&[u32]; 7] = [
        &[2],
        &[8],
        &[2, 16],
        &[4, 8, 64],
        &[2, 4, 8, 16],
        &[1024],
        &[1 << 30],
    ];
    let other: [&[u32]; 5] = [&[3], &[2, 6, 12], &[3, 6], &[4, 12], &[5, 10, 20, 40]];
    for (blocks, is_pow2) in pow2
        .iter()
        .map(|b| (*b, true))
        .chain(other.iter().map(|b| (*b, false)))
        .chain([(&[][..], true)])
    {
        let a = Axis::new(&AxisLevels::new(blocks).unwrap());
        assert_eq!(a.is_pow2(), is_pow2, "{blocks:?}");
        let d = a.by_division();
        // Under Miri (about 10^4 times slower) every x below 70 (past the digit boundaries of
        // the blocks up to 64), every 499th, and the neighbours of 1024 and 4096.
        let xs: Vec<u32> = if cfg!(miri) {
            (0..70)
                .chain((499..5000).step_by(499))
                .chain([1023, 1024, 1025, 4095, 4096, 4097])
                .collect()
        } else {
            (0..5000).collect()
        };
        let xs = xs
            .into_iter()
            .chain([u32::MAX, (1 << 31) - 1, 1 << 30, 123_456_789]);
        for x in xs {
            let (fast, slow) = (a.digits(x), d.digits(x));
            let mut q = x;
            for p in 0..=blocks.len() {
                let b = if p == 0 { 1 } else { blocks[p - 1] };
                let want = match blocks.get(p) {
                    Some(&nb) => (x % nb) / b,
                    None => x / b,
                };
                assert_eq!(fast.digit[p], want, "{blocks:?} x={x} p={p}");
                assert_eq!(slow.digit[p], want, "{blocks:?} x={x} p={p}");
                let (sd, si, sq) = a.step(p, q).unwrap();
                assert_eq!(sd, want);
                q = sq;
                if want != 0 {
                    let t = x - x % b;
                    let idx = count128(blocks, p, t as u128) - 1;
                    assert_eq!(fast.index[p] as u128, idx, "{blocks:?} x={x} p={p}");
                    assert_eq!(slow.index[p], fast.index[p]);
                    assert_eq!(si, fast.index[p]);
                }
            }
            assert_eq!(a.step(blocks.len() + 1, q), None);
            // The row step's (q, iy): the lowest non-zero digit's component and index.
            let want = (0..=blocks.len())
                .find(|&p| fast.digit[p] != 0)
                .map(|p| (p, fast.index[p]));
            assert_eq!(a.lowest(x), want, "{blocks:?} x={x}");
            assert_eq!(d.lowest(x), want, "{blocks:?} x={x}");
        }
    }
}

/// The straight-line one-level corner equals the general one on every corner (power-of-two
/// tiles, other tiles, and mixed axes), and both equal the flat table on every box: the
/// power-of-two fast path against the general path, exhaustively.
#[test]
fn pow2_fast_path_equals_general_path_every_box() {
    let level = |b: &[u32]| AxisLevels::new(b).unwrap();
    let mixed = |x: &[u32], y: &[u32]| TiledSpec {
        x: level(x),
        y: level(y),
        modulus: None,
    };
    let specs = [
        TiledSpec::tiles(4, 4).unwrap(),
        TiledSpec::tiles(8, 2).unwrap(),
        TiledSpec::tiles(2, 16).unwrap(),
        TiledSpec::tiles(3, 5).unwrap(),
        TiledSpec::tiles(4, 3).unwrap(),
        TiledSpec::tiles(6, 8).unwrap(),
        TiledSpec::square(&[2, 4, 8, 16]).unwrap(),
        TiledSpec::square(&[2, 6, 12]).unwrap(),
        mixed(&[2, 8], &[3]),
        mixed(&[3, 9], &[4, 16]),
        mixed(&[], &[4]),
        mixed(&[5], &[]),
        TiledSpec::tiles(4, 4).unwrap().with_modulus(13),
        TiledSpec::tiles(3, 5).unwrap().with_modulus(13),
    ];
    // Under Miri (about 10^4 times slower) every 5th combination of size and spec (5 is coprime
    // to the 14 specs, so each spec still runs once, on a different size), and every 7th corner
    // of the spans.
    let mut combo = 0u32;
    for (w, h) in [(9usize, 10usize), (16, 13), (17, 17), (32, 5), (5, 33)] {
        let tex = texture(w, h, (w * 7 + h) as u32);
        let t = Texture::<u8>::new(&tex[..w * h], w, h).unwrap();
        let mut flat_st = [0u32; 4096];
        let flat = Sat::build(&t, &mut flat_st).unwrap();
        for spec in specs {
            combo += 1;
            if cfg!(miri) && combo % 5 != 1 {
                continue;
            }
            let mut corner = 0u32;
            let mut words = [0u32; 4096];
            let mut scratch = [0u32; 512];
            let l = Tiled::<u32>::build(&t, spec, &mut words, &mut scratch).unwrap();
            let g = l.geometry();
            for y in span(1, h as i32).map(|v| v as u32) {
                for x in span(1, w as i32).map(|v| v as u32) {
                    corner += 1;
                    if cfg!(miri) && corner % 7 != 1 {
                        continue;
                    }
                    let (mut fast, mut general) = ([0u32], [0u32]);
                    let (mut kf, mut kg) = (Tally::new(), Tally::new());
                    l.corner_one_level(x, y, &mut fast, &mut kf);
                    l.corner_general(x, y, &mut general, &mut kg);
                    assert_eq!(fast, general, "{spec:?} ({x},{y})");
                    assert_eq!(kf, kg, "{spec:?} ({x},{y})");
                    let want = flat.corner(x as usize, y as usize).unwrap()[0];
                    let got = l.corner(x as usize, y as usize, &mut NoCount)[0];
                    match spec.modulus {
                        Some(m) => assert_eq!(got, want & ((1 << m) - 1)),
                        None => assert_eq!(got, want, "{spec:?} ({x},{y})"),
                    }
                }
            }
            assert!(g.total_bits > 0);
            if spec.modulus.is_none() {
                check_all_boxes(&l, &flat);
            }
        }
    }
}

/// The sizes are `const fn`s: a `static` sized at compile time, built into at run time.
#[test]
fn const_sizes_for_statics() {
    const SPEC: TiledSpec = match TiledSpec::tiles(8, 8) {
        Ok(s) => s,
        Err(_) => panic!(),
    };
    const TW: usize = match Tiled::<u32>::words_needed(SPEC, 40, 24, 8) {
        Ok(n) => n,
        Err(_) => panic!(),
    };
    const TS: usize = match Tiled::<u32>::scratch_needed(SPEC, 40) {
        Ok(n) => n,
        Err(_) => panic!(),
    };
    const MW: usize = match Modular::<u32>::words_needed(40, 24, 16) {
        Ok(n) => n,
        Err(_) => panic!(),
    };
    const PW: usize = match words_for_checked(40 * 24, 13) {
        Some(n) => n,
        None => panic!(),
    };
    static FLASH: [u32; TW] = [0; TW];
    assert_eq!(Tiled::<u32>::words_needed(SPEC, 40, 24, 8), Ok(TW));
    assert_eq!(TS, 3 * 41);
    assert_eq!(MW, 40 * 24 / 2);
    assert_eq!(PW, (40 * 24 * 13usize).div_ceil(32));
    let tex = texture(40, 24, 5);
    let t = Texture::<u8>::new(&tex[..40 * 24], 40, 24).unwrap();
    let mut words = [0u32; TW];
    let mut scratch = [0u32; TS];
    let l = Tiled::<u32>::build(&t, SPEC, &mut words, &mut scratch).unwrap();
    let mut flat_st = [0u32; 4096];
    let flat = Sat::build(&t, &mut flat_st).unwrap();
    assert_eq!(l.corner(40, 24, &mut NoCount), flat.corner(40, 24).unwrap());
    let z = Tiled::<u32>::from_words(&FLASH, SPEC, 40, 24, 8).unwrap();
    assert_eq!(z.corner(40, 24, &mut NoCount), [0]);
    let mut mw = [0u32; MW];
    let mut row = [0u32; 40];
    let m = Modular::<u32>::build(&t, 16, &mut mw, &mut row).unwrap();
    assert_eq!(
        m.box_sum_int(&Rect::new(3, 4, 10, 9), Border, &mut NoCount),
        flat.box_sum_int(&Rect::new(3, 4, 10, 9), Border, &mut NoCount)
    );
}

/// Multi-channel tiled layouts, every corner and every cell's four corners against sums
/// computed here texel by texel: narrow texels (`texel_bits` 1 and 2) so that two entries of
/// `C` channels fit one 32-bit read (the lookups' paired read of entries side by side), and
/// 8-bit ones so that they do not; one-level power-of-two tiles (the fast paths) and others.
#[test]
fn tiled_channels_every_corner_and_cell() {
    fn check<const C: usize>(texel_bits: u32, w: usize, h: usize, spec: TiledSpec) {
        let t = texture(w * C, h, (w * 131 + h * 7 + C) as u32);
        let texels: Vec<u8> = t[..w * h * C]
            .iter()
            .map(|&v| v & ((1u16 << texel_bits) - 1) as u8)
            .collect();
        // S(x, y) per channel, texel by texel.
        let s = |x: usize, y: usize| -> [u32; C] {
            core::array::from_fn(|c| {
                let mut sum = 0u32;
                for j in 0..y {
                    for i in 0..x {
                        sum += u32::from(texels[(j * w + i) * C + c]);
                    }
                }
                sum
            })
        };
        let mut words =
            std::vec![0u32; Tiled::<u32, C>::words_needed(spec, w, h, texel_bits).unwrap()];
        let mut scratch = std::vec![0u32; Tiled::<u32, C>::scratch_needed(spec, w).unwrap()];
        let mut b =
            TiledBuilder::<u32, C>::new(spec, w, h, texel_bits, &mut words, &mut scratch).unwrap();
        for row in texels.chunks_exact(w * C) {
            b.push_row(row).unwrap();
        }
        let l = b.finish().unwrap();
        let what = (C, texel_bits, w, h, spec);
        for y in 0..=h {
            for x in 0..=w {
                assert_eq!(l.corner(x, y, &mut NoCount), s(x, y), "{what:?} ({x}, {y})");
            }
        }
        for j in 0..h {
            for i in 0..w {
                let want = [s(i, j), s(i + 1, j), s(i, j + 1), s(i + 1, j + 1)];
                assert_eq!(
                    l.cell_corners(i, j, &mut NoCount),
                    want,
                    "{what:?} cell ({i}, {j})"
                );
            }
        }
    }
    let specs = [
        TiledSpec::tiles(4, 4).unwrap(),
        TiledSpec::tiles(8, 2).unwrap(),
        TiledSpec::tiles(3, 5).unwrap(),
        TiledSpec::square(&[2, 4]).unwrap(),
    ];
    // Under Miri (about 10^4 times slower) one size, the first and last specs (one level of
    // power-of-two tiles, two levels), 2- and 8-bit texels.
    let sizes: &[(usize, usize)] = if cfg!(miri) {
        &[(9, 7)]
    } else {
        &[(9, 7), (16, 13)]
    };
    let miri_skips = |i: usize| cfg!(miri) && i != 0 && i != specs.len() - 1;
    for (_, spec) in specs
        .into_iter()
        .enumerate()
        .filter(|&(i, _)| !miri_skips(i))
    {
        for &(w, h) in sizes {
            for bits in [1, 2, 8].into_iter().filter(|&b| !cfg!(miri) || b != 1) {
                check::<2>(bits, w, h, spec);
                check::<3>(bits, w, h, spec);
            }
        }
    }
}

/// The tiled layout's `cells4_placed` (its four-cell fast path when every cell lies inside its
/// tile, cell by cell otherwise) gives the values (modulo 2^k under a modular spec), counts and
/// read order of four `cell_corners_placed` calls in its order, for every choice of two columns and two rows on
/// small textures (cells inside tiles, on their edges, mixed), every spec kind.
#[test]
fn tiled_cells4_equals_four_cells() {
    use crate::cost::{Counter, Region};
    /// Everything a counter hears, in order.
    #[derive(Default, PartialEq, Debug)]
    struct Trace(Vec<(u8, u64, u32)>);
    impl Counter for Trace {
        fn reads(&mut self, n: u32, bits: u32) {
            self.0.push((0, u64::from(n), bits));
        }
        fn muls(&mut self, n: u32) {
            self.0.push((1, u64::from(n), 0));
        }
        fn divs(&mut self, n: u32) {
            self.0.push((2, u64::from(n), 0));
        }
        fn adds(&mut self, n: u32) {
            self.0.push((3, u64::from(n), 0));
        }
        fn words(&mut self, n: u32) {
            self.0.push((4, u64::from(n), 0));
        }
        fn read_at(&mut self, _: Region, offset: u64, bits: u32) {
            self.0.push((5, offset, bits));
        }
    }
    fn check<const C: usize>(w: usize, h: usize, spec: TiledSpec) {
        let texels: Vec<u8> = texture(w * C, h, (w * 31 + h + C) as u32)[..w * h * C].to_vec();
        let mut words = std::vec![0u32; Tiled::<u32, C>::words_needed(spec, w, h, 8).unwrap()];
        let mut scratch = std::vec![0u32; Tiled::<u32, C>::scratch_needed(spec, w).unwrap()];
        let mut b = TiledBuilder::<u32, C>::new(spec, w, h, 8, &mut words, &mut scratch).unwrap();
        for row in texels.chunks_exact(w * C) {
            b.push_row(row).unwrap();
        }
        let l = b.finish().unwrap();
        // Under Miri every third column and row.
        let step = if cfg!(miri) { 3 } else { 1 };
        for i0 in (0..w).step_by(step) {
            for i1 in (0..w).step_by(step) {
                for j0 in (0..h).step_by(step) {
                    for j1 in (0..h).step_by(step) {
                        let (mut a, mut b) = (Trace::default(), Trace::default());
                        let mut got = l.cells4_placed([i0, i1], [j0, j1], &mut a);
                        // A modular spec's four cells are congruent modulo 2^k (the lookups
                        // reduce after their differences): compared reduced.
                        if let Some(m) = spec.modulus {
                            for v in got.iter_mut().flatten().flatten() {
                                *v = v.low_bits(m);
                            }
                        }
                        let want = [
                            l.cell_corners_placed(i1, j1, &mut b),
                            l.cell_corners_placed(i1, j0, &mut b),
                            l.cell_corners_placed(i0, j1, &mut b),
                            l.cell_corners_placed(i0, j0, &mut b),
                        ];
                        let what = (C, w, h, spec, i0, i1, j0, j1);
                        assert_eq!(got, want, "{what:?}");
                        assert_eq!(a, b, "{what:?}");
                    }
                }
            }
        }
    }
    let specs = [
        TiledSpec::tiles(4, 4).unwrap(),
        TiledSpec::tiles(8, 2).unwrap(),
        TiledSpec::tiles(3, 5).unwrap(),
        TiledSpec::square(&[2, 4]).unwrap(),
        TiledSpec::tiles(4, 4).unwrap().with_modulus(12),
    ];
    for spec in specs {
        check::<1>(11, 9, spec);
        if !cfg!(miri) {
            check::<2>(9, 7, spec);
        }
    }
}

/// The tiled four-cell reader against the flat table on fields too wide to pair in one 32-bit
/// read (16-bit texels: 20-bit local sums and strips) and on the firmware's shape (8-bit
/// texels, 8 x 8 tiles, 64 x 64: paired 14-bit local sums, unpaired 17-bit strips), one and
/// two channels: every cell's four corners equal the flat table's `S`, reduced modulo `2^k` on
/// a modular spec. The cell reader's two-window reads (`read2_32`) on every path.
#[test]
fn tiled_cells4_equal_the_flat_table_on_wide_fields() {
    fn check<T: crate::Texel, const C: usize>(
        texels: &[T],
        w: usize,
        h: usize,
        bits: u32,
        spec: TiledSpec,
    ) -> [u32; 2] {
        let t = Texture::<T, C>::new(texels, w, h).unwrap();
        let mut flat_st = std::vec![0u32; w * h * C];
        let flat = Sat::build(&t, &mut flat_st).unwrap();
        let mut words = std::vec![0u32; Tiled::<u32, C>::words_needed(spec, w, h, bits).unwrap()];
        let mut scratch = std::vec![0u32; Tiled::<u32, C>::scratch_needed(spec, w).unwrap()];
        let l = Tiled::<u32, C>::build(&t, spec, &mut words, &mut scratch).unwrap();
        let reduce = |v: [u32; C]| match spec.modulus {
            Some(m) => v.map(|e| e & ((1u32 << m) - 1)),
            None => v,
        };
        let s = |x: usize, y: usize| reduce(flat.corner(x, y).unwrap());
        let cell = |i: usize, j: usize| [s(i, j), s(i + 1, j), s(i, j + 1), s(i + 1, j + 1)];
        // Every column and row up to 20, every 5th past it; under Miri every 7th and 31st.
        let step = |n: usize| match (cfg!(miri), n <= 20) {
            (false, true) => 1,
            (false, false) => 5,
            (true, true) => 7,
            (true, false) => 31,
        };
        for i0 in (0..w).step_by(step(w)) {
            for i1 in (0..w).step_by(step(w)) {
                for j0 in (0..h).step_by(step(h)) {
                    for j1 in (0..h).step_by(step(h)) {
                        let got = l.cells4_placed([i0, i1], [j0, j1], &mut NoCount);
                        let want = [cell(i1, j1), cell(i1, j0), cell(i0, j1), cell(i0, j0)];
                        assert_eq!(got, want, "{:?}", (C, w, h, spec, i0, i1, j0, j1));
                    }
                }
            }
        }
        [0, 1].map(|q| l.field_bits(0, q).unwrap())
    }
    let wide: Vec<u16> = (0..19 * 13 * 2)
        .map(|i: u32| (i.wrapping_mul(0x9E37_79B9) >> 16) as u16)
        .collect();
    for spec in [
        TiledSpec::tiles(4, 4).unwrap(),
        TiledSpec::tiles(8, 4).unwrap(),
        TiledSpec::tiles(4, 4).unwrap().with_modulus(24),
    ] {
        // Local sums and strips wider than 16 bits: no two fit one 32-bit read.
        let [b00, b01] = check::<u16, 1>(&wide[..19 * 13], 19, 13, 16, spec);
        assert!(b00 > 16 && b01 > 16, "{spec:?}: {b00}, {b01}");
        check::<u16, 2>(&wide, 19, 13, 16, spec);
    }
    // The firmware's shape: local sums paired (14 bits), strips above not (17 bits).
    let tex = texture(64, 64, 7);
    let [b00, b01] = check::<u8, 1>(&tex, 64, 64, 8, TiledSpec::tiles(8, 8).unwrap());
    assert_eq!((b00, b01), (14, 17));
}

/// The fused modular row (`simd::modular_row`) with its working row at every rotation: the
/// caller's row 0 to 7 entries past 32 bytes, so that the row's last vector crosses its end
/// (512 x 21, no tail), the tail is shorter than the rotation (515 and 517 x 32) or longer
/// (520 x 16, 544 x 21, in two runs), with the layout taken as past the caches or not (the
/// streamed stores with AVX-512 VL; 515 x 32's rows alternate between 16 bytes and off them),
/// and a `u16` row in the middle (the working row put back in position order, the portable
/// path after it). Every corner against the summed-area table mod `2^k`.
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
#[test]
fn modular_rows_in_every_rotation() {
    #[repr(align(32))]
    struct Rows([u32; 560]);
    let h = if cfg!(miri) { 3 } else { 5 };
    for (w, k) in [(512, 21), (515, 32), (517, 32), (520, 16), (544, 21)] {
        let texels = noise_bytes(w * h, w as u64 + u64::from(k));
        let mut rows = Rows([7; 560]);
        for (shift, past) in (0..8).flat_map(|s| [(s, false), (s, true)]) {
            if cfg!(miri) && !matches!(shift, 0 | 3 | 4) {
                continue;
            }
            let mut words = std::vec![0u32; (w * h * k as usize).div_ceil(32)];
            // With AVX-512 VL the rows taken as past the caches whose words start on 16 bytes
            // are streamed (the first at least, when the words do); no others.
            let may_stream = past && crate::simd::Kernel::Avx512Vnni.available();
            let must_stream = may_stream && (words.as_ptr() as usize).is_multiple_of(16);
            let streamed_before = crate::simd::STREAMED_ROWS.with(|c| c.get());
            let row = &mut rows.0[shift..shift + w];
            let mut b = ModularBuilder::<u32>::new(w, h, 8, k, &mut words, row).unwrap();
            b.set_past(past);
            for y in 0..h {
                let r = &texels[y * w..(y + 1) * w];
                if y == 2 {
                    let wide: Vec<u16> = r.iter().map(|&t| u16::from(t)).collect();
                    b.push_row(&wide).unwrap();
                } else {
                    b.push_row(r).unwrap();
                }
            }
            let m = b.finish().unwrap();
            let streamed = crate::simd::STREAMED_ROWS.with(|c| c.get()) - streamed_before;
            assert!(
                (streamed > 0 || !must_stream) && (streamed == 0 || may_stream),
                "{w} x {k}, past {past}: {streamed} rows streamed"
            );
            let what = std::format!("row {shift} past 32 bytes, past {past}");
            check_modular_corners(&m, &texels, w, h, k, &what);
        }
    }
}

/// Every corner of `m` (a `w x h` modular layout of `texels` at `k` bits) against the
/// summed-area table mod `2^k`, computed row by row here.
fn check_modular_corners(
    m: &Modular<'_, u32>,
    texels: &[u8],
    w: usize,
    h: usize,
    k: u32,
    what: &str,
) {
    let mask = if k == 32 { u32::MAX } else { (1u32 << k) - 1 };
    let mut above = std::vec![0u32; w + 1];
    for y in 1..=h {
        let mut run = 0u32;
        for x in 1..=w {
            run = run.wrapping_add(u32::from(texels[(y - 1) * w + x - 1]));
            above[x] = above[x].wrapping_add(run);
            let got = m.corner(x, y, &mut NoCount)[0];
            assert_eq!(
                got & mask,
                above[x] & mask,
                "{w}x{h} k {k}, {what}: ({x}, {y})"
            );
        }
    }
}

/// The modular builder under every build kernel this CPU runs (with `simd`: the fused AVX2 row,
/// `simd::modular_row`, under the AVX2 and AVX-512 kernels, the row kernel and packer under
/// SSE2 and wherever the fused row does not apply): every corner of noise textures equals the
/// summed-area table mod `2^k`, for widths and `k` with whole passes of 256 texels on rows that start on a word (512 x 21, 520 x 12,
/// 544 x 20: fused, with a tail after the passes) and without (520 x 21: rows off a word).
#[test]
fn modular_rows_under_every_kernel() {
    fn check(w: usize, h: usize, k: u32) {
        let texels = noise_bytes(w * h, w as u64 * 31 + u64::from(k));
        let tex = Texture::<u8>::new(&texels, w, h).unwrap();
        let mut words = std::vec![0u32; (w * h * k as usize).div_ceil(32) + 1];
        let mut row = std::vec![0u32; w + 1];
        let m = Modular::<u32>::build(&tex, k, &mut words, &mut row).unwrap();
        check_modular_corners(&m, &texels, w, h, k, "under every kernel");
    }
    let cases = || {
        for (w, k) in [(512, 21), (520, 12), (544, 20), (520, 21)] {
            check(w, if cfg!(miri) { 2 } else { 5 }, k);
        }
    };
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    for kernel in crate::simd::Kernel::ALL
        .into_iter()
        .filter(|k| k.available())
    {
        kernel.cap(cases);
    }
    #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
    cases();
}

/// The tiled builder's rows that end a tile row in the band form (8 x 8 tiles, `u8` texels,
/// `u32` entries), under every build kernel this CPU runs: every corner of noise and saturated
/// textures equals the summed-area table. Widths whose component rows all start on a word
/// (256, 512, 1,024, and 384 with 128 columns after its chunk: packed in the pass with
/// AVX-512BW, `simd::band512::end_row_packed`, its chunks counted), others whose rows do not
/// (808 x 27, 520 x 24) or that have no whole chunk (136); heights with a partial tile row
/// last (17, 27).
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
#[test]
fn tiled_end_rows_under_every_kernel() {
    fn check(w: usize, h: usize, full: bool) -> usize {
        let texels = if full {
            std::vec![255u8; w * h]
        } else {
            noise_bytes(w * h, w as u64 * 131 + h as u64)
        };
        let tex = Texture::<u8>::new(&texels, w, h).unwrap();
        let spec = TiledSpec::tiles(8, 8).unwrap();
        let mut words = std::vec![0u32; Tiled::<u32>::words_needed(spec, w, h, 8).unwrap()];
        let mut scratch = std::vec![0u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
        let before = crate::simd::END_CHUNKS.with(|c| c.get());
        let t = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).unwrap();
        let chunks = crate::simd::END_CHUNKS.with(|c| c.get()) - before;
        let mut above = std::vec![0u32; w + 1];
        for y in 1..=h {
            let mut run = 0u32;
            for x in 1..=w {
                run += u32::from(texels[(y - 1) * w + x - 1]);
                above[x] += run;
                let got = t.corner(x, y, &mut NoCount)[0];
                assert_eq!(got, above[x], "{w}x{h}, full {full}: ({x}, {y})");
            }
        }
        chunks
    }
    // (w, h, the chunks each row that ends a tile row packs in the pass with AVX-512BW).
    let sizes = [
        (512, 24, 2),
        (256, 16, 1),
        (1024, 17, 4),
        (384, 24, 1),
        (808, 27, 0),
        (520, 24, 0),
        (136, 16, 0),
    ];
    under_every_kernel(|kernel, packs| {
        for &(w, h, per_row) in &sizes {
            for full in [false, true] {
                let chunks = check(w, h, full);
                // Where both components' rows all start on a word (7/8 of 256 columns are 224 k
                // bits, their boundaries 32 k; 384 x 24: 336 fields of 16 bits and 48 of 22),
                // every row that ends a tile row packs all its chunks in the pass, and the 128
                // columns after them go to the packer (384); where they do not (808 x 27, 520 x
                // 24: 707 and 455 fields of 16 bits per row of `(0, 1)`), or without a whole
                // chunk (136), none.
                let want = if packs { h / 8 * per_row } else { 0 };
                assert_eq!(chunks, want, "{w}x{h}, full {full}, under {kernel:?}");
            }
        }
    });
}

/// Runs `f(kernel, packs)` under every build kernel this CPU runs ([`Kernel::cap`]), `packs`
/// telling whether that kernel takes the paths that pack in the pass (AVX-512 with VBMI).
///
/// [`Kernel::cap`]: crate::simd::Kernel::cap
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
fn under_every_kernel(mut f: impl FnMut(crate::simd::Kernel, bool)) {
    let fused =
        crate::simd::Kernel::best() == crate::simd::Kernel::Avx512Vnni && crate::simd::vbmi();
    for kernel in crate::simd::Kernel::ALL
        .into_iter()
        .filter(|k| k.available())
    {
        kernel.cap(|| f(kernel, fused && kernel == crate::simd::Kernel::Avx512Vnni));
    }
}

/// `Tiled::build`, which takes the band rows of a tile row in runs where it can
/// (`TiledBuilder::push_band_rows`, `simd::band_rows`: one level of tiles 8 wide, local sums
/// of 8 to 14 bits, and with AVX-512 VBMI whole pairs of blocks, with AVX2 alone widths a
/// multiple of 128: 128, 256 and 512 here), against `TiledBuilder::push_row` row by
/// row: the same words, every bit, and exactly the rows the runs should take (the rest of each
/// tile row's band rows, at most 8: the scratch row; at least 2). Tiles 8 wide and 2 to 16
/// high: runs of 7 band rows (8 x 8, 8-bit texels: local sums of 14 bits), of 3 (8 x 4, 7-bit
/// texels: 12 bits) and of 15 split 8 + 7 (8 x 16, 7-bit texels: 14 bits), none for local sums
/// of 11, 13 and 15 bits (8 x 2, 8 x 4 and 8 x 16 with 8-bit texels); two levels on y (8 and
/// 32, 8 and 64); widths with whole pairs and without (40, 520); heights with a partial tile
/// row last (shorter runs); rows a stride apart wider than the texture; the first rows pushed
/// one by one before the rest (a run starting inside a tile row); noise and saturated
/// textures; under every build kernel this CPU runs.
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
#[test]
fn tiled_band_runs_equal_row_by_row() {
    struct Case {
        spec: TiledSpec,
        w: usize,
        h: usize,
        bits: u32,
        pad: usize,
        first: usize,
    }
    fn check(c: &Case, full: bool, kernel: crate::simd::Kernel, packs: bool) {
        let Case {
            spec,
            w,
            h,
            bits,
            pad,
            first,
        } = *c;
        let top = (1u16 << bits) - 1;
        let stride = w + pad;
        let texels: Vec<u8> = if full {
            std::vec![top as u8; stride * h]
        } else {
            let n = noise_bytes(stride * h, w as u64 * 7 + h as u64);
            n.into_iter().map(|t| (u16::from(t) & top) as u8).collect()
        };
        let tex = Texture::<u8>::with_stride(&texels, w, h, stride).unwrap();
        let need = Tiled::<u32>::words_needed(spec, w, h, bits).unwrap();
        let mut scratch = std::vec![0u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
        let mut want = std::vec![0x5a5a_5a5au32; need + 2];
        let mut b = TiledBuilder::<u32>::new(spec, w, h, bits, &mut want, &mut scratch).unwrap();
        for y in 0..h {
            b.push_row(tex.row(y).unwrap()).unwrap();
        }
        b.finish().unwrap();
        let mut words = std::vec![0x5a5a_5a5au32; need + 2];
        let before = crate::simd::RUN_ROWS.with(|c| c.get());
        let mut b = TiledBuilder::<u32>::new(spec, w, h, bits, &mut words, &mut scratch).unwrap();
        for y in 0..first {
            b.push_row(tex.row(y).unwrap()).unwrap();
        }
        b.push_texture(&tex).unwrap();
        b.finish().unwrap();
        let runs = crate::simd::RUN_ROWS.with(|c| c.get()) - before;
        let what = std::format!("{spec:?} {w}x{h} (+{pad}), {bits} bits, from {first}");
        assert_eq!(words, want, "{what}, full {full}");
        // The rows the runs should take: from each row on, the rest of its tile row's band
        // rows (th: the lowest y level), at most 8, when 2 or more.
        let t = Tiled::<u32>::from_words(&words, spec, w, h, bits).unwrap();
        let k = t.field_bits(0, 0).unwrap();
        let th = spec.y.blocks()[0] as usize;
        // Widths the runs take: whole pairs of blocks where the kernel packs in its pass,
        // whole steps of 16 local sums (a multiple of 128) on the AVX2 run.
        let whole = if packs {
            w % 32 == 0
        } else {
            kernel != crate::simd::Kernel::Sse2 && w % 128 == 0
        };
        let fits = whole && spec.x.blocks().len() == 1 && matches!(k, 8 | 10 | 12 | 14);
        let mut expect = 0;
        let mut y = first;
        while fits && y < h {
            let r = (th - 1 - y % th).min(h - y).min(8);
            if r >= 2 {
                expect += r;
                y += r;
            } else {
                y += 1;
            }
        }
        assert_eq!(runs, expect, "{what}, k {k}");
    }
    let spec = |x: &[u32], y: &[u32]| TiledSpec {
        x: AxisLevels::new(x).unwrap(),
        y: AxisLevels::new(y).unwrap(),
        modulus: None,
    };
    let mut cases = Vec::new();
    for (th, bits) in [(2u32, 8u32), (4, 8), (4, 7), (8, 8), (16, 8), (16, 7)] {
        for (w, h) in [(32, 16), (64, 21), (256, 35), (512, 17), (40, 16), (520, 9)] {
            let (pad, first) = (0, 0);
            cases.push(Case {
                spec: spec(&[8], &[th]),
                w,
                h,
                bits,
                pad,
                first,
            });
        }
    }
    for (y, bits) in [(&[8u32, 32][..], 6u32), (&[8, 64][..], 6), (&[8][..], 8)] {
        for (w, h, pad, first) in [(64, 75, 0, 0), (96, 40, 5, 3), (128, 33, 32, 10)] {
            cases.push(Case {
                spec: spec(&[8], y),
                w,
                h,
                bits,
                pad,
                first,
            });
        }
    }
    under_every_kernel(|kernel, packs| {
        for c in &cases {
            for full in [false, true] {
                check(c, full, kernel, packs);
            }
        }
    });
}
