//! `--filter`: the comparison filters of `texsat::filters` (Heckbert 1986, "Comparison of
//! Prefiltering Methods"; Du and Wan, "Dipmap") behind `sat query` and `sat info`.
//!
//! | `--filter` | structure | sample | survey |
//! |---|---|---|---|
//! | `point` | the texture | [`point::point`]: the texel at the footprint centre | 1, 0 |
//! | `mip` | [`MipPyramid`] | [`MipPyramid::point_sample`] (point-sampled pyramid) | 1, 0 |
//! | `trilinear` | [`MipPyramid`] | [`MipPyramid::trilinear`] (Williams) | 8, 7 |
//! | `ripmap` | [`RipMap`] | [`RipMap::sample`] (4-D pyramid) | 16, 15 |
//! | `dipmap` | [`DipMap`] | [`DipMap::sample`] with [`DipFilter::Bilinear`] | (8, 6) |
//! | `dipmap-trilinear` | [`DipMap`] | [`DipMap::sample`] with [`DipFilter::Trilinear`] | (16, 14) |
//! | `box` | the SAT (`--layout`) | the box sum and mean (the rest of `sat`) | 4, 2 or 16, 14 |
//! | `tent` | [`TentTable`] | [`TentTable::sample_int`] or [`TentTable::sample`] | 9, 4 or 36, 31 |
//! | `tent-exact` | [`TentTable`] + [`TentLines`] | [`TentTable::sample_exact`] | — |
//! | `variance` | [`VarianceTables`] | [`VarianceTables::variance_int`] or `variance` | — |
//!
//! Each structure is built once per run, in `Vec`s of the sizes its `storage_needed` gives,
//! reserved with `try_reserve_exact`; [`estimate`] counts the same sizes before the image is
//! decoded, so a command over its budget is refused before anything large is allocated. Each
//! filter is compiled only with its crate feature (`filter-point`, ..., or `filters` for all);
//! without it `--filter NAME` is refused with a message naming the feature.
//!
//! Entry types: the tent table is `u64` (`u128` when [`tent_entry_bits`] exceeds 64), the tent
//! line tables `u32` or `u64` ([`tent_line_bits`]), the variance tables the narrowest of `u32`
//! and `u64` that holds the squares ([`squares_entry_bits`]) unless `--entry` names one.

// Without some filter features, parts of this module have nothing to run.
#![cfg_attr(
    not(all(
        feature = "filter-point",
        feature = "filter-mip",
        feature = "filter-rip",
        feature = "filter-dip",
        feature = "filter-tent",
        feature = "filter-variance"
    )),
    allow(dead_code, unused_imports, unused_variables, unreachable_code)
)]

use crate::num::Inexact;
use crate::{answer_lines, entry_name, parse_box, per_channel, round4, EdgeArg, EntryArg, FormArg};
use clap::ValueEnum;
use serde_json::{json, Map, Value};
use texsat::filters::{Sample, OUT_FRAC_BITS};
use texsat::{Error, FracBits, Rect, Tally, Texel, Texture};
use texsat_tools::budget::{self, Estimate};

#[cfg(feature = "filter-dip")]
use texsat::filters::dip::{DipFilter, DipMap, DipPyramid};
#[cfg(feature = "filter-mip")]
use texsat::filters::mip::MipPyramid;
#[cfg(feature = "filter-point")]
use texsat::filters::point;
#[cfg(feature = "filter-rip")]
use texsat::filters::rip::RipMap;
#[cfg(feature = "filter-tent")]
use texsat::filters::tent::{tent_entry_bits, tent_line_bits, TentEntry, TentLines, TentTable};
#[cfg(feature = "filter-variance")]
use texsat::filters::variance::{squares_entry_bits, VarianceTables};

