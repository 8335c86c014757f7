//! `sat`: summed-area tables of image files from the command line.
//!
//! ```text
//! sat info IMAGE [--layout L] [--entry u16|u32|u64] [--checked] [--filter NAME]
//!                                                         one JSON object about the table
//! sat query IMAGE [--filter NAME] [--layout L] [--frac-bits F] [--edge MODE] [--form FORM] ...
//!                                                         box queries on stdin, JSON lines out
//! sat plan --size WxH --texel-bits B --box MIN..MAX [--edge MODE] [--frac-bits F] ...
//!                                                         the smallest table for a scene, as JSON
//! sat query IMAGE --plan FILE                             box queries with exactly that plan
//! sat vectors (--scene NAME | --image FILE) --out DIR ...  golden vectors for an RTL test bench
//! sat demo                                                a guided tour on a generated texture
//! ```
//!
//! `--layout` is one of `flat` (the default), `packed`, `tiled:WxH`, `tiled:W1xH1/W2xH2[/...]`,
//! `modular:K`, `modular:box=WxH` and `tiled:WxH+mod:K` (see `sat/layout.rs`). `--filter` is
//! `box` (the summed-area table, the default) or one of the comparison filters `point`, `mip`,
//! `trilinear`, `ripmap`, `dipmap`, `dipmap-trilinear`, `tent`, `tent-exact`, `variance` (see
//! `sat/filter.rs`; they need the crate's `filters` feature: `--features filters`).
//!
//! Every command estimates the memory and work it is about to take from the image header
//! before it allocates, and refuses above `--max-memory` (default 1G) or `--max-work` (default
//! 32G texel operations); see `sat --help` and `texsat_tools::budget`. Exit status: 0 success,
//! 1 refused input, budget, build or query line, 2 command-line usage error; never a signal.
//!
//! Run `sat help <command>` for the details of each command; `cargo run --example sat -- demo`
//! for the tour.

#[path = "sat/demo.rs"]
mod demo;
#[path = "sat/filter.rs"]
mod filter;
#[path = "sat/layout.rs"]
mod layout;
#[path = "sat/load.rs"]
mod load;
#[path = "sat/num.rs"]
mod num;
#[path = "sat/scene.rs"]
mod scene;
#[path = "sat/vectors.rs"]
mod vectors;

use clap::{Args, Parser, Subcommand, ValueEnum};
use filter::{FilterArg, FilterQuery, ImageTexel};
use layout::{with_layout, Detail, LayoutArg, LayoutJob, LayoutKind, Plan, Refused};
use load::{channel_totals, with_texture, with_types, Probe, TextureJob, TypesJob};
use num::{fixed_decimal, parse_fixed, Inexact};
use serde_json::{json, Value};
use std::io::{BufRead, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use texsat::texel::Acc;
use texsat::width::{self, bits_of};
use texsat::{
    BoxLookup, BoxSum, EdgeKind, EdgeMode, Entry, Error, FormKind, FracBits, NoCount, Quantity,
    Rect, RepeatWithinPeriod, Tally, Texel, Texture,
};
use texsat_tools::budget::{self, Budget, Estimate, MAX_LINE_BYTES};

#[derive(Parser)]
#[command(
    name = "sat",
    version,
    about = "Summed-area tables (Crow 1984) of PNG/PNM images: table sizes, exact box sums and means, lookup costs",
    long_about = None,
    after_long_help = RESOURCES_HELP
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    #[command(flatten)]
    budget: BudgetArgs,
}

/// `--max-memory` and `--max-work`, taken by every command.
#[derive(Args, Clone, Copy)]
struct BudgetArgs {
    /// Memory budget in bytes (suffixes K, M, G, T: powers of 1024). A command whose image,
    /// table or filter structure would take more is refused before it allocates.
    #[arg(long, global = true, value_name = "BYTES", default_value = "1G",
          value_parser = budget::parse_amount)]
    max_memory: u64,
    /// Work budget in texel operations (texels x channels x per-texel cost of each pass over
    /// the image; 32G is about 15 s of one core). A command that would take more is refused
    /// before it starts.
    #[arg(long, global = true, value_name = "N", default_value = "32G",
          value_parser = budget::parse_amount)]
    max_work: u64,
}

impl BudgetArgs {
    fn budget(self) -> Budget {
        Budget {
            max_memory: self.max_memory,
            max_work: self.max_work,
        }
    }
}

const RESOURCES_HELP: &str = "\
RESOURCES: every command reads the image header first (decoder limits: sides up to 2^31 - 1,
the decoder's own allocations within --max-memory), then estimates what it is about to take,
from the same size functions the builds use: memory (the decoded image, the table in the chosen
entry type and layout, the filter's pyramids, ripmap, dipmap, order-2 or variance tables, the
builders' scratch) and work (texel operations: texels x channels x the per-texel cost of each
pass over the image, e.g. one pass per ripmap level). Above --max-memory (default 1G) or
--max-work (default 32G, about 15 s of one core) it refuses, naming the need, the budget and
the flag that raises it, before anything large is allocated. A buffer the system cannot give is
reported, not aborted on. Query lines are read up to 4096 bytes each (a longer line is answered
with an error line); every lookup takes a bounded number of reads, whatever the box.

EXIT STATUS: 0 success; 1 refused input (unreadable, corrupt or unsupported image, a plan file
that does not hold), a budget exceeded, a table or structure that cannot be built, or at least
one query line answered with an error line; 2 command-line usage error (unknown option, a
malformed --layout, --max-memory, --max-work or --frac-bits value). Never a signal.";

#[derive(Subcommand)]
enum Command {
    /// Print one JSON object describing IMAGE's summed-area table (sizes and widths).
    #[command(after_long_help = INFO_HELP)]
    Info(InfoArgs),
    /// Answer box queries "x0 y0 x1 y1" read from stdin with one JSON object per line.
    #[command(after_long_help = QUERY_HELP)]
    Query(QueryArgs),
    /// Print the plan for a scene (the smallest table, entry word and lookup that serve its
    /// facts, with costs and the rejected candidates) as one JSON object.
    #[command(after_long_help = RESOURCES_HELP)]
    Plan(scene::PlanArgs),
    /// Write golden vectors for a hardware test bench: stimulus, bit-exact expected sums and
    /// means with their costs, and the table memory image (hex for $readmemh, or JSON).
    #[command(after_long_help = vectors::VECTORS_HELP)]
    Vectors(vectors::VectorsArgs),
    /// Build the table of a generated 256 x 256 texture and walk through sizes, lookups and costs.
    #[command(after_long_help = RESOURCES_HELP)]
    Demo,
}

