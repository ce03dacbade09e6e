#version 460
// Resamples an equirectangular environment into mip 0 of a cube map (one invocation per
// destination texel, z = face), bilinearly.
#include "shared/kernel.glsl"
#include "lib/cubemap.glsl"
#include "lib/equirect.glsl"

layout(set = 0, binding = 0) uniform sampler2D equirect;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray cube;

layout(push_constant) uniform Push {
    uint face_size;
} push;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= push.face_size || id.y >= push.face_size) {
        return;
    }
    vec2 uv = (vec2(id.xy) + 0.5) / float(push.face_size);
    vec3 dir = cube_direction(id.z, uv);
    vec4 radiance = textureLod(equirect, equirect_uv(dir), 0.0);
    imageStore(cube, ivec3(id), vec4(radiance.rgb, 1.0));
}
