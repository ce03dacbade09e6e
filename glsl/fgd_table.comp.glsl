#version 460
// FGD(μ, α, η, κ) = ∫ F(ω_i·h; η, κ) D(h) G2(ω_i, ω_o) / (4μ) dω_o on a vertex-centred grid
// (ALGORITHMS.md §6.1): texel (i, j, k, l) holds μ = i/(n_μ−1), α = j/(n_α−1),
// η = mix(η_min, η_max, k/(n_η−1)), κ = mix(κ_min, κ_max, l/(n_κ−1)); μ = 0 is evaluated at
// 1e-3. Behind `fgd=4d`, `fgd=resampled4d` (n⁴ over η, κ ∈ [0, 4]) and the η < 1 dielectric
// table of `fgd=belcour` (n³, κ = 0). Layout: μ fastest, then α, η, κ.
//
// Visible-normal sampling of h with Hammersley points, weight G2/G1 (the G2 form of the
// G2_MODE constant). The samples depend on (μ, α) only, so a work group (one μ, one α, one κ,
// every η) draws them once into shared memory and each invocation sums F over them.
#include "shared/kernel.glsl"
#include "lib/sampling.glsl"
#include "lib/microfacet.glsl"
#include "lib/fresnel.glsl"

#define MAX_SAMPLES 1024u

layout(set = 0, binding = 0, std430) writeonly buffer Table {
    float texels[];
} table;

// One dispatch fills the κ slices l0 .. l0 + depth (the host splits the table for progress).
layout(push_constant) uniform Push {
    uvec4 dims;
    vec4 range;   // η_min, η_max, κ_min, κ_max
    uint sample_count;
    uint l0;
} push;

shared float sample_cos[MAX_SAMPLES];
shared float sample_weight[MAX_SAMPLES];

float axis_value(uint index, uint n, float lo, float hi) {
    return n > 1u ? mix(lo, hi, float(index) / float(n - 1u)) : lo;
}

void main() {
    uvec4 n = push.dims;
    uint k = gl_GlobalInvocationID.x;
    uint i = gl_WorkGroupID.y;
    uint j = gl_WorkGroupID.z % n.y;
    uint l = push.l0 + gl_WorkGroupID.z / n.y;
    float mu = max(axis_value(i, n.x, 0.0, 1.0), 1e-3);
    float alpha = axis_value(j, n.y, 0.0, 1.0);
    vec3 v = vec3(sqrt(1.0 - mu * mu), 0.0, mu);
    uint count = min(push.sample_count, MAX_SAMPLES);

    float g1_v = masking_g1(mu, alpha);
    for (uint s = gl_LocalInvocationID.x; s < count; s += gl_WorkGroupSize.x) {
        vec3 h;
        sample_weight[s] = vndf_reflection(v, hammersley(s, count), alpha, g1_v, h);
        sample_cos[s] = clamp(dot(v, h), 0.0, 1.0);
    }
    barrier();

    if (k >= n.z || l >= n.w) {
        return;
    }
    float eta = axis_value(k, n.z, push.range.x, push.range.y);
    float kappa = axis_value(l, n.w, push.range.z, push.range.w);
    float value;
    if (alpha == 0.0) {
        value = fresnel_conductor(mu, eta, kappa);
    } else {
        float sum = 0.0;
        for (uint s = 0u; s < count; ++s) {
            sum += fresnel_conductor(sample_cos[s], eta, kappa) * sample_weight[s];
        }
        value = sum / float(count);
    }
    table.texels[((l * n.z + k) * n.y + j) * n.x + i] = value;
}
