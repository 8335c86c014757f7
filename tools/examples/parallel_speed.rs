//! The all-cores build against one core (issue 13), and what bounds it: ns per texel of
//! `Sat::build`, `texsat_tools::parallel::build_parallel` (the strip build on rayon's pool) and
//! the same strips run on one thread (`strips_seq`), u8 texels into u32 entries; and two
//! single-threaded `Sat::build`s of two separate tables run at the same time on two threads
//! (`two_builds`, time per table), which shows how much of a second core the memory system
//! lets a build use at all.
//!
//! Run: `cargo run --release -p texsat-tools --features parallel,simd --example parallel_speed
//! [-- rounds]` (default 31). Rounds interleave the methods in a rotating order; each figure is
//! the median over rounds (and the fastest round), with the paired per-round ratio to `build`. Every method's table is
//! compared with `Sat::build`'s first. The machine's load is printed beside the figures.

use std::hint::black_box;
use std::time::Instant;

use texsat::{Sat, Texture};
use texsat_tools::parallel::build_parallel;

const METHODS: [&str; 4] = ["build", "parallel", "strips_seq", "two_builds"];

/// Deterministic texels, full 8-bit range.
fn texels(n: usize) -> Vec<u8> {
    texsat_host_tests::random_bytes(n, 0x2545_F491)
}

/// One timed run of `method`, in seconds per table.
fn run(method: &str, t: &Texture<'_, u8>, a: &mut [u32], b: &mut [u32]) -> f64 {
    let start = Instant::now();
    match method {
        "build" => {
            black_box(Sat::build(t, black_box(&mut *a)).expect("build"));
        }
        "parallel" => {
            black_box(build_parallel(t, black_box(&mut *a)).expect("parallel"));
        }
        "strips_seq" => {
            black_box(
                Sat::build_strips(t, black_box(&mut *a), 4, |jobs| {
                    jobs.iter_mut().for_each(|j| j.run())
                })
                .expect("strips"),
            );
        }
        "two_builds" => {
            std::thread::scope(|s| {
                s.spawn(|| black_box(Sat::build(t, black_box(&mut *b)).map(|_| ())));
                black_box(Sat::build(t, black_box(&mut *a)).expect("build"));
            });
            // Two tables built: the time per table.
            return start.elapsed().as_secs_f64() / 2.0;
        }
        _ => unreachable!("unknown method"),
    }
    start.elapsed().as_secs_f64()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|x, y| x.total_cmp(y));
    v[v.len() / 2]
}

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("rounds: a number"))
        .unwrap_or(31);
    let load = || std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "rayon threads: {}; loadavg before: {}",
        rayon::current_num_threads(),
        load().trim()
    );
    println!("| side | method | ns per texel (median) | fastest | / build (paired median) |");
    println!("|---|---|---:|---:|---:|");
    for side in [1024usize, 4096] {
        let n = side * side;
        let data = texels(n);
        let t = Texture::<u8>::new(&data, side, side).expect("texture");
        let (mut a, mut b) = (vec![0u32; n], vec![0u32; n]);
        let want = Sat::build(&t, &mut b).expect("build").entries().to_vec();
        for m in METHODS {
            run(m, &t, &mut a, &mut b);
            assert!(a == want, "{m}: a different table");
        }
        let mut times = vec![Vec::with_capacity(rounds); METHODS.len()];
        for r in 0..rounds {
            for k in 0..METHODS.len() {
                let i = (k + r) % METHODS.len();
                times[i].push(run(METHODS[i], &t, &mut a, &mut b));
            }
        }
        let base = times[0].clone();
        for (m, ts) in METHODS.iter().zip(&times) {
            let mut ratios: Vec<f64> = ts.iter().zip(&base).map(|(x, y)| x / y).collect();
            let mut ts = ts.clone();
            let per = 1e9 / n as f64;
            println!(
                "| {side}^2 | {m} | {:.3} | {:.3} | {:.2} |",
                median(&mut ts) * per,
                ts[0] * per,
                median(&mut ratios)
            );
        }
    }
    println!("loadavg after: {}", load().trim());
}
