// Pieces shared by the 2-flux and 6-flux models: lobes, the adding equations per RGB channel,
// and the Snell chain of the mean direction (ALGORITHMS.md §2, §4.2). The models read the stack
// and the tables from the shading set (bindings/shading.glsl), which every entry point that
// shades binds as set 0.
#ifndef LAMINA_LIB_TM_COMMON
#define LAMINA_LIB_TM_COMMON

#include "precision.glsl"
#include "hg.glsl"
#include "medium.glsl"
#include "fgd.glsl"
#include "tir.glsl"
#include "../shared/variant.glsl"
#include "../bindings/shading.glsl"
#include "../generated/layer_values.glsl"

// The medium above the stack: vacuum, as src/model/mod.rs's IOR_AIR.
const float IOR_AIR = 1.0;

// Lobes reflect around the mirror direction of the view, or (6-flux back-scatter) around the
// view itself.
#define LOBE_MIRROR 0u
#define LOBE_RETRO 1u
// A diffuse base's Lambertian lobe (src/model/diffuse.rs): lit by the irradiance.
#define LOBE_DIFFUSE 2u
// transport=corrected: the top interface's lobe (tm_top_reflects), lit like LOBE_MIRROR by the
// environment and, under lights, as that interface's microfacet lobe with its Fresnel factor
// (lib/light.glsl's light_lobe).
#define LOBE_FRESNEL 3u

// Largest lobe count of a variant (src/model/mod.rs's max_lobes, whose constants
// generated/codes.glsl carries): one per layer (2-flux), 6n − 2 in 6-flux. src/render/eval.rs
// sizes its output by it.
const uint TM_MAX_LOBES =
    MODEL == MODEL_TM6 ? TM6_LOBES_PER_LAYER * MAX_LAYERS - TM6_LOBES_LESS : MAX_LAYERS;

// Each model hands every lobe it finds, top to bottom, to this function, which the including
// shader defines (the forward pass shades it, tm_eval stores it): the lobes are not collected
// in an array first.
//   weight: RGB energy (directional albedo), alpha: GGX roughness, kind: LOBE_MIRROR,
//   LOBE_RETRO, LOBE_DIFFUSE or LOBE_FRESNEL; top: LOBE_FRESNEL's interface, its relative IOR
//   η and the directional albedo the model gave it at the view (its weight before the
//   transport's ratio); (0, 0) for any other lobe.
void tm_emit_lobe(vec3 weight, float alpha, uint kind, vec2 top);

// The stack composed so far, seen as two-flux scattering: from above, reflectance r and
// transmittance t; from below, r' (rp), t' (tp) and q = 1 − r'. Components are added below it
// by the adding equations (src/model/adding.rs, which says why not by transfer matrices: those
// hold 1/t and fail wherever a valid stack stops transmitting, and why q is carried: the
// denominator 1 − R'r is formed as q + R'·(1 − r), without cancellation). Every value is an
// energy.
struct TmSlab {
    real3 r, t, rp, tp, q;
};

TmSlab tm_slab_empty() {
    return TmSlab(real3(0.0), real3(1.0), real3(0.0), real3(1.0), real3(1.0));
}

// The stack `a` with a lossless component (r, t, r', t') below it (an interface: 1 − r = t):
//   R ← R + T'·r·T/d,  T ← t·T/d,  R' ← r' + t·R'·t'/d,  T' ← T'·t'/d,  q ← t'·q/d,  d = q + R'·t.
TmSlab tm_over(TmSlab a, real3 r, real3 t, real3 rp, real3 tp) {
    real3 gap = real3(1.0) / max(a.q + a.rp * t, real3(REAL_GAP_FLOOR));
    return TmSlab(a.r + a.tp * r * a.t * gap, t * a.t * gap, rp + t * a.rp * tp * gap,
                  a.tp * tp * gap, tp * a.q * gap);
}

// Reflectance of the stack `a` over an opaque base of reflectance r_c.
real3 tm_over_base(TmSlab a, real3 r_c) {
    real3 gap = real3(1.0) / max(a.q + a.rp * (real3(1.0) - r_c), real3(REAL_GAP_FLOOR));
    return a.r + a.tp * r_c * a.t * gap;
}

