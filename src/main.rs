//! The `lamina` command line: a thin layer over the library.

mod tables_cli;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use indicatif::{ProgressBar, ProgressStyle};
use lamina::imageio;
use lamina::material::{resolve_with_variant, Stack};
use lamina::output::{EvalReport, EvalSample};
use lamina::profile::bench::{self, BenchConfig, Case};
use lamina::profile::sweep;
use lamina::profile::{counter, diff, report};
use lamina::render::Renderer;
use lamina::render::{eval::GpuEvaluator, furnace, sheet};
use lamina::shader::VariantKey;
use lamina::tables::environment::EnvDesc;
use lamina::vk::{DeviceSelector, InstanceDesc};
use lamina::{Gpu, Size};

#[derive(Parser)]
#[command(
    name = "lamina",
    version,
    about = "Transfer-matrix layered materials on Vulkan, measured"
)]
struct Cli {
    /// Vulkan device: index (see `lamina devices`) or part of its name.
    #[arg(long, global = true, value_name = "INDEX|NAME")]
    device: Option<DeviceSelector>,
    /// Enable the Khronos validation layer.
    #[arg(long, global = true)]
    validation: bool,
    /// Enable synchronization validation too (implies --validation).
    #[arg(long, global = true)]
    sync_validation: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List Vulkan devices and the features lamina uses.
    Devices,
    /// Render the sphere under an environment to EXR and PNG, and print the GPU time.
    Render(RenderArgs),
    /// Evaluate a material's model at view cosines: total R, T and the lobes.
    Eval(EvalArgs),
    /// White-furnace test: reflected energy per view angle under a uniform white environment.
    Furnace(FurnaceArgs),
    /// Render every preset material in each variant into one tiled PNG.
    Sheet(SheetArgs),
    /// Interactive viewer: edit the layer stack, switch variants, watch the GPU time.
    View(ViewArgs),
    /// Time variants of the shaded draw, interleaved, against the ggx baseline.
    Bench(BenchArgs),
    /// Run a sweep file (profiling/sweeps/*.toml): results.json, results.csv and charts per study.
    Sweep(SweepArgs),
    /// Write profiling/REPORT.md from sweep results, beside the talk's published figures.
    Report(ReportArgs),
    /// Compare two sets of results (commits, drivers, devices): time as each run's ratio to its
    /// ggx baseline, JIT instruction counts as they are.
    Diff(DiffArgs),
    /// Build a precomputed table (or load it from the cache), print its statistics and error
    /// studies.
    Tables(TablesArgs),
    /// Internal: counts instructions of shaded draws; runs under callgrind, started by
    /// `--counter instructions`.
    #[command(hide = true)]
    CountWorker(CountWorkerArgs),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum CounterArg {
    /// Instructions executed by lavapipe while it runs the shaded draw (valgrind callgrind).
    Instructions,
}

#[derive(clap::Args)]
struct SweepArgs {
    /// A study or a suite (`studies = [...]`), e.g. profiling/sweeps/reproduce.toml.
    file: PathBuf,
    /// Output directory: results of one study go here, a suite's in one sub-directory per study.
    #[arg(long, value_name = "DIR", default_value = "out/sweep")]
    out: PathBuf,
    /// Count instructions too (overrides the sweep file's `counter`).
    #[arg(long, value_enum)]
    counter: Option<CounterArg>,
    /// Equirectangular OpenEXR environment map.
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr")]
    env: PathBuf,
    /// Check and expand the file, print the cases, and stop before any GPU work.
    #[arg(long)]
    dry_run: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum TableKind {
    /// Karis's 2-channel split-sum table (the fgd=karis axis value).
    FgdKaris,
    /// Belcour, Bati & Barla 2020 4-channel table.
    FgdBelcour,
    /// The 64⁴ FGD table as a 64×64×4096 3-D image.
    #[value(name = "fgd-4d")]
    Fgd4d,
    /// The talk's 64×64×2048 resampling of the 4-D table.
    FgdResampled,
    /// The 3-D TIR table (tir=lut32 / lut16).
    Tir,
}

#[derive(clap::Args)]
struct TablesArgs {
    #[arg(value_enum)]
    kind: TableKind,
    /// Write the table in the reference's binary format (ALGORITHMS.md §6).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Write a heat map of the table's comparison (tir: |analytic − table|) as PNG.
    #[arg(long, value_name = "FILE.png")]
    error_map: Option<PathBuf>,
    /// Texels per axis.
    #[arg(long, default_value_t = 64, value_name = "N")]
    size: u32,
    /// Samples per texel (default: the size the renderer uses).
    #[arg(long, value_name = "N")]
    samples: Option<u32>,
    /// Build even when a valid cached table exists.
    #[arg(long)]
    rebuild: bool,
    /// fgd-resampled: the κ filter of the table --out writes (every filter is measured).
    #[arg(long, value_enum, default_value = "box")]
    filter: lamina::tables::fgd::Filter,
}

#[derive(clap::Args)]
struct ReportArgs {
    /// Result directories: a study's (holding study.json) or a parent of several.
    #[arg(default_value = "profiling/results/lavapipe/reproduce")]
    dirs: Vec<PathBuf>,
    #[arg(long, value_name = "FILE", default_value = "profiling/REPORT.md")]
    out: PathBuf,
}

#[derive(clap::Args)]
struct DiffArgs {
    /// The older results: a results.json, a study's directory, or a `lamina sweep` output
    /// directory (its studies pair by name).
    old: PathBuf,
    /// The newer results, in the same forms.
    new: PathBuf,
    /// Exit with an error when a run's JIT instruction count grew by more than PCT percent, or
    /// when a run or study of OLD cannot be checked in NEW (instruction counts are
    /// deterministic; timings are too noisy on lavapipe to gate on).
    #[arg(long, value_name = "PCT", value_parser = parse_percent)]
    fail_above: Option<f64>,
}

fn parse_percent(text: &str) -> std::result::Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("`{text}` is not a percentage ≥ 0")),
    }
}

