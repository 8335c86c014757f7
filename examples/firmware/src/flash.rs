//! Flash per plan (feature `flash`, bin `texsat-flash`; run by `flash.sh`): a firmware that builds
//! one 64 x 64 table of 8-bit texels and samples boxes with exactly one configuration, chosen by
//! a cargo feature, beside a straightforward hand-written Rust version of the same behaviour
//! (`hand.rs`). `flash.sh` builds every variant and subtracts the flash (`.text` + `.rodata`) of
//! the `flash` feature alone, an empty `cortex-m-rt` firmware with the same harness, so each
//! figure is what the configuration adds.
//!
//! | feature | texsat | hand-written |
//! |---|---|---|
//! | `flash-int4` / `flash-int4-hand` | `Sat::build` (u32), `box_sum_int` under `ClampToEdge`, the plan's mean (`mean_rounded_u32`) | the same in `hand.rs` (a `u64` mean) |
//! | `flash-inside` / `flash-inside-hand` | `Sat::build` (u32), `Sat::box_sum_inside` | the same |
//! | `flash-stable-repeat` / `flash-stable-repeat-hand` | `Sat::build` (u32), `box_sum` Stable under the plan's mode (`RepeatWithinPeriod`: boxes crossing the edge included, up to the texture's size), the plan's mean (`mean_rounded_u32`) | the same for boxes inside one period |
//! | `flash-all` | every cargo feature: the Stable + Repeat plan, `box_sum_raw` with the form and mode at run time, and every filter's raw sampler | |
//!
//! Inputs and results go through `black_box`, so nothing is folded away; the panic handler is
//! the link gate's (an undefined symbol): every variant links only if panic-free.
#![no_std]
#![no_main]

use core::arch::asm;
use core::hint::black_box;

use cortex_m_rt::entry;

#[allow(dead_code)]
mod hand;

const W: usize = 64;
const H: usize = 64;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "C" {
        fn texsat_link_gate_a_panic_path_remains() -> !;
    }
    // SAFETY: never runs: a reachable handler makes the link fail (see main.rs).
    unsafe { texsat_link_gate_a_panic_path_remains() }
}

/// Semihosting SYS_EXIT: QEMU exits with 0 (the binary is only measured, not run, by flash.sh).
fn exit() -> ! {
    loop {
        // SAFETY: semihosting call; r0 = SYS_EXIT (0x18), r1 = ADP_Stopped_ApplicationExit.
        unsafe { asm!("bkpt 0xab", in("r0") 0x18u32, in("r1") 0x20026u32, options(nostack)) }
    }
}

static mut TEXELS: [u8; W * H] = [0; W * H];
static mut TABLE: [u32; W * H] = [0; W * H];

/// The plan of a 64 x 64 scene of 8-bit texels at `F = f` under `edge`, boxes up to the
/// texture's size that may leave it, 8 output bits of the mean: computed by the compiler.
#[allow(dead_code)]
const fn plan(f: u32, edge: texsat::EdgeKind) -> texsat::plan::Plan {
    let facts = texsat::plan::SceneFacts {
        max_box: [(W as u64) << f, (H as u64) << f],
        leaves_texture: true,
        ..texsat::plan::SceneFacts::new(W, H, 8, f, edge)
    };
    match texsat::plan::Plan::for_scene(&facts) {
        Ok(p) => p,
        Err(_) => panic!("no plan"),
    }
}

/// Box corners from the (opaque) loop counter: raw `F = 8` values.
fn corners(i: u32) -> [i32; 4] {
    let i = black_box(i) as i32;
    [i * 37, i * 11, i * 37 + 5000, i * 11 + 3000]
}

#[entry]
fn main() -> ! {
    // SAFETY: single-threaded, no interrupts: `main` is the only user of these statics.
    let (texels, table) = unsafe {
        (
            &mut *core::ptr::addr_of_mut!(TEXELS),
            &mut *core::ptr::addr_of_mut!(TABLE),
        )
    };
    let mut s = 0x1234_5678u32;
    for t in texels.iter_mut() {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        *t = (s >> 24) as u8;
    }
    let texels: &[u8] = black_box(&texels[..]);
    let (w, h) = (black_box(W), black_box(H));
    let _ = (&texels, &table, w, h);
    for i in 0..black_box(16u32) {
        let c = corners(i);
        let _ = black_box(c);
        #[cfg(feature = "flash-int4")]
        int4::run(texels, table, w, h, c);
        #[cfg(feature = "flash-int4-hand")]
        int4_hand::run(texels, table, w, h, c);
        #[cfg(feature = "flash-inside")]
        inside::run(texels, table, w, h, c);
        #[cfg(feature = "flash-inside-hand")]
        inside_hand::run(texels, table, w, h, c);
        #[cfg(any(feature = "flash-stable-repeat", feature = "flash-all"))]
        stable_repeat::run(texels, table, w, h, c);
        #[cfg(feature = "flash-stable-repeat-hand")]
        stable_repeat_hand::run(texels, table, w, h, c);
        #[cfg(feature = "flash-all")]
        all::run(texels, w, h, c);
    }
    exit()
}

