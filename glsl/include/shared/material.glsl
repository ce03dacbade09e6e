// The layer stack as the shaders read it. Mirrors `MaterialGpu` in src/shader/interface.rs
// (std430, which lays these vec4s out as std140 would; the Rust side asserts size and offsets,
// tests/suite/reflection.rs compares them with the compiled block). The array has the host's fixed maximum;
// the shading loops run over `info.x` layers into function-local arrays sized by MAX_LAYERS.
#ifndef LAMINA_SHARED_MATERIAL
#define LAMINA_SHARED_MATERIAL

struct LayerGpu {
    vec4 ior;      // rgb: η of the layer (absolute)
    vec4 kappa;    // rgb: κ of the layer; > 0 in any channel: conductor (last layer)
    vec4 sigma_s;  // rgb: scattering coefficient of the medium (6-flux)
    vec4 sigma_a;  // rgb: absorption coefficient of the medium (6-flux)
    vec4 params;   // x: GGX α of the top interface, y: medium depth, z: HG g, w: unused
    vec4 diffuse;  // w = 1: a Lambertian base of albedo rgb, which ends the stack
                   // (src/model/diffuse.rs); w = 0 for every other layer
};

struct MaterialGpu {
    uvec4 info;    // x: layer count
    LayerGpu layers[LAMINA_MAX_LAYERS_LIMIT];
    // Per layer, the maps of a spatially varying stack (src/material/surface.rs): a byte per
    // field, 0 (constant) or 1 + the slice of `layer_maps`, bit 7 set for screen coordinates.
    // x: η, κ, σs, σa; y: α, depth, g, coverage (low byte first). Zeros for a uniform stack.
    uvec4 maps[LAMINA_MAX_LAYERS_LIMIT];
    // Then, at LAMINA_TRANSPORT_OFFSET, transport=corrected's energy ratios, which the shaders
    // read through a uniform-buffer view of the same buffer (bindings/shading.glsl's
    // TransportRatios).
};

#endif
