//! The frame: sky, then the shaded sphere, into an RGBA16F (or, on request, RGBA32F) target
//! that is read back.
//!
//! Both draws sit in their own profiler scope; the shaded scope is the number lamina reports
//! (GPU time of the shaded draw and its fragment-shader invocations).

use half::f16;

use std::cell::RefCell;
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::material::Surface;
use crate::model::transport::Correction;
use crate::model::LayerParams;
use crate::shader::interface::{
    material_buffer, FrameConstants, SCENE_BINDINGS, SCENE_SET, SHADING_SET,
};
use crate::tables::environment::{EnvDesc, Environment};
use crate::tables::lobe_moments::LobeMomentsTable;
use crate::variant::{Ibl, Mode, Model, Transport, VariantKey};
use crate::vk::{
    submit_and_wait, texel_bytes, Access, Buffer, BufferDesc, BufferUsageFlags, DescriptorSet,
    DescriptorSetLayout, Format, GpuProfiler, Image, ImageDesc, ImageState, ImageUsageFlags,
    ImageView, PipelineLayout, Recorder, Resource, Sampler, SamplerDesc, ScopeTiming, Stages,
};

use super::baked::{self, BakedTable, BakedTexture};
use super::classes::Routing;
use super::deferred::{DeferredFrame, DeferredPipelines};
use super::forward::ForwardPass;
use super::inputs::ShadingInputs;
use super::lights::{lights_block, Lighting};
use super::pass::{MaterialKey, PassKey};
use super::scene::{uv_sphere, Camera, Mesh};
use super::sky::SkyPass;
use super::surface::SurfaceTexture;
use crate::tables::lamps::{lamp_values, LAMP_VALUES};

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
    /// Each lobe's mean direction and spread, where `ibl=matched` reads the matched cube.
    moments: LobeMomentsTable,
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
    /// The reference pass's sample stream (`render::reference::stream`), mixed into every
    /// frame's seed; 0 by default.
    pub seed: u32,
    /// The maps of every spatially varying stack set so far ([`Renderer::set_surface`]), and
    /// the one frames are rendered with (`None`: uniform stacks).
    surfaces: Vec<SurfaceTexture>,
    current_surface: Option<usize>,
    /// The energy ratios of the stacks rendered under `transport=corrected` so far, by
    /// variant and stack (the last few: building them walks the stack's transport).
    corrections: RefCell<Vec<(VariantKey, Vec<LayerParams>, Correction)>>,
    /// The routing last planned for a surface (its index in `surfaces`), model and stack:
    /// planning walks every texel of the coverage maps, which a frame should not repeat.
    routing: RefCell<Option<PlannedRouting>>,
}

/// A routing as planned: the surface's index, the model, the stack, and the routing.
type PlannedRouting = (usize, Model, Vec<LayerParams>, Routing);

