//! The report's text outputs: `report.csv`, `stability.csv`, `report.md` and the console summary.

use crate::measure::{MethodResult, SceneResult};
use crate::methods::Method;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use texsat_host_tests::scenes::SceneSize;
use texsat_host_tests::stability::{Float32Curve, StabilityRow};
use texsat_host_tests::RefMode;

/// How the report was run.
pub struct RunInfo {
    /// The command line.
    pub command: String,
    /// Scene size.
    pub size: SceneSize,
    /// Timed passes per method.
    pub repeats: usize,
    /// Methods run.
    pub methods: Vec<Method>,
    /// Seconds spent in the stability study.
    pub stability_secs: f64,
    /// Whether the stability study was skipped.
    pub no_stability: bool,
}

/// The CSV columns, with what each one holds (documented in report.md).
pub const CSV_COLUMNS: [(&str, &str); 27] = [
    ("scene", "scene name"),
    ("method", "method name (`--method`)"),
    (
        "reference",
        "1 for the f64 EWA quality reference, 0 otherwise",
    ),
    ("texture_w", "texture width, texels"),
    ("texture_h", "texture height, texels"),
    ("out_w", "output width, pixels"),
    ("out_h", "output height, pixels"),
    ("mode", "boundary mode of the scene"),
    ("samples", "pixels with an ideal value and a method value"),
    (
        "refused",
        "pixels texsat refused for this method (not in the errors)",
    ),
    (
        "rmse",
        "root mean square error against the ideal, texel units (0..255)",
    ),
    ("psnr_db", "20 log10(255 / rmse)"),
    ("max_abs_error", "largest |method - ideal|, texel units"),
    (
        "arith_error",
        "largest |method - f64 same-filter reference|, texel units",
    ),
    (
        "ns_per_sample",
        "median over the timed passes of (pass time / samples), ns",
    ),
    ("timing_runs", "timed passes run"),
    (
        "reads",
        "table/texel reads per sample (Tally), empty where not counted",
    ),
    ("bits_read", "bits read per sample"),
    ("words", "32-bit words touched per sample"),
    ("muls", "multiplies per sample"),
    ("divs", "divides per sample"),
    ("adds", "additive operations per sample"),
    (
        "bits_per_texel",
        "bits of storage the method reads, per texel",
    ),
    ("memory_ratio", "bits_per_texel / 8 (the 8-bit texture = 1)"),
    ("modular_k", "modulus bits of the scene's modular table"),
    (
        "magnified_share",
        "share of the scene's footprints no larger than one texel per side",
    ),
    ("note", "refusals, structures not built, k"),
];

fn num(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else if v.is_infinite() {
        if v > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        }
    } else {
        format!("{v}")
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The name of a boundary mode.
pub fn mode_name(m: RefMode) -> &'static str {
    match m {
        RefMode::Border => "border",
        RefMode::Clamp => "clamp-to-edge",
        RefMode::Repeat => "repeat",
        RefMode::Mirror => "mirrored-repeat",
    }
}

fn write(path: PathBuf, text: &str) -> Result<PathBuf, String> {
    std::fs::write(&path, text).map_err(|e| format!("writing {}: {e}", path.display()))?;
    Ok(path)
}

/// Writes `report.csv`: one row per scene and method.
pub fn write_csv(dir: &Path, results: &[SceneResult]) -> Result<PathBuf, String> {
    let mut s = String::new();
    let header: Vec<&str> = CSV_COLUMNS.iter().map(|c| c.0).collect();
    let _ = writeln!(s, "{}", header.join(","));
    for r in results {
        for m in &r.methods {
            let row = [
                csv_field(&r.name),
                m.method.name().to_string(),
                (m.method.is_reference() as u8).to_string(),
                r.tex_size.0.to_string(),
                r.tex_size.1.to_string(),
                r.out_size.0.to_string(),
                r.out_size.1.to_string(),
                mode_name(r.mode).to_string(),
                m.samples.to_string(),
                m.refused.to_string(),
                num(m.rmse),
                num(m.psnr),
                num(m.max_err),
                num(m.arith_err),
                num(m.ns),
                m.runs.to_string(),
                num(m.reads),
                num(m.bits_read),
                num(m.words),
                num(m.muls),
                num(m.divs),
                num(m.adds),
                num(m.bits_per_texel),
                num(m.bits_per_texel / 8.0),
                r.modular_k.to_string(),
                num(r.magnified),
                csv_field(&m.note),
            ];
            let _ = writeln!(s, "{}", row.join(","));
        }
    }
    write(dir.join("report.csv"), &s)
}

