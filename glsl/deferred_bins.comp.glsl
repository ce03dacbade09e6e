#version 460
// The deferred path's shading of one bin (classify=tiles|pixels; src/render/deferred.rs): an
// indirect dispatch whose size bin_offsets.comp.glsl wrote, each work group shading one tile
// of the bin's list (LAMINA_BIN_TILES, an invocation per pixel of the tile) or a group's worth
// of its pixels, with the pipeline of the bin's class (lib/deferred.glsl).
#define TM_SURFACE_MAPS
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "bindings/scene.glsl"

#include "lib/shade.glsl"
#include "lib/deferred.glsl"
#include "lib/bins.glsl"

layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID, local_size_y = 8) in;

layout(set = 2, binding = 3, std430) readonly buffer Bins {
    uint words[];
} bins;
layout(set = 2, binding = 4, std430) readonly buffer List {
    uint items[];
} list;

layout(push_constant) uniform Push {
    uint width;
    uint height;
    uint bin;
} push;

void main() {
    uint base = push.bin * BIN_STRIDE;
    uint offset = bins.words[base + BIN_OFFSET];
#ifdef LAMINA_BIN_TILES
    uvec2 tile = bin_unpack(list.items[offset + gl_WorkGroupID.x]);
    uvec2 pixel = tile * gl_WorkGroupSize.xy + gl_LocalInvocationID.xy;
    if (pixel.x >= push.width || pixel.y >= push.height) {
        return;
    }
#else
    uint i = gl_WorkGroupID.x * (gl_WorkGroupSize.x * gl_WorkGroupSize.y) + gl_LocalInvocationIndex;
    if (i >= bins.words[base + BIN_ITEMS]) {
        return;
    }
    uvec2 pixel = bin_unpack(list.items[offset + i]);
#endif
    deferred_shade(pixel);
}