/// Stacks whose `transport=corrected` ratios a renderer keeps.
const KEPT_CORRECTIONS: usize = 8;

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
        let moments = LobeMomentsTable::load_or_build(gpu)?;
        let inputs = ShadingInputs::new(gpu)?;
        // Read by the graphics passes and by the deferred path's shading kernel.
        let scene_layout = DescriptorSetLayout::new(
            device,
            &SCENE_BINDINGS.map(|b| b.kind),
            Stages::All,
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
            moments,
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
            seed: 0,
            surfaces: Vec::new(),
            current_surface: None,
            corrections: RefCell::new(Vec::new()),
            routing: RefCell::new(None),
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
        let matched = self.environment.matched_view().is_some();
        let lamps = self.environment.lamps_view().is_some();
        self.environment = Environment::build(self.gpu, equirect, env)?;
        // The passes prepared so far may read the matched cube, or the one without lamps.
        if matched {
            self.environment.build_matched(self.gpu)?;
        }
        if lamps {
            self.environment.build_lamps(self.gpu)?;
        }
        Ok(())
    }

    /// Sets the spatial variation of the stacks that later frames shade: a stack's
    /// [`crate::material::Stack::surface`] (its maps are uploaded once per surface), or `None`
    /// for uniform stacks. A frame renders with a pass whose key was made with the same kind.
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

    /// Compiles and builds the pipeline of `key` (and the tables it samples): under
    /// `mode=generic` the pass shades any stack that fits; under the other modes it is built
    /// for the key's stack (its structure, its values, or its baked lobes, `render::baked`, at
    /// [`baked::DEFAULT_SIZE`] samples).
    pub fn prepare(&mut self, key: &PassKey) -> Result<ForwardPass> {
        self.prepare_baked(key, baked::DEFAULT_SIZE)
    }

    /// [`Renderer::prepare`] for the uniform stack `layers` in `variant`, under the renderer's
    /// lighting.
    pub fn prepare_uniform(
        &mut self,
        variant: VariantKey,
        layers: &[LayerParams],
    ) -> Result<ForwardPass> {
        let key = PassKey::uniform(variant, layers, &self.lighting)?;
        self.prepare(&key)
    }

    /// [`Renderer::prepare`] with a baked table of `baked_size` samples per lobe.
    pub fn prepare_baked(&mut self, key: &PassKey, baked_size: u32) -> Result<ForwardPass> {
        let variant = key.variant;
        self.inputs.prepare(variant)?;
        match variant.ibl {
            Ibl::SplitSum => {}
            Ibl::Lamps => self.environment.build_lamps(self.gpu)?,
            _ => self.environment.build_matched(self.gpu)?,
        }
        let baked = match (variant.mode, key.layers()) {
            (Mode::Baked, Some(layers)) => {
                let evaluator = baked::evaluator_for(self.gpu, variant, layers.len())?;
                let table = BakedTable::build(&evaluator, layers, baked_size)?;
                let texture = table.upload(self.gpu, "baked lobes")?;
                Some((table, texture))
            }
            _ => None,
        };
        self.pass(key.clone(), baked)
    }

    /// The reference pass of the uniform stack `layers` in `model` (`render::reference`),
    /// reading the lobes from `table` (`render::reference::table_of`).
    pub fn prepare_reference(
        &mut self,
        model: Model,
        layers: &[LayerParams],
        table: BakedTable,
    ) -> Result<ForwardPass> {
        self.require_float_target()?;
        let key = PassKey::reference(model, layers, &self.lighting);
        self.inputs.prepare(key.variant)?;
        let texture = table.upload(self.gpu, "reference lobes")?;
        self.pass(key, Some((table, texture)))
    }

    /// The reference pass that evaluates `variant`'s lobes of `layers` per pixel, with the
    /// maps of `surface` (`render::reference::render_evaluated`).
    pub fn prepare_evaluated_reference(
        &mut self,
        variant: VariantKey,
        layers: &[LayerParams],
        surface: Option<&Surface>,
    ) -> Result<ForwardPass> {
        self.require_float_target()?;
        let key = PassKey::evaluated_reference(variant, layers, surface, &self.lighting);
        self.inputs.prepare(variant)?;
        self.pass(key, None)
    }

    /// Errs unless frames render into a float target, which a reference pass needs.
    fn require_float_target(&self) -> Result<()> {
        if self.target != TargetFormat::Float {
            return Err(Error::Unsupported(
                "a reference pass averages frames finer than a half float: render it into a \
                 float target (TargetFormat::Float)"
                    .into(),
            ));
        }
        Ok(())
    }

    fn pass(
        &self,
        mut key: PassKey,
        baked: Option<(BakedTable, BakedTexture)>,
    ) -> Result<ForwardPass> {
        key.lamps = self.lamps_of(key.variant);
        ForwardPass::new(
            self.gpu,
            &self.layout,
            [&self.inputs.layout.set_layout, &self.scene_layout],
            self.target.format(),
            key,
            baked,
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
        self.check_pass(pass, layers)?;
        let sets = self.frame_sets(pass, layers, width, height)?;
        let device = &self.gpu.device;
        let format = self.target.format();
        let mut target_desc = ImageDesc::render_target(format, width, height);
        if pass.deferred.is_some() {
            // The deferred path's kernel writes it as a storage image.
            target_desc = target_desc.usage(target_desc.usage | ImageUsageFlags::STORAGE);
        }
        let target = Image::new(device, target_desc, "render target")?;
        let target_view = target.view("render target")?;
        let readback = Buffer::new(
            device,
            BufferDesc::readback(u64::from(width) * u64::from(height) * texel_bytes(format)),
            "render readback",
        )?;
        let mut profiler = GpuProfiler::new(device, 2, "frame")?;

        self.draw_sky(&sets, &target, &target_view, &mut profiler)?;

        if let Some(deferred) = &pass.deferred {
            let gbuffer = DeferredFrame::new(
                self.gpu,
                deferred,
                &target_view,
                &self.sampler,
                width,
                height,
            )?;
            observe(ShadedPhase::Before);
            submit_and_wait(device, "shaded", |rec| {
                let scope = profiler
                    .begin(rec, "shaded")
                    .expect("the sky scope is closed");
                self.record_deferred(rec, deferred, &sets, &gbuffer, &target, [width, height]);
                profiler.end(rec, scope);
                Ok(())
            })?;
        } else {
            observe(ShadedPhase::Before);
            self.submit_forward(pass, &sets, &target_view, &mut profiler, width, height)?;
        }
        observe(ShadedPhase::After);

        let mut scopes = profiler.results()?.into_iter();
        let (sky, shaded) = (
            scopes.next().expect("sky scope"),
            scopes.next().expect("shaded scope"),
        );
        Ok(RenderedFrame {
            width,
            height,
            pixels: self.read_back(&target, &readback)?,
            sky,
            shaded,
        })
    }

    /// Records and submits the forward path's draws of `pass` into `target_view`, timed in
    /// `profiler`'s second scope (a routed pass's stencil made and cleared with them).
    fn submit_forward(
        &self,
        pass: &ForwardPass,
        sets: &FrameSets,
        target_view: &ImageView,
        profiler: &mut GpuProfiler,
        width: u32,
        height: u32,
    ) -> Result<()> {
        let device = &self.gpu.device;
        // A routed pass's stencil, cleared when its rendering begins.
        let stencil = if pass.routed() {
            let image = Image::new(
                device,
                ImageDesc::stencil_target(width, height),
                "class stencil",
            )?;
            let view = image.view("class stencil")?;
            Some((image, view))
        } else {
            None
        };
        submit_and_wait(device, "shaded", |rec| {
            if let Some((image, _)) = &stencil {
                rec.transition(
                    image,
                    0..1,
                    ImageState::Undefined,
                    ImageState::StencilAttachment,
                );
            }
            let scope = profiler
                .begin(rec, "shaded")
                .expect("the sky scope is closed");
            match &stencil {
                Some((_, view)) => {
                    rec.begin_rendering_load_stencil(target_view, view, width, height)
                }
                None => rec.begin_rendering_load(target_view, width, height),
            }
            rec.bind_vertex_buffer(&self.vertices);
            rec.bind_index_buffer_u32(&self.indices);
            for draw in &pass.draws {
                rec.bind_pipeline(&draw.pipeline);
                rec.bind_set(&draw.pipeline, &self.layout, SHADING_SET, &sets.shading);
                rec.bind_set(&draw.pipeline, &self.layout, SCENE_SET, &sets.scene);
                if let Some((reference, compare, write)) = draw.stencil {
                    rec.set_stencil(reference, compare, write);
                }
                rec.draw_indexed(self.index_count);
            }
            rec.end_rendering();
            profiler.end(rec, scope);
            Ok(())
        })?;
        Ok(())
    }

    /// Records the deferred path: the mesh into the G-buffer, then its shading into `target`
    /// (which the sky left as a colour attachment, and which is left as one).
    fn record_deferred(
        &self,
        rec: &mut Recorder<'_>,
        deferred: &DeferredPipelines,
        sets: &FrameSets,
        frame: &DeferredFrame,
        target: &Image,
        [width, height]: [u32; 2],
    ) {
        for image in &frame.images {
            rec.transition(
                image,
                0..1,
                ImageState::Undefined,
                ImageState::ColorAttachment,
            );
        }
        rec.begin_rendering_targets(&[&frame.views[0], &frame.views[1]], width, height, [0.0; 4]);
        rec.bind_pipeline(&deferred.gbuffer);
        rec.bind_set(&deferred.gbuffer, &self.layout, SHADING_SET, &sets.shading);
        rec.bind_set(&deferred.gbuffer, &self.layout, SCENE_SET, &sets.scene);
        rec.bind_vertex_buffer(&self.vertices);
        rec.bind_index_buffer_u32(&self.indices);
        rec.draw_indexed(self.index_count);
        rec.end_rendering();
        for image in &frame.images {
            rec.transition(
                image,
                0..1,
                ImageState::ColorAttachment,
                ImageState::ComputeRead,
            );
        }
        let shared = [&sets.shading, &sets.scene];
        frame.record_shading(rec, deferred, shared, target, [width, height]);
    }

    /// Records and submits the sky into `target` (cleared first), timed in `profiler`'s
    /// first scope.
    fn draw_sky(
        &self,
        sets: &FrameSets,
        target: &Image,
        target_view: &ImageView,
        profiler: &mut GpuProfiler,
    ) -> Result<()> {
        let (width, height, _) = target.desc.mip_extent(0);
        submit_and_wait(&self.gpu.device, "sky", |rec| {
            rec.transition(
                target,
                0..1,
                ImageState::Undefined,
                ImageState::ColorAttachment,
            );
            rec.bind_pipeline(&self.sky.pipeline);
            rec.bind_set(&self.sky.pipeline, &self.layout, SHADING_SET, &sets.shading);
            rec.bind_set(&self.sky.pipeline, &self.layout, SCENE_SET, &sets.scene);
            let scope = profiler
                .begin(rec, "sky")
                .expect("first scope of a fresh profiler");
            rec.begin_rendering(target_view, width, height, [0.0, 0.0, 0.0, 1.0]);
            rec.draw(3);
            rec.end_rendering();
            profiler.end(rec, scope);
            Ok(())
        })?;
        Ok(())
    }

    /// Copies the drawn `target` into `readback` and returns its texels as f32 (a half-float
    /// target's values, widened exactly).
    fn read_back(&self, target: &Image, readback: &Buffer) -> Result<Vec<[f32; 4]>> {
        submit_and_wait(&self.gpu.device, "read-back", |rec| {
            rec.transition(
                target,
                0..1,
                ImageState::ColorAttachment,
                ImageState::TransferSrc,
            );
            rec.copy_image_to_buffer(target, 0, readback);
            rec.barrier(Access::TransferWrite, Access::HostRead);
            Ok(())
        })?;
        Ok(match self.target {
            TargetFormat::Half => readback
                .read::<[f16; 4]>()
                .into_iter()
                .map(|p| p.map(f16::to_f32))
                .collect(),
            TargetFormat::Float => readback.read::<[f32; 4]>(),
        })
    }

    /// Errs unless `pass` shades `layers` with the maps set by [`Renderer::set_surface`] and
    /// the renderer's lighting: each of them compiled into the pass (its [`PassKey`]).
    /// The environment's lamps as a pass of `variant` holds them (`ibl=lamps`; none else).
    pub fn lamps_of(&self, variant: VariantKey) -> [f32; LAMP_VALUES] {
        match variant.ibl {
            Ibl::Lamps => lamp_values(self.environment.lamps()),
            _ => [0.0; LAMP_VALUES],
        }
    }

    fn check_pass(&self, pass: &ForwardPass, layers: &[LayerParams]) -> Result<()> {
        pass.key.admits(layers)?;
        if pass.key.lamps != self.lamps_of(pass.key.variant) {
            return Err(Error::Unsupported(format!(
                "this pass ({}) holds the lamps of another environment than the renderer's: \
                 prepare it again after setting the environment",
                pass.key.variant
            )));
        }
        if let (Some(surface), MaterialKey::Classes(_)) = (self.current_surface, &pass.key.material)
        {
            pass.key
                .routes(&self.routing(surface, pass.key.variant.model, layers)?)?;
        }
        let key = &pass.key;
        match (self.surface_texture(), key.surface != 0) {
            (None, false) => {}
            (Some(s), true) if s.surface.layers.len() != layers.len() => {
                return Err(Error::Unsupported(format!(
                    "the surface's maps are for {} layers; this stack has {}",
                    s.surface.layers.len(),
                    layers.len()
                )))
            }
            (Some(s), true) if s.surface.maps.spec_bits() == key.surface => {}
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
                     surface that the pass's key was made with",
                    kind(built_for_maps),
                    kind(self.current_surface.is_some())
                )));
            }
        }
        let lit = !self.lighting.lights.is_empty();
        if key.lights != lit {
            let kind = |lights: bool| if lights { "with" } else { "without" };
            return Err(Error::Unsupported(format!(
                "this pass ({}) was prepared for a scene {} analytic lights and the renderer's \
                 lighting is {} them; prepare one under this lighting",
                key.variant,
                kind(key.lights),
                kind(lit)
            )));
        }
        Ok(())
    }

    /// The routing of `layers` in `model` over surface `surface`'s maps
    /// (`render::classes`), planned once per surface, model and stack.
    fn routing(&self, surface: usize, model: Model, layers: &[LayerParams]) -> Result<Routing> {
        let mut kept = self.routing.borrow_mut();
        if let Some((s, m, l, routing)) = kept.as_ref() {
            if *s == surface && *m == model && l == layers {
                return Ok(routing.clone());
            }
        }
        let maps = &self.surfaces[surface].surface.maps;
        let routing = Routing::plan(model, layers, maps)
            .map_err(|e| Error::Unsupported(format!("routing the stack's pixels: {e}")))?;
        *kept = Some((surface, model, layers.to_vec(), routing.clone()));
        Ok(routing)
    }

    /// The energy ratios of `layers` under `variant` when its transport is `corrected`, from
    /// the very tables it samples (their CPU twins): built once per variant and stack.
    fn correction(
        &self,
        variant: VariantKey,
        layers: &[LayerParams],
    ) -> Result<Option<Correction>> {
        if variant.transport != Transport::Corrected {
            return Ok(None);
        }
        let mut kept = self.corrections.borrow_mut();
        if let Some((_, _, c)) = kept.iter().find(|(v, l, _)| *v == variant && l == layers) {
            return Ok(Some(c.clone()));
        }
        let fgd = self.inputs.fgd_lookup(variant)?;
        let tir = self.inputs.tir_lookup(variant);
        let c = Correction::new(
            layers,
            variant.model,
            variant.interfaces,
            &fgd,
            tir.as_ref(),
        );
        if kept.len() >= KEPT_CORRECTIONS {
            kept.remove(0);
        }
        kept.push((variant, layers.to_vec(), c.clone()));
        Ok(Some(c))
    }

    /// The frame's descriptor sets: the shading set (`layers`, the tables of `pass`'s variant,
    /// its baked lobes, the surface's maps) and the scene set (frame constants for a
    /// `width`×`height` target, the environment, the lights).
    fn frame_sets(
        &self,
        pass: &ForwardPass,
        layers: &[LayerParams],
        width: u32,
        height: u32,
    ) -> Result<FrameSets> {
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
                f32::from_bits(self.seed),
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
        let correction = self.correction(pass.key.variant, layers)?;
        let material = material_buffer(device, layers, maps, correction.as_ref(), "material")?;
        let baked = pass.baked.as_ref().map(|(_, texture)| &texture.view);
        let shading = self.inputs.bind(
            pass.key.variant,
            &material,
            baked,
            self.surface_texture().map(|t| &t.view),
            "shading",
        )?;
        let cube = match pass.key.variant.ibl {
            Ibl::Lamps => self.environment.lamps_view(),
            _ => self.environment.matched_view(),
        };
        let matched = match cube {
            Some(view) => view,
            None if pass.key.variant.ibl == Ibl::SplitSum => &self.environment.view,
            None => {
                return Err(Error::Unsupported(format!(
                    "the pass of {} reads a matched environment cube, which this renderer \
                     has not built: prepare the pass with this renderer",
                    pass.key.variant
                )))
            }
        };
        let lamps_irradiance = self.environment.lamps_irradiance_binding();
        let mut scene = DescriptorSet::new(device, &self.scene_layout, "scene")?;
        scene
            .write(0, Resource::Buffer(&uniforms))
            .write(1, Resource::Sampled(&self.environment.view, &self.sampler))
            .write(2, Resource::Buffer(&lights))
            .write(3, Resource::Buffer(&self.environment.sampling))
            // A pass whose `ibl` reads the matched cube built it when it was prepared; any
            // other never reads the binding, which holds the Karis cube until then.
            .write(4, Resource::Sampled(matched, &self.sampler))
            .write(5, Resource::Sampled(&self.moments.view, &self.sampler))
            .write(6, Resource::Sampled(lamps_irradiance, &self.sampler));
        Ok(FrameSets {
            shading,
            scene,
            _buffers: [uniforms, lights, material],
        })
    }
}

/// A frame's descriptor sets and the buffers they point at (alive while the sets are used).
struct FrameSets {
    shading: DescriptorSet,
    scene: DescriptorSet,
    _buffers: [Buffer; 3],
}
