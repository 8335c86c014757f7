//! Integration tests of the `sat` command-line tool (`examples/sat.rs`).
//!
//! The tests run the example binary on small PNG and PNM fixtures written to a temporary
//! directory and check its JSON against sums computed here, texel by texel. `cargo test` does not
//! build examples when a single test target is selected (`cargo test --test cli`), so the first
//! test to need the binary runs `cargo build --example sat` for the same profile and target
//! directory; set `SAT_BIN` to test another binary.

use serde_json::Value;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------------------
// Running the binary

fn sat_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        if let Some(bin) = std::env::var_os("SAT_BIN") {
            return PathBuf::from(bin);
        }
        // target/<profile>/deps/cli-XXXX -> target/<profile>/examples/sat
        let exe = std::env::current_exe().expect("current_exe");
        let profile_dir = exe
            .parent()
            .and_then(Path::parent)
            .expect("target/<profile>");
        let target_dir = profile_dir.parent().expect("target dir");
        let mut cmd = Command::new(env!("CARGO"));
        cmd.args(["build", "--quiet", "--example", "sat", "--manifest-path"])
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
            .arg("--target-dir")
            .arg(target_dir);
        if profile_dir.file_name().is_some_and(|n| n == "release") {
            cmd.arg("--release");
        }
        let status = cmd.status().expect("running cargo build --example sat");
        assert!(status.success(), "cargo build --example sat failed");
        let bin = profile_dir
            .join("examples")
            .join(format!("sat{}", std::env::consts::EXE_SUFFIX));
        assert!(bin.exists(), "{} not found after building", bin.display());
        bin
    })
}

fn run(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(sat_bin())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn sat");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    child.wait_with_output().expect("wait for sat")
}

fn stdout(out: &Output) -> String {
    String::from_utf8(out.stdout.clone()).expect("utf-8 stdout")
}

fn stderr(out: &Output) -> String {
    String::from_utf8(out.stderr.clone()).expect("utf-8 stderr")
}

/// Runs a query and returns the parsed JSON lines and whether the exit status was success.
fn query(image: &Path, opts: &[&str], input: &str) -> (Vec<Value>, bool) {
    let mut args = vec!["query", image.to_str().unwrap()];
    args.extend_from_slice(opts);
    let out = run(&args, input);
    let lines = stdout(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("bad JSON {l:?}: {e}")))
        .collect();
    (lines, out.status.success())
}

