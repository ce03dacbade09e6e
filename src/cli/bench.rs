//! `lamina bench`: variants of the shaded draw timed interleaved against the ggx baseline
//! (`lamina::profile::bench`), optionally with instruction counts; a table, JSON and CSV.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use lamina::imageio::{self, HdrImage};
use lamina::material::Stack;
use lamina::profile::bench::{self, BenchConfig, CaseDraw};
use lamina::profile::counter::{self, CounterSetup, CounterSizes};
use lamina::profile::image_error::{self, References};
use lamina::profile::plan::{Case, Plan};
use lamina::profile::results::Results;
use lamina::render::reference;
use lamina::render::scene::Scene;
use lamina::vk::Capturer;
use lamina::{Gpu, Size};

use super::args::{CounterArg, EnvArg};
use super::{
    asset_path, check_validation, follow, load_capturer, print_pipelines, progress_bar,
    save_pipelines, GlobalArgs,
};

#[derive(clap::Args)]
pub struct BenchArgs {
    /// A variant to time (repeat the flag); axes not given come from the defaults and the
    /// material. The ggx baseline is added when absent.
    #[arg(long = "variant", value_name = "KEY", required = true)]
    variants: Vec<String>,
    /// Material file or preset name.
    #[arg(long, value_name = "FILE|PRESET", default_value = "varnished-gold")]
    material: String,
    /// What the draw shades: `fullscreen`, every pixel once with the sphere's spread of view
    /// angles (the talk's setup), or `sphere`, `render`'s image.
    #[arg(long, default_value = "fullscreen", value_name = "SCENE")]
    scene: Scene,
    #[arg(long, default_value = "640x360", value_name = "WxH")]
    size: Size,
    /// Measured frames per variant.
    #[arg(long, default_value_t = 20, value_name = "N")]
    frames: u32,
    /// Frames per variant rendered first and discarded.
    #[arg(long, default_value_t = 2, value_name = "N")]
    warmup: u32,
    #[command(flatten)]
    env: EnvArg,
    /// Also measure each variant's image against the reference image of the material and
    /// scene (`lamina render --reference`, this many samples per lobe): mean FLIP, RMSE and the
    /// largest relative error in the table, JSON and CSV.
    #[arg(long, value_name = "N")]
    reference_spp: Option<u32>,
    /// With --reference-spp: the reference's seed (any u64). Its noise floor, the FLIP between
    /// it and the reference from the next seed, is printed beside each image error.
    #[arg(
        long,
        value_name = "SEED",
        default_value_t = 0,
        requires = "reference_spp"
    )]
    seed: u64,
    /// With --reference-spp: write each run's FLIP error map under this directory
    /// (error-maps/run-N.png, N the run's row in the JSON).
    #[arg(long, value_name = "DIR", requires = "reference_spp")]
    error_maps: Option<PathBuf>,
    /// Write the results as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write the results as CSV.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Also count each variant's instructions under callgrind (lavapipe only).
    #[arg(long, value_enum)]
    counter: Option<CounterArg>,
    /// The two resolutions of the counted draw, the smaller first: instructions per shaded
    /// pixel are the difference of the two counts over the added pixels, so what a draw costs
    /// whatever its size cancels; the whole-draw count is the smaller size's.
    #[arg(long, default_value = "48x48,96x96", value_name = "WxH,WxH")]
    counter_sizes: CounterSizes,
    /// Record one frame of the first `--variant` (after the timing, after its own warm-up
    /// frames) with RenderDoc into this file, for RenderDoc's UI, renderdoccmd or its Python
    /// module; needs RenderDoc's library (Debian: librenderdoc).
    #[arg(long, value_name = "FILE.rdc")]
    capture: Option<PathBuf>,
}

