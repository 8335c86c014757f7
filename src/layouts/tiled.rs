//! Exact tiled layouts: tiles within tiles, every field packed at its exact width.
//!
//! ## The decomposition
//! Per axis, choose block sizes `1 = b_0 < b_1 < ... < b_L`, each a multiple of the one before
//! (one level of `t`-texel tiles: `b_1 = t`). Write a corner coordinate `x` in that mixed radix,
//! `x = sum_p d_p b_p`, and let `trunc_p(x) = sum_{k >= p} d_k b_k` (x rounded down to a multiple
//! of `b_p`). The prefix `[0, x)` splits into the intervals `I_p(x) = [trunc_{p+1}(x), trunc_p(x))`
//! of length `d_p b_p`, and so
//!
//! `S(x, y) = sum_p sum_q  C_pq(trunc_p(x), trunc_q(y))`,  `C_pq(X, Y) = sum over I_p(X) x I_q(Y)`.
//!
//! `C_00` are the local sums inside a tile, `C_01`/`C_10` the edge strips (the sum above a tile
//! for each of its columns, left of it for each of its rows), `C_11` the tile corners; with more
//! levels the strips and corners are themselves split the same way. Only positions whose digit
//! `d_p` is non-zero are stored (a zero digit means an empty interval): a `t x t` tile stores
//! `(t-1)^2` local sums, `t - 1` strip values per side and one corner. Each component is an
//! array of fields of exactly `bits_of(m * len_p * len_q)` bits (`len` the longest interval,
//! `m` the largest texel), packed back to back in 32-bit words.
//!
//! ## Storage order
//! The components follow each other in the order `(0, 0), (0, 1), ..., (1, 0), ...` (x level
//! `p` major). Inside component `(p, q)`, with `cx` and `cy` stored positions per axis, the
//! entries are stored **row by row**: entry `(ix, iy)` (the `ix`-th stored `X`, the `iy`-th
//! stored `Y`) starts at bit `offset + (iy cx + ix) C bits`, its `C` channels side by side. So
//! texture row `y`, which finishes exactly row `iy` of the components `(., q)` of its lowest
//! non-zero digit `q`, is written as one stream of fields per component ([`TiledBuilder`]), and
//! the lookups find the two local sums of neighbouring columns side by side (one read when
//! both fit 32 bits).
//!
//! Reading `S(x, y)` costs one field per pair of non-zero digits: at most `(Lx + 1)(Ly + 1)`
//! fields (4 for one level of tiles), each 1 to 3 words, and one addition per field after the
//! first. With no levels (`AxisLevels::FLAT`) the layout is the flat table packed at its exact
//! width.
//!
//! Crow's §3.0 sketch stores only `C_00` and a corner per region, which loses the edge strips;
//! see `docs/layouts.md` and the `CrowLiteral` test in host-tests.
//!
//! ## Sizes, digits, safety
//! Every size and bit offset is computed once, in `u64` with checks, when the layout is made
//! ([`Tiled::words_needed`] is a `const fn`); a layout whose size overflows `u64` bits or the
//! target's `usize` words is refused with [`Error::TextureTooLarge`], so on a 32-bit target
//! exactly as on a 64-bit one no storage that is too short is accepted. The digits of a corner
//! are shifts and masks when every block is a power of two times the one before (8 x 8 tiles,
//! 2 in 16, ...), divisions by non-zero radices otherwise. Reads go through `get`: a corrupted
//! layout (from [`Tiled::from_words`]) gives wrong sums, never a panic.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use core::num::NonZeroU32;
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
use core::ops::Range;

use super::packed::{
    bits_of_mul, check_dimensions, mask, pack_fields, read2_32, read_masked, read_masked32,
    word_shift, words_of_bits, USIZE_MAX64, WORD_BITS,
};
use super::Layout;
use crate::cost::{per_channel, Counter, Region};
use crate::error::{Error, Quantity};
use crate::texel::{Entry, Texel};
use crate::texture::Texture;
use crate::width;

/// The most block levels per axis.
pub const MAX_LEVELS: usize = 4;

/// The block sizes of one axis (ascending, each a multiple of the previous, all at least 2);
/// `b_0 = 1` is implied.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AxisLevels {
    blocks: [u32; MAX_LEVELS],
    len: usize,
}

impl AxisLevels {
    /// No levels: the axis of a flat table.
    pub const FLAT: AxisLevels = AxisLevels {
        blocks: [0; MAX_LEVELS],
        len: 0,
    };

    /// Block sizes `b_1 < b_2 < ...`, each a multiple of the one before, at least 2.
    #[allow(
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects,
        reason = "const fn (no iterators): i < blocks.len() and i < MAX_LEVELS (the loop \
                  condition) for both indexings and the increment"
    )]
    pub const fn new(blocks: &[u32]) -> Result<Self, Error> {
        if blocks.len() > MAX_LEVELS {
            return Err(Error::InvalidLevels);
        }
        let mut out = [0u32; MAX_LEVELS];
        let mut prev = 1u32;
        let mut i = 0;
        while i < blocks.len() && i < MAX_LEVELS {
            let b = blocks[i];
            if b < 2 || b <= prev || !b.is_multiple_of(prev) {
                return Err(Error::InvalidLevels);
            }
            out[i] = b;
            prev = b;
            i += 1;
        }
        Ok(AxisLevels {
            blocks: out,
            len: blocks.len(),
        })
    }

    /// The block sizes.
    pub fn blocks(&self) -> &[u32] {
        self.blocks.get(..self.len).unwrap_or(&[])
    }

    /// Number of components along this axis: levels + 1.
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "len <= MAX_LEVELS (AxisLevels::new, FLAT)"
    )]
    pub const fn components(&self) -> usize {
        self.len + 1
    }
}

/// The levels of both axes, and an optional modulus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TiledSpec {
    /// Levels along x.
    pub x: AxisLevels,
    /// Levels along y.
    pub y: AxisLevels,
    /// `Some(k)`: every field is stored modulo `2^k` and capped at `k` bits (the tiled and
    /// modular layouts combined: exact for boxes whose sums stay below `2^k`, see
    /// [`super::Modular`]); `None`: exact for every box.
    pub modulus: Option<u32>,
}

impl TiledSpec {
    /// One level of `tw x th` tiles (local sums, edge strips, corners).
    pub const fn tiles(tw: u32, th: u32) -> Result<Self, Error> {
        let x = match AxisLevels::new(&[tw]) {
            Ok(v) => v,
            Err(e) => return Err(e),
        };
        let y = match AxisLevels::new(&[th]) {
            Ok(v) => v,
            Err(e) => return Err(e),
        };
        Ok(TiledSpec {
            x,
            y,
            modulus: None,
        })
    }

    /// The same block sizes on both axes.
    pub const fn square(blocks: &[u32]) -> Result<Self, Error> {
        match AxisLevels::new(blocks) {
            Ok(a) => Ok(TiledSpec {
                x: a,
                y: a,
                modulus: None,
            }),
            Err(e) => Err(e),
        }
    }

    /// No levels: the flat table packed at its exact width.
    pub const FLAT_PACKED: TiledSpec = TiledSpec {
        x: AxisLevels::FLAT,
        y: AxisLevels::FLAT,
        modulus: None,
    };

    /// The same levels with every field stored modulo `2^k` (at most `k` bits).
    pub const fn with_modulus(self, k: u32) -> Self {
        TiledSpec {
            modulus: Some(k),
            ..self
        }
    }
}

/// Components per axis, at most.
const N: usize = MAX_LEVELS + 1;

const ONE: NonZeroU32 = NonZeroU32::MIN;

/// `a / b` by a divisor the type proves non-zero (`checked_div` so that it is a `const fn`; the
/// `None` arm is unreachable).
const fn div(a: u64, b: NonZeroU32) -> u64 {
    #[allow(
        clippy::as_conversions,
        reason = "u32 -> u64 is lossless; u64::from is not const"
    )]
    let b = b.get() as u64;
    match a.checked_div(b) {
        Some(q) => q,
        None => 0,
    }
}

/// The mixed-radix digits of one coordinate: per component `p`, the digit `d_p` and the index
/// of the stored position `trunc_p(x)` among those of component `p` (meaningful when
/// `d_p != 0`). Entries past the axis's components are 0.
#[derive(Debug, Clone, Copy)]
pub(super) struct Digits {
    pub(super) digit: [u32; N],
    pub(super) index: [u32; N],
}

/// One axis of a geometry, precomputed for the lookups: the block sizes and the radices
/// `r_p = b_{p+1} / b_p` as non-zero divisors and, when every radix is a power of two (8 x 8
/// tiles, 2 in 16, ...), as shifts and masks.
///
/// With `q_0 = x` and `q_{p+1} = floor(q_p / r_p)` (so `q_p = floor(x / b_p)`), the digit is
/// `d_p = q_p - q_{p+1} r_p` (`q_L` for the top component) and the index of `trunc_p(x)` is
/// `q_{p+1} (r_p - 1) + d_p - 1` (`q_L - 1` at the top): every one of the `q_{p+1}` whole
/// blocks of `b_{p+1}` before it holds `r_p - 1` stored positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Axis {
    /// Levels `L`; components `L + 1`.
    levels: usize,
    /// `b_0 = 1, b_1, ..., b_L` (1 past `L`).
    block: [NonZeroU32; N],
    /// `r_p` for `p < L` (1 past).
    radix: [NonZeroU32; MAX_LEVELS],
    /// `log2 r_p` when `pow2`.
    shift: [u32; MAX_LEVELS],
    /// `r_p - 1`.
    low: [u32; MAX_LEVELS],
    /// Every radix is a power of two: the digits are shifts and masks.
    pow2: bool,
}

impl Axis {
    /// The axis of `levels` (whose blocks `AxisLevels::new` has checked; a block that would break
    /// the checks ends the levels there, so the divisors are non-zero whatever the input).
    #[allow(
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "const fn (no iterators): p < MAX_LEVELS (loop condition), so p and p + 1 < N index \
                  in bounds and p += 1 stays small; r >= 1 (NonZeroU32): r - 1 does not wrap; the \
                  quotient b / prev <= b fits u32 and u32 -> u64 is lossless"
    )]
    pub(super) const fn new(levels: &AxisLevels) -> Axis {
        let mut a = Axis {
            levels: 0,
            block: [ONE; N],
            radix: [ONE; MAX_LEVELS],
            shift: [0; MAX_LEVELS],
            low: [0; MAX_LEVELS],
            pow2: true,
        };
        let mut prev = ONE;
        let mut p = 0;
        while p < MAX_LEVELS && p < levels.len {
            let b = levels.blocks[p];
            let Some(bn) = NonZeroU32::new(b) else {
                break;
            };
            if b <= prev.get() || !b.is_multiple_of(prev.get()) {
                break;
            }
            let Some(r) = NonZeroU32::new(div(b as u64, prev) as u32) else {
                break;
            };
            a.block[p + 1] = bn;
            a.radix[p] = r;
            a.low[p] = r.get() - 1;
            if r.is_power_of_two() {
                a.shift[p] = r.trailing_zeros();
            } else {
                a.pow2 = false;
            }
            prev = bn;
            p += 1;
            a.levels = p;
        }
        a
    }

    /// The same axis with the power-of-two shortcut off: the digits by division (tests).
    #[cfg(test)]
    pub(super) fn by_division(mut self) -> Axis {
        self.pow2 = false;
        self
    }

    /// Whether the digits are shifts and masks.
    #[cfg(test)]
    pub(super) fn is_pow2(&self) -> bool {
        self.pow2
    }

    /// Components: levels + 1.
    #[inline(always)]
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "levels <= MAX_LEVELS (Axis::new)"
    )]
    pub(super) const fn components(&self) -> usize {
        self.levels + 1
    }

    /// The digits and indices of `x` (see [`Axis`]).
    #[inline(always)]
    pub(super) fn digits(&self, x: u32) -> Digits {
        let mut out = Digits {
            digit: [0; N],
            index: [0; N],
        };
        let mut q = x;
        let levels = self
            .radix
            .iter()
            .zip(self.shift.iter().zip(self.low.iter()))
            .zip(out.digit.iter_mut().zip(out.index.iter_mut()))
            .take(self.levels);
        if self.pow2 {
            for ((_, (&s, &low)), (d, i)) in levels {
                let next = q.wrapping_shr(s);
                *d = q & low;
                *i = next.wrapping_mul(low).wrapping_add(*d).wrapping_sub(1);
                q = next;
            }
        } else {
            for ((&r, (_, &low)), (d, i)) in levels {
                let next = q / r;
                *d = q.wrapping_sub(next.wrapping_mul(r.get()));
                *i = next.wrapping_mul(low).wrapping_add(*d).wrapping_sub(1);
                q = next;
            }
        }
        if let Some(d) = out.digit.get_mut(self.levels) {
            *d = q;
        }
        if let Some(i) = out.index.get_mut(self.levels) {
            *i = q.wrapping_sub(1);
        }
        out
    }

    /// One level of the digits: for `q = floor(x / b_p)`, the digit `d_p`, the index of
    /// `trunc_p(x)` (meaningful when `d_p != 0`) and `floor(x / b_{p+1})`; `None` past the top
    /// component.
    #[inline(always)]
    #[allow(
        clippy::indexing_slicing,
        reason = "p < MAX_LEVELS is checked first (the compiler elides the bounds checks)"
    )]
    pub(super) fn step(&self, p: usize, q: u32) -> Option<(u32, u32, u32)> {
        if p < self.levels && p < MAX_LEVELS {
            let low = self.low[p];
            let (d, next) = if self.pow2 {
                (q & low, q.wrapping_shr(self.shift[p]))
            } else {
                let next = q / self.radix[p];
                (q.wrapping_sub(next.wrapping_mul(self.radix[p].get())), next)
            };
            Some((
                d,
                next.wrapping_mul(low).wrapping_add(d).wrapping_sub(1),
                next,
            ))
        } else if p == self.levels {
            Some((q, q.wrapping_sub(1), 0))
        } else {
            None
        }
    }

    /// The component of the lowest non-zero digit of `x >= 1` and the index of `x` among its
    /// stored positions: the row step's `(q, iy)` ([`Axis::step`] from level 0 up, stopping
    /// there: one step for most rows of power-of-two tiles, instead of all of [`Axis::digits`]).
    /// `None` for `x = 0`.
    #[inline(always)]
    pub(super) fn lowest(&self, x: u32) -> Option<(usize, u32)> {
        let mut q = x;
        for p in 0..N {
            let (d, index, next) = self.step(p, q)?;
            if d != 0 {
                return Some((p, index));
            }
            q = next;
        }
        None
    }

    /// Stored positions of component `p` on an axis of `n` texels: the `X` in `1..=n` that are
    /// multiples of `b_p` with a non-zero digit `d_p`.
    #[allow(
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "const fn: p < N, and p + 1 < N where p < MAX_LEVELS (checked); u32 -> u64 is \
                  lossless; r >= 1; whole = n / b_{p+1}, so whole b_{p+1} <= n and \
                  whole (r - 1) <= n: nothing wraps"
    )]
    const fn count(&self, p: usize, n: u64) -> u64 {
        if p >= N {
            return 0;
        }
        let b = self.block[p];
        if p < self.levels && p < MAX_LEVELS {
            let nb = self.block[p + 1];
            let r = self.radix[p].get() as u64;
            let whole = div(n, nb);
            whole * (r - 1) + div(n - whole * nb.get() as u64, b)
        } else {
            div(n, b)
        }
    }

    /// The longest interval `d_p b_p` of component `p` on an axis of `n` texels.
    #[allow(
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "const fn: p < N, and p + 1 < N where p < MAX_LEVELS (checked); u32 -> u64 is \
                  lossless; b_{p+1} > b_p (Axis::new); floor(n / b_p) b_p <= n"
    )]
    const fn max_len(&self, p: usize, n: u64) -> u64 {
        if p >= N {
            return 0;
        }
        let b = self.block[p].get() as u64;
        if p < self.levels && p < MAX_LEVELS {
            let nb = self.block[p + 1].get() as u64;
            if n >= nb {
                return nb - b;
            }
        }
        div(n, self.block[p]) * b
    }

    /// `b_p` (1 past the levels).
    #[inline(always)]
    fn block(&self, p: usize) -> u32 {
        self.block.get(p).map_or(1, |b| b.get())
    }
}

