//! The firmware demo (feature `demo`, bin `texsat-demo`; run by `run.sh`): builds the tables of
//! the demo scene (`scene.rs`) into `static`s sized by three scene plans at compile time,
//! samples the 32 x 24 perspective scene with each plan's configuration (and, for comparison,
//! with trilinear mip-mapping), and logs one line per plan (checksum, first means, samples) with `defmt`, its frames written to the semihosting
//! console, then exits QEMU. `run.sh` decodes the frames with `defmt-print` and compares the
//! lines with the host's (`tools/examples/firmware_scene.rs`, the same scene code).
//!
//! Same panic handler as the link gate: this binary links only if no panic path remains.
#![no_std]
#![no_main]

use core::arch::asm;

use cortex_m_rt::entry;
use texsat::filters::mip::MipPyramid;
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
/// The mip levels below the texture: `W H / 3` texels for a square power-of-two texture
/// (`MipPyramid::storage_needed`, checked in `main`); one spare.
static mut MIP_LEVELS: [u8; W * H / 3 + 1] = [0; W * H / 3 + 1];

/// A marker between phases (`run.sh` with `DEMO_COUNT=1` counts the instructions executed
/// between its calls: build and render of each plan).
#[no_mangle]
#[inline(never)]
pub extern "C" fn texsat_demo_mark() {
    // SAFETY: a `nop`, no effect beyond keeping this function distinct.
    unsafe { asm!("nop", options(nomem, nostack, preserves_flags)) }
}

/// Semihosting: `SYS_OPEN` of `":tt"` for writing (the console), `SYS_WRITE` of a buffer.
mod semihosting {
    use core::arch::asm;

    /// One semihosting call: operation `op`, parameter block at `arg`; returns r0.
    fn call(op: u32, arg: *const u32) -> i32 {
        let r: i32;
        // SAFETY: the semihosting trap; `arg` points to a parameter block that lives across it.
        unsafe { asm!("bkpt 0xab", inout("r0") op as i32 => r, in("r1") arg, options(nostack)) }
        r
    }

    /// The console, opened once (`:tt`, mode 4 = "w").
    pub fn console() -> i32 {
        let name = b":tt\0";
        let block = [name.as_ptr() as u32, 4, 3];
        call(0x01, block.as_ptr())
    }

    /// Writes `bytes` to `handle` (binary-safe, unlike `SYS_WRITE0`).
    pub fn write(handle: i32, bytes: &[u8]) {
        let block = [handle as u32, bytes.as_ptr() as u32, bytes.len() as u32];
        call(0x05, block.as_ptr());
    }

    /// `SYS_EXIT`: ADP_Stopped_ApplicationExit (QEMU exits 0) or RunTimeErrorUnknown (1).
    pub fn exit(ok: bool) -> ! {
        let reason = if ok { 0x20026u32 } else { 0x20023u32 };
        loop {
            // SAFETY: the semihosting trap; r1 holds the reason (a value, not a pointer).
            unsafe { asm!("bkpt 0xab", in("r0") 0x18u32, in("r1") reason, options(nostack)) }
        }
    }
}

/// The `defmt` global logger: frames written to the semihosting console (QEMU writes them to a
/// file, `run.sh` decodes them with `defmt-print`). Panic-free (unlike a logger that checks for
/// re-entry with `panic!`): the firmware is single-threaded with no interrupts, so frames never
/// interleave.
mod logger {
    use core::ptr::addr_of_mut;

    static mut ENCODER: defmt::Encoder = defmt::Encoder::new();
    static mut CONSOLE: i32 = -1;

    fn emit(bytes: &[u8]) {
        // SAFETY: single-threaded, no interrupts: the only access to CONSOLE.
        let h = unsafe { &mut *addr_of_mut!(CONSOLE) };
        if *h < 0 {
            *h = super::semihosting::console();
        }
        super::semihosting::write(*h, bytes);
    }

    #[defmt::global_logger]
    struct Logger;

