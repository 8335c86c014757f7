//! Width analysis: how many bits each entry and each lookup intermediate needs, proved before a
//! table is written or a lookup is made.
//!
//! All functions are `const fn`, so a firmware build can check its texture sizes at compile time:
//!
//! ```
//! use texsat::width;
//! // 8-bit texels, u32 entries: 4104 x 4104 fits (255 * 4104^2 < 2^32), 4105 x 4105 does not.
//! const _: () = assert!(width::entry_bits_worst_case(8, 4104, 4104) == 32);
//! const _: () = assert!(width::entry_bits_worst_case(8, 4105, 4105) == 33);
//! ```
//!
//! ## Entries (proof)
//! Texels are unsigned, so the table is monotone in both coordinates and its largest entry is the
//! whole-texture sum `T <= m * w * h` with `m = 2^b - 1` the largest texel. Every intermediate of
//! the two-addition build (§3.0: running row sum `r`, then `r + entry above`) is a sum of texels of
//! a sub-rectangle, hence `<= T`. An entry type of `k` bits is therefore safe iff
//! `m * w * h < 2^k`, i.e. `bits_of(m * w * h) <= k`, where `bits_of(v)` is the position of the
//! highest set bit of `v`. This is exact: the all-`m` texture reaches it.
//!
//! The often-quoted `b + ceil(log2(w * h))` is only an upper bound (it rounds `m = 2^b - 1` up to
//! `2^b`): it would refuse 4104 x 4104 in `u32` (33 bits) although every entry fits; see
//! [`entry_bits_naive`].
//!
//! ## Lookups
//! With `F` fractional corner bits the box integral is a multiple of `2^-2F`; lookups compute it
//! scaled by `2^2F`. See [`paper_acc_bits`], [`stable_acc_bits`], and `docs/design.md` for the
//! multiplier operand widths of each formulation.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::error::{Error, Quantity};

// The `usize as u64` / `usize as u128` casts below are lossless (no From in a `const fn`).
const _: () = assert!(usize::BITS <= u64::BITS);

/// Number of bits needed to hold `v`: `0` for `0`, else `floor(log2(v)) + 1`.
#[allow(
    clippy::arithmetic_side_effects,
    reason = "leading_zeros is at most the width"
)]
pub const fn bits_of(v: u128) -> u32 {
    128 - v.leading_zeros()
}

/// [`bits_of`] for `u64` (what the lookups' paths use: no 128-bit operation).
#[allow(
    clippy::arithmetic_side_effects,
    reason = "leading_zeros is at most the width"
)]
pub const fn bits_of_u64(v: u64) -> u32 {
    64 - v.leading_zeros()
}

/// `ceil(log2(v))` for `v >= 1` (and `0` for `v <= 1`).
pub const fn ceil_log2(v: u128) -> u32 {
    if v <= 1 {
        0
    } else {
        #[allow(clippy::arithmetic_side_effects, reason = "v > 1 here")]
        let below = v - 1;
        bits_of(below)
    }
}

/// The largest texel of `texel_bits` bits: `2^b - 1` (`u128::MAX` from 128 bits on).
pub const fn max_texel(texel_bits: u32) -> u128 {
    if texel_bits >= 128 {
        u128::MAX
    } else {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "texel_bits < 128: 1 << texel_bits >= 1"
        )]
        let m = (1u128 << texel_bits) - 1;
        m
    }
}

/// The largest texel of `texel_bits` bits in `u64` (`u64::MAX` from 64 bits on).
pub const fn max_texel_u64(texel_bits: u32) -> u64 {
    if texel_bits >= 64 {
        u64::MAX
    } else {
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "texel_bits < 64: 1 << texel_bits >= 1"
        )]
        let m = (1u64 << texel_bits) - 1;
        m
    }
}

/// Texel widths the crate accepts: 1 to 16 bits.
pub const MAX_TEXEL_BITS: u32 = 16;

