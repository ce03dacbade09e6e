//! `lamina tables tir-fit`: the coefficients of `tir=fit` ([`FitTir`]), least-squares fitted
//! to the TIR table's f64 reference, and the Rust source that holds them
//! ([`SOURCE_PATH`]), which the CPU twin reads and the shaders receive through
//! generated/codes.glsl (`TIR_FIT_COEFFICIENTS`).
//!
//! The data are [`trapped_fraction`] (a [`REFERENCE_RESOLUTION`]² midpoint rule: as many
//! samples as the table's texels) at every [`GRID_STEP`]-th vertex of the 64³ table's grid with
//! 0 < η < 1: 22 × 22 × 20 = 9680 points, both ends of μ and α included. The solver is
//! Levenberg–Marquardt on the sum of squared errors (central-difference Jacobian, damping
//! scaled by the normal matrix's diagonal), started from [`START`], the bare geometric form.
//! Everything is CPU f64 with a fixed order of operations, so a machine refits the same bits;
//! a test refits and holds the committed file to it.

use crate::error::{Error, Result};
use crate::model::tir::{trapped_fraction, FitTir, FIT_COEFFICIENTS};
use crate::model::Tir as _;

use super::tir::{ErrorStats, DEFAULT_SIZE};

/// Where the coefficients live, from the repository root.
pub const SOURCE_PATH: &str = "src/model/tir_fit.rs";
/// The fit uses every `GRID_STEP`-th vertex of the table's grid along each axis (63 = 3 · 21,
/// so μ = 1 and α = 1 are among them).
pub const GRID_STEP: u32 = 3;
/// The reference's midpoint rule per point: 32² = 1024 samples, the table's own count.
pub const REFERENCE_RESOLUTION: u32 = 32;
/// The starting coefficients, the bare geometric form: slope scale a/2 ≈ α, no shift, a
/// Lambertian rough limit 1 − η², and a blend weight α²/(1 + α²).
pub const START: [f64; FIT_COEFFICIENTS] = [0.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.25];
/// Iterations before the solver gives up.
const MAX_ITERATIONS: u32 = 500;
/// Converged: an accepted step lowers the squared error by less than this fraction.
const TOLERANCE: f64 = 1e-13;

/// One reference value: (μ, α, η) and the trapped fraction there.
pub type Point = ((f64, f64, f64), f64);

/// The fit and how well it does.
#[derive(Clone, Debug)]
pub struct TirFit {
    pub coefficients: [f64; FIT_COEFFICIENTS],
    /// Levenberg–Marquardt iterations (accepted steps).
    pub iterations: u32,
    /// Against the reference points it was fitted to.
    pub error: ErrorStats,
}

