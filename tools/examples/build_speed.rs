//! Build-speed bench server (issue 13): times table builds of a square `u8` texture into `u32`
//! entries, one at a time on request, so that a driver can interleave them with builds it times
//! itself (OpenCV in `tools/examples/build_speed.py`, which starts this binary).
//!
//! Protocol: one request per line on stdin, `<method> <side>`; the answer is one line on stdout,
//! the wall time of that one build in nanoseconds per texel. `methods` lists the methods;
//! `kernel` names the build kernel compiled in ([`texsat::build_kernel`]); `dump <side> <file>`
//! writes the texture's bytes to a file (the driver times OpenCV on the same texels). Every method's table
//! is compared with `Sat::build`'s (or, for the layouts, their corners with its entries) before
//! its first timing. Storage is allocated and touched once per side and reused.
//!
//! Texture placement: with `TEXSAT_BS_TEXTURE_PAGE_OFFSET=B` (0 to 4,095) in its environment,
//! each texture's first texel lies at byte `B` of a 4 KiB page (and so does every row of 4,096
//! texels); otherwise where its storage starts (a page boundary for a map, 16 bytes past one for
//! a large heap block on glibc).
//!
//! Pages: with `TEXSAT_BS_PAGES=thp` in its environment, every timed output (the table, the
//! layouts' words) is an anonymous map advised `MADV_HUGEPAGE`, and so is the texture from 4
//! MiB on, as numpy advises its arrays of 4 MiB and more (OpenCV's output at both sizes, its
//! image at 4,096^2, in the driver); otherwise (`4k`, the driver's default, which turns
//! numpy's advice off) all storage is plain heap memory. Every output, not only those of 4 MiB
//! and more: the tiled layout of 1,024^2 (2.3 MiB) on 4 KiB pages beside a flat table on 2 MiB
//! ones would compare the pages, not the builds. The driver reports how much of each side lay
//! in huge pages.
//!
//! Methods:
//! * `floor`: the widen-copy floor, `out[i] = u32::from(texel[i])` (reads 1 byte and writes 4 per
//!   texel, as any build must; the compiler vectorizes it).
//! * `build`: `Sat::build`; `checked`: `Sat::build_checked` (every addition checked).
//! * `stream`: `RowStreamBuilder::push_row`, each finished row copied into the table (as a caller
//!   keeping the table would); `stream_nocopy`: the same without the copy; `stream_into`:
//!   `RowStreamBuilder::push_row_into`, which writes each row into the table in the same pass.
//! * `tiled`: `Tiled::build` with 8 x 8 tiles; `modular`: `Modular::build` with the modulus for
//!   65 x 65 boxes of 8-bit texels.
//! * `imageproc`: `imageproc::integral_image::integral_image` (allocates its (w+1) x (h+1)
//!   output every call).
//! * `parallel` (feature `parallel`): `texsat_tools::parallel::build_parallel`, the strip build
//!   on rayon's pool (all cores); `strips_seq`: `Sat::build_strips` with 4 strips run one after
//!   the other on the calling thread (the strip build's own cost: column sums and carries).
//!
//! Run it through the driver: `python3 tools/examples/build_speed.py` (see there).

use std::collections::HashMap;
use std::hint::black_box;
use std::io::{BufRead, Write};
use std::ops::{Deref, DerefMut};
use std::time::Instant;

use bytemuck::Pod;
use memmap2::MmapMut;

use image::GrayImage;
use texsat::layouts::{modulus_bits_for, Modular, Tiled, TiledSpec};
use texsat::{NoCount, RowStreamBuilder, Sat, Texture};

const METHODS: &[&str] = &[
    "floor",
    "build",
    "checked",
    "stream",
    "stream_nocopy",
    "stream_into",
    "tiled",
    "modular",
    "imageproc",
    "strips_seq",
    #[cfg(feature = "parallel")]
    "parallel",
];

/// The widen-copy floor.
#[inline(never)]
fn floor(t: &[u8], out: &mut [u32]) {
    for (o, t) in out.iter_mut().zip(t) {
        *o = u32::from(*t);
    }
}

