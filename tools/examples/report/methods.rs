//! The methods the report compares: what each one is, the structures it reads (built once per
//! scene), one sample of it (generic over the counter and the boundary mode, so the timed passes
//! are monomorphised with `NoCount`), and its `f64` same-filter reference from `host-tests`.

use fixed::types::I24F8;
use texsat::filters::dip::{DipFilter, DipMap};
use texsat::filters::mip::MipPyramid;
use texsat::filters::point::point;
use texsat::filters::rip::RipMap;
use texsat::filters::tent::{TentLines, TentTable};
use texsat::filters::Sample;
use texsat::layouts::{Modular, Tiled, TiledSpec};
use texsat::plan::{EntryWord, Plan, PlanLayout, SceneFacts};
use texsat::{
    BoxLookup, BoxSum, Counter, Error, Layout, NoCount, Paper, Rect, Sat, Stable, Texture, Wide,
};
use texsat_host_tests::filter_ref_mip::{self as rmip, RefImage};
use texsat_host_tests::filter_ref_ripdip::{self as rrd, DipVariant, LevelSel, RefDip, RefRip};
use texsat_host_tests::filter_ref_tentvar::{footprint, round_ratio, triangle_weights};
use texsat_host_tests::footprint::Footprint;
use texsat_host_tests::scenes::Scene;
use texsat_host_tests::{axis_weights, ewa::ewa_gaussian, RefMode, RefTexture};

/// Fractional bits of the footprint rectangles (`I24F8`).
pub const F: u32 = 8;
/// Fractional bits of every mean (texsat's `OUT_FRAC_BITS`).
pub const G: u32 = 16;

