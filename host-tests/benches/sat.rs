//! Benchmarks for texsat: table build throughput and per-lookup time.
//!
//! Run all of them once, on one machine, so the ratios between variants mean something:
//!
//! ```text
//! cargo bench -p texsat-host-tests --bench sat
//! ```
//!
//! Quick mode (shorter warm-up and measurement, for a smoke run): criterion's own `--quick`
//! (`cargo bench -p texsat-host-tests --bench sat -- --quick`) or `TEXSAT_BENCH_QUICK=1`, which
//! cuts the warm-up and measurement times below. CI only compiles this file
//! (`cargo clippy --all-targets`), it does not run it. Results are written up in
//! `docs/benchmarks.md`.
//!
//! * `build/*`: a 4096 x 4096 `u8` texture (seeded ChaCha8 content) into `u32` entries, reported as
//!   elements (texels) per second. `texsat_build` is [`Sat::build`] into reused storage;
//!   `texsat_build_alloc` allocates the storage in the timed loop, as `imageproc` does;
//!   `imageproc` is `imageproc::integral_image::integral_image::<_, u32>`, whose output is
//!   `(w + 1) x (h + 1)` with a zero first row and column (it allocates it on every call);
//!   `naive_3add_indexed` is the textbook `t + left + above - aboveleft` recurrence written here
//!   with plain indexing and edge branches, `naive_3add_rows` the same recurrence over row slices;
//!   `row_stream` pushes rows through [`RowStreamBuilder`] and copies each finished row into a
//!   table, as a caller storing the table elsewhere would.
//! * `lookup/*`: a 1024 x 1024 `u8` texture into `u32` entries and 4096 precomputed random
//!   boxes; one iteration runs every box once, reported as elements (lookups) per second, so
//!   criterion's time per element is the time per lookup.
//! * `lookup_l1/*`: the same lookups on a 64 x 64 table (16 KiB, inside L1), to separate the
//!   arithmetic from the cache misses of the 4 MiB table.

use std::hint::black_box;
use std::time::Duration;

use criterion::{
    criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode, Throughput,
};
use fixed::types::I24F8;
use image::GrayImage;
use texsat::{
    Border, NoCount, Paper, Rect, Repeat, RowStreamBuilder, Sat, Shortcut, Stable, Tally, Texture,
};
use texsat_host_tests::{rng, Rng, RngExt, TestRng};

/// Side of the build benchmark's texture.
const BUILD_SIDE: usize = 4096;
/// Side of the lookup benchmark's texture.
const LOOKUP_SIDE: usize = 1024;
/// Boxes per lookup iteration.
const N_BOXES: usize = 4096;
/// Side of the cache-resident lookup table.
const L1_SIDE: usize = 64;
/// Fractional bits of the fixed-point corners (`I24F8`).
const F: u32 = 8;

/// Deterministic pseudo-random content: the host tests' one seeded generator.
fn texels(side: usize, seed: u64) -> Vec<u8> {
    let mut v = vec![0u8; side * side];
    rng(seed).fill_bytes(&mut v);
    v
}

fn quick() -> bool {
    std::env::var_os("TEXSAT_BENCH_QUICK").is_some_and(|v| !v.is_empty() && v != "0")
}

/// Warm-up and measurement time: short by default, shorter in quick mode.
fn times(warm_ms: u64, measure_ms: u64) -> (Duration, Duration) {
    if quick() {
        (Duration::from_millis(100), Duration::from_millis(300))
    } else {
        (
            Duration::from_millis(warm_ms),
            Duration::from_millis(measure_ms),
        )
    }
}

/// The textbook build: `entry = t + left + above - aboveleft` (three additive operations per
/// entry). Wrapping arithmetic because `t + left + above` can exceed `u32` before the subtraction
/// brings it back; the result is exact modulo `2^32`, and every entry fits.
fn naive_build(tex: &[u8], w: usize, h: usize, out: &mut [u32]) {
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let left = if x > 0 { out[i - 1] } else { 0 };
            let above = if y > 0 { out[i - w] } else { 0 };
            let above_left = if x > 0 && y > 0 { out[i - w - 1] } else { 0 };
            out[i] = (tex[i] as u32)
                .wrapping_add(left)
                .wrapping_add(above)
                .wrapping_sub(above_left);
        }
    }
}

