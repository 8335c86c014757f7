//! Reading PNG and PNM images into texel buffers, and dispatching on texel type and channel
//! count to code generic over `Texture<T, C>`.

use crate::filter::ImageTexel;
use image::codecs::pnm::PnmDecoder;
use image::{DynamicImage, ImageFormat, ImageReader};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;
use texsat::{Texel, Texture};

/// Texels as read from the file: 8 or 16 bits per sample, channels interleaved.
pub enum Pixels {
    U8(Vec<u8>),
    U16(Vec<u16>),
}

/// A decoded image.
pub struct Image {
    pub pixels: Pixels,
    pub width: usize,
    pub height: usize,
    pub channels: usize,
}

/// Reads a PNG or PNM (PBM, PGM, PPM, PAM) file. 8-bit samples become `u8` texels, 16-bit
/// samples `u16` texels, with the values stored in the file. Gray, gray+alpha, RGB and RGBA give
/// 1, 2, 3 and 4 channels.
///
/// The `image` crate rescales PNM samples whose maxval is neither 255 nor 65535 (through `f32`),
/// which would change the data; such files are refused rather than silently rescaled. PBM
/// bitmaps read as 8-bit gray with black = 0 and white = 255, and PNG gray of 1, 2 or 4 bits is
/// scaled to 8 bits exactly (by 255, 85, 17), as the `png` crate expands it.
pub fn load(path: &Path) -> Result<Image, String> {
    let name = path.display();
    let err = |e: &dyn std::fmt::Display| format!("{name}: {e}");
    let reader = ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| err(&e))?;
    let decoded = if reader.format() == Some(ImageFormat::Pnm) {
        let file = File::open(path).map_err(|e| err(&e))?;
        let decoder = PnmDecoder::new(BufReader::new(file)).map_err(|e| err(&e))?;
        let header = decoder.header();
        let maxval = header.maximal_sample();
        if header.as_bitmap().is_none() && maxval != 255 && maxval != 65535 {
            return Err(err(&format_args!(
                "PNM maxval {maxval} is not 255 or 65535; the image decoder would rescale the \
                 samples, so the file is refused (store it with maxval 255 or 65535)"
            )));
        }
        DynamicImage::from_decoder(decoder).map_err(|e| err(&e))?
    } else {
        reader.decode().map_err(|e| err(&e))?
    };
    let (width, height) = (decoded.width() as usize, decoded.height() as usize);
    let (pixels, channels) = match decoded {
        DynamicImage::ImageLuma8(b) => (Pixels::U8(b.into_raw()), 1),
        DynamicImage::ImageLumaA8(b) => (Pixels::U8(b.into_raw()), 2),
        DynamicImage::ImageRgb8(b) => (Pixels::U8(b.into_raw()), 3),
        DynamicImage::ImageRgba8(b) => (Pixels::U8(b.into_raw()), 4),
        DynamicImage::ImageLuma16(b) => (Pixels::U16(b.into_raw()), 1),
        DynamicImage::ImageLumaA16(b) => (Pixels::U16(b.into_raw()), 2),
        DynamicImage::ImageRgb16(b) => (Pixels::U16(b.into_raw()), 3),
        DynamicImage::ImageRgba16(b) => (Pixels::U16(b.into_raw()), 4),
        other => {
            return Err(err(&format_args!(
                "unsupported sample type {:?} (only 8- and 16-bit integer samples)",
                other.color()
            )))
        }
    };
    Ok(Image {
        pixels,
        width,
        height,
        channels,
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
    for y in 0..texture.height() {
        let row = texture.row(y).expect("row in range");
        for px in row.chunks_exact(C) {
            for (t, &v) in totals.iter_mut().zip(px) {
                *t += u128::from(v.to_u16());
            }
        }
    }
    totals
}