/// The filter a query runs (`--filter`).
#[derive(Clone, Copy, PartialEq, Eq, Debug, ValueEnum)]
pub enum FilterArg {
    /// Nearest texel to the footprint centre: 1 read, 0 multiplies.
    Point,
    /// Point-sampled mip pyramid (level round(log2 max(W, H))): 1 read, 0 multiplies.
    Mip,
    /// Williams' trilinear interpolation on the mip pyramid: 8 reads, 7 multiplies.
    Trilinear,
    /// 4-D pyramid (ripmap), u and v scaled independently: 16 reads, 15 multiplies.
    Ripmap,
    /// Dipmap, bilinear in the lower level of the row and column pyramids: 8 reads, 6 multiplies.
    Dipmap,
    /// Dipmap, trilinear in both pyramids: 16 reads, 14 multiplies.
    DipmapTrilinear,
    /// The summed-area table's box filter (sum and mean; the default).
    Box,
    /// Triangle filter by repeated integration: integer centre and half-widths 9 reads, 3 muls +
    /// 1 div; otherwise the paper's bilinear form, 36 reads, 30 muls + 1 div.
    Tent,
    /// Triangle filter, exact for fixed-point corners: 81 reads.
    TentExact,
    /// Variance over the box from SATs of the values and the squares.
    Variance,
}

impl FilterArg {
    /// The name on the command line and in the output.
    pub fn name(self) -> &'static str {
        match self {
            FilterArg::Point => "point",
            FilterArg::Mip => "mip",
            FilterArg::Trilinear => "trilinear",
            FilterArg::Ripmap => "ripmap",
            FilterArg::Dipmap => "dipmap",
            FilterArg::DipmapTrilinear => "dipmap-trilinear",
            FilterArg::Box => "box",
            FilterArg::Tent => "tent",
            FilterArg::TentExact => "tent-exact",
            FilterArg::Variance => "variance",
        }
    }

    /// The crate feature the filter needs (`None` for the box filter, always there).
    fn feature(self) -> Option<&'static str> {
        match self {
            FilterArg::Point => Some("filter-point"),
            FilterArg::Mip | FilterArg::Trilinear => Some("filter-mip"),
            FilterArg::Ripmap => Some("filter-rip"),
            FilterArg::Dipmap | FilterArg::DipmapTrilinear => Some("filter-dip"),
            FilterArg::Box => None,
            FilterArg::Tent | FilterArg::TentExact => Some("filter-tent"),
            FilterArg::Variance => Some("filter-variance"),
        }
    }

    /// Whether this binary was built with the filter's feature.
    fn compiled(self) -> bool {
        match self {
            FilterArg::Point => cfg!(feature = "filter-point"),
            FilterArg::Mip | FilterArg::Trilinear => cfg!(feature = "filter-mip"),
            FilterArg::Ripmap => cfg!(feature = "filter-rip"),
            FilterArg::Dipmap | FilterArg::DipmapTrilinear => cfg!(feature = "filter-dip"),
            FilterArg::Box => true,
            FilterArg::Tent | FilterArg::TentExact => cfg!(feature = "filter-tent"),
            FilterArg::Variance => cfg!(feature = "filter-variance"),
        }
    }

    /// Whether `--entry` chooses the filter's table type.
    fn takes_entry(self) -> bool {
        matches!(self, FilterArg::Box | FilterArg::Variance)
    }
}

/// The texel types of the images (`u8`, `u16`) with what every filter's build needs.
pub trait ImageTexel: Texel + Default {}
impl ImageTexel for u8 {}
impl ImageTexel for u16 {}

/// Checks, before the image is read, that `filter` is compiled in and that the table options
/// given make sense for it. The box filter takes every option.
pub fn check_options(
    filter: FilterArg,
    layout_is_flat: bool,
    checked: bool,
    entry: Option<EntryArg>,
) -> Result<(), String> {
    if !filter.compiled() {
        return Err(format!(
            "--filter {} needs the crate feature '{}', which this binary was built without \
             (build with --features filters)",
            filter.name(),
            filter.feature().unwrap_or("filters")
        ));
    }
    if filter == FilterArg::Box {
        return Ok(());
    }
    if !layout_is_flat {
        return Err(format!(
            "--layout applies to --filter box only (the {} filter builds its own structure)",
            filter.name()
        ));
    }
    if checked {
        return Err(format!(
            "--checked applies to --filter box only, not to --filter {}",
            filter.name()
        ));
    }
    if let Some(e) = entry {
        if !filter.takes_entry() {
            return Err(format!(
                "--entry applies to --filter box and variance only, not to --filter {}",
                filter.name()
            ));
        }
        if filter == FilterArg::Variance && e == EntryArg::U16 {
            return Err(
                "--filter variance stores its tables in u32 or u64 (--entry u16 is not \
                        offered: one squared 8-bit texel already needs 16 bits)"
                    .to_string(),
            );
        }
    }
    Ok(())
}

