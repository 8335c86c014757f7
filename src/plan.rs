//! Scene plans: from what a scene needs, the smallest table, entry word and lookup that serve it
//! (and what was rejected, and why).
//!
//! A firmware knows its scene: the texture's size and texel width, how large and how small the
//! footprints get, whether they leave the texture and under which boundary mode, how many
//! sub-texel bits the corners carry and how exact the mean must be. [`Plan::for_scene`] turns
//! these [`SceneFacts`] into a [`Plan`]: the entry word (`u16`, `u32`, `u64`), the layout (flat,
//! packed at the exact width, tiled, modular with its `k` from the largest box, or tiled and
//! modular), the lookup (the 4-read lookup for integer corners, Crow's large-footprint shortcut
//! where its proven bound meets the tolerance, else the exact 16-read lookup in the Stable form,
//! or Paper where only Paper's one bit narrower accumulator fits), and its costs.
//!
//! It is a `const fn`: with the facts as constants the plan is computed by the compiler, and a
//! firmware sizes its `static` table from [`Plan::storage_len`]:
//!
//! ```
//! use texsat::plan::{Plan, PlanLayout, PlanLookup, SceneFacts};
//! use texsat::EdgeKind;
//! const FACTS: SceneFacts = SceneFacts {
//!     max_box: [16 << 8, 16 << 8],
//!     ..SceneFacts::new(256, 256, 8, 8, EdgeKind::Repeat)
//! };
//! const PLAN: Plan = match Plan::for_scene(&FACTS) {
//!     Ok(p) => p,
//!     Err(_) => panic!("no table serves this scene"),
//! };
//! static TABLE: [u32; PLAN.storage_len()] = [0; PLAN.storage_len()];
//! // Boxes of at most 16 x 16 texels at F = 8 overlap at most 18 x 18 cells: their sums fit
//! // k = bits(255 * 324) = 17 bits, so 8 x 8 tiles with every field modulo 2^17 (the flat
//! // table needs 24 bits of its u32 per entry); exact means by the Stable form.
//! assert_eq!(PLAN.layout(), PlanLayout::TiledModular { tile: 8, k: 17 });
//! assert_eq!(PLAN.layout().to_string(), "tiled:8x8+mod:17");
//! assert_eq!(PLAN.lookup(), PlanLookup::Stable);
//! assert!(PLAN.table_bytes() < 256 * 256 * 4 / 2);
//! assert_eq!(TABLE.len() as u64 * 4, PLAN.table_bytes());
//! ```
//!
//! A plan also guards its facts at run time: [`Plan::check_box`] refuses a box outside them
//! with [`Error::OutsidePlan`] (and a modular table refuses a box too large for its `k` by
//! itself: a box is never answered wrongly).
//!
//! ## How the plan decides
//! 1. The lookup: `F = 0` takes the exact 4-read lookup. Otherwise, if the tolerance admits
//!    Crow's shortcut for every box (its bound `m (1/(W-1) + 1/(H-1))` texel units, for the
//!    smallest box, plus half a unit of the mean's last bit, within the tolerance), the 4-read
//!    shortcut; else the exact 16-read lookup.
//! 2. Every candidate layout is sized: flat in `u16`, `u32`, `u64` entries; packed (the flat
//!    table at the exact width of the worst-case total); tiled with square tiles of 4, 8, 16 and
//!    32 texels; modular with `k = bits((2^b - 1) cells)` for the largest box's cells (plus `2F`
//!    for Paper); tiled 8 x 8 and 16 x 16 with the same modulus. A candidate is rejected if its
//!    values or the lookup's accumulator do not fit its word ([`crate::width::max_frac_bits`]),
//!    if it reads more than the read bound, or if it saves nothing (a modulus not below the full
//!    table's bits).
//! 3. The smallest table wins (fewest bytes; on a tie, fewest reads, then the earlier in the list
//!    above). Every other candidate is listed in [`Plan::rejected`] with its reason.
//! 4. The mean's word: [`Plan::mean_fits_u32`] when the largest box's area (in units of
//!    `2^-2F`) and the largest mean (`(2^b - 1) 2^g`) both fit 32 bits; then
//!    [`crate::BoxSum::mean_rounded_u32`] answers every box of the scene with one 64-by-32-bit
//!    division, and a firmware that calls it links none of the wide mean's fallbacks.
//!
//! Costs are worst cases per sample (all channels): reads of table values (a tiled corner reads
//! up to 4 fields, each counted), multiplies, divides and additive operations as the lookups
//! count them ([`crate::Tally`]), a box crossing an edge counted as its split (at most 2 or 3
//! pieces per axis), plus the mean: one multiply and one divide per channel. The error is in
//! units of the mean's last bit: 1/2 for the exact lookups (the mean's rounding).
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::edge::EdgeKind;
use crate::error::Error;
use crate::layouts::{modular_words, modulus_bits_for, tiled_words, TiledSpec};
use crate::lookup::{FormKind, Shortcut};
use crate::rect::Rect;
use crate::texture::check_dimensions;
use crate::width::{self, MAX_FRAC_BITS};

