//! The texture-filtering report: every comparison filter of `texsat::filters` and every
//! summed-area-table formulation and layout, on the scenes of `texsat-host-tests`, against the
//! ideal pixel values (the exact mean over each pixel's pre-image), against each filter's own
//! `f64` reference, timed and counted; plus the float32 stability study.
//!
//! ```text
//! cargo run --release --example report [-- --quick|--full] [--scene NAME]... [--method NAME]...
//!                                          [--out DIR] [--repeats R] [--no-stability]
//! ```
//!
//! An image scene (`--scene FILE`) is read under the `sat` tool's limits: its header first
//! (decoder limits), then the memory and work the scene will take are estimated and checked
//! against `--max-memory` (default 1G) and `--max-work` (default 32G texel operations) before the
//! image is decoded; a file too short for its header, or over budget, is refused with exit status
//! 1 (see `texsat_tools::budget`).
//!
//! Writes `DIR/report.md`, `DIR/report.csv`, `DIR/stability.csv`, `DIR/error_vs_time.png`,
//! `DIR/error_vs_cost.png`, `DIR/float32_error_vs_size.png` and `DIR/render_<scene>.png`
//! (default `DIR` = `target/report`). `docs/report.md` explains the numbers.

use clap::Parser;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use texsat::layouts::TiledSpec;
use texsat_host_tests::scenes::{builtin_scenes, image_scene, Scene, SceneSize};
use texsat_host_tests::stability;
use texsat_tools::budget::{self, Budget, Estimate, Item};
use texsat_tools::image_file;

#[path = "report/dof.rs"]
mod dof;
#[path = "report/measure.rs"]
mod measure;
#[path = "report/methods.rs"]
mod methods;
#[path = "report/output.rs"]
mod output;
#[path = "report/plots.rs"]
mod plots;
#[path = "report/traffic.rs"]
mod traffic;

use methods::Method;

/// Compares texture filters on analytic scenes and writes a report with tables, plots and
/// renders.
#[derive(Parser, Debug)]
#[command(name = "report")]
struct Args {
    /// Tiny scenes and 3 timed passes (seconds; for CI).
    #[arg(long, conflicts_with = "full")]
    quick: bool,
    /// Larger scenes (1024 x 1024 textures, 320 x 240 outputs) and the largest stability sizes.
    #[arg(long)]
    full: bool,
    /// A scene to run (a built-in name, or a path to a PNG/PGM image shown on a perspective
    /// plane); repeat to run several; default: every built-in scene.
    #[arg(long = "scene", value_name = "NAME")]
    scenes: Vec<String>,
    /// A method to run; repeat to run several; default: every method.
    #[arg(long = "method", value_name = "NAME", value_enum)]
    methods: Vec<Method>,
    /// Output folder.
    #[arg(long, value_name = "DIR", default_value = "target/report")]
    out: PathBuf,
    /// Timed passes per method and scene (median reported); default 5, 3 with --quick.
    #[arg(long, value_name = "R")]
    repeats: Option<usize>,
    /// Skip the float32 stability study.
    #[arg(long)]
    no_stability: bool,
    /// Skip the depth-of-field scene (every pixel its own box).
    #[arg(long)]
    no_dof: bool,
    /// Skip the memory-traffic and texel-cache section.
    #[arg(long)]
    no_traffic: bool,
    /// Memory budget for an image scene, in bytes (suffixes K, M, G, T: powers of 1024).
    #[arg(long, value_name = "BYTES", default_value = "1G", value_parser = budget::parse_amount)]
    max_memory: u64,
    /// Work budget for an image scene, in texel operations (32G is about 15 s of one core).
    #[arg(long, value_name = "N", default_value = "32G", value_parser = budget::parse_amount)]
    max_work: u64,
}

/// Bytes per texel an image scene takes in the host code (`texsat-host-tests`: the decoded
/// image as luma, the `u32` reference texels, the exact `u128` table, the `f64` reference
/// pyramids, ripmap and dipmap, the column prefix sums of the ideal), beyond the `texsat`
/// structures [`image_scene_estimate`] counts from the crate's size functions. Measured (peak
/// resident memory of `report --scene` on 1024^2 and 2048^2 noise images, about 130 bytes per
/// texel besides the structures) and rounded up.
const HOST_BYTES_PER_TEXEL: usize = 144;

/// Texel operations per texel of the host references and the ideal over an image scene
/// (measured: about 1 us per texel at the default size, 0.5 ns per operation).
const HOST_WORK_PER_TEXEL: u128 = 2048;