/// The options of a filtered query.
pub struct FilterQuery {
    pub filter: FilterArg,
    pub frac_bits: u32,
    pub edge: EdgeArg,
    pub form: FormArg,
    pub inexact: Inexact,
    pub entry: Option<EntryArg>,
}

/// The query box `[x0, y0, x1, y1]` (raw units) and its `F`, checked once: every filter takes
/// `F` as a value (`*_raw` entry points), so one sampler per filter serves every `--frac-bits`.
fn raw_box(raw: [i64; 4], f: u32) -> Result<(Rect<i64>, FracBits), Error> {
    let [x0, y0, x1, y1] = raw;
    Ok((Rect::new(x0, y0, x1, y1), FracBits::new(f)?))
}

/// One answer line: the value(s), the filter, the variant if any, and the costs.
fn respond<const C: usize>(
    filter: FilterArg,
    variant: Option<&'static str>,
    s: &Sample<C>,
    k: &Tally,
) -> Value {
    let mut o = Map::new();
    o.insert(
        "value".into(),
        per_channel(s.values.map(u128::from), OUT_FRAC_BITS),
    );
    o.insert("filter".into(), json!(filter.name()));
    if let Some(v) = variant {
        o.insert("variant".into(), json!(v));
    }
    for (key, n) in [
        ("reads", k.reads),
        ("bits_read", k.bits_read),
        ("words", k.words),
        ("muls", k.muls),
        ("divs", k.divs),
        ("adds", k.adds),
    ] {
        o.insert(key.into(), json!(n));
    }
    Value::Object(o)
}

