//! Numerical stability on stiff and extreme cases: floating-point summed-area tables built as on
//! a GPU against texsat's exact integer tables.
//!
//! # What is compared
//!
//! * **float32 SAT, GPU build.** Green ("Summed Area Tables using Graphics Hardware", NVIDIA)
//!   builds the table with two passes of render-to-texture, one line primitive per row or column,
//!   each fragment adding its texel to the running value to its left (below). Every addition is
//!   one `f32` rounding. [`FloatSat::build`] does exactly that, sequentially, in the order the
//!   issue names (rows first, then columns, [`BuildOrder::RowsThenColumns`]); Green's slide sums
//!   columns first ([`BuildOrder::ColumnsThenRows`], shown once on the noise texture). The
//!   texels are integer-valued floats (`0.0..=255.0`, an unnormalised `R32F` upload), so the
//!   input itself is exact and every error comes from the table.
//! * **Lookup.** Green's `texRECT_summedArea`: four reads of the corner function, each a
//!   bilinear read of the `(w + 1) x (h + 1)` grid of corner values (exact interpolation for a
//!   piecewise-constant texture; here evaluated in full `f32`, which is kinder than hardware's
//!   8-bit filter weights), `r = S11 - S10 - S01 + S00`, mean `r / (a b)`, all in `f32`.
//! * **float32 centred.** The same, on texels minus an offset `c` (the texture's mean, or 128,
//!   Hensley et al.'s "subtract 0.5"); the lookup adds the offset back: mean `r / (a b) + c`
//!   (the same as adding `c a b` to the sum before dividing). Centring keeps the table values
//!   near zero, so they keep their low bits.
//! * **f64 SAT.** The same build and lookup in `f64`. For 8-bit texels every partial sum of an
//!   integer table is an integer below `2^53`, so the f64 table is exact; only fractional
//!   lookups (bilinear weights, the division) round.
//! * **texsat.** [`texsat::Sat`] with `u32` entries (`u64` in the size curve): the 4-read
//!   integer lookup ([`Sat::box_sum_int`]) and the 16-read [`texsat::Stable`] lookup at `F = 8`
//!   ([`Sat::box_sum`] with `I24F8` corners), under [`texsat::Repeat`] for the repeated-texture
//!   cases. Sums are exact integers; the mean is reported as the `f64` nearest the exact
//!   rational, exactly as the reference, so texsat's error is 0 where the sum is exact.
//!
//! Every box is given exactly, in fixed point with 8 fractional bits (raw = texels x 256); the
//! float methods receive its corners converted to their type (an `f32` rounds coordinates above
//! `2^16` texels: part of what a GPU does). The reference mean is the exact integral (integer
//! direct summation, or per-texel periodic weights for [`RefMode::Repeat`]) divided by the exact
//! area, correctly rounded to `f64`.
//!
//! Errors are of box **means** in texel units (0..=255): the maximum and RMS absolute error over
//! a case's boxes, and the maximum relative error `|error| / max(exact mean, 1)`.

use std::ops::{Add, Div, Mul, Sub};

use fixed::types::I24F8;
use texsat::{ClampToEdge, NoCount, Rect, Repeat, Sat, Stable, Texture};

use crate::scenes::SceneSize;
use crate::{rect_from_raw, RefMode, RefTexture, RngExt, TestRng};

/// Fractional bits of every box in the study (`F = 8`, texsat's `I24F8`).
pub const FRAC_BITS: u32 = 8;
const ONE: i64 = 1 << FRAC_BITS;

/// One method on one case: errors of box means against the exact mean.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityRow {
    /// The case: texture, box shape and placement, e.g. `all-255 4104x4104: 1x1 boxes at the far
    /// corner`.
    pub case: String,
    /// The method, e.g. `float32 SAT (GPU build)` or `texsat u32 4-read`.
    pub method: String,
    /// The texture's side in texels (the period for the repeated cases).
    pub size: usize,
    /// The largest `|mean - exact mean|` over the case's boxes, in texel units.
    pub max_abs_error: f64,
    /// The root mean square of `mean - exact mean` over the case's boxes.
    pub rms_error: f64,
    /// The largest `|mean - exact mean| / max(exact mean, 1)`.
    pub max_rel_error: f64,
    /// The result in plain words: the worst box, what came out, the correct bits left.
    pub note: String,
}

/// One method's error against the table size (the float32-error plot).
#[derive(Debug, Clone, PartialEq)]
pub struct Float32Curve {
    /// The method (the same names as [`StabilityRow::method`], plus `texsat u64 ...`).
    pub method: String,
    /// `(table side, max abs error of box means)`, by increasing side.
    pub points: Vec<(usize, f64)>,
}

/// The order of the two prefix-sum passes of a GPU table build.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildOrder {
    /// Running sums along every row, then down every column (the order).
    RowsThenColumns,
    /// Down every column, then along every row (Green's slide: "sum columns first").
    ColumnsThenRows,
}

