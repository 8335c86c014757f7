//! `--layout`: parsing the layout string, choosing the value type, and building the chosen
//! layout of a texture for code generic over [`BoxLookup`].
//!
//! | string | layout |
//! |---|---|
//! | `flat` | [`Sat`]: the flat table in native `u16`/`u32`/`u64` entries (`--entry`) |
//! | `packed` | [`TiledSpec::FLAT_PACKED`]: the flat table packed at its exact bit width |
//! | `tiled:WxH` | [`TiledSpec::tiles`]: one level of `W x H` tiles |
//! | `tiled:W1xH1/W2xH2[/...]` | tiles within tiles: x blocks `[W1, W2, ...]`, y blocks `[H1, H2, ...]` |
//! | `modular:K` | [`Modular`]: the flat table modulo `2^K`, packed at `K` bits |
//! | `modular:box=WxH` | the same with `K = modulus_bits_for(texel_bits, W * H)` |
//! | `tiled:...+mod:K`, `tiled:...+mod:box=WxH` | tiled with every field modulo `2^K` |

use crate::{entry_bits, entry_name, EntryArg};
use texsat::layouts::{modulus_bits_for, AxisLevels, Modular, Tiled, TiledSpec, MAX_LEVELS};
use texsat::width;
use texsat::{BoxLookup, Entry, Error, Sat, Texel, Texture};
use texsat_tools::budget::{self, Estimate};

/// The accepted forms, for error messages and help.
pub const FORMS: &str = "flat, packed, tiled:WxH, tiled:W1xH1/W2xH2[/...], modular:K, \
                         modular:box=WxH, tiled:WxH+mod:K or tiled:WxH+mod:box=WxH";

/// How the modulus of a modular layout is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModArg {
    /// `K`: values modulo `2^K`.
    Bits(u32),
    /// `box=WxH`: the smallest `K` that keeps every box of `W * H` texels exact.
    Box { w: u32, h: u32 },
}

impl ModArg {
    /// `K` for texels of `texel_bits` bits.
    pub fn bits(self, texel_bits: u32) -> u32 {
        match self {
            ModArg::Bits(k) => k,
            ModArg::Box { w, h } => modulus_bits_for(texel_bits, u64::from(w) * u64::from(h)),
        }
    }
}

/// The layout as parsed (before the image, and so the texel width, is known).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayoutKind {
    Flat,
    Packed,
    Tiled {
        x: AxisLevels,
        y: AxisLevels,
        modulus: Option<ModArg>,
    },
    Modular(ModArg),
}

/// The `--layout` value: the string as given and what it means.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayoutArg {
    pub text: String,
    pub kind: LayoutKind,
}

impl Default for LayoutArg {
    fn default() -> Self {
        LayoutArg {
            text: "flat".to_string(),
            kind: LayoutKind::Flat,
        }
    }
}

/// Parses a `--layout` string (see the module documentation).
pub fn parse_layout(s: &str) -> Result<LayoutArg, String> {
    let kind = match s {
        "flat" => LayoutKind::Flat,
        "packed" => LayoutKind::Packed,
        _ => {
            if let Some(rest) = s.strip_prefix("tiled:") {
                let (tiles, modulus) = match rest.split_once('+') {
                    None => (rest, None),
                    Some((tiles, m)) => {
                        let m = m
                            .strip_prefix("mod:")
                            .or_else(|| m.strip_prefix("modular:"))
                            .ok_or_else(|| {
                                format!("after '+' expected mod:K or mod:box=WxH, got '{m}'")
                            })?;
                        (tiles, Some(parse_mod(m)?))
                    }
                };
                let (x, y) = parse_tiles(tiles)?;
                LayoutKind::Tiled { x, y, modulus }
            } else if let Some(rest) = s.strip_prefix("modular:") {
                LayoutKind::Modular(parse_mod(rest)?)
            } else {
                return Err(format!("unknown layout '{s}'; expected {FORMS}"));
            }
        }
    };
    Ok(LayoutArg {
        text: s.to_string(),
        kind,
    })
}

