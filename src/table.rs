//! Building and holding a summed-area table (Crow §3.0).
//!
//! Entry `(i, j)` of the stored (inclusive) table is the sum of texels `(i', j')` with
//! `i' <= i` and `j' <= j`, per channel. The build keeps a running sum `r` along the row and adds
//! the entry above: `entry(i, j) = r(i, j) + entry(i, j - 1)`, `r(i, j) = r(i - 1, j) + t(i, j)`:
//! two additions per entry and channel, as Crow counts.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::cost::per_channel;
use crate::error::{Error, Quantity};
use crate::rect::Rect;
use crate::texel::{Entry, Texel};
use crate::texture::{check_dimensions, Texture};
use crate::width;

/// A summed-area table over borrowed storage.
///
/// `E` is the entry type (`u16`, `u32`, `u64`); `C` the number of interleaved channels. Once
/// built (or validated by [`Sat::from_table`]) the table is monotone and its largest entry per
/// channel is the whole-texture sum, which the lookups' width checks rely on.
#[derive(Debug, Clone, Copy)]
pub struct Sat<'a, E: Entry, const C: usize = 1> {
    table: &'a [E],
    width: usize,
    height: usize,
    texel_bits: u32,
    total: [E; C],
}

/// One addition of the build: plain where the width proof covers it, checked otherwise.
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "CHECKED = false only after width::check_entry_worst_case proved m w h < 2^BITS for the \
              texel width: every running sum and entry is the sum of a sub-rectangle, at most that"
)]
fn add<E: Entry, const CHECKED: bool>(a: E, b: E) -> Result<E, ()> {
    if CHECKED {
        a.checked_add(b).ok_or(())
    } else {
        Ok(a + b)
    }
}

/// One row of the build: `out = prefix sums of texels (per channel) + above`.
///
/// With `CHECKED = false` the caller has proved (worst-case analysis) that no sum can exceed
/// `E`; with `CHECKED = true` every addition is checked and an overflow is an error.
///
/// Out of line on purpose: inlined into the row loop of [`Sat::build`], the loop's own state
/// left LLVM too few registers, and it indexed the three rows with one counter (8 instructions
/// per entry on the Cortex-M4); in a function of its own the loop walks them with
/// post-incremented pointers and a count-down (7, like a hand-written loop), for one call per
/// row (`examples/firmware/count-insns.sh`: 8.34 -> 7.59 per entry of a 64 x 64 table; 7.57
/// since [`Sat::build`] walks the table's rows with `chunks_exact_mut`).
#[inline(never)]
fn build_row<T: Texel, E: Entry, const C: usize, const CHECKED: bool>(
    texels: &[T],
    above: Option<&[E]>,
    out: &mut [E],
) -> Result<(), ()> {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    if !CHECKED && crate::simd::build_row::<T, E, C>(texels, above, out) {
        return Ok(());
    }
    #[cfg(all(feature = "simd", texsat_armv7em))]
    if !CHECKED && crate::dsp::build_row::<T, E, C>(texels, above, out) {
        return Ok(());
    }
    let mut run = [E::ZERO; C];
    match above {
        None => {
            for (o, t) in out.chunks_exact_mut(C).zip(texels.chunks_exact(C)) {
                for ((o, t), r) in o.iter_mut().zip(t).zip(run.iter_mut()) {
                    *r = add::<E, CHECKED>(*r, E::from(t.to_u16()))?;
                    *o = *r;
                }
            }
        }
        Some(above) => {
            for ((o, t), a) in out
                .chunks_exact_mut(C)
                .zip(texels.chunks_exact(C))
                .zip(above.chunks_exact(C))
            {
                for (((o, t), a), r) in o.iter_mut().zip(t).zip(a).zip(run.iter_mut()) {
                    *r = add::<E, CHECKED>(*r, E::from(t.to_u16()))?;
                    *o = add::<E, CHECKED>(*r, *a)?;
                }
            }
        }
    }
    Ok(())
}

/// The error of a build addition that overflows `E`.
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "E::BITS is 16, 32 or 64 (Entry is sealed): + 1 does not wrap"
)]
fn entry_overflow<E: Entry>() -> Error {
    Error::TooWide {
        what: Quantity::Entry,
        bits_needed: E::BITS + 1,
        bits_available: E::BITS,
    }
}

/// `w * h * C` entries, or an error if that overflows `usize` (a 32-bit target, a corrupt header).
pub(crate) const fn entries_needed<const C: usize>(
    width: usize,
    height: usize,
) -> Result<usize, Error> {
    let too_large = Error::TextureTooLarge {
        dimension: if width > height { width } else { height },
    };
    match width.checked_mul(height) {
        Some(v) => match v.checked_mul(C) {
            Some(n) => Ok(n),
            None => Err(too_large),
        },
        None => Err(too_large),
    }
}

/// Exact bits of the largest channel total of a texture (the error path of the checked build),
/// summed in two 64-bit words (at most `2^31 x 2^31` texels of 16 bits: below `2^78`).
fn actual_total_bits<T: Texel, const C: usize>(texture: &Texture<'_, T, C>) -> u32 {
    let mut totals = [(0u64, 0u64); C];
    for y in 0..texture.height() {
        if let Some(row) = texture.row(y) {
            for px in row.chunks_exact(C) {
                for ((hi, lo), p) in totals.iter_mut().zip(px) {
                    let (v, carry) = lo.overflowing_add(u64::from(p.to_u16()));
                    *lo = v;
                    // The total is below 2^78 (above): the high word stays below 2^14.
                    *hi = hi.wrapping_add(u64::from(carry));
                }
            }
        }
    }
    totals
        .iter()
        .map(|&(hi, lo)| {
            if hi != 0 {
                #[allow(clippy::arithmetic_side_effects, reason = "bits_of_u64 <= 64")]
                let bits = 64 + crate::width::bits_of_u64(hi);
                bits
            } else {
                crate::width::bits_of_u64(lo)
            }
        })
        .max()
        .unwrap_or(0)
}

