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
//! Every error names the file, the layer and the field, and the allowed range.

mod artist;
mod parse;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

use crate::model::LayerParams;
use crate::shader::Model;

pub use artist::gulbrandsen;

/// A named stack of layers, top first, with the model it is meant for.
#[derive(Clone, Debug, PartialEq)]
pub struct Stack {
    pub name: String,
    pub model: Model,
    pub layers: Vec<LayerParams>,
}

#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    #[error("{path}: {message}")]
    File { path: PathBuf, message: String },
    #[error("{path}: layer {layer}: `{field}`: {message}")]
    Field {
        path: PathBuf,
        layer: usize,
        field: String,
        message: String,
    },
    #[error("no material `{name}`: not a file, and no preset {name}.toml under {searched}")]
    NotFound { name: String, searched: String },
    #[error(
        "`{name}` has {layers} layers; variant max_layers={max_layers} holds at most {max_layers}"
    )]
    TooManyLayers {
        name: String,
        layers: usize,
        max_layers: u32,
    },
}

/// Where presets live, relative to the working directory or to the source tree.
const PRESET_DIR: &str = "assets/materials";

fn preset_dirs() -> [PathBuf; 2] {
    [
        PathBuf::from(PRESET_DIR),
        Path::new(env!("CARGO_MANIFEST_DIR")).join(PRESET_DIR),
    ]
}

/// Preset files, sorted by name (from the first preset directory that exists).
pub fn presets() -> Vec<PathBuf> {
    let Some(dir) = preset_dirs().into_iter().find(|d| d.is_dir()) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

impl Stack {
    /// Loads a material file, or a preset by name (`gold` → `assets/materials/gold.toml`).
    pub fn resolve(spec: &str) -> Result<Self, MaterialError> {
        let path = Path::new(spec);
        if path.is_file() {
            return Self::load(path);
        }
        let is_name = !spec.contains(['/', '\\']) && !spec.ends_with(".toml");
        if is_name {
            for dir in preset_dirs() {
                let candidate = dir.join(format!("{spec}.toml"));
                if candidate.is_file() {
                    return Self::load(&candidate);
                }
            }
        }
        Err(MaterialError::NotFound {
            name: spec.to_owned(),
            searched: preset_dirs()
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(" and "),
        })
    }

    pub fn load(path: &Path) -> Result<Self, MaterialError> {
        let text = std::fs::read_to_string(path).map_err(|e| MaterialError::File {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        parse::parse(&text, path)
    }

    /// Parses TOML text; `path` only names the source in errors.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, MaterialError> {
        parse::parse(text, path)
    }

    /// The stack in the physical form of the file format; loads back to an equal stack.
    pub fn to_toml(&self) -> String {
        parse::write(self)
    }

    /// The layers as the model consumes them.
    pub fn params(&self) -> Vec<LayerParams> {
        self.layers.clone()
    }

    /// Errs when the stack has more layers than a variant's static array size.
    pub fn check_fits(&self, max_layers: u32) -> Result<(), MaterialError> {
        if self.layers.len() > max_layers as usize {
            return Err(MaterialError::TooManyLayers {
                name: self.name.clone(),
                layers: self.layers.len(),
                max_layers,
            });
        }
        Ok(())
    }
}
