//! `lamina table-worker` (hidden): builds the tables some variants sample into lamina's disk
//! cache with lavapipe's default thread count, for a run pinned to one thread
//! (`lamina::profile::prebuild`); started by `sweep`.

use anyhow::Result;
use lamina::render::inputs::ShadingInputs;
use lamina::variant::VariantKey;

use super::{check_validation, GlobalArgs};

#[derive(clap::Args)]
pub struct TableWorkerArgs {
    /// A variant whose tables to build (repeatable).
    #[arg(long = "variant", value_name = "KEY", required = true)]
    variants: Vec<VariantKey>,
}

pub fn run(global: &GlobalArgs, args: &TableWorkerArgs) -> Result<()> {
    let gpu = global.open_gpu()?;
    let mut inputs = ShadingInputs::new(&gpu)?;
    for &variant in &args.variants {
        inputs.prepare(variant)?;
    }
    check_validation(&gpu)
}
