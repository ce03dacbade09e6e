//! The viewer's UI layer: egui's meshes drawn by `egui-ash-renderer` into the frame being
//! recorded (dynamic rendering, one frame in flight).

use std::sync::Arc;

use ash::vk;
use egui_ash_renderer::{DynamicRendering, Options, RenderMode, Renderer};

use super::command::{CommandPool, Recorder};
use super::device::Device;
use super::error::{VkError, VkResult};

fn ui_error(what: &str, e: egui_ash_renderer::RendererError) -> VkError {
    VkError::Unsupported(format!("the UI renderer failed to {what}: {e}"))
}

pub struct Overlay {
    renderer: Renderer<egui_ash_renderer::allocator::DefaultAllocator>,
    /// Texture uploads record from here.
    pool: CommandPool,
    /// Last: the device outlives the renderer's objects.
    device: Arc<Device>,
}

impl Overlay {
    /// A UI renderer for colour targets of `format` (a UNORM format: it encodes sRGB itself).
    pub fn new(device: &Arc<Device>, format: vk::Format) -> VkResult<Self> {
        let instance = &device.instance().raw;
        let renderer = Renderer::with_default_allocator(
            instance,
            device.physical,
            device.raw.clone(),
            RenderMode::DynamicRendering(DynamicRendering {
                color_attachment_format: format,
                depth_attachment_format: None,
                stencil_attachment_format: None,
            }),
            Options {
                in_flight_frames: 1,
                enable_depth_test: false,
                enable_depth_write: false,
                srgb_framebuffer: false,
            },
        )
        .map_err(|e| ui_error("initialise", e))?;
        Ok(Self {
            renderer,
            pool: CommandPool::new(device, "ui textures")?,
            device: device.clone(),
        })
    }

    /// Uploads the textures egui created or changed this frame (before recording the frame).
    pub fn set_textures(&mut self, delta: &egui::TexturesDelta) -> VkResult<()> {
        for (id, images) in &delta.set {
            for image in images {
                self.renderer
                    .set_texture(self.device.queue, self.pool.raw, *id, image)
                    .map_err(|e| ui_error("upload a texture", e))?;
            }
        }
        Ok(())
    }

    /// Frees the textures egui released this frame (after the frame completed).
    pub fn free_textures(&mut self, delta: &egui::TexturesDelta) -> VkResult<()> {
        for id in &delta.free {
            self.renderer
                .free_texture(*id)
                .map_err(|e| ui_error("free a texture", e))?;
        }
        Ok(())
    }

    /// Records the UI's draws into the rendering begun on `rec` (a `width`×`height` target).
    pub fn draw(
        &mut self,
        rec: &mut Recorder<'_>,
        width: u32,
        height: u32,
        pixels_per_point: f32,
        primitives: &[egui::ClippedPrimitive],
    ) -> VkResult<()> {
        self.renderer
            .cmd_draw(
                rec.raw,
                vk::Extent2D { width, height },
                pixels_per_point,
                primitives,
            )
            .map_err(|e| ui_error("record", e))
    }
}