// The same for one channel-independent quantity of factors that are not energies (the 2-flux
// asymmetry, g-weighted): d = q + R'·(1 − r), q ← t'·(q + R'·(1 − r − t))/d + 1 − r' − t'.
struct TmSlab1 {
    real r, t, rp, tp, q;
};

TmSlab1 tm_slab1_empty() {
    return TmSlab1(real(0.0), real(1.0), real(0.0), real(1.0), real(1.0));
}

TmSlab1 tm_over1(TmSlab1 a, real r, real t, real rp, real tp) {
    real gap = real(1.0) / max(a.q + a.rp * (real(1.0) - r), real(REAL_GAP_FLOOR));
    return TmSlab1(a.r + a.tp * r * a.t * gap, t * a.t * gap, rp + t * a.rp * tp * gap,
                   a.tp * tp * gap,
                   tp * (a.q + a.rp * (real(1.0) - r - t)) * gap + (real(1.0) - rp - tp));
}

// A g-weighted flux bounded by its energy (a mean cosine is within ±1; src/model/adding.rs's
// `bound`: the reference's first-order ratios of g's diverge along multiply-reflected paths).
real tm_bound(real g_weighted, real energy) {
    return clamp(g_weighted, -abs(energy), abs(energy));
}

// The g-weighted 2-flux stack `g` bounded by the energy stack `e` (grey: a dielectric stack's
// energies are the same in every channel).
TmSlab1 tm_bounded1(TmSlab1 g, TmSlab e) {
    real rp = tm_bound(g.rp, e.rp.x);
    return TmSlab1(tm_bound(g.r, e.r.x), tm_bound(g.t, e.t.x), rp, tm_bound(g.tp, e.tp.x),
                   rp == g.rp ? g.q : real(1.0) - rp);
}

real tm_over_base1(TmSlab1 a, real r_c) {
    real gap = real(1.0) / max(a.q + a.rp * (real(1.0) - r_c), real(REAL_GAP_FLOOR));
    return a.r + a.tp * r_c * a.t * gap;
}

real tm_avg(real3 v) {
    return (v.x + v.y + v.z) * real(1.0 / 3.0);
}

float tm_mean(vec3 v) {
    return (v.x + v.y + v.z) / 3.0;
}

bool tm_is_conductor(LayerGpu layer) {
    return any(greaterThan(layer.kappa.rgb, vec3(0.0)));
}

bool tm_is_diffuse(LayerGpu layer) {
    return layer.diffuse.w != 0.0;
}

// Whether layer i is the stack's diffuse base: a pass with a diffuse base's code
// (DIFFUSE_BASE) ends in one, which a specialized pipeline knows to be its last layer.
bool tm_diffuse_at(uint i, LayerGpu layer) {
    if (DIFFUSE_BASE == 0u) {
        return false;
    }
    return SPECIALIZED ? i + 1u == LAYER_COUNT : tm_is_diffuse(layer);
}

// The stack `a` with a lossy component below it that is the same from above and below
// (reflectance r, transmittance t: a medium crossed by diffuse light), by adding.rs's
// general equations, with 1 − r − t absorbed.
TmSlab tm_over_symmetric(TmSlab a, real3 r, real3 t) {
    real3 one_minus_r = real3(1.0) - r;
    real3 gap = real3(1.0) / max(a.q + a.rp * one_minus_r, real3(REAL_GAP_FLOOR));
    real3 loss = one_minus_r - t;
    return TmSlab(a.r + a.tp * r * a.t * gap, t * a.t * gap, r + t * a.rp * t * gap,
                  a.tp * t * gap, t * (a.q + a.rp * loss) * gap + loss);
}

// The cosine-weighted hemispherical average of the dielectric Fresnel reflectance at relative
// IOR η (src/model/diffuse.rs's fresnel_hemispherical): Gauss–Legendre in √μ from the rarer side,
// reciprocity from the denser.
float tm_fresnel_hemispherical(float eta) {
    bool inside = eta < 1.0;
    float n = inside ? 1.0 / eta : eta;
    // μ = s²: 2μ dμ = 4s³ ds, the nodes crowded towards grazing incidence.
    float sum = 0.0;
    for (int k = 0; k < HEMISPHERE_POINTS; ++k) {
        float s = HEMISPHERE_MU[k];
        sum += HEMISPHERE_W[k] * 4.0 * s * s * s * fresnel_dielectric(s * s, n);
    }
    return inside ? 1.0 - eta * eta * (1.0 - sum) : sum;
}

