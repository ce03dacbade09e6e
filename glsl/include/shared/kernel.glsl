// Specialization constants of the table and utility kernels — not the shading passes'
// (shared/variant.glsl): the work-group size, set by the host from the kernel's interface,
// and the G2 form a table is built for. Mirrors `KernelSpec` in src/shader/kernel.rs (ids and
// order). Tables use the reference GGX D (NDF_GGX): the ndf axis picks the shading passes'
// arrangement of it.
#ifndef LAMINA_SHARED_KERNEL
#define LAMINA_SHARED_KERNEL

layout(local_size_x_id = 0, local_size_y_id = 1) in;
layout(constant_id = 2) const uint G2_MODE = 0;

#include "../generated/codes.glsl"

const uint NDF_MODE = NDF_GGX;

#endif
