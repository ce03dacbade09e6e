#version 460
// The shaded pass. Every lobe is lit by the environment as the variant's `ibl` integrates it
// (lobe_radiance; `split-sum`, the talk's: one prefiltered fetch along its dominant direction),
// weighted by its energy (ALGORITHMS.md §8.2), at the scene's scale s of the environment, and
// by each analytic light j of irradiance E_j from l_j as the normalised microfacet lobe of its
// roughness (lib/light.glsl, src/model/light.rs):
//   L = Σ_k e_k · (s·L̃(dir_k, α_k) + Σ_j E_j · f̂_k(l_j, v)).
// MODEL = ggx: one GGX lobe of the top layer, energy F0·A + B (Karis 2013) — the yardstick
// every transfer-matrix variant is divided by. MODEL = tm2 / tm6: the lobes of the
// transfer-matrix model (lib/tm2.glsl, lib/tm6.glsl), or under MODE_BAKED the material's lobes
// read from its table (bindings/shading.glsl's baked_lobes) at the view cosine.
// A stack that transmits (TRANSMITS) is a thin slab: its base's back face is parallel to the
// stack, so what it transmits leaves along the direction it entered and the pixel sees, through
// the transmitted lobe (weight T, roughness lib/tm_common.glsl's tm_transmitted_alpha), the
// environment and lights behind the surface around the view's continuation −v. That lobe is the
// mirror image, in the tangent plane, of a reflection lobe about reflect(−v, n), and is lit as
// one, with the directions it reads mirrored (shade_behind).
// This entry point has texture coordinates: the models read a varying stack's maps.
#define TM_SURFACE_MAPS
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "bindings/scene.glsl"

#include "lib/ibl.glsl"
#include "lib/light.glsl"
#include "lib/sampling.glsl"
#include "lib/tm2.glsl"
#include "lib/tm6.glsl"

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 surface_uv;
layout(location = 0) out vec4 color;
// A varying stack under a per-material mode draws once per class of pixels, each draw
// shading only its own (the stencil test, src/render/classes.rs): tested before shading.
layout(early_fragment_tests) in;

// The point being shaded: the models emit their lobes one by one (tm_emit_lobe) and each is
// lit as it comes.
vec3 shade_p;
vec3 shade_n;
vec3 shade_v;
float shade_n_dot_v;
vec3 shade_sum;

// The mirror image of direction `d` in the tangent plane of normal `n`: where a lobe that
// transmits through a thin slab reads what a reflection lobe would read at `d`.
vec3 shade_behind(vec3 n, vec3 d) {
    return d - 2.0 * dot(n, d) * n;
}

// One fetch of the environment for a lobe of roughness α around `r` (`behind`: mirrored):
// `ibl=split-sum`, Karis's cube along Lagarde's dominant direction at the lobe's own mip; the
// others, the matched cube along the lobe's mean direction at the mip of its spread
// (lib/ibl.glsl's ibl_lobe_moments). A mirror lobe reads mip 0 along `r` either way.
vec3 lobe_fetch(vec3 n, vec3 r, float alpha, bool behind) {
    vec3 dir;
    float mip;
    if (alpha <= IBL_MIN_ALPHA) {
        dir = r;
        mip = 0.0;
    } else if (IBL == IBL_SPLIT_SUM) {
        dir = ibl_dominant_direction(n, r, alpha);
        mip = ibl_mip_of_alpha(alpha, frame.params.x);
    } else {
        vec2 moments = ibl_lobe_moments(lobe_moments, dot(n, r), alpha);
        dir = mix(r, n, moments.x);
        mip = ibl_mip_of_alpha(moments.y * moments.y, frame.params.x);
    }
    dir = behind ? shade_behind(n, dir) : dir;
    return IBL == IBL_SPLIT_SUM ? textureLod(prefiltered, dir, mip).rgb
                                : textureLod(matched, dir, mip).rgb;
}

