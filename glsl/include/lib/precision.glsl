// Arithmetic precision of the shading math: `real` is float16_t under the `fp16` variant
// (LAMINA_FP16, needs the shaderFloat16 device feature), float otherwise. Storage and
// interpolants stay 32-bit; only the per-pixel math of the 2-flux model and the ggx baseline
// narrows (the 6-flux model's 3×3 adding state needs float, tm6.glsl).
#ifndef LAMINA_LIB_PRECISION
#define LAMINA_LIB_PRECISION

#ifdef LAMINA_FP16
#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require
#define real float16_t
#define real2 f16vec2
#define real3 f16vec3
#define real4 f16vec4
// Smallest cosine used as a divisor: the smallest normal half float.
#define REAL_MIN_COS real(6.2e-5)
// Smallest denominator the adding equations divide by: the smallest normal half float
// (src/model/adding.rs: it only turns 0/0 into 0).
#define REAL_GAP_FLOOR 6.103515625e-5
#else
#define real float
#define real2 vec2
#define real3 vec3
#define real4 vec4
#define REAL_MIN_COS 1e-20
// Smallest denominator the adding equations divide by: the smallest normal float
// (src/model/adding.rs: it only turns 0/0 into 0).
#define REAL_GAP_FLOOR 1.17549435e-38
#endif

#endif
