//! Modular (wrapping) entries: the flat table stored modulo `2^k`, packed at `k` bits.
//!
//! Box sums are differences of table values, and differences are exact modulo `2^k`: if the true
//! box sum is below `2^k`, the residue *is* the sum. So `k` depends only on the largest box a
//! scene asks for, not on the texture size: `k = bits_of(m * A)` for boxes of at most `A`
//! texels (`m = 2^b - 1`), e.g. 16 bits for 8-bit texels and boxes up to 16 x 16.
//!
//! The lookups know `k` ([`Layout::modulus`]) and refuse, with
//! `TooWide { what: ModularBox, .. }`, any box whose sum could reach `2^k`: the texel cells the
//! box overlaps times `m`, plus `2F` bits for [`crate::Paper`], whose interpolated corner values
//! are only known modulo `2^k` (the [`crate::Stable`] form reduces its box-bounded differences
//! first and needs no headroom). A box that crosses the texture's edge is split into in-range
//! pieces, each at most the box's sum: no headroom beyond the form's own.
//!
//! Sizes are computed in `u64` with checks ([`Modular::words_needed`] is a `const fn`); a corner
//! is one read of `k C` bits (two 32-bit words for `k C <= 33`); corrupted words give wrong
//! sums, never a panic.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use super::packed::{
    bits_of_mul, check_dimensions, mask, pack_fields, read_field, read_masked, read_masked32,
    word_shift, words_of_bits, BitWriter, USIZE_MAX64, WORD_BITS,
};
use super::Layout;
use crate::cost::{Counter, Region};
use crate::error::Error;
use crate::texel::{Entry, Texel};
use crate::texture::Texture;

/// The flat table modulo `2^k`, `k`-bit fields packed in 32-bit words.
#[derive(Debug, Clone, Copy)]
pub struct Modular<'a, E: Entry, const C: usize = 1> {
    words: &'a [u32],
    width: usize,
    height: usize,
    texel_bits: u32,
    k: u32,
    sizes: Sizes,
    _e: core::marker::PhantomData<E>,
}

/// `k` for boxes of at most `max_area` texels: `bits_of((2^b - 1) * max_area)`.
pub const fn modulus_bits_for(texel_bits: u32, max_area: u64) -> u32 {
    if texel_bits <= 64 {
        bits_of_mul(mask(texel_bits), max_area)
    } else if max_area == 0 {
        0
    } else {
        // (2^b - 1) a = a 2^b - a with a < 2^b: bits_of(a) + b, one less if a is a power of two.
        let a_bits = crate::width::bits_of_u64(max_area);
        #[allow(
            clippy::as_conversions,
            reason = "bool -> u32 is 0 or 1; u32::from is not const"
        )]
        let pow2 = max_area.is_power_of_two() as u32;
        texel_bits.saturating_add(a_bits).saturating_sub(pow2)
    }
}

/// Refuses `k` outside `texel_bits..=E::BITS` (and texel widths outside `1..=16`).
const fn check_k<E: Entry>(texel_bits: u32, k: u32) -> Result<(), Error> {
    if let Err(e) = crate::width::check_texel_bits(texel_bits) {
        return Err(e);
    }
    if k < texel_bits || k > E::BITS || k == 0 {
        Err(Error::InvalidModulus { bits: k })
    } else {
        Ok(())
    }
}

/// The sizes of a modular layout in bits, computed once and checked: every field offset of a
/// valid corner is below `total_bits`, so the lookups' offset arithmetic cannot wrap.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Sizes {
    /// Bits of one entry, all channels: `k C`.
    pub(super) entry_bits: u64,
    /// Bits of one table row: `w k C`.
    pub(super) row_bits: u64,
    /// Bits of the table: `w h k C`.
    pub(super) total_bits: u64,
    /// `ceil(total_bits / 32)`.
    pub(super) words: usize,
    /// The low `entry_bits` bits set (all ones from 64 on).
    pub(super) entry_mask: u64,
}

/// [`Modular::words_needed`] for `k <= 64` with the channels as a value.
pub(super) const fn words_for_channels(
    width: usize,
    height: usize,
    k: u32,
    channels: usize,
) -> Result<usize, Error> {
    match Sizes::new(width, height, k, channels, USIZE_MAX64) {
        Ok(s) => Ok(s.words),
        Err(e) => Err(e),
    }
}

