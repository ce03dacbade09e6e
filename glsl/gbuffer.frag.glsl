#version 460
// The G-buffer of the deferred path (path=deferred, src/render/deferred.rs): per pixel, what
// the forward pass's fragment shader receives from forward.vert.glsl — the world position and
// normal as interpolated (the normal not normalised), and the texture coordinates — for
// deferred.comp.glsl to shade. A pixel the mesh leaves keeps the clear value, a zero normal.
layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 surface_uv;
layout(location = 0) out vec4 position_u;
layout(location = 1) out vec4 normal_v;

void main() {
    position_u = vec4(world_position, surface_uv.x);
    normal_v = vec4(world_normal, surface_uv.y);
}
