#version 460
// The deferred path's classification, first step (classify=tiles|pixels;
// src/render/deferred.rs): each pixel's class — bit k set where mark k's coverage holds its
// layer (lib/tm_common.glsl's tm_covered, the test the generic pass and the forward path's
// stencil marks make) — from what the G-buffer holds there. Per pixel (classify=pixels), or
// per 8×8 tile, one work group (LAMINA_BIN_TILES: the tile's class where its covered pixels
// share one, else BIN_MIXED), the item takes the next place in its bin; its key (bin, place)
// is written for bin_scatter.comp.glsl. bin_offsets.comp.glsl then turns the counts into
// offsets and dispatch sizes.
#define TM_SURFACE_MAPS
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "lib/tm_common.glsl"
#include "lib/bins.glsl"

layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID, local_size_y = 8) in;

layout(set = 1, binding = 0) uniform sampler2D gbuffer_position;  // xyz: position, w: u
layout(set = 1, binding = 1) uniform sampler2D gbuffer_normal;    // xyz: normal, w: v
layout(set = 1, binding = 2, std430) buffer Bins {
    uint words[];
} bins;
layout(set = 1, binding = 3, std430) writeonly buffer Keys {
    uvec2 keys[];
} keys;

// marks: mark k's material layer in bits 4k…4k+3.
layout(push_constant) uniform Push {
    uint width;
    uint height;
    uint marks;
    uint mark_count;
} push;

#ifdef LAMINA_BIN_TILES
shared uint tile_or;
shared uint tile_and;
shared uint tile_covered;
#endif

// The next place in bin `bin`.
uint bin_place(uint bin) {
    return atomicAdd(bins.words[bin * BIN_STRIDE + BIN_ITEMS], 1u);
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    bool covered = false;
    uint bits = 0u;
    if (pixel.x < push.width && pixel.y < push.height) {
        vec4 position_u = texelFetch(gbuffer_position, ivec2(pixel), 0);
        vec4 normal_v = texelFetch(gbuffer_normal, ivec2(pixel), 0);
        covered = dot(normal_v.xyz, normal_v.xyz) != 0.0;
        tm_surface_uv = vec2(position_u.w, normal_v.w);
        tm_surface_pixel = ivec2(pixel);
        for (uint k = 0u; k < push.mark_count; ++k) {
            if (tm_covered((push.marks >> (4u * k)) & 15u)) {
                bits |= 1u << k;
            }
        }
    }
#ifdef LAMINA_BIN_TILES
    if (gl_LocalInvocationIndex == 0u) {
        tile_or = 0u;
        tile_and = BIN_NONE;
        tile_covered = 0u;
    }
    barrier();
    if (covered) {
        atomicOr(tile_or, bits);
        atomicAnd(tile_and, bits);
        atomicOr(tile_covered, 1u);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        uint tile = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
        uint bin = tile_or == tile_and ? tile_or : BIN_MIXED;
        keys.keys[tile] = tile_covered != 0u ? uvec2(bin, bin_place(bin)) : uvec2(BIN_NONE, 0u);
    }
#else
    if (pixel.x < push.width && pixel.y < push.height) {
        keys.keys[pixel.y * push.width + pixel.x] =
            covered ? uvec2(bits, bin_place(bits)) : uvec2(BIN_NONE, 0u);
    }
#endif
}
