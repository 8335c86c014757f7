//! Bits per entry against reads per lookup for every layout: the table `OUT/layouts_table.md`
//! (copied into `docs/layouts.md`) and
//! the Pareto plot `docs/layouts_pareto.svg`.
//!
//! `cargo run --release --example layouts [-- --sizes 1024,2048,4096 --boxes 2000 --out docs]`
//!
//! Bits per entry are computed from the layout's actual storage (words x 32 / texels); reads are
//! counted with `Tally` over random boxes of a random 8-bit texture built into each layout
//! (integer corners: the 4-corner lookup; fractional corners at F = 8: the 16-corner Stable
//! lookup). A "read" is one table value fetched (a field, all channels); "words" are the 32-bit
//! memory words those reads touch.

use fixed::types::I24F8;
use plotters::prelude::*;
use std::fmt::Write as _;
use texsat::layouts::{modulus_bits_for, Modular, Tiled, TiledSpec};
use texsat::{Border, BoxLookup, NoCount, Rect, Sat, Stable, Tally, Texture};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

struct Row {
    name: String,
    exact: &'static str,
    bits: f64,
    reads_int: f64,
    reads_int_max: u64,
    words_int: f64,
    reads_frac: f64,
    adds_int: f64,
}

fn measure<L: BoxLookup<1>>(
    name: String,
    exact: &'static str,
    l: &L,
    flat: &Sat<'_, u32, 1>,
    boxes: usize,
    max_side: u64,
) -> Row {
    let (w, h) = (l.width() as u64, l.height() as u64);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let (mut ri, mut rmax, mut rf, mut ai, mut wi) = (0u64, 0u64, 0u64, 0u64, 0u64);
    for _ in 0..boxes {
        let bw = 1 + rng.below(max_side.min(w - 1));
        let bh = 1 + rng.below(max_side.min(h - 1));
        let x0 = 1 + rng.below(w - bw);
        let y0 = 1 + rng.below(h - bh);
        let r = Rect::new(x0 as i32, y0 as i32, (x0 + bw) as i32, (y0 + bh) as i32);
        let mut t = Tally::new();
        let s = l.box_sum_int(&r, Border, &mut t).expect("in-range box");
        assert_eq!(
            s.to_u128(),
            flat.box_sum_int(&r, Border, &mut NoCount)
                .unwrap()
                .to_u128()
        );
        ri += t.reads;
        wi += t.words;
        ai += t.adds;
        rmax = rmax.max(t.reads);
        let fr = Rect::new(
            I24F8::from_bits((x0 * 256 - 1 - rng.below(255)) as i32),
            I24F8::from_bits((y0 * 256 - 1 - rng.below(255)) as i32),
            I24F8::from_bits(((x0 + bw - 1) * 256 + 1 + rng.below(254)) as i32),
            I24F8::from_bits(((y0 + bh - 1) * 256 + 1 + rng.below(254)) as i32),
        );
        let mut t = Tally::new();
        let s = l
            .box_sum(&fr, Stable, Border, &mut t)
            .expect("in-range box");
        assert_eq!(
            s.to_u128(),
            flat.box_sum(&fr, Stable, Border, &mut NoCount)
                .unwrap()
                .to_u128()
        );
        rf += t.reads;
    }
    let n = boxes as f64;
    Row {
        name,
        exact,
        bits: l.bits_per_entry(),
        reads_int: ri as f64 / n,
        reads_int_max: rmax,
        words_int: wi as f64 / n,
        reads_frac: rf as f64 / n,
        adds_int: ai as f64 / n,
    }
}

fn arg(name: &str) -> Option<String> {
    let mut it = std::env::args();
    while let Some(a) = it.next() {
        if a == name {
            return it.next();
        }
    }
    None
}

