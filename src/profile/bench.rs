//! `lamina bench`: every variant's pipeline built up front, frames interleaved round-robin so
//! drift hits all variants alike, warm-up frames discarded, the shaded draw timed by the
//! profiler scope and its fragment invocations counted; each variant's median divided by the
//! `ggx` baseline's from the same run (DESIGN.md §7). The draw shades a [`Scene`]: the
//! full-screen grid (every pixel once, the talk's setup) or `render`'s sphere.
//!
//! A run's cases are a [`Plan`], expanded once (the baselines added) and handed to every
//! measurement of the run — the timing here, the image errors, the instruction counts — which
//! each return their values per case, in the plan's order, for [`Results`] to record.

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::model::LayerParams;
use crate::render::forward::ForwardPass;
use crate::render::lights::Lighting;
use crate::render::scene::Scene;
use crate::render::{PassCache, RenderedFrame, Renderer};
use crate::stats::Summary;
use crate::tables::environment::EnvDesc;
use crate::vk::ExecutableStats;

use super::plan::{Case, Plan};
use super::results::{ActiveLayers, DeviceInfo, Results, Run, UNSUPPORTED};

/// How a run draws: its plan, its scene at one size, the frames and the lighting.
pub struct BenchConfig {
    pub plan: Plan,
    pub scene: Scene,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
    /// The environment's scale and the analytic lights of every frame.
    pub lighting: Lighting,
}

/// Puts `scene`'s mesh in front of `renderer`'s camera for a `width`×`height` frame.
pub fn place_scene(renderer: &mut Renderer, scene: Scene, width: u32, height: u32) -> Result<()> {
    let mesh = scene.mesh(&renderer.camera, width, height);
    renderer.set_mesh(&mesh)
}

/// One case's draw over a bench's scene, ready to render single frames: what a capture
/// records (`bench --capture`).
pub struct CaseDraw<'g> {
    renderer: Renderer<'g>,
    pass: ForwardPass,
    layers: Vec<LayerParams>,
    width: u32,
    height: u32,
}

impl<'g> CaseDraw<'g> {
    pub fn new(
        gpu: &'g Gpu,
        equirect: &HdrImage,
        config: &BenchConfig,
        case: &Case,
    ) -> Result<Self> {
        let mut renderer = Renderer::new(gpu, equirect, EnvDesc::default())?;
        renderer.lighting = config.lighting.clone();
        place_scene(&mut renderer, config.scene, config.width, config.height)?;
        renderer.set_surface(case.stack.surface.as_ref())?;
        let pass = renderer.prepare(&case.pass_key(&config.lighting)?)?;
        Ok(Self {
            renderer,
            pass,
            layers: case.stack.params(),
            width: config.width,
            height: config.height,
        })
    }

    /// One frame, as the bench times it.
    pub fn render(&mut self) -> Result<RenderedFrame> {
        self.renderer
            .render(&self.pass, &self.layers, self.width, self.height)
    }
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
    let cases = config.plan.cases();
    let mut renderer = Renderer::new(gpu, equirect, EnvDesc::default())?;
    let layers: Vec<Vec<LayerParams>> = cases.iter().map(|c| c.stack.params()).collect();
    place_scene(&mut renderer, config.scene, config.width, config.height)?;
    renderer.lighting = config.lighting.clone();
    let keys = cases
        .iter()
        .map(|c| c.pass_key(&config.lighting))
        .collect::<Result<Vec<_>>>()?;
    let mut passes = PassCache::new();
    for key in &keys {
        passes.get(&mut renderer, key)?;
    }
    let mut times = vec![Vec::new(); cases.len()];
    let mut invocations = vec![None; cases.len()];
    let total = (config.warmup + config.frames) * cases.len() as u32;
    let mut done = 0;
    for frame in 0..config.warmup + config.frames {
        for (i, case) in cases.iter().enumerate() {
            renderer.set_surface(case.stack.surface.as_ref())?;
            let pass = passes.get(&mut renderer, &keys[i])?;
            let result = renderer.render(pass, &layers[i], config.width, config.height)?;
            if frame >= config.warmup {
                times[i].push(result.shaded.duration.as_ms());
                invocations[i] = result.shaded.fragment_invocations;
            }
            done += 1;
            progress(done, total);
        }
    }
    let timings = keys
        .iter()
        .zip(times.iter().zip(invocations))
        .map(|(key, (times, fragment_invocations))| {
            let pass = passes.find(&renderer, key).expect("prepared above");
            Ok(CaseTiming {
                summary: Summary::of(times)
                    .ok_or_else(|| Error::Unsupported("a timing was not finite".into()))?,
                fragment_invocations,
                pipeline_ms: pass.creation_ms(),
                pipeline_cache_hit: pass.cache_hit(),
                spirv_bytes: pass.spirv_bytes,
                executable_stats: pass.pipeline().executable_statistics()?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(results(gpu, config, timings))
}

/// What the bench measured of one case (`profile::bench::run`).
pub struct CaseTiming {
    pub summary: Summary,
    pub fragment_invocations: Option<u64>,
    pub pipeline_ms: f64,
    pub pipeline_cache_hit: Option<bool>,
    pub spirv_bytes: usize,
    /// `None` where the device does not report statistics.
    pub executable_stats: Option<Vec<ExecutableStats>>,
}

/// A case's run as the bench timed it, `baseline` the median of its material's `ggx` run.
fn timed_run(case: &Case, t: &CaseTiming, baseline: f64, config: &BenchConfig) -> Run {
    let s = t.summary;
    Run {
        variant: case.variant,
        material: case.stack.name.clone(),
        frames: config.frames,
        min_ms: s.min,
        median_ms: s.median,
        mean_ms: s.mean,
        max_ms: s.max,
        stdev_ms: s.stdev,
        ratio_to_baseline: s.median / baseline,
        fragment_invocations: t.fragment_invocations,
        pipeline_ms: t.pipeline_ms,
        pipeline_cache_hit: t.pipeline_cache_hit,
        spirv_bytes: t.spirv_bytes,
        instructions: None,
        instructions_total: None,
        instructions_large: None,
        instructions_total_large: None,
        instructions_per_pixel: None,
        instructions_per_pixel_ratio: None,
        executable_stats: Some(match &t.executable_stats {
            Some(stats) => serde_json::to_value(stats).expect("statistics serialise"),
            None => serde_json::Value::from(UNSUPPORTED),
        }),
        active_layers: (!case.is_baseline())
            .then(|| ActiveLayers::of(&case.stack, config.scene, config.width, config.height))
            .flatten(),
        image_error: None,
        reference_noise: None,
        reference_flip_floor: None,
        image_error_vs_fp32: None,
        lighting_error: None,
        model_error: None,
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

/// The runs of `config`'s plan as the bench timed them (`timings`, in plan order), with the
/// device and the command line; nothing counted or compared yet.
fn results(gpu: &Gpu, config: &BenchConfig, timings: Vec<CaseTiming>) -> Results {
    let cases = config.plan.cases();
    assert_eq!(
        cases.len(),
        timings.len(),
        "one timing per case of the plan"
    );
    let report = &gpu.device.report;
    let runs = cases
        .iter()
        .zip(&timings)
        .enumerate()
        .map(|(i, (case, t))| {
            let baseline = timings[config.plan.baseline_of(i)].summary.median;
            timed_run(case, t, baseline, config)
        })
        .collect();
    Results {
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
        environment: None,
        calibration: None,
        runs,
    }
}
