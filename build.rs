//! Emits `texsat_armv7em` when building for an ARMv7E-M core (`thumbv7em-*`: Cortex-M4 and
//! Cortex-M7), whose DSP extension the `simd` feature's row scan uses (`src/dsp.rs`). Stable
//! Rust does not expose ARM target features to `cfg`, so the target's name decides, as the
//! `cortex-m` crate's build script does.
fn main() {
    println!("cargo:rustc-check-cfg=cfg(texsat_armv7em)");
    println!("cargo:rerun-if-env-changed=TARGET");
    let target = std::env::var("TARGET").unwrap_or_default();
    if target.starts_with("thumbv7em-") {
        println!("cargo:rustc-cfg=texsat_armv7em");
    }
}
