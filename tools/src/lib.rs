//! Host tools for texsat: see `examples/` (`sat`, `report`, `layouts`) and `tests/`.
//! The library itself is empty; the package exists so that the tools' dependencies (and the
//! `filters` feature they need) stay out of the core's own test build.
