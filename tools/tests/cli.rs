//! Integration tests of the `sat` command-line tool (`examples/sat.rs`).
//!
//! The tests run the example binary on small PNG and PNM fixtures written to a temporary
//! directory and check its JSON against sums computed here, texel by texel. `cargo test` does not
//! build examples when a single test target is selected (`cargo test --test cli`), so the first
//! test to need the binary runs `cargo build --example sat` for the same profile and target
//! directory (with `--features filters`, for `--filter`); set `SAT_BIN` to test another binary.

mod common;

use serde_json::{json, Value};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------------------
// Running the binary

fn sat_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| common::example_bin("sat", "SAT_BIN", &[]))
}

fn run(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(sat_bin())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn sat");
    // A run that fails before reading its input may close the pipe first: not an error here.
    let written = child.stdin.take().unwrap().write_all(stdin.as_bytes());
    if let Err(e) = written {
        assert_eq!(
            e.kind(),
            std::io::ErrorKind::BrokenPipe,
            "writing stdin: {e}"
        );
    }
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
            "totals": "78", "value_type": "u32", "storage_bits": 12 * 32, "fields_per_corner": 1,
        });
        assert_eq!(v, expected, "{}", path.display());
    }
    let v = info(&png, &["--entry", "u16", "--checked"]);
    assert_eq!(v["table_bytes"], 24);
    assert_eq!(
        v,
        info(&png, &["--entry", "u16", "--checked", "--layout", "flat"])
    );
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

// ---------------------------------------------------------------------------------------------
// --layout

use texsat::layouts::{modulus_bits_for, AxisLevels, Modular, Tiled, TiledSpec};
use texsat::{Layout, Texel, Texture};

/// A packed layout as the tests build it through the library, to compute what `sat info` must
/// report.
#[derive(Clone, Copy)]
enum Packed {
    Tiled(TiledSpec),
    Modular(u32),
}

fn spec(xs: &[u32], ys: &[u32]) -> TiledSpec {
    TiledSpec {
        x: AxisLevels::new(xs).unwrap(),
        y: AxisLevels::new(ys).unwrap(),
        modulus: None,
    }
}

/// `v` rounded to 4 decimals, as `sat info` prints bits per entry.
fn round4(v: f64) -> Value {
    json!((v * 1e4).round() / 1e4)
}

/// The fields `sat info` reports for a packed layout, from the layout API (`u64` values: the
/// value type does not change the storage).
fn packed_facts<T: Texel, const C: usize>(data: &[T], w: usize, h: usize, p: Packed) -> Value {
    let tex = Texture::<T, C>::new(data, w, h).unwrap();
    let m = (1u128 << T::BITS) - 1;
    // bits_per_entry is storage bits / (w h C), bits_per_texel storage bits / (w h).
    let per = |bits: u64| {
        (
            round4(bits as f64 / (w * h * C) as f64),
            round4(bits as f64 / (w * h) as f64),
        )
    };
    match p {
        Packed::Tiled(spec) => {
            let n = Tiled::<u64, C>::words_needed(spec, w, h, T::BITS).unwrap();
            let mut words = vec![0u32; n];
            let mut scratch = vec![0u64; Tiled::<u64, C>::scratch_needed(spec, w).unwrap()];
            let t = Tiled::<u64, C>::build(&tex, spec, &mut words, &mut scratch).unwrap();
            let field_bits: Vec<Vec<u32>> = (0..spec.x.components())
                .map(|p| {
                    (0..spec.y.components())
                        .map(|q| t.field_bits(p, q).unwrap())
                        .collect()
                })
                .collect();
            let (bpe, bpt) = per(t.storage_bits());
            assert_eq!(bpe, round4(t.bits_per_entry()), "Layout::bits_per_entry");
            let mut v = json!({
                "words": n, "table_bytes": 4 * n, "storage_bits": t.storage_bits(),
                "bits_per_entry": bpe, "bits_per_texel": bpt,
                "fields_per_corner": t.max_fields_per_corner(), "field_bits": field_bits,
                "blocks_x": spec.x.blocks(), "blocks_y": spec.y.blocks(),
            });
            if let Some(k) = spec.modulus {
                v["k"] = json!(k);
                v["max_exact_area"] = json!((((1u128 << k) - 1) / m) as u64);
            }
            v
        }
        Packed::Modular(k) => {
            let n = Modular::<u64, C>::words_needed(w, h, k).unwrap();
            let mut words = vec![0u32; n];
            let mut row = vec![0u64; w * C];
            let l = Modular::<u64, C>::build(&tex, k, &mut words, &mut row).unwrap();
            let (bpe, bpt) = per(l.storage_bits());
            assert_eq!(bpe, round4(l.bits_per_entry()), "Layout::bits_per_entry");
            json!({
                "words": n, "table_bytes": 4 * n, "storage_bits": l.storage_bits(),
                "bits_per_entry": bpe, "bits_per_texel": bpt, "fields_per_corner": 1,
                "k": k, "max_exact_area": l.max_exact_area() as u64,
            })
        }
    }
}

/// Checks every field of `expected` against `sat info IMAGE --layout LAYOUT`, and the fields
/// common to every layout against the flat layout's.
fn check_info(path: &Path, layout: &str, expected: &Value, value_type: &str) {
    let v = info(path, &["--layout", layout]);
    for (key, want) in expected.as_object().unwrap() {
        assert_eq!(&v[key], want, "{layout}: {key} in {v}");
    }
    assert_eq!(v["layout"], layout);
    assert_eq!(v["value_type"], value_type, "{layout}: {v}");
    let flat = info(path, &[]);
    for key in [
        "width",
        "height",
        "channels",
        "texel_bits",
        "texel_type",
        "bits_needed_worst_case",
        "bits_needed_actual",
        "totals",
    ] {
        assert_eq!(v[key], flat[key], "{layout}: {key}");
    }
}

