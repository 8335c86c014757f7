//! Exact references and input generators shared by the fuzz targets (`fuzz_targets/`).
//!
//! Everything here is written independently of the crate under test: the summed-area table is
//! recomputed in `u128`, a box's integral over the *extended* texture (Crow §2.4: border,
//! clamp-to-edge, repeat, mirrored repeat) is the exact measure of the box's pre-image of every
//! texel, per axis, in `i128` ([`axis_weights`]), and means are rounded in big integers. The
//! only things taken from `texsat` are the types that name what is being checked. The references
//! themselves are checked against brute-force integration over raw sub-cells in the tests at the
//! bottom (`cargo test --manifest-path fuzz/Cargo.toml`, stable is enough).

use std::fmt::Debug;

use arbitrary::{Result, Unstructured};
use num_bigint::BigUint;
use texsat::{
    BoxLookup, BoxSum, EdgeKind, Error, FormKind, FracBits, NoCount, Quantity, Rect, Shortcut,
    ShortcutMean, Tally, Wide, WideOf,
};

/// A boundary mode, as this crate's own enum (so the reference does not lean on `EdgeKind`'s
/// own methods).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Zero outside the texture.
    Border,
    /// The nearest edge texel outside.
    Clamp,
    /// Period `n`.
    Repeat,
    /// Period `2n`, the second half reflected.
    Mirror,
}

impl Mode {
    /// All four modes.
    pub const ALL: [Mode; 4] = [Mode::Border, Mode::Clamp, Mode::Repeat, Mode::Mirror];

    /// The library's run-time value for this mode.
    pub fn kind(self) -> EdgeKind {
        match self {
            Mode::Border => EdgeKind::Border,
            Mode::Clamp => EdgeKind::Clamp,
            Mode::Repeat => EdgeKind::Repeat,
            Mode::Mirror => EdgeKind::Mirror,
        }
    }

    /// One of the four, from the input.
    pub fn pick(u: &mut Unstructured<'_>) -> Result<Mode> {
        Ok(*u.choose(&Mode::ALL)?)
    }
}

/// A texture as plain numbers: `w x h` texels of `c` channels, each in `[0, 2^bits - 1]`,
/// row-major with channels interleaved (`t[(y w + x) c + ch]`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tex {
    /// Width in texels.
    pub w: usize,
    /// Height in texels.
    pub h: usize,
    /// Channels.
    pub c: usize,
    /// Bits per texel.
    pub bits: u32,
    /// The texels.
    pub t: Vec<u16>,
}

impl Tex {
    /// A texture of `1..=max_w` x `1..=max_h` texels whose values follow one of a few styles
    /// chosen by the input: arbitrary, all at the maximum (the width proofs' worst case), sparse
    /// maxima, or tiny values. Small sides keep each execution fast.
    pub fn gen(
        u: &mut Unstructured<'_>,
        c: usize,
        bits: u32,
        max_w: usize,
        max_h: usize,
    ) -> Result<Tex> {
        let w = u.int_in_range(1..=max_w)?;
        let h = u.int_in_range(1..=max_h)?;
        let max = max_texel(bits) as u16;
        let style = u.int_in_range(0u8..=3)?;
        let mut t = Vec::with_capacity(w * h * c);
        for _ in 0..w * h * c {
            let v = match style {
                0 => u.arbitrary::<u16>()? & max,
                1 => max,
                2 => {
                    if u.ratio(1u8, 4)? {
                        max
                    } else {
                        0
                    }
                }
                _ => u.int_in_range(0..=3u16)? & max,
            };
            t.push(v);
        }
        Ok(Tex { w, h, c, bits, t })
    }

    /// Texel `(x, y)`, channel `ch`.
    pub fn at(&self, x: usize, y: usize, ch: usize) -> u16 {
        self.t[(y * self.w + x) * self.c + ch]
    }

    /// The inclusive summed-area table in `u128`: entry `(x, y)` is the sum of texels `(x', y')`
    /// with `x' <= x`, `y' <= y`, by inclusion-exclusion `t + S(left) + S(above) - S(diagonal)`
    /// (not the library's two running additions; checked against direct sums in the tests).
    pub fn sat(&self) -> Vec<u128> {
        let (w, c) = (self.w, self.c);
        let mut out = vec![0u128; w * self.h * c];
        for y in 0..self.h {
            for x in 0..w {
                for ch in 0..c {
                    let at = |out: &[u128], dx: usize, dy: usize| -> u128 {
                        if x < dx || y < dy {
                            0
                        } else {
                            out[((y - dy) * w + (x - dx)) * c + ch]
                        }
                    };
                    out[(y * w + x) * c + ch] =
                        u128::from(self.at(x, y, ch)) + at(&out, 1, 0) + at(&out, 0, 1)
                            - at(&out, 1, 1);
                }
            }
        }
        out
    }

    /// Per-channel whole-texture sums.
    pub fn totals(&self) -> Vec<u128> {
        (0..self.c)
            .map(|ch| {
                let mut s = 0u128;
                for y in 0..self.h {
                    for x in 0..self.w {
                        s += u128::from(self.at(x, y, ch));
                    }
                }
                s
            })
            .collect()
    }

    /// Bits of the largest channel total (what the lookups' accumulator checks use for a flat
    /// table).
    pub fn total_bits(&self) -> u32 {
        self.totals().into_iter().map(bits_of).max().unwrap_or(0)
    }
}

/// `2^bits - 1`.
pub fn max_texel(bits: u32) -> u64 {
    (1u64 << bits) - 1
}

/// `floor(log2 v) + 1`, 0 for 0.
pub fn bits_of(v: u128) -> u32 {
    128 - v.leading_zeros()
}

/// Bits of `(2^bits - 1) w h`: the worst-case total the build's width proof uses.
pub fn worst_case_bits(bits: u32, w: usize, h: usize) -> u32 {
    bits_of(u128::from(max_texel(bits)) * w as u128 * h as u128)
}

/// Validity of a lent table of `w x h x c` entries for `bits`-bit texels: the first texel
/// (row-major, then channel) that the table implies outside `[0, 2^bits - 1]`, as `(x, y, ch)`,
/// or `None` if the table is the SAT of some texture. In `i128`, so nothing overflows.
pub fn first_invalid(
    table: &[u128],
    w: usize,
    h: usize,
    c: usize,
    bits: u32,
) -> Option<(usize, usize, usize)> {
    let s = |x: usize, y: usize, ch: usize| -> i128 {
        // S at corner (x, y): entry (x - 1, y - 1), zero on the zero row and column.
        if x == 0 || y == 0 {
            0
        } else {
            table[((y - 1) * w + (x - 1)) * c + ch] as i128
        }
    };
    let max = i128::from(max_texel(bits));
    for y in 0..h {
        for x in 0..w {
            for ch in 0..c {
                let t = s(x + 1, y + 1, ch) - s(x, y + 1, ch) - s(x + 1, y, ch) + s(x, y, ch);
                if !(0..=max).contains(&t) {
                    return Some((x, y, ch));
                }
            }
        }
    }
    None
}

