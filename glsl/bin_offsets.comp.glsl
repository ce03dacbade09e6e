#version 460
// The deferred path's classification, second step (src/render/deferred.rs): one invocation
// turns the bins' item counts (bin_count.comp.glsl) into each bin's offset in the list (the
// counts before it) and its indirect dispatch's work-group counts: one group per
// `per_group` items (a tile per group, or a group's worth of pixels).
#include "shared/kernel.glsl"
#include "lib/bins.glsl"

layout(set = 0, binding = 0, std430) buffer Bins {
    uint words[];
} bins;

layout(push_constant) uniform Push {
    uint per_group;
} push;

void main() {
    uint offset = 0u;
    for (uint bin = 0u; bin < BIN_COUNT; ++bin) {
        uint base = bin * BIN_STRIDE;
        uint items = bins.words[base + BIN_ITEMS];
        bins.words[base + BIN_GROUPS] = (items + push.per_group - 1u) / push.per_group;
        bins.words[base + BIN_GROUPS + 1u] = 1u;
        bins.words[base + BIN_GROUPS + 2u] = 1u;
        bins.words[base + BIN_OFFSET] = offset;
        offset += items;
    }
}
