// Directional albedo FGD(μ, α, η, κ) of a rough interface, from the table the FGD_MODE
// constant selects. The including entry point declares the tables:
//   uniform sampler2D split_sum;   // fgd = karis: (A, B) at (μ, √α), see split_sum.comp.glsl
// Mirrors the providers of src/model/fgd.rs.
#ifndef LAMINA_LIB_FGD
#define LAMINA_LIB_FGD

#include "fresnel.glsl"

// Karis 2013 split sum: F0·A + B with F0 from the complex IOR (exact at normal incidence, a
// Schlick-shaped approximation elsewhere, no total internal reflection).
vec3 fgd_rgb(float mu, float alpha, vec3 eta, vec3 kappa) {
    vec2 ab = texture(split_sum, vec2(mu, sqrt(alpha))).rg;
    return f0_complex(eta, kappa) * ab.x + ab.y;
}

float fgd_dielectric(float mu, float alpha, float eta) {
    vec2 ab = texture(split_sum, vec2(mu, sqrt(alpha))).rg;
    float f0 = (eta - 1.0) * (eta - 1.0) / ((eta + 1.0) * (eta + 1.0));
    return f0 * ab.x + ab.y;
}

#endif
