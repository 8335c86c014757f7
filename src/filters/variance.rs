//! Variance over a box from summed-area tables of the texture and of its squares (Heckbert's
//! survey, "summed area table": "A more accurate method for computing rectangle variance would be
//! to pre-compute summed area tables of the texture values and their squares. Using these two
//! tables variance can be computed as `σ^2 = Σ x_i^2 / n - (Σ x_i / n)^2`"; Glassner 1986 uses
//! rectangle variance to drive adaptive refinement).
//!
//! [`VarianceTables`] holds the core's [`Sat`] of the values and a [`SquaresTable`] of the
//! squares, both in caller storage and built with Crow's two additions per entry. The squares
//! table implements [`Layout`], so every box lookup of the core ([`BoxLookup::box_sum_int`],
//! [`BoxLookup::box_sum`] in both forms, every boundary mode) runs on it unchanged.
//!
//! ## Exact arithmetic
//!
//! With `n` the box area, `S` the sum and `Q` the sum of squares (for fixed-point corners all
//! three scaled by `2^2F`, as [`crate::BoxSum`] returns them; `n` is the unclipped box's, so
//! under [`crate::Border`] the zeros outside count), the variance is
//!
//! `σ^2 = Q/n - (S/n)^2 = (n Q - S^2) / n^2`,
//!
//! computed in `u128` integers: `n Q - S^2 >= 0` exactly (Cauchy–Schwarz for the integrals of a
//! piecewise-constant function), one division at the end, rounded to nearest with ties up, with
//! [`OUT_FRAC_BITS`] fraction bits. The result is the variance of the extended piecewise-constant
//! texture over the box, exact before that rounding (so within `2^-17`). The numerator `n Q`
//! must fit `u128` and `n^2` must be below `2^127`, else [`Error::TooWide`]
//! (`MeanNumerator`): for 8-bit texels and `F = 8` that allows boxes up to about `2^24` texels
//! per side.
//!
//! ## Costs
//!
//! Integer corners, interior box, one channel: 8 reads (4 per table), 4 multiplies (the area
//! `w h`, `n^2`, `n Q`, `S^2`) and 1 divide, 7 additive operations (3 per box sum and
//! `n Q - S^2`). Fixed-point corners: 32 reads and each box sum's 12 multiplies and 27 (Paper) or
//! 31 (Stable) additive operations, plus the same 4 multiplies, 1 divide and 1 subtraction. With
//! `C` channels the area and `n^2` are shared: `2 + 2C` multiplies, `C` divides.
//!
//! ## Widths
//!
//! Values: [`crate::width::entry_bits_worst_case`] (`Sat::build` checks it). Squares:
//! [`squares_entry_bits`] `= bits_of(m^2 w h)`, exact by the same argument (the all-`m` texture
//! reaches it). Both tables use the entry type `E`; 8-bit 256 x 256 needs 32 bits for the
//! squares (24 for the values); `u32` holds squares up to 257 x 257.

use crate::cost::Counter;
use crate::edge::EdgeMode;
use crate::error::{Error, Quantity};
use crate::filters::{Sample, OUT_FRAC_BITS};
use crate::layouts::Layout;
use crate::lookup::{BoxLookup, BoxSum, Form};
use crate::rect::{Coord, Rect};
use crate::table::Sat;
use crate::texel::{Entry, Texel};
use crate::texture::Texture;
use crate::wide::Wide;
use crate::width::{bits_of, check_texel_bits, max_texel};

/// Exact bits per entry of the squares table: `bits_of((2^b - 1)^2 * w * h)` (saturating at 128).
pub const fn squares_entry_bits(texel_bits: u32, width: usize, height: usize) -> u32 {
    let m = max_texel(texel_bits);
    bits_of(
        m.saturating_mul(m)
            .saturating_mul(width as u128)
            .saturating_mul(height as u128),
    )
}

/// A summed-area table of the squared texels (inclusive storage, like [`Sat`]).
#[derive(Debug, Clone, Copy)]
pub struct SquaresTable<'a, E: Entry, const C: usize = 1> {
    table: &'a [E],
    width: usize,
    height: usize,
    texel_bits: u32,
    total_bits: u32,
}

