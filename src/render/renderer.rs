//! The frame: sky, then the shaded sphere, into an RGBA16F (or, on request, RGBA32F) target
//! that is read back.
//!
//! Both draws sit in their own profiler scope; the shaded scope is the number lamina reports
//! (GPU time of the shaded draw and its fragment-shader invocations).

use half::f16;

use crate::error::Error;
use crate::error::Result;
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::model::LayerParams;
use crate::shader::interface::{
    lights_block, material_buffer, FrameConstants, SCENE_BINDINGS, SCENE_SET, SHADING_SET,
};
use crate::shader::specialize::{shade_spec, SpecializeError};
use crate::tables::environment::{EnvDesc, Environment};
use crate::variant::{Mode, Model, VariantKey};
use crate::vk::{
    submit_and_wait, texel_bytes, Access, Buffer, BufferDesc, BufferUsageFlags, DescriptorSet,
    DescriptorSetLayout, Format, GpuProfiler, Image, ImageDesc, ImageState, PipelineLayout,
    Resource, Sampler, SamplerDesc, ScopeTiming, Stages,
};

use super::baked::{self, BakedTable};
use super::forward::{ForwardPass, PassMaterial};
use super::inputs::ShadingInputs;
use super::lights::Lighting;
use super::scene::{uv_sphere, Camera, Mesh};
use super::sky::SkyPass;
use super::surface::SurfaceTexture;
use crate::material::Surface;
use std::sync::Arc;

/// The render target's format: linear HDR RGBA.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TargetFormat {
    /// Half floats (RGBA16F): what `lamina render` writes to EXR and the viewer shows.
    #[default]
    Half,
    /// Floats (RGBA32F): for comparisons finer than a half float's rounding (2⁻¹¹ relative).
    Float,
}

impl TargetFormat {
    /// The Vulkan format of the target.
    pub fn format(self) -> Format {
        match self {
            Self::Half => Format::R16G16B16A16_SFLOAT,
            Self::Float => Format::R32G32B32A32_SFLOAT,
        }
    }
}

/// One rendered image and what the GPU measured while drawing it.
pub struct RenderedFrame {
    pub width: u32,
    pub height: u32,
    /// Linear radiance, rows top to bottom (a half-float target's values, widened exactly).
    pub pixels: Vec<[f32; 4]>,
    pub sky: ScopeTiming,
    pub shaded: ScopeTiming,
}

/// Where [`Renderer::render_observed`] stands when it calls its observer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadedPhase {
    Before,
    After,
}

pub struct Renderer<'g> {
    gpu: &'g Gpu,
    pub environment: Environment,
    /// Set 0: the stack and the tables of every variant prepared so far.
    pub inputs: ShadingInputs<'g>,
    /// Set 1: frame constants and the prefiltered environment.
    scene_layout: DescriptorSetLayout,
    layout: PipelineLayout,
    sampler: Sampler,
    sky: SkyPass,
    vertices: Buffer,
    indices: Buffer,
    index_count: u32,
    target: TargetFormat,
    pub camera: Camera,
    /// The environment's scale and the analytic lights (the environment alone by default).
    pub lighting: Lighting,
    /// The frame's index, which seeds a reference pass's samples (`render::reference`).
    pub frame_index: u32,
    /// The maps of every spatially varying stack set so far ([`Renderer::set_surface`]), and
    /// the one passes are prepared and frames rendered for (`None`: uniform stacks).
    surfaces: Vec<SurfaceTexture>,
    current_surface: Option<usize>,
}

impl<'g> Renderer<'g> {
    /// A renderer into a half-float target.
    pub fn new(gpu: &'g Gpu, equirect: &HdrImage, env: EnvDesc) -> Result<Self> {
        Self::with_target(gpu, equirect, env, TargetFormat::Half)
    }

