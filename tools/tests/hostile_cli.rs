//! Hostile inputs against the `sat` binary: a catalogue of files and query lines a test bench
//! might feed it, each with its documented answer (`sat --help`, RESOURCES and EXIT STATUS):
//!
//! * a file that is not a usable image (empty, wrong magic, corrupt or truncated PNG/PNM, a
//!   zero side, unsupported samples, a header claiming more than the budget or than the file
//!   can hold, a directory, a missing file) is refused on stderr with exit status 1, nothing on
//!   stdout, and never by a signal;
//! * a query line that cannot be answered gets `{"error": ..., "line": N}` and the following
//!   lines are still answered; the exit status is then 1;
//! * a malformed `--max-memory`, `--max-work` or `--frac-bits` is a usage error (exit status 2);
//! * a `--plan` file that does not hold is refused with exit status 1.
//!
//! Each case checks the exit status (`Some(code)`: a signal has no code) and a stable substring
//! of the message. The binary is the debug or release build of the running test's profile (see
//! `common::example_bin`); every run is on small files or is refused before anything large is
//! allocated, so the whole file runs in seconds.

mod common;

use serde_json::Value;
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

fn run(args: &[&str], stdin: &[u8]) -> Output {
    let mut child = Command::new(sat_bin())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn sat");
    let mut input = child.stdin.take().expect("stdin");
    let stdin = stdin.to_vec();
    // Written from a thread: a large input must not block while sat fills its stdout pipe.
    let writer = std::thread::spawn(move || {
        // A run that fails before reading its input may close the pipe first: not an error.
        if let Err(e) = input.write_all(&stdin) {
            assert_eq!(
                e.kind(),
                std::io::ErrorKind::BrokenPipe,
                "writing stdin: {e}"
            );
        }
    });
    let out = child.wait_with_output().expect("wait for sat");
    writer.join().expect("stdin writer");
    out
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8(bytes.to_vec()).expect("utf-8 output")
}

/// Asserts that `out` ended with exit status `code` (not a signal) and that stderr contains
/// every needle.
#[track_caller]
fn expect_status(out: &Output, code: i32, needles: &[&str], what: &str) {
    let err = text(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(code),
        "{what}: status {:?}, stderr {err:?}",
        out.status
    );
    for n in needles {
        assert!(err.contains(n), "{what}: stderr {err:?} lacks {n:?}");
    }
}

/// A refused run: exit status 1, the needles on stderr, nothing on stdout.
#[track_caller]
fn expect_refused(out: &Output, needles: &[&str], what: &str) {
    expect_status(out, 1, needles, what);
    assert!(
        out.stdout.is_empty(),
        "{what}: refused but printed {:?}",
        text(&out.stdout)
    );
}

/// The JSON lines of stdout.
fn json_lines(out: &Output) -> Vec<Value> {
    text(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("bad JSON {l:?}: {e}")))
        .collect()
}

/// A fresh directory for one test, removed when the test passes.
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
    let dir = std::env::temp_dir().join(format!("texsat-hostile-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path.to_str().unwrap().to_string()
}

// ---------------------------------------------------------------------------------------------
// Fixtures

/// The 4 x 3 gray image of texels 1..=12 (row-major), as a binary PGM.
fn small_pgm() -> Vec<u8> {
    let mut b = b"P5\n4 3\n255\n".to_vec();
    b.extend(1..=12u8);
    b
}

/// The texels of [`small_pgm`] and their total.
const SMALL: [u8; 12] = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12];

/// CRC-32 (ISO-HDLC, as PNG uses), bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// One PNG chunk with its length and CRC.
fn chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
    let mut c = (data.len() as u32).to_be_bytes().to_vec();
    c.extend_from_slice(kind);
    c.extend_from_slice(data);
    let mut crc_input = kind.to_vec();
    crc_input.extend_from_slice(data);
    c.extend_from_slice(&crc32(&crc_input).to_be_bytes());
    c
}

/// A PNG whose IHDR claims `w x h` 8-bit gray texels, followed by an IDAT of `idat` (not
/// necessarily valid deflate data) and IEND.
fn png_with_header(w: u32, h: u32, idat: &[u8]) -> Vec<u8> {
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]); // 8 bits, gray, deflate, filter 0, no interlace
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(b"IDAT", idat));
    png.extend(chunk(b"IEND", &[]));
    png
}

/// A valid PNG of `w x h` samples of `color`, encoded by the `image` crate.
fn valid_png(w: u32, h: u32, color: image::ExtendedColorType, samples: &[u8]) -> Vec<u8> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(samples, w, h, color)
        .expect("encode PNG");
    out
}

// ---------------------------------------------------------------------------------------------
// Files

