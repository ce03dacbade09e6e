// The bins of the deferred path's classification (classify=tiles|pixels;
// src/render/deferred.rs's Bins, which mirrors these constants): one bin per class of pixels,
// named by the class's marked bits (render::classes: bit k set where mark k's coverage holds
// its layer), and one more for the tiles whose pixels mix classes. A bin's header is
// BIN_STRIDE words: the indirect dispatch's work-group counts (x, y, z), the count of its
// items (pixels or tiles), and the offset of its first item in the list.
#ifndef LAMINA_LIB_BINS
#define LAMINA_LIB_BINS

const uint BIN_MIXED = 256u;
const uint BIN_COUNT = 257u;
const uint BIN_STRIDE = 8u;
const uint BIN_GROUPS = 0u;
const uint BIN_ITEMS = 3u;
const uint BIN_OFFSET = 4u;
// An item (a pixel, or a tile) that no bin holds: the mesh covers none of it.
const uint BIN_NONE = 0xffffffffu;

// An item's place in the list: its pixel or tile coordinates, 16 bits each.
uint bin_pack(uvec2 item) {
    return (item.y << 16) | item.x;
}

uvec2 bin_unpack(uint packed) {
    return uvec2(packed & 0xffffu, packed >> 16);
}

#endif