/// What `Sat::from_table` must answer for `table` (entries as `u128`, `w x h x c`, texels of
/// `bits` bits, `bits` valid): the table itself, or `InvalidTable` at the first texel (row-major,
/// then channel) it implies outside `[0, 2^bits - 1]`, whatever the entry type (a valid table
/// whose `S(x, y) + S(x-1, y-1)` exceeds the entry type is still valid: found by `sat_build`,
/// fixed in c0556b4).
pub fn from_table_verdict(
    table: &[u128],
    w: usize,
    h: usize,
    c: usize,
    bits: u32,
) -> std::result::Result<Vec<u128>, Error> {
    match first_invalid(table, w, h, c, bits) {
        None => Ok(table.to_vec()),
        Some((x, y, channel)) => Err(Error::InvalidTable { x, y, channel }),
    }
}

/// The texels a valid table implies (the inverse of [`Tex::sat`]).
pub fn texels_of_table(table: &[u128], w: usize, h: usize, c: usize, bits: u32) -> Tex {
    let s = |x: usize, y: usize, ch: usize| -> i128 {
        if x == 0 || y == 0 {
            0
        } else {
            table[((y - 1) * w + (x - 1)) * c + ch] as i128
        }
    };
    let mut t = Vec::with_capacity(w * h * c);
    for y in 0..h {
        for x in 0..w {
            for ch in 0..c {
                let v = s(x + 1, y + 1, ch) - s(x, y + 1, ch) - s(x + 1, y, ch) + s(x, y, ch);
                t.push(u16::try_from(v).expect("texels_of_table: table not valid"));
            }
        }
    }
    Tex { w, h, c, bits, t }
}

/// Length of `[lo, hi) ∩ [a, b)` with open ends where `a` or `b` is `None`.
fn overlap(lo: i128, hi: i128, a: Option<i128>, b: Option<i128>) -> i128 {
    let s = a.map_or(lo, |a| lo.max(a));
    let e = b.map_or(hi, |b| hi.min(b));
    (e - s).max(0)
}

/// Per texel column `u` of an axis of `n` texels, the measure (in raw units, `2^-F` texels) of
/// the points of `[lo, hi)` (raw, `F = f` fractional bits, `lo <= hi`) that the extended texture
/// shows as column `u`.
///
/// Border: `[u, u+1)`. Clamp: the same, with the first column open to the left and the last to
/// the right. Repeat: `G(hi) - G(lo)` with `G(X)` the signed measure of `[0, X)`'s points in
/// column `u`: `floor(X / P) 2^F + clamp(X mod P - u 2^F, 0, 2^F)`, `P = n 2^F` (one period holds
/// one copy of the column). Mirror: period `2P`, holding the column twice, at `u` and `2n-1-u`.
pub fn axis_weights(mode: Mode, lo: i64, hi: i64, n: usize, f: u32) -> Vec<u128> {
    assert!(lo <= hi && n >= 1 && f <= 24);
    let (lo, hi) = (i128::from(lo), i128::from(hi));
    let one = 1i128 << f;
    let nn = n as i128;
    let p = nn * one;
    let cl = |v: i128| v.clamp(0, one);
    (0..nn)
        .map(|u| {
            let w = match mode {
                Mode::Border => overlap(lo, hi, Some(u * one), Some((u + 1) * one)),
                Mode::Clamp => overlap(
                    lo,
                    hi,
                    (u != 0).then_some(u * one),
                    (u != nn - 1).then_some((u + 1) * one),
                ),
                Mode::Repeat => {
                    let g = |x: i128| x.div_euclid(p) * one + cl(x.rem_euclid(p) - u * one);
                    g(hi) - g(lo)
                }
                Mode::Mirror => {
                    let g = |x: i128| {
                        let r = x.rem_euclid(2 * p);
                        x.div_euclid(2 * p) * 2 * one
                            + cl(r - u * one)
                            + cl(r - (2 * nn - 1 - u) * one)
                    };
                    g(hi) - g(lo)
                }
            };
            u128::try_from(w).expect("axis weight is never negative")
        })
        .collect()
}

/// The exact integral of the extended texture over the box `[x0, x1) x [y0, y1)` (raw corners,
/// `F = f`, not inverted), scaled by `2^2F`, per channel; `None` where it exceeds `u128`.
pub fn box_integral(tex: &Tex, mode: Mode, r: [i64; 4], f: u32) -> Vec<Option<u128>> {
    let wx = axis_weights(mode, r[0], r[2], tex.w, f);
    let wy = axis_weights(mode, r[1], r[3], tex.h, f);
    (0..tex.c)
        .map(|ch| {
            let mut acc = Some(0u128);
            for (y, &b) in wy.iter().enumerate() {
                for (x, &a) in wx.iter().enumerate() {
                    let t = u128::from(tex.at(x, y, ch));
                    if t == 0 || a == 0 || b == 0 {
                        continue;
                    }
                    let term = a.checked_mul(b).and_then(|v| v.checked_mul(t));
                    acc = match (acc, term) {
                        (Some(s), Some(t)) => s.checked_add(t),
                        _ => None,
                    };
                }
            }
            acc
        })
        .collect()
}

/// `round(sum 2^g / (w h))`, to nearest, ties up, exactly.
pub fn mean_ref(sum: u128, g: u32, w: u64, h: u64) -> BigUint {
    let num = BigUint::from(sum) << g;
    let area = BigUint::from(w) * BigUint::from(h);
    let q = &num / &area;
    let r = &num % &area;
    if r.clone() * 2u32 >= area {
        q + 1u32
    } else {
        q
    }
}

/// `hi - lo` as `u64` (exact for `lo <= hi`).
pub fn side(lo: i64, hi: i64) -> u64 {
    (i128::from(hi) - i128::from(lo)) as u64
}

/// A raw coordinate on an axis of `n` texels with `F = f`: mostly near the texture (a few
/// periods either side, with a fraction), sometimes many periods away, sometimes at or near the
/// limits of `i64`.
pub fn coord(u: &mut Unstructured<'_>, n: usize, f: u32) -> Result<i64> {
    let one = 1i64 << f;
    let n = n as i64;
    Ok(match u.int_in_range(0u8..=15)? {
        0 => u.arbitrary::<i64>()?,
        1 => *u.choose(&[
            i64::MIN,
            i64::MIN + 1,
            i64::MAX,
            i64::MAX - 1,
            1 << 62,
            -(1 << 62),
            i64::MAX / 2,
            i64::MIN / 2,
            u32::MAX as i64,
            -(u32::MAX as i64),
        ])?,
        2 => {
            let k = u.int_in_range(-(1i64 << 36)..=1 << 36)?;
            k.saturating_mul(n * one)
                .saturating_add(u.int_in_range(-n * one..=n * one)?)
        }
        _ => {
            let i = u.int_in_range(-2 * n - 2..=3 * n + 2)?;
            let fr = if f == 0 || u.ratio(1u8, 4)? {
                0
            } else {
                u.int_in_range(0..=one - 1)?
            };
            i * one + fr
        }
    })
}

