// Set 1 of the scene's graphics passes (forward, sky): the frame constants, the prefiltered
// environment and the analytic lights. Mirrors SCENE_BINDINGS in src/shader/interface.rs. The
// lights are a storage buffer for the material's reason (bindings/shading.glsl): lavapipe would
// inline a uniform light count into the shader and recompile it per count.
#ifndef LAMINA_BINDINGS_SCENE
#define LAMINA_BINDINGS_SCENE

#include "../shared/frame.glsl"
#include "../shared/light.glsl"

layout(set = 1, binding = 0, std140) uniform Frame {
    FrameConstants frame;
};
layout(set = 1, binding = 1) uniform samplerCube prefiltered;
layout(set = 1, binding = 2, std430) readonly buffer Lights {
    uvec4 light_info;  // x: light count
    LightGpu lights[];
};
// The environment's importance sampling (tables::environment::sampling_tables): over a grid of
// x × y equirect cells, the marginal CDF of the rows (y floats), then each row's CDF over its
// cells (x floats per row). A reference pass draws environment directions from it.
layout(set = 1, binding = 3, std430) readonly buffer EnvironmentSampling {
    uvec4 env_sampling_info;  // x, y: the grid
    float env_cdf[];
};
// The environment prefiltered with the lobe's own weighting (tables::environment's matched
// cube), which `ibl=matched`, `ibl=taps` and `ibl=anisotropic` read; under `ibl=lamps`, Karis's
// cube of the map without its lamps (tables::lamps); a split-sum pass never reads it.
layout(set = 1, binding = 4) uniform samplerCube matched;
// Each GGX lobe's mean direction and spread over (√μ, √α) (tables::lobe_moments): where and at
// which mip `ibl=matched` reads the matched cube.
layout(set = 1, binding = 5) uniform sampler2D lobe_moments;
// Under `ibl=lamps`, the irradiance of the map without its lamps at each normal
// (tables::irradiance::irradiance_cube), which lights a diffuse base; no other pass reads it.
layout(set = 1, binding = 6) uniform samplerCube lamps_irradiance;

#endif