const INFO_HELP: &str = "\
Output fields, every layout: width, height, channels, texel_bits, texel_type,
bits_needed_worst_case (bits of (2^b - 1) * w * h, what the exact builds prove before they
write), bits_needed_naive (b + ceil(log2(w * h)), the textbook bound, for comparison),
bits_needed_actual (bits of the largest per-channel whole-texture sum of this image), layout (the
--layout string), bits_per_entry (storage bits / (w * h * channels)), bits_per_texel (storage
bits / (w * h), all channels), storage_bits, table_bytes, fields_per_corner (the most table values
one corner S(x, y) reads), totals (per-channel whole-texture sums as decimal strings; an array
when channels > 1).

flat (the default): row-major, channels interleaved, entry (i, j) = sum of texels (i', j') with
i' <= i and j' <= j, in native --entry words; also entry_type, entry_bits, value_type (=
entry_type), table_entries, build (\"worst_case\" or \"checked\"). bits_per_entry = entry_bits.

packed, tiled:..., modular:...: fields of exact widths packed in 32-bit words; also value_type
(the type corner values are summed in), words (table_bytes = 4 x words). bits_per_entry and
bits_per_texel are rounded to 4 decimals.
  packed             the flat table packed at its exact width (bits_needed_worst_case bits)
  tiled:WxH          one level of W x H tiles: local sums, edge strips, tile corners
  tiled:W1xH1/W2xH2  tiles within tiles (x blocks [W1, W2, ...], y blocks [H1, H2, ...]; each a
                     multiple of the previous, at most 4 levels)
  Tiled layouts (packed included) also report blocks_x, blocks_y and field_bits
  (field_bits[p][q]: the field width of component (p, q), p the x level, q the y level; level 0
  = inside the smallest block).
  modular:K          the flat table modulo 2^K, K bits per field: exact only for boxes whose sum
                     stays below 2^K; reports k and max_exact_area = floor((2^K - 1) / (2^b - 1))
  modular:box=WxH    K = bits of (2^b - 1) * W * H: every box of W x H texel cells is exact
  tiled:WxH+mod:K    tiles with every field modulo 2^K (also +mod:box=WxH); reports both
The value type is --entry for exact layouts (default u32) and the narrowest of u32 and u64 that
holds K for modular ones (--entry may name a wider one).

If the entry (value) type is too narrow (the worst case with the default build, the actual sums
with --checked), nothing is printed on stdout; the reason, with the bits needed and available,
goes to stderr and the exit status is 1. A malformed --layout is refused with a message on
stderr (exit status 2), as are K < texel bits and --checked with a layout other than flat (exit
status 1). Before the image's samples are read, the table (or --filter structure) is estimated
from the header: above --max-memory (default 1G) or --max-work (default 32G texel operations)
the command is refused on stderr with the need, the budget and the flag that raises it (exit
status 1); see `sat --help`, RESOURCES.

--filter NAME reports the memory of that filter's structure, built from the image: width,
height, channels, texel_bits, texel_type, filter, texture_bytes (w x h x channels x texel
bytes), storage_bytes (the filter's own storage), reads_texture (whether samples also read the
texture: point, mip/trilinear level 0, tent-exact), memory_bytes (storage, plus the texture if
it is read) and memory_ratio (memory_bytes / texture_bytes, 4 decimals), and per filter:
  point              no storage, ratio 1
  mip, trilinear     levels, pyramid_texels, storage_type: levels 1.. (level 0 is the texture);
                     ratio about 4/3 (Heckbert's 1.33)
  ripmap             levels_x, levels_y, storage_type: every level (u, v scaled apart), the
                     texture copied as level (0, 0); ratio about 4
  dipmap, dipmap-trilinear
                     levels_row, levels_column, storage_type: row and column pyramids sharing
                     level 0; ratio about 3
  tent               entry_type (u64, u128 if needed), entry_bits_needed, table_bytes: the
                     order-2 table of the texture padded by one row and column; u8 texels in u64:
                     about 8
  tent-exact         also lines_entry_type, lines_bits_needed, lines_bytes (per-line order-2
                     tables) and the texture
  variance           tables (2), entry_type (--entry, else u32 or u64, whichever holds the
                     squares), values_bits_needed, squares_bits_needed, values_bytes,
                     squares_bytes
  box                the table report above (--layout, --entry) plus these memory fields.
--layout and --checked apply to box only, --entry to box and variance.";

const QUERY_HELP: &str = "\
INPUT: one box per line, \"x0 y0 x1 y1\" separated by blanks: the box [x0, x1) x [y0, y1) in
texel units (x to the right, y down; texel (i, j) covers [i, i+1) x [j, j+1)). Coordinates are
decimals such as 3, -1.25 or 0.375, parsed exactly (never through floating point). A coordinate
that is not a multiple of 2^-F is an error unless --round is given. Empty lines and lines starting
with '#' are skipped.

OUTPUT: per input line, one JSON object:
  {\"sum\": \"<exact>\", \"mean\": \"<decimal>\", \"filter\": \"box\", \"lookup\": \"int4|paper|stable\",
   \"reads\": R, \"bits_read\": B, \"words\": W, \"muls\": M, \"divs\": D, \"adds\": A}
sum is the exact integral of the texture over the box (a multiple of 2^-2F, printed with all its
digits). mean is sum / area rounded to the nearest multiple of 2^-G (ties away from zero), G =
--mean-bits, printed exactly; it is within 2^-(G+1) of the exact mean. With the border mode the
area is the unclipped box's (outside counts as 0). A zero-area box has sum \"0\" and mean null.
For images with several channels, sum and mean are arrays with one string per channel. Sums and
means are strings because they can exceed 2^53.
The counts are Crow's (1984, section 2.2), tallied over the lookup and the mean: reads of table
values (fields; all channels together), the bits and the 32-bit words they touch, multiplies,
divides and additive operations (per channel). On the flat table interior boxes cost 4 reads, 1
mul, 1 div and 3 adds with integer corners (F = 0) and 16 reads, 13 muls, 1 div, 27 adds (paper)
or 31 adds (stable) with F > 0; with C channels, 12C + 1 muls (paper), C divs and 3C or 27C adds.
The corner function's row y = 0 and column x = 0 are zero and cost no read, so boxes touching the
first texel row or column read fewer entries; boxes straddling the texture edge under clamp,
repeat or mirror take a weighted path with other counts. On a tiled layout a corner reads one
field per pair of non-zero digits of (x, y) (up to 4 with one level of tiles) and adds them: more
reads and adds, fewer bits.

--layout chooses the table the lookups read (see `sat help info`); sums are the same on every
layout. A modular layout (modular:K, tiled:...+mod:K) refuses a box whose sum may reach 2^K: the
texel cells the box overlaps times 2^b - 1 (plus 2F bits for the paper form at F > 0, and for
boxes straddling the texture edge under clamp, repeat or mirror) must stay below 2^K; such a line
gives {\"error\": \"box sum on the modular layout needs X bits but only K are available\", ...}.
A fractional box W texels wide overlaps up to W + 1 cells.

F = 0 uses the 4-read integer lookup (coordinates must be integers). F > 0 uses the 16-read
lookup in the chosen --form for every box, integer corners included (as fixed-point hardware
would), unless --int4 is given.

A line that cannot be answered (wrong number of fields, not a number, not representable at F
bits, inverted box, too wide for the accumulator, too large for the modular layout, longer than
4096 bytes, not UTF-8, ...) gives {\"error\": \"...\", \"line\": N} and the following lines are
still answered; the exit status is then 1. A table that cannot be built, a lookup width that the
value type (or K) can never satisfy, or an image whose table or filter structure is over
--max-memory or --max-work (estimated from the header, before the samples are read; see `sat
--help`, RESOURCES) is reported on stderr before any input is read (exit status 1).

FILTERS: --filter box (the default) is the summed-area table described above. The comparison
filters (Heckbert 1986, \"Comparison of Prefiltering Methods\"; Du and Wan, \"Dipmap\") read the
same lines; a filter that needs a footprint takes the box as the rectangle bounding it (centre
((x0 + x1) / 2, (y0 + y1) / 2), sides W = x1 - x0, H = y1 - y0). Each prints
  {\"value\": \"<decimal>\", \"filter\": NAME, [\"variant\": V,] \"reads\": R, \"bits_read\": B,
   \"words\": W, \"muls\": M, \"divs\": D, \"adds\": A}
value is the filter's output (a multiple of 2^-16, printed exactly; an array of strings with
several channels). The structures are built once per run from the image. Costs are counted as
the survey and Crow count them (reads of texels or table entries, all channels together; the
arithmetic per channel); the survey's figures (reads, multiplies) hold for footprints away from
the edges (reads that the border mode resolves to zero are not counted by ripmap and dipmap):
  point              the texel holding the centre (exact): 1, 0
  mip                point-sampled pyramid: level round(log2 max(W, H)), nearest texel: 1, 0
  trilinear          Williams' trilinear on the pyramid: 8 reads, 7 muls, 14 adds
  ripmap             4-D pyramid, levels log2 W and log2 H apart: 16 reads, 15 muls
  dipmap             bilinear in the lower level of the row and column pyramids, averaged:
                     8 reads, 6 muls
  dipmap-trilinear   trilinear in both pyramids, averaged: 16 reads, 14 muls
  tent               triangle filter by repeated integration. variant \"int\" when the four
                     numbers are integers and both sides even (integer centre and half-widths):
                     9 reads, 3 muls + 1 div, exact; else variant \"paper\": bilinear
                     interpolation of the order-2 table, 36 reads, 30 muls + 1 div, within the
                     documented bound m/4 (1/a^2 + 1/b^2 + 1/(2 a^2 b^2)) of the exact filter
  tent-exact         the exact triangle filter for fixed-point corners: 81 reads, 72 muls + 1 div
  variance           the variance of the texels over the box (exact, rounded to 2^-16): variant
                     \"int\" (integer corners, 8 reads) or the --form used (32 reads)
Every boundary mode (--edge) applies to every filter. ripmap and dipmap floor their output to
2^-16; trilinear, tent, tent-exact and variance round to nearest (ties up); point and mip are
exact. --layout, --checked, --mean-bits and --int4 apply to box only; --entry to box and variance;
--form to box and variance. Zero-area footprints are errors for tent and variance and point
samples for the others.";

#[derive(Clone, Copy, PartialEq, Eq, Debug, ValueEnum)]
enum EntryArg {
    U16,
    U32,
    U64,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum, Debug)]
enum EdgeArg {
    /// Zero outside the texture; the mean divides by the unclipped area.
    Border,
    /// Coordinates clamp to the edge texels.
    Clamp,
    /// The texture repeats.
    Repeat,
    /// The texture repeats, every other copy reflected.
    Mirror,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum FormArg {
    /// Crow's bilinear interpolation of the table at each corner (16 reads, 27 adds).
    Paper,
    /// Differences first; multiplier operands bounded by the box (16 reads, 31 adds).
    Stable,
}

impl EdgeArg {
    /// The crate's run-time mode.
    fn kind(self) -> EdgeKind {
        match self {
            EdgeArg::Border => EdgeKind::Border,
            EdgeArg::Clamp => EdgeKind::Clamp,
            EdgeArg::Repeat => EdgeKind::Repeat,
            EdgeArg::Mirror => EdgeKind::Mirror,
        }
    }
}

impl FormArg {
    /// The crate's run-time form.
    fn kind(self) -> FormKind {
        match self {
            FormArg::Paper => FormKind::Paper,
            FormArg::Stable => FormKind::Stable,
        }
    }
}

#[derive(Args)]
struct TableArgs {
    /// PNG or PNM (PGM, PPM, PAM, PBM) file; 8- or 16-bit samples, 1 to 4 channels.
    image: PathBuf,
    /// Table layout: flat, packed, tiled:WxH, tiled:W1xH1/W2xH2[/...], modular:K,
    /// modular:box=WxH, tiled:WxH+mod:K (see `sat help info`).
    #[arg(long, value_parser = layout::parse_layout, default_value = "flat")]
    layout: LayoutArg,
    /// Table entry type (bits per entry and channel) of the flat layout; the type corner values
    /// are summed in for the others [default: u32; modular: u32 if K <= 32, else u64].
    #[arg(long, value_enum)]
    entry: Option<EntryArg>,
    /// Build with checked additions (`Sat::build_checked`): accept any image whose actual sums
    /// fit the entry type, instead of proving the worst case first (`Sat::build`). Flat only.
    #[arg(long)]
    checked: bool,
}

impl TableArgs {
    /// What to build for texels of `texel_bits` bits.
    fn plan(&self, texel_bits: u32) -> Result<Plan, String> {
        layout::resolve(&self.layout, self.entry, self.checked, texel_bits)
    }
}

#[derive(Args)]
struct InfoArgs {
    #[command(flatten)]
    table: TableArgs,
    /// Report the memory of this filter's structure instead of (box: as well as) the table's.
    #[arg(long, value_enum)]
    filter: Option<FilterArg>,
}

#[derive(Args)]
struct QueryArgs {
    #[command(flatten)]
    table: TableArgs,
    /// The filter that answers each line (see `sat help query`).
    #[arg(long, value_enum, default_value_t = FilterArg::Box)]
    filter: FilterArg,
    /// Fractional bits F of the corner coordinates (0 to 24). F = 0: integer corners, 4 reads.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=24))]
    frac_bits: u32,
    /// Boundary mode for boxes reaching outside the texture.
    #[arg(long, value_enum, default_value_t = EdgeArg::Border)]
    edge: EdgeArg,
    /// Formulation of the 16-read lookup (F > 0).
    #[arg(long, value_enum, default_value_t = FormArg::Paper)]
    form: FormArg,
    /// Round coordinates to the nearest multiple of 2^-F (ties toward +infinity) instead of
    /// refusing those that are not representable.
    #[arg(long)]
    round: bool,
    /// Fractional bits G of the printed mean (0 to 120) [default: min(2F + 8, 40)].
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=120))]
    mean_bits: Option<u32>,
    /// With F > 0, answer boxes whose four coordinates are integers by the 4-read lookup.
    #[arg(long)]
    int4: bool,
    /// A plan written by `sat plan`: answer with exactly its layout, entry, F, mode and lookup
    /// (and its mean bits), refusing boxes outside its facts.
    #[arg(long, conflicts_with_all = ["layout", "entry", "checked", "filter", "frac_bits", "edge", "form", "mean_bits", "int4"])]
    plan: Option<PathBuf>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let budget = cli.budget.budget();
    let result = match cli.command {
        Command::Info(args) => info(&args, &budget),
        Command::Query(args) => query(&args, &budget),
        Command::Plan(args) => scene::run(&args),
        Command::Vectors(args) => vectors::run(&args, &budget),
        Command::Demo => demo::run(&budget),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(msg) => {
            // A closed stderr cannot be told anything more; the status still says it.
            let _ = writeln!(std::io::stderr(), "sat: {msg}");
            ExitCode::FAILURE
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Building the table

fn entry_name(e: EntryArg) -> &'static str {
    match e {
        EntryArg::U16 => "u16",
        EntryArg::U32 => "u32",
        EntryArg::U64 => "u64",
    }
}

fn entry_bits(e: EntryArg) -> u32 {
    match e {
        EntryArg::U16 => 16,
        EntryArg::U32 => 32,
        EntryArg::U64 => 64,
    }
}

/// The message for a refused build: the crate's reason, the numbers behind it, and what to do
/// (or the allocation that failed).
fn refusal<T: Texel, const C: usize>(
    texture: &Texture<'_, T, C>,
    args: &TableArgs,
    plan: &Plan,
    refused: Refused,
) -> String {
    let err = match refused {
        Refused::Build(e) => e,
        Refused::Alloc(msg) => return msg,
    };
    let (w, h, b) = (texture.width(), texture.height(), T::BITS);
    let actual = channel_totals(texture)
        .iter()
        .map(|&t| bits_of(t))
        .max()
        .unwrap_or(0);
    let value = plan.value();
    let mut msg = match plan {
        Plan::Flat { .. } => format!(
            "cannot build the table with {} entries: {err}",
            entry_name(value)
        ),
        _ => format!(
            "cannot build the {} layout with {} values: {err}",
            args.layout.text,
            entry_name(value)
        ),
    };
    if let Error::TooWide {
        what: Quantity::Entry,
        bits_needed,
        ..
    } = err
    {
        let wider = [EntryArg::U16, EntryArg::U32, EntryArg::U64]
            .into_iter()
            .find(|&e| entry_bits(e) >= bits_needed)
            .map_or("no entry type is wide enough".to_string(), |e| {
                format!("use --entry {}", entry_name(e))
            });
        if plan.checked() {
            msg +=
                &format!(" (this texture's largest channel sum needs {bits_needed} bits); {wider}");
        } else if plan.worst_case() {
            let worst = width::worst_case_total(b, w, h);
            msg += &format!(
                " (worst case for {w} x {h} texels of {b} bits: (2^{b} - 1) x {w} x {h} = {worst}); \
                 {wider}"
            );
            if args.layout.kind == LayoutKind::Flat && actual <= entry_bits(value) {
                msg += &format!(", or --checked (this texture's sums need only {actual} bits)");
            }
        }
    }
    msg
}

/// Strings for per-channel values: a string for one channel, an array for several.
fn per_channel<const C: usize>(values: [u128; C], k: u32) -> Value {
    if C == 1 {
        Value::String(fixed_decimal(values[0], k))
    } else {
        Value::Array(
            values
                .iter()
                .map(|&v| Value::String(fixed_decimal(v, k)))
                .collect(),
        )
    }
}

/// `v` rounded to 4 decimals, as a JSON number.
fn round4(v: f64) -> Value {
    json!((v * 1e4).round() / 1e4)
}

// ---------------------------------------------------------------------------------------------
// sat info

fn info(args: &InfoArgs, budget: &Budget) -> Result<bool, String> {
    if let Some(f) = args.filter {
        check_filter_options(f, &args.table)?;
    }
    let probe = load::probe(&args.table.image, budget)?;
    let filter = args
        .filter
        .map_or(String::new(), |f| format!(" --filter {}", f.name()));
    let job = EstimateJob {
        subject: probe.subject(&format!("info{filter}")),
        table: &args.table,
        filter: args.filter.unwrap_or(FilterArg::Box),
        probe: &probe,
    };
    with_types(&probe, job)??.check(budget)?;
    let img = probe.decode()?;
    let json = with_texture(
        &img,
        InfoJob {
            args: &args.table,
            filter: args.filter,
        },
    )??;
    print_line(&json)?;
    Ok(true)
}

/// Prints one line on stdout; a closed or full stdout is an error (exit status 1), not a panic.
fn print_line(v: &dyn std::fmt::Display) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{v}")
        .and_then(|()| out.flush())
        .map_err(|e| format!("writing stdout: {e}"))
}

/// What a command on an image takes: the decoded image, then the table (`--filter box`, any
/// `--layout`) or the filter's structure, estimated before the samples are read.
struct EstimateJob<'a> {
    subject: String,
    table: &'a TableArgs,
    filter: FilterArg,
    probe: &'a Probe,
}

impl TypesJob for EstimateJob<'_> {
    type Out = Result<Estimate, String>;
    fn run<T: ImageTexel, const C: usize>(self, w: usize, h: usize) -> Self::Out {
        let mut est = Estimate::new(self.subject);
        est.push(self.probe.image_item());
        if self.filter == FilterArg::Box {
            // `sat info` sums the texels; a query does when it explains a refused build.
            est.push(budget::totals(w, h, C));
            let plan = self.table.plan(T::BITS)?;
            layout::estimate::<T, C>(&plan, w, h, &mut est);
        } else {
            filter::estimate::<T, C>(self.filter, self.table.entry, w, h, &mut est);
        }
        Ok(est)
    }
}

/// Refuses table options that do not apply to `filter` (and filters not compiled in).
fn check_filter_options(filter: FilterArg, t: &TableArgs) -> Result<(), String> {
    filter::check_options(
        filter,
        t.layout.kind == LayoutKind::Flat,
        t.checked,
        t.entry,
    )
}

struct InfoJob<'a> {
    args: &'a TableArgs,
    filter: Option<FilterArg>,
}

impl TextureJob for InfoJob<'_> {
    type Out = Result<Value, String>;
    fn run<T: ImageTexel, const C: usize>(self, texture: &Texture<'_, T, C>) -> Self::Out {
        if let Some(f) = self.filter.filter(|&f| f != FilterArg::Box) {
            return filter::info(texture, f, self.args.entry);
        }
        let plan = self.args.plan(T::BITS)?;
        let job = InfoLayoutJob {
            args: self.args,
            plan: &plan,
            totals: channel_totals(texture),
            filter_box: self.filter == Some(FilterArg::Box),
            texture_bytes: texture.width() * texture.height() * C * std::mem::size_of::<T>(),
        };
        with_layout(texture, &plan, job).map_err(|e| refusal(texture, self.args, &plan, e))?
    }
}