impl<'a, E: Entry, const C: usize> Sat<'a, E, C> {
    /// Builds the table of `texture` into `storage` (its first `w * h * C` entries), after
    /// proving from the texel width alone that no entry can overflow `E`
    /// ([`width::check_entry_worst_case`]). Nothing is written if the proof fails.
    ///
    /// With the `simd` feature, a table of `u8` texels of one channel into `u32` entries of 1
    /// MiB and more (rows of at most 4,096 entries) is built row by row in a working row of at
    /// most 16 KiB (in a 20 KiB buffer on the stack), each row copied to the table in the same
    /// pass: the next row reads the row above from L1, not from table lines still on their way
    /// from memory (cold, 1,024^2 took 0.7x to 0.8x the time on a Zen 4 guest). From 32 MiB
    /// the copies are non-temporal stores (in each row that starts on 16 bytes): such a table
    /// would not stay in cache anyway, and the stores skip reading each line before writing it
    /// (0.75x the time at 4,096^2). Such a table is then not in cache after the build
    /// (docs/benchmarks.md).
    pub fn build<T: Texel>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
    ) -> Result<Self, Error> {
        width::check_entry_worst_case(T::BITS, texture.width(), texture.height(), E::BITS)?;
        Self::build_impl::<T, false>(texture, storage)
    }

    /// Builds the table with every addition checked, so a texture whose *actual* sums fit `E`
    /// is accepted even where the worst case is refused. On overflow the error names the exact
    /// bits the data needs; the storage then holds a partial table and no `Sat` is returned.
    pub fn build_checked<T: Texel>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
    ) -> Result<Self, Error> {
        Self::build_impl::<T, true>(texture, storage).map_err(|e| match e {
            Error::TooWide {
                what: Quantity::Entry,
                ..
            } => Error::TooWide {
                what: Quantity::Entry,
                bits_needed: actual_total_bits(texture),
                bits_available: E::BITS,
            },
            other => other,
        })
    }

    fn build_impl<T: Texel, const CHECKED: bool>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
    ) -> Result<Self, Error> {
        let (w, h) = (texture.width(), texture.height());
        let needed = entries_needed::<C>(w, h)?;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w C <= w h C = needed, which entries_needed computed without overflow"
        )]
        let row_len = w * C;
        let got = storage.len();
        let Some(table) = storage.get_mut(..needed) else {
            return Err(Error::StorageTooSmall { needed, got });
        };
        let overflow = entry_overflow::<E>();
        if row_len == 0 {
            return Err(Error::EmptyTexture);
        }
        // With `simd`, a table of 1 MiB and more: rows built in a working row in L1 and written
        // to the table in the same pass, past the caches by non-temporal stores
        // (`simd::build_via_working_row`; nothing written where it declines).
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        if !CHECKED
            && crate::simd::build_via_working_row::<T, E, C>(table, row_len, |y| texture.row(y))
        {
            let table: &'a [E] = storage.get(..needed).unwrap_or(&[]);
            return Self::from_parts(table, w, h, T::BITS);
        }
        // `table` is exactly `h` rows of `row_len` entries: `chunks_exact_mut` walks them.
        let mut above: Option<&[E]> = None;
        for (y, out) in table.chunks_exact_mut(row_len).enumerate() {
            let texels = texture.row(y).ok_or(Error::EmptyTexture)?;
            build_row::<T, E, C, CHECKED>(texels, above, out).map_err(|_| overflow)?;
            above = Some(out);
        }
        let table: &'a [E] = storage.get(..needed).unwrap_or(&[]);
        Self::from_parts(table, w, h, T::BITS)
    }

    /// The table over exactly `w * h * C` entries; its last entry per channel is the total.
    fn from_parts(
        table: &'a [E],
        width: usize,
        height: usize,
        texel_bits: u32,
    ) -> Result<Self, Error> {
        let total = table
            .last_chunk::<C>()
            .copied()
            .ok_or(Error::StorageTooSmall {
                needed: C,
                got: table.len(),
            })?;
        Ok(Sat {
            table,
            width,
            height,
            texel_bits,
            total,
        })
    }

    /// Entries a `width x height` table with `C` channels needs, for sizing a `static` at
    /// compile time: `w * h * C`, or [`Error::TextureTooLarge`] if that overflows `usize` (or a
    /// side is zero or above `2^31 - 1`).
    ///
    /// ```
    /// use texsat::Sat;
    /// const ENTRIES: usize = match Sat::<u32, 1>::entries_needed(64, 64) {
    ///     Ok(n) => n,
    ///     Err(_) => panic!("texture too large"),
    /// };
    /// static mut TABLE: [u32; ENTRIES] = [0; ENTRIES];
    /// ```
    pub const fn entries_needed(width: usize, height: usize) -> Result<usize, Error> {
        if let Err(e) = check_dimensions(width, height, C) {
            return Err(e);
        }
        entries_needed::<C>(width, height)
    }

    /// Wraps a table built elsewhere (in flash, by [`RowStreamBuilder`], by an RTL model),
    /// after checking that it is the SAT of some texture of `texel_bits`-bit texels: every texel
    /// it implies, `S(i,j) - S(i-1,j) - S(i,j-1) + S(i-1,j-1)`, must lie in `[0, 2^b - 1]`.
    /// This check (`O(w h)`) is what lets the lookups rely on monotonicity.
    pub fn from_table(
        table: &'a [E],
        width: usize,
        height: usize,
        texel_bits: u32,
    ) -> Result<Self, Error> {
        check_dimensions(width, height, C)?;
        width::check_texel_bits(texel_bits)?;
        let needed = entries_needed::<C>(width, height)?;
        if table.len() < needed {
            return Err(Error::StorageTooSmall {
                needed,
                got: table.len(),
            });
        }
        let table = table.get(..needed).unwrap_or(&[]);
        // The implied texel `S(x,y) - S(x-1,y) - S(x,y-1) + S(x-1,y-1)` must lie in [0, max]:
        // checked as the difference of the two column strips `(S(x,y) - S(x,y-1)) - (S(x-1,y)
        // - S(x-1,y-1))`, in the entry type with checked subtractions: on a valid table both
        // strips are sums of texels (no underflow) and every intermediate is at most S(x,y), so
        // no valid table is refused for want of a bit (a sum such as S(x,y) + S(x-1,y-1) may
        // not fit the word); an underflow means an invalid table. Nothing wider.
        let max = E::max_texel(texel_bits);
        let zero_row = [E::ZERO; 0];
        let mut above: &[E] = &zero_row;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w C <= w h C = needed, which entries_needed computed without overflow"
        )]
        let row_len = (width * C).max(1);
        for (y, row) in table.chunks_exact(row_len).enumerate() {
            for x in 0..width {
                for c in 0..C {
                    #[allow(
                        clippy::arithmetic_side_effects,
                        reason = "x < w <= 2^31 - 1, so x + 1 <= w and, for 1 <= x <= w and c < C, \
                                  (x - 1) C + c < w C = row_len (entries_needed: no overflow)"
                    )]
                    let at = |r: &[E], x: usize| -> E {
                        if x == 0 {
                            E::ZERO
                        } else {
                            r.get((x - 1) * C + c).copied().unwrap_or(E::ZERO)
                        }
                    };
                    #[allow(clippy::arithmetic_side_effects, reason = "x < w <= 2^31 - 1")]
                    let (s, sl, su, sul) =
                        (at(row, x + 1), at(row, x), at(above, x + 1), at(above, x));
                    let ok = match (s.checked_sub(su), sl.checked_sub(sul)) {
                        (Some(right), Some(left)) => {
                            right.checked_sub(left).is_some_and(|t| t <= max)
                        }
                        _ => false,
                    };
                    if !ok {
                        return Err(Error::InvalidTable { x, y, channel: c });
                    }
                }
            }
            above = row;
        }
        Self::from_parts(table, width, height, texel_bits)
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Bits per texel of the source texture.
    pub fn texel_bits(&self) -> u32 {
        self.texel_bits
    }

    /// The stored entries, row-major, channels interleaved (`w * h * C`).
    pub fn entries(&self) -> &'a [E] {
        self.table
    }

    /// The whole-texture sum per channel (the last entry).
    pub fn total(&self) -> [E; C] {
        self.total
    }

    /// Bits of the largest whole-texture sum over the channels: what the lookups' accumulators
    /// must hold (see [`crate::width`]).
    pub fn total_bits(&self) -> u32 {
        self.total
            .iter()
            .map(|t| crate::width::bits_of_u64(t.to_u64()))
            .max()
            .unwrap_or(0)
    }

    /// Table bytes as stored (`w * h * C * size_of::<E>()`).
    pub fn table_bytes(&self) -> usize {
        core::mem::size_of_val(self.table)
    }

    /// The corner function `S(x, y)` (integral over `[0, x) x [0, y)`) for `x <= w`, `y <= h`;
    /// `None` outside. Zero on the row `y = 0` and the column `x = 0`.
    pub fn corner(&self, x: usize, y: usize) -> Option<[E; C]> {
        if x > self.width || y > self.height {
            None
        } else {
            Some(self.s(x, y))
        }
    }

    /// The 4-read box sum `S(x1, y1) - S(x0, y1) - S(x1, y0) + S(x0, y0)` over `[x0, x1) x [y0,
    /// y1)` for a scene whose boxes lie inside the texture (a plan with `leaves_texture: false`
    /// and integer corners): no boundary mode, no area bookkeeping, the sum in the entry word
    /// itself (exact: the table is monotone, so no difference wraps and the sum is at most the
    /// total, which `E` holds). A box that is inverted or reaches outside `[0, w] x [0, h]` is
    /// [`Error::CoordinateOutOfRange`], never clipped or wrapped. 4 reads (fewer on the zero row
    /// and column), 3 additive operations per channel; for the mean use
    /// [`Sat::box_sum_int`] or divide by the area yourself.
    #[inline]
    pub fn box_sum_inside(&self, r: &Rect<u32>) -> Result<[E; C], Error> {
        #[allow(
            clippy::as_conversions,
            reason = "u32 -> usize is lossless: usize has at least 32 bits (MAX_DIMENSION)"
        )]
        let (x0, y0, x1, y1) = (r.x0 as usize, r.y0 as usize, r.x1 as usize, r.y1 as usize);
        // The common case first: `1 <= x0 <= x1 <= w` and `1 <= y0 <= y1 <= h` (`x0 - 1 < x1`
        // in wrapping arithmetic is `1 <= x0 <= x1`), where all four corners are stored
        // entries and each read is one range check that never fails on a built table (a
        // compare and a branch, where a read that may land on the zero row needs a compare
        // and a select: 44 instructions per call on the Cortex-M4 against 49). An inverted
        // box, one past the texture, and a box on the zero row or column (whose corners read
        // as zero) take the out-of-line path.
        let (x0m, y0m) = (x0.wrapping_sub(1), y0.wrapping_sub(1));
        if x0m >= x1 || y0m >= y1 || x1 > self.width || y1 > self.height {
            return self.box_sum_inside_edge(x0, y0, x1, y1);
        }
        let w = self.width;
        // x1, y1 >= 1 here; every index is below `w h`, which entries_needed computed without
        // overflow, so the wrapping operations are the plain ones.
        let (row0, row1, x1m) = (
            y0m.wrapping_mul(w),
            y1.wrapping_sub(1).wrapping_mul(w),
            x1.wrapping_sub(1),
        );
        let at = |i: usize| -> Option<[E; C]> {
            self.table
                .get(i.wrapping_mul(C)..)
                .and_then(|t| t.first_chunk::<C>())
                .copied()
        };
        // A table shorter than `w h C` (impossible after a build) refuses, never panics.
        let Some(d) = at(row1.wrapping_add(x1m)) else {
            return Err(Error::CoordinateOutOfRange);
        };
        let Some(c) = at(row1.wrapping_add(x0m)) else {
            return Err(Error::CoordinateOutOfRange);
        };
        let Some(b) = at(row0.wrapping_add(x1m)) else {
            return Err(Error::CoordinateOutOfRange);
        };
        let Some(a) = at(row0.wrapping_add(x0m)) else {
            return Err(Error::CoordinateOutOfRange);
        };
        let mut out = [E::ZERO; C];
        for (((o, d), c), (b, a)) in out.iter_mut().zip(d).zip(c).zip(b.iter().zip(a)) {
            *o = d.wrapping_sub(c).wrapping_sub(b.wrapping_sub(a));
        }
        Ok(out)
    }

    /// [`Sat::box_sum_inside`] for the boxes its common case leaves: inverted, past the
    /// texture, or on the zero row or column. Out of line: a firmware whose boxes start inside
    /// pays for it only in flash (216 bytes on the Cortex-M4).
    #[inline(never)]
    fn box_sum_inside_edge(
        &self,
        x0: usize,
        y0: usize,
        x1: usize,
        y1: usize,
    ) -> Result<[E; C], Error> {
        if x0 > x1 || y0 > y1 || x1 > self.width || y1 > self.height {
            return Err(Error::CoordinateOutOfRange);
        }
        let mut out = [E::ZERO; C];
        // Each read is one range check on a wrapping index, `((y - 1) w + x - 1) C`: on the
        // zero row (`y = 0`) every index wraps below zero (above `w h C` as an unsigned
        // number: `w C <= w h C < 2^(usize::BITS - 1)`, slices being at most `isize::MAX`
        // bytes), so it reads nothing; the zero column (`x0 = 0`) is one test for both of its
        // reads. For corners with `x, y >= 1` the wrapping index equals the plain one (below
        // `w h C`, computed without overflow). An empty box needs no test of its own: for
        // `x0 = x1 >= 1` or `y0 = y1` the reads cancel exactly; only `x0 = x1 = 0`, where the
        // index of `x1 - 1` would wrap into the row before, returns early.
        let w = self.width;
        let (row0, row1) = (
            y0.wrapping_sub(1).wrapping_mul(w),
            y1.wrapping_sub(1).wrapping_mul(w),
        );
        let at = |i: usize| -> [E; C] {
            self.table
                .get(i.wrapping_mul(C)..)
                .and_then(|t| t.first_chunk::<C>())
                .copied()
                .unwrap_or([E::ZERO; C])
        };
        let x1m = x1.wrapping_sub(1);
        let (i1, i0) = (row1.wrapping_add(x1m), row0.wrapping_add(x1m));
        let (d, b) = (at(i1), at(i0));
        let (c, a) = if x0 == 0 {
            if x1 == 0 {
                return Ok(out);
            }
            ([E::ZERO; C], [E::ZERO; C])
        } else {
            let bw = x1.wrapping_sub(x0);
            (at(i1.wrapping_sub(bw)), at(i0.wrapping_sub(bw)))
        };
        for (((o, d), c), (b, a)) in out.iter_mut().zip(d).zip(c).zip(b.iter().zip(a)) {
            *o = d.wrapping_sub(c).wrapping_sub(b.wrapping_sub(a));
        }
        Ok(out)
    }

    /// `S(x, y)` for `x <= w`, `y <= h` (callers guarantee the range).
    ///
    /// No panic path: the index is in range by construction (`x <= w`, `y <= h` and the table
    /// holds `w h C` entries); an index outside would read as zero.
    #[inline(always)]
    pub(crate) fn s(&self, x: usize, y: usize) -> [E; C] {
        if x == 0 || y == 0 {
            return [E::ZERO; C];
        }
        // Wrapping: for x <= w, y <= h (every caller: `Layout::corner` checks, the lookups place
        // their boxes in range) the index is below w h C, which entries_needed computed without
        // overflow, so it equals the plain expression; outside, no panic path.
        let base = y
            .wrapping_sub(1)
            .wrapping_mul(self.width)
            .wrapping_add(x.wrapping_sub(1))
            .wrapping_mul(C);
        self.table
            .get(base..)
            .and_then(|t| t.first_chunk::<C>())
            .copied()
            .unwrap_or([E::ZERO; C])
    }

    /// `[S(xa, ya), S(xb, ya), S(xa, yb), S(xb, yb)]`, reads counted as by [`Sat::read`]; zero
    /// (and no read) for a corner outside `[0, w] x [0, h]`, however far (a row or column
    /// offset that would overflow reads nothing). [`Layout::quad`](crate::Layout::quad).
    #[inline(always)]
    pub(crate) fn read_quad<K: crate::Counter>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[E; C]; 4] {
        self.read_quad_with::<K, true>(xa, xb, ya, yb, k)
    }

    /// [`Sat::read_quad`] for corners placed in `[0, w] x [0, h]` (the lookups): wrapping
    /// coordinates, equal to the checked ones there (`box_sum_int` 85 instructions on the
    /// Cortex-M4 against 86); outside, unspecified values and no panic path.
    #[inline(always)]
    pub(crate) fn read_quad_placed<K: crate::Counter>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[E; C]; 4] {
        self.read_quad_with::<K, false>(xa, xb, ya, yb, k)
    }

    /// The four reads of [`Sat::read_quad`] (`CHECKED`: overflow-checked offsets) and
    /// [`Sat::read_quad_placed`] (wrapping ones).
    ///
    /// Two row slices of exactly `w C` entries, one range check each; the reads index them at
    /// `(x - 1) C` with `x <= w`, which the compiler sees, so they carry no check of their own
    /// (4-read box: 63 instructions on the Cortex-M4 against 71 through four [`Sat::s`]). `y =
    /// 0` (the zero row) gives no row and `x = 0` is the zero column; a row past the table, or
    /// a table shorter than `w h C` (impossible after a build), reads as zero: no panic path.
    #[inline(always)]
    fn read_quad_with<K: crate::Counter, const CHECKED: bool>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[E; C]; 4] {
        let zero = [E::ZERO; C];
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w C <= w h C, which entries_needed computed without overflow"
        )]
        let row_len = self.width * C;
        let row = |y: usize| -> Option<&[E]> {
            if CHECKED {
                // A `y` so large that its row's start overflows reads nothing.
                let start = y.checked_sub(1)?.checked_mul(row_len)?;
                self.table.get(start..start.checked_add(row_len)?)
            } else {
                // `y = 0` wraps the row's start past its end: no row.
                let start = y.wrapping_sub(1).wrapping_mul(row_len);
                self.table.get(start..start.wrapping_add(row_len))
            }
        };
        let mut at = |row: Option<&[E]>, x: usize, y: usize| -> [E; C] {
            let Some(row) = row else { return zero };
            if x == 0 {
                return zero;
            }
            // x >= 1 here; for x <= w, (x - 1) C < w C; past the row (or, checked, a product
            // that overflows, possible only for C > 1) nothing is read.
            let start = if CHECKED {
                match x.wrapping_sub(1).checked_mul(C) {
                    Some(s) => s,
                    None => return zero,
                }
            } else {
                x.wrapping_sub(1).wrapping_mul(C)
            };
            match row.get(start..).and_then(|t| t.first_chunk::<C>()) {
                Some(v) => {
                    k.reads(1, const { per_channel(E::BITS, C) });
                    k.words(const { per_channel(E::BITS, C).div_ceil(32) });
                    k.read_at(
                        crate::Region::Table,
                        self.entry_bit_offset(x, y),
                        const { per_channel(E::BITS, C) },
                    );
                    *v
                }
                None => zero,
            }
        };
        let (ra, rb) = (row(ya), row(yb));
        [
            at(ra, xa, ya),
            at(ra, xb, ya),
            at(rb, xa, yb),
            at(rb, xb, yb),
        ]
    }

    /// Bit offset of `S(x, y)` (`x, y >= 1`) in the table, for [`crate::Counter::read_at`]:
    /// `((y - 1) w + (x - 1)) C E::BITS` (wrapping: only a counter that records it computes it).
    #[inline(always)]
    #[allow(
        clippy::as_conversions,
        reason = "usize -> u64 is lossless (usize::BITS <= 64)"
    )]
    fn entry_bit_offset(&self, x: usize, y: usize) -> u64 {
        (y.wrapping_sub(1) as u64)
            .wrapping_mul(self.width as u64)
            .wrapping_add(x.wrapping_sub(1) as u64)
            .wrapping_mul(C as u64)
            .wrapping_mul(u64::from(E::BITS))
    }

    /// `S(x, y)` with its read counted (reads of the zero row and column are free).
    #[inline(always)]
    pub(crate) fn read<K: crate::Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        if x != 0 && y != 0 {
            k.reads(1, const { per_channel(E::BITS, C) });
            k.words(const { per_channel(E::BITS, C).div_ceil(32) });
            k.read_at(
                crate::Region::Table,
                self.entry_bit_offset(x, y),
                const { per_channel(E::BITS, C) },
            );
        }
        self.s(x, y)
    }
}

