//! Texture boundary modes (Crow §2.4): what a box reaching outside `[0, w) x [0, h)` sums.
//!
//! Each mode is a zero-sized type, passed by value to the lookups, so a build that names one
//! mode compiles only its branch: [`Border`], [`ClampToEdge`], [`Repeat`], [`MirroredRepeat`],
//! and [`RepeatWithinPeriod`] (Repeat for boxes at most one period long, what a scene plan
//! states).
//! [`EdgeKind`] is the same choice as a run-time value (a tool that reads the mode from its
//! command line compiles one lookup for all four). [`EdgeMode`] is sealed; its one piece of
//! behaviour is [`EdgeMode::kind`], and everything a mode means is written once, on
//! [`EdgeKind`]: the texel an index shows ([`EdgeKind::texel_index`]) and, crate-internally, how
//! a box is placed against the table.
//!
//! Every mode defines an *extended texture* over the whole plane, and the lookups return its exact
//! integral over the box:
//!
//! * [`Border`]: zero outside. The box is clipped to the texture; the area of the mean stays the
//!   unclipped box's (Crow: "truncate texture image coordinates while calculating the area from
//!   the unmodified coordinates").
//! * [`ClampToEdge`]: texel `(clamp(i, 0, w-1), clamp(j, 0, h-1))`.
//! * [`Repeat`]: texel `(i mod w, j mod h)`. Whole periods add whole-period sums (Crow: "values
//!   lying to the right or above a boundary must be increased by the value at the boundary"),
//!   in constant time however many periods the box covers.
//! * [`MirroredRepeat`]: period `2w` (`2h`), the second half reflected.
//!
//! ## Placement (crate-internal)
//! Per axis, an interval `[lo, hi)` (raw, `F` fractional bits) is *placed*:
//!
//! * in range: an equivalent interval inside `[0, n 2^F]` exists (the clip for `Border`; the
//!   interval itself for `ClampToEdge`; a shift by whole periods for `Repeat`; a shift and a
//!   reflection for `MirroredRepeat`). This is the common case and costs comparisons only when
//!   `lo` lies in the first period (`Repeat`) or the first two half-periods (`MirroredRepeat`),
//!   else one 64-bit division;
//! * split: no such interval. The axis is cut into at most three in-range pieces, each with a
//!   multiplicity, following Crow §2.4: for `Repeat`/`MirroredRepeat` the head of the first
//!   period, `q` whole periods (the whole axis, `q` times) and the tail of the last (one more
//!   division when `q > 0`); for `ClampToEdge` the part left of the texture (the first texel
//!   column, as many times as the part is long), the part inside, and the part right of it.
//!
//! A box's sum is then the sum over the product of both axes' pieces of `mult_x mult_y` times an
//! ordinary in-range lookup: every quantity stays a sum over (part of) the box, so the same narrow
//! accumulator and the same modular bound serve, and nothing needs 128 bits.
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use crate::error::Error;

/// The boundary mode as a run-time value. Implements [`EdgeMode`] by a `match`; the zero-sized
/// types compile the same code with the branch fixed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EdgeKind {
    /// [`Border`]: zero outside.
    #[default]
    Border,
    /// [`ClampToEdge`].
    Clamp,
    /// [`Repeat`].
    Repeat,
    /// [`MirroredRepeat`].
    Mirror,
}

impl EdgeKind {
    /// All four modes.
    pub const ALL: [EdgeKind; 4] = [
        EdgeKind::Border,
        EdgeKind::Clamp,
        EdgeKind::Repeat,
        EdgeKind::Mirror,
    ];