#[derive(clap::Args)]
struct CountWorkerArgs {
    #[arg(long, value_name = "FILE")]
    job: PathBuf,
    #[arg(long, value_name = "FILE")]
    env: PathBuf,
    #[arg(long, value_name = "WxH")]
    size: Size,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// A variant to time (repeat the flag); axes not given come from the defaults and the
    /// material. The ggx baseline is added when absent.
    #[arg(long = "variant", value_name = "KEY", required = true)]
    variants: Vec<String>,
    /// Material file or preset name.
    #[arg(long, value_name = "FILE|PRESET", default_value = "varnished-gold")]
    material: String,
    #[arg(long, default_value = "640x360", value_name = "WxH")]
    size: Size,
    /// Measured frames per variant.
    #[arg(long, default_value_t = 20, value_name = "N")]
    frames: u32,
    /// Frames per variant rendered first and discarded.
    #[arg(long, default_value_t = 2, value_name = "N")]
    warmup: u32,
    /// Equirectangular OpenEXR environment map.
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr")]
    env: PathBuf,
    /// Write the results as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write the results as CSV.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Also count each variant's instructions under callgrind (lavapipe only).
    #[arg(long, value_enum)]
    counter: Option<CounterArg>,
    /// Resolution of the counted draw (instructions grow with covered pixels).
    #[arg(long, default_value = "48x48", value_name = "WxH")]
    counter_size: Size,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Backend {
    Cpu,
    Gpu,
}

#[derive(clap::Args)]
struct EvalArgs {
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    /// View cosines, comma-separated, each in (0, 1].
    #[arg(
        long = "cos",
        value_name = "LIST",
        value_delimiter = ',',
        required = true
    )]
    cosines: Vec<f64>,
    #[arg(long, value_enum, default_value_t = Backend::Gpu)]
    backend: Backend,
    /// Shader variant; axes not given come from the defaults and the material's model.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Print the JSON of DESIGN.md §5 instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct FurnaceArgs {
    /// Material file or preset name.
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    /// Shader variant; axes not given come from the defaults and the material's model.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Number of view-cosine bins.
    #[arg(long, default_value_t = 10, value_name = "N")]
    bins: usize,
}

