//! Fields of exact bit width packed into 32-bit words, as block RAM or a flash image holds them.
//!
//! Field `i` of a `b`-bit array occupies bits `[i b, (i + 1) b)` of the little-endian bit stream
//! formed by the words (bit 0 of word 0 first). A field of up to 64 bits touches one to three
//! words; readers report the number of words touched, which is what a 32-bit memory port pays.

/// Bits per storage word.
pub const WORD_BITS: u32 = 32;

/// Words needed for `count` fields of `bits` bits: `ceil(count * bits / 32)`.
pub const fn words_for(count: usize, bits: u32) -> usize {
    let total = count as u128 * bits as u128;
    total.div_ceil(WORD_BITS as u128) as usize
}

/// Reads `len <= 64` bits starting at bit `offset` of `words`; returns the value and the number
/// of words touched. Bits past the end of the slice read as 0 (callers size the slice with
/// [`words_for`], so this never happens for a valid layout).
#[inline]
pub fn read_bits(words: &[u32], offset: u64, len: u32) -> (u64, u32) {
    if len == 0 {
        return (0, 0);
    }
    let first = (offset / WORD_BITS as u64) as usize;
    let shift = (offset % WORD_BITS as u64) as u32;
    let touched = (shift + len).div_ceil(WORD_BITS);
    let mut acc: u128 = 0;
    for k in 0..touched as usize {
        let w = words.get(first + k).copied().unwrap_or(0) as u128;
        acc |= w << (k as u32 * WORD_BITS);
    }
    let mask = if len == 64 {
        u64::MAX
    } else {
        (1u64 << len) - 1
    };
    (((acc >> shift) as u64) & mask, touched)
}

/// Writes the low `len <= 64` bits of `value` at bit `offset` (other bits untouched). Returns
/// `false` (writing nothing) if the field does not fit the slice or `value` has more than `len`
/// bits.
#[inline]
pub fn write_bits(words: &mut [u32], offset: u64, len: u32, value: u64) -> bool {
    if len == 0 {
        return value == 0;
    }
    if len < 64 && value >> len != 0 {
        return false;
    }
    let first = (offset / WORD_BITS as u64) as usize;
    let shift = (offset % WORD_BITS as u64) as u32;
    let touched = (shift + len).div_ceil(WORD_BITS) as usize;
    if first
        .checked_add(touched)
        .is_none_or(|end| end > words.len())
    {
        return false;
    }
    let field_mask: u128 = ((1u128 << len) - 1) << shift;
    let bits: u128 = (value as u128) << shift;
    for k in 0..touched {
        let m = (field_mask >> (k as u32 * WORD_BITS)) as u32;
        let b = (bits >> (k as u32 * WORD_BITS)) as u32;
        words[first + k] = (words[first + k] & !m) | (b & m);
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_every_width_and_offset() {
        let mut words = [0u32; 8];
        for len in 1..=64u32 {
            for offset in 0..(8 * 32 - len as u64) {
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
            }
        }
    }

    #[test]
    fn refuses_what_does_not_fit() {
        let mut words = [0u32; 2];
        assert!(!write_bits(&mut words, 40, 32, 1));
        assert!(!write_bits(&mut words, 0, 4, 16));
        assert_eq!(words_for(3, 12), 2);
        assert_eq!(words_for(0, 12), 0);
    }
}
