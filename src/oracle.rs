//! The CPU oracle of a variant: the f64 model of [`crate::model`], picked by the variant.
//!
//! Two forms:
//! - [`evaluate`]: the model itself — FGD integrated exactly (with the variant's G2 form), no
//!   TIR correction. The white furnace compares the GPU with it, and `lamina eval --backend
//!   exact` prints it.
//! - [`VariantOracle`]: the model with every axis of the variant that f64 can honour — the FGD
//!   source (`fgd`: the CPU twins of the split-sum, 4-D, resampled and Belcour tables) and the
//!   TIR correction (`tir`: constant, analytic, and the twins of the LUTs) — from the very tables
//!   the GPU samples. `lamina eval --backend cpu` prints it; it refuses, naming the axis, what it
//!   cannot honour (`fp16=on`, `model=ggx`).

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::model::fgd::ExactFgd;
use crate::model::{tm2, tm6, Evaluation, Fgd, LayerParams, NoTir, Tir};
use crate::render::inputs::ShadingInputs;
use crate::variant::{Model, VariantKey};

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

/// The f64 model run with exactly what `variant` samples on the GPU: its FGD tables and TIR
/// term through their CPU twins. The tables come from the disk cache or are built on `gpu`,
/// as the GPU backend's would be.
pub struct VariantOracle<'g> {
    variant: VariantKey,
    inputs: ShadingInputs<'g>,
}

impl<'g> VariantOracle<'g> {
    pub fn new(gpu: &'g Gpu, variant: VariantKey) -> Result<Self> {
        check_cpu_variant(variant)?;
        let mut inputs = ShadingInputs::new(gpu)?;
        inputs.prepare(variant)?;
        Ok(Self { variant, inputs })
    }

    /// The model at each view cosine.
    pub fn evaluate(&self, layers: &[LayerParams], cosines: &[f64]) -> Result<Vec<Evaluation>> {
        let fgd = self.inputs.fgd_lookup(self.variant)?;
        let tir = self.inputs.tir_lookup(self.variant);
        Ok(cosines
            .iter()
            .map(|&mu| evaluate_model(self.variant.model, layers, mu, &fgd, tir.as_ref()))
            .collect())
    }
}
