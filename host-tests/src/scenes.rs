//! Test scenes for the filter report, and their *ideal* images.
//!
//! A [`Scene`] is a generated 8-bit texture, a boundary mode, and a [`Mapping`] from screen
//! `(x, y)` (pixels; x right, y down; the centre of pixel `(px, py)` is `(px + 0.5, py + 0.5)`)
//! to texture `(u, v)` (texels; texel `(i, j)` covers `[i, i + 1) x [j, j + 1)`). The scenes
//! are the ones the papers used to show filter weaknesses (Crow 1984, figures 3 and 5-7;
//! Heckbert's survey, figure 5), plus a zone plate and value noise under anisotropic
//! minification. Everything is generated; nothing is downloaded.
//!
//! # The ideal
//!
//! [`ideal_pixel`] is the mean of the extended texture (the scene's mode decides what lies
//! outside the texture) over the pixel's true pre-image: the image in texture space of the
//! pixel square `[px, px + 1) x [py, py + 1)`. That is the box-filtered pixel, the quantity
//! every prefilter in the report approximates.
//!
//! * **Planar mappings** ([`crate::footprint::Perspective`], affine included): a homography
//!   maps lines to lines, so the pre-image of the pixel square is exactly the quadrilateral of
//!   its four mapped corners, and it is convex (the square does not cross the horizon line
//!   `W = 0` when `W > 0` at all four corners). The mean over it is computed **exactly** (up to
//!   `f64` rounding) by [`polygon_integral`]: `sum over texels of value * area(quad ∩ cell) /
//!   area(quad)`, by clipping the quadrilateral into texel-column strips and each strip into
//!   texel cells (Sutherland-Hodgman against axis-aligned lines). Cells completely inside a
//!   strip are not clipped: their run is summed from per-column prefix sums of the extended
//!   texture ([`ExtendedColumns`], closed form for every boundary mode), so the cost is the
//!   quadrilateral's perimeter in texels, not its area — pixels next to the horizon, whose
//!   pre-images cover millions of texels, cost a few thousand clips.
//! * **Curved mappings** ([`Cylinder`]): the pixel is cut into `n x n` sub-squares
//!   ([`Mapping::ideal_subdivisions`], 8 x 8 in the built-in cylinder scene at
//!   [`SceneSize::Default`]) and each sub-square's pre-image is replaced by the quadrilateral
//!   of its mapped corners (a piecewise-linear approximation of the curved pre-image), then
//!   integrated exactly as above; the mean is the sum of the integrals over the sum of the
//!   areas. This is the texture-space mean `∫ t(m(s)) |det J(s)| ds / ∫ |det J(s)| ds` of the
//!   brief, with the inner integral done exactly per sub-square instead of by point samples:
//!   next to the silhouettes a pixel covers dozens of stripes, and point-sampled supersampling
//!   (kept as [`supersample_pixel`] for the tests) aliases there, while the piecewise-linear
//!   pre-image only errs by the curvature of the mapping inside a sub-square (`O(1/n^2)` of
//!   the area). Non-convex sub-quadrilaterals are integrated as two signed triangles.
//!
//! A pixel any part of which misses the surface (a corner of the pixel or of a sub-square maps
//! to `None`: beyond the horizon, off the cylinder) has no ideal (`None`). If a pre-image is so
//! large that even the perimeter walk would exceed [`MAX_BOUNDARY_CELLS`] clipped cells, the
//! ideal falls back to Jacobian-weighted supersampling with 64 x 64 samples (no built-in scene
//! gets there).

use crate::ewa::EwaEllipse;
use crate::footprint::{Footprint, Perspective};
use crate::{RefMode, RefTexture, Rng};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

/// A screen-to-texture mapping.
pub trait Mapping: Send + Sync {
    /// Texture (u, v) in texels and its analytic derivatives at screen point (x, y) (continuous
    /// screen coordinates; the centre of pixel (px, py) is (px + 0.5, py + 0.5)). None where the
    /// point misses the surface (beyond the horizon).
    fn footprint(&self, x: f64, y: f64) -> Option<Footprint>;

    /// Texture `(u, v)` of screen `(x, y)` (default: the footprint's position).
    fn map(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        self.footprint(x, y).map(|f| (f.u, f.v))
    }

    /// How finely [`ideal_pixel`] cuts a pixel (`n x n` sub-squares, each pre-image replaced by
    /// the quadrilateral of its mapped corners). `1` is exact for homographies; the default `8`
    /// is for curved mappings.
    fn ideal_subdivisions(&self) -> usize {
        8
    }
}

impl Mapping for Perspective {
    fn footprint(&self, x: f64, y: f64) -> Option<Footprint> {
        Perspective::footprint(self, x, y)
    }

    fn map(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        Perspective::map(self, x, y)
    }

    /// A homography maps the pixel square exactly onto the quadrilateral of its corners.
    fn ideal_subdivisions(&self) -> usize {
        1
    }
}

