//! The transfer-matrix model against the stochastic reference, per material and view cosine:
//! total reflectance and the BRDF in the plane of incidence (the `[reference]` study of a sweep
//! file, `profiling/sweeps/reference.toml`).
//!
//! The model side is the f64 model itself, as the paper defines it: FGD integrated exactly and
//! the TIR correction from the exact trapped fraction (the integral the TIR table holds), with
//! the interfaces' masking the `g2` of the study's variant. Its BRDF is the sum of its lobes as
//! lamina shades them under a light, binned exactly as the reference bins its paths
//! ([`super::slice`]); beside it, the corrected model's slice error with its lobes reshaped as
//! the walk's are ([`super::slice::Shaping`]), which says how much of that error is shape.

use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

use serde::{Deserialize, Serialize};

use super::slice::{exit_shaped_slice, model_slice};
use super::{simulate, slice_projected_solid_angle, Estimate, Settings, SLICE_BINS};
use crate::error::Result;
use crate::model::fgd::ExactFgd;
use crate::model::oracle::evaluate_model;
use crate::model::transport::Correction;
use crate::model::{tir, LayerParams, NoTir, Tir};
use crate::variant::{Interfaces, Model, VariantKey};

/// Grid side of the exact trapped fraction (`model::tir::trapped_fraction`).
const TIR_GRID: u32 = 128;

/// The TIR correction from the exact trapped fraction (no table).
pub struct ExactTir;

impl Tir for ExactTir {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        tir::trapped_fraction(mu, alpha, eta, TIR_GRID)
    }
}

/// One material's comparison, as a study keeps it (`study.json`).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MaterialReference {
    pub material: String,
    pub model: String,
    pub variant: String,
    /// The reference's interface mode (the truth), and the corrected model's.
    #[serde(default = "single")]
    pub interfaces: String,
    /// Layers in the stack (a coated stack has more than one).
    #[serde(default)]
    pub layers: usize,
    /// A random stack of the study's (`[reference.random]`), its TOML beside it; `None` for a
    /// named material.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub random_stack: Option<String>,
    pub paths: u64,
    pub rows: Vec<ReferenceRow>,
}

fn single() -> String {
    Interfaces::Single.to_string()
}

/// The model and the reference at one view cosine.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ReferenceRow {
    pub cos_theta: f64,
    /// The reference's total reflectance.
    pub reference: Estimate,
    /// Energy of the reference's paths given up (R is short by at most this).
    pub unresolved: [f64; 3],
    /// The model's total reflectance with its TIR correction.
    pub model: [f64; 3],
    /// The same without the TIR correction.
    pub model_no_tir: [f64; 3],
    /// The model with `transport=corrected` (`model::transport`) in the reference's
    /// interface mode.
    #[serde(default)]
    pub model_corrected: [f64; 3],
    /// BRDF per plane-of-incidence bin (`reference::slice_bin`): the reference's…
    pub slice_reference: Vec<Estimate>,
    /// …and the model's…
    pub slice_model: Vec<[f64; 3]>,
    /// …and the corrected model's.
    #[serde(default)]
    pub slice_corrected: Vec<[f64; 3]>,
    /// The corrected model's slice error with the lobes from below the top leaving through it
    /// as the walk's do (`reference::slice::exit_shaped_slice`): how much of it is still the
    /// lobes' shapes.
    #[serde(default)]
    pub slice_exit: f64,
    /// Total transmittance: the reference's, the paper model's and the corrected model's
    /// (zero for a stack that ends in a base).
    #[serde(default)]
    pub transmittance: Estimate,
    #[serde(default)]
    pub transmittance_model: [f64; 3],
    #[serde(default)]
    pub transmittance_corrected: [f64; 3],
}

fn mean3(v: [f64; 3]) -> f64 {
    (v[0] + v[1] + v[2]) / 3.0
}

impl ReferenceRow {
    /// (model − reference) / reference of the channels' mean reflectance.
    pub fn relative_error(&self) -> f64 {
        let r = mean3(self.reference.mean);
        (mean3(self.model) - r) / r
    }

    /// The same for the model without its TIR correction.
    pub fn relative_error_no_tir(&self) -> f64 {
        let r = mean3(self.reference.mean);
        (mean3(self.model_no_tir) - r) / r
    }

    /// The same for the corrected model.
    pub fn relative_error_corrected(&self) -> f64 {
        let r = mean3(self.reference.mean);
        (mean3(self.model_corrected) - r) / r
    }