    /// A short name: `border`, `clamp`, `repeat`, `mirror`.
    pub const fn name(self) -> &'static str {
        match self {
            EdgeKind::Border => "border",
            EdgeKind::Clamp => "clamp",
            EdgeKind::Repeat => "repeat",
            EdgeKind::Mirror => "mirror",
        }
    }

    /// The mode named by [`EdgeKind::name`].
    pub fn from_name(name: &str) -> Option<EdgeKind> {
        EdgeKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The texel index the extended texture shows at integer position `i` of an axis of `n`
    /// texels, or `None` where it is zero ([`Border`] outside the texture) or the axis is empty
    /// (`n = 0`). Any `n` up to `usize::MAX` and any `i`. No division when `i` lies in `[0, n)`
    /// (or `[0, 2n)` for the mirror); otherwise one, in 32 bits when the numbers fit (one
    /// hardware `udiv` on a Cortex-M4). Axes longer than `2^62` take an out-of-line path in
    /// `u64` (so the common one stays small: it is inlined into every tap of the filters).
    #[allow(
        clippy::arithmetic_side_effects,
        clippy::as_conversions,
        reason = "one proof for the function (const: no From/TryFrom): with a 64-bit usize n is at \
                  most i64::MAX / 2 past the check (longer axes take texel_index_long), with a \
                  32-bit one n < 2^32; either way n as i64 is lossless and 2 n does not wrap; \
                  n - 1 >= 0 as n >= 1; 2 n - 1 - r >= 0 as n <= r < 2 n; k lies in [0, n), so \
                  k as usize is exact"
    )]
    pub const fn texel_index(self, i: i64, n: usize) -> Option<usize> {
        if n == 0 {
            return None;
        }
        // An axis longer than 2^62 texels (possible only with a 64-bit usize; no texture has
        // one): the u64 path. With a 32-bit usize, n < 2^32 and every value below is exact in
        // i64, so the check does not exist there.
        #[cfg(target_pointer_width = "64")]
        if n > i64::MAX as usize / 2 {
            return texel_index_long(self, i, n);
        }
        let n = n as i64;
        let inside = i >= 0 && i < n;
        let k = match self {
            EdgeKind::Border => {
                if inside {
                    i
                } else {
                    return None;
                }
            }
            EdgeKind::Clamp => {
                if i < 0 {
                    0
                } else if i >= n {
                    n - 1
                } else {
                    i
                }
            }
            EdgeKind::Repeat => {
                if inside {
                    i
                } else {
                    match rem_euclid_narrow(i, n) {
                        Some(r) => r,
                        None => return None,
                    }
                }
            }
            EdgeKind::Mirror => {
                let r = if i >= 0 && i < 2 * n {
                    i
                } else {
                    match rem_euclid_narrow(i, 2 * n) {
                        Some(r) => r,
                        None => return None,
                    }
                };
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

/// `x mod p` (in `[0, p)`) for `p > 0`, in 32 bits when `|x|` and `p` fit (one hardware `udiv` on
/// the Cortex-M4 instead of a software 64-bit division), else in 64. `None` for `p <= 0`.
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "one proof for the function (const: no From/TryFrom): the casts to u32 follow the \
              checks |x| <= u32::MAX and 0 < p <= u32::MAX (so they are exact), u32 -> i64 and \
              u32::MAX -> u64/i64 are lossless, and p - r with 0 < r < p is in (0, p)"
)]
const fn rem_euclid_narrow(x: i64, p: i64) -> Option<i64> {
    if p <= 0 {
        return None;
    }
    let a = x.unsigned_abs();
    if a <= u32::MAX as u64 && p <= u32::MAX as i64 {
        let r = match (a as u32).checked_rem(p as u32) {
            Some(r) => r as i64,
            None => return None,
        };
        return Some(if x >= 0 || r == 0 { r } else { p - r });
    }
    x.checked_rem_euclid(p)
}

/// [`EdgeKind::texel_index`] for an axis longer than `2^62` texels, in `u64` on `|i|` so that no
/// intermediate overflows (the mirror's period `2n` may exceed `u64` only when every `i` lies
/// within one period). Compiled on every target (tested on the host); called with a 64-bit usize.
#[allow(
    clippy::arithmetic_side_effects,
    clippy::as_conversions,
    reason = "one proof for the function (const: no From/TryFrom): usize has at most 64 bits, \
              so n as u64 and the results (each below n, hence below usize::MAX + 1) as usize \
              are exact; a = |i| <= 2^63; each subtraction is of a smaller value (m < p, \
              m <= a, r < 2n, a > n where taken), and 2 n is formed with checked_mul"
)]
#[cfg_attr(not(target_pointer_width = "64"), allow(dead_code))]
#[inline(never)]
const fn texel_index_long(kind: EdgeKind, i: i64, n: usize) -> Option<usize> {
    if n == 0 {
        return None;
    }
    let n = n as u64;
    let neg = i < 0;
    let a = i.unsigned_abs();
    if !neg && a < n {
        return Some(a as usize);
    }
    let k = match kind {
        EdgeKind::Border => return None,
        EdgeKind::Clamp => {
            if neg {
                0
            } else {
                n - 1
            }
        }
        EdgeKind::Repeat => {
            let m = rem_narrow(a, n);
            if neg && m != 0 {
                n - m
            } else {
                m
            }
        }
        EdgeKind::Mirror => match n.checked_mul(2) {
            Some(p) => {
                let m = rem_narrow(a, p);
                // The index in the period [0, 2n), reflected in its second half.
                let r = if neg && m != 0 { p - m } else { m };
                if r < n {
                    r
                } else {
                    p - 1 - r
                }
            }
            // 2n > 2^64 > a: i lies in (-2n, 2n). i >= n: r = i < 2n; i < 0: r = 2n - a.
            None => {
                if !neg {
                    2 * n - 1 - a
                } else if a > n {
                    n - (a - n)
                } else {
                    a - 1
                }
            }
        },
    };
    Some(k as usize)
}