/// Most strips [`Sat::build_strips`] cuts a texture into (its jobs live on the stack).
pub const MAX_STRIPS: usize = 64;

/// One unit of work of [`Sat::build_strips`], for the caller's executor: call
/// [`StripJob::run`] on every job it is given, in any order, on any threads.
///
/// A job borrows the texture and its own disjoint part of the table storage; it is `Send` when
/// the texel and entry types are (always, for the crate's types).
#[derive(Debug)]
pub struct StripJob<'t, 's, T: Texel, E: Entry, const C: usize> {
    texture: &'t Texture<'t, T, C>,
    /// Texture rows `y0..y1`.
    y0: usize,
    y1: usize,
    kind: JobKind<'s, E>,
    done: bool,
}

#[derive(Debug)]
enum JobKind<'s, E> {
    /// Column sums of the strip's rows into `out` (`w C` entries).
    ColumnSums { out: &'s mut [E] },
    /// The table rows `y0..y1` onto the table row `above` (none for the first strip).
    Rows {
        above: Option<&'s [E]>,
        out: &'s mut [E],
    },
    /// No work (the only row of a one-row strip is done by the carry pass).
    Empty,
}

impl<'t, 's, T: Texel, E: Entry, const C: usize> StripJob<'t, 's, T, E, C> {
    /// A job with nothing to do (the unused slots of the job array).
    fn empty(texture: &'t Texture<'t, T, C>) -> Self {
        StripJob {
            texture,
            y0: 0,
            y1: 0,
            kind: JobKind::Empty,
            done: false,
        }
    }

