//! Buffers: a descriptor value type and the owning wrapper.

use std::mem::ManuallyDrop;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;

use super::device::Device;
use super::error::{Check, VkResult};
use super::memory;

/// How a buffer is created; doubles as a pool key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BufferDesc {
    pub size: u64,
    pub usage: vk::BufferUsageFlags,
    pub location: MemoryLocation,
}

impl BufferDesc {
    /// Device-local storage buffer, also a transfer target.
    pub fn storage(size: u64) -> Self {
        Self {
            size,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::GpuOnly,
        }
    }

    /// Device-local storage buffer that also holds indirect dispatch arguments.
    pub fn indirect(size: u64) -> Self {
        let storage = Self::storage(size);
        Self {
            usage: storage.usage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            ..storage
        }
    }

    /// Host-visible buffer the CPU writes and the GPU reads (uniforms, vertices, uploads).
    pub fn upload(size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self {
            size,
            usage: usage | vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::CpuToGpu,
        }
    }

    /// Host-visible buffer the GPU writes and the CPU reads back.
    pub fn readback(size: u64) -> Self {
        Self {
            size,
            usage: vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::GpuToCpu,
        }
    }
}

pub struct Buffer {
    device: Arc<Device>,
    pub(crate) raw: vk::Buffer,
    allocation: ManuallyDrop<Allocation>,
    pub desc: BufferDesc,
}

impl Buffer {
    pub fn new(device: &Arc<Device>, desc: BufferDesc, name: &str) -> VkResult<Self> {
        let info = vk::BufferCreateInfo::default()
            .size(desc.size.max(4))
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_buffer(&info, None) }.check("vkCreateBuffer")?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { device.raw.get_buffer_memory_requirements(raw) };
        let allocation = match memory::allocate(device, name, requirements, desc.location, true) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: not bound or used yet.
                unsafe { device.raw.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        let buffer = Self {
            device: device.clone(),
            raw,
            allocation: ManuallyDrop::new(allocation),
            desc,
        };
        // SAFETY: the allocation satisfies `requirements` and is bound once.
        unsafe {
            device.raw.bind_buffer_memory(
                raw,
                buffer.allocation.memory(),
                buffer.allocation.offset(),
            )
        }
        .check("vkBindBufferMemory")?;
        device.set_name(raw, name);
        Ok(buffer)
    }

    /// A host-visible buffer holding `data`.
    pub fn with_data<T: bytemuck::Pod>(
        device: &Arc<Device>,
        usage: vk::BufferUsageFlags,
        data: &[T],
        name: &str,
    ) -> VkResult<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut buffer = Self::new(device, BufferDesc::upload(bytes.len() as u64, usage), name)?;
        buffer.write(0, data);
        Ok(buffer)
    }

    pub fn size(&self) -> u64 {
        self.desc.size
    }

    /// Copies `data` into a host-visible buffer at `offset` bytes.
    ///
    /// Panics when the buffer is not host-visible or the range does not fit: both are caller bugs.
    pub fn write<T: bytemuck::Pod>(&mut self, offset: usize, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mapped = self
            .allocation
            .mapped_slice_mut()
            .expect("Buffer::write needs a host-visible buffer");
        mapped[offset..offset + bytes.len()].copy_from_slice(bytes);
    }

    /// Reads the whole host-visible buffer as `T`s (after the GPU work writing it has completed).
    pub fn read<T: bytemuck::Pod>(&self) -> Vec<T> {
        let mapped = self
            .allocation
            .mapped_slice()
            .expect("Buffer::read needs a host-visible buffer");
        let len = self.desc.size as usize / std::mem::size_of::<T>();
        bytemuck::pod_collect_to_vec(&mapped[..len * std::mem::size_of::<T>()])
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: owners release only after the GPU work using them has completed (module
        // invariant); the allocation is taken exactly once.
        unsafe {
            self.device.raw.destroy_buffer(self.raw, None);
            memory::free(&self.device, ManuallyDrop::take(&mut self.allocation));
        }
    }
}
