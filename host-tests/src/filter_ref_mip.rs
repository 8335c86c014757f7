//! `f64` references for texsat's point sampling (`filters::point`) and box-filtered pyramid
//! (`filters::mip`): the pyramid built in `f64` without rounding, its rounded integer twin,
//! and the point, point-sampled-pyramid and trilinear (Williams) filters evaluated in `f64` on
//! any pyramid (the exact one, or texsat's *stored* one to isolate texsat's arithmetic error).
//!
//! Written independently of texsat: texels are plain `u32` slices (`w x h x c`, row-major,
//! channels interleaved), boundary modes are index functions `(i, n) -> Option<usize>` (`None` =
//! zero, texsat's `Border` outside), and nothing here calls texsat's filters. Only the level of
//! detail `L_q` (texsat's fixed-point `lod`) is an input of the level-dependent references, so
//! that the reference evaluates the *same* filter; [`lod_in_range`] checks `L_q` itself against
//! `f64` `log2`.

/// A boundary mode as an index function: the in-texture index that extended index `i` shows on
/// an axis of `n` texels, or `None` where the extended texture is zero.
pub type IndexFn<'a> = &'a dyn Fn(i64, usize) -> Option<usize>;

/// An `f64` image, `w x h` texels, `c` interleaved channels.
#[derive(Debug, Clone, PartialEq)]
pub struct RefImage {
    /// Width in texels.
    pub w: usize,
    /// Height in texels.
    pub h: usize,
    /// Channels.
    pub c: usize,
    /// Values, row-major, channels interleaved.
    pub data: Vec<f64>,
}

impl RefImage {
    /// Texel `(x, y)` channel `ch` (panics outside).
    pub fn get(&self, x: usize, y: usize, ch: usize) -> f64 {
        assert!(x < self.w && y < self.h && ch < self.c);
        self.data[(y * self.w + x) * self.c + ch]
    }

    /// Texel `(i, j)` channel `ch` of the extended image under `index` (0 where it gives none).
    pub fn ext(&self, i: i64, j: i64, ch: usize, index: IndexFn) -> f64 {
        match (index(i, self.w), index(j, self.h)) {
            (Some(x), Some(y)) => self.get(x, y, ch),
            _ => 0.0,
        }
    }
}

/// The level sizes `(ceil(w / 2^l), ceil(h / 2^l))` from `(w, h)` down to `(1, 1)`.
pub fn level_sizes(w: usize, h: usize) -> Vec<(usize, usize)> {
    assert!(w > 0 && h > 0);
    let mut out = vec![(w, h)];
    let (mut a, mut b) = (w, h);
    while (a, b) != (1, 1) {
        a = a.div_ceil(2);
        b = b.div_ceil(2);
        out.push((a, b));
    }
    out
}

/// Texels per channel of the whole pyramid, level 0 included.
pub fn pyramid_texels(w: usize, h: usize) -> usize {
    level_sizes(w, h).iter().map(|&(a, b)| a * b).sum()
}

/// The memory ratio of the pyramid to the texture (the survey's "1.33" for square textures).
pub fn memory_ratio(w: usize, h: usize) -> f64 {
    pyramid_texels(w, h) as f64 / (w * h) as f64
}

/// The exact integer sum and texel count of the base block of level-`l` texel `(i, j)`,
/// channel `ch`: base texels `[i 2^l, (i+1) 2^l) x [j 2^l, (j+1) 2^l)` clipped to the texture.
#[allow(clippy::too_many_arguments)]
pub fn block_sum(
    texels: &[u32],
    w: usize,
    h: usize,
    c: usize,
    l: u32,
    i: usize,
    j: usize,
    ch: usize,
) -> (u64, u64) {
    let (mut s, mut n) = (0u64, 0u64);
    for y in (j << l)..((j + 1) << l).min(h) {
        for x in (i << l)..((i + 1) << l).min(w) {
            s += texels[(y * w + x) * c + ch] as u64;
            n += 1;
        }
    }
    (s, n)
}