#[derive(clap::Args)]
struct SheetArgs {
    /// Variants, one column each (default: model=tm2 and model=tm6).
    #[arg(long = "variant", value_name = "KEY")]
    variants: Vec<String>,
    /// Side of one tile in pixels.
    #[arg(long, default_value_t = 256, value_name = "PIXELS")]
    tile: u32,
    /// Equirectangular OpenEXR environment map.
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr")]
    env: PathBuf,
    #[arg(long, value_name = "FILE.png", default_value = "out/sheet.png")]
    out: PathBuf,
    /// Exposure of the PNG, in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Image size.
    #[arg(long, default_value = "640x360", value_name = "WxH")]
    size: Size,
    /// Equirectangular OpenEXR environment map.
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr")]
    env: PathBuf,
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET", default_value = "gold")]
    material: String,
    /// Shader variant, e.g. `model=ggx,fp16=on`; axes not given take their defaults, with the
    /// model from the material file.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Linear HDR output (RGBA half).
    #[arg(long, value_name = "FILE.exr", default_value = "out/render.exr")]
    out: PathBuf,
    /// Tone-mapped PNG output.
    #[arg(long, value_name = "FILE.png", default_value = "out/render.png")]
    png: PathBuf,
    /// Frames rendered and discarded before the measured one (the first frame on lavapipe
    /// includes the shader's JIT compilation).
    #[arg(long, default_value_t = 1, value_name = "N")]
    warmup: u32,
    /// Exposure of the PNG, in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
}

#[derive(clap::Args)]
struct ViewArgs {
    /// Window size.
    #[arg(long, default_value = "1280x720", value_name = "WxH")]
    size: Size,
    /// Equirectangular OpenEXR environment map (the picker lists its directory's maps).
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr")]
    env: PathBuf,
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET", default_value = "gold")]
    material: String,
    /// Shader variant to start with; axes not given take their defaults.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Save the last frame (the swapchain image, UI included) as PNG; needs --frames.
    #[arg(long, value_name = "FILE.png", requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Exit after N frames.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// Resize the window to WxH half-way through --frames (exercises swapchain recreation).
    #[arg(long, value_name = "WxH", requires = "frames")]
    resize: Option<Size>,
    /// Save the edited stack to FILE on exit (what the Save button writes).
    #[arg(long, value_name = "FILE.toml")]
    save_stack: Option<PathBuf>,
}

fn view(cli: &Cli, args: &ViewArgs) -> Result<()> {
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    let env = asset_path(&args.env);
    let env_dir = env
        .parent()
        .map(Path::to_owned)
        .unwrap_or_else(|| PathBuf::from("."));
    let report = lamina::viewer::run(lamina::viewer::ViewOptions {
        stack,
        variant,
        env,
        env_dir,
        width: args.size.width,
        height: args.size.height,
        screenshot: args.screenshot.clone(),
        frames: args.frames,
        resize: args.resize.map(|s| (s.width, s.height)),
        save_stack: args.save_stack.clone(),
        instance: InstanceDesc {
            validation: cli.validation,
            sync_validation: cli.sync_validation,
            surface: true,
        },
        selector: cli.device.clone().unwrap_or_default(),
    })?;
    println!(
        "{} frame(s), final size {}x{}, swapchain built {} time(s)",
        report.frames, report.final_size.0, report.final_size.1, report.swapchain_builds
    );
    if let Some(path) = &args.screenshot {
        println!("wrote {}", path.display());
    }
    if let Some(path) = &args.save_stack {
        println!("wrote {}", path.display());
    }
    if cli.validation || cli.sync_validation {
        let problems = report.validation_problems;
        if problems > 0 {
            anyhow::bail!(
                "the validation layer reported {problems} problem(s); see the messages above"
            );
        }
    }
    Ok(())
}

/// A relative asset path that does not exist under the working directory is looked up in the
/// source tree the binary was built from, so `lamina render` works from any directory.
fn asset_path(path: &Path) -> PathBuf {
    if path.is_relative() && !path.exists() {
        let in_tree = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
        if in_tree.exists() {
            return in_tree;
        }
    }
    path.to_owned()
}

