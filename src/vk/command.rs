//! Command recording, image state transitions and one-shot submission.
//!
//! A [`Recorder`] is the only way code outside `vk/` records GPU work. Its methods take owning
//! wrappers, so handles can't be mixed up, and it holds a graveyard: values passed to
//! [`Recorder::retire`] live until the submission's fence has signalled, so a staging buffer
//! created inside a recording closure is never freed while the GPU still reads it.

use std::any::Any;
use std::sync::Arc;

use ash::vk;

use super::buffer::Buffer;
use super::descriptor::DescriptorSet;
use super::device::Device;
use super::error::{Check, VkResult};
use super::image::{Image, ImageView};
use super::pipeline::{Pipeline, PipelineLayout};

/// Where an image is in its life: layout plus the stage and access that use it there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageState {
    Undefined,
    TransferDst,
    TransferSrc,
    /// Sampled by compute shaders.
    ComputeRead,
    /// Sampled by fragment shaders.
    FragmentRead,
    /// Storage image written (and read) by compute shaders.
    ComputeWrite,
    ColorAttachment,
    /// A stencil attachment, tested and written by the draws of a rendering scope.
    StencilAttachment,
    /// A swapchain image handed to presentation.
    Present,
}

impl ImageState {
    fn parts(self) -> (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2) {
        use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
        match self {
            Self::Undefined => (L::UNDEFINED, S::NONE, A::NONE),
            Self::TransferDst => (L::TRANSFER_DST_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_WRITE),
            Self::TransferSrc => (L::TRANSFER_SRC_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_READ),
            Self::ComputeRead => (
                L::SHADER_READ_ONLY_OPTIMAL,
                S::COMPUTE_SHADER,
                A::SHADER_SAMPLED_READ,
            ),
            Self::FragmentRead => (
                L::SHADER_READ_ONLY_OPTIMAL,
                S::FRAGMENT_SHADER,
                A::SHADER_SAMPLED_READ,
            ),
            Self::ComputeWrite => (
                L::GENERAL,
                S::COMPUTE_SHADER,
                A::SHADER_STORAGE_WRITE | A::SHADER_STORAGE_READ,
            ),
            Self::ColorAttachment => (
                L::COLOR_ATTACHMENT_OPTIMAL,
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_WRITE | A::COLOR_ATTACHMENT_READ,
            ),
            Self::StencilAttachment => (
                L::STENCIL_ATTACHMENT_OPTIMAL,
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_WRITE | A::DEPTH_STENCIL_ATTACHMENT_READ,
            ),
            Self::Present => (L::PRESENT_SRC_KHR, S::NONE, A::NONE),
        }
    }
}

/// Memory accesses for buffer/global barriers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    ComputeWrite,
    ComputeRead,
    /// Storage reads and writes (atomics) by compute shaders.
    ComputeReadWrite,
    /// Read as the arguments of an indirect dispatch or draw.
    IndirectRead,
    TransferWrite,
    TransferRead,
    HostRead,
    HostWrite,
}

impl Access {
    fn parts(self) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
        use vk::{AccessFlags2 as A, PipelineStageFlags2 as S};
        match self {
            Self::ComputeWrite => (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE),
            Self::ComputeRead => (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ),
            Self::ComputeReadWrite => (
                S::COMPUTE_SHADER,
                A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE,
            ),
            Self::IndirectRead => (S::DRAW_INDIRECT, A::INDIRECT_COMMAND_READ),
            Self::TransferWrite => (S::ALL_TRANSFER, A::TRANSFER_WRITE),
            Self::TransferRead => (S::ALL_TRANSFER, A::TRANSFER_READ),
            Self::HostRead => (S::HOST, A::HOST_READ),
            Self::HostWrite => (S::HOST, A::HOST_WRITE),
        }
    }
}

/// Records into one command buffer.
pub struct Recorder<'d> {
    pub(crate) device: &'d Device,
    pub(crate) raw: vk::CommandBuffer,
    graveyard: Vec<Box<dyn Any>>,
}