/// Where component `(p, q)` lives and how wide its fields are. Entry `(ix, iy)` channel `c`
/// starts at bit `offset_bits + iy row_bits + ix stride_bits + c bits`: the entries are stored
/// row by row (all `ix` of one `iy`, then the next `iy`), so the builder, which finishes one
/// `iy` of one y component per texture row, writes each component row as one stream of fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Component {
    pub(super) offset_bits: u64,
    /// Bits of one row of entries (`count_x` entries): `count_x * stride_bits`.
    pub(super) row_bits: u64,
    /// Bits of one entry, all channels: `bits * C`.
    pub(super) stride_bits: u64,
    /// Bits per field.
    pub(super) bits: u32,
    /// The low `bits` bits set.
    pub(super) mask: u64,
}

impl Component {
    const ZERO: Component = Component {
        offset_bits: 0,
        row_bits: 0,
        stride_bits: 0,
        bits: 0,
        mask: 0,
    };

    /// Bit offset of entry `(ix, iy)` (channel 0). For the stored positions of a geometry
    /// (`ix < count_x`, `iy < count_y`) it is below the geometry's `total_bits`, which
    /// [`Geometry::new`] computed with checks: no wrap.
    #[inline(always)]
    pub(super) fn offset(&self, ix: u32, iy: u32) -> u64 {
        self.offset_bits
            .wrapping_add(u64::from(iy).wrapping_mul(self.row_bits))
            .wrapping_add(u64::from(ix).wrapping_mul(self.stride_bits))
    }
}

/// A component of a [`OneLevel`] geometry in 32-bit words (every offset below `2^32`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Comp32 {
    offset: u32,
    row: u32,
    stride: u32,
    bits: u32,
    mask: u32,
    /// The low `2 stride` bits set when two entries side by side (`ix`, `ix + 1`) fit one
    /// 32-bit read (`2 stride <= 32`: 14-bit local sums of 8 x 8 tiles of 8-bit texels), else 0.
    pair_mask: u32,
}

impl Comp32 {
    const ZERO: Comp32 = Comp32 {
        offset: 0,
        row: 0,
        stride: 0,
        bits: 0,
        mask: 0,
        pair_mask: 0,
    };
}

/// One level of power-of-two tiles on both axes, offsets below `2^32` and fields of at most
/// 32 bits (8 x 8 tiles on any texture a microcontroller holds): the digits are a shift and a
/// mask, every offset two multiply-adds. Precomputed once by [`Geometry::new_for`], so a lookup
/// reads 36 bytes of it instead of walking the general geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct OneLevel {
    shift_x: u32,
    low_x: u32,
    shift_y: u32,
    low_y: u32,
    /// Components `(0, 0)` (local sums), `(0, 1)` (strips above the tile, per column), `(1,
    /// 0)` (strips left of it, per row), `(1, 1)` (tile corners).
    comps: [Comp32; 4],
}

/// One coordinate under a [`OneLevel`] geometry: the digit `d` (position inside the tile),
/// `q` (whole tiles before it) and the index of `trunc_0(x)` (`q (t - 1) + d - 1`, meaningful
/// when `d != 0`); the tile-level index is `q - 1` (meaningful when `q != 0`).
#[derive(Clone, Copy)]
struct OneDigits {
    d: u32,
    q: u32,
    i0: u32,
}

impl OneLevel {
    /// Whether columns `i` and `i + 1` lie inside one tile off its left edge (digit `d` of `i`
    /// in `1..=t - 2`): `d - 1 < t - 2` (`d = 0` wraps to the largest value), one comparison.
    #[inline(always)]
    fn inside_x(&self, i: u32) -> bool {
        (i & self.low_x).wrapping_sub(1) < self.low_x.wrapping_sub(1)
    }

    /// [`OneLevel::inside_x`] for rows.
    #[inline(always)]
    fn inside_y(&self, j: u32) -> bool {
        (j & self.low_y).wrapping_sub(1) < self.low_y.wrapping_sub(1)
    }

    #[inline(always)]
    fn digits(shift: u32, low: u32, x: u32) -> OneDigits {
        let (d, q) = (x & low, x >> (shift & 31));
        OneDigits {
            d,
            q,
            i0: q.wrapping_mul(low).wrapping_add(d).wrapping_sub(1),
        }
    }
}

/// One column's (or row's) part of the bit offsets of a cell's fields under a [`OneLevel`]
/// geometry, so that each offset is one addition `x.pNN + y.pNN`: for a column, `ix stride` of
/// each component (`ix` the column's index there: `i0` for the local sums and the strips
/// above, `q - 1` for the strips left and the tile corners); for a row, the component's offset
/// plus `iy row`. `q`: the whole tiles before it (where 0, the parts with `q - 1` are unused).
/// Formed once per column and per row of a 16-read lookup (two of each for four cells).
#[derive(Clone, Copy)]
pub(super) struct CellParts {
    p00: u32,
    p01: u32,
    p10: u32,
    p11: u32,
    /// Whole tiles before the column (row): non-zero when a tile lies left of (above) it.
    q: u32,
}

impl CellParts {
    /// The parts of column `i`.
    #[inline(always)]
    fn x(o: &OneLevel, i: u32) -> CellParts {
        let d = OneLevel::digits(o.shift_x, o.low_x, i);
        let t = d.q.wrapping_sub(1);
        let [c00, c01, c10, c11] = &o.comps;
        CellParts {
            p00: d.i0.wrapping_mul(c00.stride),
            p01: d.i0.wrapping_mul(c01.stride),
            p10: t.wrapping_mul(c10.stride),
            p11: t.wrapping_mul(c11.stride),
            q: d.q,
        }
    }

    /// The parts of row `j`, the components' offsets included.
    #[inline(always)]
    fn y(o: &OneLevel, j: u32) -> CellParts {
        let d = OneLevel::digits(o.shift_y, o.low_y, j);
        let t = d.q.wrapping_sub(1);
        let [c00, c01, c10, c11] = &o.comps;
        CellParts {
            p00: c00.offset.wrapping_add(d.i0.wrapping_mul(c00.row)),
            p01: c01.offset.wrapping_add(t.wrapping_mul(c01.row)),
            p10: c10.offset.wrapping_add(d.i0.wrapping_mul(c10.row)),
            p11: c11.offset.wrapping_add(t.wrapping_mul(c11.row)),
            q: d.q,
        }
    }
}

/// Counts one read of the entry at bit `at` of `c` (all channels): the read, where it is, and
/// the 32-bit words it touches.
#[inline(always)]
fn count_field<K: Counter>(c: &Comp32, at: u32, k: &mut K) {
    k.reads(1, c.stride);
    k.read_at(Region::Table, u64::from(at), c.stride);
    k.words(
        (at % WORD_BITS)
            .saturating_add(c.stride)
            .div_ceil(WORD_BITS),
    );
}

/// [`Tiled::words_needed`] with the channels as a value.
pub(super) const fn words_for_channels(
    spec: TiledSpec,
    width: usize,
    height: usize,
    texel_bits: u32,
    channels: usize,
) -> Result<usize, Error> {
    match Geometry::new(spec, width, height, texel_bits, channels) {
        Ok(g) => Ok(g.words),
        Err(e) => Err(e),
    }
}

/// The computed geometry of a tiled layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Geometry {
    pub(super) spec: TiledSpec,
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) texel_bits: u32,
    pub(super) channels: usize,
    pub(super) ax: Axis,
    pub(super) ay: Axis,
    pub(super) comps: [[Component; N]; N],
    /// Bits of storage, checked in `u64`.
    pub(super) total_bits: u64,
    /// `ceil(total_bits / 32)`, checked to fit `usize`.
    pub(super) words: usize,
    /// Bits of the largest value `S` can take: `k` for a modular spec, else the worst-case
    /// total (computed once here: the lookups' width check reads it per call).
    pub(super) value_bits: u32,
    /// Every bit offset is below `2^32` and every field at most 32 bits wide: the lookups
    /// compute offsets in 32-bit words and read each field from at most two words (decided
    /// once here, not per field).
    pub(super) fields32: bool,
    /// The straight-line path's constants when the spec is one level of power-of-two tiles
    /// and `fields32` holds.
    pub(super) one_level: Option<OneLevel>,
}

impl Geometry {
    /// The geometry on this target (`usize` words).
    pub(super) const fn new(
        spec: TiledSpec,
        width: usize,
        height: usize,
        texel_bits: u32,
        channels: usize,
    ) -> Result<Self, Error> {
        Self::new_for(spec, width, height, texel_bits, channels, USIZE_MAX64)
    }

    /// The geometry, with every size and offset computed in `u64` with checks, and the word
    /// count refused above `max_words` (this target's `usize::MAX`; tests pass `u32::MAX` to
    /// check a 32-bit target's arithmetic on any host). Overflow anywhere is
    /// [`Error::TextureTooLarge`]: no storage could hold the layout.
    #[allow(
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "const fn (no iterators, no From): p, q < N and i < 4 (loop conditions; i / 2 and \
                  i % 2 < 2) index in bounds and the increments stay small; usize -> u64 is lossless \
                  (usize::BITS <= 64) and so is bits <= 64 -> u64; lx, ly <= max side < 2^31, so \
                  lx ly < 2^62; the u32 casts of offsets, rows, strides and masks happen only when \
                  fields32 holds, i.e. every offset <= total_bits <= u32::MAX and every field <= 32 bits"
    )]
    pub(super) const fn new_for(
        spec: TiledSpec,
        width: usize,
        height: usize,
        texel_bits: u32,
        channels: usize,
        max_words: u64,
    ) -> Result<Self, Error> {
        if let Err(e) = check_dimensions(width, height, channels) {
            return Err(e);
        }
        if let Err(e) = width::check_texel_bits(texel_bits) {
            return Err(e);
        }
        if let Some(k) = spec.modulus {
            if k < texel_bits || k == 0 || k > 64 {
                return Err(Error::InvalidModulus { bits: k });
            }
        }
        let too_large = Error::TextureTooLarge {
            dimension: if width > height { width } else { height },
        };
        let (ax, ay) = (Axis::new(&spec.x), Axis::new(&spec.y));
        let m = mask(texel_bits);
        // `usize` has at most 64 bits, so `as u64` is lossless.
        let (w, h, ch) = (width as u64, height as u64, channels as u64);
        let mut comps = [[Component::ZERO; N]; N];
        let mut offset = 0u64;
        let mut p = 0;
        while p < N && p < ax.components() {
            let (cx, lx) = (ax.count(p, w), ax.max_len(p, w));
            let mut q = 0;
            while q < N && q < ay.components() {
                let (cy, ly) = (ay.count(q, h), ay.max_len(q, h));
                // Sides below 2^31: the area fits u64; m * area may not, hence bits_of_mul.
                let mut bits = bits_of_mul(m, lx * ly);
                if let Some(k) = spec.modulus {
                    if bits > k {
                        bits = k;
                    }
                }
                if bits > 64 {
                    return Err(Error::TooWide {
                        what: Quantity::Field,
                        bits_needed: bits,
                        bits_available: 64,
                    });
                }
                let Some(stride_bits) = (bits as u64).checked_mul(ch) else {
                    return Err(too_large);
                };
                let Some(row_bits) = stride_bits.checked_mul(cx) else {
                    return Err(too_large);
                };
                let Some(size) = row_bits.checked_mul(cy) else {
                    return Err(too_large);
                };
                comps[p][q] = Component {
                    offset_bits: offset,
                    row_bits,
                    stride_bits,
                    bits,
                    mask: mask(bits),
                };
                offset = match offset.checked_add(size) {
                    Some(v) => v,
                    None => return Err(too_large),
                };
                q += 1;
            }
            p += 1;
        }
        let Some(words) = words_of_bits(offset, max_words) else {
            return Err(too_large);
        };
        let mut fields32 = offset <= u32::MAX as u64;
        let mut p = 0;
        while p < N {
            let mut q = 0;
            while q < N {
                if comps[p][q].bits > 32 {
                    fields32 = false;
                }
                q += 1;
            }
            p += 1;
        }
        Ok(Geometry {
            spec,
            width,
            height,
            texel_bits,
            channels,
            ax,
            ay,
            comps,
            total_bits: offset,
            words,
            value_bits: match spec.modulus {
                Some(k) => k,
                None => width::entry_bits_worst_case(texel_bits, width, height),
            },
            fields32,
            one_level: if fields32 && ax.levels == 1 && ay.levels == 1 && ax.pow2 && ay.pow2 {
                let mut c = [Comp32::ZERO; 4];
                let mut i = 0;
                while i < 4 {
                    // fields32: every offset, row, stride and field fits 32 bits.
                    let comp = comps[i / 2][i % 2];
                    c[i] = Comp32 {
                        offset: comp.offset_bits as u32,
                        row: comp.row_bits as u32,
                        stride: comp.stride_bits as u32,
                        bits: comp.bits,
                        mask: comp.mask as u32,
                        pair_mask: if comp.stride_bits <= 16 {
                            mask(2 * comp.stride_bits as u32) as u32
                        } else {
                            0
                        },
                    };
                    i += 1;
                }
                Some(OneLevel {
                    shift_x: ax.shift[0],
                    low_x: ax.low[0],
                    shift_y: ay.shift[0],
                    low_y: ay.low[0],
                    comps: c,
                })
            } else {
                None
            },
        })
    }

    /// The value type must hold the worst-case total, or `k` bits for a modular spec.
    const fn check_value_type<E: Entry>(&self) -> Result<(), Error> {
        match self.spec.modulus {
            Some(k) if k <= E::BITS => Ok(()),
            Some(k) => Err(Error::InvalidModulus { bits: k }),
            None => {
                width::check_entry_worst_case(self.texel_bits, self.width, self.height, E::BITS)
            }
        }
    }

    /// Component `(p, q)`, if the spec has it.
    #[inline(always)]
    pub(super) fn component(&self, p: usize, q: usize) -> Option<&Component> {
        if p < self.ax.components() && q < self.ay.components() {
            self.comps.get(p).and_then(|row| row.get(q))
        } else {
            None
        }
    }

    /// Refuses storage shorter than the layout.
    fn check_storage(&self, got: usize) -> Result<(), Error> {
        if got < self.words {
            Err(Error::StorageTooSmall {
                needed: self.words,
                got,
            })
        } else {
            Ok(())
        }
    }
}

/// An exact tiled (or hierarchical, or packed flat) layout over borrowed 32-bit words.
///
/// `E` is the type corner values are summed in; it must hold the worst-case whole-texture sum.
#[derive(Debug, Clone, Copy)]
pub struct Tiled<'a, E: Entry, const C: usize = 1> {
    words: &'a [u32],
    geo: Geometry,
    _e: core::marker::PhantomData<E>,
}

impl<'a, E: Entry, const C: usize> Tiled<'a, E, C> {
    /// Words of storage a `w x h` texture of `texel_bits`-bit texels needs under `spec`.
    ///
    /// Every size and offset is computed in `u64` with checks; a layout whose size overflows
    /// `u64` bits or `usize` words (on a 32-bit target: more than `2^32 - 1` words) is refused
    /// with [`Error::TextureTooLarge`], as are sides above `2^31 - 1`. Also
    /// [`Error::EmptyTexture`], [`Error::InvalidTexelBits`], [`Error::InvalidModulus`] and
    /// `TooWide { what: Field, .. }` for a field above 64 bits.
    ///
    /// A `const fn`, so firmware can size a `static` at compile time:
    ///
    /// ```
    /// use texsat::layouts::{Tiled, TiledSpec};
    /// use texsat::{Layout, NoCount, Texture};
    /// const SPEC: TiledSpec = match TiledSpec::tiles(8, 8) {
    ///     Ok(s) => s,
    ///     Err(_) => panic!(),
    /// };
    /// const WORDS: usize = match Tiled::<u32>::words_needed(SPEC, 64, 48, 8) {
    ///     Ok(n) => n,
    ///     Err(_) => panic!(),
    /// };
    /// const SCRATCH: usize = match Tiled::<u32>::scratch_needed(SPEC, 64) {
    ///     Ok(n) => n,
    ///     Err(_) => panic!(),
    /// };
    /// static IMAGE: [u32; WORDS] = [0; WORDS]; // e.g. written by a host tool into flash
    ///
    /// let texels = [7u8; 64 * 48];
    /// let tex = Texture::<u8>::new(&texels, 64, 48)?;
    /// let mut words = [0u32; WORDS];
    /// let mut scratch = [0u32; SCRATCH];
    /// let t = Tiled::<u32>::build(&tex, SPEC, &mut words, &mut scratch)?;
    /// assert_eq!(t.corner(64, 48, &mut NoCount), [7 * 64 * 48]);
    /// let flash = Tiled::<u32>::from_words(&IMAGE, SPEC, 64, 48, 8)?;
    /// assert_eq!(flash.corner(64, 48, &mut NoCount), [0]);
    /// # Ok::<(), texsat::Error>(())
    /// ```
    pub const fn words_needed(
        spec: TiledSpec,
        width: usize,
        height: usize,
        texel_bits: u32,
    ) -> Result<usize, Error> {
        match Geometry::new(spec, width, height, texel_bits, C) {
            Ok(g) => Ok(g.words),
            Err(e) => Err(e),
        }
    }

