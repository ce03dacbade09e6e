#version 460
// The shaded pass. Every lobe is lit by one pre-filtered environment fetch along its dominant
// direction, weighted by its energy (split sum per lobe, ALGORITHMS.md §8.2), at the scene's
// scale s of the environment, and by each analytic light j of irradiance E_j from l_j as the
// normalised microfacet lobe of its roughness (lib/light.glsl, src/model/light.rs):
//   L = Σ_k e_k · (s·L̃(dir_k, α_k) + Σ_j E_j · f̂_k(l_j, v)).
// MODEL = ggx: one GGX lobe of the top layer, energy F0·A + B (Karis 2013) — the yardstick
// every transfer-matrix variant is divided by. MODEL = tm2 / tm6: the lobes of the
// transfer-matrix model (lib/tm2.glsl, lib/tm6.glsl), or under MODE_BAKED the material's lobes
// read from its table (bindings/shading.glsl's baked_lobes) at the view cosine.
// This entry point has texture coordinates: the models read a varying stack's maps.
#define TM_SURFACE_MAPS
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "bindings/scene.glsl"

#include "lib/ibl.glsl"
#include "lib/light.glsl"
#include "lib/tm2.glsl"
#include "lib/tm6.glsl"

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 surface_uv;
layout(location = 0) out vec4 color;

// The point being shaded: the models emit their lobes one by one (tm_emit_lobe) and each is
// lit as it comes.
vec3 shade_p;
vec3 shade_n;
vec3 shade_v;
float shade_n_dot_v;
vec3 shade_sum;

// Pre-filtered radiance of a lobe of roughness α around `r` (the view for back-scatter).
vec3 lobe_radiance(vec3 n, vec3 r, float alpha) {
    vec3 dir = ibl_dominant_direction(n, r, alpha);
    return textureLod(prefiltered, dir, ibl_mip_of_alpha(alpha, frame.params.x)).rgb;
}

// Light j at the point: its direction `l` and the irradiance it brings normal to it.
vec3 light_at(uint j, out vec3 l) {
    LightGpu light = lights[j];
    l = light.position.xyz;
    vec3 irradiance = light.radiance.rgb;
    if (light.position.w != 0.0) {
        vec3 to_light = light.position.xyz - shade_p;
        float d2 = max(dot(to_light, to_light), 1e-8);
        l = to_light * inversesqrt(d2);
        irradiance /= d2;
    }
    return irradiance;
}

// What the analytic lights send back through a lobe of unit weight and roughness α.
vec3 lobe_lights(float alpha, bool retro) {
    vec3 sum = vec3(0.0);
    // LIGHTS = 0: a scene without lights compiles none of this (lavapipe compiles and runs
    // every path a constant does not remove).
    uint count = LIGHTS != 0u ? light_info.x : 0u;
    for (uint j = 0u; j < count; ++j) {
        vec3 l;
        vec3 irradiance = light_at(j, l);
        float a = light_alpha(alpha, lights[j].radiance.w);
        sum += irradiance * light_lobe(shade_n, shade_v, shade_n_dot_v, l, a, retro);
    }
    return sum;
}

// What a Lambertian lobe of unit weight sends back (src/model/diffuse.rs): the irradiance at
// the point over π — the lights' E·max(n·l, 0), and the environment's, cosine-convolved
// (its order-2 spherical harmonics, tables::environment::irradiance_sh).
vec3 diffuse_light() {
    vec3 sum = vec3(0.0);
    uint count = LIGHTS != 0u ? light_info.x : 0u;
    for (uint j = 0u; j < count; ++j) {
        vec3 l;
        vec3 irradiance = light_at(j, l);
        sum += irradiance * max(dot(shade_n, l), 0.0);
    }
    float scale = frame.params.y;
    if (scale > 0.0) {
        sum += scale * ibl_irradiance(shade_n, frame.irradiance);
    }
    return sum * INV_PI;
}

// A lobe's radiance: the environment's, scaled, and the lights'.
vec3 lobe_light(vec3 around, float alpha, bool retro) {
    vec3 sum = lobe_lights(alpha, retro);
    float scale = frame.params.y;
    if (scale > 0.0) {
        sum += scale * lobe_radiance(shade_n, around, alpha);
    }
    return sum;
}

void shade_begin(vec3 p, vec3 n, vec3 v, float n_dot_v) {
    shade_p = p;
    shade_n = n;
    shade_v = v;
    shade_n_dot_v = n_dot_v;
    shade_sum = vec3(0.0);
}

vec3 shade_ggx(vec3 n, vec3 v, float n_dot_v) {
    LayerGpu top = tm_layer(0u);
    float alpha = top.params.x;
    vec2 ab = texture(split_sum, vec2(n_dot_v, sqrt(alpha))).rg;
    real3 f0 = real3(f0_complex(top.ior.rgb, top.kappa.rgb));
    real3 albedo = f0 * real(ab.x) + real(ab.y);
    return vec3(real3(lobe_light(reflect(-v, n), alpha, false)) * albedo);
}

void tm_emit_lobe(vec3 weight, float alpha, uint kind) {
    if (kind == LOBE_DIFFUSE) {
        shade_sum += weight * diffuse_light();
        return;
    }
    bool retro = kind == LOBE_RETRO;
    vec3 around = retro ? shade_v : reflect(-shade_v, shade_n);
    shade_sum += weight * lobe_light(around, alpha, retro);
}

vec3 shade_lobes(vec3 n, vec3 v, float n_dot_v) {
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
        float alpha = lobe.a * lobe.a;
        bool retro = tm_bit(RETRO_MASK, k);
        vec3 dir = ibl_dominant_direction(n, retro ? v : mirror, alpha);
        vec3 radiance = lobe_lights(alpha, retro);
        if (frame.params.y > 0.0) {
            float mip = lobe.a * (frame.params.x - 1.0);
            radiance += frame.params.y * textureLod(prefiltered, dir, mip).rgb;
        }
        sum += lobe.rgb * radiance;
    }
    return sum;
}

void main() {
    vec3 n = normalize(world_normal);
    vec3 v = normalize(frame.camera_pos.xyz - world_position);
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    shade_begin(world_position, n, v, n_dot_v);
    if (SURFACE_MAPS != 0u) {
        tm_surface_begin(surface_uv, gl_FragCoord.xy);
    }
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