fn info(image: &Path, opts: &[&str]) -> Value {
    let mut args = vec!["info", image.to_str().unwrap()];
    args.extend_from_slice(opts);
    let out = run(&args, "");
    assert!(out.status.success(), "info failed: {}", stderr(&out));
    let text = stdout(&out);
    assert_eq!(text.lines().count(), 1, "info prints one line: {text}");
    serde_json::from_str(&text).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Fixtures

/// A fresh directory for one test, removed when the test passes (kept for inspection if not).
struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

fn temp_dir(test: &str) -> TempDir {
    let dir = std::env::temp_dir().join(format!("texsat-cli-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// An in-memory image: samples (0..=65535), channels interleaved, and the sample width.
#[derive(Clone)]
struct Img {
    w: usize,
    h: usize,
    c: usize,
    bits: u32,
    data: Vec<u16>,
}

impl Img {
    /// Deterministic pseudo-random samples.
    fn noise(w: usize, h: usize, c: usize, bits: u32, seed: u64) -> Img {
        let mut s = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut data = Vec::with_capacity(w * h * c);
        for _ in 0..w * h * c {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            data.push(((s >> 33) % (1u64 << bits)) as u16);
        }
        Img {
            w,
            h,
            c,
            bits,
            data,
        }
    }

    fn at(&self, x: usize, y: usize, ch: usize) -> u16 {
        self.data[(y * self.w + x) * self.c + ch]
    }

    /// Binary PNM (P5 gray, P6 RGB), maxval 255 or 65535 (big-endian samples).
    fn write_pnm(&self, path: &Path) {
        let magic = match self.c {
            1 => "P5",
            3 => "P6",
            c => panic!("no PNM fixture with {c} channels"),
        };
        let maxval = (1u32 << self.bits) - 1;
        let mut bytes = format!("{magic}\n{} {}\n{maxval}\n", self.w, self.h).into_bytes();
        for &v in &self.data {
            if self.bits == 8 {
                bytes.push(v as u8);
            } else {
                bytes.extend_from_slice(&v.to_be_bytes());
            }
        }
        std::fs::write(path, bytes).unwrap();
    }

    /// PNG via the `image` crate.
    fn write_png(&self, path: &Path) {
        use image::ExtendedColorType as T;
        let color = match (self.c, self.bits) {
            (1, 8) => T::L8,
            (2, 8) => T::La8,
            (3, 8) => T::Rgb8,
            (4, 8) => T::Rgba8,
            (1, 16) => T::L16,
            (2, 16) => T::La16,
            (3, 16) => T::Rgb16,
            (4, 16) => T::Rgba16,
            other => panic!("no PNG fixture for {other:?}"),
        };
        let bytes: Vec<u8> = if self.bits == 8 {
            self.data.iter().map(|&v| v as u8).collect()
        } else {
            // `save_buffer` takes 16-bit samples in native byte order.
            self.data.iter().flat_map(|v| v.to_ne_bytes()).collect()
        };
        image::save_buffer_with_format(
            path,
            &bytes,
            self.w as u32,
            self.h as u32,
            color,
            image::ImageFormat::Png,
        )
        .unwrap();
    }

    /// The texel of the extended texture under a boundary mode (`None`: zero).
    fn ext(&self, i: i64, j: i64, ch: usize, mode: &str) -> Option<u16> {
        let map = |i: i64, n: usize| -> Option<usize> {
            let n = n as i64;
            let k = match mode {
                "border" => (0..n).contains(&i).then_some(i)?,
                "clamp" => i.clamp(0, n - 1),
                "repeat" => i.rem_euclid(n),
                "mirror" => {
                    let r = i.rem_euclid(2 * n);
                    if r < n {
                        r
                    } else {
                        2 * n - 1 - r
                    }
                }
                _ => unreachable!("{mode}"),
            };
            Some(k as usize)
        };
        Some(self.at(map(i, self.w)?, map(j, self.h)?, ch))
    }

    /// The exact integral over a box in raw units (`value * 2^f`), scaled by `2^2f`.
    fn direct(&self, raw: [i64; 4], f: u32, ch: usize, mode: &str) -> u128 {
        let [x0, y0, x1, y1] = raw;
        if x1 <= x0 || y1 <= y0 {
            return 0;
        }
        let overlap = |lo: i64, hi: i64, i: i64| (hi.min((i + 1) << f) - lo.max(i << f)).max(0);
        let mut sum = 0u128;
        for j in (y0 >> f)..=((y1 - 1) >> f) {
            for i in (x0 >> f)..=((x1 - 1) >> f) {
                if let Some(t) = self.ext(i, j, ch, mode) {
                    let weight = overlap(x0, x1, i) * overlap(y0, y1, j);
                    sum += u128::from(t) * weight as u128;
                }
            }
        }
        sum
    }
}

// ---------------------------------------------------------------------------------------------
// Expected values

/// The exact decimal of `v / 2^k` (all digits, no trailing zeros, no point for integers).
fn decimal(v: u128, k: u32) -> String {
    let mut s = (v >> k).to_string();
    let mask = (1u128 << k) - 1;
    let mut frac = v & mask;
    if frac != 0 {
        s.push('.');
        while frac != 0 {
            frac *= 10;
            s.push(char::from(b'0' + (frac >> k) as u8));
            frac &= mask;
        }
    }
    s
}

/// `raw / 2^f` as a signed decimal, the way a test bench would write a coordinate.
fn coord(raw: i64, f: u32) -> String {
    let s = decimal(u128::from(raw.unsigned_abs()), f);
    if raw < 0 {
        format!("-{s}")
    } else {
        s
    }
}

fn box_line(raw: [i64; 4], f: u32) -> String {
    raw.map(|v| coord(v, f)).join(" ")
}

/// `round(sum * 2^g / area)`, ties up: the mean `sat query` prints, as a decimal.
fn mean(sum: u128, raw: [i64; 4], g: u32) -> String {
    let area = ((raw[2] - raw[0]) * (raw[3] - raw[1])) as u128;
    let n = sum << g;
    let (q, r) = (n / area, n % area);
    decimal(if 2 * r >= area { q + 1 } else { q }, g)
}

fn costs(v: &Value) -> (u64, u64, u64, u64) {
    let n = |k: &str| v[k].as_u64().unwrap_or_else(|| panic!("no {k} in {v}"));
    (n("reads"), n("muls"), n("divs"), n("adds"))
}

/// Checks one answer against the direct integral and the mean formula, every channel.
fn check_answer(img: &Img, v: &Value, raw: [i64; 4], f: u32, g: u32, mode: &str) {
    assert!(v.get("error").is_none(), "box {raw:?} F={f} {mode}: {v}");
    for ch in 0..img.c {
        let (sum, mean_v) = if img.c == 1 {
            (&v["sum"], &v["mean"])
        } else {
            assert_eq!(v["sum"].as_array().unwrap().len(), img.c, "{v}");
            (&v["sum"][ch], &v["mean"][ch])
        };
        let expected = img.direct(raw, f, ch, mode);
        assert_eq!(
            sum.as_str().unwrap(),
            decimal(expected, 2 * f),
            "sum of {raw:?} (F={f}, {mode}, channel {ch}): {v}"
        );
        assert_eq!(
            mean_v.as_str().unwrap(),
            mean(expected, raw, g),
            "mean of {raw:?} (F={f}, {mode}, channel {ch}): {v}"
        );
    }
}

/// Boxes with corners on the `2^-f` grid spread over (and, with `outside`, beyond) the image.
fn boxes(img: &Img, f: u32, outside: bool, count: usize, seed: u64) -> Vec<[i64; 4]> {
    let noise = Img::noise(count * 4, 1, 1, 16, seed).data;
    let (w, h) = ((img.w as i64) << f, (img.h as i64) << f);
    let pick = |v: u16, n: i64| {
        if outside {
            i64::from(v) % (3 * n) - n
        } else {
            i64::from(v) % (n + 1)
        }
    };
    noise
        .chunks_exact(4)
        .map(|q| {
            let (a, b) = (pick(q[0], w), pick(q[1], w));
            let (c, d) = (pick(q[2], h), pick(q[3], h));
            [a.min(b), c.min(d), a.max(b), c.max(d)]
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// sat info

#[test]
fn info_reports_sizes_and_widths() {
    let dir = temp_dir("info");
    let img = Img {
        w: 4,
        h: 3,
        c: 1,
        bits: 8,
        data: (1..=12).collect(),
    };
    let (pgm, png) = (dir.join("t.pgm"), dir.join("t.png"));
    img.write_pnm(&pgm);
    img.write_png(&png);
    for path in [&pgm, &png] {
        let v = info(path, &[]);
        let expected = serde_json::json!({
            "width": 4, "height": 3, "channels": 1, "texel_bits": 8, "texel_type": "u8",
            "bits_needed_worst_case": 12, // bits_of(255 * 12 = 3060)
            "bits_needed_naive": 12,      // 8 + ceil(log2 12)
            "bits_needed_actual": 7,      // 78
            "entry_type": "u32", "entry_bits": 32, "bits_per_entry": 32, "bits_per_texel": 32,
            "table_entries": 12, "table_bytes": 48, "layout": "flat", "build": "worst_case",
            "totals": "78",
        });
        assert_eq!(v, expected, "{}", path.display());
    }
    let v = info(&png, &["--entry", "u16", "--checked"]);
    assert_eq!(v["table_bytes"], 24);
    assert_eq!(v["build"], "checked");

    // RGB: per-channel totals, bits per texel = entry bits x channels.
    let rgb = Img {
        w: 2,
        h: 2,
        c: 3,
        bits: 8,
        data: (1..=12).collect(),
    };
    let ppm = dir.join("rgb.ppm");
    rgb.write_pnm(&ppm);
    let v = info(&ppm, &["--entry", "u64"]);
    assert_eq!(v["channels"], 3);
    assert_eq!(v["bits_per_entry"], 64);
    assert_eq!(v["bits_per_texel"], 192);
    assert_eq!(v["table_bytes"], 2 * 2 * 3 * 8);
    assert_eq!(v["totals"], serde_json::json!(["22", "26", "30"]));
}

#[test]
fn info_refuses_an_entry_type_too_narrow() {
    let dir = temp_dir("refuse");
    // 300 x 300 texels of 16 bits: the worst case (2^16 - 1) * 90000 needs 33 bits.
    let full = Img {
        w: 300,
        h: 300,
        c: 1,
        bits: 16,
        data: vec![65535; 90000],
    };
    let png = dir.join("full16.png");
    full.write_png(&png);
    let out = run(&["info", png.to_str().unwrap(), "--entry", "u32"], "");
    assert!(!out.status.success());
    assert!(out.stdout.is_empty(), "nothing on stdout when refused");
    let msg = stderr(&out);
    assert!(
        msg.contains("33 bits") && msg.contains("32 are available"),
        "message names bits needed and available: {msg}"
    );
    let v = info(&png, &["--entry", "u64"]);
    assert_eq!(v["bits_needed_worst_case"], 33);
    assert_eq!(v["bits_needed_actual"], 33);
    assert_eq!(v["totals"], "5898150000");
    assert_eq!(v["table_bytes"], 90000 * 8);
    // The checked build refuses it too (its data really needs 33 bits) ...
    let out = run(&["info", png.to_str().unwrap(), "--checked"], "");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("33 bits"), "{}", stderr(&out));

    // ... but accepts a dim image of the same size, which the worst-case build refuses.
    let dim = Img {
        data: vec![4096; 90000],
        ..full
    };
    let pgm = dir.join("dim16.pgm");
    dim.write_pnm(&pgm);
    let out = run(&["info", pgm.to_str().unwrap()], "");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--checked"), "{}", stderr(&out));
    let v = info(&pgm, &["--checked"]);
    assert_eq!(v["bits_needed_worst_case"], 33);
    assert_eq!(v["bits_needed_actual"], 29); // 4096 * 90000 = 368,640,000
    assert_eq!(v["entry_bits"], 32);
}

#[test]
fn pnm_with_other_maxval_is_refused() {
    let dir = temp_dir("maxval");
    let path = dir.join("ten.pgm");
    let mut bytes = b"P5\n2 2\n1023\n".to_vec();
    bytes.extend_from_slice(&[0, 1, 0, 2, 3, 255, 0, 0]);
    std::fs::write(&path, bytes).unwrap();
    let out = run(&["info", path.to_str().unwrap()], "");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("maxval 1023"), "{}", stderr(&out));
    let out = run(&["info", dir.join("missing.png").to_str().unwrap()], "");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("missing.png"), "{}", stderr(&out));
}

// ---------------------------------------------------------------------------------------------
// sat query: sums, means, costs

#[test]
fn integer_corners_are_exact_and_cost_4_1_1_3() {
    let dir = temp_dir("int");
    let img = Img::noise(13, 9, 1, 8, 1);
    let png = dir.join("n.png");
    img.write_png(&png);
    let list = boxes(&img, 0, false, 200, 2);
    let input: String = list.iter().map(|&b| box_line(b, 0) + "\n").collect();
    let (answers, ok) = query(&png, &["--frac-bits", "0"], &input);
    assert!(ok);
    assert_eq!(answers.len(), list.len());
    let mut interior = 0;
    for (v, &b) in answers.iter().zip(&list) {
        if b[0] == b[2] || b[1] == b[3] {
            assert_eq!(v["sum"], "0");
            assert_eq!(v["mean"], Value::Null, "zero area has no mean");
            continue;
        }
        check_answer(&img, v, b, 0, 8, "border");
        assert_eq!(v["lookup"], "int4");
        if b[0] >= 1 && b[1] >= 1 {
            interior += 1;
            assert_eq!(costs(v), (4, 1, 1, 3), "{b:?}: {v}");
            assert_eq!(v["bits_read"], 4 * 32);
        }
    }
    assert!(interior > 50);
    // Corners on the zero row and column read nothing: the whole image is one read.
    let (answers, _) = query(&png, &["--frac-bits", "0"], "0 0 13 9\n");
    assert_eq!(costs(&answers[0]), (1, 1, 1, 3));
    let total: u128 = img.data.iter().map(|&v| u128::from(v)).sum();
    assert_eq!(answers[0]["sum"], total.to_string());
}

#[test]
fn fractional_corners_are_exact_and_cost_crows_16_14_27() {
    let dir = temp_dir("frac");
    let img = Img::noise(11, 7, 1, 16, 3);
    let pgm = dir.join("n16.pgm");
    img.write_pnm(&pgm);
    for (f, form, adds) in [
        (8, "paper", 27),
        (8, "stable", 31),
        (4, "paper", 27),
        (12, "stable", 31),
    ] {
        let list = boxes(&img, f, false, 150, 4 + u64::from(f));
        let input: String = list.iter().map(|&b| box_line(b, f) + "\n").collect();
        let fs = f.to_string();
        let (answers, ok) = query(&pgm, &["--frac-bits", &fs, "--form", form], &input);
        assert!(ok, "F={f} {form}");
        assert_eq!(answers.len(), list.len());
        let g = 2 * f + 8;
        let mut interior = 0;
        for (v, &b) in answers.iter().zip(&list) {
            if b[0] == b[2] || b[1] == b[3] {
                assert_eq!(v["mean"], Value::Null);
                continue;
            }
            check_answer(&img, v, b, f, g, "border");
            assert_eq!(v["lookup"], form);
            // Interior: no corner in the first cell row or column (those reads are free).
            if b[0] >= 1 << f && b[1] >= 1 << f {
                interior += 1;
                assert_eq!(costs(v), (16, 13, 1, adds), "F={f} {form} {b:?}: {v}");
            }
        }
        assert!(interior > 30, "F={f}: {interior} interior boxes");
    }
    // A hand-checked box: [1.25, 3.5) x [0, 2) over rows (1 2 3 4) and (5 6 7 8).
    let small = Img {
        w: 4,
        h: 3,
        c: 1,
        bits: 8,
        data: (1..=12).collect(),
    };
    let path = dir.join("small.pgm");
    small.write_pnm(&path);
    let (answers, ok) = query(&path, &[], "1.25 0 3.5 2\n1.25 1 3.5 2.75\n");
    assert!(ok);
    assert_eq!(answers[0]["sum"], "22"); // 0.75*2 + 3 + 0.5*4 + 0.75*6 + 7 + 0.5*8
    assert_eq!(answers[0]["mean"], mean(22 << 16, [320, 0, 896, 512], 24));
    assert_eq!(costs(&answers[1]), (16, 13, 1, 27));
    // Integer corners at F > 0 still take the 16-read lookup, unless --int4.
    let (answers, _) = query(&path, &[], "1 1 3 3\n");
    assert_eq!(
        (answers[0]["sum"].as_str(), costs(&answers[0])),
        (Some("34"), (16, 13, 1, 27))
    );
    let (answers, _) = query(&path, &["--int4"], "1 1 3 3\n1.5 1 3 3\n");
    assert_eq!(
        (answers[0]["sum"].as_str(), costs(&answers[0])),
        (Some("34"), (4, 1, 1, 3))
    );
    assert_eq!(answers[0]["lookup"], "int4");
    assert_eq!(answers[1]["lookup"], "paper");
    assert_eq!(answers[1]["sum"], "26"); // 0.5*6 + 7 + 0.5*10 + 11
}

#[test]
fn every_edge_mode_matches_the_extended_texture() {
    let dir = temp_dir("edge");
    let img = Img::noise(6, 5, 1, 8, 5);
    let png = dir.join("e.png");
    img.write_png(&png);
    let f = 4;
    for mode in ["border", "clamp", "repeat", "mirror"] {
        let mut list = boxes(&img, f, true, 120, 6);
        // Boxes spanning several periods, and fully outside on each side.
        list.push([-(40 << f) - 3, -(2 << f), (33 << f) + 5, (7 << f) + 1]);
        list.push([-(9 << f), 1 << f, -(1 << f) - 7, 3 << f]);
        list.push([(7 << f) + 1, -(6 << f), (20 << f) + 2, -(1 << f)]);
        let input: String = list.iter().map(|&b| box_line(b, f) + "\n").collect();
        let (answers, ok) = query(&png, &["--frac-bits", "4", "--edge", mode], &input);
        assert!(ok, "{mode}: {answers:?}");
        assert_eq!(answers.len(), list.len());
        for (v, &b) in answers.iter().zip(&list) {
            if b[0] == b[2] || b[1] == b[3] {
                continue;
            }
            check_answer(&img, v, b, f, 2 * f + 8, mode);
        }
        // Integer corners under the same mode.
        let list = boxes(&img, 0, true, 60, 7);
        let input: String = list.iter().map(|&b| box_line(b, 0) + "\n").collect();
        let (answers, ok) = query(&png, &["--frac-bits", "0", "--edge", mode], &input);
        assert!(ok, "{mode} F=0");
        for (v, &b) in answers.iter().zip(&list) {
            if b[0] != b[2] && b[1] != b[3] {
                check_answer(&img, v, b, 0, 8, mode);
            }
        }
    }
}

#[test]
fn several_channels_give_arrays() {
    let dir = temp_dir("chan");
    let f = 8;
    for (c, bits) in [(2, 8), (3, 8), (4, 16), (3, 16)] {
        let img = Img::noise(7, 6, c, bits, 8 + c as u64);
        let png = dir.join(format!("c{c}_{bits}.png"));
        img.write_png(&png);
        let list = boxes(&img, f, false, 40, 9);
        let input: String = list.iter().map(|&b| box_line(b, f) + "\n").collect();
        for form in ["paper", "stable"] {
            let (answers, ok) = query(&png, &["--form", form, "--entry", "u64"], &input);
            assert!(ok);
            for (v, &b) in answers.iter().zip(&list) {
                if b[0] == b[2] || b[1] == b[3] {
                    continue;
                }
                check_answer(&img, v, b, f, 2 * f + 8, "border");
                assert_eq!(v["mean"].as_array().unwrap().len(), c);
            }
        }
        let v = info(&png, &[]);
        assert_eq!(
            (v["channels"].as_u64(), v["texel_bits"].as_u64()),
            (Some(c as u64), Some(u64::from(bits)))
        );
    }
    // A PPM too: the 2 x 2 RGB image, whole.
    let rgb = Img {
        w: 2,
        h: 2,
        c: 3,
        bits: 8,
        data: (1..=12).collect(),
    };
    let ppm = dir.join("rgb.ppm");
    rgb.write_pnm(&ppm);
    let (answers, ok) = query(&ppm, &["--frac-bits", "0"], "0 0 2 2\n");
    assert!(ok);
    assert_eq!(answers[0]["sum"], serde_json::json!(["22", "26", "30"]));
    assert_eq!(answers[0]["mean"], serde_json::json!(["5.5", "6.5", "7.5"]));
    // Values are counted per channel, reads once per entry: 1 read, 1 mul, 3 divs, 9 adds.
    assert_eq!(costs(&answers[0]), (1, 1, 3, 9));
    assert_eq!(answers[0]["bits_read"], 3 * 32);
}

// ---------------------------------------------------------------------------------------------
// sat query: input handling

#[test]
fn malformed_lines_give_errors_and_the_rest_are_answered() {
    let dir = temp_dir("bad");
    let img = Img {
        w: 4,
        h: 3,
        c: 1,
        bits: 8,
        data: (1..=12).collect(),
    };
    let path = dir.join("t.pgm");
    img.write_pnm(&path);
    let input = "1 1 3 3\n\
                 \n\
                 # a comment\n\
                 1 1 3\n\
                 1 1 3 3 4\n\
                 1 one 3 3\n\
                 0.3 0 1 1\n\
                 3 0 1 1\n\
                 1e1 0 1 1\n\
                 \t 0.5 0   1.5 1 \r\n\
                 -5 0 99999999999999999999999 1\n\
                 0 0 4 3";
    let out = run(&["query", path.to_str().unwrap()], input);
    assert!(
        !out.status.success(),
        "a failed line makes the exit status non-zero"
    );
    let lines: Vec<Value> = stdout(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(
        lines.len(),
        10,
        "blank and comment lines are skipped: {lines:?}"
    );
    let error_at = |i: usize, line: u64, needle: &str| {
        let v = &lines[i];
        let msg = v["error"]
            .as_str()
            .unwrap_or_else(|| panic!("no error in {v}"));
        assert!(msg.contains(needle), "{msg:?} should mention {needle:?}");
        assert_eq!(v["line"], line, "{v}");
        assert!(v.get("sum").is_none());
    };
    assert_eq!(lines[0]["sum"], "34");
    error_at(1, 4, "expected 4 numbers");
    error_at(2, 5, "expected 4 numbers");
    error_at(3, 6, "not a decimal number");
    error_at(4, 7, "not a multiple of 2^-8");
    error_at(5, 8, "inverted");
    error_at(6, 9, "not a decimal number");
    assert_eq!(lines[7]["sum"], "1.5");
    error_at(8, 11, "out of range");
    assert_eq!(lines[9]["sum"], "78");
}

#[test]
fn round_flag_rounds_to_nearest_ties_up() {
    let dir = temp_dir("round");
    let img = Img {
        w: 4,
        h: 3,
        c: 1,
        bits: 8,
        data: (1..=12).collect(),
    };
    let path = dir.join("t.pgm");
    img.write_pnm(&path);
    // At F = 2: 0.3 -> 0.25, 0.125 (a tie) -> 0.25, 1.9 -> 2.
    let (a, ok) = query(
        &path,
        &["--frac-bits", "2", "--round"],
        "0.3 0 0.125 1\n0 0 1.9 1\n",
    );
    assert!(ok);
    assert_eq!(a[0]["sum"], "0");
    assert_eq!(a[0]["mean"], Value::Null);
    assert_eq!(a[1]["sum"], "3");
    let (a, ok) = query(&path, &["--frac-bits", "2"], "0 0 1.9 1\n");
    assert!(!ok);
    assert!(a[0]["error"].as_str().unwrap().contains("2^-2"));
    // At F = 0 every coordinate must be an integer; --round rounds ties toward +infinity.
    let (a, _) = query(
        &path,
        &["--frac-bits", "0", "--round"],
        "0.5 -0.5 2.5 1.4\n",
    );
    assert_eq!(a[0]["sum"], "5"); // [1, 3) x [0, 1): 2 + 3
}

#[test]
fn mean_bits_and_accumulator_width() {
    let dir = temp_dir("width");
    let img = Img {
        w: 4,
        h: 3,
        c: 1,
        bits: 8,
        data: (1..=12).collect(),
    };
    let path = dir.join("t.pgm");
    img.write_pnm(&path);
    let (a, _) = query(
        &path,
        &["--frac-bits", "0", "--mean-bits", "0"],
        "0 0 3 1\n0 0 2 1\n",
    );
    assert_eq!(
        (a[0]["mean"].as_str(), a[1]["mean"].as_str()),
        (Some("2"), Some("2"))
    ); // 1.5 -> 2
    let (a, _) = query(
        &path,
        &["--frac-bits", "0", "--mean-bits", "4"],
        "0 0 3 1\n",
    );
    assert_eq!(a[0]["mean"], "2"); // (1+2+3)/3
    let (a, _) = query(&path, &["--frac-bits", "0"], "1 0 4 1\n");
    assert_eq!(a[0]["mean"], mean(9, [1, 0, 4, 1], 8)); // 3 = 9/3 exactly
    let (a, _) = query(&path, &["--frac-bits", "0"], "0 1 3 2\n");
    assert_eq!(a[0]["mean"], mean(18, [0, 1, 3, 2], 8));

    // 182 x 182 texels of 65535 sum to 2,170,631,340 (32 bits): u32 entries hold the table, but
    // a paper lookup at F = 16 needs 32 + 32 = 64 accumulator bits and u32 lookups have 63.
    let full = Img {
        w: 182,
        h: 182,
        c: 1,
        bits: 16,
        data: vec![65535; 182 * 182],
    };
    let pgm = dir.join("full.pgm");
    full.write_pnm(&pgm);
    let out = run(
        &["query", pgm.to_str().unwrap(), "--frac-bits", "16"],
        "1 1 2 2\n",
    );
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    let msg = stderr(&out);
    assert!(
        msg.contains("64-bit accumulator") && msg.contains("63"),
        "{msg}"
    );
    let (a, ok) = query(
        &pgm,
        &["--frac-bits", "16", "--entry", "u64"],
        "0.5 0.5 182 182\n",
    );
    assert!(ok);
    assert_eq!(a[0]["sum"], decimal((65535 * 363u128 * 363) << 30, 32)); // 181.5^2 * 65535
    assert_eq!(a[0]["mean"], "65535");
    // Stable needs one bit more than paper: 32 + 2 * 15 + 1 = 63 still fits i64.
    let (a, ok) = query(
        &pgm,
        &["--frac-bits", "15", "--form", "stable"],
        "0.5 0.5 182 182\n",
    );
    assert!(ok, "{a:?}");
    assert_eq!(a[0]["sum"], "2158870353.75");
}

#[test]
fn argument_errors_and_demo() {
    let dir = temp_dir("args");
    let img = Img::noise(3, 3, 1, 8, 11);
    let path = dir.join("a.png");
    img.write_png(&path);
    let p = path.to_str().unwrap();
    for bad in [
        vec!["query", p, "--frac-bits", "25"],
        vec!["query", p, "--edge", "wrap"],
        vec!["query", p, "--form", "crow"],
        vec!["info", p, "--entry", "u8"],
        vec!["info"],
    ] {
        let out = run(&bad, "");
        assert!(!out.status.success(), "{bad:?} should be refused");
        assert!(!stderr(&out).is_empty());
    }
    let out = run(&["demo"], "");
    assert!(out.status.success(), "demo failed: {}", stdout(&out));
    let text = stdout(&out);
    assert!(
        text.contains("All sums match the direct integrals"),
        "{text}"
    );
    for needle in [
        "262,144 bytes",
        "24 bits",
        "border",
        "clamp",
        "repeat",
        "mirror",
        "Crow",
    ] {
        assert!(text.contains(needle), "demo output lacks {needle:?}");
    }
}
