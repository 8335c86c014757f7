//! Fields of exact bit width packed into 32-bit words, as block RAM or a flash image holds them.
//!
//! Field `i` of a `b`-bit array occupies bits `[i b, (i + 1) b)` of the little-endian bit stream
//! formed by the words (bit 0 of word 0 first). A field of up to 64 bits touches one to three
//! words; readers report the number of words touched, which is what a 32-bit memory port pays.
//!
//! Sizes are computed in `u64` bits and converted to `usize` words with a check, so they are the
//! same on 32- and 64-bit targets or refused: [`words_for_checked`] is a `const fn`, for sizing a
//! `static` at compile time.
//!
//! Nothing here panics: reads past the end of the slice give zero bits, writes that do not fit
//! are refused.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

#[cfg(test)]
use crate::error::Error;
use crate::texel::Entry;
#[cfg(test)]
use crate::width::bits_of_u64;

/// Bits per storage word.
pub const WORD_BITS: u32 = 32;

/// [`WORD_BITS`] as a `u64` (bit offsets are `u64`).
#[allow(
    clippy::as_conversions,
    reason = "u32 -> u64 is lossless; u64::from is not const"
)]
const WORD_BITS64: u64 = WORD_BITS as u64;

/// `usize::MAX` as a `u64`: `usize` has at most 64 bits on every target Rust supports (asserted
/// here), so the conversion is lossless.
#[allow(
    clippy::as_conversions,
    reason = "usize::BITS <= 64 (asserted): lossless; u64::try_from is not const"
)]
pub(crate) const USIZE_MAX64: u64 = {
    assert!(usize::BITS <= u64::BITS);
    usize::MAX as u64
};

/// Words needed for `count` fields of `bits` bits: `ceil(count * bits / 32)`, saturating at
/// `usize::MAX` (which no slice holds, so a size check against it still refuses). See
/// [`words_for_checked`] for the checked form.
pub const fn words_for(count: usize, bits: u32) -> usize {
    match words_for_checked(count, bits) {
        Some(n) => n,
        None => usize::MAX,
    }
}

/// Words needed for `count` fields of `bits` bits, `ceil(count * bits / 32)`, or `None` if the
/// bit count overflows `u64` or the word count does not fit `usize` (on a 32-bit target: more
/// than `2^32 - 1` words).
///
/// ```
/// use texsat::layouts::packed::words_for_checked;
/// const WORDS: usize = match words_for_checked(1000, 12) {
///     Some(n) => n,
///     None => panic!("does not fit"),
/// };
/// static TABLE: [u32; WORDS] = [0; WORDS];
/// assert_eq!(TABLE.len(), 375);
/// assert_eq!(words_for_checked(usize::MAX, 64), None);
/// ```
pub const fn words_for_checked(count: usize, bits: u32) -> Option<usize> {
    // `usize` has at most 64 bits on every target Rust supports (USIZE_MAX64), so `as u64` is
    // lossless.
    #[allow(
        clippy::as_conversions,
        reason = "usize::BITS <= 64 (asserted at USIZE_MAX64) and u32 -> u64: lossless; \
                  From is not const"
    )]
    let (count, bits) = (count as u64, bits as u64);
    match count.checked_mul(bits) {
        Some(total) => words_of_bits(total, USIZE_MAX64),
        None => None,
    }
}

/// `ceil(bits / 32)` as `usize`, or `None` if it exceeds `max_words` (callers pass
/// `usize::MAX as u64`; tests pass `u32::MAX as u64` to check a 32-bit target's arithmetic on a
/// 64-bit host).
pub(crate) const fn words_of_bits(bits: u64, max_words: u64) -> Option<usize> {
    let words = bits.div_ceil(WORD_BITS64);
    #[allow(
        clippy::as_conversions,
        reason = "usize::MAX -> u64 is lossless (USIZE_MAX64), and words <= usize::MAX where it is \
                  cast back: lossless; From/TryFrom are not const"
    )]
    if words > max_words || words > usize::MAX as u64 {
        None
    } else {
        Some(words as usize)
    }
}

pub(crate) use crate::texture::check_dimensions;

/// `bits_of(a * b)`: the position of the highest set bit of the exact 128-bit product (`0` for
/// `0`), without a 128-bit multiply (32-bit limbs, as a 32-bit core would do it).
pub(crate) const fn bits_of_mul(a: u64, b: u64) -> u32 {
    const M: u64 = 0xFFFF_FFFF;
    let (a1, a0, b1, b0) = (a >> 32, a & M, b >> 32, b & M);
    // Each partial product is below 2^64; `mid` below 3 * 2^32; `hi` below 2^64 because the
    // whole product is below 2^128: no step wraps.
    let (p00, p01, p10, p11) = (
        a0.wrapping_mul(b0),
        a0.wrapping_mul(b1),
        a1.wrapping_mul(b0),
        a1.wrapping_mul(b1),
    );
    let mid = (p00 >> 32).wrapping_add(p01 & M).wrapping_add(p10 & M);
    let lo = (p00 & M) | (mid << 32);
    let hi = p11
        .wrapping_add(p01 >> 32)
        .wrapping_add(p10 >> 32)
        .wrapping_add(mid >> 32);
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "leading_zeros of a u64 is at most 64"
    )]
    let bits = if hi == 0 {
        64 - lo.leading_zeros()
    } else {
        128 - hi.leading_zeros()
    };
    bits
}