/// A method of the comparison (`--method NAME`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, clap::ValueEnum)]
pub enum Method {
    /// Nearest texel of the texture.
    #[value(name = "point")]
    Point,
    /// Nearest texel of the mip level `round(log2 d)`.
    #[value(name = "mip-point")]
    MipPoint,
    /// Williams' trilinear mip map.
    #[value(name = "trilinear")]
    Trilinear,
    /// Heckbert's 4-D pyramid.
    #[value(name = "ripmap")]
    Ripmap,
    /// Dipmap, bilinear in `floor(L)` of both pyramids (the paper's measured variant).
    #[value(name = "dipmap-bilinear")]
    DipmapBilinear,
    /// Dipmap, trilinear in both pyramids.
    #[value(name = "dipmap-trilinear")]
    DipmapTrilinear,
    /// Crow's 4-read lookup: the rectangle rounded to integer corners.
    #[value(name = "sat4")]
    Sat4,
    /// 16-read fractional box, Crow's paper form, flat `u32` table.
    #[value(name = "sat16-paper")]
    Sat16Paper,
    /// 16-read fractional box, stable form, flat `u32` table.
    #[value(name = "sat16-stable")]
    Sat16Stable,
    /// Stable form on a tiled layout, 8 x 8 tiles.
    #[value(name = "sat16-stable-tiled8")]
    Sat16StableTiled8,
    /// Stable form on 2 x 2 tiles within 16 x 16 tiles.
    #[value(name = "sat16-stable-tiled2-16")]
    Sat16StableTiled2_16,
    /// Stable form on the table modulo `2^k`.
    #[value(name = "sat16-stable-modular")]
    Sat16StableModular,
    /// The scene's plan (`texsat::plan`): the smallest table for the scene's facts.
    #[value(name = "sat-plan")]
    SatPlan,
    /// Tent by repeated integration, integer centre and half-widths (9 reads).
    #[value(name = "tent-int")]
    TentInt,
    /// Tent, paper form: 9 bilinear interpolations of the order-2 table (36 reads).
    #[value(name = "tent-paper")]
    TentPaper,
    /// Tent, exact for fractional corners (81 reads).
    #[value(name = "tent-exact")]
    TentExact,
    /// Heckbert's elliptical weighted average with a Gaussian, `f64` (the quality reference).
    #[value(name = "ewa")]
    Ewa,
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Method; 17] = [
        Method::Point,
        Method::MipPoint,
        Method::Trilinear,
        Method::Ripmap,
        Method::DipmapBilinear,
        Method::DipmapTrilinear,
        Method::Sat4,
        Method::Sat16Paper,
        Method::Sat16Stable,
        Method::Sat16StableTiled8,
        Method::Sat16StableTiled2_16,
        Method::Sat16StableModular,
        Method::SatPlan,
        Method::TentInt,
        Method::TentPaper,
        Method::TentExact,
        Method::Ewa,
    ];

    /// The methods drawn in the render strips.
    pub const RENDERED: [Method; 7] = [
        Method::Point,
        Method::Trilinear,
        Method::Ripmap,
        Method::DipmapBilinear,
        Method::Sat16Stable,
        Method::TentExact,
        Method::Ewa,
    ];

    /// The `--method` name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Point => "point",
            Method::MipPoint => "mip-point",
            Method::Trilinear => "trilinear",
            Method::Ripmap => "ripmap",
            Method::DipmapBilinear => "dipmap-bilinear",
            Method::DipmapTrilinear => "dipmap-trilinear",
            Method::Sat4 => "sat4",
            Method::Sat16Paper => "sat16-paper",
            Method::Sat16Stable => "sat16-stable",
            Method::Sat16StableTiled8 => "sat16-stable-tiled8",
            Method::Sat16StableTiled2_16 => "sat16-stable-tiled2-16",
            Method::Sat16StableModular => "sat16-stable-modular",
            Method::SatPlan => "sat-plan",
            Method::TentInt => "tent-int",
            Method::TentPaper => "tent-paper",
            Method::TentExact => "tent-exact",
            Method::Ewa => "ewa",
        }
    }

    /// One line: what the method computes and over which structure.
    pub fn what(self) -> &'static str {
        match self {
            Method::Point => "nearest texel to the footprint centre (texsat `filters::point`)",
            Method::MipPoint => "nearest texel of mip level round(log2 max(W, H)) (`MipPyramid::point_sample`)",
            Method::Trilinear => "Williams' trilinear interpolation on the mip map (`MipPyramid::trilinear`)",
            Method::Ripmap => "4 bilinear probes in the ripmap levels around (log2 W, log2 H), blended (`RipMap::sample`)",
            Method::DipmapBilinear => "bilinear in floor(log2 W) of the column and floor(log2 H) of the row pyramid, averaged (`DipMap::sample`, `Bilinear`)",
            Method::DipmapTrilinear => "trilinear in both dipmap pyramids, averaged (`DipMap::sample`, `Trilinear`)",
            Method::Sat4 => "Crow's 4-read box: the rectangle's corners rounded to integers (`box_sum_int` + `mean_rounded`)",
            Method::Sat16Paper => "fractional box, Crow's bilinear corner form, flat u32 table (`box_sum(Paper)` + `mean_rounded`)",
            Method::Sat16Stable => "fractional box, stable form, flat u32 table (`box_sum(Stable)` + `mean_rounded`)",
            Method::Sat16StableTiled8 => "stable fractional box on `Tiled` with 8 x 8 tiles",
            Method::Sat16StableTiled2_16 => "stable fractional box on `Tiled`, 2 x 2 tiles within 16 x 16 tiles",
            Method::Sat16StableModular => "stable fractional box on `Modular` (table mod 2^k, k from the scene's largest box)",
            Method::SatPlan => "the scene's plan: the smallest table for its facts (box sizes, mode, F = 8, exact means) and its lookup (`Plan::for_scene`)",
            Method::TentInt => "triangle filter by repeated integration, integer centre and half-widths (`TentTable::sample_int`)",
            Method::TentPaper => "triangle filter, 9 bilinear interpolations of the order-2 table (`TentTable::sample`)",
            Method::TentExact => "triangle filter, exact for fractional corners (`TentTable::sample_exact` + `TentLines`)",
            Method::Ewa => "elliptical weighted average, Gaussian, f64 (`host-tests::ewa`; the quality reference)",
        }
    }

    /// Whether the method is the `f64` quality reference (timed, but not a contender).
    pub fn is_reference(self) -> bool {
        self == Method::Ewa
    }

    /// Methods that share one reference (the same filter on the same footprint).
    pub fn reference_family(self) -> Option<&'static str> {
        if self.is_sat16() {
            Some("fractional box")
        } else if matches!(self, Method::TentPaper | Method::TentExact) {
            Some("fractional tent")
        } else {
            None
        }
    }

    /// Whether the method is one of the 16-read summed-area-table lookups (exact arithmetic).
    pub fn is_sat16(self) -> bool {
        matches!(
            self,
            Method::Sat16Paper
                | Method::Sat16Stable
                | Method::Sat16StableTiled8
                | Method::Sat16StableTiled2_16
                | Method::Sat16StableModular
                | Method::SatPlan
        )
    }
}

/// One pixel's footprint in every form the methods take.
#[derive(Debug, Clone, Copy)]
pub struct Input {
    /// Row-major pixel index.
    pub pixel: usize,
    /// The footprint at the pixel centre (analytic derivatives).
    pub fp: Footprint,
    /// Crow's rectangle, rounded to `I24F8` (each side at least one raw unit).
    pub rect: Rect<I24F8>,
    /// Its raw corners `[x0, y0, x1, y1]` (units `2^-8` texel).
    pub raw: [i64; 4],
    /// The rectangle with corners rounded to integers (ties up; a side that rounds to zero is
    /// the one texel holding the centre), for the 4-read lookup.
    pub int_rect: Rect<i32>,
    /// Integer centre and half-widths `(cx, cy, a, b)` of the tent (`a, b >= 1`).
    pub tent_int: (i32, i32, u32, u32),
}

