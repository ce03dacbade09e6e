//! `lamina count-worker` (hidden): the side of the instruction counter that runs under
//! callgrind (`lamina::profile::counter`), started by `--counter instructions`.

use std::path::PathBuf;

use anyhow::{Context, Result};
use lamina::imageio;
use lamina::profile::count_worker::{self, WorkerJob};
use lamina::render::scene::Scene;
use lamina::Size;

use super::{check_validation, GlobalArgs};

#[derive(clap::Args)]
pub struct CountWorkerArgs {
    #[arg(long, value_name = "FILE")]
    job: PathBuf,
    #[arg(long, value_name = "FILE")]
    env: PathBuf,
    #[arg(long, value_name = "SCENE")]
    scene: Scene,
    /// A counted resolution (repeated: every case is counted at each, in order).
    #[arg(long = "size", value_name = "WxH", required = true)]
    sizes: Vec<Size>,
}

pub fn run(global: &GlobalArgs, args: &CountWorkerArgs) -> Result<()> {
    let (cases, lighting) = WorkerJob::read(&args.job)?;
    let equirect = imageio::read_exr(&args.env).context("reading the environment map")?;
    let gpu = global.open_gpu()?;
    count_worker::worker(&gpu, &equirect, &cases, args.scene, &lighting, &args.sizes)?;
    check_validation(&gpu)
}
