//! The coefficients of `tir=fit` ([`super::tir::FitTir`]; `TIR_FIT_COEFFICIENTS` in the
//! shaders' generated/codes.glsl), written by `lamina tables tir-fit --out src/model/tir_fit.rs`
//! from its least-squares fit to the TIR table's f64 reference (src/tables/tir_fit.rs). Do not
//! edit: rerun the command. A test refits and fails when they differ.

/// c0 … c6 of [`super::tir::FitTir`].
pub const COEFFICIENTS: [f64; 7] = [
    0.40202588157051494,
    -0.09864696505070758,
    -0.015780646216384395,
    0.3684017505659152,
    0.7726188367664242,
    0.2560542554613918,
    3.3282200545969647,
];
