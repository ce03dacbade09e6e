//! The viewer's editor of a layer's maps (`material::surface`): which fields vary, and each
//! one's source — a pattern (kind, scale, seed, octaves, threshold) or a texture (file, colour
//! space, channel), its range and its coordinates. Every edit goes through the file format, so
//! the viewer accepts exactly what `lamina render` would, and says why where it refuses.

use std::collections::HashMap;
use std::path::Path;

use egui::{ComboBox, DragValue, RichText, Slider, Ui};
use toml::{Table, Value};

use crate::material::surface::{Field, MAX_SCALE};
use crate::material::Stack;
use crate::model::LayerParams;

/// Text the user is typing into a map's fields (texture file, range), kept between frames:
/// per layer, field and box.
pub type MapTexts = HashMap<(usize, Field, TextBox), String>;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextBox {
    Texture,
    Range,
}

/// An edit of layer `layer`'s maps, applied by [`apply`].
#[derive(Clone, Debug, PartialEq)]
pub enum MapEdit {
    /// The field varies, from a noise pattern over a range around its constant.
    Add(Field),
    /// The field is constant again (its value in the stack being edited).
    Remove(Field),
    /// The field's source becomes this table.
    Set(Field, Table),
}

/// The fields of `layer` a map may drive here: what the layer's kind uses (the medium's only
/// under 6-flux). Coverage has its own editor; the artist form is edited as (η, κ).
pub fn mappable(layer: &LayerParams, tm6: bool) -> Vec<Field> {
    if layer.diffuse.is_some() {
        return vec![Field::Diffuse];
    }
    let mut fields = vec![Field::Roughness, Field::Ior];
    if layer.is_conductor() {
        fields.push(Field::Kappa);
    } else if tm6 {
        fields.extend([Field::Depth, Field::SigmaS, Field::SigmaA, Field::G]);
    }
    fields
}

/// The source tables of layer `i` in `stack`, by field, coverage and the artist form left out.
pub fn sources_of(stack: &Stack, i: usize) -> Vec<(Field, Table)> {
    let Some(layer) = stack.surface.as_ref().and_then(|s| s.layers.get(i)) else {
        return Vec::new();
    };
    layer
        .sources
        .iter()
        .filter(|(f, _)| !matches!(f, Field::Coverage | Field::F0 | Field::EdgeTint))
        .filter_map(|(f, s)| s.table.as_table().map(|t| (*f, t.clone())))
        .collect()
}

/// `stack` with `edit` made to layer `i`, validated as a material file; the error is the
/// file format's.
pub fn apply(stack: &Stack, i: usize, edit: &MapEdit) -> Result<Stack, String> {
    let constant = stack
        .layers
        .get(i)
        .copied()
        .ok_or_else(|| format!("no layer {}", i + 1))?;
    edit_layer(stack, i, |layer| match edit {
        MapEdit::Add(field) => {
            layer.insert(
                field.key().into(),
                Value::Table(default_source(*field, &constant)),
            );
        }
        MapEdit::Remove(field) => {
            layer.insert(field.key().into(), constant_value(*field, &constant));
        }
        MapEdit::Set(field, table) => {
            layer.insert(field.key().into(), Value::Table(table.clone()));
        }
    })
}

/// `stack` with layer `i`'s table in its file form changed by `change`, read back as a file.
pub fn edit_layer(
    stack: &Stack,
    i: usize,
    change: impl FnOnce(&mut Table),
) -> Result<Stack, String> {
    if i >= stack.layers.len() {
        return Err(format!("no layer {}", i + 1));
    }
    edit_document(stack, |document| {
        let layer = document
            .get_mut("layer")
            .and_then(Value::as_array_mut)
            .and_then(|layers| layers.get_mut(i))
            .and_then(Value::as_table_mut);
        if let Some(layer) = layer {
            change(layer);
        }
    })
}

/// `stack` in its file form changed by `change`, read back as a file.
pub fn edit_document(stack: &Stack, change: impl FnOnce(&mut Table)) -> Result<Stack, String> {
    let mut document: Table = stack
        .to_toml()
        .parse()
        .map_err(|e| format!("the stack's text does not parse: {e}"))?;
    change(&mut document);
    // `map_resolution` sizes maps; the file refuses it once no layer has one.
    let mapped = |layer: &Value| {
        layer.as_table().is_some_and(|t| {
            t.contains_key("coverage") || t.values().any(|v| matches!(v, Value::Table(_)))
        })
    };
    let any_map = document
        .get("layer")
        .and_then(Value::as_array)
        .is_some_and(|layers| layers.iter().any(mapped));
    if !any_map {
        document.remove("map_resolution");
    }
    Stack::from_toml(&document.to_string(), Path::new("(edited stack)")).map_err(|e| e.to_string())
}

