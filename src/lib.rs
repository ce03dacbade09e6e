//! lamina: layered materials with the transfer-matrix model on Vulkan, measured.
//!
//! Module map (DESIGN.md §3):
//! - [`vk`] — the only module with raw `ash` — instance, device, memory, pipelines, queries;
//! - [`gpu`] — the device, shader compiler and pipeline cache every pass is built from;
//! - [`pipeline_cache`] — the pipeline cache's file: where, keyed how, trusted when;
//! - [`variant`] — the typed variant key: the axes a shader is specialized on;
//! - [`shader`] — GLSL → SPIR-V with shaderc, the shading and kernel interfaces;
//! - [`tables`] — GPU-built tables (prefiltered environment, split-sum, FGD, TIR) with CPU
//!   references, their spot checks and error studies;
//! - [`render`] — passes (sky, shaded sphere), the scene and readback;
//! - [`model`] — the CPU reference in f64;
//! - [`reference`] — the stochastic reference: light paths through the stack (`lamina reference`);
//! - [`material`] — layer stacks, and the variant a stack is shaded with;
//! - [`imageio`] — EXR/PNG input and atomic output;
//! - [`size`] — `WxH` image sizes, one limit for the command line and the sweep files;
//! - [`output`] — the JSON and tables commands print;
//! - [`profile`] — measuring one set of cases: the bench, image errors, instruction counts,
//!   the results schema;
//! - [`study`] — the documents above the measurements: sweep files, study runs, charts, the
//!   report, diffs;
//! - [`viewer`] — the interactive window (winit + egui).
//!
//! The `lamina` binary (`src/main.rs`, `src/cli/`) only parses, checks arguments and prints:
//! every rule a command applies is here, where the sweep, the viewer and the tests use it too.

pub mod cache;
pub mod chart;
pub mod error;
pub mod gpu;
pub mod imageio;
pub mod material;
pub mod model;
pub mod output;
pub mod pipeline_cache;
pub mod profile;
pub mod reference;
pub mod render;
pub mod shader;
pub mod size;
pub mod stats;
pub mod study;
pub mod tables;
pub mod text;
pub mod variant;
pub mod viewer;
pub mod vk;

pub use error::{Error, Result};
pub use gpu::Gpu;
pub use size::Size;
