// Analytic lights on the model's lobes: each lobe is the GGX microfacet lobe of its roughness,
// without Fresnel (the model put the energy in the lobe's weight), divided by the white lobe's
// directional albedo E(μ_v, α) so that its response to light from every direction integrates
// to the weight. src/model/light.rs derives it, with its sources, and is the oracle.
// D is the ndf axis's form, G2 the g2 axis's (lib/microfacet.glsl); E is read from the
// shading set's lobe_albedo table, built with the same G2. Under transport=corrected the top
// interface's lobe (LOBE_FRESNEL) is that interface's own microfacet lobe instead, with its
// Fresnel factor (light_lobe's `top`).
#ifndef LAMINA_LIB_LIGHT
#define LAMINA_LIB_LIGHT

#include "fresnel.glsl"
#include "microfacet.glsl"
#include "../bindings/shading.glsl"

#ifdef LAMINA_FP16
const float LIGHT_ALPHA_FLOOR = LIGHT_MIN_ALPHA_FP16;
#else
const float LIGHT_ALPHA_FLOOR = LIGHT_MIN_ALPHA;
#endif

// The roughness a lobe of roughness α is shaded with under a light whose disk widens it by
// `widening`, tan(θ_r/2) of its angular radius θ_r: floored (a punctual light's highlight on
// a mirror is a delta), then widened in quadrature, α'² = α² + tan²(θ_r/2), the GGX lobe
// whose peak is that of the lobe averaged over the disk (model::light::shading_alpha).
float light_alpha_widened(float alpha, float widening) {
    float a = max(alpha, LIGHT_ALPHA_FLOOR);
    return min(sqrt(a * a + widening * widening), 1.0);
}

// light_alpha_widened under a light of angular radius θ_r (radians).
float light_alpha(float alpha, float angular_radius) {
    return light_alpha_widened(alpha, tan(0.5 * angular_radius));
}

// E(μ_v, α): the white GGX lobe's directional albedo, from the shading set's table (vertex-
// centred texels, src/tables/lobe_albedo.rs: x·(n − 1) + ½ texels in).
float white_albedo(float n_dot_v, float alpha) {
    vec2 at = (vec2(n_dot_v, sqrt(alpha)) * (LOBE_ALBEDO_SIZE - 1.0) + 0.5) / LOBE_ALBEDO_SIZE;
    return textureLod(lobe_albedo, at, 0.0).r;
}

// The normalised lobe's response to a unit irradiance arriving along l (unit, towards the
// light), times μ_l: D·G2 / (4 μ_v E(μ_v, α)). `n_dot_v` is the view cosine the model was
// evaluated at; a retro lobe (6-flux back-scatter) is the same lobe about the view's mirror
// image, whose peak is at l = v.
// `top` (LOBE_FRESNEL, top.x > 0): the top interface's relative IOR η and the directional
// albedo A the model gave it at this view. The lobe is then the interface's microfacet lobe,
// D·G2·F(v·h) / (4 μ_v A), times the lobe's weight: the interface's own reflection scaled by
// the transport's ratio (weight / A), whose Fresnel factor rises across the lobe towards
// grazing as the walk's does (ALGORITHMS.md §17). It is normalised at the model's roughness:
// a light that widens the lobe (a disk, the floor) spreads it and keeps A.
//
// light_lobe_with takes the white lobe's albedo to divide by instead of reading it at α, as
// the environment's lamps do (lib/shade.glsl's lobe_lamps: one read per lobe, not per lamp).
float light_lobe_with(
    vec3 n, vec3 v, float n_dot_v, vec3 l, float alpha, bool retro, vec2 top, float albedo) {
    float n_dot_l = dot(n, l);
    if (n_dot_l <= 0.0) {
        return 0.0;
    }
    vec3 view = retro ? 2.0 * n_dot_v * n - v : v;
    vec3 h = normalize(view + l);
    float d = float(ndf(real(max(dot(n, h), 0.0)), real(alpha)));
    float g2 = float(masking_shadowing(real(n_dot_l), real(n_dot_v), real(alpha)));
    if (top.x > 0.0) {
        float f = fresnel_dielectric(max(dot(view, h), 0.0), top.x);
        return top.y > 0.0 ? d * g2 * f / (4.0 * n_dot_v * top.y) : 0.0;
    }
    return d * g2 / (4.0 * n_dot_v * albedo);
}

float light_lobe(vec3 n, vec3 v, float n_dot_v, vec3 l, float alpha, bool retro, vec2 top) {
    return light_lobe_with(n, v, n_dot_v, l, alpha, retro, top, white_albedo(n_dot_v, alpha));
}

#endif