#[test]
fn hostile_image_files_are_refused_with_status_1() {
    let dir = temp_dir("files");
    let good_png = valid_png(8, 8, image::ExtendedColorType::L8, &[7u8; 64]);
    let mut corrupt_idat = good_png.clone();
    // The IDAT data starts after the signature (8), IHDR (25) and the IDAT length and type (8).
    for b in corrupt_idat.iter_mut().skip(8 + 25 + 8 + 2).take(6) {
        *b ^= 0x5A;
    }
    let mut bad_crc = good_png.clone();
    bad_crc[8 + 8 + 3] ^= 1; // a bit of the width, under the IHDR CRC
    let sixteen = [0u8; 4 * 4 * 2];
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        ("empty.pgm", vec![], &["the file is empty"]),
        ("empty.png", vec![], &["the file is empty"]),
        (
            "text.img",
            b"hello, not an image\n".to_vec(),
            &["not a PNG or PNM image"],
        ),
        (
            "gif.png",
            b"GIF89a\x01\x00\x01\x00\x00\x00\x00;".to_vec(),
            &["Gif images are not supported"],
        ),
        (
            "signature-only.png",
            b"\x89PNG\r\n\x1a\n".to_vec(),
            &["cannot read the PNG header"],
        ),
        (
            "garbage-after-signature.png",
            b"\x89PNG\r\n\x1a\nIHDRxxxxxxxxxxxxxxxxxxxx".to_vec(),
            &["cannot read the PNG header"],
        ),
        ("bad-crc.png", bad_crc, &["cannot read the PNG header"]),
        (
            "zero-width.png",
            png_with_header(0, 5, &[0; 16]),
            &["cannot read the PNG header"],
        ),
        (
            "truncated.png",
            good_png[..good_png.len() - 20].to_vec(),
            &["cannot decode the samples"],
        ),
        (
            "corrupt-idat.png",
            corrupt_idat,
            &["cannot decode the samples"],
        ),
        (
            "huge-header.png",
            png_with_header(200_000, 200_000, &[0; 16]),
            &["200000 x 200000", "above the memory budget", "--max-memory"],
        ),
        (
            "huge-header.pgm",
            b"P5\n200000 200000\n255\n".to_vec(),
            &["200000 x 200000", "above the memory budget", "--max-memory"],
        ),
        (
            "huge-header.ppm",
            b"P6\n100000 100000\n65535\n".to_vec(),
            &["above the memory budget", "--max-memory"],
        ),
        (
            "huge-header.pam",
            b"P7\nWIDTH 70000\nHEIGHT 70000\nDEPTH 4\nMAXVAL 255\nTUPLTYPE RGB_ALPHA\nENDHDR\n"
                .to_vec(),
            &["above the memory budget", "--max-memory"],
        ),
        (
            "zero-side.pgm",
            b"P5\n0 5\n255\n".to_vec(),
            &["0 x 5 texels"],
        ),
        (
            "truncated.pgm",
            [b"P5\n8 8\n255\n".as_slice(), &[1; 10]].concat(),
            &["truncated or corrupt", "64 bytes of raw samples"],
        ),
        (
            "truncated16.pgm",
            [b"P5\n4 4\n65535\n".as_slice(), &sixteen[..10]].concat(),
            &["truncated or corrupt", "32 bytes of raw samples"],
        ),
        (
            "truncated-ascii.pgm",
            b"P2\n2 2\n255\n1 2 3\n".to_vec(),
            &["cannot decode the samples"],
        ),
        (
            "maxval-zero.pgm",
            [b"P5\n2 2\n0\n".as_slice(), &[0; 4]].concat(),
            &["cannot read the PNM header"],
        ),
        (
            "maxval-1000.pgm",
            [b"P5\n2 2\n1000\n".as_slice(), &[0; 8]].concat(),
            &["maxval 1000 is not 255 or 65535"],
        ),
        (
            "maxval-too-big.pgm",
            [b"P5\n2 2\n70000\n".as_slice(), &[0; 8]].concat(),
            &["cannot read the PNM header"],
        ),
        (
            "negative-side.pgm",
            [b"P5\n-2 2\n255\n".as_slice(), &[0; 4]].concat(),
            &["cannot read the PNM header"],
        ),
        (
            "side-overflows.pgm",
            [b"P5\n99999999999 2\n255\n".as_slice(), &[0; 4]].concat(),
            &["cannot read the PNM header"],
        ),
        (
            "bad-magic.pgm",
            [b"P9\n2 2\n255\n".as_slice(), &[0; 4]].concat(),
            &["cannot read the PNM header"],
        ),
        (
            "depth-5.pam",
            [
                b"P7\nWIDTH 2\nHEIGHT 2\nDEPTH 5\nMAXVAL 255\nENDHDR\n".as_slice(),
                &[0; 20],
            ]
            .concat(),
            &["cannot read the PNM header"],
        ),
    ];
    for (name, bytes, needles) in &cases {
        let path = write(&dir, name, bytes);
        let what = format!("info {name}");
        let out = run(&["info", &path], b"");
        expect_refused(&out, needles, &what);
        assert!(
            text(&out.stderr).contains(&path),
            "{what}: the message names the file"
        );
        // The same refusal before a query reads any line.
        let out = run(&["query", &path], b"0 0 1 1\n");
        expect_refused(&out, needles, &format!("query {name}"));
    }
    // A directory and a missing file.
    let d = dir.to_str().unwrap();
    expect_refused(&run(&["info", d], b""), &["is a directory"], "a directory");
    let missing = dir.join("no-such-file.png");
    let out = run(&["query", missing.to_str().unwrap()], b"");
    expect_refused(&out, &["no-such-file.png"], "a missing file");
    // 16-bit images are not hostile: they are read as u16 texels.
    let mut pgm16 = b"P5\n2 1\n65535\n".to_vec();
    pgm16.extend_from_slice(&[0xFF, 0xFE, 0x00, 0x02]);
    let path = write(&dir, "ok16.pgm", &pgm16);
    let out = run(&["query", &path, "--frac-bits", "0"], b"0 0 2 1\n");
    expect_status(&out, 0, &[], "16-bit PGM");
    assert_eq!(json_lines(&out)[0]["sum"], (0xFFFE + 2).to_string());
    // The encoder takes 16-bit samples in native byte order.
    let values = [0x3412u16, 0xCDAB];
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
    let png16 = valid_png(1, 2, image::ExtendedColorType::L16, &bytes);
    let path = write(&dir, "ok16.png", &png16);
    let v = json_lines(&run(&["info", &path], b""));
    assert_eq!(v[0]["texel_type"], "u16");
    let total: u32 = values.iter().map(|&v| u32::from(v)).sum();
    assert_eq!(v[0]["totals"], total.to_string());
}

