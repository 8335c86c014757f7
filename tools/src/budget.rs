//! Resource budgets of the host tools: what a command is about to take (memory and work),
//! estimated from the image header *before* anything large is allocated, and checked against
//! `--max-memory` and `--max-work`.
//!
//! A test bench may hand the tools any file: a 21-byte PGM whose header claims 200000 x 200000
//! texels, a 261 KB PNG of 16384 x 16384 zeros. Every structure the tools build from an image is
//! sized by a function of the `texsat` crate (`Sat::entries_needed`, `Tiled::words_needed`,
//! `RipMap::storage_needed`, ...); the estimates here call the same functions, so they cannot
//! drift from what the builds allocate (the tests below build each structure in exactly the
//! storage the estimate names). Above the budget the command is refused with a message that names
//! the need, the budget and the flag that raises it.
//!
//! **Memory** is counted in bytes of the large buffers: the decoded image, the table or filter
//! structure, the builders' scratch. Small, bounded allocations (a query line, at most
//! [`MAX_LINE_BYTES`]; JSON output; per-level bookkeeping) are not counted.
//!
//! **Work** is counted in *texel operations*: texels times channels times a per-texel cost of
//! each pass the command makes over the image ([`cost`]). The costs are the builds' passes and
//! additions per texel, scaled so that one operation is roughly 0.5 ns of one core in a release
//! build on the development machine (2 shared cores); the default budget, [`DEFAULT_MAX_WORK`],
//! is then about 15 s there. Work per query line is bounded (every lookup reads a fixed number of
//! entries, whatever the box), so the lines themselves are not counted: their number is the
//! caller's.
//!
//! Amounts on the command line take binary suffixes: `K` = 2^10, `M` = 2^20, `G` = 2^30,
//! `T` = 2^40 (also `KiB`, `MB`, ...; case-insensitive), for bytes and operations alike.

use texsat::layouts::{Modular, Tiled, TiledSpec};
use texsat::{Entry, Error, Sat};

#[cfg(any(feature = "filter-mip", feature = "filter-rip", feature = "filter-dip"))]
use texsat::Texel;

#[cfg(feature = "filter-dip")]
use texsat::filters::dip::DipMap;
#[cfg(feature = "filter-mip")]
use texsat::filters::mip::MipPyramid;
#[cfg(feature = "filter-rip")]
use texsat::filters::rip::RipMap;
#[cfg(feature = "filter-tent")]
use texsat::filters::tent::{TentEntry, TentLines, TentTable};
#[cfg(feature = "filter-variance")]
use texsat::filters::variance::VarianceTables;

/// The default memory budget: 1 GiB (`--max-memory 1G`).
pub const DEFAULT_MAX_MEMORY: u64 = 1 << 30;

/// The default work budget: 32 G texel operations (`--max-work 32G`), about 15 s of one core
/// on the development machine (module docs). It accepts the largest commands the repository's
/// tests and report run by a wide margin (a ripmap of 8192 x 8192 texels, 13 G operations) and
/// refuses the ripmap of 16384 x 16384 (56 G operations, 45 s).
pub const DEFAULT_MAX_WORK: u64 = 32 << 30;

/// The longest query line the tools read (bytes, newline excluded); a longer line is answered
/// with an error line and skipped, so a line without an end cannot grow a buffer without bound.
pub const MAX_LINE_BYTES: usize = 4096;

