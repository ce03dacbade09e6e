#version 460
// Background: the environment's radiance along each view ray (cube mip 0, unfiltered), at
// the scene's scale of it.
#include "bindings/scene.glsl"

layout(location = 0) in vec2 ndc;
layout(location = 0) out vec4 color;

void main() {
    vec4 far_point = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 dir = normalize(far_point.xyz / far_point.w - frame.camera_pos.xyz);
    color = vec4(textureLod(prefiltered, dir, 0.0).rgb * frame.params.y, 1.0);
}