    /// Scratch entries the builder needs: one accumulator row per y component plus one row for
    /// the current row's prefix sums, `(Ly + 2) (w + 1) C`; [`Error::TextureTooLarge`] if that
    /// overflows `usize`. A `const fn` (see [`Tiled::words_needed`]).
    pub const fn scratch_needed(spec: TiledSpec, width: usize) -> Result<usize, Error> {
        let too_large = Error::TextureTooLarge { dimension: width };
        let Some(w1) = width.checked_add(1) else {
            return Err(too_large);
        };
        let Some(row) = w1.checked_mul(C) else {
            return Err(too_large);
        };
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "components() <= MAX_LEVELS + 1"
        )]
        let rows = spec.y.components() + 1;
        match row.checked_mul(rows) {
            Some(n) => Ok(n),
            None => Err(too_large),
        }
    }

    /// Builds the layout of `texture` into `words` (see [`Tiled::words_needed`]) using `scratch`
    /// (see [`Tiled::scratch_needed`]); refuses, before writing, a texture whose worst-case
    /// total does not fit `E`. The same words as a [`TiledBuilder`] fed row by row; with
    /// `simd` it takes the band rows of each tile row in one step where they apply
    /// (`TiledBuilder::push_texture`), which a caller streaming rows cannot.
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        spec: TiledSpec,
        words: &'a mut [u32],
        scratch: &mut [E],
    ) -> Result<Self, Error> {
        let mut b = TiledBuilder::<E, C>::new(
            spec,
            texture.width(),
            texture.height(),
            T::BITS,
            words,
            scratch,
        )?;
        b.push_texture(texture)?;
        b.finish()
    }

    /// Wraps words written elsewhere (flash, an RTL dump) under `spec`. The content is not
    /// validated: a corrupted layout gives wrong sums (never a panic).
    pub fn from_words(
        words: &'a [u32],
        spec: TiledSpec,
        width: usize,
        height: usize,
        texel_bits: u32,
    ) -> Result<Self, Error> {
        let geo = Geometry::new(spec, width, height, texel_bits, C)?;
        geo.check_value_type::<E>()?;
        geo.check_storage(words.len())?;
        Ok(Tiled {
            words,
            geo,
            _e: core::marker::PhantomData,
        })
    }

    /// Adds the `C` fields of entry `(ix, iy)` of `comp` to `out`, counting the read.
    #[inline(always)]
    #[allow(
        clippy::as_conversions,
        reason = "the u32 casts are on the fields32 path only: there every offset (so every row \
                  and stride) is below 2^32 and every field at most 32 bits, so its mask too \
                  (Geometry::new_for): lossless"
    )]
    fn add_entry<K: Counter>(
        &self,
        comp: &Component,
        ix: u32,
        iy: u32,
        out: &mut [E; C],
        k: &mut K,
    ) {
        if self.geo.fields32 {
            // Every offset is below the total, so below 2^32: the offset in 32-bit arithmetic
            // (exact, the low words of the u64 geometry) and each field from at most two words
            // with 32-bit shifts. The common case on a microcontroller (tables below 512 MiB).
            let at = (comp.offset_bits as u32)
                .wrapping_add(iy.wrapping_mul(comp.row_bits as u32))
                .wrapping_add(ix.wrapping_mul(comp.stride_bits as u32));
            let read = comp.stride_bits as u32;
            k.reads(1, read);
            k.read_at(Region::Table, u64::from(at), read);
            k.words((at % WORD_BITS).saturating_add(read).div_ceil(WORD_BITS));
            let mut at = at;
            for o in out.iter_mut() {
                let v = read_masked32(self.words, at, comp.mask as u32);
                *o = o.wrapping_add(E::from_u64_truncating(u64::from(v)));
                at = at.wrapping_add(comp.bits);
            }
            return;
        }
        let offset = comp.offset(ix, iy);
        let read = u32::try_from(comp.stride_bits).unwrap_or(u32::MAX);
        k.reads(1, read);
        k.read_at(Region::Table, offset, read);
        k.words(word_shift(offset).saturating_add(read).div_ceil(WORD_BITS));
        let mut at = offset;
        for o in out.iter_mut() {
            let v = read_masked(self.words, at, comp.bits, comp.mask);
            // Sums of parts of S: no wrap on a valid layout (E holds the total).
            *o = o.wrapping_add(E::from_u64_truncating(v));
            at = at.wrapping_add(u64::from(comp.bits));
        }
    }

    /// The `C` fields of entry `(ix, iy)` of a [`OneLevel`] component, the read counted.
    #[inline(always)]
    fn field32<K: Counter>(&self, c: &Comp32, ix: u32, iy: u32, k: &mut K) -> [E; C] {
        let mut at = c
            .offset
            .wrapping_add(iy.wrapping_mul(c.row))
            .wrapping_add(ix.wrapping_mul(c.stride));
        count_field(c, at, k);
        let mut out = [E::ZERO; C];
        for o in out.iter_mut() {
            *o = E::from_u64_truncating(u64::from(read_masked32(self.words, at, c.mask)));
            at = at.wrapping_add(c.bits);
        }
        out
    }

    /// `S(x, y)` for `x <= w`, `y <= h` under a [`OneLevel`] geometry: one field per pair of
    /// non-zero digits (`x = 0` or `y = 0` reads nothing and gives 0).
    #[inline(always)]
    fn corner_fast<K: Counter>(&self, o: &OneLevel, x: u32, y: u32, k: &mut K) -> [E; C] {
        let dx = OneLevel::digits(o.shift_x, o.low_x, x);
        let dy = OneLevel::digits(o.shift_y, o.low_y, y);
        let [c00, c01, c10, c11] = &o.comps;
        let mut out = [E::ZERO; C];
        let mut add = |v: [E; C]| {
            for (o, v) in out.iter_mut().zip(v) {
                *o = o.wrapping_add(v);
            }
        };
        if dx.d != 0 {
            if dy.d != 0 {
                add(self.field32(c00, dx.i0, dy.i0, k));
            }
            if dy.q != 0 {
                add(self.field32(c01, dx.i0, dy.q.wrapping_sub(1), k));
            }
        }
        if dx.q != 0 {
            if dy.d != 0 {
                add(self.field32(c10, dx.q.wrapping_sub(1), dy.i0, k));
            }
            if dy.q != 0 {
                add(self.field32(c11, dx.q.wrapping_sub(1), dy.q.wrapping_sub(1), k));
            }
        }
        count_corner_adds::<K, C>(&dx, &dy, k);
        if let Some(m) = self.geo.spec.modulus {
            for o in out.iter_mut() {
                *o = o.low_bits(m);
            }
        }
        out
    }

    /// The four corners `[S(xa, ya), S(xb, ya), S(xa, yb), S(xb, yb)]` (all `<= w`, `<= h`)
    /// under a [`OneLevel`] geometry, each field read once: a tile-level field depends on its
    /// axis only through `q`, so two corners with the same `q` on that axis share it. For the
    /// 2 x 2 neighbourhood of a 16-read corner inside one tile (`xb = xa + 1`, `yb = ya + 1`,
    /// the usual case) that is 9 fields instead of 16: 4 local sums, 2 strips per side, 1
    /// tile corner. The sums, and the additions counted per corner, are those of four
    /// [`Layout::corner`] calls; only the reads are fewer.
    #[inline(always)]
    fn quad_fast<K: Counter>(
        &self,
        o: &OneLevel,
        [xa, xb, ya, yb]: [u32; 4],
        k: &mut K,
    ) -> [[E; C]; 4] {
        let xa = OneLevel::digits(o.shift_x, o.low_x, xa);
        let xb = OneLevel::digits(o.shift_x, o.low_x, xb);
        let ya = OneLevel::digits(o.shift_y, o.low_y, ya);
        let yb = OneLevel::digits(o.shift_y, o.low_y, yb);
        let [c00, c01, c10, c11] = &o.comps;
        let z = [E::ZERO; C];
        let (same_qx, same_qy) = (xa.q == xb.q, ya.q == yb.q);
        // Tile corners C11 at (qx - 1, qy - 1).
        let t11 = |x: &OneDigits, y: &OneDigits, k: &mut K| {
            if x.q != 0 && y.q != 0 {
                self.field32(c11, x.q.wrapping_sub(1), y.q.wrapping_sub(1), k)
            } else {
                z
            }
        };
        let t11_aa = t11(&xa, &ya, k);
        let t11_ba = if same_qx { t11_aa } else { t11(&xb, &ya, k) };
        let t11_ab = if same_qy { t11_aa } else { t11(&xa, &yb, k) };
        let t11_bb = match (same_qy, same_qx) {
            (true, _) => t11_ba,
            (false, true) => t11_ab,
            (false, false) => t11(&xb, &yb, k),
        };
        // Strips left of the tile, C10 at (qx - 1, i0(y)): shared along x.
        let t10 = |x: &OneDigits, y: &OneDigits, k: &mut K| {
            if x.q != 0 && y.d != 0 {
                self.field32(c10, x.q.wrapping_sub(1), y.i0, k)
            } else {
                z
            }
        };
        let t10_aa = t10(&xa, &ya, k);
        let t10_ba = if same_qx { t10_aa } else { t10(&xb, &ya, k) };
        let t10_ab = t10(&xa, &yb, k);
        let t10_bb = if same_qx { t10_ab } else { t10(&xb, &yb, k) };
        // Strips above the tile, C01 at (i0(x), qy - 1): shared along y.
        let t01 = |x: &OneDigits, y: &OneDigits, k: &mut K| {
            if x.d != 0 && y.q != 0 {
                self.field32(c01, x.i0, y.q.wrapping_sub(1), k)
            } else {
                z
            }
        };
        let t01_aa = t01(&xa, &ya, k);
        let t01_ab = if same_qy { t01_aa } else { t01(&xa, &yb, k) };
        let t01_ba = t01(&xb, &ya, k);
        let t01_bb = if same_qy { t01_ba } else { t01(&xb, &yb, k) };
        // Local sums C00 at (i0(x), i0(y)).
        let t00 = |x: &OneDigits, y: &OneDigits, k: &mut K| {
            if x.d != 0 && y.d != 0 {
                self.field32(c00, x.i0, y.i0, k)
            } else {
                z
            }
        };
        let t00_aa = t00(&xa, &ya, k);
        let t00_ba = t00(&xb, &ya, k);
        let t00_ab = t00(&xa, &yb, k);
        let t00_bb = t00(&xb, &yb, k);
        for (x, y) in [(&xa, &ya), (&xb, &ya), (&xa, &yb), (&xb, &yb)] {
            count_corner_adds::<K, C>(x, y, k);
        }
        let modulus = self.geo.spec.modulus;
        let sum = |a: [E; C], b: [E; C], c: [E; C], d: [E; C]| -> [E; C] {
            core::array::from_fn(|i| {
                let g = |v: &[E; C]| v.get(i).copied().unwrap_or(E::ZERO);
                let v = g(&a)
                    .wrapping_add(g(&b))
                    .wrapping_add(g(&c))
                    .wrapping_add(g(&d));
                match modulus {
                    Some(m) => v.low_bits(m),
                    None => v,
                }
            })
        };
        [
            sum(t00_aa, t01_aa, t10_aa, t11_aa),
            sum(t00_ba, t01_ba, t10_ba, t11_ba),
            sum(t00_ab, t01_ab, t10_ab, t11_ab),
            sum(t00_bb, t01_bb, t10_bb, t11_bb),
        ]
    }

    /// The fields at bit `at` (all channels), the read counted: [`Tiled::field32`] with the
    /// offset already formed.
    #[inline(always)]
    fn field_at<K: Counter>(&self, c: &Comp32, mut at: u32, k: &mut K) -> [E; C] {
        count_field(c, at, k);
        let mut out = [E::ZERO; C];
        for o in out.iter_mut() {
            *o = E::from_u64_truncating(u64::from(read_masked32(self.words, at, c.mask)));
            at = at.wrapping_add(c.bits);
        }
        out
    }

    /// The entries at bit `at` and the next one (`at + stride`: `ix + 1`, same `iy`), the reads
    /// counted as two [`Tiled::field_at`] calls count them. When both fit one 32-bit read
    /// (`pair_mask`), one [`read_masked32`] of `2 stride` bits gives both; else two reads.
    #[inline(always)]
    fn pair_at<K: Counter>(&self, c: &Comp32, at: u32, k: &mut K) -> ([E; C], [E; C]) {
        let next = at.wrapping_add(c.stride);
        if c.pair_mask == 0 {
            if C != 1 {
                return (self.field_at(c, at, k), self.field_at(c, next, k));
            }
            // One channel: the two fields' windows with one range check.
            for a in [at, next] {
                count_field(c, a, k);
            }
            let (u, v) = read2_32(self.words, at, c.stride);
            let one = |v: u32| [E::from_u64_truncating(u64::from(v & c.mask)); C];
            return (one(u), one(v));
        }
        for a in [at, next] {
            count_field(c, a, k);
        }
        // Both fields are masked below: the 32 bits at `at` unmasked.
        let v = read_masked32(self.words, at, u32::MAX);
        let (mut a, mut b) = ([E::ZERO; C], [E::ZERO; C]);
        // Channel c of the first entry at c bits, of the second at stride + c bits: both below
        // 2 stride <= 32 (pair_mask != 0), so the shifts are below 32.
        let mut sh = 0u32;
        for (a, b) in a.iter_mut().zip(b.iter_mut()) {
            *a = E::from_u64_truncating(u64::from(v.wrapping_shr(sh) & c.mask));
            *b = E::from_u64_truncating(u64::from(
                v.wrapping_shr(sh.wrapping_add(c.stride)) & c.mask,
            ));
            sh = sh.wrapping_add(c.bits);
        }
        (a, b)
    }

    /// Two entries of one column a component row apart (`at` and `at + row`: `iy` and `iy + 1`,
    /// same `ix`), the reads counted as two [`Tiled::field_at`] calls count them: one range
    /// check for both ([`read2_32`]) when there is one channel.
    #[inline(always)]
    fn column2_at<K: Counter>(&self, c: &Comp32, at: u32, k: &mut K) -> ([E; C], [E; C]) {
        if C != 1 {
            return (
                self.field_at(c, at, k),
                self.field_at(c, at.wrapping_add(c.row), k),
            );
        }
        let next = at.wrapping_add(c.row);
        for a in [at, next] {
            count_field(c, a, k);
        }
        let (u, v) = read2_32(self.words, at, c.row);
        let one = |v: u32| [E::from_u64_truncating(u64::from(v & c.mask)); C];
        (one(u), one(v))
    }

    /// The entries `(ix, iy)`, `(ix + 1, iy)`, `(ix, iy + 1)`, `(ix + 1, iy + 1)` of a
    /// component (`at`, `at + stride`, `at + row`, `at + row + stride`), read and counted as
    /// two [`Tiled::pair_at`] calls: with one channel and pairs that fit 32 bits, two 32-bit
    /// windows a row apart with one range check ([`read2_32`]).
    #[inline(always)]
    fn square_at<K: Counter>(&self, c: &Comp32, at: u32, k: &mut K) -> [[E; C]; 4] {
        if C != 1 || c.pair_mask == 0 {
            let (a, b) = self.pair_at(c, at, k);
            let (d, e) = self.pair_at(c, at.wrapping_add(c.row), k);
            return [a, b, d, e];
        }
        let below = at.wrapping_add(c.row);
        for a in [
            at,
            at.wrapping_add(c.stride),
            below,
            below.wrapping_add(c.stride),
        ] {
            count_field(c, a, k);
        }
        let (u, v) = read2_32(self.words, at, c.row);
        // One channel: the first entry at bit 0 of each window, the second at `stride` < 32.
        let one = |v: u32| [E::from_u64_truncating(u64::from(v & c.mask)); C];
        [
            one(u),
            one(u.wrapping_shr(c.stride)),
            one(v),
            one(v.wrapping_shr(c.stride)),
        ]
    }

    /// The corners of cell `(i, j)` when the cell lies inside one tile away from its left and
    /// top edges (`i` and `j` not multiples of the tile sides, and neither is `i + 1`, `j + 1`:
    /// every digit non-zero, both columns and both rows in the same tile): the usual corner of
    /// a 16-read lookup. The 9 fields ([`Tiled::quad_fast`]) at offsets formed by additions
    /// ([`Tiled::cell_in_tile`]). `None` when the cell is not of that kind.
    #[inline(always)]
    fn cell_fast<K: Counter>(
        &self,
        o: &OneLevel,
        i: u32,
        j: u32,
        k: &mut K,
    ) -> Option<[[E; C]; 4]> {
        if !(o.inside_x(i) && o.inside_y(j)) {
            return None;
        }
        let cell = self.cell_in_tile(o, &CellParts::x(o, i), &CellParts::y(o, j), k);
        Some(self.reduce_cell(cell))
    }

    /// The four cells of a 16-read lookup, in [`Layout::cells4_placed`]'s order, when all four
    /// lie inside their tiles as [`Tiled::cell_fast`] needs (`None`, nothing read, otherwise):
    /// the checks once, the digits and the per-axis parts of the offsets of each of the two
    /// columns and two rows once ([`CellParts`]), and each cell written in place by the one
    /// out-of-line copy of [`Tiled::cell_in_tile`].
    #[inline(always)]
    fn cells4_fast<K: Counter>(
        &self,
        o: &OneLevel,
        [i0, i1]: [u32; 2],
        [j0, j1]: [u32; 2],
        k: &mut K,
    ) -> Option<[[[E; C]; 4]; 4]> {
        if !(o.inside_x(i0) && o.inside_x(i1) && o.inside_y(j0) && o.inside_y(j1)) {
            return None;
        }
        // Not reduced modulo 2^k under a modular spec: congruent values, which the lookups
        // reduce after their differences ([`Layout::cells4_placed`]).
        Some(self.cells4_in_tiles(o, [i0, i1], [j0, j1], k))
    }

    /// [`Layout::cells4_placed`]'s cell-by-cell path, out of line.
    #[inline(never)]
    fn cells4_slow<K: Counter>(&self, i: [usize; 2], j: [usize; 2], k: &mut K) -> [[[E; C]; 4]; 4] {
        super::cells4_by_cell(self, i, j, k)
    }
    /// [`Tiled::cells4_fast`]'s reads, out of line.
    #[inline(always)]
    fn cells4_in_tiles<K: Counter>(
        &self,
        o: &OneLevel,
        [i0, i1]: [u32; 2],
        [j0, j1]: [u32; 2],
        k: &mut K,
    ) -> [[[E; C]; 4]; 4] {
        let (x0, x1) = (CellParts::x(o, i0), CellParts::x(o, i1));
        let (y0, y1) = (CellParts::y(o, j0), CellParts::y(o, j1));
        [
            self.cell_in_tile(o, &x1, &y1, k),
            self.cell_in_tile(o, &x1, &y0, k),
            self.cell_in_tile(o, &x0, &y1, k),
            self.cell_in_tile(o, &x0, &y0, k),
        ]
    }

    /// [`Tiled::cell_fast`]'s cell into `out` from the parts of its column `x` and row `y`
    /// ([`CellParts`]; the digits checked by the caller with [`OneLevel::inside_x`] and
    /// [`OneLevel::inside_y`]): the local sums at `o00`, `o00 + stride` (next column), `o00 +
    /// row` (next row) and `o00 + row + stride`; the strips above at `o01` and `o01 + stride`;
    /// the strips left at `o10` and `o10 + row`; the tile corner at `o11`, each offset one
    /// addition of the two parts. Out of line, written in place: one copy serves
    /// [`Tiled::cell_fast`] and the four cells of [`Tiled::cells4_fast`] (docs/benchmarks.md).
    #[inline(never)]
    fn cell_in_tile<K: Counter>(
        &self,
        o: &OneLevel,
        x: &CellParts,
        y: &CellParts,
        k: &mut K,
    ) -> [[E; C]; 4] {
        let mut out = [[E::ZERO; C]; 4];
        self.cell_in_tile_inline(o, x, y, &mut out, k);
        out
    }

    #[inline(always)]
    fn cell_in_tile_inline<K: Counter>(
        &self,
        o: &OneLevel,
        x: &CellParts,
        y: &CellParts,
        out: &mut [[E; C]; 4],
        k: &mut K,
    ) {
        let [c00, c01, c10, c11] = &o.comps;
        let [mut s0, mut s1, mut s2, mut s3] = self.square_at(c00, x.p00.wrapping_add(y.p00), k);
        if y.q != 0 {
            let (a, b) = self.pair_at(c01, x.p01.wrapping_add(y.p01), k);
            add_to(&mut s0, &a);
            add_to(&mut s1, &b);
            add_to(&mut s2, &a);
            add_to(&mut s3, &b);
        }
        if x.q != 0 {
            let (mut a, mut b) = self.column2_at(c10, x.p10.wrapping_add(y.p10), k);
            if y.q != 0 {
                let t = self.field_at(c11, x.p11.wrapping_add(y.p11), k);
                add_to(&mut a, &t);
                add_to(&mut b, &t);
            }
            add_to(&mut s0, &a);
            add_to(&mut s1, &a);
            add_to(&mut s2, &b);
            add_to(&mut s3, &b);
        }
        // The additions done: 4 for the strips above, 4 for those to the left, 2 for the
        // tile corner (into the two left strips), per channel.
        let (left, above) = (x.q != 0, y.q != 0);
        #[allow(clippy::arithmetic_side_effects, reason = "at most 4 + 4 + 2")]
        let adds = 4 * u32::from(above) + 4 * u32::from(left) + 2 * u32::from(left && above);
        k.adds(adds.saturating_mul(const { per_channel(1, C) }));
        // Not reduced here: the four cells of a lookup stay unreduced (congruent values,
        // [`Layout::cells4_placed`]); a single cell is reduced by [`Tiled::cell_fast`].
        *out = [s0, s1, s2, s3];
    }

    /// Reduces the four corners of [`Tiled::cell_fast`]'s cell modulo `2^k` under a modular
    /// spec (its modulus `k`); a plain spec leaves them as they are. (The four cells of
    /// [`Tiled::cells4_fast`] are left unreduced: docs/benchmarks.md.)
    #[inline(always)]
    fn reduce_cell(&self, mut cell: [[E; C]; 4]) -> [[E; C]; 4] {
        if let Some(m) = self.geo.spec.modulus {
            for v in cell.iter_mut().flatten() {
                *v = v.low_bits(m);
            }
        }
        cell
    }

    /// Adds `S(x, y)` for one level of tiles on both axes (`0 < x <= w`, `0 < y <= h`) to `out`:
    /// straight-line code over the four components. (Also correct, via the general path, for
    /// any other spec: the lookups use it only for one level.)
    #[inline(always)]
    pub(super) fn corner_one_level<K: Counter>(&self, x: u32, y: u32, out: &mut [E; C], k: &mut K) {
        let g = &self.geo;
        if g.ax.levels != 1 || g.ay.levels != 1 {
            return self.corner_general(x, y, out, k);
        }
        let (Some((dx, ix0, qx)), Some((dy, iy0, qy))) = (g.ax.step(0, x), g.ay.step(0, y)) else {
            return;
        };
        let (ix1, iy1) = (qx.wrapping_sub(1), qy.wrapping_sub(1));
        let [r0, r1, ..] = &g.comps;
        let ([c00, c01, ..], [c10, c11, ..]) = (r0, r1);
        if dx != 0 {
            if dy != 0 {
                self.add_entry(c00, ix0, iy0, out, k);
            }
            if qy != 0 {
                self.add_entry(c01, ix0, iy1, out, k);
            }
        }
        if qx != 0 {
            if dy != 0 {
                self.add_entry(c10, ix1, iy0, out, k);
            }
            if qy != 0 {
                self.add_entry(c11, ix1, iy1, out, k);
            }
        }
        count_field_adds::<K, C>([dx != 0, qx != 0], [dy != 0, qy != 0], k);
    }

    /// Adds `S(x, y)` (`0 < x <= w`, `0 < y <= h`) to `out` for any spec: the digits of both
    /// coordinates, then one field per pair of non-zero digits.
    #[inline(always)]
    pub(super) fn corner_general<K: Counter>(&self, x: u32, y: u32, out: &mut [E; C], k: &mut K) {
        let g = &self.geo;
        let (dx, dy) = (g.ax.digits(x), g.ay.digits(y));
        let mut fields = 0u32;
        for ((row, &ddx), &ix) in g
            .comps
            .iter()
            .zip(dx.digit.iter())
            .zip(dx.index.iter())
            .take(g.ax.components())
        {
            if ddx == 0 {
                continue;
            }
            for ((comp, &ddy), &iy) in row
                .iter()
                .zip(dy.digit.iter())
                .zip(dy.index.iter())
                .take(g.ay.components())
            {
                if ddy == 0 {
                    continue;
                }
                self.add_entry(comp, ix, iy, out, k);
                #[allow(
                    clippy::arithmetic_side_effects,
                    reason = "at most (MAX_LEVELS + 1)^2 = 25 fields"
                )]
                {
                    fields += 1;
                }
            }
        }
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "fields - 1 only when fields > 1"
        )]
        if fields > 1 {
            k.adds((fields - 1).saturating_mul(const { per_channel(1, C) }));
        }
    }

    /// The geometry (tests).
    #[cfg(test)]
    pub(super) fn geometry(&self) -> &Geometry {
        &self.geo
    }

    /// The spec.
    pub fn spec(&self) -> TiledSpec {
        self.geo.spec
    }

    /// Field width of component `(p, q)` (`p` the x level, `q` the y level), or `None`.
    pub fn field_bits(&self, p: usize, q: usize) -> Option<u32> {
        self.geo.component(p, q).map(|c| c.bits)
    }

    /// The most fields one `S(x, y)` reads: `(Lx + 1)(Ly + 1)`.
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "each at most MAX_LEVELS + 1 = 5"
    )]
    pub fn max_fields_per_corner(&self) -> usize {
        self.geo.ax.components() * self.geo.ay.components()
    }

    /// The storage words.
    pub fn words(&self) -> &'a [u32] {
        self.words
    }
}

