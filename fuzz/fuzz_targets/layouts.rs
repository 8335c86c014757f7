//! Every layout against the flat table and the exact reference: `Tiled` (no levels = the packed
//! flat table, one level of tiles, tiles within tiles, rectangular and non-power-of-two blocks,
//! with and without a modulus) and `Modular`, built with `Tiled::build` / `TiledBuilder` and
//! `Modular::build` / `ModularBuilder` from small textures.
//!
//! Checked: the build's verdict (exactly the documented refusal, or a layout); every corner
//! `S(x, y)` (modulo `2^k` where there is a modulus) against the `u128` table; the same layout
//! re-wrapped with `from_words` reads the same; and up to four queries of every lookup form and
//! mode, each answered by the layout and by the flat `Sat`: each answer must be exact or an
//! allowed refusal (`texsat_fuzz::run_query`), and where both answer they must agree.
#![no_main]

use arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use texsat::layouts::{AxisLevels, Modular, ModularBuilder, Tiled, TiledBuilder, TiledSpec};
use texsat::{Entry, Error, Layout, NoCount, Quantity, Sat, Texel, Texture};
use texsat_fuzz::{max_texel, run_query, worst_case_bits, Facts, Query, Tex};

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = run(&mut u);
});

fn run(u: &mut Unstructured<'_>) -> Result<()> {
    let e = u.int_in_range(0u8..=2)?;
    let wide = u.arbitrary::<bool>()?;
    let two = u.arbitrary::<bool>()?;
    match (e, wide, two) {
        (0, false, false) => check::<u16, u8, 1>(u),
        (0, false, true) => check::<u16, u8, 2>(u),
        (0, true, false) => check::<u16, u16, 1>(u),
        (0, true, true) => check::<u16, u16, 2>(u),
        (1, false, false) => check::<u32, u8, 1>(u),
        (1, false, true) => check::<u32, u8, 2>(u),
        (1, true, false) => check::<u32, u16, 1>(u),
        (1, true, true) => check::<u32, u16, 2>(u),
        (_, false, false) => check::<u64, u8, 1>(u),
        (_, false, true) => check::<u64, u8, 2>(u),
        (_, true, false) => check::<u64, u16, 1>(u),
        (_, true, true) => check::<u64, u16, 2>(u),
    }
}

/// Block sizes for one axis: none, or up to three levels, each a multiple of the one before
/// (one time in sixteen an arbitrary, possibly invalid, list).
fn blocks(u: &mut Unstructured<'_>) -> Result<Vec<u32>> {
    if u.ratio(1u8, 16)? {
        let n = u.int_in_range(0..=5)?;
        return (0..n).map(|_| u.int_in_range(0..=20)).collect();
    }
    let mut out = Vec::new();
    let mut b = 1u32;
    for _ in 0..u.int_in_range(0..=3)? {
        b *= *u.choose(&[2u32, 2, 3, 4, 8])?;
        out.push(b);
    }
    Ok(out)
}

/// The valid levels of `b`, as the reference sees them.
fn valid_levels(b: &[u32]) -> bool {
    let mut prev = 1;
    b.len() <= 4
        && b.iter().all(|&v| {
            let ok = v >= 2 && v > prev && v % prev == 0;
            prev = v;
            ok
        })
}