#[cfg(feature = "flash-int4")]
mod int4 {
    use super::*;
    use texsat::{ClampToEdge, EdgeKind, NoCount, Rect, Sat, Texture};

    /// The smallest plan's scene: integer boxes up to the texture's size, leaving it, clamp.
    const PLAN: texsat::plan::Plan = super::plan(0, EdgeKind::Clamp);

    pub fn run(texels: &[u8], table: &mut [u32], w: usize, h: usize, c: [i32; 4]) {
        let Ok(t) = Texture::<u8>::new(texels, w, h) else {
            return;
        };
        let Ok(sat) = Sat::build(&t, table) else {
            return;
        };
        let r = Rect::new(c[0] >> 8, c[1] >> 8, c[2] >> 8, c[3] >> 8);
        if let Ok(sum) = sat.box_sum_int(&r, ClampToEdge, &mut NoCount) {
            // The plan's mean (a constant branch: one of the two is compiled).
            if PLAN.mean_fits_u32() {
                let _ = black_box(sum.mean_rounded_u32(0, 8, &mut NoCount));
            } else {
                let _ = black_box(sum.mean_rounded(0, 8, &mut NoCount));
            }
        }
    }
}

#[cfg(feature = "flash-int4-hand")]
mod int4_hand {
    use super::*;

    pub fn run(texels: &[u8], table: &mut [u32], w: usize, h: usize, c: [i32; 4]) {
        hand::build(texels, w, table);
        let t = hand::Table {
            t: table,
            w: w as u32,
            h: h as u32,
        };
        let (x0, y0, x1, y1) = (c[0] >> 8, c[1] >> 8, c[2] >> 8, c[3] >> 8);
        // Clamp-to-edge on integer corners: the box clipped, plus the edge texels repeated
        // outside; hand-written as the clipped sum plus the strips and corners outside, the
        // way `hand::Table::box_sum_int_clamp` does it.
        let sum = t.box_sum_int_clamp(x0, y0, x1, y1);
        let (bw, bh) = ((x1 - x0).max(0) as u64, (y1 - y0).max(0) as u64);
        let _ = black_box(hand::mean_rounded(sum, 8, bw, bh));
    }
}

#[cfg(feature = "flash-inside")]
mod inside {
    use super::*;
    use texsat::{Rect, Sat, Texture};

    pub fn run(texels: &[u8], table: &mut [u32], w: usize, h: usize, c: [i32; 4]) {
        let Ok(t) = Texture::<u8>::new(texels, w, h) else {
            return;
        };
        let Ok(sat) = Sat::build(&t, table) else {
            return;
        };
        let r = Rect::new(
            (c[0] >> 10) as u32,
            (c[1] >> 10) as u32,
            (c[2] >> 10) as u32,
            (c[3] >> 10) as u32,
        );
        let _ = black_box(sat.box_sum_inside(&r));
    }
}

#[cfg(feature = "flash-inside-hand")]
mod inside_hand {
    use super::*;

    pub fn run(texels: &[u8], table: &mut [u32], w: usize, h: usize, c: [i32; 4]) {
        hand::build(texels, w, table);
        let t = hand::Table {
            t: table,
            w: w as u32,
            h: h as u32,
        };
        let [x0, y0, x1, y1] = c.map(|v| (v >> 10) as u32);
        let _ = black_box(t.box_sum_inside(x0, y0, x1, y1));
    }
}

#[cfg(any(feature = "flash-stable-repeat", feature = "flash-all"))]
mod stable_repeat {
    use super::*;
    use texsat::{
        DefaultCoord as I24F8, EdgeKind, NoCount, Rect, Repeat, RepeatWithinPeriod, Sat, Stable,
        Texture,
    };

    /// The Stable + Repeat plan's scene: boxes at `F = 8` up to the texture's size, Repeat.
    const PLAN: texsat::plan::Plan = super::plan(8, EdgeKind::Repeat);

