//! References for texsat's host tests: an `f64` and an exact integer model of the extended
//! texture and its box integrals, a naive table builder, wide-integer helpers for checking
//! rounded means without floats, dispatch helpers that call texsat with a run-time mode or form,
//! and proptest strategies.
//!
//! Everything here is written independently of texsat's lookups: the references never look at a
//! summed-area table, they sum texels of the extended texture directly (or, for boxes spanning
//! many periods, per-texel weights in closed form, cross-checked against direct summation in
//! `tests/reference.rs`).
//!
//! Random inputs: every test and bench draws from one seeded generator, [`rng`] (ChaCha8 from a
//! constant seed), so inputs are the same on every run.
//!
//! Units: a fixed-point coordinate with `F` fractional bits is the integer `raw = value * 2^F`;
//! exact box integrals are returned scaled by `2^2F` (the product of two raw lengths), which is
//! exactly the unit of [`texsat::BoxSum::scaled_sum`].
// A host-only package: on a bare-metal target (the workspace root's default members, built
// with `--target thumbv7em-none-eabihf`) the library is empty and `no_std`.
#![cfg_attr(target_os = "none", no_std)]
#![cfg(not(target_os = "none"))]
#![warn(missing_docs)]

pub mod crow_literal;
use fixed::traits::Fixed;
use proptest::prelude::*;
use texsat::{
    Acc, Border, BoxSum, ClampToEdge, Coord, Counter, EdgeKind, Entry, Error, FormKind,
    MirroredRepeat, Paper, Rect, Repeat, Sat, Shortcut, ShortcutMean, Stable, Texel, Texture,
};

/// A boundary mode of the reference, mirroring texsat's zero-sized mode types at run time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RefMode {
    /// Zero outside the texture.
    Border,
    /// Indices clamp to `[0, n - 1]`.
    Clamp,
    /// Index `i mod n`.
    Repeat,
    /// Period `2n`; an index `r` in `[n, 2n)` of the period maps to `2n - 1 - r`.
    Mirror,
}

impl RefMode {
    /// texsat's run-time mode value for this mode.
    pub fn kind(self) -> EdgeKind {
        match self {
            RefMode::Border => EdgeKind::Border,
            RefMode::Clamp => EdgeKind::Clamp,
            RefMode::Repeat => EdgeKind::Repeat,
            RefMode::Mirror => EdgeKind::Mirror,
        }
    }

    /// All four modes.
    pub const ALL: [RefMode; 4] = [
        RefMode::Border,
        RefMode::Clamp,
        RefMode::Repeat,
        RefMode::Mirror,
    ];

    /// The in-texture index that extended index `i` shows on an axis of `n` texels, or `None`
    /// where the extended texture is zero (outside, under [`RefMode::Border`]).
    pub fn index(self, i: i64, n: usize) -> Option<usize> {
        let n = n as i64;
        assert!(n > 0, "empty axis");
        let k = match self {
            RefMode::Border => {
                if (0..n).contains(&i) {
                    i
                } else {
                    return None;
                }
            }
            RefMode::Clamp => i.clamp(0, n - 1),
            RefMode::Repeat => i.rem_euclid(n),
            RefMode::Mirror => {
                let r = i.rem_euclid(2 * n);
                if r < n {
                    r
                } else {
                    2 * n - 1 - r
                }
            }
        };
        Some(k as usize)
    }
}

/// A box-sum formulation at run time (texsat's [`Paper`] or [`Stable`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RefForm {
    /// [`texsat::Paper`].
    Paper,
    /// [`texsat::Stable`].
    Stable,
}

impl RefForm {
    /// texsat's run-time form value for this form.
    pub fn kind(self) -> FormKind {
        match self {
            RefForm::Paper => FormKind::Paper,
            RefForm::Stable => FormKind::Stable,
        }
    }

    /// Both forms.
    pub const ALL: [RefForm; 2] = [RefForm::Paper, RefForm::Stable];
}

/// A texture for the references: `width x height` texels with `channels` interleaved channels,
/// texel `(i, j)` channel `c` at `texels[(j * width + i) * channels + c]` (row 0 on top).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RefTexture {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Interleaved channels per texel.
    pub channels: usize,
    /// The texel values, row-major, channels interleaved.
    pub texels: Vec<u32>,
}