/// The pyramid in `f64` without rounding: every level-`l` texel the exact average of its clipped
/// base block (sums of at most `2^37` texels of 16 bits are exact in `f64`).
pub fn exact_pyramid(texels: &[u32], w: usize, h: usize, c: usize) -> Vec<RefImage> {
    assert_eq!(texels.len(), w * h * c);
    level_sizes(w, h)
        .iter()
        .enumerate()
        .map(|(l, &(lw, lh))| {
            let mut data = Vec::with_capacity(lw * lh * c);
            for y in 0..lh {
                for x in 0..lw {
                    for ch in 0..c {
                        let (s, n) = block_sum(texels, w, h, c, l as u32, x, y, ch);
                        data.push(s as f64 / n as f64);
                    }
                }
            }
            RefImage {
                w: lw,
                h: lh,
                c,
                data,
            }
        })
        .collect()
}

/// The pyramid as texsat must store it: each exact block average rounded to nearest, ties up
/// (`floor((2 s + n) / (2 n))`, in integers).
pub fn rounded_pyramid(texels: &[u32], w: usize, h: usize, c: usize) -> Vec<Vec<u32>> {
    level_sizes(w, h)
        .iter()
        .enumerate()
        .map(|(l, &(lw, lh))| {
            let mut data = Vec::with_capacity(lw * lh * c);
            for y in 0..lh {
                for x in 0..lw {
                    for ch in 0..c {
                        let (s, n) = block_sum(texels, w, h, c, l as u32, x, y, ch);
                        data.push(((2 * s + n) / (2 * n)) as u32);
                    }
                }
            }
            data
        })
        .collect()
}

/// A pyramid of integer levels (e.g. read back from texsat) as `f64` images.
pub fn pyramid_from_levels(
    sizes: &[(usize, usize)],
    c: usize,
    levels: &[Vec<u32>],
) -> Vec<RefImage> {
    sizes
        .iter()
        .zip(levels)
        .map(|(&(w, h), d)| {
            assert_eq!(d.len(), w * h * c);
            RefImage {
                w,
                h,
                c,
                data: d.iter().map(|&v| v as f64).collect(),
            }
        })
        .collect()
}

/// The footprint centre `((x0 + x1) / 2, (y0 + y1) / 2)` in texels from raw corners at `F = f`
/// (exact while `|x0 + x1| < 2^53`).
pub fn centre(raw: [i64; 4], f: u32) -> (f64, f64) {
    let s = 2f64.powi(f as i32 + 1);
    (
        (raw[0] as i128 + raw[2] as i128) as f64 / s,
        (raw[1] as i128 + raw[3] as i128) as f64 / s,
    )
}

/// `log2(max(W, H))` in texels, or `None` for `d = 0`.
pub fn log2_diameter(raw: [i64; 4], f: u32) -> Option<f64> {
    let d = (raw[2] as i128 - raw[0] as i128).max(raw[3] as i128 - raw[1] as i128);
    if d <= 0 {
        None
    } else {
        Some((d as f64).log2() - f as f64)
    }
}

/// Whether texsat's fixed-point level of detail `lod_q` (8 fraction bits, clamped to
/// `[0, (levels - 1) 256]`) is `floor(256 log2 d)` or one below it, clamped the same way
/// (`0` for `d = 0`). A slack of `1e-7` on `256 log2 d` absorbs `f64`'s own `log2` rounding.
pub fn lod_in_range(lod_q: u32, raw: [i64; 4], f: u32, levels: usize) -> bool {
    let top = ((levels - 1) * 256) as f64;
    match log2_diameter(raw, f) {
        None => lod_q == 0,
        Some(l) => {
            let x = l * 256.0;
            let lo = ((x - 1e-7).floor() - 1.0).clamp(0.0, top);
            let hi = (x + 1e-7).floor().clamp(0.0, top);
            (lo..=hi).contains(&(lod_q as f64))
        }
    }
}

