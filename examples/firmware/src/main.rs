//! texsat's link gate: a Cortex-M4F firmware (QEMU `mps2-an386`) that calls every public entry
//! point of texsat for the enabled features and LINKS ONLY IF NO PANIC PATH REMAINS.
//!
//! How: the panic handler calls a symbol that nothing defines. If any panic path survives
//! optimisation (fat LTO, `opt-level = "s"`) the handler is reachable, the linker must resolve
//! that symbol and fails with `undefined symbol: texsat_link_gate_a_panic_path_remains`. If none
//! survives, the handler is dead, garbage-collected, and the binary links.
//!
//! For that to prove anything, the compiler must not be able to see the inputs: every texel,
//! size, box and storage slice goes through [`core::hint::black_box`], and every result goes
//! back into it, so no call is constant-folded or optimised out. Each entry point is called from
//! its own `#[inline(never)] fn gate_<name>` so `llvm-nm --print-size` gives its flash, and the
//! diagnostics build (`--features diagnose`) can tell which gate reaches which panic.
//!
//! Types: 8-bit texels, `u32` entries, one channel, `I24F8` corners (the crate's defaults), on
//! textures of up to 16 x 16 texels (sizes opaque). Every boundary mode is instantiated.
#![no_std]
#![no_main]
// The self-test builds (`selftest*` features) replace `main` and leave the gates unused.
#![cfg_attr(feature = "selftest", allow(dead_code, unused_imports, unused_macros))]

use core::hint::black_box;

use cortex_m_rt::entry;
use texsat::layouts::{Modular, ModularBuilder, Tiled, TiledBuilder, TiledSpec};
use texsat::lookup::BatchLookup;
use texsat::{
    Border, BoxLookup, BoxSum, ClampToEdge, DefaultCoord, EdgeKind, FormKind, FracBits, Layout,
    MirroredRepeat, NoCount, Paper, Rect, Repeat, RepeatWithinPeriod, RowStreamBuilder, Sat,
    Shortcut, Stable, Tally, Texture,
};

/// Texel type.
type Tx = u8;
/// Table entry type.
type En = u32;
/// Corner coordinate type (`I24F8`).
type Co = DefaultCoord;

/// Largest side of the gate's textures; the actual sizes are opaque.
const MAX_SIDE: usize = 16;
/// Texels (and flat table entries) of the largest texture.
const MAX_TEXELS: usize = MAX_SIDE * MAX_SIDE;
/// 32-bit words for the packed layouts (generous: a tiled layout of 16 x 16 8-bit texels needs
/// well under this).
const MAX_WORDS: usize = 4 * MAX_TEXELS;

// ---------------------------------------------------------------------------------------------
// Panic handler: the gate itself.
// ---------------------------------------------------------------------------------------------

/// The gate's panic handler: reachable only if a panic path remains, and then the link fails.
///
/// `unsafe` is needed because calling a foreign function is unsafe (the only other `unsafe` here
/// is defmt's `Logger` impl): `texsat_link_gate_a_panic_path_remains` is deliberately *defined
/// nowhere*. It is never executed: if the handler is reachable the binary does not link, so no
/// firmware with this handler can ever run it. texsat itself stays `forbid(unsafe_code)`.
#[cfg(not(feature = "diagnose"))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "C" {
        fn texsat_link_gate_a_panic_path_remains() -> !;
    }
    // SAFETY: never runs; see above. A remaining panic path turns into a link error.
    unsafe { texsat_link_gate_a_panic_path_remains() }
}

/// The diagnostics build's panic handler: links, so `link-gate.sh` can list from the binary
/// which panic machinery remains and which `gate_*` function reaches it.
#[cfg(feature = "diagnose")]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    keep(info);
    loop {
        core::hint::spin_loop();
    }
}

// ---------------------------------------------------------------------------------------------
// defmt: a no-op global logger (no transport needed to link and measure).
// ---------------------------------------------------------------------------------------------

#[cfg(feature = "defmt")]
mod logger {
    /// Discards every frame (but hands it to `black_box`, so the encoding is kept).
    #[defmt::global_logger]
    struct NoopLogger;

    // SAFETY (`unsafe impl`, required by defmt's trait): the logger has no state, so
    // `acquire`/`release` nesting and reentrancy cannot break anything.
    unsafe impl defmt::Logger for NoopLogger {
        fn acquire() {}
        unsafe fn flush() {}
        unsafe fn release() {}
        unsafe fn write(bytes: &[u8]) {
            core::hint::black_box(bytes);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Inputs the compiler cannot see.
// ---------------------------------------------------------------------------------------------

/// Hands a result to `black_box` (so it is computed and kept) and drops it.
#[inline(always)]
fn keep<T>(v: T) {
    let _ = black_box(v);
}

/// An opaque box with fixed-point corners (raw `I24F8` bits).
fn opaque_rect(x0: i32, y0: i32, x1: i32, y1: i32) -> Rect<Co> {
    black_box(Rect::new(
        Co::from_bits(black_box(x0)),
        Co::from_bits(black_box(y0)),
        Co::from_bits(black_box(x1)),
        Co::from_bits(black_box(y1)),
    ))
}

// ---------------------------------------------------------------------------------------------
// Core: texture, builds.
// ---------------------------------------------------------------------------------------------

#[inline(never)]
fn gate_texture_new<'a>(data: &'a [Tx], w: usize, h: usize) -> Option<Texture<'a, Tx>> {
    black_box(Texture::<Tx>::new(data, w, h)).ok()
}

#[inline(never)]
fn gate_texture_with_stride<'a>(
    data: &'a [Tx],
    w: usize,
    h: usize,
    stride: usize,
) -> Option<Texture<'a, Tx>> {
    black_box(Texture::<Tx>::with_stride(data, w, h, stride)).ok()
}

#[inline(never)]
fn gate_rect_from_f64(v: [f64; 4], f: [f32; 4]) {
    keep(Rect::<Co>::from_f64(v[0], v[1], v[2], v[3]));
    keep(Rect::<Co>::from_f32(f[0], f[1], f[2], f[3]));
}

#[inline(never)]
fn gate_sat_build<'a>(t: &Texture<'_, Tx>, storage: &'a mut [En]) -> Option<Sat<'a, En>> {
    black_box(Sat::build(t, storage)).ok()
}

#[inline(never)]
fn gate_sat_build_checked<'a>(t: &Texture<'_, Tx>, storage: &'a mut [En]) -> Option<Sat<'a, En>> {
    black_box(Sat::build_checked(t, storage)).ok()
}

#[inline(never)]
fn gate_sat_from_table<'a>(
    table: &'a [En],
    w: usize,
    h: usize,
    texel_bits: u32,
) -> Option<Sat<'a, En>> {
    black_box(Sat::<En>::from_table(table, w, h, texel_bits)).ok()
}

/// The accessors of a built table, `Sat::corner` and `Layout::corner` included.
#[inline(never)]
fn gate_sat_accessors(sat: &Sat<'_, En>, x: usize, y: usize) {
    keep(sat.corner(x, y));
    keep(Layout::corner(sat, x, y, &mut NoCount));
    keep((sat.width(), sat.height(), sat.texel_bits()));
    keep((
        sat.total(),
        sat.total_bits(),
        sat.table_bytes(),
        sat.entries(),
    ));
    keep(Layout::bits_per_entry(sat));
}