fn check<E: Entry + std::fmt::Debug, T: Texel, const C: usize>(
    u: &mut Unstructured<'_>,
) -> Result<()> {
    let tex = Tex::gen(u, C, T::BITS, 16, 16)?;
    let (w, h) = (tex.w, tex.h);
    let texels: Vec<T> = tex.t.iter().map(|&v| T::from_u16_clamped(v)).collect();
    let texture = Texture::<T, C>::new(&texels, w, h).expect("valid texture");
    let reference = tex.sat();

    // The flat table to compare with (only if the actual sums fit E).
    let mut flat_store = vec![E::ZERO; w * h * C];
    let flat = Sat::build_checked(&texture, &mut flat_store).ok();
    let flat_facts = Facts {
        texel_bits: T::BITS,
        value_bits: tex.total_bits(),
        entry_bits: E::BITS,
        modulus: None,
        reads_per_corner: 1,
    };

    // Texel bits the layout is told (the builder path may state more than T has).
    let tb = if u.ratio(1u8, 4)? {
        u.int_in_range(T::BITS..=16)?
    } else {
        T::BITS
    };
    let modular = u.arbitrary::<bool>()?;
    let k_of = |u: &mut Unstructured<'_>| -> Result<u32> {
        Ok(match u.int_in_range(0u8..=7)? {
            0 => u.int_in_range(0..=70)?,
            1 => E::BITS,
            _ => {
                // Large enough for some boxes: k for boxes of up to A texels.
                let a = u.int_in_range(1u64..=64)?;
                Modular::<E, C>::bits_for_max_area(tb, a)
            }
        })
    };

    if modular {
        let k = k_of(u)?;
        let valid_k = k >= tb && k <= E::BITS && k >= 1;
        let words_needed = Modular::<E, C>::words_needed(w, h, k);
        if !(1..=E::BITS).contains(&k) {
            assert_eq!(words_needed, Err(Error::InvalidModulus { bits: k }));
        } else {
            let bits = (w * h * C) as u64 * u64::from(k);
            assert_eq!(words_needed, Ok(bits.div_ceil(32) as usize));
        }
        let nw = words_needed.unwrap_or(0);
        let short = u.ratio(1u8, 16)?;
        let mut words = vec![0u32; if short { nw.saturating_sub(1) } else { nw }];
        let mut row = vec![E::ZERO; w * C];
        let got = if tb == T::BITS && u.arbitrary()? {
            Modular::<E, C>::build(&texture, k, &mut words, &mut row)
        } else {
            ModularBuilder::<E, C>::new(w, h, tb, k, &mut words, &mut row).and_then(|mut b| {
                for y in 0..h {
                    b.push_row(texture.row(y).expect("row"))?;
                }
                b.finish()
            })
        };
        let m = match got {
            Err(e) => {
                let want = if !valid_k {
                    Error::InvalidModulus { bits: k }
                } else {
                    Error::StorageTooSmall {
                        needed: nw,
                        got: nw.saturating_sub(1),
                    }
                };
                assert_eq!(e, want, "Modular build (k = {k}, tb = {tb})");
                return Ok(());
            }
            Ok(m) => m,
        };
        assert!(
            valid_k && !short,
            "Modular built with k = {k}, short = {short}"
        );
        assert_eq!(
            m.max_exact_area(),
            ((1u128 << k) - 1) as u64 / max_texel(tb)
        );
        let facts = Facts {
            texel_bits: tb,
            value_bits: k,
            entry_bits: E::BITS,
            modulus: Some(k),
            reads_per_corner: 1,
        };
        check_layout(&m, &facts, &tex, &reference, Some(k));
        let again = Modular::<E, C>::from_words(m.words(), w, h, tb, k).expect("from_words");
        check_same_corners(&m, &again);
        compare(u, &m, &facts, flat.as_ref(), &flat_facts, &tex)
    } else {
        let (bx, by) = (blocks(u)?, blocks(u)?);
        let spec_x = AxisLevels::new(&bx);
        let spec_y = AxisLevels::new(&by);
        assert_eq!(spec_x.is_ok(), valid_levels(&bx), "AxisLevels::new({bx:?})");
        assert_eq!(spec_y.is_ok(), valid_levels(&by), "AxisLevels::new({by:?})");
        let (Ok(x), Ok(y)) = (spec_x, spec_y) else {
            assert_eq!(spec_x.err().or(spec_y.err()), Some(Error::InvalidLevels));
            return Ok(());
        };
        let mut spec = TiledSpec {
            x,
            y,
            modulus: None,
        };
        if u.ratio(1u8, 3)? {
            spec = spec.with_modulus(k_of(u)?);
        }
        let worst = worst_case_bits(tb, w, h);
        // The refusals, in the order the layout checks them.
        let want_err = match spec.modulus {
            Some(k) if k < tb || k == 0 || k > 64 => Some(Error::InvalidModulus { bits: k }),
            Some(k) if k > E::BITS => Some(Error::InvalidModulus { bits: k }),
            None if worst > E::BITS => Some(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: worst,
                bits_available: E::BITS,
            }),
            _ => None,
        };
        let nw = Tiled::<E, C>::words_needed(spec, w, h, tb);
        let scratch_n = Tiled::<E, C>::scratch_needed(spec, w).expect("small scratch");
        assert_eq!(scratch_n, (w + 1) * C * (by.len() + 2), "scratch_needed");
        let nw = match nw {
            Ok(n) => n,
            Err(e) => {
                assert!(
                    matches!(e, Error::InvalidModulus { .. }),
                    "words_needed: {e:?}"
                );
                assert_eq!(Some(e), want_err);
                return Ok(());
            }
        };
        let short = u.ratio(1u8, 16)?;
        let mut words = vec![0u32; if short { nw.saturating_sub(1) } else { nw }];
        let mut scratch = vec![E::ZERO; scratch_n];
        let got = if tb == T::BITS && u.arbitrary()? {
            Tiled::<E, C>::build(&texture, spec, &mut words, &mut scratch)
        } else {
            TiledBuilder::<E, C>::new(spec, w, h, tb, &mut words, &mut scratch).and_then(|mut b| {
                for y in 0..h {
                    b.push_row(texture.row(y).expect("row"))?;
                }
                b.finish()
            })
        };
        let t = match (got, want_err) {
            (Err(e), Some(want)) => {
                assert_eq!(e, want, "Tiled build {spec:?}");
                return Ok(());
            }
            (Err(e), None) => {
                assert!(short, "Tiled build {spec:?} refused: {e:?}");
                assert_eq!(
                    e,
                    Error::StorageTooSmall {
                        needed: nw,
                        got: nw - 1
                    }
                );
                return Ok(());
            }
            (Ok(_), Some(want)) => panic!("Tiled build {spec:?} accepted, want {want:?}"),
            (Ok(t), None) => {
                assert!(!short, "Tiled built into short storage");
                t
            }
        };
        assert!(t.storage_bits() <= nw as u64 * 32, "storage bits");
        let facts = Facts {
            texel_bits: tb,
            value_bits: spec.modulus.unwrap_or(worst),
            entry_bits: E::BITS,
            modulus: spec.modulus,
            reads_per_corner: (bx.len() as u64 + 1) * (by.len() as u64 + 1),
        };
        check_layout(&t, &facts, &tex, &reference, spec.modulus);
        let again = Tiled::<E, C>::from_words(t.words(), spec, w, h, tb).expect("from_words");
        check_same_corners(&t, &again);
        compare(u, &t, &facts, flat.as_ref(), &flat_facts, &tex)
    }
}