/// What one sample returns: the value and the variant that computed it (tent, variance).
type Sampled<const C: usize> = Result<(Sample<C>, Option<&'static str>), Error>;

/// Answers the query lines on stdin with `sample`.
fn run_lines<const C: usize>(
    q: &FilterQuery,
    mut sample: impl FnMut([i64; 4], &mut Tally) -> Sampled<C>,
) -> Result<bool, String> {
    answer_lines(|line| {
        let raw = parse_box(line, q.frac_bits, q.inexact)?;
        let mut k = Tally::new();
        let (s, variant) = sample(raw, &mut k).map_err(|e| e.to_string())?;
        Ok(respond(q.filter, variant, &s, &k))
    })
}

/// A refused build, for stderr.
fn build_error(filter: FilterArg, what: &str, e: Error) -> String {
    format!("cannot build the {what} of --filter {}: {e}", filter.name())
}

/// `needed` elements of `T`, refusing the saturated sizes some `storage_needed` return, and
/// reporting (not aborting on) an allocation failure.
fn storage<T: Clone>(needed: usize, zero: T, filter: FilterArg) -> Result<Vec<T>, String> {
    if needed == usize::MAX || needed > isize::MAX as usize / 16 {
        return Err(format!(
            "--filter {}: the structure for this texture is too large to allocate",
            filter.name()
        ));
    }
    budget::zeroed(
        needed,
        zero,
        &format!("structure of --filter {}", filter.name()),
    )
}

/// Whether the tent table of a `w x h` texture of `T` needs `u128` entries (else `u64`).
#[cfg(feature = "filter-tent")]
fn tent_wide<T: Texel>(w: usize, h: usize) -> bool {
    tent_entry_bits(T::BITS, w, h) > 64
}

/// Whether the exact tent's line tables of a `w x h` texture of `T` need `u64` entries (else
/// `u32`).
#[cfg(feature = "filter-tent")]
fn lines_wide<T: Texel>(w: usize, h: usize) -> bool {
    tent_line_bits(T::BITS, w.max(h)) > 32
}

/// Adds to `est` the storage and build work of `filter`'s structure (every filter but box) on a
/// `w x h` texture of `T` texels with `C` channels: the sizes [`query`] and [`info`] allocate,
/// from the same `texsat` functions (through [`budget`]).
pub fn estimate<T: ImageTexel, const C: usize>(
    filter: FilterArg,
    entry: Option<EntryArg>,
    w: usize,
    h: usize,
    est: &mut Estimate,
) {
    #[allow(unreachable_patterns)]
    match filter {
        #[cfg(feature = "filter-mip")]
        FilterArg::Mip | FilterArg::Trilinear => est.push_sized(budget::mip::<T, C>(w, h)),
        #[cfg(feature = "filter-rip")]
        FilterArg::Ripmap => est.push(budget::rip::<T, C>(w, h)),
        #[cfg(feature = "filter-dip")]
        FilterArg::Dipmap | FilterArg::DipmapTrilinear => est.push(budget::dip::<T, C>(w, h)),
        #[cfg(feature = "filter-tent")]
        FilterArg::Tent | FilterArg::TentExact => {
            est.push_sized(if tent_wide::<T>(w, h) {
                budget::tent::<u128, C>(w, h)
            } else {
                budget::tent::<u64, C>(w, h)
            });
            if filter == FilterArg::TentExact {
                est.push_sized(if lines_wide::<T>(w, h) {
                    budget::tent_lines::<u64, C>(w, h)
                } else {
                    budget::tent_lines::<u32, C>(w, h)
                });
            }
        }
        #[cfg(feature = "filter-variance")]
        FilterArg::Variance => est.push_sized(match variance_entry::<T>(w, h, entry) {
            EntryArg::U64 => budget::variance::<u64, C>(w, h),
            _ => budget::variance::<u32, C>(w, h),
        }),
        // point reads the texture only; box is the table (`layout::estimate`).
        _ => {}
    }
}

/// Runs the query lines through `q.filter` on `texture` (every filter but box).
pub fn query<T: ImageTexel, const C: usize>(
    texture: &Texture<'_, T, C>,
    q: &FilterQuery,
) -> Result<bool, String> {
    #[allow(unreachable_patterns)]
    match q.filter {
        #[cfg(feature = "filter-point")]
        FilterArg::Point => run_lines(q, |raw, k| {
            raw_box(raw, q.frac_bits)
                .and_then(|(r, f)| point::point_raw(texture, &r, f, q.edge.kind(), k))
                .map(|s| (s, None))
        }),
        #[cfg(feature = "filter-mip")]
        FilterArg::Mip | FilterArg::Trilinear => {
            let (w, h) = (texture.width(), texture.height());
            let needed = MipPyramid::<T, C>::storage_needed(w, h)
                .map_err(|e| build_error(q.filter, "mip pyramid", e))?;
            let mut st = storage(needed, T::default(), q.filter)?;
            let pyramid = MipPyramid::build(texture, &mut st)
                .map_err(|e| build_error(q.filter, "mip pyramid", e))?;
            let tri = q.filter == FilterArg::Trilinear;
            run_lines(q, |raw, k| {
                raw_box(raw, q.frac_bits)
                    .and_then(|(r, f)| {
                        if tri {
                            pyramid.trilinear_raw(&r, f, q.edge.kind(), k)
                        } else {
                            pyramid.point_sample_raw(&r, f, q.edge.kind(), k)
                        }
                    })
                    .map(|s| (s, None))
            })
        }
        #[cfg(feature = "filter-rip")]
        FilterArg::Ripmap => {
            let (w, h) = (texture.width(), texture.height());
            let mut st = storage(RipMap::<T, C>::storage_needed(w, h), T::default(), q.filter)?;
            let map =
                RipMap::build(texture, &mut st).map_err(|e| build_error(q.filter, "ripmap", e))?;
            run_lines(q, |raw, k| {
                raw_box(raw, q.frac_bits)
                    .and_then(|(r, f)| map.sample_raw(&r, f, q.edge.kind(), k))
                    .map(|s| (s, None))
            })
        }
        #[cfg(feature = "filter-dip")]
        FilterArg::Dipmap | FilterArg::DipmapTrilinear => {
            let (w, h) = (texture.width(), texture.height());
            let mut st = storage(DipMap::<T, C>::storage_needed(w, h), T::default(), q.filter)?;
            let map =
                DipMap::build(texture, &mut st).map_err(|e| build_error(q.filter, "dipmap", e))?;
            let variant = if q.filter == FilterArg::Dipmap {
                DipFilter::Bilinear
            } else {
                DipFilter::Trilinear
            };
            run_lines(q, |raw, k| {
                raw_box(raw, q.frac_bits)
                    .and_then(|(r, f)| map.sample_raw(&r, f, variant, q.edge.kind(), k))
                    .map(|s| (s, None))
            })
        }
        #[cfg(feature = "filter-tent")]
        FilterArg::Tent | FilterArg::TentExact => {
            let (w, h) = (texture.width(), texture.height());
            if tent_wide::<T>(w, h) {
                tent_query::<T, u128, C>(texture, q)
            } else {
                tent_query::<T, u64, C>(texture, q)
            }
        }
        #[cfg(feature = "filter-variance")]
        FilterArg::Variance => {
            match variance_entry::<T>(texture.width(), texture.height(), q.entry) {
                EntryArg::U64 => variance_query::<T, u64, C>(texture, q),
                _ => variance_query::<T, u32, C>(texture, q),
            }
        }
        other => Err(format!(
            "--filter {} is not available in this binary",
            other.name()
        )),
    }
}

// ---------------------------------------------------------------------------------------------
// Tent

/// The tent filter's lookups on a `Q` table of entry type `E` (and, for `tent-exact`, line
/// tables of the narrowest of `u32`/`u64` that hold them).
#[cfg(feature = "filter-tent")]
fn tent_query<T: ImageTexel, E: TentEntry, const C: usize>(
    texture: &Texture<'_, T, C>,
    q: &FilterQuery,
) -> Result<bool, String> {
    let (w, h) = (texture.width(), texture.height());
    let err = |e| build_error(q.filter, "tent table", e);
    let needed = TentTable::<E, C>::storage_needed(w, h).map_err(err)?;
    let mut st = storage(needed, E::ZERO, q.filter)?;
    let table = TentTable::<E, C>::build(texture, &mut st).map_err(err)?;
    if q.filter == FilterArg::TentExact {
        return if lines_wide::<T>(w, h) {
            tent_exact_query::<T, E, u64, C>(texture, &table, q)
        } else {
            tent_exact_query::<T, E, u32, C>(texture, &table, q)
        };
    }
    let f = q.frac_bits;
    run_lines(q, |raw, k| {
        if let Some((cx, cy, a, b)) = tent_int_box(raw, f) {
            let s = {
                let m = q.edge.kind();
                table.sample_int(cx, cy, a, b, m, k)
            }?;
            return Ok((s, Some("int")));
        }
        let (r, fb) = raw_box(raw, f)?;
        let s = table.sample_raw(&r, fb, q.edge.kind(), k)?;
        Ok((s, Some("paper")))
    })
}

/// The integer centre and half-widths `(cx, cy, a, b)` of `raw` if its four corners are
/// integers and both sides are even and non-negative, and they fit the integer lookup's `i32`
/// and `u32` arguments; `None` sends the box to the paper form.
#[cfg(feature = "filter-tent")]
fn tent_int_box(raw: [i64; 4], f: u32) -> Option<(i32, i32, u32, u32)> {
    let mask = (1i64 << f) - 1;
    if raw.iter().any(|&v| v & mask != 0) {
        return None;
    }
    let [x0, y0, x1, y1] = raw.map(|v| i128::from(v >> f));
    let (sw, sh) = (x1 - x0, y1 - y0);
    if sw < 0 || sh < 0 || sw % 2 != 0 || sh % 2 != 0 {
        return None;
    }
    Some((
        i32::try_from((x0 + x1) / 2).ok()?,
        i32::try_from((y0 + y1) / 2).ok()?,
        u32::try_from(sw / 2).ok()?,
        u32::try_from(sh / 2).ok()?,
    ))
}

#[cfg(feature = "filter-tent")]
fn tent_exact_query<T: ImageTexel, E: TentEntry, L: TentEntry, const C: usize>(
    texture: &Texture<'_, T, C>,
    table: &TentTable<'_, E, C>,
    q: &FilterQuery,
) -> Result<bool, String> {
    let (w, h) = (texture.width(), texture.height());
    let err = |e| build_error(q.filter, "tent line tables", e);
    let needed = TentLines::<L, C>::storage_needed(w, h).map_err(err)?;
    let mut st = storage(needed, L::ZERO, q.filter)?;
    let lines = TentLines::<L, C>::build(texture, &mut st).map_err(err)?;
    run_lines(q, |raw, k| {
        raw_box(raw, q.frac_bits)
            .and_then(|(r, f)| table.sample_exact_raw(&lines, texture, &r, f, q.edge.kind(), k))
            .map(|s| (s, None))
    })
}

// ---------------------------------------------------------------------------------------------
// Variance

/// The variance tables' entry type: `--entry`, else the narrowest of `u32` and `u64` that holds
/// the squares (which need more bits than the values).
#[cfg(feature = "filter-variance")]
fn variance_entry<T: Texel>(w: usize, h: usize, entry: Option<EntryArg>) -> EntryArg {
    entry.unwrap_or(if squares_entry_bits(T::BITS, w, h) <= 32 {
        EntryArg::U32
    } else {
        EntryArg::U64
    })
}

#[cfg(feature = "filter-variance")]
fn variance_query<T: ImageTexel, E: texsat::Entry, const C: usize>(
    texture: &Texture<'_, T, C>,
    q: &FilterQuery,
) -> Result<bool, String> {
    let (w, h) = (texture.width(), texture.height());
    let err = |e| build_error(q.filter, "variance tables", e);
    let needed = VarianceTables::<E, C>::storage_needed(w, h).map_err(err)?;
    let mut values = storage(needed, E::ZERO, q.filter)?;
    let mut squares = storage(needed, E::ZERO, q.filter)?;
    let tables = VarianceTables::<E, C>::build(texture, &mut values, &mut squares).map_err(err)?;
    let f = q.frac_bits;
    run_lines(q, |raw, k| {
        let mask = (1i64 << f) - 1;
        if raw.iter().all(|&v| v & mask == 0) {
            let c = raw.map(|v| i32::try_from(v >> f));
            if let [Ok(x0), Ok(y0), Ok(x1), Ok(y1)] = c {
                let r = Rect::new(x0, y0, x1, y1);
                let s = {
                    let m = q.edge.kind();
                    tables.variance_int(&r, m, k)
                }?;
                return Ok((s, Some("int")));
            }
            return Err(Error::CoordinateOutOfRange);
        }
        let (r, fb) = raw_box(raw, f)?;
        let s = tables.variance_raw(&r, fb, q.form.kind(), q.edge.kind(), k)?;
        let form = match q.form {
            FormArg::Paper => "paper",
            FormArg::Stable => "stable",
        };
        Ok((s, Some(form)))
    })
}

// ---------------------------------------------------------------------------------------------
// sat info --filter

/// Memory facts of a built filter structure.
struct Memory {
    /// Bytes of the filter's own (caller-provided) storage.
    storage_bytes: usize,
    /// Whether samples also read the texture itself (point, the mip pyramid's level 0,
    /// tent-exact).
    reads_texture: bool,
    /// Filter-specific fields.
    extra: Vec<(&'static str, Value)>,
}

/// One JSON object about `filter`'s structure for `texture`: sizes and the memory ratio to the
/// texture (every filter but box, which `sat info` reports with its table).
pub fn info<T: ImageTexel, const C: usize>(
    texture: &Texture<'_, T, C>,
    filter: FilterArg,
    entry: Option<EntryArg>,
) -> Result<Value, String> {
    let (w, h) = (texture.width(), texture.height());
    let tsize = std::mem::size_of::<T>();
    #[allow(unreachable_patterns)]
    let mem: Memory = match filter {
        #[cfg(feature = "filter-point")]
        FilterArg::Point => Memory {
            storage_bytes: 0,
            reads_texture: true,
            extra: vec![],
        },
        #[cfg(feature = "filter-mip")]
        FilterArg::Mip | FilterArg::Trilinear => {
            let err = |e| build_error(filter, "mip pyramid", e);
            let needed = MipPyramid::<T, C>::storage_needed(w, h).map_err(err)?;
            let mut st = storage(needed, T::default(), filter)?;
            let p = MipPyramid::build(texture, &mut st).map_err(err)?;
            Memory {
                storage_bytes: p.storage_len() * tsize,
                reads_texture: true,
                extra: vec![
                    ("levels", json!(p.level_count())),
                    (
                        "pyramid_texels",
                        json!(MipPyramid::<T, C>::pyramid_texels(w, h).map_err(err)?),
                    ),
                    ("storage_type", json!(texel_name::<T>())),
                ],
            }
        }
        #[cfg(feature = "filter-rip")]
        FilterArg::Ripmap => {
            let mut st = storage(RipMap::<T, C>::storage_needed(w, h), T::default(), filter)?;
            let m =
                RipMap::build(texture, &mut st).map_err(|e| build_error(filter, "ripmap", e))?;
            Memory {
                storage_bytes: m.storage_len() * tsize,
                reads_texture: false,
                extra: vec![
                    ("levels_x", json!(m.levels_x())),
                    ("levels_y", json!(m.levels_y())),
                    ("storage_type", json!(texel_name::<T>())),
                ],
            }
        }
        #[cfg(feature = "filter-dip")]
        FilterArg::Dipmap | FilterArg::DipmapTrilinear => {
            let mut st = storage(DipMap::<T, C>::storage_needed(w, h), T::default(), filter)?;
            let m =
                DipMap::build(texture, &mut st).map_err(|e| build_error(filter, "dipmap", e))?;
            Memory {
                storage_bytes: m.storage_len() * tsize,
                reads_texture: false,
                extra: vec![
                    ("levels_row", json!(m.levels(DipPyramid::Row))),
                    ("levels_column", json!(m.levels(DipPyramid::Column))),
                    ("storage_type", json!(texel_name::<T>())),
                ],
            }
        }
        #[cfg(feature = "filter-tent")]
        FilterArg::Tent | FilterArg::TentExact => {
            if tent_wide::<T>(w, h) {
                tent_memory::<T, u128, C>(texture, filter)?
            } else {
                tent_memory::<T, u64, C>(texture, filter)?
            }
        }
        #[cfg(feature = "filter-variance")]
        FilterArg::Variance => match variance_entry::<T>(w, h, entry) {
            EntryArg::U64 => variance_memory::<T, u64, C>(texture, filter)?,
            _ => variance_memory::<T, u32, C>(texture, filter)?,
        },
        other => {
            return Err(format!(
                "--filter {} is not available in this binary",
                other.name()
            ))
        }
    };
    let texture_bytes = w * h * C * tsize;
    let memory_bytes = mem.storage_bytes + if mem.reads_texture { texture_bytes } else { 0 };
    let mut o = Map::new();
    for (key, v) in [
        ("width", json!(w)),
        ("height", json!(h)),
        ("channels", json!(C)),
        ("texel_bits", json!(T::BITS)),
        ("texel_type", json!(texel_name::<T>())),
        ("filter", json!(filter.name())),
        ("texture_bytes", json!(texture_bytes)),
        ("storage_bytes", json!(mem.storage_bytes)),
        ("reads_texture", json!(mem.reads_texture)),
        ("memory_bytes", json!(memory_bytes)),
        (
            "memory_ratio",
            round4(memory_bytes as f64 / texture_bytes as f64),
        ),
    ] {
        o.insert(key.into(), v);
    }
    for (key, v) in mem.extra {
        o.insert(key.into(), v);
    }
    Ok(Value::Object(o))
}

/// `u8` or `u16`.
fn texel_name<T: Texel>() -> &'static str {
    if T::BITS == 8 {
        "u8"
    } else {
        "u16"
    }
}

/// `u32`, `u64` or `u128` for a tent entry type.
#[cfg(feature = "filter-tent")]
fn tent_entry_name<E: TentEntry>() -> &'static str {
    match E::BITS {
        32 => "u32",
        64 => "u64",
        _ => "u128",
    }
}

