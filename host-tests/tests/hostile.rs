//! The hostile-input catalogue (issue 11): every public entry point of the core, and each filter
//! constructor, fed the inputs a careless or malicious caller would give it, each checked against
//! the answer the documentation promises (`docs/guarantees.md`, the doc comments,
//! `docs/design.md` "Degenerate and bad input"): an exact result (compared with a reference
//! computed here, by periodicity or by summing texels, never with texsat's own tables), a result
//! within a stated bound, or a typed error with its fields.
//!
//! Every case is a named test or a row of a table whose message names the input, so a failure
//! says which input broke. Where the code disagrees with its documentation the test is kept but
//! marked `#[ignore = "finding: ..."]` (section "Findings" at the end), so the suite stays green
//! and `cargo test -- --ignored` shows the findings.
//!
//! Memory: no test allocates more than about 90 MB, and those that allocate tens of megabytes take
//! [`big_lock`] so they never run together. The suite runs in debug (overflow checks on) and in
//! release (`cargo test --release -p texsat-host-tests --test hostile`): a wrap that only debug
//! catches cannot hide, because every expectation is an exact value, not "did not panic".

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Mutex, MutexGuard};

use fixed::types::{I24F8, I32F32};
use texsat::filters::dip::{self, DipFilter, DipMap, DipPyramid};
use texsat::filters::mip::{self, MipPyramid};
use texsat::filters::point::point_raw;
use texsat::filters::rip::{self, RipMap};
use texsat::filters::tent::{self, TentLines, TentTable};
use texsat::filters::variance::{self, SquaresTable, VarianceTables};
use texsat::filters::OUT_FRAC_BITS;
use texsat::layouts::packed;
use texsat::layouts::{AxisLevels, Modular, ModularBuilder, Tiled, TiledBuilder, TiledSpec};
use texsat::plan::{Plan, PlanLayout, PlanLimit, SceneFacts};
use texsat::width;
use texsat::{
    Border, BoxLookup, EdgeKind, Error, FormKind, FracBits, NoCount, Paper, Quantity, Rect, Repeat,
    RowStreamBuilder, Sat, Shortcut, Stable, Tally, Texture, Wide, WideOf,
};

// =============================================================================================
// Helpers (the reference side: plain integer arithmetic, independent of texsat's tables)
// =============================================================================================

/// Serialises the tests that allocate tens of megabytes, so the suite's peak stays below 100 MB.
static BIG: Mutex<()> = Mutex::new(());

fn big_lock() -> MutexGuard<'static, ()> {
    BIG.lock().unwrap_or_else(|e| e.into_inner())
}

/// All four boundary modes, as run-time values.
const MODES: [EdgeKind; 4] = EdgeKind::ALL;
/// Both 16-read forms.
const FORMS: [FormKind; 2] = [FormKind::Paper, FormKind::Stable];

/// `F` as a checked value (only called with `F <= 24`).
fn fb(f: u32) -> FracBits {
    FracBits::new(f).expect("F <= 24")
}

/// A raw box `[x0, x1) x [y0, y1)`.
fn raw(r: [i64; 4]) -> Rect<i64> {
    Rect::new(r[0], r[1], r[2], r[3])
}

/// `bits_of(v)`: the position of the highest set bit, 0 for 0 (the docs' definition).
fn bits(v: u128) -> u32 {
    128 - v.leading_zeros()
}

/// A texture as plain numbers: texel `(x, y)` channel `c` is `t[(y w + x) C + c]`.
#[derive(Clone, Debug)]
struct RefTex {
    w: usize,
    h: usize,
    c: usize,
    bits: u32,
    t: Vec<u16>,
}

impl RefTex {
    /// Deterministic pseudo-random texels of `bits` bits (xorshift64).
    fn seeded(w: usize, h: usize, c: usize, bits: u32, seed: u64) -> RefTex {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let modulus = 1u64 << bits;
        let t = (0..w * h * c)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                u16::try_from(s % modulus).expect("bits <= 16")
            })
            .collect();
        RefTex { w, h, c, bits, t }
    }

    /// Every texel `v`.
    fn filled(w: usize, h: usize, c: usize, bits: u32, v: u16) -> RefTex {
        RefTex {
            w,
            h,
            c,
            bits,
            t: vec![v; w * h * c],
        }
    }

    fn texel(&self, x: usize, y: usize, ch: usize) -> i128 {
        i128::from(self.t[(y * self.w + x) * self.c + ch])
    }

    fn max(&self) -> u128 {
        (1u128 << self.bits) - 1
    }

    fn u8s(&self) -> Vec<u8> {
        self.t
            .iter()
            .map(|&v| u8::try_from(v).expect("8-bit texels"))
            .collect()
    }
}

/// Signed measure, in raw units (`2^-F` texels), of `{ t in [0, x / 2^F) : floor(t) = r mod p }`
/// (negative for `x < 0`): whole cells counted by one floor division, plus the part of the cell
/// holding `x`. This is periodicity written out: no loop over periods.
fn count_residue(x: i128, r: i128, p: i128, f: u32) -> i128 {
    let cell = x >> f;
    let frac = x - (cell << f);
    let whole = (cell - 1 - r).div_euclid(p) + 1;
    (whole << f) + if cell.rem_euclid(p) == r { frac } else { 0 }
}

/// Per texel column `i` of an axis of `n` texels: the measure (raw units) of the part of
/// `[lo, hi)` where the extended texture of `kind` shows column `i`.
fn axis_weights(kind: EdgeKind, n: usize, lo: i64, hi: i64, f: u32) -> Vec<i128> {
    let (lo, hi, n) = (i128::from(lo), i128::from(hi), n as i128);
    let one = 1i128 << f;
    (0..n)
        .map(|i| match kind {
            EdgeKind::Border => (hi.min((i + 1) * one) - lo.max(i * one)).max(0),
            EdgeKind::Clamp => {
                let a = if i == 0 { lo } else { lo.max(i * one) };
                let b = if i == n - 1 {
                    hi
                } else {
                    hi.min((i + 1) * one)
                };
                (b - a).max(0)
            }
            EdgeKind::Repeat => count_residue(hi, i, n, f) - count_residue(lo, i, n, f),
            EdgeKind::Mirror => {
                let p = 2 * n;
                let m = p - 1 - i;
                count_residue(hi, i, p, f) + count_residue(hi, m, p, f)
                    - count_residue(lo, i, p, f)
                    - count_residue(lo, m, p, f)
            }
        })
        .collect()
}

/// The exact integral of the extended texture over the raw box, per channel, scaled by `2^2F`
/// (the unit of `BoxSum::scaled_sum`); `None` if it leaves `i128`.
fn ref_sums(tex: &RefTex, r: [i64; 4], f: u32, kind: EdgeKind) -> Option<Vec<i128>> {
    let wx = axis_weights(kind, tex.w, r[0], r[2], f);
    let wy = axis_weights(kind, tex.h, r[1], r[3], f);
    (0..tex.c)
        .map(|ch| {
            let mut acc = 0i128;
            for (y, &b) in wy.iter().enumerate() {
                for (x, &a) in wx.iter().enumerate() {
                    let term = tex.texel(x, y, ch).checked_mul(a)?.checked_mul(b)?;
                    acc = acc.checked_add(term)?;
                }
            }
            Some(acc)
        })
        .collect()
}

/// The exact sums as `u128` if every channel fits a result word of `word` bits.
fn fitting(reference: Option<Vec<i128>>, word: u32) -> Option<Vec<u128>> {
    let v = reference?;
    let fits = v
        .iter()
        .all(|&s| s >= 0 && (word >= 127 || s < 1i128 << word));
    fits.then(|| v.iter().map(|&s| s as u128).collect())
}

/// One lookup through the run-time API, the sums widened to `u128`.
fn lookup<L: BoxLookup<C>, const C: usize>(
    l: &L,
    r: [i64; 4],
    f: u32,
    form: FormKind,
    kind: EdgeKind,
    k: &mut Tally,
) -> Result<Vec<u128>, Error> {
    l.box_sum_raw(&raw(r), fb(f), form, kind, k)
        .map(|s| s.to_u128().scaled_sums().to_vec())
}

/// Bits of the result word of a layout's lookups (`u64` or `u128`).
fn word_bits<L: BoxLookup<C>, const C: usize>() -> u32 {
    <WideOf<L, C> as Wide>::BITS
}

/// Cells `ceil(x1) - floor(x0)` (times the same in y) a raw box overlaps: the modular bound's
/// measure (docs/layouts.md, section 3).
fn cells(r: [i64; 4], f: u32) -> u128 {
    let axis = |lo: i64, hi: i64| -> u128 {
        let (lo, hi) = (i128::from(lo), i128::from(hi));
        let one = 1i128 << f;
        let ceil_hi = (hi + one - 1).div_euclid(one);
        (ceil_hi - lo.div_euclid(one)) as u128
    };
    axis(r[0], r[2]).saturating_mul(axis(r[1], r[3]))
}

/// What the docs allow for one box (see [`check_box`]).
#[derive(Debug)]
enum Verdict {
    /// The documented answer.
    Ok,
    /// Not the documented answer.
    Wrong(String),
}

/// Checks one box on layout `l` (a texture `tex`) against the documented answer:
///
/// * the exact sums when they fit the result word (`BoxLookup::box_sum_raw`: "exact");
/// * else `TooWide { LookupAccumulator, bits_needed > word, bits_available: word }` ("if the sum
///   of a box that covers many periods does not fit the result word");
/// * on a modular layout (`modulus = Some(k)`), a box whose sum may reach `2^k` by the documented
///   bound (`m` times the cells it overlaps, `2F` more bits for Paper) may instead be
///   `TooWide { ModularBox, bits_available: k }`, and one inside that bound must be exact;
/// * with `limits` (corners at the ends of `i64`), also `CoordinateOutOfRange`
///   (docs/design.md: "exact result, or TooWide from the checked split path, or
///   CoordinateOutOfRange").
#[allow(clippy::too_many_arguments)]
fn check_box<L: BoxLookup<C>, const C: usize>(
    l: &L,
    tex: &RefTex,
    r: [i64; 4],
    f: u32,
    form: FormKind,
    kind: EdgeKind,
    limits: bool,
) -> Verdict {
    let word = word_bits::<L, C>();
    let want = fitting(ref_sums(tex, r, f, kind), word);
    let got = lookup(l, r, f, form, kind, &mut Tally::new());
    if let Some(k) = l.modulus() {
        let headroom = if form == FormKind::Paper { 2 * f } else { 0 };
        let needed = bits(tex.max().saturating_mul(cells(r, f))).saturating_add(headroom);
        if needed > k {
            return match (&got, &want) {
                (
                    Err(Error::TooWide {
                        what: Quantity::ModularBox,
                        bits_needed,
                        bits_available,
                    }),
                    _,
                ) if *bits_available == k && *bits_needed > k => Verdict::Ok,
                (Ok(g), Some(w)) if g == w => Verdict::Ok,
                (Err(Error::CoordinateOutOfRange), _) if limits => Verdict::Ok,
                _ => Verdict::Wrong(format!(
                    "modular k={k}, box needs {needed} bits: got {got:?}, want TooWide ModularBox \
                     or {want:?}"
                )),
            };
        }
    }
    match (&got, &want) {
        (Ok(g), Some(w)) if g == w => Verdict::Ok,
        (
            Err(Error::TooWide {
                what: Quantity::LookupAccumulator,
                bits_needed,
                bits_available,
            }),
            None,
        ) if *bits_available == word && *bits_needed > word => Verdict::Ok,
        (Err(Error::CoordinateOutOfRange), _) if limits => Verdict::Ok,
        _ => Verdict::Wrong(format!("got {got:?}, want {want:?} (word {word} bits)")),
    }
}

/// Boxes (raw units at `F = f`) that probe every placement of a `w x h` texture: interior,
/// crossing each edge, wholly and far outside, a few periods, a million periods, `2^40` periods
/// (and `2^20 x 2^20`), at fractional offsets when `f > 0`.
fn hostile_boxes(w: usize, h: usize, f: u32) -> Vec<(String, [i64; 4])> {
    let (w, h) = (w as i64, h as i64);
    let s = |v: i64| v << f;
    // Fractional nudges (0 for integer corners): a quarter and three eighths of a texel.
    let (q, e) = if f >= 3 {
        (1i64 << (f - 2), 3i64 << (f - 3))
    } else {
        (0, 0)
    };
    let mut out: Vec<(String, [i64; 4])> = vec![
        ("interior".into(), [s(1) + q, s(1) + e, s(w - 1) - e, s(h)]),
        ("one texel".into(), [s(0), s(0), s(1), s(1)]),
        ("whole texture".into(), [0, 0, s(w), s(h)]),
        (
            "crosses left/top".into(),
            [s(-2) + q, s(-1) - e, s(2), s(1) + q],
        ),
        (
            "crosses right/bottom".into(),
            [s(w - 1) + e, s(h - 1) + q, s(w + 2) + e, s(h + 3)],
        ),
        (
            "a few periods".into(),
            [s(-2 * w) - q, s(-h) + e, s(3 * w) + e, s(2 * h) + q],
        ),
        ("wholly right".into(), [s(w + 5), 0, s(w + 7) + q, s(h)]),
        (
            "far outside".into(),
            [s(-1000 * w) + q, s(500 * h), s(-990 * w), s(501 * h) + e],
        ),
        (
            "a million periods in x".into(),
            [s(-1_000_000 * w) - q, 0, s(1_000_000 * w) + e, s(h)],
        ),
        (
            "2^40 periods in x".into(),
            [s(-(w << 40)) - e, s(1), s(w << 40) + q, s(h) + q],
        ),
        (
            "2^20 x 2^20 periods".into(),
            [
                s(-(w << 19)) + q,
                s(-(h << 19)) - e,
                s(w << 19),
                s(h << 19) + q,
            ],
        ),
        (
            "2^40 x 2^40 periods".into(),
            [0, 0, s(w << 40) + q, s(h << 40) + e],
        ),
    ];
    out.retain(|(_, r)| r[2] >= r[0] && r[3] >= r[1]);
    out
}

/// Whether a sweep runs its `case`-th case: natively every case; under Miri, which interprets
/// about 10^4 times slower, every `stride`-th (the first included). The strides used are
/// coprime to the 8 modes and forms of a box, so every box still meets some mode and form.
fn sampled(case: usize, stride: usize) -> bool {
    !cfg!(miri) || case.is_multiple_of(stride)
}

