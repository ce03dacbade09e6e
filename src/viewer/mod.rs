//! `lamina view`: an interactive window (winit + egui) to edit a layer stack, switch shader
//! variants and watch the shaded draw's GPU time.
//!
//! Two threads, two Vulkan devices. The scene thread ([`scene`]) renders with the same
//! [`Renderer`](crate::render::Renderer) as `lamina render` (sky, shaded mesh, query-pool
//! timings, read back) and sends the pixels; the window thread tone-maps them into an egui
//! texture, draws the UI into the swapchain image and presents. A variant's compilation or a
//! slow 6-flux frame therefore never freezes the UI: it keeps showing the last image and says
//! what is compiling. The profiling panel reports the shaded draw's own query-pool scope, so
//! neither the read-back nor the UI enters the timings.
//!
//! `--screenshot FILE --frames N` renders N frames that show the scene, saves the last
//! swapchain image and exits (tests, documentation).

mod layer_edit;
mod maps;
mod panels;
mod scene;

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

use std::sync::mpsc::{channel, Receiver, Sender};

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio;
use crate::material::Stack;
use crate::render::scene::Camera;
use crate::stats::MinMeanMax;
use crate::variant::{Model, VariantKey};
use crate::vk::{
    submit_frame, Acquired, Buffer, BufferDesc, DeviceSelector, Format, ImageState, InstanceDesc,
    Overlay, Semaphore, Surface, Swapchain,
};

use panels::{Action, Panels};
use scene::{Reply, Request};

/// Frames the profiling panel averages over.
pub const HISTORY: usize = 64;

/// What `lamina view` was asked to do.
pub struct ViewOptions {
    pub stack: Stack,
    pub variant: VariantKey,
    pub env: PathBuf,
    /// Where the environment picker looks (`assets/env/`).
    pub env_dir: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Save the last frame's swapchain image here and exit after `frames`.
    pub screenshot: Option<PathBuf>,
    /// Exit after this many frames.
    pub frames: Option<u32>,
    /// Resize the window to this size half-way through `frames` (tests the swapchain).
    pub resize: Option<(u32, u32)>,
    /// Save the edited stack here on exit (the Save button's code path).
    pub save_stack: Option<PathBuf>,
    pub instance: InstanceDesc,
    pub selector: DeviceSelector,
    /// The environment's scale and the analytic lights (`--lights`, `--light`).
    pub lighting: crate::render::lights::Lighting,
}

/// What a run did, for the command's summary and the tests.
#[derive(Debug, Default)]
pub struct ViewReport {
    pub frames: u32,
    pub swapchain_builds: u32,
    pub final_size: (u32, u32),
    /// Validation messages of error or warning severity over the run.
    pub validation_problems: u32,
}

/// Opens the window and runs until it is closed or `frames` are done.
pub fn run(options: ViewOptions) -> Result<ViewReport> {
    let event_loop = EventLoop::new().map_err(|e| {
        Error::Unsupported(format!(
            "cannot open a window: {e} (is DISPLAY set? headless, run under xvfb-run)"
        ))
    })?;
    let gpu = Gpu::new(
        InstanceDesc {
            surface: true,
            ..options.instance
        },
        &options.selector,
    )?;
    if !options.env.is_file() {
        return Err(Error::Input {
            path: options.env.clone(),
            message: "no such environment map".into(),
        });
    }
    let panels = Panels::new(
        &options,
        gpu.device.report.name.clone(),
        gpu.device.supports_fp16(),
    )?;
    let (request_tx, request_rx) = channel();
    let (reply_tx, reply_rx) = channel();
    let (instance, selector, env) = (
        options.instance,
        options.selector.clone(),
        options.env.clone(),
    );
    std::thread::scope(|scope| {
        let scene =
            scope.spawn(move || scene::serve(instance, selector, env, request_rx, reply_tx));
        let mut app = App {
            gpu: &gpu,
            panels,
            options,
            window: None,
            egui: egui::Context::default(),
            texture: None,
            last_frame: None,
            requests: Some(request_tx),
            replies: reply_rx,
            in_flight: false,
            error: None,
            report: ViewReport::default(),
            swapchain_stale: false,
        };
        let looped = event_loop
            .run_app(&mut app)
            .map_err(|e| Error::Unsupported(format!("the window's event loop failed: {e}")));
        // Hanging up ends the scene thread.
        app.requests = None;
        let scene_problems = match scene.join() {
            Ok(result) => result,
            Err(_) => Err(Error::Unsupported("the scene thread panicked".into())),
        };
        looped?;
        if let Some(e) = app.error.take() {
            return Err(e);
        }
        if let Some(path) = &app.options.save_stack {
            app.panels.stack.save(path)?;
        }
        let mut report = std::mem::take(&mut app.report);
        drop(app);
        report.validation_problems = gpu.device.validation_problems() + scene_problems?;
        Ok(report)
    })
}

