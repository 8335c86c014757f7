//! Crow's §3.0 bit-saving scheme, implemented *literally*, to show what it gets wrong.
//!
//! Crow (1984), §3.0: "the texture image may be divided into regions of 16 pixels square to
//! limit the sum within such a region to 16 bits (256 entries of 8 bits each). A 32-bit quantity
//! would be stored for each region giving the sum at its lower left corner. To recover a value
//! from the table would require adding the appropriate 32-bit quantity to the table entry."
//!
//! ## What [`CrowLiteral`] stores
//! The texture (`w x h`, y down, texel `(i, j)` covering `[i, i+1) x [j, j+1)`) is cut into
//! regions of `R x R` texels (Crow: `R = 16`; the last region row and column may be partial).
//! For the region with origin corner `(X0, Y0)` (multiples of `R`) it stores
//!
//! * per texel `(i, j)` of the region, the **local sum** `local(i, j)` = the sum of the texels
//!   `(i', j')` of the *same region* with `X0 <= i' <= i`, `Y0 <= j' <= j` (the 2D prefix sum
//!   inside the region, inclusive like texsat's stored table): at most `m R^2`, so
//!   `bits_of(m R^2)` bits (16 for `m = 255`, `R = 16`);
//! * one full-width value, Crow's "sum at its lower left corner" — in our y-down convention the
//!   corner function at the region's origin, `corner(X0, Y0) = S(X0, Y0)` = the sum of all
//!   texels with `i < X0` and `j < Y0`. Crow stores it in 32 bits.
//!
//! Reconstruction ("adding the appropriate 32-bit quantity to the table entry"): the table
//! entry of texel `(i, j)`, i.e. the corner function at `(x, y) = (i + 1, j + 1)`, is
//! `S_lit(x, y) = corner(region of texel (x-1, y-1)) + local(x-1, y-1)`, and
//! `S_lit(0, y) = S_lit(x, 0) = 0` (never stored, as in texsat).
//!
//! So a corner coordinate `x >= 1` belongs to region column `(x - 1) / R`: a coordinate on a
//! region boundary, `x = X0 > 0`, is the *right edge of the previous* region (its entry is
//! that of texel `X0 - 1`), and `x = 0` behaves as region column 0 (see below). The same holds
//! for `y` and region rows. [`CrowLiteral::region_of_corner`] implements this rule.
//!
//! ## Why it is incomplete
//! For a corner `(x, y)` in the region with origin `(X0, Y0)` (so `X0 < x <= X0 + R`,
//! `Y0 < y <= Y0 + R`) the prefix `[0, x) x [0, y)` splits into four parts:
//!
//! `S(x, y) = S(X0, Y0) + T(x) + L(y) + local(x - 1, y - 1)`, with
//!
//! * `T(x) = S(x, Y0) - S(X0, Y0)`: the strip **above** the region (rows `0..Y0`) for its
//!   columns `X0..x`;
//! * `L(y) = S(X0, y) - S(X0, Y0)`: the strip **left** of the region (columns `0..X0`) for its
//!   rows `Y0..y`.
//!
//! The literal reconstruction has only the first and last terms: it misses `T(x) + L(y)`.
//! `T` vanishes for every `x` only when `Y0 = 0` (there is nothing above the first region row),
//! `L` only when `X0 = 0`. Both are sums of non-negative texels, so a reconstructed corner
//! value is right in general **only in the first region** (`X0 = Y0 = 0`); a region in the
//! first region row but not the first column still misses `L(y) = S(X0, y)`, and vice versa.
//! (With `x = 0` or `y = 0` the value is the exact 0, which is what the formula gives with
//! `X0 = 0`, resp. `Y0 = 0`: `T(0) = L(y) = 0` — hence `x = 0` counts as region column 0.)
//! Texsat's [`texsat::layouts::Tiled`] stores `T` and `L` as well (the "edge strips", `C_10`
//! and `C_01`, one value per region column (row) and per row (column) of the region): that
//! costs the strip fields on top of Crow's figure, and makes every box exact.
//!
//! ## When it is nevertheless right
//! The error `e(x, y) = S(x, y) - S_lit(x, y) = T(x) + L(y)` is, within one region, a sum of a
//! function of `x` alone and a function of `y` alone. For a box `[x0, x1) x [y0, y1)` whose four
//! corners all belong to the same region (by the rule above), the error of the 4-corner formula
//! is
//!
//! `e(x1,y1) - e(x1,y0) - e(x0,y1) + e(x0,y0)
//!  = [T(x1) + L(y1)] - [T(x1) + L(y0)] - [T(x0) + L(y1)] + [T(x0) + L(y0)] = 0`:
//!
//! `T(x1)` appears in `S(x1, y1)` and `S(x1, y0)` with opposite signs, `T(x0)` in `S(x0, y1)`
//! and `S(x0, y0)`, `L(y1)` in `S(x1, y1)` and `S(x0, y1)`, `L(y0)` in `S(x1, y0)` and
//! `S(x0, y0)`. So the literal scheme is **exact for boxes inside one region** (where only the
//! local sums matter anyway) and **wrong in general**: a box whose corners fall in different
//! regions picks up strips of `T` and `L` that do not cancel. For example a box in the first
//! region row (`T = 0`) spanning region columns `a < b` gets
//! `L_b(y1) - L_b(y0) - L_a(y1) + L_a(y0)` = the sum over columns `X0_a..X0_b`, rows `y0..y1`
//! added to it. `tests/crow_literal.rs` exhibits failing boxes with their numbers.
//!
//! ## Bits per entry
//! `bits_of(m R^2) + 32 / R^2`: Crow's `16 + 32/256 = 16.125` for `R = 16` ("16 bits or
//! less", ignoring the overhead), and his "effective 14 bits per entry" is `R = 4`:
//! `bits_of(255 * 16) = 12` plus a 32-bit value per 16 entries, `12 + 2`.

