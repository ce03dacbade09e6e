//! The FGD error studies (issue #6): how far the resampled 4-D table is from the full one, and
//! how far each `fgd` value is from the exact directional albedo; the shaders' own lookups
//! measured through `fgd_probe.comp.glsl`. `lamina tables fgd-4d | fgd-resampled |
//! fgd-belcour` print them; the numbers land in profiling/TABLES.md.
//!
//! The tables are built with [`G2_FORM`], the renderer's default, and compared with the exact
//! FGD at [`EXACT_RESOLUTION`]² quadrature points.

use std::path::Path;

use crate::error::Result;
use crate::gpu::Gpu;
use crate::model::fgd::ExactFgd;
use crate::model::Fgd as _;
use crate::variant::{Fgd, G2};

use super::belcour::Basis;
use super::fgd::{self, resampled_at, BelcourTable, FgdImages, FgdProbe, Filter, Grid, GridKind};
use super::split_sum::{self, SplitSumTable};
use crate::cache;

/// The G2 form `lamina tables` builds the FGD tables with: the renderer's default.
pub const G2_FORM: G2 = G2::HeightCorrelated;
/// Quadrature resolution of the exact FGD in the studies (within 1.3e-3 of the converged
/// value at α = 0.1, src/model/fgd.rs).
pub const EXACT_RESOLUTION: u32 = 256;
/// Points of the hardware-path comparison.
pub const PROBE_POINTS: usize = 20_000;

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

/// A 4-D grid as `lamina tables` asks for it: with `rebuild`, built on the GPU and stored in
/// `cache_dir` (`false`: not from the cache); otherwise [`fgd::load_or_build_grid`].
pub fn load_grid(
    gpu: &Gpu,
    kind: GridKind,
    size: u32,
    samples: u32,
    cache_dir: Option<&Path>,
    rebuild: bool,
    progress: impl FnMut(u32, u32),
) -> Result<(Grid, bool)> {
    if !rebuild {
        return fgd::load_or_build_grid(gpu, kind, G2_FORM, size, samples, cache_dir, progress);
    }
    let grid = fgd::build_grid(gpu, kind, G2_FORM, size, samples, progress)?;
    if let Some(dir) = cache_dir {
        let key = fgd::grid_cache_key(kind, G2_FORM, size, samples);
        cache::store(dir, &key, &grid.texels)?;
    }
    Ok((grid, false))
}

/// The Belcour table likewise: with `rebuild`, built with a freshly fitted basis (and not
/// stored); otherwise [`BelcourTable::load_or_build`].
pub fn load_belcour(
    gpu: &Gpu,
    size: u32,
    samples: u32,
    cache_dir: Option<&Path>,
    rebuild: bool,
) -> Result<(BelcourTable, bool)> {
    if rebuild {
        let table = BelcourTable::build(gpu, G2_FORM, size, samples, Basis::fit())?;
        return Ok((table, false));
    }
    BelcourTable::load_or_build(gpu, G2_FORM, size, samples, cache_dir)
}

/// The split-sum table the probes bind (the 4-D tables read it beyond their κ).
pub fn probe_split_table(gpu: &Gpu) -> Result<SplitSumTable> {
    SplitSumTable::load_or_build(
        gpu,
        G2_FORM,
        split_sum::DEFAULT_SIZE,
        split_sum::DEFAULT_SAMPLES,
    )
}

/// The shader's lookup (`fgd_probe.comp.glsl`) at every vertex with even μ and α indices
/// (a quarter of them), against `expected(i, j, k, l)`.
pub fn hardware_at_vertices(
    probe: &FgdProbe<'_>,
    split: &SplitSumTable,
    images: &FgdImages,
    grid: &Grid,
    expected: impl Fn(u32, u32, u32, u32) -> f64,
) -> Result<Errors> {
    let [nm, na, ne, nk] = grid.dims;
    let mut errors = Errors::default();
    for l in 0..nk {
        let mut points = Vec::new();
        let mut index = Vec::new();
        for k in 0..ne {
            for j in (0..na).step_by(2) {
                for i in (0..nm).step_by(2) {
                    let at = grid.coordinates(i, j, k, l);
                    points.push(at.map(|v| v as f32));
                    index.push((i, j, k, at));
                }
            }
        }
        let values = probe.sample(split, images, &points)?;
        for (v, (i, j, k, at)) in values.iter().zip(index) {
            errors.add(f64::from(*v) - expected(i, j, k, l), at);
        }
    }
    Ok(errors)
}

