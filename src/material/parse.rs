//! Reading and writing the material TOML, with errors that name file, layer and field.
//!
//! The document is walked as a `toml::Table` rather than deserialised into structs, so every
//! problem — an unknown key, an array of the wrong length, a value out of range — is reported
//! with its layer index and the allowed range.

use std::ops::RangeInclusive;
use std::path::Path;

use toml::{Table, Value};

use super::artist::gulbrandsen;
use super::{MaterialError, Stack};
use crate::model::LayerParams;
use crate::shader::{Axis, Model};

const TOP_KEYS: &[&str] = &["name", "model", "layer"];
const LAYER_KEYS: &[&str] = &[
    "ior",
    "kappa",
    "f0",
    "edge_tint",
    "roughness",
    "depth",
    "sigma_s",
    "sigma_a",
    "g",
];
const MEDIUM_KEYS: &[&str] = &["depth", "sigma_s", "sigma_a", "g"];

/// Allowed ranges, inclusive; `open_low`/`open_high` exclude an end.
struct Range {
    span: RangeInclusive<f64>,
    open_low: bool,
    open_high: bool,
    text: &'static str,
}

const IOR: Range = Range {
    span: 0.0..=10.0,
    open_low: true,
    open_high: false,
    text: "(0, 10]",
};
const KAPPA: Range = Range {
    span: 0.0..=20.0,
    open_low: false,
    open_high: false,
    text: "[0, 20]",
};
const UNIT: Range = Range {
    span: 0.0..=1.0,
    open_low: false,
    open_high: false,
    text: "[0, 1]",
};
const F0: Range = Range {
    span: 0.0..=1.0,
    open_low: false,
    open_high: true,
    text: "[0, 1)",
};
const DEPTH: Range = Range {
    span: 0.0..=100.0,
    open_low: false,
    open_high: false,
    text: "[0, 100]",
};
const SIGMA: Range = Range {
    span: 0.0..=1000.0,
    open_low: false,
    open_high: false,
    text: "[0, 1000]",
};
const HG_G: Range = Range {
    span: -1.0..=1.0,
    open_low: true,
    open_high: true,
    text: "(-1, 1)",
};

impl Range {
    fn contains(&self, v: f64) -> bool {
        self.span.contains(&v)
            && !(self.open_low && v == *self.span.start())
            && !(self.open_high && v == *self.span.end())
    }
}

/// Field access for one layer, carrying what error messages need.
struct LayerReader<'a> {
    path: &'a Path,
    index: usize,
    table: &'a Table,
}

impl LayerReader<'_> {
    fn error(&self, field: &str, message: impl Into<String>) -> MaterialError {
        MaterialError::Field {
            path: self.path.to_owned(),
            layer: self.index + 1,
            field: field.to_owned(),
            message: message.into(),
        }
    }

    fn number(&self, field: &str, value: &Value, range: &Range) -> Result<f64, MaterialError> {
        let v = match value {
            Value::Float(f) => *f,
            Value::Integer(i) => *i as f64,
            other => {
                return Err(self.error(
                    field,
                    format!("expected a number, found {}", other.type_str()),
                ))
            }
        };
        if !v.is_finite() {
            return Err(self.error(field, format!("{v} is not finite; allowed {}", range.text)));
        }
        if !range.contains(v) {
            return Err(self.error(
                field,
                format!("{v} is out of range; allowed {}", range.text),
            ));
        }
        Ok(v)
    }

    fn scalar(&self, field: &str, range: &Range) -> Result<Option<f64>, MaterialError> {
        self.table
            .get(field)
            .map(|v| self.number(field, v, range))
            .transpose()
    }

    fn rgb(&self, field: &str, range: &Range) -> Result<Option<[f64; 3]>, MaterialError> {
        let Some(value) = self.table.get(field) else {
            return Ok(None);
        };
        let Value::Array(items) = value else {
            return Err(self.error(
                field,
                format!(
                    "expected an array of 3 numbers (RGB), found {}",
                    value.type_str()
                ),
            ));
        };
        if items.len() != 3 {
            return Err(self.error(
                field,
                format!("expected 3 numbers (RGB), found {}", items.len()),
            ));
        }
        let mut out = [0.0; 3];
        for (o, item) in out.iter_mut().zip(items) {
            *o = self.number(field, item, range)?;
        }
        Ok(Some(out))
    }

    fn layer(&self, model: Model) -> Result<LayerParams, MaterialError> {
        if let Some(key) = self
            .table
            .keys()
            .find(|k| !LAYER_KEYS.contains(&k.as_str()))
        {
            return Err(self.error(
                key,
                format!("unknown key; layer keys are {}", LAYER_KEYS.join(", ")),
            ));
        }
        if model == Model::Tm2 {
            if let Some(key) = MEDIUM_KEYS.iter().find(|k| self.table.contains_key(**k)) {
                return Err(self.error(key, "a medium field, allowed only with model = \"tm6\""));
            }
        }
        let (ior, kappa) = self.interface()?;
        let roughness = self.scalar("roughness", &UNIT)?.ok_or_else(|| {
            self.error(
                "roughness",
                "missing; the GGX α of the layer's top interface, in [0, 1]",
            )
        })?;
        Ok(LayerParams {
            ior,
            kappa,
            roughness,
            depth: self.scalar("depth", &DEPTH)?.unwrap_or(0.0),
            sigma_s: self.rgb("sigma_s", &SIGMA)?.unwrap_or([0.0; 3]),
            sigma_a: self.rgb("sigma_a", &SIGMA)?.unwrap_or([0.0; 3]),
            g: self.scalar("g", &HG_G)?.unwrap_or(0.0),
        })
    }

    /// (η, κ) from the physical form, or from the artist form.
    fn interface(&self) -> Result<([f64; 3], [f64; 3]), MaterialError> {
        let physical = self.table.contains_key("ior") || self.table.contains_key("kappa");
        let artist = self.table.contains_key("f0") || self.table.contains_key("edge_tint");
        match (physical, artist) {
            (true, true) => {
                Err(self.error("f0", "give either ior/kappa or f0/edge_tint, not both"))
            }
            (false, false) => {
                Err(self.error("ior", "missing; give ior (and kappa) or f0 and edge_tint"))
            }
            (true, false) => {
                let ior = self
                    .rgb("ior", &IOR)?
                    .ok_or_else(|| self.error("ior", "missing (kappa alone is not enough)"))?;
                Ok((ior, self.rgb("kappa", &KAPPA)?.unwrap_or([0.0; 3])))
            }
            (false, true) => {
                let f0 = self
                    .rgb("f0", &F0)?
                    .ok_or_else(|| self.error("f0", "missing (edge_tint needs f0)"))?;
                let tint = self
                    .rgb("edge_tint", &UNIT)?
                    .ok_or_else(|| self.error("edge_tint", "missing (f0 needs edge_tint)"))?;
                let mut ior = [0.0; 3];
                let mut kappa = [0.0; 3];
                for c in 0..3 {
                    (ior[c], kappa[c]) = gulbrandsen(f0[c], tint[c]);
                }
                Ok((ior, kappa))
            }
        }
    }
}

