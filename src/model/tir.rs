//! The TIR modes without a table, in f64: the twins of `tir=constant`, `tir=analytic` and
//! `tir=fit` in glsl/include/lib/tir.glsl (the table modes' twin is `tables::tir::TableTir`),
//! and the exact trapped fraction the table holds ([`trapped_fraction`], its reference).

use super::{hg, microfacet, Tir};
use crate::variant::G2;

/// `tir=constant`: the talk's dummy constant in place of the table fetch.
pub struct ConstantTir(pub f64);

/// The value glsl/include/lib/tir.glsl uses (`TIR_CONSTANT_FRACTION`).
pub const CONSTANT_FRACTION: f64 = 0.1;

impl Tir for ConstantTir {
    fn tir(&self, _mu: f64, _alpha: f64, _eta: f64) -> f64 {
        self.0
    }
}

/// `tir=analytic`: the talk's naive estimator (ALGORITHMS.md §9.2), as the port wrote it, with
/// the exit factor (1 − F(wo.z, η_10)) taken for an exit into air (factor 1; exact at the top
/// interface), the GLSL's one deviation, kept identical here.
pub struct AnalyticTir;

fn fresnel_dielectric(c: f64, eta: f64) -> f64 {
    let ct2 = 1.0 - (1.0 - c * c) / (eta * eta);
    if ct2 <= 0.0 {
        return 1.0;
    }
    let ct = ct2.sqrt();
    let rs = (c - eta * ct) / (c + eta * ct);
    let rp = (eta * c - ct) / (eta * c + ct);
    0.5 * (rs * rs + rp * rp)
}

impl Tir for AnalyticTir {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        let s = (0.25 * std::f64::consts::PI * (1.0 + mu)).sin();
        let wo = [s, 0.0, (1.0 - s * s).max(0.0).sqrt()];
        let a = alpha.max(0.01);
        let l = (39.4115 - 39.0029 * a).ln();
        let f = (1.0 - mu).powf(10.8649) * (1.0 - 0.298475 * l) + 0.298475 * l;
        let m = [f * wo[0], 0.0, 1.0 + (wo[2] - 1.0) * f];
        let wo_m = wo[0] * m[0] + wo[2] * m[2];
        let ws_z = 2.0 * wo_m * m[2] - wo[2];
        if ws_z > 0.0 {
            return 0.0;
        }
        let c = ws_z.abs();
        let lambda = 0.5 * (-1.0 + (1.0 + a * a * (1.0 - c * c) / (c * c).max(1e-8)).sqrt());
        let g1 = 1.0 / (1.0 + lambda);
        fresnel_dielectric(wo_m.clamp(0.0, 1.0), eta) * g1
    }
}

/// How many coefficients [`FitTir`] has.
pub const FIT_COEFFICIENTS: usize = 7;

/// The floor of [`FitTir`]'s slope scale: it keeps the smooth limit (α = 0) a steep but
/// continuous step, so f32 and f64 agree next to the critical angle, and the form finite at
/// μ = 0, η = 1 (the shaders' `TIR_FIT_MIN_SCALE`).
pub const FIT_MIN_SCALE: f64 = 1e-3;

/// [`FitTir`]'s roughness variable x = (2α)^1.3, α clamped to [`hg::MIN_ALPHA`]…1 as
/// [`hg::alpha_of_g`] clamps it. It is [`hg::alpha_power_of_g`] of the lobe's g (one division),
/// where α costs a pow, so the shader's `tir=fit` takes g; the shaders' `TIR_FIT_X_MIN` and
/// `TIR_FIT_X_MAX` are this at α = 0 and 1.
pub fn fit_roughness(alpha: f64) -> f64 {
    (2.0 * alpha.clamp(hg::MIN_ALPHA, 1.0)).powf(1.3)
}

/// `tir=fit`: a closed form of [`trapped_fraction`] whose coefficients c0 … c6 `lamina tables
/// tir-fit` fits to it (src/tables/tir_fit.rs) and writes to [`super::tir_fit::COEFFICIENTS`],
/// which the shader's `tir_fit` reads too (`TIR_FIT_COEFFICIENTS`, generated/codes.glsl).
///
/// The shape is the lobe's geometry in the plane of incidence. A facet of slope m reflects the
/// lobe's centre (incidence θ_i) to θ_i + 2 atan m, which stays inside the escape cone
/// (sin θ_o < η, half-angle θ_c) for −tan((θ_c + θ_i)/2) < m < tan((θ_c − θ_i)/2), i.e.
/// −(η + sin θ_i)/d < m < (η − sin θ_i)/d with d = cos θ_c + μ. GGX's slopes along one axis
/// follow the law ½ + ½ m/√(s² + m²) of scale s = α (the 1-D marginal of the slope
/// distribution in Heitz 2014), so the escaping fraction is ½ (m₊/√(s² + m₊²) +
/// m₋/√(s² + m₋²)) over the two bounds m₊, m₋. Fitted corrections, with a = x^¾ ≈ 2α for the
/// roughness ([`fit_roughness`] x; two square roots where α itself would cost a pow): the
/// scale s = a (c0 + c1 a) (visible-normal weighting, masking, facets out of the plane), a
/// shift of the slopes by a (c2 + c3 (1 − μ)²) (visible normals lean towards the viewer at
/// grazing incidence), and for rough lobes, which forget their direction, a blend with weight
/// k a²/(1 + k a²), k = c6, towards 1 − η² (c4 + c5 η²) (a Lambertian lobe: 1 − η²).
/// Everything is multiplied through by d, so there is no division but the blend's. μ and η are
/// clamped to [0, 1] as the table lookups clamp them.
pub struct FitTir(pub [f64; FIT_COEFFICIENTS]);

