//! Writing a stack in the physical form of the material TOML.
//!
//! Numbers use Rust's shortest round-trip formatting (`{:?}`), so loading the text gives back
//! the identical f64 values. Medium fields are written only for `tm6` dielectric layers (a
//! conductor has no medium, and `tm2` rejects them).

use toml::Value;

use super::Stack;
use crate::model::LayerParams;
use crate::variant::{Axis, Model};

fn rgb_text(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

fn layer_text(layer: &LayerParams, with_medium: bool) -> String {
    let mut out = format!(
        "\n[[layer]]\nior = {}\nkappa = {}\nroughness = {:?}\n",
        rgb_text(layer.ior),
        rgb_text(layer.kappa),
        layer.roughness
    );
    if with_medium {
        out += &format!(
            "depth = {:?}\nsigma_s = {}\nsigma_a = {}\ng = {:?}\n",
            layer.depth,
            rgb_text(layer.sigma_s),
            rgb_text(layer.sigma_a),
            layer.g
        );
    }
    out
}

/// The TOML text of `stack`.
pub(super) fn write(stack: &Stack) -> String {
    let name = Value::String(stack.name.clone());
    let mut out = format!("name = {name}\nmodel = \"{}\"\n", stack.model.name());
    for layer in &stack.layers {
        let with_medium = stack.model == Model::Tm6 && !layer.is_conductor();
        out += &layer_text(layer, with_medium);
    }
    out
}
