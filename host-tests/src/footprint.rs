//! Screen-to-texture mappings and the texture footprint of a pixel (Heckbert 1986, "Perspective
//! Mapping"; Crow §2.3).
//!
//! A planar perspective mapping takes screen `(x, y)` to texture `(u, v)` through a 3 x 3
//! homogeneous matrix: `(U, V, W) = M (x, y, 1)`, `u = U / W`, `v = V / W`. Its derivatives follow
//! from the quotient rule, `du/dx = (M00 W - M20 U) / W^2` and so on, which this module evaluates
//! analytically (no finite differences). Crow (§2.3) turns the increments into a rectangle: "the
//! texture rectangle is determined by taking the maximum of the absolute values of both
//! x-coordinates and similarly for the y-coordinates", i.e. a rectangle centred on `(u, v)` of
//! width `max(|du/dx|, |du/dy|)` and height `max(|dv/dx|, |dv/dy|)`. The bounding box of the
//! pixel's parallelogram (`|du/dx| + |du/dy|` by `|dv/dx| + |dv/dy|`) is offered beside it.
//!
//! This is host-side `f64` arithmetic, the reference the scenes and the report use (it lived in
//! the core until the firmware-grade-core issue moved it here: soft double precision has no place
//! in a Cortex-M4 firmware). The mapping is the address unit's job, not the texture datapath's;
//! the lookups take its output converted to fixed point by [`texsat::Rect::from_f64`], which
//! refuses NaN and infinities.

/// A 3 x 3 homogeneous mapping from screen `(x, y)` to texture `(u, v)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Perspective {
    /// Row-major: `U = m[0] . (x, y, 1)`, `V = m[1] . (x, y, 1)`, `W = m[2] . (x, y, 1)`.
    pub m: [[f64; 3]; 3],
}

/// The texture-space footprint of one screen point: position and the four partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    /// Texture u (texels).
    pub u: f64,
    /// Texture v (texels).
    pub v: f64,
    /// `du/dx`
    pub du_dx: f64,
    /// `du/dy`
    pub du_dy: f64,
    /// `dv/dx`
    pub dv_dx: f64,
    /// `dv/dy`
    pub dv_dy: f64,
}

/// A rectangle `[u0, u1) x [v0, v1)` in texels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RectF {
    /// Left.
    pub u0: f64,
    /// Top.
    pub v0: f64,
    /// Right.
    pub u1: f64,
    /// Bottom.
    pub v1: f64,
}

impl RectF {
    /// Width `u1 - u0`.
    pub fn width(&self) -> f64 {
        self.u1 - self.u0
    }
    /// Height `v1 - v0`.
    pub fn height(&self) -> f64 {
        self.v1 - self.v0
    }
}

fn abs(v: f64) -> f64 {
    if v < 0.0 {
        -v
    } else {
        v
    }
}

impl Perspective {
    /// The mapping with matrix `m`.
    pub const fn new(m: [[f64; 3]; 3]) -> Self {
        Perspective { m }
    }

    /// The affine mapping `u = a x + b y + c`, `v = d x + e y + f`.
    pub const fn affine(a: f64, b: f64, c: f64, d: f64, e: f64, f: f64) -> Self {
        Perspective {
            m: [[a, b, c], [d, e, f], [0.0, 0.0, 1.0]],
        }
    }

    /// The homogeneous coordinates `(U, V, W)` of screen point `(x, y)`.
    pub fn homogeneous(&self, x: f64, y: f64) -> [f64; 3] {
        let r = |i: usize| self.m[i][0] * x + self.m[i][1] * y + self.m[i][2];
        [r(0), r(1), r(2)]
    }

    /// Texture `(u, v)` of screen `(x, y)`, or `None` where `W <= 0` (at or behind the
    /// horizon) or the result is not finite.
    pub fn map(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let [uu, vv, w] = self.homogeneous(x, y);
        if w <= 0.0 || !w.is_finite() {
            return None;
        }
        let (u, v) = (uu / w, vv / w);
        if u.is_finite() && v.is_finite() {
            Some((u, v))
        } else {
            None
        }
    }

