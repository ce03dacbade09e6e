// Cube-face texel ↔ direction, following the Vulkan cube-map face convention (spec §16.5.4,
// "Cube Map Face Selection"): layer = +X, −X, +Y, −Y, +Z, −Z.
#ifndef LAMINA_LIB_CUBEMAP
#define LAMINA_LIB_CUBEMAP

// Direction through face `face` at face coordinates uv ∈ [0,1]² (texel centres at (i+0.5)/size).
vec3 cube_direction(uint face, vec2 uv) {
    vec2 p = uv * 2.0 - 1.0;
    vec3 d;
    if (face == 0u) d = vec3(1.0, -p.y, -p.x);
    else if (face == 1u) d = vec3(-1.0, -p.y, p.x);
    else if (face == 2u) d = vec3(p.x, 1.0, p.y);
    else if (face == 3u) d = vec3(p.x, -1.0, -p.y);
    else if (face == 4u) d = vec3(p.x, -p.y, 1.0);
    else d = vec3(-p.x, -p.y, -1.0);
    return normalize(d);
}

#endif
