//! The device and shader compiler every pass is built from, and the compute-kernel helper the
//! table builders share.

use std::sync::Arc;

use crate::error::Result;
use crate::shader::kernel::{KernelInterface, WorkGroupSpec};
use crate::shader::ShaderCompiler;
use crate::vk::{
    DescriptorSet, DescriptorSetLayout, Device, DeviceSelector, InstanceDesc, Pipeline,
    PipelineLayout, Recorder, Stages,
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
        let pipeline = Pipeline::compute(device, &layout, &spirv, &spec, entry)?;
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
        debug_assert_eq!(std::mem::size_of::<P>() as u32, self.interface.push.size);
        rec.bind_pipeline(&self.pipeline);
        for (index, set) in sets.iter().enumerate() {
            rec.bind_set(&self.pipeline, &self.layout, index as u32, set);
        }
        if std::mem::size_of::<P>() > 0 {
            rec.push_constants(&self.layout, push);
        }
        let [x, y, z] = self.interface.groups(invocations);
        rec.dispatch(x, y, z);
    }
}
