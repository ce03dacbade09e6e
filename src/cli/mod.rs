//! The command line's layer over the library (DESIGN.md §3): the commands and their flags,
//! argument checks, and printing — nothing else. Every rule a command applies lives in the
//! library, where the sweep, the viewer and the tests reach it too.
//!
//! One file per command, each with its `…Args` and a `run`; [`args`] holds the argument types
//! several commands share; this file holds the global flags, the dispatch and the helpers every
//! command uses (opening the device, the validation check, progress bars, asset paths).

mod args;
mod bake_error;
mod bench;
mod count_worker;
mod devices;
mod diff;
mod eval;
mod export;
mod furnace;
mod merge;
mod reference;
mod render;
mod report;
mod sheet;
mod simplify;
mod sweep;
mod table_worker;
mod tables;
mod view;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Result;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use lamina::vk::{Capturer, DeviceSelector, InstanceDesc};
use lamina::Gpu;

#[derive(Parser)]
#[command(
    name = "lamina",
    version,
    about = "Transfer-matrix layered materials on Vulkan, measured"
)]
pub struct Cli {
    #[command(flatten)]
    global: GlobalArgs,
    #[command(subcommand)]
    command: Command,
}

/// The flags every command takes.
#[derive(clap::Args)]
struct GlobalArgs {
    /// Vulkan device: index (see `lamina devices`) or part of its name.
    #[arg(long, global = true, value_name = "INDEX|NAME")]
    device: Option<DeviceSelector>,
    /// Enable the Khronos validation layer.
    #[arg(long, global = true)]
    validation: bool,
    /// Enable synchronization validation too (implies --validation).
    #[arg(long, global = true)]
    sync_validation: bool,
}

#[derive(Subcommand)]
enum Command {
    /// List Vulkan devices and the features lamina uses; --calibrate times compute against
    /// fragment shading on the selected one.
    Devices(devices::DevicesArgs),
    /// Render the sphere under an environment to EXR and PNG, and print the GPU time.
    Render(render::RenderArgs),
    /// Evaluate a material's model at view cosines: total R, T and the lobes.
    Eval(eval::EvalArgs),
    /// Stochastic reference of a material: light paths through the stack, total R and T with
    /// standard errors, the BRDF in the plane of incidence and over the hemisphere.
    Reference(reference::ReferenceArgs),
    /// White-furnace test: reflected energy per view angle under a uniform white environment.
    Furnace(furnace::FurnaceArgs),
    /// What static simplification removes from a material (index-matched layers, empty media,
    /// layers no light reaches), and why; optionally the simplified material file.
    Simplify(simplify::SimplifyArgs),
    /// The forward pass of one variant and material as SPIR-V with its specialization
    /// constants frozen (spirv-opt, validated by spirv-val), and spec.json with their values:
    /// for offline compilers and shader analysers.
    Export(export::ExportArgs),
    /// Render every preset material in each variant into one tiled PNG.
    Sheet(sheet::SheetArgs),
    /// Interactive viewer: edit the layer stack, switch variants, watch the GPU time.
    View(view::ViewArgs),
    /// How far a baked material (mode=baked) is from the per-pixel model, per table size.
    BakeError(bake_error::BakeErrorArgs),
    /// Time variants of the shaded draw, interleaved, against the ggx baseline.
    Bench(bench::BenchArgs),
    /// Run a sweep file (profiling/sweeps/*.toml): results.json, results.csv and charts per study.
    Sweep(sweep::SweepArgs),
    /// Write profiling/REPORT.md from sweep results, beside the talk's published figures.
    Report(report::ReportArgs),
    /// Join the shards of a sweep (`sweep --shard K/N`, run on many machines) into one results
    /// directory and its report.
    Merge(merge::MergeArgs),
    /// Compare two sets of results (commits, drivers, devices): time as each run's ratio to its
    /// ggx baseline, JIT instruction counts as they are.
    Diff(diff::DiffArgs),
    /// Build a precomputed table (or load it from the cache), print its statistics and error
    /// studies.
    Tables(tables::TablesArgs),
    /// Internal: counts instructions of shaded draws; runs under callgrind, started by
    /// `--counter instructions`.
    #[command(hide = true)]
    CountWorker(count_worker::CountWorkerArgs),
    /// Builds the tables and the SPIR-V of some variants into the disk caches on every core;
    /// started by `sweep` on lavapipe pinned to one thread, and by the instruction counter.
    #[command(hide = true)]
    TableWorker(table_worker::TableWorkerArgs),
}

