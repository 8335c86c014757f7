//! Point sampling: the texel nearest the footprint's centre (Heckbert 1986, "Comparison of
//! Prefiltering Methods": "point sampling", impulse filter, 1 access, 0 multiplies, memory 1).
//!
//! The footprint `[x0, x1) x [y0, y1)` is reduced to its centre
//! `((x0 + x1) / 2, (y0 + y1) / 2)`; the sample is the texel `(floor(cx), floor(cy))` of the
//! extended texture (the boundary mode's [`EdgeKind::texel_index`](crate::EdgeKind::texel_index)), read straight from the
//! [`Texture`] — no table. The survey: "the pixel nearest the desired sample point is used".
//!
//! **Ties.** Texel `i` covers `[i, i + 1)`, so a centre exactly on the boundary between texels
//! `i - 1` and `i` (`cx = i`) samples texel `i` (the one to the right, below for `y`): the index
//! is `floor`, not round-half-down. In raw units (`F` fractional bits) the index is the
//! arithmetic shift `(x0 + x1) >> (F + 1)`, exact, no rounding beyond that floor.
//!
//! **Cost.** One read (all channels together), no multiplies, no additive operations: the centre
//! and the address are the address unit's work (module docs of [`crate::filters`]). The read is
//! counted also when [`crate::Border`] puts the centre outside the texture (the value is then the
//! zero border): the cost is constant, as in the survey's table.
//!
//! **Output.** Exact: channel value `v` is returned as `v << OUT_FRAC_BITS`.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::cost::Counter;
use crate::edge::EdgeMode;
use crate::error::Error;
use crate::filters::{per_channel, Sample, OUT_FRAC_BITS};
use crate::rect::{Coord, FracBits, Rect};
use crate::texel::Texel;
use crate::texture::Texture;

/// The nearest texel to the centre of `rect` under boundary mode `M`: 1 read, 0 multiplies,
/// 0 additive operations (Heckbert's "point sampling 1,0").
///
/// The centre is `((x0 + x1) / 2, (y0 + y1) / 2)`; the texel is `(floor(cx), floor(cy))`
/// (a centre on a texel boundary takes the texel to the right / below), mapped through
/// [`EdgeKind::texel_index`](crate::EdgeKind::texel_index); outside the texture under [`crate::Border`] the value is 0.
/// The result is exact: `values[c] = texel[c] << OUT_FRAC_BITS`.
///
/// A zero-area footprint (a point) is accepted. Errors: [`Error::FracBitsUnsupported`] for
/// `F > 24`, [`Error::InvertedBox`] for `x1 < x0` or `y1 < y0`. Any `i64` corners work, in
/// `i64` arithmetic: `floor((x0 + x1) / 2^(F + 1)) = floor(mid / 2^F)` with
/// `mid = floor((x0 + x1) / 2) = (x0 >> 1) + (x1 >> 1) + (x0 & x1 & 1)`, which cannot overflow
/// (the 65-bit sum `x0 + x1` is never formed).
pub fn point<T: Texel, const C: usize, X: Coord, M: EdgeMode, K: Counter>(
    texture: &Texture<'_, T, C>,
    rect: &Rect<X>,
    mode: M,
    k: &mut K,
) -> Result<Sample<C>, Error> {
    point_raw(texture, &rect.to_raw(), FracBits::of::<X>()?, mode, k)
}

/// [`point`] with raw corners (`value * 2^F`) and `F` as a value, checked once by
/// [`FracBits::new`]: one compiled sampler serves every `F`.
pub fn point_raw<T: Texel, const C: usize, M: EdgeMode, K: Counter>(
    texture: &Texture<'_, T, C>,
    rect: &Rect<i64>,
    frac_bits: FracBits,
    mode: M,
    k: &mut K,
) -> Result<Sample<C>, Error> {
    let f = frac_bits.get();
    let (x0, y0, x1, y1) = (rect.x0, rect.y0, rect.x1, rect.y1);
    if x1 < x0 || y1 < y0 {
        return Err(Error::InvertedBox);
    }
    let ix = centre_index(x0, x1, f);
    let iy = centre_index(y0, y1, f);
    k.reads(1, const { per_channel(T::BITS, C) });
    k.words(const { per_channel(T::BITS, C).div_ceil(32) });
    let mut values = [0u64; C];
    if let (Some(x), Some(y)) = (
        mode.kind().texel_index(ix, texture.width()),
        mode.kind().texel_index(iy, texture.height()),
    ) {
        // x < width and width * C fits (the texture's own check): no wrap.
        let at = x.wrapping_mul(C);
        if let Some(px) = texture.row(y).and_then(|r| r.get(at..at.wrapping_add(C))) {
            for (v, t) in values.iter_mut().zip(px) {
                *v = u64::from(t.to_u16()) << OUT_FRAC_BITS;
            }
        }
    }
    Ok(Sample { values })
}