/// A decimal `u32` of digits only.
fn parse_u32(s: &str, what: &str) -> Result<u32, String> {
    if s.is_empty() || !s.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("{what} '{s}' is not a positive integer"));
    }
    s.parse().map_err(|_| format!("{what} '{s}' is too large"))
}

/// `WxH`, both at least 1.
fn parse_size(s: &str, what: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("{what} '{s}' is not of the form WxH (e.g. 8x8)"))?;
    let (w, h) = (
        parse_u32(w, &format!("{what} width"))?,
        parse_u32(h, &format!("{what} height"))?,
    );
    if w == 0 || h == 0 {
        return Err(format!("{what} '{s}' has a zero side"));
    }
    Ok((w, h))
}

/// `W1xH1/W2xH2/...`: the block sizes of each axis.
fn parse_tiles(s: &str) -> Result<(AxisLevels, AxisLevels), String> {
    let levels: Vec<(u32, u32)> = s
        .split('/')
        .map(|t| parse_size(t, "tile size"))
        .collect::<Result<_, _>>()?;
    if levels.len() > MAX_LEVELS {
        return Err(format!(
            "{} tile levels given; at most {MAX_LEVELS} are supported",
            levels.len()
        ));
    }
    let xs: Vec<u32> = levels.iter().map(|l| l.0).collect();
    let ys: Vec<u32> = levels.iter().map(|l| l.1).collect();
    let x = AxisLevels::new(&xs).map_err(|e| format!("tile widths {xs:?}: {e}"))?;
    let y = AxisLevels::new(&ys).map_err(|e| format!("tile heights {ys:?}: {e}"))?;
    Ok((x, y))
}

/// `K` (1 to 64) or `box=WxH`.
fn parse_mod(s: &str) -> Result<ModArg, String> {
    if let Some(size) = s.strip_prefix("box=") {
        let (w, h) = parse_size(size, "modular box")?;
        return Ok(ModArg::Box { w, h });
    }
    let k = parse_u32(s, "modulus bits")?;
    if !(1..=64).contains(&k) {
        return Err(format!("modulus bits {k} outside 1..=64"));
    }
    Ok(ModArg::Bits(k))
}

// ---------------------------------------------------------------------------------------------
// Resolving against the image

/// What to build, with the texel width known.
#[derive(Clone, Copy, Debug)]
pub enum Plan {
    Flat { entry: EntryArg, checked: bool },
    Tiled { spec: TiledSpec, value: EntryArg },
    Modular { k: u32, value: EntryArg },
}

impl Plan {
    /// The value type corner values are summed in.
    pub fn value(&self) -> EntryArg {
        match *self {
            Plan::Flat { entry, .. } => entry,
            Plan::Tiled { value, .. } | Plan::Modular { value, .. } => value,
        }
    }

    /// Whether `--checked` applies (the flat layout's data-dependent build).
    pub fn checked(&self) -> bool {
        matches!(self, Plan::Flat { checked: true, .. })
    }

    /// Whether the build proves the worst case first (flat without `--checked`, exact tiled).
    pub fn worst_case(&self) -> bool {
        match self {
            Plan::Flat { checked, .. } => !checked,
            Plan::Tiled { spec, .. } => spec.modulus.is_none(),
            Plan::Modular { .. } => false,
        }
    }
}