/// Writes `stability.csv`: the stability rows.
pub fn write_stability_csv(dir: &Path, rows: &[StabilityRow]) -> Result<PathBuf, String> {
    let mut s = String::from("case,method,size,max_abs_error,rms_error,max_rel_error,note\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{}",
            csv_field(&r.case),
            csv_field(&r.method),
            r.size,
            num(r.max_abs_error),
            num(r.rms_error),
            num(r.max_rel_error),
            csv_field(&r.note)
        );
    }
    write(dir.join("stability.csv"), &s)
}

/// A method's figures over every scene it ran on.
pub struct Summary {
    /// The method.
    pub method: Method,
    /// Scenes with samples.
    pub scenes: usize,
    /// Mean RMSE over scenes.
    pub rmse: f64,
    /// Mean PSNR over scenes.
    pub psnr: f64,
    /// Worst max error.
    pub max_err: f64,
    /// Worst arithmetic error.
    pub arith_err: f64,
    /// Mean ns per sample over scenes.
    pub ns: f64,
    /// Mean reads per sample.
    pub reads: f64,
    /// Mean multiplies + divides per sample.
    pub muldiv: f64,
    /// Mean additive operations per sample.
    pub adds: f64,
    /// Mean bits per texel.
    pub bits_per_texel: f64,
    /// Refusals over all scenes.
    pub refused: usize,
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

fn worst(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(f64::NAN, |a, b| if a.is_nan() || b > a { b } else { a })
}

/// The per-method summary, in method order.
pub fn summaries(results: &[SceneResult]) -> Vec<Summary> {
    let mut out = Vec::new();
    for method in Method::ALL {
        let rows: Vec<&MethodResult> = results
            .iter()
            .flat_map(|r| r.methods.iter())
            .filter(|m| m.method == method && m.samples > 0)
            .collect();
        if rows.is_empty() {
            continue;
        }
        out.push(Summary {
            method,
            scenes: rows.len(),
            rmse: mean(rows.iter().map(|m| m.rmse)),
            psnr: mean(rows.iter().map(|m| m.psnr)),
            max_err: worst(rows.iter().map(|m| m.max_err)),
            arith_err: worst(rows.iter().map(|m| m.arith_err)),
            ns: mean(rows.iter().map(|m| m.ns)),
            reads: mean(rows.iter().map(|m| m.reads)),
            muldiv: mean(rows.iter().map(|m| m.muls + m.divs)),
            adds: mean(rows.iter().map(|m| m.adds)),
            bits_per_texel: mean(rows.iter().map(|m| m.bits_per_texel)),
            refused: rows.iter().map(|m| m.refused).sum(),
        });
    }
    out
}

/// A number for a Markdown table: `digits` significant-ish places, `—` for missing.
fn f(v: f64, digits: usize) -> String {
    if v.is_nan() {
        "—".into()
    } else if v.is_infinite() {
        "∞".into()
    } else if v == 0.0 {
        "0".into()
    } else if v.abs() < 10f64.powi(-(digits as i32)) {
        format!("{v:.1e}")
    } else {
        format!("{v:.digits$}")
    }
}

/// The console summary (the Markdown summary table without its links).
pub fn summary_text(results: &[SceneResult]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<24} {:>8} {:>7} {:>8} {:>9} {:>9} {:>6} {:>7} {:>6}",
        "method", "RMSE", "PSNR", "max err", "arith err", "ns/sample", "reads", "mul+div", "bits/t"
    );
    for m in summaries(results) {
        let _ = writeln!(
            s,
            "{:<24} {:>8} {:>7} {:>8} {:>9} {:>9} {:>6} {:>7} {:>6}",
            m.method.name(),
            f(m.rmse, 3),
            f(m.psnr, 2),
            f(m.max_err, 2),
            f(m.arith_err, 5),
            f(m.ns, 1),
            f(m.reads, 1),
            f(m.muldiv, 1),
            f(m.bits_per_texel, 1)
        );
    }
    s
}

