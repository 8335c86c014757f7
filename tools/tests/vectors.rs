//! `sat vectors`: both output formats re-read and checked against the library, so that the files
//! an RTL test bench loads cannot drift from what texsat computes.
//!
//! For each configuration the tool writes hex and JSON for the same seed; the JSON's texture is
//! rebuilt here with the library (its table words compared, every sample's sum, mean and counted
//! costs recomputed), and the hex files (table, stimulus, expected, parameters) are compared
//! field by field with the JSON.

mod common;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use texsat::layouts::{Modular, Tiled, TiledSpec};
use texsat::{BoxLookup, EdgeKind, FormKind, FracBits, Layout, Rect, Sat, Tally, Texture};

fn sat_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| common::example_bin("sat", "SAT_BIN", &[]))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("texsat-vectors-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn vectors(args: &[&str], out: &Path) {
    let o = Command::new(sat_bin())
        .arg("vectors")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("spawn sat");
    assert!(
        o.status.success(),
        "sat vectors {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A JSON number or decimal string as u128 (i128 for coordinates).
fn big(v: &Value) -> i128 {
    match v {
        Value::Number(n) => n
            .as_i64()
            .map(i128::from)
            .unwrap_or_else(|| i128::from(n.as_u64().expect("integer"))),
        Value::String(s) => s.parse().expect("decimal string"),
        other => panic!("not a number: {other}"),
    }
}

/// Checks every sample of `doc` against `layout`.
fn check_samples<L: Layout<1>>(layout: &L, doc: &Value, what: &str) {
    let p = &doc["params"];
    let f = p["frac_bits"].as_u64().unwrap() as u32;
    let g = p["mean_bits"].as_u64().unwrap() as u32;
    let form = match p["form"].as_str().unwrap() {
        "paper" => FormKind::Paper,
        _ => FormKind::Stable,
    };
    let edge = match p["edge"].as_str().unwrap() {
        "border" => EdgeKind::Border,
        "clamp" => EdgeKind::Clamp,
        "repeat" => EdgeKind::Repeat,
        _ => EdgeKind::Mirror,
    };
    let samples = doc["samples"].as_array().unwrap();
    assert_eq!(samples.len() as u64, p["count"].as_u64().unwrap());
    let mut answered = 0;
    for (n, s) in samples.iter().enumerate() {
        let c = |k: &str| big(&s[k]) as i64;
        let r = Rect::new(c("x0"), c("y0"), c("x1"), c("y1"));
        let mut k = Tally::new();
        let sum = if f == 0 {
            let i = |v: i64| i32::try_from(v).unwrap();
            layout.box_sum_int(&Rect::new(i(r.x0), i(r.y0), i(r.x1), i(r.y1)), edge, &mut k)
        } else {
            layout.box_sum_raw(&r, FracBits::new(f).unwrap(), form, edge, &mut k)
        };
        match sum {
            Ok(sum) => {
                let (w, h) = sum.sides_raw();
                let mean: u128 = if w == 0 || h == 0 {
                    0
                } else {
                    sum.mean_rounded(0, g, &mut k).unwrap().into()
                };
                let total: u128 = sum.sum().into();
                assert_eq!(big(&s["sum"]) as u128, total, "{what} sample {n}");
                assert_eq!(big(&s["mean"]) as u128, mean, "{what} sample {n}");
                assert!(s.get("error").is_none(), "{what} sample {n}");
                answered += 1;
            }
            Err(e) => assert_eq!(s["error"].as_str(), Some(e.to_string().as_str())),
        }
        let costs = [k.reads, k.muls, k.divs, k.adds];
        let want = ["reads", "muls", "divs", "adds"].map(|key| s[key].as_u64().unwrap());
        assert_eq!(costs, want, "{what} sample {n} costs");
    }
    assert!(answered > samples.len() / 2, "{what}: {answered} answered");
}

/// Rebuilds the JSON's texture with the library and checks the table image and every sample.
fn check_json(doc: &Value, what: &str) {
    let t = &doc["texture"];
    let (w, h) = (
        t["width"].as_u64().unwrap() as usize,
        t["height"].as_u64().unwrap() as usize,
    );
    assert_eq!(t["texel_bits"].as_u64(), Some(8));
    let texels: Vec<u8> = t["texels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| u8::try_from(v.as_u64().unwrap()).unwrap())
        .collect();
    let tex = Texture::<u8>::new(&texels, w, h).unwrap();
    let words: Vec<u128> = doc["table"]["words"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| big(v) as u128)
        .collect();
    let layout = doc["params"]["layout"].as_str().unwrap().to_string();
    if layout == "flat" {
        assert_eq!(doc["table"]["word_bits"].as_u64(), Some(32), "{what}");
        let mut st = vec![0u32; w * h];
        let sat = Sat::build(&tex, &mut st).unwrap();
        let got: Vec<u128> = sat.entries().iter().map(|&v| u128::from(v)).collect();
        assert_eq!(got, words, "{what}: table image");
        check_samples(&sat, doc, what);
    } else if let Some(k) = layout.strip_prefix("modular:") {
        let k: u32 = k.parse().unwrap();
        let mut st = vec![0u32; Modular::<u64>::words_needed(w, h, k).unwrap()];
        let mut row = vec![0u64; w];
        let m = Modular::<u64>::build(&tex, k, &mut st, &mut row).unwrap();
        let got: Vec<u128> = m.words().iter().map(|&v| u128::from(v)).collect();
        assert_eq!(got, words, "{what}: table image");
        check_samples(&m, doc, what);
    } else {
        let spec = TiledSpec::tiles(8, 8).unwrap();
        assert_eq!(layout, "tiled:8x8");
        let mut st = vec![0u32; Tiled::<u64>::words_needed(spec, w, h, 8).unwrap()];
        let mut scratch = vec![0u64; Tiled::<u64>::scratch_needed(spec, w).unwrap()];
        let t = Tiled::<u64>::build(&tex, spec, &mut st, &mut scratch).unwrap();
        let got: Vec<u128> = t.words().iter().map(|&v| u128::from(v)).collect();
        assert_eq!(got, words, "{what}: table image");
        check_samples(&t, doc, what);
    }
}

fn hex_lines(path: &Path) -> Vec<u128> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| u128::from_str_radix(l, 16).unwrap())
        .collect()
}

/// 256-bit hex lines as four 64-bit words (most significant first).
fn hex_quads(path: &Path) -> Vec<[u64; 4]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            assert_eq!(l.len(), 64, "{}: a 256-bit line", path.display());
            let w = |i: usize| u64::from_str_radix(&l[16 * i..16 * i + 16], 16).unwrap();
            [w(0), w(1), w(2), w(3)]
        })
        .collect()
}

