//! Materials: a stack of layers (top first) and the TOML format of DESIGN.md §6.
//!
//! ```toml
//! name = "varnished gold"
//! model = "tm2"              # or "tm6"
//! [[layer]]                  # top first; the medium above the top layer is vacuum
//! ior = [1.5, 1.5, 1.5]      # η per RGB channel
//! kappa = [0.0, 0.0, 0.0]    # κ > 0: conductor, ends the stack
//! roughness = 0.1            # GGX α
//! [[layer]]
//! f0 = [0.97, 0.80, 0.32]    # artist form (Gulbrandsen 2014) instead of ior/kappa
//! edge_tint = [0.95, 0.85, 0.5]
//! roughness = 0.3
//! ```
//! 6-flux layers add the medium that fills them: `depth`, `sigma_s`, `sigma_a` (RGB) and `g`.
//! A stack holds [`LayerParams`] directly: the artist form is converted to (η, κ) on load, and
//! [`Stack::to_toml`] writes the physical form back.
//!
//! Every error names the file, the layer (1-based, top first) and the field, and the allowed
//! range. The ranges, and why:
//!
//! | field | range | why |
//! |---|---|---|
//! | `ior` | [0.001, 400] | η ≤ 0 is unphysical and conductors go below 1 (gold's red η is 0.14; the artist form reaches 0.005 at f0 = 0.99, edge tint 1). Below 10⁻³ a relative IOR's reciprocal and square leave the GPU's f32 range in the TIR and lobe-refraction terms. Measured RGB values stay below 5, but the artist form reaches η ≈ 398 (f0 = 0.99, edge tint 0), and the physical form must load whatever [`Stack::to_toml`] writes |
//! | `kappa` | [0, 200] | likewise: measured κ stays below 10 (aluminium 9.2), the artist form reaches κ ≈ 199; the bound keeps κ⁴ in the GPU's f32 conductor Fresnel far from overflow |
//! | `roughness` | [0, 1] | GGX α; 0 is a mirror, and the FGD/TIR tables span α ∈ [0, 1] |
//! | `f0` | [0, 0.99] | as r → 1 Gulbrandsen's η and κ go to infinity; the most reflective RGB metal, silver, has F0 ≈ 0.975 |
//! | `edge_tint` | [0, 1] | a reflectance-like colour; every value gives (η, κ) inside the rows above |
//! | `depth` | [0, 100] | only τ = depth·σ matters, and τ = 10⁵ is opaque to f64 already; larger values are unit slips |
//! | `sigma_s`, `sigma_a` | [0, 1000] | the same reasoning; coefficients, so non-negative |
//! | `g` | (−1, 1) | HG asymmetry; ±1 is the degenerate limit (a delta, not a phase function) |
//!
//! Structural rules: a layer gives exactly one of the physical (`ior`, optional `kappa`) or the
//! artist (`f0` and `edge_tint`) form, and always `roughness`; a conductor (any κ > 0) is the
//! last layer and has no medium; medium fields need `model = "tm6"`, and `sigma_s`/`sigma_a` need
//! a `depth`; a stack has 1 to [`MAX_LAYERS_LIMIT`] layers (the GPU buffer's size), and
//! [`Stack::check_fits`] tests it against a variant's static array size.
//!
//! [`Stack::variant`] gives the variant a stack is shaded with for a key that names only some
//! axes (the model and `max_layers` follow the stack; `variant.rs`). [`random`] draws valid
//! stacks over the whole of these ranges for the property tests (`properties.rs` runs the f64
//! model over them). [`simplify`] takes out what the model provably ignores (index-matched
//! layers, empty media, layers no light reaches) and says why.
//!
//! [`MAX_LAYERS_LIMIT`]: crate::variant::MAX_LAYERS_LIMIT

mod artist;
mod layer;
mod parse;
mod presets;
#[cfg(test)]
mod properties;
pub mod random;
pub mod simplify;
#[cfg(test)]
mod simplify_properties;
mod source;
pub mod surface;
#[cfg(test)]
mod tests;
mod variant;
mod write;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::imageio::{self, ImageIoError};
use crate::model::LayerParams;
use crate::variant::{Model, VariantError};

pub use artist::gulbrandsen;
pub use presets::presets;
pub use surface::Surface;
pub use variant::{base_variant, resolve_with_variant};

/// A named stack of layers, top first, with the model it is meant for.
#[derive(Clone, Debug, PartialEq)]
pub struct Stack {
    /// Display name (`name` in the file; the file stem when absent).
    pub name: String,
    /// `tm2` or `tm6`.
    pub model: Model,
    /// Top first; only the last may be a conductor.
    pub layers: Vec<LayerParams>,
    /// The file the stack was read from, named by later errors ([`Stack::check_fits`]).
    pub source: PathBuf,
    /// Where parameters vary over the surface (textures, patterns, coverage): the maps, baked
    /// on load; `layers` then holds the constants and each map's middle value. `None` for a
    /// uniform stack.
    pub surface: Option<Arc<Surface>>,
}