/// Runs [`hostile_boxes`] through every mode and form (and `F` in {0, 8}) on one layout (under
/// Miri every 11th case).
fn sweep<L: BoxLookup<C>, const C: usize>(name: &str, l: &L, tex: &RefTex) {
    let mut failures = Vec::new();
    let mut n = 0;
    for f in [0u32, 8] {
        for (label, r) in hostile_boxes(tex.w, tex.h, f) {
            for kind in MODES {
                for form in FORMS {
                    n += 1;
                    if !sampled(n - 1, 11) {
                        continue;
                    }
                    if let Verdict::Wrong(why) = check_box(l, tex, r, f, form, kind, false) {
                        failures.push(format!(
                            "{name}: {label} {r:?} F={f} {kind:?} {form:?}: {why}"
                        ));
                    }
                }
            }
        }
    }
    assert!(n > 0);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Boxes with corners at the ends of `i64` (raw) for an `h`-texel-high texture at `F = f`.
fn limit_boxes(h: usize, f: u32) -> Vec<(String, [i64; 4])> {
    let hh = (h as i64) << f;
    vec![
        ("x over all of i64".into(), [i64::MIN, 0, i64::MAX, hh]),
        ("x at i64::MIN".into(), [i64::MIN, 0, i64::MIN + 1, hh]),
        ("x at i64::MAX".into(), [i64::MAX - 1, 0, i64::MAX, hh]),
        ("x half of i64".into(), [i64::MIN / 2, 0, i64::MAX / 2, 1]),
        ("y over all of i64".into(), [0, i64::MIN, 1, i64::MAX]),
        (
            "both over all of i64".into(),
            [i64::MIN, i64::MIN, i64::MAX, i64::MAX],
        ),
        (
            "empty at i64::MAX".into(),
            [i64::MAX, i64::MAX, i64::MAX, i64::MAX],
        ),
        ("empty at i64::MIN".into(), [i64::MIN, 0, i64::MIN, hh]),
    ]
}

/// Runs [`limit_boxes`] through every mode and form, `F` in {0, 8, 24}, on one layout (under
/// Miri every 3rd case).
fn limit_sweep<L: BoxLookup<C>, const C: usize>(name: &str, l: &L, tex: &RefTex) {
    let mut failures = Vec::new();
    let mut case = 0;
    for f in [0u32, 8, 24] {
        for (label, r) in limit_boxes(tex.h, f) {
            for kind in MODES {
                for form in FORMS {
                    case += 1;
                    if !sampled(case - 1, 3) {
                        continue;
                    }
                    // F = 24 on a u16 table exceeds its accumulator: covered elsewhere.
                    if f > 8 && l.value_bits() + 2 * f + 1 > 63 && word_bits::<L, C>() == 64 {
                        continue;
                    }
                    if let Verdict::Wrong(why) = check_box(l, tex, r, f, form, kind, true) {
                        failures.push(format!(
                            "{name}: {label} {r:?} F={f} {kind:?} {form:?}: {why}"
                        ));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A table row: the input's name, what the code answered, what the docs promise.
type Row<T> = (&'static str, Result<T, Error>, Result<T, Error>);

/// A lookup on one layout, for comparing a valid layout with a corrupt one.
type LookupFn<'a> = &'a dyn Fn(&[i64; 4], u32, FormKind, EdgeKind) -> Result<Vec<u128>, Error>;

/// Whether `f` panics (the crate promises it never does).
fn panics<R>(f: impl FnOnce() -> R) -> bool {
    catch_unwind(AssertUnwindSafe(f)).is_err()
}

// =============================================================================================
// Sizes: zero, huge, past the side limit, products above u32::MAX, stride below the width
// =============================================================================================

/// The side limit of every table and texture (`texture.rs`: `2^31 - 1`).
const MAX_SIDE: usize = (1 << 31) - 1;

#[test]
fn texture_sizes_and_strides() {
    let data = [0u8; 64];
    let rows: Vec<Row<()>> = vec![
        (
            "width 0",
            Texture::<u8>::new(&data, 0, 4).map(|_| ()),
            Err(Error::EmptyTexture),
        ),
        (
            "height 0",
            Texture::<u8>::new(&data, 4, 0).map(|_| ()),
            Err(Error::EmptyTexture),
        ),
        (
            "0 x 0",
            Texture::<u8>::new(&[], 0, 0).map(|_| ()),
            Err(Error::EmptyTexture),
        ),
        (
            "zero channels",
            Texture::<u8, 0>::new(&data, 4, 4).map(|_| ()),
            Err(Error::EmptyTexture),
        ),
        (
            "width 2^31",
            Texture::<u8>::new(&data, MAX_SIDE + 1, 1).map(|_| ()),
            Err(Error::TextureTooLarge {
                dimension: MAX_SIDE + 1,
            }),
        ),
        (
            "height usize::MAX",
            Texture::<u8>::new(&data, 1, usize::MAX).map(|_| ()),
            Err(Error::TextureTooLarge {
                dimension: usize::MAX,
            }),
        ),
        (
            "both usize::MAX",
            Texture::<u8>::new(&data, usize::MAX, usize::MAX).map(|_| ()),
            Err(Error::TextureTooLarge {
                dimension: usize::MAX,
            }),
        ),
        (
            "stride below width x channels",
            Texture::<u8, 3>::with_stride(&data, 4, 2, 11).map(|_| ()),
            Err(Error::StrideTooSmall {
                stride: 11,
                needed: 12,
            }),
        ),
        (
            "stride 0",
            Texture::<u8>::with_stride(&data, 4, 2, 0).map(|_| ()),
            Err(Error::StrideTooSmall {
                stride: 0,
                needed: 4,
            }),
        ),
        (
            "data short by one (stride 10)",
            Texture::<u8>::with_stride(&data[..33], 4, 4, 10).map(|_| ()),
            Err(Error::TextureDataTooShort {
                needed: 34,
                got: 33,
            }),
        ),
        (
            "data exactly stride (h - 1) + w C",
            Texture::<u8>::with_stride(&data[..34], 4, 4, 10).map(|_| ()),
            Ok(()),
        ),
        (
            "largest sides, no data",
            Texture::<u8>::new(&[], MAX_SIDE, 1).map(|_| ()),
            Err(Error::TextureDataTooShort {
                needed: MAX_SIDE,
                got: 0,
            }),
        ),
    ];
    for (name, got, want) in rows {
        assert_eq!(got, want, "{name}");
    }
}

/// Sizes whose product is above `u32::MAX`: fine on this 64-bit host, refused with
/// `TextureTooLarge` on a 32-bit target ("a size derived from the sides ... that overflows u64 or
/// this target's usize"). The expectation is computed from the target's `usize`, so the same
/// test states the 32-bit answer.
#[test]
fn products_above_u32_max() {
    let (w, h) = (70_000usize, 70_000usize);
    let product = (w as u128) * (h as u128);
    assert!(product > u128::from(u32::MAX));
    let fits_usize = usize::try_from(product).ok();
    let too_large = Error::TextureTooLarge { dimension: w };
    // Flat table entries.
    assert_eq!(
        Sat::<u32, 1>::entries_needed(w, h),
        fits_usize.ok_or(too_large),
        "Sat::entries_needed(70000, 70000)"
    );
    // Modular words at k = 32: w h words.
    assert_eq!(
        Modular::<u32>::words_needed(w, h, 32),
        fits_usize.ok_or(too_large),
        "Modular::words_needed(70000, 70000, 32)"
    );
    // Packed words for w h fields of 32 bits.
    if let Some(n) = fits_usize {
        assert_eq!(
            packed::words_for_checked(n, 32),
            Some(n),
            "words_for_checked"
        );
    }
    // A texture of that size over a short slice: data too short (64-bit), too large (32-bit).
    #[cfg(target_pointer_width = "64")]
    assert_eq!(
        Texture::<u8>::new(&[0u8; 10], w, h).map(|_| ()),
        Err(Error::TextureDataTooShort {
            needed: w * h,
            got: 10
        })
    );
    // The largest accepted sides with 4 channels: (2^31 - 1)^2 * 4 < 2^64.
    let big = (MAX_SIDE as u128).pow(2) * 4;
    assert_eq!(
        Sat::<u64, 4>::entries_needed(MAX_SIDE, MAX_SIDE),
        usize::try_from(big).map_err(|_| Error::TextureTooLarge {
            dimension: MAX_SIDE
        }),
        "Sat::entries_needed at the side limit, 4 channels"
    );
}

#[test]
fn table_and_layout_sizes_at_and_past_the_limits() {
    let tl = |d: usize| Error::TextureTooLarge { dimension: d };
    let tiles8 = TiledSpec::tiles(8, 8).expect("8 x 8");
    // Bits of a modular table: k C w h; refused when they overflow u64.
    let modular_bits = |k: u128, c: u128| k * c * (MAX_SIDE as u128).pow(2);
    let modular_rows: Vec<Row<usize>> = vec![
        (
            "modular 0 x 5",
            Modular::<u32>::words_needed(0, 5, 16),
            Err(Error::EmptyTexture),
        ),
        (
            "modular side 2^31",
            Modular::<u32>::words_needed(MAX_SIDE + 1, 1, 16),
            Err(tl(MAX_SIDE + 1)),
        ),
        (
            "modular k = 0",
            Modular::<u32>::words_needed(4, 4, 0),
            Err(Error::InvalidModulus { bits: 0 }),
        ),
        (
            "modular k = 33 in u32",
            Modular::<u32>::words_needed(4, 4, 33),
            Err(Error::InvalidModulus { bits: 33 }),
        ),
        (
            "modular bits above u64 (k 16, side limit)",
            Modular::<u32>::words_needed(MAX_SIDE, MAX_SIDE, 16),
            {
                assert!(modular_bits(16, 1) > u128::from(u64::MAX));
                Err(tl(MAX_SIDE))
            },
        ),
        (
            "modular k 64, 4 channels, side limit",
            Modular::<u64, 4>::words_needed(MAX_SIDE, MAX_SIDE, 64),
            Err(tl(MAX_SIDE)),
        ),
        (
            "modular k 3 at the side limit (bits fit u64)",
            Modular::<u32>::words_needed(MAX_SIDE, MAX_SIDE, 3),
            {
                let b = modular_bits(3, 1);
                assert!(b <= u128::from(u64::MAX));
                usize::try_from(b.div_ceil(32)).map_err(|_| tl(MAX_SIDE))
            },
        ),
    ];
    for (name, got, want) in modular_rows {
        assert_eq!(got, want, "{name}");
    }
    // Tiled: a field above 64 bits is TooWide { Field }, a size above u64 bits TextureTooLarge.
    let field78 = bits(65535 * (MAX_SIDE as u128).pow(2));
    assert_eq!(field78, 78);
    let tiled_rows: Vec<Row<usize>> = vec![
        (
            "tiled 0 x 4",
            Tiled::<u32>::words_needed(tiles8, 0, 4, 8),
            Err(Error::EmptyTexture),
        ),
        (
            "tiled texel bits 0",
            Tiled::<u32>::words_needed(tiles8, 4, 4, 0),
            Err(Error::InvalidTexelBits { bits: 0 }),
        ),
        (
            "tiled texel bits 17",
            Tiled::<u32>::words_needed(tiles8, 4, 4, 17),
            Err(Error::InvalidTexelBits { bits: 17 }),
        ),
        (
            "tiled side 2^31",
            Tiled::<u32>::words_needed(tiles8, 4, MAX_SIDE + 1, 8),
            Err(tl(MAX_SIDE + 1)),
        ),
        (
            "packed 16-bit texels at the side limit: a 78-bit field",
            Tiled::<u64>::words_needed(TiledSpec::FLAT_PACKED, MAX_SIDE, MAX_SIDE, 16),
            Err(Error::TooWide {
                what: Quantity::Field,
                bits_needed: field78,
                bits_available: 64,
            }),
        ),
        (
            "tiled + mod 32, 4 channels, side limit: bits above u64",
            Tiled::<u32, 4>::words_needed(tiles8.with_modulus(32), MAX_SIDE, MAX_SIDE, 8),
            Err(tl(MAX_SIDE)),
        ),
        (
            "tiled modulus 3 below 8-bit texels",
            Tiled::<u32>::words_needed(tiles8.with_modulus(3), 4, 4, 8),
            Err(Error::InvalidModulus { bits: 3 }),
        ),
        (
            "tiled modulus 65",
            Tiled::<u64>::words_needed(tiles8.with_modulus(65), 4, 4, 8),
            Err(Error::InvalidModulus { bits: 65 }),
        ),
        (
            "tiled scratch for width usize::MAX",
            Tiled::<u32>::scratch_needed(tiles8, usize::MAX),
            Err(tl(usize::MAX)),
        ),
        (
            "tiled scratch for width 4: (Ly + 2)(w + 1) C",
            Tiled::<u32, 2>::scratch_needed(tiles8, 4),
            Ok(3 * 5 * 2),
        ),
    ];
    for (name, got, want) in tiled_rows {
        assert_eq!(got, want, "{name}");
    }
    // Flat entries.
    let flat_rows: Vec<Row<usize>> = vec![
        (
            "flat 0 x 3",
            Sat::<u32, 1>::entries_needed(0, 3),
            Err(Error::EmptyTexture),
        ),
        (
            "flat side 2^31",
            Sat::<u32, 1>::entries_needed(MAX_SIDE + 1, 1),
            Err(tl(MAX_SIDE + 1)),
        ),
        (
            "flat side 2^31 - 1",
            Sat::<u32, 1>::entries_needed(MAX_SIDE, 1),
            Ok(MAX_SIDE),
        ),
        (
            "flat zero channels",
            Sat::<u32, 0>::entries_needed(3, 3),
            Err(Error::EmptyTexture),
        ),
    ];
    for (name, got, want) in flat_rows {
        assert_eq!(got, want, "{name}");
    }
    // Tile levels.
    let level_rows: Vec<(&str, Result<AxisLevels, Error>)> = vec![
        ("block 1", AxisLevels::new(&[1])),
        ("block 0", AxisLevels::new(&[0])),
        ("not ascending", AxisLevels::new(&[8, 4])),
        ("not a multiple", AxisLevels::new(&[4, 6])),
        ("equal blocks", AxisLevels::new(&[4, 4])),
        ("five levels", AxisLevels::new(&[2, 4, 8, 16, 32])),
    ];
    for (name, got) in level_rows {
        assert_eq!(got, Err(Error::InvalidLevels), "{name}");
    }
    assert_eq!(
        TiledSpec::tiles(0, 8),
        Err(Error::InvalidLevels),
        "tiles 0 x 8"
    );
    assert!(AxisLevels::new(&[2, 4, 8, 16]).is_ok(), "four levels");
}

// =============================================================================================
// Short and corrupted storage, every layout
// =============================================================================================

/// A 5 x 3 texture of 8-bit texels (odd sizes on purpose).
fn tex53() -> RefTex {
    RefTex::seeded(5, 3, 1, 8, 53)
}

#[test]
fn short_storage_every_layout() {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("5 x 3");
    let tiles = TiledSpec::tiles(2, 2).expect("2 x 2");
    // Flat: w h C entries.
    let mut st = vec![0u32; 14];
    assert_eq!(
        Sat::build(&tex, &mut st).map(|_| ()),
        Err(Error::StorageTooSmall {
            needed: 15,
            got: 14
        }),
        "Sat::build one entry short"
    );
    assert!(st.iter().all(|&v| v == 0), "Sat::build wrote on refusal");
    assert_eq!(
        Sat::<u32>::build_checked(&tex, &mut []).map(|_| ()),
        Err(Error::StorageTooSmall { needed: 15, got: 0 }),
        "Sat::build_checked, no storage"
    );
    assert_eq!(
        Sat::<u32>::from_table(&[0u32; 14], 5, 3, 8).map(|_| ()),
        Err(Error::StorageTooSmall {
            needed: 15,
            got: 14
        }),
        "Sat::from_table one entry short"
    );
    assert_eq!(
        RowStreamBuilder::<u32, 2>::new(5, 3, 8, &mut [0u32; 9]).map(|_| ()),
        Err(Error::StorageTooSmall { needed: 10, got: 9 }),
        "RowStreamBuilder row storage"
    );
    // Tiled: words, then scratch.
    for spec in [TiledSpec::FLAT_PACKED, tiles, tiles.with_modulus(12)] {
        let words = Tiled::<u32>::words_needed(spec, 5, 3, 8).expect("words");
        let scratch = Tiled::<u32>::scratch_needed(spec, 5).expect("scratch");
        let mut w_short = vec![0u32; words - 1];
        let mut s_ok = vec![0u32; scratch];
        assert_eq!(
            Tiled::<u32>::build(&tex, spec, &mut w_short, &mut s_ok).map(|_| ()),
            Err(Error::StorageTooSmall {
                needed: words,
                got: words - 1
            }),
            "Tiled::build words short, {spec:?}"
        );
        assert!(w_short.iter().all(|&v| v == 0), "Tiled::build wrote words");
        let mut w_ok = vec![0u32; words];
        let mut s_short = vec![0u32; scratch - 1];
        assert_eq!(
            Tiled::<u32>::build(&tex, spec, &mut w_ok, &mut s_short).map(|_| ()),
            Err(Error::StorageTooSmall {
                needed: scratch,
                got: scratch - 1
            }),
            "Tiled::build scratch short, {spec:?}"
        );
        assert_eq!(
            Tiled::<u32>::from_words(&w_ok[..words - 1], spec, 5, 3, 8).map(|_| ()),
            Err(Error::StorageTooSmall {
                needed: words,
                got: words - 1
            }),
            "Tiled::from_words short, {spec:?}"
        );
    }
    // Modular: words, then the row.
    let words = Modular::<u32>::words_needed(5, 3, 12).expect("words");
    assert_eq!(words, (5 * 3 * 12usize).div_ceil(32));
    assert_eq!(
        Modular::<u32>::build(&tex, 12, &mut vec![0u32; words - 1], &mut [0u32; 5]).map(|_| ()),
        Err(Error::StorageTooSmall {
            needed: words,
            got: words - 1
        }),
        "Modular::build words short"
    );
    assert_eq!(
        Modular::<u32>::build(&tex, 12, &mut vec![0u32; words], &mut [0u32; 4]).map(|_| ()),
        Err(Error::StorageTooSmall { needed: 5, got: 4 }),
        "Modular::build row short"
    );
    assert_eq!(
        Modular::<u32>::from_words(&vec![0u32; words - 1], 5, 3, 8, 12).map(|_| ()),
        Err(Error::StorageTooSmall {
            needed: words,
            got: words - 1
        }),
        "Modular::from_words short"
    );
    let modular_args: Vec<(&str, Result<(), Error>, Error)> = vec![
        (
            "k below the texel bits",
            Modular::<u32>::from_words(&[0; 64], 5, 3, 8, 7).map(|_| ()),
            Error::InvalidModulus { bits: 7 },
        ),
        (
            "k above u32",
            Modular::<u32>::from_words(&[0; 64], 5, 3, 8, 33).map(|_| ()),
            Error::InvalidModulus { bits: 33 },
        ),
        (
            "texel bits 0",
            Modular::<u32>::from_words(&[0; 64], 5, 3, 0, 8).map(|_| ()),
            Error::InvalidTexelBits { bits: 0 },
        ),
        (
            "texel bits 17",
            Modular::<u32>::from_words(&[0; 64], 5, 3, 17, 20).map(|_| ()),
            Error::InvalidTexelBits { bits: 17 },
        ),
        (
            "tiled modulus 40 in u32",
            Tiled::<u32>::from_words(&[0; 64], tiles.with_modulus(40), 5, 3, 8).map(|_| ()),
            Error::InvalidModulus { bits: 40 },
        ),
    ];
    for (name, got, want) in modular_args {
        assert_eq!(got, Err(want), "{name}");
    }
}

#[test]
fn streaming_builders_refuse_bad_rows_and_change_nothing() {
    let rt = tex53();
    let texels = rt.u8s();
    let rows: Vec<&[u8]> = texels.chunks(5).collect();
    // RowStreamBuilder.
    let mut row = [0u32; 5];
    let mut b = RowStreamBuilder::<u32>::new(5, 3, 8, &mut row).expect("builder");
    assert_eq!(
        b.push_row(&texels[..4]).map(|_| ()),
        Err(Error::RowLength {
            expected: 5,
            got: 4
        }),
        "RowStreamBuilder short row"
    );
    for r in &rows[..2] {
        b.push_row(r).expect("row");
    }
    assert_eq!(b.rows_done(), 2);
    let mut early_row = [0u32; 5];
    let early = RowStreamBuilder::<u32>::new(5, 3, 8, &mut early_row).expect("builder");
    assert_eq!(
        early.finish().map(|_| ()),
        Err(Error::MissingRows {
            got: 0,
            expected: 3
        }),
        "RowStreamBuilder finished early"
    );
    b.push_row(rows[2]).expect("last row");
    assert_eq!(
        b.push_row(rows[0]).map(|_| ()),
        Err(Error::TooManyRows),
        "RowStreamBuilder fourth row"
    );
    let last = b.finish().expect("finish").to_vec();
    let total: i128 = (0..5)
        .flat_map(|x| (0..3).map(move |y| (x, y)))
        .map(|(x, y)| rt.texel(x, y, 0))
        .sum();
    assert_eq!(i128::from(last[4]), total, "RowStreamBuilder last entry");
    // A row of wider texels than declared overflows: checked, refused, never wrapped.
    let mut row16 = [0u16; 2];
    let mut wide = RowStreamBuilder::<u16>::new(2, 2, 8, &mut row16).expect("builder");
    let e = wide.push_row(&[65535u16, 1]).map(|_| ());
    assert!(
        matches!(
            e,
            Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed,
                bits_available: 16
            }) if bits_needed > 16
        ),
        "RowStreamBuilder wider texels: {e:?}"
    );

    // Tiled and modular builders: a refused row changes nothing (compare with a clean build).
    let spec = TiledSpec::tiles(2, 2).expect("2 x 2");
    let words = Tiled::<u32>::words_needed(spec, 5, 3, 4).expect("words");
    let scratch = Tiled::<u32>::scratch_needed(spec, 5).expect("scratch");
    let small: Vec<u8> = texels.iter().map(|v| v & 15).collect();
    let small_tex = Texture::<u8>::new(&small, 5, 3).expect("tex");
    let mut clean = vec![0u32; words];
    let mut s = vec![0u32; scratch];
    let mut cb = TiledBuilder::<u32>::new(spec, 5, 3, 4, &mut clean, &mut s).expect("builder");
    for r in small.chunks(5) {
        cb.push_row(r).expect("row");
    }
    cb.finish().expect("clean");
    let mut dirty = vec![0u32; words];
    let mut s2 = vec![0u32; scratch];
    let mut tb = TiledBuilder::<u32>::new(spec, 5, 3, 4, &mut dirty, &mut s2).expect("builder");
    let mut bad = small[..5].to_vec();
    bad[3] = 16; // 5 bits, declared 4
    assert_eq!(
        tb.push_row(&bad),
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 5,
            bits_available: 4
        }),
        "TiledBuilder texel wider than texel_bits"
    );
    assert_eq!(
        tb.push_row(&small[..6]),
        Err(Error::RowLength {
            expected: 5,
            got: 6
        }),
        "TiledBuilder long row"
    );
    for r in small.chunks(5) {
        tb.push_row(r).expect("row");
    }
    assert_eq!(tb.push_row(&small[..5]), Err(Error::TooManyRows));
    tb.finish().expect("finish");
    assert_eq!(dirty, clean, "TiledBuilder after refused rows");
    let mut early_w = vec![0u32; words];
    let mut early_s = vec![0u32; scratch];
    let tb = TiledBuilder::<u32>::new(spec, 5, 3, 4, &mut early_w, &mut early_s).expect("b");
    assert_eq!(
        tb.finish().map(|_| ()),
        Err(Error::MissingRows {
            got: 0,
            expected: 3
        })
    );

    let mw = Modular::<u32>::words_needed(5, 3, 8).expect("words");
    let mut mclean = vec![0u32; mw];
    Modular::<u32>::build(&small_tex, 8, &mut mclean, &mut [0u32; 5]).expect("clean");
    let mut mdirty = vec![0u32; mw];
    let mut mrow = [0u32; 5];
    let mut mb = ModularBuilder::<u32>::new(5, 3, 4, 8, &mut mdirty, &mut mrow).expect("b");
    assert_eq!(
        mb.push_row(&bad),
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: 5,
            bits_available: 4
        }),
        "ModularBuilder texel wider than texel_bits"
    );
    assert_eq!(
        mb.push_row(&small[..4]),
        Err(Error::RowLength {
            expected: 5,
            got: 4
        })
    );
    for r in small.chunks(5) {
        mb.push_row(r).expect("row");
    }
    assert_eq!(mb.push_row(&small[..5]), Err(Error::TooManyRows));
    mb.finish().expect("finish");
    assert_eq!(mdirty, mclean, "ModularBuilder after refused rows");
}

/// Lent tiled and modular words that are garbage: "a wrong sum or CorruptStorage, never a panic"
/// (docs/design.md). Errors that do not depend on the content (the same lookup on valid words
/// gives them) are of course still allowed. Returns the lookups that broke that; with
/// `allow_too_wide`, a `TooWide { LookupAccumulator }` (garbage pieces whose weighted sum leaves
/// the word on the split path) does not count (see `finding_corrupt_storage_too_wide`).
fn corrupt_lent_layouts(allow_too_wide: bool) -> Vec<String> {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("tex");
    let tiles = TiledSpec::tiles(2, 2).expect("2 x 2");
    let mut failures = Vec::new();
    let mut seed = 0x1234_5678_9ABC_DEF1u64;
    let mut garbage = |n: usize| -> Vec<u32> {
        (0..n)
            .map(|_| {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                seed as u32
            })
            .collect()
    };
    // Under Miri every 29th case of the sweeps, counted across the layouts (so each layout
    // meets different boxes), and two fills per layout (all ones and one random).
    let mut case = 0;
    let mut check = |name: &str, valid: LookupFn, bad: LookupFn| {
        for f in [0u32, 8] {
            for (label, r) in hostile_boxes(5, 3, f) {
                for kind in MODES {
                    for form in FORMS {
                        case += 1;
                        if !sampled(case - 1, 29) {
                            continue;
                        }
                        let good = valid(&r, f, form, kind);
                        let got = bad(&r, f, form, kind);
                        // A sum too large for the word depends on the content: garbage may sum
                        // to anything instead. Every other refusal depends on the box alone.
                        let content_dependent = matches!(
                            good,
                            Ok(_)
                                | Err(Error::TooWide {
                                    what: Quantity::LookupAccumulator,
                                    ..
                                })
                        );
                        let ok = match (&got, &good) {
                            (Ok(_) | Err(Error::CorruptStorage), _) if content_dependent => true,
                            (
                                Err(Error::TooWide {
                                    what: Quantity::LookupAccumulator,
                                    ..
                                }),
                                _,
                            ) if content_dependent && allow_too_wide => true,
                            (Err(a), Err(b)) => a == b,
                            _ => false,
                        };
                        if !ok {
                            failures.push(format!(
                                "{name}: {label} F={f} {kind:?} {form:?}: valid {good:?}, garbage {got:?}"
                            ));
                        }
                    }
                }
            }
        }
    };
    for (name, spec) in [
        ("packed", TiledSpec::FLAT_PACKED),
        ("tiled 2x2", tiles),
        ("tiled [2,4]", TiledSpec::square(&[2, 4]).expect("levels")),
        ("tiled 2x2 mod 16", tiles.with_modulus(16)),
    ] {
        let n = Tiled::<u32>::words_needed(spec, 5, 3, 8).expect("words");
        let mut words = vec![0u32; n];
        let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, 5).expect("s")];
        let valid = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).expect("build");
        let fills = if cfg!(miri) { 2 } else { 3 };
        for junk in [vec![u32::MAX; n], garbage(n), garbage(n)]
            .into_iter()
            .take(fills)
        {
            let bad = Tiled::<u32>::from_words(&junk, spec, 5, 3, 8).expect("lent");
            check(
                name,
                &|r, f, form, kind| lookup(&valid, *r, f, form, kind, &mut Tally::new()),
                &|r, f, form, kind| lookup(&bad, *r, f, form, kind, &mut Tally::new()),
            );
        }
    }
    let n = Modular::<u32>::words_needed(5, 3, 16).expect("words");
    let mut words = vec![0u32; n];
    let valid = Modular::<u32>::build(&tex, 16, &mut words, &mut [0u32; 5]).expect("build");
    for junk in [vec![u32::MAX; n], garbage(n)] {
        let bad = Modular::<u32>::from_words(&junk, 5, 3, 8, 16).expect("lent");
        check(
            "modular 16",
            &|r, f, form, kind| lookup(&valid, *r, f, form, kind, &mut Tally::new()),
            &|r, f, form, kind| lookup(&bad, *r, f, form, kind, &mut Tally::new()),
        );
    }
    failures
}

