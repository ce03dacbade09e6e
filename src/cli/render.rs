//! `lamina render`: the sphere under an environment, to EXR and PNG, with the GPU time of the
//! shaded draw. Nothing is written when a pixel is not finite or the validation layer spoke.

use std::path::PathBuf;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use lamina::imageio;
use lamina::material::{resolve_with_variant, Stack};
use lamina::profile::bench::place_scene;
use lamina::render::reference;
use lamina::render::scene::Scene;
use lamina::render::{PassKey, Renderer, TargetFormat};
use lamina::tables::environment::EnvDesc;
use lamina::variant::{Axis, Interfaces};

use super::args::{self, SceneArgs, SceneDefaults};
use super::{
    asset_path, check_validation, load_capturer, print_pipelines, require_extension,
    save_pipelines, stop_on_interrupt, GlobalArgs,
};

#[derive(clap::Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs<RenderScene>,
    /// What is drawn: `sphere`, the unit sphere before the sky, or `fullscreen`, the grid
    /// `bench` measures by default (every pixel once, with the sphere's spread of view angles).
    #[arg(long = "scene", default_value = "sphere", value_name = "SCENE")]
    shape: Scene,
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
    /// Exposure of the PNG, in stops (-24 to 24).
    #[arg(long, default_value = "0", allow_negative_numbers = true, value_parser = args::exposure)]
    exposure: f32,
    /// Render the reference image instead: the exact model's lobes integrated by Monte Carlo
    /// against the unfiltered environment and the lights — no split sum, no prefiltering, no
    /// FGD table (`render::reference`). Takes no --variant.
    #[arg(long)]
    reference: bool,
    /// With --reference: samples per lobe and pixel (whole frames of 16).
    #[arg(long, value_name = "N", default_value_t = 1024, requires = "reference")]
    spp: u32,
    /// With --reference: stop earlier once the image's relative noise (RMS standard error
    /// over mean radiance, from the frames' spread, which overstates it: the frames are
    /// stratified together) is at most this, e.g. 0.005.
    #[arg(long, value_name = "X", requires = "reference")]
    noise: Option<f64>,
    /// With --reference: the samples' seed (any u64); two seeds give two independent
    /// estimates of the same image, whose difference is its noise.
    #[arg(long, value_name = "SEED", default_value_t = 0, requires = "reference")]
    seed: u64,
    /// With --reference: the truth in this interface mode of the reference walk (`single`:
    /// microfacet interfaces that lose what masking removes; `multiple`: the microsurface
    /// walk, which conserves it) — the exact model's lobes with each layer's energy from the
    /// transport that follows light's angles, as `transport=corrected,interfaces=MODE`
    /// computes it. Without it: the paper's transport, the talk's model.
    #[arg(long, value_name = "MODE", requires = "reference")]
    interfaces: Option<String>,
    /// Record the measured frame (the sky and the shaded draw) with RenderDoc into this file,
    /// for RenderDoc's UI, renderdoccmd or its Python module; needs RenderDoc's library
    /// (Debian: librenderdoc). Written whatever the image's checks find: a failing frame is
    /// what one captures.
    #[arg(long, value_name = "FILE.rdc", conflicts_with = "reference")]
    capture: Option<PathBuf>,
}

pub struct RenderScene;

impl SceneDefaults for RenderScene {
    const SIZE: &'static str = "640x360";
    const SIZE_HELP: &'static str = "Image size";
    const ENV_HELP: &'static str = "Equirectangular OpenEXR environment map";
    const VARIANT_HELP: &'static str = "Shader variant, e.g. `model=ggx,fp16=on`; axes not given \
        take their defaults, with the model from the material file";
}