/// The low `len` bits set (`len <= 64`; `0` gives `0`, more than 64 all ones).
#[inline(always)]
pub(crate) const fn mask(len: u32) -> u64 {
    if len >= 64 {
        u64::MAX
    } else {
        1u64.wrapping_shl(len).wrapping_sub(1)
    }
}

/// The bit position of `offset` inside its 32-bit word: `offset mod 32`.
#[inline(always)]
pub(crate) fn word_shift(offset: u64) -> u32 {
    #[allow(
        clippy::as_conversions,
        reason = "offset mod 32 < 32: lossless (a cast, not u32::try_from: no branch on the field reads)"
    )]
    let s = (offset % WORD_BITS64) as u32;
    s
}

/// Word `first + i` of `words` widened to `u64`, `0` past the end.
#[inline(always)]
fn word(words: &[u32], first: usize, i: usize) -> u64 {
    match first.checked_add(i) {
        Some(j) => match words.get(j) {
            Some(&w) => u64::from(w),
            None => 0,
        },
        None => 0,
    }
}

/// The `len`-bit field (`1 <= len <= 64`) at bit `offset` of `words`; bits past the end of the
/// slice read as 0. Two 32-bit words joined in a `u64` when `offset % 32 + len <= 64` (every
/// field of at most 33 bits), a third one otherwise.
#[inline(always)]
pub(crate) fn read_field(words: &[u32], offset: u64, len: u32) -> u64 {
    read_masked(words, offset, len, mask(len))
}

/// [`read_field`] with `mask(len)` precomputed.
#[inline(always)]
pub(crate) fn read_masked(words: &[u32], offset: u64, len: u32, mask: u64) -> u64 {
    let shift = word_shift(offset);
    let Ok(first) = usize::try_from(offset / WORD_BITS64) else {
        return 0;
    };
    // Two words with one range check; at the end of the slice, word by word (0 past it).
    let pair = match words.get(first..first.wrapping_add(2)) {
        Some(&[a, b]) => u64::from(a) | u64::from(b) << 32,
        _ => word(words, first, 0) | word(words, first, 1) << 32,
    };
    let mut v = pair.wrapping_shr(shift);
    if shift.wrapping_add(len) > 64 {
        // shift is in 1..=31 here: the third word supplies the top `shift + len - 64` bits.
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "shift < 32 (word_shift): 64 - shift is in 33..=64"
        )]
        let up = 64 - shift;
        v |= word(words, first, 2).wrapping_shl(up);
    }
    v & mask
}

/// The field of at most 32 bits at bit `at` of `words` (`mask` its low bits set): the word
/// holding its first bit shifted down, or-ed with the next word shifted up (`(w << 1) << (31 -
/// s)`, which is 0 for `s = 0` without a 32-bit shift); words past the slice read as 0.
#[inline(always)]
#[allow(
    clippy::as_conversions,
    reason = "u32 -> usize is lossless (usize has at least 32 bits: MAX_DIMENSION); the last cast \
              keeps the low 32 bits on purpose, which mask (at most 32 bits) then selects"
)]
pub(crate) fn read_masked32(words: &[u32], at: u32, mask: u32) -> u32 {
    let i = (at / WORD_BITS) as usize;
    let s = at % WORD_BITS;
    // Both words with one range check; the last word of the slice alone (0 past it).
    let pair = match words.get(i..i.wrapping_add(2)) {
        Some(&[a, b]) => u64::from(a) | u64::from(b) << 32,
        _ => u64::from(words.get(i).copied().unwrap_or(0)),
    };
    (pair >> s) as u32 & mask
}

/// The 32 bits at bit `at` of `words` and the 32 bits at bit `at + delta` (both unmasked):
/// when `at + delta <= u32::MAX`, exactly [`read_masked32`] of each with `mask = u32::MAX`.
/// When both two-word windows lie inside the slice, one range check covers both: the second
/// window starts `(at % 32 + delta) / 32` words after the first, a non-negative amount formed
/// without wrapping, so the check of the later window implies the earlier one's and the
/// compiler drops it (two reads of a column of a tiled component, a row apart: one check fewer
/// per pair on the Cortex-M4). Otherwise the two reads one by one.
///
/// When `at + delta` passes `u32::MAX` the second value is unspecified (never a panic). The
/// tiled lookups never ask for it: their offsets are below the layout's total bits, below
/// `2^32`.
#[inline(always)]
#[allow(
    clippy::as_conversions,
    reason = "u32 -> usize is lossless (usize has at least 32 bits: MAX_DIMENSION); the casts to \
              u32 keep the low 32 bits on purpose, as in read_masked32"
)]
pub(crate) fn read2_32(words: &[u32], at: u32, delta: u32) -> (u32, u32) {
    let i = (at / WORD_BITS) as usize;
    let s = at % WORD_BITS;
    if let Some(t) = s.checked_add(delta) {
        // i < 2^27 and t / 32 < 2^27: no wrap on a 32-bit usize, so j >= i.
        let j = i.wrapping_add((t / WORD_BITS) as usize);
        if let (Some(&[c, d]), Some(&[a, b])) = (
            words.get(j..j.wrapping_add(2)),
            words.get(i..i.wrapping_add(2)),
        ) {
            let lo = (u64::from(a) | u64::from(b) << 32) >> s;
            let hi = (u64::from(c) | u64::from(d) << 32) >> (t % WORD_BITS);
            return (lo as u32, hi as u32);
        }
    }
    (
        read_masked32(words, at, u32::MAX),
        read_masked32(words, at.wrapping_add(delta), u32::MAX),
    )
}

