//! `lamina report`: profiling/REPORT.md from sweep results (`lamina::study::report`).

use std::path::PathBuf;

use anyhow::Result;
use lamina::study::report;

use super::studies;

#[derive(clap::Args)]
pub struct ReportArgs {
    /// Result directories: a study's (holding study.json) or a parent of several.
    #[arg(default_value = "profiling/results/lavapipe/reproduce")]
    dirs: Vec<PathBuf>,
    #[arg(long, value_name = "FILE", default_value = "profiling/REPORT.md")]
    out: PathBuf,
}

pub fn run(args: &ReportArgs) -> Result<()> {
    let count = report::write(&args.dirs, &args.out)?;
    println!("wrote {} ({})", args.out.display(), studies(count));
    Ok(())
}