/// numpy's threshold for advising huge pages: it calls `madvise(MADV_HUGEPAGE)` on the data
/// of every array of at least 4 MiB (as numpy 2.4 does; see `--pages` in the driver).
const HUGE_MIN_BYTES: usize = 1 << 22;

/// A huge page: maps for huge pages are a whole number of them (Linux 6.7 and later then
/// places an anonymous map on a 2 MiB boundary, so that all of it can be huge pages; numpy's
/// arrays, inside unaligned heap maps, get slightly less: see the driver's report).
const HUGE_PAGE: usize = 1 << 21;

/// A 4 KiB page, the unit of `TEXSAT_BS_TEXTURE_PAGE_OFFSET`.
const PAGE: usize = 4096;

/// Which page each buffer asks for.
#[derive(Clone, Copy, PartialEq)]
enum Pages {
    /// Heap memory (4 KiB pages where THP is `madvise`).
    Small,
    /// Huge pages for the outputs, and for the texture from [`HUGE_MIN_BYTES`] on.
    Huge,
}

/// A timed buffer: heap memory, or an anonymous map advised `MADV_HUGEPAGE` (page-aligned, so
/// any `Pod` view of it is aligned).
enum Buf<T> {
    Heap(Vec<T>),
    Map(MmapMut, usize),
}

impl<T: Pod> Buf<T> {
    /// `len` copies of `fill`, every page touched; in huge pages if `huge`.
    fn new(len: usize, fill: T, huge: bool) -> Self {
        let bytes = len * std::mem::size_of::<T>();
        if !huge {
            return Buf::Heap(vec![fill; len]);
        }
        let map = MmapMut::map_anon(bytes.div_ceil(HUGE_PAGE) * HUGE_PAGE).expect("anonymous map");
        // Refused where the kernel has no THP: then 4 KiB pages, as numpy goes on (the driver
        // reports the pages each side got).
        #[cfg(target_os = "linux")]
        if let Err(e) = map.advise(memmap2::Advice::HugePage) {
            eprintln!("build_speed: madvise(MADV_HUGEPAGE) refused ({e}): 4 KiB pages");
        }
        let mut b = Buf::Map(map, len);
        b.fill(fill);
        b
    }
}

impl<T: Pod> Deref for Buf<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        match self {
            Buf::Heap(v) => v,
            Buf::Map(m, len) => &bytemuck::cast_slice(&m[..])[..*len],
        }
    }
}

impl<T: Pod> DerefMut for Buf<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        match self {
            Buf::Heap(v) => v,
            Buf::Map(m, len) => &mut bytemuck::cast_slice_mut(&mut m[..])[..*len],
        }
    }
}

/// One side's texture and reused storage.
struct Case {
    side: usize,
    /// The texture's storage: its texels from byte `at` on.
    tex: Buf<u8>,
    at: usize,
    gray: GrayImage,
    reference: Vec<u32>,
    table: Buf<u32>,
    row: Vec<u32>,
    spec: TiledSpec,
    words: Buf<u32>,
    scratch: Buf<u32>,
    k: u32,
    mwords: Buf<u32>,
    checked: HashMap<&'static str, bool>,
}

