#version 460
// The deferred path's classification, last step (src/render/deferred.rs): each item (pixel or
// tile, over the grid of the push constants) writes its coordinates at its place in its
// bin's part of the list (its key from bin_count.comp.glsl, the bin's offset from
// bin_offsets.comp.glsl).
#include "shared/kernel.glsl"
#include "lib/bins.glsl"

layout(set = 0, binding = 0, std430) readonly buffer Bins {
    uint words[];
} bins;
layout(set = 0, binding = 1, std430) readonly buffer Keys {
    uvec2 keys[];
} keys;
layout(set = 0, binding = 2, std430) writeonly buffer List {
    uint items[];
} list;

layout(push_constant) uniform Push {
    uint width;
    uint height;
} push;

void main() {
    uvec2 item = gl_GlobalInvocationID.xy;
    if (item.x >= push.width || item.y >= push.height) {
        return;
    }
    uvec2 key = keys.keys[item.y * push.width + item.x];
    if (key.x == BIN_NONE) {
        return;
    }
    list.items[bins.words[key.x * BIN_STRIDE + BIN_OFFSET] + key.y] = bin_pack(item);
}
