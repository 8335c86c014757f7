//! Reading PNG and PNM images (through [`texsat_tools::image_file`]: header first, budget
//! checked, then the samples), and dispatching on texel type and channel count to code generic
//! over `Texture<T, C>` ([`with_types`] before decoding, [`with_texture`] after).

use crate::filter::ImageTexel;
use texsat::{Texel, Texture};
pub use texsat_tools::image_file::{probe, Image, Pixels, Probe};

/// Code generic over the texel type and channel count of an image not yet decoded (estimates).
pub trait TypesJob {
    type Out;
    fn run<T: ImageTexel, const C: usize>(self, width: usize, height: usize) -> Self::Out;
}

/// Runs `job` with the texel type (`u8`, `u16`) and channel count (1 to 4) of `p`.
pub fn with_types<J: TypesJob>(p: &Probe, job: J) -> Result<J::Out, String> {
    let (w, h) = (p.width, p.height);
    Ok(match (p.sample_bits, p.channels) {
        (8, 1) => job.run::<u8, 1>(w, h),
        (8, 2) => job.run::<u8, 2>(w, h),
        (8, 3) => job.run::<u8, 3>(w, h),
        (8, 4) => job.run::<u8, 4>(w, h),
        (16, 1) => job.run::<u16, 1>(w, h),
        (16, 2) => job.run::<u16, 2>(w, h),
        (16, 3) => job.run::<u16, 3>(w, h),
        (16, 4) => job.run::<u16, 4>(w, h),
        (b, c) => return Err(format!("{c} channels of {b} bits are not supported")),
    })
}

/// Code generic over the texel type (`u8`, `u16`: [`ImageTexel`]) and the channel count.
pub trait TextureJob {
    type Out;
    fn run<T: ImageTexel, const C: usize>(self, texture: &Texture<'_, T, C>) -> Self::Out;
}

/// Runs `job` on the image as a `Texture<T, C>` with `T = u8 | u16` and `C = 1..=4`.
pub fn with_texture<J: TextureJob>(img: &Image, job: J) -> Result<J::Out, String> {
    macro_rules! go {
        ($data:expr, $c:literal) => {{
            let texture = Texture::<_, $c>::new($data, img.width, img.height)
                .map_err(|e| format!("texture: {e}"))?;
            Ok(job.run(&texture))
        }};
    }
    match (&img.pixels, img.channels) {
        (Pixels::U8(d), 1) => go!(d, 1),
        (Pixels::U8(d), 2) => go!(d, 2),
        (Pixels::U8(d), 3) => go!(d, 3),
        (Pixels::U8(d), 4) => go!(d, 4),
        (Pixels::U16(d), 1) => go!(d, 1),
        (Pixels::U16(d), 2) => go!(d, 2),
        (Pixels::U16(d), 3) => go!(d, 3),
        (Pixels::U16(d), 4) => go!(d, 4),
        (_, c) => Err(format!("{c} channels are not supported (1 to 4)")),
    }
}

/// Exact per-channel whole-texture sums, straight from the texels (independent of the table).
pub fn channel_totals<T: Texel, const C: usize>(texture: &Texture<'_, T, C>) -> [u128; C] {
    let mut totals = [0u128; C];
    for row in (0..texture.height()).filter_map(|y| texture.row(y)) {
        for px in row.chunks_exact(C) {
            for (t, &v) in totals.iter_mut().zip(px) {
                *t += u128::from(v.to_u16());
            }
        }
    }
    totals
}
