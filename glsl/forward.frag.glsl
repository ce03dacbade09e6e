#version 460
// The shaded pass. Every lobe is lit by one pre-filtered environment fetch along its dominant
// direction, weighted by its energy (split sum per lobe, ALGORITHMS.md §8.2):
//   L = Σ_k e_k · L̃(dir_k, α_k).
// MODEL = ggx: one GGX lobe of the top layer, energy F0·A + B (Karis 2013) — the yardstick
// every transfer-matrix variant is divided by. MODEL = tm2 / tm6: the lobes of the
// transfer-matrix model (lib/tm2.glsl, lib/tm6.glsl), or under MODE_BAKED the material's lobes
// read from its table (bindings/shading.glsl's baked_lobes) at the view cosine.
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "bindings/scene.glsl"

#include "lib/ibl.glsl"
#include "lib/tm2.glsl"
#include "lib/tm6.glsl"

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 0) out vec4 color;

// Pre-filtered radiance of a lobe of roughness α around `r` (the view for back-scatter).
vec3 lobe_radiance(vec3 n, vec3 r, float alpha) {
    vec3 dir = ibl_dominant_direction(n, r, alpha);
    return textureLod(prefiltered, dir, ibl_mip_of_alpha(alpha, frame.params.x)).rgb;
}

vec3 shade_ggx(vec3 n, vec3 v, float n_dot_v) {
    LayerGpu top = tm_layer(0u);
    float alpha = top.params.x;
    vec2 ab = texture(split_sum, vec2(n_dot_v, sqrt(alpha))).rg;
    real3 f0 = real3(f0_complex(top.ior.rgb, top.kappa.rgb));
    real3 albedo = f0 * real(ab.x) + real(ab.y);
    return vec3(real3(lobe_radiance(n, reflect(-v, n), alpha)) * albedo);
}

// The point being shaded, for tm_emit_lobe: the models emit their lobes one by one and each
// is lit as it comes.
vec3 shade_n;
vec3 shade_v;
vec3 shade_sum;

void tm_emit_lobe(vec3 weight, float alpha, uint kind) {
    vec3 around = kind == LOBE_RETRO ? shade_v : reflect(-shade_v, shade_n);
    shade_sum += weight * lobe_radiance(shade_n, around, alpha);
}

vec3 shade_lobes(vec3 n, vec3 v, float n_dot_v) {
    shade_n = n;
    shade_v = v;
    shade_sum = vec3(0.0);
    vec3 reflectance;
    vec3 transmittance;
    if (MODEL == MODEL_TM6) {
        tm6_evaluate(n_dot_v, reflectance, transmittance);
    } else {
        tm2_evaluate(n_dot_v, reflectance, transmittance);
    }
    return shade_sum;
}

// The baked lobes at the view cosine: each lobe's (weight, √α) interpolated linearly between
// its two samples around √μ by the sampler (render/baked.rs), then lit like the model's
// (lobe_radiance, with the mip read off √α directly). The row coordinate is a texel centre, so
// the filter's weight on the neighbouring lobe is zero.
vec3 shade_baked(vec3 n, vec3 v, float n_dot_v) {
    float u = (sqrt(n_dot_v) * float(BAKED_SIZE - 1u) + 0.5) / float(BAKED_SIZE);
    vec3 mirror = reflect(-v, n);
    vec3 sum = vec3(0.0);
    [[unroll]] for (uint k = 0u; k < LOBE_COUNT; ++k) {
        vec4 lobe = textureLod(baked_lobes, vec2(u, (float(k) + 0.5) / float(LOBE_COUNT)), 0.0);
        // .a is the perceptual roughness √α, the cube's mip axis.
        vec3 dir = ibl_dominant_direction(n, tm_bit(RETRO_MASK, k) ? v : mirror, lobe.a * lobe.a);
        sum += lobe.rgb * textureLod(prefiltered, dir, lobe.a * (frame.params.x - 1.0)).rgb;
    }
    return sum;
}

void main() {
    vec3 n = normalize(world_normal);
    vec3 v = normalize(frame.camera_pos.xyz - world_position);
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 radiance;
    if (MODEL == MODEL_GGX) {
        radiance = shade_ggx(n, v, n_dot_v);
    } else if (MODE == MODE_BAKED) {
        radiance = shade_baked(n, v, n_dot_v);
    } else {
        radiance = shade_lobes(n, v, n_dot_v);
    }
    color = vec4(radiance, 1.0);
}