/// Per-texel costs of the passes, in texel operations per texel and channel (module docs).
pub mod cost {
    /// Decoding the image into its sample buffer.
    pub const DECODE: u64 = 1;
    /// One pass summing every texel (the whole-texture totals `sat info` reports and checks).
    pub const TOTALS: u64 = 1;
    /// The flat summed-area table: Crow's two additions per entry.
    pub const FLAT: u64 = 2;
    /// The modular table: the flat table's additions, then the masking and packing.
    pub const MODULAR: u64 = 4;
    /// The packed and tiled layouts, fixed part: the field packing.
    pub const TILED: u64 = 16;
    /// The packed and tiled layouts, per component (x components times y components).
    pub const TILED_PER_COMPONENT: u64 = 2;
    /// The mip pyramid, per level (each level is one pass over the texture).
    pub const MIP_PER_LEVEL: u64 = 1;
    /// The ripmap, per level pair (each of the `levels_x * levels_y` levels is one pass).
    pub const RIP_PER_LEVEL: u64 = 1;
    /// The dipmap, per level of either pyramid (`levels_x + levels_y` passes, strided ones).
    pub const DIP_PER_LEVEL: u64 = 2;
    /// The order-2 (tent) table: 3 + 3 additions per entry.
    pub const TENT: u64 = 6;
    /// The exact tent's line tables: 3 additions per entry, two tables.
    pub const TENT_LINES: u64 = 6;
    /// The variance tables: the values' table, the squares' (a multiply and 3 additions).
    pub const VARIANCE: u64 = 6;
}

/// The limits a command runs under.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// Bytes (`--max-memory`).
    pub max_memory: u64,
    /// Texel operations (`--max-work`).
    pub max_work: u64,
}

impl Default for Budget {
    fn default() -> Self {
        Budget {
            max_memory: DEFAULT_MAX_MEMORY,
            max_work: DEFAULT_MAX_WORK,
        }
    }
}

/// Parses an amount: a whole number with an optional binary suffix (`K`, `M`, `G`, `T`, with
/// or without `B` or `iB`; case-insensitive): `1073741824`, `1G`, `512M`, `2GiB`. Zero and
/// amounts above `u64::MAX` are refused.
pub fn parse_amount(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let digits_end = t.bytes().take_while(u8::is_ascii_digit).count();
    let (digits, suffix) = t.split_at(digits_end);
    if digits.is_empty() {
        return Err(format!(
            "'{s}' is not an amount: expected a whole number with an optional suffix K, M, G or \
             T (powers of 1024), e.g. 2G or 512M"
        ));
    }
    let shift = match suffix.to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        _ => {
            return Err(format!(
                "'{s}': unknown suffix '{suffix}' (expected K, M, G or T, powers of 1024)"
            ))
        }
    };
    let n: u64 = digits
        .parse()
        .map_err(|_| format!("'{s}' is too large (at most {})", u64::MAX))?;
    if n == 0 {
        return Err(format!("'{s}': a budget must be at least 1"));
    }
    n.checked_mul(1u64 << shift).ok_or_else(|| {
        format!(
            "'{s}' is too large (at most {} bytes or operations)",
            u64::MAX
        )
    })
}

/// `v` in binary units with 2 decimals: `512 bytes`, `1.50 KiB`, `6.56 GiB`; `u128::MAX` (a
/// size that overflowed) as "more than 2^64 bytes".
pub fn show_bytes(v: u128) -> String {
    if v > u128::from(u64::MAX) {
        return "more than 2^64 bytes".to_string();
    }
    match scaled(v) {
        (_, "") => format!("{v} bytes"),
        (x, unit) => format!("{x:.2} {unit}iB"),
    }
}

/// `v` texel operations with a binary suffix: `812`, `56.25G`.
pub fn show_work(v: u128) -> String {
    if v > u128::from(u64::MAX) {
        return "more than 2^64".to_string();
    }
    match scaled(v) {
        (_, "") => v.to_string(),
        (x, unit) => format!("{x:.2}{unit}"),
    }
}

/// `v` as a multiple of the largest power of 1024 not above it, and that power's letter.
fn scaled(v: u128) -> (f64, &'static str) {
    let mut unit = "";
    let mut div = 1u128;
    for (u, shift) in [
        ("K", 10),
        ("M", 20),
        ("G", 30),
        ("T", 40),
        ("P", 50),
        ("E", 60),
    ] {
        if v >= 1u128 << shift {
            unit = u;
            div = 1 << shift;
        }
    }
    (v as f64 / div as f64, unit)
}

