//! Host tools for texsat: see `examples/` (`sat`, `report`, `layouts`) and `tests/`.
//! The package exists so that the tools' dependencies (and the `filters` feature they need) stay
//! out of the core's own test build. The library holds what the tools share: [`budget`], the
//! memory and work estimates every command checks before it allocates, and [`image_file`], the
//! image reading under decoder limits (header first, samples after the budget check), and
//! [`cache`], the memory-traffic and texel-cache models of a hardware texture unit. With the
//! feature `parallel`, `parallel` builds large tables on all cores.
// A host-only package: on a bare-metal target (the workspace root's default members, built
// with `--target thumbv7em-none-eabihf`) the library is empty and `no_std`.
#![cfg_attr(target_os = "none", no_std)]
#![cfg(not(target_os = "none"))]

pub mod budget;
pub mod cache;
pub mod image_file;
#[cfg(feature = "parallel")]
pub mod parallel;
