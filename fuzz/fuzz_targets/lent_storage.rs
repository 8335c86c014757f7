//! Lent storage: tables and layouts wrapped around words the caller supplies (flash, an RTL dump,
//! a corrupted copy), `Sat::from_table`, `Tiled::from_words` and `Modular::from_words`.
//!
//! The words are a built table or layout with a few words changed, or arbitrary words. Then:
//!
//! * `Sat::from_table` validates, so it must accept exactly the tables that are the SAT of some
//!   texture (`texsat_fuzz::from_table_verdict`), and an accepted table must answer every lookup
//!   exactly for the texture it implies;
//! * `Tiled::from_words` and `Modular::from_words` do not validate the content: every corner and
//!   every lookup form, mode and mean must return a value or a typed error, never panic (and an
//!   unchanged layout is exact: the `layouts` target checks that).
#![no_main]

use arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use texsat::layouts::{AxisLevels, Modular, Tiled, TiledSpec};
use texsat::{
    BoxLookup, EdgeKind, Entry, FormKind, FracBits, NoCount, Rect, Sat, Shortcut, Tally, Texture,
};
use texsat_fuzz::{from_table_verdict, raw_box, run_query, texels_of_table, Facts, Query, Tex};

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = run(&mut u);
});

fn run(u: &mut Unstructured<'_>) -> Result<()> {
    let e = u.int_in_range(0u8..=2)?;
    let two = u.arbitrary::<bool>()?;
    match (e, two) {
        (0, false) => check::<u16, 1>(u),
        (0, true) => check::<u16, 2>(u),
        (1, false) => check::<u32, 1>(u),
        (1, true) => check::<u32, 2>(u),
        (_, false) => check::<u64, 1>(u),
        (_, true) => check::<u64, 2>(u),
    }
}

/// Changes one to four words: off by one, a flipped bit, or an arbitrary value.
fn corrupt<W: Copy>(
    u: &mut Unstructured<'_>,
    words: &mut [W],
    to: impl Fn(u64) -> W,
    from: impl Fn(W) -> u64,
    bits: u32,
) -> Result<()> {
    if words.is_empty() {
        return Ok(());
    }
    for _ in 0..u.int_in_range(1..=4)? {
        let i = u.int_in_range(0..=words.len() - 1)?;
        let v = from(words[i]);
        words[i] = to(match u.int_in_range(0u8..=3)? {
            0 => v.wrapping_add(1),
            1 => v.wrapping_sub(1),
            2 => v ^ (1 << u.int_in_range(0..=bits - 1)?),
            _ => u.arbitrary()?,
        });
    }
    Ok(())
}

fn check<E: Entry + std::fmt::Debug, const C: usize>(u: &mut Unstructured<'_>) -> Result<()> {
    let bits = u.int_in_range(1..=16)?;
    let arbitrary_words = u.ratio(1u8, 4)?;
    // Arbitrary words only have a chance to be a valid table when the texture is tiny.
    let max_side = if arbitrary_words { 3 } else { 12 };
    let tex = Tex::gen(u, C, bits, max_side, max_side)?;
    let (w, h) = (tex.w, tex.h);
    match u.int_in_range(0u8..=2)? {
        0 => {
            // Sat::from_table.
            let e_max = u128::from(u64::MAX) >> (64 - E::BITS);
            let mut table: Vec<E> = if arbitrary_words {
                (0..w * h * C)
                    .map(|_| u.arbitrary::<u64>().map(E::from_u64_truncating))
                    .collect::<Result<_>>()?
            } else {
                let reference = tex.sat();
                if reference.iter().any(|&v| v > e_max) {
                    return Ok(());
                }
                reference
                    .iter()
                    .map(|&v| E::from_u64_truncating(v as u64))
                    .collect()
            };
            if !arbitrary_words {
                corrupt(
                    u,
                    &mut table,
                    E::from_u64_truncating,
                    |e| e.to_u64(),
                    E::BITS,
                )?;
            }
            let t128: Vec<u128> = table.iter().map(|e| e.to_u128()).collect();
            let got = Sat::<E, C>::from_table(&table, w, h, bits);
            let want = from_table_verdict(&t128, w, h, C, bits);
            assert_eq!(
                got.map(|s| s.entries().iter().map(|e| e.to_u128()).collect::<Vec<_>>()),
                want,
                "from_table"
            );
            let Ok(sat) = got else { return Ok(()) };
            // Accepted: it is the table of the texture it implies, and answers exactly for it.
            let implied = texels_of_table(&t128, w, h, C, bits);
            let facts = Facts {
                texel_bits: bits,
                value_bits: implied.total_bits(),
                entry_bits: E::BITS,
                modulus: None,
                reads_per_corner: 1,
            };
            for _ in 0..u.int_in_range(1..=3)? {
                let q = Query::gen(u, w, h, C, bits)?;
                let _ = run_query(&sat, &facts, &implied, &q);
            }
        }
        1 => {
            // Tiled::from_words.
            let levels = |u: &mut Unstructured<'_>| -> Result<AxisLevels> {
                let b = *u.choose(&[&[][..], &[2], &[4], &[3], &[2, 4], &[2, 6, 12], &[8]])?;
                Ok(AxisLevels::new(b).expect("valid levels"))
            };
            let mut spec = TiledSpec {
                x: levels(u)?,
                y: levels(u)?,
                modulus: None,
            };
            if u.ratio(1u8, 3)? {
                spec = spec.with_modulus(u.int_in_range(bits..=E::BITS)?);
            }
            let Ok(nw) = Tiled::<E, C>::words_needed(spec, w, h, bits) else {
                return Ok(());
            };
            let words = lent_words(u, nw, |words| {
                let texels: Vec<u16> = tex.t.clone();
                let texture = Texture::<u16, C>::new(&texels, w, h).expect("texture");
                let mut scratch =
                    vec![E::ZERO; Tiled::<E, C>::scratch_needed(spec, w).expect("scratch")];
                // Built with the texel width stated as `bits` (u16 texels below 2^bits).
                let mut b = texsat::layouts::TiledBuilder::<E, C>::new(
                    spec,
                    w,
                    h,
                    bits,
                    words,
                    &mut scratch,
                )
                .ok()?;
                for y in 0..h {
                    b.push_row(texture.row(y)?).ok()?;
                }
                b.finish().ok().map(|_| ())
            })?;
            let Some(words) = words else { return Ok(()) };
            let Ok(t) = Tiled::<E, C>::from_words(&words, spec, w, h, bits) else {
                return Ok(());
            };
            exercise(u, &t)?;
        }
        _ => {
            // Modular::from_words.
            let k = u.int_in_range(bits..=E::BITS)?;
            let Ok(nw) = Modular::<E, C>::words_needed(w, h, k) else {
                return Ok(());
            };
            let words = lent_words(u, nw, |words| {
                let texture = Texture::<u16, C>::new(&tex.t, w, h).expect("texture");
                let mut row = vec![E::ZERO; w * C];
                let mut b =
                    texsat::layouts::ModularBuilder::<E, C>::new(w, h, bits, k, words, &mut row)
                        .ok()?;
                for y in 0..h {
                    b.push_row(texture.row(y)?).ok()?;
                }
                b.finish().ok().map(|_| ())
            })?;
            let Some(words) = words else { return Ok(()) };
            let Ok(m) = Modular::<E, C>::from_words(&words, w, h, bits, k) else {
                return Ok(());
            };
            exercise(u, &m)?;
        }
    }
    Ok(())
}