fn main() {
    let sizes: Vec<usize> = arg("--sizes")
        .unwrap_or_else(|| "1024,2048,4096".into())
        .split(',')
        .map(|s| s.parse().expect("size"))
        .collect();
    let boxes: usize = arg("--boxes").map_or(2000, |s| s.parse().expect("boxes"));
    let out = arg("--out").unwrap_or_else(|| "target/layouts".into());
    std::fs::create_dir_all(&out).expect("output folder");
    let mut md = String::new();
    let mut plot_points: Vec<(usize, String, f64, f64, bool)> = Vec::new();
    for &n in &sizes {
        let mut rng = Rng(n as u64 * 7919);
        let texels: Vec<u8> = (0..n * n).map(|_| rng.next() as u8).collect();
        let tex = Texture::<u8>::new(&texels, n, n).unwrap();
        let mut flat_st = vec![0u32; n * n];
        let flat = Sat::build(&tex, &mut flat_st).unwrap();
        let mut rows = Vec::new();
        rows.push(measure(
            "flat u32".into(),
            "every box",
            &flat,
            &flat,
            boxes,
            n as u64,
        ));
        let specs: Vec<(String, TiledSpec)> = vec![
            ("flat, packed".into(), TiledSpec::FLAT_PACKED),
            ("tiles 16x16".into(), TiledSpec::tiles(16, 16).unwrap()),
            ("tiles 12x12".into(), TiledSpec::tiles(12, 12).unwrap()),
            ("tiles 8x8".into(), TiledSpec::tiles(8, 8).unwrap()),
            ("tiles 6x6".into(), TiledSpec::tiles(6, 6).unwrap()),
            ("tiles 4x4".into(), TiledSpec::tiles(4, 4).unwrap()),
            ("tiles 8 in 64".into(), TiledSpec::square(&[8, 64]).unwrap()),
            ("tiles 4 in 64".into(), TiledSpec::square(&[4, 64]).unwrap()),
            ("tiles 2 in 16".into(), TiledSpec::square(&[2, 16]).unwrap()),
            ("tiles 2 in 10".into(), TiledSpec::square(&[2, 10]).unwrap()),
            (
                "tiles 4 in 16 in 64".into(),
                TiledSpec::square(&[4, 16, 64]).unwrap(),
            ),
            (
                "tiles 2 in 4 in 16".into(),
                TiledSpec::square(&[2, 4, 16]).unwrap(),
            ),
        ];
        for (name, spec) in specs {
            let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, n, n, 8).unwrap()];
            let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, n).unwrap()];
            let t = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).unwrap();
            rows.push(measure(name, "every box", &t, &flat, boxes, n as u64));
        }
        // Bounded layouts: exact for boxes covering at most 16 x 16 texel cells, so the random
        // boxes have sides up to 15 (a fractional box of side 15 covers up to 16 cells).
        let k16 = modulus_bits_for(8, 16 * 16);
        for (name, spec) in [
            (
                "tiles 4x4, mod 2^16",
                TiledSpec::tiles(4, 4).unwrap().with_modulus(k16),
            ),
            (
                "tiles 4 in 16, mod 2^16",
                TiledSpec::square(&[4, 16]).unwrap().with_modulus(k16),
            ),
        ] {
            let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, n, n, 8).unwrap()];
            let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, n).unwrap()];
            let t = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).unwrap();
            rows.push(measure(
                name.into(),
                "boxes <= 16 x 16 cells",
                &t,
                &flat,
                boxes,
                15,
            ));
        }
        for side in [16u64, 64] {
            let k = modulus_bits_for(8, side * side);
            let mut words = vec![0u32; Modular::<u32>::words_needed(n, n, k).unwrap()];
            let mut row = vec![0u32; n];
            let m = Modular::<u32>::build(&tex, k, &mut words, &mut row).unwrap();
            let exact = if side == 16 {
                "boxes <= 16 x 16 cells"
            } else {
                "boxes <= 64 x 64 cells"
            };
            rows.push(measure(
                format!("modular k={k}"),
                exact,
                &m,
                &flat,
                boxes,
                side - 1,
            ));
        }
        let _ = writeln!(md, "\n### {n} x {n}, 8-bit texels\n");
        let _ = writeln!(
            md,
            "| layout | bits per entry | memory vs texture | reads per 4-corner box (mean / max) | 32-bit words per 4-corner box | adds per 4-corner box | reads per 16-corner box | exact for |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
        for r in &rows {
            let _ = writeln!(
                md,
                "| {} | {:.3} | {:.2} | {:.2} / {} | {:.2} | {:.2} | {:.2} | {} |",
                r.name,
                r.bits,
                r.bits / 8.0,
                r.reads_int,
                r.reads_int_max,
                r.words_int,
                r.adds_int,
                r.reads_frac,
                r.exact
            );
            plot_points.push((
                n,
                r.name.clone(),
                r.bits,
                r.reads_int,
                r.exact == "every box",
            ));
        }
        eprintln!("{n} x {n} done");
    }
    std::fs::write(format!("{out}/layouts_table.md"), &md).expect("write table");
    print!("{md}");
    plot(&format!("{out}/layouts_pareto.svg"), &plot_points, &sizes);
}

/// Bits per entry (x) against mean reads per 4-corner box (y), one colour per size: circles for
/// layouts exact for every box (with each size's Pareto front), triangles for layouts exact only
/// for bounded boxes (modular).
fn plot(path: &str, pts: &[(usize, String, f64, f64, bool)], sizes: &[usize]) {
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).unwrap();
    let ymax = pts.iter().map(|p| p.3).fold(0.0, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Exact layouts: bits per entry vs reads per box",
            ("sans-serif", 22),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0f64..34.0, 0.0f64..ymax)
        .unwrap();
    chart
        .configure_mesh()
        .x_desc("bits per entry (8-bit texels)")
        .y_desc("reads per integer-corner box (mean)")
        .draw()
        .unwrap();
    let colors = [RED, BLUE, GREEN];
    for (si, &n) in sizes.iter().enumerate() {
        let c = colors[si % colors.len()];
        let mine: Vec<_> = pts.iter().filter(|p| p.0 == n).collect();
        chart
            .draw_series(
                mine.iter()
                    .filter(|p| p.4)
                    .map(|p| Circle::new((p.2, p.3), 4, c.filled())),
            )
            .unwrap()
            .label(format!(
                "{n} x {n} (exact for every box; line: Pareto front)"
            ))
            .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
        chart
            .draw_series(
                mine.iter()
                    .filter(|p| !p.4)
                    .map(|p| TriangleMarker::new((p.2, p.3), 6, c.filled())),
            )
            .unwrap()
            .label(format!("{n} x {n} (exact for bounded boxes)"))
            .legend(move |(x, y)| TriangleMarker::new((x, y), 6, c.filled()));
        // Pareto front of the layouts exact for every box: sorted by bits, keep points with fewer
        // reads than every point with fewer bits.
        let mut sorted: Vec<(f64, f64)> = mine.iter().filter(|p| p.4).map(|p| (p.2, p.3)).collect();
        sorted.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
        let mut front = Vec::new();
        let mut best = f64::INFINITY;
        for &(b, r) in &sorted {
            if r < best {
                front.push((b, r));
                best = r;
            }
        }
        chart.draw_series(LineSeries::new(front, c)).unwrap();
        if si == sizes.len() / 2 {
            for p in &mine {
                chart
                    .draw_series(std::iter::once(Text::new(
                        p.1.clone(),
                        (p.2 + 0.3, p.3),
                        ("sans-serif", 11),
                    )))
                    .unwrap();
            }
        }
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .unwrap();
    root.present().unwrap();
}