impl Sizes {
    /// The sizes of a `w x h` table of `channels` channels at `k <= 64` bits, or
    /// `TextureTooLarge` if the bits overflow `u64` or the words exceed `max_words` (the
    /// target's `usize::MAX`; tests pass `u32::MAX` to check a 32-bit target on any host).
    pub(super) const fn new(
        width: usize,
        height: usize,
        k: u32,
        channels: usize,
        max_words: u64,
    ) -> Result<Sizes, Error> {
        if let Err(e) = check_dimensions(width, height, channels) {
            return Err(e);
        }
        if k == 0 || k > 64 {
            return Err(Error::InvalidModulus { bits: k });
        }
        let too_large = Error::TextureTooLarge {
            dimension: if width > height { width } else { height },
        };
        // `usize` has at most 64 bits, so `as u64` is lossless.
        #[allow(
            clippy::as_conversions,
            reason = "u32 -> u64, and usize -> u64 with usize::BITS <= 64 (USIZE_MAX64): lossless; \
                      From is not const"
        )]
        let (k64, channels, width64, height64) =
            (k as u64, channels as u64, width as u64, height as u64);
        let Some(entry_bits) = k64.checked_mul(channels) else {
            return Err(too_large);
        };
        let Some(row_bits) = entry_bits.checked_mul(width64) else {
            return Err(too_large);
        };
        let Some(total_bits) = row_bits.checked_mul(height64) else {
            return Err(too_large);
        };
        let Some(words) = words_of_bits(total_bits, max_words) else {
            return Err(too_large);
        };
        Ok(Sizes {
            entry_bits,
            row_bits,
            total_bits,
            words,
            entry_mask: if entry_bits >= 64 {
                u64::MAX
            } else {
                #[allow(clippy::as_conversions, reason = "entry_bits < 64 here: lossless")]
                let bits = entry_bits as u32;
                mask(bits)
            },
        })
    }
}

impl<'a, E: Entry, const C: usize> Modular<'a, E, C> {
    /// `k` for boxes of at most `max_area` texels (see [`modulus_bits_for`]).
    pub const fn bits_for_max_area(texel_bits: u32, max_area: u64) -> u32 {
        modulus_bits_for(texel_bits, max_area)
    }

    /// Words a `w x h` table at `k` bits needs: `ceil(w h C k / 32)`, computed in `u64` and
    /// checked. Refuses `k` outside `1..=E::BITS` ([`Error::InvalidModulus`]), an empty or
    /// oversized texture ([`Error::EmptyTexture`], [`Error::TextureTooLarge`]), and, with
    /// [`Error::TextureTooLarge`], a table whose size overflows `u64` bits or `usize` words (on a
    /// 32-bit target, more than `2^32 - 1` words).
    ///
    /// A `const fn`, so firmware can size a `static` at compile time:
    ///
    /// ```
    /// use texsat::layouts::Modular;
    /// use texsat::{BoxLookup, Border, NoCount, Rect, Texture};
    /// const K: u32 = Modular::<u32>::bits_for_max_area(8, 16 * 16); // 16 bits
    /// const WORDS: usize = match Modular::<u32>::words_needed(64, 48, K) {
    ///     Ok(n) => n,
    ///     Err(_) => panic!(),
    /// };
    /// static IMAGE: [u32; WORDS] = [0; WORDS]; // e.g. written by a host tool into flash
    /// assert_eq!(WORDS, 64 * 48 * 16 / 32);
    ///
    /// let texels = [3u8; 64 * 48];
    /// let tex = Texture::<u8>::new(&texels, 64, 48)?;
    /// let mut words = [0u32; WORDS];
    /// let mut row = [0u32; 64];
    /// let m = Modular::<u32>::build(&tex, K, &mut words, &mut row)?;
    /// let s = m.box_sum_int(&Rect::new(10, 10, 26, 26), Border, &mut NoCount)?;
    /// assert_eq!(s.sum(), 3 * 256);
    /// let _flash = Modular::<u32>::from_words(&IMAGE, 64, 48, 8, K)?;
    /// # Ok::<(), texsat::Error>(())
    /// ```
    pub const fn words_needed(width: usize, height: usize, k: u32) -> Result<usize, Error> {
        if k == 0 || k > E::BITS {
            return Err(Error::InvalidModulus { bits: k });
        }
        match Sizes::new(width, height, k, C, USIZE_MAX64) {
            Ok(s) => Ok(s.words),
            Err(e) => Err(e),
        }
    }

