//! The firmware demo's footprints (`examples/firmware/src/scene.rs`, computed in `f32` on the
//! Cortex-M4F's FPU) against the same perspective mapping in `f64`: every corner of every
//! pixel's box within one raw unit (`2^-F` texel) of the `f64` one, the bound
//! `docs/firmware.md` states.
//!
//! Why one raw unit: the mapped coordinates stay below 2^8 texels (`v <= 24`, `|u| <= 16 v S`),
//! where an `f32` ulp is at most `2^-16`; `ground` is 4 operations, each within half an ulp,
//! and the shift by 1024 before the truncation adds half an ulp at 2^11 (`2^-13`), so the `f32`
//! coordinate is within about `2^-12` texels of the exact one, `2^-4` raw units at `F = 8`: the
//! truncated raw corner is the exact one's floor or a neighbour. The box's far corner is the
//! near one plus a side clamped to the plan's `[min, max]`, so it inherits the same bound.

#[path = "../../examples/firmware/src/scene.rs"]
#[allow(dead_code)]
mod scene;

use scene::{OUT_H, OUT_W, REPEAT};

/// `scene::ground` in `f64`, with the scene's constants.
fn ground64(sx: f64, sy: f64) -> (f64, f64) {
    const D: f64 = 96.0;
    const Y0: f64 = 4.0;
    const CX: f64 = OUT_W as f64 / 2.0;
    const S: f64 = 0.35;
    let v = D / (sy + Y0);
    ((sx - CX) * v * S, v)
}

/// `scene::footprint` in `f64`: the same bounding box, floors and clamps.
fn footprint64(px: usize, py: usize, f: u32, min: i64, max: i64) -> [i64; 4] {
    let one = f64::from(1u32 << f);
    let mut lo = [f64::MAX, f64::MAX];
    let mut hi = [f64::MIN, f64::MIN];
    for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let (u, v) = ground64(px as f64 + dx, py as f64 + dy);
        lo = [lo[0].min(u), lo[1].min(v)];
        hi = [hi[0].max(u), hi[1].max(v)];
    }
    let raw = |t: f64| (t * one).floor() as i64;
    let (x0, y0) = (raw(lo[0]), raw(lo[1]));
    let side = |a: i64, b: i64| (b - a).max(min).min(max);
    [x0, y0, x0 + side(x0, raw(hi[0])), y0 + side(y0, raw(hi[1]))]
}

#[test]
fn f32_footprints_within_one_raw_unit_of_f64() {
    let facts = REPEAT.facts();
    // The demo's fractional plans (F = 8, sides 0.5 to 12 texels), F = 0 with the integer
    // plan's sides, and the unclamped boxes at F = 8.
    let cases = [
        (
            facts.frac_bits,
            facts.min_box[0] as i64,
            facts.max_box[0] as i64,
        ),
        (0, 1, 8),
        (8, 0, i64::MAX),
    ];
    for (f, min, max) in cases {
        let (mut corners, mut off_by_one) = (0u32, 0u32);
        for py in 0..OUT_H {
            for px in 0..OUT_W {
                let got = scene::footprint(px, py, f, min, max);
                let want = footprint64(px, py, f, min, max);
                for (g, w) in got.iter().zip(want) {
                    corners += 1;
                    assert!(
                        (g - w).abs() <= 1,
                        "F = {f}, pixel ({px}, {py}): f32 {got:?}, f64 {want:?}"
                    );
                    off_by_one += u32::from(*g != w);
                }
            }
        }
        // Not a bound, a measurement: how many corners the f32 arithmetic moved by one unit.
        eprintln!(
            "F = {f}, sides {min}..{max}: {off_by_one} of {corners} corners off by one raw unit"
        );
        assert_eq!(corners, 4 * (OUT_W * OUT_H) as u32);
    }
}
