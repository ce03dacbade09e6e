// Image-based lighting with a GGX-prefiltered cube (Karis 2013, split sum), read per lobe as
// ALGORITHMS.md §8.2 recommends.
#ifndef LAMINA_LIB_IBL
#define LAMINA_LIB_IBL

#include "math.glsl"

// Karis's cube's roughness ↔ mip mapping, used by its prefilter pass and by the split sum's
// lookup: perceptual roughness r = √α = mip / (mip_count − 1).
float ibl_mip_of_alpha(float alpha, float mip_count) {
    return sqrt(clamp(alpha, 0.0, 1.0)) * (mip_count - 1.0);
}

// The matched cube's levels (tables::environment::matched_alpha_of_mip, the prefilter's twin):
// mip 0 a mirror, mip 1 at α₁ = 1/(mip_count − 1)², where Karis's cube has it, and the
// levels above spaced evenly in log α up to α = 1 at the last — about twice α a level with
// 8 levels, where √α steps put mips 1 and 2 at α 0.020 and 0.082, whose blend has twice a
// lobe's GGX tail between them. Below α₁ the lookup reads between mips 0 and 1 as Karis's.
float ibl_matched_mip_of_alpha(float alpha, float mip_count) {
    float last = max(mip_count - 1.0, 1.0);
    float a = clamp(alpha, 0.0, 1.0);
    if (a * last * last <= 1.0) {
        return sqrt(a) * last;
    }
    return last + max(mip_count - 2.0, 0.0) * log(a) / max(2.0 * log(last), 1e-6);
}

// A lobe of α at most the models' smallest (a smooth layer's, HG_MIN_ALPHA) is a mirror to
// the lighting: one fetch of the cubes' shared mip 0, whatever the `ibl` value.
const float IBL_MIN_ALPHA = HG_MIN_ALPHA;

// GGX D and Smith's Λ in single precision whatever the model's precision (the lighting's
// arithmetic is not the fp16 axis's): D peaks at 1/(πα²), beyond half floats below α ≈ 2e-3.
float ibl_ggx_d(float cos_h, float alpha) {
    float a2 = alpha * alpha;
    float d = cos_h * cos_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float ibl_lambda(float cos_t, float alpha) {
    float c = max(cos_t, 1e-6);
    float c2 = c * c;
    return (sqrt(c2 + alpha * alpha * (1.0 - c2)) - c) / (2.0 * c);
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

// A lobe's moments from tables::lobe_moments (`table`: over √μ and √α, n×n vertex-centred
// texels in each half of a 2n × n image). The left half: x, the weight w with which
// normalize(mix(R, N, w)) is the mean m̂ of its reflected directions; y, √α′ of the normal-view
// lobe that spreads as much; z, √α″ of the normal-view lobe that spreads as much across one
// tangent axis as the lobe across its plane of incidence; w, `up`. The right half's x:
// `down`. Two points at m̂ + up·t and m̂ − down·t (t: m̂'s tangent in the plane of incidence,
// towards the normal), weighted down/(up + down) and up/(up + down), hold the rest of the
// lobe's spread and its skew along t. The right half's y and z: `ibl=matched`'s fetch
// (tables::lobe_fit), the w of normalize(mix(R, N, w)) and the √α′ of the matched cube's
// kernel that come closest to the lobe in L².
vec2 ibl_lobe_moments_at(float n_dot_v, float alpha) {
    vec2 at = vec2(sqrt(clamp(n_dot_v, 0.0, 1.0)), sqrt(clamp(alpha, 0.0, 1.0)));
    vec2 texels = vec2(2.0 * LOBE_MOMENTS_SIZE, LOBE_MOMENTS_SIZE);
    return (at * (LOBE_MOMENTS_SIZE - 1.0) + 0.5) / texels;
}

vec4 ibl_lobe_moments(sampler2D table, float n_dot_v, float alpha) {
    return textureLod(table, ibl_lobe_moments_at(n_dot_v, alpha), 0.0);
}

float ibl_lobe_moments_down(sampler2D table, float n_dot_v, float alpha) {
    return textureLod(table, ibl_lobe_moments_at(n_dot_v, alpha) + vec2(0.5, 0.0), 0.0).x;
}

vec2 ibl_lobe_fit(sampler2D table, float n_dot_v, float alpha) {
    return textureLod(table, ibl_lobe_moments_at(n_dot_v, alpha) + vec2(0.5, 0.0), 0.0).yz;
}

// `ibl=lamps`' placement of its fetch: tables::lobe_fit::polynomial, the lean w of
// normalize(mix(R, N, w)) along the lobe's mean direction (ibl_lobe_moments' x) and the √α′
// of the fetch that comes closest to the lobe in L² (ibl_lobe_fit's y) as two polynomials
// in (√μ, √α), in two steps where the tables are a texture fetch: the terms in √μ alone
// (the lean's constant and √α terms, the root's; the same for every lobe of a point, whose
// directions all make the view's angle with the normal), then per lobe three multiply-adds
// in √α.
vec4 ibl_lobe_fit_terms(float n_dot_v) {
    float s = sqrt(clamp(n_dot_v, 0.0, 1.0));
    return vec4(IBL_LAMPS_LEAN[0] + s * (IBL_LAMPS_LEAN[2] + s * IBL_LAMPS_LEAN[4]),
                IBL_LAMPS_LEAN[1] + s * IBL_LAMPS_LEAN[3],
                IBL_LAMPS_ROOT[0] + s * (IBL_LAMPS_ROOT[2] + s * IBL_LAMPS_ROOT[4]),
                IBL_LAMPS_ROOT[1] + s * (IBL_LAMPS_ROOT[3] + s * IBL_LAMPS_ROOT[5]));
}

vec2 ibl_lobe_fit_polynomial(vec4 terms, float alpha) {
    float r = sqrt(clamp(alpha, 0.0, 1.0));
    float w = terms.x + r * (terms.y + r * IBL_LAMPS_LEAN[5]);
    float root = terms.z + r * terms.w;
    return clamp(r * vec2(w, root), 0.0, 1.0);
}

// The irradiance E(n) of an environment given by its order-2 spherical-harmonic coefficients,
// each already times its band's cosine-lobe factor Â_l (π, 2π/3, π/4): Ramamoorthi & Hanrahan,
// "An Efficient Representation for Irradiance Environment Maps" (2001). The coefficients come
// from tables::irradiance::irradiance_sh, in the order Y00, Y1−1, Y10, Y11, Y2−2, Y2−1, Y20,
// Y21, Y22.
vec3 ibl_irradiance(vec3 n, vec4 c[9]) {
    vec3 e = c[0].rgb * 0.282095;
    e += c[1].rgb * (0.488603 * n.y) + c[2].rgb * (0.488603 * n.z) + c[3].rgb * (0.488603 * n.x);
    e += c[4].rgb * (1.092548 * n.x * n.y) + c[5].rgb * (1.092548 * n.y * n.z);
    e += c[6].rgb * (0.315392 * (3.0 * n.z * n.z - 1.0)) + c[7].rgb * (1.092548 * n.x * n.z);
    e += c[8].rgb * (0.546274 * (n.x * n.x - n.y * n.y));
    return max(e, vec3(0.0));
}

#endif
