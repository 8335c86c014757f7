//! `sat vectors`: golden vectors for a hardware texture unit's test bench.
//!
//! For one texture (a built-in scene's or an image file's, one channel), one layout, `F`, form
//! and boundary mode, writes the stimulus (box corners in the unit's fixed-point format), the
//! bit-exact expected result of every sample (the exact sum scaled by `2^2F` and the rounded
//! mean) with its counted reads, multiplies, divides and additive operations, and the table
//! memory image the RTL holds, in the layout's storage format. `hex` loads with Verilog
//! `$readmemh`; `json` carries the same plus the texture, so a checker in any language can
//! recompute every expected value from the texture alone. docs/hardware.md describes the files.

use crate::layout::{self, LayoutArg, Plan};
use crate::{EdgeArg, EntryArg, FormArg};
use clap::{Args, ValueEnum};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use texsat::layouts::{Modular, Tiled};
use texsat::{BoxLookup, BoxSum, Entry, FracBits, Layout, Rect, Sat, Tally, Texel, Texture};
use texsat_host_tests::scenes::{builtin_scenes, SceneSize};
use texsat_tools::budget::{self, Budget, Estimate};
use texsat_tools::image_file::{probe, Pixels};

/// Output format of `sat vectors`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum, Debug)]
pub enum VectorFormat {
    /// `$readmemh` files: table.hex, stim.hex, expect.hex, vectors.vh, header.txt.
    Hex,
    /// vectors.json: parameters, texture, table image and samples.
    Json,
}

/// Where the boxes lie.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum, Debug)]
pub enum BoxSet {
    /// Inside the texture (what the reference datapath in `hw/` accepts).
    Inside,
    /// Anywhere in three texture widths around it, crossing edges and periods.
    Around,
}

#[derive(Args)]
pub struct VectorsArgs {
    /// A built-in scene's texture: crow-vertical, zone-plate, noise, ... (see `sat help vectors`).
    #[arg(long, conflicts_with = "image", required_unless_present = "image")]
    scene: Option<String>,
    /// A PNG or PNM file (one channel, 8 or 16 bits).
    #[arg(long)]
    image: Option<PathBuf>,
    /// Texture side of a built-in scene: 64 (quick), 256 or 1024.
    #[arg(long, default_value_t = 64)]
    scene_size: usize,
    /// Table layout (as `sat query --layout`).
    #[arg(long, value_parser = layout::parse_layout, default_value = "flat")]
    layout: LayoutArg,
    /// Entry (value) type [default: u32; modular: u32 if K <= 32, else u64].
    #[arg(long, value_enum)]
    entry: Option<EntryArg>,
    /// Fractional bits F of the corners (0: integer corners, the 4-read lookup).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=24))]
    frac_bits: u32,
    /// Formulation of the 16-read lookup.
    #[arg(long, value_enum, default_value_t = FormArg::Stable)]
    form: FormArg,
    /// Boundary mode.
    #[arg(long, value_enum, default_value_t = EdgeArg::Border)]
    edge: EdgeArg,
    /// Where the boxes lie.
    #[arg(long, value_enum, default_value_t = BoxSet::Inside)]
    boxes: BoxSet,
    /// Number of samples (at most 1,000,000).
    #[arg(long, default_value_t = 1000)]
    count: usize,
    /// Seed of the boxes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Fractional bits of the rounded mean.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=32))]
    mean_bits: u32,
    /// Output format.
    #[arg(long, value_enum, default_value_t = VectorFormat::Hex)]
    format: VectorFormat,
    /// Output directory (created).
    #[arg(long)]
    out: PathBuf,
}