#[test]
fn corrupt_lent_layouts_never_panic() {
    let failures = corrupt_lent_layouts(true);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `Sat::from_table` checks that every implied texel lies in `[0, 2^b - 1]` and names one that
/// does not.
#[test]
fn from_table_refuses_tables_that_are_not_sats() {
    // The SAT of a 3 x 2 texture of zeros, with one entry changed at a time. Entry (x, y) enters
    // the implied texels (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1), so the offender is one
    // of those (the docs name "the texel", not which one first).
    let (w, h) = (3usize, 2usize);
    let base = vec![0u32; w * h];
    let near = |x: usize, y: usize| -> Vec<(usize, usize)> {
        [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)]
            .into_iter()
            .filter(|&(a, b)| a < w && b < h)
            .collect()
    };
    for y in 0..h {
        for x in 0..w {
            for v in [1u32, 255, 256, u32::MAX] {
                let mut t = base.clone();
                t[y * w + x] = v;
                let got = Sat::<u32>::from_table(&t, w, h, 8).map(|_| ());
                // +v at (x, y) makes texel (x + 1, y) (or (x, y + 1)) negative unless both are
                // outside, and texel (x, y) too large if v > 255.
                let candidates = near(x, y);
                let valid = candidates.len() == 1 && v <= 255;
                match got {
                    Ok(()) => assert!(valid, "entry ({x}, {y}) = {v} accepted"),
                    Err(Error::InvalidTable {
                        x: ex,
                        y: ey,
                        channel: 0,
                    }) => assert!(
                        !valid && candidates.contains(&(ex, ey)),
                        "entry ({x}, {y}) = {v}: blamed ({ex}, {ey})"
                    ),
                    Err(e) => panic!("entry ({x}, {y}) = {v}: {e:?}"),
                }
            }
        }
    }
    let args: Vec<(&str, Result<(), Error>, Error)> = vec![
        (
            "width 0",
            Sat::<u32>::from_table(&[], 0, 2, 8).map(|_| ()),
            Error::EmptyTexture,
        ),
        (
            "texel bits 0",
            Sat::<u32>::from_table(&[0; 4], 2, 2, 0).map(|_| ()),
            Error::InvalidTexelBits { bits: 0 },
        ),
        (
            "texel bits 17",
            Sat::<u32>::from_table(&[0; 4], 2, 2, 17).map(|_| ()),
            Error::InvalidTexelBits { bits: 17 },
        ),
        (
            "side 2^31",
            Sat::<u32>::from_table(&[0; 4], MAX_SIDE + 1, 1, 8).map(|_| ()),
            Error::TextureTooLarge {
                dimension: MAX_SIDE + 1,
            },
        ),
        (
            "1-bit texels, entry 2",
            Sat::<u32>::from_table(&[2], 1, 1, 1).map(|_| ()),
            Error::InvalidTable {
                x: 0,
                y: 0,
                channel: 0,
            },
        ),
        (
            "second channel bad",
            Sat::<u32, 2>::from_table(&[0, 0, 0, 300], 2, 1, 8).map(|_| ()),
            Error::InvalidTable {
                x: 1,
                y: 0,
                channel: 1,
            },
        ),
    ];
    for (name, got, want) in args {
        assert_eq!(got, Err(want), "{name}");
    }
    // A valid table at the top of its word is accepted (every texel 2^16 - 1 in u32 entries).
    let full: Vec<u32> = (1..=4u32).map(|i| 65535 * i).collect();
    assert!(
        Sat::<u32>::from_table(&full, 4, 1, 16).is_ok(),
        "a 4 x 1 row of 65535"
    );
}

// =============================================================================================
// Width limits: 4104 x 4104 accepted, 4105 x 4105 refused (8-bit texels in u32)
// =============================================================================================

#[test]
fn width_proof_at_4104_and_4105() {
    // bits_of(255 * n^2) in u128, the docs' formula.
    let need = |n: u128| bits(255 * n * n);
    assert_eq!(need(4104), 32);
    assert_eq!(need(4105), 33);
    assert_eq!(
        width::entry_bits_worst_case(8, 4104, 4104),
        need(4104),
        "entry bits 4104"
    );
    assert_eq!(width::check_entry_worst_case(8, 4104, 4104, 32), Ok(()));
    let refusal = Err(Error::TooWide {
        what: Quantity::Entry,
        bits_needed: 33,
        bits_available: 32,
    });
    assert_eq!(width::check_entry_worst_case(8, 4105, 4105, 32), refusal);
    // The same product in one row: 1 x 16 851 025 texels.
    assert_eq!(
        width::check_entry_worst_case(8, 1, 4105 * 4105, 32),
        refusal,
        "one long row"
    );
    assert_eq!(
        RowStreamBuilder::<u32>::new(4105, 4105, 8, &mut [0u32; 4105]).map(|_| ()),
        refusal,
        "RowStreamBuilder 4105"
    );
    assert_eq!(
        RowStreamBuilder::<u32>::new(4105, 4105, 0, &mut [0u32; 4105]).map(|_| ()),
        Err(Error::InvalidTexelBits { bits: 0 }),
        "RowStreamBuilder texel bits 0"
    );
    // Under Miri (about 10^4 times slower, 16.8 M texels would take hours) the same proof at the
    // u16 limit instead: 255 * 16^2 = 65 280 fits 16 bits, 255 * 17^2 = 73 695 does not; the
    // largest accepted u16 table streamed, its last entry exactly 65 280.
    if cfg!(miri) {
        assert_eq!(need(16), 16);
        assert_eq!(need(17), 17);
        assert_eq!(
            RowStreamBuilder::<u16>::new(17, 17, 8, &mut [0u16; 17]).map(|_| ()),
            Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: 17,
                bits_available: 16,
            }),
            "RowStreamBuilder<u16> 17"
        );
        let mut row = vec![0u16; 16];
        let mut b = RowStreamBuilder::<u16>::new(16, 16, 8, &mut row).expect("16 accepted");
        for _ in 0..16 {
            b.push_row(&[255u8; 16]).expect("row");
        }
        let last = b.finish().expect("finish");
        assert_eq!(u128::from(last[15]), 255 * 16 * 16);
        return;
    }
    // The largest accepted table, streamed in one row of storage: the last entry is the exact
    // worst case 255 * 4104^2 = 4 294 918 080 (no wrap in u32).
    let mut row = vec![0u32; 4104];
    let mut b = RowStreamBuilder::<u32>::new(4104, 4104, 8, &mut row).expect("4104 accepted");
    let texels = vec![255u8; 4104];
    for _ in 0..4104 {
        b.push_row(&texels).expect("row");
    }
    let last = b.finish().expect("finish");
    assert_eq!(u128::from(last[4103]), 255 * 4104 * 4104);
}

