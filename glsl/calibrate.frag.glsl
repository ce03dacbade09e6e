#version 460
// `lamina devices --calibrate`, fragment side: the calibration loop (lib/calibrate.glsl) at
// every pixel of a full-screen triangle (sky.vert.glsl), its result written out.
#include "lib/calibrate.glsl"

layout(push_constant) uniform Push {
    uint iterations;
    uint width;
} push;

layout(location = 0) in vec2 ndc;
layout(location = 0) out vec4 color;

void main() {
    uvec2 p = uvec2(gl_FragCoord.xy);
    color = calibrate_loop(p.y * push.width + p.x, push.iterations);
}
