//! The spatially variant blur scene: a depth-of-field blur in which every pixel has its own box
//! (the use of summed-area tables in Green's GPU depth-of-field slides), rendered with the SAT,
//! with trilinear mip mapping and with an exact `f64` reference; error, counted cost and run time
//! side by side, and the renders.
//!
//! The texture (a checkerboard with value noise on it, `n x n`) is shown one texel per pixel.
//! The depth of pixel `(x, y)` is `d = y / (n - 1)` (a floor receding to the top) and its blur
//! radius `r = R |d - 1/2| / (1/2)` texels, `R = n / 16`: sharp in the middle row, boxes up to
//! `2R + 1` texels wide at the top and bottom. Pixel `(x, y)` is the mean of the texture (clamped
//! to its edges) over the box of side `2r + 1` centred on the texel's centre, corners rounded to
//! `F = 8` fractional bits. A SAT answers every box with the same 16 reads whatever `r`; the mip
//! map's cost is constant too, but it blurs with the level's texels instead of the box.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use texsat::filters::mip::MipPyramid;
use texsat::{ClampToEdge, FracBits, NoCount, Rect, Sat, Stable, Tally, Texture};
use texsat_host_tests::scenes::{checkerboard, value_noise, SceneSize};

/// Fraction bits of the box corners.
const F: u32 = 8;

/// One method's figures on the scene.
pub struct DofRow {
    pub method: &'static str,
    pub mean_abs_error: f64,
    pub max_abs_error: f64,
    pub rms_error: f64,
    pub ns_per_sample: f64,
    pub reads: f64,
    pub muls: f64,
    pub adds: f64,
}

/// The scene's results.
pub struct DofResult {
    pub n: usize,
    pub max_radius: f64,
    pub rows: Vec<DofRow>,
    /// Row-major images: radius (texels), exact, SAT, trilinear.
    pub images: [Vec<f64>; 4],
}

/// The texture: checkerboard squares of `n / 8` in 40..215 plus value noise of amplitude 40.
fn texture(n: usize) -> Vec<u8> {
    let board = checkerboard(n, (n / 8).max(1), 40, 215);
    let noise = value_noise(n, 7);
    board
        .texels
        .iter()
        .zip(&noise.texels)
        .map(|(&b, &v)| {
            (b as f64 + (v as f64 - 127.5) * 40.0 / 255.0)
                .round()
                .clamp(0.0, 255.0) as u8
        })
        .collect()
}

/// The pixel's box, raw corners at `F` bits, and its radius in texels.
fn pixel_box(n: usize, x: usize, y: usize, max_r: f64) -> (Rect<i64>, f64) {
    let d = y as f64 / (n - 1).max(1) as f64;
    let r = max_r * (d - 0.5).abs() * 2.0;
    let half = r + 0.5;
    let raw = |v: f64| (v * f64::from(1u32 << F)).round() as i64;
    let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
    (
        Rect::new(
            raw(cx - half),
            raw(cy - half),
            raw(cx + half),
            raw(cy + half),
        ),
        r,
    )
}

/// The exact mean of the clamped texture over the box (raw corners), in `f64`: every texel
/// the box overlaps weighted by its overlap.
fn exact_mean(tex: &[u8], n: usize, r: &Rect<i64>) -> f64 {
    let s = f64::from(1u32 << F);
    let (x0, y0, x1, y1) = (
        r.x0 as f64 / s,
        r.y0 as f64 / s,
        r.x1 as f64 / s,
        r.y1 as f64 / s,
    );
    let clamp = |i: i64| i.clamp(0, n as i64 - 1) as usize;
    let mut sum = 0.0;
    for j in y0.floor() as i64..y1.ceil() as i64 {
        let wy = (y1.min((j + 1) as f64) - y0.max(j as f64)).max(0.0);
        for i in x0.floor() as i64..x1.ceil() as i64 {
            let wx = (x1.min((i + 1) as f64) - x0.max(i as f64)).max(0.0);
            sum += wx * wy * f64::from(tex[clamp(j) * n + clamp(i)]);
        }
    }
    sum / ((x1 - x0) * (y1 - y0))
}

