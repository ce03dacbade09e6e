//! Shader compilation (GLSL → SPIR-V), the shading pass's interface and the compute kernels'.
//! The variant key the shaders are specialized with is [`crate::variant`].

mod compiler;
pub mod freeze;
pub mod interface;
pub mod kernel;
pub mod specialize;

pub use compiler::{entry_hash, entry_points, source, ShaderCompiler, ShaderError, HOST_DEFINES};