impl Input {
    /// The input of a footprint, or `None` if its rectangle does not fit `I24F8`.
    pub fn new(pixel: usize, fp: Footprint) -> Option<Input> {
        let r = fp.crow_rect();
        let q = Rect::<I24F8>::from_f64(r.u0, r.v0, r.u1, r.v1).ok()?;
        let mut raw = [q.x0, q.y0, q.x1, q.y1].map(|v| i64::from(v.to_bits()));
        // A side that rounds to zero raw units becomes one unit (1/256 texel) wide.
        for a in 0..2 {
            if raw[a + 2] <= raw[a] {
                raw[a + 2] = raw[a] + 1;
            }
        }
        let fx = |v: i64| Some(I24F8::from_bits(i32::try_from(v).ok()?));
        let rect = Rect::new(fx(raw[0])?, fx(raw[1])?, fx(raw[2])?, fx(raw[3])?);
        let round = |v: i64| ((v + 128) >> F) as i32;
        let mut ir = [round(raw[0]), round(raw[1]), round(raw[2]), round(raw[3])];
        for a in 0..2 {
            if ir[a + 2] <= ir[a] {
                ir[a] = ((raw[a] + raw[a + 2]) >> (F + 1)) as i32;
                ir[a + 2] = ir[a] + 1;
            }
        }
        let int_rect = Rect::new(ir[0], ir[1], ir[2], ir[3]);
        // Centre round((x0 + x1) / 2) and half-width max(1, round((x1 - x0) / 2)), ties up.
        let half = 1i64 << F;
        let cx = ((raw[0] + raw[2] + half) >> (F + 1)) as i32;
        let cy = ((raw[1] + raw[3] + half) >> (F + 1)) as i32;
        let a = (((raw[2] - raw[0] + half) >> (F + 1)) as u32).max(1);
        let b = (((raw[3] - raw[1] + half) >> (F + 1)) as u32).max(1);
        Some(Input {
            pixel,
            fp,
            rect,
            raw,
            int_rect,
            tent_int: (cx, cy, a, b),
        })
    }

    /// Texel cells the fractional rectangle overlaps (the modular lookups' bound).
    pub fn cells(&self) -> u64 {
        let s = 1i64 << F;
        let cx = (self.raw[2] + s - 1).div_euclid(s) - self.raw[0].div_euclid(s);
        let cy = (self.raw[3] + s - 1).div_euclid(s) - self.raw[1].div_euclid(s);
        (cx.max(0) as u64).saturating_mul(cy.max(0) as u64)
    }

    /// Footprint area in texels (of the fixed-point rectangle).
    pub fn area(&self) -> f64 {
        let s = (1u64 << F) as f64;
        (self.raw[2] - self.raw[0]) as f64 * (self.raw[3] - self.raw[1]) as f64 / (s * s)
    }
}

/// Why a sample has no value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleError {
    /// texsat refused it.
    Texsat(Error),
    /// The structure could not be built for this scene.
    Unavailable,
}

impl From<Error> for SampleError {
    fn from(e: Error) -> Self {
        SampleError::Texsat(e)
    }
}

/// The owned storage of every structure of a scene.
#[derive(Default)]
pub struct Storage {
    texels: Vec<u8>,
    mip: Vec<u8>,
    rip: Vec<u8>,
    dip: Vec<u8>,
    sat: Vec<u32>,
    tiled8: (Vec<u32>, Vec<u32>),
    tiled2_16: (Vec<u32>, Vec<u32>),
    modular: (Vec<u32>, Vec<u64>),
    planned: (Vec<u32>, Vec<u32>),
    tent: Vec<u64>,
    lines: Vec<u32>,
}

