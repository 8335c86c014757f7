//! Measuring one scene: the ideal image, the footprints, every method's values, errors, counts,
//! memory and timing.

use crate::methods::{self, Input, Method, Refs, SampleError, Storage, Structures};
use indicatif::ProgressBar;
use std::collections::HashMap;
use std::hint::black_box;
use std::time::{Duration, Instant};
use texsat::EdgeMode;
use texsat::{Border, ClampToEdge, MirroredRepeat, NoCount, Repeat, Tally};
use texsat_host_tests::scenes::{ideal_image, Scene};
use texsat_host_tests::RefMode;

/// Everything measured for one method on one scene.
#[derive(Debug, Clone)]
pub struct MethodResult {
    /// The method.
    pub method: Method,
    /// Samples with a value (pixels with an ideal value and a footprint that fits `I24F8`, less
    /// refusals).
    pub samples: usize,
    /// Samples texsat refused (or whose structure could not be built).
    pub refused: usize,
    /// Root mean square error against the ideal, texel units.
    pub rmse: f64,
    /// `20 log10(255 / rmse)`.
    pub psnr: f64,
    /// Largest absolute error against the ideal.
    pub max_err: f64,
    /// Largest absolute difference to the `f64` same-filter reference.
    pub arith_err: f64,
    /// Median ns per sample over the timed passes.
    pub ns: f64,
    /// Timed passes run.
    pub runs: usize,
    /// Mean counts per sample from the `Tally` pass.
    pub reads: f64,
    /// Mean bits read per sample.
    pub bits_read: f64,
    /// Mean 32-bit words touched per sample.
    pub words: f64,
    /// Mean multiplies per sample.
    pub muls: f64,
    /// Mean divides per sample.
    pub divs: f64,
    /// Mean additive operations per sample.
    pub adds: f64,
    /// Bits of storage per texel.
    pub bits_per_texel: f64,
    /// What the storage is.
    pub memory_what: &'static str,
    /// A note (refusal reasons, structure failures).
    pub note: String,
    /// Per pixel value (row-major), for the renders.
    pub values: Vec<Option<f64>>,
}

/// One scene's results.
pub struct SceneResult {
    /// Scene name.
    pub name: String,
    /// One line from the scene.
    pub description: String,
    /// Texture size.
    pub tex_size: (usize, usize),
    /// Output size.
    pub out_size: (usize, usize),
    /// Boundary mode.
    pub mode: RefMode,
    /// Pixels with an ideal value.
    pub ideal_pixels: usize,
    /// Pixels whose footprint rectangle did not fit `I24F8`.
    pub unfit: usize,
    /// Modulus bits of the modular table.
    pub modular_k: u32,
    /// Share of footprints with both sides at most one texel (magnification).
    pub magnified: f64,
    /// Median and largest footprint area, texels.
    pub area_median: f64,
    /// Largest footprint area.
    pub area_max: f64,
    /// Seconds spent computing the ideal image.
    pub ideal_secs: f64,
    /// Ideal per pixel.
    pub ideal: Vec<Option<f64>>,
    /// Per method.
    pub methods: Vec<MethodResult>,
}

/// How to measure.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Timed passes per method (the median is reported).
    pub repeats: usize,
    /// Stop repeating once a method's timed passes took this long (at least one pass runs).
    pub time_budget: Duration,
}

/// Measures `scene` for `methods`, advancing `bar` once per method (and once for the setup).
pub fn measure_scene(
    scene: &Scene,
    methods: &[Method],
    settings: Settings,
    bar: &ProgressBar,
) -> SceneResult {
    match scene.mode {
        RefMode::Border => measure_mode(scene, methods, settings, bar, Border),
        RefMode::Clamp => measure_mode(scene, methods, settings, bar, ClampToEdge),
        RefMode::Repeat => measure_mode(scene, methods, settings, bar, Repeat),
        RefMode::Mirror => measure_mode(scene, methods, settings, bar, MirroredRepeat),
    }
}

/// Times `f` over `inputs`: up to `repeats` passes (fewer once `budget` is spent), returning the
/// median seconds per pass and the passes run.
fn time_passes<F: FnMut(&Input) -> f64>(
    inputs: &[Input],
    settings: Settings,
    mut f: F,
) -> (f64, usize) {
    let start = Instant::now();
    let mut times = Vec::with_capacity(settings.repeats);
    for _ in 0..settings.repeats.max(1) {
        let t = Instant::now();
        let mut acc = 0.0;
        for inp in inputs {
            acc += f(black_box(inp));
        }
        black_box(acc);
        times.push(t.elapsed().as_secs_f64());
        if start.elapsed() > settings.time_budget {
            break;
        }
    }
    times.sort_by(f64::total_cmp);
    let n = times.len();
    let median = if n % 2 == 1 {
        times[n / 2]
    } else {
        (times[n / 2 - 1] + times[n / 2]) / 2.0
    };
    (median, n)
}