/// What an image scene of `p`'s size takes: the decoded image, the host references, and every
/// structure `methods::Storage::build` makes (the scene's plan bounded by the flat table, the
/// modular table by `K = 64`).
fn image_scene_estimate(p: &image_file::Probe) -> Estimate {
    let (w, h) = (p.width, p.height);
    let mut est = Estimate::new(p.subject("report --scene"));
    est.push(p.image_item());
    let texels = w as u128 * h as u128;
    est.push(Item {
        what: "host references".to_string(),
        bytes: texels * HOST_BYTES_PER_TEXEL as u128,
        work: texels * HOST_WORK_PER_TEXEL,
    });
    est.push_sized(budget::mip::<u8, 1>(w, h));
    est.push(budget::rip::<u8, 1>(w, h));
    est.push(budget::dip::<u8, 1>(w, h));
    est.push_sized(budget::flat::<u32, 1>(w, h));
    for spec in [TiledSpec::tiles(8, 8), TiledSpec::square(&[2, 16])]
        .into_iter()
        .flatten()
    {
        est.push_sized(budget::tiled::<u32, 1>(spec, w, h, 8).map(|mut i| {
            i.what = format!("tiled table {:?}x{:?}", spec.x.blocks(), spec.y.blocks());
            i
        }));
    }
    est.push_sized(budget::modular::<u64, 1>(w, h, 64));
    est.push_sized(budget::flat::<u32, 1>(w, h).map(|mut i| {
        i.what = "scene plan's table (at most the flat table)".to_string();
        i
    }));
    est.push_sized(budget::tent::<u64, 1>(w, h));
    est.push_sized(budget::tent_lines::<u32, 1>(w, h));
    est
}

/// Reads an image scene's header under the decoder limits, checks its estimate against
/// `budget` and that the file can hold what its header claims, then builds the scene.
fn checked_image_scene(
    path: &std::path::Path,
    size: SceneSize,
    budget: &Budget,
) -> Result<Scene, String> {
    let probe = image_file::probe(path, budget)?;
    image_scene_estimate(&probe).check(budget)?;
    probe.check_size()?;
    drop(probe);
    image_scene(path, size)
}

/// The scenes to run; an error carries the exit status (2: an unknown name; 1: an image file
/// refused).
fn pick_scenes(
    names: &[String],
    size: SceneSize,
    budget: &Budget,
) -> Result<Vec<Scene>, (i32, String)> {
    let builtin = builtin_scenes(size);
    if names.is_empty() {
        return Ok(builtin);
    }
    let available: Vec<String> = builtin.iter().map(|s| s.name.clone()).collect();
    let mut builtin: Vec<Option<Scene>> = builtin.into_iter().map(Some).collect();
    let mut out = Vec::new();
    for name in names {
        if let Some(i) = available.iter().position(|a| a == name) {
            if let Some(s) = builtin[i].take() {
                out.push(s);
            }
            continue;
        }
        let path = std::path::Path::new(name);
        if path.is_file() {
            out.push(checked_image_scene(path, size, budget).map_err(|e| (1, e))?);
            continue;
        }
        return Err((
            2,
            format!(
                "unknown scene {name:?}: not a built-in ({}) nor an image file",
                available.join(", ")
            ),
        ));
    }
    Ok(out)
}

