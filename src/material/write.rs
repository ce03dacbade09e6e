//! Writing a stack in the physical form of the material TOML.
//!
//! Numbers use Rust's shortest round-trip formatting (`{:?}`), so loading the text gives back
//! the identical f64 values. Medium fields are written only for `tm6` dielectric layers (a
//! conductor has no medium, and `tm2` rejects them).

use toml::Value;

use super::source::source_text;
use super::surface::{Field, LayerSurface};
use super::Stack;
use crate::model::LayerParams;
use crate::variant::{Axis, Model};

fn rgb_text(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

/// A field's text: its map's table where it varies, else the constant.
fn field_text(surface: Option<&LayerSurface>, field: Field, constant: String) -> String {
    match surface.and_then(|s| s.source(field)) {
        Some(source) => source_text(source),
        None => constant,
    }
}

fn layer_text(layer: &LayerParams, surface: Option<&LayerSurface>, with_medium: bool) -> String {
    let text = |field: Field, constant: String| field_text(surface, field, constant);
    let coverage = match surface.and_then(|s| s.source(Field::Coverage)) {
        Some(coverage) => format!("coverage = {}\n", source_text(coverage)),
        None => String::new(),
    };
    if let Some(rho) = layer.diffuse {
        return format!(
            "\n[[layer]]\ndiffuse = {}\n{coverage}",
            text(Field::Diffuse, rgb_text(rho))
        );
    }
    let interface = match surface.and_then(|s| s.artist) {
        Some((f0, tint)) => format!(
            "f0 = {}\nedge_tint = {}\n",
            text(Field::F0, rgb_text(f0)),
            text(Field::EdgeTint, rgb_text(tint))
        ),
        None => format!(
            "ior = {}\nkappa = {}\n",
            text(Field::Ior, rgb_text(layer.ior)),
            text(Field::Kappa, rgb_text(layer.kappa))
        ),
    };
    let mut out = format!(
        "\n[[layer]]\n{interface}roughness = {}\n",
        text(Field::Roughness, format!("{:?}", layer.roughness))
    );
    if with_medium {
        out += &format!(
            "depth = {}\nsigma_s = {}\nsigma_a = {}\ng = {}\n",
            text(Field::Depth, format!("{:?}", layer.depth)),
            text(Field::SigmaS, rgb_text(layer.sigma_s)),
            text(Field::SigmaA, rgb_text(layer.sigma_a)),
            text(Field::G, format!("{:?}", layer.g))
        );
    }
    out + &coverage
}

/// The TOML text of `stack`.
pub(super) fn write(stack: &Stack) -> String {
    let name = Value::String(stack.name.clone());
    let mut out = format!("name = {name}\nmodel = \"{}\"\n", stack.model.name());
    if let Some(surface) = &stack.surface {
        out += &format!("map_resolution = {}\n", surface.resolution);
    }
    for (i, layer) in stack.layers.iter().enumerate() {
        let with_medium = stack.model == Model::Tm6 && !layer.is_opaque_base();
        let surface = stack.surface.as_ref().and_then(|s| s.layers.get(i));
        out += &layer_text(layer, surface, with_medium);
    }
    out
}