/// A material that cannot be read or used, located as precisely as the problem allows.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// The file as a whole: unreadable, not TOML, or a top-level key is wrong.
    #[error("{path}: {message}")]
    File { path: PathBuf, message: String },
    /// One field of one layer (1-based, top first).
    #[error("{path}: layer {layer}: `{field}`: {message}")]
    Field {
        path: PathBuf,
        layer: usize,
        field: String,
        message: String,
    },
    /// A preset name that names no file.
    #[error("no material `{name}`: no preset {name}.toml under {searched} (give a path, e.g. ./{name}, for a file)")]
    NotFound { name: String, searched: String },
    /// The stack is deeper than the static layer array of the chosen variant.
    #[error("{path}: layer {layer}: `max_layers`: `{name}` has {layers} layers; variant max_layers={max_layers} holds at most {max_layers}")]
    TooManyLayers {
        path: PathBuf,
        name: String,
        layer: usize,
        layers: usize,
        max_layers: u32,
    },
    /// A variant key that does not parse ([`Stack::variant`]).
    #[error(transparent)]
    Variant(#[from] VariantError),
    /// The stack could not be written ([`Stack::save`]); names the file and why.
    #[error(transparent)]
    Save(ImageIoError),
}

impl Stack {
    /// Loads a preset by name (no path separator, no `.toml`: `gold` →
    /// `assets/materials/gold.toml`, under the working directory, then under the source tree),
    /// or else a material file by path.
    pub fn resolve(spec: &str) -> Result<Self, MaterialError> {
        if presets::is_preset_name(spec) {
            Self::load(&presets::find(spec)?)
        } else {
            Self::load(Path::new(spec))
        }
    }

    /// Reads and validates a material file.
    pub fn load(path: &Path) -> Result<Self, MaterialError> {
        let text = std::fs::read_to_string(path).map_err(|e| MaterialError::File {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        parse::parse(&text, path)
    }

    /// Parses and validates TOML text; `path` names the source in errors.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, MaterialError> {
        parse::parse(text, path)
    }

    /// The stack in the physical form of the file format; loads back to an equal stack.
    pub fn to_toml(&self) -> String {
        write::write(self)
    }

    /// Writes [`Stack::to_toml`] to `path` atomically (a temporary file, then a rename).
    pub fn save(&self, path: &Path) -> Result<(), MaterialError> {
        imageio::write_file_atomically(path, self.to_toml()).map_err(MaterialError::Save)
    }

    /// The layers as the model consumes them.
    pub fn params(&self) -> Vec<LayerParams> {
        self.layers.clone()
    }

    /// The stack resized to `n` layers for layer-count studies: the bottom layer stays the
    /// substrate and the `n − 1` layers above it cycle through the stack's coats from the top
    /// (a five-layer stack at `n = 3` keeps its first two coats; at `n = 7` it repeats them).
    /// Named `NAME @ n layers`. Errs when `n` is 0 or when `n > 1` and the stack has no coat.
    pub fn with_active_layers(&self, n: usize) -> Result<Self, MaterialError> {
        self.require_uniform("the active_layers axis")?;
        let (substrate, coats) = self
            .layers
            .split_last()
            .expect("a validated stack has at least one layer");
        if n == 0 || (n > 1 && coats.is_empty()) {
            return Err(MaterialError::File {
                path: self.source.clone(),
                message: format!(
                    "cannot build {n} active layer(s) from `{}`: it has {} coat(s) above its \
                     substrate (allowed: 1, or any n ≥ 1 when it has a coat)",
                    self.name,
                    coats.len()
                ),
            });
        }
        let mut layers: Vec<LayerParams> = coats.iter().cycle().take(n - 1).copied().collect();
        layers.push(*substrate);
        Ok(Self {
            name: format!("{} @ {n} layers", self.name),
            layers,
            ..self.clone()
        })
    }

    /// Errs when the stack varies over its surface, naming the first varying field: `what`
    /// (a command or study) takes one stack for every point.
    pub fn require_uniform(&self, what: &str) -> Result<(), MaterialError> {
        let Some(surface) = &self.surface else {
            return Ok(());
        };
        let (layer, field) = surface
            .layers
            .iter()
            .enumerate()
            .find_map(|(i, l)| l.sources.first().map(|(f, _)| (i, f.key())))
            .expect("a surface has a source");
        Err(MaterialError::Field {
            path: self.source.clone(),
            layer: layer + 1,
            field: field.to_owned(),
            message: format!(
                "varies over the surface; {what} takes a stack that is the same everywhere \
                 (render, bench, sweep, sheet and view shade varying stacks)"
            ),
        })
    }

    /// Errs when the stack has more layers than a variant's static array size, naming the
    /// first layer that does not fit.
    pub fn check_fits(&self, max_layers: u32) -> Result<(), MaterialError> {
        if self.layers.len() > max_layers as usize {
            return Err(MaterialError::TooManyLayers {
                path: self.source.clone(),
                name: self.name.clone(),
                layer: max_layers as usize + 1,
                layers: self.layers.len(),
                max_layers,
            });
        }
        Ok(())
    }
}