impl<'a, E: Entry, const C: usize> SquaresTable<'a, E, C> {
    /// Builds the table of `t^2` into `storage` after proving [`squares_entry_bits`] fits `E`;
    /// nothing is written on refusal. Two additions per entry (running row sum, plus the entry
    /// above), as Crow §3.0; squaring is one multiply per texel.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
    ) -> Result<Self, Error> {
        let (w, h) = Self::check::<T>(texture, storage.len())?;
        let row_len = w * C;
        let needed = row_len * h;
        let table = &mut storage[..needed];
        for y in 0..h {
            let texels = texture.row(y).ok_or(Error::EmptyTexture)?;
            let (done, rest) = table.split_at_mut(y * row_len);
            let above = if y == 0 {
                None
            } else {
                Some(&done[(y - 1) * row_len..])
            };
            let out = &mut rest[..row_len];
            let mut run = [E::ZERO; C];
            for (xi, px) in texels.chunks_exact(C).enumerate() {
                for c in 0..C {
                    let t = px[c].to_u16() as u64;
                    // t^2 <= m^2 <= the worst-case total, which fits E.
                    run[c] = run[c] + E::from_u64_truncating(t * t);
                    let i = xi * C + c;
                    out[i] = match above {
                        Some(a) => run[c] + a[i],
                        None => run[c],
                    };
                }
            }
        }
        let table: &'a [E] = &storage[..needed];
        let last = &table[needed - C..];
        let total_bits = last.iter().map(|e| bits_of(e.to_u128())).max().unwrap_or(0);
        Ok(SquaresTable {
            table,
            width: w,
            height: h,
            texel_bits: T::BITS,
            total_bits,
        })
    }

    /// The refusals of [`SquaresTable::build`], before anything is written.
    fn check<T: Texel>(texture: &Texture<'_, T, C>, got: usize) -> Result<(usize, usize), Error> {
        let (w, h) = (texture.width(), texture.height());
        check_texel_bits(T::BITS)?;
        let bits = squares_entry_bits(T::BITS, w, h);
        if bits > E::BITS {
            return Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: bits,
                bits_available: E::BITS,
            });
        }
        let needed = storage_needed::<C>(w, h)?;
        if got < needed {
            return Err(Error::StorageTooSmall { needed, got });
        }
        Ok((w, h))
    }

    /// Bits per texel of the source texture (the squares have twice as many).
    pub fn source_texel_bits(&self) -> u32 {
        self.texel_bits
    }

    /// The stored entries, row-major, channels interleaved.
    pub fn entries(&self) -> &'a [E] {
        self.table
    }

    /// Table bytes as stored.
    pub fn table_bytes(&self) -> usize {
        core::mem::size_of_val(self.table)
    }
}

impl<E: Entry, const C: usize> Layout<C> for SquaresTable<'_, E, C> {
    type Value = E;
    fn width(&self) -> usize {
        self.width
    }
    fn height(&self) -> usize {
        self.height
    }
    /// The squares' width: twice the source texel bits (what the shortcut's bound uses).
    fn texel_bits(&self) -> u32 {
        2 * self.texel_bits
    }
    fn value_bits(&self) -> u32 {
        self.total_bits
    }
    fn storage_bits(&self) -> u64 {
        self.table_bytes() as u64 * 8
    }
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        let mut out = [E::ZERO; C];
        if x != 0 && y != 0 && x <= self.width && y <= self.height {
            k.reads(1, E::BITS * C as u32);
            k.words((E::BITS * C as u32).div_ceil(32));
            let base = ((y - 1) * self.width + (x - 1)) * C;
            out.copy_from_slice(&self.table[base..base + C]);
        }
        out
    }
}

/// Entries each table of a `width x height` texture needs: `w h C`.
pub fn storage_needed<const C: usize>(width: usize, height: usize) -> Result<usize, Error> {
    width
        .checked_mul(height)
        .and_then(|v| v.checked_mul(C))
        .ok_or(Error::TextureTooLarge {
            dimension: width.max(height),
        })
}

/// The SATs of the values and of the squares of one texture.
#[derive(Debug, Clone, Copy)]
pub struct VarianceTables<'a, E: Entry, const C: usize = 1> {
    values: Sat<'a, E, C>,
    squares: SquaresTable<'a, E, C>,
}

