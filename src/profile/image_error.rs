//! How far a variant's image is from the reference image of the same material and scene
//! (`render::reference`): RMSE and the largest relative error of the linear radiance, and
//! FLIP (Andersson et al. 2020, NVIDIA's perceptual difference; the `nv-flip` bindings wgpu's
//! tests use) between the two images tone-mapped as `lamina render` writes its PNGs, at FLIP's
//! default 67 pixels per degree. The FLIP error map (magma) is what a reader looks at.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use crate::error::Result;
use crate::gpu::Gpu;
use crate::imageio::{tonemap, HdrImage};
use crate::material::Surface;
use crate::model::LayerParams;
use crate::render::lights::Lighting;
use crate::render::reference::{self, Convergence, ReferenceImage, Truth};
use crate::render::scene::Scene;
use crate::render::{PassCache, Renderer, TargetFormat};
use crate::tables::environment::EnvDesc;
use crate::variant::{Ibl, Model, VariantKey};

use super::bench::{place_scene, BenchConfig};
use super::results::{CaseImageError, ImageError};

/// The error maps of a run's cases, by case index ([`error_map_path`]).
pub type ErrorMaps = Vec<(usize, ErrorMap)>;

/// An error map: RGB8 rows top to bottom.
pub struct ErrorMap {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

impl ErrorMap {
    /// As RGBA8, for `imageio::write_png`.
    pub fn rgba(&self) -> Vec<u8> {
        self.rgb
            .chunks(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect()
    }
}

/// `test` against `reference` (linear RGBA, rows top to bottom, `width` × `height`).
pub fn compare(
    test: &[[f32; 4]],
    reference: &[[f32; 4]],
    width: u32,
    height: u32,
) -> (ImageError, ErrorMap) {
    assert_eq!(test.len(), reference.len(), "images of one size");
    assert_eq!(test.len(), (width * height) as usize, "pixel count");
    let mean = |p: &[f32; 4]| (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0;
    let image_mean = reference.iter().map(mean).sum::<f64>() / reference.len().max(1) as f64;
    let floor = (0.01 * image_mean).max(f64::MIN_POSITIVE);
    let (mut sq, mut max_relative) = (0.0, 0.0f64);
    for (t, r) in test.iter().zip(reference) {
        for c in 0..3 {
            sq += (f64::from(t[c]) - f64::from(r[c])).powi(2);
        }
        max_relative = max_relative.max((mean(t) - mean(r)).abs() / mean(r).max(floor));
    }
    let rmse = (sq / (3 * test.len().max(1)) as f64).sqrt();
    let rgb8 = |pixels: &[[f32; 4]]| {
        let rgba = tonemap(pixels, 0.0);
        let rgb: Vec<u8> = rgba.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        nv_flip::FlipImageRgb8::with_data(width, height, &rgb)
    };
    let map = nv_flip::flip(
        rgb8(reference),
        rgb8(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let flip = f64::from(nv_flip::FlipPool::from_image(&map).mean());
    let colours = map.apply_color_lut(&nv_flip::magma_lut());
    (
        ImageError {
            flip,
            rmse,
            max_relative,
        },
        ErrorMap {
            width,
            height,
            rgb: colours.to_vec(),
        },
    )
}

/// Renders each uniform material's reference image (`config`'s scene, size and lighting, `spp`
/// samples per lobe, from `seed`; the exact model's under the truth of each case's transport,
/// `reference::Truth::of`) and one frame of each case of `config`'s plan, in float
/// targets, and measures each case's image error — beside the reference's noise floor, the
/// FLIP between it and the same reference from the next seed, and in two parts: lighting,
/// against the reference of the case's own lobes ([`reference_image`]), and model, that reference
/// against the exact model's — and, for a half-precision case, its error against its
/// single-precision twin: one [`CaseImageError`] per case, in plan
/// order, and the error maps by case ([`error_map_path`]). A stack that varies over the
/// surface has its references' lobes evaluated per pixel from its maps
/// (`reference::render_evaluated`; the exact model's by [`reference::exact_stand_in`]).
pub fn measure(
    gpu: &Gpu,
    equirect: &HdrImage,
    config: &BenchConfig,
    (spp, seed): (u32, u64),
    references: &mut References,
    progress: &mut impl FnMut(&str, usize, usize),
) -> Result<(Vec<CaseImageError>, ErrorMaps)> {
    let cases = config.plan.cases();
    let (width, height) = (config.width, config.height);
    let mut renderer =
        Renderer::with_target(gpu, equirect, EnvDesc::default(), TargetFormat::Float)?;
    renderer.lighting = config.lighting.clone();
    place_scene(&mut renderer, config.scene, width, height)?;
    let never = AtomicBool::new(false);
    let mut passes = PassCache::new();
    let mut errors = vec![CaseImageError::default(); cases.len()];
    let mut maps = Vec::new();
    let mut frames: Vec<Option<Vec<[f32; 4]>>> = vec![None; cases.len()];
    for (i, case) in cases.iter().enumerate() {
        progress("image error", i, cases.len());
        let layers = case.stack.params();
        let key = ReferenceKey {
            model: case.stack.model,
            layers: layers.clone(),
            surface: case.stack.surface.clone(),
            scene: config.scene,
            size: (width, height),
            lighting: config.lighting.clone(),
            truth: Truth::of(case.variant),
            spp,
            seed,
        };
        // The lobes do not depend on how the environment lights them.
        let lobes = VariantKey {
            ibl: Ibl::SplitSum,
            ..case.variant
        };
        references.render_missing(&mut renderer, &key, lobes, &never)?;
        let (image, floor) = references.find(&key).expect("rendered above");
        let own = references.find_lobes(&key, lobes).expect("rendered above");
        renderer.set_surface(case.stack.surface.as_ref())?;
        let pass = passes.get(&mut renderer, &case.pass_key(&config.lighting)?)?;
        let frame = renderer.render(pass, &layers, width, height)?;
        let (error, map) = compare(&frame.pixels, &image.pixels, width, height);
        errors[i].error = Some(error);
        errors[i].reference_noise = Some(image.noise);
        errors[i].flip_floor = Some(floor);
        errors[i].lighting = Some(compare(&frame.pixels, &own.pixels, width, height).0);
        errors[i].model = Some(compare(&own.pixels, &image.pixels, width, height).0);
        maps.push((i, map));
        frames[i] = Some(frame.pixels);
    }
    // Half precision against its own single-precision twin: what fp16 alone changes.
    for (i, case) in cases.iter().enumerate() {
        let twin = VariantKey {
            fp16: false,
            ..case.variant
        };
        let Some(j) = cases
            .iter()
            .position(|c| c.variant == twin && c.stack.name == case.stack.name)
            .filter(|_| case.variant.fp16)
        else {
            continue;
        };
        if let (Some(test), Some(fp32)) = (&frames[i], &frames[j]) {
            let (error, map) = compare(test, fp32, width, height);
            errors[i].vs_fp32 = Some(error);
            maps.push((i + FP32_MAPS, map));
        }
    }
    progress("image error", cases.len(), cases.len());
    Ok((errors, maps))
}

/// The reference image `key` names, and its noise floor: the FLIP between it and the same
/// reference from the next seed.
fn reference_with_floor(
    renderer: &mut Renderer<'_>,
    key: &ReferenceKey,
    never: &AtomicBool,
) -> Result<(ReferenceImage, f64)> {
    let (width, height) = key.size;
    let mut render = |seed| reference_image(renderer, key, None, seed, never);
    let image = render(key.seed)?;
    let other = render(key.seed.wrapping_add(1))?;
    let floor = compare(&other.pixels, &image.pixels, width, height).0.flip;
    Ok((image, floor))
}

/// The reference image of `key`'s stack, scene and samples from `seed`: of the exact model's
/// lobes, or with `own` of that variant's own lobes (`reference::render_variant`), which the
/// image error renders from the exact reference's seed so that the two share their samples and
/// the model part compares lobes, not noise.
fn reference_image(
    renderer: &mut Renderer<'_>,
    key: &ReferenceKey,
    own: Option<VariantKey>,
    seed: u64,
    never: &AtomicBool,
) -> Result<ReferenceImage> {
    let convergence = Convergence {
        spp: key.spp,
        noise: None,
        seed,
    };
    let (layers, size, quiet) = (&key.layers, key.size, &mut |_, _| {});
    match (own, &key.surface) {
        (None, None) => {
            renderer.set_surface(None)?;
            let (model, truth) = (key.model, key.truth);
            reference::render(
                renderer,
                model,
                layers,
                truth,
                size,
                convergence,
                quiet,
                never,
            )
        }
        (Some(variant), None) => {
            renderer.set_surface(None)?;
            reference::render_variant(renderer, variant, layers, size, convergence, quiet, never)
        }
        (own, Some(surface)) => reference::render_evaluated(
            renderer,
            own.unwrap_or_else(|| reference::exact_stand_in(key.model, key.truth)),
            layers,
            Some(surface),
            size,
            convergence,
            quiet,
            never,
        ),
    }
    .map(|image| image.expect("an image-error reference is never stopped"))
}

/// What a reference image depends on, under one environment: the stack in its model (and
/// its maps), the scene and size, the lighting, the truth the case's transport is measured
/// against, the samples and their seed.
#[derive(Clone, PartialEq)]
struct ReferenceKey {
    model: Model,
    layers: Vec<LayerParams>,
    surface: Option<Arc<Surface>>,
    scene: Scene,
    size: (u32, u32),
    lighting: Lighting,
    truth: Truth,
    spp: u32,
    seed: u64,
}

/// The reference images rendered so far under one environment, each with its noise floor,
/// kept across the measurements of a run: a suite's studies of one material at one size share
/// its reference, rendered once per truth (with the next seed's for its floor; it is seeded by
/// its seed and frames, so a second render would be the same image).
#[derive(Default)]
pub struct References {
    images: Vec<(ReferenceKey, ReferenceImage, f64)>,
    /// The references of variants' own lobes ([`reference_image`]).
    lobes: Vec<(ReferenceKey, VariantKey, ReferenceImage)>,
}

impl References {
    fn find(&self, key: &ReferenceKey) -> Option<(&ReferenceImage, f64)> {
        self.images
            .iter()
            .find(|(k, ..)| k == key)
            .map(|(_, i, floor)| (i, *floor))
    }

    /// Renders the exact model's reference of `key` (with its floor) and that of `lobes`'s
    /// own lobes, where not rendered yet.
    fn render_missing(
        &mut self,
        renderer: &mut Renderer<'_>,
        key: &ReferenceKey,
        lobes: VariantKey,
        never: &AtomicBool,
    ) -> Result<()> {
        if self.find(key).is_none() {
            let (image, floor) = reference_with_floor(renderer, key, never)?;
            self.images.push((key.clone(), image, floor));
        }
        if self.find_lobes(key, lobes).is_none() {
            let image = reference_image(renderer, key, Some(lobes), key.seed, never)?;
            self.lobes.push((key.clone(), lobes, image));
        }
        Ok(())
    }

    fn find_lobes(&self, key: &ReferenceKey, variant: VariantKey) -> Option<&ReferenceImage> {
        self.lobes
            .iter()
            .find(|(k, v, _)| k == key && *v == variant)
            .map(|(.., i)| i)
    }
}

/// Offset of the run index under which a half-precision run's error map against its fp32
/// twin travels with the others ([`error_map_path`]).
pub const FP32_MAPS: usize = 1 << 20;

/// Where a run's error map goes in its study's directory: against the reference, or (for a
/// half-precision run's map against its fp32 twin, index offset by [`FP32_MAPS`]) against it.
pub fn error_map_path(run: usize) -> String {
    if run >= FP32_MAPS {
        format!("error-maps/run-{}-vs-fp32.png", run - FP32_MAPS)
    } else {
        format!("error-maps/run-{run}.png")
    }
}

/// [`error_map_path`] of run `run`'s map against its fp32 twin.
pub fn fp32_error_map_path(run: usize) -> String {
    error_map_path(run + FP32_MAPS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_against_itself_has_no_error_and_a_change_has_some() {
        let (w, h) = (32, 24);
        let reference: Vec<[f32; 4]> = (0..w * h)
            .map(|i| {
                let v = (i % w) as f32 / w as f32;
                [v, 0.5 * v, 0.2, 1.0]
            })
            .collect();
        let (same, _) = compare(&reference, &reference, w, h);
        assert_eq!(same.rmse, 0.0);
        assert_eq!(same.max_relative, 0.0);
        assert!(same.flip < 1e-6, "{}", same.flip);
        // A brighter band over a quarter of the rows.
        let mut test = reference.clone();
        for p in &mut test[..(w * h / 4) as usize] {
            p[0] *= 1.5;
            p[1] *= 1.5;
        }
        let (changed, map) = compare(&test, &reference, w, h);
        assert!(
            changed.rmse > 0.01 && changed.max_relative > 0.2,
            "{changed:?}"
        );
        assert!(
            changed.flip > 0.01 && changed.flip < 1.0,
            "{}",
            changed.flip
        );
        assert_eq!(map.rgb.len(), (w * h * 3) as usize);
        // A bigger change is a bigger error.
        for p in &mut test[..(w * h / 4) as usize] {
            p[0] *= 2.0;
        }
        assert!(compare(&test, &reference, w, h).0.flip > changed.flip);
    }
}
