//! The shaded pass: the sphere, lit by the prefiltered environment, in one shader variant —
//! for every material (`mode=generic`) or for one (every other mode), as its [`PassKey`]
//! says; a baked material's pass keeps its lobe table. A varying stack under
//! `mode=specialized` is several draws: its stencil marks, then one pipeline per class of
//! pixels (`render::classes`).

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::shader::specialize::BakedShape;
use crate::variant::{Classify, ShadePath, ShadeSpec};
use crate::vk::{DescriptorSetLayout, Format, GraphicsDesc, Pipeline, PipelineLayout, StencilUse};

use super::baked::{BakedTable, BakedTexture};
use super::classes::Routing;
use super::deferred::{DeferredPipelines, BINS_KERNEL, GBUFFER_ENTRY, GBUFFER_FORMAT, KERNEL};
use super::pass::{MaterialKey, PassKey};
use super::scene::Vertex;

/// The entry points compiled per variant (the only ones that see the variant's defines).
pub const ENTRIES: [&str; 2] = ["forward.vert.glsl", "forward.frag.glsl"];

/// The stencil marks' fragment shader (`render::classes`).
pub const MARK_ENTRY: &str = "classify.frag.glsl";

/// One draw of the mesh in a pass.
pub struct Draw {
    pub pipeline: Pipeline,
    /// A routed pass's draw: its stencil (reference, compared bits, written bits).
    pub stencil: Option<(u32, u32, u32)>,
}

/// The shader defines of `key`'s pass: its variant's, and a reference pass's.
fn defines_of(key: &PassKey) -> Vec<(&'static str, &'static str)> {
    let mut defines = key.variant.defines();
    if key.is_reference() {
        defines.push(("LAMINA_REFERENCE", "1"));
    }
    if key.material == MaterialKey::Evaluated {
        defines.push(("LAMINA_REFERENCE_EVALUATED", "1"));
    }
    defines
}

pub struct ForwardPass {
    /// What the pass was built for; its specialization constants come from it.
    pub key: PassKey,
    /// The draws of a frame, in order: one shading pipeline, or for a routed pass (a varying
    /// stack under `mode=specialized`) the stencil marks, then one pipeline per class.
    pub draws: Vec<Draw>,
    /// The draw whose pipeline the bench reports (a routed pass's class with the most
    /// layers).
    main: usize,
    /// `path=deferred`: the G-buffer's draw and the shading kernel, in place of `draws`.
    pub deferred: Option<DeferredPipelines>,
    /// Size of the fragment shader's SPIR-V.
    pub spirv_bytes: usize,
    /// `mode=baked` and the reference pass: the lobe table, on the host and in the texture
    /// the pass reads.
    pub baked: Option<(BakedTable, BakedTexture)>,
}

impl ForwardPass {
    /// The pass of `key`, reading `baked` where the key is `mode=baked`'s or a reference's
    /// (whose table holds two rows per lobe, `render::reference::lobe_table`). `layout` is
    /// the graphics pipelines' (the `shared` shading and scene sets), which the deferred
    /// path's kernel shares.
    pub fn new(
        gpu: &Gpu,
        layout: &PipelineLayout,
        shared: [&DescriptorSetLayout; 2],
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
        let reference = key.is_reference();
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
        let defines = defines_of(&key);
        let builder = Builder {
            gpu,
            layout,
            vertex: gpu.shaders.compile(ENTRIES[0], &defines)?,
            color_format,
        };
        let spec = key.spec(shape);
        if variant.path == ShadePath::Deferred {
            let deferred = builder.deferred(&key, shared, spec, &defines)?;
            let entry = match variant.classify {
                Classify::None => KERNEL.entry,
                Classify::Tiles | Classify::Pixels => BINS_KERNEL.entry,
            };
            let spirv_bytes = gpu.shaders.compile(entry, &defines)?.len() * 4;
            return Ok(Self {
                key,
                draws: Vec::new(),
                main: 0,
                deferred: Some(deferred),
                spirv_bytes,
                baked,
            });
        }
        let fragment = gpu.shaders.compile(ENTRIES[1], &defines)?;
        let (draws, main) = match &key.material {
            MaterialKey::Classes(routing) => builder.routed(&key, routing, &fragment, &defines)?,
            _ => {
                let name = format!("forward {variant}");
                let pipeline = builder.build(&fragment, None, &spec, &name)?;
                (
                    vec![Draw {
                        pipeline,
                        stencil: None,
                    }],
                    0,
                )
            }
        };
        Ok(Self {
            key,
            draws,
            main,
            deferred: None,
            spirv_bytes: fragment.len() * 4,
            baked,
        })
    }

    /// The pipeline the bench reports: the only one, or a routed pass's class with the most
    /// layers.
    pub fn pipeline(&self) -> &Pipeline {
        match &self.deferred {
            Some(d) => d.main_pipeline(),
            None => &self.draws[self.main].pipeline,
        }
    }

