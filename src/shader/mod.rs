//! Shader compilation and the variant key.

mod compiler;
pub mod interface;
pub mod kernel;
pub mod variant;

pub use compiler::{entry_hash, entry_points, source, ShaderCompiler, ShaderError, HOST_DEFINES};
pub use variant::{Axis, Fgd, Model, Ndf, ShadeSpec, Tir, VariantError, VariantKey, G2};