    /// Builds the table of `texture` modulo `2^k` into `words`, using `row` (`w * C` entries) as
    /// the one row of working state (its content afterwards is unspecified: with `simd` on an
    /// AVX2 CPU it holds the last row's residues in the fused row's order, transposed and
    /// rotated).
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
        let sizes = Sizes::new(width, height, k, C, USIZE_MAX64)?;
        if words.len() < sizes.words {
            return Err(Error::StorageTooSmall {
                needed: sizes.words,
                got: words.len(),
            });
        }
        Ok(Modular {
            words,
            width,
            height,
            texel_bits,
            k,
            sizes,
            _e: core::marker::PhantomData,
        })
    }

    /// The largest box area (in texel cells) whose sum is always exact: `floor((2^k - 1) / m)`.
    pub fn max_exact_area(&self) -> u64 {
        // k <= 64 and m = 2^b - 1 >= 1.
        mask(self.k).checked_div(mask(self.texel_bits)).unwrap_or(0)
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
        self.sizes.total_bits
    }
    /// One field of `k C` bits: read at once (two or three words) when `k C <= 64`, else one
    /// `k`-bit read per channel. Corners outside `[0, w] x [0, h]` read nothing and give 0.
    #[inline]
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        let mut out = [E::ZERO; C];
        // x - 1 < w and y - 1 < h: also refuses x = 0 and y = 0 (wrapping to usize::MAX).
        if x.wrapping_sub(1) >= self.width || y.wrapping_sub(1) >= self.height {
            return out;
        }
        let s = &self.sizes;
        if s.total_bits <= u64::from(u32::MAX) && s.entry_bits <= 32 {
            // Offsets below 2^32 and fields of at most 32 bits (the common case on a
            // microcontroller): 32-bit offset arithmetic and one two-word read, as the tiled
            // layout does.
            #[allow(
                clippy::arithmetic_side_effects,
                clippy::as_conversions,
                reason = "x, y >= 1 (checked above); x - 1 < w, y - 1 < h <= 2^31 - 1, and \
                          row_bits <= total_bits < 2^32, entry_bits <= 32, entry_mask < 2^32 here: \
                          every cast is lossless (and the offset below total_bits, Sizes)"
            )]
            let (at, read, entry_mask) = (
                ((y - 1) as u32)
                    .wrapping_mul(s.row_bits as u32)
                    .wrapping_add(((x - 1) as u32).wrapping_mul(s.entry_bits as u32)),
                s.entry_bits as u32,
                s.entry_mask as u32,
            );
            k.reads(1, read);
            k.read_at(Region::Table, u64::from(at), read);
            k.words((at % WORD_BITS).saturating_add(read).div_ceil(WORD_BITS));
            let v = u64::from(read_masked32(self.words, at, entry_mask));
            let m = mask(self.k);
            let mut shift = 0u32;
            for o in out.iter_mut() {
                *o = E::from_u64_truncating(v.wrapping_shr(shift) & m);
                shift = shift.wrapping_add(self.k);
            }
            return out;
        }
        // Below total_bits for x <= w, y <= h (checked when the sizes were made): no wrap.
        #[allow(
            clippy::arithmetic_side_effects,
            clippy::as_conversions,
            reason = "x, y >= 1 (checked above); usize -> u64 is lossless (usize::BITS <= 64)"
        )]
        let offset = ((y - 1) as u64)
            .wrapping_mul(s.row_bits)
            .wrapping_add(((x - 1) as u64).wrapping_mul(s.entry_bits));
        let read = u32::try_from(s.entry_bits).unwrap_or(u32::MAX);
        k.reads(1, read);
        k.read_at(Region::Table, offset, read);
        k.words(word_shift(offset).saturating_add(read).div_ceil(WORD_BITS));
        if C == 1 || s.entry_bits <= 64 {
            // One read of all channels (k C <= 64 bits; for C = 1, k <= 64).
            #[allow(
                clippy::as_conversions,
                reason = "entry_bits <= 64 in this branch (for C = 1 it is k <= 64): lossless"
            )]
            let bits = s.entry_bits as u32;
            let v = read_masked(self.words, offset, bits, s.entry_mask);
            if C == 1 {
                for o in out.iter_mut() {
                    *o = E::from_u64_truncating(v);
                }
            } else {
                let m = mask(self.k);
                let mut shift = 0u32;
                for o in out.iter_mut() {
                    *o = E::from_u64_truncating(v.wrapping_shr(shift) & m);
                    shift = shift.wrapping_add(self.k);
                }
            }
        } else {
            let mut at = offset;
            for o in out.iter_mut() {
                *o = E::from_u64_truncating(read_field(self.words, at, self.k));
                at = at.wrapping_add(u64::from(self.k));
            }
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
    sizes: Sizes,
    rows_done: usize,
    /// Whether the rows so far went through `simd::modular_row` (decided at the first row), so
    /// that `row` holds that function's transposed order.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    fused: bool,
    /// Whether the layout is past the caches (at least `simd::STREAM_MIN_BYTES`): the fused
    /// rows then store their words by non-temporal stores (AVX-512 VL) or ask for them ahead
    /// of their stores (see `simd::modular_row`).
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    past: bool,
}

