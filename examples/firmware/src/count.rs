//! Instruction counter harness (feature `count`, bin `texsat-count`; run by `count-insns.sh`).
//!
//! Calls each measured texsat entry point from its own `#[inline(never)] fn m_<name>`, first
//! `REPS` times and then `2 REPS` times through one out-of-line loop ([`run`]: the same code for
//! both), with `texsat_count_mark` called just before and after each loop. Under QEMU, the TCG plugin
//! `plugin/insn_count.c` counts every executed instruction and prints the running count each
//! time the mark's first instruction runs (fallback: `-singlestep -d exec,nochain`, one logged TB
//! per executed instruction), so the instructions executed between two marks are known exactly;
//! a self-check in assembly comes first (`texsat_count_selftest`). `count-insns.sh` takes
//! `(count(2 REPS) - count(REPS)) / REPS`: the two regions run the same code and differ by
//! exactly `REPS` calls, so the setup cancels and the figure is an integer. It subtracts the
//! same figure for `m_baseline` (an empty wrapper of the same shape: loop, call, return,
//! `black_box`). Then it exits QEMU through semihosting `SYS_EXIT`.
//!
//! Same types as the link gate: 8-bit texels, `u32` entries, one channel, `I24F8` corners,
//! `NoCount`; a 64 x 64 pseudo-random texture. Same panic handler as the gate too: this binary
//! links only if no panic path remains.
#![no_std]
#![no_main]

use core::arch::asm;
use core::hint::black_box;

use cortex_m_rt::entry;

// The clamp lookup is measured for flash only (flash.rs).
#[allow(dead_code)]
mod hand;
use texsat::layouts::{Modular, Tiled, TiledSpec};
use texsat::texel::Entry;
use texsat::{
    Border, BoxSum, DefaultCoord, NoCount, Rect, Repeat, RepeatWithinPeriod, RowStreamBuilder, Sat,
    Stable, Texture,
};

type Tx = u8;
type En = u32;
type Co = DefaultCoord;

const W: usize = 64;
const H: usize = 64;
/// Calls in the first measured region (the second has twice as many): see the module docs.
const REPS: u32 = 10;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "C" {
        fn texsat_link_gate_a_panic_path_remains() -> !;
    }
    // SAFETY: never runs: a reachable handler makes the link fail (see main.rs).
    unsafe { texsat_link_gate_a_panic_path_remains() }
}

/// The marker between measured regions (its address is found with `llvm-nm`).
#[no_mangle]
#[inline(never)]
pub extern "C" fn texsat_count_mark() {
    // SAFETY: a `nop`, no effect beyond keeping this function distinct.
    unsafe { asm!("nop", options(nomem, nostack, preserves_flags)) }
}

/// Semihosting SYS_EXIT (ADP_Stopped_ApplicationExit): QEMU (`-semihosting`) exits with 0.
fn exit() -> ! {
    loop {
        // SAFETY: semihosting call; r0 = SYS_EXIT (0x18), r1 = ADP_Stopped_ApplicationExit.
        unsafe { asm!("bkpt 0xab", in("r0") 0x18u32, in("r1") 0x20026u32, options(nostack)) }
    }
}

// The counting method's self-check (count_insns.py, entry `selftest`): a mark, 7 `nop`s, a
// mark, 29 `nop`s, a mark, in assembly, so the instructions executed between the marks are
// known from the disassembly alone (the rest of `texsat_count_mark` after its first
// instruction, the `nop`s, the next `bl`); count_insns.py fails unless the count agrees.
core::arch::global_asm!(
    ".section .text.texsat_count_selftest,\"ax\",%progbits",
    ".syntax unified",
    ".thumb",
    ".global texsat_count_selftest",
    ".type texsat_count_selftest, %function",
    ".thumb_func",
    "texsat_count_selftest:",
    "push {{r4, lr}}",
    "bl texsat_count_mark",
    ".rept 7",
    "nop",
    ".endr",
    "bl texsat_count_mark",
    ".rept 29",
    "nop",
    ".endr",
    "bl texsat_count_mark",
    "pop {{r4, pc}}",
    ".size texsat_count_selftest, . - texsat_count_selftest",
);

extern "C" {
    fn texsat_count_selftest();
}

