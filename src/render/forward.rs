//! The shaded pass: the sphere, lit by the prefiltered environment, in one shader variant.

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::variant::VariantKey;
use crate::vk::{Format, GraphicsDesc, Pipeline, PipelineLayout};

use super::scene::Vertex;

/// The entry points compiled per variant (the only ones that see the variant's defines).
pub const ENTRIES: [&str; 2] = ["forward.vert.glsl", "forward.frag.glsl"];

pub struct ForwardPass {
    pub variant: VariantKey,
    pub pipeline: Pipeline,
    /// Size of the fragment shader's SPIR-V.
    pub spirv_bytes: usize,
}

impl ForwardPass {
    pub fn new(
        gpu: &Gpu,
        layout: &PipelineLayout,
        color_format: Format,
        variant: VariantKey,
    ) -> Result<Self> {
        if variant.fp16 && !gpu.device.supports_fp16() {
            return Err(Error::Unsupported(format!(
                "fp16=on needs the shaderFloat16 feature, which `{}` lacks",
                gpu.device.report.name
            )));
        }
        let defines = variant.defines();
        let vertex = gpu.shaders.compile(ENTRIES[0], &defines)?;
        let fragment = gpu.shaders.compile(ENTRIES[1], &defines)?;
        let desc = GraphicsDesc {
            vertex: &vertex,
            fragment: &fragment,
            vertex_stride: std::mem::size_of::<Vertex>() as u32,
            attributes: &[
                (0, Format::R32G32B32_SFLOAT, 0),
                (1, Format::R32G32B32_SFLOAT, 12),
            ],
            color_format,
            cull_back: true,
        };
        let pipeline = Pipeline::graphics(
            &gpu.device,
            layout,
            &desc,
            &variant.spec(),
            &format!("forward {variant}"),
        )?;
        Ok(Self {
            variant,
            pipeline,
            spirv_bytes: fragment.len() * 4,
        })
    }
}