/// `a mod p` for `p > 0`, in 32 bits when both fit (one hardware `udiv` on the Cortex-M4 instead
/// of a software 64-bit division), else in 64; 0 for `p = 0` (never passed).
#[allow(
    clippy::as_conversions,
    reason = "const fn (no TryFrom): the casts to u32 are taken only when both values are at most \
              u32::MAX (checked), and u32 -> u64 is lossless"
)]
const fn rem_narrow(a: u64, p: u64) -> u64 {
    if a <= u32::MAX as u64 && p <= u32::MAX as u64 {
        return match (a as u32).checked_rem(p as u32) {
            Some(r) => r as u64,
            None => 0,
        };
    }
    match a.checked_rem(p) {
        Some(r) => r,
        None => 0,
    }
}

mod sealed {
    pub trait Sealed {}
}

/// A boundary mode: one of [`Border`], [`ClampToEdge`], [`Repeat`], [`MirroredRepeat`],
/// [`RepeatWithinPeriod`] (zero-sized)
/// or [`EdgeKind`] (chosen at run time). Sealed.
pub trait EdgeMode: Copy + sealed::Sealed {
    /// Which mode this is. Constant for the zero-sized types, so their lookups compile one branch.
    fn kind(self) -> EdgeKind;
    /// Whether the lookups answer only boxes at most one period long on each axis
    /// ([`RepeatWithinPeriod`]): then a box crossing the edge is at most 2 x 2 pieces of
    /// multiplicity 1, and no code for whole periods is compiled.
    #[doc(hidden)]
    const WITHIN_PERIOD: bool = false;
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

/// [`Repeat`] for boxes at most one period (the texture's side) long on each axis, as a scene
/// plan states when its largest box is at most the texture
/// ([`crate::plan::Plan::repeat_within_period`]). The box lookups (every layout, form and
/// path: `box_sum*`, the batch, the shortcut) give [`Repeat`]'s sums, errors, counted costs and
/// read order for those boxes, and refuse a longer, non-empty one with
/// [`crate::Error::OutsidePlan`] ([`crate::plan::PlanLimit::LongerThanPeriod`]), unless the
/// placement refuses its coordinates first ([`crate::Error::CoordinateOutOfRange`], as for
/// Repeat); never a wrong sum. What it leaves out: a box crossing the edge is at most 2 x 2
/// in-range pieces of multiplicity 1, so the whole periods' division and the multiplies are not
/// compiled (Stable + Repeat firmware on a Cortex-M4: docs/firmware.md). Its [`EdgeMode::kind`]
/// is [`EdgeKind::Repeat`]; the filters that take a mode (point, mip, rip, dip, tent) sample
/// with it as with [`Repeat`], with no period limit.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RepeatWithinPeriod;

/// The texture repeats with period `2w x 2h`, every other copy reflected.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MirroredRepeat;

macro_rules! zst_mode {
    ($t:ty, $k:expr) => {
        impl sealed::Sealed for $t {}
        impl EdgeMode for $t {
            #[inline(always)]
            fn kind(self) -> EdgeKind {
                $k
            }
        }
    };
}

zst_mode!(Border, EdgeKind::Border);
zst_mode!(ClampToEdge, EdgeKind::Clamp);
zst_mode!(Repeat, EdgeKind::Repeat);
zst_mode!(MirroredRepeat, EdgeKind::Mirror);

impl sealed::Sealed for RepeatWithinPeriod {}
impl EdgeMode for RepeatWithinPeriod {
    #[inline(always)]
    fn kind(self) -> EdgeKind {
        EdgeKind::Repeat
    }
    const WITHIN_PERIOD: bool = true;
}

impl sealed::Sealed for EdgeKind {}
impl EdgeMode for EdgeKind {
    #[inline(always)]
    fn kind(self) -> EdgeKind {
        self
    }
}

/// One in-range piece of a split axis: `[lo, hi)` inside `[0, n 2^F]`, counted `mult` times;
/// `unit` pieces are one texel wide and stand for a clamped run `mult` raw units long, so their
/// contribution is divided by `2^F` (exactly: a one-texel-wide integral is a multiple of `2^F`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct AxisPiece {
    pub lo: i64,
    pub hi: i64,
    pub mult: u64,
    pub unit: bool,
}

