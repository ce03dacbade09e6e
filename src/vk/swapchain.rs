//! Presenting to a window: the surface, the swapchain (recreated on resize and when out of
//! date), the semaphores of a frame, and the frame's submission.
//!
//! One frame in flight: [`submit_frame`] waits for its fence before returning, so a frame's
//! resources (and the swapchain's, at recreation) are free again when it returns.

use std::sync::Arc;

use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::command::{submit_blocking, CommandPool, Recorder};
use super::device::Device;
use super::error::{Check, VkError, VkResult};
use super::{Buffer, ImageState};

/// A window's Vulkan surface.
pub struct Surface {
    /// Keeps the instance (through the device) alive while the surface lives.
    _device: Arc<Device>,
    loader: ash::khr::surface::Instance,
    raw: vk::SurfaceKHR,
}

impl Surface {
    /// The surface of a window, checked for presentation from the device's queue.
    pub fn new(
        device: &Arc<Device>,
        display: RawDisplayHandle,
        window: RawWindowHandle,
    ) -> VkResult<Self> {
        let instance = device.instance();
        if !instance.surface || device.swapchain.is_none() {
            return Err(VkError::Unsupported(format!(
                "`{}` cannot present: the instance was created without surfaces or the device \
                 lacks VK_KHR_swapchain",
                device.report.name
            )));
        }
        // SAFETY: the handles come from a live window that the caller keeps alive for as long as
        // this surface (the viewer drops the surface before the window).
        let raw = unsafe {
            ash_window::create_surface(&instance.entry, &instance.raw, display, window, None)
        }
        .check("vkCreate*SurfaceKHR")?;
        let loader = ash::khr::surface::Instance::new(&instance.entry, &instance.raw);
        let surface = Self {
            _device: device.clone(),
            loader,
            raw,
        };
        // SAFETY: live physical device, queue family and surface.
        let supported = unsafe {
            surface.loader.get_physical_device_surface_support(
                device.physical,
                device.queue_family,
                raw,
            )
        }
        .check("vkGetPhysicalDeviceSurfaceSupportKHR")?;
        if !supported {
            return Err(VkError::Unsupported(format!(
                "`{}` cannot present to this window from its graphics queue",
                device.report.name
            )));
        }
        Ok(surface)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: swapchains hold an `Arc<Surface>`, so none of this surface's is alive.
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// A binary semaphore.
pub struct Semaphore {
    device: Arc<Device>,
    pub(crate) raw: vk::Semaphore,
}

impl Semaphore {
    pub fn new(device: &Arc<Device>, name: &str) -> VkResult<Self> {
        // SAFETY: valid create info on a live device.
        let raw = unsafe {
            device
                .raw
                .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
        }
        .check("vkCreateSemaphore")?;
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }
}

impl Drop for Semaphore {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: frames wait for their fence before returning, so no pending work uses it.
        unsafe { self.device.raw.destroy_semaphore(self.raw, None) };
    }
}

/// The swapchain of a surface, with one view and one "rendered" semaphore per image.
pub struct Swapchain {
    device: Arc<Device>,
    raw: vk::SwapchainKHR,
    pub(crate) images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    /// Signalled by the frame that renders image i, waited on by its presentation.
    rendered: Vec<Semaphore>,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    /// Whether the images can be copied out (screenshots).
    pub readable: bool,
    /// Last: the surface outlives its swapchain.
    _surface: Arc<Surface>,
}

/// What acquiring an image gave.
pub enum Acquired {
    /// Render into image `index`; `suboptimal` asks for a recreation after presenting.
    Image { index: u32, suboptimal: bool },
    /// The surface changed (resize): recreate the swapchain and try again.
    OutOfDate,
}

impl Swapchain {
    /// A swapchain of `width`×`height` (clamped to what the surface allows), replacing `old`
    /// when given.
    pub fn new(
        device: &Arc<Device>,
        surface: &Arc<Surface>,
        width: u32,
        height: u32,
        old: Option<&Swapchain>,
    ) -> VkResult<Self> {
        let loader = device
            .swapchain
            .as_ref()
            .ok_or_else(|| VkError::Unsupported("VK_KHR_swapchain is not enabled".into()))?;
        let pd = device.physical;
        // SAFETY: live physical device and surface.
        let (caps, formats) = unsafe {
            (
                surface
                    .loader
                    .get_physical_device_surface_capabilities(pd, surface.raw)
                    .check("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?,
                surface
                    .loader
                    .get_physical_device_surface_formats(pd, surface.raw)
                    .check("vkGetPhysicalDeviceSurfaceFormatsKHR")?,
            )
        };
        // UNORM targets: the UI renderer encodes sRGB itself, and so does the scene's tonemap.
        let format = formats
            .iter()
            .find(|f| {
                matches!(
                    f.format,
                    vk::Format::B8G8R8A8_UNORM | vk::Format::R8G8B8A8_UNORM
                ) && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
            })
            .or_else(|| formats.first())
            .copied()
            .ok_or_else(|| VkError::Unsupported("the surface offers no format".into()))?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            return Err(VkError::Unsupported(
                "the window has no area (minimised)".into(),
            ));
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let readable = caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let composite = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|c| caps.supported_composite_alpha.contains(*c))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(composite)
            // FIFO is the one mode every driver offers.
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        // SAFETY: the create info borrows locals; `old` is idle (frames wait for their fence).
        let raw = unsafe { loader.create_swapchain(&info, None) }.check("vkCreateSwapchainKHR")?;
        let mut swapchain = Self {
            device: device.clone(),
            raw,
            images: Vec::new(),
            views: Vec::new(),
            rendered: Vec::new(),
            format: format.format,
            width: extent.width,
            height: extent.height,
            readable,
            _surface: surface.clone(),
        };
        // SAFETY: the swapchain was just created.
        swapchain.images =
            unsafe { loader.get_swapchain_images(raw) }.check("vkGetSwapchainImagesKHR")?;
        for (i, &image) in swapchain.images.clone().iter().enumerate() {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format.format)
                .subresource_range(color_range());
            // SAFETY: the image belongs to this device's swapchain.
            let view = unsafe { device.raw.create_image_view(&view_info, None) }
                .check("vkCreateImageView")?;
            swapchain.views.push(view);
            swapchain.rendered.push(Semaphore::new(
                device,
                &format!("swapchain image {i} rendered"),
            )?);
        }
        Ok(swapchain)
    }

