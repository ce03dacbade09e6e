//! `lamina furnace`: the white furnace — the GPU's reflected energy per view-cosine bin beside
//! the CPU oracle's (`lamina::render::furnace`).

use anyhow::Result;
use lamina::material::resolve_with_variant;
use lamina::render::furnace;

use super::{check_validation, GlobalArgs};

#[derive(clap::Args)]
pub struct FurnaceArgs {
    /// Material file or preset name.
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    /// Shader variant; axes not given come from the defaults and the material's model.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Number of view-cosine bins.
    #[arg(long, default_value_t = 10, value_name = "N")]
    bins: usize,
}

pub fn run(global: &GlobalArgs, args: &FurnaceArgs) -> Result<()> {
    if !(1..=256).contains(&args.bins) {
        anyhow::bail!("--bins {}: must be in 1..=256", args.bins);
    }
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    stack.require_uniform("`lamina furnace`")?;
    let gpu = global.open_gpu()?;
    let layers = stack.params();
    let bins = furnace::gpu(&gpu, variant, &layers, 256, args.bins)?;
    check_validation(&gpu)?;
    let cosines: Vec<f64> = bins.iter().map(|b| b.cos_theta).collect();
    let cpu = furnace::cpu(variant, &layers, &cosines);
    println!("white furnace: {} ({variant})", stack.name);
    println!(
        "GPU: the sphere rendered at 256x256 under radiance 1, binned by n·v (FGD: {})",
        variant.fgd
    );
    println!("CPU: the f64 model with exactly integrated FGD at each bin's mean n·v");
    println!(
        "{:>7}  {:>22}  {:>22}  {:>7}",
        "cos θ", "GPU energy R G B", "CPU energy R G B", "pixels"
    );
    let rgb = |v: [f64; 3]| format!("{:.4} {:.4} {:.4}", v[0], v[1], v[2]);
    for (g, c) in bins.iter().zip(&cpu) {
        println!(
            "{:>7.4}  {:>22}  {:>22}  {:>7}",
            g.cos_theta,
            rgb(g.energy),
            rgb(c.energy),
            g.samples
        );
    }
    for (name, set) in [("GPU", &bins), ("CPU", &cpu)] {
        let (min, mean, max) = furnace::summary(set);
        println!("{name}: min {min:.5}  mean {mean:.5}  max {max:.5}");
    }
    Ok(())
}