/// `floor((lo + hi) / 2^(f + 1))`: the index of the texel holding the centre of `[lo, hi)`,
/// as `floor(floor((lo + hi) / 2) / 2^f)` (equal: nested floors of divisions by positive
/// integers), the inner floor exact in `i64`.
#[inline(always)]
fn centre_index(lo: i64, hi: i64, f: u32) -> i64 {
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "lo >> 1 and hi >> 1 lie in [-2^62, 2^62 - 1]: their sum in [-2^63, 2^63 - 2], \
                  plus 0 or 1, stays in i64"
    )]
    let mid = (lo >> 1) + (hi >> 1) + (lo & hi & 1);
    mid >> f.min(63)
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]
mod tests {
    extern crate std;
    use super::*;
    use crate::cost::{NoCount, Tally};
    use crate::edge::{Border, ClampToEdge, MirroredRepeat, Repeat};
    use fixed::types::{I24F8, I32F0, I32F32, I40F24, I64F0};
    use std::vec::Vec;

    fn r8(x0: f64, y0: f64, x1: f64, y1: f64) -> Rect<I24F8> {
        Rect::from_f64(x0, y0, x1, y1).unwrap()
    }

    #[test]
    fn cost_is_one_read_no_arithmetic() {
        let data: Vec<u8> = (0..12).collect();
        let t = Texture::<u8, 3>::new(&data, 2, 2).unwrap();
        let mut k = Tally::new();
        point(&t, &r8(0.0, 0.0, 1.0, 1.0), Border, &mut k).unwrap();
        assert_eq!((k.reads, k.muls, k.divs, k.adds), (1, 0, 0, 0));
        assert_eq!(k.bits_read, 24);
        // Outside under Border: still one read (constant cost), value zero.
        let s = point(&t, &r8(5.0, 5.0, 6.0, 6.0), Border, &mut k).unwrap();
        assert_eq!(s.values, [0; 3]);
        assert_eq!(k.reads, 2);
    }

    #[test]
    fn nearest_texel_and_ties() {
        let data: Vec<u8> = (0..12).collect(); // 4 x 3, value = x + 4y
        let t = Texture::<u8>::new(&data, 4, 3).unwrap();
        let v = |r: Rect<I24F8>| point(&t, &r, ClampToEdge, &mut NoCount).unwrap().values[0];
        assert_eq!(v(r8(1.0, 1.0, 2.0, 2.0)), 5 << 16);
        // Centre (1.0, 1.0) on a boundary: the texel to the right and below.
        assert_eq!(v(r8(0.5, 0.5, 1.5, 1.5)), 5 << 16);
        // Just left of it.
        assert_eq!(v(r8(0.5, 0.5, 1.49609375, 1.5)), 4 << 16);
        // A point footprint.
        assert_eq!(v(r8(3.75, 2.25, 3.75, 2.25)), 11 << 16);
        // Clamp far outside.
        assert_eq!(v(r8(-100.0, 50.0, -99.0, 51.0)), 8 << 16);
    }

