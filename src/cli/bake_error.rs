//! `lamina bake-error`: a baked material's lobes and image against the per-pixel model, per
//! table size (`lamina::render::baked::error_study`).

use anyhow::{Context, Result};
use lamina::imageio;
use lamina::material::resolve_with_variant;
use lamina::render::baked::{self, DEFAULT_SIZE, IMAGE_FLOOR, SIZE_RANGE, STUDY_SIZES};
use lamina::tables::environment::EnvDesc;

use super::args::EnvArg;
use super::{asset_path, check_validation, GlobalArgs};

#[derive(clap::Args)]
pub struct BakeErrorArgs {
    /// Material file or preset name.
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    /// Shader variant (its mode is ignored: the per-pixel pass and the baked one are both
    /// measured); axes not given come from the defaults and the material's model.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Table sizes (samples per lobe), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = STUDY_SIZES, value_name = "N,N,…")]
    sizes: Vec<u32>,
    /// Side of the square images compared.
    #[arg(long, default_value_t = 128, value_name = "PIXELS")]
    image_size: u32,
    #[command(flatten)]
    env: EnvArg,
}

pub fn run(global: &GlobalArgs, args: &BakeErrorArgs) -> Result<()> {
    if let Some(bad) = args.sizes.iter().find(|s| !SIZE_RANGE.contains(s)) {
        anyhow::bail!(
            "--sizes {bad}: a table size must be in {}..={}",
            SIZE_RANGE.start(),
            SIZE_RANGE.end()
        );
    }
    if !(8..=2048).contains(&args.image_size) {
        anyhow::bail!("--image-size {}: must be in 8..=2048", args.image_size);
    }
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    stack.require_uniform("`lamina bake-error`")?;
    let env_path = asset_path(&args.env.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let gpu = global.open_gpu()?;
    let layers = stack.params();
    let rows = baked::error_study(
        &gpu,
        &equirect,
        EnvDesc::default(),
        variant,
        &layers,
        &args.sizes,
        args.image_size,
    )?;
    check_validation(&gpu)?;
    println!(
        "baked lobes of {} against the per-pixel model ({variant})",
        stack.name
    );
    println!(
        "lobes: largest error at {probes} view cosines between samples (dense in √cos), \
         relative to R; image: largest relative pixel difference at {side}x{side} in RGBA32F \
         (radiance floor {IMAGE_FLOOR})",
        probes = baked::probe_cosines().len(),
        side = args.image_size
    );
    println!("{:>6}  {:>11}  {:>11}", "size", "lobes", "image");
    for row in &rows {
        let chosen = if row.size == DEFAULT_SIZE {
            "  (default)"
        } else {
            ""
        };
        println!(
            "{:>6}  {:>11.2e}  {:>11.2e}{chosen}",
            row.size, row.lobe_error, row.image_error
        );
    }
    Ok(())
}
