//! `sat demo`: a guided tour on a generated texture. Every sum it prints is checked against a
//! direct texel-by-texel integral; a mismatch makes the demo fail (exit status 1).

use crate::num::{fixed_decimal, grouped};
use fixed::types::I24F8;
use std::io::Write;
use texsat::width::{self, bits_of};
use texsat::{
    Border, ClampToEdge, EdgeMode, Form, MirroredRepeat, Paper, Rect, Repeat, Sat, Shortcut,
    Stable, Tally, Texture,
};
use texsat_tools::budget::{self, Budget, Estimate};

const W: usize = 256;
const H: usize = 256;
/// Fractional bits of the demo's fractional corners (`I24F8`).
const F: u32 = 8;
/// Fractional bits of the means the demo computes.
const G: u32 = 24;

/// A checkerboard of 32-texel squares (0 or 128) plus a left-to-right ramp (0 to 127).
fn texels() -> Vec<u8> {
    let mut t = Vec::with_capacity(W * H);
    for y in 0..H {
        for x in 0..W {
            let check = if (x / 32 + y / 32) % 2 == 1 { 128 } else { 0 };
            t.push((check + x / 2) as u8);
        }
    }
    t
}

/// The texel of the extended texture under a boundary mode, by its name (`None`: zero).
fn ext(i: i64, n: usize, mode: &str) -> Option<usize> {
    let n = n as i64;
    let j = match mode {
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
        _ => unreachable!(),
    };
    Some(j as usize)
}

/// The integral over a box given in raw units (`value * 2^f`), scaled by `2^2f`, summed texel by
/// texel over the extended texture: the reference every lookup below is checked against.
fn direct(t: &[u8], raw: [i64; 4], f: u32, mode: &str) -> u128 {
    let [x0, y0, x1, y1] = raw;
    let overlap = |lo: i64, hi: i64, i: i64| (hi.min((i + 1) << f) - lo.max(i << f)).max(0);
    let mut sum = 0u128;
    for j in (y0 >> f)..=((y1 - 1) >> f) {
        let oy = overlap(y0, y1, j);
        for i in (x0 >> f)..=((x1 - 1) >> f) {
            let ox = overlap(x0, x1, i);
            if let (Some(tx), Some(ty)) = (ext(i, W, mode), ext(j, H, mode)) {
                sum += u128::from(t[ty * W + tx]) * (ox * oy) as u128;
            }
        }
    }
    sum
}

/// `raw / 2^f` as an exact signed decimal.
fn coord(raw: i64, f: u32) -> String {
    let s = fixed_decimal(u128::from(raw.unsigned_abs()), f);
    if raw < 0 {
        format!("-{s}")
    } else {
        s
    }
}

/// One lookup of the tour.
struct Row {
    what: String,
    mode: &'static str,
    lookup: String,
    sum: String,
    mean: f64,
    tally: Tally,
    ok: bool,
}

/// Looks up one box (integer corners when `f = 0`, `I24F8` corners when `f = 8`), takes its mean
/// and checks the sum.
fn lookup<M: EdgeMode, Fm: Form>(
    sat: &Sat<'_, u32>,
    t: &[u8],
    raw: [i64; 4],
    f: u32,
    mode: M,
    form: Fm,
) -> Result<Row, String> {
    let mut tally = Tally::new();
    let sum = if f == 0 {
        let [x0, y0, x1, y1] = raw.map(|v| v as i32);
        sat.box_sum_int(&Rect::new(x0, y0, x1, y1), mode, &mut tally)
    } else {
        let [x0, y0, x1, y1] = raw.map(|v| I24F8::from_bits(v as i32));
        sat.box_sum(&Rect::new(x0, y0, x1, y1), form, mode, &mut tally)
    }
    .map_err(|e| format!("demo lookup failed: {e}"))?
    .to_u128();
    let mean = sum
        .mean_rounded(0, G, &mut tally)
        .map_err(|e| format!("demo mean failed: {e}"))?;
    let reference = direct(t, raw, f, mode.kind().name());
    let c = |v| coord(v, f);
    Ok(Row {
        what: format!(
            "[{}, {}) x [{}, {})",
            c(raw[0]),
            c(raw[2]),
            c(raw[1]),
            c(raw[3])
        ),
        mode: mode.kind().name(),
        lookup: if f == 0 {
            "int4".to_string()
        } else {
            format!("{} F={f}", form.kind().name())
        },
        sum: fixed_decimal(sum.sum(), 2 * f),
        mean: mean as f64 / (1u64 << G) as f64,
        tally,
        ok: sum.sum() == reference,
    })
}

