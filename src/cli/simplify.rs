//! `lamina simplify`: what static simplification takes out of a material and why
//! (`lamina::material::simplify`), as a report or JSON, and optionally the simplified stack as a
//! material file.

use std::path::PathBuf;

use anyhow::Result;
use lamina::material::simplify::simplify;
use lamina::material::Stack;

#[derive(clap::Args)]
pub struct SimplifyArgs {
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    /// Print JSON (`material`, `model`, `layers_before`, `layers_after`, `steps`, `stack`)
    /// instead of the report.
    #[arg(long)]
    json: bool,
    /// Write the simplified stack as a material file (atomically).
    #[arg(long, value_name = "FILE.toml")]
    out: Option<PathBuf>,
}

pub fn run(args: &SimplifyArgs) -> Result<()> {
    let stack = Stack::resolve(&args.material)?;
    stack.require_uniform("`lamina simplify`")?;
    let simplified = simplify(&stack);
    if let Some(path) = &args.out {
        simplified.stack.save(path)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&simplified.to_report())?);
    } else {
        print!("{simplified}");
    }
    Ok(())
}