struct InfoLayoutJob<'a, const N: usize> {
    args: &'a TableArgs,
    plan: &'a Plan,
    /// Whole-texture sums straight from the texels.
    totals: [u128; N],
    /// `--filter box`: add the memory fields the other filters report.
    filter_box: bool,
    /// Bytes of the texture's texels.
    texture_bytes: usize,
}

impl<const N: usize> LayoutJob for InfoLayoutJob<'_, N> {
    type Out = Result<Value, String>;
    fn run<L: BoxLookup<C>, const C: usize>(self, l: &L, detail: &Detail) -> Self::Out {
        let (w, h, b) = (l.width(), l.height(), l.texel_bits());
        // The layout's whole-texture corner must be the texel sum (mod 2^k if modular).
        let corner: Vec<u128> = l
            .corner(w, h, &mut NoCount)
            .iter()
            .map(|v| v.to_u128())
            .collect();
        let expected: Vec<u128> = self
            .totals
            .iter()
            .map(|&t| match l.modulus() {
                Some(k) if k < 128 => t & ((1u128 << k) - 1),
                _ => t,
            })
            .collect();
        if corner != expected {
            return Err(format!(
                "internal error: the layout's whole-texture corner {corner:?} differs from the \
                 texel sums {expected:?}"
            ));
        }
        let mut totals = [0u128; C];
        totals.copy_from_slice(&self.totals);
        let storage_bits = l.storage_bits();
        let value = self.plan.value();
        let mut out = json!({
            "width": w,
            "height": h,
            "channels": C,
            "texel_bits": b,
            "texel_type": if b == 8 { "u8" } else { "u16" },
            "bits_needed_worst_case": width::entry_bits_worst_case(b, w, h),
            "bits_needed_naive": width::entry_bits_naive(b, w, h),
            "bits_needed_actual": self.totals.iter().map(|&t| bits_of(t)).max().unwrap_or(0),
            "layout": self.args.layout.text,
        });
        let o = out.as_object_mut().expect("an object");
        let mut put = |k: &str, v: Value| {
            o.insert(k.to_string(), v);
        };
        let packed = |put: &mut dyn FnMut(&str, Value), words: usize| {
            put("words", json!(words));
            put("table_bytes", json!(words * 4));
            put("storage_bits", json!(storage_bits));
            put("bits_per_entry", round4(l.bits_per_entry()));
            put(
                "bits_per_texel",
                round4(storage_bits as f64 / (w as f64 * h as f64)),
            );
        };
        match detail {
            Detail::Flat {
                entries,
                table_bytes,
            } => {
                let eb = entry_bits(value);
                put("entry_type", json!(entry_name(value)));
                put("entry_bits", json!(eb));
                put("value_type", json!(entry_name(value)));
                put("bits_per_entry", json!(eb));
                put("bits_per_texel", json!(eb * C as u32));
                put("table_entries", json!(entries));
                put("table_bytes", json!(table_bytes));
                put("storage_bits", json!(storage_bits));
                put("fields_per_corner", json!(1));
                put(
                    "build",
                    json!(if self.plan.checked() {
                        "checked"
                    } else {
                        "worst_case"
                    }),
                );
            }
            Detail::Tiled {
                spec,
                words,
                field_bits,
                fields_per_corner,
            } => {
                put("value_type", json!(entry_name(value)));
                put("blocks_x", json!(spec.x.blocks()));
                put("blocks_y", json!(spec.y.blocks()));
                put("fields_per_corner", json!(fields_per_corner));
                put("field_bits", json!(field_bits));
                if let Some(k) = spec.modulus {
                    put("k", json!(k));
                    put(
                        "max_exact_area",
                        json!(u64::try_from(layout::max_exact_area(k, b)).unwrap_or(u64::MAX)),
                    );
                }
                packed(&mut put, *words);
            }
            Detail::Modular {
                k,
                words,
                max_exact_area,
            } => {
                put("value_type", json!(entry_name(value)));
                put("k", json!(k));
                put(
                    "max_exact_area",
                    json!(u64::try_from(*max_exact_area).unwrap_or(u64::MAX)),
                );
                put("fields_per_corner", json!(1));
                packed(&mut put, *words);
            }
        }
        put("totals", per_channel(totals, 0));
        if self.filter_box {
            let table_bytes = o["table_bytes"].as_u64().unwrap_or(0);
            let texture_bytes = self.texture_bytes as u64;
            o.insert("filter".into(), json!("box"));
            o.insert("texture_bytes".into(), json!(texture_bytes));
            o.insert("storage_bytes".into(), json!(table_bytes));
            o.insert("reads_texture".into(), json!(false));
            o.insert("memory_bytes".into(), json!(table_bytes));
            o.insert(
                "memory_ratio".into(),
                round4(table_bytes as f64 / texture_bytes as f64),
            );
        }
        Ok(out)
    }
}