/// Every corner (and a ring outside, which reads 0) against the `u128` table, modulo `2^k`.
fn check_layout<L: Layout<C>, const C: usize>(
    l: &L,
    facts: &Facts,
    tex: &Tex,
    reference: &[u128],
    modulus: Option<u32>,
) {
    let (w, h) = (tex.w, tex.h);
    assert_eq!((l.width(), l.height()), (w, h));
    assert_eq!(l.texel_bits(), facts.texel_bits);
    assert_eq!(l.value_bits(), facts.value_bits, "value_bits");
    assert_eq!(l.modulus(), modulus);
    let m = modulus.map_or(u128::MAX, |k| (1u128 << k) - 1);
    for y in 0..=h + 1 {
        for x in 0..=w + 1 {
            let got = l.corner(x, y, &mut NoCount);
            for (ch, v) in got.iter().enumerate() {
                let want = if x == 0 || y == 0 || x > w || y > h {
                    0
                } else {
                    reference[((y - 1) * w + x - 1) * C + ch] & m
                };
                assert_eq!(v.to_u128(), want, "corner({x}, {y}), channel {ch}");
            }
        }
    }
}

fn check_same_corners<L: Layout<C>, const C: usize>(a: &L, b: &L) {
    for y in 0..=a.height() {
        for x in 0..=a.width() {
            let (p, q) = (a.corner(x, y, &mut NoCount), b.corner(x, y, &mut NoCount));
            assert!(
                p.iter()
                    .zip(q.iter())
                    .all(|(p, q)| p.to_u128() == q.to_u128()),
                "from_words reads differently at ({x}, {y})"
            );
        }
    }
}

/// Up to four queries on the layout and on the flat table: each checked against the reference,
/// and equal where both answer.
fn compare<L: Layout<C> + texsat::BoxLookup<C>, E: Entry, const C: usize>(
    u: &mut Unstructured<'_>,
    l: &L,
    facts: &Facts,
    flat: Option<&Sat<'_, E, C>>,
    flat_facts: &Facts,
    tex: &Tex,
) -> Result<()>
where
    texsat::WideOf<L, C>: Into<u128> + std::fmt::Debug,
{
    for _ in 0..u.int_in_range(1..=4)? {
        let q = Query::gen(u, tex.w, tex.h, C, facts.texel_bits)?;
        let a = run_query(l, facts, tex, &q);
        if let Some(flat) = flat {
            let b = run_query(flat, flat_facts, tex, &q);
            if let (Ok(a), Ok(b)) = (&a, &b) {
                assert_eq!(a.0, b.0, "{q:?}: layout and flat table disagree");
                if let (Ok(x), Ok(y)) = (&a.1, &b.1) {
                    assert_eq!(x, y, "{q:?}: means disagree");
                }
            }
        }
    }
    Ok(())
}