impl Recorder<'_> {
    /// Keeps `value` alive until the GPU has finished this submission.
    pub fn retire<T: 'static>(&mut self, value: T) {
        self.graveyard.push(Box::new(value));
    }

    /// Moves `image`'s mips `mips` (all layers) from `from` to `to`.
    pub fn transition(
        &mut self,
        image: &Image,
        mips: std::ops::Range<u32>,
        from: ImageState,
        to: ImageState,
    ) {
        let range = vk::ImageSubresourceRange {
            base_mip_level: mips.start,
            level_count: mips.end - mips.start,
            ..image.desc.full_range()
        };
        self.barrier_raw(image.raw, range, from, to);
    }

    /// An image barrier on a raw image of this device.
    pub(crate) fn barrier_raw(
        &mut self,
        image: vk::Image,
        range: vk::ImageSubresourceRange,
        from: ImageState,
        to: ImageState,
    ) {
        let (old_layout, src_stage, src_access) = from.parts();
        let (new_layout, dst_stage, dst_access) = to.parts();
        let barrier = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(src_stage)
            .src_access_mask(src_access)
            .dst_stage_mask(dst_stage)
            .dst_access_mask(dst_access)
            .old_layout(old_layout)
            .new_layout(new_layout)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range)];
        let info = vk::DependencyInfo::default().image_memory_barriers(&barrier);
        // SAFETY: recording state; the image belongs to this device.
        unsafe { self.device.raw.cmd_pipeline_barrier2(self.raw, &info) };
    }

    /// A global memory dependency from `src` to `dst`.
    pub fn barrier(&mut self, src: Access, dst: Access) {
        let (src_stage, src_access) = src.parts();
        let (dst_stage, dst_access) = dst.parts();
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(src_stage)
            .src_access_mask(src_access)
            .dst_stage_mask(dst_stage)
            .dst_access_mask(dst_access)];
        let info = vk::DependencyInfo::default().memory_barriers(&barrier);
        // SAFETY: recording state.
        unsafe { self.device.raw.cmd_pipeline_barrier2(self.raw, &info) };
    }

    pub fn bind_pipeline(&mut self, pipeline: &Pipeline) {
        // SAFETY: recording state; pipeline alive for the recording (caller holds it).
        unsafe {
            self.device
                .raw
                .cmd_bind_pipeline(self.raw, pipeline.bind_point, pipeline.raw)
        };
    }

    pub fn bind_set(
        &mut self,
        pipeline: &Pipeline,
        layout: &PipelineLayout,
        index: u32,
        set: &DescriptorSet,
    ) {
        // SAFETY: recording state; the set was created against a layout compatible with `layout`.
        unsafe {
            self.device.raw.cmd_bind_descriptor_sets(
                self.raw,
                pipeline.bind_point,
                layout.raw,
                index,
                &[set.raw],
                &[],
            )
        };
    }

    pub fn push_constants<T: bytemuck::Pod>(&mut self, layout: &PipelineLayout, value: &T) {
        // SAFETY: recording state; the layout declares a push range of at least size_of::<T>().
        unsafe {
            self.device.raw.cmd_push_constants(
                self.raw,
                layout.raw,
                layout.push_stages,
                0,
                bytemuck::bytes_of(value),
            )
        };
    }

    pub fn dispatch(&mut self, x: u32, y: u32, z: u32) {
        // SAFETY: recording state with a compute pipeline bound.
        unsafe { self.device.raw.cmd_dispatch(self.raw, x, y, z) };
    }

    /// A dispatch whose work-group counts (three u32) the GPU reads from `buffer` at byte
    /// `offset` when it runs. Panics unless the buffer was made for indirect arguments and
    /// holds them there.
    pub fn dispatch_indirect(&mut self, buffer: &Buffer, offset: u64) {
        assert!(
            buffer
                .desc
                .usage
                .contains(vk::BufferUsageFlags::INDIRECT_BUFFER),
            "dispatch_indirect: the buffer was not made for indirect arguments"
        );
        assert!(offset.is_multiple_of(4) && offset + 12 <= buffer.size());
        // SAFETY: recording state with a compute pipeline bound; the buffer is alive (the
        // caller holds it until the submission completes), has INDIRECT_BUFFER usage and
        // holds 12 bytes at the 4-aligned `offset` (asserted above).
        unsafe {
            self.device
                .raw
                .cmd_dispatch_indirect(self.raw, buffer.raw, offset)
        };
    }

    /// Fills the first `bytes` of `buffer` (a multiple of 4) with the u32 `value`: a
    /// transfer write.
    pub fn fill_buffer(&mut self, buffer: &Buffer, bytes: u64, value: u32) {
        assert!(bytes.is_multiple_of(4) && bytes <= buffer.size());
        assert!(buffer
            .desc
            .usage
            .contains(vk::BufferUsageFlags::TRANSFER_DST));
        // SAFETY: recording state outside a rendering scope; the buffer is alive, a transfer
        // target, and `bytes` (4-aligned) lies within it (asserted above).
        unsafe {
            self.device
                .raw
                .cmd_fill_buffer(self.raw, buffer.raw, 0, bytes, value)
        };
    }

    /// Begins dynamic rendering into `target` (in `ColorAttachment` state), clearing it.
    pub fn begin_rendering(
        &mut self,
        target: &ImageView,
        width: u32,
        height: u32,
        clear: [f32; 4],
    ) {
        self.begin_rendering_raw(target.raw, width, height, Some(clear));
    }

    /// Begins dynamic rendering into `target` (in `ColorAttachment` state), keeping its contents.
    pub fn begin_rendering_load(&mut self, target: &ImageView, width: u32, height: u32) {
        self.begin_rendering_raw(target.raw, width, height, None);
    }

    /// [`Recorder::begin_rendering_load`] with `stencil` (in `StencilAttachment` state) as the
    /// stencil attachment, cleared to 0: the draws that follow route pixels by its bits.
    pub fn begin_rendering_load_stencil(
        &mut self,
        target: &ImageView,
        stencil: &ImageView,
        width: u32,
        height: u32,
    ) {
        self.begin_rendering_with(&[target.raw], Some(stencil.raw), width, height, None);
    }

    /// Begins dynamic rendering into `targets` (each in `ColorAttachment` state), attachment i
    /// at location i, each cleared to `clear`.
    pub fn begin_rendering_targets(
        &mut self,
        targets: &[&ImageView],
        width: u32,
        height: u32,
        clear: [f32; 4],
    ) {
        let raw: Vec<vk::ImageView> = targets.iter().map(|t| t.raw).collect();
        self.begin_rendering_with(&raw, None, width, height, Some(clear));
    }

    pub(crate) fn begin_rendering_raw(
        &mut self,
        target: vk::ImageView,
        width: u32,
        height: u32,
        clear: Option<[f32; 4]>,
    ) {
        self.begin_rendering_with(&[target], None, width, height, clear);
    }

    fn begin_rendering_with(
        &mut self,
        targets: &[vk::ImageView],
        stencil: Option<vk::ImageView>,
        width: u32,
        height: u32,
        clear: Option<[f32; 4]>,
    ) {
        let attachments: Vec<_> = targets
            .iter()
            .map(|&target| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(target)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(if clear.is_some() {
                        vk::AttachmentLoadOp::CLEAR
                    } else {
                        vk::AttachmentLoadOp::LOAD
                    })
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue {
                        color: vk::ClearColorValue {
                            float32: clear.unwrap_or_default(),
                        },
                    })
            })
            .collect();
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D { width, height },
        };
        let stencil_attachment = stencil.map(|view| {
            vk::RenderingAttachmentInfo::default()
                .image_view(view)
                .image_layout(vk::ImageLayout::STENCIL_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .clear_value(vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue {
                        depth: 0.0,
                        stencil: 0,
                    },
                })
        });
        let mut info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&attachments);
        if let Some(attachment) = stencil_attachment.as_ref() {
            info = info.stencil_attachment(attachment);
        }
        // SAFETY: recording state; the view's image is in COLOR_ATTACHMENT_OPTIMAL, the
        // stencil view's (if any) in STENCIL_ATTACHMENT_OPTIMAL.
        unsafe {
            self.device.raw.cmd_begin_rendering(self.raw, &info);
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: width as f32,
                height: height as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            self.device.raw.cmd_set_viewport(self.raw, 0, &[viewport]);
            self.device.raw.cmd_set_scissor(self.raw, 0, &[area]);
        }
    }

    /// The stencil state of the draws that follow (a pipeline made with
    /// `GraphicsDesc::stencil`): the reference value, the bits compared and the bits written.
    pub fn set_stencil(&mut self, reference: u32, compare_mask: u32, write_mask: u32) {
        let face = vk::StencilFaceFlags::FRONT_AND_BACK;
        // SAFETY: recording state; the bound pipeline declares these states dynamic.
        unsafe {
            self.device
                .raw
                .cmd_set_stencil_reference(self.raw, face, reference);
            self.device
                .raw
                .cmd_set_stencil_compare_mask(self.raw, face, compare_mask);
            self.device
                .raw
                .cmd_set_stencil_write_mask(self.raw, face, write_mask);
        }
    }

    pub fn end_rendering(&mut self) {
        // SAFETY: paired with `begin_rendering`.
        unsafe { self.device.raw.cmd_end_rendering(self.raw) };
    }

    pub fn bind_vertex_buffer(&mut self, buffer: &Buffer) {
        // SAFETY: recording state; buffer created with VERTEX_BUFFER usage by the caller.
        unsafe {
            self.device
                .raw
                .cmd_bind_vertex_buffers(self.raw, 0, &[buffer.raw], &[0])
        };
    }

    pub fn bind_index_buffer_u32(&mut self, buffer: &Buffer) {
        // SAFETY: recording state; buffer created with INDEX_BUFFER usage by the caller.
        unsafe {
            self.device
                .raw
                .cmd_bind_index_buffer(self.raw, buffer.raw, 0, vk::IndexType::UINT32)
        };
    }

    pub fn draw(&mut self, vertices: u32) {
        // SAFETY: recording inside a rendering scope with a graphics pipeline bound.
        unsafe { self.device.raw.cmd_draw(self.raw, vertices, 1, 0, 0) };
    }

    pub fn draw_indexed(&mut self, indices: u32) {
        // SAFETY: as `draw`, with an index buffer bound.
        unsafe {
            self.device
                .raw
                .cmd_draw_indexed(self.raw, indices, 1, 0, 0, 0)
        };
    }

    /// Copies a tightly packed buffer into mip 0, all layers, of `image` (in `TransferDst`).
    pub fn copy_buffer_to_image(&mut self, buffer: &Buffer, image: &Image) {
        let d = &image.desc;
        let (width, height, depth) = d.mip_extent(0);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: d.aspect(),
                mip_level: 0,
                base_array_layer: 0,
                layer_count: d.layers(),
            })
            .image_extent(vk::Extent3D {
                width,
                height,
                depth,
            });
        // SAFETY: recording state; the buffer holds the whole mip (callers size it so).
        unsafe {
            self.device.raw.cmd_copy_buffer_to_image(
                self.raw,
                buffer.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Copies mip `mip`, all layers, of `image` (in `TransferSrc`) into `buffer`, tightly packed
    /// (layer-major, then rows).
    pub fn copy_image_to_buffer(&mut self, image: &Image, mip: u32, buffer: &Buffer) {
        let d = &image.desc;
        let (w, h, depth) = d.mip_extent(mip);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: d.aspect(),
                mip_level: mip,
                base_array_layer: 0,
                layer_count: d.layers(),
            })
            .image_extent(vk::Extent3D {
                width: w,
                height: h,
                depth,
            });
        // SAFETY: recording state; the buffer is large enough (callers size it from the desc).
        unsafe {
            self.device.raw.cmd_copy_image_to_buffer(
                self.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            )
        };
    }

    /// Copies mip 0, all layers, of `src` (in `TransferSrc`) into mip 0 of `dst` (in
    /// `TransferDst`); both have the same size and format.
    pub fn copy_mip0(&mut self, src: &Image, dst: &Image) {
        let d = &src.desc;
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: d.aspect(),
            mip_level: 0,
            base_array_layer: 0,
            layer_count: d.layers(),
        };
        let region = vk::ImageCopy::default()
            .src_subresource(layers)
            .dst_subresource(layers)
            .extent(vk::Extent3D {
                width: d.width,
                height: d.height,
                depth: d.depth,
            });
        // SAFETY: recording state; the images match in size and format (callers create them so).
        unsafe {
            self.device.raw.cmd_copy_image(
                self.raw,
                src.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Linear-filtered blit of mip `mip - 1` (in `TransferSrc`) into mip `mip` (in
    /// `TransferDst`), all layers.
    pub fn blit_mip_down(&mut self, image: &Image, mip: u32) {
        let d = &image.desc;
        let (sw, sh, _) = d.mip_extent(mip - 1);
        let (dw, dh, _) = d.mip_extent(mip);
        let layers = |m| vk::ImageSubresourceLayers {
            aspect_mask: d.aspect(),
            mip_level: m,
            base_array_layer: 0,
            layer_count: d.layers(),
        };
        let region = vk::ImageBlit::default()
            .src_subresource(layers(mip - 1))
            .src_offsets([
                vk::Offset3D::default(),
                vk::Offset3D {
                    x: sw as i32,
                    y: sh as i32,
                    z: 1,
                },
            ])
            .dst_subresource(layers(mip))
            .dst_offsets([
                vk::Offset3D::default(),
                vk::Offset3D {
                    x: dw as i32,
                    y: dh as i32,
                    z: 1,
                },
            ]);
        // SAFETY: recording state; both subresources exist and are in the stated layouts.
        unsafe {
            self.device.raw.cmd_blit_image(
                self.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                vk::Filter::LINEAR,
            )
        };
    }

    /// Opens a debug label (shown by capture tools and in validation messages).
    pub fn begin_label(&mut self, name: &str) {
        if let (Some(utils), Ok(name)) = (&self.device.debug_utils, std::ffi::CString::new(name)) {
            let label = vk::DebugUtilsLabelEXT::default().label_name(&name);
            // SAFETY: recording state.
            unsafe { utils.cmd_begin_debug_utils_label(self.raw, &label) };
        }
    }

    pub fn end_label(&mut self) {
        if let Some(utils) = &self.device.debug_utils {
            // SAFETY: paired with `begin_label`.
            unsafe { utils.cmd_end_debug_utils_label(self.raw) };
        }
    }
}

/// Records with `record`, submits once, waits for completion and returns `record`'s value.
pub fn submit_and_wait<R>(
    device: &Arc<Device>,
    name: &str,
    record: impl FnOnce(&mut Recorder<'_>) -> VkResult<R>,
) -> VkResult<R> {
    let pool = CommandPool::new(device, name)?;
    let cmd = pool.allocate(device, name)?;
    let mut recorder = Recorder::begin(device, cmd)?;
    let value = record(&mut recorder)?;
    recorder.end()?;
    submit_blocking(device, cmd, &[], &[])?;
    drop(recorder);
    Ok(value)
}

/// Submits the recorded `cmd` once, waiting on and signalling the given semaphores, and waits
/// for it to complete: what the command references may be released when this returns.
pub(crate) fn submit_blocking(
    device: &Arc<Device>,
    cmd: vk::CommandBuffer,
    waits: &[vk::SemaphoreSubmitInfo<'_>],
    signals: &[vk::SemaphoreSubmitInfo<'_>],
) -> VkResult<()> {
    let fence = Fence::new(device)?;
    let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
    let submit = vk::SubmitInfo2::default()
        .command_buffer_infos(&cmd_infos)
        .wait_semaphore_infos(waits)
        .signal_semaphore_infos(signals);
    // SAFETY: the command buffer is executable; resources it references are held by the caller
    // (or a recorder's graveyard) until the fence wait below returns.
    unsafe {
        device
            .raw
            .queue_submit2(device.queue, &[submit], fence.raw)
            .check("vkQueueSubmit2")?;
        device
            .raw
            .wait_for_fences(&[fence.raw], true, u64::MAX)
            .check("vkWaitForFences")
    }
}

impl<'d> Recorder<'d> {
    /// Begins recording a fresh primary command buffer.
    pub(crate) fn begin(device: &'d Device, cmd: vk::CommandBuffer) -> VkResult<Self> {
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: a fresh command buffer of this device.
        unsafe { device.raw.begin_command_buffer(cmd, &begin) }.check("vkBeginCommandBuffer")?;
        Ok(Self {
            device,
            raw: cmd,
            graveyard: Vec::new(),
        })
    }

    /// Ends recording; the recorder lives on to keep retired values until the submission ends.
    pub(crate) fn end(&mut self) -> VkResult<()> {
        // SAFETY: recording state.
        unsafe { self.device.raw.end_command_buffer(self.raw) }.check("vkEndCommandBuffer")
    }
}

pub(crate) struct CommandPool {
    device: Arc<Device>,
    pub(crate) raw: vk::CommandPool,
}

impl CommandPool {
    pub(crate) fn new(device: &Arc<Device>, name: &str) -> VkResult<Self> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid create info on a live device.
        let raw =
            unsafe { device.raw.create_command_pool(&info, None) }.check("vkCreateCommandPool")?;
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }
}

impl CommandPool {
    /// One primary command buffer, freed with the pool.
    pub(crate) fn allocate(&self, device: &Device, name: &str) -> VkResult<vk::CommandBuffer> {
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.raw)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is alive and owned by the caller.
        let cmd = unsafe { device.raw.allocate_command_buffers(&alloc) }
            .check("vkAllocateCommandBuffers")?[0];
        device.set_name(cmd, name);
        Ok(cmd)
    }
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: the only submission from this pool was waited for (or never made).
        unsafe { self.device.raw.destroy_command_pool(self.raw, None) };
    }
}

pub(crate) struct Fence {
    device: Arc<Device>,
    pub(crate) raw: vk::Fence,
}

impl Fence {
    pub(crate) fn new(device: &Arc<Device>) -> VkResult<Self> {
        // SAFETY: valid create info on a live device.
        let raw = unsafe {
            device
                .raw
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .check("vkCreateFence")?;
        device.set_name(raw, "submit fence");
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }
}

impl Drop for Fence {
    fn drop(&mut self) {
        // SAFETY: the fence is signalled or was never submitted when its owner drops it, except
        // on an error path after submission, where the device is waited idle first.
        unsafe {
            let _ = self.device.raw.device_wait_idle();
            self.device.raw.destroy_fence(self.raw, None);
        }
    }
}

/// Bytes per texel of the formats lamina uses (a caller bug otherwise).
pub fn texel_bytes(format: vk::Format) -> u64 {
    match format {
        vk::Format::R16_SFLOAT => 2,
        vk::Format::R32_SFLOAT | vk::Format::R16G16_SFLOAT | vk::Format::R8G8B8A8_UNORM => 4,
        vk::Format::R32G32_SFLOAT | vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32G32B32A32_SFLOAT => 16,
        other => panic!("texel size of {other:?} is not tabulated"),
    }
}

/// Uploads `bytes` (tightly packed, layer-major) into mip 0 of `image`, leaving it in `to`.
pub fn upload_image(
    device: &Arc<Device>,
    image: &Image,
    bytes: &[u8],
    to: ImageState,
) -> VkResult<()> {
    let staging = Buffer::with_data(device, vk::BufferUsageFlags::TRANSFER_SRC, bytes, "staging")?;
    submit_and_wait(device, "upload", |rec| {
        let mips = 0..image.desc.mip_levels;
        rec.transition(
            image,
            mips.clone(),
            ImageState::Undefined,
            ImageState::TransferDst,
        );
        rec.copy_buffer_to_image(&staging, image);
        rec.transition(image, mips, ImageState::TransferDst, to);
        Ok(())
    })
}

/// Reads mip `mip` (all layers) of `image`, which is in `state` before and after.
pub fn read_image_mip(
    device: &Arc<Device>,
    image: &Image,
    mip: u32,
    state: ImageState,
) -> VkResult<Vec<u8>> {
    let (w, h, d) = image.desc.mip_extent(mip);
    let size = (w * h * d * image.desc.layers()) as u64 * texel_bytes(image.desc.format);
    let buffer = Buffer::new(
        device,
        super::buffer::BufferDesc::readback(size),
        "readback",
    )?;
    submit_and_wait(device, "readback", |rec| {
        rec.transition(image, mip..mip + 1, state, ImageState::TransferSrc);
        rec.copy_image_to_buffer(image, mip, &buffer);
        rec.transition(image, mip..mip + 1, ImageState::TransferSrc, state);
        rec.barrier(Access::TransferWrite, Access::HostRead);
        Ok(())
    })?;
    Ok(buffer.read::<u8>())
}
