//! The report's PNGs (plotters, bitmap backend, DejaVu Sans embedded): RMSE against time and
//! against reads, the float32 error against table size, and the render strips.

use crate::measure::{MethodResult, SceneResult};
use crate::methods::Method;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::path::{Path, PathBuf};
use texsat_host_tests::scenes::Scene;
use texsat_host_tests::stability::Float32Curve;

const FONT: &str = "sans-serif";

/// Registers DejaVu Sans as plotters' `sans-serif` (no system fonts needed).
pub fn register_fonts() {
    let _ = register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    let _ = register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
}

/// A file-name-safe form of a scene name.
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The colour of a method (related methods in related hues).
pub fn colour(m: Method) -> RGBColor {
    match m {
        Method::Point => RGBColor(120, 120, 120),
        Method::MipPoint => RGBColor(188, 189, 34),
        Method::Trilinear => RGBColor(31, 119, 180),
        Method::Ripmap => RGBColor(23, 190, 207),
        Method::DipmapBilinear => RGBColor(148, 103, 189),
        Method::DipmapTrilinear => RGBColor(90, 50, 140),
        Method::Sat4 => RGBColor(255, 127, 14),
        Method::Sat16Paper => RGBColor(214, 39, 40),
        Method::Sat16Stable => RGBColor(255, 120, 110),
        Method::Sat16StableTiled8 => RGBColor(227, 119, 194),
        Method::Sat16StableTiled2_16 => RGBColor(170, 40, 120),
        Method::Sat16StableModular => RGBColor(140, 86, 75),
        Method::SatPlan => RGBColor(250, 190, 0),
        Method::TentInt => RGBColor(44, 160, 44),
        Method::TentPaper => RGBColor(130, 210, 110),
        Method::TentExact => RGBColor(0, 90, 0),
        Method::Ewa => RGBColor(0, 0, 0),
    }
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

fn err<E: std::fmt::Debug>(path: &Path) -> impl Fn(E) -> String + '_ {
    move |e| format!("drawing {}: {e:?}", path.display())
}

/// Draws marker `shape` (0..8) centred on pixel `p`.
fn marker(
    area: &Area<'_>,
    p: (i32, i32),
    shape: usize,
    size: i32,
    style: ShapeStyle,
) -> Result<(), String> {
    let (x, y) = p;
    let s = size;
    let poly = |pts: Vec<(i32, i32)>| -> Result<(), String> {
        if style.filled {
            area.draw(&Polygon::new(pts, style))
                .map_err(|e| format!("{e:?}"))
        } else {
            let mut pts = pts;
            pts.push(pts[0]);
            area.draw(&PathElement::new(pts, style))
                .map_err(|e| format!("{e:?}"))
        }
    };
    match shape % 8 {
        0 => area
            .draw(&Circle::new(p, s, style))
            .map_err(|e| format!("{e:?}")),
        1 => poly(vec![(x, y - s - 1), (x + s + 1, y + s), (x - s - 1, y + s)]),
        2 => area
            .draw(&Rectangle::new([(x - s, y - s), (x + s, y + s)], style))
            .map_err(|e| format!("{e:?}")),
        3 => poly(vec![
            (x, y - s - 2),
            (x + s + 2, y),
            (x, y + s + 2),
            (x - s - 2, y),
        ]),
        4 => poly(vec![(x - s - 1, y - s), (x + s + 1, y - s), (x, y + s + 1)]),
        5 => {
            let st = style.stroke_width(3);
            area.draw(&PathElement::new(vec![(x - s, y - s), (x + s, y + s)], st))
                .and_then(|_| {
                    area.draw(&PathElement::new(vec![(x - s, y + s), (x + s, y - s)], st))
                })
                .map_err(|e| format!("{e:?}"))
        }
        6 => {
            let st = style.stroke_width(3);
            area.draw(&PathElement::new(vec![(x - s - 1, y), (x + s + 1, y)], st))
                .and_then(|_| {
                    area.draw(&PathElement::new(vec![(x, y - s - 1), (x, y + s + 1)], st))
                })
                .map_err(|e| format!("{e:?}"))
        }
        _ => poly(vec![
            (x - s, y - s / 2),
            (x, y - s - 1),
            (x + s, y - s / 2),
            (x + s, y + s / 2),
            (x, y + s + 1),
            (x - s, y + s / 2),
        ]),
    }
}