/// A floating-point type the study builds tables in (`f32` or `f64`).
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
{
    /// Significand bits, including the implicit one (24 or 53).
    const SIGNIFICAND_BITS: u32;
    /// Zero.
    const ZERO: Self;
    /// The nearest value to `v`.
    fn from_f64(v: f64) -> Self;
    /// The value as `f64` (exact).
    fn to_f64(self) -> f64;
    /// The largest integer not above the value.
    fn floor(self) -> Self;
}

impl Real for f32 {
    const SIGNIFICAND_BITS: u32 = 24;
    const ZERO: Self = 0.0;
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    fn to_f64(self) -> f64 {
        self as f64
    }
    fn floor(self) -> Self {
        f32::floor(self)
    }
}

impl Real for f64 {
    const SIGNIFICAND_BITS: u32 = 53;
    const ZERO: Self = 0.0;
    fn from_f64(v: f64) -> Self {
        v
    }
    fn to_f64(self) -> f64 {
        self
    }
    fn floor(self) -> Self {
        f64::floor(self)
    }
}

/// A floating-point summed-area table built as on a GPU: the corner function
/// `S(x, y) = sum of (t - offset)` over `[0, x) x [0, y)` at the integer grid points
/// `0..=w x 0..=h` (row and column 0 are zero), built by two sequential prefix-sum passes with
/// one rounding per addition.
#[derive(Debug, Clone)]
pub struct FloatSat<R: Real> {
    w: usize,
    h: usize,
    offset: R,
    grid: Vec<R>,
}

impl<R: Real> FloatSat<R> {
    /// Builds the table of `texels` (row-major `w x h`, one channel) minus `offset`, in
    /// `order`: each pass is a running sum along its lines, `acc = acc + value` rounded once per
    /// step, as Green's line primitives do (the column pass is done row after row, which
    /// performs the same additions in the same order per column).
    pub fn build(texels: &[u8], w: usize, h: usize, offset: f64, order: BuildOrder) -> Self {
        assert!(w > 0 && h > 0 && texels.len() == w * h, "texture size");
        let w1 = w + 1;
        let off = R::from_f64(offset);
        let mut grid = vec![R::ZERO; w1 * (h + 1)];
        let value = |i: usize, j: usize| R::from_f64(texels[j * w + i] as f64) - off;
        match order {
            BuildOrder::RowsThenColumns => {
                for j in 0..h {
                    let mut acc = R::ZERO;
                    for i in 0..w {
                        acc = acc + value(i, j);
                        grid[(j + 1) * w1 + i + 1] = acc;
                    }
                }
                for j in 1..h {
                    let (above, rest) = grid.split_at_mut((j + 1) * w1);
                    let above = &above[j * w1..];
                    for (d, &a) in rest[..w1].iter_mut().zip(above).skip(1) {
                        *d = *d + a;
                    }
                }
            }
            BuildOrder::ColumnsThenRows => {
                for j in 0..h {
                    for i in 0..w {
                        let a = grid[j * w1 + i + 1];
                        grid[(j + 1) * w1 + i + 1] = a + value(i, j);
                    }
                }
                for j in 1..=h {
                    let row = &mut grid[j * w1..(j + 1) * w1];
                    for i in 2..w1 {
                        row[i] = row[i] + row[i - 1];
                    }
                }
            }
        }
        FloatSat {
            w,
            h,
            offset: off,
            grid,
        }
    }

    /// The table's width.
    pub fn width(&self) -> usize {
        self.w
    }

    /// The table's height.
    pub fn height(&self) -> usize {
        self.h
    }

    /// The stored corner value at grid point `(i, j)`, `0 <= i <= w`, `0 <= j <= h`.
    pub fn at(&self, i: usize, j: usize) -> R {
        self.grid[j * (self.w + 1) + i]
    }

    /// The corner function at `(x, y)` (clamped to `[0, w] x [0, h]`) by a bilinear read of the
    /// grid: `lerp(p, q, a) = p + (q - p) a` along x on two grid rows, then along y. Integer
    /// coordinates read one stored value exactly.
    pub fn corner(&self, x: R, y: R) -> R {
        let (i, a) = split(x, self.w);
        let (j, b) = split(y, self.h);
        let lerp = |p: R, q: R, t: R| p + (q - p) * t;
        let top = lerp(self.at(i, j), self.at(i + 1, j), a);
        let bottom = lerp(self.at(i, j + 1), self.at(i + 1, j + 1), a);
        lerp(top, bottom, b)
    }

    /// The mean over the box `[x0, x1) x [y0, y1)` inside the table: Green's decode
    /// `((S11 - S10) - S01 + S00) / ((x1 - x0)(y1 - y0))`, plus the offset.
    pub fn box_mean(&self, x0: R, y0: R, x1: R, y1: R) -> R {
        let r =
            self.corner(x1, y1) - self.corner(x1, y0) - self.corner(x0, y1) + self.corner(x0, y0);
        r / ((x1 - x0) * (y1 - y0)) + self.offset
    }

