//! `sat plan`: a scene's facts in, [`texsat::plan::Plan`] out as one JSON object; and the
//! reading of such an object back for `sat query --plan FILE`.
//!
//! The JSON holds the plan's choices (`layout`, `entry`, `frac_bits`, `lookup`, `edge`), its
//! costs (`table_bytes`, `bits_per_entry`, `reads`, `muls`, `divs`, `adds`, `max_error` in units
//! of the mean's last bit), `mean` (`u32`: `BoxSum::mean_rounded_u32` serves every box of the
//! facts; `wide`: `BoxSum::mean_rounded`), `features`, `rejected` (`[{layout, entry, why}]`) and the `facts` it
//! was made from. `sat query --plan` re-plans from those facts and refuses a file whose choices
//! differ (edited by hand, or written by another version), so a query runs exactly the plan's
//! configuration.

use crate::num::{fixed_decimal, parse_fixed, Inexact};
use crate::EdgeArg;
use clap::Args;
use serde_json::{json, Map, Value};
use std::path::Path;
use texsat::plan::{Plan, RejectReason, SceneFacts};
use texsat::EdgeKind;

#[derive(Args)]
pub struct PlanArgs {
    /// Texture size WxH in texels.
    #[arg(long)]
    size: String,
    /// Bits per texel (1 to 16).
    #[arg(long)]
    texel_bits: u32,
    /// Channels per texel.
    #[arg(long, default_value_t = 1)]
    channels: usize,
    /// Smallest and largest box, MIN..MAX, each WxH in texels (decimals allowed, exact at F).
    #[arg(long = "box")]
    box_range: String,
    /// Boundary mode; a mode other than border means boxes may leave the texture unless
    /// --inside is given.
    #[arg(long, value_enum, default_value_t = EdgeArg::Border)]
    edge: EdgeArg,
    /// Boxes stay inside the texture (whatever the mode).
    #[arg(long)]
    inside: bool,
    /// Fractional bits F of the corners (0: integer corners).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=24))]
    frac_bits: u32,
    /// Fractional bits G of the mean.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=32))]
    mean_bits: u32,
    /// Error allowed on the mean, in units of its last bit (0: exact).
    #[arg(long, default_value_t = 0)]
    tolerance: u64,
    /// The most table reads per sample (0: no bound).
    #[arg(long, default_value_t = 0)]
    max_reads: u32,
}

/// `WxH` of decimals, as raw values at `F = f`.
fn parse_sides(s: &str, f: u32, what: &str) -> Result<[u64; 2], String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("{what} '{s}' is not of the form WxH"))?;
    let side = |v: &str| -> Result<u64, String> {
        let raw = parse_fixed(v, f, Inexact::Refuse).map_err(|e| format!("{what} '{s}': {e}"))?;
        u64::try_from(raw).map_err(|_| format!("{what} '{s}' has a negative side"))
    };
    Ok([side(w)?, side(h)?])
}

impl PlanArgs {
    /// The facts these flags state.
    pub fn facts(&self) -> Result<SceneFacts, String> {
        let (w, h) = self
            .size
            .split_once('x')
            .ok_or_else(|| format!("--size '{}' is not of the form WxH", self.size))?;
        let parse = |v: &str| -> Result<usize, String> {
            v.parse::<usize>()
                .map_err(|_| format!("--size '{}': '{v}' is not a whole number", self.size))
        };
        let (width, height) = (parse(w)?, parse(h)?);
        let f = self.frac_bits;
        let (min, max) = self
            .box_range
            .split_once("..")
            .ok_or_else(|| format!("--box '{}' is not of the form MIN..MAX", self.box_range))?;
        Ok(SceneFacts {
            width,
            height,
            texel_bits: self.texel_bits,
            channels: self.channels,
            frac_bits: f,
            min_box: parse_sides(min, f, "--box MIN")?,
            max_box: parse_sides(max, f, "--box MAX")?,
            leaves_texture: self.edge != EdgeArg::Border && !self.inside,
            edge: self.edge.kind(),
            mean_frac_bits: self.mean_bits,
            tolerance: self.tolerance,
            max_reads: self.max_reads,
        })
    }
}