fn main() {
    let args = Args::parse();
    let started = Instant::now();
    let size = if args.quick {
        SceneSize::Quick
    } else if args.full {
        SceneSize::Full
    } else {
        SceneSize::Default
    };
    let repeats = args
        .repeats
        .unwrap_or(if args.quick { 3 } else { 5 })
        .max(1);
    let settings = measure::Settings {
        repeats,
        time_budget: Duration::from_secs_f64(if args.quick { 0.3 } else { 1.5 }),
    };
    let budget = Budget {
        max_memory: args.max_memory,
        max_work: args.max_work,
    };
    let scenes = match pick_scenes(&args.scenes, size, &budget) {
        Ok(s) => s,
        Err((code, e)) => {
            eprintln!("error: {e}");
            std::process::exit(code);
        }
    };
    let mut methods: Vec<Method> = if args.methods.is_empty() {
        Method::ALL.to_vec()
    } else {
        args.methods.clone()
    };
    methods.sort();
    methods.dedup();
    if let Err(e) = std::fs::create_dir_all(&args.out) {
        eprintln!("error: cannot create {}: {e}", args.out.display());
        std::process::exit(2);
    }
    plots::register_fonts();

    let steps = scenes.len() * (methods.len() + 1) + if args.no_stability { 0 } else { 2 } + 1;
    let bar = ProgressBar::with_draw_target(Some(steps as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.enable_steady_tick(Duration::from_millis(200));

    let mut results = Vec::new();
    for scene in &scenes {
        let r = measure::measure_scene(scene, &methods, settings, &bar);
        let line = format!(
            "{:<24} {} x {} px, ideal in {:.1} s, done at {:.1} s",
            r.name,
            r.out_size.0,
            r.out_size.1,
            r.ideal_secs,
            started.elapsed().as_secs_f64()
        );
        if bar.is_hidden() {
            eprintln!("{line}");
        } else {
            bar.println(line);
        }
        results.push(r);
    }

    let (stab_rows, curves, stab_secs) = if args.no_stability {
        (Vec::new(), Vec::new(), 0.0)
    } else {
        let t = Instant::now();
        bar.set_message("stability: float32 cases");
        let rows = stability::stability_rows(size);
        bar.inc(1);
        bar.set_message("stability: float32 error against table size");
        let curves = stability::float32_error_vs_size(size);
        bar.inc(1);
        (rows, curves, t.elapsed().as_secs_f64())
    };

    let dof = if args.no_dof {
        None
    } else {
        bar.set_message("depth of field");
        match dof::run(size, repeats) {
            Ok(r) => Some(r),
            Err(e) => {
                bar.finish_and_clear();
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        }
    };

    // Memory traffic and the texel cache, on every scene (the plot: the first).
    let traffic = if args.no_traffic || scenes.is_empty() {
        None
    } else {
        bar.set_message("memory traffic and texel cache");
        let mut all = Vec::new();
        for scene in &scenes {
            match traffic::run(scene) {
                Ok(rows) => all.push((scene, rows)),
                Err(e) => {
                    bar.finish_and_clear();
                    eprintln!("error: traffic on {}: {e}", scene.name);
                    std::process::exit(1);
                }
            }
        }
        let md = traffic::markdown(&all);
        let first = all
            .into_iter()
            .next()
            .map(|(_, rows)| rows)
            .unwrap_or_default();
        Some((md, first))
    };

    bar.set_message("writing report");
    let run = output::RunInfo {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        size,
        repeats,
        methods: methods.clone(),
        stability_secs: stab_secs,
        no_stability: args.no_stability,
    };
    let mut written = Vec::new();
    let mut problems = Vec::new();
    let mut note = |r: Result<PathBuf, String>| match r {
        Ok(p) => written.push(p),
        Err(e) => problems.push(e),
    };
    note(output::write_csv(&args.out, &results));
    if !args.no_stability {
        note(output::write_stability_csv(&args.out, &stab_rows));
    }
    note(plots::error_vs_time(&args.out, &results));
    note(plots::error_vs_cost(&args.out, &results));
    if !args.no_stability {
        note(plots::float32_error_vs_size(&args.out, &curves));
    }
    for (scene, r) in scenes.iter().zip(&results) {
        note(plots::render_strip(&args.out, scene, r));
    }
    if let Some(d) = &dof {
        note(dof::render(&args.out, d));
    }
    if let Some((_, rows)) = &traffic {
        note(traffic::plot(&args.out, rows));
    }
    let total = started.elapsed().as_secs_f64();
    let md = output::write_markdown(&args.out, &run, &results, &stab_rows, &curves, total);
    // The depth-of-field section goes at the end of report.md.
    // The traffic and depth-of-field sections go at the end of report.md.
    let extra = format!(
        "{}{}",
        traffic
            .as_ref()
            .map(|t| format!("\n{}![cache traffic](cache_traffic.png)\n", t.0))
            .unwrap_or_default(),
        dof.as_ref()
            .map(|d| format!("\n{}", dof::markdown(d)))
            .unwrap_or_default()
    );
    let md = match md {
        Ok(path) if !extra.is_empty() => std::fs::read_to_string(&path)
            .and_then(|text| std::fs::write(&path, format!("{text}{extra}")))
            .map(|_| path)
            .map_err(|e| format!("report.md: {e}")),
        md => md,
    };
    note(md);
    bar.inc(1);
    bar.finish_and_clear();

    println!("{}", output::summary_text(&results));
    for p in &written {
        println!("wrote {}", p.display());
    }
    println!("total {total:.1} s");
    if !problems.is_empty() {
        for p in &problems {
            eprintln!("error: {p}");
        }
        std::process::exit(1);
    }
}