/// A raw box `[x0, y0, x1, y1]` for a `w x h` texture at `F = f`: usually not inverted (one in
/// sixteen may be), with sides that are usually a few texels, sometimes zero, sometimes huge.
pub fn raw_box(u: &mut Unstructured<'_>, w: usize, h: usize, f: u32) -> Result<[i64; 4]> {
    let one = 1i64 << f;
    let mut axis = |n: usize| -> Result<(i64, i64)> {
        let lo = coord(u, n, f)?;
        let hi = match u.int_in_range(0u8..=7)? {
            0 => coord(u, n, f)?,
            1 => lo,
            _ => {
                let len = u.int_in_range(0..=(4 * n as i64 + 2) * one)?;
                lo.saturating_add(len)
            }
        };
        Ok((lo, hi))
    };
    let (mut x0, mut x1) = axis(w)?;
    let (mut y0, mut y1) = axis(h)?;
    if !u.ratio(1u8, 16)? {
        if x1 < x0 {
            std::mem::swap(&mut x0, &mut x1);
        }
        if y1 < y0 {
            std::mem::swap(&mut y0, &mut y1);
        }
    }
    Ok([x0, y0, x1, y1])
}

/// What the reference says a box-sum lookup may return, and which refusals are legitimate.
#[derive(Debug, Clone)]
pub struct SumCase {
    /// The raw box.
    pub r: [i64; 4],
    /// `F`.
    pub f: u32,
    /// Exact per-channel sums scaled by `2^2F` (`None`: above `u128`); empty for an inverted box.
    pub sums: Vec<Option<u128>>,
    /// The largest value of the lookup's result word.
    pub word_max: u128,
    /// The form's accumulator check fails on this table (`TooWide { LookupAccumulator }` allowed).
    pub acc_refusal: bool,
    /// A modular layout may refuse this box (`TooWide { ModularBox }` allowed).
    pub modular_refusal: bool,
    /// The placement arithmetic may refuse these coordinates (`CoordinateOutOfRange` allowed).
    pub coord_refusal: bool,
}

impl SumCase {
    /// The case for box `r` under `mode` on `tex` at `F = f`; refusal flags start false.
    pub fn new(tex: &Tex, mode: Mode, r: [i64; 4], f: u32, word_max: u128) -> SumCase {
        let inverted = r[2] < r[0] || r[3] < r[1];
        let sums = if inverted {
            Vec::new()
        } else {
            box_integral(tex, mode, r, f)
        };
        // Periodic placement adds the box's side to its start's offset in the period, in u64
        // (edge.rs `place_periodic`): a side within a period of 2^64 may be refused.
        let coord_refusal = matches!(mode, Mode::Repeat | Mode::Mirror)
            && !inverted
            && [(r[0], r[2], tex.w), (r[1], r[3], tex.h)]
                .iter()
                .any(|&(lo, hi, n)| {
                    let p = (n as i128) << f;
                    i128::from(lo).rem_euclid(p) + i128::from(side(lo, hi)) > u64::MAX as i128
                });
        SumCase {
            r,
            f,
            sums,
            word_max,
            acc_refusal: false,
            modular_refusal: false,
            coord_refusal,
        }
    }

    /// Inverted box.
    pub fn inverted(&self) -> bool {
        self.r[2] < self.r[0] || self.r[3] < self.r[1]
    }

    /// Raw sides `(W, H)` (for a box that is not inverted).
    pub fn sides(&self) -> (u64, u64) {
        (side(self.r[0], self.r[2]), side(self.r[1], self.r[3]))
    }

    /// Some channel's sum does not fit the result word.
    pub fn too_big(&self) -> bool {
        self.sums
            .iter()
            .any(|s| s.is_none_or(|v| v > self.word_max))
    }

    /// Panics (the fuzzer's finding) unless `got` is what this case allows.
    pub fn check<W: Wide, const C: usize>(
        &self,
        got: &std::result::Result<BoxSum<W, C>, Error>,
        what: &dyn Debug,
    ) {
        let fail = |why: &str| -> ! {
            panic!(
                "{what:?}: {why}\n  box {:?} F={}\n  got {got:?}\n  case {self:?}",
                self.r, self.f
            )
        };
        if self.inverted() {
            if !matches!(got, Err(Error::InvertedBox)) {
                fail("an inverted box must be InvertedBox");
            }
            return;
        }
        match got {
            Ok(s) => {
                if s.sides_raw() != self.sides() || s.frac_bits() != self.f {
                    fail("wrong sides or F");
                }
                for (ch, want) in self.sums.iter().enumerate() {
                    let g: u128 = s.scaled_sum(ch).into();
                    if *want != Some(g) {
                        fail(&format!("channel {ch}: sum {g}, exact {want:?}"));
                    }
                }
            }
            Err(Error::TooWide {
                what: Quantity::LookupAccumulator,
                ..
            }) if self.acc_refusal || self.too_big() => {}
            Err(Error::TooWide {
                what: Quantity::ModularBox,
                ..
            }) if self.modular_refusal => {}
            Err(Error::CoordinateOutOfRange) if self.coord_refusal => {}
            Err(_) => fail("refused without cause"),
        }
    }
}

/// Panics unless `got` is the mean of channel `ch` of an `Ok` lookup as [`mean_ref`] says,
/// or a refusal the documentation allows.
///
/// Allowed refusals: `ZeroArea` for a zero side; `TooWide { MeanNumerator }` exactly when the
/// rounded mean does not fit the word (not merely `sum 2^g`: found by `lookup`, fixed in
/// f7c47fc).
pub fn check_mean<W: Into<u128> + Copy + Debug>(
    got: &std::result::Result<W, Error>,
    sum: u128,
    g: u32,
    sides: (u64, u64),
    word_bits: u32,
    what: &dyn Debug,
) {
    let fail = |why: &str| -> ! {
        panic!("{what:?}: mean {why}: sum {sum} g {g} sides {sides:?}, got {got:?}")
    };
    let (w, h) = sides;
    if w == 0 || h == 0 {
        if !matches!(got, Err(Error::ZeroArea)) {
            fail("of a zero-area box must be ZeroArea");
        }
        return;
    }
    let exact = mean_ref(sum, g, w, h);
    match got {
        Ok(v) => {
            let v: u128 = (*v).into();
            if BigUint::from(v) != exact {
                fail(&format!("is not the exact rounded mean {exact}"));
            }
        }
        Err(Error::TooWide {
            what: Quantity::MeanNumerator,
            ..
        }) => {
            if !mean_refusal_allowed(sum, g, sides, word_bits) {
                fail(&format!("refused, but the exact mean {exact} fits"));
            }
        }
        Err(_) => fail("refused without cause"),
    }
}