/// Refuses texel widths outside `1..=16`.
pub const fn check_texel_bits(texel_bits: u32) -> Result<(), Error> {
    if texel_bits == 0 || texel_bits > MAX_TEXEL_BITS {
        Err(Error::InvalidTexelBits { bits: texel_bits })
    } else {
        Ok(())
    }
}

/// The largest possible whole-table sum: `(2^b - 1) * w * h` (saturating at `u128::MAX`, which
/// no entry type holds, so a saturated value is still refused). A host-side convenience; the
/// checks below compute the bits without 128-bit arithmetic.
#[allow(
    clippy::as_conversions,
    reason = "usize has at most 64 bits (asserted at the top): lossless"
)]
pub const fn worst_case_total(texel_bits: u32, width: usize, height: usize) -> u128 {
    max_texel(texel_bits)
        .saturating_mul(width as u128)
        .saturating_mul(height as u128)
}

/// Bits of the product `a * b * c` of three `u64`, exactly, from 32-bit limbs (no 128-bit
/// operation, so it costs a firmware's build and lookups nothing wider than 64 bits).
#[allow(
    clippy::arithmetic_side_effects,
    clippy::indexing_slicing,
    clippy::as_conversions,
    reason = "one proof for the function (const: no iterators, no From), in its comments: the fast \
              path multiplies factors below 2^32 and (ab >> 32) c + (lo >> 32) < 2^64; 32 + bits <= \
              96. The limb loop indexes with f < 2, i < 6 and k < 6 (loop bounds), multiplies limbs \
              below 2^32, and each limb plus a carry stays below 2^33; 32 i + bits <= 224"
)]
pub const fn bits_of_product(a: u64, b: u64, c: u64) -> u32 {
    // Factors below 2^32 (a texel maximum and two sides, on any target with 32-bit `usize` the
    // compiler sees it and drops the general path below): `a b` is exact in `u64`, and its
    // product with `c` is two 32 x 32 -> 64 multiplies: `a b c = hi 2^32 + (lo mod 2^32)`.
    if a >> 32 == 0 && b >> 32 == 0 && c >> 32 == 0 {
        let ab = a * b;
        let lo = (ab & 0xFFFF_FFFF) * c;
        // (ab >> 32) c < 2^64 - 2^32 and lo >> 32 < 2^32: no overflow.
        let hi = (ab >> 32) * c + (lo >> 32);
        return if hi >> 32 != 0 {
            32 + bits_of_u64(hi)
        } else {
            bits_of_u64((hi << 32) | (lo & 0xFFFF_FFFF))
        };
    }
    // Six 32-bit limbs, least significant first.
    let mut limbs = [0u64; 6];
    limbs[0] = a & 0xFFFF_FFFF;
    limbs[1] = a >> 32;
    let factors = [b, c];
    let mut f = 0;
    while f < 2 {
        let (v0, v1) = (factors[f] & 0xFFFF_FFFF, factors[f] >> 32);
        let mut out = [0u64; 6];
        let mut i = 0;
        while i < 6 {
            // Each partial product is below 2^64 and each sum of a limb and a carry stays below
            // 2^64 because limbs and carries are below 2^32 after normalisation.
            let lo = limbs[i] * v0;
            let hi = limbs[i] * v1;
            let mut k = i;
            let mut carry = lo;
            while carry != 0 && k < 6 {
                let t = out[k] + (carry & 0xFFFF_FFFF);
                out[k] = t & 0xFFFF_FFFF;
                carry = (carry >> 32) + (t >> 32);
                k += 1;
            }
            let mut k = i + 1;
            let mut carry = hi;
            while carry != 0 && k < 6 {
                let t = out[k] + (carry & 0xFFFF_FFFF);
                out[k] = t & 0xFFFF_FFFF;
                carry = (carry >> 32) + (t >> 32);
                k += 1;
            }
            i += 1;
        }
        limbs = out;
        f += 1;
    }
    let mut i = 6;
    while i > 0 {
        i -= 1;
        if limbs[i] != 0 {
            return 32 * i as u32 + bits_of_u64(limbs[i]);
        }
    }
    0
}

