//! A run's results: the schema of `results.json` and `results.csv`, which other tools read —
//! keep its fields (issue #5's schema); fields added since are optional when read, so older
//! files still load. Each run's variant is a [`VariantKey`] in memory and its text in the files.
//!
//! The bench lays the runs out in the order of the run's plan (`profile::plan`); what the
//! other measurements return per case (image errors, instruction counts) is recorded here, by
//! the owner of the runs, never by the measuring module.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::material::Stack;
use crate::render::lights::Lighting;
use crate::render::scene::Scene;
use crate::variant::{Model, VariantKey};

/// [`Run::executable_stats`] of a device without `VK_KHR_pipeline_executable_properties`.
pub const UNSUPPORTED: &str = "unsupported";

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DeviceInfo {
    pub name: String,
    pub driver: String,
    pub api_version: String,
    pub vendor_id: u32,
    /// The lanes a SIMD unit runs in lockstep (Vulkan's subgroup size); absent in results
    /// written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subgroup_size: Option<u32>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Run {
    pub variant: VariantKey,
    pub material: String,
    pub frames: u32,
    pub min_ms: f64,
    pub median_ms: f64,
    pub mean_ms: f64,
    pub max_ms: f64,
    pub stdev_ms: f64,
    pub ratio_to_baseline: f64,
    pub fragment_invocations: Option<u64>,
    pub pipeline_ms: f64,
    /// Whether the driver found the pipeline in the pipeline cache; `null` where it does not
    /// say (`vk::PipelineCreation::cache_hit`).
    #[serde(default)]
    pub pipeline_cache_hit: Option<bool>,
    pub spirv_bytes: usize,
    /// Instructions executed in llvmpipe's JIT-compiled code (the shaders and triangle setup)
    /// during the shaded draw, under callgrind (`--counter instructions`), at the smaller
    /// counter size; deterministic. The whole draw's: per-draw costs included.
    pub instructions: Option<u64>,
    /// All instructions executed for the shaded draw at the smaller counter size, the driver's
    /// own work included.
    #[serde(default)]
    pub instructions_total: Option<u64>,
    /// [`Run::instructions`] at the larger counter size.
    #[serde(default)]
    pub instructions_large: Option<u64>,
    /// [`Run::instructions_total`] at the larger counter size.
    #[serde(default)]
    pub instructions_total_large: Option<u64>,
    /// JIT instructions per shaded pixel: `(instructions_large − instructions)` over the
    /// difference of the pixels the scene shades at the two sizes ([`Results::counter`]), so
    /// the costs a draw pays whatever its size cancel. The figure to compare variants by.
    #[serde(default)]
    pub instructions_per_pixel: Option<f64>,
    /// [`Run::instructions_per_pixel`] over that of the `ggx` baseline on the same material,
    /// from the same run.
    #[serde(default)]
    pub instructions_per_pixel_ratio: Option<f64>,
    /// `VK_KHR_pipeline_executable_properties` statistics (registers, spills, code size … as
    /// the driver names them) where the device offers the extension, else `"unsupported"`
    /// (lavapipe); `null` in results written before the distinction.
    pub executable_stats: Option<serde_json::Value>,
    /// The layers the model runs over per shaded pixel, where the draw's pixels are known
    /// (the full-screen scene, or a stack that is the same everywhere): the CPU twin of the
    /// shader's coverage test (`material::surface`). Absent for ggx runs, and in results
    /// written before coverage.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active_layers: Option<ActiveLayers>,
    /// The run's image against the reference image of its material and scene (a sweep's
    /// `reference_spp`, `profile::image_error`); absent where not measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_error: Option<ImageError>,
    /// That reference's relative noise (`render::reference::ReferenceImage::noise`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_noise: Option<f64>,
    /// The reference's noise floor: FLIP between it and the same reference from the next seed
    /// (`profile::image_error::measure`). An image error below it is not resolved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_flip_floor: Option<f64>,
    /// A half-precision run's image against that of the same variant in single precision:
    /// what fp16 alone changes (its banding, as a number).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_error_vs_fp32: Option<ImageError>,
    /// The image error's lighting part: the run's image against the reference image of its
    /// own lobes (`render::reference::render_variant`: the lobes the variant computes,
    /// integrated exactly). What the image-based lighting and the lights' approximations
    /// alone cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lighting_error: Option<ImageError>,
    /// The image error's model part: the reference image of the run's own lobes against the
    /// exact model's (the one [`Run::image_error`] is measured against: that of the run's own
    /// transport, `render::reference::Truth::of`). What the variant's lobes (its tables,
    /// precision, TIR mode) alone cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_error: Option<ImageError>,
}

