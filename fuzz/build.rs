//! Copies `parse_box` (the `sat query` line parser) out of `tools/examples/sat.rs` into
//! `$OUT_DIR/parse_box.rs`, so that the `cli_query` target fuzzes the CLI's own function: the
//! example is a binary (its `main`, clap and the commands do not compile into a library), and a
//! copy in this crate would drift. Fails the build if the function is no longer there.

use std::path::Path;

fn main() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/examples/sat.rs");
    println!("cargo:rerun-if-changed={}", src.display());
    let text = std::fs::read_to_string(&src).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
    let start = text
        .find("\nfn parse_box(")
        .expect("fn parse_box not found in tools/examples/sat.rs: update fuzz/build.rs")
        + 1;
    let len = text[start..]
        .find("\n}\n")
        .expect("the end of fn parse_box not found")
        + 3;
    let body = &text[start..start + len];
    let out = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("parse_box.rs");
    std::fs::write(
        &out,
        format!("// Copied by fuzz/build.rs from tools/examples/sat.rs.\npub {body}"),
    )
    .unwrap_or_else(|e| panic!("{}: {e}", out.display()));
}
