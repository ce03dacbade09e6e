//! The deferred path (`path=deferred`, issue 28): the mesh's draw writes a G-buffer of what
//! the forward pass's fragment shader receives (the interpolated world position and normal,
//! the texture coordinates: `gbuffer.frag.glsl`), then a compute kernel shades every pixel it
//! covers with the forward pass's own shading code (`deferred.comp.glsl`,
//! `glsl/include/lib/shade.glsl`) into the render target. On a GPU whose graphics run on a few
//! of its units (the H100: 4 of 132 SMs) the compute dispatch runs on all of them.
//!
//! One pipeline shades every pixel (`mode` says which: generic, specialized, specialized
//! values or baked); a varying stack under `mode=specialized`, whose pixels need one pipeline
//! per class (`render::classes`), is refused by name until the deferred path classifies
//! pixels itself (issue 28's `classify`).

use crate::error::Result;
use crate::gpu::{ComputeKernel, Gpu};
use crate::shader::kernel::KernelInterface;
use crate::variant::ShadeSpec;
use crate::vk::{BindingKind, DescriptorSetLayout, Format, Pipeline};

/// The G-buffer's two attachments: (position, u) and (normal, v), in floats, so that the
/// compute kernel shades the very inputs the fragment shader would.
pub const GBUFFER_FORMAT: Format = Format::R32G32B32A32_SFLOAT;

/// The G-buffer's fragment shader.
pub const GBUFFER_ENTRY: &str = "gbuffer.frag.glsl";

/// The shading kernel's tile edge, in pixels (its work group).
pub const TILE: u32 = 8;

/// The shading kernel's push constants: the frame's size.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DeferredPush {
    pub width: u32,
    pub height: u32,
}

/// `deferred.comp.glsl`: the shading and scene sets, then its own — the G-buffer's two
/// attachments (sampled) and the render target (storage).
pub const KERNEL: KernelInterface = KernelInterface {
    entry: "deferred.comp.glsl",
    shades: true,
    scene: true,
    bindings: &[
        BindingKind::SampledImage,
        BindingKind::SampledImage,
        BindingKind::StorageImage,
    ],
    push: crate::push_block!(DeferredPush { width, height }),
    local_size: [TILE, TILE],
};

/// A deferred pass's pipelines: the G-buffer's draw and the shading kernel.
pub struct DeferredPipelines {
    /// Draws the mesh into the G-buffer (`forward.vert.glsl`, `gbuffer.frag.glsl`); built
    /// by the caller, who owns the graphics layout.
    pub gbuffer: Pipeline,
    pub kernel: ComputeKernel,
}

impl DeferredPipelines {
    /// The shading kernel with `spec` (the pass's constants) over the `shading` and `scene`
    /// set layouts, writing a target of `target_format`, beside the G-buffer's pipeline.
    pub fn new(
        gpu: &Gpu,
        gbuffer: Pipeline,
        shared: [&DescriptorSetLayout; 2],
        spec: ShadeSpec,
        defines: &[(&'static str, &'static str)],
        target_format: Format,
    ) -> Result<Self> {
        let mut defines = defines.to_vec();
        if target_format == Format::R32G32B32A32_SFLOAT {
            defines.push(("LAMINA_TARGET_RGBA32F", "1"));
        }
        let kernel = ComputeKernel::build(gpu, &KERNEL, &defines, &shared, spec)?;
        Ok(Self { gbuffer, kernel })
    }
}
