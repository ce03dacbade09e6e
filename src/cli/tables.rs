//! `lamina tables tir | fgd-karis | fgd-4d | fgd-resampled | fgd-belcour`: builds a table (or
//! loads it from the cache), prints its statistics and error studies (`lamina::tables::spot`,
//! `tir_study`, `fgd_study`), writes the reference file format and the error maps.
//! `lamina tables tir-fit` fits `tir=fit`'s coefficients (`lamina::tables::tir_fit`, CPU only)
//! and writes them as Rust source.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use lamina::cache;
use lamina::chart::HeatMap;
use lamina::imageio;
use lamina::model::tir::{AnalyticTir, FitTir};
use lamina::model::tir_fit::COEFFICIENTS;
use lamina::stats::MinMeanMax;
use lamina::tables::fgd::{self, Filter, Grid, GridKind};
use lamina::tables::fgd_study::{self, ResampledStudy, EXACT_RESOLUTION, G2_FORM, PROBE_POINTS};
use lamina::tables::split_sum::{self, SplitSumTable};
use lamina::tables::tir_fit::{self, TirFit};
use lamina::tables::tir_study::{self, TirStudy};
use lamina::tables::{spot, tir};
use lamina::Gpu;

use super::{check_validation, follow, progress_bar, GlobalArgs};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum TableKind {
    /// Karis's 2-channel split-sum table (the fgd=karis axis value).
    FgdKaris,
    /// Belcour, Bati & Barla 2020 4-channel table.
    FgdBelcour,
    /// The 64⁴ FGD table as a 64×64×4096 3-D image.
    #[value(name = "fgd-4d")]
    Fgd4d,
    /// The talk's 64×64×2048 resampling of the 4-D table.
    FgdResampled,
    /// The 3-D TIR table (tir=lut32 / lut16).
    Tir,
    /// Fits tir=fit's coefficients to the TIR table's f64 reference (CPU only).
    TirFit,
}

/// How `fgd=resampled4d` brings κ to half resolution ([`Filter`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum FilterArg {
    /// ½, ½: the mean of the two slices (the talk's best).
    Box,
    /// ⅛, ⅜, ⅜, ⅛: a triangle twice as wide.
    Tent,
    /// −1/16, 9/16, 9/16, −1/16: Catmull–Rom interpolation at the midpoint.
    CatmullRom,
}

impl From<FilterArg> for Filter {
    fn from(arg: FilterArg) -> Self {
        match arg {
            FilterArg::Box => Filter::Box,
            FilterArg::Tent => Filter::Tent,
            FilterArg::CatmullRom => Filter::CatmullRom,
        }
    }
}

#[derive(clap::Args)]
pub struct TablesArgs {
    #[arg(value_enum)]
    kind: TableKind,
    /// Write the table in the reference's binary format (ALGORITHMS.md §6); tir-fit: the
    /// coefficients as Rust source (src/model/tir_fit.rs).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Write a heat map of the table's comparison (tir: |analytic − table|) as PNG.
    #[arg(long, value_name = "FILE.png")]
    error_map: Option<PathBuf>,
    /// tir: write a heat map of |tir=fit − table| as PNG.
    #[arg(long, value_name = "FILE.png")]
    fit_error_map: Option<PathBuf>,
    /// Texels per axis.
    #[arg(long, default_value_t = 64, value_name = "N")]
    size: u32,
    /// Samples per texel (default: the size the renderer uses).
    #[arg(long, value_name = "N")]
    samples: Option<u32>,
    /// Build even when a valid cached table exists.
    #[arg(long)]
    rebuild: bool,
    /// fgd-resampled: the κ filter of the table --out writes (every filter is measured).
    #[arg(long, value_enum, default_value = "box")]
    filter: FilterArg,
}

