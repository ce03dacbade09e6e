// Set 0 of every entry point that evaluates the model: the layer stack and the tables the
// variant samples. Mirrors SHADING_BINDINGS in src/render/inputs.rs (tests/suite/reflection.rs
// compares the compiled SPIR-V with it). The material is a storage buffer: lavapipe inlines
// uniform-buffer values that feed control flow into the shader and recompiles it per material
// (src/shader/interface.rs); only its energy ratios, read at per-pixel offsets, go through a
// uniform-buffer view (binding 8).
#ifndef LAMINA_BINDINGS_SHADING
#define LAMINA_BINDINGS_SHADING

#include "../shared/material.glsl"

layout(set = 0, binding = 0, std430) readonly buffer Material {
    MaterialGpu material;
};
layout(set = 0, binding = 1) uniform sampler2D split_sum;   // (A, B) at (μ, √α)
layout(set = 0, binding = 2) uniform sampler3D tir_table;   // (μ, α, η), vertex-centred
layout(set = 0, binding = 3) uniform sampler3D fgd_table;   // 4d, resampled4d, belcour's η < 1
layout(set = 0, binding = 4) uniform sampler2D fgd_belcour; // belcour's folded integrals
// MODE_BAKED: the material's lobes over the view cosine, (weight RGB, √α): lobe k in row k,
// sample j in column j at √μ = j/(BAKED_SIZE − 1) (vertex-centred), read with the linear filter.
layout(set = 0, binding = 5) uniform sampler2D baked_lobes;
// The directional albedo E of a white GGX lobe at (μ, √α) (vertex-centred texels), with the variant's G2 (f32,
// src/tables/lobe_albedo.rs): what the analytic lights normalise each lobe by (lib/light.glsl).
layout(set = 0, binding = 6) uniform sampler2D lobe_albedo;
// A spatially varying stack's maps (src/material/surface.rs), one slice per varying field,
// sampled bilinearly with repeat; a 1×1 placeholder for uniform stacks.
layout(set = 0, binding = 7) uniform sampler2DArray layer_maps;
// transport=corrected: the material's buffer again, as a uniform buffer (src/shader/interface.rs
// says why), holding per layer, then for the transmittance, the ratio of the transport's
// energy to the paper model's over each interval between LAMINA_TRANSPORT_POINTS evenly spaced
// view cosines (μ_k = k/(P − 1); src/model/transport.rs) as half-float pairs:
// x = (r, g), y = (b, Δr), z = (Δg, Δb) — the ratio at the lower cosine and its change to the
// upper one. Ratio 1 under transport=paper.
layout(set = 0, binding = 8, std140) uniform TransportRatios {
    layout(offset = LAMINA_TRANSPORT_OFFSET)
    uvec4 transport[(LAMINA_MAX_LAYERS_LIMIT + 1) * (LAMINA_TRANSPORT_POINTS - 1)];
};

#endif
