//! The viewer's layer editing: a layer's fields (physical or artist form, roughness, the
//! 6-flux medium), its coverage (none, a value or a pattern), and the moves of layers through
//! the material file, so that each layer keeps its maps.

use egui::{ComboBox, DragValue, Slider, Ui};

use crate::material::surface::{Coords, Field, PatternKind, Shape};
use crate::material::{gulbrandsen, Stack};
use crate::model::LayerParams;

/// An edit of the stack's layers, applied to the material file's layers so that each layer
/// keeps its maps.
pub(super) enum LayerOp {
    Up(usize),
    Down(usize),
    Remove(usize),
    AddTop,
}

impl LayerOp {
    /// The operation on the file's `layer` array (each layer's table carries its maps).
    pub(super) fn apply(&self, document: &mut toml::Table) {
        let Some(layers) = document
            .get_mut("layer")
            .and_then(toml::Value::as_array_mut)
        else {
            return;
        };
        match *self {
            Self::Up(i) => layers.swap(i - 1, i),
            Self::Down(i) => layers.swap(i, i + 1),
            Self::Remove(i) => {
                layers.remove(i);
            }
            Self::AddTop => {
                let mut coat = toml::Table::new();
                coat.insert("ior".into(), toml::Value::Array(vec![1.5.into(); 3]));
                coat.insert("roughness".into(), 0.05.into());
                layers.insert(0, toml::Value::Table(coat));
            }
        }
    }

    pub(super) fn apply_artist(&self, artist: &mut Vec<Option<([f32; 3], [f32; 3])>>) {
        match *self {
            Self::Up(i) => artist.swap(i - 1, i),
            Self::Down(i) => artist.swap(i, i + 1),
            Self::Remove(i) => {
                artist.remove(i);
            }
            Self::AddTop => artist.insert(0, None),
        }
    }
}

/// A layer's coverage as the viewer edits it (`material::surface`): none, one value, or a
/// pattern (checker, noise, cells) with its scale, seed, optional threshold and coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum CoverageEdit {
    None,
    Constant(f64),
    Pattern {
        kind: PatternKind,
        scale: u32,
        seed: u32,
        threshold: Option<f64>,
        screen: bool,
    },
}

/// Layer `i`'s coverage in `stack`, as [`CoverageEdit`]; a texture reads as `None` here (it
/// is kept unless the editor replaces it).
pub(super) fn coverage_of(stack: &Stack, i: usize) -> CoverageEdit {
    let source = stack
        .surface
        .as_ref()
        .and_then(|s| s.layers.get(i))
        .and_then(|l| l.source(Field::Coverage));
    match source.map(|s| (&s.shape, s)) {
        Some((Shape::Uniform(c), _)) => CoverageEdit::Constant(*c),
        Some((Shape::Pattern(p), s)) => CoverageEdit::Pattern {
            kind: p.kind,
            scale: p.scale,
            seed: p.seed,
            threshold: s.threshold,
            screen: s.coords == Coords::Screen,
        },
        _ => CoverageEdit::None,
    }
}

/// The TOML value of a coverage; `None` removes it.
pub(super) fn coverage_value(coverage: CoverageEdit) -> Option<toml::Value> {
    match coverage {
        CoverageEdit::None => None,
        CoverageEdit::Constant(c) => Some(toml::Value::Float(c)),
        CoverageEdit::Pattern {
            kind,
            scale,
            seed,
            threshold,
            screen,
        } => {
            let mut t = toml::Table::new();
            let name = match kind {
                PatternKind::Checker => "checker",
                PatternKind::Noise => "noise",
                PatternKind::Cells => "cells",
            };
            t.insert("pattern".into(), name.into());
            t.insert("scale".into(), i64::from(scale).into());
            if kind != PatternKind::Checker {
                t.insert("seed".into(), i64::from(seed).into());
            }
            if let Some(th) = threshold {
                t.insert("threshold".into(), th.into());
            }
            if screen {
                t.insert("coords".into(), "screen".into());
            }
            Some(toml::Value::Table(t))
        }
    }
}