// ibl=taps: filtered importance sampling of the lobe (Křivánek & Colbert 2008, "Real-time
// shading with filtered importance sampling"): IBL_TAP_COUNT directions l_i through the
// visible normals of the GGX lobe about the view whose mirror image is `r` (Heitz 2018), each
// read from the matched cube blurred over its share of the lobe — the solid angle
// 1/(count·pdf(l_i)) taken as a GGX lobe's 4πα² — and weighted by G2/G1, which with the
// visible normals' pdf G1·D/(4 v.z) makes Σ w_i L_i / Σ w_i the lobe's average radiance
// (ALGORITHMS.md §8.2). A mirror lobe, or a view at the horizon, is one fetch.
vec3 lobe_taps(vec3 n, vec3 r, float alpha, bool behind) {
    mat3 frame_of_n = basis(n);
    vec3 v = transpose(frame_of_n) * reflect(-r, n);
    if (alpha <= IBL_MIN_ALPHA || v.z <= 1e-4) {
        return lobe_fetch(n, r, alpha, behind);
    }
    // G2/G1 in the height-correlated form the reference's lobes take.
    float masked = 1.0 + ibl_lambda(v.z, alpha);
    float g1 = 1.0 / masked;
    float mips = frame.params.x;
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (uint i = 0u; i < IBL_TAP_COUNT; ++i) {
        vec3 h = sample_ggx_vndf(v, hammersley(i, IBL_TAP_COUNT), alpha);
        vec3 l = reflect(-v, h);
        if (l.z <= 0.0) {
            continue;
        }
        float w = masked / (masked + ibl_lambda(l.z, alpha));
        float pdf = g1 * ibl_ggx_d(h.z, alpha) / (4.0 * v.z);
        float share = 1.0 / (float(IBL_TAP_COUNT) * pdf);
        vec3 d = frame_of_n * l;
        d = behind ? shade_behind(n, d) : d;
        sum += w * textureLod(matched, d, ibl_mip_of_alpha(sqrt(share / (4.0 * PI)), mips)).rgb;
        total += w;
    }
    return total > 0.0 ? sum / total : lobe_fetch(n, r, alpha, behind);
}