pub const VECTORS_HELP: &str = "\
FILES (--format hex), in --out:
  vectors.vh   Verilog localparams: VEC_TEX_W, VEC_TEX_H, VEC_B (texel bits), VEC_W_E (bits of
               one table word), VEC_F, VEC_N (samples), VEC_W_STRIP (bits of the largest strip
               of a box, for the Stable datapath's multipliers), VEC_MEAN_BITS, and the file
               names VEC_TABLE_HEX, VEC_STIM_HEX, VEC_EXPECT_HEX.
  table.hex    the table memory image, one word per line: for the flat layout one entry
               (VEC_W_E = 16, 32 or 64 bits) per line, entry (i, j) at line j w + i holding the
               sum of texels (i' <= i, j' <= j); for packed, tiled and modular layouts the 32-bit
               storage words (VEC_W_E = 32) exactly as texsat lays them out.
  stim.hex     one sample per line, 256 bits: x0, y0, x1, y1, each the raw corner (value x 2^F)
               as a 64-bit two's complement word, x0 in the top bits.
  expect.hex   one sample per line, 256 bits: the exact integral scaled by 2^2F (128 bits), the
               mean rounded to VEC_MEAN_BITS fractional bits (64 bits; 0 for a zero-area box),
               then reads, muls, divs and adds as texsat counts them (16 bits each), the sum in
               the top bits.
  header.txt   the same description, with the parameters of this run.
--format json writes vectors.json: {params, texture: {width, height, texel_bits, texels},
table: {word_bits, words}, samples: [{x0, y0, x1, y1, sum, mean, reads, muls, divs, adds}]}, the
numbers above 2^53 as decimal strings.

SCENES: crow-vertical, crow-lateral, crow-horizontal, crow-stripes-cylinder,
heckbert-checker-plane, zone-plate, noise (8-bit, --scene-size 64, 256 or 1024 texels).";

/// The texture of a built-in scene (8-bit, one channel).
fn scene_texels(name: &str, side: usize) -> Result<(usize, usize, Vec<u8>), String> {
    let size = match side {
        64 => SceneSize::Quick,
        256 => SceneSize::Default,
        1024 => SceneSize::Full,
        other => return Err(format!("--scene-size {other}: 64, 256 or 1024")),
    };
    let scene = builtin_scenes(size)
        .into_iter()
        .find(|s| s.name == name)
        .ok_or_else(|| format!("no built-in scene '{name}' (see `sat help vectors`)"))?;
    let t = scene.texture;
    let texels = t
        .texels
        .iter()
        .map(|&v| u8::try_from(v).map_err(|_| format!("scene '{name}': texel {v} above 8 bits")))
        .collect::<Result<Vec<u8>, String>>()?;
    Ok((t.width, t.height, texels))
}

/// xorshift64*: the boxes' generator (seeded, reproducible).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `[0, n]`.
    fn upto(&mut self, n: i64) -> i64 {
        (self.next() % (n as u64 + 1)) as i64
    }
}

/// The sample boxes, raw corners at `F` bits.
fn boxes(args: &VectorsArgs, w: usize, h: usize) -> Vec<Rect<i64>> {
    let f = args.frac_bits;
    let mut rng = Rng(args.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let (pw, ph) = ((w as i64) << f, (h as i64) << f);
    let axis = |rng: &mut Rng, p: i64| -> (i64, i64) {
        match args.boxes {
            BoxSet::Inside => {
                // A quarter of the boxes small (up to 4 texels), the rest any size.
                let a = rng.upto(p);
                let span = if rng.next().is_multiple_of(4) {
                    (4i64 << f).min(p)
                } else {
                    p
                };
                let b = (a + rng.upto(span)).min(p);
                (a, b)
            }
            BoxSet::Around => {
                let a = rng.upto(3 * p) - p;
                (a, a + rng.upto(2 * p))
            }
        }
    };
    (0..args.count)
        .map(|_| {
            let (x0, x1) = axis(&mut rng, pw);
            let (y0, y1) = axis(&mut rng, ph);
            Rect::new(x0, y0, x1, y1)
        })
        .collect()
}

/// One sample's expected outputs.
struct Expected {
    sum: u128,
    mean: u128,
    k: Tally,
    error: Option<String>,
}

/// The expected outputs of every box on `layout`.
fn expect<L: Layout<1>>(layout: &L, args: &VectorsArgs, rects: &[Rect<i64>]) -> Vec<Expected> {
    let f = args.frac_bits;
    rects
        .iter()
        .map(|r| {
            let mut k = Tally::new();
            let sum: Result<BoxSum<_, 1>, _> = if f == 0 {
                let int =
                    |v: i64| i32::try_from(v).unwrap_or(if v < 0 { i32::MIN } else { i32::MAX });
                layout.box_sum_int(
                    &Rect::new(int(r.x0), int(r.y0), int(r.x1), int(r.y1)),
                    args.edge.kind(),
                    &mut k,
                )
            } else {
                match FracBits::new(f) {
                    Ok(fb) => layout.box_sum_raw(r, fb, args.form.kind(), args.edge.kind(), &mut k),
                    Err(e) => Err(e),
                }
            };
            match sum {
                Ok(s) => {
                    let (w, h) = s.sides_raw();
                    let mean = if w == 0 || h == 0 {
                        Ok(0u128)
                    } else {
                        s.mean_rounded(0, args.mean_bits, &mut k).map(Into::into)
                    };
                    match mean {
                        Ok(mean) => Expected {
                            sum: s.sum().into(),
                            mean,
                            k,
                            error: None,
                        },
                        Err(e) => Expected {
                            sum: 0,
                            mean: 0,
                            k,
                            error: Some(e.to_string()),
                        },
                    }
                }
                Err(e) => Expected {
                    sum: 0,
                    mean: 0,
                    k,
                    error: Some(e.to_string()),
                },
            }
        })
        .collect()
}

/// Everything the writers need.
struct Run<'a> {
    args: &'a VectorsArgs,
    width: usize,
    height: usize,
    texel_bits: u32,
    texels: Vec<u32>,
    word_bits: u32,
    words: Vec<u64>,
    rects: Vec<Rect<i64>>,
    expected: Vec<Expected>,
    layout_text: String,
    entry: &'static str,
}

