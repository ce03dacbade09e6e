// The shading of one point, shared by the forward pass (forward.frag.glsl) and the deferred
// one (deferred.comp.glsl): every lobe is lit by the environment as the variant's `ibl`
// integrates it and by the analytic lights, as forward.frag.glsl's header says. The including
// entry point defines TM_SURFACE_MAPS and includes the shading and scene sets first.
#ifndef LAMINA_LIB_SHADE
#define LAMINA_LIB_SHADE

#include "ibl.glsl"
#include "light.glsl"
#include "sampling.glsl"
#include "tm2.glsl"
#include "tm6.glsl"

// The point being shaded: the models emit their lobes one by one (tm_emit_lobe) and each is
// lit as it comes.
vec3 shade_p;
vec3 shade_n;
vec3 shade_v;
float shade_n_dot_v;
vec3 shade_sum;
// ibl=lamps: the share of the last lobe_fetch that read the cube without the lamps, and the
// terms of its placement in the view's angle alone (ibl_lobe_fit_terms).
float shade_lamps_share;
vec4 shade_fit_terms;

// The mirror image of direction `d` in the tangent plane of normal `n`: where a lobe that
// transmits through a thin slab reads what a reflection lobe would read at `d`.
vec3 shade_behind(vec3 n, vec3 d) {
    return d - 2.0 * dot(n, d) * n;
}

// The share of a fetch of the lamps' cube at `mip` that reads the map without its lamps: none
// up to mip 1, which holds the whole map, all from mip 2 (tables::environment's lamps' cube).
float lamps_share_at(float mip) {
    return clamp(mip - 1.0, 0.0, 1.0);
}