// The environment's radiance through a lobe of roughness α around `r` (the view for
// back-scatter), or with `behind` through the transmitted lobe mirrored from it, as the
// variant's `ibl` integrates it.
vec3 lobe_radiance(vec3 n, vec3 r, float alpha, bool behind) {
    return IBL == IBL_TAPS ? lobe_taps(n, r, alpha, behind) : lobe_fetch(n, r, alpha, behind);
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

// What the analytic lights send back through a lobe of unit weight and roughness α (`behind`:
// send through the transmitted lobe, from behind the surface).
vec3 lobe_lights(float alpha, bool retro, bool behind) {
    vec3 sum = vec3(0.0);
    // LIGHTS = 0: a scene without lights compiles none of this (lavapipe compiles and runs
    // every path a constant does not remove).
    uint count = LIGHTS != 0u ? light_info.x : 0u;
    for (uint j = 0u; j < count; ++j) {
        vec3 l;
        vec3 irradiance = light_at(j, l);
        l = behind ? shade_behind(shade_n, l) : l;
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

// A lobe's radiance: the environment's, scaled, and the lights' (`behind`: the transmitted
// lobe's, mirrored from the reflection lobe around `around`).
vec3 lobe_light(vec3 around, float alpha, bool retro, bool behind) {
    vec3 sum = lobe_lights(alpha, retro, behind);
    float scale = frame.params.y;
    if (scale > 0.0) {
        sum += scale * lobe_radiance(shade_n, around, alpha, behind);
    }
    return sum;
}

// What a thin slab transmits towards the view through a lobe of weight `t` and roughness α.
vec3 transmitted_light(vec3 t, float alpha) {
    return t * lobe_light(reflect(-shade_v, shade_n), alpha, false, true);
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
    vec3 radiance = vec3(real3(lobe_light(reflect(-v, n), alpha, false, false)) * albedo);
    if (TRANSMITS != 0u) {
        // The baseline's top interface as a thin slab: what it does not reflect, through a
        // lobe of its roughness.
        radiance += transmitted_light(vec3(max(real3(1.0) - albedo, real3(0.0))), alpha);
    }
    return radiance;
}

void tm_emit_lobe(vec3 weight, float alpha, uint kind) {
    if (kind == LOBE_DIFFUSE) {
        shade_sum += weight * diffuse_light();
        return;
    }
    bool retro = kind == LOBE_RETRO;
    vec3 around = retro ? shade_v : reflect(-shade_v, shade_n);
    shade_sum += weight * lobe_light(around, alpha, retro, false);
}

vec3 shade_lobes(vec3 n, vec3 v, float n_dot_v) {
    vec3 reflectance;
    vec3 transmittance;
    float transmitted_alpha;
    if (MODEL == MODEL_TM6) {
        tm6_evaluate(n_dot_v, reflectance, transmittance, transmitted_alpha);
    } else {
        tm2_evaluate(n_dot_v, reflectance, transmittance, transmitted_alpha);
    }
    if (TRANSMITS != 0u) {
        shade_sum += transmitted_light(transmittance, transmitted_alpha);
    }
    return shade_sum;
}

// The baked lobes at the view cosine: each lobe's (weight, √α) interpolated linearly between
// its two samples around √μ by the sampler (render/baked.rs), then lit like the model's
// (lobe_light). The row coordinate is a texel centre, so the filter's weight on the
// neighbouring lobe is zero.
vec3 shade_baked(vec3 n, vec3 v, float n_dot_v) {
    float u = (sqrt(n_dot_v) * float(BAKED_SIZE - 1u) + 0.5) / float(BAKED_SIZE);
    vec3 mirror = reflect(-v, n);
    vec3 sum = vec3(0.0);
    [[unroll]] for (uint k = 0u; k < LOBE_COUNT; ++k) {
        vec4 lobe = textureLod(baked_lobes, vec2(u, (float(k) + 0.5) / float(LOBE_COUNT)), 0.0);
        // A diffuse base's lobe (.a = −1 at every sample, render/baked.rs): Lambertian.
        if (DIFFUSE_BASE != 0u && lobe.a < 0.0) {
            sum += lobe.rgb * diffuse_light();
            continue;
        }
        // .a is the perceptual roughness √α, the cube's mip axis.
        float alpha = lobe.a * lobe.a;
        // A thin slab's last row is its transmitted lobe, lit from behind (transmitted_light).
        bool behind = TRANSMITS != 0u && k + 1u == LOBE_COUNT;
        bool retro = !behind && tm_bit(RETRO_MASK, k);
        sum += lobe.rgb * lobe_light(retro ? v : mirror, alpha, retro, behind);
    }
    return sum;
}

#ifdef LAMINA_REFERENCE
#include "lib/equirect.glsl"
#include "lib/sampling.glsl"

// The reference image (`lamina render --reference`, src/render/reference.rs): each lobe of the
// f64 model (FGD and TIR integrated exactly, tabulated finely over the view cosine in
// baked_lobes: its weight divided by its white albedo E and √α, √α < 0 for a diffuse base's
// lobe, then E in the next row)
// integrated by Monte Carlo against the unfiltered environment (the cube's level 0) and the
// lights (a disk light over its disk): REFERENCE_SAMPLES iterations per lobe per frame, each
// one direction through the lobe and one from the environment's importance sampling
// (reference_environment), seeded by the pixel, the frame (frame.params.z) and the seed's
// stream (frame.params.w's bits, render::reference::stream); the host
// averages the frames. No split sum, no
// prefiltering, no FGD table.
const uint REFERENCE_SAMPLES = 16u;

uint reference_state;

// A 32-bit hash (PCG's output permutation of an LCG step).
uint reference_hash(uint x) {
    uint state = x * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform in [0, 1).
float reference_random() {
    reference_state = reference_hash(reference_state);
    return float(reference_state >> 8u) * (1.0 / 16777216.0);
}

// The lobe's response to a unit irradiance from l, times μ_l, before its 1/E (already in the
// table's weight): D·G2 / (4 μ_v), about `view` (the view, or its mirror image for a retro
// lobe).
float reference_lobe(vec3 n, vec3 view, vec3 l, float alpha) {
    float n_dot_l = dot(n, l);
    float n_dot_v = dot(n, view);
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) {
        return 0.0;
    }
    vec3 h = normalize(view + l);
    return ggx_d(max(dot(n, h), 0.0), alpha) * masking_shadowing(n_dot_l, n_dot_v, alpha)
        / (4.0 * n_dot_v);
}

// A direction within the cone of half-angle `radius` around `axis`, uniform in solid angle.
vec3 reference_cone(vec3 axis, float radius) {
    float cos_t = 1.0 - reference_random() * (1.0 - cos(radius));
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = TWO_PI * reference_random();
    return basis(axis) * vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// The lights through a lobe: `diffuse`, μ_l/π; else reference_lobe about `view` (`behind`:
// the transmitted lobe, lit from the mirrored directions). A disk light averages its cone.
vec3 reference_lights(vec3 n, vec3 view, float alpha, bool diffuse, bool behind) {
    vec3 sum = vec3(0.0);
    uint count = LIGHTS != 0u ? light_info.x : 0u;
    for (uint j = 0u; j < count; ++j) {
        vec3 centre;
        vec3 irradiance = light_at(j, centre);
        float radius = lights[j].radiance.w;
        uint samples = radius > 0.0 ? REFERENCE_SAMPLES : 1u;
        float value = 0.0;
        for (uint s = 0u; s < samples; ++s) {
            vec3 l = radius > 0.0 ? reference_cone(centre, radius) : centre;
            l = behind ? shade_behind(n, l) : l;
            value += diffuse ? max(dot(n, l), 0.0) * INV_PI : reference_lobe(n, view, l, alpha);
        }
        sum += irradiance * (value / float(samples));
    }
    return sum;
}

// The environment's density at direction d (solid angle) under its importance sampling
// (bindings/scene.glsl's EnvironmentSampling): the cell's probability over its solid angle.
float reference_env_pdf(vec3 d) {
    uvec2 grid = env_sampling_info.xy;
    vec2 uv = equirect_uv(d);
    uint i = min(uint(uv.y * float(grid.y)), grid.y - 1u);
    uint j = min(uint(uv.x * float(grid.x)), grid.x - 1u);
    // The CDFs' values before the cell, 0 for the first: indices clamped in bounds, since a
    // select reads both of its sides.
    float row = env_cdf[i] - env_cdf[max(i, 1u) - 1u] * float(i > 0u);
    uint base = grid.y + i * grid.x;
    float cell = env_cdf[base + j] - env_cdf[base + max(j, 1u) - 1u] * float(j > 0u);
    float sin_t = sqrt(max(0.0, 1.0 - d.y * d.y));
    return row * cell * float(grid.x * grid.y) / (2.0 * PI * PI * max(sin_t, 1e-6));
}

// The first index in [first, first + count) whose CDF value exceeds u (the last if none), by
// bisection in a fixed number of steps (count ≤ 2¹⁶): a data-dependent `while` nested in the
// caller's sample loop left lavapipe's fragments unwritten.
uint reference_search(uint first, uint count, float u) {
    uint lo = 0u;
    uint hi = count - 1u;
    for (uint step = 0u; step < 16u; ++step) {
        uint mid = (lo + hi) / 2u;
        bool above = env_cdf[first + mid] > u;
        hi = lo < hi && above ? mid : hi;
        lo = lo < hi && !above ? mid + 1u : lo;
    }
    return lo;
}

// A direction drawn from the environment's importance sampling: a row by its marginal CDF, a
// cell of it by the row's CDF, a point uniform in the cell's (u, v).
vec3 reference_env_sample() {
    uvec2 grid = env_sampling_info.xy;
    uint i = reference_search(0u, grid.y, reference_random());
    uint j = reference_search(grid.y + i * grid.x, grid.x, reference_random());
    vec2 uv = (vec2(j, i) + vec2(reference_random(), reference_random())) / vec2(grid);
    float phi = (uv.x - 0.5) * TWO_PI;
    float theta = uv.y * PI;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

// One sample's share under the balance heuristic: f·(L − c) / (pdf + the environment's pdf),
// for a direction either technique drew (f: the lobe's f·μ_l; pdf: the lobe's density there;
// `seen`: where the environment is read, the lobe's direction or its mirror image behind the
// surface; c: the control variate, reference_environment).
vec3 reference_mis(float f, float pdf, vec3 seen, vec3 c) {
    float both = pdf + reference_env_pdf(seen);
    return both > 0.0 ? f / both * (textureLod(prefiltered, seen, 0.0).rgb - c) : vec3(0.0);
}

// The unfiltered environment through a lobe of roughness α about `view` (`diffuse`: μ_l/π),
// by multiple importance sampling with the balance heuristic: per iteration one direction
// through the lobe's visible normals (cosine-distributed for a diffuse lobe) and one from the
// environment's importance sampling, each weighing f·μ_l / (pdf_lobe + pdf_env). A control
// variate c takes out what the lobe's samples would spend estimating its own integral E
// (which the table's weight already divides out): the estimate is c·E + Σ f·(L − c)/pdf,
// unbiased for any c constant over the samples, and c is the prefiltered environment along
// the lobe (the irradiance's over π for a diffuse lobe), so that only the environment's
// departure from its filtered value is sampled. Under a uniform environment it is exact.
// `behind`: the transmitted lobe, which reads the environment at the mirror images of the
// lobe's directions (and draws those mirror images from the environment's sampling).
vec3 reference_environment(vec3 n, vec3 view, float alpha, bool diffuse, bool behind,
                           float white) {
    mat3 frame_of_n = basis(n);
    vec3 v = transpose(frame_of_n) * view;
    if (!diffuse && v.z <= 0.0) {
        return vec3(0.0);
    }
    float g1 = 1.0 / (1.0 + smith_lambda(v.z, alpha));
    vec3 c = diffuse
        ? ibl_irradiance(n, frame.irradiance) * INV_PI
        : lobe_radiance(n, reflect(-view, n), alpha, behind);
    vec3 sum = vec3(0.0);
    for (uint s = 0u; s < REFERENCE_SAMPLES; ++s) {
        // Through the lobe.
        vec2 u = vec2(reference_random(), reference_random());
        vec3 l;
        if (diffuse) {
            float r = sqrt(u.x);
            float phi = TWO_PI * u.y;
            l = vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
        } else {
            l = reflect(-v, sample_ggx_vndf(v, u, alpha));
        }
        if (l.z > 0.0) {
            vec3 world = frame_of_n * l;
            float f = diffuse ? l.z * INV_PI : reference_lobe(n, view, world, alpha);
            float pdf = diffuse ? l.z * INV_PI : f * g1 / max(masking_shadowing(l.z, v.z, alpha), 1e-30);
            sum += reference_mis(f, pdf, behind ? shade_behind(n, world) : world, c);
        }
        // From the environment.
        vec3 seen = reference_env_sample();
        vec3 world = behind ? shade_behind(n, seen) : seen;
        float n_dot_l = dot(n, world);
        if (n_dot_l > 0.0) {
            float f;
            float pdf;
            if (diffuse) {
                f = n_dot_l * INV_PI;
                pdf = f;
            } else {
                vec3 h = normalize(view + world);
                float d = ggx_d(max(dot(n, h), 0.0), alpha);
                f = d * masking_shadowing(n_dot_l, v.z, alpha) / (4.0 * v.z);
                pdf = g1 * d / (4.0 * v.z);
            }
            sum += reference_mis(f, pdf, seen, c);
        }
    }
    return c * white + sum / float(REFERENCE_SAMPLES);
}

vec3 shade_reference(vec3 n, vec3 v, float n_dot_v) {
    float u = (sqrt(n_dot_v) * float(BAKED_SIZE - 1u) + 0.5) / float(BAKED_SIZE);
    vec3 sum = vec3(0.0);
    // Two rows per lobe (render/reference.rs): (weight / E, √α), then (E, behind, 0, 0), behind
    // 1 for the lobe a stack that transmits sends through (the last).
    float rows = float(2u * LOBE_COUNT);
    for (uint k = 0u; k < LOBE_COUNT; ++k) {
        vec4 lobe = textureLod(baked_lobes, vec2(u, (float(2u * k) + 0.5) / rows), 0.0);
        vec2 white = textureLod(baked_lobes, vec2(u, (float(2u * k) + 1.5) / rows), 0.0).rg;
        bool diffuse = lobe.a < 0.0;
        bool behind = white.y > 0.5;
        float alpha = lobe.a * lobe.a;
        vec3 view = tm_bit(RETRO_MASK, k) ? 2.0 * dot(n, v) * n - v : v;
        vec3 radiance = reference_lights(n, view, alpha, diffuse, behind);
        if (frame.params.y > 0.0) {
            radiance += frame.params.y
                * reference_environment(n, view, alpha, diffuse, behind, white.x);
        }
        sum += lobe.rgb * radiance;
    }
    return sum;
}
#endif

void main() {
    vec3 n = normalize(world_normal);
    vec3 v = normalize(frame.camera_pos.xyz - world_position);
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    shade_begin(world_position, n, v, n_dot_v);
    if (SURFACE_MAPS != 0u) {
        tm_surface_begin(surface_uv, gl_FragCoord.xy);
    }
    vec3 radiance;
#ifdef LAMINA_REFERENCE
    reference_state = reference_hash(uint(gl_FragCoord.x)
        ^ reference_hash(uint(gl_FragCoord.y)
        ^ reference_hash(uint(frame.params.z) ^ floatBitsToUint(frame.params.w))));
    radiance = shade_reference(n, v, n_dot_v);
#else
    if (MODEL == MODEL_GGX) {
        radiance = shade_ggx(n, v, n_dot_v);
    } else if (MODE == MODE_BAKED) {
        radiance = shade_baked(n, v, n_dot_v);
    } else {
        radiance = shade_lobes(n, v, n_dot_v);
    }
#endif
    color = vec4(radiance, 1.0);
}
