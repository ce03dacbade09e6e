//! Descriptor set layouts and sets.
//!
//! Each [`DescriptorSet`] owns a pool sized exactly for its layout: lamina binds a handful of
//! long-lived sets per pass, so a pool per set keeps ownership trivial (the set dies with its
//! pool in `Drop`) at no measurable cost.

use std::sync::Arc;

use ash::vk;

use super::buffer::Buffer;
use super::device::Device;
use super::error::{Check, VkResult};
use super::image::{ImageView, Sampler};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BindingKind {
    UniformBuffer,
    StorageBuffer,
    /// Combined image sampler.
    SampledImage,
    StorageImage,
}

impl BindingKind {
    fn raw(self) -> vk::DescriptorType {
        match self {
            Self::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
            Self::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            Self::SampledImage => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            Self::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
        }
    }
}

/// Shader stages a binding is visible to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stages {
    Compute,
    Graphics,
    /// Graphics and compute: a set layout shared by both kinds of pipeline (the shading inputs).
    All,
}

impl Stages {
    pub(crate) fn raw(self) -> vk::ShaderStageFlags {
        match self {
            Self::Compute => vk::ShaderStageFlags::COMPUTE,
            Self::Graphics => vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            Self::All => {
                vk::ShaderStageFlags::VERTEX
                    | vk::ShaderStageFlags::FRAGMENT
                    | vk::ShaderStageFlags::COMPUTE
            }
        }
    }
}

pub struct DescriptorSetLayout {
    device: Arc<Device>,
    pub(crate) raw: vk::DescriptorSetLayout,
    /// Binding `i` has kind `kinds[i]`.
    kinds: Vec<BindingKind>,
}

impl DescriptorSetLayout {
    /// Bindings are numbered 0, 1, … in declaration order.
    pub fn new(
        device: &Arc<Device>,
        kinds: &[BindingKind],
        stages: Stages,
        name: &str,
    ) -> VkResult<Self> {
        let bindings: Vec<_> = kinds
            .iter()
            .enumerate()
            .map(|(i, k)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(k.raw())
                    .descriptor_count(1)
                    .stage_flags(stages.raw())
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_descriptor_set_layout(&info, None) }
            .check("vkCreateDescriptorSetLayout")?;
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
            kinds: kinds.to_vec(),
        })
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: layouts may be destroyed once pipelines and sets using them were created.
        unsafe {
            self.device
                .raw
                .destroy_descriptor_set_layout(self.raw, None)
        };
    }
}

/// What a binding points at.
pub enum Resource<'a> {
    Buffer(&'a Buffer),
    /// Read through a sampler in `SHADER_READ_ONLY_OPTIMAL`.
    Sampled(&'a ImageView, &'a Sampler),
    /// Read/written as a storage image in `GENERAL`.
    Storage(&'a ImageView),
}

pub struct DescriptorSet {
    device: Arc<Device>,
    pool: vk::DescriptorPool,
    pub(crate) raw: vk::DescriptorSet,
    kinds: Vec<BindingKind>,
}

impl DescriptorSet {
    pub fn new(device: &Arc<Device>, layout: &DescriptorSetLayout, name: &str) -> VkResult<Self> {
        let sizes: Vec<vk::DescriptorPoolSize> = layout
            .kinds
            .iter()
            .map(|k| vk::DescriptorPoolSize {
                ty: k.raw(),
                descriptor_count: 1,
            })
            .collect();
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes);
        // SAFETY: valid create info on a live device.
        let pool = unsafe { device.raw.create_descriptor_pool(&info, None) }
            .check("vkCreateDescriptorPool")?;
        device.set_name(pool, name);
        let layouts = [layout.raw];
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&layouts);
        // SAFETY: the pool was sized for exactly this layout.
        let raw = match unsafe { device.raw.allocate_descriptor_sets(&alloc) } {
            Ok(sets) => sets[0],
            Err(result) => {
                // SAFETY: the pool has no sets in use.
                unsafe { device.raw.destroy_descriptor_pool(pool, None) };
                return Err(super::error::VkError::Vk {
                    call: "vkAllocateDescriptorSets",
                    result,
                });
            }
        };
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            pool,
            raw,
            kinds: layout.kinds.clone(),
        })
    }

    /// Points `binding` at `resource`. Panics when the resource does not match the binding's
    /// kind in the layout: that is a caller bug, not a runtime condition.
    pub fn write(&mut self, binding: u32, resource: Resource<'_>) -> &mut Self {
        let kind = self.kinds[binding as usize];
        let buffer_info;
        let image_info;
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(kind.raw());
        let write = match (kind, resource) {
            (BindingKind::UniformBuffer | BindingKind::StorageBuffer, Resource::Buffer(b)) => {
                buffer_info = [vk::DescriptorBufferInfo {
                    buffer: b.raw,
                    offset: 0,
                    range: vk::WHOLE_SIZE,
                }];
                write.buffer_info(&buffer_info)
            }
            (BindingKind::SampledImage, Resource::Sampled(view, sampler)) => {
                image_info = [vk::DescriptorImageInfo {
                    sampler: sampler.raw,
                    image_view: view.raw,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }];
                write.image_info(&image_info)
            }
            (BindingKind::StorageImage, Resource::Storage(view)) => {
                image_info = [vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: view.raw,
                    image_layout: vk::ImageLayout::GENERAL,
                }];
                write.image_info(&image_info)
            }
            (kind, _) => panic!("binding {binding} is {kind:?}; the resource does not match"),
        };
        // SAFETY: the set is not in use by pending GPU work when callers rewrite it (sets are
        // written before the submission that reads them).
        unsafe { self.device.raw.update_descriptor_sets(&[write], &[]) };
        self
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: module invariant: no pending GPU work uses the set; destroying the pool frees it.
        unsafe { self.device.raw.destroy_descriptor_pool(self.pool, None) };
    }
}