/// What a scene needs of its table. Build one with [`SceneFacts::new`] and struct update
/// syntax for the rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SceneFacts {
    /// Texture width in texels.
    pub width: usize,
    /// Texture height in texels.
    pub height: usize,
    /// Bits per texel (1 to 16).
    pub texel_bits: u32,
    /// Channels per texel.
    pub channels: usize,
    /// Fractional bits `F` of the corners (0: integer corners, the 4-read lookup).
    pub frac_bits: u32,
    /// The smallest box, `[width, height]` in raw units (`texels * 2^F`).
    pub min_box: [u64; 2],
    /// The largest box, `[width, height]` in raw units.
    pub max_box: [u64; 2],
    /// Whether boxes reach outside `[0, w] x [0, h]` (then `edge` decides what they sum).
    pub leaves_texture: bool,
    /// The boundary mode.
    pub edge: EdgeKind,
    /// Fractional bits `g` of the mean (`BoxSum::mean_rounded`'s `out_frac_bits`).
    pub mean_frac_bits: u32,
    /// The error allowed on the mean, in units of its last bit (`2^-g` texel units); 0: exact
    /// (correctly rounded).
    pub tolerance: u64,
    /// The most table reads per sample; 0: no bound.
    pub max_reads: u32,
}

impl SceneFacts {
    /// Facts for a `width x height` texture of `texel_bits`-bit single-channel texels at `F =
    /// frac_bits`, boxes from one texel up to the whole texture, inside it, exact means with 8
    /// fractional bits, no read bound; `edge` the boundary mode.
    pub const fn new(
        width: usize,
        height: usize,
        texel_bits: u32,
        frac_bits: u32,
        edge: EdgeKind,
    ) -> SceneFacts {
        let one = if frac_bits < 64 { 1u64 << frac_bits } else { 0 };
        #[allow(
            clippy::as_conversions,
            reason = "usize -> u64 is lossless (usize::BITS <= 64, asserted in width.rs); From is not const"
        )]
        let (w, h) = (width as u64, height as u64);
        SceneFacts {
            width,
            height,
            texel_bits,
            channels: 1,
            frac_bits,
            min_box: [one, one],
            max_box: [w.saturating_mul(one), h.saturating_mul(one)],
            leaves_texture: false,
            edge,
            mean_frac_bits: 8,
            tolerance: 0,
            max_reads: 0,
        }
    }
}

/// The table's entry word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EntryWord {
    /// `u16` (lookups in 32-bit arithmetic).
    U16,
    /// `u32` (lookups in 64-bit arithmetic).
    U32,
    /// `u64` (lookups in 128-bit arithmetic).
    U64,
}

impl EntryWord {
    /// Bits of the word.
    pub const fn bits(self) -> u32 {
        match self {
            EntryWord::U16 => 16,
            EntryWord::U32 => 32,
            EntryWord::U64 => 64,
        }
    }

    /// `u16`, `u32` or `u64`.
    pub const fn name(self) -> &'static str {
        match self {
            EntryWord::U16 => "u16",
            EntryWord::U32 => "u32",
            EntryWord::U64 => "u64",
        }
    }

    /// The narrowest word of at least `bits` bits.
    const fn at_least(bits: u32) -> Option<EntryWord> {
        if bits <= 16 {
            Some(EntryWord::U16)
        } else if bits <= 32 {
            Some(EntryWord::U32)
        } else if bits <= 64 {
            Some(EntryWord::U64)
        } else {
            None
        }
    }

    const fn wider(self) -> Option<EntryWord> {
        match self {
            EntryWord::U16 => Some(EntryWord::U32),
            EntryWord::U32 => Some(EntryWord::U64),
            EntryWord::U64 => None,
        }
    }
}

/// How the table is stored (see [`crate::layouts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanLayout {
    /// [`crate::Sat`]: native words.
    Flat,
    /// [`crate::layouts::Tiled`] with no levels: the flat table packed at its exact width.
    Packed,
    /// [`crate::layouts::Tiled`], one level of `tile x tile` tiles.
    Tiled {
        /// Tile side in texels.
        tile: u32,
    },
    /// [`crate::layouts::Modular`] at `k` bits.
    Modular {
        /// Bits per value.
        k: u32,
    },
    /// [`crate::layouts::Tiled`] with `tile x tile` tiles, every field modulo `2^k`.
    TiledModular {
        /// Tile side in texels.
        tile: u32,
        /// Modulus bits.
        k: u32,
    },
}

impl PlanLayout {
    /// The [`TiledSpec`] of a packed or tiled layout.
    pub const fn tiled_spec(self) -> Option<TiledSpec> {
        match self {
            PlanLayout::Packed => Some(TiledSpec::FLAT_PACKED),
            PlanLayout::Tiled { tile } => match TiledSpec::tiles(tile, tile) {
                Ok(s) => Some(s),
                Err(_) => None,
            },
            PlanLayout::TiledModular { tile, k } => match TiledSpec::tiles(tile, tile) {
                Ok(s) => Some(s.with_modulus(k)),
                Err(_) => None,
            },
            PlanLayout::Flat | PlanLayout::Modular { .. } => None,
        }
    }

