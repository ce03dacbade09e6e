// Specialization constants of the shading passes. Mirrors `ShadeSpec` in
// src/variant.rs (ids 0…6 and order); the codes follow the value tables there.
#ifndef LAMINA_SHARED_VARIANT
#define LAMINA_SHARED_VARIANT

layout(constant_id = 0) const uint MODEL = 0;
layout(constant_id = 1) const uint MAX_LAYERS = 4;
layout(constant_id = 2) const uint TIR_MODE = 0;
layout(constant_id = 3) const uint FGD_MODE = 0;
layout(constant_id = 4) const uint G2_MODE = 0;
layout(constant_id = 5) const uint NDF_MODE = 0;
// The work-group width of the compute entry points that shade (tm_eval, fgd_probe):
//   layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID) in;
#define SHADE_LOCAL_SIZE_X_ID 6

// The codes of every axis value (MODEL_TM2, TIR_LUT32, FGD_RESAMPLED4D, G2_EARL, …), written
// from the Rust value tables by src/shader/compiler.rs.
#include "../generated/codes.glsl"

#endif