impl<'a, E: Entry, const C: usize> VarianceTables<'a, E, C> {
    /// Entries each of the two storages needs: `w h C`.
    pub fn storage_needed(width: usize, height: usize) -> Result<usize, Error> {
        storage_needed::<C>(width, height)
    }

    /// Builds both tables. The squares' width and storage are checked first, then
    /// [`Sat::build`] checks and builds the values, then the squares are built: a refusal
    /// writes nothing.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        values: &'a mut [E],
        squares: &'a mut [E],
    ) -> Result<Self, Error> {
        SquaresTable::<E, C>::check::<T>(texture, squares.len())?;
        let values = Sat::build(texture, values)?;
        let squares = SquaresTable::build(texture, squares)?;
        Ok(VarianceTables { values, squares })
    }

    /// The values' table.
    pub fn values(&self) -> &Sat<'a, E, C> {
        &self.values
    }

    /// The squares' table.
    pub fn squares(&self) -> &SquaresTable<'a, E, C> {
        &self.squares
    }

    /// Bytes of both tables.
    pub fn table_bytes(&self) -> usize {
        self.values.table_bytes() + self.squares.table_bytes()
    }

    /// The variance over the box `[x0, x1) x [y0, y1)` with integer corners under mode `M`:
    /// `round((n Q - S^2) 2^16 / n^2)` per channel, ties up (exact before the rounding).
    /// Interior box: 8 reads, 4 multiplies, 1 divide, 7 additive operations (one channel).
    /// Zero-area boxes are [`Error::ZeroArea`], inverted ones [`Error::InvertedBox`].
    pub fn variance_int<M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<i32>,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let s = self.values.box_sum_int(r, mode, k)?;
        let q = BoxLookup::box_sum_int(&self.squares, r, mode, k)?;
        finish(&s, &q, k)
    }

    /// The variance over the box with fixed-point corners (`F <= 24`), box sums in form `Fm`,
    /// under mode `M`: the exact variance of the piecewise-constant texture over the box, rounded
    /// as [`VarianceTables::variance_int`]. Interior box: 32 reads, the two box sums' operations,
    /// plus 4 multiplies, 1 divide and 1 subtraction per channel.
    pub fn variance<X: Coord, Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        r: &Rect<X>,
        form: Fm,
        mode: M,
        k: &mut K,
    ) -> Result<Sample<C>, Error> {
        let s = self.values.box_sum(r, form, mode, k)?;
        let q = BoxLookup::box_sum(&self.squares, r, form, mode, k)?;
        finish(&s, &q, k)
    }
}

/// `(n Q - S^2) / n^2` per channel, rounded (module docs), with its operations counted.
fn finish<W1: Wide, W2: Wide, const C: usize, K: Counter>(
    s: &BoxSum<W1, C>,
    q: &BoxSum<W2, C>,
    k: &mut K,
) -> Result<Sample<C>, Error> {
    let (wr, hr) = s.sides_raw();
    let (wr, hr) = (u128::from(wr), u128::from(hr));
    let wide = |needed: u32, available: u32| Error::TooWide {
        what: Quantity::MeanNumerator,
        bits_needed: needed,
        bits_available: available,
    };
    k.muls(2);
    let n = wr
        .checked_mul(hr)
        .ok_or(wide(bits_of(wr) + bits_of(hr), 128))?;
    if n == 0 {
        return Err(Error::ZeroArea);
    }
    let nn = n
        .checked_mul(n)
        .filter(|&v| v < 1u128 << 127)
        .ok_or(wide(2 * bits_of(n), 127))?;
    let mut out = [0u64; C];
    for (c, o) in out.iter_mut().enumerate() {
        let (sc, qc): (u128, u128) = (s.scaled_sum(c).into(), q.scaled_sum(c).into());
        k.muls(2);
        k.adds(1);
        k.divs(1);
        let nq = n
            .checked_mul(qc)
            .ok_or(wide(bits_of(n) + bits_of(qc), 128))?;
        let ss = sc.checked_mul(sc).ok_or(wide(2 * bits_of(sc), 128))?;
        // n Q >= S^2 for any tables built from a texture (Cauchy–Schwarz); a table that
        // violates it was not.
        let num = nq.checked_sub(ss).ok_or(Error::InvalidTable {
            x: 0,
            y: 0,
            channel: c,
        })?;
        *o = div_round_shift(num, OUT_FRAC_BITS, nn)?;
    }
    Ok(Sample { values: out })
}

