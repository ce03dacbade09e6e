#version 460
#include "bindings/scene.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;
layout(location = 2) out vec2 surface_uv;

void main() {
    world_position = position;
    world_normal = normal;
    surface_uv = uv;
    gl_Position = frame.view_proj * vec4(position, 1.0);
}
