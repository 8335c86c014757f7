//! Slices of the crate's generic texel and entry types seen as the concrete types of the `simd`
//! feature's row kernels: `u8` texels, `u32` entries (and, on ARMv7E-M, `u16` entries). Shared
//! by both kernel modules (`src/simd.rs` on x86-64, `src/dsp.rs` on ARMv7E-M), so that the one
//! cast they need is written and argued once ([`same`], [`same_mut`]).
//!
//! # Safety argument
//! Each function casts only after `TypeId` equality shows that the element type *is* the
//! target type (`T = u8`, `E = u32` or `E = u16`): the same type, so the same size, alignment,
//! validity and length. The new slice covers exactly the old one's elements and takes over its
//! borrow (shared for shared; for mutable, the `&mut` borrow is moved into the result), so no
//! two live references alias.
#![allow(unsafe_code)]
#![deny(
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::as_conversions
)]

use core::any::TypeId;

use crate::texel::{Entry, Texel};

/// `s` as `&[B]` when `A` is `B`, else `None`.
fn same<A: 'static, B: 'static>(s: &[A]) -> Option<&[B]> {
    (TypeId::of::<A>() == TypeId::of::<B>()).then(|| {
        // SAFETY: A is B (TypeId equality): the same layout and length; the shared borrow of
        // `s` carries over.
        unsafe { core::slice::from_raw_parts(s.as_ptr().cast::<B>(), s.len()) }
    })
}

/// `s` as `&mut [B]` when `A` is `B`, else `None`; the borrow is moved into the result.
fn same_mut<A: 'static, B: 'static>(s: &mut [A]) -> Option<&mut [B]> {
    (TypeId::of::<A>() == TypeId::of::<B>()).then(|| {
        // SAFETY: A is B (TypeId equality): the same layout and length; the mutable borrow of
        // `s` is moved into the result.
        unsafe { core::slice::from_raw_parts_mut(s.as_mut_ptr().cast::<B>(), s.len()) }
    })
}

/// `s` as `&[u8]` when `T` is `u8`, else `None`.
pub(crate) fn u8s<T: Texel>(s: &[T]) -> Option<&[u8]> {
    same(s)
}

/// `s` as `&[u32]` when `E` is `u32`, else `None`.
pub(crate) fn u32s<E: Entry>(s: &[E]) -> Option<&[u32]> {
    same(s)
}

/// `s` as `&mut [u32]` when `E` is `u32`, else `None`; the borrow is moved into the result.
pub(crate) fn u32s_mut<E: Entry>(s: &mut [E]) -> Option<&mut [u32]> {
    same_mut(s)
}

/// `s` as `&[u16]` when `E` is `u16`, else `None` (the ARMv7E-M row scan's `u16` tables).
#[cfg_attr(not(any(test, texsat_armv7em)), allow(dead_code))]
pub(crate) fn u16s<E: Entry>(s: &[E]) -> Option<&[u16]> {
    same(s)
}

/// `s` as `&mut [u16]` when `E` is `u16`, else `None`; the borrow is moved into the result.
#[cfg_attr(not(any(test, texsat_armv7em)), allow(dead_code))]
pub(crate) fn u16s_mut<E: Entry>(s: &mut [E]) -> Option<&mut [u16]> {
    same_mut(s)
}

#[cfg(test)]
#[allow(clippy::indexing_slicing, reason = "tests: a panic is a failed test")]
mod tests {
    use super::*;

    /// Each cast gives the same elements for its own type and declines every other.
    #[test]
    fn casts_take_their_own_type_only() {
        let texels = [1u8, 2, 255];
        assert_eq!(u8s(&texels), Some(&texels[..]));
        assert_eq!(u8s(&[1u16, 2]), None);
        let entries = [7u32, 0, u32::MAX];
        assert_eq!(u32s(&entries), Some(&entries[..]));
        assert_eq!(u32s(&[7u16]), None);
        assert_eq!(u32s(&[7u64]), None);
        let mut row = [1u32, 2, 3];
        if let Some(r) = u32s_mut(&mut row) {
            r[1] = 9;
        }
        assert_eq!(row, [1, 9, 3]);
        let mut wide = [1u64];
        assert!(u32s_mut(&mut wide).is_none());
        assert_eq!(u8s::<u8>(&[]), Some(&[][..]));
        let halves = [7u16, 0, u16::MAX];
        assert_eq!(u16s(&halves), Some(&halves[..]));
        assert_eq!(u16s(&entries), None);
        assert_eq!(u16s(&[7u64]), None);
        let mut row16 = [1u16, 2, 3];
        if let Some(r) = u16s_mut(&mut row16) {
            r[2] = 9;
        }
        assert_eq!(row16, [1, 2, 9]);
        assert!(u16s_mut(&mut row).is_none());
    }
}