use texsat::width::bits_of;

use crate::RefTexture;

/// Bits Crow gives the per-region corner value.
pub const CROW_CORNER_BITS: u32 = 32;

/// Crow's §3.0 scheme taken literally: per-region local sums plus one corner value per region
/// (see the [module documentation](self) for what it stores and why it is wrong in general).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CrowLiteral {
    width: usize,
    height: usize,
    channels: usize,
    region: usize,
    texel_bits: u32,
    /// `local[(j * width + i) * channels + c]`: the inclusive prefix sum inside the region.
    local: Vec<u64>,
    /// `corners[(ry * regions_x + rx) * channels + c]` = `S(rx R, ry R)`.
    corners: Vec<u128>,
}

impl CrowLiteral {
    /// Builds the scheme for `tex` with `region x region` texel regions; `texel_bits` is the
    /// texel width the local sums are sized for (8 in Crow's example). Panics if `region` is 0
    /// or a texel exceeds `2^texel_bits - 1`.
    pub fn build(tex: &RefTexture, region: usize, texel_bits: u32) -> Self {
        assert!(region > 0, "empty region");
        assert!(
            (tex.max_texel() as u64) < (1u64 << texel_bits),
            "texel wider than texel_bits"
        );
        let (w, h, ch, r) = (tex.width, tex.height, tex.channels, region);
        // Local sums: prefix sums restarted at every region boundary.
        let mut local = vec![0u64; w * h * ch];
        for j in 0..h {
            for i in 0..w {
                for c in 0..ch {
                    let left = if i % r > 0 {
                        local[(j * w + i - 1) * ch + c]
                    } else {
                        0
                    };
                    let up = if j % r > 0 {
                        local[((j - 1) * w + i) * ch + c]
                    } else {
                        0
                    };
                    let diag = if i % r > 0 && j % r > 0 {
                        local[((j - 1) * w + i - 1) * ch + c]
                    } else {
                        0
                    };
                    local[(j * w + i) * ch + c] = tex.texel(i, j, c) as u64 + left + up - diag;
                }
            }
        }
        // Corner values S(X0, Y0), summed directly from the texels.
        let (rx, ry) = (w.div_ceil(r), h.div_ceil(r));
        let mut corners = vec![0u128; rx * ry * ch];
        for by in 0..ry {
            for bx in 0..rx {
                for c in 0..ch {
                    let mut s = 0u128;
                    for j in 0..by * r {
                        for i in 0..bx * r {
                            s += tex.texel(i, j, c) as u128;
                        }
                    }
                    corners[(by * rx + bx) * ch + c] = s;
                }
            }
        }
        CrowLiteral {
            width: w,
            height: h,
            channels: ch,
            region,
            texel_bits,
            local,
            corners,
        }
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The region side `R`.
    pub fn region(&self) -> usize {
        self.region
    }

    /// Region columns and rows.
    pub fn regions(&self) -> (usize, usize) {
        (
            self.width.div_ceil(self.region),
            self.height.div_ceil(self.region),
        )
    }

    /// The stored local sum of texel `(i, j)`, channel `c`.
    pub fn local(&self, i: usize, j: usize, c: usize) -> u64 {
        assert!(i < self.width && j < self.height && c < self.channels);
        self.local[(j * self.width + i) * self.channels + c]
    }

    /// The stored corner value of region `(rx, ry)` (`S(rx R, ry R)`), channel `c`.
    pub fn region_corner(&self, rx: usize, ry: usize, c: usize) -> u128 {
        let (nx, ny) = self.regions();
        assert!(rx < nx && ry < ny && c < self.channels);
        self.corners[(ry * nx + rx) * self.channels + c]
    }

    /// The region whose reconstruction answers the corner `(x, y)`: `((x - 1) / R, (y - 1) / R)`,
    /// with `0` mapped to region column (row) 0. A corner on a region boundary belongs to the
    /// region to its left (above).
    pub fn region_of_corner(&self, x: usize, y: usize) -> (usize, usize) {
        let f = |v: usize| v.saturating_sub(1) / self.region;
        (f(x), f(y))
    }

    /// Whether the four corners of the box `[x0, x1) x [y0, y1)` belong to one region
    /// (the condition under which the literal scheme is exact).
    pub fn box_in_one_region(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> bool {
        let (ax, ay) = self.region_of_corner(x0, y0);
        let (bx, by) = self.region_of_corner(x1, y1);
        ax == bx && ay == by
    }

    /// The reconstructed table entry of texel `(i, j)`: region corner value plus local sum.
    pub fn entry(&self, i: usize, j: usize, c: usize) -> u128 {
        let (r, nx) = (self.region, self.regions().0);
        let corner = self.corners[((j / r) * nx + i / r) * self.channels + c];
        corner + self.local(i, j, c) as u128
    }

    /// The reconstructed corner function `S_lit(x, y)` for `0 <= x <= w`, `0 <= y <= h`
    /// (`0` on the zero row and column, else the entry of texel `(x - 1, y - 1)`).
    pub fn corner(&self, x: usize, y: usize, c: usize) -> u128 {
        assert!(
            x <= self.width && y <= self.height,
            "corner outside the table"
        );
        if x == 0 || y == 0 {
            0
        } else {
            self.entry(x - 1, y - 1, c)
        }
    }

    /// The 4-corner formula on the reconstructed values,
    /// `S_lit(x1,y1) - S_lit(x1,y0) - S_lit(x0,y1) + S_lit(x0,y0)`, in `i128` (it can be wrong,
    /// and even negative). Requires `x0 <= x1 <= w`, `y0 <= y1 <= h`.
    pub fn box_sum(&self, x0: usize, y0: usize, x1: usize, y1: usize, c: usize) -> i128 {
        assert!(x0 <= x1 && y0 <= y1, "inverted box");
        let s = |x, y| self.corner(x, y, c) as i128;
        s(x1, y1) - s(x1, y0) - s(x0, y1) + s(x0, y0)
    }

    /// Bits of one local sum: `bits_of(m R^2)`.
    pub fn local_bits(&self) -> u32 {
        Self::local_bits_for(self.texel_bits, self.region)
    }

    /// `bits_of((2^b - 1) R^2)`.
    pub fn local_bits_for(texel_bits: u32, region: usize) -> u32 {
        bits_of(((1u128 << texel_bits) - 1) * (region * region) as u128)
    }

    /// Crow's nominal bits per entry: `bits_of(m R^2) + 32 / R^2` (full regions).
    pub fn nominal_bits_per_entry(texel_bits: u32, region: usize) -> f64 {
        Self::local_bits_for(texel_bits, region) as f64
            + CROW_CORNER_BITS as f64 / (region * region) as f64
    }

    /// Bits per entry and channel of this instance: every local sum at [`Self::local_bits`]
    /// plus one 32-bit value per region (partial regions included), over `w h`.
    pub fn bits_per_entry(&self) -> f64 {
        let (nx, ny) = self.regions();
        let bits = (self.width * self.height) as f64 * self.local_bits() as f64
            + (nx * ny) as f64 * CROW_CORNER_BITS as f64;
        bits / (self.width * self.height) as f64
    }
}