/// Whether `TooWide { MeanNumerator }` is an allowed answer for this mean (see [`check_mean`]).
pub fn mean_refusal_allowed(sum: u128, g: u32, sides: (u64, u64), word_bits: u32) -> bool {
    let (w, h) = sides;
    if w == 0 || h == 0 {
        return false;
    }
    mean_ref(sum, g, w, h).bits() > u64::from(word_bits)
}

/// Accumulator value bits of a table of `entry_bits`-bit words (`i32`, `i64`, `i128` without
/// the sign), as `docs/design.md` states them.
pub fn acc_value_bits(entry_bits: u32) -> u32 {
    match entry_bits {
        16 => 31,
        32 => 63,
        _ => 127,
    }
}

/// Accumulator bits a form needs (`docs/design.md`): Paper `T + 2F`, Stable `T + 2F + 1`.
pub fn form_acc_bits(form: FormKind, total_bits: u32, f: u32) -> u32 {
    match form {
        FormKind::Paper => total_bits + 2 * f,
        FormKind::Stable => total_bits + 2 * f + 1,
    }
}

/// Texel cells `[lo, hi)` overlaps: `ceil(hi) - floor(lo)` (raw, `F = f`).
fn cells(lo: i64, hi: i64, f: u32) -> u128 {
    let one = 1i128 << f;
    let (lo, hi) = (i128::from(lo), i128::from(hi));
    (hi.div_euclid(one) + i128::from(hi.rem_euclid(one) != 0) - lo.div_euclid(one)) as u128
}

/// Whether a modular layout (`2^k`) may refuse box `r` at `F = f` with `headroom` extra bits:
/// `bits(cells_x cells_y m) + headroom > k` (`src/layouts/modular.rs`: the bound uses the cells the
/// box overlaps; a placed box overlaps no more cells than the box itself).
pub fn modular_may_refuse(r: [i64; 4], f: u32, texel_bits: u32, k: u32, headroom: u32) -> bool {
    let bound = cells(r[0], r[2], f)
        .checked_mul(cells(r[1], r[3], f))
        .and_then(|a| a.checked_mul(u128::from(max_texel(texel_bits))));
    match bound {
        Some(v) => bits_of(v) + headroom > k,
        None => true,
    }
}

/// What the fuzz targets know about a layout independently of it.
#[derive(Debug, Clone, Copy)]
pub struct Facts {
    /// The texture.
    pub texel_bits: u32,
    /// Bits of the values the lookups' accumulator check uses: the actual total for a flat
    /// table, the worst case for a tiled layout, `k` for a modular one.
    pub value_bits: u32,
    /// Bits of the table word (16, 32, 64): fixes the accumulator and the result word.
    pub entry_bits: u32,
    /// `Some(k)` for a modular layout.
    pub modulus: Option<u32>,
    /// Reads one corner `S(x, y)` costs at most: 1 for the flat table and a modular layout,
    /// one field per pair of levels, `(Lx + 1)(Ly + 1)`, for a tiled one.
    pub reads_per_corner: u64,
}

impl Facts {
    /// Bits of the result word: `u64`, or `u128` for 64-bit tables.
    pub fn word_bits(&self) -> u32 {
        if self.entry_bits == 64 {
            128
        } else {
            64
        }
    }

    fn word_max(&self) -> u128 {
        if self.entry_bits == 64 {
            u128::MAX
        } else {
            u128::from(u64::MAX)
        }
    }

    /// The case for one lookup: exact sums and the refusals allowed for `form` (`None`: the
    /// 4-read lookup at integer corners, which needs no accumulator headroom).
    pub fn case(
        &self,
        tex: &Tex,
        mode: Mode,
        r: [i64; 4],
        f: u32,
        form: Option<FormKind>,
    ) -> SumCase {
        let mut c = SumCase::new(tex, mode, r, f, self.word_max());
        if let Some(form) = form {
            c.acc_refusal =
                form_acc_bits(form, self.value_bits, f) > acc_value_bits(self.entry_bits);
        }
        if let Some(k) = self.modulus {
            let headroom = match form {
                Some(FormKind::Paper) => 2 * f,
                _ => 0,
            };
            c.modular_refusal =
                !c.inverted() && modular_may_refuse(r, f, self.texel_bits, k, headroom);
        }
        c
    }
}

/// A `fixed` corner type for [`BoxLookup::box_sum`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FixedTy {
    /// `F = 8` in `i16`.
    I8F8,
    /// `F = 8` in `i32` (the crate's default).
    I24F8,
    /// `F = 8` in `u32`.
    U24F8,
    /// `F = 24` in `i64`.
    I40F24,
    /// `F = 32` in `i64`: more fractional bits than the lookups support.
    I32F32,
}

impl FixedTy {
    const ALL: [FixedTy; 5] = [
        FixedTy::I8F8,
        FixedTy::I24F8,
        FixedTy::U24F8,
        FixedTy::I40F24,
        FixedTy::I32F32,
    ];

    /// `F` and the range of the raw bits.
    fn spec(self) -> (u32, i64, i64) {
        match self {
            FixedTy::I8F8 => (8, i16::MIN.into(), i16::MAX.into()),
            FixedTy::I24F8 => (8, i32::MIN.into(), i32::MAX.into()),
            FixedTy::U24F8 => (8, 0, u32::MAX.into()),
            FixedTy::I40F24 => (24, i64::MIN, i64::MAX),
            FixedTy::I32F32 => (32, i64::MIN, i64::MAX),
        }
    }
}

/// One lookup with its parameters, made before it runs so that several layouts can answer the
/// same query.
#[derive(Debug, Clone)]
pub enum Lookup {
    /// `box_sum_int` (integer corners, 4 reads).
    Int {
        /// corners
        r: [i32; 4],
    },
    /// `box_sum_raw` with `F` as a value.
    Raw {
        /// raw corners
        r: [i64; 4],
        /// `F`
        f: u32,
        /// form
        form: FormKind,
    },
    /// `box_sum` with corners of a `fixed` type.
    Fixed {
        /// raw bits, inside the type's range
        r: [i64; 4],
        /// the type
        ty: FixedTy,
        /// form
        form: FormKind,
    },
    /// `box_mean_shortcut_raw` (or `box_mean_shortcut` with `I24F8` corners when `fixed`).
    Shortcut {
        /// raw corners
        r: [i64; 4],
        /// `F`
        f: u32,
        /// form of the exact fallback
        form: FormKind,
        /// the shortcut's threshold
        shortcut: Shortcut,
        /// through the `fixed` API with `I24F8`
        fixed: bool,
    },
}

/// A lookup under a boundary mode, and the mean asked of its result.
#[derive(Debug, Clone)]
pub struct Query {
    /// What to look up.
    pub lookup: Lookup,
    /// Boundary mode.
    pub mode: Mode,
    /// Output fraction bits of the mean.
    pub g: u32,
    /// Channel whose mean is asked (may be past the last: `NoSuchChannel`).
    pub ch: usize,
}