/// Every structure of a scene, built once from the scene's 8-bit texture (`None` where texsat
/// refused to build it; the reason is in `failures`).
pub struct Structures<'a> {
    /// The texture itself (point sampling, the exact tent's texel term).
    pub tex: Texture<'a, u8>,
    /// Mip map.
    pub mip: Option<MipPyramid<'a, u8>>,
    /// Ripmap.
    pub rip: Option<RipMap<'a, u8, 1>>,
    /// Dipmap.
    pub dip: Option<DipMap<'a, u8, 1>>,
    /// Flat `u32` summed-area table.
    pub sat: Option<Sat<'a, u32>>,
    /// Tiled 8 x 8.
    pub tiled8: Option<Tiled<'a, u32>>,
    /// Tiled 2 in 16.
    pub tiled2_16: Option<Tiled<'a, u32>>,
    /// Modular, `k` bits.
    pub modular: Option<Modular<'a, u64>>,
    /// The modulus bits of `modular`.
    pub modular_k: u32,
    /// `(k0, boxes refused at k0)` when `modular_k` had to exceed `k0` (see
    /// [`choose_modular_k`]).
    pub modular_k0: Option<(u32, usize)>,
    /// The scene's plan, and its table (`None` with the reason in `failures`).
    pub plan: Option<Plan>,
    /// The plan's table.
    pub planned: Option<Planned<'a>>,
    /// Order-2 table.
    pub tent: Option<TentTable<'a, u64>>,
    /// Line tables of the exact tent.
    pub lines: Option<TentLines<'a, u32>>,
    /// `(structure, error)` for every structure texsat refused.
    pub failures: Vec<(&'static str, Error)>,
}

/// `n` zeros reserved with `try_reserve_exact`: a failed allocation ends the report with a
/// message and exit status 1, not an abort. (Image scenes are checked against `--max-memory`
/// first, in `report.rs`; the built-in scenes are small.)
fn zeros<T: Clone + Default>(n: usize, what: &str) -> Vec<T> {
    texsat_tools::budget::zeroed(n, T::default(), what).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(1)
    })
}

fn keep<T>(
    r: Result<T, Error>,
    what: &'static str,
    failures: &mut Vec<(&'static str, Error)>,
) -> Option<T> {
    r.map_err(|e| failures.push((what, e))).ok()
}

/// The texels of `tex` (one 8-bit channel) as `u8`.
pub fn texels_u8(tex: &RefTexture) -> Vec<u8> {
    tex.texels
        .iter()
        .map(|&v| u8::try_from(v.min(255)).unwrap_or(u8::MAX))
        .collect()
}

fn build_tiled<'a>(
    tex: &Texture<'_, u8>,
    spec: Result<TiledSpec, Error>,
    st: &'a mut (Vec<u32>, Vec<u32>),
    what: &'static str,
    f: &mut Vec<(&'static str, Error)>,
) -> Option<Tiled<'a, u32>> {
    let (w, h) = (tex.width(), tex.height());
    let spec = keep(spec, what, f)?;
    let words = keep(Tiled::<u32>::words_needed(spec, w, h, 8), what, f)?;
    st.0 = zeros(words, what);
    st.1 = zeros(keep(Tiled::<u32>::scratch_needed(spec, w), what, f)?, what);
    keep(Tiled::build(tex, spec, &mut st.0, &mut st.1), what, f)
}

impl Storage {
    /// Storage holding the scene's texels.
    pub fn new(tex: &RefTexture) -> Self {
        Storage {
            texels: texels_u8(tex),
            ..Default::default()
        }
    }

    /// Builds every structure (`modular_k` bits for the modular table, `plan` for the planned
    /// one).
    pub fn build(
        &mut self,
        w: usize,
        h: usize,
        modular_k: u32,
        modular_k0: Option<(u32, usize)>,
        plan: Result<Plan, Error>,
    ) -> Result<Structures<'_>, Error> {
        let Storage {
            texels,
            mip,
            rip,
            dip,
            sat,
            tiled8,
            tiled2_16,
            modular,
            planned,
            tent,
            lines,
        } = self;
        let tex = Texture::<u8>::new(texels, w, h)?;
        let mut failures = Vec::new();
        let f = &mut failures;
        *mip = zeros(MipPyramid::<u8>::storage_needed(w, h)?, "mip map");
        let mip = keep(MipPyramid::build(&tex, mip), "mip map", f);
        *rip = zeros(RipMap::<u8, 1>::storage_needed(w, h), "ripmap");
        let rip = keep(RipMap::build(&tex, rip), "ripmap", f);
        *dip = zeros(DipMap::<u8, 1>::storage_needed(w, h), "dipmap");
        let dip = keep(DipMap::build(&tex, dip), "dipmap", f);
        *sat = zeros(Sat::<u32>::entries_needed(w, h)?, "summed-area table");
        let sat = keep(Sat::build(&tex, sat), "summed-area table", f);
        let tiled8 = build_tiled(&tex, TiledSpec::tiles(8, 8), tiled8, "tiled 8x8", f);
        let tiled2_16 = build_tiled(
            &tex,
            TiledSpec::square(&[2, 16]),
            tiled2_16,
            "tiled 2 in 16",
            f,
        );
        modular.0 = zeros(
            Modular::<u64>::words_needed(w, h, modular_k).unwrap_or(0),
            "modular table",
        );
        modular.1 = zeros(w, "modular table");
        let modular = keep(
            Modular::build(&tex, modular_k, &mut modular.0, &mut modular.1),
            "modular table",
            f,
        );
        let plan = keep(plan, "scene plan", f);
        let planned = plan.and_then(|p| build_planned(&tex, &p, planned, f));
        let tent = match TentTable::<u64>::storage_needed(w, h) {
            Ok(n) => {
                *tent = zeros(n, "order-2 table");
                keep(TentTable::build(&tex, tent), "order-2 table", f)
            }
            Err(e) => {
                f.push(("order-2 table", e));
                None
            }
        };
        let lines = match TentLines::<u32>::storage_needed(w, h) {
            Ok(n) => {
                *lines = zeros(n, "tent line tables");
                keep(TentLines::build(&tex, lines), "tent line tables", f)
            }
            Err(e) => {
                f.push(("tent line tables", e));
                None
            }
        };
        Ok(Structures {
            tex,
            mip,
            rip,
            dip,
            sat,
            tiled8,
            tiled2_16,
            modular,
            modular_k,
            modular_k0,
            plan,
            planned,
            tent,
            lines,
            failures,
        })
    }
}