/// `acc += v` per channel (wrapping: sums of parts of `S`, which `E` holds on a valid layout).
#[inline(always)]
fn add_to<E: Entry, const C: usize>(acc: &mut [E; C], v: &[E; C]) {
    for (a, v) in acc.iter_mut().zip(v) {
        *a = a.wrapping_add(*v);
    }
}

/// The additions of one corner under a [`OneLevel`] geometry: one per field after the first,
/// per channel (as [`Tiled::corner_one_level`] counts them).
#[inline(always)]
fn count_corner_adds<K: Counter, const C: usize>(x: &OneDigits, y: &OneDigits, k: &mut K) {
    count_field_adds::<K, C>([x.d != 0, x.q != 0], [y.d != 0, y.q != 0], k);
}

/// The additions of one corner of one level of tiles: one per field read after the first, per
/// channel, for the non-zero digits `[d, q]` of each axis.
#[inline(always)]
fn count_field_adds<K: Counter, const C: usize>(x: [bool; 2], y: [bool; 2], k: &mut K) {
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "(at most 2) * (at most 2) fields; fields - 1 only when fields > 1"
    )]
    {
        let ([xd, xq], [yd, yq]) = (x, y);
        let fields = (u32::from(xd) + u32::from(xq)) * (u32::from(yd) + u32::from(yq));
        if fields > 1 {
            k.adds((fields - 1).saturating_mul(const { per_channel(1, C) }));
        }
    }
}

impl<E: Entry, const C: usize> Layout<C> for Tiled<'_, E, C> {
    type Value = E;
    fn width(&self) -> usize {
        self.geo.width
    }
    fn height(&self) -> usize {
        self.geo.height
    }
    fn texel_bits(&self) -> u32 {
        self.geo.texel_bits
    }
    fn value_bits(&self) -> u32 {
        self.geo.value_bits
    }
    fn modulus(&self) -> Option<u32> {
        self.geo.spec.modulus
    }
    fn storage_bits(&self) -> u64 {
        self.geo.total_bits
    }
    /// One field per pair of non-zero digits. Corners outside `[0, w] x [0, h]` read nothing
    /// and give 0.
    #[inline]
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        let g = &self.geo;
        let mut out = [E::ZERO; C];
        // x - 1 < w and y - 1 < h: also refuses x = 0 and y = 0 (wrapping to usize::MAX).
        if x.wrapping_sub(1) >= g.width || y.wrapping_sub(1) >= g.height {
            return out;
        }
        #[allow(
            clippy::as_conversions,
            reason = "x <= w and y <= h (checked above) are below 2^31: lossless"
        )]
        let (x, y) = (x as u32, y as u32);
        if let Some(o) = &g.one_level {
            return self.corner_fast(o, x, y, k);
        }
        if g.ax.levels == 1 && g.ay.levels == 1 {
            self.corner_one_level(x, y, &mut out, k);
        } else {
            self.corner_general(x, y, &mut out, k);
        }
        if let Some(m) = g.spec.modulus {
            for o in out.iter_mut() {
                *o = o.low_bits(m);
            }
        }
        out
    }
    #[inline(always)]
    fn cell_corners<K: Counter>(&self, i: usize, j: usize, k: &mut K) -> [[E; C]; 4] {
        if let Some(o) = &self.geo.one_level {
            // i + 1 <= w and j + 1 <= h (so both below 2^31) for the fast path.
            if i < self.geo.width && j < self.geo.height {
                #[allow(
                    clippy::as_conversions,
                    reason = "i < w and j < h (checked above) are below 2^31: lossless"
                )]
                let (i, j) = (i as u32, j as u32);
                if let Some(v) = self.cell_fast(o, i, j, k) {
                    return v;
                }
            }
        }
        self.quad(i, i.wrapping_add(1), j, j.wrapping_add(1), k)
    }
    /// The four cells through [`Tiled::cells4_fast`] when each lies inside its tile, else cell
    /// by cell ([`Layout::cell_corners_placed`]); the same values, counts and read order.
    #[inline(always)]
    fn cells4_placed<K: Counter>(
        &self,
        [i0, i1]: [usize; 2],
        [j0, j1]: [usize; 2],
        k: &mut K,
    ) -> [[[E; C]; 4]; 4] {
        let g = &self.geo;
        if let Some(o) = &g.one_level {
            if i0.max(i1) < g.width && j0.max(j1) < g.height {
                #[allow(
                    clippy::as_conversions,
                    reason = "below w and h (checked above), so below 2^31: lossless"
                )]
                let (i, j) = ([i0 as u32, i1 as u32], [j0 as u32, j1 as u32]);
                if let Some(v) = self.cells4_fast(o, i, j, k) {
                    return v;
                }
            }
        }
        self.cells4_slow([i0, i1], [j0, j1], k)
    }
    /// Under one level of power-of-two tiles (8 x 8 and the like), each field of the four corners
    /// read once (9 instead of 16 for a 16-read corner inside a tile); else four
    /// [`Layout::corner`] calls.
    #[inline]
    fn quad<K: Counter>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[E; C]; 4] {
        let g = &self.geo;
        match &g.one_level {
            Some(o) if xa.max(xb) <= g.width && ya.max(yb) <= g.height => {
                #[allow(
                    clippy::as_conversions,
                    reason = "at most w, h (the guard) < 2^31: lossless"
                )]
                let corners = [xa as u32, xb as u32, ya as u32, yb as u32];
                self.quad_fast(o, corners, k)
            }
            _ => [
                self.corner(xa, ya, k),
                self.corner(xb, ya, k),
                self.corner(xa, yb, k),
                self.corner(xb, yb, k),
            ],
        }
    }
}

