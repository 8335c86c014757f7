//! The run-time entry points (`F` as a checked [`FracBits`] value, raw `i64` corners, the mode as
//! [`EdgeKind`], the form as [`FormKind`]) against the `fixed`-typed, zero-sized-mode ones they
//! wrap: for every filter and the box lookups, the same result (or the same error) and the same
//! counted costs, for random textures and boxes at `F` = 0, 4, 8 and 16, in every mode.
//!
//! One compiled sampler per filter serves every `F` this way (the `sat` CLI relies on it), so
//! these tests are what ties it to the typed API that the other host tests check against the
//! references.

use fixed::traits::Fixed;
use fixed::types::{I48F16, I56F8, I60F4, I64F0};
use proptest::prelude::*;
use texsat::filters::dip::{DipFilter, DipMap};
use texsat::filters::mip::MipPyramid;
use texsat::filters::point::{point, point_raw};
use texsat::filters::rip::RipMap;
use texsat::filters::tent::{TentLines, TentTable};
use texsat::filters::variance::{storage_needed as variance_storage, VarianceTables};
use texsat::{
    Border, ClampToEdge, Coord, EdgeKind, EdgeMode, Error, FormKind, FracBits, MirroredRepeat,
    Paper, Rect, Repeat, Sat, Stable, Tally, Texture,
};

/// A texture; [`Structures::check`] builds every structure for it and checks one box at one `F`
/// in every mode.
#[derive(Debug)]
struct Structures {
    w: usize,
    h: usize,
    texels: Vec<u8>,
}

/// One result and its costs, comparable across the two APIs.
type Outcome<T> = (Result<T, Error>, Tally);

fn run<T>(f: impl FnOnce(&mut Tally) -> Result<T, Error>) -> Outcome<T> {
    let mut k = Tally::new();
    let r = f(&mut k);
    (r, k)
}

impl Structures {
    fn check<X: Coord + Fixed<Bits = i64>>(&self, raw: [i64; 4]) {
        let tex = Texture::<u8>::new(&self.texels, self.w, self.h).unwrap();
        let fb = FracBits::new(X::FRAC_BITS).unwrap();
        let typed = Rect::new(
            X::from_bits(raw[0]),
            X::from_bits(raw[1]),
            X::from_bits(raw[2]),
            X::from_bits(raw[3]),
        );
        let rr = typed.to_raw();
        assert_eq!(rr, Rect::new(raw[0], raw[1], raw[2], raw[3]));

        let mut table = vec![0u32; Sat::<u32>::entries_needed(self.w, self.h).unwrap()];
        let sat = Sat::build(&tex, &mut table).unwrap();
        let mut mip_st = vec![0u8; MipPyramid::<u8>::storage_needed(self.w, self.h).unwrap()];
        let mip = MipPyramid::build(&tex, &mut mip_st).unwrap();
        let mut rip_st = vec![0u8; RipMap::<u8, 1>::storage_needed(self.w, self.h)];
        let rip = RipMap::build(&tex, &mut rip_st).unwrap();
        let mut dip_st = vec![0u8; DipMap::<u8, 1>::storage_needed(self.w, self.h)];
        let dip = DipMap::build(&tex, &mut dip_st).unwrap();
        let mut tent_st = vec![0u64; TentTable::<u64>::storage_needed(self.w, self.h).unwrap()];
        let tent = TentTable::<u64>::build(&tex, &mut tent_st).unwrap();
        let mut lines_st = vec![0u64; TentLines::<u64>::storage_needed(self.w, self.h).unwrap()];
        let lines = TentLines::<u64>::build(&tex, &mut lines_st).unwrap();
        let n = variance_storage::<1>(self.w, self.h).unwrap();
        let (mut vs, mut sq) = (vec![0u64; n], vec![0u64; n]);
        let var = VarianceTables::<u64>::build(&tex, &mut vs, &mut sq).unwrap();

        assert_eq!(mip.lod(&typed), mip.lod_raw(&rr, fb));
        self.modes(
            &typed,
            &rr,
            fb,
            &sat,
            &tex,
            &mip,
            &rip,
            &dip,
            (&tent, &lines),
            &var,
        );
    }