/// Bits of the product of up to six `u64` factors, exactly, with no 128-bit operation: checked
/// 64-bit multiplies while the product fits, else from 32-bit limbs. For the width proofs whose
/// worst case has more factors than [`bits_of_product`] takes (the tent filter's
/// `m w (w + 2) h (h + 2)`). `None` for more than six factors; the empty product is 1.
#[cfg(any(feature = "filter-tent", test))]
#[allow(
    clippy::arithmetic_side_effects,
    clippy::indexing_slicing,
    clippy::as_conversions,
    reason = "one proof for the function (const: no iterators, no From): the loops index limbs \
              with i, k < LIMBS and factors with f < factors.len() (loop bounds, so f + 1 does \
              not wrap); the product of at most six 64-bit factors is below 2^384 = \
              2^(32 LIMBS), so every carry settles inside the limbs; limbs and factor halves are \
              below 2^32, so each partial product is below 2^64 and each limb plus a carry's low \
              half below 2^33; 32 i + bits <= 384"
)]
pub(crate) const fn bits_of_product_n(factors: &[u64]) -> Option<u32> {
    const LIMBS: usize = 12;
    const MASK: u64 = 0xFFFF_FFFF;
    if factors.len() > 6 {
        return None;
    }
    // A product that fits 64 bits (every table a build accepts into `u32` or `u64` entries):
    // checked 64-bit multiplies.
    let mut p: u64 = 1;
    let mut f = 0;
    while f < factors.len() {
        match p.checked_mul(factors[f]) {
            Some(v) => p = v,
            None => break,
        }
        f += 1;
    }
    if f == factors.len() {
        return Some(bits_of_u64(p));
    }
    // Past 64 bits: 32-bit limbs, least significant first.
    let mut limbs = [0u64; LIMBS];
    limbs[0] = 1;
    let mut f = 0;
    while f < factors.len() {
        let (v0, v1) = (factors[f] & MASK, factors[f] >> 32);
        let mut out = [0u64; LIMBS];
        let mut i = 0;
        while i < LIMBS {
            // limbs[i] v0 adds at limb i, limbs[i] v1 at limb i + 1.
            let mut half = 0;
            while half < 2 {
                let mut k = i + half;
                let mut carry = limbs[i] * if half == 0 { v0 } else { v1 };
                while carry != 0 && k < LIMBS {
                    let t = out[k] + (carry & MASK);
                    out[k] = t & MASK;
                    carry = (carry >> 32) + (t >> 32);
                    k += 1;
                }
                half += 1;
            }
            i += 1;
        }
        limbs = out;
        f += 1;
    }
    let mut i = LIMBS;
    while i > 0 {
        i -= 1;
        if limbs[i] != 0 {
            return Some(32 * i as u32 + bits_of_u64(limbs[i]));
        }
    }
    Some(0)
}

/// Exact bits per entry (and channel) the worst case needs: `bits_of((2^b - 1) * w * h)`
/// (texel widths above 64 bits, which no texel has, saturate at `2^64 - 1`).
#[allow(
    clippy::as_conversions,
    reason = "usize has at most 64 bits (asserted at the top): lossless"
)]
pub const fn entry_bits_worst_case(texel_bits: u32, width: usize, height: usize) -> u32 {
    bits_of_product(max_texel_u64(texel_bits), width as u64, height as u64)
}

/// The conservative textbook bound `b + ceil(log2(w * h))`. Never smaller than
/// [`entry_bits_worst_case`], sometimes one larger; kept to document the difference.
#[allow(
    clippy::as_conversions,
    reason = "usize has at most 64 bits (asserted at the top): lossless"
)]
pub const fn entry_bits_naive(texel_bits: u32, width: usize, height: usize) -> u32 {
    texel_bits.saturating_add(ceil_log2((width as u128).saturating_mul(height as u128)))
}