// ---------------------------------------------------------------------------------------------
// sat query

struct QueryOpts {
    frac_bits: u32,
    mean_bits: u32,
    edge: EdgeArg,
    form: FormArg,
    inexact: Inexact,
    int4: bool,
    plan: Option<texsat::plan::Plan>,
}

/// `sat query --plan FILE`: the plan's configuration, nothing else.
fn query_plan(args: &QueryArgs, path: &std::path::Path, budget: &Budget) -> Result<bool, String> {
    let plan = scene::read(path)?;
    let facts = *plan.facts();
    let table = TableArgs {
        image: args.table.image.clone(),
        layout: layout::parse_layout(&plan.layout().to_string())?,
        entry: Some(match plan.entry() {
            texsat::plan::EntryWord::U16 => EntryArg::U16,
            texsat::plan::EntryWord::U32 => EntryArg::U32,
            texsat::plan::EntryWord::U64 => EntryArg::U64,
        }),
        checked: false,
    };
    let opts = QueryOpts {
        frac_bits: facts.frac_bits,
        mean_bits: facts.mean_frac_bits,
        edge: match facts.edge {
            EdgeKind::Border => EdgeArg::Border,
            EdgeKind::Clamp => EdgeArg::Clamp,
            EdgeKind::Repeat => EdgeArg::Repeat,
            EdgeKind::Mirror => EdgeArg::Mirror,
        },
        form: match plan.lookup().form() {
            FormKind::Paper => FormArg::Paper,
            FormKind::Stable => FormArg::Stable,
        },
        inexact: if args.round {
            Inexact::Round
        } else {
            Inexact::Refuse
        },
        int4: false,
        plan: Some(plan),
    };
    let probe = load::probe(&table.image, budget)?;
    let job = EstimateJob {
        subject: probe.subject("query --plan"),
        table: &table,
        filter: FilterArg::Box,
        probe: &probe,
    };
    with_types(&probe, job)??.check(budget)?;
    let img = probe.decode()?;
    with_texture(
        &img,
        QueryJob {
            args: &table,
            opts: &opts,
        },
    )?
}