#[inline(always)]
fn keep<T>(v: T) {
    let _ = black_box(v);
}

fn rect_fix(x0: i32, y0: i32, x1: i32, y1: i32) -> Rect<Co> {
    black_box(Rect::new(
        Co::from_bits(black_box(x0)),
        Co::from_bits(black_box(y0)),
        Co::from_bits(black_box(x1)),
        Co::from_bits(black_box(y1)),
    ))
}

/// A mark, `f` called `n` times (`n` through `black_box`), a mark. Out of line, one copy per
/// measured call: the two measured regions of [`measure!`] are this same code between its two
/// marks, so they differ by exactly the calls.
#[inline(never)]
fn run<F: FnMut()>(n: u32, f: &mut F) {
    texsat_count_mark();
    for _ in 0..black_box(n) {
        f();
    }
    texsat_count_mark();
}

/// Four regions: whatever ran since the last mark (setup, ignored), the call `REPS` times, the
/// return and the next call of [`run`] (ignored), the call `2 REPS` times.
macro_rules! measure {
    ($call:expr) => {{
        let mut f = || keep($call);
        run(REPS, &mut f);
        run(2 * REPS, &mut f);
    }};
}

// --- the measured wrappers -------------------------------------------------------------------

#[inline(never)]
fn m_baseline(sat: &Sat<'_, En>, r: &Rect<Co>) {
    keep((sat, r));
}

#[inline(never)]
fn m_box_sum_int_border(sat: &Sat<'_, En>, r: &Rect<i32>) {
    keep(
        sat.box_sum_int(r, Border, &mut NoCount)
            .map_or(0, |s| s.sum()),
    );
}

#[inline(never)]
fn m_box_sum_inside(sat: &Sat<'_, En>, r: &Rect<u32>) {
    keep(sat.box_sum_inside(r).map_or(0, |s| s[0]));
}

#[inline(never)]
fn h_box_sum_inside(t: &hand::Table<'_>, r: &Rect<u32>) {
    keep(t.box_sum_inside(r.x0, r.y0, r.x1, r.y1));
}

#[inline(never)]
fn m_box_sum_stable_border(sat: &Sat<'_, En>, r: &Rect<Co>) {
    keep(sat.box_sum(r, Stable, Border, &mut NoCount));
}

#[inline(never)]
fn m_box_sum_stable_repeat(sat: &Sat<'_, En>, r: &Rect<Co>) {
    keep(sat.box_sum(r, Stable, Repeat, &mut NoCount));
}

/// Repeat for a plan whose boxes are at most the texture (`Plan::repeat_within_period`).
#[inline(never)]
fn m_box_sum_stable_repeat_within(sat: &Sat<'_, En>, r: &Rect<Co>) {
    keep(sat.box_sum(r, Stable, RepeatWithinPeriod, &mut NoCount));
}

#[inline(never)]
fn m_mean_rounded(sum: &BoxSum<u64, 1>) {
    keep(sum.mean_rounded(black_box(0), black_box(8), &mut NoCount));
}

#[inline(never)]
fn m_mean_rounded_u32(sum: &BoxSum<u64, 1>) {
    keep(sum.mean_rounded_u32(black_box(0), black_box(8), &mut NoCount));
}

#[inline(never)]
fn m_box_sum_stable_border_mean(sat: &Sat<'_, En>, r: &Rect<Co>) {
    if let Ok(s) = sat.box_sum(r, Stable, Border, &mut NoCount) {
        keep(s.mean_rounded(black_box(0), black_box(8), &mut NoCount));
    }
}

#[inline(never)]
fn m_sat_build(t: &Texture<'_, Tx>, storage: &mut [En]) {
    keep(Sat::build(t, storage));
}

/// The `u16` table measured: `SMALL_W` x `SMALL_H` texels (at most 255 x 256 = 65,280, so the
/// width proof holds for `u16`), rows as wide as the other builds' (the row scan declines `u16`
/// rows under 16 entries, where it does not pay: texsat's src/dsp.rs). count_insns.py divides
/// row 6e by 256 and labels it 64x4: change them together.
const SMALL_W: usize = 64;
const SMALL_H: usize = 4;
/// Its entries.
const SMALL: usize = SMALL_W * SMALL_H;