    /// `k` of a modular layout.
    pub const fn modulus(self) -> Option<u32> {
        match self {
            PlanLayout::Modular { k } | PlanLayout::TiledModular { k, .. } => Some(k),
            _ => None,
        }
    }
}

/// Written as `sat query --layout` takes it: `flat`, `packed`, `tiled:8x8`, `modular:21`,
/// `tiled:8x8+mod:21`.
impl core::fmt::Display for PlanLayout {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            PlanLayout::Flat => f.write_str("flat"),
            PlanLayout::Packed => f.write_str("packed"),
            PlanLayout::Tiled { tile } => write!(f, "tiled:{tile}x{tile}"),
            PlanLayout::Modular { k } => write!(f, "modular:{k}"),
            PlanLayout::TiledModular { tile, k } => write!(f, "tiled:{tile}x{tile}+mod:{k}"),
        }
    }
}

/// Which lookup answers the scene's boxes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanLookup {
    /// Integer corners: `box_sum_int`, 4 reads, exact.
    Int4,
    /// `box_sum` in the [`crate::Paper`] form, 16 reads, exact.
    Paper,
    /// `box_sum` in the [`crate::Stable`] form, 16 reads, exact.
    Stable,
    /// `box_mean_shortcut` with [`Shortcut::with_min_side`]`(min_side)`: every box of the scene
    /// is at least `min_side` texels on both sides, so all take the 4-read shortcut.
    Shortcut {
        /// The shortcut's smallest side, in texels.
        min_side: u64,
    },
}

impl PlanLookup {
    /// `int4`, `paper`, `stable` or `shortcut`.
    pub const fn name(self) -> &'static str {
        match self {
            PlanLookup::Int4 => "int4",
            PlanLookup::Paper => "paper",
            PlanLookup::Stable => "stable",
            PlanLookup::Shortcut { .. } => "shortcut",
        }
    }

    /// The 16-read form behind the lookup (the shortcut's fallback form is Stable).
    pub const fn form(self) -> FormKind {
        match self {
            PlanLookup::Paper => FormKind::Paper,
            _ => FormKind::Stable,
        }
    }

    /// Table values read per corner-set: 4 or 16.
    const fn corner_reads(self) -> u32 {
        match self {
            PlanLookup::Int4 | PlanLookup::Shortcut { .. } => 4,
            PlanLookup::Paper | PlanLookup::Stable => 16,
        }
    }

    /// Accumulator value bits the lookup needs on values of `value_bits` bits at `F = f`
    /// (0 for the 4-read lookup, which computes in the value word).
    const fn acc_bits(self, value_bits: u32, f: u32) -> u32 {
        match self {
            PlanLookup::Int4 => 0,
            PlanLookup::Paper => width::paper_acc_bits(value_bits, f),
            PlanLookup::Stable | PlanLookup::Shortcut { .. } => {
                width::stable_acc_bits(value_bits, f)
            }
        }
    }

    /// Per channel and in-range lookup: multiplies and additive operations (as counted).
    const fn ops(self) -> (u32, u32) {
        match self {
            PlanLookup::Int4 | PlanLookup::Shortcut { .. } => (0, 3),
            PlanLookup::Paper => (12, 27),
            PlanLookup::Stable => (12, 31),
        }
    }
}

/// Worst-case operations per sample, all channels, the mean included.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanCosts {
    /// Table values read (a tiled corner reads up to one field per component, each counted).
    pub reads: u32,
    /// Multiplies.
    pub muls: u32,
    /// Divides (the mean's: one per channel).
    pub divs: u32,
    /// Additive operations.
    pub adds: u32,
}

/// Why a candidate layout was not chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RejectReason {
    /// It serves the scene, but takes more bytes than the plan's table.
    Larger {
        /// Its table bytes.
        bytes: u64,
    },
    /// It reads more values per sample than the read bound allows.
    TooManyReads {
        /// Its worst-case reads per sample.
        reads: u32,
    },
    /// Its values or the lookup's accumulator need more bits than any word it could use.
    TooWide {
        /// Bits needed.
        bits_needed: u32,
        /// Bits of the widest word.
        bits_available: u32,
    },
    /// A modulus no smaller than the full table's values: nothing saved.
    NoSaving {
        /// The modulus the largest box needs.
        k: u32,
    },
    /// Its size could not be computed (the layout refused the texture).
    Refused(Error),
}

/// A candidate that was not chosen, and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rejection {
    /// The candidate layout.
    pub layout: PlanLayout,
    /// Its entry word (`None` where it could not be chosen).
    pub entry: Option<EntryWord>,
    /// Why.
    pub why: RejectReason,
}