fn rounded(x: f64) -> f64 {
    (x * 1e4).round() / 1e4
}

fn rgb(c: [f64; 3]) -> Value {
    Value::Array(c.iter().map(|&x| Value::Float(rounded(x))).collect())
}

/// The field's constant in `layer`, as the file writes it.
fn constant_value(field: Field, layer: &LayerParams) -> Value {
    match field {
        Field::Roughness => Value::Float(rounded(layer.roughness)),
        Field::Ior => rgb(layer.ior),
        Field::Kappa => rgb(layer.kappa),
        Field::Depth => Value::Float(rounded(layer.depth)),
        Field::SigmaS => rgb(layer.sigma_s),
        Field::SigmaA => rgb(layer.sigma_a),
        Field::G => Value::Float(rounded(layer.g)),
        Field::Diffuse => rgb(layer.diffuse.unwrap_or([0.8; 3])),
        Field::Coverage | Field::F0 | Field::EdgeTint => Value::Float(1.0),
    }
}

/// A noise pattern over a range around the field's constant in `layer`, inside the field's
/// own range.
fn default_source(field: Field, layer: &LayerParams) -> Table {
    // An RGB field's range: its constant scaled down and up, or [0, empty] where it is 0.
    let scaled = |c: [f64; 3], low: f64, high: f64, empty: f64| {
        if c.iter().all(|&x| x == 0.0) {
            (rgb([0.0; 3]), rgb([empty; 3]))
        } else {
            (rgb(c.map(|x| x * low)), rgb(c.map(|x| x * high)))
        }
    };
    let (low, high): (Value, Value) = match field {
        Field::Roughness => {
            let r = layer.roughness;
            (
                Value::Float(rounded(r * 0.5)),
                Value::Float(rounded((r * 2.0 + 0.05).min(1.0))),
            )
        }
        Field::Ior => scaled(layer.ior, 0.95, 1.05, 1.5),
        Field::Kappa => scaled(layer.kappa, 0.8, 1.2, 1.0),
        Field::Depth => {
            let d = layer.depth;
            let (l, h) = if d == 0.0 {
                (0.0, 1.0)
            } else {
                (d * 0.5, d * 1.5)
            };
            (Value::Float(rounded(l)), Value::Float(rounded(h)))
        }
        Field::SigmaS => scaled(layer.sigma_s, 0.5, 1.5, 1.0),
        Field::SigmaA => scaled(layer.sigma_a, 0.5, 1.5, 1.0),
        Field::G => (
            Value::Float(rounded((layer.g - 0.2).max(-0.95))),
            Value::Float(rounded((layer.g + 0.2).min(0.95))),
        ),
        Field::Diffuse => {
            let c = layer.diffuse.unwrap_or([0.8; 3]);
            (rgb(c.map(|x| x * 0.5)), rgb(c))
        }
        Field::Coverage | Field::F0 | Field::EdgeTint => (Value::Float(0.0), Value::Float(1.0)),
    };
    let mut t = Table::new();
    t.insert("pattern".into(), "noise".into());
    t.insert("scale".into(), Value::Integer(4));
    t.insert("range".into(), Value::Array(vec![low, high]));
    t
}

/// The kinds a source may take, as the editor names them.
const KINDS: [&str; 4] = ["checker", "noise", "cells", "texture"];

fn kind_of(table: &Table) -> &'static str {
    if table.contains_key("texture") {
        return "texture";
    }
    match table.get("pattern").and_then(Value::as_str) {
        Some("checker") => "checker",
        Some("cells") => "cells",
        _ => "noise",
    }
}

/// `table` as a pattern of `kind`, keeping what applies of its scale, range, threshold,
/// coordinates and seed.
fn as_pattern(table: &Table, kind: &str) -> Table {
    let mut t = Table::new();
    t.insert("pattern".into(), kind.into());
    for key in ["scale", "range", "coords", "threshold", "seed", "octaves"] {
        let keep = match key {
            "seed" => kind != "checker",
            "octaves" => kind == "noise",
            "threshold" => table.contains_key("pattern"),
            _ => true,
        };
        if let (true, Some(v)) = (keep, table.get(key)) {
            t.insert(key.into(), v.clone());
        }
    }
    if kind == "checker" {
        even_scale(&mut t);
    }
    t
}

/// A checker tiles with an even scale: an odd one is raised to the next.
fn even_scale(t: &mut Table) {
    let scale = t.get("scale").and_then(Value::as_integer).unwrap_or(4);
    t.insert("scale".into(), Value::Integer(scale + scale % 2));
}

