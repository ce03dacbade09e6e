//! `mode=baked`: a spatially uniform material's lobes (weight RGB and GGX α per lobe)
//! tabulated over the view cosine by the GPU evaluator (`tm_eval.comp.glsl`, the model the
//! generic pass runs), so that the shaded pass makes one filtered fetch of the table per lobe
//! (the linear filter interpolates between its two samples) and one environment fetch per
//! lobe (`forward.frag.glsl`'s `shade_baked`). A texture rather than a storage buffer: on
//! lavapipe two gathered `vec4` loads and a `mix` cost about 65 JIT instructions per pixel
//! more than the filtered fetch.
//!
//! Sample j of `size` lies at μ = (j/(size − 1))² (μ = 0 evaluated at the pass's smallest
//! cosine, [`MIN_COS`]): uniform in √μ, so that samples crowd towards grazing, where the model
//! has its kinks (the FGD tables' first texel, lobes whose α saturates at 1): uniform in μ, the
//! 64-sample table of `absorbing-film` was 1.2e-2 off there. Lobes that carry no energy at any sample are left out; the rest keep the
//! model's order. The study (`profiling/sweeps/specialization.toml`, `lamina bake-error`)
//! measures the interpolation's error against the model per table size.

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::model::{ends_transmissive, Evaluation, LayerParams, Lobe};
use crate::shader::specialize::{BakedShape, MAX_BAKED_LOBES};
use crate::tables::environment::EnvDesc;
use crate::variant::{Mode, VariantKey, MAX_LAYERS_LIMIT};
use crate::vk::{upload_image, Format, Image, ImageDesc, ImageState, ImageView};

use super::eval::GpuEvaluator;
use super::{PassKey, Renderer, TargetFormat};

/// Samples per lobe of a baked table unless asked otherwise: the smallest size of the error
/// study ([`STUDY_SIZES`]) whose largest lobe and image errors over the presets are both
/// within 1e-3 — at 512, 4.2e-4 and 3.9e-4; at 256, 1.35e-3 (`lacquered-copper`'s lobes) and
/// 2.2e-3 (`varnished-gold`'s image). `lamina sweep profiling/sweeps/specialization.toml`
/// tabulates them; `cargo test --test suite specialized::baked -- --nocapture` prints the lobes. The
/// errors come from the model's kinks near grazing (the FGD table's first texel, a lobe's α
/// reaching 1 near μ = 0.07), so they fall unevenly with the size: where a kink falls inside
/// a table interval decides. The image is the more sensitive there: at the α = 1 kink a
/// roughness error moves the prefiltered radiance 4–11 times more than the lobe metric's
/// `share·|Δ√α|` assumes (the mip, between the cube's two coarsest levels, and the dominant
/// direction's blend both change fastest there).
pub const DEFAULT_SIZE: u32 = 512;

/// The sizes a baked table may have.
pub const SIZE_RANGE: std::ops::RangeInclusive<u32> = 2..=4096;

/// The smallest view cosine the forward pass shades (its clamp of n·v).
pub const MIN_COS: f64 = 1e-4;

/// A material's baked lobes, on the host.
#[derive(Clone, Debug, PartialEq)]
pub struct BakedTable {
    pub shape: BakedShape,
    /// `[lobe][sample]`: (weight RGB, √α). The perceptual roughness √α is what the pass needs
    /// (the prefiltered cube's mip is linear in it) and what it interpolates.
    pub texels: Vec<[f32; 4]>,
    /// The model's index of each kept lobe; a thin slab's table has one row more, its
    /// transmitted lobe (weight T, the transmitted roughness), last.
    pub kept: Vec<usize>,
}

/// The view cosine of sample `j` of a table of `size`.
pub fn sample_cos(j: u32, size: u32) -> f64 {
    let u = f64::from(j) / f64::from(size - 1);
    (u * u).max(MIN_COS)
}

