// Equirectangular mapping: +Y is up, u = 0.5 looks down −Z... see `equirect_uv`.
#ifndef LAMINA_LIB_EQUIRECT
#define LAMINA_LIB_EQUIRECT

#include "math.glsl"

// Texture coordinates of direction d (unit): u = atan2(d.x, −d.z)/2π + 0.5 wraps around the
// horizon, v = acos(d.y)/π runs from the zenith (v = 0) to the nadir. Mirrored by
// `tables::environment::equirect_uv` on the CPU.
vec2 equirect_uv(vec3 d) {
    float u = atan(d.x, -d.z) * (0.5 * INV_PI) + 0.5;
    float v = acos(clamp(d.y, -1.0, 1.0)) * INV_PI;
    return vec2(u, v);
}

#endif
