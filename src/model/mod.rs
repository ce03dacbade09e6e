//! The CPU reference in f64: pure functions the GPU is tested against.

pub mod microfacet;
