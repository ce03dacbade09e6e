#version 460
// Samples FGD(μ, α, η, κ) at given points exactly as the shading passes do (lib/fgd.glsl, the
// FGD_MODE constant): the GPU side of the FGD error studies and table tests.
#include "shared/variant.glsl"
#include "bindings/shading.glsl"

layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID) in;

layout(set = 1, binding = 0, std430) readonly buffer Points {
    vec4 points[];   // (μ, α, η, κ)
} points;
layout(set = 1, binding = 1, std430) writeonly buffer Values {
    float values[];
} values;

layout(push_constant) uniform Push {
    uint count;
} push;

#include "lib/fgd.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) {
        return;
    }
    vec4 p = points.points[i];
    values.values[i] = fgd_channel(p.x, p.y, p.z, p.w);
}