/// `RowStreamBuilder`: new, one `push_row` per texture row, `finish`.
#[inline(never)]
fn gate_row_stream_builder(t: &Texture<'_, Tx>, row: &mut [En], texel_bits: u32) {
    let r = (|| {
        let mut b = RowStreamBuilder::<En>::new(t.width(), t.height(), texel_bits, row)?;
        for y in 0..t.height() {
            let texels = t.row(y).ok_or(texsat::Error::EmptyTexture)?;
            keep(b.push_row(texels)?);
        }
        keep(b.rows_done());
        b.finish().map(|last| black_box(last).len())
    })();
    keep(r);
}

// ---------------------------------------------------------------------------------------------
// Core: lookups on the flat table, every form and boundary mode.
// ---------------------------------------------------------------------------------------------

macro_rules! box_sum_int_gates {
    ($($name:ident: $mode:expr;)*) => {$(
        #[inline(never)]
        fn $name(sat: &Sat<'_, En>, r: &Rect<i32>) -> Option<BoxSum<u64, 1>> {
            black_box(sat.box_sum_int(r, $mode, &mut NoCount)).ok()
        }
    )*};
}

box_sum_int_gates! {
    gate_box_sum_int_border: Border;
    gate_box_sum_int_clamp: ClampToEdge;
    gate_box_sum_int_repeat: Repeat;
    gate_box_sum_int_mirror: MirroredRepeat;
    gate_box_sum_int_repeat_within: RepeatWithinPeriod;
}

/// `Sat::box_sum_inside` (boxes known inside, no edge handling).
#[inline(never)]
fn gate_box_sum_inside(sat: &Sat<'_, En>, r: &Rect<i32>) {
    let u = Rect::new(r.x0 as u32, r.y0 as u32, r.x1 as u32, r.y1 as u32);
    keep(sat.box_sum_inside(&black_box(u)));
}

macro_rules! box_sum_gates {
    ($($name:ident: $form:expr, $mode:expr;)*) => {$(
        #[inline(never)]
        fn $name(sat: &Sat<'_, En>, r: &Rect<Co>) -> Option<BoxSum<u64, 1>> {
            black_box(sat.box_sum(r, $form, $mode, &mut NoCount)).ok()
        }
    )*};
}

box_sum_gates! {
    gate_box_sum_paper_border: Paper, Border;
    gate_box_sum_paper_clamp: Paper, ClampToEdge;
    gate_box_sum_paper_repeat: Paper, Repeat;
    gate_box_sum_paper_mirror: Paper, MirroredRepeat;
    gate_box_sum_stable_border: Stable, Border;
    gate_box_sum_stable_clamp: Stable, ClampToEdge;
    gate_box_sum_stable_repeat: Stable, Repeat;
    gate_box_sum_stable_mirror: Stable, MirroredRepeat;
    gate_box_sum_stable_repeat_within: Stable, RepeatWithinPeriod;
    gate_box_sum_paper_repeat_within: Paper, RepeatWithinPeriod;
}

/// One lookup with the `Tally` counter (its additions are not overflow-checked in release).
#[inline(never)]
fn gate_box_sum_stable_repeat_tally(sat: &Sat<'_, En>, r: &Rect<Co>) -> Tally {
    let mut tally = Tally::new();
    keep(sat.box_sum(r, Stable, Repeat, &mut tally));
    keep(tally.multiplicative());
    tally
}

/// The run-time arguments of the `*_raw` entry points, opaque to the compiler: the raw corners
/// of `r`, `F` as a value (8 here, but the compiler cannot see it: one lookup for every `F`),
/// the boundary mode and the form as run-time values (every mode's and form's branch compiled).
#[inline(always)]
fn raw_args(r: &Rect<Co>) -> Option<(Rect<i64>, FracBits, EdgeKind, FormKind)> {
    let f = black_box(FracBits::new(black_box(Co::FRAC_NBITS))).ok()?;
    Some((
        black_box(r.to_raw()),
        f,
        black_box(EdgeKind::Repeat),
        black_box(FormKind::Stable),
    ))
}

/// `box_sum_raw` and `box_mean_shortcut_raw` with `F`, the mode and the form at run time.
#[inline(never)]
fn gate_box_sum_raw(sat: &Sat<'_, En>, r: &Rect<Co>, tol: [u64; 2], out_frac_bits: u32) {
    let Some((rr, f, kind, form)) = raw_args(r) else {
        return;
    };
    keep(sat.box_sum_raw(&rr, f, form, kind, &mut NoCount));
    let s = Shortcut::for_tolerance(sat.texel_bits(), tol[0], tol[1]);
    keep(sat.box_mean_shortcut_raw(&rr, f, form, kind, &s, out_frac_bits, &mut NoCount));
}

macro_rules! shortcut_gates {
    ($($name:ident: $form:expr, $mode:expr;)*) => {$(
        #[inline(never)]
        fn $name(sat: &Sat<'_, En>, r: &Rect<Co>, tol: [u64; 2], out_frac_bits: u32) {
            let s = Shortcut::for_tolerance(sat.texel_bits(), tol[0], tol[1]);
            keep(s.min_side());
            let s2 = Shortcut::with_min_side(black_box(tol[0]));
            keep(sat.box_mean_shortcut(r, $form, $mode, &s, out_frac_bits, &mut NoCount));
            keep(sat.box_mean_shortcut(r, $form, $mode, &s2, out_frac_bits, &mut NoCount));
        }
    )*};
}

shortcut_gates! {
    gate_box_mean_shortcut_paper_border: Paper, Border;
    gate_box_mean_shortcut_stable_clamp: Stable, ClampToEdge;
    gate_box_mean_shortcut_stable_repeat: Stable, Repeat;
    gate_box_mean_shortcut_paper_mirror: Paper, MirroredRepeat;
}

#[inline(never)]
fn gate_mean_rounded(sum: &BoxSum<u64, 1>, c: usize, out_frac_bits: u32) {
    keep(sum.mean_rounded(c, out_frac_bits, &mut NoCount));
    let mut tally = Tally::new();
    keep(sum.mean_rounded(c, out_frac_bits, &mut tally));
    keep(tally);
    keep((sum.scaled_sum(c), sum.scaled_sums(), sum.sum()));
    keep((sum.frac_bits(), sum.sides_raw()));
}

#[inline(never)]
fn gate_means_rounded(sum: &BoxSum<u64, 1>, out_frac_bits: u32) {
    keep(sum.means_rounded(out_frac_bits, &mut NoCount));
}

/// `BoxSum::mean_rounded_u32`: the plan's 32-bit mean (one 64-by-32-bit division), and its
/// refusals.
#[inline(never)]
fn gate_mean_rounded_u32(sum: &BoxSum<u64, 1>, c: usize, out_frac_bits: u32) {
    keep(sum.mean_rounded_u32(c, out_frac_bits, &mut NoCount));
    let mut tally = Tally::new();
    keep(sum.mean_rounded_u32(c, out_frac_bits, &mut tally));
    keep(tally);
}