#[test]
fn a_raised_budget_does_not_let_a_small_file_claim_a_huge_image() {
    let dir = temp_dir("claims");
    let raise = ["--max-memory", "1T", "--max-work", "1T"];
    // The issue's 21-byte PGM: 40 GB of samples claimed, 21 bytes held.
    let pgm = write(&dir, "claim.pgm", b"P5\n200000 200000\n255\n");
    assert_eq!(std::fs::metadata(&pgm).unwrap().len(), 21);
    for cmd in ["info", "query"] {
        let out = run(&[&[cmd, pgm.as_str()][..], &raise].concat(), b"0 0 1 1\n");
        expect_refused(
            &out,
            &[
                "truncated or corrupt",
                "40000000000 bytes",
                "the file has 21 bytes",
            ],
            cmd,
        );
    }
    // A PNG: deflate expands at most 1033-fold, so a small IDAT cannot hold 200000 rows.
    let png = write(
        &dir,
        "claim.png",
        &png_with_header(200_000, 200_000, &[0; 64]),
    );
    let out = run(&[&["info", png.as_str()][..], &raise].concat(), b"");
    expect_refused(&out, &["truncated or corrupt", "deflated rows"], "png");
}

#[test]
fn the_issues_16384_square_png_is_refused_by_default_and_names_the_flags() {
    let dir = temp_dir("issue");
    // The header of the issue's 261 KB PNG of 16384 x 16384 8-bit texels; the budget is
    // checked on the header, before any sample is read.
    let png = write(&dir, "big.png", &png_with_header(16384, 16384, &[0; 64]));
    let out = run(&["info", &png, "--filter", "tent-exact"], b"");
    expect_refused(
        &out,
        &[
            "info --filter tent-exact on this 16384 x 16384 image",
            "needs about 6.25 GiB of memory",
            "order-2 table 2.00 GiB",
            "tent line tables 4.00 GiB",
            "above the memory budget of 1.00 GiB",
            "--max-memory 7G",
        ],
        "tent-exact",
    );
    let out = run(&["query", &png, "--filter", "ripmap"], b"0 0 1 1\n");
    expect_refused(
        &out,
        &[
            "query --filter ripmap on this 16384 x 16384 image",
            "above the memory budget",
            "--max-memory 2G",
            "texel operations",
            "above the work budget of 32.00G",
            "--max-work 57G",
        ],
        "ripmap",
    );
    // Raised budgets pass the check (and the file, a header without its rows, is then refused
    // as truncated: the budget let it through).
    for (filter, raise) in [
        ("tent-exact", ["--max-memory", "7G", "--max-work", "32G"]),
        ("ripmap", ["--max-memory", "2G", "--max-work", "57G"]),
    ] {
        let out = run(
            &[&["info", png.as_str(), "--filter", filter][..], &raise].concat(),
            b"",
        );
        let err = text(&out.stderr);
        assert!(!err.contains("budget"), "{filter}: {err}");
        expect_refused(&out, &["truncated or corrupt"], filter);
    }
}