/// The same three-addition recurrence written over row slices: no per-entry bounds checks or
/// edge branches, so the only difference from [`Sat::build`] is the extra addition.
fn naive_build_rows(tex: &[u8], w: usize, out: &mut [u32]) {
    let mut above: Option<&[u32]> = None;
    for (src, row) in tex.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
        let (mut left, mut above_left) = (0u32, 0u32);
        match above {
            None => {
                for (o, &t) in row.iter_mut().zip(src) {
                    left = left.wrapping_add(t as u32);
                    *o = left;
                }
            }
            Some(above) => {
                for ((o, &t), &a) in row.iter_mut().zip(src).zip(above) {
                    left = (t as u32)
                        .wrapping_add(left)
                        .wrapping_add(a)
                        .wrapping_sub(above_left);
                    above_left = a;
                    *o = left;
                }
            }
        }
        above = Some(row);
    }
}

/// Streams the texture through [`RowStreamBuilder`] and copies each table row into `out`.
fn stream_build(tex: &[u8], w: usize, h: usize, row: &mut [u32], out: &mut [u32]) {
    let mut b = RowStreamBuilder::<u32>::new(w, h, 8, row).expect("stream builder");
    for (src, dst) in tex.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
        dst.copy_from_slice(b.push_row(src).expect("push_row"));
    }
    b.finish().expect("finish");
}

fn bench_build(c: &mut Criterion) {
    let (w, h) = (BUILD_SIDE, BUILD_SIDE);
    let tex = texels(w, 0x9E37_79B9_7F4A_7C15);
    let texture = Texture::<u8>::new(&tex, w, h).expect("texture");
    let gray = GrayImage::from_raw(w as u32, h as u32, tex.clone()).expect("gray image");

    // All variants must produce the same table before any of them is timed.
    let mut reference = vec![0u32; w * h];
    Sat::build(&texture, &mut reference).expect("build");
    let ip = imageproc::integral_image::integral_image::<_, u32>(&gray);
    assert_eq!((ip.width() as usize, ip.height() as usize), (w + 1, h + 1));
    for y in 0..h {
        let ip_row = &ip.as_raw()[(y + 1) * (w + 1) + 1..(y + 2) * (w + 1)];
        assert_eq!(ip_row, &reference[y * w..(y + 1) * w], "imageproc row {y}");
    }
    let mut table = vec![0u32; w * h];
    naive_build(&tex, w, h, &mut table);
    assert_eq!(table, reference, "naive build");
    table.fill(0);
    naive_build_rows(&tex, w, &mut table);
    assert_eq!(table, reference, "naive row build");
    let mut row = vec![0u32; w];
    table.fill(0);
    stream_build(&tex, w, h, &mut row, &mut table);
    assert_eq!(table, reference, "row stream build");

    let (warm, measure) = times(1000, 4000);
    let mut g = c.benchmark_group("build");
    g.sampling_mode(SamplingMode::Flat)
        .warm_up_time(warm)
        .measurement_time(measure)
        .throughput(Throughput::Elements((w * h) as u64));

    g.bench_function("texsat_build", |b| {
        b.iter(|| {
            let sat = Sat::build(black_box(&texture), &mut table).expect("build");
            black_box(sat.total())
        })
    });
    g.bench_function("texsat_build_alloc", |b| {
        b.iter(|| {
            let mut storage = vec![0u32; w * h];
            let total = Sat::build(black_box(&texture), &mut storage)
                .expect("build")
                .total();
            black_box(storage);
            total
        })
    });
    g.bench_function("imageproc", |b| {
        b.iter(|| imageproc::integral_image::integral_image::<_, u32>(black_box(&gray)))
    });
    g.bench_function("naive_3add_indexed", |b| {
        b.iter(|| {
            naive_build(black_box(&tex), w, h, &mut table);
            black_box(table[w * h - 1])
        })
    });
    g.bench_function("naive_3add_rows", |b| {
        b.iter(|| {
            naive_build_rows(black_box(&tex), w, &mut table);
            black_box(table[w * h - 1])
        })
    });
    g.bench_function("row_stream", |b| {
        b.iter(|| {
            stream_build(black_box(&tex), w, h, &mut row, &mut table);
            black_box(table[w * h - 1])
        })
    });
    g.finish();
}

