//! The viewer's panels: the layer stack, the variant, the environment and the profiling
//! history, around the rendered scene.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};

use egui::{Color32, ComboBox, RichText, Slider, Ui};

use crate::error::{Error, Result};
use crate::material::simplify::simplify;
use crate::material::{presets, Stack};
use crate::model::LayerParams;
use crate::render::scene::Camera;
use crate::variant::{
    Axis, Channels, Classify, Fgd, Ibl, Mode, Model, Ndf, ShadePath, Tir, VariantKey, G2,
    IBL_TAP_COUNT, IBL_TAP_LIMIT,
};

use super::layer_edit::{
    coverage_editor, coverage_of, coverage_value, describe, layer_editor, rgb_row, CoverageEdit,
    LayerOp,
};
use super::maps::{self, MapEdit, MapTexts};
use super::{orbit, stack_model, summary, ViewOptions, HISTORY};

/// Width of the side panel in points.
const SIDE_WIDTH: f32 = 330.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshKind {
    Sphere,
    Torus,
}

/// Work the panels ask of the renderer between frames.
pub enum Action {
    Environment(PathBuf),
    Mesh(MeshKind),
}

pub struct Panels {
    pub stack: Stack,
    /// The lighting every frame is drawn under.
    pub lighting: crate::render::lights::Lighting,
    /// What the variant panel asks for.
    requested: VariantKey,
    /// What the current pipeline was built from (`None` before the first build).
    compiled: Option<VariantKey>,
    /// Pipelines built so far: a specialized pipeline is rebuilt on structural edits only.
    builds: u32,
    message: Option<String>,
    presets: Vec<(String, PathBuf)>,
    envs: Vec<PathBuf>,
    env_index: usize,
    mesh: MeshKind,
    pub exposure: f32,
    /// Per layer: edit the artist form (F0, edge tint) instead of (η, κ).
    artist: Vec<Option<([f32; 3], [f32; 3])>>,
    /// What is being typed into the map editors' text boxes.
    map_texts: MapTexts,
    file: String,
    history: VecDeque<f64>,
    invocations: Option<u64>,
    device: String,
    fp16_supported: bool,
    yaw: f32,
    pitch: f32,
    distance: f32,
    /// The scene image's size in physical pixels, from the last layout.
    viewport: (u32, u32),
    actions: Vec<Action>,
}

