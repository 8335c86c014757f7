//! `f64` references of texsat's ripmap (`texsat::filters::rip`) and dipmap
//! (`texsat::filters::dip`), written from the definitions, not from texsat's code:
//!
//! * levels: exact block averages (`f64`) and the correctly rounded integers (`round(sum / n)`,
//!   ties up, from `u128` sums), for any block shape `2^sx x 2^sy`, clipped to the texture;
//! * sampling: bilinear probes at the footprint centre with exact positions and weights, the
//!   ripmap's bilinear blend of four probes, the dipmap's average of a row and a column sample
//!   (bilinear in `floor(L)` or trilinear), on any set of levels (exact, rounded, or the ones a
//!   texsat map stored);
//! * level positions either exactly as texsat quantises them (`log2_fixed` with
//!   [`LEVEL_FRAC_BITS`] bits: "the same filter") or with the exact `f64` `log2`.
//!
//! Boundary modes are passed as a closure `(index, axis length) -> Option<index>` (`None` =
//! zero), so the reference does not depend on any crate-local mode type.
//!
//! Units: values in texel units (not scaled); rectangles as raw fixed-point corners
//! `[x0, y0, x1, y1]` with `f` fractional bits.

use texsat::filters::level::log2_fixed;

/// Fraction bits of the level positions (must equal `texsat::filters::{rip,dip}::LEVEL_FRAC_BITS`;
/// the tests assert it).
pub const LEVEL_FRAC_BITS: u32 = 12;

/// A boundary mode: the in-level index shown at integer position `i` of an axis of `n`
/// texels, or `None` where the extended level is zero.
pub type IndexFn<'a> = &'a dyn Fn(i64, usize) -> Option<usize>;

/// A level (or texture) in `f64`: `w x h` texels, `c` interleaved channels, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Img {
    /// Width in texels.
    pub w: usize,
    /// Height in texels.
    pub h: usize,
    /// Channels.
    pub c: usize,
    /// Values, `(j * w + i) * c + ch`.
    pub v: Vec<f64>,
}

impl Img {
    /// Texel `(i, j)` channel `ch`.
    pub fn at(&self, i: usize, j: usize, ch: usize) -> f64 {
        self.v[(j * self.w + i) * self.c + ch]
    }

    /// An image from a texel function.
    pub fn from_fn(w: usize, h: usize, c: usize, f: impl Fn(usize, usize, usize) -> f64) -> Self {
        let mut v = Vec::with_capacity(w * h * c);
        for j in 0..h {
            for i in 0..w {
                for ch in 0..c {
                    v.push(f(i, j, ch));
                }
            }
        }
        Img { w, h, c, v }
    }
}

/// `ceil(n / 2^l)`.
pub fn level_len(n: usize, l: usize) -> usize {
    n.div_ceil(1usize << l)
}

/// Levels of an axis of `n >= 1` texels: halve (rounding up) until 1, counting level 0.
pub fn level_count(n: usize) -> usize {
    let mut m = n;
    let mut count = 1;
    while m > 1 {
        m = m.div_ceil(2);
        count += 1;
    }
    count
}

/// The level of `2^sx x 2^sy` blocks of the texture `tex` (`w x h`, `c` channels, row-major
/// `u32` texels), blocks clipped to the texture: `(exact averages, correctly rounded averages)`.
/// The rounded value is `floor((2 sum + n) / (2 n))` in `u128`: to nearest, ties up.
pub fn block_level(tex: &[u32], w: usize, h: usize, c: usize, sx: usize, sy: usize) -> (Img, Img) {
    let (lw, lh) = (level_len(w, sx), level_len(h, sy));
    let mut exact = Img {
        w: lw,
        h: lh,
        c,
        v: vec![],
    };
    let mut rounded = exact.clone();
    for j in 0..lh {
        for i in 0..lw {
            for ch in 0..c {
                let (mut s, mut n) = (0u128, 0u128);
                for y in (j << sy)..((j + 1) << sy).min(h) {
                    for x in (i << sx)..((i + 1) << sx).min(w) {
                        s += tex[(y * w + x) * c + ch] as u128;
                        n += 1;
                    }
                }
                exact.v.push(s as f64 / n as f64);
                rounded.v.push(((2 * s + n) / (2 * n)) as f64);
            }
        }
    }
    (exact, rounded)
}