    /// Does the job (again, harmlessly, if run twice). Additions are unchecked:
    /// [`Sat::build_strips`] proved the whole texture's worst case first, and every value
    /// formed is the sum over a sub-rectangle of it.
    pub fn run(&mut self) {
        match &mut self.kind {
            JobKind::ColumnSums { out } => {
                out.fill(E::ZERO);
                // Four rows per pass over `out` (a quarter of its reads and writes; the texel
                // sums vectorize): every partial sum is a column strip's, at most the total.
                let t = |a: &T| E::from(a.to_u16());
                let mut y = self.y0;
                while y.saturating_add(4) <= self.y1 {
                    let row = |k: usize| self.texture.row(y.saturating_add(k)).unwrap_or(&[]);
                    let (r0, r1, r2, r3) = (row(0), row(1), row(2), row(3));
                    // Plain additions (the proof above), one expression per entry, so the loop
                    // vectorizes (a chain of `Result`s kept it scalar: 1.8x the flat build for
                    // a sequential strip build, docs/benchmarks.md).
                    for ((((o, a), b), c), d) in out.iter_mut().zip(r0).zip(r1).zip(r2).zip(r3) {
                        #[allow(
                            clippy::arithmetic_side_effects,
                            reason = "every partial sum is a column strip's, at most the \
                                      texture's worst-case total, which E holds (checked first)"
                        )]
                        {
                            *o = *o + ((t(a) + t(b)) + (t(c) + t(d)));
                        }
                    }
                    y = y.saturating_add(4);
                }
                for y in y..self.y1 {
                    if let Some(row) = self.texture.row(y) {
                        for (o, a) in out.iter_mut().zip(row) {
                            if let Ok(v) = add::<E, false>(*o, t(a)) {
                                *o = v;
                            }
                        }
                    }
                }
            }
            JobKind::Rows { above, out } => {
                let rows = self.y1.saturating_sub(self.y0);
                let row_len = out.len().checked_div(rows).unwrap_or(0);
                let mut above: Option<&[E]> = *above;
                let mut rest: &mut [E] = out;
                for y in self.y0..self.y1 {
                    let (Some(texels), Some((row, tail))) =
                        (self.texture.row(y), rest.split_at_mut_checked(row_len))
                    else {
                        return;
                    };
                    if build_row::<T, E, C, false>(texels, above, row).is_err() {
                        return;
                    }
                    above = Some(row);
                    rest = tail;
                }
            }
            JobKind::Empty => {}
        }
        self.done = true;
    }

    /// Texture rows `(first, end)` the job covers.
    pub fn rows(&self) -> (usize, usize) {
        (self.y0, self.y1)
    }
}

