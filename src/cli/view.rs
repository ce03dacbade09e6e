//! `lamina view`: the interactive viewer (`lamina::viewer`), and its summary once it exits.

use std::path::{Path, PathBuf};

use anyhow::Result;
use lamina::material::resolve_with_variant;
use lamina::viewer::{self, ViewOptions};
use lamina::Size;

use super::args::{SceneArgs, SceneDefaults};
use super::{asset_path, GlobalArgs};

#[derive(clap::Args)]
pub struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs<ViewScene>,
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

pub struct ViewScene;

impl SceneDefaults for ViewScene {
    const SIZE: &'static str = "1280x720";
    const SIZE_HELP: &'static str = "Window size";
    const ENV_HELP: &'static str =
        "Equirectangular OpenEXR environment map (the picker lists its directory's maps)";
    const VARIANT_HELP: &'static str =
        "Shader variant to start with; axes not given take their defaults";
}

pub fn run(global: &GlobalArgs, args: &ViewArgs) -> Result<()> {
    let scene = &args.scene;
    let (stack, variant) = resolve_with_variant(&scene.material, scene.variant.as_deref())?;
    let env = asset_path(&scene.env);
    let env_dir = env
        .parent()
        .map(Path::to_owned)
        .unwrap_or_else(|| PathBuf::from("."));
    let report = viewer::run(ViewOptions {
        stack,
        variant,
        env,
        env_dir,
        width: scene.size.width,
        height: scene.size.height,
        screenshot: args.screenshot.clone(),
        frames: args.frames,
        resize: args.resize.map(|s| (s.width, s.height)),
        save_stack: args.save_stack.clone(),
        instance: global.instance(true),
        selector: global.selector(),
        lighting: scene.lights.lighting()?,
    })?;
    println!(
        "{} frame(s), final size {}x{}, swapchain built {} time(s)",
        report.frames, report.final_size.0, report.final_size.1, report.swapchain_builds
    );
    for path in [&args.screenshot, &args.save_stack].into_iter().flatten() {
        println!("wrote {}", path.display());
    }
    if global.validation || global.sync_validation {
        let problems = report.validation_problems;
        if problems > 0 {
            anyhow::bail!(
                "the validation layer reported {problems} problem(s); see the messages above"
            );
        }
    }
    Ok(())
}