    /// The corner function of the repeated texture at any `(x, y)`, with the period arithmetic
    /// a shader would do: `q = floor(x / w)`, `r = x - q w` (clamped to `[0, w]`), and
    /// `S_ext = qx qy T + qx S(w, ry) + qy S(rx, h) + S(rx, ry)` (`T = S(w, h)`), all in `R`.
    pub fn corner_repeat(&self, x: R, y: R) -> R {
        let (qx, rx) = wrap(x, self.w);
        let (qy, ry) = wrap(y, self.h);
        let wr = R::from_f64(self.w as f64);
        let hr = R::from_f64(self.h as f64);
        let total = self.at(self.w, self.h);
        qx * qy * total + qx * self.corner(wr, ry) + qy * self.corner(rx, hr) + self.corner(rx, ry)
    }

    /// [`FloatSat::box_mean`] over the repeated texture (any box), from [`FloatSat::corner_repeat`].
    pub fn box_mean_repeat(&self, x0: R, y0: R, x1: R, y1: R) -> R {
        let r =
            self.corner_repeat(x1, y1) - self.corner_repeat(x1, y0) - self.corner_repeat(x0, y1)
                + self.corner_repeat(x0, y0);
        r / ((x1 - x0) * (y1 - y0)) + self.offset
    }
}

/// Cell index `i <= n - 1` and fraction of a coordinate clamped to `[0, n]`.
fn split<R: Real>(x: R, n: usize) -> (usize, R) {
    let nr = R::from_f64(n as f64);
    let x = if x < R::ZERO {
        R::ZERO
    } else if x > nr {
        nr
    } else {
        x
    };
    let fl = x.floor();
    let i = fl.to_f64() as usize;
    if i >= n {
        (n - 1, x - R::from_f64((n - 1) as f64))
    } else {
        (i, x - fl)
    }
}

/// Whole periods and remainder of `x` on an axis of period `n`, in `R`.
fn wrap<R: Real>(x: R, n: usize) -> (R, R) {
    let nr = R::from_f64(n as f64);
    let q = (x / nr).floor();
    let r = x - q * nr;
    let r = if r < R::ZERO {
        R::ZERO
    } else if r > nr {
        nr
    } else {
        r
    };
    (q, r)
}

/// The largest square `n x n` of `texel_bits`-bit texels whose worst-case table fits `u32`
/// entries (texsat's width check, [`texsat::width::entry_bits_worst_case`]): 4104 for 8 bits.
pub fn largest_u32_square(texel_bits: u32) -> usize {
    let fits = |n: usize| texsat::width::entry_bits_worst_case(texel_bits, n, n) <= 32;
    let (mut lo, mut hi) = (1usize, 1usize << 17);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// A one-channel 8-bit texture.
struct Tex {
    w: usize,
    h: usize,
    t: Vec<u8>,
}

impl Tex {
    fn constant(n: usize, v: u8) -> Self {
        Tex {
            w: n,
            h: n,
            t: vec![v; n * n],
        }
    }

    /// Texels uniform in `lo..=hi`, reproducible from `seed`.
    fn noise(n: usize, lo: u8, hi: u8, seed: u64) -> Self {
        let mut rng = crate::rng(seed);
        let span = (hi - lo) as u64 + 1;
        let t = (0..n * n)
            .map(|_| lo + rng.random_range(0..span) as u8)
            .collect();
        Tex { w: n, h: n, t }
    }

    fn mean(&self) -> f64 {
        self.t.iter().map(|&v| v as u64).sum::<u64>() as f64 / self.t.len() as f64
    }

    /// The exact integral over the in-range raw box (`F = 8`), scaled by `2^16`, by direct
    /// summation of every texel cell times its overlap.
    fn exact_sum(&self, b: [i64; 4]) -> u128 {
        let [x0, y0, x1, y1] = b;
        assert!(0 <= x0 && x0 < x1 && x1 <= self.w as i64 * ONE);
        assert!(0 <= y0 && y0 < y1 && y1 <= self.h as i64 * ONE);
        let overlap = |lo: i64, hi: i64, i: i64| (hi.min((i + 1) * ONE) - lo.max(i * ONE)).max(0);
        let mut sum = 0u128;
        for j in (y0 >> FRAC_BITS)..((y1 + ONE - 1) >> FRAC_BITS) {
            let oy = overlap(y0, y1, j) as u128;
            let row = &self.t[j as usize * self.w..];
            let mut rs = 0u128;
            for i in (x0 >> FRAC_BITS)..((x1 + ONE - 1) >> FRAC_BITS) {
                rs += row[i as usize] as u128 * overlap(x0, x1, i) as u128;
            }
            sum += rs * oy;
        }
        sum
    }

    fn to_ref(&self) -> RefTexture {
        RefTexture::new(
            self.w,
            self.h,
            1,
            self.t.iter().map(|&v| v as u32).collect(),
        )
    }
}

/// `sum / area` correctly rounded (to within an ulp) in `f64`: integer quotient plus remainder.
fn exact_mean(sum: u128, area: u128) -> f64 {
    (sum / area) as f64 + (sum % area) as f64 / area as f64
}

fn area_raw(b: [i64; 4]) -> u128 {
    ((b[2] - b[0]) as u128) * ((b[3] - b[1]) as u128)
}

fn to_real<R: Real>(raw: i64) -> R {
    R::from_f64(raw as f64 / ONE as f64)
}

/// A set of boxes (raw `F = 8` corners) evaluated as one case.
struct Case {
    name: String,
    boxes: Vec<[i64; 4]>,
    /// All corners are integers (the 4-read integer lookup applies).
    integer: bool,
    /// The repeated texture (boxes may lie anywhere).
    repeat: bool,
}

/// The methods of the study.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Method {
    F32,
    F32Mean,
    F32Half,
    F32ColumnsFirst,
    F64,
    Int4,
    Stable16,
    Int4U64,
    Stable16U64,
}

