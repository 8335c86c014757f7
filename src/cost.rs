//! Cost counting: what a hardware texture unit would spend per sample.
//!
//! Every lookup takes a `&mut impl Counter`. [`NoCount`] is a zero-sized type whose methods are
//! empty and inline, so a build that does not count compiles to the same code as one that had no
//! counting at all. [`Tally`] adds the operations up.
//!
//! What is counted follows Crow §2.2: the operations on *table values* and the area multiply and
//! the divide of the mean. A *read* is one table entry fetched, all channels together; a read of
//! the zero row or column of the corner function (`x = 0` or `y = 0`) and the cached whole-table
//! sum cost no read. A packed layout also reports the 32-bit *words* a read touches (a field may
//! straddle words), which is what an MCU's bus pays; an FPGA with one block RAM per field width
//! pays one access per read. *Additive* operations are adds and subtracts; *multiplicative* operations are
//! multiplies (`muls`) plus divides (`divs`). Shifts by the constant `F` (a scale by `2^F`) are
//! wiring in hardware and are not counted. Coordinate arithmetic (splitting a corner into integer
//! and fraction, side lengths, addresses, comparisons) belongs to the address unit and is not
//! counted either, as in Crow's table. Arithmetic on values is counted once per channel; reads
//! are not multiplied by the channel count.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

/// Receives the operations a lookup performs.
pub trait Counter {
    /// `n` entries of `bits` bits each (all channels) were read.
    fn reads(&mut self, n: u32, bits: u32);
    /// `n` multiplies.
    fn muls(&mut self, n: u32);
    /// `n` divides.
    fn divs(&mut self, n: u32);
    /// `n` additive operations (adds or subtracts).
    fn adds(&mut self, n: u32);
    /// `n` 32-bit memory words touched by the reads.
    fn words(&mut self, n: u32) {
        let _ = n;
    }
    /// Where a read was: `bits` bits (all channels) from bit `offset` of storage `region`
    /// ([`Region`]). Reported once per read, beside [`Counter::reads`], so that a host-side
    /// counter can model memory traffic and texel caches; the default ignores it (and
    /// [`NoCount`] compiles it away).
    #[inline(always)]
    fn read_at(&mut self, region: Region, offset: u64, bits: u32) {
        let _ = (region, offset, bits);
    }
}

/// The storage a read comes from ([`Counter::read_at`]): separate memories of a texture unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Region {
    /// The summed-area table (flat entries, or the 32-bit words of a packed, tiled or modular
    /// layout); offset = entry index x entry bits x channels, or the field's bit offset.
    Table,
    /// The texture itself (texel index x texel bits x channels).
    Texture,
    /// A filter's own storage (pyramid levels, ripmap, dipmap, order-2 or squares tables).
    Filter,
}

/// `n * channels` as the `u32` a [`Counter`] takes: a per-channel operation count, or the bits
/// of a read of all channels (`n` = bits per channel). Meant for a `const` block at the use
/// (`const { per_channel(3, C) }`): the count is then a constant of the compiled lookup (no
/// run-time work, the same code as `3 * C as u32`), and a channel count whose product does not
/// fit `u32` stops the build instead of wrapping the count.
#[allow(
    clippy::panic,
    reason = "evaluated in const blocks only: a product past u32 is a compile error, not a run-time panic"
)]
pub(crate) const fn per_channel(n: u32, channels: usize) -> u32 {
    const _: () = assert!(usize::BITS <= u64::BITS);
    #[allow(
        clippy::as_conversions,
        reason = "lossless: usize::BITS <= 64 (asserted above); u64::from is not const"
    )]
    let (n, c) = (n as u64, channels as u64);
    match n.checked_mul(c) {
        Some(v) if v >> u32::BITS == 0 => {
            #[allow(
                clippy::as_conversions,
                reason = "v < 2^32 (checked by the match guard): lossless; u32::try_from is not const"
            )]
            let v = v as u32;
            v
        }
        _ => panic!("a per-channel cost count past u32"),
    }
}

/// The counter that counts nothing: a zero-sized type that compiles away.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoCount;

impl Counter for NoCount {
    #[inline(always)]
    fn reads(&mut self, _n: u32, _bits: u32) {}
    #[inline(always)]
    fn muls(&mut self, _n: u32) {}
    #[inline(always)]
    fn divs(&mut self, _n: u32) {}
    #[inline(always)]
    fn adds(&mut self, _n: u32) {}
}

/// A running total of the operations of one or more lookups.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tally {
    /// Table entries read (one per entry, all channels together).
    pub reads: u64,
    /// Bits read: the sum over reads of bits per entry times channels.
    pub bits_read: u64,
    /// 32-bit words touched by the reads.
    pub words: u64,
    /// Multiplies.
    pub muls: u64,
    /// Divides.
    pub divs: u64,
    /// Additive operations (adds and subtracts).
    pub adds: u64,
}

impl Tally {
    /// An empty tally.
    pub const fn new() -> Self {
        Tally {
            reads: 0,
            bits_read: 0,
            words: 0,
            muls: 0,
            divs: 0,
            adds: 0,
        }
    }

    /// Multiplicative operations as Crow counts them: multiplies plus divides (saturating).
    pub const fn multiplicative(&self) -> u64 {
        self.muls.saturating_add(self.divs)
    }
}

/// The counts saturate at `u64::MAX` (no lookup comes near: a few hundred operations each; a
/// caller feeding arbitrary counts gets `u64::MAX`, never a wrapped or panicking count).
impl Counter for Tally {
    #[inline]
    fn reads(&mut self, n: u32, bits: u32) {
        self.reads = self.reads.saturating_add(u64::from(n));
        self.bits_read = self
            .bits_read
            .saturating_add(u64::from(n).saturating_mul(u64::from(bits)));
    }
    #[inline]
    fn muls(&mut self, n: u32) {
        self.muls = self.muls.saturating_add(u64::from(n));
    }
    #[inline]
    fn divs(&mut self, n: u32) {
        self.divs = self.divs.saturating_add(u64::from(n));
    }
    #[inline]
    fn adds(&mut self, n: u32) {
        self.adds = self.adds.saturating_add(u64::from(n));
    }
    #[inline]
    fn words(&mut self, n: u32) {
        self.words = self.words.saturating_add(u64::from(n));
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
mod tests {
    use super::*;

    #[test]
    fn no_count_is_zero_sized() {
        assert_eq!(core::mem::size_of::<NoCount>(), 0);
    }

    #[test]
    fn tally_adds_up() {
        let mut t = Tally::new();
        t.reads(4, 32);
        t.muls(1);
        t.divs(1);
        t.adds(3);
        assert_eq!(
            (t.reads, t.bits_read, t.multiplicative(), t.adds),
            (4, 128, 2, 3)
        );
    }
}
