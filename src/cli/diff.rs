//! `lamina diff`: two sets of results side by side, with an optional gate on instruction
//! growth (`lamina::study::diff`).

use std::path::PathBuf;

use anyhow::Result;
use lamina::study::diff;

use super::args;

#[derive(clap::Args)]
pub struct DiffArgs {
    /// The older results: a results.json, a study's directory, or a `lamina sweep` output
    /// directory (its studies pair by name).
    old: PathBuf,
    /// The newer results, in the same forms.
    new: PathBuf,
    /// Exit with an error when a run's JIT instruction count grew by more than PCT percent, or
    /// when a run or study of OLD cannot be checked in NEW (instruction counts are
    /// deterministic; timings are too noisy on lavapipe to gate on).
    #[arg(long, value_name = "PCT", value_parser = args::percent)]
    fail_above: Option<f64>,
}

pub fn run(args: &DiffArgs) -> Result<()> {
    let old = diff::load(&args.old)?;
    let new = diff::load(&args.new)?;
    let cmp = diff::diff(&old, &new, &args.old, &args.new)?;
    print!("{}", diff::render(&cmp));
    if let Some(pct) = args.fail_above {
        let problems = diff::gate(&cmp, pct);
        if !problems.is_empty() {
            anyhow::bail!(
                "--fail-above {pct}: {} problem(s) — JIT instructions grew by more than {pct} %, \
                 or the new results cannot be checked:\n  {}",
                problems.len(),
                problems.join("\n  ")
            );
        }
    }
    Ok(())
}
