// Image-based lighting with a GGX-prefiltered cube (Karis 2013, split sum), read per lobe as
// ALGORITHMS.md §8.2 recommends.
#ifndef LAMINA_LIB_IBL
#define LAMINA_LIB_IBL

#include "math.glsl"

// The one roughness ↔ mip mapping, used by the prefilter pass and by every lookup:
// perceptual roughness r = √α = mip / (mip_count − 1).
float ibl_alpha_of_mip(float mip, float mip_count) {
    float r = mip / max(mip_count - 1.0, 1.0);
    return r * r;
}

float ibl_mip_of_alpha(float alpha, float mip_count) {
    return sqrt(clamp(alpha, 0.0, 1.0)) * (mip_count - 1.0);
}

// Off-specular dominant direction (Lagarde & de Rousiers 2014, simple form):
// lerp(N, R, (1 − α)(√(1 − α) + α)). Not normalised: a cube lookup divides by the major axis
// anyway, and the lerp of two unit vectors with N·R ≥ 0 (R is the view's mirror about N, or
// the view itself) is never zero.
vec3 ibl_dominant_direction(vec3 n, vec3 r, float alpha) {
    float a = clamp(alpha, 0.0, 1.0);
    float f = (1.0 - a) * (sqrt(1.0 - a) + a);
    return mix(n, r, f);
}

#endif
