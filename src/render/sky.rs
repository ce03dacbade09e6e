//! The background: a full-screen triangle showing the environment's mip 0 along each view ray.

use crate::error::Result;
use crate::gpu::Gpu;
use crate::vk::{Format, GraphicsDesc, Pipeline, PipelineLayout};

/// The sky's entry points.
pub const ENTRIES: [&str; 2] = ["sky.vert.glsl", "sky.frag.glsl"];

pub struct SkyPass {
    /// Draws 3 vertices, no vertex buffer, with the scene set bound.
    pub pipeline: Pipeline,
}

impl SkyPass {
    pub fn new(gpu: &Gpu, layout: &PipelineLayout, color_format: Format) -> Result<Self> {
        let vertex = gpu.shaders.compile(ENTRIES[0], &[])?;
        let fragment = gpu.shaders.compile(ENTRIES[1], &[])?;
        let desc = GraphicsDesc {
            vertex: &vertex,
            fragment: &fragment,
            vertex_stride: 0,
            attributes: &[],
            color_formats: &[color_format],
            cull_back: false,
            stencil: None,
        };
        let pipeline = gpu.graphics_pipeline(layout, &desc, &(), "sky")?;
        Ok(Self { pipeline })
    }
}
