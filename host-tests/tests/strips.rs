//! `Sat::build_strips` (the strip-parallel build's no_std core) against `Sat::build`: identical
//! tables for every strip count, texel and entry type and channel count; executors that run the
//! jobs in any order or twice change nothing; a job left unrun is an error; the width proof is
//! `Sat::build`'s.

use texsat::table::{StripJob, MAX_STRIPS};
use texsat::{Entry, Error, Sat, Texel, Texture};
use texsat_host_tests::RngExt;

fn run_all<T: Texel, E: Entry, const C: usize>(jobs: &mut [StripJob<'_, '_, T, E, C>]) {
    jobs.iter_mut().for_each(|j| j.run());
}

fn check<T: Texel, E: Entry, const C: usize>(texels: &[T], w: usize, h: usize) {
    let texture = Texture::<T, C>::new(texels, w, h).unwrap();
    let mut want = vec![E::ZERO; w * h * C];
    Sat::build(&texture, &mut want).unwrap();
    for strips in [0, 1, 2, 3, 5, h / 2, h, h + 1, MAX_STRIPS + 7] {
        // Storage starts dirty: every entry must be written.
        let mut got = vec![E::from(0x5a5a); w * h * C + 2];
        let sat = Sat::build_strips(&texture, &mut got, strips, run_all).unwrap();
        assert!(sat.entries() == &want[..], "{w}x{h} C {C}, {strips} strips");
        assert!(sat.total() == *want.last_chunk::<C>().unwrap());
        assert!(
            got[w * h * C..] == [E::from(0x5a5a); 2],
            "wrote past the table"
        );
        // Backwards, and every job twice.
        let mut again = vec![E::ZERO; w * h * C];
        let sat = Sat::build_strips(&texture, &mut again, strips, |jobs| {
            jobs.iter_mut().rev().for_each(|j| j.run());
            jobs.iter_mut().for_each(|j| j.run());
        })
        .unwrap();
        assert!(
            sat.entries() == &want[..],
            "{w}x{h}, {strips} strips, reversed and twice"
        );
    }
}

#[test]
fn equal_to_build_for_every_strip_count_and_type() {
    let mut rng = texsat_host_tests::rng(13);
    for (w, h) in [(1, 1), (1, 9), (9, 1), (17, 33), (40, 70), (3, 130)] {
        let t8: Vec<u8> = (0..w * h * 3)
            .map(|_| rng.random_range(0..=255u8))
            .collect();
        let t16: Vec<u16> = (0..w * h * 3)
            .map(|_| rng.random_range(0..=u16::MAX))
            .collect();
        check::<u8, u32, 1>(&t8[..w * h], w, h);
        check::<u8, u64, 3>(&t8, w, h);
        check::<u16, u64, 1>(&t16[..w * h], w, h);
        check::<u16, u64, 3>(&t16, w, h);
        check::<u16, u32, 2>(&t16[..w * h * 2], w, h);
        if w * h <= 257 {
            check::<u8, u16, 1>(&t8[..w * h], w, h);
        }
    }
}

#[test]
fn a_job_left_unrun_is_an_error() {
    let (w, h) = (8, 20);
    let t = vec![1u8; w * h];
    let texture = Texture::<u8>::new(&t, w, h).unwrap();
    let mut storage = vec![0u32; w * h];
    for skip in 0..4 {
        let mut round = 0;
        let r = Sat::build_strips(&texture, &mut storage, 4, |jobs| {
            round += 1;
            for (k, j) in jobs.iter_mut().enumerate() {
                if !(round == 2 && k == skip) {
                    j.run();
                }
            }
        });
        assert!(
            matches!(r, Err(Error::MissingRows { expected: 20, .. })),
            "skip {skip}: {r:?}"
        );
    }
    // Nothing run at all.
    let r = Sat::build_strips(&texture, &mut storage, 3, |_| {});
    assert!(
        matches!(
            r,
            Err(Error::MissingRows {
                got: 0,
                expected: 20
            })
        ),
        "{r:?}"
    );
}

#[test]
fn the_width_proof_and_storage_are_checked_first() {
    // 8-bit texels into u16 entries: 255 w h < 2^16 needs w h <= 257.
    let t = vec![0u8; 17 * 16];
    let texture = Texture::<u8>::new(&t, 17, 16).unwrap();
    let mut storage = vec![7u16; 17 * 16];
    let mut called = false;
    let r = Sat::build_strips(&texture, &mut storage, 4, |_| called = true);
    assert!(matches!(r, Err(Error::TooWide { .. })), "{r:?}");
    assert!(!called && storage.iter().all(|&v| v == 7));
    let texture = Texture::<u8>::new(&t, 16, 16).unwrap();
    let mut short = vec![0u16; 255];
    let r = Sat::build_strips(&texture, &mut short, 4, |_| called = true);
    assert!(
        matches!(
            r,
            Err(Error::StorageTooSmall {
                needed: 256,
                got: 255
            })
        ),
        "{r:?}"
    );
    assert!(!called);
}