/// The ripmap's levels, `(lx, ly)` at `ly * levels_x + lx`.
#[derive(Debug, Clone)]
pub struct RefRip {
    /// Levels along x.
    pub levels_x: usize,
    /// Levels along y.
    pub levels_y: usize,
    /// The levels.
    pub levels: Vec<Img>,
}

impl RefRip {
    /// All levels from the texture, exact (`rounded = false`) or correctly rounded.
    pub fn build(tex: &[u32], w: usize, h: usize, c: usize, rounded: bool) -> Self {
        let (levels_x, levels_y) = (level_count(w), level_count(h));
        let mut levels = vec![];
        for ly in 0..levels_y {
            for lx in 0..levels_x {
                let (e, r) = block_level(tex, w, h, c, lx, ly);
                levels.push(if rounded { r } else { e });
            }
        }
        RefRip {
            levels_x,
            levels_y,
            levels,
        }
    }

    /// Levels from a texel function `(lx, ly, i, j, ch)` (e.g. a texsat map's stored texels).
    pub fn from_fn(
        w: usize,
        h: usize,
        c: usize,
        get: impl Fn(usize, usize, usize, usize, usize) -> f64,
    ) -> Self {
        let (levels_x, levels_y) = (level_count(w), level_count(h));
        let mut levels = vec![];
        for ly in 0..levels_y {
            for lx in 0..levels_x {
                levels.push(Img::from_fn(
                    level_len(w, lx),
                    level_len(h, ly),
                    c,
                    |i, j, ch| get(lx, ly, i, j, ch),
                ));
            }
        }
        RefRip {
            levels_x,
            levels_y,
            levels,
        }
    }

    /// Level `(lx, ly)`.
    pub fn level(&self, lx: usize, ly: usize) -> &Img {
        &self.levels[ly * self.levels_x + lx]
    }
}

/// The dipmap's two pyramids: `row[l]` is `w x ceil(h / 2^l)` (shrinks y), `col[l]` is
/// `ceil(w / 2^l) x h` (shrinks x); both start with the texture.
#[derive(Debug, Clone)]
pub struct RefDip {
    /// Row pyramid (levels shrink y), sampled at `log2(H)`.
    pub row: Vec<Img>,
    /// Column pyramid (levels shrink x), sampled at `log2(W)`.
    pub col: Vec<Img>,
}

impl RefDip {
    /// Both pyramids from the texture, exact or correctly rounded.
    pub fn build(tex: &[u32], w: usize, h: usize, c: usize, rounded: bool) -> Self {
        let pick = |(e, r): (Img, Img)| if rounded { r } else { e };
        RefDip {
            row: (0..level_count(h))
                .map(|l| pick(block_level(tex, w, h, c, 0, l)))
                .collect(),
            col: (0..level_count(w))
                .map(|l| pick(block_level(tex, w, h, c, l, 0)))
                .collect(),
        }
    }

    /// Pyramids from texel functions `(l, i, j, ch)` for the row and the column pyramid.
    pub fn from_fn(
        w: usize,
        h: usize,
        c: usize,
        row: impl Fn(usize, usize, usize, usize) -> f64,
        col: impl Fn(usize, usize, usize, usize) -> f64,
    ) -> Self {
        RefDip {
            row: (0..level_count(h))
                .map(|l| Img::from_fn(w, level_len(h, l), c, |i, j, ch| row(l, i, j, ch)))
                .collect(),
            col: (0..level_count(w))
                .map(|l| Img::from_fn(level_len(w, l), h, c, |i, j, ch| col(l, i, j, ch)))
                .collect(),
        }
    }
}

/// How the reference selects levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LevelSel {
    /// As texsat: `log2_fixed(side, f, LEVEL_FRAC_BITS)`, exact rational blend weights.
    Fixed,
    /// The exact `log2` of the side in `f64`.
    Exact,
}

/// `(lo, hi, frac)` for a side of `side_raw / 2^f` texels on an axis whose top level is `top`:
/// `L = clamp(log2(side), 0, top)`, `lo = floor(L)`, `hi = min(lo + 1, top)`, `frac = L - lo`.
/// A zero side is level 0.
pub fn level_split(side_raw: i64, f: u32, top: usize, sel: LevelSel) -> (usize, usize, f64) {
    let l = match sel {
        LevelSel::Fixed => {
            let q = log2_fixed(side_raw as u64, f, LEVEL_FRAC_BITS).unwrap_or(0);
            q as f64 / (1u64 << LEVEL_FRAC_BITS) as f64
        }
        LevelSel::Exact => {
            if side_raw <= 0 {
                0.0
            } else {
                (side_raw as f64).log2() - f as f64
            }
        }
    };
    let l = l.clamp(0.0, top as f64);
    let lo = (l.floor() as usize).min(top);
    (lo, (lo + 1).min(top), l - lo as f64)
}

