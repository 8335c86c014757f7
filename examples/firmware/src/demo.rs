//! The firmware demo (feature `demo`, bin `texsat-demo`; run by `run.sh`): builds the tables of
//! the demo scene (`scene.rs`) into `static`s sized by three scene plans at compile time,
//! samples the 32 x 24 perspective scene with each plan's configuration, and prints one line per
//! plan (checksum, first means, samples) through semihosting, then exits QEMU. `run.sh` compares
//! the lines with the host's (`tools/examples/firmware_scene.rs`, the same scene code).
//!
//! Same panic handler as the link gate: this binary links only if no panic path remains.
#![no_std]
#![no_main]

use core::arch::asm;

use cortex_m_rt::entry;
use texsat::layouts::{Modular, Tiled};
use texsat::plan::{EntryWord, PlanLayout};
use texsat::Texture;

mod scene;
use scene::{Checksum, H, REPEAT, SMALL, TILED, W};

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "C" {
        fn texsat_link_gate_a_panic_path_remains() -> !;
    }
    // SAFETY: never runs: a reachable handler makes the link fail (see main.rs).
    unsafe { texsat_link_gate_a_panic_path_remains() }
}

// What each plan is, checked when the firmware compiles (a change of the planner that picks
// another table stops the build here, instead of building the wrong one).
const SMALL_K: u32 = match SMALL.layout() {
    PlanLayout::Modular { k } => k,
    _ => panic!("SMALL: expected a modular plan"),
};
const _: () = assert!(matches!(SMALL.entry(), EntryWord::U16));
const REPEAT_K: u32 = match REPEAT.layout() {
    PlanLayout::Modular { k } => k,
    _ => panic!("REPEAT: expected a modular plan"),
};
const _: () = assert!(matches!(REPEAT.entry(), EntryWord::U32));
const TILED_SPEC: texsat::layouts::TiledSpec = match TILED.layout().tiled_spec() {
    Some(s) => s,
    None => panic!("TILED: expected a tiled plan"),
};
const TILED_SCRATCH: usize = match Tiled::<u32>::scratch_needed(TILED_SPEC, W) {
    Ok(n) => n,
    Err(_) => panic!(),
};

static mut TEXELS: [u8; W * H] = [0; W * H];
static mut SMALL_WORDS: [u32; SMALL.storage_len()] = [0; SMALL.storage_len()];
static mut SMALL_ROW: [u16; W] = [0; W];
static mut REPEAT_WORDS: [u32; REPEAT.storage_len()] = [0; REPEAT.storage_len()];
static mut REPEAT_ROW: [u32; W] = [0; W];
static mut TILED_WORDS: [u32; TILED.storage_len()] = [0; TILED.storage_len()];
static mut TILED_SCRATCH_ROWS: [u32; TILED_SCRATCH] = [0; TILED_SCRATCH];

/// A marker between phases (`run.sh` with `DEMO_COUNT=1` counts the instructions executed
/// between its calls: build and render of each plan).
#[no_mangle]
#[inline(never)]
pub extern "C" fn texsat_demo_mark() {
    // SAFETY: a `nop`, no effect beyond keeping this function distinct.
    unsafe { asm!("nop", options(nomem, nostack, preserves_flags)) }
}

/// Semihosting SYS_WRITE0: prints a NUL-terminated string on QEMU's stdout.
fn write0(s: &[u8]) {
    // SAFETY: semihosting call; r0 = SYS_WRITE0 (0x04), r1 = a NUL-terminated string.
    unsafe { asm!("bkpt 0xab", inout("r0") 0x04u32 => _, in("r1") s.as_ptr(), options(nostack)) }
}

/// Semihosting SYS_EXIT: ADP_Stopped_ApplicationExit (QEMU exits 0) or RunTimeErrorUnknown (1).
fn exit(ok: bool) -> ! {
    let reason = if ok { 0x20026u32 } else { 0x20023u32 };
    loop {
        // SAFETY: semihosting call; r0 = SYS_EXIT (0x18), r1 = the reason.
        unsafe { asm!("bkpt 0xab", in("r0") 0x18u32, in("r1") reason, options(nostack)) }
    }
}

/// A line buffer with hex and decimal formatting (no `core::fmt`).
struct Line {
    buf: [u8; 160],
    len: usize,
}

