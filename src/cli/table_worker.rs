//! `lamina table-worker` (hidden): builds the tables some variants sample and compiles their
//! shaders' SPIR-V into lamina's disk caches, natively with lavapipe's default thread count,
//! for a run that would build them slowly — pinned to one thread, or under valgrind
//! (`lamina::profile::prebuild`); started by `sweep` and by the instruction counter.

use anyhow::Result;
use lamina::profile::prebuild;
use lamina::variant::VariantKey;

use super::{check_validation, GlobalArgs};

#[derive(clap::Args)]
pub struct TableWorkerArgs {
    /// A variant whose tables and shaders to build (repeatable).
    #[arg(long = "variant", value_name = "KEY", required = true)]
    variants: Vec<VariantKey>,
}

pub fn run(global: &GlobalArgs, args: &TableWorkerArgs) -> Result<()> {
    let gpu = global.open_gpu()?;
    prebuild::prepare(&gpu, &args.variants)?;
    check_validation(&gpu)
}
