//! Ratios against hand-written baselines, measured in one run (issue "firmware-grade core").
//!
//! Each texsat lookup is timed beside a straightforward hand-written Rust version of the same
//! behaviour (kept here, below), over the same precomputed boxes, interleaved rounds, medians.
//! Run: `cargo bench -p texsat-host-tests --bench ratios` (add `-- --quick` for a smoke run).
//! The targets are the issue's: 4-read within 1.2x of hand-written, 16-read Stable within 1.3x,
//! trilinear within 1.5x of a lean hand-written trilinear, a Repeat box crossing the edge within
//! 3x of an interior box, a tiled lookup within 1.5x of the flat one per table value read, a
//! modular one within 1.3x of the flat one.

use fixed::types::I24F8;
use std::hint::black_box;
use std::time::Instant;
use texsat::filters::mip::MipPyramid;
use texsat::layouts::{modulus_bits_for, Modular, Tiled, TiledSpec};
use texsat::{Border, BoxLookup, ClampToEdge, NoCount, Rect, Repeat, Sat, Stable, Tally, Texture};
use texsat_host_tests::{rng, RngExt};

const F: u32 = 8;

// ---------------------------------------------------------------------------------------------
// Hand-written baselines: what a firmware engineer writes for one fixed configuration.

/// 4-read box sum, Border: clip, then `S(x1,y1) - S(x1,y0) - (S(x0,y1) - S(x0,y0))`.
/// (`#[inline]` like texsat's lookups: both are inlined into the measuring loop.)
#[inline]
fn hand_int4(t: &[u32], w: usize, h: usize, r: [i32; 4]) -> u64 {
    let cl = |v: i32, n: usize| v.clamp(0, n as i32) as usize;
    let (x0, x1, y0, y1) = (cl(r[0], w), cl(r[2], w), cl(r[1], h), cl(r[3], h));
    let s = |x: usize, y: usize| -> u64 {
        if x == 0 || y == 0 {
            0
        } else {
            t[(y - 1) * w + x - 1] as u64
        }
    };
    (s(x1, y1) - s(x1, y0)) - (s(x0, y1) - s(x0, y0))
}

/// 16-read box sum at `F` fractional bits, Border, scaled by `2^2F`: bilinear interpolation of
/// the table at each corner (exact: S is bilinear in each cell), in `i64`, 4 reads per corner.
#[inline]
fn hand_16(t: &[u32], w: usize, h: usize, r: [i64; 4]) -> i64 {
    let one = 1i64 << F;
    let cl = |v: i64, n: usize| v.clamp(0, (n as i64) << F);
    let s = |x: usize, y: usize| -> i64 {
        if x == 0 || y == 0 {
            0
        } else {
            t[(y - 1) * w + x - 1] as i64
        }
    };
    let v = |x: i64, y: i64| -> i64 {
        let (mut i, mut a) = ((x >> F) as usize, x & (one - 1));
        if i == w {
            i = w - 1;
            a = one;
        }
        let (mut j, mut b) = ((y >> F) as usize, y & (one - 1));
        if j == h {
            j = h - 1;
            b = one;
        }
        let (s00, s10, s01, s11) = (s(i, j), s(i + 1, j), s(i, j + 1), s(i + 1, j + 1));
        let r0 = s00 * one + (s10 - s00) * a;
        let r1 = s01 * one + (s11 - s01) * a;
        r0 * one + (r1 - r0) * b
    };
    let (x0, x1, y0, y1) = (cl(r[0], w), cl(r[2], w), cl(r[1], h), cl(r[3], h));
    (v(x1, y1) - v(x1, y0)) - (v(x0, y1) - v(x0, y0))
}

/// A lean mip pyramid: 2x2 box-filtered levels of `u8`, each its own `Vec`.
struct HandMip {
    levels: Vec<(usize, usize, Vec<u8>)>,
}

