// One analytic light. Mirrors `LightGpu` in src/shader/interface.rs (std430; the Rust side
// asserts size and offsets).
#ifndef LAMINA_SHARED_LIGHT
#define LAMINA_SHARED_LIGHT

struct LightGpu {
    vec4 position;  // w = 0: xyz is the unit direction towards a directional light;
                    // w = 1: xyz is a point light's position
    vec4 radiance;  // rgb: colour × intensity (irradiance at normal incidence; a point light's
                    // intensity, divided by the squared distance); w: angular radius (radians)
};

#endif