#[inline(never)]
fn m_sat_build_u16(t: &Texture<'_, Tx>, storage: &mut [u16]) {
    keep(Sat::build(t, storage));
}

#[inline(never)]
fn h_build_u16(texels: &[Tx], storage: &mut [u16]) {
    hand::build(texels, black_box(SMALL_W), storage);
    keep(&*storage);
}

#[inline(never)]
fn m_tiled_box_sum_int_border(l: &Tiled<'_, En>, r: &Rect<i32>) {
    keep(texsat::BoxLookup::box_sum_int(l, r, Border, &mut NoCount));
}

#[inline(never)]
fn m_tiled_box_sum_stable_border(l: &Tiled<'_, En>, r: &Rect<Co>) {
    keep(texsat::BoxLookup::box_sum(
        l,
        r,
        Stable,
        Border,
        &mut NoCount,
    ));
}

#[cfg(feature = "filter-mip")]
#[inline(never)]
fn m_mip_trilinear(p: &texsat::filters::mip::MipPyramid<'_, Tx>, r: &Rect<Co>) {
    keep(p.trilinear(r, Border, &mut NoCount));
}

#[cfg(feature = "filter-mip")]
#[inline(never)]
fn m_mip_trilinear_repeat(p: &texsat::filters::mip::MipPyramid<'_, Tx>, r: &Rect<Co>) {
    keep(p.trilinear(r, Repeat, &mut NoCount));
}

#[inline(never)]
fn h_box_sum_int_border(t: &hand::Table<'_>, r: &Rect<i32>) {
    keep(t.box_sum_int_border(r.x0, r.y0, r.x1, r.y1));
}

#[inline(never)]
fn h_box_sum_border(t: &hand::Table<'_>, r: &Rect<Co>) {
    keep(t.box_sum_border(
        r.x0.to_bits(),
        r.y0.to_bits(),
        r.x1.to_bits(),
        r.y1.to_bits(),
    ));
}

#[inline(never)]
fn h_box_sum_repeat(t: &hand::Table<'_>, r: &Rect<Co>) {
    keep(t.box_sum_repeat_in_period(
        r.x0.to_bits(),
        r.y0.to_bits(),
        r.x1.to_bits(),
        r.y1.to_bits(),
    ));
}

#[inline(never)]
fn h_mean_rounded(sum: u64, sides: (u64, u64)) {
    keep(hand::mean_rounded(sum, black_box(8), sides.0, sides.1));
}

#[inline(never)]
fn h_box_sum_border_mean(t: &hand::Table<'_>, r: &Rect<Co>) {
    let s = t.box_sum_border(
        r.x0.to_bits(),
        r.y0.to_bits(),
        r.x1.to_bits(),
        r.y1.to_bits(),
    );
    let w = (r.x1.to_bits() - r.x0.to_bits()) as u64;
    let h = (r.y1.to_bits() - r.y0.to_bits()) as u64;
    keep(hand::mean_rounded(s, black_box(8), w, h));
}

#[inline(never)]
fn m_stream_build(texels: &[Tx], storage: &mut [En]) {
    let mut row = [0 as En; W];
    let Ok(mut s) = RowStreamBuilder::<En>::new(W, H, 8, &mut row[..]) else {
        return;
    };
    for (src, dst) in texels.chunks_exact(W).zip(storage.chunks_exact_mut(W)) {
        if s.push_row_into(src, dst).is_err() {
            return;
        }
    }
    keep(s.finish().is_ok());
}

/// The modulus of the measured modular build (fields of 20 bits: not byte-aligned).
const MODULAR_K: u32 = 20;

/// The modulus bits of the measured `u16` modular layout (the demo's `small` plan's kind).
const MODULAR_K16: u32 = 12;

#[inline(never)]
fn m_modular_build_u16(tex: &Texture<'_, Tx>, words: &mut [u32], row: &mut [u16]) {
    keep(Modular::<u16>::build(tex, MODULAR_K16, words, row).is_ok());
}

#[inline(never)]
fn m_modular_build(tex: &Texture<'_, Tx>, words: &mut [u32], row: &mut [En]) {
    keep(Modular::<En>::build(tex, MODULAR_K, words, row).is_ok());
}