impl Line {
    fn new() -> Self {
        Line {
            buf: [0; 160],
            len: 0,
        }
    }
    fn text(&mut self, s: &[u8]) -> &mut Self {
        for &b in s {
            if let Some(c) = self.buf.get_mut(self.len) {
                *c = b;
                self.len += 1;
            }
        }
        self
    }
    fn hex(&mut self, v: u64) -> &mut Self {
        let mut d = [0u8; 16];
        for (i, c) in d.iter_mut().enumerate() {
            let n = ((v >> (60 - 4 * i)) & 15) as u8;
            *c = if n < 10 { b'0' + n } else { b'a' + n - 10 };
        }
        self.text(&d)
    }
    fn dec(&mut self, mut v: u64) -> &mut Self {
        let mut d = [0u8; 20];
        let mut i = d.len();
        loop {
            i -= 1;
            if let Some(c) = d.get_mut(i) {
                *c = b'0' + (v % 10) as u8;
            }
            v /= 10;
            if v == 0 || i == 0 {
                break;
            }
        }
        let digits = d.get(i..).unwrap_or(&[]);
        let mut tmp = [0u8; 20];
        let n = digits.len();
        if let Some(t) = tmp.get_mut(..n) {
            t.copy_from_slice(digits);
        }
        self.text(tmp.get(..n).unwrap_or(&[]))
    }
    fn print(&mut self) {
        self.text(b"\n\0");
        write0(self.buf.get(..self.len).unwrap_or(b"\0"));
        self.len = 0;
    }
}

/// Prints `plan NAME samples N checksum HEX first A,B,C,D` (the host prints the same).
fn report(name: &[u8], c: &Checksum) {
    let mut l = Line::new();
    l.text(b"plan ")
        .text(name)
        .text(b" samples ")
        .dec(u64::from(c.samples));
    l.text(b" checksum ").hex(c.hash).text(b" first ");
    for (i, v) in c.first.iter().enumerate() {
        if i > 0 {
            l.text(b",");
        }
        l.dec(*v);
    }
    l.print();
}

fn fail(what: &[u8]) -> ! {
    let mut l = Line::new();
    l.text(b"error ").text(what).print();
    exit(false)
}

#[entry]
fn main() -> ! {
    // SAFETY: single-threaded, no interrupts: `main` is the only user of these statics, each
    // borrowed once.
    let (texels, small_w, small_r, rep_w, rep_r, til_w, til_s) = unsafe {
        (
            &mut *core::ptr::addr_of_mut!(TEXELS),
            &mut *core::ptr::addr_of_mut!(SMALL_WORDS),
            &mut *core::ptr::addr_of_mut!(SMALL_ROW),
            &mut *core::ptr::addr_of_mut!(REPEAT_WORDS),
            &mut *core::ptr::addr_of_mut!(REPEAT_ROW),
            &mut *core::ptr::addr_of_mut!(TILED_WORDS),
            &mut *core::ptr::addr_of_mut!(TILED_SCRATCH_ROWS),
        )
    };
    scene::fill_texture(texels);
    let Ok(tex) = Texture::<u8>::new(texels, W, H) else {
        fail(b"texture")
    };
    texsat_demo_mark();
    let built = Modular::<u16>::build(&tex, SMALL_K, small_w, small_r);
    texsat_demo_mark();
    match built {
        Ok(m) => {
            let rendered = scene::render(&m, &SMALL);
            texsat_demo_mark();
            match rendered {
                Ok(c) => report(b"small", &c),
                Err(_) => fail(b"small: a box was refused"),
            }
        }
        Err(_) => fail(b"small: build"),
    }
    texsat_demo_mark();
    let built = Modular::<u32>::build(&tex, REPEAT_K, rep_w, rep_r);
    texsat_demo_mark();
    match built {
        Ok(m) => {
            let rendered = scene::render(&m, &REPEAT);
            texsat_demo_mark();
            match rendered {
                Ok(c) => report(b"repeat", &c),
                Err(_) => fail(b"repeat: a box was refused"),
            }
        }
        Err(_) => fail(b"repeat: build"),
    }
    texsat_demo_mark();
    let built = Tiled::<u32>::build(&tex, TILED_SPEC, til_w, til_s);
    texsat_demo_mark();
    match built {
        Ok(t) => {
            let rendered = scene::render(&t, &TILED);
            texsat_demo_mark();
            match rendered {
                Ok(c) => report(b"tiled", &c),
                Err(_) => fail(b"tiled: a box was refused"),
            }
        }
        Err(_) => fail(b"tiled: build"),
    }
    exit(true)
}