/// Chooses the value type and `K` for `layout` on texels of `texel_bits` bits. `entry` is the
/// `--entry` option if given: the default is `u32` for exact layouts and the narrowest of
/// `u32`/`u64` holding `K` for modular ones.
pub fn resolve(
    layout: &LayoutArg,
    entry: Option<EntryArg>,
    checked: bool,
    texel_bits: u32,
) -> Result<Plan, String> {
    if checked && layout.kind != LayoutKind::Flat {
        return Err(format!(
            "--checked applies to the flat layout only (layout '{}' is built from the worst case \
             or modulo 2^K)",
            layout.text
        ));
    }
    let modular_value = |k: u32, u16_ok: bool| -> Result<EntryArg, String> {
        if k < texel_bits {
            return Err(format!(
                "layout '{}': K = {k} bits is less than the texel width ({texel_bits} bits); \
                 one texel would not fit",
                layout.text
            ));
        }
        match entry {
            None if k <= 32 => Ok(EntryArg::U32),
            None => Ok(EntryArg::U64),
            Some(e) if entry_bits(e) < k => Err(format!(
                "layout '{}': K = {k} bits does not fit --entry {} ({} bits)",
                layout.text,
                entry_name(e),
                entry_bits(e)
            )),
            Some(EntryArg::U16) if !u16_ok => Err(format!(
                "layout '{}': the modular layout computes in u32 or u64 (--entry u16 is not offered \
                 for it)",
                layout.text
            )),
            Some(e) => Ok(e),
        }
    };
    Ok(match layout.kind {
        LayoutKind::Flat => Plan::Flat {
            entry: entry.unwrap_or(EntryArg::U32),
            checked,
        },
        LayoutKind::Packed => Plan::Tiled {
            spec: TiledSpec::FLAT_PACKED,
            value: entry.unwrap_or(EntryArg::U32),
        },
        LayoutKind::Tiled {
            x,
            y,
            modulus: None,
        } => Plan::Tiled {
            spec: TiledSpec {
                x,
                y,
                modulus: None,
            },
            value: entry.unwrap_or(EntryArg::U32),
        },
        LayoutKind::Tiled {
            x,
            y,
            modulus: Some(m),
        } => {
            let k = m.bits(texel_bits);
            Plan::Tiled {
                spec: TiledSpec {
                    x,
                    y,
                    modulus: None,
                }
                .with_modulus(k),
                value: modular_value(k, true)?,
            }
        }
        LayoutKind::Modular(m) => {
            let k = m.bits(texel_bits);
            Plan::Modular {
                k,
                value: modular_value(k, false)?,
            }
        }
    })
}

// ---------------------------------------------------------------------------------------------
// Building

/// What `sat info` reports about a built layout beyond the [`texsat::Layout`] methods.
#[derive(Clone, Debug)]
pub enum Detail {
    Flat {
        entries: usize,
        table_bytes: usize,
    },
    Tiled {
        spec: TiledSpec,
        words: usize,
        /// `field_bits[p][q]`: `p` the x level, `q` the y level.
        field_bits: Vec<Vec<u32>>,
        fields_per_corner: usize,
    },
    Modular {
        k: u32,
        words: usize,
        max_exact_area: u128,
    },
}

/// Code generic over the layout and the channel count, run on a built layout.
pub trait LayoutJob {
    type Out;
    fn run<L: BoxLookup<C>, const C: usize>(self, layout: &L, detail: &Detail) -> Self::Out;
}

/// The largest box area (in texel cells) whose sum stays below `2^k`.
pub fn max_exact_area(k: u32, texel_bits: u32) -> u128 {
    let modulus = if k >= 128 {
        u128::MAX
    } else {
        (1u128 << k) - 1
    };
    modulus / width::max_texel(texel_bits)
}

/// Why a layout was not built: the crate refused it (the caller explains the numbers), or its
/// storage could not be allocated.
#[derive(Debug)]
pub enum Refused {
    Build(Error),
    Alloc(String),
}

impl From<Error> for Refused {
    fn from(e: Error) -> Self {
        Refused::Build(e)
    }
}

