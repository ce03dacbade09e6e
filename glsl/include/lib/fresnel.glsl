// Fresnel reflectance (ALGORITHMS.md §10.5).
#ifndef LAMINA_LIB_FRESNEL
#define LAMINA_LIB_FRESNEL

#include "precision.glsl"

// Normal-incidence reflectance of an interface with relative complex IOR η + iκ:
// F0 = ((η − 1)² + κ²) / ((η + 1)² + κ²). Exact for conductors and dielectrics alike.
vec3 f0_complex(vec3 eta, vec3 kappa) {
    vec3 k2 = kappa * kappa;
    return ((eta - 1.0) * (eta - 1.0) + k2) / ((eta + 1.0) * (eta + 1.0) + k2);
}

// f0_complex of one channel.
float f0_channel(float eta, float kappa) {
    float k2 = kappa * kappa;
    return ((eta - 1.0) * (eta - 1.0) + k2) / ((eta + 1.0) * (eta + 1.0) + k2);
}

// Exact unpolarised reflectance of a dielectric interface of relative IOR η at incidence
// cosine c: 1 beyond the critical angle, and for η = 0 (nothing to transmit into).
float fresnel_dielectric(float c, float eta) {
    float ct2 = 1.0 - (1.0 - c * c) / max(eta * eta, 1e-12);
    if (ct2 <= 0.0 || eta <= 0.0) {
        return 1.0;
    }
    float ct = sqrt(ct2);
    float rs = (c - eta * ct) / (c + eta * ct);
    float rp = (eta * c - ct) / (eta * c + ct);
    return 0.5 * (rs * rs + rp * rp);
}

// Exact unpolarised reflectance of relative complex IOR η + iκ at incidence cosine c;
// a dielectric (with total internal reflection) for κ = 0. Mirrors model::fresnel::conductor.
float fresnel_conductor(float c, float eta, float kappa) {
    if (kappa <= 0.0) {
        return fresnel_dielectric(c, eta);
    }
    c = clamp(c, 0.0, 1.0);
    float c2 = c * c;
    float s2 = 1.0 - c2;
    float t0 = eta * eta - kappa * kappa - s2;
    float a2b2 = sqrt(t0 * t0 + 4.0 * eta * eta * kappa * kappa);
    float a = sqrt(max(0.0, 0.5 * (a2b2 + t0)));
    float rs = (a2b2 + c2 - 2.0 * a * c) / (a2b2 + c2 + 2.0 * a * c);
    float rp = rs * (c2 * a2b2 + s2 * s2 - 2.0 * a * c * s2)
        / (c2 * a2b2 + s2 * s2 + 2.0 * a * c * s2);
    return 0.5 * (rs + rp);
}

// Schlick's weight (1 − cos)^5, the basis of the split-sum table.
real schlick_weight(real cos_t) {
    real m = clamp(real(1.0) - cos_t, real(0.0), real(1.0));
    real m2 = m * m;
    return m2 * m2 * m;
}

#endif