impl<'a, 's, E: Entry, const C: usize> ModularBuilder<'a, 's, E, C> {
    /// A builder for a `w x h` texture of `texel_bits`-bit texels at `k` bits per entry; `row`
    /// (at least `w * C` entries, cleared here) is its working state between rows, in an order
    /// of its own (see [`Modular::build`]).
    ///
    /// With the `simd` feature on an x86-64 CPU with AVX2 (AVX-512 CPUs included), `u8` rows of
    /// one channel at least 256 texels wide, `k` from 11 to 32 and `w k` a multiple of 32 take a
    /// fused row: the prefix sums, the working row and the packing in one pass per 256 texels
    /// (`simd::modular_row`). `row` may sit anywhere: the fused row's order starts at its first
    /// index on 32 bytes. On a CPU with AVX-512 VL a layout of 32 MiB and more is written by
    /// non-temporal stores, each row whose words start on 16 bytes (every row when `words`
    /// does and `w k` is a multiple of 128). Measured against the flat build's time: on a CPU
    /// with AVX2 only 1.06x to 1.23x (earlier sessions); on a Zen 4 guest, 4,096^2 (44 MB at `k`
    /// = 21), 1.23x to 1.32x with plain stores (ninth session), 0.90x to 1.15x streamed in 11
    /// of the tenth session's 14 runs, 1.26x to 1.40x in three (`docs/benchmarks.md`).
    pub fn new(
        width: usize,
        height: usize,
        texel_bits: u32,
        k: u32,
        words: &'a mut [u32],
        row: &'s mut [E],
    ) -> Result<Self, Error> {
        check_k::<E>(texel_bits, k)?;
        let sizes = Sizes::new(width, height, k, C, USIZE_MAX64)?;
        if words.len() < sizes.words {
            return Err(Error::StorageTooSmall {
                needed: sizes.words,
                got: words.len(),
            });
        }
        let need = width
            .checked_mul(C)
            .ok_or(Error::TextureTooLarge { dimension: width })?;
        let got = row.len();
        let row = row
            .get_mut(..need)
            .ok_or(Error::StorageTooSmall { needed: need, got })?;
        row.fill(E::ZERO);
        Ok(ModularBuilder {
            words,
            row,
            width,
            height,
            texel_bits,
            k,
            sizes,
            rows_done: 0,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            fused: false,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            past: crate::simd::past_the_caches(sizes.words.saturating_mul(4)),
        })
    }

