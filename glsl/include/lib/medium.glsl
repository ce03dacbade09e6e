// A homogeneous scattering medium as the 6-flux model sees it (ALGORITHMS.md §5.3, numerics
// §5.8): the two-stream factors of its secondary fluxes and its direct transmission. Used by the
// 6-flux model (tm6.glsl) and by a diffuse base's slab (tm_common.glsl). Mirrors
// src/model/medium.rs.
#ifndef LAMINA_LIB_MEDIUM
#define LAMINA_LIB_MEDIUM

#include "hg.glsl"
#include "../shared/material.glsl"

// 1 − e^{−x} for x ≥ 0 without the cancellation of 1.0 − exp(−x) at small x (a Taylor series
// below 2⁻⁶, error < x⁴/24).
float medium_one_minus_exp_neg(float x) {
    return x < 0.015625 ? x * (1.0 - x * (0.5 - x / 6.0)) : 1.0 - exp(-x);
}

// Back-reflection and forward transmission of the two-stream system (a, b) over optical depth
// τ: r = S·b/(Cγ + S·a), t = γ/(Cγ + S·a) with S = sinh(γτ), C = cosh(γτ), divided through by
// e^{γτ}/2 so that nothing grows with τ (src/model/medium.rs: no τ clamp is needed). γ² is formed
// as (a − b)(a + b) from the caller's sums: a² − b² loses a nearly lossless medium's absorption.
void medium_two_stream(vec3 a, vec3 b, vec3 a_minus_b, vec3 a_plus_b, float tau, out vec3 r,
                    out vec3 t) {
    vec3 gamma = sqrt(max(a_minus_b * a_plus_b, vec3(0.0)));
    vec3 x = gamma * tau;
    vec3 spread = vec3(medium_one_minus_exp_neg(2.0 * x.r), medium_one_minus_exp_neg(2.0 * x.g),
                       medium_one_minus_exp_neg(2.0 * x.b));
    vec3 inv = 1.0 / (gamma * (2.0 - spread) + a * spread);
    r = b * spread * inv;
    t = 2.0 * gamma * exp(-x) * inv;
}

// Kubelka–Munk-type two-stream factors of a medium of thickness `depth` crossed at cosine
// `mu` (§5.3, numerics §5.8): T, r_fb, t_ff and the g's of r_fb and t_ff. As src/model/medium.rs,
// a = σ_sb + σ_k, b = σ_sb and a_g = σ_ext − g·σ_sf, b_g = −g·σ_sb, their sums and differences
// written as sums of non-negative terms.
void medium_factors(LayerGpu layer, float mu, out vec3 transmission, out vec3 r_fb,
                        out vec3 t_ff, out float g_rfb, out float g_tff) {
    vec3 sigma_s = layer.sigma_s.rgb;
    vec3 sigma_k = max(layer.sigma_a.rgb, vec3(1e-7));
    float g = layer.params.z;
    vec3 sigma_sb = sigma_s * hg_lh_norm(g);
    vec3 sigma_sf = sigma_s - sigma_sb;
    vec3 sigma_ext = sigma_s + sigma_k;
    float tau = layer.params.y / max(mu, 1e-7);
    transmission = exp(-sigma_ext * tau);
    medium_two_stream(sigma_sb + sigma_k, sigma_sb, sigma_k, 2.0 * sigma_sb + sigma_k, tau, r_fb,
                   t_ff);
    vec3 rg;
    vec3 tg;
    medium_two_stream(sigma_ext - sigma_sf * g, -sigma_sb * g,
                   sigma_sf * (1.0 - g) + sigma_sb * (1.0 + g) + sigma_k,
                   sigma_s * (1.0 - g) + sigma_k, tau, rg, tg);
    g_rfb = (hg_safe_ratio(rg.r, r_fb.r) + hg_safe_ratio(rg.g, r_fb.g) + hg_safe_ratio(rg.b, r_fb.b)) / 3.0;
    g_tff = (hg_safe_ratio(tg.r, t_ff.r) + hg_safe_ratio(tg.g, t_ff.g) + hg_safe_ratio(tg.b, t_ff.b)) / 3.0;
}

#endif
