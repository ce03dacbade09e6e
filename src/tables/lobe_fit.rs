//! Where `ibl=matched` places its one fetch: the lean and the roughness of the matched cube's
//! kernel that come closest to a GGX lobe in L², stored beside the lobe's moments
//! ([`lobe_moments`](super::lobe_moments)).
//!
//! A fetch of the matched cube at direction d and mip α′ averages the environment under the
//! cube's kernel K: the normal-view lobe of α′ about d, D(h)/4 · G2 at a normal view,
//! normalised over the hemisphere about d. The lobe it stands for has the density
//! p(l) = D(h) G2(v, l) / (4 μ_v E) over the upper hemisphere (E: its albedo, so that p
//! integrates to 1). Under a point light of unit power at a random direction ω the fetch's
//! error is K(ω) − p(ω), and its mean square over ω is ∫(K − p)², which this fit minimises
//! over d's lean from the mirror direction towards the normal and over α′:
//! ∫K² − 2 ∫K p (∫p² does not depend on the fetch). A kernel that crosses the horizon pays
//! for it, since p is 0 there. The moments (mean direction, resultant length) fit a smooth
//! environment; this fit, small bright lamps, where a blurred fetch reads a lamp through
//! tails the lobe does not have. It leans less and is sharper: at μ = 0.3, α = 0.2, w 0.09
//! and α′ 0.12 against the moments' 0.27 and 0.19.
//!
//! ∫K² is a 1-D quadrature per α′ ([`Kernels`]); ∫K p is the mean of p over the kernel's
//! own samples (a product rule over GGX's sampler at a normal view, its radial variable
//! warped towards the tail as in `lobe_moments`), with p in closed form, so a kernel
//! sharper than the grid stays well posed. The search: a coarse grid over (lean, √α′), then
//! [`REFINEMENTS`] refinements around the best point.
//!
//! `ibl=lamps` places its one fetch of the rest of the map with [`polynomial`], two small
//! polynomials in (√μ, √α) least-squares fitted on the grid [`POLYNOMIAL_GRID`] (the test
//! `the_polynomial_is_the_least_squares_fit_on_its_grid` refits them and prints the refit):
//! the lean of the lobe's mean direction (`lobe_moments::mean_lean`: the rest is the map
//! without its lamps, a smooth environment, which the moments fit) and the mip of this fit
//! (which reads sharper than the moments' spread, what helps under a sky); a few arithmetic
//! operations where the table's lookup is a texture fetch.

use glam::DVec3;

use crate::model::microfacet::{ggx_d, reflect, sample_vndf, smith_lambda};
use crate::shader::interface::{LAMPS_LEAN_COEFFICIENTS, LAMPS_ROOT_COEFFICIENTS};

/// Points of the kernel's 1-D quadrature of ∫K².
const KERNEL_POINTS: u32 = 2048;

/// √α′ samples of the kernel's statistics, uniform on [0, 1].
const KERNEL_SAMPLES: usize = 512;

/// Side of the grid over the kernel's sampler on which ∫K p is taken.
const KERNEL_GRID: u32 = 32;

/// Side of the visible-normal grid on which the lobe's albedo is taken.
const ALBEDO_GRID: u32 = 48;

/// Refinements of the search around its best point, each 2.5 times finer.
const REFINEMENTS: u32 = 6;

/// The smallest √α′ the search tries (α′ 1e-4, the models' smallest α).
const MIN_ROOT: f64 = 0.01;

/// The radial variable of a GGX sampler, warped towards the tail: u₁ = 1 − (1 − s)³ for s on
/// a midpoint grid of `n`, with the warp's Jacobian.
pub(super) fn warped(k: u32, n: u32) -> (f64, f64) {
    let s = (f64::from(k) + 0.5) / f64::from(n);
    (1.0 - (1.0 - s).powi(3), 3.0 * (1.0 - s) * (1.0 - s))
}

/// ∫K² of the normalised kernel times α′² (which takes out its 1/α′² growth, leaving a
/// smooth function), per √α′ uniform on [0, 1] (index 0 holds the first positive sample's).
pub struct Kernels(Vec<f64>);

