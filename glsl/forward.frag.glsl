#version 460
// The shaded pass. MODEL = ggx: one GGX lobe with the split-sum IBL (Karis 2013), F0 from the
// layer's complex IOR — the yardstick every transfer-matrix variant is divided by.
#include "shared/frame.glsl"
#include "shared/variant.glsl"
#include "lib/precision.glsl"
#include "lib/fresnel.glsl"
#include "lib/ibl.glsl"

layout(set = 0, binding = 0, std140) uniform Frame {
    FrameConstants frame;
};
layout(set = 0, binding = 1) uniform samplerCube prefiltered;
layout(set = 0, binding = 2) uniform sampler2D split_sum;

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 0) out vec4 color;

// Radiance reflected by one GGX lobe of directional albedo `f0·A + B`.
vec3 shade_ggx(vec3 n, vec3 v, float alpha) {
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec2 ab = texture(split_sum, vec2(n_dot_v, sqrt(alpha))).rg;
    real3 f0 = f0_complex(real3(frame.base_ior.rgb), real3(frame.base_kappa.rgb));
    real3 albedo = f0 * real(ab.x) + real(ab.y);
    vec3 r = reflect(-v, n);
    float mip_count = frame.params.y;
    vec3 dir = ibl_dominant_direction(n, r, alpha);
    vec3 radiance = textureLod(prefiltered, dir, ibl_mip_of_alpha(alpha, mip_count)).rgb;
    return vec3(real3(radiance) * albedo);
}

void main() {
    vec3 n = normalize(world_normal);
    vec3 v = normalize(frame.camera_pos.xyz - world_position);
    float alpha = frame.params.x;
    color = vec4(shade_ggx(n, v, alpha), 1.0);
}
