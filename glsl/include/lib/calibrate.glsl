// The calibration loop of `lamina devices --calibrate` (src/profile/calibrate.rs): the same
// arithmetic in a fragment draw (calibrate.frag.glsl) and a compute dispatch
// (calibrate.comp.glsl) over the same pixels, so that their times compare the device's two
// paths and nothing else: `iterations` dependent multiply-adds on a vec4 seeded by the pixel
// (the count a push constant, so no compiler can fold the loop), no memory access inside.
#ifndef LAMINA_LIB_CALIBRATE
#define LAMINA_LIB_CALIBRATE

vec4 calibrate_loop(uint pixel, uint iterations) {
    vec4 v = vec4(float(pixel & 255u) * (1.0 / 256.0), 0.25, 0.5, 0.75);
    const vec4 a = vec4(0.9999, 0.9998, 0.9997, 0.9996);
    const vec4 b = vec4(1e-4, 2e-4, 3e-4, 4e-4);
    for (uint i = 0u; i < iterations; ++i) {
        v = v * a + b;
    }
    return v;
}

#endif
