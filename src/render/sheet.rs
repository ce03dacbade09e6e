//! A contact sheet: every material in every variant, tone-mapped and tiled (rows = materials,
//! columns = variants), each tile labelled with its material and variant, for documentation
//! and for eyeballing a change.

use std::sync::Arc;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::{check_exposure, tonemap, HdrImage};
use crate::material::{base_variant, presets, Stack, Surface};
use crate::model::LayerParams;
use crate::tables::environment::EnvDesc;
use crate::text::TextFont;
use crate::variant::{Mode, VariantKey};

use super::lights::Lighting;
use super::pass::{PassCache, PassKey};
use super::renderer::Renderer;

/// One row of the sheet.
pub struct SheetRow {
    pub name: String,
    pub layers: Vec<LayerParams>,
    /// A spatially varying stack's maps ([`Stack::surface`]).
    pub surface: Option<Arc<Surface>>,
}

/// Gap between tiles, in pixels.
const GAP: usize = 4;

/// The columns when none are asked for: every preset in each model.
pub const DEFAULT_COLUMNS: [&str; 2] = ["model=tm2", "model=tm6"];

impl From<Stack> for SheetRow {
    fn from(stack: Stack) -> Self {
        Self {
            name: stack.name,
            layers: stack.layers,
            surface: stack.surface,
        }
    }
}

/// One row per preset material (`assets/materials/`), in the presets' order.
pub fn preset_rows() -> Result<Vec<SheetRow>> {
    presets()
        .iter()
        .map(|path| Ok(Stack::load(path)?.into()))
        .collect()
}

/// One row per material named (a preset or a file, [`Stack::resolve`]), in order.
pub fn rows_of(materials: &[String]) -> Result<Vec<SheetRow>> {
    materials
        .iter()
        .map(|spec| Ok(Stack::resolve(spec)?.into()))
        .collect()
}

/// A sheet column: the variant and the label its tiles carry (the key as given).
pub struct Column {
    pub label: String,
    pub variant: VariantKey,
}

/// The variants `keys` name, one column each: axes a key leaves out come from
/// [`base_variant`] with the default model, deep enough for every row.
pub fn columns(rows: &[SheetRow], keys: &[&str]) -> Result<Vec<Column>> {
    let deepest = rows.iter().map(|r| r.layers.len()).max().unwrap_or(1);
    let base = base_variant(VariantKey::default().model, deepest);
    keys.iter()
        .map(|k| {
            Ok(Column {
                label: (*k).to_owned(),
                variant: VariantKey::parse_over(k, base)?,
            })
        })
        .collect()
}

/// Smallest label text, in pixels: tiles too narrow for it go unlabelled.
const MIN_LABEL_PX: f64 = 7.0;

/// Writes `text` into the bottom of the `t`×`t` tile at (`x0`, `y0`) of the RGBA `sheet`
/// (`width` pixels wide): white on a darkened strip, at 1/16 of the tile (9 to 18 px), shrunk
/// to fit the tile's width.
fn label_tile(
    font: &TextFont,
    sheet: &mut [u8],
    width: usize,
    (x0, y0): (usize, usize),
    t: usize,
    text: &str,
) {
    let pad = 3;
    let mut size = (t as f64 / 16.0).clamp(9.0, 18.0);
    let (_, (w, _)) = font.layout(text, size);
    let room = t.saturating_sub(2 * pad) as f64;
    if w as f64 > room {
        size *= room / w as f64;
    }
    if size < MIN_LABEL_PX {
        return;
    }
    let (_, (_, h)) = font.layout(text, size);
    let strip = (h as usize + 2 * pad).min(t);
    for y in t - strip..t {
        let row = ((y0 + y) * width + x0) * 4;
        for px in sheet[row..row + t * 4].chunks_exact_mut(4) {
            for c in &mut px[..3] {
                *c = (f32::from(*c) * 0.3) as u8;
            }
        }
    }
    let (tx, ty) = (x0 + pad, y0 + t - strip + pad);
    font.rasterize(text, size, |x, y, coverage| {
        let (x, y) = (tx as i32 + x, ty as i32 + y);
        let inside = x >= x0 as i32 && x < (x0 + t) as i32 && y >= y0 as i32 && y < (y0 + t) as i32;
        if inside {
            let i = (y as usize * width + x as usize) * 4;
            for c in &mut sheet[i..i + 3] {
                let dst = f32::from(*c);
                *c = (dst + (255.0 - dst) * coverage.clamp(0.0, 1.0)).round() as u8;
            }
        }
    });
}