/// `f` over `items` on every available core (items dealt round-robin, so that the expensive
/// ones, which cluster in image rows near a horizon, are shared), in order.
fn par_map<T: Sync, R: Send, F: Fn(&T) -> R + Sync>(items: &[T], f: F) -> Vec<R> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, 16);
    if threads == 1 || items.len() < 2 {
        return items.iter().map(f).collect();
    }
    let f = &f;
    let mut parts: Vec<std::vec::IntoIter<R>> = std::thread::scope(|sc| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                sc.spawn(move || {
                    items
                        .iter()
                        .skip(t)
                        .step_by(threads)
                        .map(f)
                        .collect::<Vec<R>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("reference thread panicked").into_iter())
            .collect()
    });
    let mut out = Vec::with_capacity(items.len());
    for i in 0..items.len() {
        if let Some(v) = parts[i % threads].next() {
            out.push(v);
        }
    }
    out
}

/// Runs `$body` with `$m` bound to a constant `Method` equal to `$method`, so that the inlined
/// `eval` folds its `match` away in the timed loop.
macro_rules! with_const_method {
    ($method:expr, $m:ident => $body:expr) => {
        match $method {
            Method::Point => {
                const $m: Method = Method::Point;
                $body
            }
            Method::MipPoint => {
                const $m: Method = Method::MipPoint;
                $body
            }
            Method::Trilinear => {
                const $m: Method = Method::Trilinear;
                $body
            }
            Method::Ripmap => {
                const $m: Method = Method::Ripmap;
                $body
            }
            Method::DipmapBilinear => {
                const $m: Method = Method::DipmapBilinear;
                $body
            }
            Method::DipmapTrilinear => {
                const $m: Method = Method::DipmapTrilinear;
                $body
            }
            Method::Sat4 => {
                const $m: Method = Method::Sat4;
                $body
            }
            Method::Sat16Paper => {
                const $m: Method = Method::Sat16Paper;
                $body
            }
            Method::Sat16Stable => {
                const $m: Method = Method::Sat16Stable;
                $body
            }
            Method::Sat16StableTiled8 => {
                const $m: Method = Method::Sat16StableTiled8;
                $body
            }
            Method::Sat16StableTiled2_16 => {
                const $m: Method = Method::Sat16StableTiled2_16;
                $body
            }
            Method::Sat16StableModular => {
                const $m: Method = Method::Sat16StableModular;
                $body
            }
            Method::SatPlan => {
                const $m: Method = Method::SatPlan;
                $body
            }
            Method::TentInt => {
                const $m: Method = Method::TentInt;
                $body
            }
            Method::TentPaper => {
                const $m: Method = Method::TentPaper;
                $body
            }
            Method::TentExact => {
                const $m: Method = Method::TentExact;
                $body
            }
            Method::Ewa => {
                const $m: Method = Method::Ewa;
                $body
            }
        }
    };
}