// The energy a diffuse base of albedo ρ sends back out through the stack above it, whose
// transmittance towards it is `t_view` and whose diffuse slab is `d`: T·ρ·T′_d/(1 − ρR′_d).
vec3 tm_diffuse_weight(vec3 t_view, vec3 rho, TmSlab d) {
    vec3 den = max(vec3(d.q) + vec3(d.rp) * (vec3(1.0) - rho), vec3(1e-7));
    return t_view * rho * vec3(d.tp) / den;
}

// The material as the models read it. Under MODE_GENERIC every fact comes from the material
// buffer at run time; a per-material pipeline (SPECIALIZED) has the layer count and each
// layer's structure as constants (shared/variant.glsl), so that with the loops unrolled
// ([[unroll]] in the models) every branch below folds and the dead paths vanish, and
// MODE_SPECIALIZED_VALUES has the numbers too. The host decides the structure with the f64
// model's own tests (src/specialize.rs), so both agree with the CPU oracle.
// The material layer of slot `i` in a pass built for one class of a varying stack's pixels
// (shared/variant.glsl's LAYER_SLOTS_LO/HI): a constant where `i` is.
uint tm_slot(uint i) {
    return ((i < 8u ? LAYER_SLOTS_LO >> (4u * i) : LAYER_SLOTS_HI >> (4u * (i - 8u)))) & 15u;
}

#ifdef TM_SURFACE_MAPS
// A spatially varying stack (SURFACE_MAPS; src/material/surface.rs, whose SurfaceMaps::layers_at
// is the CPU twin): an entry point that has texture coordinates defines TM_SURFACE_MAPS and
// calls tm_surface_begin per pixel, which keeps the layers whose coverage holds them there, in
// order; the models then run over those only, so an uncovered layer costs no iteration and
// the pixel is the stack without it. Every other field a map varies is read where the model
// asks for the layer.
vec2 tm_surface_uv;
ivec2 tm_surface_pixel;
uint tm_surface_count;
uint tm_surface_slots[MAX_LAYERS];

const uint TM_SCREEN_BIT = 0x80u;

// Whether some layer reads field `bit` from a map (src/material/surface.rs's spec_bits): a
// constant, so the lookups of fields that never vary fold away.
bool tm_varies(uint bit) {
    return (SURFACE_MAPS & (1u << bit)) != 0u;
}

// The texel of map `code` holding the point: the pixel's in screen coordinates, else the
// nearest to its texture coordinates (repeated).
// The repeat is taken in floats: integer division has no vector instruction on a CPU, and
// whole numbers below 2^24 divide exactly enough that the floor is the integer quotient's.
ivec3 tm_map_texel(uint code) {
    ivec2 n = textureSize(layer_maps, 0).xy;
    vec2 size = vec2(n);
    vec2 texel = (code & TM_SCREEN_BIT) != 0u ? vec2(tm_surface_pixel)
                                              : floor(tm_surface_uv * size);
    ivec2 wrapped = ivec2(texel - size * floor(texel / size));
    return ivec3(clamp(wrapped, ivec2(0), n - 1), int((code & 0x7fu) - 1u));
}

// The value of map `code` at the point: bilinear over texture coordinates, or the pixel's.
vec4 tm_map(uint code) {
    if ((code & TM_SCREEN_BIT) != 0u) {
        return texelFetch(layer_maps, tm_map_texel(code), 0);
    }
    return textureLod(layer_maps, vec3(tm_surface_uv, float((code & 0x7fu) - 1u)), 0.0);
}

// Whether the coverage of material layer `layer` holds it at the point (a layer without a
// coverage map: everywhere). classify.frag.glsl marks the stencil by the same test.
bool tm_covered(uint layer) {
    uint coverage = tm_varies(7u) ? material.maps[layer].y >> 24 : 0u;
    return coverage == 0u || texelFetch(layer_maps, tm_map_texel(coverage), 0).r > 0.5;
}

