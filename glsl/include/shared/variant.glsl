// Specialization constants of the shading passes. Mirrors `ShadeSpec` in
// src/shader/variant.rs (ids and order); the codes follow the value tables there.
#ifndef LAMINA_SHARED_VARIANT
#define LAMINA_SHARED_VARIANT

layout(constant_id = 0) const uint MODEL = 0;
layout(constant_id = 1) const uint MAX_LAYERS = 4;
layout(constant_id = 2) const uint TIR_MODE = 0;
layout(constant_id = 3) const uint FGD_MODE = 0;
layout(constant_id = 4) const uint G2_MODE = 0;
layout(constant_id = 5) const uint NDF_MODE = 0;

#define MODEL_GGX 0u
#define MODEL_TM2 1u
#define MODEL_TM6 2u

#define G2_HEIGHT_CORRELATED 0u
#define G2_SMITH 1u
#define G2_SCHLICK 2u
#define G2_EARL 3u

#define NDF_GGX 0u
#define NDF_KARIS 1u

#endif
