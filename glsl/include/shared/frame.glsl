// Per-frame constants. Mirrors `FrameConstants` in src/render/frame.rs (std140; the Rust side
// asserts size and offsets).
#ifndef LAMINA_SHARED_FRAME
#define LAMINA_SHARED_FRAME

struct FrameConstants {
    mat4 view_proj;
    mat4 inv_view_proj;
    vec4 camera_pos;     // xyz: world-space eye
    vec4 params;         // x: mip count of the prefiltered environment; y: the environment's
                         // scale (0: lights only); z: the frame's index, seeding a
                         // reference pass (render/reference.rs); w: the bits of its seed's
                         // sample stream (render::reference::stream)
    vec4 irradiance[9];  // rgb: the environment's irradiance in order-2 spherical harmonics,
                         // each coefficient times its band's cosine-lobe factor (lib/ibl.glsl)
};

#endif