void tm_surface_begin(vec2 uv, vec2 frag_coord) {
    tm_surface_uv = uv;
    tm_surface_pixel = ivec2(frag_coord);
    if (SPECIALIZED) {
        // The pass shades one class of pixels: its layers are constants (tm_slot).
        tm_surface_count = LAYER_COUNT;
        return;
    }
    tm_surface_slots[0] = 0u;
    uint count = min(material.info.x, MAX_LAYERS);
    uint n = 0u;
    for (uint i = 0u; i < count; ++i) {
        if (tm_covered(i)) {
            tm_surface_slots[n] = i;
            ++n;
        }
    }
    tm_surface_count = n;
}

// The material layer at slot `i` of the point's stack.
uint tm_surface_slot(uint i) {
    return SPECIALIZED ? tm_slot(i) : tm_surface_slots[i];
}

// The fields slot `i` of a class's pass reads from maps (shared/variant.glsl's SLOT_MAPS_0…3,
// a byte per slot: η, κ, σs, σa, α, depth, g, diffuse albedo from bit 0): constants, so a
// class pass compiles only the lookups its layers make.
uint tm_slot_maps(uint i) {
    uint word = i < 4u ? SLOT_MAPS_0 : i < 8u ? SLOT_MAPS_1 : i < 12u ? SLOT_MAPS_2 : SLOT_MAPS_3;
    return (word >> (8u * (i & 3u))) & 0xffu;
}

// Whether slot `i` may read field `bit` from a map: in a class's pass, whether its layer does
// (tm_slot_maps' bit `slot_bit`); in the generic pass, whether some layer does (tm_varies,
// SURFACE_MAPS' bit `bit`), its code deciding at run time. lavapipe runs the lookup of a
// branch whose condition is not a constant whether it is taken or not.
bool tm_maps(uint i, uint slot_bit, uint bit) {
    return SPECIALIZED ? ((tm_slot_maps(i) >> slot_bit) & 1u) != 0u : tm_varies(bit);
}

// Slot `i` of the point's stack with its varying fields read at the point.
LayerGpu tm_surface_layer(uint i) {
    uint index = tm_surface_slot(i);
    LayerGpu layer = material.layers[index];
    uvec3 codes = material.maps[index].xyz;
    uint c = codes.x & 0xffu;
    if (tm_maps(i, 0u, 0u) && c != 0u) layer.ior.rgb = tm_map(c).rgb;
    c = (codes.x >> 8) & 0xffu;
    if (tm_maps(i, 1u, 1u) && c != 0u) layer.kappa.rgb = tm_map(c).rgb;
    c = (codes.x >> 16) & 0xffu;
    if (tm_maps(i, 2u, 2u) && c != 0u) layer.sigma_s.rgb = tm_map(c).rgb;
    c = codes.x >> 24;
    if (tm_maps(i, 3u, 3u) && c != 0u) layer.sigma_a.rgb = tm_map(c).rgb;
    c = codes.y & 0xffu;
    if (tm_maps(i, 4u, 4u) && c != 0u) layer.params.x = tm_map(c).r;
    c = (codes.y >> 8) & 0xffu;
    if (tm_maps(i, 5u, 5u) && c != 0u) layer.params.y = tm_map(c).r;
    c = (codes.y >> 16) & 0xffu;
    if (tm_maps(i, 6u, 6u) && c != 0u) layer.params.z = tm_map(c).r;
    c = codes.z & 0xffu;
    if (tm_maps(i, 7u, 8u) && c != 0u) layer.diffuse.rgb = tm_map(c).rgb;
    return layer;
}
#endif

uint tm_layer_count() {
#ifdef TM_SURFACE_MAPS
    if (SURFACE_MAPS != 0u) {
        return tm_surface_count;
    }
#endif
    return SPECIALIZED ? LAYER_COUNT : min(material.info.x, MAX_LAYERS);
}

LayerGpu tm_layer(uint i) {
    // Not a ?: — the buffer's LayerGpu and a constant-built one are different SPIR-V types.
    if (MODE == MODE_SPECIALIZED_VALUES) {
        return tm_layer_values(i);
    }
#ifdef TM_SURFACE_MAPS
    if (SURFACE_MAPS != 0u) {
        return tm_surface_layer(i);
    }
#endif
    return material.layers[i];
}