fn measure_mode<M: EdgeMode>(
    scene: &Scene,
    methods: &[Method],
    settings: Settings,
    bar: &ProgressBar,
    mode: M,
) -> SceneResult {
    let (w, h) = (scene.width, scene.height);
    bar.set_message(format!("{}: ideal image", scene.name));
    let t0 = Instant::now();
    let ideal = ideal_image(scene);
    let ideal_secs = t0.elapsed().as_secs_f64();
    let ideal_pixels = ideal.iter().filter(|v| v.is_some()).count();
    let mut unfit = 0;
    let inputs: Vec<Input> = (0..w * h)
        .filter(|&p| ideal[p].is_some())
        .filter_map(|p| {
            let (px, py) = (p % w, p / w);
            let fp = scene.mapping.footprint(px as f64 + 0.5, py as f64 + 0.5)?;
            let inp = Input::new(p, fp);
            if inp.is_none() {
                unfit += 1;
            }
            inp
        })
        .collect();
    let mut areas: Vec<f64> = inputs.iter().map(Input::area).collect();
    areas.sort_by(f64::total_cmp);
    let magnified = inputs
        .iter()
        .filter(|i| {
            i.raw[2] - i.raw[0] <= 1 << methods::F && i.raw[3] - i.raw[1] <= 1 << methods::F
        })
        .count() as f64
        / inputs.len().max(1) as f64;

    bar.set_message(format!("{}: building structures", scene.name));
    let tex = &scene.texture;
    let (tw, th) = (tex.width, tex.height);
    let texels = methods::texels_u8(tex);
    let (modular_k, modular_k0) = match texsat::Texture::<u8>::new(&texels, tw, th) {
        Ok(t) if methods.contains(&Method::Sat16StableModular) => {
            let (k, _, k0, r0) = methods::choose_modular_k(&t, &inputs, mode);
            (k, (k != k0).then_some((k0, r0)))
        }
        _ => (texsat::layouts::modulus_bits_for(8, 1), None),
    };
    let mut storage = Storage::new(tex);
    let plan = texsat::plan::Plan::for_scene(&methods::scene_facts(tw, th, &inputs, mode.kind()));
    let structures = storage.build(tw, th, modular_k, modular_k0, plan);
    let refs = Refs::new(tex);
    // EWA once per pixel (it is also the reference of itself).
    let ewa: Vec<f64> = if methods.contains(&Method::Ewa) {
        bar.set_message(format!("{}: EWA reference", scene.name));
        par_map(&inputs, |i: &Input| {
            texsat_host_tests::ewa::ewa_gaussian(tex, scene.mode, &i.fp)
        })
    } else {
        vec![f64::NAN; inputs.len()]
    };
    bar.inc(1);

    let mut results = Vec::new();
    let mut ref_cache = HashMap::new();
    for &method in methods {
        bar.set_message(format!("{}: {}", scene.name, method.name()));
        let r = match &structures {
            Ok(s) => measure_method(
                scene,
                s,
                &refs,
                &inputs,
                &ideal,
                &ewa,
                method,
                settings,
                mode,
                &mut ref_cache,
            ),
            Err(e) => failed(method, &inputs, w * h, format!("texture refused: {e}")),
        };
        results.push(r);
        bar.inc(1);
    }
    let n = areas.len();
    SceneResult {
        name: scene.name.clone(),
        description: scene.description.clone(),
        tex_size: (tw, th),
        out_size: (w, h),
        mode: scene.mode,
        ideal_pixels,
        unfit,
        modular_k,
        magnified,
        area_median: if n > 0 { areas[n / 2] } else { f64::NAN },
        area_max: areas.last().copied().unwrap_or(f64::NAN),
        ideal_secs,
        ideal,
        methods: results,
    }
}

fn failed(method: Method, inputs: &[Input], pixels: usize, note: String) -> MethodResult {
    MethodResult {
        method,
        samples: 0,
        refused: inputs.len(),
        rmse: f64::NAN,
        psnr: f64::NAN,
        max_err: f64::NAN,
        arith_err: f64::NAN,
        ns: f64::NAN,
        runs: 0,
        reads: f64::NAN,
        bits_read: f64::NAN,
        words: f64::NAN,
        muls: f64::NAN,
        divs: f64::NAN,
        adds: f64::NAN,
        bits_per_texel: f64::NAN,
        memory_what: "",
        note,
        values: vec![None; pixels],
    }
}

