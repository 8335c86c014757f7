//! Table layouts: how the corner function `S(x, y)` is stored, and what reading it costs.
//!
//! Every layout implements [`Layout`]: "give me `S(x, y)` for `0 <= x <= w`, `0 <= y <= h`,
//! and count what you read". The lookups ([`crate::BoxLookup`]: 4-read, 16-read in both forms,
//! the shortcut, every boundary mode) are written once against this trait.
//!
//! | layout | what is stored | `S(x, y)` costs |
//! |---|---|---|
//! | [`crate::Sat`] | the flat table in native words (`u16`/`u32`/`u64`) | 1 read |
//! | [`Tiled`] | a hierarchy of tiles: local sums, edge strips and corners, each packed at its exact width (no levels: the flat table packed at its exact width) | one field per level pair, 1 to 3 words each |
//! | [`Modular`] | the flat table modulo `2^k`, packed at `k` bits | 1 field |
//!
//! See `docs/layouts.md` for the derivations, bits per entry and reads per lookup.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

mod modular;
pub mod packed;
pub(crate) mod tiled;

pub use modular::{modulus_bits_for, Modular, ModularBuilder};

/// Words of a [`Tiled`] layout with `channels` channels given at run time (the scene plan's
/// sizes; [`Tiled::words_needed`] is the same for a compile-time `C`).
pub(crate) const fn tiled_words(
    spec: TiledSpec,
    width: usize,
    height: usize,
    texel_bits: u32,
    channels: usize,
) -> Result<usize, crate::Error> {
    tiled::words_for_channels(spec, width, height, texel_bits, channels)
}

/// Words of a [`Modular`] layout with `channels` channels given at run time.
pub(crate) const fn modular_words(
    width: usize,
    height: usize,
    k: u32,
    channels: usize,
) -> Result<usize, crate::Error> {
    modular::words_for_channels(width, height, k, channels)
}
pub use tiled::{AxisLevels, Tiled, TiledBuilder, TiledSpec, MAX_LEVELS};

use crate::cost::Counter;
use crate::table::Sat;
use crate::texel::Entry;

/// Storage of the corner function of a texture with `C` channels.
pub trait Layout<const C: usize> {
    /// The type corner values are returned in.
    type Value: Entry;
    /// Width of the texture in texels.
    fn width(&self) -> usize;
    /// Height of the texture in texels.
    fn height(&self) -> usize;
    /// Bits per texel.
    fn texel_bits(&self) -> u32;
    /// Bits of the largest corner value the lookups may see (the whole-texture sum; for a
    /// modular layout, `k`).
    fn value_bits(&self) -> u32;
    /// `Some(k)` if values are residues modulo `2^k` (see [`Modular`]): the lookups then reduce
    /// every box-bounded difference modulo `2^k` and refuse boxes whose sums may reach `2^k`.
    /// `None` (the default) for layouts that store `S` itself.
    #[inline(always)]
    fn modulus(&self) -> Option<u32> {
        None
    }
    /// Bits of storage the layout occupies (all channels), for bits per entry.
    fn storage_bits(&self) -> u64;
    /// `S(x, y)` per channel (mod `2^k` for a modular layout), for `x <= w` and `y <= h`;
    /// reports the words it reads to `k`. `S(0, y) = S(x, 0) = 0` are never stored or read.
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [Self::Value; C];
    /// The four corners `[S(xa, ya), S(xb, ya), S(xa, yb), S(xb, yb)]` for `xa, xb <= w` and
    /// `ya, yb <= h`: what a 4-read box sum (`xb >= xa`, `yb >= ya`) and each corner of a
    /// 16-read lookup (`xb = xa + 1`, `yb = ya + 1`) read. The same values and counts as four
    /// [`Layout::corner`] calls (the default); a layout overrides it where the four share work
    /// (the flat table: two row slices, one range check each, instead of four index checks).
    #[inline(always)]
    fn quad<K: Counter>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[Self::Value; C]; 4] {
        [
            self.corner(xa, ya, k),
            self.corner(xb, ya, k),
            self.corner(xa, yb, k),
            self.corner(xb, yb, k),
        ]
    }
    /// The corners of cell `(i, j)`, `[S(i, j), S(i + 1, j), S(i, j + 1), S(i + 1, j + 1)]`
    /// for `i < w`, `j < h`: what one corner of a 16-read lookup reads. [`Layout::quad`] by
    /// default; the flat table keeps four [`Layout::corner`] calls (one multiply-add each
    /// beats two row slices there), a tiled layout shares the fields of the tile level.
    #[inline(always)]
    fn cell_corners<K: Counter>(&self, i: usize, j: usize, k: &mut K) -> [[Self::Value; C]; 4] {
        self.quad(i, i.wrapping_add(1), j, j.wrapping_add(1), k)
    }
    /// [`Layout::quad`] for corners the caller has placed in `[0, w] x [0, h]` (the lookups):
    /// a layout may skip the range check here. Outside that range the values are unspecified
    /// (never a panic). Hidden: callers outside the crate use [`Layout::quad`].
    #[doc(hidden)]
    #[inline(always)]
    fn quad_placed<K: Counter>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[Self::Value; C]; 4] {
        self.quad(xa, xb, ya, yb, k)
    }
    /// [`Layout::cell_corners`] for a cell the caller has placed (`i < w`, `j < h`: the 16-read
    /// lookups' `split_coord`), with the same licence as [`Layout::quad_placed`]. Hidden.
    #[doc(hidden)]
    #[inline(always)]
    fn cell_corners_placed<K: Counter>(
        &self,
        i: usize,
        j: usize,
        k: &mut K,
    ) -> [[Self::Value; C]; 4] {
        self.cell_corners(i, j, k)
    }
    /// The corners of the four cells a 16-read lookup reads, placed as for
    /// [`Layout::cell_corners_placed`], in the order `(i[1], j[1])`, `(i[1], j[0])`, `(i[0],
    /// j[1])`, `(i[0], j[0])` (reads counted in that order). A layout may share work between
    /// the four (the tiled one: one call, one geometry load, the digits of each coordinate once).
    /// Under a modulus `k` ([`Layout::modulus`]) a layout may return any values congruent to the
    /// stored ones modulo `2^k`: every lookup reduces its differences modulo `2^k` before it
    /// uses them (`lookup::stable`'s `small`, `lookup::paper`'s final reduction), so the tiled
    /// one leaves its four cells' sums of fields unreduced (one test of the modulus fewer on the
    /// plain path). Hidden.
    #[doc(hidden)]
    #[inline(always)]
    fn cells4_placed<K: Counter>(
        &self,
        i: [usize; 2],
        j: [usize; 2],
        k: &mut K,
    ) -> [[[Self::Value; C]; 4]; 4] {
        cells4_by_cell(self, i, j, k)
    }
    /// Bits per texel and channel: `storage_bits / (w h C)`.
    #[allow(
        clippy::as_conversions,
        reason = "a float ratio for reports: the counts convert to the nearest f64 (exact below 2^53; \
                  no From<u64> or From<usize> for f64)"
    )]
    fn bits_per_entry(&self) -> f64 {
        self.storage_bits() as f64 / (self.width() as f64 * self.height() as f64 * C as f64)
    }
}

