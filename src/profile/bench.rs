//! `lamina bench`: every variant's pipeline built up front, frames interleaved round-robin so
//! drift hits all variants alike, warm-up frames discarded, the shaded draw timed by the
//! profiler scope and its fragment invocations counted; each variant's median divided by the
//! `ggx` baseline's from the same run (DESIGN.md §7). The draw shades a [`Scene`]: the
//! full-screen grid (every pixel once, the talk's setup) or `render`'s sphere.
//!
//! The result file is read by other tools: keep `results.json`'s fields (issue #5's schema);
//! fields added since are optional when read, so older files still load.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::material::Stack;
use crate::model::LayerParams;
use crate::render::forward::ForwardPass;
use crate::render::lights::Lighting;
use crate::render::scene::Scene;
use crate::render::surface::spec_bits;
use crate::render::Renderer;
use crate::tables::environment::EnvDesc;
use crate::variant::{Model, VariantKey};

use super::stats::Summary;

/// One measured combination: a variant shading one material.
#[derive(Clone, Debug)]
pub struct Case {
    pub variant: VariantKey,
    pub stack: Stack,
}

pub struct BenchConfig {
    pub cases: Vec<Case>,
    pub scene: Scene,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
    /// The environment's scale and the analytic lights of every frame.
    pub lighting: Lighting,
}

impl BenchConfig {
    /// The cases as they will run: a `ggx` baseline on each material that lacks one goes
    /// first, so every ratio divides by a baseline measured in the same run on the same stack.
    pub fn with_baselines(&self) -> Vec<Case> {
        let mut out: Vec<Case> = Vec::new();
        for case in &self.cases {
            let has_baseline = self
                .cases
                .iter()
                .chain(&out)
                .any(|c| c.stack.name == case.stack.name && c.variant.model == Model::Ggx);
            if !has_baseline {
                out.push(Case {
                    variant: VariantKey {
                        max_layers: case.variant.max_layers,
                        ..baseline()
                    },
                    ..case.clone()
                });
            }
        }
        out.extend(self.cases.iter().cloned());
        out
    }
}

/// [`Run::executable_stats`] of a device without `VK_KHR_pipeline_executable_properties`.
pub const UNSUPPORTED: &str = "unsupported";

#[derive(Debug, Serialize, Deserialize)]
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

#[derive(Debug, Serialize, Deserialize)]
pub struct Run {
    pub variant: String,
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
    pub image_error: Option<super::image_error::ImageError>,
    /// That reference's relative noise (`render::reference::ReferenceImage::noise`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_noise: Option<f64>,
    /// A half-precision run's image against that of the same variant in single precision:
    /// what fp16 alone changes (its banding, as a number).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_error_vs_fp32: Option<super::image_error::ImageError>,
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

#[derive(Debug, Serialize, Deserialize)]
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
    pub runs: Vec<Run>,
}

impl Results {
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

/// Puts `scene`'s mesh in front of `renderer`'s camera for a `width`×`height` frame.
pub fn place_scene(renderer: &mut Renderer, scene: Scene, width: u32, height: u32) -> Result<()> {
    let mesh = scene.mesh(&renderer.camera, width, height);
    renderer.set_mesh(&mesh)
}

/// The `ggx` baseline every run is divided by.
pub fn baseline() -> VariantKey {
    VariantKey {
        model: Model::Ggx,
        ..VariantKey::default()
    }
}

fn git_rev() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_else(|| "unknown".into())
}

