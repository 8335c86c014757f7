//! Table builds on all cores (feature `parallel`): [`texsat::Sat::build_strips`], the core's
//! `no_std` strip build, with its jobs run on rayon's thread pool. The core stays
//! single-threaded and dependency-free; this is the host's executor for it.
//!
//! The strip build makes one pass over the table, like [`texsat::Sat::build`], plus a read of
//! the texels for the column sums and `O(w strips)` sequential additions for the carries (see
//! `build_strips`). The speed-up is bounded by memory bandwidth: a build is close to the
//! widen-copy floor already (docs/benchmarks.md, issue 13).

use rayon::prelude::*;
use texsat::table::{StripJob, MAX_STRIPS};
use texsat::{Entry, Error, Sat, Texel, Texture};

/// Below this many texels a build runs on the calling thread (the thread pool's wake-up costs
/// more than the build: 64 K texels build in about 10 us).
pub const MIN_PARALLEL_TEXELS: usize = 1 << 16;

/// Builds the table of `texture` on rayon's global pool: `2 x threads` strips (at most
/// [`MAX_STRIPS`]), or [`Sat::build`] for textures below [`MIN_PARALLEL_TEXELS`] or a pool of
/// one thread. The same table as [`Sat::build`], the same width proof and errors.
pub fn build_parallel<'a, T, E, const C: usize>(
    texture: &Texture<'_, T, C>,
    storage: &'a mut [E],
) -> Result<Sat<'a, E, C>, Error>
where
    T: Texel + Sync,
    E: Entry + Send + Sync,
{
    let threads = rayon::current_num_threads();
    if threads < 2 || texture.width().saturating_mul(texture.height()) < MIN_PARALLEL_TEXELS {
        return Sat::build(texture, storage);
    }
    build_with_strips(texture, storage, (2 * threads).min(MAX_STRIPS))
}

/// [`build_parallel`] with a given strip count (tests, benchmarks).
pub fn build_with_strips<'a, T, E, const C: usize>(
    texture: &Texture<'_, T, C>,
    storage: &'a mut [E],
    strips: usize,
) -> Result<Sat<'a, E, C>, Error>
where
    T: Texel + Sync,
    E: Entry + Send + Sync,
{
    Sat::build_strips(texture, storage, strips, run_jobs::<T, E, C>)
}

/// Runs every job on the pool.
fn run_jobs<T: Texel + Sync, E: Entry + Send + Sync, const C: usize>(
    jobs: &mut [StripJob<'_, '_, T, E, C>],
) {
    jobs.par_iter_mut().for_each(|j| j.run());
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texels(n: usize, seed: u64) -> Vec<u8> {
        texsat_host_tests::random_bytes(n, seed)
    }

    /// Equal to `Sat::build` for sizes around the parallel threshold and strip counts from 1 to
    /// past the maximum, on a pool of 4 threads (whatever the machine's cores).
    #[test]
    fn equal_to_build() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        pool.install(|| {
            for (w, h) in [
                (1, 1),
                (300, 1),
                (1, 300),
                (255, 257),
                (256, 256),
                (513, 700),
            ] {
                let t = texels(w * h, (w * 31 + h) as u64);
                let texture = Texture::<u8>::new(&t, w, h).unwrap();
                let mut want = vec![0u32; w * h];
                Sat::build(&texture, &mut want).unwrap();
                let mut got = vec![1u32; w * h];
                let sat = build_parallel(&texture, &mut got).unwrap();
                assert_eq!(sat.entries(), &want[..], "{w}x{h}");
                for strips in [1, 2, 3, 8, 64, 65] {
                    let mut got = vec![1u32; w * h];
                    let sat = build_with_strips(&texture, &mut got, strips).unwrap();
                    assert_eq!(sat.entries(), &want[..], "{w}x{h}, {strips} strips");
                }
            }
            // Three channels of u16 into u64.
            let (w, h) = (300, 301);
            let t: Vec<u16> = texels(w * h * 6, 5)
                .chunks_exact(2)
                .map(|p| u16::from_le_bytes([p[0], p[1]]))
                .collect();
            let texture = Texture::<u16, 3>::new(&t, w, h).unwrap();
            let mut want = vec![0u64; w * h * 3];
            Sat::build(&texture, &mut want).unwrap();
            let mut got = vec![0u64; w * h * 3];
            assert_eq!(
                build_parallel(&texture, &mut got).unwrap().entries(),
                &want[..]
            );
        });
    }

    /// The width proof refuses before any job runs, as `Sat::build` does.
    #[test]
    fn width_proof_refuses() {
        let t = vec![255u8; 300 * 300];
        let texture = Texture::<u8>::new(&t, 300, 300).unwrap();
        let mut storage = vec![0u16; 300 * 300];
        assert!(matches!(
            build_with_strips(&texture, &mut storage, 4),
            Err(Error::TooWide { .. })
        ));
    }
}