#[test]
fn info_reports_every_layout() {
    let dir = temp_dir("info-layouts");
    // 8-bit gray, sides that are not multiples of the tiles.
    let gray = Img::noise(13, 9, 1, 8, 21);
    let pgm = dir.join("g.pgm");
    gray.write_pnm(&pgm);
    let g8: Vec<u8> = gray.data.iter().map(|&v| v as u8).collect();
    let b8 = |w: u64, h: u64| modulus_bits_for(8, w * h);
    let cases: Vec<(&str, Packed, &str)> = vec![
        ("packed", Packed::Tiled(TiledSpec::FLAT_PACKED), "u32"),
        (
            "tiled:4x4",
            Packed::Tiled(TiledSpec::tiles(4, 4).unwrap()),
            "u32",
        ),
        (
            "tiled:3x2",
            Packed::Tiled(TiledSpec::tiles(3, 2).unwrap()),
            "u32",
        ),
        (
            "tiled:2x2/8x4",
            Packed::Tiled(spec(&[2, 8], &[2, 4])),
            "u32",
        ),
        (
            "tiled:2x2/4x4/8x8",
            Packed::Tiled(spec(&[2, 4, 8], &[2, 4, 8])),
            "u32",
        ),
        ("modular:12", Packed::Modular(12), "u32"),
        ("modular:40", Packed::Modular(40), "u64"),
        ("modular:box=3x3", Packed::Modular(b8(3, 3)), "u32"),
        (
            "tiled:4x4+mod:14",
            Packed::Tiled(TiledSpec::tiles(4, 4).unwrap().with_modulus(14)),
            "u32",
        ),
        (
            "tiled:2x2/4x4+mod:box=5x5",
            Packed::Tiled(spec(&[2, 4], &[2, 4]).with_modulus(b8(5, 5))),
            "u32",
        ),
    ];
    for (layout, p, value_type) in &cases {
        let expected = packed_facts::<u8, 1>(&g8, 13, 9, *p);
        check_info(&pgm, layout, &expected, value_type);
    }
    // The packed flat table is the flat table at exactly the worst-case width.
    let v = info(&pgm, &["--layout", "packed"]);
    assert_eq!(v["field_bits"], json!([[v["bits_needed_worst_case"]]]));
    assert_eq!(v["bits_per_entry"].as_f64(), Some(15.0)); // bits_of(255 * 117 = 29835)
    assert_eq!(v["storage_bits"], 13 * 9 * 15);
    assert_eq!(v["table_bytes"], (13 * 9 * 15usize).div_ceil(32) * 4);
    // box=3x3: k = bits_of(255 * 9) = 12, exact up to floor(4095 / 255) = 16 cells.
    let v = info(&pgm, &["--layout", "modular:box=3x3"]);
    assert_eq!(
        (v["k"].as_u64(), v["max_exact_area"].as_u64()),
        (Some(12), Some(16))
    );
    // --entry names the value type of the exact packed layouts.
    let v = info(&pgm, &["--layout", "tiled:4x4", "--entry", "u64"]);
    assert_eq!(v["value_type"], "u64");
    let v = info(&pgm, &["--layout", "tiled:4x4", "--entry", "u16"]);
    assert_eq!(v["value_type"], "u16");

    // 16-bit RGB: bits per entry divide by the channels, bits per texel do not.
    let rgb = Img::noise(10, 7, 3, 16, 22);
    let png = dir.join("rgb16.png");
    rgb.write_png(&png);
    let d16 = rgb.data.clone();
    let b16 = |w: u64, h: u64| modulus_bits_for(16, w * h);
    for (layout, p, value_type) in [
        ("packed", Packed::Tiled(TiledSpec::FLAT_PACKED), "u32"),
        (
            "tiled:4x2",
            Packed::Tiled(TiledSpec::tiles(4, 2).unwrap()),
            "u32",
        ),
        (
            "tiled:2x2/4x6",
            Packed::Tiled(spec(&[2, 4], &[2, 6])),
            "u32",
        ),
        ("modular:box=2x2", Packed::Modular(b16(2, 2)), "u32"),
        ("modular:33", Packed::Modular(33), "u64"),
        (
            "tiled:5x5+mod:20",
            Packed::Tiled(TiledSpec::tiles(5, 5).unwrap().with_modulus(20)),
            "u32",
        ),
    ] {
        let expected = packed_facts::<u16, 3>(&d16, 10, 7, p);
        check_info(&png, layout, &expected, value_type);
        let v = info(&png, &["--layout", layout]);
        let (bpe, bpt) = (v["bits_per_entry"].as_f64(), v["bits_per_texel"].as_f64());
        assert!((bpt.unwrap() - 3.0 * bpe.unwrap()).abs() < 1e-3, "{v}");
    }

    // Known numbers: 64 x 64 texels of 8 bits in 8 x 8 tiles (m = 255). Per axis, component 0
    // (inside a tile) stores 7 positions per tile, 56 in all, intervals up to 7 long; component 1
    // (tile corners) stores 8 positions, intervals up to 64 long. Fields (count x bits):
    //   local sums   56 x 56 = 3136 x bits_of(255 * 7 * 7 = 12495)   = 14 -> 43904
    //   strips       56 x 8  =  448 x bits_of(255 * 7 * 64 = 114240) = 17 ->  7616, twice
    //   corners       8 x 8  =   64 x bits_of(255 * 64 * 64)         = 20 ->  1280
    // 60416 bits = 1888 words = 7552 bytes; 60416 / 4096 = 14.75 bits per entry.
    let big = Img::noise(64, 64, 1, 8, 23);
    let path = dir.join("g64.pgm");
    big.write_pnm(&path);
    let v = info(&path, &["--layout", "tiled:8x8"]);
    assert_eq!(v["bits_per_entry"].as_f64(), Some(14.75), "{v}");
    assert_eq!(v["bits_per_texel"].as_f64(), Some(14.75));
    assert_eq!(v["storage_bits"], 60416);
    assert_eq!(v["words"], 1888);
    assert_eq!(v["table_bytes"], 7552);
    assert_eq!(v["field_bits"], json!([[14, 17], [17, 20]]));
    assert_eq!(v["fields_per_corner"], 4);
    assert_eq!(v["blocks_x"], json!([8]));
}