/// Every corner of a modular layout of `k` bits (`E` values) built from `tex` equals the
/// reference table's entry (`w` wide) modulo `2^k`.
fn modular_agrees<E: Entry>(
    tex: &Texture<'_, Tx>,
    k: u32,
    words: &mut [u32],
    row: &mut [E],
    reference: &[En],
) -> bool {
    use texsat::Layout;
    let (w, h) = (tex.width(), tex.height());
    let Ok(m) = Modular::<E>::build(tex, k, words, row) else {
        return false;
    };
    let mask = u64::MAX >> (64 - k);
    for y in 1..=h {
        for x in 1..=w {
            let Some(&want) = reference.get((y - 1) * w + (x - 1)) else {
                return false;
            };
            if m.corner(x, y, &mut NoCount)[0].to_u64() & mask != u64::from(want) & mask {
                return false;
            }
        }
    }
    true
}

#[inline(never)]
fn h_build(texels: &[Tx], storage: &mut [En]) {
    hand::build(texels, black_box(W), storage);
    keep(&*storage);
}

/// `Sat::build` and the streaming builder (`RowStreamBuilder::push_row_into`, and `push_row`
/// with each row copied out) equal the hand-written build (`hand::build`, the plain loop) for
/// every width 1 to 40 and height 1 to 4, the texels at byte offsets 0 to 3 (unaligned word
/// loads in the `simd` feature's row scan, texsat's src/dsp.rs) of the harness's random texels
/// and of all 255, each output first filled with a sentinel, into `u32` entries, and so do the
/// modular layout's rows (in place, wrapping) at two moduli into `u32` values. With `simd`,
/// `Sat::build` and the streaming builder into `u16` entries too, the table and the builder's
/// row from `a16[0]`, `row16[0]` and from `a16[1]`, `row16[1]` (rows 2 bytes off a word: the
/// scan's first entry one by one, or the portable loop where the rows cannot all be on words;
/// rows of 16 entries and more; the `u16` modular rows are checked in `main`). On the device,
/// the one place that scan runs. A mismatch exits before the first mark, and count_insns.py
/// then fails (no regions).
fn builds_agree(
    texels: &[Tx],
    (a32, row32): (&mut [En], &mut [En]),
    (a16, row16): (&mut [u16], &mut [u16]),
    b: &mut [En],
    words: &mut [u32],
) -> bool {
    #[cfg(not(feature = "simd"))]
    let _ = (a16, row16);
    let full = [255u8; 4 + 40 * 4];
    for w in 1..=40 {
        for h in 1..=4 {
            for skip in 0..4 {
                for src in [texels, &full[..]] {
                    let (Some(t), Some(b)) = (src.get(skip..skip + w * h), b.get_mut(..w * h))
                    else {
                        return false;
                    };
                    hand::build(t, w, b);
                    let Ok(tex) = Texture::<Tx>::new(t, black_box(w), h) else {
                        return false;
                    };
                    if !entries_agree(&tex, a32, b, words, row32, &[MODULAR_K, 32], 1) {
                        return false;
                    }
                    // `u16` with the scan only: its sweep in the portable loop took QEMU's
                    // `-singlestep` run (CI's cross-check) past 7 minutes; host tests have it.
                    #[cfg(feature = "simd")]
                    if !entries_agree(&tex, &mut *a16, b, words, &mut *row16, &[], 2) {
                        return false;
                    }
                }
            }
        }
    }
    true
}

/// One case of [`builds_agree`] with `E` entries: `b` the hand-written table of `tex`.
fn entries_agree<E: Entry>(
    tex: &Texture<'_, Tx>,
    a: &mut [E],
    b: &[En],
    words: &mut [u32],
    row: &mut [E],
    ks: &[u32],
    offsets: usize,
) -> bool {
    let (w, h) = (tex.width(), tex.height());
    let sentinel = E::from(0xBEEF);
    let same = |a: &[E]| a.iter().zip(b).all(|(x, y)| x.to_u64() == u64::from(*y));
    for &k in ks {
        words.fill(0xDEAD_BEEF);
        row.fill(sentinel);
        let Some(row) = row.get_mut(..w) else {
            return false;
        };
        if !modular_agrees(tex, k, words, row, b) {
            return false;
        }
    }
    for off in 0..offsets {
        let (Some(a), Some(row)) = (a.get_mut(off..off + w * h), row.get_mut(off..off + w)) else {
            return false;
        };
        a.fill(sentinel);
        if Sat::build(tex, black_box(&mut a[..])).is_err() || !same(a) {
            return false;
        }
        for into in [true, false] {
            a.fill(sentinel);
            let Ok(mut s) = RowStreamBuilder::<E>::new(w, h, 8, &mut row[..]) else {
                return false;
            };
            for (y, dst) in a.chunks_exact_mut(w).enumerate() {
                let Some(src) = tex.row(y) else {
                    return false;
                };
                let ok = if into {
                    s.push_row_into(black_box(src), dst).is_ok()
                } else {
                    s.push_row(black_box(src))
                        .map(|r| dst.iter_mut().zip(r).for_each(|(d, v)| *d = *v))
                        .is_ok()
                };
                if !ok {
                    return false;
                }
            }
            if s.finish().is_err() || !same(a) {
                return false;
            }
        }
    }
    true
}

