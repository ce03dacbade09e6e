// Specialization constants of the shading passes. Mirrors `ShadeSpec` in
// src/variant.rs (ids 0…22 and order, the values from id 32 in generated/layer_values.glsl);
// the codes follow the value tables there.
#ifndef LAMINA_SHARED_VARIANT
#define LAMINA_SHARED_VARIANT

// [[unroll]] on the loops of a per-material pipeline, whose trip counts are constants.
#extension GL_EXT_control_flow_attributes : require

layout(constant_id = 0) const uint MODEL = 0;
layout(constant_id = 1) const uint MAX_LAYERS = 4;
layout(constant_id = 2) const uint TIR_MODE = 0;
// The `fgd` axis in its low byte; bit 8, FGD_PAST_EDGE: the stack's lookups may fall past the
// 4-D table's η, κ ≤ 4 (src/render/pass.rs's past_fgd_edge), and lib/fgd.glsl keeps the code
// that carries FGD on from its edge; 0 folds it away.
layout(constant_id = 3) const uint FGD_SPEC = 0;
const uint FGD_MODE = FGD_SPEC & 0xFFu;
const uint FGD_PAST_EDGE = (FGD_SPEC >> 8) & 1u;
layout(constant_id = 4) const uint G2_MODE = 0;
layout(constant_id = 5) const uint NDF_MODE = 0;
// The work-group width of the compute entry points that shade (tm_eval, fgd_probe):
//   layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID) in;
#define SHADE_LOCAL_SIZE_X_ID 6
layout(constant_id = 7) const uint MODE = 0;
// The structure of the material a per-material pipeline (every MODE but generic) is built
// for, from src/specialize.rs: the layer count, and per-layer bit masks (bit i: layer i, top
// first). Zero under MODE_GENERIC, where the shader reads the same facts from the material.
layout(constant_id = 8) const uint LAYER_COUNT = 0;
layout(constant_id = 9) const uint SMOOTH_MASK = 0;      // α = 0: Fresnel, no FGD lookup
layout(constant_id = 10) const uint CONDUCTOR_BASE = 0;  // 1: the last layer is a conductor
layout(constant_id = 11) const uint MEDIUM_MASK = 0;     // a 6-flux medium (depth > 0)
layout(constant_id = 12) const uint DENSER_MASK = 0;     // η_ij ≥ 1: TIR only going up
layout(constant_id = 13) const uint MATCHED_MASK = 0;    // index-matched: no interface
layout(constant_id = 14) const uint CLEAR_MASK = 0;      // refracts, reflects nothing
// MODE_BAKED: the lobe count, the lobes lit around the view, the samples per lobe.
layout(constant_id = 15) const uint LOBE_COUNT = 0;
layout(constant_id = 16) const uint RETRO_MASK = 0;
layout(constant_id = 17) const uint BAKED_SIZE = 0;
// Non-zero: the stack varies over the surface (maps, coverage), and bit k
// says which field some layer reads from a map (src/material/surface.rs's spec_bits): the
// forward pass reads each pixel's layers through lib/tm_common.glsl's surface lookups.
layout(constant_id = 18) const uint SURFACE_MAPS = 0;
// 1: the stack may end in a diffuse base (src/model/diffuse.rs); 0 folds its code away.
layout(constant_id = 19) const uint DIFFUSE_BASE = 0;
// 1: the scene has analytic lights (render::lights); 0 folds the light loops away.
layout(constant_id = 20) const uint LIGHTS = 0;
// TRANSPORT_PAPER or TRANSPORT_CORRECTED: under `corrected` each layer's lobes are scaled by
// the material's energy ratios (material.transport, src/model/transport.rs).
layout(constant_id = 21) const uint TRANSPORT = 0;
// 1: the stack may end in a dielectric (neither a conductor nor a diffuse base) and transmits:
// the forward pass shades what it transmits from behind the surface; 0 folds that code away.
layout(constant_id = 22) const uint TRANSMITS = 0;
// The `ibl` axis in its low byte — IBL_SPLIT_SUM, IBL_MATCHED, IBL_TAPS, IBL_ANISOTROPIC or
// IBL_LAMPS: how the environment lights each lobe (lib/shade.glsl's lobe_radiance) — and above
// it `taps`, the directions ibl=taps reads per lobe (src/variant.rs, VariantKey::spec).
layout(constant_id = 23) const uint IBL_SPEC = 0;
const uint IBL = IBL_SPEC & 0xFFu;
const uint IBL_TAP_COUNT = IBL_SPEC >> 8;
// A varying stack under a per-material mode (SURFACE_MAPS and SPECIALIZED): the pipeline
// shades one class of pixels, those whose coverage leaves the same layers (src/render/
// classes.rs). LAYER_SLOTS_LO/HI: slot i's layer of the material, 4 bits each (slots 0–7 in
// LO, 8–15 in HI); DYNAMIC_MASK: the slots whose maps carry a value across one of the
// model's tests, which such a slot makes at run time as the generic pipeline does.
layout(constant_id = 24) const uint DYNAMIC_MASK = 0;
layout(constant_id = 25) const uint LAYER_SLOTS_LO = 0;
layout(constant_id = 26) const uint LAYER_SLOTS_HI = 0;
// classify.frag.glsl: the material layer whose coverage the pass marks in the stencil.
layout(constant_id = 27) const uint MARK_LAYER = 0;
// A class's pass: per slot, a byte of the fields its layer reads from maps (η, κ, σs, σa, α,
// depth, g, diffuse albedo from bit 0), four slots per word (lib/tm_common.glsl's
// tm_slot_maps).
layout(constant_id = 28) const uint SLOT_MAPS_0 = 0;
layout(constant_id = 29) const uint SLOT_MAPS_1 = 0;
layout(constant_id = 30) const uint SLOT_MAPS_2 = 0;
layout(constant_id = 31) const uint SLOT_MAPS_3 = 0;

// The codes of every axis value (MODEL_TM2, TIR_LUT32, FGD_RESAMPLED4D, G2_EARL, …), written
// from the Rust value tables by src/shader/compiler.rs.
#include "../generated/codes.glsl"

// Whether the pipeline knows the material's structure.
const bool SPECIALIZED = MODE != MODE_GENERIC;

#endif
