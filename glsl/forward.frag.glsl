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

#include "lib/shade.glsl"

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 surface_uv;
layout(location = 0) out vec4 color;
// A varying stack under a per-material mode draws once per class of pixels, each draw
// shading only its own (the stencil test, src/render/classes.rs): tested before shading.
layout(early_fragment_tests) in;

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
// (reference_environment), drawn by randomised quasi-Monte Carlo (reference_random2). The host
// averages the frames. No split sum, no prefiltering, no FGD table.
const uint REFERENCE_SAMPLES = 16u;

// The sampler's state. Sample k of an integral (k = frame × REFERENCE_SAMPLES + s, running on
// over the frames: frame.params.z) draws its pairs of numbers from one scrambled sequence per
// pair; a pixel's integrals (a lobe's environment, a lobe's disk light) are numbered in the
// order the pass begins them, which every frame repeats, so each keeps its sequence across
// frames. The scrambles are seeded by the pixel, the integral, the pair and the seed's stream
// (frame.params.w's bits, render::reference::stream).
uint reference_pixel;
uint reference_integrals;
uint reference_integral;
uint reference_index;
uint reference_pair;

// A 32-bit hash (PCG's output permutation of an LCG step).
uint reference_hash(uint x) {
    uint state = x * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Begins the pixel's next integral.
void reference_begin_integral() {
    reference_integral = reference_hash(reference_pixel ^ reference_hash(reference_integrals));
    reference_integrals += 1u;
}

// Begins sample `s` of this frame in the current integral.
void reference_begin_sample(uint s) {
    reference_index = uint(frame.params.z) * REFERENCE_SAMPLES + s;
    reference_pair = 0u;
}

// A random nested scramble of x's binary digits read as a fraction (most significant first):
// each digit flipped by a function of the seed and the digits before it (Owen 1995), done on
// the reversed bits by steps that change a bit only through the bits below it (an addition, a
// product by an odd number, xor with a product by an even one). Uniform in [0, 2³²) for a
// random seed; points of a (0, m, 2)-net stay a net. On an index it shuffles the sequence
// while keeping every aligned block of 2^m indices a block.
uint reference_scramble(uint x, uint seed) {
    x = bitfieldReverse(x);
    x += seed;
    x ^= x * 0x9e3779b8u;
    x *= reference_hash(seed) | 1u;
    x ^= x * 0x2c1b3c6cu;
    x += reference_hash(seed ^ 0x5bd1e995u);
    x ^= x * 0x297a2d38u;
    return bitfieldReverse(x);
}

// The second dimension of Sobol's sequence at index i: the XOR of the direction numbers of
// i's set bits, v₀ = 2³¹ and v_{j+1} = v_j ⊕ v_j/2 (primitive polynomial x + 1), so v_j's bit
// 31 − r is C(j, r) mod 2, 1 where r's bits are among j's (Lucas). Bit 31 − r of the sum is
// then the XOR of i's bits at the positions j ⊇ r: five steps of the superset transform, then
// the bits reversed. The first dimension is i's reversed bits (van der Corput).
uint reference_sobol1(uint i) {
    i ^= (i >> 1u) & 0x55555555u;
    i ^= (i >> 2u) & 0x33333333u;
    i ^= (i >> 4u) & 0x0f0f0f0fu;
    i ^= (i >> 8u) & 0x00ff00ffu;
    i ^= (i >> 16u) & 0x0000ffffu;
    return bitfieldReverse(i);
}

// The sample's next pair of numbers, uniform in [0, 1)²: the first two dimensions of Sobol's
// sequence at the sample's index, the index shuffled and both coordinates scrambled by seeds
// of the pair's own (Burley 2020, "Practical hash-based Owen scrambling"), so each pair is
// stratified over the frames so far and the pairs are independent of each other. Every point
// is uniform: the estimate stays unbiased, and two streams give independent images.
vec2 reference_random2() {
    uint seed = reference_hash(reference_integral ^ reference_hash(reference_pair));
    reference_pair += 1u;
    uint i = reference_scramble(reference_index, seed);
    uint x = reference_scramble(bitfieldReverse(i), reference_hash(seed ^ 0x68bc21ebu));
    uint y = reference_scramble(reference_sobol1(i), reference_hash(seed ^ 0x02e5be93u));
    return vec2(uvec2(x, y) >> 8u) * (1.0 / 16777216.0);
}

// The top interface's Fresnel factor F(v·h) at relative IOR η for a LOBE_FRESNEL lobe
// (lib/light.glsl's light_lobe), 1 for any other (η = 0).
float reference_fresnel(vec3 view, vec3 l, float eta) {
    return eta > 0.0 ? fresnel_dielectric(max(dot(view, normalize(view + l)), 0.0), eta) : 1.0;
}

// The lobe's response to a unit irradiance from l, times μ_l, before its 1/E (already in the
// table's weight): D·G2 / (4 μ_v), about `view` (the view, or its mirror image for a retro
// lobe), times reference_fresnel.
float reference_lobe(vec3 n, vec3 view, vec3 l, float alpha, float eta) {
    float n_dot_l = dot(n, l);
    float n_dot_v = dot(n, view);
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) {
        return 0.0;
    }
    vec3 h = normalize(view + l);
    return ggx_d(max(dot(n, h), 0.0), alpha) * masking_shadowing(n_dot_l, n_dot_v, alpha)
        / (4.0 * n_dot_v) * reference_fresnel(view, l, eta);
}

