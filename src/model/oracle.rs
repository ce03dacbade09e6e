//! The CPU oracle of a variant: the f64 model, picked by the variant.
//!
//! [`evaluate`] is the model itself — FGD integrated exactly (with the variant's G2 form), no
//! TIR correction: the white furnace compares the GPU with it, and `lamina eval --backend
//! exact` prints it. [`evaluate_model`] runs the model with given FGD and TIR providers; the
//! renderer's `render::oracle::VariantOracle` gives it the very tables a variant samples on
//! the GPU. [`check_cpu_variant`] refuses, naming the axis, what f64 cannot honour.

use crate::error::{Error, Result};
use crate::variant::{Model, Transport, VariantKey};

use super::fgd::ExactFgd;
use super::transport::Correction;
use super::{tm2, tm6, Evaluation, Fgd, LayerParams, NoTir, Tir};

/// The f64 model with exactly integrated FGD (the variant's G2 form) and no TIR correction;
/// under `transport=corrected`, with each layer's energy the transport's.
pub fn evaluate(variant: VariantKey, layers: &[LayerParams], cos_theta: f64) -> Evaluation {
    let fgd = ExactFgd::new(variant.g2);
    evaluate_variant(variant, layers, &[cos_theta], &fgd, &NoTir)
        .pop()
        .expect("one cosine")
}

/// The f64 model `variant` names (its model and transport) at each view cosine, with the given
/// FGD and TIR providers; under `transport=corrected` the ratios are built once for all.
pub fn evaluate_variant(
    variant: VariantKey,
    layers: &[LayerParams],
    cosines: &[f64],
    fgd: &dyn Fgd,
    tir: &dyn Tir,
) -> Vec<Evaluation> {
    let correction = (variant.transport == Transport::Corrected)
        .then(|| Correction::new(layers, variant.model, variant.interfaces, fgd, tir));
    cosines
        .iter()
        .map(|&mu| {
            let mut e = evaluate_model(variant.model, layers, mu, fgd, tir);
            if let Some(c) = &correction {
                c.apply(&mut e, mu);
            }
            e
        })
        .collect()
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
    check_transport(variant)?;
    if variant.model == Model::Ggx {
        return Err(Error::Unsupported(format!(
            "variant {variant}: model=ggx is not a transfer-matrix model; use model=tm2 or model=tm6"
        )));
    }
    Ok(())
}

/// Refuses, naming the axes, a transport the variant cannot have: `corrected` for `model=ggx`
/// (one lobe, no layers to carry energy between), and `interfaces=multiple` under the paper's
/// transport (which has one interface mode).
pub fn check_transport(variant: VariantKey) -> Result<()> {
    if variant.transport == Transport::Corrected && variant.model == Model::Ggx {
        return Err(Error::Unsupported(format!(
            "variant {variant}: transport=corrected needs a layered model (model=tm2 or tm6); \
             model=ggx has one lobe and no layers"
        )));
    }
    if variant.transport == Transport::Paper
        && variant.interfaces != crate::variant::Interfaces::Single
    {
        return Err(Error::Unsupported(format!(
            "variant {variant}: interfaces={} changes transport=corrected's energies; the \
             paper's transport has one interface mode (use transport=corrected, or drop \
             interfaces)",
            variant.interfaces
        )));
    }
    Ok(())
}
