//! Batch lookups against one call per sample (issue 13): ns per sample over the report's
//! built-in scenes, every pixel's footprint in rendering order (row by row), one batch per
//! image row. Run: `cargo run --release -p texsat-tools --example batch_speed [-- quick|default|
//! full] [rounds]` (default: `default` scenes, 31 rounds).
//!
//! Per scene (in its boundary mode) and per method (`sat4` = `box_sum_int` of the rounded
//! rectangle; `sat16-paper` / `sat16-stable` = `box_sum_raw` at F = 8 on the flat `u32` table;
//! `tiled8-stable` = the same on 8 x 8 tiles), `single` loops over the samples calling the
//! single lookup, `batch` calls `BatchLookup::box_sums_*` once per image row. Both answers are
//! compared (every result, errors included) before timing. Rounds interleave single and batch in
//! alternating order; medians, and the median of the per-round ratios.

use std::hint::black_box;
use std::time::Instant;

use fixed::types::I24F8;
use texsat::layouts::{Tiled, TiledSpec};
use texsat::lookup::BatchLookup;
use texsat::{
    BoxSum, ClampToEdge, EdgeMode, Error, FracBits, MirroredRepeat, NoCount, Paper, Rect, Repeat,
    Sat, Stable, Texture,
};
use texsat_host_tests::scenes::{builtin_scenes, Scene, SceneSize};
use texsat_host_tests::RefMode;

type Answer = Result<BoxSum<u64, 1>, Error>;

/// The report's inputs (tools/examples/report/methods.rs `Input::new`): the footprint's Crow
/// rectangle in I24F8 (a side that rounds to nothing made one raw unit wide), and its rounding
/// to integer corners (at least one texel).
fn inputs(scene: &Scene) -> Vec<Vec<(Rect<i64>, Rect<i32>)>> {
    const F: u32 = 8;
    (0..scene.height)
        .map(|py| {
            (0..scene.width)
                .filter_map(|px| {
                    let fp = scene.mapping.footprint(px as f64 + 0.5, py as f64 + 0.5)?;
                    let r = fp.crow_rect();
                    let q = Rect::<I24F8>::from_f64(r.u0, r.v0, r.u1, r.v1).ok()?;
                    let mut raw = [q.x0, q.y0, q.x1, q.y1].map(|v| i64::from(v.to_bits()));
                    for a in 0..2 {
                        if raw[a + 2] <= raw[a] {
                            raw[a + 2] = raw[a] + 1;
                        }
                    }
                    let round = |v: i64| ((v + 128) >> F) as i32;
                    let mut ir = raw.map(round);
                    for a in 0..2 {
                        if ir[a + 2] <= ir[a] {
                            ir[a] = ((raw[a] + raw[a + 2]) >> (F + 1)) as i32;
                            ir[a + 2] = ir[a] + 1;
                        }
                    }
                    Some((
                        Rect::new(raw[0], raw[1], raw[2], raw[3]),
                        Rect::new(ir[0], ir[1], ir[2], ir[3]),
                    ))
                })
                .collect()
        })
        .collect()
}

#[derive(Clone, Copy, PartialEq)]
enum Method {
    Sat4,
    Paper,
    Stable,
}

/// Answers of every sample, single calls (`batch = false`) or one batch per row.
#[allow(clippy::too_many_arguments)]
fn run<L: BatchLookup<1, Value = u32>, M: EdgeMode>(
    layout: &L,
    rows: &[Vec<(Rect<i64>, Rect<i32>)>],
    raw: &[Vec<Rect<i64>>],
    int: &[Vec<Rect<i32>>],
    method: Method,
    mode: M,
    batch: bool,
    out: &mut [Vec<Answer>],
) {
    let f = FracBits::new(8).expect("F");
    for (y, row) in rows.iter().enumerate() {
        let o = &mut out[y];
        if batch {
            match method {
                Method::Sat4 => layout.box_sums_int(&int[y], mode, &mut NoCount, o),
                Method::Paper => layout.box_sums_raw(&raw[y], f, Paper, mode, &mut NoCount, o),
                Method::Stable => layout.box_sums_raw(&raw[y], f, Stable, mode, &mut NoCount, o),
            };
        } else {
            // The method chosen outside the loop, as for the batch: one lookup per iteration.
            let pairs = row.iter().zip(o.iter_mut());
            match method {
                Method::Sat4 => {
                    for ((_, ir), o) in pairs {
                        *o = layout.box_sum_int(ir, mode, &mut NoCount);
                    }
                }
                Method::Paper => {
                    for ((r, _), o) in pairs {
                        *o = layout.box_sum_raw(r, f, Paper, mode, &mut NoCount);
                    }
                }
                Method::Stable => {
                    for ((r, _), o) in pairs {
                        *o = layout.box_sum_raw(r, f, Stable, mode, &mut NoCount);
                    }
                }
            }
        }
    }
}