pub fn run(global: &GlobalArgs, args: &RenderArgs) -> Result<()> {
    require_extension("--out", &args.out, "exr", "linear HDR, OpenEXR")?;
    require_extension("--png", &args.png, "png", "tone-mapped PNG")?;
    if args.reference {
        return run_reference(global, args);
    }
    let scene = &args.scene;
    let env_path = asset_path(&scene.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let (stack, variant) = resolve_with_variant(&scene.material, scene.variant.as_deref())?;
    let layers = stack.params();
    let mut capturer = load_capturer(args.capture.as_deref())?;
    let mut gpu = global.open_gpu()?;
    print_pipelines(&mut gpu, None);
    let mut renderer = Renderer::new(&gpu, &equirect, EnvDesc::default())?;
    renderer.lighting = scene.lights.lighting()?;
    let key = PassKey::new(
        variant,
        &layers,
        stack.surface.as_deref(),
        &renderer.lighting,
    )?;
    let pass = renderer.prepare(&key)?;
    renderer.set_surface(stack.surface.as_ref())?;
    let (width, height) = (scene.size.width, scene.size.height);
    place_scene(&mut renderer, args.shape, width, height)?;
    for _ in 0..args.warmup {
        renderer.render(&pass, &layers, width, height)?;
    }
    let frame = match (&mut capturer, &args.capture) {
        (Some(capturer), Some(file)) => capturer.capture(&gpu.device, file, || {
            renderer.render(&pass, &layers, width, height)
        })??,
        _ => renderer.render(&pass, &layers, width, height)?,
    };
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
    if let (Some(capturer), Some(file)) = (&capturer, &args.capture) {
        println!(
            "capture:     {} (RenderDoc API {})",
            file.display(),
            capturer.version()
        );
    }
    save_pipelines(&gpu);
    Ok(())
}

/// `--reference`: the reference image, progressive, with a progress bar; nothing is written
/// when Ctrl-C stops it.
fn run_reference(global: &GlobalArgs, args: &RenderArgs) -> Result<()> {
    let scene = &args.scene;
    if scene.variant.is_some() {
        anyhow::bail!(
            "--reference renders the exact model, which has no variant; leave out --variant"
        );
    }
    let convergence = reference::Convergence {
        spp: args.spp,
        noise: args.noise,
        seed: args.seed,
    };
    convergence.check()?;
    let truth = truth(args)?;
    let env_path = asset_path(&scene.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let stack = Stack::resolve(&scene.material)?;
    let layers = stack.params();
    let gpu = global.open_gpu()?;
    let mut renderer =
        Renderer::with_target(&gpu, &equirect, EnvDesc::default(), TargetFormat::Float)?;
    renderer.lighting = scene.lights.lighting()?;
    let (width, height) = (scene.size.width, scene.size.height);
    place_scene(&mut renderer, args.shape, width, height)?;
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix:>12} [{bar:30}] {pos}/{len} frames of 16 samples ({elapsed}, ETA {eta})",
        )
        .expect("a valid template")
        .progress_chars("=> "),
    );
    bar.set_prefix("reference");
    let stop = stop_on_interrupt();
    let mut progress = |done, total| {
        bar.set_length(u64::from(total));
        bar.set_position(u64::from(done));
    };
    match &stack.surface {
        None => eprintln!(
            "tabulating the exact model at {} view cosines…",
            reference::TABLE_SIZE
        ),
        Some(_) => eprintln!(
            "{} varies over the surface: each pixel's lobes evaluated from its maps with {} \
             (the model's finest tables, not its exact integrals)",
            stack.name,
            reference::evaluated_variant(
                reference::exact_stand_in(stack.model, truth),
                layers.len()
            )
            .short()
        ),
    }
    let size = (width, height);
    let image = reference::render_stack(
        &mut renderer,
        &stack,
        truth,
        size,
        convergence,
        &mut progress,
        stop,
    )?;
    let Some(image) = image else {
        bar.abandon();
        anyhow::bail!("interrupted; nothing was written");
    };
    bar.finish_and_clear();
    check_validation(&gpu)?;
    let (w, h) = (image.width as usize, image.height as usize);
    imageio::write_exr_rgba32f(&args.out, w, h, &image.pixels)?;
    imageio::write_png_tonemapped(&args.png, w, h, &image.pixels, args.exposure)?;
    print_reference(&gpu, &env_path, &stack, &image, truth, args);
    Ok(())
}

/// The truth `--interfaces` names: the paper's transport without it.
fn truth(args: &RenderArgs) -> Result<reference::Truth> {
    Ok(match &args.interfaces {
        None => reference::Truth::Paper,
        Some(mode) => {
            reference::Truth::Transport(Interfaces::parse_value(mode).context("--interfaces")?)
        }
    })
}

/// What `--reference` rendered and wrote.
fn print_reference(
    gpu: &lamina::Gpu,
    env_path: &std::path::Path,
    stack: &Stack,
    image: &reference::ReferenceImage,
    truth: reference::Truth,
    args: &RenderArgs,
) {
    let (width, height) = (image.width, image.height);
    println!(
        "device:      {} ({})",
        gpu.device.report.name, gpu.device.report.driver_info
    );
    println!("environment: {}", env_path.display());
    println!(
        "material:    {} ({}, {} layers)",
        stack.name,
        stack.model,
        stack.layers.len()
    );
    println!("truth:       {truth}");
    println!(
        "size:        {width}x{height}\nreference:   {} samples per lobe and pixel from seed {}, \
         relative noise at most {:.2e}",
        image.spp, args.seed, image.noise
    );
    println!(
        "wrote:       {}, {}",
        args.out.display(),
        args.png.display()
    );
}
