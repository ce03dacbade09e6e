//! Precomputed tables the shading passes sample: the GGX-prefiltered environment, the
//! split-sum (Karis) table, the other FGD tables and the TIR table. Each is generated on the GPU
//! by a compute pass, has a CPU f64 reference for spot checks, and a CPU twin that looks it up
//! as the shader's sampler does ([`filter_axis`]).
//!
//! What `lamina tables` prints is computed here too: [`spot`] (every table's spot check),
//! [`tir_study`] and [`fgd_study`] (the error studies of profiling/TABLES.md), and [`tir_fit`]
//! (the coefficients of `tir=fit`).

pub mod belcour;
pub mod environment;
pub mod fgd;
pub mod fgd_study;
pub mod irradiance;
pub mod lamps;
pub mod lobe_albedo;
pub mod lobe_fit;
pub mod lobe_moments;
pub mod split_sum;
pub mod spot;
pub mod tir;
pub mod tir_fit;
pub mod tir_study;

/// How a table's texels sit on its axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Texels {
    /// Texel i at (i + ½)/n: a normalised coordinate u read as is (`texture(t, u)`).
    Centred,
    /// Texel i at i/(n − 1): the shaders remap x to (x·(n − 1) + ½)/n.
    Vertices,
}

/// The two texels a linear filter reads on one axis of `n` texels at coordinate `x` ∈ [0, 1]
/// (clamped to the edge), as (lower index, weight of the upper one). lavapipe filters float
/// textures with float weights (rounding them to 8 bits, its `subTexelPrecisionBits`, moved the
/// twins further from it).
pub fn filter_axis(x: f64, n: usize, texels: Texels) -> (usize, f64) {
    let x = x.clamp(0.0, 1.0);
    let f = match texels {
        Texels::Centred => (x * n as f64 - 0.5).clamp(0.0, (n - 1) as f64),
        Texels::Vertices => x * (n - 1) as f64,
    };
    let i0 = (f.floor() as usize).min(n - 2);
    (i0, f - i0 as f64)
}