fn text(
    area: &Area<'_>,
    s: &str,
    p: (i32, i32),
    size: f64,
    colour: &RGBColor,
) -> Result<(), String> {
    area.draw(&Text::new(
        s.to_string(),
        p,
        (FONT, size).into_font().color(colour),
    ))
    .map_err(|e| format!("{e:?}"))
}

/// A method's mean `(x, rmse)` over the scenes.
type MethodPoint = (Method, f64, f64);

/// The per-method mean over scenes of `(x, rmse)`, and the Pareto front (ascending x, each point
/// with a lower RMSE than every point left of it).
fn means_and_front(
    results: &[SceneResult],
    x: impl Fn(&MethodResult) -> f64,
) -> (Vec<MethodPoint>, Vec<MethodPoint>) {
    let mut means = Vec::new();
    for m in Method::ALL {
        let pts: Vec<(f64, f64)> = results
            .iter()
            .flat_map(|r| r.methods.iter())
            .filter(|r| r.method == m && r.samples > 0 && x(r).is_finite() && r.rmse.is_finite())
            .map(|r| (x(r), r.rmse))
            .collect();
        if !pts.is_empty() {
            let n = pts.len() as f64;
            means.push((
                m,
                pts.iter().map(|p| p.0).sum::<f64>() / n,
                pts.iter().map(|p| p.1).sum::<f64>() / n,
            ));
        }
    }
    // The front is over the contenders: the f64 EWA reference is drawn but not on it.
    let mut sorted: Vec<MethodPoint> = means
        .iter()
        .copied()
        .filter(|m| !m.0.is_reference())
        .collect();
    sorted.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.2.total_cmp(&b.2)));
    let mut front: Vec<MethodPoint> = Vec::new();
    for p in sorted {
        if front.last().is_none_or(|l| p.2 < l.2) {
            front.push(p);
        }
    }
    (means, front)
}

/// RMSE against `x` for every scene and method: `error_vs_time.png` or `error_vs_cost.png`.
#[allow(clippy::too_many_arguments)]
fn error_scatter(
    path: &Path,
    results: &[SceneResult],
    title: &str,
    x_desc: &str,
    x: impl Fn(&MethodResult) -> f64 + Copy,
    skip: impl Fn(Method) -> bool,
) -> Result<PathBuf, String> {
    let e = err(path);
    let root = BitMapBackend::new(path, (1400, 820)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let (plot, legend) = root.split_horizontally(1080);
    let pts: Vec<(usize, &MethodResult)> = results
        .iter()
        .enumerate()
        .flat_map(|(i, r)| r.methods.iter().map(move |m| (i, m)))
        .filter(|(_, m)| {
            !skip(m.method) && m.samples > 0 && x(m) > 0.0 && x(m).is_finite() && m.rmse.is_finite()
        })
        .collect();
    let xmin = pts.iter().map(|p| x(p.1)).fold(f64::INFINITY, f64::min);
    let xmax = pts.iter().map(|p| x(p.1)).fold(0.0, f64::max);
    let ymax = pts.iter().map(|p| p.1.rmse).fold(0.0, f64::max);
    let (xmin, xmax) = if pts.is_empty() {
        (1.0, 10.0)
    } else {
        (xmin / 1.5, xmax * 1.5)
    };
    let ymax = if ymax > 0.0 { ymax * 1.08 } else { 1.0 };
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, (FONT, 24))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin..xmax).log_scale(), 0.0..ymax)
        .map_err(&e)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("RMSE against the ideal (texel units, 0..255)")
        .x_label_formatter(&|v| fmt_tick(*v))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .light_line_style(RGBColor(245, 245, 245))
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()
        .map_err(&e)?;
    // Every scene x method.
    for &(si, m) in &pts {
        let p = chart.backend_coord(&(x(m), m.rmse));
        let c = colour(m.method);
        let style = if m.method.is_reference() {
            c.stroke_width(2)
        } else {
            c.mix(0.75).filled()
        };
        marker(&root, p, si, 5, style)?;
    }
    // Means and the Pareto front of the means.
    let (means, front) = means_and_front(results, x);
    let means: Vec<_> = means.into_iter().filter(|m| !skip(m.0)).collect();
    let front: Vec<_> = front.into_iter().filter(|m| !skip(m.0)).collect();
    let mut stairs = Vec::new();
    for (i, p) in front.iter().enumerate() {
        if i > 0 {
            stairs.push((p.1, front[i - 1].2));
        }
        stairs.push((p.1, p.2));
    }
    chart
        .draw_series(std::iter::once(PathElement::new(
            stairs,
            BLACK.stroke_width(2),
        )))
        .map_err(&e)?;
    for &(m, mx, my) in &means {
        let p = chart.backend_coord(&(mx, my));
        let c = colour(m);
        if m.is_reference() {
            root.draw(&Circle::new(p, 9, c.stroke_width(3)))
                .map_err(&e)?;
        } else {
            root.draw(&Circle::new(p, 9, c.filled())).map_err(&e)?;
            root.draw(&Circle::new(p, 9, BLACK.stroke_width(2)))
                .map_err(&e)?;
        }
    }
    for &(m, mx, my) in &front {
        let p = chart.backend_coord(&(mx, my));
        text(&root, m.name(), (p.0 + 12, p.1 - 20), 15.0, &BLACK)?;
    }
    // Legend: methods (colour) and scenes (shape).
    let mut y = 30;
    text(
        &legend,
        "method (mean over scenes: large mark)",
        (10, y),
        16.0,
        &BLACK,
    )?;
    y += 26;
    for &(m, _, _) in &means {
        let c = colour(m);
        let style = if m.is_reference() {
            c.stroke_width(2)
        } else {
            c.filled()
        };
        legend
            .draw(&Circle::new((22, y + 8), 6, style))
            .map_err(&e)?;
        let label = if m.is_reference() {
            format!("{} (f64 reference)", m.name())
        } else {
            m.name().to_string()
        };
        text(&legend, &label, (36, y), 15.0, &BLACK)?;
        y += 22;
    }
    y += 14;
    text(&legend, "scene", (10, y), 16.0, &BLACK)?;
    y += 26;
    for (i, r) in results.iter().enumerate() {
        marker(&legend, (22, y + 8), i, 5, RGBColor(60, 60, 60).filled())?;
        text(&legend, &r.name, (36, y), 15.0, &BLACK)?;
        y += 22;
    }
    y += 14;
    legend
        .draw(&PathElement::new(
            vec![(12, y + 8), (32, y + 8)],
            BLACK.stroke_width(2),
        ))
        .map_err(&e)?;
    text(&legend, "Pareto front of the means", (36, y), 15.0, &BLACK)?;
    root.present().map_err(&e)?;
    Ok(path.to_path_buf())
}

