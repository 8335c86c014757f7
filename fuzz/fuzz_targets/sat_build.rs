//! The builds against a `u128` reference: `Texture::with_stride`, `Sat::build`,
//! `Sat::build_checked`, `RowStreamBuilder` and `Sat::from_table` (on the built table and on
//! copies with a few entries changed), with `u8`/`u16` texels, `u16`/`u32`/`u64` entries, 1 or 3
//! channels, strides with padding, and storage that is sometimes too short.
//!
//! Every build must return exactly the reference table or exactly the documented error (the same
//! numbers in it), and a refused build must leave the storage as it was, except
//! `build_checked`'s overflow, which is documented to leave a partial table.
#![no_main]

use arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use texsat::{Entry, Error, Quantity, RowStreamBuilder, Sat, Texel, Texture};
use texsat_fuzz::{bits_of, from_table_verdict, worst_case_bits, Tex};

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = run(&mut u);
});

fn run(u: &mut Unstructured<'_>) -> Result<()> {
    let e = u.int_in_range(0u8..=2)?;
    let wide = u.arbitrary::<bool>()?;
    let three = u.arbitrary::<bool>()?;
    match (e, wide, three) {
        (0, false, false) => check::<u16, u8, 1>(u),
        (0, false, true) => check::<u16, u8, 3>(u),
        (0, true, false) => check::<u16, u16, 1>(u),
        (0, true, true) => check::<u16, u16, 3>(u),
        (1, false, false) => check::<u32, u8, 1>(u),
        (1, false, true) => check::<u32, u8, 3>(u),
        (1, true, false) => check::<u32, u16, 1>(u),
        (1, true, true) => check::<u32, u16, 3>(u),
        (_, false, false) => check::<u64, u8, 1>(u),
        (_, false, true) => check::<u64, u8, 3>(u),
        (_, true, false) => check::<u64, u16, 1>(u),
        (_, true, true) => check::<u64, u16, 3>(u),
    }
}

fn to_u128<E: Entry>(v: &[E]) -> Vec<u128> {
    v.iter().map(|e| e.to_u128()).collect()
}

/// Storage of `needed` entries, or a few more, or (one time in eight) fewer, filled with a
/// pattern so that writes outside the table show.
fn storage<E: Entry>(u: &mut Unstructured<'_>, needed: usize) -> Result<Vec<E>> {
    let len = if u.ratio(1u8, 8)? {
        u.int_in_range(0..=needed.saturating_sub(1))?
    } else {
        needed + u.int_in_range(0..=3)?
    };
    Ok(vec![E::from(0xA5A5); len])
}