/// The spread of a run's active layer count over its shaded pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ActiveLayers {
    pub min: u32,
    pub mean: f64,
    pub max: u32,
}

impl ActiveLayers {
    /// Over the `width`×`height` frame of `scene`; `None` where the pixels' texture
    /// coordinates are not known (a varying stack on the sphere).
    pub fn of(stack: &Stack, scene: Scene, width: u32, height: u32) -> Option<Self> {
        let n = stack.layers.len() as u32;
        let Some(surface) = &stack.surface else {
            return Some(Self {
                min: n,
                mean: f64::from(n),
                max: n,
            });
        };
        if scene != Scene::FullScreen {
            return None;
        }
        let (mut min, mut max, mut sum) = (u32::MAX, 0, 0u64);
        for y in 0..height {
            for x in 0..width {
                // The full-screen grid's texture coordinates are the frame's.
                let uv = (
                    (f64::from(x) + 0.5) / f64::from(width),
                    (f64::from(y) + 0.5) / f64::from(height),
                );
                let count = surface.maps.layers_at(&stack.layers, uv, (x, y)).len() as u32;
                min = min.min(count);
                max = max.max(count);
                sum += u64::from(count);
            }
        }
        Some(Self {
            min,
            mean: sum as f64 / (f64::from(width) * f64::from(height)),
            max,
        })
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Results {
    pub device: DeviceInfo,
    pub git_rev: String,
    pub command: String,
    pub size: [u32; 2],
    pub lp_num_threads: Option<String>,
    /// What the shaded draw covers; results written before it was recorded shaded the sphere.
    #[serde(default = "sphere")]
    pub scene: Scene,
    /// The instruction counter's sizes and shaded pixels; `null` when not counted.
    #[serde(default)]
    pub counter: Option<CounterInfo>,
    /// The lighting as a lighting file (`render::lights`); absent: the environment alone, as
    /// every result before lights.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lighting: Option<String>,
    /// The environment map's file name where a study names its own (a sweep file's `env`);
    /// absent: the run's `--env`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment: Option<String>,
    /// The device's calibration pair (`profile::calibrate`), measured by a sweep on a GPU so
    /// that its report says what a fragment timing stands for there; absent on lavapipe.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<super::calibrate::Calibration>,
    pub runs: Vec<Run>,
}

impl Run {
    /// Whether this is a `ggx` baseline run, which other runs' ratios divide by.
    pub fn is_baseline(&self) -> bool {
        self.variant.model == Model::Ggx
    }
}

/// A variant's image against the reference.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
pub struct ImageError {
    /// Mean FLIP over the pixels (0: identical to the eye, 1: as different as can be).
    pub flip: f64,
    /// Root mean square of the linear radiance's difference, over pixels and RGB.
    pub rmse: f64,
    /// The largest |test − reference| / reference over the pixels (mean of RGB), references
    /// below 1 % of the image's mean radiance counting as that.
    pub max_relative: f64,
}

/// What one counted draw executed, split by where the code lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counts {
    /// Everything: the driver's work for the draw included.
    pub total: u64,
    /// Only llvmpipe's JIT-compiled code (shaders, triangle setup): code in anonymous
    /// mappings, which callgrind names `???`. Deterministic for a given shader and coverage.
    pub jit: u64,
}

/// What the image-error pass measured of one case (`profile::image_error::measure`); all
/// `None` for a case it does not measure.
#[derive(Clone, Copy, Debug, Default)]
pub struct CaseImageError {
    pub error: Option<ImageError>,
    pub reference_noise: Option<f64>,
    pub flip_floor: Option<f64>,
    pub vs_fp32: Option<ImageError>,
    pub lighting: Option<ImageError>,
    pub model: Option<ImageError>,
}

/// The instructions of one case's shaded draw at the two counted sizes
/// (`profile::counter`).
#[derive(Clone, Copy, Debug)]
pub struct CaseCounts {
    pub small: Counts,
    pub large: Counts,
    /// JIT instructions per shaded pixel: the difference of the two counts over the added
    /// pixels.
    pub per_pixel: f64,
}

impl Results {
    /// Records each case's image errors (`errors`, in plan order).
    pub fn record_image_errors(&mut self, errors: &[CaseImageError]) {
        assert_eq!(self.runs.len(), errors.len(), "one image error per run");
        for (run, e) in self.runs.iter_mut().zip(errors) {
            run.image_error = e.error;
            run.reference_noise = e.reference_noise;
            run.reference_flip_floor = e.flip_floor;
            run.image_error_vs_fp32 = e.vs_fp32;
            run.lighting_error = e.lighting;
            run.model_error = e.model;
        }
    }