#[test]
fn sat_and_tiled_at_4105_refused_before_writing() {
    let _g = big_lock();
    let refusal = Err(Error::TooWide {
        what: Quantity::Entry,
        bits_needed: 33,
        bits_available: 32,
    });
    {
        // 17 MB of texels and 67 MB of correctly sized storage: the refusal is the width proof.
        let texels = vec![255u8; 4105 * 4105];
        let tex = Texture::<u8>::new(&texels, 4105, 4105).expect("texture");
        let mut st = vec![0u32; 4105 * 4105];
        assert_eq!(
            Sat::build(&tex, &mut st).map(|_| ()),
            refusal,
            "Sat::build 4105"
        );
        // Under Miri (about 10^4 times slower) every 4099th entry and the last.
        let stride = if cfg!(miri) { 4099 } else { 1 };
        let probe = st.iter().step_by(stride).chain(st.last());
        assert!(probe.into_iter().all(|&v| v == 0), "nothing written");
    }
    // A tiled layout lent at 4105 x 4105 cannot promise u32 sums either; at 4104 it can.
    let spec = TiledSpec::tiles(8, 8).expect("8 x 8");
    for (n, want) in [(4105usize, refusal), (4104, Ok(()))] {
        let words = Tiled::<u32>::words_needed(spec, n, n, 8).expect("words");
        let image = vec![0u32; words];
        assert_eq!(
            Tiled::<u32>::from_words(&image, spec, n, n, 8).map(|_| ()),
            want,
            "Tiled::from_words {n}"
        );
    }
}

#[test]
fn checked_build_names_the_exact_bits() {
    // 300 texels of 255 in u16: the worst case is refused, the actual total 76 500 needs 17 bits.
    let texels = vec![255u8; 300];
    let tex = Texture::<u8>::new(&texels, 300, 1).expect("texture");
    let mut st = vec![0u16; 300];
    assert_eq!(
        Sat::build(&tex, &mut st).map(|_| ()),
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: bits(255 * 300),
            bits_available: 16
        }),
        "worst case"
    );
    assert_eq!(
        Sat::build_checked(&tex, &mut st).map(|_| ()),
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: bits(255 * 300),
            bits_available: 16
        }),
        "actual data"
    );
    // Ones: the actual total 300 fits, so the data-dependent build accepts it.
    let ones = vec![1u8; 300];
    let tex = Texture::<u8>::new(&ones, 300, 1).expect("texture");
    let sat = Sat::build_checked(&tex, &mut st).expect("fits");
    assert_eq!(sat.total(), [300]);
}

// =============================================================================================
// Fractional bits and float corners
// =============================================================================================

#[test]
fn frac_bits_out_of_range() {
    for f in [25u32, 32, 63, 64, u32::MAX] {
        assert_eq!(
            FracBits::new(f),
            Err(Error::FracBitsUnsupported {
                frac_bits: f,
                max: 24
            }),
            "FracBits::new({f})"
        );
    }
    for f in 0..=24u32 {
        assert_eq!(
            FracBits::new(f).map(FracBits::get),
            Ok(f),
            "FracBits::new({f})"
        );
    }
    assert_eq!(
        FracBits::of::<I32F32>(),
        Err(Error::FracBitsUnsupported {
            frac_bits: 32,
            max: 24
        })
    );
    // Every entry point taking a fixed type refuses F = 32 the same way.
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("tex");
    let mut st = vec![0u32; 15];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    let r = Rect::<I32F32>::from_f64(0.5, 0.5, 2.5, 2.5).expect("rect");
    let unsupported = Error::FracBitsUnsupported {
        frac_bits: 32,
        max: 24,
    };
    assert_eq!(
        sat.box_sum(&r, Stable, Border, &mut NoCount).map(|_| ()),
        Err(unsupported),
        "box_sum"
    );
    assert_eq!(
        sat.box_mean_shortcut(
            &r,
            Stable,
            Border,
            &Shortcut::with_min_side(2),
            8,
            &mut NoCount
        )
        .map(|_| ()),
        Err(unsupported),
        "box_mean_shortcut"
    );
    assert_eq!(
        texsat::filters::point::point(&tex, &r, Border, &mut NoCount).map(|_| ()),
        Err(unsupported),
        "point"
    );
}

#[test]
fn float_corners_nan_inf_and_out_of_range() {
    type R = Rect<I24F8>;
    let rows: Vec<Row<R>> = vec![
        (
            "NaN",
            R::from_f64(f64::NAN, 0.0, 1.0, 1.0),
            Err(Error::NotFinite),
        ),
        (
            "+inf",
            R::from_f64(0.0, 0.0, f64::INFINITY, 1.0),
            Err(Error::NotFinite),
        ),
        (
            "-inf",
            R::from_f64(0.0, f64::NEG_INFINITY, 1.0, 1.0),
            Err(Error::NotFinite),
        ),
        (
            "f32 NaN",
            R::from_f32(0.0, 0.0, 1.0, f32::NAN),
            Err(Error::NotFinite),
        ),
        (
            "f32 inf",
            R::from_f32(f32::INFINITY, 0.0, 1.0, 1.0),
            Err(Error::NotFinite),
        ),
        (
            "1e300",
            R::from_f64(0.0, 0.0, 1e300, 1.0),
            Err(Error::CoordinateOutOfRange),
        ),
        (
            "f64::MAX",
            R::from_f64(f64::MAX, 0.0, 1.0, 1.0),
            Err(Error::CoordinateOutOfRange),
        ),
        (
            "-f64::MAX",
            R::from_f64(0.0, -f64::MAX, 1.0, 1.0),
            Err(Error::CoordinateOutOfRange),
        ),
        (
            "2^23 (one past I24F8)",
            R::from_f64(0.0, 0.0, 8_388_608.0, 1.0),
            Err(Error::CoordinateOutOfRange),
        ),
        (
            "largest I24F8",
            R::from_f64(-8_388_608.0, 0.0, 8_388_607.99609375, 1.0),
            Ok(Rect::new(I24F8::MIN, I24F8::ZERO, I24F8::MAX, I24F8::ONE)),
        ),
        (
            "nearest: 0.7 / 256 -> 1 raw unit, 0.3 / 256 -> 0",
            R::from_f64(0.7 / 256.0, 0.3 / 256.0, 1.0, 1.0),
            Ok(Rect::new(
                I24F8::from_bits(1),
                I24F8::ZERO,
                I24F8::ONE,
                I24F8::ONE,
            )),
        ),
        (
            "subnormal -> 0",
            R::from_f64(f64::MIN_POSITIVE / 2.0, -0.0, 0.0, 0.0),
            Ok(Rect::new(
                I24F8::ZERO,
                I24F8::ZERO,
                I24F8::ZERO,
                I24F8::ZERO,
            )),
        ),
    ];
    for (name, got, want) in rows {
        assert_eq!(got, want, "{name}");
    }
}

// =============================================================================================
// Lookups: inverted, empty, outside; F too large for the word; limits of i64; many periods
// =============================================================================================

/// Flat tables of the 5 x 3 texture in all three words, and 2-channel 16-bit ones.
#[test]
fn hostile_boxes_flat_tables() {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("tex");
    let mut s16 = vec![0u16; 15];
    let mut s32 = vec![0u32; 15];
    let mut s64 = vec![0u64; 15];
    sweep("Sat<u16>", &Sat::build(&tex, &mut s16).expect("u16"), &rt);
    sweep("Sat<u32>", &Sat::build(&tex, &mut s32).expect("u32"), &rt);
    sweep("Sat<u64>", &Sat::build(&tex, &mut s64).expect("u64"), &rt);
    let rt2 = RefTex::seeded(3, 2, 2, 16, 7);
    let tex2 = Texture::<u16, 2>::new(&rt2.t, 3, 2).expect("tex2");
    let mut a = vec![0u32; 12];
    let mut b = vec![0u64; 12];
    sweep(
        "Sat<u32, 2>",
        &Sat::build(&tex2, &mut a).expect("u32x2"),
        &rt2,
    );
    sweep(
        "Sat<u64, 2>",
        &Sat::build(&tex2, &mut b).expect("u64x2"),
        &rt2,
    );
}

#[test]
fn hostile_boxes_packed_tiled_and_modular() {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("tex");
    let tiles = TiledSpec::tiles(2, 2).expect("2 x 2");
    for (name, spec) in [
        ("packed", TiledSpec::FLAT_PACKED),
        ("tiled 2x2", tiles),
        ("tiled 4x2", TiledSpec::tiles(4, 2).expect("4 x 2")),
        ("tiled [2,4]", TiledSpec::square(&[2, 4]).expect("levels")),
        ("tiled 2x2 mod 16", tiles.with_modulus(16)),
        ("tiled 2x2 mod 32", tiles.with_modulus(32)),
    ] {
        let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, 5, 3, 8).expect("words")];
        let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, 5).expect("s")];
        let t = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).expect("build");
        sweep(name, &t, &rt);
    }
    for k in [8u32, 16, 24, 32] {
        let mut words = vec![0u32; Modular::<u32>::words_needed(5, 3, k).expect("words")];
        let m = Modular::<u32>::build(&tex, k, &mut words, &mut [0u32; 5]).expect("build");
        sweep(&format!("modular k={k}"), &m, &rt);
    }
}

#[test]
fn i64_limit_corners_every_layout() {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("tex");
    let mut s32 = vec![0u32; 15];
    let mut s64 = vec![0u64; 15];
    limit_sweep("Sat<u32>", &Sat::build(&tex, &mut s32).expect("u32"), &rt);
    limit_sweep("Sat<u64>", &Sat::build(&tex, &mut s64).expect("u64"), &rt);
    let spec = TiledSpec::tiles(2, 2).expect("2 x 2");
    let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, 5, 3, 8).expect("w")];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, 5).expect("s")];
    let t = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).expect("tiled");
    limit_sweep("tiled 2x2", &t, &rt);
    let mut mw = vec![0u32; Modular::<u32>::words_needed(5, 3, 32).expect("w")];
    let m = Modular::<u32>::build(&tex, 32, &mut mw, &mut [0u32; 5]).expect("modular");
    limit_sweep("modular 32", &m, &rt);
    // A zero texture: every sum is 0 whatever the multiplicities, so the checked split path has
    // nothing to overflow: the limits must give 0 or CoordinateOutOfRange, never TooWide.
    let zero = RefTex::filled(5, 3, 1, 8, 0);
    let zt = zero.u8s();
    let ztex = Texture::<u8>::new(&zt, 5, 3).expect("zero");
    let mut zs = vec![0u32; 15];
    let zsat = Sat::build(&ztex, &mut zs).expect("zero sat");
    for f in [0u32, 8, 24] {
        for (label, r) in limit_boxes(3, f) {
            for kind in MODES {
                for form in FORMS {
                    let got = lookup(&zsat, r, f, form, kind, &mut Tally::new());
                    assert!(
                        matches!(&got, Ok(v) if v.iter().all(|&s| s == 0))
                            || got == Err(Error::CoordinateOutOfRange),
                        "zero texture {label} F={f} {kind:?} {form:?}: {got:?}"
                    );
                }
            }
        }
    }
}

/// Integer-corner lookups (`box_sum_int`) at the ends of `i32`, every mode: exact when the sum
/// fits `u64` (with the unclipped box's sides for the mean), else `TooWide { LookupAccumulator }`.
#[test]
fn i32_limit_corners_box_sum_int() {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("tex");
    let mut st = vec![0u32; 15];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    let boxes = [
        [i32::MIN, i32::MIN, i32::MAX, i32::MAX],
        [i32::MIN, 0, i32::MIN + 1, 3],
        [i32::MAX - 1, 0, i32::MAX, 3],
        [-7, -7, 11, 9],
    ];
    for r in boxes {
        for kind in MODES {
            let want = fitting(ref_sums(&rt, r.map(i64::from), 0, kind), 64);
            let got = sat
                .box_sum_int(&Rect::new(r[0], r[1], r[2], r[3]), kind, &mut NoCount)
                .map(|s| (u128::from(s.sum()), s.sides_raw()));
            let sides = (
                (i64::from(r[2]) - i64::from(r[0])) as u64,
                (i64::from(r[3]) - i64::from(r[1])) as u64,
            );
            match want {
                Some(w) => assert_eq!(got, Ok((w[0], sides)), "{r:?} {kind:?}"),
                None => assert!(
                    matches!(
                        got,
                        Err(Error::TooWide {
                            what: Quantity::LookupAccumulator,
                            bits_available: 64,
                            ..
                        })
                    ),
                    "{r:?} {kind:?}: {got:?}"
                ),
            }
        }
    }
}

#[test]
fn inverted_empty_and_outside_boxes() {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8, 1>::new(&texels, 5, 3).expect("tex");
    let mut st = vec![0u32; 15];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    for kind in MODES {
        for form in FORMS {
            for f in [0u32, 8, 24] {
                let one = 1i64 << f;
                // Inverted by one raw unit, in x and in y, anywhere.
                for r in [
                    [one, 0, one - 1, one],
                    [0, one, one, one - 1],
                    [i64::MAX, 0, i64::MIN, 1],
                    [0, i64::MAX, 1, i64::MIN],
                ] {
                    assert_eq!(
                        lookup(&sat, r, f, form, kind, &mut Tally::new()),
                        Err(Error::InvertedBox),
                        "inverted {r:?} F={f} {kind:?} {form:?}"
                    );
                }
                // Zero area: sum 0, no reads; its mean is ZeroArea.
                for r in [
                    [one, one, one, 3 * one],
                    [0, 2 * one, 5 * one, 2 * one],
                    [i64::MIN, i64::MIN, i64::MIN, i64::MAX],
                    [-7 * one, 9, i64::MAX, 9],
                ] {
                    let mut k = Tally::new();
                    let s = sat
                        .box_sum_raw(&raw(r), fb(f), form, kind, &mut k)
                        .expect("zero area is not an error");
                    assert_eq!((s.sum(), k), (0, Tally::new()), "empty {r:?} {kind:?}");
                    assert_eq!(
                        s.mean_rounded(0, 8, &mut NoCount),
                        Err(Error::ZeroArea),
                        "mean of empty {r:?}"
                    );
                    assert_eq!(s.means_rounded(8, &mut NoCount), Err(Error::ZeroArea));
                }
            }
        }
    }
    // Wholly outside under Border: sum 0, no reads, mean 0 (the area is the unclipped box's).
    for f in [0u32, 8] {
        for r in [
            [6 << f, 0, 9 << f, 3 << f],
            [-(9 << f), -(9 << f), -(1 << f), -(1 << f)],
            [i64::MIN, i64::MIN, -1, -1],
            [5 << f, 3 << f, i64::MAX, i64::MAX],
        ] {
            for form in FORMS {
                let mut k = Tally::new();
                let s = sat
                    .box_sum_raw(&raw(r), fb(f), form, Border, &mut k)
                    .expect("outside");
                assert_eq!((s.sum(), k.reads), (0, 0), "outside {r:?} F={f}");
                assert_eq!(s.mean_rounded(0, 8, &mut NoCount), Ok(0), "mean {r:?}");
            }
        }
    }
    // Integer-corner API and box_sum_inside.
    assert_eq!(
        sat.box_sum_int(&Rect::new(3, 0, 2, 1), Repeat, &mut NoCount)
            .map(|s| s.sum()),
        Err(Error::InvertedBox)
    );
    let inside = vec![
        (
            "inverted",
            Rect::new(3, 0, 2, 1),
            Err(Error::CoordinateOutOfRange),
        ),
        (
            "x1 = w + 1",
            Rect::new(0, 0, 6, 1),
            Err(Error::CoordinateOutOfRange),
        ),
        (
            "y1 = h + 1",
            Rect::new(0, 0, 1, 4),
            Err(Error::CoordinateOutOfRange),
        ),
        (
            "u32::MAX",
            Rect::new(0, 0, u32::MAX, u32::MAX),
            Err(Error::CoordinateOutOfRange),
        ),
        ("empty", Rect::new(2, 1, 2, 3), Ok([0])),
        (
            "whole",
            Rect::new(0, 0, 5, 3),
            Ok([rt.t.iter().map(|&v| u32::from(v)).sum::<u32>()]),
        ),
    ];
    for (name, r, want) in inside {
        assert_eq!(sat.box_sum_inside(&r), want, "box_sum_inside {name}");
    }
    // Channels past C.
    let s = sat
        .box_sum_int(&Rect::new(0, 0, 2, 2), Border, &mut NoCount)
        .expect("sum");
    assert_eq!(
        s.mean_rounded(1, 8, &mut NoCount),
        Err(Error::NoSuchChannel)
    );
    assert_eq!(
        s.mean_rounded(usize::MAX, 8, &mut NoCount),
        Err(Error::NoSuchChannel)
    );
    assert_eq!(s.scaled_sum(1), 0, "channels past C read as 0");
    // Corners outside the table.
    assert_eq!(sat.corner(6, 0), None);
    assert_eq!(sat.corner(0, 4), None);
    assert_eq!(sat.corner(usize::MAX, usize::MAX), None);
    assert_eq!(sat.corner(0, 3), Some([0]), "zero column");
}

