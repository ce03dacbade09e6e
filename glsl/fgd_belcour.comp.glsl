#version 460
// The 4-channel table of Belcour, Bati & Barla 2020 (ALGORITHMS.md §7.4): for view cosine μ
// and GGX α, L_k(μ, α) = ∫ b_k(ω_i·h) D(h) G2(ω_i, ω_o) / (4μ) dω_o with b_0 = 1 and the
// basis functions b_1..b_3 of the host's fit (src/tables/belcour.rs), tabulated at
// BASIS_POINTS cosines uniform on [0, 1] and interpolated linearly. Texel (i, j) holds
// μ = (i + ½)/n and r = √α = (j + ½)/n, like the split-sum table. Visible-normal sampling,
// weight G2/G1 (the G2 form of the G2_MODE constant). The host folds the projection into the
// channels before upload.
#include "shared/kernel.glsl"
#include "lib/sampling.glsl"
#include "lib/microfacet.glsl"

layout(set = 0, binding = 0, std430) writeonly buffer Table {
    vec4 texels[];
} table;
// b_1, b_2, b_3 one after the other, `basis_points` values each.
layout(set = 0, binding = 1, std430) readonly buffer Basis {
    float values[];
} basis_table;

layout(push_constant) uniform Push {
    uint size;
    uint sample_count;
    uint basis_points;
} push;

float basis_at(uint k, float c) {
    float f = clamp(c, 0.0, 1.0) * float(push.basis_points - 1u);
    uint i0 = min(uint(f), push.basis_points - 2u);
    uint o = (k - 1u) * push.basis_points;
    return mix(basis_table.values[o + i0], basis_table.values[o + i0 + 1u], f - float(i0));
}

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

    vec4 sum = vec4(0.0);
    for (uint i = 0u; i < push.sample_count; ++i) {
        vec3 h;
        float w = vndf_reflection(v, hammersley(i, push.sample_count), alpha, g1_v, h);
        if (w == 0.0) {
            continue;
        }
        float c = dot(v, h);
        sum += w * vec4(1.0, basis_at(1u, c), basis_at(2u, c), basis_at(3u, c));
    }
    table.texels[id.y * push.size + id.x] = sum / float(push.sample_count);
}