/// Today's UTC date `YYYY-MM-DD` (civil-from-days, no dependency).
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let z = secs.div_euclid(86_400) + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!("{y:04}-{m:02}-{d:02}")
}

fn size_name(s: SceneSize) -> &'static str {
    match s {
        SceneSize::Quick => "quick",
        SceneSize::Default => "default",
        SceneSize::Full => "full",
    }
}

fn summary_table(s: &mut String, results: &[SceneResult]) {
    let _ = writeln!(
        s,
        "| method | scenes | mean RMSE | mean PSNR (dB) | worst max error | worst arith. error | mean ns/sample | reads | mul+div | adds | bits/texel | memory × texture | refused |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for m in summaries(results) {
        let name = if m.method.is_reference() {
            format!("{} (reference)", m.method.name())
        } else {
            m.method.name().to_string()
        };
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            m.scenes,
            f(m.rmse, 3),
            f(m.psnr, 2),
            f(m.max_err, 2),
            f(m.arith_err, 6),
            f(m.ns, 1),
            f(m.reads, 2),
            f(m.muldiv, 2),
            f(m.adds, 2),
            f(m.bits_per_texel, 2),
            f(m.bits_per_texel / 8.0, 2),
            m.refused
        );
    }
}

/// The non-reference method with the lowest RMSE on a scene, and the fastest method whose RMSE
/// is within 10% of it.
fn winners(r: &SceneResult) -> Option<(&MethodResult, &MethodResult)> {
    let cands: Vec<&MethodResult> = r
        .methods
        .iter()
        .filter(|m| !m.method.is_reference() && m.samples > 0 && m.rmse.is_finite())
        .collect();
    let best = cands
        .iter()
        .copied()
        .min_by(|a, b| a.rmse.total_cmp(&b.rmse))?;
    let fast = cands
        .iter()
        .copied()
        .filter(|m| m.rmse <= best.rmse * 1.1)
        .min_by(|a, b| a.ns.total_cmp(&b.ns))?;
    Some((best, fast))
}

fn scene_table(s: &mut String, r: &SceneResult) {
    let _ = writeln!(
        s,
        "| method | RMSE | PSNR (dB) | max error | arith. error | ns/sample | reads | muls | divs | adds | bits/texel | memory × | note |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for m in &r.methods {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            m.method.name(),
            f(m.rmse, 3),
            f(m.psnr, 2),
            f(m.max_err, 2),
            f(m.arith_err, 6),
            f(m.ns, 1),
            f(m.reads, 2),
            f(m.muls, 2),
            f(m.divs, 2),
            f(m.adds, 2),
            f(m.bits_per_texel, 2),
            f(m.bits_per_texel / 8.0, 2),
            m.note.replace('|', "\\|")
        );
    }
}