/// `error_vs_time.png`.
pub fn error_vs_time(dir: &Path, results: &[SceneResult]) -> Result<PathBuf, String> {
    error_scatter(
        &dir.join("error_vs_time.png"),
        results,
        "RMSE against time per sample (one mark per scene and method)",
        "ns per sample (log scale; median of the timed passes, single thread)",
        |m| m.ns,
        |_| false,
    )
}

/// `error_vs_cost.png`.
pub fn error_vs_cost(dir: &Path, results: &[SceneResult]) -> Result<PathBuf, String> {
    error_scatter(
        &dir.join("error_vs_cost.png"),
        results,
        "RMSE against reads per sample (one mark per scene and method)",
        "reads per sample (log scale; texels or table fields fetched, counted)",
        |m| m.reads,
        |m| m == Method::Ewa,
    )
}

/// `float32_error_vs_size.png`: log-log, one line per curve.
pub fn float32_error_vs_size(dir: &Path, curves: &[Float32Curve]) -> Result<PathBuf, String> {
    let path = dir.join("float32_error_vs_size.png");
    let e = err(&path);
    let root = BitMapBackend::new(&path, (1100, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let pos: Vec<f64> = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.1))
        .filter(|v| *v > 0.0 && v.is_finite())
        .collect();
    let ymin = pos.iter().copied().fold(f64::INFINITY, f64::min);
    let ymax = pos.iter().copied().fold(0.0, f64::max);
    let (ymin, ymax) = if pos.is_empty() {
        (1e-6, 1.0)
    } else {
        (ymin / 4.0, ymax * 4.0)
    };
    let sides: Vec<f64> = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.0 as f64))
        .collect();
    let xmin = sides.iter().copied().fold(f64::INFINITY, f64::min);
    let xmax = sides.iter().copied().fold(0.0, f64::max);
    let (xmin, xmax) = if sides.is_empty() {
        (1.0, 10.0)
    } else {
        (xmin / 1.3, xmax * 1.3)
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Largest error of box means against table size (float32 GPU-style build vs exact)",
            (FONT, 21),
        )
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d((xmin..xmax).log_scale().base(2.0), (ymin..ymax).log_scale())
        .map_err(&e)?;
    chart
        .configure_mesh()
        .x_desc(
            "table side n (an n x n texture; log scale); errors of 0 are drawn on the bottom edge",
        )
        .y_desc("max |mean - exact mean|, texel units (log)")
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| fmt_tick(*v))
        .light_line_style(RGBColor(245, 245, 245))
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()
        .map_err(&e)?;
    let palette = [
        RGBColor(214, 39, 40),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(0, 0, 0),
        RGBColor(227, 119, 194),
    ];
    for (i, c) in curves.iter().enumerate() {
        let col = palette[i % palette.len()];
        let pts: Vec<(f64, f64)> = c
            .points
            .iter()
            .map(|&(n, v)| (n as f64, v.max(ymin)))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))
            .map_err(&e)?
            .label(c.method.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(3)));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, col.filled())))
            .map_err(&e)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::MiddleRight)
        .label_font((FONT, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(path.clone())
}

/// The "inferno"-like ramp for `t` in `[0, 1]`.
fn ramp(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 6] = [
        (0.0, [0.0, 0.0, 4.0]),
        (0.2, [50.0, 10.0, 94.0]),
        (0.4, [120.0, 28.0, 109.0]),
        (0.6, [188.0, 55.0, 84.0]),
        (0.8, [249.0, 142.0, 9.0]),
        (1.0, [252.0, 255.0, 164.0]),
    ];
    let t = t.clamp(0.0, 1.0);
    let i = STOPS
        .iter()
        .position(|s| s.0 >= t)
        .unwrap_or(STOPS.len() - 1)
        .max(1);
    let (t0, a) = STOPS[i - 1];
    let (t1, b) = STOPS[i];
    let u = (t - t0) / (t1 - t0);
    let c = |k: usize| (a[k] + (b[k] - a[k]) * u).round() as u8;
    RGBColor(c(0), c(1), c(2))
}