impl BakedTable {
    /// Tabulates `layers` with `evaluator` (a `mode=generic` evaluator of the variant's model,
    /// FGD, TIR and precision) at `size` view cosines.
    pub fn build(evaluator: &GpuEvaluator<'_>, layers: &[LayerParams], size: u32) -> Result<Self> {
        if !SIZE_RANGE.contains(&size) {
            return Err(Error::Unsupported(format!(
                "baked table size {size} is outside {}..={}",
                SIZE_RANGE.start(),
                SIZE_RANGE.end()
            )));
        }
        let cosines: Vec<f64> = (0..size).map(|j| sample_cos(j, size)).collect();
        let evaluations = evaluator.evaluate_lobes(layers, &cosines)?;
        let first = &evaluations[0];
        let lobe_count = first.evaluation.lobes.len();
        if evaluations.iter().any(|e| {
            e.evaluation.lobes.len() != lobe_count
                || e.evaluation.retro_mask != first.evaluation.retro_mask
        }) {
            return Err(Error::Unsupported(
                "the model emitted a different lobe set at different view cosines; a baked \
                 table needs one lobe set"
                    .into(),
            ));
        }
        let kept: Vec<usize> = (0..lobe_count)
            .filter(|&k| {
                evaluations
                    .iter()
                    .any(|e| e.evaluation.lobes[k].weight.iter().any(|&w| w > 0.0))
            })
            .collect();
        // A thin slab's transmitted lobe is the last row (the pass lights it from behind).
        let transmits = ends_transmissive(layers);
        let rows = kept.len() + usize::from(transmits);
        if rows > MAX_BAKED_LOBES {
            return Err(Error::Unsupported(format!(
                "mode=baked holds at most {MAX_BAKED_LOBES} lobes; the stack has {rows} (the \
                 transmitted one included; use mode=specialized)"
            )));
        }
        let mut texels = Vec::with_capacity(rows * size as usize);
        let mut retro_mask = 0;
        for (slot, &k) in kept.iter().enumerate() {
            if k < 32 && first.evaluation.retro_mask & (1 << k) != 0 {
                retro_mask |= 1 << slot;
            }
            for e in &evaluations {
                let lobe = e.evaluation.lobes[k];
                let w = lobe.weight.map(|w| w as f32);
                // √α = −1 marks a diffuse base's lobe (the pass lights it as Lambertian).
                let root = if lobe.diffuse {
                    -1.0
                } else {
                    lobe.roughness.sqrt() as f32
                };
                texels.push([w[0], w[1], w[2], root]);
            }
        }
        if transmits {
            for e in &evaluations {
                let w = e.evaluation.transmittance.map(|w| w as f32);
                let root = e.evaluation.transmitted_roughness.sqrt() as f32;
                texels.push([w[0], w[1], w[2], root]);
            }
        }
        Ok(Self {
            shape: BakedShape {
                lobe_count: rows as u32,
                retro_mask,
                size,
            },
            texels,
            kept,
        })
    }

    /// The lobes the shaded pass reads at view cosine `mu` (its interpolation, on the host).
    pub fn lobes_at(&self, mu: f64) -> Vec<Lobe> {
        let size = self.shape.size;
        let x = mu.clamp(0.0, 1.0).sqrt() * f64::from(size - 1);
        let j = (x as u32).min(size - 2);
        let f = x - f64::from(j);
        (0..self.shape.lobe_count)
            .map(|k| {
                let at = (k * size + j) as usize;
                let (a, b) = (self.texels[at], self.texels[at + 1]);
                let lerp = |c: usize| f64::from(a[c]) + (f64::from(b[c]) - f64::from(a[c])) * f;
                // A diffuse base's lobe has √α = −1 at every sample (the evaluator's α 1).
                let diffuse = a[3] < 0.0;
                Lobe {
                    weight: [lerp(0), lerp(1), lerp(2)],
                    roughness: if diffuse { 1.0 } else { lerp(3) * lerp(3) },
                    diffuse,
                }
            })
            .collect()
    }

    /// The table as the texture `forward.frag.glsl` samples: one row per lobe (one row of
    /// zeros for a table without lobes, which the pass never reads).
    pub fn upload(&self, gpu: &Gpu, name: &str) -> Result<BakedTexture> {
        let size = self.shape.size;
        let rows = self.shape.lobe_count.max(1);
        let mut texels = self.texels.clone();
        texels.resize((rows * size) as usize, [0.0; 4]);
        let image = Image::new(
            &gpu.device,
            ImageDesc::new_2d(Format::R32G32B32A32_SFLOAT, size, rows),
            name,
        )?;
        upload_image(
            &gpu.device,
            &image,
            bytemuck::cast_slice(&texels),
            ImageState::FragmentRead,
        )?;
        let view = image.view(name)?;
        Ok(BakedTexture { image, view })
    }
}

/// A baked table on the device: an RGBA32F image of `size` × lobes texels, read with the
/// shading set's linear filter, which interpolates along √μ like [`BakedTable::lobes_at`]
/// (lavapipe filters float textures with float weights).
pub struct BakedTexture {
    pub image: Image,
    pub view: ImageView,
}

/// The largest error of `table`'s lobes against the model's (`exact`, evaluated at `probes`):
/// per probe, lobe and channel, the weight's error relative to the reflectance there (what the
/// lobe's error does to the shaded colour), and the roughness's error (√α, the cube's mip axis)
/// weighted by the lobe's share of that reflectance. Reflectances below 1e-3 count as 1e-3.
pub fn max_lobe_error(table: &BakedTable, probes: &[f64], exact: &[Evaluation]) -> f64 {
    let mut worst: f64 = 0.0;
    for (&mu, e) in probes.iter().zip(exact) {
        let baked = table.lobes_at(mu);
        let through = Lobe {
            weight: e.transmittance,
            roughness: e.transmitted_roughness,
            diffuse: false,
        };
        let exact = table
            .kept
            .iter()
            .map(|&k| e.lobes[k])
            .chain((baked.len() > table.kept.len()).then_some(through));
        for (b, m) in baked.iter().zip(exact) {
            for c in 0..3 {
                // Relative to what the stack sends back and through.
                let r = (e.reflectance[c] + e.transmittance[c]).max(1e-3);
                let share = m.weight[c].max(0.0) / r;
                let roughness = (b.roughness.sqrt() - m.roughness.sqrt()).abs();
                worst = worst
                    .max((b.weight[c] - m.weight[c]).abs() / r)
                    .max(share * roughness);
            }
        }
    }
    worst
}