/// Reads `len <= 64` bits starting at bit `offset` of `words`; returns the value and the number
/// of words touched. Bits past the end of the slice read as 0 (callers size the slice with
/// [`words_for`], so this never happens for a valid layout); `len` above 64 reads 64 bits.
#[inline]
pub fn read_bits(words: &[u32], offset: u64, len: u32) -> (u64, u32) {
    if len == 0 {
        return (0, 0);
    }
    let len = if len > 64 { 64 } else { len };
    let shift = word_shift(offset);
    #[allow(clippy::arithmetic_side_effects, reason = "shift < 32 and len <= 64")]
    let end = shift + len;
    (read_field(words, offset, len), end.div_ceil(WORD_BITS))
}

/// Writes the low `len <= 64` bits of `value` at bit `offset` (other bits untouched). Returns
/// `false` (writing nothing) if the field does not fit the slice, `value` has more than `len`
/// bits, or `len` exceeds 64.
#[inline]
pub fn write_bits(words: &mut [u32], offset: u64, len: u32, value: u64) -> bool {
    if len == 0 {
        return value == 0;
    }
    if len > 64 || value & !mask(len) != 0 {
        return false;
    }
    let shift = word_shift(offset);
    #[allow(
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "shift < 32 and len <= 64: at most 3 words, lossless in usize"
    )]
    let touched = (shift + len).div_ceil(WORD_BITS) as usize;
    let Ok(first) = usize::try_from(offset / WORD_BITS64) else {
        return false;
    };
    let Some(end) = first.checked_add(touched) else {
        return false;
    };
    let Some(dst) = words.get_mut(first..end) else {
        return false;
    };
    let m = mask(len);
    // The field and its mask moved to `shift`: the low 64 bits, then what spills into a third
    // word (only when shift + len > 64, so shift > 0).
    let (lo_v, lo_m) = (value.wrapping_shl(shift), m.wrapping_shl(shift));
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "shift is in 1..=31 where 64 - shift is formed"
    )]
    let (hi_v, hi_m) = if shift == 0 {
        (0, 0)
    } else {
        (value.wrapping_shr(64 - shift), m.wrapping_shr(64 - shift))
    };
    #[allow(
        clippy::as_conversions,
        reason = "splitting into 32-bit words: each cast keeps the low 32 bits on purpose"
    )]
    let parts = [
        (lo_v as u32, lo_m as u32),
        ((lo_v >> 32) as u32, (lo_m >> 32) as u32),
        (hi_v as u32, hi_m as u32),
    ];
    for (w, (b, pm)) in dst.iter_mut().zip(parts) {
        *w = (*w & !pm) | (b & pm);
    }
    true
}

/// [`write_bits`] with the reason of a refusal: [`Error::StorageTooSmall`] (in words) if the
/// field does not fit the slice, [`Error::TooWide`] if the value has more than `len` bits.
#[cfg(test)]
#[inline]
pub(crate) fn write_field(
    words: &mut [u32],
    offset: u64,
    len: u32,
    value: u64,
) -> Result<(), Error> {
    if write_bits(words, offset, len, value) {
        return Ok(());
    }
    if len > 64 || value & !mask(len) != 0 {
        return Err(Error::TooWide {
            what: crate::error::Quantity::Field,
            bits_needed: bits_of_u64(value),
            bits_available: len,
        });
    }
    Err(Error::StorageTooSmall {
        needed: match words_of_bits(offset.saturating_add(u64::from(len)), USIZE_MAX64) {
            Some(n) => n,
            None => usize::MAX,
        },
        got: words.len(),
    })
}

/// Writes consecutive fields from a bit offset on, a word at a time: the builders' packing
/// (each field costs a shift and an or; a word is stored once, when full), where
/// [`write_field`] reads and writes up to three words per field. Same layout as
/// [`write_bits`]: LSB first, little-endian words. Bits before the first field and after the last
/// are kept. The caller checks first that every field fits the slice ([`BitWriter::fits`]); a
/// word past the end would be dropped, never a panic.
///
/// In 32-bit arithmetic: the pending bits of one word in a `u32`, and the bits of a field that
/// cross into the next word one more shift. A 64-bit accumulator (as this writer had before)
/// costs several instructions per shift on a 32-bit core: on the Cortex-M4, where only 16-bit
/// fields have a group packer ([`pack_groups`]), `pack_fields` of 20-bit fields took 31
/// instructions per field with it and about 17 this way; a modular build of 64 x 64, 40.04 ->
/// 26.46 instructions per entry (`examples/firmware/count-insns.sh`, row 6c,
/// `COUNT_PROFILE=1`; docs/benchmarks.md, eighteenth session, in a function of its own), 25.89
/// since it is this writer's (nineteenth session).
pub(crate) struct BitWriter<'w> {
    /// The words from the one the pending bits go to.
    out: core::slice::IterMut<'w, u32>,
    /// Pending bits (fewer than 32 between pushes), LSB first.
    acc: u32,
    bits: u32,
}