impl Tir for FitTir {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        let [c0, c1, c2, c3, c4, c5, c6] = self.0;
        let (mu, eta) = (mu.clamp(0.0, 1.0), eta.clamp(0.0, 1.0));
        let x = fit_roughness(alpha);
        let a = (x * x.sqrt()).sqrt();
        let sin_i = (1.0 - mu * mu).sqrt();
        let d = (1.0 - eta * eta).sqrt() + mu;
        let shift = a * (c2 + c3 * (1.0 - mu) * (1.0 - mu)) * d;
        let upper = eta - sin_i + shift;
        let lower = eta + sin_i - shift;
        let scale = (a * (c0 + c1 * a) * d).max(FIT_MIN_SCALE);
        let cdf = |m: f64| m / (scale * scale + m * m).sqrt();
        let trapped = 1.0 - 0.5 * (cdf(upper) + cdf(lower));
        let rough = 1.0 - eta * eta * (c4 + c5 * eta * eta);
        let k = c6 * a * a;
        (trapped + (rough - trapped) * k / (1.0 + k)).clamp(0.0, 1.0)
    }
}

/// TIR(μ, α, η), the fraction of a GGX reflection lobe that total internal reflection keeps
/// inside a layer of relative IOR η < 1 (what the TIR table of `tir=lut32`/`lut16` tabulates),
/// in f64 by an `n`×`n` midpoint rule over the visible-normal sampler's two uniform variables
/// (the same estimator as the GPU's, with a regular grid instead of Hammersley points).
pub fn trapped_fraction(mu: f64, alpha: f64, eta: f64, n: u32) -> f64 {
    let (mut trapped, mut total) = (0.0, 0.0);
    microfacet::for_each_vndf_sample(mu.max(1e-3), alpha, n, |_, _, o| {
        let w = if alpha > 0.0 {
            microfacet::masking_g1(G2::Smith, o.z, alpha)
        } else {
            1.0
        };
        total += w;
        if o.z * o.z < 1.0 - eta * eta {
            trapped += w;
        }
    });
    if total > 0.0 {
        trapped / total
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_analytic_estimator_is_zero_over_most_of_the_domain() {
        // ALGORITHMS.md §9.2: non-zero only where the dominant-direction fit overshoots
        // (small α, μ near 1, where the off-specular direction is near grazing).
        let mut nonzero = 0;
        let mut total = 0;
        for i in 0..=10 {
            for j in 0..=10 {
                for k in 1..=9 {
                    let v = AnalyticTir.tir(
                        f64::from(i) / 10.0,
                        f64::from(j) / 10.0,
                        f64::from(k) / 10.0,
                    );
                    assert!((0.0..=1.0).contains(&v), "{v}");
                    total += 1;
                    if v > 0.0 {
                        nonzero += 1;
                    }
                }
            }
        }
        assert!(
            nonzero > 0 && nonzero * 4 < total,
            "{nonzero} of {total} non-zero"
        );
        assert_eq!(ConstantTir(CONSTANT_FRACTION).tir(0.3, 0.2, 0.5), 0.1);
    }

    #[test]
    fn the_fit_is_a_step_at_the_critical_angle_when_smooth() {
        let fit = FitTir(super::super::tir_fit::COEFFICIENTS);
        for eta in [0.2, 0.5, 0.8, 0.95] {
            let critical = f64::sqrt(1.0 - eta * eta);
            // |Δμ| = 0.02 moves the bound η − sin θ_i by ≥ 6e-3 at every η here, six times
            // the floor of the scale: within 2 % of the step's ends.
            assert!(fit.tir(critical - 0.02, 0.0, eta) > 0.98, "η {eta}");
            assert!(fit.tir(critical + 0.02, 0.0, eta) < 0.02, "η {eta}");
        }
        // The shader's roughness variable, from the lobe's g, is this one's, from α.
        for g in [-0.5, 0.1, 0.2284, 0.5, 0.9, 0.999, 1.0] {
            let x = hg::alpha_power_of_g(g).clamp(fit_roughness(0.0), fit_roughness(1.0));
            let from_alpha = fit_roughness(hg::alpha_of_g(g));
            assert!((x - from_alpha).abs() < 1e-12, "g {g}: {x} vs {from_alpha}");
        }
        // Finite and in [0, 1] at the domain's corners and beyond (clamped like the table).
        for mu in [-1.0, 0.0, 1.0, 2.0] {
            for alpha in [0.0, 1.0, 3.0] {
                for eta in [0.0, 1.0, 1.5] {
                    let v = fit.tir(mu, alpha, eta);
                    assert!((0.0..=1.0).contains(&v), "({mu}, {alpha}, {eta}): {v}");
                }
            }
        }
    }
}
