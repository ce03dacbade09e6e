//! The `lamina` command line: a thin layer over the library.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::str::FromStr;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use lamina::imageio;
use lamina::model::LayerParams;
use lamina::render::Renderer;
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
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Image size.
    #[arg(long, default_value = "640x360", value_name = "WxH")]
    size: Size,
    /// Equirectangular OpenEXR environment map.
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr")]
    env: PathBuf,
    /// Shader variant, e.g. `model=ggx,fp16=on` (unset axes take their defaults).
    #[arg(long, value_name = "KEY", default_value_t = VariantKey::default())]
    variant: VariantKey,
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

fn render(cli: &Cli, args: &RenderArgs) -> Result<()> {
    let env_path = asset_path(&args.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let gpu = open_gpu(cli)?;
    let mut renderer = Renderer::new(&gpu, &equirect, EnvDesc::default())?;
    let pass = renderer.prepare(args.variant)?;
    let layers = [LayerParams {
        ior: [0.143245, 0.377423, 1.43919],
        kappa: [3.98479, 2.3847, 1.60434],
        roughness: 0.2,
        depth: 0.0,
        sigma_s: [0.0; 3],
        sigma_a: [0.0; 3],
        g: 0.0,
    }];
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
    println!("variant:     {}", args.variant);
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
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