pub fn run(global: &GlobalArgs, args: &BenchArgs) -> Result<()> {
    if args.frames == 0 {
        anyhow::bail!("--frames 0: at least one measured frame is needed");
    }
    let env_path = asset_path(&args.env.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let stack = Stack::resolve(&args.material)?;
    let cases = args
        .variants
        .iter()
        .map(|k| {
            Ok(Case {
                variant: stack.variant(Some(k))?,
                stack: stack.clone(),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let capturer = load_capturer(args.capture.as_deref())?;
    let mut gpu = global.open_gpu()?;
    let config = BenchConfig {
        plan: Plan::new(cases),
        scene: args.scene,
        width: args.size.width,
        height: args.size.height,
        frames: args.frames,
        warmup: args.warmup,
        lighting: args.env.lights.lighting()?,
    };
    if let Some(spp) = args.reference_spp {
        reference::Convergence {
            spp,
            noise: None,
            seed: args.seed,
        }
        .check()?;
    }
    let bar = progress_bar("frames");
    print_pipelines(&mut gpu, Some(&bar));
    let mut results = bench::run(&gpu, &equirect, &config, follow(&bar))?;
    bar.finish_and_clear();
    check_validation(&gpu)?;
    if let Some(spp) = args.reference_spp {
        image_errors(&gpu, &equirect, &config, spp, args, &mut results)?;
    }
    if args.counter == Some(CounterArg::Instructions) {
        count(&gpu, &env_path, &config, args, &mut results)?;
    }
    print!("{}", results.table());
    print_image_errors(&results);
    if let Some(path) = &args.json {
        imageio::write_file_atomically(path, serde_json::to_string_pretty(&results)?)?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &args.csv {
        imageio::write_file_atomically(path, results.csv())?;
        println!("wrote {}", path.display());
    }
    if let (Some(capturer), Some(file)) = (capturer, &args.capture) {
        let case = &config.plan.cases()[config.plan.added_baselines()];
        capture(&gpu, &equirect, &config, case, capturer, file)?;
        println!(
            "capture: {} ({} | {})",
            file.display(),
            case.variant,
            case.stack.name
        );
    }
    save_pipelines(&gpu);
    Ok(())
}

/// Each run's image against the reference (`--reference-spp`), recorded in `results`, and
/// the error maps written where `--error-maps` asks.
fn image_errors(
    gpu: &Gpu,
    equirect: &HdrImage,
    config: &BenchConfig,
    spp: u32,
    args: &BenchArgs,
    results: &mut Results,
) -> Result<()> {
    let bar = progress_bar("image error");
    let (errors, maps) = image_error::measure(
        gpu,
        equirect,
        config,
        (spp, args.seed),
        &mut References::default(),
        &mut |what, done, total| {
            bar.set_message(what.to_owned());
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    results.record_image_errors(&errors);
    bar.finish_and_clear();
    check_validation(gpu)?;
    if let Some(dir) = &args.error_maps {
        for (run, map) in &maps {
            let path = dir.join(image_error::error_map_path(*run));
            imageio::write_png(&path, map.width as usize, map.height as usize, &map.rgba())?;
        }
        println!("wrote {} error map(s) under {}", maps.len(), dir.display());
    }
    Ok(())
}

/// One frame of `case` recorded with RenderDoc into `file`, after `config.warmup` frames
/// (the first compiles the shader on lavapipe).
fn capture(
    gpu: &Gpu,
    equirect: &HdrImage,
    config: &BenchConfig,
    case: &Case,
    mut capturer: Capturer,
    file: &Path,
) -> Result<()> {
    let mut draw = CaseDraw::new(gpu, equirect, config, case)?;
    for _ in 0..config.warmup {
        draw.render()?;
    }
    capturer.capture(&gpu.device, file, || draw.render())??;
    check_validation(gpu)
}

/// Each run's instructions (`--counter instructions`), counted under callgrind and recorded
/// in `results`.
fn count(
    gpu: &Gpu,
    env_path: &Path,
    config: &BenchConfig,
    args: &BenchArgs,
    results: &mut Results,
) -> Result<()> {
    let setup = CounterSetup::for_device(gpu, env_path)?;
    let bar = progress_bar("counted (callgrind)");
    let (info, counts) = counter::count_plans(
        &[&config.plan],
        &setup,
        config.scene,
        &config.lighting,
        args.counter_sizes,
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    results.record_counts(info, &counts[0]);
    bar.finish_and_clear();
    Ok(())
}

/// Each measured run's image error, its noise floor and its parts.
fn print_image_errors(results: &Results) {
    for run in &results.runs {
        if let Some(e) = run.image_error {
            let mut parts = Vec::new();
            if let Some(f) = run.reference_flip_floor {
                parts.push(format!(
                    "noise floor {f:.4}, a difference significant from {:.4}",
                    lamina::study::charts::SIGNIFICANT_FLOORS * f
                ));
            }
            if let (Some(l), Some(m)) = (run.lighting_error, run.model_error) {
                parts.push(format!("lighting {:.4}, model {:.4}", l.flip, m.flip));
            }
            let floor = if parts.is_empty() {
                String::new()
            } else {
                format!(" ({})", parts.join("; "))
            };
            println!(
                "image error: FLIP {:.4}{floor}, RMSE {:.2e}, max relative {:.1} %  {} | {}",
                e.flip,
                e.rmse,
                100.0 * e.max_relative,
                run.variant,
                run.material
            );
        }
    }
}