/// Every command estimates something: a tiny budget refuses each, and the default accepts it.
#[test]
fn every_command_checks_its_budget() {
    let dir = temp_dir("every");
    let img = valid_png(
        16,
        12,
        image::ExtendedColorType::Rgb8,
        &(0..16 * 12 * 3)
            .map(|i| (i * 7 % 251) as u8)
            .collect::<Vec<_>>(),
    );
    let path = write(&dir, "rgb.png", &img);
    let p = path.as_str();
    let mut commands: Vec<Vec<&str>> = vec![
        vec!["info", p],
        vec!["info", p, "--checked"],
        vec!["info", p, "--entry", "u64"],
        vec!["info", p, "--layout", "packed"],
        vec!["info", p, "--layout", "tiled:4x4"],
        vec!["info", p, "--layout", "tiled:2x2/8x4+mod:20"],
        vec!["info", p, "--layout", "modular:box=4x4"],
        vec!["query", p],
        vec!["query", p, "--layout", "tiled:4x4"],
        vec!["query", p, "--layout", "modular:32"],
    ];
    for f in [
        "point",
        "mip",
        "trilinear",
        "ripmap",
        "dipmap",
        "dipmap-trilinear",
        "box",
        "tent",
        "tent-exact",
        "variance",
    ] {
        commands.push(vec!["info", p, "--filter", f]);
        commands.push(vec!["query", p, "--filter", f]);
    }
    for cmd in &commands {
        let what = cmd.join(" ");
        let out = run(
            &[cmd.as_slice(), &["--max-memory", "100"]].concat(),
            b"1 1 3 3\n",
        );
        expect_refused(
            &out,
            &["above the memory budget of 100 bytes", "--max-memory"],
            &what,
        );
        let out = run(
            &[cmd.as_slice(), &["--max-work", "100"]].concat(),
            b"1 1 3 3\n",
        );
        expect_refused(&out, &["above the work budget of 100", "--max-work"], &what);
    }
    // The default budgets accept them (`tests/cli.rs` runs every command at its default).
    for cmd in commands.iter().step_by(5) {
        expect_status(&run(cmd, b"1 1 3 3\n"), 0, &[], &cmd.join(" "));
    }
    // The flags are global: before the command name too.
    let out = run(&["--max-memory", "100", "info", p], b"");
    expect_refused(
        &out,
        &["above the memory budget"],
        "--max-memory before info",
    );
    expect_refused(
        &run(&["demo", "--max-memory", "1K"], b""),
        &[
            "demo (256 x 256 texels) needs about 320.00 KiB",
            "--max-memory",
        ],
        "demo",
    );
    // sat plan allocates nothing large: any budget will do.
    let out = run(
        &[
            "plan",
            "--size",
            "16x12",
            "--texel-bits",
            "8",
            "--box",
            "1x1..2x2",
            "--max-memory",
            "1",
            "--max-work",
            "1",
        ],
        b"",
    );
    expect_status(&out, 0, &[], "plan");
}