/// Answers of `sat query` on every layout against the flat table and the direct integrals.
#[test]
fn query_on_every_layout_matches_flat() {
    let dir = temp_dir("query-layouts");
    let gray = Img::noise(13, 9, 1, 8, 31);
    let pgm = dir.join("g.pgm");
    gray.write_pnm(&pgm);
    let rgb = Img::noise(7, 6, 3, 16, 32);
    let png = dir.join("rgb16.png");
    rgb.write_png(&png);
    // Modular K large enough for every box below (boxes up to 3 periods per side, plus 2F bits
    // of headroom for the paper form and the edge path).
    let layouts = [
        "packed",
        "tiled:4x4",
        "tiled:3x2",
        "tiled:2x2/8x4",
        "tiled:2x2/4x4/8x8",
        "modular:40",
        "tiled:4x4+mod:40",
    ];
    let runs: [(u32, &str); 3] = [(0, "paper"), (4, "paper"), (6, "stable")];
    let mut checked = 0;
    for (img, path) in [(&gray, &pgm), (&rgb, &png)] {
        for mode in ["border", "clamp", "repeat", "mirror"] {
            for (i, &(f, form)) in runs.iter().enumerate() {
                let mut list = boxes(img, f, mode != "border", 25, 40 + i as u64);
                list.extend(boxes(img, f, false, 15, 50 + i as u64));
                let input: String = list.iter().map(|&b| box_line(b, f) + "\n").collect();
                let fs = f.to_string();
                let common = ["--frac-bits", &fs, "--edge", mode, "--form", form];
                let (flat, ok) = query(path, &common, &input);
                assert!(ok, "flat {mode} F={f}: {flat:?}");
                for layout in layouts {
                    let mut opts = common.to_vec();
                    opts.extend(["--layout", layout]);
                    let (answers, ok) = query(path, &opts, &input);
                    assert!(ok, "{layout} {mode} F={f}: {answers:?}");
                    assert_eq!(answers.len(), list.len());
                    for ((v, fv), &b) in answers.iter().zip(&flat).zip(&list) {
                        let what = format!("{layout} {mode} F={f} {form} {b:?}: {v}");
                        assert_eq!(v["sum"], fv["sum"], "{what}");
                        assert_eq!(v["mean"], fv["mean"], "{what}");
                        assert_eq!(v["lookup"], fv["lookup"], "{what}");
                        assert_eq!(
                            (&v["muls"], &v["divs"]),
                            (&fv["muls"], &fv["divs"]),
                            "{what}"
                        );
                        let (reads, words) = (v["reads"].as_u64(), v["words"].as_u64());
                        assert!(words >= reads, "every read touches a word: {what}");
                        if layout == "packed" || layout.starts_with("modular") {
                            // One field per corner, as the flat table.
                            assert_eq!(reads, fv["reads"].as_u64(), "{what}");
                        } else {
                            assert!(reads >= fv["reads"].as_u64(), "{what}");
                        }
                        if b[0] != b[2] && b[1] != b[3] {
                            check_answer(img, v, b, f, 2 * f + 8, mode);
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(checked > 3000, "{checked} answers checked");

    // Costs on a tiled layout, by hand: tiled:4x4, box [1, 5) x [1, 5). The corner (1, 1) reads
    // the local sum only; (5, 1) and (1, 5) a local sum and a strip; (5, 5) all four fields:
    // 9 reads, 0 + 1 + 1 + 3 adds in the corners plus 3 for the box.
    let (a, ok) = query(
        &pgm,
        &["--frac-bits", "0", "--layout", "tiled:4x4"],
        "1 1 5 5\n",
    );
    assert!(ok);
    assert_eq!(costs(&a[0]), (9, 1, 1, 8), "{}", a[0]);
    // The flat table: one 32-bit word per read.
    let (a, _) = query(&pgm, &["--frac-bits", "0"], "1 1 5 5\n");
    assert_eq!(
        (a[0]["reads"].as_u64(), a[0]["words"].as_u64()),
        (Some(4), Some(4))
    );
    // Modular: k bits per read (all channels together).
    let (a, _) = query(
        &png,
        &["--frac-bits", "0", "--layout", "modular:40"],
        "1 1 5 5\n",
    );
    assert_eq!(
        (a[0]["reads"].as_u64(), a[0]["bits_read"].as_u64()),
        (Some(4), Some(4 * 3 * 40))
    );
}

#[test]
fn modular_refuses_big_boxes_and_answers_small_ones() {
    let dir = temp_dir("modular");
    let img = Img::noise(20, 20, 1, 8, 61);
    let pgm = dir.join("g.pgm");
    img.write_pnm(&pgm);
    // box=4x4: k = bits_of(255 * 16 = 4080) = 12; a 5 x 5 box needs bits_of(255 * 25) = 13.
    let input = "0 0 4 4\n2 2 7 7\n1 1 3 4\n0 0 20 20\n16 16 20 20\n";
    for layout in [
        "modular:box=4x4",
        "modular:12",
        "tiled:4x4+mod:box=4x4",
        "tiled:2x2/4x4+mod:12",
    ] {
        let (a, ok) = query(&pgm, &["--frac-bits", "0", "--layout", layout], input);
        assert!(
            !ok,
            "{layout}: a refused box makes the exit status non-zero"
        );
        assert_eq!(a.len(), 5, "{layout}: {a:?}");
        for (i, b) in [(0, [0, 0, 4, 4]), (2, [1, 1, 3, 4]), (4, [16, 16, 20, 20])] {
            check_answer(&img, &a[i], b, 0, 8, "border");
        }
        assert_eq!(
            a[1],
            json!({"error": "box sum on the modular layout needs 13 bits but only 12 are available", "line": 2}),
            "{layout}"
        );
        assert_eq!(
            a[3],
            json!({"error": "box sum on the modular layout needs 17 bits but only 12 are available", "line": 4}),
            "{layout}"
        );
    }
    // Fractional corners (stable form: no headroom): a box counts the texel cells it overlaps.
    let (a, ok) = query(
        &pgm,
        &["--form", "stable", "--layout", "modular:box=4x4"],
        "0.5 0.5 3.5 3.5\n0.5 0.5 4.5 4.5\n1 1 5 5\n",
    );
    assert!(!ok);
    check_answer(&img, &a[0], [128, 128, 896, 896], 8, 24, "border");
    assert_eq!(a[1]["line"], 2);
    assert!(
        a[1]["error"].as_str().unwrap().contains("needs 13 bits"),
        "{}",
        a[1]
    );
    check_answer(&img, &a[2], [256, 256, 1280, 1280], 8, 24, "border");
    // The paper form needs 2F bits above the box sum: at F = 8 not even one texel fits k = 12,
    // which is said once on stderr, before any input is read.
    let out = run(
        &[
            "query",
            pgm.to_str().unwrap(),
            "--layout",
            "modular:box=4x4",
        ],
        "1 1 2 2\n",
    );
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    assert!(stderr(&out).contains("headroom"), "{}", stderr(&out));
    // At F = 2 it needs 4 bits more: one cell fits (bits_of(255) + 4 = 12), a box overlapping
    // 2 x 2 cells does not (bits_of(255 * 4) + 4 = 14).
    let (a, ok) = query(
        &pgm,
        &["--frac-bits", "2", "--layout", "modular:box=4x4"],
        "0 0 1 1\n0.25 0.25 1.75 1.75\n",
    );
    assert!(!ok);
    check_answer(&img, &a[0], [0, 0, 4, 4], 2, 12, "border");
    assert!(
        a[1]["error"]
            .as_str()
            .unwrap()
            .contains("needs 14 bits but only 12"),
        "{}",
        a[1]
    );
}

#[test]
fn bad_layouts_fail() {
    let dir = temp_dir("bad-layouts");
    let img = Img::noise(9, 9, 1, 8, 71);
    let pgm = dir.join("g.pgm");
    img.write_pnm(&pgm);
    let p = pgm.to_str().unwrap();
    for bad in [
        "",
        "Flat",
        "tiles:8x8",
        "tiled",
        "tiled:",
        "tiled:8",
        "tiled:8x",
        "tiled:x8",
        "tiled:0x4",
        "tiled:1x1",
        "tiled:8x8/12x16",
        "tiled:8x8/4x4",
        "tiled:2x2/4x4/8x8/16x16/32x32",
        "tiled:8x8+",
        "tiled:8x8+mod:",
        "tiled:8x8+mod:0",
        "tiled:8x8+k:16",
        "modular",
        "modular:",
        "modular:0",
        "modular:65",
        "modular:-3",
        "modular:box=16",
        "modular:box=0x4",
        "modular:16+tiled:8x8",
        "packed+mod:16",
    ] {
        for cmd in ["info", "query"] {
            let out = run(&[cmd, p, "--layout", bad], "1 1 2 2\n");
            assert!(!out.status.success(), "{cmd} --layout {bad:?} should fail");
            assert!(out.stdout.is_empty(), "{bad:?}: {}", stdout(&out));
            assert!(
                stderr(&out).contains("--layout"),
                "{bad:?}: {}",
                stderr(&out)
            );
        }
    }
    // Well-formed but unusable with this image or these options: a message, exit status 1.
    for (args, needle) in [
        (vec!["--layout", "modular:7"], "texel width"),
        (vec!["--layout", "tiled:4x4+mod:5"], "texel width"),
        (
            vec!["--layout", "modular:40", "--entry", "u32"],
            "does not fit --entry u32",
        ),
        (
            vec!["--layout", "modular:12", "--entry", "u16"],
            "u32 or u64",
        ),
        (vec!["--layout", "tiled:4x4", "--checked"], "--checked"),
        (vec!["--layout", "packed", "--checked"], "flat layout only"),
    ] {
        let mut full = vec!["info", p];
        full.extend(&args);
        let out = run(&full, "");
        assert!(!out.status.success(), "{args:?}");
        assert!(out.stdout.is_empty());
        assert!(stderr(&out).contains(needle), "{args:?}: {}", stderr(&out));
    }
    // A value type too narrow for the worst case names a wider one (and not --checked).
    let big = Img::noise(64, 64, 1, 8, 72);
    let path = dir.join("g64.pgm");
    big.write_pnm(&path);
    let out = run(
        &[
            "info",
            path.to_str().unwrap(),
            "--layout",
            "tiled:8x8",
            "--entry",
            "u16",
        ],
        "",
    );
    assert!(!out.status.success());
    let msg = stderr(&out);
    assert!(
        msg.contains("20 bits") && msg.contains("--entry u32") && !msg.contains("--checked"),
        "{msg}"
    );
}

// ---------------------------------------------------------------------------------------------
// --filter: the comparison filters, each against an independent computation here

const MODES: [&str; 4] = ["border", "clamp", "repeat", "mirror"];

/// Runs `sat query --filter NAME`, checks that every line was answered by that filter, and
/// returns the answers.
fn filter_query(image: &Path, filter: &str, opts: &[&str], input: &str) -> Vec<Value> {
    let mut all = vec!["--filter", filter];
    all.extend_from_slice(opts);
    let (lines, ok) = query(image, &all, input);
    assert!(ok, "--filter {filter} {opts:?}: {lines:?}");
    assert_eq!(lines.len(), input.lines().count(), "{lines:?}");
    for v in &lines {
        assert_eq!(v["filter"], filter, "{v}");
    }
    lines
}

/// Channel `ch` of a filter's value (a string, or an array of strings with several channels).
fn value(v: &Value, ch: usize) -> &str {
    let x = if v["value"].is_array() {
        &v["value"][ch]
    } else {
        &v["value"]
    };
    x.as_str()
        .unwrap_or_else(|| panic!("no value for channel {ch} in {v}"))
}

fn value_f64(v: &Value, ch: usize) -> f64 {
    value(v, ch).parse().unwrap()
}

/// `(reads, muls, divs)`, the survey's columns (multiplicative = muls + divs).
fn filter_costs(v: &Value) -> (u64, u64, u64) {
    let (r, m, d, _) = costs(v);
    (r, m, d)
}

/// `round(num / den)` to a multiple of `2^-16`, ties up, as the exact decimal the filters print.
fn rounded16(num: u128, den: u128) -> String {
    let n = num << 16;
    let (q, r) = (n / den, n % den);
    decimal(if 2 * r >= den { q + 1 } else { q }, 16)
}

fn lines_of(list: &[[i64; 4]], f: u32) -> String {
    list.iter().map(|&b| box_line(b, f) + "\n").collect()
}

/// A deterministic stream of small numbers for placing footprints.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: i64) -> i64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n as u64) as i64
    }
}

#[test]
fn point_filter_is_the_texel_at_the_centre() {
    let dir = temp_dir("filter-point");
    let gray = Img::noise(7, 5, 1, 8, 101);
    let pgm = dir.join("g.pgm");
    gray.write_pnm(&pgm);
    let rgb = Img::noise(5, 4, 3, 16, 102);
    let png = dir.join("rgb.png");
    rgb.write_png(&png);
    let f = 4;
    let fs = f.to_string();
    for (img, path) in [(&gray, &pgm), (&rgb, &png)] {
        for mode in MODES {
            let list = boxes(img, f, true, 60, 103);
            let answers = filter_query(
                path,
                "point",
                &["--frac-bits", &fs, "--edge", mode],
                &lines_of(&list, f),
            );
            for (v, b) in answers.iter().zip(&list) {
                // The texel holding the centre ((x0 + x1) / 2, (y0 + y1) / 2).
                let i = (b[0] + b[2]).div_euclid(1 << (f + 1));
                let j = (b[1] + b[3]).div_euclid(1 << (f + 1));
                for ch in 0..img.c {
                    let t = img.ext(i, j, ch, mode).unwrap_or(0);
                    assert_eq!(value(v, ch), t.to_string(), "{mode} {b:?}: {v}");
                }
                if img.c > 1 {
                    assert_eq!(v["value"].as_array().unwrap().len(), img.c);
                }
                assert_eq!(costs(v), (1, 0, 0, 0), "{v}");
            }
        }
    }
}

#[test]
fn mip_filter_point_samples_the_level_of_the_footprint() {
    let dir = temp_dir("filter-mip");
    let img = Img::noise(16, 12, 1, 8, 111);
    let pgm = dir.join("g.pgm");
    img.write_pnm(&pgm);
    let f = 2u32;
    let mut rng = Lcg(112);
    // (box, level): square and elongated footprints with power-of-two sides (log2 exact),
    // centres inside the texture; level 6 is past the top (1 x 1, level 4) and clamps.
    let mut cases = Vec::new();
    for (lx, ly) in [
        (0, 0),
        (1, 1),
        (2, 2),
        (3, 3),
        (2, 0),
        (0, 3),
        (1, 2),
        (6, 6),
    ] {
        for _ in 0..10 {
            let (cx, cy) = (rng.below(16 << f), rng.below(12 << f));
            let (hw, hh) = (1i64 << (lx + f - 1), 1i64 << (ly + f - 1));
            cases.push(([cx - hw, cy - hh, cx + hw, cy + hh], lx.max(ly).min(4)));
        }
    }
    let list: Vec<[i64; 4]> = cases.iter().map(|c| c.0).collect();
    for mode in ["border", "clamp"] {
        let answers = filter_query(
            &pgm,
            "mip",
            &["--frac-bits", "2", "--edge", mode],
            &lines_of(&list, f),
        );
        for (v, &(b, l)) in answers.iter().zip(&cases) {
            // The level-l texel holding the centre: the rounded mean of its clipped base block.
            let i = ((b[0] + b[2]) / 2) >> (f + l);
            let j = ((b[1] + b[3]) / 2) >> (f + l);
            let (xs, ys) = (
                (i << l) as usize..(((i + 1) << l) as usize).min(img.w),
                (j << l) as usize..(((j + 1) << l) as usize).min(img.h),
            );
            let count = (xs.len() * ys.len()) as u64;
            let sum: u64 = ys
                .flat_map(|y| xs.clone().map(move |x| (x, y)))
                .map(|(x, y)| u64::from(img.at(x, y, 0)))
                .sum();
            let mean = (2 * sum + count) / (2 * count);
            assert_eq!(value(v, 0), mean.to_string(), "{mode} {b:?} level {l}: {v}");
            assert_eq!(costs(v), (1, 0, 0, 0), "{v}");
        }
    }
}

#[test]
fn pyramid_filters_constant_images_bilinear_and_costs() {
    let dir = temp_dir("filter-pyramids");
    let c8 = Img {
        w: 9,
        h: 7,
        c: 1,
        bits: 8,
        data: vec![173; 63],
    };
    let p8 = dir.join("c8.pgm");
    c8.write_pnm(&p8);
    let c16 = Img {
        w: 6,
        h: 5,
        c: 3,
        bits: 16,
        data: [1000u16, 65535, 7].repeat(30),
    };
    let p16 = dir.join("c16.png");
    c16.write_png(&p16);
    let noise = Img::noise(8, 6, 1, 8, 121);
    let pn = dir.join("n.pgm");
    noise.write_pnm(&pn);
    let big = Img::noise(32, 32, 1, 8, 122);
    let pb = dir.join("big.pgm");
    big.write_pnm(&pb);
    let f = 4;
    let fs = f.to_string();
    // The survey's reads and multiplies, and Crow's additive operations.
    type Costs = (u64, u64, u64, u64);
    let filters: [(&str, Costs); 4] = [
        ("trilinear", (8, 7, 0, 14)),
        ("ripmap", (16, 15, 0, 30)),
        ("dipmap", (8, 6, 0, 13)),
        ("dipmap-trilinear", (16, 14, 0, 29)),
    ];
    for (filter, survey) in filters {
        // A constant image gives the constant exactly, every footprint (inside, outside, zero
        // area, spanning periods) under the modes that extend it with itself.
        for (img, path) in [(&c8, &p8), (&c16, &p16)] {
            for mode in ["clamp", "repeat", "mirror"] {
                let list = boxes(img, f, true, 40, 123);
                let opts = ["--frac-bits", fs.as_str(), "--edge", mode];
                let answers = filter_query(path, filter, &opts, &lines_of(&list, f));
                for (v, b) in answers.iter().zip(&list) {
                    for ch in 0..img.c {
                        assert_eq!(value(v, ch), img.data[ch].to_string(), "{mode} {b:?}: {v}");
                    }
                }
            }
            // Border: footprints of one texel whose taps stay inside.
            let list: Vec<[i64; 4]> = (0..20)
                .map(|n| {
                    let x = (8 + 3 * n) % ((img.w as i64 - 1) << f) + 8;
                    let y = (8 + 5 * n) % ((img.h as i64 - 1) << f) + 8;
                    [x - 8, y - 8, x + 8, y + 8]
                })
                .collect();
            let opts = ["--frac-bits", fs.as_str(), "--edge", "border"];
            let answers = filter_query(path, filter, &opts, &lines_of(&list, f));
            for (v, b) in answers.iter().zip(&list) {
                for ch in 0..img.c {
                    assert_eq!(value(v, ch), img.data[ch].to_string(), "border {b:?}: {v}");
                }
            }
        }
        // A footprint of exactly one texel is level 0 of every pyramid: bilinear interpolation
        // of the texture at the centre, exact here (weights are multiples of 2^-4).
        for mode in MODES {
            let list: Vec<[i64; 4]> = boxes(&noise, f, true, 50, 124)
                .into_iter()
                .map(|b| [b[0], b[1], b[0] + 16, b[1] + 16])
                .collect();
            let opts = ["--frac-bits", fs.as_str(), "--edge", mode];
            let answers = filter_query(&pn, filter, &opts, &lines_of(&list, f));
            for (v, b) in answers.iter().zip(&list) {
                // Centre c = x0 + 1/2, so u = c - 1/2 = x0: taps floor(x0), floor(x0) + 1.
                let (i, a) = (b[0] >> f, (b[0] & 15) as u128);
                let (j, c) = (b[1] >> f, (b[1] & 15) as u128);
                let t =
                    |di: i64, dj: i64| u128::from(noise.ext(i + di, j + dj, 0, mode).unwrap_or(0));
                let num = (16 - a) * (16 - c) * t(0, 0)
                    + a * (16 - c) * t(1, 0)
                    + (16 - a) * c * t(0, 1)
                    + a * c * t(1, 1);
                assert_eq!(value(v, 0), decimal(num << 8, 16), "{mode} {b:?}: {v}");
            }
        }
        // The survey's counts, for every footprint under clamp (every tap is fetched) and for
        // interior footprints under border.
        let list = boxes(&big, f, true, 40, 125);
        let opts = ["--frac-bits", fs.as_str(), "--edge", "clamp"];
        for v in filter_query(&pb, filter, &opts, &lines_of(&list, f)) {
            assert_eq!(costs(&v), survey, "{filter} clamp: {v}");
        }
        let inner = "12 12 16 16\n10.5 10.25 17.75 13.5\n14 9 15 21.5\n";
        for v in filter_query(&pb, filter, &[], inner) {
            assert_eq!(costs(&v), survey, "{filter} border: {v}");
        }
    }
}

/// The exact triangle filter with integer centre `(cx, cy)` and half-widths `a`, `b`: texel
/// `cx + d` has weight `(2a - |2d + 1|) / (2a^2)` per axis. Returns the numerator over
/// `4 a^2 b^2`.
fn tent_int(img: &Img, cx: i64, cy: i64, a: i64, b: i64, ch: usize, mode: &str) -> u128 {
    let mut num = 0u128;
    for e in -b..b {
        for d in -a..a {
            let wx = (2 * a - (2 * d + 1).abs()) as u128;
            let wy = (2 * b - (2 * e + 1).abs()) as u128;
            let t = u128::from(img.ext(cx + d, cy + e, ch, mode).unwrap_or(0));
            num += wx * wy * t;
        }
    }
    num
}

/// The exact triangle filter over the footprint `[x0, x1) x [y0, y1)` (f64), per texel the
/// integral of the separable kernel `(a - |u - c|)+ / a^2`.
fn tent_f64(img: &Img, raw: [i64; 4], f: u32, ch: usize, mode: &str) -> f64 {
    let s = (1u64 << f) as f64;
    let [x0, y0, x1, y1] = raw.map(|v| v as f64 / s);
    let axis = |lo: f64, hi: f64| -> Vec<(i64, f64)> {
        let (c, a) = ((lo + hi) / 2.0, (hi - lo) / 2.0);
        // The kernel's integral from -infinity to c + s.
        let p = |s: f64| {
            if s <= -a {
                0.0
            } else if s <= 0.0 {
                (s + a) * (s + a) / (2.0 * a * a)
            } else if s < a {
                1.0 - (a - s) * (a - s) / (2.0 * a * a)
            } else {
                1.0
            }
        };
        (lo.floor() as i64..=hi.ceil() as i64)
            .map(|i| (i, p(i as f64 + 1.0 - c) - p(i as f64 - c)))
            .collect()
    };
    let (wx, wy) = (axis(x0, x1), axis(y0, y1));
    let mut v = 0.0;
    for &(j, b) in &wy {
        for &(i, a) in &wx {
            v += a * b * f64::from(img.ext(i, j, ch, mode).unwrap_or(0));
        }
    }
    v
}

#[test]
fn tent_filters_match_the_triangle_filter() {
    let dir = temp_dir("filter-tent");
    let img = Img::noise(11, 9, 1, 8, 131);
    let pgm = dir.join("g.pgm");
    img.write_pnm(&pgm);
    let m = 255.0;
    let mut rng = Lcg(132);
    for mode in MODES {
        // Integer corners, even sides: the integer variant, exact.
        let cases: Vec<[i64; 4]> = (0..40)
            .map(|_| {
                [
                    rng.below(21) - 5,
                    rng.below(19) - 5,
                    rng.below(5) + 1,
                    rng.below(5) + 1,
                ]
            })
            .collect();
        let list: Vec<[i64; 4]> = cases
            .iter()
            .map(|&[cx, cy, a, b]| [cx - a, cy - b, cx + a, cy + b])
            .collect();
        for f in [0, 6] {
            let fs = f.to_string();
            let opts = ["--frac-bits", fs.as_str(), "--edge", mode];
            let answers = filter_query(&pgm, "tent", &opts, &lines_of(&list, 0));
            let exact = filter_query(&pgm, "tent-exact", &opts, &lines_of(&list, 0));
            for ((v, e), &[cx, cy, a, b]) in answers.iter().zip(&exact).zip(&cases) {
                let want = rounded16(
                    tent_int(&img, cx, cy, a, b, 0, mode),
                    (4 * a * a * b * b) as u128,
                );
                assert_eq!(v["variant"], "int", "{v}");
                assert_eq!(
                    value(v, 0),
                    want,
                    "{mode} F={f} centre ({cx}, {cy}) a={a} b={b}"
                );
                assert_eq!(value(e, 0), want, "tent-exact {mode} F={f}: {e}");
            }
        }
        // Fractional corners (or odd sides): the paper's bilinear variant within its bound,
        // tent-exact within the output rounding.
        let f = 4;
        let fs = f.to_string();
        let mut list: Vec<[i64; 4]> = boxes(&img, f, true, 50, 133)
            .into_iter()
            .filter(|b| b[2] > b[0] && b[3] > b[1])
            .collect();
        list.push([1 << f, 1 << f, 4 << f, 3 << f]); // integer corners, odd width: paper
        let opts = ["--frac-bits", fs.as_str(), "--edge", mode];
        let paper = filter_query(&pgm, "tent", &opts, &lines_of(&list, f));
        let exact = filter_query(&pgm, "tent-exact", &opts, &lines_of(&list, f));
        for ((p, e), &b) in paper.iter().zip(&exact).zip(&list) {
            let want = tent_f64(&img, b, f, 0, mode);
            let a = (b[2] - b[0]) as f64 / 32.0;
            let c = (b[3] - b[1]) as f64 / 32.0;
            let bound = m / 4.0 * (1.0 / (a * a) + 1.0 / (c * c) + 1.0 / (2.0 * a * a * c * c));
            let integer = b.iter().all(|v| v % 16 == 0);
            let even = (b[2] - b[0]) % 32 == 0 && (b[3] - b[1]) % 32 == 0;
            if !(integer && even) {
                assert_eq!(p["variant"], "paper", "{p}");
            }
            let (pv, ev) = (value_f64(p, 0), value_f64(e, 0));
            assert!(
                (ev - want).abs() <= 1e-4,
                "tent-exact {mode} {b:?}: {ev} vs {want}"
            );
            assert!(
                (pv - want).abs() <= bound + 1e-4,
                "tent {mode} {b:?}: {pv} vs {want} (bound {bound})"
            );
        }
    }
    // Costs, interior footprints of a larger texture: the survey's "9,4" and "36,31".
    let big = Img::noise(32, 32, 1, 8, 134);
    let pb = dir.join("big.pgm");
    big.write_pnm(&pb);
    let a = filter_query(&pb, "tent", &[], "10 10 14 14\n10.5 10.25 17.75 13.5\n");
    assert_eq!(
        (a[0]["variant"].as_str(), filter_costs(&a[0])),
        (Some("int"), (9, 3, 1))
    );
    assert_eq!(a[0]["adds"], 8);
    assert_eq!(
        (a[1]["variant"].as_str(), filter_costs(&a[1])),
        (Some("paper"), (36, 30, 1))
    );
    let e = filter_query(&pb, "tent-exact", &[], "10.5 10.25 17.75 13.5\n");
    assert_eq!(filter_costs(&e[0]), (81, 72, 1));
    // A zero-width footprint has no triangle: an error line, the next line still answered.
    let (a, ok) = query(&pb, &["--filter", "tent"], "3 3 3 5\n2 2 4 4\n");
    assert!(!ok);
    assert!(
        a[0]["error"].as_str().unwrap().contains("zero area"),
        "{}",
        a[0]
    );
    assert_eq!(a[0]["line"], 1);
    assert_eq!(a[1]["variant"], "int");
}

/// The exact variance over a box (raw corners, `f` fraction bits) of the extended texture,
/// as the numerator and denominator `(n Q - S^2, n^2)` (areas in units of `2^-2f`).
fn variance_exact(img: &Img, raw: [i64; 4], f: u32, ch: usize, mode: &str) -> (u128, u128) {
    let [x0, y0, x1, y1] = raw;
    let overlap = |lo: i64, hi: i64, i: i64| (hi.min((i + 1) << f) - lo.max(i << f)).max(0);
    let (mut s, mut q) = (0u128, 0u128);
    for j in (y0 >> f)..=((y1 - 1) >> f) {
        for i in (x0 >> f)..=((x1 - 1) >> f) {
            let w = (overlap(x0, x1, i) * overlap(y0, y1, j)) as u128;
            let t = u128::from(img.ext(i, j, ch, mode).unwrap_or(0));
            s += w * t;
            q += w * t * t;
        }
    }
    let n = ((x1 - x0) * (y1 - y0)) as u128;
    (n * q - s * s, n * n)
}

#[test]
fn variance_filter_is_exact() {
    let dir = temp_dir("filter-variance");
    let constant = Img {
        w: 8,
        h: 6,
        c: 3,
        bits: 8,
        data: [77u16, 0, 255].repeat(48),
    };
    let pc = dir.join("c.png");
    constant.write_png(&pc);
    let img = Img::noise(9, 7, 1, 8, 141);
    let pgm = dir.join("g.pgm");
    img.write_pnm(&pgm);
    let f = 4;
    let fs = f.to_string();
    // A constant image has variance 0 over every box (border: boxes inside the texture).
    for mode in MODES {
        let list: Vec<[i64; 4]> = boxes(&constant, f, mode != "border", 40, 142)
            .into_iter()
            .filter(|b| b[2] > b[0] && b[3] > b[1])
            .collect();
        let opts = ["--frac-bits", fs.as_str(), "--edge", mode];
        for v in filter_query(&pc, "variance", &opts, &lines_of(&list, f)) {
            for ch in 0..3 {
                assert_eq!(value(&v, ch), "0", "{mode}: {v}");
            }
        }
    }
    // Two texels a, b: ((a - b) / 2)^2, horizontally and vertically.
    let mut pairs = String::new();
    let mut want = Vec::new();
    for y in 0..6 {
        for x in 0..8 {
            pairs += &format!("{x} {y} {} {}\n{x} {y} {} {}\n", x + 2, y + 1, x + 1, y + 2);
            for (a, b) in [
                (img.at(x, y, 0), img.at(x + 1, y, 0)),
                (img.at(x, y, 0), img.at(x, y + 1, 0)),
            ] {
                let d = u128::from(a.abs_diff(b));
                want.push(rounded16(d * d, 4));
            }
        }
    }
    let answers = filter_query(&pgm, "variance", &["--frac-bits", "0"], &pairs);
    for (v, w) in answers.iter().zip(&want) {
        assert_eq!(value(v, 0), w.as_str(), "{v}");
        assert_eq!(v["variant"], "int");
    }
    // Every box, every mode, both forms: the exact weighted variance, rounded.
    for mode in MODES {
        for form in ["paper", "stable"] {
            let list: Vec<[i64; 4]> = boxes(&img, f, true, 40, 143)
                .into_iter()
                .filter(|b| b[2] > b[0] && b[3] > b[1])
                .collect();
            let opts = ["--frac-bits", fs.as_str(), "--edge", mode, "--form", form];
            let answers = filter_query(&pgm, "variance", &opts, &lines_of(&list, f));
            for (v, &b) in answers.iter().zip(&list) {
                let (num, den) = variance_exact(&img, b, f, 0, mode);
                assert_eq!(value(v, 0), rounded16(num, den), "{mode} {form} {b:?}: {v}");
                let integer = b.iter().all(|c| c % 16 == 0);
                assert_eq!(v["variant"], if integer { "int" } else { form }, "{v}");
            }
        }
    }
    // Costs, interior boxes: 4 reads per table; 4 muls + 1 div (+ 12 per fractional box sum).
    let a = filter_query(&pgm, "variance", &[], "2 2 5 4\n2.5 2 5 4.75\n");
    assert_eq!(filter_costs(&a[0]), (8, 4, 1));
    assert_eq!(filter_costs(&a[1]), (32, 28, 1));
}

#[test]
fn info_filter_reports_memory() {
    let dir = temp_dir("filter-info");
    let img = Img::noise(64, 64, 1, 8, 151);
    let pgm = dir.join("g.pgm");
    img.write_pnm(&pgm);
    let tex = 64 * 64;
    // (filter, storage bytes, memory ratio range): mip levels 1.. = 32^2 + ... + 1 = 1365;
    // ripmap (sum of 64 >> l)^2 = 127^2; dipmap 64 * 127 + 64 * 63; tent 65^2 u64 entries;
    // variance two u32 tables (squares need 28 bits); box one u32 table.
    let expected: [(&str, Option<u64>, f64, f64); 10] = [
        ("point", Some(0), 1.0, 1.0),
        ("mip", Some(1365), 1.3, 1.36),
        ("trilinear", Some(1365), 1.3, 1.36),
        ("ripmap", Some(127 * 127), 3.8, 4.1),
        ("dipmap", Some(64 * 127 + 64 * 63), 2.9, 3.1),
        ("dipmap-trilinear", Some(64 * 127 + 64 * 63), 2.9, 3.1),
        ("tent", Some(65 * 65 * 8), 7.9, 8.3),
        ("tent-exact", None, 12.0, 20.0),
        ("variance", Some(2 * 4 * tex), 8.0, 8.0),
        ("box", Some(4 * tex), 4.0, 4.0),
    ];
    for (filter, storage, lo, hi) in expected {
        let v = info(&pgm, &["--filter", filter]);
        assert_eq!(v["filter"], filter, "{v}");
        assert_eq!(v["texture_bytes"], tex, "{v}");
        if let Some(s) = storage {
            assert_eq!(v["storage_bytes"], s, "{v}");
        }
        let memory = v["storage_bytes"].as_u64().unwrap()
            + if v["reads_texture"].as_bool().unwrap() {
                tex
            } else {
                0
            };
        assert_eq!(v["memory_bytes"], memory, "{v}");
        let ratio = v["memory_ratio"].as_f64().unwrap();
        assert!(
            (lo..=hi).contains(&ratio),
            "{filter}: ratio {ratio} not in [{lo}, {hi}]"
        );
    }
    assert_eq!(info(&pgm, &["--filter", "tent"])["entry_type"], "u64");
    let var = info(&pgm, &["--filter", "variance"]);
    assert_eq!(
        (var["tables"].as_u64(), var["entry_type"].as_str()),
        (Some(2), Some("u32"))
    );
    let var64 = info(&pgm, &["--filter", "variance", "--entry", "u64"]);
    assert_eq!(var64["memory_ratio"], 16.0);
    // The box filter keeps the table report and adds the memory fields (packed: 20 bits of
    // 255 x 64 x 64 per 8-bit texel).
    let b = info(&pgm, &["--filter", "box", "--layout", "packed"]);
    assert_eq!(
        (b["layout"].as_str(), b["memory_ratio"].as_f64()),
        (Some("packed"), Some(2.5))
    );
    // Several channels of 16 bits: the ratios do not change.
    let rgb = Img::noise(32, 16, 3, 16, 152);
    let png = dir.join("rgb.png");
    rgb.write_png(&png);
    let mip = info(&png, &["--filter", "mip"]);
    assert_eq!(
        (mip["channels"].as_u64(), mip["storage_type"].as_str()),
        (Some(3), Some("u16"))
    );
    // 16 x 8 + 8 x 4 + 4 x 2 + 2 x 1 + 1 x 1 = 171 texels of 3 u16.
    assert_eq!(mip["storage_bytes"], 171 * 3 * 2);
    let ratio = mip["memory_ratio"].as_f64().unwrap();
    assert!((1.3..1.36).contains(&ratio), "{ratio}");
}

#[test]
fn bad_filters_and_options_fail() {
    let dir = temp_dir("filter-bad");
    let img = Img::noise(9, 9, 1, 8, 161);
    let pgm = dir.join("g.pgm");
    img.write_pnm(&pgm);
    let p = pgm.to_str().unwrap();
    for bad in [
        "",
        "blur",
        "Box",
        "tent_exact",
        "dip",
        "ripmap ",
        "variance2",
        "mipmap",
    ] {
        for cmd in ["info", "query"] {
            let out = run(&[cmd, p, "--filter", bad], "1 1 2 2\n");
            assert!(!out.status.success(), "{cmd} --filter {bad:?} should fail");
            assert!(out.stdout.is_empty(), "{bad:?}: {}", stdout(&out));
            assert!(
                stderr(&out).contains("--filter"),
                "{bad:?}: {}",
                stderr(&out)
            );
        }
    }
    // Options that do not apply to the filter: a message, nothing on stdout.
    for (args, needle) in [
        (
            vec!["query", p, "--filter", "mip", "--layout", "packed"],
            "--layout",
        ),
        (
            vec!["info", p, "--filter", "tent", "--checked"],
            "--checked",
        ),
        (
            vec!["query", p, "--filter", "ripmap", "--entry", "u64"],
            "--entry",
        ),
        (
            vec!["info", p, "--filter", "variance", "--entry", "u16"],
            "u32 or u64",
        ),
        (
            vec!["query", p, "--filter", "tent", "--mean-bits", "4"],
            "--mean-bits",
        ),
        (vec!["query", p, "--filter", "point", "--int4"], "--int4"),
    ] {
        let out = run(&args, "1 1 2 2\n");
        assert!(!out.status.success(), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}: {}", stdout(&out));
        assert!(stderr(&out).contains(needle), "{args:?}: {}", stderr(&out));
    }
    // Bad lines: an error each, the others answered, exit status 1.
    let (a, ok) = query(
        &pgm,
        &["--filter", "trilinear"],
        "3 3 1 5\n1 1 3 3\n1 2 3\n0.3 1 2 2\n",
    );
    assert!(!ok);
    assert_eq!(a.len(), 4);
    assert!(
        a[0]["error"].as_str().unwrap().contains("inverted"),
        "{}",
        a[0]
    );
    assert_eq!(a[1]["filter"], "trilinear");
    assert_eq!(
        (a[2]["line"].as_u64(), a[3]["line"].as_u64()),
        (Some(3), Some(4))
    );
    let (a, ok) = query(&pgm, &["--filter", "variance"], "2 2 2 4\n");
    assert!(!ok);
    assert!(
        a[0]["error"].as_str().unwrap().contains("zero area"),
        "{}",
        a[0]
    );
}

// ---------------------------------------------------------------------------------------------
// sat plan, sat query --plan

fn plan(args: &[&str]) -> Value {
    let mut all = vec!["plan"];
    all.extend_from_slice(args);
    let out = run(&all, "");
    assert!(out.status.success(), "sat plan {args:?}: {}", stderr(&out));
    serde_json::from_str(&stdout(&out)).expect("plan JSON")
}

#[test]
fn plan_prints_the_smallest_table_and_its_reasons() {
    let p = plan(&[
        "--size",
        "64x48",
        "--texel-bits",
        "8",
        "--box",
        "1x1..8x8",
        "--edge",
        "repeat",
    ]);
    for key in [
        "layout",
        "entry",
        "frac_bits",
        "lookup",
        "edge",
        "table_bytes",
        "bits_per_entry",
        "reads",
        "muls",
        "adds",
        "max_error",
        "mean",
        "repeat_within_period",
        "features",
        "rejected",
    ] {
        assert!(p.get(key).is_some(), "missing {key}: {p}");
    }
    assert_eq!(p["edge"], "repeat");
    // Boxes up to 8 x 8 on a 64 x 48 texture: Repeat within one period; a box wider than the
    // texture is not, and neither is another mode.
    assert_eq!(p["repeat_within_period"], true);
    for (b, edge) in [("1x1..65x8", "repeat"), ("1x1..8x8", "border")] {
        let q = plan(&[
            "--size",
            "64x48",
            "--texel-bits",
            "8",
            "--box",
            b,
            "--edge",
            edge,
        ]);
        assert_eq!(q["repeat_within_period"], false, "{b} {edge}: {q}");
    }
    // Boxes up to 8 x 8 texels at F = 8: area 2^22, mean 8 + 8 bits: the 32-bit mean.
    assert_eq!(p["mean"], "u32");
    assert_eq!(p["lookup"], "stable");
    assert_eq!(p["max_error"], 0.5);
    // Every rejected candidate that serves is at least as large as the plan's table.
    let bytes = p["table_bytes"].as_u64().unwrap();
    assert!(bytes < 64 * 48 * 4);
    for r in p["rejected"].as_array().unwrap() {
        let why = r["why"].as_str().unwrap();
        if let Some(n) = why.strip_prefix("larger: ") {
            let n: u64 = n.trim_end_matches(" bytes").parse().unwrap();
            assert!(n >= bytes, "{r} vs {bytes}");
        }
    }
    // Integer corners: the 4-read lookup; a read bound of 4 then keeps one field per corner.
    let p = plan(&[
        "--size",
        "64x48",
        "--texel-bits",
        "8",
        "--box",
        "1x1..64x48",
        "--frac-bits",
        "0",
        "--max-reads",
        "4",
    ]);
    assert_eq!(p["lookup"], "int4");
    assert_eq!(p["reads"], 4);
    assert!(
        ["flat", "packed"].contains(&p["layout"].as_str().unwrap()),
        "{p}"
    );
    // No plan: 16-read lookups under a bound of 4 reads.
    let out = run(
        &[
            "plan",
            "--size",
            "64x48",
            "--texel-bits",
            "8",
            "--box",
            "1x1..8x8",
            "--max-reads",
            "4",
        ],
        "",
    );
    assert!(!out.status.success());
    assert!(stderr(&out).contains("no plan"), "{}", stderr(&out));
}

#[test]
fn query_with_a_plan_answers_its_boxes_exactly_and_refuses_others() {
    let dir = temp_dir("plan");
    let img = Img::noise(40, 30, 1, 8, 11);
    let png = dir.join("p.png");
    img.write_png(&png);
    let f = 4;
    let p = plan(&[
        "--size",
        "40x30",
        "--texel-bits",
        "8",
        "--box",
        "0.5x0.5..6x6",
        "--edge",
        "repeat",
        "--frac-bits",
        "4",
        "--mean-bits",
        "12",
    ]);
    assert_eq!(p["lookup"], "stable", "{p}");
    let file = dir.join("plan.json");
    std::fs::write(&file, p.to_string()).unwrap();
    // Boxes within the facts (up to 6 x 6 texels, anywhere: Repeat lets them leave).
    let noise = Img::noise(400, 1, 1, 16, 12).data;
    let list: Vec<[i64; 4]> = noise
        .chunks_exact(4)
        .map(|q| {
            let x0 = i64::from(q[0]) % (60 << f) - (10 << f);
            let y0 = i64::from(q[1]) % (50 << f) - (10 << f);
            let w = (8 + i64::from(q[2]) % (88 + 1)).min(6 << f);
            let h = (8 + i64::from(q[3]) % (88 + 1)).min(6 << f);
            [x0, y0, x0 + w, y0 + h]
        })
        .collect();
    let input: String = list.iter().map(|&b| box_line(b, f) + "\n").collect();
    let (answers, ok) = query(&png, &["--plan", file.to_str().unwrap()], &input);
    assert!(ok, "{answers:?}");
    for (v, &b) in answers.iter().zip(&list) {
        check_answer(&img, v, b, f, 12, "repeat");
        assert!(v["reads"].as_u64().unwrap() <= p["reads"].as_u64().unwrap());
    }
    // Outside the facts: too large, too small.
    let (answers, ok) = query(
        &png,
        &["--plan", file.to_str().unwrap()],
        "0 0 7 1\n0 0 0.25 1\n",
    );
    assert!(!ok);
    assert!(answers[0]["error"]
        .as_str()
        .unwrap()
        .contains("largest box"));
    assert!(answers[1]["error"]
        .as_str()
        .unwrap()
        .contains("smallest box"));
    // A plan edited by hand, or for another image, is refused before any line is read.
    let mut edited = p.clone();
    edited["layout"] = json!("flat");
    std::fs::write(&file, edited.to_string()).unwrap();
    let out = run(
        &[
            "query",
            png.to_str().unwrap(),
            "--plan",
            file.to_str().unwrap(),
        ],
        "",
    );
    assert!(
        !out.status.success() && stderr(&out).contains("its layout is"),
        "{}",
        stderr(&out)
    );
    let other = plan(&["--size", "41x30", "--texel-bits", "8", "--box", "1x1..6x6"]);
    std::fs::write(&file, other.to_string()).unwrap();
    let out = run(
        &[
            "query",
            png.to_str().unwrap(),
            "--plan",
            file.to_str().unwrap(),
        ],
        "",
    );
    assert!(
        !out.status.success() && stderr(&out).contains("the plan is for 41x30"),
        "{}",
        stderr(&out)
    );
}