impl RefTexture {
    /// A texture from its texels; panics if the length is not `width * height * channels`.
    pub fn new(width: usize, height: usize, channels: usize, texels: Vec<u32>) -> Self {
        assert!(width > 0 && height > 0 && channels > 0, "empty texture");
        assert_eq!(texels.len(), width * height * channels, "texel count");
        RefTexture {
            width,
            height,
            channels,
            texels,
        }
    }

    /// A texture with every texel of every channel equal to `v`.
    pub fn constant(width: usize, height: usize, channels: usize, v: u32) -> Self {
        Self::new(width, height, channels, vec![v; width * height * channels])
    }

    /// A pseudo-random texture with texels in `0..=max`, reproducible from `seed`.
    pub fn random(width: usize, height: usize, channels: usize, max: u32, seed: u64) -> Self {
        let mut rng = rng(seed);
        let texels = (0..width * height * channels)
            .map(|_| rng.random_range(0..=max))
            .collect();
        Self::new(width, height, channels, texels)
    }

    /// Texel `(i, j)` channel `c` of the texture itself (panics outside).
    pub fn texel(&self, i: usize, j: usize, c: usize) -> u32 {
        assert!(i < self.width && j < self.height && c < self.channels);
        self.texels[(j * self.width + i) * self.channels + c]
    }

    /// Texel `(i, j)` channel `c` of the *extended* texture under `mode` (any integer indices).
    pub fn texel_ext(&self, mode: RefMode, i: i64, j: i64, c: usize) -> u32 {
        match (mode.index(i, self.width), mode.index(j, self.height)) {
            (Some(x), Some(y)) => self.texel(x, y, c),
            _ => 0,
        }
    }

    /// The largest texel value present.
    pub fn max_texel(&self) -> u32 {
        self.texels.iter().copied().max().unwrap_or(0)
    }

    /// Channel `c`'s whole-texture sum.
    pub fn total(&self, c: usize) -> u128 {
        self.texels
            .iter()
            .skip(c)
            .step_by(self.channels)
            .map(|&t| t as u128)
            .sum()
    }

    /// The texels converted to the texel type `T` (panics if a value does not fit).
    pub fn texels_as<T: RefTexel>(&self) -> Vec<T> {
        self.texels.iter().map(|&v| T::from_u32(v)).collect()
    }

    /// The integral of the extended texture over the float box `[x0, x1) x [y0, y1)`, channel
    /// `c`, by direct summation: every texel cell the box overlaps, times the overlap area.
    /// Zero for an empty or inverted box. Only for boxes covering a moderate number of cells.
    pub fn box_integral(&self, mode: RefMode, x0: f64, y0: f64, x1: f64, y1: f64, c: usize) -> f64 {
        if !(x1 > x0 && y1 > y0) {
            return 0.0;
        }
        let cells = |lo: f64, hi: f64| (lo.floor() as i64)..(hi.ceil() as i64);
        let overlap =
            |lo: f64, hi: f64, i: i64| (hi.min(i as f64 + 1.0) - lo.max(i as f64)).max(0.0);
        let mut sum = 0.0;
        for j in cells(y0, y1) {
            let oy = overlap(y0, y1, j);
            for i in cells(x0, x1) {
                let ox = overlap(x0, x1, i);
                sum += self.texel_ext(mode, i, j, c) as f64 * ox * oy;
            }
        }
        sum
    }

    /// The exact integral over the raw box `[x0, x1) x [y0, y1)` (coordinates `value * 2^F`),
    /// channel `c`, scaled by `2^2F`, by *direct summation*: for every texel cell `(i, j)` the
    /// box overlaps, `texel_ext(i, j) * overlap_x_raw * overlap_y_raw`, in integers. Zero for an
    /// empty or inverted box. Cost is the number of cells overlapped.
    pub fn exact_integral_direct(&self, mode: RefMode, b: [i64; 4], f: u32, c: usize) -> u128 {
        let [x0, y0, x1, y1] = b.map(|v| v as i128);
        if x1 <= x0 || y1 <= y0 {
            return 0;
        }
        let s = 1i128 << f;
        let cells = |lo: i128, hi: i128| lo.div_euclid(s)..(hi + s - 1).div_euclid(s);
        let overlap = |lo: i128, hi: i128, i: i128| (hi.min((i + 1) * s) - lo.max(i * s)).max(0);
        let mut sum: u128 = 0;
        for j in cells(y0, y1) {
            let oy = overlap(y0, y1, j) as u128;
            for i in cells(x0, x1) {
                let ox = overlap(x0, x1, i) as u128;
                let t = self.texel_ext(mode, i as i64, j as i64, c) as u128;
                sum += t * ox * oy;
            }
        }
        sum
    }

