//! `lamina tables fgd-4d | fgd-resampled | fgd-belcour`: builds (or loads) the FGD tables,
//! prints their statistics and the error studies of issue #6, writes the reference file
//! format and the error maps.

use std::path::Path;

use anyhow::Result;
use lamina::imageio;
use lamina::model::fgd::ExactFgd;
use lamina::model::Fgd as _;
use lamina::profile::chart::HeatMap;
use lamina::shader::{Fgd, G2};
use lamina::tables::cache;
use lamina::tables::fgd::{self, BelcourTable, FgdImages, FgdProbe, Filter, Grid, GridKind};
use lamina::tables::fgd_study::{self, Class, Errors};
use lamina::tables::split_sum::{self, SplitSumTable};
use lamina::Gpu;

use super::{check_validation, progress_bar, provenance, spot_points, TableKind, TablesArgs};

/// The G2 form the tables are built with here: the renderer's default.
const G2_FORM: G2 = G2::HeightCorrelated;
/// Quadrature resolution of the exact FGD in the studies (within 1.3e-3 of the converged
/// value at α = 0.1, src/model/fgd.rs).
const EXACT_RESOLUTION: u32 = 256;
/// Points of the hardware-path comparison.
const PROBE_POINTS: usize = 20_000;

pub fn run(gpu: &Gpu, args: &TablesArgs) -> Result<()> {
    let samples = args.samples.unwrap_or(match args.kind {
        TableKind::FgdBelcour => fgd::BELCOUR_SAMPLES,
        _ => fgd::GRID_SAMPLES,
    });
    match args.kind {
        TableKind::Fgd4d => full_4d(gpu, args, samples)?,
        TableKind::FgdResampled => resampled(gpu, args, samples)?,
        _ => belcour(gpu, args, samples)?,
    }
    check_validation(gpu)
}

fn load_grid(gpu: &Gpu, kind: GridKind, args: &TablesArgs, samples: u32) -> Result<Grid> {
    let dir = cache::dir();
    let bar = progress_bar(match kind {
        GridKind::Full4d => "fgd 4-D table (κ slices)",
        GridKind::DielectricBelow1 => "fgd η<1 table",
    });
    let started = std::time::Instant::now();
    let progress = |done: u32, total: u32| {
        bar.set_length(u64::from(total));
        bar.set_position(u64::from(done));
    };
    let key = fgd::grid_cache_key(kind, G2_FORM, args.size, samples);
    let (grid, cached) = if args.rebuild {
        let grid = fgd::build_grid(gpu, kind, G2_FORM, args.size, samples, progress)?;
        if let Some(d) = &dir {
            cache::store(d, &key, &grid.texels)?;
        }
        (grid, false)
    } else {
        fgd::load_or_build_grid(
            gpu,
            kind,
            G2_FORM,
            args.size,
            samples,
            dir.as_deref(),
            progress,
        )?
    };
    bar.finish_and_clear();
    let where_ = dir
        .as_deref()
        .map(|d| cache::path_of(d, &key).display().to_string())
        .unwrap_or_else(|| "no cache directory".into());
    let [a, b, c, d] = grid.dims;
    println!(
        "{}: {a}x{b}x{c}x{d} (μ, α, η ∈ [{}, {}], κ ∈ [{}, {}]), {samples} samples per texel, \
         G2 {G2_FORM}, {} ({:.2} s) on {}; cache: {where_}",
        kind.name(),
        grid.eta.0,
        grid.eta.1,
        grid.kappa.0,
        grid.kappa.1,
        provenance(cached),
        started.elapsed().as_secs_f64(),
        gpu.device.report.name
    );
    let n = grid.texels.len() as f64;
    let (min, max) = grid
        .texels
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let mean = grid.texels.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    println!("values: min {min:.4}, mean {mean:.4}, max {max:.4}");
    Ok(grid)
}

/// 16 interior vertices of a grid against the f64 quadrature.
fn spot_check(grid: &Grid) -> Errors {
    let exact = ExactFgd {
        g2: G2_FORM,
        resolution: EXACT_RESOLUTION,
    };
    let [n, _, ne, nk] = grid.dims;
    spot_points(n)
        .into_iter()
        .map(|(i, j)| {
            let i = i.max(1);
            let k = 1 + (i * 7 + j * 3) % (ne - 1);
            let l = if nk > 1 { (i * 5 + j * 11) % nk } else { 0 };
            let at = grid.coordinates(i, j, k, l);
            let [mu, alpha, eta, kappa] = at;
            (
                exact.fgd(mu, alpha, eta, kappa) - f64::from(grid.texel(i, j, k, l)),
                at,
            )
        })
        .fold(Errors::default(), |mut e, (d, at)| {
            e.add(d, at);
            e
        })
}