// A direction within the cone of half-angle `radius` around `axis`, uniform in solid angle.
vec3 reference_cone(vec3 axis, float radius) {
    vec2 u = reference_random2();
    float cos_t = 1.0 - u.x * (1.0 - cos(radius));
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = TWO_PI * u.y;
    return basis(axis) * vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// The lights through a lobe: `diffuse`, μ_l/π; else reference_lobe about `view` (`behind`:
// the transmitted lobe, lit from the mirrored directions; `eta`: reference_fresnel's). A disk
// light averages its cone.
vec3 reference_lights(vec3 n, vec3 view, float alpha, bool diffuse, bool behind, float eta) {
    vec3 sum = vec3(0.0);
    uint count = LIGHTS != 0u ? light_info.x : 0u;
    for (uint j = 0u; j < count; ++j) {
        vec3 centre;
        vec3 irradiance = light_at(j, centre);
        float radius = lights[j].radiance.w;
        uint samples = radius > 0.0 ? REFERENCE_SAMPLES : 1u;
        float value = 0.0;
        reference_begin_integral();
        for (uint s = 0u; s < samples; ++s) {
            reference_begin_sample(s);
            vec3 l = radius > 0.0 ? reference_cone(centre, radius) : centre;
            l = behind ? shade_behind(n, l) : l;
            value += diffuse ? max(dot(n, l), 0.0) * INV_PI
                             : reference_lobe(n, view, l, alpha, eta);
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
    vec2 cell = reference_random2();
    uint i = reference_search(0u, grid.y, cell.y);
    uint j = reference_search(grid.y + i * grid.x, grid.x, cell.x);
    vec2 uv = (vec2(j, i) + reference_random2()) / vec2(grid);
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
// lobe's directions (and draws those mirror images from the environment's sampling). `eta`:
// a LOBE_FRESNEL lobe's, whose f carries reference_fresnel and whose `white` is the albedo
// the model gave it (the integral of f, exactly so for the f64 model's).
vec3 reference_environment(vec3 n, vec3 view, float alpha, bool diffuse, bool behind,
                           float white, float eta) {
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
    reference_begin_integral();
    for (uint s = 0u; s < REFERENCE_SAMPLES; ++s) {
        reference_begin_sample(s);
        // Through the lobe.
        vec2 u = reference_random2();
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
            float lobe = diffuse ? l.z * INV_PI : reference_lobe(n, view, world, alpha, 0.0);
            float f = diffuse ? lobe : lobe * reference_fresnel(view, world, eta);
            float pdf = diffuse
                ? lobe
                : lobe * g1 / max(masking_shadowing(l.z, v.z, alpha), 1e-30);
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
                f = d * masking_shadowing(n_dot_l, v.z, alpha) / (4.0 * v.z)
                    * reference_fresnel(view, world, eta);
                pdf = g1 * d / (4.0 * v.z);
            }
            sum += reference_mis(f, pdf, seen, c);
        }
    }
    return c * white + sum / float(REFERENCE_SAMPLES);
}

#ifdef LAMINA_REFERENCE_EVALUATED
// The reference of a varying stack (render::reference::render_evaluated): each pixel's lobes
// are evaluated here, from its maps, by the shader library of the pass's variant (the models
// hand them to tm_emit_lobe one by one), and each is integrated as shade_reference integrates a
// tabulated one: its weight over the white lobe's albedo E (white_albedo, the table the
// lights normalise by, of the variant's G2), times its integral against the lights and the
// unfiltered environment. `behind`: a thin slab's transmitted lobe. `top` (LOBE_FRESNEL):
// the top interface's η and albedo A, which divides the lobe in place of E (light_lobe's).
void reference_emit(vec3 weight, float alpha, bool diffuse, bool retro, bool behind,
                    vec2 top) {
    float a = diffuse ? 1.0 : max(alpha, LIGHT_MIN_ALPHA);
    float white = diffuse ? 1.0 : (top.x > 0.0 ? top.y : white_albedo(shade_n_dot_v, a));
    if (white <= 0.0) {
        return;
    }
    vec3 view = retro ? 2.0 * dot(shade_n, shade_v) * shade_n - shade_v : shade_v;
    vec3 radiance = reference_lights(shade_n, view, a, diffuse, behind, top.x);
    if (frame.params.y > 0.0) {
        radiance += frame.params.y
            * reference_environment(shade_n, view, a, diffuse, behind, white, top.x);
    }
    shade_sum += weight / white * radiance;
}

void tm_emit_lobe(vec3 weight, float alpha, uint kind, vec2 top) {
    reference_emit(weight, alpha, kind == LOBE_DIFFUSE, kind == LOBE_RETRO, false, top);
}

// The pixel's lobes in the pass's model (model=ggx: shade_ggx's one lobe, F0·A + B from the
// split-sum table, and 1 − that through a thin slab), integrated as they come.
vec3 shade_reference_evaluated(vec3 n, vec3 v, float n_dot_v) {
    vec3 transmittance;
    float transmitted_alpha;
    if (MODEL == MODEL_GGX) {
        LayerGpu top = tm_layer(0u);
        transmitted_alpha = top.params.x;
        vec2 ab = texture(split_sum, vec2(n_dot_v, sqrt(transmitted_alpha))).rg;
        vec3 albedo = vec3(f0_complex(top.ior.rgb, top.kappa.rgb)) * ab.x + ab.y;
        reference_emit(albedo, transmitted_alpha, false, false, false, vec2(0.0));
        transmittance = max(vec3(1.0) - albedo, vec3(0.0));
    } else {
        vec3 reflectance;
        if (MODEL == MODEL_TM6) {
            tm6_evaluate(n_dot_v, reflectance, transmittance, transmitted_alpha);
        } else {
            tm2_evaluate(n_dot_v, reflectance, transmittance, transmitted_alpha);
        }
    }
    if (TRANSMITS != 0u) {
        reference_emit(transmittance, transmitted_alpha, false, false, true, vec2(0.0));
    }
    return shade_sum;
}
#else
vec3 shade_reference(vec3 n, vec3 v, float n_dot_v) {
    float u = (sqrt(n_dot_v) * float(BAKED_SIZE - 1u) + 0.5) / float(BAKED_SIZE);
    vec3 sum = vec3(0.0);
    // Two rows per lobe (render/reference.rs): (weight / E, √α), then (E, behind, η, 0), behind
    // 1 for the lobe a stack that transmits sends through (the last), η > 0 for a LOBE_FRESNEL
    // lobe (E then the top interface's albedo).
    float rows = float(2u * LOBE_COUNT);
    for (uint k = 0u; k < LOBE_COUNT; ++k) {
        vec4 lobe = textureLod(baked_lobes, vec2(u, (float(2u * k) + 0.5) / rows), 0.0);
        vec3 white = textureLod(baked_lobes, vec2(u, (float(2u * k) + 1.5) / rows), 0.0).rgb;
        bool diffuse = lobe.a < 0.0;
        bool behind = white.y > 0.5;
        float alpha = lobe.a * lobe.a;
        vec3 view = tm_bit(RETRO_MASK, k) ? 2.0 * dot(n, v) * n - v : v;
        vec3 radiance = reference_lights(n, view, alpha, diffuse, behind, white.z);
        if (frame.params.y > 0.0) {
            radiance += frame.params.y
                * reference_environment(n, view, alpha, diffuse, behind, white.x, white.z);
        }
        sum += lobe.rgb * radiance;
    }
    return sum;
}
#endif
#endif

void main() {
    vec3 n = normalize(world_normal);
    vec3 v = normalize(frame.camera_pos.xyz - world_position);
#ifdef LAMINA_REFERENCE
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    shade_begin(world_position, n, v, n_dot_v);
    reference_pixel = reference_hash(uint(gl_FragCoord.x)
        ^ reference_hash(uint(gl_FragCoord.y) ^ reference_hash(floatBitsToUint(frame.params.w))));
    reference_integrals = 0u;
#ifdef LAMINA_REFERENCE_EVALUATED
    if (SURFACE_MAPS != 0u) {
        tm_surface_begin(surface_uv, gl_FragCoord.xy);
    }
    vec3 radiance = shade_reference_evaluated(n, v, n_dot_v);
#else
    vec3 radiance = shade_reference(n, v, n_dot_v);
#endif
#else
    vec3 radiance = shade_point(world_position, n, v, surface_uv, gl_FragCoord.xy);
#endif
    color = vec4(radiance, 1.0);
}