    /// The exact integral over the raw box, channel `c`, scaled by `2^2F`, via per-texel axis
    /// weights: `sum over (i, j) in the texture of t(i, j) * wx(i) * wy(j)` with
    /// [`axis_weights`] (the total overlap of the box's interval with every cell of the extended
    /// axis that shows texel `i`). Exact, and `O(w h)` however many periods the box spans.
    /// Panics if the result does not fit `u128`.
    pub fn exact_integral(&self, mode: RefMode, b: [i64; 4], f: u32, c: usize) -> u128 {
        self.exact_integrals(mode, b, f)[c]
    }

    /// [`RefTexture::exact_integral`] for every channel (panics if a value overflows `u128`).
    pub fn exact_integrals(&self, mode: RefMode, b: [i64; 4], f: u32) -> Vec<u128> {
        self.exact_integrals_checked(mode, b, f)
            .expect("reference integral overflows u128")
    }

    /// [`RefTexture::exact_integrals`], or `None` if an integral (scaled by `2^2F`) does not fit
    /// `u128`.
    pub fn exact_integrals_checked(&self, mode: RefMode, b: [i64; 4], f: u32) -> Option<Vec<u128>> {
        let [x0, y0, x1, y1] = b;
        let mut out = vec![0u128; self.channels];
        if x1 <= x0 || y1 <= y0 {
            return Some(out);
        }
        let wx = axis_weights(mode, x0, x1, self.width, f);
        let wy = axis_weights(mode, y0, y1, self.height, f);
        for (j, &wyj) in wy.iter().enumerate() {
            if wyj == 0 {
                continue;
            }
            for (i, &wxi) in wx.iter().enumerate() {
                if wxi == 0 {
                    continue;
                }
                let w = wxi.checked_mul(wyj)?;
                for (c, o) in out.iter_mut().enumerate() {
                    let t = self.texel(i, j, c) as u128;
                    *o = o.checked_add(t.checked_mul(w)?)?;
                }
            }
        }
        Some(out)
    }

    /// The exact sum over an integer box (`F = 0`), every channel.
    pub fn int_sums(&self, mode: RefMode, r: [i32; 4]) -> Vec<u128> {
        self.exact_integrals(mode, r.map(|v| v as i64), 0)
    }

    /// The naive table: `S(i, j) = t(i, j) + S(i-1, j) + S(i, j-1) - S(i-1, j-1)` (three additive
    /// operations per entry and channel), inclusive layout like texsat's (`w * h * C` entries,
    /// entry `(i, j)` is the sum over `i' <= i`, `j' <= j`).
    pub fn naive_table(&self) -> Vec<u128> {
        let (w, h, ch) = (self.width, self.height, self.channels);
        let mut t = vec![0u128; w * h * ch];
        let at = |t: &[u128], i: usize, j: usize, c: usize| t[(j * w + i) * ch + c];
        for j in 0..h {
            for i in 0..w {
                for c in 0..ch {
                    let left = if i > 0 { at(&t, i - 1, j, c) } else { 0 };
                    let up = if j > 0 { at(&t, i, j - 1, c) } else { 0 };
                    let diag = if i > 0 && j > 0 {
                        at(&t, i - 1, j - 1, c)
                    } else {
                        0
                    };
                    t[(j * w + i) * ch + c] = self.texel(i, j, c) as u128 + left + up - diag;
                }
            }
        }
        t
    }
}