/// `BatchLookup::box_sums_raw` (`F`, the mode and the form at run time) and
/// `BatchLookup::box_sums_int` over a slice of boxes.
#[inline(never)]
fn gate_batch(sat: &Sat<'_, En>, r: &Rect<Co>, ri: &Rect<i32>) {
    let Some((rr, f, kind, form)) = raw_args(r) else {
        return;
    };
    let rects = black_box([rr, ri.to_raw_int()]);
    let mut out: [Result<BoxSum<u64, 1>, texsat::Error>; 2] =
        core::array::from_fn(|_| Err(texsat::Error::ZeroArea));
    keep(sat.box_sums_raw(&rects, f, form, kind, &mut NoCount, &mut out));
    keep(out);
    let ints = black_box([*ri, *ri]);
    keep(sat.box_sums_int(&ints, ClampToEdge, &mut NoCount, &mut out));
    keep(out);
}

/// `Layout::quad` and `Layout::cell_corners` on each layout (what the lookups read, called
/// directly).
macro_rules! quad_gates {
    ($($name:ident: $l:ty;)*) => {$(
        #[inline(never)]
        fn $name(l: &$l, x: [usize; 2], y: [usize; 2]) {
            keep(Layout::quad(l, x[0], x[1], y[0], y[1], &mut NoCount));
            keep(Layout::cell_corners(l, x[0], y[0], &mut NoCount));
        }
    )*};
}

quad_gates! {
    gate_sat_quad: Sat<'_, En>;
    gate_tiled_quad: Tiled<'_, En>;
    gate_modular_quad: Modular<'_, En>;
}

/// `Sat::build_strips` with the jobs run in order (a firmware has one core), and `StripJob::rows`.
#[inline(never)]
fn gate_sat_build_strips<'a>(
    t: &Texture<'_, Tx>,
    storage: &'a mut [En],
    strips: usize,
) -> Option<Sat<'a, En>> {
    black_box(Sat::build_strips(t, storage, strips, |jobs| {
        for j in jobs.iter_mut() {
            keep(j.rows());
            j.run();
        }
    }))
    .ok()
}

/// `RowStreamBuilder::push_row_into`: each finished row written into its place in a table.
#[inline(never)]
fn gate_row_stream_builder_into(
    t: &Texture<'_, Tx>,
    row: &mut [En],
    table: &mut [En],
    texel_bits: u32,
) {
    let r = (|| {
        let mut b = RowStreamBuilder::<En>::new(t.width(), t.height(), texel_bits, row)?;
        let mut rest = &mut *table;
        for y in 0..t.height() {
            let texels = t.row(y).ok_or(texsat::Error::EmptyTexture)?;
            let (out, tail) = rest
                .split_at_mut_checked(t.width())
                .ok_or(texsat::Error::EmptyTexture)?;
            b.push_row_into(texels, out)?;
            rest = tail;
        }
        b.finish().map(|last| black_box(last).len())
    })();
    keep(r);
}

// ---------------------------------------------------------------------------------------------
// Core: layouts.
// ---------------------------------------------------------------------------------------------

/// One level of `tw x th` tiles.
#[inline(never)]
fn gate_tiled_build<'a>(
    t: &Texture<'_, Tx>,
    tile: [u32; 2],
    words: &'a mut [u32],
    scratch: &mut [En],
) -> Option<Tiled<'a, En>> {
    let spec = black_box(TiledSpec::tiles(tile[0], tile[1])).ok()?;
    keep(Tiled::<En>::words_needed(spec, t.width(), t.height(), 8));
    keep(Tiled::<En>::scratch_needed(spec, t.width()));
    black_box(Tiled::build(t, spec, words, scratch)).ok()
}

/// Tiles within tiles, row by row.
#[inline(never)]
fn gate_tiled_builder<'a>(
    t: &Texture<'_, Tx>,
    blocks: [u32; 2],
    words: &'a mut [u32],
    scratch: &mut [En],
) -> Option<Tiled<'a, En>> {
    #[inline(always)]
    fn rows<'a>(
        t: &Texture<'_, Tx>,
        spec: TiledSpec,
        words: &'a mut [u32],
        scratch: &mut [En],
    ) -> Result<Tiled<'a, En>, texsat::Error> {
        let mut b = TiledBuilder::<En>::new(spec, t.width(), t.height(), 8, words, scratch)?;
        for y in 0..t.height() {
            b.push_row(t.row(y).ok_or(texsat::Error::EmptyTexture)?)?;
        }
        b.finish()
    }
    let spec = black_box(TiledSpec::square(&blocks)).ok()?;
    black_box(rows(t, spec, words, scratch)).ok()
}

#[inline(never)]
fn gate_tiled_from_words<'a>(
    words: &'a [u32],
    tile: [u32; 2],
    w: usize,
    h: usize,
) -> Option<Tiled<'a, En>> {
    let spec = black_box(TiledSpec::tiles(tile[0], tile[1])).ok()?;
    black_box(Tiled::<En>::from_words(words, spec, w, h, 8)).ok()
}

#[inline(never)]
fn gate_tiled_accessors(l: &Tiled<'_, En>, x: usize, y: usize, p: usize, q: usize) {
    keep(Layout::corner(l, x, y, &mut NoCount));
    keep((
        l.spec(),
        l.field_bits(p, q),
        l.max_fields_per_corner(),
        l.words(),
    ));
    keep((Layout::storage_bits(l), Layout::value_bits(l)));
}

#[inline(never)]
fn gate_tiled_box_sum_int(l: &Tiled<'_, En>, r: &Rect<i32>) {
    keep(BoxLookup::box_sum_int(l, r, Border, &mut NoCount));
    keep(BoxLookup::box_sum_int(l, r, Repeat, &mut NoCount));
}

#[inline(never)]
fn gate_tiled_box_sum(l: &Tiled<'_, En>, r: &Rect<Co>) {
    keep(BoxLookup::box_sum(l, r, Stable, ClampToEdge, &mut NoCount));
    keep(BoxLookup::box_sum(
        l,
        r,
        Paper,
        MirroredRepeat,
        &mut NoCount,
    ));
}

#[inline(never)]
fn gate_modular_build<'a>(
    t: &Texture<'_, Tx>,
    max_area: u64,
    words: &'a mut [u32],
    row: &mut [En],
) -> Option<Modular<'a, En>> {
    let k = Modular::<En>::bits_for_max_area(8, max_area);
    keep(Modular::<En>::words_needed(t.width(), t.height(), k));
    black_box(Modular::build(t, k, words, row)).ok()
}

#[inline(never)]
fn gate_modular_builder<'a>(
    t: &Texture<'_, Tx>,
    k: u32,
    words: &'a mut [u32],
    row: &mut [En],
) -> Option<Modular<'a, En>> {
    #[inline(always)]
    fn rows<'a>(
        t: &Texture<'_, Tx>,
        k: u32,
        words: &'a mut [u32],
        row: &mut [En],
    ) -> Result<Modular<'a, En>, texsat::Error> {
        let mut b = ModularBuilder::<En>::new(t.width(), t.height(), 8, k, words, row)?;
        for y in 0..t.height() {
            b.push_row(t.row(y).ok_or(texsat::Error::EmptyTexture)?)?;
        }
        b.finish()
    }
    black_box(rows(t, k, words, row)).ok()
}

#[inline(never)]
fn gate_modular_from_words<'a>(
    words: &'a [u32],
    w: usize,
    h: usize,
    k: u32,
) -> Option<Modular<'a, En>> {
    black_box(Modular::<En>::from_words(words, w, h, 8, k)).ok()
}