/// `sat plan`: prints the plan's JSON, or refuses.
pub fn run(args: &PlanArgs) -> Result<bool, String> {
    let facts = args.facts()?;
    let plan = Plan::for_scene(&facts).map_err(|e| format!("no plan: {e}"))?;
    crate::print_line(&to_json(&plan))?;
    Ok(true)
}

fn sides(v: [u64; 2], f: u32) -> String {
    format!(
        "{}x{}",
        fixed_decimal(v[0] as u128, f),
        fixed_decimal(v[1] as u128, f)
    )
}

fn why(r: &RejectReason) -> String {
    match *r {
        RejectReason::Larger { bytes } => format!("larger: {bytes} bytes"),
        RejectReason::TooManyReads { reads } => {
            format!("{reads} reads per sample, above the bound")
        }
        RejectReason::TooWide {
            bits_needed,
            bits_available,
        } => format!("needs {bits_needed} bits, the widest word gives {bits_available}"),
        RejectReason::NoSaving { k } => {
            format!("the largest box needs k = {k} bits, no fewer than the full table's")
        }
        RejectReason::Refused(e) => format!("refused: {e}"),
    }
}

/// The plan as one JSON object (module docs).
pub fn to_json(p: &Plan) -> Value {
    let f = p.facts();
    let (bits, texels) = p.bits_per_entry();
    let (en, ed) = p.max_error();
    let c = p.costs();
    let rejected: Vec<Value> = p
        .rejected()
        .map(|r| {
            json!({
                "layout": r.layout.to_string(),
                "entry": r.entry.map(|e| e.name()),
                "why": why(&r.why),
            })
        })
        .collect();
    let mut o = Map::new();
    o.insert("layout".into(), json!(p.layout().to_string()));
    o.insert("entry".into(), json!(p.entry().name()));
    o.insert("frac_bits".into(), json!(f.frac_bits));
    o.insert("lookup".into(), json!(p.lookup().name()));
    if let Some(s) = p.shortcut() {
        o.insert("shortcut_min_side".into(), json!(s.min_side()));
    }
    o.insert("edge".into(), json!(f.edge.name()));
    o.insert("acc_bits".into(), json!(p.acc_bits()));
    o.insert("storage_len".into(), json!(p.storage_len()));
    o.insert("table_bytes".into(), json!(p.table_bytes()));
    o.insert(
        "bits_per_entry".into(),
        json!(if texels == 0 {
            0.0
        } else {
            bits as f64 / texels as f64
        }),
    );
    o.insert("reads".into(), json!(c.reads));
    o.insert("muls".into(), json!(c.muls));
    o.insert("divs".into(), json!(c.divs));
    o.insert("adds".into(), json!(c.adds));
    o.insert("max_error".into(), json!(en as f64 / ed as f64));
    o.insert(
        "mean".into(),
        json!(if p.mean_fits_u32() { "u32" } else { "wide" }),
    );
    o.insert(
        "repeat_within_period".into(),
        json!(p.repeat_within_period()),
    );
    o.insert("features".into(), json!(p.features()));
    o.insert("rejected".into(), Value::Array(rejected));
    o.insert(
        "facts".into(),
        json!({
            "size": format!("{}x{}", f.width, f.height),
            "texel_bits": f.texel_bits,
            "channels": f.channels,
            "box": format!("{}..{}", sides(f.min_box, f.frac_bits), sides(f.max_box, f.frac_bits)),
            "leaves_texture": f.leaves_texture,
            "edge": f.edge.name(),
            "frac_bits": f.frac_bits,
            "mean_bits": f.mean_frac_bits,
            "tolerance": f.tolerance,
            "max_reads": f.max_reads,
        }),
    );
    Value::Object(o)
}

/// The largest plan file read (bytes): a plan written by `sat plan` is about 2 KB.
pub const MAX_PLAN_BYTES: u64 = 1 << 20;