/// Total overlap, in raw units (`2^-F` texels), of the raw interval `[lo, hi)` with the cells of
/// the extended axis that show each texel `0..n` under `mode`. Closed form (no loop over
/// periods): for the periodic modes the overlap of `[0, x)` with the union of a cell's periodic
/// copies is `q * 2^F + clamp(r - a, 0, 2^F)` (`x = q * period + r`, `a` the cell's offset), a
/// signed prefix measure valid for negative `x` too, and the weight is its difference. Empty or
/// inverted intervals give all zeros.
pub fn axis_weights(mode: RefMode, lo: i64, hi: i64, n: usize, f: u32) -> Vec<u128> {
    let (lo, hi) = (lo as i128, hi as i128);
    let mut out = vec![0u128; n];
    if hi <= lo {
        return out;
    }
    let s = 1i128 << f;
    let nn = n as i128;
    let overlap = |a: i128, b: i128| (hi.min(b) - lo.max(a)).max(0);
    // Signed prefix measure of [0, x) intersected with {cell at offset a} + k * period.
    let prefix = |x: i128, a: i128, period: i128| {
        x.div_euclid(period) * s + (x.rem_euclid(period) - a).clamp(0, s)
    };
    for (t, o) in out.iter_mut().enumerate() {
        let t = t as i128;
        let v = match mode {
            RefMode::Border => overlap(t * s, (t + 1) * s),
            RefMode::Clamp => {
                let a = if t == 0 { i128::MIN } else { t * s };
                let b = if t == nn - 1 { i128::MAX } else { (t + 1) * s };
                overlap(a, b)
            }
            RefMode::Repeat => {
                let p = nn * s;
                prefix(hi, t * s, p) - prefix(lo, t * s, p)
            }
            RefMode::Mirror => {
                let p = 2 * nn * s;
                let (a1, a2) = (t * s, (2 * nn - 1 - t) * s);
                prefix(hi, a1, p) - prefix(lo, a1, p) + prefix(hi, a2, p) - prefix(lo, a2, p)
            }
        };
        assert!(v >= 0, "negative axis weight");
        *o = v as u128;
    }
    out
}

/// The first texel (row-major `y`, then `x`, then channel) that an inclusive table implies
/// outside `[0, 2^texel_bits - 1]`, or `None` if the table is the SAT of a valid texture.
/// Implied texel: `S(i,j) - S(i-1,j) - S(i,j-1) + S(i-1,j-1)` (zero outside the table).
pub fn invalid_texels(
    table: &[u128],
    width: usize,
    height: usize,
    channels: usize,
    texel_bits: u32,
) -> Vec<(usize, usize, usize)> {
    let max = (1i128 << texel_bits) - 1;
    let at = |i: usize, j: usize, c: usize| table[(j * width + i) * channels + c] as i128;
    let mut bad = Vec::new();
    for j in 0..height {
        for i in 0..width {
            for c in 0..channels {
                let left = if i > 0 { at(i - 1, j, c) } else { 0 };
                let up = if j > 0 { at(i, j - 1, c) } else { 0 };
                let diag = if i > 0 && j > 0 {
                    at(i - 1, j - 1, c)
                } else {
                    0
                };
                let t = at(i, j, c) - left - up + diag;
                if !(0..=max).contains(&t) {
                    bad.push((i, j, c));
                }
            }
        }
    }
    bad
}

/// An unsigned 256-bit integer as `(hi, lo)`, ordered numerically (for exact comparisons of
/// products of two `u128`s).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct U256 {
    /// High 128 bits.
    pub hi: u128,
    /// Low 128 bits.
    pub lo: u128,
}

impl U256 {
    /// `a * b`, exactly.
    pub fn mul(a: u128, b: u128) -> Self {
        let mask = u64::MAX as u128;
        let (a1, a0) = (a >> 64, a & mask);
        let (b1, b0) = (b >> 64, b & mask);
        let p00 = a0 * b0;
        let p01 = a0 * b1;
        let p10 = a1 * b0;
        let p11 = a1 * b1;
        let mid = (p00 >> 64) + (p01 & mask) + (p10 & mask);
        let lo = (p00 & mask) | ((mid & mask) << 64);
        let hi = p11 + (p01 >> 64) + (p10 >> 64) + (mid >> 64);
        U256 { hi, lo }
    }

    /// `a * 2^k` for `k < 128`, exactly.
    pub fn shl(a: u128, k: u32) -> Self {
        assert!(k < 128);
        if k == 0 {
            U256 { hi: 0, lo: a }
        } else {
            U256 {
                hi: a >> (128 - k),
                lo: a << k,
            }
        }
    }

    /// `a * 2^k` for any `k` whose result fits 256 bits (panics otherwise), exactly.
    pub fn shl_any(a: u128, k: u32) -> Self {
        let bits = 128 - a.leading_zeros();
        assert!(a == 0 || bits + k <= 256, "2^{k} * a overflows 256 bits");
        if a == 0 {
            U256 { hi: 0, lo: 0 }
        } else if k < 128 {
            Self::shl(a, k)
        } else {
            U256 {
                hi: a << (k - 128),
                lo: 0,
            }
        }
    }

