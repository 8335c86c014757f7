//! Elliptical weighted average (EWA) with a Gaussian filter, in `f64`: the high-quality
//! reference filter of the report (Heckbert 1989, "Fundamentals of Texture Mapping and Image
//! Warping", §3.5.8; Heckbert's survey, "Elliptical Weighted Average"; the same formulation as
//! pbrt's `MIPMap::EWA`, but on the full-resolution texture instead of a pyramid level).
//!
//! # The ellipse
//!
//! A circular Gaussian in screen space, pulled back through the local Jacobian
//! `J = [[du/dx, du/dy], [dv/dx, dv/dy]]`, is an elliptical Gaussian in texture space with
//! covariance proportional to `J J^T`. Convolving it with a unit reconstruction filter adds the
//! identity to that covariance, which gives the ellipse a minimum radius of one texel, so
//! magnification is defined too. As the implicit conic `Q(du, dv) = A du^2 + B du dv + C dv^2`:
//!
//! ```text
//! A = dv_dx^2 + dv_dy^2 + 1
//! B = -2 (du_dx dv_dx + du_dy dv_dy)
//! C = du_dx^2 + du_dy^2 + 1
//! F = A C - B^2 / 4            (= det(J)^2 + |grad u|^2 + |grad v|^2 + 1 >= 1)
//! ```
//!
//! Without the `+ 1` terms, `Q = F` is exactly the image of the screen circle of radius one
//! pixel (`F = det(J)^2`). With them, `Q <= F` always contains the unit disc of texture space
//! (its covariance `J J^T + I` dominates `I`).
//!
//! # The filter
//!
//! For each texel centre `(i + 0.5, j + 0.5)` of the *extended* texture (the boundary mode
//! decides what lies outside), `r^2 = Q(i + 0.5 - u, j + 0.5 - v) / F`, and texels with
//! `r^2 < 1` get the weight `exp(-EWA_ALPHA r^2)` with [`EWA_ALPHA`] `= 2`: a Gaussian whose
//! standard deviation is half the ellipse radius (half a pixel in screen space, the choice of
//! pbrt and of Heckbert's thesis), truncated at two standard deviations (the weight at the
//! cutoff is `e^-2 = 0.135`). The result is `sum(w t) / sum(w)`: the normalisation makes a
//! constant texture come out exactly constant. The weight sum is never zero, since the ellipse
//! contains the unit disc and every disc of radius `sqrt(1/2)` contains a texel centre.
//!
//! The texels visited are exactly those inside the ellipse: for each texel row the quadratic
//! `Q <= F` is solved for the range of `du` (the bounding box of `Q <= F` is `|du| <= sqrt(C)`,
//! `|dv| <= sqrt(A)`), so the cost is the ellipse's area `pi sqrt(F)` texels, not its bounding
//! box's (which is far larger for thin oblique ellipses).
//!
//! # The cap
//!
//! Near a horizon the ellipse can cover millions of texels. When its area `pi sqrt(F)` exceeds
//! the cap ([`EWA_MAX_TEXELS`] `= 2^16`), the texture plane is cut into `s x s` blocks with
//! `s = ceil(sqrt(area / cap))`, and one texel per block is used, at a position inside the
//! block chosen by a deterministic hash of the block's coordinates (jittered, not a regular
//! stride: a regular stride aliases with periodic textures such as tiled checkerboards, whose
//! period is a power of two like the stride would often be). Each used texel stands for its
//! block with its own Gaussian weight; the estimate is unbiased up to the ellipse-boundary
//! blocks and its noise is of the order of `sigma_texture / sqrt(cap / 2)` (about 0.7 of 255
//! for a 0/255 checkerboard; the `/ 2` for the Gaussian's uneven weights). The cap is `2^16`
//! rather than `~1e6` for time: only the few pixel rows next to a horizon reach it, and with
//! `2^20` those rows alone made one EWA pass over the Default checkerboard plane take 3 s (one
//! core) instead of a fraction of a second. [`ewa_gaussian_capped`] takes the cap as a
//! parameter.

use crate::footprint::Footprint;
use crate::{RefMode, RefTexture};

/// The Gaussian's exponent factor: weight `exp(-EWA_ALPHA r^2)` for `r^2 = Q / F < 1`.
pub const EWA_ALPHA: f64 = 2.0;

/// The default cap on the number of texels one EWA evaluation visits (`2^16`); beyond it, one
/// jittered texel per block is used (see the module docs).
pub const EWA_MAX_TEXELS: f64 = 65_536.0;

/// The EWA ellipse `A du^2 + B du dv + C dv^2 <= F` of a footprint (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EwaEllipse {
    /// Coefficient of `du^2`: `dv_dx^2 + dv_dy^2 + 1`.
    pub a: f64,
    /// Coefficient of `du dv`: `-2 (du_dx dv_dx + du_dy dv_dy)`.
    pub b: f64,
    /// Coefficient of `dv^2`: `du_dx^2 + du_dy^2 + 1`.
    pub c: f64,
    /// The level: `A C - B^2 / 4` (`>= 1`).
    pub f: f64,
}

impl EwaEllipse {
    /// The ellipse of `fp`'s Jacobian, with the `+ 1` minimum radius.
    pub fn new(fp: &Footprint) -> Self {
        let a = fp.dv_dx * fp.dv_dx + fp.dv_dy * fp.dv_dy + 1.0;
        let b = -2.0 * (fp.du_dx * fp.dv_dx + fp.du_dy * fp.dv_dy);
        let c = fp.du_dx * fp.du_dx + fp.du_dy * fp.du_dy + 1.0;
        // A C - B^2 / 4 expanded: det^2 + |grad u|^2 + |grad v|^2 + 1, which avoids the
        // cancellation of the difference for thin ellipses.
        let det = fp.du_dx * fp.dv_dy - fp.du_dy * fp.dv_dx;
        let f = det * det + (c - 1.0) + (a - 1.0) + 1.0;
        EwaEllipse { a, b, c, f }
    }