pub fn run(global: &GlobalArgs, args: &TablesArgs) -> Result<()> {
    check(args)?;
    let on_gpu = |table: fn(&Gpu, &TablesArgs) -> Result<()>| {
        let gpu = global.open_gpu()?;
        table(&gpu, args)?;
        check_validation(&gpu)
    };
    match args.kind {
        TableKind::TirFit => tir_fit(args),
        TableKind::Tir => on_gpu(tir),
        TableKind::FgdKaris => on_gpu(karis),
        TableKind::Fgd4d => on_gpu(full_4d),
        TableKind::FgdResampled => on_gpu(resampled),
        TableKind::FgdBelcour => on_gpu(belcour),
    }
}

/// The flags each table takes, before any GPU work.
fn check(args: &TablesArgs) -> Result<()> {
    if !(2..=256).contains(&args.size) {
        anyhow::bail!("--size {}: allowed 2..=256 texels per axis", args.size);
    }
    if args.samples == Some(0) {
        anyhow::bail!("--samples 0: allowed 1 or more samples per texel");
    }
    if args.fit_error_map.is_some() && args.kind != TableKind::Tir {
        anyhow::bail!("--fit-error-map applies to the tir table only");
    }
    match args.kind {
        TableKind::Tir if args.size < 3 => anyhow::bail!(
            "tir: --size {}: the study needs an η slice inside (0, 1), at least 3 texels per axis",
            args.size
        ),
        TableKind::TirFit
            if args.error_map.is_some()
                || args.samples.is_some()
                || args.rebuild
                || args.size != tir::DEFAULT_SIZE =>
        {
            anyhow::bail!(
                "tir-fit: the fit's data are fixed (src/tables/tir_fit.rs); it takes --out only \
                 (--size, --samples, --rebuild and --error-map apply to the tables)"
            )
        }
        TableKind::FgdKaris if args.out.is_some() || args.error_map.is_some() => {
            anyhow::bail!("fgd-karis: --out and --error-map apply to the tir table only")
        }
        TableKind::Fgd4d if args.error_map.is_some() => anyhow::bail!(
            "fgd-4d: --error-map applies to the comparisons (fgd-resampled: against this table; \
             fgd-belcour: against exact FGD; tir: analytic against the table)"
        ),
        TableKind::FgdResampled if args.size != fgd::SIZE => anyhow::bail!(
            "fgd-resampled: --size {}: the shader's stacked layout is fixed at {}",
            args.size,
            fgd::SIZE
        ),
        TableKind::FgdBelcour if args.out.is_some() => {
            anyhow::bail!("fgd-belcour: --out writes the 4-D tables only (fgd-4d, fgd-resampled)")
        }
        _ => Ok(()),
    }
}

/// Runs `load` (a table's cache-or-build) behind a progress bar labelled `what`; returns the
/// table, whether it came from the cache, and the seconds it took.
fn load_table<T>(
    what: &str,
    load: impl FnOnce(&mut dyn FnMut(u32, u32)) -> lamina::Result<(T, bool)>,
) -> Result<(T, bool, f64)> {
    let bar = progress_bar(what);
    let started = Instant::now();
    let (table, cached) = load(&mut follow(&bar))?;
    bar.finish_and_clear();
    Ok((table, cached, started.elapsed().as_secs_f64()))
}

/// How a table came to be, for the first line.
fn provenance(cached: bool) -> &'static str {
    if cached {
        "loaded from the cache"
    } else {
        "built"
    }
}

/// Where the cache keeps `key`, for the first line.
fn cache_text(dir: Option<&Path>, key: &cache::Key) -> String {
    dir.map(|d| cache::path_of(d, key).display().to_string())
        .unwrap_or_else(|| "no cache directory".into())
}