/// `table` reading the texture `path` (linear data; the red channel for a scalar field).
fn as_texture(table: &Table, path: &str, field: Field) -> Table {
    let mut t = Table::new();
    t.insert("texture".into(), path.into());
    t.insert("space".into(), "linear".into());
    if !field.is_rgb() {
        t.insert("channel".into(), "r".into());
    }
    for key in ["scale", "range", "coords"] {
        if let Some(v) = table.get(key) {
            t.insert(key.into(), v.clone());
        }
    }
    t
}

fn integer_control(ui: &mut Ui, t: &mut Table, key: &str, range: (i64, i64), default: i64) {
    let mut v = t.get(key).and_then(Value::as_integer).unwrap_or(default);
    ui.add(
        DragValue::new(&mut v)
            .range(range.0..=range.1)
            .prefix(format!("{key} ")),
    );
    t.insert(key.into(), Value::Integer(v));
}

/// The map controls of layer `i`: one section per varying field and a choice of a field to
/// vary. Returns the edit the user made this frame.
pub fn maps_editor(
    ui: &mut Ui,
    i: usize,
    stack: &Stack,
    tm6: bool,
    texts: &mut MapTexts,
) -> Option<MapEdit> {
    let layer = stack.layers.get(i)?;
    let sources = sources_of(stack, i);
    let mut edit = None;
    for (field, table) in &sources {
        let field = *field;
        egui::CollapsingHeader::new(format!("map: {}", field.key()))
            .id_salt(("map", i, field.key()))
            .default_open(true)
            .show(ui, |ui| {
                let mut t = table.clone();
                let kind = kind_of(&t);
                ComboBox::from_id_salt(("map kind", i, field.key()))
                    .selected_text(kind)
                    .show_ui(ui, |ui| {
                        for choice in &KINDS[..3] {
                            if ui.selectable_label(kind == *choice, *choice).clicked() {
                                t = as_pattern(&t, choice);
                            }
                        }
                    });
                if kind == "texture" {
                    texture_controls(ui, &mut t, field);
                } else {
                    pattern_controls(ui, &mut t, kind);
                }
                let mut screen = t.get("coords").and_then(Value::as_str) == Some("screen");
                ui.checkbox(&mut screen, "screen coordinates (pixel for pixel)");
                if screen {
                    t.insert("coords".into(), "screen".into());
                } else {
                    t.remove("coords");
                }
                text_controls(ui, &mut t, (i, field), texts);
                if ui.small_button("remove map").clicked() {
                    edit = Some(MapEdit::Remove(field));
                } else if t != *table {
                    edit = Some(MapEdit::Set(field, t));
                }
            });
    }
    let unmapped: Vec<Field> = mappable(layer, tm6)
        .into_iter()
        .filter(|f| !sources.iter().any(|(s, _)| s == f))
        .collect();
    if !unmapped.is_empty() {
        ComboBox::from_id_salt(("map a field", i))
            .selected_text("map a field…")
            .show_ui(ui, |ui| {
                for f in unmapped {
                    if ui.selectable_label(false, f.key()).clicked() {
                        edit = Some(MapEdit::Add(f));
                    }
                }
            });
    }
    edit
}

/// A texture map's controls: how it decodes, the channel a scalar field reads, the scale.
fn texture_controls(ui: &mut Ui, t: &mut Table, field: Field) {
    let path = t.get("texture").and_then(Value::as_str).unwrap_or("");
    ui.label(RichText::new(path).small());
    let mut space = t.get("space").and_then(Value::as_str).unwrap_or("linear");
    ui.horizontal(|ui| {
        for s in ["linear", "srgb"] {
            ui.radio_value(&mut space, s, s);
        }
    });
    t.insert("space".into(), space.into());
    if !field.is_rgb() {
        let mut channel = t.get("channel").and_then(Value::as_str).unwrap_or("r");
        ui.horizontal(|ui| {
            ui.label("channel");
            for c in ["r", "g", "b", "a"] {
                ui.radio_value(&mut channel, c, c);
            }
        });
        t.insert("channel".into(), channel.into());
    }
    integer_control(ui, t, "scale", (1, i64::from(MAX_SCALE)), 1);
}

/// A pattern's controls: its scale (even for a checker), seed, octaves and threshold.
fn pattern_controls(ui: &mut Ui, t: &mut Table, kind: &str) {
    integer_control(ui, t, "scale", (1, i64::from(MAX_SCALE)), 4);
    if kind == "checker" {
        even_scale(t);
    } else {
        integer_control(ui, t, "seed", (0, 9999), 0);
    }
    if kind == "noise" {
        integer_control(ui, t, "octaves", (1, 8), 4);
    }
    let mut on = t.contains_key("threshold");
    let mut th = t.get("threshold").and_then(Value::as_float).unwrap_or(0.5);
    ui.horizontal(|ui| {
        ui.checkbox(&mut on, "threshold");
        ui.add_enabled(on, Slider::new(&mut th, 0.0..=1.0));
    });
    if on {
        t.insert("threshold".into(), Value::Float(th));
    } else {
        t.remove("threshold");
    }
}