/// Refuses a table whose worst case does not fit `entry_bits`.
pub const fn check_entry_worst_case(
    texel_bits: u32,
    width: usize,
    height: usize,
    entry_bits: u32,
) -> Result<(), Error> {
    if let Err(e) = check_texel_bits(texel_bits) {
        return Err(e);
    }
    let needed = entry_bits_worst_case(texel_bits, width, height);
    if needed > entry_bits {
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: needed,
            bits_available: entry_bits,
        })
    } else {
        Ok(())
    }
}

/// Largest `F` the fixed-point lookups accept. Keeps `w * 2^F` and the placed coordinates inside
/// `i64` (`2^31 x 2^24 = 2^55`) and the fraction numerators inside `u32`.
pub const MAX_FRAC_BITS: u32 = 24;

/// Accumulator bits (sign excluded) of the [`crate::Paper`] lookup for a table whose entries are
/// at most `total` (`total_bits = bits_of(total)`): `total_bits + 2F`.
///
/// Proof: every corner value is a bilinear interpolation `v = r0 * 2^F + (r1 - r0) * B` with
/// `r = S0 * 2^F + (S1 - S0) * A`, `0 <= A, B <= 2^F`; the table is monotone, so every
/// difference is non-negative and every partial result lies in `[0, total * 2^2F]`; the final
/// `(V11 - V10) - (V01 - V00)` is a difference of non-negative, ordered values.
pub const fn paper_acc_bits(total_bits: u32, frac_bits: u32) -> u32 {
    total_bits.saturating_add(frac_bits.saturating_mul(2))
}

/// Accumulator bits (sign excluded) of the [`crate::Stable`] lookup: `total_bits + 2F + 1`.
///
/// `total_bits` may be the bits of the largest *box* sum the caller will ask for (the width of
/// the accumulator depends on the box, not on the table), but this crate checks against the
/// table's total. Proof: the lookup evaluates `(Bint << 2F) + (E << F) + K` with
/// `E = (A1 Rt - A0 L) + (B1 Bm - B0 T)` and `K = (A1 B1 t11 - A1 B0 t10) - (A0 B1 t01 - A0 B0 t00)`.
/// `Bint`, `Rt` (column `i1`), `Bm` (row `j1`) cover disjoint parts of the box grown by one
/// texel, so `Bint + Rt + Bm <= total`; `L + T <= total + t00`; each product of a fraction and a
/// strip lies in `[0, 2^F strip]`. So `E << F` lies in `[-(L + T) 2^2F, (Rt + Bm) 2^2F]`, every
/// partial sum in `(-2 total 2^2F, 2 total 2^2F)`, and `|K| <= 2 m 2^2F`.
pub const fn stable_acc_bits(total_bits: u32, frac_bits: u32) -> u32 {
    total_bits
        .saturating_add(frac_bits.saturating_mul(2))
        .saturating_add(1)
}

/// Accumulator value bits of each table entry type: `u16` tables compute in `i32` (31 value
/// bits), `u32` tables in `i64` (63), `u64` tables in `i128` (127).
pub const fn acc_value_bits(entry_bits: u32) -> u32 {
    if entry_bits <= 16 {
        31
    } else if entry_bits <= 32 {
        63
    } else {
        127
    }
}