/// The four cells of a 16-read lookup read one by one, in [`Layout::cells4_placed`]'s order
/// (the default, and a layout's fallback when it cannot share work between them).
#[inline(always)]
pub(crate) fn cells4_by_cell<L: Layout<C> + ?Sized, K: Counter, const C: usize>(
    l: &L,
    [i0, i1]: [usize; 2],
    [j0, j1]: [usize; 2],
    k: &mut K,
) -> [[[L::Value; C]; 4]; 4] {
    [
        l.cell_corners_placed(i1, j1, k),
        l.cell_corners_placed(i1, j0, k),
        l.cell_corners_placed(i0, j1, k),
        l.cell_corners_placed(i0, j0, k),
    ]
}

impl<E: Entry, const C: usize> Layout<C> for Sat<'_, E, C> {
    type Value = E;
    fn width(&self) -> usize {
        Sat::width(self)
    }
    fn height(&self) -> usize {
        Sat::height(self)
    }
    fn texel_bits(&self) -> u32 {
        Sat::texel_bits(self)
    }
    fn value_bits(&self) -> u32 {
        self.total_bits()
    }
    #[allow(
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "usize -> u64 is lossless (usize::BITS <= 64); the table's bytes are at most \
                  isize::MAX < 2^63, so times 8 fits u64"
    )]
    fn storage_bits(&self) -> u64 {
        self.table_bytes() as u64 * 8
    }
    /// Zero outside `[0, w] x [0, h]` (no read), as the other layouts.
    #[inline(always)]
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        if x > Sat::width(self) || y > Sat::height(self) {
            return [E::ZERO; C];
        }
        self.read(x, y, k)
    }
    #[inline(always)]
    fn quad<K: Counter>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[E; C]; 4] {
        self.read_quad(xa, xb, ya, yb, k)
    }
    /// Zero for a cell outside the table (`i >= w` or `j >= h`: no read).
    #[inline(always)]
    fn cell_corners<K: Counter>(&self, i: usize, j: usize, k: &mut K) -> [[E; C]; 4] {
        if i >= Sat::width(self) || j >= Sat::height(self) {
            return [[E::ZERO; C]; 4];
        }
        self.cell_corners_placed(i, j, k)
    }
    /// Four reads through [`Sat::read`] (one multiply-add each beats two row slices here);
    /// wrapping coordinates: for a placed cell they are the plain ones.
    #[inline(always)]
    fn cell_corners_placed<K: Counter>(&self, i: usize, j: usize, k: &mut K) -> [[E; C]; 4] {
        let (i1, j1) = (i.wrapping_add(1), j.wrapping_add(1));
        [
            self.read(i, j, k),
            self.read(i1, j, k),
            self.read(i, j1, k),
            self.read(i1, j1, k),
        ]
    }
    #[inline(always)]
    fn quad_placed<K: Counter>(
        &self,
        xa: usize,
        xb: usize,
        ya: usize,
        yb: usize,
        k: &mut K,
    ) -> [[E; C]; 4] {
        self.read_quad_placed(xa, xb, ya, yb, k)
    }
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
mod tests;