const MISSING: RGBColor = RGBColor(70, 95, 130);

fn grey(v: f64) -> RGBColor {
    let g = v.round().clamp(0.0, 255.0) as u8;
    RGBColor(g, g, g)
}

/// A number rounded up to 1, 2 or 5 times a power of ten.
fn nice_ceil(v: f64) -> f64 {
    if v <= 0.0 || !v.is_finite() {
        return 1.0;
    }
    let p = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|&c| c >= v)
        .unwrap_or(10.0 * p)
}

/// `render_<scene>.png`: the ideal and each rendered method side by side (top), each method's
/// `|method - ideal|` as a heat map below it, on a common scale.
pub fn render_strip(dir: &Path, scene: &Scene, r: &SceneResult) -> Result<PathBuf, String> {
    let path = dir.join(format!("render_{}.png", file_stem(&r.name)));
    let e = err(&path);
    let (w, h) = r.out_size;
    let shown: Vec<&MethodResult> = Method::RENDERED
        .iter()
        .filter_map(|m| r.methods.iter().find(|x| x.method == *m))
        .collect();
    let scale = 300usize.div_ceil(w.max(1)).clamp(1, 6);
    let (pw, ph) = ((w * scale) as i32, (h * scale) as i32);
    let gap = 10;
    let head = 50;
    let top = 60;
    let cols = shown.len() as i32 + 1;
    let width = gap + cols * (pw + gap);
    let height = top + 2 * (head + ph + gap) + 10;
    let root = BitMapBackend::new(&path, (width as u32, height as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    // Common error scale: the largest 99th percentile of the shown methods' errors.
    let mut cap: f64 = 1.0;
    for m in &shown {
        let mut errs: Vec<f64> = m
            .values
            .iter()
            .zip(&r.ideal)
            .filter_map(|(v, i)| Some((v.as_ref()? - i.as_ref()?).abs()))
            .collect();
        if !errs.is_empty() {
            errs.sort_by(f64::total_cmp);
            cap = cap.max(errs[(errs.len() - 1) * 99 / 100]);
        }
    }
    let cap = nice_ceil(cap);
    let title = format!(
        "{} — {} x {} texture, {} x {} pixels, {} (scale {scale}x)",
        r.name,
        r.tex_size.0,
        r.tex_size.1,
        w,
        h,
        crate::output::mode_name(r.mode)
    );
    text(&root, &title, (gap, 10), 24.0, &BLACK)?;
    text(
        &root,
        &scene.description,
        (gap, 36),
        16.0,
        &RGBColor(70, 70, 70),
    )?;
    let draw_img = |x0: i32, y0: i32, px: &dyn Fn(usize) -> RGBColor| -> Result<(), String> {
        for y in 0..h {
            for x in 0..w {
                let c = px(y * w + x);
                for dy in 0..scale {
                    for dx in 0..scale {
                        let p = (x0 + (x * scale + dx) as i32, y0 + (y * scale + dy) as i32);
                        root.draw_pixel(p, &c).map_err(|e| format!("{e:?}"))?;
                    }
                }
            }
        }
        Ok(())
    };
    let y_img = top + head;
    let y_err = top + head + ph + gap + head;
    // Ideal, then the colour bar under it.
    text(
        &root,
        "ideal (exact pre-image mean)",
        (gap, top + 2),
        19.0,
        &BLACK,
    )?;
    draw_img(gap, y_img, &|p| r.ideal[p].map_or(MISSING, grey))?;
    text(
        &root,
        "|method − ideal| (texel units)",
        (gap, y_err - head + 2),
        19.0,
        &BLACK,
    )?;
    let bar_h = 18;
    for x in 0..pw {
        let c = ramp(x as f64 / (pw - 1).max(1) as f64);
        root.draw(&PathElement::new(
            vec![(gap + x, y_err), (gap + x, y_err + bar_h)],
            c,
        ))
        .map_err(&e)?;
    }
    // Square-root scale: small errors stay visible next to point sampling's large ones.
    for (v, label) in [
        (0.0, "0".to_string()),
        (cap / 4.0, format!("{}", cap / 4.0)),
        (cap, format!("{cap}+")),
    ] {
        let x = gap + ((v / cap).sqrt() * (pw - 1) as f64) as i32;
        root.draw(&PathElement::new(
            vec![(x, y_err + bar_h), (x, y_err + bar_h + 5)],
            BLACK,
        ))
        .map_err(&e)?;
        let tx = (x - 4 * label.len() as i32).clamp(gap, gap + pw - 9 * label.len() as i32);
        text(&root, &label, (tx, y_err + bar_h + 7), 14.0, &BLACK)?;
    }
    text(
        &root,
        "(square-root scale)",
        (gap, y_err + bar_h + 26),
        14.0,
        &BLACK,
    )?;
    text(
        &root,
        "no pre-image:",
        (gap, y_err + bar_h + 48),
        14.0,
        &BLACK,
    )?;
    root.draw(&Rectangle::new(
        [
            (gap + 100, y_err + bar_h + 48),
            (gap + 124, y_err + bar_h + 64),
        ],
        MISSING.filled(),
    ))
    .map_err(&e)?;
    for (i, m) in shown.iter().enumerate() {
        let x0 = gap + (i as i32 + 1) * (pw + gap);
        let label = if m.method.is_reference() {
            format!("{} (f64 ref.)", m.method.name())
        } else {
            m.method.name().to_string()
        };
        text(&root, &label, (x0, top + 2), 19.0, &colour_text(m.method))?;
        text(
            &root,
            &format!("RMSE {:.2}, {:.0} ns", m.rmse, m.ns),
            (x0, top + 26),
            16.0,
            &RGBColor(60, 60, 60),
        )?;
        draw_img(x0, y_img, &|p| m.values[p].map_or(MISSING, grey))?;
        text(
            &root,
            &format!("max {:.1}", m.max_err),
            (x0, y_err - head + 26),
            16.0,
            &RGBColor(60, 60, 60),
        )?;
        draw_img(x0, y_err, &|p| match (m.values[p], r.ideal[p]) {
            (Some(v), Some(i)) => ramp(((v - i).abs() / cap).sqrt()),
            _ => MISSING,
        })?;
    }
    root.present().map_err(&e)?;
    Ok(path.clone())
}

fn colour_text(m: Method) -> RGBColor {
    let RGBColor(r, g, b) = colour(m);
    // Darken light colours for legibility on white.
    let f = |v: u8| (v as f64 * 0.75) as u8;
    RGBColor(f(r), f(g), f(b))
}

/// A log-axis tick: integers without decimals, small values with as many as they need.
fn fmt_tick(v: f64) -> String {
    if v >= 1.0 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}
