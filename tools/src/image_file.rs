//! Image files read in two steps, so that nothing large is allocated before a command has
//! checked its budget: [`probe`] reads the header (size, channels, sample width) under the
//! `image` crate's decoder limits; [`Probe::decode`] checks that the file can hold what its
//! header claims and reads the samples into a buffer reserved with `try_reserve_exact`. Shared by
//! the `sat` CLI and the report.

use crate::budget::{self, Budget};
use image::codecs::pnm::{PnmDecoder, PnmSubtype, SampleEncoding};
use image::{ColorType, ImageDecoder, ImageFormat, ImageReader, Limits};
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// The largest side the decoders accept: the crate's own limit on a texture side (`2^31 - 1`,
/// `texsat::Texture`), so that no header the crate would refuse gets as far as a buffer.
const MAX_SIDE: u32 = (1 << 31) - 1;

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

/// The most bytes one byte of deflate data can expand to (a 258-byte match coded in 2 bits,
/// plus headers: about 1032.3), rounded up: a PNG file of `n` bytes holds at most `1033 n` bytes
/// of raw (filtered) rows.
const DEFLATE_MAX_RATIO: u128 = 1033;

/// An image whose header has been read and checked, and whose samples have not.
pub struct Probe {
    path: PathBuf,
    decoder: Box<dyn ImageDecoder>,
    /// The file's length in bytes.
    file_bytes: u64,
    /// The fewest bytes a file with this header can have, and what they hold (for the message):
    /// PNM samples are stored raw, PNG rows take at least a filter byte and a bit per texel,
    /// deflated at most [`DEFLATE_MAX_RATIO`]-fold.
    min_file_bytes: (u128, &'static str),
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    /// 8 or 16.
    pub sample_bits: u32,
}

/// Reads the header of a PNG or PNM (PBM, PGM, PPM, PAM) file under decoder limits (sides up
/// to `2^31 - 1`, the decoder's own allocations within `budget.max_memory`). 8-bit samples
/// become `u8` texels, 16-bit samples `u16` texels, with the values stored in the file. Gray,
/// gray+alpha, RGB and RGBA give 1, 2, 3 and 4 channels.
///
/// Refused here, before any sample is read: a directory, a missing, unreadable or empty file,
/// an unknown format, a corrupt header, a zero side, an unsupported sample type, and PNM samples
/// whose maxval is neither 255 nor 65535 (the `image` crate would rescale them through `f32`,
/// changing the data). PBM bitmaps read as 8-bit gray with black = 0 and white = 255, and PNG
/// gray of 1, 2 or 4 bits is scaled to 8 bits exactly (by 255, 85, 17), as the `png` crate
/// expands it.
pub fn probe(path: &Path, budget: &Budget) -> Result<Probe, String> {
    let name = path.display();
    let err = |e: &dyn std::fmt::Display| format!("{name}: {e}");
    if path.is_dir() {
        return Err(err(&"is a directory, not an image file"));
    }
    let limits = {
        let mut l = Limits::no_limits();
        l.max_image_width = Some(MAX_SIDE);
        l.max_image_height = Some(MAX_SIDE);
        l.max_alloc = Some(budget.max_memory);
        l
    };
    let file_bytes = std::fs::metadata(path).map_err(|e| err(&e))?.len();
    if file_bytes == 0 {
        return Err(err(&"the file is empty, not an image"));
    }
    let mut reader = ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| err(&e))?;
    reader.limits(limits.clone());
    let header_err = |kind: &str, e: &dyn std::fmt::Display| {
        err(&format_args!("cannot read the {kind} header: {e}"))
    };
    let mut pnm_encoding = None;
    let decoder: Box<dyn ImageDecoder> = match reader.format() {
        Some(ImageFormat::Pnm) => {
            let file = File::open(path).map_err(|e| err(&e))?;
            let mut decoder =
                PnmDecoder::new(BufReader::new(file)).map_err(|e| header_err("PNM", &e))?;
            let header = decoder.header();
            pnm_encoding = Some(header.subtype());
            let maxval = header.maximal_sample();
            if header.as_bitmap().is_none() && maxval != 255 && maxval != 65535 {
                return Err(err(&format_args!(
                    "PNM maxval {maxval} is not 255 or 65535; the image decoder would rescale \
                     the samples, so the file is refused (store it with maxval 255 or 65535)"
                )));
            }
            decoder
                .set_limits(limits)
                .map_err(|e| header_err("PNM", &e))?;
            Box::new(decoder)
        }
        Some(ImageFormat::Png) => {
            Box::new(reader.into_decoder().map_err(|e| header_err("PNG", &e))?)
        }
        Some(other) => {
            return Err(err(&format_args!(
                "{other:?} images are not supported (PNG or PNM only)"
            )))
        }
        None => {
            return Err(err(
                &"not a PNG or PNM image (the file's first bytes are no known signature)",
            ))
        }
    };
    let (w, h) = decoder.dimensions();
    let (channels, sample_bits) = match decoder.color_type() {
        ColorType::L8 => (1, 8),
        ColorType::La8 => (2, 8),
        ColorType::Rgb8 => (3, 8),
        ColorType::Rgba8 => (4, 8),
        ColorType::L16 => (1, 16),
        ColorType::La16 => (2, 16),
        ColorType::Rgb16 => (3, 16),
        ColorType::Rgba16 => (4, 16),
        other => {
            return Err(err(&format_args!(
                "unsupported sample type {other:?} (only 8- and 16-bit integer samples)"
            )))
        }
    };
    if w == 0 || h == 0 {
        return Err(err(&format_args!(
            "the image is {w} x {h} texels: a texture needs at least one"
        )));
    }
    let (w128, h128) = (u128::from(w), u128::from(h));
    let samples = w128 * h128 * channels as u128;
    let min_file_bytes = match pnm_encoding {
        Some(PnmSubtype::Bitmap(SampleEncoding::Binary)) => {
            (h128 * w128.div_ceil(8), "packed bitmap rows")
        }
        Some(t) if t.sample_encoding() == SampleEncoding::Binary => {
            (samples * u128::from(sample_bits / 8), "raw samples")
        }
        Some(_) => (samples, "ASCII samples (a digit each at least)"),
        None => (
            (h128 * (1 + w128.div_ceil(8))).div_ceil(DEFLATE_MAX_RATIO),
            "deflated rows (a filter byte and a bit per texel, expanded at most 1033-fold)",
        ),
    };
    Ok(Probe {
        path: path.to_path_buf(),
        decoder,
        file_bytes,
        min_file_bytes,
        width: w as usize,
        height: h as usize,
        channels,
        sample_bits,
    })
}