/// `F` too large for the table word: `TooWide { LookupAccumulator, bits_needed, bits_available }`
/// with `bits_needed` = `total + 2F` (Paper) or `total + 2F + 1` (Stable) and `bits_available` =
/// 31, 63 or 127 (`width::paper_acc_bits`, `width::stable_acc_bits`, `width::acc_value_bits`).
#[test]
fn frac_bits_too_large_for_the_word() {
    // u16 table whose total has exactly 16 bits: 1 x 257 texels of 255 = 65 535.
    let ones = vec![255u8; 257];
    let tex = Texture::<u8>::new(&ones, 257, 1).expect("tex");
    let mut s16 = vec![0u16; 257];
    let t16 = Sat::build_checked(&tex, &mut s16).expect("fits u16");
    assert_eq!(t16.total_bits(), 16);
    // u32 table whose total has exactly 32 bits: 182 x 182 texels of 65 535.
    let big = vec![65535u16; 182 * 182];
    let tex32 = Texture::<u16>::new(&big, 182, 182).expect("tex");
    let mut s32 = vec![0u32; 182 * 182];
    let t32 = Sat::build_checked(&tex32, &mut s32).expect("fits u32");
    assert_eq!(t32.total_bits(), 32);
    // u64 table, 64-bit total is not buildable in a test; a 1-texel u64 table: 8-bit total.
    let one = [255u8];
    let tex1 = Texture::<u8>::new(&one, 1, 1).expect("tex");
    let mut s64 = [0u64; 1];
    let t64 = Sat::build(&tex1, &mut s64).expect("u64");

    let r16 = [1 << 7, 0, 3 << 7, 1 << 7]; // inside, F-independent shape below
    let cases = vec![
        // (name, got, Some((needed, available)) for a refusal, None for success)
        (
            "u16 Paper F=7",
            lookup(
                &t16,
                r16,
                7,
                FormKind::Paper,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            None,
        ),
        (
            "u16 Stable F=7",
            lookup(
                &t16,
                r16,
                7,
                FormKind::Stable,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            None,
        ),
        (
            "u16 Paper F=8",
            lookup(
                &t16,
                [256, 0, 768, 256],
                8,
                FormKind::Paper,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            Some((16 + 16, 31)),
        ),
        (
            "u16 Stable F=8",
            lookup(
                &t16,
                [256, 0, 768, 256],
                8,
                FormKind::Stable,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            Some((16 + 16 + 1, 31)),
        ),
        (
            "u16 Stable F=24",
            lookup(
                &t16,
                [1 << 24, 0, 3 << 24, 1 << 24],
                24,
                FormKind::Stable,
                EdgeKind::Repeat,
                &mut Tally::new(),
            ),
            Some((16 + 48 + 1, 31)),
        ),
        (
            "u32 Paper F=15",
            lookup(
                &t32,
                [1 << 15, 0, 3 << 15, 1 << 15],
                15,
                FormKind::Paper,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            None,
        ),
        (
            "u32 Stable F=15",
            lookup(
                &t32,
                [1 << 15, 0, 3 << 15, 1 << 15],
                15,
                FormKind::Stable,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            None,
        ),
        (
            "u32 Paper F=16",
            lookup(
                &t32,
                [1 << 16, 0, 3 << 16, 1 << 16],
                16,
                FormKind::Paper,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            Some((32 + 32, 63)),
        ),
        (
            "u32 Stable F=16",
            lookup(
                &t32,
                [1 << 16, 0, 3 << 16, 1 << 16],
                16,
                FormKind::Stable,
                EdgeKind::Clamp,
                &mut Tally::new(),
            ),
            Some((32 + 32 + 1, 63)),
        ),
        (
            "u64 Stable F=24",
            lookup(
                &t64,
                [0, 0, 1 << 23, 1 << 24],
                24,
                FormKind::Stable,
                EdgeKind::Border,
                &mut Tally::new(),
            ),
            None,
        ),
    ];
    for (name, got, refusal) in cases {
        match refusal {
            Some((needed, available)) => assert_eq!(
                got,
                Err(Error::TooWide {
                    what: Quantity::LookupAccumulator,
                    bits_needed: needed,
                    bits_available: available
                }),
                "{name}"
            ),
            None => assert!(got.is_ok(), "{name}: {got:?}"),
        }
    }
    // The documented limits agree: u16 F <= 7, u32 F <= 15, u64 capped at 24.
    assert_eq!(width::max_frac_bits(FormKind::Stable, 16, 31), Some(7));
    assert_eq!(width::max_frac_bits(FormKind::Paper, 32, 63), Some(15));
    assert_eq!(width::max_frac_bits(FormKind::Stable, 64, 127), Some(24));
    assert_eq!(width::max_frac_bits(FormKind::Stable, 31, 31), None);
    // A zero-area box needs no accumulator: sum 0 even at F = 24 on the u16 table.
    let s = t16
        .box_sum_raw(
            &raw([5, 0, 5, 1 << 24]),
            fb(24),
            Stable,
            Border,
            &mut NoCount,
        )
        .expect("empty");
    assert_eq!(s.sum(), 0);
}

/// Millions and `2^40` of repeated periods: exact against the periodicity reference, and the
/// counted work is the same for `10^6` and `2^40` periods (constant time: at most 9 in-range
/// lookups of 16 reads).
#[test]
fn millions_and_2_pow_40_periods() {
    let rt = RefTex::seeded(3, 2, 1, 8, 40);
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 3, 2).expect("tex");
    let mut s32 = vec![0u32; 6];
    let mut s64 = vec![0u64; 6];
    let t32 = Sat::build(&tex, &mut s32).expect("u32");
    let t64 = Sat::build(&tex, &mut s64).expect("u64");
    // At F = 8 sums are scaled by 2^16, so 2^30 periods is about the most a u64 word holds.
    for (f, most) in [(0u32, 1i64 << 40), (8, 1 << 30)] {
        let (p, ph) = (3i64 << f, 2i64 << f);
        let (x0, tail) = (-(5i64 << f) - 77, (1i64 << f) + 19);
        for kind in MODES {
            for form in FORMS {
                let mut costs = Vec::new();
                // Even counts: a mirror's tail is reflected by the parity of the whole periods.
                for q in [1_000_000i64, 7_654_320, most] {
                    let r = [x0, -ph - 3, x0 + q * p + tail, 2 * ph + 5];
                    let mut k = Tally::new();
                    let want = fitting(ref_sums(&rt, r, f, kind), 64).expect("fits u64");
                    let got = lookup(&t32, r, f, form, kind, &mut k);
                    assert_eq!(got, Ok(want), "{q} periods F={f} {kind:?} {form:?}");
                    assert!(k.reads <= 9 * 16, "{q} periods: {} reads", k.reads);
                    costs.push(k);
                }
                assert!(
                    costs.windows(2).all(|c| c[0] == c[1]),
                    "work depends on the number of periods: F={f} {kind:?} {form:?} {costs:?}"
                );
                // 2^40 periods in both axes: too large for u64 (TooWide) unless clipped, exact
                // in the u128 word of a u64 table.
                let r = [x0, -ph, x0 + (p << 40) + tail, (ph << 40) + 5];
                let want = ref_sums(&rt, r, f, kind).expect("fits i128");
                let got32 = lookup(&t32, r, f, form, kind, &mut Tally::new());
                match fitting(Some(want.clone()), 64) {
                    Some(w) => assert_eq!(got32, Ok(w), "2^40 x 2^40 u32 F={f} {kind:?}"),
                    None => assert!(
                        matches!(
                            got32,
                            Err(Error::TooWide {
                                what: Quantity::LookupAccumulator,
                                bits_needed,
                                bits_available: 64
                            }) if bits_needed > 64
                        ),
                        "2^40 x 2^40 u32 F={f} {kind:?} {form:?}: {got32:?}"
                    ),
                }
                let got64 = lookup(&t64, r, f, form, kind, &mut Tally::new());
                assert_eq!(
                    got64,
                    Ok(want.iter().map(|&v| v as u128).collect()),
                    "2^40 x 2^40 u64 F={f} {kind:?} {form:?}"
                );
            }
        }
    }
    // Integer corners, millions of periods through the i32 API.
    for kind in [EdgeKind::Repeat, EdgeKind::Mirror] {
        let r = [-3_000_001, -2_000_000, 3_000_002, 2_000_001];
        let want = ref_sums(&rt, r.map(i64::from), 0, kind).expect("ref")[0];
        let mut k = Tally::new();
        let got = t32
            .box_sum_int(&Rect::new(r[0], r[1], r[2], r[3]), kind, &mut k)
            .map(|s| u128::from(s.sum()));
        assert_eq!(got, Ok(want as u128), "int {kind:?}");
        assert!(k.reads <= 9 * 4, "int {kind:?}: {} reads", k.reads);
    }
}

/// The mean: `round(sum 2^g / area)` ties up, refused only when it does not fit the word.
#[test]
fn means_of_hostile_boxes() {
    let rt = tex53();
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 5, 3).expect("tex");
    let mut st = vec![0u32; 15];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    // A Border box over all of i64 in x: the area is (2^64 - 1) * 3 raw units.
    let r = [i64::MIN, 0, i64::MAX, 3];
    let s = sat
        .box_sum_raw(&raw(r), FracBits::ZERO, Stable, Border, &mut NoCount)
        .expect("sum");
    let sum = u128::from(s.sum());
    let area = u128::from(u64::MAX) * 3;
    for g in [0u32, 1, 8, 16, 40, 60] {
        // round(sum 2^g / area), ties up, in u128 (sum 2^g < 2^76 here).
        let n = sum << g;
        let (q, rem) = (n / area, n % area);
        let want = if rem >= area - rem { q + 1 } else { q };
        assert_eq!(
            s.mean_rounded(0, g, &mut NoCount).map(u128::from),
            Ok(want),
            "mean g={g}"
        );
    }
    // Output bits that no word holds: TooWide { MeanNumerator } with the word's width.
    let small = sat
        .box_sum_int(&Rect::new(0, 0, 2, 2), Border, &mut NoCount)
        .expect("sum");
    for g in [64u32, 65, 129, 1000, u32::MAX] {
        let got = small.mean_rounded(0, g, &mut NoCount);
        assert!(
            matches!(
                got,
                Err(Error::TooWide {
                    what: Quantity::MeanNumerator,
                    bits_needed,
                    bits_available: 64
                }) if bits_needed > 64
            ),
            "g = {g}: {got:?}"
        );
    }
    // Exact ties round up: means 1/2 and 3/2 at g = 0 give 1 and 2; 3/4 at g = 1 (3/2) gives 2.
    let tie = [0u8, 1, 2, 0];
    let ttex = Texture::<u8>::new(&tie, 4, 1).expect("tex");
    let mut tst = [0u32; 4];
    let tsat = Sat::build(&ttex, &mut tst).expect("sat");
    for (r, g, want) in [
        ([0, 0, 2, 1], 0u32, 1u64),
        ([1, 0, 3, 1], 0, 2),
        ([0, 0, 4, 1], 1, 2),
    ] {
        let s = tsat
            .box_sum_int(&Rect::new(r[0], r[1], r[2], r[3]), Border, &mut NoCount)
            .expect("sum");
        assert_eq!(
            s.mean_rounded(0, g, &mut NoCount),
            Ok(want),
            "tie {r:?} g={g}"
        );
    }
    // A zero sum has mean 0 for any g (it fits every word).
    let zero = sat
        .box_sum_raw(
            &raw([6, 0, 9, 3]),
            FracBits::ZERO,
            Stable,
            Border,
            &mut NoCount,
        )
        .expect("outside");
    for g in [0u32, 64, 200, u32::MAX] {
        assert_eq!(
            zero.mean_rounded(0, g, &mut NoCount),
            Ok(0),
            "zero sum, g = {g}"
        );
    }
}

/// Crow's shortcut: within its proven bound of the exact mean, or refused as documented.
#[test]
fn shortcut_within_its_bound_and_at_the_limits() {
    let rt = RefTex::seeded(37, 29, 1, 8, 11);
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 37, 29).expect("tex");
    let mut st = vec![0u32; 37 * 29];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    let sc = Shortcut::with_min_side(9);
    let f = 8u32;
    let g = 8u32;
    let m = rt.max() as i128;
    let mut seed = 99u64;
    for kind in MODES {
        // Under Miri (about 10^4 times slower) 4 random boxes per mode.
        for _ in 0..if cfg!(miri) { 4 } else { 200 } {
            let mut next = |n: i64| -> i64 {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                (seed % (n as u64)) as i64
            };
            let x0 = next(80 << f) - (20 << f);
            let y0 = next(60 << f) - (15 << f);
            let r = [
                x0,
                y0,
                x0 + next(40 << f) + (2 << f),
                y0 + next(40 << f) + (2 << f),
            ];
            let got = sat
                .box_mean_shortcut_raw(&raw(r), fb(f), Stable, kind, &sc, g, &mut NoCount)
                .expect("mean");
            let (wr, hr) = (i128::from(r[2] - r[0]), i128::from(r[3] - r[1]));
            let taken = wr >= 9 << f && hr >= 9 << f;
            assert_eq!(got.shortcut, taken, "{r:?} {kind:?}");
            let sum = ref_sums(&rt, r, f, kind).expect("ref")[0];
            let area = wr * hr;
            let q = got.means[0] as i128;
            let err2 = 2 * (q * area - (sum << g)).abs(); // 2 |q - exact 2^g| area
            if taken {
                // |q / 2^g - exact| <= m (1/(W-1) + 1/(H-1)) + 2^-(g+1), W = wr / 2^F.
                let (a, b) = (wr - (1 << f), hr - (1 << f));
                let rhs = area * (2 * m * (1 << f) * (a + b) * (1 << g) + a * b);
                assert!(err2 * a * b <= rhs, "shortcut {r:?} {kind:?}: {q}");
            } else {
                assert!(err2 <= area, "exact mean {r:?} {kind:?}: {q}");
            }
        }
    }
    // Corners whose rounding leaves i64, and the usual refusals.
    let limits: Vec<(&str, [i64; 4], Error)> = vec![
        (
            "x1 = i64::MAX",
            [0, 0, i64::MAX, 1 << 20],
            Error::CoordinateOutOfRange,
        ),
        ("inverted", [1 << 12, 0, 0, 1 << 12], Error::InvertedBox),
        ("zero area", [0, 0, 0, 1 << 12], Error::ZeroArea),
    ];
    for (name, r, want) in limits {
        assert_eq!(
            sat.box_mean_shortcut_raw(&raw(r), fb(f), Stable, Repeat, &sc, g, &mut NoCount)
                .map(|_| ()),
            Err(want),
            "{name}"
        );
    }
    // Tolerance-derived sides (docs/design.md: 1 grey level -> 511, 64 levels -> 9; 0 -> never).
    assert_eq!(Shortcut::for_tolerance(8, 1, 1).min_side(), 511);
    assert_eq!(Shortcut::for_tolerance(8, 64, 1).min_side(), 9);
    assert_eq!(Shortcut::for_tolerance(8, 0, 1).min_side(), u64::MAX);
    assert_eq!(Shortcut::with_min_side(0).min_side(), 2);
    assert!(!panics(|| Shortcut::for_tolerance(
        u32::MAX,
        u64::MAX,
        u64::MAX
    )));
}

// =============================================================================================
// Modular layouts asked for boxes beyond their bound; plans asked for boxes outside their facts
// =============================================================================================

#[test]
fn modular_boxes_beyond_their_bound() {
    let rt = RefTex::seeded(40, 40, 1, 8, 5);
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 40, 40).expect("tex");
    let k = 16u32; // bits_of(255 * 256) = 16: boxes up to 256 cells
    assert_eq!(Modular::<u32>::bits_for_max_area(8, 256), 16);
    let mut words = vec![0u32; Modular::<u32>::words_needed(40, 40, k).expect("words")];
    let m = Modular::<u32>::build(&tex, k, &mut words, &mut [0u32; 40]).expect("build");
    assert_eq!(m.max_exact_area(), 65535 / 255);
    let tiles = TiledSpec::tiles(8, 8).expect("8 x 8").with_modulus(k);
    let mut tw = vec![0u32; Tiled::<u32>::words_needed(tiles, 40, 40, 8).expect("words")];
    let mut ts = vec![0u32; Tiled::<u32>::scratch_needed(tiles, 40).expect("s")];
    let tm = Tiled::<u32>::build(&tex, tiles, &mut tw, &mut ts).expect("tiled mod");
    let refuse = |needed: u32| Error::TooWide {
        what: Quantity::ModularBox,
        bits_needed: needed,
        bits_available: k,
    };
    // (name, box, F, form, mode, refusal bits or None for exact). In-range boxes: the bound is
    // m * cells (+ 2F for Paper).
    let rows = vec![
        (
            "16 x 16 at the bound",
            [3, 4, 19, 20],
            0,
            FormKind::Stable,
            EdgeKind::Border,
            None,
        ),
        (
            "16 x 17 one row past",
            [3, 4, 19, 21],
            0,
            FormKind::Stable,
            EdgeKind::Border,
            Some(bits(255 * 272)),
        ),
        (
            "40 x 40 whole texture",
            [0, 0, 40, 40],
            0,
            FormKind::Paper,
            EdgeKind::Border,
            Some(bits(255 * 1600)),
        ),
        (
            "15.5 x 15.5 spans 16 x 16 cells, Stable",
            [128, 128, 16 * 256, 16 * 256],
            8,
            FormKind::Stable,
            EdgeKind::Border,
            None,
        ),
        (
            "15.5 x 15.5, Paper needs 2F more",
            [128, 128, 16 * 256, 16 * 256],
            8,
            FormKind::Paper,
            EdgeKind::Border,
            Some(16 + 16),
        ),
        (
            "16.5 wide spans 17 cells",
            [128, 0, 16 * 256 + 256, 16 * 256],
            8,
            FormKind::Stable,
            EdgeKind::Border,
            Some(bits(255 * 17 * 16)),
        ),
        (
            "inside one later period, Repeat",
            [4003, 8, 4019, 24],
            0,
            FormKind::Stable,
            EdgeKind::Repeat,
            None,
        ),
        (
            "crossing the edge, 16 x 16 cells, Stable Repeat",
            [-8, -8, 8, 8],
            0,
            FormKind::Stable,
            EdgeKind::Repeat,
            None,
        ),
        (
            "crossing the edge, 16 x 16 cells, Stable Mirror",
            [32, 36, 48, 52],
            0,
            FormKind::Stable,
            EdgeKind::Mirror,
            None,
        ),
        (
            "a million periods",
            [0, 0, 40_000_000, 8],
            0,
            FormKind::Stable,
            EdgeKind::Repeat,
            Some(bits(255 * 320_000_000)),
        ),
    ];
    for (name, r, f, form, kind, refusal) in rows {
        let want = match refusal {
            Some(b) => Err(refuse(b)),
            None => Ok(fitting(ref_sums(&rt, r, f, kind), 64).expect("fits")),
        };
        assert_eq!(
            lookup(&m, r, f, form, kind, &mut Tally::new()),
            want,
            "modular: {name}"
        );
        assert_eq!(
            lookup(&tm, r, f, form, kind, &mut Tally::new()),
            want,
            "tiled+mod: {name}"
        );
    }
    // The integer-corner API refuses the same way.
    assert_eq!(
        m.box_sum_int(&Rect::new(0, 0, 17, 16), Border, &mut NoCount)
            .map(|s| s.sum()),
        Err(refuse(bits(255 * 272)))
    );
}

#[test]
fn plan_invalid_facts() {
    let base = SceneFacts::new(64, 64, 8, 8, EdgeKind::Repeat);
    let rows: Vec<(&str, SceneFacts, Error)> = vec![
        (
            "width 0",
            SceneFacts::new(0, 64, 8, 8, EdgeKind::Repeat),
            Error::EmptyTexture,
        ),
        (
            "texel bits 0",
            SceneFacts::new(64, 64, 0, 8, EdgeKind::Repeat),
            Error::InvalidTexelBits { bits: 0 },
        ),
        (
            "texel bits 17",
            SceneFacts::new(64, 64, 17, 8, EdgeKind::Repeat),
            Error::InvalidTexelBits { bits: 17 },
        ),
        (
            "zero channels",
            SceneFacts {
                channels: 0,
                ..base
            },
            Error::NoSuchChannel,
        ),
        (
            "F = 25",
            SceneFacts::new(64, 64, 8, 25, EdgeKind::Repeat),
            Error::FracBitsUnsupported {
                frac_bits: 25,
                max: 24,
            },
        ),
        (
            "F = u32::MAX",
            SceneFacts::new(64, 64, 8, u32::MAX, EdgeKind::Repeat),
            Error::FracBitsUnsupported {
                frac_bits: u32::MAX,
                max: 24,
            },
        ),
        (
            "smallest box above the largest",
            SceneFacts {
                min_box: [1000, 1000],
                max_box: [999, 2000],
                ..base
            },
            Error::InvertedBox,
        ),
        (
            "a read bound nothing meets",
            SceneFacts {
                max_reads: 3,
                ..base
            },
            Error::NoPlan,
        ),
        (
            "a texture no word holds",
            SceneFacts::new(MAX_SIDE, MAX_SIDE, 16, 24, EdgeKind::Repeat),
            Error::NoPlan,
        ),
    ];
    for (name, facts, want) in rows {
        assert_eq!(Plan::for_scene(&facts).map(|_| ()), Err(want), "{name}");
    }
}

#[test]
fn plan_boxes_outside_their_facts() {
    const FACTS: SceneFacts = SceneFacts {
        max_box: [16 << 8, 16 << 8],
        ..SceneFacts::new(256, 256, 8, 8, EdgeKind::Repeat)
    };
    let plan = Plan::for_scene(&FACTS).expect("plan");
    let outside = |limit| Err(Error::OutsidePlan { limit });
    let rows: Vec<(&str, [i64; 4], Result<(), Error>)> = vec![
        ("one texel", [0, 0, 256, 256], Ok(())),
        (
            "16 x 16 at the far corner",
            [240 << 8, 240 << 8, 256 << 8, 256 << 8],
            Ok(()),
        ),
        ("inverted", [256, 0, 0, 256], Err(Error::InvertedBox)),
        (
            "inverted at i64 ends",
            [i64::MAX, 0, i64::MIN, 256],
            Err(Error::InvertedBox),
        ),
        (
            "zero area",
            [512, 512, 512, 768],
            outside(PlanLimit::BoxTooSmall),
        ),
        (
            "half a texel",
            [0, 0, 128, 256],
            outside(PlanLimit::BoxTooSmall),
        ),
        (
            "17 texels wide",
            [0, 0, 17 << 8, 256],
            outside(PlanLimit::BoxTooLarge),
        ),
        (
            "all of i64",
            [i64::MIN, i64::MIN, i64::MAX, i64::MAX],
            outside(PlanLimit::BoxTooLarge),
        ),
        (
            "leaves the texture left",
            [-256, 0, 256, 256],
            outside(PlanLimit::LeavesTexture),
        ),
        (
            "leaves at the far corner",
            [255 << 8, 255 << 8, (257 << 8) - 1, 256 << 8],
            outside(PlanLimit::LeavesTexture),
        ),
        (
            "far outside",
            [i64::MAX - 512, 0, i64::MAX, 512],
            outside(PlanLimit::LeavesTexture),
        ),
    ];
    for (name, r, want) in rows {
        assert_eq!(plan.check_box(&raw(r)), want, "{name}");
    }
    // The plan's own table refuses by itself a box too large for its modulus.
    assert_eq!(plan.layout(), PlanLayout::TiledModular { tile: 8, k: 17 });
    // Under Miri (about 10^4 times slower) the plan's layout on a 48 x 48 texture: the boxes
    // below fit in it.
    let n = if cfg!(miri) { 48 } else { 256 };
    let rt = RefTex::seeded(n, n, 1, 8, 17);
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, n, n).expect("tex");
    let spec = plan.layout().tiled_spec().expect("tiled");
    let len = if cfg!(miri) {
        Tiled::<u32>::words_needed(spec, n, n, 8).expect("words")
    } else {
        plan.storage_len()
    };
    let mut words = vec![0u32; len];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, n).expect("s")];
    let t = Tiled::<u32>::build(&tex, spec, &mut words, &mut scratch).expect("build");
    // 22 x 22 cells: 255 * 484 = 123 420 < 2^17, exact although the facts say 16; 23 x 23 cells:
    // 134 895 needs 18 bits.
    let ok = [10 << 8, 10 << 8, 32 << 8, 32 << 8];
    assert_eq!(
        lookup(
            &t,
            ok,
            8,
            FormKind::Stable,
            EdgeKind::Repeat,
            &mut Tally::new()
        ),
        Ok(fitting(ref_sums(&rt, ok, 8, EdgeKind::Repeat), 64).expect("fits"))
    );
    assert_eq!(
        lookup(
            &t,
            [10 << 8, 10 << 8, 33 << 8, 33 << 8],
            8,
            FormKind::Stable,
            EdgeKind::Repeat,
            &mut Tally::new()
        ),
        Err(Error::TooWide {
            what: Quantity::ModularBox,
            bits_needed: bits(255 * 23 * 23),
            bits_available: 17
        })
    );
}