/// Every hand-written result equals texsat's (else the harness exits before measuring, and
/// count_insns.py reports missing regions).
fn same_results(
    sat: &Sat<'_, En>,
    t: &hand::Table<'_>,
    ri: &Rect<i32>,
    boxes: &[Rect<Co>],
) -> bool {
    let int_ok = matches!(sat.box_sum_int(ri, Border, &mut NoCount),
        Ok(s) if s.sum() == t.box_sum_int_border(ri.x0, ri.y0, ri.x1, ri.y1));
    int_ok
        && boxes.iter().all(|r| {
            let bits = (
                r.x0.to_bits(),
                r.y0.to_bits(),
                r.x1.to_bits(),
                r.y1.to_bits(),
            );
            let border = matches!(sat.box_sum(r, Stable, Border, &mut NoCount),
                Ok(s) if s.sum() == t.box_sum_border(bits.0, bits.1, bits.2, bits.3));
            let repeat = matches!(sat.box_sum(r, Stable, Repeat, &mut NoCount),
                Ok(s) if s.sum() == t.box_sum_repeat_in_period(bits.0, bits.1, bits.2, bits.3)
                    || t.box_sum_repeat_in_period(bits.0, bits.1, bits.2, bits.3) == 0);
            let mean = match sat.box_sum(r, Stable, Border, &mut NoCount) {
                Ok(s) => {
                    let (w, h) = s.sides_raw();
                    matches!(s.mean_rounded(0, 8, &mut NoCount),
                        Ok(m) if m == hand::mean_rounded(s.sum(), 8, w, h))
                }
                Err(_) => false,
            };
            border && repeat && mean
        })
}

// --- main ------------------------------------------------------------------------------------

/// `u16` entries on a word (4 bytes): the harness places `u16` rows on a word or 2 bytes off
/// one by the index it starts them at, which a plain `[u16; N]` (on 2 bytes) would not fix.
#[repr(C, align(4))]
struct Words16<const N: usize>([u16; N]);

static mut TEXELS: [Tx; W * H] = [0; W * H];
static mut TABLE: [En; W * H] = [0; W * H];
static mut TABLE2: [En; W * H] = [0; W * H];
static mut TABLE16: Words16<SMALL> = Words16([0; SMALL]);
static mut WORDS: [u32; 4 * W * H] = [0; 4 * W * H];
static mut SCRATCH: [En; 16 * (W + 1)] = [0; 16 * (W + 1)];
#[cfg(feature = "filter-mip")]
static mut MIP: [Tx; W * H] = [0; W * H];