/// The hex files say what the JSON says.
fn check_hex(dir: &Path, doc: &Value, what: &str) {
    let p = &doc["params"];
    let vh = std::fs::read_to_string(dir.join("vectors.vh")).unwrap();
    let param = |name: &str| -> u64 {
        let line = vh
            .lines()
            .find(|l| l.starts_with(&format!("localparam {name} = ")))
            .unwrap_or_else(|| panic!("{what}: {name} missing"));
        line.trim_end_matches(';')
            .rsplit(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    assert_eq!(param("VEC_TEX_W"), p["width"].as_u64().unwrap());
    assert_eq!(param("VEC_TEX_H"), p["height"].as_u64().unwrap());
    assert_eq!(param("VEC_B"), 8);
    assert_eq!(
        param("VEC_W_E"),
        doc["table"]["word_bits"].as_u64().unwrap()
    );
    assert_eq!(param("VEC_F"), p["frac_bits"].as_u64().unwrap());
    assert_eq!(param("VEC_N"), p["count"].as_u64().unwrap());
    assert_eq!(param("VEC_W_STRIP"), p["strip_bits"].as_u64().unwrap());
    assert_eq!(param("VEC_MEAN_BITS"), p["mean_bits"].as_u64().unwrap());

    let words: Vec<u128> = doc["table"]["words"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| big(v) as u128)
        .collect();
    assert_eq!(
        hex_lines(&dir.join("table.hex")),
        words,
        "{what}: table.hex"
    );

    let samples = doc["samples"].as_array().unwrap();
    let stim = hex_quads(&dir.join("stim.hex"));
    let expect = hex_quads(&dir.join("expect.hex"));
    assert_eq!((stim.len(), expect.len()), (samples.len(), samples.len()));
    for (n, ((s, st), ex)) in samples.iter().zip(&stim).zip(&expect).enumerate() {
        let corners = ["x0", "y0", "x1", "y1"].map(|k| big(&s[k]) as i64 as u64);
        assert_eq!(*st, corners, "{what} sample {n}: stim.hex");
        let sum = (u128::from(ex[0]) << 64) | u128::from(ex[1]);
        assert_eq!(
            sum,
            big(&s["sum"]) as u128,
            "{what} sample {n}: expect.hex sum"
        );
        assert_eq!(
            u128::from(ex[2]),
            big(&s["mean"]) as u128,
            "{what} sample {n}: mean"
        );
        let costs = [
            ex[3] >> 48,
            (ex[3] >> 32) & 0xFFFF,
            (ex[3] >> 16) & 0xFFFF,
            ex[3] & 0xFFFF,
        ];
        let want = ["reads", "muls", "divs", "adds"].map(|k| s[k].as_u64().unwrap());
        assert_eq!(costs, want, "{what} sample {n}: expect.hex costs");
    }
}

fn both_formats(name: &str, args: &[&str]) {
    let dir = temp_dir(name);
    let (hex, json) = (dir.join("hex"), dir.join("json"));
    vectors(&[args, &["--format", "hex"]].concat(), &hex);
    vectors(&[args, &["--format", "json"]].concat(), &json);
    let doc: Value =
        serde_json::from_str(&std::fs::read_to_string(json.join("vectors.json")).unwrap()).unwrap();
    check_json(&doc, name);
    check_hex(&hex, &doc, name);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn stable_border_inside_boxes() {
    both_formats(
        "stable-border",
        &[
            "--scene",
            "noise",
            "--frac-bits",
            "8",
            "--form",
            "stable",
            "--count",
            "150",
        ],
    );
}

#[test]
fn paper_repeat_boxes_around_the_texture() {
    both_formats(
        "paper-repeat",
        &[
            "--scene",
            "zone-plate",
            "--frac-bits",
            "4",
            "--form",
            "paper",
            "--edge",
            "repeat",
            "--boxes",
            "around",
            "--count",
            "120",
            "--seed",
            "3",
        ],
    );
}

#[test]
fn int4_mirror_on_a_tiled_layout() {
    both_formats(
        "tiled-mirror",
        &[
            "--scene",
            "noise",
            "--frac-bits",
            "0",
            "--layout",
            "tiled:8x8",
            "--edge",
            "mirror",
            "--boxes",
            "around",
            "--count",
            "120",
            "--seed",
            "5",
        ],
    );
}

#[test]
fn modular_layout_refuses_big_boxes_in_its_vectors() {
    // k = 20 holds boxes of at most 4112 cells of 8-bit texels: the larger random boxes are
    // refused, and the vectors carry the library's error for them (sum 0 in the hex files).
    both_formats(
        "modular",
        &[
            "--scene",
            "noise",
            "--frac-bits",
            "8",
            "--layout",
            "modular:20",
            "--form",
            "stable",
            "--count",
            "100",
            "--seed",
            "7",
        ],
    );
}

#[test]
fn refusals() {
    let dir = temp_dir("refusals");
    let run = |args: &[&str]| {
        Command::new(sat_bin())
            .arg("vectors")
            .args(args)
            .output()
            .expect("spawn sat")
    };
    let o = run(&["--scene", "nope", "--out", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no built-in scene 'nope'"));
    let o = run(&[
        "--scene",
        "noise",
        "--count",
        "2000000",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("at most 1000000"));
    let o = run(&["--out", dir.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