    /// (model − reference) / reference of the channels' mean transmittance, for the paper's
    /// (`corrected` false) or the corrected model; `None` where the stack transmits less than
    /// 1e-3.
    pub fn transmittance_error(&self, corrected: bool) -> Option<f64> {
        let t = mean3(self.transmittance.mean);
        let model = if corrected {
            self.transmittance_corrected
        } else {
            self.transmittance_model
        };
        (t > 1e-3).then(|| (mean3(model) - t) / t)
    }

    /// The largest of the channels' relative errors of `model` (in magnitude, signed).
    pub fn worst_channel(&self, model: [f64; 3]) -> f64 {
        (0..3)
            .map(|c| (model[c] - self.reference.mean[c]) / self.reference.mean[c].max(1e-12))
            .fold(0.0, |a: f64, e| if e.abs() > a.abs() { e } else { a })
    }

    /// The slice's relative L1 error, Σ |f_model − f_ref| Ω⊥ / Σ f_ref Ω⊥ over the bins
    /// (channels' mean), and the part of it the reference's own noise explains (the expected
    /// |error| of a normal estimate, √(2/π) σ, summed the same way).
    pub fn slice_error(&self) -> (f64, f64) {
        self.slice_error_of(&self.slice_model)
    }

    /// [`Self::slice_error`] of another model's slice (the corrected model's).
    pub fn slice_error_of(&self, slice: &[[f64; 3]]) -> (f64, f64) {
        let (mut diff, mut noise, mut total) = (0.0, 0.0, 0.0);
        for (i, model) in slice.iter().enumerate().take(SLICE_BINS) {
            let omega = slice_projected_solid_angle(i);
            let r = mean3(self.slice_reference[i].mean);
            let se = mean3(self.slice_reference[i].std_error) / 3f64.sqrt();
            diff += (mean3(*model) - r).abs() * omega;
            noise += (2.0 / PI).sqrt() * se * omega;
            total += r * omega;
        }
        if total > 0.0 {
            (diff / total, noise / total)
        } else {
            (0.0, 0.0)
        }
    }
}

/// The model against the reference for one material (`layers`, named `name`) in `variant`'s
/// model with its masking form, at each view cosine, the reference in interface mode
/// `interfaces` following `paths` paths per channel from `seed`; `None` when `stop` was set.
/// The paper's model is the same in both modes; the corrected model takes the reference's.
#[allow(clippy::too_many_arguments)]
pub fn compare(
    name: &str,
    layers: &[LayerParams],
    variant: VariantKey,
    interfaces: Interfaces,
    cosines: &[f64],
    (paths, seed): (u64, u64),
    progress: &mut dyn FnMut(u64),
    stop: &AtomicBool,
) -> Result<Option<MaterialReference>> {
    let settings = Settings {
        paths,
        seed,
        g2: variant.g2,
        interfaces,
        media: variant.model == Model::Tm6,
    };
    let fgd = ExactFgd::new(variant.g2);
    let correction = Correction::new(layers, variant.model, interfaces, &fgd, &ExactTir);
    let mut rows = Vec::with_capacity(cosines.len());
    for (j, &mu) in cosines.iter().enumerate() {
        let before = j as u64 * paths;
        let Some(reference) = simulate(layers, &settings, mu, &mut |p| progress(before + p), stop)?
        else {
            return Ok(None);
        };
        let model = evaluate_model(variant.model, layers, mu, &fgd, &ExactTir);
        let model_no_tir = evaluate_model(variant.model, layers, mu, &fgd, &NoTir);
        let mut corrected = model.clone();
        correction.apply(&mut corrected, mu);
        let mut row = ReferenceRow {
            cos_theta: mu,
            reference: reference.reflectance,
            unresolved: reference.unresolved,
            model: model.reflectance,
            model_no_tir: model_no_tir.reflectance,
            model_corrected: corrected.reflectance,
            slice_reference: reference.slice,
            slice_model: model_slice(&model, mu, variant),
            slice_corrected: model_slice(&corrected, mu, variant),
            transmittance: reference.transmittance,
            transmittance_model: model.transmittance,
            transmittance_corrected: corrected.transmittance,
            slice_exit: 0.0,
        };
        let exit = exit_shaped_slice(&corrected, mu, variant, layers);
        row.slice_exit = row.slice_error_of(&exit).0;
        rows.push(row);
    }
    Ok(Some(MaterialReference {
        material: name.to_owned(),
        model: variant.model.to_string(),
        variant: variant.to_string(),
        interfaces: interfaces.to_string(),
        layers: layers.len(),
        random_stack: None,
        paths,
        rows,
    }))
}
