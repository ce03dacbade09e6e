//! A contact sheet: every material in every variant, tone-mapped and tiled (rows = materials,
//! columns = variants), for documentation and for eyeballing a change.

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::{check_exposure, tonemap, HdrImage};
use crate::material::{base_variant, presets, Stack};
use crate::model::LayerParams;
use crate::shader::VariantKey;
use crate::tables::environment::EnvDesc;

use super::renderer::Renderer;

/// One row of the sheet.
pub struct SheetRow {
    pub name: String,
    pub layers: Vec<LayerParams>,
}

/// Gap between tiles, in pixels.
const GAP: usize = 4;

/// The columns when none are asked for: every preset in each model.
pub const DEFAULT_COLUMNS: [&str; 2] = ["model=tm2", "model=tm6"];

/// One row per preset material (`assets/materials/`), in the presets' order.
pub fn preset_rows() -> Result<Vec<SheetRow>> {
    presets()
        .iter()
        .map(|path| {
            let stack = Stack::load(path)?;
            Ok(SheetRow {
                name: stack.name,
                layers: stack.layers,
            })
        })
        .collect()
}

/// The variants `keys` name, one column each: axes a key leaves out come from
/// [`base_variant`] with the default model, deep enough for every row.
pub fn columns(rows: &[SheetRow], keys: &[&str]) -> Result<Vec<VariantKey>> {
    let deepest = rows.iter().map(|r| r.layers.len()).max().unwrap_or(1);
    let base = base_variant(VariantKey::default().model, deepest);
    keys.iter()
        .map(|k| Ok(VariantKey::parse_over(k, base)?))
        .collect()
}

/// Renders each row in each variant at `tile`² pixels and returns the sheet as 8-bit RGBA
/// (width, height, pixels). Fails on an exposure outside [`EXPOSURE_RANGE_EV`] before any
/// work, and on the first non-finite pixel, naming row and variant.
///
/// [`EXPOSURE_RANGE_EV`]: crate::imageio::EXPOSURE_RANGE_EV
pub fn render(
    gpu: &Gpu,
    equirect: &HdrImage,
    rows: &[SheetRow],
    variants: &[VariantKey],
    tile: u32,
    exposure_ev: f32,
) -> Result<(usize, usize, Vec<u8>)> {
    check_exposure(exposure_ev)?;
    let mut renderer = Renderer::new(gpu, equirect, EnvDesc::default())?;
    let passes = variants
        .iter()
        .map(|&v| renderer.prepare(v))
        .collect::<Result<Vec<_>>>()?;
    let t = tile as usize;
    let width = variants.len() * (t + GAP) + GAP;
    let height = rows.len() * (t + GAP) + GAP;
    let mut sheet: Vec<u8> = [40, 40, 40, 255].repeat(width * height);
    for (r, row) in rows.iter().enumerate() {
        for (c, pass) in passes.iter().enumerate() {
            let frame = renderer.render(pass, &row.layers, tile, tile)?;
            if frame.pixels.iter().flatten().any(|v| !v.is_finite()) {
                return Err(Error::Unsupported(format!(
                    "`{}` in {} rendered a non-finite pixel",
                    row.name, pass.variant
                )));
            }
            let rgba = tonemap(&frame.pixels, exposure_ev);
            let (x0, y0) = (GAP + c * (t + GAP), GAP + r * (t + GAP));
            for y in 0..t {
                let dst = ((y0 + y) * width + x0) * 4;
                sheet[dst..dst + t * 4].copy_from_slice(&rgba[y * t * 4..(y + 1) * t * 4]);
            }
        }
    }
    Ok((width, height, sheet))
}
