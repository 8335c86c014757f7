//! Memory traffic and a texel cache for each method and layout, on one scene rendered in
//! scanline order and in 8 x 8 tiles.
//!
//! Every lookup reports where it reads (`texsat::Counter::read_at`): a bit range of the table,
//! the texture or a filter's storage. A recording counter collects those reads per sample; the
//! models of `texsat_tools::cache` turn them into bus traffic (32- and 64-bit buses, bursts of 4)
//! and the behaviour of a set-associative LRU texel cache (8 KiB, 32-byte lines, 4 ways).

use crate::methods::{texels_u8, Input, F};
use std::fmt::Write as _;
use texsat::filters::mip::MipPyramid;
use texsat::layouts::{Modular, Tiled, TiledSpec};
use texsat::{BoxLookup, Counter, EdgeKind, FormKind, FracBits, Region, Sat, Texture};
use texsat_host_tests::scenes::Scene;
use texsat_host_tests::RefMode;
use texsat_tools::cache::{Access, Bus, BusTraffic, Cache};

/// A counter that records every read's place.
#[derive(Default)]
struct Trace {
    reads: Vec<Access>,
}

impl Counter for Trace {
    fn reads(&mut self, _n: u32, _bits: u32) {}
    fn muls(&mut self, _n: u32) {}
    fn divs(&mut self, _n: u32) {}
    fn adds(&mut self, _n: u32) {}
    fn read_at(&mut self, region: Region, offset: u64, bits: u32) {
        let region = match region {
            Region::Table => 0,
            Region::Texture => 1,
            Region::Filter => 2,
        };
        self.reads.push(Access {
            region,
            offset,
            bits,
        });
    }
}

/// The cache the rows are measured with.
pub const CACHE: (u64, u64, usize) = (8 * 1024, 32, 4);

/// One method or layout in one rendering order.
pub struct TrafficRow {
    pub method: String,
    pub order: &'static str,
    pub samples: usize,
    /// Reads per sample.
    pub reads: f64,
    /// Bits asked for per sample.
    pub bits: f64,
    /// Bytes per sample with no cache: 32-bit bus single transfers, 64-bit bus single
    /// transfers, 64-bit bus bursts of 4.
    pub bus_bytes: [f64; 3],
    /// Cache hit rate (line accesses).
    pub hit_rate: f64,
    /// Bytes fetched from memory per sample behind the cache.
    pub cache_bytes: f64,
}