/// The largest `F` a lookup in `form` allows on a table whose largest entry has `total_bits`
/// bits, computing in an accumulator of `acc_value_bits` value bits (see [`acc_value_bits`]),
/// capped at [`MAX_FRAC_BITS`]; `None` if not even `F = 0` fits. From [`paper_acc_bits`]
/// (`total + 2F <= acc`) and [`stable_acc_bits`] (`total + 2F + 1 <= acc`).
///
/// For full tables: a `u16` table (16-bit total) allows `F <= 7` in both forms; a `u32` table
/// (32-bit total) `F <= 15`; a `u64` table (64-bit total) `F <= 24` (the cap). Tabulated in
/// `docs/design.md`.
pub const fn max_frac_bits(
    form: crate::FormKind,
    total_bits: u32,
    acc_value_bits: u32,
) -> Option<u32> {
    let extra = match form {
        crate::FormKind::Paper => 0,
        crate::FormKind::Stable => 1,
    };
    // Saturating: a `total_bits` near `u32::MAX` (no table has one) needs more than any
    // accumulator holds, so the answer is `None`, not a wrapped sum.
    let needed = total_bits.saturating_add(extra);
    if needed > acc_value_bits {
        return None;
    }
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "total_bits + extra <= acc_value_bits (checked above)"
    )]
    let f = (acc_value_bits - needed) / 2;
    Some(if f > MAX_FRAC_BITS { MAX_FRAC_BITS } else { f })
}

/// Refuses a lookup whose accumulator needs more than `available` value bits.
pub const fn check_acc(needed: u32, available: u32) -> Result<(), Error> {
    if needed > available {
        Err(Error::TooWide {
            what: Quantity::LookupAccumulator,
            bits_needed: needed,
            bits_available: available,
        })
    } else {
        Ok(())
    }
}

/// The unsigned operand widths of one kind of multiply in a lookup, for sizing hardware
/// multipliers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MulShape {
    /// Bits of the data operand (a table difference, a strip sum or a texel).
    pub data_bits: u32,
    /// Bits of the fraction operand: `F + 1` for one fraction (it may equal `2^F` at the right or
    /// bottom edge of the table), `2F + 1` for a product of two.
    pub frac_bits: u32,
}

impl MulShape {
    /// Whether this multiply fits a signed `p x q` hardware multiplier (e.g. an FPGA DSP block,
    /// 18 x 18 or 18 x 25): unsigned operands need one extra bit each, in either orientation.
    pub const fn fits_signed(&self, p: u32, q: u32) -> bool {
        let (a, b) = (
            self.data_bits.saturating_add(1),
            self.frac_bits.saturating_add(1),
        );
        (a <= p && b <= q) || (a <= q && b <= p)
    }
}

/// The multiplies of [`crate::Paper`] for a `w x h` table of `b`-bit texels at `F` bits:
/// the first lerps multiply a column strip `S(i+1, j) - S(i, j) <= m h` by `A`; the second lerp
/// multiplies `r1 - r0 = 2^F (row strip) + A t <= m w 2^F` by `B`. Both grow with the *table*.
#[allow(
    clippy::as_conversions,
    reason = "usize has at most 64 bits (asserted at the top): lossless"
)]
pub const fn paper_multiplies(
    texel_bits: u32,
    width: usize,
    height: usize,
    frac_bits: u32,
) -> [MulShape; 2] {
    let m = max_texel_u64(texel_bits);
    [
        MulShape {
            data_bits: bits_of_product(m, height as u64, 1),
            frac_bits: frac_bits.saturating_add(1),
        },
        MulShape {
            data_bits: bits_of_product(m, width as u64, 1).saturating_add(frac_bits),
            frac_bits: frac_bits.saturating_add(1),
        },
    ]
}