#[inline(never)]
fn gate_modular_accessors(l: &Modular<'_, En>, x: usize, y: usize) {
    keep(Layout::corner(l, x, y, &mut NoCount));
    keep((l.max_exact_area(), l.words(), Layout::storage_bits(l)));
}

#[inline(never)]
fn gate_modular_box_sum_int(l: &Modular<'_, En>, r: &Rect<i32>) {
    keep(BoxLookup::box_sum_int(l, r, ClampToEdge, &mut NoCount));
    keep(BoxLookup::box_sum_int(l, r, MirroredRepeat, &mut NoCount));
}

#[inline(never)]
fn gate_modular_box_sum(l: &Modular<'_, En>, r: &Rect<Co>) {
    keep(BoxLookup::box_sum(l, r, Stable, Repeat, &mut NoCount));
    keep(BoxLookup::box_sum(l, r, Paper, Border, &mut NoCount));
}

// ---------------------------------------------------------------------------------------------
// Core: width proofs, packed fields, tiled specs, footprints (public helpers a firmware may call
// at run time; the `const fn`s are called here with opaque arguments).
// ---------------------------------------------------------------------------------------------

#[inline(never)]
fn gate_width(texel_bits: u32, w: usize, h: usize, entry_bits: u32, frac_bits: u32) {
    use texsat::width;
    keep(width::check_texel_bits(texel_bits));
    keep(width::entry_bits_worst_case(texel_bits, w, h));
    keep(width::check_entry_worst_case(texel_bits, w, h, entry_bits));
    keep(width::paper_acc_bits(entry_bits, frac_bits));
    keep(width::stable_acc_bits(entry_bits, frac_bits));
    keep(width::check_acc(entry_bits, frac_bits));
    let p = width::paper_multiplies(texel_bits, w, h, frac_bits);
    let q = width::stable_multiplies(texel_bits, w, frac_bits);
    keep((p[0].fits_signed(18, 25), q[2].fits_signed(18, 25), p, q));
    keep(width::max_texel_u64(texel_bits));
    keep(width::bits_of_u64(w as u64));
    keep(width::bits_of_product(
        w as u64,
        h as u64,
        texel_bits as u64,
    ));
}

/// The width helpers whose signature is 128-bit (`u128` in or out): host-side and compile-time
/// analysis that no build or lookup calls. The IR check (link-gate.sh) allows 128-bit
/// operations here and nowhere else.
#[inline(never)]
fn gate_width_u128(texel_bits: u32, w: usize, h: usize, halves: [u64; 2]) {
    use texsat::width;
    // Formed here, not in `main`, so that no other function of the gate holds a 128-bit value.
    let v = (u128::from(halves[0]) << 64) | u128::from(halves[1]);
    keep((
        width::bits_of(v),
        width::ceil_log2(v),
        width::max_texel(texel_bits),
    ));
    keep(width::worst_case_total(texel_bits, w, h));
    keep(width::entry_bits_naive(texel_bits, w, h));
}

#[inline(never)]
fn gate_packed(words: &mut [u32], offset: u64, len: u32, value: u64, count: usize) {
    use texsat::layouts::packed;
    keep(packed::words_for(count, len));
    keep(packed::write_bits(words, offset, len, value));
    keep(packed::read_bits(words, offset, len));
}

#[inline(never)]
fn gate_tiled_spec(blocks: &[u32], t: [u32; 2], k: u32, texel_bits: u32, area: u64) {
    use texsat::layouts::{modulus_bits_for, AxisLevels};
    let levels = AxisLevels::new(blocks);
    if let Ok(l) = levels {
        keep((l.blocks(), l.components()));
    }
    keep(levels);
    keep(TiledSpec::tiles(t[0], t[1]).map(|s| s.with_modulus(k)));
    keep(TiledSpec::square(blocks));
    keep(TiledSpec::FLAT_PACKED.with_modulus(k));
    keep(modulus_bits_for(texel_bits, area));
}

/// The shortcut's f64 error bound (soft double precision on the M4F; a report helper).
#[inline(never)]
fn gate_shortcut_bound(x: f64, y: f64) {
    keep(Shortcut::error_bound(8, x, y));
}

/// The small public helpers no other gate calls by name: `EdgeKind::texel_index` (a mode's
/// texel index at run time), the `from_name`s, `Rect::to_raw_int`, the accumulator widths,
/// `FormKind::modular_headroom_bits`, `packed::words_for_checked`, `Sat::entries_needed`,
/// `build_kernel`.
#[inline(never)]
fn gate_helpers(i: i64, n: usize, name: &str, ri: &Rect<i32>, bits: [u32; 3]) {
    use texsat::width;
    for kind in EdgeKind::ALL {
        keep(kind.texel_index(i, n));
    }
    keep((EdgeKind::from_name(name), FormKind::from_name(name)));
    keep(ri.to_raw_int());
    keep(width::acc_value_bits(bits[0]));
    keep(width::max_frac_bits(FormKind::Stable, bits[1], bits[2]));
    keep(width::max_frac_bits(FormKind::Paper, bits[1], bits[2]));
    keep(FormKind::Paper.modular_headroom_bits(bits[2]));
    keep(texsat::layouts::packed::words_for_checked(n, bits[0]));
    keep(Sat::<En>::entries_needed(n, n));
    keep(texsat::build_kernel());
}

/// Scene plans at run time (facts opaque to the compiler): `Plan::for_scene`, the accessors,
/// `check_box`, the rejections.
#[inline(never)]
fn gate_plan(facts: &texsat::plan::SceneFacts, r: &Rect<Co>) {
    let Ok(p) = black_box(texsat::plan::Plan::for_scene(facts)) else {
        return;
    };
    keep((
        p.entry(),
        p.layout(),
        p.lookup(),
        p.acc_bits(),
        p.storage_len(),
        p.mean_fits_u32(),
        p.repeat_within_period(),
    ));
    keep((
        p.table_bytes(),
        p.bits_per_entry(),
        p.costs(),
        p.max_error(),
    ));
    keep((p.shortcut(), p.layout().tiled_spec(), p.layout().modulus()));
    keep(p.check_box(&r.to_raw()));
    for rej in p.rejected() {
        keep(rej);
    }
}

// ---------------------------------------------------------------------------------------------
// Core: `u16` tables (the smallest plans' values; their lookups compute in `i32`), so the IR check
// covers their paths too.
// ---------------------------------------------------------------------------------------------

/// Table entry type of the narrow tables.
type En16 = u16;

/// A flat `u16` table: build, integer lookups, the run-time-`F` lookup, both means.
#[inline(never)]
fn gate_u16_sat(
    t: &Texture<'_, Tx>,
    storage: &mut [En16],
    r: &Rect<Co>,
    ri: &Rect<i32>,
    out_frac_bits: u32,
) {
    let Ok(sat) = black_box(Sat::<En16>::build(t, storage)) else {
        return;
    };
    keep(sat.box_sum_int(ri, Border, &mut NoCount));
    keep(sat.box_sum_int(ri, Repeat, &mut NoCount));
    let s = sat.box_sum_int(ri, ClampToEdge, &mut NoCount);
    if let Some((rr, f, kind, form)) = raw_args(r) {
        keep(sat.box_sum_raw(&rr, f, form, kind, &mut NoCount));
    }
    if let Ok(s) = black_box(s) {
        keep(s.mean_rounded(0, out_frac_bits, &mut NoCount));
        keep(s.mean_rounded_u32(0, out_frac_bits, &mut NoCount));
    }
}

