//! Images, views and samplers.

use std::mem::ManuallyDrop;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;

use super::device::Device;
use super::error::{Check, VkResult};
use super::memory;

/// The stencil attachments' format: 8 bits, no depth (lavapipe and the desktop GPUs lamina
/// runs on take it as an attachment; `Device::supports_stencil_target` checks).
pub const STENCIL_FORMAT: vk::Format = vk::Format::S8_UINT;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImageKind {
    D2,
    /// Six array layers, cube-compatible.
    Cube,
    D3,
    /// `depth` array layers of 2-D images.
    D2Array,
}

/// How an image is created; doubles as a pool key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ImageDesc {
    pub kind: ImageKind,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub depth: u32,
    pub mip_levels: u32,
    pub usage: vk::ImageUsageFlags,
}

impl ImageDesc {
    pub fn new_2d(format: vk::Format, width: u32, height: u32) -> Self {
        Self {
            kind: ImageKind::D2,
            format,
            width,
            height,
            depth: 1,
            mip_levels: 1,
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        }
    }

    pub fn new_cube(format: vk::Format, size: u32) -> Self {
        Self {
            kind: ImageKind::Cube,
            ..Self::new_2d(format, size, size)
        }
    }

    pub fn new_3d(format: vk::Format, width: u32, height: u32, depth: u32) -> Self {
        Self {
            kind: ImageKind::D3,
            depth,
            ..Self::new_2d(format, width, height)
        }
    }

    /// `layers` 2-D images of one size, sampled as a `sampler2DArray`.
    pub fn new_2d_array(format: vk::Format, width: u32, height: u32, layers: u32) -> Self {
        Self {
            kind: ImageKind::D2Array,
            depth: layers,
            ..Self::new_2d(format, width, height)
        }
    }

    /// A colour attachment that is then copied out.
    pub fn render_target(format: vk::Format, width: u32, height: u32) -> Self {
        Self::new_2d(format, width, height).usage(
            vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::SAMPLED,
        )
    }

    /// An 8-bit stencil attachment (`STENCIL_FORMAT`) the draws of one frame route pixels by.
    pub fn stencil_target(width: u32, height: u32) -> Self {
        Self::new_2d(STENCIL_FORMAT, width, height)
            .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)
    }

    pub fn mips(mut self, levels: u32) -> Self {
        self.mip_levels = levels;
        self
    }

    /// Every mip level down to 1×1.
    pub fn all_mips(self) -> Self {
        let levels = 32 - self.width.max(self.height).max(1).leading_zeros();
        self.mips(levels)
    }

    pub fn usage(mut self, usage: vk::ImageUsageFlags) -> Self {
        self.usage = usage;
        self
    }

    pub fn layers(&self) -> u32 {
        match self.kind {
            ImageKind::Cube => 6,
            ImageKind::D2Array => self.depth,
            _ => 1,
        }
    }

    pub fn aspect(&self) -> vk::ImageAspectFlags {
        match self.format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
            vk::Format::S8_UINT => vk::ImageAspectFlags::STENCIL,
            _ => vk::ImageAspectFlags::COLOR,
        }
    }

    /// Every mip and layer.
    pub fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect(),
            base_mip_level: 0,
            level_count: self.mip_levels,
            base_array_layer: 0,
            layer_count: self.layers(),
        }
    }

    /// One mip level, every layer.
    pub fn mip_range(&self, mip: u32) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            base_mip_level: mip,
            level_count: 1,
            ..self.full_range()
        }
    }

    pub fn mip_extent(&self, mip: u32) -> (u32, u32, u32) {
        (
            (self.width >> mip).max(1),
            (self.height >> mip).max(1),
            match self.kind {
                ImageKind::D2Array => 1,
                _ => (self.depth >> mip).max(1),
            },
        )
    }
}

pub struct Image {
    device: Arc<Device>,
    pub(crate) raw: vk::Image,
    allocation: ManuallyDrop<Allocation>,
    pub desc: ImageDesc,
}

