// Directional albedo FGD(μ, α, η, κ), from the table the FGD_MODE constant selects, bound by
// the shading set (bindings/shading.glsl):
//   split_sum     karis: (A, B) at (μ, √α), see split_sum.comp.glsl
//   fgd_table     4d: 64×64×4096, resampled4d: 64×64×2048, belcour: the 64³ dielectric table
//                 over η < 1
//   fgd_belcour   belcour: the folded 4-channel table
// Mirrors the providers of src/tables/fgd.rs.
#ifndef LAMINA_LIB_FGD
#define LAMINA_LIB_FGD

#include "fresnel.glsl"
#include "../shared/variant.glsl"
#include "../bindings/shading.glsl"

// Texels per axis of the vertex-centred grids (the host builds them at this size).
const float FGD_N = float(LAMINA_FGD_SIZE);
// The 4-D table's domain in η and κ (FGD_ETA_MAX, FGD_KAPPA_MAX: [0, 4] each, ALGORITHMS.md
// §6.1; beyond it, carried on from its edge: fgd_stacked) and the cosines where the Belcour projection interpolates F exactly
// (BELCOUR_CT1, BELCOUR_CT2, §7.2) come from src/shader/interface.rs through
// generated/codes.glsl.

// Normalised coordinate of x ∈ [0, 1] on a vertex-centred grid of FGD_N texels.
float fgd_grid(float x) {
    return (clamp(x, 0.0, 1.0) * (FGD_N - 1.0) + 0.5) / FGD_N;
}

// The 4-D table stacked as (μ, α, η + N·κ-slice): two hardware-trilinear fetches in the κ
// slices around κ and a lerp between them. `resampled4d` holds N/2 slices, slice m filtered
// around the original κ index 2m + ½ (src/tables/fgd.rs).
float fgd_stacked(float mu, float alpha, float eta, float kappa) {
    vec2 xy = vec2(fgd_grid(mu), fgd_grid(alpha));
    float fe = clamp(eta / FGD_ETA_MAX, 0.0, 1.0) * (FGD_N - 1.0);
    float fk = clamp(kappa / FGD_KAPPA_MAX, 0.0, 1.0) * (FGD_N - 1.0);
    float slices = FGD_N;
    float g = fk;
    if (FGD_MODE == FGD_RESAMPLED4D) {
        slices = 0.5 * FGD_N;
        g = clamp(0.5 * (fk - 0.5), 0.0, slices - 1.0);
    }
    float s0 = min(floor(g), slices - 2.0);
    float depth = slices * FGD_N;
    float z0 = (s0 * FGD_N + fe + 0.5) / depth;
    float a = texture(fgd_table, vec3(xy, z0)).r;
    float b = texture(fgd_table, vec3(xy, z0 + FGD_N / depth)).r;
    float value = mix(a, b, g - s0);
    if (FGD_PAST_EDGE != 0u && (eta > FGD_ETA_MAX || kappa > FGD_KAPPA_MAX)) {
        // Beyond the domain (aluminium's κ reaches 9.2), FGD goes on from the value at its
        // edge along the split sum's slope in F0 (src/tables/fgd.rs's `beyond_the_table`).
        float slope = texture(split_sum, vec2(mu, sqrt(alpha))).r;
        float edge = f0_channel(min(eta, FGD_ETA_MAX), min(kappa, FGD_KAPPA_MAX));
        value += slope * (f0_channel(eta, kappa) - edge);
    }
    return value;
}

// Belcour et al. 2020 with the projection folded into the table: F(1)·P0 + P1 + F(ct1)·P2 +
// F(ct2)·P3. The basis has no total internal reflection, so a dielectric interface with
// η < 1 reads the dedicated (μ, α, η) table instead.
float fgd_belcour_channel(float mu, float alpha, float eta, float kappa) {
    if (kappa <= 0.0 && eta < 1.0) {
        return texture(fgd_table, vec3(fgd_grid(mu), fgd_grid(alpha), fgd_grid(eta))).r;
    }
    vec4 p = texture(fgd_belcour, vec2(mu, sqrt(alpha)));
    return f0_channel(eta, kappa) * p.x + p.y + fresnel_conductor(BELCOUR_CT1, eta, kappa) * p.z
        + fresnel_conductor(BELCOUR_CT2, eta, kappa) * p.w;
}

// One channel: relative complex IOR η + iκ (κ = 0 for a dielectric).
float fgd_channel(float mu, float alpha, float eta, float kappa) {
    if (FGD_MODE == FGD_BELCOUR) {
        return fgd_belcour_channel(mu, alpha, eta, kappa);
    } else if (FGD_MODE == FGD_4D || FGD_MODE == FGD_RESAMPLED4D) {
        return fgd_stacked(mu, alpha, eta, kappa);
    }
    // Karis 2013 split sum: F0·A + B with F0 from the complex IOR (exact at normal incidence,
    // a Schlick-shaped approximation elsewhere, no total internal reflection).
    vec2 ab = texture(split_sum, vec2(mu, sqrt(alpha))).rg;
    return f0_channel(eta, kappa) * ab.x + ab.y;
}

// The albedo the models consume: within [0, 1] (src/model/mod.rs's `albedo`: half-float,
// interpolated tables overshoot 1 for near-perfect mirrors, and an albedo above 1 makes light).
vec3 fgd_rgb(float mu, float alpha, vec3 eta, vec3 kappa) {
    if (FGD_MODE == FGD_KARIS) {
        vec2 ab = texture(split_sum, vec2(mu, sqrt(alpha))).rg;
        return clamp(f0_complex(eta, kappa) * ab.x + ab.y, 0.0, 1.0);
    }
    return clamp(vec3(
        fgd_channel(mu, alpha, eta.r, kappa.r),
        fgd_channel(mu, alpha, eta.g, kappa.g),
        fgd_channel(mu, alpha, eta.b, kappa.b)), 0.0, 1.0);
}

float fgd_dielectric(float mu, float alpha, float eta) {
    return clamp(fgd_channel(mu, alpha, eta, 0.0), 0.0, 1.0);
}

#endif