/// An infinite cylinder seen from the side in orthographic projection, texture wrapped around
/// it (Crow 1984, figure 3: stripes on a curved surface compress toward the silhouettes).
///
/// With `d = (x - cx, y - cy)`, the across-axis coordinate is `a = d . (cos t, -sin t)` and the
/// along-axis one `b = d . (sin t, cos t)` (`t` = [`Cylinder::tilt`]; `t = 0` is a vertical
/// axis). The visible half of the cylinder has `|a| < R`, at angle `asin(a / R)` around the
/// axis, so
///
/// ```text
/// u = u0 + k asin(a / R)        v = v0 + s b
/// du/dx = k cos t / sqrt(R^2 - a^2)     du/dy = -k sin t / sqrt(R^2 - a^2)
/// dv/dx = s sin t                        dv/dy = s cos t
/// ```
///
/// with `k` = [`Cylinder::u_per_radian`], `s` = [`Cylinder::v_per_pixel`]. `du/dx` grows without
/// bound toward the silhouettes `|a| = R`; points with `|a| >= R` miss (`None`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Screen x of a point on the axis.
    pub cx: f64,
    /// Screen y of a point on the axis.
    pub cy: f64,
    /// Radius in pixels.
    pub radius: f64,
    /// The axis's angle from the vertical, in radians: the axis direction is `(sin t, cos t)`.
    pub tilt: f64,
    /// Texels of `u` per radian around the axis.
    pub u_per_radian: f64,
    /// `u` on the axis's front line (`a = 0`).
    pub u0: f64,
    /// Texels of `v` per pixel along the axis.
    pub v_per_pixel: f64,
    /// `v` at `b = 0`.
    pub v0: f64,
    /// [`Mapping::ideal_subdivisions`] for this mapping.
    pub subdivisions: usize,
}

impl Cylinder {
    /// `(a, b)`: across and along the axis, in pixels from `(cx, cy)`.
    pub fn axis_coords(&self, x: f64, y: f64) -> (f64, f64) {
        let (s, c) = self.tilt.sin_cos();
        let (dx, dy) = (x - self.cx, y - self.cy);
        (dx * c - dy * s, dx * s + dy * c)
    }
}

impl Mapping for Cylinder {
    fn footprint(&self, x: f64, y: f64) -> Option<Footprint> {
        let (a, b) = self.axis_coords(x, y);
        let r = self.radius;
        if a.is_nan() || a.abs() >= r {
            return None;
        }
        let root = (r * r - a * a).sqrt();
        if root.is_nan() || root <= 0.0 {
            return None;
        }
        let (s, c) = self.tilt.sin_cos();
        let k = self.u_per_radian / root; // du/da
        let fp = Footprint {
            u: self.u0 + self.u_per_radian * (a / r).asin(),
            v: self.v0 + self.v_per_pixel * b,
            du_dx: k * c,
            du_dy: -k * s,
            dv_dx: self.v_per_pixel * s,
            dv_dy: self.v_per_pixel * c,
        };
        let all = [fp.u, fp.v, fp.du_dx, fp.du_dy, fp.dv_dx, fp.dv_dy];
        all.iter().all(|d| d.is_finite()).then_some(fp)
    }

    fn ideal_subdivisions(&self) -> usize {
        self.subdivisions.max(1)
    }
}

/// A test scene: a texture, its boundary mode, and a mapping onto a `width x height` image.
pub struct Scene {
    /// e.g. "crow-vertical", "crow-lateral", "crow-horizontal", "crow-stripes-cylinder",
    /// "heckbert-checker-plane", "zone-plate", "noise", or the PNG's file stem.
    pub name: String,
    /// One line, with the paper figure it reproduces.
    pub description: String,
    /// 1 channel, 8-bit texel values 0..=255.
    pub texture: RefTexture,
    /// Screen to texture.
    pub mapping: Box<dyn Mapping>,
    /// Output width in pixels.
    pub width: usize,
    /// Output height in pixels.
    pub height: usize,
    /// Boundary mode of the scene (Repeat for tiled checkerboards and the tileable noise).
    pub mode: RefMode,
}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("name", &self.name)
            .field("description", &self.description)
            .field("texture", &(self.texture.width, self.texture.height))
            .field("width", &self.width)
            .field("height", &self.height)
            .field("mode", &self.mode)
            .finish_non_exhaustive()
    }
}

/// How large the scenes are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneSize {
    /// CI: 64 x 64 textures, 48 x 48 outputs.
    Quick,
    /// 256 x 256 textures, 160 x 120 outputs.
    Default,
    /// 1024 x 1024 textures, 320 x 240 outputs.
    Full,
}

/// The sizes behind a [`SceneSize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneDims {
    /// Texture side (square, a power of two).
    pub texture: usize,
    /// Output width.
    pub width: usize,
    /// Output height.
    pub height: usize,
    /// Texels-per-pixel scale relative to `Default`: `(texture / 256) * (160 / width)`, so a
    /// scene looks the same at every size.
    pub scale: f64,
    /// [`Cylinder::subdivisions`] of the cylinder scene.
    pub cylinder_subdivisions: usize,
}

