//! The shaded pass: the sphere, lit by the prefiltered environment, in one shader variant —
//! for every material (`mode=generic`) or for one (every other mode: the pass keeps the
//! material it was built for, and a baked material's lobe table).

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::model::LayerParams;
use crate::shader::specialize::{check_generic_fit, Structure};
use crate::variant::{Mode, ShadeSpec, VariantKey};
use crate::vk::{Format, GraphicsDesc, Pipeline, PipelineLayout};

use super::baked::{BakedTable, BakedTexture};
use super::scene::Vertex;

/// The entry points compiled per variant (the only ones that see the variant's defines).
pub const ENTRIES: [&str; 2] = ["forward.vert.glsl", "forward.frag.glsl"];

/// What a per-material pass was built for.
pub struct PassMaterial {
    pub layers: Vec<LayerParams>,
    /// `mode=baked`: the lobe table, on the host and in the texture the pass reads.
    pub baked: Option<(BakedTable, BakedTexture)>,
    /// A reference pass (`render::reference`): `baked` holds the exact model's lobes, which
    /// it integrates by Monte Carlo (`LAMINA_REFERENCE`).
    pub reference: bool,
}

pub struct ForwardPass {
    pub variant: VariantKey,
    pub pipeline: Pipeline,
    /// Size of the fragment shader's SPIR-V.
    pub spirv_bytes: usize,
    /// `None` under `mode=generic`.
    pub material: Option<PassMaterial>,
    /// The `SURFACE_MAPS` it was built with: 0 for uniform stacks, else the varying fields
    /// (`SurfaceMaps::spec_bits`).
    pub surface: u32,
    /// Built for a stack that ends in a diffuse base (`ShadeSpec::diffuse_base`).
    pub diffuse: bool,
    /// Built for a scene with analytic lights (`ShadeSpec::lights`).
    pub lights: bool,
}

impl ForwardPass {
    pub fn new(
        gpu: &Gpu,
        layout: &PipelineLayout,
        color_format: Format,
        variant: VariantKey,
        spec: &ShadeSpec,
        material: Option<PassMaterial>,
    ) -> Result<Self> {
        if variant.fp16 && !gpu.device.supports_fp16() {
            return Err(Error::Unsupported(format!(
                "fp16=on needs the shaderFloat16 feature, which `{}` lacks",
                gpu.device.report.name
            )));
        }
        let mut defines = variant.defines();
        if material.as_ref().is_some_and(|m| m.reference) {
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
        let pipeline = gpu.graphics_pipeline(layout, &desc, spec, &format!("forward {variant}"))?;
        Ok(Self {
            variant,
            pipeline,
            spirv_bytes: fragment.len() * 4,
            material,
            surface: spec.surface_maps,
            diffuse: spec.diffuse_base != 0,
            lights: spec.lights != 0,
        })
    }

    /// Whether this pass is `variant`'s and shades `layers` with maps of `surface` (the
    /// stack's `render::surface::spec_bits`).
    pub fn shades(&self, variant: VariantKey, layers: &[LayerParams], surface: u32) -> bool {
        self.variant == variant && self.surface == surface && self.check_material(layers).is_ok()
    }

    /// Whether this pass shades `layers` as its variant says: any stack that fits a generic
    /// pass, the same structure under `specialized`, the same stack under the other modes.
    pub fn check_material(&self, layers: &[LayerParams]) -> Result<()> {
        if crate::model::ends_diffuse(layers) != self.diffuse {
            let kind = |d: bool| if d { "ends in" } else { "has no" };
            return Err(Error::Unsupported(format!(
                "this pass ({}) was built for a stack that {} diffuse base and this one {} one; \
                 prepare a pass for this stack",
                self.variant,
                kind(self.diffuse),
                kind(!self.diffuse)
            )));
        }
        let Some(own) = &self.material else {
            return check_generic_fit(self.variant, layers);
        };
        let same = match self.variant.mode {
            Mode::Specialized => {
                let model = self.variant.model;
                Structure::of(model, layers).ok() == Structure::of(model, &own.layers).ok()
            }
            _ => own.layers == layers,
        };
        if same {
            Ok(())
        } else {
            Err(Error::Unsupported(format!(
                "this pass ({}) was built for another material; prepare one for this stack",
                self.variant
            )))
        }
    }
}