fn pick_form(u: &mut Unstructured<'_>) -> Result<FormKind> {
    Ok(if u.arbitrary::<bool>()? {
        FormKind::Paper
    } else {
        FormKind::Stable
    })
}

impl Query {
    /// A query for a `w x h` texture of `c` channels and `texel_bits`-bit texels.
    pub fn gen(
        u: &mut Unstructured<'_>,
        w: usize,
        h: usize,
        c: usize,
        texel_bits: u32,
    ) -> Result<Query> {
        let mode = Mode::pick(u)?;
        let small_f = |u: &mut Unstructured<'_>| -> Result<u32> {
            // F <= 24; small F most often (it is where u16 tables still work).
            Ok(if u.ratio(3u8, 4)? {
                u.int_in_range(0..=9)?
            } else {
                u.int_in_range(0..=24)?
            })
        };
        let lookup = match u.int_in_range(0u8..=3)? {
            0 => {
                let r = raw_box(u, w, h, 0)?;
                let n = |v: i64| v.clamp(i32::MIN.into(), i32::MAX.into()) as i32;
                Lookup::Int {
                    r: [n(r[0]), n(r[1]), n(r[2]), n(r[3])],
                }
            }
            1 => {
                let f = small_f(u)?;
                Lookup::Raw {
                    r: raw_box(u, w, h, f)?,
                    f,
                    form: pick_form(u)?,
                }
            }
            2 => {
                let ty = *u.choose(&FixedTy::ALL)?;
                let (f, lo, hi) = ty.spec();
                let r = raw_box(u, w, h, f.min(24))?.map(|v| v.clamp(lo, hi));
                Lookup::Fixed {
                    r,
                    ty,
                    form: pick_form(u)?,
                }
            }
            _ => {
                let fixed = u.ratio(1u8, 4)?;
                let f = if fixed { 8 } else { small_f(u)? };
                let mut r = raw_box(u, w, h, f)?;
                if fixed {
                    r = r.map(|v| v.clamp(i32::MIN.into(), i32::MAX.into()));
                }
                let shortcut = match u.int_in_range(0u8..=3)? {
                    0 => Shortcut::with_min_side(u.arbitrary()?),
                    1 => Shortcut::for_tolerance(
                        texel_bits,
                        u.int_in_range(0..=1000)?,
                        u.int_in_range(1..=1000)?,
                    ),
                    _ => Shortcut::with_min_side(u.int_in_range(0..=12)?),
                };
                Lookup::Shortcut {
                    r,
                    f,
                    form: pick_form(u)?,
                    shortcut,
                    fixed,
                }
            }
        };
        let g = if u.ratio(3u8, 4)? {
            u.int_in_range(0..=32)?
        } else {
            u.int_in_range(0..=200)?
        };
        let ch = u.int_in_range(0..=c)?;
        Ok(Query {
            lookup,
            mode,
            g,
            ch,
        })
    }
}

/// What a layout answered, normalized for comparing layouts: the sums (scaled by `2^2F`, or the
/// shortcut's means) and the requested mean, or the refusal.
pub type Answer = std::result::Result<(Vec<u128>, std::result::Result<u128, Error>), Error>;

/// A zero-sized mode chosen by a run-time [`Mode`], bound to `$m` in `$body`.
#[macro_export]
macro_rules! with_mode {
    ($mode:expr, |$m:ident| $body:expr) => {
        match $mode {
            $crate::Mode::Border => {
                let $m = texsat::Border;
                $body
            }
            $crate::Mode::Clamp => {
                let $m = texsat::ClampToEdge;
                $body
            }
            $crate::Mode::Repeat => {
                let $m = texsat::Repeat;
                $body
            }
            $crate::Mode::Mirror => {
                let $m = texsat::MirroredRepeat;
                $body
            }
        }
    };
}

/// A zero-sized form chosen by a run-time [`FormKind`], bound to `$m` in `$body`.
#[macro_export]
macro_rules! with_form {
    ($form:expr, |$m:ident| $body:expr) => {
        match $form {
            texsat::FormKind::Paper => {
                let $m = texsat::Paper;
                $body
            }
            texsat::FormKind::Stable => {
                let $m = texsat::Stable;
                $body
            }
        }
    };
}

/// `hi - lo` for `hi >= lo` (as the lookups compute it; 0 for an inverted box, which both
/// modes refuse alike).
fn width_of(lo: i64, hi: i64) -> u64 {
    if hi < lo {
        0
    } else {
        hi.wrapping_sub(lo) as u64
    }
}

/// The same result, as a run-time choice and as zero-sized types, must agree exactly.
fn same<T: PartialEq + Debug>(a: &T, b: &T, what: &dyn Debug) {
    assert_eq!(a, b, "{what:?}: run-time and zero-sized mode/form disagree");
}

/// `RepeatWithinPeriod`'s answer `within` against Repeat's `got` for a box of raw sides `w x h`
/// on a texture of `pw x ph` raw units: the same answer for an empty box or one at most a
/// period long on both axes; for a longer one a refusal, `OutsidePlan { LongerThanPeriod }`
/// unless an earlier check (the one Repeat gives too) refused it first.
fn check_within<T: PartialEq + Debug>(
    got: &std::result::Result<T, Error>,
    within: &std::result::Result<T, Error>,
    (w, h): (u64, u64),
    (pw, ph): (u64, u64),
    what: &dyn Debug,
) {
    if w == 0 || h == 0 || (w <= pw && h <= ph) {
        assert_eq!(
            got, within,
            "{what:?}: Repeat and RepeatWithinPeriod disagree"
        );
        return;
    }
    let longer = Error::OutsidePlan {
        limit: texsat::plan::PlanLimit::LongerThanPeriod,
    };
    match within {
        Err(e) if *e == longer => {}
        Err(_) => assert_eq!(
            got, within,
            "{what:?}: RepeatWithinPeriod's earlier refusal"
        ),
        Ok(v) => panic!("{what:?}: RepeatWithinPeriod answered a box longer than a period: {v:?}"),
    }
}

