//! Shared by the integration tests that run an example binary (`cli.rs`, `report.rs`).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The path of example `name`, built for the profile and target directory of the running test
/// (`cargo test --test X` does not build examples); `env_override` names a variable that, when
/// set, gives another binary to test instead.
pub fn example_bin(name: &str, env_override: &str, features: &[&str]) -> PathBuf {
    if let Some(bin) = std::env::var_os(env_override) {
        return PathBuf::from(bin);
    }
    // target/<profile>/deps/<test>-XXXX -> target/<profile>/examples/<name>
    let exe = std::env::current_exe().expect("current_exe");
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>");
    let target_dir = profile_dir.parent().expect("target dir");
    let mut cmd = Command::new(env!("CARGO"));
    cmd.args(["build", "--quiet", "--example", name]);
    for f in features {
        cmd.args(["--features", f]);
    }
    cmd.arg("--manifest-path")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
        .arg("--target-dir")
        .arg(target_dir);
    if profile_dir.file_name().is_some_and(|n| n == "release") {
        cmd.arg("--release");
    }
    let status = cmd
        .status()
        .unwrap_or_else(|e| panic!("running cargo build --example {name}: {e}"));
    assert!(status.success(), "cargo build --example {name} failed");
    let bin = profile_dir
        .join("examples")
        .join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    assert!(bin.exists(), "{} not found after building", bin.display());
    bin
}