// transport=corrected: where the view cosine `mu` falls among the evenly spaced cosines of
// the material's energy ratios (μ_k = k/(P − 1)): the interval and the weight of its upper end
// (src/model/transport.rs's `interpolate`). Found once per evaluation; each lobe then reads
// its layer's interval.
// The conversions are signed: x is never negative, and a CPU converts between floats and
// signed integers in one vector instruction, unsigned ones in several.
struct TmTransportAt {
    int k;
    float f;
};

TmTransportAt tm_transport_at(float mu) {
    const int P = int(LAMINA_TRANSPORT_POINTS);
    float x = clamp(mu, 0.0, 1.0) * float(P - 1);
    int k = min(int(x), P - 2);
    return TmTransportAt(k, x - float(k));
}

// The ratio of row `row` (a layer of the material, or LAMINA_MAX_LAYERS_LIMIT for the
// transmittance) at `at`: one interval's three words (bindings/shading.glsl's
// TransportRatios), the lower end plus the weighted change.
vec3 tm_transport_ratio(uint row, TmTransportAt at) {
    uvec3 packed = transport[row * (LAMINA_TRANSPORT_POINTS - 1u) + uint(at.k)].xyz;
    vec2 rg = unpackHalf2x16(packed.x);
    vec2 b_dr = unpackHalf2x16(packed.y);
    vec2 dgb = unpackHalf2x16(packed.z);
    return vec3(rg, b_dr.x) + vec3(b_dr.y, dgb) * at.f;
}

// The weight a lobe of layer `i` (of the stack being evaluated) emits: the model's, scaled
// under transport=corrected by its material layer's ratio (a pixel whose coverage drops layers
// evaluates its covered ones: `i` is then a slot of the material's).
vec3 tm_transported(uint i, TmTransportAt at, vec3 weight) {
    if (TRANSPORT != TRANSPORT_CORRECTED) {
        return weight;
    }
    uint row = i;
#ifdef TM_SURFACE_MAPS
    if (SURFACE_MAPS != 0u) {
        row = tm_surface_slot(i);
    }
#endif
    return weight * tm_transport_ratio(row, at);
}

// The stack's transmittance under the variant's transport (nothing to scale over a
// conductor, which a specialized pipeline knows).
vec3 tm_transported_transmittance(TmTransportAt at, vec3 t) {
    if (TRANSPORT != TRANSPORT_CORRECTED || (SPECIALIZED && CONDUCTOR_BASE != 0u)) {
        return t;
    }
    return t * tm_transport_ratio(LAMINA_MAX_LAYERS_LIMIT, at);
}

// The roughness of the lobe a stack of `count` layers transmits, under the thin-slab
// assumption of the forward pass (TRANSMITS): the primary path's asymmetry in the base
// (§4.4's first-order g_t0, `g_t0`) refracted back out through the base's back face, parallel
// to the stack, into the outside medium (src/model/mod.rs's transmitted_alpha).
float tm_transmitted_alpha(float g_t0, uint count) {
    // A pixel whose coverage leaves no layer: nothing there, a clear view through.
    if (count == 0u) {
        return 0.0;
    }
    float eta = tm_mean(tm_layer(count - 1u).ior.rgb) / IOR_AIR;
    return hg_alpha_of_g(hg_refract(g_t0, eta));
}

bool tm_bit(uint mask, uint i) {
    return ((mask >> i) & 1u) != 0u;
}

// Whether layer i's structure is a constant of the pipeline: a per-material pipeline's, unless
// a map carries the layer's values across one of the tests below (DYNAMIC_MASK), which it
// then makes at run time as the generic pipeline does.
bool tm_fixed_at(uint i) {
    return SPECIALIZED && !tm_bit(DYNAMIC_MASK, i);
}

bool tm_conductor_at(uint i, LayerGpu layer) {
    return SPECIALIZED ? CONDUCTOR_BASE != 0u && i + 1u == LAYER_COUNT : tm_is_conductor(layer);
}