// =============================================================================================
// Filters: constructors with short storage, hostile footprints
// =============================================================================================

#[test]
fn filter_constructors_with_short_storage() {
    let rt = RefTex::seeded(6, 5, 1, 8, 3);
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 6, 5).expect("tex");
    let short = |needed: usize| {
        Err(Error::StorageTooSmall {
            needed,
            got: needed - 1,
        })
    };
    // Mip: coarse levels 3 x 3, 2 x 2, 1 x 1 = 14 texels.
    let mip_need = MipPyramid::<u8>::storage_needed(6, 5).expect("need");
    assert_eq!(mip_need, 9 + 4 + 1);
    let mut m = vec![0u8; mip_need - 1];
    assert_eq!(
        MipPyramid::build(&tex, &mut m).map(|_| ()),
        short(mip_need),
        "MipPyramid::build"
    );
    // Rip: (6 + 3 + 2 + 1) * (5 + 3 + 2 + 1).
    let rip_need = RipMap::<u8, 1>::storage_needed(6, 5);
    assert_eq!(rip_need, 12 * 11);
    let mut r = vec![0u8; rip_need - 1];
    assert_eq!(
        RipMap::build(&tex, &mut r).map(|_| ()),
        short(rip_need),
        "RipMap::build"
    );
    assert_eq!(
        RipMap::<u8, 1>::from_storage(&r, 6, 5).map(|_| ()),
        short(rip_need),
        "RipMap::from_storage"
    );
    // Dip: w * (5 + 3 + 2 + 1) + h * (3 + 2 + 1).
    let dip_need = DipMap::<u8, 1>::storage_needed(6, 5);
    assert_eq!(dip_need, 6 * 11 + 5 * 6);
    let mut d = vec![0u8; dip_need - 1];
    assert_eq!(
        DipMap::build(&tex, &mut d).map(|_| ()),
        short(dip_need),
        "DipMap::build"
    );
    assert_eq!(
        DipMap::<u8, 1>::from_storage(&d, 6, 5).map(|_| ()),
        short(dip_need),
        "DipMap::from_storage"
    );
    // Tent: (w + 1)(h + 1) C; lines (w (h + 1) + (w + 1) h) C.
    let tent_need = TentTable::<u64>::storage_needed(6, 5).expect("need");
    assert_eq!(tent_need, 7 * 6);
    let mut q = vec![0u64; tent_need - 1];
    assert_eq!(
        TentTable::build(&tex, &mut q).map(|_| ()),
        short(tent_need),
        "TentTable::build"
    );
    let lines_need = TentLines::<u32>::storage_needed(6, 5).expect("need");
    assert_eq!(lines_need, 6 * 6 + 7 * 5);
    let mut l = vec![0u32; lines_need - 1];
    assert_eq!(
        TentLines::build(&tex, &mut l).map(|_| ()),
        short(lines_need),
        "TentLines::build"
    );
    // Variance: w h C each.
    let mut v_ok = vec![0u32; 30];
    let mut v_short = vec![0u32; 29];
    assert_eq!(
        VarianceTables::build(&tex, &mut v_short, &mut v_ok).map(|_| ()),
        short(30),
        "VarianceTables values"
    );
    let mut v_ok2 = vec![0u32; 30];
    let mut v_short2 = vec![0u32; 29];
    assert_eq!(
        VarianceTables::build(&tex, &mut v_ok2, &mut v_short2).map(|_| ()),
        short(30),
        "VarianceTables squares"
    );
    assert!(
        v_ok2.iter().all(|&v| v == 0),
        "VarianceTables wrote on refusal"
    );
    let mut sq = vec![0u32; 29];
    assert_eq!(
        SquaresTable::build(&tex, &mut sq).map(|_| ()),
        short(30),
        "SquaresTable"
    );
    // Widths: squares of 8-bit texels in u16 (2 texels: bits_of(255^2 * 2) = 17).
    let two = [255u8, 255];
    let tex2 = Texture::<u8>::new(&two, 2, 1).expect("tex");
    assert_eq!(
        SquaresTable::build(&tex2, &mut [0u16; 2]).map(|_| ()),
        Err(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: bits(255 * 255 * 2),
            bits_available: 16
        })
    );
    assert_eq!(variance::squares_entry_bits(8, 2, 1), 17);
    // Tent in u32: 63 x 63 fits (bits_of(255 (63 * 65)^2) = 32), 64 x 64 does not (33).
    let tent_bits = |n: u128| bits(255 * (n * (n + 2)).pow(2));
    assert_eq!((tent_bits(63), tent_bits(64)), (32, 33));
    let big = vec![255u8; 64 * 64];
    for (n, want) in [(63usize, Ok(())), (64, Err(33u32))] {
        let t = Texture::<u8>::new(&big[..n * n], n, n).expect("tex");
        let mut st = vec![0u32; (n + 1) * (n + 1)];
        let got = TentTable::build(&t, &mut st).map(|_| ());
        let want = want.map_err(|b| Error::TooWide {
            what: Quantity::Entry,
            bits_needed: b,
            bits_available: 32,
        });
        assert_eq!(got, want, "TentTable<u32> {n} x {n}");
    }
    // u64 holds 8-bit tables up to 16 399 x 16 399 and refuses 16 400 (docs/filters.md).
    assert!(tent::tent_entry_bits(8, 16_399, 16_399) <= 64);
    assert!(tent::tent_entry_bits(8, 16_400, 16_400) > 64);
    // Dimensions.
    let dims: Vec<(&str, Result<(), Error>, Error)> = vec![
        (
            "RipMap 0 x 5",
            RipMap::<u8, 1>::from_storage(&[], 0, 5).map(|_| ()),
            Error::EmptyTexture,
        ),
        (
            "DipMap 2^31 x 1",
            DipMap::<u8, 1>::from_storage(&[], MAX_SIDE + 1, 1).map(|_| ()),
            Error::TextureTooLarge {
                dimension: MAX_SIDE + 1,
            },
        ),
        (
            "MipPyramid 2^31 x 1",
            MipPyramid::<u8>::storage_needed(MAX_SIDE + 1, 1).map(|_| ()),
            Error::TextureTooLarge {
                dimension: MAX_SIDE + 1,
            },
        ),
        (
            "RipMap at the side limit: saturated need, refused",
            RipMap::<u8, 1>::from_storage(&[0u8; 8], MAX_SIDE, MAX_SIDE).map(|_| ()),
            Error::StorageTooSmall {
                needed: RipMap::<u8, 1>::storage_needed(MAX_SIDE, MAX_SIDE),
                got: 8,
            },
        ),
    ];
    for (name, got, want) in dims {
        assert_eq!(got, Err(want), "{name}");
    }
    assert_eq!(RipMap::<u8, 1>::storage_needed(0, 5), 0);
    assert_eq!(
        RipMap::<u8, 4>::storage_needed(usize::MAX, usize::MAX),
        usize::MAX
    );
}