/// The probed image of a query, checked against the budget with the table or the filter's
/// structure, then decoded.
fn query_image(args: &QueryArgs, budget: &Budget) -> Result<load::Image, String> {
    let probe = load::probe(&args.table.image, budget)?;
    let job = EstimateJob {
        subject: probe.subject(&format!("query --filter {}", args.filter.name())),
        table: &args.table,
        filter: args.filter,
        probe: &probe,
    };
    with_types(&probe, job)??.check(budget)?;
    probe.decode()
}

fn query(args: &QueryArgs, budget: &Budget) -> Result<bool, String> {
    if let Some(path) = &args.plan {
        return query_plan(args, path, budget);
    }
    let f = args.frac_bits;
    check_filter_options(args.filter, &args.table)?;
    if args.filter != FilterArg::Box {
        let name = args.filter.name();
        if args.mean_bits.is_some() {
            return Err(format!(
                "--mean-bits applies to --filter box only (--filter {name} prints its value \
                 with 16 fraction bits)"
            ));
        }
        if args.int4 {
            return Err(format!(
                "--int4 applies to --filter box only, not to --filter {name}"
            ));
        }
        let q = FilterQuery {
            filter: args.filter,
            frac_bits: f,
            edge: args.edge,
            form: args.form,
            inexact: if args.round {
                Inexact::Round
            } else {
                Inexact::Refuse
            },
            entry: args.table.entry,
        };
        let img = query_image(args, budget)?;
        return with_texture(&img, FilterJob { q: &q })?;
    }
    let opts = QueryOpts {
        frac_bits: f,
        mean_bits: args.mean_bits.unwrap_or((2 * f + 8).min(40)),
        edge: args.edge,
        form: args.form,
        inexact: if args.round {
            Inexact::Round
        } else {
            Inexact::Refuse
        },
        int4: args.int4,
        plan: None,
    };
    let img = query_image(args, budget)?;
    with_texture(
        &img,
        QueryJob {
            args: &args.table,
            opts: &opts,
        },
    )?
}