// An index-matched interface (relative IOR η): none at all.
bool tm_matched_at(uint i, float eta) {
    return tm_fixed_at(i) ? tm_bit(MATCHED_MASK, i) : abs(eta - 1.0) < TM_INDEX_MATCHED;
}

// An interface that refracts but reflects nothing.
bool tm_clear_at(uint i, float eta) {
    return tm_fixed_at(i) ? tm_bit(CLEAR_MASK, i) : abs(eta - 1.0) < TM_REFLECTS_NOTHING;
}

// Denser below (η ≥ 1): light going down cannot be trapped, light going up can.
bool tm_denser_at(uint i, float eta) {
    return tm_fixed_at(i) ? tm_bit(DENSER_MASK, i) : eta >= 1.0;
}

// Whether layer i's interface, of relative IOR η, emits the top's Fresnel lobe under
// transport=corrected (LOBE_FRESNEL): the `first` interface light meets (every layer above
// index-matched to the air, and in 6-flux without a medium), a dielectric (not `opaque`: a
// conductor or a diffuse base) that is not index-matched and is denser than air.
// src/model/transport.rs's `top_reflects` is the CPU side.
bool tm_top_reflects(uint i, bool first, bool opaque, float eta) {
    return TRANSPORT == TRANSPORT_CORRECTED && first && !opaque && !tm_matched_at(i, eta)
        && tm_denser_at(i, eta);
}

bool tm_medium_at(uint i, LayerGpu layer) {
    return tm_fixed_at(i) ? tm_bit(MEDIUM_MASK, i) : layer.params.y > 0.0;
}

// A smooth interface's directional albedo is its Fresnel reflectance: exact, with no table
// (src/model/mod.rs's `albedo`).
bool tm_smooth_at(uint i, float alpha) {
    return tm_fixed_at(i) ? tm_bit(SMOOTH_MASK, i) : alpha == 0.0;
}

vec3 tm_albedo_rgb(uint i, float mu, float alpha, vec3 eta, vec3 kappa) {
    if (tm_smooth_at(i, alpha)) {
        return vec3(fresnel_conductor(mu, eta.r, kappa.r), fresnel_conductor(mu, eta.g, kappa.g),
                    fresnel_conductor(mu, eta.b, kappa.b));
    }
    return fgd_rgb(mu, alpha, eta, kappa);
}

float tm_albedo_dielectric(uint i, float mu, float alpha, float eta) {
    return tm_smooth_at(i, alpha) ? fresnel_dielectric(mu, eta) : fgd_dielectric(mu, alpha, eta);
}

// |cos| of the mean direction refracted from cosine `cos_i` through relative IOR η; 0 when the
// mean direction itself is totally reflected.
float tm_refracted_cos(float cos_i, float eta) {
    float c2 = 1.0 - (1.0 - cos_i * cos_i) / (eta * eta);
    return c2 > 0.0 ? sqrt(c2) : 0.0;
}

// The first `count` layers as diffuse light sees them (src/model/diffuse.rs's slab), with the
// 6-flux media crossed at μ = 1/2 when `media`.
TmSlab tm_diffuse_slab(uint count, bool media) {
    TmSlab s = tm_slab_empty();
    float eta_above = IOR_AIR;
    for (uint i = 0u; i < count; ++i) {
        LayerGpu layer = tm_layer(i);
        float eta_layer = tm_mean(layer.ior.rgb);
        float eta = eta_layer / eta_above;
        if (abs(eta - 1.0) >= TM_INDEX_MATCHED) {
            float down = tm_fresnel_hemispherical(eta);
            float up = tm_fresnel_hemispherical(1.0 / eta);
            s = tm_over(s, real3(down), real3(1.0 - down), real3(up), real3(1.0 - up));
            eta_above = eta_layer;
        }
        if (media && layer.params.y > 0.0) {
            vec3 transmission, r_fb, t_ff;
            float g_rfb, g_tff;
            medium_factors(layer, 0.5, transmission, r_fb, t_ff, g_rfb, g_tff);
            // t_ff holds the unscattered transmission too (tm6_over_medium's arguments).
            s = tm_over_symmetric(s, real3(r_fb), real3(t_ff));
        }
    }
    return s;
}

#endif