    /// Records each case's instruction counts (`counts`, in plan order) counted as `counter`
    /// says, and each run's per-pixel ratio to its baseline.
    pub fn record_counts(&mut self, counter: CounterInfo, counts: &[CaseCounts]) {
        assert_eq!(self.runs.len(), counts.len(), "one count per run");
        for (run, c) in self.runs.iter_mut().zip(counts) {
            run.instructions = Some(c.small.jit);
            run.instructions_total = Some(c.small.total);
            run.instructions_large = Some(c.large.jit);
            run.instructions_total_large = Some(c.large.total);
            run.instructions_per_pixel = Some(c.per_pixel);
        }
        self.counter = Some(counter);
        self.set_per_pixel_ratios();
    }

    /// The lighting the runs were drawn under.
    pub fn lighting(&self) -> Result<Lighting> {
        match &self.lighting {
            None => Ok(Lighting::default()),
            Some(text) => Lighting::parse(text, std::path::Path::new("the results' `lighting`")),
        }
    }
}

fn sphere() -> Scene {
    Scene::Sphere
}

/// Where the instructions were counted: the two sizes (smaller first) and the pixels the scene
/// shades at each ([`Scene::shaded_pixels`]; width × height for the full-screen scene).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CounterInfo {
    pub sizes: [[u32; 2]; 2],
    pub shaded_pixels: [u64; 2],
}

impl Results {
    /// The `ggx` run on `material`: every other run's ratios divide by it.
    pub fn baseline_of(&self, material: &str) -> Option<&Run> {
        self.runs
            .iter()
            .find(|r| r.material == material && r.is_baseline())
    }

    /// Sets every run's [`Run::instructions_per_pixel_ratio`] from the per-pixel counts.
    pub fn set_per_pixel_ratios(&mut self) {
        let ratios: Vec<Option<f64>> = self
            .runs
            .iter()
            .map(|r| {
                let base = self.baseline_of(&r.material)?.instructions_per_pixel?;
                (base > 0.0).then_some(r.instructions_per_pixel? / base)
            })
            .collect();
        for (run, ratio) in self.runs.iter_mut().zip(ratios) {
            run.instructions_per_pixel_ratio = ratio;
        }
    }