/// Runs the scene: `repeats` timed passes per method (median).
pub fn run(size: SceneSize, repeats: usize) -> Result<DofResult, String> {
    let n = size.dims().texture;
    let max_r = n as f64 / 16.0;
    let texels = texture(n);
    let tex = Texture::<u8>::new(&texels, n, n).map_err(|e| e.to_string())?;
    let mut table = vec![0u32; n * n];
    let sat = Sat::build(&tex, &mut table).map_err(|e| format!("dof: SAT build: {e}"))?;
    let mut storage = vec![0u8; MipPyramid::<u8>::storage_needed(n, n).map_err(|e| e.to_string())?];
    let mip = MipPyramid::build(&tex, &mut storage).map_err(|e| format!("dof: mip build: {e}"))?;
    let boxes: Vec<(Rect<i64>, f64)> = (0..n * n)
        .map(|p| pixel_box(n, p % n, p / n, max_r))
        .collect();
    let f = FracBits::new(F).map_err(|e| e.to_string())?;

    let t = Instant::now();
    let exact: Vec<f64> = boxes
        .iter()
        .map(|(r, _)| exact_mean(&texels, n, r))
        .collect();
    let exact_ns = t.elapsed().as_nanos() as f64 / boxes.len() as f64;

    let sat_value = |r: &Rect<i64>, k: &mut Tally| -> f64 {
        sat.box_sum_raw(r, f, Stable, ClampToEdge, k)
            .and_then(|s| s.mean_rounded(0, 16, k))
            .map(|m| m as f64 / 65536.0)
            .unwrap_or(f64::NAN)
    };
    let mip_value = |r: &Rect<i64>, k: &mut Tally| -> f64 {
        mip.trilinear_raw(r, f, ClampToEdge, k)
            .ok()
            .and_then(|s| s.value_f64(0))
            .unwrap_or(f64::NAN)
    };
    let mut rows = Vec::new();
    let mut images = [
        boxes.iter().map(|b| b.1).collect::<Vec<f64>>(),
        exact.clone(),
        Vec::new(),
        Vec::new(),
    ];
    for (slot, name, method) in [
        (
            2usize,
            "sat16-stable",
            &sat_value as &dyn Fn(&Rect<i64>, &mut Tally) -> f64,
        ),
        (3, "trilinear", &mip_value),
    ] {
        // Counted costs and values in one pass; then the timed passes with no counter.
        let mut k = Tally::new();
        let values: Vec<f64> = boxes.iter().map(|(r, _)| method(r, &mut k)).collect();
        let mut times = Vec::new();
        for _ in 0..repeats.max(1) {
            let t = Instant::now();
            let mut acc = 0.0;
            for (r, _) in &boxes {
                let v = match slot {
                    2 => sat
                        .box_sum_raw(r, f, Stable, ClampToEdge, &mut NoCount)
                        .and_then(|s| s.mean_rounded(0, 16, &mut NoCount))
                        .map(|m| m as f64)
                        .unwrap_or(0.0),
                    _ => mip
                        .trilinear_raw(r, f, ClampToEdge, &mut NoCount)
                        .map(|s| s.values[0] as f64)
                        .unwrap_or(0.0),
                };
                acc += v;
            }
            std::hint::black_box(acc);
            times.push(t.elapsed().as_nanos() as f64 / boxes.len() as f64);
        }
        times.sort_by(f64::total_cmp);
        let errs: Vec<f64> = values
            .iter()
            .zip(&exact)
            .map(|(v, e)| (v - e).abs())
            .collect();
        let cnt = errs.len() as f64;
        let per = |v: u64| v as f64 / cnt;
        rows.push(DofRow {
            method: name,
            mean_abs_error: errs.iter().sum::<f64>() / cnt,
            max_abs_error: errs.iter().cloned().fold(0.0, f64::max),
            rms_error: (errs.iter().map(|e| e * e).sum::<f64>() / cnt).sqrt(),
            ns_per_sample: times[times.len() / 2],
            reads: per(k.reads),
            muls: per(k.muls),
            adds: per(k.adds),
        });
        images[slot] = values;
    }
    rows.push(DofRow {
        method: "exact (f64, per texel)",
        mean_abs_error: 0.0,
        max_abs_error: 0.0,
        rms_error: 0.0,
        ns_per_sample: exact_ns,
        reads: boxes
            .iter()
            .map(|(r, _)| {
                let c = |a: i64, b: i64| ((b + (1 << F) - 1) >> F) - (a >> F);
                (c(r.x0, r.x1) * c(r.y0, r.y1)) as f64
            })
            .sum::<f64>()
            / boxes.len() as f64,
        muls: f64::NAN,
        adds: f64::NAN,
    });
    Ok(DofResult {
        n,
        max_radius: max_r,
        rows,
        images,
    })
}

