// Total-internal-reflection correction (ALGORITHMS.md §4.5, §9), by the TIR_MODE constant.
// The host accepts only `tir=none` until the TIR tables land (issue #6).
#ifndef LAMINA_LIB_TIR
#define LAMINA_LIB_TIR

// Fraction of a lobe (incidence μ, roughness α) trapped by relative IOR η < 1.
float tir_fraction(float mu, float alpha, float eta) {
    return 0.0;
}

#endif
