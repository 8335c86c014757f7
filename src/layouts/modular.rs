//! Modular (wrapping) entries: the flat table stored modulo `2^k`, packed at `k` bits.
//!
//! Box sums are differences of table values, and differences are exact modulo `2^k`: if the true
//! box sum is below `2^k`, the residue *is* the sum. So `k` depends only on the largest box a
//! scene asks for, not on the texture size: `k = bits_of(m * A)` for boxes of at most `A`
//! texels (`m = 2^b - 1`), e.g. 16 bits for 8-bit texels and boxes up to 16 x 16.
//!
//! The lookups know `k` ([`Layout::modulus`]) and refuse, with
//! `TooWide { what: ModularBox, .. }`, any box whose sum could reach `2^k`: the texel cells the
//! box overlaps times `m`, plus `2F` bits for [`crate::Paper`] and the edge-mode weighted path,
//! whose corner values are only known modulo `2^k` (the [`crate::Stable`] form reduces its
//! box-bounded differences first and needs no headroom).

use super::packed::{read_bits, write_bits, WORD_BITS};
use super::Layout;
use crate::cost::Counter;
use crate::error::{Error, Quantity};
use crate::texel::{Entry, Texel};
use crate::texture::{check_dimensions, Texture};
use crate::width::{self, bits_of};

/// The flat table modulo `2^k`, `k`-bit fields packed in 32-bit words.
#[derive(Debug, Clone, Copy)]
pub struct Modular<'a, E: Entry, const C: usize = 1> {
    words: &'a [u32],
    width: usize,
    height: usize,
    texel_bits: u32,
    k: u32,
    _e: core::marker::PhantomData<E>,
}

/// `k` for boxes of at most `max_area` texels: `bits_of((2^b - 1) * max_area)`.
pub const fn modulus_bits_for(texel_bits: u32, max_area: u64) -> u32 {
    bits_of(width::max_texel(texel_bits) * max_area as u128)
}

fn check_k<E: Entry>(texel_bits: u32, k: u32) -> Result<(), Error> {
    width::check_texel_bits(texel_bits)?;
    if k < texel_bits || k > E::BITS || k == 0 {
        Err(Error::InvalidModulus { bits: k })
    } else {
        Ok(())
    }
}

impl<'a, E: Entry, const C: usize> Modular<'a, E, C> {
    /// `k` for boxes of at most `max_area` texels (see [`modulus_bits_for`]).
    pub const fn bits_for_max_area(texel_bits: u32, max_area: u64) -> u32 {
        modulus_bits_for(texel_bits, max_area)
    }

    /// Words a `w x h` table at `k` bits needs: `ceil(w h C k / 32)`.
    pub fn words_needed(width: usize, height: usize, k: u32) -> usize {
        super::packed::words_for(width * height * C, k)
    }

    /// Builds the table of `texture` modulo `2^k` into `words`, using `row` (`w * C` entries) as
    /// the one row of working state.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        k: u32,
        words: &'a mut [u32],
        row: &mut [E],
    ) -> Result<Self, Error> {
        let mut b = ModularBuilder::new(texture.width(), texture.height(), T::BITS, k, words, row)?;
        for y in 0..texture.height() {
            b.push_row(texture.row(y).ok_or(Error::EmptyTexture)?)?;
        }
        b.finish()
    }

    /// Wraps words written elsewhere. Not validated: wrong content gives wrong sums, never a
    /// panic.
    pub fn from_words(
        words: &'a [u32],
        width: usize,
        height: usize,
        texel_bits: u32,
        k: u32,
    ) -> Result<Self, Error> {
        check_k::<E>(texel_bits, k)?;
        check_dimensions(width, height, C)?;
        let need = Self::words_needed(width, height, k);
        if words.len() < need {
            return Err(Error::StorageTooSmall {
                needed: need,
                got: words.len(),
            });
        }
        Ok(Modular {
            words,
            width,
            height,
            texel_bits,
            k,
            _e: core::marker::PhantomData,
        })
    }

    /// The largest box area (in texel cells) whose sum is always exact: `floor((2^k - 1) / m)`.
    pub fn max_exact_area(&self) -> u128 {
        ((1u128 << self.k) - 1) / width::max_texel(self.texel_bits)
    }

    /// The storage words.
    pub fn words(&self) -> &'a [u32] {
        self.words
    }
}