/// `v` in units of `2^-f` from a decimal `x` that is exactly representable.
fn r(x: f64) -> i64 {
    let v = x * f64::from(1u32 << F);
    assert!(
        v.fract() == 0.0,
        "demo coordinate {x} is not a multiple of 2^-{F}"
    );
    v as i64
}

fn cost(t: &Tally) -> String {
    format!("{:>3} {:>4} {:>4} {:>4}", t.reads, t.muls, t.divs, t.adds)
}

/// Appends a formatted line to the demo's text (printed at the end in one write).
macro_rules! say {
    ($out:ident) => {
        $out.push('\n')
    };
    ($out:ident, $($arg:tt)*) => {{
        $out.push_str(&format!($($arg)*));
        $out.push('\n');
    }};
}

/// The demo's memory and work, checked against `budget` like every other command's.
fn estimate() -> Estimate {
    let mut est = Estimate::new(format!("demo ({W} x {H} texels)"));
    est.push(budget::image(W, H, 1, 1));
    est.push_sized(budget::flat::<u32, 1>(W, H));
    est
}

pub fn run(budget: &Budget) -> Result<bool, String> {
    estimate().check(budget)?;
    let mut out = String::new();
    let t = texels();
    let texture = Texture::<u8>::new(&t, W, H).map_err(|e| e.to_string())?;
    let entries = Sat::<u32>::entries_needed(W, H).map_err(|e| e.to_string())?;
    let mut storage = budget::zeroed(entries, 0u32, "demo table")?;
    let sat = Sat::build(&texture, &mut storage).map_err(|e| e.to_string())?;

    let b = 8u32;
    let worst = width::worst_case_total(b, W, H);
    let total = u128::from(sat.total()[0]);
    let tex_bytes = W * H;
    let heading = "texsat demo: summed-area tables (Crow, SIGGRAPH 1984)";
    say!(out, "{heading}\n{}\n", "=".repeat(heading.len()));
    say!(
        out,
        "Texture   {W} x {H} texels, 1 channel of {b} bits (u8): {} bytes",
        grouped(tex_bytes as u128)
    );
    say!(out, "          a checkerboard of 32-texel squares (0 or 128) plus a left-to-right ramp (0..127)");
    say!(out);
    say!(
        out,
        "Table     one u32 entry per texel: {} entries, {} bytes ({}x the texture)",
        grouped(sat.entries().len() as u128),
        grouped(sat.table_bytes() as u128),
        sat.table_bytes() / tex_bytes
    );
    say!(
        out,
        "          entry (i, j) = sum of the texels (i', j') with i' <= i and j' <= j"
    );
    say!(out);
    let need = width::entry_bits_worst_case(b, W, H);
    say!(
        out,
        "Width     worst case: 255 x {W} x {H} = {} needs {need} bits (Crow: 24 bits for 256 x 256)",
        grouped(worst)
    );
    say!(
        out,
        "          textbook bound b + ceil(log2(w h)) = {} bits; Sat::build proves the exact one",
        width::entry_bits_naive(b, W, H)
    );
    say!(
        out,
        "          this texture sums to {} ({} bits); packed {need}-bit entries would take {} bytes",
        grouped(total),
        bits_of(total),
        grouped((W * H * need as usize / 8) as u128)
    );
    say!(
        out,
        "          16-read lookups at F = {F} accumulate in i64 (63 value bits): paper needs {}, stable {}",
        texsat::FormKind::Paper.acc_bits(sat.total_bits(), F),
        texsat::FormKind::Stable.acc_bits(sat.total_bits(), F)
    );
    say!(out);

    // The tour: an interior box with integer corners, the same region with fractional corners in
    // both forms, a box on the zero row and column, a box over the left edge in every mode, and a
    // wide box over several periods.
    let int_box = [40, 40, 72, 72];
    let frac_box = [r(40.5), r(40.75), r(71.25), r(72.0)];
    let corner_box = [0, 0, 16, 16];
    let edge_box = [r(-8.5), r(100.0), r(8.5), r(116.25)];
    let wide_box = [r(-300.0), r(10.5), r(600.0), r(20.0)];
    let rows = vec![
        lookup(&sat, &t, int_box, 0, Border, Paper)?,
        lookup(&sat, &t, frac_box, F, Border, Paper)?,
        lookup(&sat, &t, frac_box, F, Border, Stable)?,
        lookup(&sat, &t, corner_box, 0, Border, Paper)?,
        lookup(&sat, &t, edge_box, F, Border, Paper)?,
        lookup(&sat, &t, edge_box, F, ClampToEdge, Paper)?,
        lookup(&sat, &t, edge_box, F, Repeat, Paper)?,
        lookup(&sat, &t, edge_box, F, MirroredRepeat, Paper)?,
        lookup(&sat, &t, wide_box, F, Repeat, Paper)?,
    ];
    say!(
        out,
        "Lookups   sum: the exact integral over the box (a multiple of 2^-2F, all digits shown)"
    );
    say!(
        out,
        "          mean: sum / area, computed to 2^-{G} and shown to 4 places"
    );
    say!(
        out,
        "          costs: Tally over the lookup and the mean (reads, multiplies, divides, adds)"
    );
    say!(
        out,
        "          check: the sum equals a direct texel-by-texel integral"
    );
    say!(out);
    say!(
        out,
        "  {:<30} {:<7} {:<10} {:>15} {:>9}  {:>3} {:>4} {:>4} {:>4}  check",
        "box [x0, x1) x [y0, y1)",
        "mode",
        "lookup",
        "sum",
        "mean",
        "rd",
        "mul",
        "div",
        "add"
    );
    let mut all_ok = true;
    let mut last_what = String::new();
    for row in &rows {
        let what = if row.what == last_what {
            "  (same box)".to_string()
        } else {
            row.what.clone()
        };
        last_what = row.what.clone();
        say!(
            out,
            "  {:<30} {:<7} {:<10} {:>15} {:>9.4}  {}  {}",
            what,
            row.mode,
            row.lookup,
            row.sum,
            row.mean,
            cost(&row.tally),
            if row.ok { "ok" } else { "MISMATCH" }
        );
        all_ok &= row.ok;
    }
    say!(out);
    say!(out, "          The integer box reads 4 entries; its fractional neighbour reads 16, four per corner.");
    say!(out, "          A corner on row 0 or column 0 of the corner function costs no read (the corner box");
    say!(
        out,
        "          reads 1). Boxes over the edge under clamp, repeat and mirror have no in-range"
    );
    say!(
        out,
        "          equivalent and take the weighted path (up to 9 reads per corner); whole periods"
    );
    say!(
        out,
        "          fold into the weights, so the wide box, 3.5 periods across, costs no more."
    );
    say!(out);

    // Crow's shortcut for large footprints.
    let big = [r(20.375), r(15.125), r(220.625), r(235.875)];
    let [x0, y0, x1, y1] = big.map(|v| I24F8::from_bits(v as i32));
    let big_rect = Rect::new(x0, y0, x1, y1);
    let tolerance = 4u64;
    let shortcut = Shortcut::for_tolerance(b, tolerance, 1);
    let mut exact_tally = Tally::new();
    let exact = sat
        .box_mean_shortcut(
            &big_rect,
            Paper,
            Border,
            &Shortcut::with_min_side(u64::MAX),
            G,
            &mut exact_tally,
        )
        .map_err(|e| e.to_string())?;
    let mut short_tally = Tally::new();
    let short = sat
        .box_mean_shortcut(&big_rect, Paper, Border, &shortcut, G, &mut short_tally)
        .map_err(|e| e.to_string())?;
    let to_f = |m: u128| m as f64 / (1u64 << G) as f64;
    let (me, ms) = (to_f(exact.means[0].into()), to_f(short.means[0].into()));
    let (bw, bh) = (
        (big[2] - big[0]) as f64 / 256.0,
        (big[3] - big[1]) as f64 / 256.0,
    );
    let bound = Shortcut::error_bound(b, bw, bh);
    say!(
        out,
        "Shortcut  Crow 2.2: for large footprints, skip the corner interpolation (4 reads, not 16)"
    );
    say!(
        out,
        "          box [{}, {}) x [{}, {}), {bw} x {bh} texels; a tolerance of {tolerance} texel units",
        coord(big[0], F),
        coord(big[2], F),
        coord(big[1], F),
        coord(big[3], F)
    );
    say!(
        out,
        "          allows it for sides >= {} texels (bound 2m / (s - 1), m = 255)",
        shortcut.min_side()
    );
    say!(
        out,
        "          exact     mean {me:>9.4}  cost {}  (shortcut: {})",
        cost(&exact_tally),
        exact.shortcut
    );
    say!(
        out,
        "          shortcut  mean {ms:>9.4}  cost {}  (shortcut: {})",
        cost(&short_tally),
        short.shortcut
    );
    let err = (me - ms).abs();
    let within = err <= bound + 1.0 / (1u64 << G) as f64;
    say!(
        out,
        "          |error| = {err:.4} <= proven bound m (1/(W-1) + 1/(H-1)) = {bound:.4}: {}",
        if within { "ok" } else { "VIOLATED" }
    );
    all_ok &= within && short.shortcut && !exact.shortcut;
    say!(out);

    // Crow's cost table against what the tallies above counted (interior boxes, one channel).
    let (int_t, paper_t, stable_t) = (&rows[0].tally, &rows[1].tally, &rows[2].tally);
    let mult = |t: &Tally| format!("{} ({} mul + {} div)", t.multiplicative(), t.muls, t.divs);
    say!(
        out,
        "Costs     per filtered sample, one channel: Crow (1984, 2.2) and this crate's tallies"
    );
    say!(
        out,
        "  {:<38} {:>5}  {:<22} {:>8}  {:>9}",
        "",
        "reads",
        "multiplicative",
        "additive",
        "bits read"
    );
    say!(
        out,
        "  {:<38} {:>5}  {:<22} {:>8}",
        "Crow: no interpolation",
        4,
        "2",
        3
    );
    say!(
        out,
        "  {:<38} {:>5}  {:<22} {:>8}  {:>9}",
        "texsat int4 + mean (box_sum_int)",
        int_t.reads,
        mult(int_t),
        int_t.adds,
        int_t.bits_read
    );
    say!(
        out,
        "  {:<38} {:>5}  {:<22} {:>8}",
        "Crow: interpolated corners",
        16,
        "14",
        27
    );
    say!(
        out,
        "  {:<38} {:>5}  {:<22} {:>8}  {:>9}",
        "texsat paper + mean (box_sum, Paper)",
        paper_t.reads,
        mult(paper_t),
        paper_t.adds,
        paper_t.bits_read
    );
    say!(
        out,
        "  {:<38} {:>5}  {:<22} {:>8}  {:>9}",
        "texsat stable + mean (box_sum, Stable)",
        stable_t.reads,
        mult(stable_t),
        stable_t.adds,
        stable_t.bits_read
    );
    say!(out);
    say!(
        out,
        "          Stable spends 4 more additions to subtract before it multiplies, so its"
    );
    say!(
        out,
        "          multiplier operands are bounded by the box, not the table (texsat::width)."
    );
    let crow = [(int_t, 4, 2, 3), (paper_t, 16, 14, 27)];
    let matches = crow
        .iter()
        .all(|&(t, rd, mu, ad)| (t.reads, t.multiplicative(), t.adds) == (rd, mu, ad));
    all_ok &= matches;
    say!(out);
    say!(
        out,
        "{}",
        if all_ok {
            "All sums match the direct integrals; the counts match Crow's."
        } else {
            "SOMETHING DID NOT MATCH: see the rows marked above."
        }
    );
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(out.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(|e| format!("writing stdout: {e}"))?;
    Ok(all_ok)
}