/// `round(num * 2^shift / den)`, ties up, for `0 < den < 2^127`, by restoring division.
fn div_round_shift(num: u128, shift: u32, den: u128) -> Result<u64, Error> {
    let wide = || Error::TooWide {
        what: Quantity::MeanNumerator,
        bits_needed: 65,
        bits_available: 64,
    };
    let mut q = num / den;
    let mut r = num % den;
    for _ in 0..shift {
        q = q.checked_mul(2).ok_or_else(wide)?;
        r <<= 1;
        if r >= den {
            r -= den;
            q += 1;
        }
    }
    if r >= den - r {
        q += 1;
    }
    u64::try_from(q).map_err(|_| wide())
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::{Border, ClampToEdge, MirroredRepeat, NoCount, Paper, Repeat, Stable, Tally};
    use fixed::types::I24F8;
    use std::vec;
    use std::vec::Vec;

    fn tex(w: usize, h: usize, seed: u64) -> Vec<u8> {
        let mut s = seed;
        (0..w * h)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 33) as u8
            })
            .collect()
    }

    /// Direct: n, S, Q over the extended texture, then the same rounding.
    fn direct<M: EdgeMode>(mode: M, t: &[u8], w: usize, h: usize, r: &Rect<i32>) -> u64 {
        let (mut s, mut q, mut n) = (0u128, 0u128, 0u128);
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                n += 1;
                if let (Some(i), Some(j)) = (
                    mode.kind().texel_index(x as i64, w),
                    mode.kind().texel_index(y as i64, h),
                ) {
                    let v = t[j * w + i] as u128;
                    s += v;
                    q += v * v;
                }
            }
        }
        div_round_shift(n * q - s * s, 16, n * n).unwrap()
    }

    fn every_box<M: EdgeMode>(mode: M) {
        for (w, h) in [(1, 1), (1, 5), (5, 1), (4, 3)] {
            let t = tex(w, h, (w * 7 + h) as u64);
            let texture = Texture::<u8>::new(&t, w, h).unwrap();
            let mut vs = vec![0u32; w * h];
            let mut qs = vec![0u32; w * h];
            let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
            for x0 in -3..=w as i32 + 2 {
                for x1 in x0 + 1..=w as i32 + 3 {
                    for y0 in -2..=h as i32 + 1 {
                        for y1 in y0 + 1..=h as i32 + 2 {
                            let r = Rect::new(x0, y0, x1, y1);
                            let got = vt.variance_int(&r, mode, &mut NoCount).unwrap();
                            assert_eq!(
                                got.values[0],
                                direct(mode, &t, w, h, &r),
                                "{} {r:?}",
                                mode.kind().name()
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn integer_boxes_every_mode() {
        every_box(Border);
        every_box(ClampToEdge);
        every_box(Repeat);
        every_box(MirroredRepeat);
    }

    #[test]
    fn fractional_boxes_are_exact() {
        // Half-texel box over two texels a, b: mean (a+b)/2, variance ((a-b)/2)^2.
        let t = [10u8, 30, 0, 0];
        let texture = Texture::<u8>::new(&t, 2, 2).unwrap();
        let mut vs = [0u32; 4];
        let mut qs = [0u32; 4];
        let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
        let r = Rect::new(
            I24F8::from_num(0.5),
            I24F8::ZERO,
            I24F8::from_num(1.5),
            I24F8::ONE,
        );
        for v in [
            vt.variance(&r, Paper, Border, &mut NoCount).unwrap(),
            vt.variance(&r, Stable, Border, &mut NoCount).unwrap(),
        ] {
            assert_eq!(v.values[0], 100 << 16);
        }
        // A quarter of texel 0 and three quarters of texel 1: var = 1/4 * 3/4 * 20^2 = 75.
        let r = Rect::new(
            I24F8::from_num(0.75),
            I24F8::ZERO,
            I24F8::from_num(1.75),
            I24F8::ONE,
        );
        let v = vt.variance(&r, Stable, Border, &mut NoCount).unwrap();
        assert_eq!(v.values[0], 75 << 16);
    }

    #[test]
    fn costs() {
        let t = tex(8, 8, 1);
        let texture = Texture::<u8>::new(&t, 8, 8).unwrap();
        let mut vs = [0u32; 64];
        let mut qs = [0u32; 64];
        let vt = VarianceTables::build(&texture, &mut vs, &mut qs).unwrap();
        let mut k = Tally::new();
        vt.variance_int(&Rect::new(2, 2, 6, 7), Border, &mut k)
            .unwrap();
        assert_eq!((k.reads, k.muls, k.divs, k.adds), (8, 4, 1, 7));
        let mut k = Tally::new();
        let r = Rect::new(
            I24F8::from_num(1.3),
            I24F8::from_num(2.2),
            I24F8::from_num(6.1),
            I24F8::from_num(5.9),
        );
        vt.variance(&r, Paper, Border, &mut k).unwrap();
        assert_eq!((k.reads, k.muls, k.divs, k.adds), (32, 28, 1, 55));
    }

    #[test]
    fn widths_and_refusals() {
        assert_eq!(squares_entry_bits(8, 256, 256), 32);
        // Largest square in u32 at 8 bits: 257 x 257 (255^2 * 257^2 < 2^32); 258 is refused.
        assert_eq!(squares_entry_bits(8, 257, 257), 32);
        assert_eq!(squares_entry_bits(8, 258, 258), 33);
        assert_eq!(squares_entry_bits(16, 1, 1), 32);
        let t = vec![0u8; 258 * 258];
        let texture = Texture::<u8>::new(&t, 258, 258).unwrap();
        let mut vs = vec![7u32; 258 * 258];
        let mut qs = vec![7u32; 258 * 258];
        assert_eq!(
            VarianceTables::build(&texture, &mut vs, &mut qs).err(),
            Some(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: 33,
                bits_available: 32
            })
        );
        assert!(vs.iter().chain(qs.iter()).all(|&v| v == 7));
        let mut short = vec![0u64; 10];
        let mut vs64 = vec![0u64; 258 * 258];
        let mut qs64 = vec![0u64; 258 * 258];
        assert!(VarianceTables::build(&texture, &mut vs64, &mut qs64).is_ok());
        let mut vs2 = vec![0u64; 258 * 258];
        assert!(matches!(
            VarianceTables::build(&texture, &mut vs2, &mut short),
            Err(Error::StorageTooSmall { .. })
        ));
        // 16-bit texels: squares need u64.
        let t16 = vec![65535u16; 9];
        let texture = Texture::<u16>::new(&t16, 3, 3).unwrap();
        let mut a = [0u64; 9];
        let mut b = [0u64; 9];
        let vt = VarianceTables::build(&texture, &mut a, &mut b).unwrap();
        let v = vt
            .variance_int(&Rect::new(-1, 0, 3, 3), Border, &mut NoCount)
            .unwrap();
        // 3/4 of the box is 65535, 1/4 zero: variance = 65535^2 * 3/16.
        let want = (65535f64 * 65535.0 * 3.0 / 16.0 * 65536.0).round() as u64;
        assert_eq!(v.values[0], want);
        assert_eq!(
            vt.variance_int(&Rect::new(1, 1, 1, 3), Border, &mut NoCount),
            Err(Error::ZeroArea)
        );
    }

    #[test]
    fn channels() {
        let t = tex(5, 4, 9);
        let texture = Texture::<u8, 2>::new(&t[..20], 5, 2).unwrap();
        let mut a = [0u32; 20];
        let mut b = [0u32; 20];
        let vt = VarianceTables::build(&texture, &mut a, &mut b).unwrap();
        let mut k = Tally::new();
        let v = vt
            .variance_int(&Rect::new(1, 0, 4, 2), Repeat, &mut k)
            .unwrap();
        for c in 0..2 {
            let ch: Vec<u8> = t[..20].iter().skip(c).step_by(2).copied().collect();
            assert_eq!(
                v.values[c],
                direct(Repeat, &ch, 5, 2, &Rect::new(1, 0, 4, 2))
            );
        }
        assert_eq!((k.muls, k.divs), (6, 2));
    }
}