fn check<E: Entry + std::fmt::Debug, T: Texel, const C: usize>(
    u: &mut Unstructured<'_>,
) -> Result<()> {
    let tex = Tex::gen(u, C, T::BITS, 16, 16)?;
    let (w, h) = (tex.w, tex.h);
    let row = w * C;
    let reference = tex.sat();
    let totals = tex.totals();
    let max_total = totals.iter().copied().max().unwrap_or(0);
    let e_max = u128::from(u64::MAX) >> (64 - E::BITS);

    // The texture in memory: rows `stride` apart, the padding filled with arbitrary texels.
    let stride = row + u.int_in_range(0..=3)?;
    let mut data = Vec::with_capacity(stride * h);
    for y in 0..h {
        for i in 0..stride {
            data.push(if i < row {
                T::from_u16_clamped(tex.t[y * row + i])
            } else {
                T::from_u16_clamped(u.arbitrary()?)
            });
        }
    }
    // Refusals of the texture view itself.
    match u.int_in_range(0u8..=15)? {
        0 => {
            let bad = u.int_in_range(0..=row - 1)?;
            assert_eq!(
                Texture::<T, C>::with_stride(&data, w, h, bad).map(|_| ()),
                Err(Error::StrideTooSmall {
                    stride: bad,
                    needed: row
                })
            );
        }
        1 => {
            let needed = stride * (h - 1) + row;
            let short = u.int_in_range(0..=needed - 1)?;
            assert_eq!(
                Texture::<T, C>::with_stride(&data[..short], w, h, stride).map(|_| ()),
                Err(Error::TextureDataTooShort { needed, got: short })
            );
        }
        2 => {
            assert_eq!(
                Texture::<T, C>::new(&data, 0, h).map(|_| ()),
                Err(Error::EmptyTexture)
            );
            assert_eq!(Sat::<E, C>::entries_needed(w, 0), Err(Error::EmptyTexture));
        }
        _ => {}
    }
    assert_eq!(Sat::<E, C>::entries_needed(w, h), Ok(w * h * C));
    // The padding may be omitted after the last row.
    let texture = Texture::<T, C>::with_stride(&data[..stride * (h - 1) + row], w, h, stride)
        .expect("a valid texture");
    let needed = w * h * C;

    // Sat::build: the worst case first, then the storage; nothing written on refusal.
    let mut st = storage::<E>(u, needed)?;
    let before = st.clone();
    let worst = worst_case_bits(T::BITS, w, h);
    let got = Sat::build(&texture, &mut st).map(|s| (to_u128(s.entries()), s.total()));
    if worst > E::BITS {
        assert_eq!(
            got.map(|_| ()),
            Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: worst,
                bits_available: E::BITS
            })
        );
        assert!(st == before, "Sat::build wrote before refusing");
    } else if st.len() < needed {
        assert_eq!(
            got.map(|_| ()),
            Err(Error::StorageTooSmall {
                needed,
                got: st.len()
            })
        );
        assert!(st == before, "Sat::build wrote before refusing");
    } else {
        let (entries, total) = got.expect("Sat::build refused a texture it must build");
        assert_eq!(entries, reference, "Sat::build");
        assert_eq!(to_u128(&total), totals, "Sat::build total");
        assert!(
            st[needed..] == before[needed..],
            "Sat::build wrote past the table"
        );
    }

    // Sat::build_checked: the storage first, then the actual sums.
    let mut st = storage::<E>(u, needed)?;
    let before = st.clone();
    let got = Sat::build_checked(&texture, &mut st).map(|s| {
        // The accessors of the built table.
        assert_eq!((s.width(), s.height(), s.texel_bits()), (w, h, T::BITS));
        assert_eq!(s.table_bytes(), needed * core::mem::size_of::<E>());
        assert_eq!(s.total_bits(), bits_of(max_total));
        for y in 0..=h + 1 {
            for x in 0..=w + 1 {
                let c = s.corner(x, y).map(|v| to_u128(&v));
                let want = (x <= w && y <= h).then(|| {
                    (0..C)
                        .map(|ch| {
                            if x == 0 || y == 0 {
                                0
                            } else {
                                reference[((y - 1) * w + x - 1) * C + ch]
                            }
                        })
                        .collect::<Vec<_>>()
                });
                assert_eq!(c, want, "corner({x}, {y})");
            }
        }
        to_u128(s.entries())
    });
    if st.len() < needed {
        assert_eq!(
            got,
            Err(Error::StorageTooSmall {
                needed,
                got: st.len()
            })
        );
        assert!(st == before, "build_checked wrote before refusing");
    } else if max_total > e_max {
        assert_eq!(
            got,
            Err(Error::TooWide {
                what: Quantity::Entry,
                bits_needed: bits_of(max_total),
                bits_available: E::BITS
            })
        );
    } else {
        assert_eq!(got, Ok(reference.clone()), "Sat::build_checked");
        assert!(
            st[needed..] == before[needed..],
            "build_checked wrote past the table"
        );
    }

    // RowStreamBuilder with a stated texel width that may differ from T's.
    let tb = match u.int_in_range(0u8..=7)? {
        0 => u.int_in_range(0..=17)?,
        1 => u.int_in_range(1..=16)?,
        _ => T::BITS,
    };
    let mut rs = storage::<E>(u, row)?;
    let rs_len = rs.len();
    let got = RowStreamBuilder::<E, C>::new(w, h, tb, &mut rs);
    let want_err = if tb == 0 || tb > 16 {
        Some(Error::InvalidTexelBits { bits: tb })
    } else if worst_case_bits(tb, w, h) > E::BITS {
        Some(Error::TooWide {
            what: Quantity::Entry,
            bits_needed: worst_case_bits(tb, w, h),
            bits_available: E::BITS,
        })
    } else if rs_len < row {
        Some(Error::StorageTooSmall {
            needed: row,
            got: rs_len,
        })
    } else {
        None
    };
    let mut b = match (got, want_err) {
        (Err(e), Some(want)) => {
            assert_eq!(e, want, "RowStreamBuilder::new");
            return Ok(());
        }
        (Ok(b), None) => b,
        (got, want) => panic!(
            "RowStreamBuilder::new: got {:?}, want {want:?}",
            got.map(|_| ())
        ),
    };
    let stop = if u.ratio(1u8, 8)? {
        u.int_in_range(0..=h)?
    } else {
        h
    };
    let mut table: Vec<u128> = Vec::with_capacity(needed);
    for y in 0..stop {
        let texels = texture.row(y).expect("row in range");
        if u.ratio(1u8, 16)? {
            let len = u.int_in_range(0..=row + 2)?;
            if len != row {
                let wrong: Vec<T> = (0..len).map(|i| texels[i % row]).collect();
                assert_eq!(
                    b.push_row(&wrong).map(|_| ()),
                    Err(Error::RowLength {
                        expected: row,
                        got: len
                    })
                );
            }
        }
        let want = &reference[y * row..(y + 1) * row];
        let overflow = want.iter().any(|&v| v > e_max);
        match b.push_row(texels) {
            Ok(out) => {
                assert!(!overflow, "push_row: row {y} overflows but was accepted");
                assert_eq!(to_u128(out), want, "push_row({y})");
                table.extend_from_slice(want);
            }
            Err(e) => {
                // Only texels wider than the stated bits take checked additions, and only an
                // overflow of E refuses them.
                assert!(T::BITS > tb && overflow, "push_row({y}): {e:?}");
                assert_eq!(
                    e,
                    Error::TooWide {
                        what: Quantity::Entry,
                        bits_needed: E::BITS + 1,
                        bits_available: E::BITS
                    }
                );
                return Ok(());
            }
        }
        assert_eq!(b.rows_done(), y + 1);
    }
    if stop < h {
        assert_eq!(
            b.finish(),
            Err(Error::MissingRows {
                got: stop,
                expected: h
            })
        );
        return Ok(());
    }
    let last_row = texture.row(h - 1).expect("row in range");
    assert_eq!(b.push_row(last_row).map(|_| ()), Err(Error::TooManyRows));
    let last = b.finish().map(to_u128);
    assert_eq!(last.as_deref(), Ok(&reference[(h - 1) * row..]), "finish");

    // Sat::from_table: the streamed table, then copies with a few entries changed; accepted
    // exactly when the texels it implies lie in [0, 2^b - 1].
    let stored: Vec<E> = table
        .iter()
        .map(|&v| E::from_u64_truncating(v as u64))
        .collect();
    let got = Sat::<E, C>::from_table(&stored, w, h, T::BITS).map(|s| to_u128(s.entries()));
    assert_eq!(
        got,
        from_table_verdict(&reference, w, h, C, T::BITS),
        "from_table of a built table"
    );
    let mut bad = stored.clone();
    for _ in 0..u.int_in_range(1..=3)? {
        let i = u.int_in_range(0..=needed - 1)?;
        let v = bad[i].to_u64();
        let nv = match u.int_in_range(0u8..=3)? {
            0 => v.wrapping_add(1),
            1 => v.wrapping_sub(1),
            2 => v ^ (1 << u.int_in_range(0..=E::BITS - 1)?),
            _ => u.arbitrary()?,
        };
        bad[i] = E::from_u64_truncating(nv);
    }
    let bits = if u.ratio(1u8, 8)? {
        u.int_in_range(0..=17)?
    } else {
        T::BITS
    };
    let got = Sat::<E, C>::from_table(&bad, w, h, bits).map(|s| to_u128(s.entries()));
    let bad128 = to_u128(&bad);
    if bits == 0 || bits > 16 {
        assert_eq!(got, Err(Error::InvalidTexelBits { bits }));
    } else {
        let want = from_table_verdict(&bad128, w, h, C, bits);
        assert_eq!(got, want, "from_table of a changed table");
    }
    // Too short a table.
    if u.ratio(1u8, 8)? {
        let short = u.int_in_range(0..=needed - 1)?;
        assert_eq!(
            Sat::<E, C>::from_table(&bad[..short], w, h, T::BITS).map(|_| ()),
            Err(Error::StorageTooSmall { needed, got: short })
        );
    }
    Ok(())
}
