//! Texture boundary modes (Crow §2.4): what a box reaching outside `[0, w) x [0, h)` sums.
//!
//! Each mode is a zero-sized type, passed by value to the lookups, so only the modes a build
//! names are compiled in. Every mode defines an *extended texture* over the whole plane and the
//! lookups return its exact integral over the box:
//!
//! * [`Border`]: zero outside. The box is clipped to the texture; the area of the mean stays the
//!   unclipped box's (Crow: "truncate texture image coordinates while calculating the area from
//!   the unmodified coordinates").
//! * [`ClampToEdge`]: texel `(clamp(i, 0, w-1), clamp(j, 0, h-1))`.
//! * [`Repeat`]: texel `(i mod w, j mod h)`. Whole periods add whole-table sums (Crow: "values
//!   lying to the right or above a boundary must be increased by the value at the boundary"),
//!   in constant time however many periods the box covers.
//! * [`MirroredRepeat`]: period `2w` (`2h`), the second half reflected.
//!
//! Implementation: a box is first *placed*. If an equivalent box inside `[0, w] x [0, h]` exists
//! (the clip for `Border`; a shift by whole periods for `Repeat`; a shift and a reflection for
//! `MirroredRepeat`; the box itself for `ClampToEdge`) the ordinary 4- or 16-read lookup answers.
//! Otherwise each corner is a signed combination of in-range corner values: per axis the prefix
//! integral `P(x) = integral_0^x` of the extended texture is a weighted sum of at most three
//! table columns (rows), and `S_ext(x, y)` is the tensor product of the two axes' weights (see
//! [`EdgeMode::axis_terms`]). Those lookups run in checked `i128` arithmetic.

use crate::rect::RawBox;

/// At most three `(index, weight)` pairs: `2^F * P(x) = sum weight * S(index, .)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct AxisTerms {
    /// `(corner index in 0..=n, weight scaled by 2^F)`; only the first `len` are used.
    pub terms: [(usize, i128); 3],
    /// Number of terms.
    pub len: usize,
}

impl AxisTerms {
    /// Adds `weight * S(index)`, merging with a term at the same index. Index 0 (the zero
    /// column of the corner function) and zero weights are dropped: they cost no read.
    fn push(&mut self, index: usize, weight: i128) {
        if weight == 0 || index == 0 {
            return;
        }
        if let Some(term) = self.terms[..self.len].iter_mut().find(|(i, _)| *i == index) {
            term.1 += weight;
        } else if self.len < 3 {
            self.terms[self.len] = (index, weight);
            self.len += 1;
        }
    }

    /// The terms in use.
    pub fn as_slice(&self) -> &[(usize, i128)] {
        &self.terms[..self.len]
    }

    /// The in-range interpolation `P(x) = (1 - a) S(i) + a S(i + 1)` for `0 <= x <= n * 2^F`.
    fn lerp(x: i128, n: usize, f: u32, sign: i128) -> Self {
        let s = 1i128 << f;
        let (i, a) = split(x, n, f);
        let mut t = AxisTerms::default();
        t.push(i, sign * (s - a as i128));
        t.push(i + 1, sign * a as i128);
        t
    }
}

/// Splits an in-range raw coordinate `0 <= x <= n * 2^F` into cell `i <= n - 1` and fraction
/// `a <= 2^F` (the right edge `x = n` is cell `n - 1` with `a = 2^F`, so `i + 1 <= n`).
#[inline(always)]
pub(crate) fn split(x: i128, n: usize, f: u32) -> (usize, u32) {
    let i = (x >> f) as usize;
    if i >= n {
        (n - 1, 1u32 << f)
    } else {
        (i, (x & ((1i128 << f) - 1)) as u32)
    }
}

/// Where one axis of a box lands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisPlacement {
    /// An equivalent interval inside `[0, n * 2^F]`.
    InRange(i128, i128),
    /// The interval sums to zero (clipped away by [`Border`]).
    Empty,
    /// No in-range equivalent: the weighted path takes this (possibly shifted) interval.
    Outside(i128, i128),
}

/// A boundary mode. Implemented by zero-sized types only.
pub trait EdgeMode: Copy + Default {
    /// A short name (`border`, `clamp`, `repeat`, `mirror`).
    const NAME: &'static str;
    /// Places the interval `[lo, hi)` (raw, `hi >= lo`) against an axis of `n` texels and `F`
    /// fractional bits.
    fn place_axis(lo: i128, hi: i128, n: usize, f: u32) -> AxisPlacement;
    /// The prefix integral of the extended texture at `x` (raw) as weights on the in-range corner
    /// function: `2^F * integral_0^x t_ext = sum weight * S(index)`, valid for any `x`.
    fn axis_terms(x: i128, n: usize, f: u32) -> AxisTerms;
    /// The texel index the extended texture shows at integer position `i` of an axis of `n`
    /// texels, or `None` where it is zero ([`Border`] outside the texture). Used by the
    /// texel-fetching filters (point, pyramids).
    fn texel_index(i: i64, n: usize) -> Option<usize>;
}

/// Outside the texture is zero; the area of the mean is the unclipped box's (Crow §2.4).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Border;

/// Coordinates clamp to the edge texels.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClampToEdge;

/// The texture repeats with period `w x h`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Repeat;

/// The texture repeats with period `2w x 2h`, every other copy reflected.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MirroredRepeat;