#[allow(clippy::too_many_arguments)]
fn measure_method<M: EdgeMode>(
    scene: &Scene,
    s: &Structures<'_>,
    refs: &Refs,
    inputs: &[Input],
    ideal: &[Option<f64>],
    ewa: &[f64],
    method: Method,
    settings: Settings,
    mode: M,
    ref_cache: &mut HashMap<&'static str, Vec<f64>>,
) -> MethodResult {
    let pixels = scene.width * scene.height;
    let mut values = vec![None; pixels];
    let mut tally = Tally::new();
    let mut refused = 0usize;
    let mut reasons: Vec<String> = Vec::new();
    let mut ok: Vec<usize> = Vec::with_capacity(inputs.len());
    // Values and counts (one Tally pass; EWA values were computed once already).
    for (n, inp) in inputs.iter().enumerate() {
        let v = if method == Method::Ewa {
            Ok(ewa[n])
        } else {
            methods::eval(s, scene, method, inp, mode, &mut tally)
        };
        match v {
            Ok(v) => {
                values[inp.pixel] = Some(v);
                ok.push(n);
            }
            Err(e) => {
                refused += 1;
                let why = match e {
                    SampleError::Texsat(e) => e.to_string(),
                    SampleError::Unavailable => "structure not built".to_string(),
                };
                if !reasons.contains(&why) && reasons.len() < 3 {
                    reasons.push(why);
                }
            }
        }
    }
    let samples = ok.len();
    // Errors against the ideal and against the same-filter reference (shared by the methods of
    // one reference family: computed for the first, reused by the others).
    let family = method.reference_family();
    let cached = family
        .and_then(|f| ref_cache.get(f))
        .filter(|c| ok.iter().all(|&n| c.get(n).is_some_and(|r| !r.is_nan())));
    let reference: Vec<f64> = match cached {
        Some(c) => c.clone(),
        None => {
            let refs_ok = par_map(&ok, |&n| {
                let inp = &inputs[n];
                let lod_q = match (&s.mip, method) {
                    (Some(m), Method::MipPoint | Method::Trilinear) => {
                        m.lod(&inp.rect).unwrap_or(0)
                    }
                    _ => 0,
                };
                methods::reference(refs, scene, method, inp, lod_q, ewa[n])
            });
            let mut all = vec![f64::NAN; inputs.len()];
            for (&n, r) in ok.iter().zip(refs_ok) {
                all[n] = r;
            }
            if let Some(f) = family {
                ref_cache.insert(f, all.clone());
            }
            all
        }
    };
    let (mut se, mut max_err, mut arith) = (0.0f64, 0.0f64, 0.0f64);
    let mut no_ref = 0usize;
    for &n in &ok {
        let inp = &inputs[n];
        let v = values[inp.pixel].unwrap_or(f64::NAN);
        let e = v - ideal[inp.pixel].unwrap_or(f64::NAN);
        se += e * e;
        max_err = max_err.max(e.abs());
        let d = (v - reference[n]).abs();
        if d.is_nan() {
            no_ref += 1;
        } else {
            arith = arith.max(d);
        }
    }
    let rmse = (se / samples.max(1) as f64).sqrt();
    let psnr = 20.0 * (255.0 / rmse).log10();
    // Timed passes over the inputs that have values.
    let timed: Vec<Input> = ok.iter().map(|&n| inputs[n]).collect();
    let (secs, runs) = if method == Method::Ewa {
        let tex = &scene.texture;
        time_passes(&timed, settings, |i| {
            texsat_host_tests::ewa::ewa_gaussian(tex, scene.mode, &i.fp)
        })
    } else {
        with_const_method!(method, METHOD => time_passes(&timed, settings, |i| {
            methods::eval(s, scene, METHOD, i, mode, &mut NoCount).unwrap_or(0.0)
        }))
    };
    let per = |c: u64| c as f64 / samples.max(1) as f64;
    let (bits_per_texel, memory_what) =
        methods::memory(s, method).unwrap_or((f64::NAN, "not built"));
    let mut note = String::new();
    if methods::memory(s, method).is_none() && !s.failures.is_empty() {
        let f: Vec<String> = s
            .failures
            .iter()
            .map(|(w, e)| format!("{w}: {e}"))
            .collect();
        note.push_str(&format!("not built: {}", f.join("; ")));
    }
    if refused > 0 {
        if !note.is_empty() {
            note.push_str("; ");
        }
        note.push_str(&format!("{refused} refused ({})", reasons.join("; ")));
    }
    if no_ref > 0 {
        if !note.is_empty() {
            note.push_str("; ");
        }
        note.push_str(&format!(
            "{no_ref} samples without a reference (arithmetic error over the rest)"
        ));
    }
    if method == Method::Sat16StableModular {
        if !note.is_empty() {
            note.push_str("; ");
        }
        note.push_str(&format!("k = {}", s.modular_k));
        if let Some((k0, r0)) = s.modular_k0 {
            note.push_str(&format!(
                " (k0 = {k0}, from the largest box alone, refuses {r0} boxes)"
            ));
        }
    }
    if method == Method::SatPlan {
        if let Some(p) = &s.plan {
            if !note.is_empty() {
                note.push_str("; ");
            }
            note.push_str(&format!(
                "plan: {} ({} values, {} lookup), {} bytes, worst case {} reads",
                p.layout(),
                p.entry().name(),
                p.lookup().name(),
                p.table_bytes(),
                p.costs().reads
            ));
        }
    }
    let counted = method != Method::Ewa;
    let c = |v: u64| if counted { per(v) } else { f64::NAN };
    MethodResult {
        method,
        samples,
        refused,
        rmse,
        psnr,
        max_err,
        arith_err: arith,
        ns: secs * 1e9 / samples.max(1) as f64,
        runs,
        reads: c(tally.reads),
        bits_read: c(tally.bits_read),
        words: c(tally.words),
        muls: c(tally.muls),
        divs: c(tally.divs),
        adds: c(tally.adds),
        bits_per_texel,
        memory_what,
        note,
        values,
    }
}