struct FilterJob<'a> {
    q: &'a FilterQuery,
}

impl TextureJob for FilterJob<'_> {
    type Out = Result<bool, String>;
    fn run<T: ImageTexel, const C: usize>(self, texture: &Texture<'_, T, C>) -> Self::Out {
        filter::query(texture, self.q)
    }
}

struct QueryJob<'a> {
    args: &'a TableArgs,
    opts: &'a QueryOpts,
}

impl TextureJob for QueryJob<'_> {
    type Out = Result<bool, String>;
    fn run<T: ImageTexel, const C: usize>(self, texture: &Texture<'_, T, C>) -> Self::Out {
        if let Some(p) = &self.opts.plan {
            let f = p.facts();
            let (got, want) = (
                (texture.width(), texture.height(), T::BITS, C),
                (f.width, f.height, f.texel_bits, f.channels),
            );
            if got != want {
                return Err(format!(
                    "the image is {}x{}, {}-bit, {} channel(s), but the plan is for {}x{}, \
                     {}-bit, {} channel(s)",
                    got.0, got.1, got.2, got.3, want.0, want.1, want.2, want.3
                ));
            }
        }
        let plan = self.args.plan(T::BITS)?;
        let job = QueryLayoutJob {
            opts: self.opts,
            value: plan.value(),
        };
        with_layout(texture, &plan, job).map_err(|e| refusal(texture, self.args, &plan, e))?
    }
}