    /// A renderer into a `target` target: every pipeline it builds writes that format.
    pub fn with_target(
        gpu: &'g Gpu,
        equirect: &HdrImage,
        env: EnvDesc,
        target: TargetFormat,
    ) -> Result<Self> {
        let device = &gpu.device;
        let environment = Environment::build(gpu, equirect, env)?;
        let inputs = ShadingInputs::new(gpu)?;
        let scene_layout = DescriptorSetLayout::new(
            device,
            &SCENE_BINDINGS.map(|b| b.kind),
            Stages::Graphics,
            "scene",
        )?;
        let layout = PipelineLayout::new(
            device,
            &[&inputs.layout.set_layout, &scene_layout],
            0,
            Stages::Graphics,
            "scene",
        )?;
        let sampler = Sampler::new(device, SamplerDesc::linear_clamp(), "scene")?;
        let sky = SkyPass::new(gpu, &layout, target.format())?;
        let mesh = uv_sphere(64, 128);
        let vertices = Buffer::with_data(
            device,
            BufferUsageFlags::VERTEX_BUFFER,
            &mesh.vertices,
            "sphere vertices",
        )?;
        let indices = Buffer::with_data(
            device,
            BufferUsageFlags::INDEX_BUFFER,
            &mesh.indices,
            "sphere indices",
        )?;
        Ok(Self {
            gpu,
            environment,
            inputs,
            scene_layout,
            layout,
            sampler,
            sky,
            vertices,
            indices,
            index_count: mesh.indices.len() as u32,
            target,
            camera: Camera::default(),
            lighting: Lighting::default(),
            frame_index: 0,
            surfaces: Vec::new(),
            current_surface: None,
        })
    }