/// Renders each row in each column's variant at `tile`² pixels, labels each tile "material ·
/// column label", and returns the sheet as 8-bit RGBA (width, height, pixels). Fails on an exposure outside [`EXPOSURE_RANGE_EV`] before any
/// work, and on the first non-finite pixel, naming row and variant.
///
/// [`EXPOSURE_RANGE_EV`]: crate::imageio::EXPOSURE_RANGE_EV
pub fn render(
    gpu: &Gpu,
    equirect: &HdrImage,
    rows: &[SheetRow],
    columns: &[Column],
    tile: u32,
    exposure_ev: f32,
    lighting: &Lighting,
) -> Result<(usize, usize, Vec<u8>)> {
    check_exposure(exposure_ev)?;
    let mut renderer = Renderer::new(gpu, equirect, EnvDesc::default())?;
    renderer.lighting = lighting.clone();
    // A generic column's pass shades every row; a per-material one is built per tile.
    let mut passes = PassCache::new();
    let t = tile as usize;
    let width = columns.len() * (t + GAP) + GAP;
    let height = rows.len() * (t + GAP) + GAP;
    let mut sheet: Vec<u8> = [40, 40, 40, 255].repeat(width * height);
    let font = TextFont::bundled();
    for (r, row) in rows.iter().enumerate() {
        for (c, column) in columns.iter().enumerate() {
            let (x0, y0) = (GAP + c * (t + GAP), GAP + r * (t + GAP));
            let variant = column.variant;
            let varies = row.surface.is_some();
            if varies && variant.mode.per_material() && variant.mode != Mode::Specialized {
                // A varying stack shades under mode=generic and specialized only: the tile
                // says so.
                let label = format!(
                    "{} · {}: varies, generic or specialized only",
                    row.name, column.label
                );
                label_tile(&font, &mut sheet, width, (x0, y0), t, &label);
                continue;
            }
            let key = PassKey::new(variant, &row.layers, row.surface.as_deref(), lighting)?;
            renderer.set_surface(row.surface.as_ref())?;
            let pass = passes.get(&mut renderer, &key)?;
            let frame = renderer.render(pass, &row.layers, tile, tile)?;
            if frame.pixels.iter().flatten().any(|v| !v.is_finite()) {
                return Err(Error::Unsupported(format!(
                    "`{}` in {variant} rendered a non-finite pixel",
                    row.name
                )));
            }
            let rgba = tonemap(&frame.pixels, exposure_ev);
            for y in 0..t {
                let dst = ((y0 + y) * width + x0) * 4;
                sheet[dst..dst + t * 4].copy_from_slice(&rgba[y * t * 4..(y + 1) * t * 4]);
            }
            let label = format!("{} · {}", row.name, column.label);
            label_tile(&font, &mut sheet, width, (x0, y0), t, &label);
        }
    }
    Ok((width, height, sheet))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(width: usize, height: usize) -> Vec<u8> {
        [128, 128, 128, 255].repeat(width * height)
    }

    #[test]
    fn a_label_darkens_the_tile_bottom_and_writes_white_text_there_only() {
        let (t, width) = (192, 200);
        let mut sheet = grey(width, t + 8);
        label_tile(
            &TextFont::bundled(),
            &mut sheet,
            width,
            (4, 4),
            t,
            "varnished gold · model=tm2",
        );
        let pixel = |x: usize, y: usize| sheet[(y * width + x) * 4];
        let strip: Vec<u8> = (t - 10..t + 4)
            .flat_map(|y| (4..4 + t).map(move |x| (x, y)))
            .map(|(x, y)| pixel(x, y))
            .collect();
        assert!(strip.iter().any(|&v| v < 60), "no darkened strip");
        assert!(strip.iter().any(|&v| v > 200), "no text");
        assert!((0..t / 2).all(|y| (0..width).all(|x| pixel(x, y) == 128)));
        assert!((0..t + 8).all(|y| pixel(0, y) == 128 && pixel(width - 1, y) == 128));
    }

    #[test]
    fn tiles_too_small_for_legible_text_stay_unlabelled() {
        let mut sheet = grey(16, 16);
        label_tile(
            &TextFont::bundled(),
            &mut sheet,
            16,
            (4, 4),
            8,
            "varnished gold · model=tm2",
        );
        assert!(sheet.chunks_exact(4).all(|p| p[0] == 128));
    }
}
