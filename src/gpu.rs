//! The device and shader compiler every pass is built from, the pipeline cache every pipeline
//! goes through (`crate::pipeline_cache`: kept on disk between runs), and the compute-kernel
//! helper the table builders share.

use std::path::Path;
use std::sync::Arc;

use crate::error::Result;
use crate::pipeline_cache::{self, PersistentCache};
use crate::shader::kernel::{KernelInterface, WorkGroupSpec};
use crate::shader::ShaderCompiler;
use crate::vk::{
    Buffer, DescriptorSet, DescriptorSetLayout, Device, DeviceSelector, GraphicsDesc, InstanceDesc,
    Pipeline, PipelineCreation, PipelineLayout, Recorder, SpecConstants, Stages,
};

/// Called with a pipeline's name and how its creation went, for each pipeline a [`Gpu`] builds.
type PipelineObserver = Box<dyn Fn(&str, &PipelineCreation) + Send + Sync>;

pub struct Gpu {
    pub device: Arc<Device>,
    pub shaders: ShaderCompiler,
    pipelines: PersistentCache,
    observer: Option<PipelineObserver>,
}

impl Gpu {
    /// The device `selector` picks, with the pipeline cache of `pipeline_cache::default_dir`.
    pub fn new(instance: InstanceDesc, selector: &DeviceSelector) -> Result<Self> {
        Self::with_pipeline_cache(instance, selector, pipeline_cache::default_dir().as_deref())
    }

    /// [`Gpu::new`] with the pipeline cache's file in `dir`; `None`: in memory only.
    pub fn with_pipeline_cache(
        instance: InstanceDesc,
        selector: &DeviceSelector,
        dir: Option<&Path>,
    ) -> Result<Self> {
        let device = Device::create(instance, selector)?;
        Ok(Self {
            pipelines: PersistentCache::open(&device, dir)?,
            device,
            shaders: ShaderCompiler::new()?,
            observer: None,
        })
    }

    /// With the validation layer on: what the tests use. The pipeline cache stays in memory,
    /// so tests neither read nor write the user's.
    pub fn validated() -> Result<Self> {
        Self::with_pipeline_cache(InstanceDesc::validated(), &DeviceSelector::Best, None)
    }

    /// The pipeline cache, and the file it is saved to.
    pub fn pipeline_cache(&self) -> &PersistentCache {
        &self.pipelines
    }

    /// Calls `observer` with each pipeline built from now on (the commands print them).
    pub fn on_pipeline_built(
        &mut self,
        observer: impl Fn(&str, &PipelineCreation) + Send + Sync + 'static,
    ) {
        self.observer = Some(Box::new(observer));
    }

    fn built(&self, pipeline: Pipeline, name: &str) -> Pipeline {
        if let Some(observer) = &self.observer {
            observer(name, &pipeline.creation);
        }
        pipeline
    }

    /// A graphics pipeline, through the pipeline cache.
    pub fn graphics_pipeline<S: SpecConstants>(
        &self,
        layout: &PipelineLayout,
        desc: &GraphicsDesc<'_>,
        spec: &S,
        name: &str,
    ) -> Result<Pipeline> {
        let pipeline = Pipeline::graphics(self.pipelines.cache(), layout, desc, spec, name)?;
        Ok(self.built(pipeline, name))
    }

    /// A compute pipeline, through the pipeline cache.
    pub fn compute_pipeline<S: SpecConstants>(
        &self,
        layout: &PipelineLayout,
        spirv: &[u32],
        spec: &S,
        name: &str,
    ) -> Result<Pipeline> {
        let pipeline = Pipeline::compute(self.pipelines.cache(), layout, spirv, spec, name)?;
        Ok(self.built(pipeline, name))
    }
}

/// A compute entry point made from its [`KernelInterface`]: its own descriptor set layout and
/// push-constant block, after the set layouts it shares with other passes (the shading inputs
/// are set 0 of every entry point that shades), with the interface's work-group size.
pub struct ComputeKernel {
    pub interface: KernelInterface,
    /// The kernel's own set: index `interface.own_set()`.
    pub set_layout: DescriptorSetLayout,
    pub layout: PipelineLayout,
    pub pipeline: Pipeline,
}

impl ComputeKernel {
    /// Compiles `interface.entry` with `defines` (a variant's `defines()`) and makes its
    /// pipeline: `shared` set layouts first (the shading set when the kernel shades), then
    /// the kernel's own; `spec` gets the interface's work-group size.
    pub fn build<S: WorkGroupSpec>(
        gpu: &Gpu,
        interface: &KernelInterface,
        defines: &[(&str, &str)],
        shared: &[&DescriptorSetLayout],
        spec: S,
    ) -> Result<Self> {
        let entry = interface.entry;
        if shared.len() != interface.own_set() as usize {
            return Err(crate::error::Error::Unsupported(format!(
                "{entry}: {} shared set layouts given, its interface names {}",
                shared.len(),
                interface.own_set()
            )));
        }
        let spirv = gpu.shaders.compile(entry, defines)?;
        let device = &gpu.device;
        let set_layout =
            DescriptorSetLayout::new(device, interface.bindings, Stages::Compute, entry)?;
        let mut sets = shared.to_vec();
        sets.push(&set_layout);
        let layout =
            PipelineLayout::new(device, &sets, interface.push.size, Stages::Compute, entry)?;
        let spec = spec.with_local_size(interface.local_size);
        let pipeline = gpu.compute_pipeline(&layout, &spirv, &spec, entry)?;
        Ok(Self {
            interface: *interface,
            set_layout,
            layout,
            pipeline,
        })
    }

    /// Records one dispatch covering `invocations` (x, y, z): binds `sets` in order (the
    /// shared ones first) and `push`, then dispatches the work groups that cover them.
    pub fn record_dispatch<P: bytemuck::Pod>(
        &self,
        rec: &mut Recorder,
        sets: &[&DescriptorSet],
        push: &P,
        invocations: [u32; 3],
    ) {
        self.bind(rec, sets, push);
        let [x, y, z] = self.interface.groups(invocations);
        rec.dispatch(x, y, z);
    }

    /// Records one dispatch whose work-group counts the GPU reads from `args` at byte
    /// `offset` (written by an earlier dispatch), with `sets` and `push` bound as
    /// [`ComputeKernel::record_dispatch`] binds them.
    pub fn record_dispatch_indirect<P: bytemuck::Pod>(
        &self,
        rec: &mut Recorder,
        sets: &[&DescriptorSet],
        push: &P,
        args: &Buffer,
        offset: u64,
    ) {
        self.bind(rec, sets, push);
        rec.dispatch_indirect(args, offset);
    }

    fn bind<P: bytemuck::Pod>(&self, rec: &mut Recorder, sets: &[&DescriptorSet], push: &P) {
        debug_assert_eq!(std::mem::size_of::<P>() as u32, self.interface.push.size);
        rec.bind_pipeline(&self.pipeline);
        for (index, set) in sets.iter().enumerate() {
            rec.bind_set(&self.pipeline, &self.layout, index as u32, set);
        }
        if std::mem::size_of::<P>() > 0 {
            rec.push_constants(&self.layout, push);
        }
    }
}