    /// Every pipeline the pass made.
    fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        let deferred = self.deferred.iter().flat_map(|d| d.pipelines());
        self.draws.iter().map(|d| &d.pipeline).chain(deferred)
    }

    /// Whether the pass routes pixels by a stencil (`render::classes`).
    pub fn routed(&self) -> bool {
        self.draws.iter().any(|d| d.stencil.is_some())
    }

    /// Host time of every pipeline's creation, in milliseconds.
    pub fn creation_ms(&self) -> f64 {
        self.pipelines()
            .map(|p| p.creation.duration.as_secs_f64() * 1e3)
            .sum()
    }

    /// Whether the driver found every pipeline in the pipeline cache (`None` where one's
    /// feedback is not valid).
    pub fn cache_hit(&self) -> Option<bool> {
        self.pipelines()
            .map(|p| p.creation.cache_hit)
            .try_fold(true, |all, hit| hit.map(|h| all && h))
    }
}

/// What every pipeline of a pass shares: the device, the graphics layout, the vertex shader
/// and the target's format.
struct Builder<'a> {
    gpu: &'a Gpu,
    layout: &'a PipelineLayout,
    vertex: std::sync::Arc<[u32]>,
    color_format: Format,
}

impl Builder<'_> {
    /// A graphics pipeline drawing the mesh with `fragment` into `formats`.
    fn build_into(
        &self,
        fragment: &[u32],
        formats: &[Format],
        stencil: Option<StencilUse>,
        spec: &ShadeSpec,
        name: &str,
    ) -> Result<Pipeline> {
        let desc = GraphicsDesc {
            vertex: &self.vertex,
            fragment,
            vertex_stride: std::mem::size_of::<Vertex>() as u32,
            attributes: &[
                (0, Format::R32G32B32_SFLOAT, 0),
                (1, Format::R32G32B32_SFLOAT, 12),
                (2, Format::R32G32_SFLOAT, 24),
            ],
            color_formats: formats,
            cull_back: true,
            stencil,
        };
        self.gpu.graphics_pipeline(self.layout, &desc, spec, name)
    }

    /// A graphics pipeline drawing the mesh with `fragment` into the target.
    fn build(
        &self,
        fragment: &[u32],
        stencil: Option<StencilUse>,
        spec: &ShadeSpec,
        name: &str,
    ) -> Result<Pipeline> {
        self.build_into(fragment, &[self.color_format], stencil, spec, name)
    }

    /// A routed pass's draws (`render::classes`): the stencil marks, then one pipeline per
    /// class; and the index of the first class.
    fn routed(
        &self,
        key: &PassKey,
        routing: &Routing,
        fragment: &[u32],
        defines: &[(&'static str, &'static str)],
    ) -> Result<(Vec<Draw>, usize)> {
        let variant = key.variant;
        if !self.gpu.device.supports_stencil_target() {
            return Err(Error::Unsupported(format!(
                "variant {variant}: a varying stack under mode=specialized routes its pixels \
                 by an 8-bit stencil, which `{}` cannot attach; shade it under mode=generic",
                self.gpu.device.report.name
            )));
        }
        let marker = self.gpu.shaders.compile(MARK_ENTRY, defines)?;
        let mut draws = Vec::new();
        for (bit, &layer) in routing.marks.iter().enumerate() {
            let name = format!("mark layer {} {variant}", layer + 1);
            let pipeline = self.build(
                &marker,
                Some(StencilUse::Mark),
                &key.mark_spec(layer),
                &name,
            )?;
            draws.push(Draw {
                pipeline,
                stencil: Some((1 << bit, 0, 1 << bit)),
            });
        }
        let main = draws.len();
        for class in &routing.classes {
            let name = format!("forward {variant} class {:#04x}", class.bits);
            let spec = key.class_spec(class);
            let pipeline = self.build(fragment, Some(StencilUse::Equal), &spec, &name)?;
            draws.push(Draw {
                pipeline,
                stencil: Some((class.bits, routing.compare_mask(), 0)),
            });
        }
        Ok((draws, main))
    }

    /// The deferred path's pipelines (`render::deferred`): the G-buffer's draw and the
    /// shading kernel over the `shared` sets.
    fn deferred(
        &self,
        key: &PassKey,
        shared: [&DescriptorSetLayout; 2],
        spec: ShadeSpec,
        defines: &[(&'static str, &'static str)],
    ) -> Result<DeferredPipelines> {
        let variant = key.variant;
        if key.is_reference() {
            return Err(Error::Unsupported(
                "the reference image is drawn by the forward path only".into(),
            ));
        }
        let fragment = self.gpu.shaders.compile(GBUFFER_ENTRY, defines)?;
        let name = format!("g-buffer {variant}");
        let gbuffer = self.build_into(&fragment, &[GBUFFER_FORMAT; 2], None, &spec, &name)?;
        DeferredPipelines::new(
            self.gpu,
            gbuffer,
            shared,
            key,
            spec,
            defines,
            self.color_format,
        )
    }
}