/// The candidates, in the order that breaks ties.
const CANDIDATES: [PlanLayout; 10] = [
    PlanLayout::Flat,
    PlanLayout::Packed,
    PlanLayout::Tiled { tile: 4 },
    PlanLayout::Tiled { tile: 8 },
    PlanLayout::Tiled { tile: 16 },
    PlanLayout::Tiled { tile: 32 },
    PlanLayout::Modular { k: 0 },
    PlanLayout::TiledModular { tile: 8, k: 0 },
    PlanLayout::TiledModular { tile: 16, k: 0 },
    // The flat table once more, so that the widest word is tried when the lookup's
    // accumulator needs it (the first Flat takes the narrowest word that holds the values).
    PlanLayout::Flat,
];

/// The number of candidates (the most rejections a plan lists).
pub const MAX_CANDIDATES: usize = CANDIDATES.len();

/// A sized candidate.
#[derive(Debug, Clone, Copy)]
struct Sized {
    layout: PlanLayout,
    entry: EntryWord,
    storage_len: usize,
    bytes: u64,
    costs: PlanCosts,
    acc_bits: u32,
}

/// The plan for a scene: see the module docs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Plan {
    facts: SceneFacts,
    entry: EntryWord,
    layout: PlanLayout,
    lookup: PlanLookup,
    acc_bits: u32,
    storage_len: usize,
    table_bytes: u64,
    costs: PlanCosts,
    max_error: (u64, u64),
    mean_fits_u32: bool,
    rejected: [Option<Rejection>; MAX_CANDIDATES],
}