impl SceneSize {
    /// Texture and output sizes.
    pub fn dims(self) -> SceneDims {
        let (texture, width, height, n) = match self {
            SceneSize::Quick => (64, 48, 48, 4),
            SceneSize::Default => (256, 160, 120, 8),
            SceneSize::Full => (1024, 320, 240, 12),
        };
        SceneDims {
            texture,
            width,
            height,
            scale: (texture as f64 / 256.0) * (160.0 / width as f64),
            cylinder_subdivisions: n,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Textures.

/// A `n x n` checkerboard of squares `square` texels wide, `lo` on the squares whose indices
/// sum to an even number (the top-left one), `hi` on the others.
pub fn checkerboard(n: usize, square: usize, lo: u32, hi: u32) -> RefTexture {
    let square = square.max(1);
    let texels = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            if (i / square + j / square).is_multiple_of(2) {
                lo
            } else {
                hi
            }
        })
        .collect();
    RefTexture::new(n, n, 1, texels)
}

/// `n x n` vertical stripes (varying along `u` only): `period / 2` texels of `hi`, then
/// `period / 2` of `lo`.
pub fn stripes(n: usize, period: usize, lo: u32, hi: u32) -> RefTexture {
    let half = (period / 2).max(1);
    let texels = (0..n * n)
        .map(|k| {
            if (k % n / half).is_multiple_of(2) {
                hi
            } else {
                lo
            }
        })
        .collect();
    RefTexture::new(n, n, 1, texels)
}

/// A `n x n` zone plate: `round(127.5 + 127.5 cos(pi r^2 / n))` with `r` the distance of the
/// texel centre from the texture centre. The local frequency is `r / n` cycles per texel: it
/// rises linearly from 0 at the centre to the Nyquist limit (1/2) at the middle of each edge
/// (and beyond it, toward the corners).
pub fn zone_plate(n: usize) -> RefTexture {
    let c = n as f64 / 2.0;
    let texels = (0..n * n)
        .map(|k| {
            let x = (k % n) as f64 + 0.5 - c;
            let y = (k / n) as f64 + 0.5 - c;
            let phase = core::f64::consts::PI * (x * x + y * y) / n as f64;
            (127.5 + 127.5 * phase.cos()).round().clamp(0.0, 255.0) as u32
        })
        .collect();
    RefTexture::new(n, n, 1, texels)
}

/// Smooth, tileable `n x n` value noise: four octaves with lattice cells of `n/4`, `n/8`,
/// `n/16`, `n/32` texels (at least 2) and amplitudes `1, 1/2, 1/4, 1/8`; each octave is a
/// periodic lattice of random values (wrapping, so the texture tiles seamlessly under
/// `Repeat`) interpolated with smoothstep weights at the texel centres. The sum is stretched to
/// `0..=255` and rounded. Reproducible from `seed`.
pub fn value_noise(n: usize, seed: u64) -> RefTexture {
    let mut acc = vec![0.0f64; n * n];
    let mut amp = 1.0;
    for octave in 0..4 {
        let cell = (n >> (2 + octave)).max(2);
        let lattice = n.div_ceil(cell).max(1);
        let mut rng = crate::rng(seed.wrapping_add(0x5EED_0000 + octave as u64));
        let values: Vec<f64> = (0..lattice * lattice)
            .map(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
            .collect();
        let at = |i: usize, j: usize| values[(j % lattice) * lattice + (i % lattice)];
        let smooth = |t: f64| t * t * (3.0 - 2.0 * t);
        for (k, a) in acc.iter_mut().enumerate() {
            let x = ((k % n) as f64 + 0.5) / cell as f64;
            let y = ((k / n) as f64 + 0.5) / cell as f64;
            let (i, j) = (x.floor() as usize, y.floor() as usize);
            let (fx, fy) = (smooth(x - i as f64), smooth(y - j as f64));
            let top = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
            let bottom = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
            *a += amp * (top + (bottom - top) * fy);
        }
        amp /= 2.0;
    }
    let lo = acc.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = acc.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = if hi > lo { hi - lo } else { 1.0 };
    let texels = acc
        .iter()
        .map(|&a| ((a - lo) / span * 255.0).round().clamp(0.0, 255.0) as u32)
        .collect();
    RefTexture::new(n, n, 1, texels)
}

// ---------------------------------------------------------------------------------------------
// Mappings.

/// A linear form `c[0] x + c[1] y + c[2]`.
type Form = [f64; 3];

fn combine(terms: &[(f64, Form)]) -> Form {
    let mut out = [0.0; 3];
    for (k, f) in terms {
        for (o, v) in out.iter_mut().zip(f) {
            *o += k * v;
        }
    }
    out
}

/// A square of checkerboard seen in perspective, compressed along one screen direction (Crow's
/// figures 5-7). The plane is tilted away from the viewer about the axis perpendicular to the
/// unit screen direction `far = (cos phi, sin phi)` (pointing to the far side), through the
/// image centre `(cx, cy)`. With `q = (x - cx, y - cy) . far` (along the compression),
/// `p = (x - cx, y - cy) . (-sin phi, cos phi)` (across it) and `W = 1 - kappa q`:
///
/// ```text
/// (u, v) = (s_a p e + s_b q far) / W + offset      (e = (-sin phi, cos phi))
/// ```
///
/// a homography (texture axes aligned with the screen axes). Along the compression
/// `d(texels)/dq = s_b / W^2`, across it `s_a / W`; `kappa` is chosen so that `W` falls by the
/// factor `rho` from the near edge of the image to the far edge (no horizon inside), and
/// `s_a`, `s_b` so that the near edge has `near_across` and `near_along` texels per pixel. The
/// far edge then has `near_across * rho` and `near_along * rho^2`.
#[allow(clippy::too_many_arguments)]
pub fn squeezed_plane(
    width: usize,
    height: usize,
    phi: f64,
    near_across: f64,
    near_along: f64,
    rho: f64,
    offset: (f64, f64),
) -> Perspective {
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    let (s, c) = phi.sin_cos();
    let far = (c, s);
    let e = (-s, c);
    // Half the image's extent along `far` (the largest |q| at a corner).
    let l = c.abs() * cx + s.abs() * cy;
    let kappa = (rho - 1.0) / ((rho + 1.0) * l);
    let w_near = 1.0 + kappa * l;
    let s_a = near_across * w_near;
    let s_b = near_along * w_near * w_near;
    let p: Form = [e.0, e.1, -(e.0 * cx + e.1 * cy)];
    let q: Form = [far.0, far.1, -(far.0 * cx + far.1 * cy)];
    let w = combine(&[(1.0, [0.0, 0.0, 1.0]), (-kappa, q)]);
    let uu = combine(&[(s_a * e.0, p), (s_b * far.0, q), (offset.0, w)]);
    let vv = combine(&[(s_a * e.1, p), (s_b * far.1, q), (offset.1, w)]);
    Perspective::new([uu, vv, w])
}

/// Heckbert's infinite plane receding to the horizon (survey figure 5): a camera looking
/// horizontally over a ground plane. The horizon is the pixel-row boundary `y = horizon`
/// (`W = y - horizon`, so every row at or above it misses the surface and the row just below
/// it has huge pre-images); with `D = height - horizon`, `m` texels per pixel at the bottom row
/// and the texture rotated by `theta`:
///
/// ```text
/// a = m D (x - cx) / (y - horizon)       b = m D^2 / (y - horizon)
/// (u, v) = R(theta) (a, b) + offset
/// ```
///
/// (`du/dx = m D / (y - horizon)`, `db/dy = -m D^2 / (y - horizon)^2`: at the bottom both are
/// `m`, and the compression along the view grows as the square of the distance, the across
/// one linearly.)
pub fn ground_plane(
    width: usize,
    height: usize,
    horizon: usize,
    m: f64,
    theta: f64,
    offset: (f64, f64),
) -> Perspective {
    let cx = width as f64 / 2.0;
    let yh = horizon as f64;
    let d = (height - horizon) as f64;
    let a: Form = [m * d, 0.0, -m * d * cx];
    let b: Form = [0.0, 0.0, m * d * d];
    let w: Form = [0.0, 1.0, -yh];
    let (s, c) = theta.sin_cos();
    let uu = combine(&[(c, a), (-s, b), (offset.0, w)]);
    let vv = combine(&[(s, a), (c, b), (offset.1, w)]);
    Perspective::new([uu, vv, w])
}

/// An affine anisotropic minification about the image centre: `(u, v) = centre + R(theta)
/// diag(across, along) R(theta)^T (x - cx, y - cy)`, i.e. `along` texels per pixel in the
/// screen direction `(cos theta, sin theta)` and `across` perpendicular to it.
pub fn affine_squeeze(
    width: usize,
    height: usize,
    theta: f64,
    across: f64,
    along: f64,
    centre: (f64, f64),
) -> Perspective {
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    let (s, c) = theta.sin_cos();
    // M = along * f f^T + across * e e^T with f = (c, s), e = (-s, c).
    let m00 = along * c * c + across * s * s;
    let m01 = (along - across) * c * s;
    let m11 = along * s * s + across * c * c;
    Perspective::affine(
        m00,
        m01,
        centre.0 - m00 * cx - m01 * cy,
        m01,
        m11,
        centre.1 - m01 * cx - m11 * cy,
    )
}

/// The built-in scenes (see the crate report docs): Crow's three compressed checkerboards and
/// striped cylinder, Heckbert's checkerboard plane, a zone plate and value noise.
///
/// | name | texture | mapping | mode |
/// |---|---|---|---|
/// | `crow-vertical` | checkerboard, squares `n/16`, 0/255 | [`squeezed_plane`] far side up: along 2 -> 32, across 0.75 -> 3 texels/pixel | Repeat |
/// | `crow-lateral` | same | same, compressed along the diagonal toward the upper right | Repeat |
/// | `crow-horizontal` | same | same, far side right | Repeat |
/// | `crow-stripes-cylinder` | stripes, period `n/32`, 0/255 | [`Cylinder`], radius `0.35 w`, axis tilted 20 degrees, 2 texels/pixel across at the front line (10 at 98% of the radius, unbounded at the silhouettes), 1 along | Repeat |
/// | `heckbert-checker-plane` | checkerboard, squares `n/16`, 0/255 | [`ground_plane`], horizon at `h/4`, 1 texel/pixel at the bottom | Repeat |
/// | `zone-plate` | [`zone_plate`] | [`affine_squeeze`]: 5 texels/pixel along a screen axis at 30 degrees, 1 across | Mirror (the plate is symmetric, so its mirror images continue the rings) |
/// | `noise` | [`value_noise`] | [`ground_plane`], horizon at `h/8`, texture turned 30 degrees | Repeat |
///
/// Texels-per-pixel figures are for [`SceneSize::Default`] and scale with
/// [`SceneDims::scale`].
pub fn builtin_scenes(size: SceneSize) -> Vec<Scene> {
    let d = size.dims();
    let (n, w, h, r) = (d.texture, d.width, d.height, d.scale);
    let nf = n as f64;
    let deg = core::f64::consts::PI / 180.0;
    let board = || checkerboard(n, n / 16, 0, 255);
    let mut out = Vec::new();
    let crow = |name: &str, phi: f64, what: &str, fig: u32| Scene {
        name: name.into(),
        description: format!(
            "Crow 1984 fig. {fig}: checkerboard on a square in perspective, compressed {what} \
             (2 -> 32 texels/pixel along, 0.75 -> 3 across)"
        ),
        texture: board(),
        mapping: Box::new(squeezed_plane(
            w,
            h,
            phi,
            0.75 * r,
            2.0 * r,
            4.0,
            (nf / 2.0 + 0.3, nf / 2.0 + 0.7),
        )),
        width: w,
        height: h,
        mode: RefMode::Repeat,
    };
    out.push(crow("crow-vertical", -90.0 * deg, "vertically", 5));
    out.push(crow(
        "crow-lateral",
        -45.0 * deg,
        "laterally (along the diagonal, oblique to the texture axes)",
        6,
    ));
    out.push(crow("crow-horizontal", 0.0, "horizontally", 7));
    let radius = 0.35 * w as f64;
    out.push(Scene {
        name: "crow-stripes-cylinder".into(),
        description: "Crow 1984 fig. 3: stripes wrapped around a cylinder (axis tilted 20 deg), \
                      compressing toward the silhouettes"
            .into(),
        texture: stripes(n, n / 32, 0, 255),
        mapping: Box::new(Cylinder {
            cx: w as f64 / 2.0,
            cy: h as f64 / 2.0,
            radius,
            tilt: 20.0 * deg,
            u_per_radian: 2.0 * r * radius,
            u0: nf / 2.0 + 0.25,
            v_per_pixel: r,
            v0: nf / 2.0,
            subdivisions: d.cylinder_subdivisions,
        }),
        width: w,
        height: h,
        mode: RefMode::Repeat,
    });
    out.push(Scene {
        name: "heckbert-checker-plane".into(),
        description: "Heckbert survey fig. 5: checkerboard plane in perspective receding to the \
                      horizon"
            .into(),
        texture: board(),
        mapping: Box::new(ground_plane(w, h, h / 4, r, 0.0, (nf / 2.0 + 0.3, 0.0))),
        width: w,
        height: h,
        mode: RefMode::Repeat,
    });
    out.push(Scene {
        name: "zone-plate".into(),
        description: "zone plate (rising frequency) under affine anisotropic minification, \
                      5 x 1 texels/pixel along a 30 deg axis"
            .into(),
        texture: zone_plate(n),
        mapping: Box::new(affine_squeeze(
            w,
            h,
            30.0 * deg,
            r,
            5.0 * r,
            (nf / 2.0, nf / 2.0),
        )),
        width: w,
        height: h,
        mode: RefMode::Mirror,
    });
    out.push(Scene {
        name: "noise".into(),
        description: "smooth value noise (4 octaves, tileable) on a plane receding to the \
                      horizon, texture turned 30 deg"
            .into(),
        texture: value_noise(n, 0x007E_55A7),
        mapping: Box::new(ground_plane(
            w,
            h,
            h / 8,
            r,
            30.0 * deg,
            (nf / 2.0 + 0.4, nf / 3.0),
        )),
        width: w,
        height: h,
        mode: RefMode::Repeat,
    });
    out
}

/// A scene from any PNG or PGM file (converted to 8-bit luma), on Heckbert's receding plane
/// ([`ground_plane`], horizon at `h/4`, the texture's width spanning the image's width at the
/// bottom row), [`RefMode::Repeat`]. The output size follows `size`; the texture keeps its own
/// size. Named after the file stem.
pub fn image_scene(path: &std::path::Path, size: SceneSize) -> Result<Scene, String> {
    let img = image::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let luma = img.to_luma8();
    let (tw, th) = (luma.width() as usize, luma.height() as usize);
    if tw == 0 || th == 0 {
        return Err(format!("{}: empty image", path.display()));
    }
    let texels = luma.into_raw().into_iter().map(u32::from).collect();
    let texture = RefTexture::new(tw, th, 1, texels);
    let d = size.dims();
    let (w, h) = (d.width, d.height);
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".into());
    let m = tw as f64 / w as f64;
    Ok(Scene {
        description: format!(
            "{} ({tw} x {th}, luma) on Heckbert's plane receding to the horizon (survey fig. 5 \
             mapping), Repeat",
            path.file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        ),
        name,
        texture,
        mapping: Box::new(ground_plane(
            w,
            h,
            h / 4,
            m,
            0.0,
            (tw as f64 / 2.0, th as f64 / 3.0),
        )),
        width: w,
        height: h,
        mode: RefMode::Repeat,
    })
}

// ---------------------------------------------------------------------------------------------
// Exact integration over polygons.

/// The largest number of clipped (partial) cells plus columns one [`polygon_integral`] call
/// walks before giving up (`None`), and [`ideal_pixel`] falls back to supersampling.
pub const MAX_BOUNDARY_CELLS: usize = 20_000_000;

/// Full-cell runs shorter than this are summed texel by texel instead of from the column
/// prefix sums (which are built lazily, a column at a time).
const PREFIX_MIN_RUN: i64 = 24;

/// The extended texture (channel 0) under a boundary mode, with lazily built per-column
/// prefix sums so a run of cells in one column sums in closed form for every mode
/// (`Border`: zero outside; `Clamp`: the edge texel repeated; `Repeat`: whole periods plus a
/// remainder; `Mirror`: period `2h`, the second half reflected).
pub struct ExtendedColumns<'a> {
    tex: &'a RefTexture,
    mode: RefMode,
    prefix: Vec<OnceLock<Vec<f64>>>,
}

impl<'a> ExtendedColumns<'a> {
    /// The extended texture of `tex` under `mode` (no work until a column is summed).
    pub fn new(tex: &'a RefTexture, mode: RefMode) -> Self {
        ExtendedColumns {
            tex,
            mode,
            prefix: (0..tex.width).map(|_| OnceLock::new()).collect(),
        }
    }

