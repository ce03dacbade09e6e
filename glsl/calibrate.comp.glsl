#version 460
// `lamina devices --calibrate`, compute side: the calibration loop (lib/calibrate.glsl) once
// per pixel, `count` pixels in all, each result written to the buffer.
#include "shared/kernel.glsl"

layout(set = 0, binding = 0, std430) writeonly buffer Result {
    vec4 values[];
} result;

layout(push_constant) uniform Push {
    uint iterations;
    uint count;
} push;

#include "lib/calibrate.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) {
        return;
    }
    result.values[i] = calibrate_loop(i, push.iterations);
}
