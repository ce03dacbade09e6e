//! A homogeneous scattering medium as the 6-flux model sees it (ALGORITHMS.md §5.3, numerics
//! §5.8): the two-stream factors of its secondary fluxes — back-reflection, forward
//! transmission and their asymmetries — and its direct transmission. Used by the 6-flux model
//! (`tm6`) and by the diffuse base's slab (`diffuse`); the f64 twin of
//! `glsl/include/lib/medium.glsl`.
//!
//! One departure from the reference, where it returned wrong values rather than failing: its
//! medium clamped the optical depth τ to 45/max(σ_ext) (and 45/max(γ)) to keep sinh, cosh and
//! 1/T finite. The same τ also drives the scattered flux, which decays at γ ≪ σ_ext in a
//! scattering medium, so a medium of optical depth 10⁴ transmitted like one of 45/σ_ext·γ
//! (T = 0.003 through four layers of σ_s = 222, depth 49). The two-stream factors are written
//! here in forms that only decay (e^{−γτ}, e^{−2γτ}), so no clamp is needed.

use super::adding::{avg, map3, Rgb};
use super::hg::{self, safe_ratio};
use super::LayerParams;

/// 1 − e^{−x} for x ≥ 0, without cancellation at small x.
fn one_minus_exp_neg(x: f64) -> f64 {
    -(-x).exp_m1()
}

/// A medium's two-stream factors (§5.3, numerics §5.8).
pub struct Medium {
    pub t: Rgb,
    pub r_fb: Rgb,
    pub t_ff: Rgb,
    pub g_rfb: f64,
    pub g_tff: f64,
}

/// Back-reflection and forward transmission of the two-stream system (a, b) over optical
/// depth τ: with S = sinh(γτ), C = cosh(γτ), r = S·b/(Cγ + S·a) and t = γ/(Cγ + S·a), here
/// divided through by e^{γτ}/2 so that nothing grows with τ. γ² = a² − b² is taken as
/// (a − b)(a + b) from those sums as the caller forms them: a − b is the absorption alone in a
/// nearly lossless medium, and a² − b² lost it to f32 rounding (γ = 0, then 0/0 on the GPU).
fn two_stream(a: f64, b: f64, a_minus_b: f64, a_plus_b: f64, tau: f64) -> (f64, f64) {
    let gamma = (a_minus_b * a_plus_b).max(0.0).sqrt();
    let x = gamma * tau;
    let (decay, spread) = ((-x).exp(), one_minus_exp_neg(2.0 * x));
    let den = gamma * (2.0 - spread) + a * spread;
    (b * spread / den, 2.0 * gamma * decay / den)
}

/// The two-stream factors of a medium (energies, then g-weighted), with a = σ_ext − σ_sf and
/// b = σ_sb, resp. a_g = σ_ext − g·σ_sf and b_g = −g·σ_sb; their sums and differences written
/// as sums of non-negative terms.
pub fn medium_factors(layer: &LayerParams, mu: f64) -> Medium {
    let g = layer.g;
    let tau = layer.depth / mu.max(1e-7);
    let (mut r_fb, mut t_ff) = ([0.0; 3], [0.0; 3]);
    let (mut rg, mut tg) = ([0.0; 3], [0.0; 3]);
    let mut t = [0.0; 3];
    for c in 0..3 {
        let sigma_k = layer.sigma_a[c].max(1e-7);
        let sigma_sb = layer.sigma_s[c] * hg::lh_norm(g);
        let sigma_sf = layer.sigma_s[c] - sigma_sb;
        let sigma_ext = layer.sigma_s[c] + sigma_k;
        let a = sigma_sb + sigma_k;
        (r_fb[c], t_ff[c]) = two_stream(a, sigma_sb, sigma_k, 2.0 * sigma_sb + sigma_k, tau);
        let a_g = sigma_ext - sigma_sf * g;
        let minus = sigma_sf * (1.0 - g) + sigma_sb * (1.0 + g) + sigma_k;
        let plus = layer.sigma_s[c] * (1.0 - g) + sigma_k;
        (rg[c], tg[c]) = two_stream(a_g, -sigma_sb * g, minus, plus, tau);
        t[c] = (-sigma_ext * tau).exp();
    }
    Medium {
        t,
        r_fb,
        t_ff,
        g_rfb: avg(map3(|c| safe_ratio(rg[c], r_fb[c]))),
        g_tff: avg(map3(|c| safe_ratio(tg[c], t_ff[c]))),
    }
}
