//! A borrowed view of a texture: texels in rows, `C` interleaved channels, any row stride.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::error::Error;
use crate::texel::Texel;

/// Largest width or height accepted (coordinates stay far inside `i64`/`i128` arithmetic).
pub(crate) const MAX_DIMENSION: usize = (1 << 31) - 1;

/// The size check every table, layout and texture shares: both sides in `1..=2^31 - 1` and at
/// least one channel.
pub(crate) const fn check_dimensions(
    width: usize,
    height: usize,
    channels: usize,
) -> Result<(), Error> {
    if width == 0 || height == 0 || channels == 0 {
        return Err(Error::EmptyTexture);
    }
    if width > MAX_DIMENSION || height > MAX_DIMENSION {
        return Err(Error::TextureTooLarge {
            dimension: if width > height { width } else { height },
        });
    }
    Ok(())
}

/// A texture of `width x height` texels with `C` interleaved channels (`1..=4` in practice).
///
/// Texel `(x, y)` channel `c` is `data[y * stride + x * C + c]`; `stride` is in elements and at
/// least `width * C`. Row 0 is the top row (image-file order).
#[derive(Debug, Clone, Copy)]
pub struct Texture<'a, T: Texel, const C: usize = 1> {
    data: &'a [T],
    width: usize,
    height: usize,
    stride: usize,
}

impl<'a, T: Texel, const C: usize> Texture<'a, T, C> {
    /// A tightly packed texture (`stride = width * C`).
    pub fn new(data: &'a [T], width: usize, height: usize) -> Result<Self, Error> {
        Self::with_stride(data, width, height, width.saturating_mul(C))
    }

    /// A texture whose rows start `stride` elements apart.
    pub fn with_stride(
        data: &'a [T],
        width: usize,
        height: usize,
        stride: usize,
    ) -> Result<Self, Error> {
        check_dimensions(width, height, C)?;
        let row = width
            .checked_mul(C)
            .ok_or(Error::TextureTooLarge { dimension: width })?;
        if stride < row {
            return Err(Error::StrideTooSmall {
                stride,
                needed: row,
            });
        }
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "check_dimensions above: height >= 1"
        )]
        let last_row = height - 1;
        let needed = stride
            .checked_mul(last_row)
            .and_then(|v| v.checked_add(row))
            .ok_or(Error::TextureDataTooShort {
                needed: usize::MAX,
                got: data.len(),
            })?;
        if data.len() < needed {
            return Err(Error::TextureDataTooShort {
                needed,
                got: data.len(),
            });
        }
        Ok(Texture {
            data,
            width,
            height,
            stride,
        })
    }

    /// The texels' storage (row `y` from element `y * stride`) and the stride: for the tiled
    /// build's prefetch hints (`simd::TexturePages`).
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    pub(crate) fn storage(&self) -> (&'a [T], usize) {
        (self.data, self.stride)
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Row `y` (`width * C` elements), or `None` if `y` is not below the height.
    pub fn row(&self, y: usize) -> Option<&'a [T]> {
        if y >= self.height {
            return None;
        }
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "y < height and width * C <= stride, so start + width * C <= stride * (height - 1) + width * C, \
                      which with_stride computed with checked arithmetic (and found <= data.len())"
        )]
        let (start, end) = {
            let start = y * self.stride;
            (start, start + self.width * C)
        };
        self.data.get(start..end)
    }
}