/// Runs the command the line names.
pub fn run(cli: &Cli) -> Result<()> {
    let global = &cli.global;
    match &cli.command {
        Command::Devices(args) => devices::run(global, args),
        Command::Render(args) => render::run(global, args),
        Command::Eval(args) => eval::run(global, args),
        Command::Reference(args) => reference::run(args),
        Command::Furnace(args) => furnace::run(global, args),
        Command::BakeError(args) => bake_error::run(global, args),
        Command::Simplify(args) => simplify::run(args),
        Command::Export(args) => export::run(args),
        Command::Sheet(args) => sheet::run(global, args),
        Command::View(args) => view::run(global, args),
        Command::Bench(args) => bench::run(global, args),
        Command::Sweep(args) => sweep::run(global, args),
        Command::Report(args) => report::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Diff(args) => diff::run(args),
        Command::Tables(args) => tables::run(global, args),
        Command::CountWorker(args) => count_worker::run(global, args),
        Command::TableWorker(args) => table_worker::run(global, args),
    }
}

impl GlobalArgs {
    /// The instance the flags ask for; `surface` for a window.
    fn instance(&self, surface: bool) -> InstanceDesc {
        InstanceDesc {
            validation: self.validation,
            sync_validation: self.sync_validation,
            surface,
        }
    }

    fn selector(&self) -> DeviceSelector {
        self.device.clone().unwrap_or_default()
    }

    /// The device the flags select, headless.
    fn open_gpu(&self) -> Result<Gpu> {
        Ok(Gpu::new(self.instance(false), &self.selector())?)
    }
}

/// Set by Ctrl-C once [`stop_on_interrupt`] ran: a long run stops at its next step and writes
/// nothing.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_interrupt(_: libc::c_int) {
    INTERRUPTED.store(true, Ordering::Relaxed);
    // SAFETY: signal() is async-signal-safe; a second Ctrl-C then ends the process at once.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

/// Routes Ctrl-C to the flag it returns, which a long run polls.
fn stop_on_interrupt() -> &'static AtomicBool {
    // SAFETY: `on_interrupt` only stores an atomic and calls signal(), both async-signal-safe;
    // the handler is a valid `extern "C" fn(c_int)` for the process's lifetime.
    unsafe {
        libc::signal(
            libc::SIGINT,
            on_interrupt as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
    }
    &INTERRUPTED
}

/// Fails when the validation layer reported anything over the run.
fn check_validation(gpu: &Gpu) -> Result<()> {
    let problems = gpu.device.validation_problems();
    if problems > 0 {
        anyhow::bail!(
            "the validation layer reported {problems} problem(s); see the messages above"
        );
    }
    Ok(())
}

/// Prints `compiled <name> in 12.3 ms (cache hit|miss|unknown)` on stderr for every pipeline
/// `gpu` builds from now on, above `bar` when it is drawn.
fn print_pipelines(gpu: &mut Gpu, bar: Option<&ProgressBar>) {
    let bar = bar.cloned();
    gpu.on_pipeline_built(move |name, creation| {
        let line = format!(
            "compiled {name} in {:.1} ms (cache {})",
            creation.duration.as_secs_f64() * 1e3,
            creation.cache_outcome()
        );
        match &bar {
            Some(bar) => bar.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    });
}

/// Saves the pipeline cache for the next run; a failure only costs compiles then, so it is a
/// warning.
fn save_pipelines(gpu: &Gpu) {
    if let Err(e) = gpu.pipeline_cache().save() {
        eprintln!("warning: the pipeline cache was not saved (the next run compiles again): {e}");
    }
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
fn progress_bar(what: &str) -> ProgressBar {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{prefix:>28} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    bar.set_prefix(what.to_owned());
    bar
}

/// `progress(done, total)` for the library's long runs, drawn on `bar`.
fn follow(bar: &ProgressBar) -> impl FnMut(u32, u32) + '_ {
    |done, total| {
        bar.set_length(u64::from(total));
        bar.set_position(u64::from(done));
    }
}

/// A relative asset path that does not exist under the working directory is looked up in the
/// source tree the binary was built from, so `lamina render` works from any directory.
fn asset_path(path: &Path) -> PathBuf {
    if path.is_relative() && !path.exists() {
        let in_tree = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
        if in_tree.exists() {
            return in_tree;
        }
    }
    path.to_owned()
}

/// RenderDoc, loaded when `--capture FILE.rdc` asks for a capture: before the device is
/// opened, or its layer would not see the device.
fn load_capturer(file: Option<&Path>) -> Result<Option<Capturer>> {
    let Some(file) = file else {
        return Ok(None);
    };
    require_extension("--capture", file, "rdc", "RenderDoc's format")?;
    Ok(Some(Capturer::load()?))
}

/// Errs unless `file` (given to `flag`) ends in `.ext`: what is written there is `format`,
/// whatever the name says.
fn require_extension(flag: &str, file: &Path, ext: &str, format: &str) -> Result<()> {
    if file.extension().and_then(|e| e.to_str()) != Some(ext) {
        anyhow::bail!(
            "{flag} {}: the file {flag} names ends in .{ext} ({format})",
            file.display()
        );
    }
    Ok(())
}

/// `1 study`, `2 studies`.
fn studies(n: usize) -> String {
    format!("{n} stud{}", if n == 1 { "y" } else { "ies" })
}