    #[test]
    fn modes() {
        let data: Vec<u16> = (0..6).map(|v| v * 1000 + 7).collect(); // 3 x 2
        let t = Texture::<u16>::new(&data, 3, 2).unwrap();
        let r = r8(-1.5, 2.25, -1.0, 2.75); // centre (-1.25, 2.5): texel (-2, 2)
        let at = |x: usize, y: usize| ((data[y * 3 + x]) as u64) << 16;
        assert_eq!(point(&t, &r, Border, &mut NoCount).unwrap().values[0], 0);
        assert_eq!(
            point(&t, &r, ClampToEdge, &mut NoCount).unwrap().values[0],
            at(0, 1)
        );
        assert_eq!(
            point(&t, &r, Repeat, &mut NoCount).unwrap().values[0],
            at(1, 0)
        );
        // Mirror: x -2 -> 1, y 2 -> period 4, r = 2 >= 2 -> 2*2-1-2 = 1.
        assert_eq!(
            point(&t, &r, MirroredRepeat, &mut NoCount).unwrap().values[0],
            at(1, 1)
        );
    }

    #[test]
    fn centre_index_matches_the_i128_formulation() {
        let old = |lo: i64, hi: i64, f: u32| ((lo as i128 + hi as i128) >> (f + 1)) as i64;
        // Under Miri (about 10^4 times slower) every 37th start, every 7th width, and 40 random values.
        let (lo_step, width_step, rounds) = if cfg!(miri) {
            (37, 7, 40)
        } else {
            (1, 1, 2000)
        };
        for lo in (-300i64..300).step_by(lo_step) {
            for hi in (lo..lo + 300).step_by(width_step) {
                for f in [0u32, 1, 2, 8] {
                    assert_eq!(centre_index(lo, hi, f), old(lo, hi, f), "{lo} {hi} {f}");
                }
            }
        }
        let edge = [i64::MIN, i64::MIN + 1, -1, 0, 1, i64::MAX - 1, i64::MAX];
        let mut s = 3u64;
        let mut vals: Vec<i64> = edge.to_vec();
        for _ in 0..rounds {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            vals.push(s as i64 >> (s % 64));
        }
        for &a in &vals {
            for &b in &edge {
                let (lo, hi) = (a.min(b), a.max(b));
                for f in 0..=24u32 {
                    assert_eq!(centre_index(lo, hi, f), old(lo, hi, f), "{lo} {hi} {f}");
                }
            }
        }
    }

    #[test]
    fn refusals_and_extremes() {
        let data = [1u8, 2, 3, 4];
        let t = Texture::<u8>::new(&data, 2, 2).unwrap();
        assert_eq!(
            point(&t, &r8(1.0, 0.0, 0.5, 1.0), Border, &mut NoCount),
            Err(Error::InvertedBox)
        );
        let r = Rect::new(I32F32::ZERO, I32F32::ZERO, I32F32::ONE, I32F32::ONE);
        assert_eq!(
            point(&t, &r, Border, &mut NoCount),
            Err(Error::FracBitsUnsupported {
                frac_bits: 32,
                max: 24
            })
        );
        // The widest corner type: centres at the extremes stay in range.
        let lo = Rect::new(I64F0::MIN, I64F0::MIN, I64F0::MIN, I64F0::MIN);
        let hi = Rect::new(I64F0::MAX, I64F0::MAX, I64F0::MAX, I64F0::MAX);
        let all = Rect::new(I64F0::MIN, I64F0::MIN, I64F0::MAX, I64F0::MAX);
        for r in [lo, hi, all] {
            for s in [
                point(&t, &r, Border, &mut NoCount),
                point(&t, &r, ClampToEdge, &mut NoCount),
                point(&t, &r, Repeat, &mut NoCount),
                point(&t, &r, MirroredRepeat, &mut NoCount),
            ] {
                assert!(s.is_ok());
            }
        }
        // (MIN + MAX) / 2 = -0.5 -> texel -1; clamp gives texel 0.
        assert_eq!(
            point(&t, &all, ClampToEdge, &mut NoCount).unwrap().values[0],
            1 << 16
        );
        let r = Rect::new(
            I32F0::from_num(1),
            I32F0::ZERO,
            I32F0::from_num(2),
            I32F0::ONE,
        );
        assert_eq!(
            point(&t, &r, Border, &mut NoCount).unwrap().values[0],
            2 << 16
        );
        let r = Rect::new(I40F24::ZERO, I40F24::ONE, I40F24::ONE, I40F24::from_num(2));
        assert_eq!(
            point(&t, &r, Border, &mut NoCount).unwrap().values[0],
            3 << 16
        );
    }
}