impl Case {
    /// The texture and storage of one side; with `page_offset`, the texture's first texel at
    /// that byte of a 4 KiB page (its storage then 4 KiB longer).
    fn new(side: usize, pages: Pages, page_offset: Option<usize>) -> Self {
        let out = pages == Pages::Huge;
        // xorshift64 noise, uniform bytes (the same generator as benches/sat.rs's texels).
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let tex: Vec<u8> = (0..side * side)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 24) as u8
            })
            .collect();
        let gray = GrayImage::from_raw(side as u32, side as u32, tex.clone()).expect("image");
        let mut reference = vec![0u32; side * side];
        let texture = Texture::<u8>::new(&tex, side, side).expect("texture");
        Sat::build(&texture, &mut reference).expect("build");
        let spec = TiledSpec::tiles(8, 8).expect("spec");
        let words_needed = Tiled::<u32>::words_needed(spec, side, side, 8).expect("words");
        let words = Buf::new(words_needed, 0, out);
        let scratch_needed = Tiled::<u32>::scratch_needed(spec, side).expect("scratch");
        let scratch = Buf::new(scratch_needed, 0, false);
        let k = modulus_bits_for(8, 65 * 65);
        let mwords_needed = Modular::<u32>::words_needed(side, side, k).expect("words");
        let mwords = Buf::new(mwords_needed, 0, out);
        let huge_tex = out && side * side >= HUGE_MIN_BYTES;
        // The texels from byte `at` (0 unless placed: then a page more, to place them in).
        let mut buf = Buf::new(tex.len() + page_offset.map_or(0, |_| PAGE), 0, huge_tex);
        let at = page_offset.map_or(0, |b| {
            (b % PAGE + PAGE - buf.as_ptr() as usize % PAGE) % PAGE
        });
        buf[at..at + tex.len()].copy_from_slice(&tex);
        Case {
            side,
            tex: buf,
            at,
            gray,
            reference,
            table: Buf::new(side * side, 1, out),
            row: vec![1u32; side],
            spec,
            words,
            scratch,
            k,
            mwords,
            checked: HashMap::new(),
        }
    }

    /// Runs `method` once; checks its output against the reference the first time.
    fn run(&mut self, method: &str) -> f64 {
        let n = self.side;
        let tex = &self.tex[self.at..self.at + n * n];
        let texture = Texture::<u8>::new(tex, n, n).expect("texture");
        let start = Instant::now();
        match method {
            "floor" => floor(black_box(tex), black_box(&mut self.table)),
            "build" => {
                Sat::build(&texture, black_box(&mut self.table)).expect("build");
            }
            "checked" => {
                Sat::build_checked(&texture, black_box(&mut self.table)).expect("build");
            }
            "stream" | "stream_nocopy" => {
                let copy = method == "stream";
                let mut b = RowStreamBuilder::<u32>::new(n, n, 8, &mut self.row).expect("stream");
                for (src, dst) in tex.chunks_exact(n).zip(self.table.chunks_exact_mut(n)) {
                    let row = b.push_row(src).expect("push_row");
                    if copy {
                        dst.copy_from_slice(row);
                    }
                }
                black_box(b.finish().expect("finish"));
            }
            "stream_into" => {
                let mut b = RowStreamBuilder::<u32>::new(n, n, 8, &mut self.row).expect("stream");
                for (src, dst) in tex.chunks_exact(n).zip(self.table.chunks_exact_mut(n)) {
                    b.push_row_into(src, dst).expect("push_row_into");
                }
                black_box(b.finish().expect("finish"));
            }
            "tiled" => {
                black_box(
                    Tiled::<u32>::build(&texture, self.spec, &mut self.words, &mut self.scratch)
                        .expect("tiled"),
                );
            }
            "modular" => {
                black_box(
                    Modular::<u32>::build(&texture, self.k, &mut self.mwords, &mut self.row)
                        .expect("modular"),
                );
            }
            "imageproc" => {
                black_box(imageproc::integral_image::integral_image::<_, u32>(
                    &self.gray,
                ));
            }
            "strips_seq" => {
                Sat::build_strips(&texture, black_box(&mut self.table), 4, |jobs| {
                    jobs.iter_mut().for_each(|j| j.run())
                })
                .expect("strips");
            }
            #[cfg(feature = "parallel")]
            "parallel" => {
                texsat_tools::parallel::build_parallel(&texture, black_box(&mut self.table))
                    .expect("parallel");
            }
            other => panic!("unknown method {other}"),
        }
        let ns = start.elapsed().as_nanos() as f64 / (n * n) as f64;
        let key = METHODS
            .iter()
            .find(|m| **m == method)
            .copied()
            .expect("method");
        if !self.checked.contains_key(key) {
            self.check(method);
            self.checked.insert(key, true);
        }
        ns
    }

    fn check(&mut self, method: &str) {
        let n = self.side;
        let texture =
            Texture::<u8>::new(&self.tex[self.at..self.at + n * n], n, n).expect("texture");
        match method {
            "floor" | "stream_nocopy" => {}
            "build" | "checked" | "stream" | "stream_into" | "strips_seq" | "parallel" => {
                assert!(*self.table == self.reference[..], "{method}: table differs");
            }
            "tiled" => {
                let t =
                    Tiled::<u32>::build(&texture, self.spec, &mut self.words, &mut self.scratch)
                        .expect("tiled");
                use texsat::Layout;
                let get = |x, y| t.corner(x, y, &mut NoCount)[0];
                check_corners(&self.reference, n, u32::MAX, get, method);
            }
            "modular" => {
                use texsat::Layout;
                let m = Modular::<u32>::build(&texture, self.k, &mut self.mwords, &mut self.row)
                    .expect("modular");
                let mask = if self.k >= 32 {
                    u32::MAX
                } else {
                    (1 << self.k) - 1
                };
                let get = |x, y| m.corner(x, y, &mut NoCount)[0];
                check_corners(&self.reference, n, mask, get, method);
            }
            "imageproc" => {
                let ip = imageproc::integral_image::integral_image::<_, u32>(&self.gray);
                for y in 0..n {
                    let row = &ip.as_raw()[(y + 1) * (n + 1) + 1..(y + 2) * (n + 1)];
                    assert!(
                        row == &self.reference[y * n..(y + 1) * n],
                        "imageproc row {y}"
                    );
                }
            }
            _ => {}
        }
    }
}