impl<'a, E: Entry, const C: usize> Sat<'a, E, C> {
    /// [`Sat::build`] cut into `strips` horizontal strips whose work the caller's `execute`
    /// runs (on threads, say): `execute` gets a slice of jobs and must call [`StripJob::run`] on
    /// each, in any order, before it returns. The table is identical to [`Sat::build`]'s.
    ///
    /// Two rounds of jobs and one pass over the table: (1) each strip sums its columns into the
    /// storage of its own last table row; then here, in order, each of those rows becomes the
    /// strip's last table row: the last row of the strip above plus the prefix sums of the
    /// column sums along x (`O(w strips)` additions); (2) each strip builds its other rows onto
    /// the last row of the strip above. The width proof is [`Sat::build`]'s, for the whole
    /// texture, before anything is written; every value formed is a sum over a sub-rectangle.
    /// `strips` is clamped to `1..=min(h, MAX_STRIPS)`. A job left unrun is
    /// [`Error::MissingRows`] (the table is then incomplete and no `Sat` is returned).
    ///
    /// ```
    /// use texsat::{Sat, Texture};
    /// let texels: Vec<u8> = (0..64 * 48).map(|i| (i * 7 % 256) as u8).collect();
    /// let texture = Texture::<u8>::new(&texels, 64, 48)?;
    /// let (mut a, mut b) = (vec![0u32; 64 * 48], vec![0u32; 64 * 48]);
    /// // One thread here; with rayon: `|jobs| jobs.par_iter_mut().for_each(|j| j.run())`.
    /// let s = Sat::build_strips(&texture, &mut a, 5, |jobs| jobs.iter_mut().for_each(|j| j.run()))?;
    /// assert_eq!(s.entries(), Sat::build(&texture, &mut b)?.entries());
    /// # Ok::<(), texsat::Error>(())
    /// ```
    pub fn build_strips<T: Texel, X>(
        texture: &Texture<'_, T, C>,
        storage: &'a mut [E],
        strips: usize,
        mut execute: X,
    ) -> Result<Self, Error>
    where
        X: for<'t, 's> FnMut(&mut [StripJob<'t, 's, T, E, C>]),
    {
        let (w, h) = (texture.width(), texture.height());
        width::check_entry_worst_case(T::BITS, w, h, E::BITS)?;
        let needed = entries_needed::<C>(w, h)?;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "w C <= w h C = needed, which entries_needed computed without overflow"
        )]
        let row_len = w * C;
        let got = storage.len();
        let Some(table) = storage.get_mut(..needed) else {
            return Err(Error::StorageTooSmall { needed, got });
        };
        let n = strips.clamp(1, h.clamp(1, MAX_STRIPS));
        // Strip k covers rows [k h / n, (k + 1) h / n): n <= h, so none is empty.
        #[allow(
            clippy::arithmetic_side_effects,
            clippy::as_conversions,
            reason = "k <= n <= 64 and h < 2^31: k h < 2^37 fits u64; n >= 1; usize -> u64 is \
                      lossless"
        )]
        let bound = |k: usize| -> usize {
            let v = (k as u64) * (h as u64) / (n as u64);
            usize::try_from(v).unwrap_or(h)
        };
        let missing = |done: usize| Error::MissingRows {
            got: done,
            expected: h,
        };

        // Round 1: each strip's column sums into its last row.
        {
            let mut rest: &mut [E] = &mut *table;
            let mut jobs: [StripJob<'_, '_, T, E, C>; MAX_STRIPS] = core::array::from_fn(|k| {
                let mut job = StripJob::empty(texture);
                if k < n {
                    let (y0, y1) = (bound(k), bound(k.saturating_add(1)));
                    let rows = y1.saturating_sub(y0).saturating_sub(1);
                    let taken = core::mem::take(&mut rest);
                    if let Some((_, after)) =
                        taken.split_at_mut_checked(rows.saturating_mul(row_len))
                    {
                        if let Some((last, tail)) = after.split_at_mut_checked(row_len) {
                            job = StripJob {
                                texture,
                                y0,
                                y1,
                                kind: JobKind::ColumnSums { out: last },
                                done: false,
                            };
                            rest = tail;
                        }
                    }
                }
                job
            });
            run_round(&mut jobs, n, &mut execute).map_err(missing)?;
        }

        // The carry pass: each strip's last row, in order.
        {
            let mut above: Option<&[E]> = None;
            let mut rest: &mut [E] = &mut *table;
            for k in 0..n {
                let (y0, y1) = (bound(k), bound(k.saturating_add(1)));
                let rows = y1.saturating_sub(y0).saturating_sub(1);
                let taken = core::mem::take(&mut rest);
                let Some((_, after)) = taken.split_at_mut_checked(rows.saturating_mul(row_len))
                else {
                    return Err(missing(y0));
                };
                let Some((last, tail)) = after.split_at_mut_checked(row_len) else {
                    return Err(missing(y0));
                };
                let mut run = [E::ZERO; C];
                // Unchecked additions (the proof): each value is a sum over rows 0..y1.
                for (i, o) in last.chunks_exact_mut(C).enumerate() {
                    let a = above.and_then(|a| a.get(i.saturating_mul(C)..)?.first_chunk::<C>());
                    for (c, (o, r)) in o.iter_mut().zip(run.iter_mut()).enumerate() {
                        *r = add::<E, false>(*r, *o).map_err(|_| missing(y0))?;
                        let up = a.and_then(|a| a.get(c)).copied().unwrap_or(E::ZERO);
                        *o = add::<E, false>(*r, up).map_err(|_| missing(y0))?;
                    }
                }
                above = Some(last);
                rest = tail;
            }
        }

        // Round 2: each strip's other rows onto the last row of the strip above.
        {
            let mut above: Option<&[E]> = None;
            let mut rest: &mut [E] = &mut *table;
            let mut jobs: [StripJob<'_, '_, T, E, C>; MAX_STRIPS] = core::array::from_fn(|k| {
                let mut job = StripJob::empty(texture);
                if k < n {
                    let (y0, y1) = (bound(k), bound(k.saturating_add(1)));
                    let rows = y1.saturating_sub(y0).saturating_sub(1);
                    let taken = core::mem::take(&mut rest);
                    if let Some((body, after)) =
                        taken.split_at_mut_checked(rows.saturating_mul(row_len))
                    {
                        if let Some((last, tail)) = after.split_at_mut_checked(row_len) {
                            job = StripJob {
                                texture,
                                y0,
                                y1: y0.saturating_add(rows),
                                kind: if rows == 0 {
                                    JobKind::Empty
                                } else {
                                    JobKind::Rows { above, out: body }
                                },
                                done: false,
                            };
                            above = Some(last);
                            rest = tail;
                        }
                    }
                }
                job
            });
            run_round(&mut jobs, n, &mut execute).map_err(missing)?;
        }
        let table: &'a [E] = storage.get(..needed).unwrap_or(&[]);
        Self::from_parts(table, w, h, T::BITS)
    }
}