/// `fgd=4d`'s lookup (the 64×64×4096 image, two trilinear fetches) at the vertices against the
/// grid's own texels: what the stacked layout and the hardware filter lose.
pub fn full_lookup_error(gpu: &Gpu, grid: &Grid) -> Result<Errors> {
    let images = FgdImages::stacked(gpu, Fgd::Full4d, grid, Filter::Box)?;
    let probe = FgdProbe::new(gpu, Fgd::Full4d)?;
    let split = probe_split_table(gpu)?;
    hardware_at_vertices(&probe, &split, &images, grid, |i, j, k, l| {
        f64::from(grid.texel(i, j, k, l))
    })
}

/// The `fgd-resampled` study: each κ filter's resampling against the 4-D grid, one
/// [`ResampledRow`] per filter ([`ResampledStudy::row`]).
pub struct ResampledStudy<'g> {
    gpu: &'g Gpu,
    grid: &'g Grid,
    split: SplitSumTable,
    probe: FgdProbe<'g>,
    points: Vec<[f32; 4]>,
    /// `fgd=4d`'s lookup at `points`, when the device holds its 64×64×4096 image.
    full: Option<Vec<f32>>,
    /// Why the comparison of the shaders' lookups is skipped, when it is.
    pub skipped: Option<String>,
}

/// One filter's row of the `fgd-resampled` study.
pub struct ResampledRow {
    pub filter: Filter,
    /// The resampled table ([`fgd::resample`]).
    pub table: Vec<f32>,
    /// Its CPU lookup against the 4-D grid at every vertex ([`resampling_error`]).
    pub table_error: Errors,
    /// Per (κ, η) vertex, the largest error over (μ, α): `map[l][k]`.
    pub map: Vec<Vec<f64>>,
    /// The variants' lookups (`fgd=resampled4d` against `fgd=4d`) at [`PROBE_POINTS`] points;
    /// `None` when skipped.
    pub shader: Option<Errors>,
    /// The shader's fetches at the vertices against the same lookup in f64.
    pub hardware: Errors,
}

impl<'g> ResampledStudy<'g> {
    pub fn new(gpu: &'g Gpu, grid: &'g Grid) -> Result<Self> {
        let split = probe_split_table(gpu)?;
        let points = probe_points(PROBE_POINTS, fgd::ETA_MAX, fgd::KAPPA_MAX);
        let (full, skipped) = match FgdImages::stacked(gpu, Fgd::Full4d, grid, Filter::Box) {
            Ok(images) => (
                Some(FgdProbe::new(gpu, Fgd::Full4d)?.sample(&split, &images, &points)?),
                None,
            ),
            Err(e) => (None, Some(e.to_string())),
        };
        Ok(Self {
            gpu,
            grid,
            probe: FgdProbe::new(gpu, Fgd::Resampled4d)?,
            split,
            points,
            full,
            skipped,
        })
    }

    pub fn row(&self, filter: Filter) -> Result<ResampledRow> {
        let grid = self.grid;
        let table = fgd::resample(grid, filter);
        let (table_error, map) = resampling_error(grid, &table);
        let images = FgdImages::stacked(self.gpu, Fgd::Resampled4d, grid, filter)?;
        let shader = match &self.full {
            Some(full) => {
                let values = self.probe.sample(&self.split, &images, &self.points)?;
                let mut e = Errors::default();
                for ((p, r), f) in self.points.iter().zip(&values).zip(full) {
                    e.add(f64::from(r - f), p.map(f64::from));
                }
                Some(e)
            }
            None => None,
        };
        let hardware =
            hardware_at_vertices(&self.probe, &self.split, &images, grid, |i, j, k, l| {
                resampled_at(grid, &table, i, j, k, grid.coordinates(i, j, k, l)[3])
            })?;
        Ok(ResampledRow {
            filter,
            table,
            table_error,
            map,
            shader,
            hardware,
        })
    }
}

/// The `fgd-belcour` accuracy study: every `fgd` value against the exact FGD over the
/// [`interfaces`] at [`MU`] × [`ALPHA`], by [`Class`].
pub struct Accuracy {
    /// One per column: `belcour, basis only`, then each `fgd` value through its shader.
    pub columns: Vec<String>,
    pub rows: Vec<AccuracyRow>,
}

/// One class of interfaces: how many, and each column's errors over them.
pub struct AccuracyRow {
    pub class: Class,
    pub interfaces: usize,
    pub errors: Vec<Errors>,
}

