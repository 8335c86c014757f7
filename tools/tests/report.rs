//! Runs the report example (`examples/report.rs`) with `--quick` into a temporary folder and
//! checks its files: `report.md`, `report.csv`, `stability.csv` and the PNGs exist; every method
//! has a row with finite numbers for every scene; the summed-area-table lookups are exact
//! against the integer reference (arithmetic error 0) and the paper and stable forms agree.
//!
//! `cargo test` does not build examples when a single test target is selected
//! (`cargo test --test report`), so the test runs `cargo build --example report` for the same
//! profile and target directory first (as `tests/cli.rs` does); set `REPORT_BIN` to test
//! another binary.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

const METHODS: [&str; 17] = [
    "point",
    "mip-point",
    "trilinear",
    "ripmap",
    "dipmap-bilinear",
    "dipmap-trilinear",
    "sat4",
    "sat16-paper",
    "sat16-stable",
    "sat16-stable-tiled8",
    "sat16-stable-tiled2-16",
    "sat16-stable-modular",
    "sat-plan",
    "tent-int",
    "tent-paper",
    "tent-exact",
    "ewa",
];

/// Methods whose arithmetic is exact: their values must equal the integer reference rounded to
/// 16 fraction bits.
const EXACT: [&str; 9] = [
    "sat4",
    "sat16-paper",
    "sat16-stable",
    "sat16-stable-tiled8",
    "sat16-stable-tiled2-16",
    "sat16-stable-modular",
    "sat-plan",
    "tent-int",
    "tent-exact",
];

fn report_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| common::example_bin("report", "REPORT_BIN", &[]))
}

struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

fn temp_dir(test: &str) -> TempDir {
    let dir = std::env::temp_dir().join(format!("texsat-report-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(report_bin())
        .args(args)
        .output()
        .expect("running the report")
}

/// The CSV as rows of `column -> value` (no quoted commas in the numeric columns; the note
/// column is last and may be quoted).
fn read_csv(path: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).expect("report.csv");
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            let mut fields: Vec<String> = Vec::new();
            let (mut cur, mut quoted) = (String::new(), false);
            let mut chars = l.chars().peekable();
            while let Some(c) = chars.next() {
                match c {
                    '"' if quoted && chars.peek() == Some(&'"') => {
                        cur.push('"');
                        chars.next();
                    }
                    '"' => quoted = !quoted,
                    ',' if !quoted => fields.push(std::mem::take(&mut cur)),
                    _ => cur.push(c),
                }
            }
            fields.push(cur);
            assert_eq!(fields.len(), header.len(), "row {l:?}");
            header.iter().cloned().zip(fields).collect()
        })
        .collect()
}

fn number(row: &BTreeMap<String, String>, col: &str) -> f64 {
    let v = &row[col];
    v.parse::<f64>().unwrap_or_else(|_| {
        panic!(
            "{} / {}: column {col} is {v:?}, not a number",
            row["scene"], row["method"]
        )
    })
}

fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.len() > 1000 && b.starts_with(b"\x89PNG\r\n\x1a\n"))
}

