//! The CPU oracle of a variant: the f64 model, picked by the variant.
//!
//! [`evaluate`] is the model itself — FGD integrated exactly (with the variant's G2 form), no
//! TIR correction: the white furnace compares the GPU with it, and `lamina eval --backend
//! exact` prints it. [`evaluate_model`] runs the model with given FGD and TIR providers; the
//! renderer's `render::oracle::VariantOracle` gives it the very tables a variant samples on
//! the GPU. [`check_cpu_variant`] refuses, naming the axis, what f64 cannot honour.

use crate::error::{Error, Result};
use crate::variant::{Model, VariantKey};

use super::fgd::ExactFgd;
use super::{tm2, tm6, Evaluation, Fgd, LayerParams, NoTir, Tir};

/// The f64 model with exactly integrated FGD (the variant's G2 form) and no TIR correction.
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

/// Refuses, naming the axis, a variant whose evaluation f64 cannot reproduce.
pub fn check_cpu_variant(variant: VariantKey) -> Result<()> {
    if variant.fp16 {
        return Err(Error::Unsupported(format!(
            "variant {variant}: fp16=on cannot be evaluated on the CPU (the oracle is f64); \
             use --backend gpu, or fp16=off"
        )));
    }
    if variant.model == Model::Ggx {
        return Err(Error::Unsupported(format!(
            "variant {variant}: model=ggx is not a transfer-matrix model; use model=tm2 or model=tm6"
        )));
    }
    Ok(())
}