impl Default for Kernels {
    fn default() -> Self {
        Self(
            (0..KERNEL_SAMPLES)
                .map(|k| {
                    let root = k.max(1) as f64 / (KERNEL_SAMPLES - 1) as f64;
                    kernel_square(root * root) * root.powi(4)
                })
                .collect(),
        )
    }
}

impl Kernels {
    /// ∫K² at √α′ = `root` (at least the first positive sample), interpolated linearly.
    fn square(&self, root: f64) -> f64 {
        let last = (KERNEL_SAMPLES - 1) as f64;
        let x = root.clamp(1.0 / last, 1.0) * last;
        let k = (x.floor() as usize).min(KERNEL_SAMPLES - 2);
        let t = x - k as f64;
        let scaled = self.0[k] + (self.0[k + 1] - self.0[k]) * t;
        scaled / (x / last).powi(4)
    }
}

/// ∫K² of the kernel of roughness α: under GGX's sampler at a normal view l has the density
/// D/4, so with the weight g = G2 at a normal view, Z = E[g] and ∫K² = E[D/4 · g²]/Z².
fn kernel_square(alpha: f64) -> f64 {
    let (mut z, mut square, mut total) = (0.0, 0.0, 0.0);
    for k in 0..KERNEL_POINTS {
        let (u, jacobian) = warped(k, KERNEL_POINTS);
        total += jacobian;
        let tan2 = alpha * alpha * u / (1.0 - u);
        let cos_h = 1.0 / (1.0 + tan2).sqrt();
        let cos_l = 2.0 * cos_h * cos_h - 1.0;
        if cos_l <= 0.0 {
            continue;
        }
        let g = 1.0 / (1.0 + smith_lambda(cos_l, alpha));
        z += jacobian * g;
        square += jacobian * ggx_d(cos_h, alpha) / 4.0 * g * g;
    }
    (square / total) / (z / total).powi(2)
}

/// The lobe's albedo at view `v`: the mean of G2/G1 over its visible normals.
fn albedo(v: DVec3, alpha: f64) -> f64 {
    let masked = 1.0 + smith_lambda(v.z, alpha);
    let (mut sum, mut total) = (0.0, 0.0);
    for a in 0..ALBEDO_GRID {
        let (u1, jacobian) = warped(a, ALBEDO_GRID);
        for b in 0..ALBEDO_GRID {
            let u2 = (f64::from(b) + 0.5) / f64::from(ALBEDO_GRID);
            let l = reflect(v, sample_vndf(v, (u1, u2), alpha));
            if l.z > 0.0 {
                sum += jacobian * masked / (masked + smith_lambda(l.z, alpha));
            }
            total += jacobian;
        }
    }
    sum / total
}

/// The grid the polynomial is fitted on: √μ and √α each at `n` points uniform on `[lo, hi]`,
/// where `ibl=lamps` reads its mip from it (above α ≈ 0.08, its mip 2: below, the split sum's
/// mip of α is at most 2 and the fetch never reads sharper than that) and the lean changes the
/// fetch (away from the normal view).
pub const POLYNOMIAL_GRID: [(f64, f64, u32); 2] = [(0.1, 0.9, 9), (0.25, 0.85, 9)];

/// The terms of the lean's and √α′'s polynomials at (√μ, √α), before their factor √α.
fn polynomial_terms(s: f64, r: f64) -> ([f64; 6], [f64; 6]) {
    (
        [1.0, r, s, s * r, s * s, r * r],
        [1.0, r, s, s * r, s * s, s * s * r],
    )
}

/// The polynomials that `ibl=lamps` evaluates (lib/ibl.glsl's ibl_lobe_fit_polynomial): the
/// lean w of the lobe's mean direction and [`fit`]'s √α′, each clamped to [0, 1].
pub fn polynomial(mu: f64, alpha: f64) -> (f64, f64) {
    let (s, r) = (mu.clamp(0.0, 1.0).sqrt(), alpha.clamp(0.0, 1.0).sqrt());
    let (lean, root) = polynomial_terms(s, r);
    let dot = |c: &[f64; 6], t: &[f64; 6]| c.iter().zip(t).map(|(c, t)| c * t).sum::<f64>();
    (
        (r * dot(&LAMPS_LEAN_COEFFICIENTS, &lean)).clamp(0.0, 1.0),
        (r * dot(&LAMPS_ROOT_COEFFICIENTS, &root)).clamp(0.0, 1.0),
    )
}