fn values_line(values: MinMeanMax) -> String {
    format!(
        "values: min {:.4}, mean {:.4}, max {:.4}",
        values.min, values.mean, values.max
    )
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    imageio::write_file_atomically(path, bytes)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// An axis of an error map: its label and range.
type Axis = (&'static str, (f64, f64));

/// Writes `panels` of absolute errors over (x, y) as a PNG heat map.
fn write_error_map(
    path: &Path,
    title: String,
    (x_label, x_range): Axis,
    (y_label, y_range): Axis,
    panels: Vec<(String, Vec<Vec<f64>>)>,
) -> Result<()> {
    HeatMap {
        title,
        x_label: x_label.into(),
        y_label: y_label.into(),
        x_range,
        y_range,
        panels,
        value_label: "absolute error".into(),
    }
    .write_png(path)?;
    println!("wrote {}", path.display());
    Ok(())
}

fn tir(gpu: &Gpu, args: &TablesArgs) -> Result<()> {
    let samples = args.samples.unwrap_or(tir::DEFAULT_SAMPLES);
    let dir = cache::tables_dir();
    let (table, cached, seconds) = load_table("tir table (η slices)", |progress| {
        tir_study::load(
            gpu,
            args.size,
            samples,
            dir.as_deref(),
            args.rebuild,
            progress,
        )
    })?;
    println!(
        "tir: {0}x{0}x{0} (μ, α, η), {samples} samples per texel, {1} ({2:.2} s) on {3}; cache: {4}",
        args.size,
        provenance(cached),
        seconds,
        gpu.device.report.name,
        cache_text(dir.as_deref(), &tir::cache_key(args.size, samples))
    );
    let study = TirStudy::of(&table);
    println!("{}", values_line(study.values));
    println!(
        "spot check against the f64 reference ({}² midpoint rule) at 16 texels: max |Δ| = {:.2e}",
        spot::REFERENCE_RESOLUTION,
        study.spot_max_abs
    );
    println!(
        "lut16 against lut32: max |Δ| = {:.2e} (half-float rounding of values ≤ 1: ≤ 2.44e-4)",
        study.lut16_gap
    );
    println!(
        "analytic estimator against the table ({}); the talk: MSE 0.0764, max 0.5",
        error_text(&study.analytic)
    );
    println!("tir=fit against the table ({})", error_text(&study.fit));
    if let Some(path) = &args.out {
        write_file(path, &tir::reference_file_bytes(&table))?;
    }
    let maps = [
        (
            &args.error_map,
            "analytic estimator",
            &AnalyticTir as &dyn lamina::model::Tir,
        ),
        (&args.fit_error_map, "tir=fit", &FitTir(COEFFICIENTS)),
    ];
    for (path, name, estimate) in maps {
        if let Some(path) = path {
            write_error_map(
                path,
                format!("TIR: |{name} − table|"),
                ("μ (cos θ)", (0.0, 1.0)),
                ("α", (0.0, 1.0)),
                tir_study::error_panels(&table, estimate),
            )?;
        }
    }
    Ok(())
}

/// An estimator's errors over a TIR grid, for one line.
fn error_text(e: &tir::ErrorStats) -> String {
    format!(
        "{} grid points, 0 < η < 1: MSE {:.5}, mean |Δ| {:.4}, max |Δ| {:.3} at (μ, α, η) = \
         ({:.3}, {:.3}, {:.3})",
        e.points, e.mse, e.mean_abs, e.max_abs, e.worst_at.0, e.worst_at.1, e.worst_at.2
    )
}

fn tir_fit(args: &TablesArgs) -> Result<()> {
    let started = Instant::now();
    let TirFit {
        coefficients,
        iterations,
        error,
    } = tir_fit::fit()?;
    println!(
        "tir-fit: {} coefficients fitted to the f64 trapped fraction ({}² midpoint rule) at {} \
         vertices of the {}³ table's grid (one in {} along each axis, 0 < η < 1), in \
         {iterations} Levenberg–Marquardt iterations ({:.2} s)",
        coefficients.len(),
        tir_fit::REFERENCE_RESOLUTION,
        error.points,
        tir::DEFAULT_SIZE,
        tir_fit::GRID_STEP,
        started.elapsed().as_secs_f64()
    );
    let listed: Vec<String> = coefficients.iter().map(|c| format!("{c:.6}")).collect();
    println!("coefficients c0 … c6: {}", listed.join(", "));
    println!("against the reference ({})", error_text(&error));
    let difference = tir_fit::largest_difference(&coefficients, &COEFFICIENTS);
    if difference == 0.0 {
        println!(
            "the built-in coefficients ({}) are these",
            tir_fit::SOURCE_PATH
        );
    } else {
        println!(
            "the built-in coefficients ({}) differ (relative {difference:.2e}): write them with \
             --out {} and rebuild",
            tir_fit::SOURCE_PATH,
            tir_fit::SOURCE_PATH
        );
    }
    if let Some(path) = &args.out {
        write_file(path, tir_fit::source_text(&coefficients).as_bytes())?;
    }
    Ok(())
}

fn karis(gpu: &Gpu, args: &TablesArgs) -> Result<()> {
    let samples = args.samples.unwrap_or(split_sum::DEFAULT_SAMPLES);
    let started = Instant::now();
    let table = SplitSumTable::build(gpu, G2_FORM, args.size, samples)?;
    println!(
        "fgd-karis: {0}x{0} (A, B), {samples} samples per texel, built in {1:.2} s on {2}",
        args.size,
        started.elapsed().as_secs_f64(),
        gpu.device.report.name
    );
    println!(
        "spot check against the f64 reference at 16 texels: max |Δ| = {:.2e}",
        spot::split_sum(&table, G2_FORM)
    );
    Ok(())
}

/// Loads (or builds) a 4-D grid and prints its first two lines.
fn load_grid(gpu: &Gpu, kind: GridKind, args: &TablesArgs) -> Result<Grid> {
    let samples = args.samples.unwrap_or(fgd::GRID_SAMPLES);
    let dir = cache::tables_dir();
    let what = match kind {
        GridKind::Full4d => "fgd 4-D table (κ slices)",
        GridKind::DielectricBelow1 => "fgd η<1 table",
    };
    let (grid, cached, seconds) = load_table(what, |progress| {
        fgd_study::load_grid(
            gpu,
            kind,
            args.size,
            samples,
            dir.as_deref(),
            args.rebuild,
            progress,
        )
    })?;
    let [a, b, c, d] = grid.dims;
    println!(
        "{}: {a}x{b}x{c}x{d} (μ, α, η ∈ [{}, {}], κ ∈ [{}, {}]), {samples} samples per texel, \
         G2 {G2_FORM}, {} ({:.2} s) on {}; cache: {}",
        kind.name(),
        grid.eta.0,
        grid.eta.1,
        grid.kappa.0,
        grid.kappa.1,
        provenance(cached),
        seconds,
        gpu.device.report.name,
        cache_text(
            dir.as_deref(),
            &fgd::grid_cache_key(kind, G2_FORM, args.size, samples)
        )
    );
    let values = MinMeanMax::of(grid.texels.iter().map(|&v| f64::from(v)));
    println!("{}", values_line(values.expect("a grid has texels")));
    Ok(grid)
}

/// The reference file of a 4-D grid's `texels` (`slices` κ slices).
fn write_grid(path: &Path, grid: &Grid, texels: &[f32], slices: u32) -> Result<()> {
    write_file(path, &fgd_study::grid_file_bytes(grid, texels, slices))
}

fn full_4d(gpu: &Gpu, args: &TablesArgs) -> Result<()> {
    let grid = load_grid(gpu, GridKind::Full4d, args)?;
    let spot = spot::grid(&grid, G2_FORM);
    println!(
        "spot check against the f64 quadrature ({EXACT_RESOLUTION}² points) at 16 vertices: \
         max |Δ| = {:.2e} at (μ, α, η, κ) = {:.3?}",
        spot.max_abs, spot.worst_at
    );
    if args.size == fgd::SIZE {
        let err = fgd_study::full_lookup_error(gpu, &grid)?;
        println!(
            "the shader's lookup (64×64×4096 image, two trilinear fetches) at {} vertices: \
             max |Δ| {:.2e} from the texels, at (μ, α, η, κ) = {:.3?}",
            err.points, err.max_abs, err.worst_at
        );
    }
    if let Some(path) = &args.out {
        write_grid(path, &grid, &grid.texels, grid.dims[3])?;
    }
    Ok(())
}

fn resampled(gpu: &Gpu, args: &TablesArgs) -> Result<()> {
    let grid = load_grid(gpu, GridKind::Full4d, args)?;
    let study = ResampledStudy::new(gpu, &grid)?;
    if let Some(why) = &study.skipped {
        println!("{why}: the hardware-path comparison is skipped");
    }
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
    for filter in Filter::ALL {
        let row = study.row(filter)?;
        let (err, w) = (row.table_error, row.table_error.worst_at);
        println!(
            "{:<12} {:>24} {:>24} {:>26} {:>22}",
            filter.name(),
            format!("{:.4} ({:.5})", err.max_abs, err.mean_abs),
            format!("({:.2}, {:.2}, {:.2}, {:.2})", w[0], w[1], w[2], w[3]),
            row.shader.map_or("-".into(), |e| format!(
                "{:.4} ({:.5})",
                e.max_abs, e.mean_abs
            )),
            format!("{:.2e}", row.hardware.max_abs)
        );
        if filter == Filter::from(args.filter) {
            if let Some(path) = &args.out {
                write_grid(path, &grid, &row.table, grid.dims[3] / 2)?;
            }
        }
        panels.push((format!("{} filter", filter.name()), row.map));
    }
    println!(
        "table: every vertex of the 4-D grid (the error resampling adds where the full table is \
         exact); shader: the variants' own lookups at {PROBE_POINTS} points; hardware vs CPU: \
         the shader's fetches at the vertices against the same lookup in f64 (stacked-slice \
         boundaries and filtering precision). The talk: up to 46 %, box filter best."
    );
    if let Some(path) = &args.error_map {
        write_error_map(
            path,
            "fgd-resampled: max over (μ, α) of |resampled − 4-D|".into(),
            ("η", (0.0, fgd::ETA_MAX)),
            ("κ", (0.0, fgd::KAPPA_MAX)),
            panels,
        )?;
    }
    Ok(())
}

fn belcour(gpu: &Gpu, args: &TablesArgs) -> Result<()> {
    let samples = args.samples.unwrap_or(fgd::BELCOUR_SAMPLES);
    let started = Instant::now();
    let (table, cached) = fgd_study::load_belcour(
        gpu,
        args.size,
        samples,
        cache::tables_dir().as_deref(),
        args.rebuild,
    )?;
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
    println!(
        "spot check of L0…L3 against the f64 reference at 16 texels: max |Δ| = {:.2e}",
        spot::belcour(&table, G2_FORM)
    );

    let split = fgd_study::probe_split_table(gpu)?;
    let accuracy = fgd_study::belcour_accuracy(gpu, &table, &split)?;
    print_accuracy(&accuracy);
    if let Some(path) = &args.error_map {
        let bar = progress_bar("belcour error map (cells)");
        let panels = fgd_study::belcour_error_panels(gpu, &table, &split, |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })?;
        bar.finish_and_clear();
        write_error_map(
            path,
            format!(
                "fgd-belcour: |FGD − exact|, dielectrics, α = {}",
                fgd_study::MAP_ALPHA
            ),
            ("μ (cos θ)", (0.0, 1.0)),
            ("η", fgd_study::MAP_ETA),
            panels,
        )?;
    }
    Ok(())
}

/// The accuracy study's table: one row per class of interfaces, one column per `fgd` value.
fn print_accuracy(accuracy: &fgd_study::Accuracy) {
    println!(
        "\nmax |FGD − exact| (mean) over μ ∈ {:?} × α ∈ {:?}, exact = f64 quadrature ({EXACT_RESOLUTION}²):",
        fgd_study::MU,
        fgd_study::ALPHA
    );
    print!("{:<20}", "interfaces");
    for label in &accuracy.columns {
        print!(" {label:>22}");
    }
    println!();
    for row in &accuracy.rows {
        print!(
            "{:<20}",
            format!("{} ({})", row.class.label(), row.interfaces)
        );
        for e in &row.errors {
            print!(" {:>22}", format!("{:.4} ({:.4})", e.max_abs, e.mean_abs));
        }
        println!();
    }
    println!(
        "fgd=belcour reads a 64³ dielectric table for η < 1 (the basis has no total internal \
         reflection); beyond κ = 4 the 4-D tables go on from their edge along the split sum's \
         slope in F0."
    );
}