/// Runs the accuracy study of [`Accuracy`] with `table` (the basis-only column) and every
/// `fgd` value's own lookup.
pub fn belcour_accuracy(
    gpu: &Gpu,
    table: &BelcourTable,
    split: &SplitSumTable,
) -> Result<Accuracy> {
    let points = exact_points(G2_FORM, EXACT_RESOLUTION);
    let probe_input: Vec<[f32; 4]> = points.iter().map(|p| p.0.map(|v| v as f32)).collect();
    let mut columns: Vec<(String, Vec<f64>)> = vec![(
        "belcour, basis only".into(),
        points
            .iter()
            .map(|p| belcour_unguarded(table, p.0))
            .collect(),
    )];
    for mode in [Fgd::Karis, Fgd::Belcour, Fgd::Full4d, Fgd::Resampled4d] {
        let images = FgdImages::for_variant(gpu, mode, G2_FORM)?;
        let values = FgdProbe::new(gpu, mode)?.sample(split, &images, &probe_input)?;
        let label = if mode == Fgd::Belcour {
            "belcour (fgd=belcour)".to_string()
        } else {
            format!("fgd={mode}")
        };
        columns.push((label, values.into_iter().map(f64::from).collect()));
    }
    let rows = Class::ALL
        .into_iter()
        .map(|class| AccuracyRow {
            class,
            interfaces: interfaces().iter().filter(|i| i.class == class).count(),
            errors: columns
                .iter()
                .map(|(_, values)| {
                    let mut e = Errors::default();
                    for (p, v) in points.iter().zip(values) {
                        if p.1 == class {
                            e.add(v - p.2, p.0);
                        }
                    }
                    e
                })
                .collect(),
        })
        .collect();
    Ok(Accuracy {
        columns: columns.into_iter().map(|(label, _)| label).collect(),
        rows,
    })
}

/// The Belcour error map's roughness.
pub const MAP_ALPHA: f64 = 0.3;
/// The Belcour error map's η range (dielectrics on both sides of 1).
pub const MAP_ETA: (f64, f64) = (0.5, 2.5);
/// Cells per axis of the Belcour error map.
const MAP_CELLS: u32 = 48;

/// |FGD − exact| over (μ, η) at α = [`MAP_ALPHA`] for dielectrics η ∈ [`MAP_ETA`]: the basis
/// alone, and `fgd=belcour` as the shader samples it (the η < 1 table below 1), as (label,
/// rows) panels; `progress(done, total)` follows the exact FGD's cells.
pub fn belcour_error_panels(
    gpu: &Gpu,
    table: &BelcourTable,
    split: &SplitSumTable,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<(String, Vec<Vec<f64>>)>> {
    let n = MAP_CELLS;
    let exact = ExactFgd {
        g2: G2_FORM,
        resolution: 128,
    };
    let (eta_lo, eta_hi) = MAP_ETA;
    let cells: Vec<[f64; 4]> = (0..n)
        .flat_map(|y| {
            let eta = eta_lo + (eta_hi - eta_lo) * (f64::from(y) + 0.5) / f64::from(n);
            (0..n).map(move |x| [(f64::from(x) + 0.5) / f64::from(n), MAP_ALPHA, eta, 0.0])
        })
        .collect();
    let truth: Vec<f64> = cells
        .iter()
        .enumerate()
        .map(|(done, &[mu, alpha, eta, kappa])| {
            progress(done + 1, cells.len());
            exact.fgd(mu, alpha, eta, kappa)
        })
        .collect();
    let images = FgdImages::for_variant(gpu, Fgd::Belcour, G2_FORM)?;
    let input: Vec<[f32; 4]> = cells.iter().map(|c| c.map(|v| v as f32)).collect();
    let shipped = FgdProbe::new(gpu, Fgd::Belcour)?.sample(split, &images, &input)?;
    let rows = |value: &dyn Fn(usize) -> f64| -> Vec<Vec<f64>> {
        (0..n as usize)
            .map(|y| {
                (0..n as usize)
                    .map(|x| {
                        let i = y * n as usize + x;
                        (value(i) - truth[i]).abs()
                    })
                    .collect()
            })
            .collect()
    };
    Ok(vec![
        (
            "basis only".into(),
            rows(&|i| belcour_unguarded(table, cells[i])),
        ),
        (
            "fgd=belcour (η < 1: table)".into(),
            rows(&|i| f64::from(shipped[i])),
        ),
    ])
}

/// A 4-D grid's texels (`slices` κ slices of them) in the reference's file format
/// (ALGORITHMS.md §6): int32 sizes, (f32 min, f32 max) per axis, then the f32 values, first
/// axis fastest.
pub fn grid_file_bytes(grid: &Grid, texels: &[f32], slices: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity(48 + texels.len() * 4);
    let [nm, na, ne, _] = grid.dims;
    for n in [nm, na, ne, slices] {
        out.extend((n as i32).to_le_bytes());
    }
    for (lo, hi) in [(0.0, 1.0), (0.0, 1.0), grid.eta, grid.kappa] {
        out.extend((lo as f32).to_le_bytes());
        out.extend((hi as f32).to_le_bytes());
    }
    for v in texels {
        out.extend(v.to_le_bytes());
    }
    out
}