/// `render_dof.png`: radius map, exact, SAT, trilinear and 8 x |trilinear - exact|, side by
/// side.
pub fn render(dir: &Path, r: &DofResult) -> Result<PathBuf, String> {
    let n = r.n;
    let panels = 5;
    let mut img = image::GrayImage::new((n * panels + 4 * (panels - 1)) as u32, n as u32);
    for p in img.pixels_mut() {
        p.0 = [255];
    }
    let diff: Vec<f64> = r.images[3]
        .iter()
        .zip(&r.images[1])
        .map(|(a, b)| 255.0 - 8.0 * (a - b).abs())
        .collect();
    let radius: Vec<f64> = r.images[0]
        .iter()
        .map(|v| 255.0 * v / r.max_radius.max(1e-9))
        .collect();
    let sources: [&Vec<f64>; 5] = [&radius, &r.images[1], &r.images[2], &r.images[3], &diff];
    for (k, src) in sources.iter().enumerate() {
        for y in 0..n {
            for x in 0..n {
                let v = src[y * n + x].clamp(0.0, 255.0).round() as u8;
                img.put_pixel((k * (n + 4) + x) as u32, y as u32, image::Luma([v]));
            }
        }
    }
    let path = dir.join("render_dof.png");
    img.save(&path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// The report section (markdown).
pub fn markdown(r: &DofResult) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## Spatially variant blur (depth of field)\n");
    let _ = writeln!(
        s,
        "A {n} x {n} texture (checkerboard and noise) shown one texel per pixel; every pixel is \
         the mean over its own box, side `2r + 1` texels, `r` from 0 (the middle row, in focus) \
         to {R} (top and bottom rows), clamped to the edges, corners at F = {F} bits. Errors in \
         texel units (0..255) against the exact mean of each box; costs per sample as counted \
         (lookup and mean); time per sample on this machine (median of the passes).\n",
        n = r.n,
        R = r.max_radius,
    );
    let _ = writeln!(
        s,
        "| method | mean abs error | RMS error | max abs error | reads | muls | adds | ns / sample |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|");
    for row in &r.rows {
        let num = |v: f64, d: usize| {
            if v.is_nan() {
                "–".to_string()
            } else if v != 0.0 && v.abs() < 1e-3 {
                format!("{v:.2e}")
            } else {
                format!("{v:.d$}")
            }
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            row.method,
            num(row.mean_abs_error, 5),
            num(row.rms_error, 5),
            num(row.max_abs_error, 4),
            num(row.reads, 1),
            num(row.muls, 1),
            num(row.adds, 1),
            num(row.ns_per_sample, 1),
        );
    }
    let _ = writeln!(
        s,
        "\n![depth of field](render_dof.png)\n\nLeft to right: the blur radius (white = {R} \
         texels), the exact image, the SAT (Stable form, exact box sums, the mean rounded to \
         2^-16: its error is that rounding), trilinear mip mapping (the level's texels instead of \
         the box: blocky and shifted where the box is large), and 8 x |trilinear - exact| \
         (white = 0). The SAT's cost per sample is the same for every radius (more reads only \
         where a box crosses the texture's edge and is split into clamped pieces); the exact \
         reference reads every texel of the box.\n",
        R = r.max_radius
    );
    s
}