/// The table a plan names, with `u32` values (the report's 8-bit textures of at most 1024^2
/// texels have totals below 2^28; a plan for `u64` values is refused as unavailable).
pub enum Planned<'a> {
    /// The flat table (the scene's `sat`).
    Flat,
    /// Packed, tiled, or tiled and modular.
    Tiled(Box<Tiled<'a, u32>>),
    /// Modular.
    Modular(Modular<'a, u32>),
}

fn build_planned<'a>(
    tex: &Texture<'_, u8>,
    p: &Plan,
    st: &'a mut (Vec<u32>, Vec<u32>),
    f: &mut Vec<(&'static str, Error)>,
) -> Option<Planned<'a>> {
    if p.entry() == EntryWord::U64 {
        f.push(("plan's table", Error::NoPlan));
        return None;
    }
    let w = tex.width();
    match p.layout() {
        PlanLayout::Flat => Some(Planned::Flat),
        PlanLayout::Modular { k } => {
            st.0 = zeros(p.storage_len(), "plan's table");
            st.1 = zeros(w, "plan's table");
            keep(
                Modular::build(tex, k, &mut st.0, &mut st.1),
                "plan's table",
                f,
            )
            .map(Planned::Modular)
        }
        l => {
            let spec = l.tiled_spec()?;
            st.0 = zeros(p.storage_len(), "plan's table");
            st.1 = zeros(
                keep(Tiled::<u32>::scratch_needed(spec, w), "plan's table", f)?,
                "plan's table",
            );
            keep(
                Tiled::build(tex, spec, &mut st.0, &mut st.1),
                "plan's table",
                f,
            )
            .map(|t| Planned::Tiled(Box::new(t)))
        }
    }
}

/// The facts of a scene, read off its footprints: the smallest and largest sides (per axis,
/// raw at `F = 8`), whether any leaves the texture, its mode; exact means with `G` bits.
pub fn scene_facts(w: usize, h: usize, inputs: &[Input], mode: texsat::EdgeKind) -> SceneFacts {
    let side = |i: &Input, a: usize| (i.raw[a + 2] - i.raw[a]).max(1) as u64;
    let fold = |a: usize, pick: fn(u64, u64) -> u64, init: u64| {
        inputs.iter().map(|i| side(i, a)).fold(init, pick)
    };
    let (pw, ph) = ((w as i64) << F, (h as i64) << F);
    let leaves = inputs
        .iter()
        .any(|i| i.raw[0] < 0 || i.raw[1] < 0 || i.raw[2] > pw || i.raw[3] > ph);
    SceneFacts {
        min_box: [fold(0, u64::min, u64::MAX), fold(1, u64::min, u64::MAX)],
        max_box: [fold(0, u64::max, 1), fold(1, u64::max, 1)],
        leaves_texture: leaves,
        mean_frac_bits: G,
        ..SceneFacts::new(w, h, 8, F, mode)
    }
}

