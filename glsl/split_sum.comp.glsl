#version 460
// The 2-channel split-sum table (Karis 2013): for view cosine μ and GGX α,
//   A = ∫ (1 − F_c) f/F cos dω,   B = ∫ F_c f/F cos dω,   F_c = (1 − v·h)^5,
// so that ∫ f cos = F0·A + B. Texel (i, j) holds μ = (i + ½)/n and r = √α = (j + ½)/n.
// Estimated with visible-normal sampling: the weight of a sample is G2(v, l)/G1(v)
// (ALGORITHMS.md §10.3), with the G2 form of the G2_MODE constant.
#include "shared/kernel.glsl"
#include "lib/sampling.glsl"
#include "lib/microfacet.glsl"
#include "lib/fresnel.glsl"

layout(set = 0, binding = 0, std430) writeonly buffer Table {
    vec2 texels[];
} table;

layout(push_constant) uniform Push {
    uint size;
    uint sample_count;
} push;

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (id.x >= push.size || id.y >= push.size) {
        return;
    }
    float mu = (float(id.x) + 0.5) / float(push.size);
    float r = (float(id.y) + 0.5) / float(push.size);
    float alpha = r * r;
    vec3 v = vec3(sqrt(1.0 - mu * mu), 0.0, mu);
    float g1_v = masking_g1(mu, alpha);

    vec2 sum = vec2(0.0);
    for (uint i = 0u; i < push.sample_count; ++i) {
        vec3 h;
        float w = vndf_reflection(v, hammersley(i, push.sample_count), alpha, g1_v, h);
        if (w == 0.0) {
            continue;
        }
        float fc = schlick_weight(dot(v, h));
        sum += vec2((1.0 - fc) * w, fc * w);
    }
    table.texels[id.y * push.size + id.x] = sum / float(push.sample_count);
}