#[test]
fn filter_samples_with_hostile_footprints() {
    let rt = RefTex::seeded(6, 5, 1, 8, 3);
    let texels = rt.u8s();
    let tex = Texture::<u8>::new(&texels, 6, 5).expect("tex");
    let mut ms = vec![0u8; MipPyramid::<u8>::storage_needed(6, 5).expect("n")];
    let mip = MipPyramid::build(&tex, &mut ms).expect("mip");
    let mut rs = vec![0u8; RipMap::<u8, 1>::storage_needed(6, 5)];
    let ripm = RipMap::build(&tex, &mut rs).expect("rip");
    let mut ds = vec![0u8; DipMap::<u8, 1>::storage_needed(6, 5)];
    let dipm = DipMap::build(&tex, &mut ds).expect("dip");
    let m16 = u64::from(rt.max() as u16) << OUT_FRAC_BITS;
    let inverted = [[3, 0, 2, 1], [0, 3, 1, 2], [i64::MAX, 0, i64::MIN, 0]];
    let min_point = [i64::MIN, 0, i64::MIN, 0];
    let huge = [
        [i64::MIN, i64::MIN, i64::MAX, i64::MAX],
        [i64::MAX, i64::MAX, i64::MAX, i64::MAX],
        [i64::MIN + 1, 7, i64::MIN + 1, 7],
        [-5, i64::MIN, 9, i64::MIN / 3],
    ];
    for kind in MODES {
        for f in [0u32, 8, 24] {
            for r in inverted {
                let rr = raw(r);
                let e = Err(Error::InvertedBox);
                assert_eq!(
                    point_raw(&tex, &rr, fb(f), kind, &mut NoCount),
                    e,
                    "point {r:?}"
                );
                assert_eq!(mip.lod_raw(&rr, fb(f)).map(|_| ()), Err(Error::InvertedBox));
                assert_eq!(mip.point_sample_raw(&rr, fb(f), kind, &mut NoCount), e);
                assert_eq!(mip.trilinear_raw(&rr, fb(f), kind, &mut NoCount), e);
                assert_eq!(ripm.sample_raw(&rr, fb(f), kind, &mut NoCount), e);
                assert_eq!(
                    dipm.sample_raw(&rr, fb(f), DipFilter::Trilinear, kind, &mut NoCount),
                    e
                );
            }
            // Any i64 corners: a sample, never a wrap. Point and point-sampled pyramid are
            // exact texels; the interpolating filters are convex combinations, so at most m.
            for r in huge {
                let rr = raw(r);
                let ctx = format!("{r:?} F={f} {kind:?}");
                // Point: the texel of the extended texture holding the centre, by i128.
                let centre = |a: i64, b: i64| (i128::from(a) + i128::from(b)) >> (f + 1);
                let (cx, cy) = (centre(r[0], r[2]), centre(r[1], r[3]));
                let want = ref_texel_index(kind, cx, 6)
                    .zip(ref_texel_index(kind, cy, 5))
                    .map_or(0, |(x, y)| (rt.texel(x, y, 0) as u64) << OUT_FRAC_BITS);
                assert_eq!(
                    point_raw(&tex, &rr, fb(f), kind, &mut NoCount).map(|s| s.values[0]),
                    Ok(want),
                    "point {ctx}"
                );
                let p = mip.point_sample_raw(&rr, fb(f), kind, &mut NoCount);
                assert!(
                    matches!(p, Ok(s) if s.values[0] <= m16),
                    "mip point {ctx}: {p:?}"
                );
                for (name, got) in [
                    (
                        "trilinear",
                        mip.trilinear_raw(&rr, fb(f), kind, &mut NoCount),
                    ),
                    ("ripmap", ripm.sample_raw(&rr, fb(f), kind, &mut NoCount)),
                    (
                        "dipmap",
                        dipm.sample_raw(&rr, fb(f), DipFilter::Bilinear, kind, &mut NoCount),
                    ),
                ] {
                    assert!(
                        matches!(got, Ok(s) if s.values[0] <= m16),
                        "{name} {ctx}: {got:?}"
                    );
                }
            }
        }
        // The one documented refusal of the interpolating pyramids: a centre at the bottom of
        // i64 at F = 0 (its left tap is below i64::MIN).
        let rr = raw(min_point);
        let oor = Err(Error::CoordinateOutOfRange);
        assert_eq!(
            mip.trilinear_raw(&rr, FracBits::ZERO, kind, &mut NoCount),
            oor
        );
        assert_eq!(
            ripm.sample_raw(&rr, FracBits::ZERO, kind, &mut NoCount),
            oor
        );
        for filter in [DipFilter::Bilinear, DipFilter::Trilinear] {
            assert_eq!(
                dipm.sample_raw(&rr, FracBits::ZERO, filter, kind, &mut NoCount),
                oor
            );
        }
        assert!(mip
            .point_sample_raw(&rr, FracBits::ZERO, kind, &mut NoCount)
            .is_ok());
    }
    // Accessors out of range.
    assert_eq!(mip.level_texel(0, 6, 0), None);
    assert_eq!(mip.level_texel(usize::MAX, 0, 0), None);
    assert_eq!(ripm.level_size(ripm.levels_x(), 0), None);
    assert_eq!(ripm.level_texel(0, 0, 6, 0), None);
    assert_eq!(
        dipm.level_size(DipPyramid::Row, dipm.levels(DipPyramid::Row)),
        None
    );
    assert_eq!(dipm.level_texel(DipPyramid::Column, 0, 0, 5), None);
}

/// A reference for the extended texture's texel index (not texsat's `texel_index`).
fn ref_texel_index(kind: EdgeKind, i: i128, n: i128) -> Option<usize> {
    let idx = match kind {
        EdgeKind::Border => (0..n).contains(&i).then_some(i)?,
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
    usize::try_from(idx).ok()
}

#[test]
fn tent_and_variance_hostile_footprints() {
    // A constant texture: the tent filter of the extended texture under Clamp/Repeat/Mirror is
    // the constant exactly, however large the footprint; the variance 0.
    let c = 77u8;
    let texels = vec![c; 4 * 3];
    let tex = Texture::<u8>::new(&texels, 4, 3).expect("tex");
    let mut q = vec![0u64; TentTable::<u64>::storage_needed(4, 3).expect("n")];
    let tt = TentTable::build(&tex, &mut q).expect("tent");
    let mut ls = vec![0u32; TentLines::<u32>::storage_needed(4, 3).expect("n")];
    let lines = TentLines::build(&tex, &mut ls).expect("lines");
    let want = u64::from(c) << OUT_FRAC_BITS;
    for kind in [EdgeKind::Clamp, EdgeKind::Repeat, EdgeKind::Mirror] {
        for (cx, cy, a, b) in [
            (1, 1, 1, 1),
            (i32::MAX, i32::MIN, 1, 1),
            (-1000, 5000, 3000, 7),
            (i32::MIN, i32::MAX, u32::MAX, u32::MAX),
        ] {
            let got = tt.sample_int(cx, cy, a, b, kind, &mut NoCount);
            assert!(
                matches!(got, Ok(s) if s.values[0] == want)
                    || matches!(
                        got,
                        Err(Error::TooWide {
                            what: Quantity::LookupAccumulator | Quantity::MeanNumerator,
                            ..
                        })
                    ),
                "tent int ({cx}, {cy}, {a}, {b}) {kind:?}: {got:?}"
            );
        }
        for f in [0u32, 8] {
            for r in [
                [0, 0, 4 << f, 3 << f],
                [-(1000 << f), -(7 << f) + 3, 1000 << f, 9 << f],
                [i64::MIN / 4, i64::MIN / 4, i64::MAX / 4, i64::MAX / 4],
            ] {
                let rr = raw(r);
                let exact = tt.sample_exact_raw(&lines, &tex, &rr, fb(f), kind, &mut NoCount);
                assert!(
                    matches!(exact, Ok(s) if s.values[0] == want)
                        || matches!(exact, Err(Error::TooWide { .. })),
                    "tent exact {r:?} F={f} {kind:?}: {exact:?}"
                );
            }
        }
    }
    let zero_and_inverted: Vec<(&str, Result<(), Error>, Error)> = vec![
        (
            "tent int a = 0",
            tt.sample_int(1, 1, 0, 3, Border, &mut NoCount).map(|_| ()),
            Error::ZeroArea,
        ),
        (
            "tent zero width",
            tt.sample_raw(&raw([256, 0, 256, 512]), fb(8), Border, &mut NoCount)
                .map(|_| ()),
            Error::ZeroArea,
        ),
        (
            "tent inverted",
            tt.sample_raw(&raw([512, 0, 256, 512]), fb(8), Border, &mut NoCount)
                .map(|_| ()),
            Error::InvertedBox,
        ),
        (
            "tent exact inverted",
            tt.sample_exact_raw(
                &lines,
                &tex,
                &raw([0, 9, 1, 8]),
                FracBits::ZERO,
                Repeat,
                &mut NoCount,
            )
            .map(|_| ()),
            Error::InvertedBox,
        ),
    ];
    for (name, got, want) in zero_and_inverted {
        assert_eq!(got, Err(want), "{name}");
    }
    // Lines or texture of other dimensions than the table: RowLength.
    let other = vec![c; 5 * 3];
    let tex5 = Texture::<u8>::new(&other, 5, 3).expect("tex");
    assert_eq!(
        tt.sample_exact_raw(
            &lines,
            &tex5,
            &raw([0, 0, 1, 1]),
            FracBits::ZERO,
            Border,
            &mut NoCount
        )
        .map(|_| ()),
        Err(Error::RowLength {
            expected: 4,
            got: 5
        }),
        "tent exact, texture 5 wide"
    );
    assert_eq!(tt.corner(6, 0), None);
    assert_eq!(tt.corner(0, usize::MAX), None);

    // Variance: a 2 x 1 texture [0, 1] repeated: over whole periods the variance is 1/4
    // (2^16 / 4 output units), up to n < 2^62 raw area units; from 2^62 on refused with
    // TooWide { MeanNumerator, bits_needed: bits_of(n), bits_available: 62 }.
    let vt = [0u8, 1];
    let vtex = Texture::<u8>::new(&vt, 2, 1).expect("tex");
    let mut a = [0u32; 2];
    let mut b = [0u32; 2];
    let v = VarianceTables::build(&vtex, &mut a, &mut b).expect("variance");
    let big_ok = [0, 0, 1i32 << 30, i32::MAX]; // 2^30 x (2^31 - 1) < 2^62
    let ok = v.variance_int(
        &Rect::new(big_ok[0], big_ok[1], big_ok[2], big_ok[3]),
        Repeat,
        &mut NoCount,
    );
    assert_eq!(
        ok.map(|s| s.values[0]),
        Ok(1 << 14),
        "variance just below 2^62"
    );
    let n = (1u128 << 31) * (1u128 << 31);
    let too_big = v.variance_raw(
        &raw([0, 0, 1 << 31, 1 << 31]),
        FracBits::ZERO,
        Stable,
        Repeat,
        &mut NoCount,
    );
    assert_eq!(
        too_big.map(|_| ()),
        Err(Error::TooWide {
            what: Quantity::MeanNumerator,
            bits_needed: bits(n),
            bits_available: 62
        }),
        "variance at 2^62 raw area units"
    );
    let vz: Vec<(&str, Result<(), Error>, Error)> = vec![
        (
            "variance zero area",
            v.variance_int(&Rect::new(1, 0, 1, 1), Border, &mut NoCount)
                .map(|_| ()),
            Error::ZeroArea,
        ),
        (
            "variance inverted",
            v.variance_int(&Rect::new(1, 0, 0, 1), Border, &mut NoCount)
                .map(|_| ()),
            Error::InvertedBox,
        ),
        (
            "variance inverted raw",
            v.variance_raw(&raw([0, 1, 1, 0]), fb(8), Paper, Repeat, &mut NoCount)
                .map(|_| ()),
            Error::InvertedBox,
        ),
    ];
    for (name, got, want) in vz {
        assert_eq!(got, Err(want), "{name}");
    }
}

// =============================================================================================
// Const helpers, packed fields, boundary-mode indices, counters, errors
// =============================================================================================

#[test]
fn width_helpers_with_absurd_arguments() {
    let rows: Vec<(&str, u32, u32)> = vec![
        (
            "bits_of_product max^3",
            width::bits_of_product(u64::MAX, u64::MAX, u64::MAX),
            192,
        ),
        (
            "bits_of_product 0",
            width::bits_of_product(0, u64::MAX, u64::MAX),
            0,
        ),
        (
            "entry bits of absurd sizes",
            width::entry_bits_worst_case(u32::MAX, usize::MAX, usize::MAX),
            192,
        ),
        (
            "entry bits 1-bit 1x1",
            width::entry_bits_worst_case(1, 1, 1),
            1,
        ),
        (
            "entry bits 0 texels wide",
            width::entry_bits_worst_case(8, 0, 5),
            0,
        ),
        (
            "paper acc saturates",
            width::paper_acc_bits(u32::MAX, u32::MAX),
            u32::MAX,
        ),
        (
            "stable acc saturates",
            width::stable_acc_bits(u32::MAX, 0),
            u32::MAX,
        ),
        (
            "naive saturates",
            width::entry_bits_naive(u32::MAX, usize::MAX, usize::MAX),
            u32::MAX,
        ),
        ("acc value bits u16", width::acc_value_bits(16), 31),
        ("acc value bits u32", width::acc_value_bits(32), 63),
        ("acc value bits 1000", width::acc_value_bits(1000), 127),
        (
            "modular k for 0 area",
            texsat::layouts::modulus_bits_for(8, 0),
            0,
        ),
        (
            "modular k, max area",
            texsat::layouts::modulus_bits_for(16, u64::MAX),
            bits(65535 * u128::from(u64::MAX)),
        ),
        (
            "modular k, texel bits 200",
            texsat::layouts::modulus_bits_for(200, 1),
            200,
        ),
        (
            "squares bits saturate",
            variance::squares_entry_bits(u32::MAX, usize::MAX, usize::MAX),
            192,
        ),
        (
            "tent bits saturate",
            tent::tent_entry_bits(u32::MAX, usize::MAX, usize::MAX),
            128,
        ),
    ];
    for (name, got, want) in rows {
        assert_eq!(got, want, "{name}");
    }
    let check: Vec<Row<()>> = vec![
        (
            "texel bits 0",
            width::check_texel_bits(0),
            Err(Error::InvalidTexelBits { bits: 0 }),
        ),
        (
            "texel bits 17",
            width::check_texel_bits(17),
            Err(Error::InvalidTexelBits { bits: 17 }),
        ),
        ("texel bits 16", width::check_texel_bits(16), Ok(())),
        (
            "entry check, texel bits u32::MAX",
            width::check_entry_worst_case(u32::MAX, 1, 1, 64),
            Err(Error::InvalidTexelBits { bits: u32::MAX }),
        ),
        (
            "entry check, zero entry bits",
            width::check_entry_worst_case(1, 1, 1, 0),
            Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: 1,
                bits_available: 0,
            }),
        ),
        (
            "acc check",
            width::check_acc(u32::MAX, 0),
            Err(Error::TooWide {
                what: Quantity::LookupAccumulator,
                bits_needed: u32::MAX,
                bits_available: 0,
            }),
        ),
    ];
    for (name, got, want) in check {
        assert_eq!(got, want, "{name}");
    }
    assert_eq!(width::max_frac_bits(FormKind::Paper, 200, 63), None);
    assert_eq!(width::max_frac_bits(FormKind::Stable, 0, 127), Some(24));
    assert!(!panics(|| width::paper_multiplies(
        u32::MAX,
        usize::MAX,
        usize::MAX,
        u32::MAX
    )));
    assert!(!panics(|| width::stable_multiplies(
        u32::MAX,
        usize::MAX,
        u32::MAX
    )));
}

