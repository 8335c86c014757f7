//! Tests of the report's scenes (host-tests/src/scenes.rs) and the EWA reference
//! (host-tests/src/ewa.rs).

use texsat_host_tests::ewa::{ewa_gaussian, ewa_gaussian_capped, EwaEllipse};
use texsat_host_tests::footprint::{Footprint, Perspective};
use texsat_host_tests::scenes::*;
use texsat_host_tests::{RefMode, RefTexture, Rng, RngExt, TestRng};

fn scene_with(
    texture: RefTexture,
    mode: RefMode,
    mapping: Box<dyn Mapping>,
    w: usize,
    h: usize,
) -> Scene {
    Scene {
        name: "test".into(),
        description: "test".into(),
        texture,
        mapping,
        width: w,
        height: h,
        mode,
    }
}

/// Naive reference for `polygon_integral`: clip the polygon against every texel cell of its
/// bounding box (no strips, no prefix sums).
fn naive_polygon_integral(tex: &RefTexture, mode: RefMode, poly: &[(f64, f64)]) -> (f64, f64) {
    fn clip(poly: &[(f64, f64)], axis: usize, c: f64, above: bool) -> Vec<(f64, f64)> {
        let co = |p: &(f64, f64)| if axis == 0 { p.0 } else { p.1 };
        let ins = |p: &(f64, f64)| if above { co(p) >= c } else { co(p) <= c };
        let mut out = Vec::new();
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            let x = || {
                let t = (c - co(&a)) / (co(&b) - co(&a));
                (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
            };
            match (ins(&a), ins(&b)) {
                (true, true) => out.push(b),
                (true, false) => out.push(x()),
                (false, true) => {
                    out.push(x());
                    out.push(b)
                }
                _ => {}
            }
        }
        out
    }
    let area = |p: &[(f64, f64)]| {
        (0..p.len())
            .map(|k| {
                let (a, b) = (p[k], p[(k + 1) % p.len()]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            / 2.0
    };
    let umin = poly
        .iter()
        .map(|p| p.0)
        .fold(f64::INFINITY, f64::min)
        .floor() as i64;
    let umax = poly
        .iter()
        .map(|p| p.0)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil() as i64;
    let vmin = poly
        .iter()
        .map(|p| p.1)
        .fold(f64::INFINITY, f64::min)
        .floor() as i64;
    let vmax = poly
        .iter()
        .map(|p| p.1)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil() as i64;
    let mut int = 0.0;
    for j in vmin..vmax {
        for i in umin..umax {
            let mut c = clip(poly, 0, i as f64, true);
            c = clip(&c, 0, i as f64 + 1.0, false);
            c = clip(&c, 1, j as f64, true);
            c = clip(&c, 1, j as f64 + 1.0, false);
            if c.len() >= 3 {
                int += area(&c) * tex.texel_ext(mode, i, j, 0) as f64;
            }
        }
    }
    (int, area(poly))
}

#[test]
fn polygon_integral_matches_naive_cell_clipping() {
    let tex = RefTexture::random(13, 9, 1, 255, 7);
    let mut rng = texsat_host_tests::rng(99);
    let mut scratch = ClipScratch::default();
    for mode in RefMode::ALL {
        let cols = ExtendedColumns::new(&tex, mode);
        for case in 0..60 {
            // A random convex quad (a perspective image of a square) or triangle, up to ~80
            // texels across, partly outside the texture; half of them mirrored (other
            // orientation).
            let r = |rng: &mut TestRng, lo: f64, hi: f64| {
                lo + (hi - lo) * (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
            };
            let scale = if case % 3 == 0 { 60.0 } else { 6.0 };
            let (cx, cy) = (r(&mut rng, -20.0, 40.0), r(&mut rng, -20.0, 30.0));
            let p = Perspective::new([
                [
                    r(&mut rng, 0.2, 1.0) * scale,
                    r(&mut rng, -0.5, 0.5) * scale,
                    cx,
                ],
                [
                    r(&mut rng, -0.5, 0.5) * scale,
                    r(&mut rng, 0.2, 1.0) * scale,
                    cy,
                ],
                [r(&mut rng, -0.3, 0.3), r(&mut rng, -0.3, 0.3), 1.0],
            ]);
            let mut quad: Vec<(f64, f64)> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
                .iter()
                .map(|&(x, y)| p.map(x, y).unwrap())
                .collect();
            if case % 2 == 1 {
                quad.reverse();
            }
            if case % 5 == 4 {
                quad.pop();
            }
            let (int, area) = polygon_integral(&cols, &quad, &mut scratch).unwrap();
            let (nint, narea) = naive_polygon_integral(&tex, mode, &quad);
            assert!(
                (area - narea).abs() <= 1e-9 * narea.abs().max(1.0),
                "{mode:?} {case}"
            );
            assert!(
                (int - nint).abs() <= 1e-9 * (255.0 * narea.abs()).max(1.0),
                "{mode:?} case {case}: {int} vs {nint}"
            );
        }
    }
}

#[test]
fn nonconvex_polygon_is_integrated_as_signed_triangles() {
    let tex = RefTexture::random(8, 8, 1, 255, 3);
    let cols = ExtendedColumns::new(&tex, RefMode::Repeat);
    // An arrowhead (reflex vertex at (4, 3)).
    let poly = [(0.5, 0.5), (7.5, 0.7), (4.0, 3.0), (6.8, 7.2)];
    let mut s = ClipScratch::default();
    let (int, area) = polygon_integral(&cols, &poly, &mut s).unwrap();
    let (nint, narea) = naive_polygon_integral(&tex, RefMode::Repeat, &poly);
    // The naive clipper is exact for non-convex polygons too when clipping against convex cells
    // only leaves degenerate edges (areas still sum correctly).
    assert!((area - narea).abs() < 1e-9);
    assert!((int - nint).abs() < 1e-7, "{int} vs {nint}");
}

#[test]
fn column_sums_match_direct_summation_in_every_mode() {
    let tex = RefTexture::random(5, 7, 1, 255, 11);
    for mode in RefMode::ALL {
        let cols = ExtendedColumns::new(&tex, mode);
        for i in [-7i64, -1, 0, 3, 4, 5, 12] {
            for (j0, j1) in [
                (-40i64, 3i64),
                (-3, 60),
                (2, 30),
                (0, 7),
                (-100, -20),
                (10, 90),
            ] {
                let direct: f64 = (j0..j1).map(|j| tex.texel_ext(mode, i, j, 0) as f64).sum();
                assert_eq!(cols.column_sum(i, j0, j1), direct, "{mode:?} {i} {j0} {j1}");
            }
        }
    }
}

/// The checkerboard closed form (exact polygon clipping) against dense point supersampling on
/// pixels of Heckbert's plane: the 64 x 64 estimate is close and closer than the 8 x 8 one.
#[test]
fn checker_plane_ideal_matches_dense_supersampling() {
    let scenes = builtin_scenes(SceneSize::Default);
    let s = scenes
        .iter()
        .find(|s| s.name == "heckbert-checker-plane")
        .unwrap();
    let horizon = s.height / 4;
    assert_eq!(ideal_pixel(s, 10, horizon - 1), None);
    assert_eq!(
        ideal_pixel(s, 10, horizon),
        None,
        "the horizon row's top corners miss"
    );
    let pixels = [
        (80usize, 119usize),
        (3, 110),
        (150, 100),
        (70, 90),
        (33, 80),
        (120, 70),
        (90, 60),
        (17, 50),
        (140, 45),
    ];
    let (mut e8, mut e64) = (0.0, 0.0);
    for &(px, py) in &pixels {
        let exact = ideal_pixel(s, px, py).unwrap();
        let s8 = supersample_pixel(s, px, py, 8).unwrap();
        let s64 = supersample_pixel(s, px, py, 64).unwrap();
        assert!(
            (s64 - exact).abs() < 4.0,
            "({px}, {py}): exact {exact}, 64x64 {s64}"
        );
        e8 += (s8 - exact).abs();
        e64 += (s64 - exact).abs();
    }
    assert!(e64 < e8, "64x64 total error {e64} not below 8x8 {e8}");
    assert!(e64 / (pixels.len() as f64) < 1.5, "mean 64x64 error {e64}");
}

#[test]
fn ideal_of_identity_mapping_is_the_texels() {
    let tex = RefTexture::random(6, 5, 1, 255, 5);
    for mode in RefMode::ALL {
        // Offset by (-3, -2) texels so part of the image lies outside the texture.
        let s = scene_with(
            tex.clone(),
            mode,
            Box::new(Perspective::affine(1.0, 0.0, -3.0, 0.0, 1.0, -2.0)),
            14,
            11,
        );
        let img = ideal_image(&s);
        for py in 0..s.height {
            for px in 0..s.width {
                let want = tex.texel_ext(mode, px as i64 - 3, py as i64 - 2, 0) as f64;
                let got = img[py * s.width + px].unwrap();
                assert!(
                    (got - want).abs() < 1e-9,
                    "{mode:?} ({px}, {py}): {got} vs {want}"
                );
                assert_eq!(ideal_pixel(&s, px, py), Some(got));
            }
        }
    }
}

#[test]
fn affine_2x_minification_is_the_2x2_box_mean() {
    let tex = RefTexture::random(16, 16, 1, 255, 8);
    let s = scene_with(
        tex.clone(),
        RefMode::Clamp,
        Box::new(Perspective::affine(2.0, 0.0, 0.0, 0.0, 2.0, 0.0)),
        8,
        8,
    );
    for py in 0..8 {
        for px in 0..8 {
            let want = tex.box_integral(
                RefMode::Clamp,
                2.0 * px as f64,
                2.0 * py as f64,
                2.0 * px as f64 + 2.0,
                2.0 * py as f64 + 2.0,
                0,
            ) / 4.0;
            let got = ideal_pixel(&s, px, py).unwrap();
            assert!((got - want).abs() < 1e-9);
        }
    }
}

#[test]
fn constant_texture_gives_constant_ideal_and_ewa() {
    for mode in [RefMode::Clamp, RefMode::Repeat, RefMode::Mirror] {
        let tex = RefTexture::constant(32, 32, 1, 77);
        for sc in builtin_scenes(SceneSize::Quick) {
            let s = scene_with(tex.clone(), mode, sc.mapping, sc.width, sc.height);
            let img = ideal_image(&s);
            assert!(img.iter().any(|p| p.is_some()));
            for (k, p) in img.iter().enumerate() {
                if let Some(v) = p {
                    assert!(
                        (v - 77.0).abs() < 1e-6,
                        "{} {mode:?} pixel {k}: {v}",
                        sc.name
                    );
                }
                let (px, py) = (k % s.width, k / s.width);
                if let Some(f) = s.mapping.footprint(px as f64 + 0.5, py as f64 + 0.5) {
                    let e = ewa_gaussian(&s.texture, mode, &f);
                    assert!((e - 77.0).abs() < 1e-9, "{} EWA {e}", sc.name);
                }
            }
        }
    }
}

fn bilinear(tex: &RefTexture, mode: RefMode, u: f64, v: f64) -> f64 {
    let (x, y) = (u - 0.5, v - 0.5);
    let (i, j) = (x.floor() as i64, y.floor() as i64);
    let (fx, fy) = (x - i as f64, y - j as f64);
    let t = |a: i64, b: i64| tex.texel_ext(mode, a, b, 0) as f64;
    let top = t(i, j) * (1.0 - fx) + t(i + 1, j) * fx;
    let bot = t(i, j + 1) * (1.0 - fx) + t(i + 1, j + 1) * fx;
    top * (1.0 - fy) + bot * fy
}

#[test]
fn ewa_of_magnified_footprint_is_close_to_bilinear() {
    // A smooth texture: a ramp plus a slow sine; magnified 8x (derivatives 1/8).
    let n = 32;
    let texels = (0..n * n)
        .map(|k| {
            let (i, j) = ((k % n) as f64, (k / n) as f64);
            (40.0 + 4.0 * i + 2.0 * j + 10.0 * (j / 5.0).sin()).round() as u32
        })
        .collect();
    let tex = RefTexture::new(n, n, 1, texels);
    let mut rng = texsat_host_tests::rng(4);
    let mut worst: f64 = 0.0;
    for _ in 0..200 {
        let u = 6.0 + (rng.random_range(0..20_000) as f64) / 1000.0;
        let v = 6.0 + (rng.random_range(0..20_000) as f64) / 1000.0;
        let fp = Footprint {
            u,
            v,
            du_dx: 0.125,
            du_dy: 0.0,
            dv_dx: 0.0,
            dv_dy: 0.125,
        };
        let e = ewa_gaussian(&tex, RefMode::Clamp, &fp);
        let b = bilinear(&tex, RefMode::Clamp, u, v);
        worst = worst.max((e - b).abs());
    }
    // A Gaussian of radius ~1 texel over a texture with a gradient of ~4.5 per texel: the
    // discrete, truncated weights are not exactly centred, a fraction of a gradient.
    assert!(worst < 2.5, "EWA vs bilinear: {worst}");
}

#[test]
fn ewa_ellipse_is_the_pulled_back_pixel_circle() {
    let fp = Footprint {
        u: 0.0,
        v: 0.0,
        du_dx: 3.0,
        du_dy: 1.0,
        dv_dx: -0.5,
        dv_dy: 2.0,
    };
    let e = EwaEllipse::new(&fp);
    let det = 3.0 * 2.0 - 1.0 * (-0.5);
    assert!((e.f - (e.a * e.c - e.b * e.b / 4.0)).abs() < 1e-9);
    // Without the +1 terms the ellipse Q = F is the image of the unit screen circle: check on
    // the conic with A-1, C-1 and F' = det^2.
    let (a, b, c) = (e.a - 1.0, e.b, e.c - 1.0);
    for k in 0..16 {
        let t = k as f64 * std::f64::consts::TAU / 16.0;
        let (x, y) = (t.cos(), t.sin());
        let du = fp.du_dx * x + fp.du_dy * y;
        let dv = fp.dv_dx * x + fp.dv_dy * y;
        let q = a * du * du + b * du * dv + c * dv * dv;
        assert!((q - det * det).abs() < 1e-9 * det * det);
    }
    // The bounding box half extents touch the ellipse.
    let (uh, vh) = e.half_extents();
    let (lo, hi) = e.du_range(0.0).unwrap();
    assert!(hi <= uh + 1e-12 && -lo <= uh + 1e-12);
    assert!(e.du_range(vh * 1.0001).is_none());
}

#[test]
fn ewa_ellipse_is_oriented_along_the_compression() {
    // Diagonal stripes: value depends on (i + j), period 8 (4 texels 255, 4 texels 0).
    let n = 64;
    let texels = (0..n * n)
        .map(|k| {
            if ((k % n + k / n) / 4) % 2 == 0 {
                255
            } else {
                0
            }
        })
        .collect();
    let tex = RefTexture::new(n, n, 1, texels);
    // J = R(theta) diag(24, 0.2): screen x compresses along the texture direction
    // (cos theta, sin theta); screen y barely moves.
    let fp_along = |theta: f64| {
        let (s, c) = f64::sin_cos(theta);
        Footprint {
            u: 31.3,
            v: 31.2,
            du_dx: 24.0 * c,
            du_dy: -0.2 * s,
            dv_dx: 24.0 * s,
            dv_dy: 0.2 * c,
        }
    };
    // Across the stripes (along (1, 1)): many periods average to ~127.5.
    let across = ewa_gaussian(
        &tex,
        RefMode::Repeat,
        &fp_along(std::f64::consts::FRAC_PI_4),
    );
    assert!((across - 127.5).abs() < 12.0, "{across}");
    // Along the stripes (along (1, -1)): the ellipse's short axis (radius ~1.02 texels, i.e.
    // +-1.44 in i + j) stays inside the 0-stripe whose texel centres have i + j + 1 in 61..=64
    // ((u, v) sums to 62.5, the stripe's middle).
    let along = ewa_gaussian(
        &tex,
        RefMode::Repeat,
        &fp_along(-std::f64::consts::FRAC_PI_4),
    );
    assert!(along < 1e-9, "{along}");
}

#[test]
fn ewa_row_walk_matches_bounding_box_brute_force_and_cap_is_close() {
    let tex = RefTexture::random(64, 64, 1, 255, 21);
    let mut rng = texsat_host_tests::rng(5);
    let f = |rng: &mut TestRng, s: f64| s * ((rng.random_range(0..20_001) as f64) / 10_000.0 - 1.0);
    for case in 0..40 {
        let s = if case % 4 == 0 { 20.0 } else { 3.0 };
        let fp = Footprint {
            u: 30.0 + f(&mut rng, 40.0),
            v: 30.0 + f(&mut rng, 40.0),
            du_dx: f(&mut rng, s),
            du_dy: f(&mut rng, s),
            dv_dx: f(&mut rng, s),
            dv_dy: f(&mut rng, s),
        };
        let mode = RefMode::ALL[case % 4];
        let e = EwaEllipse::new(&fp);
        let (uh, vh) = e.half_extents();
        let (mut sw, mut swt) = (0.0, 0.0);
        for j in (fp.v - vh - 2.0).floor() as i64..=(fp.v + vh + 2.0).ceil() as i64 {
            for i in (fp.u - uh - 2.0).floor() as i64..=(fp.u + uh + 2.0).ceil() as i64 {
                let r2 = e.q(i as f64 + 0.5 - fp.u, j as f64 + 0.5 - fp.v) / e.f;
                if r2 < 1.0 {
                    let w = (-2.0 * r2).exp();
                    sw += w;
                    swt += w * tex.texel_ext(mode, i, j, 0) as f64;
                }
            }
        }
        let want = swt / sw;
        let got = ewa_gaussian(&tex, mode, &fp);
        assert!((got - want).abs() < 1e-9, "case {case}: {got} vs {want}");
        if e.area() > 2000.0 {
            // A cap of a tenth of the area: one jittered texel per ~10-texel block.
            let capped = ewa_gaussian_capped(&tex, mode, &fp, e.area() / 10.0);
            assert!(
                (capped - want).abs() < 12.0,
                "case {case}: capped {capped} vs {want}"
            );
        }
    }
}

#[test]
fn ewa_subsampling_does_not_alias_with_a_periodic_checkerboard() {
    // A 0/255 checkerboard with 2-texel squares and a huge isotropic footprint: one texel per
    // block with a regular stride of 4 would see a single colour; the jitter sees both.
    let tex = checkerboard(64, 2, 0, 255);
    let fp = Footprint {
        u: 1000.0,
        v: 1000.0,
        du_dx: 300.0,
        du_dy: 0.0,
        dv_dx: 0.0,
        dv_dy: 300.0,
    };
    let full = ewa_gaussian(&tex, RefMode::Repeat, &fp);
    let capped = ewa_gaussian_capped(&tex, RefMode::Repeat, &fp, 20_000.0);
    assert!((full - 127.5).abs() < 1.0, "{full}");
    assert!((capped - 127.5).abs() < 6.0, "{capped}");
}

#[test]
fn scenes_are_deterministic_and_well_formed() {
    let a = builtin_scenes(SceneSize::Quick);
    let b = builtin_scenes(SceneSize::Quick);
    let names: Vec<&str> = a.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "crow-vertical",
            "crow-lateral",
            "crow-horizontal",
            "crow-stripes-cylinder",
            "heckbert-checker-plane",
            "zone-plate",
            "noise"
        ]
    );
    for (s, t) in a.iter().zip(&b) {
        assert_eq!(s.texture, t.texture);
        assert_eq!((s.width, s.height, s.mode), (t.width, t.height, t.mode));
        assert_eq!((s.width, s.height), (48, 48));
        assert_eq!(s.texture.channels, 1);
        assert!(s.texture.max_texel() <= 255);
        assert!(s.texture.width.is_power_of_two() && s.texture.height.is_power_of_two());
        assert!(!s.description.is_empty());
        for k in 0..40 {
            let (px, py) = (k % s.width, 20 + k / s.width);
            let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
            assert_eq!(s.mapping.footprint(x, y), t.mapping.footprint(x, y));
            assert_eq!(ideal_pixel(s, px, py), ideal_pixel(t, px, py));
        }
    }
    for size in [SceneSize::Default, SceneSize::Full] {
        let d = size.dims();
        for s in builtin_scenes(size) {
            assert_eq!((s.width, s.height), (d.width, d.height));
            assert_eq!(s.texture.width, d.texture);
        }
    }
}

#[test]
fn quick_ideal_images_cover_the_surface() {
    for s in builtin_scenes(SceneSize::Quick) {
        let img = ideal_image(&s);
        assert_eq!(img.len(), s.width * s.height);
        let some = img.iter().filter(|p| p.is_some()).count();
        assert!(some > s.width * s.height / 2, "{}: {some} pixels", s.name);
        for v in img.iter().flatten() {
            assert!((-1e-6..=255.0 + 1e-6).contains(v), "{}: {v}", s.name);
        }
        // Sequential pixels agree with the threaded image.
        for k in (0..img.len()).step_by(97) {
            assert_eq!(
                ideal_pixel(&s, k % s.width, k / s.width),
                img[k],
                "{}",
                s.name
            );
        }
    }
}

#[test]
fn planes_miss_above_the_horizon_only() {
    let scenes = builtin_scenes(SceneSize::Quick);
    for (name, horizon) in [("heckbert-checker-plane", 12usize), ("noise", 6)] {
        let s = scenes.iter().find(|s| s.name == name).unwrap();
        for py in 0..s.height {
            let hit = s.mapping.footprint(10.5, py as f64 + 0.5).is_some();
            assert_eq!(hit, py >= horizon, "{name} row {py}");
            assert_eq!(
                ideal_pixel(s, 10, py).is_some(),
                py > horizon,
                "{name} row {py}"
            );
        }
    }
}

#[test]
fn crow_planes_compress_along_their_axis() {
    let scenes = builtin_scenes(SceneSize::Default);
    let get = |n: &str| scenes.iter().find(|s| s.name == n).unwrap();
    let len = |a: f64, b: f64| (a * a + b * b).sqrt();
    // Vertical: top row compressed ~32 texels/pixel along y, ~3 along x; bottom ~2 and ~0.75.
    let v = get("crow-vertical");
    let top = v.mapping.footprint(80.0, 0.0).unwrap();
    let bot = v.mapping.footprint(80.0, 120.0).unwrap();
    assert!((len(top.du_dy, top.dv_dy) - 32.0).abs() < 1e-9);
    assert!((len(top.du_dx, top.dv_dx) - 3.0).abs() < 1e-9);
    assert!((len(bot.du_dy, bot.dv_dy) - 2.0).abs() < 1e-9);
    assert!((len(bot.du_dx, bot.dv_dx) - 0.75).abs() < 1e-9);
    // Horizontal: the right edge is the far one.
    let h = get("crow-horizontal");
    let right = h.mapping.footprint(160.0, 60.0).unwrap();
    assert!((len(right.du_dx, right.dv_dx) - 32.0).abs() < 1e-9);
    // Lateral: the far side is the upper right; compression along the diagonal (checked on the
    // line through the centre along it, at q = L = (80 + 60) / sqrt(2)).
    let l = get("crow-lateral");
    let c = l.mapping.footprint(150.0, -10.0).unwrap();
    let (d, e) = (
        std::f64::consts::FRAC_1_SQRT_2,
        std::f64::consts::FRAC_1_SQRT_2,
    );
    let along = len(c.du_dx * d - c.du_dy * e, c.dv_dx * d - c.dv_dy * e);
    assert!((along - 32.0).abs() < 1e-9, "{along}");
}

#[test]
fn cylinder_derivatives_match_finite_differences() {
    let c = Cylinder {
        cx: 80.0,
        cy: 60.0,
        radius: 50.0,
        tilt: 0.35,
        u_per_radian: 70.0,
        u0: 10.0,
        v_per_pixel: 1.3,
        v0: -4.0,
        subdivisions: 8,
    };
    let h = 1e-6;
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-5 * (1.0 + b.abs());
    let mut checked = 0;
    for k in 0..200 {
        let (x, y) = (20.0 + (k % 20) as f64 * 6.1, 5.0 + (k / 20) as f64 * 11.3);
        let Some(f) = c.footprint(x, y) else { continue };
        let (a, _) = c.axis_coords(x, y);
        if a.abs() > 0.98 * c.radius {
            continue; // too close to the silhouette for central differences
        }
        let (u1, v1) = c.map(x + h, y).unwrap();
        let (u0, v0) = c.map(x - h, y).unwrap();
        assert!(close(f.du_dx, (u1 - u0) / (2.0 * h)), "du/dx at ({x}, {y})");
        assert!(close(f.dv_dx, (v1 - v0) / (2.0 * h)));
        let (u1, v1) = c.map(x, y + h).unwrap();
        let (u0, v0) = c.map(x, y - h).unwrap();
        assert!(close(f.du_dy, (u1 - u0) / (2.0 * h)), "du/dy at ({x}, {y})");
        assert!(close(f.dv_dy, (v1 - v0) / (2.0 * h)));
        checked += 1;
    }
    assert!(checked > 100, "{checked}");
    // Beyond the silhouette: none.
    assert!(c.footprint(80.0 + 60.0, 60.0).is_none());
}

#[test]
fn cylinder_ideal_converges_and_matches_the_exact_rectangle_untilted() {
    // Untilted, u depends on x only and v on y only, so a pixel's pre-image is exactly the
    // rectangle [u(x0), u(x1)] x [v(y0), v(y1)]: the box integral.
    let tex = stripes(64, 8, 0, 255);
    let cyl = |tilt: f64, n: usize| Cylinder {
        cx: 24.0,
        cy: 24.0,
        radius: 20.0,
        tilt,
        u_per_radian: 30.0,
        u0: 32.25,
        v_per_pixel: 0.8,
        v0: 5.0,
        subdivisions: n,
    };
    let s0 = scene_with(tex.clone(), RefMode::Repeat, Box::new(cyl(0.0, 4)), 48, 48);
    let c0 = cyl(0.0, 4);
    for px in [5usize, 6, 10, 24, 38, 42] {
        let py = 17;
        let (u0, v0) = c0.map(px as f64, py as f64).unwrap();
        let (u1, v1) = c0.map(px as f64 + 1.0, py as f64 + 1.0).unwrap();
        let want = tex.box_integral(RefMode::Repeat, u0, v0, u1, v1, 0) / ((u1 - u0) * (v1 - v0));
        let got = ideal_pixel(&s0, px, py).unwrap();
        // The piecewise-linear pre-image of the curved edges is exact here (they are straight
        // lines u = const), so only rounding remains.
        assert!((got - want).abs() < 1e-6, "px {px}: {got} vs {want}");
    }
    assert_eq!(ideal_pixel(&s0, 3, 17), None, "straddles the silhouette");
    // Tilted: 4x4 and 8x8 sub-squares against 32x32, and the point-sampled supersampling.
    let coarse = scene_with(tex.clone(), RefMode::Repeat, Box::new(cyl(0.4, 4)), 48, 48);
    let mid = scene_with(tex.clone(), RefMode::Repeat, Box::new(cyl(0.4, 8)), 48, 48);
    let fine = scene_with(tex.clone(), RefMode::Repeat, Box::new(cyl(0.4, 32)), 48, 48);
    let (mut e4, mut e8, mut n) = (0.0, 0.0, 0);
    for (px, py) in [
        (8usize, 20usize),
        (10, 30),
        (24, 24),
        (36, 18),
        (40, 30),
        (12, 12),
        (33, 40),
    ] {
        let Some(f) = ideal_pixel(&fine, px, py) else {
            continue;
        };
        let a = ideal_pixel(&coarse, px, py).unwrap();
        let b = ideal_pixel(&mid, px, py).unwrap();
        let ss = supersample_pixel(&fine, px, py, 128).unwrap();
        assert!(
            (ss - f).abs() < 6.0,
            "({px}, {py}): supersampled {ss} vs {f}"
        );
        e4 += (a - f).abs();
        e8 += (b - f).abs();
        n += 1;
    }
    assert!(n >= 5);
    assert!(e8 <= e4 + 1e-9, "8x8 error {e8} vs 4x4 {e4}");
    assert!(e8 / n as f64 <= 0.5, "mean 8x8 error {}", e8 / n as f64);
}

#[test]
fn image_scene_reads_a_png_as_luma() {
    let dir = std::env::temp_dir().join(format!("texsat-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("tiny_rgb.png");
    let (w, h) = (12u32, 8u32);
    let img = image::RgbImage::from_fn(w, h, |x, y| {
        image::Rgb([(x * 20) as u8, (y * 30) as u8, 200])
    });
    img.save(&path).unwrap();
    let s = image_scene(&path, SceneSize::Quick).unwrap();
    assert_eq!(s.name, "tiny_rgb");
    assert_eq!(
        (s.texture.width, s.texture.height, s.texture.channels),
        (12, 8, 1)
    );
    assert_eq!((s.width, s.height), (48, 48));
    let luma = image::DynamicImage::ImageRgb8(img).to_luma8();
    for y in 0..h {
        for x in 0..w {
            assert_eq!(
                s.texture.texel(x as usize, y as usize, 0),
                luma.get_pixel(x, y).0[0] as u32
            );
        }
    }
    // A PGM too, and an error for a missing file.
    let gray = image::GrayImage::from_fn(4, 4, |x, y| image::Luma([(x * 60 + y) as u8]));
    let pgm = dir.join("g.pgm");
    gray.save(&pgm).unwrap();
    let g = image_scene(&pgm, SceneSize::Quick).unwrap();
    assert_eq!(g.texture.texel(3, 2, 0), 182);
    assert!(ideal_image(&g).iter().any(|p| p.is_some()));
    assert!(image_scene(&dir.join("missing.png"), SceneSize::Quick).is_err());
    std::fs::remove_dir_all(&dir).ok();
}

/// Release-mode timing of the Default scenes' ideal images (and EWA over every pixel):
/// `cargo test --release -p texsat-host-tests --test scenes -- --ignored --nocapture`.
#[test]
#[ignore]
fn timing_default_ideal_images() {
    for size in [SceneSize::Default, SceneSize::Full] {
        let mut total = 0.0;
        for s in builtin_scenes(size) {
            let t = std::time::Instant::now();
            let img = ideal_image(&s);
            let dt = t.elapsed().as_secs_f64();
            total += dt;
            let t = std::time::Instant::now();
            let mut err = 0.0;
            let mut cnt = 0;
            for (k, p) in img.iter().enumerate() {
                let (px, py) = (k % s.width, k / s.width);
                if let (Some(v), Some(f)) =
                    (p, s.mapping.footprint(px as f64 + 0.5, py as f64 + 0.5))
                {
                    let e = ewa_gaussian(&s.texture, s.mode, &f);
                    err += (e - v) * (e - v);
                    cnt += 1;
                }
            }
            let de = t.elapsed().as_secs_f64();
            println!(
                "{size:?} {:24} ideal {:7.3} s  EWA {:7.3} s  EWA rmse vs ideal {:6.2} ({} px)",
                s.name,
                dt,
                de,
                (err / cnt.max(1) as f64).sqrt(),
                cnt
            );
        }
        println!("{size:?} total ideal {total:.3} s");
    }
}

/// Writes the Default scenes' ideal images and EWA renders as PNGs to
/// `$TMPDIR/texsat-scenes-preview` for eyeballing:
/// `cargo test --release -p texsat-host-tests --test scenes -- --ignored preview`.
#[test]
#[ignore]
fn preview_default_scenes() {
    let dir = std::env::temp_dir().join("texsat-scenes-preview");
    std::fs::create_dir_all(&dir).unwrap();
    for s in builtin_scenes(SceneSize::Default) {
        let img = ideal_image(&s);
        let (w, h) = (s.width as u32, s.height as u32);
        let mut out = image::RgbImage::new(2 * w, h);
        for (k, p) in img.iter().enumerate() {
            let (x, y) = ((k % s.width) as u32, (k / s.width) as u32);
            let ideal = match p {
                Some(v) => image::Rgb([v.round() as u8; 3]),
                None => image::Rgb([40, 60, 120]),
            };
            out.put_pixel(x, y, ideal);
            let f = s.mapping.footprint(x as f64 + 0.5, y as f64 + 0.5);
            let e = match f {
                Some(f) => image::Rgb([ewa_gaussian(&s.texture, s.mode, &f).round() as u8; 3]),
                None => image::Rgb([40, 60, 120]),
            };
            out.put_pixel(w + x, y, e);
        }
        out.save(dir.join(format!("{}.png", s.name))).unwrap();
    }
    println!("wrote {}", dir.display());
}
