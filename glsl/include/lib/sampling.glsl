// Low-discrepancy points and GGX sampling for precomputation passes.
#ifndef LAMINA_LIB_SAMPLING
#define LAMINA_LIB_SAMPLING

#include "math.glsl"
#include "microfacet.glsl"

// Hammersley point i of n (radical inverse in base 2).
vec2 hammersley(uint i, uint n) {
    return vec2((float(i) + 0.5) / float(n), float(bitfieldReverse(i)) * 2.3283064365386963e-10);
}

// GGX half-vector sampling proportional to D(h)·cos θ_h (Walter et al. 2007), tangent space.
vec3 sample_ggx_ndf(vec2 u, float alpha) {
    float a2 = alpha * alpha;
    float cos2 = (1.0 - u.x) / (1.0 + (a2 - 1.0) * u.x);
    float cos_t = sqrt(cos2);
    float sin_t = sqrt(max(0.0, 1.0 - cos2));
    float phi = TWO_PI * u.y;
    return vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of Visible Normals"),
// tangent space, view v with v.z > 0. pdf of the reflected direction: G1(v)·D(h)/(4 v.z).
vec3 sample_ggx_vndf(vec3 v, vec2 u, float alpha) {
    vec3 vh = normalize(vec3(alpha * v.x, alpha * v.y, v.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = len2 > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(len2) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = TWO_PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

// One visible-normal sample of the GGX reflection of the view v (tangent space, v.z > 0, whose
// G1 is `g1_v`) at point u: the half vector `h`, and the weight G2(v, l)/G1(v) by which the
// reflected direction l = reflect(−v, h) enters an estimate of the directional albedo
// ∫ F·G2·D/(4 v.z) dl = E[F(v·h)·G2/G1] (Heitz 2018); 0 when l is below the horizon.
float vndf_reflection(vec3 v, vec2 u, float alpha, float g1_v, out vec3 h) {
    h = sample_ggx_vndf(v, u, alpha);
    vec3 l = reflect(-v, h);
    return l.z <= 0.0 ? 0.0 : float(masking_shadowing(real(v.z), real(l.z), real(alpha))) / g1_v;
}

// An orthonormal basis around n (Duff et al. 2017).
mat3 basis(vec3 n) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    vec3 bt = vec3(b, s + n.y * n.y * a, -n.y);
    return mat3(t, bt, n);
}

#endif