fn build_and_expect<'a, T: Texel + Copy + Into<u32>>(
    args: &'a VectorsArgs,
    w: usize,
    h: usize,
    data: &[T],
) -> Result<Run<'a>, String> {
    let texture = Texture::<T, 1>::new(data, w, h).map_err(|e| format!("texture: {e}"))?;
    let plan = layout::resolve(&args.layout, args.entry, false, T::BITS)?;
    let rects = boxes(args, w, h);
    let (word_bits, words, expected, entry) = match plan {
        Plan::Flat { entry, .. } => match entry {
            EntryArg::U16 => flat::<T, u16>(&texture, args, &rects)?,
            EntryArg::U32 => flat::<T, u32>(&texture, args, &rects)?,
            EntryArg::U64 => flat::<T, u64>(&texture, args, &rects)?,
        },
        Plan::Tiled { spec, value } => {
            let n =
                Tiled::<u64, 1>::words_needed(spec, w, h, T::BITS).map_err(|e| e.to_string())?;
            let s = Tiled::<u64, 1>::scratch_needed(spec, w).map_err(|e| e.to_string())?;
            let mut words = vec![0u32; n];
            let mut scratch = vec![0u64; s];
            let t = Tiled::<u64, 1>::build(&texture, spec, &mut words, &mut scratch)
                .map_err(|e| format!("tiled build: {e}"))?;
            let e = expect(&t, args, &rects);
            (
                32,
                words.iter().map(|&v| u64::from(v)).collect(),
                e,
                entry_name(value),
            )
        }
        Plan::Modular { k, value } => {
            let n = Modular::<u64, 1>::words_needed(w, h, k).map_err(|e| e.to_string())?;
            let mut words = vec![0u32; n];
            let mut row = vec![0u64; w];
            let m = Modular::<u64, 1>::build(&texture, k, &mut words, &mut row)
                .map_err(|e| format!("modular build: {e}"))?;
            let e = expect(&m, args, &rects);
            (
                32,
                words.iter().map(|&v| u64::from(v)).collect(),
                e,
                entry_name(value),
            )
        }
    };
    Ok(Run {
        args,
        width: w,
        height: h,
        texel_bits: T::BITS,
        texels: data.iter().map(|&t| t.into()).collect(),
        word_bits,
        words,
        rects,
        expected,
        layout_text: args.layout.text.clone(),
        entry,
    })
}

fn form_name(f: FormArg) -> &'static str {
    match f {
        FormArg::Paper => "paper",
        FormArg::Stable => "stable",
    }
}

fn entry_name(e: EntryArg) -> &'static str {
    match e {
        EntryArg::U16 => "u16",
        EntryArg::U32 => "u32",
        EntryArg::U64 => "u64",
    }
}