    /// Texel `(i, j)` of the extended texture.
    pub fn texel(&self, i: i64, j: i64) -> f64 {
        self.tex.texel_ext(self.mode, i, j, 0) as f64
    }

    fn column_prefix(&self, k: usize) -> &[f64] {
        self.prefix[k].get_or_init(|| {
            let mut p = Vec::with_capacity(self.tex.height + 1);
            let mut s = 0.0;
            p.push(0.0);
            for j in 0..self.tex.height {
                s += self.tex.texel(k, j, 0) as f64;
                p.push(s);
            }
            p
        })
    }

    /// `G(j)`: the signed sum of the extended column `k` over rows `[0, j)` (`-sum [j, 0)` for
    /// negative `j`).
    fn column_g(&self, k: usize, j: i64) -> f64 {
        let p = self.column_prefix(k);
        let h = self.tex.height as i64;
        let t = p[h as usize];
        match self.mode {
            RefMode::Border => p[j.clamp(0, h) as usize],
            RefMode::Clamp => {
                if j <= 0 {
                    j as f64 * self.tex.texel(k, 0, 0) as f64
                } else if j >= h {
                    t + (j - h) as f64 * self.tex.texel(k, h as usize - 1, 0) as f64
                } else {
                    p[j as usize]
                }
            }
            RefMode::Repeat => j.div_euclid(h) as f64 * t + p[j.rem_euclid(h) as usize],
            RefMode::Mirror => {
                let r = j.rem_euclid(2 * h);
                let m = if r <= h {
                    p[r as usize]
                } else {
                    2.0 * t - p[(2 * h - r) as usize]
                };
                j.div_euclid(2 * h) as f64 * 2.0 * t + m
            }
        }
    }