/// A modular layout with `u16` values (the demo's `small` plan): build, integer lookups, the
/// run-time-`F` lookup, the 32-bit mean.
#[inline(never)]
fn gate_u16_modular(
    t: &Texture<'_, Tx>,
    k: u32,
    words: &mut [u32],
    row: &mut [En16],
    r: &Rect<Co>,
    ri: &Rect<i32>,
    out_frac_bits: u32,
) {
    let Ok(m) = black_box(Modular::<En16>::build(t, k, words, row)) else {
        return;
    };
    keep(BoxLookup::box_sum_int(&m, ri, MirroredRepeat, &mut NoCount));
    let s = BoxLookup::box_sum_int(&m, ri, ClampToEdge, &mut NoCount);
    if let Some((rr, f, kind, form)) = raw_args(r) {
        keep(BoxLookup::box_sum_raw(&m, &rr, f, form, kind, &mut NoCount));
    }
    if let Ok(s) = black_box(s) {
        keep(s.mean_rounded_u32(0, out_frac_bits, &mut NoCount));
    }
}

// ---------------------------------------------------------------------------------------------
// Filters, each behind its feature; each sample function in all four boundary modes.
// ---------------------------------------------------------------------------------------------

/// Calls `$call` once per boundary mode, binding the mode value to `$m`.
#[allow(unused_macros)] // used by the filter gates only
macro_rules! each_mode {
    (|$m:ident| $call:expr) => {{
        {
            let $m = Border;
            keep($call);
        }
        {
            let $m = ClampToEdge;
            keep($call);
        }
        {
            let $m = Repeat;
            keep($call);
        }
        {
            let $m = MirroredRepeat;
            keep($call);
        }
    }};
}

#[cfg(feature = "filter-point")]
#[inline(never)]
fn gate_point(t: &Texture<'_, Tx>, r: &Rect<Co>) {
    use texsat::filters::point::point;
    each_mode!(|m| point(t, r, m, &mut NoCount));
    if let Some((rr, f, kind, _)) = raw_args(r) {
        keep(texsat::filters::point::point_raw(
            t,
            &rr,
            f,
            kind,
            &mut NoCount,
        ));
    }
    if let Ok(sample) = point(t, r, Repeat, &mut NoCount) {
        keep(sample.value_f64(black_box(0)));
    }
}

#[cfg(any(
    feature = "filter-mip",
    feature = "filter-rip",
    feature = "filter-dip",
    feature = "filter-tent"
))]
#[inline(never)]
fn gate_level_log2_fixed(raw: u64, f: u32, out_frac: u32) {
    keep(texsat::filters::level::log2_fixed(raw, f, out_frac));
}

#[cfg(feature = "filter-mip")]
mod mip_gates {
    use super::*;
    use texsat::filters::mip::MipPyramid;

    #[inline(never)]
    pub fn gate_mip_build<'a>(
        t: &Texture<'a, Tx>,
        storage: &'a mut [Tx],
    ) -> Option<MipPyramid<'a, Tx>> {
        keep(MipPyramid::<Tx>::pyramid_texels(t.width(), t.height()));
        keep(MipPyramid::<Tx>::storage_needed(t.width(), t.height()));
        black_box(MipPyramid::build(t, storage)).ok()
    }

    #[inline(never)]
    pub fn gate_mip_queries(p: &MipPyramid<'_, Tx>, r: &Rect<Co>, l: usize, x: usize, y: usize) {
        keep(texsat::filters::mip::trilinear_error_bound(black_box(8)));
        keep(texsat::filters::mip::weight_bits(black_box(8)));
        keep(p.lod(r));
        if let Some((rr, f, _, _)) = raw_args(r) {
            keep(p.lod_raw(&rr, f));
        }
        keep(p.level_texel(l, x, y));
        keep((p.levels(), p.level_count(), p.storage_len()));
    }

    #[inline(never)]
    pub fn gate_mip_point_sample(p: &MipPyramid<'_, Tx>, r: &Rect<Co>) {
        each_mode!(|m| p.point_sample(r, m, &mut NoCount));
        if let Some((rr, f, kind, _)) = raw_args(r) {
            keep(p.point_sample_raw(&rr, f, kind, &mut NoCount));
        }
    }

    #[inline(never)]
    pub fn gate_mip_trilinear(p: &MipPyramid<'_, Tx>, r: &Rect<Co>) {
        each_mode!(|m| p.trilinear(r, m, &mut NoCount));
        if let Some((rr, f, kind, _)) = raw_args(r) {
            keep(p.trilinear_raw(&rr, f, kind, &mut NoCount));
        }
    }
}

#[cfg(feature = "filter-rip")]
mod rip_gates {
    use super::*;
    use texsat::filters::rip::RipMap;

    #[inline(never)]
    pub fn gate_rip_build<'a>(
        t: &Texture<'_, Tx>,
        storage: &'a mut [Tx],
    ) -> Option<RipMap<'a, Tx, 1>> {
        keep(RipMap::<Tx, 1>::storage_needed(t.width(), t.height()));
        black_box(RipMap::build(t, storage)).ok()
    }

    #[inline(never)]
    pub fn gate_rip_from_storage(storage: &[Tx], w: usize, h: usize) -> Option<RipMap<'_, Tx, 1>> {
        black_box(RipMap::<Tx, 1>::from_storage(storage, w, h)).ok()
    }

    #[inline(never)]
    pub fn gate_rip_queries(m: &RipMap<'_, Tx, 1>, lx: usize, ly: usize, i: usize, j: usize) {
        use texsat::filters::rip::{arithmetic_error_bound, level_selection_error_bound};
        let b = black_box(8);
        keep((arithmetic_error_bound(b), level_selection_error_bound(b)));
        keep((m.level_size(lx, ly), m.level_texel(lx, ly, i, j)));
        keep((
            m.levels_x(),
            m.levels_y(),
            m.storage_len(),
            m.storage_bits(),
        ));
    }

    #[inline(never)]
    pub fn gate_rip_sample(map: &RipMap<'_, Tx, 1>, r: &Rect<Co>) {
        each_mode!(|m| map.sample(r, m, &mut NoCount));
        if let Some((rr, f, kind, _)) = raw_args(r) {
            keep(map.sample_raw(&rr, f, kind, &mut NoCount));
        }
    }
}

#[cfg(feature = "filter-dip")]
mod dip_gates {
    use super::*;
    use texsat::filters::dip::{DipFilter, DipMap, DipPyramid};