impl Panels {
    pub fn new(options: &ViewOptions, device: String, fp16_supported: bool) -> Result<Self> {
        let presets = presets()
            .into_iter()
            .filter_map(|p| Some((p.file_stem()?.to_string_lossy().into_owned(), p)))
            .collect();
        let mut envs: Vec<PathBuf> = std::fs::read_dir(&options.env_dir)
            .map_err(|e| Error::Input {
                path: options.env_dir.clone(),
                message: format!("listing environment maps: {e}"),
            })?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "exr"))
            .collect();
        envs.sort();
        let env_index = envs
            .iter()
            .position(|p| p.file_name() == options.env.file_name())
            .unwrap_or_else(|| {
                envs.push(options.env.clone());
                envs.len() - 1
            });
        let camera = Camera::default();
        let distance = camera.eye.length();
        Ok(Self {
            artist: vec![None; options.stack.layers.len()],
            map_texts: MapTexts::new(),
            stack: options.stack.clone(),
            lighting: options.lighting.clone(),
            requested: options.variant,
            compiled: None,
            builds: 0,
            message: None,
            presets,
            envs,
            env_index,
            mesh: MeshKind::Sphere,
            exposure: 0.0,
            file: options
                .save_stack
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| "stack.toml".into()),
            history: VecDeque::with_capacity(HISTORY),
            invocations: None,
            device,
            fp16_supported,
            yaw: (camera.eye.x).atan2(camera.eye.z),
            pitch: (camera.eye.y / distance).asin(),
            distance,
            viewport: (
                options.width.saturating_sub(SIDE_WIDTH as u32).max(64),
                options.height,
            ),
            actions: Vec::new(),
        })
    }

    pub fn take_actions(&mut self) -> Vec<Action> {
        std::mem::take(&mut self.actions)
    }

    /// The variant the scene should render: the requested one, unless it cannot hold the
    /// stack (then the message says so and the last good one stays).
    pub fn variant_for_scene(&mut self) -> VariantKey {
        // A per-material pipeline's arrays have the stack's own size.
        if !self.requested.mode.per_material()
            && self.stack.layers.len() > self.requested.max_layers as usize
        {
            self.message = Some(format!(
                "the stack has {} layers; max_layers={} holds at most {}: raise max_layers or \
                 remove layers",
                self.stack.layers.len(),
                self.requested.max_layers,
                self.requested.max_layers
            ));
            return self.compiled.unwrap_or(self.requested);
        }
        self.requested
    }

    /// The scene thread could not render a frame.
    pub fn failed(&mut self, message: String) {
        self.message = Some(message);
    }

    /// The outcome of building `variant`.
    pub fn compiled(&mut self, variant: VariantKey, error: Option<String>) {
        match error {
            None => {
                self.compiled = Some(variant);
                self.builds += 1;
                self.message = None;
                self.history.clear();
            }
            Some(e) => {
                self.message = Some(format!("{variant}: {e}"));
                // Back to what runs, so the message stays until the next change.
                if let Some(c) = self.compiled {
                    self.requested = c;
                }
            }
        }
    }

    pub fn record_timing(&mut self, ms: f64, invocations: Option<u64>) {
        if self.history.len() == HISTORY {
            self.history.pop_front();
        }
        self.history.push_back(ms);
        self.invocations = invocations;
    }

    pub fn viewport_pixels(&self) -> (u32, u32) {
        (self.viewport.0.max(16), self.viewport.1.max(16))
    }

    pub fn camera(&self) -> Camera {
        orbit(self.yaw, self.pitch, self.distance)
    }

    fn zoom(&mut self, lines: f32) {
        self.distance = (self.distance * (1.0 - 0.08 * lines)).clamp(1.4, 12.0);
    }

    pub fn show(&mut self, ui: &mut Ui, scene: Option<&egui::TextureHandle>) {
        egui::Panel::left("controls")
            .resizable(false)
            .exact_size(SIDE_WIDTH)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    if let Some(message) = &self.message {
                        ui.label(RichText::new(message).color(Color32::from_rgb(240, 180, 80)));
                        ui.separator();
                    }
                    if self.compiled != Some(self.requested) && self.message.is_none() {
                        ui.label(format!("compiling {} …", self.requested));
                        ui.separator();
                    }
                    egui::CollapsingHeader::new("Profiling")
                        .default_open(true)
                        .show(ui, |ui| self.profiling(ui));
                    egui::CollapsingHeader::new("Variant")
                        .default_open(true)
                        .show(ui, |ui| self.variant(ui));
                    ui.collapsing("Scene", |ui| self.scene(ui));
                    ui.collapsing("Lights", |ui| self.lights(ui));
                    egui::CollapsingHeader::new("Layer stack")
                        .default_open(true)
                        .show(ui, |ui| self.layers(ui));
                    ui.collapsing("Simplification", |ui| self.simplification(ui));
                });
            });
        egui::CentralPanel::no_frame().show(ui, |ui| {
            let size = ui.available_size();
            let ppp = ui.ctx().pixels_per_point();
            self.viewport = (
                (size.x * ppp).round().max(16.0) as u32,
                (size.y * ppp).round().max(16.0) as u32,
            );
            if let Some(texture) = scene {
                let response = ui.add(
                    egui::Image::new((texture.id(), size)).sense(egui::Sense::click_and_drag()),
                );
                if response.dragged_by(egui::PointerButton::Secondary) {
                    // The right button turns the first directional light.
                    self.turn_light(response.drag_delta());
                } else if response.dragged() {
                    let d = response.drag_delta();
                    self.yaw -= d.x * 0.01;
                    self.pitch = (self.pitch + d.y * 0.01).clamp(-1.45, 1.45);
                }
                if response.hovered() {
                    let scroll = ui.input(|i| i.smooth_scroll_delta.y);
                    if scroll != 0.0 {
                        self.zoom(scroll / 40.0);
                    }
                }
            }
        });
    }

    fn profiling(&mut self, ui: &mut Ui) {
        ui.label(format!("device: {}", self.device));
        match summary(&self.history) {
            Some((avg, min, max)) => {
                ui.label(format!(
                    "shaded draw, last {} frames: avg {avg:.3} ms, min {min:.3}, max {max:.3}",
                    self.history.len()
                ));
            }
            None => {
                ui.label("shaded draw: no frame yet");
            }
        }
        if let Some(n) = self.invocations {
            ui.label(format!("fragment invocations: {n}"));
        }
        let (rect, _) =
            ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), egui::Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 2.0, Color32::from_gray(24));
        if let Some((_, _, max)) = summary(&self.history) {
            let n = self.history.len().max(2) - 1;
            let points: Vec<egui::Pos2> = self
                .history
                .iter()
                .enumerate()
                .map(|(i, &ms)| {
                    egui::pos2(
                        rect.left() + rect.width() * i as f32 / n as f32,
                        rect.bottom() - rect.height() * (ms / max.max(1e-9)) as f32 * 0.95,
                    )
                })
                .collect();
            painter.add(egui::Shape::line(
                points,
                egui::Stroke::new(1.5, Color32::from_rgb(120, 200, 255)),
            ));
        }
    }

    fn variant(&mut self, ui: &mut Ui) {
        let before = self.requested;
        let v = &mut self.requested;
        choose(ui, "model", &mut v.model, Model::VALUES);
        ui.add(Slider::new(&mut v.max_layers, 1..=16).text("max_layers"));
        ui.add_enabled(
            self.fp16_supported,
            egui::Checkbox::new(&mut v.fp16, "fp16 arithmetic"),
        );
        choose(ui, "tir", &mut v.tir, Tir::VALUES);
        choose(ui, "fgd", &mut v.fgd, Fgd::VALUES);
        choose(ui, "g2", &mut v.g2, G2::VALUES);
        choose(ui, "ndf", &mut v.ndf, Ndf::VALUES);
        // The 6-flux walk: every colour channel at once, or one at a time.
        if v.model == Model::Tm6 {
            choose(ui, "channels", &mut v.channels, Channels::VALUES);
        } else {
            v.channels = Channels::Rgb;
        }
        // generic: one pipeline for every stack; specialized: rebuilt when an edit changes
        // the stack's structure; specialized-values and baked: rebuilt on every edit.
        choose(ui, "mode", &mut v.mode, Mode::VALUES);
        // How the environment lights each lobe (matched and taps build a second cube once).
        choose(ui, "ibl", &mut v.ibl, Ibl::VALUES);
        if v.ibl == Ibl::Taps {
            ui.add(
                Slider::new(&mut v.taps, 1..=IBL_TAP_LIMIT)
                    .logarithmic(true)
                    .text("taps per lobe"),
            );
        } else {
            v.taps = IBL_TAP_COUNT;
        }
        // Fragment shading, or a G-buffer then compute.
        choose(ui, "path", &mut v.path, ShadePath::VALUES);
        // The deferred path's pixels to their pipelines: all at once, by tile, or by pixel.
        if v.path == ShadePath::Deferred {
            choose(ui, "classify", &mut v.classify, Classify::VALUES);
        } else {
            v.classify = Classify::None;
        }
        if self.requested != before {
            self.stack.model = stack_model(self.requested.model, self.stack.model);
            self.message = None;
        }
        ui.label(RichText::new(self.requested.to_string()).small());
        ui.label(RichText::new(format!("pipelines built: {}", self.builds)).small());
    }

    fn scene(&mut self, ui: &mut Ui) {
        let env_before = self.env_index;
        ComboBox::from_label("environment")
            .selected_text(file_stem(&self.envs[self.env_index]))
            .show_ui(ui, |ui| {
                for (i, path) in self.envs.iter().enumerate() {
                    ui.selectable_value(&mut self.env_index, i, file_stem(path));
                }
            });
        if self.env_index != env_before {
            self.actions
                .push(Action::Environment(self.envs[self.env_index].clone()));
        }
        let mesh_before = self.mesh;
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.mesh, MeshKind::Sphere, "sphere");
            ui.selectable_value(&mut self.mesh, MeshKind::Torus, "torus");
        });
        if self.mesh != mesh_before {
            self.actions.push(Action::Mesh(self.mesh));
        }
        ui.add(Slider::new(&mut self.exposure, -6.0..=6.0).text("exposure (EV)"));
        ui.label("drag the image to orbit, scroll to zoom");
    }

    /// Turns the first directional light by a drag of `d` points (azimuth across, elevation
    /// up and down), adding one from the upper left when there is none.
    fn turn_light(&mut self, d: egui::Vec2) {
        use crate::render::lights::LightKind;
        let index = match self
            .lighting
            .lights
            .iter()
            .position(|l| matches!(l.kind, LightKind::Directional { .. }))
        {
            Some(i) => i,
            None if self.lighting.lights.len() < crate::render::lights::MAX_LIGHTS => {
                self.lighting.lights.push(new_directional());
                self.lighting.lights.len() - 1
            }
            None => return,
        };
        if let LightKind::Directional { direction, .. } = &mut self.lighting.lights[index].kind {
            let (azimuth, elevation) = angles_of(*direction);
            *direction = direction_of(
                azimuth + f64::from(d.x) * 0.01,
                (elevation - f64::from(d.y) * 0.01).clamp(-1.5, 1.5),
            );
        }
    }

    /// The environment's scale and each analytic light: direction (azimuth, elevation) or
    /// position, colour, intensity, a directional light's angular radius; add and remove.
    fn lights(&mut self, ui: &mut Ui) {
        use crate::render::lights::{Light, LightKind, MAX_ANGULAR_RADIUS_DEG, MAX_LIGHTS};
        ui.add(Slider::new(&mut self.lighting.environment, 0.0..=4.0).text("environment scale"));
        let mut remove = None;
        for (i, light) in self.lighting.lights.iter_mut().enumerate() {
            ui.separator();
            ui.horizontal(|ui| {
                let mut rgb = light.color.map(|c| c as f32);
                egui::color_picker::color_edit_button_rgb(ui, &mut rgb);
                light.color = rgb.map(f64::from);
                ui.label(match light.kind {
                    LightKind::Directional { .. } => format!("light {}: directional", i + 1),
                    LightKind::Point { .. } => format!("light {}: point", i + 1),
                });
                if ui.small_button("remove").clicked() {
                    remove = Some(i);
                }
            });
            ui.add(
                Slider::new(&mut light.intensity, 0.0..=50.0)
                    .logarithmic(true)
                    .text("intensity"),
            );
            match &mut light.kind {
                LightKind::Directional {
                    direction,
                    angular_radius,
                } => {
                    let (mut azimuth, mut elevation) = angles_of(*direction);
                    azimuth = azimuth.to_degrees();
                    elevation = elevation.to_degrees();
                    ui.add(Slider::new(&mut azimuth, -180.0..=180.0).text("azimuth °"));
                    ui.add(Slider::new(&mut elevation, -85.0..=85.0).text("elevation °"));
                    *direction = direction_of(azimuth.to_radians(), elevation.to_radians());
                    let mut degrees = angular_radius.to_degrees();
                    ui.add(
                        Slider::new(&mut degrees, 0.0..=MAX_ANGULAR_RADIUS_DEG)
                            .text("angular radius °"),
                    );
                    *angular_radius = degrees.to_radians();
                }
                LightKind::Point { position } => {
                    rgb_row(ui, "position", position, -20.0..=20.0, 0.05)
                }
            }
        }
        if let Some(i) = remove {
            self.lighting.lights.remove(i);
        }
        ui.separator();
        ui.horizontal(|ui| {
            let room = self.lighting.lights.len() < MAX_LIGHTS;
            if ui
                .add_enabled(room, egui::Button::new("add directional"))
                .clicked()
            {
                self.lighting.lights.push(new_directional());
            }
            if ui
                .add_enabled(room, egui::Button::new("add point"))
                .clicked()
            {
                self.lighting.lights.push(Light {
                    kind: LightKind::Point {
                        position: [2.0, 1.5, 2.0],
                    },
                    color: [1.0; 3],
                    intensity: 10.0,
                });
            }
        });
        ui.label("right-drag the image to turn the first directional light");
    }

    fn layers(&mut self, ui: &mut Ui) {
        self.files(ui);
        ui.separator();
        let count = self.stack.layers.len();
        let mut edit = self.stack.layers.clone();
        let mut artist = self.artist.clone();
        let mut op = None;
        let tm6 = self.stack.model == Model::Tm6;
        let mapped = self.mapped_fields();
        let mut coverage_change = None;
        let mut map_change = None;
        for (i, layer) in edit.iter_mut().enumerate() {
            let last = i + 1 == count;
            egui::CollapsingHeader::new(format!("layer {}{}", i + 1, describe(layer)))
                .id_salt(("layer", i))
                .default_open(count <= 2)
                .show(ui, |ui| {
                    ui.horizontal(|ui| {
                        if ui.small_button("up").clicked() && i > 0 && !last {
                            op = Some(LayerOp::Up(i));
                        }
                        if ui.small_button("down").clicked() && i + 2 < count {
                            op = Some(LayerOp::Down(i));
                        }
                        if ui.small_button("remove").clicked() && count > 1 {
                            op = Some(LayerOp::Remove(i));
                        }
                    });
                    if !mapped[i].is_empty() {
                        ui.label(
                            RichText::new(format!("varies over the surface: {}", mapped[i]))
                                .small(),
                        );
                    }
                    layer_editor(ui, layer, &mut artist[i], tm6);
                    let before = coverage_of(&self.stack, i);
                    let mut after = before;
                    coverage_editor(ui, i, &mut after);
                    if after != before {
                        coverage_change = Some((i, after));
                    }
                    if let Some(edit) =
                        maps::maps_editor(ui, i, &self.stack, tm6, &mut self.map_texts)
                    {
                        map_change = Some((i, edit));
                    }
                });
        }
        if let Some((i, coverage)) = coverage_change {
            self.set_coverage(i, coverage);
        }
        if let Some((i, edit)) = map_change {
            self.set_map(i, &edit);
        }
        if ui.button("add a clear coat on top").clicked() {
            op = Some(LayerOp::AddTop);
        }
        if let Some(op) = op {
            // Layers move, go and come in the file's form, so each keeps its maps.
            op.apply_artist(&mut artist);
            self.artist = artist;
            self.map_texts.clear();
            let edited = maps::edit_document(&self.stack, |document| op.apply(document));
            self.accept(edited);
        } else {
            self.artist = artist;
            if edit != self.stack.layers {
                self.try_stack(edit);
            }
        }
    }

    /// The presets, and loading and saving the stack as a material file.
    fn files(&mut self, ui: &mut Ui) {
        ui.horizontal(|ui| {
            let mut chosen = None;
            ComboBox::from_label("preset")
                .selected_text(&self.stack.name)
                .show_ui(ui, |ui| {
                    for (name, path) in &self.presets {
                        if ui.selectable_label(false, name).clicked() {
                            chosen = Some(path.clone());
                        }
                    }
                });
            if let Some(path) = chosen {
                self.load(&path);
            }
        });
        ui.horizontal(|ui| {
            ui.text_edit_singleline(&mut self.file);
        });
        ui.horizontal(|ui| {
            if ui.button("Load TOML").clicked() {
                let path = PathBuf::from(&self.file);
                self.load(&path);
            }
            if ui.button("Save TOML").clicked() {
                let path = PathBuf::from(&self.file);
                self.message = Some(match self.stack.save(&path) {
                    Ok(()) => format!("saved {}", path.display()),
                    Err(e) => e.to_string(),
                });
            }
        });
    }

    /// The fields each layer reads from a map (textures, patterns, coverage): shown, and kept
    /// through edits; the map's values override the constants edited here.
    fn mapped_fields(&self) -> Vec<String> {
        (0..self.stack.layers.len())
            .map(|i| {
                let surface = self.stack.surface.as_ref();
                let layer = surface.and_then(|s| s.layers.get(i));
                layer.map_or_else(String::new, |l| {
                    l.sources
                        .iter()
                        .map(|(f, _)| f.key())
                        .collect::<Vec<_>>()
                        .join(", ")
                })
            })
            .collect()
    }

    /// What `lamina simplify` would do to the stack being edited, step by step (recomputed as
    /// it is edited; the rules are exact in the model, `material::simplify`).
    fn simplification(&mut self, ui: &mut Ui) {
        let report = simplify(&self.stack).to_string();
        for line in report.lines() {
            ui.label(RichText::new(line.trim_start()).small());
        }
    }

    /// Takes an edited stack when it passes the file format's validation (the same checks
    /// `lamina render` applies), else says why and keeps the current one.
    fn try_stack(&mut self, layers: Vec<LayerParams>) {
        let candidate = Stack {
            layers,
            ..self.stack.clone()
        };
        let valid = Stack::from_toml(&candidate.to_toml(), Path::new("(edited stack)"))
            .map_err(|e| e.to_string());
        self.accept(valid);
    }

    /// Takes a validated edit of the stack (or shows why it was refused), and says when the
    /// stack outgrows the requested `max_layers`.
    fn accept(&mut self, edited: std::result::Result<Stack, String>) {
        match edited {
            Ok(valid) => {
                self.artist.resize(valid.layers.len(), None);
                self.stack = valid;
                if !self.requested.mode.per_material()
                    && self.stack.layers.len() > self.requested.max_layers as usize
                {
                    self.message = Some(format!(
                        "the stack has {} layers; max_layers={} holds at most {}: raise max_layers",
                        self.stack.layers.len(),
                        self.requested.max_layers,
                        self.requested.max_layers
                    ));
                } else if self
                    .message
                    .as_deref()
                    .is_some_and(|m| m.contains("layers;"))
                {
                    self.message = None;
                }
            }
            Err(e) => self.message = Some(e),
        }
    }

    /// Gives layer `i` the coverage `coverage` through the file format (the maps are baked
    /// again), or says why the format refuses it.
    fn set_coverage(&mut self, i: usize, coverage: CoverageEdit) {
        let edited = maps::edit_layer(&self.stack, i, |layer| {
            match coverage_value(coverage) {
                Some(value) => layer.insert("coverage".into(), value),
                None => layer.remove("coverage"),
            };
        });
        self.accept(edited);
    }

    /// Makes `edit` to layer `i`'s maps through the file format, or says why it refuses.
    fn set_map(&mut self, i: usize, edit: &MapEdit) {
        let edited = maps::apply(&self.stack, i, edit);
        if edited.is_ok() {
            // The text boxes start again from what the file now says.
            self.map_texts.retain(|(layer, _, _), _| *layer != i);
        }
        self.accept(edited);
    }

    fn load(&mut self, path: &Path) {
        match Stack::load(path) {
            Ok(stack) => {
                self.artist = vec![None; stack.layers.len()];
                self.map_texts.clear();
                if stack.layers.len() > self.requested.max_layers as usize {
                    self.requested.max_layers = stack.layers.len() as u32;
                }
                if self.requested.model != Model::Ggx {
                    self.requested.model = stack.model;
                }
                self.stack = stack;
                self.message = None;
            }
            Err(e) => self.message = Some(e.to_string()),
        }
    }
}

