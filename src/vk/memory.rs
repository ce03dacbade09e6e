//! Allocation helpers shared by buffers and images.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::device::Device;
use super::error::{VkError, VkResult};

pub(crate) fn allocate(
    device: &Arc<Device>,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> VkResult<Allocation> {
    let mut allocator = device
        .allocator
        .lock()
        .map_err(|_| VkError::Unsupported("allocator mutex poisoned by an earlier panic".into()))?;
    allocator
        .allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })
        .map_err(|source| VkError::Alloc {
            name: name.to_owned(),
            source,
        })
}

pub(crate) fn free(device: &Device, allocation: Allocation) {
    if let Ok(mut allocator) = device.allocator.lock() {
        // A failed free only leaks; the allocator reports leaks by name at teardown.
        let _ = allocator.free(allocation);
    }
}