fn file_error(path: &Path, message: impl Into<String>) -> MaterialError {
    MaterialError::File {
        path: path.to_owned(),
        message: message.into(),
    }
}

pub(super) fn parse(text: &str, path: &Path) -> Result<Stack, MaterialError> {
    let table: Table = text.parse().map_err(|e: toml::de::Error| {
        file_error(path, format!("not valid TOML: {}", e.message()))
    })?;
    if let Some(key) = table.keys().find(|k| !TOP_KEYS.contains(&k.as_str())) {
        return Err(file_error(
            path,
            format!(
                "`{key}`: unknown key; top-level keys are {}",
                TOP_KEYS.join(", ")
            ),
        ));
    }
    let name = match table.get("name") {
        None => path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => {
            return Err(file_error(
                path,
                format!("`name`: expected a string, found {}", other.type_str()),
            ))
        }
    };
    let model = match table.get("model") {
        None => Model::Tm2,
        Some(Value::String(s)) => match s.as_str() {
            "tm2" => Model::Tm2,
            "tm6" => Model::Tm6,
            _ => {
                return Err(file_error(
                    path,
                    format!("`model`: `{s}`; allowed \"tm2\", \"tm6\""),
                ))
            }
        },
        Some(other) => {
            return Err(file_error(
                path,
                format!("`model`: expected a string, found {}", other.type_str()),
            ))
        }
    };
    let layers = match table.get("layer") {
        Some(Value::Array(items)) if !items.is_empty() => items,
        _ => {
            return Err(file_error(
                path,
                "`layer`: needs at least one [[layer]] table",
            ))
        }
    };
    let mut stack = Vec::with_capacity(layers.len());
    for (index, item) in layers.iter().enumerate() {
        let Value::Table(table) = item else {
            return Err(file_error(
                path,
                format!("`layer`: entry {} is not a table", index + 1),
            ));
        };
        let reader = LayerReader { path, index, table };
        stack.push(reader.layer(model)?);
    }
    if let Some(i) = stack[..stack.len() - 1]
        .iter()
        .position(LayerParams::is_conductor)
    {
        return Err(MaterialError::Field {
            path: path.to_owned(),
            layer: i + 1,
            field: "kappa".into(),
            message: format!(
                "a conductor (κ > 0) must be the last layer; {} layer(s) follow it",
                stack.len() - 1 - i
            ),
        });
    }
    Ok(Stack {
        name,
        model,
        layers: stack,
    })
}

fn rgb_text(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

pub(super) fn write(stack: &Stack) -> String {
    let mut out = format!(
        "name = {}\nmodel = \"{}\"\n",
        Value::String(stack.name.clone()),
        stack.model.name()
    );
    for layer in &stack.layers {
        out += &format!(
            "\n[[layer]]\nior = {}\nkappa = {}\nroughness = {:?}\n",
            rgb_text(layer.ior),
            rgb_text(layer.kappa),
            layer.roughness
        );
        if stack.model == Model::Tm6 {
            out += &format!(
                "depth = {:?}\nsigma_s = {}\nsigma_a = {}\ng = {:?}\n",
                layer.depth,
                rgb_text(layer.sigma_s),
                rgb_text(layer.sigma_a),
                layer.g
            );
        }
    }
    out
}