/// `mean_rounded_u32` against `mean_rounded`'s answer `wide` for the channel sum `sum` (None:
/// no such channel): the same value where the numerator `sum 2^g` fits 64 bits and the area and
/// the mean fit 32 bits; otherwise the refusal that names the first that does not (numerator,
/// area, mean); the wide mean's own refusals (no such channel, zero area) alike.
fn check_mean_u32(
    got: std::result::Result<u32, Error>,
    wide: &std::result::Result<u128, Error>,
    sum: Option<u128>,
    g: u32,
    (w, h): (u64, u64),
    q: &dyn Debug,
) {
    let (Some(sum), Ok(m)) = (sum, wide) else {
        if let Err(e) = wide {
            if !matches!(e, Error::TooWide { .. }) {
                assert_eq!(got, Err(*e), "{q:?}: mean_rounded_u32");
                return;
            }
        }
        assert!(
            got.is_err(),
            "{q:?}: mean_rounded_u32 answered where mean_rounded refused"
        );
        return;
    };
    let bits = |v: u128| 128 - v.leading_zeros();
    let area = u128::from(w) * u128::from(h);
    let want = if sum != 0 && bits(sum) + g > 64 {
        Some(Quantity::MeanNumerator)
    } else if sum != 0 && area > u128::from(u32::MAX) {
        Some(Quantity::MeanArea)
    } else if *m > u128::from(u32::MAX) {
        Some(Quantity::Mean)
    } else {
        None
    };
    match want {
        None => assert_eq!(got.map(u128::from), Ok(*m), "{q:?}: mean_rounded_u32"),
        Some(what) => assert!(
            matches!(got, Err(Error::TooWide { what: w, .. }) if w == what),
            "{q:?}: mean_rounded_u32 {got:?}, want a refusal of {what:?}"
        ),
    }
}

/// At most 9 pieces of 16 corner reads each, whatever the box.
fn check_reads(t: &Tally, facts: &Facts, what: &dyn Debug) {
    let max = 9 * 16 * facts.reads_per_corner;
    assert!(t.reads <= max, "{what:?}: {} reads, at most {max}", t.reads);
}

/// Runs `q` on layout `l` (through the run-time `EdgeKind`/`FormKind` API with a [`Tally`], and
/// again through the zero-sized modes and forms with [`NoCount`]), checks every result against
/// the exact reference for `tex` and the refusals `facts` allow, and returns the answer.
pub fn run_query<L: BoxLookup<C>, const C: usize>(
    l: &L,
    facts: &Facts,
    tex: &Tex,
    q: &Query,
) -> Answer
where
    WideOf<L, C>: Into<u128> + Debug,
{
    let mode = q.mode;
    let wb = facts.word_bits();
    let sums_of = |s: &BoxSum<WideOf<L, C>, C>| -> Vec<u128> {
        s.scaled_sums().iter().map(|&v| v.into()).collect()
    };
    // The mean asked of a sum, checked; `NoSuchChannel` past the last channel.
    let mean_of =
        |s: &BoxSum<WideOf<L, C>, C>, case: &SumCase| -> std::result::Result<u128, Error> {
            let mut k = Tally::new();
            let got = s.mean_rounded(q.ch, q.g, &mut k);
            if q.ch >= C {
                assert_eq!(got, Err(Error::NoSuchChannel), "{q:?}");
            } else {
                let sum = case.sums[q.ch].expect("an Ok sum fits");
                check_mean(&got, sum, q.g, case.sides(), wb, q);
            }
            check_mean_u32(
                s.mean_rounded_u32(q.ch, q.g, &mut NoCount),
                &got.map(Into::into),
                case.sums.get(q.ch).copied().flatten(),
                q.g,
                case.sides(),
                q,
            );
            // Every channel's mean at once agrees with the channel-by-channel ones (or fails with
            // the first channel's refusal).
            let all = s.means_rounded(q.g, &mut NoCount);
            let mut first_err = None;
            for (ch, want) in case.sums.iter().enumerate() {
                let one = s.mean_rounded(ch, q.g, &mut NoCount).map(Into::into);
                check_mean(
                    &one,
                    want.expect("an Ok sum fits"),
                    q.g,
                    case.sides(),
                    wb,
                    q,
                );
                match (&all, one) {
                    (Ok(a), _) => assert_eq!(Ok(a[ch].into()), one, "{q:?}: means_rounded, {ch}"),
                    (Err(_), Err(e)) => {
                        first_err.get_or_insert(e);
                    }
                    (Err(_), Ok(_)) => {}
                }
            }
            if let Err(e) = all {
                assert_eq!(first_err, Some(e), "{q:?}: means_rounded refused");
            }
            got.map(Into::into)
        };
    match &q.lookup {
        Lookup::Int { r } => {
            let rect = Rect::new(r[0], r[1], r[2], r[3]);
            let r64 = r.map(i64::from);
            let case = facts.case(tex, mode, r64, 0, None);
            let mut k = Tally::new();
            let got = l.box_sum_int(&rect, mode.kind(), &mut k);
            check_reads(&k, facts, q);
            let zst = with_mode!(mode, |m| l.box_sum_int(&rect, m, &mut NoCount));
            same(&got, &zst, q);
            if mode == Mode::Repeat {
                let mut kw = Tally::new();
                let within = l.box_sum_int(&rect, texsat::RepeatWithinPeriod, &mut kw);
                let sides = (width_of(r64[0], r64[2]), width_of(r64[1], r64[3]));
                check_within(&got, &within, sides, (tex.w as u64, tex.h as u64), q);
                if within.is_ok() {
                    assert_eq!(kw, k, "{q:?}: RepeatWithinPeriod's counted costs");
                }
            }
            case.check(&got, q);
            got.map(|s| (sums_of(&s), mean_of(&s, &case)))
        }
        Lookup::Raw { r, f, form } => {
            let rect = Rect::new(r[0], r[1], r[2], r[3]);
            let fb = FracBits::new(*f).expect("F <= 24");
            let case = facts.case(tex, mode, *r, *f, Some(*form));
            let mut k = Tally::new();
            let got = l.box_sum_raw(&rect, fb, *form, mode.kind(), &mut k);
            check_reads(&k, facts, q);
            let zst = with_mode!(mode, |m| with_form!(*form, |fm| l.box_sum_raw(
                &rect,
                fb,
                fm,
                m,
                &mut NoCount
            )));
            same(&got, &zst, q);
            if mode == Mode::Repeat {
                let mut kw = Tally::new();
                let within = l.box_sum_raw(&rect, fb, *form, texsat::RepeatWithinPeriod, &mut kw);
                let sides = (width_of(r[0], r[2]), width_of(r[1], r[3]));
                let period = ((tex.w as u64) << f, (tex.h as u64) << f);
                check_within(&got, &within, sides, period, q);
                if within.is_ok() {
                    assert_eq!(kw, k, "{q:?}: RepeatWithinPeriod's counted costs");
                }
            }
            case.check(&got, q);
            got.map(|s| (sums_of(&s), mean_of(&s, &case)))
        }
        Lookup::Fixed { r, ty, form } => {
            use fixed::types::{I32F32, I40F24, I8F8, U24F8};
            use texsat::DefaultCoord as I24F8;
            macro_rules! fixed_sum {
                ($t:ty, $bits:ty) => {{
                    let x = |v: i64| <$t>::from_bits(v as $bits);
                    let rect = Rect::new(x(r[0]), x(r[1]), x(r[2]), x(r[3]));
                    let got = l.box_sum(&rect, *form, mode.kind(), &mut NoCount);
                    let zst = with_mode!(mode, |m| with_form!(*form, |fm| l.box_sum(
                        &rect,
                        fm,
                        m,
                        &mut NoCount
                    )));
                    same(&got, &zst, q);
                    got
                }};
            }
            let got = match ty {
                FixedTy::I8F8 => fixed_sum!(I8F8, i16),
                FixedTy::I24F8 => fixed_sum!(I24F8, i32),
                FixedTy::U24F8 => fixed_sum!(U24F8, u32),
                FixedTy::I40F24 => fixed_sum!(I40F24, i64),
                FixedTy::I32F32 => fixed_sum!(I32F32, i64),
            };
            let (f, _, _) = ty.spec();
            if f > 24 {
                assert_eq!(
                    got.map(|_| ()),
                    Err(Error::FracBitsUnsupported {
                        frac_bits: f,
                        max: 24
                    }),
                    "{q:?}"
                );
                return Err(Error::FracBitsUnsupported {
                    frac_bits: f,
                    max: 24,
                });
            }
            let case = facts.case(tex, mode, *r, f, Some(*form));
            case.check(&got, q);
            got.map(|s| (sums_of(&s), mean_of(&s, &case)))
        }
        Lookup::Shortcut {
            r,
            f,
            form,
            shortcut,
            fixed,
        } => {
            let fb = FracBits::new(*f).expect("F <= 24");
            let rect = Rect::new(r[0], r[1], r[2], r[3]);
            let mut k = Tally::new();
            let got = l.box_mean_shortcut_raw(&rect, fb, *form, mode.kind(), shortcut, q.g, &mut k);
            check_reads(&k, facts, q);
            if *fixed {
                let x = |v: i64| texsat::DefaultCoord::from_bits(v as i32);
                let rect = Rect::new(x(r[0]), x(r[1]), x(r[2]), x(r[3]));
                let via = with_mode!(mode, |m| with_form!(*form, |fm| l.box_mean_shortcut(
                    &rect,
                    fm,
                    m,
                    shortcut,
                    q.g,
                    &mut NoCount
                )));
                same(&got, &via, q);
            }
            check_shortcut(facts, tex, q, *r, *f, *form, shortcut, &got);
            got.map(|m| {
                let means: Vec<u128> = m.means.iter().map(|&v| v.into()).collect();
                let one = means.get(q.ch).copied().ok_or(Error::NoSuchChannel);
                (means, one)
            })
        }
    }
}

