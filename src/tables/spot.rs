//! Spot checks: 16 texels of each GPU-built table against the table's f64 reference, spread
//! over the grid with its corners (what `lamina tables …` prints on its second line). They
//! catch a shader that drifted from its reference without running the full error studies.

use crate::model::fgd::ExactFgd;
use crate::model::tir::trapped_fraction;
use crate::model::Fgd as _;
use crate::variant::G2;

use super::fgd::{belcour_reference, BelcourTable, Grid};
use super::fgd_study::{Errors, EXACT_RESOLUTION};
use super::split_sum::{self, SplitSumTable};
use super::tir::TirTable;

/// Points per axis of the references' midpoint rules (the 2-D tables and the TIR table).
pub const REFERENCE_RESOLUTION: u32 = 256;

/// 16 texel indices spread over an n×n grid, corners included.
pub fn points(n: u32) -> Vec<(u32, u32)> {
    let at = [0, (n - 1) / 3, 2 * (n - 1) / 3, n - 1];
    at.iter()
        .flat_map(|&i| at.iter().map(move |&j| (i, j)))
        .collect()
}

/// Largest |texel − f64 reference| of the split-sum (Karis) table built with `g2`, over both
/// channels.
pub fn split_sum(table: &SplitSumTable, g2: G2) -> f64 {
    points(table.size)
        .into_iter()
        .map(|(i, j)| {
            let (mu, alpha) = table.coordinates(i, j);
            let cpu = split_sum::cpu_reference(mu, alpha, g2, REFERENCE_RESOLUTION);
            let gpu = table.texel(i, j);
            (f64::from(gpu[0]) - cpu[0])
                .abs()
                .max((f64::from(gpu[1]) - cpu[1]).abs())
        })
        .fold(0.0, f64::max)
}

/// Largest |texel − f64 reference| of the TIR table, one interior η slice per (μ, α) point.
pub fn tir(table: &TirTable) -> f64 {
    let n = table.size;
    points(n)
        .into_iter()
        .map(|(i, j)| {
            let k = 1 + (i * 7 + j * 3) % (n - 2);
            let (mu, alpha, eta) = table.coordinates(i, j, k);
            let cpu = trapped_fraction(mu, alpha, eta, REFERENCE_RESOLUTION);
            (f64::from(table.texel(i, j, k)) - cpu).abs()
        })
        .fold(0.0, f64::max)
}

/// 16 interior vertices of a 4-D FGD grid built with `g2` against the f64 quadrature
/// ([`EXACT_RESOLUTION`]² points).
pub fn grid(grid: &Grid, g2: G2) -> Errors {
    let exact = ExactFgd {
        g2,
        resolution: EXACT_RESOLUTION,
    };
    let [n, _, ne, nk] = grid.dims;
    let mut errors = Errors::default();
    for (i, j) in points(n) {
        let i = i.max(1);
        let k = 1 + (i * 7 + j * 3) % (ne - 1);
        let l = if nk > 1 { (i * 5 + j * 11) % nk } else { 0 };
        let at = grid.coordinates(i, j, k, l);
        let [mu, alpha, eta, kappa] = at;
        errors.add(
            exact.fgd(mu, alpha, eta, kappa) - f64::from(grid.texel(i, j, k, l)),
            at,
        );
    }
    errors
}

/// Largest |L_k − f64 reference| of the Belcour table built with `g2`, over its four
/// integrals.
pub fn belcour(table: &BelcourTable, g2: G2) -> f64 {
    points(table.size)
        .into_iter()
        .flat_map(|(i, j)| {
            let (mu, alpha) = table.coordinates(i, j);
            let cpu = belcour_reference(&table.basis, mu, alpha, g2, REFERENCE_RESOLUTION);
            let gpu = table.raw[(j * table.size + i) as usize];
            (0..4).map(move |k| (f64::from(gpu[k]) - cpu[k]).abs())
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_points_cover_the_corners() {
        let p = points(64);
        assert_eq!(p.len(), 16);
        for corner in [(0, 0), (0, 63), (63, 0), (63, 63), (21, 42)] {
            assert!(p.contains(&corner), "{corner:?}");
        }
    }
}