/// The modulus bits for the modular table: the least of `k0 = modulus_bits_for(8, largest
/// number of cells a footprint overlaps)`, `k0 + 2F` (the headroom of boxes straddling an edge
/// under a wrapping mode) and 64 for which no input is refused. Returns `(k, refused at k, k0,
/// refused at k0)`.
pub fn choose_modular_k<M: texsat::EdgeMode>(
    tex: &Texture<'_, u8>,
    inputs: &[Input],
    mode: M,
) -> (u32, usize, u32, usize) {
    let max_cells = inputs.iter().map(Input::cells).max().unwrap_or(1).max(1);
    let k0 = texsat::layouts::modulus_bits_for(8, max_cells).clamp(8, 64);
    let refused_at = |k: u32| -> usize {
        let mut words = zeros::<u32>(
            Modular::<u64>::words_needed(tex.width(), tex.height(), k).unwrap_or(0),
            "modular table",
        );
        let mut row = zeros::<u64>(tex.width(), "modular table");
        let Ok(m) = Modular::build(tex, k, &mut words, &mut row) else {
            return inputs.len();
        };
        inputs
            .iter()
            .filter(|i| {
                BoxLookup::box_sum(&m, &i.rect, Stable, mode, &mut NoCount)
                    .and_then(|s| s.mean_rounded(0, G, &mut NoCount))
                    .is_err()
            })
            .count()
    };
    let r0 = refused_at(k0);
    let mut best = (k0, r0);
    if r0 > 0 {
        for k in [(k0 + 2 * F).min(64), 64] {
            let r = refused_at(k);
            if r < best.1 {
                best = (k, r);
            }
            if r == 0 {
                break;
            }
        }
    }
    (best.0, best.1, k0, r0)
}

#[inline(always)]
fn value(s: Sample<1>) -> f64 {
    s.values[0] as f64 / (1u64 << G) as f64
}

#[inline(always)]
fn mean<W: Wide, K: Counter>(s: BoxSum<W, 1>, k: &mut K) -> Result<f64, SampleError> {
    let m: u128 = s.mean_rounded(0, G, k)?.into();
    Ok(m as f64 / (1u64 << G) as f64)
}

#[inline(always)]
fn get<T>(o: &Option<T>) -> Result<&T, SampleError> {
    o.as_ref().ok_or(SampleError::Unavailable)
}

/// One sample of `method` at `inp`, in texel units, counting to `k`.
#[inline(always)]
pub fn eval<M: texsat::EdgeMode, K: Counter>(
    s: &Structures<'_>,
    scene: &Scene,
    method: Method,
    inp: &Input,
    mode: M,
    k: &mut K,
) -> Result<f64, SampleError> {
    let r = &inp.rect;
    Ok(match method {
        Method::Point => value(point(&s.tex, r, mode, k)?),
        Method::MipPoint => value(get(&s.mip)?.point_sample(r, mode, k)?),
        Method::Trilinear => value(get(&s.mip)?.trilinear(r, mode, k)?),
        Method::Ripmap => value(get(&s.rip)?.sample(r, mode, k)?),
        Method::DipmapBilinear => value(get(&s.dip)?.sample(r, DipFilter::Bilinear, mode, k)?),
        Method::DipmapTrilinear => value(get(&s.dip)?.sample(r, DipFilter::Trilinear, mode, k)?),
        Method::Sat4 => mean(get(&s.sat)?.box_sum_int(&inp.int_rect, mode, k)?, k)?,
        Method::Sat16Paper => mean(get(&s.sat)?.box_sum(r, Paper, mode, k)?, k)?,
        Method::Sat16Stable => mean(get(&s.sat)?.box_sum(r, Stable, mode, k)?, k)?,
        Method::Sat16StableTiled8 => {
            mean(BoxLookup::box_sum(get(&s.tiled8)?, r, Stable, mode, k)?, k)?
        }
        Method::Sat16StableTiled2_16 => mean(
            BoxLookup::box_sum(get(&s.tiled2_16)?, r, Stable, mode, k)?,
            k,
        )?,
        Method::Sat16StableModular => {
            mean(BoxLookup::box_sum(get(&s.modular)?, r, Stable, mode, k)?, k)?
        }
        Method::SatPlan => {
            let form = get(&s.plan)?.lookup().form();
            match get(&s.planned)? {
                Planned::Flat => mean(get(&s.sat)?.box_sum(r, form, mode, k)?, k)?,
                Planned::Tiled(t) => mean(BoxLookup::box_sum(&**t, r, form, mode, k)?, k)?,
                Planned::Modular(m) => mean(BoxLookup::box_sum(m, r, form, mode, k)?, k)?,
            }
        }
        Method::TentInt => {
            let (cx, cy, a, b) = inp.tent_int;
            value(get(&s.tent)?.sample_int(cx, cy, a, b, mode, k)?)
        }
        Method::TentPaper => value(get(&s.tent)?.sample(r, mode, k)?),
        Method::TentExact => {
            value(get(&s.tent)?.sample_exact(get(&s.lines)?, &s.tex, r, mode, k)?)
        }
        Method::Ewa => ewa_gaussian(&scene.texture, scene.mode, &inp.fp),
    })
}