    /// The value as `f64` (rounded).
    pub fn to_f64(self) -> f64 {
        self.hi as f64 * 2f64.powi(128) + self.lo as f64
    }

    /// `|a - b|`.
    pub fn abs_diff(a: Self, b: Self) -> Self {
        let (big, small) = if a >= b { (a, b) } else { (b, a) };
        let (lo, borrow) = big.lo.overflowing_sub(small.lo);
        U256 {
            hi: big.hi - small.hi - borrow as u128,
            lo,
        }
    }
}

/// Whether `m` is `round(sum * 2^g / area)` rounded to nearest with ties up, checked by the
/// defining inequality in exact integers: `(2m - 1) area <= sum * 2^(g+1) < (2m + 1) area`.
/// Any `g` for which `sum * 2^(g+1)` fits 256 bits; any `m` below `2^128`.
pub fn is_rounded_mean(sum: u128, area: u128, g: u32, m: u128) -> bool {
    assert!(area > 0);
    // (2m +- 1) area = 2 m area +- area, formed in 256 bits for any m (m area < 2^256).
    let twice = |v: U256| U256 {
        hi: (v.hi << 1) | (v.lo >> 127),
        lo: v.lo << 1,
    };
    let add = |a: U256, b: u128| {
        let (lo, carry) = a.lo.overflowing_add(b);
        U256 {
            hi: a.hi + carry as u128,
            lo,
        }
    };
    let n2 = U256::shl_any(sum, g + 1);
    let two_m_area = twice(U256::mul(m, area));
    let upper = add(two_m_area, area);
    let lower_ok = m == 0 || U256::abs_diff(two_m_area, U256 { hi: 0, lo: area }) <= n2;
    lower_ok && n2 < upper
}

/// `|m / 2^g - sum / area|` (a fixed-point mean against the exact rational mean), computed from
/// the exact integer `|m * area - sum * 2^g|` and divided in `f64` at the end.
pub fn mean_error(sum: u128, area: u128, g: u32, m: u128) -> f64 {
    let a = U256::mul(m, area);
    let b = U256::shl(sum, g);
    U256::abs_diff(a, b).to_f64() / (area as f64 * 2f64.powi(g as i32))
}

/// The one random generator of the host tests and benches: ChaCha8, a stream cipher, so the
/// inputs are well mixed, and seeded from a constant, so every run sees the same inputs. Use
/// [`rng`] to make one, [`RngExt::random_range`] for bounded values and [`Rng::next_u64`] for
/// raw bits.
pub type TestRng = rand_chacha::ChaCha8Rng;

/// The generator for `seed` (every test and bench names its own constant seed).
pub fn rng(seed: u64) -> TestRng {
    <TestRng as rand::SeedableRng>::seed_from_u64(seed)
}

pub use rand::{Rng, RngExt};

/// `n` bytes from [`rng`]`(seed)`: uniform 8-bit texels for the tests and benches that take
/// a plain texel buffer.
pub fn random_bytes(n: usize, seed: u64) -> Vec<u8> {
    let mut bytes = vec![0u8; n];
    rng(seed).fill_bytes(&mut bytes);
    bytes
}

/// A texel type the references can produce from `u32` (texsat's `u8` and `u16`).
pub trait RefTexel: Texel + Copy {
    /// The value as this type; panics if it does not fit.
    fn from_u32(v: u32) -> Self;
}

impl RefTexel for u8 {
    fn from_u32(v: u32) -> Self {
        u8::try_from(v).expect("texel does not fit u8")
    }
}

impl RefTexel for u16 {
    fn from_u32(v: u32) -> Self {
        u16::try_from(v).expect("texel does not fit u16")
    }
}

/// Builds texsat's table of `tex` (texels converted to `T`) into `storage` with
/// [`Sat::build`]. `C` must equal `tex.channels`.
pub fn build_sat<'a, T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
    storage: &'a mut [E],
) -> Result<Sat<'a, E, C>, Error> {
    assert_eq!(tex.channels, C, "channel count");
    let texels = tex.texels_as::<T>();
    let texture = Texture::<T, C>::new(&texels, tex.width, tex.height)?;
    Sat::build(&texture, storage)
}

