// The deferred path's shading of one pixel (path=deferred, src/render/deferred.rs), shared by
// deferred.comp.glsl (every pixel of the frame) and deferred_bins.comp.glsl (one class's
// pixels or tiles): what the G-buffer (gbuffer.frag.glsl) holds at the pixel, shaded exactly
// as the forward pass's fragment shader shades it (lib/shade.glsl), from the same
// interpolated inputs, into the render target. A pixel the mesh does not cover (a zero
// normal, the G-buffer's clear value) keeps the sky drawn before. The includer has included
// the shading and scene sets and lib/shade.glsl.
#ifndef LAMINA_LIB_DEFERRED
#define LAMINA_LIB_DEFERRED

layout(set = 2, binding = 0) uniform sampler2D gbuffer_position;  // xyz: position, w: u
layout(set = 2, binding = 1) uniform sampler2D gbuffer_normal;    // xyz: normal, w: v
#ifdef LAMINA_TARGET_RGBA32F
layout(set = 2, binding = 2, rgba32f) uniform writeonly image2D target;
#else
layout(set = 2, binding = 2, rgba16f) uniform writeonly image2D target;
#endif

// Shades `pixel`, which lies in the frame.
void deferred_shade(uvec2 pixel) {
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

#endif
