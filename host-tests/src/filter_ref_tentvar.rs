//! References for texsat's `filters::tent` (repeated integration of order 2: the triangle filter)
//! and `filters::variance` (variance over a box), written without any integrated table:
//!
//! * the triangle filter by **direct convolution**: per axis, the weight of texel `i` is the
//!   integral of the (unnormalised) triangle `K(u) = max(0, a - |u - c|)` over `[i, i+1)`,
//!   computed piece by piece between the breakpoints `c - a`, `c`, `c + a` (trapezoids, exact
//!   for a piecewise-linear kernel), in exact integers and in `f64`; the sample is
//!   `sum t_ext(i, j) wx_i wy_j / (a^2 b^2)`;
//! * the variance by **direct summation** of `n`, `sum t` and `sum t^2` over the texel cells the
//!   box overlaps, times the overlap areas, in exact integers and in `f64`;
//! * the order-2 table by its closed form `Q(X, Y) = sum (2X - 2i - 1)(2Y - 2j - 1) t(i, j)`.
//!
//! Units: a texture axis position with `g` fractional bits is the integer `value * 2^g`. For a
//! footprint `[x0, x1)` with `F` fractional bits, the centre `x0 + x1` and half-width `x1 - x0`
//! are exact with `g = F + 1`.

use crate::{RefMode, RefTexture};

/// Per-axis texel weights of the triangle centred at `c` with half-width `a` (both in units of
/// `2^-g`, `a > 0`): `(extended texel index, 2^(2g+1) * integral_i^{i+1} K)`, exact integers,
/// zero weights omitted. `K` is unnormalised (peak `a`), so the weights sum to `2^(2g+1) a^2`
/// in texel units.
pub fn triangle_weights(c: i128, a: i128, g: u32) -> Vec<(i64, i128)> {
    assert!(a > 0);
    let s = 1i128 << g;
    let k = |x: i128| (a - (x - c).abs()).max(0);
    let lo = (c - a).div_euclid(s);
    let hi = (c + a).div_euclid(s);
    let mut out = Vec::new();
    for i in lo..=hi {
        let (u0, u1) = (i * s, (i + 1) * s);
        let mut pts = vec![u0];
        for b in [c - a, c, c + a] {
            if b > u0 && b < u1 {
                pts.push(b);
            }
        }
        pts.push(u1);
        pts.sort();
        // 2 s^2 * integral = sum over pieces (K(u) + K(v)) (v - u), in units 2^-2g.
        let w: i128 = pts
            .windows(2)
            .map(|p| (k(p[0]) + k(p[1])) * (p[1] - p[0]))
            .sum();
        if w != 0 {
            out.push((i as i64, w));
        }
    }
    out
}

/// The `f64` version of [`triangle_weights`] in texel units (centre and half-width in texels),
/// normalised so the weights sum to 1 (for a kernel inside the line).
pub fn triangle_weights_f64(c: f64, a: f64) -> Vec<(i64, f64)> {
    let k = |x: f64| (a - (x - c).abs()).max(0.0);
    let lo = (c - a).floor() as i64;
    let hi = (c + a).floor() as i64;
    let mut out = Vec::new();
    for i in lo..=hi {
        let (u0, u1) = (i as f64, (i + 1) as f64);
        let mut pts = vec![u0];
        for b in [c - a, c, c + a] {
            if b > u0 && b < u1 {
                pts.push(b);
            }
        }
        pts.push(u1);
        pts.sort_by(|x, y| x.partial_cmp(y).unwrap());
        let w: f64 = pts
            .windows(2)
            .map(|p| (k(p[0]) + k(p[1])) * (p[1] - p[0]) / 2.0)
            .sum::<f64>()
            / (a * a);
        if w != 0.0 {
            out.push((i, w));
        }
    }
    out
}

/// The exact numerator `N = sum t_ext(i, j) wx_i wy_j` of the triangle filter of channel `ch`
/// (centres and half-widths in units `2^-g`): the filtered value is `N / (4 a^2 b^2)`
/// (`a`, `b` in the same units).
pub fn tent_numerator(
    tex: &RefTexture,
    mode: RefMode,
    (cx, a): (i128, i128),
    (cy, b): (i128, i128),
    g: u32,
    ch: usize,
) -> i128 {
    let wx = triangle_weights(cx, a, g);
    let wy = triangle_weights(cy, b, g);
    let mut n = 0i128;
    for &(j, vy) in &wy {
        for &(i, vx) in &wx {
            let t = tex.texel_ext(mode, i, j, ch) as i128;
            n += t * vx * vy;
        }
    }
    n
}

/// `round(num * 2^shift / den)`, ties up (exact, by long division; `den < 2^127`).
pub fn round_ratio(num: u128, shift: u32, den: u128) -> u64 {
    assert!(den > 0 && den < 1u128 << 127);
    let mut q = num / den;
    let mut r = num % den;
    for _ in 0..shift {
        q = q.checked_mul(2).expect("quotient fits");
        r <<= 1;
        if r >= den {
            r -= den;
            q += 1;
        }
    }
    if r >= den - r {
        q += 1;
    }
    u64::try_from(q).expect("quotient fits u64")
}

/// The exact triangle filter of channel `ch`, rounded as texsat rounds: `round(value * 2^16)`,
/// ties up, for centre/half-widths in units `2^-g`.
pub fn tent_rounded(
    tex: &RefTexture,
    mode: RefMode,
    x: (i128, i128),
    y: (i128, i128),
    g: u32,
    ch: usize,
) -> u64 {
    let n = tent_numerator(tex, mode, x, y, g, ch);
    assert!(n >= 0);
    round_ratio(n as u128, 14, (x.1 * x.1 * y.1 * y.1) as u128)
}