/// The multiplies of [`crate::Stable`] for boxes of at most `max_side` texels per side: edge
/// strips `<= m (max_side + 1)` times one fraction, corner texels (`b` bits) times a product of
/// two fractions, and the fraction products themselves. All bounded by the *box*.
#[allow(
    clippy::as_conversions,
    reason = "usize has at most 64 bits (asserted at the top): lossless"
)]
pub const fn stable_multiplies(texel_bits: u32, max_side: usize, frac_bits: u32) -> [MulShape; 3] {
    let f1 = frac_bits.saturating_add(1);
    [
        MulShape {
            data_bits: bits_of_product(
                max_texel_u64(texel_bits),
                (max_side as u64).saturating_add(1),
                1,
            ),
            frac_bits: f1,
        },
        MulShape {
            data_bits: texel_bits,
            frac_bits: frac_bits.saturating_mul(2).saturating_add(1),
        },
        MulShape {
            data_bits: f1,
            frac_bits: f1,
        },
    ]
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
    use super::*;

    #[test]
    fn crow_example_4104() {
        assert!(check_entry_worst_case(8, 4104, 4104, 32).is_ok());
        assert_eq!(
            check_entry_worst_case(8, 4105, 4105, 32),
            Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: 33,
                bits_available: 32
            })
        );
        assert_eq!(entry_bits_naive(8, 4104, 4104), 33);
    }

    #[test]
    fn multiplier_shapes() {
        // 8-bit texels, F = 8: Paper at 256 x 256 needs a 24 x 9 multiply (fits 18 x 25 signed),
        // at 1024 x 1024 a 26 x 9 one (does not); Stable for boxes up to 255 texels fits 18 x 18.
        let p256 = paper_multiplies(8, 256, 256, 8);
        assert_eq!(
            p256[1],
            MulShape {
                data_bits: 24,
                frac_bits: 9
            }
        );
        assert!(p256.iter().all(|m| m.fits_signed(18, 25)));
        let p1024 = paper_multiplies(8, 1024, 1024, 8);
        assert_eq!(p1024[1].data_bits, 26);
        assert!(!p1024[1].fits_signed(18, 25));
        let s = stable_multiplies(8, 255, 8);
        assert!(s.iter().all(|m| m.fits_signed(18, 18)), "{s:?}");
    }

    #[test]
    fn crow_28_bits_at_1024() {
        // Crow §3.0: "a 1024 by 1024 entry table could require entries as long as 28 bits".
        assert_eq!(entry_bits_worst_case(8, 1024, 1024), 28);
        // "as little as 24 bits per entry by restricting texture images to 256 by 256".
        assert_eq!(entry_bits_worst_case(8, 256, 256), 24);
    }

    #[test]
    fn frac_bit_limits_per_entry_word() {
        use crate::FormKind::{Paper, Stable};
        // Full tables: u16 in i32, u32 in i64, u64 in i128.
        assert_eq!(max_frac_bits(Paper, 16, acc_value_bits(16)), Some(7));
        assert_eq!(max_frac_bits(Stable, 16, acc_value_bits(16)), Some(7));
        assert_eq!(max_frac_bits(Paper, 32, acc_value_bits(32)), Some(15));
        assert_eq!(max_frac_bits(Stable, 32, acc_value_bits(32)), Some(15));
        assert_eq!(
            max_frac_bits(Stable, 64, acc_value_bits(64)),
            Some(MAX_FRAC_BITS)
        );
        // Crow's 28-bit table of 1024^2 8-bit texels in u32: F <= 17 (Paper), 17 (Stable).
        assert_eq!(max_frac_bits(Paper, 28, 63), Some(17));
        assert_eq!(max_frac_bits(Stable, 28, 63), Some(17));
        assert_eq!(max_frac_bits(Stable, 31, 31), None);
        // Consistent with the checks the lookups make.
        for total in 0..=64u32 {
            for acc in [31u32, 63, 127] {
                for (form, bits) in [
                    (Paper, paper_acc_bits as fn(u32, u32) -> u32),
                    (Stable, stable_acc_bits),
                ] {
                    match max_frac_bits(form, total, acc) {
                        None => assert!(bits(total, 0) > acc),
                        Some(f) => {
                            assert!(bits(total, f) <= acc);
                            assert!(f == MAX_FRAC_BITS || bits(total, f + 1) > acc);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn absurd_inputs_do_not_overflow() {
        // Regression (fuzz finding, width.rs:120, 134, 165, 182, 198): unchecked additions and
        // 128-bit products overflowed for absurd bit counts and sizes.
        assert_eq!(paper_acc_bits(u32::MAX, u32::MAX), u32::MAX);
        assert_eq!(stable_acc_bits(u32::MAX - 1, 1), u32::MAX);
        let p = paper_multiplies(200, usize::MAX, usize::MAX, u32::MAX);
        assert_eq!(p[0].data_bits, 128);
        assert_eq!(p[1].frac_bits, u32::MAX);
        let s = stable_multiplies(200, usize::MAX, u32::MAX);
        assert!(!s[0].fits_signed(18, 25));
        assert_eq!(entry_bits_naive(u32::MAX, usize::MAX, usize::MAX), u32::MAX);
    }

    #[test]
    fn bits_of_product_n_matches_u128_and_bits_of_product() {
        let vals = [
            0u64,
            1,
            2,
            3,
            255,
            65_535,
            (1 << 32) - 1,
            1 << 32,
            (1 << 32) + 1,
            0xDEAD_BEEF_1234_5678,
            u64::MAX - 2,
            u64::MAX,
        ];
        for &a in &vals {
            for &b in &vals {
                let want2 = bits_of(u128::from(a) * u128::from(b));
                assert_eq!(bits_of_product_n(&[a, b]), Some(want2), "{a} {b}");
                for &c in &vals {
                    let want = bits_of_product(a, b, c);
                    assert_eq!(bits_of_product_n(&[a, b, c]), Some(want), "{a} {b} {c}");
                    // Five and six factors: exact where the product fits u128, else past 128
                    // bits (the sum of the factors' bits bounds it from above, minus the factor
                    // count from below).
                    let five = [a, b, c, b, a];
                    let got = bits_of_product_n(&five).unwrap();
                    let exact = five
                        .iter()
                        .try_fold(1u128, |p, &v| p.checked_mul(u128::from(v)));
                    match exact {
                        Some(p) => assert_eq!(got, bits_of(p), "{five:?}"),
                        None => {
                            let hi: u32 = five.iter().map(|&v| bits_of_u64(v)).sum();
                            assert!(got > 128 && got <= hi && got + 5 > hi, "{five:?} {got}");
                        }
                    }
                }
            }
        }
        assert_eq!(bits_of_product_n(&[]), Some(1));
        assert_eq!(bits_of_product_n(&[u64::MAX; 6]), Some(384));
        assert_eq!(bits_of_product_n(&[1 << 63; 6]), Some(379));
        assert_eq!(bits_of_product_n(&[1; 7]), None);
    }

    #[test]
    fn bits_of_product_matches_u128() {
        let vals = [
            0u64,
            1,
            2,
            3,
            255,
            65535,
            4104,
            1 << 31,
            (1 << 31) - 1,
            u32::MAX as u64,
            1 << 40,
            u64::MAX,
        ];
        for &a in &vals {
            for &b in &vals {
                for &c in &vals {
                    let want = (a as u128)
                        .checked_mul(b as u128)
                        .and_then(|v| v.checked_mul(c as u128));
                    let got = bits_of_product(a, b, c);
                    match want {
                        Some(v) => assert_eq!(got, bits_of(v), "{a} {b} {c}"),
                        None => assert!(got > 128, "{a} {b} {c}: {got}"),
                    }
                }
            }
        }
        assert_eq!(bits_of_product(u64::MAX, u64::MAX, u64::MAX), 192);
    }

    #[test]
    fn bits_and_logs() {
        assert_eq!(bits_of(0), 0);
        assert_eq!(bits_of(1), 1);
        assert_eq!(bits_of(255), 8);
        assert_eq!(bits_of(256), 9);
        assert_eq!(ceil_log2(1), 0);
        assert_eq!(ceil_log2(2), 1);
        assert_eq!(ceil_log2(3), 2);
        assert_eq!(ceil_log2(4), 2);
    }

    #[test]
    fn naive_never_below_exact() {
        for b in [1u32, 8, 16] {
            for w in 1..70usize {
                for h in [1usize, 2, 3, 7, 64, 65, 1000] {
                    let exact = entry_bits_worst_case(b, w, h);
                    let naive = entry_bits_naive(b, w, h);
                    assert!(naive >= exact && naive <= exact + 1, "{b} {w} {h}");
                }
            }
        }
    }
}