impl Method {
    fn name(self, repeat: bool) -> String {
        let r = if repeat { "Repeat " } else { "" };
        match self {
            Method::F32 => "float32 SAT (GPU build, rows then columns)".into(),
            Method::F32Mean => "float32 SAT centred on the texture mean".into(),
            Method::F32Half => "float32 SAT centred on 128".into(),
            Method::F32ColumnsFirst => "float32 SAT (GPU build, columns first as Green)".into(),
            Method::F64 => "f64 SAT".into(),
            Method::Int4 => format!("texsat {r}u32 4-read"),
            Method::Stable16 => format!("texsat {r}u32 16-read Stable F=8"),
            Method::Int4U64 => format!("texsat {r}u64 4-read"),
            Method::Stable16U64 => format!("texsat {r}u64 16-read Stable F=8"),
        }
    }

    fn significand_bits(self) -> Option<u32> {
        match self {
            Method::F32 | Method::F32Mean | Method::F32Half | Method::F32ColumnsFirst => Some(24),
            Method::F64 => Some(53),
            _ => None,
        }
    }

    fn is_texsat(self) -> bool {
        self.significand_bits().is_none()
    }

    fn integer_only(self) -> bool {
        matches!(self, Method::Int4 | Method::Int4U64)
    }
}

/// Error statistics over one case's boxes.
#[derive(Debug, Clone, Default)]
struct Stats {
    n: usize,
    max_abs: f64,
    sum_sq: f64,
    max_rel: f64,
    /// (box, exact mean, computed mean) of the worst box.
    worst: Option<([i64; 4], f64, f64)>,
}

impl Stats {
    fn add(&mut self, b: [i64; 4], exact: f64, got: f64) {
        let err = (got - exact).abs();
        let err = if err.is_nan() { f64::INFINITY } else { err };
        self.n += 1;
        self.sum_sq += err * err;
        self.max_rel = self.max_rel.max(err / exact.abs().max(1.0));
        if self.worst.is_none() || err > self.max_abs {
            self.max_abs = err;
            self.worst = Some((b, exact, got));
        }
    }

    fn rms(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            (self.sum_sq / self.n as f64).sqrt()
        }
    }
}

/// A box in words: `1x1 box at (4103, 4103)`.
fn describe(b: [i64; 4]) -> String {
    let t = |raw: i64| {
        let v = raw as f64 / ONE as f64;
        if raw % ONE == 0 {
            format!("{}", raw / ONE)
        } else {
            format!("{v}")
        }
    };
    format!(
        "{}x{} box at ({}, {})",
        t(b[2] - b[0]),
        t(b[3] - b[1]),
        t(b[0]),
        t(b[1])
    )
}

fn note(method: Method, s: &Stats, repeat: bool) -> String {
    let Some((b, exact, got)) = s.worst else {
        return "no boxes".into();
    };
    if s.max_abs == 0.0 {
        return if method.is_texsat() {
            format!(
                "exact on all {} boxes: integer table{}, sums without rounding",
                s.n,
                if repeat {
                    ", whole periods added in closed form"
                } else {
                    ""
                }
            )
        } else {
            format!(
                "no error on all {} boxes: every table value is an integer the {}-bit \
                 significand holds, and the lookup's roundings did not show in the mean",
                s.n,
                method.significand_bits().unwrap_or(0)
            )
        };
    }
    let p = method.significand_bits().unwrap_or(0);
    let bits = if s.max_rel > 0.0 {
        (-s.max_rel.log2()).clamp(0.0, p as f64)
    } else {
        p as f64
    };
    let head = if method.is_texsat() {
        "unexpected error".to_string()
    } else if bits < 0.5 {
        format!("float loses all {p} bits")
    } else {
        format!("about {bits:.0} of {p} bits left")
    };
    let off = (got - exact).abs();
    let (off, digits) = if off >= 0.01 {
        (format!("{off:.3}"), 4)
    } else {
        (format!("{off:.2e}"), 8)
    };
    format!(
        "{head}: mean of the {} is {exact:.digits$}, computed {got:.digits$} (off by {off})",
        describe(b)
    )
}