/// A random interior box with integer corners: every corner off the zero row and column of the
/// corner function, so each lookup costs the full 4 reads. Sides in `min_side..=max_side`.
fn int_box(rng: &mut TestRng, n: i64, min_side: i64, max_side: i64) -> Rect<i32> {
    let sw = rng.random_range(min_side..max_side + 1);
    let sh = rng.random_range(min_side..max_side + 1);
    let x0 = rng.random_range(1..n - sw + 1);
    let y0 = rng.random_range(1..n - sh + 1);
    Rect::new(x0 as i32, y0 as i32, (x0 + sw) as i32, (y0 + sh) as i32)
}

/// A random interior box with `I24F8` corners and non-zero fractions (the full 16 reads): corners
/// in `[1, n - 1)` texels, sides in `min_side..max_side` texels.
fn frac_box(rng: &mut TestRng, n: i64, min_side: i64, max_side: i64) -> Rect<I24F8> {
    let one = 1i64 << F;
    let frac = |rng: &mut TestRng| rng.random_range(1..one);
    let sw = rng.random_range(min_side..max_side) * one + frac(rng);
    let sh = rng.random_range(min_side..max_side) * one + frac(rng);
    let x0 = rng.random_range(1..n - 1 - max_side - 1) * one + frac(rng);
    let y0 = rng.random_range(1..n - 1 - max_side - 1) * one + frac(rng);
    let fx = |raw: i64| I24F8::from_bits(raw as i32);
    Rect::new(fx(x0), fx(y0), fx(x0 + sw), fx(y0 + sh))
}

/// A box that straddles the right edge (and, for half of them, the bottom edge) of a Repeat
/// texture, so no in-range equivalent exists and the split path answers (2 or 4 in-range
/// pieces, src/lookup/split.rs).
fn straddle_box(rng: &mut TestRng, n: i64, max_over: i64, fractional: bool) -> Rect<i64> {
    let one = if fractional { 1i64 << F } else { 1 };
    let frac = |rng: &mut TestRng| {
        if fractional {
            rng.random_range(1..one)
        } else {
            0
        }
    };
    let x0 = rng.random_range(n - max_over..n) * one + frac(rng);
    let x1 = rng.random_range(n + 1..n + max_over) * one + frac(rng);
    let (y0, y1) = if rng.next_u64() & 1 == 0 {
        (
            rng.random_range(n - max_over..n) * one + frac(rng),
            rng.random_range(n + 1..n + max_over) * one + frac(rng),
        )
    } else {
        let y0 = rng.random_range(1..n / 2) * one + frac(rng);
        (y0, y0 + rng.random_range(1..max_over) * one + frac(rng))
    };
    Rect::new(x0, y0, x1, y1)
}

