//! Batch lookups: a row of footprints at once, the way a texture unit or a renderer asks.
//!
//! [`BatchLookup::box_sums_raw`] and [`BatchLookup::box_sums_int`] answer a slice of boxes
//! into a slice of results, each result exactly what [`BoxLookup::box_sum_raw`] /
//! [`BoxLookup::box_sum_int`] returns for that box (tests compare them on every box of a
//! sweep). What a batch saves: the accumulator-width proof ([`crate::width::check_acc`]),
//! which depends on the table, the form and `F` but not on the box, runs once per batch; the
//! 16-read in-range lookup is inlined into the loop instead of called out of line (the single
//! lookup keeps one out-of-line copy for flash, see `in_range_wide`); the mode's placement and
//! the table's parameters are read once per loop rather than per call. It does not share corner
//! reads between neighbouring boxes: footprints of a perspective scene overlap without sharing
//! exact corners.

use super::{
    check_acc, check_modular, in_range_wide_inline, split, sum_int, BoxLookup, BoxSum, Form, WideOf,
};
use crate::cost::Counter;
use crate::edge::{place_axis, width_u64, AxisPlan, EdgeMode};
use crate::error::Error;
use crate::layouts::Layout;
use crate::rect::{FracBits, RawBox, Rect};
use crate::wide::Wide;

/// Box lookups over a slice of boxes: implemented for every layout.
pub trait BatchLookup<const C: usize>: BoxLookup<C> {
    /// [`BoxLookup::box_sum_raw`] for each of `rects` into `out`, in order; returns how many
    /// were answered (`min(rects.len(), out.len())`). Each result is the single call's.
    #[inline]
    fn box_sums_raw<Fm: Form, M: EdgeMode, K: Counter>(
        &self,
        rects: &[Rect<i64>],
        frac_bits: FracBits,
        form: Fm,
        mode: M,
        k: &mut K,
        out: &mut [Result<BoxSum<WideOf<Self, C>, C>, Error>],
    ) -> usize {
        let f = frac_bits.get();
        // The one check that depends on no box: once (its result is used only where the single
        // call would check it, so errors come in the same order).
        let acc = check_acc(self, form, f);
        let mut n = 0usize;
        for (r, o) in rects.iter().zip(out.iter_mut()) {
            *o = one_raw(self, r, f, form, mode, acc, k);
            n = n.saturating_add(1);
        }
        n
    }

    /// [`BoxLookup::box_sum_int`] for each of `rects` into `out`, in order; returns how many
    /// were answered.
    #[inline]
    fn box_sums_int<M: EdgeMode, K: Counter>(
        &self,
        rects: &[Rect<i32>],
        mode: M,
        k: &mut K,
        out: &mut [Result<BoxSum<WideOf<Self, C>, C>, Error>],
    ) -> usize {
        let mut n = 0usize;
        for (r, o) in rects.iter().zip(out.iter_mut()) {
            *o = sum_int(self, r, mode, k);
            n = n.saturating_add(1);
        }
        n
    }
}

impl<const C: usize, L: Layout<C>> BatchLookup<C> for L {}

/// `sum_raw` with the accumulator check's result given and the in-range lookup inlined.
#[inline(always)]
fn one_raw<L: Layout<C>, Fm: Form, M: EdgeMode, K: Counter, const C: usize>(
    layout: &L,
    r: &Rect<i64>,
    f: u32,
    form: Fm,
    mode: M,
    acc: Result<(), Error>,
    k: &mut K,
) -> Result<BoxSum<WideOf<L, C>, C>, Error> {
    if r.x1 < r.x0 || r.y1 < r.y0 {
        return Err(Error::InvertedBox);
    }
    let mut out = BoxSum {
        sums: [<WideOf<L, C> as Wide>::ZERO; C],
        frac_bits: f,
        width_raw: width_u64(r.x0, r.x1),
        height_raw: width_u64(r.y0, r.y1),
    };
    if out.width_raw == 0 || out.height_raw == 0 {
        return Ok(out);
    }
    let kind = mode.kind();
    let px = place_axis(kind, r.x0, r.x1, layout.width(), f)?;
    let py = place_axis(kind, r.y0, r.y1, layout.height(), f)?;
    match (px, py) {
        (AxisPlan::Empty, _) | (_, AxisPlan::Empty) => {}
        (AxisPlan::InRange(x0, x1), AxisPlan::InRange(y0, y1)) => {
            let b = RawBox { x0, y0, x1, y1 };
            let placed = Rect::new(x0, y0, x1, y1);
            check_modular(layout, &placed, f, form.modular_headroom_bits(f))?;
            acc?;
            out.sums = in_range_wide_inline(layout, &b, f, form, k)?;
        }
        (px, py) => {
            check_modular(layout, r, f, form.modular_headroom_bits(f))?;
            acc?;
            out.sums = split::sum(layout, px, py, f, form, mode, k)?;
        }
    }
    Ok(out)
}
