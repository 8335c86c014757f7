//! Every lookup form and boundary mode on the flat table against the exact reference.
//!
//! A small texture (up to 16 x 16, 1 or 3 channels, `u8` or `u16` texels) is built into a
//! `u16`, `u32` or `u64` table (`Sat::build_checked`, so `u16` tables of wide texels occur
//! where their actual sums fit); then up to four queries, each through `box_sum_int`,
//! `box_sum_raw` (`FormKind::{Paper, Stable}`, `F` 0..=24), `box_sum` (five `fixed` corner
//! types, one with `F = 32`) or the shortcut (`box_mean_shortcut_raw`, `box_mean_shortcut`),
//! under `EdgeKind` and again under the zero-sized mode and form (and, under Repeat, with
//! `RepeatWithinPeriod`: Repeat's answer and counted costs for a box at most a period long, a
//! refusal for a longer one), with `mean_rounded` and `means_rounded`; and `box_sum_inside`. Every answer must be the exact integral of the extended
//! texture (`texsat_fuzz::box_integral`), the exactly rounded mean, or a refusal the
//! documentation allows for that input.
#![no_main]

use arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use texsat::{Entry, Error, Rect, Sat, Texel, Texture};
use texsat_fuzz::{acc_value_bits, run_query, Facts, Query, Tex};

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = run(&mut u);
});

fn run(u: &mut Unstructured<'_>) -> Result<()> {
    let e = u.int_in_range(0u8..=2)?;
    let wide = u.arbitrary::<bool>()?;
    let three = u.arbitrary::<bool>()?;
    match (e, wide, three) {
        (0, false, false) => check::<u16, u8, 1>(u),
        (0, false, true) => check::<u16, u8, 3>(u),
        (0, true, false) => check::<u16, u16, 1>(u),
        (0, true, true) => check::<u16, u16, 3>(u),
        (1, false, false) => check::<u32, u8, 1>(u),
        (1, false, true) => check::<u32, u8, 3>(u),
        (1, true, false) => check::<u32, u16, 1>(u),
        (1, true, true) => check::<u32, u16, 3>(u),
        (_, false, false) => check::<u64, u8, 1>(u),
        (_, false, true) => check::<u64, u8, 3>(u),
        (_, true, false) => check::<u64, u16, 1>(u),
        (_, true, true) => check::<u64, u16, 3>(u),
    }
}

fn check<E: Entry, T: Texel, const C: usize>(u: &mut Unstructured<'_>) -> Result<()> {
    let tex = Tex::gen(u, C, T::BITS, 16, 16)?;
    let texels: Vec<T> = tex.t.iter().map(|&v| T::from_u16_clamped(v)).collect();
    let texture = Texture::<T, C>::new(&texels, tex.w, tex.h).expect("valid texture");
    let mut storage = vec![E::ZERO; tex.w * tex.h * C];
    let Ok(sat) = Sat::build_checked(&texture, &mut storage) else {
        // The actual sums do not fit E (the build target checks that refusal).
        return Ok(());
    };
    let facts = Facts {
        texel_bits: T::BITS,
        value_bits: tex.total_bits(),
        entry_bits: E::BITS,
        modulus: None,
        reads_per_corner: 1,
    };
    assert_eq!(
        texsat::Layout::value_bits(&sat),
        facts.value_bits,
        "value bits"
    );
    assert!(acc_value_bits(E::BITS) > 0);
    for _ in 0..u.int_in_range(1..=4)? {
        let q = Query::gen(u, tex.w, tex.h, C, T::BITS)?;
        let _ = run_query(&sat, &facts, &tex, &q);
    }
    // box_sum_inside: integer corners inside [0, w] x [0, h], the sum in the entry word.
    let mut c = || -> Result<u32> {
        Ok(if u.ratio(1u8, 8)? {
            u.arbitrary()?
        } else {
            u.int_in_range(0..=18)?
        })
    };
    let r = [c()?, c()?, c()?, c()?];
    let got = sat.box_sum_inside(&Rect::new(r[0], r[1], r[2], r[3]));
    let inside = r[0] <= r[2] && r[1] <= r[3] && r[2] as usize <= tex.w && r[3] as usize <= tex.h;
    if inside {
        let want = texsat_fuzz::box_integral(&tex, texsat_fuzz::Mode::Border, r.map(i64::from), 0);
        let got = got.unwrap_or_else(|e| panic!("box_sum_inside {r:?}: {e:?}"));
        let got: Vec<Option<u128>> = got.iter().map(|v| Some(v.to_u128())).collect();
        assert_eq!(got, want, "box_sum_inside {r:?}");
    } else {
        assert!(
            matches!(got, Err(Error::CoordinateOutOfRange)),
            "box_sum_inside {r:?}: {:?}",
            got.map(|v| v.map(|e| e.to_u128()))
        );
    }
    Ok(())
}