/// Everything that lives with the window. Field order is drop order: the UI renderer and
/// the swapchain go before the surface, the surface before the window.
struct WindowState {
    overlay: Overlay,
    swapchain: Swapchain,
    acquired: Semaphore,
    surface: Arc<Surface>,
    input: egui_winit::State,
    window: Arc<Window>,
}

struct App<'g> {
    gpu: &'g Gpu,
    panels: Panels,
    options: ViewOptions,
    window: Option<WindowState>,
    egui: egui::Context,
    /// The tone-mapped scene, shown by the central panel.
    texture: Option<egui::TextureHandle>,
    /// The last scene frame (linear), kept to re-tone-map when the exposure changes.
    last_frame: Option<(u32, u32, Vec<[f32; 4]>, f32)>,
    requests: Option<Sender<Request>>,
    replies: Receiver<Reply>,
    /// A request was sent and its frame (or failure) has not come back.
    in_flight: bool,
    error: Option<Error>,
    report: ViewReport,
    swapchain_stale: bool,
}

impl App<'_> {
    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let attributes = Window::default_attributes()
            .with_title("lamina")
            .with_inner_size(PhysicalSize::new(self.options.width, self.options.height));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| Error::Unsupported(format!("creating the window: {e}")))?,
        );
        let handle_error = |e: winit::raw_window_handle::HandleError| {
            Error::Unsupported(format!("the window has no usable handle: {e}"))
        };
        let display = window.display_handle().map_err(handle_error)?.as_raw();
        let raw = window.window_handle().map_err(handle_error)?.as_raw();
        let device = &self.gpu.device;
        let surface = Arc::new(Surface::new(device, display, raw)?);
        let size = window.inner_size();
        let swapchain = Swapchain::new(device, &surface, size.width, size.height, None)?;
        self.report.swapchain_builds += 1;
        let overlay = Overlay::new(device, swapchain.format)?;
        let input = egui_winit::State::new(
            self.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        self.window = Some(WindowState {
            overlay,
            swapchain,
            acquired: Semaphore::new(device, "swapchain image acquired")?,
            surface,
            input,
            window,
        });
        Ok(())
    }

    fn rebuild_swapchain(&mut self) -> Result<()> {
        let Some(w) = self.window.as_mut() else {
            return Ok(());
        };
        let size = w.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(());
        }
        let next = Swapchain::new(
            &self.gpu.device,
            &w.surface,
            size.width,
            size.height,
            Some(&w.swapchain),
        )?;
        if next.format != w.swapchain.format {
            w.overlay = Overlay::new(&self.gpu.device, next.format)?;
        }
        w.swapchain = next;
        self.report.swapchain_builds += 1;
        self.swapchain_stale = false;
        Ok(())
    }

    /// Takes the scene thread's replies and, when it is idle, asks for the next frame.
    /// `wait` blocks until the request in flight has come back (the screenshot frame).
    fn update_scene(&mut self, wait: bool) -> Result<()> {
        loop {
            let reply = if wait && self.in_flight {
                match self.replies.recv() {
                    Ok(r) => r,
                    Err(_) => return Err(Error::Unsupported("the scene thread stopped".into())),
                }
            } else {
                match self.replies.try_recv() {
                    Ok(r) => r,
                    Err(_) => break,
                }
            };
            match reply {
                Reply::Compiled { variant, error } => self.panels.compiled(variant, error),
                Reply::Frame(frame) => {
                    self.in_flight = false;
                    self.panels
                        .record_timing(frame.shaded_ms, frame.fragment_invocations);
                    self.last_frame = Some((frame.width, frame.height, frame.pixels, f32::NAN));
                }
                Reply::Skipped => self.in_flight = false,
                Reply::Failed(message) => {
                    self.in_flight = false;
                    self.panels.failed(message);
                }
            }
        }
        self.show_frame();
        if !self.in_flight {
            let mut environment = None;
            let mut mesh = None;
            for action in self.panels.take_actions() {
                match action {
                    Action::Environment(path) => environment = Some(path),
                    Action::Mesh(kind) => mesh = Some(kind),
                }
            }
            let (width, height) = self.panels.viewport_pixels();
            let request = Request {
                layers: self.panels.stack.params(),
                surface: self.panels.stack.surface.clone(),
                variant: self.panels.variant_for_scene(),
                camera: self.panels.camera(),
                lighting: self.panels.lighting.clone(),
                width,
                height,
                environment,
                mesh,
            };
            if let Some(tx) = &self.requests {
                if tx.send(request).is_err() {
                    return Err(Error::Unsupported("the scene thread stopped".into()));
                }
                self.in_flight = true;
            }
        }
        Ok(())
    }

    /// Tone-maps the last frame into the texture when it or the exposure changed.
    fn show_frame(&mut self) {
        let exposure = self.panels.exposure;
        let Some((width, height, pixels, shown)) = &mut self.last_frame else {
            return;
        };
        if *shown == exposure {
            return;
        }
        *shown = exposure;
        let rgba = imageio::tonemap(pixels, exposure);
        let image =
            egui::ColorImage::from_rgba_unmultiplied([*width as usize, *height as usize], &rgba);
        match &mut self.texture {
            Some(t) => t.set(image, egui::TextureOptions::LINEAR),
            None => {
                self.texture = Some(self.egui.load_texture(
                    "scene",
                    image,
                    egui::TextureOptions::LINEAR,
                ))
            }
        }
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        if self.swapchain_stale {
            self.rebuild_swapchain()?;
        }
        // Frames count once the scene shows; the last one waits for the newest scene.
        let last = self.texture.is_some()
            && self
                .options
                .frames
                .is_some_and(|n| self.report.frames + 1 >= n);
        self.update_scene(last)?;
        let Some(w) = self.window.as_mut() else {
            return Ok(());
        };
        let input = w.input.take_egui_input(&w.window);
        let texture = self.texture.clone();
        let panels = &mut self.panels;
        let output = self
            .egui
            .run_ui(input, |ui| panels.show(ui, texture.as_ref()));
        w.input
            .handle_platform_output(&w.window, output.platform_output.clone());
        let primitives = self.egui.tessellate(output.shapes, output.pixels_per_point);

        // egui's texture changes are applied whatever happens to this frame.
        let mut textures = output.textures_delta;
        w.overlay.set_textures(&textures)?;
        let index = match w.swapchain.acquire(&w.acquired)? {
            Acquired::Image { index, suboptimal } => {
                self.swapchain_stale |= suboptimal;
                Some(index)
            }
            Acquired::OutOfDate => {
                self.swapchain_stale = true;
                None
            }
        };
        let Some(index) = index else {
            w.overlay.free_textures(&textures)?;
            textures.clear();
            return Ok(());
        };
        let screenshot = self
            .options
            .screenshot
            .as_ref()
            .filter(|_| last && w.swapchain.readable);
        if self.options.screenshot.is_some() && last && !w.swapchain.readable {
            return Err(Error::Unsupported(
                "the swapchain's images cannot be copied out (no TRANSFER_SRC usage): no screenshot"
                    .into(),
            ));
        }
        let (sw, sh) = (w.swapchain.width, w.swapchain.height);
        let readback = match screenshot {
            Some(_) => Some(Buffer::new(
                &self.gpu.device,
                BufferDesc::readback(u64::from(sw) * u64::from(sh) * 4),
                "screenshot",
            )?),
            None => None,
        };
        let device = self.gpu.device.clone();
        let swapchain = &w.swapchain;
        let overlay = &mut w.overlay;
        submit_frame(&device, swapchain, index, &w.acquired, |rec| {
            rec.transition_swapchain(
                swapchain,
                index,
                ImageState::Undefined,
                ImageState::ColorAttachment,
            );
            rec.begin_rendering_swapchain(swapchain, index, [0.02, 0.02, 0.025, 1.0]);
            overlay.draw(rec, sw, sh, output.pixels_per_point, &primitives)?;
            rec.end_rendering();
            let mut state = ImageState::ColorAttachment;
            if let Some(buffer) = &readback {
                rec.transition_swapchain(swapchain, index, state, ImageState::TransferSrc);
                rec.copy_swapchain_to_buffer(swapchain, index, buffer);
                state = ImageState::TransferSrc;
            }
            rec.transition_swapchain(swapchain, index, state, ImageState::Present);
            Ok(())
        })?;
        if !w.swapchain.present(index)? {
            self.swapchain_stale = true;
        }
        w.overlay.free_textures(&textures)?;
        textures.clear();
        if self.texture.is_some() {
            self.report.frames += 1;
        }
        self.report.final_size = (sw, sh);

        if let (Some(path), Some(buffer)) = (screenshot, &readback) {
            let mut rgba: Vec<u8> = buffer.read();
            if matches!(
                w.swapchain.format,
                Format::B8G8R8A8_UNORM | Format::B8G8R8A8_SRGB
            ) {
                rgba.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
            }
            rgba.chunks_exact_mut(4).for_each(|p| p[3] = 255);
            imageio::write_png(path, sw as usize, sh as usize, &rgba)?;
        }
        if let (Some((rw, rh)), Some(n)) = (self.options.resize, self.options.frames) {
            if self.report.frames == n / 2 {
                let _ = w.window.request_inner_size(PhysicalSize::new(rw, rh));
            }
        }
        if last {
            event_loop.exit();
        }
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            if let Err(e) = self.open_window(event_loop) {
                self.fail(event_loop, e);
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(w) = self.window.as_mut() else {
            return;
        };
        let _ = w.input.on_window_event(&w.window, &event);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) | WindowEvent::ScaleFactorChanged { .. } => {
                self.swapchain_stale = true;
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(w) = &self.window {
            w.window.request_redraw();
        }
    }
}

/// Average, minimum and maximum of a history of milliseconds.
pub fn summary(history: &VecDeque<f64>) -> Option<(f64, f64, f64)> {
    MinMeanMax::of(history.iter().copied()).map(|s| (s.mean, s.min, s.max))
}

/// The stack model a variant model implies (the baseline keeps the stack's own).
fn stack_model(model: Model, current: Model) -> Model {
    match model {
        Model::Ggx => current,
        other => other,
    }
}

/// The orbit camera: yaw and pitch around the target at a distance.
fn orbit(yaw: f32, pitch: f32, distance: f32) -> Camera {
    let (sy, cy) = yaw.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    Camera {
        eye: glam::Vec3::new(cp * sy, sp, cp * cy) * distance,
        ..Camera::default()
    }
}