fn full_4d(gpu: &Gpu, args: &TablesArgs, samples: u32) -> Result<()> {
    if args.error_map.is_some() {
        anyhow::bail!(
            "fgd-4d: --error-map applies to the comparisons (fgd-resampled: against this table; \
             fgd-belcour: against exact FGD; tir: analytic against the table)"
        );
    }
    let grid = load_grid(gpu, GridKind::Full4d, args, samples)?;
    let spot = spot_check(&grid);
    println!(
        "spot check against the f64 quadrature ({EXACT_RESOLUTION}² points) at 16 vertices: \
         max |Δ| = {:.2e} at (μ, α, η, κ) = {:.3?}",
        spot.max_abs, spot.worst_at
    );
    if args.size == fgd::SIZE {
        let images = FgdImages::stacked(gpu, Fgd::Full4d, &grid, Filter::Box)?;
        let probe = FgdProbe::new(gpu, Fgd::Full4d)?;
        let err =
            hardware_at_vertices(&probe, &split_table(gpu)?, &images, &grid, |i, j, k, l| {
                f64::from(grid.texel(i, j, k, l))
            })?;
        println!(
            "the shader's lookup (64×64×4096 image, two trilinear fetches) at {} vertices: \
             max |Δ| {:.2e} from the texels, at (μ, α, η, κ) = {:.3?}",
            err.points, err.max_abs, err.worst_at
        );
    }
    if let Some(path) = &args.out {
        write_reference(path, &grid, &grid.texels, grid.dims[3])?;
    }
    Ok(())
}