/// The directional light the viewer adds: white, from the upper left.
fn new_directional() -> crate::render::lights::Light {
    use crate::render::lights::{Light, LightKind};
    Light {
        kind: LightKind::Directional {
            direction: direction_of(-0.6, 0.6),
            angular_radius: 0.0,
        },
        color: [1.0; 3],
        intensity: 3.0,
    }
}

/// A unit direction (towards the light) of azimuth φ around +y from +z and elevation θ.
fn direction_of(azimuth: f64, elevation: f64) -> [f64; 3] {
    let (s, c) = elevation.sin_cos();
    [c * azimuth.sin(), s, c * azimuth.cos()]
}

/// The (azimuth, elevation) of a unit direction, [`direction_of`]'s inverse.
fn angles_of(d: [f64; 3]) -> (f64, f64) {
    (d[0].atan2(d[2]), d[1].clamp(-1.0, 1.0).asin())
}

fn choose<T: Axis + PartialEq + Copy + std::fmt::Display>(
    ui: &mut Ui,
    label: &str,
    value: &mut T,
    values: &[(&str, T)],
) {
    ComboBox::from_label(label)
        .selected_text(value.to_string())
        .show_ui(ui, |ui| {
            for &(name, v) in values {
                ui.selectable_value(value, v, name);
            }
        });
}

fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