    /// Consumes the next texture row. The additions wrap modulo `2^k` on purpose; the row's
    /// fields are packed a word at a time. A refused row (wrong length, a texel wider than
    /// `texel_bits`, fields past the storage) changes nothing.
    pub fn push_row<T: Texel>(&mut self, texels: &[T]) -> Result<(), Error> {
        if self.rows_done >= self.height {
            return Err(Error::TooManyRows);
        }
        if texels.len() != self.row.len() {
            return Err(Error::RowLength {
                expected: self.row.len(),
                got: texels.len(),
            });
        }
        super::tiled::check_texel_width(texels, self.texel_bits)?;
        let k = self.k;
        // rows_done < h: the row's fields end at or before total_bits (no wrap).
        #[allow(
            clippy::as_conversions,
            reason = "usize -> u64 is lossless (usize::BITS <= 64)"
        )]
        let offset = (self.rows_done as u64).wrapping_mul(self.sizes.row_bits);
        if !BitWriter::fits(self.words, offset, self.row.len(), k) {
            // The first field that does not fit, as a field-by-field write would report it
            // (possible only with sizes that disagree with the storage: tests). Nothing is
            // written.
            let got = self.words.len();
            let mut end = offset;
            for _ in 0..self.row.len() {
                end = end.saturating_add(u64::from(k));
                let needed = words_of_bits(end, USIZE_MAX64).unwrap_or(usize::MAX);
                if needed > got {
                    return Err(Error::StorageTooSmall { needed, got });
                }
            }
        }
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        if self.fused_row(texels, offset)? {
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "rows_done < height (checked above)"
            )]
            {
                self.rows_done += 1;
            }
            return Ok(());
        }
        // The row of the table modulo 2^E::BITS (wrapping additions: only the low k bits are
        // kept, and those of a sum depend only on the low k bits of its terms); the same
        // vectorized row as the flat build where it applies (`simd`).
        super::tiled::add_prefix_row::<T, E, C>(texels, self.row);
        // Its low k bits, packed 32 fields (k words) at a time.
        if !pack_fields(self.words, offset, self.row, k) {
            return Err(Error::StorageTooSmall {
                needed: self.sizes.words,
                got: self.words.len(),
            });
        }
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "rows_done < height (checked above)"
        )]
        {
            self.rows_done += 1;
        }
        Ok(())
    }

    /// The row through `simd::modular_row` (AVX2: the prefix sums, the working row and the
    /// packing in one pass per 256 texels), its tail as the portable row; `Ok(false)` (nothing
    /// written) where that path does not apply. Decided at the first row for the whole build,
    /// since the fused path keeps the working row in its own order; a later row it declines
    /// (another texel type) puts the working row back in order first.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    fn fused_row<T: Texel>(&mut self, texels: &[T], offset: u64) -> Result<bool, Error> {
        if self.rows_done == 0 {
            self.fused = crate::simd::modular_fused::<T, E, C>(self.width, self.k);
        }
        if !self.fused {
            return Ok(false);
        }
        // `modular_fused`: width k is a multiple of 32, so every row starts on a word.
        let first = usize::try_from(offset.checked_div(u64::from(WORD_BITS)).unwrap_or(0))
            .unwrap_or(usize::MAX);
        let fused = self.words.get_mut(first..).and_then(|w| {
            crate::simd::modular_row::<T, E, C>(texels, self.row, w, self.k, self.past)
        });
        let Some((done, run)) = fused else {
            crate::simd::modular_untranspose(self.row);
            self.fused = false;
            return Ok(false);
        };
        // The tail after the last pass (one channel: `modular_fused`), in one or two runs of
        // the working row (`simd::modular_tail`): the portable row, started at the passes'
        // running sum, then at that and the first run's texels.
        let (first_run, second_run) = crate::simd::modular_tail(self.row, done);
        let texels = texels.get(done..).unwrap_or(&[]);
        let (t1, t2) = texels.split_at(first_run.len().min(texels.len()));
        let mut r = E::from_u64_truncating(u64::from(run));
        #[allow(
            clippy::arithmetic_side_effects,
            clippy::as_conversions,
            reason = "done <= width fields of k bits fit the storage (checked by the caller): \
                      no wrap; usize -> u64 is lossless"
        )]
        let mut at = offset + done as u64 * u64::from(self.k);
        for (run_texels, tail) in [(t1, first_run), (t2, second_run)] {
            if tail.is_empty() {
                // No tail (a width of whole passes), or no second run: nothing to add or pack
                // (the calls cost about a hundred instructions per row).
                continue;
            }
            super::tiled::add_prefix_row::<T, E, C>(run_texels, tail);
            for v in tail.iter_mut() {
                *v = v.wrapping_add(r);
            }
            if !pack_fields(self.words, at, tail, self.k) {
                return Err(Error::StorageTooSmall {
                    needed: self.sizes.words,
                    got: self.words.len(),
                });
            }
            for t in run_texels {
                r = r.wrapping_add(E::from(t.to_u16()));
            }
            #[allow(
                clippy::arithmetic_side_effects,
                clippy::as_conversions,
                reason = "as above: inside the row's fields"
            )]
            {
                at += tail.len() as u64 * u64::from(self.k);
            }
        }
        Ok(true)
    }

    /// Sets whether the layout counts as past the caches (tests: to run the fused row's
    /// streamed stores on a small layout).
    #[cfg(all(test, feature = "simd", target_arch = "x86_64"))]
    pub(super) fn set_past(&mut self, past: bool) {
        self.past = past;
    }

    /// The sizes the writes use (tests: to make a write fail).
    #[cfg(test)]
    pub(super) fn sizes_mut(&mut self) -> &mut Sizes {
        &mut self.sizes
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
            sizes: self.sizes,
            _e: core::marker::PhantomData,
        })
    }
}
