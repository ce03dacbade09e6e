#version 460
// The deferred path's shading (path=deferred, src/render/deferred.rs): one invocation per
// pixel, in 8×8 tiles, reads what the G-buffer (gbuffer.frag.glsl) holds at its pixel and
// shades it exactly as the forward pass's fragment shader does (lib/shade.glsl), from the
// same interpolated inputs, into the render target. A pixel the mesh does not cover (a zero
// normal, the G-buffer's clear value) keeps the sky drawn before.
#define TM_SURFACE_MAPS
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "bindings/scene.glsl"

#include "lib/shade.glsl"

// The tile's width is the shading passes' work-group constant; its height is fixed here and
// in the kernel's interface (render::deferred::KERNEL).
layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID, local_size_y = 8) in;

layout(set = 2, binding = 0) uniform sampler2D gbuffer_position;  // xyz: position, w: u
layout(set = 2, binding = 1) uniform sampler2D gbuffer_normal;    // xyz: normal, w: v
#ifdef LAMINA_TARGET_RGBA32F
layout(set = 2, binding = 2, rgba32f) uniform writeonly image2D target;
#else
layout(set = 2, binding = 2, rgba16f) uniform writeonly image2D target;
#endif

layout(push_constant) uniform Push {
    uint width;
    uint height;
} push;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= push.width || pixel.y >= push.height) {
        return;
    }
    ivec2 texel = ivec2(pixel);
    vec4 position_u = texelFetch(gbuffer_position, texel, 0);
    vec4 normal_v = texelFetch(gbuffer_normal, texel, 0);
    if (dot(normal_v.xyz, normal_v.xyz) == 0.0) {
        return;
    }
    vec3 n = normalize(normal_v.xyz);
    vec3 v = normalize(frame.camera_pos.xyz - position_u.xyz);
    vec3 radiance =
        shade_point(position_u.xyz, n, v, vec2(position_u.w, normal_v.w), vec2(pixel) + 0.5);
    imageStore(target, texel, vec4(radiance, 1.0));
}
