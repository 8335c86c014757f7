//! The demo scene, shared by the firmware (`src/demo.rs`, Cortex-M4F under QEMU) and the host
//! check (`tools/examples/firmware_scene.rs`, which includes this file): a 64 x 64 procedural
//! texture on a ground plane seen in perspective (Crow §2.3), 32 x 24 pixels, each pixel's
//! footprint rectangle sampled with the configuration a scene plan picked. The same code runs
//! on both, in `f32` (IEEE single on both, no fused multiply-add: Rust does not contract), so
//! the checksums must be equal.
//!
//! Three plans, fixed at compile time by `Plan::for_scene` on constant facts:
//! * `SMALL`: integer boxes of 1 to 8 texels inside the texture, ClampToEdge: `modular:14` with
//!   `u16` values and the 4-read lookup;
//! * `REPEAT`: boxes of 0.5 to 12 texels at `F = 8` that leave the texture under Repeat, at most
//!   64 reads: `modular:16`, `u32` values, Stable;
//! * `TILED`: the same facts without a read bound: `tiled:4x4`, the smallest table.
//!
//! And for comparison, not a plan: trilinear mip-mapping (`filter-mip`) of the `REPEAT`
//! footprints under Repeat, the 8-tap filter a texture unit would use instead of a table.

use texsat::filters::mip::MipPyramid;
use texsat::filters::OUT_FRAC_BITS;
use texsat::plan::{Plan, PlanLookup, SceneFacts};
use texsat::{BoxLookup, EdgeKind, Error, FracBits, NoCount, Rect, Repeat};

/// Texture side.
pub const W: usize = 64;
/// Texture side.
pub const H: usize = 64;
/// Output pixels across.
pub const OUT_W: usize = 32;
/// Output pixels down.
pub const OUT_H: usize = 24;
/// Fractional bits of the mean.
pub const G: u32 = 8;

const fn plan(f: SceneFacts) -> Plan {
    match Plan::for_scene(&f) {
        Ok(p) => p,
        Err(_) => panic!("no plan for the demo scene"),
    }
}

/// Integer boxes of 1 to 8 texels inside the texture, ClampToEdge.
pub const SMALL: Plan = plan(SceneFacts {
    max_box: [8, 8],
    ..SceneFacts::new(W, H, 8, 0, EdgeKind::Clamp)
});

/// Boxes of 0.5 to 12 texels at `F = 8`, leaving the texture under Repeat, at most 64 reads.
pub const REPEAT: Plan = plan(SceneFacts {
    min_box: [128, 128],
    max_box: [12 << 8, 12 << 8],
    leaves_texture: true,
    max_reads: 64,
    ..SceneFacts::new(W, H, 8, 8, EdgeKind::Repeat)
});

/// The same facts without a read bound.
pub const TILED: Plan = plan(SceneFacts {
    max_reads: 0,
    ..*REPEAT.facts()
});

/// Texel `(x, y)` of the procedural texture (a deterministic hash).
pub const fn texel(x: usize, y: usize) -> u8 {
    let mut v = (x as u32).wrapping_mul(0x9E37_79B9) ^ (y as u32).wrapping_mul(0x85EB_CA6B);
    v ^= v >> 15;
    v = v.wrapping_mul(0xC2B2_AE35);
    v ^= v >> 13;
    (v >> 24) as u8
}

/// The texture, row-major.
pub fn fill_texture(out: &mut [u8]) {
    for (i, t) in out.iter_mut().enumerate() {
        *t = texel(i % W, i / W);
    }
}

/// Texture coordinates of screen point `(sx, sy)` (pixel units, `sy` down from the horizon
/// line above the image): a ground plane in perspective, `v = D / (sy + Y0)`, `u = (sx - CX) v S`.
fn ground(sx: f32, sy: f32) -> (f32, f32) {
    const D: f32 = 96.0;
    const Y0: f32 = 4.0;
    const CX: f32 = OUT_W as f32 / 2.0;
    const S: f32 = 0.35;
    let v = D / (sy + Y0);
    ((sx - CX) * v * S, v)
}

/// The footprint rectangle of pixel `(px, py)`, raw at `F = f` (`texels 2^f`): the bounding box
/// of its four mapped corners (Crow §2.3), each side limited to `[min, max]` raw units (the
/// renderer's level-of-detail clamp, so every box lies within the plan's facts).
pub fn footprint(px: usize, py: usize, f: u32, min: i64, max: i64) -> [i64; 4] {
    let one = (1u32 << f) as f32;
    let mut lo = [f32::MAX, f32::MAX];
    let mut hi = [f32::MIN, f32::MIN];
    for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let (u, v) = ground(px as f32 + dx, py as f32 + dy);
        lo = [lo[0].min(u), lo[1].min(v)];
        hi = [hi[0].max(u), hi[1].max(v)];
    }
    // Raw units, rounded down (`as` truncates toward zero: shift positive first).
    let raw = |t: f32| ((t + 1024.0) * one) as i64 - (1024i64 << f);
    let (x0, y0) = (raw(lo[0]), raw(lo[1]));
    let side = |a: i64, b: i64| (b - a).max(min).min(max);
    [x0, y0, x0 + side(x0, raw(hi[0])), y0 + side(y0, raw(hi[1]))]
}

