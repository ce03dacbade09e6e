//! The CPU oracle of a variant with every axis f64 can honour — the FGD source (`fgd`: the
//! CPU twins of the split-sum, 4-D, resampled and Belcour tables) and the TIR correction
//! (`tir`: constant, analytic, and the twins of the LUTs) — from the very tables the GPU
//! samples ([`ShadingInputs`]). `lamina eval --backend cpu` prints it; it refuses, naming the
//! axis, what it cannot honour (`fp16=on`, `model=ggx`).

use crate::error::Result;
use crate::gpu::Gpu;
use crate::model::oracle::{check_cpu_variant, evaluate_variant};
use crate::model::{Evaluation, LayerParams};
use crate::variant::VariantKey;

use super::inputs::ShadingInputs;

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
        Ok(evaluate_variant(
            self.variant,
            layers,
            cosines,
            &fgd,
            tir.as_ref(),
        ))
    }
}
