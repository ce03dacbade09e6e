//! Measuring one set of cases: the plan of a run, the bench (timings), the image errors
//! against the reference, the instruction counts under callgrind (and the table prebuild that
//! keeps a pinned run fast), and the results schema they fill. Nothing here knows the studies
//! and documents built on these measurements (`crate::study`).

pub mod bench;
pub mod calibrate;
pub mod callgrind;
pub mod count_worker;
pub mod counter;
pub mod image_error;
pub mod plan;
pub mod prebuild;
pub mod results;
