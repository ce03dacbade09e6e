//! `lamina bench`: every variant's pipeline built up front, frames interleaved round-robin so
//! drift hits all variants alike, warm-up frames discarded, the shaded draw timed by the
//! profiler scope and its fragment invocations counted; each variant's median divided by the
//! `ggx` baseline's from the same run (DESIGN.md §7).
//!
//! The result file is read by other tools: keep `results.json`'s fields (issue #5's schema).

use serde::Serialize;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::model::LayerParams;
use crate::render::Renderer;
use crate::shader::{Model, VariantKey};
use crate::tables::environment::EnvDesc;

use super::stats::Summary;

pub struct BenchConfig {
    pub variants: Vec<VariantKey>,
    pub material: String,
    pub layers: Vec<LayerParams>,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
}

#[derive(Debug, Serialize)]
pub struct DeviceInfo {
    pub name: String,
    pub driver: String,
    pub api_version: String,
    pub vendor_id: u32,
}

#[derive(Debug, Serialize)]
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
    pub spirv_bytes: usize,
    /// Filled by the instruction counter (issue #5); `null` until then.
    pub instructions: Option<u64>,
    /// `VK_KHR_pipeline_executable_properties` statistics where offered; `null` otherwise.
    pub executable_stats: Option<serde_json::Value>,
}

#[derive(Debug, Serialize)]
pub struct Results {
    pub device: DeviceInfo,
    pub git_rev: String,
    pub command: String,
    pub size: [u32; 2],
    pub lp_num_threads: Option<String>,
    pub runs: Vec<Run>,
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
    let mut variants = config.variants.clone();
    if !variants.iter().any(|v| v.model == Model::Ggx) {
        variants.insert(0, baseline());
    }
    let mut renderer = Renderer::new(gpu, equirect, EnvDesc::default())?;
    let passes = variants
        .iter()
        .map(|&v| renderer.prepare(v))
        .collect::<Result<Vec<_>>>()?;
    let mut times = vec![Vec::new(); passes.len()];
    let mut invocations = vec![None; passes.len()];
    let total = (config.warmup + config.frames) * passes.len() as u32;
    let mut done = 0;
    for frame in 0..config.warmup + config.frames {
        for (i, pass) in passes.iter().enumerate() {
            let result = renderer.render(pass, &config.layers, config.width, config.height)?;
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
    let base = variants
        .iter()
        .position(|v| v.model == Model::Ggx)
        .map(|i| summaries[i].median)
        .expect("a ggx variant was added above");
    let report = &gpu.device.report;
    Ok(Results {
        device: DeviceInfo {
            name: report.name.clone(),
            driver: format!("{} {}", report.driver_name, report.driver_info),
            api_version: report.api_version.clone(),
            vendor_id: report.vendor_id,
        },
        git_rev: git_rev(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        size: [config.width, config.height],
        lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
        runs: variants
            .iter()
            .zip(&passes)
            .zip(summaries.iter().zip(&invocations))
            .map(|((v, pass), (s, inv))| Run {
                variant: v.to_string(),
                material: config.material.clone(),
                frames: config.frames,
                min_ms: s.min,
                median_ms: s.median,
                mean_ms: s.mean,
                max_ms: s.max,
                stdev_ms: s.stdev,
                ratio_to_baseline: s.median / base,
                fragment_invocations: *inv,
                pipeline_ms: pass.pipeline.creation_time.as_secs_f64() * 1e3,
                spirv_bytes: pass.spirv_bytes,
                instructions: None,
                executable_stats: None,
            })
            .collect(),
    })
}

impl Results {
    /// CSV with one row per run, the same fields as the JSON runs (variant keys quoted).
    pub fn csv(&self) -> String {
        let opt = |v: Option<u64>| v.map(|n| n.to_string()).unwrap_or_default();
        let mut out = String::from(
            "variant,material,frames,min_ms,median_ms,mean_ms,max_ms,stdev_ms,ratio_to_baseline,\
             fragment_invocations,pipeline_ms,spirv_bytes,instructions\n",
        );
        for r in &self.runs {
            out += &format!(
                "\"{}\",\"{}\",{},{},{},{},{},{},{},{},{},{},{}\n",
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
                opt(r.instructions)
            );
        }
        out
    }

    /// A table for the terminal.
    pub fn table(&self) -> String {
        let mut out = format!(
            "device: {} ({}), {}x{}, LP_NUM_THREADS={}, rev {}\n",
            self.device.name,
            self.device.driver,
            self.size[0],
            self.size[1],
            self.lp_num_threads.as_deref().unwrap_or("unset"),
            self.git_rev
        );
        out += &format!(
            "{:>9} {:>9} {:>9} {:>9} {:>8} {:>7} {:>9} {:>8}  variant\n",
            "min ms", "median", "mean", "max", "stdev", "×ggx", "pipe ms", "SPIR-V"
        );
        for r in &self.runs {
            out += &format!(
                "{:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>8.3} {:>7.2} {:>9.1} {:>8}  {}\n",
                r.min_ms,
                r.median_ms,
                r.mean_ms,
                r.max_ms,
                r.stdev_ms,
                r.ratio_to_baseline,
                r.pipeline_ms,
                r.spirv_bytes,
                r.variant
            );
        }
        out
    }
}
