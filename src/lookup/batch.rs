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

use super::{check_acc, sum_int, sum_raw_with, BoxLookup, BoxSum, Form, WideOf};
use crate::cost::Counter;
use crate::edge::EdgeMode;
use crate::error::Error;
use crate::layouts::Layout;
use crate::rect::{FracBits, Rect};

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
            *o = sum_raw_with::<Self, Fm, M, K, _, C, true>(self, r, f, form, mode, || acc, k);
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