    #[allow(clippy::too_many_arguments)]
    fn modes<X: Coord>(
        &self,
        typed: &Rect<X>,
        rr: &Rect<i64>,
        fb: FracBits,
        sat: &Sat<'_, u32>,
        tex: &Texture<'_, u8>,
        mip: &MipPyramid<'_, u8>,
        rip: &RipMap<'_, u8, 1>,
        dip: &DipMap<'_, u8, 1>,
        tent: (&TentTable<'_, u64>, &TentLines<'_, u64>),
        var: &VarianceTables<'_, u64>,
    ) {
        #[allow(clippy::too_many_arguments)]
        fn one<X: Coord, M: EdgeMode>(
            m: M,
            typed: &Rect<X>,
            rr: &Rect<i64>,
            fb: FracBits,
            sat: &Sat<'_, u32>,
            tex: &Texture<'_, u8>,
            mip: &MipPyramid<'_, u8>,
            rip: &RipMap<'_, u8, 1>,
            dip: &DipMap<'_, u8, 1>,
            tent: (&TentTable<'_, u64>, &TentLines<'_, u64>),
            var: &VarianceTables<'_, u64>,
        ) {
            let kind = m.kind();
            let ctx = format!("{kind:?} {rr:?} F={}", fb.get());
            macro_rules! per_form {
                ($form:expr, $fk:expr) => {
                    assert_eq!(
                        run(|k| sat.box_sum(typed, $form, m, k)),
                        run(|k| sat.box_sum_raw(rr, fb, $fk, kind, k)),
                        "box_sum {ctx}"
                    );
                    assert_eq!(
                        run(|k| var.variance(typed, $form, m, k)),
                        run(|k| var.variance_raw(rr, fb, $fk, kind, k)),
                        "variance {ctx}"
                    );
                };
            }
            per_form!(Paper, FormKind::Paper);
            per_form!(Stable, FormKind::Stable);
            assert_eq!(
                run(|k| point(tex, typed, m, k)),
                run(|k| point_raw(tex, rr, fb, kind, k)),
                "point {ctx}"
            );
            assert_eq!(
                run(|k| mip.point_sample(typed, m, k)),
                run(|k| mip.point_sample_raw(rr, fb, kind, k)),
                "mip {ctx}"
            );
            assert_eq!(
                run(|k| mip.trilinear(typed, m, k)),
                run(|k| mip.trilinear_raw(rr, fb, kind, k)),
                "trilinear {ctx}"
            );
            assert_eq!(
                run(|k| rip.sample(typed, m, k)),
                run(|k| rip.sample_raw(rr, fb, kind, k)),
                "ripmap {ctx}"
            );
            for filter in [DipFilter::Bilinear, DipFilter::Trilinear] {
                assert_eq!(
                    run(|k| dip.sample(typed, filter, m, k)),
                    run(|k| dip.sample_raw(rr, fb, filter, kind, k)),
                    "dipmap {filter:?} {ctx}"
                );
            }
            let (table, lines) = tent;
            assert_eq!(
                run(|k| table.sample(typed, m, k)),
                run(|k| table.sample_raw(rr, fb, kind, k)),
                "tent {ctx}"
            );
            assert_eq!(
                run(|k| table.sample_exact(lines, tex, typed, m, k)),
                run(|k| table.sample_exact_raw(lines, tex, rr, fb, kind, k)),
                "tent exact {ctx}"
            );
        }
        one(Border, typed, rr, fb, sat, tex, mip, rip, dip, tent, var);
        one(
            ClampToEdge,
            typed,
            rr,
            fb,
            sat,
            tex,
            mip,
            rip,
            dip,
            tent,
            var,
        );
        one(Repeat, typed, rr, fb, sat, tex, mip, rip, dip, tent, var);
        one(
            MirroredRepeat,
            typed,
            rr,
            fb,
            sat,
            tex,
            mip,
            rip,
            dip,
            tent,
            var,
        );
    }
}

fn arb_case() -> impl Strategy<Value = (Structures, [i64; 4], u32)> {
    (
        1usize..12,
        1usize..12,
        prop_oneof![Just(0u32), Just(4), Just(8), Just(16)],
    )
        .prop_flat_map(|(w, h, f)| {
            let span = |n: usize| (3 * n as i64) << f;
            (
                proptest::collection::vec(any::<u8>(), w * h),
                -span(w)..span(w),
                0i64..span(w),
                -span(h)..span(h),
                0i64..span(h),
            )
                .prop_map(move |(texels, x0, dx, y0, dy)| {
                    (Structures { w, h, texels }, [x0, y0, x0 + dx, y0 + dy], f)
                })
        })
}

fn check_at(s: &Structures, raw: [i64; 4], f: u32) {
    match f {
        0 => s.check::<I64F0>(raw),
        4 => s.check::<I60F4>(raw),
        8 => s.check::<I56F8>(raw),
        16 => s.check::<I48F16>(raw),
        _ => unreachable!(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, ..ProptestConfig::default() })]

    #[test]
    fn raw_entry_points_equal_the_typed_ones((s, raw, f) in arb_case()) {
        check_at(&s, raw, f);
    }
}

#[test]
fn inverted_zero_area_and_edge_boxes_agree() {
    let s = Structures {
        w: 5,
        h: 3,
        texels: (0..15).map(|i| (i * 37 % 256) as u8).collect(),
    };
    for f in [0u32, 4, 8, 16] {
        let one = 1i64 << f;
        for raw in [
            [0, 0, 5 * one, 3 * one],                       // the whole texture
            [2 * one, one, 2 * one, 2 * one],               // zero width
            [3 * one, one, one, 2 * one],                   // inverted
            [-7 * one - 1, -one, 9 * one + 3, 4 * one + 1], // over every edge
            [i64::MIN / 4, 0, i64::MIN / 4 + one, one],     // far left
        ] {
            check_at(&s, raw, f);
        }
    }
}

#[test]
fn frac_bits_above_24_are_refused_once() {
    assert_eq!(
        FracBits::new(25),
        Err(Error::FracBitsUnsupported {
            frac_bits: 25,
            max: 24
        })
    );
    assert_eq!(FracBits::new(24).map(FracBits::get), Ok(24));
    assert_eq!(FracBits::of::<I48F16>().map(FracBits::get), Ok(16));
    // Every run-time mode name round-trips (the CLI's path from text to a lookup).
    for k in EdgeKind::ALL {
        assert_eq!(EdgeKind::from_name(k.name()), Some(k));
    }
}