/// Hands the first `n` jobs to `execute`; `Err(first row of the first job left unrun)`.
fn run_round<T: Texel, E: Entry, const C: usize, X>(
    jobs: &mut [StripJob<'_, '_, T, E, C>; MAX_STRIPS],
    n: usize,
    execute: &mut X,
) -> Result<(), usize>
where
    X: for<'t, 's> FnMut(&mut [StripJob<'t, 's, T, E, C>]),
{
    let live = jobs.get_mut(..n).unwrap_or(&mut []);
    execute(live);
    match jobs.iter().take(n).find(|j| !j.done) {
        Some(j) => Err(j.y0),
        None => Ok(()),
    }
}

/// Builds a table one texture row at a time, holding only the previous table row.
///
/// For sources larger than RAM (a sensor, a flash image): push each texture row; each call
/// returns the finished table row, which the caller stores wherever the table lives (external
/// RAM, flash, an RTL test vector file). The rows are bit-identical to [`Sat::build`]'s: the
/// same two additions per entry in the same order, in place (host-tests compare them bit for
/// bit). The width check runs in [`RowStreamBuilder::new`]; rows of texels no wider than the
/// bits given there use unchecked additions, wider ones checked additions.
#[derive(Debug)]
pub struct RowStreamBuilder<'a, E: Entry, const C: usize = 1> {
    row: &'a mut [E],
    width: usize,
    height: usize,
    texel_bits: u32,
    rows_done: usize,
    /// Whether `push_row_into` writes `out` by non-temporal stores: a table of at least
    /// `simd::STREAM_MIN_BYTES` (decided once, in `new`).
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    stream: bool,
}