/// Evaluates every applicable method on every case of one texture, building one table at a
/// time. Returns rows grouped by case, methods in the order given.
fn study(tex: &Tex, cases: &[Case], methods: &[Method]) -> Vec<StabilityRow> {
    let exact: Vec<Vec<f64>> = {
        let reference = if cases.iter().any(|c| c.repeat) {
            Some(tex.to_ref())
        } else {
            None
        };
        cases
            .iter()
            .map(|c| {
                c.boxes
                    .iter()
                    .map(|&b| {
                        let sum = match (&reference, c.repeat) {
                            (Some(r), true) => r.exact_integral(RefMode::Repeat, b, FRAC_BITS, 0),
                            _ => tex.exact_sum(b),
                        };
                        exact_mean(sum, area_raw(b))
                    })
                    .collect()
            })
            .collect()
    };
    let mut stats: Vec<Vec<Option<Stats>>> = vec![vec![None; methods.len()]; cases.len()];
    let mut run = |mi: usize, f: &mut dyn FnMut(&Case, [i64; 4]) -> f64| {
        for (ci, c) in cases.iter().enumerate() {
            if methods[mi].integer_only() && !c.integer {
                continue;
            }
            let mut s = Stats::default();
            for (&b, &e) in c.boxes.iter().zip(&exact[ci]) {
                s.add(b, e, f(c, b));
            }
            stats[ci][mi] = Some(s);
        }
    };
    for (mi, &m) in methods.iter().enumerate() {
        match m {
            Method::F32 | Method::F32Mean | Method::F32Half | Method::F32ColumnsFirst => {
                let offset = match m {
                    Method::F32Mean => tex.mean(),
                    Method::F32Half => 128.0,
                    _ => 0.0,
                };
                let order = if m == Method::F32ColumnsFirst {
                    BuildOrder::ColumnsThenRows
                } else {
                    BuildOrder::RowsThenColumns
                };
                let t = FloatSat::<f32>::build(&tex.t, tex.w, tex.h, offset, order);
                run(mi, &mut |c, b| float_mean(&t, c.repeat, b));
            }
            Method::F64 => {
                let t =
                    FloatSat::<f64>::build(&tex.t, tex.w, tex.h, 0.0, BuildOrder::RowsThenColumns);
                run(mi, &mut |c, b| float_mean(&t, c.repeat, b));
            }
            Method::Int4 | Method::Stable16 => {
                let mut storage = vec![0u32; tex.w * tex.h];
                let texture = Texture::<u8, 1>::new(&tex.t, tex.w, tex.h).expect("texture");
                let sat = Sat::<u32, 1>::build(&texture, &mut storage).expect("u32 table");
                run(mi, &mut |c, b| {
                    texsat_mean(&sat, m == Method::Int4, c.repeat, b)
                });
            }
            Method::Int4U64 | Method::Stable16U64 => {
                let mut storage = vec![0u64; tex.w * tex.h];
                let texture = Texture::<u8, 1>::new(&tex.t, tex.w, tex.h).expect("texture");
                let sat = Sat::<u64, 1>::build(&texture, &mut storage).expect("u64 table");
                run(mi, &mut |c, b| {
                    texsat_mean(&sat, m == Method::Int4U64, c.repeat, b)
                });
            }
        }
    }
    let mut rows = Vec::new();
    for (ci, c) in cases.iter().enumerate() {
        for (mi, &m) in methods.iter().enumerate() {
            if let Some(s) = &stats[ci][mi] {
                rows.push(StabilityRow {
                    case: c.name.clone(),
                    method: m.name(c.repeat),
                    size: tex.w,
                    max_abs_error: s.max_abs,
                    rms_error: s.rms(),
                    max_rel_error: s.max_rel,
                    note: note(m, s, c.repeat),
                });
            }
        }
    }
    rows
}

fn float_mean<R: Real>(t: &FloatSat<R>, repeat: bool, b: [i64; 4]) -> f64 {
    let [x0, y0, x1, y1] = b.map(to_real::<R>);
    if repeat {
        t.box_mean_repeat(x0, y0, x1, y1).to_f64()
    } else {
        t.box_mean(x0, y0, x1, y1).to_f64()
    }
}