/// [`build_sat`] with [`Sat::build_checked`].
pub fn build_sat_checked<'a, T: RefTexel, E: Entry, const C: usize>(
    tex: &RefTexture,
    storage: &'a mut [E],
) -> Result<Sat<'a, E, C>, Error> {
    assert_eq!(tex.channels, C, "channel count");
    let texels = tex.texels_as::<T>();
    let texture = Texture::<T, C>::new(&texels, tex.width, tex.height)?;
    Sat::build_checked(&texture, storage)
}

/// The raw coordinate `raw` as the fixed type `X`, or `None` if it does not fit.
pub fn fixed_from_raw<X: Fixed>(raw: i64) -> Option<X> {
    X::Bits::try_from(raw).ok().map(X::from_bits)
}

/// The box with raw corners `[x0, y0, x1, y1]` as a `Rect<X>` (panics if a corner does not fit).
pub fn rect_from_raw<X: Fixed>(b: [i64; 4]) -> Rect<X> {
    let [x0, y0, x1, y1] = b.map(|v| fixed_from_raw::<X>(v).expect("raw coordinate fits X"));
    Rect::new(x0, y0, x1, y1)
}

/// [`Sat::box_sum_int`] under a run-time mode, in the table's own result word.
pub fn sum_int_native<E: Entry, const C: usize, K: Counter>(
    sat: &Sat<'_, E, C>,
    r: [i32; 4],
    mode: RefMode,
    k: &mut K,
) -> Result<BoxSum<WideOfEntry<E>, C>, Error> {
    let r = Rect::new(r[0], r[1], r[2], r[3]);
    match mode {
        RefMode::Border => sat.box_sum_int(&r, Border, k),
        RefMode::Clamp => sat.box_sum_int(&r, ClampToEdge, k),
        RefMode::Repeat => sat.box_sum_int(&r, Repeat, k),
        RefMode::Mirror => sat.box_sum_int(&r, MirroredRepeat, k),
    }
}

/// [`Sat::box_sum_int`] under a run-time mode, the sums as `u128` (for exact comparisons with
/// the `u128` references).
pub fn sum_int<E: Entry, const C: usize, K: Counter>(
    sat: &Sat<'_, E, C>,
    r: [i32; 4],
    mode: RefMode,
    k: &mut K,
) -> Result<BoxSum<u128, C>, Error> {
    sum_int_native(sat, r, mode, k).map(|s| s.to_u128())
}

/// [`Sat::box_sum`] under a run-time form and mode, in the table's own result word (so a mean
/// taken from it runs the word's own division, e.g. the `u64` one for `u16`/`u32` tables).
pub fn sum_fixed_native<X: Coord, E: Entry, const C: usize, K: Counter>(
    sat: &Sat<'_, E, C>,
    r: &Rect<X>,
    form: RefForm,
    mode: RefMode,
    k: &mut K,
) -> Result<BoxSum<WideOfEntry<E>, C>, Error> {
    macro_rules! go {
        ($form:expr) => {
            match mode {
                RefMode::Border => sat.box_sum(r, $form, Border, k),
                RefMode::Clamp => sat.box_sum(r, $form, ClampToEdge, k),
                RefMode::Repeat => sat.box_sum(r, $form, Repeat, k),
                RefMode::Mirror => sat.box_sum(r, $form, MirroredRepeat, k),
            }
        };
    }
    match form {
        RefForm::Paper => go!(Paper),
        RefForm::Stable => go!(Stable),
    }
}

/// [`Sat::box_sum`] under a run-time form and mode, the sums as `u128`.
pub fn sum_fixed<X: Coord, E: Entry, const C: usize, K: Counter>(
    sat: &Sat<'_, E, C>,
    r: &Rect<X>,
    form: RefForm,
    mode: RefMode,
    k: &mut K,
) -> Result<BoxSum<u128, C>, Error> {
    sum_fixed_native(sat, r, form, mode, k).map(|s| s.to_u128())
}

/// The result word of a table with entries `E` (`u64`, or `u128` for `u64` entries).
pub type WideOfEntry<E> = <<E as Entry>::Acc as Acc>::Wide;

