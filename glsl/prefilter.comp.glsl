#version 460
// GGX pre-filtered radiance for one mip of the environment cube (Karis 2013, with N = V = R),
// importance-sampling D and reading a source mip chosen from the sample's pdf (Colbert &
// Křivánek 2007, "GPU-Based Importance Sampling") so few samples give a smooth result.
// `matched` = 0: Karis's weights n·l and his source mip one level blurrier than the sample's
// solid angle. `matched` = 1 (tables::environment's matched cube): the lobe's own weights —
// its BRDF times the cosine, D·G2/4 at normal view, over the samples' pdf D/4 — and the
// source mip of the solid angle itself.
#include "shared/kernel.glsl"
#include "lib/cubemap.glsl"
#include "lib/sampling.glsl"
#include "lib/microfacet.glsl"
#include "lib/ibl.glsl"

layout(set = 0, binding = 0) uniform samplerCube source;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray destination;

layout(push_constant) uniform Push {
    float alpha;
    uint source_size;
    uint destination_size;
    uint sample_count;
    uint matched;
} push;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= push.destination_size || id.y >= push.destination_size) {
        return;
    }
    vec2 uv = (vec2(id.xy) + 0.5) / float(push.destination_size);
    vec3 n = cube_direction(id.z, uv);
    mat3 frame = basis(n);
    float texel_solid_angle = 4.0 * PI / (6.0 * float(push.source_size * push.source_size));

    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint i = 0u; i < push.sample_count; ++i) {
        vec3 h = frame * sample_ggx_ndf(hammersley(i, push.sample_count), push.alpha);
        vec3 l = reflect(-n, h);
        float n_dot_l = dot(n, l);
        if (n_dot_l <= 0.0) {
            continue;
        }
        // With N = V, pdf(l) = D(h)·cos θ_h / (4 v·h) = D(h) / 4.
        float pdf = ggx_d(clamp(dot(n, h), 0.0, 1.0), push.alpha) * 0.25;
        float sample_solid_angle = 1.0 / (float(push.sample_count) * pdf + 1e-6);
        float bias = push.matched != 0u ? 0.0 : 1.0;
        float lod = max(0.5 * log2(sample_solid_angle / texel_solid_angle) + bias, 0.0);
        // G2 in the height-correlated form at a normal view: 1 / (1 + Λ(l)).
        float w = push.matched != 0u ? 1.0 / (1.0 + ibl_lambda(n_dot_l, push.alpha)) : n_dot_l;
        sum += textureLod(source, l, lod).rgb * w;
        weight += w;
    }
    imageStore(destination, ivec3(id), vec4(sum / max(weight, 1e-6), 1.0));
}