/// The coverage controls of layer `i`.
pub(super) fn coverage_editor(ui: &mut Ui, i: usize, coverage: &mut CoverageEdit) {
    let label = |c: &CoverageEdit| match c {
        CoverageEdit::None => "none",
        CoverageEdit::Constant(_) => "constant",
        CoverageEdit::Pattern {
            kind: PatternKind::Checker,
            ..
        } => "checker",
        CoverageEdit::Pattern {
            kind: PatternKind::Noise,
            ..
        } => "noise",
        CoverageEdit::Pattern {
            kind: PatternKind::Cells,
            ..
        } => "cells",
    };
    let pattern = |kind| CoverageEdit::Pattern {
        kind,
        scale: 4,
        seed: 0,
        threshold: Some(0.5),
        screen: false,
    };
    ComboBox::from_id_salt(("coverage", i))
        .selected_text(format!("coverage: {}", label(coverage)))
        .show_ui(ui, |ui| {
            for choice in [
                CoverageEdit::None,
                CoverageEdit::Constant(1.0),
                pattern(PatternKind::Checker),
                pattern(PatternKind::Noise),
                pattern(PatternKind::Cells),
            ] {
                if ui
                    .selectable_label(label(coverage) == label(&choice), label(&choice))
                    .clicked()
                    && label(coverage) != label(&choice)
                {
                    *coverage = choice;
                }
            }
        });
    match coverage {
        CoverageEdit::None => {}
        CoverageEdit::Constant(c) => {
            ui.add(Slider::new(c, 0.0..=1.0).text("coverage"));
        }
        CoverageEdit::Pattern {
            kind,
            scale,
            seed,
            threshold,
            screen,
        } => {
            ui.add(Slider::new(scale, 1..=64).text("scale"));
            if *kind == PatternKind::Checker && *scale % 2 == 1 {
                *scale += 1; // a checker tiles with an even scale
            }
            if *kind != PatternKind::Checker {
                ui.add(DragValue::new(seed).range(0..=9999).prefix("seed "));
                let mut on = threshold.is_some();
                ui.horizontal(|ui| {
                    ui.checkbox(&mut on, "threshold");
                    let mut t = threshold.unwrap_or(0.5);
                    ui.add_enabled(on, Slider::new(&mut t, 0.0..=1.0));
                    *threshold = on.then_some(t);
                });
            }
            ui.checkbox(screen, "screen coordinates (pixel for pixel)");
        }
    }
}

/// How the layer header names a layer's kind.
pub(super) fn describe(layer: &LayerParams) -> &'static str {
    if layer.is_diffuse() {
        " (diffuse base)"
    } else if layer.is_conductor() {
        " (conductor)"
    } else if layer.depth > 0.0 {
        " (dielectric, medium)"
    } else {
        " (dielectric)"
    }
}