impl Plan {
    /// The plan for `facts`, or the reason none exists: invalid facts
    /// ([`Error::EmptyTexture`], [`Error::InvalidTexelBits`], [`Error::FracBitsUnsupported`],
    /// [`Error::InvertedBox`] for a smallest box above the largest, [`Error::NoSuchChannel`]
    /// for zero channels, [`Error::ZeroArea`] for a largest box of zero area: no box to plan
    /// for), or [`Error::NoPlan`] when no candidate fits a word and the read bound (also for a
    /// texture no table accepts, a side above `2^31 - 1`: every candidate is then rejected with
    /// [`Error::TextureTooLarge`]).
    #[allow(
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects,
        reason = "const fn (no iterators): i < MAX_CANDIDATES and n < MAX_CANDIDATES (loop \
                  conditions) and b < MAX_CANDIDATES (checked before each use) index in bounds, and \
                  the increments stay at most MAX_CANDIDATES"
    )]
    pub const fn for_scene(facts: &SceneFacts) -> Result<Plan, Error> {
        if let Err(e) = check_facts(facts) {
            return Err(e);
        }
        let lookup = choose_lookup(facts);
        let mut sized: [Option<Result<Sized, Rejection>>; MAX_CANDIDATES] = [None; MAX_CANDIDATES];
        let mut best: Option<usize> = None;
        let mut i = 0;
        while i < MAX_CANDIDATES {
            let widest = i == MAX_CANDIDATES - 1;
            let r = size_candidate(facts, lookup, CANDIDATES[i], widest);
            if let Ok(s) = &r {
                best = match best {
                    None => Some(i),
                    // `b < i`: an index already visited (the check keeps the const fn free of a
                    // bounds-check panic path).
                    Some(b) if b >= MAX_CANDIDATES => Some(i),
                    Some(b) => match &sized[b] {
                        Some(Ok(bs)) if bs.bytes < s.bytes => Some(b),
                        Some(Ok(bs)) if bs.bytes == s.bytes && bs.costs.reads <= s.costs.reads => {
                            Some(b)
                        }
                        _ => Some(i),
                    },
                };
            }
            sized[i] = Some(r);
            i += 1;
        }
        let Some(b) = best else {
            return Err(Error::NoPlan);
        };
        if b >= MAX_CANDIDATES {
            return Err(Error::NoPlan);
        }
        let Some(Ok(chosen)) = sized[b] else {
            return Err(Error::NoPlan);
        };
        let mut rejected = [None; MAX_CANDIDATES];
        let mut n = 0;
        let mut i = 0;
        while i < MAX_CANDIDATES {
            let r = match sized[i] {
                Some(Ok(s)) if i != b => {
                    // The second flat candidate repeats the first when both chose one word.
                    if s.bytes == chosen.bytes
                        && matches!(s.layout, PlanLayout::Flat)
                        && matches!(chosen.layout, PlanLayout::Flat)
                    {
                        None
                    } else {
                        Some(Rejection {
                            layout: s.layout,
                            entry: Some(s.entry),
                            why: RejectReason::Larger { bytes: s.bytes },
                        })
                    }
                }
                Some(Err(rej)) => Some(rej),
                _ => None,
            };
            if let Some(r) = r {
                if n < MAX_CANDIDATES && !duplicate(&rejected, n, &r) {
                    rejected[n] = Some(r);
                    n += 1;
                }
            }
            i += 1;
        }
        Ok(Plan {
            facts: *facts,
            entry: chosen.entry,
            layout: chosen.layout,
            lookup,
            acc_bits: chosen.acc_bits,
            storage_len: chosen.storage_len,
            table_bytes: chosen.bytes,
            costs: chosen.costs,
            max_error: max_error(facts, lookup),
            mean_fits_u32: mean_fits_u32(facts),
            rejected,
        })
    }

    /// The facts the plan was made for.
    pub const fn facts(&self) -> &SceneFacts {
        &self.facts
    }

    /// The entry word: of the flat table's entries, or the value type of a packed, tiled or
    /// modular layout's lookups.
    pub const fn entry(&self) -> EntryWord {
        self.entry
    }

    /// The layout.
    pub const fn layout(&self) -> PlanLayout {
        self.layout
    }

    /// The lookup.
    pub const fn lookup(&self) -> PlanLookup {
        self.lookup
    }

    /// The shortcut the plan's lookup uses, if it is the shortcut.
    pub const fn shortcut(&self) -> Option<Shortcut> {
        match self.lookup {
            PlanLookup::Shortcut { min_side } => Some(Shortcut::with_min_side(min_side)),
            _ => None,
        }
    }

    /// Accumulator value bits the lookup needs (0 for the 4-read lookup, which computes in the
    /// entry word); at most the entry word's accumulator ([`width::acc_value_bits`]).
    pub const fn acc_bits(&self) -> u32 {
        self.acc_bits
    }

    /// Elements of storage the table needs: entries of the entry word for the flat table,
    /// `u32` words for the packed, tiled and modular layouts. A `const fn`: size a `static`.
    pub const fn storage_len(&self) -> usize {
        self.storage_len
    }

    /// Bytes of the table.
    pub const fn table_bytes(&self) -> u64 {
        self.table_bytes
    }

    /// Stored bits per texel entry (all channels), `table_bytes * 8 / (w h)`, as a fraction
    /// `(bits, texels)`.
    #[allow(
        clippy::as_conversions,
        reason = "usize -> u64 is lossless (usize::BITS <= 64, asserted in width.rs); From is not const"
    )]
    pub const fn bits_per_entry(&self) -> (u64, u64) {
        (
            self.table_bytes.saturating_mul(8),
            (self.facts.width as u64).saturating_mul(self.facts.height as u64),
        )
    }

    /// Worst-case operations per sample.
    pub const fn costs(&self) -> PlanCosts {
        self.costs
    }

    /// Worst-case error of the mean in units of its last bit, as a fraction `(num, den)`:
    /// `(1, 2)` for the exact lookups.
    pub const fn max_error(&self) -> (u64, u64) {
        self.max_error
    }

    /// Whether [`crate::BoxSum::mean_rounded_u32`] answers every box of the facts: the largest
    /// box's area `W H` (in units of `2^-2F`) and the largest mean `(2^b - 1) 2^g` both fit 32
    /// bits (then the numerator, at most `(2^b - 1) W H 2^g`, fits 64). A firmware calls it
    /// instead of [`crate::BoxSum::mean_rounded`] (the same value) and leaves out the wide
    /// mean's fallbacks (about 1 KiB on a Cortex-M4, docs/firmware.md); otherwise the wide mean.
    pub const fn mean_fits_u32(&self) -> bool {
        self.mean_fits_u32
    }

    /// Whether the facts' boxes are Repeat boxes at most one period (the texture's side) long on
    /// each axis: then [`crate::RepeatWithinPeriod`] answers every box of the plan with
    /// [`crate::Repeat`]'s sums, and a firmware that uses it leaves out the whole periods'
    /// division and multiplies (about 1 KiB of the Stable + Repeat firmware on a Cortex-M4,
    /// docs/firmware.md). `false` for any other mode and for a largest box past the texture.
    #[allow(
        clippy::as_conversions,
        reason = "const fn (no From): a plan exists only for sides below 2^31 and F <= 24 \
                  (check_facts, check_dimensions), so n 2^F < 2^55 is exact in u64"
    )]
    pub const fn repeat_within_period(&self) -> bool {
        let f = &self.facts;
        matches!(f.edge, EdgeKind::Repeat)
            && f.max_box[0] <= (f.width as u64) << f.frac_bits
            && f.max_box[1] <= (f.height as u64) << f.frac_bits
    }

    /// The cargo features the firmware needs for this plan: none (box lookups, every layout
    /// and mode are in the core without features).
    pub const fn features(&self) -> &'static [&'static str] {
        &[]
    }

    /// The candidates not chosen, with the reasons.
    pub fn rejected(&self) -> impl Iterator<Item = &Rejection> {
        self.rejected.iter().flatten()
    }

    /// Refuses a box (raw corners at the plan's `F`) outside the plan's facts:
    /// [`Error::InvertedBox`], or [`Error::OutsidePlan`] for a side below the smallest box or
    /// above the largest, or a box reaching outside the texture when the facts say boxes stay
    /// inside.
    pub const fn check_box(&self, r: &Rect<i64>) -> Result<(), Error> {
        if r.x1 < r.x0 || r.y1 < r.y0 {
            return Err(Error::InvertedBox);
        }
        let f = &self.facts;
        // Two's complement: the difference of the bit patterns modulo 2^64 is x1 - x0, which
        // lies in [0, 2^64) for x1 >= x0.
        let w = r.x1.cast_unsigned().wrapping_sub(r.x0.cast_unsigned());
        let h = r.y1.cast_unsigned().wrapping_sub(r.y0.cast_unsigned());
        if w < f.min_box[0] || h < f.min_box[1] {
            return Err(Error::OutsidePlan {
                limit: PlanLimit::BoxTooSmall,
            });
        }
        if w > f.max_box[0] || h > f.max_box[1] {
            return Err(Error::OutsidePlan {
                limit: PlanLimit::BoxTooLarge,
            });
        }
        if !f.leaves_texture {
            #[allow(
                clippy::as_conversions,
                reason = "a plan exists only for sides below 2^31 (every candidate checks \
                          check_dimensions) and F <= 24 (check_facts): the value is exact, below 2^55"
            )]
            let (pw, ph) = (
                (f.width as i64) << f.frac_bits,
                (f.height as i64) << f.frac_bits,
            );
            if r.x0 < 0 || r.y0 < 0 || r.x1 > pw || r.y1 > ph {
                return Err(Error::OutsidePlan {
                    limit: PlanLimit::LeavesTexture,
                });
            }
        }
        Ok(())
    }
}