    /// The sum of extended column `i` over rows `[j0, j1)` (zero if `j1 <= j0`).
    pub fn column_sum(&self, i: i64, j0: i64, j1: i64) -> f64 {
        if j1 <= j0 {
            return 0.0;
        }
        let Some(k) = self.mode.index(i, self.tex.width) else {
            return 0.0;
        };
        if j1 - j0 < PREFIX_MIN_RUN {
            return (j0..j1).map(|j| self.texel(i, j)).sum();
        }
        self.column_g(k, j1) - self.column_g(k, j0)
    }
}

type Pt = (f64, f64);

/// Sutherland-Hodgman clip of a convex polygon against the half-plane `coord(axis) >= c`
/// (`keep_above`) or `<= c`. Points created on the line get that coordinate exactly `c`.
fn clip(poly: &[Pt], out: &mut Vec<Pt>, axis: usize, c: f64, keep_above: bool) {
    out.clear();
    let n = poly.len();
    if n == 0 {
        return;
    }
    let coord = |p: &Pt| if axis == 0 { p.0 } else { p.1 };
    let inside = |p: &Pt| {
        if keep_above {
            coord(p) >= c
        } else {
            coord(p) <= c
        }
    };
    let cross = |a: &Pt, b: &Pt| {
        let (ca, cb) = (coord(a), coord(b));
        let t = (c - ca) / (cb - ca);
        if axis == 0 {
            (c, a.1 + t * (b.1 - a.1))
        } else {
            (a.0 + t * (b.0 - a.0), c)
        }
    };
    for k in 0..n {
        let a = &poly[k];
        let b = &poly[(k + 1) % n];
        match (inside(a), inside(b)) {
            (true, true) => out.push(*b),
            (true, false) => out.push(cross(a, b)),
            (false, true) => {
                out.push(cross(a, b));
                out.push(*b);
            }
            (false, false) => {}
        }
    }
}

/// Signed shoelace area.
fn shoelace(poly: &[Pt]) -> f64 {
    let n = poly.len();
    if n < 3 {
        return 0.0;
    }
    let mut s = 0.0;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        s += a.0 * b.1 - b.0 * a.1;
    }
    s / 2.0
}