/// The estimate is at least what `sat info` reports the structures take, and exactly that for
/// the filters (their storage is all the estimate counts besides the decoded image): a budget
/// of the reported bytes is accepted, one byte less refused.
#[test]
fn estimates_hold_the_reported_memory() {
    let dir = temp_dir("reported");
    let samples: Vec<u8> = (0..37 * 23).map(|i| (i * 13 % 256) as u8).collect();
    let path = write(
        &dir,
        "g.png",
        &valid_png(37, 23, image::ExtendedColorType::L8, &samples),
    );
    let p = path.as_str();
    let info = |extra: &[&str]| -> Value {
        let out = run(&[&["info", p][..], extra].concat(), b"");
        expect_status(&out, 0, &[], &format!("{extra:?}"));
        json_lines(&out).remove(0)
    };
    let accepted = |extra: &[&str], budget: u64| {
        let b = budget.to_string();
        run(&[&["info", p, "--max-memory", &b][..], extra].concat(), b"")
            .status
            .code()
            == Some(0)
    };
    for f in ["mip", "ripmap", "dipmap", "tent", "tent-exact", "variance"] {
        let opts = ["--filter", f];
        let v = info(&opts);
        let storage = v["storage_bytes"].as_u64().unwrap();
        let texture = v["texture_bytes"].as_u64().unwrap();
        assert!(storage > 0, "{f}");
        assert!(
            accepted(&opts, texture + storage),
            "{f}: the reported bytes are accepted"
        );
        assert!(
            !accepted(&opts, texture + storage - 1),
            "{f}: one byte less is refused"
        );
    }
    for layout in ["flat", "packed", "tiled:4x4", "tiled:2x2/8x8", "modular:18"] {
        let opts = ["--layout", layout];
        let v = info(&opts);
        let table = v["table_bytes"].as_u64().unwrap();
        let texture = samples.len() as u64;
        assert!(
            !accepted(&opts, texture + table - 1),
            "{layout}: the estimate holds at least the texture and the table"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Query lines

/// What a query line must give.
enum Want {
    /// `{"sum": S, ...}`.
    Sum(String),
    /// `{"error": "...needle...", "line": N}`.
    Error(&'static str),
}

/// Runs `lines` (one input line each, joined by `'\n'`) and checks each answer in order;
/// skipped lines (blank, comments) have no entry in `want`.
#[track_caller]
fn check_lines(args: &[&str], input: &[u8], want: &[(usize, Want)]) {
    let out = run(args, input);
    let any_error = want.iter().any(|(_, w)| matches!(w, Want::Error(_)));
    expect_status(&out, if any_error { 1 } else { 0 }, &[], &args.join(" "));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), want.len(), "{lines:?}");
    for (v, (line, w)) in lines.iter().zip(want) {
        match w {
            Want::Sum(s) => assert_eq!(v["sum"], *s, "line {line}: {v}"),
            Want::Error(needle) => {
                let msg = v["error"]
                    .as_str()
                    .unwrap_or_else(|| panic!("line {line}: no error in {v}"));
                assert!(
                    msg.contains(needle),
                    "line {line}: {msg:?} lacks {needle:?}"
                );
                assert_eq!(v["line"], *line as u64, "{v}");
            }
        }
    }
}

#[test]
fn hostile_query_lines_get_error_lines_and_the_rest_are_answered() {
    let dir = temp_dir("lines");
    let path = write(&dir, "s.pgm", &small_pgm());
    let total: u32 = SMALL.iter().map(|&v| u32::from(v)).sum();
    let mut input: Vec<u8> = Vec::new();
    let mut want = Vec::new();
    let mut line = 0;
    let mut add = |input: &mut Vec<u8>, text: &[u8], w: Option<Want>| {
        input.extend_from_slice(text);
        input.push(b'\n');
        line += 1;
        if let Some(w) = w {
            want.push((line, w));
        }
    };
    use Want::{Error as E, Sum as S};
    add(&mut input, b"0 0 4 3", Some(S(total.to_string())));
    for bad in [
        "nan 0 1 1",
        "NaN NaN NaN NaN",
        "inf 0 1 1",
        "-inf 0 1 1",
        "0 0 infinity 1",
        "1e3 0 1 1",
        "0x10 0 1 1",
        "1.2.3 0 1 1",
        "+-1 0 1 1",
        "0 0 1 1_000",
        "\u{0661} 0 1 1",
        ". 0 1 1",
        "- 0 1 1",
    ] {
        add(&mut input, bad.as_bytes(), Some(E("not a decimal number")));
    }
    add(&mut input, b"\0 0 1 1", Some(E("not a decimal number")));
    add(&mut input, b"", None);
    add(&mut input, b"# a comment 1 2 3", None);
    add(&mut input, b"   \t  ", None);
    add(
        &mut input,
        b"1",
        Some(E("expected 4 numbers \"x0 y0 x1 y1\", got 1 field")),
    );
    add(&mut input, b"1 2 3 4 5 6 7 8", Some(E("got 8 fields")));
    add(&mut input, b"3 0 1 1", Some(E("inverted")));
    add(&mut input, b"0 2 1 1", Some(E("inverted")));
    add(&mut input, b"1 1 1 1", Some(S("0".into())));
    add(
        &mut input,
        b"0.001 0 1 1",
        Some(E("not a multiple of 2^-8")),
    );
    add(
        &mut input,
        b"99999999999999999999999999999 0 1 1",
        Some(E("out of range")),
    );
    // 2^55 texels is 2^63 at F = 8: one past i64.
    add(
        &mut input,
        b"0 0 36028797018963968 1",
        Some(E("out of range")),
    );
    add(&mut input, b"\xFF\xFE 0 1 1", Some(E("not valid UTF-8")));
    add(&mut input, b"0 0 1 1\r", Some(S("1".into())));
    // Lines at and past the 4096-byte bound: the longer one is refused, the next answered.
    let mut at_bound = b"0 0 2 1".to_vec();
    at_bound.resize(4096, b' ');
    add(&mut input, &at_bound, Some(S("3".into())));
    let mut past = at_bound.clone();
    past.push(b' ');
    add(&mut input, &past, Some(E("line is longer than 4096 bytes")));
    add(
        &mut input,
        "7 ".repeat(1 << 20).as_bytes(),
        Some(E("longer than 4096")),
    );
    add(&mut input, b"0 0 4 1", Some(S("10".into())));
    // Ends without a newline, 4 MB long.
    input.extend(std::iter::repeat_n(b'9', 4 << 20));
    line += 1;
    want.push((line, E("longer than 4096")));
    check_lines(&["query", &path], &input, &want);
}

#[test]
fn every_filter_answers_hostile_lines_with_error_lines() {
    let dir = temp_dir("filters");
    let path = write(&dir, "s.pgm", &small_pgm());
    let input = b"1 1 3 3\nnan 0 1 1\n3 0 1 1\n1 2 3 4 5\n99999999999999999999 0 1 1\n0 0 1 1\n";
    for f in [
        "point",
        "mip",
        "trilinear",
        "ripmap",
        "dipmap",
        "dipmap-trilinear",
        "tent",
        "tent-exact",
        "variance",
    ] {
        for edge in ["clamp", "mirror"] {
            let what = format!("{f} {edge}");
            let out = run(&["query", &path, "--filter", f, "--edge", edge], input);
            expect_status(&out, 1, &[], &what);
            let lines = json_lines(&out);
            assert_eq!(lines.len(), 6, "{what}: {lines:?}");
            for i in [0, 5] {
                assert!(
                    lines[i]["value"].is_string(),
                    "{what}: line {}: {}",
                    i + 1,
                    lines[i]
                );
            }
            for (i, needle) in [
                (1, "not a decimal number"),
                (2, "inverted"),
                (3, "expected 4 numbers"),
                (4, "out of range"),
            ] {
                let msg = lines[i]["error"].as_str().unwrap_or_default();
                assert!(msg.contains(needle), "{what}: line {}: {}", i + 1, lines[i]);
                assert_eq!(lines[i]["line"], i as u64 + 1);
            }
        }
    }
}

#[test]
fn millions_of_periods_are_exact_or_a_typed_error() {
    let dir = temp_dir("periods");
    let path = write(&dir, "s.pgm", &small_pgm());
    let total = SMALL.iter().map(|&v| u128::from(v)).sum::<u128>();
    // Whole periods of the 4 x 3 texture: the sum is periods x periods x total, under repeat
    // and mirror (whose period 8 x 6 holds 4 copies) alike.
    let boxes: [(i64, i64, i64, i64); 3] = [
        (-20_000_000, -15_000_000, 20_000_000, 15_000_000),
        (-2_000_000_000, -1_500_000_000, 2_000_000_000, 1_500_000_000),
        // 2^54 - 1 periods across, at the edge of i64 at F = 8.
        (-(1 << 55), 0, (1 << 55) - 4, 3),
    ];
    let sums: Vec<String> = boxes
        .iter()
        .map(|&(x0, y0, x1, y1)| {
            let px = ((x1 - x0) / 4) as u128;
            let py = ((y1 - y0) / 3) as u128;
            (px * py * total).to_string()
        })
        .collect();
    let input: String = boxes
        .iter()
        .map(|(x0, y0, x1, y1)| format!("{x0} {y0} {x1} {y1}\n"))
        .collect();
    for edge in ["repeat", "mirror"] {
        // u64 entries accumulate in i128: every box is exact.
        let want: Vec<(usize, Want)> = sums
            .iter()
            .enumerate()
            .map(|(i, s)| (i + 1, Want::Sum(s.clone())))
            .collect();
        check_lines(
            &["query", &path, "--edge", edge, "--entry", "u64"],
            input.as_bytes(),
            &want,
        );
        // u32 entries accumulate in i64: a sum that needs more is a typed error line.
        let out = run(&["query", &path, "--edge", edge], input.as_bytes());
        expect_status(&out, 1, &[], edge);
        for v in json_lines(&out) {
            let msg = v["error"].as_str().unwrap_or_else(|| panic!("{edge}: {v}"));
            assert!(msg.contains("accumulator needs 65 bits"), "{edge}: {msg}");
        }
        // The integer lookup takes i32 corners: the first two boxes, then a typed error.
        let out = run(
            &[
                "query",
                &path,
                "--edge",
                edge,
                "--entry",
                "u64",
                "--frac-bits",
                "0",
            ],
            input.as_bytes(),
        );
        let lines = json_lines(&out);
        assert_eq!(lines[0]["sum"], sums[0]);
        assert_eq!(lines[1]["sum"], sums[1]);
        let msg = lines[2]["error"].as_str().unwrap_or_default();
        assert!(
            msg.contains("outside the integer lookup's range (i32)"),
            "{msg}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Flags

#[test]
fn malformed_flag_values_are_usage_errors() {
    let dir = temp_dir("flags");
    let path = write(&dir, "s.pgm", &small_pgm());
    let p = path.as_str();
    for (flag, value, needle) in [
        ("--max-memory", "", "not an amount"),
        ("--max-memory", "abc", "not an amount"),
        ("--max-memory", "-5", "not an amount"),
        ("--max-memory", "G", "not an amount"),
        ("--max-memory", "1.5G", "unknown suffix"),
        ("--max-memory", "1X", "unknown suffix"),
        ("--max-memory", "1 G", "unknown suffix"),
        ("--max-memory", "0", "at least 1"),
        ("--max-memory", "0M", "at least 1"),
        ("--max-memory", "99999999999999999999", "too large"),
        ("--max-memory", "16777216T", "too large"),
        ("--max-work", "lots", "not an amount"),
        ("--max-work", "0", "at least 1"),
        ("--max-work", "1e9", "unknown suffix"),
        ("--frac-bits", "25", "25 is not in 0..=24"),
        ("--frac-bits", "-1", "--frac-bits"),
        ("--frac-bits", "4294967296", "--frac-bits"),
        ("--frac-bits", "eight", "--frac-bits"),
        ("--mean-bits", "121", "--mean-bits"),
    ] {
        let what = format!("{flag} {value:?}");
        let arg = format!("{flag}={value}");
        let out = run(&["query", p, &arg], b"0 0 1 1\n");
        expect_status(&out, 2, &[flag, needle], &what);
        assert!(out.stdout.is_empty(), "{what}");
    }
    // Well-formed amounts, in every spelling.
    for value in ["1073741824", "1G", "2g", "512M", "512MiB", "4096KB", "1T"] {
        let out = run(&["query", p, "--max-memory", value], b"0 0 1 1\n");
        expect_status(&out, 0, &[], value);
        let out = run(&["query", p, "--max-work", value], b"0 0 1 1\n");
        expect_status(&out, 0, &[], value);
    }
}

// ---------------------------------------------------------------------------------------------
// --plan files

#[test]
fn corrupt_plan_files_are_refused() {
    let dir = temp_dir("plans");
    let image = write(&dir, "s.pgm", &small_pgm());
    let out = run(
        &[
            "plan",
            "--size",
            "4x3",
            "--texel-bits",
            "8",
            "--box",
            "1x1..2x2",
        ],
        b"",
    );
    expect_status(&out, 0, &[], "sat plan");
    let good: Value = serde_json::from_slice(&out.stdout).unwrap();
    let good_path = write(&dir, "good.json", &out.stdout);
    let out = run(&["query", &image, "--plan", &good_path], b"1 1 2 2\n");
    expect_status(&out, 0, &[], "the good plan");
    assert_eq!(json_lines(&out)[0]["sum"], "6");

    let edit = |f: &dyn Fn(&mut Value)| -> Vec<u8> {
        let mut v = good.clone();
        f(&mut v);
        serde_json::to_vec(&v).unwrap()
    };
    let deep = format!("{}{}", "[".repeat(100_000), "]".repeat(100_000));
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty", vec![], "not JSON"),
        ("not-json", b"layout: flat".to_vec(), "not JSON"),
        ("not-utf8", b"{\"layout\": \"\xFF\"}".to_vec(), "not UTF-8"),
        ("deep", deep.into_bytes(), "not JSON"),
        (
            "too-large",
            vec![b' '; (1 << 20) + 1],
            "larger than 1048576 bytes",
        ),
        ("no-facts", b"{}".to_vec(), "missing or invalid facts"),
        (
            "frac-bits-30",
            edit(&|v| v["facts"]["frac_bits"] = 30.into()),
            "facts.frac_bits (above 24)",
        ),
        (
            "frac-bits-wraps",
            edit(&|v| v["facts"]["frac_bits"] = 4_294_967_304u64.into()),
            "facts.frac_bits (above 24)",
        ),
        (
            "frac-bits-negative",
            edit(&|v| v["facts"]["frac_bits"] = (-1).into()),
            "missing or invalid facts.frac_bits",
        ),
        (
            "frac-bits-fraction",
            edit(&|v| v["facts"]["frac_bits"] = 8.5.into()),
            "missing or invalid facts.frac_bits",
        ),
        (
            "mean-bits-33",
            edit(&|v| v["facts"]["mean_bits"] = 33.into()),
            "facts.mean_bits (above 32)",
        ),
        (
            "texel-bits-wraps",
            edit(&|v| v["facts"]["texel_bits"] = (1u64 << 32 | 8).into()),
            "facts.texel_bits",
        ),
        (
            "size-overflows",
            edit(&|v| v["facts"]["size"] = "99999999999999999999x3".into()),
            "is not a whole number",
        ),
        (
            "size-zero",
            edit(&|v| v["facts"]["size"] = "0x0".into()),
            "no plan for its facts",
        ),
        (
            "box-out-of-range",
            edit(&|v| v["facts"]["box"] = "1x1..99999999999999999999999x1".into()),
            "out of range",
        ),
        (
            "edge-unknown",
            edit(&|v| v["facts"]["edge"] = "wrap".into()),
            "missing or invalid facts.edge",
        ),
        (
            "layout-edited",
            edit(&|v| v["layout"] = "flat".into()),
            "edited by hand",
        ),
        (
            "other-image",
            edit(&|v| v["facts"]["size"] = "5x3".into()),
            "the plan is for 5x3",
        ),
    ];
    for (name, bytes, needle) in &cases {
        let path = write(&dir, &format!("{name}.json"), bytes);
        let out = run(&["query", &image, "--plan", &path], b"1 1 2 2\n");
        expect_refused(&out, &[needle], name);
    }
    let d = dir.to_str().unwrap();
    expect_refused(
        &run(&["query", &image, "--plan", d], b""),
        &["--plan", "is a directory"],
        "a directory",
    );
    let missing = dir.join("missing.json");
    expect_refused(
        &run(&["query", &image, "--plan", missing.to_str().unwrap()], b""),
        &["--plan", "missing.json"],
        "a missing plan",
    );
}

// ---------------------------------------------------------------------------------------------
// The report's image scenes

#[test]
fn the_report_refuses_hostile_image_scenes_before_decoding() {
    let report = common::example_bin("report", "REPORT_BIN", &[]);
    let dir = temp_dir("report");
    let out_dir = dir.join("out");
    let run_report = |scene: &str, extra: &[&str]| -> Output {
        Command::new(&report)
            .args(["--quick", "--no-stability", "--scene", scene, "--out"])
            .arg(&out_dir)
            .args(extra)
            .output()
            .expect("run report")
    };
    let huge = write(&dir, "huge.pgm", b"P5\n200000 200000\n255\n");
    let out = run_report(&huge, &[]);
    expect_status(
        &out,
        1,
        &["200000 x 200000", "above the memory budget", "--max-memory"],
        "report huge",
    );
    let out = run_report(&huge, &["--max-memory", "8T", "--max-work", "100T"]);
    expect_status(&out, 1, &["truncated or corrupt"], "report huge, raised");
    let small = write(&dir, "s.pgm", &small_pgm());
    let out = run_report(&small, &["--max-memory", "1K"]);
    expect_status(
        &out,
        1,
        &[
            "report --scene on this 4 x 3 image",
            "above the memory budget of 1.00 KiB",
        ],
        "report small, 1K",
    );
    let out = run_report(&write(&dir, "e.png", b""), &[]);
    expect_status(&out, 1, &["the file is empty"], "report empty");
    assert!(!out_dir.join("report.md").exists(), "nothing written");
}

/// A palette PNG whose PLTE chunk is 4 bytes long (not a multiple of 3): the `png` crate panics
/// while decoding it (image-rs/image-png#694, found by the `cli_image` fuzz target); `sat`
/// turns that into a message and exit status 1, with nothing else on stderr.
#[test]
fn a_png_that_makes_the_decoder_panic_is_refused() {
    let dir = temp_dir("plte");
    let ihdr = [0, 0, 0, 2, 0, 0, 0, 2, 8, 3, 0, 0, 0]; // 2 x 2, 8-bit palette
    let raw = [0u8, 0, 0, 0, 0, 0];
    let mut idat = Vec::new();
    {
        let mut enc = flate2_like_store(&raw);
        idat.append(&mut enc);
    }
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(b"PLTE", &[10, 20, 30, 40]));
    png.extend(chunk(b"IDAT", &idat));
    png.extend(chunk(b"IEND", &[]));
    let path = write(&dir.0, "plte.png", &png);
    for cmd in [vec!["info", path.as_str()], vec!["query", path.as_str()]] {
        let out = run(&cmd, b"0 0 1 1\n");
        expect_status(&out, 1, &["plte.png", "corrupt image data"], "bad PLTE");
        assert!(
            !text(&out.stderr).contains("panicked"),
            "{}",
            text(&out.stderr)
        );
    }
}

/// A zlib stream holding `data` in one stored (uncompressed) block: what an IDAT chunk needs,
/// without a compressor.
fn flate2_like_store(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01, 0x01];
    let len = data.len() as u16;
    out.extend(len.to_le_bytes());
    out.extend((!len).to_le_bytes());
    out.extend(data);
    // Adler-32 of the data, big-endian.
    let (mut a, mut b) = (1u32, 0u32);
    for &d in data {
        a = (a + u32::from(d)) % 65521;
        b = (b + a) % 65521;
    }
    out.extend(((b << 16) | a).to_be_bytes());
    out
}