/// One row of the build in place: `row` holds the row above on entry (ignored for the first row)
/// and the new row on exit. The same additions as [`build_row`], in the same order.
#[inline]
fn build_row_in_place<T: Texel, E: Entry, const C: usize, const CHECKED: bool>(
    texels: &[T],
    row: &mut [E],
    first: bool,
) -> Result<(), ()> {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    if !CHECKED && crate::simd::build_row_in_place::<T, E, C>(texels, row, first, None, false) {
        return Ok(());
    }
    #[cfg(all(feature = "simd", texsat_armv7em))]
    if !CHECKED && crate::dsp::build_row_in_place::<T, E, C>(texels, row, first, None) {
        return Ok(());
    }
    // Two loops, not a test of `first` per entry: the firmware's opt-level "s" does not
    // unswitch loops (the streaming build on the Cortex-M4: `count-insns.sh`, row 6b).
    let mut run = [E::ZERO; C];
    let pixels = row.chunks_exact_mut(C).zip(texels.chunks_exact(C));
    if first {
        for (o, t) in pixels {
            for ((o, t), r) in o.iter_mut().zip(t).zip(run.iter_mut()) {
                *r = add::<E, CHECKED>(*r, E::from(t.to_u16()))?;
                *o = *r;
            }
        }
    } else {
        for (o, t) in pixels {
            for ((o, t), r) in o.iter_mut().zip(t).zip(run.iter_mut()) {
                *r = add::<E, CHECKED>(*r, E::from(t.to_u16()))?;
                *o = add::<E, CHECKED>(*r, *o)?;
            }
        }
    }
    Ok(())
}