/// The `mode=generic` evaluator whose lobes a `mode=baked` variant tabulates, for a stack of
/// `layers` layers.
pub fn evaluator_for(gpu: &Gpu, variant: VariantKey, layers: usize) -> Result<GpuEvaluator<'_>> {
    GpuEvaluator::new(
        gpu,
        VariantKey {
            mode: Mode::Generic,
            max_layers: layers.clamp(1, MAX_LAYERS_LIMIT as usize) as u32,
            ..variant
        },
    )
}

/// The table sizes the error study compares (issue 11 §5).
pub const STUDY_SIZES: [u32; 5] = [32, 64, 128, 256, 512];

/// A baked table of one size against the per-pixel model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeError {
    pub size: u32,
    /// [`max_lobe_error`] at [`probe_cosines`].
    pub lobe_error: f64,
    /// The largest relative difference of a rendered pixel (any channel) between the baked
    /// pass and the per-pixel pass of the same variant, over pixels whose radiance is at least
    /// [`IMAGE_FLOOR`]. Both are rendered into a float target, so that the difference is the
    /// baking's and not the rounding of a half-float target (2⁻¹¹ relative).
    pub image_error: f64,
}

/// Radiances below this count as this in [`BakeError::image_error`].
pub const IMAGE_FLOOR: f64 = 1e-2;

/// Probes per unit of √μ in [`probe_cosines`]: odd, so that no probe is a sample of a table
/// whose size is a power of two (sample j of `size` lies at √μ = j/(size − 1)).
const PROBES: u32 = 4093;

/// The view cosines at which a baked table's lobes are compared with the model's: √μ =
/// (i + ½)/4093, those with μ ≥ [`MIN_COS`] (the pass clamps below). Dense in √μ like the
/// samples, they crowd towards grazing, where the silhouette's pixels are and where the model
/// has its kinks (the FGD table's first texel centre at μ = 0.5/64, a lobe's α reaching 1);
/// uniform in μ, they would leave μ < 0.002 nearly unprobed.
pub fn probe_cosines() -> Vec<f64> {
    (0..PROBES)
        .map(|i| {
            let root = (f64::from(i) + 0.5) / f64::from(PROBES);
            root * root
        })
        .filter(|&mu| mu >= MIN_COS)
        .collect()
}

/// The baked-table error study of one material: per size, the lobes against the model and the
/// image against the per-pixel pass (`mode=generic` of `variant`'s other axes), both rendered
/// at `image_size`² under `equirect` (prefiltered per `env`) into a float target.
pub fn error_study(
    gpu: &Gpu,
    equirect: &HdrImage,
    env: EnvDesc,
    variant: VariantKey,
    layers: &[LayerParams],
    sizes: &[u32],
    image_size: u32,
) -> Result<Vec<BakeError>> {
    let mut renderer = Renderer::with_target(gpu, equirect, env, TargetFormat::Float)?;
    let evaluator = evaluator_for(gpu, variant, layers.len())?;
    let probes = probe_cosines();
    let exact = evaluator.evaluate(layers, &probes)?;
    let generic = VariantKey {
        mode: Mode::Generic,
        ..evaluator.variant
    };
    let reference_pass = renderer.prepare_uniform(generic, layers)?;
    let reference = renderer.render(&reference_pass, layers, image_size, image_size)?;
    let baked_key = PassKey::uniform(
        VariantKey {
            mode: Mode::Baked,
            ..variant
        },
        layers,
        &renderer.lighting,
    )?;
    sizes
        .iter()
        .map(|&size| {
            let table = BakedTable::build(&evaluator, layers, size)?;
            let pass = renderer.prepare_baked(&baked_key, size)?;
            let frame = renderer.render(&pass, layers, image_size, image_size)?;
            let image_error = reference
                .pixels
                .iter()
                .zip(&frame.pixels)
                .flat_map(|(a, b)| (0..3).map(move |c| (f64::from(a[c]), f64::from(b[c]))))
                .map(|(a, b)| (a - b).abs() / a.abs().max(IMAGE_FLOOR))
                .fold(0.0, f64::max);
            Ok(BakeError {
                size,
                lobe_error: max_lobe_error(&table, &probes, &exact),
                image_error,
            })
        })
        .collect()
}