fn open_gpu(cli: &Cli) -> Result<Gpu> {
    let instance = InstanceDesc {
        validation: cli.validation,
        sync_validation: cli.sync_validation,
        surface: false,
    };
    let selector = cli.device.clone().unwrap_or_default();
    Ok(Gpu::new(instance, &selector)?)
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

fn devices(cli: &Cli) -> Result<()> {
    let instance = lamina::vk::Instance::new(InstanceDesc {
        validation: cli.validation,
        sync_validation: cli.sync_validation,
        surface: false,
    })?;
    for d in lamina::vk::enumerate(&instance)? {
        println!("[{}] {} ({})", d.index, d.name, d.device_type);
        println!(
            "    driver:                 {} — {}",
            d.driver_name, d.driver_info
        );
        println!("    Vulkan API:             {}", d.api_version);
        println!("    vendor id:              {:#06x}", d.vendor_id);
        println!("    shaderFloat16 (fp16):   {}", yes(d.shader_float16));
        println!(
            "    timestamps:             {} ({} valid bits, {} ns/tick)",
            yes(d.timestamps),
            d.timestamp_valid_bits,
            d.timestamp_period_ns
        );
        println!("    pipeline statistics:    {}", yes(d.pipeline_statistics));
        println!(
            "    pipeline executables:   {}",
            yes(d.pipeline_executable_properties)
        );
        println!(
            "    1.3 core (dyn. rendering, sync2, host query reset): {}",
            yes(d.dynamic_rendering && d.synchronization2 && d.host_query_reset)
        );
        println!("    max 3-D image side:     {}", d.max_image_dimension_3d);
    }
    Ok(())
}

fn eval(cli: &Cli, args: &EvalArgs) -> Result<()> {
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    if let Some(c) = args
        .cosines
        .iter()
        .find(|c| !(c.is_finite() && **c > 0.0 && **c <= 1.0))
    {
        anyhow::bail!("--cos: {c} is not a view cosine; each must be in (0, 1]");
    }
    let (backend, results) = match args.backend {
        Backend::Cpu => (
            "cpu",
            args.cosines
                .iter()
                .map(|&c| lamina::oracle::evaluate(variant, &stack.params(), c))
                .collect::<Vec<_>>(),
        ),
        Backend::Gpu => {
            let gpu = open_gpu(cli)?;
            let evaluator = GpuEvaluator::new(&gpu, variant)?;
            let results = evaluator.evaluate(&stack.params(), &args.cosines)?;
            check_validation(&gpu)?;
            ("gpu", results)
        }
    };
    let report = EvalReport {
        material: stack.name.clone(),
        model: variant.model.to_string(),
        backend: backend.into(),
        samples: args
            .cosines
            .iter()
            .zip(&results)
            .map(|(&c, e)| EvalSample::new(c, e))
            .collect(),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table());
    }
    Ok(())
}

fn run_furnace(cli: &Cli, args: &FurnaceArgs) -> Result<()> {
    if !(1..=256).contains(&args.bins) {
        anyhow::bail!("--bins {}: must be in 1..=256", args.bins);
    }
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    let gpu = open_gpu(cli)?;
    let layers = stack.params();
    let bins = furnace::gpu(&gpu, variant, &layers, 256, args.bins)?;
    check_validation(&gpu)?;
    let cosines: Vec<f64> = bins.iter().map(|b| b.cos_theta).collect();
    let cpu = furnace::cpu(variant, &layers, &cosines);
    println!("white furnace: {} ({variant})", stack.name);
    println!(
        "GPU: the sphere rendered at 256x256 under radiance 1, binned by n·v (FGD: {})",
        variant.fgd
    );
    println!("CPU: the f64 model with exactly integrated FGD at each bin's mean n·v");
    println!(
        "{:>7}  {:>22}  {:>22}  {:>7}",
        "cos θ", "GPU energy R G B", "CPU energy R G B", "pixels"
    );
    let rgb = |v: [f64; 3]| format!("{:.4} {:.4} {:.4}", v[0], v[1], v[2]);
    for (g, c) in bins.iter().zip(&cpu) {
        println!(
            "{:>7.4}  {:>22}  {:>22}  {:>7}",
            g.cos_theta,
            rgb(g.energy),
            rgb(c.energy),
            g.samples
        );
    }
    for (name, set) in [("GPU", &bins), ("CPU", &cpu)] {
        let (min, mean, max) = furnace::summary(set);
        println!("{name}: min {min:.5}  mean {mean:.5}  max {max:.5}");
    }
    Ok(())
}

