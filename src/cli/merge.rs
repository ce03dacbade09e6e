//! `lamina merge`: the shards of a sweep (`lamina sweep --shard K/N`) joined into one results
//! directory (`lamina::study::shard`).

use std::path::PathBuf;

use anyhow::Result;
use lamina::study::shard;

use super::studies;

#[derive(clap::Args)]
pub struct MergeArgs {
    /// Every shard's output directory (as `lamina sweep --shard K/N --out DIR` wrote it).
    #[arg(required = true, value_name = "DIR")]
    dirs: Vec<PathBuf>,
    /// Where the merged results go, with their REPORT.md.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

pub fn run(args: &MergeArgs) -> Result<()> {
    let written = shard::merge_dirs(&args.dirs, &args.out)?;
    println!(
        "merged {} shard directories into {} ({}); report: {}",
        args.dirs.len(),
        args.out.display(),
        studies(written.len()),
        args.out.join("REPORT.md").display()
    );
    Ok(())
}