/// Point sampling in `f64`: the texel `(floor(cx), floor(cy))` of the extended texture, per
/// channel, in texel units.
pub fn point_ref(base: &RefImage, raw: [i64; 4], f: u32, index: IndexFn) -> Vec<f64> {
    let (cx, cy) = centre(raw, f);
    let (i, j) = (cx.floor() as i64, cy.floor() as i64);
    (0..base.c).map(|ch| base.ext(i, j, ch, index)).collect()
}

/// The point-sampled pyramid in `f64`: level `min((lod_q + 128) >> 8, top)`, texel
/// `floor(c / 2^l)` of that level under `index` (at the level's own size).
pub fn point_sample_ref(
    pyr: &[RefImage],
    raw: [i64; 4],
    f: u32,
    lod_q: u32,
    index: IndexFn,
) -> Vec<f64> {
    let top = pyr.len() - 1;
    let l = (((lod_q + 128) >> 8) as usize).min(top);
    let (cx, cy) = centre(raw, f);
    let s = 2f64.powi(l as i32);
    let (i, j) = ((cx / s).floor() as i64, (cy / s).floor() as i64);
    (0..pyr[l].c)
        .map(|ch| pyr[l].ext(i, j, ch, index))
        .collect()
}

/// Bilinear interpolation of pyramid level `l` at base position `(cx, cy)`: level texel centres
/// at `(i + 0.5) 2^l`, taps through `index` at the level's size; exact weights in `f64`.
pub fn bilinear_ref(level: &RefImage, l: usize, cx: f64, cy: f64, index: IndexFn) -> Vec<f64> {
    let s = 2f64.powi(l as i32);
    let (u, v) = (cx / s - 0.5, cy / s - 0.5);
    let (fi, fj) = (u.floor(), v.floor());
    let (a, b) = (u - fi, v - fj);
    let (i, j) = (fi as i64, fj as i64);
    (0..level.c)
        .map(|ch| {
            let p = |di: i64, dj: i64| level.ext(i + di, j + dj, ch, index);
            let r0 = p(0, 0) * (1.0 - a) + p(1, 0) * a;
            let r1 = p(0, 1) * (1.0 - a) + p(1, 1) * a;
            r0 * (1.0 - b) + r1 * b
        })
        .collect()
}

/// Williams' trilinear in `f64` with texsat's level of detail `lod_q` (8 fraction bits):
/// bilinear in levels `floor(L)` and `min(floor(L) + 1, top)`, lerp by `frac(L)`.
pub fn trilinear_ref(
    pyr: &[RefImage],
    raw: [i64; 4],
    f: u32,
    lod_q: u32,
    index: IndexFn,
) -> Vec<f64> {
    let top = pyr.len() - 1;
    let l0 = ((lod_q >> 8) as usize).min(top);
    let l1 = (l0 + 1).min(top);
    let t = (lod_q & 255) as f64 / 256.0;
    let (cx, cy) = centre(raw, f);
    let v0 = bilinear_ref(&pyr[l0], l0, cx, cy, index);
    let v1 = bilinear_ref(&pyr[l1], l1, cx, cy, index);
    v0.iter()
        .zip(&v1)
        .map(|(a, b)| a * (1.0 - t) + b * t)
        .collect()
}

/// The documented bound of texsat's trilinear against [`trilinear_ref`] on the same stored
/// pyramid, in texel units: `m 2^(1-W) + 2^-17`, `m = 2^bits - 1`, with `W = (64 - 8 - bits) / 2`
/// weight bits (24 for 8-bit texels, 20 for 16-bit: the most that keeps the trilinear in `u64`).
pub fn trilinear_bound(texel_bits: u32) -> f64 {
    let w = (64 - 8 - texel_bits as i32) / 2;
    ((1u64 << texel_bits) - 1) as f64 * 2f64.powi(1 - w) + 2f64.powi(-17)
}