/// [`Sat::box_mean_shortcut`] under a run-time form and mode.
pub fn mean_shortcut<X: Coord, E: Entry, const C: usize, K: Counter>(
    sat: &Sat<'_, E, C>,
    r: &Rect<X>,
    form: RefForm,
    mode: RefMode,
    shortcut: &Shortcut,
    g: u32,
    k: &mut K,
) -> Result<ShortcutMean<u128, C>, Error> {
    macro_rules! go {
        ($form:expr) => {
            match mode {
                RefMode::Border => sat.box_mean_shortcut(r, $form, Border, shortcut, g, k),
                RefMode::Clamp => sat.box_mean_shortcut(r, $form, ClampToEdge, shortcut, g, k),
                RefMode::Repeat => sat.box_mean_shortcut(r, $form, Repeat, shortcut, g, k),
                RefMode::Mirror => sat.box_mean_shortcut(r, $form, MirroredRepeat, shortcut, g, k),
            }
            .map(|s| s.to_u128())
        };
    }
    match form {
        RefForm::Paper => go!(Paper),
        RefForm::Stable => go!(Stable),
    }
}

/// The accumulator value bits of a table with `entry_bits`-bit entries, as the core's docs state
/// them (`u16` tables compute in `i32`, `u32` in `i64`, `u64` in `i128`): 31, 63 or 127.
pub fn acc_value_bits_for_entry(entry_bits: u32) -> u32 {
    match entry_bits {
        0..=16 => 31,
        17..=32 => 63,
        _ => 127,
    }
}

/// The result word's bits of a table with `entry_bits`-bit entries: 64 (`u16`, `u32`), or 128
/// (`u64`).
pub fn wide_bits_for_entry(entry_bits: u32) -> u32 {
    if entry_bits <= 32 {
        64
    } else {
        128
    }
}

/// Whether a Repeat or Mirror interval `[lo, hi)` (raw, `F = f`, `lo < hi`, not inside
/// `[0, n 2^F]`) is beyond what the core places: it computes the interval's end relative to
/// the (half-)period `p = n 2^F` that `lo` falls in, `(lo mod p) + (hi - lo)`, in `u64`, and
/// refuses with `CoordinateOutOfRange` when that overflows (widths within `p` of `2^64`).
/// (The core's documented error for this case names integer corners only; for fractional
/// corners this refusal was first seen by `tests/extremes.rs`' `i64` limits.)
pub fn periodic_overflow(mode: RefMode, lo: i64, hi: i64, n: usize, f: u32) -> bool {
    if !matches!(mode, RefMode::Repeat | RefMode::Mirror) || hi <= lo {
        return false;
    }
    let p = (n as i128) << f;
    if lo >= 0 && (hi as i128) <= p {
        return false;
    }
    let r0 = (lo as i128).rem_euclid(p);
    r0 + (hi as i128 - lo as i128) > u64::MAX as i128
}

/// What a flat table's lookup must return for the raw box `b` at `F = f` under `mode`, from
/// the documented rules alone (independent of the lookup code): `Err(InvertedBox)` for an
/// inverted box; all zeros for a zero-width or zero-height box and for a Border box clipped
/// away; `Err(TooWide { LookupAccumulator, needed, acc })` when the form's intermediates need
/// more than the accumulator's value bits (`total_bits + 2F` for Paper, one more for Stable,
/// none for integer corners: `form = None`; `total_bits` is the largest channel total's bits);
/// `Err(TooWide { LookupAccumulator, wide + 1, wide })` when an exact sum does not fit the
/// `wide_bits` result word; else the exact sums. Before the accumulator check,
/// `Err(CoordinateOutOfRange)` for a Repeat or Mirror box that [`periodic_overflow`] says the
/// core cannot place (raw widths near `2^64`, only reachable at the `i64` limits).
pub fn expected_sums(
    tex: &RefTexture,
    mode: RefMode,
    b: [i64; 4],
    f: u32,
    form: Option<RefForm>,
    acc_value_bits: u32,
    wide_bits: u32,
) -> Result<Vec<u128>, Error> {
    let [x0, y0, x1, y1] = b;
    if x1 < x0 || y1 < y0 {
        return Err(Error::InvertedBox);
    }
    let zeros = vec![0u128; tex.channels];
    if x1 == x0 || y1 == y0 {
        return Ok(zeros);
    }
    if mode == RefMode::Border {
        let clipped_away = |lo: i64, hi: i64, n: usize| {
            let end = (n as i128) << f;
            (hi as i128) <= 0 || (lo as i128) >= end
        };
        if clipped_away(x0, x1, tex.width) || clipped_away(y0, y1, tex.height) {
            return Ok(zeros);
        }
    }
    if periodic_overflow(mode, x0, x1, tex.width, f)
        || periodic_overflow(mode, y0, y1, tex.height, f)
    {
        return Err(Error::CoordinateOutOfRange);
    }
    if let Some(form) = form {
        let total_bits = (0..tex.channels)
            .map(|c| texsat::width::bits_of(tex.total(c)))
            .max()
            .unwrap_or(0);
        let extra = match form {
            RefForm::Paper => 0,
            RefForm::Stable => 1,
        };
        let needed = total_bits + 2 * f + extra;
        if needed > acc_value_bits {
            return Err(Error::TooWide {
                what: texsat::Quantity::LookupAccumulator,
                bits_needed: needed,
                bits_available: acc_value_bits,
            });
        }
    }
    let too_wide = Error::TooWide {
        what: texsat::Quantity::LookupAccumulator,
        bits_needed: wide_bits + 1,
        bits_available: wide_bits,
    };
    let sums = tex.exact_integrals_checked(mode, b, f).ok_or(too_wide)?;
    if wide_bits < 128 && sums.iter().any(|&v| v >> wide_bits != 0) {
        return Err(too_wide);
    }
    Ok(sums)
}