/// [`build_row_in_place`] that also writes the new row to `copy` (as long as `row`), in the same
/// pass: what a caller storing the table would otherwise do with a second pass over the row.
/// With `simd`, `stream` makes the copy's stores non-temporal where the kernel applies (a large
/// table: `simd::STREAM_MIN_BYTES`); the values are the same.
#[inline]
fn build_row_in_place_copy<T: Texel, E: Entry, const C: usize, const CHECKED: bool>(
    texels: &[T],
    row: &mut [E],
    first: bool,
    copy: &mut [E],
    #[cfg_attr(
        not(all(feature = "simd", target_arch = "x86_64")),
        allow(unused_variables)
    )]
    stream: bool,
) -> Result<(), ()> {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    if !CHECKED
        && crate::simd::build_row_in_place::<T, E, C>(texels, row, first, Some(copy), stream)
    {
        return Ok(());
    }
    #[cfg(all(feature = "simd", texsat_armv7em))]
    if !CHECKED && crate::dsp::build_row_in_place::<T, E, C>(texels, row, first, Some(copy)) {
        return Ok(());
    }
    // Two loops, as in `build_row_in_place`.
    let mut run = [E::ZERO; C];
    let pixels = row
        .chunks_exact_mut(C)
        .zip(texels.chunks_exact(C))
        .zip(copy.chunks_exact_mut(C));
    if first {
        for ((o, t), c) in pixels {
            for (((o, t), c), r) in o.iter_mut().zip(t).zip(c).zip(run.iter_mut()) {
                *r = add::<E, CHECKED>(*r, E::from(t.to_u16()))?;
                *o = *r;
                *c = *r;
            }
        }
    } else {
        for ((o, t), c) in pixels {
            for (((o, t), c), r) in o.iter_mut().zip(t).zip(c).zip(run.iter_mut()) {
                *r = add::<E, CHECKED>(*r, E::from(t.to_u16()))?;
                *o = add::<E, CHECKED>(*r, *o)?;
                *c = *o;
            }
        }
    }
    Ok(())
}

impl<'a, E: Entry, const C: usize> RowStreamBuilder<'a, E, C> {
    /// A builder for a `width x height` texture of `texel_bits`-bit texels; `row_storage` must
    /// hold at least `width * C` entries. Refuses sizes whose worst case overflows `E`.
    pub fn new(
        width: usize,
        height: usize,
        texel_bits: u32,
        row_storage: &'a mut [E],
    ) -> Result<Self, Error> {
        check_dimensions(width, height, C)?;
        width::check_entry_worst_case(texel_bits, width, height, E::BITS)?;
        let needed = entries_needed::<C>(width, 1)?;
        let got = row_storage.len();
        let Some(row) = row_storage.get_mut(..needed) else {
            return Err(Error::StorageTooSmall { needed, got });
        };
        Ok(RowStreamBuilder {
            // A table past the caches (its bytes saturating: a product past `usize` is past
            // the threshold too).
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            stream: crate::simd::past_the_caches(
                needed
                    .saturating_mul(height)
                    .saturating_mul(core::mem::size_of::<E>()),
            ),
            row,
            width,
            height,
            texel_bits,
            rows_done: 0,
        })
    }

    /// Consumes the next texture row (`width * C` texels) and returns the table row it yields.
    /// The texel type must have the bits given to [`RowStreamBuilder::new`] or fewer.
    pub fn push_row<T: Texel>(&mut self, texels: &[T]) -> Result<&[E], Error> {
        if self.rows_done >= self.height {
            return Err(Error::TooManyRows);
        }
        if texels.len() != self.row.len() {
            return Err(Error::RowLength {
                expected: self.row.len(),
                got: texels.len(),
            });
        }
        // The new row overwrites the old in place, which is safe because entry i only needs
        // above[i]. `new` proved the worst case for `texel_bits`; texels of at most that many
        // bits take the plain additions, wider ones (whose values may exceed the proof) the
        // checked ones.
        let overflow = entry_overflow::<E>();
        let first = self.rows_done == 0;
        if T::BITS <= self.texel_bits {
            build_row_in_place::<T, E, C, false>(texels, self.row, first)
        } else {
            build_row_in_place::<T, E, C, true>(texels, self.row, first)
        }
        .map_err(|_| overflow)?;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "rows_done < height (checked above)"
        )]
        {
            self.rows_done += 1;
        }
        Ok(self.row)
    }

    /// [`RowStreamBuilder::push_row`] that also writes the finished table row into `out`
    /// (`width * C` entries, for instance the row's place in a table), in the same pass over the
    /// row: the same entries as `push_row` followed by `out.copy_from_slice(row)`, without the
    /// second pass. Nothing is written to `out` if the row is refused.
    ///
    /// With the `simd` feature, for a table of 32 MiB and more (`width * C * height` entries,
    /// `u8` texels of one channel into `u32` entries), `out` is written by non-temporal stores
    /// where it starts on 16 bytes, as [`Sat::build`] writes such a table: the row is not left
    /// in cache (0.71x the time at 4,096^2 on a Zen 4 guest, docs/benchmarks.md); the entries
    /// are the same.
    pub fn push_row_into<T: Texel>(&mut self, texels: &[T], out: &mut [E]) -> Result<(), Error> {
        if self.rows_done >= self.height {
            return Err(Error::TooManyRows);
        }
        if texels.len() != self.row.len() {
            return Err(Error::RowLength {
                expected: self.row.len(),
                got: texels.len(),
            });
        }
        if out.len() != self.row.len() {
            return Err(Error::StorageTooSmall {
                needed: self.row.len(),
                got: out.len(),
            });
        }
        let overflow = entry_overflow::<E>();
        let first = self.rows_done == 0;
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let stream = self.stream;
        #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
        let stream = false;
        if T::BITS <= self.texel_bits {
            build_row_in_place_copy::<T, E, C, false>(texels, self.row, first, out, stream)
        } else {
            build_row_in_place_copy::<T, E, C, true>(texels, self.row, first, out, stream)
        }
        .map_err(|_| overflow)?;
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "rows_done < height (checked above)"
        )]
        {
            self.rows_done += 1;
        }
        Ok(())
    }

    /// Width of the texture in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows pushed so far.
    pub fn rows_done(&self) -> usize {
        self.rows_done
    }

    /// Checks that every row arrived and returns the last table row (its last entry per channel
    /// is the whole-texture sum).
    pub fn finish(self) -> Result<&'a [E], Error> {
        if self.rows_done != self.height {
            return Err(Error::MissingRows {
                got: self.rows_done,
                expected: self.height,
            });
        }
        Ok(self.row)
    }
}