impl<'w> BitWriter<'w> {
    /// Whether `count` fields of `len` bits from bit `offset` fit `words`.
    pub(crate) fn fits(words: &[u32], offset: u64, count: usize, len: u32) -> bool {
        let Ok(count) = u64::try_from(count) else {
            return false;
        };
        count
            .checked_mul(u64::from(len))
            .and_then(|b| b.checked_add(offset))
            .and_then(|end| words_of_bits(end, USIZE_MAX64))
            .is_some_and(|n| n <= words.len())
    }

    /// A writer at bit `offset` (its word's lower bits kept).
    #[inline]
    #[allow(
        clippy::as_conversions,
        reason = "mask(bits) < 2^32 (bits < 32): the low word, lossless"
    )]
    pub(crate) fn new(words: &'w mut [u32], offset: u64) -> Self {
        let rest = usize::try_from(offset / WORD_BITS64)
            .ok()
            .and_then(|first| words.get_mut(first..))
            .unwrap_or_default();
        let bits = word_shift(offset);
        let acc = rest.first().map_or(0, |&w| w & mask(bits) as u32);
        BitWriter {
            out: rest.iter_mut(),
            acc,
            bits,
        }
    }

    /// Appends the low `len <= 32` bits of `v` (`v < 2^len`).
    #[inline(always)]
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "bits < 32 and len <= 32 between pushes, so bits + len < 64 and end - 32 >= 0 \
                  where formed; v << bits is a u32 shift below 32, and 32 - bits is in 1..=32 \
                  (checked_shr takes 32)"
    )]
    pub(crate) fn push32(&mut self, v: u32, len: u32) {
        self.acc |= v << self.bits;
        let end = self.bits + len;
        if end >= WORD_BITS {
            if let Some(w) = self.out.next() {
                *w = self.acc;
            }
            // The field's bits past this word (none when it ends on the boundary).
            self.acc = v.checked_shr(WORD_BITS - self.bits).unwrap_or(0);
            self.bits = end - WORD_BITS;
        } else {
            self.bits = end;
        }
    }

    /// Appends a field of `len <= 64` bits (`v < 2^len`): as one push of 32 bits or fewer, or
    /// its low word then the rest.
    #[inline(always)]
    #[allow(
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "len - 32 where len > 32; the u32 casts keep the low word on purpose"
    )]
    pub(crate) fn push(&mut self, v: u64, len: u32) {
        if len <= WORD_BITS {
            self.push32(v as u32, len);
        } else {
            self.push32(v as u32, WORD_BITS);
            self.push32((v >> WORD_BITS) as u32, len - WORD_BITS);
        }
    }

    /// Stores the pending bits, keeping the word's bits above them.
    #[inline]
    #[allow(
        clippy::as_conversions,
        reason = "mask(bits) < 2^32 (bits < 32): the low word, lossless"
    )]
    pub(crate) fn finish(mut self) {
        if self.bits > 0 {
            if let Some(w) = self.out.next() {
                *w = (*w & !(mask(self.bits) as u32)) | self.acc;
            }
        }
    }
}

/// Packs the low `len` bits (`1 <= len <= 64`) of every value of `fields` back to back from bit
/// `offset` (field `i` at bit `offset + i len`, the layout of [`write_bits`]), keeping the bits
/// before `offset` and after the last field. Returns `false`, writing nothing, if the fields do
/// not fit the slice or `len` is 0 or above 64.
///
/// The builders' packing. Fields of at most 32 bits go 32 at a time (exactly `len` words)
/// through code specialized for the width ([`pack_groups`]): every shift a constant, every word
/// assembled in a register and stored once, no branch per field. On 64-bit targets every width
/// has its specialization; on smaller ones (microcontrollers, where each costs flash: about
/// 0.5 KiB per width and entry type on the Cortex-M4) only 16 bits, the width of a `modular:16`
/// plan, whose build it makes 2.5 times faster there (31.5 to 12.7 instructions per entry).
/// The rest (other widths, the fields after the last whole group, and fields wider than 32
/// bits) go through [`BitWriter`], in 32-bit arithmetic.
pub(crate) fn pack_fields<E: Entry>(
    words: &mut [u32],
    offset: u64,
    fields: &[E],
    len: u32,
) -> bool {
    if len == 0 || len > 64 || !BitWriter::fits(words, offset, fields.len(), len) {
        return false;
    }
    // With the `simd` feature, a word-aligned start and `u32` values, AVX-512 where the CPU has
    // it (`simd::pack_u32`); then the width-specialized groups; then the rest.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    let (fields, offset) = {
        let done = match usize::try_from(offset / WORD_BITS64) {
            Ok(first) if word_shift(offset) == 0 && len <= WORD_BITS => words
                .get_mut(first..)
                .map_or(0, |w| crate::simd::pack_u32(w, fields, len)),
            _ => 0,
        };
        #[allow(
            clippy::arithmetic_side_effects,
            clippy::as_conversions,
            reason = "done fields of len bits were written inside the slice (fits): no wrap; \
                      usize -> u64 is lossless"
        )]
        let offset = offset + done as u64 * u64::from(len);
        (fields.get(done..).unwrap_or(&[]), offset)
    };
    if fields.is_empty() {
        // All packed above (the tiled builder's rows of whole groups or runs): no writer to set
        // up.
        return true;
    }
    let (done, offset) = if len <= WORD_BITS {
        pack_groups(words, offset, fields, len)
    } else {
        (0, offset)
    };
    let fields = fields.get(done..).unwrap_or(&[]);
    let m = mask(len);
    let mut out = BitWriter::new(words, offset);
    if len <= WORD_BITS {
        #[allow(
            clippy::as_conversions,
            reason = "m < 2^32 (len <= 32): the low word, lossless"
        )]
        let m = m as u32;
        for f in fields {
            #[allow(
                clippy::as_conversions,
                reason = "the value's low word on purpose (its low len <= 32 bits kept)"
            )]
            out.push32(f.to_u64() as u32 & m, len);
        }
        out.finish();
        return true;
    }
    for f in fields {
        out.push(f.to_u64() & m, len);
    }
    out.finish();
    true
}