/// Which of a plan's facts a box breaks ([`Error::OutsidePlan`]). Non-exhaustive, as
/// [`Error`] is: a later plan fact adds a limit without breaking a firmware's `match`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanLimit {
    /// A side is below the smallest box's.
    BoxTooSmall,
    /// A side is above the largest box's.
    BoxTooLarge,
    /// The box reaches outside the texture, and the facts say boxes stay inside.
    LeavesTexture,
    /// A side is longer than the texture's, and the lookup answers boxes within one period
    /// only ([`crate::RepeatWithinPeriod`]).
    LongerThanPeriod,
}

impl core::fmt::Display for PlanLimit {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            PlanLimit::BoxTooSmall => "a side is below the plan's smallest box",
            PlanLimit::BoxTooLarge => "a side is above the plan's largest box",
            PlanLimit::LeavesTexture => {
                "the box leaves the texture, and the plan's boxes stay inside"
            }
            PlanLimit::LongerThanPeriod => {
                "a side is longer than the texture, and the lookup answers boxes within one \
                 period (RepeatWithinPeriod)"
            }
        })
    }
}

const fn check_facts(f: &SceneFacts) -> Result<(), Error> {
    if f.width == 0 || f.height == 0 {
        return Err(Error::EmptyTexture);
    }
    if let Err(e) = width::check_texel_bits(f.texel_bits) {
        return Err(e);
    }
    if f.channels == 0 {
        return Err(Error::NoSuchChannel);
    }
    if f.frac_bits > MAX_FRAC_BITS {
        return Err(Error::FracBitsUnsupported {
            frac_bits: f.frac_bits,
            max: MAX_FRAC_BITS,
        });
    }
    if f.min_box[0] > f.max_box[0] || f.min_box[1] > f.max_box[1] {
        return Err(Error::InvertedBox);
    }
    if f.max_box[0] == 0 || f.max_box[1] == 0 {
        return Err(Error::ZeroArea);
    }
    Ok(())
}

/// Step 1 of the module docs.
const fn choose_lookup(f: &SceneFacts) -> PlanLookup {
    if f.frac_bits == 0 {
        return PlanLookup::Int4;
    }
    match shortcut_error(f) {
        Some((num, den)) if f.tolerance > 0 => match f.tolerance.checked_mul(den) {
            Some(t) if num <= t => PlanLookup::Shortcut {
                min_side: min_side_texels(f),
            },
            _ => PlanLookup::Stable,
        },
        _ => PlanLookup::Stable,
    }
}

/// The smallest box's smaller side in whole texels (rounded down).
const fn min_side_texels(f: &SceneFacts) -> u64 {
    let a = f.min_box[0] >> f.frac_bits;
    let b = f.min_box[1] >> f.frac_bits;
    if a < b {
        a
    } else {
        b
    }
}