/// The bilinear probe of `img` at the base-texel centre `(cx, cy)` in a level that shrinks x by
/// `2^sx` and y by `2^sy`: the four level texels around `(cx / 2^sx - 1/2, cy / 2^sy - 1/2)`,
/// exact weights, indices outside resolved by `index` on the level's own grid.
pub fn bilinear(img: &Img, cx: f64, cy: f64, sx: usize, sy: usize, index: IndexFn) -> Vec<f64> {
    let u = cx / (1u64 << sx) as f64 - 0.5;
    let v = cy / (1u64 << sy) as f64 - 0.5;
    let (i0, j0) = (u.floor(), v.floor());
    let (a, b) = (u - i0, v - j0);
    let (i0, j0) = (i0 as i64, j0 as i64);
    (0..img.c)
        .map(|ch| {
            let t = |i: i64, j: i64| match (index(i, img.w), index(j, img.h)) {
                (Some(x), Some(y)) => img.at(x, y, ch),
                _ => 0.0,
            };
            let r0 = t(i0, j0) * (1.0 - a) + t(i0 + 1, j0) * a;
            let r1 = t(i0, j0 + 1) * (1.0 - a) + t(i0 + 1, j0 + 1) * a;
            r0 * (1.0 - b) + r1 * b
        })
        .collect()
}

fn centre(r: [i64; 4], f: u32) -> (f64, f64) {
    let s = (1u64 << f) as f64;
    (
        (r[0] as f64 + r[2] as f64) / 2.0 / s,
        (r[1] as f64 + r[3] as f64) / 2.0 / s,
    )
}

fn mix(a: &[f64], b: &[f64], t: f64) -> Vec<f64> {
    a.iter()
        .zip(b)
        .map(|(a, b)| a * (1.0 - t) + b * t)
        .collect()
}

/// The ripmap filter: four bilinear probes at the centre of `r` in levels
/// `{lo_x, hi_x} x {lo_y, hi_y}`, blended bilinearly by `(frac_x, frac_y)`.
pub fn rip_sample(rip: &RefRip, r: [i64; 4], f: u32, sel: LevelSel, index: IndexFn) -> Vec<f64> {
    let (lox, hix, fx) = level_split(r[2] - r[0], f, rip.levels_x - 1, sel);
    let (loy, hiy, fy) = level_split(r[3] - r[1], f, rip.levels_y - 1, sel);
    let (cx, cy) = centre(r, f);
    let p = |lx: usize, ly: usize| bilinear(rip.level(lx, ly), cx, cy, lx, ly, index);
    let b0 = mix(&p(lox, loy), &p(hix, loy), fx);
    let b1 = mix(&p(lox, hiy), &p(hix, hiy), fx);
    mix(&b0, &b1, fy)
}

/// The dipmap variants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DipVariant {
    /// Bilinear in `floor(L)` of each pyramid, averaged.
    Bilinear,
    /// Trilinear in each pyramid, averaged.
    Trilinear,
}

/// The dipmap filter: the column pyramid sampled at `log2(W)`, the row pyramid at `log2(H)`,
/// both at the centre of `r`, averaged.
pub fn dip_sample(
    dip: &RefDip,
    r: [i64; 4],
    f: u32,
    variant: DipVariant,
    sel: LevelSel,
    index: IndexFn,
) -> Vec<f64> {
    let (lox, hix, fx) = level_split(r[2] - r[0], f, dip.col.len() - 1, sel);
    let (loy, hiy, fy) = level_split(r[3] - r[1], f, dip.row.len() - 1, sel);
    let (cx, cy) = centre(r, f);
    let col = |l: usize| bilinear(&dip.col[l], cx, cy, l, 0, index);
    let row = |l: usize| bilinear(&dip.row[l], cx, cy, 0, l, index);
    let (a, b) = match variant {
        DipVariant::Bilinear => (col(lox), row(loy)),
        DipVariant::Trilinear => (mix(&col(lox), &col(hix), fx), mix(&row(loy), &row(hiy), fy)),
    };
    mix(&a, &b, 0.5)
}