/// Packs the whole groups of 32 fields of `fields` (`len <= 32` bits each, their low bits) from
/// bit `offset`, which the caller has checked they fit; returns the fields done and the bit
/// offset after them (none for a width without a specialization on this target). Dispatches
/// on `len` to [`pack_groups_k`].
fn pack_groups<E: Entry>(words: &mut [u32], offset: u64, fields: &[E], len: u32) -> (usize, u64) {
    macro_rules! by_width {
        ($($k:literal)*) => {
            match len {
                $($k => pack_groups_k::<E, $k>(words, offset, fields),)*
                _ => (0, offset),
            }
        };
    }
    #[cfg(target_pointer_width = "64")]
    let done = by_width!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32);
    #[cfg(not(target_pointer_width = "64"))]
    let done = by_width!(16);
    done
}

/// [`pack_groups`] for `K`-bit fields. A group of 32 fields is exactly `K` words: [`group`]
/// assembles them as if the group started at a word boundary (the shifts are constants) and
/// stores each moved up by `s = offset mod 32`: stored word `m` is the top 32 bits of
/// `(w_m : w_{m-1}) >> (32 - s)`, the word before the first holding the `s` bits already in
/// the destination below `offset`. The `s` bits left over after the last group are merged into
/// the next word (its upper bits kept).
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "s < 32, so 32 - s is in 1..=32 and a u64 shift by it is defined; groups K words \
              and groups 32 K bits end inside the slice, which the caller checked (fits), so \
              first + n and offset + bits do not wrap; K <= 32: lossless casts; the u32 casts \
              keep the low word on purpose"
)]
fn pack_groups_k<E: Entry, const K: usize>(
    words: &mut [u32],
    offset: u64,
    fields: &[E],
) -> (usize, u64) {
    let groups = fields.len() / 32;
    let s = word_shift(offset);
    let Ok(first) = usize::try_from(offset / WORD_BITS64) else {
        return (0, offset);
    };
    let n = groups * K;
    if groups == 0 {
        return (0, offset);
    }
    let Some(dst) = words.get_mut(first..first + n) else {
        return (0, offset);
    };
    // The destination's bits below `offset`, at the top of the word before the first.
    let mut prev = (dst.first().map_or(0, |&w| u64::from(w)) << (32 - s)) as u32;
    for (f, d) in fields.chunks_exact(32).zip(dst.chunks_exact_mut(K)) {
        let (Ok(f), Ok(d)) = (<&[E; 32]>::try_from(f), <&mut [u32; K]>::try_from(d)) else {
            break;
        };
        if s == 0 {
            group::<E, K, false>(f, d, &mut prev, s);
        } else {
            group::<E, K, true>(f, d, &mut prev, s);
        }
    }
    if s > 0 {
        if let Some(d) = words.get_mut(first + n) {
            let keep = !(mask(s) as u32);
            *d = (*d & keep) | (prev >> (32 - s));
        }
    }
    (groups * 32, offset + (K as u64) * 32 * groups as u64)
}