/// Round a raw coordinate to the nearest integer, ties up; `None` past `i64` (the shortcut's
/// documented `CoordinateOutOfRange`).
fn round_raw(v: i64, f: u32) -> Option<i64> {
    if f == 0 {
        return Some(v);
    }
    let s = i128::from(v) + (1i128 << (f - 1));
    (s <= i128::from(i64::MAX)).then(|| s.div_euclid(1i128 << f) as i64)
}

/// Checks a shortcut mean: the 4-read path exactly when both sides reach the threshold, then the
/// exact rounded mean of the rounded box and within the proven bound of the true box's mean;
/// otherwise the exact rounded mean of the box.
#[allow(clippy::too_many_arguments)]
fn check_shortcut<W: Wide, const C: usize>(
    facts: &Facts,
    tex: &Tex,
    q: &Query,
    r: [i64; 4],
    f: u32,
    form: FormKind,
    shortcut: &Shortcut,
    got: &std::result::Result<ShortcutMean<W, C>, Error>,
) {
    let fail = |why: &str| -> ! { panic!("{q:?}: shortcut {why}: got {got:?}") };
    if r[2] < r[0] || r[3] < r[1] {
        if !matches!(got, Err(Error::InvertedBox)) {
            fail("inverted box must be InvertedBox");
        }
        return;
    }
    let (wr, hr) = (side(r[0], r[2]), side(r[1], r[3]));
    let min_raw = u128::from(shortcut.min_side()) << f;
    let taken = u128::from(wr) >= min_raw && u128::from(hr) >= min_raw;
    let wb = facts.word_bits();
    if !taken {
        let case = facts.case(tex, q.mode, r, f, Some(form));
        match got {
            Ok(m) => {
                if m.shortcut {
                    fail("taken below the threshold");
                }
                for (ch, &v) in m.means.iter().enumerate() {
                    let sum = case.sums[ch].unwrap_or_else(|| fail("a sum above u128 answered"));
                    check_mean(&Ok(v), sum, q.g, (wr, hr), wb, q);
                }
            }
            Err(Error::ZeroArea) if wr == 0 || hr == 0 => {}
            Err(Error::TooWide {
                what: Quantity::MeanNumerator,
                ..
            }) => {
                let ok = case
                    .sums
                    .iter()
                    .any(|s| s.is_none_or(|s| mean_refusal_allowed(s, q.g, (wr, hr), wb)));
                if !ok {
                    fail("mean refused, but every mean fits");
                }
            }
            Err(e) => {
                // The same refusals as the plain lookup.
                let as_sum: std::result::Result<BoxSum<u128, C>, Error> = Err(*e);
                case.check(&as_sum, q);
            }
        }
        return;
    }
    // Taken: the 4-read lookup of the rounded box.
    let rounded = [
        round_raw(r[0], f),
        round_raw(r[1], f),
        round_raw(r[2], f),
        round_raw(r[3], f),
    ];
    let Some(rb) = rounded.iter().copied().collect::<Option<Vec<i64>>>() else {
        if !matches!(got, Err(Error::CoordinateOutOfRange)) {
            fail("rounding past i64 must be CoordinateOutOfRange");
        }
        return;
    };
    let rb = [rb[0], rb[1], rb[2], rb[3]];
    let case = facts.case(tex, q.mode, rb, 0, None);
    let (wr0, hr0) = case.sides();
    match got {
        Ok(m) => {
            if !m.shortcut {
                fail("not taken above the threshold");
            }
            for (ch, &v) in m.means.iter().enumerate() {
                let sr = case.sums[ch].unwrap_or_else(|| fail("a sum above u128 answered"));
                check_mean(&Ok(v), sr, q.g, (wr0, hr0), wb, q);
                // The bound, in exact rationals: |SB/(Wr Hr) - SR/(WR HR)|
                //   <= m 2^F (1/(Wr - 2^F) + 1/(Hr - 2^F)).
                let exact = box_integral(tex, q.mode, r, f);
                if let Some(sb) = exact[ch] {
                    use num_bigint::BigInt;
                    let one = BigInt::from(1u8) << f;
                    let (bw, bh) = (BigInt::from(wr), BigInt::from(hr));
                    let (rw, rh) = (BigInt::from(wr0), BigInt::from(hr0));
                    let diff = BigInt::from(sb) * &rw * &rh - BigInt::from(sr) * &bw * &bh;
                    let lhs = diff.magnitude() * ((&bw - &one) * (&bh - &one)).magnitude();
                    let rhs = (BigInt::from(max_texel(tex.bits))
                        * &one
                        * ((&bh - &one) + (&bw - &one))
                        * &bw
                        * &bh
                        * &rw
                        * &rh)
                        .magnitude()
                        .clone();
                    if lhs > rhs {
                        fail(&format!("channel {ch}: error above the proven bound"));
                    }
                }
            }
        }
        Err(Error::TooWide {
            what: Quantity::MeanNumerator,
            ..
        }) => {
            let ok = case
                .sums
                .iter()
                .any(|s| s.is_none_or(|s| mean_refusal_allowed(s, q.g, (wr0, hr0), wb)));
            if !ok {
                fail("mean of the rounded box refused, but every mean fits");
            }
        }
        Err(e) => {
            let as_sum: std::result::Result<BoxSum<u128, C>, Error> = Err(*e);
            case.check(&as_sum, q);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The column the extended texture shows at integer position `i`, by stepping (no closed
    /// form): the definition the weights must agree with.
    fn ext(mode: Mode, i: i64, n: i64) -> Option<i64> {
        match mode {
            Mode::Border => (0..n).contains(&i).then_some(i),
            Mode::Clamp => Some(i.clamp(0, n - 1)),
            Mode::Repeat => {
                let mut k = i;
                while k < 0 {
                    k += n;
                }
                while k >= n {
                    k -= n;
                }
                Some(k)
            }
            Mode::Mirror => {
                let mut k = i;
                while k < 0 {
                    k += 2 * n;
                }
                while k >= 2 * n {
                    k -= 2 * n;
                }
                Some(if k < n { k } else { 2 * n - 1 - k })
            }
        }
    }

    /// The box integral by summing every raw unit cell (`2^-F x 2^-F`) of the box.
    fn brute(tex: &Tex, mode: Mode, r: [i64; 4], f: u32) -> Vec<u128> {
        let mut out = vec![0u128; tex.c];
        for yr in r[1]..r[3] {
            for xr in r[0]..r[2] {
                let (i, j) = (xr >> f, yr >> f);
                if let (Some(x), Some(y)) = (ext(mode, i, tex.w as i64), ext(mode, j, tex.h as i64))
                {
                    for (ch, o) in out.iter_mut().enumerate() {
                        *o += u128::from(tex.at(x as usize, y as usize, ch));
                    }
                }
            }
        }
        out
    }

    fn lcg(s: &mut u64) -> u64 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *s >> 33
    }

    #[test]
    fn integral_matches_brute_force() {
        let mut s = 7u64;
        for _ in 0..3000 {
            let (w, h, c) = (
                1 + lcg(&mut s) as usize % 4,
                1 + lcg(&mut s) as usize % 4,
                1 + lcg(&mut s) as usize % 2,
            );
            let t = (0..w * h * c).map(|_| (lcg(&mut s) % 256) as u16).collect();
            let tex = Tex {
                w,
                h,
                c,
                bits: 8,
                t,
            };
            let f = (lcg(&mut s) % 3) as u32;
            let one = 1i64 << f;
            let mut pick = |n: usize| -> (i64, i64) {
                let span = 3 * n as i64 * one;
                let lo = (lcg(&mut s) as i64 % (2 * span + 1)) - span;
                (lo, lo + lcg(&mut s) as i64 % (3 * n as i64 * one + 1))
            };
            let ((x0, x1), (y0, y1)) = (pick(w), pick(h));
            for mode in Mode::ALL {
                let r = [x0, y0, x1, y1];
                let want: Vec<Option<u128>> =
                    brute(&tex, mode, r, f).into_iter().map(Some).collect();
                assert_eq!(box_integral(&tex, mode, r, f), want, "{mode:?} {r:?} f={f}");
            }
        }
    }

    #[test]
    fn weights_of_whole_periods() {
        // q whole periods give every column q 2^F (Repeat) and 2q 2^F per double period (Mirror).
        for n in 1..5usize {
            for f in [0u32, 3, 24] {
                let p = (n as i64) << f;
                let q = 1_000_000_007i64;
                let w = axis_weights(Mode::Repeat, -5 * p, (q - 5) * p, n, f);
                assert!(w.iter().all(|&v| v == (q as u128) << f));
                let w = axis_weights(Mode::Mirror, 3 * p, 3 * p + 2 * q * p, n, f);
                assert!(w.iter().all(|&v| v == (2 * q as u128) << f));
                // The whole i64 range under Clamp: all of it on the two end columns.
                let w = axis_weights(Mode::Clamp, i64::MIN, i64::MAX, n, f);
                assert_eq!(w.iter().sum::<u128>(), u64::MAX as u128);
            }
        }
    }

    #[test]
    fn sat_matches_direct_sums() {
        let mut s = 11u64;
        for _ in 0..200 {
            let (w, h, c) = (
                1 + lcg(&mut s) as usize % 7,
                1 + lcg(&mut s) as usize % 7,
                1 + lcg(&mut s) as usize % 3,
            );
            let t = (0..w * h * c).map(|_| lcg(&mut s) as u16).collect();
            let tex = Tex {
                w,
                h,
                c,
                bits: 16,
                t,
            };
            let sat = tex.sat();
            for y in 0..h {
                for x in 0..w {
                    for ch in 0..c {
                        let mut d = 0u128;
                        for yy in 0..=y {
                            for xx in 0..=x {
                                d += u128::from(tex.at(xx, yy, ch));
                            }
                        }
                        assert_eq!(sat[(y * w + x) * c + ch], d);
                    }
                }
            }
            assert_eq!(
                tex.totals(),
                (0..c)
                    .map(|ch| sat[(w * h - 1) * c + ch])
                    .collect::<Vec<_>>()
            );
        }
    }

    #[test]
    fn sat_and_table_validity() {
        let tex = Tex {
            w: 3,
            h: 2,
            c: 1,
            bits: 8,
            t: vec![1, 2, 3, 4, 5, 255],
        };
        let sat = tex.sat();
        assert_eq!(sat, vec![1, 3, 6, 5, 12, 270]);
        assert_eq!(first_invalid(&sat, 3, 2, 1, 8), None);
        assert_eq!(texels_of_table(&sat, 3, 2, 1, 8), tex);
        assert_eq!(first_invalid(&sat, 3, 2, 1, 7), Some((2, 1, 0)));
        let mut bad = sat.clone();
        bad[1] = 0; // texel (1, 0) = -1
        assert_eq!(first_invalid(&bad, 3, 2, 1, 8), Some((1, 0, 0)));
    }

    #[test]
    fn means_round_half_up() {
        assert_eq!(mean_ref(1, 0, 2, 1), BigUint::from(1u32));
        assert_eq!(mean_ref(1, 0, 3, 1), BigUint::from(0u32));
        assert_eq!(mean_ref(5, 1, 2, 2), BigUint::from(3u32)); // 2.5 -> 3
        assert_eq!(
            mean_ref(u128::MAX, 8, 1, 1),
            BigUint::from(u128::MAX) << 8u32
        );
    }
}