    #[inline(never)]
    pub fn gate_dip_build<'a>(
        t: &Texture<'_, Tx>,
        storage: &'a mut [Tx],
    ) -> Option<DipMap<'a, Tx, 1>> {
        keep(DipMap::<Tx, 1>::storage_needed(t.width(), t.height()));
        black_box(DipMap::build(t, storage)).ok()
    }

    #[inline(never)]
    pub fn gate_dip_from_storage(storage: &[Tx], w: usize, h: usize) -> Option<DipMap<'_, Tx, 1>> {
        black_box(DipMap::<Tx, 1>::from_storage(storage, w, h)).ok()
    }

    #[inline(never)]
    pub fn gate_dip_queries(m: &DipMap<'_, Tx, 1>, p: DipPyramid, l: usize, i: usize, j: usize) {
        use texsat::filters::dip::{arithmetic_error_bound, level_selection_error_bound};
        let b = black_box(8);
        keep((arithmetic_error_bound(b), level_selection_error_bound(b)));
        keep((m.levels(p), m.level_size(p, l), m.level_texel(p, l, i, j)));
        keep((m.storage_len(), m.storage_bits()));
    }

    #[inline(never)]
    pub fn gate_dip_sample(map: &DipMap<'_, Tx, 1>, r: &Rect<Co>, filter: DipFilter) {
        each_mode!(|m| map.sample(r, filter, m, &mut NoCount));
        if let Some((rr, f, kind, _)) = raw_args(r) {
            keep(map.sample_raw(&rr, f, filter, kind, &mut NoCount));
        }
    }
}

#[cfg(feature = "filter-tent")]
mod tent_gates {
    use super::*;
    use texsat::filters::tent::{TentLines, TentTable};

    /// Entry type of the order-2 tables (8-bit 16 x 16 textures need 25 bits): `u32`, so the
    /// lookups below compute in `i64` (`TentEntry::Acc`), and the IR check proves that no
    /// 128-bit operation is left on their paths.
    pub type Te = u32;

    #[inline(never)]
    pub fn gate_tent_table_build<'a>(
        t: &Texture<'_, Tx>,
        storage: &'a mut [Te],
    ) -> Option<TentTable<'a, Te>> {
        keep(TentTable::<Te>::storage_needed(t.width(), t.height()));
        black_box(TentTable::build(t, storage)).ok()
    }

    #[inline(never)]
    pub fn gate_tent_lines_build<'a>(
        t: &Texture<'_, Tx>,
        storage: &'a mut [Te],
    ) -> Option<TentLines<'a, Te>> {
        keep(TentLines::<Te>::storage_needed(t.width(), t.height()));
        black_box(TentLines::build(t, storage)).ok()
    }

    /// The tent filter's width analysis, whose public `const fn`s answer for any texel width
    /// and side (a saturating `u128` product past 64-bit texels or `2^64 - 3` sides) and its
    /// `f64` error bound (`max_texel` as `u128`): host and compile-time helpers (category (c)
    /// of docs/wide-arithmetic.md), kept out of the `u32` lookups' gates so that the IR check
    /// (link-gate.sh) can allow 128-bit operations here and in no tent lookup.
    #[inline(never)]
    pub fn gate_tent_width_u128(x: usize, y: usize) {
        use texsat::filters::tent::{paper_error_bound, tent_entry_bits, tent_line_bits};
        let b = black_box(8);
        keep((tent_entry_bits(b, x, y), tent_line_bits(b, x)));
        keep(paper_error_bound(b, x as f64, y as f64));
    }

    #[inline(never)]
    pub fn gate_tent_queries(q: &TentTable<'_, Te>, l: &TentLines<'_, Te>, x: usize, y: usize) {
        keep((q.width(), q.height(), q.texel_bits()));
        keep((
            q.corner(x, y),
            q.entries(),
            q.table_bytes(),
            l.table_bytes(),
        ));
    }

    #[inline(never)]
    pub fn gate_tent_sample_int(q: &TentTable<'_, Te>, c: [i32; 2], ab: [u32; 2]) {
        each_mode!(|m| q.sample_int(c[0], c[1], ab[0], ab[1], m, &mut NoCount));
    }

    #[inline(never)]
    pub fn gate_tent_sample(q: &TentTable<'_, Te>, r: &Rect<Co>) {
        each_mode!(|m| q.sample(r, m, &mut NoCount));
        if let Some((rr, f, kind, _)) = raw_args(r) {
            keep(q.sample_raw(&rr, f, kind, &mut NoCount));
        }
    }

    #[inline(never)]
    pub fn gate_tent_sample_exact(
        q: &TentTable<'_, Te>,
        l: &TentLines<'_, Te>,
        t: &Texture<'_, Tx>,
        r: &Rect<Co>,
    ) {
        each_mode!(|m| q.sample_exact(l, t, r, m, &mut NoCount));
        if let Some((rr, f, kind, _)) = raw_args(r) {
            keep(q.sample_exact_raw(l, t, &rr, f, kind, &mut NoCount));
        }
    }
}

#[cfg(feature = "filter-variance")]
mod variance_gates {
    use super::*;
    use texsat::filters::variance::{SquaresTable, VarianceTables};