fn is_convex(poly: &[Pt]) -> bool {
    let n = poly.len();
    let (mut pos, mut neg) = (false, false);
    for k in 0..n {
        let (a, b, c) = (poly[k], poly[(k + 1) % n], poly[(k + 2) % n]);
        let z = (b.0 - a.0) * (c.1 - b.1) - (b.1 - a.1) * (c.0 - b.0);
        pos |= z > 0.0;
        neg |= z < 0.0;
    }
    !(pos && neg)
}

/// Reusable buffers for [`polygon_integral`].
#[derive(Debug, Default)]
pub struct ClipScratch {
    a: Vec<Pt>,
    slice: Vec<Pt>,
    b: Vec<Pt>,
    cell: Vec<Pt>,
    poly: Vec<Pt>,
}

/// The integral of the extended texture over a simple polygon (texture coordinates, any
/// orientation), exactly up to `f64` rounding: `(sum of value * area(poly ∩ cell), area(poly))`,
/// both signed by the polygon's orientation (so pieces of a subdivided pre-image add up).
/// Convex polygons are walked directly (module docs: column strips, clipped cells at the
/// boundary, prefix sums for the full runs); non-convex ones as a fan of signed triangles.
/// `None` if the walk would exceed [`MAX_BOUNDARY_CELLS`] or a coordinate is not finite.
pub fn polygon_integral(
    cols: &ExtendedColumns<'_>,
    poly: &[Pt],
    scratch: &mut ClipScratch,
) -> Option<(f64, f64)> {
    if poly.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
        return None;
    }
    if poly.len() < 3 {
        return Some((0.0, 0.0));
    }
    if is_convex(poly) {
        return convex_integral(cols, poly, scratch);
    }
    let (mut int, mut area) = (0.0, 0.0);
    for k in 1..poly.len() - 1 {
        let (i, a) = convex_integral(cols, &[poly[0], poly[k], poly[k + 1]], scratch)?;
        int += i;
        area += a;
    }
    Some((int, area))
}