#[test]
fn packed_fields_past_the_end() {
    // Reads past the slice give zero bits; writes that do not fit are refused, writing nothing.
    let words = [u32::MAX; 3];
    let rows = vec![
        ("len 0", packed::read_bits(&words, 5, 0), (0, 0)),
        (
            "64 bits at 0",
            packed::read_bits(&words, 0, 64),
            (u64::MAX, 2),
        ),
        (
            "64 bits at 31: three words",
            packed::read_bits(&words, 31, 64),
            (u64::MAX, 3),
        ),
        ("past the end", packed::read_bits(&words, 96, 8), (0, 1)),
        (
            "at u64::MAX",
            packed::read_bits(&words, u64::MAX, 64),
            (0, 3),
        ),
        (
            "len 100 reads 64",
            packed::read_bits(&words, 0, 100),
            (u64::MAX, 2),
        ),
        ("empty slice", packed::read_bits(&[], 0, 7), (0, 1)),
    ];
    for (name, got, want) in rows {
        assert_eq!(got, want, "read_bits {name}");
    }
    let mut w = [0u32; 2];
    let writes: Vec<(&str, bool, bool)> = vec![
        ("fits", packed::write_bits(&mut w, 60, 4, 0xF), true),
        (
            "one bit past",
            packed::write_bits(&mut w, 61, 4, 0xF),
            false,
        ),
        (
            "value wider than len",
            packed::write_bits(&mut w, 0, 4, 0x10),
            false,
        ),
        ("len 65", packed::write_bits(&mut w, 0, 65, 1), false),
        (
            "offset u64::MAX",
            packed::write_bits(&mut w, u64::MAX, 1, 1),
            false,
        ),
        ("len 0, value 0", packed::write_bits(&mut w, 9, 0, 0), true),
        ("len 0, value 1", packed::write_bits(&mut w, 9, 0, 1), false),
    ];
    for (name, got, want) in writes {
        assert_eq!(got, want, "write_bits {name}");
    }
    assert_eq!(w, [0, 0xF000_0000], "only the fitting write landed");
    assert_eq!(packed::words_for(usize::MAX, 64), usize::MAX, "saturates");
    assert_eq!(packed::words_for_checked(usize::MAX, 64), None);
    assert_eq!(packed::words_for_checked(1000, 12), Some(375));
    assert_eq!(packed::words_for_checked(usize::MAX, 0), Some(0));
}

#[test]
fn texel_index_at_the_ends_of_i64() {
    for kind in MODES {
        for n in [1usize, 2, 3, 7, 1 << 20] {
            for i in [
                i64::MIN,
                i64::MIN + 1,
                -1,
                0,
                1,
                n as i64 - 1,
                n as i64,
                i64::MAX - 1,
                i64::MAX,
            ] {
                assert_eq!(
                    kind.texel_index(i, n),
                    ref_texel_index(kind, i128::from(i), n as i128),
                    "{kind:?} i={i} n={n}"
                );
            }
        }
        assert_eq!(kind.texel_index(0, 0), None, "{kind:?} empty axis");
        assert_eq!(kind.texel_index(i64::MAX, 0), None);
    }
    for name in ["", "BORDER", "repeat ", "\u{0}"] {
        assert_eq!(EdgeKind::from_name(name), None, "{name:?}");
        assert_eq!(FormKind::from_name(name), None, "{name:?}");
    }
}

#[test]
fn every_error_displays() {
    let all = [
        Error::EmptyTexture,
        Error::TextureTooLarge {
            dimension: usize::MAX,
        },
        Error::StrideTooSmall {
            stride: 0,
            needed: usize::MAX,
        },
        Error::TextureDataTooShort {
            needed: usize::MAX,
            got: 0,
        },
        Error::StorageTooSmall {
            needed: usize::MAX,
            got: 0,
        },
        Error::TooWide {
            what: Quantity::Field,
            bits_needed: u32::MAX,
            bits_available: 0,
        },
        Error::FracBitsUnsupported {
            frac_bits: u32::MAX,
            max: 24,
        },
        Error::InvertedBox,
        Error::ZeroArea,
        Error::CoordinateOutOfRange,
        Error::NotFinite,
        Error::InvalidTable {
            x: usize::MAX,
            y: 0,
            channel: 3,
        },
        Error::RowLength {
            expected: 0,
            got: usize::MAX,
        },
        Error::TooManyRows,
        Error::MissingRows {
            got: 0,
            expected: usize::MAX,
        },
        Error::NoSuchChannel,
        Error::InvalidLevels,
        Error::InvalidModulus { bits: u32::MAX },
        Error::CorruptStorage,
        Error::InvalidTexelBits { bits: u32::MAX },
        Error::NoPlan,
        Error::OutsidePlan {
            limit: PlanLimit::LeavesTexture,
        },
    ];
    for e in all {
        assert!(!e.to_string().is_empty(), "{e:?}");
    }
}

/// The helpers for texel widths the crate supports (1 to 16 bits) give the documented values.
#[test]
fn error_bound_helpers_in_their_domain() {
    for b in 1..=16u32 {
        let m = (1u64 << b) - 1;
        assert_eq!(rip::arithmetic_error_bound(b), 1 << (b + 1), "rip {b}");
        assert_eq!(dip::arithmetic_error_bound(b), 1 << (b + 1), "dip {b}");
        assert_eq!(
            rip::level_selection_error_bound(b),
            m << (16 + 2 - 12),
            "rip level {b}"
        );
        assert_eq!(
            dip::level_selection_error_bound(b),
            m << (16 + 1 - 12),
            "dip level {b}"
        );
        assert_eq!(mip::weight_bits(b), (64 - 8 - b) / 2, "weight bits {b}");
    }
}

// =============================================================================================
// Findings: the code disagrees with its documentation (kept, ignored; see the report)
// =============================================================================================

/// `width::max_frac_bits` promises `None` "if not even F = 0 fits"; with `total_bits` near
/// `u32::MAX` the sum `total_bits + 1` overflows (debug: panic; release: wraps and answers
/// `Some(24)`).
#[test]
fn finding_max_frac_bits_overflow() {
    let got = catch_unwind(|| width::max_frac_bits(FormKind::Stable, u32::MAX, 63));
    assert_eq!(got.ok(), Some(None));
}

/// The pyramids' error-bound helpers shift by `texel_bits + 1` (or `texel_bits`) unchecked: for
/// texel widths of 63 and up they panic in debug and wrap silently in release, against "no
/// public function panics on any input" and "nothing wraps silently". A wider texel can only
/// have a larger bound, so the value must not shrink.
#[test]
fn finding_error_bounds_wrap_for_wide_texels() {
    for b in [17u32, 62, 63, 64, 100, u32::MAX] {
        for (name, f) in [
            (
                "rip arithmetic",
                rip::arithmetic_error_bound as fn(u32) -> u64,
            ),
            ("dip arithmetic", dip::arithmetic_error_bound),
            ("rip level", rip::level_selection_error_bound),
            ("dip level", dip::level_selection_error_bound),
        ] {
            let got = catch_unwind(|| f(b));
            let at16 = f(16);
            assert!(
                matches!(got, Ok(v) if v >= at16),
                "{name}({b}): {got:?} (bound for 16 bits: {at16})"
            );
        }
    }
}

/// `Tally` adds without a check: a caller feeding it large counts panics in debug and wraps in
/// release.
#[test]
fn finding_tally_overflow() {
    use texsat::Counter;
    let got = catch_unwind(|| {
        let mut t = Tally::new();
        for _ in 0..3 {
            t.reads(u32::MAX, u32::MAX);
        }
        t
    });
    assert!(
        matches!(got, Ok(t) if t.bits_read >= u64::from(u32::MAX) * u64::from(u32::MAX)),
        "{got:?}"
    );
}

/// `Sat::from_table` checks each implied texel as `S(x,y) + S(x-1,y-1) - S(x,y-1)` in the entry
/// word and treats an overflow of that sum as "not a SAT"; but a valid SAT can have
/// `S(x,y) + S(x-1,y-1)` above the word (here 60 000 + 30 000 in `u16`). The table below is
/// what `Sat::build_checked` itself writes for the 2 x 2 texture [30000, 0; 0, 30000].
#[test]
fn finding_from_table_refuses_valid_tables_near_the_word() {
    let texels = [30000u16, 0, 0, 30000];
    let tex = Texture::<u16>::new(&texels, 2, 2).expect("tex");
    let mut st = [0u16; 4];
    Sat::build_checked(&tex, &mut st).expect("fits u16");
    assert_eq!(st, [30000, 30000, 30000, 60000]);
    assert!(
        Sat::<u16>::from_table(&st, 2, 2, 16).is_ok(),
        "{:?}",
        Sat::<u16>::from_table(&st, 2, 2, 16).map(|s| s.total())
    );
}

/// `Plan::for_scene` sizes a flat table for a texture wider than any table accepts: the plan's
/// table cannot be built (`Sat::entries_needed` refuses the width). A flat candidate should be
/// rejected (`RejectReason::Refused(TextureTooLarge)`) like the packed, tiled and modular ones,
/// leaving `NoPlan`.
#[test]
fn finding_plan_for_a_texture_past_the_side_limit() {
    let facts = SceneFacts::new(MAX_SIDE + 1, 1, 8, 0, EdgeKind::Border);
    assert_eq!(
        Sat::<u64, 1>::entries_needed(MAX_SIDE + 1, 1),
        Err(Error::TextureTooLarge {
            dimension: MAX_SIDE + 1
        })
    );
    assert_eq!(
        Plan::for_scene(&facts).map(|p| p.layout()),
        Err(Error::NoPlan)
    );
}

/// `Plan::for_scene` documents its refusals (EmptyTexture, InvalidTexelBits,
/// FracBitsUnsupported, InvertedBox, NoSuchChannel, ZeroArea for a zero largest box, NoPlan).
/// (A finding of the catalogue: `ZeroArea` was not documented; it is now.)
#[test]
fn finding_plan_zero_box_error_undocumented() {
    let facts = SceneFacts {
        min_box: [0, 0],
        max_box: [0, 0],
        ..SceneFacts::new(4, 4, 8, 0, EdgeKind::Border)
    };
    let got = Plan::for_scene(&facts).map(|_| ());
    assert!(
        matches!(
            got,
            Ok(())
                | Err(Error::EmptyTexture
                    | Error::InvalidTexelBits { .. }
                    | Error::FracBitsUnsupported { .. }
                    | Error::InvertedBox
                    | Error::NoSuchChannel
                    | Error::ZeroArea
                    | Error::NoPlan)
        ),
        "{got:?}"
    );
}

/// `EdgeKind::texel_index` documents `None` only for Border outside the texture and an empty
/// axis; it also answers `None` for any axis longer than `i64::MAX / 2` (64-bit targets).
#[test]
fn finding_texel_index_long_axis() {
    let n = 1usize << 62;
    for kind in MODES {
        assert_eq!(kind.texel_index(0, n), Some(0), "{kind:?}");
    }
}

/// A mean of 0 fits every word, but the `u128` word (tables of `u64`) refuses it for 128
/// output bits and more ("Refuses a result that does not fit the word"); the `u64` word
/// answers 0 (see `means_of_hostile_boxes`).
#[test]
fn finding_u128_mean_of_zero() {
    let texels = [9u8; 4];
    let tex = Texture::<u8>::new(&texels, 2, 2).expect("tex");
    let mut st = [0u64; 4];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    let zero = sat
        .box_sum_raw(
            &raw([5, 0, 7, 2]),
            FracBits::ZERO,
            Stable,
            Border,
            &mut NoCount,
        )
        .expect("outside");
    for g in [128u32, 200, u32::MAX] {
        assert_eq!(zero.mean_rounded(0, g, &mut NoCount), Ok(0), "g = {g}");
    }
}

/// `Error::TooWide` carries "bits the worst case (or the actual data) needs", and, where that
/// number leaves 64-bit arithmetic, 65 as a documented lower bound (a finding of the catalogue:
/// the floor was not documented). Here the sum needs 82 bits and the modular bound 72.
#[test]
fn finding_bits_needed_floors_at_65() {
    let texels = [255u8; 4];
    let tex = Texture::<u8>::new(&texels, 2, 2).expect("tex");
    let mut st = [0u32; 4];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    let r = [0, 0, 2 << 36, 2 << 36];
    let sum_bits = bits(255 * (1u128 << 37) * (1u128 << 37));
    assert_eq!(sum_bits, 82);
    assert_eq!(
        lookup(
            &sat,
            r,
            0,
            FormKind::Stable,
            EdgeKind::Repeat,
            &mut Tally::new()
        ),
        Err(Error::TooWide {
            what: Quantity::LookupAccumulator,
            // Documented (Error::TooWide): past 64-bit arithmetic, 65, a lower bound.
            bits_needed: 65,
            bits_available: 64
        }),
        "split path"
    );
    let mut words = vec![0u32; Modular::<u32>::words_needed(2, 2, 16).expect("words")];
    let m = Modular::<u32>::build(&tex, 16, &mut words, &mut [0u32; 2]).expect("modular");
    let r = [i64::MIN, 0, i64::MAX, 1];
    let bound_bits = bits(255 * cells(r, 0));
    assert_eq!(bound_bits, 72);
    assert_eq!(
        lookup(
            &m,
            r,
            0,
            FormKind::Stable,
            EdgeKind::Repeat,
            &mut Tally::new()
        ),
        Err(Error::TooWide {
            what: Quantity::ModularBox,
            bits_needed: 65,
            bits_available: 16
        }),
        "modular bound"
    );
}

/// docs/design.md: a corrupt lent layout gives "a wrong sum or CorruptStorage, never a panic".
/// On the split path (a box crossing the edge under Clamp, Repeat or Mirror) garbage pieces times
/// their multiplicities can leave the result word: `TooWide { LookupAccumulator }`, where the
/// valid layout answers. A typed error, not a panic, but not one the docs list for this case.
#[test]
fn finding_corrupt_storage_too_wide() {
    // docs/design.md now lists TooWide { LookupAccumulator } on the split path.
    let failures = corrupt_lent_layouts(true);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `Layout::corner` (and `quad`, `cell_corners`) on the flat table, far outside `[0, w] x [0, h]`:
/// the tiled and modular layouts document "corners outside read nothing and give 0", `Sat`'s
/// reader says "an index outside would read as zero", and no public function may panic. The
/// flat table's index `((y - 1) w + (x - 1)) C` overflows instead: a panic in debug; in release
/// it wraps, and `x = 2^63 + 1` with two channels reads entry 0, `S(1, 1)`, not 0.
#[test]
fn finding_flat_layout_corner_far_outside() {
    use texsat::Layout;
    let t = [1u8, 2, 3, 4, 5, 6];
    let tex = Texture::<u8, 2>::new(&t, 3, 1).expect("tex");
    let mut st = [0u32; 6];
    let sat = Sat::build(&tex, &mut st).expect("sat");
    let zero = [[0u32; 2]; 4];
    for (x, y) in [
        ((1usize << 63) + 1, 1usize),
        (usize::MAX, 1),
        (1, usize::MAX),
        (usize::MAX, usize::MAX),
    ] {
        let corner = catch_unwind(|| Layout::corner(&sat, x, y, &mut NoCount));
        assert_eq!(corner.ok(), Some([0, 0]), "corner({x}, {y})");
        let quad = catch_unwind(|| Layout::quad(&sat, x, x, y, y, &mut NoCount));
        assert_eq!(quad.ok(), Some(zero), "quad({x}, {y})");
        let cell = catch_unwind(|| Layout::cell_corners(&sat, x, y, &mut NoCount));
        assert_eq!(cell.ok(), Some(zero), "cell_corners({x}, {y})");
    }
}
