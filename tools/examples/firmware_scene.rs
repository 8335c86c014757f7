//! The host side of the firmware demo (`examples/firmware/run.sh`): the same scene code as the
//! firmware (`examples/firmware/src/scene.rs`, included here), the same plans and layouts, built
//! in `Vec`s, printing the same lines: `plan NAME samples N checksum C first A,B,C,D`.
//! `run.sh` compares them with what the Cortex-M4F printed under QEMU.
//!
//! ```text
//! cargo run -p texsat-tools --example firmware_scene
//! ```

#[path = "../../examples/firmware/src/scene.rs"]
#[allow(dead_code)]
mod scene;

use scene::{Checksum, H, REPEAT, SMALL, TILED, W};
use std::process::ExitCode;
use texsat::filters::mip::MipPyramid;
use texsat::layouts::{Modular, Tiled};
use texsat::plan::{Plan, PlanLayout};
use texsat::{Error, Texture};

fn line(name: &str, c: &Checksum) -> String {
    let first: Vec<String> = c.first.iter().map(u64::to_string).collect();
    format!(
        "plan {name} samples {} checksum {} first {}",
        c.samples,
        c.hash,
        first.join(",")
    )
}

fn modular<E: texsat::Entry>(tex: &Texture<'_, u8>, plan: &Plan) -> Result<Checksum, Error>
where
    <E::Acc as texsat::Acc>::Wide: Into<u64>,
{
    let PlanLayout::Modular { k } = plan.layout() else {
        return Err(Error::NoPlan);
    };
    let mut words = vec![0u32; plan.storage_len()];
    let mut row = vec![E::ZERO; W];
    let m = Modular::<E>::build(tex, k, &mut words, &mut row)?;
    scene::render(&m, plan)
}

fn tiled(tex: &Texture<'_, u8>, plan: &Plan) -> Result<Checksum, Error> {
    let spec = plan.layout().tiled_spec().ok_or(Error::NoPlan)?;
    let mut words = vec![0u32; plan.storage_len()];
    let mut scratch = vec![0u32; Tiled::<u32>::scratch_needed(spec, W)?];
    let t = Tiled::<u32>::build(tex, spec, &mut words, &mut scratch)?;
    scene::render(&t, plan)
}

fn mip(tex: &Texture<'_, u8>) -> Result<Checksum, Error> {
    let mut levels = vec![0u8; MipPyramid::<u8>::storage_needed(W, H)?];
    let p = MipPyramid::build(tex, &mut levels)?;
    scene::render_mip(&p)
}

fn main() -> ExitCode {
    let mut texels = vec![0u8; W * H];
    scene::fill_texture(&mut texels);
    let run = || -> Result<Vec<String>, Error> {
        let tex = Texture::<u8>::new(&texels, W, H)?;
        Ok(vec![
            line("small", &modular::<u16>(&tex, &SMALL)?),
            line("repeat", &modular::<u32>(&tex, &REPEAT)?),
            line("tiled", &tiled(&tex, &TILED)?),
            line("mip", &mip(&tex)?),
        ])
    };
    match run() {
        Ok(lines) => {
            for l in lines {
                println!("{l}");
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("firmware_scene: {e}");
            ExitCode::FAILURE
        }
    }
}
