// GGX microfacet terms (Walter et al. 2007; Heitz 2014, "Understanding the Masking-Shadowing
// Function in Microfacet-Based BRDFs"; Karis 2013; Hammon 2017). Written in `real` so the fp16
// variant narrows them; α below ~1e-2 loses precision in fp16 (α² underflows near 6e-5).
// The forms are chosen by NDF_MODE and G2_MODE, which the including entry point declares:
// shared/variant.glsl in the shading passes, shared/kernel.glsl in the table kernels.
#ifndef LAMINA_LIB_MICROFACET
#define LAMINA_LIB_MICROFACET

#include "math.glsl"
#include "precision.glsl"
#if !defined(LAMINA_SHARED_VARIANT) && !defined(LAMINA_SHARED_KERNEL)
#error "include shared/variant.glsl or shared/kernel.glsl before lib/microfacet.glsl"
#endif

// D(h) = α² / (π (cos²θ_h (α² − 1) + 1)²).
real ggx_d(real cos_h, real alpha) {
    real a2 = alpha * alpha;
    real d = cos_h * cos_h * (a2 - real(1.0)) + real(1.0);
    return a2 / (real(PI) * d * d);
}

// Karis 2013's arrangement of the same D: one fewer multiply, different rounding.
real ggx_d_karis(real cos_h, real alpha) {
    real a2 = alpha * alpha;
    real d = (cos_h * a2 - cos_h) * cos_h + real(1.0);
    return a2 / (real(PI) * d * d);
}

real ndf(real cos_h, real alpha) {
    return NDF_MODE == NDF_KARIS ? ggx_d_karis(cos_h, alpha) : ggx_d(cos_h, alpha);
}

// Smith Λ for GGX: (−1 + √(1 + α² tan²θ)) / 2, written as (√(c² + α² s²) − c) / 2c so that
// grazing directions (c → 0) give a large Λ instead of a clamped one; the divisor's floor,
// REAL_MIN_COS, only keeps c = 0 finite.
real smith_lambda(real cos_t, real alpha) {
    real c = max(cos_t, REAL_MIN_COS);
    real c2 = c * c;
    real root = sqrt(c2 + alpha * alpha * (real(1.0) - c2));
    return (root - c) / (real(2.0) * c);
}

// Schlick-Smith G1 with the IBL constant k = α/2 (Karis 2013).
real schlick_g1(real cos_t, real alpha) {
    real k = real(0.5) * alpha;
    return cos_t / (cos_t * (real(1.0) - k) + k);
}

// Masking G1 matching the chosen G2 form (Smith's for all but Schlick).
real masking_g1(real cos_t, real alpha) {
    if (G2_MODE == G2_SCHLICK) {
        return schlick_g1(cos_t, alpha);
    }
    return real(1.0) / (real(1.0) + smith_lambda(cos_t, alpha));
}

// Masking-shadowing G2(ω_i, ω_o) for upper-hemisphere cosines.
real masking_shadowing(real cos_i, real cos_o, real alpha) {
    if (G2_MODE == G2_SMITH) {
        return masking_g1(cos_i, alpha) * masking_g1(cos_o, alpha);
    } else if (G2_MODE == G2_SCHLICK) {
        return schlick_g1(cos_i, alpha) * schlick_g1(cos_o, alpha);
    } else if (G2_MODE == G2_EARL) {
        // Hammon 2017, "PBR Diffuse Lighting for GGX+Smith Microsurfaces", approximating the
        // height-correlated form.
        real two = real(2.0) * cos_i * cos_o;
        return two / mix(two, cos_i + cos_o, alpha);
    }
    return real(1.0) / (real(1.0) + smith_lambda(cos_i, alpha) + smith_lambda(cos_o, alpha));
}

#endif
