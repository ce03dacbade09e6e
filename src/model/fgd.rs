//! FGD providers on the CPU. [`ExactFgd`] integrates the directional albedo numerically — the
//! oracle. The GPU's own tables implement [`Fgd`](super::Fgd) where they are built
//! (`tables::split_sum::SplitSumTable` for `fgd=karis`), so the model can run on the CPU with
//! exactly what the shader samples.

use super::{fresnel, microfacet, Fgd};
use crate::variant::G2;

/// FGD(μ, α, η, κ) = ∫ F(ω_i·h; η, κ) D(h) G2(ω_i, ω_o) / (4μ) dω_o by a midpoint rule over
/// the two uniform variables of visible-normal sampling (Heitz 2018): h ~ D_v(ω_i, h), whose
/// pdf carries the 1/μ, so the integrand F·G2/G1 is bounded by 1 even at grazing incidence
/// (a rule over D(h) cos θ_h, ALGORITHMS.md §6.1's, is still 1e-3 off at 4096² there).
/// α below 1e-4 is a smooth interface and gives the exact Fresnel F(μ). `resolution`²
/// points: the default 512² agrees with ALGORITHMS.md §12.5 to 1e-3; the error left is the
/// step of F at the critical angle (η < 1) cutting through the grid.
pub struct ExactFgd {
    pub g2: G2,
    pub resolution: u32,
}

impl ExactFgd {
    pub fn new(g2: G2) -> Self {
        Self {
            g2,
            resolution: 512,
        }
    }
}

impl Fgd for ExactFgd {
    fn fgd(&self, mu: f64, alpha: f64, eta: f64, kappa: f64) -> f64 {
        let mu = mu.clamp(1e-4, 1.0);
        if alpha < 1e-4 {
            return fresnel::conductor(mu, eta, kappa);
        }
        let g1 = microfacet::masking_g1(self.g2, mu, alpha);
        let n = self.resolution;
        let mut sum = 0.0;
        microfacet::for_each_vndf_sample(mu, alpha, n, |wi, h, wo| {
            let f = fresnel::conductor(wi.dot(h).clamp(0.0, 1.0), eta, kappa);
            sum += f * microfacet::masking_shadowing(self.g2, mu, wo.z, alpha) / g1;
        });
        sum / f64::from(n * n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ALGORITHMS.md §12.5, separable Smith G2, at α = 0.1, 0.3, 0.6 and μ = 1, 0.5, 0.2.
    #[test]
    fn matches_published_fgd_values() {
        let fgd = ExactFgd::new(G2::Smith);
        let cases: [(f64, f64, [f64; 9]); 4] = [
            (
                1.5,
                0.0,
                [
                    0.0396, 0.0859, 0.2356, 0.0356, 0.0606, 0.1114, 0.0243, 0.0367, 0.0584,
                ],
            ),
            (
                1.0 / 1.5,
                0.0,
                [
                    0.0425, 0.9402, 0.8831, 0.0487, 0.6505, 0.7020, 0.0425, 0.3455, 0.4737,
                ],
            ),
            (
                0.143245,
                3.98479,
                [
                    0.9554, 0.9327, 0.8680, 0.8480, 0.7885, 0.7852, 0.5717, 0.6028, 0.6688,
                ],
            ),
            (
                1.43919,
                1.60434,
                [
                    0.3210, 0.3590, 0.4516, 0.2855, 0.2920, 0.3310, 0.1929, 0.2143, 0.2524,
                ],
            ),
        ];
        for (eta, kappa, values) in cases {
            for (k, want) in values.iter().enumerate() {
                let alpha = [0.1, 0.3, 0.6][k / 3];
                let mu = [1.0, 0.5, 0.2][k % 3];
                let got = fgd.fgd(mu, alpha, eta, kappa);
                assert!(
                    (got - want).abs() < 1e-3,
                    "η {eta} κ {kappa} α {alpha} μ {mu}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn smooth_limit_is_fresnel() {
        let fgd = ExactFgd::new(G2::HeightCorrelated);
        for mu in [0.1, 0.5, 1.0] {
            assert_eq!(fgd.fgd(mu, 0.0, 1.5, 0.0), fresnel::dielectric(mu, 1.5));
            let rough = fgd.fgd(mu, 2e-3, 1.5, 0.0);
            assert!(
                (rough - fresnel::dielectric(mu, 1.5)).abs() < 2e-3,
                "{mu}: {rough}"
            );
        }
    }
}