fn convex_integral(
    cols: &ExtendedColumns<'_>,
    poly: &[Pt],
    s: &mut ClipScratch,
) -> Option<(f64, f64)> {
    let area = shoelace(poly);
    if area == 0.0 {
        return Some((0.0, 0.0));
    }
    let sign = area.signum();
    // Work on a positively oriented copy.
    s.poly.clear();
    s.poly.extend_from_slice(poly);
    if sign < 0.0 {
        s.poly.reverse();
    }
    let (mut umin, mut umax) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &s.poly {
        umin = umin.min(p.0);
        umax = umax.max(p.0);
    }
    let i0 = umin.floor() as i64;
    let i1 = umax.ceil() as i64;
    if (i1 - i0) as f64 > MAX_BOUNDARY_CELLS as f64 {
        return None;
    }
    let mut budget = MAX_BOUNDARY_CELLS as i64 - (i1 - i0);
    let mut total = 0.0;
    for i in i0..i1 {
        let x0 = i as f64;
        clip(&s.poly, &mut s.a, 0, x0, true);
        clip(&s.a, &mut s.slice, 0, x0 + 1.0, false);
        if s.slice.len() < 3 {
            continue;
        }
        let (mut vmin, mut vmax) = (f64::INFINITY, f64::NEG_INFINITY);
        // Vertical extents on the strip's two sides (points exactly on them, if any).
        let (mut l, mut r) = (
            (f64::INFINITY, f64::NEG_INFINITY),
            (f64::INFINITY, f64::NEG_INFINITY),
        );
        for p in &s.slice {
            vmin = vmin.min(p.1);
            vmax = vmax.max(p.1);
            if p.0 == x0 {
                l = (l.0.min(p.1), l.1.max(p.1));
            }
            if p.0 == x0 + 1.0 {
                r = (r.0.min(p.1), r.1.max(p.1));
            }
        }
        // Rows fully covered across the whole strip: the lower boundary of a convex slice is
        // convex and the upper concave, so both are within their end values.
        let (mut jf0, mut jf1) = (0i64, 0i64);
        if l.0 <= l.1 && r.0 <= r.1 {
            let lo = l.0.max(r.0);
            let hi = l.1.min(r.1);
            if hi > lo {
                jf0 = lo.ceil() as i64;
                jf1 = hi.floor() as i64;
            }
        }
        let j0 = vmin.floor() as i64;
        let j1 = vmax.ceil() as i64;
        if jf1 <= jf0 {
            jf0 = j1;
            jf1 = j1;
        }
        // Partial rows: [j0, jf0) and [jf1, j1), clipped in coordinates local to the cell's
        // column and the slice's first row.
        let partial = (jf0 - j0) + (j1 - jf1);
        budget -= partial;
        if budget < 0 {
            return None;
        }
        let jb = j0 as f64;
        for p in s.slice.iter_mut() {
            *p = (p.0 - x0, p.1 - jb);
        }
        for j in (j0..jf0).chain(jf1..j1) {
            let y0 = (j - j0) as f64;
            clip(&s.slice, &mut s.b, 1, y0, true);
            clip(&s.b, &mut s.cell, 1, y0 + 1.0, false);
            let a = shoelace(&s.cell);
            if a != 0.0 {
                total += a * cols.texel(i, j);
            }
        }
        total += cols.column_sum(i, jf0, jf1);
    }
    Some((sign * total, area))
}