impl Image {
    pub fn new(device: &Arc<Device>, desc: ImageDesc, name: &str) -> VkResult<Self> {
        let (image_type, flags) = match desc.kind {
            ImageKind::D2 => (vk::ImageType::TYPE_2D, vk::ImageCreateFlags::empty()),
            ImageKind::Cube => (
                vk::ImageType::TYPE_2D,
                vk::ImageCreateFlags::CUBE_COMPATIBLE,
            ),
            ImageKind::D3 => (vk::ImageType::TYPE_3D, vk::ImageCreateFlags::empty()),
            ImageKind::D2Array => (vk::ImageType::TYPE_2D, vk::ImageCreateFlags::empty()),
        };
        let (_, _, extent_depth) = desc.mip_extent(0);
        let info = vk::ImageCreateInfo::default()
            .flags(flags)
            .image_type(image_type)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: extent_depth,
            })
            .mip_levels(desc.mip_levels)
            .array_layers(desc.layers())
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_image(&info, None) }.check("vkCreateImage")?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { device.raw.get_image_memory_requirements(raw) };
        let allocation =
            match memory::allocate(device, name, requirements, MemoryLocation::GpuOnly, false) {
                Ok(a) => a,
                Err(e) => {
                    // SAFETY: not bound or used yet.
                    unsafe { device.raw.destroy_image(raw, None) };
                    return Err(e);
                }
            };
        let image = Self {
            device: device.clone(),
            raw,
            allocation: ManuallyDrop::new(allocation),
            desc,
        };
        // SAFETY: the allocation satisfies `requirements` and is bound once.
        unsafe {
            device
                .raw
                .bind_image_memory(raw, image.allocation.memory(), image.allocation.offset())
        }
        .check("vkBindImageMemory")?;
        device.set_name(raw, name);
        Ok(image)
    }

    /// A view over every mip and layer, of the image's natural type (2-D, cube or 3-D).
    pub fn view(&self, name: &str) -> VkResult<ImageView> {
        let view_type = match self.desc.kind {
            ImageKind::D2 => vk::ImageViewType::TYPE_2D,
            ImageKind::Cube => vk::ImageViewType::CUBE,
            ImageKind::D3 => vk::ImageViewType::TYPE_3D,
            ImageKind::D2Array => vk::ImageViewType::TYPE_2D_ARRAY,
        };
        ImageView::new(self, view_type, self.desc.full_range(), name)
    }

    /// A 2-D-array view of one mip level over all layers, for storage writes into a cube.
    pub fn mip_view(&self, mip: u32, name: &str) -> VkResult<ImageView> {
        let view_type = match self.desc.kind {
            ImageKind::D2 => vk::ImageViewType::TYPE_2D,
            ImageKind::Cube | ImageKind::D2Array => vk::ImageViewType::TYPE_2D_ARRAY,
            ImageKind::D3 => vk::ImageViewType::TYPE_3D,
        };
        ImageView::new(self, view_type, self.desc.mip_range(mip), name)
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: module invariant: no GPU work using the image is pending; allocation taken once.
        unsafe {
            self.device.raw.destroy_image(self.raw, None);
            memory::free(&self.device, ManuallyDrop::take(&mut self.allocation));
        }
    }
}

pub struct ImageView {
    device: Arc<Device>,
    pub(crate) raw: vk::ImageView,
}

impl ImageView {
    pub fn new(
        image: &Image,
        view_type: vk::ImageViewType,
        range: vk::ImageSubresourceRange,
        name: &str,
    ) -> VkResult<Self> {
        let device = &image.device;
        let info = vk::ImageViewCreateInfo::default()
            .image(image.raw)
            .view_type(view_type)
            .format(image.desc.format)
            .subresource_range(range);
        // SAFETY: the range lies within the image (callers build it from the image's desc).
        let raw =
            unsafe { device.raw.create_image_view(&info, None) }.check("vkCreateImageView")?;
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }
}

impl Drop for ImageView {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: module invariant: no pending GPU work uses the view.
        unsafe { self.device.raw.destroy_image_view(self.raw, None) };
    }
}

/// Sampler addressing per axis: how lamina's tables and environments are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SamplerDesc {
    pub filter: vk::Filter,
    pub mipmap: vk::SamplerMipmapMode,
    pub address_u: vk::SamplerAddressMode,
    pub address_v: vk::SamplerAddressMode,
}

impl SamplerDesc {
    /// Trilinear, clamped: tables and cube maps.
    pub fn linear_clamp() -> Self {
        Self {
            filter: vk::Filter::LINEAR,
            mipmap: vk::SamplerMipmapMode::LINEAR,
            address_u: vk::SamplerAddressMode::CLAMP_TO_EDGE,
            address_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        }
    }

    /// Bilinear, repeating in u and v, one level: the surface maps.
    pub fn linear_repeat() -> Self {
        Self {
            address_u: vk::SamplerAddressMode::REPEAT,
            address_v: vk::SamplerAddressMode::REPEAT,
            ..Self::linear_clamp()
        }
    }

    /// Bilinear, wrapping in u: equirectangular maps (longitude wraps, latitude clamps).
    pub fn equirect() -> Self {
        Self {
            address_u: vk::SamplerAddressMode::REPEAT,
            ..Self::linear_clamp()
        }
    }
}

pub struct Sampler {
    device: Arc<Device>,
    pub(crate) raw: vk::Sampler,
}

impl Sampler {
    pub fn new(device: &Arc<Device>, desc: SamplerDesc, name: &str) -> VkResult<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(desc.filter)
            .min_filter(desc.filter)
            .mipmap_mode(desc.mipmap)
            .address_mode_u(desc.address_u)
            .address_mode_v(desc.address_v)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .min_lod(0.0)
            .max_lod(vk::LOD_CLAMP_NONE);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_sampler(&info, None) }.check("vkCreateSampler")?;
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: module invariant: no pending GPU work uses the sampler.
        unsafe { self.device.raw.destroy_sampler(self.raw, None) };
    }
}