/// Runs the bench; `progress(done, total)` is called after every frame.
pub fn run(
    gpu: &Gpu,
    equirect: &HdrImage,
    config: &BenchConfig,
    mut progress: impl FnMut(u32, u32),
) -> Result<Results> {
    if config.frames == 0 {
        return Err(Error::Unsupported("--frames must be at least 1".into()));
    }
    let cases = config.with_baselines();
    let mut renderer = Renderer::new(gpu, equirect, EnvDesc::default())?;
    let layers: Vec<Vec<LayerParams>> = cases.iter().map(|c| c.stack.params()).collect();
    place_scene(&mut renderer, config.scene, config.width, config.height)?;
    renderer.lighting = config.lighting.clone();
    let mut passes: Vec<ForwardPass> = Vec::new();
    let mut pass_of = Vec::with_capacity(cases.len());
    for (case, stack) in cases.iter().zip(&layers) {
        let surface = case.stack.surface.as_ref();
        let shades = |p: &ForwardPass| p.shades(case.variant, stack, spec_bits(surface));
        let index = match passes.iter().position(shades) {
            Some(i) => i,
            None => {
                renderer.set_surface(surface)?;
                passes.push(renderer.prepare(case.variant, stack)?);
                passes.len() - 1
            }
        };
        pass_of.push(index);
    }
    let mut times = vec![Vec::new(); cases.len()];
    let mut invocations = vec![None; cases.len()];
    let total = (config.warmup + config.frames) * cases.len() as u32;
    let mut done = 0;
    for frame in 0..config.warmup + config.frames {
        for i in 0..cases.len() {
            let pass = &passes[pass_of[i]];
            renderer.set_surface(cases[i].stack.surface.as_ref())?;
            let result = renderer.render(pass, &layers[i], config.width, config.height)?;
            if frame >= config.warmup {
                times[i].push(result.shaded.duration.as_ms());
                invocations[i] = result.shaded.fragment_invocations;
            }
            done += 1;
            progress(done, total);
        }
    }
    let summaries: Vec<Summary> = times
        .iter()
        .map(|t| Summary::of(t).ok_or_else(|| Error::Unsupported("a timing was not finite".into())))
        .collect::<Result<_>>()?;
    let baseline_of = |material: &str| {
        cases
            .iter()
            .position(|c| c.stack.name == material && c.variant.model == Model::Ggx)
            .map(|i| summaries[i].median)
            .expect("with_baselines gives every material a ggx case")
    };
    let executable_stats = passes
        .iter()
        .map(|p| {
            Ok(Some(match p.pipeline.executable_statistics()? {
                Some(s) => serde_json::to_value(s).expect("statistics serialise"),
                None => serde_json::Value::from(UNSUPPORTED),
            }))
        })
        .collect::<Result<Vec<_>>>()?;
    let report = &gpu.device.report;
    Ok(Results {
        device: DeviceInfo {
            name: report.name.clone(),
            driver: format!("{} {}", report.driver_name, report.driver_info),
            api_version: report.api_version.clone(),
            vendor_id: report.vendor_id,
            subgroup_size: Some(report.subgroup_size),
        },
        git_rev: git_rev(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        size: [config.width, config.height],
        lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
        scene: config.scene,
        counter: None,
        lighting: (config.lighting != Lighting::default()).then(|| config.lighting.to_toml()),
        runs: cases
            .iter()
            .zip(&pass_of)
            .zip(summaries.iter().zip(&invocations))
            .map(|((case, &p), (s, inv))| Run {
                variant: case.variant.to_string(),
                material: case.stack.name.clone(),
                frames: config.frames,
                min_ms: s.min,
                median_ms: s.median,
                mean_ms: s.mean,
                max_ms: s.max,
                stdev_ms: s.stdev,
                ratio_to_baseline: s.median / baseline_of(&case.stack.name),
                fragment_invocations: *inv,
                pipeline_ms: passes[p].pipeline.creation.duration.as_secs_f64() * 1e3,
                pipeline_cache_hit: passes[p].pipeline.creation.cache_hit,
                spirv_bytes: passes[p].spirv_bytes,
                instructions: None,
                instructions_total: None,
                instructions_large: None,
                instructions_total_large: None,
                instructions_per_pixel: None,
                instructions_per_pixel_ratio: None,
                executable_stats: executable_stats[p].clone(),
                active_layers: (case.variant.model != Model::Ggx)
                    .then(|| {
                        ActiveLayers::of(&case.stack, config.scene, config.width, config.height)
                    })
                    .flatten(),
                image_error: None,
                reference_noise: None,
                image_error_vs_fp32: None,
            })
            .collect(),
    })
}

impl Results {
    /// The `ggx` run on `material`: every other run's ratios divide by it.
    pub fn baseline_of(&self, material: &str) -> Option<&Run> {
        self.runs
            .iter()
            .find(|r| r.material == material && r.variant.starts_with("model=ggx"))
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
             instructions_per_pixel_ratio,flip,rmse,max_relative_error,flip_vs_fp32\n",
        );
        for r in &self.runs {
            out += &format!(
                "\"{}\",\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
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
                opt_f(r.image_error_vs_fp32.map(|e| e.flip))
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