struct QueryLayoutJob<'a> {
    opts: &'a QueryOpts,
    value: EntryArg,
}

/// Refuses, before any input is read, lookups that no box could pass: an accumulator too narrow
/// for the table's values at F, or a modular K below the paper form's headroom for one texel.
fn check_widths<L: BoxLookup<C>, const C: usize>(
    l: &L,
    o: &QueryOpts,
    value: EntryArg,
    detail: &Detail,
) -> Result<(), String> {
    if o.frac_bits == 0 {
        return Ok(());
    }
    let f = o.frac_bits;
    let (name, needed) = match o.form {
        FormArg::Paper => ("paper", FormKind::Paper.acc_bits(l.value_bits(), f)),
        FormArg::Stable => ("stable", FormKind::Stable.acc_bits(l.value_bits(), f)),
    };
    let available = <<L::Value as Entry>::Acc as Acc>::VALUE_BITS;
    if needed > available {
        let what = match (l.modulus(), detail) {
            (Some(_), _) => "residues",
            (None, Detail::Flat { .. }) => "sums",
            (None, _) => "worst-case sums",
        };
        return Err(format!(
            "the {name} lookup at F = {f} needs a {needed}-bit accumulator for this table \
             ({what} of {} bits, scaled by 2^{}), but lookups on {} values accumulate in i{} \
             ({available} value bits); use a wider --entry or fewer --frac-bits",
            l.value_bits(),
            2 * f,
            entry_name(value),
            available + 1
        ));
    }
    if let (Some(k), FormArg::Paper, false) = (l.modulus(), o.form, o.int4) {
        let headroom = FormKind::Paper.modular_headroom_bits(f);
        let one_texel = l.texel_bits() + headroom;
        if one_texel > k {
            return Err(format!(
                "the paper lookup at F = {f} on a modular layout needs {headroom} bits of headroom \
                 above the box sum, so even a one-texel box needs {one_texel} bits but K = {k}; \
                 use --form stable (no headroom), fewer --frac-bits, --int4 for integer boxes, \
                 or a larger K"
            ));
        }
    }
    Ok(())
}

impl LayoutJob for QueryLayoutJob<'_> {
    type Out = Result<bool, String>;
    fn run<L: BoxLookup<C>, const C: usize>(self, l: &L, detail: &Detail) -> Self::Out {
        let o = self.opts;
        check_widths(l, o, self.value, detail)?;
        answer_lines(|line| answer_line(l, o, line))
    }
}