fn texsat_mean<E: texsat::Entry>(
    sat: &Sat<'_, E, 1>,
    int4: bool,
    repeat: bool,
    b: [i64; 4],
) -> f64 {
    let k = &mut NoCount;
    let sum = if int4 {
        let r = Rect::new(
            (b[0] / ONE) as i32,
            (b[1] / ONE) as i32,
            (b[2] / ONE) as i32,
            (b[3] / ONE) as i32,
        );
        let s = if repeat {
            sat.box_sum_int(&r, Repeat, k)
        } else {
            sat.box_sum_int(&r, ClampToEdge, k)
        };
        s.expect("integer lookup").to_u128().sum() << (2 * FRAC_BITS)
    } else {
        let r: Rect<I24F8> = rect_from_raw(b);
        let s = if repeat {
            sat.box_sum(&r, Stable, Repeat, k)
        } else {
            sat.box_sum(&r, Stable, ClampToEdge, k)
        };
        s.expect("fixed-point lookup").to_u128().sum()
    };
    exact_mean(sum, area_raw(b))
}

/// `count` random boxes inside an `n x n` table with sides in `1..=max_side` texels; integer
/// corners, or (when `frac`) corners on the `1/256` grid with sides from `0.25` texel.
fn random_boxes(
    rng: &mut TestRng,
    n: usize,
    count: usize,
    max_side: i64,
    frac: bool,
) -> Vec<[i64; 4]> {
    let end = n as i64 * ONE;
    let max_side = (max_side * ONE).min(end);
    (0..count)
        .map(|_| {
            let side = |rng: &mut TestRng| {
                if frac {
                    rng.random_range(ONE / 4..=max_side.max(ONE / 4))
                } else {
                    rng.random_range(1..=max_side / ONE) * ONE
                }
            };
            let (sw, sh) = (side(rng), side(rng));
            let pos = |rng: &mut TestRng, s: i64| {
                let p = rng.random_range(0..=end - s);
                if frac {
                    p
                } else {
                    p / ONE * ONE
                }
            };
            let (x0, y0) = (pos(rng, sw), pos(rng, sh));
            [x0, y0, x0 + sw, y0 + sh]
        })
        .collect()
}

/// An 8 x 8 block of `side`-square boxes (raw) stepping by `step` back from the far corner.
fn far_corner_boxes(n: usize, side: i64, step: i64) -> Vec<[i64; 4]> {
    let end = n as i64 * ONE;
    let mut v = Vec::new();
    for dy in 0..8 {
        for dx in 0..8 {
            let (x1, y1) = (end - dx * step, end - dy * step);
            if x1 - side >= 0 && y1 - side >= 0 {
                v.push([x1 - side, y1 - side, x1, y1]);
            }
        }
    }
    v
}

/// Long thin boxes (grazing view near the horizon): `thick x len` and `len x thick`, placed at
/// random with many near the far edges.
fn thin_boxes(rng: &mut TestRng, n: usize, len: i64, thick: i64, count: usize) -> Vec<[i64; 4]> {
    let end = n as i64 * ONE;
    let len = (len * ONE).min(end);
    let grid = if thick % ONE == 0 { ONE } else { 1 };
    (0..count)
        .map(|k| {
            let far = k % 2 == 0;
            let a = if far {
                end - thick - rng.random_range(0..=16 * ONE) / grid * grid
            } else {
                rng.random_range(0..=end - thick) / grid * grid
            };
            let l0 = if far {
                end - len
            } else {
                rng.random_range(0..=end - len) / ONE * ONE
            };
            if k % 4 < 2 {
                [a, l0, a + thick, l0 + len]
            } else {
                [l0, a, l0 + len, a + thick]
            }
        })
        .collect()
}

/// Boxes over the `period x period` repeated texture with sides of `periods/2..=periods`
/// periods plus a random fraction, starting anywhere within the first `periods` periods.
fn repeat_wide_boxes(
    rng: &mut TestRng,
    period: usize,
    periods: i64,
    count: usize,
) -> Vec<[i64; 4]> {
    let p = period as i64 * ONE;
    (0..count)
        .map(|_| {
            let mut b = [0i64; 4];
            for axis in 0..2 {
                let lo = rng.random_range(0..=periods * p);
                let side = rng.random_range((periods * p / 2).max(ONE / 4)..=periods * p);
                b[axis] = lo;
                b[axis + 2] = lo + side;
            }
            b
        })
        .collect()
}

/// 1x1 integer boxes about `periods` periods from the origin.
fn repeat_far_unit_boxes(
    rng: &mut TestRng,
    period: usize,
    periods: i64,
    count: usize,
) -> Vec<[i64; 4]> {
    let p = period as i64;
    (0..count)
        .map(|_| {
            let x = periods * p + rng.random_range(0..=p - 1);
            let y = periods * p + rng.random_range(0..=p - 1);
            [x * ONE, y * ONE, (x + 1) * ONE, (y + 1) * ONE]
        })
        .collect()
}

const FLOAT_METHODS: [Method; 4] = [Method::F32, Method::F32Mean, Method::F32Half, Method::F64];