#[cfg(feature = "filter-tent")]
fn tent_memory<T: ImageTexel, E: TentEntry, const C: usize>(
    texture: &Texture<'_, T, C>,
    filter: FilterArg,
) -> Result<Memory, String> {
    let (w, h) = (texture.width(), texture.height());
    let err = |e| build_error(filter, "tent table", e);
    let needed = TentTable::<E, C>::storage_needed(w, h).map_err(err)?;
    let mut st = storage(needed, E::ZERO, filter)?;
    let table = TentTable::<E, C>::build(texture, &mut st).map_err(err)?;
    let mut extra = vec![
        ("entry_type", json!(tent_entry_name::<E>())),
        ("entry_bits_needed", json!(tent_entry_bits(T::BITS, w, h))),
        ("table_bytes", json!(table.table_bytes())),
    ];
    if filter == FilterArg::Tent {
        return Ok(Memory {
            storage_bytes: table.table_bytes(),
            reads_texture: false,
            extra,
        });
    }
    let line_bits = tent_line_bits(T::BITS, w.max(h));
    let lines_bytes = if lines_wide::<T>(w, h) {
        tent_lines_bytes::<T, u64, C>(texture, filter)?
    } else {
        tent_lines_bytes::<T, u32, C>(texture, filter)?
    };
    extra.extend([
        (
            "lines_entry_type",
            json!(if lines_wide::<T>(w, h) { "u64" } else { "u32" }),
        ),
        ("lines_bits_needed", json!(line_bits)),
        ("lines_bytes", json!(lines_bytes)),
    ]);
    Ok(Memory {
        storage_bytes: table.table_bytes() + lines_bytes,
        reads_texture: true,
        extra,
    })
}