impl HandMip {
    fn build(t: &[u8], w: usize, h: usize) -> Self {
        let mut levels = vec![(w, h, t.to_vec())];
        while let Some((lw, lh, prev)) = levels.last().filter(|(lw, lh, _)| *lw > 1 || *lh > 1) {
            let (nw, nh) = ((lw / 2).max(1), (lh / 2).max(1));
            let mut next = vec![0u8; nw * nh];
            for y in 0..nh {
                for x in 0..nw {
                    let p = |dx: usize, dy: usize| {
                        prev[(2 * y + dy).min(lh - 1) * lw + (2 * x + dx).min(lw - 1)] as u32
                    };
                    next[y * nw + x] = ((p(0, 0) + p(1, 0) + p(0, 1) + p(1, 1) + 2) / 4) as u8;
                }
            }
            levels.push((nw, nh, next));
        }
        HandMip { levels }
    }

    /// Bilinear at level `l`, clamp to edge, centre `(cx, cy)` in base texels times 256;
    /// result times 2^16.
    fn bilinear(&self, l: usize, cx: i64, cy: i64) -> i64 {
        let (w, h, ref t) = self.levels[l];
        // Texel centres at (i + 1/2) 2^l: position in level texels, 8 fraction bits.
        let px = (cx >> l) - 128;
        let py = (cy >> l) - 128;
        let (i, a) = (px >> 8, px & 255);
        let (j, b) = (py >> 8, py & 255);
        let at = |x: i64, y: i64| {
            t[(y.clamp(0, h as i64 - 1) as usize) * w + x.clamp(0, w as i64 - 1) as usize] as i64
        };
        let r0 = at(i, j) * (256 - a) + at(i + 1, j) * a;
        let r1 = at(i, j + 1) * (256 - a) + at(i + 1, j + 1) * a;
        r0 * (256 - b) + r1 * b
    }

    /// Trilinear at the footprint `[x0, x1) x [y0, y1)` (raw, F = 8): level from the larger
    /// side, 8 fraction bits of LOD.
    #[inline]
    fn trilinear(&self, r: [i64; 4]) -> i64 {
        let side = (r[2] - r[0]).max(r[3] - r[1]).max(1) as f32 / 256.0;
        let lod = side.log2().max(0.0);
        let top = self.levels.len() - 1;
        let l0 = (lod as usize).min(top);
        let l1 = (l0 + 1).min(top);
        let t = ((lod - l0 as f32) * 256.0) as i64;
        let (cx, cy) = ((r[0] + r[2]) / 2, (r[1] + r[3]) / 2);
        let v0 = self.bilinear(l0, cx, cy);
        let v1 = self.bilinear(l1, cx, cy);
        v0 * (256 - t) + v1 * t
    }
}

// ---------------------------------------------------------------------------------------------

/// Median ns per call of each closure over `rounds` interleaved rounds of `n` calls.
fn time_pair(
    rounds: usize,
    mut a: impl FnMut() -> u64,
    mut b: impl FnMut() -> u64,
    n: usize,
) -> (f64, f64) {
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    for _ in 0..rounds {
        let s = Instant::now();
        black_box(a());
        ta.push(s.elapsed().as_secs_f64() * 1e9 / n as f64);
        let s = Instant::now();
        black_box(b());
        tb.push(s.elapsed().as_secs_f64() * 1e9 / n as f64);
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(|x, y| x.partial_cmp(y).unwrap());
        v[v.len() / 2]
    };
    (med(&mut ta), med(&mut tb))
}