/// The stability table: every case and method (see the module docs). Cases:
///
/// * `all-255 NxN`: a constant 255 texture (the largest sums) at `N` = 256, 1024 and 4104 (the
///   largest square whose table fits `u32`, [`largest_u32_square`]; `Full` adds 512, 2048,
///   4096): random small integer boxes anywhere, and 1x1, 2x2 and 0.25x0.25 boxes at the far
///   corner (where `f32` cancels catastrophically).
/// * `noise 200..=255 NxN` (N = 1024 for `Quick`, 4104 otherwise): a large mean, where centring
///   helps; small integer and fractional boxes, 1x1 boxes at the far corner, and grazing boxes
///   (1 x L and 0.25 x L, L = N - 104, i.e. 1 x 4000 at 4104).
/// * `repeat 64x64`: noise 200..=255 under repeat; for `P` = 1, 10, 100, 1000, 10 000 periods
///   (`Quick`: 1, 100, 10 000; `Full` adds 30 000), boxes `P/2..P` periods wide starting within
///   the first `P` periods (corners up to about 1.3 million texels, 3.8 million for `Full`), and
///   1x1 boxes `P` periods from the origin: the float path does the period arithmetic of
///   [`FloatSat::corner_repeat`], texsat its exact [`texsat::Repeat`] lookup.
///
/// Box counts (Quick / Default / Full): 64 / 500 / 2000 random small boxes per case, 64 boxes at
/// a far corner, 32 / 64 / 256 grazing boxes, 16 / 32 / 128 boxes per repeat case. Runs in about
/// a second in release at `Default` (a few seconds in debug at `Quick`).
pub fn stability_rows(size: SceneSize) -> Vec<StabilityRow> {
    let largest = largest_u32_square(8);
    let mut rng = crate::rng(0x5AB1_u64);
    let mut rows = Vec::new();
    let (n_random, n_thin, n_repeat) = match size {
        SceneSize::Quick => (64, 32, 16),
        SceneSize::Default => (500, 64, 32),
        SceneSize::Full => (2000, 256, 128),
    };

    // All-255 textures.
    let mut sides = match size {
        SceneSize::Full => vec![256, 512, 1024, 2048, 4096, largest],
        _ => vec![256, 1024, largest],
    };
    sides.dedup();
    for &n in &sides {
        let tex = Tex::constant(n, 255);
        let label = format!("all-255 {n}x{n}");
        let mut boxes = random_boxes(&mut rng, n, n_random, 16, false);
        boxes.extend(far_corner_boxes(n, ONE, ONE).into_iter().take(1));
        let cases = [
            Case {
                name: format!("{label}: small boxes anywhere"),
                boxes,
                integer: true,
                repeat: false,
            },
            Case {
                name: format!("{label}: 1x1 boxes at the far corner"),
                boxes: far_corner_boxes(n, ONE, ONE),
                integer: true,
                repeat: false,
            },
            Case {
                name: format!("{label}: 2x2 boxes at the far corner"),
                boxes: far_corner_boxes(n, 2 * ONE, ONE),
                integer: true,
                repeat: false,
            },
            Case {
                name: format!("{label}: 0.25x0.25 boxes at the far corner"),
                boxes: far_corner_boxes(n, ONE / 4, ONE / 4),
                integer: false,
                repeat: false,
            },
        ];
        let methods = [&FLOAT_METHODS[..], &[Method::Int4, Method::Stable16]].concat();
        rows.extend(study(&tex, &cases, &methods));
    }

    // Noise with a large mean.
    let n = if size == SceneSize::Quick {
        1024
    } else {
        largest
    };
    let tex = Tex::noise(n, 200, 255, 0x0015E);
    let label = format!("noise 200..=255 {n}x{n}");
    let len = n as i64 - 104;
    let cases = [
        Case {
            name: format!("{label}: small integer boxes anywhere"),
            boxes: random_boxes(&mut rng, n, n_random, 16, false),
            integer: true,
            repeat: false,
        },
        Case {
            name: format!("{label}: small fractional boxes anywhere"),
            boxes: random_boxes(&mut rng, n, n_random, 16, true),
            integer: false,
            repeat: false,
        },
        Case {
            name: format!("{label}: 1x1 boxes at the far corner"),
            boxes: far_corner_boxes(n, ONE, ONE),
            integer: true,
            repeat: false,
        },
        Case {
            name: format!("{label}: grazing 1x{len} boxes"),
            boxes: thin_boxes(&mut rng, n, len, ONE, n_thin),
            integer: true,
            repeat: false,
        },
        Case {
            name: format!("{label}: grazing 0.25x{len} boxes"),
            boxes: thin_boxes(&mut rng, n, len, ONE / 4, n_thin),
            integer: false,
            repeat: false,
        },
    ];
    let methods = [
        &FLOAT_METHODS[..],
        &[Method::F32ColumnsFirst, Method::Int4, Method::Stable16],
    ]
    .concat();
    rows.extend(study(&tex, &cases, &methods));
    drop(tex);

    // Repeated texture, many periods.
    let period = 64;
    let tex = Tex::noise(period, 200, 255, 0x00EE7);
    let scales: &[i64] = match size {
        SceneSize::Quick => &[1, 100, 10_000],
        SceneSize::Default => &[1, 10, 100, 1_000, 10_000],
        SceneSize::Full => &[1, 10, 100, 1_000, 10_000, 30_000],
    };
    let mut cases = Vec::new();
    for &p in scales {
        cases.push(Case {
            name: format!(
                "repeat {period}x{period}: boxes {}..{p} periods wide",
                p as f64 / 2.0
            ),
            boxes: repeat_wide_boxes(&mut rng, period, p, n_repeat),
            integer: false,
            repeat: true,
        });
        cases.push(Case {
            name: format!(
                "repeat {period}x{period}: 1x1 boxes {p} period{} from the origin",
                if p == 1 { "" } else { "s" }
            ),
            boxes: repeat_far_unit_boxes(&mut rng, period, p, n_repeat),
            integer: true,
            repeat: true,
        });
    }
    let methods = [&FLOAT_METHODS[..], &[Method::Int4, Method::Stable16]].concat();
    rows.extend(study(&tex, &cases, &methods));
    rows
}

