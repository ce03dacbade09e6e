//! The shaded pass: the sphere, lit by the prefiltered environment, in one shader variant —
//! for every material (`mode=generic`) or for one (every other mode), as its [`PassKey`]
//! says; a baked material's pass keeps its lobe table.

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::shader::specialize::BakedShape;
use crate::vk::{Format, GraphicsDesc, Pipeline, PipelineLayout};

use super::baked::{BakedTable, BakedTexture};
use super::pass::{MaterialKey, PassKey};
use super::scene::Vertex;

/// The entry points compiled per variant (the only ones that see the variant's defines).
pub const ENTRIES: [&str; 2] = ["forward.vert.glsl", "forward.frag.glsl"];

pub struct ForwardPass {
    /// What the pass was built for; its specialization constants come from it.
    pub key: PassKey,
    pub pipeline: Pipeline,
    /// Size of the fragment shader's SPIR-V.
    pub spirv_bytes: usize,
    /// `mode=baked` and the reference pass: the lobe table, on the host and in the texture
    /// the pass reads.
    pub baked: Option<(BakedTable, BakedTexture)>,
}

impl ForwardPass {
    /// The pass of `key`, reading `baked` where the key is `mode=baked`'s or a reference's
    /// (whose table holds two rows per lobe, `render::reference::lobe_table`).
    pub fn new(
        gpu: &Gpu,
        layout: &PipelineLayout,
        color_format: Format,
        key: PassKey,
        baked: Option<(BakedTable, BakedTexture)>,
    ) -> Result<Self> {
        let variant = key.variant;
        crate::model::oracle::check_transport(variant)?;
        if variant.fp16 && !gpu.device.supports_fp16() {
            return Err(Error::Unsupported(format!(
                "fp16=on needs the shaderFloat16 feature, which `{}` lacks",
                gpu.device.report.name
            )));
        }
        let reference = matches!(key.material, MaterialKey::Reference(_));
        let shape = baked.as_ref().map(|(table, _)| {
            let shape = table.shape;
            if reference {
                BakedShape {
                    lobe_count: shape.lobe_count / 2,
                    ..shape
                }
            } else {
                shape
            }
        });
        let spec = key.spec(shape);
        let mut defines = variant.defines();
        if reference {
            defines.push(("LAMINA_REFERENCE", "1"));
        }
        let vertex = gpu.shaders.compile(ENTRIES[0], &defines)?;
        let fragment = gpu.shaders.compile(ENTRIES[1], &defines)?;
        let desc = GraphicsDesc {
            vertex: &vertex,
            fragment: &fragment,
            vertex_stride: std::mem::size_of::<Vertex>() as u32,
            attributes: &[
                (0, Format::R32G32B32_SFLOAT, 0),
                (1, Format::R32G32B32_SFLOAT, 12),
                (2, Format::R32G32_SFLOAT, 24),
            ],
            color_format,
            cull_back: true,
        };
        let pipeline =
            gpu.graphics_pipeline(layout, &desc, &spec, &format!("forward {variant}"))?;
        Ok(Self {
            key,
            pipeline,
            spirv_bytes: fragment.len() * 4,
            baked,
        })
    }
}
