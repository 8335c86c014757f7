//! Vectorized build rows for x86-64 (cargo feature `simd`): the one module of the crate with
//! `unsafe` code.
//!
//! The portable build ([`crate::table`]) keeps one running sum along the row, a chain of
//! dependent additions that no compiler vectorizes: about one entry per cycle. Here a row is cut
//! into blocks of 16 texels; each block's inclusive prefix sums are computed in registers,
//! independently of the other blocks, and only the block's totals join the running sum (one or
//! two vector additions per 16 entries on the dependency chain). Each entry is then `prefix +
//! running sum +
//! entry above`: the same value as the portable build's `r(i, j) + entry(i, j - 1)` (integer
//! addition is associative and, under the width proof, nothing wraps), so tables are identical
//! bit for bit (tests below compare them exhaustively on small sizes; host-tests by proptest).
//!
//! Covered: `u8` texels into `u32` entries, one channel, the unchecked build (after the width
//! proof) of [`crate::Sat::build`], [`crate::Sat::build_strips`], [`crate::RowStreamBuilder`]
//! and the modular builder's rows; the tiled builder's row step ([`tiled_row`]: the row's sums,
//! the fold of the level below and the split into local sums and tile boundaries in one pass,
//! with AVX-512 VNNI for tiles of 2 to 16 texels or AVX2 for tiles of 8; with AVX-512BW and
//! VBMI as well, the local sums of tiles of 8 packed in the same pass, for the rows the band
//! rows below do not take). Everything else (and
//! [`crate::Sat::build_checked`]) takes the portable path. Also, with AVX-512 or AVX2,
//! [`pack_u32`]: the packing of `u32` fields of 11 to 32 bits into 32-bit words that the
//! modular and tiled builders do per row (the portable packer, width-specialized scalar code,
//! costs about a cycle per field; the AVX2 kernel, eight groups of 32 fields transposed into
//! lanes, about a third to a half of it); and, with AVX2 (on AVX-512 CPUs too),
//! [`modular_row`]: the modular builder's whole row (prefix sums, working row and packing) in
//! one pass per 256 texels, the working row kept transposed (with AVX-512 VL, in a layout past
//! the caches, its words stored by non-temporal stores); and, with AVX2 (on AVX-512 CPUs
//! too), [`band_row`]: the tiled builder's rows inside a tile row (tiles 8 wide, a layout
//! without a modulus whose tiles' sums fit 16 bits),
//! the level-0 accumulator kept as 16-bit column sums and the local sums packed from 16 bits
//! ([`pack256::even`], which also packs `u32` fields of 12 and 14 bits for [`pack_u32`]; with
//! AVX-512BW, DQ and VBMI as well, `band512::row_packed` packs them in the row step itself,
//! 32 columns at a time, and stores no 16-bit values); [`band_end_row`]: the rows that end a
//! tile row, which add the column sums' form into the level above (with AVX-512BW and DQ as
//! well, `band512::end_row_packed` packs both components' rows in the same pass, 256 columns at a
//! time); [`band_flush`] turns the column sums back into the accumulator. The kernel is the
//! widest this CPU runs, detected once at run time from CPUID and XGETBV (no `std` needed), as
//! OpenCV and the standard
//! library's `is_x86_feature_detected!` do; the binary needs no `-C target-cpu` flag:
//!
//! * AVX-512 VNNI (`avx512f` + `avx512vl` + `avx512vnni`): the 8 prefix sums of each half
//!   block are two 256-bit `vpdpbusd` dot products of a broadcast group of 4 texels with a
//!   constant triangle of 0/1 weights, straight into 32-bit lanes: no shifts, no widening.
//! * AVX2: the same dot products, per 8 texels: two broadcast groups of 4 texels times 0/1
//!   weights by `vpmaddubsw` (16-bit pairs), added, then `vpmaddwd` with ones (32-bit lanes);
//!   only the two 8-lane totals take a lane-crossing permute.
//! * SSE2 (every x86-64): the same in two 8-lane halves.
//!
//! Why 16-bit lanes suffice for the in-block prefix: 16 texels of at most 255 sum to at most
//! 4080 < 2^16.
//!
//! `Sat::build` of a table of [`WORKING_ROW_MIN_BYTES`] (1 MiB) and more builds each row in a
//! working row on the stack, which stays in L1, and writes it to the table in the same pass
//! ([`build_via_working_row`]): the next row reads the row above from L1, not from table lines
//! whose reads for ownership may still be on their way from memory. Tables of
//! [`STREAM_MIN_BYTES`] (32 MiB) and more, which would not stay in cache anyway, are written by
//! non-temporal stores (`movntdq`, 16 bytes each): those rows of `Sat::build` and the copy of
//! `RowStreamBuilder::push_row_into`. A non-temporal store writes its line without first
//! reading it for ownership, which halves a cold table's memory traffic; such a table is not
//! left in cache after the build.
//!
//! # Safety argument
//!
//! 1. *Target features.* Each kernel is a `#[target_feature]` function; it is called only as
//!    [`Kernel::best`], the widest kernel whose features CPUID reports and whose registers the
//!    operating system saves (XCR0), per the Intel SDM's detection procedure (SSE2 is part of
//!    the x86-64 baseline; the AVX-512 kernel's detection includes AVX2's, so the AVX2 code
//!    also runs under it: the band rows and the fused modular row, whose streamed form
//!    `modular256::row_streamed` also enables AVX-512F and VL, which that detection includes
//!    too); the tiled packing kernels `tiled512::kernel8_packed` and `band512::row_packed`
//!    (AVX-512BW and VBMI as well; the latter DQ too) and `band512::end_row_packed` (AVX-512F,
//!    VL, BW and DQ) only when [`vbmi`] also reports those (CPUID leaf 7, on top of the AVX-512
//!    kernel's detection).
//!    Under Miri, which cannot execute CPUID, the kernel is the one the build's target
//!    features enable. The AVX-512 build kernel's 256-bit `vpdpbusd` needs AVX-512 VL, which
//!    its detection includes (CPUID leaf 7 EBX bit 31). The helpers with target features of
//!    their own ([`lane7`], `modular256::field_mask`, `pack256::rows8x8`: AVX2;
//!    `modular256::perm2`: AVX2, AVX-512F and VL; `pack512::pack_k` uses it too) are called only
//!    from functions that enable them (the compiler refuses other callers without `unsafe`).
//!    Calling the kernels (and XGETBV, after CPUID reports OSXSAVE) is the only reason for `unsafe`
//!    beyond the memory accesses below.
//! 2. *Memory.* [`pack_u32`] passes its AVX-512 kernel `groups` with `32 groups <=
//!    fields.len()` and `groups k <= words.len()`; the kernel reads `fields[32 g..32 g + 32]` and
//!    writes `words[g k..g k + k]` for `g < groups` (16 words, then the rest: 16 words, or 8 for
//!    `k` = 17 to 24; a whole store past `g k + k` reaches the next group's words, inside
//!    `words[..groups k]`, which that group rewrites after; the last group's last store is masked
//!    to its own words) only. It passes its AVX2 kernel `runs` (of 16 fields, `2 k` bytes) with `16
//!    runs <= fields.len()` and `2 k runs <= 4 words.len()` bytes; the kernel reads
//!    `fields[..16 runs]` and writes the first `2 k runs` bytes of `words` only (8 words at a
//!    time, then a group's last 4 or 8 words, some of them a second time with the same value;
//!    a last pass of fewer than 8 groups or runs reads its last one again for the missing
//!    lanes and stores the ones it has only; an odd `k`'s last run word by word, its last
//!    word's low 16 bits only).
//!    [`modular_row`] checks `acc.len() >= 256 p` and `words.len() >= 8 k p` (`p >= 1` passes of
//!    256 texels, `p = floor(texels.len() / 256)`) before its kernel reads `texels[256 b..][..256]`
//!    and reads and writes (one 8-lane load and store per field) `acc[s + 256 b..][..256]` for
//!    `b < p - 1` and `acc[s + 256 (p - 1)..][..248]` (`s < 8` the rotation, so `s + 256 p - 8
//!    < acc.len()`) and the last pass's last 8 values at `last`: `acc[s + 256 p - 8..][..8]`
//!    when `s + 256 p <= acc.len()`, else a 32-byte buffer on the stack gathered from
//!    `acc[s + 256 p - 8..]` and `acc[..s + 256 p - acc.len()]` before the kernel (both ranges
//!    checked) and scattered back after it; and it
//!    writes `words[8 k b..][..8 k]` (the packer's stores of each group's `k` words; streamed,
//!    `k` 8-word vectors at `8 k b + 8 v`, `v < k`, each by two non-temporal 16-byte stores,
//!    only after checking that `words` starts on 16 bytes: `32 k` bytes per pass keep every
//!    one aligned, and the row ends with an `sfence`) for `b < p` only.
//!    [`tiled_row`] checks its slices' lengths against the row (`acc`, `lower`: `n`; `bnd`:
//!    `n / tile`; `local`: `n - n / tile`) before its kernel touches block `b` (16 texels) of
//!    `t`, `acc` and `lower` for `b < n / 16` only; the boundary and local-sum stores stay inside
//!    the values the whole row writes (a 16- or 8-lane store whose last lanes the next block
//!    overwrites, a masked store or a copy of the exact count for the last block; see the
//!    kernels); the prefetches of `ahead` access no memory. With a packing target
//!    ([`PackTo`]), it checks that the bytes the pairs of blocks pack into (`7 k / 2` per pair,
//!    from byte `bit / 8`) lie inside the target's words before `tiled512::kernel8_packed`
//!    writes them: pair `p`'s `7 k / 2` bytes by one full 64-byte store only when it ends
//!    inside those bytes (`7 k / 2 p + 64 <= 7 k / 2 pairs`; its excess lies in the later pairs'
//!    bytes, which their own stores rewrite, in order), else by a masked byte store of exactly
//!    its bytes (the lanes past them masked off: not accessed). The first byte starts at the
//!    row's first bit and the last ends on a byte boundary, so no bit outside the row's fields
//!    is written.
//!    [`band_row`] checks `acc0.len() = n`, `bnd.len() >= n / 8` and `local.len() >= n - n /
//!    8` (its 16-bit local sums, `14 (n / 16) + 1` with the last block's overhang, and the
//!    tail's, fit the `2 (n - n / 8)` halves of `local`'s words) before its kernel touches
//!    block `b < n / 16`: texels `t[16 b..][..16]`, column sums `u16` `c + 16 b..` of `acc0`'s
//!    `2 n` halves (`c` = [`column_sums_at`], `n - 15 <= c <= n`), local sums
//!    `14 b..14 b + 15`, boundaries `2 b`, `2 b + 1` (for four blocks `b..b + 4` at once,
//!    `b + 4 <= n / 16`: boundaries `2 b..2 b + 8`, one store). With
//!    `band512::row_packed` it touches pair `p < n / 32` instead (texels `t[32 p..][..32]`,
//!    column sums `u16` `c + 32 p..` (32), boundaries `4 p..4 p + 4`), after checking that the
//!    `7 k / 2` bytes per pair from byte `bit / 8` lie inside the target's words, and writes
//!    them as `tiled512::kernel8_packed` does (a full 64-byte store only when it ends inside
//!    those bytes, else a masked store of exactly the pair's); the 16-bit values of the tail
//!    go to `local`'s halves from `28 (n / 32)` on, and [`pack256::even`] packs whole steps of
//!    them right after the pairs' bytes (which end on a byte: `k` is even), from byte
//!    `bit / 8 + 7 k / 2 (n / 32)`, after the same check for its bytes. It packs
//!    from 16 bits into the target's words only after checking that the `2 k` bytes per 16
//!    fields from byte `bit / 8` lie inside them ([`pack256::even`] writes the last step's
//!    bytes as two 8-byte pieces ending on its last byte: exactly `2 k steps` bytes); then it
//!    widens the rest in place, last
//!    first (word `j` holds halves `2 j` and `2 j + 1`, read already). [`band_end_row`]
//!    checks the same lengths (and `acc.len() >= n`) before its kernels touch block `b < n /
//!    16` as [`band_row`]'s AVX2 kernel does, with `acc[16 b..][..16]` read and written. With
//!    a packing target ([`EndPackTo`]) `band512::end_row_packed` takes the first `c` chunks
//!    of 256 columns, `c` at most `n / 256`, `wl.len() / (7 kl)` and `wb.len() / kb`: chunk
//!    `j` touches texels, column sums and `acc` `256 j..256 j + 256`, two buffers on its own
//!    stack (the gathers of 8 steps: 28 words each, stored 32 from `28 s`, into 228; 4 each
//!    into 32), and writes words `7 kl j..7 kl (j + 1)` and `kb j..kb (j + 1)` of the two
//!    rows ([`pack_u32`]'s AVX-512 kernel's stores); the AVX2 kernel goes on from block `16
//!    c`. [`band_rows`] checks `acc0.len() = n`, `r n / 8` boundaries and the rows' bytes in
//!    the target before its kernels, which touch each row as [`band_row`]'s do; on AVX2 each
//!    row's 16-bit local sums go to `u16` `0..n - n / 8 + 1` of `acc0`'s halves, below `c`
//!    (`n >= 128`: at most `n - 15`). [`band_flush`] first moves the column sums from `c` to
//!    `n` (one overlapping copy inside the `2 n` halves), then rewrites `acc0` in place,
//!    forward: word `i` holds the halves of column sums `2 i - n` and `2 i + 1 - n`, at most
//!    `i`, which a block reads before it writes its words.
//!    [`row_u8_u32`] takes slices, `n = min(len)` over all of them; it does the head (the
//!    `h` entries before `out` reaches 32 bytes: `h < 8`, `h <= n`, and `h = 0` for rows built
//!    into a table, for rows that end before 32 bytes, where a non-temporal copy would
//!    leave 16 bytes, and where [`takes_heads`] says no) with checked indexing and passes the
//!    kernels each slice from `h` on, `n - h` entries. A kernel touches entries `i..i + 16` of
//!    those slices only while `i + 16 <= n - h`, through unaligned loads and stores
//!    (`loadu`/`storeu`, or `read_unaligned` for the 4-byte groups), then the tail is finished
//!    with checked indexing. Every pointer is derived from its slice and stays in bounds. The
//!    copy's stores are non-temporal (`_mm_stream_si128`, which faults on an address off 16
//!    bytes) only when [`row_u8_u32`] has checked that the copy starts on 16 bytes, and then
//!    `h` is 0 or 4: block `b`'s four 16-byte stores are at `4 h + 64 b`, `4 h + 64 b + 16`,
//!    ... bytes from it, all aligned; the head's and the tail's whole 4 entries are stored
//!    non-temporally only where `copy_run` finds them on 16 bytes. Each row whose copy took
//!    non-temporal stores ends with an `sfence`, so they are ordered before every later store
//!    (the table is handed out, possibly to another thread, through ordinary release/acquire
//!    synchronization, which does not order weakly ordered stores by itself). Under Miri,
//!    which cannot run them (inline assembly in stdarch), plain stores stand in.
//! 3. *Aliasing.* `above` and `out` are separate slices (`&[u32]`, `&mut [u32]`) except in the
//!    in-place working row, where the kernel gets the single `&mut [u32]` and reads the row
//!    above through the same pointer it writes: each step (a block of 16, or with AVX-512 half
//!    a block) reads `row[j..j + s]` before it writes those same entries, and no step reads
//!    what another wrote. The optional copy of the working row is a third, separate `&mut
//!    [u32]` (at least `n` long). [`modular_row`]'s kernel gets `acc`'s pointers (the passes'
//!    values and, when in place, the last vector) from one `&mut` borrow, or the last vector
//!    in its own stack buffer, disjoint from the values the passes touch. No reference is
//!    created from the raw pointers.
//! 4. *Type casts.* [`build_row`] and the other entry points see `&[T]` as `&[u8]` and `&mut
//!    [E]` as `&mut [u32]` through `crate::cast` (safe functions whose own safety argument is
//!    `TypeId` equality: `T = u8` and `E = u32`, the same type, the same length). The band
//!    rows read and write `u32` words as pairs of `u16` halves through raw pointers derived
//!    from the one slice (any bit pattern is a valid `u16` and `u32`; `u16`'s alignment
//!    divides `u32`'s); no reference of the other type is created.
#![allow(unsafe_code)]
#![allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "x86-64 host code (never the firmware): indices and offsets are bounded by `n` as the \
              safety argument states; `as` casts reinterpret lanes between i32 and u32"
)]

use core::any::TypeId;
use core::arch::x86_64::*;
use core::sync::atomic::{AtomicU8, Ordering};

use crate::cast;
use crate::texel::{Entry, Texel};

/// Where the row above comes from.
#[derive(Clone, Copy)]
enum Above {
    /// The first row: zero above.
    Zero,
    /// A separate slice of the same length.
    Slice,
    /// The output row itself (in-place streaming).
    InPlace,
}

/// `out = prefix sums of texels + above` for `u8` texels, `u32` entries and one channel;
/// `false` (nothing written) for any other types, which then take the portable path.
#[inline]
pub(crate) fn build_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    above: Option<&[E]>,
    out: &mut [E],
) -> bool {
    let (Some(t), Some(out)) = (cast::u8s(texels), as_u32_mut::<E, C>(out)) else {
        return false;
    };
    match above {
        None => row_u8_u32(Kernel::for_rows(), t, &[], out, Above::Zero, None, false),
        Some(a) => match cast::u32s(a) {
            Some(a) => row_u8_u32(Kernel::for_rows(), t, a, out, Above::Slice, None, false),
            None => return false,
        },
    }
    true
}

/// [`build_row`] in place: `row` holds the row above on entry (ignored if `first`) and the new
/// row on exit; with `copy`, the new row is also written there (same length as `row`) in the
/// same pass, by non-temporal stores if `stream` (see [`STREAM_MIN_BYTES`]).
#[inline]
pub(crate) fn build_row_in_place<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    row: &mut [E],
    first: bool,
    copy: Option<&mut [E]>,
    stream: bool,
) -> bool {
    let (Some(t), Some(row)) = (cast::u8s(texels), as_u32_mut::<E, C>(row)) else {
        return false;
    };
    let copy = match copy {
        None => None,
        Some(c) => match as_u32_mut::<E, C>(c) {
            Some(c) if c.len() == row.len() => Some(c),
            _ => return false,
        },
    };
    let mode = if first { Above::Zero } else { Above::InPlace };
    row_u8_u32(Kernel::for_rows(), t, &[], row, mode, copy, stream);
    true
}

/// The smallest table (in bytes) whose copy stores are non-temporal
/// ([`RowStreamBuilder::push_row_into`](crate::RowStreamBuilder::push_row_into),
/// [`build_via_working_row`]): 32 MiB, past the last-level cache of the machines measured
/// (32 MiB of L3), so the table would not stay in cache anyway. A non-temporal store writes
/// its line without reading it first (no read for ownership), which halves a cold table's
/// memory traffic: on a Zen 4 guest, `Sat::build` of a 4,096^2 table (64 MiB) took 0.75x the
/// time with them (1.37x the widen-copy floor before, 1.07x after) and `push_row_into` 0.71x;
/// with the threshold at 4 MiB, a 1,024^2 table took 1.31x and 1.73x the time: a table that
/// fits the cache is better written through it (docs/benchmarks.md, sixth session).
pub(crate) const STREAM_MIN_BYTES: usize = 32 << 20;

/// Whether a table or layout of `bytes` is past the caches ([`STREAM_MIN_BYTES`]): the one
/// test behind the streamed builds and the modular row's streamed stores or prefetch hints.
#[inline]
pub(crate) const fn past_the_caches(bytes: usize) -> bool {
    bytes >= STREAM_MIN_BYTES
}

/// The smallest table (in bytes) that `Sat::build` builds through a working row
/// ([`build_via_working_row`]): 1 MiB, an L2 cache of the machines measured. Built straight
/// into the table, each row reads the row above from the table, whose lines were just stored
/// to: in a cold table their reads for ownership may still be in flight, and the loads wait
/// for them. On a Zen 4 guest, cold (96 MiB touched between builds), `Sat::build` of 1,024^2
/// took 0.32 to 0.37 ns per texel straight and 0.23 to 0.27 through the working row (the
/// widen-copy floor 0.24 to 0.25), 2,048^2 0.31 against 0.25; with the table in cache the two
/// were even at 1,024^2, and at 256^2 (256 KiB, in L2) the working row's extra store took
/// 1.1x the time (docs/benchmarks.md, eighth session).
pub(crate) const WORKING_ROW_MIN_BYTES: usize = 1 << 20;

/// The widest row [`build_via_working_row`] takes: its working row is at most 16 KiB (inside a
/// 20 KiB buffer on the stack, [`ALIAS_PAD`]), which stays in a 32 KiB L1 data cache beside
/// the row's texels.
pub(crate) const WORKING_ROW_MAX: usize = 4096;

/// [`build_via_working_row`]'s working row's room to move within its buffer: 1,024 entries
/// (4 KiB), so that the row can start anywhere modulo 4 KiB.
const ALIAS_PAD: usize = 1024;

/// A 128-bit copy store: non-temporal if `nt` (which needs `to` 16-byte aligned), else
/// unaligned. Under Miri, which cannot run `movntdq` (stdarch writes it as inline assembly),
/// always the plain store: Miri still checks the address and the bytes written.
///
/// # Safety
/// The CPU has SSE2 (x86-64 baseline); `to` is valid for writes of 16 bytes and, if `nt`,
/// 16-byte aligned.
#[inline(always)]
unsafe fn store_copy(to: *mut u32, v: __m128i, nt: bool) {
    // Under Miri too, where the store is plain: the address a non-temporal store would need.
    debug_assert!(!nt || (to as usize).is_multiple_of(16));
    // SAFETY: the caller's contract.
    unsafe {
        if nt && !cfg!(miri) {
            #[cfg(not(miri))]
            _mm_stream_si128(to.cast(), v);
        } else {
            _mm_storeu_si128(to.cast(), v);
        }
    }
}

/// Orders the non-temporal stores before every later store (`sfence`): they are weakly
/// ordered, and the table is handed out (possibly to another thread) after the build. Not
/// under Miri (inline assembly in stdarch; the stores there are plain).
#[inline]
fn fence() {
    #[cfg(not(miri))]
    // SAFETY: SSE is baseline on x86-64.
    unsafe {
        _mm_sfence()
    };
}

/// `Sat::build`'s rows through a working row: for `u8` texels, `u32` entries and one channel,
/// a table of at least [`WORKING_ROW_MIN_BYTES`] whose rows are at most [`WORKING_ROW_MAX`]
/// entries. Each row is built in a working row on the stack (the row above stays in L1
/// instead of being read back from the table) and written to the table in the same pass
/// (`row(y)` gives texture row `y`); by non-temporal stores for a table of at least
/// [`STREAM_MIN_BYTES`], each row that starts on 16 bytes (every row when the table does and
/// `width` is a multiple of 4; the others by plain stores). `false`, with nothing written,
/// where it does not apply, including when `row` lacks a row `y < height` of `width` texels
/// (checked for every row before the first is written; the caller's own loop then reports
/// it). `row` is called twice per row and must give the same row each time (the caller passes
/// `Texture::row`).
///
/// Also `false` below [`STREAM_MIN_BYTES`] where the flat rows take SSE2's kernel in place of
/// AVX2's ([`Kernel::for_rows`]: Zen, Zen+): there the working row's second store per entry
/// costs more than the reads it saves. On a Zen 1 guest, `Sat::build` of 1,024^2 took 0.91x
/// the time straight into the table, both back to back and after 64 MiB written between
/// builds (1.09x the widen-copy floor against 1.19x; docs/benchmarks.md, nineteenth
/// session).
#[inline(never)]
pub(crate) fn build_via_working_row<'t, T: Texel + 't, E: Entry, const C: usize>(
    table: &mut [E],
    width: usize,
    row: impl Fn(usize) -> Option<&'t [T]>,
) -> bool {
    let Some(out) = as_u32_mut::<E, C>(table) else {
        return false;
    };
    let bytes = out.len().saturating_mul(4);
    if TypeId::of::<T>() != TypeId::of::<u8>()
        || width == 0
        || width > WORKING_ROW_MAX
        || out.len() % width != 0
        || bytes < WORKING_ROW_MIN_BYTES
        || (Kernel::for_rows() != Kernel::best() && !past_the_caches(bytes))
    {
        return false;
    }
    // Every row exists and has `width` texels, so that a `false` below never follows a write.
    let rows = out.len() / width;
    if !(0..rows).all(|y| row(y).is_some_and(|t| t.len() == width)) {
        return false;
    }
    // The working row starts on a cache line (a row 16 bytes off one, where the stack first
    // put it, split every 64-byte access in two: `Sat::build` took 1.5x to 1.7x the widen-copy
    // floor at 4,096^2 instead of 1.1x), 2 KiB from the table's first row modulo 4 KiB (a load
    // from it then never matches the low 12 address bits of a recent store to the table, which
    // the CPU would hold up as a possible overlap). Every row keeps that distance when `4
    // width` is a multiple of 4 KiB (1,024, 2,048, 4,096); otherwise it moves by `4 width` mod
    // 4 KiB per row, and only some rows keep clear of the aliasing.
    let mut buf = [0u32; WORKING_ROW_MAX + ALIAS_PAD];
    let want = (out.as_ptr() as usize).wrapping_add(2048) & !63;
    let gap = want.wrapping_sub(buf.as_ptr() as usize) % 4096 / 4;
    let Some(work) = buf.get_mut(gap..gap.saturating_add(width)) else {
        return false;
    };
    let stream = past_the_caches(bytes);
    for (y, copy) in out.chunks_exact_mut(width).enumerate() {
        // Checked above: every row is there, `width` texels of `u8`.
        let t = row(y).and_then(cast::u8s).unwrap_or(&[]);
        let mode = if y == 0 { Above::Zero } else { Above::InPlace };
        row_u8_u32(Kernel::for_rows(), t, &[], work, mode, Some(copy), stream);
    }
    true
}

/// `s` as `u32` entries of one channel (`C = 1`), for the row kernels ([`cast::u32s_mut`]).
fn as_u32_mut<E: Entry, const C: usize>(s: &mut [E]) -> Option<&mut [u32]> {
    if C == 1 {
        cast::u32s_mut(s)
    } else {
        None
    }
}

/// One row with `kernel` (which must be [`Kernel::available`]); `above` is read only for
/// [`Above::Slice`]; `copy` (at least as long as `out`) receives the row too, by non-temporal
/// stores if `stream` and it starts on 16 bytes ([`STREAM_MIN_BYTES`]).
///
/// A working row (the row above in place, [`Above::InPlace`], or none yet, [`Above::Zero`]),
/// where [`takes_heads`] says so (every CPU but AMD's Zen 5 and later): the entries before
/// `out` reaches 32 bytes (up to 7, the head) go first, and the kernel starts after them with
/// their running sum, so that its 32-byte loads and stores of the working row never straddle
/// two cache lines. The head goes the portable way, as the tail after the last block does.
/// The builders' working rows are the caller's storage, anywhere on 4 bytes: on a Zen 4
/// guest, one 16 bytes off 32 made `RowStreamBuilder::push_row_into` take 1.4x to 1.5x the
/// flat build's time at 4,096^2 (1.0x with the head) and 1.3x its own time at 500^2
/// (docs/benchmarks.md, ninth session). A head that would move a non-temporal copy off 16
/// bytes is not taken. Rows built into a table after its first ([`Above::Slice`], `Sat::build`
/// below [`WORKING_ROW_MIN_BYTES`]) take no head: with it, a table of rows 16 bytes off 32
/// (512 x 480) took 1.08x to 1.13x the time. All the row's non-temporal stores (the kernel's
/// and `copy_run`'s) are followed by one `sfence`.
#[inline]
fn row_u8_u32(
    kernel: Kernel,
    texels: &[u8],
    above: &[u32],
    out: &mut [u32],
    mode: Above,
    mut copy: Option<&mut [u32]>,
    stream: bool,
) {
    let mut n = out.len().min(texels.len());
    if let Above::Slice = mode {
        n = n.min(above.len());
    }
    if let Some(c) = &copy {
        n = n.min(c.len());
    }
    // Non-temporal copy stores need the copy 16-byte aligned (each block's stores are then
    // too: 16 entries, 64 bytes apart).
    let nt = stream
        && copy
            .as_ref()
            .is_some_and(|c| (c.as_ptr() as usize).is_multiple_of(16));
    // The entries before `out` reaches 32 bytes (none for rows built into a table, nor where
    // the CPU takes no head).
    let to_line = match mode {
        Above::Slice => 0,
        Above::Zero | Above::InPlace if takes_heads() => {
            (32 - (out.as_ptr() as usize) % 32) % 32 / 4
        }
        Above::Zero | Above::InPlace => 0,
    };
    // The head: those entries, unless the row ends before 32 bytes (no block could run) or a
    // non-temporal copy would leave 16 bytes (its head must be 0 or 4).
    let head = if to_line > n || (nt && !to_line.is_multiple_of(4)) {
        0
    } else {
        to_line
    };
    let start = row_portable(texels, above, out, mode, 0..head, 0);
    copy_run(out, copy.as_deref_mut(), 0..head, nt);
    let m = n - head;
    let t = texels[head..].as_ptr();
    let o = out[head..].as_mut_ptr();
    let o2: *mut u32 = match &mut copy {
        Some(c) => c[head..].as_mut_ptr(),
        None => core::ptr::null_mut(),
    };
    let a: *const u32 = match mode {
        Above::Zero => core::ptr::null(),
        Above::Slice => above[head..].as_ptr(),
        Above::InPlace => o.cast_const(),
    };
    // SAFETY: the CPU has the kernel's features (argument 1: every caller passes an available
    // kernel); `t`, `a` (when read), `o` and `o2` (when written) are valid for `m` elements
    // (argument 2: each is its slice from `head`, and `head + m = n` is within every slice)
    // and alias only as argument 3 allows; `o2` is 16-byte aligned when `nt` (the copy was,
    // and `head` is then a multiple of 4 entries).
    let run = unsafe {
        match (mode, o2.is_null()) {
            (Above::Zero, true) => kernel.run::<false, false>(t, a, o, o2, m, start, false),
            (Above::Zero, false) => kernel.run::<false, true>(t, a, o, o2, m, start, nt),
            (Above::Slice | Above::InPlace, true) => {
                kernel.run::<true, false>(t, a, o, o2, m, start, false)
            }
            (Above::Slice | Above::InPlace, false) => {
                kernel.run::<true, true>(t, a, o, o2, m, start, nt)
            }
        }
    };
    // The tail after the last full block, portable: the same two additions per entry.
    let tail = n - m % BLOCK..n;
    row_portable(texels, above, out, mode, tail.clone(), run);
    copy_run(out, copy, tail, nt);
    // After the row's last non-temporal store (the kernel's, or the head's and tail's).
    if nt {
        fence();
    }
}

/// [`row_u8_u32`]'s entries `range` the portable way (the head and the tail), from the running
/// sum `r`; returns the running sum after them. The indices are within the slices (the caller's
/// `n`), checked.
fn row_portable(
    texels: &[u8],
    above: &[u32],
    out: &mut [u32],
    mode: Above,
    range: core::ops::Range<usize>,
    mut r: u32,
) -> u32 {
    for i in range {
        r = r.wrapping_add(u32::from(texels[i]));
        let up = match mode {
            Above::Zero => 0,
            Above::Slice => above.get(i).copied().unwrap_or(0),
            Above::InPlace => out[i],
        };
        out[i] = r.wrapping_add(up);
    }
    r
}

/// `copy[range] = out[range]` for [`row_u8_u32`]'s head and tail: with `nt`, where the copy
/// from `range.start` is on 16 bytes, each whole 4 entries by a non-temporal store like the
/// kernel's (the caller fences after the row), the rest plain. A plain store into a line that
/// non-temporal stores also write reads the line first and splits the line's write: with a
/// plain head and tail, `push_row_into` with a working row 16 bytes off 32 took 1.13x to 1.36x
/// the flat build's time instead of 1.0x (docs/benchmarks.md, ninth session). `range` lies
/// within both slices (the caller's `n`).
fn copy_run(out: &[u32], copy: Option<&mut [u32]>, range: core::ops::Range<usize>, nt: bool) {
    let Some(copy) = copy else {
        return;
    };
    let (c, o) = (&mut copy[range.clone()], &out[range]);
    let nt = nt && (c.as_ptr() as usize).is_multiple_of(16);
    let mut cs = c.chunks_exact_mut(4);
    let mut os = o.chunks_exact(4);
    for (c4, o4) in (&mut cs).zip(&mut os) {
        // SAFETY: SSE2 (x86-64 baseline); 4 entries each (chunks_exact); with `nt` the chunk is
        // on 16 bytes (the copy from the range's start is, checked above, and each chunk is 16
        // bytes).
        unsafe { store_copy(c4.as_mut_ptr(), _mm_loadu_si128(o4.as_ptr().cast()), nt) };
    }
    cs.into_remainder().copy_from_slice(os.remainder());
}

/// `vpermd` indices that broadcast lane 7 (an 8-lane total) into every lane, opaque to the
/// compiler: LLVM turns a permute by a constant splat index into two shuffles (`vpshufd` and
/// `vpermq`); the kernels' one `vpermd` per 8 lanes measured 0.9x the time of that pair for a
/// row in L1 (the AVX2 build kernel; docs/benchmarks.md, eighth session). `black_box` is only
/// a hint: at worst the pair comes back, with the same values.
#[inline]
#[target_feature(enable = "avx2")]
fn lane7() -> __m256i {
    core::hint::black_box(_mm256_set1_epi32(7))
}

/// Lanes a kernel handles per step.
const BLOCK: usize = 16;

/// A build kernel: the widest one the CPU runs is chosen once, at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kernel {
    /// SSE2: every x86-64 CPU.
    Sse2,
    /// AVX2.
    Avx2,
    /// AVX-512F with AVX-512 VL and AVX-512 VNNI.
    Avx512Vnni,
}

/// The detected kernel: 0 before the first detection, else `1 + Kernel as u8`.
static DETECTED: AtomicU8 = AtomicU8::new(0);

#[cfg(test)]
extern crate std;

#[cfg(test)]
std::thread_local! {
    /// The calling test thread's cap on [`Kernel::best`] ([`Kernel::cap`]).
    static CAP: core::cell::Cell<Option<Kernel>> = const { core::cell::Cell::new(None) };
    /// The calling test thread's answer for [`takes_heads`] (`set_heads`).
    static HEADS: core::cell::Cell<Option<bool>> = const { core::cell::Cell::new(None) };
    /// The rows [`modular_row`] streamed on the calling test thread (tests: that the path ran).
    pub(crate) static STREAMED_ROWS: core::cell::Cell<usize> = const { core::cell::Cell::new(0) };
    /// The chunks [`band_end_row`] packed in its pass on the calling test thread (tests: that
    /// `band512::end_row_packed` ran).
    pub(crate) static END_CHUNKS: core::cell::Cell<usize> = const { core::cell::Cell::new(0) };
    /// The rows [`band_rows`] took in runs on the calling test thread (tests: that the path
    /// ran).
    pub(crate) static RUN_ROWS: core::cell::Cell<usize> = const { core::cell::Cell::new(0) };
}

impl Kernel {
    /// Every kernel, narrowest first.
    #[cfg(test)]
    pub(crate) const ALL: [Kernel; 3] = [Kernel::Sse2, Kernel::Avx2, Kernel::Avx512Vnni];

    /// Its name, for benchmarks and reports.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Kernel::Sse2 => "sse2",
            Kernel::Avx2 => "avx2",
            Kernel::Avx512Vnni => "avx512vnni",
        }
    }

    /// Whether this CPU (and its operating system, which must save the wider registers) runs
    /// the kernel: CPUID and XGETBV, read once. (The tests run every available kernel.)
    /// Under Miri, which cannot run CPUID, the widest kernel the target features the build
    /// enables allow, and only that one: each flag set of `.ci/miri.sh` tests its own kernel,
    /// and the narrower ones are their own sets' (every kernel is still tested once; with the
    /// narrower kernels too, the VBMI set's tests took 501 s instead of 290 on a Zen 3).
    #[cfg(test)]
    pub(crate) fn available(self) -> bool {
        let best = Kernel::detected();
        if cfg!(miri) {
            return self == best;
        }
        match self {
            Kernel::Sse2 => true,
            Kernel::Avx2 => best != Kernel::Sse2,
            Kernel::Avx512Vnni => best == Kernel::Avx512Vnni,
        }
    }

    /// The kernel the builds run: the widest this CPU runs ([`Kernel::detected`]; in the
    /// crate's unit tests, at most the calling thread's [`Kernel::cap`], so that they reach
    /// the narrower kernels' code paths on a CPU with wider ones).
    #[inline]
    pub(crate) fn best() -> Kernel {
        let k = Kernel::detected();
        #[cfg(test)]
        if let Some(cap) = CAP.with(|c| c.get()) {
            if (cap as u8) < (k as u8) {
                return cap;
            }
        }
        k
    }

    /// The kernel for the flat rows ([`row_u8_u32`]: `Sat::build` and the streaming builder):
    /// [`Kernel::best`], except SSE2's where that is AVX2 on a CPU that executes 256-bit
    /// operations as two 128-bit halves ([`splits_256`], Zen and Zen+). There each AVX2
    /// instruction costs two, and the AVX2 kernel's multiplies (`vpmaddubsw`, `vpmaddwd`: 6
    /// per 16 texels, 12 halves, all on the one pipe that multiplies) outweigh the shifts
    /// they save: on a Zen 1 guest (EPYC 7001) the SSE2 kernel built 1,024^2 and 4,096^2 in
    /// 0.75x and 0.72x the time; with it `Sat::build` went from 1.36x to 1.42x and 1.18x to
    /// 1.23x the widen-copy floor to 1.09x to 1.18x and 0.81x to 0.93x, also without the
    /// working row below 32 MiB (docs/benchmarks.md, nineteenth session). The layouts' AVX2
    /// kernels (modular rows, band rows, packing) have no SSE2 form and stay. In the crate's
    /// unit tests a thread's [`Kernel::cap`] names the row kernel exactly, so that every kernel
    /// is tested on every CPU.
    #[inline]
    pub(crate) fn for_rows() -> Kernel {
        let k = Kernel::best();
        #[cfg(test)]
        if CAP.with(|c| c.get()).is_some() {
            return k;
        }
        k.rows_on(splits_256())
    }

    /// [`Kernel::for_rows`] for the best kernel `self` on a CPU that splits 256-bit operations
    /// or not.
    fn rows_on(self, splits: bool) -> Kernel {
        if self == Kernel::Avx2 && splits {
            Kernel::Sse2
        } else {
            self
        }
    }

    /// Runs `f` with [`Kernel::best`] at most `self` on this thread (tests only: the other
    /// test threads keep theirs).
    #[cfg(test)]
    pub(crate) fn cap<R>(self, f: impl FnOnce() -> R) -> R {
        let before = CAP.with(|c| c.replace(Some(self)));
        let r = f();
        CAP.with(|c| c.set(before));
        r
    }

    /// The widest kernel this CPU runs (detected on the first call, then cached: a relaxed
    /// atomic, every thread detects the same).
    #[inline]
    fn detected() -> Kernel {
        match DETECTED.load(Ordering::Relaxed) {
            1 => Kernel::Sse2,
            2 => Kernel::Avx2,
            3 => Kernel::Avx512Vnni,
            _ => {
                let k = detect();
                DETECTED.store(1 + k as u8, Ordering::Relaxed);
                k
            }
        }
    }

    /// Runs the kernel over the full blocks of a row (the copy by non-temporal stores if `nt`;
    /// the caller fences after the row's last one, [`row_u8_u32`]).
    ///
    /// # Safety
    /// `self` is [`Kernel::available`]; the pointers as the kernels require (`o2` 16-byte
    /// aligned if `COPY` and `nt`).
    #[inline]
    #[allow(
        clippy::too_many_arguments,
        reason = "the kernels' arguments, forwarded"
    )]
    unsafe fn run<const ABOVE: bool, const COPY: bool>(
        self,
        t: *const u8,
        a: *const u32,
        o: *mut u32,
        o2: *mut u32,
        n: usize,
        start: u32,
        nt: bool,
    ) -> u32 {
        // SAFETY: forwarded (the caller's contract).
        unsafe {
            match self {
                Kernel::Sse2 => sse2::kernel::<ABOVE, COPY>(t, a, o, o2, n, start, nt),
                Kernel::Avx2 => avx2::kernel::<ABOVE, COPY>(t, a, o, o2, n, start, nt),
                Kernel::Avx512Vnni => avx512vnni::kernel::<ABOVE, COPY>(t, a, o, o2, n, start, nt),
            }
        }
    }
}

/// The build kernel in use (detected at run time), for benchmarks and reports: its name, or
/// `"avx2, sse2 rows"` where the flat rows take SSE2's ([`Kernel::for_rows`]).
pub fn kernel_name() -> &'static str {
    match (Kernel::best(), Kernel::for_rows()) {
        (Kernel::Avx2, Kernel::Sse2) => "avx2, sse2 rows",
        (k, _) => k.name(),
    }
}

/// CPUID leaf 1 ECX: OSXSAVE (27) and AVX (28); leaf 7 EBX: AVX2 (5), AVX-512F (16),
/// AVX-512 VL (31, for the 256-bit `vpdpbusd` of the build kernel); leaf 7 ECX: AVX-512 VNNI
/// (11). XCR0: SSE and AVX state (bits 1, 2) for AVX2; also opmask and the
/// upper ZMM state (5, 6, 7) for AVX-512. (Intel SDM vol. 1 §13.3 and §15.2, "Detection of
/// AVX-512 instructions".)
#[cfg(not(miri))]
fn detect() -> Kernel {
    let bit = |v: u32, b: u32| (v >> b) & 1 == 1;
    let max_leaf = __cpuid(0).eax;
    let l1 = __cpuid(1);
    if max_leaf < 7 || !bit(l1.ecx, 27) || !bit(l1.ecx, 28) {
        return Kernel::Sse2;
    }
    // SAFETY: OSXSAVE (checked above) means XGETBV is supported and enabled.
    let xcr0 = unsafe { xgetbv0() };
    let l7 = __cpuid_count(7, 0);
    let ymm = xcr0 & 0b110 == 0b110;
    let zmm = xcr0 & 0b1110_0110 == 0b1110_0110;
    // The AVX-512 kernel's detection includes AVX2's (the ZMM state includes the YMM state),
    // since the builds then run AVX2 kernels too (`modular_row`, `band_row`).
    if zmm && bit(l7.ebx, 16) && bit(l7.ebx, 31) && bit(l7.ecx, 11) && bit(l7.ebx, 5) {
        Kernel::Avx512Vnni
    } else if ymm && bit(l7.ebx, 5) {
        Kernel::Avx2
    } else {
        Kernel::Sse2
    }
}

/// Whether the CPU also has AVX-512BW, AVX-512DQ and AVX-512 VBMI (for
/// `tiled512::kernel8_packed` and the `band512` kernels), on top of [`Kernel::Avx512Vnni`]:
/// CPUID leaf 7 EBX bits 30 and 17, ECX bit 1 (the registers' state as for AVX-512F). Every
/// CPU with VBMI has DQ too (Cannon Lake, Ice Lake and later, Zen 4 and later). Detected once,
/// then cached as [`Kernel::detected`] is (from the CPU's kernel, not a test thread's capped
/// [`Kernel::best`], so that the cached answer does not depend on which test asked first; the
/// packing kernels run only with the AVX-512 kernel).
pub(crate) fn vbmi() -> bool {
    cached(&VBMI, || {
        Kernel::detected() == Kernel::Avx512Vnni && detect_vbmi()
    })
}

/// A CPU property held in `cell` (0 before the first detection, 1 no, 2 yes): `detect`'s
/// answer on the first call, then the cached one (a relaxed atomic: every thread detects the
/// same).
#[inline]
fn cached(cell: &AtomicU8, detect: impl FnOnce() -> bool) -> bool {
    match cell.load(Ordering::Relaxed) {
        1 => false,
        2 => true,
        _ => {
            let v = detect();
            cell.store(1 + u8::from(v), Ordering::Relaxed);
            v
        }
    }
}

/// [`vbmi`]'s answer: 0 before the first detection, 1 no, 2 yes.
static VBMI: AtomicU8 = AtomicU8::new(0);

/// CPUID leaf 7: AVX-512BW (EBX bit 30), AVX-512DQ (EBX bit 17), AVX-512 VBMI (ECX bit 1);
/// called once the AVX-512 kernel is detected (leaf 7 exists, XCR0 enables the ZMM state).
#[cfg(not(miri))]
fn detect_vbmi() -> bool {
    let l7 = __cpuid_count(7, 0);
    (l7.ebx >> 30) & 1 == 1 && (l7.ebx >> 17) & 1 == 1 && (l7.ecx >> 1) & 1 == 1
}

/// Under Miri: the build's target features.
#[cfg(miri)]
fn detect_vbmi() -> bool {
    cfg!(all(
        target_feature = "avx512bw",
        target_feature = "avx512dq",
        target_feature = "avx512vbmi"
    ))
}

/// Whether this CPU executes 256-bit AVX operations as two 128-bit halves (for
/// [`Kernel::for_rows`]): detected once, then cached as [`vbmi`] is.
pub(crate) fn splits_256() -> bool {
    cached(&SPLITS_256, detect_splits_256)
}

/// [`splits_256`]'s answer: 0 before the first detection, 1 no, 2 yes.
static SPLITS_256: AtomicU8 = AtomicU8::new(0);

/// CPUID's vendor registers (leaf 0: EBX, EDX, ECX) of AMD and of Hygon (whose Dhyana is a
/// Zen core), the vendors that define leaf `8000_001A`.
const SPLIT_VENDORS: [[u32; 3]; 2] = [AMD, vendor(b"HygonGenuine")];

/// CPUID's vendor registers of AMD (`AuthenticAMD`).
const AMD: [u32; 3] = vendor(b"AuthenticAMD");

/// A 12-byte vendor string as CPUID leaf 0 returns it: EBX, EDX, ECX, 4 bytes each,
/// little-endian.
const fn vendor(s: &[u8; 12]) -> [u32; 3] {
    let mut out = [0u32; 3];
    let mut i = 0;
    while i < 3 {
        out[i] = u32::from_le_bytes([s[4 * i], s[4 * i + 1], s[4 * i + 2], s[4 * i + 3]]);
        i += 1;
    }
    out
}

/// CPUID leaf `8000_001A` ("Performance Optimization Identifiers", AMD64 Architecture
/// Programmer's Manual vol. 3, appendix E): EAX bit 0, FP128, is set when 128-bit SSE
/// instructions are executed with full-width internal operations, and bit 2, FP256, when
/// 256-bit AVX instructions are, rather than decomposed into 128-bit ones.
const LEAF_FP: u32 = 0x8000_001A;

/// [`splits_256`] from CPUID's answers: `vendor` (leaf 0), `max_ext` (leaf `8000_0000` EAX,
/// the highest extended leaf) and `fp` (leaf [`LEAF_FP`] EAX, 0 where the leaf is absent).
/// Only AMD and Hygon define the leaf (on other CPUs a leaf past the highest returns another
/// leaf's data); their CPUs split where FP128 (bit 0: 128-bit operations full width) is set and
/// FP256 clear (Zen, Zen+, and the Excavator cores with AVX2: `0b011`), and are full width
/// where FP256 is set (Zen 2 on). A leaf that reads all zero (as a hypervisor may give it) is
/// taken as full width, the choice that was the only one before. Intel's AVX2 cores are taken
/// as full width (no CPUID bit says otherwise; the Atom-derived cores with AVX2, Gracemont on,
/// split, but are not told apart here: not measured).
fn splits_256_from(vendor: [u32; 3], max_ext: u32, fp: u32) -> bool {
    SPLIT_VENDORS.contains(&vendor) && max_ext >= LEAF_FP && fp & 0b101 == 0b001
}

/// CPUID leaves 0, `8000_0000` and [`LEAF_FP`] into [`splits_256_from`].
#[cfg(not(miri))]
fn detect_splits_256() -> bool {
    let v = __cpuid(0);
    let max_ext = __cpuid(0x8000_0000).eax;
    let fp = if max_ext >= LEAF_FP {
        __cpuid(LEAF_FP).eax
    } else {
        0
    };
    splits_256_from([v.ebx, v.edx, v.ecx], max_ext, fp)
}

/// Under Miri, which cannot run CPUID: full width.
#[cfg(miri)]
fn detect_splits_256() -> bool {
    false
}

/// Whether [`row_u8_u32`] takes a head, the entries before a working row reaches 32 bytes, so
/// that the kernel's 32-byte accesses to the row stay inside cache lines: yes, except on AMD's
/// family 1Ah (Zen 5) and later ([`takes_heads_from`]). Detected once, then cached as
/// [`splits_256`] is; in the crate's unit tests a thread's `set_heads` decides, so that
/// both forms are tested on every CPU.
#[inline]
pub(crate) fn takes_heads() -> bool {
    #[cfg(test)]
    if let Some(heads) = HEADS.with(|c| c.get()) {
        return heads;
    }
    cached(&TAKES_HEADS, detect_takes_heads)
}

/// [`takes_heads`]'s answer: 0 before the first detection, 1 no, 2 yes.
static TAKES_HEADS: AtomicU8 = AtomicU8::new(0);

/// The first AMD family whose working rows take no head: 1Ah (Zen 5).
const NO_HEAD_FAMILY: u32 = 0x1A;

/// [`takes_heads`] from CPUID's answers: `vendor` (leaf 0) and `signature` (leaf 1 EAX, whose
/// family is bits 8 to 11, plus bits 20 to 27 where those read 0xF). On AMD from family 1Ah
/// no head is taken; on every other CPU it is. Both were measured, on one CPU each (the
/// families after 1Ah are taken as 1Ah is, not measured):
/// * Zen 4 guest: a working row 16 bytes off 32 took `push_row_into` at 4,096^2 to 1.4x to
///   1.5x the flat build's time, 1.0x with the head (docs/benchmarks.md, ninth session).
/// * Zen 5 guest (family 1Ah model 02h): `push_row_into` of 1,024^2 into a cold table,
///   against the same build with every row on a cache line. Over the 16 places of the working
///   row and the table (each 0, 16, 32 or 48 bytes past a line), without a head: 1.00x to
///   1.03x. With the head: 1.33x to 1.43x wherever the row was 16 bytes off 32. (A head by
///   one AVX2 step with masked stores, tried, still took 1.27x to 1.32x where the table was
///   off a line.) At 2,048^2 and 4,096^2, and 1,024^2 in cache, without the head it was no
///   slower beyond the noise. Only 500^2 in L2 took 1.04x to 1.11x without it, against 1.00x
///   to 1.06x with it (docs/benchmarks.md, twenty-seventh session).
fn takes_heads_from(vendor: [u32; 3], signature: u32) -> bool {
    let base = (signature >> 8) & 0xF;
    let family = if base == 0xF {
        base + ((signature >> 20) & 0xFF)
    } else {
        base
    };
    !(vendor == AMD && family >= NO_HEAD_FAMILY)
}

/// CPUID leaves 0 and 1 into [`takes_heads_from`].
#[cfg(not(miri))]
fn detect_takes_heads() -> bool {
    let v = __cpuid(0);
    takes_heads_from([v.ebx, v.edx, v.ecx], __cpuid(1).eax)
}

/// Under Miri, which cannot run CPUID: the head (the tests take both forms).
#[cfg(miri)]
fn detect_takes_heads() -> bool {
    true
}

/// Makes [`takes_heads`] answer `heads` on this thread, or detect again with `None` (tests
/// only: the other test threads keep theirs).
#[cfg(test)]
pub(crate) fn set_heads(heads: Option<bool>) {
    HEADS.with(|c| c.set(heads));
}

/// XCR0.
///
/// # Safety
/// The CPU supports XGETBV (CPUID.1:ECX.OSXSAVE).
#[cfg(not(miri))]
#[target_feature(enable = "xsave")]
unsafe fn xgetbv0() -> u64 {
    _xgetbv(0)
}

/// Under Miri: the kernels the build's target features enable.
#[cfg(miri)]
fn detect() -> Kernel {
    if cfg!(all(
        target_feature = "avx512f",
        target_feature = "avx512vl",
        target_feature = "avx512vnni",
        target_feature = "avx2"
    )) {
        Kernel::Avx512Vnni
    } else if cfg!(target_feature = "avx2") {
        Kernel::Avx2
    } else {
        Kernel::Sse2
    }
}

mod sse2 {
    use super::*;

    /// Blocks of 16 while `i + 16 <= n`; returns the running sum after the last full block.
    ///
    /// # Safety
    /// SSE2 (x86-64 baseline); `t`, `o`, (if `ABOVE`) `a` and (if `COPY`) `o2` valid for `n`
    /// elements; `a` may equal `o` (each block reads before it writes); `o2` aliases nothing;
    /// if `COPY` and `nt` (the copy by non-temporal stores), `o2` is 16-byte aligned. The
    /// caller fences after the row ([`row_u8_u32`]).
    #[target_feature(enable = "sse2")]
    pub(super) unsafe fn kernel<const ABOVE: bool, const COPY: bool>(
        t: *const u8,
        a: *const u32,
        o: *mut u32,
        o2: *mut u32,
        n: usize,
        start: u32,
        nt: bool,
    ) -> u32 {
        let zero = _mm_setzero_si128();
        let mut carry = _mm_set1_epi32(start as i32);
        let mut i = 0;
        while i + BLOCK <= n {
            // SAFETY: i + 16 <= n (the caller's bounds); unaligned loads and stores.
            unsafe {
                let v = _mm_loadu_si128(t.add(i).cast());
                let mut lo = _mm_unpacklo_epi8(v, zero);
                let mut hi = _mm_unpackhi_epi8(v, zero);
                lo = _mm_add_epi16(lo, _mm_slli_si128(lo, 2));
                hi = _mm_add_epi16(hi, _mm_slli_si128(hi, 2));
                lo = _mm_add_epi16(lo, _mm_slli_si128(lo, 4));
                hi = _mm_add_epi16(hi, _mm_slli_si128(hi, 4));
                lo = _mm_add_epi16(lo, _mm_slli_si128(lo, 8));
                hi = _mm_add_epi16(hi, _mm_slli_si128(hi, 8));
                // Lane 7 of the low half (its total) into every lane of the high half.
                hi = _mm_add_epi16(hi, _mm_shuffle_epi32(_mm_shufflehi_epi16(lo, 0xff), 0xff));
                let top = _mm_unpackhi_epi16(hi, zero);
                let mut p = [
                    _mm_add_epi32(_mm_unpacklo_epi16(lo, zero), carry),
                    _mm_add_epi32(_mm_unpackhi_epi16(lo, zero), carry),
                    _mm_add_epi32(_mm_unpacklo_epi16(hi, zero), carry),
                    _mm_add_epi32(top, carry),
                ];
                // The block's own total broadcast, then added: one addition on the carry's
                // chain per block.
                carry = _mm_add_epi32(carry, _mm_shuffle_epi32(top, 0xff));
                if ABOVE {
                    for (k, v) in p.iter_mut().enumerate() {
                        *v = _mm_add_epi32(*v, _mm_loadu_si128(a.add(i + 4 * k).cast()));
                    }
                }
                for (k, v) in p.iter().enumerate() {
                    _mm_storeu_si128(o.add(i + 4 * k).cast(), *v);
                    if COPY {
                        store_copy(o2.add(i + 4 * k), *v, nt);
                    }
                }
            }
            i += BLOCK;
        }
        _mm_cvtsi128_si32(carry) as u32
    }
}

mod avx2 {
    use super::*;

    /// `vpmaddubsw` weights for lane `j` (0..8) of an 8-texel chunk, bytes `4 j + b`: texel
    /// `q + b` of the chunk (the broadcast quad `q`, 0 or 4) counts for lane `j` when `q + b`
    /// is at most `j`.
    const fn weights(q: usize) -> [i8; 32] {
        let mut w = [0i8; 32];
        let mut j = 0;
        while j < 8 {
            let mut b = 0;
            while b < 4 {
                if q + b <= j {
                    w[4 * j + b] = 1;
                }
                b += 1;
            }
            j += 1;
        }
        w
    }

    const W: [[i8; 32]; 2] = [weights(0), weights(4)];

    /// The weights of [`chunk`], and the ones that join its 16-bit pairs, in registers.
    #[derive(Clone, Copy)]
    pub(super) struct Weights {
        /// Quads 0 and 4 (also the AVX-512 kernel's `vpdpbusd` weights).
        pub(super) w: [__m256i; 2],
        ones: __m256i,
    }

    impl Weights {
        #[inline]
        #[target_feature(enable = "avx2")]
        pub(super) fn new() -> Self {
            // SAFETY: W's rows are 32 bytes: unaligned 32-byte loads.
            let w = W.map(|r| unsafe { _mm256_loadu_si256(r.as_ptr().cast()) });
            Weights {
                w,
                ones: _mm256_set1_epi16(1),
            }
        }
    }

    /// The prefix sums of the 8 texels at `t` (lane `j`: `t[0] + ... + t[j]`): per quad of
    /// texels, broadcast (a load), `vpmaddubsw` with 0/1 weights (unsigned texels times signed
    /// weights, pairs summed into 16 bits: at most 510); the two added (at most 1,020); then
    /// `vpmaddwd` with ones (the pairs summed into 32 bits). No shuffle.
    ///
    /// # Safety
    /// The CPU has AVX2; `t` is valid for reads of 8 bytes.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn chunk(t: *const u8, w: Weights) -> __m256i {
        // SAFETY: t[0..8] readable (the caller's contract): two unaligned 4-byte reads.
        let (q0, q1) = unsafe {
            (
                _mm256_set1_epi32(t.cast::<i32>().read_unaligned()),
                _mm256_set1_epi32(t.add(4).cast::<i32>().read_unaligned()),
            )
        };
        _mm256_madd_epi16(
            _mm256_add_epi16(
                _mm256_maddubs_epi16(q0, w.w[0]),
                _mm256_maddubs_epi16(q1, w.w[1]),
            ),
            w.ones,
        )
    }

    /// See the SSE2 kernel. Per 8 texels, the prefix sums by [`chunk`]: two dot products of
    /// broadcast texel quads with 0/1 weights, no shuffle. Only the two chunk totals take a
    /// lane-crossing permute: an earlier form (the prefix by three shift-and-adds in 16-bit
    /// lanes, then widened) spent 12 shuffles per 16 texels, the bound on CPUs with two shuffle
    /// ports (0.29 against 0.17 ns per texel for a row in L1 on a Zen 3 core); this one spends
    /// 2. The running sum takes one add per block on its chain.
    ///
    /// # Safety
    /// As the SSE2 kernel, with AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn kernel<const ABOVE: bool, const COPY: bool>(
        t: *const u8,
        a: *const u32,
        o: *mut u32,
        o2: *mut u32,
        n: usize,
        start: u32,
        nt: bool,
    ) -> u32 {
        let w = Weights::new();
        let last = lane7();
        let mut carry = _mm256_set1_epi32(start as i32);
        let mut i = 0;
        while i + BLOCK <= n {
            // SAFETY: i + 16 <= n (the caller's bounds); unaligned loads and stores.
            unsafe {
                let lo8 = chunk(t.add(i), w);
                let hi8 = chunk(t.add(i + 8), w);
                let ta = _mm256_permutevar8x32_epi32(lo8, last);
                let tb = _mm256_permutevar8x32_epi32(hi8, last);
                let lo = _mm256_add_epi32(lo8, carry);
                let hi = _mm256_add_epi32(hi8, _mm256_add_epi32(carry, ta));
                carry = _mm256_add_epi32(carry, _mm256_add_epi32(ta, tb));
                put8::<ABOVE, COPY>(a, o, o2, i, lo, nt);
                put8::<ABOVE, COPY>(a, o, o2, i + 8, hi, nt);
            }
            i += BLOCK;
        }
        _mm256_cvtsi256_si32(carry) as u32
    }

    /// The 8 entries at `j`, shared by the AVX2 and AVX-512 kernels: `v` (prefix sums and
    /// running sum) plus the row above `a[j..j + 8]` if `ABOVE`, stored to `o[j..j + 8]` and,
    /// if `COPY`, to `o2[j..j + 8]`: by two non-temporal 16-byte stores if `nt`, else one
    /// unaligned store. The row above is read before `o` is written (`a` may be `o`).
    ///
    /// # Safety
    /// AVX2; `o`, `a` (if `ABOVE`) and `o2` (if `COPY`) valid for 8 entries from `j`; `o2 + j`
    /// 16-byte aligned if `COPY` and `nt`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn put8<const ABOVE: bool, const COPY: bool>(
        a: *const u32,
        o: *mut u32,
        o2: *mut u32,
        j: usize,
        mut v: __m256i,
        nt: bool,
    ) {
        // SAFETY: the caller's contract; unaligned loads and stores.
        unsafe {
            if ABOVE {
                v = _mm256_add_epi32(v, _mm256_loadu_si256(a.add(j).cast()));
            }
            _mm256_storeu_si256(o.add(j).cast(), v);
            if COPY {
                if nt {
                    store_copy(o2.add(j), _mm256_castsi256_si128(v), true);
                    store_copy(o2.add(j + 4), _mm256_extracti128_si256::<1>(v), true);
                } else {
                    _mm256_storeu_si256(o2.add(j).cast(), v);
                }
            }
        }
    }
}

mod avx512vnni {
    use super::*;

    /// The 16 texels at `tp` weighted into 16 lanes by four `vpdpbusd`, one per group of 4
    /// texels broadcast to every lane (unsigned texel bytes times the lane's signed 0/1
    /// weights `w[k]` for group `k`, summed per 32-bit lane; each lane at most 16 x 255, far
    /// from any saturation), in one chain; the weights are the tiled kernels' ([`TileTable`]).
    ///
    /// # Safety
    /// The CPU has AVX-512F and AVX-512 VNNI; `tp` is valid for reads of 16 bytes.
    #[inline]
    #[target_feature(enable = "avx512f,avx512vnni")]
    pub(super) unsafe fn dot16(tp: *const u8, w: &[__m512i; 4]) -> __m512i {
        // SAFETY: tp[4 k..4 k + 4] for k < 4: inside the 16 bytes (the caller's contract).
        let g =
            |k: usize| unsafe { _mm512_set1_epi32(tp.add(4 * k).cast::<i32>().read_unaligned()) };
        let p = _mm512_dpbusd_epi32(
            _mm512_dpbusd_epi32(_mm512_setzero_si512(), g(0), w[0]),
            g(1),
            w[1],
        );
        _mm512_dpbusd_epi32(_mm512_dpbusd_epi32(p, g(2), w[2]), g(3), w[3])
    }

    /// Per half block of 8 texels, two 256-bit `vpdpbusd` (AVX-512 VL): each group of 4
    /// texels broadcast to the 8 lanes, times the AVX2 kernel's 0/1 weights (`avx2::Weights`:
    /// byte `b` of lane `j` of quad `q` is 1 when texel `q + b` is at or before texel `j`;
    /// unsigned texel bytes times signed weights, summed per 32-bit lane: at most 8 x 255, far
    /// from any saturation), gives the half block's 8 prefix sums; its total (lane 7) is
    /// broadcast by one `vpermd` into the running sum. Half as many multiplies as the 512-bit
    /// form's four `vpdpbusd` per 16 lanes ([`dot16`]), most of whose lanes' weights are zero:
    /// on a Zen 4 guest, 0.78x the time per row in L1 (docs/benchmarks.md, eighth session).
    ///
    /// # Safety
    /// As the SSE2 kernel, with AVX2, AVX-512F, AVX-512 VL and AVX-512 VNNI.
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512vnni")]
    pub(super) unsafe fn kernel<const ABOVE: bool, const COPY: bool>(
        t: *const u8,
        a: *const u32,
        o: *mut u32,
        o2: *mut u32,
        n: usize,
        start: u32,
        nt: bool,
    ) -> u32 {
        let [w0, w1] = avx2::Weights::new().w;
        let last = lane7();
        let zero = _mm256_setzero_si256();
        let mut carry = _mm256_set1_epi32(start as i32);
        let mut i = 0;
        while i + BLOCK <= n {
            for j in [i, i + 8] {
                // SAFETY: j + 8 <= i + 16 <= n (the caller's bounds); unaligned loads and
                // stores; the 4-byte groups at j and j + 4.
                unsafe {
                    let g = |k: usize| {
                        _mm256_set1_epi32(t.add(j + 4 * k).cast::<i32>().read_unaligned())
                    };
                    let p = _mm256_dpbusd_epi32(_mm256_dpbusd_epi32(zero, g(0), w0), g(1), w1);
                    let v = _mm256_add_epi32(p, carry);
                    carry = _mm256_add_epi32(carry, _mm256_permutevar8x32_epi32(p, last));
                    avx2::put8::<ABOVE, COPY>(a, o, o2, j, v, nt);
                }
            }
            i += BLOCK;
        }
        _mm256_cvtsi256_si32(carry) as u32
    }
}

/// Packs fields of `k` bits (`MIN_PACK_BITS <= k <= 32`, the low `k` bits of each value) into
/// `words` from its bit 0, with AVX-512F 32 fields (exactly `k` words) at a time, with AVX2 16
/// fields (exactly `2 k` bytes) at a time; returns the fields packed (the whole groups of 32,
/// or with AVX2 the whole runs of 16 except for `k` = 16 and 32, that fit `words`; 0 for other
/// types, widths, or CPUs without AVX2). Each word written ends as the word the layouts'
/// portable packing writes there (`layouts::packed::pack_fields`: field `i` at bit `i k`); no
/// bit past the fields packed is written (for an odd `k` and an odd number of runs, the last
/// word's upper 16 bits are kept).
///
/// With AVX-512F ([`pack512`]): output word `j` of a group holds bits `32 j .. 32 j + 32`, that
/// is `f[i] >> s | f[i + 1] << (k - s) | f[i + 2] << (2k - s) | f[i + 3] << (3k - s)` with
/// `i = floor(32 j / k)`, `s = 32 j - i k`: at most four fields for `k >= 11`. Per 16 output
/// words: four `vpermt2d` gathering those fields from the group's two registers (indices past
/// the group clamped to 31: their shift counts are at least 32, and AVX-512's variable shifts
/// give 0 there, as for the terms a word does not need), one `vpsrlvd`, three `vpsllvd`, three
/// ors, one (masked) store; from 16 bits on, a word holds parts of at most three fields: three
/// of each. The index and count tables depend on `k` only: constants of the width's own
/// instantiation (`pack512::pack_k`). For `k` = 17 to 24 the words past 16 (at most 8) are
/// computed in 256-bit vectors (AVX-512 VL), from 8-field loads of the group's second half.
///
/// With AVX2 ([`pack256`]), which has no two-register permute: eight groups side by side, one
/// per 32-bit lane, so that every shift is the same in all lanes (the constant shifts of the
/// portable `packed::group`); see there.
pub(crate) fn pack_u32<E: Entry>(words: &mut [u32], fields: &[E], k: u32) -> usize {
    // SAFETY: `Kernel::best` is what this CPU runs (CPUID and XGETBV, cached).
    unsafe { pack_u32_with(Kernel::best(), words, fields, k) }
}

/// [`pack_u32`] with `kernel`'s packing: [`pack512`] for [`Kernel::Avx512Vnni`], [`pack256`]
/// for [`Kernel::Avx2`], none (0 fields) for [`Kernel::Sse2`].
///
/// # Safety
/// `kernel` is [`Kernel::available`] on this CPU (the tests run each available one).
unsafe fn pack_u32_with<E: Entry>(
    kernel: Kernel,
    words: &mut [u32],
    fields: &[E],
    k: u32,
) -> usize {
    let Some(f) = cast::u32s(fields) else {
        return 0;
    };
    if !(MIN_PACK_BITS..=32).contains(&k) || kernel == Kernel::Sse2 {
        return 0;
    }
    let ku = k as usize;
    if kernel == Kernel::Avx2 {
        // Runs of 16 fields, `2 k` bytes each: the whole groups of 32 and, when 16 to 31
        // fields are left after them, one run more (a row of 128 texels has 16 tile
        // boundaries: without it they went field by field).
        let runs = (f.len() / 16).min(2 * words.len() / ku);
        if runs == 0 {
            return 0;
        }
        // SAFETY: AVX2 is available (the caller's contract: `Kernel::Avx2` runs on this CPU);
        // `f` holds at least 16 runs values and `words` spans 4 words.len() >= 2 k runs bytes
        // (above); the kernel reads f[0..16 runs] and writes the first 2 k runs bytes of
        // `words` only.
        return unsafe {
            by_pack_width!(
                ku,
                pack256::pack(f.as_ptr(), words.as_mut_ptr(), runs),
                return 0
            )
        };
    }
    let groups = (f.len() / 32).min(words.len() / ku);
    if groups == 0 {
        return 0;
    }
    // SAFETY: AVX-512F and VL are available (`kernel` is Avx512Vnni, whose detection includes them,
    // and available: the caller's contract); `f` holds at least 32 groups values and `words` at
    // least groups k words (above); the kernel reads f[0..32 groups] and writes words[0..groups k]
    // only; 11 <= k <= 32 (above).
    unsafe { pack512::pack(f.as_ptr(), words.as_mut_ptr(), groups, k) };
    groups * 32
}

/// `module::function::<K>(args)` for the field width `k` (`MIN_PACK_BITS..=32`: each width is
/// its own instantiation, every shift a constant), `none` for any other width. Expands to the
/// call only: the caller's `unsafe` block and safety argument cover it.
macro_rules! by_pack_width {
    ($k:expr, $m:ident::$f:ident($($arg:expr),*), $none:expr) => {
        by_pack_width!(@ $k, $m, $f, ($($arg),*), $none;
            11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
    };
    (@ $k:expr, $m:ident, $f:ident, $args:tt, $none:expr; $($w:literal)*) => {
        match $k {
            $($w => $m::$f::<$w> $args,)*
            _ => $none,
        }
    };
}
use by_pack_width;

/// The narrowest field [`pack_u32`] packs: from 11 bits on, a word holds parts of at most four
/// fields.
pub(crate) const MIN_PACK_BITS: u32 = 11;

/// [`pack_u32`]'s tables, per width `k = 11..=32` (index `k - 11`): rows `t = 0..4` the field
/// (0..32 in the group, clamped to 31) of term `t` of output word `j` (column `j`), rows
/// `4 + t` its shift count (`s` right for `t = 0`, `t k - s` left after; at most 96).
/// Computed at compile time, widened to 32-bit lanes per width (`pack512::pack_k`).
const PACK_TABLES: [[[u8; 32]; 8]; 22] = pack_tables();

const fn pack_tables() -> [[[u8; 32]; 8]; 22] {
    let mut out = [[[0u8; 32]; 8]; 22];
    let mut k = MIN_PACK_BITS;
    while k <= 32 {
        // Word j + 1 starts 32 bits after word j: (i, s) by subtraction.
        let (mut i, mut s, mut j) = (0u32, 0u32, 0usize);
        while j < k as usize {
            let mut t = 0u32;
            while t < 4 {
                let row = &mut out[(k - MIN_PACK_BITS) as usize];
                row[t as usize][j] = if i + t > 31 { 31 } else { (i + t) as u8 };
                row[4 + t as usize][j] = if t == 0 { s as u8 } else { (t * k - s) as u8 };
                t += 1;
            }
            s += 32;
            while s >= k {
                s -= k;
                i += 1;
            }
            j += 1;
        }
        k += 1;
    }
    out
}

mod pack512 {
    use super::*;

    /// Lane `j` of the 32 lanes of `a` then `b` selected by lane `j` of `idx` (0..32):
    /// `vpermt2d`. Miri does not emulate it, so under Miri the same selection by two `vpermd`
    /// and a blend (slower, same lanes): Miri still checks every load and store of the kernel.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(super) fn perm2(a: __m512i, idx: __m512i, b: __m512i) -> __m512i {
        #[cfg(not(miri))]
        let v = _mm512_permutex2var_epi32(a, idx, b);
        #[cfg(miri)]
        let v = _mm512_mask_blend_epi32(
            _mm512_cmpge_epu32_mask(idx, _mm512_set1_epi32(16)),
            _mm512_permutexvar_epi32(idx, a),
            _mm512_permutexvar_epi32(idx, b),
        );
        v
    }

    /// The kernel of [`pack_u32`]: [`pack_k`] for `k`.
    ///
    /// # Safety
    /// The CPU has AVX-512F and VL; `f` is valid for reads of `32 groups` values and `w` for
    /// writes of `groups k` words; `11 <= k <= 32` (any other width packs nothing).
    #[target_feature(enable = "avx512f,avx512vl")]
    pub(super) unsafe fn pack(f: *const u32, w: *mut u32, groups: usize, k: u32) {
        // SAFETY: the caller's contract, with K = k.
        unsafe { by_pack_width!(k as usize, pack512::pack_k(f, w, groups), ()) }
    }

    /// `PACK_TABLES[K - 11]` widened to 32-bit lanes, per half of the output (words 0..16 and
    /// 16..K): rows 0..4 the terms' field indices, rows 4..8 their shift counts. A constant of
    /// each instantiation of [`pack_k`], so its vectors are constants of the code.
    const fn wide_table<const K: usize>() -> [[[u32; 16]; 8]; 2] {
        let t = &PACK_TABLES[K - MIN_PACK_BITS as usize];
        let mut out = [[[0u32; 16]; 8]; 2];
        let mut h = 0;
        while h < 2 {
            let mut r = 0;
            while r < 8 {
                let mut j = 0;
                while j < 16 {
                    out[h][r][j] = t[r][16 * h + j] as u32;
                    j += 1;
                }
                r += 1;
            }
            h += 1;
        }
        out
    }

    /// Words 16..24 of a group (the second half for `K <= 24`) as [`wide_table`]'s second
    /// half has them, the field indices less 16: rows 0, 1 and 2 index the fields 16..32 of
    /// the group (those words' terms start at field `floor(512 / K) >= 21`; the fourth term,
    /// for `K < 16` only, is left out), rows 3, 4 and 5 hold the terms' shift counts.
    const fn narrow_table<const K: usize>() -> [[u32; 8]; 6] {
        let t = &PACK_TABLES[K - MIN_PACK_BITS as usize];
        let mut out = [[0u32; 8]; 6];
        let mut r = 0;
        while r < 3 {
            let mut j = 0;
            while j < 8 {
                // Words K..24 (entries 0): the last group's masked store leaves them out, and
                // another group's are the next group's first words, which it writes after.
                out[r][j] = (t[r][16 + j] as u32).saturating_sub(16);
                out[3 + r][j] = t[4 + r][16 + j] as u32;
                j += 1;
            }
            r += 1;
        }
        out
    }

    /// [`pack`] for a width `K` known at compile time (`pack_u32`'s path, one instantiation per
    /// width): the index and count vectors are constants, the terms, halves and masks of `K`
    /// chosen at compile time, so a call does not build them first (built at run time from
    /// `k`, they went through the stack: the call's fixed cost about halved on a Zen 4, where
    /// a tiled band row's boundaries are 4 groups; docs/benchmarks.md, thirteenth session).
    /// Every group but the last stores whole vectors: the words past its own
    /// `K` that a 16-word (or, for words 16..K with `K` = 17 to 24, 8-word) store writes
    /// belong to the next group, which writes them after it (for `K >= 16` they lie inside the
    /// next group's first 16 words, for `K < 16` inside its `K`); the last group stores its own
    /// words only.
    ///
    /// # Safety
    /// The CPU has AVX-512F and VL; `f` is valid for reads of `32 groups` values and `w` for
    /// writes of `groups K` words; `11 <= K <= 32`.
    #[target_feature(enable = "avx512f,avx512vl")]
    pub(super) unsafe fn pack_k<const K: usize>(f: *const u32, w: *mut u32, groups: usize) {
        let wide = const { wide_table::<K>() };
        // Words 16..K in 256-bit vectors for K <= 24 (at most 8 words): on a Zen 4, where a
        // 512-bit operation takes two 256-bit ones' share, 896 fields of 21 bits took 0.85x
        // the time (docs/benchmarks.md, fourteenth session).
        let narrow = const { narrow_table::<K>() };
        let m8 = _mm256_set1_epi32(((1u64 << K) - 1) as u32 as i32);
        // SAFETY: each row is 8 u32, one 32-byte unaligned load.
        let y = |r: usize| unsafe { _mm256_loadu_si256(narrow[r].as_ptr().cast()) };
        let (yix, yc) = ([y(0), y(1), y(2)], [y(3), y(4), y(5)]);
        let m = _mm512_set1_epi32(if K >= 32 {
            -1
        } else {
            ((1u32 << K) - 1) as i32
        });
        // SAFETY: each row is 16 u32, one 64-byte unaligned load.
        let v = |h: usize, r: usize| unsafe { _mm512_loadu_si512(wide[h][r].as_ptr().cast()) };
        let half = |h: usize| {
            (
                [v(h, 0), v(h, 1), v(h, 2), v(h, 3)],
                [v(h, 4), v(h, 5), v(h, 6), v(h, 7)],
                K.saturating_sub(16 * h).min(16),
            )
        };
        let halves = [half(0), half(1)];
        for g in 0..groups {
            let last = g + 1 == groups;
            // SAFETY: g < groups: f[32 g .. 32 g + 32] is readable (the caller's contract). The
            // last group's stores write n <= 16 words from 16 h < K on, inside w[g K .. g K +
            // K]; another group's whole stores end at g K + 16 h + 16 <= (groups - 2) K + 32
            // <= groups K words (K >= 16 when h = 1, and K >= 8), inside the caller's words.
            unsafe {
                let a = _mm512_and_si512(_mm512_loadu_si512(f.add(32 * g).cast()), m);
                let b = _mm512_and_si512(_mm512_loadu_si512(f.add(32 * g + 16).cast()), m);
                for (h, (ix, c, n)) in halves.iter().enumerate() {
                    if *n == 0 {
                        continue;
                    }
                    if h == 1 && K <= 24 {
                        let load = |at: usize| _mm256_loadu_si256(f.add(32 * g + at).cast());
                        let (a8, b8) = (
                            _mm256_and_si256(load(16), m8),
                            _mm256_and_si256(load(24), m8),
                        );
                        let t = |i: usize| modular256::perm2(a8, yix[i], b8);
                        let v = _mm256_or_si256(
                            _mm256_or_si256(
                                _mm256_srlv_epi32(t(0), yc[0]),
                                _mm256_sllv_epi32(t(1), yc[1]),
                            ),
                            _mm256_sllv_epi32(t(2), yc[2]),
                        );
                        let out = w.add(g * K + 16);
                        if !last {
                            _mm256_storeu_si256(out.cast(), v);
                        } else {
                            _mm256_mask_storeu_epi32(out.cast(), ((1u32 << n) - 1) as u8, v);
                        }
                        continue;
                    }
                    let t = |i: usize| perm2(a, ix[i], b);
                    let mut v = _mm512_or_si512(
                        _mm512_or_si512(
                            _mm512_srlv_epi32(t(0), c[0]),
                            _mm512_sllv_epi32(t(1), c[1]),
                        ),
                        _mm512_sllv_epi32(t(2), c[2]),
                    );
                    if K < 16 {
                        v = _mm512_or_si512(v, _mm512_sllv_epi32(t(3), c[3]));
                    }
                    let out = w.add(g * K + 16 * h);
                    if *n == 16 || !last {
                        _mm512_storeu_si512(out.cast(), v);
                    } else {
                        _mm512_mask_storeu_epi32(out.cast(), ((1u32 << n) - 1) as u16, v);
                    }
                }
            }
        }
    }
}

/// [`pack_u32`]'s AVX2 kernel: eight groups of 32 fields at a time, one group per 32-bit lane.
///
/// Field `i` of a group (its low `K` bits, `v = f[i] & (2^K - 1)`) sits at bit `i K`: word
/// `j = floor(i K / 32)` gets `v << s` (`s = i K mod 32`, the bits past 32 dropped) and, when
/// the field crosses into the next word (`s + K > 32`), word `j + 1` gets `v >> (32 - s)`. With
/// `K` a constant, `j` and `s` are constants per field: the portable `packed::group`'s shifts.
/// AVX2 has no permute across its registers that would gather each word's fields from a group
/// in four registers, so instead lane `g` of every register holds group `g` of the eight: each
/// 8 x 8 block of `u32` (8 groups, 8 consecutive fields or words) is transposed on the way in
/// and on the way out (two 4 x 4 transposes within the 128-bit halves, fed by 128-bit loads
/// into both halves on the way in; then a swap of halves on the way out), and in between every
/// field costs one `vpand`, one immediate shift and one `vpor` (two of each when it crosses a
/// word boundary), shared by the eight groups.
mod pack256 {
    use super::*;

    /// Two 4 x 4 transposes, one per 128-bit half: lane `c` of result `r` is lane `r` of `a[c]`
    /// (both within the same half).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn transpose4(a: [__m256i; 4]) -> [__m256i; 4] {
        let t0 = _mm256_unpacklo_epi32(a[0], a[1]);
        let t1 = _mm256_unpackhi_epi32(a[0], a[1]);
        let t2 = _mm256_unpacklo_epi32(a[2], a[3]);
        let t3 = _mm256_unpackhi_epi32(a[2], a[3]);
        [
            _mm256_unpacklo_epi64(t0, t2),
            _mm256_unpackhi_epi64(t0, t2),
            _mm256_unpacklo_epi64(t1, t3),
            _mm256_unpackhi_epi64(t1, t3),
        ]
    }

    /// Words `at..at + 8` of the eight groups of `S` values from `f` (group `g` at `f + S g`,
    /// or the last group, `gn - 1`, for the lanes past it; no clamp if `FULL`), transposed: lane
    /// `g` of result `c` is word `at + c` of group `g`.
    ///
    /// # Safety
    /// Each (clamped) group is valid for reads of `at + 8` words.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn load8x8<const FULL: bool, const S: usize>(
        f: *const u32,
        gn: usize,
        at: usize,
    ) -> [__m256i; 8] {
        // SAFETY: group g's words at..at + 8 are readable (the caller's contract): 16-byte
        // unaligned loads of words at..at + 4 and at + 4..at + 8.
        let half = |g: usize, c: usize| unsafe {
            let p = |g: usize| f.add(S * if FULL { g } else { g.min(gn - 1) });
            _mm256_loadu2_m128i(p(g + 4).add(at + c).cast(), p(g).add(at + c).cast())
        };
        // Group g's words in the low half, group g + 4's in the high half.
        let [c0, c1, c2, c3] = transpose4([half(0, 0), half(1, 0), half(2, 0), half(3, 0)]);
        let [c4, c5, c6, c7] = transpose4([half(0, 4), half(1, 4), half(2, 4), half(3, 4)]);
        [c0, c1, c2, c3, c4, c5, c6, c7]
    }

    /// Stores output words `j..j + 8` (`o[j + c]`, lane `g` for group `g`) of the first `gn`
    /// groups (all 8 if `FULL`): lane `g` of the eight registers into the 8 words from byte
    /// `stride g + 4 j` of `w` (unaligned).
    ///
    /// # Safety
    /// `gn <= 8`; `w + stride g` is valid for writes of `4 j + 32` bytes for `g < gn`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn store8x8<const FULL: bool>(
        w: *mut u8,
        stride: usize,
        gn: usize,
        j: usize,
        o: &[__m256i],
    ) {
        let rows = rows8x8(o, j);
        let n = if FULL { 8 } else { gn };
        for (g, r) in rows.iter().enumerate().take(n) {
            // SAFETY: g < gn: bytes stride g + 4 j.. + 32 of w are writable (the caller's
            // contract).
            unsafe { _mm256_storeu_si256(w.add(stride * g + 4 * j).cast(), *r) };
        }
    }

    /// Output words `j..j + 8` (`o[j + c]`, lane `g` for group `g`) transposed: result `g`
    /// holds group `g`'s words `j..j + 8` (two 4 x 4 transposes, then the halves swapped).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) fn rows8x8(o: &[__m256i], j: usize) -> [__m256i; 8] {
        let x = transpose4([o[j], o[j + 1], o[j + 2], o[j + 3]]);
        let y = transpose4([o[j + 4], o[j + 5], o[j + 6], o[j + 7]]);
        // x[g], y[g]: words j..j + 4 and j + 4..j + 8 of group g (low half), g + 4 (high half).
        [
            _mm256_permute2x128_si256::<0x20>(x[0], y[0]),
            _mm256_permute2x128_si256::<0x20>(x[1], y[1]),
            _mm256_permute2x128_si256::<0x20>(x[2], y[2]),
            _mm256_permute2x128_si256::<0x20>(x[3], y[3]),
            _mm256_permute2x128_si256::<0x31>(x[0], y[0]),
            _mm256_permute2x128_si256::<0x31>(x[1], y[1]),
            _mm256_permute2x128_si256::<0x31>(x[2], y[2]),
            _mm256_permute2x128_si256::<0x31>(x[3], y[3]),
        ]
    }

    /// As [`store8x8`] for the four words `j..j + 4`.
    ///
    /// # Safety
    /// `gn <= 8`; `w + stride g` is valid for writes of `4 j + 16` bytes for `g < gn`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn store8x4<const FULL: bool>(
        w: *mut u8,
        stride: usize,
        gn: usize,
        j: usize,
        o: &[__m256i],
    ) {
        let x = transpose4([o[j], o[j + 1], o[j + 2], o[j + 3]]);
        let rows = [
            _mm256_castsi256_si128(x[0]),
            _mm256_castsi256_si128(x[1]),
            _mm256_castsi256_si128(x[2]),
            _mm256_castsi256_si128(x[3]),
            _mm256_extracti128_si256::<1>(x[0]),
            _mm256_extracti128_si256::<1>(x[1]),
            _mm256_extracti128_si256::<1>(x[2]),
            _mm256_extracti128_si256::<1>(x[3]),
        ];
        let n = if FULL { 8 } else { gn };
        for (g, r) in rows.iter().enumerate().take(n) {
            // SAFETY: g < gn: bytes stride g + 4 j.. + 16 of w are writable (the caller's
            // contract).
            unsafe { _mm_storeu_si128(w.add(stride * g + 4 * j).cast(), *r) };
        }
    }

    /// Stores the `K` output words of each of `gn` groups (all 8 if `FULL`), group `g` at `w +
    /// K g`: words `0..8 (K / 8)` 8 at a time; the `K mod 8` after them, if any, by a store of
    /// the group's last 4 words (`K mod 8 <= 4`) or last 8, whose first words are written
    /// twice, with the same value: nothing outside the groups' words is written.
    ///
    /// # Safety
    /// `8 <= K`, `gn <= 8`; `w + K g` is valid for writes of `K` words for `g < gn`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn store_words<const K: usize, const FULL: bool>(
        w: *mut u32,
        gn: usize,
        o: &[__m256i; K],
    ) {
        // SAFETY: the stores cover w[K g + j..][..8] with j + 8 <= K, or the group's last 4 or 8
        // words (K >= 8), for g < gn: inside the groups' K words (the caller's contract).
        unsafe {
            let (w, stride) = (w.cast::<u8>(), 4 * K);
            let mut j = 0;
            while j + 8 <= K {
                store8x8::<FULL>(w, stride, gn, j, o);
                j += 8;
            }
            if j < K {
                if K - j <= 4 {
                    store8x4::<FULL>(w, stride, gn, K - 4, o);
                } else {
                    store8x8::<FULL>(w, stride, gn, K - 8, o);
                }
            }
        }
    }

    /// Field `i` (0..32) of every lane's group, `v`: its low `K` bits (`m`; all of them for
    /// `K = 32`) into word `floor(i K / 32)` of `o` at bit `i K mod 32`, the bits past 32 into
    /// the next word (the portable `packed::group`'s constant shifts).
    #[inline(always)]
    #[allow(clippy::as_conversions, reason = "i K mod 32 < 32: lossless into i32")]
    pub(super) fn field<const K: usize>(o: &mut [__m256i; K], i: usize, v: __m256i, m: __m256i) {
        let (j, s) = (i * K / 32, (i * K % 32) as i32);
        // SAFETY (of the intrinsics): the caller's target features include AVX2 (this is only
        // called from AVX2 functions, and inlined into them).
        unsafe {
            let x = if K == 32 { v } else { _mm256_and_si256(v, m) };
            if let Some(oj) = o.get_mut(j) {
                *oj = _mm256_or_si256(*oj, _mm256_sll_epi32(x, _mm_cvtsi32_si128(s)));
            }
            if s as usize + K > 32 {
                if let Some(on) = o.get_mut(j + 1) {
                    *on = _mm256_or_si256(*on, _mm256_srl_epi32(x, _mm_cvtsi32_si128(32 - s)));
                }
            }
        }
    }

    /// [`pack`] for the widths that divide 32 (`K` = 16 or 32), where a word holds whole fields
    /// and no transpose is needed (the portable packer, which the compiler vectorizes for these,
    /// is faster than the transposing kernel): 32 bits, a copy; 16 bits, each 16 fields masked
    /// to their low 16 bits and narrowed by `vpackusdw` (no saturation: every value is below
    /// 2^16), the 64-bit quarters put back in order (`vpermq`: `vpackusdw` interleaves its two
    /// sources per 128-bit half), 8 words stored.
    ///
    /// # Safety
    /// As [`pack`], with `K` = 16 or 32.
    #[target_feature(enable = "avx2")]
    unsafe fn whole<const K: usize>(f: *const u32, w: *mut u32, groups: usize) {
        if K == 32 {
            // SAFETY: f[0..32 groups] readable, w[0..32 groups] writable (the caller's
            // contract); separate slices (a `&` and a `&mut`), so not overlapping.
            unsafe { core::ptr::copy_nonoverlapping(f, w, 32 * groups) };
            return;
        }
        let m = _mm256_set1_epi32(0xffff);
        let mut i = 0;
        while i < 32 * groups {
            // SAFETY: i + 16 <= 32 groups: f[i..i + 16] readable and w[i / 2..i / 2 + 8]
            // writable (i / 2 + 8 <= 16 groups = groups K; the caller's contract).
            unsafe {
                let a = _mm256_and_si256(_mm256_loadu_si256(f.add(i).cast()), m);
                let b = _mm256_and_si256(_mm256_loadu_si256(f.add(i + 8).cast()), m);
                let v = _mm256_permute4x64_epi64::<0xd8>(_mm256_packus_epi32(a, b));
                _mm256_storeu_si256(w.add(i / 2).cast(), v);
            }
            i += 16;
        }
    }

    /// [`even`] from `u16` values (`NARROW`) for a width `k` known at run time: masked unless
    /// `exact` (every value below `2^k`). The one dispatch of [`band_row`] and [`band_rows`].
    ///
    /// # Safety
    /// As [`even`] with `NARROW`, `K = k`: `k` is 8, 10, 12 or 14 (any other is taken as 14).
    #[inline]
    pub(super) unsafe fn even_u16(k: u32, exact: bool, f: *const u8, out: *mut u8, steps: usize) {
        // SAFETY: the caller's contract.
        unsafe {
            match (k, exact) {
                (8, true) => even::<8, true, false>(f, out, steps),
                (10, true) => even::<10, true, false>(f, out, steps),
                (12, true) => even::<12, true, false>(f, out, steps),
                (_, true) => even::<14, true, false>(f, out, steps),
                (8, false) => even::<8, true, true>(f, out, steps),
                (10, false) => even::<10, true, true>(f, out, steps),
                (12, false) => even::<12, true, true>(f, out, steps),
                (_, false) => even::<14, true, true>(f, out, steps),
            }
        }
    }

    /// The packer for the even widths `K` = 8, 10, 12 and 14 (the tiled layouts' 14-bit local
    /// sums of 8 x 8 tiles of 8-bit texels), `steps` steps of 16 fields, `2 K` bytes each, in
    /// order, instead of the transposing passes: 16 fields as 16-bit lanes, each masked to its
    /// low `K` bits (from `u32` values, `NARROW = false`: narrowed by `vpackusdw`, no
    /// saturation after the mask, the quarters put back in order by `vpermq`; from `u16`
    /// values, `NARROW`: one load, and no mask without `MASK`, for values the caller knows are
    /// below `2^K`); pairs joined by `vpmaddwd` with weights `(1, 2^K)` (`f_0 + 2^K f_1 <
    /// 2^{2K} <= 2^28`); pairs of pairs in each 64-bit lane by two shifts (`P_0 + 2^{2K} P_1`,
    /// the `4 K / 8 = K / 2` bytes of 4 fields); the `K / 2` bytes of each 64-bit
    /// lane moved together (`vpshufb`, per 128-bit half: `K` bytes) and stored as two 16-byte
    /// stores `K` bytes apart. A store's bytes past its `K` are the next fields', rewritten by
    /// the next store in order; the last step stores `hi` as two 8-byte pieces ending on its
    /// last byte, so nothing past `2 K steps` bytes is written. About one instruction per
    /// field (the passes below: four).
    ///
    /// # Safety
    /// The CPU has AVX2; `K` is 8, 10, 12 or 14; `f` is valid for reads of `16 steps` values
    /// (`u16` if `NARROW`, else `u32`) and `out` for writes of `2 K steps` bytes. (`MASK`
    /// matters for `NARROW` only: `u32` values are always masked, as `vpackusdw` needs. A
    /// `u16` value of `2^K` or more without `MASK` gives wrong bits, never an access out of
    /// bounds.)
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn even<const K: usize, const NARROW: bool, const MASK: bool>(
        f: *const u8,
        out: *mut u8,
        steps: usize,
    ) {
        let m32 = _mm256_set1_epi32((1 << K) - 1);
        let m16 = _mm256_set1_epi16((1 << K) - 1);
        let weights = _mm256_set1_epi32((1 << K) << 16 | 1);
        let shift = _mm_cvtsi32_si128(32 - 2 * K as i32);
        let up = _mm256_set1_epi64x(32 - 2 * K as i64);
        // Byte j < K of each 128-bit half: byte j mod (K / 2) of its 64-bit lane j / (K / 2).
        let mut idx = [-128i8; 32];
        for (j, ix) in idx.iter_mut().enumerate() {
            let j = j % 16;
            if j < K {
                *ix = (8 * (j / (K / 2)) + j % (K / 2)) as i8;
            }
        }
        // SAFETY: 32 bytes: one unaligned load.
        let squeeze = unsafe { _mm256_loadu_si256(idx.as_ptr().cast()) };
        // Step s's 2 K bytes: `lo`'s first K, `hi`'s first K.
        let step = |s: usize| {
            // SAFETY: step s reads values 16 s..16 s + 16 <= 16 steps (s < steps, the
            // caller's contract); the intrinsics need AVX2, which this function enables.
            let p = unsafe {
                if NARROW && !MASK {
                    _mm256_loadu_si256(f.add(32 * s).cast())
                } else if NARROW {
                    _mm256_and_si256(_mm256_loadu_si256(f.add(32 * s).cast()), m16)
                } else {
                    let a = _mm256_and_si256(_mm256_loadu_si256(f.add(64 * s).cast()), m32);
                    let b = _mm256_and_si256(_mm256_loadu_si256(f.add(64 * s + 32).cast()), m32);
                    _mm256_permute4x64_epi64::<0xd8>(_mm256_packus_epi32(a, b))
                }
            };
            let d = _mm256_madd_epi16(p, weights);
            // Per 64-bit lane: P_0 (low half) + P_1 (high half) shifted down to bit 2 K, in two
            // instructions: P_0 shifted up by 32 - 2 K inside its half (`vpsllvd`; P_0 <
            // 2^{2 K}, so no bit leaves it), which makes the lane 2^{32 - 2 K} (P_0 + 2^{2 K}
            // P_1), then the lane shifted down by 32 - 2 K (its low bits are zeros; for K = 8
            // and 12 LLVM folds that byte shift into the `vpshufb` below). Two blends, a shift
            // and an OR before: `even` took 0.591 -> 0.433 instructions per texel of a tiled
            // build of 1,024^2 (callgrind; docs/benchmarks.md, twenty-first session).
            let q = _mm256_srl_epi64(_mm256_sllv_epi32(d, up), shift);
            let v = _mm256_shuffle_epi8(q, squeeze);
            (_mm256_castsi256_si128(v), _mm256_extracti128_si256::<1>(v))
        };
        let Some(last) = steps.checked_sub(1) else {
            return;
        };
        for s in 0..last {
            let (lo, hi) = step(s);
            // SAFETY: s + 1 < steps: the stores end at byte 2 K s + K + 16 <= 2 K (s + 1) + 2
            // K (K >= 8), inside the 2 K steps bytes of `out` (the caller's contract).
            unsafe {
                _mm_storeu_si128(out.add(2 * K * s).cast(), lo);
                _mm_storeu_si128(out.add(2 * K * s + K).cast(), hi);
            }
        }
        // The last step: `lo` (its bytes past K rewritten after), then the K bytes of `hi` as
        // two 8-byte stores, the second ending on byte 2 K (overlapping the first; one for K =
        // 8). No buffer: a copy through one waited on its two stores (a store-forwarding miss
        // per call).
        let (lo, hi) = step(last);
        let at = 2 * K * last;
        let h0 = _mm_cvtsi128_si64(hi) as u64;
        // SAFETY: the stores end at at + 16, at + K + 8 and at + 2 K, all <= at + 2 K (8 <= K
        // <= 14): the last step's 2 K bytes, the last of `out` (the caller's contract).
        unsafe {
            _mm_storeu_si128(out.add(at).cast(), lo);
            out.add(at + K).cast::<u64>().write_unaligned(h0);
            if K > 8 {
                let h1 = _mm_extract_epi64::<1>(hi) as u64;
                let tail = h0 >> (8 * (K - 8)) | h1 << (8 * (16 - K));
                out.add(at + 2 * K - 8).cast::<u64>().write_unaligned(tail);
            }
        }
    }

    /// One pass: the `gn` groups (all 8 if `FULL`) of 32 fields from `f` (group `g` at `f + 32
    /// g`) into `K` words each at `w` (group `g` at `w + K g`). The lanes past `gn` repeat the
    /// last group, and are not stored.
    ///
    /// # Safety
    /// The CPU has AVX2; `11 <= K <= 32`, `1 <= gn <= 8`; `f` valid for reads of `32 gn` values
    /// and `w` for writes of `gn K` words.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn pass<const K: usize, const FULL: bool>(f: *const u32, w: *mut u32, gn: usize) {
        // SAFETY: each (clamped) group holds 32 readable values (the caller's contract).
        let o = unsafe { lanes::<K, FULL, 32>(f, gn) };
        // SAFETY: w + K g holds K writable words for g < gn (the caller's contract).
        unsafe { store_words::<K, FULL>(w, gn, &o) };
    }

    /// The output words of the eight lanes' runs of `S` (32 or 16) fields, run `g` at `f + S g`
    /// (or the last run, `gn - 1`, for the lanes past it; no clamp if `FULL`): each field's low
    /// `K` bits at its place from bit 0 (word `floor(i K / 32)`, [`field`]), lane `g` for run
    /// `g`; the words past the runs' `S K` bits zero.
    ///
    /// # Safety
    /// The CPU has AVX2; `11 <= K <= 32`, `1 <= gn <= 8`; each (clamped) run is valid for
    /// reads of `S` values.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn lanes<const K: usize, const FULL: bool, const S: usize>(
        f: *const u32,
        gn: usize,
    ) -> [__m256i; K] {
        let m = _mm256_set1_epi32(if K >= 32 {
            -1
        } else {
            ((1u32 << K) - 1) as i32
        });
        let mut o = [_mm256_setzero_si256(); K];
        // Written out per field so that the word and the shift are constants.
        macro_rules! fields {
            ($at:literal: $($c:literal)*) => {{
                // SAFETY: at + 8 <= S: inside each (clamped) run.
                let v = unsafe { load8x8::<FULL, S>(f, gn, $at) };
                $(field::<K>(&mut o, $at + $c, v[$c], m);)*
            }};
        }
        fields!(0: 0 1 2 3 4 5 6 7);
        fields!(8: 0 1 2 3 4 5 6 7);
        if S == 32 {
            fields!(16: 0 1 2 3 4 5 6 7);
            fields!(24: 0 1 2 3 4 5 6 7);
        }
        o
    }

    /// [`pass`] over runs of 16 fields instead of groups of 32, for the runs left after the
    /// whole passes when they are 8 or fewer (the tiled build's 128 boundaries of a 1,024-texel
    /// row: 4 groups, which a pass of 8 lanes would take at the cost of 8; the 16 of a
    /// 128-texel row, which are no whole group), or the odd last run: `hn <= 8` runs from
    /// `f` (run `h` at `f + 16 h`), each lane one run, half the fields of a pass. Sixteen
    /// fields are `16 K` bits, `2 K` bytes, so run `h`'s fields start on byte `2 K h` of `out`
    /// and each run is packed as if from bit 0 (the same constant shifts in every lane) into
    /// `ceil(K / 2)` words; for an odd `K` the last word's upper 16 bits are zero and belong to
    /// the next run. The runs are stored 8 words at a time (4 for the last ones) at byte `2 K
    /// h`, the last words of every run first, so each run's first words, stored last,
    /// overwrite the zeros its predecessor's last word wrote over them. For an odd `K` the
    /// last run is written after the others, word by word, its last word's 16 bits only:
    /// nothing past `2 K hn` bytes is written.
    ///
    /// # Safety
    /// The CPU has AVX2; `11 <= K <= 32`, `1 <= hn <= 8`; `f` valid for reads of `16 hn` values
    /// and `out` for writes of `2 K hn` bytes.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn runs16<const K: usize, const ONE: bool>(f: *const u32, out: *mut u8, hn: usize) {
        // One run (`ONE`): a constant, and an instance of its own (each instance has one
        // caller, so each is inlined: with two callers this function was not, and cost more).
        let hn = if ONE { 1 } else { hn };
        // Only words 0..ceil(K / 2) are set: field 15 ends at bit 16 K.
        // SAFETY: each (clamped) run holds 16 readable values (the caller's contract).
        let o = unsafe { lanes::<K, false, 16>(f, hn) };
        let words = K.div_ceil(2);
        // For an odd K, the last run's last word would pass byte 2 K hn: that run is written
        // apart, after the others.
        let direct = if K.is_multiple_of(2) { hn } else { hn - 1 };
        // The chunks of each run's words, from the last: 8 or 4 words ending at `words`, then
        // 8 at a time down to 0 (a chunk may overlap the one after it: the same values).
        let mut end = words;
        // SAFETY: each store writes words j..j + 8 (or + 4) <= words of runs h < direct, bytes
        // 2 K h + 4 j.. < 2 K h + 4 words <= 2 K (h + 1) + 2 <= 2 K hn for h < hn - 1 (odd K),
        // and <= 2 K (h + 1) for an even K: inside out's 2 K hn bytes (the caller's contract).
        unsafe {
            while end > 0 {
                if end >= 8 {
                    store8x8::<false>(out, 2 * K, direct, end - 8, &o);
                    end -= 8;
                } else if end >= 4 {
                    store8x4::<false>(out, 2 * K, direct, end - 4, &o);
                    end -= 4;
                } else {
                    // Fewer than 4 left: words 0..4 (overlapping the chunk after them).
                    store8x4::<false>(out, 2 * K, direct, 0, &o);
                    end = 0;
                }
            }
        }
        if direct < hn {
            // The last run (odd K): its words one by one (lane hn - 1), the last one's low
            // 16 bits only.
            let lane = _mm256_set1_epi32(direct as i32);
            let at = 2 * K * direct;
            for (j, v) in o.iter().take(words).enumerate() {
                let x = _mm256_cvtsi256_si32(_mm256_permutevar8x32_epi32(*v, lane)) as u32;
                // SAFETY: bytes at + 4 j.. + 4 for j + 1 < words (4 j + 4 <= 2 K - 2), and at
                // + 4 j.. + 2 for the last (4 (words - 1) + 2 = 2 K): inside out's 2 K hn
                // bytes (the caller's contract).
                unsafe {
                    let to = out.add(at + 4 * j);
                    if j + 1 < words {
                        to.cast::<u32>().write_unaligned(x);
                    } else {
                        to.cast::<u16>().write_unaligned(x as u16);
                    }
                }
            }
        }
    }

    /// The kernel: `runs` runs of 16 `K`-bit fields from `f` into `2 K` bytes each from `w`
    /// (run `r`: `f[16 r..16 r + 16]` into bytes `2 K r..2 K (r + 1)`; a pair of runs is a
    /// group of 32 fields, `K` words); returns the fields packed, `16 runs` (for `K` = 16 or
    /// 32, the whole groups only: `32 floor(runs / 2)`). Eight groups per pass, each group in a
    /// 32-bit lane so that every shift is the same in all lanes; the groups left after the
    /// whole passes: 5 to 7, a last pass (`pass::<K, false>`); 4 or fewer, their runs one lane
    /// each ([`runs16`]: half the work of a pass); then, for an odd `runs`, the last run by
    /// [`runs16`] (a call of its own: one run, constant).
    ///
    /// # Safety
    /// The CPU has AVX2; `11 <= K <= 32`; `f` is valid for reads of `16 runs` values and `w`
    /// for writes of `2 K runs` bytes.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn pack<const K: usize>(f: *const u32, w: *mut u32, runs: usize) -> usize {
        if K == 16 || K == 32 {
            // SAFETY: forwarded (the caller's contract: 32 floor(runs / 2) values, as many
            // groups of K words).
            unsafe { whole::<K>(f, w, runs / 2) };
            return 32 * (runs / 2);
        }
        if K == 12 || K == 14 {
            // SAFETY: forwarded (the caller's contract: 16 runs values, 2 K runs bytes), K is
            // 12 or 14.
            unsafe { even::<K, false, true>(f.cast(), w.cast(), runs) };
            return 16 * runs;
        }
        let groups = runs / 2;
        let mut g0 = 0;
        // SAFETY: every pass reads groups g0..g0 + gn and writes their words, g0 + gn <=
        // groups; the odd last run reads f[32 groups..16 runs] and writes bytes 4 K groups..2
        // K runs (the caller's contract).
        unsafe {
            while g0 + 8 <= groups {
                pass::<K, true>(f.add(32 * g0), w.add(K * g0), 8);
                g0 += 8;
            }
            if groups - g0 > 4 {
                pass::<K, false>(f.add(32 * g0), w.add(K * g0), groups - g0);
            } else if g0 < groups {
                runs16::<K, false>(f.add(32 * g0), w.add(K * g0).cast(), 2 * (groups - g0));
            }
            if runs % 2 == 1 {
                runs16::<K, true>(f.add(32 * groups), w.add(K * groups).cast(), 1);
            }
        }
        16 * runs
    }
}

/// Whether [`modular_row`] takes the rows of a modular build of `u8` texels into `u32` entries,
/// one channel, `width` texels per row, `k`-bit fields: with AVX2, on an AVX-512 CPU too (on a
/// Zen 4 guest the fused row took 0.55x to 0.60x the time of the AVX-512 row kernel and packer
/// at 4,096^2, 0.76x at 1,024^2: docs/benchmarks.md, seventh session); `k` in
/// `MIN_PACK_BITS..=32`, at least one pass of 256 texels, and every row starting on a word
/// (`width k` a multiple of 32). The builder asks once: its working row is then stored
/// transposed in blocks of 256 (see [`modular_row`]) for the whole build.
pub(crate) fn modular_fused<T: Texel, E: Entry, const C: usize>(width: usize, k: u32) -> bool {
    T::BITS == 8
        && E::BITS == 32
        && C == 1
        && matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni)
        && (MIN_PACK_BITS..=32).contains(&k)
        && width >= MODULAR_PASS
        && width.checked_mul(k as usize).is_some_and(|b| b % 32 == 0)
}

/// Texels per pass of [`modular_row`]: 8 groups of 32.
pub(crate) const MODULAR_PASS: usize = 256;

/// How many passes ahead [`modular_row`] asks for the words it will write (with `past`, on
/// the plain path): 3, about 2 KiB at `k` = 21. Two and four passes ran as fast on a Zen 4
/// guest; eight no faster than none.
const MODULAR_AHEAD: usize = 3;

/// One row of the modular build, fused (AVX2): for the first `p = floor(n / 256)` passes of 256
/// texels, `acc[x] += r(x)` (wrapping; `r(x)` the row's prefix sum `t_0 + ... + t_x`) and the low
/// `k` bits of the new `acc[x]` packed into `words` from its bit 0 (field `x` at bit `x k`, as
/// `layouts::packed::pack_fields`). Returns the texels done (`256 p`) and `r` after them
/// (wrapping), for the caller to finish the row's tail; `None` (nothing written) unless
/// [`modular_fused`] holds and the slices are long enough (`acc`: `256 p`, `words`: `8 k p`).
///
/// **`acc` is transposed within each pass**: the value of position `256 b + 32 g + i` (group
/// `g`, field `i`) is kept at index `256 b + 8 i + g`, so that field `i` of the pass's eight
/// groups is one 8-lane vector. Only this function reads and writes that part of `acc`, and it
/// is the same for every row of a build ([`modular_fused`] is asked once), so the order is
/// private to the builder; positions from `256 p` on keep their own order. **That order is then
/// rotated** by `s` ([`modular_shift`], 0 to 7 entries: the first index of `acc` on 32 bytes):
/// index `j` of it is at `(j + s) mod n` (`n = acc.len()`), so that every 8-lane access of the
/// passes is on 32 bytes; the one vector that may cross the end of `acc` (the last pass's
/// last, when `s` exceeds the tail) goes through a 32-byte buffer, gathered before the passes
/// and scattered after. [`modular_tail`] gives the tail's positions, [`modular_untranspose`]
/// puts the row back in position order. (With the working row 16 bytes off 32 a modular build
/// of 4,096^2 with the streamed stores took 1.22x to 1.40x the flat build's time, against 0.89x
/// to 1.08x on 32 bytes, in single processes on a Zen 4 guest: docs/benchmarks.md, tenth
/// session.)
///
/// Per pass (`modular256::row`): the eight groups' texels loaded (one 32-byte load each), their
/// totals by `vpsadbw` and an exclusive scan across the lanes (plus the running sum) as each
/// lane's start; the bytes transposed (24 unpacks) so that field `i` of every group is one
/// vector; per field one widening, the running add, the add of `acc` (one load, one store) and
/// the constant shifts of the AVX2 packer (`pack256`); the `k` words of each group transposed
/// back and stored. It replaces the row kernel's pass, the packer's pass over the row, and the
/// packer's transposes of the values on their way in.
///
/// With `past` (a layout past the caches: the builder passes it for one of at least
/// [`STREAM_MIN_BYTES`]):
/// - on a CPU with AVX-512 VL ([`Kernel::Avx512Vnni`]), a row whose words start on 16 bytes
///   stores them by non-temporal stores (`modular256::row_streamed`: each pass's `8 k` words,
///   which the packer holds as `k` registers of one word of each of the 8 groups, transposed
///   into the groups' rows and realigned by one two-register permute per 8 words, then two
///   16-byte `movntdq`), without reading each line first, and ends with an `sfence`. In one
///   process on a Zen 4 guest, a modular build of 4,096^2 (`k` = 21, 44 MB) took 0.95x to 1.13x
///   the flat build's time, against 1.09x to 1.41x with the plain stores (docs/benchmarks.md,
///   tenth session);
/// - otherwise each pass asks for the lines of the words [`MODULAR_AHEAD`] passes on
///   (`prefetcht0`), so that its stores do not wait on each line's read: on a Zen 4 guest a
///   modular build of 4,096^2 took 0.88x to 0.90x the time with them, one of 1,024^2 (2.75 MB,
///   in the L3) 1.03x, hence the threshold (docs/benchmarks.md, seventh session).
pub(crate) fn modular_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    acc: &mut [E],
    words: &mut [u32],
    k: u32,
    past: bool,
) -> Option<(usize, u32)> {
    if !modular_fused::<T, E, C>(texels.len(), k) {
        return None;
    }
    let t = cast::u8s(texels)?;
    let a = as_u32_mut::<E, C>(acc)?;
    let passes = t.len() / MODULAR_PASS;
    let ku = k as usize;
    if a.len() < passes * MODULAR_PASS || words.len() < passes * 8 * ku {
        return None;
    }
    if passes == 0 {
        return None;
    }
    // The passes' values: indices s..s + 256 passes of the ring, the last vector's 8 (ring
    // indices end - 8..end) in `last` when they cross the end of `a`.
    let (n, s) = (a.len(), modular_shift(a));
    let end = s + passes * MODULAR_PASS;
    // The entries past the end (< 8): the last vector is a[end - 8..n] then a[..over].
    let over = end.saturating_sub(n);
    let wraps = over > 0;
    let mut last = Line32([0; 8]);
    if wraps {
        let (x, y) = last.0.split_at_mut(8 - over);
        x.copy_from_slice(a.get(end - 8..n)?);
        y.copy_from_slice(a.get(..over)?);
    }
    let (tp, wp) = (t.as_ptr(), words.as_mut_ptr());
    let ap = a.get_mut(s..)?.as_mut_ptr();
    // The last vector: in `a` (inside: end <= n) or `last`.
    let lp = if wraps {
        last.0.as_mut_ptr()
    } else {
        ap.wrapping_add(passes * MODULAR_PASS - 8)
    };
    let run = if past && Kernel::best() == Kernel::Avx512Vnni && (wp as usize).is_multiple_of(16) {
        // SAFETY: as below, and AVX-512F and VL are available (`Kernel::Avx512Vnni`'s
        // detection includes them); `words` starts on 16 bytes (checked).
        let run = unsafe {
            by_pack_width!(
                ku,
                modular256::row_streamed(tp, ap, lp, wp, passes),
                return None
            )
        };
        fence();
        #[cfg(test)]
        STREAMED_ROWS.with(|c| c.set(c.get() + 1));
        run
    } else {
        // SAFETY: AVX2 is available (`modular_fused`: `Kernel::best` is AVX2 or AVX-512 VNNI,
        // whose detection includes AVX2's); `t` holds 256 passes texels; `ap` is `a` from
        // index s, and the kernel touches its values 0..256 passes - 8 (s + 256 passes - 8 <
        // n: s < 8 and 256 passes <= n) and the last vector's 8 at `lp` (inside `a` when
        // `end <= n`, else `last`); `words` holds 8 k passes words (checked above): what the
        // kernel reads and writes.
        unsafe {
            by_pack_width!(
                ku,
                modular256::row(tp, ap, lp, wp, passes, past),
                return None
            )
        }
    };
    if wraps {
        // The gather above checked both ranges: no return here, after the kernel wrote.
        let (x, y) = last.0.split_at(8 - over);
        if let Some(d) = a.get_mut(end - 8..n) {
            d.copy_from_slice(x);
        }
        if let Some(d) = a.get_mut(..over) {
            d.copy_from_slice(y);
        }
    }
    Some((passes * MODULAR_PASS, run))
}

/// Eight `u32` on 32 bytes: [`modular_row`]'s last vector when it crosses the working row's
/// end.
#[repr(align(32))]
struct Line32([u32; 8]);

/// The rotation of [`modular_row`]'s working row: the entries before its first index on 32
/// bytes (0 to 7; 0 unless `E` is `u32`, the only type the fused row takes).
fn modular_shift<E: Entry>(acc: &[E]) -> usize {
    if TypeId::of::<E>() != TypeId::of::<u32>() {
        return 0;
    }
    (32 - acc.as_ptr() as usize % 32) % 32 / 4
}

/// The positions of [`modular_row`]'s working row from `done` (its passes' `256 p`) on, in
/// position order: one or two runs of `acc` (`(a, b)`: `a`'s positions first), the rotation's
/// place for them (see there).
pub(crate) fn modular_tail<E: Entry>(acc: &mut [E], done: usize) -> (&mut [E], &mut [E]) {
    let (n, s) = (acc.len(), modular_shift(acc));
    let start = (s + done) % n.max(1);
    let len = n.saturating_sub(done);
    if start + len <= n {
        let a = acc.get_mut(start..start + len).unwrap_or(&mut []);
        (a, &mut [])
    } else {
        // start + len - n = s (the run wraps to the ring's first s indices): [start, n), [0, s).
        let (head, rest) = acc.split_at_mut(start.min(n));
        let b = head.get_mut(..start + len - n).unwrap_or(&mut []);
        (rest, b)
    }
}

/// Where [`modular_row`] keeps position `x = 32 g + i` of a pass (`x < 256`): at `8 i + g`.
const fn kept_at(x: usize) -> usize {
    8 * (x % 32) + x / 32
}

/// Puts a working row written by [`modular_row`] back in position order (the rotation undone,
/// then each full pass of 256 values from its transposed order).
pub(crate) fn modular_untranspose<E: Entry>(acc: &mut [E]) {
    let s = modular_shift(acc);
    if s < acc.len() {
        acc.rotate_left(s);
    }
    untranspose_passes(acc);
}

/// Each full pass of 256 values of `acc` from [`modular_row`]'s transposed order back to
/// position order (`acc` not rotated).
fn untranspose_passes<E: Entry>(acc: &mut [E]) {
    for pass in acc.chunks_exact_mut(MODULAR_PASS) {
        let mut t = [E::ZERO; MODULAR_PASS];
        t.copy_from_slice(pass);
        for (x, v) in pass.iter_mut().enumerate() {
            if let Some(&f) = t.get(kept_at(x)) {
                *v = f;
            }
        }
    }
}

mod modular256 {
    use super::*;

    /// The lanes' group totals: lane `g` is the sum of the 32 texels of `g[g]` (`vpsadbw`
    /// against zero gives four partial sums per group, at most 2,040 each; pairs of groups
    /// joined into 32-bit lanes, then the partial sums added across).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn totals(g: &[__m256i; 8]) -> __m256i {
        let z = _mm256_setzero_si256();
        // Lanes [a0 b0 a1 b1 | a2 b2 a3 b3]: the four partial sums of groups 2h (a), 2h + 1 (b).
        let pair = |h: usize| {
            _mm256_or_si256(
                _mm256_sad_epu8(g[2 * h], z),
                _mm256_slli_epi64::<32>(_mm256_sad_epu8(g[2 * h + 1], z)),
            )
        };
        let (r0, r1, r2, r3) = (pair(0), pair(1), pair(2), pair(3));
        // [A B C D | A B C D]: partial sums 0 + 1 (low half) and 2 + 3 (high half).
        let s01 = _mm256_add_epi32(_mm256_unpacklo_epi64(r0, r1), _mm256_unpackhi_epi64(r0, r1));
        let s23 = _mm256_add_epi32(_mm256_unpacklo_epi64(r2, r3), _mm256_unpackhi_epi64(r2, r3));
        _mm256_add_epi32(
            _mm256_permute2x128_si256::<0x20>(s01, s23),
            _mm256_permute2x128_si256::<0x31>(s01, s23),
        )
    }

    /// The eight groups' bytes transposed: 64-bit unit `q` of result `c[2 (i mod 16) / 4 + (i
    /// mod 4) / 2]`, with `q = (i mod 2) + 2 floor(i / 16)`, holds byte `i` of each group, group
    /// `g` in byte `g` (unpacks of bytes, 16-bit and 32-bit units, all within 128-bit halves).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn transpose(g: &[__m256i; 8]) -> [__m256i; 8] {
        // Bytes i = 0..8 (16..24 in the high half) and 8..16 (24..32), groups 2h, 2h + 1.
        let u = |h: usize| _mm256_unpacklo_epi8(g[2 * h], g[2 * h + 1]);
        let v = |h: usize| _mm256_unpackhi_epi8(g[2 * h], g[2 * h + 1]);
        let (u0, u1, u2, u3) = (u(0), u(1), u(2), u(3));
        let (v0, v1, v2, v3) = (v(0), v(1), v(2), v(3));
        // 32-bit units: column i, groups 0..4 (a) and 4..8 (b); quads of i.
        let a = [
            _mm256_unpacklo_epi16(u0, u1),
            _mm256_unpackhi_epi16(u0, u1),
            _mm256_unpacklo_epi16(v0, v1),
            _mm256_unpackhi_epi16(v0, v1),
        ];
        let b = [
            _mm256_unpacklo_epi16(u2, u3),
            _mm256_unpackhi_epi16(u2, u3),
            _mm256_unpacklo_epi16(v2, v3),
            _mm256_unpackhi_epi16(v2, v3),
        ];
        [
            _mm256_unpacklo_epi32(a[0], b[0]),
            _mm256_unpackhi_epi32(a[0], b[0]),
            _mm256_unpacklo_epi32(a[1], b[1]),
            _mm256_unpackhi_epi32(a[1], b[1]),
            _mm256_unpacklo_epi32(a[2], b[2]),
            _mm256_unpackhi_epi32(a[2], b[2]),
            _mm256_unpacklo_epi32(a[3], b[3]),
            _mm256_unpackhi_epi32(a[3], b[3]),
        ]
    }

    /// Byte `i` (0..32) of every group, widened: lane `g` is texel `32 g + i` (see
    /// [`transpose`]).
    #[inline(always)]
    fn column(c: &[__m256i; 8], i: usize) -> __m256i {
        let r = i % 16;
        let reg = c[2 * (r / 4) + (r % 4) / 2];
        // SAFETY (of the intrinsics): only inlined into AVX2 functions.
        unsafe {
            let x = if i < 16 {
                _mm256_castsi256_si128(reg)
            } else {
                _mm256_extracti128_si256::<1>(reg)
            };
            let x = if i.is_multiple_of(2) {
                x
            } else {
                _mm_unpackhi_epi64(x, x)
            };
            _mm256_cvtepu8_epi32(x)
        }
    }

    /// [`modular_row`]'s kernel over `passes` passes of 256 texels (with `prefetch`, the
    /// hints for the words [`MODULAR_AHEAD`] passes on); returns the running sum after them.
    ///
    /// # Safety
    /// The CPU has AVX2; `11 <= K <= 32`; `passes >= 1`; `t` is valid for reads of `256
    /// passes` bytes, `acc` for reads and writes of `256 passes - 8` values and `last` of 8
    /// (the last pass's last vector: `acc + 256 passes - 8`, or a buffer of its own), `w` for
    /// writes of `8 K passes` words, and none overlaps another.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn row<const K: usize>(
        t: *const u8,
        acc: *mut u32,
        last: *mut u32,
        w: *mut u32,
        passes: usize,
        prefetch: bool,
    ) -> u32 {
        let (m, seven) = (field_mask::<K>(), lane7());
        let mut carry = _mm256_setzero_si256();
        for p in 0..passes {
            // SAFETY: p < passes (the caller's contract, forwarded).
            let wp = unsafe { pass::<K, false>(t, acc, last, w, p, passes, &mut carry, m, seven) };
            if prefetch {
                // The words of the pass `MODULAR_AHEAD` passes on (past the row's end: the next
                // row's, or none; a hint only, never dereferenced, so the pointer may point
                // anywhere), one hint per 64 bytes.
                let ahead = wp.wrapping_add(8 * K * MODULAR_AHEAD).cast::<u8>();
                let mut b = 0;
                while b < 32 * K {
                    hint(ahead.wrapping_add(b));
                    b += 64;
                }
            }
        }
        _mm256_cvtsi256_si32(carry) as u32
    }

    /// [`row`] with the words stored by non-temporal 16-byte stores ([`store_streamed`]), no
    /// prefetch hints and no fence (the caller fences after the row).
    ///
    /// # Safety
    /// As [`row`], with AVX-512F and AVX-512 VL, and `w` on 16 bytes.
    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    pub(super) unsafe fn row_streamed<const K: usize>(
        t: *const u8,
        acc: *mut u32,
        last: *mut u32,
        w: *mut u32,
        passes: usize,
    ) -> u32 {
        let (m, seven) = (field_mask::<K>(), lane7());
        let mut carry = _mm256_setzero_si256();
        for p in 0..passes {
            // SAFETY: p < passes (the caller's contract, forwarded).
            unsafe { pass::<K, true>(t, acc, last, w, p, passes, &mut carry, m, seven) };
        }
        _mm256_cvtsi256_si32(carry) as u32
    }

    /// The low `K` bits of every lane.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn field_mask<const K: usize>() -> __m256i {
        _mm256_set1_epi32(if K >= 32 {
            -1
        } else {
            ((1u32 << K) - 1) as i32
        })
    }

    /// Pass `p` of [`row`] (plain stores) or [`row_streamed`] (`STREAM`); `carry` is the
    /// running sum in every lane, before and after; `m` is [`field_mask`], `seven` is
    /// [`lane7`]. Returns where the pass's words start.
    ///
    /// # Safety
    /// As the caller's ([`row`] or [`row_streamed`]), with `p < passes`. Inlined into them
    /// (no target features of its own: theirs).
    #[inline(always)]
    #[allow(
        clippy::too_many_arguments,
        reason = "the row's pointers, the pass and its running state"
    )]
    unsafe fn pass<const K: usize, const STREAM: bool>(
        t: *const u8,
        acc: *mut u32,
        last: *mut u32,
        w: *mut u32,
        p: usize,
        passes: usize,
        carry: &mut __m256i,
        m: __m256i,
        seven: __m256i,
    ) -> *mut u32 {
        // SAFETY (of the intrinsics): the caller's target features include AVX2.
        unsafe {
            // SAFETY: p < passes: the pass's 256 texels, 256 values and 8 K words are inside
            // the caller's slices.
            let (tp, ap, wp) = (t.add(256 * p), acc.add(256 * p), w.add(8 * K * p));
            // The pass's last vector: the row's last in `last`.
            let a31 = if p + 1 == passes { last } else { ap.add(248) };
            // SAFETY: tp[32 g..32 g + 32] is readable for g < 8: unaligned loads.
            let g: [__m256i; 8] =
                core::array::from_fn(|h| _mm256_loadu_si256(tp.add(32 * h).cast()));
            let tot = totals(&g);
            // Inclusive scan across the 8 lanes: within the halves, then the low half's total
            // into the high half.
            let mut x = _mm256_add_epi32(tot, _mm256_slli_si256::<4>(tot));
            x = _mm256_add_epi32(x, _mm256_slli_si256::<8>(x));
            let low = _mm256_shuffle_epi32::<0xff>(x);
            x = _mm256_add_epi32(x, _mm256_permute2x128_si256::<0x08>(low, low));
            // Each group's start: the running sum and the groups before it.
            let mut run = _mm256_add_epi32(*carry, _mm256_sub_epi32(x, tot));
            *carry = _mm256_add_epi32(*carry, _mm256_permutevar8x32_epi32(x, seven));
            let c = transpose(&g);
            let mut o = [_mm256_setzero_si256(); K];
            macro_rules! steps {
                ($($i:literal)*) => {$(
                    run = _mm256_add_epi32(run, column(&c, $i));
                    // SAFETY: 8 i + 8 <= 256: inside the pass's values (the last pass's: 248, and
                    // its vector 31 at `last`: the caller's contract); unaligned accesses.
                    let at = if $i == 31 { a31 } else { ap.add(8 * $i) };
                    let f = _mm256_add_epi32(run, _mm256_loadu_si256(at.cast()));
                    _mm256_storeu_si256(at.cast(), f);
                    pack256::field::<K>(&mut o, $i, f, m);
                )*};
            }
            steps!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
            steps!(16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31);
            if STREAM {
                // SAFETY: the pass's 8 K words from wp, on 16 bytes (w is, and 32 K bytes per
                // pass); AVX-512F and VL (the caller's, `row_streamed`).
                store_streamed::<K>(wp, &o);
            } else {
                // SAFETY: wp + K g holds K writable words for g < 8 (the pass's 8 K words).
                pack256::store_words::<K, true>(wp, 8, &o);
            }
            wp
        }
    }

    /// Where output vector `v` of a pass comes from ([`store_streamed`]): its 8 words (words
    /// `8 v..8 v + 8` of the pass's `8 K`) are lanes `idx` of the two transposed registers `a`
    /// and `b` (lane `l` of `a` for `idx = l`, of `b` for `idx = 8 + l`). A register is named
    /// `8 r + g`: group `g`'s words `8 r..8 r + 8` for `r < K / 8`, its last 8 words `K - 8..K`
    /// for `r = K / 8` (when 8 does not divide `K`).
    #[derive(Clone, Copy)]
    pub(super) struct Source {
        pub(super) a: usize,
        pub(super) b: usize,
        pub(super) idx: [i32; 8],
    }

    /// [`Source`] of every output vector `v < K` of a pass (entries past `K` unused). Word `x`
    /// of the pass is word `u = x mod K` of group `g = floor(x / K)`. Where 8 does not divide
    /// `K` and the vector's words of group `g` run to the group's last word, they are taken from
    /// its last 8 words (they are at most 8); otherwise each from its words `8 floor(u / 8)..`,
    /// or the last 8 for the `K mod 8` words past the whole blocks. So the 8 words come from at
    /// most two registers: across two groups (`K > 8`: never three) the end of one (its last 8)
    /// and the start of the next (its first block); within a group, words of two adjacent
    /// blocks, or of the last whole block and the last 8. The assertion checks it for each
    /// `K` at compile time.
    pub(super) const fn sources<const K: usize>() -> [Source; 32] {
        let mut out = [Source {
            a: 0,
            b: 0,
            idx: [0; 8],
        }; 32];
        let last = !K.is_multiple_of(8);
        let mut v = 0;
        while v < K {
            let mut l = 0;
            let (mut a, mut b) = (usize::MAX, usize::MAX);
            while l < 8 {
                let x = 8 * v + l;
                let (g, u) = (x / K, x % K);
                // Whether this group's words in the vector run to its last word.
                let to_end = 8 * v + 7 >= K * g + K - 1;
                let (r, lane) = if last && (to_end || u >= 8 * (K / 8)) {
                    (K / 8, u + 8 - K)
                } else {
                    (u / 8, u % 8)
                };
                let reg = 8 * r + g;
                if a == usize::MAX || a == reg {
                    a = reg;
                    out[v].idx[l] = lane as i32;
                } else {
                    // A third register would be a bug in the reasoning above: caught at
                    // compile time (this runs in a constant).
                    assert!(b == usize::MAX || b == reg);
                    b = reg;
                    out[v].idx[l] = 8 + lane as i32;
                }
                l += 1;
            }
            out[v].a = a;
            out[v].b = if b == usize::MAX { a } else { b };
            v += 1;
        }
        out
    }

    /// Lanes `idx` of `a` (0..8) and `b` (8..16): `vpermt2d`. Under Miri, which does not emulate
    /// it, two `vpermd` and a blend (the same lanes).
    #[inline]
    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    pub(super) fn perm2(a: __m256i, idx: __m256i, b: __m256i) -> __m256i {
        #[cfg(not(miri))]
        let v = _mm256_permutex2var_epi32(a, idx, b);
        #[cfg(miri)]
        let v = _mm256_blendv_epi8(
            _mm256_permutevar8x32_epi32(a, idx),
            _mm256_permutevar8x32_epi32(b, idx),
            _mm256_cmpgt_epi32(idx, _mm256_set1_epi32(7)),
        );
        v
    }

    /// Stores the `8 K` words of a pass (`o[j]`: word `j` of group `g` in lane `g`; group `g`'s
    /// words at `w + K g`) as `K` vectors of 8 consecutive words, each by two non-temporal
    /// 16-byte stores: the `K` registers transposed into groups' rows ([`pack256::rows8x8`]:
    /// words `0..8`, `8..16`, ..., and the last 8 when 8 does not divide `K`), each output
    /// vector then one two-register permute of them ([`sources`], constants per `K`). With
    /// AVX-512 VL's 32 registers the rows stay in registers (with AVX2's 16 they spilled:
    /// docs/benchmarks.md, ninth session).
    ///
    /// # Safety
    /// AVX2, AVX-512F and AVX-512 VL; `w` is on 16 bytes and valid for writes of `8 K` words.
    #[inline(always)]
    unsafe fn store_streamed<const K: usize>(w: *mut u32, o: &[__m256i; K]) {
        // SAFETY (of the intrinsics): the caller's target features.
        unsafe {
            let z = _mm256_setzero_si256();
            let mut rows = [[z; 8]; 5];
            let mut r = 0;
            while r < K / 8 {
                rows[r] = pack256::rows8x8(o, 8 * r);
                r += 1;
            }
            if !K.is_multiple_of(8) {
                rows[K / 8] = pack256::rows8x8(o, K - 8);
            }
            macro_rules! out {
                ($($v:literal)*) => {$(
                    if $v < K {
                        let s = const { sources::<K>() }[$v];
                        let i = s.idx;
                        let idx = _mm256_setr_epi32(i[0], i[1], i[2], i[3], i[4], i[5], i[6], i[7]);
                        let v = perm2(rows[s.a / 8][s.a % 8], idx, rows[s.b / 8][s.b % 8]);
                        // SAFETY: words 8 v..8 v + 8 < 8 K of the pass, on 16 bytes.
                        store_copy(w.add(8 * $v), _mm256_castsi256_si128(v), true);
                        store_copy(w.add(8 * $v + 4), _mm256_extracti128_si256::<1>(v), true);
                    }
                )*};
            }
            out!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
            out!(16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31);
        }
    }
}

/// Where the tiled builder will pack a row's fields, for the row kernels' prefetches: per
/// component, the first word and the number of words (a hint only: never read or written
/// through, so any pointer will do; the builder passes the table's words).
pub(crate) use crate::layouts::tiled::Ahead;

/// A component row the tiled row step may pack its local sums into directly (see
/// [`tiled_row`]): `k`-bit fields from bit `bit` of `words` (field `i` at bit `bit + i k`,
/// the layouts' order: `layouts::packed::pack_fields`), the bits around them kept.
pub(crate) struct PackTo<'w> {
    /// The words the row's fields go to (from the word holding its first bit).
    pub(crate) words: &'w mut [u32],
    /// The row's first bit in `words` (below 32).
    pub(crate) bit: u64,
    /// The field width.
    pub(crate) k: u32,
    /// Whether every local sum is below `2^k` (the layout's width proof, without a modulus):
    /// then not masked to `k` bits (wrong bits if it is not, never an access out of bounds).
    pub(crate) exact: bool,
}

/// The tiled builder's row step (`layouts::tiled`'s `row_fields`, the same values) with
/// AVX-512 VNNI, one pass over the row: for `u8` texels, `u32` entries, one channel and tiles
/// of `tile` in {2, 4, 8, 16} texels along x (a tile never straddles a 16-lane block).
///
/// Position `x = 1..=n` is at index `x - 1` of `acc` and `lower`. Per `x`, with `r(x)` the
/// row's prefix sum `t_0 + ... + t_{x-1}` at a boundary (`x` a multiple of `tile`) and the sum
/// `t_{trunc(x)} + ... + t_{x-1}` inside its tile elsewhere (`trunc(x)`: `x` rounded down to
/// a multiple of `tile`): `acc[x] += lower[x] + r(x)` (wrapping; `lower` optional and cleared
/// as it is read), then the boundaries' `acc[x]` into `bnd` and the others into `local`, in
/// order of `x`. Returns the values written to `bnd` and `local`, and how many of the local
/// sums, from the first, went into `pack` instead of `local` (`local[..kp]` is then not
/// written); `None` (nothing written) for other types, tile widths or CPUs, or slices shorter
/// than the row needs (`acc`, `lower`: `n`; `bnd`: `n / tile`; `local`: `n - n / tile`).
///
/// Per block of 16 texels: four `vpdpbusd` with weights that give each lane its `r(x)` (the
/// build kernel's triangle, cut at the tile starts for the local lanes), the running sum added
/// to the boundary lanes (a masked add), the rows added and stored, and two `vpermd` with
/// stores compacting the lanes into the two streams (the lane pattern is the same in every
/// block: constant tables per tile width, [`TILE_TABLES`]). While it computes, it prefetches
/// the words of `ahead` (where the caller will pack the fields), spread over the blocks.
///
/// With `pack` (tiles of 8, an even width `k` of 8 to 14 bits, a byte-aligned `bit`, a CPU with
/// AVX-512BW and VBMI as well: `tiled512::kernel8_packed`), the local sums of each pair of
/// blocks (28 values) are packed straight into `pack.words` instead (`kp` a multiple of 28),
/// the odd last block and the tail into `local` as above.
#[allow(
    clippy::too_many_arguments,
    reason = "the row step's slices, the prefetch hint and the packing target"
)]
pub(crate) fn tiled_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    lower: Option<&mut [E]>,
    acc: &mut [E],
    tile: usize,
    bnd: &mut [E],
    local: &mut [E],
    ahead: Ahead,
    pack: Option<PackTo<'_>>,
) -> Option<(usize, usize, usize)> {
    // SAFETY: `Kernel::best` and `vbmi` are what this CPU runs (CPUID, cached).
    unsafe {
        tiled_row_with::<T, E, C>(
            Kernel::best(),
            vbmi(),
            texels,
            lower,
            acc,
            tile,
            bnd,
            local,
            ahead,
            pack,
        )
    }
}

/// [`tiled_row`] with `kernel` and, if `vbmi`, the packing kernel: AVX-512 VNNI for tiles of
/// 2, 4, 8 and 16 texels; AVX2 for tiles of 8 (each 128-bit half of its 16 texels is one tile,
/// see `tiled256`); `None` otherwise.
///
/// # Safety
/// `kernel` is [`Kernel::available`] on this CPU, and `vbmi` is `false` or [`vbmi`]'s answer:
/// the kernels it selects use those instructions.
#[allow(
    clippy::too_many_arguments,
    reason = "the row step's slices, as tiled_row's, plus the kernels"
)]
unsafe fn tiled_row_with<T: Texel, E: Entry, const C: usize>(
    kernel: Kernel,
    vbmi: bool,
    texels: &[T],
    lower: Option<&mut [E]>,
    acc: &mut [E],
    tile: usize,
    bnd: &mut [E],
    local: &mut [E],
    ahead: Ahead,
    pack: Option<PackTo<'_>>,
) -> Option<(usize, usize, usize)> {
    let t = cast::u8s(texels)?;
    let acc = as_u32_mut::<E, C>(acc)?;
    let mut lower = match lower {
        None => None,
        Some(l) => Some(as_u32_mut::<E, C>(l)?),
    };
    let bnd = as_u32_mut::<E, C>(bnd)?;
    let local = as_u32_mut::<E, C>(local)?;
    let wide = kernel == Kernel::Avx512Vnni && matches!(tile, 2 | 4 | 8 | 16);
    if !(wide || kernel == Kernel::Avx2 && tile == 8) {
        return None;
    }
    let n = t.len();
    let nb = n / tile;
    if acc.len() < n
        || lower.as_ref().is_some_and(|l| l.len() < n)
        || bnd.len() < nb
        || local.len() < n - nb
    {
        return None;
    }
    let blocks = n / BLOCK;
    let lp = match &mut lower {
        Some(l) => l.as_mut_ptr(),
        None => core::ptr::null_mut(),
    };
    let (tp, ap, bp, op) = (
        t.as_ptr(),
        acc.as_mut_ptr(),
        bnd.as_mut_ptr(),
        local.as_mut_ptr(),
    );
    // The packing kernel: its pairs of blocks' local sums, 7 k / 2 bytes per pair, must fit
    // `pack.words` from byte bit / 8.
    let packed = match pack {
        Some(PackTo {
            words,
            bit,
            k,
            exact,
        }) if wide
            && vbmi
            && tile == 8
            && blocks >= 2
            && matches!(k, 8 | 10 | 12 | 14)
            && bit % 8 == 0
            && bit < 32
            && (bit as usize / 8 + blocks / 2 * PAIR * k as usize / 8) <= 4 * words.len() =>
        {
            Some((
                words
                    .as_mut_ptr()
                    .cast::<u8>()
                    .wrapping_add(bit as usize / 8),
                k,
                exact,
            ))
        }
        _ => None,
    };
    macro_rules! run {
        ($($tile:literal)*) => {
            match (tile, lp.is_null()) {
                $(
                    ($tile, true) => tiled512::kernel::<false, $tile>(tp, lp, ap, bp, op, blocks, ahead),
                    ($tile, false) => tiled512::kernel::<true, $tile>(tp, lp, ap, bp, op, blocks, ahead),
                )*
                _ => return None,
            }
        };
    }
    // SAFETY: the kernel's features are available (`kernel` is, argument 1: AVX-512F and VNNI
    // for `wide`, else AVX2; `packed` only with `vbmi`, argument 2: AVX-512BW and VBMI as
    // well); the kernel reads `t[..16 blocks]`, reads and writes `acc` and (if not null)
    // `lower` there, and writes `bnd[..16 blocks / tile]` and `local[..16 blocks - 16 blocks /
    // tile]`, all inside the slices (checked above; 16 blocks <= n); the packing kernel writes
    // `7 k / 2` bytes per pair of blocks from `out`, inside `pack.words` (checked above), and
    // not `local[..28 pairs]`; the six slices are distinct borrows.
    let (run, kp) = unsafe {
        match packed {
            Some((out, k, exact)) => (
                match (lp.is_null(), exact) {
                    (true, true) => tiled512::kernel8_packed::<false, true>(
                        tp, lp, ap, bp, op, blocks, out, k, ahead,
                    ),
                    (true, false) => tiled512::kernel8_packed::<false, false>(
                        tp, lp, ap, bp, op, blocks, out, k, ahead,
                    ),
                    (false, true) => tiled512::kernel8_packed::<true, true>(
                        tp, lp, ap, bp, op, blocks, out, k, ahead,
                    ),
                    (false, false) => tiled512::kernel8_packed::<true, false>(
                        tp, lp, ap, bp, op, blocks, out, k, ahead,
                    ),
                },
                blocks / 2 * PAIR,
            ),
            None if wide => (run!(2 4 8 16), 0),
            None if lp.is_null() => (
                tiled256::kernel::<false>(tp, lp, ap, bp, op, blocks, ahead),
                0,
            ),
            None => (
                tiled256::kernel::<true>(tp, lp, ap, bp, op, blocks, ahead),
                0,
            ),
        }
    };
    // The tail after the last full block, portable: the same values (it starts at a tile
    // boundary: 16 blocks is a multiple of the tile).
    let i0 = blocks * BLOCK;
    let (mut kb, mut kl) = (i0 / tile, i0 - i0 / tile);
    tile_walk(
        i0,
        n,
        tile,
        run,
        |i| u32::from(t[i]),
        |i, boundary, f| {
            let mut v = acc[i].wrapping_add(f);
            if let Some(l) = &mut lower {
                v = v.wrapping_add(l[i]);
                l[i] = 0;
            }
            acc[i] = v;
            if boundary {
                bnd[kb] = v;
                kb += 1;
            } else {
                local[kl] = v;
                kl += 1;
            }
        },
    );
    Some((kb, kl, kp))
}

/// The portable walk over a row's columns `i0..n` after the vectorized blocks (`i0` a tile
/// start), tiles of `tile` columns, shared by the row steps' tails: per column its value
/// `col(i)` (a texel, or a column sum) added to the sum inside its tile; at a tile's last
/// column that sum joins the running sum `run` and `out(i, true, run)` gets it (a boundary),
/// elsewhere `out(i, false, the sum inside the tile so far)` (a local sum). Wrapping, as the
/// kernels. `col(i)` runs before `out(i)`.
#[inline(always)]
fn tile_walk(
    i0: usize,
    n: usize,
    tile: usize,
    mut run: u32,
    mut col: impl FnMut(usize) -> u32,
    mut out: impl FnMut(usize, bool, u32),
) {
    let mut inner = 0u32;
    for i in i0..n {
        inner = inner.wrapping_add(col(i));
        if (i + 1) % tile == 0 {
            run = run.wrapping_add(inner);
            inner = 0;
            out(i, true, run);
        } else {
            out(i, false, inner);
        }
    }
}

/// The local sums of a pair of blocks of tiles of 8 (2 x 14): what the packing kernel packs
/// at a time (4 fields of `k` bits per 64-bit lane, `7 k / 2` bytes).
const PAIR: usize = 28;

/// How far ahead of its own packed bytes each row of [`band_rows`] asks for the layout's
/// lines (at most a row: then the next row's): 2 KiB, a row of 1,024 texels (1,568 bytes of
/// 14-bit local sums) a row ahead, about 0.25 us before the next row stores to them. Asking for
/// a row's own lines 16 blocks ahead in the row itself left a cold build waiting for them. In
/// the rounds' mixed order (Zen 4 guest, in one process, docs/benchmarks.md, seventeenth
/// session), with [`TexturePages`], a tiled build of 1,024^2 took about 0.9x the time of
/// neither on 2 MiB pages; asking a whole row ahead at 4,096^2 (6,272 bytes a row) took 1.03x
/// there, where 2 KiB took 0.99x.
const BAND_WORDS_AHEAD: usize = 2048;

/// The most band rows [`band_rows`] takes at once: the builder's scratch row holds the
/// boundaries of `(n + 1) / (n / 8)` rows, 8 for every width `band_rows` takes (a multiple of
/// 32): a tile row of 8 (7 band rows) in one run, of 16 (15) in two.
pub(crate) const MAX_BAND_ROWS: usize = 8;

/// [`tiled_row`]'s lane pattern for one tile width: lane `l` of a block holds position `x =
/// 16 b + l + 1`, texel `j` of the block (`16 b + j`) counts in every `x > 16 b + j`. With `r =
/// (l + 1) mod tile`, lane `l` is a tile boundary if `r = 0`: it takes the block's prefix sum
/// (texels `j <= l`; plus the running sum before the block); else a local sum, which takes the
/// texels of its tile before it, `l + 1 - r <= j <= l`.
struct TileTable {
    /// `vpdpbusd` weights ([`avx512vnni::dot16`]): byte `j` of lane `l` of group `g` is 1 when
    /// texel `4 g + j` counts in lane `l`.
    w: [[i32; 16]; 4],
    /// The boundary lanes (bit `l`).
    bmask: u16,
    /// The local lanes in order, then zeros (`vpermd` indices).
    local: [i32; 16],
    /// The boundary lanes in order, then zeros.
    bnd: [i32; 16],
}

const fn tile_table(tile: usize) -> TileTable {
    let mut tab = TileTable {
        w: [[0; 16]; 4],
        bmask: 0,
        local: [0; 16],
        bnd: [0; 16],
    };
    let (mut nl, mut nb) = (0, 0);
    let mut l = 0;
    while l < 16 {
        let r = (l + 1) % tile;
        // The first texel lane l takes: 0 at a boundary, its tile's first otherwise.
        let first = if r == 0 { 0 } else { l + 1 - r };
        if r == 0 {
            tab.bmask |= 1 << l;
            tab.bnd[nb] = l as i32;
            nb += 1;
        } else {
            tab.local[nl] = l as i32;
            nl += 1;
        }
        let mut j = first;
        while j <= l {
            tab.w[j / 4][l] |= 1 << (8 * (j % 4));
            j += 1;
        }
        l += 1;
    }
    tab
}

/// Tile widths 2, 4, 8, 16 (index `log2 tile - 1`).
static TILE_TABLES: [TileTable; 4] = [tile_table(2), tile_table(4), tile_table(8), tile_table(16)];

/// Asks for the 64-byte line that holds `p` (`prefetcht0`): a hint, the crate's one call of
/// it. A hint reads and writes nothing and never faults, whatever `p` points to (past a slice,
/// or at nothing), so this is safe to call with any pointer.
#[inline(always)]
fn hint(p: *const u8) {
    // SAFETY: SSE is baseline on x86-64; a prefetch dereferences nothing, so it cannot fault
    // or change memory.
    unsafe { _mm_prefetch::<_MM_HINT_T0>(p.cast()) };
}

/// Bytes past the rows a step of the tiled build is about to read up to which
/// [`TexturePages`] has asked for the texture's pages.
const PAGE_LEAD: usize = 16 << 10;

/// The pages [`TexturePages`] asks for: 4 KiB, the smallest page on x86-64, the span the
/// hardware's stream prefetchers stop at.
const PAGE: usize = 4096;

/// The texture's pages asked for before the tiled build reads them: before each step (a row,
/// or a run of band rows), [`TexturePages::ask`] asks for one line of every 4 KiB page that
/// starts below [`PAGE_LEAD`] bytes past the [`MAX_BAND_ROWS`] rows from the step's on, each
/// page once: about 4 to 6 pages ahead at 1,024 texels a row. The line is the page's first,
/// or, where the page starts between two rows (a stride longer than the row), the next row's
/// first; pages of padding alone are skipped.
///
/// Why: after other jobs (its texture out of the caches) `perf` put a cold tiled build's extra
/// time on the loads of the band rows' texels (about a quarter of `band512::row_packed`'s
/// samples on the instruction after the texels' load, none there back to back). The tiled build
/// is bound by its arithmetic, so a load that waits costs it the whole wait, where the flat
/// build, bound by its stores, drains them meanwhile. The hardware's stream prefetchers start
/// over at each 4 KiB page; one hint per page, well ahead, presumably takes the page's first
/// miss (and its page walk) out of the build's way (inferred: the guest has no hardware
/// counters). Measured in the rounds' mixed order, in one process with the hints switched at
/// run time (Zen 4 guest, docs/benchmarks.md, seventeenth session): a tiled build of 1,024^2
/// on 2 MiB pages (the texture on 4 KiB ones) took 0.96x the time (median of 6 runs) with the
/// pages asked for alone and 0.90x with the band rows' words asked further ahead too
/// ([`BAND_WORDS_AHEAD`]); of 4,096^2 (everything on 2 MiB pages) 1.01x and 0.99x. Asking for
/// the first 2 to 64 lines of each page took longer than asking for one, and asking for every
/// line 256 bytes to 16 KiB ahead gained nothing.
pub(crate) struct TexturePages {
    /// The texture's first byte (the hints' base: never dereferenced).
    base: *const u8,
    /// Bytes from the first texel to the last row's end.
    len: usize,
    /// Bytes from one row's start to the next's.
    stride: usize,
    /// Bytes of a row's texels.
    row: usize,
    /// The next page start not asked for (bytes from `base`).
    next: usize,
    /// Bytes below which a line has been asked for (none twice).
    asked: usize,
}

impl TexturePages {
    /// The schedule for `texture`'s rows from row `from` on.
    pub(crate) fn new<T: Texel, const C: usize>(
        texture: &crate::Texture<'_, T, C>,
        from: usize,
    ) -> Self {
        let (data, stride) = texture.storage();
        let size = core::mem::size_of::<T>();
        let (stride, row) = (stride.saturating_mul(size), (texture.width() * C) * size);
        // The last row's end: inside `data` (`Texture::with_stride` checked it).
        let len = (texture.height() - 1)
            .saturating_mul(stride)
            .saturating_add(row)
            .min(core::mem::size_of_val(data));
        let base: *const u8 = data.as_ptr().cast();
        // The first page start (by address) at or after row `from`'s first byte.
        let at = from.saturating_mul(stride).min(len);
        let into = (base.addr() % PAGE + at % PAGE) % PAGE;
        TexturePages {
            base,
            len,
            stride,
            row,
            next: at + (PAGE - into) % PAGE,
            asked: at,
        }
    }

    /// Before the step that starts at row `y`: asks for the line [`TexturePages::due`] gives
    /// for each page.
    pub(crate) fn ask(&mut self, y: usize) {
        let base = self.base;
        self.due(y, |at| hint(base.wrapping_add(at)));
    }

    /// `each(at)` for the pages due before the step that starts at row `y`, in order: those that
    /// start below [`PAGE_LEAD`] bytes past rows `y..y + MAX_BAND_ROWS` and were not due
    /// before (steps come in increasing `y`), `at` (bytes from the first texel) the page's
    /// first byte, or the next row's first where the page starts past a row's texels; none
    /// past the last row, none twice.
    fn due(&mut self, y: usize, mut each: impl FnMut(usize)) {
        let to = y
            .saturating_add(MAX_BAND_ROWS)
            .saturating_mul(self.stride)
            .saturating_add(PAGE_LEAD)
            .min(self.len);
        while self.next < to {
            let page = self.next;
            self.next += PAGE;
            // Past a row's texels (in the padding to the next row): that row's start.
            let past = page % self.stride >= self.row;
            let at = if past {
                (page / self.stride + 1) * self.stride
            } else {
                page
            };
            if at >= self.asked && at < self.len {
                each(at);
                self.asked = at + 1;
            }
        }
    }
}

/// When the AVX2 band rows' kernels ([`band_row`], [`band_rows`], [`band_end_row`]) ask for the
/// lines of their `ahead` slices ([`Prefetch`]): chosen per layout by its size, as the flat
/// build chooses its non-temporal stores ([`Pace::for_layout`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pace {
    /// All of them by the middle of the row ([`Prefetch::new`]): for a layout that stays in
    /// the caches, whose lines come back soon, so the packing after the row step finds every
    /// one of them there.
    Early,
    /// Evenly over the row ([`Prefetch::even`]): for a layout past the caches, whose lines
    /// come from memory. Asked for in the first half of the row, twice as many misses are in
    /// flight at once, and the kernel waits on them: on a Zen 3 guest (AVX2, 2 MiB pages) a
    /// tiled build of 4,096^2 took 0.93x to 0.97x the time with the band rows and the rows
    /// that end a tile row paced evenly, one of 1,024^2 1.03x to 1.05x
    /// (`tools/examples/build_speed.py --servers`; docs/benchmarks.md, twenty-fifth session).
    Even,
}

impl Pace {
    /// [`Pace::Even`] for a layout of `bytes` past the caches ([`past_the_caches`]), else
    /// [`Pace::Early`].
    pub(crate) const fn for_layout(bytes: usize) -> Pace {
        if past_the_caches(bytes) {
            Pace::Even
        } else {
            Pace::Early
        }
    }
}

/// The prefetch schedule of the tiled row kernels ([`tiled512::kernel`], [`tiled256::kernel`], the
/// band rows' kernels): the 64-byte lines of each `ahead` slice (the words the row's fields go to,
/// or [`band_rows`]' next row's), spread over the first half of the row's blocks
/// ([`Prefetch::new`]), over all of them ([`Prefetch::even`]) or over all of them a lead ahead
/// ([`Prefetch::paced`]), asked for a group of blocks at a time.
struct Prefetch {
    ahead: Ahead,
    lines: [usize; 2],
    asked: [usize; 2],
    /// Lines due per block, `2 lines / blocks` in 16.16 fixed point (one division per row, not
    /// per group), or `lines / blocks` ([`Prefetch::even`], [`Prefetch::paced`]).
    rate: [usize; 2],
    /// Blocks ahead of the one asked for ([`Prefetch::paced`]; 0 for the others).
    lead: usize,
}

impl Prefetch {
    /// All the lines by the middle of the row: for kernels whose fields are packed after the
    /// row step (the packing then needs every line soon after it).
    fn new(ahead: Ahead, blocks: usize) -> Self {
        Self::with_rate(ahead, blocks, 17, 0)
    }

    /// [`Prefetch::new`] or [`Prefetch::even`], as `pace` says.
    fn at_pace(ahead: Ahead, blocks: usize, pace: Pace) -> Self {
        match pace {
            Pace::Early => Self::new(ahead, blocks),
            Pace::Even => Self::even(ahead, blocks),
        }
    }

    /// The lines at the row's pace, evenly from its first block to its last (those due by the
    /// end of each group of blocks asked for before the group): for the band rows' kernels
    /// when the layout is past the caches ([`Pace::Even`]).
    fn even(ahead: Ahead, blocks: usize) -> Self {
        Self::with_rate(ahead, blocks, 16, 0)
    }

    /// The lines at the row's pace, `lead` blocks ahead of the block asked for: for kernels
    /// that pack their fields as they go (`band512::row_packed`, `band512::end_row_packed`),
    /// which need a line only when they reach it. At 4,096^2 a tiled build took 0.91x to
    /// 0.93x the time with the rows that end a tile row paced 16 blocks ahead instead of all
    /// their lines by the middle of the row, and 0.97x to 0.99x more with the band rows paced
    /// too (in process on a Zen 4 guest, docs/benchmarks.md, twelfth session).
    fn paced(ahead: Ahead, blocks: usize, lead: usize) -> Self {
        Self::with_rate(ahead, blocks, 16, lead)
    }

    /// `2^shift lines / blocks` lines per block in 16.16 fixed point.
    fn with_rate(ahead: Ahead, blocks: usize, shift: u32, lead: usize) -> Self {
        let lines = ahead.map(|(_, len)| len.div_ceil(16));
        Prefetch {
            ahead,
            lines,
            asked: [0; 2],
            // A shift for a power of two (a row of 2^m texels): no division per row.
            rate: lines.map(|l| {
                let b = blocks.max(1);
                if b.is_power_of_two() {
                    ((l << shift) + b - 1) >> b.trailing_zeros()
                } else {
                    (l << shift).div_ceil(b)
                }
            }),
            lead,
        }
    }

    /// Runs `each` on blocks `0..blocks` in order, asking for the lines due by the end of each
    /// group of 16 blocks before it (the bookkeeping once per group: groups of 8 executed 4 %
    /// more instructions in a tiled build of 1,024^2, `tools/examples/build_insns.py`).
    #[inline(always)]
    fn for_blocks(&mut self, blocks: usize, mut each: impl FnMut(usize)) {
        let mut from = 0;
        while from < blocks {
            let end = (from + Self::GROUP).min(blocks);
            self.ask(end);
            for b in from..end {
                each(b);
            }
            from = end;
        }
    }

    /// Blocks per group (a multiple of 4, for [`Prefetch::for_quads`]).
    const GROUP: usize = 16;

    /// As [`Prefetch::for_blocks`], four blocks at a time: `step(b, true)` for blocks `b..b +
    /// 4` while a group has four left (every group but the row's last has 16), then `step(b,
    /// false)` for each block left (fewer than 4, at the row's end).
    #[inline(always)]
    fn for_quads(&mut self, blocks: usize, mut step: impl FnMut(usize, bool)) {
        let mut from = 0;
        while from < blocks {
            let end = (from + Self::GROUP).min(blocks);
            self.ask(end);
            let mut b = from;
            while b + 4 <= end {
                step(b, true);
                b += 4;
            }
            while b < end {
                step(b, false);
                b += 1;
            }
            from = end;
        }
    }

    /// Asks for the lines due by the end of the group ending at block `end`: with
    /// [`Prefetch::new`] all of them by the middle of the row (2 lines end / blocks, rounded
    /// up: the last lines are packed soon after the row step, so they need the lead; asking
    /// for all of them at once measured slower at 4096^2), with [`Prefetch::even`] those up to
    /// block `end` (lines end / blocks), with [`Prefetch::paced`] those up to block `end +
    /// lead` (lines (end + lead) / blocks). The lines of a slice (fewer than
    /// 2^28) times 2^17, and `rate (end + lead) <= 2^17 lines (1 + lead / blocks) + end +
    /// lead`: no overflow on x86-64.
    /// A stream whose lines are all asked for costs one comparison per group.
    #[inline(always)]
    fn ask(&mut self, end: usize) {
        self.ask_with(end, |p| hint(p.cast()));
    }

    /// [`Prefetch::ask`] with `each` called on each line's first word instead of asking for it
    /// (the tests record the schedule).
    #[inline(always)]
    fn ask_with(&mut self, end: usize, mut each: impl FnMut(*const u32)) {
        for r in 0..2 {
            let (asked, lines) = (self.asked[r], self.lines[r]);
            if asked >= lines {
                continue;
            }
            let due = ((self.rate[r] * (end + self.lead) + 0xffff) >> 16).min(lines);
            // Lines asked..due, four per turn (a loop of one took five instructions per line:
            // 2 % of a tiled build of 1,024^2), then the rest.
            let mut at = self.ahead[r].0.wrapping_add(16 * asked);
            let mut left = due.saturating_sub(asked);
            // The lines asked..due < lines of the slice `ahead[r]` (16 line < len), which may
            // lie past the words ([`band_rows`] asks for the next row's): hints.
            while left >= 4 {
                each(at);
                each(at.wrapping_add(16));
                each(at.wrapping_add(32));
                each(at.wrapping_add(48));
                at = at.wrapping_add(64);
                left -= 4;
            }
            while left > 0 {
                each(at);
                at = at.wrapping_add(16);
                left -= 1;
            }
            self.asked[r] = due.max(asked);
        }
    }
}

mod tiled512 {
    use super::*;

    /// The kernel of [`tiled_row`] over `blocks` blocks of 16 texels, tiles of `TILE` texels
    /// (2, 4, 8 or 16); returns the running sum after them.
    ///
    /// Stores: `acc` (and `lower`) whole; per block the `nb = 16 / TILE` boundaries by one
    /// store of exactly `nb` lanes (4 to 32 bytes); the `nl = 16 - nb` local sums by a
    /// 16-lane store whose last `nb` lanes the next block's store overwrites (`nl >= 8`, so it
    /// ends inside the `blocks nl` values written in all), a masked store for the last block.
    ///
    /// # Safety
    /// The CPU has AVX-512F and AVX-512 VNNI; `t` is valid for reads and `acc` (and, if
    /// `LOWER`, `lower`) for reads and writes of `16 blocks` values; `bnd` for writes of
    /// `16 blocks / TILE` and `local` of `16 blocks - 16 blocks / TILE` values; no two of them
    /// overlap; `TILE` is 2, 4, 8 or 16.
    #[target_feature(enable = "avx512f,avx512vnni")]
    pub(super) unsafe fn kernel<const LOWER: bool, const TILE: usize>(
        t: *const u8,
        lower: *mut u32,
        acc: *mut u32,
        bnd: *mut u32,
        local: *mut u32,
        blocks: usize,
        ahead: Ahead,
    ) -> u32 {
        // Prefetching, a group of blocks at a time (the bookkeeping once per group).
        let mut prefetch = Prefetch::new(ahead, blocks);
        let table = &TILE_TABLES[TILE.trailing_zeros() as usize - 1];
        let w = table.w.map(|g| {
            let [a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15] = g;
            _mm512_setr_epi32(
                a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15,
            )
        });
        // SAFETY: each table row is 16 i32: one 64-byte unaligned load.
        let (local_ix, bnd_ix) = unsafe {
            (
                _mm512_loadu_si512(table.local.as_ptr().cast()),
                _mm512_loadu_si512(table.bnd.as_ptr().cast()),
            )
        };
        let bmask = table.bmask;
        let nb = BLOCK / TILE;
        let nl = BLOCK - nb;
        let ml = ((1u32 << nl) - 1) as u16;
        let last = _mm512_set1_epi32(15);
        let zero = _mm512_setzero_si512();
        let mut carry = zero;
        prefetch.for_blocks(blocks, |b| {
            let i = BLOCK * b;
            // SAFETY: i + 16 <= 16 blocks: inside `t`, `acc` and `lower` (the caller's
            // contract). The boundary store writes nb lanes at bnd[b nb..], inside
            // bnd[..blocks nb]; the local store 16 lanes at local[b nl..] for b + 2 <= blocks
            // (b nl + 16 <= (blocks - 2) nl + 2 nl: inside local[..blocks nl]), nl lanes for the
            // last block.
            unsafe {
                let p = avx512vnni::dot16(t.add(i), &w);
                // The running sum before the block, kept in the boundary lanes only (zero
                // in the others): one addition gives every lane its r(x); the block's
                // total (lane 15, a boundary) joins it by a zero-masked permute.
                let mut v = _mm512_add_epi32(p, carry);
                carry = _mm512_add_epi32(carry, _mm512_maskz_permutexvar_epi32(bmask, last, p));
                if LOWER {
                    v = _mm512_add_epi32(v, _mm512_loadu_si512(lower.add(i).cast()));
                    _mm512_storeu_si512(lower.add(i).cast(), zero);
                }
                v = _mm512_add_epi32(v, _mm512_loadu_si512(acc.add(i).cast()));
                _mm512_storeu_si512(acc.add(i).cast(), v);
                let loc = _mm512_permutexvar_epi32(local_ix, v);
                let lo = local.add(b * nl);
                if b + 1 < blocks {
                    _mm512_storeu_si512(lo.cast(), loc);
                } else {
                    _mm512_mask_storeu_epi32(lo.cast(), ml, loc);
                }
                let bv = _mm512_permutexvar_epi32(bnd_ix, v);
                let bo = bnd.add(b * nb);
                match nb {
                    1 => bo.write_unaligned(_mm512_cvtsi512_si32(bv) as u32),
                    2 => _mm_storel_epi64(bo.cast(), _mm512_castsi512_si128(bv)),
                    4 => _mm_storeu_si128(bo.cast(), _mm512_castsi512_si128(bv)),
                    _ => _mm256_storeu_si256(bo.cast(), _mm512_castsi512_si256(bv)),
                }
            }
        });
        // Lane 15, a boundary, holds the running sum.
        _mm_extract_epi32::<3>(_mm512_extracti32x4_epi32::<3>(carry)) as u32
    }

    /// Under Miri, which emulates neither `vpermt2w`, `vpermw` nor `vpermb`: the 64 bytes
    /// [`kernel8_packed`] stores for a pair of blocks, computed field by field (the low `k`
    /// bits of the 28 local sums at bits `i k`), so that Miri checks the kernel's loads and
    /// stores; the vector computation itself is tested natively.
    #[cfg(miri)]
    #[target_feature(enable = "avx512f")]
    fn miri_pack(va: __m512i, vb: __m512i, k: u32) -> __m512i {
        let mut lanes = [0u32; 32];
        // SAFETY: 64-byte stores into 128 bytes of `lanes`.
        unsafe {
            _mm512_storeu_si512(lanes.as_mut_ptr().cast(), va);
            _mm512_storeu_si512(lanes.as_mut_ptr().add(16).cast(), vb);
        }
        let fields = PACK8_WORDS
            .iter()
            .take(PAIR)
            .map(|&ix| lanes[usize::from(ix) / 2]);
        super::miri_pack_bits(fields, k)
    }

    /// [`kernel`] for tiles of 8 with the local sums packed: per pair of blocks, the 28 local
    /// sums (lanes 0..7 and 8..15 of each block's 16 but the boundaries 7 and 15) gathered
    /// into 16-bit lanes by one `vpermt2w` (their low halves: `k <= 14` bits), masked to `k`
    /// bits (not with `EXACT`: the caller knows they are below `2^k`); `vpmaddwd` with weights
    /// `(1, 2^k)` joins each pair into a 2k-bit value per 32-bit
    /// lane; a shift and a bit select (`vpsrlq`, `vpternlogq`) join each pair of those into a
    /// 4k-bit value at the bottom of each 64-bit lane (`4k / 8 = k / 2` whole bytes, `k` even);
    /// `vpermb` moves the 7 lanes' bytes together, one masked byte store writes the `7 k / 2`
    /// bytes at `out + 7 k / 2 pair`. The bit stream is the layouts' (field `i` at bit `i k`,
    /// little-endian words: byte `j` holds bits `8 j..8 j + 8`). The boundaries of the pair go
    /// out by one `vpermt2d` and a 4-lane store. An odd last block goes as in [`kernel`] (its
    /// local sums into `local[14 (blocks - 1)..]`, then 14 values, a masked store).
    /// Returns the running sum after the blocks.
    ///
    /// # Safety
    /// As [`kernel`] with `TILE = 8`, and: the CPU has AVX-512BW and AVX-512 VBMI; `k` is 8,
    /// 10, 12 or 14; `out` is valid for writes of `7 k / 2 (blocks / 2)` bytes, not
    /// overlapping the others. `local[..28 (blocks / 2)]` is not written.
    #[allow(
        clippy::too_many_arguments,
        reason = "kernel's pointers plus the packing target"
    )]
    #[target_feature(enable = "avx512f,avx512vnni,avx512bw,avx512vbmi")]
    pub(super) unsafe fn kernel8_packed<const LOWER: bool, const EXACT: bool>(
        t: *const u8,
        lower: *mut u32,
        acc: *mut u32,
        bnd: *mut u32,
        local: *mut u32,
        blocks: usize,
        out: *mut u8,
        k: u32,
        ahead: Ahead,
    ) -> u32 {
        // Prefetching, a group of pairs at a time (the bookkeeping once per group).
        const GROUP: usize = 4;
        let mut prefetch = Prefetch::new(ahead, blocks);
        let table = &TILE_TABLES[2];
        let w = table.w.map(|g| {
            let [a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15] = g;
            _mm512_setr_epi32(
                a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15,
            )
        });
        let bmask = table.bmask;
        let last = _mm512_set1_epi32(15);
        let zero = _mm512_setzero_si512();
        // SAFETY: each table is 64 bytes: one unaligned load.
        let (widx, bidx) = unsafe {
            (
                _mm512_loadu_si512(PACK8_WORDS.as_ptr().cast()),
                _mm512_loadu_si512(PACK8_BYTES[(k as usize - 8) / 2].as_ptr().cast()),
            )
        };
        let bnd_ix = _mm512_setr_epi32(7, 15, 23, 31, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
        let fmask = _mm512_set1_epi16(((1u32 << k) - 1) as i16);
        let weights = _mm512_set1_epi32(((1u32 << k) << 16 | 1) as i32);
        let low2k = _mm512_set1_epi64(((1u64 << (2 * k)) - 1) as i64);
        let shift = _mm512_set1_epi64(i64::from(32 - 2 * k));
        #[cfg(miri)]
        let _ = (widx, bidx, fmask, weights, low2k, shift);
        let bytes = 7 * k as usize / 2;
        let store = (1u64 << bytes) - 1;
        let mut carry = zero;
        // Block b's 16 accumulators after the row (stored to `acc`, `lower` cleared).
        // SAFETY (of each call): b < blocks, so 16 b + 16 <= 16 blocks: inside `t`, `acc` and
        // `lower` (the caller's contract).
        let mut block = |b: usize| unsafe {
            let i = BLOCK * b;
            let tp = t.add(i);
            let g = |k: usize| _mm512_set1_epi32(tp.add(4 * k).cast::<i32>().read_unaligned());
            // Two chains of two dot products, added: half the latency of one chain of four
            // (measured 4 to 8 % faster than the one chain, one instruction more).
            let p = _mm512_add_epi32(
                _mm512_dpbusd_epi32(_mm512_dpbusd_epi32(zero, g(0), w[0]), g(1), w[1]),
                _mm512_dpbusd_epi32(_mm512_dpbusd_epi32(zero, g(2), w[2]), g(3), w[3]),
            );
            // The running sum before the block, kept in the boundary lanes only (zero in the
            // others): one addition gives every lane its r(x); the block's total (lane 15)
            // joins it by a zero-masked permute.
            let mut v = _mm512_add_epi32(p, carry);
            carry = _mm512_add_epi32(carry, _mm512_maskz_permutexvar_epi32(bmask, last, p));
            if LOWER {
                v = _mm512_add_epi32(v, _mm512_loadu_si512(lower.add(i).cast()));
                _mm512_storeu_si512(lower.add(i).cast(), zero);
            }
            v = _mm512_add_epi32(v, _mm512_loadu_si512(acc.add(i).cast()));
            _mm512_storeu_si512(acc.add(i).cast(), v);
            v
        };
        let pairs = blocks / 2;
        let mut from = 0;
        while from < pairs {
            let end = (from + GROUP).min(pairs);
            prefetch.ask(2 * end);
            for pr in from..end {
                let (va, vb) = (block(2 * pr), block(2 * pr + 1));
                // SAFETY: the boundaries go to bnd[4 pr..4 pr + 4], inside bnd[..2 blocks];
                // the packed bytes to out[bytes pr..bytes pr + 64] when that ends inside the
                // caller's `bytes pairs` (the excess is later pairs' bytes, rewritten by their
                // stores), else to out[bytes pr..bytes (pr + 1)] by a masked store.
                unsafe {
                    let bv = super::pack512::perm2(va, bnd_ix, vb);
                    _mm_storeu_si128(bnd.add(4 * pr).cast(), _mm512_castsi512_si128(bv));
                    #[cfg(not(miri))]
                    let o = {
                        let mut f = _mm512_permutex2var_epi16(va, widx, vb);
                        if !EXACT {
                            f = _mm512_and_si512(f, fmask);
                        }
                        let d = _mm512_madd_epi16(f, weights);
                        let q = _mm512_ternarylogic_epi64::<0xE4>(
                            d,
                            _mm512_srlv_epi64(d, shift),
                            low2k,
                        );
                        _mm512_permutexvar_epi8(bidx, q)
                    };
                    #[cfg(miri)]
                    let o = miri_pack(va, vb, k);
                    // All 64 bytes while they end inside the pairs' bytes: those past this
                    // pair's are the next pairs', which their stores overwrite (in order);
                    // then masked stores.
                    if bytes * pr + 64 <= bytes * pairs {
                        _mm512_storeu_si512(out.add(bytes * pr).cast(), o);
                    } else {
                        _mm512_mask_storeu_epi8(out.add(bytes * pr).cast(), store, o);
                    }
                }
            }
            from = end;
        }
        if blocks % 2 == 1 {
            let b = blocks - 1;
            let v = block(b);
            // SAFETY: 14 local sums at local[14 b..14 b + 14], inside local[..14 blocks]; two
            // boundaries at bnd[2 b..2 b + 2], inside bnd[..2 blocks].
            unsafe {
                let local_ix = _mm512_loadu_si512(table.local.as_ptr().cast());
                let bnd_ix = _mm512_loadu_si512(table.bnd.as_ptr().cast());
                _mm512_mask_storeu_epi32(
                    local.add(14 * b).cast(),
                    (1 << 14) - 1,
                    _mm512_permutexvar_epi32(local_ix, v),
                );
                _mm_storel_epi64(
                    bnd.add(2 * b).cast(),
                    _mm512_castsi512_si128(_mm512_permutexvar_epi32(bnd_ix, v)),
                );
            }
        }
        // Lane 15, a boundary, holds the running sum.
        _mm_extract_epi32::<3>(_mm512_extracti32x4_epi32::<3>(carry)) as u32
    }
}

/// Under Miri: `fields` (at most 28 of at most 14 bits' width `k`) packed field by field, the
/// low `k` bits of field `i` at bits `i k` of the 64 bytes returned (the rest zero): what the
/// packing kernels' byte permutes produce, for the permutes Miri does not emulate.
#[cfg(miri)]
#[target_feature(enable = "avx512f")]
fn miri_pack_bits(fields: impl Iterator<Item = u32>, k: u32) -> __m512i {
    let mut bytes = [0u8; 64];
    for (i, f) in fields.enumerate() {
        let v = f & ((1 << k) - 1);
        for bit in 0..k as usize {
            let at = i * k as usize + bit;
            bytes[at / 8] |= (((v >> bit) & 1) as u8) << (at % 8);
        }
    }
    // SAFETY: a 64-byte load of `bytes`.
    unsafe { _mm512_loadu_si512(bytes.as_ptr().cast()) }
}

/// [`tiled512::kernel8_packed`]'s `vpermt2w` indices: the 16-bit lanes (the low halves of the
/// 32-bit lanes `l` of the pair's first block, `16 + l` of its second) of the 28 local sums in
/// order (lanes `0..7` and `8..15` of each block, not the boundaries 7 and 15), then 4 unused.
static PACK8_WORDS: [u16; 32] = {
    let mut ix = [0u16; 32];
    let mut f = 0;
    while f < PAIR {
        let (block, within) = (f / 14, f % 14);
        let lane = if within < 7 { within } else { within + 1 };
        ix[f] = (32 * block + 2 * lane) as u16;
        f += 1;
    }
    ix
};

/// [`tiled512::kernel8_packed`]'s `vpermb` indices per width `k = 8, 10, 12, 14`: output byte
/// `j` is byte `j mod (k / 2)` of 64-bit lane `j / (k / 2)` (which holds 4 fields, `k / 2`
/// bytes); the bytes past the 7 lanes' are not stored.
static PACK8_BYTES: [[u8; 64]; 4] = {
    let mut out = [[0u8; 64]; 4];
    let mut w = 0;
    while w < 4 {
        let per = 4 + w;
        let mut j = 0;
        while j < 7 * per {
            out[w][j] = (8 * (j / per) + j % per) as u8;
            j += 1;
        }
        w += 1;
    }
    out
};

mod tiled256 {
    use super::*;

    /// [`tiled_row`]'s kernel for AVX2 and tiles of 8 texels, over `blocks` blocks of 16;
    /// returns the running sum after them. Per block: each tile's sums since its start by
    /// `avx2::chunk` (lanes 0..8 `lo`, 8..16 `hi`; dot products, no shuffle); the boundary lanes
    /// (7 of each)
    /// get the running sum, and `hi`'s also the first tile's total; the rows added and stored;
    /// the local sums stored as two 8-lane stores 7 apart (each one's lane 7, a boundary, is
    /// overwritten by the next store: through a copy for the last block's `hi`), the two
    /// boundaries extracted.
    ///
    /// # Safety
    /// The CPU has AVX2; the pointers as for `tiled512::kernel` with `TILE = 8`.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn kernel<const LOWER: bool>(
        t: *const u8,
        lower: *mut u32,
        acc: *mut u32,
        bnd: *mut u32,
        local: *mut u32,
        blocks: usize,
        ahead: Ahead,
    ) -> u32 {
        let mut prefetch = Prefetch::new(ahead, blocks);
        let seven = lane7();
        let zero = _mm256_setzero_si256();
        let w = avx2::Weights::new();
        let mut carry = zero;
        prefetch.for_blocks(blocks, |b| {
            let i = BLOCK * b;
            // SAFETY: i + 16 <= 16 blocks: inside `t`, `acc` and `lower` (the caller's
            // contract); the boundaries go to bnd[2 b], bnd[2 b + 1] < 2 blocks; the local
            // stores write local[14 b .. 14 b + 15] for b + 1 < blocks (inside
            // local[..14 blocks]), local[14 b .. 14 b + 14] for the last block.
            unsafe {
                let lo = avx2::chunk(t.add(i), w);
                let hi = avx2::chunk(t.add(i + 8), w);
                // The tiles' totals in every lane.
                let t0 = _mm256_permutevar8x32_epi32(lo, seven);
                let t1 = _mm256_permutevar8x32_epi32(hi, seven);
                let mut a = _mm256_blend_epi32(lo, _mm256_add_epi32(lo, carry), 0x80);
                let mut h =
                    _mm256_blend_epi32(hi, _mm256_add_epi32(hi, _mm256_add_epi32(carry, t0)), 0x80);
                carry = _mm256_add_epi32(carry, _mm256_add_epi32(t0, t1));
                if LOWER {
                    a = _mm256_add_epi32(a, _mm256_loadu_si256(lower.add(i).cast()));
                    h = _mm256_add_epi32(h, _mm256_loadu_si256(lower.add(i + 8).cast()));
                    _mm256_storeu_si256(lower.add(i).cast(), zero);
                    _mm256_storeu_si256(lower.add(i + 8).cast(), zero);
                }
                a = _mm256_add_epi32(a, _mm256_loadu_si256(acc.add(i).cast()));
                h = _mm256_add_epi32(h, _mm256_loadu_si256(acc.add(i + 8).cast()));
                _mm256_storeu_si256(acc.add(i).cast(), a);
                _mm256_storeu_si256(acc.add(i + 8).cast(), h);
                split(a, h, local, bnd, b, b + 1 == blocks);
            }
        });
        _mm256_cvtsi256_si32(carry) as u32
    }

    /// Block `b`'s new accumulator values (`a`: the first tile, `h`: the second) split into
    /// the streams: the local sums as two 8-lane stores 7 apart from `local + 14 b` (each
    /// one's lane 7, a boundary, is overwritten by the next store; the `last` block's `h`
    /// through a copy of its 7 local sums), the two boundaries (lanes 7) to `bnd + 2 b`.
    ///
    /// # Safety
    /// The CPU has AVX2; `local` valid for writes of `14 b + 15` words (`14 b + 14` if
    /// `last`), `bnd` of `2 b + 2`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn split(
        a: __m256i,
        h: __m256i,
        local: *mut u32,
        bnd: *mut u32,
        b: usize,
        last: bool,
    ) {
        // SAFETY: the caller's contract.
        unsafe {
            let lo_out = local.add(14 * b);
            _mm256_storeu_si256(lo_out.cast(), a);
            if !last {
                _mm256_storeu_si256(lo_out.add(7).cast(), h);
            } else {
                let mut rest = [0u32; 8];
                _mm256_storeu_si256(rest.as_mut_ptr().cast(), h);
                core::ptr::copy_nonoverlapping(rest.as_ptr(), lo_out.add(7), 7);
            }
            bnd.add(2 * b)
                .write_unaligned(_mm256_extract_epi32::<7>(a) as u32);
            bnd.add(2 * b + 1)
                .write_unaligned(_mm256_extract_epi32::<7>(h) as u32);
        }
    }
}

/// Whether the band rows ([`band_row`], [`band_flush`]) can take a tiled build's rows that end
/// no tile row, entries `E`, `C` channels (with texels of [`band_types`]): `u32` entries, one
/// channel; with AVX2, on an AVX-512 CPU too (there the rows that end a tile row take
/// [`band_end_row`], with AVX-512BW and DQ its packing step `band512::end_row_packed`, and only the
/// rows that end a level above the tiles the AVX-512 row kernel; the boundaries go to the
/// widest packer; on a Zen 4 guest the tiled build of 1,024^2 took 0.80x the time with the
/// band rows, 4,096^2 about the same:
/// docs/benchmarks.md, seventh session); tiles 8 texels wide (`tile_w`); a row of at least
/// one block of 16 texels; and the sum of a whole tile, `tile_w tile_h (2^texel_bits - 1)`, at
/// most `2^16 - 1`. The band rows keep the column
/// sums and their prefix inside a tile, up to the tile's total (lane 7 of each half, the
/// boundary's increment), as 16-bit values: a tile row's rows before its last are fewer than
/// `tile_h`, so every such value is at most that bound. The local sums' field width is not
/// enough: it bounds 7 columns, and a tile's total over 8 columns can pass `2^16` while the
/// local sums fit 16 bits (`u8` texels, tiles of 8 x 36: local sums up to `7 * 35 * 255 =
/// 62,475`, a tile row's total `8 * 35 * 255 = 71,400`).
pub(crate) fn band_applies<E: Entry, const C: usize>(
    width: usize,
    tile_w: u32,
    tile_h: u32,
    texel_bits: u32,
) -> bool {
    let texel_max = if texel_bits >= 64 {
        u64::MAX
    } else {
        (1u64 << texel_bits) - 1
    };
    E::BITS == 32
        && C == 1
        && matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni)
        && tile_w == 8
        && texel_max
            .checked_mul(u64::from(tile_w) * u64::from(tile_h))
            .is_some_and(|s| s <= u64::from(u16::MAX))
        && width >= BLOCK
}

/// The types [`band_row`] takes: `u8` texels, `u32` entries, one channel.
pub(crate) fn band_types<T: Texel, E: Entry, const C: usize>() -> bool {
    T::BITS == 8 && E::BITS == 32 && C == 1
}

/// Where the band form keeps its `n` column sums inside acc_0's storage of `n` words at `storage`:
/// the `u16` index of the first. At `n - d`, the `d` (0 to 15) that puts them on a 32-byte
/// boundary, when `n >= 128`; else at `n` (the upper half). The AVX2 kernels load and store them 32
/// bytes at a time, so aligned, none of those accesses splits a cache line (the AVX-512 ones, 64
/// bytes at a time, still split one where the start is 32 bytes past 64: on a Zen 5 guest, on 64
/// bytes or not made no difference to a tiled build of 1,024^2, docs/benchmarks.md,
/// twenty-seventh session; not measured on Zen 4). With them
/// at `n`, a tiled build of 1,024^2 took 0.302 to 0.305 ns per texel where they missed a 32-byte
/// boundary and 0.292 where they fell on one (medians, one process, the scratch moved to each
/// 8-byte offset of 64 bytes in turn); placed here, 0.260 to 0.262 at every offset (Zen 3, AVX2;
/// docs/benchmarks.md, twenty-third session). Room: they end at `u16` `2 n - d`, inside the
/// storage; [`band_rows`] keeps a row's `n - n / 8` local sums and one more below them, in `u16`
/// `0..n - n / 8 + 1`, which is at most `n - 15` from `n / 8 >= 16` on. A function of the address,
/// so every call on the same storage (a builder's scratch, borrowed for its life) finds them at the
/// same place; [`band_flush`] moves them back to `n` first.
pub(crate) fn column_sums_at(storage: *const u32, n: usize) -> usize {
    if n < 128 {
        return n;
    }
    // Bytes past the last 32-byte boundary at or below u16 n (an even count: the storage is
    // 4-byte aligned).
    let past = storage.addr().wrapping_add(2 * n) % 32;
    n - past / 2
}

/// The tiled builder's row step for a row that ends no tile row (`q = 0`), tiles of 8 texels, in
/// the band form: instead of the level-0 accumulator (per position its local sum or, at a tile
/// boundary, its total over the tile row's rows so far, 32 bits), the row `acc0` holds the *column
/// sums* of the tile row's rows so far, 16 bits each, from `u16` index [`column_sums_at`] of its
/// storage (at or just below its upper half, 32-byte aligned from `n = 128` on; the rest unused).
/// The accumulator is a function of them: the local sum at `x` is the prefix of the column sums
/// inside its tile, and a boundary the prefix of the tiles' totals. Per 16 columns
/// ([`band256::row`]): the row added to the column sums (one 16-bit add), their prefix inside each
/// tile (a multiply, two shuffles and two adds within each 128-bit half, which holds one tile:
/// `band256::prefix8`), the 14 local sums stored as 16-bit values, the two tiles' totals added into
/// the running boundary sum (four blocks' 8 boundaries by one vector prefix sum, [`band256::row`]).
/// Then the local sums packed as `pack`'s fields straight from 16 bits ([`pack256::even`], for `k`
/// = 8, 10, 12 and 14 from a byte-aligned `bit`: `kp` fields, a multiple of 16 on this path), the
/// rest widened into `local`.
///
/// With AVX-512BW, DQ and VBMI, fields below `2^k` (`exact`) and room for them, the pairs of
/// blocks go through `band512::row_packed` instead, which packs their local sums in the same pass
/// (`28 (n / 32)` fields, `7 k / 2` bytes per pair) and stores no 16-bit values;
/// `pack256::even` then packs whole steps of 16 of the tail's after them where the target's
/// words hold them (`kp = 28 (n / 32) + 16 steps`; the rest is the caller's). (A tiled build
/// of 4,096^2 took 1.04x and 1.10x the flat build's time with it, 1.34x and 1.46x with the
/// AVX2 step, in two processes on a Zen 4 guest: docs/benchmarks.md, eleventh session.)
///
/// The values are [`tiled_row`]'s with the level-0 accumulator the column sums' form and no
/// level below: `(kb, kl, kp)` as there. Column sums, local sums and the tiles' totals fit 16
/// bits by [`band_applies`]'s conditions (a tile's sum fits); the 16-bit additions wrap only
/// past them. `None` (nothing written) for other types, without AVX2, or short slices.
pub(crate) fn band_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    acc0: &mut [E],
    bnd: &mut [E],
    local: &mut [E],
    (ahead, pace): (Ahead, Pace),
    pack: Option<PackTo<'_>>,
) -> Option<(usize, usize, usize)> {
    if !band_types::<T, E, C>() || !matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni) {
        return None;
    }
    let t = cast::u8s(texels)?;
    let acc0 = as_u32_mut::<E, C>(acc0)?;
    let bnd = as_u32_mut::<E, C>(bnd)?;
    let local = as_u32_mut::<E, C>(local)?;
    let n = t.len();
    let (nb, nl, blocks) = (n / 8, n - n / 8, n / BLOCK);
    // The 16-bit local sums go to local's storage (2 per word): 14 blocks + 1 (the last
    // block's overhang) and the tail's, at most 2 nl.
    if acc0.len() != n
        || bnd.len() < nb
        || local.len() < nl
        || (blocks > 0 && 14 * blocks + 1 > 2 * nl)
    {
        return None;
    }
    let base = local.as_mut_ptr();
    let loc = base.cast::<u16>();
    let cs = acc0
        .as_mut_ptr()
        .cast::<u16>()
        .wrapping_add(column_sums_at(acc0.as_ptr(), n));
    let bp = bnd.as_mut_ptr();
    // The packing target, if the fields start on a byte and have a width the packers take:
    // its first byte and the bytes available from it. (Exact local sums, below 2^k, need no
    // mask: one instruction per 16 fields.)
    let target = pack.and_then(
        |PackTo {
             words,
             bit,
             k,
             exact,
         }| {
            (matches!(k, 8 | 10 | 12 | 14) && bit % 8 == 0 && bit < 32).then(|| {
                let skip = bit as usize / 8;
                let room = (4 * words.len()).saturating_sub(skip);
                (
                    words.as_mut_ptr().cast::<u8>().wrapping_add(skip),
                    room,
                    k,
                    exact,
                )
            })
        },
    );
    // With AVX-512BW and VBMI, exact fields and at least one pair of blocks (32 columns): the
    // pairs' local sums packed in the row step (`band512::row_packed`), 7 k / 2 bytes per pair,
    // the rest (fewer than 32 columns) by the tail below; else the AVX2 step, which stores them
    // as 16-bit values for `pack256::even` below.
    let pairs = n / (2 * BLOCK);
    let fused = target.filter(|&(_, room, k, exact)| {
        exact
            && pairs > 0
            && 7 * k as usize / 2 * pairs <= room
            && Kernel::best() == Kernel::Avx512Vnni
            && vbmi()
    });
    let (run, from, mut kb, mut kl, packed) = if let Some((out, _, k, _)) = fused {
        // SAFETY: AVX-512F, BW, DQ and VBMI are available (Kernel::best is AVX-512 VNNI, whose
        // detection includes AVX-512F, and `vbmi`); k is 8, 10, 12 or 14 and every local sum below
        // 2^k (`exact`: the width proof); the kernel reads t[..32 pairs] (<= n), reads and writes
        // the column sums cs[..32 pairs] (u16 c..c + 32 pairs <= 2 n of acc0's storage, c =
        // column_sums_at <= n), writes bnd[..4 pairs] (<= nb) and out[..7 k / 2 pairs] (inside the
        // target's words, checked above, not local's storage); distinct slices.
        let run = unsafe { band512::row_packed(t.as_ptr(), cs, bp, pairs, out, k, ahead) };
        (
            run,
            2 * BLOCK * pairs,
            4 * pairs,
            PAIR * pairs,
            PAIR * pairs,
        )
    } else {
        // SAFETY: AVX2 is available (Kernel::best is AVX2 or AVX-512 VNNI, whose detection
        // includes it); the kernel reads t[..16 blocks], reads and writes the column sums
        // cs[..16 blocks] (u16 c..c + 16 blocks <= 2 n of acc0's storage, c = column_sums_at
        // <= n), writes loc[..14 blocks + 1] (inside local's 2 nl u16, checked above) and
        // bnd[..2 blocks] (<= nb); distinct slices.
        let run = unsafe { band256::row(t.as_ptr(), cs, loc, bp, blocks, (ahead, pace)) };
        (run, BLOCK * blocks, 2 * blocks, 14 * blocks, 0)
    };
    // The tail, column by column (it starts on a tile boundary).
    let col = |i: usize| {
        // SAFETY: i < n: column sum c + i < 2 n u16 of acc0 (c = column_sums_at <= n).
        unsafe {
            let c = cs.add(i).read().wrapping_add(u16::from(t[i]));
            cs.add(i).write(c);
            u32::from(c)
        }
    };
    tile_walk(from, n, 8, run, col, |_, boundary, v| {
        // SAFETY: kb < nb; kl < nl <= 2 nl u16 of local's storage (one value per column).
        unsafe {
            if boundary {
                bp.add(kb).write(v);
                kb += 1;
            } else {
                loc.add(kl).write(v as u16);
                kl += 1;
            }
        }
    });
    // The whole steps of 16 local sums after those packed in the row step, packed from 16
    // bits (loc[packed..kl]), right after them in the target.
    let mut kp = packed;
    if let Some((out, room, k, exact)) = target {
        let steps = (kl - packed) / 16;
        let ku = k as usize;
        // The packed fields end on a byte: 7 k / 2 bytes per pair, k even.
        let at = packed * ku / 8;
        if steps > 0 && at + 2 * ku * steps <= room {
            let (f, out) = (loc.wrapping_add(packed).cast::<u8>(), out.wrapping_add(at));
            // SAFETY: AVX2 (above); loc[packed..packed + 16 steps] readable (<= kl, written
            // above); out[..2 k steps] inside the target's words (checked above), not local's
            // storage.
            unsafe { pack256::even_u16(k, exact, f, out, steps) };
            kp += 16 * steps;
        }
    }
    // The rest widened to 32 bits in place, last first: word j holds u16 2 j and 2 j + 1, at
    // least j, already read. 8 at a time from the end, then the first few.
    let mut j = kl;
    while j >= kp + 8 {
        j -= 8;
        // SAFETY: AVX2 (above); u16 j..j + 8 and words j..j + 8 inside local's storage (j + 8
        // <= kl <= nl); the load before the store, which reaches u16 2 j.. (at least j: this
        // step's, or read by the steps before).
        unsafe { band256::widen8(base.add(j), loc.add(j)) };
    }
    for j in (kp..j).rev() {
        // SAFETY: j < kl <= nl: u16 j and word j inside local's storage.
        unsafe { base.add(j).write(u32::from(loc.add(j).read())) };
    }
    Some((kb, kl, kp))
}

/// Whether [`band_rows`] takes rows of `n` texels with fields of `k` bits, `exact` or not, on
/// this CPU (asked before the rows are gathered: where it does not, the builder takes each
/// row on its own).
pub(crate) fn band_rows_apply<T: Texel, E: Entry, const C: usize>(
    n: usize,
    k: u32,
    exact: bool,
) -> bool {
    band_types::<T, E, C>()
        && exact
        && matches!(k, 8 | 10 | 12 | 14)
        && n > 0
        && n.is_multiple_of(32)
        && match Kernel::best() {
            Kernel::Avx512Vnni if vbmi() => true,
            // The AVX2 run: each row's local sums in whole steps of 16 (`7 n / 8`, a
            // multiple of 16).
            Kernel::Avx2 | Kernel::Avx512Vnni => n.is_multiple_of(128),
            Kernel::Sse2 => false,
        }
}

/// [`band_row`] for a run of consecutive band rows of one tile row (`rows`, each `n` texels), exact
/// fields of 8, 10, 12 or 14 bits from a byte-aligned `bit`, the checks and constants once for the
/// run: with AVX-512BW, DQ and VBMI, whole pairs of blocks (`n` a multiple of 32),
/// `band512::row_packed` on each row in turn; else with AVX2, `n` a multiple of 128, `band256::row`
/// and `pack256::even` on each row in turn (the row's 16-bit local sums in u16 `0..n - n / 8 + 1`
/// of `acc0`'s storage, below the column sums ([`column_sums_at`]), which the band form leaves
/// unused; whole steps of 16 of them). On AVX2 the run took a tiled build of 1,024^2 from 3.50 to
/// 2.86 instructions per texel (callgrind) and 0.85x to 0.94x the time in three runs (Zen 3;
/// 4,096^2: 0.96x to 0.99x; docs/benchmarks.md, twentieth session): the builder's per-row work, and
/// the boundaries packed in one call per run. Row `j`'s local sums are packed at `bit + j
/// stride_bits` of `out` (the rows of component `(0, 0)` follow each other: `stride_bits = 28 (n /
/// 32) k`), its `n / 8` boundaries stored at `bnd[j n / 8..]` (the caller packs them, one call for
/// the run). `ahead`: the words of the run's boundaries' rows, when the layout is large enough;
/// each row asks, at its pace, for the packed bytes [`BAND_WORDS_AHEAD`] bytes (at most a row) past
/// its own, and for the next row's share of `ahead` (the run's last row for those after the run,
/// which the next tile row's first band row writes: the rows of both components follow each other).
/// Returns whether it ran; `false` (nothing written) for other types, CPUs, widths or short slices:
/// the caller then takes the rows one by one.
pub(crate) fn band_rows<T: Texel, E: Entry, const C: usize>(
    rows: &[&[T]],
    acc0: &mut [E],
    bnd: &mut [E],
    (ahead, pace): (Option<(*const u32, usize)>, Pace),
    out: PackTo<'_>,
) -> bool {
    let n = acc0.len();
    let r = rows.len();
    let PackTo {
        words,
        bit,
        k,
        exact,
    } = out;
    if !band_rows_apply::<T, E, C>(n, k, exact) || bit % 8 != 0 || bit >= 32 {
        return false;
    }
    let (pairs, nb) = (n / 32, n / 8);
    let stride = 7 * k as usize / 2 * pairs;
    let skip = bit as usize / 8;
    let (Some(acc0), Some(bnd)) = (as_u32_mut::<E, C>(acc0), as_u32_mut::<E, C>(bnd)) else {
        return false;
    };
    let fits = r
        .checked_mul(stride)
        .and_then(|b| b.checked_add(skip))
        .is_some_and(|b| b <= 4 * words.len());
    if r.checked_mul(nb).is_none_or(|b| b > bnd.len()) || !fits {
        return false;
    }
    if rows
        .iter()
        .any(|row| cast::u8s(row).is_none_or(|b| b.len() != n))
    {
        return false;
    }
    let loc = acc0.as_mut_ptr().cast::<u16>();
    let cs = loc.wrapping_add(column_sums_at(acc0.as_ptr(), n));
    let out = words.as_mut_ptr().cast::<u8>().wrapping_add(skip);
    // Each row's share of the boundaries' words (a hint: never read).
    let share = ahead.map(|(p, len)| (p, len / r.max(1)));
    // The AVX-512 VBMI kernel packs in its pass; else each row is the AVX2 step, which
    // stores its local sums as 16-bit values in u16 0..n - n / 8 + 1 of acc0's storage
    // (below the column sums at column_sums_at, unused in the band form), then
    // `pack256::even` from there.
    let packs = Kernel::best() == Kernel::Avx512Vnni && vbmi();
    let (blocks, steps) = (n / BLOCK, (n - nb) / 16);
    for (j, row) in rows.iter().enumerate() {
        let Some(t) = cast::u8s(row) else {
            return false;
        };
        let to = out.wrapping_add(j * stride);
        // The lines [`BAND_WORDS_AHEAD`] bytes (at most a row) past the row's own, and the
        // next row's share of the boundaries' (hints: past the words after the layout's last
        // rows, which `Prefetch` never dereferences).
        let lines: Ahead = match share {
            Some((p, len)) => [
                (
                    to.wrapping_add(stride.min(BAND_WORDS_AHEAD))
                        .cast::<u32>()
                        .cast_const(),
                    stride / 4,
                ),
                (p.wrapping_add((j + 1) * len), len),
            ],
            None => [(core::ptr::null(), 0); 2],
        };
        let bj = bnd.as_mut_ptr().wrapping_add(j * nb);
        if packs {
            // SAFETY: AVX-512F, BW, DQ and VBMI are available (Kernel::best is AVX-512 VNNI, whose
            // detection includes AVX-512F, and `vbmi`); k is 8, 10, 12 or 14 and every local sum
            // below 2^k (`exact`: the width proof); the kernel reads t[..32 pairs] (= n, checked
            // above), reads and writes the column sums cs[..32 pairs] (u16 c..c + n <= 2 n of
            // acc0's n words, c = column_sums_at <= n), writes bj[..4 pairs] = bnd[j nb..(j + 1)
            // nb] (4 pairs = nb, r nb <= bnd.len()) and to[..stride] = out[j stride..(j + 1)
            // stride] (7 k / 2 pairs = stride, inside the words from byte skip: skip + r stride <=
            // 4 words.len()); distinct slices.
            unsafe { band512::row_packed(t.as_ptr(), cs, bj, pairs, to, k, lines) };
            continue;
        }
        // SAFETY: AVX2 is available (`band_rows_apply`: Kernel::best is AVX2 or AVX-512 VNNI,
        // whose detection includes it); n is a multiple of 128 (`band_rows_apply`): the row
        // is whole blocks (16 blocks = n), its 14 blocks = 7 n / 8 local sums are whole steps
        // (16 steps = 7 n / 8), and 2 k steps = 7 k n / 64 = stride bytes; band256::row reads
        // t[..n], reads and writes the column sums cs[..n] (u16 c..c + n <= 2 n of acc0's n
        // words, c = column_sums_at <= n), writes loc[..7 n / 8 + 1] (u16 0..n - n / 8 + 1 <=
        // n - 15 <= c, below the column sums: n >= 128, column_sums_at's room) and bj[..2
        // blocks] (= nb, as above); `even` reads loc[..16 steps], written just before, every
        // value below 2^k (`exact`: the width proof), and writes to[..2 k steps] (= stride, as
        // above); distinct slices.
        unsafe {
            band256::row(t.as_ptr(), cs, loc, bj, blocks, (lines, pace));
            pack256::even_u16(k, true, loc.cast::<u8>().cast_const(), to, steps);
        }
    }
    #[cfg(test)]
    RUN_ROWS.with(|c| c.set(c.get() + r));
    true
}

/// The rows of components `(0, 1)` and `(1, 1)` that [`band_end_row`] may pack into as it
/// computes them: each from its first word (the row starts on a word), the low `k` bits of
/// each value in the layouts' order (field `i` at bit `i k`).
pub(crate) struct EndPackTo<'w> {
    /// Component `(0, 1)`'s row (the local sums) and its field width.
    pub(crate) local: (&'w mut [u32], u32),
    /// Component `(1, 1)`'s row (the boundaries) and its field width.
    pub(crate) bnd: (&'w mut [u32], u32),
}

/// The tiled builder's row step for a row that ends a tile row (`q = 1`, the level above the
/// local one) while the level-0 accumulator `acc0` is in [`band_row`]'s form (column sums):
/// the row added to the column sums; their form (the level-0 accumulator they stand for:
/// local sums inside each tile, at a boundary the prefix of the tiles' totals) added into
/// the level above, `acc` (`n` positions, wrapping, as [`tiled_row`] adds the level below);
/// the column sums cleared, which is acc_0 = 0 in the band form, so the next tile row goes
/// on in it; `acc`'s new values split into `bnd` and `local` as [`tiled_row`] does. One pass
/// ([`band256::end_row`]) instead of [`band_flush`] (which writes acc_0's 32-bit form) and
/// the 32-bit row kernel with a level below (which reads it back, adds it and clears it).
/// The column sums with this row are a whole tile's at most: they fit 16 bits by
/// [`band_applies`].
///
/// With `pack`, on a CPU with AVX-512BW and DQ (detected with VBMI: [`vbmi`]; the kernel itself
/// needs BW and DQ only) and field widths of [`MIN_PACK_BITS`] to 32, the row's whole chunks of
/// [`band512::CHUNK`] columns whose fields both of `pack`'s rows hold take
/// [`band512::end_row_packed`], which packs their local sums and boundaries into those rows
/// as it computes them (written to neither `local` nor `bnd`); the rest as above.
/// Returns `(kb, kl, pl, pb)`: the boundaries and local sums of the row (`n / 8`, `n - n /
/// 8`), and how many of each were packed (from the first: those before them in `local` and
/// `bnd` are not written). `None` (nothing written) for other types, without AVX2, or short
/// slices (`acc0` must be exactly `n`).
pub(crate) fn band_end_row<T: Texel, E: Entry, const C: usize>(
    texels: &[T],
    acc0: &mut [E],
    acc: &mut [E],
    bnd: &mut [E],
    local: &mut [E],
    (ahead, pace): (Ahead, Pace),
    pack: Option<EndPackTo<'_>>,
) -> Option<(usize, usize, usize, usize)> {
    if !band_types::<T, E, C>() || !matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni) {
        return None;
    }
    let t = cast::u8s(texels)?;
    let acc0 = as_u32_mut::<E, C>(acc0)?;
    let acc = as_u32_mut::<E, C>(acc)?;
    let bnd = as_u32_mut::<E, C>(bnd)?;
    let local = as_u32_mut::<E, C>(local)?;
    let n = t.len();
    let (nb, nl, blocks) = (n / 8, n - n / 8, n / BLOCK);
    if acc0.len() != n || acc.len() < n || bnd.len() < nb || local.len() < nl {
        return None;
    }
    let cs = acc0
        .as_mut_ptr()
        .cast::<u16>()
        .wrapping_add(column_sums_at(acc0.as_ptr(), n));
    let (ap, bp, lp) = (acc.as_mut_ptr(), bnd.as_mut_ptr(), local.as_mut_ptr());
    // The chunks packed in the pass: as many whole ones as the row and both rows of words
    // hold.
    let widths = MIN_PACK_BITS..=32;
    let fused = match pack {
        Some(EndPackTo {
            local: (wl, kl),
            bnd: (wb, kb),
        }) if Kernel::best() == Kernel::Avx512Vnni
            && vbmi()
            && widths.contains(&kl)
            && widths.contains(&kb) =>
        {
            let (kl_, kb_) = (kl as usize, kb as usize);
            let chunks = (n / band512::CHUNK)
                .min(wl.len() / (7 * kl_))
                .min(wb.len() / kb_);
            (chunks > 0).then_some((chunks, (wl, kl), (wb, kb)))
        }
        _ => None,
    };
    let (done, run, ahead) = match fused {
        Some((chunks, (wl, kl), (wb, kb))) => {
            // SAFETY: AVX-512F, VL, BW and DQ are available (the AVX-512 kernel's detection
            // includes F and VL, `vbmi` BW and DQ); the kernel reads t[..256 chunks] (<= n), reads
            // and writes the column sums cs[..256 chunks] (u16 c..c + 256 chunks <= 2 n of acc0's
            // storage, c = column_sums_at <= n) and acc[..256 chunks] (<= n), writes wl[..7 kl
            // chunks] and wb[..kb chunks], inside them (the chunks' bound above); both widths in
            // 11..=32 (above); distinct slices.
            let run = unsafe {
                band512::end_row_packed(
                    t.as_ptr(),
                    cs,
                    ap,
                    chunks,
                    (wl.as_mut_ptr(), kl),
                    (wb.as_mut_ptr(), kb),
                    ahead,
                )
            };
            #[cfg(test)]
            END_CHUNKS.with(|c| c.set(c.get() + chunks));
            // The row's lines were all asked for by the chunks (paced a chunk ahead over the
            // chunks' blocks: all of them by the start of the last chunk).
            (band512::CHUNK * chunks, run, [(core::ptr::null(), 0); 2])
        }
        None => (0, 0, ahead),
    };
    let first = done / BLOCK;
    // SAFETY: AVX2 is available (as in band_row); the kernel reads t[16 first..16 blocks], reads
    // and writes the column sums cs[16 first..16 blocks] (u16 c..c + 16 blocks <= 2 n of acc0's
    // storage, c = column_sums_at <= n) and acc[16 first..16 blocks] (<= n), writes local[14
    // first..14 blocks] (<= nl) and bnd[2 first..2 blocks] (<= nb), checked above; distinct slices.
    let run = unsafe {
        band256::end_row(
            t.as_ptr().add(BLOCK * first),
            cs.add(BLOCK * first),
            ap.add(BLOCK * first),
            (bp.add(2 * first), lp.add(14 * first)),
            blocks - first,
            (ahead, pace),
            run,
        )
    };
    // The tail, column by column (it starts on a tile boundary).
    let (mut kb, mut kl) = (2 * blocks, 14 * blocks);
    let col = |i: usize| {
        // SAFETY: i < n: column sum c + i < 2 n u16 of acc0 (c = column_sums_at <= n).
        unsafe {
            let c = u32::from(cs.add(i).read()) + u32::from(t[i]);
            cs.add(i).write(0);
            c
        }
    };
    tile_walk(BLOCK * blocks, n, 8, run, col, |i, boundary, f| {
        // SAFETY: i < n: acc[i]; kb < nb, kl < nl.
        unsafe {
            let v = ap.add(i).read().wrapping_add(f);
            ap.add(i).write(v);
            if boundary {
                bp.add(kb).write(v);
                kb += 1;
            } else {
                lp.add(kl).write(v);
                kl += 1;
            }
        }
    });
    Some((kb, kl, done - done / 8, done / 8))
}

/// Turns [`band_row`]'s column sums in `acc0` (`n` positions) back into the level-0 accumulator
/// (the local sums and boundaries of the column sums, `u32`), in place, before a row that ends a
/// tile row (which adds it into the level above and clears it) or a row that leaves the band form.
/// First the column sums move from [`column_sums_at`] up to the upper half (`u16` `n..2 n`; a rare
/// step, one copy). Then forward: word `i` holds `u16` `2 i` and `2 i + 1`, that is column sums `2
/// i - n` and `2 i + 1 - n`, at most `i`: read already (a block of 16 reads its 16 before it
/// writes). With AVX2 per 16 columns ([`band256::flush`]), the rest column by column. `false`
/// (nothing done) for entries other than `u32` with one channel.
pub(crate) fn band_flush<E: Entry, const C: usize>(acc0: &mut [E]) -> bool {
    let Some(a) = as_u32_mut::<E, C>(acc0) else {
        return false;
    };
    let n = a.len();
    let base = a.as_mut_ptr();
    let cs = base.cast::<u16>().wrapping_add(n);
    let at = column_sums_at(base, n);
    if at != n {
        // SAFETY: u16 at..at + n and n..2 n are inside the storage's 2 n u16 (at <= n); an
        // overlapping copy (memmove), u16 to u16.
        unsafe { core::ptr::copy(base.cast::<u16>().add(at), cs, n) };
    }
    let blocks = if matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni) {
        n / BLOCK
    } else {
        0
    };
    // SAFETY: AVX2 is available when blocks > 0 (as in band_row); the kernel reads column
    // sums cs[..16 blocks] (u16 n..n + 16 blocks <= 2 n) and writes base[..16 blocks] (<= n),
    // each block's reads before its writes, which reach only column sums read already.
    let run = if blocks > 0 {
        unsafe { band256::flush(base, cs, blocks) }
    } else {
        0
    };
    // SAFETY (both closures): i < n: u16 n + i < 2 n and word i inside the storage; the word
    // written holds column sums at most i, read already (`col(i)` runs before `out(i)`).
    let col = |i: usize| unsafe { u32::from(cs.add(i).read()) };
    tile_walk(BLOCK * blocks, n, 8, run, col, |i, _, v| unsafe {
        base.add(i).write(v)
    });
    true
}

mod band256 {
    use super::*;

    /// `vpshufb` controls (per 128-bit half, -128 writes a zero) of [`prefix8`]'s two
    /// broadcasts: lane 1 into lanes 2 and 3 and lane 5 into 6 and 7; lane 3 into lanes 4..8.
    static PREFIX_SHUFFLES: [[i8; 32]; 2] = {
        let mut ix = [[-128i8; 32]; 2];
        let mut b = 0;
        while b < 32 {
            let lane = (b % 16) / 2;
            let byte = (b % 2) as i8;
            if lane % 4 >= 2 {
                ix[0][b] = 2 * (lane as i8 / 4 * 4 + 1) + byte;
            }
            if lane >= 4 {
                ix[1][b] = 2 * 3 + byte;
            }
            b += 1;
        }
        ix
    };

    /// The constants of [`prefix8`]: the multiplier `1 + 2^16` in every 32-bit lane and the
    /// two shuffles' controls ([`PREFIX_SHUFFLES`]), made once per kernel call.
    #[derive(Clone, Copy)]
    struct Prefix {
        pair: __m256i,
        lanes1: __m256i,
        lane3: __m256i,
    }

    impl Prefix {
        /// The constants. The multiplier passes through `black_box`: as a known constant
        /// LLVM turns the multiply back into a shift and an add, one instruction more.
        #[inline]
        #[target_feature(enable = "avx2")]
        fn new() -> Self {
            let [a, b] = &PREFIX_SHUFFLES;
            // SAFETY: each control is 32 bytes: one unaligned load.
            unsafe {
                Prefix {
                    pair: core::hint::black_box(_mm256_set1_epi32(0x0001_0001)),
                    lanes1: _mm256_loadu_si256(a.as_ptr().cast()),
                    lane3: _mm256_loadu_si256(b.as_ptr().cast()),
                }
            }
        }
    }

    /// The prefix sums of each 128-bit half's eight 16-bit lanes (one tile of 8 columns),
    /// wrapping: each 32-bit lane's two by a multiply (`vpmulld` by `1 + 2^16`: the low 32 bits
    /// of `(x_0 + 2^16 x_1)(1 + 2^16)` are `x_0 + 2^16 (x_0 + x_1)`), then the pairs' sums
    /// carried on by two shuffles and adds (lane 1 into 2 and 3, 5 into 6 and 7; then lane 3
    /// into 4..8). Five instructions where three byte shifts and three adds were six. (Intel's
    /// `vpmulld` is two uops; measured on Zen 3 only.) `consts`: the multiplier and both
    /// controls, made once per kernel call ([`Prefix::new`]).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn prefix8(c: __m256i, consts: &Prefix) -> __m256i {
        let p = _mm256_mullo_epi32(c, consts.pair);
        let p = _mm256_add_epi16(p, _mm256_shuffle_epi8(p, consts.lanes1));
        _mm256_add_epi16(p, _mm256_shuffle_epi8(p, consts.lane3))
    }

    /// [`band_row`]'s kernel over `blocks` blocks of 16 columns; returns the running boundary
    /// sum after them. Per block ([`column_step`]): 16 texels widened (`vpmovzxbw`) and added
    /// to the column sums `cs`, stored back; their prefix within each tile; the two tiles'
    /// local sums stored as 16-bit values, 7 apart (the second store overwrites the first's
    /// lane 7, the tile's total; its own lane 7 is the next block's first, or one past the
    /// last block's). The boundaries, four blocks (8 tiles) at a time: the 8 tiles' totals
    /// (lanes 7 and 15 of each block) gathered by three unpacks and an interleave of the
    /// halves, widened to 32 bits, their prefix sum plus the running sum stored as 8
    /// boundaries at once, the running sum the last of them (about 4 instructions per block
    /// instead of 7 for two extracts, three additions and two stores: 5 % of a tiled build of
    /// 1,024^2). The blocks after the last four (at the row's end): each tile's total
    /// extracted and added to the running sum, each sum after a tile stored. The lines of
    /// `ahead` asked for at `pace` ([`Prefetch::at_pace`]).
    ///
    /// # Safety
    /// The CPU has AVX2; `t` valid for reads of `16 blocks` bytes, `cs` for reads and writes
    /// of `16 blocks` `u16`, `loc` for writes of `14 blocks + 1` `u16`, `bnd` for writes of `2
    /// blocks` `u32`; not overlapping.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn row(
        t: *const u8,
        cs: *mut u16,
        loc: *mut u16,
        bnd: *mut u32,
        blocks: usize,
        (ahead, pace): (Ahead, Pace),
    ) -> u32 {
        let mut prefetch = Prefetch::at_pace(ahead, blocks, pace);
        let seven = lane7();
        let prefix = Prefix::new();
        // The running sum in every lane.
        let mut run = _mm256_setzero_si256();
        prefetch.for_quads(blocks, |b, quad| {
            // SAFETY (both arms): blocks b..b + 4 (quad) or b < blocks: inside the caller's
            // slices for column_step; the boundaries bnd[2 b..2 b + 8] (quad: b + 4 <=
            // blocks) or bnd[2 b], bnd[2 b + 1], < 2 blocks (the caller's contract).
            unsafe {
                if quad {
                    let p0 = column_step(t, cs, loc, b, &prefix);
                    let p1 = column_step(t, cs, loc, b + 1, &prefix);
                    let p2 = column_step(t, cs, loc, b + 2, &prefix);
                    let p3 = column_step(t, cs, loc, b + 3, &prefix);
                    // u16 lanes 4..8 of each half of v: lane 7 of p0, p1, p2, p3 (low half:
                    // the blocks' first tiles' totals; high half: lane 15, the second tiles').
                    let v = _mm256_unpackhi_epi32(
                        _mm256_unpackhi_epi16(p0, p1),
                        _mm256_unpackhi_epi16(p2, p3),
                    );
                    // The 8 tiles in order: p0's two, p1's two, ...
                    let tiles = _mm_unpackhi_epi16(
                        _mm256_castsi256_si128(v),
                        _mm256_extracti128_si256::<1>(v),
                    );
                    let w = _mm256_cvtepu16_epi32(tiles);
                    // Inclusive prefix: within each half, then the low half's total into the
                    // high half, then the running sum.
                    let w = _mm256_add_epi32(w, _mm256_slli_si256::<4>(w));
                    let w = _mm256_add_epi32(w, _mm256_slli_si256::<8>(w));
                    let low_total =
                        _mm256_shuffle_epi32::<0xff>(_mm256_permute2x128_si256::<0x08>(w, w));
                    let w = _mm256_add_epi32(_mm256_add_epi32(w, low_total), run);
                    _mm256_storeu_si256(bnd.add(2 * b).cast(), w);
                    run = _mm256_permutevar8x32_epi32(w, seven);
                } else {
                    let p = column_step(t, cs, loc, b, &prefix);
                    let r = _mm256_cvtsi256_si32(run) as u32;
                    let ta = _mm256_extract_epi16::<7>(p) as u32;
                    let tb = _mm256_extract_epi16::<15>(p) as u32;
                    let first = r.wrapping_add(ta);
                    let last = first.wrapping_add(tb);
                    bnd.add(2 * b).write_unaligned(first);
                    bnd.add(2 * b + 1).write_unaligned(last);
                    run = _mm256_set1_epi32(last as i32);
                }
            }
        });
        _mm256_cvtsi256_si32(run) as u32
    }

    /// Block `b` of [`row`]: texels `16 b..16 b + 16` widened and added to the column sums,
    /// stored back; their prefix within each tile, returned; the two tiles' local sums stored
    /// as 16-bit values at `loc + 14 b` and `loc + 14 b + 7` (lanes 0..8 of each half; the
    /// second store overwrites the first's lane 7).
    ///
    /// # Safety
    /// The CPU has AVX2; `t` valid for reads of `16 b + 16` bytes, `cs` for reads and writes
    /// of `16 b + 16` `u16`, `loc` for writes of `14 b + 15` `u16`.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn column_step(
        t: *const u8,
        cs: *mut u16,
        loc: *mut u16,
        b: usize,
        prefix: &Prefix,
    ) -> __m256i {
        let i = BLOCK * b;
        // SAFETY: the caller's contract; unaligned loads and stores.
        unsafe {
            let x = _mm256_cvtepu8_epi16(_mm_loadu_si128(t.add(i).cast()));
            let c = _mm256_add_epi16(x, _mm256_loadu_si256(cs.add(i).cast()));
            _mm256_storeu_si256(cs.add(i).cast(), c);
            let p = prefix8(c, prefix);
            _mm_storeu_si128(loc.add(14 * b).cast(), _mm256_castsi256_si128(p));
            _mm_storeu_si128(loc.add(14 * b + 7).cast(), _mm256_extracti128_si256::<1>(p));
            p
        }
    }

    /// Eight `u16` at `from` widened to `u32` at `to` (one load, then one store).
    ///
    /// # Safety
    /// The CPU has AVX2; `from` valid for reads of 16 bytes, `to` for writes of 32.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn widen8(to: *mut u32, from: *const u16) {
        // SAFETY: the caller's contract; unaligned.
        unsafe {
            let v = _mm256_cvtepu16_epi32(_mm_loadu_si128(from.cast()));
            _mm256_storeu_si256(to.cast(), v);
        }
    }

    /// [`band_flush`]'s kernel over `blocks` blocks of 16 columns; returns the running
    /// boundary sum after them. Per block: the column sums' prefix within each tile, widened
    /// to 32 bits, the boundary lanes (7 of each half) given the running sum (and the second
    /// the first tile's total) as in [`tiled256::kernel`], stored over the block's words.
    ///
    /// # Safety
    /// The CPU has AVX2; `cs` valid for reads of `16 blocks` `u16`, `out` for writes of `16
    /// blocks` words; block `b`'s words (bytes `64 b..64 b + 64` from `out`) overlap no column
    /// sum of a later block.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn flush(out: *mut u32, cs: *const u16, blocks: usize) -> u32 {
        let seven = lane7();
        let prefix = Prefix::new();
        let mut carry = _mm256_setzero_si256();
        for b in 0..blocks {
            let i = BLOCK * b;
            // SAFETY: i + 16 <= 16 blocks: inside both (the caller's contract); the load
            // before the stores.
            unsafe {
                let (a, h) = form(
                    _mm256_loadu_si256(cs.add(i).cast()),
                    seven,
                    &prefix,
                    &mut carry,
                );
                _mm256_storeu_si256(out.add(i).cast(), a);
                _mm256_storeu_si256(out.add(i + 8).cast(), h);
            }
        }
        _mm256_cvtsi256_si32(carry) as u32
    }

    /// The level-0 accumulator's form of 16 column sums `c` (two tiles, one per 128-bit half):
    /// their prefix inside each tile, widened to 32 bits (`a`: the first tile, `h`: the
    /// second); the boundary lanes (7 of each) given the running sum `carry` (and `h`'s the
    /// first tile's total too), which then grows by both tiles' totals (`vpermd` broadcasts of
    /// lane 7), as in [`tiled256::kernel`].
    #[inline]
    #[target_feature(enable = "avx2")]
    fn form(
        c: __m256i,
        seven: __m256i,
        prefix: &Prefix,
        carry: &mut __m256i,
    ) -> (__m256i, __m256i) {
        let p = prefix8(c, prefix);
        let lo = _mm256_cvtepu16_epi32(_mm256_castsi256_si128(p));
        let hi = _mm256_cvtepu16_epi32(_mm256_extracti128_si256::<1>(p));
        let t0 = _mm256_permutevar8x32_epi32(lo, seven);
        let t1 = _mm256_permutevar8x32_epi32(hi, seven);
        let a = _mm256_blend_epi32::<0x80>(lo, _mm256_add_epi32(lo, *carry));
        let h = _mm256_blend_epi32::<0x80>(hi, _mm256_add_epi32(hi, _mm256_add_epi32(*carry, t0)));
        *carry = _mm256_add_epi32(*carry, _mm256_add_epi32(t0, t1));
        (a, h)
    }

    /// [`band_end_row`]'s kernel over `blocks` blocks of 16 columns from the running boundary
    /// sum `run` (that of the columns before them); returns it after them. Per block: 16
    /// texels widened and added to the column sums, which are cleared (one 32-byte store of
    /// zeros); the sums' [`form`] added to `acc` and stored; the new values split into the
    /// streams ([`tiled256::split`]). The lines of `ahead` asked for at `pace`
    /// ([`Prefetch::at_pace`]).
    ///
    /// # Safety
    /// The CPU has AVX2; `t` valid for reads of `16 blocks` bytes, `cs` for reads and writes
    /// of `16 blocks` `u16`, `acc` for reads and writes of `16 blocks` words, `local` for
    /// writes of `14 blocks` words, `bnd` of `2 blocks`; not overlapping.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn end_row(
        t: *const u8,
        cs: *mut u16,
        acc: *mut u32,
        (bnd, local): (*mut u32, *mut u32),
        blocks: usize,
        (ahead, pace): (Ahead, Pace),
        run: u32,
    ) -> u32 {
        let mut prefetch = Prefetch::at_pace(ahead, blocks, pace);
        let seven = lane7();
        let prefix = Prefix::new();
        let zero = _mm256_setzero_si256();
        let mut carry = _mm256_set1_epi32(run as i32);
        prefetch.for_blocks(blocks, |b| {
            let i = BLOCK * b;
            // SAFETY: i + 16 <= 16 blocks: inside `t`, `cs` and `acc`; `split` writes
            // local[..14 b + 15] (14 b + 14 for the last block) <= 14 blocks and bnd[..2 b +
            // 2] <= 2 blocks (the caller's contract).
            unsafe {
                let x = _mm256_cvtepu8_epi16(_mm_loadu_si128(t.add(i).cast()));
                let c = _mm256_add_epi16(x, _mm256_loadu_si256(cs.add(i).cast()));
                _mm256_storeu_si256(cs.add(i).cast(), zero);
                let (a, h) = form(c, seven, &prefix, &mut carry);
                let a = _mm256_add_epi32(a, _mm256_loadu_si256(acc.add(i).cast()));
                let h = _mm256_add_epi32(h, _mm256_loadu_si256(acc.add(i + 8).cast()));
                _mm256_storeu_si256(acc.add(i).cast(), a);
                _mm256_storeu_si256(acc.add(i + 8).cast(), h);
                tiled256::split(a, h, local, bnd, b, b + 1 == blocks);
            }
        });
        _mm256_cvtsi256_si32(carry) as u32
    }
}

/// [`band_row`]'s kernel on CPUs with AVX-512BW, DQ and VBMI when the local sums are packed as
/// they are computed (see [`band512::row_packed`]); [`band_end_row`]'s with BW and DQ.
mod band512 {
    use super::*;

    /// `vpermw` indices: the 28 local sums of a pair of blocks (lanes 0..7 of each tile's 8,
    /// not its boundary lane 7) in order, then 4 unused (lane 0).
    static LOCAL_LANES: [u16; 32] = {
        let mut ix = [0u16; 32];
        let mut f = 0;
        while f < PAIR {
            ix[f] = local_lane(f) as u16;
            f += 1;
        }
        ix
    };

    /// The lane of local sum `f` among the lanes of whole tiles of 8 (7 local sums, then the
    /// boundary lane, per tile).
    const fn local_lane(f: usize) -> usize {
        8 * (f / 7) + f % 7
    }

    /// `vpermw` indices: the 4 tiles' totals (lanes 7, 15, 23 and 31) into the low halves of
    /// 32-bit lanes 0..4 (16-bit lanes 0, 2, 4 and 6; the others zeroed by the mask `0x55`).
    static TOTAL_LANES: [u16; 32] = {
        let mut ix = [0u16; 32];
        let mut j = 0;
        while j < 4 {
            ix[2 * j] = (8 * j + 7) as u16;
            j += 1;
        }
        ix
    };

    /// The prefix sums of each 128-bit lane's eight 16-bit lanes (one tile of 8 columns), for
    /// lanes whose tile sums fit 16 bits (the band form's bound, [`band_applies`]): each 64-bit
    /// lane's four by one multiply, then the low four's total added to the high four.
    ///
    /// A 64-bit lane holding `x_0..x_3` (16 bits each, `x_0` lowest) times `1 + 2^16 + 2^32 +
    /// 2^48` (`vpmullq`, the product's low 64 bits) is `sum_j 2^(16 j) (x_0 + ... + x_j)`: lane
    /// `j` of the product is the prefix `x_0 + ... + x_j` as long as no prefix carries past 16
    /// bits, and none does when the tile's sum fits 16 bits (a carry can leave lanes 0 to 2 and
    /// 4 to 6 only: lanes 3 and 7 wrap as the 16-bit adds did, so the local sums' bound is what
    /// matters). Then lane 3 (the low half's total) is broadcast into lanes 4..8 (`vpshufb`,
    /// zeros into lanes 0..4) and added. One multiply and one shuffle instead of three byte
    /// shifts (shuffles) and three adds: on a Zen 4, `band512::row_packed` took 0.87x the time
    /// per row and a tiled build of 1,024^2 0.88x (docs/benchmarks.md, fourteenth session).
    /// Intel's `vpmullq` is slower (three uops); not measured here.
    #[cfg(not(miri))]
    #[inline]
    #[target_feature(enable = "avx512f,avx512bw,avx512dq")]
    fn prefix8(c: __m512i) -> __m512i {
        let q = _mm512_mullo_epi64(c, _mm512_set1_epi64(0x0001_0001_0001_0001));
        // Bytes 6 and 7 (lane 3) into lanes 4..8 of each 128-bit lane; -128 writes a zero.
        let lane3 = _mm512_broadcast_i32x4(_mm_setr_epi8(
            -128, -128, -128, -128, -128, -128, -128, -128, 6, 7, 6, 7, 6, 7, 6, 7,
        ));
        _mm512_add_epi16(q, _mm512_shuffle_epi8(q, lane3))
    }

    /// Under Miri, which may not emulate the 512-bit `vpshufb`: the broadcast of lane 3 by two
    /// shuffles it does emulate (`vpshuflw` into lanes 0..4, then a byte shift by 8), the same
    /// lanes.
    #[cfg(miri)]
    #[target_feature(enable = "avx512f,avx512bw,avx512dq")]
    fn prefix8(c: __m512i) -> __m512i {
        let q = _mm512_mullo_epi64(c, _mm512_set1_epi64(0x0001_0001_0001_0001));
        let lane3 = _mm512_bslli_epi128::<8>(_mm512_shufflelo_epi16::<0xff>(q));
        _mm512_add_epi16(q, lane3)
    }

    /// The constants of [`pack`] for the width `k` (8, 10, 12 or 14).
    #[derive(Clone, Copy)]
    struct Packing {
        local: __m512i,
        weights: __m512i,
        shift: __m512i,
        low2k: __m512i,
        bytes: __m512i,
        #[cfg(miri)]
        k: u32,
    }

    /// The 28 local sums of a pair of blocks (the tiles' prefix sums `p`, all below `2^k`)
    /// packed at `k` bits: bytes `0..7 k / 2` of the result (the rest unspecified), as
    /// [`tiled512::kernel8_packed`] packs them: gathered into 16-bit lanes (`vpermw`), pairs
    /// joined by `vpmaddwd` with weights `(1, 2^k)`, pairs of pairs by a shift and a bit
    /// select (`vpsrlvq`, `vpternlogq`: `4 k` bits at the bottom of each 64-bit lane), the 7
    /// lanes' `k / 2` bytes moved together (`vpermb`, [`PACK8_BYTES`]).
    #[cfg(not(miri))]
    #[inline]
    #[target_feature(enable = "avx512f,avx512bw,avx512vbmi")]
    fn pack(p: __m512i, c: &Packing) -> __m512i {
        let f = _mm512_permutexvar_epi16(c.local, p);
        let d = _mm512_madd_epi16(f, c.weights);
        let q = _mm512_ternarylogic_epi64::<0xE4>(d, _mm512_srlv_epi64(d, c.shift), c.low2k);
        _mm512_permutexvar_epi8(c.bytes, q)
    }

    /// Under Miri, which emulates neither `vpermw` nor `vpermb`: [`pack`]'s bytes computed
    /// field by field (bytes past `7 k / 2` zero).
    #[cfg(miri)]
    #[target_feature(enable = "avx512f")]
    fn pack(p: __m512i, c: &Packing) -> __m512i {
        // (The vector constants are the native path's.)
        let _ = (c.local, c.weights, c.shift, c.low2k, c.bytes);
        let mut lanes = [0u16; 32];
        // SAFETY: a 64-byte store into `lanes`.
        unsafe { _mm512_storeu_si512(lanes.as_mut_ptr().cast(), p) };
        let fields = LOCAL_LANES
            .iter()
            .take(PAIR)
            .map(|&ix| u32::from(lanes[usize::from(ix)]));
        super::miri_pack_bits(fields, c.k)
    }

    /// The 4 tiles' totals of the prefix sums `p` (lanes 7, 15, 23, 31) as 32-bit lanes.
    #[cfg(not(miri))]
    #[inline]
    #[target_feature(enable = "avx512f,avx512bw")]
    fn totals(p: __m512i, ix: __m512i) -> __m128i {
        _mm512_castsi512_si128(_mm512_maskz_permutexvar_epi16(0x55, ix, p))
    }

    /// Under Miri (no `vpermw`): [`totals`] lane by lane.
    #[cfg(miri)]
    #[target_feature(enable = "avx512f")]
    fn totals(p: __m512i, _ix: __m512i) -> __m128i {
        let mut lanes = [0u16; 32];
        // SAFETY: a 64-byte store into `lanes`.
        unsafe { _mm512_storeu_si512(lanes.as_mut_ptr().cast(), p) };
        let t = |j: usize| i32::from(lanes[8 * j + 7]);
        _mm_setr_epi32(t(0), t(1), t(2), t(3))
    }

    /// The 4 tiles' boundaries of the prefix sums `p`: their totals ([`totals`]) prefix-summed
    /// onto the running sum `run`, which becomes the last of them.
    #[inline]
    #[target_feature(enable = "avx512f,avx512bw")]
    fn boundaries(p: __m512i, ix: __m512i, run: &mut __m128i) -> __m128i {
        let w = totals(p, ix);
        let w = _mm_add_epi32(w, _mm_slli_si128::<4>(w));
        let w = _mm_add_epi32(w, _mm_slli_si128::<8>(w));
        let w = _mm_add_epi32(w, *run);
        *run = _mm_shuffle_epi32::<0xff>(w);
        w
    }

    /// [`band_row`]'s kernel over `pairs` pairs of blocks (32 columns, 4 tiles) with the local
    /// sums packed as they are computed; returns the running boundary sum after them. Per
    /// pair: 32 texels widened (`vpmovzxbw`) and added to the column sums `cs`, stored back;
    /// their prefix within each tile (each 128-bit lane holds one); the 28 local sums packed
    /// at `k` bits ([`pack`]) and stored at `out + 7 k / 2 pair` (all 64 bytes while they end
    /// inside the pairs' `7 k / 2 pairs` bytes: the bytes past this pair's are the next
    /// pairs', rewritten by their stores in order; then a masked store of exactly its bytes);
    /// the 4 tiles' totals ([`totals`]) prefix-summed onto the running sum and stored as the 4
    /// boundaries. The 16-bit local sums of [`band256::row`] are neither stored nor read back
    /// by [`pack256::even`]: per 32 columns about 22 instructions instead of about 50 (55
    /// before the AVX2 cuts of the twenty-first session). The
    /// lines of `ahead` asked for at the row's pace, 16 blocks ahead ([`Prefetch::paced`]: the
    /// pairs pack as they go), a group of 4 pairs at a time.
    ///
    /// # Safety
    /// The CPU has AVX-512F, BW, DQ and VBMI; `k` is 8, 10, 12 or 14 and every
    /// local sum below `2^k`; `t` valid for reads of `32 pairs` bytes, `cs` for reads and
    /// writes of `32 pairs` `u16`, `bnd` for writes of `4 pairs` `u32`, `out` for writes of
    /// `7 k / 2 pairs` bytes; not overlapping.
    #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vbmi")]
    pub(super) unsafe fn row_packed(
        t: *const u8,
        cs: *mut u16,
        bnd: *mut u32,
        pairs: usize,
        out: *mut u8,
        k: u32,
        ahead: Ahead,
    ) -> u32 {
        // Prefetching, a group of pairs at a time (the bookkeeping once per group).
        const GROUP: usize = 4;
        let mut prefetch = Prefetch::paced(ahead, 2 * pairs, 16);
        // SAFETY: each table is 64 bytes: one unaligned load.
        let (local, total, bytes) = unsafe {
            (
                _mm512_loadu_si512(LOCAL_LANES.as_ptr().cast()),
                _mm512_loadu_si512(TOTAL_LANES.as_ptr().cast()),
                _mm512_loadu_si512(PACK8_BYTES[(k as usize - 8) / 2].as_ptr().cast()),
            )
        };
        let c = Packing {
            local,
            weights: _mm512_set1_epi32(((1u32 << k) << 16 | 1) as i32),
            shift: _mm512_set1_epi64(i64::from(32 - 2 * k)),
            low2k: _mm512_set1_epi64(((1u64 << (2 * k)) - 1) as i64),
            bytes,
            #[cfg(miri)]
            k,
        };
        let n = 7 * k as usize / 2;
        let store = (1u64 << n) - 1;
        let mut run = _mm_setzero_si128();
        let mut from = 0;
        while from < pairs {
            let end = (from + GROUP).min(pairs);
            prefetch.ask(2 * end);
            for pr in from..end {
                let i = 32 * pr;
                // SAFETY: pr < pairs: texels and column sums i..i + 32 inside `t` and `cs`,
                // boundaries 4 pr..4 pr + 4 inside `bnd`; the packed bytes at out[n pr..n pr +
                // 64] when that ends inside the caller's `n pairs`, else out[n pr..n (pr +
                // 1)] by the masked store (the caller's contract).
                unsafe {
                    let x = _mm512_cvtepu8_epi16(_mm256_loadu_si256(t.add(i).cast()));
                    let s = _mm512_add_epi16(x, _mm512_loadu_si512(cs.add(i).cast()));
                    _mm512_storeu_si512(cs.add(i).cast(), s);
                    let p = prefix8(s);
                    let o = pack(p, &c);
                    if n * pr + 64 <= n * pairs {
                        _mm512_storeu_si512(out.add(n * pr).cast(), o);
                    } else {
                        _mm512_mask_storeu_epi8(out.add(n * pr).cast(), store, o);
                    }
                    let w = boundaries(p, total, &mut run);
                    _mm_storeu_si128(bnd.add(4 * pr).cast(), w);
                }
            }
            from = end;
        }
        _mm_cvtsi128_si32(run) as u32
    }

    /// Columns per chunk of [`end_row_packed`]: 32 tiles, whose 224 local sums and 32
    /// boundaries are 7 and 1 groups of [`pack512::pack`] (each chunk's fields start on a
    /// word: `224 k` and `32 k` bits).
    pub(super) const CHUNK: usize = 256;

    /// `vpermd` indices (each of `lo`, `hi` in [`end_row_packed`]): the tiles' boundaries
    /// (lanes 0..4 of the prefix of the totals) into lanes 7 and 15: `lo` takes lanes 0 and 1,
    /// `hi` 2 and 3 (the other lanes kept by the mask `0x8080`).
    static INSERT_LANES: [[u32; 16]; 2] = {
        let mut ix = [[0u32; 16]; 2];
        let mut h = 0;
        while h < 2 {
            ix[h][7] = 2 * h as u32;
            ix[h][15] = 2 * h as u32 + 1;
            h += 1;
        }
        ix
    };

    /// `vpermt2d` indices over `lo` (0..16) and `hi` (16..32), 4 tiles of 8 columns: the 28
    /// local sums in order (lanes 0..16 of the first, 0..12 of the second; the rest lane 0),
    /// then the 4 boundaries (lanes 7, 15, 23, 31) in lanes 0..4 of the third.
    static END_LANES: [[u32; 16]; 3] = {
        let mut ix = [[0u32; 16]; 3];
        let mut f = 0;
        while f < PAIR {
            ix[f / 16][f % 16] = local_lane(f) as u32;
            f += 1;
        }
        let mut j = 0;
        while j < 4 {
            ix[2][j] = (8 * j + 7) as u32;
            j += 1;
        }
        ix
    };

    /// [`band_end_row`]'s kernel with both components' rows packed in the same pass, over
    /// `chunks` chunks of [`CHUNK`] columns; returns the running boundary sum after them.
    /// Per 32 columns (4 tiles): 32 texels widened and added to the column sums, which are
    /// cleared (one 64-byte store of zeros); their prefix within each tile; the 4 tiles'
    /// totals prefix-summed onto the running sum (the boundaries of acc_0's form, as in
    /// [`row_packed`]) and put in the boundary lanes of the prefix widened to 32 bits (the
    /// form of [`band256::form`], 32 columns at once); the level above `acc` plus the form,
    /// stored; its 28 local sums and 4 boundaries gathered (`vpermt2d`) into two small
    /// buffers (`buf`, `bbuf`: they stay in L1). Per chunk, the buffers packed into the rows:
    /// 7 groups of `kl`-bit fields at `wl + 7 kl chunk`, 1 group of `kb`-bit fields at `wb +
    /// kb chunk` ([`pack512::pack`]: its constants are the code's, loaded from memory per
    /// call; with the kernel's own they would pass the 32 registers). The 32-bit local
    /// sums and boundaries are not written to the builder's scratch and read back by a second
    /// pass, and the step itself takes about 37 instructions per 32 columns instead of about
    /// 75 ([`band256::end_row`]). The lines of `ahead` asked for a chunk ahead, a chunk (16
    /// blocks) at a time ([`Prefetch::paced`]: all of them by the middle of the row, as
    /// [`band256::end_row`] asks, took 1.06x to 1.08x the time of the tiled build of
    /// 4,096^2).
    ///
    /// # Safety
    /// The CPU has AVX-512F, VL, BW and DQ; `t` valid for reads of `256 chunks` bytes, `cs` for
    /// reads and writes of `256 chunks` `u16`, `acc` for reads and writes of `256 chunks`
    /// words, `wl` for writes of `7 kl chunks` words, `wb` for writes of `kb chunks` words;
    /// `11 <= kl, kb <= 32`; not overlapping.
    #[allow(
        clippy::too_many_arguments,
        reason = "a kernel's raw parts, one call site"
    )]
    #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl")]
    pub(super) unsafe fn end_row_packed(
        t: *const u8,
        cs: *mut u16,
        acc: *mut u32,
        chunks: usize,
        (wl, kl): (*mut u32, u32),
        (wb, kb): (*mut u32, u32),
        ahead: Ahead,
    ) -> u32 {
        const STEPS: usize = CHUNK / 32;
        let mut prefetch = Prefetch::paced(ahead, CHUNK / BLOCK * chunks, CHUNK / BLOCK);
        // 28 local sums per step, 16 past the last one's start stored: 224 + 4 words.
        let mut buf = [0u32; PAIR * STEPS + 4];
        let mut bbuf = [0u32; 4 * STEPS];
        // SAFETY: each table is 64 bytes: one unaligned load.
        let ([ins_lo, ins_hi], [loc_a, loc_b, bnd_ix], total) = unsafe {
            let load = |p: &[u32; 16]| _mm512_loadu_si512(p.as_ptr().cast());
            (
                [load(&INSERT_LANES[0]), load(&INSERT_LANES[1])],
                [
                    load(&END_LANES[0]),
                    load(&END_LANES[1]),
                    load(&END_LANES[2]),
                ],
                _mm512_loadu_si512(TOTAL_LANES.as_ptr().cast()),
            )
        };
        let zero = _mm512_setzero_si512();
        let mut run = _mm_setzero_si128();
        for c in 0..chunks {
            prefetch.ask(CHUNK / BLOCK * (c + 1));
            for st in 0..STEPS {
                let i = CHUNK * c + 32 * st;
                // SAFETY: c < chunks: columns i..i + 32 inside `t`, `cs` and `acc` (the
                // caller's contract); buf[28 st..28 st + 32] (<= 228) and bbuf[4 st..4 st +
                // 4] (<= 32) inside the buffers.
                unsafe {
                    let x = _mm512_cvtepu8_epi16(_mm256_loadu_si256(t.add(i).cast()));
                    let sum = _mm512_add_epi16(x, _mm512_loadu_si512(cs.add(i).cast()));
                    _mm512_storeu_si512(cs.add(i).cast(), zero);
                    let p = prefix8(sum);
                    let w = _mm512_zextsi128_si512(boundaries(p, total, &mut run));
                    let lo = _mm512_cvtepu16_epi32(_mm512_castsi512_si256(p));
                    let hi = _mm512_cvtepu16_epi32(_mm512_extracti64x4_epi64::<1>(p));
                    let lo = _mm512_mask_permutexvar_epi32(lo, 0x8080, ins_lo, w);
                    let hi = _mm512_mask_permutexvar_epi32(hi, 0x8080, ins_hi, w);
                    let lo = _mm512_add_epi32(lo, _mm512_loadu_si512(acc.add(i).cast()));
                    let hi = _mm512_add_epi32(hi, _mm512_loadu_si512(acc.add(i + 16).cast()));
                    _mm512_storeu_si512(acc.add(i).cast(), lo);
                    _mm512_storeu_si512(acc.add(i + 16).cast(), hi);
                    let b = buf.as_mut_ptr().add(PAIR * st);
                    _mm512_storeu_si512(b.cast(), pack512::perm2(lo, loc_a, hi));
                    _mm512_storeu_si512(b.add(16).cast(), pack512::perm2(lo, loc_b, hi));
                    let v = _mm512_castsi512_si128(pack512::perm2(lo, bnd_ix, hi));
                    _mm_storeu_si128(bbuf.as_mut_ptr().add(4 * st).cast(), v);
                }
            }
            // SAFETY: the buffers hold 7 and 1 groups of 32 fields; c < chunks: words
            // wl[7 kl c..7 kl (c + 1)] and wb[kb c..kb (c + 1)] writable (the caller's
            // contract).
            unsafe {
                pack512::pack(
                    buf.as_ptr(),
                    wl.add(7 * kl as usize * c),
                    PAIR * STEPS / 32,
                    kl,
                );
                pack512::pack(bbuf.as_ptr(), wb.add(kb as usize * c), 1, kb);
            }
        }
        _mm_cvtsi128_si32(run) as u32
    }
}

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::panic,
    reason = "tests: a panic is a failed test"
)]
mod tests {
    extern crate std;
    use super::*;

    /// [`TexturePages`]'s schedule, against the pages computed row by row: textures of `u8` and
    /// `u16` texels, tight and with strides of a few bytes to two pages past the row, at 4 offsets
    /// from an allocation (under Miri one padded shape), from row 0 and from a later row; steps of
    /// 7 rows and 1 (the band rows' runs and the rows that end a tile row) and of 1, each step
    /// asked twice (the second asks nothing). Every page (by address) that holds texels of the rows
    /// from the first gets exactly one line, that line a texel's, and before the step at row `y`
    /// every page that holds texels of its rows has one; none is asked for past `PAGE_LEAD` bytes
    /// beyond the next `MAX_BAND_ROWS` rows; `ask` follows the same schedule.
    #[test]
    fn texture_pages_ask_once_per_page_ahead_of_its_rows() {
        use std::collections::BTreeSet;
        fn check<T: Texel + Default>(
            width: usize,
            pad: usize,
            height: usize,
            skip: usize,
            from: usize,
            steps: &[usize],
        ) {
            let stride = width + pad;
            let buf = std::vec![T::default(); stride * height + 4096];
            let data = &buf[skip..skip + stride * (height - 1) + width];
            let texture = crate::Texture::<T, 1>::with_stride(data, width, height, stride).unwrap();
            let (size, addr) = (core::mem::size_of::<T>(), data.as_ptr().addr());
            let page_of = |b: usize| (addr + b) / PAGE;
            // The pages that hold texels of rows `from..rows`, computed row by row; those that
            // start before row `from`'s first byte belong to the rows before.
            let first = page_of(from * stride * size)
                + usize::from(!(addr + from * stride * size).is_multiple_of(PAGE));
            let pages = |rows: core::ops::Range<usize>| -> BTreeSet<usize> {
                rows.flat_map(|r| {
                    page_of(r * stride * size)..=page_of((r * stride + width) * size - 1)
                })
                .filter(|&p| p >= first)
                .collect()
            };
            let mut schedule = TexturePages::new(&texture, from);
            let mut hinted = TexturePages::new(&texture, from);
            let (mut y, mut got) = (from, std::vec::Vec::new());
            let case =
                std::format!("width {width} pad {pad} height {height} skip {skip} from {from}");
            for &step in steps.iter().cycle() {
                if y >= height {
                    break;
                }
                let before = got.len();
                schedule.due(y, |at| got.push(at));
                schedule.due(y, |at| got.push(at));
                hinted.ask(y);
                assert_eq!(
                    (hinted.next, hinted.asked),
                    (schedule.next, schedule.asked),
                    "{case}"
                );
                // Each line a texel's, in order; none past the lead.
                let lead = ((y + MAX_BAND_ROWS) * stride * size + PAGE_LEAD).max(stride * size);
                for &at in &got[before..] {
                    assert!(
                        at % (stride * size) < width * size && at < data.len() * size,
                        "{case}"
                    );
                    assert!(at < lead + stride * size, "{case} y {y} at {at}");
                }
                let asked: BTreeSet<usize> = got.iter().map(|&at| page_of(at)).collect();
                assert_eq!(asked.len(), got.len(), "{case}: a page twice");
                assert!(got.windows(2).all(|w| w[0] < w[1]), "{case}");
                assert!(
                    pages(y..(y + step).min(height)).is_subset(&asked),
                    "{case} y {y}"
                );
                y += step;
            }
            let asked: BTreeSet<usize> = got.iter().map(|&at| page_of(at)).collect();
            assert_eq!(asked, pages(from..height), "{case}");
        }
        // Under Miri (four runs in CI, for the hints' unsafe call) one padded shape.
        let (skips, shapes): (&[usize], &[(usize, usize, usize)]) = if cfg!(miri) {
            (&[1], &[(1000, 24, 40)])
        } else {
            (
                &[0, 1, 17, 4095],
                &[
                    (1, 0, 3),
                    (100, 0, 50),
                    (1024, 0, 64),
                    (4096, 0, 40),
                    (5000, 0, 9),
                    (64, 0, 700),
                    (1000, 24, 40),
                    (100, 8000, 12),
                    (3000, 5000, 10),
                ],
            )
        };
        for &skip in skips {
            for &(width, pad, height) in shapes {
                for from in [0, height / 2] {
                    for steps in [&[7, 1][..], &[1]] {
                        check::<u8>(width, pad, height, skip, from, steps);
                        check::<u16>(width, pad, height, skip, from, steps);
                    }
                }
            }
        }
    }

    /// `build_via_working_row` takes exactly the tables it documents (`u8` texels, one
    /// channel, `u32` entries, whole rows, at least 1 MiB, rows of at most 4,096 entries, every
    /// row present and whole; streamed from 32 MiB, by plain stores below, or for the rows off
    /// 16 bytes) and builds them as the portable checked build does, each case under another
    /// kernel cap (SSE2, AVX2, AVX-512 in turn; the widest the CPU runs for a kernel it lacks,
    /// so that no case is skipped); it declines the rest with nothing written. (Whether a copy
    /// was streamed cannot be seen from the table: the values are the same.)
    #[test]
    #[cfg_attr(miri, ignore = "tables of 1 to 34 MiB: too slow under Miri")]
    fn build_via_working_row_takes_tables_of_a_mib_and_more() {
        use crate::{Sat, Texture};
        let texels: std::vec::Vec<u8> = (0..4094u32 * 2100)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
            .collect();
        // (width, height, entries off 16 bytes, last row: 0 there, 1 missing, 2 short, taken);
        // case `c` under kernel `c mod 3` (SSE2, AVX2, AVX-512; else the widest the CPU runs).
        let cases = [
            // Streamed: every row on 16 bytes, or every other row (4,094 entries, a tail of 14).
            (4096, 2048, 0, 0, true),
            (4092, 2052, 0, 0, true),
            (4094, 2100, 0, 0, true),
            (1024, 8192, 0, 0, true),
            // Past 32 MiB but off 16 bytes, and under 32 MiB: plain stores.
            (4096, 2048, 1, 0, true),
            (1023, 257, 3, 0, true),
            (4096, 2047, 0, 0, true),
            (1024, 256, 0, 0, true),
            (4096, 64, 0, 0, true),
            // Under 1 MiB, rows too wide, a row missing or short.
            (1024, 255, 0, 0, false),
            (4100, 2048, 0, 0, false),
            (4097, 64, 0, 0, false),
            (4096, 2048, 0, 1, false),
            (4096, 2048, 0, 2, false),
        ];
        for (c, (w, h, off, last, taken)) in cases.into_iter().enumerate() {
            let kernel = Some(Kernel::ALL[c % 3])
                .filter(|k| k.available())
                .unwrap_or_else(Kernel::detected);
            let t = &texels[..w * h];
            let mut whole = std::vec![0xDEAD_BEEFu32; w * h + 8];
            let base = (0..4)
                .find(|&i| (whole.as_ptr() as usize + 4 * i).is_multiple_of(16))
                .unwrap()
                + off;
            let table = &mut whole[base..base + w * h];
            let row = |y: usize| match (y == h - 1, last) {
                (true, 1) => None,
                (true, 2) => Some(&t[y * w..][..w - 4]),
                _ => Some(&t[y * w..][..w]),
            };
            let got = kernel.cap(|| build_via_working_row::<u8, u32, 1>(table, w, row));
            let what = (w, h, off, last, kernel);
            assert_eq!(got, taken, "{what:?}");
            if taken {
                let mut want = std::vec![0u32; w * h];
                let texture = Texture::<u8>::new(t, w, h).unwrap();
                Sat::build_checked(&texture, &mut want).unwrap();
                assert!(whole[base..base + w * h] == want[..], "{w} x {h}");
                whole[base..base + w * h].fill(0xDEAD_BEEF);
            }
            assert!(
                whole.iter().all(|&v| v == 0xDEAD_BEEF),
                "{w} x {h}: written outside the table or where declined"
            );
        }
        // Other texel, entry and channel types.
        let mut table = std::vec![0u32; 4096 * 2048];
        let t16 = std::vec![1u16; 4096];
        assert!(!build_via_working_row::<u16, u32, 1>(
            &mut table,
            4096,
            |_| Some(&t16[..])
        ));
        assert!(!build_via_working_row::<u8, u32, 2>(
            &mut table,
            4096,
            |_| Some(&texels[..4096])
        ));
        let mut t64 = std::vec![0u64; 4096 * 1024];
        assert!(!build_via_working_row::<u8, u64, 1>(&mut t64, 4096, |_| {
            Some(&texels[..4096])
        }));
        // A table that is not whole rows (one entry past 64 rows of 4,096).
        let mut ragged = std::vec![0u32; 4096 * 64 + 1];
        assert!(!build_via_working_row::<u8, u32, 1>(
            &mut ragged,
            4096,
            |_| Some(&texels[..4096])
        ));
        assert!(table.iter().all(|&v| v == 0) && t64.iter().all(|&v| v == 0));
        assert!(ragged.iter().all(|&v| v == 0));
    }

    /// `band_applies` takes a tiling only where a tile's sum fits 16 bits: 8 x 32 tiles of `u8`
    /// texels (65,280) and 8 x 64 of 7-bit ones (65,024), not 8 x 33 (67,320) nor 8 x 36, whose
    /// local sums (7 x 35 x 255 = 62,475) fit 16 bits but its tile rows' totals do not; not 16-bit
    /// texels, tiles other than 8 wide, rows shorter than a block, or other entries; only with AVX2
    /// or AVX-512 as the best kernel (capped to each kernel the CPU has).
    #[test]
    fn band_applies_bounds_a_tiles_sum() {
        for kernel in Kernel::ALL.into_iter().filter(|k| k.available()) {
            kernel.cap(band_applies_bounds_under_the_cap);
        }
    }

    fn band_applies_bounds_under_the_cap() {
        let avx2 = Kernel::best() != Kernel::Sse2;
        assert_eq!(band_applies::<u32, 1>(16, 8, 32, 8), avx2);
        assert_eq!(band_applies::<u32, 1>(1024, 8, 64, 7), avx2);
        assert!(!band_applies::<u32, 1>(16, 8, 33, 8));
        assert!(!band_applies::<u32, 1>(16, 8, 36, 8));
        assert!(!band_applies::<u32, 1>(16, 8, 65, 7));
        assert!(!band_applies::<u32, 1>(16, 8, 1, 16));
        assert!(!band_applies::<u32, 1>(16, 4, 8, 8));
        assert!(!band_applies::<u32, 1>(15, 8, 8, 8));
        assert!(!band_applies::<u64, 1>(16, 8, 8, 8));
        assert!(!band_applies::<u32, 2>(16, 8, 8, 8));
    }

    /// `pack_u32` writes, for every width 11 to 32, the words a field-by-field write of the
    /// low `k` bits gives (`layouts::packed::write_bits`), for whole groups of 32 (AVX-512) or
    /// runs of 16 (AVX2) only, and nothing past them (for an odd `k` an odd run ends in the
    /// middle of a word: its upper half kept); values with their high bits set (only the low
    /// `k` stored); counts below, at and past whole runs and groups, and past whole passes of
    /// 8 groups of the AVX2 kernel (a last pass of 4 to 7 groups, or 1 to 8 runs, with and
    /// without an odd run after them; under Miri the first count, one group and an odd run,
    /// for every width). Then a slice of `k` words, which holds 2 of 3 runs: no more packed. Every
    /// packing kernel the CPU runs, explicitly (AVX2 on
    /// an AVX-512 CPU too), then `pack_u32` itself: all the whole groups packed with AVX2 or
    /// AVX-512 (Miri: the kernel the target features enable), 0 without, for another type, or
    /// a width outside 11..=32.
    #[test]
    fn pack_u32_equals_field_by_field() {
        extern crate std;
        use std::vec::Vec;
        let counts: &[usize] = if cfg!(miri) {
            &[48, 33, 9 * 32 + 17]
        } else {
            &[
                0,
                15,
                16,
                31,
                32,
                48,
                64,
                101,
                3 * 32 + 16 + 5,
                4 * 32,
                4 * 32 + 16,
                5 * 32 + 16,
                8 * 32 + 16,
                13 * 32 + 16,
                9 * 32 + 16,
                12 * 32 + 16,
                8 * 32,
                8 * 32 + 31,
                12 * 32 + 5,
                15 * 32 + 7,
                17 * 32,
            ]
        };
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed as u32
        };
        // None: `pack_u32`, which packs with AVX2 or AVX-512 (whichever is best).
        let packs = Kernel::best() != Kernel::Sse2;
        let kernels = [Kernel::Sse2, Kernel::Avx2, Kernel::Avx512Vnni]
            .into_iter()
            .filter(|k| k.available())
            .map(Some)
            .chain([None]);
        let mut ran = 0;
        for kernel in kernels {
            for k in MIN_PACK_BITS..=32 {
                for (c, &n) in counts.iter().enumerate() {
                    // Under Miri, the count of several passes for a few widths only.
                    if cfg!(miri) && c > 0 && ![11, 16, 21, 32].contains(&k) {
                        continue;
                    }
                    let fields: Vec<u32> = (0..n).map(|_| next()).collect();
                    let noise: Vec<u32> = (0..n * k as usize / 32 + 3).map(|_| next()).collect();
                    let mut words = noise.clone();
                    let done = match kernel {
                        // SAFETY: `kernel` is available on this CPU (filtered above).
                        Some(kr) => unsafe { pack_u32_with(kr, &mut words, &fields, k) },
                        None => pack_u32(&mut words, &fields, k),
                    };
                    // AVX2 packs runs of 16 (whole groups for the widths that divide 32),
                    // AVX-512 whole groups of 32, SSE2 nothing.
                    let expect = match kernel.unwrap_or(Kernel::best()) {
                        Kernel::Sse2 => 0,
                        Kernel::Avx2 if k % 16 != 0 => n / 16 * 16,
                        _ => n / 32 * 32,
                    };
                    let name = kernel.map_or("pack_u32", Kernel::name);
                    assert_eq!(done, expect, "{name} k {k} n {n}");
                    ran += usize::from(done > 0);
                    let want = field_by_field(noise.clone(), &fields[..done], k);
                    assert_eq!(words, want, "{name} k {k} n {n}");
                    // Words exactly as long as the whole groups, guard words after them: the
                    // same words, the guards untouched (`pack512::pack_k` stores whole
                    // vectors for every group but the last; Miri checks each store too).
                    let len = n / 32 * k as usize;
                    let mut guarded = noise.clone();
                    let done = match kernel {
                        // SAFETY: as above.
                        Some(kr) => unsafe { pack_u32_with(kr, &mut guarded[..len], &fields, k) },
                        None => pack_u32(&mut guarded[..len], &fields, k),
                    };
                    let fit = field_by_field(noise.clone(), &fields[..done], k);
                    assert_eq!(guarded, fit, "{name} k {k} n {n}, exact words");
                }
            }
        }
        assert_eq!(ran > 0, packs);
        // A slice of k words holds one group: of 48 fields, AVX2 packs 2 runs of 16 (AVX-512
        // its one group of 32), and writes no word past the slice (it ends there).
        for k in MIN_PACK_BITS..=32 {
            let fields: Vec<u32> = (0..48).map(|_| next()).collect();
            let mut words = std::vec![0u32; k as usize];
            let done = pack_u32(&mut words, &fields, k);
            assert_eq!(done, if packs { 32 } else { 0 }, "k {k}");
            let want = field_by_field(std::vec![0u32; k as usize], &fields[..done], k);
            assert_eq!(words, want, "k {k}");
        }
        let mut w = [0u32; 64];
        assert_eq!(pack_u32(&mut w, &[1u16; 64], 16), 0);
        assert_eq!(pack_u32(&mut w, &[1u32; 64], MIN_PACK_BITS - 1), 0);
        assert_eq!(pack_u32(&mut w, &[1u32; 64], 33), 0);
        assert_eq!(w, [0; 64]);
    }

    /// The reference of `tiled_row`, written independently: per position `x = 1..=n`, the sum
    /// of the row's texels since the last multiple of `tile` (all of them up to `x` at a
    /// multiple) added to `acc` with `lower`, summed texel by texel; then every value at a
    /// multiple of `tile` into `bnd` and every other one into `local`.
    fn tiled_reference(
        t: &[u8],
        lower: Option<&mut [u32]>,
        acc: &mut [u32],
        tile: usize,
    ) -> (std::vec::Vec<u32>, std::vec::Vec<u32>) {
        let (mut bnd, mut local) = (std::vec::Vec::new(), std::vec::Vec::new());
        let mut lower = lower;
        for x in 1..=t.len() {
            let from = if x % tile == 0 { 0 } else { x - x % tile };
            let r = t[from..x]
                .iter()
                .fold(0u32, |s, &v| s.wrapping_add(u32::from(v)));
            let l = lower.as_mut().map_or(0, |l| core::mem::take(&mut l[x - 1]));
            acc[x - 1] = acc[x - 1].wrapping_add(l).wrapping_add(r);
            if x % tile == 0 {
                bnd.push(acc[x - 1]);
            } else {
                local.push(acc[x - 1]);
            }
        }
        (bnd, local)
    }

    /// `tiled_row_with` every kernel this CPU runs (under Miri: the widest the build enables;
    /// AVX-512 VNNI for every tile width, AVX2 for tiles of 8; otherwise it must decline) equals the
    /// reference for every tile width 2, 4, 8 and 16, every row width up to 6 blocks and a
    /// tail, with and without the level below, texels all 0, all 255, a ramp and random,
    /// accumulators near `u32::MAX` (wrapping): the accumulators, the cleared level below, the
    /// boundaries and the local sums, their counts, and nothing written past them (the slices
    /// are exactly as long as the row needs, then sentinels). Also: other types, tile widths
    /// and short slices decline, writing nothing.
    #[test]
    fn tiled_row_equals_the_reference() {
        extern crate std;
        use std::vec::Vec;
        const MAX: usize = 6 * BLOCK + 7;
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let widths: Vec<usize> = if cfg!(miri) {
            std::vec![0, 15, 16, 17, 33, 48, 50]
        } else {
            (0..=MAX).collect()
        };
        let words = [0u32; 100];
        let mut ran = [0usize; 3];
        for (k, kernel) in Kernel::ALL
            .into_iter()
            .enumerate()
            .filter(|(_, k)| k.available())
        {
            for tile in [2usize, 4, 8, 16] {
                let runs = kernel == Kernel::Avx512Vnni || kernel == Kernel::Avx2 && tile == 8;
                for &n in &widths {
                    for pattern in 0..4 {
                        if cfg!(miri) && pattern != 3 {
                            continue;
                        }
                        let t: Vec<u8> = (0..n)
                            .map(|i| match pattern {
                                0 => 0,
                                1 => 255,
                                2 => (i % 256) as u8,
                                _ => rng(&mut seed),
                            })
                            .collect();
                        let acc0: Vec<u32> = (0..n)
                            .map(|i| (u32::MAX - 1000).wrapping_add(37 * i as u32))
                            .collect();
                        let low0: Vec<u32> = (0..n)
                            .map(|i| 3 * i as u32 + u32::from(rng(&mut seed)))
                            .collect();
                        for with_lower in [false, true] {
                            let (nb, nl) = (n / tile, n - n / tile);
                            let mut acc = acc0.clone();
                            let mut low = low0.clone();
                            let mut bnd = std::vec![7u32; nb + 20];
                            let mut local = std::vec![9u32; nl + 20];
                            let ahead = [(words.as_ptr(), n.min(100)), (words.as_ptr(), 3)];
                            // SAFETY: `kernel` is one of the CPU's (`Kernel::available`).
                            let got = unsafe {
                                tiled_row_with::<u8, u32, 1>(
                                    kernel,
                                    false,
                                    &t,
                                    with_lower.then_some(&mut low[..]),
                                    &mut acc,
                                    tile,
                                    &mut bnd[..nb],
                                    &mut local[..nl],
                                    ahead,
                                    None,
                                )
                            };
                            let what = (kernel.name(), tile, n, pattern, with_lower);
                            if !runs {
                                assert_eq!(got, None, "{what:?}");
                                assert_eq!(acc, acc0, "{what:?}");
                                continue;
                            }
                            ran[k] += 1;
                            let mut want_acc = acc0.clone();
                            let mut want_low = low0.clone();
                            let (want_b, want_l) = tiled_reference(
                                &t,
                                with_lower.then_some(&mut want_low[..]),
                                &mut want_acc,
                                tile,
                            );
                            assert_eq!(got, Some((nb, nl, 0)), "{what:?}");
                            assert_eq!(acc, want_acc, "{what:?}");
                            assert_eq!(
                                low,
                                if with_lower { want_low } else { low0.clone() },
                                "{what:?}"
                            );
                            assert_eq!(bnd[..nb], want_b[..], "{what:?}");
                            assert_eq!(local[..nl], want_l[..], "{what:?}");
                            assert!(bnd[nb..].iter().all(|&v| v == 7), "{what:?}: past bnd");
                            assert!(local[nl..].iter().all(|&v| v == 9), "{what:?}: past local");
                        }
                    }
                }
            }
        }
        // Every vector kernel this CPU has ran (under Miri: the widest the build enables).
        assert_eq!(ran[1] > 0, Kernel::Avx2.available());
        assert_eq!(ran[2] > 0, Kernel::Avx512Vnni.available());
        // Declined: a tile width the kernel has no table for, another type, short slices.
        let (mut acc, mut b, mut l) = ([1u32; 40], [0u32; 40], [0u32; 40]);
        let t = [3u8; 32];
        let none: Ahead = [(core::ptr::null(), 0); 2];
        assert_eq!(
            tiled_row::<u8, u32, 1>(&t, None, &mut acc, 3, &mut b, &mut l, none, None),
            None
        );
        assert_eq!(
            tiled_row::<u8, u32, 1>(&t, None, &mut acc, 32, &mut b, &mut l, none, None),
            None
        );
        assert_eq!(
            tiled_row::<u8, u32, 1>(&t, None, &mut acc[..31], 8, &mut b, &mut l, none, None),
            None
        );
        assert_eq!(
            tiled_row::<u8, u32, 1>(&t, None, &mut acc, 8, &mut b[..3], &mut l, none, None),
            None
        );
        assert_eq!(
            tiled_row::<u8, u32, 1>(&t, None, &mut acc, 8, &mut b, &mut l[..27], none, None),
            None
        );
        let mut low = [5u32; 31];
        assert_eq!(
            tiled_row::<u8, u32, 1>(&t, Some(&mut low), &mut acc, 8, &mut b, &mut l, none, None),
            None
        );
        let mut acc16 = [1u16; 40];
        let (mut b16, mut l16) = ([0u16; 40], [0u16; 40]);
        assert_eq!(
            tiled_row::<u8, u16, 1>(&t, None, &mut acc16, 8, &mut b16, &mut l16, none, None),
            None
        );
        assert_eq!(
            tiled_row::<u8, u32, 2>(
                &[3u8; 64],
                None,
                &mut [1u32; 80],
                8,
                &mut b,
                &mut l,
                none,
                None
            ),
            None
        );
        assert_eq!((acc, b, l, low), ([1; 40], [0; 40], [0; 40], [5; 31]));
    }

    /// `tiled_row` with a packing target: on a CPU with AVX-512BW and VBMI (under Miri: when the
    /// target features include them, as the last of `.ci/miri.sh`'s flag sets does; widths of
    /// one, two and three pairs and more, so both the masked and the full 64-byte stores run)
    /// and tiles of 8, for every even width `k` of 8 to 14 and
    /// byte-aligned starts 0, 8, 16, 24, the local sums of each pair of blocks go into the
    /// words exactly as the layouts' field-by-field write of their low `k` bits
    /// (`layouts::packed::write_bits`), every other bit of the words (before, between rows,
    /// after) unchanged, `local[..kp]` untouched and the rest of `local`, the boundaries and
    /// the accumulators equal to the reference; every row width up to 6 blocks and a tail
    /// (odd and even block counts), with and without the level below, four texel patterns,
    /// accumulators near `u32::MAX` (local sums wider than `k`: masked). Not packed (`kp =
    /// 0`, the words unchanged): odd widths, 16 bits, starts not on a byte, a slice one byte
    /// short, other tile widths, or a CPU without the instructions.
    #[test]
    fn tiled_row_packs_like_write_bits() {
        extern crate std;
        use std::vec::Vec;
        const MAX: usize = 6 * BLOCK + 7;
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let widths: Vec<usize> = if cfg!(miri) {
            std::vec![32, 50, 64, 103]
        } else {
            (0..=MAX).collect()
        };
        let packs = Kernel::best() == Kernel::Avx512Vnni && vbmi();
        let mut packed_rows = 0usize;
        for tile in [8usize, 4] {
            for &n in &widths {
                for k in [8u32, 10, 11, 12, 14, 16] {
                    for bit in [0u64, 3, 8, 16, 24] {
                        for (pattern, exact) in (0..4).flat_map(|p| [(p, false), (p, true)]) {
                            if cfg!(miri) && (pattern != 3 || (k != 14 && k != 8) || bit > 8) {
                                continue;
                            }
                            // `exact`: the local sums below 2^k (texels at most t_max, the
                            // rows below 4 each; 7 texels a tile).
                            let t_max = if exact { ((1u32 << k) - 8) / 7 } else { 255 };
                            let t: Vec<u8> = (0..n)
                                .map(|i| match pattern {
                                    0 => 0,
                                    1 => 255,
                                    2 => (i % 256) as u8,
                                    _ => rng(&mut seed),
                                })
                                .map(|v| (u32::from(v) % (t_max + 1)) as u8)
                                .collect();
                            let acc0: Vec<u32> = (0..n)
                                .map(|i| {
                                    if exact {
                                        i as u32 % 4
                                    } else {
                                        (u32::MAX - 1000).wrapping_add(37 * i as u32)
                                    }
                                })
                                .collect();
                            let low0: Vec<u32> = (0..n)
                                .map(|i| {
                                    if exact {
                                        u32::from(rng(&mut seed)) % 4
                                    } else {
                                        3 * i as u32 + u32::from(rng(&mut seed))
                                    }
                                })
                                .collect();
                            for (with_lower, short) in
                                [(false, false), (true, false), (false, true)]
                            {
                                let (nb, nl) = (n / tile, n - n / tile);
                                let blocks = n / BLOCK;
                                let fused = packs
                                    && tile == 8
                                    && blocks >= 2
                                    && k % 2 == 0
                                    && k <= 14
                                    && bit % 8 == 0
                                    && !short;
                                let kp = if fused { blocks / 2 * PAIR } else { 0 };
                                // The row's words (exactly as many as its bits need; one byte
                                // short of the packed pairs' bytes with `short`), then noise.
                                let need = (bit as usize + nl * k as usize).div_ceil(32);
                                let len = if short {
                                    ((bit as usize / 8 + blocks / 2 * PAIR * k as usize / 8)
                                        .saturating_sub(1)
                                        / 4)
                                    .min(need)
                                } else {
                                    need
                                };
                                let noise: Vec<u32> = (0..need + 4)
                                    .map(|_| {
                                        (u32::from(rng(&mut seed)) * 0x0101_0101)
                                            ^ u32::from(rng(&mut seed))
                                    })
                                    .collect();
                                let mut words = noise.clone();
                                let mut acc = acc0.clone();
                                let mut low = low0.clone();
                                let mut bnd = std::vec![7u32; nb + 20];
                                let mut local = std::vec![9u32; nl + 20];
                                // SAFETY: the CPU's best kernel and its `vbmi` answer.
                                let got = unsafe {
                                    tiled_row_with::<u8, u32, 1>(
                                        Kernel::best(),
                                        vbmi(),
                                        &t,
                                        with_lower.then_some(&mut low[..]),
                                        &mut acc,
                                        tile,
                                        &mut bnd[..nb],
                                        &mut local[..nl],
                                        [(core::ptr::null(), 0); 2],
                                        Some(PackTo {
                                            words: &mut words[..len],
                                            bit,
                                            k,
                                            exact,
                                        }),
                                    )
                                };
                                let what = (tile, n, k, bit, pattern, exact, with_lower, short);
                                if Kernel::best() != Kernel::Avx512Vnni
                                    && !(Kernel::best() == Kernel::Avx2 && tile == 8)
                                {
                                    assert_eq!(got, None, "{what:?}");
                                    assert_eq!(words, noise, "{what:?}");
                                    continue;
                                }
                                let mut want_acc = acc0.clone();
                                let mut want_low = low0.clone();
                                let (want_b, want_l) = tiled_reference(
                                    &t,
                                    with_lower.then_some(&mut want_low[..]),
                                    &mut want_acc,
                                    tile,
                                );
                                assert_eq!(got, Some((nb, nl, kp)), "{what:?}");
                                packed_rows += usize::from(kp > 0);
                                assert_eq!(acc, want_acc, "{what:?}");
                                if with_lower {
                                    assert_eq!(low, want_low, "{what:?}");
                                }
                                assert_eq!(bnd[..nb], want_b[..], "{what:?}");
                                assert!(local[..kp].iter().all(|&v| v == 9), "{what:?}");
                                assert_eq!(local[kp..nl], want_l[kp..], "{what:?}");
                                assert!(local[nl..].iter().all(|&v| v == 9), "{what:?}");
                                let mut want = noise.clone();
                                for (i, &f) in want_l.iter().take(kp).enumerate() {
                                    let at = bit + i as u64 * u64::from(k);
                                    let v = u64::from(f & ((1 << k) - 1));
                                    assert!(crate::layouts::packed::write_bits(
                                        &mut want, at, k, v
                                    ));
                                }
                                assert_eq!(words, want, "{what:?}");
                            }
                        }
                    }
                }
            }
        }
        // The packing kernel ran wherever the CPU has it.
        assert_eq!(packed_rows > 0, packs);
    }

    /// The portable row (the reference): running sum plus the entry above.
    fn reference(t: &[u8], above: Option<&[u32]>, out: &mut [u32]) {
        let mut r = 0u32;
        for (i, (o, &t)) in out.iter_mut().zip(t).enumerate() {
            r = r.wrapping_add(u32::from(t));
            *o = r.wrapping_add(above.map_or(0, |a| a[i]));
        }
    }

    fn rng(seed: &mut u64) -> u8 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 24) as u8
    }

    /// Every kernel this CPU runs (under Miri: the widest the build enables), every width up to
    /// 4 blocks and a tail, texels all 0, all 255, a ramp and random, rows above with large
    /// entries (near u32::MAX, as a width-proved table can hold): separate, in place, in place
    /// with a copy (by plain stores, and by non-temporal ones into a copy on a cache line, one
    /// 16 bytes past it and one 4 bytes off it, which falls back to plain stores; nothing
    /// written around the row), and first row, against the reference; each row 0 to 7 entries
    /// past a cache line, so that every head `row_u8_u32` takes before 32 bytes (and a head it
    /// declines for the non-temporal copy) runs. Then the same through the dispatching entry
    /// points. Every case with heads and without ([`takes_heads`]: a CPU takes one form). Under
    /// Miri only the ramp and the random texels (117 of the 128 pairings of a head with a tail
    /// length; the four patterns took each of CI's Miri passes 1.5x as long), with heads.
    #[test]
    fn rows_equal_the_portable_rows() {
        const MAX: usize = 4 * BLOCK + 7;
        /// A row or copy target on a cache line.
        #[repr(align(64))]
        #[derive(Clone, Copy)]
        struct Line([u32; MAX + 8]);
        let mut seed = 0x9e37_79b9_7f4a_7c15;
        let mut ran = 0;
        // With and without heads ([`takes_heads`]); under Miri with them (the kernel from a
        // head's running sum).
        let heads: &[bool] = if cfg!(miri) { &[true] } else { &[true, false] };
        let kernels = Kernel::ALL.into_iter().filter(|k| k.available());
        for (kernel, heads) in kernels.flat_map(|k| heads.iter().map(move |&h| (k, h))) {
            ran += 1;
            set_heads(Some(heads));
            assert_eq!(takes_heads(), heads, "the test's form");
            for w in 0..=MAX {
                for pattern in if cfg!(miri) { 2..4 } else { 0..4 } {
                    let mut t = [0u8; MAX];
                    for (i, t) in t.iter_mut().enumerate() {
                        *t = match pattern {
                            0 => 0,
                            1 => 255,
                            2 => (i % 256) as u8,
                            _ => rng(&mut seed),
                        };
                    }
                    let t = &t[..w];
                    let base = u32::MAX - 255 * 1024;
                    let mut above = [0u32; MAX];
                    for (i, a) in above.iter_mut().enumerate() {
                        *a = base + 255 * i as u32;
                    }
                    let above = &above[..w];
                    // The row `shift` entries past a cache line: over the widths and
                    // patterns, every head (the entries before 32 bytes, `row_u8_u32`) from 0
                    // to 7 with every length of the tail after the kernel's blocks (0 to 15).
                    let shift = (w + pattern + 3 * (w / 16)) % 8;
                    for a in [None, Some(above)] {
                        let what =
                            |how: &str| (kernel.name(), heads, w, pattern, a.is_some(), how.len());
                        let mut want = [0u32; MAX];
                        reference(t, a, &mut want[..w]);
                        // Separate rows.
                        let mut got = Line([7u32; MAX + 8]);
                        let mode = if a.is_some() {
                            Above::Slice
                        } else {
                            Above::Zero
                        };
                        row_u8_u32(
                            kernel,
                            t,
                            a.unwrap_or(&[]),
                            &mut got.0[shift..shift + w],
                            mode,
                            None,
                            false,
                        );
                        let row = shift..shift + w;
                        // Only the row written: 7 before and after it.
                        let untouched = |l: &Line| {
                            l.0[..shift]
                                .iter()
                                .chain(&l.0[shift + w..])
                                .all(|&v| v == 7)
                        };
                        assert_eq!(
                            got.0[row.clone()],
                            want[..w],
                            "{:?} {shift}",
                            what("separate")
                        );
                        assert!(untouched(&got), "wrote around the row");
                        // In place, without and with a copy (each row on a line, `shift` in).
                        let mut inplace = Line([7u32; MAX + 8]);
                        if let Some(a) = a {
                            inplace.0[row.clone()].copy_from_slice(a);
                        }
                        let mode = if a.is_some() {
                            Above::InPlace
                        } else {
                            Above::Zero
                        };
                        let mut again = inplace;
                        row_u8_u32(
                            kernel,
                            t,
                            &[],
                            &mut inplace.0[row.clone()],
                            mode,
                            None,
                            false,
                        );
                        assert_eq!(inplace.0[row.clone()], want[..w], "{:?}", what("in place"));
                        assert!(untouched(&inplace), "wrote around the row in place");
                        let mut copy = [9u32; MAX];
                        let c = Some(&mut copy[..w]);
                        let back = again;
                        row_u8_u32(kernel, t, &[], &mut again.0[row.clone()], mode, c, false);
                        assert_eq!(
                            again.0[row.clone()],
                            want[..w],
                            "{:?}",
                            what("in place + copy")
                        );
                        assert!(untouched(&again), "wrote around the row in place");
                        assert_eq!(copy[..w], want[..w], "{:?}", what("the copy"));
                        assert!(copy[w..].iter().all(|&v| v == 9), "copied past the row");
                        // The copy by non-temporal stores: into a copy on 16 bytes (the stores
                        // stream, the head and the tail's whole 4 entries too; a head that
                        // would move them off 16 bytes is not taken), 16 bytes past a line,
                        // and one 4 bytes off (they fall back to plain ones); nothing before
                        // or past the row written.
                        for off in [0, 4, 1] {
                            let mut again = back;
                            let mut line = Line([9; MAX + 8]);
                            let c = Some(&mut line.0[off..off + w]);
                            row_u8_u32(kernel, t, &[], &mut again.0[row.clone()], mode, c, true);
                            let copy = &line.0[off..off + w];
                            let how = what("streamed");
                            assert_eq!(again.0[row.clone()], want[..w], "{how:?} {off} {shift}");
                            assert!(untouched(&again), "wrote around the row, streamed");
                            assert_eq!(copy, &want[..w], "{how:?} copy {off} {shift}");
                            assert!(line.0[..off].iter().all(|&v| v == 9), "before the row");
                            assert!(line.0[off + w..].iter().all(|&v| v == 9), "past the row");
                        }
                        // The dispatching entry points (the best kernel).
                        let what = |how: &str| {
                            (
                                Kernel::for_rows().name(),
                                heads,
                                w,
                                pattern,
                                a.is_some(),
                                how.len(),
                            )
                        };
                        let mut got = [7u32; MAX];
                        assert!(build_row::<u8, u32, 1>(t, a, &mut got[..w]));
                        assert_eq!(got[..w], want[..w], "{:?}", what("build_row"));
                        let mut inplace = [7u32; MAX];
                        if let Some(a) = a {
                            inplace[..w].copy_from_slice(a);
                        }
                        let first = a.is_none();
                        assert!(build_row_in_place::<u8, u32, 1>(
                            t,
                            &mut inplace[..w],
                            first,
                            None,
                            false
                        ));
                        assert_eq!(inplace[..w], want[..w], "{:?}", what("build_row_in_place"));
                    }
                }
            }
        }
        set_heads(None);
        assert!(ran >= 1);
    }

    /// No lines to ask for (the even pace: the hints move no output).
    const NO_HINTS: (Ahead, Pace) = ([(core::ptr::null(), 0); 2], Pace::Even);

    /// Each pace asks for every line of both slices once, in order, the last by the row's
    /// last group: [`Pace::Even`] by the end of the group ending at block `e` the `ceil(L e /
    /// B)` lines due there (one more at most, from the rounded-up rate), [`Pace::Early`] twice
    /// as many (all of them by the group that holds the middle block). `L` lines (slices of
    /// `16 L - 3` words: the last line partial), `B` blocks, groups of [`Prefetch::GROUP`]
    /// blocks as [`Prefetch::for_blocks`] asks. Records the schedule: nothing is asked for.
    #[test]
    fn prefetch_asks_every_line_once_at_its_pace() {
        let bases = [
            core::ptr::null::<u32>().wrapping_add(1 << 20),
            core::ptr::null::<u32>().wrapping_add(1 << 24),
        ];
        // Under Miri (about 15 s per instruction set with all of them: no unsafe code here, so
        // only the ends), blocks 1, 17 and 256 and three line counts.
        let (blocks_list, lines_list): (std::vec::Vec<usize>, &[usize]) = if cfg!(miri) {
            (std::vec![1, 17, 256], &[0, 5, 98])
        } else {
            ((1..=300).collect(), &[0, 1, 2, 5, 16, 25, 98, 130, 400])
        };
        for &blocks in &blocks_list {
            for &lines in lines_list {
                for pace in [Pace::Early, Pace::Even] {
                    let len = (16 * lines).saturating_sub(3);
                    let ahead: Ahead = [(bases[0], len), (bases[1], len / 2 + 1)];
                    let want = ahead.map(|(_, l)| l.div_ceil(16));
                    let mut p = Prefetch::at_pace(ahead, blocks, pace);
                    let mut got = [std::vec::Vec::new(), std::vec::Vec::new()];
                    let mut from = 0;
                    while from < blocks {
                        let end = (from + Prefetch::GROUP).min(blocks);
                        p.ask_with(end, |q| {
                            let r = usize::from(q.addr() >= bases[1].addr());
                            got[r].push((q.addr() - bases[r].addr()) / 64);
                        });
                        for r in 0..2 {
                            let l = want[r];
                            let scale = if pace == Pace::Even { 1 } else { 2 };
                            let due = (scale * l * end).div_ceil(blocks).min(l);
                            let what =
                                std::format!("{pace:?}, {blocks} blocks, {l} lines, end {end}");
                            assert!(got[r].len() >= due, "{what}: {} asked", got[r].len());
                            assert!(got[r].len() <= (due + 1).min(l), "{what}: {}", got[r].len());
                        }
                        from = end;
                    }
                    for r in 0..2 {
                        let all: std::vec::Vec<usize> = (0..want[r]).collect();
                        assert_eq!(got[r], all, "{pace:?}, {blocks} blocks, slice {r}");
                    }
                }
            }
        }
    }

    /// `band_row` and `band_flush` against an independent reference, under each kernel this
    /// CPU runs: rows of 0 to 70 texels and a few long ones, column sums that start dirty (up
    /// to 6 rows of the largest texel, the most a tile row of 8 leaves before its last row),
    /// texels all 255, random, or random below the largest whose local sums fit `k` bits. The
    /// column sums after the row (in `acc0` from `column_sums_at`), the boundaries (the running
    /// sum of the tiles' column totals), the local sums (the prefix of the column sums inside each
    /// tile) and their counts; with a packing target of 14 bits from bits 0, 8, 24, of 8, 10
    /// and 12 bits from bits 16, 0 and 8 and of 14 bits from bit 3 (not byte-aligned: nothing
    /// packed). Packed: with AVX-512 VBMI and exact fields, the pairs of blocks' in the row
    /// step (`band512::row_packed`), then whole steps of 16 of the rest from 16 bits
    /// (`pack256::even`); `kp` exactly that, the fields as `write_bits` writes them, the words
    /// past them untouched. Exact (no mask) for the small texels and for 14 bits except from
    /// bit 8; masked for the others, whose local sums pass `2^k` (so a missing mask fails).
    /// Then `band_flush` gives the level-0 accumulator of the column sums (local sums,
    /// boundaries at multiples of 8).
    #[test]
    fn band_rows_equal_the_reference() {
        // Each kernel this CPU runs: with AVX-512BW and VBMI the local sums of whole pairs of
        // blocks are packed in the row step (band512), with AVX2 alone from 16-bit values.
        for kernel in [Kernel::Avx512Vnni, Kernel::Avx2, Kernel::Sse2] {
            if kernel.available() {
                kernel.cap(band_rows_equal_the_reference_at_best);
            }
        }
    }

    fn band_rows_equal_the_reference_at_best() {
        extern crate std;
        use std::vec::Vec;
        let avx2 = matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni);
        let vbmi = Kernel::best() == Kernel::Avx512Vnni && vbmi();
        let sizes = band_sizes();
        let mut seed = 0x1234_5678_9abc_def0u64;
        let mut ran = 0;
        for &n in &sizes {
            // The texels and column sums: all at their largest (255, 6 x 255), random, or
            // random below the largest texel whose tile's local sums fit k bits (49 m < 2^k):
            // then every width is exact.
            for data in 0..3 {
                let widths = [
                    (0, 0),
                    (14, 0),
                    (14, 8),
                    (14, 24),
                    (10, 0),
                    (14, 3),
                    (8, 16),
                    (12, 8),
                ];
                for (k, bit) in widths {
                    if cfg!(miri) && matches!(k, 8 | 10 | 12) {
                        continue;
                    }
                    let small = data == 2 && k > 0;
                    let top = if small {
                        (((1u32 << k) - 1) / 49).min(255) as u8
                    } else {
                        255
                    };
                    let texel = |seed: &mut u64| match data {
                        0 => 255,
                        1 => rng(seed),
                        _ => (u16::from(rng(seed)) % (u16::from(top) + 1)) as u8,
                    };
                    let t: Vec<u8> = (0..n).map(|_| texel(&mut seed)).collect();
                    let cs0: Vec<u16> = (0..n).map(|_| u16::from(texel(&mut seed)) * 6).collect();
                    // acc0's storage: the column sums from column_sums_at, the rest dirty.
                    let (_, mut acc0) = band_storage(&cs0);
                    // The reference.
                    let cs: Vec<u16> = cs0.iter().zip(&t).map(|(c, &x)| c + u16::from(x)).collect();
                    let (mut want_b, mut want_l, mut form) = (Vec::new(), Vec::new(), Vec::new());
                    let (mut run, mut inner) = (0u32, 0u32);
                    for (i, &c) in cs.iter().enumerate() {
                        inner += u32::from(c);
                        if (i + 1) % 8 == 0 {
                            run += inner;
                            inner = 0;
                            want_b.push(run);
                            form.push(run);
                        } else {
                            want_l.push(inner);
                            form.push(inner);
                        }
                    }
                    let (nb, nl) = (n / 8, n - n / 8);
                    let mut bnd = std::vec![0xdead_beefu32; nb + 1];
                    let mut local = std::vec![0xdead_beefu32; nl + 1];
                    let noise: Vec<u32> = (0..nl * 14 / 32 + 4)
                        .map(|i| 0x9e37_79b9u32.rotate_left(i as u32))
                        .collect();
                    let mut words = noise.clone();
                    // Exact (no mask) where the local sums fit k bits (at most 7 * 7 * 255 =
                    // 12,495 < 2^14), and once with the mask for k = 14 too.
                    let pack = (k > 0).then(|| PackTo {
                        words: &mut words,
                        bit,
                        k,
                        exact: small || (k == 14 && bit != 8),
                    });
                    let got = band_row::<u8, u32, 1>(
                        &t,
                        &mut acc0,
                        &mut bnd[..nb],
                        &mut local[..nl],
                        ([(core::ptr::null(), 0); 2], Pace::Early),
                        pack,
                    );
                    if !avx2 {
                        assert_eq!(got, None);
                        continue;
                    }
                    ran += 1;
                    let (kb, kl, kp) = got.unwrap_or_else(|| panic!("None: n {n} k {k} bit {bit}"));
                    // Packed: the row step's pairs of blocks (28 fields each, exact fields on
                    // AVX-512 VBMI), then whole steps of 16 of the rest.
                    let packs = k > 0 && bit % 8 == 0;
                    let fused = if packs && vbmi && (small || (k == 14 && bit != 8)) {
                        PAIR * (n / 32)
                    } else {
                        0
                    };
                    let want_kp = if packs {
                        fused + (nl - fused) / 16 * 16
                    } else {
                        0
                    };
                    assert_eq!((kb, kl, kp), (nb, nl, want_kp), "n {n} k {k} bit {bit}");
                    assert_eq!(column_sums_in(&acc0), cs, "column sums, n {n}");
                    assert_eq!(&bnd[..nb], &want_b[..], "boundaries, n {n}");
                    assert_eq!(bnd[nb], 0xdead_beef);
                    assert_eq!(
                        &local[kp..nl],
                        &want_l[kp..],
                        "local sums, n {n} k {k} bit {bit}"
                    );
                    assert_eq!(local[nl], 0xdead_beef);
                    let mut want_w = noise.clone();
                    for (i, &f) in want_l.iter().take(kp).enumerate() {
                        let at = bit + i as u64 * u64::from(k);
                        assert!(crate::layouts::packed::write_bits(
                            &mut want_w,
                            at,
                            k,
                            u64::from(f) & ((1 << k) - 1)
                        ));
                    }
                    assert_eq!(words, want_w, "packed, n {n} k {k} bit {bit}");
                    assert!(band_flush::<u32, 1>(&mut acc0));
                    assert_eq!(acc0, form, "flush, n {n}");
                }
            }
        }
        assert_eq!(ran > 0, avx2);
    }

    /// `band_row` with packing targets around the sizes each part needs, 92 columns (2 pairs of
    /// blocks and 28 columns: 81 local sums), 14-bit exact fields from bit 0. With AVX-512
    /// VBMI the pairs' 56 fields (98 bytes) are packed in the row step when they fit, then one
    /// step of 16 (28 bytes more) when it fits too; without, or when the pairs' bytes do not
    /// fit, the AVX2 step's 5 steps of 16 (140 bytes) or nothing. `kp` is exactly what fits,
    /// the packed fields are the reference's, and no byte past them changes.
    #[test]
    fn band_row_packs_only_what_fits() {
        extern crate std;
        use std::vec::Vec;
        for kernel in [Kernel::Avx512Vnni, Kernel::Avx2] {
            if !kernel.available() {
                continue;
            }
            kernel.cap(|| {
                let fused = Kernel::best() == Kernel::Avx512Vnni && vbmi();
                let (n, k) = (92usize, 14u32);
                let (nb, nl) = (n / 8, n - n / 8);
                let mut seed = 0x5eed_0f0f_1234_abcdu64;
                let t: Vec<u8> = (0..n).map(|_| rng(&mut seed)).collect();
                let cs0: Vec<u16> = (0..n).map(|_| u16::from(rng(&mut seed)) * 6).collect();
                let (mut want_l, mut inner) = (Vec::new(), 0u32);
                for (i, (&c, &x)) in cs0.iter().zip(&t).enumerate() {
                    inner += u32::from(c) + u32::from(x);
                    if (i + 1) % 8 == 0 {
                        inner = 0;
                    } else {
                        want_l.push(inner);
                    }
                }
                // Words 24 to 36: 96 to 144 bytes.
                for len in [24usize, 25, 31, 32, 34, 35, 36] {
                    let room = 4 * len;
                    let want_kp = match (fused && room >= 98, fused) {
                        (true, _) if room >= 98 + 28 => 72,
                        (true, _) => 56,
                        _ if room >= 140 => 80,
                        _ => 0,
                    };
                    let (_, mut acc0) = band_storage(&cs0);
                    let mut bnd = std::vec![0u32; nb];
                    let mut local = std::vec![0u32; nl];
                    let noise: Vec<u32> = (0..len as u32)
                        .map(|i| 0x9e37_79b9u32.rotate_left(i))
                        .collect();
                    let mut words = noise.clone();
                    let got = band_row::<u8, u32, 1>(
                        &t,
                        &mut acc0,
                        &mut bnd,
                        &mut local,
                        ([(core::ptr::null(), 0); 2], Pace::Early),
                        Some(PackTo {
                            words: &mut words,
                            bit: 0,
                            k,
                            exact: true,
                        }),
                    );
                    assert_eq!(got, Some((nb, nl, want_kp)), "{len} words, {kernel:?}");
                    let mut want_w = noise.clone();
                    for (i, &f) in want_l.iter().take(want_kp).enumerate() {
                        let at = i as u64 * u64::from(k);
                        assert!(crate::layouts::packed::write_bits(
                            &mut want_w,
                            at,
                            k,
                            u64::from(f)
                        ));
                    }
                    assert_eq!(words, want_w, "{len} words, {kernel:?}");
                    assert_eq!(
                        &local[want_kp..],
                        &want_l[want_kp..],
                        "{len} words, {kernel:?}"
                    );
                }
            });
        }
    }

    /// [`band_rows`] against [`band_row`] on each row in turn: the same packed words (every
    /// bit, from byte offsets 0, 1 and 3 of a word; the words around the rows untouched), the
    /// same boundaries, the same column sums after the run; runs of 2, 3 and 7 rows, fields of
    /// 8 to 14 bits (texels bounded so that every local sum is below `2^k`); rows of 128, 256
    /// and 384 take the AVX2 run under an AVX2 cap (the others the per-row path). Where it does
    /// not apply (SSE2; with AVX-512 VBMI a row not a whole number of pairs, else a row not a
    /// multiple of 128; inexact fields; too few words) it returns `false` and writes nothing.
    #[test]
    fn band_rows_equal_band_row() {
        extern crate std;
        use std::vec::Vec;
        fn check(n: usize, r: usize, k: u32, skip: usize, seed: &mut u64) {
            let (pairs, nb, nl) = (n / 32, n / 8, n - n / 8);
            // Local sums at most 7 columns of r rows of texels up to `top`: below 2^k.
            let top = (((1u32 << k) - 1) / (7 * r as u32)).min(255) as u8;
            let rows: Vec<Vec<u8>> = (0..r)
                .map(|_| {
                    (0..n)
                        .map(|_| (u16::from(rng(seed)) % (u16::from(top) + 1)) as u8)
                        .collect()
                })
                .collect();
            let refs: Vec<&[u8]> = rows.iter().map(|v| v.as_slice()).collect();
            // A row's bits (for a whole number of pairs, 8 times the kernel's stride).
            let (stride, row_bits) = (7 * k as usize / 2 * pairs, nl * k as usize);
            let len = (8 * skip + r * row_bits).div_ceil(32) + 2;
            let noise: Vec<u32> = (0..len as u32)
                .map(|i| 0x9e37_79b9u32.rotate_left(i))
                .collect();
            let bit = 8 * skip as u64;
            // The reference: band_row on each row, its fields from bit + j row_bits.
            let (_, mut acc_ref) = band_storage(&std::vec![0u16; n]);
            let mut want_w = noise.clone();
            let mut want_b = std::vec![0u32; r * nb];
            for (j, row) in rows.iter().enumerate() {
                let mut local = std::vec![0u32; nl];
                let at = bit + (j * row_bits) as u64;
                let (w0, b0) = ((at / 32) as usize, at % 32);
                let got = band_row::<u8, u32, 1>(
                    row,
                    &mut acc_ref,
                    &mut want_b[j * nb..(j + 1) * nb],
                    &mut local,
                    ([(core::ptr::null(), 0); 2], Pace::Early),
                    Some(PackTo {
                        words: &mut want_w[w0..],
                        bit: b0,
                        k,
                        exact: true,
                    }),
                )
                .unwrap();
                assert_eq!((got.0, got.1), (nb, nl));
                // Whatever band_row left unpacked, field by field.
                for (i, &f) in local.iter().enumerate().skip(got.2) {
                    let b = at + i as u64 * u64::from(k);
                    assert!(crate::layouts::packed::write_bits(
                        &mut want_w,
                        b,
                        k,
                        u64::from(f)
                    ));
                }
            }
            let applies = band_rows_apply::<u8, u32, 1>(n, k, true);
            for exact in [true, false] {
                // Both paces (they move only the hints, never the output).
                let pace = if exact { Pace::Even } else { Pace::Early };
                let (halves, mut acc) = band_storage(&std::vec![0u16; n]);
                let mut words = noise.clone();
                let mut bnd = std::vec![0u32; r * nb];
                let hint = Some((words.as_ptr(), words.len()));
                let out = PackTo {
                    words: &mut words,
                    bit,
                    k,
                    exact,
                };
                let ran = band_rows::<u8, u32, 1>(&refs, &mut acc, &mut bnd, (hint, pace), out);
                let what = std::format!("n {n}, {r} rows, k {k}, skip {skip}, exact {exact}");
                assert_eq!(ran, applies && exact, "{what}");
                if ran {
                    assert_eq!(words, want_w, "{what}");
                    assert_eq!(bnd, want_b, "{what}");
                    // The column sums; the rest of the storage is the AVX2 run's scratch (its
                    // 16-bit local sums), untouched where the kernel packs in its pass.
                    assert_eq!(column_sums_in(&acc), column_sums_in(&acc_ref), "{what}");
                    if vbmi() && Kernel::best() == Kernel::Avx512Vnni {
                        let (after, at) = (halves_of(&acc), column_sums_at(acc.as_ptr(), n));
                        assert_eq!(after[..at], halves[..at], "{what}");
                        assert_eq!(after[at + n..], halves[at + n..], "{what}");
                    }
                } else {
                    assert_eq!(words, noise, "{what}");
                    assert!(bnd.iter().all(|&b| b == 0), "{what}");
                }
            }
            // Too few words for the run: refused, nothing written.
            if applies {
                let (_, mut acc) = band_storage(&std::vec![0u16; n]);
                let short = (skip + r * stride).div_ceil(4) - 1;
                let mut words = noise[..short].to_vec();
                let mut bnd = std::vec![0u32; r * nb];
                let out = PackTo {
                    words: &mut words,
                    bit,
                    k,
                    exact: true,
                };
                assert!(!band_rows::<u8, u32, 1>(
                    &refs,
                    &mut acc,
                    &mut bnd,
                    (None, Pace::Early),
                    out
                ));
                assert_eq!(words, noise[..short]);
            }
        }
        let sizes: &[usize] = if cfg!(miri) {
            &[32, 128]
        } else {
            &[32, 64, 96, 128, 256, 384, 40]
        };
        let runs: &[usize] = if cfg!(miri) { &[2] } else { &[2, 3, 7] };
        let mut seed = 0x0b5e_55ed_2718_2818u64;
        // (band_row, the reference, needs AVX2.)
        for kernel in [Kernel::Avx2, Kernel::Avx512Vnni]
            .into_iter()
            .filter(|k| k.available())
        {
            kernel.cap(|| {
                for &n in sizes {
                    for &r in runs {
                        for k in [8u32, 10, 12, 14] {
                            for skip in [0usize, 1, 3] {
                                check(n, r, k, skip, &mut seed);
                            }
                        }
                    }
                }
            });
        }
    }

    /// The column sums' place (`column_sums_at`) wherever acc_0's storage starts: from each of 8
    /// word offsets into a larger allocation (every 32-byte alignment of the storage: the even
    /// shifts of 0 to 14 `u16` for even `n`, the odd ones of 1 to 15 for odd `n`), 4 band rows
    /// (one by one, or as one `band_rows` run where it applies, which must run then), then
    /// either `band_flush`, whose accumulator must equal the reference form of the rows' column
    /// sums (local sums inside each tile, the running sum at each boundary), or a row that ends
    /// the tile row (`band_end_row`, with packing targets of 23 and 32 bits, which AVX-512 VBMI
    /// fills for whole chunks of 256 columns), whose level above, boundaries and local sums
    /// (packed or not) must equal the level above plus the form of all 5 rows, with the column
    /// sums cleared; the run's packed words and boundaries must equal those from offset 0.
    /// Rows of 100 (below 128: the column sums at `u16` `n`), 128, 201, 256 and 1,000 (129
    /// and 256 under Miri).
    #[test]
    fn band_form_wherever_the_storage_starts() {
        extern crate std;
        use std::vec::Vec;
        let sizes: &[usize] = if cfg!(miri) {
            &[129, 256]
        } else {
            &[100, 128, 201, 256, 1000]
        };
        // The reference form of rows' column sums: the local sums inside each tile, the running
        // sum at each boundary.
        let form_of = |rows: &[&[u8]], n: usize| {
            let (mut form, mut run, mut inner) = (Vec::new(), 0u32, 0u32);
            for i in 0..n {
                inner += rows.iter().map(|row| u32::from(row[i])).sum::<u32>();
                if (i + 1) % 8 == 0 {
                    run += inner;
                    inner = 0;
                    form.push(run);
                } else {
                    form.push(inner);
                }
            }
            form
        };
        let mut seed = 0x51a7_ed0f_f5e7_0001u64;
        for kernel in [Kernel::Avx2, Kernel::Avx512Vnni]
            .into_iter()
            .filter(|k| k.available())
        {
            kernel.cap(|| {
                for &n in sizes {
                    let (nb, nl, r) = (n / 8, n - n / 8, 4);
                    let rows: Vec<Vec<u8>> = (0..=r)
                        .map(|_| (0..n).map(|_| rng(&mut seed)).collect())
                        .collect();
                    let refs: Vec<&[u8]> = rows.iter().map(|v| v.as_slice()).collect();
                    let form = form_of(&refs[..r], n);
                    // The end row's reference: the level above plus the form of all r + 1 rows,
                    // split into boundaries and local sums.
                    let acc1: Vec<u32> =
                        (0..n as u32).map(|i| i.wrapping_mul(0x9e37_79b9)).collect();
                    let want_acc: Vec<u32> = acc1
                        .iter()
                        .zip(form_of(&refs, n))
                        .map(|(a, f)| a.wrapping_add(f))
                        .collect();
                    let want_b: Vec<u32> = want_acc.iter().skip(7).step_by(8).copied().collect();
                    let want_l: Vec<u32> = (0..n)
                        .filter(|i| (i + 1) % 8 != 0)
                        .map(|i| want_acc[i])
                        .collect();
                    let (kl, kb) = (23u32, 32u32);
                    let noise = |len: usize, salt: u32| -> Vec<u32> {
                        (0..len as u32)
                            .map(|i| 0x9e37_79b9u32.rotate_left(i ^ salt))
                            .collect()
                    };
                    let (wl0, wb0) = (noise((nl * 23).div_ceil(32) + 1, 5), noise(nb + 1, 9));
                    let mut first = None;
                    for o in 0..8 {
                        let what = std::format!("n {n}, offset {o}, {kernel:?}");
                        // Band rows, then the flush.
                        let mut big = std::vec![0u32; n + 8];
                        let acc0 = &mut big[o..o + n];
                        // The column sums on 32 bytes from n = 128 on, above the local sums'
                        // room.
                        let at = column_sums_at(acc0.as_ptr(), n);
                        if n >= 128 {
                            let bytes = acc0.as_ptr() as usize + 2 * at;
                            assert!(bytes.is_multiple_of(32) && at >= n - 15, "{what}");
                        } else {
                            assert_eq!(at, n, "{what}");
                        }
                        assert!(at <= n && at > n - n / 8, "{what}");
                        let (mut bnd, mut local) = (std::vec![0u32; nb], std::vec![0u32; nl]);
                        for row in &refs[..r] {
                            let got = band_row::<u8, u32, 1>(
                                row, acc0, &mut bnd, &mut local, NO_HINTS, None,
                            );
                            assert!(got.is_some(), "{what}");
                        }
                        assert!(band_flush::<u32, 1>(acc0), "{what}");
                        assert_eq!(acc0, &form[..], "flushed, {what}");
                        // Band rows (a run where it applies), then the row that ends the tile row.
                        let mut big = std::vec![0u32; n + 8];
                        let acc0 = &mut big[o..o + n];
                        let mut words = std::vec![0u32; r * 7 * nl / 8 + 8];
                        let mut run_b = std::vec![0u32; r * nb];
                        let out = PackTo {
                            words: &mut words,
                            bit: 0,
                            k: 14,
                            exact: true,
                        };
                        let ran = band_rows::<u8, u32, 1>(
                            &refs[..r],
                            acc0,
                            &mut run_b,
                            (None, Pace::Even),
                            out,
                        );
                        assert_eq!(ran, band_rows_apply::<u8, u32, 1>(n, 14, true), "{what}");
                        if !ran {
                            for row in &refs[..r] {
                                let got = band_row::<u8, u32, 1>(
                                    row, acc0, &mut bnd, &mut local, NO_HINTS, None,
                                );
                                assert!(got.is_some(), "{what}");
                            }
                        }
                        let mut acc = acc1.clone();
                        let (mut bnd, mut local) = (std::vec![0u32; nb], std::vec![0u32; nl]);
                        let (mut wl, mut wb) = (wl0.clone(), wb0.clone());
                        let pack = EndPackTo {
                            local: (&mut wl, kl),
                            bnd: (&mut wb, kb),
                        };
                        let none = [(core::ptr::null(), 0); 2];
                        let got = band_end_row::<u8, u32, 1>(
                            &rows[r],
                            acc0,
                            &mut acc,
                            &mut bnd,
                            &mut local,
                            (none, Pace::Early),
                            Some(pack),
                        );
                        // Packed in the pass: whole chunks of 256 columns with AVX-512 VBMI.
                        let chunks = if Kernel::best() == Kernel::Avx512Vnni && vbmi() {
                            n / 256
                        } else {
                            0
                        };
                        let (pl, pb) = (224 * chunks, 32 * chunks);
                        assert_eq!(got, Some((nb, nl, pl, pb)), "{what}");
                        assert_eq!(acc, want_acc, "level above, {what}");
                        assert_eq!(&bnd[pb..], &want_b[pb..], "boundaries, {what}");
                        assert_eq!(&local[pl..], &want_l[pl..], "local sums, {what}");
                        let packed_l = field_by_field(wl0.clone(), &want_l[..pl], kl);
                        assert_eq!(wl, packed_l, "packed local sums, {what}");
                        let packed_b = field_by_field(wb0.clone(), &want_b[..pb], kb);
                        assert_eq!(wb, packed_b, "packed boundaries, {what}");
                        assert!(column_sums_in(acc0).iter().all(|&c| c == 0), "{what}");
                        let this = (words, run_b);
                        match &first {
                            None => first = Some(this),
                            Some(f) => assert!(*f == this, "the run's words, {what}"),
                        }
                    }
                }
            });
        }
    }

    /// The row lengths of the band tests: 0 to 70 and 255, 256 and 1,000 (a few under Miri).
    fn band_sizes() -> std::vec::Vec<usize> {
        if cfg!(miri) {
            std::vec![0, 7, 16, 17, 40, 60, 112]
        } else {
            (0..=70).chain([255, 256, 1000]).collect()
        }
    }

    /// The packers' reference: each field's low `k` bits written one by one over `words`
    /// (field `i` at bit `i k`).
    fn field_by_field(mut words: std::vec::Vec<u32>, fields: &[u32], k: u32) -> std::vec::Vec<u32> {
        let m = if k == 32 { u32::MAX } else { (1 << k) - 1 };
        for (i, &f) in fields.iter().enumerate() {
            let at = i as u64 * u64::from(k);
            assert!(crate::layouts::packed::write_bits(
                &mut words,
                at,
                k,
                u64::from(f & m)
            ));
        }
        words
    }

    /// acc_0's storage in the band form for column sums `cs0` (`n` of them): its `u16`
    /// halves (dirty, the column sums from `column_sums_at` of the words' address) and the
    /// words that hold them.
    fn band_storage(cs0: &[u16]) -> (std::vec::Vec<u16>, std::vec::Vec<u32>) {
        let n = cs0.len();
        let mut words = std::vec![0u32; n];
        let mut halves: std::vec::Vec<u16> = (0..2 * n).map(|i| (i as u16) ^ 0x5a5a).collect();
        let at = column_sums_at(words.as_ptr(), n);
        halves[at..at + n].copy_from_slice(cs0);
        for (w, p) in words.iter_mut().zip(halves.chunks(2)) {
            *w = u32::from(p[0]) | u32::from(p[1]) << 16;
        }
        (halves, words)
    }

    /// The `u16` halves of `words`, in memory order.
    fn halves_of(words: &[u32]) -> std::vec::Vec<u16> {
        words
            .iter()
            .flat_map(|w| [*w as u16, (w >> 16) as u16])
            .collect()
    }

    /// The column sums acc_0's storage `words` holds in the band form (from `column_sums_at`).
    fn column_sums_in(words: &[u32]) -> std::vec::Vec<u16> {
        let (n, at) = (words.len(), column_sums_at(words.as_ptr(), words.len()));
        halves_of(words)[at..at + n].to_vec()
    }

    /// `band_end_row` against an independent reference: rows of 0 to 70 texels and 255, 256, 512,
    /// 537, 968 and 1,000 (a few under Miri, 280 and 536 the longest), saturated and random texels,
    /// dirty column sums of up to 7 rows of 255 (with the row: a tile row of 8) and of 31 rows of
    /// 255 (a tile row of 32: a tile's sum of 65,280, at the 16-bit bound of the prefix sums; not
    /// under Miri without packing), a dirty level above (values near 2^32: the adds wrap). Checked:
    /// the level above plus the column sums' form, its split into boundaries and local sums
    /// (nothing written past them), the column sums cleared, the lower half of acc_0's storage
    /// untouched; `None` without AVX2.
    ///
    /// Under each kernel this CPU runs, and each way of packing: none (the fields in `local`
    /// and `bnd`), and both component rows packed from their first word, with widths (local,
    /// boundaries) of (21, 28), (11, 32), (23, 32), (32, 11) and (16, 17), (10, 28) (no
    /// packer: nothing packed) and a local row one chunk and 5 words long. With AVX-512BW the
    /// whole chunks of 256 columns that both rows hold are packed in the pass
    /// (`band512::end_row_packed`) and their fields not written to `local` and `bnd`; the
    /// rest, or everything on other kernels, is left there from the counts returned. The
    /// packed words equal each field's low `k` bits written one by one over noise, the words
    /// past the chunks untouched.
    #[test]
    fn band_end_row_equals_the_reference() {
        for kernel in [Kernel::Avx512Vnni, Kernel::Avx2, Kernel::Sse2] {
            if kernel.available() {
                kernel.cap(band_end_row_equals_the_reference_at_best);
            }
        }
    }

    fn band_end_row_equals_the_reference_at_best() {
        extern crate std;
        use std::vec::Vec;
        let avx2 = matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni);
        let fused = Kernel::best() == Kernel::Avx512Vnni && vbmi();
        let mut sizes = band_sizes();
        if !cfg!(miri) {
            sizes.extend([512, 512 + 16 + 9, 3 * 256 + 200]);
        } else {
            sizes.extend([256 + 24, 512 + 24]);
        }
        // ((k local, k boundaries), the local row's words if fewer than its fields need):
        // None leaves every field in the scratch; 10 bits has no packer (nothing packed); the
        // last row holds one chunk and 5 words (one chunk packed).
        type Widths = (Option<(u32, u32)>, Option<usize>);
        let widths: &[Widths] = if cfg!(miri) {
            &[(None, None), (Some((21, 28)), None)]
        } else {
            &[
                (None, None),
                (Some((21, 28)), None),
                (Some((11, 32)), None),
                (Some((23, 32)), None),
                (Some((32, 11)), None),
                (Some((16, 17)), None),
                (Some((10, 28)), None),
                (Some((21, 28)), Some(7 * 21 + 5)),
            ]
        };
        let mut seed = 0x0fed_cba9_8765_4321u64;
        let (mut ran, mut packed_any) = (0, false);
        for &n in &sizes {
            // Saturated texels over 7 rows of them (a tile row of 8), over 31 (a tile row of 32:
            // a tile's sum of 65,280, at the band form's 16-bit bound), random over 7.
            for ((full, rows), &(w, short)) in [(true, 7), (true, 31), (false, 7)]
                .into_iter()
                .flat_map(|f| widths.iter().map(move |w| (f, w)))
            {
                if cfg!(miri) && rows == 31 && w.is_none() {
                    continue;
                }
                let mut next = || if full { 255 } else { rng(&mut seed) };
                let t: Vec<u8> = (0..n).map(|_| next()).collect();
                let cs0: Vec<u16> = (0..n).map(|_| u16::from(next()) * rows).collect();
                let acc1: Vec<u32> = (0..n)
                    .map(|_| {
                        u32::from(next())
                            .wrapping_mul(0x0101_0101)
                            .wrapping_add(0xff00_0000)
                    })
                    .collect();
                let (halves, mut acc0) = band_storage(&cs0);
                // The reference: the level above plus the form of the column sums with the row.
                let (mut want_acc, mut want_b, mut want_l) = (acc1.clone(), Vec::new(), Vec::new());
                let (mut run, mut inner) = (0u32, 0u32);
                for i in 0..n {
                    inner += u32::from(cs0[i]) + u32::from(t[i]);
                    let form = if (i + 1) % 8 == 0 {
                        run += inner;
                        inner = 0;
                        run
                    } else {
                        inner
                    };
                    want_acc[i] = want_acc[i].wrapping_add(form);
                    if (i + 1) % 8 == 0 {
                        want_b.push(want_acc[i]);
                    } else {
                        want_l.push(want_acc[i]);
                    }
                }
                let (nb, nl) = (n / 8, n - n / 8);
                let mut acc = acc1.clone();
                let mut bnd = std::vec![0xdead_beefu32; nb + 1];
                let mut local = std::vec![0xdead_beefu32; nl + 1];
                // The component rows (as many words as the fields need) over noise.
                let noise = |len: usize, salt: u32| -> Vec<u32> {
                    (0..len as u32)
                        .map(|i| i.wrapping_mul(0x9e37_79b9) ^ salt)
                        .collect()
                };
                let (kl, kb) = w.unwrap_or((32, 32));
                let (ll, lb) = (
                    (nl * kl as usize)
                        .div_ceil(32)
                        .min(short.unwrap_or(usize::MAX)),
                    (nb * kb as usize).div_ceil(32),
                );
                let (mut wl, mut wb) = (noise(ll, 0x1357), noise(lb, 0x2468));
                let (wl0, wb0) = (wl.clone(), wb.clone());
                let pack = w.map(|_| EndPackTo {
                    local: (&mut wl[..], kl),
                    bnd: (&mut wb[..], kb),
                });
                let got = band_end_row::<u8, u32, 1>(
                    &t,
                    &mut acc0,
                    &mut acc,
                    &mut bnd[..nb],
                    &mut local[..nl],
                    ([(core::ptr::null(), 0); 2], Pace::Early),
                    pack,
                );
                if !avx2 {
                    assert_eq!(got, None);
                    continue;
                }
                ran += 1;
                // Whole chunks whose fields both rows hold, with a packer for both widths.
                let packer = |k: u32| (MIN_PACK_BITS..=32).contains(&k);
                let chunks = if fused && w.is_some() && packer(kl) && packer(kb) {
                    (n / 256).min(ll / (7 * kl as usize)).min(lb / kb as usize)
                } else {
                    0
                };
                let (pl, pb) = (224 * chunks, 32 * chunks);
                packed_any |= chunks > 0;
                assert_eq!(got, Some((nb, nl, pl, pb)), "n {n}, {w:?}, {short:?}");
                assert_eq!(acc, want_acc, "level above, n {n}");
                assert_eq!(&bnd[pb..nb], &want_b[pb..], "boundaries, n {n}, {w:?}");
                assert_eq!(&local[pl..nl], &want_l[pl..], "local sums, n {n}, {w:?}");
                assert_eq!((bnd[nb], local[nl]), (0xdead_beef, 0xdead_beef), "n {n}");
                // The fields packed in the pass are not written to the scratch.
                assert!(bnd[..pb].iter().all(|&v| v == 0xdead_beef), "n {n}");
                assert!(local[..pl].iter().all(|&v| v == 0xdead_beef), "n {n}");
                // The packed fields, each one's low k bits, over the noise; the words past
                // them untouched.
                let reference = field_by_field;
                assert_eq!(
                    wl,
                    reference(wl0, &want_l[..pl], kl),
                    "local row, n {n}, {w:?}"
                );
                assert_eq!(
                    wb,
                    reference(wb0, &want_b[..pb], kb),
                    "boundary row, n {n}, {w:?}"
                );
                // The column sums cleared, the rest of the storage untouched.
                let (after, at) = (halves_of(&acc0), column_sums_at(acc0.as_ptr(), n));
                assert_eq!(&after[..at], &halves[..at], "below the column sums, n {n}");
                assert!(
                    after[at..at + n].iter().all(|&c| c == 0),
                    "column sums, n {n}"
                );
                assert_eq!(&after[at + n..], &halves[at + n..], "above, n {n}");
            }
        }
        assert_eq!(ran > 0, avx2);
        assert_eq!(packed_any, fused);
    }

    /// `modular256::row` and, with AVX-512 VL, `modular256::row_streamed` against an
    /// independent reference, for every width 11..=32 (a few under Miri): per position the
    /// running sum of the row's texels (each pass continuing the last) added to a dirty working
    /// row (transposed as `modular_row` documents), the new values' low `k` bits packed field by
    /// field with `write_bits`; texels all 255, all 0 and random; the words before and past the
    /// passes untouched (the streamed words start on 16 bytes: on 32 for two patterns, 16 off it
    /// for the third). Then `untranspose_passes` gives the values in position order.
    #[test]
    fn modular_row_equals_the_reference() {
        extern crate std;
        use std::vec::Vec;
        if !matches!(Kernel::best(), Kernel::Avx2 | Kernel::Avx512Vnni) {
            return;
        }
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let passes_list: &[usize] = if cfg!(miri) { &[1] } else { &[1, 3] };
        let mut streamed_runs = 0;
        for (k, streamed) in (MIN_PACK_BITS..=32).flat_map(|k| [(k, false), (k, true)]) {
            if cfg!(miri) && ![11, 21, 32].contains(&k) {
                continue;
            }
            if streamed && !Kernel::Avx512Vnni.available() {
                continue;
            }
            for &passes in passes_list {
                for pattern in 0..3 {
                    let n = passes * MODULAR_PASS;
                    let t: Vec<u8> = (0..n)
                        .map(|_| match pattern {
                            0 => 255,
                            1 => 0,
                            _ => rng(&mut seed),
                        })
                        .collect();
                    // Position-order values before the row, near the top of u32 (wrapping).
                    let before: Vec<u32> = (0..n)
                        .map(|x| (u32::MAX - 3 * x as u32).wrapping_add(u32::from(rng(&mut seed))))
                        .collect();
                    let to_kept = |x: usize| 256 * (x / 256) + kept_at(x % 256);
                    let mut acc = std::vec![0u32; n];
                    for (x, &v) in before.iter().enumerate() {
                        acc[to_kept(x)] = v;
                    }
                    let ku = k as usize;
                    let noise: Vec<u32> = (0..8 * ku * passes + 16)
                        .map(|_| u32::from(rng(&mut seed)) * 0x0101_0101)
                        .collect();
                    let mut words = noise.clone();
                    // The row's words from `at`: on 16 bytes (from 32 bytes and 16 past them)
                    // for the streamed stores, else one word past the buffer's start.
                    let at = if streamed {
                        let base = words.as_ptr() as usize;
                        let on32 = (32 - base % 32) % 32 / 4;
                        if pattern == 1 {
                            on32 + 4
                        } else {
                            on32
                        }
                    } else {
                        1
                    };
                    let run = {
                        let (tp, ap) = (t.as_ptr(), acc.as_mut_ptr());
                        // The last vector in place (modular_rows_in_every_rotation covers the
                        // buffer).
                        let lp = ap.wrapping_add(n - 8);
                        let wp = words[at..].as_mut_ptr();
                        // SAFETY: AVX2 is available (checked above), and AVX-512F and VL for
                        // the streamed row (`Kernel::Avx512Vnni`, checked); the slices hold 256
                        // passes texels and values and 8 k passes words from `wp`, on 16 bytes
                        // for the streamed row.
                        unsafe {
                            // With the prefetch hints for an odd count of passes (the
                            // same values either way).
                            let pf = passes % 2 == 1;
                            if streamed {
                                streamed_runs += 1;
                                let r = by_pack_width!(
                                    ku,
                                    modular256::row_streamed(tp, ap, lp, wp, passes),
                                    unreachable!()
                                );
                                fence();
                                r
                            } else {
                                by_pack_width!(
                                    ku,
                                    modular256::row(tp, ap, lp, wp, passes, pf),
                                    unreachable!()
                                )
                            }
                        }
                    };
                    let mut want_words = noise.clone();
                    let mut r = 0u32;
                    let m = if k == 32 { u32::MAX } else { (1 << k) - 1 };
                    let mut want = before.clone();
                    for x in 0..n {
                        r = r.wrapping_add(u32::from(t[x]));
                        want[x] = want[x].wrapping_add(r);
                        assert!(crate::layouts::packed::write_bits(
                            &mut want_words[at..],
                            x as u64 * u64::from(k),
                            k,
                            u64::from(want[x] & m)
                        ));
                    }
                    let what = (k, streamed, passes, pattern, at);
                    assert_eq!(run, r, "{what:?}");
                    assert_eq!(words, want_words, "{what:?}");
                    for x in 0..n {
                        assert_eq!(acc[to_kept(x)], want[x], "{what:?} x {x}");
                    }
                    untranspose_passes(&mut acc);
                    assert_eq!(acc, want, "{what:?}");
                }
            }
        }
        assert_eq!(streamed_runs > 0, Kernel::Avx512Vnni.available());
    }

    /// The streamed modular row's plan (`modular256::sources`) for every width 11..=32, on any
    /// CPU: with the transposed rows as `pack256::rows8x8` leaves them (register `8 r + g`, lane
    /// `l`: group `g`'s word `8 r + l`, or `K - 8 + l` for the last 8 when 8 does not divide
    /// `K`), lane `l` of output vector `v` is word `8 v + l` of the pass (group `g`'s words at
    /// `K g`), each from one of the two registers named, which exist.
    #[test]
    fn streamed_plan_puts_every_word_in_order() {
        fn check<const K: usize>() {
            let plan = modular256::sources::<K>();
            let rows = K / 8 + usize::from(!K.is_multiple_of(8));
            for (v, s) in plan.iter().enumerate().take(K) {
                for (l, &i) in s.idx.iter().enumerate() {
                    assert!((0..16).contains(&i), "K {K} v {v} lane {l}: index {i}");
                    let reg = if i < 8 { s.a } else { s.b };
                    let (r, g, lane) = (reg / 8, reg % 8, i as usize % 8);
                    assert!(r < rows, "K {K} v {v}: register row {r}");
                    let word = if r == K / 8 {
                        K - 8 + lane
                    } else {
                        8 * r + lane
                    };
                    assert_eq!(K * g + word, 8 * v + l, "K {K}, vector {v}, lane {l}");
                }
            }
        }
        macro_rules! every {
            ($($k:literal)*) => {$( check::<$k>(); )*};
        }
        every!(11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32);
    }

    /// The detected kernel is available, and so is every narrower one (under Miri only the
    /// detected one: [`Kernel::available`]).
    #[test]
    fn detection_is_consistent() {
        let best = Kernel::best();
        assert!(best.available());
        assert_eq!(Kernel::best(), best, "cached");
        let rank = |k: Kernel| Kernel::ALL.iter().position(|&x| x == k).unwrap();
        for k in Kernel::ALL {
            let want = if cfg!(miri) {
                k == best
            } else {
                rank(k) <= rank(best)
            };
            assert_eq!(k.available(), want, "{k:?}");
        }
        assert!(kernel_name().starts_with(best.name()));
    }

    /// The flat rows' kernel is SSE2's exactly where the best is AVX2 on a CPU that splits
    /// 256-bit operations, the best elsewhere, and the cap under a cap (so that the tests
    /// reach every kernel); `kernel_name` says which.
    #[test]
    fn rows_take_sse2_where_256_bit_operations_split() {
        let best = Kernel::best();
        let rows = if best == Kernel::Avx2 && splits_256() {
            Kernel::Sse2
        } else {
            best
        };
        assert_eq!(Kernel::for_rows(), rows);
        assert_eq!(kernel_name() == "avx2, sse2 rows", rows != best);
        for k in Kernel::ALL.into_iter().filter(|k| k.available()) {
            assert_eq!(k.cap(Kernel::for_rows), k);
        }
        // The choice itself, whatever this CPU is: only AVX2 on a splitting CPU gives way.
        for k in Kernel::ALL {
            assert_eq!(k.rows_on(false), k);
            let on_split = if k == Kernel::Avx2 { Kernel::Sse2 } else { k };
            assert_eq!(k.rows_on(true), on_split);
        }
    }

    /// Where SSE2 stands in for AVX2 ([`Kernel::for_rows`]), `Sat::build` of a table of 1 MiB
    /// to 32 MiB goes straight into the table (`build_via_working_row` declines, nothing
    /// written); everywhere else through the working row. Either way the portable checked
    /// build's table.
    #[test]
    #[cfg_attr(miri, ignore = "a table of 1 MiB: too slow under Miri")]
    fn working_row_declined_where_sse2_stands_in() {
        let rows = Kernel::for_rows() != Kernel::best();
        let (w, h) = (1024, 256);
        let texels: std::vec::Vec<u8> = (0..w * h).map(|i| (i * 7 % 251) as u8).collect();
        let texture = crate::Texture::<u8, 1>::new(&texels, w, h).unwrap();
        let mut table = std::vec![5u32; w * h];
        let took = build_via_working_row::<u8, u32, 1>(&mut table, w, |y| texture.row(y));
        assert_eq!(took, !rows);
        if !took {
            assert!(table.iter().all(|&v| v == 5), "nothing written");
        }
        let mut straight = std::vec![0u32; w * h];
        let sat = crate::Sat::build(&texture, &mut straight).unwrap();
        let mut reference = std::vec![0u32; w * h];
        let sat_ref = crate::Sat::build_checked(&texture, &mut reference).unwrap();
        assert_eq!(sat.entries(), sat_ref.entries());
    }

    /// `splits_256_from` on CPUID's answers: AMD's and Hygon's FP128 and FP256 bits (leaf
    /// `8000_001A` EAX bits 0 and 2) read where the leaf exists, every other vendor full width.
    #[test]
    fn splits_256_reads_amds_fp256_bit() {
        let (amd, hygon) = (vendor(b"AuthenticAMD"), vendor(b"HygonGenuine"));
        let intel = vendor(b"GenuineIntel");
        // The Zen 1 guest of the nineteenth session (EPYC 7001): FP128 and MOVU set, FP256
        // clear; its highest extended leaf 8000_0021.
        assert!(splits_256_from(amd, 0x8000_0021, 0b011));
        assert!(splits_256_from(hygon, 0x8000_001F, 0b011));
        assert!(splits_256_from(amd, LEAF_FP, 0b001));
        // FP256 set (Zen 2 on), whatever the other bits.
        assert!(!splits_256_from(amd, 0x8000_0021, 0b111));
        assert!(!splits_256_from(amd, 0x8000_0021, 0b110));
        assert!(!splits_256_from(amd, 0x8000_0021, 0b100));
        // The leaf all zero (a hypervisor's): full width.
        assert!(!splits_256_from(amd, 0x8000_0021, 0));
        assert!(!splits_256_from(hygon, 0x8000_001F, 0b111));
        // The leaf absent, or another vendor's (Intel's highest is 8000_0008; past it, another
        // leaf's data).
        assert!(!splits_256_from(amd, LEAF_FP - 1, 0));
        assert!(!splits_256_from(intel, 0x8000_0008, 0));
        assert!(!splits_256_from(intel, 0x8000_0021, 0));
        assert_eq!(
            vendor(b"AuthenticAMD"),
            [0x6874_7541, 0x6974_6E65, 0x444D_4163],
            "EBX, EDX, ECX as CPUID returns them"
        );
    }

    /// `takes_heads_from` on CPUID's answers: no head on AMD from family 1Ah (its family
    /// field 0xF plus the extended family 0Bh), a head on earlier AMD families, on Hygon and
    /// on Intel.
    #[test]
    fn takes_heads_reads_amds_family() {
        let (amd, hygon) = (vendor(b"AuthenticAMD"), vendor(b"HygonGenuine"));
        let intel = vendor(b"GenuineIntel");
        // This session's Zen 5 guest (family 1Ah model 02h stepping 1), a later family.
        assert!(!takes_heads_from(amd, 0x00B0_0F21));
        assert!(!takes_heads_from(amd, 0x00C0_0F00));
        // Zen 4 (19h model 11h, the ninth session's), Zen 3 (19h model 01h, the twentieth to
        // twenty-sixth sessions'), Zen 1 (17h), Hygon's Dhyana (18h).
        assert!(takes_heads_from(amd, 0x00A1_0F11));
        assert!(takes_heads_from(amd, 0x00A0_0F11));
        assert!(takes_heads_from(amd, 0x0080_0F12));
        assert!(takes_heads_from(hygon, 0x0090_0F12));
        // A family field under 0xF ignores the extended family bits (6 + 14h would be 1Ah).
        assert!(takes_heads_from(amd, 0x0140_0621));
        // Intel: Sapphire Rapids (family 6 model 143), and the same bits as Zen 5's.
        assert!(takes_heads_from(intel, 0x0008_06F8));
        assert!(takes_heads_from(intel, 0x00B0_0F21));
    }

    /// Other types and channel counts are left to the portable path, untouched.
    #[test]
    fn other_types_are_declined() {
        let mut out16 = [5u16; 20];
        assert!(!build_row::<u8, u16, 1>(&[1; 20], None, &mut out16));
        assert_eq!(out16, [5; 20]);
        let mut out32 = [5u32; 20];
        assert!(!build_row::<u16, u32, 1>(&[1; 20], None, &mut out32));
        assert!(!build_row::<u8, u32, 2>(&[1; 20], None, &mut out32));
        assert_eq!(out32, [5; 20]);
    }
}
