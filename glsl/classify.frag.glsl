#version 460
// The stencil marks of a varying stack under a per-material mode (src/render/classes.rs): one
// draw per coverage map that differs over the surface, each keeping only the fragments where
// material layer MARK_LAYER is covered (lib/tm_common.glsl's tm_covered, the test the generic
// pass makes), whose stencil bit the pipeline then sets. Every class's pipeline shades the
// pixels whose bits are its own. No colour is written.
#define TM_SURFACE_MAPS
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "bindings/scene.glsl"
#include "lib/tm_common.glsl"

layout(location = 2) in vec2 surface_uv;

void main() {
    tm_surface_uv = surface_uv;
    tm_surface_pixel = ivec2(gl_FragCoord.xy);
    if (!tm_covered(MARK_LAYER)) {
        discard;
    }
}
