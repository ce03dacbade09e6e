// Pieces shared by the 2-flux and 6-flux models: lobes, 2×2 energy matrices per RGB channel,
// and the Snell chain of the mean direction (ALGORITHMS.md §2, §4.2).
#ifndef LAMINA_LIB_TM_COMMON
#define LAMINA_LIB_TM_COMMON

#include "precision.glsl"
#include "hg.glsl"
#include "fgd.glsl"
#include "tir.glsl"
#include "../shared/variant.glsl"
#include "../shared/material.glsl"

// The medium above the stack: vacuum, as src/model/mod.rs's IOR_AIR.
const float IOR_AIR = 1.0;

// Lobes reflect around the mirror direction of the view, or (6-flux back-scatter) around the
// view itself.
#define LOBE_MIRROR 0u
#define LOBE_RETRO 1u

// Largest lobe count of a variant: one per layer (2-flux); in 6-flux, the first interface
// emits its primary lobe alone and each later component (medium, interface, …) up to three,
// most when every layer is a dielectric with a medium: 1 + 3·(2n − 1) = 6n − 2.
// src/render/eval.rs sizes its output by it.
const uint TM_MAX_LOBES = MODEL == MODEL_TM6 ? 6u * MAX_LAYERS - 2u : MAX_LAYERS;

// Each model hands every lobe it finds, top to bottom, to this function, which the including
// shader defines (the forward pass shades it, tm_eval stores it): the lobes are not collected
// in an array first.
//   weight: RGB energy (directional albedo), alpha: GGX roughness, kind: LOBE_MIRROR or LOBE_RETRO
void tm_emit_lobe(vec3 weight, float alpha, uint kind);

// A 2×2 transfer matrix per RGB channel, mapping the fluxes below a component to those above.
struct TmMatrix {
    real3 m11, m12, m21, m22;
};

TmMatrix tm_identity() {
    return TmMatrix(real3(1.0), real3(0.0), real3(0.0), real3(1.0));
}

TmMatrix tm_mul(TmMatrix a, TmMatrix b) {
    return TmMatrix(a.m11 * b.m11 + a.m12 * b.m21, a.m11 * b.m12 + a.m12 * b.m22,
                    a.m21 * b.m11 + a.m22 * b.m21, a.m21 * b.m12 + a.m22 * b.m22);
}

// Interface matrix from its scattering relations a↑ = r a↓ + t' b↑, b↓ = t a↓ + r' b↑ (§4.2):
// M = (1/t) [1, −r'; r, t t' − r r'].
TmMatrix tm_interface(real3 r, real3 t, real3 rp, real3 tp) {
    real3 inv_t = real3(1.0) / t;
    return TmMatrix(inv_t, -rp * inv_t, r * inv_t, (t * tp - r * rp) * inv_t);
}

// Reflectance of a composed stack over a substrate of reflectance r_c (the paper's Eq. 24).
real3 tm_terminate(TmMatrix m, real3 r_c) {
    return (m.m21 + m.m22 * r_c) / (m.m11 + m.m12 * r_c);
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

// |cos| of the mean direction refracted from cosine `cos_i` through relative IOR η; 0 when the
// mean direction itself is totally reflected.
float tm_refracted_cos(float cos_i, float eta) {
    float c2 = 1.0 - (1.0 - cos_i * cos_i) / (eta * eta);
    return c2 > 0.0 ? sqrt(c2) : 0.0;
}

#endif