fn bench_lookup(c: &mut Criterion) {
    let n = LOOKUP_SIDE;
    let tex = texels(n, 0xD1B5_4A32_D192_ED03);
    let texture = Texture::<u8>::new(&tex, n, n).expect("texture");
    let mut storage = vec![0u32; n * n];
    let sat = Sat::build(&texture, &mut storage).expect("build");
    let ni = n as i64;

    let mut rng = rng(0x2545_F491_4F6C_DD1D);
    let int_boxes: Vec<Rect<i32>> = (0..N_BOXES)
        .map(|_| int_box(&mut rng, ni, 1, 256))
        .collect();
    let frac_boxes: Vec<Rect<I24F8>> = (0..N_BOXES)
        .map(|_| frac_box(&mut rng, ni, 1, 256))
        .collect();
    // Large boxes for the shortcut: sides 64..256 texels, above the min side chosen below.
    let large_boxes: Vec<Rect<I24F8>> = (0..N_BOXES)
        .map(|_| frac_box(&mut rng, ni, 64, 256))
        .collect();
    let to_i32 = |r: Rect<i64>| Rect::new(r.x0 as i32, r.y0 as i32, r.x1 as i32, r.y1 as i32);
    let to_fix = |r: Rect<i64>| {
        let f = |v: i64| I24F8::from_bits(v as i32);
        Rect::new(f(r.x0), f(r.y0), f(r.x1), f(r.y1))
    };
    let rep_int: Vec<Rect<i32>> = (0..N_BOXES)
        .map(|_| to_i32(straddle_box(&mut rng, ni, 128, false)))
        .collect();
    let rep_frac: Vec<Rect<I24F8>> = (0..N_BOXES)
        .map(|_| to_fix(straddle_box(&mut rng, ni, 128, true)))
        .collect();

    // Sanity checks outside the timing: the boxes take the paths they are meant to.
    let mut t = Tally::new();
    for r in &int_boxes {
        sat.box_sum_int(r, Border, &mut t).expect("int box");
    }
    assert_eq!(t.reads, 4 * N_BOXES as u64, "int boxes are interior");
    let mut t = Tally::new();
    for r in &frac_boxes {
        sat.box_sum(r, Paper, Border, &mut t).expect("frac box");
    }
    assert_eq!(t.reads, 16 * N_BOXES as u64, "frac boxes are interior");
    // Shortcut for sides of at least 64 texels: error bound 255 * 2/63 ~ 8 texel units.
    let shortcut = Shortcut::with_min_side(64);
    for r in &large_boxes {
        let m = sat
            .box_mean_shortcut(r, Paper, Border, &shortcut, 8, &mut NoCount)
            .expect("shortcut");
        assert!(m.shortcut, "large boxes take the shortcut");
    }
    let mut t = Tally::new();
    for r in &rep_int {
        sat.box_sum_int(r, Repeat, &mut t).expect("repeat int");
    }
    // Split into 2 pieces (x only: (2 + 1) x 2 = 6 reads) or 4 ((2 + 1) x (2 + 1) = 9).
    assert!(
        t.reads > 4 * N_BOXES as u64,
        "repeat boxes take the split path"
    );
    let mut t = Tally::new();
    for r in &rep_frac {
        sat.box_sum(r, Paper, Repeat, &mut t).expect("repeat frac");
    }
    assert!(
        t.reads > 16 * N_BOXES as u64,
        "repeat boxes take the split path"
    );

    let (warm, measure) = times(500, 2000);
    let mut g = c.benchmark_group("lookup");
    g.warm_up_time(warm)
        .measurement_time(measure)
        .throughput(Throughput::Elements(N_BOXES as u64));

    macro_rules! bench_boxes {
        ($name:expr, $param:expr, $boxes:expr, $counter:expr, |$r:ident, $k:ident| $body:expr) => {
            g.bench_with_input(BenchmarkId::new($name, $param), $boxes, |b, boxes| {
                b.iter(|| {
                    let mut $k = $counter;
                    for $r in black_box(boxes).iter() {
                        black_box($body.expect("lookup"));
                    }
                    black_box($k)
                })
            });
        };
    }

    bench_boxes!("int4_border", "nocount", &int_boxes, NoCount, |r, k| {
        sat.box_sum_int(r, Border, &mut k)
    });
    bench_boxes!("int4_border", "tally", &int_boxes, Tally::new(), |r, k| {
        sat.box_sum_int(r, Border, &mut k)
    });
    bench_boxes!("paper16_border", "nocount", &frac_boxes, NoCount, |r, k| {
        sat.box_sum(r, Paper, Border, &mut k)
    });
    bench_boxes!(
        "paper16_border",
        "tally",
        &frac_boxes,
        Tally::new(),
        |r, k| { sat.box_sum(r, Paper, Border, &mut k) }
    );
    bench_boxes!(
        "stable16_border",
        "nocount",
        &frac_boxes,
        NoCount,
        |r, k| { sat.box_sum(r, Stable, Border, &mut k) }
    );
    bench_boxes!(
        "stable16_border",
        "tally",
        &frac_boxes,
        Tally::new(),
        |r, k| { sat.box_sum(r, Stable, Border, &mut k) }
    );
    // Means (one area multiply and one u64 divide on top of the sum, for this u32 table).
    bench_boxes!("int4_mean", "nocount", &int_boxes, NoCount, |r, k| {
        sat.box_sum_int(r, Border, &mut k)
            .and_then(|s| s.mean_rounded(0, 8, &mut k))
    });
    bench_boxes!("paper16_mean", "nocount", &frac_boxes, NoCount, |r, k| {
        sat.box_sum(r, Paper, Border, &mut k)
            .and_then(|s| s.mean_rounded(0, 8, &mut k))
    });
    // Crow's shortcut on large boxes, against the exact 16-read mean of the same boxes.
    bench_boxes!(
        "shortcut_mean_large",
        "nocount",
        &large_boxes,
        NoCount,
        |r, k| { sat.box_mean_shortcut(r, Paper, Border, &shortcut, 8, &mut k) }
    );
    bench_boxes!(
        "paper16_mean_large",
        "nocount",
        &large_boxes,
        NoCount,
        |r, k| {
            sat.box_sum(r, Paper, Border, &mut k)
                .and_then(|s| s.mean_rounded(0, 8, &mut k))
        }
    );
    // Repeat boxes straddling the edge: the split path (2 or 4 in-range pieces).
    bench_boxes!(
        "int_repeat_straddle",
        "nocount",
        &rep_int,
        NoCount,
        |r, k| { sat.box_sum_int(r, Repeat, &mut k) }
    );
    bench_boxes!(
        "paper_repeat_straddle",
        "nocount",
        &rep_frac,
        NoCount,
        |r, k| { sat.box_sum(r, Paper, Repeat, &mut k) }
    );
    bench_boxes!(
        "paper_repeat_straddle",
        "tally",
        &rep_frac,
        Tally::new(),
        |r, k| { sat.box_sum(r, Paper, Repeat, &mut k) }
    );
    // The same interior boxes as above under Repeat: the mode's placement cost alone.
    bench_boxes!(
        "int4_repeat_interior",
        "nocount",
        &int_boxes,
        NoCount,
        |r, k| { sat.box_sum_int(r, Repeat, &mut k) }
    );
    bench_boxes!(
        "paper16_repeat_interior",
        "nocount",
        &frac_boxes,
        NoCount,
        |r, k| { sat.box_sum(r, Paper, Repeat, &mut k) }
    );
    g.finish();
}