/// The float32-error-against-table-size curves: for square tables of noise 200..=255 (a large
/// mean) with sides 16, 32, ..., 4096 and 4104 (`Quick`: up to 512; `Full`: also the half-octave
/// sides in between), the max abs error of box means over random small boxes (half with integer
/// corners, half fractional at `F = 8`, sides up to 16 texels; 2 x 500 per size, 2 x 100 for
/// `Quick`, 2 x 1000 for `Full`) plus the 1x1 box at the far corner, for: float32 (GPU build),
/// float32 centred on the mean and on 128, f64, and texsat `u32` and `u64` (4-read for integer
/// boxes, 16-read Stable for fractional ones: 0, the sums are exact). Zeros are exact results
/// (a log-scale plot must clamp them). About a second in release at `Default`.
pub fn float32_error_vs_size(size: SceneSize) -> Vec<Float32Curve> {
    let largest = largest_u32_square(8);
    let mut sides = Vec::new();
    let mut n = 16usize;
    let max = if size == SceneSize::Quick { 512 } else { 4096 };
    while n <= max {
        sides.push(n);
        if size == SceneSize::Full && n < max {
            sides.push((n as f64 * std::f64::consts::SQRT_2).round() as usize);
        }
        n *= 2;
    }
    if size != SceneSize::Quick {
        sides.push(largest);
    }
    let count = match size {
        SceneSize::Quick => 100,
        SceneSize::Default => 500,
        SceneSize::Full => 1000,
    };
    let methods = [
        Method::F32,
        Method::F32Mean,
        Method::F32Half,
        Method::F64,
        Method::Int4,
        Method::Stable16,
        Method::Int4U64,
        Method::Stable16U64,
    ];
    let curve_names = [
        "float32 SAT (GPU build, rows then columns)",
        "float32 SAT centred on the texture mean",
        "float32 SAT centred on 128",
        "f64 SAT",
        "texsat u32 (4-read integer, 16-read Stable F=8)",
        "texsat u64 (4-read integer, 16-read Stable F=8)",
    ];
    let mut curves: Vec<Float32Curve> = curve_names
        .iter()
        .map(|m| Float32Curve {
            method: m.to_string(),
            points: Vec::new(),
        })
        .collect();
    let mut rng = crate::rng(0xC0_12BE);
    for &n in &sides {
        let tex = Tex::noise(n, 200, 255, 0x5EED ^ n as u64);
        let mut int_boxes = random_boxes(&mut rng, n, count, 16, false);
        int_boxes.extend(far_corner_boxes(n, ONE, ONE).into_iter().take(1));
        let cases = [
            Case {
                name: "integer".into(),
                boxes: int_boxes,
                integer: true,
                repeat: false,
            },
            Case {
                name: "fractional".into(),
                boxes: random_boxes(&mut rng, n, count, 16, true),
                integer: false,
                repeat: false,
            },
        ];
        let rows = study(&tex, &cases, &methods);
        let max_of = |ms: &[Method]| {
            rows.iter()
                .filter(|r| ms.iter().any(|m| m.name(false) == r.method))
                .map(|r| r.max_abs_error)
                .fold(0.0f64, f64::max)
        };
        let groups: [&[Method]; 6] = [
            &[Method::F32],
            &[Method::F32Mean],
            &[Method::F32Half],
            &[Method::F64],
            &[Method::Int4, Method::Stable16],
            &[Method::Int4U64, Method::Stable16U64],
        ];
        for (c, g) in curves.iter_mut().zip(groups) {
            c.points.push((n, max_of(g)));
        }
    }
    curves
}
