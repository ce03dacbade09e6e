//! Precomputed tables the shading passes sample: the GGX-prefiltered environment, the
//! split-sum (Karis) table, the other FGD tables and the TIR table. Each is generated on the GPU by a compute pass and has a CPU f64
//! reference for spot checks.

pub mod belcour;
pub mod cache;
pub mod environment;
pub mod fgd;
pub mod fgd_study;
pub mod split_sum;
pub mod tir;

/// Work-group edge of lamina's 2-D compute passes (reaches GLSL as `LAMINA_LOCAL_SIZE_2D`).
pub const LOCAL_SIZE_2D: u32 = 8;

/// Work groups needed to cover `n` invocations along one axis.
pub fn groups(n: u32) -> u32 {
    n.div_ceil(LOCAL_SIZE_2D)
}