/// Proptest strategies (dimensions first, then texels via `prop_flat_map`, as in imageproc's
/// `proptest_utils`).
pub mod strategies {
    use super::*;

    /// Texture dimensions up to `max_w x max_h`, with the degenerate shapes `1 x N` and `N x 1`
    /// drawn often.
    pub fn arb_dims(max_w: usize, max_h: usize) -> impl Strategy<Value = (usize, usize)> {
        prop_oneof![
            3 => (1..=max_w, 1..=max_h),
            1 => (Just(1usize), 1..=max_h),
            1 => (1..=max_w, Just(1usize)),
        ]
    }

    /// One texel value in `0..=max`, with the extremes `0` and `max` drawn often.
    pub fn arb_texel(max: u32) -> impl Strategy<Value = u32> {
        prop_oneof![
            4 => 0..=max,
            1 => Just(0u32),
            1 => Just(max),
        ]
    }

    /// A texture of at most `max_w x max_h` texels, `channels` channels, texels in `0..=max`:
    /// dimensions first, then exactly `w * h * channels` texels.
    pub fn arb_texture(
        max_w: usize,
        max_h: usize,
        channels: usize,
        max: u32,
    ) -> impl Strategy<Value = RefTexture> {
        arb_dims(max_w, max_h).prop_flat_map(move |(w, h)| {
            prop::collection::vec(arb_texel(max), w * h * channels)
                .prop_map(move |t| RefTexture::new(w, h, channels, t))
        })
    }

    /// A raw interval `[lo, hi)` (`lo <= hi`) on an axis of `n` texels at `F = f` fractional
    /// bits: inside the texture, within three periods of it, or anywhere within
    /// `far_periods` periods and up to `far_periods` periods long. Every coordinate lies in
    /// `[raw_min, raw_max]` (the range of the fixed type under test).
    pub fn arb_interval(
        n: usize,
        f: u32,
        far_periods: i64,
        raw_min: i64,
        raw_max: i64,
    ) -> impl Strategy<Value = (i64, i64)> {
        let end = (n as i64) << f;
        let near = 3 * end;
        let far = far_periods.max(1) * end;
        let fit = move |(a, b): (i64, i64)| {
            let lo = a.min(b).clamp(raw_min, raw_max);
            let hi = a.max(b).clamp(raw_min, raw_max);
            (lo, hi)
        };
        prop_oneof![
            3 => (0..=end, 0..=end).prop_map(fit),
            3 => (-near..=end + near, -near..=end + near).prop_map(fit),
            1 => (-far..=far, 0..=far).prop_map(move |(lo, len)| fit((lo, lo.saturating_add(len)))),
            1 => (0..=end).prop_map(move |a| fit((a, a))),
        ]
    }

    /// A run-time boundary mode.
    pub fn arb_mode() -> impl Strategy<Value = RefMode> {
        prop::sample::select(RefMode::ALL.to_vec())
    }

    /// A run-time form.
    pub fn arb_form() -> impl Strategy<Value = RefForm> {
        prop::sample::select(RefForm::ALL.to_vec())
    }
}

pub mod ewa;
pub mod filter_ref_mip;
pub mod filter_ref_ripdip;
pub mod filter_ref_tentvar;
pub mod footprint;
pub mod scenes;
pub mod stability;
