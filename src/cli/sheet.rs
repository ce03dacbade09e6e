//! `lamina sheet`: every preset in each variant, tiled into one PNG
//! (`lamina::render::sheet`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use lamina::imageio;
use lamina::render::sheet;
use lamina::Size;

use super::args::{self, EnvArg};
use super::{asset_path, check_validation, GlobalArgs};

#[derive(clap::Args)]
pub struct SheetArgs {
    /// Variants, one column each (default: model=tm2 and model=tm6).
    #[arg(long = "variant", value_name = "KEY")]
    variants: Vec<String>,
    /// Materials, one row each: presets or files (default: every preset).
    #[arg(long = "material", value_name = "NAME|FILE")]
    materials: Vec<String>,
    /// Side of one tile in pixels (1 to 16384).
    #[arg(
        long,
        default_value_t = 256,
        value_name = "PIXELS",
        value_parser = clap::value_parser!(u32).range(1..=i64::from(Size::MAX_SIDE))
    )]
    tile: u32,
    #[command(flatten)]
    env: EnvArg,
    #[arg(long, value_name = "FILE.png", default_value = "out/sheet.png")]
    out: PathBuf,
    /// Exposure of the PNG, in stops (-24 to 24).
    #[arg(long, default_value = "0", allow_negative_numbers = true, value_parser = args::exposure)]
    exposure: f32,
}

pub fn run(global: &GlobalArgs, args: &SheetArgs) -> Result<()> {
    let env_path = asset_path(&args.env.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let keys: Vec<&str> = if args.variants.is_empty() {
        sheet::DEFAULT_COLUMNS.to_vec()
    } else {
        args.variants.iter().map(String::as_str).collect()
    };
    let rows = if args.materials.is_empty() {
        sheet::preset_rows()?
    } else {
        sheet::rows_of(&args.materials)?
    };
    let columns = sheet::columns(&rows, &keys)?;
    let gpu = global.open_gpu()?;
    let lighting = args.env.lights.lighting()?;
    let (w, h, rgba) = sheet::render(
        &gpu,
        &equirect,
        &rows,
        &columns,
        args.tile,
        args.exposure,
        &lighting,
    )?;
    check_validation(&gpu)?;
    imageio::write_png(&args.out, w, h, &rgba)?;
    println!(
        "rows (top to bottom): {}",
        rows.iter()
            .map(|r| r.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!(
        "columns: {}",
        columns
            .iter()
            .map(|c| c.variant.to_string())
            .collect::<Vec<_>>()
            .join(" | ")
    );
    println!("wrote {}", args.out.display());
    Ok(())
}