/// Compares a layout's corners `S(x, y)` (via `get`, modulo `mask + 1` for a modular layout)
/// with the flat table on a grid of rows and columns (every 7th, and the last).
fn check_corners(
    reference: &[u32],
    n: usize,
    mask: u32,
    get: impl Fn(usize, usize) -> u32,
    what: &str,
) {
    let idx = |v: usize| (1..=n).filter(move |i| i % 7 == 0 || *i == v);
    for y in idx(n) {
        for x in idx(n) {
            let want = reference[(y - 1) * n + (x - 1)] & mask;
            let got = get(x, y) & mask;
            assert!(got == want, "{what}: S({x}, {y}) {got} != {want}");
        }
    }
}

fn main() {
    let stdin = std::io::stdin();
    let mut stdout = std::io::stdout().lock();
    let mut cases: HashMap<usize, Case> = HashMap::new();
    let pages = match std::env::var("TEXSAT_BS_PAGES").as_deref() {
        Ok("thp") => Pages::Huge,
        Ok("4k") | Err(_) => Pages::Small,
        Ok(other) => panic!("TEXSAT_BS_PAGES={other:?}: 4k or thp"),
    };
    let page_offset = std::env::var("TEXSAT_BS_TEXTURE_PAGE_OFFSET")
        .ok()
        .map(|v| {
            v.parse::<usize>()
                .ok()
                .filter(|&b| b < PAGE)
                .unwrap_or_else(|| panic!("TEXSAT_BS_TEXTURE_PAGE_OFFSET={v:?}: 0 to 4095"))
        });
    for line in stdin.lock().lines() {
        let line = line.expect("stdin");
        let words: Vec<&str> = line.split_whitespace().collect();
        let answer = match words.as_slice() {
            ["methods"] => METHODS.join(" "),
            ["kernel"] => texsat::build_kernel().to_string(),
            ["path"] => std::env::current_exe().expect("exe").display().to_string(),
            ["dump", side, path] => {
                let side: usize = side.parse().expect("side");
                let case = cases
                    .entry(side)
                    .or_insert_with(|| Case::new(side, pages, page_offset));
                std::fs::write(path, &case.tex[case.at..case.at + side * side])
                    .expect("write texture");
                "ok".to_string()
            }
            [method, side] => {
                let side: usize = side.parse().expect("side");
                let case = cases
                    .entry(side)
                    .or_insert_with(|| Case::new(side, pages, page_offset));
                format!("{}", case.run(method))
            }
            [] => continue,
            _ => panic!("bad request {line:?}"),
        };
        writeln!(stdout, "{answer}").expect("stdout");
        stdout.flush().expect("stdout");
    }
}