/// The footprint of an integer-corner plan: the box rounded to whole texels, shifted and
/// clipped into the texture (the facts say boxes stay inside).
pub fn footprint_int(px: usize, py: usize) -> Rect<i32> {
    let [x0, y0, x1, y1] = footprint(px, py, 0, 1, 8);
    // Shift the box by whole periods so that it starts inside, then clip its far side.
    let fit = |a: i64, b: i64, n: i64| {
        let start = a.rem_euclid(n);
        let end = (start + (b - a)).min(n);
        (start as i32, end as i32)
    };
    let (x0, x1) = fit(x0, x1, W as i64);
    let (y0, y1) = fit(y0, y1, H as i64);
    Rect::new(x0, y0, x1.max(x0 + 1), y1.max(y0 + 1))
}

/// FNV-1a, 64-bit, over the means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Checksum {
    /// The hash.
    pub hash: u64,
    /// The first four means (`2^-G` texel units).
    pub first: [u64; 4],
    /// Pixels sampled.
    pub samples: u32,
}

impl Checksum {
    const fn new() -> Self {
        Checksum {
            hash: 0xcbf2_9ce4_8422_2325,
            first: [0; 4],
            samples: 0,
        }
    }

    fn push(&mut self, v: u64) {
        if let Some(f) = self.first.get_mut(self.samples as usize) {
            *f = v;
        }
        for b in v.to_le_bytes() {
            self.hash = (self.hash ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
        self.samples = self.samples.wrapping_add(1);
    }
}

/// One pixel's mean under `plan` on `l` (a box outside the plan's facts is an error, never a
/// wrong answer).
pub fn sample<L: BoxLookup<1>>(l: &L, plan: &Plan, px: usize, py: usize) -> Result<u64, Error>
where
    <<L::Value as texsat::Entry>::Acc as texsat::Acc>::Wide: Into<u64>,
{
    let f = plan.facts();
    let s = if plan.lookup() == PlanLookup::Int4 {
        let r = footprint_int(px, py);
        plan.check_box(&r.to_raw_int())?;
        l.box_sum_int(&r, f.edge, &mut NoCount)?
    } else {
        let min = f.min_box[0] as i64;
        let max = f.max_box[0] as i64;
        let [x0, y0, x1, y1] = footprint(px, py, f.frac_bits, min, max);
        let r = Rect::new(x0, y0, x1, y1);
        plan.check_box(&r)?;
        let fb = FracBits::new(f.frac_bits)?;
        l.box_sum_raw(&r, fb, plan.lookup().form(), f.edge, &mut NoCount)?
    };
    // The plan's mean: the 32-bit one where its facts keep every box's area and mean narrow
    // (the same value; the wide mean's fallbacks are then left out of the firmware).
    if plan.mean_fits_u32() {
        Ok(s.mean_rounded_u32(0, G, &mut NoCount)?.into())
    } else {
        Ok(s.mean_rounded(0, G, &mut NoCount)?.into())
    }
}

/// Every pixel of the image under `plan` on `l`.
pub fn render<L: BoxLookup<1>>(l: &L, plan: &Plan) -> Result<Checksum, Error>
where
    <<L::Value as texsat::Entry>::Acc as texsat::Acc>::Wide: Into<u64>,
{
    let mut c = Checksum::new();
    for py in 0..OUT_H {
        for px in 0..OUT_W {
            c.push(sample(l, plan, px, py)?);
        }
    }
    Ok(c)
}

/// One pixel's trilinear mip sample, for comparison with the plans: the `REPEAT` plan's
/// footprint under Repeat, the value rounded (ties up) from `2^-16` to `2^-G` texel units, the
/// units of the plans' means.
pub fn sample_mip(p: &MipPyramid<'_, u8>, px: usize, py: usize) -> Result<u64, Error> {
    let f = REPEAT.facts();
    let [x0, y0, x1, y1] = footprint(
        px,
        py,
        f.frac_bits,
        f.min_box[0] as i64,
        f.max_box[0] as i64,
    );
    let s = p.trilinear_raw(
        &Rect::new(x0, y0, x1, y1),
        FracBits::new(f.frac_bits)?,
        Repeat,
        &mut NoCount,
    )?;
    let v = s.values.first().copied().unwrap_or(0);
    let shift = OUT_FRAC_BITS - G;
    // v <= 255 2^16: the rounding addition does not wrap.
    Ok(v.wrapping_add(1 << (shift - 1)) >> shift)
}

/// Every pixel of the image, trilinear mip-mapped ([`sample_mip`]).
pub fn render_mip(p: &MipPyramid<'_, u8>) -> Result<Checksum, Error> {
    let mut c = Checksum::new();
    for py in 0..OUT_H {
        for px in 0..OUT_W {
            c.push(sample_mip(p, px, py)?);
        }
    }
    Ok(c)
}