impl AxisPiece {
    /// The piece `[lo, hi)` counted `mult` times, or the absent piece (`mult = 0`) when it is
    /// empty.
    #[inline(always)]
    fn new(lo: i64, hi: i64, mult: u64, unit: bool) -> AxisPiece {
        if hi <= lo {
            AxisPiece::default()
        } else {
            AxisPiece { lo, hi, mult, unit }
        }
    }
}

/// At most three pieces; absent ones have `mult = 0` (the tests' view of a [`Prepared`] axis).
#[cfg(test)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct AxisPieces([AxisPiece; 3]);

#[cfg(test)]
impl AxisPieces {
    /// The pieces present.
    #[inline(always)]
    pub(crate) fn iter(&self) -> impl Iterator<Item = &AxisPiece> {
        self.0.iter().filter(|p| p.mult != 0)
    }
}

/// Where one axis of a box lands. Small (no pieces inside): the common in-range case moves
/// three words, and the pieces of a split axis are made only on the split path
/// ([`AxisSplit::pieces`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum AxisPlan {
    /// An equivalent interval inside `[0, n 2^F]`.
    InRange(i64, i64),
    /// The interval sums to zero (clipped away by [`Border`]).
    Empty,
    /// Crosses the edge: pieces, each in range (see the module docs).
    Split(AxisSplit),
}

/// A split axis, as the few numbers its pieces follow from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum AxisSplit {
    /// [`ClampToEdge`]: the raw interval `[lo, hi)` reaching past `[0, p)`.
    Clamp { lo: i64, hi: i64 },
    /// [`Repeat`] / [`MirroredRepeat`]: starts at `r0` in its period (reflected when `odd`) and
    /// runs `rest` raw units past that period's end.
    Periodic {
        mirror: bool,
        odd: bool,
        r0: i64,
        rest: u64,
    },
}

impl AxisSplit {
    /// The in-range pieces on an axis of raw length `p = n 2^F`, `F = f`, under the mode `kind`
    /// that made the split (the tests' view of [`Prepared::piece`]).
    #[cfg(test)]
    pub(crate) fn pieces(self, kind: EdgeKind, p: i64, f: u32) -> AxisPieces {
        let prepared = AxisPlan::Split(self).prepare(kind, p);
        AxisPieces([0, 1, 2].map(|k| prepared.piece(k, p, f)))
    }
}

impl AxisPlan {
    /// The numbers the pieces of this axis follow from, with the one division of a periodic
    /// split (its whole periods) done, under the mode `kind` that placed it. Matched on the mode
    /// as well as the split, so that a lookup with a zero-sized mode (a constant `kind`)
    /// compiles only its own pieces; a split of another mode (never made) has none.
    #[inline(always)]
    pub(crate) fn prepare(self, kind: EdgeKind, p: i64) -> Prepared {
        match self {
            AxisPlan::Empty => Prepared::Empty,
            AxisPlan::InRange(lo, hi) => Prepared::One(lo, hi),
            AxisPlan::Split(s) => match (kind, s) {
                (EdgeKind::Clamp, AxisSplit::Clamp { lo, hi }) => Prepared::Clamp { lo, hi },
                (EdgeKind::Repeat, AxisSplit::Periodic { odd, r0, rest, .. }) => {
                    prepare_periodic(false, odd, r0, rest, p)
                }
                (EdgeKind::Mirror, AxisSplit::Periodic { odd, r0, rest, .. }) => {
                    prepare_periodic(true, odd, r0, rest, p)
                }
                _ => Prepared::Empty,
            },
        }
    }
}