/// `n / d` (`None` for `d = 0`): a shift when `d` is a power of two (the usual block sizes),
/// so that the row step divides only for other sizes.
#[inline(always)]
fn div_by(n: usize, d: usize) -> Option<usize> {
    if d.is_power_of_two() {
        Some(n >> d.trailing_zeros())
    } else {
        n.checked_div(d)
    }
}

/// `n mod d` (`None` for `d = 0`), a mask when `d` is a power of two (as [`div_by`]).
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
#[inline(always)]
fn rem_by(n: usize, d: usize) -> Option<usize> {
    if d.is_power_of_two() {
        Some(n & d.wrapping_sub(1))
    } else {
        n.checked_rem(d)
    }
}

/// Refuses a row holding a texel wider than `texel_bits` (the field widths are proved for
/// `texel_bits`), reporting the first such texel's width. Nothing to check when `T` is no wider;
/// else one OR over the row (vectorized: every texel is at most `2^b - 1` iff their OR is), the
/// texel-by-texel search only when that fails.
pub(super) fn check_texel_width<T: Texel>(texels: &[T], texel_bits: u32) -> Result<(), Error> {
    if T::BITS <= texel_bits {
        return Ok(());
    }
    let max = mask(texel_bits);
    if u64::from(texels.iter().fold(0u16, |a, t| a | t.to_u16())) <= max {
        return Ok(());
    }
    for t in texels {
        let v = t.to_u16();
        if u64::from(v) > max {
            return Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: width::bits_of_u64(u64::from(v)),
                bits_available: texel_bits,
            });
        }
    }
    Ok(())
}

/// `row[x] += t_0 + ... + t_x` per channel (wrapping), for a row of `w C` entries: the flat
/// build's row step (the row above plus the running sum), with the vectorized kernel where it
/// applies (`simd`: `u8` texels, `u32` entries, one channel).
pub(super) fn add_prefix_row<T: Texel, E: Entry, const C: usize>(texels: &[T], row: &mut [E]) {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    if crate::simd::build_row_in_place::<T, E, C>(texels, row, false, None, false) {
        return;
    }
    // ARMv7E-M: the same row in place (its additions, on 32-bit registers or, for `u16`, on
    // 16-bit halves, wrap as these do).
    #[cfg(all(feature = "simd", texsat_armv7em))]
    if crate::dsp::build_row_in_place::<T, E, C>(texels, row, false, None) {
        return;
    }
    let mut run = [E::ZERO; C];
    for (o, t) in row.chunks_exact_mut(C).zip(texels.chunks_exact(C)) {
        for ((ov, tv), r) in o.iter_mut().zip(t).zip(run.iter_mut()) {
            *r = r.wrapping_add(E::from(tv.to_u16()));
            *ov = ov.wrapping_add(*r);
        }
    }
}

/// One row of the fields of x component `p` into `out`, in storage order: for every stored
/// position `x <= n` (a multiple of `b = b_p` whose digit `d_p` is not zero) the `C` values
/// `acc[x] - acc[trunc_{p+1}(x)]`, `acc[x]` at `x C`. `big = b_{p+1}`, or 0 for the top
/// component (its intervals start at 0). Returns the number of values written; `None` if `acc`
/// or `out` is too short (never, for the builder's rows). Within a block of `b_{p+1}` the
/// positions are `base + b, base + 2b, ...` (contiguous for `b = 1`: the local sums).
fn component_fields<E: Entry, const C: usize>(
    acc: &[E],
    n: usize,
    b: usize,
    big: usize,
    out: &mut [E],
) -> Option<usize> {
    let at = |x: usize| x.checked_mul(C);
    // The differences inside blocks of the common powers of two (the builder calls this over
    // the tile boundaries, for hierarchical tiles): whole blocks by code specialized for the
    // width; the last, partial block below. Not on 32-bit targets (flash: the general loop
    // does the same, and the local sums themselves are `split_fields`'s).
    #[cfg(target_pointer_width = "64")]
    let (mut k, mut base) = match (b, big) {
        (1, 2) => local_fields::<E, C, 2>(acc, n, out)?,
        (1, 4) => local_fields::<E, C, 4>(acc, n, out)?,
        (1, 8) => local_fields::<E, C, 8>(acc, n, out)?,
        (1, 16) => local_fields::<E, C, 16>(acc, n, out)?,
        (1, 32) => local_fields::<E, C, 32>(acc, n, out)?,
        _ => (0, 0),
    };
    #[cfg(not(target_pointer_width = "64"))]
    let (mut k, mut base) = (0usize, 0usize);
    if big != 0 && base >= n {
        return Some(k);
    }
    loop {
        let from = at(base)?;
        let lo: [E; C] = acc.get(from..)?.first_chunk::<C>().copied()?;
        let end = if big == 0 {
            n
        } else {
            n.min(base.saturating_add(big).saturating_sub(1))
        };
        if b == 1 {
            if end > base {
                let src = acc.get(from.checked_add(C)?..at(end)?.checked_add(C)?)?;
                let dst = out.get_mut(k..k.checked_add(src.len())?)?;
                // Channel i % C of each entry (C >= 1 and i % C < C: never the default; with C a
                // constant, no division and, for C = 1, a plain loop over the tile's row).
                for (i, (d, s)) in dst.iter_mut().zip(src).enumerate() {
                    *d = s.wrapping_sub(
                        i.checked_rem(C)
                            .and_then(|c| lo.get(c))
                            .copied()
                            .unwrap_or(E::ZERO),
                    );
                }
                k = k.checked_add(src.len())?;
            }
        } else if C == 1 {
            // x = base + b, base + 2b, ... <= end: every b-th value from base + b.
            let first = base.saturating_add(b);
            if first <= end {
                // b >= 1 (a block size): the division is checked.
                let count = end.checked_sub(first)?.checked_div(b)?.checked_add(1)?;
                let dst = out.get_mut(k..k.checked_add(count)?)?;
                let lo = lo.first().copied().unwrap_or(E::ZERO);
                // x <= end <= n for every value written: inside acc (no default taken).
                let mut x = first;
                for d in dst.iter_mut() {
                    *d = acc.get(x).copied().unwrap_or(E::ZERO).wrapping_sub(lo);
                    x = x.wrapping_add(b);
                }
                k = k.checked_add(count)?;
            }
        } else {
            let mut x = base.saturating_add(b);
            while x <= end {
                let v: [E; C] = acc.get(at(x)?..)?.first_chunk::<C>().copied()?;
                let dst = out.get_mut(k..k.checked_add(C)?)?;
                for ((d, s), l) in dst.iter_mut().zip(&v).zip(&lo) {
                    *d = s.wrapping_sub(*l);
                }
                k = k.checked_add(C)?;
                x = x.saturating_add(b);
            }
        }
        if big == 0 {
            return Some(k);
        }
        base = base.saturating_add(big);
        if base >= n {
            return Some(k);
        }
    }
}

/// [`component_fields`] for the local sums (`b = 1`) of `B`-texel blocks, over the whole blocks
/// of the row (those whose `B - 1` positions are all at most `n`): per block, `acc[base + d] -
/// acc[base]` for `d = 1..B`, loops of constant length that LLVM unrolls and vectorizes.
/// Returns the values written and the first block not done.
#[cfg(target_pointer_width = "64")]
fn local_fields<E: Entry, const C: usize, const B: usize>(
    acc: &[E],
    n: usize,
    out: &mut [E],
) -> Option<(usize, usize)> {
    // Block t is whole if t B + B - 1 <= n, i.e. t < (n + 1) / B.
    let blocks = n.checked_add(1)?.checked_div(B)?;
    let len_in = B.checked_mul(C)?;
    let len_out = len_in.checked_sub(C)?;
    let done = blocks.checked_mul(len_out)?;
    if C == 1 {
        // Block t (acc[t B .. t B + B] as an array): acc[t B + j] - acc[t B] for j = 1..B into
        // out[t (B - 1)..] as an array of B values, the last a 0 that the next block's first
        // value overwrites (or past the values returned: out holds w + 1 values and
        // t (B - 1) + B <= n + 1 for a whole block). Constant lengths: one vector operation.
        let (tiles, _) = acc.as_chunks::<B>();
        let step = B.checked_sub(1)?;
        let mut at = 0usize;
        for (t, a) in tiles.iter().take(blocks).enumerate() {
            let lo = a.first().copied().unwrap_or(E::ZERO);
            // No room for the array (a row of few blocks over the tile boundaries): the
            // blocks from here on go through the caller's general loop.
            let Some(d) = out.get_mut(at..).and_then(|o| o.first_chunk_mut::<B>()) else {
                return Some((at, t.checked_mul(B)?));
            };
            for (j, d) in d.iter_mut().enumerate() {
                *d = a
                    .get(j.wrapping_add(1))
                    .map_or(E::ZERO, |v| v.wrapping_sub(lo));
            }
            at = at.wrapping_add(step);
        }
        return Some((done, blocks.checked_mul(B)?));
    }
    let src = acc.get(..blocks.checked_mul(len_in)?)?;
    let dst = out.get_mut(..done)?;
    for (d, a) in dst.chunks_exact_mut(len_out).zip(src.chunks_exact(len_in)) {
        let (lo, rest) = a.split_at_checked(C)?;
        for (i, (d, r)) in d.iter_mut().zip(rest).enumerate() {
            *d = r.wrapping_sub(
                i.checked_rem(C)
                    .and_then(|c| lo.get(c))
                    .copied()
                    .unwrap_or(E::ZERO),
            );
        }
    }
    Some((dst.len(), blocks.checked_mul(B)?))
}

/// The words whose lines a row kernel asks for (first word, word count), two slices: the
/// component rows a row's fields go to, per x component 0 and 1, or, for `simd::band_rows`,
/// words further ahead (the next row's, and past the layout after its last rows). A prefetch
/// hint, never dereferenced. The one definition, also the `simd` kernels' (`simd::Ahead`).
pub(crate) type Ahead = [(*const u32, usize); 2];

/// The row step of [`TiledBuilder::push_row`] on one accumulator row `acc` (position `x =
/// 1..=n` at `(x - 1) C`, `C` values each) and, when the row ends a block of a level above 0,
/// the level below, `lower` (same form; added into `acc` and cleared).
///
/// The accumulators are kept in the form the fields are read from. With the tile width `t =
/// b_1` (0 for an axis without levels: no boundary), a *boundary* `x` (a multiple of `t`) holds
/// the sum `A(x)` of the rows' prefix sums `t_0 + ... + t_{x-1}`; every other `x` holds the
/// local sum `A(x) - A(trunc_1(x))`, the sum of the texels of `[trunc_1(x), x)` over the rows
/// (`A(0) = 0`; for `t = 0`, `A(x)` itself). Per row: `acc[x] += lower[x] + r(x)` with `r(x)` the
/// row's prefix sum at a boundary (the running sum) and its sum from `trunc_1(x)` elsewhere
/// (the running sum inside the tile), per channel, wrapping; then the boundaries are copied
/// into `bnd` and the local sums into `local`, in order of `x`: the fields of the first two x
/// components, without a subtraction. Returns the values written to each; `None` if a slice
/// is too short (never, for the builder's rows). With `simd`, one vectorized pass where it
/// applies ([`crate::simd::tiled_row`], the same values), which may pack the first `kp` local
/// sums straight into `pack` (`(words, bit, k, exact)`: `k`-bit fields from bit `bit < 32` of
/// `words`, the component row of the local sums; `exact` if every local sum is below `2^k`) and
/// not write `local[..kp]`; returns `(kb,
/// kl, kp)` (`kp = 0` on the portable path). `ahead` (the first word and the word count of the
/// rows the fields go to) is a prefetch hint for the kernel, never dereferenced.
#[allow(
    clippy::too_many_arguments,
    reason = "the row step's slices, the prefetch hint and the packing target"
)]
fn row_fields<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    lower: Option<&mut [E]>,
    acc: &mut [E],
    t: usize,
    bnd: &mut [E],
    local: &mut [E],
    ahead: Ahead,
    pack: Option<(&mut [u32], u64, u32, bool)>,
) -> Option<(usize, usize, usize)> {
    #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
    let _ = (ahead, pack);
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    let lower = {
        let pack = pack.map(|(words, bit, k, exact)| crate::simd::PackTo {
            words,
            bit,
            k,
            exact,
        });
        match lower {
            // The kernel needs its own borrow of `lower`: try it, then fall through.
            Some(l) => {
                if let Some(done) = crate::simd::tiled_row::<T, E, C>(
                    texels,
                    Some(&mut *l),
                    acc,
                    t,
                    bnd,
                    local,
                    ahead,
                    pack,
                ) {
                    return Some(done);
                }
                Some(l)
            }
            None => {
                if let Some(done) =
                    crate::simd::tiled_row::<T, E, C>(texels, None, acc, t, bnd, local, ahead, pack)
                {
                    return Some(done);
                }
                None
            }
        }
    };
    if let Some(l) = lower {
        for (h, b) in acc.iter_mut().zip(l.iter_mut()) {
            *h = h.wrapping_add(*b);
            *b = E::ZERO;
        }
    }
    // Tiles of common power-of-two widths by code specialized for the width; on 32-bit
    // targets (flash) only 8, the width of the plans' tiles.
    if C == 1 {
        #[cfg(target_pointer_width = "64")]
        match t {
            2 => return row_tiles::<T, E, 2>(texels, acc, bnd, local).map(|(b, l)| (b, l, 0)),
            4 => return row_tiles::<T, E, 4>(texels, acc, bnd, local).map(|(b, l)| (b, l, 0)),
            8 => return row_tiles::<T, E, 8>(texels, acc, bnd, local).map(|(b, l)| (b, l, 0)),
            16 => return row_tiles::<T, E, 16>(texels, acc, bnd, local).map(|(b, l)| (b, l, 0)),
            _ => {}
        }
        #[cfg(not(target_pointer_width = "64"))]
        if t == 8 {
            return row_tiles::<T, E, 8>(texels, acc, bnd, local).map(|(b, l)| (b, l, 0));
        }
    }
    let (mut kb, mut kl) = (0usize, 0usize);
    let (mut run, mut inner) = ([E::ZERO; C], [E::ZERO; C]);
    let mut d = 0usize;
    for (a, tx) in acc.chunks_exact_mut(C).zip(texels.chunks_exact(C)) {
        // d counts the positions since the last boundary (t = 0: never one, and the running
        // sum inside the "tile" is the running sum).
        d = d.wrapping_add(1);
        let boundary = d == t;
        for (((a, tx), r), i) in a.iter_mut().zip(tx).zip(&mut run).zip(&mut inner) {
            let v = E::from(tx.to_u16());
            *r = r.wrapping_add(v);
            *i = i.wrapping_add(v);
            *a = a.wrapping_add(if boundary { *r } else { *i });
        }
        if boundary {
            let end = kb.checked_add(C)?;
            bnd.get_mut(kb..end)?.copy_from_slice(a);
            kb = end;
            inner = [E::ZERO; C];
            d = 0;
        } else {
            let end = kl.checked_add(C)?;
            local.get_mut(kl..end)?.copy_from_slice(a);
            kl = end;
        }
    }
    Some((kb, kl, 0))
}

