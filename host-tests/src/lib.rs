//! f64 references for texsat's host tests.
