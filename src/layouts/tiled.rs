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
//! Reading `S(x, y)` costs one field per pair of non-zero digits: at most `(Lx + 1)(Ly + 1)`
//! fields (4 for one level of tiles), each 1 to 3 words, and one addition per field after the
//! first. With no levels (`AxisLevels::FLAT`) the layout is the flat table packed at its exact
//! width.
//!
//! Crow's §3.0 sketch stores only `C_00` and a corner per region, which loses the edge strips;
//! see `docs/layouts.md` and the `CrowLiteral` test in host-tests.

use super::packed::{read_bits, write_bits, WORD_BITS};
use super::Layout;
use crate::cost::Counter;
use crate::error::{Error, Quantity};
use crate::texel::{Entry, Texel};
use crate::texture::{check_dimensions, Texture};
use crate::width::{self, bits_of};

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
    pub const fn new(blocks: &[u32]) -> Result<Self, Error> {
        if blocks.len() > MAX_LEVELS {
            return Err(Error::InvalidLevels);
        }
        let mut out = [0u32; MAX_LEVELS];
        let mut prev = 1u32;
        let mut i = 0;
        while i < blocks.len() {
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
        &self.blocks[..self.len]
    }

    /// Number of components along this axis: levels + 1.
    pub const fn components(&self) -> usize {
        self.len + 1
    }

    const fn block(&self, p: usize) -> usize {
        if p == 0 {
            1
        } else {
            self.blocks[p - 1] as usize
        }
    }

    /// `b_{p+1}`, or `None` for the top component.
    const fn next(&self, p: usize) -> Option<usize> {
        if p < self.len {
            Some(self.blocks[p] as usize)
        } else {
            None
        }
    }

    /// Digit `d_p` of `x`.
    #[inline(always)]
    const fn digit(&self, p: usize, x: usize) -> usize {
        let b = self.block(p);
        match self.next(p) {
            Some(nb) => (x % nb) / b,
            None => x / b,
        }
    }

    /// `trunc_p(x)`: `x` rounded down to a multiple of `b_p`.
    #[inline(always)]
    const fn trunc(&self, p: usize, x: usize) -> usize {
        x - x % self.block(p)
    }

    /// Index of the stored position `X = trunc_p(X)` with a non-zero digit.
    #[inline(always)]
    const fn index(&self, p: usize, x: usize) -> usize {
        let b = self.block(p);
        match self.next(p) {
            Some(nb) => (x / nb) * (nb / b - 1) + (x % nb) / b - 1,
            None => x / b - 1,
        }
    }

    /// Stored positions of component `p` on an axis of `n` texels.
    const fn count(&self, p: usize, n: usize) -> usize {
        let b = self.block(p);
        match self.next(p) {
            Some(nb) => (n / nb) * (nb / b - 1) + (n % nb) / b,
            None => n / b,
        }
    }

    /// The longest interval `d_p b_p` of component `p` on an axis of `n` texels.
    const fn max_len(&self, p: usize, n: usize) -> usize {
        let b = self.block(p);
        match self.next(p) {
            Some(nb) => {
                if n >= nb {
                    nb - b
                } else {
                    (n / b) * b
                }
            }
            None => (n / b) * b,
        }
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

const N: usize = MAX_LEVELS + 1;

/// Where component `(p, q)` lives and how wide its fields are.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Component {
    offset_bits: u64,
    bits: u32,
    count_x: usize,
    count_y: usize,
}

/// The computed geometry of a tiled layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Geometry {
    spec: TiledSpec,
    width: usize,
    height: usize,
    texel_bits: u32,
    channels: usize,
    comps: [[Component; N]; N],
    total_bits: u64,
}

impl Geometry {
    fn new(
        spec: TiledSpec,
        width: usize,
        height: usize,
        texel_bits: u32,
        channels: usize,
    ) -> Result<Self, Error> {
        check_dimensions(width, height, channels)?;
        width::check_texel_bits(texel_bits)?;
        if let Some(k) = spec.modulus {
            if k < texel_bits || k == 0 || k > 64 {
                return Err(Error::InvalidModulus { bits: k });
            }
        }
        let m = width::max_texel(texel_bits);
        let mut comps = [[Component::default(); N]; N];
        let mut offset = 0u64;
        for (p, row) in comps.iter_mut().enumerate().take(spec.x.components()) {
            for (q, comp) in row.iter_mut().enumerate().take(spec.y.components()) {
                let (cx, cy) = (spec.x.count(p, width), spec.y.count(q, height));
                let len = spec.x.max_len(p, width) as u128 * spec.y.max_len(q, height) as u128;
                let mut bits = bits_of(m * len);
                if let Some(k) = spec.modulus {
                    bits = bits.min(k);
                }
                if bits > 64 {
                    return Err(Error::TooWide {
                        what: Quantity::Field,
                        bits_needed: bits,
                        bits_available: 64,
                    });
                }
                *comp = Component {
                    offset_bits: offset,
                    bits,
                    count_x: cx,
                    count_y: cy,
                };
                offset += cx as u64 * cy as u64 * bits as u64 * channels as u64;
            }
        }
        Ok(Geometry {
            spec,
            width,
            height,
            texel_bits,
            channels,
            comps,
            total_bits: offset,
        })
    }

