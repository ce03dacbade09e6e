#version 460
#include "bindings/scene.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;

void main() {
    world_position = position;
    world_normal = normal;
    gl_Position = frame.view_proj * vec4(position, 1.0);
}
