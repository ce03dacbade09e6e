//! The TIR modes without a table, in f64: the twins of `tir=constant` and `tir=analytic` in
//! glsl/include/lib/tir.glsl (the table modes' twin is `tables::tir::TableTir`), and the exact
//! trapped fraction the table holds ([`trapped_fraction`], its reference).

use super::{microfacet, Tir};
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
}