    /// The device this renderer draws on.
    pub fn gpu(&self) -> &'g Gpu {
        self.gpu
    }

    /// The format of the targets this renderer draws into.
    pub fn target(&self) -> TargetFormat {
        self.target
    }

    /// Replaces the drawn mesh (the sphere by default).
    pub fn set_mesh(&mut self, mesh: &Mesh) -> Result<()> {
        let device = &self.gpu.device;
        self.vertices = Buffer::with_data(
            device,
            BufferUsageFlags::VERTEX_BUFFER,
            &mesh.vertices,
            "mesh vertices",
        )?;
        self.indices = Buffer::with_data(
            device,
            BufferUsageFlags::INDEX_BUFFER,
            &mesh.indices,
            "mesh indices",
        )?;
        self.index_count = mesh.indices.len() as u32;
        Ok(())
    }

    /// Replaces the environment (prefiltered from `equirect` per `env`).
    pub fn set_environment(&mut self, equirect: &HdrImage, env: EnvDesc) -> Result<()> {
        self.environment = Environment::build(self.gpu, equirect, env)?;
        Ok(())
    }

    /// Sets the spatial variation of the stacks that later passes and frames shade: a
    /// stack's [`crate::material::Stack::surface`] (its maps are uploaded once per surface),
    /// or `None` for uniform stacks. A pass prepared for one kind renders only that kind.
    pub fn set_surface(&mut self, surface: Option<&Arc<Surface>>) -> Result<()> {
        self.current_surface = match surface {
            None => None,
            Some(s) => match self.surfaces.iter().position(|t| t.holds(s)) {
                Some(i) => Some(i),
                None => {
                    self.surfaces.push(SurfaceTexture::upload(self.gpu, s)?);
                    Some(self.surfaces.len() - 1)
                }
            },
        };
        Ok(())
    }

    /// The maps set by [`Renderer::set_surface`].
    fn surface_texture(&self) -> Option<&SurfaceTexture> {
        self.current_surface.map(|i| &self.surfaces[i])
    }

    /// Compiles and builds the pipeline of `variant` (and the tables it samples) for the
    /// stack `layers` (top first): under `mode=generic` the pass shades any stack that fits;
    /// under the other modes it is built for this one (its structure, its values, or its baked
    /// lobes, `render::baked`, at [`baked::DEFAULT_SIZE`] samples).
    pub fn prepare(&mut self, variant: VariantKey, layers: &[LayerParams]) -> Result<ForwardPass> {
        self.prepare_baked(variant, layers, baked::DEFAULT_SIZE)
    }

    /// [`Renderer::prepare`] with a baked table of `baked_size` samples per lobe.
    pub fn prepare_baked(
        &mut self,
        variant: VariantKey,
        layers: &[LayerParams],
        baked_size: u32,
    ) -> Result<ForwardPass> {
        self.inputs.prepare(variant)?;
        let specialize = |e: SpecializeError| Error::Unsupported(format!("variant {variant}: {e}"));
        if variant.model == Model::Ggx && variant.mode.per_material() {
            return Err(Error::Unsupported(format!(
                "variant {variant}: model=ggx is the generic baseline; it has no per-material \
                 mode (use mode=generic)"
            )));
        }
        if self.current_surface.is_some() && variant.mode.per_material() {
            return Err(Error::Unsupported(format!(
                "variant {variant}: this stack varies over the surface (textures, patterns or \
                 coverage); it shades under mode=generic only, which reads its maps per pixel"
            )));
        }
        if !variant.mode.per_material() {
            let mut spec = shade_spec(variant, layers, None).map_err(specialize)?;
            spec.surface_maps = self
                .surface_texture()
                .map_or(0, |t| t.surface.maps.spec_bits());
            spec.diffuse_base = u32::from(crate::model::ends_diffuse(layers));
            spec.lights = u32::from(!self.lighting.lights.is_empty());
            let format = self.target.format();
            let pass = ForwardPass::new(self.gpu, &self.layout, format, variant, &spec, None)?;
            return Ok(pass);
        }
        let baked = if variant.mode == Mode::Baked {
            let evaluator = baked::evaluator_for(self.gpu, variant, layers.len())?;
            let table = BakedTable::build(&evaluator, layers, baked_size)?;
            let texture = table.upload(self.gpu, "baked lobes")?;
            Some((table, texture))
        } else {
            None
        };
        let mut spec = shade_spec(variant, layers, baked.as_ref().map(|(t, _)| t.shape))
            .map_err(specialize)?;
        spec.lights = u32::from(!self.lighting.lights.is_empty());
        ForwardPass::new(
            self.gpu,
            &self.layout,
            self.target.format(),
            variant,
            &spec,
            Some(PassMaterial {
                layers: layers.to_vec(),
                baked,
                reference: false,
            }),
        )
    }

    /// The reference pass of the uniform stack `layers` in `model` (`render::reference`),
    /// reading the exact model's lobes from `table`.
    pub fn prepare_reference(
        &mut self,
        model: Model,
        layers: &[LayerParams],
        table: BakedTable,
    ) -> Result<ForwardPass> {
        if self.current_surface.is_some() {
            return Err(Error::Unsupported(
                "this stack varies over the surface (textures, patterns or coverage); the \
                 reference renders uniform stacks"
                    .into(),
            ));
        }
        if self.target != TargetFormat::Float {
            return Err(Error::Unsupported(
                "a reference pass averages frames finer than a half float: render it into a \
                 float target (TargetFormat::Float)"
                    .into(),
            ));
        }
        let variant = VariantKey {
            model,
            mode: Mode::Baked,
            ..VariantKey::default()
        };
        self.inputs.prepare(variant)?;
        let mut spec = variant.spec();
        // Two rows per lobe (`render::reference::lobe_table`).
        spec.lobe_count = table.shape.lobe_count / 2;
        spec.retro_mask = table.shape.retro_mask;
        spec.baked_size = table.shape.size;
        spec.lights = u32::from(!self.lighting.lights.is_empty());
        spec.diffuse_base = u32::from(crate::model::ends_diffuse(layers));
        let texture = table.upload(self.gpu, "reference lobes")?;
        ForwardPass::new(
            self.gpu,
            &self.layout,
            self.target.format(),
            variant,
            &spec,
            Some(PassMaterial {
                layers: layers.to_vec(),
                baked: Some((table, texture)),
                reference: true,
            }),
        )
    }

    /// Renders one frame of the stack `layers` (top first) with a prepared pass.
    pub fn render(
        &self,
        pass: &ForwardPass,
        layers: &[LayerParams],
        width: u32,
        height: u32,
    ) -> Result<RenderedFrame> {
        self.render_observed(pass, layers, width, height, &mut |_| {})
    }

    /// [`Renderer::render`], with `observe` called on the host right before the shaded draw's
    /// submission and right after it completed. The sky, the shaded draw and the read-back are
    /// three submissions, so what runs between the two calls is the shaded draw's recording,
    /// submission and execution only (the instruction counter brackets it).
    pub fn render_observed(
        &self,
        pass: &ForwardPass,
        layers: &[LayerParams],
        width: u32,
        height: u32,
        observe: &mut dyn FnMut(ShadedPhase),
    ) -> Result<RenderedFrame> {
        pass.check_material(layers)?;
        let bits = self
            .surface_texture()
            .map_or(0, |t| t.surface.maps.spec_bits());
        match (self.surface_texture(), pass.surface != 0) {
            (Some(s), true) if s.surface.layers.len() == layers.len() && bits == pass.surface => {}
            (None, false) => {}
            (Some(s), true) if s.surface.layers.len() != layers.len() => {
                return Err(Error::Unsupported(format!(
                    "the surface's maps are for {} layers; this stack has {}",
                    s.surface.layers.len(),
                    layers.len()
                )))
            }
            (Some(_), true) => {
                return Err(Error::Unsupported(
                    "this pass was prepared for a stack whose maps vary other fields; prepare \
                     one for this stack"
                        .into(),
                ))
            }
            (_, built_for_maps) => {
                let kind = |maps: bool| if maps { "a varying" } else { "a uniform" };
                return Err(Error::Unsupported(format!(
                    "this pass was prepared for {} stack and the renderer holds {}; set the \
                     surface before preparing",
                    kind(built_for_maps),
                    kind(self.current_surface.is_some())
                )));
            }
        }
        let device = &self.gpu.device;
        let view_proj = self.camera.view_proj(width as f32 / height as f32);
        let constants = FrameConstants {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            camera_pos: self.camera.eye.extend(1.0).to_array(),
            params: [
                self.environment.desc.mip_count as f32,
                self.lighting.environment as f32,
                self.frame_index as f32,
                0.0,
            ],
            irradiance: self.environment.irradiance,
        };
        let uniforms = Buffer::with_data(
            device,
            BufferUsageFlags::UNIFORM_BUFFER,
            &[constants],
            "frame constants",
        )?;
        let lights = Buffer::with_data(
            device,
            BufferUsageFlags::STORAGE_BUFFER,
            &lights_block(&self.lighting.lights),
            "lights",
        )?;
        let maps = self.surface_texture().map(|t| &t.surface.maps);
        let material = material_buffer(device, layers, maps, "material")?;
        let baked = pass
            .material
            .as_ref()
            .and_then(|m| m.baked.as_ref())
            .map(|(_, texture)| &texture.view);
        let shading = self.inputs.bind(
            pass.variant,
            &material,
            baked,
            self.surface_texture().map(|t| &t.view),
            "shading",
        )?;
        let mut scene = DescriptorSet::new(device, &self.scene_layout, "scene")?;
        scene
            .write(0, Resource::Buffer(&uniforms))
            .write(1, Resource::Sampled(&self.environment.view, &self.sampler))
            .write(2, Resource::Buffer(&lights))
            .write(3, Resource::Buffer(&self.environment.sampling));

        let format = self.target.format();
        let target = Image::new(
            device,
            ImageDesc::render_target(format, width, height),
            "render target",
        )?;
        let target_view = target.view("render target")?;
        let readback = Buffer::new(
            device,
            BufferDesc::readback(u64::from(width) * u64::from(height) * texel_bytes(format)),
            "render readback",
        )?;
        let mut profiler = GpuProfiler::new(device, 2, "frame")?;

        submit_and_wait(device, "sky", |rec| {
            rec.transition(
                &target,
                0..1,
                ImageState::Undefined,
                ImageState::ColorAttachment,
            );
            rec.bind_pipeline(&self.sky.pipeline);
            rec.bind_set(&self.sky.pipeline, &self.layout, SHADING_SET, &shading);
            rec.bind_set(&self.sky.pipeline, &self.layout, SCENE_SET, &scene);
            let scope = profiler
                .begin(rec, "sky")
                .expect("first scope of a fresh profiler");
            rec.begin_rendering(&target_view, width, height, [0.0, 0.0, 0.0, 1.0]);
            rec.draw(3);
            rec.end_rendering();
            profiler.end(rec, scope);
            Ok(())
        })?;

        observe(ShadedPhase::Before);
        submit_and_wait(device, "shaded", |rec| {
            rec.bind_pipeline(&pass.pipeline);
            rec.bind_set(&pass.pipeline, &self.layout, SHADING_SET, &shading);
            rec.bind_set(&pass.pipeline, &self.layout, SCENE_SET, &scene);
            let scope = profiler
                .begin(rec, "shaded")
                .expect("the sky scope is closed");
            rec.begin_rendering_load(&target_view, width, height);
            rec.bind_vertex_buffer(&self.vertices);
            rec.bind_index_buffer_u32(&self.indices);
            rec.draw_indexed(self.index_count);
            rec.end_rendering();
            profiler.end(rec, scope);
            Ok(())
        })?;
        observe(ShadedPhase::After);

        submit_and_wait(device, "read-back", |rec| {
            rec.transition(
                &target,
                0..1,
                ImageState::ColorAttachment,
                ImageState::TransferSrc,
            );
            rec.copy_image_to_buffer(&target, 0, &readback);
            rec.barrier(Access::TransferWrite, Access::HostRead);
            Ok(())
        })?;

        let mut scopes = profiler.results()?.into_iter();
        let (sky, shaded) = (
            scopes.next().expect("sky scope"),
            scopes.next().expect("shaded scope"),
        );
        Ok(RenderedFrame {
            width,
            height,
            pixels: match self.target {
                TargetFormat::Half => readback
                    .read::<[f16; 4]>()
                    .into_iter()
                    .map(|p| p.map(f16::to_f32))
                    .collect(),
                TargetFormat::Float => readback.read::<[f32; 4]>(),
            },
            sky,
            shaded,
        })
    }
}
