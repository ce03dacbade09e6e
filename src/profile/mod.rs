//! Measuring variants: the bench runner, its statistics and its result files.

pub mod bench;
pub mod stats;