/// The in-range lookups again on a table small enough to stay in L1.
fn bench_lookup_l1(c: &mut Criterion) {
    let n = L1_SIDE;
    let tex = texels(n, 0x6A09_E667_F3BC_C908);
    let texture = Texture::<u8>::new(&tex, n, n).expect("texture");
    let mut storage = vec![0u32; n * n];
    let sat = Sat::build(&texture, &mut storage).expect("build");
    let ni = n as i64;
    let mut rng = rng(0xBB67_AE85_84CA_A73B);
    let int_boxes: Vec<Rect<i32>> = (0..N_BOXES).map(|_| int_box(&mut rng, ni, 1, 32)).collect();
    let frac_boxes: Vec<Rect<I24F8>> = (0..N_BOXES)
        .map(|_| frac_box(&mut rng, ni, 1, 32))
        .collect();
    let mut t = Tally::new();
    for r in &frac_boxes {
        sat.box_sum(r, Paper, Border, &mut t).expect("frac box");
    }
    assert_eq!(t.reads, 16 * N_BOXES as u64, "frac boxes are interior");

    let (warm, measure) = times(500, 2000);
    let mut g = c.benchmark_group("lookup_l1");
    g.warm_up_time(warm)
        .measurement_time(measure)
        .throughput(Throughput::Elements(N_BOXES as u64));
    g.bench_function("int4_border", |b| {
        b.iter(|| {
            for r in black_box(&int_boxes).iter() {
                black_box(sat.box_sum_int(r, Border, &mut NoCount).expect("lookup"));
            }
        })
    });
    g.bench_function("paper16_border", |b| {
        b.iter(|| {
            for r in black_box(&frac_boxes).iter() {
                black_box(sat.box_sum(r, Paper, Border, &mut NoCount).expect("lookup"));
            }
        })
    });
    g.bench_function("stable16_border", |b| {
        b.iter(|| {
            for r in black_box(&frac_boxes).iter() {
                black_box(
                    sat.box_sum(r, Stable, Border, &mut NoCount)
                        .expect("lookup"),
                );
            }
        })
    });
    g.finish();
}

fn config() -> Criterion {
    // Criterion's minimum; command-line flags (`--quick`, `--sample-size`, ...) still override.
    Criterion::default().sample_size(10)
}

criterion_group! {
    name = benches;
    config = config();
    targets = bench_build, bench_lookup, bench_lookup_l1
}
criterion_main!(benches);