/// A placed axis ready to give its at most three in-range pieces one at a time
/// ([`Prepared::piece`]): the split path holds these few words per axis, never an array of
/// pieces (which a Cortex-M4 build zeroes and copies through `memset`/`memcpy`: about 1 KiB of
/// library code).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Prepared {
    /// No piece.
    Empty,
    /// One piece `[lo, hi)` of multiplicity 1.
    One(i64, i64),
    /// [`ClampToEdge`]: the part left of the texture, the part inside, the part right of it.
    Clamp { lo: i64, hi: i64 },
    /// [`Repeat`] / [`MirroredRepeat`]: the head of the first period, `whole` whole periods and
    /// the tail (reflected in the odd halves).
    Periodic {
        odd: bool,
        tail_odd: bool,
        r0: i64,
        whole: u64,
        tail: u64,
    },
}

/// The whole periods and the tail of a periodic split (one division).
#[inline(always)]
fn prepare_periodic(mirror: bool, odd: bool, r0: i64, rest: u64, p: i64) -> Prepared {
    // p = n 2^F is in [1, 2^55] (place_axis): its bit pattern is its value.
    let pu = p.cast_unsigned();
    let (whole, tail) = match div_rem_narrow(rest, pu) {
        Some(qr) if rest > pu => qr,
        _ => (0, rest),
    };
    Prepared::Periodic {
        odd,
        // The tail lies in the half (period) after the head and the whole ones.
        tail_odd: mirror && (odd ^ (whole & 1 == 0)),
        r0,
        whole,
        tail,
    }
}

impl Prepared {
    /// Piece `k` (`0..3`) on an axis of raw length `p = n 2^F`; absent pieces have `mult = 0`.
    #[inline(always)]
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "p = n 2^F in [2^F, 2^55] (place_axis, n >= 1): the head [r0, p) and the tail \
                  [0, tail) lie in [0, p], so p - a and p - b are in [0, p]; p - 2^F >= 0"
    )]
    pub(crate) fn piece(&self, k: usize, p: i64, f: u32) -> AxisPiece {
        let map = |a: i64, b: i64, odd: bool| if odd { (p - b, p - a) } else { (a, b) };
        match (*self, k) {
            (Prepared::One(lo, hi), 0) => AxisPiece::new(lo, hi, 1, false),
            (Prepared::Clamp { lo, hi }, 0) if lo < 0 => {
                AxisPiece::new(0, 1i64 << f, width_u64(lo, hi.min(0)), true)
            }
            (Prepared::Clamp { lo, hi }, 1) => AxisPiece::new(lo.max(0), hi.min(p), 1, false),
            (Prepared::Clamp { lo, hi }, 2) if hi > p => {
                AxisPiece::new(p - (1i64 << f), p, width_u64(lo.max(p), hi), true)
            }
            (Prepared::Periodic { odd, r0, .. }, 0) => {
                let (a, b) = map(r0, p, odd);
                AxisPiece::new(a, b, 1, false)
            }
            (Prepared::Periodic { whole, .. }, 1) => AxisPiece::new(0, p, whole, false),
            (Prepared::Periodic { tail_odd, tail, .. }, 2) => {
                // tail <= p <= 2^55 (prepare_periodic): its bit pattern is its value.
                let (a, b) = map(0, tail.cast_signed(), tail_odd);
                AxisPiece::new(a, b, 1, false)
            }
            _ => AxisPiece::default(),
        }
    }
}

/// The width `hi - lo` of an interval with `hi >= lo`, exact in `u64`.
#[inline(always)]
pub(crate) fn width_u64(lo: i64, hi: i64) -> u64 {
    // Two's complement: the difference of the bit patterns modulo 2^64 is hi - lo, which lies in
    // [0, 2^64) for hi >= lo.
    hi.cast_unsigned().wrapping_sub(lo.cast_unsigned())
}