/// Adds to `est` the storage [`with_layout`] allocates for `plan` on a `w x h` texture of `T`
/// texels with `C` channels: the same `texsat` size functions, through [`budget`].
pub fn estimate<T: Texel, const C: usize>(plan: &Plan, w: usize, h: usize, est: &mut Estimate) {
    let item = match *plan {
        Plan::Flat { entry, .. } => match entry {
            EntryArg::U16 => budget::flat::<u16, C>(w, h),
            EntryArg::U32 => budget::flat::<u32, C>(w, h),
            EntryArg::U64 => budget::flat::<u64, C>(w, h),
        },
        Plan::Tiled { spec, value } => match value {
            EntryArg::U16 => budget::tiled::<u16, C>(spec, w, h, T::BITS),
            EntryArg::U32 => budget::tiled::<u32, C>(spec, w, h, T::BITS),
            EntryArg::U64 => budget::tiled::<u64, C>(spec, w, h, T::BITS),
        },
        Plan::Modular { k, value } => match value {
            EntryArg::U64 => budget::modular::<u64, C>(w, h, k),
            _ => budget::modular::<u32, C>(w, h, k),
        },
    };
    est.push_sized(item);
}

/// Builds the layout `plan` of `texture` and runs `job` on it. Every buffer is sized by the
/// function [`estimate`] counts and reserved with `try_reserve_exact`.
///
/// Monomorphization: the job runs on `Sat<u16 | u32 | u64>`, `Tiled<u16 | u32 | u64>` (packed,
/// tiled and tiled+modular share that type) and `Modular<u32 | u64>`, for each channel count.
pub fn with_layout<T: Texel, const C: usize, J: LayoutJob>(
    texture: &Texture<'_, T, C>,
    plan: &Plan,
    job: J,
) -> Result<J::Out, Refused> {
    match *plan {
        Plan::Flat { entry, checked } => match entry {
            EntryArg::U16 => flat::<T, u16, C, J>(texture, checked, job),
            EntryArg::U32 => flat::<T, u32, C, J>(texture, checked, job),
            EntryArg::U64 => flat::<T, u64, C, J>(texture, checked, job),
        },
        Plan::Tiled { spec, value } => match value {
            EntryArg::U16 => tiled::<T, u16, C, J>(texture, spec, job),
            EntryArg::U32 => tiled::<T, u32, C, J>(texture, spec, job),
            EntryArg::U64 => tiled::<T, u64, C, J>(texture, spec, job),
        },
        Plan::Modular { k, value } => match value {
            EntryArg::U32 => modular::<T, u32, C, J>(texture, k, job),
            EntryArg::U64 => modular::<T, u64, C, J>(texture, k, job),
            // resolve() never picks u16 for the modular layout.
            EntryArg::U16 => Err(Refused::Alloc(
                "internal error: the modular layout has no u16 values".to_string(),
            )),
        },
    }
}

fn flat<T: Texel, E: Entry, const C: usize, J: LayoutJob>(
    texture: &Texture<'_, T, C>,
    checked: bool,
    job: J,
) -> Result<J::Out, Refused> {
    let n = Sat::<E, C>::entries_needed(texture.width(), texture.height())?;
    let mut storage = budget::zeroed(n, E::ZERO, "summed-area table").map_err(Refused::Alloc)?;
    let sat = if checked {
        Sat::build_checked(texture, &mut storage)?
    } else {
        Sat::build(texture, &mut storage)?
    };
    let detail = Detail::Flat {
        entries: sat.entries().len(),
        table_bytes: sat.table_bytes(),
    };
    Ok(job.run(&sat, &detail))
}