#[entry]
fn main() -> ! {
    // SAFETY: single-threaded, no interrupts: `main` is the only user of these statics, each
    // borrowed once.
    let (texels, table, table2, table16, words, scratch) = unsafe {
        (
            &mut *core::ptr::addr_of_mut!(TEXELS),
            &mut *core::ptr::addr_of_mut!(TABLE),
            &mut *core::ptr::addr_of_mut!(TABLE2),
            &mut (*core::ptr::addr_of_mut!(TABLE16)).0,
            &mut *core::ptr::addr_of_mut!(WORDS),
            &mut *core::ptr::addr_of_mut!(SCRATCH),
        )
    };
    // A pseudo-random texture (xorshift32).
    let mut s = 0x1234_5678u32;
    for t in texels.iter_mut() {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        *t = (s >> 24) as u8;
    }
    let texels: &[Tx] = black_box(&texels[..]);
    // u32 tables; u16 tables (at most 255 x 160 = 40,800: the width proof holds) in 2 + 160
    // entries and a 41-entry row on the stack.
    let (mut sweep16, mut row16) = (Words16([0u16; 2 + 40 * 4]), Words16([0u16; 41]));
    let Some(row32) = scratch.get_mut(..41) else {
        exit()
    };
    if !builds_agree(
        texels,
        (&mut table[..], row32),
        (&mut sweep16.0[..], &mut row16.0[..]),
        &mut table2[..],
        &mut words[..],
    ) {
        exit()
    }
    let Ok(tex) = Texture::<Tx>::new(texels, black_box(W), black_box(H)) else {
        exit()
    };
    let tex = black_box(tex);
    let Ok(sat) = Sat::build(&tex, black_box(&mut table[..])) else {
        exit()
    };
    let sat = black_box(sat);

    let f = |v: f32| (v * 256.0) as i32;
    // Interior boxes.
    let ri: Rect<i32> = black_box(Rect::new(
        black_box(10),
        black_box(12),
        black_box(30),
        black_box(27),
    ));
    let rf = rect_fix(f(10.5), f(12.25), f(30.75), f(27.5));
    // Repeat: inside one period, not the first (x in the 2nd period, y in the 3rd).
    let rr_in = rect_fix(
        f(64.0 + 10.5),
        f(128.0 + 12.25),
        f(64.0 + 30.75),
        f(128.0 + 27.5),
    );
    // Repeat: crossing the right edge (x from 50.5 to 70.75).
    let rr_cross = rect_fix(f(50.5), f(12.25), f(70.75), f(27.5));
    let Ok(sum) = sat.box_sum(&rf, Stable, Border, &mut NoCount) else {
        exit()
    };
    let sum = black_box(sum);

    let hand_table = black_box(hand::Table {
        t: black_box(sat.entries()),
        w: black_box(W as u32),
        h: black_box(H as u32),
    });
    let rr_first = rect_fix(f(10.5), f(12.25), f(30.75), f(27.5));
    if !same_results(&sat, &hand_table, &ri, &[rf, rr_in, rr_first]) {
        exit()
    }
    let sides = black_box(sum.sides_raw());

    // Region order (count_insns.py's ENTRIES relies on it): the self-check and each measure!
    // give three regions.
    // SAFETY: the assembly above is an AAPCS function without arguments: it calls only
    // `texsat_count_mark` and restores `lr` (pushed with `r4`, keeping the stack 8-byte aligned).
    unsafe { texsat_count_selftest() };
    measure!(m_baseline(&sat, &rf));
    measure!(m_box_sum_int_border(&sat, &ri));
    measure!(h_box_sum_int_border(&hand_table, &ri));
    let ru: Rect<u32> = black_box(Rect::new(
        black_box(10),
        black_box(12),
        black_box(30),
        black_box(27),
    ));
    if sat.box_sum_inside(&ru).map(|s| u64::from(s[0]))
        != Ok(hand_table.box_sum_inside(10, 12, 30, 27))
    {
        exit()
    }
    measure!(m_box_sum_inside(&sat, &ru));
    measure!(h_box_sum_inside(&hand_table, &ru));
    measure!(m_box_sum_stable_border(&sat, &rf));
    measure!(h_box_sum_border(&hand_table, &rf));
    measure!(m_box_sum_stable_repeat(&sat, &rr_first));
    measure!(m_box_sum_stable_repeat(&sat, &rr_in));
    measure!(h_box_sum_repeat(&hand_table, &rr_in));
    measure!(m_box_sum_stable_repeat(&sat, &rr_cross));
    for r in [&rr_in, &rr_cross] {
        if sat.box_sum(r, Stable, RepeatWithinPeriod, &mut NoCount)
            != sat.box_sum(r, Stable, Repeat, &mut NoCount)
        {
            exit()
        }
    }
    measure!(m_box_sum_stable_repeat_within(&sat, &rr_in));
    measure!(m_box_sum_stable_repeat_within(&sat, &rr_cross));
    measure!(m_mean_rounded(&sum));
    measure!(h_mean_rounded(sum.sum(), sides));
    if sum.mean_rounded_u32(0, 8, &mut NoCount).map(u64::from)
        != sum.mean_rounded(0, 8, &mut NoCount)
    {
        exit()
    }
    measure!(m_mean_rounded_u32(&sum));
    measure!(m_box_sum_stable_border_mean(&sat, &rf));
    measure!(h_box_sum_border_mean(&hand_table, &rf));
    // Sat::build of the whole W x H table (per entry: divided by W * H in count-insns.sh).
    measure!(m_sat_build(&tex, black_box(&mut table2[..])));
    measure!(h_build(texels, black_box(&mut table2[..])));
    if table2[..] != sat.entries()[..] {
        exit()
    }
    table2.fill(0);
    measure!(m_stream_build(texels, black_box(&mut table2[..])));
    if table2[..] != sat.entries()[..] {
        exit()
    }
    measure!(m_modular_build(
        &tex,
        black_box(&mut words[..]),
        &mut scratch[..W]
    ));
    if !modular_agrees(
        &tex,
        MODULAR_K,
        &mut words[..],
        &mut scratch[..W],
        sat.entries(),
    ) {
        exit()
    }
    // The modular layout with u16 values, k = 12, of the whole W x H texture (sums past 16
    // bits: the rows wrap).
    let mut row_u16 = Words16([0u16; W + 1]);
    measure!(m_modular_build_u16(
        &tex,
        black_box(&mut words[..]),
        &mut row_u16.0[..W]
    ));
    // Its corners = the u32 table's (Sat::build, checked against the hand-written build above)
    // modulo 2^12, at widths 61 to 64 (every tail) and the builder's row on a word and 2 bytes
    // off one (the scan's head entry), one call site in the loop.
    for (w, off) in (61..=W).flat_map(|w| [(w, 0), (w, 1)]) {
        let (Some(t), Some(reference), Some(row)) = (
            texels.get(..w * H),
            table2.get_mut(..w * H),
            row_u16.0.get_mut(off..off + w),
        ) else {
            exit()
        };
        let Ok(tex_w) = Texture::<Tx>::new(t, black_box(w), H) else {
            exit()
        };
        if Sat::build(&tex_w, &mut reference[..]).is_err()
            || !modular_agrees(&tex_w, MODULAR_K16, &mut words[..], row, reference)
        {
            exit()
        }
    }
    // Sat::build of a SMALL_W x SMALL_H u16 table (per entry: divided by 256 in count_insns.py),
    // beside the hand-written build into u16.
    let (Some(small_texels), Some(reference)) = (texels.get(..SMALL), table2.get_mut(..SMALL))
    else {
        exit()
    };
    let Ok(small) = Texture::<Tx>::new(small_texels, black_box(SMALL_W), SMALL_H) else {
        exit()
    };
    measure!(m_sat_build_u16(&small, black_box(&mut table16[..])));
    let built = table16.map(u32::from);
    measure!(h_build_u16(small_texels, black_box(&mut table16[..])));
    if Sat::build(&small, &mut reference[..]).is_err()
        || built[..] != reference[..]
        || table16.map(u32::from) != built
    {
        exit()
    }
    // Tiled, 8 x 8 tiles.
    let tiled = TiledSpec::tiles(black_box(8), black_box(8))
        .ok()
        .and_then(|spec| Tiled::build(&tex, spec, &mut words[..], &mut scratch[..]).ok());
    match black_box(tiled) {
        Some(l) => {
            measure!(m_tiled_box_sum_int_border(&l, &ri));
            measure!(m_tiled_box_sum_stable_border(&l, &rf));
        }
        None => exit(),
    }
    #[cfg(feature = "filter-mip")]
    {
        // SAFETY: as above.
        let mip = unsafe { &mut *core::ptr::addr_of_mut!(MIP) };
        let p = texsat::filters::mip::MipPyramid::build(&tex, &mut mip[..]).ok();
        match black_box(p) {
            Some(p) => {
                // A 20.25 x 15.25 footprint (between levels 3 and 4), and the same in Repeat
                // in the second period.
                measure!(m_mip_trilinear(&p, &rf));
                measure!(m_mip_trilinear_repeat(&p, &rr_in));
            }
            None => exit(),
        }
    }
    exit()
}