// ---------------------------------------------------------------------------------------------
// The ideal.

/// The ideal pixel value: the mean of the scene's extended texture (scene.mode) over the pixel's
/// true pre-image (the image in texture space of the pixel square [px, px+1) x [py, py+1)), in
/// texel units. None where any part of the pixel misses the surface. See the module docs for
/// how (exact for planar mappings). Each call builds its column sums afresh; [`ideal_image`]
/// shares them.
pub fn ideal_pixel(scene: &Scene, px: usize, py: usize) -> Option<f64> {
    let cols = ExtendedColumns::new(&scene.texture, scene.mode);
    ideal_pixel_with(scene, &cols, px, py, &mut ClipScratch::default())
}

/// [`ideal_pixel`] with caller-provided column sums (built for `scene.texture` and
/// `scene.mode`) and buffers.
pub fn ideal_pixel_with(
    scene: &Scene,
    cols: &ExtendedColumns<'_>,
    px: usize,
    py: usize,
    scratch: &mut ClipScratch,
) -> Option<f64> {
    let n = scene.mapping.ideal_subdivisions().max(1);
    let step = 1.0 / n as f64;
    let mut grid = Vec::with_capacity((n + 1) * (n + 1));
    for b in 0..=n {
        for a in 0..=n {
            let x = px as f64 + a as f64 * step;
            let y = py as f64 + b as f64 * step;
            grid.push(scene.mapping.map(x, y)?);
        }
    }
    let at = |a: usize, b: usize| grid[b * (n + 1) + a];
    let (mut int, mut area) = (0.0, 0.0);
    for b in 0..n {
        for a in 0..n {
            let quad = [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)];
            match polygon_integral(cols, &quad, scratch) {
                Some((i, ar)) => {
                    int += i;
                    area += ar;
                }
                None => return supersample_pixel(scene, px, py, 64),
            }
        }
    }
    if area != 0.0 && (int / area).is_finite() {
        Some(int / area)
    } else {
        // A degenerate (zero-area) pre-image: the texel under the pixel centre.
        let (u, v) = scene.mapping.map(px as f64 + 0.5, py as f64 + 0.5)?;
        Some(cols.texel(u.floor() as i64, v.floor() as i64))
    }
}

/// The ideal image, row-major `width * height`, computed on all available cores
/// (`std::thread::scope`, rows handed out one at a time).
pub fn ideal_image(scene: &Scene) -> Vec<Option<f64>> {
    let (w, h) = (scene.width, scene.height);
    let cols = ExtendedColumns::new(&scene.texture, scene.mode);
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .clamp(1, h.max(1));
    let next = AtomicUsize::new(0);
    let mut rows: Vec<(usize, Vec<Option<f64>>)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    let mut scratch = ClipScratch::default();
                    loop {
                        let py = next.fetch_add(1, Ordering::Relaxed);
                        if py >= h {
                            break;
                        }
                        let row = (0..w)
                            .map(|px| ideal_pixel_with(scene, &cols, px, py, &mut scratch))
                            .collect();
                        done.push((py, row));
                    }
                    done
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|t| t.join().expect("ideal_image worker panicked"))
            .collect()
    });
    rows.sort_by_key(|r| r.0);
    rows.into_iter().flat_map(|r| r.1).collect()
}

/// Point-sampled supersampling of the ideal, for checking it: `n x n` samples at the centres
/// of a regular grid over the pixel, each weighted by `|det J|` of the mapping there (uniform
/// screen samples are not uniform in texture space), `sum(|det J| t(map(s))) / sum(|det J|)`
/// with `t` the extended texel under the sample. None if any sample misses the surface.
pub fn supersample_pixel(scene: &Scene, px: usize, py: usize, n: usize) -> Option<f64> {
    let n = n.max(1);
    let (mut sw, mut swt) = (0.0, 0.0);
    for b in 0..n {
        for a in 0..n {
            let x = px as f64 + (a as f64 + 0.5) / n as f64;
            let y = py as f64 + (b as f64 + 0.5) / n as f64;
            let f = scene.mapping.footprint(x, y)?;
            let w = (f.du_dx * f.dv_dy - f.du_dy * f.dv_dx).abs();
            let t = scene
                .texture
                .texel_ext(scene.mode, f.u.floor() as i64, f.v.floor() as i64, 0);
            sw += w;
            swt += w * t as f64;
        }
    }
    (sw > 0.0).then(|| swt / sw)
}

/// The EWA ellipse of the footprint at a pixel centre (a convenience for reports: its area
/// `pi sqrt(F)` is the texel count an EWA evaluation visits).
pub fn pixel_ellipse(scene: &Scene, px: usize, py: usize) -> Option<EwaEllipse> {
    let f = scene.mapping.footprint(px as f64 + 0.5, py as f64 + 0.5)?;
    Some(EwaEllipse::new(&f))
}