fn main() {
    // RATIOS_N=256 gives a table that fits the L2 cache (compute-bound ratios); the default,
    // 1024, is the memory-bound case.
    let n_side: usize = std::env::var("RATIOS_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1024);
    let quick = std::env::args().any(|a| a == "--quick");
    let (rounds, nbox) = if quick { (3, 2_000) } else { (31, 50_000) };
    let mut rng = rng(0x007E_55A7);
    let tex: Vec<u8> = (0..n_side * n_side).map(|_| rng.random::<u8>()).collect();
    let texture = Texture::<u8>::new(&tex, n_side, n_side).unwrap();
    let mut st = vec![0u32; n_side * n_side];
    let sat = Sat::build(&texture, &mut st).unwrap();
    let table = sat.entries();

    let int_boxes: Vec<[i32; 4]> = (0..nbox)
        .map(|_| {
            let (sw, sh) = (rng.random_range(1..65), rng.random_range(1..65));
            let (x, y) = (
                rng.random_range(0..n_side as i64 - sw),
                rng.random_range(0..n_side as i64 - sh),
            );
            [x as i32, y as i32, (x + sw) as i32, (y + sh) as i32]
        })
        .collect();
    let frac_boxes: Vec<[i64; 4]> = (0..nbox)
        .map(|_| {
            let (sw, sh) = (
                rng.random_range(256..64 << 8),
                rng.random_range(256..64 << 8),
            );
            let (x, y) = (
                rng.random_range(0..(n_side as i64 - 65) << 8),
                rng.random_range(0..(n_side as i64 - 65) << 8),
            );
            [x, y, x + sw, y + sh]
        })
        .collect();
    // Crossing the right edge (and, for a quarter of them, the bottom edge too) under Repeat.
    let cross_boxes: Vec<[i64; 4]> = frac_boxes
        .iter()
        .enumerate()
        .map(|(n, b)| {
            let (sw, sh) = (b[2] - b[0], b[3] - b[1]);
            let x = ((n_side as i64) << 8) - sw / 2;
            let y = if n % 4 == 0 {
                ((n_side as i64) << 8) - sh / 2
            } else {
                b[1]
            };
            [x, y, x + sw, y + sh]
        })
        .collect();
    let rect = |b: &[i64; 4]| {
        Rect::new(
            I24F8::from_bits(b[0] as i32),
            I24F8::from_bits(b[1] as i32),
            I24F8::from_bits(b[2] as i32),
            I24F8::from_bits(b[3] as i32),
        )
    };
    let frects: Vec<Rect<I24F8>> = frac_boxes.iter().map(rect).collect();
    let crects: Vec<Rect<I24F8>> = cross_boxes.iter().map(rect).collect();

    // Correctness first: the baselines agree with texsat.
    for (b, r) in frac_boxes.iter().zip(&frects).take(1000) {
        let s: u64 = sat.box_sum(r, Stable, Border, &mut NoCount).unwrap().sum();
        assert_eq!(s as i64, hand_16(table, n_side, n_side, *b));
    }
    for b in int_boxes.iter().take(1000) {
        let r = Rect::new(b[0], b[1], b[2], b[3]);
        assert_eq!(
            sat.box_sum_int(&r, Border, &mut NoCount).unwrap().sum(),
            hand_int4(table, n_side, n_side, *b)
        );
    }

    let mut rows: Vec<(String, f64, f64, f64, String)> = Vec::new();
    let n = nbox;

    // 1. 4-read.
    let (ts, th) = time_pair(
        rounds,
        || {
            int_boxes
                .iter()
                .map(|b| {
                    sat.box_sum_int(&Rect::new(b[0], b[1], b[2], b[3]), Border, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        || {
            int_boxes
                .iter()
                .map(|b| hand_int4(table, n_side, n_side, *b))
                .fold(0, u64::wrapping_add)
        },
        n,
    );
    rows.push((
        "4-read box sum, Border (u32 table)".into(),
        ts,
        th,
        ts / th,
        "<= 1.2".into(),
    ));

    // 2. 16-read Stable (and Paper) vs hand-written 16-read.
    let (ts, th) = time_pair(
        rounds,
        || {
            frects
                .iter()
                .map(|r| {
                    sat.box_sum(r, Stable, Border, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        || {
            frac_boxes
                .iter()
                .map(|b| hand_16(table, n_side, n_side, *b) as u64)
                .fold(0, u64::wrapping_add)
        },
        n,
    );
    rows.push((
        "16-read Stable, Border, F = 8".into(),
        ts,
        th,
        ts / th,
        "<= 1.3".into(),
    ));
    let (tp, th2) = time_pair(
        rounds,
        || {
            frects
                .iter()
                .map(|r| {
                    sat.box_sum(r, texsat::Paper, Border, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        || {
            frac_boxes
                .iter()
                .map(|b| hand_16(table, n_side, n_side, *b) as u64)
                .fold(0, u64::wrapping_add)
        },
        n,
    );
    rows.push((
        "16-read Paper, Border, F = 8".into(),
        tp,
        th2,
        tp / th2,
        "".into(),
    ));

    // 3. Trilinear.
    let mut mip_st = vec![0u8; MipPyramid::<u8>::storage_needed(n_side, n_side).unwrap()];
    let mip = MipPyramid::<u8>::build(&texture, &mut mip_st).unwrap();
    let hmip = HandMip::build(&tex, n_side, n_side);
    let (ts, th) = time_pair(
        rounds,
        || {
            frects
                .iter()
                .map(|r| {
                    mip.trilinear(r, ClampToEdge, &mut NoCount)
                        .map_or(0, |s| s.values[0])
                })
                .fold(0, u64::wrapping_add)
        },
        || {
            frac_boxes
                .iter()
                .map(|b| hmip.trilinear(*b) as u64)
                .fold(0, u64::wrapping_add)
        },
        n,
    );
    rows.push((
        "trilinear mip sample, clamp".into(),
        ts,
        th,
        ts / th,
        "<= 1.5".into(),
    ));

    // 4. Repeat crossing vs interior.
    let (tc, ti) = time_pair(
        rounds,
        || {
            crects
                .iter()
                .map(|r| {
                    sat.box_sum(r, Stable, Repeat, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        || {
            frects
                .iter()
                .map(|r| {
                    sat.box_sum(r, Stable, Repeat, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        n,
    );
    rows.push((
        "Repeat, box crossing the edge vs interior (Stable)".into(),
        tc,
        ti,
        tc / ti,
        "<= 3".into(),
    ));

    // 5. Tiled (8 x 8 tiles) vs flat, per table value read.
    let spec = TiledSpec::tiles(8, 8).unwrap();
    let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, n_side, n_side, 8).unwrap()];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, n_side).unwrap()];
    let tiled = Tiled::<u32>::build(&texture, spec, &mut words, &mut scratch).unwrap();
    let reads = |l: &dyn Fn(&Rect<I24F8>, &mut Tally)| {
        let mut k = Tally::new();
        for r in frects.iter().take(2000) {
            l(r, &mut k);
        }
        k.reads as f64 / 2000.0
    };
    let rf = reads(&|r, k| {
        let _ = sat.box_sum(r, Stable, Border, k);
    });
    let rt = reads(&|r, k| {
        let _ = tiled.box_sum(r, Stable, Border, k);
    });
    let (tt, tf) = time_pair(
        rounds,
        || {
            frects
                .iter()
                .map(|r| {
                    tiled
                        .box_sum(r, Stable, Border, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        || {
            frects
                .iter()
                .map(|r| {
                    sat.box_sum(r, Stable, Border, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        n,
    );
    rows.push((
        format!("tiled 8x8 vs flat, per value read ({rt:.1} vs {rf:.1} reads)"),
        tt / rt,
        tf / rf,
        (tt / rt) / (tf / rf),
        "<= 1.5".into(),
    ));

    // 6. Modular (k for boxes up to 65 x 65 cells) vs flat.
    let k = modulus_bits_for(8, 65 * 65);
    let mut mwords = vec![0u32; Modular::<u32>::words_needed(n_side, n_side, k).unwrap()];
    let mut mrow = vec![0u32; n_side];
    let modular = Modular::<u32>::build(&texture, k, &mut mwords, &mut mrow).unwrap();
    let (tm, tf) = time_pair(
        rounds,
        || {
            frects
                .iter()
                .map(|r| {
                    modular
                        .box_sum(r, Stable, Border, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        || {
            frects
                .iter()
                .map(|r| {
                    sat.box_sum(r, Stable, Border, &mut NoCount)
                        .map_or(0, |s| s.sum())
                })
                .fold(0, u64::wrapping_add)
        },
        n,
    );
    rows.push((
        format!("modular k = {k} vs flat (Stable)"),
        tm,
        tf,
        tm / tf,
        "<= 1.3".into(),
    ));

    println!("| lookup ({n_side}^2, u8 texels, u32 table; {nbox} boxes, {rounds} rounds, medians) | texsat ns | baseline ns | ratio | target |");
    println!("|---|---|---|---|---|");
    for (name, a, b, r, t) in rows {
        println!("| {name} | {a:.2} | {b:.2} | {r:.2} | {t} |");
    }
}