/// [`row_fields`] for one channel and tiles of `T` texels: per whole tile, the running sum
/// inside the tile (a chain of `T` additions, independent from tile to tile) added into the
/// `T - 1` local sums, and the tile's total into the running sum (one addition per tile on
/// the chain from tile to tile) added into the boundary; the local sums copied out as an array
/// of `T` (the last overwritten by the next tile's first: constant lengths); the partial tile
/// at the end, value by value.
fn row_tiles<T: Texel, E: Entry, const TW: usize>(
    texels: &[T],
    acc: &mut [E],
    bnd: &mut [E],
    local: &mut [E],
) -> Option<(usize, usize)> {
    let step = TW.checked_sub(1)?;
    let (tiles, rest) = acc.as_chunks_mut::<TW>();
    let (tx, tx_rest) = texels.as_chunks::<TW>();
    let (mut kb, mut kl) = (0usize, 0usize);
    let mut run = E::ZERO;
    for (a, tx) in tiles.iter_mut().zip(tx) {
        // Each value written to the accumulator and to the field row from a register (a
        // reload of the accumulator as a vector would wait on the scalar stores).
        let mut inner = E::ZERO;
        match local.get_mut(kl..).and_then(|s| s.first_chunk_mut::<TW>()) {
            Some(d) => {
                for (j, ((a, t), d)) in a.iter_mut().zip(tx).zip(d.iter_mut()).enumerate() {
                    inner = inner.wrapping_add(E::from(t.to_u16()));
                    if j < step {
                        *a = a.wrapping_add(inner);
                    } else {
                        run = run.wrapping_add(inner);
                        *a = a.wrapping_add(run);
                    }
                    *d = *a;
                }
            }
            None => {
                // The last tile of a row that ends at a tile boundary: no room for the array.
                let end = kl.checked_add(step)?;
                let mut d = local.get_mut(kl..end)?.iter_mut();
                for (j, (a, t)) in a.iter_mut().zip(tx).enumerate() {
                    inner = inner.wrapping_add(E::from(t.to_u16()));
                    if j < step {
                        *a = a.wrapping_add(inner);
                    } else {
                        run = run.wrapping_add(inner);
                        *a = a.wrapping_add(run);
                    }
                    if let Some(d) = d.next() {
                        *d = *a;
                    }
                }
            }
        }
        *bnd.get_mut(kb)? = a.last().copied().unwrap_or(E::ZERO);
        kb = kb.checked_add(1)?;
        kl = kl.checked_add(step)?;
    }
    let end = kl.checked_add(rest.len())?;
    let mut inner = E::ZERO;
    for ((d, a), t) in local.get_mut(kl..end)?.iter_mut().zip(rest).zip(tx_rest) {
        inner = inner.wrapping_add(E::from(t.to_u16()));
        *a = a.wrapping_add(inner);
        *d = *a;
    }
    Some((kb, end))
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    clippy::unwrap_used,
    clippy::needless_range_loop,
    reason = "tests: a panic is a failed test; the reference indexes by position on purpose"
)]
mod row_step_tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// `row_fields` (with `simd`, the kernel where it applies, else the portable loops: `u8`
    /// into `u32` and `u64`, one and two channels) equals a value-by-value reference for tile
    /// widths 0 (no level), 2, 3, 4, 5, 8 and 16, rows of 0 to 70
    /// positions, with and without the level below: accumulators, the cleared level below,
    /// boundaries, local sums and their counts.
    #[test]
    fn row_fields_equal_the_reference() {
        fn check<E: Entry + core::fmt::Debug, const C: usize>(to: fn(u64) -> E) {
            let mut seed = 0x9e37_79b9_7f4a_7c15u64;
            let mut next = move || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                seed
            };
            for t in [0usize, 2, 3, 4, 5, 8, 16] {
                // Under Miri (slow): no level, a non-power of two and 8; short rows and a few
                // long ones.
                if cfg!(miri) && ![0, 3, 8].contains(&t) {
                    continue;
                }
                for n in 0..=70usize {
                    if cfg!(miri) && n > 17 && ![33, 64, 70].contains(&n) {
                        continue;
                    }
                    for with_lower in [false, true] {
                        let texels: Vec<u8> = (0..n * C).map(|_| next() as u8).collect();
                        let acc0: Vec<E> = (0..n * C).map(|_| to(next() >> 8)).collect();
                        let low0: Vec<E> = (0..n * C).map(|_| to(next() >> 8)).collect();
                        // Reference, value by value: the texels since the last boundary
                        // (all of them at a boundary; t = 0: all), summed afresh per x.
                        let (mut want_acc, mut want_b, mut want_l) =
                            (acc0.clone(), Vec::new(), Vec::new());
                        for x in 1..=n {
                            let boundary = t != 0 && x % t == 0;
                            let from = if boundary || t == 0 { 0 } else { x - x % t };
                            for c in 0..C {
                                let i = (x - 1) * C + c;
                                let r = (from..x).fold(E::ZERO, |s, j| {
                                    s.wrapping_add(E::from(u16::from(texels[j * C + c])))
                                });
                                let l = if with_lower { low0[i] } else { E::ZERO };
                                want_acc[i] = acc0[i].wrapping_add(l).wrapping_add(r);
                            }
                            let v = &want_acc[(x - 1) * C..x * C];
                            if boundary {
                                want_b.extend_from_slice(v);
                            } else {
                                want_l.extend_from_slice(v);
                            }
                        }
                        let mut acc = acc0.clone();
                        let mut low = low0.clone();
                        let mut bnd = std::vec![to(7); want_b.len()];
                        let mut local = std::vec![to(9); want_l.len()];
                        let got = row_fields::<u8, E, C>(
                            &texels,
                            with_lower.then_some(&mut low[..]),
                            &mut acc,
                            t,
                            &mut bnd,
                            &mut local,
                            [(core::ptr::null(), 0); 2],
                            None,
                        );
                        let what = (t, n, with_lower, C);
                        assert_eq!(got, Some((want_b.len(), want_l.len(), 0)), "{what:?}");
                        assert_eq!(acc, want_acc, "{what:?}");
                        if with_lower {
                            assert!(low.iter().all(|&v| v == E::ZERO), "{what:?}");
                        }
                        assert_eq!(bnd, want_b, "{what:?}");
                        assert_eq!(local, want_l, "{what:?}");
                    }
                }
            }
        }
        check::<u32, 1>(|v| v as u32);
        if !cfg!(miri) {
            check::<u64, 1>(|v| v);
        }
        check::<u32, 2>(|v| v as u32);
    }

    /// Rows of about a thousand positions (the other layout tests' textures are narrow):
    /// every corner of the layout equals the summed-area table computed directly, for one
    /// level of 8, 3 and 16 texels, the packed flat layout (no level), 2 in 4 and 2 in 6 in 12
    /// (the components above 0 from the boundaries), one and two channels, a width that ends
    /// inside a tile: many kernel blocks and whole groups of packed fields per row.
    #[test]
    fn wide_rows_every_corner() {
        // Under Miri (slow): one row pair, the 8 x 8 tiles and the flat layout.
        let (w, h) = if cfg!(miri) { (1030, 2) } else { (1100, 17) };
        // With `simd`, once per kernel this CPU runs (the builds take the widest allowed; the
        // band rows, `TiledBuilder::band_step`, under the AVX2 and the AVX-512 kernel alike):
        // widths 1,100 and 1,095, whose rows of boundaries start off a word every other row
        // and leave local sums after the kernel's steps of 16.
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        for k in crate::simd::Kernel::ALL
            .into_iter()
            .filter(|k| k.available())
        {
            k.cap(|| every_spec(w, h));
        }
        #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
        every_spec(w, h);
    }

    /// [`wide_rows_every_corner`]'s layouts and sizes.
    fn every_spec(w: usize, h: usize) {
        let check = wide_rows_check::<1>;
        for spec in [
            TiledSpec::tiles(8, 8).unwrap(),
            TiledSpec::tiles(3, 5).unwrap(),
            TiledSpec::tiles(16, 2).unwrap(),
            TiledSpec::FLAT_PACKED,
            TiledSpec::square(&[2, 4]).unwrap(),
            TiledSpec::square(&[2, 6, 12]).unwrap(),
        ]
        .into_iter()
        .filter(|s| {
            !cfg!(miri) || [TiledSpec::tiles(8, 8).unwrap(), TiledSpec::FLAT_PACKED].contains(s)
        }) {
            check(w, h, spec);
            if !cfg!(miri) {
                check(w - 5, h, spec);
                wide_rows_check::<2>(w, h, spec);
            }
        }
    }

    /// [`wide_rows_every_corner`]'s check: every corner of a `w x h` layout of `spec` built
    /// from noise against the summed-area table computed directly.
    fn wide_rows_check<const C: usize>(w: usize, h: usize, spec: TiledSpec) {
        use crate::NoCount;
        let texels = crate::layouts::tests::noise_bytes(w * h * C, (w * h) as u64);
        let tex = Texture::<u8, C>::new(&texels, w, h).unwrap();
        let mut words = std::vec![0u32; Tiled::<u32, C>::words_needed(spec, w, h, 8).unwrap()];
        let mut scratch = std::vec![0u32; Tiled::<u32, C>::scratch_needed(spec, w).unwrap()];
        let t = Tiled::<u32, C>::build(&tex, spec, &mut words, &mut scratch).unwrap();
        // S(x, y) row by row.
        let mut s = std::vec![[0u32; C]; (w + 1) * (h + 1)];
        for y in 1..=h {
            for x in 1..=w {
                for c in 0..C {
                    s[y * (w + 1) + x][c] = s[(y - 1) * (w + 1) + x][c]
                        .wrapping_add(s[y * (w + 1) + x - 1][c])
                        .wrapping_sub(s[(y - 1) * (w + 1) + x - 1][c])
                        .wrapping_add(u32::from(texels[((y - 1) * w + x - 1) * C + c]));
                }
            }
        }
        let step = if cfg!(miri) { 37 } else { 1 };
        for y in 0..=h {
            for x in (0..=w).step_by(step).chain([w]) {
                assert_eq!(
                    t.corner(x, y, &mut NoCount),
                    s[y * (w + 1) + x],
                    "{spec:?} {w}x{h} C {C} at ({x}, {y})"
                );
            }
        }
    }
}

/// The smallest layout (in words) whose rows the `simd` row steps prefetch: 256 KiB. A smaller
/// one stays in the L2 cache of a current x86-64 core between rows and builds (and the hardware
/// prefetchers follow its row streams), so the hints only cost instructions: about 100 per row,
/// 0.8 of 11.6 instructions per texel in a tiled build of 128^2
/// (`tools/examples/build_insns.py`).
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
const PREFETCH_MIN_WORDS: usize = 1 << 16;

/// When the band rows' kernels ask for the lines of a layout of `words` words
/// (`simd::Pace::for_layout` of its bytes; a size past `usize` is past the caches).
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
fn pace_for(words: usize) -> crate::simd::Pace {
    crate::simd::Pace::for_layout(words.saturating_mul(4))
}

/// Builds a [`Tiled`] layout one texture row at a time, holding one accumulator row per y
/// component (two for one level of tiles) plus one row of fields.
///
/// Per row `y`, ending a block of y level `q` (`q = 0` for 7 rows in 8 with 8 x 8 tiles): one
/// pass over the row (`row_fields`; with `simd`, one AVX-512 or AVX2 kernel) adds the row's sums
/// and the
/// level below (`q >= 1`) into the accumulator of level `q`, which holds the sums in the form
/// the fields are read in (inside a tile the local sum, at a tile boundary the total), and
/// splits it into the row's local sums `C_0q(X, y)` and tile boundaries; the local sums are
/// packed as row `iy` of component `(0, q)`, and the fields of the x levels above, `C_pq(X, y)
/// = acc_q[X] - acc_q[trunc_{p+1}(X)]`, are formed over the boundaries and packed as row `iy`
/// of component `(p, q)`: 32 fields at a time, each output word written once, in order (see
/// the module's "Storage order").
///
/// With `simd` on an AVX2 CPU, AVX-512 CPUs included (tiles 8 wide, `u8` texels into `u32`
/// entries, one channel, no modulus, a whole tile's sum below 2^16), the rows inside a tile
/// row keep acc_0 as the tile row's 16-bit column sums instead (`simd::band_row`): acc_0's
/// local sum at `X` is the prefix of the column sums inside the tile, and a boundary the
/// prefix of the tiles' column totals, so one 16-bit addition per texel and a prefix within
/// each tile give the row's fields, and the local sums are packed from 16 bits (with
/// AVX-512BW, DQ and VBMI, in the same pass, 32 columns at a time: tiled over flat 0.82x to 1.25x
/// at 1,024^2 and 1.06x to 1.23x at 4,096^2 in 20 of 25 runs on a Zen 4 guest, against 1.22x to
/// 1.65x at 4,096^2 before; docs/benchmarks.md, eleventh session). A row that ends a tile row
/// adds the column sums' form into acc_1 in one pass (`simd::band_end_row`; with AVX-512BW and DQ
/// and one level of tiles on x it packs components `(0, 1)` and `(1, 1)` in the same pass
/// when both rows start on a word, `band_end_step`: with the kernels' lines asked for at
/// their own pace, the tiled build of 4,096^2 took about 0.90x the time, 1.03x to 1.15x the
/// flat build in 14 runs; docs/benchmarks.md, twelfth session); a row that ends a higher
/// level, or a row of other texels, first turns the column sums back into acc_0.
#[derive(Debug)]
pub struct TiledBuilder<'a, 's, E: Entry, const C: usize = 1> {
    words: &'a mut [u32],
    scratch: &'s mut [E],
    geo: Geometry,
    /// `(w + 1) C`: one scratch row.
    row_len: usize,
    rows_done: usize,
    /// With `simd`: whether the level-0 accumulator row holds column sums in the band form
    /// (`simd::band_row`): entered at a row that starts a tile row, left (the row turned
    /// back) before a row of other texels or one that ends a higher level.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    band: bool,
    /// With `simd`: whether the geometry, the entries and the CPU allow the band form (levels
    /// on both axes, no modulus, `simd::band_applies`): asked once, not per row.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    band_fits: bool,
    /// With `simd`: the band form applies and the x axis has one level of tiles, so a band
    /// row writes components `(0, 0)` and `(1, 0)` only ([`TiledBuilder::band_step`]); their
    /// constants, looked up and checked once here instead of per row.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    band_one: Option<BandPlan>,
    /// As `band_one`, for the rows that end a tile row in the band form (`q = 1`:
    /// components `(0, 1)` and `(1, 1)`, [`TiledBuilder::band_end_step`]).
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    end_one: Option<BandPlan>,
}

/// [`TiledBuilder::band_step`]'s constants (`q = 0`) or [`TiledBuilder::band_end_step`]'s (`q
/// = 1`), from the geometry (`TiledBuilder::new`): the two components such a row writes, `(0,
/// q)` and `(1, q)`, where the row of fields splits, and the checks that hold for every row
/// (each row's field counts are `n / t` boundaries and `n - n / t` local sums, which fill the
/// components' rows exactly).
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
#[derive(Debug, Clone, Copy)]
struct BandPlan {
    /// Component `(0, q)`: the local sums.
    local: Component,
    /// Component `(1, q)`: the tile boundaries (one level: the running sums themselves).
    bnd: Component,
    /// The boundaries per row, `n / t`, and the local sums, `n - n / t`.
    nb: usize,
    nl: usize,
    /// Where the first scratch row splits: `(n / t + 1) C` (the boundaries after `acc[0]`).
    split: usize,
    /// The layout is large enough for prefetch hints (`PREFETCH_MIN_WORDS`).
    prefetch: bool,
    /// No modulus: every local sum is below `2^k` (the width proof), packed unmasked.
    exact: bool,
    /// The layout's words (`Geometry::words`), for the refusal of short storage.
    words: usize,
}

#[cfg(all(feature = "simd", target_arch = "x86_64"))]
impl BandPlan {
    /// Row `iy` of both components in `words` (`len` of them): each one's first bit and the
    /// words it spans, `None` past the end.
    fn rows(&self, len: usize, iy: u32) -> Option<[(u64, Range<usize>); 2]> {
        let span = |c: &Component| {
            let at = c.offset(0, iy);
            let from = usize::try_from(at / 32).ok()?;
            let to = usize::try_from(at.saturating_add(c.row_bits).div_ceil(32)).ok()?;
            (from <= to && to <= len).then_some((at, from..to))
        };
        Some([span(&self.local)?, span(&self.bnd)?])
    }

