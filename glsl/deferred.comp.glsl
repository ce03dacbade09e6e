#version 460
// The deferred path's shading (path=deferred, classify=none; src/render/deferred.rs): one
// invocation per pixel of the frame, in 8×8 tiles, each shading its pixel as the forward
// pass's fragment shader would (lib/deferred.glsl).
#define TM_SURFACE_MAPS
#include "shared/variant.glsl"
#include "bindings/shading.glsl"
#include "bindings/scene.glsl"

#include "lib/shade.glsl"
#include "lib/deferred.glsl"

// The tile's width is the shading passes' work-group constant; its height is fixed here and
// in the kernel's interface (render::deferred::KERNEL).
layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID, local_size_y = 8) in;

layout(push_constant) uniform Push {
    uint width;
    uint height;
} push;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= push.width || pixel.y >= push.height) {
        return;
    }
    deferred_shade(pixel);
}