/// The smallest whole amount in the largest unit that holds `v`, for a flag's example value:
/// `7046430720` gives `7G`.
pub fn suggest(v: u128) -> String {
    for (u, shift) in [("T", 40u32), ("G", 30), ("M", 20), ("K", 10)] {
        if v >= 1u128 << shift {
            return format!("{}{u}", v.div_ceil(1u128 << shift));
        }
    }
    v.max(1).to_string()
}

/// One part of a command's need.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Item {
    /// What it is ("decoded image", "order-2 table", ...).
    pub what: String,
    /// Bytes allocated (`u128::MAX` if the size overflows).
    pub bytes: u128,
    /// Texel operations.
    pub work: u128,
}

impl Item {
    /// `elems` elements of `elem_bytes` bytes and `work` operations.
    pub fn new(what: &str, elems: usize, elem_bytes: usize, work: u128) -> Item {
        Item {
            what: what.to_string(),
            bytes: elems as u128 * elem_bytes as u128,
            work,
        }
    }

    /// Work only (a pass that allocates nothing).
    pub fn work(what: &str, work: u128) -> Item {
        Item {
            what: what.to_string(),
            bytes: 0,
            work,
        }
    }
}

/// What a command is about to take, part by part.
#[derive(Clone, Debug, Default)]
pub struct Estimate {
    /// The command, for the message ("info --filter ripmap on this 16384 x 16384 image").
    pub subject: String,
    /// The parts.
    pub items: Vec<Item>,
}

impl Estimate {
    /// An empty estimate for `subject`.
    pub fn new(subject: impl Into<String>) -> Self {
        Estimate {
            subject: subject.into(),
            items: Vec::new(),
        }
    }

    /// Adds a part.
    pub fn push(&mut self, item: Item) {
        self.items.push(item);
    }

    /// Adds a part sized by a `texsat` size function. An error there is not a need: the build
    /// calls the same function before it allocates and refuses with that error, so the part is
    /// left out here and the build's own message reaches the user.
    pub fn push_sized(&mut self, item: Result<Item, Error>) {
        if let Ok(i) = item {
            self.items.push(i);
        }
    }

    /// Total bytes (saturating).
    pub fn bytes(&self) -> u128 {
        self.items
            .iter()
            .fold(0u128, |a, i| a.saturating_add(i.bytes))
    }

    /// Total texel operations (saturating).
    pub fn work(&self) -> u128 {
        self.items
            .iter()
            .fold(0u128, |a, i| a.saturating_add(i.work))
    }

    /// Refuses an estimate above `budget`, with a message naming the need part by part, the
    /// budget and the flag that raises it.
    pub fn check(&self, budget: &Budget) -> Result<(), String> {
        let (bytes, work) = (self.bytes(), self.work());
        // How to raise a budget to `v`, unless no value of the flag is that large.
        let raise = |flag: &str, value: &str, v: u128, why: &str| {
            if v > u128::from(u64::MAX) {
                format!("no {flag} can be that large")
            } else {
                format!(
                    "raise it with {flag} {value} (e.g. {flag} {}){why}",
                    suggest(v)
                )
            }
        };
        let mut over = Vec::new();
        if bytes > u128::from(budget.max_memory) {
            over.push(format!(
                "needs about {} of memory ({}), above the memory budget of {}; {}",
                show_bytes(bytes),
                self.parts(|i| i.bytes, show_bytes),
                show_bytes(u128::from(budget.max_memory)),
                raise(
                    "--max-memory",
                    "BYTES",
                    bytes,
                    " if the machine has the memory"
                )
            ));
        }
        if work > u128::from(budget.max_work) {
            over.push(format!(
                "needs about {} texel operations ({}), above the work budget of {} (32G is \
                 about 15 s of one core); {}",
                show_work(work),
                self.parts(|i| i.work, show_work),
                show_work(u128::from(budget.max_work)),
                raise("--max-work", "N", work, "")
            ));
        }
        if over.is_empty() {
            Ok(())
        } else {
            Err(format!("{} {}", self.subject, over.join("; and it ")))
        }
    }

