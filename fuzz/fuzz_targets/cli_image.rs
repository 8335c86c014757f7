//! The `sat` CLI's image reading, as the CLI does it: `texsat_tools::image_file::probe` (header
//! under decoder limits), the budget check of the decoded image (`budget::Estimate`), then
//! `Probe::decode`; the input bytes are written to a file first, since the reader takes a path.
//!
//! Any answer is a value or an error message, never a panic (the `png` crate's own panic on a PLTE
//! chunk whose length is not a multiple of 3, image-rs/image-png#694, found here, is refused by
//! the reader since f7c47fc) and never an allocation beyond the
//! budget (64 MiB here: libFuzzer's `-malloc_limit_mb` turns a larger one into a crash). A
//! decoded image must hold `w h C` samples and, when small, build a table whose totals are the
//! texels' sums.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use texsat::{Sat, Texel, Texture};
use texsat_tools::budget::{Budget, Estimate};
use texsat_tools::image_file::{probe, Image, Pixels};

/// The budget the target runs under: small, so that every allocation it allows stays far below
/// libFuzzer's malloc limit.
const BUDGET: Budget = Budget {
    max_memory: 64 << 20,
    max_work: 1 << 32,
};

/// One file per process (libFuzzer runs one input at a time in a process), in memory when
/// `/dev/shm` exists; removed after each input.
fn path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let shm = std::path::Path::new("/dev/shm");
        let dir = if shm.is_dir() {
            shm.to_path_buf()
        } else {
            std::env::temp_dir()
        };
        dir.join(format!("texsat-fuzz-cli-image-{}", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    let p = path();
    std::fs::write(p, data).expect("write the input file");
    one(p);
    let _ = std::fs::remove_file(p);
});

fn one(p: &std::path::Path) {
    let Ok(probed) = probe(p, &BUDGET) else {
        return;
    };
    let (w, h, c) = (probed.width, probed.height, probed.channels);
    assert!(
        w >= 1 && h >= 1 && (1..=4).contains(&c),
        "{}",
        probed.describe()
    );
    assert!(matches!(probed.sample_bits, 8 | 16));
    let mut est = Estimate::new(probed.subject("fuzz"));
    est.push(probed.image_item());
    if est.check(&BUDGET).is_err() {
        return;
    }
    let Ok(img) = probed.decode() else {
        return;
    };
    check(&img);
}

fn check(img: &Image) {
    let n = img.width * img.height * img.channels;
    match &img.pixels {
        Pixels::U8(d) => assert_eq!(d.len(), n),
        Pixels::U16(d) => assert_eq!(d.len(), n),
    }
    if img.width * img.height > 1 << 16 {
        return;
    }
    match (&img.pixels, img.channels) {
        (Pixels::U8(d), 1) => totals::<u8, 1>(d, img),
        (Pixels::U8(d), 2) => totals::<u8, 2>(d, img),
        (Pixels::U8(d), 3) => totals::<u8, 3>(d, img),
        (Pixels::U8(d), _) => totals::<u8, 4>(d, img),
        (Pixels::U16(d), 1) => totals::<u16, 1>(d, img),
        (Pixels::U16(d), 2) => totals::<u16, 2>(d, img),
        (Pixels::U16(d), 3) => totals::<u16, 3>(d, img),
        (Pixels::U16(d), _) => totals::<u16, 4>(d, img),
    }
}

/// The table's totals are the sums of the decoded samples.
fn totals<T: Texel, const C: usize>(d: &[T], img: &Image) {
    let texture = Texture::<T, C>::new(d, img.width, img.height).expect("decoded texture");
    let mut storage = vec![0u64; img.width * img.height * C];
    let sat = Sat::build(&texture, &mut storage).expect("u64 holds any small table");
    let mut want = [0u64; C];
    for px in d.chunks_exact(C) {
        for (t, v) in want.iter_mut().zip(px) {
            *t += u64::from(v.to_u16());
        }
    }
    assert_eq!(sat.total(), want);
}
