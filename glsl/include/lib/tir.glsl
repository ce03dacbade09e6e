// Total-internal-reflection correction (ALGORITHMS.md §4.5, §9), by the TIR_MODE constant, from
// the shading set's tir_table (bindings/shading.glsl; n³, vertex-centred (μ, α, η), see
// tir_table.comp.glsl) in the LUT modes. Mirrors the Tir providers of src/model and
// src/tables/tir.rs.
#ifndef LAMINA_LIB_TIR
#define LAMINA_LIB_TIR

#include "math.glsl"
#include "fresnel.glsl"
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

// Fraction of a lobe (incidence μ, roughness α) trapped by relative IOR η < 1.
float tir_fraction(float mu, float alpha, float eta) {
    if (TIR_MODE == TIR_NONE) {
        return 0.0;
    } else if (TIR_MODE == TIR_CONSTANT) {
        return TIR_CONSTANT_FRACTION;
    } else if (TIR_MODE == TIR_ANALYTIC) {
        return tir_analytic(mu, alpha, eta);
    }
    float n = float(LAMINA_TIR_SIZE);
    vec3 x = clamp(vec3(mu, alpha, eta), 0.0, 1.0);
    return textureLod(tir_table, (x * (n - 1.0) + 0.5) / n, 0.0).r;
}

#endif