/// Pixel order: scanlines, or 8 x 8 tiles (each tile in scanline order).
fn orders(w: usize, h: usize) -> [(&'static str, Vec<usize>); 2] {
    let scan: Vec<usize> = (0..w * h).collect();
    let mut tiles = Vec::with_capacity(w * h);
    for ty in (0..h).step_by(8) {
        for tx in (0..w).step_by(8) {
            for y in ty..(ty + 8).min(h) {
                for x in tx..(tx + 8).min(w) {
                    tiles.push(y * w + x);
                }
            }
        }
    }
    [("scanline", scan), ("8x8 tiles", tiles)]
}

/// The traffic of one method: `sample(input, trace)` runs one lookup into the trace.
fn measure(
    name: &str,
    inputs: &[Option<&Input>],
    w: usize,
    h: usize,
    mut sample: impl FnMut(&Input, &mut Trace),
) -> Vec<TrafficRow> {
    let mut rows = Vec::new();
    for (order, pixels) in orders(w, h) {
        let mut trace = Trace::default();
        let mut samples = 0usize;
        for &p in &pixels {
            if let Some(Some(inp)) = inputs.get(p) {
                sample(inp, &mut trace);
                samples += 1;
            }
        }
        let n = samples.max(1) as f64;
        let buses = [
            Bus {
                width: 32,
                burst: 1,
            },
            Bus {
                width: 64,
                burst: 1,
            },
            Bus {
                width: 64,
                burst: 4,
            },
        ];
        let t: Vec<BusTraffic> = buses.iter().map(|b| b.traffic(&trace.reads)).collect();
        let (size, line, ways) = CACHE;
        let mut cache = match Cache::new(size, line, ways) {
            Ok(c) => c,
            Err(_) => return rows,
        };
        for a in &trace.reads {
            cache.access(a);
        }
        rows.push(TrafficRow {
            method: name.to_string(),
            order,
            samples,
            reads: t[0].reads as f64 / n,
            bits: t[0].bits as f64 / n,
            bus_bytes: [
                t[0].bytes(&buses[0]) as f64 / n,
                t[1].bytes(&buses[1]) as f64 / n,
                t[2].bytes(&buses[2]) as f64 / n,
            ],
            hit_rate: cache.hit_rate(),
            cache_bytes: cache.bytes_fetched() as f64 / n,
        });
    }
    rows
}

/// Runs every method on `scene` (its footprints, its boundary mode).
pub fn run(scene: &Scene) -> Result<Vec<TrafficRow>, String> {
    let tex = &scene.texture;
    let (tw, th) = (tex.width, tex.height);
    let texels = texels_u8(tex);
    let texture = Texture::<u8>::new(&texels, tw, th).map_err(|e| e.to_string())?;
    let (w, h) = (scene.width, scene.height);
    let owned: Vec<Option<Input>> = (0..w * h)
        .map(|p| {
            let fp = scene
                .mapping
                .footprint((p % w) as f64 + 0.5, (p / w) as f64 + 0.5)?;
            Input::new(p, fp)
        })
        .collect();
    let inputs: Vec<Option<&Input>> = owned.iter().map(Option::as_ref).collect();
    let kind = match scene.mode {
        RefMode::Border => EdgeKind::Border,
        RefMode::Clamp => EdgeKind::Clamp,
        RefMode::Repeat => EdgeKind::Repeat,
        RefMode::Mirror => EdgeKind::Mirror,
    };
    let f = FracBits::new(F).map_err(|e| e.to_string())?;
    let mut rows = Vec::new();

    let mut flat = vec![0u32; tw * th];
    let sat = Sat::build(&texture, &mut flat).map_err(|e| e.to_string())?;
    rows.extend(measure("sat16-stable (flat u32)", &inputs, w, h, |i, k| {
        let r = texsat::Rect::new(i.raw[0], i.raw[1], i.raw[2], i.raw[3]);
        let _ = sat.box_sum_raw(&r, f, FormKind::Stable, kind, k);
    }));
    rows.extend(measure(
        "sat4 (flat u32, integer corners)",
        &inputs,
        w,
        h,
        |i, k| {
            let _ = sat.box_sum_int(&i.int_rect, kind, k);
        },
    ));

    let spec = TiledSpec::tiles(8, 8).map_err(|e| e.to_string())?;
    let mut words =
        vec![0u32; Tiled::<u32>::words_needed(spec, tw, th, 8).map_err(|e| e.to_string())?];
    let mut scratch =
        vec![0u32; Tiled::<u32>::scratch_needed(spec, tw).map_err(|e| e.to_string())?];
    let tiled =
        Tiled::<u32>::build(&texture, spec, &mut words, &mut scratch).map_err(|e| e.to_string())?;
    rows.extend(measure(
        "sat16-stable (tiled 8x8)",
        &inputs,
        w,
        h,
        |i, k| {
            let r = texsat::Rect::new(i.raw[0], i.raw[1], i.raw[2], i.raw[3]);
            let _ = tiled.box_sum_raw(&r, f, FormKind::Stable, kind, k);
        },
    ));

    // Modular with the k that serves every footprint of the scene (as the report's modular
    // method picks it): the largest box's cells.
    let max_cells = owned
        .iter()
        .flatten()
        .map(|i| {
            let cells = |a: i64, b: i64| (((b + (1 << F) - 1) >> F) - (a >> F)) as u128;
            cells(i.raw[0], i.raw[2]) * cells(i.raw[1], i.raw[3])
        })
        .max()
        .unwrap_or(1);
    let k = texsat::width::bits_of(255 * max_cells).max(8);
    if k <= 32 {
        let mut mw =
            vec![0u32; Modular::<u32>::words_needed(tw, th, k).map_err(|e| e.to_string())?];
        let mut row = vec![0u32; tw];
        let m = Modular::<u32>::build(&texture, k, &mut mw, &mut row).map_err(|e| e.to_string())?;
        rows.extend(measure(
            &format!("sat16-stable (modular:{k})"),
            &inputs,
            w,
            h,
            |i, kk| {
                let r = texsat::Rect::new(i.raw[0], i.raw[1], i.raw[2], i.raw[3]);
                let _ = m.box_sum_raw(&r, f, FormKind::Stable, kind, kk);
            },
        ));
    }

    let mut pyr = vec![0u8; MipPyramid::<u8>::storage_needed(tw, th).map_err(|e| e.to_string())?];
    let mip = MipPyramid::build(&texture, &mut pyr).map_err(|e| e.to_string())?;
    rows.extend(measure("trilinear (mip map)", &inputs, w, h, |i, k| {
        let r = texsat::Rect::new(i.raw[0], i.raw[1], i.raw[2], i.raw[3]);
        let _ = mip.trilinear_raw(&r, f, kind, k);
    }));
    Ok(rows)
}

/// The report section: every scene's rows (the first scene's described in the text).
pub fn markdown(scenes: &[(&Scene, Vec<TrafficRow>)]) -> String {
    let Some((scene, _)) = scenes.first() else {
        return String::new();
    };
    let mut s = String::new();
    let (size, line, ways) = CACHE;
    let _ = writeln!(s, "## Memory traffic and texel cache\n");
    let _ = writeln!(
        s,
        "Every scene, every pixel's footprint, in two rendering orders (the plot: scene `{}`, \
         {} x {} pixels, {} x {} texture). Per sample: reads and bits as the lookups report them \
         (`Counter::read_at`), the \
         bytes a bus moves with no cache (each read fetches every aligned bus word or burst it \
         overlaps), and behind a {} KiB set-associative cache ({}-byte lines, {} ways, LRU): the \
         hit rate of line accesses and the bytes fetched from memory. The table, the texture and \
         the pyramid are separate memories (`tools/src/cache.rs`).\n",
        scene.name,
        scene.width,
        scene.height,
        scene.texture.width,
        scene.texture.height,
        size / 1024,
        line,
        ways
    );
    let _ = writeln!(
        s,
        "| scene | method (layout) | order | reads | bits | bytes, 32-bit bus | bytes, 64-bit bus | bytes, 64-bit x 4 bursts | cache hit rate | bytes from memory behind the cache | KiB per frame behind the cache |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (scene, rows) in scenes {
        for r in rows {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.1} | {:.0} | {:.1} | {:.1} | {:.1} | {:.3} | {:.2} | {:.1} |",
                scene.name,
                r.method,
                r.order,
                r.reads,
                r.bits,
                r.bus_bytes[0],
                r.bus_bytes[1],
                r.bus_bytes[2],
                r.hit_rate,
                r.cache_bytes,
                r.cache_bytes * r.samples as f64 / 1024.0
            );
        }
    }
    let _ = writeln!(
        s,
        "\nA frame is every pixel whose footprint the scene defines (the samples); per frame with \
         no cache, multiply the bus bytes by them. A SAT lookup's 16 reads fall on four 2 x 2 \
         neighbourhoods that neighbouring pixels share when the footprints overlap; the tiled \
         layout reads narrower fields (fewer bits) spread over four components; the mip map \
         reads 8 texels of two small levels, which a small cache holds.\n"
    );
    s
}