/// The typed controls of the map of `field` on layer `i`: its range (applied when the box
/// loses focus) and a texture file to use instead.
fn text_controls(ui: &mut Ui, t: &mut Table, (i, field): (usize, Field), texts: &mut MapTexts) {
    let range_now = t.get("range").map(Value::to_string).unwrap_or_default();
    let range = texts
        .entry((i, field, TextBox::Range))
        .or_insert_with(|| range_now.clone());
    ui.horizontal(|ui| {
        ui.label("range");
        let typed = ui.add(egui::TextEdit::singleline(range).desired_width(170.0));
        if typed.lost_focus() && *range != range_now {
            match range.parse::<toml::Value>().or_else(|_| {
                format!("r = {range}")
                    .parse::<Table>()
                    .map(|d| d["r"].clone())
            }) {
                Ok(v) => {
                    t.insert("range".into(), v);
                }
                Err(_) => {
                    t.insert("range".into(), Value::String(range.clone()));
                }
            }
        }
    });
    let file = texts.entry((i, field, TextBox::Texture)).or_default();
    ui.horizontal(|ui| {
        ui.label("texture");
        ui.add(
            egui::TextEdit::singleline(file)
                .desired_width(150.0)
                .hint_text("a PNG or EXR file"),
        );
        if ui.button("use").clicked() && !file.is_empty() {
            *t = as_texture(t, file, field);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn preset(name: &str) -> Stack {
        Stack::resolve(name).unwrap()
    }

    /// Adding a map makes the field vary; setting its table is what the file reads back;
    /// removing it leaves the layer's constant and no map.
    #[test]
    fn a_map_edit_round_trips_through_the_file_format() {
        let stack = preset("varnished-gold");
        assert!(sources_of(&stack, 0).is_empty());
        let added = apply(&stack, 0, &MapEdit::Add(Field::Roughness)).unwrap();
        let sources = sources_of(&added, 0);
        assert_eq!(sources.len(), 1);
        let (field, table) = &sources[0];
        assert_eq!(*field, Field::Roughness);
        assert_eq!(kind_of(table), "noise");

        let cells = as_pattern(table, "cells");
        let set = apply(&added, 0, &MapEdit::Set(Field::Roughness, cells.clone())).unwrap();
        assert_eq!(sources_of(&set, 0), vec![(Field::Roughness, cells)]);

        let removed = apply(&set, 0, &MapEdit::Remove(Field::Roughness)).unwrap();
        assert!(sources_of(&removed, 0).is_empty());
        assert!(removed.surface.is_none(), "no maps left");
        // The constant left is the one the editor showed for the mapped layer.
        assert_eq!(
            removed.layers[0].roughness,
            rounded(set.layers[0].roughness)
        );
    }

    /// Every field the editor offers takes its default map on every preset's layers.
    #[test]
    fn every_offered_field_accepts_its_default_map() {
        for name in [
            "varnished-gold",
            "glazed-ceramic",
            "dusty-varnish",
            "five-layers",
        ] {
            let stack = preset(name);
            let tm6 = stack.model == crate::variant::Model::Tm6;
            for (i, layer) in stack.layers.iter().enumerate() {
                for field in mappable(layer, tm6) {
                    let edited = apply(&stack, i, &MapEdit::Add(field));
                    assert!(edited.is_ok(), "{name} layer {i} {field:?}: {edited:?}");
                }
            }
        }
    }

    /// A texture that does not exist, or a range out of the field's range, is refused with the
    /// file format's message.
    #[test]
    fn a_bad_map_is_refused_with_the_reason() {
        let stack = apply(
            &preset("varnished-gold"),
            0,
            &MapEdit::Add(Field::Roughness),
        )
        .unwrap();
        let (_, table) = sources_of(&stack, 0).remove(0);
        let texture = as_texture(&table, "/nonexistent/wear.png", Field::Roughness);
        let e = apply(&stack, 0, &MapEdit::Set(Field::Roughness, texture)).unwrap_err();
        assert!(e.contains("wear.png"), "{e}");
        let mut wide = table.clone();
        wide.insert(
            "range".into(),
            Value::Array(vec![Value::Float(0.0), Value::Float(3.0)]),
        );
        let e = apply(&stack, 0, &MapEdit::Set(Field::Roughness, wide)).unwrap_err();
        assert!(e.contains("range") && e.contains('3'), "{e}");
    }
}