/// The triangle filter of channel `ch` in `f64` by direct convolution, for the footprint
/// rectangle `[x0, x1) x [y0, y1)` (texel units).
pub fn tent_f64(tex: &RefTexture, mode: RefMode, r: [f64; 4], ch: usize) -> f64 {
    let [x0, y0, x1, y1] = r;
    let wx = triangle_weights_f64((x0 + x1) / 2.0, (x1 - x0) / 2.0);
    let wy = triangle_weights_f64((y0 + y1) / 2.0, (y1 - y0) / 2.0);
    let mut v = 0.0;
    for &(j, vy) in &wy {
        for &(i, vx) in &wx {
            v += tex.texel_ext(mode, i, j, ch) as f64 * vx * vy;
        }
    }
    v
}

/// The footprint `[x0, y0, x1, y1]` (raw, `F` fractional bits) as centre/half-width pairs in units
/// `2^-(F+1)`.
pub fn footprint(b: [i64; 4]) -> ((i128, i128), (i128, i128)) {
    let [x0, y0, x1, y1] = b.map(|v| v as i128);
    ((x0 + x1, x1 - x0), (y0 + y1, y1 - y0))
}

/// The bound of texsat's paper (bilinear) tent against the exact filter, re-derived:
/// `m/4 (1/a^2 + 1/b^2 + 1/(2 a^2 b^2))` texel units, half-widths in texels.
pub fn paper_bound(m: f64, a: f64, b: f64) -> f64 {
    m / 4.0 * (1.0 / (a * a) + 1.0 / (b * b) + 1.0 / (2.0 * a * a * b * b))
}

/// The closed form of the stored order-2 table of channel `ch`:
/// `Q(X, Y) = sum_{i < min(X, w), j < min(Y, h)} (2X - 2i - 1)(2Y - 2j - 1) t(i, j)` for
/// `1 <= X <= w + 1`, `1 <= Y <= h + 1`, row-major.
pub fn tent_table(tex: &RefTexture, ch: usize) -> Vec<u128> {
    let (w, h) = (tex.width, tex.height);
    let mut out = Vec::with_capacity((w + 1) * (h + 1));
    for y in 1..=h + 1 {
        for x in 1..=w + 1 {
            let mut q = 0u128;
            for j in 0..h.min(y) {
                for i in 0..w.min(x) {
                    q += (2 * (x - i) as u128 - 1)
                        * (2 * (y - j) as u128 - 1)
                        * tex.texel(i, j, ch) as u128;
                }
            }
            out.push(q);
        }
    }
    out
}

/// Exact `(n, S, Q)` over the raw box `[x0, x1) x [y0, y1)` (`F = f` fractional bits) of the
/// extended texture, channel `ch`, all in units of `2^-2f`: the area, the sum and the sum of
/// squares by direct summation of every overlapped cell.
pub fn variance_sums(
    tex: &RefTexture,
    mode: RefMode,
    b: [i64; 4],
    f: u32,
    ch: usize,
) -> (u128, u128, u128) {
    let [x0, y0, x1, y1] = b.map(|v| v as i128);
    let s = 1i128 << f;
    let overlaps = |lo: i128, hi: i128| -> Vec<(i64, i128)> {
        let mut v = Vec::new();
        if hi <= lo {
            return v;
        }
        for i in lo.div_euclid(s)..=(hi - 1).div_euclid(s) {
            let o = hi.min((i + 1) * s) - lo.max(i * s);
            if o > 0 {
                v.push((i as i64, o));
            }
        }
        v
    };
    let (ox, oy) = (overlaps(x0, x1), overlaps(y0, y1));
    let (mut sum, mut sq) = (0u128, 0u128);
    for &(j, vy) in &oy {
        for &(i, vx) in &ox {
            let t = tex.texel_ext(mode, i, j, ch) as u128;
            let a = (vx * vy) as u128;
            sum += t * a;
            sq += t * t * a;
        }
    }
    (((x1 - x0) * (y1 - y0)) as u128, sum, sq)
}

/// The exact variance rounded as texsat rounds: `round((n Q - S^2) 2^16 / n^2)`, ties up.
pub fn variance_rounded(tex: &RefTexture, mode: RefMode, b: [i64; 4], f: u32, ch: usize) -> u64 {
    let (n, s, q) = variance_sums(tex, mode, b, f, ch);
    round_ratio(n * q - s * s, 16, n * n)
}

/// The variance in `f64`: `sum t^2 / n - (sum t / n)^2` over the float box, by direct
/// summation of overlaps.
pub fn variance_f64(tex: &RefTexture, mode: RefMode, r: [f64; 4], ch: usize) -> f64 {
    let [x0, y0, x1, y1] = r;
    let cells = |lo: f64, hi: f64| (lo.floor() as i64)..(hi.ceil() as i64);
    let ov = |lo: f64, hi: f64, i: i64| (hi.min((i + 1) as f64) - lo.max(i as f64)).max(0.0);
    let (mut s, mut q) = (0.0, 0.0);
    for j in cells(y0, y1) {
        for i in cells(x0, x1) {
            let a = ov(x0, x1, i) * ov(y0, y1, j);
            let t = tex.texel_ext(mode, i, j, ch) as f64;
            s += t * a;
            q += t * t * a;
        }
    }
    let n = (x1 - x0) * (y1 - y0);
    q / n - (s / n) * (s / n)
}
