//! `BatchLookup` answers exactly what the single lookups answer, box by box, errors included:
//! random boxes (inside, crossing the edges, far outside, inverted, empty, huge) on the flat,
//! tiled and modular layouts, in every boundary mode, for the 4-read and both 16-read forms;
//! and `RepeatWithinPeriod` answers what `Repeat` does for boxes at most a period long.

use texsat::layouts::{modulus_bits_for, Modular, Tiled, TiledSpec};
use texsat::lookup::BatchLookup;
use texsat::{
    Border, BoxLookup, ClampToEdge, EdgeMode, FracBits, MirroredRepeat, NoCount, Paper, Rect,
    Repeat, RepeatWithinPeriod, Sat, Stable, Tally, Texture,
};
use texsat_host_tests::RngExt;

fn boxes(n: usize, w: i64, seed: u64) -> (Vec<Rect<i64>>, Vec<Rect<i32>>) {
    let mut rng = texsat_host_tests::rng(seed);
    let f = 1i64 << 8;
    let mut raw = Vec::new();
    for i in 0..n {
        let span = match i % 5 {
            0 => 3 * w * f,  // crossing edges, several periods
            1 => w * f,      // inside or crossing
            2 => 8 * f,      // small
            3 => 1i64 << 40, // far outside (some refused)
            _ => f,          // sub-texel
        };
        let x0 = rng.random_range(-span..=span);
        let y0 = rng.random_range(-span..=span);
        let (dx, dy) = if i % 17 == 0 {
            (-rng.random_range(1..=f), 0) // inverted
        } else if i % 13 == 0 {
            (0, rng.random_range(0..=span)) // empty
        } else {
            (rng.random_range(0..=span), rng.random_range(0..=span))
        };
        raw.push(Rect::new(x0, y0, x0 + dx, y0 + dy));
    }
    let int = raw
        .iter()
        .map(|r| {
            let c = |v: i64| (v >> 8).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
            Rect::new(c(r.x0), c(r.y0), c(r.x1), c(r.y1))
        })
        .collect();
    (raw, int)
}

fn check<L: BoxLookup<1> + BatchLookup<1>, M: EdgeMode + Copy>(layout: &L, mode: M, what: &str)
where
    L::Value: std::fmt::Debug,
{
    let w = layout.width() as i64;
    let (raw, int) = boxes(600, w, 31 + w as u64);
    let f = FracBits::new(8).unwrap();
    let single_raw = |form: u8| -> Vec<_> {
        raw.iter()
            .map(|r| match form {
                0 => layout.box_sum_raw(r, f, Paper, mode, &mut NoCount),
                _ => layout.box_sum_raw(r, f, Stable, mode, &mut NoCount),
            })
            .collect()
    };
    for form in 0..2u8 {
        let want = single_raw(form);
        let mut got = vec![Err(texsat::Error::EmptyTexture); raw.len() + 3];
        let n = match form {
            0 => layout.box_sums_raw(&raw, f, Paper, mode, &mut NoCount, &mut got),
            _ => layout.box_sums_raw(&raw, f, Stable, mode, &mut NoCount, &mut got),
        };
        assert_eq!(n, raw.len());
        assert!(got[..n] == want[..], "{what}: form {form}");
        assert!(got[n..]
            .iter()
            .all(|g| *g == Err(texsat::Error::EmptyTexture)));
        // Counted: the same reads and operations as the single calls.
        let (mut a, mut b) = (Tally::new(), Tally::new());
        for r in &raw {
            let _ = layout.box_sum_raw(r, f, Stable, mode, &mut a);
        }
        let mut out = vec![Err(texsat::Error::EmptyTexture); raw.len()];
        layout.box_sums_raw(&raw, f, Stable, mode, &mut b, &mut out);
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "{what}: counts");
    }
    let want: Vec<_> = int
        .iter()
        .map(|r| layout.box_sum_int(r, mode, &mut NoCount))
        .collect();
    let mut got = vec![Err(texsat::Error::EmptyTexture); int.len()];
    // Shorter output: answers only as many as fit.
    assert_eq!(
        layout.box_sums_int(&int, mode, &mut NoCount, &mut got[..7]),
        7
    );
    assert_eq!(
        layout.box_sums_int(&int, mode, &mut NoCount, &mut got),
        int.len()
    );
    assert!(got == want, "{what}: int");
}