#[cfg(feature = "filter-tent")]
fn tent_lines_bytes<T: ImageTexel, L: TentEntry, const C: usize>(
    texture: &Texture<'_, T, C>,
    filter: FilterArg,
) -> Result<usize, String> {
    let err = |e| build_error(filter, "tent line tables", e);
    let needed =
        TentLines::<L, C>::storage_needed(texture.width(), texture.height()).map_err(err)?;
    let mut st = storage(needed, L::ZERO, filter)?;
    Ok(TentLines::<L, C>::build(texture, &mut st)
        .map_err(err)?
        .table_bytes())
}

#[cfg(feature = "filter-variance")]
fn variance_memory<T: ImageTexel, E: texsat::Entry, const C: usize>(
    texture: &Texture<'_, T, C>,
    filter: FilterArg,
) -> Result<Memory, String> {
    let (w, h) = (texture.width(), texture.height());
    let err = |e| build_error(filter, "variance tables", e);
    let needed = VarianceTables::<E, C>::storage_needed(w, h).map_err(err)?;
    let mut values = storage(needed, E::ZERO, filter)?;
    let mut squares = storage(needed, E::ZERO, filter)?;
    let t = VarianceTables::<E, C>::build(texture, &mut values, &mut squares).map_err(err)?;
    let name = match E::BITS {
        16 => EntryArg::U16,
        32 => EntryArg::U32,
        _ => EntryArg::U64,
    };
    Ok(Memory {
        storage_bytes: t.table_bytes(),
        reads_texture: false,
        extra: vec![
            ("tables", json!(2)),
            ("entry_type", json!(entry_name(name))),
            (
                "values_bits_needed",
                json!(texsat::width::entry_bits_worst_case(T::BITS, w, h)),
            ),
            (
                "squares_bits_needed",
                json!(squares_entry_bits(T::BITS, w, h)),
            ),
            ("values_bytes", json!(t.values().table_bytes())),
            ("squares_bytes", json!(t.squares().table_bytes())),
        ],
    })
}