/// 32 fields of `K` bits (their low bits) packed into `K` words, as from a word boundary (field
/// `i` at bit `i K`: bit `i K mod 32` of word `i K / 32`, its top bits in the next word when
/// it crosses the boundary), each word stored into `d` moved up by `s` bits as soon as it is
/// complete (see [`pack_groups_k`]; `prev` is the word before). Written out once per field (a
/// macro, not a loop, which LLVM keeps rolled): with `K` a constant every index, shift and
/// test is a constant, each word is assembled in a register and written once, and nothing
/// goes through memory in between.
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "i < 32 and K <= 32: i K < 1024 and the casts are lossless; sh < 32 and s < 32, so \
              32 - sh and 32 - s are in 1..=32, a K-bit field shifted by sh fits 64 bits, and \
              the u32 casts keep a word on purpose; j = i K / 32 < K, and j + 1 < K where the \
              field crosses (i K + K > 32 (j + 1) and i K + K <= 32 K)"
)]
fn group<E: Entry, const K: usize, const SHIFT: bool>(
    f: &[E; 32],
    d: &mut [u32; K],
    prev: &mut u32,
    s: u32,
) {
    let kb = K as u32;
    let m = mask(kb);
    let mut out = [0u32; K];
    macro_rules! fields {
        ($($i:literal)*) => {$(
            let v = f[$i].to_u64() & m;
            let p = $i * kb;
            let (j, sh) = ((p / WORD_BITS) as usize, p % WORD_BITS);
            if let Some(o) = out.get_mut(j) {
                *o |= (v << sh) as u32;
            }
            if sh + kb > WORD_BITS {
                if let Some(o) = out.get_mut(j + 1) {
                    *o |= (v >> (WORD_BITS - sh)) as u32;
                }
            }
            // Word j is complete once a field reaches its end.
            if sh + kb >= WORD_BITS {
                if let (Some(&w), Some(o)) = (out.get(j), d.get_mut(j)) {
                    if SHIFT {
                        *o = ((u64::from(w) << 32 | u64::from(*prev)) >> (WORD_BITS - s)) as u32;
                        *prev = w;
                    } else {
                        *o = w;
                    }
                }
            }
        )*};
    }
    fields!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31);
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions,
    reason = "tests: a panic is a failed test"
)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// The tests' noise: xorshift64 (13, 7, 17), the state advanced and returned.
    fn xorshift(seed: &mut u64) -> u64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        *seed
    }

    /// `BitWriter::push32` runs (what a 32-bit target's `pack_fields` runs for every width
    /// but 16, whole rows at a time) write what `write_bits` writes field by field: every
    /// width 1 to 32, every start bit 0 to 31 (and in a later word), runs of 0 to 3, 31 to 33
    /// and 100 and 257 fields; into noise with room after the fields, and into a slice that
    /// ends exactly at the last field's word (the last word full, or partial and the slice's
    /// last).
    #[test]
    fn bit_writer_push32_equals_write_bits() {
        let counts: &[usize] = if cfg!(miri) {
            &[0, 1, 33]
        } else {
            &[0, 1, 2, 3, 31, 32, 33, 100, 257]
        };
        let lens = (1..=32u32).filter(|l| !cfg!(miri) || [1, 7, 20, 31, 32].contains(l));
        for len in lens {
            let starts = (0..32u64)
                .chain([64 + 17])
                .filter(|s| !cfg!(miri) || s % 8 == 3);
            for start in starts {
                for &count in counts {
                    let mut seed = 0x0fed_cba9_8765_4321u64 ^ u64::from(len) << 7 ^ start << 20;
                    let mut next = || xorshift(&mut seed);
                    let end = start + count as u64 * u64::from(len);
                    let exact = end.div_ceil(32) as usize;
                    let noise: Vec<u32> = (0..exact + 3).map(|_| next() as u32).collect();
                    let fields: Vec<u64> = (0..count).map(|_| next()).collect();
                    for room in [3, 0] {
                        let n = exact + room;
                        let (mut a, mut b) = (noise[..n].to_vec(), noise[..n].to_vec());
                        for (i, f) in fields.iter().enumerate() {
                            let at = start + i as u64 * u64::from(len);
                            assert!(write_bits(&mut a, at, len, f & mask(len)));
                        }
                        let mut wr = BitWriter::new(&mut b, start);
                        for f in &fields {
                            wr.push32(*f as u32 & mask(len) as u32, len);
                        }
                        wr.finish();
                        assert_eq!(a, b, "len {len} start {start} count {count} room {room}");
                    }
                }
            }
        }
    }

    /// `pack_fields` writes what `write_bits` field by field writes, bits around the fields
    /// kept: every width 1 to 64, start offsets at and around word boundaries, counts below,
    /// at and past whole groups of 32 (the width-specialized path and the `BitWriter` tail),
    /// values wider than the field (only their low bits stored), for `u16`, `u32` and `u64`
    /// values; refusals (past the slice, width 0 or above 64) write nothing.
    #[test]
    fn pack_fields_equals_write_bits() {
        fn check<E: Entry>(to_e: impl Fn(u64) -> E, value_bits: u32) {
            // Under Miri (about 10^4 times slower) the widths around the specializations' and
            // the BitWriter's cases only, fewer offsets and counts.
            let counts: &[usize] = if cfg!(miri) {
                &[0, 70]
            } else {
                &[0, 1, 31, 32, 33, 64, 65, 100]
            };
            let starts: &[u64] = if cfg!(miri) {
                &[0, 13]
            } else {
                &[0, 1, 5, 13, 31, 32, 33, 63, 64, 100]
            };
            let lens =
                (1..=64u32).filter(|l| !cfg!(miri) || [1, 7, 16, 21, 32, 33, 64].contains(l));
            for len in lens {
                for &start in starts {
                    for &count in counts {
                        let mut seed = 0x1234_5678_9abc_def1u64 ^ u64::from(len) ^ start << 8;
                        let mut next = || xorshift(&mut seed);
                        let noise: Vec<u32> = (0..240).map(|_| next() as u32).collect();
                        let fields: Vec<E> = (0..count)
                            .map(|_| to_e(next() & mask(value_bits)))
                            .collect();
                        let (mut a, mut b) = (noise.clone(), noise.clone());
                        for (i, f) in fields.iter().enumerate() {
                            let at = start + i as u64 * u64::from(len);
                            assert!(write_bits(&mut a, at, len, f.to_u64() & mask(len)));
                        }
                        assert!(pack_fields(&mut b, start, &fields, len));
                        assert_eq!(a, b, "len {len} start {start} count {count}");
                        // One bit short of the slice: refused, nothing written.
                        let end = start + count as u64 * u64::from(len);
                        if count > 0 {
                            let mut c = noise.clone();
                            let short = end.div_ceil(32) as usize - 1;
                            assert!(!pack_fields(&mut c[..short], start, &fields, len));
                            assert_eq!(c, noise);
                        }
                    }
                }
            }
            let mut c = [7u32; 4];
            assert!(!pack_fields(&mut c, 0, &[to_e(1)], 0));
            assert!(!pack_fields(&mut c, 0, &[to_e(1)], 65));
            assert_eq!(c, [7; 4]);
        }
        check(|v| v as u16, 16);
        check(|v| v as u32, 32);
        check(|v| v, 64);
    }

    /// The writer lays fields out exactly as `write_bits` does, for every field width 1 to 64
    /// (`push`: one or two 32-bit pushes) at several starting offsets, over words that start
    /// as noise (bits outside the fields kept).
    #[test]
    fn bit_writer_equals_write_bits() {
        for len in 1..=64u32 {
            for start in [0u64, 1, 5, 31, 32, 33, 63, 100] {
                let mut seed = 0x1234_5678_9abc_def1u64 ^ u64::from(len);
                let mut noise = [0u32; 40];
                for w in noise.iter_mut() {
                    *w = xorshift(&mut seed) as u32;
                }
                let count = 9;
                let fields: [u64; 9] = core::array::from_fn(|i| {
                    (seed.rotate_left(7 * i as u32) ^ (i as u64 * 0x9e37_79b9)) & mask(len)
                });
                let (mut a, mut b) = (noise, noise);
                for (i, &v) in fields.iter().enumerate() {
                    assert!(write_bits(
                        &mut a,
                        start + i as u64 * u64::from(len),
                        len,
                        v
                    ));
                }
                assert!(BitWriter::fits(&b, start, count, len));
                let mut wr = BitWriter::new(&mut b, start);
                for &v in &fields {
                    wr.push(v, len);
                }
                wr.finish();
                assert_eq!(a, b, "len {len} start {start}");
            }
        }
        assert!(!BitWriter::fits(&[0u32; 2], 60, 1, 5));
        assert!(BitWriter::fits(&[0u32; 2], 59, 1, 5));
    }

    #[test]
    fn read_masked32_equals_the_64_bit_read() {
        // Every width up to 32 at every offset of a pseudo-random slice, including fields that
        // end in the last word and offsets past the slice (read as 0 by both).
        let mut x = 0x9E37_79B9u32;
        let words: [u32; 6] = core::array::from_fn(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        });
        for len in 1..=32u32 {
            let m = mask(len);
            for at in 0..(7 * 32) {
                assert_eq!(
                    u64::from(read_masked32(&words, at, m as u32)),
                    read_masked(&words, u64::from(at), len, m),
                    "len {len} at {at}"
                );
            }
        }
    }

    #[test]
    fn read2_32_equals_two_single_reads() {
        // Both windows at every pair of offsets of a pseudo-random slice (the second before,
        // at or after the first, in the last word, past the slice): always the two
        // read_masked32 calls' values.
        let mut x = 0x2545_F491u32;
        let words: [u32; 5] = core::array::from_fn(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        });
        let step = if cfg!(miri) { 7 } else { 1 };
        for at in (0..(6 * 32)).step_by(step) {
            for second in (0..(6 * 32)).step_by(step) {
                let delta = u32::wrapping_sub(second, at);
                assert_eq!(
                    read2_32(&words, at, delta),
                    (
                        read_masked32(&words, at, u32::MAX),
                        read_masked32(&words, second, u32::MAX)
                    ),
                    "at {at} second {second}"
                );
            }
        }
        // A second offset past u32::MAX: no panic; the first value is still exact.
        for (at, delta) in [(u32::MAX, 1), (u32::MAX - 31, 40), (33, u32::MAX - 1)] {
            assert_eq!(
                read2_32(&words, at, delta).0,
                read_masked32(&words, at, u32::MAX),
                "at {at} delta {delta}"
            );
        }
    }

    #[test]
    fn round_trip_every_width_and_offset() {
        let mut words = [0u32; 8];
        for len in 1..=64u32 {
            let end_offset = 8 * 32 - len as u64;
            // Under Miri (about 10^4 times slower) every width, but only the offsets at and next
            // to a word boundary, every 11th, and the last.
            let offsets = (0..end_offset).filter(|o| {
                !cfg!(miri)
                    || matches!(o % 32, 0 | 1 | 31)
                    || o.is_multiple_of(11)
                    || o + 1 == end_offset
            });
            for offset in offsets {
                let value =
                    0xDEAD_BEEF_CAFE_F00Du64 & if len == 64 { u64::MAX } else { (1 << len) - 1 };
                words.fill(0xA5A5_A5A5);
                assert!(write_bits(&mut words, offset, len, value));
                let (v, touched) = read_bits(&words, offset, len);
                assert_eq!(v, value, "len {len} offset {offset}");
                assert_eq!(touched, ((offset % 32) as u32 + len).div_ceil(32));
                // Neighbouring bits are untouched.
                if offset > 0 {
                    assert_eq!(
                        read_bits(&words, 0, offset.min(64) as u32).0,
                        read_bits(&[0xA5A5_A5A5u32; 8], 0, offset.min(64) as u32).0
                    );
                }
                let end = offset + len as u64;
                if end < 8 * 32 {
                    let rest = (8 * 32 - end).min(64) as u32;
                    assert_eq!(
                        read_bits(&words, end, rest).0,
                        read_bits(&[0xA5A5_A5A5u32; 8], end, rest).0,
                        "len {len} offset {offset}: bits after the field"
                    );
                }
            }
        }
    }

    /// The reads against a `u128` reference (tests may use `u128`): every width, every offset,
    /// including fields that run past the end of the slice (those bits read as 0).
    #[test]
    fn read_matches_u128_reference() {
        let words = [
            0x0123_4567u32,
            0x89AB_CDEF,
            0xFEDC_BA98,
            0x7654_3210,
            0xDEAD_BEEF,
        ];
        let bit = |i: u64| -> u64 {
            words
                .get((i / 32) as usize)
                .map_or(0, |&w| (w as u64 >> (i % 32)) & 1)
        };
        // Under Miri (about 10^4 times slower) every width but only every 40th offset and the
        // word and slice boundaries (the slice holds 160 bits).
        let edges = [1, 31, 32, 33, 63, 64, 96, 127, 128, 159, 160, 199];
        let offsets: Vec<u64> = (0..200u64)
            .filter(|o| !cfg!(miri) || o.is_multiple_of(40) || edges.contains(o))
            .collect();
        for len in 1..=64u32 {
            for &offset in &offsets {
                let want = (0..len as u64).fold(0u64, |v, i| v | bit(offset + i) << i);
                assert_eq!(read_field(&words, offset, len), want, "{len} {offset}");
                assert_eq!(read_bits(&words, offset, len).0, want, "{len} {offset}");
            }
        }
        // Offsets whose word index does not fit the slice (or usize) read 0.
        assert_eq!(read_bits(&words, u64::MAX - 3, 64), (0, 3));
        assert_eq!(read_bits(&words, u64::MAX, 1).0, 0);
        assert_eq!(read_bits(&words, 3, 0), (0, 0));
        assert_eq!(read_bits(&words, 0, 200).0, read_bits(&words, 0, 64).0);
    }

    #[test]
    fn refuses_what_does_not_fit() {
        let mut words = [0u32; 2];
        assert!(!write_bits(&mut words, 40, 32, 1));
        assert!(!write_bits(&mut words, 0, 4, 16));
        assert!(!write_bits(&mut words, 0, 65, 1));
        assert!(!write_bits(&mut words, u64::MAX - 10, 8, 1));
        assert!(write_bits(&mut words, 0, 0, 0));
        assert!(!write_bits(&mut words, 0, 0, 1));
        assert_eq!(words, [0, 0]);
        assert_eq!(
            write_field(&mut words, 40, 32, 1),
            Err(Error::StorageTooSmall { needed: 3, got: 2 })
        );
        assert_eq!(
            write_field(&mut words, 0, 4, 16),
            Err(Error::TooWide {
                what: crate::error::Quantity::Field,
                bits_needed: 5,
                bits_available: 4
            })
        );
        assert_eq!(words_for(3, 12), 2);
        assert_eq!(words_for(0, 12), 0);
        assert_eq!(words_for_checked(3, 12), Some(2));
        assert_eq!(words_for_checked(usize::MAX, 64), None);
        assert_eq!(words_for(usize::MAX, 64), usize::MAX);
    }

    /// The 32-bit target's conversion, checked on any host: `2^32 - 1` words fit, one more does
    /// not (on a 64-bit host it does).
    #[test]
    fn words_of_bits_on_32_bit_targets() {
        let max32 = u32::MAX as u64;
        assert_eq!(words_of_bits(max32 * 32, max32), Some(u32::MAX as usize));
        assert_eq!(words_of_bits(max32 * 32 + 1, max32), None);
        assert_eq!(words_of_bits(u64::MAX, max32), None);
        assert_eq!(
            words_of_bits(max32 * 32 + 1, u64::MAX),
            Some(u32::MAX as usize + 1)
        );
        assert_eq!(
            words_of_bits(u64::MAX, u64::MAX),
            Some((u64::MAX / 32 + 1) as usize)
        );
    }

    #[test]
    fn bits_of_mul_matches_u128() {
        let vals = [
            0u64,
            1,
            2,
            3,
            255,
            256,
            65535,
            (1 << 31) - 1,
            1 << 32,
            (1 << 32) + 1,
            u64::MAX / 3,
            (1 << 62) - 1,
            u64::MAX - 1,
            u64::MAX,
        ];
        for &a in &vals {
            for &b in &vals {
                let want = 128 - (a as u128 * b as u128).leading_zeros();
                assert_eq!(bits_of_mul(a, b), want, "{a} * {b}");
            }
        }
    }
}