fn tiled<T: Texel, E: Entry, const C: usize, J: LayoutJob>(
    texture: &Texture<'_, T, C>,
    spec: TiledSpec,
    job: J,
) -> Result<J::Out, Refused> {
    let (w, h) = (texture.width(), texture.height());
    let words_needed = Tiled::<E, C>::words_needed(spec, w, h, T::BITS)?;
    let scratch_needed = Tiled::<E, C>::scratch_needed(spec, w)?;
    let mut words = budget::zeroed(words_needed, 0u32, "tiled table").map_err(Refused::Alloc)?;
    let mut scratch =
        budget::zeroed(scratch_needed, E::ZERO, "tiled build's scratch").map_err(Refused::Alloc)?;
    let t = Tiled::<E, C>::build(texture, spec, &mut words, &mut scratch)?;
    drop(scratch);
    let field_bits = (0..spec.x.components())
        .map(|p| {
            (0..spec.y.components())
                .map(|q| t.field_bits(p, q).unwrap_or(0))
                .collect()
        })
        .collect();
    let detail = Detail::Tiled {
        spec,
        words: words_needed,
        field_bits,
        fields_per_corner: t.max_fields_per_corner(),
    };
    Ok(job.run(&t, &detail))
}

fn modular<T: Texel, E: Entry, const C: usize, J: LayoutJob>(
    texture: &Texture<'_, T, C>,
    k: u32,
    job: J,
) -> Result<J::Out, Refused> {
    let (w, h) = (texture.width(), texture.height());
    let words_needed = Modular::<E, C>::words_needed(w, h, k)?;
    let row_needed = budget::modular_row::<C>(w)?;
    let mut words = budget::zeroed(words_needed, 0u32, "modular table").map_err(Refused::Alloc)?;
    let mut row =
        budget::zeroed(row_needed, E::ZERO, "modular build's row").map_err(Refused::Alloc)?;
    let m = Modular::<E, C>::build(texture, k, &mut words, &mut row)?;
    let detail = Detail::Modular {
        k,
        words: words_needed,
        max_exact_area: u128::from(m.max_exact_area()),
    };
    Ok(job.run(&m, &detail))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_form() {
        assert_eq!(parse_layout("flat").unwrap().kind, LayoutKind::Flat);
        assert_eq!(parse_layout("packed").unwrap().kind, LayoutKind::Packed);
        let t = parse_layout("tiled:8x4").unwrap();
        assert_eq!(
            t.kind,
            LayoutKind::Tiled {
                x: AxisLevels::new(&[8]).unwrap(),
                y: AxisLevels::new(&[4]).unwrap(),
                modulus: None
            }
        );
        assert_eq!(t.text, "tiled:8x4");
        assert_eq!(
            parse_layout("tiled:2x2/16x8+mod:17").unwrap().kind,
            LayoutKind::Tiled {
                x: AxisLevels::new(&[2, 16]).unwrap(),
                y: AxisLevels::new(&[2, 8]).unwrap(),
                modulus: Some(ModArg::Bits(17))
            }
        );
        assert_eq!(
            parse_layout("modular:box=16x16").unwrap().kind,
            LayoutKind::Modular(ModArg::Box { w: 16, h: 16 })
        );
        assert_eq!(
            parse_layout("modular:40").unwrap().kind,
            LayoutKind::Modular(ModArg::Bits(40))
        );
        assert_eq!(ModArg::Box { w: 16, h: 16 }.bits(8), 16);
        assert_eq!(ModArg::Box { w: 17, h: 17 }.bits(8), 17);
    }

    #[test]
    fn refuses_malformed_strings() {
        for bad in [
            "",
            "Flat",
            "tiled",
            "tiled:",
            "tiled:8",
            "tiled:8x",
            "tiled:x8",
            "tiled:0x8",
            "tiled:1x1",
            "tiled:8x8/12x16",
            "tiled:8x8/4x4",
            "tiled:2x2/4x4/8x8/16x16/32x32",
            "tiled:+8x8",
            "tiled:8x8+",
            "tiled:8x8+mod:",
            "tiled:8x8+k:16",
            "modular:",
            "modular:0",
            "modular:65",
            "modular:-3",
            "modular:box=16",
            "modular:box=0x4",
            "modular:16+tiled:8x8",
            "packed+mod:16",
            "tiles:8x8",
            "tiled:99999999999x2",
        ] {
            assert!(parse_layout(bad).is_err(), "{bad:?} should be refused");
        }
    }
}