/// `cache_traffic.png`: bytes fetched from memory per sample behind the cache, and with no
/// cache on a 32-bit bus, per method and layout, for both rendering orders (log scale).
pub fn plot(dir: &std::path::Path, rows: &[TrafficRow]) -> Result<std::path::PathBuf, String> {
    use plotters::prelude::*;
    let path = dir.join("cache_traffic.png");
    let shown = path.display().to_string();
    let e = |x: &dyn std::fmt::Display| format!("{shown}: {x}");
    let root = BitMapBackend::new(&path, (1100, 620)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let methods: Vec<&str> = {
        let mut m: Vec<&str> = rows.iter().map(|r| r.method.as_str()).collect();
        m.dedup();
        m
    };
    let ymax = rows
        .iter()
        .map(|r| r.bus_bytes[0].max(r.cache_bytes))
        .fold(1.0, f64::max)
        * 2.0;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Bytes from memory per sample: no cache (32-bit bus) and behind an 8 KiB LRU cache",
            ("sans-serif", 20),
        )
        .margin(16)
        .x_label_area_size(20)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..methods.len() as f64, (0.08f64..ymax).log_scale())
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc("bytes per sample (log)")
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|x| e(&x))?;
    let bars = [
        (
            "no cache, 32-bit bus (either order)",
            RGBColor(150, 150, 150),
        ),
        ("cache, scanline order", RGBColor(31, 119, 180)),
        ("cache, 8x8 tiles", RGBColor(255, 127, 14)),
    ];
    for (k, &(label, color)) in bars.iter().enumerate() {
        let rects: Vec<Rectangle<(f64, f64)>> = methods
            .iter()
            .enumerate()
            .filter_map(|(i, m)| {
                let v = match k {
                    0 => rows.iter().find(|r| r.method == *m)?.bus_bytes[0],
                    1 => {
                        rows.iter()
                            .find(|r| r.method == *m && r.order == "scanline")?
                            .cache_bytes
                    }
                    _ => {
                        rows.iter()
                            .find(|r| r.method == *m && r.order != "scanline")?
                            .cache_bytes
                    }
                };
                let x0 = i as f64 + 0.15 + 0.23 * k as f64;
                Some(Rectangle::new(
                    [(x0, 0.1), (x0 + 0.2, v.max(0.1))],
                    color.filled(),
                ))
            })
            .collect();
        chart
            .draw_series(rects)
            .map_err(|x| e(&x))?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled()));
    }
    // The method names under their bars (inside the plot, above the axis).
    chart
        .draw_series(methods.iter().enumerate().map(|(i, m)| {
            Text::new(
                m.to_string(),
                (i as f64 + 0.12, 0.13),
                ("sans-serif", 13).into_font(),
            )
        }))
        .map_err(|x| e(&x))?;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    drop(chart);
    drop(root);
    Ok(path)
}
