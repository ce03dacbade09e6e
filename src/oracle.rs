//! The CPU oracle of a variant: what `lamina eval --backend cpu` prints and what the white
//! furnace compares the GPU with — the f64 model of [`crate::model`], picked by the variant.
//!
//! It honours the variant's model (`tm6`: the 6-flux model; `tm2` and `ggx`: the 2-flux model)
//! and its G2 form (the exactly integrated FGD uses it). It ignores the `tir` and `fgd` axes:
//! FGD is always integrated exactly and there is no TIR correction (issue 14 §1 asks for both).

use crate::model::fgd::ExactFgd;
use crate::model::{tm2, tm6, Evaluation, Fgd, LayerParams, NoTir, Tir};
use crate::shader::{Model, VariantKey};

/// The f64 oracle: the variant's model with exactly integrated FGD (its G2 form) and no TIR
/// correction.
pub fn evaluate(variant: VariantKey, layers: &[LayerParams], cos_theta: f64) -> Evaluation {
    let fgd = ExactFgd::new(variant.g2);
    evaluate_model(variant.model, layers, cos_theta, &fgd, &NoTir)
}

/// The f64 model `model` names with the given FGD and TIR providers: the 6-flux model for
/// `tm6`, the 2-flux model otherwise.
pub fn evaluate_model(
    model: Model,
    layers: &[LayerParams],
    cos_theta: f64,
    fgd: &dyn Fgd,
    tir: &dyn Tir,
) -> Evaluation {
    match model {
        Model::Tm6 => tm6::evaluate(layers, cos_theta, fgd, tir),
        _ => tm2::evaluate(layers, cos_theta, fgd, tir),
    }
}