fn resampled(gpu: &Gpu, args: &TablesArgs, samples: u32) -> Result<()> {
    if args.size != fgd::SIZE {
        anyhow::bail!(
            "fgd-resampled: --size {}: the shader's stacked layout is fixed at {}",
            args.size,
            fgd::SIZE
        );
    }
    let grid = load_grid(gpu, GridKind::Full4d, args, samples)?;
    let split = split_table(gpu)?;
    let points = fgd_study::probe_points(PROBE_POINTS, fgd::ETA_MAX, fgd::KAPPA_MAX);
    let full = match FgdImages::stacked(gpu, Fgd::Full4d, &grid, Filter::Box) {
        Ok(images) => Some(FgdProbe::new(gpu, Fgd::Full4d)?.sample(&split, &images, &points)?),
        Err(e) => {
            println!("{e}: the hardware-path comparison is skipped");
            None
        }
    };
    println!("resampled 64x64x2048 (κ at half resolution, stacked onto η) against the 4-D table:");
    println!(
        "{:<12} {:>24} {:>24} {:>26} {:>22}",
        "filter",
        "table: max |Δ| (mean)",
        "worst at (μ, α, η, κ)",
        "shader, 20000 pts: max (mean)",
        "hardware vs CPU lookup"
    );
    let mut panels = Vec::new();
    let probe = FgdProbe::new(gpu, Fgd::Resampled4d)?;
    for filter in Filter::ALL {
        let table = fgd::resample(&grid, filter);
        let (err, map) = fgd_study::resampling_error(&grid, &table);
        let images = FgdImages::stacked(gpu, Fgd::Resampled4d, &grid, filter)?;
        let shader = match &full {
            Some(full) => {
                let values = probe.sample(&split, &images, &points)?;
                let mut e = Errors::default();
                for ((p, r), f) in points.iter().zip(&values).zip(full) {
                    e.add(f64::from(r - f), p.map(f64::from));
                }
                format!("{:.4} ({:.5})", e.max_abs, e.mean_abs)
            }
            None => "-".into(),
        };
        let hw = hardware_at_vertices(&probe, &split, &images, &grid, |i, j, k, l| {
            fgd::resampled_at(&grid, &table, i, j, k, grid.coordinates(i, j, k, l)[3])
        })?;
        let w = err.worst_at;
        println!(
            "{:<12} {:>24} {:>24} {:>26} {:>22}",
            filter.name(),
            format!("{:.4} ({:.5})", err.max_abs, err.mean_abs),
            format!("({:.2}, {:.2}, {:.2}, {:.2})", w[0], w[1], w[2], w[3]),
            shader,
            format!("{:.2e}", hw.max_abs)
        );
        panels.push((format!("{} filter", filter.name()), map));
        if filter == args.filter {
            if let Some(path) = &args.out {
                write_reference(path, &grid, &table, grid.dims[3] / 2)?;
            }
        }
    }
    println!(
        "table: every vertex of the 4-D grid (the error resampling adds where the full table is \
         exact); shader: the variants' own lookups at {PROBE_POINTS} points; hardware vs CPU: \
         the shader's fetches at the vertices against the same lookup in f64 (stacked-slice \
         boundaries and filtering precision). The talk: up to 46 %, box filter best."
    );
    if let Some(path) = &args.error_map {
        HeatMap {
            title: "fgd-resampled: max over (μ, α) of |resampled − 4-D|".into(),
            x_label: "η".into(),
            y_label: "κ".into(),
            x_range: (0.0, fgd::ETA_MAX),
            y_range: (0.0, fgd::KAPPA_MAX),
            panels,
            value_label: "absolute error".into(),
        }
        .write_png(path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The shader's lookup (`fgd_probe.comp.glsl`) at every vertex with even μ and α indices
/// (a quarter of them), against `expected(i, j, k, l)`.
fn hardware_at_vertices(
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

/// The split-sum table the probes bind (unused by the FGD modes measured here, but bound).
fn split_table(gpu: &Gpu) -> Result<SplitSumTable> {
    Ok(SplitSumTable::load_or_build(
        gpu,
        G2_FORM,
        split_sum::DEFAULT_SIZE,
        split_sum::DEFAULT_SAMPLES,
    )?)
}

fn belcour(gpu: &Gpu, args: &TablesArgs, samples: u32) -> Result<()> {
    if args.out.is_some() {
        anyhow::bail!("fgd-belcour: --out writes the 4-D tables only (fgd-4d, fgd-resampled)");
    }
    let dir = cache::dir();
    let started = std::time::Instant::now();
    let (table, cached) = if args.rebuild {
        let t = BelcourTable::build(
            gpu,
            G2_FORM,
            args.size,
            samples,
            lamina::tables::belcour::Basis::fit(),
        )?;
        (t, false)
    } else {
        BelcourTable::load_or_build(gpu, G2_FORM, args.size, samples, dir.as_deref())?
    };
    println!(
        "fgd-belcour: {0}x{0} (L0…L3 at μ, √α), {samples} samples per texel, G2 {G2_FORM}, \
         {1} ({2:.2} s) on {3}",
        args.size,
        provenance(cached),
        started.elapsed().as_secs_f64(),
        gpu.device.report.name
    );
    let basis = &table.basis;
    println!(
        "basis (fitted, src/tables/belcour.rs): b1, b2, b3 at μ = 0.1: {:.4}, {:.4}, {:.4} \
         (paper 0.5088, 0.9770, 0.8370); at 0.5: {:.4}, {:.4}, {:.4} (paper 0.0484, 0.3374, -0.6085)",
        basis.at(1, 0.1),
        basis.at(2, 0.1),
        basis.at(3, 0.1),
        basis.at(1, 0.5),
        basis.at(2, 0.5),
        basis.at(3, 0.5)
    );
    let glass = basis.coefficients(1.5, 0.0);
    println!(
        "projection of glass 1.5: c = {:.5}, {:.5}, {:.5}, {:.5} (paper's basis: 0.04, 0.96, 0.03348, 0.01376)",
        glass[0], glass[1], glass[2], glass[3]
    );
    let mut worst = 0.0f64;
    for (i, j) in spot_points(table.size) {
        let (mu, alpha) = table.coordinates(i, j);
        let cpu = fgd::belcour_reference(basis, mu, alpha, G2_FORM, 256);
        let gpu_v = table.raw[(j * table.size + i) as usize];
        for k in 0..4 {
            worst = worst.max((f64::from(gpu_v[k]) - cpu[k]).abs());
        }
    }
    println!("spot check of L0…L3 against the f64 reference at 16 texels: max |Δ| = {worst:.2e}");

    // The accuracy study: every fgd value against exact FGD at the same points.
    let points = fgd_study::exact_points(G2_FORM, EXACT_RESOLUTION);
    let probe_input: Vec<[f32; 4]> = points.iter().map(|p| p.0.map(|v| v as f32)).collect();
    let split = split_table(gpu)?;
    let mut columns: Vec<(String, Vec<f64>)> = vec![(
        "belcour, basis only".into(),
        points
            .iter()
            .map(|p| fgd_study::belcour_unguarded(&table, p.0))
            .collect(),
    )];
    for mode in [Fgd::Karis, Fgd::Belcour, Fgd::Full4d, Fgd::Resampled4d] {
        let images = FgdImages::for_variant(gpu, mode, G2_FORM)?;
        let values = FgdProbe::new(gpu, mode)?.sample(&split, &images, &probe_input)?;
        let label = if mode == Fgd::Belcour {
            "belcour (fgd=belcour)".to_string()
        } else {
            format!("fgd={mode}")
        };
        columns.push((label, values.into_iter().map(f64::from).collect()));
    }
    println!(
        "\nmax |FGD − exact| (mean) over μ ∈ {:?} × α ∈ {:?}, exact = f64 quadrature ({EXACT_RESOLUTION}²):",
        fgd_study::MU,
        fgd_study::ALPHA
    );
    print!("{:<20}", "interfaces");
    for (label, _) in &columns {
        print!(" {label:>22}");
    }
    println!();
    for class in Class::ALL {
        let count = fgd_study::interfaces()
            .iter()
            .filter(|i| i.class == class)
            .count();
        print!("{:<20}", format!("{} ({count})", class.label()));
        for (_, values) in &columns {
            let mut e = Errors::default();
            for (p, v) in points.iter().zip(values) {
                if p.1 == class {
                    e.add(v - p.2, p.0);
                }
            }
            print!(" {:>22}", format!("{:.4} ({:.4})", e.max_abs, e.mean_abs));
        }
        println!();
    }
    println!(
        "fgd=belcour reads a 64³ dielectric table for η < 1 (the basis has no total internal \
         reflection); the 4-D tables clamp κ to [0, 4]."
    );
    if let Some(path) = &args.error_map {
        belcour_map(gpu, &table, &split, path)?;
    }
    Ok(())
}

/// |FGD − exact| over (μ, η) at α = 0.3 for dielectrics η ∈ [0.5, 2.5]: the basis alone, and
/// `fgd=belcour` as the shader samples it (the η < 1 table below 1).
fn belcour_map(gpu: &Gpu, table: &BelcourTable, split: &SplitSumTable, path: &Path) -> Result<()> {
    let n = 48u32;
    let exact = ExactFgd {
        g2: G2_FORM,
        resolution: 128,
    };
    let alpha = 0.3;
    let (eta_lo, eta_hi) = (0.5, 2.5);
    let cells: Vec<[f64; 4]> = (0..n)
        .flat_map(|y| {
            let eta = eta_lo + (eta_hi - eta_lo) * (f64::from(y) + 0.5) / f64::from(n);
            (0..n).map(move |x| [(f64::from(x) + 0.5) / f64::from(n), alpha, eta, 0.0])
        })
        .collect();
    let bar = progress_bar("belcour error map (cells)");
    bar.set_length(cells.len() as u64);
    let truth: Vec<f64> = cells
        .iter()
        .map(|&[mu, alpha, eta, kappa]| {
            bar.inc(1);
            exact.fgd(mu, alpha, eta, kappa)
        })
        .collect();
    bar.finish_and_clear();
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
    HeatMap {
        title: "fgd-belcour: |FGD − exact|, dielectrics, α = 0.3".into(),
        x_label: "μ (cos θ)".into(),
        y_label: "η".into(),
        x_range: (0.0, 1.0),
        y_range: (eta_lo, eta_hi),
        panels: vec![
            (
                "basis only".into(),
                rows(&|i| fgd_study::belcour_unguarded(table, cells[i])),
            ),
            (
                "fgd=belcour (η < 1: table)".into(),
                rows(&|i| f64::from(shipped[i])),
            ),
        ],
        value_label: "absolute error".into(),
    }
    .write_png(path)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// The reference's file format (ALGORITHMS.md §6): int32 sizes, (f32 min, f32 max) per axis,
/// then the f32 values, first axis fastest.
fn write_reference(path: &Path, grid: &Grid, texels: &[f32], slices: u32) -> Result<()> {
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
    imageio::write_file_atomically(path, &out)?;
    println!("wrote {}", path.display());
    Ok(())
}
