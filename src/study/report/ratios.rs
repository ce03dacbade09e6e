//! The report's arithmetic and number formats: ratios to a baseline on the study's main basis
//! (JIT instructions per pixel, else per draw, else median time), the talk's agreement, spreads
//! and least-squares lines.

use crate::profile::results::{Results, Run};

/// The basis of a ratio of median times ([`main_ratio`]), which noise makes a target judge
/// within a tolerance.
pub(super) const TIME_BASIS: &str = "median time";

/// A count in millions, or a dash.
pub(super) fn fmt_count(n: Option<u64>) -> String {
    n.map(|n| format!("{:.3} M", n as f64 / 1e6))
        .unwrap_or_else(|| "–".into())
}

/// A ratio as `1.23×`, or a dash.
pub(super) fn fmt_ratio(r: Option<f64>) -> String {
    r.map(|r| format!("{r:.2}×")).unwrap_or_else(|| "–".into())
}

/// `run`'s whole-draw JIT count over `base`'s.
pub(super) fn instructions_ratio(run: &Run, base: Option<&Run>) -> Option<f64> {
    Some(run.instructions? as f64 / base?.instructions? as f64)
}

/// The ggx baseline `run` is divided by: the one on its material, else the study's first.
pub(super) fn baseline_of<'a>(r: &'a Results, run: &Run) -> Option<&'a Run> {
    r.baseline_of(&run.material)
        .or_else(|| r.runs.iter().find(|b| b.is_baseline()))
}

/// `a` over `b` on the study's main basis: JIT instructions per pixel, else per draw, else
/// median time; with the basis's name.
pub(super) fn main_ratio(r: &Results, a: &Run, b: &Run) -> (f64, &'static str) {
    match jit_ratio(a, b) {
        Some(x) => (x, jit_basis(r)),
        None => (a.median_ms / b.median_ms, TIME_BASIS),
    }
}

/// Instructions per pixel to a tenth, or a dash.
pub(super) fn fmt_per_pixel(n: Option<f64>) -> String {
    n.map(|n| format!("{n:.1}")).unwrap_or_else(|| "–".into())
}

/// Whether the study's runs carry instructions per shaded pixel (counted at two sizes).
pub(super) fn per_pixel(r: &Results) -> bool {
    r.runs
        .iter()
        .any(|run| run.instructions_per_pixel.is_some())
}

/// `a`'s JIT instructions over `b`'s: per shaded pixel when both have that figure, else the
/// whole draws' counts.
pub(super) fn jit_ratio(a: &Run, b: &Run) -> Option<f64> {
    match (a.instructions_per_pixel, b.instructions_per_pixel) {
        (Some(x), Some(y)) if y > 0.0 => Some(x / y),
        _ => Some(a.instructions? as f64 / b.instructions? as f64),
    }
}

/// How [`jit_ratio`] compared the study's runs, for prose.
pub(super) fn jit_basis(r: &Results) -> &'static str {
    if per_pixel(r) {
        "JIT instructions per pixel"
    } else {
        "JIT instructions"
    }
}

/// A ratio of ours within this fraction of the talk's agrees with it.
pub(super) const AGREEMENT: f64 = 0.15;
/// A run executing more than this many times the baseline's instructions outside the JIT code
/// is one lavapipe rebuilds at every draw (profiling/README.md).
pub(super) const REBUILD_OVERHEAD: f64 = 3.0;

/// Our ratio against the talk's: agreeing within [`AGREEMENT`], else how far off.
pub(super) fn verdict(ours: Option<f64>, talk: f64) -> String {
    match ours {
        None => "not measured".into(),
        Some(x) if (x / talk - 1.0).abs() <= AGREEMENT => format!("{x:.2}×, agrees"),
        Some(x) => format!("{x:.2}×, {:.2}× the talk's", x / talk),
    }
}

/// Whether the results are lavapipe's (its "GPU" is the CPU).
pub(super) fn is_llvmpipe(r: &Results) -> bool {
    r.device.name.contains("llvmpipe") || r.device.driver.contains("llvmpipe")
}

/// `lo–hi× (median m×)` of a non-empty list of ratios.
pub(super) fn spread(values: &mut [f64]) -> String {
    values.sort_by(f64::total_cmp);
    let (lo, hi) = (values[0], values[values.len() - 1]);
    let median = values[values.len() / 2];
    if (hi - lo).abs() < 0.005 {
        format!("{lo:.2}×")
    } else {
        format!("{lo:.2}–{hi:.2}× (median {median:.2}×)")
    }
}

/// Least-squares line y = a + b·x and its R².
pub fn linear_fit(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = points.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx == 0.0 {
        return None;
    }
    let b = sxy / sxx;
    let r2 = if syy == 0.0 {
        1.0
    } else {
        sxy * sxy / (sxx * syy)
    };
    Some((my - b * mx, b, r2))
}