fn run_sheet(cli: &Cli, args: &SheetArgs) -> Result<()> {
    let env_path = asset_path(&args.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let keys: Vec<String> = if args.variants.is_empty() {
        vec!["model=tm2".into(), "model=tm6".into()]
    } else {
        args.variants.clone()
    };
    let mut rows = Vec::new();
    let mut max_layers = 1;
    for path in lamina::material::presets() {
        let stack = Stack::load(&path)?;
        max_layers = max_layers.max(stack.layers.len());
        rows.push(sheet::SheetRow {
            name: stack.name.clone(),
            layers: stack.params(),
        });
    }
    let base = lamina::material::base_variant(VariantKey::default().model, max_layers);
    let variants = keys
        .iter()
        .map(|k| VariantKey::parse_over(k, base))
        .collect::<Result<Vec<_>, _>>()?;
    let gpu = open_gpu(cli)?;
    let (w, h, rgba) = sheet::render(&gpu, &equirect, &rows, &variants, args.tile, args.exposure)?;
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
        variants
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(" | ")
    );
    println!("wrote {}", args.out.display());
    Ok(())
}

fn run_bench(cli: &Cli, args: &BenchArgs) -> Result<()> {
    if args.frames == 0 {
        anyhow::bail!("--frames 0: at least one measured frame is needed");
    }
    let env_path = asset_path(&args.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let stack = Stack::resolve(&args.material)?;
    let cases = args
        .variants
        .iter()
        .map(|k| {
            let variant = stack.variant(Some(k))?;
            Ok(Case {
                variant,
                stack: stack.clone(),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let gpu = open_gpu(cli)?;
    let config = BenchConfig {
        cases,
        width: args.size.width,
        height: args.size.height,
        frames: args.frames,
        warmup: args.warmup,
    };
    let bar = progress_bar("frames");
    let mut results = bench::run(&gpu, &equirect, &config, |done, total| {
        bar.set_length(u64::from(total));
        bar.set_position(u64::from(done));
    })?;
    bar.finish_and_clear();
    check_validation(&gpu)?;
    if args.counter.is_some() {
        let setup = counter::CounterSetup::for_device(&gpu, &env_path)?;
        let all = config.with_baselines();
        let bar = progress_bar("counted (callgrind)");
        let size = (args.counter_size.width, args.counter_size.height);
        counter::add_counts(&mut results, &setup, &all, size, |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })?;
        bar.finish_and_clear();
    }
    print!("{}", results.table());
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&results)?;
        imageio::write_file_atomically(path, &text)?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &args.csv {
        let text = results.csv();
        imageio::write_file_atomically(path, &text)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
fn progress_bar(what: &str) -> ProgressBar {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{prefix:>28} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    bar.set_prefix(what.to_owned());
    bar
}

fn run_sweep(cli: &Cli, args: &SweepArgs) -> Result<()> {
    let (mut studies, suite) = sweep::load(&args.file)?;
    if let Some(CounterArg::Instructions) = args.counter {
        for s in &mut studies {
            s.counter.get_or_insert((48, 48));
        }
    }
    let dir_of = |s: &sweep::Study| {
        if suite {
            args.out.join(&s.name)
        } else {
            args.out.clone()
        }
    };
    let cases: usize = studies.iter().map(|s| s.points.len()).sum();
    println!(
        "{}: {} stud{}, {cases} case(s) (+ ggx baselines)",
        args.file.display(),
        studies.len(),
        if studies.len() == 1 { "y" } else { "ies" }
    );
    for s in &studies {
        println!(
            "  {:<22} {:>3} case(s) at {}x{}, {}+{} frames{}{}  -> {}",
            s.name,
            s.points.len(),
            s.width,
            s.height,
            s.warmup,
            s.frames,
            s.counter
                .map(|(w, h)| format!(", instructions at {w}x{h}"))
                .unwrap_or_default(),
            if s.skipped.is_empty() {
                String::new()
            } else {
                format!(", {} skipped (stack > max_layers)", s.skipped.len())
            },
            dir_of(s).display()
        );
    }
    if args.dry_run {
        for s in &studies {
            println!("{}:", s.name);
            for p in &s.points {
                println!("  {} | {}", p.case.variant, p.case.stack.name);
            }
        }
        return Ok(());
    }
    let env_path = asset_path(&args.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let gpu = open_gpu(cli)?;
    let setup = if studies.iter().any(|s| s.counter.is_some()) {
        Some(counter::CounterSetup::for_device(&gpu, &env_path)?)
    } else {
        None
    };
    let started = std::time::Instant::now();
    let mut written = Vec::new();
    for (k, study) in studies.iter().enumerate() {
        let bar = progress_bar(&format!("[{}/{}] {}", k + 1, studies.len(), study.name));
        let (results, meta) = sweep::run(
            &gpu,
            &equirect,
            study,
            setup.as_ref(),
            |what, done, total| {
                bar.set_message(what.to_owned());
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            },
        )?;
        bar.finish_and_clear();
        check_validation(&gpu)?;
        let dir = dir_of(study);
        let charts = sweep::write(&dir, study, &results, &meta)?;
        println!("\n== {} ({})", study.title, study.name);
        print!("{}", results.table());
        println!(
            "wrote {}/results.json, results.csv, {} chart(s)",
            dir.display(),
            charts.len()
        );
        written.push(dir);
    }
    let studies_read = report::collect(&written)?;
    let report_path = args.out.join("REPORT.md");
    let text = report::render(&studies_read, &report_path);
    imageio::write_file_atomically(&report_path, &text)?;
    println!(
        "\n{} stud{} in {:.0} s; report: {}",
        studies.len(),
        if studies.len() == 1 { "y" } else { "ies" },
        started.elapsed().as_secs_f64(),
        report_path.display()
    );
    Ok(())
}

fn run_tables(cli: &Cli, args: &TablesArgs) -> Result<()> {
    use lamina::tables::{cache, split_sum, tir};
    if !(2..=256).contains(&args.size) {
        anyhow::bail!("--size {}: allowed 2..=256 texels per axis", args.size);
    }
    if args.samples == Some(0) {
        anyhow::bail!("--samples 0: allowed 1 or more samples per texel");
    }
    match args.kind {
        TableKind::Tir => {}
        TableKind::FgdKaris => {
            if args.out.is_some() || args.error_map.is_some() {
                anyhow::bail!("fgd-karis: --out and --error-map apply to the tir table only");
            }
            let gpu = open_gpu(cli)?;
            let samples = args.samples.unwrap_or(split_sum::DEFAULT_SAMPLES);
            let started = std::time::Instant::now();
            let table = split_sum::SplitSumTable::build(
                &gpu,
                lamina::shader::G2::HeightCorrelated,
                args.size,
                samples,
            )?;
            println!(
                "fgd-karis: {0}x{0} (A, B), {samples} samples per texel, built in {1:.2} s on {2}",
                args.size,
                started.elapsed().as_secs_f64(),
                gpu.device.report.name
            );
            let mut worst = 0.0f64;
            for (i, j) in spot_points(args.size) {
                let (mu, alpha) = table.coordinates(i, j);
                let cpu =
                    split_sum::cpu_reference(mu, alpha, lamina::shader::G2::HeightCorrelated, 256);
                let gpu_v = table.texel(i, j);
                worst = worst
                    .max((f64::from(gpu_v[0]) - cpu[0]).abs())
                    .max((f64::from(gpu_v[1]) - cpu[1]).abs());
            }
            println!("spot check against the f64 reference at 16 texels: max |Δ| = {worst:.2e}");
            check_validation(&gpu)?;
            return Ok(());
        }
        TableKind::Fgd4d | TableKind::FgdResampled | TableKind::FgdBelcour => {
            return tables_cli::run(&open_gpu(cli)?, args);
        }
    }
    let gpu = open_gpu(cli)?;
    let samples = args.samples.unwrap_or(tir::DEFAULT_SAMPLES);
    let dir = cache::dir();
    let bar = progress_bar("tir table (η slices)");
    let started = std::time::Instant::now();
    let progress = |done: u32, total: u32| {
        bar.set_length(u64::from(total));
        bar.set_position(u64::from(done));
    };
    let (table, cached) = if args.rebuild {
        let table = tir::TirTable::build(&gpu, args.size, samples, progress)?;
        if let Some(d) = &dir {
            cache::store(d, &tir::cache_key(args.size, samples), &table.texels)?;
        }
        (table, false)
    } else {
        tir::TirTable::load_or_build(&gpu, args.size, samples, dir.as_deref(), progress)?
    };
    bar.finish_and_clear();
    let where_ = dir
        .as_deref()
        .map(|d| {
            cache::path_of(d, &tir::cache_key(args.size, samples))
                .display()
                .to_string()
        })
        .unwrap_or_else(|| "no cache directory".into());
    println!(
        "tir: {0}x{0}x{0} (μ, α, η), {samples} samples per texel, {1} ({2:.2} s) on {3}; cache: {where_}",
        args.size,
        provenance(cached),
        started.elapsed().as_secs_f64(),
        gpu.device.report.name
    );
    let n = table.texels.len() as f64;
    let (min, max) = table
        .texels
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let mean = table.texels.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    println!("values: min {min:.4}, mean {mean:.4}, max {max:.4}");
    let mut worst = 0.0f64;
    for (i, j) in spot_points(args.size) {
        let k = 1 + (i * 7 + j * 3) % (args.size - 2);
        let (mu, alpha, eta) = table.coordinates(i, j, k);
        let cpu = tir::cpu_reference(mu, alpha, eta, 256);
        worst = worst.max((f64::from(table.texel(i, j, k)) - cpu).abs());
    }
    println!("spot check against the f64 reference (256² midpoint rule) at 16 texels: max |Δ| = {worst:.2e}");
    let half_gap = table
        .texels
        .iter()
        .map(|&v| (f64::from(half::f16::from_f32(v).to_f32()) - f64::from(v)).abs())
        .fold(0.0f64, f64::max);
    println!("lut16 against lut32: max |Δ| = {half_gap:.2e} (half-float rounding of values ≤ 1: ≤ 2.44e-4)");
    let analytic = tir::error_against(&table, &lamina::model::tir::AnalyticTir);
    println!(
        "analytic estimator against the table ({} grid points, 0 < η < 1): MSE {:.4}, mean |Δ| {:.4}, \
         max |Δ| {:.3} at (μ, α, η) = ({:.3}, {:.3}, {:.3}); the talk: MSE 0.0764, max 0.5",
        analytic.points,
        analytic.mse,
        analytic.mean_abs,
        analytic.max_abs,
        analytic.worst_at.0,
        analytic.worst_at.1,
        analytic.worst_at.2
    );
    if let Some(path) = &args.out {
        let bytes = tir::reference_file_bytes(&table);
        imageio::write_file_atomically(path, &bytes)?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &args.error_map {
        let size = args.size;
        let panels = [0.3, 0.5, 0.7, 0.9]
            .iter()
            .map(|&eta: &f64| {
                let k = (eta * f64::from(size - 1)).round() as u32;
                let (_, _, eta_k) = table.coordinates(0, 0, k);
                let values = (0..size)
                    .map(|j| {
                        (0..size)
                            .map(|i| {
                                let (mu, alpha, eta) = table.coordinates(i, j, k);
                                let a = lamina::model::Tir::tir(
                                    &lamina::model::tir::AnalyticTir,
                                    mu,
                                    alpha,
                                    eta,
                                );
                                (a - f64::from(table.texel(i, j, k))).abs()
                            })
                            .collect()
                    })
                    .collect();
                (format!("η = {eta_k:.3}"), values)
            })
            .collect();
        lamina::profile::chart::HeatMap {
            title: "TIR: |analytic estimator − table|".into(),
            x_label: "μ (cos θ)".into(),
            y_label: "α".into(),
            x_range: (0.0, 1.0),
            y_range: (0.0, 1.0),
            panels,
            value_label: "absolute error".into(),
        }
        .write_png(path)?;
        println!("wrote {}", path.display());
    }
    check_validation(&gpu)
}

/// How a table came to be, for the `tables` commands' first line.
fn provenance(cached: bool) -> &'static str {
    if cached {
        "loaded from the cache"
    } else {
        "built"
    }
}

/// 16 texel indices spread over an n×n grid, corners included.
fn spot_points(n: u32) -> Vec<(u32, u32)> {
    let at = [0, (n - 1) / 3, 2 * (n - 1) / 3, n - 1];
    at.iter()
        .flat_map(|&i| at.iter().map(move |&j| (i, j)))
        .collect()
}

fn run_diff(args: &DiffArgs) -> Result<()> {
    let old = diff::load(&args.old)?;
    let new = diff::load(&args.new)?;
    let cmp = diff::diff(&old, &new, &args.old, &args.new)?;
    print!("{}", diff::render(&cmp));
    if let Some(pct) = args.fail_above {
        let problems = diff::gate(&cmp, pct);
        if !problems.is_empty() {
            anyhow::bail!(
                "--fail-above {pct}: {} problem(s) — JIT instructions grew by more than {pct} %, \
                 or the new results cannot be checked:\n  {}",
                problems.len(),
                problems.join("\n  ")
            );
        }
    }
    Ok(())
}

fn run_report(args: &ReportArgs) -> Result<()> {
    let studies = report::collect(&args.dirs)?;
    let text = report::render(&studies, &args.out);
    imageio::write_file_atomically(&args.out, &text)?;
    println!(
        "wrote {} ({} stud{})",
        args.out.display(),
        studies.len(),
        if studies.len() == 1 { "y" } else { "ies" }
    );
    Ok(())
}

fn count_worker(cli: &Cli, args: &CountWorkerArgs) -> Result<()> {
    let cases = counter::WorkerJob::read_cases(&args.job)?;
    let equirect = imageio::read_exr(&args.env).context("reading the environment map")?;
    let gpu = open_gpu(cli)?;
    counter::worker(&gpu, &equirect, &cases, args.size.width, args.size.height)?;
    check_validation(&gpu)
}

fn check_validation(gpu: &Gpu) -> Result<()> {
    let problems = gpu.device.validation_problems();
    if problems > 0 {
        anyhow::bail!(
            "the validation layer reported {problems} problem(s); see the messages above"
        );
    }
    Ok(())
}

fn render(cli: &Cli, args: &RenderArgs) -> Result<()> {
    let env_path = asset_path(&args.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    let layers = stack.params();
    let gpu = open_gpu(cli)?;
    let mut renderer = Renderer::new(&gpu, &equirect, EnvDesc::default())?;
    let pass = renderer.prepare(variant)?;
    for _ in 0..args.warmup {
        renderer.render(&pass, &layers, args.size.width, args.size.height)?;
    }
    let frame = renderer.render(&pass, &layers, args.size.width, args.size.height)?;
    if let Some(i) = frame
        .pixels
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        anyhow::bail!(
            "the render has a non-finite pixel at ({}, {}); nothing was written",
            i as u32 % frame.width,
            i as u32 / frame.width
        );
    }
    let problems = gpu.device.validation_problems();
    if problems > 0 {
        anyhow::bail!("the validation layer reported {problems} problem(s); see the messages above; nothing was written");
    }
    let (w, h) = (frame.width as usize, frame.height as usize);
    imageio::write_exr_rgba16f(&args.out, w, h, &frame.pixels)?;
    imageio::write_png_tonemapped(&args.png, w, h, &frame.pixels, args.exposure)?;

    println!(
        "device:      {} ({})",
        gpu.device.report.name, gpu.device.report.driver_info
    );
    println!("environment: {}", env_path.display());
    println!(
        "material:    {} ({} layers)",
        stack.name,
        stack.layers.len()
    );
    println!("variant:     {variant}");
    println!(
        "size:        {}x{} (measured after {} warm-up frame(s))",
        frame.width, frame.height, args.warmup
    );
    let invocations = |n: Option<u64>| n.map_or("n/a".to_string(), |n| n.to_string());
    println!(
        "shaded draw: {:.3} ms GPU, {} fragment invocations",
        frame.shaded.duration.as_ms(),
        invocations(frame.shaded.fragment_invocations)
    );
    println!(
        "sky draw:    {:.3} ms GPU, {} fragment invocations",
        frame.sky.duration.as_ms(),
        invocations(frame.sky.fragment_invocations)
    );
    println!(
        "wrote:       {}, {}",
        args.out.display(),
        args.png.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Devices => devices(&cli),
        Command::Render(args) => render(&cli, args),
        Command::Eval(args) => eval(&cli, args),
        Command::Furnace(args) => run_furnace(&cli, args),
        Command::Sheet(args) => run_sheet(&cli, args),
        Command::Bench(args) => run_bench(&cli, args),
        Command::Sweep(args) => run_sweep(&cli, args),
        Command::Report(args) => run_report(args),
        Command::Diff(args) => run_diff(args),
        Command::Tables(args) => run_tables(&cli, args),
        Command::View(args) => view(&cli, args),
        Command::CountWorker(args) => count_worker(&cli, args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