/// Bits of storage per texel the method reads (structures as stored, in their entry types) and
/// what they are.
pub fn memory(s: &Structures<'_>, method: Method) -> Option<(f64, &'static str)> {
    let texels = (s.tex.width() * s.tex.height()) as f64;
    let tex_bits = texels * 8.0;
    Some(match method {
        Method::Point | Method::Ewa => (tex_bits, "the texture"),
        Method::MipPoint | Method::Trilinear => (
            tex_bits + s.mip.as_ref()?.storage_len() as f64 * 8.0,
            "texture + coarse levels (u8)",
        ),
        Method::Ripmap => (
            s.rip.as_ref()?.storage_bits() as f64,
            "all levels, level 0 a copy (u8)",
        ),
        Method::DipmapBilinear | Method::DipmapTrilinear => (
            s.dip.as_ref()?.storage_bits() as f64,
            "both pyramids, level 0 once (u8)",
        ),
        Method::Sat4 | Method::Sat16Paper | Method::Sat16Stable => (
            Layout::<1>::storage_bits(s.sat.as_ref()?) as f64,
            "flat table, u32 entries (replaces the texture)",
        ),
        Method::Sat16StableTiled8 => (
            Layout::<1>::storage_bits(s.tiled8.as_ref()?) as f64,
            "tiled fields, packed",
        ),
        Method::Sat16StableTiled2_16 => (
            Layout::<1>::storage_bits(s.tiled2_16.as_ref()?) as f64,
            "tiled fields, packed",
        ),
        Method::Sat16StableModular => (
            Layout::<1>::storage_bits(s.modular.as_ref()?) as f64,
            "table mod 2^k, packed at k bits",
        ),
        Method::SatPlan => (
            s.plan.as_ref()?.table_bytes() as f64 * 8.0,
            "the plan's table (layout in the note)",
        ),
        Method::TentInt | Method::TentPaper => (
            s.tent.as_ref()?.table_bytes() as f64 * 8.0,
            "order-2 table, u64 entries",
        ),
        Method::TentExact => (
            s.tent.as_ref()?.table_bytes() as f64 * 8.0
                + lines_bits(s.tex.width(), s.tex.height())
                + tex_bits,
            "order-2 table (u64) + line tables (u32) + texture",
        ),
    })
    .map(|(bits, what)| (bits / texels, what))
}

fn lines_bits(w: usize, h: usize) -> f64 {
    TentLines::<u32>::storage_needed(w, h).map_or(f64::NAN, |n| n as f64 * 32.0)
}

/// The `f64` references of a scene (levels rebuilt by the host code, independently of texsat).
pub struct Refs {
    w: usize,
    h: usize,
    /// The host's naive inclusive table (`RefTexture::naive_table`), exact `u128`.
    table: Vec<u128>,
    base: RefImage,
    mip: Vec<RefImage>,
    rip: RefRip,
    dip: RefDip,
}

impl Refs {
    /// The references of `tex` (one channel): the correctly rounded pyramids texsat must store.
    pub fn new(tex: &RefTexture) -> Self {
        let (w, h) = (tex.width, tex.height);
        let t = &tex.texels;
        let sizes = rmip::level_sizes(w, h);
        let levels = rmip::rounded_pyramid(t, w, h, 1);
        let mip = rmip::pyramid_from_levels(&sizes, 1, &levels);
        Refs {
            w,
            h,
            table: tex.naive_table(),
            base: mip[0].clone(),
            mip,
            rip: RefRip::build(t, w, h, 1, true),
            dip: RefDip::build(t, w, h, 1, true),
        }
    }
}

/// The same filter as `method` evaluated by the host-tests references on the same footprint, in
/// texel units. Pyramids: `f64`, with texsat's own fixed-point level selection (`lod_q` from the
/// mip map, `LevelSel::Fixed` for rip/dip), on the correctly rounded levels the host code
/// rebuilds. Tables: the *exact* box mean or triangle filter over the same fixed-point
/// rectangle in integers, rounded to [`G`] fraction bits as texsat documents (to nearest, ties
/// up), so a difference of 0 means bit-exact. `ewa` is its own reference.
pub fn reference(
    refs: &Refs,
    scene: &Scene,
    method: Method,
    inp: &Input,
    lod_q: u32,
    ewa: f64,
) -> f64 {
    let mode = scene.mode;
    let index = move |i: i64, n: usize| mode.index(i, n);
    let raw = inp.raw;
    let tex = &scene.texture;
    match method {
        Method::Point => rmip::point_ref(&refs.base, raw, F, &index)[0],
        Method::MipPoint => rmip::point_sample_ref(&refs.mip, raw, F, lod_q, &index)[0],
        Method::Trilinear => rmip::trilinear_ref(&refs.mip, raw, F, lod_q, &index)[0],
        Method::Ripmap => rrd::rip_sample(&refs.rip, raw, F, LevelSel::Fixed, &index)[0],
        Method::DipmapBilinear => rrd::dip_sample(
            &refs.dip,
            raw,
            F,
            DipVariant::Bilinear,
            LevelSel::Fixed,
            &index,
        )[0],
        Method::DipmapTrilinear => rrd::dip_sample(
            &refs.dip,
            raw,
            F,
            DipVariant::Trilinear,
            LevelSel::Fixed,
            &index,
        )[0],
        Method::Sat4 => {
            let r = &inp.int_rect;
            box_mean_ref(refs, mode, [r.x0, r.y0, r.x1, r.y1].map(i64::from), 0)
        }
        m if m.is_sat16() => box_mean_ref(refs, mode, raw, F),
        Method::TentInt => {
            let (cx, cy, a, b) = inp.tent_int;
            tent_ref(tex, mode, (cx.into(), a.into()), (cy.into(), b.into()), 0)
        }
        Method::TentPaper | Method::TentExact => {
            let (x, y) = footprint(raw);
            tent_ref(tex, mode, x, y, F + 1)
        }
        _ => ewa,
    }
}