    #[inline(never)]
    pub fn gate_variance_build<'a>(
        t: &Texture<'_, Tx>,
        values: &'a mut [En],
        squares: &'a mut [En],
    ) -> Option<VarianceTables<'a, En>> {
        keep(VarianceTables::<En>::storage_needed(t.width(), t.height()));
        black_box(VarianceTables::build(t, values, squares)).ok()
    }

    #[inline(never)]
    pub fn gate_squares_build<'a>(
        t: &Texture<'_, Tx>,
        storage: &'a mut [En],
    ) -> Option<SquaresTable<'a, En>> {
        keep(texsat::filters::variance::storage_needed::<1>(
            t.width(),
            t.height(),
        ));
        black_box(SquaresTable::build(t, storage)).ok()
    }

    #[inline(never)]
    pub fn gate_variance_queries(v: &VarianceTables<'_, En>, x: usize, y: usize) {
        keep(texsat::filters::variance::squares_entry_bits(
            black_box(8),
            x,
            y,
        ));
        keep(Layout::corner(v.squares(), x, y, &mut NoCount));
        keep((
            v.values().total(),
            v.squares().source_texel_bits(),
            v.table_bytes(),
        ));
    }

    #[inline(never)]
    pub fn gate_variance_int(v: &VarianceTables<'_, En>, r: &Rect<i32>) {
        each_mode!(|m| v.variance_int(r, m, &mut NoCount));
    }

    #[inline(never)]
    pub fn gate_variance_paper(v: &VarianceTables<'_, En>, r: &Rect<Co>) {
        each_mode!(|m| v.variance(r, Paper, m, &mut NoCount));
    }

    #[inline(never)]
    pub fn gate_variance_stable(v: &VarianceTables<'_, En>, r: &Rect<Co>) {
        each_mode!(|m| v.variance(r, Stable, m, &mut NoCount));
        if let Some((rr, f, kind, form)) = raw_args(r) {
            keep(v.variance_raw(&rr, f, form, kind, &mut NoCount));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// defmt: the `Format` impls the `defmt` feature adds.
// ---------------------------------------------------------------------------------------------

#[cfg(feature = "defmt")]
#[inline(never)]
fn gate_defmt_format(
    err: &texsat::Error,
    sum: &BoxSum<u64, 1>,
    r: &Rect<i32>,
    s: &Shortcut,
    t: &Tally,
) {
    defmt::println!("{} {} {} {} {}", err, sum, r, s, t);
}

#[cfg(all(feature = "defmt", feature = "filter-point"))]
#[inline(never)]
fn gate_defmt_format_sample(s: &texsat::filters::Sample<1>) {
    defmt::println!("{}", s);
}

#[cfg(all(feature = "defmt", feature = "filter-dip"))]
#[inline(never)]
fn gate_defmt_format_dip(
    p: &texsat::filters::dip::DipPyramid,
    f: &texsat::filters::dip::DipFilter,
) {
    defmt::println!("{} {}", p, f);
}

// ---------------------------------------------------------------------------------------------
// main: feed opaque inputs to every gate.
// ---------------------------------------------------------------------------------------------

/// The gate's self-test (`link-gate.sh` runs it first): firmware-local code only, so it does
/// not depend on the state of texsat. With `selftest` it has no panic path and must link; with
/// `selftest-panic` it indexes an array out of bounds at an opaque index and must NOT link.
#[cfg(feature = "selftest")]
mod selftest {
    use core::hint::black_box;

    /// Panic-free: `get` instead of indexing, checked division, wrapping addition.
    #[inline(never)]
    pub fn gate_selftest_clean(data: &[u8], i: usize) -> u8 {
        let a = data.get(i).copied().unwrap_or(0);
        let b = data.len().checked_div(i).unwrap_or(0) as u8;
        a.wrapping_add(b)
    }

    /// One bounds check the compiler cannot remove.
    #[cfg(feature = "selftest-panic")]
    #[inline(never)]
    pub fn gate_selftest_panic() -> u8 {
        [0u8; 4][black_box(9)]
    }

    pub fn run() -> ! {
        let data = [1u8, 2, 3, 4];
        black_box(gate_selftest_clean(black_box(&data[..]), black_box(2)));
        #[cfg(feature = "selftest-panic")]
        black_box(gate_selftest_panic());
        loop {
            core::hint::spin_loop();
        }
    }
}

#[cfg(feature = "selftest")]
#[entry]
fn main() -> ! {
    selftest::run()
}

#[cfg(not(feature = "selftest"))]
#[entry]
fn main() -> ! {
    // Texels and sizes the compiler cannot see.
    let texel_array: [Tx; MAX_TEXELS] = black_box(core::array::from_fn(|i| (i * 37 + 11) as Tx));
    let texels: &[Tx] = black_box(&texel_array[..]);
    let (w, h) = (black_box(8usize), black_box(6usize));
    let stride = black_box(MAX_SIDE);

    let rect_int: Rect<i32> = black_box(Rect::new(
        black_box(1),
        black_box(1),
        black_box(5),
        black_box(4),
    ));
    // [0.5, 7.25) x [-1.0, 4.5) in I24F8 raw units.
    let rect_fix = opaque_rect(128, -256, 1856, 1152);
    let out_frac_bits = black_box(8u32);
    let (x, y) = (black_box(3usize), black_box(2usize));

    gate_rect_from_f64(
        black_box([0.5, 0.5, 7.5, 3.5]),
        black_box([0.25, 0.0, 2.0, 1.5]),
    );
    gate_width(black_box(8), w, h, black_box(32), black_box(8));
    gate_width_u128(black_box(8), w, h, black_box([0, 12345]));
    let mut field_words = [0u32; 8];
    gate_packed(
        black_box(&mut field_words[..]),
        black_box(37),
        black_box(14),
        black_box(0x1abc),
        black_box(16),
    );
    gate_tiled_spec(
        black_box(&[2, 8][..]),
        black_box([4, 4]),
        black_box(16),
        black_box(8),
        black_box(64),
    );
    gate_shortcut_bound(black_box(12.5), black_box(7.25));
    gate_helpers(
        black_box(-37),
        black_box(8),
        black_box("repeat"),
        &rect_int,
        black_box([32, 28, 63]),
    );
    {
        let facts = texsat::plan::SceneFacts {
            max_box: black_box([16 << 8, 16 << 8]),
            tolerance: black_box(0),
            max_reads: black_box(0),
            ..texsat::plan::SceneFacts::new(
                black_box(64),
                black_box(48),
                black_box(8),
                black_box(8),
                black_box(texsat::EdgeKind::Repeat),
            )
        };
        gate_plan(&black_box(facts), &rect_fix);
    }

    let packed = gate_texture_new(texels, w, h);
    let strided = gate_texture_with_stride(texels, w, h, stride);
    let Some(tex) = black_box(packed.or(strided)) else {
        loop {
            core::hint::spin_loop();
        }
    };

    // Builds: each into its own opaque storage.
    let mut table = [0 as En; MAX_TEXELS];
    let mut table2 = [0 as En; MAX_TEXELS];
    let mut row = [0 as En; MAX_SIDE];
    let sat = gate_sat_build(&tex, black_box(&mut table[..]));
    let sat2 = gate_sat_build_checked(&tex, black_box(&mut table2[..]));
    gate_row_stream_builder(&tex, black_box(&mut row[..]), black_box(8));
    let mut table3 = [0 as En; MAX_TEXELS];
    keep(gate_sat_build_strips(
        &tex,
        black_box(&mut table3[..]),
        black_box(3),
    ));
    gate_row_stream_builder_into(
        &tex,
        black_box(&mut row[..]),
        black_box(&mut table3[..]),
        black_box(8),
    );

    if let Some(sat) = black_box(sat.or(sat2)) {
        let from = gate_sat_from_table(black_box(sat.entries()), w, h, black_box(8));
        let sat = black_box(from.unwrap_or(sat));
        gate_sat_accessors(&sat, x, y);
        gate_sat_quad(&sat, black_box([1, 4]), black_box([0, 3]));
        gate_batch(&sat, &rect_fix, &rect_int);

        let s0 = gate_box_sum_int_border(&sat, &rect_int);
        gate_box_sum_inside(&sat, &rect_int);
        gate_box_sum_int_clamp(&sat, &rect_int);
        gate_box_sum_int_repeat(&sat, &rect_int);
        gate_box_sum_int_mirror(&sat, &rect_int);
        gate_box_sum_int_repeat_within(&sat, &rect_int);
        let s1 = gate_box_sum_paper_border(&sat, &rect_fix);
        gate_box_sum_paper_clamp(&sat, &rect_fix);
        gate_box_sum_paper_repeat(&sat, &rect_fix);
        gate_box_sum_paper_mirror(&sat, &rect_fix);
        gate_box_sum_stable_border(&sat, &rect_fix);
        gate_box_sum_stable_clamp(&sat, &rect_fix);
        gate_box_sum_stable_repeat(&sat, &rect_fix);
        gate_box_sum_stable_mirror(&sat, &rect_fix);
        gate_box_sum_stable_repeat_within(&sat, &rect_fix);
        gate_box_sum_paper_repeat_within(&sat, &rect_fix);
        let tally = gate_box_sum_stable_repeat_tally(&sat, &rect_fix);

        let tol = black_box([1u64, 4]);
        gate_box_mean_shortcut_paper_border(&sat, &rect_fix, tol, out_frac_bits);
        gate_box_sum_raw(&sat, &rect_fix, tol, out_frac_bits);
        gate_box_mean_shortcut_stable_clamp(&sat, &rect_fix, tol, out_frac_bits);
        gate_box_mean_shortcut_stable_repeat(&sat, &rect_fix, tol, out_frac_bits);
        gate_box_mean_shortcut_paper_mirror(&sat, &rect_fix, tol, out_frac_bits);

        if let Some(sum) = black_box(s1.or(s0)) {
            gate_mean_rounded(&sum, black_box(0), out_frac_bits);
            gate_means_rounded(&sum, out_frac_bits);
            gate_mean_rounded_u32(&sum, black_box(0), out_frac_bits);
            #[cfg(feature = "defmt")]
            gate_defmt_format(
                &black_box(texsat::Error::EmptyTexture),
                &sum,
                &rect_int,
                &black_box(Shortcut::with_min_side(4)),
                &tally,
            );
        }
        keep(tally);
    }

    // Layouts.
    let mut words = [0u32; MAX_WORDS];
    let mut words2 = [0u32; MAX_WORDS];
    let mut scratch = [0 as En; 8 * (MAX_SIDE + 1)];
    let tiled = gate_tiled_build(
        &tex,
        black_box([4, 4]),
        black_box(&mut words[..]),
        black_box(&mut scratch[..]),
    );
    let tiled2 = gate_tiled_builder(
        &tex,
        black_box([2, 4]),
        black_box(&mut words2[..]),
        black_box(&mut scratch[..]),
    );
    if let Some(t) = black_box(tiled.or(tiled2)) {
        let from = gate_tiled_from_words(black_box(t.words()), black_box([4, 4]), w, h);
        let t = black_box(from.unwrap_or(t));
        gate_tiled_accessors(&t, x, y, black_box(1), black_box(0));
        gate_tiled_quad(&t, black_box([1, 4]), black_box([0, 3]));
        gate_tiled_box_sum_int(&t, &rect_int);
        gate_tiled_box_sum(&t, &rect_fix);
    }

    let mut mwords = [0u32; MAX_WORDS];
    let mut mwords2 = [0u32; MAX_WORDS];
    let modular = gate_modular_build(
        &tex,
        black_box(64),
        black_box(&mut mwords[..]),
        black_box(&mut row[..]),
    );
    let modular2 = gate_modular_builder(
        &tex,
        black_box(16),
        black_box(&mut mwords2[..]),
        black_box(&mut row[..]),
    );
    if let Some(m) = black_box(modular.or(modular2)) {
        let from = gate_modular_from_words(black_box(m.words()), w, h, black_box(14));
        let m = black_box(from.unwrap_or(m));
        gate_modular_accessors(&m, x, y);
        gate_modular_quad(&m, black_box([1, 4]), black_box([0, 3]));
        gate_modular_box_sum_int(&m, &rect_int);
        gate_modular_box_sum(&m, &rect_fix);
    }

    // u16 tables.
    let mut table16 = [0 as En16; MAX_TEXELS];
    gate_u16_sat(
        &tex,
        black_box(&mut table16[..]),
        &rect_fix,
        &rect_int,
        out_frac_bits,
    );
    let mut words16 = [0u32; MAX_WORDS];
    let mut row16 = [0 as En16; MAX_SIDE];
    gate_u16_modular(
        &tex,
        black_box(14),
        black_box(&mut words16[..]),
        black_box(&mut row16[..]),
        &rect_fix,
        &rect_int,
        out_frac_bits,
    );

    // Filters.
    #[cfg(feature = "filter-point")]
    gate_point(&tex, &rect_fix);

    #[cfg(any(
        feature = "filter-mip",
        feature = "filter-rip",
        feature = "filter-dip",
        feature = "filter-tent"
    ))]
    gate_level_log2_fixed(black_box(3 << 12), black_box(8), black_box(8));

    #[cfg(feature = "filter-mip")]
    {
        use mip_gates::*;
        let mut storage = [0 as Tx; MAX_TEXELS];
        if let Some(p) = black_box(gate_mip_build(&tex, black_box(&mut storage[..]))) {
            gate_mip_queries(&p, &rect_fix, black_box(1), x, y);
            gate_mip_point_sample(&p, &rect_fix);
            gate_mip_trilinear(&p, &rect_fix);
        }
    }

    #[cfg(feature = "filter-rip")]
    {
        use rip_gates::*;
        let mut storage = [0 as Tx; 4 * MAX_TEXELS];
        let flash = [0 as Tx; 4 * MAX_TEXELS]; // stands for levels built elsewhere
        let built = gate_rip_build(&tex, black_box(&mut storage[..]));
        if let Some(map) = black_box(built) {
            let from = gate_rip_from_storage(black_box(&flash[..]), w, h);
            let map = black_box(from.unwrap_or(map));
            gate_rip_queries(&map, black_box(1), black_box(2), x, y);
            gate_rip_sample(&map, &rect_fix);
        }
    }

    #[cfg(feature = "filter-dip")]
    {
        use dip_gates::*;
        use texsat::filters::dip::{DipFilter, DipPyramid};
        let mut storage = [0 as Tx; 3 * MAX_TEXELS];
        let flash = [0 as Tx; 3 * MAX_TEXELS]; // stands for pyramids built elsewhere
        let built = gate_dip_build(&tex, black_box(&mut storage[..]));
        if let Some(map) = black_box(built) {
            let from = gate_dip_from_storage(black_box(&flash[..]), w, h);
            let map = black_box(from.unwrap_or(map));
            let pyramid = black_box(DipPyramid::Column);
            gate_dip_queries(&map, pyramid, black_box(1), x, y);
            gate_dip_sample(&map, &rect_fix, black_box(DipFilter::Bilinear));
            gate_dip_sample(&map, &rect_fix, black_box(DipFilter::Trilinear));
            #[cfg(feature = "defmt")]
            gate_defmt_format_dip(&pyramid, &black_box(DipFilter::Trilinear));
        }
    }

    #[cfg(feature = "filter-tent")]
    {
        use tent_gates::*;
        let mut q = [0 as Te; (MAX_SIDE + 1) * (MAX_SIDE + 1)];
        let mut lines = [0 as Te; 2 * MAX_SIDE * (MAX_SIDE + 1)];
        let table = gate_tent_table_build(&tex, black_box(&mut q[..]));
        let lines = gate_tent_lines_build(&tex, black_box(&mut lines[..]));
        if let (Some(q), Some(l)) = black_box((table, lines)) {
            gate_tent_queries(&q, &l, x, y);
            gate_tent_width_u128(x, y);
            gate_tent_sample_int(&q, black_box([3, 2]), black_box([2, 3]));
            gate_tent_sample(&q, &rect_fix);
            gate_tent_sample_exact(&q, &l, &tex, &rect_fix);
        }
    }

    #[cfg(feature = "filter-variance")]
    {
        use variance_gates::*;
        let mut values = [0 as En; MAX_TEXELS];
        let mut squares = [0 as En; MAX_TEXELS];
        let mut squares2 = [0 as En; MAX_TEXELS];
        keep(gate_squares_build(&tex, black_box(&mut squares2[..])));
        let built = gate_variance_build(
            &tex,
            black_box(&mut values[..]),
            black_box(&mut squares[..]),
        );
        if let Some(v) = black_box(built) {
            gate_variance_queries(&v, x, y);
            gate_variance_int(&v, &rect_int);
            gate_variance_paper(&v, &rect_fix);
            gate_variance_stable(&v, &rect_fix);
        }
    }

    #[cfg(all(feature = "defmt", feature = "filter-point"))]
    gate_defmt_format_sample(&black_box(texsat::filters::Sample { values: [1 << 16] }));

    loop {
        core::hint::spin_loop();
    }
}