fn measure<L: BatchLookup<1, Value = u32>, M: EdgeMode + Copy>(
    name: &str,
    layout: &L,
    rows: &[Vec<(Rect<i64>, Rect<i32>)>],
    methods: &[(&str, Method)],
    mode: M,
    rounds: usize,
) {
    let raw: Vec<Vec<Rect<i64>>> = rows
        .iter()
        .map(|r| r.iter().map(|p| p.0).collect())
        .collect();
    let int: Vec<Vec<Rect<i32>>> = rows
        .iter()
        .map(|r| r.iter().map(|p| p.1).collect())
        .collect();
    let samples: usize = rows.iter().map(Vec::len).sum();
    for &(mname, method) in methods {
        let fresh = || -> Vec<Vec<Answer>> {
            rows.iter()
                .map(|r| vec![Err(Error::EmptyTexture); r.len()])
                .collect()
        };
        let (mut a, mut b) = (fresh(), fresh());
        run(layout, rows, &raw, &int, method, mode, false, &mut a);
        run(layout, rows, &raw, &int, method, mode, true, &mut b);
        assert!(a == b, "{name} {mname}: batch answers differ");
        let mut times = [Vec::new(), Vec::new()];
        for round in 0..rounds {
            for k in [round % 2, 1 - round % 2] {
                let t = Instant::now();
                run(
                    layout,
                    rows,
                    &raw,
                    &int,
                    method,
                    mode,
                    k == 1,
                    black_box(&mut a),
                );
                times[k].push(t.elapsed().as_secs_f64() * 1e9 / samples as f64);
            }
        }
        let med = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        // Paired: each round's batch time over the same round's single time.
        let mut ratios: Vec<f64> = times[1].iter().zip(&times[0]).map(|(b, s)| b / s).collect();
        let r = med(&mut ratios);
        let (s, bt) = (med(&mut times[0]), med(&mut times[1]));
        println!("| {name} | {mname} | {samples} | {s:.1} | {bt:.1} | {r:.2} |");
    }
}

fn scene_mode<M: EdgeMode + Copy>(scene: &Scene, rounds: usize, mode: M) {
    let t = &scene.texture;
    let texels: Vec<u8> = t.texels.iter().map(|&v| v.min(255) as u8).collect();
    let texture = Texture::<u8>::new(&texels, t.width, t.height).expect("texture");
    let mut table = vec![0u32; t.width * t.height];
    let sat = Sat::build(&texture, &mut table).expect("build");
    let rows = inputs(scene);
    let all = [
        ("sat4", Method::Sat4),
        ("sat16-paper", Method::Paper),
        ("sat16-stable", Method::Stable),
    ];
    measure(&scene.name, &sat, &rows, &all, mode, rounds);
    let spec = TiledSpec::tiles(8, 8).expect("spec");
    let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, t.width, t.height, 8).expect("w")];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, t.width).expect("s")];
    let tiled = Tiled::<u32>::build(&texture, spec, &mut words, &mut scratch).expect("tiled");
    measure(
        &scene.name,
        &tiled,
        &rows,
        &[("tiled8-stable", Method::Stable)],
        mode,
        rounds,
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let size = match args.get(1).map(String::as_str) {
        Some("quick") => SceneSize::Quick,
        Some("full") => SceneSize::Full,
        _ => SceneSize::Default,
    };
    let rounds: usize = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(31);
    println!(
        "kernel {}; {size:?} scenes, {rounds} rounds; medians",
        texsat::build_kernel()
    );
    println!("| scene | method | samples | single ns/sample | batch ns/sample | batch / single (paired) |");
    println!("|---|---|---:|---:|---:|---:|");
    for scene in builtin_scenes(size) {
        match scene.mode {
            RefMode::Border => scene_mode(&scene, rounds, texsat::Border),
            RefMode::Clamp => scene_mode(&scene, rounds, ClampToEdge),
            RefMode::Repeat => scene_mode(&scene, rounds, Repeat),
            RefMode::Mirror => scene_mode(&scene, rounds, MirroredRepeat),
        }
    }
}