fn to_value(q: u64) -> f64 {
    q as f64 / (1u64 << G) as f64
}

/// The exact mean of the extended texture over the raw box `[x0, y0, x1, y1]` (`f` fractional
/// bits), rounded to [`G`] fraction bits (ties up), from host code only: the per-texel axis
/// weights of `texsat_host_tests::axis_weights` (the exact overlap of the box's interval with
/// every cell that shows texel `i` under `mode`, in closed form) grouped into runs of equal
/// weight, each pair of runs times the texel sum of its rectangle from the host's naive table.
/// Exact in `u128`, and `O(w + h + runs^2)` however many periods the box spans.
pub fn box_mean_ref(refs: &Refs, mode: RefMode, raw: [i64; 4], f: u32) -> f64 {
    let (w, h) = (refs.w, refs.h);
    let rx = runs(axis_weights(mode, raw[0], raw[2], w, f));
    let ry = runs(axis_weights(mode, raw[1], raw[3], h, f));
    let s = |i: usize, j: usize| -> u128 {
        if i == 0 || j == 0 {
            0
        } else {
            refs.table[(j - 1) * w + (i - 1)]
        }
    };
    let mut sum = 0u128;
    for &(j0, j1, vy) in &ry {
        for &(i0, i1, vx) in &rx {
            let block = s(i1, j1) + s(i0, j0) - s(i0, j1) - s(i1, j0);
            sum += vx * vy * block;
        }
    }
    let area = (raw[2] - raw[0]) as u128 * (raw[3] - raw[1]) as u128;
    to_value(round_ratio(sum, G, area))
}

/// The runs `[start, end)` of equal non-zero values of `v`.
fn runs(v: Vec<u128>) -> Vec<(usize, usize, u128)> {
    let mut out: Vec<(usize, usize, u128)> = Vec::new();
    for (i, x) in v.into_iter().enumerate() {
        match out.last_mut() {
            Some(last) if last.1 == i && last.2 == x => last.1 = i + 1,
            _ if x != 0 => out.push((i, i + 1, x)),
            _ => {}
        }
    }
    out
}

/// The exact triangle filter (centres and half-widths `(c, a)` in units `2^-g`, as
/// `filter_ref_tentvar::tent_numerator`) rounded to [`G`] fraction bits (ties up): the exact
/// per-axis weights of `triangle_weights` folded onto the texture's texels under `mode`, so
/// wide footprints cost `O(w h)` at most.
pub fn tent_ref(tex: &RefTexture, mode: RefMode, x: (i128, i128), y: (i128, i128), g: u32) -> f64 {
    let fold = |(c, a): (i128, i128), n: usize| -> Vec<(usize, i128)> {
        let mut acc = vec![0i128; n];
        for (i, w) in triangle_weights(c, a, g) {
            if let Some(t) = mode.index(i, n) {
                acc[t] += w;
            }
        }
        acc.into_iter()
            .enumerate()
            .filter(|&(_, w)| w != 0)
            .collect()
    };
    let wx = fold(x, tex.width);
    let wy = fold(y, tex.height);
    let mut n = 0i128;
    for &(j, vy) in &wy {
        let texels = &tex.texels[j * tex.width..(j + 1) * tex.width];
        let mut row = 0i128;
        for &(i, vx) in &wx {
            row += texels[i] as i128 * vx;
        }
        n += row * vy;
    }
    // a^2 b^2 overflows u128 only for sides beyond 2^23 texels (outside I24F8 anyway).
    let sq = |v: i128| (v.unsigned_abs()).checked_mul(v.unsigned_abs());
    match sq(x.1).zip(sq(y.1)).and_then(|(a, b)| a.checked_mul(b)) {
        Some(den) if den > 0 && den < 1 << 127 => {
            to_value(round_ratio(n.max(0) as u128, G - 2, den))
        }
        _ => f64::NAN,
    }
}
