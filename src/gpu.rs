//! The device and shader compiler every pass is built from, and the compute-kernel helper the
//! table builders share.

use std::sync::Arc;

use crate::error::Result;
use crate::shader::ShaderCompiler;
use crate::vk::{
    BindingKind, DescriptorSet, DescriptorSetLayout, Device, DeviceSelector, InstanceDesc,
    Pipeline, PipelineLayout, Recorder, SpecConstants, Stages,
};

pub struct Gpu {
    pub device: Arc<Device>,
    pub shaders: ShaderCompiler,
}

impl Gpu {
    pub fn new(instance: InstanceDesc, selector: &DeviceSelector) -> Result<Self> {
        Ok(Self {
            device: Device::create(instance, selector)?,
            shaders: ShaderCompiler::new()?,
        })
    }

    /// With the validation layer on: what the tests use.
    pub fn validated() -> Result<Self> {
        Self::new(InstanceDesc::validated(), &DeviceSelector::Best)
    }
}

/// A compute entry point with its own descriptor set layout and push-constant block, after
/// the set layouts it shares with other passes (the shading inputs are set 0 of every entry
/// point that shades).
pub struct ComputeKernel {
    /// The kernel's own set: index `shared_sets`.
    pub set_layout: DescriptorSetLayout,
    pub layout: PipelineLayout,
    pub pipeline: Pipeline,
}

impl ComputeKernel {
    pub fn new<S: SpecConstants>(
        gpu: &Gpu,
        entry: &str,
        bindings: &[BindingKind],
        push_constant_bytes: u32,
        spec: &S,
    ) -> Result<Self> {
        Self::with_sets(gpu, entry, &[], &[], bindings, push_constant_bytes, spec)
    }

    /// As [`ComputeKernel::new`], with preprocessor definitions (a variant's `defines()`) and
    /// `shared` set layouts bound before the kernel's own (sets 0, 1, …; its own is last).
    pub fn with_sets<S: SpecConstants>(
        gpu: &Gpu,
        entry: &str,
        defines: &[(&str, &str)],
        shared: &[&DescriptorSetLayout],
        bindings: &[BindingKind],
        push_constant_bytes: u32,
        spec: &S,
    ) -> Result<Self> {
        let spirv = gpu.shaders.compile(entry, defines)?;
        let device = &gpu.device;
        let set_layout = DescriptorSetLayout::new(device, bindings, Stages::Compute, entry)?;
        let mut sets = shared.to_vec();
        sets.push(&set_layout);
        let layout =
            PipelineLayout::new(device, &sets, push_constant_bytes, Stages::Compute, entry)?;
        let pipeline = Pipeline::compute(device, &layout, &spirv, spec, entry)?;
        Ok(Self {
            set_layout,
            layout,
            pipeline,
        })
    }

    /// Records one dispatch of a kernel with no shared sets: binds it with `set` and `push`,
    /// then dispatches `groups` workgroups.
    pub fn record_dispatch<P: bytemuck::Pod>(
        &self,
        rec: &mut Recorder,
        set: &DescriptorSet,
        push: &P,
        groups: [u32; 3],
    ) {
        self.record_dispatch_sets(rec, &[set], push, groups);
    }

    /// As [`ComputeKernel::record_dispatch`], with every set in order (the shared ones first).
    pub fn record_dispatch_sets<P: bytemuck::Pod>(
        &self,
        rec: &mut Recorder,
        sets: &[&DescriptorSet],
        push: &P,
        groups: [u32; 3],
    ) {
        rec.bind_pipeline(&self.pipeline);
        for (index, set) in sets.iter().enumerate() {
            rec.bind_set(&self.pipeline, &self.layout, index as u32, set);
        }
        rec.push_constants(&self.layout, push);
        rec.dispatch(groups[0], groups[1], groups[2]);
    }
}
