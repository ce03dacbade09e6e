// Total-internal-reflection correction (ALGORITHMS.md §4.5, §9), by the TIR_MODE constant, from
// the shading set's tir_table (bindings/shading.glsl; n³, vertex-centred (μ, α, η), see
// tir_table.comp.glsl) in the LUT modes, or a fitted closed form. Mirrors the Tir providers
// of src/model and src/tables/tir.rs.
#ifndef LAMINA_LIB_TIR
#define LAMINA_LIB_TIR

#include "math.glsl"
#include "fresnel.glsl"
#include "hg.glsl"
#include "../shared/variant.glsl"
#include "../bindings/shading.glsl"

// `tir=constant` returns TIR_CONSTANT_FRACTION (generated/codes.glsl, from
// src/model/tir.rs): the talk's dummy constant, standing in for the fetch to measure its cost.

// The talk's naive analytic estimator (ALGORITHMS.md §9.2), kept as the port wrote it (the
// Frostbite dominant-direction fit unclamped: it only overshoots, and the estimate is only
// non-zero, at small α near grazing reflection), except for its exit factor
// (1 − F(wo.z, η_10)), η_10 = 1 / IOR of the layer above, which tir_fraction does not receive:
// it is taken for an exit into air (η_10 = 1, factor 1), exact at the top interface.
float tir_analytic(float mu, float alpha, float eta) {
    float s = sin(0.25 * PI * (1.0 + mu));
    vec3 wo = vec3(s, 0.0, sqrt(max(0.0, 1.0 - s * s)));
    float a = max(alpha, 0.01);
    float l = log(39.4115 - 39.0029 * a);
    float f = pow(1.0 - mu, 10.8649) * (1.0 - 0.298475 * l) + 0.298475 * l;
    vec3 m = mix(vec3(0.0, 0.0, 1.0), wo, f);
    vec3 ws = 2.0 * dot(wo, m) * m - wo;
    if (ws.z > 0.0) {
        return 0.0;
    }
    float c = abs(ws.z);
    float lambda = 0.5 * (-1.0 + sqrt(1.0 + a * a * (1.0 - c * c) / max(c * c, 1e-8)));
    float g1 = 1.0 / (1.0 + lambda);
    return fresnel_dielectric(clamp(dot(wo, m), 0.0, 1.0), eta) * g1;
}

// `tir=fit`: a closed form least-squares fitted to the table (src/model/tir.rs's FitTir
// derives it; its coefficients TIR_FIT_COEFFICIENTS come from src/model/tir_fit.rs, written by
// `lamina tables tir-fit`). The fraction of the lobe's in-plane facet slopes that reflect its
// centre out of the escape cone under GGX's 1-D slope law ½ + ½ m/√(s² + m²), with a fitted
// scale s and shift, blended for rough lobes towards 1 − η² (c4 + c5 η²). Its roughness is
// a = x^¾ ≈ 2α of x = (2α)^1.3, which the lobe's g gives with one division (α costs a pow).
// Multiplied through by d = cos θ_c + μ: no division but the blend's.
float tir_fit(float mu, float g, float eta) {
    const float c[7] = TIR_FIT_COEFFICIENTS;
    mu = clamp(mu, 0.0, 1.0);
    eta = clamp(eta, 0.0, 1.0);
    float x = clamp(hg_alpha_power_of_g(g), TIR_FIT_X_MIN, TIR_FIT_X_MAX);
    float a = sqrt(x * sqrt(x));
    float sin_i = sqrt(1.0 - mu * mu);
    float d = sqrt(1.0 - eta * eta) + mu;
    float shift = a * (c[2] + c[3] * (1.0 - mu) * (1.0 - mu)) * d;
    float upper = eta - sin_i + shift;
    float lower = eta + sin_i - shift;
    float scale = max(a * (c[0] + c[1] * a) * d, TIR_FIT_MIN_SCALE);
    float s2 = scale * scale;
    float trapped = 1.0 - 0.5 * (upper * inversesqrt(s2 + upper * upper)
                                 + lower * inversesqrt(s2 + lower * lower));
    float rough = 1.0 - eta * eta * (c[4] + c[5] * eta * eta);
    float k = c[6] * a * a;
    return clamp(mix(trapped, rough, k / (1.0 + k)), 0.0, 1.0);
}

// Fraction of a lobe (incidence μ, HG asymmetry g) trapped by relative IOR η < 1. The table and
// the analytic estimator take the lobe's GGX α; tir=fit takes g itself, which spares it the
// α mapping's pow.
float tir_fraction(float mu, float g, float eta) {
    if (TIR_MODE == TIR_NONE) {
        return 0.0;
    } else if (TIR_MODE == TIR_CONSTANT) {
        return TIR_CONSTANT_FRACTION;
    } else if (TIR_MODE == TIR_FIT) {
        return tir_fit(mu, g, eta);
    }
    float alpha = hg_alpha_of_g(g);
    if (TIR_MODE == TIR_ANALYTIC) {
        return tir_analytic(mu, alpha, eta);
    }
    float n = float(LAMINA_TIR_SIZE);
    vec3 x = clamp(vec3(mu, alpha, eta), 0.0, 1.0);
    return textureLod(tir_table, (x * (n - 1.0) + 0.5) / n, 0.0).r;
}

#endif