/// `(q, r)` with `x = q p + r`, `0 <= r < p`, for `p > 0`: comparisons only when `x` lies in
/// `[0, p)` or `[p, 2p)`, else one division (checked: `None` only for `p <= 0`, which the
/// layouts' size check rules out; no panic path either way).
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "p > 0 (n >= 1, place_axis) and x >= p where x - p is formed: it lies in [0, x]"
)]
fn periods(x: i64, p: i64) -> Option<(i64, i64)> {
    if x >= 0 && x < p {
        Some((0, x))
    } else if x >= p && x - p < p {
        Some((1, x - p))
    } else {
        Some(div_euclid_narrow(x, p)?)
    }
}

/// `(floor(x / p), x mod p)` for `p > 0` with at most one division, in 32 bits whenever `|x|`
/// fits 32 bits (a hardware `udiv` on the Cortex-M4, against a software 64-bit division of
/// several hundred instructions), else one 64-bit division. `None` only for `p <= 0`.
///
/// A period longer than `|x|` needs no division: `x` lies in `[0, p)` (`q = 0`) or in `[-p, 0)`
/// (`q = -1`, `r = x + p`). Otherwise `p <= |x| < 2^32`, so the divisor fits 32 bits as well.
/// The 64-bit division is reached only for `|x| >= 2^32`: a firmware whose corners are 32-bit
/// raw values (`I24F8`, ...) never reaches it, and the compiler, seeing the corners
/// sign-extended from 32 bits, leaves it (and [`crate::div::divrem_u64_small`]) out of the
/// binary (Stable + `RepeatWithinPeriod` on the Cortex-M4: docs/firmware.md).
#[inline(always)]
#[allow(
    clippy::arithmetic_side_effects,
    reason = "x + p only for -p <= x < 0 (in [0, p)); -q0 - 1 for q0 <= u32::MAX does not wrap; \
              p - r0 for 0 < r0 < p"
)]
fn div_euclid_narrow(x: i64, p: i64) -> Option<(i64, i64)> {
    if p <= 0 {
        return None;
    }
    let Ok(a) = u32::try_from(x.unsigned_abs()) else {
        return crate::div::div_euclid_i64(x, p);
    };
    let Ok(d) = u32::try_from(p) else {
        // p >= 2^32 > |x|.
        return Some(if x >= 0 { (0, x) } else { (-1, x + p) });
    };
    if d > a {
        return Some(if x >= 0 { (0, x) } else { (-1, x + p) });
    }
    let d = core::num::NonZeroU32::new(d)?;
    let (q0, r0) = (i64::from(a / d), i64::from(a % d));
    Some(if x >= 0 {
        (q0, r0)
    } else if r0 == 0 {
        (-q0, 0)
    } else {
        (-q0 - 1, p - r0)
    })
}

/// `(x / d, x % d)` in 32 bits when both fit (one hardware `udiv`), else in 64 by the
/// smallest division code (rare operands: see [`crate::div::divrem_u64_small`]); `None` for
/// `d = 0`.
#[inline(always)]
fn div_rem_narrow(x: u64, d: u64) -> Option<(u64, u64)> {
    if let (Ok(a), Ok(d)) = (u32::try_from(x), u32::try_from(d)) {
        let d = core::num::NonZeroU32::new(d)?;
        return Some((u64::from(a / d), u64::from(a % d)));
    }
    crate::div::divrem_u64_small(x, d)
}

/// Places `[lo, hi)` (raw, `hi >= lo`) against an axis of `n >= 1` texels at `F = f`
/// (`n 2^F <= 2^55`, guaranteed by the layouts' size check and `F <= 24`).
#[inline(always)]
pub(crate) fn place_axis(
    kind: EdgeKind,
    lo: i64,
    hi: i64,
    n: usize,
    f: u32,
) -> Result<AxisPlan, Error> {
    #[allow(
        clippy::as_conversions,
        reason = "n <= 2^31 - 1 (check_dimensions) and f <= MAX_FRAC_BITS = 24: lossless, and \
                  n 2^F <= 2^55"
    )]
    let p = (n as i64) << f;
    if lo >= 0 && hi <= p {
        return Ok(AxisPlan::InRange(lo, hi));
    }
    match kind {
        EdgeKind::Border => {
            // `max` then `min`, not `clamp`: no panic path for `p < 0` (ruled out by the size
            // check, but not visible to the compiler for a run-time `F`).
            let (lo, hi) = (lo.max(0).min(p), hi.max(0).min(p));
            Ok(if lo >= hi {
                AxisPlan::Empty
            } else {
                AxisPlan::InRange(lo, hi)
            })
        }
        EdgeKind::Clamp => Ok(AxisPlan::Split(AxisSplit::Clamp { lo, hi })),
        EdgeKind::Repeat | EdgeKind::Mirror => place_periodic(kind == EdgeKind::Mirror, lo, hi, p),
    }
}

