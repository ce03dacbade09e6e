//! Measuring variants: the bench runner, sweeps over variant axes, instruction counters, charts
//! and the report.

pub mod bench;
pub mod callgrind;
pub mod chart;
pub mod counter;
pub mod diff;
pub mod image_error;
pub mod prebuild;
pub mod report;
pub mod stats;
pub mod sweep;
