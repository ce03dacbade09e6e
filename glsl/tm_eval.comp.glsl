#version 460
// Evaluates the model at given view cosines for one stack: the GPU side of `lamina eval
// --backend gpu` and of the GPU-vs-CPU tests. Same library code as the forward pass.
// Output per sample, `stride` vec4s: (R, lobe count), (T, retro mask), (the transmitted
// lobe's α, then where a lobe is LOBE_FRESNEL its interface's η and albedo A and its index,
// else 0, 0, 0), then (weight, α) per lobe; the retro mask's bits (bit k: lobe k is lit around the view, LOBE_RETRO; the first 32
// lobes) are stored as the float's bits. With `lit`, each sample also carries a light direction
// l (the normal is +z, the view (√(1 − μ²), 0, μ)) and a lobe's slot holds, in place of its
// weight, its response to a unit irradiance from l (weight × lib/light.glsl's light_lobe at
// the lobe's shading roughness for a light of angular radius `angular_radius`).
#include "shared/variant.glsl"
#include "bindings/shading.glsl"

layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID) in;

layout(set = 1, binding = 0, std430) readonly buffer Samples {
    vec4 cos_and_light[];  // x: μ; yzw: l (with `lit`)
} samples;
layout(set = 1, binding = 1, std430) writeonly buffer Results {
    vec4 values[];
} results;

layout(push_constant) uniform Push {
    uint sample_count;
    uint stride;
    uint lit;
    float angular_radius;
} push;

#include "lib/tm2.glsl"
#include "lib/tm6.glsl"
#include "lib/light.glsl"

// Where tm_emit_lobe writes: the sample's first lobe slot and how many are filled.
uint eval_first_lobe;
uint eval_lobes;
uint eval_retro;
float eval_mu;
vec3 eval_light;
vec3 eval_top;

void tm_emit_lobe(vec3 weight, float alpha, uint kind, vec2 top) {
    if (kind == LOBE_FRESNEL) {
        eval_top = vec3(top, float(eval_lobes));
    }
    if (eval_lobes < TM_MAX_LOBES) {
        vec3 value = weight;
        if (push.lit != 0u && kind == LOBE_DIFFUSE) {
            // Lambertian: E·max(n·l, 0)/π, which integrates to 1 over the light directions.
            value *= max(eval_light.z, 0.0) * INV_PI;
        } else if (push.lit != 0u) {
            vec3 v = vec3(sqrt(max(1.0 - eval_mu * eval_mu, 0.0)), 0.0, eval_mu);
            float a = light_alpha(alpha, push.angular_radius);
            value *= light_lobe(vec3(0.0, 0.0, 1.0), v, eval_mu, eval_light, a,
                                kind == LOBE_RETRO, top);
        }
        // A diffuse lobe reads back with α = −1 (render/eval.rs).
        results.values[eval_first_lobe + eval_lobes] =
            vec4(value, kind == LOBE_DIFFUSE ? -1.0 : alpha);
    }
    if (kind == LOBE_RETRO && eval_lobes < 32u) {
        eval_retro |= 1u << eval_lobes;
    }
    eval_lobes++;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.sample_count) {
        return;
    }
    uint base = i * push.stride;
    eval_first_lobe = base + 3u;
    eval_lobes = 0u;
    eval_retro = 0u;
    eval_top = vec3(0.0);
    vec3 reflectance;
    vec3 transmittance;
    float transmitted_alpha;
    vec4 sample_i = samples.cos_and_light[i];
    float mu = sample_i.x;
    eval_mu = mu;
    eval_light = sample_i.yzw;
    uint count = MODEL == MODEL_TM6
        ? tm6_evaluate(mu, reflectance, transmittance, transmitted_alpha)
        : tm2_evaluate(mu, reflectance, transmittance, transmitted_alpha);
    results.values[base] = vec4(reflectance, float(count));
    results.values[base + 1u] = vec4(transmittance, uintBitsToFloat(eval_retro));
    results.values[base + 2u] = vec4(transmitted_alpha, eval_top);
}