type Built = (u32, Vec<u64>, Vec<Expected>, &'static str);

fn flat<T: Texel, E: Entry>(
    texture: &Texture<'_, T, 1>,
    args: &VectorsArgs,
    rects: &[Rect<i64>],
) -> Result<Built, String> {
    let n = Sat::<E, 1>::entries_needed(texture.width(), texture.height())
        .map_err(|e| e.to_string())?;
    let mut storage = vec![E::ZERO; n];
    let sat = Sat::build(texture, &mut storage).map_err(|e| format!("build: {e}"))?;
    let e = expect(&sat, args, rects);
    let words = sat.entries().iter().map(|v| v.to_u64()).collect();
    Ok((
        E::BITS,
        words,
        e,
        entry_name(match E::BITS {
            16 => EntryArg::U16,
            32 => EntryArg::U32,
            _ => EntryArg::U64,
        }),
    ))
}

/// Bits of the largest strip of a box under these samples (for the Stable datapath's
/// multipliers): `bits_of(m (max_side + 1))` over the boxes' sides in cells.
fn strip_bits(run: &Run<'_>) -> u32 {
    let f = run.args.frac_bits;
    let max_side = run
        .rects
        .iter()
        .map(|r| {
            let cells = |a: i64, b: i64| ((b - a) >> f) as u64 + 2;
            cells(r.x0, r.x1).max(cells(r.y0, r.y1))
        })
        .max()
        .unwrap_or(1);
    let m = (1u64 << run.texel_bits) - 1;
    texsat::width::bits_of(u128::from(m) * u128::from(max_side))
}

fn hex_word(v: u128, bits: u32) -> String {
    let digits = bits.div_ceil(4) as usize;
    let masked = if bits >= 128 {
        v
    } else {
        v & ((1u128 << bits) - 1)
    };
    format!("{masked:0digits$x}")
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_hex(run: &Run<'_>, dir: &Path) -> Result<(), String> {
    let a = run.args;
    let mut table = String::new();
    for &w in &run.words {
        let _ = writeln!(table, "{}", hex_word(u128::from(w), run.word_bits));
    }
    let mut stim = String::new();
    let mut exp = String::new();
    for (r, e) in run.rects.iter().zip(&run.expected) {
        let c = |v: i64| hex_word(u128::from(v as u64), 64);
        let _ = writeln!(stim, "{}{}{}{}", c(r.x0), c(r.y0), c(r.x1), c(r.y1));
        let k = |v: u64| hex_word(u128::from(v.min(0xFFFF)), 16);
        let _ = writeln!(
            exp,
            "{}{}{}{}{}{}",
            hex_word(e.sum, 128),
            hex_word(e.mean, 64),
            k(e.k.reads),
            k(e.k.muls),
            k(e.k.divs),
            k(e.k.adds)
        );
    }
    let params = params_text(run);
    let vh = format!(
        "// Generated by `sat vectors` (texsat): parameters of these golden vectors.\n\
         // {}\n\
         localparam VEC_TEX_W = {};\n\
         localparam VEC_TEX_H = {};\n\
         localparam VEC_B = {};\n\
         localparam VEC_W_E = {};\n\
         localparam VEC_F = {};\n\
         localparam VEC_N = {};\n\
         localparam VEC_W_STRIP = {};\n\
         localparam VEC_MEAN_BITS = {};\n\
         localparam VEC_TABLE_HEX = \"{}\";\n\
         localparam VEC_STIM_HEX = \"{}\";\n\
         localparam VEC_EXPECT_HEX = \"{}\";\n",
        params.replace('\n', " "),
        run.width,
        run.height,
        run.texel_bits,
        run.word_bits,
        a.frac_bits,
        run.rects.len(),
        strip_bits(run),
        a.mean_bits,
        dir.join("table.hex").display(),
        dir.join("stim.hex").display(),
        dir.join("expect.hex").display(),
    );
    let header = format!("{params}\n\n{VECTORS_HELP}\n");
    write(&dir.join("table.hex"), &table)?;
    write(&dir.join("stim.hex"), &stim)?;
    write(&dir.join("expect.hex"), &exp)?;
    write(&dir.join("vectors.vh"), &vh)?;
    write(&dir.join("header.txt"), &header)
}

fn params_text(run: &Run<'_>) -> String {
    let a = run.args;
    let errors = run.expected.iter().filter(|e| e.error.is_some()).count();
    format!(
        "texture {}x{} {}-bit, layout {} ({} values), F = {}, form {}, edge {:?}, boxes {:?}, \
         {} samples (seed {}), mean bits {}, {} refused by the library (sum 0, listed in json)",
        run.width,
        run.height,
        run.texel_bits,
        run.layout_text,
        run.entry,
        a.frac_bits,
        form_name(a.form),
        a.edge,
        a.boxes,
        run.rects.len(),
        a.seed,
        a.mean_bits,
        errors
    )
}

/// A number as JSON: exact below 2^53, else a decimal string.
fn num(v: u128) -> Value {
    if v < (1u128 << 53) {
        json!(v as u64)
    } else {
        json!(v.to_string())
    }
}

fn inum(v: i64) -> Value {
    if v.unsigned_abs() < (1u64 << 53) {
        json!(v)
    } else {
        json!(v.to_string())
    }
}

fn write_json(run: &Run<'_>, dir: &Path) -> Result<(), String> {
    let a = run.args;
    let samples: Vec<Value> = run
        .rects
        .iter()
        .zip(&run.expected)
        .map(|(r, e)| {
            let mut v = json!({
                "x0": inum(r.x0), "y0": inum(r.y0), "x1": inum(r.x1), "y1": inum(r.y1),
                "sum": num(e.sum), "mean": num(e.mean),
                "reads": e.k.reads, "muls": e.k.muls, "divs": e.k.divs, "adds": e.k.adds,
            });
            if let Some(err) = &e.error {
                v["error"] = json!(err);
            }
            v
        })
        .collect();
    let doc = json!({
        "params": {
            "width": run.width, "height": run.height, "texel_bits": run.texel_bits,
            "layout": run.layout_text, "entry": run.entry, "frac_bits": a.frac_bits,
            "form": form_name(a.form),
            "edge": format!("{:?}", a.edge).to_lowercase(),
            "mean_bits": a.mean_bits, "count": run.rects.len(), "seed": a.seed,
            "strip_bits": strip_bits(run),
        },
        "texture": {
            "width": run.width, "height": run.height, "texel_bits": run.texel_bits,
            "texels": run.texels,
        },
        "table": {"word_bits": run.word_bits, "words": run.words.iter().map(|&w| num(u128::from(w))).collect::<Vec<_>>()},
        "samples": samples,
    });
    let text = serde_json::to_string(&doc).map_err(|e| e.to_string())?;
    write(&dir.join("vectors.json"), &text)
}

/// Checks what the command is about to take against the budget: the table in its layout, the
/// samples and their text, and (for an image) the decoded image.
fn check_budget(
    args: &VectorsArgs,
    w: usize,
    h: usize,
    texel_bits: u32,
    image: Option<budget::Item>,
    budget: &Budget,
) -> Result<(), String> {
    let mut est = Estimate::new(format!("vectors on this {w} x {h} texture"));
    if let Some(item) = image {
        est.push(item);
    }
    let plan = layout::resolve(&args.layout, args.entry, false, texel_bits)?;
    if texel_bits <= 8 {
        layout::estimate::<u8, 1>(&plan, w, h, &mut est);
    } else {
        layout::estimate::<u16, 1>(&plan, w, h, &mut est);
    }
    // The texture and table as text (hex: up to 17 bytes per word; JSON about twice that), and
    // per sample its box, expected values and both lines of text.
    est.push(budget::Item::new(
        "table and texture text",
        w.saturating_mul(h),
        64,
        0,
    ));
    est.push(budget::Item::new("samples", args.count, 512, 0));
    est.check(budget)
}

/// Runs `sat vectors`.
pub fn run(args: &VectorsArgs, budget: &Budget) -> Result<bool, String> {
    if args.count > 1_000_000 {
        return Err(format!("--count {}: at most 1000000", args.count));
    }
    let run = match (&args.scene, &args.image) {
        (Some(name), _) => {
            let (w, h, texels) = scene_texels(name, args.scene_size)?;
            check_budget(args, w, h, 8, None, budget)?;
            std::fs::create_dir_all(&args.out)
                .map_err(|e| format!("{}: {e}", args.out.display()))?;
            let run = build_and_expect::<u8>(args, w, h, &texels)?;
            finish(run)?
        }
        (None, Some(path)) => {
            let p = probe(path, budget)?;
            if p.channels != 1 {
                return Err(format!(
                    "{}: {} channels; vectors are for one-channel textures",
                    path.display(),
                    p.channels
                ));
            }
            check_budget(
                args,
                p.width,
                p.height,
                p.sample_bits,
                Some(p.image_item()),
                budget,
            )?;
            let img = p.decode()?;
            std::fs::create_dir_all(&args.out)
                .map_err(|e| format!("{}: {e}", args.out.display()))?;
            match &img.pixels {
                Pixels::U8(d) => finish(build_and_expect::<u8>(args, img.width, img.height, d)?)?,
                Pixels::U16(d) => finish(build_and_expect::<u16>(args, img.width, img.height, d)?)?,
            }
        }
        (None, None) => return Err("give --scene NAME or --image FILE".into()),
    };
    Ok(run)
}

fn finish(run: Run<'_>) -> Result<bool, String> {
    match run.args.format {
        VectorFormat::Hex => write_hex(&run, &run.args.out)?,
        VectorFormat::Json => write_json(&run, &run.args.out)?,
    }
    eprintln!("sat vectors: {}", params_text(&run));
    Ok(true)
}