// One fetch of the environment for a lobe of roughness α around `r` (`behind`: mirrored):
// `ibl=split-sum`, Karis's cube along Lagarde's dominant direction at the lobe's own mip;
// `ibl=matched`, the matched cube where its kernel comes closest to the lobe in L²
// (lib/ibl.glsl's ibl_lobe_fit); `ibl=lamps` along the lobe's mean direction at that fit's mip,
// both by polynomials (ibl_lobe_fit_polynomial: the rest is a smooth map, which the mean
// direction fits), but no sharper than the split sum's mip of α up to mip 2 (where the lamps
// leave the cube: sharper, a lobe would read them from the cube, through the kernel of a sharper
// lobe), from the lamps' cube (the lobe's own weights at Karis's levels) of the map without its
// lamps from mip 2 (tables::lamps, tables::environment), which the `matched` binding then holds
// (lobe_lamps adds them). Its lean goes with the share of the fetch that reads the rest
// (shade_lamps_share): below mip 2 the fetch still reads the lamps, whose light a near-mirror
// lobe sends back from its peak, the mirror direction, not from its mean (at grazing views the
// whole lean put the fetch of a glaze of α 0.02 off the sun's reflection); the others, the
// matched cube along the lobe's mean direction at the mip of its spread (ibl_lobe_moments),
// `ibl=anisotropic` in two fetches that match its second moments too. A mirror lobe reads mip 0,
// the whole map, along `r` either way.
vec3 lobe_fetch(vec3 n, vec3 r, float alpha, bool behind) {
    vec3 dir;
    float mip;
    if (alpha <= IBL_MIN_ALPHA) {
        dir = r;
        mip = 0.0;
    } else if (IBL == IBL_LAMPS) {
        vec2 fit = ibl_lobe_fit_polynomial(shade_fit_terms, alpha);
        float own = ibl_mip_of_alpha(alpha, frame.params.x);
        mip = max(fit.y * (frame.params.x - 1.0), min(own, 2.0));
        dir = mix(r, n, fit.x * lamps_share_at(mip));
    } else if (IBL == IBL_SPLIT_SUM) {
        dir = ibl_dominant_direction(n, r, alpha);
        mip = ibl_mip_of_alpha(alpha, frame.params.x);
    } else if (IBL == IBL_MATCHED) {
        vec2 fit = ibl_lobe_fit(lobe_moments, dot(n, r), alpha);
        dir = mix(r, n, fit.x);
        mip = ibl_matched_mip_of_alpha(fit.y * fit.y, frame.params.x);
    } else {
        vec4 moments = ibl_lobe_moments(lobe_moments, dot(n, r), alpha);
        dir = mix(r, n, moments.x);
        vec3 across = cross(n, r);
        if (IBL == IBL_ANISOTROPIC && dot(across, across) > 1e-8) {
            // Two points along the tangent t of the mean direction in the plane of incidence
            // (towards the normal), each fetch blurred as the lobe spreads across the plane.
            vec3 m = normalize(dir);
            vec3 t = cross(m, normalize(across));
            float up = moments.w;
            float down = ibl_lobe_moments_down(lobe_moments, dot(n, r), alpha);
            float q = down / max(up + down, 1e-6);
            vec3 d0 = behind ? shade_behind(n, m + up * t) : m + up * t;
            vec3 d1 = behind ? shade_behind(n, m - down * t) : m - down * t;
            float minor = ibl_matched_mip_of_alpha(moments.z * moments.z, frame.params.x);
            return q * textureLod(matched, d0, minor).rgb
                + (1.0 - q) * textureLod(matched, d1, minor).rgb;
        }
        mip = ibl_matched_mip_of_alpha(moments.y * moments.y, frame.params.x);
    }
    dir = behind ? shade_behind(n, dir) : dir;
    shade_lamps_share = lamps_share_at(mip);
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
        float mip = ibl_matched_mip_of_alpha(sqrt(share / (4.0 * PI)), mips);
        sum += w * textureLod(matched, d, mip).rgb;
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
// send through the transmitted lobe, from behind the surface; `top`: light_lobe's).
vec3 lobe_lights(float alpha, bool retro, bool behind, vec2 top) {
    vec3 sum = vec3(0.0);
    // LIGHTS = 0: a scene without lights compiles none of this (lavapipe compiles and runs
    // every path a constant does not remove).
    uint count = LIGHTS != 0u ? light_info.x : 0u;
    for (uint j = 0u; j < count; ++j) {
        vec3 l;
        vec3 irradiance = light_at(j, l);
        l = behind ? shade_behind(shade_n, l) : l;
        float a = light_alpha(alpha, lights[j].radiance.w);
        sum += irradiance * light_lobe(shade_n, shade_v, shade_n_dot_v, l, a, retro, top);
    }
    return sum;
}

// `ibl=lamps`: what the environment's lamps (tables::lamps: disk lights, which the pass holds
// as constants, generated/layer_values.glsl's ibl_lamp) send back through a lobe of unit
// weight and roughness α, as lobe_lights lights a disk light, but normalised once per lobe, by
// the white lobe's albedo at α. Times the share of the lobe's fetch that read the cube
// without them (shade_lamps_share): none up to mip 1, which holds the whole map (each lamp's own
// shape for a near-mirror lobe), all from mip 2. A slot without a lamp (.w of its irradiance
// 0, a constant) drops out when the pass is specialized.
vec3 lobe_lamps(float alpha, bool retro, bool behind, vec2 top) {
    vec3 sum = vec3(0.0);
    float albedo = white_albedo(shade_n_dot_v, max(alpha, LIGHT_ALPHA_FLOOR));
    [[unroll]] for (uint k = 0u; k < IBL_LAMP_COUNT; ++k) {
        vec4 lamp = ibl_lamp(2u * k);
        vec4 irradiance = ibl_lamp(2u * k + 1u);
        if (irradiance.w > 0.0) {
            vec3 l = behind ? shade_behind(shade_n, lamp.xyz) : lamp.xyz;
            float a = light_alpha_widened(alpha, lamp.w);
            sum += irradiance.rgb
                * light_lobe_with(shade_n, shade_v, shade_n_dot_v, l, a, retro, top, albedo);
        }
    }
    return shade_lamps_share * sum;
}

// What a Lambertian lobe of unit weight sends back (src/model/diffuse.rs): the irradiance at
// the point over π — the lights' E·max(n·l, 0), and the environment's, cosine-convolved
// (its order-2 spherical harmonics, tables::irradiance::irradiance_sh). Under `ibl=lamps`
// the environment's is that of the map without its lamps, read from its irradiance cube
// (tables::irradiance::irradiance_cube: exact, where the harmonics ring around the sunset's
// bright horizon; tests/suite/ibl.rs), and the lamps are lit as the lights.
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
        vec3 environment;
        vec3 lamps = vec3(0.0);
        if (IBL == IBL_LAMPS) {
            environment = textureLod(lamps_irradiance, shade_n, 0.0).rgb;
            [[unroll]] for (uint k = 0u; k < IBL_LAMP_COUNT; ++k) {
                vec4 irradiance = ibl_lamp(2u * k + 1u);
                if (irradiance.w > 0.0) {
                    lamps += irradiance.rgb * max(dot(shade_n, ibl_lamp(2u * k).xyz), 0.0);
                }
            }
        } else {
            environment = ibl_irradiance(shade_n, frame.irradiance);
        }
        sum += scale * (environment + lamps);
    }
    return sum * INV_PI;
}