/// The reference points, η slices spread over the available cores (each point is computed
/// alone, so the result does not depend on the split).
pub fn reference_points() -> Vec<Point> {
    let n = DEFAULT_SIZE - 1;
    let at = |i: u32| f64::from(i) / f64::from(n);
    let slices: Vec<u32> = (GRID_STEP..n).step_by(GRID_STEP as usize).collect();
    let slice = |k: u32| -> Vec<Point> {
        let eta = at(k);
        (0..=n)
            .step_by(GRID_STEP as usize)
            .flat_map(|j| {
                (0..=n)
                    .step_by(GRID_STEP as usize)
                    .map(move |i| (at(i), at(j)))
            })
            .map(|(mu, alpha)| {
                let value = trapped_fraction(mu, alpha, eta, REFERENCE_RESOLUTION);
                ((mu, alpha, eta), value)
            })
            .collect()
    };
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|worker| {
                let slices = &slices;
                scope.spawn(move || {
                    slices
                        .iter()
                        .skip(worker)
                        .step_by(threads)
                        .map(|&k| (k, slice(k)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        let mut done: Vec<(u32, Vec<Point>)> = workers
            .into_iter()
            .flat_map(|w| w.join().expect("a reference worker does not panic"))
            .collect();
        done.sort_by_key(|(k, _)| *k);
        done.into_iter().flat_map(|(_, points)| points).collect()
    })
}

/// Fits the coefficients to [`reference_points`].
pub fn fit() -> Result<TirFit> {
    fit_points(&reference_points())
}

/// Fits the coefficients to `points`.
pub fn fit_points(points: &[Point]) -> Result<TirFit> {
    let model = |c: &[f64; FIT_COEFFICIENTS], (mu, alpha, eta): (f64, f64, f64)| {
        FitTir(*c).tir(mu, alpha, eta)
    };
    let (coefficients, iterations) = levenberg_marquardt(points, START, model)?;
    let error = ErrorStats::of(&FitTir(coefficients), points.iter().copied())
        .ok_or_else(|| Error::Unsupported("a TIR fit needs reference points".into()))?;
    Ok(TirFit {
        coefficients,
        iterations,
        error,
    })
}

/// Minimises Σ (model(c, x) − y)² over the points (x, y) from `start`; returns the
/// coefficients and the accepted steps.
fn levenberg_marquardt<const N: usize>(
    points: &[Point],
    start: [f64; N],
    model: impl Fn(&[f64; N], (f64, f64, f64)) -> f64,
) -> Result<([f64; N], u32)> {
    let squared_error =
        |c: &[f64; N]| -> f64 { points.iter().map(|&(x, y)| (model(c, x) - y).powi(2)).sum() };
    let mut c = start;
    let mut error = squared_error(&c);
    let mut damping = 1e-3;
    for iteration in 0..MAX_ITERATIONS {
        // The normal equations JᵀJ δ = Jᵀr, J by central differences.
        let mut normal = [[0.0; N]; N];
        let mut gradient = [0.0; N];
        for &(x, y) in points {
            let residual = y - model(&c, x);
            let mut row = [0.0; N];
            for (k, slot) in row.iter_mut().enumerate() {
                let h = 1e-6 * c[k].abs().max(1.0);
                let (mut up, mut down) = (c, c);
                up[k] += h;
                down[k] -= h;
                *slot = (model(&up, x) - model(&down, x)) / (2.0 * h);
            }
            for r in 0..N {
                gradient[r] += row[r] * residual;
                for s in 0..N {
                    normal[r][s] += row[r] * row[s];
                }
            }
        }
        // Raise the damping until a step lowers the error; none does at the minimum.
        loop {
            let mut damped = normal;
            for (k, row) in damped.iter_mut().enumerate() {
                row[k] += damping * normal[k][k].max(1e-12);
            }
            if let Some(step) = solve(damped, gradient) {
                let mut trial = c;
                for (t, s) in trial.iter_mut().zip(step) {
                    *t += s;
                }
                let trial_error = squared_error(&trial);
                if trial_error < error {
                    let gain = (error - trial_error) / error;
                    c = trial;
                    error = trial_error;
                    damping = (damping * 0.3).max(1e-12);
                    if gain < TOLERANCE {
                        return Ok((c, iteration + 1));
                    }
                    break;
                }
            }
            damping *= 10.0;
            if damping > 1e16 {
                return Ok((c, iteration));
            }
        }
    }
    Err(Error::Unsupported(format!(
        "the TIR fit did not converge in {MAX_ITERATIONS} iterations"
    )))
}

/// Solves `a x = b` by Gaussian elimination with partial pivoting; `None` when `a` is
/// singular.
pub(super) fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let pivot = (col..N).max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = a[col];
        for row in col + 1..N {
            let f = a[row][col] / pivot_row[col];
            for (x, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let rest: f64 = (row + 1..N).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - rest) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The text of [`SOURCE_PATH`] holding `coefficients` (rustfmt's layout; `{:?}` prints each
/// f64 so that it reads back to the same bits).
pub fn source_text(coefficients: &[f64; FIT_COEFFICIENTS]) -> String {
    let mut out = String::from(
        "//! The coefficients of `tir=fit` ([`super::tir::FitTir`]; `TIR_FIT_COEFFICIENTS` in the\n\
         //! shaders' generated/codes.glsl), written by `lamina tables tir-fit --out src/model/tir_fit.rs`\n\
         //! from its least-squares fit to the TIR table's f64 reference (src/tables/tir_fit.rs). Do not\n\
         //! edit: rerun the command. A test refits and fails when they differ.\n\
         \n\
         /// c0 … c6 of [`super::tir::FitTir`].\n",
    );
    out.push_str(&format!(
        "pub const COEFFICIENTS: [f64; {FIT_COEFFICIENTS}] = [\n"
    ));
    for c in coefficients {
        out.push_str(&format!("    {c:?},\n"));
    }
    out.push_str("];\n");
    out
}

/// The largest difference between two sets of coefficients, relative to each (at least 1).
pub fn largest_difference(a: &[f64; FIT_COEFFICIENTS], b: &[f64; FIT_COEFFICIENTS]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / x.abs().max(1.0))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use std::sync::OnceLock;

    use super::*;
    use crate::model::tir_fit::COEFFICIENTS;

    /// The refit, once for the module's tests (about a second in a debug build).
    fn refit() -> &'static (Vec<Point>, TirFit) {
        static FIT: OnceLock<(Vec<Point>, TirFit)> = OnceLock::new();
        FIT.get_or_init(|| {
            let points = reference_points();
            let fit = fit_points(&points).unwrap();
            (points, fit)
        })
    }

    #[test]
    fn the_committed_coefficients_are_what_the_fit_gives() {
        let (_, fit) = refit();
        // Bit-equal on one machine; the margin leaves room for another libm's last bits.
        let difference = largest_difference(&fit.coefficients, &COEFFICIENTS);
        assert!(
            difference < 1e-7,
            "{SOURCE_PATH} is stale (relative difference {difference:.2e}): run \
             `lamina tables tir-fit --out {SOURCE_PATH}`\nrefit: {:?}\ncommitted: {COEFFICIENTS:?}",
            fit.coefficients
        );
        let committed = include_str!("../model/tir_fit.rs");
        assert_eq!(
            committed,
            source_text(&COEFFICIENTS),
            "{SOURCE_PATH} is not the command's output"
        );
    }

    #[test]
    fn the_fit_is_within_the_error_budget_over_the_domain() {
        let (points, fit) = refit();
        assert_eq!(points.len(), 22 * 22 * 20);
        let committed = ErrorStats::of(&FitTir(COEFFICIENTS), points.iter().copied()).unwrap();
        println!(
            "tir=fit against the f64 reference: MSE {:.2e}, max |Δ| {:.3} at {:?}, {} iterations",
            committed.mse, committed.max_abs, committed.worst_at, fit.iterations
        );
        assert!(committed.mse <= 0.005, "MSE {}", committed.mse);
        // The start is the bare geometric form: the fit must improve on it.
        let start = ErrorStats::of(&FitTir(START), points.iter().copied()).unwrap();
        assert!(
            committed.mse < 0.5 * start.mse,
            "{committed:?} vs {start:?}"
        );
    }

    #[test]
    fn the_solver_recovers_known_coefficients() {
        // Points made by the form itself: the fit returns their coefficients.
        let truth = [0.4, -0.1, -0.02, 0.35, 0.8, 0.25, 3.0];
        let points: Vec<Point> = (0..=10)
            .flat_map(|i| (0..=10).flat_map(move |j| (1..10).map(move |k| (i, j, k))))
            .map(|(i, j, k)| {
                let x = (
                    f64::from(i) / 10.0,
                    f64::from(j) / 10.0,
                    f64::from(k) / 10.0,
                );
                (x, FitTir(truth).tir(x.0, x.1, x.2))
            })
            .collect();
        let fit = fit_points(&points).unwrap();
        assert!(
            largest_difference(&truth, &fit.coefficients) < 1e-5,
            "{:?}",
            fit.coefficients
        );
        assert!(fit.error.max_abs < 1e-8, "{:?}", fit.error);
    }

    #[test]
    fn solve_inverts_and_refuses_singular_systems() {
        let x = solve([[2.0, 1.0], [1.0, 3.0]], [3.0, 5.0]).unwrap();
        assert!(
            (x[0] - 0.8).abs() < 1e-12 && (x[1] - 1.4).abs() < 1e-12,
            "{x:?}"
        );
        assert!(solve([[1.0, 2.0], [2.0, 4.0]], [1.0, 2.0]).is_none());
    }
}
