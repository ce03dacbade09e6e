//! Reading the material TOML: the document level (top-level keys, `name`, `model`, the
//! `[[layer]]` array); each layer is validated by [`super::layer`].
//!
//! The document is walked as a `toml::Table` rather than deserialised with serde's
//! `deny_unknown_fields`: serde's messages name neither the layer's index nor the allowed range.

use std::path::Path;

use toml::{Table, Value};

use std::sync::Arc;

use super::layer::LayerReader;
use super::source;
use super::surface::Surface;
use super::{MaterialError, Stack};
use crate::variant::{Model, MAX_LAYERS_LIMIT};

const TOP_KEYS: &[&str] = &["name", "model", "map_resolution", "layer"];

fn file_error(path: &Path, message: impl Into<String>) -> MaterialError {
    MaterialError::File {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// Parses and validates a whole material document.
pub(super) fn parse(text: &str, path: &Path) -> Result<Stack, MaterialError> {
    let table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| file_error(path, syntax_message(text, &e)))?;
    if let Some(key) = table.keys().find(|k| !TOP_KEYS.contains(&k.as_str())) {
        let known = TOP_KEYS.join(", ");
        let message = format!("`{key}`: unknown key; top-level keys are {known}");
        return Err(file_error(path, message));
    }
    let name = name(&table, path)?;
    let model = model(&table, path)?;
    let tables = layer_tables(&table, path)?;
    let read: Vec<_> = tables
        .iter()
        .enumerate()
        .map(|(index, table)| {
            let is_last = index + 1 == tables.len();
            LayerReader {
                path,
                index,
                is_last,
                model,
                table,
                sources: Default::default(),
                artist_base: Default::default(),
            }
            .read()
        })
        .collect::<Result<_, _>>()?;
    let (layers, surfaces): (Vec<_>, Vec<_>) = read.into_iter().unzip();
    let resolution = source::resolution(&table, path)?;
    let varies = surfaces.iter().any(|s| !s.sources.is_empty());
    if !varies && table.contains_key("map_resolution") {
        let message = "`map_resolution`: sizes the maps, and no layer has one (a field given \
                       as a texture or pattern table, or a coverage)";
        return Err(file_error(path, message));
    }
    let surface = varies
        .then(|| Surface::bake(resolution, surfaces, &layers, path))
        .transpose()?
        .map(Arc::new);
    Ok(Stack {
        name,
        model,
        layers,
        source: path.to_owned(),
        surface,
    })
}

/// The parser's message with the line it points at.
fn syntax_message(text: &str, error: &toml::de::Error) -> String {
    // Bytes, not a str slice: a span end inside a multi-byte character must not panic.
    let line = error.span().map(|span| {
        let before = &text.as_bytes()[..span.start.min(text.len())];
        before.iter().filter(|&&b| b == b'\n').count() + 1
    });
    match line {
        Some(line) => format!("line {line}: not valid TOML: {}", error.message()),
        None => format!("not valid TOML: {}", error.message()),
    }
}

/// `name`, or the file stem when absent.
fn name(table: &Table, path: &Path) -> Result<String, MaterialError> {
    match table.get("name") {
        None => Ok(path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()),
        Some(Value::String(s)) => Ok(s.clone()),
        Some(other) => Err(file_error(
            path,
            format!("`name`: expected a string, found {}", other.type_str()),
        )),
    }
}

/// `model`: `tm2` (the default) or `tm6`.
fn model(table: &Table, path: &Path) -> Result<Model, MaterialError> {
    match table.get("model").map(|v| (v, v.as_str())) {
        None => Ok(Model::Tm2),
        Some((_, Some("tm2"))) => Ok(Model::Tm2),
        Some((_, Some("tm6"))) => Ok(Model::Tm6),
        Some((_, Some(other))) => Err(file_error(
            path,
            format!("`model`: `{other}`; allowed \"tm2\", \"tm6\""),
        )),
        Some((value, None)) => Err(file_error(
            path,
            format!("`model`: expected a string, found {}", value.type_str()),
        )),
    }
}

/// The `[[layer]]` tables: 1 to `MAX_LAYERS_LIMIT` of them.
fn layer_tables<'a>(table: &'a Table, path: &Path) -> Result<Vec<&'a Table>, MaterialError> {
    let items = match table.get("layer") {
        Some(Value::Array(items)) if !items.is_empty() => items,
        Some(Value::Table(_)) => {
            let message = "`layer`: write [[layer]] (an array of tables), not [layer]";
            return Err(file_error(path, message));
        }
        _ => {
            return Err(file_error(
                path,
                "`layer`: needs at least one [[layer]] table",
            ))
        }
    };
    if items.len() > MAX_LAYERS_LIMIT as usize {
        return Err(MaterialError::Field {
            path: path.to_owned(),
            layer: MAX_LAYERS_LIMIT as usize + 1,
            field: "layer".into(),
            message: format!(
                "{} layers; a stack holds at most {MAX_LAYERS_LIMIT} (the GPU buffer's size)",
                items.len()
            ),
        });
    }
    items
        .iter()
        .enumerate()
        .map(|(index, item)| match item {
            Value::Table(t) => Ok(t),
            other => Err(MaterialError::Field {
                path: path.to_owned(),
                layer: index + 1,
                field: "layer".into(),
                message: format!("expected a [[layer]] table, found {}", other.type_str()),
            }),
        })
        .collect()
}