#[test]
fn quick_report_has_every_file_and_number() {
    let dir = temp_dir("quick");
    let out = run(&["--quick", "--out", dir.0.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "report failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(dir.0.join("report.md")).expect("report.md");
    for section in [
        "## Summary",
        "## Scenes",
        "## Numerical stability",
        "## Methodology",
        "## CSV columns",
    ] {
        assert!(md.contains(section), "report.md lacks {section}");
    }
    for png in [
        "error_vs_time.png",
        "error_vs_cost.png",
        "float32_error_vs_size.png",
    ] {
        assert!(is_png(&dir.0.join(png)), "{png} missing or not a PNG");
    }
    let stability = std::fs::read_to_string(dir.0.join("stability.csv")).expect("stability.csv");
    assert!(stability.lines().count() > 1, "stability.csv has no rows");

    let rows = read_csv(&dir.0.join("report.csv"));
    let scenes: BTreeSet<String> = rows.iter().map(|r| r["scene"].clone()).collect();
    assert!(!scenes.is_empty());
    for scene in &scenes {
        assert!(
            md.contains(&format!("### {scene}")),
            "report.md lacks scene {scene}"
        );
        let stem: String = scene
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        assert!(
            is_png(&dir.0.join(format!("render_{stem}.png"))),
            "render of {scene} missing"
        );
        let by_method: BTreeMap<&str, &BTreeMap<String, String>> = rows
            .iter()
            .filter(|r| &r["scene"] == scene)
            .map(|r| (r["method"].as_str(), r))
            .collect();
        assert_eq!(
            by_method.keys().copied().collect::<Vec<_>>().len(),
            METHODS.len(),
            "{scene}: methods {:?}",
            by_method.keys()
        );
        for m in METHODS {
            let row = by_method
                .get(m)
                .unwrap_or_else(|| panic!("{scene}: no {m} row"));
            assert!(number(row, "samples") > 0.0, "{scene} / {m}: no samples");
            assert_eq!(number(row, "refused"), 0.0, "{scene} / {m}: refusals");
            let mut cols = vec![
                "rmse",
                "max_abs_error",
                "arith_error",
                "ns_per_sample",
                "bits_per_texel",
                "memory_ratio",
            ];
            // EWA, the f64 reference, has no operation counter.
            if m != "ewa" {
                cols.extend(["reads", "bits_read", "muls", "divs", "adds"]);
            }
            for col in cols {
                let v = number(row, col);
                assert!(v.is_finite() && v >= 0.0, "{scene} / {m}: {col} = {v}");
            }
            let rmse = number(row, "rmse");
            let psnr = number(row, "psnr_db");
            assert!(
                psnr.is_finite() || rmse == 0.0,
                "{scene} / {m}: psnr {psnr}"
            );
            assert!(number(row, "ns_per_sample") > 0.0, "{scene} / {m}: no time");
        }
        for m in EXACT {
            assert_eq!(
                number(by_method[m], "arith_error"),
                0.0,
                "{scene} / {m}: not exact"
            );
        }
        for col in ["rmse", "psnr_db", "max_abs_error", "arith_error", "samples"] {
            assert_eq!(
                by_method["sat16-paper"][col], by_method["sat16-stable"][col],
                "{scene}: sat16-paper and sat16-stable differ in {col}"
            );
        }
        // The plan's table (with exact means) answers like the flat table too.
        for m in EXACT
            .iter()
            .filter(|m| m.starts_with("sat16-stable-") || **m == "sat-plan")
        {
            assert_eq!(
                by_method[*m]["rmse"], by_method["sat16-stable"]["rmse"],
                "{scene}: {m} differs from the flat table"
            );
        }
    }
}

#[test]
fn scene_and_method_selection() {
    let dir = temp_dir("pick");
    let out = run(&[
        "--quick",
        "--no-stability",
        "--repeats",
        "1",
        "--scene",
        "noise",
        "--method",
        "point",
        "--method",
        "sat16-stable",
        "--out",
        dir.0.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = read_csv(&dir.0.join("report.csv"));
    let got: Vec<(String, String)> = rows
        .iter()
        .map(|r| (r["scene"].clone(), r["method"].clone()))
        .collect();
    assert_eq!(
        got,
        [
            ("noise".to_string(), "point".to_string()),
            ("noise".to_string(), "sat16-stable".to_string())
        ]
    );
    assert!(is_png(&dir.0.join("render_noise.png")));
    assert!(!dir.0.join("stability.csv").exists());

    let bad = run(&[
        "--quick",
        "--scene",
        "no-such-scene",
        "--out",
        dir.0.to_str().unwrap(),
    ]);
    assert_eq!(
        bad.status.code(),
        Some(2),
        "an unknown scene is a usage error"
    );
    let bad = run(&["--quick", "--method", "no-such-method"]);
    assert!(!bad.status.success(), "an unknown method is a usage error");
}

/// The depth-of-field scene: the SAT's box means are exact up to the mean's rounding to 2^-16
/// (at most 2^-17 in texel units); trilinear mip mapping, which blurs with the level's texels,
/// is visibly off; the section and its render are in the report, and `--no-dof` leaves them out.
#[test]
fn depth_of_field_scene() {
    let dir = temp_dir("dof");
    let d = dir.0.to_str().unwrap();
    let out = run(&["--quick", "--no-stability", "--scene", "noise", "--out", d]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(dir.0.join("report.md")).expect("report.md");
    let section = md
        .split("## Spatially variant blur (depth of field)")
        .nth(1)
        .expect("the depth-of-field section");
    assert!(is_png(&dir.0.join("render_dof.png")));
    // | method | mean abs error | RMS error | max abs error | reads | muls | adds | ns / sample |
    let row = |name: &str| -> Vec<String> {
        section
            .lines()
            .find(|l| l.starts_with(&format!("| {name} |")))
            .unwrap_or_else(|| panic!("row {name}"))
            .split('|')
            .map(|c| c.trim().to_string())
            .filter(|c| !c.is_empty())
            .collect()
    };
    let sat = row("sat16-stable");
    let max_err: f64 = sat[3].parse().unwrap();
    assert!(
        max_err <= 2f64.powi(-17) * 1.0001,
        "SAT max error {max_err}"
    );
    let reads: f64 = sat[4].parse().unwrap();
    assert!((16.0..=144.0).contains(&reads), "SAT reads {reads}");
    let tri = row("trilinear");
    let tri_mean: f64 = tri[1].parse().unwrap();
    assert!(tri_mean > 0.1, "trilinear mean error {tri_mean}");
    assert_eq!(tri[4], "8.0", "trilinear reads");

    let dir2 = temp_dir("no-dof");
    let d2 = dir2.0.to_str().unwrap();
    let out = run(&[
        "--quick",
        "--no-stability",
        "--no-dof",
        "--scene",
        "noise",
        "--out",
        d2,
    ]);
    assert!(out.status.success());
    let md = std::fs::read_to_string(dir2.0.join("report.md")).unwrap();
    assert!(!md.contains("depth of field"));
    assert!(!dir2.0.join("render_dof.png").exists());
}

/// The memory-traffic and texel-cache section: one row per method and rendering order, whose
/// numbers hold together (a 32-bit bus moves at least the bits asked for, a 64-bit bus at least
/// as many bytes, bursts more; hit rates in [0, 1]), and `--no-traffic` leaves it out.
#[test]
fn memory_traffic_section() {
    let dir = temp_dir("traffic");
    let d = dir.0.to_str().unwrap();
    let out = run(&[
        "--quick",
        "--no-stability",
        "--no-dof",
        "--scene",
        "crow-horizontal",
        "--out",
        d,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(dir.0.join("report.md")).expect("report.md");
    let section = md
        .split("## Memory traffic and texel cache")
        .nth(1)
        .expect("section");
    assert!(is_png(&dir.0.join("cache_traffic.png")));
    assert!(section.contains("![cache traffic](cache_traffic.png)"));
    let rows: Vec<Vec<f64>> = section
        .lines()
        .filter(|l| l.starts_with("| crow-horizontal |"))
        .map(|l| {
            l.split('|')
                .skip(4)
                .filter_map(|c| c.trim().parse::<f64>().ok())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 10, "5 methods x 2 orders, one scene");
    for r in &rows {
        let [reads, bits, b32, b64, burst, hit, mem, frame] = r[..] else {
            panic!("row {r:?}")
        };
        assert!(reads >= 1.0 && bits >= reads, "{r:?}");
        assert!(
            b32 * 8.0 >= bits - 1.0 && b64 >= b32 && burst >= b64,
            "{r:?}"
        );
        assert!((0.0..=1.0).contains(&hit) && mem >= 0.0, "{r:?}");
        assert!(
            frame >= mem * 100.0 / 1024.0,
            "{r:?}: at least 100 samples a frame"
        );
    }
    let out = run(&[
        "--quick",
        "--no-stability",
        "--no-dof",
        "--no-traffic",
        "--scene",
        "noise",
        "--out",
        d,
    ]);
    assert!(out.status.success());
    let md = std::fs::read_to_string(dir.0.join("report.md")).unwrap();
    assert!(!md.contains("## Memory traffic"));
}