    /// `"what amount, ..."` of the parts with a non-zero `amount`.
    fn parts(&self, amount: impl Fn(&Item) -> u128, show: impl Fn(u128) -> String) -> String {
        self.items
            .iter()
            .filter(|i| amount(i) > 0)
            .map(|i| format!("{} {}", i.what, show(amount(i))))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// `w * h * c` as `u128` (never overflows for `usize` inputs).
fn texel_count(w: usize, h: usize, c: usize) -> u128 {
    w as u128 * h as u128 * c as u128
}

/// Levels of an axis of `n >= 1` texels in the pyramids: `ceil(log2 n) + 1`.
pub fn levels(n: usize) -> u128 {
    u128::from(usize::BITS - n.saturating_sub(1).leading_zeros()) + 1
}

/// The decoded image: `w * h * c` samples of `sample_bytes` bytes, and the decode pass.
pub fn image(w: usize, h: usize, c: usize, sample_bytes: usize) -> Item {
    Item {
        what: "decoded image".to_string(),
        bytes: texel_count(w, h, c) * sample_bytes as u128,
        work: texel_count(w, h, c) * u128::from(cost::DECODE),
    }
}

/// One pass summing the texels (no allocation).
pub fn totals(w: usize, h: usize, c: usize) -> Item {
    Item::work(
        "texture totals",
        texel_count(w, h, c) * u128::from(cost::TOTALS),
    )
}

/// The flat table: [`Sat::entries_needed`] entries of `E`.
pub fn flat<E: Entry, const C: usize>(w: usize, h: usize) -> Result<Item, Error> {
    let n = Sat::<E, C>::entries_needed(w, h)?;
    let work = texel_count(w, h, C) * u128::from(cost::FLAT);
    Ok(Item::new("summed-area table", n, size_of::<E>(), work))
}

/// The words and scratch [`Tiled::build`] takes ([`Tiled::words_needed`] 32-bit words,
/// [`Tiled::scratch_needed`] entries of `E`).
pub fn tiled<E: Entry, const C: usize>(
    spec: TiledSpec,
    w: usize,
    h: usize,
    texel_bits: u32,
) -> Result<Item, Error> {
    let words = Tiled::<E, C>::words_needed(spec, w, h, texel_bits)?;
    let scratch = Tiled::<E, C>::scratch_needed(spec, w)?;
    let components = (spec.x.components() * spec.y.components()) as u64;
    let per_texel = cost::TILED + cost::TILED_PER_COMPONENT * components;
    Ok(Item {
        what: "tiled table".to_string(),
        bytes: words as u128 * 4 + scratch as u128 * size_of::<E>() as u128,
        work: texel_count(w, h, C) * u128::from(per_texel),
    })
}

/// Row entries [`Modular::build`] takes: one row of `w * C` entries of `E`.
pub fn modular_row<const C: usize>(w: usize) -> Result<usize, Error> {
    w.checked_mul(C)
        .ok_or(Error::TextureTooLarge { dimension: w })
}

/// The words and row [`Modular::build`] takes ([`Modular::words_needed`], [`modular_row`]).
pub fn modular<E: Entry, const C: usize>(w: usize, h: usize, k: u32) -> Result<Item, Error> {
    let words = Modular::<E, C>::words_needed(w, h, k)?;
    let row = modular_row::<C>(w)?;
    Ok(Item {
        what: "modular table".to_string(),
        bytes: words as u128 * 4 + row as u128 * size_of::<E>() as u128,
        work: texel_count(w, h, C) * u128::from(cost::MODULAR),
    })
}

/// The mip pyramid's coarse levels ([`MipPyramid::storage_needed`] texels of `T`).
#[cfg(feature = "filter-mip")]
pub fn mip<T: Texel, const C: usize>(w: usize, h: usize) -> Result<Item, Error> {
    let n = MipPyramid::<T, C>::storage_needed(w, h)?;
    let passes = levels(w.max(h)) * u128::from(cost::MIP_PER_LEVEL);
    Ok(Item::new(
        "mip pyramid",
        n,
        size_of::<T>(),
        texel_count(w, h, C) * passes,
    ))
}

/// The ripmap's levels ([`RipMap::storage_needed`] texels of `T`; it saturates, so the item
/// can only be too large, never wrong).
#[cfg(feature = "filter-rip")]
pub fn rip<T: Texel, const C: usize>(w: usize, h: usize) -> Item {
    let n = RipMap::<T, C>::storage_needed(w, h);
    let passes = levels(w) * levels(h) * u128::from(cost::RIP_PER_LEVEL);
    Item::new("ripmap", n, size_of::<T>(), texel_count(w, h, C) * passes)
}

/// The dipmap's two pyramids ([`DipMap::storage_needed`] texels of `T`, saturating).
#[cfg(feature = "filter-dip")]
pub fn dip<T: Texel, const C: usize>(w: usize, h: usize) -> Item {
    let n = DipMap::<T, C>::storage_needed(w, h);
    let passes = (levels(w) + levels(h)) * u128::from(cost::DIP_PER_LEVEL);
    Item::new("dipmap", n, size_of::<T>(), texel_count(w, h, C) * passes)
}

/// The order-2 table ([`TentTable::storage_needed`] entries of `E`).
#[cfg(feature = "filter-tent")]
pub fn tent<E: TentEntry, const C: usize>(w: usize, h: usize) -> Result<Item, Error> {
    let n = TentTable::<E, C>::storage_needed(w, h)?;
    let work = texel_count(w, h, C) * u128::from(cost::TENT);
    Ok(Item::new("order-2 table", n, size_of::<E>(), work))
}

/// The exact tent's line tables ([`TentLines::storage_needed`] entries of `L`).
#[cfg(feature = "filter-tent")]
pub fn tent_lines<L: TentEntry, const C: usize>(w: usize, h: usize) -> Result<Item, Error> {
    let n = TentLines::<L, C>::storage_needed(w, h)?;
    let work = texel_count(w, h, C) * u128::from(cost::TENT_LINES);
    Ok(Item::new("tent line tables", n, size_of::<L>(), work))
}

/// Both variance tables (twice [`VarianceTables::storage_needed`] entries of `E`).
#[cfg(feature = "filter-variance")]
pub fn variance<E: Entry, const C: usize>(w: usize, h: usize) -> Result<Item, Error> {
    let n = VarianceTables::<E, C>::storage_needed(w, h)?;
    let work = texel_count(w, h, C) * u128::from(cost::VARIANCE);
    let mut item = Item::new("variance tables", n, size_of::<E>(), work);
    item.bytes *= 2;
    Ok(item)
}

/// A zeroed `Vec` of `n` elements whose allocation failure is an error, not an abort
/// (`try_reserve_exact`). `what` names the buffer in the message.
pub fn zeroed<T: Clone>(n: usize, zero: T, what: &str) -> Result<Vec<T>, String> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        format!(
            "cannot allocate the {what}: {} ({n} elements of {} bytes) are not available",
            show_bytes(n as u128 * size_of::<T>() as u128),
            size_of::<T>()
        )
    })?;
    v.resize(n, zero);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use texsat::Texture;

    #[test]
    fn amounts_parse_with_binary_suffixes() {
        assert_eq!(parse_amount("1"), Ok(1));
        assert_eq!(parse_amount("1073741824"), Ok(1 << 30));
        assert_eq!(parse_amount("1G"), Ok(1 << 30));
        assert_eq!(parse_amount("2g"), Ok(2 << 30));
        assert_eq!(parse_amount("512M"), Ok(512 << 20));
        assert_eq!(parse_amount("512MiB"), Ok(512 << 20));
        assert_eq!(parse_amount("3KB"), Ok(3 << 10));
        assert_eq!(parse_amount("5T"), Ok(5 << 40));
        assert_eq!(parse_amount("16E").ok(), None);
        assert_eq!(parse_amount("15T"), Ok(15 << 40));
        for bad in [
            "",
            "G",
            "-1",
            "0",
            "0G",
            "1.5G",
            "1X",
            "1 G",
            "1e9",
            "nan",
            "1GG",
            "18446744073709551616",
            "16777216T",
        ] {
            assert!(parse_amount(bad).is_err(), "{bad:?} should be refused");
        }
        assert_eq!(parse_amount("18446744073709551615"), Ok(u64::MAX));
    }

    #[test]
    fn amounts_show_in_binary_units() {
        assert_eq!(show_bytes(512), "512 bytes");
        assert_eq!(show_bytes(1536), "1.50 KiB");
        assert_eq!(show_bytes(7_046_430_720), "6.56 GiB");
        assert_eq!(show_bytes(u128::MAX), "more than 2^64 bytes");
        assert_eq!(show_work(812), "812");
        assert_eq!(show_work(60_397_977_600), "56.25G");
        assert_eq!(suggest(7_046_430_720), "7G");
        assert_eq!(suggest(1 << 30), "1G");
        assert_eq!(suggest((1 << 30) + 1), "2G");
        assert_eq!(suggest(1000), "1000");
        assert_eq!(suggest(5000), "5K");
        assert_eq!(suggest(u128::from(u64::MAX)), "16777216T");
    }

    #[test]
    fn check_names_need_budget_and_flag() {
        let mut e = Estimate::new("test command");
        e.push(Item::new("decoded image", 1 << 28, 1, 1 << 28));
        e.push(Item::new("ripmap", 1 << 30, 1, 60 << 30));
        let small = Budget {
            max_memory: 1 << 30,
            max_work: 32 << 30,
        };
        let msg = e.check(&small).unwrap_err();
        assert!(msg.starts_with("test command needs about 1.25 GiB of memory"));
        assert!(
            msg.contains("decoded image 256.00 MiB, ripmap 1.00 GiB"),
            "{msg}"
        );
        assert!(msg.contains("above the memory budget of 1.00 GiB"), "{msg}");
        assert!(msg.contains("--max-memory 2G"), "{msg}");
        assert!(msg.contains("texel operations"), "{msg}");
        assert!(msg.contains("above the work budget of 32.00G"), "{msg}");
        assert!(msg.contains("--max-work 61G"), "{msg}");
        let big = Budget {
            max_memory: 2 << 30,
            max_work: 61 << 30,
        };
        assert_eq!(e.check(&big), Ok(()));
        // Exactly at the budget is accepted.
        let exact = Budget {
            max_memory: (1 << 30) + (1 << 28),
            max_work: (60 << 30) + (1 << 28),
        };
        assert_eq!(e.check(&exact), Ok(()));
        let memory_only = Budget {
            max_work: u64::MAX,
            ..small
        };
        let msg = e.check(&memory_only).unwrap_err();
        assert!(msg.contains("--max-memory") && !msg.contains("--max-work"));
        // A need no flag can express (a saturated size) says so.
        let mut huge = Estimate::new("huge");
        huge.push(Item {
            what: "ripmap".to_string(),
            bytes: u128::MAX,
            work: 1,
        });
        let msg = huge.check(&Budget::default()).unwrap_err();
        assert!(msg.contains("more than 2^64 bytes"), "{msg}");
        assert!(msg.contains("no --max-memory can be that large"), "{msg}");
    }

    #[test]
    fn sized_errors_are_left_to_the_build() {
        let mut e = Estimate::new("x");
        e.push_sized(flat::<u32, 1>(0, 5));
        assert!(e.items.is_empty());
        e.push_sized(flat::<u32, 1>(3, 5));
        assert_eq!(e.bytes(), 60);
    }

    #[test]
    fn zeroed_reports_failure() {
        let v = zeroed(5, 7u16, "test buffer").unwrap();
        assert_eq!(v, [7; 5]);
        let e = zeroed(usize::MAX / 2, 0u64, "huge buffer").unwrap_err();
        assert!(e.starts_with("cannot allocate the huge buffer"), "{e}");
    }

    /// Deterministic texels of `bits` bits.
    fn texels(n: usize, bits: u32) -> Vec<u16> {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        (0..n)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
                ((s >> 33) % (1 << bits)) as u16
            })
            .collect()
    }

    const SIZES: [(usize, usize); 5] = [(1, 1), (7, 3), (16, 16), (33, 17), (64, 65)];

    /// Each layout builds in exactly the storage its estimate names, and the estimate holds
    /// the bytes the built layout reports.
    #[test]
    fn layout_estimates_hold_the_builds() {
        for (w, h) in SIZES {
            let t8: Vec<u8> = texels(w * h * 2, 8).iter().map(|&v| v as u8).collect();
            let tex = Texture::<u8, 2>::new(&t8, w, h).unwrap();
            let item = flat::<u32, 2>(w, h).unwrap();
            let n = Sat::<u32, 2>::entries_needed(w, h).unwrap();
            assert_eq!(item.bytes, (n * 4) as u128);
            let mut st = vec![0u32; n];
            let sat = Sat::build(&tex, &mut st).unwrap();
            assert!(sat.table_bytes() as u128 <= item.bytes, "flat {w}x{h}");
            assert_eq!(item.work, (w * h * 2) as u128 * 2);

            for spec in [
                TiledSpec::FLAT_PACKED,
                TiledSpec::tiles(4, 2).unwrap(),
                TiledSpec::square(&[2, 8]).unwrap(),
                TiledSpec::tiles(4, 4).unwrap().with_modulus(12),
            ] {
                let item = tiled::<u32, 2>(spec, w, h, 8).unwrap();
                let words = Tiled::<u32, 2>::words_needed(spec, w, h, 8).unwrap();
                let scratch = Tiled::<u32, 2>::scratch_needed(spec, w).unwrap();
                assert_eq!(item.bytes, (words * 4 + scratch * 4) as u128);
                let (mut wd, mut sc) = (vec![0u32; words], vec![0u32; scratch]);
                let t = Tiled::<u32, 2>::build(&tex, spec, &mut wd, &mut sc).unwrap();
                assert!(
                    texsat::Layout::storage_bits(&t) as u128 <= item.bytes * 8,
                    "tiled {spec:?} {w}x{h}"
                );
            }

            let item = modular::<u64, 2>(w, h, 20).unwrap();
            let words = Modular::<u64, 2>::words_needed(w, h, 20).unwrap();
            let row = modular_row::<2>(w).unwrap();
            assert_eq!(item.bytes, (words * 4 + row * 8) as u128);
            let (mut wd, mut r) = (vec![0u32; words], vec![0u64; row]);
            let m = Modular::<u64, 2>::build(&tex, 20, &mut wd, &mut r).unwrap();
            assert!(texsat::Layout::storage_bits(&m) as u128 <= item.bytes * 8);
        }
    }

    /// Each filter structure builds in exactly the storage its estimate names.
    #[test]
    #[cfg(all(
        feature = "filter-mip",
        feature = "filter-rip",
        feature = "filter-dip",
        feature = "filter-tent",
        feature = "filter-variance"
    ))]
    fn filter_estimates_hold_the_builds() {
        for (w, h) in SIZES {
            let t16 = texels(w * h * 3, 16);
            let tex = Texture::<u16, 3>::new(&t16, w, h).unwrap();

            let item = mip::<u16, 3>(w, h).unwrap();
            let mut st = vec![0u16; (item.bytes / 2) as usize];
            let p = MipPyramid::build(&tex, &mut st).unwrap();
            assert!(p.storage_len() as u128 * 2 <= item.bytes, "mip {w}x{h}");
            assert_eq!(item.work, (w * h * 3) as u128 * p.level_count() as u128);

            let item = rip::<u16, 3>(w, h);
            let mut st = vec![0u16; (item.bytes / 2) as usize];
            let m = RipMap::build(&tex, &mut st).unwrap();
            assert!(m.storage_len() as u128 * 2 <= item.bytes, "rip {w}x{h}");
            let passes = (m.levels_x() * m.levels_y()) as u128;
            assert_eq!(item.work, (w * h * 3) as u128 * passes);

            let item = dip::<u16, 3>(w, h);
            let mut st = vec![0u16; (item.bytes / 2) as usize];
            let d = DipMap::build(&tex, &mut st).unwrap();
            assert!(d.storage_len() as u128 * 2 <= item.bytes, "dip {w}x{h}");

            let item = tent::<u64, 3>(w, h).unwrap();
            let mut st = vec![0u64; (item.bytes / 8) as usize];
            let t = TentTable::<u64, 3>::build(&tex, &mut st).unwrap();
            assert!(t.table_bytes() as u128 <= item.bytes, "tent {w}x{h}");

            let item = tent_lines::<u64, 3>(w, h).unwrap();
            let mut st = vec![0u64; (item.bytes / 8) as usize];
            let l = TentLines::<u64, 3>::build(&tex, &mut st).unwrap();
            assert!(l.table_bytes() as u128 <= item.bytes, "lines {w}x{h}");

            let item = variance::<u64, 3>(w, h).unwrap();
            let n = VarianceTables::<u64, 3>::storage_needed(w, h).unwrap();
            assert_eq!(item.bytes, (2 * n * 8) as u128);
            let (mut v, mut s) = (vec![0u64; n], vec![0u64; n]);
            let t = VarianceTables::<u64, 3>::build(&tex, &mut v, &mut s).unwrap();
            assert!(t.table_bytes() as u128 <= item.bytes, "variance {w}x{h}");
        }
    }

    #[test]
    fn the_issue_examples_exceed_the_default_budget() {
        let b = Budget::default();
        // 16384 x 16384 8-bit gray: tent-exact (u64 table, u64 lines) and ripmap.
        let n = 16384;
        let mut tent_exact = Estimate::new("tent-exact");
        tent_exact.push(image(n, n, 1, 1));
        #[cfg(feature = "filter-tent")]
        {
            tent_exact.push(tent::<u64, 1>(n, n).unwrap());
            tent_exact.push(tent_lines::<u64, 1>(n, n).unwrap());
            assert!(tent_exact.bytes() > 6 << 30, "{}", tent_exact.bytes());
            assert!(tent_exact
                .check(&b)
                .unwrap_err()
                .contains("--max-memory 7G"));
        }
        #[cfg(feature = "filter-rip")]
        {
            let mut ripmap = Estimate::new("ripmap");
            ripmap.push(image(n, n, 1, 1));
            ripmap.push(rip::<u8, 1>(n, n));
            let msg = ripmap.check(&b).unwrap_err();
            assert!(
                msg.contains("--max-memory") && msg.contains("--max-work"),
                "{msg}"
            );
            // 8192 x 8192 fits the work budget (memory aside).
            let mut small = Estimate::new("ripmap");
            small.push(rip::<u8, 1>(8192, 8192));
            assert!(small.work() < u128::from(DEFAULT_MAX_WORK));
        }
        // The 200000 x 200000 PGM of the issue: 40 GB of samples.
        let mut pgm = Estimate::new("pgm");
        pgm.push(image(200_000, 200_000, 1, 1));
        assert!(pgm.check(&b).unwrap_err().contains("37.25 GiB"));
    }
}