/// `nw` words (sometimes a few more): arbitrary, or built by `build` and then corrupted.
fn lent_words(
    u: &mut Unstructured<'_>,
    nw: usize,
    build: impl FnOnce(&mut [u32]) -> Option<()>,
) -> Result<Option<Vec<u32>>> {
    let mut words = vec![0u32; nw + u.int_in_range(0..=2)?];
    if u.ratio(1u8, 4)? {
        for v in words.iter_mut() {
            *v = u.arbitrary()?;
        }
    } else {
        if build(&mut words).is_none() {
            return Ok(None);
        }
        corrupt(u, &mut words, |v| v as u32, u64::from, 32)?;
    }
    Ok(Some(words))
}

/// Every corner and up to four lookups of every kind on a layout over corrupted words: any
/// value or typed error, but no panic (libFuzzer reports one as a crash).
fn exercise<L: BoxLookup<C>, const C: usize>(u: &mut Unstructured<'_>, l: &L) -> Result<()> {
    let (w, h) = (l.width(), l.height());
    for y in 0..=h + 1 {
        for x in 0..=w + 1 {
            let _ = l.corner(x, y, &mut NoCount);
        }
    }
    for _ in 0..u.int_in_range(1..=4)? {
        let mode = *u.choose(&EdgeKind::ALL)?;
        let form = if u.arbitrary()? {
            FormKind::Paper
        } else {
            FormKind::Stable
        };
        let f = u.int_in_range(0..=24)?;
        let r = raw_box(u, w, h, f)?;
        let rect = Rect::new(r[0], r[1], r[2], r[3]);
        let fb = FracBits::new(f).expect("F <= 24");
        let mut k = Tally::new();
        let g = u.int_in_range(0..=70)?;
        match u.int_in_range(0u8..=2)? {
            0 => {
                let n = |v: i64| v.clamp(i32::MIN.into(), i32::MAX.into()) as i32;
                let ri = Rect::new(n(r[0]), n(r[1]), n(r[2]), n(r[3]));
                if let Ok(s) = l.box_sum_int(&ri, mode, &mut k) {
                    let _ = s.means_rounded(g, &mut k);
                }
            }
            1 => {
                if let Ok(s) = l.box_sum_raw(&rect, fb, form, mode, &mut k) {
                    let _ = s.means_rounded(g, &mut k);
                    let _ = s.mean_rounded(u.int_in_range(0..=C)?, g, &mut k);
                }
            }
            _ => {
                let s = Shortcut::with_min_side(u.int_in_range(0..=8)?);
                let _ = l.box_mean_shortcut_raw(&rect, fb, form, mode, &s, g, &mut k);
            }
        }
    }
    Ok(())
}
