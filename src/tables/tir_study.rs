//! What `lamina tables tir` measures on the TIR table: its value range, a spot check against
//! the f64 reference, the gap `tir=lut16` adds by rounding to half floats, the talk's study of
//! the analytic estimator against the table (issue #6), the same study of `tir=fit`, and those
//! errors as heat-map panels. The command prints [`TirStudy`] and draws [`error_panels`]; the
//! numbers land in profiling/TABLES.md.

use std::path::Path;

use half::f16;

use crate::error::Result;
use crate::gpu::Gpu;
use crate::model::tir::{AnalyticTir, FitTir};
use crate::model::tir_fit::COEFFICIENTS;
use crate::model::Tir;
use crate::stats::MinMeanMax;

use super::tir::{self, ErrorStats, TirTable};
use crate::cache;

/// The numbers `lamina tables tir` prints about a table.
#[derive(Clone, Copy, Debug)]
pub struct TirStudy {
    /// Over every texel.
    pub values: MinMeanMax,
    /// Largest |texel − f64 reference| at the spot points ([`super::spot::tir`]).
    pub spot_max_abs: f64,
    /// Largest |half(v) − v| over the texels: what `lut16` loses against `lut32`.
    pub lut16_gap: f64,
    /// The analytic estimator against the table, 0 < η < 1.
    pub analytic: ErrorStats,
    /// `tir=fit` against the table, 0 < η < 1.
    pub fit: ErrorStats,
}

impl TirStudy {
    /// The study of a table of at least 3 texels per axis ([`tir::error_against`]).
    pub fn of(table: &TirTable) -> Self {
        let values =
            MinMeanMax::of(table.texels.iter().map(|&v| f64::from(v))).expect("a table has texels");
        let lut16_gap = table
            .texels
            .iter()
            .map(|&v| (f64::from(f16::from_f32(v).to_f32()) - f64::from(v)).abs())
            .fold(0.0f64, f64::max);
        Self {
            values,
            spot_max_abs: super::spot::tir(table),
            lut16_gap,
            analytic: tir::error_against(table, &AnalyticTir),
            fit: tir::error_against(table, &FitTir(COEFFICIENTS)),
        }
    }
}

/// The η of the error map's panels (each panel takes the grid slice nearest).
pub const PANEL_ETAS: [f64; 4] = [0.3, 0.5, 0.7, 0.9];

/// |`estimate` − table| over (μ, α) at the η slices nearest [`PANEL_ETAS`]: one (label, rows)
/// panel each, rows over α and columns over μ.
pub fn error_panels(table: &TirTable, estimate: &dyn Tir) -> Vec<(String, Vec<Vec<f64>>)> {
    let size = table.size;
    PANEL_ETAS
        .iter()
        .map(|&eta| {
            let k = (eta * f64::from(size - 1)).round() as u32;
            let (_, _, eta_k) = table.coordinates(0, 0, k);
            let values = (0..size)
                .map(|j| {
                    (0..size)
                        .map(|i| {
                            let (mu, alpha, eta) = table.coordinates(i, j, k);
                            let e = estimate.tir(mu, alpha, eta);
                            (e - f64::from(table.texel(i, j, k))).abs()
                        })
                        .collect()
                })
                .collect();
            (format!("η = {eta_k:.3}"), values)
        })
        .collect()
}

/// The table as `lamina tables tir` asks for it: with `rebuild`, built on the GPU and stored
/// in `cache_dir` (`false`: not from the cache); otherwise [`TirTable::load_or_build`].
pub fn load(
    gpu: &Gpu,
    size: u32,
    samples: u32,
    cache_dir: Option<&Path>,
    rebuild: bool,
    progress: impl FnMut(u32, u32),
) -> Result<(TirTable, bool)> {
    if !rebuild {
        return TirTable::load_or_build(gpu, size, samples, cache_dir, progress);
    }
    let table = TirTable::build(gpu, size, samples, progress)?;
    if let Some(dir) = cache_dir {
        cache::store(dir, &tir::cache_key(size, samples), &table.texels)?;
    }
    Ok((table, false))
}