    // SAFETY: defmt's contract: acquire, then writes, then release, never nested: this
    // firmware logs only from `main` and has no interrupts.
    unsafe impl defmt::Logger for Logger {
        fn acquire() {
            // SAFETY: single-threaded (see above): the only reference to ENCODER.
            unsafe { (*addr_of_mut!(ENCODER)).start_frame(emit) }
        }
        unsafe fn flush() {}
        unsafe fn release() {
            // SAFETY: as in `acquire`.
            unsafe { (*addr_of_mut!(ENCODER)).end_frame(emit) }
        }
        unsafe fn write(bytes: &[u8]) {
            // SAFETY: as in `acquire`.
            unsafe { (*addr_of_mut!(ENCODER)).write(bytes, emit) }
        }
    }
}

/// Logs `plan NAME samples N checksum C first A,B,C,D` (the host prints the same line).
fn report(name: &str, c: &Checksum) {
    let [a, b, d, e] = c.first;
    defmt::info!(
        "plan {=str} samples {=u32} checksum {=u64} first {=u64},{=u64},{=u64},{=u64}",
        name,
        c.samples,
        c.hash,
        a,
        b,
        d,
        e
    );
}

fn fail(what: &str) -> ! {
    defmt::error!("error {=str}", what);
    semihosting::exit(false)
}

#[entry]
fn main() -> ! {
    // SAFETY: single-threaded, no interrupts: `main` is the only user of these statics, each
    // borrowed once.
    let (texels, small_w, small_r, rep_w, rep_r, til_w, til_s, mip) = unsafe {
        (
            &mut *core::ptr::addr_of_mut!(TEXELS),
            &mut *core::ptr::addr_of_mut!(SMALL_WORDS),
            &mut *core::ptr::addr_of_mut!(SMALL_ROW),
            &mut *core::ptr::addr_of_mut!(REPEAT_WORDS),
            &mut *core::ptr::addr_of_mut!(REPEAT_ROW),
            &mut *core::ptr::addr_of_mut!(TILED_WORDS),
            &mut *core::ptr::addr_of_mut!(TILED_SCRATCH_ROWS),
            &mut *core::ptr::addr_of_mut!(MIP_LEVELS),
        )
    };
    scene::fill_texture(texels);
    let Ok(tex) = Texture::<u8>::new(texels, W, H) else {
        fail("texture")
    };
    texsat_demo_mark();
    let built = Modular::<u16>::build(&tex, SMALL_K, small_w, small_r);
    texsat_demo_mark();
    match built {
        Ok(m) => {
            let rendered = scene::render(&m, &SMALL);
            texsat_demo_mark();
            match rendered {
                Ok(c) => report("small", &c),
                Err(_) => fail("small: a box was refused"),
            }
        }
        Err(_) => fail("small: build"),
    }
    texsat_demo_mark();
    let built = Modular::<u32>::build(&tex, REPEAT_K, rep_w, rep_r);
    texsat_demo_mark();
    match built {
        Ok(m) => {
            let rendered = scene::render(&m, &REPEAT);
            texsat_demo_mark();
            match rendered {
                Ok(c) => report("repeat", &c),
                Err(_) => fail("repeat: a box was refused"),
            }
        }
        Err(_) => fail("repeat: build"),
    }
    texsat_demo_mark();
    let built = Tiled::<u32>::build(&tex, TILED_SPEC, til_w, til_s);
    texsat_demo_mark();
    match built {
        Ok(t) => {
            let rendered = scene::render(&t, &TILED);
            texsat_demo_mark();
            match rendered {
                Ok(c) => report("tiled", &c),
                Err(_) => fail("tiled: a box was refused"),
            }
        }
        Err(_) => fail("tiled: build"),
    }
    // For comparison: trilinear mip-mapping of the REPEAT footprints.
    texsat_demo_mark();
    let built = match MipPyramid::<u8>::storage_needed(W, H) {
        Ok(n) => match mip.get_mut(..n) {
            Some(levels) => MipPyramid::build(&tex, levels),
            None => fail("mip: storage"),
        },
        Err(_) => fail("mip: storage"),
    };
    texsat_demo_mark();
    match built {
        Ok(p) => {
            let rendered = scene::render_mip(&p);
            texsat_demo_mark();
            match rendered {
                Ok(c) => report("mip", &c),
                Err(_) => fail("mip: a footprint was refused"),
            }
        }
        Err(_) => fail("mip: build"),
    }
    semihosting::exit(true)
}