    /// The value type must hold the worst-case total, or `k` bits for a modular spec.
    fn check_value_type<E: Entry>(&self) -> Result<(), Error> {
        match self.spec.modulus {
            Some(k) if k <= E::BITS => Ok(()),
            Some(k) => Err(Error::InvalidModulus { bits: k }),
            None => {
                width::check_entry_worst_case(self.texel_bits, self.width, self.height, E::BITS)
            }
        }
    }

    fn words(&self) -> usize {
        self.total_bits.div_ceil(WORD_BITS as u64) as usize
    }

    /// Bit offset of the fields of entry `(ix, iy)` of component `(p, q)`.
    #[inline(always)]
    fn field_offset(&self, p: usize, q: usize, ix: usize, iy: usize) -> (u64, u32) {
        let c = &self.comps[p][q];
        let entry = (ix * c.count_y + iy) as u64;
        (
            c.offset_bits + entry * c.bits as u64 * self.channels as u64,
            c.bits,
        )
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
    pub fn words_needed(
        spec: TiledSpec,
        width: usize,
        height: usize,
        texel_bits: u32,
    ) -> Result<usize, Error> {
        Ok(Geometry::new(spec, width, height, texel_bits, C)?.words())
    }

    /// Scratch entries the builder needs: one accumulator row per y component plus one row for
    /// the current row's prefix sums, `(Ly + 2) (w + 1) C`.
    pub fn scratch_needed(spec: TiledSpec, width: usize) -> usize {
        (spec.y.components() + 1) * (width + 1) * C
    }

    /// Builds the layout of `texture` into `words` (see [`Tiled::words_needed`]) using `scratch`
    /// (see [`Tiled::scratch_needed`]); refuses, before writing, a texture whose worst-case
    /// total does not fit `E`.
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
        for y in 0..texture.height() {
            b.push_row(texture.row(y).ok_or(Error::EmptyTexture)?)?;
        }
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
        if words.len() < geo.words() {
            return Err(Error::StorageTooSmall {
                needed: geo.words(),
                got: words.len(),
            });
        }
        Ok(Tiled {
            words,
            geo,
            _e: core::marker::PhantomData,
        })
    }

    /// The spec.
    pub fn spec(&self) -> TiledSpec {
        self.geo.spec
    }

    /// Field width of component `(p, q)` (`p` the x level, `q` the y level), or `None`.
    pub fn field_bits(&self, p: usize, q: usize) -> Option<u32> {
        if p < self.geo.spec.x.components() && q < self.geo.spec.y.components() {
            Some(self.geo.comps[p][q].bits)
        } else {
            None
        }
    }

    /// The most fields one `S(x, y)` reads: `(Lx + 1)(Ly + 1)`.
    pub fn max_fields_per_corner(&self) -> usize {
        self.geo.spec.x.components() * self.geo.spec.y.components()
    }

    /// The storage words.
    pub fn words(&self) -> &'a [u32] {
        self.words
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
        match self.geo.spec.modulus {
            Some(k) => k,
            None => {
                width::entry_bits_worst_case(self.geo.texel_bits, self.geo.width, self.geo.height)
            }
        }
    }
    fn modulus(&self) -> Option<u32> {
        self.geo.spec.modulus
    }
    fn storage_bits(&self) -> u64 {
        self.geo.total_bits
    }
    #[inline]
    fn corner<K: Counter>(&self, x: usize, y: usize, k: &mut K) -> [E; C] {
        let g = &self.geo;
        let mut out = [E::ZERO; C];
        let mut fields = 0u32;
        for p in 0..g.spec.x.components() {
            if g.spec.x.digit(p, x) == 0 {
                continue;
            }
            let ix = g.spec.x.index(p, g.spec.x.trunc(p, x));
            for q in 0..g.spec.y.components() {
                if g.spec.y.digit(q, y) == 0 {
                    continue;
                }
                let iy = g.spec.y.index(q, g.spec.y.trunc(q, y));
                let (offset, bits) = g.field_offset(p, q, ix, iy);
                let span = (offset % WORD_BITS as u64) as u32 + bits * C as u32;
                k.reads(1, bits * C as u32);
                k.words(span.div_ceil(WORD_BITS));
                for (c, o) in out.iter_mut().enumerate() {
                    let (v, _) = read_bits(self.words, offset + (c as u32 * bits) as u64, bits);
                    // Sums of parts of S: no wrap on a valid layout (E holds the total).
                    *o = o.wrapping_add(E::from_u64_truncating(v));
                }
                fields += 1;
            }
        }
        if fields > 1 {
            k.adds((fields - 1) * C as u32);
        }
        if let Some(m) = g.spec.modulus {
            for o in out.iter_mut() {
                *o = o.low_bits(m);
            }
        }
        out
    }
}