/// One layer's fields: the physical form (η, κ per channel) or the artist form (F0 and edge
/// tint, Gulbrandsen 2014) for conductors, roughness, and the 6-flux medium.
pub(super) fn layer_editor(
    ui: &mut Ui,
    layer: &mut LayerParams,
    artist: &mut Option<([f32; 3], [f32; 3])>,
    tm6: bool,
) {
    if let Some(rho) = &mut layer.diffuse {
        // A Lambertian base has its albedo and nothing else (model::diffuse).
        ui.horizontal(|ui| {
            let mut rgb = rho.map(|c| c as f32);
            egui::color_picker::color_edit_button_rgb(ui, &mut rgb);
            *rho = rgb.map(|c| f64::from(c.clamp(0.0, 1.0)));
            ui.label("albedo");
        });
        return;
    }
    if layer.is_conductor() {
        let mut use_artist = artist.is_some();
        ui.checkbox(&mut use_artist, "artist form (F0, edge tint)");
        if use_artist && artist.is_none() {
            let f0 = std::array::from_fn(|c| {
                let (n, k) = (layer.ior[c], layer.kappa[c]);
                (((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)) as f32
            });
            *artist = Some((f0, [0.5; 3]));
        } else if !use_artist {
            *artist = None;
        }
    }
    match artist {
        Some((f0, tint)) => {
            ui.horizontal(|ui| {
                egui::color_picker::color_edit_button_rgb(ui, f0);
                ui.label("F0");
                egui::color_picker::color_edit_button_rgb(ui, tint);
                ui.label("edge tint");
            });
            for c in 0..3 {
                let (n, k) = gulbrandsen(f64::from(f0[c]).clamp(0.0, 0.999), f64::from(tint[c]));
                layer.ior[c] = n;
                layer.kappa[c] = k.max(1e-3);
            }
        }
        None => {
            rgb_row(ui, "η", &mut layer.ior, 0.01..=10.0, 0.005);
            if layer.is_conductor() {
                rgb_row(ui, "κ", &mut layer.kappa, 0.001..=20.0, 0.01);
            }
        }
    }
    ui.add(Slider::new(&mut layer.roughness, 0.0..=1.0).text("roughness α"));
    if tm6 && !layer.is_conductor() {
        ui.add(Slider::new(&mut layer.depth, 0.0..=10.0).text("depth"));
        rgb_row(ui, "σs", &mut layer.sigma_s, 0.0..=50.0, 0.05);
        rgb_row(ui, "σa", &mut layer.sigma_a, 0.0..=50.0, 0.05);
        ui.add(Slider::new(&mut layer.g, -0.95..=0.95).text("g"));
    }
}

pub(super) fn rgb_row(
    ui: &mut Ui,
    label: &str,
    values: &mut [f64; 3],
    range: std::ops::RangeInclusive<f64>,
    speed: f64,
) {
    ui.horizontal(|ui| {
        ui.label(label);
        for v in values.iter_mut() {
            ui.add(DragValue::new(v).range(range.clone()).speed(speed));
        }
    });
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::viewer::maps;

    /// Moving, removing and adding layers keeps each layer's maps with it.
    #[test]
    fn layer_operations_carry_the_maps() {
        let text = "[[layer]]\nior = [1.5, 1.5, 1.5]\nroughness = 0.1\n\
                    coverage = { pattern = \"checker\", scale = 4 }\n\
                    [[layer]]\nior = [1.4, 1.4, 1.4]\nroughness = 0.2\n\
                    [[layer]]\nior = [0.2, 0.4, 1.4]\nkappa = [4.0, 2.4, 1.6]\nroughness = 0.3\n";
        let stack = Stack::from_toml(text, Path::new("test.toml")).unwrap();
        let coverage = |s: &Stack, i: usize| {
            s.surface
                .as_ref()
                .and_then(|m| m.layers.get(i))
                .is_some_and(|l| l.sources.iter().any(|(f, _)| *f == Field::Coverage))
        };
        assert!(coverage(&stack, 0) && !coverage(&stack, 1));
        let moved = maps::edit_document(&stack, |d| LayerOp::Down(0).apply(d));
        let moved = moved.unwrap();
        assert!(
            !coverage(&moved, 0) && coverage(&moved, 1),
            "the coverage moved with its coat"
        );
        assert_eq!(moved.layers[1].ior, stack.layers[0].ior);
        let added = maps::edit_document(&stack, |d| LayerOp::AddTop.apply(d)).unwrap();
        assert!(!coverage(&added, 0) && coverage(&added, 1));
        assert_eq!(added.layers.len(), stack.layers.len() + 1);
        let removed = maps::edit_document(&stack, |d| LayerOp::Remove(0).apply(d)).unwrap();
        assert!(!coverage(&removed, 0));
    }

    /// What the coverage editor writes reads back as what it edited, and "none" removes it.
    #[test]
    fn a_coverage_edit_round_trips_through_the_file_format() {
        let base = "[[layer]]\nior = [1.5, 1.5, 1.5]\nroughness = 0.1\n[[layer]]\ndiffuse = [0.5, 0.5, 0.5]\n";
        let stack = Stack::from_toml(base, Path::new("test.toml")).unwrap();
        assert_eq!(coverage_of(&stack, 0), CoverageEdit::None);
        for edit in [
            CoverageEdit::Constant(0.25),
            CoverageEdit::Pattern {
                kind: PatternKind::Noise,
                scale: 6,
                seed: 3,
                threshold: Some(0.4),
                screen: false,
            },
            CoverageEdit::Pattern {
                kind: PatternKind::Checker,
                scale: 8,
                seed: 0,
                threshold: None,
                screen: true,
            },
        ] {
            let edited = maps::edit_layer(&stack, 0, |layer| {
                layer.insert("coverage".into(), coverage_value(edit).unwrap());
            })
            .unwrap();
            assert_eq!(coverage_of(&edited, 0), edit);
            // Taking the last map away takes its `map_resolution` too.
            let cleared = maps::edit_layer(&edited, 0, |layer| {
                layer.remove("coverage");
            })
            .unwrap();
            assert_eq!(coverage_of(&cleared, 0), CoverageEdit::None);
            assert!(cleared.surface.is_none());
        }
    }
}