    /// Position and analytic derivatives at screen `(x, y)` (quotient rule), or `None` where
    /// [`Perspective::map`] is `None`.
    pub fn footprint(&self, x: f64, y: f64) -> Option<Footprint> {
        let (u, v) = self.map(x, y)?;
        let w = self.homogeneous(x, y)[2];
        let m = &self.m;
        // d(U/W)/dx = (U_x W - U W_x) / W^2 = (m00 - u m20) / W.
        let fp = Footprint {
            u,
            v,
            du_dx: (m[0][0] - u * m[2][0]) / w,
            du_dy: (m[0][1] - u * m[2][1]) / w,
            dv_dx: (m[1][0] - v * m[2][0]) / w,
            dv_dy: (m[1][1] - v * m[2][1]) / w,
        };
        let all = [fp.du_dx, fp.du_dy, fp.dv_dx, fp.dv_dy];
        if all.iter().all(|d| d.is_finite()) {
            Some(fp)
        } else {
            None
        }
    }
}

impl Footprint {
    /// Crow's rectangle (§2.3): centred on `(u, v)`, width `max(|du/dx|, |du/dy|)`, height
    /// `max(|dv/dx|, |dv/dy|)`.
    pub fn crow_rect(&self) -> RectF {
        let wu = max(abs(self.du_dx), abs(self.du_dy));
        let wv = max(abs(self.dv_dx), abs(self.dv_dy));
        self.centred(wu, wv)
    }

    /// The bounding box of the pixel's parallelogram: width `|du/dx| + |du/dy|`, height
    /// `|dv/dx| + |dv/dy|`.
    pub fn bounding_rect(&self) -> RectF {
        let wu = abs(self.du_dx) + abs(self.du_dy);
        let wv = abs(self.dv_dx) + abs(self.dv_dy);
        self.centred(wu, wv)
    }

    fn centred(&self, wu: f64, wv: f64) -> RectF {
        RectF {
            u0: self.u - wu / 2.0,
            v0: self.v - wv / 2.0,
            u1: self.u + wu / 2.0,
            v1: self.v + wv / 2.0,
        }
    }
}

fn max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        abs(a - b) <= tol * (1.0 + abs(b))
    }

    #[test]
    fn affine_derivatives_are_the_coefficients() {
        let p = Perspective::affine(2.0, -0.5, 3.0, 0.25, 4.0, -1.0);
        let f = p.footprint(10.0, 7.0).unwrap();
        assert_eq!((f.u, f.v), (2.0 * 10.0 - 0.5 * 7.0 + 3.0, 2.5 + 28.0 - 1.0));
        assert_eq!((f.du_dx, f.du_dy, f.dv_dx, f.dv_dy), (2.0, -0.5, 0.25, 4.0));
        let r = f.crow_rect();
        assert_eq!((r.width(), r.height()), (2.0, 4.0));
        let b = f.bounding_rect();
        assert_eq!((b.width(), b.height()), (2.5, 4.25));
    }

    #[test]
    fn hand_worked_perspective() {
        // U = x, V = 1, W = y: u = x / y, v = 1 / y (a ground plane seen from above the horizon).
        let p = Perspective::new([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]);
        let f = p.footprint(3.0, 2.0).unwrap();
        // u = 1.5, v = 0.5; du/dx = 1/y = 0.5, du/dy = -x/y^2 = -0.75, dv/dx = 0, dv/dy = -1/y^2.
        assert_eq!((f.u, f.v), (1.5, 0.5));
        assert_eq!(
            (f.du_dx, f.du_dy, f.dv_dx, f.dv_dy),
            (0.5, -0.75, 0.0, -0.25)
        );
        assert_eq!(p.map(3.0, 0.0), None);
        assert_eq!(p.map(3.0, -1.0), None);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let p = Perspective::new([[0.9, 0.2, 5.0], [-0.1, 1.3, 2.0], [0.001, 0.004, 1.0]]);
        let h = 1e-5;
        for (x, y) in [(0.0, 0.0), (10.5, 3.25), (100.0, 200.0), (-20.0, 50.0)] {
            let f = p.footprint(x, y).unwrap();
            let (u1, v1) = p.map(x + h, y).unwrap();
            let (u0, v0) = p.map(x - h, y).unwrap();
            assert!(close(f.du_dx, (u1 - u0) / (2.0 * h), 1e-6));
            assert!(close(f.dv_dx, (v1 - v0) / (2.0 * h), 1e-6));
            let (u1, v1) = p.map(x, y + h).unwrap();
            let (u0, v0) = p.map(x, y - h).unwrap();
            assert!(close(f.du_dy, (u1 - u0) / (2.0 * h), 1e-6));
            assert!(close(f.dv_dy, (v1 - v0) / (2.0 * h), 1e-6));
        }
    }
}