    /// The lines to ask for while the row is computed (both components' rows, as the general
    /// step asks), when the layout is large enough.
    fn ahead(&self, words: &[u32], rows: &[(u64, Range<usize>); 2]) -> Ahead {
        let mut ahead: Ahead = [(core::ptr::null(), 0); 2];
        if self.prefetch {
            for (a, (_, r)) in ahead.iter_mut().zip(rows) {
                if let Some(w) = words.get(r.clone()) {
                    *a = (w.as_ptr(), w.len());
                }
            }
        }
        ahead
    }

    /// When the band rows' kernels ask for their lines: evenly over the row for a layout past
    /// the caches (`simd::Pace::for_layout`).
    fn pace(&self) -> crate::simd::Pace {
        pace_for(self.words)
    }

    /// The refusal of storage shorter than the layout (`got` words).
    fn too_small(&self, got: usize) -> Error {
        Error::StorageTooSmall {
            needed: self.words,
            got,
        }
    }

    /// What both band steps start from: the row of fields `buf` split into the boundaries
    /// after `acc[0]` (not written here: the general step zeroes it) and the local sums; the
    /// refusal of short storage; row `iy` of both components ([`BandPlan::rows`]) and the
    /// lines to ask for ([`BandPlan::ahead`]).
    #[allow(
        clippy::type_complexity,
        reason = "the steps' five parts, destructured at once by both callers"
    )]
    fn start<'b, E: Entry, const C: usize>(
        &self,
        words: &[u32],
        buf: &'b mut [E],
        iy: u32,
        short: Error,
    ) -> Result<
        (
            &'b mut [E],
            &'b mut [E],
            Error,
            [(u64, Range<usize>); 2],
            Ahead,
        ),
        Error,
    > {
        let (bnd, local) = buf.split_at_mut_checked(self.split).ok_or(short)?;
        let bnd_out = bnd.get_mut(C..).ok_or(short)?;
        let too_small = self.too_small(words.len());
        let rows = self.rows(words.len(), iy).ok_or(too_small)?;
        let ahead = self.ahead(words, &rows);
        Ok((bnd_out, local, too_small, rows, ahead))
    }

    /// What both band steps end with: the row's field counts `(kb, kl)` checked against the
    /// plan (a mismatch would be a bug here, refused rather than written across the next
    /// row), then the local sums and the boundaries the kernel left (after the `packed`
    /// first of each) packed from the rows' first bits `at` (from a word boundary the
    /// packer's vector path takes them; the rest, if any, field by field).
    fn end<E: Entry>(
        &self,
        words: &mut [u32],
        at: [u64; 2],
        (local, bnd): (&[E], &[E]),
        (kb, kl): (usize, usize),
        (pl, pb): (usize, usize),
        short: Error,
    ) -> Result<(), Error> {
        if kb != self.nb || kl != self.nl {
            return Err(short);
        }
        let too_small = self.too_small(words.len());
        let (local, bnd) = (local.get(..kl).ok_or(short)?, bnd.get(..kb).ok_or(short)?);
        pack_rest(words, at[0], local, (pl, self.local.bits), short, too_small)?;
        pack_rest(words, at[1], bnd, (pb, self.bnd.bits), short, too_small)
    }

    /// The plan for `g` when a band row (`q = 0`) or a row that ends a tile row (`q = 1`)
    /// writes components `(0, q)` and `(1, q)` only (one level of tiles on x); `None` if any
    /// check fails (the general step then runs).
    fn new<const C: usize>(g: &Geometry, q: usize) -> Option<BandPlan> {
        if g.ax.levels != 1 {
            return None;
        }
        let (local, bnd) = (*g.component(0, q)?, *g.component(1, q)?);
        #[allow(
            clippy::as_conversions,
            reason = "u32 -> usize is lossless (MAX_DIMENSION)"
        )]
        let nb = div_by(g.width, g.ax.block(1) as usize)?;
        let split = nb.checked_add(1)?.checked_mul(C)?;
        let fills = |count: usize, c: &Component| {
            u64::try_from(count)
                .ok()
                .and_then(|n| n.checked_mul(u64::from(c.bits)))
                == Some(c.row_bits)
        };
        let nl = g.width.checked_sub(nb)?;
        (fills(nl, &local) && fills(nb, &bnd)).then_some(BandPlan {
            local,
            bnd,
            nb,
            nl,
            split,
            prefetch: g.words >= PREFETCH_MIN_WORDS,
            exact: g.spec.modulus.is_none(),
            words: g.words,
        })
    }
}

/// Packs `fields[done..]` (`bits` each) into `words` from bit `at + done bits`: the fields of
/// a component's row left after a kernel packed its first `done`. `short` for `done` past
/// the fields, `too_small` for words too short.
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
fn pack_rest<E: Entry>(
    words: &mut [u32],
    at: u64,
    fields: &[E],
    (done, bits): (usize, u32),
    short: Error,
    too_small: Error,
) -> Result<(), Error> {
    let rest = fields.get(done..).ok_or(short)?;
    if rest.is_empty() {
        return Ok(());
    }
    let from = u64::try_from(done)
        .ok()
        .and_then(|d| d.checked_mul(u64::from(bits)))
        .and_then(|b| b.checked_add(at))
        .ok_or(short)?;
    if pack_fields(words, from, rest, bits) {
        Ok(())
    } else {
        Err(too_small)
    }
}

/// The words of two disjoint ranges of `words`, mutably (`None` if they overlap or pass its
/// end).
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
fn two_rows(
    words: &mut [u32],
    a: Range<usize>,
    b: Range<usize>,
) -> Option<(&mut [u32], &mut [u32])> {
    if a.end <= b.start {
        let (lo, hi) = words.split_at_mut_checked(b.start)?;
        Some((lo.get_mut(a)?, hi.get_mut(..b.end.checked_sub(b.start)?)?))
    } else if b.end <= a.start {
        let (lo, hi) = words.split_at_mut_checked(a.start)?;
        Some((hi.get_mut(..a.end.checked_sub(a.start)?)?, lo.get_mut(b)?))
    } else {
        None
    }
}

