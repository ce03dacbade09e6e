// Henyey–Greenstein lobe algebra of the transfer-matrix model (Randrianandrasana, Callet &
// Lucas 2021; ALGORITHMS.md §3). A lobe's spread is its HG asymmetry g; paths compose by
// multiplying g's. Mirrors src/model/hg.rs.
#ifndef LAMINA_LIB_HG
#define LAMINA_LIB_HG

#include "precision.glsl"
#include "../generated/codes.glsl"

// GGX α → HG g (the paper's Eq. 15), exact inverse of hg_alpha_of_g on α ∈ [0, 1].
float hg_g_of_alpha(float alpha) {
    float a = clamp(alpha, 0.0, 1.0);
    return clamp(-0.085 + 1.085 / (1.0 + pow(a / 0.5, 1.3)), 0.0, 1.0);
}

// HG g → (2α)^1.3, the paper's Eq. 15 solved for it without the root (one division, where α
// costs a pow): what tir=fit reads.
float hg_alpha_power_of_g(float g) {
    return 1.085 / (max(clamp(g, -1.0, 1.0), 0.2) + 0.085) - 1.0;
}

// HG g → GGX α; any g below 0.2284 maps to α = 1.
float hg_alpha_of_g(float g) {
    return clamp(0.5 * pow(hg_alpha_power_of_g(g), 1.0 / 1.3), HG_MIN_ALPHA, 1.0);
}

// Lobe refraction through relative IOR η (the paper's Eq. 17–18).
float hg_refract(float g, float eta) {
    return min(sqrt(max(1.0 - (1.0 - g * g) * pow(eta, 0.75), 0.0)), 1.0);
}

// num / den, or 0 where |den| ≤ HG_RATIO_FLOOR: ratios of g's, undefined where a lobe has
// collapsed (src/model/hg.rs's safe_ratio says why not > 0: f32 underflows long before f64).
float hg_safe_ratio(float num, float den) {
    return abs(den) > HG_RATIO_FLOOR ? num / den : 0.0;
}

// Fraction of an HG phase function in the backward hemisphere (polynomial fit, §3.5).
float hg_lh_norm(float g) {
    float b = clamp(0.5039 - 0.8254 * abs(g) + 0.3226 * g * g, 0.0, 0.5);
    return g < 0.0 ? 1.0 - b : b;
}

#endif