/// The shortcut's worst error over the scene's boxes in units of the mean's last bit, as
/// `(num, den)`: `m 2^g (1/(W-1) + 1/(H-1)) + 1/2` for the smallest box's sides rounded down to
/// whole texels `W, H >= 2`; `None` below 2 texels or on overflow.
const fn shortcut_error(f: &SceneFacts) -> Option<(u64, u64)> {
    let w = f.min_box[0] >> f.frac_bits;
    let h = f.min_box[1] >> f.frac_bits;
    if w < 2 || h < 2 || f.mean_frac_bits > 32 {
        return None;
    }
    #[allow(clippy::arithmetic_side_effects, reason = "w, h >= 2 (checked above)")]
    let (a, b) = (w - 1, h - 1);
    let m = width::max_texel_u64(f.texel_bits);
    let Some(den) = a.checked_mul(b) else {
        return None;
    };
    let Some(den2) = den.checked_mul(2) else {
        return None;
    };
    // 2 m 2^g (a + b) + a b, over 2 a b.
    let Some(t) = m.checked_mul(2) else {
        return None;
    };
    let Some(t) = t.checked_shl(f.mean_frac_bits) else {
        return None;
    };
    // a + b cannot overflow where this is called (F >= 1, so a, b < 2^63), but checked all the
    // same: an overflow is the documented None.
    let Some(sides) = a.checked_add(b) else {
        return None;
    };
    let Some(t) = t.checked_mul(sides) else {
        return None;
    };
    let Some(num) = t.checked_add(den) else {
        return None;
    };
    Some((num, den2))
}

/// [`Plan::mean_fits_u32`]: `W H < 2^32` for the largest box and `b + g <= 32`.
const fn mean_fits_u32(f: &SceneFacts) -> bool {
    let [w, h] = f.max_box;
    let area_fits = match w.checked_mul(h) {
        Some(a) => a <= 0xFFFF_FFFF,
        None => false,
    };
    let mean_fits = match 32u32.checked_sub(f.texel_bits) {
        Some(room) => f.mean_frac_bits <= room,
        None => false,
    };
    area_fits && mean_fits
}

const fn max_error(f: &SceneFacts, lookup: PlanLookup) -> (u64, u64) {
    match lookup {
        PlanLookup::Shortcut { .. } => match shortcut_error(f) {
            Some(e) => e,
            None => (u64::MAX, 1),
        },
        _ => (1, 2),
    }
}

/// In-range lookups a box may split into per axis (module docs of [`crate::edge`]).
const fn pieces_per_axis(f: &SceneFacts, n: usize, max_side: u64) -> u32 {
    if !f.leaves_texture {
        return 1;
    }
    #[allow(
        clippy::as_conversions,
        reason = "usize -> u64 is lossless (usize::BITS <= 64, asserted in width.rs); From is not const"
    )]
    let p = (n as u64) << f.frac_bits;
    match f.edge {
        EdgeKind::Border => 1,
        EdgeKind::Clamp | EdgeKind::Repeat | EdgeKind::Mirror => {
            if max_side <= p {
                2
            } else {
                3
            }
        }
    }
}

/// Cells `ceil(hi) - floor(lo)` a raw interval of width `d` can overlap.
const fn max_cells(d: u64, f: u32) -> u64 {
    if f == 0 {
        d
    } else {
        (d >> f).saturating_add(2)
    }
}

const fn reject(layout: PlanLayout, entry: Option<EntryWord>, why: RejectReason) -> Rejection {
    Rejection { layout, entry, why }
}