impl<'a, 's, E: Entry, const C: usize> TiledBuilder<'a, 's, E, C> {
    /// A builder for a `w x h` texture of `texel_bits`-bit texels. Refuses a texture whose
    /// worst-case total does not fit `E`, or short storage.
    pub fn new(
        spec: TiledSpec,
        width: usize,
        height: usize,
        texel_bits: u32,
        words: &'a mut [u32],
        scratch: &'s mut [E],
    ) -> Result<Self, Error> {
        let geo = Geometry::new(spec, width, height, texel_bits, C)?;
        geo.check_value_type::<E>()?;
        geo.check_storage(words.len())?;
        let need = Tiled::<E, C>::scratch_needed(spec, width)?;
        let got = scratch.len();
        let scratch = scratch
            .get_mut(..need)
            .ok_or(Error::StorageTooSmall { needed: need, got })?;
        scratch.fill(E::ZERO);
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let band_fits = geo.ax.levels >= 1
            && geo.ay.levels >= 1
            && geo.spec.modulus.is_none()
            && crate::simd::band_applies::<E, C>(
                width,
                geo.ax.block(1),
                geo.ay.block(1),
                geo.texel_bits,
            );
        Ok(TiledBuilder {
            words,
            scratch,
            geo,
            // (w + 1) C <= need: no overflow.
            row_len: {
                #[allow(
                    clippy::arithmetic_side_effects,
                    reason = "(w + 1) C <= need, which scratch_needed computed with checks"
                )]
                let row_len = (width + 1) * C;
                row_len
            },
            rows_done: 0,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            band: false,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            band_fits,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            band_one: if band_fits {
                BandPlan::new::<C>(&geo, 0)
            } else {
                None
            },
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            end_one: if band_fits {
                BandPlan::new::<C>(&geo, 1)
            } else {
                None
            },
        })
    }

    /// Consumes the next texture row (`w * C` texels). A refused row (wrong length, a texel
    /// wider than `texel_bits`) changes nothing.
    pub fn push_row<T: Texel>(&mut self, texels: &[T]) -> Result<(), Error> {
        let TiledBuilder {
            words,
            scratch,
            geo: g,
            row_len,
            rows_done,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            band,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            band_fits,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            band_one,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            end_one,
        } = self;
        let row_len = *row_len;
        if *rows_done >= g.height {
            return Err(Error::TooManyRows);
        }
        // w C < (w + 1) C = row_len: no overflow.
        let n = g.width;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w C < (w + 1) C = row_len, computed with checks (scratch_needed)"
        )]
        let expected = n * C;
        if texels.len() != expected {
            return Err(Error::RowLength {
                expected,
                got: texels.len(),
            });
        }
        check_texel_width(texels, g.texel_bits)?;
        let short = Error::StorageTooSmall {
            needed: row_len,
            got: scratch.len(),
        };
        // The first scratch row holds the current row's tile boundaries and local sums (then
        // the fields of the x components above 0); then one accumulator row per y component,
        // acc_q[x] at x C.. for x = 0..=w (x = 0 always zero).
        let (buf, accs) = scratch.split_at_mut_checked(row_len).ok_or(short)?;
        // Row y ends a block of exactly one y component: that of its lowest non-zero digit
        // (a multiple of b_q with d_q != 0).
        #[allow(
            clippy::arithmetic_side_effects,
            clippy::as_conversions,
            reason = "rows_done < h (checked above), so y <= h < 2^31: no wrap, lossless"
        )]
        let y = (*rows_done + 1) as u32;
        let Some((q, iy)) = g.ay.lowest(y) else {
            return Err(short);
        };
        // With `simd`, the band form of the level-0 accumulator (`simd::band_row`: column
        // sums) for rows that end no tile row: entered at a row that starts a tile row (the
        // accumulator is zero there). A row that ends a tile row and no level above it (q = 1)
        // adds the form into acc_1 and clears the column sums (`simd::band_end_row`): the band
        // goes on. Before any other row the column sums are turned back into the accumulator
        // (a row ending a higher level reads it in its 32-bit form; one of other texels takes
        // the other path).
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let (band_row, band_end) = {
            let fits = *band_fits && crate::simd::band_types::<T, E, C>();
            let want = q == 0 && fits;
            let end = q == 1 && fits && *band;
            if *band && !want && !end {
                let acc0 = accs.get_mut(C..row_len).ok_or(short)?;
                if !crate::simd::band_flush::<E, C>(acc0) {
                    return Err(short);
                }
                *band = false;
            }
            #[allow(
                clippy::as_conversions,
                reason = "u32 -> usize is lossless (MAX_DIMENSION)"
            )]
            let starts = rem_by(*rows_done, g.ay.block(1) as usize) == Some(0);
            if want && starts {
                *band = true;
            }
            (want && *band, end)
        };
        // A band row of one level of tiles: the short step.
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        if let (true, Some(plan)) = (band_row, band_one) {
            let acc = accs.get_mut(C..row_len).ok_or(short)?;
            Self::band_step(words, plan, texels, buf, acc, iy, short)?;
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "rows_done < h (checked above)"
            )]
            {
                *rows_done += 1;
            }
            return Ok(());
        }
        // A row that ends a tile row in the band form, one level of tiles: the short step.
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        if let (true, Some(plan)) = (band_end, end_one) {
            // acc_0 (its first n positions: the band form) and acc_1.
            let (acc0, acc1) = accs.split_at_mut_checked(row_len).ok_or(short)?;
            let acc0 = acc0
                .get_mut(C..)
                .and_then(|a| a.get_mut(..n))
                .ok_or(short)?;
            let acc = acc1.get_mut(C..row_len).ok_or(short)?;
            Self::band_end_step(words, plan, texels, buf, acc0, acc, iy, short)?;
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "rows_done < h (checked above)"
            )]
            {
                *rows_done += 1;
            }
            return Ok(());
        }
        // Invariant between rows: acc_j holds the rows in [trunc_{j+1}(y), trunc_j(y)) for
        // j >= 1 and acc_0 those in [trunc_1(y), y). Here y is a multiple of b_1, ..., b_q, so
        // adding the row and acc_0, ..., acc_{q-1} into acc_q (and clearing them) leaves in
        // acc_q the rows of I_q(y) = [trunc_{q+1}(y), y], the sums C_pq(., y) need, and restores
        // the invariant. Levels 1..q-1 first (a pass over a row, 1 row in b_2); acc_{q-1} goes
        // with the row, in the row step's own pass.
        for j in 1..q {
            #[allow(
                clippy::arithmetic_side_effects,
                reason = "j < q <= Ly < MAX_LEVELS + 1 and (Ly + 2) row_len fits usize \
                          (scratch_needed): no overflow"
            )]
            let (lower, upper) = accs.split_at_mut_checked(j * row_len).ok_or(short)?;
            #[allow(clippy::arithmetic_side_effects, reason = "j >= 1; as above")]
            let below = lower.get_mut((j - 1) * row_len..).ok_or(short)?;
            let here = upper.get_mut(..row_len).ok_or(short)?;
            for (h, b) in here.iter_mut().zip(below.iter_mut()) {
                *h = h.wrapping_add(*b);
                *b = E::ZERO;
            }
        }
        let from = q.checked_mul(row_len).ok_or(short)?;
        let (below, at_q) = accs.split_at_mut_checked(from).ok_or(short)?;
        let acc = at_q.get_mut(C..row_len).ok_or(short)?;
        let lower = match from.checked_sub(row_len) {
            Some(f) => Some(
                below
                    .get_mut(f.checked_add(C).ok_or(short)?..)
                    .ok_or(short)?,
            ),
            None => None,
        };
        // The tile width b_1 (0 for an axis without levels: every position local), and the
        // first scratch row split: the boundaries after acc[0] = 0 ((n / t + 1) C values), then
        // the local sums (the rest: (n - n / t) C, as many as there are).
        #[allow(
            clippy::as_conversions,
            reason = "u32 -> usize is lossless (MAX_DIMENSION)"
        )]
        let t = if g.ax.levels >= 1 {
            g.ax.block(1) as usize
        } else {
            0
        };
        let nb = div_by(n, t).unwrap_or(0);
        let split = nb
            .checked_add(1)
            .and_then(|b| b.checked_mul(C))
            .ok_or(short)?;
        let (bnd, local) = buf.split_at_mut_checked(split).ok_or(short)?;
        bnd.get_mut(..C).ok_or(short)?.fill(E::ZERO);
        // The words this row's fields go to in the first two x components (with `simd`, the
        // row step asks for them while it computes: a table being built is usually not in
        // cache, and the packing would wait on each line).
        // The local sums' component row, which the row step may pack into directly (with
        // `simd`; the rest of its fields below). Not on other targets (flash).
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let (ahead, pace, pack) = {
            let mut ahead: Ahead = [(core::ptr::null(), 0); 2];
            let mut rows = [(0usize, 0usize); 2];
            for (p, (a, r)) in ahead.iter_mut().zip(&mut rows).enumerate() {
                if let Some(c) = g.component(p, q) {
                    let from = usize::try_from(c.offset(0, iy) / 32);
                    let to =
                        usize::try_from(c.offset(0, iy).saturating_add(c.row_bits).div_ceil(32));
                    if let (Ok(from), Ok(to)) = (from, to) {
                        if let Some(w) = words.get(from..to) {
                            // The component's row only: the next row asks for its own lines
                            // at its start, long before it packs (docs/benchmarks.md, "The
                            // tiled build's fixed costs and boundaries").
                            *a = (w.as_ptr(), w.len());
                            *r = (from, to);
                        }
                    }
                }
            }
            if g.words < PREFETCH_MIN_WORDS {
                ahead = [(core::ptr::null(), 0); 2];
            }
            let pace = pace_for(g.words);
            let [row0, _] = rows;
            let (bit0, k0) = g
                .component(0, q)
                .map_or((0, 0), |c| (c.offset(0, iy) % 32, c.bits));
            // Without a modulus every field is below 2^bits (the width proof): `exact`.
            let exact = g.spec.modulus.is_none();
            (
                ahead,
                pace,
                words.get_mut(row0.0..row0.1).map(|w| (w, bit0, k0, exact)),
            )
        };
        #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
        let (ahead, pack): (Ahead, _) = ([(core::ptr::null(), 0); 2], None);
        // acc_q += acc_{q-1} + the row's sums (row_fields: in the accumulators' form), split.
        // Wrapping additions: without a modulus every sum is at most the texture's total, which
        // `E` holds (`check_value_type`); with one, only the low k bits are stored, and those
        // of a sum depend only on the low k bits of its terms.
        let bnd_out = bnd.get_mut(C..).ok_or(short)?;
        // In the band form (q = 0: no level below), `acc` holds acc_0's column sums.
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let done = if band_row {
            let pack = pack.map(|(words, bit, k, exact)| crate::simd::PackTo {
                words,
                bit,
                k,
                exact,
            });
            crate::simd::band_row::<T, E, C>(texels, acc, bnd_out, local, (ahead, pace), pack)
        } else if band_end {
            // q = 1: `lower` is acc_0's storage (n positions from its first), in the band form.
            let acc0 = lower.and_then(|l| l.get_mut(..n)).ok_or(short)?;
            crate::simd::band_end_row::<T, E, C>(
                texels,
                acc0,
                acc,
                bnd_out,
                local,
                (ahead, pace),
                None,
            )
            .map(|(kb, kl, _, _)| (kb, kl, 0))
        } else {
            row_fields::<T, E, C>(texels, lower, acc, t, bnd_out, local, ahead, pack)
        };
        #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
        let done = row_fields::<T, E, C>(texels, lower, acc, t, bnd_out, local, ahead, pack);
        let (kb, kl, kp) = done.ok_or(short)?;
        // (Without `simd` nothing is packed in the row step: a constant, the code below folds.)
        let kp = if cfg!(all(feature = "simd", target_arch = "x86_64")) {
            kp
        } else {
            0
        };
        // Row iy of every component (p, q): for each stored x, C_pq(x, y) = acc_q[x] -
        // acc_q[trunc_{p+1}(x)], packed as one stream (the components are stored row by row).
        // p = 0: the local sums; p >= 1: the same differences over the tile boundaries (x a
        // multiple of t: positions x / t, blocks b_p / t), the top one (one level) being the
        // boundaries themselves.
        for p in 0..g.ax.components() {
            let comp = g.component(p, q).ok_or(short)?;
            let big = if p < g.ax.levels {
                g.ax.block(p.saturating_add(1))
            } else {
                0
            };
            #[allow(
                clippy::as_conversions,
                reason = "u32 -> usize is lossless (MAX_DIMENSION)"
            )]
            let (b, big) = (g.ax.block(p) as usize, big as usize);
            // p = 0: the first kp local sums are packed already (row_fields).
            let (fields, done) = if p == 0 {
                (local.get(..kl).ok_or(short)?, kp)
            } else {
                // p >= 1: t = b_1 >= 2 divides b_p and b_{p+1}.
                let (b, big) = (div_by(b, t).ok_or(short)?, div_by(big, t).ok_or(short)?);
                if b == 1 && big == 0 {
                    (bnd.get(C..kb.checked_add(C).ok_or(short)?).ok_or(short)?, 0)
                } else {
                    let count = component_fields::<E, C>(bnd, nb, b, big, local).ok_or(short)?;
                    (local.get(..count).ok_or(short)?, 0)
                }
            };
            // The stored positions, counted as Geometry::new counted them: a mismatch would
            // be a bug here, refused rather than written across the next row.
            let bits = u64::try_from(fields.len())
                .ok()
                .and_then(|c| c.checked_mul(u64::from(comp.bits)));
            if bits != Some(comp.row_bits) {
                return Err(short);
            }
            // (A component without stored positions on this axis has no fields, and 0 bits.)
            let rest = fields.get(done..).ok_or(short)?;
            let from = u64::try_from(done)
                .ok()
                .and_then(|d| d.checked_mul(u64::from(comp.bits)))
                .and_then(|b| b.checked_add(comp.offset(0, iy)))
                .ok_or(short)?;
            if !rest.is_empty() && !pack_fields(words, from, rest, comp.bits) {
                return Err(Error::StorageTooSmall {
                    needed: g.words,
                    got: words.len(),
                });
            }
        }
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "rows_done < h (checked above)"
        )]
        {
            *rows_done += 1;
        }
        Ok(())
    }

    /// Every row of `texture` from the next one on ([`Tiled::build`]'s rows): with `simd`, the
    /// band rows of a tile row in runs where they apply ([`TiledBuilder::push_band_rows`]),
    /// the others (and all without `simd`) by [`TiledBuilder::push_row`], the texture's pages
    /// asked for ahead of them (`simd::TexturePages`, x86-64). The same table.
    pub(super) fn push_texture<T: Texel>(
        &mut self,
        texture: &Texture<'_, T, C>,
    ) -> Result<(), Error> {
        // Whether runs can apply at all (the geometry, the types, the CPU): asked once here,
        // not per run (`band_one` is a plan only where the band form fits).
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let runs = self.band_one.is_some_and(|plan| {
            crate::simd::band_rows_apply::<T, E, C>(self.geo.width, plan.local.bits, plan.exact)
        });
        // The texture's pages asked for ahead of the rows (hints only).
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let mut pages = crate::simd::TexturePages::new(texture, self.rows_done);
        let mut y = self.rows_done;
        while y < texture.height() {
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            pages.ask(y);
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            if runs {
                let took = self.push_band_rows(texture)?;
                if took > 0 {
                    y = y.saturating_add(took);
                    continue;
                }
            }
            self.push_row(texture.row(y).ok_or(Error::EmptyTexture)?)?;
            y = y.saturating_add(1);
        }
        Ok(())
    }

    /// [`Tiled::build`]'s step for a run of the texture's next rows when they are band rows of
    /// one tile row (`q = 0`) and the band form applies with one level of tiles on x
    /// ([`BandPlan`]), on the paths of `simd::band_rows` (AVX-512 VBMI, which packs in the
    /// pass, whole pairs of blocks; or AVX2, rows a multiple of 128; the local sums' rows from
    /// a byte): the rest of the tile row's band
    /// rows, at least two, as many as `simd::MAX_BAND_ROWS` and the scratch row (their
    /// boundaries) hold. The same values and fields as [`TiledBuilder::push_row`] on each in
    /// turn (each row its own pass, in order), with the builder's per-row work (the plan's
    /// rows, the prefetch ranges, the checks, the packer's call for the boundaries: the
    /// component's rows follow each other) once per run: a tiled build of 1,024^2 in cache
    /// took about 0.87x the time, of 4,096^2 about 0.95x (docs/benchmarks.md, thirteenth
    /// session). Row by row inside the run, not 32 columns of every row in turn: that saves
    /// the column sums' store and load between the rows, but a cold build of 1,024^2 took
    /// 1.3x the time (the interleaved rows' lines). Returns how many rows it took; 0 (nothing
    /// changed) when the run does not apply, and the caller pushes the next row with
    /// `push_row`. A refused row (wrong length, a texel too wide) refuses the run before
    /// anything is written, with the error `push_row` gives for it (the rows before it in the
    /// run are not taken either, where `push_row` would have taken them: `Tiled::build`'s rows,
    /// whole rows of texels of `T::BITS`, are never refused).
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    fn push_band_rows<T: Texel>(&mut self, texture: &Texture<'_, T, C>) -> Result<usize, Error> {
        let TiledBuilder {
            words,
            scratch,
            geo: g,
            row_len,
            rows_done,
            band,
            band_one,
            ..
        } = self;
        // (Whether the runs apply at all was asked by `push_texture`; `simd::band_rows` checks
        // again before its kernel.)
        let Some(plan) = band_one.as_ref() else {
            return Ok(0);
        };
        #[allow(
            clippy::as_conversions,
            reason = "u32 -> usize is lossless (MAX_DIMENSION)"
        )]
        let b1 = g.ay.block(1) as usize;
        // Row rows_done + 1 + j is a band row while rows_done + 1 + j is not a multiple of b1:
        // b1 - 1 - pos of them are left in this tile row (b1 >= 2).
        let Some(pos) = rem_by(*rows_done, b1) else {
            return Ok(0);
        };
        if pos != 0 && !*band {
            return Ok(0);
        }
        let left = b1.saturating_sub(pos.saturating_add(1));
        let y = *rows_done;
        // As many as the texels' array and the scratch row (their boundaries) hold.
        let r = left
            .min(crate::simd::MAX_BAND_ROWS)
            .min(g.height.saturating_sub(y))
            .min(div_by(*row_len, plan.nb).unwrap_or(0));
        if r < 2 {
            return Ok(0);
        }
        let mut texels: [&[T]; crate::simd::MAX_BAND_ROWS] = [&[]; crate::simd::MAX_BAND_ROWS];
        for (j, t) in texels.iter_mut().enumerate().take(r) {
            *t = texture
                .row(y.saturating_add(j))
                .ok_or(Error::EmptyTexture)?;
        }
        let rows = texels.get(..r).unwrap_or(&[]);
        let n = g.width;
        let expected = n.checked_mul(C).ok_or(Error::TooManyRows)?;
        for row in rows {
            if row.len() != expected {
                return Err(Error::RowLength {
                    expected,
                    got: row.len(),
                });
            }
            check_texel_width(row, g.texel_bits)?;
        }
        // The rows' indices in components (0, 0) and (1, 0): consecutive (one tile row).
        #[allow(
            clippy::arithmetic_side_effects,
            clippy::as_conversions,
            reason = "rows_done + r <= h < 2^31 (MAX_DIMENSION): no wrap, lossless"
        )]
        let (y0, y1) = ((*rows_done + 1) as u32, (*rows_done + r) as u32);
        let (Some((0, iy0)), Some((0, iy1))) = (g.ay.lowest(y0), g.ay.lowest(y1)) else {
            return Ok(0);
        };
        #[allow(
            clippy::as_conversions,
            reason = "usize -> u64 is lossless; r <= MAX_BAND_ROWS"
        )]
        let rn = r as u64;
        if Some(u64::from(iy1)) != u64::from(iy0).checked_add(rn.saturating_sub(1)) {
            return Ok(0);
        }
        let short = Error::StorageTooSmall {
            needed: *row_len,
            got: scratch.len(),
        };
        let (buf, accs) = scratch.split_at_mut_checked(*row_len).ok_or(short)?;
        let acc = accs.get_mut(C..*row_len).ok_or(short)?;
        let too_small = plan.too_small(words.len());
        // Both components' rows iy0..=iy1: their first bits and the words they span.
        let span = |c: &Component| {
            let at = c.offset(0, iy0);
            let bits = c.row_bits.checked_mul(rn)?;
            let from = usize::try_from(at / 32).ok()?;
            let to = usize::try_from(at.checked_add(bits)?.div_ceil(32)).ok()?;
            (from <= to && to <= words.len()).then_some((at, from..to))
        };
        let ((at0, row0), (at1, row1)) = (
            span(&plan.local).ok_or(too_small)?,
            span(&plan.bnd).ok_or(too_small)?,
        );
        let [_, bnd_lines] = plan.ahead(words, &[(at0, row0.clone()), (at1, row1)]);
        let ahead = (!bnd_lines.0.is_null()).then_some(bnd_lines);
        let nb = r.checked_mul(plan.nb).ok_or(short)?;
        let bnd = buf.get_mut(..nb).ok_or(short)?;
        let out = crate::simd::PackTo {
            words: words.get_mut(row0).ok_or(too_small)?,
            bit: at0 % 32,
            k: plan.local.bits,
            exact: plan.exact,
        };
        if !crate::simd::band_rows::<T, E, C>(rows, acc, bnd, (ahead, plan.pace()), out) {
            return Ok(0);
        }
        if !pack_fields(words, at1, bnd, plan.bnd.bits) {
            return Err(too_small);
        }
        *band = true;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "rows_done + r <= h (r bounded above)"
        )]
        {
            *rows_done += r;
        }
        Ok(r)
    }

    /// [`TiledBuilder::push_row`]'s step for a row in the band form (`q = 0`,
    /// `simd::band_row`) when the x axis has one level of tiles: it writes components `(0, 0)`
    /// (the local sums, which the band kernel packs) and `(1, 0)` (the boundaries) only. The
    /// same values, fields and refusals as the general step, without its loops over the levels
    /// below `q` and over the x components, and with what they look up and check per row
    /// looked up and checked once ([`BandPlan`]), and the boundaries handed to the packer
    /// straight from a word boundary: the builder's share of a tiled build of 1,024^2 (its
    /// own code and `pack_fields`, averaged over every row, callgrind) went from 414
    /// instructions per row to 315 with the plan (docs/benchmarks.md, sixth session).
    /// `acc` is acc_0's row (its column sums), `buf` the row of fields.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    fn band_step<T: Texel>(
        words: &mut [u32],
        plan: &BandPlan,
        texels: &[T],
        buf: &mut [E],
        acc: &mut [E],
        iy: u32,
        short: Error,
    ) -> Result<(), Error> {
        let (bnd_out, local, too_small, rows, ahead) = plan.start::<E, C>(words, buf, iy, short)?;
        let [(at0, ref row0), (at1, _)] = rows;
        let pack = crate::simd::PackTo {
            words: words.get_mut(row0.clone()).ok_or(too_small)?,
            bit: at0 % 32,
            k: plan.local.bits,
            exact: plan.exact,
        };
        let (kb, kl, kp) = crate::simd::band_row::<T, E, C>(
            texels,
            acc,
            bnd_out,
            local,
            (ahead, plan.pace()),
            Some(pack),
        )
        .ok_or(short)?;
        plan.end(
            words,
            [at0, at1],
            (local, bnd_out),
            (kb, kl),
            (kp, 0),
            short,
        )
    }

    /// [`TiledBuilder::push_row`]'s step for a row that ends a tile row in the band form (`q
    /// = 1`, `simd::band_end_row`) when the x axis has one level of tiles: it writes
    /// components `(0, 1)` (the local sums) and `(1, 1)` (the boundaries) only, the same
    /// values, fields and refusals as the general step, with the plan's constants
    /// ([`BandPlan`]). When both rows start on a word, the kernel packs them as it computes them
    /// (with AVX-512BW and DQ: `simd::band512::end_row_packed`); the fields it leaves go to the
    /// packer. `acc0` is acc_0's row (its column sums, `n` positions), `acc` acc_1's, `buf` the row
    /// of fields.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    #[allow(
        clippy::too_many_arguments,
        reason = "push_row's parts, split for the borrows; one call site"
    )]
    fn band_end_step<T: Texel>(
        words: &mut [u32],
        plan: &BandPlan,
        texels: &[T],
        buf: &mut [E],
        acc0: &mut [E],
        acc: &mut [E],
        iy: u32,
        short: Error,
    ) -> Result<(), Error> {
        let (bnd_out, local, _, rows, ahead) = plan.start::<E, C>(words, buf, iy, short)?;
        let [(at0, ref row0), (at1, ref row1)] = rows;
        let (k0, k1) = (plan.local.bits, plan.bnd.bits);
        // Both rows from a word (disjoint: two components' rows), for the kernel to pack.
        let rows_words = if at0 % 32 == 0 && at1 % 32 == 0 {
            two_rows(words, row0.clone(), row1.clone())
        } else {
            None
        };
        let pack = rows_words.map(|(w0, w1)| crate::simd::EndPackTo {
            local: (w0, k0),
            bnd: (w1, k1),
        });
        let packed = crate::simd::band_end_row::<T, E, C>(
            texels,
            acc0,
            acc,
            bnd_out,
            local,
            (ahead, plan.pace()),
            pack,
        );
        let (kb, kl, pl, pb) = packed.ok_or(short)?;
        plan.end(
            words,
            [at0, at1],
            (local, bnd_out),
            (kb, kl),
            (pl, pb),
            short,
        )
    }

    /// Checks that every row arrived and returns the layout.
    pub fn finish(self) -> Result<Tiled<'a, E, C>, Error> {
        if self.rows_done != self.geo.height {
            return Err(Error::MissingRows {
                got: self.rows_done,
                expected: self.geo.height,
            });
        }
        Ok(Tiled {
            words: self.words,
            geo: self.geo,
            _e: core::marker::PhantomData,
        })
    }
}