impl EdgeMode for Border {
    const NAME: &'static str = "border";
    #[inline]
    fn place_axis(lo: i128, hi: i128, n: usize, f: u32) -> AxisPlacement {
        let end = (n as i128) << f;
        let (lo, hi) = (lo.clamp(0, end), hi.clamp(0, end));
        if lo >= hi {
            AxisPlacement::Empty
        } else {
            AxisPlacement::InRange(lo, hi)
        }
    }
    fn axis_terms(x: i128, n: usize, f: u32) -> AxisTerms {
        AxisTerms::lerp(x.clamp(0, (n as i128) << f), n, f, 1)
    }
    fn texel_index(i: i64, n: usize) -> Option<usize> {
        if i >= 0 && (i as u64) < n as u64 {
            Some(i as usize)
        } else {
            None
        }
    }
}

impl EdgeMode for ClampToEdge {
    const NAME: &'static str = "clamp";
    #[inline]
    fn place_axis(lo: i128, hi: i128, n: usize, f: u32) -> AxisPlacement {
        if lo >= 0 && hi <= (n as i128) << f {
            AxisPlacement::InRange(lo, hi)
        } else {
            AxisPlacement::Outside(lo, hi)
        }
    }
    fn axis_terms(x: i128, n: usize, f: u32) -> AxisTerms {
        let s = 1i128 << f;
        let end = (n as i128) << f;
        let mut t = AxisTerms::default();
        if x < 0 {
            // integral_0^x of the constant first texel = x * t(0) = x * S(1).
            t.push(1, x);
        } else if x > end {
            // S(n) + (x - n) * t(n - 1), and t(n - 1) = S(n) - S(n - 1).
            let over = x - end;
            t.push(n, s + over);
            t.push(n - 1, -over);
        } else {
            return AxisTerms::lerp(x, n, f, 1);
        }
        t
    }
    fn texel_index(i: i64, n: usize) -> Option<usize> {
        Some(i.clamp(0, n as i64 - 1) as usize)
    }
}

impl EdgeMode for Repeat {
    const NAME: &'static str = "repeat";
    #[inline]
    fn place_axis(lo: i128, hi: i128, n: usize, f: u32) -> AxisPlacement {
        let period = (n as i128) << f;
        let shift = lo.div_euclid(period) * period;
        let (lo, hi) = (lo - shift, hi - shift);
        if hi <= period {
            AxisPlacement::InRange(lo, hi)
        } else {
            AxisPlacement::Outside(lo, hi)
        }
    }
    fn axis_terms(x: i128, n: usize, f: u32) -> AxisTerms {
        // x = q * n + r: q whole periods plus the prefix up to r.
        let period = (n as i128) << f;
        let q = x.div_euclid(period);
        let r = x.rem_euclid(period);
        let mut t = AxisTerms::lerp(r, n, f, 1);
        t.push(n, q << f);
        t
    }
    fn texel_index(i: i64, n: usize) -> Option<usize> {
        Some(i.rem_euclid(n as i64) as usize)
    }
}

impl EdgeMode for MirroredRepeat {
    const NAME: &'static str = "mirror";
    #[inline]
    fn place_axis(lo: i128, hi: i128, n: usize, f: u32) -> AxisPlacement {
        let half = (n as i128) << f;
        let period = 2 * half;
        let shift = lo.div_euclid(period) * period;
        let (lo, hi) = (lo - shift, hi - shift);
        if hi <= half {
            AxisPlacement::InRange(lo, hi)
        } else if lo >= half && hi <= period {
            AxisPlacement::InRange(period - hi, period - lo)
        } else {
            AxisPlacement::Outside(lo, hi)
        }
    }
    fn axis_terms(x: i128, n: usize, f: u32) -> AxisTerms {
        // x = q * 2n + r. Each whole period adds 2 S(n); r <= n adds S(r); r > n adds
        // S(n) + (S(n) - S(2n - r)) = 2 S(n) - S(2n - r).
        let half = (n as i128) << f;
        let period = 2 * half;
        let q = x.div_euclid(period);
        let r = x.rem_euclid(period);
        let mut t;
        let mut whole = 2 * q;
        if r <= half {
            t = AxisTerms::lerp(r, n, f, 1);
        } else {
            t = AxisTerms::lerp(period - r, n, f, -1);
            whole += 2;
        }
        t.push(n, whole << f);
        t
    }
    fn texel_index(i: i64, n: usize) -> Option<usize> {
        let r = i.rem_euclid(2 * n as i64);
        Some(if r < n as i64 {
            r
        } else {
            2 * n as i64 - 1 - r
        } as usize)
    }
}

/// Places a box: both axes in range, empty, or the weighted path.
pub(crate) enum Placement {
    InRange(RawBox),
    Empty,
    Outside(RawBox),
}

#[inline]
pub(crate) fn place<M: EdgeMode>(b: RawBox, w: usize, h: usize, f: u32) -> Placement {
    use AxisPlacement as A;
    let px = M::place_axis(b.x0, b.x1, w, f);
    let py = M::place_axis(b.y0, b.y1, h, f);
    match (px, py) {
        (A::Empty, _) | (_, A::Empty) => Placement::Empty,
        (A::InRange(x0, x1), A::InRange(y0, y1)) => Placement::InRange(RawBox { x0, y0, x1, y1 }),
        (A::InRange(x0, x1) | A::Outside(x0, x1), A::InRange(y0, y1) | A::Outside(y0, y1)) => {
            Placement::Outside(RawBox { x0, y0, x1, y1 })
        }
    }
}