/// Builds a [`Tiled`] layout one texture row at a time, holding one accumulator row per y
/// component (two for one level of tiles) plus the current row's prefix sums.
#[derive(Debug)]
pub struct TiledBuilder<'a, 's, E: Entry, const C: usize = 1> {
    words: &'a mut [u32],
    scratch: &'s mut [E],
    geo: Geometry,
    rows_done: usize,
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
        if words.len() < geo.words() {
            return Err(Error::StorageTooSmall {
                needed: geo.words(),
                got: words.len(),
            });
        }
        let need = Tiled::<E, C>::scratch_needed(spec, width);
        if scratch.len() < need {
            return Err(Error::StorageTooSmall {
                needed: need,
                got: scratch.len(),
            });
        }
        let scratch = &mut scratch[..need];
        scratch.fill(E::ZERO);
        Ok(TiledBuilder {
            words,
            scratch,
            geo,
            rows_done: 0,
        })
    }

    /// Consumes the next texture row (`w * C` texels).
    pub fn push_row<T: Texel>(&mut self, texels: &[T]) -> Result<(), Error> {
        let g = self.geo;
        let (n, row) = (g.width, (g.width + 1) * C);
        if self.rows_done >= g.height {
            return Err(Error::TooManyRows);
        }
        if texels.len() != n * C {
            return Err(Error::RowLength {
                expected: n * C,
                got: texels.len(),
            });
        }
        let overflow = Error::TooWide {
            what: Quantity::Entry,
            bits_needed: E::BITS + 1,
            bits_available: E::BITS,
        };
        let modulus = g.spec.modulus;
        // Exact sums are checked; a modular spec needs them only modulo 2^k and wraps on purpose.
        let add = |a: E, b: E| -> Result<E, Error> {
            match modulus {
                Some(_) => Ok(a.wrapping_add(b)),
                None => a.checked_add(b).ok_or(overflow),
            }
        };
        let max = width::max_texel(g.texel_bits);
        let (prefix, accs) = self.scratch.split_at_mut(row);
        // The row's prefix sums P[X], X = 0..=n.
        let mut run = [E::ZERO; C];
        prefix[..C].fill(E::ZERO);
        for (x, t) in texels.chunks_exact(C).enumerate() {
            for c in 0..C {
                let v = t[c].to_u16();
                // The field widths are proved for `texel_bits`; a wider texel would break them.
                if v as u128 > max {
                    return Err(Error::TooWide {
                        what: Quantity::Entry,
                        bits_needed: bits_of(v as u128),
                        bits_available: g.texel_bits,
                    });
                }
                run[c] = add(run[c], E::from(v))?;
                prefix[(x + 1) * C + c] = run[c];
            }
        }
        // Every y component accumulates the row.
        for acc in accs.chunks_exact_mut(row) {
            for (a, &p) in acc.iter_mut().zip(prefix.iter()) {
                *a = add(*a, p)?;
            }
        }
        let y = self.rows_done + 1;
        for q in 0..g.spec.y.components() {
            if !y.is_multiple_of(g.spec.y.block(q)) || g.spec.y.digit(q, y) == 0 {
                continue;
            }
            let iy = g.spec.y.index(q, y);
            let acc = &accs[q * row..(q + 1) * row];
            for p in 0..g.spec.x.components() {
                let bx = g.spec.x.block(p);
                let mut x = bx;
                while x <= n {
                    if g.spec.x.digit(p, x) != 0 {
                        let lo = match g.spec.x.next(p) {
                            Some(nb) => x - x % nb,
                            None => 0,
                        };
                        let ix = g.spec.x.index(p, x);
                        let (offset, bits) = g.field_offset(p, q, ix, iy);
                        for c in 0..C {
                            let mut v = acc[x * C + c].wrapping_sub(acc[lo * C + c]);
                            if let Some(m) = modulus {
                                v = v.low_bits(m);
                            }
                            if !write_bits(
                                self.words,
                                offset + (c as u32 * bits) as u64,
                                bits,
                                v.to_u64(),
                            ) {
                                return Err(Error::TooWide {
                                    what: Quantity::Field,
                                    bits_needed: bits_of(v.to_u128()),
                                    bits_available: bits,
                                });
                            }
                        }
                    }
                    x += bx;
                }
            }
        }
        // Reset the accumulators whose super-block ends here.
        for q in 0..g.spec.y.components() {
            if let Some(nb) = g.spec.y.next(q) {
                if y.is_multiple_of(nb) {
                    accs[q * row..(q + 1) * row].fill(E::ZERO);
                }
            }
        }
        self.rows_done += 1;
        Ok(())
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
