//! The FGD error studies (issue #6): how far the resampled 4-D table is from the full one, and
//! how far each `fgd` value is from the exact directional albedo. `lamina tables fgd-resampled`
//! and `lamina tables fgd-belcour` print them; the numbers land in profiling/TABLES.md.

use crate::model::fgd::ExactFgd;
use crate::model::Fgd as _;
use crate::shader::G2;

use super::fgd::{resampled_at, BelcourTable, Grid};

/// Absolute errors over a set of points.
#[derive(Clone, Copy, Debug)]
pub struct Errors {
    pub max_abs: f64,
    pub mean_abs: f64,
    pub points: usize,
    /// (μ, α, η, κ) of the largest error.
    pub worst_at: [f64; 4],
    sum: f64,
}

impl Default for Errors {
    fn default() -> Self {
        Self {
            max_abs: 0.0,
            mean_abs: 0.0,
            points: 0,
            worst_at: [0.0; 4],
            sum: 0.0,
        }
    }
}

impl Errors {
    pub fn add(&mut self, error: f64, at: [f64; 4]) {
        let e = error.abs();
        self.sum += e;
        self.points += 1;
        self.mean_abs = self.sum / self.points as f64;
        if e > self.max_abs || self.points == 1 {
            self.max_abs = e;
            self.worst_at = at;
        }
    }
}

/// `fgd=resampled4d` (CPU twin of its lookup) against the 4-D table at every vertex of the
/// 4-D grid: the error the resampling adds where the full table is exact to itself. Also
/// returns, per (κ, η) vertex, the largest error over (μ, α): `map[l][k]`.
pub fn resampling_error(grid: &Grid, resampled: &[f32]) -> (Errors, Vec<Vec<f64>>) {
    let [nm, na, ne, nk] = grid.dims;
    let mut errors = Errors::default();
    let mut map = vec![vec![0.0f64; ne as usize]; nk as usize];
    for l in 0..nk {
        for k in 0..ne {
            for j in 0..na {
                for i in 0..nm {
                    let at = grid.coordinates(i, j, k, l);
                    let e = resampled_at(grid, resampled, i, j, k, at[3])
                        - f64::from(grid.texel(i, j, k, l));
                    errors.add(e, at);
                    let cell = &mut map[l as usize][k as usize];
                    *cell = cell.max(e.abs());
                }
            }
        }
    }
    (errors, map)
}

/// `count` points (μ, α, η, κ) spread over the 4-D table's domain by a fixed low-discrepancy
/// sequence (R4, Roberts 2018), so every run probes the same points.
pub fn probe_points(count: usize, eta_max: f64, kappa_max: f64) -> Vec<[f32; 4]> {
    // The inverse powers of the unique positive root of x⁵ = x + 1.
    let phi = 1.167_303_978_261_418_7_f64;
    let step = [1.0 / phi, phi.powi(-2), phi.powi(-3), phi.powi(-4)];
    (0..count)
        .map(|n| {
            let u = step.map(|s| (0.5 + s * (n + 1) as f64).fract());
            [
                u[0].max(0.01) as f32,
                u[1] as f32,
                (u[2] * eta_max) as f32,
                (u[3] * kappa_max) as f32,
            ]
        })
        .collect()
}

/// The interfaces of the accuracy study, by what they ask of a table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Dielectric, relative IOR above 1 (entering a denser medium).
    DielectricAbove1,
    /// Dielectric, relative IOR below 1 (leaving a denser layer): total internal reflection.
    DielectricBelow1,
    /// Conductor with κ inside the 4-D table's [0, 4].
    Conductor,
    /// Conductor with κ beyond 4 (aluminium): the 4-D tables clamp.
    ConductorBeyondTable,
}