// A lobe's radiance: the environment's, scaled, and the lights' (`behind`: the transmitted
// lobe's, mirrored from the reflection lobe around `around`; `top`: light_lobe's).
vec3 lobe_light(vec3 around, float alpha, bool retro, bool behind, vec2 top) {
    vec3 sum = lobe_lights(alpha, retro, behind, top);
    float scale = frame.params.y;
    if (scale > 0.0) {
        vec3 fetched = lobe_radiance(shade_n, around, alpha, behind);
        vec3 lamps = IBL == IBL_LAMPS ? lobe_lamps(alpha, retro, behind, top) : vec3(0.0);
        sum += scale * (fetched + lamps);
    }
    return sum;
}

// What a thin slab transmits towards the view through a lobe of weight `t` and roughness α.
vec3 transmitted_light(vec3 t, float alpha) {
    return t * lobe_light(reflect(-shade_v, shade_n), alpha, false, true, vec2(0.0));
}

void shade_begin(vec3 p, vec3 n, vec3 v, float n_dot_v) {
    shade_p = p;
    shade_n = n;
    shade_v = v;
    shade_n_dot_v = n_dot_v;
    shade_sum = vec3(0.0);
    if (IBL == IBL_LAMPS) {
        shade_fit_terms = ibl_lobe_fit_terms(n_dot_v);
    }
}

vec3 shade_ggx(vec3 n, vec3 v, float n_dot_v) {
    LayerGpu top = tm_layer(0u);
    float alpha = top.params.x;
    vec2 ab = texture(split_sum, vec2(n_dot_v, sqrt(alpha))).rg;
    real3 f0 = real3(f0_complex(top.ior.rgb, top.kappa.rgb));
    real3 albedo = f0 * real(ab.x) + real(ab.y);
    vec3 radiance =
        vec3(real3(lobe_light(reflect(-v, n), alpha, false, false, vec2(0.0))) * albedo);
    if (TRANSMITS != 0u) {
        // The baseline's top interface as a thin slab: what it does not reflect, through a
        // lobe of its roughness.
        radiance += transmitted_light(vec3(max(real3(1.0) - albedo, real3(0.0))), alpha);
    }
    return radiance;
}

// The reference pass over a varying stack integrates each lobe by Monte Carlo instead
// (forward.frag.glsl's own tm_emit_lobe).
#ifndef LAMINA_REFERENCE_EVALUATED
void tm_emit_lobe(vec3 weight, float alpha, uint kind, vec2 top) {
    if (kind == LOBE_DIFFUSE) {
        shade_sum += weight * diffuse_light();
        return;
    }
    bool retro = kind == LOBE_RETRO;
    vec3 around = retro ? shade_v : reflect(-shade_v, shade_n);
    shade_sum += weight * lobe_light(around, alpha, retro, false, top);
}
#endif

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
// (lobe_light). The table holds no lobe's Fresnel shape: a pass that would light one
// (transport=corrected's LOBE_FRESNEL under lights) is refused (render/pass.rs). The row coordinate is a texel centre, so the filter's weight on the
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
        sum += lobe.rgb * lobe_light(retro ? v : mirror, alpha, retro, behind, vec2(0.0));
    }
    return sum;
}

// The point's radiance under the pass's model and mode (the reference pass has its own).
vec3 shade_point(vec3 p, vec3 n, vec3 v, vec2 uv, vec2 pixel) {
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    shade_begin(p, n, v, n_dot_v);
    if (SURFACE_MAPS != 0u) {
        tm_surface_begin(uv, pixel);
    }
    if (MODEL == MODEL_GGX) {
        return shade_ggx(n, v, n_dot_v);
    } else if (MODE == MODE_BAKED) {
        return shade_baked(n, v, n_dot_v);
    }
    return shade_lobes(n, v, n_dot_v);
}

#endif