/// Reads one line of `input` into `buf` (without its `'\n'`), keeping at most `max` bytes and
/// discarding the rest of a longer line: `None` at the end of the input, else whether the line
/// fit. Memory stays bounded by `max` whatever the input (a line without an end included).
fn read_line_bounded(
    input: &mut impl BufRead,
    buf: &mut Vec<u8>,
    max: usize,
) -> std::io::Result<Option<bool>> {
    buf.clear();
    let (mut any, mut fits) = (false, true);
    loop {
        let chunk = match input.fill_buf() {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if chunk.is_empty() {
            return Ok(any.then_some(fits));
        }
        any = true;
        let (take, end) = match chunk.iter().position(|&b| b == b'\n') {
            Some(i) => (i, true),
            None => (chunk.len(), false),
        };
        if fits {
            if buf.len() + take <= max {
                buf.extend_from_slice(&chunk[..take]);
            } else {
                fits = false;
                buf.clear();
            }
        }
        input.consume(if end { take + 1 } else { take });
        if end {
            return Ok(Some(fits));
        }
    }
}

/// Reads query lines from stdin and prints `answer`'s JSON for each (`{"error": ..., "line": N}`
/// for a refused one). Empty lines and lines starting with '#' are skipped; a line longer than
/// [`MAX_LINE_BYTES`] is refused (and skipped to its end). Returns whether every line was
/// answered.
fn answer_lines(mut answer: impl FnMut(&str) -> Result<Value, String>) -> Result<bool, String> {
    let stdin = std::io::stdin();
    let mut input = stdin.lock();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut buf = Vec::new();
    let mut line_no = 0usize;
    let mut all_ok = true;
    loop {
        let fits = read_line_bounded(&mut input, &mut buf, MAX_LINE_BYTES)
            .map_err(|e| format!("reading stdin: {e}"))?;
        let Some(fits) = fits else {
            break;
        };
        line_no += 1;
        let result = match std::str::from_utf8(&buf) {
            _ if !fits => Some(Err(format!(
                "line is longer than {MAX_LINE_BYTES} bytes (the rest of it is skipped)"
            ))),
            Err(_) => Some(Err("line is not valid UTF-8".to_string())),
            Ok(line) => {
                let line = line.trim();
                if line.is_empty() || line.starts_with('#') {
                    None
                } else {
                    Some(answer(line))
                }
            }
        };
        let json = match result {
            None => continue,
            Some(Ok(v)) => v,
            Some(Err(msg)) => {
                all_ok = false;
                json!({ "error": msg, "line": line_no })
            }
        };
        writeln!(out, "{json}").map_err(|e| format!("writing stdout: {e}"))?;
    }
    out.flush().map_err(|e| format!("writing stdout: {e}"))?;
    Ok(all_ok)
}

/// Parses `"x0 y0 x1 y1"` into raw fixed-point values with `f` fraction bits.
fn parse_box(line: &str, f: u32, inexact: Inexact) -> Result<[i64; 4], String> {
    let fields: Vec<&str> = line.split_whitespace().collect();
    if fields.len() != 4 {
        return Err(format!(
            "expected 4 numbers \"x0 y0 x1 y1\", got {} field{}",
            fields.len(),
            if fields.len() == 1 { "" } else { "s" }
        ));
    }
    let mut raw = [0i64; 4];
    for ((r, s), name) in raw.iter_mut().zip(&fields).zip(["x0", "y0", "x1", "y1"]) {
        *r = parse_fixed(s, f, inexact).map_err(|e| format!("{name}: {e}"))?;
    }
    Ok(raw)
}

/// One query line: parse, look up, take the mean, format.
fn answer_line<L: BoxLookup<C>, const C: usize>(
    l: &L,
    o: &QueryOpts,
    line: &str,
) -> Result<Value, String> {
    let raw = parse_box(line, o.frac_bits, o.inexact)?;
    if let Some(p) = &o.plan {
        let [x0, y0, x1, y1] = raw;
        let r = Rect::new(x0, y0, x1, y1);
        p.check_box(&r).map_err(|e| e.to_string())?;
        if let Some(shortcut) = p.shortcut() {
            return answer_shortcut(l, o, &r, &shortcut);
        }
    }
    let mut tally = Tally::new();
    let (sum, lookup) = lookup(l, o, raw, &mut tally)?;
    let mean = match sum.means_rounded(o.mean_bits, &mut tally) {
        Ok(m) => per_channel(m, o.mean_bits),
        Err(Error::ZeroArea) => Value::Null,
        Err(e) => return Err(format!("mean: {e} (try fewer --mean-bits)")),
    };
    Ok(json!({
        "sum": per_channel(sum.scaled_sums(), 2 * sum.frac_bits()),
        "mean": mean,
        "filter": "box",
        "lookup": lookup,
        "reads": tally.reads,
        "bits_read": tally.bits_read,
        "words": tally.words,
        "muls": tally.muls,
        "divs": tally.divs,
        "adds": tally.adds,
    }))
}

/// A plan's shortcut lookup: the mean only (the shortcut has no exact sum).
fn answer_shortcut<L: BoxLookup<C>, const C: usize>(
    l: &L,
    o: &QueryOpts,
    r: &Rect<i64>,
    shortcut: &texsat::Shortcut,
) -> Result<Value, String> {
    let mut tally = Tally::new();
    let fb = FracBits::new(o.frac_bits).map_err(|e| e.to_string())?;
    let form = o.form.kind();
    // The plan's mode, as in `lookup`.
    let m = if o.plan.as_ref().is_some_and(|p| p.repeat_within_period()) {
        let mode = RepeatWithinPeriod;
        l.box_mean_shortcut_raw(r, fb, form, mode, shortcut, o.mean_bits, &mut tally)
    } else {
        let mode = o.edge.kind();
        l.box_mean_shortcut_raw(r, fb, form, mode, shortcut, o.mean_bits, &mut tally)
    }
    .map_err(|e| e.to_string())?;
    Ok(json!({
        "sum": Value::Null,
        "mean": per_channel(m.to_u128().means, o.mean_bits),
        "filter": "box",
        "lookup": if m.shortcut { "shortcut" } else { o.form.kind().name() },
        "reads": tally.reads,
        "bits_read": tally.bits_read,
        "words": tally.words,
        "muls": tally.muls,
        "divs": tally.divs,
        "adds": tally.adds,
    }))
}

type Looked<const C: usize> = Result<(BoxSum<u128, C>, &'static str), String>;

/// The lookup: the 4-read integer lookup at `F = 0` (or for integer boxes with `--int4`), else
/// the 16-read lookup with `F` as a value and the mode and form as run-time values
/// (`EdgeKind`, `FormKind`): one compiled lookup per layout serves every `F`, mode and form
/// (and one more, `RepeatWithinPeriod`, for a plan that says so).
fn lookup<L: BoxLookup<C>, const C: usize>(
    l: &L,
    o: &QueryOpts,
    raw: [i64; 4],
    k: &mut Tally,
) -> Looked<C> {
    // A plan whose Repeat boxes are at most the texture: its firmware's mode
    // (`RepeatWithinPeriod`, the same sums; `check_box` has refused longer boxes).
    if o.plan.as_ref().is_some_and(|p| p.repeat_within_period()) {
        return lookup_in(l, o, raw, RepeatWithinPeriod, k);
    }
    lookup_in(l, o, raw, o.edge.kind(), k)
}

/// [`lookup`] under the boundary mode `mode`.
fn lookup_in<L: BoxLookup<C>, M: EdgeMode, const C: usize>(
    l: &L,
    o: &QueryOpts,
    raw: [i64; 4],
    mode: M,
    k: &mut Tally,
) -> Looked<C> {
    let f = o.frac_bits;
    let integer = raw.iter().all(|&v| v & ((1i64 << f) - 1) == 0);
    if f == 0 || (o.int4 && integer) {
        let mut c = [0i32; 4];
        for (ci, &r) in c.iter_mut().zip(&raw) {
            *ci = i32::try_from(r >> f).map_err(|_| {
                format!(
                    "coordinate {} is outside the integer lookup's range (i32)",
                    r >> f
                )
            })?;
        }
        let r = Rect::new(c[0], c[1], c[2], c[3]);
        return l
            .box_sum_int(&r, mode, k)
            .map(|s| (s.to_u128(), "int4"))
            .map_err(|e| e.to_string());
    }
    let form = o.form.kind();
    let fb = FracBits::new(f).map_err(|e| e.to_string())?;
    let [x0, y0, x1, y1] = raw;
    l.box_sum_raw(&Rect::new(x0, y0, x1, y1), fb, form, mode, k)
        .map(|s| (s.to_u128(), form.name()))
        .map_err(|e| e.to_string())
}