/// Sizes one candidate, or says why it cannot serve.
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "const fn (no From/TryFrom): u32 -> usize and usize -> u64 are lossless (32 <= \
              usize::BITS <= 64); n as usize and channels as u32 follow checks that they fit; \
              bits / 8 by a constant; the cost counts are small: fields is 1 or 4, pieces per axis \
              1 to 3 (lookups = px py <= 9, >= 1), corner reads and ops below 32"
)]
const fn size_candidate(
    f: &SceneFacts,
    lookup: PlanLookup,
    layout: PlanLayout,
    widest: bool,
) -> Result<Sized, Rejection> {
    let form = lookup.form();
    let total_bits = width::entry_bits_worst_case(f.texel_bits, f.width, f.height);
    // The modulus the largest box needs, where the layout is modular.
    let layout = match layout {
        PlanLayout::Modular { .. } | PlanLayout::TiledModular { .. } => {
            let cells = max_cells(f.max_box[0], f.frac_bits)
                .saturating_mul(max_cells(f.max_box[1], f.frac_bits));
            let headroom = if matches!(lookup, PlanLookup::Int4) {
                0
            } else {
                form.modular_headroom_bits(f.frac_bits)
            };
            let k = modulus_bits_for(f.texel_bits, cells).saturating_add(headroom);
            let with_k = match layout {
                PlanLayout::TiledModular { tile, .. } => PlanLayout::TiledModular { tile, k },
                _ => PlanLayout::Modular { k },
            };
            if k >= total_bits {
                return Err(reject(with_k, None, RejectReason::NoSaving { k }));
            }
            with_k
        }
        PlanLayout::Tiled { tile } => {
            if tile as usize >= f.width && tile as usize >= f.height {
                return Err(reject(
                    layout,
                    None,
                    RejectReason::Refused(Error::InvalidLevels),
                ));
            }
            layout
        }
        _ => layout,
    };
    let value_bits = match layout.modulus() {
        Some(k) => k,
        None => total_bits,
    };
    let acc = lookup.acc_bits(value_bits, f.frac_bits);
    // The narrowest word holding the values whose accumulator holds the lookup (the widest
    // word for the second flat candidate).
    let Some(mut entry) = EntryWord::at_least(value_bits) else {
        return Err(reject(
            layout,
            None,
            RejectReason::TooWide {
                bits_needed: value_bits,
                bits_available: 64,
            },
        ));
    };
    if widest {
        entry = EntryWord::U64;
    }
    while acc > width::acc_value_bits(entry.bits()) {
        entry = match entry.wider() {
            Some(e) => e,
            None => {
                return Err(reject(
                    layout,
                    None,
                    RejectReason::TooWide {
                        bits_needed: acc,
                        bits_available: 127,
                    },
                ))
            }
        };
    }
    // Storage.
    let words = match layout {
        PlanLayout::Flat => None,
        PlanLayout::Modular { k } => Some(modular_words(f.width, f.height, k, f.channels)),
        _ => match layout.tiled_spec() {
            Some(spec) => Some(tiled_words(
                spec,
                f.width,
                f.height,
                f.texel_bits,
                f.channels,
            )),
            None => Some(Err(Error::InvalidLevels)),
        },
    };
    let (storage_len, bytes) = match words {
        None => {
            // The flat table's own size check (sides below 2^31, the entry count in usize).
            if let Err(e) = check_dimensions(f.width, f.height, f.channels) {
                return Err(reject(layout, Some(entry), RejectReason::Refused(e)));
            }
            let n = (f.width as u64)
                .saturating_mul(f.height as u64)
                .saturating_mul(f.channels as u64);
            if n > usize::MAX as u64 {
                return Err(reject(
                    layout,
                    Some(entry),
                    RejectReason::Refused(Error::TextureTooLarge { dimension: f.width }),
                ));
            }
            (n as usize, n.saturating_mul(entry.bits() as u64 / 8))
        }
        Some(Ok(w)) => (w, (w as u64).saturating_mul(4)),
        Some(Err(e)) => return Err(reject(layout, Some(entry), RejectReason::Refused(e))),
    };
    // Costs.
    let fields: u32 = match layout {
        PlanLayout::Tiled { .. } | PlanLayout::TiledModular { .. } => 4,
        _ => 1,
    };
    let px = pieces_per_axis(f, f.width, f.max_box[0]);
    let py = pieces_per_axis(f, f.height, f.max_box[1]);
    let lookups = px * py;
    let c = if f.channels > u32::MAX as usize {
        u32::MAX
    } else {
        f.channels as u32
    };
    let (muls, adds) = lookup.ops();
    let reads = lookups
        .saturating_mul(lookup.corner_reads())
        .saturating_mul(fields);
    let field_adds = lookup.corner_reads().saturating_mul(fields - 1);
    // Split: one add per piece after the first, up to two multiplies per piece pair.
    let split_muls = if lookups > 1 { 2 * lookups } else { 0 };
    let costs = PlanCosts {
        reads,
        muls: c.saturating_mul(
            lookups
                .saturating_mul(muls)
                .saturating_add(split_muls)
                .saturating_add(1),
        ),
        divs: c,
        adds: c.saturating_mul(
            lookups
                .saturating_mul(adds + field_adds)
                .saturating_add(lookups - 1),
        ),
    };
    if f.max_reads > 0 && reads > f.max_reads {
        return Err(reject(
            layout,
            Some(entry),
            RejectReason::TooManyReads { reads },
        ));
    }
    Ok(Sized {
        layout,
        entry,
        storage_len,
        bytes,
        costs,
        acc_bits: acc,
    })
}

#[allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    reason = "const fn (no iterators): i < MAX_CANDIDATES (loop condition) indexes in bounds and \
              the increment stays at most MAX_CANDIDATES"
)]
const fn duplicate(list: &[Option<Rejection>; MAX_CANDIDATES], n: usize, r: &Rejection) -> bool {
    let mut i = 0;
    while i < n && i < MAX_CANDIDATES {
        if let Some(x) = &list[i] {
            if same_layout(x.layout, r.layout) && same_entry(x.entry, r.entry) {
                return true;
            }
        }
        i += 1;
    }
    false
}

const fn same_entry(a: Option<EntryWord>, b: Option<EntryWord>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits() == b.bits(),
        _ => false,
    }
}

const fn same_layout(a: PlanLayout, b: PlanLayout) -> bool {
    match (a, b) {
        (PlanLayout::Flat, PlanLayout::Flat) | (PlanLayout::Packed, PlanLayout::Packed) => true,
        (PlanLayout::Tiled { tile: x }, PlanLayout::Tiled { tile: y }) => x == y,
        (PlanLayout::Modular { k: x }, PlanLayout::Modular { k: y }) => x == y,
        (
            PlanLayout::TiledModular { tile: t, k: x },
            PlanLayout::TiledModular { tile: u, k: y },
        ) => t == u && x == y,
        _ => false,
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
