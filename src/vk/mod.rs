//! The Vulkan layer: the only module that touches raw `ash`.
//!
//! One file per Vulkan concept. Invariants every `unsafe` block here relies on, unless its
//! `SAFETY:` note says otherwise:
//! - a wrapper's handle is valid while the wrapper lives; wrappers hold `Arc<Device>`, and the
//!   device holds `Arc<Instance>`, so parents always outlive children;
//! - an owner is dropped only after the GPU work that uses it has completed: work is submitted
//!   with [`submit_and_wait`], and values created inside a recording are kept alive with
//!   [`Recorder::retire`] until the fence signals;
//! - `Drop` skips releasing during a panic (a leaked handle beats a double fault).
//!
//! Plain Vulkan enums and flags (`Format`, usage flags) are re-exported below, so callers never
//! import `ash` themselves.

mod buffer;
mod capture;
mod command;
mod descriptor;
mod device;
mod error;
mod image;
mod instance;
mod memory;
mod overlay;
mod pipeline;
mod pipeline_cache;
mod query;
mod swapchain;

pub use ash::vk::{BufferUsageFlags, Format, ImageUsageFlags};
pub use buffer::{Buffer, BufferDesc};
pub use capture::Capturer;
pub use command::{
    read_image_mip, submit_and_wait, texel_bytes, upload_image, Access, ImageState, Recorder,
};
pub use descriptor::{BindingKind, DescriptorSet, DescriptorSetLayout, Resource, Stages};
pub use device::{enumerate, Device, DeviceReport, DeviceSelector};
pub use error::{VkError, VkResult};
pub use image::{Image, ImageDesc, ImageKind, ImageView, Sampler, SamplerDesc, STENCIL_FORMAT};
pub use instance::{Instance, InstanceDesc, MessageCounts};
pub use overlay::Overlay;
pub use pipeline::{
    ExecutableStat, ExecutableStats, GraphicsDesc, Pipeline, PipelineCreation, PipelineLayout,
    SpecConstants, SpecEntry, StencilUse,
};
pub use pipeline_cache::{CacheData, CacheDataError, PipelineCache};
pub use query::{GpuProfiler, Nanos, ScopeError, ScopeTiming, ScopeToken};
pub use swapchain::{submit_frame, Acquired, Semaphore, Surface, Swapchain};
