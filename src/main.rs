//! The `lamina` command line: a thin layer over the library.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::str::FromStr;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use lamina::imageio;
use lamina::material::Stack;
use lamina::model::fgd::ExactFgd;
use lamina::model::{tm2, tm6, Evaluation, LayerParams, NoTir};
use lamina::output::{EvalReport, EvalSample};
use lamina::profile::bench::{self, BenchConfig};
use lamina::render::Renderer;
use lamina::render::{eval::GpuEvaluator, furnace, sheet};
use lamina::shader::Model;
use lamina::shader::VariantKey;
use lamina::tables::environment::EnvDesc;
use lamina::vk::{DeviceSelector, InstanceDesc};
use lamina::Gpu;

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
    /// Time variants of the shaded draw, interleaved, against the ggx baseline.
    Bench(BenchArgs),
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

/// `WxH`, each side in 1..=16384.
#[derive(Clone, Copy, Debug)]
struct Size {
    width: u32,
    height: u32,
}

impl FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        const MAX: u32 = 16384;
        let (w, h) = s
            .split_once(['x', 'X'])
            .ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT, e.g. 640x360"))?;
        let side = |v: &str, name: &str| {
            v.trim()
                .parse::<u32>()
                .ok()
                .filter(|n| (1..=MAX).contains(n))
                .ok_or_else(|| format!("{name} `{v}` must be an integer in 1..={MAX}"))
        };
        Ok(Self {
            width: side(w, "width")?,
            height: side(h, "height")?,
        })
    }
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

/// Loads the material and builds its variant: axes the key leaves out come from the defaults,
/// the model from the material, and `max_layers` grows to fit the stack.
fn material_and_variant(material: &str, key: Option<&str>) -> Result<(Stack, VariantKey)> {
    let stack = Stack::resolve(material)?;
    let base = VariantKey {
        model: stack.model,
        max_layers: VariantKey::default()
            .max_layers
            .max(stack.layers.len() as u32),
        ..VariantKey::default()
    };
    let variant = match key {
        Some(k) => VariantKey::parse_over(k, base)?,
        None => base,
    };
    stack.check_fits(variant.max_layers)?;
    Ok((stack, variant))
}

fn eval(cli: &Cli, args: &EvalArgs) -> Result<()> {
    let (stack, variant) = material_and_variant(&args.material, args.variant.as_deref())?;
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
                .map(|&c| cpu_model(variant, &stack.params(), c))
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

/// The f64 oracle: the variant's model with exactly integrated FGD (its G2 form) and no TIR
/// correction.
fn cpu_model(variant: VariantKey, layers: &[LayerParams], cos_theta: f64) -> Evaluation {
    let fgd = ExactFgd::new(variant.g2);
    match variant.model {
        Model::Tm6 => tm6::evaluate(layers, cos_theta, &fgd, &NoTir),
        _ => tm2::evaluate(layers, cos_theta, &fgd, &NoTir),
    }
}

fn run_furnace(cli: &Cli, args: &FurnaceArgs) -> Result<()> {
    if !(1..=256).contains(&args.bins) {
        anyhow::bail!("--bins {}: must be in 1..=256", args.bins);
    }
    let (stack, variant) = material_and_variant(&args.material, args.variant.as_deref())?;
    let gpu = open_gpu(cli)?;
    let layers = stack.params();
    let bins = furnace::gpu(&gpu, variant, &layers, 256, args.bins)?;
    check_validation(&gpu)?;
    let cosines: Vec<f64> = bins.iter().map(|b| b.cos_theta).collect();
    let cpu = furnace::cpu(&cosines, |c| {
        if variant.model == Model::Ggx {
            let top = VariantKey {
                model: Model::Tm2,
                ..variant
            };
            cpu_model(top, &layers[..1], c).reflectance
        } else {
            cpu_model(variant, &layers, c).reflectance
        }
    });
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
        max_layers = max_layers.max(stack.layers.len() as u32);
        rows.push(sheet::SheetRow {
            name: stack.name.clone(),
            layers: stack.params(),
        });
    }
    let base = VariantKey {
        max_layers: VariantKey::default().max_layers.max(max_layers),
        ..VariantKey::default()
    };
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
    let (stack, base) = material_and_variant(&args.material, None)?;
    let variants = args
        .variants
        .iter()
        .map(|k| {
            let v = VariantKey::parse_over(k, base)?;
            stack.check_fits(v.max_layers)?;
            Ok(v)
        })
        .collect::<Result<Vec<_>>>()?;
    let gpu = open_gpu(cli)?;
    let config = BenchConfig {
        variants,
        material: stack.name.clone(),
        layers: stack.params(),
        width: args.size.width,
        height: args.size.height,
        frames: args.frames,
        warmup: args.warmup,
    };
    let results = bench::run(&gpu, &equirect, &config, |done, total| {
        eprint!("\rframe {done}/{total}");
        if done == total {
            eprintln!();
        }
    })?;
    check_validation(&gpu)?;
    print!("{}", results.table());
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&results)?;
        imageio::write_atomically(path, |temp| {
            std::fs::write(temp, &text).map_err(|e| e.to_string())
        })?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &args.csv {
        let text = results.csv();
        imageio::write_atomically(path, |temp| {
            std::fs::write(temp, &text).map_err(|e| e.to_string())
        })?;
        println!("wrote {}", path.display());
    }
    Ok(())
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
    let (stack, variant) = material_and_variant(&args.material, args.variant.as_deref())?;
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
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