fn all_modes<L: BoxLookup<1> + BatchLookup<1>>(layout: &L, what: &str)
where
    L::Value: std::fmt::Debug,
{
    check(layout, Border, what);
    check(layout, ClampToEdge, what);
    check(layout, Repeat, what);
    check(layout, MirroredRepeat, what);
    check(layout, RepeatWithinPeriod, what);
    within_equals_repeat(layout, what);
}

/// `RepeatWithinPeriod` against `Repeat` on the same random boxes: for a box at most a period
/// long on both axes (or empty) the same answer, single and batch, raw and integer; for a
/// longer one a refusal (`OutsidePlan`, or the error Repeat gives first).
fn within_equals_repeat<L: BoxLookup<1> + BatchLookup<1>>(layout: &L, what: &str)
where
    L::Value: std::fmt::Debug,
{
    let (w, h) = (layout.width() as u64, layout.height() as u64);
    let (raw, int) = boxes(600, w as i64, 77 + w);
    let f = FracBits::new(8).unwrap();
    let longer = texsat::Error::OutsidePlan {
        limit: texsat::plan::PlanLimit::LongerThanPeriod,
    };
    let side = |lo: i64, hi: i64| hi.wrapping_sub(lo) as u64;
    let (mut same, mut refused) = (0, 0);
    for (r, ri) in raw.iter().zip(&int) {
        let cases = [
            (
                side(r.x0, r.x1),
                side(r.y0, r.y1),
                w << 8,
                h << 8,
                layout.box_sum_raw(r, f, Stable, Repeat, &mut NoCount),
                layout.box_sum_raw(r, f, Stable, RepeatWithinPeriod, &mut NoCount),
            ),
            (
                side(ri.x0.into(), ri.x1.into()),
                side(ri.y0.into(), ri.y1.into()),
                w,
                h,
                layout.box_sum_int(ri, Repeat, &mut NoCount),
                layout.box_sum_int(ri, RepeatWithinPeriod, &mut NoCount),
            ),
        ];
        for (bw, bh, pw, ph, want, got) in cases {
            let inverted = bw > i64::MAX as u64 || bh > i64::MAX as u64;
            if inverted || bw == 0 || bh == 0 || (bw <= pw && bh <= ph) {
                assert_eq!(got, want, "{what}: {r:?} {ri:?}");
                same += 1;
            } else {
                match got {
                    Err(e) if e == longer => refused += 1,
                    Err(_) => assert_eq!(got, want, "{what}: {r:?}"),
                    Ok(_) => panic!("{what}: a box longer than a period answered: {r:?} {ri:?}"),
                }
            }
        }
    }
    assert!(same > 300 && refused > 50, "{what}: {same} {refused}");
}

#[test]
fn batch_equals_single_calls_on_every_layout_and_mode() {
    let (w, h) = (37, 29);
    let mut rng = texsat_host_tests::rng(5);
    let t: Vec<u8> = (0..w * h).map(|_| rng.random_range(0..=255u8)).collect();
    let texture = Texture::<u8>::new(&t, w, h).unwrap();
    let mut table = vec![0u32; w * h];
    all_modes(&Sat::build(&texture, &mut table).unwrap(), "flat");
    let spec = TiledSpec::tiles(8, 8).unwrap();
    let mut words = vec![0u32; Tiled::<u32>::words_needed(spec, w, h, 8).unwrap()];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, w).unwrap()];
    all_modes(
        &Tiled::<u32>::build(&texture, spec, &mut words, &mut scratch).unwrap(),
        "tiled",
    );
    let k = modulus_bits_for(8, 20 * 20);
    let mut mwords = vec![0u32; Modular::<u32>::words_needed(w, h, k).unwrap()];
    let mut row = vec![0u32; w];
    all_modes(
        &Modular::<u32>::build(&texture, k, &mut mwords, &mut row).unwrap(),
        "modular",
    );
    // u16 entries (i32 accumulator): a 16 x 16 texture, the largest the width proof allows.
    let small = Texture::<u8>::new(&t[..256], 16, 16).unwrap();
    let mut t16 = vec![0u16; 256];
    all_modes(&Sat::build(&small, &mut t16).unwrap(), "flat u16");
}