    pub fn run(texels: &[u8], table: &mut [u32], w: usize, h: usize, c: [i32; 4]) {
        let Ok(t) = Texture::<u8>::new(texels, w, h) else {
            return;
        };
        let Ok(sat) = Sat::build(&t, table) else {
            return;
        };
        let r = Rect::new(
            I24F8::from_bits(c[0]),
            I24F8::from_bits(c[1]),
            I24F8::from_bits(c[2]),
            I24F8::from_bits(c[3]),
        );
        // The plan's mode: its boxes are at most the texture, so Repeat within one period
        // (a constant branch, as for the mean: one of the two is compiled).
        let sum = if PLAN.repeat_within_period() {
            sat.box_sum(&r, Stable, RepeatWithinPeriod, &mut NoCount)
        } else {
            sat.box_sum(&r, Stable, Repeat, &mut NoCount)
        };
        if let Ok(sum) = sum {
            // The plan's mean (a constant branch: one of the two is compiled).
            if PLAN.mean_fits_u32() {
                let _ = black_box(sum.mean_rounded_u32(0, 8, &mut NoCount));
            } else {
                let _ = black_box(sum.mean_rounded(0, 8, &mut NoCount));
            }
        }
    }
}

#[cfg(feature = "flash-stable-repeat-hand")]
mod stable_repeat_hand {
    use super::*;

    pub fn run(texels: &[u8], table: &mut [u32], w: usize, h: usize, c: [i32; 4]) {
        hand::build(texels, w, table);
        let t = hand::Table {
            t: table,
            w: w as u32,
            h: h as u32,
        };
        let sum = t.box_sum_repeat_in_period(c[0], c[1], c[2], c[3]);
        let (bw, bh) = ((c[2] - c[0]) as u64, (c[3] - c[1]) as u64);
        let _ = black_box(hand::mean_rounded(sum, 8, bw, bh));
    }
}

#[cfg(feature = "flash-all")]
mod all {
    use super::*;
    use texsat::filters::dip::{DipFilter, DipMap};
    use texsat::filters::mip::MipPyramid;
    use texsat::filters::rip::RipMap;
    use texsat::filters::tent::TentTable;
    use texsat::filters::variance::VarianceTables;
    use texsat::{EdgeKind, FormKind, FracBits, NoCount, Rect, Sat, Texture};

    static mut PYRAMID: [u8; W * H] = [0; W * H];
    static mut RIP: [u8; 4 * W * H] = [0; 4 * W * H];
    static mut DIP: [u8; 3 * W * H] = [0; 3 * W * H];
    static mut TENT: [u32; (W + 1) * (H + 1)] = [0; (W + 1) * (H + 1)];
    static mut VALUES: [u32; W * H] = [0; W * H];
    static mut SQUARES: [u32; W * H] = [0; W * H];

    pub fn run(texels: &[u8], w: usize, h: usize, c: [i32; 4]) {
        let Ok(t) = Texture::<u8>::new(texels, w, h) else {
            return;
        };
        let r = Rect::new(
            i64::from(c[0]),
            i64::from(c[1]),
            i64::from(c[2]),
            i64::from(c[3]),
        );
        let (Ok(f), kind, form) = (
            FracBits::new(black_box(8)),
            black_box(EdgeKind::Repeat),
            black_box(FormKind::Stable),
        ) else {
            return;
        };
        // SAFETY: single-threaded; each static is borrowed once per call and released.
        let (pyr, rip, dip, tent, values, squares) = unsafe {
            (
                &mut *core::ptr::addr_of_mut!(PYRAMID),
                &mut *core::ptr::addr_of_mut!(RIP),
                &mut *core::ptr::addr_of_mut!(DIP),
                &mut *core::ptr::addr_of_mut!(TENT),
                &mut *core::ptr::addr_of_mut!(VALUES),
                &mut *core::ptr::addr_of_mut!(SQUARES),
            )
        };
        if let Ok(sat) = Sat::build(&t, &mut values[..]) {
            let _ = black_box(sat.box_sum_raw(&r, f, form, kind, &mut NoCount));
        }
        let _ = black_box(texsat::filters::point::point_raw(
            &t,
            &r,
            f,
            kind,
            &mut NoCount,
        ));
        if let Ok(p) = MipPyramid::build(&t, &mut pyr[..]) {
            let _ = black_box(p.trilinear_raw(&r, f, kind, &mut NoCount));
        }
        if let Ok(m) = RipMap::build(&t, &mut rip[..]) {
            let _ = black_box(m.sample_raw(&r, f, kind, &mut NoCount));
        }
        if let Ok(m) = DipMap::build(&t, &mut dip[..]) {
            let _ = black_box(m.sample_raw(&r, f, DipFilter::Bilinear, kind, &mut NoCount));
        }
        if let Ok(tt) = TentTable::<u32>::build(&t, &mut tent[..]) {
            let _ = black_box(tt.sample_raw(&r, f, kind, &mut NoCount));
        }
        if let Ok(v) = VarianceTables::<u32>::build(&t, &mut values[..], &mut squares[..]) {
            let _ = black_box(v.variance_raw(&r, f, form, kind, &mut NoCount));
        }
    }
}
