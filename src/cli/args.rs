//! Argument types several commands share: what `render` and `view` take to set up a scene
//! (flattened into both), the environment map of the timing commands, the instruction counter,
//! and the checks of numeric arguments — each value finite and inside a documented range,
//! refused with the flag and the range named.

use std::marker::PhantomData;
use std::path::PathBuf;

use lamina::imageio;
use lamina::render::lights::{Light, Lighting, MAX_INTENSITY};
use lamina::Size;

/// What a command that shows one material sets up: the material, its variant, the
/// environment and the image size. The defaults and help that differ between commands come
/// from `D`.
#[derive(clap::Args)]
pub struct SceneArgs<D: SceneDefaults> {
    #[arg(long, default_value = D::SIZE, value_name = "WxH", help = D::SIZE_HELP)]
    pub size: Size,
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr", help = D::ENV_HELP)]
    pub env: PathBuf,
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET", default_value = "gold")]
    pub material: String,
    #[arg(long, value_name = "KEY", help = D::VARIANT_HELP)]
    pub variant: Option<String>,
    #[command(flatten)]
    pub lights: LightArgs,
    #[arg(skip)]
    defaults: PhantomData<D>,
}

/// The defaults and help of [`SceneArgs`] for one command.
pub trait SceneDefaults: Send + Sync + 'static {
    const SIZE: &'static str;
    const SIZE_HELP: &'static str;
    const ENV_HELP: &'static str;
    const VARIANT_HELP: &'static str;
}

/// The environment map of the commands that render many frames.
#[derive(clap::Args)]
pub struct EnvArg {
    /// Equirectangular OpenEXR environment map.
    #[arg(long, value_name = "FILE", default_value = "assets/env/studio.exr")]
    pub env: PathBuf,
    #[command(flatten)]
    pub lights: LightArgs,
}

/// The analytic lights and the environment's scale (`render::lights`).
#[derive(clap::Args)]
pub struct LightArgs {
    /// Lighting file or preset (sun, sun-only, studio-keys; see assets/lights/): the
    /// environment's scale and analytic lights. Default: the environment alone.
    #[arg(long, value_name = "FILE|PRESET")]
    pub lights: Option<String>,
    /// An analytic light added to the lighting: `directional:X,Y,Z[:INTENSITY[:RADIUS_DEG]]`
    /// (direction towards the light), `point:X,Y,Z[:INTENSITY]`, or a TOML inline table with a
    /// lighting file's light keys. Repeatable.
    #[arg(long = "light", value_name = "SPEC", value_parser = light_spec)]
    pub light: Vec<Light>,
    /// Scale of the environment's light, 0 to 10000 (0: the lights alone); overrides the
    /// lighting file's `environment`.
    #[arg(long, value_name = "X", value_parser = env_scale, allow_negative_numbers = true)]
    pub env_scale: Option<f64>,
}

impl LightArgs {
    /// The lighting these arguments ask for.
    pub fn lighting(&self) -> anyhow::Result<Lighting> {
        let mut lighting = match &self.lights {
            Some(spec) => Lighting::load(spec)?,
            None => Lighting::default(),
        };
        if let Some(scale) = self.env_scale {
            lighting.environment = scale;
        }
        Ok(lighting.with_lights(&self.light)?)
    }

    /// Whether any lighting argument was given.
    pub fn given(&self) -> bool {
        self.lights.is_some() || !self.light.is_empty() || self.env_scale.is_some()
    }
}

fn light_spec(text: &str) -> Result<Light, String> {
    Light::parse_arg(text)
}

fn env_scale(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() && (0.0..=MAX_INTENSITY).contains(&x) => Ok(x),
        _ => Err(format!("`{text}` is not a scale in 0 … {MAX_INTENSITY}")),
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CounterArg {
    /// Instructions executed by lavapipe while it runs the shaded draw (valgrind callgrind).
    Instructions,
    /// No counting, whatever the sweep files ask (e.g. on a GPU, where there is nothing to
    /// count).
    None,
}

/// `--exposure EV`: a number of stops in [`imageio::EXPOSURE_RANGE_EV`].
/// `--cos`: the view cosines a command evaluates at.
#[derive(clap::Args)]
pub struct CosinesArg {
    /// View cosines, comma-separated, each in (0, 1].
    #[arg(
        long = "cos",
        value_name = "LIST",
        value_delimiter = ',',
        required = true
    )]
    cosines: Vec<f64>,
}

impl CosinesArg {
    /// The cosines, each checked to be in (0, 1].
    pub fn checked(&self) -> anyhow::Result<&[f64]> {
        if let Some(c) = self
            .cosines
            .iter()
            .find(|c| !(c.is_finite() && **c > 0.0 && **c <= 1.0))
        {
            anyhow::bail!("--cos: {c} is not a view cosine; each must be in (0, 1]");
        }
        Ok(&self.cosines)
    }
}

pub fn exposure(text: &str) -> Result<f32, String> {
    let ev = text
        .parse::<f32>()
        .map_err(|_| format!("`{text}` is not a number of stops"))?;
    imageio::check_exposure(ev).map_err(|e| e.to_string())?;
    Ok(ev)
}

/// `--fail-above PCT`: a finite percentage ≥ 0.
pub fn percent(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("`{text}` is not a percentage ≥ 0")),
    }
}