/// The fetch closest in L² to the lobe of roughness `alpha` at view cosine `mu`: the weight w
/// of normalize(mix(R, N, w)) and √α′.
pub fn fit(mu: f64, alpha: f64, kernels: &Kernels) -> (f64, f64) {
    let v = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let scale = 1.0 / (4.0 * mu * albedo(v, alpha));
    let lambda_v = smith_lambda(mu, alpha);
    let density = |l: DVec3| {
        if l.z <= 0.0 {
            return 0.0;
        }
        let h = (l + v).normalize();
        ggx_d(h.z.max(0.0), alpha) / (1.0 + lambda_v + smith_lambda(l.z, alpha)) * scale
    };
    let theta = mu.acos();
    // The mean squared error, less ∫p², of the kernel √α′ = `root` leaning `t`·θ from R.
    let error = |t: f64, root: f64| {
        let square = kernels.square(root);
        let kernel_alpha = root * root;
        let angle = (t - 1.0) * theta;
        let d = DVec3::new(angle.sin(), 0.0, angle.cos());
        let across = DVec3::Y;
        let along = across.cross(d);
        let (mut sum, mut total) = (0.0, 0.0);
        for a in 0..KERNEL_GRID {
            let (u, jacobian) = warped(a, KERNEL_GRID);
            let tan2 = kernel_alpha * kernel_alpha * u / (1.0 - u);
            let cos_h = 1.0 / (1.0 + tan2).sqrt();
            let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
            for b in 0..KERNEL_GRID {
                let phi = std::f64::consts::TAU * (f64::from(b) + 0.5) / f64::from(KERNEL_GRID);
                let h = d * cos_h + (along * phi.cos() + across * phi.sin()) * sin_h;
                let l = reflect(d, h);
                let cos_l = l.dot(d);
                if cos_l <= 0.0 {
                    continue;
                }
                let g = jacobian / (1.0 + smith_lambda(cos_l, kernel_alpha));
                sum += g * density(l);
                total += g;
            }
        }
        square - 2.0 * sum / total.max(1e-300)
    };
    let consider = |best: &mut (f64, f64, f64), t: f64, root: f64| {
        let (t, root) = (t.clamp(0.0, 1.0), root.clamp(MIN_ROOT, 1.0));
        let e = error(t, root);
        if e < best.0 {
            *best = (e, t, root);
        }
    };
    let mut best = (f64::INFINITY, 0.0, alpha.sqrt().max(MIN_ROOT));
    for i in 0..=8 {
        for j in 1..=12 {
            consider(&mut best, f64::from(i) / 8.0, f64::from(j) / 12.0);
        }
    }
    let mut step = (1.0 / 8.0, 1.0 / 12.0);
    for _ in 0..REFINEMENTS {
        let (_, t, root) = best;
        for i in -2..=2 {
            for j in -2..=2 {
                let (dt, dr) = (f64::from(i) * step.0 / 2.0, f64::from(j) * step.1 / 2.0);
                consider(&mut best, t + dt, root + dr);
            }
        }
        step = (step.0 / 2.5, step.1 / 2.5);
    }
    let (_, t, root) = best;
    (super::lobe_moments::mix_weight(theta, t * theta), root)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Least squares of `y ≈ Σ c_k x_k` by the normal equations, solved as the TIR fit's are.
    fn least_squares(rows: &[([f64; 6], f64)]) -> [f64; 6] {
        let (mut a, mut b) = ([[0.0f64; 6]; 6], [0.0f64; 6]);
        for (x, y) in rows {
            for i in 0..6 {
                for j in 0..6 {
                    a[i][j] += x[i] * x[j];
                }
                b[i] += x[i] * y;
            }
        }
        super::super::tir_fit::solve(a, b).expect("the grid's normal equations are regular")
    }

    #[test]
    fn the_polynomial_is_the_least_squares_fit_on_its_grid() {
        let kernels = Kernels::default();
        let [(s_lo, s_hi, s_n), (r_lo, r_hi, r_n)] = POLYNOMIAL_GRID;
        let at =
            |lo: f64, hi: f64, n: u32, k: u32| lo + (hi - lo) * f64::from(k) / f64::from(n - 1);
        let mut points = Vec::new();
        for i in 0..s_n {
            for j in 0..r_n {
                let (s, r) = (at(s_lo, s_hi, s_n, i), at(r_lo, r_hi, r_n, j));
                let (mu, alpha) = (s * s, r * r);
                let m = super::super::lobe_moments::mean_direction(mu, alpha);
                let mean = super::super::lobe_moments::mean_lean(mu, m);
                points.push((s, r, (mean, fit(mu, alpha, &kernels).1)));
            }
        }
        let rows = |root: bool| -> Vec<([f64; 6], f64)> {
            points
                .iter()
                .map(|&(s, r, (w, root_alpha))| {
                    let (lean, spread) = polynomial_terms(s, r);
                    if root {
                        (spread.map(|t| t * r), root_alpha)
                    } else {
                        (lean.map(|t| t * r), w)
                    }
                })
                .collect()
        };
        let (lean, root) = (least_squares(&rows(false)), least_squares(&rows(true)));
        println!("lean {lean:?}\nroot {root:?}");
        for (committed, refit) in [
            (LAMPS_LEAN_COEFFICIENTS, lean),
            (LAMPS_ROOT_COEFFICIENTS, root),
        ] {
            for (c, f) in committed.iter().zip(refit) {
                assert!(
                    (c - f).abs() < 1e-6,
                    "committed {committed:?}, refit {refit:?}"
                );
            }
        }
        // How close the polynomial comes to the fit it stands for: the lean within 0.05, and
        // √α′ within one of the lamps' cube's levels at eight mips (1/7 in √α: the fit's own
        // search steps through √α′ of 0.6, 0.7, 0.95 and 1 on the roughest lobes).
        let (mut lean_error, mut root_error) = (0.0f64, 0.0f64);
        for &(s, r, (w, root_alpha)) in &points {
            let (pw, proot) = polynomial(s * s, r * r);
            lean_error = lean_error.max((pw - w).abs());
            root_error = root_error.max((proot - root_alpha).abs());
        }
        println!("largest error: lean {lean_error:.4}, √α′ {root_error:.4}");
        assert!(lean_error < 0.05, "lean {lean_error}");
        assert!(root_error < 1.0 / 7.0, "√α′ {root_error}");
    }

    #[test]
    fn a_normal_view_is_fitted_by_the_cubes_own_lobe() {
        let kernels = Kernels::default();
        for alpha in [0.001, 0.004, 0.05, 0.2, 0.5] {
            let (w, root) = fit(1.0, alpha, &kernels);
            assert!(w < 1e-9, "{alpha}: w {w}");
            assert!(
                (root * root / alpha - 1.0).abs() < 0.05,
                "{alpha}: α′ {}",
                root * root
            );
        }
    }

    #[test]
    fn a_grazing_lobe_is_fitted_sharper_and_leaning_less_than_its_moments_say() {
        let kernels = Kernels::default();
        let spread = super::super::lobe_moments::spread_samples();
        let (mu, alpha) = (0.3f64, 0.2);
        let m = super::super::lobe_moments::mean_direction(mu, alpha);
        let moments_w = super::super::lobe_moments::mean_lean(mu, m);
        let moments_root = super::super::lobe_moments::matched_root_alpha(&spread, m.length());
        let (w, root) = fit(mu, alpha, &kernels);
        println!(
            "μ {mu}, α {alpha}: fit w {w:.3}, α′ {:.3}; moments w {moments_w:.3}, α′ {:.3}",
            root * root,
            moments_root * moments_root
        );
        assert!(w > 0.0 && w < 0.5 * moments_w, "w {w} against {moments_w}");
        assert!(
            root < 0.9 * moments_root,
            "√α′ {root} against {moments_root}"
        );
        // Leaning grows as the view grazes.
        let leans = [0.9, 0.5, 0.2].map(|mu| fit(mu, alpha, &kernels).0);
        assert!(leans.windows(2).all(|p| p[1] > p[0]), "{leans:?}");
    }
}