impl<E: Entry, const C: usize> Layout<C> for Modular<'_, E, C> {
    type Value = E;
    fn width(&self) -> usize {
        self.width
    }
    fn height(&self) -> usize {
        self.height
    }
    fn texel_bits(&self) -> u32 {
        self.texel_bits
    }
    fn value_bits(&self) -> u32 {
        self.k
    }
    fn modulus(&self) -> Option<u32> {
        Some(self.k)
    }
    fn storage_bits(&self) -> u64 {
        (self.width * self.height * C) as u64 * self.k as u64
    }
    #[inline]
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        let mut out = [E::ZERO; C];
        if x == 0 || y == 0 {
            return out;
        }
        let entry = ((y - 1) * self.width + (x - 1)) as u64;
        let offset = entry * C as u64 * self.k as u64;
        let span = (offset % WORD_BITS as u64) as u32 + self.k * C as u32;
        k.reads(1, self.k * C as u32);
        k.words(span.div_ceil(WORD_BITS));
        for (c, o) in out.iter_mut().enumerate() {
            *o = E::from_u64_truncating(
                read_bits(self.words, offset + (c as u32 * self.k) as u64, self.k).0,
            );
        }
        out
    }
}

/// Builds a [`Modular`] layout one row at a time, holding one table row of residues.
#[derive(Debug)]
pub struct ModularBuilder<'a, 's, E: Entry, const C: usize = 1> {
    words: &'a mut [u32],
    row: &'s mut [E],
    width: usize,
    height: usize,
    texel_bits: u32,
    k: u32,
    rows_done: usize,
}

impl<'a, 's, E: Entry, const C: usize> ModularBuilder<'a, 's, E, C> {
    /// A builder for a `w x h` texture of `texel_bits`-bit texels at `k` bits per entry.
    pub fn new(
        width: usize,
        height: usize,
        texel_bits: u32,
        k: u32,
        words: &'a mut [u32],
        row: &'s mut [E],
    ) -> Result<Self, Error> {
        check_k::<E>(texel_bits, k)?;
        check_dimensions(width, height, C)?;
        let need = Modular::<E, C>::words_needed(width, height, k);
        if words.len() < need {
            return Err(Error::StorageTooSmall {
                needed: need,
                got: words.len(),
            });
        }
        if row.len() < width * C {
            return Err(Error::StorageTooSmall {
                needed: width * C,
                got: row.len(),
            });
        }
        let row = &mut row[..width * C];
        row.fill(E::ZERO);
        Ok(ModularBuilder {
            words,
            row,
            width,
            height,
            texel_bits,
            k,
            rows_done: 0,
        })
    }

    /// Consumes the next texture row. The additions wrap modulo `2^k` on purpose.
    pub fn push_row<T: Texel>(&mut self, texels: &[T]) -> Result<(), Error> {
        if self.rows_done >= self.height {
            return Err(Error::TooManyRows);
        }
        if texels.len() != self.width * C {
            return Err(Error::RowLength {
                expected: self.width * C,
                got: texels.len(),
            });
        }
        let max = width::max_texel(self.texel_bits);
        let mut run = [E::ZERO; C];
        let base = (self.rows_done * self.width * C) as u64;
        for (x, (o, t)) in self
            .row
            .chunks_exact_mut(C)
            .zip(texels.chunks_exact(C))
            .enumerate()
        {
            for c in 0..C {
                let v = t[c].to_u16();
                if v as u128 > max {
                    return Err(Error::TooWide {
                        what: Quantity::Entry,
                        bits_needed: bits_of(v as u128),
                        bits_available: self.texel_bits,
                    });
                }
                run[c] = run[c].wrapping_add(E::from(v)).low_bits(self.k);
                o[c] = o[c].wrapping_add(run[c]).low_bits(self.k);
                let offset = (base + (x * C + c) as u64) * self.k as u64;
                write_bits(self.words, offset, self.k, o[c].to_u64());
            }
        }
        self.rows_done += 1;
        Ok(())
    }

    /// Checks that every row arrived and returns the layout.
    pub fn finish(self) -> Result<Modular<'a, E, C>, Error> {
        if self.rows_done != self.height {
            return Err(Error::MissingRows {
                got: self.rows_done,
                expected: self.height,
            });
        }
        Ok(Modular {
            words: self.words,
            width: self.width,
            height: self.height,
            texel_bits: self.texel_bits,
            k: self.k,
            _e: core::marker::PhantomData,
        })
    }
}