impl Probe {
    /// Bytes per sample (1 or 2).
    pub fn sample_bytes(&self) -> usize {
        if self.sample_bits == 8 {
            1
        } else {
            2
        }
    }

    /// `"W x H, C channel(s) of B bits"`, for messages.
    pub fn describe(&self) -> String {
        format!(
            "{} x {} image ({} channel{} of {} bits)",
            self.width,
            self.height,
            self.channels,
            if self.channels == 1 { "" } else { "s" },
            self.sample_bits
        )
    }

    /// The subject of a budget message: `"PATH: COMMAND on this W x H image (...)"`.
    pub fn subject(&self, command: &str) -> String {
        format!(
            "{}: {command} on this {}",
            self.path.display(),
            self.describe()
        )
    }

    /// The decoded image: what [`budget::image`] estimates.
    pub fn image_item(&self) -> budget::Item {
        budget::image(self.width, self.height, self.channels, self.sample_bytes())
    }

    /// Refuses a file too short to hold what its header claims (PNM samples are stored raw; PNG
    /// rows take at least a filter byte and a bit per texel, deflated at most 1033-fold), so
    /// that a raised budget does not turn a 21-byte file into a 40 GB buffer.
    pub fn check_size(&self) -> Result<(), String> {
        let (min, what) = self.min_file_bytes;
        if u128::from(self.file_bytes) < min {
            return Err(format!(
                "{}: truncated or corrupt: the header claims {} x {} texels, which take at least \
                 {min} bytes of {what}, but the file has {} bytes",
                self.path.display(),
                self.width,
                self.height,
                self.file_bytes
            ));
        }
        Ok(())
    }

    /// Reads the samples into a buffer of exactly [`Probe::image_item`]'s bytes, reserved with
    /// `try_reserve_exact` (an allocation failure is an error, not an abort). A file too short
    /// to hold what its header claims is refused before the buffer is made (so a raised budget
    /// does not turn a 21-byte file into a 40 GB buffer); truncated or corrupt data is an error.
    pub fn decode(self) -> Result<Image, String> {
        self.check_size()?;
        let name = self.path.display();
        let err = |e: &dyn std::fmt::Display| format!("{name}: {e}");
        let samples = self
            .width
            .checked_mul(self.height)
            .and_then(|n| n.checked_mul(self.channels))
            .ok_or_else(|| err(&"the image is too large to address"))?;
        let expected = samples as u128 * self.sample_bytes() as u128;
        if u128::from(self.decoder.total_bytes()) != expected {
            return Err(err(&format_args!(
                "internal error: the decoder wants {} bytes, the estimate is {expected}",
                self.decoder.total_bytes()
            )));
        }
        let what = format!("buffer of the {}", self.describe());
        let decode_err =
            |e: &dyn std::fmt::Display| err(&format_args!("cannot decode the samples: {e}"));
        let decoder = self.decoder;
        let pixels = if self.sample_bits == 8 {
            let mut buf = budget::zeroed(samples, 0u8, &what)?;
            without_panic(|| decoder.read_image(&mut buf))
                .map_err(|e| decode_err(&e))?
                .map_err(|e| decode_err(&e))?;
            Pixels::U8(buf)
        } else {
            let mut buf = budget::zeroed(samples, 0u16, &what)?;
            // The decoder writes native-endian 16-bit samples.
            without_panic(|| decoder.read_image(bytemuck::cast_slice_mut(&mut buf)))
                .map_err(|e| decode_err(&e))?
                .map_err(|e| decode_err(&e))?;
            Pixels::U16(buf)
        };
        Ok(Image {
            pixels,
            width: self.width,
            height: self.height,
            channels: self.channels,
        })
    }
}

/// Runs a decoder step, turning a panic inside it into an error: the `png` crate (0.18.1, the
/// latest release) panics on a PLTE chunk whose length is not a multiple of 3
/// (image-rs/image-png#694; found by `fuzz/fuzz_targets/cli_image.rs`), and a test bench's file
/// must give a message and exit status 1, never a panic. The panic hook is silenced for the call
/// (the tools decode on one thread), so nothing but the error reaches stderr.
fn without_panic<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    out.map_err(|p| {
        let what = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a decoder panic".to_string());
        format!("corrupt image data (the decoder failed: {what})")
    })
}
