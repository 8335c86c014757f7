//! Straightforward hand-written Rust versions of the measured behaviours, as a firmware engineer
//! would write them for one known configuration (a `u32` table of 8-bit texels, one channel,
//! `F = 8`): the baselines `count-insns.sh` prints beside texsat's figures. Same results as
//! texsat on the harness's boxes (checked in `main` before measuring), no panic path (reads go
//! through `get`), 64-bit arithmetic, no width proof, no error handling beyond that.

/// A `w x h` summed-area table, `t[(y - 1) w + (x - 1)] = S(x, y)` (the zero row and column
/// implicit), as `Sat` stores it.
#[derive(Clone, Copy)]
pub struct Table<'a> {
    pub t: &'a [u32],
    pub w: u32,
    pub h: u32,
}

impl Table<'_> {
    /// `S(x, y)` for `x <= w`, `y <= h`.
    #[inline(always)]
    fn s(&self, x: u32, y: u32) -> u64 {
        if x == 0 || y == 0 {
            return 0;
        }
        let i = (y - 1) as usize * self.w as usize + (x - 1) as usize;
        self.t.get(i).copied().unwrap_or(0) as u64
    }

    /// 4-read box sum for a box known to lie inside the texture (0 for one that does not).
    #[inline(always)]
    pub fn box_sum_inside(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> u64 {
        if x0 > x1 || y0 > y1 || x1 > self.w || y1 > self.h {
            return 0;
        }
        self.s(x1, y1)
            .wrapping_sub(self.s(x0, y1))
            .wrapping_sub(self.s(x1, y0))
            .wrapping_add(self.s(x0, y0))
    }

    /// 4-read box sum at integer corners, Border (the box clipped to the texture).
    #[inline(always)]
    pub fn box_sum_int_border(&self, x0: i32, y0: i32, x1: i32, y1: i32) -> u64 {
        let cx = |v: i32| v.max(0).min(self.w as i32) as u32;
        let cy = |v: i32| v.max(0).min(self.h as i32) as u32;
        let (x0, x1, y0, y1) = (cx(x0), cx(x1), cy(y0), cy(y1));
        if x1 <= x0 || y1 <= y0 {
            return 0;
        }
        self.s(x1, y1) - self.s(x0, y1) - self.s(x1, y0) + self.s(x0, y0)
    }

    /// 4-read box sum at integer corners under clamp-to-edge: per axis the part left of the
    /// texture (the first column, repeated), the part inside and the part right of it (the
    /// last column, repeated); the sum over the up to 3 x 3 pieces, each a 4-read box sum
    /// times its repeat counts.
    #[inline(always)]
    pub fn box_sum_int_clamp(&self, x0: i32, y0: i32, x1: i32, y1: i32) -> u64 {
        if x1 <= x0 || y1 <= y0 {
            return 0;
        }
        let axis = |v0: i32, v1: i32, n: u32| -> [(u32, u32, u64); 3] {
            let n_i = n as i32;
            [
                (0, 1, (v1.min(0) - v0).max(0) as u64),
                (v0.max(0).min(n_i) as u32, v1.min(n_i).max(0) as u32, 1),
                (n - 1, n, (v1 - v0.max(n_i)).max(0) as u64),
            ]
        };
        let mut sum = 0u64;
        for (xa, xb, wx) in axis(x0, x1, self.w) {
            for (ya, yb, wy) in axis(y0, y1, self.h) {
                if wx != 0 && wy != 0 && xa < xb && ya < yb {
                    sum += wx * wy * self.box_sum_inside(xa, ya, xb, yb);
                }
            }
        }
        sum
    }

    /// `2^16 S(x, y)` at `F = 8` raw corners clipped to the texture: bilinear interpolation of
    /// the table (Crow §2.1), exact in `u64` (`2^32 2^16` fits).
    #[inline(always)]
    fn corner(&self, x: i32, y: i32) -> u64 {
        let x = x.max(0).min((self.w << 8) as i32) as u32;
        let y = y.max(0).min((self.h << 8) as i32) as u32;
        let (mut i, mut a) = (x >> 8, (x & 255) as u64);
        let (mut j, mut b) = (y >> 8, (y & 255) as u64);
        if i == self.w {
            i -= 1;
            a = 256;
        }
        if j == self.h {
            j -= 1;
            b = 256;
        }
        (256 - a) * (256 - b) * self.s(i, j)
            + a * (256 - b) * self.s(i + 1, j)
            + (256 - a) * b * self.s(i, j + 1)
            + a * b * self.s(i + 1, j + 1)
    }

    /// 16-read box integral times `2^16` at `F = 8` corners, Border.
    #[inline(always)]
    pub fn box_sum_border(&self, x0: i32, y0: i32, x1: i32, y1: i32) -> u64 {
        (self.corner(x1, y1) + self.corner(x0, y0))
            .wrapping_sub(self.corner(x0, y1))
            .wrapping_sub(self.corner(x1, y0))
    }

    /// The same under Repeat for a box inside one period: each axis shifted into the first
    /// period by one 32-bit division of its low corner (0 if the box crosses the edge: the
    /// hand-written version does not split).
    #[inline(always)]
    pub fn box_sum_repeat_in_period(&self, x0: i32, y0: i32, x1: i32, y1: i32) -> u64 {
        let (pw, ph) = ((self.w << 8) as i32, (self.h << 8) as i32);
        let (Some(qx), Some(qy)) = (x0.checked_div_euclid(pw), y0.checked_div_euclid(ph)) else {
            return 0;
        };
        let (sx, sy) = (qx * pw, qy * ph);
        let (x0, x1, y0, y1) = (x0 - sx, x1 - sx, y0 - sy, y1 - sy);
        if x1 > pw || y1 > ph {
            return 0;
        }
        self.box_sum_border(x0, y0, x1, y1)
    }
}

/// `round(sum 2^g / area)`, ties up, with one `u64` division (the caller knows `sum 2^g` fits).
#[inline(always)]
pub fn mean_rounded(sum: u64, g: u32, w_raw: u64, h_raw: u64) -> u64 {
    let area = w_raw * h_raw;
    if area == 0 {
        return 0;
    }
    ((sum << g) + area / 2).checked_div(area).unwrap_or(0)
}

/// Builds the `w x h` table of 8-bit texels into `t` (`S(x, y)` at `(y - 1) w + (x - 1)`): a
/// running row sum plus the entry above, in `E` (`u32`, or `u16` for a small table: the caller
/// knows `255 w h` fits).
#[inline(always)]
pub fn build<E>(texels: &[u8], w: usize, t: &mut [E])
where
    E: Copy + Default + From<u8> + core::ops::Add<Output = E>,
{
    if w == 0 {
        return;
    }
    let mut above: Option<&[E]> = None;
    for (row, out) in texels.chunks_exact(w).zip(t.chunks_exact_mut(w)) {
        let mut run = E::default();
        match above {
            Some(up) => {
                for ((o, &v), &u) in out.iter_mut().zip(row).zip(up) {
                    run = run + E::from(v);
                    *o = run + u;
                }
            }
            None => {
                for (o, &v) in out.iter_mut().zip(row) {
                    run = run + E::from(v);
                    *o = run;
                }
            }
        }
        above = Some(out);
    }
}