/// Places a periodic axis: in range when `[lo, hi)` lies within one period (half-period for
/// `MirroredRepeat`), else the numbers its split follows from.
#[inline(always)]
fn place_periodic(mirror: bool, lo: i64, hi: i64, p: i64) -> Result<AxisPlan, Error> {
    let (q0, r0) = periods(lo, p).ok_or(Error::CoordinateOutOfRange)?;
    let odd = mirror && q0 & 1 != 0;
    let d = width_u64(lo, hi);
    // 0 <= r0 < p <= 2^55 (periods, place_axis): their bit patterns are their values.
    let (r0u, pu) = (r0.cast_unsigned(), p.cast_unsigned());
    let end = r0u.checked_add(d).ok_or(Error::CoordinateOutOfRange)?;
    if end <= pu {
        // Reflection of [a, b) inside an odd half: [p - b, p - a). end <= p <= 2^55: exact.
        let end = end.cast_signed();
        #[allow(
            clippy::arithmetic_side_effects,
            reason = "0 <= r0 <= end <= p: p - end and p - r0 are in [0, p]"
        )]
        let (a, b) = if odd { (p - end, p - r0) } else { (r0, end) };
        return Ok(AxisPlan::InRange(a, b));
    }
    #[allow(clippy::arithmetic_side_effects, reason = "end > p here")]
    let rest = end - pu;
    Ok(AxisPlan::Split(AxisSplit::Periodic {
        mirror,
        odd,
        r0,
        rest,
    }))
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions,
    reason = "tests: a panic is a failed test"
)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// The extended texture's prefix sum of a 1-D texture along one axis, by summing texels:
    /// the reference for the pieces.
    fn direct(kind: EdgeKind, t: &[u64], lo: i64, hi: i64) -> u64 {
        (lo..hi)
            .map(|i| kind.texel_index(i, t.len()).map_or(0, |k| t[k]))
            .sum()
    }

    fn by_plan(kind: EdgeKind, t: &[u64], lo: i64, hi: i64) -> u64 {
        // f = 0: a piece [a, b) sums t[a..b].
        let seg = |a: i64, b: i64| -> u64 { t[a as usize..b as usize].iter().sum() };
        match place_axis(kind, lo, hi, t.len(), 0).unwrap() {
            AxisPlan::Empty => 0,
            AxisPlan::InRange(a, b) => seg(a, b),
            AxisPlan::Split(s) => s
                .pieces(kind, t.len() as i64, 0)
                .iter()
                .map(|pc| seg(pc.lo, pc.hi) * pc.mult)
                .sum(),
        }
    }

    #[test]
    fn pieces_sum_like_the_extended_texture() {
        // Under Miri (about 10^4 times slower) every 8th start and widths up to 12, which is
        // still more than the longest period (mirror, 2n = 10) so every wrap shape occurs.
        let (lo_step, widths) = if cfg!(miri) { (8, 13) } else { (1, 30) };
        for n in 1..6usize {
            let t: Vec<u64> = (0..n as u64).map(|i| 1 + i * i * 7).collect();
            for kind in EdgeKind::ALL {
                for lo in (-25i64..25).step_by(lo_step) {
                    for hi in lo..lo + widths {
                        assert_eq!(
                            by_plan(kind, &t, lo, hi),
                            direct(kind, &t, lo, hi),
                            "{kind:?} n={n} [{lo},{hi})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn at_most_three_pieces_and_in_range() {
        for kind in EdgeKind::ALL {
            for (lo, hi) in [
                (-1000i64, 1000i64),
                (i64::MIN / 2, i64::MAX / 2),
                (-7, 3),
                (5, 9),
            ] {
                if let Ok(AxisPlan::Split(s)) = place_axis(kind, lo, hi, 4, 0) {
                    let s = s.pieces(kind, 4, 0);
                    for p in s.iter() {
                        assert!(0 <= p.lo && p.lo < p.hi && p.hi <= 4, "{kind:?} {p:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn texel_index_zero_width_axis_is_none() {
        // Regression: the public edge methods panicked on a zero-width axis (fuzz finding,
        // edge.rs:173, 182, 200, 239 before the sealed API).
        for kind in EdgeKind::ALL {
            assert_eq!(kind.texel_index(3, 0), None);
            assert_eq!(kind.texel_index(i64::MIN, 0), None);
        }
        assert_eq!(EdgeKind::Mirror.texel_index(i64::MIN, 3), Some(1));
        assert_eq!(EdgeKind::Repeat.texel_index(i64::MAX, 3), Some(1));
        assert_eq!(EdgeKind::Clamp.texel_index(i64::MIN, 3), Some(0));
    }

    /// The extended texture's index by its definition, in `i128` (the test's own arithmetic).
    fn texel_index_ref(kind: EdgeKind, i: i64, n: u128) -> Option<u128> {
        let (i, n) = (i128::from(i), n as i128);
        if n == 0 {
            return None;
        }
        let k = match kind {
            EdgeKind::Border => {
                if i < 0 || i >= n {
                    return None;
                }
                i
            }
            EdgeKind::Clamp => i.clamp(0, n - 1),
            EdgeKind::Repeat => i.rem_euclid(n),
            EdgeKind::Mirror => {
                let r = i.rem_euclid(2 * n);
                if r < n {
                    r
                } else {
                    2 * n - 1 - r
                }
            }
        };
        Some(k as u128)
    }

    #[test]
    fn texel_index_matches_the_definition_for_every_axis_length() {
        // Under Miri (about 10^4 times slower) a few short axes and positions.
        let short = if cfg!(miri) { 5 } else { 40 };
        let mut ns: Vec<usize> = (1..short).collect();
        ns.extend([
            255,
            256,
            u32::MAX as usize,
            1 << 32,
            (1 << 62) - 1,
            1 << 62,
            (1 << 62) + 1,
            i64::MAX as usize,
            (i64::MAX as usize) + 1,
            usize::MAX - 1,
            usize::MAX,
        ]);
        let near = if cfg!(miri) { 8 } else { 100 };
        let mut is: Vec<i64> = (-near..near).collect();
        is.extend([
            i64::MIN,
            i64::MIN + 1,
            i64::MAX,
            i64::MAX - 1,
            -(1 << 62),
            1 << 62,
        ]);
        is.extend([(1 << 32) - 1, 1 << 32, -(1 << 32), u32::MAX as i64 + 7]);
        for kind in EdgeKind::ALL {
            for &n in &ns {
                for &i in &is {
                    assert_eq!(
                        kind.texel_index(i, n).map(|k| k as u128),
                        texel_index_ref(kind, i, n as u128),
                        "{kind:?} i = {i} n = {n}"
                    );
                }
            }
        }
    }

    #[test]
    fn narrow_division_matches_div_euclid() {
        for p in [
            1i64,
            2,
            3,
            7,
            255,
            1 << 20,
            u32::MAX as i64,
            u32::MAX as i64 + 1,
            1 << 40,
        ] {
            for x in [
                0i64,
                1,
                -1,
                5,
                -5,
                p,
                -p,
                p + 1,
                -p - 1,
                p - 1,
                1 - p,
                2 * p,
                -2 * p,
                3 * p + 1,
                -3 * p - 1,
                u32::MAX as i64,
                -(u32::MAX as i64),
                u32::MAX as i64 + 1,
                -(u32::MAX as i64) - 1,
                i64::MAX,
                i64::MIN,
                i64::MIN + 1,
            ] {
                assert_eq!(
                    div_euclid_narrow(x, p),
                    Some((x.div_euclid(p), x.rem_euclid(p))),
                    "{x} {p}"
                );
            }
        }
        assert_eq!(div_euclid_narrow(5, 0), None);
        // Every small pair: the one-period shortcuts (|x| < p) and the division meet exactly.
        let (pmax, xmax) = if cfg!(miri) { (8, 20) } else { (40, 200) };
        for p in 1i64..=pmax {
            for x in -xmax..=xmax {
                assert_eq!(
                    div_euclid_narrow(x, p),
                    Some((x.div_euclid(p), x.rem_euclid(p))),
                    "{x} {p}"
                );
            }
        }
    }

    #[test]
    fn names_round_trip() {
        for k in EdgeKind::ALL {
            assert_eq!(EdgeKind::from_name(k.name()), Some(k));
        }
    }
}
