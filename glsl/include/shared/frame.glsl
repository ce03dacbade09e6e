// Per-frame constants. Mirrors `FrameConstants` in src/render/frame.rs (std140; the Rust side
// asserts size and offsets).
#ifndef LAMINA_SHARED_FRAME
#define LAMINA_SHARED_FRAME

struct FrameConstants {
    mat4 view_proj;
    mat4 inv_view_proj;
    vec4 camera_pos;     // xyz: world-space eye
    vec4 base_ior;       // rgb: eta of the single GGX layer, relative to air
    vec4 base_kappa;     // rgb: kappa of that layer
    vec4 params;         // x: GGX alpha, y: prefiltered mip count, z, w: unused
};

#endif