/// Writes `report.md`.
pub fn write_markdown(
    dir: &Path,
    run: &RunInfo,
    results: &[SceneResult],
    stab: &[StabilityRow],
    curves: &[Float32Curve],
    total_secs: f64,
) -> Result<PathBuf, String> {
    let mut s = String::new();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let _ = writeln!(s, "# Texture filtering report\n");
    let _ = writeln!(
        s,
        "Generated {} by `{}` ({} size, {} timed passes per method, {} cores available), in {:.1} s \
         (of which {:.1} s the stability study). Numbers are in texel units (8-bit texels, 0..255) \
         unless stated; `docs/report.md` explains them.\n",
        today(),
        run.command,
        size_name(run.size),
        run.repeats,
        cores,
        total_secs,
        run.stability_secs
    );
    let _ = writeln!(s, "Contents: [summary](#summary) · [scenes](#scenes) · [numerical stability](#numerical-stability) · [methodology](#methodology) · [CSV columns](#csv-columns)\n");

    let _ = writeln!(s, "## Summary\n");
    let _ = writeln!(
        s,
        "Means over the scenes each method ran on (RMSE, PSNR, time and counts are means of the \
         per-scene figures; the max and arithmetic errors are the worst scene's).\n"
    );
    summary_table(&mut s, results);
    let _ = writeln!(s, "\n### Best per scene\n");
    let _ = writeln!(
        s,
        "The contender (EWA excluded) with the lowest RMSE against the ideal, and the fastest \
         contender within 10% of that RMSE.\n"
    );
    let _ = writeln!(
        s,
        "| scene | lowest RMSE | RMSE | EWA RMSE | fastest within 10% | its RMSE | its ns/sample |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for r in results {
        if let Some((best, fast)) = winners(r) {
            let ewa = r
                .methods
                .iter()
                .find(|m| m.method == Method::Ewa)
                .map_or(f64::NAN, |m| m.rmse);
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.name,
                best.method.name(),
                f(best.rmse, 3),
                f(ewa, 3),
                fast.method.name(),
                f(fast.rmse, 3),
                f(fast.ns, 1)
            );
        }
    }
    let _ = writeln!(
        s,
        "\n![RMSE against time](error_vs_time.png)\n\n`error_vs_time.png`: one mark per scene and \
         method (colour = method, shape = scene); the large outlined marks are each method's mean \
         over the scenes, and the black line is the Pareto front of those means (no other method \
         is both faster and more accurate). EWA is drawn hollow: it is the f64 reference.\n"
    );
    let _ = writeln!(
        s,
        "![RMSE against reads](error_vs_cost.png)\n\n`error_vs_cost.png`: the same errors against \
         the counted reads per sample (table entries or texels fetched, Crow's and Heckbert's \
         cost measure). EWA has no counter and is not drawn.\n"
    );

    let _ = writeln!(s, "## Scenes\n");
    for r in results {
        let _ = writeln!(s, "### {}\n", r.name);
        let _ = writeln!(s, "{}\n", r.description);
        let _ = writeln!(
            s,
            "Texture {} x {}, output {} x {} pixels, boundary mode {}; {} pixels with an ideal value{}; \
             {:.1}% of the footprints magnified (both sides at most one texel); footprint area \
             median {} and largest {} texels; modular table k = {} bits; ideal image in {:.1} s.\n",
            r.tex_size.0,
            r.tex_size.1,
            r.out_size.0,
            r.out_size.1,
            mode_name(r.mode),
            r.ideal_pixels,
            if r.unfit > 0 {
                format!(" ({} of them with footprints beyond I24F8's range, skipped)", r.unfit)
            } else {
                String::new()
            },
            100.0 * r.magnified,
            f(r.area_median, 2),
            f(r.area_max, 1),
            r.modular_k,
            r.ideal_secs
        );
        let _ = writeln!(
            s,
            "![renders of {0}](render_{0}.png)\n",
            crate::plots::file_stem(&r.name)
        );
        scene_table(&mut s, r);
        let _ = writeln!(s);
    }

    let _ = writeln!(s, "## Numerical stability\n");
    if run.no_stability {
        let _ = writeln!(s, "Skipped (`--no-stability`).\n");
    } else {
        let _ = writeln!(
            s,
            "float32 summed-area tables built as on a GPU (rows, then columns; each addition one \
             f32 rounding), with and without an offset that centres the texel values, against \
             texsat's exact integer tables and an f64 table, on stiff cases (`host-tests/src/stability.rs` \
             documents each case). Errors are of box means, texel units; relative errors are \
             against the exact mean. Also in `stability.csv`.\n"
        );
        let _ = writeln!(
            s,
            "| case | method | size | max abs error | RMS error | max rel. error | note |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        for r in stab {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.case.replace('|', "\\|"),
                r.method.replace('|', "\\|"),
                r.size,
                sci(r.max_abs_error),
                sci(r.rms_error),
                sci(r.max_rel_error),
                r.note.replace('|', "\\|")
            );
        }
        let _ = writeln!(
            s,
            "\n![float32 error against table size](float32_error_vs_size.png)\n\n\
             `float32_error_vs_size.png`: the largest error of box means against the table side, \
             log-log, per method (zero errors are drawn at the bottom edge).\n"
        );
        if !curves.is_empty() {
            let _ = writeln!(s, "| method | side: max abs error |");
            let _ = writeln!(s, "|---|---|");
            for c in curves {
                let pts: Vec<String> = c
                    .points
                    .iter()
                    .map(|(n, e)| format!("{n}: {}", sci(*e)))
                    .collect();
                let _ = writeln!(s, "| {} | {} |", c.method, pts.join(", "));
            }
            let _ = writeln!(s);
        }
    }

    let _ = writeln!(s, "## Methodology\n");
    let _ = writeln!(
        s,
        "* **Scenes** (`host-tests/src/scenes.rs`): an 8-bit texture, a screen-to-texture mapping with \
         analytic derivatives, an output size and a boundary mode. The **ideal** pixel value is the \
         mean of the extended texture over the pixel's exact pre-image (the image in texture space \
         of the pixel square), in f64; pixels any part of which misses the surface have none and \
         are skipped.\n\
         * **Footprint**: at each pixel centre the Jacobian gives Crow's rectangle (§2.3: centred on \
         (u, v), width max(|du/dx|, |du/dy|), height max(|dv/dx|, |dv/dy|)), rounded to `I24F8` \
         (8 fractional bits; a side that rounds to zero becomes 1/256 texel). Every method filters \
         that rectangle; EWA uses the Jacobian itself.\n\
         * **sat4** rounds the corners to integers (a side that rounds to zero becomes the texel \
         holding the centre). **tent-int** uses the rounded centre and half-widths max(1, round(side/2)); \
         **tent-paper** and **tent-exact** take the fractional rectangle as the tent's support \
         (half-widths = half the sides). **sat16-stable-modular** stores the table modulo 2^k with \
         k = bits_of(255 × the largest number of texel cells a footprint overlaps), plus 2F = 16 \
         bits of headroom if boxes straddling an edge under a wrapping mode need it, so no box is refused.\n\
         * **Errors against the ideal**: RMSE, PSNR (peak 255) and the largest absolute error over \
         the pixels with an ideal value.\n\
         * **Arithmetic error**: the largest |method − f64 reference of the same filter on the same \
         footprint|: `filter_ref_mip` (point, pyramid point, trilinear, with texsat's fixed-point \
         level of detail), `filter_ref_ripdip` (`LevelSel::Fixed`), the exact box mean \
         (`RefTexture::box_integral` / area, or `exact_integral` for boxes of more cells than \
         the texture) for the SAT lookups, direct convolution with `triangle_weights_f64` for the \
         tents (so tent-paper's figure is its bilinear approximation error), and 0 for EWA by \
         definition. The references use the correctly rounded pyramids the host code rebuilds, \
         so the figure covers texsat's storage too.\n\
         * **Time**: each method's samples over all the scene's footprints (precomputed, \
         `black_box`ed, counters compiled out with `NoCount`), {} passes (fewer once a method has \
         spent 1.5 s), median pass time divided by the samples; in one process, single-threaded, \
         release build. EWA is timed the same way but is the f64 quality reference, not a contender.\n\
         * **Counts**: a separate pass with texsat's `Tally` counter: reads (texels or table fields \
         fetched, all channels together), multiplies, divides and additive operations, counted as \
         Crow §2.2 and Heckbert's survey count them (a lerp = 1 multiply + 2 additive), averaged per \
         sample. Edge cases (boxes outside the texture under a wrapping mode, footprints on the \
         table's zero row) change the per-sample figures slightly from the interior counts.\n\
         * **Memory**: bits of storage per texel of the structures the method reads, as stored \
         (entry types as named in each row's definition), and that over the 8-bit texture.\n",
        run.repeats
    );
    let _ = writeln!(s, "| method | what it computes | what it stores |");
    let _ = writeln!(s, "|---|---|---|");
    for m in &run.methods {
        let stores = results
            .iter()
            .flat_map(|r| r.methods.iter())
            .find(|r| r.method == *m)
            .map_or("", |r| r.memory_what);
        let _ = writeln!(s, "| {} | {} | {} |", m.name(), m.what(), stores);
    }
    let _ = writeln!(s, "\n## CSV columns\n");
    let _ = writeln!(
        s,
        "`report.csv` has one row per scene and method; missing values are empty cells.\n"
    );
    let _ = writeln!(s, "| column | meaning |");
    let _ = writeln!(s, "|---|---|");
    for (c, what) in CSV_COLUMNS {
        let _ = writeln!(s, "| `{c}` | {what} |");
    }
    let _ = writeln!(
        s,
        "\n`stability.csv`: `case, method, size, max_abs_error, rms_error, max_rel_error, note` \
         (as the stability table above)."
    );
    write(dir.join("report.md"), &s)
}

fn sci(v: f64) -> String {
    if v.is_nan() {
        "—".into()
    } else if v == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&v.abs()) {
        format!("{v:.4}")
    } else {
        format!("{v:.2e}")
    }
}