    /// CSV with one row per run, the same fields as the JSON runs (variant keys quoted).
    pub fn csv(&self) -> String {
        let opt = |v: Option<u64>| v.map(|n| n.to_string()).unwrap_or_default();
        let opt_f = |v: Option<f64>| v.map(|x| x.to_string()).unwrap_or_default();
        let mut out = String::from(
            "variant,material,frames,min_ms,median_ms,mean_ms,max_ms,stdev_ms,ratio_to_baseline,\
             fragment_invocations,pipeline_ms,spirv_bytes,instructions,instructions_total,\
             instructions_large,instructions_total_large,instructions_per_pixel,\
             instructions_per_pixel_ratio,flip,rmse,max_relative_error,flip_vs_fp32,flip_floor,\
             flip_lighting,flip_model\n",
        );
        for r in &self.runs {
            out += &format!(
                "\"{}\",\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                r.variant,
                r.material.replace('"', "\"\""),
                r.frames,
                r.min_ms,
                r.median_ms,
                r.mean_ms,
                r.max_ms,
                r.stdev_ms,
                r.ratio_to_baseline,
                opt(r.fragment_invocations),
                r.pipeline_ms,
                r.spirv_bytes,
                opt(r.instructions),
                opt(r.instructions_total),
                opt(r.instructions_large),
                opt(r.instructions_total_large),
                opt_f(r.instructions_per_pixel),
                opt_f(r.instructions_per_pixel_ratio),
                opt_f(r.image_error.map(|e| e.flip)),
                opt_f(r.image_error.map(|e| e.rmse)),
                opt_f(r.image_error.map(|e| e.max_relative)),
                opt_f(r.image_error_vs_fp32.map(|e| e.flip)),
                opt_f(r.reference_flip_floor),
                opt_f(r.lighting_error.map(|e| e.flip)),
                opt_f(r.model_error.map(|e| e.flip))
            );
        }
        out
    }

    /// A table for the terminal: the time, then (when counted) the JIT instructions per shaded
    /// pixel and their ratio to ggx, then the whole draw's at the smaller counter size.
    pub fn table(&self) -> String {
        let mut out = format!(
            "device: {} ({}), {} scene, {}x{}, LP_NUM_THREADS={}, rev {}\n",
            self.device.name,
            self.device.driver,
            self.scene,
            self.size[0],
            self.size[1],
            self.lp_num_threads.as_deref().unwrap_or("unset"),
            self.git_rev
        );
        if let Some(c) = &self.counter {
            out += &format!(
                "instructions counted at {}x{} and {}x{} ({} and {} shaded pixels); per pixel: \
                 the difference over the added pixels\n",
                c.sizes[0][0],
                c.sizes[0][1],
                c.sizes[1][0],
                c.sizes[1][1],
                c.shaded_pixels[0],
                c.shaded_pixels[1]
            );
        }
        let counted = self.runs.iter().any(|r| r.instructions.is_some());
        out += &format!(
            "{:>9} {:>9} {:>9} {:>9} {:>8} {:>7} {:>9} {:>8}{}  variant | material\n",
            "min ms",
            "median",
            "mean",
            "max",
            "stdev",
            "×ggx",
            "pipe ms",
            "SPIR-V",
            if counted {
                format!(
                    " {:>10} {:>7} {:>14} {:>7} {:>14}",
                    "JIT/pixel", "×ggx", "JIT instr.", "×ggx", "all instr."
                )
            } else {
                String::new()
            }
        );
        let dash = || "–".to_string();
        for r in &self.runs {
            let instructions = if counted {
                let whole_ratio = self
                    .baseline_of(&r.material)
                    .and_then(|b| Some(r.instructions? as f64 / b.instructions? as f64));
                format!(
                    " {:>10} {:>7} {:>14} {:>7} {:>14}",
                    r.instructions_per_pixel
                        .map_or_else(dash, |n| format!("{n:.1}")),
                    r.instructions_per_pixel_ratio
                        .map_or_else(dash, |x| format!("{x:.2}")),
                    r.instructions.map_or_else(dash, |n| n.to_string()),
                    whole_ratio.map_or_else(dash, |x| format!("{x:.2}")),
                    r.instructions_total.map_or_else(dash, |n| n.to_string())
                )
            } else {
                String::new()
            };
            out += &format!(
                "{:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>8.3} {:>7.2} {:>9.1} {:>8}{}  {} | {}\n",
                r.min_ms,
                r.median_ms,
                r.mean_ms,
                r.max_ms,
                r.stdev_ms,
                r.ratio_to_baseline,
                r.pipeline_ms,
                r.spirv_bytes,
                instructions,
                r.variant,
                r.material
            );
        }
        out
    }
}