    /// Acquires the next image, `signal` signalled when it is ready to be rendered to.
    pub fn acquire(&self, signal: &Semaphore) -> VkResult<Acquired> {
        let loader = self.device.swapchain.as_ref().expect("checked at creation");
        // SAFETY: live swapchain and semaphore; the semaphore is unsignalled (the previous
        // frame's wait consumed it).
        match unsafe {
            loader.acquire_next_image(self.raw, u64::MAX, signal.raw, vk::Fence::null())
        } {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(result) => Err(VkError::Vk {
                call: "vkAcquireNextImageKHR",
                result,
            }),
        }
    }

    /// Presents image `index` once its frame signalled its "rendered" semaphore. `false` when
    /// the swapchain should be recreated (out of date or suboptimal).
    pub fn present(&self, index: u32) -> VkResult<bool> {
        let loader = self.device.swapchain.as_ref().expect("checked at creation");
        let waits = [self.rendered[index as usize].raw];
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        // SAFETY: the image was acquired and rendered by a submitted frame that signals `waits`.
        match unsafe { loader.queue_present(self.device.queue, &info) } {
            Ok(suboptimal) => Ok(!suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(result) => Err(VkError::Vk {
                call: "vkQueuePresentKHR",
                result,
            }),
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: frames wait for their fence, and presentation finished with the device idle.
        unsafe {
            let _ = self.device.raw.device_wait_idle();
            for &view in &self.views {
                self.device.raw.destroy_image_view(view, None);
            }
            if let Some(loader) = &self.device.swapchain {
                loader.destroy_swapchain(self.raw, None);
            }
        }
    }
}

fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

impl Recorder<'_> {
    /// Moves swapchain image `index` between states (`ImageState::Present` for presentation).
    pub fn transition_swapchain(
        &mut self,
        swapchain: &Swapchain,
        index: u32,
        from: ImageState,
        to: ImageState,
    ) {
        self.barrier_raw(swapchain.images[index as usize], color_range(), from, to);
    }

    /// Begins dynamic rendering into swapchain image `index` (in `ColorAttachment` state),
    /// cleared to `clear`.
    pub fn begin_rendering_swapchain(
        &mut self,
        swapchain: &Swapchain,
        index: u32,
        clear: [f32; 4],
    ) {
        self.begin_rendering_raw(
            swapchain.views[index as usize],
            swapchain.width,
            swapchain.height,
            Some(clear),
        );
    }

    /// Copies swapchain image `index` (in `TransferSrc` state) into `buffer`, tightly packed.
    pub fn copy_swapchain_to_buffer(&mut self, swapchain: &Swapchain, index: u32, buffer: &Buffer) {
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: swapchain.width,
                height: swapchain.height,
                depth: 1,
            });
        // SAFETY: recording state; the image is in TRANSFER_SRC_OPTIMAL (caller's transition)
        // and the buffer holds width × height × 4 bytes (the caller sized it).
        unsafe {
            self.device.raw.cmd_copy_image_to_buffer(
                self.raw,
                swapchain.images[index as usize],
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            );
        }
    }
}

/// Records a frame into swapchain image `index` and submits it: waits for `acquired` before
/// writing colour, signals the image's "rendered" semaphore for presentation, and waits for
/// the frame to complete before returning.
pub fn submit_frame<R>(
    device: &Arc<Device>,
    swapchain: &Swapchain,
    index: u32,
    acquired: &Semaphore,
    record: impl FnOnce(&mut Recorder<'_>) -> VkResult<R>,
) -> VkResult<R> {
    let pool = CommandPool::new(device, "frame")?;
    let cmd = pool.allocate(device, "frame")?;
    let mut recorder = Recorder::begin(device, cmd)?;
    let value = record(&mut recorder)?;
    recorder.end()?;
    let waits = [vk::SemaphoreSubmitInfo::default()
        .semaphore(acquired.raw)
        .stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)];
    let signals = [vk::SemaphoreSubmitInfo::default()
        .semaphore(swapchain.rendered[index as usize].raw)
        .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
    submit_blocking(device, cmd, &waits, &signals)?;
    drop(recorder);
    Ok(value)
}