/// Reads at most [`MAX_PLAN_BYTES`] of `path` as UTF-8 (a directory, a device without end or a
/// larger file is refused, never read whole).
fn read_bounded(path: &Path) -> Result<String, String> {
    use std::io::Read;
    let name = path.display();
    if path.is_dir() {
        return Err(format!("--plan {name}: is a directory, not a plan file"));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("--plan {name}: {e}"))?;
    let mut bytes = Vec::new();
    file.take(MAX_PLAN_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("--plan {name}: {e}"))?;
    if bytes.len() as u64 > MAX_PLAN_BYTES {
        return Err(format!(
            "--plan {name}: larger than {MAX_PLAN_BYTES} bytes, so not a plan written by sat plan"
        ));
    }
    String::from_utf8(bytes).map_err(|_| format!("--plan {name}: not UTF-8 text"))
}

/// Reads a plan written by `sat plan` and re-plans from its facts; refuses a file whose
/// choices differ from the re-plan. Every number of the facts is range-checked as the flags of
/// `sat plan` are (no silent truncation of a hand-edited value).
pub fn read(path: &Path) -> Result<Plan, String> {
    let text = read_bounded(path)?;
    let v: Value = serde_json::from_str(&text)
        .map_err(|e| format!("--plan {}: not JSON: {e}", path.display()))?;
    let bad = |what: &str| format!("--plan {}: missing or invalid {what}", path.display());
    let facts = v.get("facts").ok_or_else(|| bad("facts"))?;
    let s = |k: &str| -> Result<String, String> {
        facts
            .get(k)
            .and_then(Value::as_str)
            .map(str::to_string)
            .ok_or_else(|| bad(&format!("facts.{k}")))
    };
    let n = |k: &str| -> Result<u64, String> {
        facts
            .get(k)
            .and_then(Value::as_u64)
            .ok_or_else(|| bad(&format!("facts.{k}")))
    };
    let edge = EdgeKind::from_name(&s("edge")?).ok_or_else(|| bad("facts.edge"))?;
    let leaves = facts
        .get("leaves_texture")
        .and_then(Value::as_bool)
        .ok_or_else(|| bad("facts.leaves_texture"))?;
    // A number of the facts within `0..=max`, as the flags of `sat plan` take it.
    let within = |k: &str, max: u64| -> Result<u64, String> {
        n(k).and_then(|v| {
            if v <= max {
                Ok(v)
            } else {
                Err(format!("{} (above {max})", bad(&format!("facts.{k}"))))
            }
        })
    };
    let small = |k: &str, max: u32| within(k, u64::from(max)).map(|v| v as u32);
    let args = PlanArgs {
        size: s("size")?,
        texel_bits: small("texel_bits", u32::MAX)?,
        channels: within("channels", u64::from(u32::MAX))? as usize,
        box_range: s("box")?,
        edge: match edge {
            EdgeKind::Border => EdgeArg::Border,
            EdgeKind::Clamp => EdgeArg::Clamp,
            EdgeKind::Repeat => EdgeArg::Repeat,
            EdgeKind::Mirror => EdgeArg::Mirror,
        },
        inside: !leaves,
        frac_bits: small("frac_bits", 24)?,
        mean_bits: small("mean_bits", 32)?,
        tolerance: n("tolerance")?,
        max_reads: small("max_reads", u32::MAX)?,
    };
    let facts = args.facts()?;
    if facts.leaves_texture != leaves {
        return Err(bad(
            "facts.leaves_texture (a border plan's boxes never leave)",
        ));
    }
    let plan = Plan::for_scene(&facts)
        .map_err(|e| format!("--plan {}: no plan for its facts: {e}", path.display()))?;
    let want = to_json(&plan);
    for key in [
        "layout",
        "entry",
        "frac_bits",
        "lookup",
        "edge",
        "mean",
        "repeat_within_period",
    ] {
        if v.get(key) != want.get(key) {
            return Err(format!(
                "--plan {}: its {key} is {}, but its facts plan {} (edited by hand, or written \
                 by another version of sat: run `sat plan` again)",
                path.display(),
                v.get(key).unwrap_or(&Value::Null),
                want[key]
            ));
        }
    }
    Ok(plan)
}