impl Class {
    pub const ALL: [Class; 4] = [
        Class::DielectricAbove1,
        Class::DielectricBelow1,
        Class::Conductor,
        Class::ConductorBeyondTable,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Self::DielectricAbove1 => "dielectric, η > 1",
            Self::DielectricBelow1 => "dielectric, η < 1",
            Self::Conductor => "conductor, κ ≤ 4",
            Self::ConductorBeyondTable => "conductor, κ > 4",
        }
    }
}

/// One interface of the study: a label, its class and its relative complex IOR.
pub struct Interface {
    pub label: String,
    pub class: Class,
    pub eta: f64,
    pub kappa: f64,
}

/// Dielectrics on both sides of 1, and the RGB channels of ALGORITHMS.md §12.2's metals,
/// bare and under a 1.5 coat (what a varnished metal's lower interface sees).
pub fn interfaces() -> Vec<Interface> {
    let mut out = Vec::new();
    for eta in [1.1, 1.2, 1.33, 1.5, 2.0, 2.4] {
        out.push(Interface {
            label: format!("dielectric {eta}"),
            class: Class::DielectricAbove1,
            eta,
            kappa: 0.0,
        });
        out.push(Interface {
            label: format!("dielectric 1/{eta}"),
            class: Class::DielectricBelow1,
            eta: 1.0 / eta,
            kappa: 0.0,
        });
    }
    let metals: [(&str, [f64; 3], [f64; 3]); 5] = [
        (
            "Au",
            [0.143245, 0.377423, 1.43919],
            [3.98479, 2.3847, 1.60434],
        ),
        (
            "Ag",
            [0.15554, 0.11678, 0.138371],
            [4.83139, 3.12331, 2.14745],
        ),
        (
            "Al",
            [1.66058, 0.88143, 0.521467],
            [9.2282, 6.27077, 4.83803],
        ),
        (
            "Cu",
            [0.208183, 0.919438, 1.10241],
            [3.92198, 2.45627, 2.14157],
        ),
        (
            "Cr",
            [4.48917, 2.90664, 1.66205],
            [5.21625, 4.22766, 3.75206],
        ),
    ];
    for (name, eta, kappa) in metals {
        for (coat, scale) in [("", 1.0), (" under 1.5", 1.5)] {
            for (c, channel) in ["R", "G", "B"].iter().enumerate() {
                let k = kappa[c] / scale;
                out.push(Interface {
                    label: format!("{name} {channel}{coat}"),
                    class: if k > super::fgd::KAPPA_MAX {
                        Class::ConductorBeyondTable
                    } else {
                        Class::Conductor
                    },
                    eta: eta[c] / scale,
                    kappa: k,
                });
            }
        }
    }
    out
}

/// The (μ, α) pairs of the accuracy study: ALGORITHMS.md §7.5's grid.
pub const MU: [f64; 3] = [1.0, 0.5, 0.15];
pub const ALPHA: [f64; 3] = [0.05, 0.3, 0.7];

/// Every (interface, μ, α) point of the study as (μ, α, η, κ), with its class and the exact
/// FGD (CPU f64 quadrature at `resolution`²).
pub fn exact_points(g2: G2, resolution: u32) -> Vec<([f64; 4], Class, f64)> {
    let exact = ExactFgd { g2, resolution };
    let mut out = Vec::new();
    for interface in interfaces() {
        for mu in MU {
            for alpha in ALPHA {
                let value = exact.fgd(mu, alpha, interface.eta, interface.kappa);
                out.push((
                    [mu, alpha, interface.eta, interface.kappa],
                    interface.class,
                    value,
                ));
            }
        }
    }
    out
}

/// Belcour's reconstruction with no fallback (what the decomposition gives on its own, from
/// the CPU twin of the raw table): the breakdown below η = 1 shows here.
pub fn belcour_unguarded(table: &BelcourTable, at: [f64; 4]) -> f64 {
    let [mu, alpha, eta, kappa] = at;
    table.basis.reconstruct(table.sample(mu, alpha), eta, kappa)
}
