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

// Schlick's weight (1 − cos)^5, the basis of the split-sum table.
real schlick_weight(real cos_t) {
    real m = clamp(real(1.0) - cos_t, real(0.0), real(1.0));
    real m2 = m * m;
    return m2 * m2 * m;
}

#endif