    /// `Q(du, dv) = A du^2 + B du dv + C dv^2`.
    pub fn q(&self, du: f64, dv: f64) -> f64 {
        self.a * du * du + self.b * du * dv + self.c * dv * dv
    }

    /// The half extents `(sqrt(C), sqrt(A))` of the bounding box of `Q <= F`.
    pub fn half_extents(&self) -> (f64, f64) {
        (self.c.sqrt(), self.a.sqrt())
    }

    /// The ellipse's area `pi F / sqrt(A C - B^2 / 4) = pi sqrt(F)`, in texels.
    pub fn area(&self) -> f64 {
        core::f64::consts::PI * self.f.sqrt()
    }

    /// The `du` range of `Q(du, dv) <= F` on the line `dv`, or `None` if the line misses.
    pub fn du_range(&self, dv: f64) -> Option<(f64, f64)> {
        // A du^2 + (B dv) du + (C dv^2 - F) <= 0.
        let bb = self.b * dv;
        let disc = bb * bb - 4.0 * self.a * (self.c * dv * dv - self.f);
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        Some(((-bb - s) / (2.0 * self.a), (-bb + s) / (2.0 * self.a)))
    }
}

/// Elliptical weighted average with a Gaussian filter (Heckbert 1989, "Fundamentals of Texture
/// Mapping and Image Warping"; the survey's high-quality reference), f64, over the extended
/// texture, for the footprint's Jacobian (the ellipse from du_dx, du_dy, dv_dx, dv_dy; with a
/// minimum radius so magnification is defined). Channel 0. The cap is [`EWA_MAX_TEXELS`]; see
/// the module docs for the ellipse, the weights and the cap. NaN if the footprint is not finite.
pub fn ewa_gaussian(tex: &RefTexture, mode: RefMode, fp: &Footprint) -> f64 {
    ewa_gaussian_capped(tex, mode, fp, EWA_MAX_TEXELS)
}

/// [`ewa_gaussian`] with an explicit cap on the texels visited (`max_texels >= 1`).
pub fn ewa_gaussian_capped(
    tex: &RefTexture,
    mode: RefMode,
    fp: &Footprint,
    max_texels: f64,
) -> f64 {
    let all = [fp.u, fp.v, fp.du_dx, fp.du_dy, fp.dv_dx, fp.dv_dy];
    if !all.iter().all(|x| x.is_finite()) {
        return f64::NAN;
    }
    let e = EwaEllipse::new(fp);
    let area = e.area();
    let s = if area > max_texels.max(1.0) {
        (area / max_texels.max(1.0)).sqrt().ceil() as i64
    } else {
        1
    };
    let (_, vh) = e.half_extents();
    let (u, v) = (fp.u, fp.v);
    let mut sum_w = 0.0;
    let mut sum_wt = 0.0;
    let mut add = |i: i64, j: i64| {
        let du = i as f64 + 0.5 - u;
        let dv = j as f64 + 0.5 - v;
        let r2 = e.q(du, dv) / e.f;
        if r2 < 1.0 {
            let w = (-EWA_ALPHA * r2).exp();
            sum_w += w;
            sum_wt += w * tex.texel_ext(mode, i, j, 0) as f64;
        }
    };
    // Texel rows whose centres lie within the ellipse's v extent.
    let j0 = (v - vh - 0.5).ceil() as i64;
    let j1 = (v + vh - 0.5).floor() as i64;
    if s == 1 {
        for j in j0..=j1 {
            let Some((lo, hi)) = e.du_range(j as f64 + 0.5 - v) else {
                continue;
            };
            let i0 = (u + lo - 0.5).ceil() as i64;
            let i1 = (u + hi - 0.5).floor() as i64;
            for i in i0..=i1 {
                add(i, j);
            }
        }
    } else {
        // One jittered texel per s x s block (blocks anchored at multiples of s).
        let (k0, k1) = (j0.div_euclid(s), j1.div_euclid(s));
        for k in k0..=k1 {
            let j = k * s + (hash2(k, i64::MIN) % s as u64) as i64;
            let Some((lo, hi)) = e.du_range(j as f64 + 0.5 - v) else {
                continue;
            };
            // Blocks whose column range can hold a texel centre inside the ellipse on row j.
            let m0 = ((u + lo - 0.5).ceil() as i64).div_euclid(s);
            let m1 = ((u + hi - 0.5).floor() as i64).div_euclid(s);
            for m in m0..=m1 {
                let i = m * s + (hash2(k, m) % s as u64) as i64;
                add(i, j);
            }
        }
    }
    if sum_w > 0.0 {
        sum_wt / sum_w
    } else {
        // Unreachable for s == 1 (the ellipse contains the unit disc); with subsampling, a
        // degenerate case: fall back to the texel under the centre.
        tex.texel_ext(mode, u.floor() as i64, v.floor() as i64, 0) as f64
    }
}

/// A deterministic 64-bit hash of two integers (SplitMix64 finaliser), for the block jitter.
fn hash2(a: i64, b: i64) -> u64 {
    let mut z = (a as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((b as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add(0x1656_67B1_9E37_79F9);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
