//! Tables and SPIR-V built before a run that would build them slowly: on lavapipe pinned to
//! one thread, or under valgrind. `LP_NUM_THREADS=0` keeps lavapipe's timings steady, but it
//! also runs lavapipe's compute dispatches — the table builds, a cold run's largest cost after
//! the counting (the FGD study's 64⁴ grid: about 100 s) — on one core; under valgrind, the
//! instruction counter's workers would build every table and run shaderc tens of times slower
//! than natively. The tables and the SPIR-V of a run's variants are built first by
//! `lamina table-worker`, a native child process with lavapipe's default thread count (one
//! per core), into the disk caches (`crate::cache`) that the run then reads.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::render::inputs::ShadingInputs;
use crate::render::{forward, sky};
use crate::tables::environment::{CONVERT_KERNEL, PREFILTER_KERNEL};
use crate::variant::VariantKey;

/// Whether a prebuild helps: a CPU device (lavapipe) held by `LP_NUM_THREADS` to fewer
/// threads than the machine has cores, and a disk cache to build into.
pub fn worthwhile(gpu: &Gpu) -> bool {
    let cpu = gpu.device.report.device_type.eq_ignore_ascii_case("cpu");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = std::env::var("LP_NUM_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok());
    cpu && threads.is_some_and(|t| t.max(1) < cores) && crate::cache::tables_dir().is_some()
}

/// One variant per set of tables among `variants`: the FGD table, the G2 form and the TIR
/// mode decide them (`render::inputs::ShadingInputs::prepare`).
pub fn table_variants(variants: impl IntoIterator<Item = VariantKey>) -> Vec<VariantKey> {
    let mut chosen: Vec<VariantKey> = Vec::new();
    for v in variants {
        if !chosen
            .iter()
            .any(|c| (c.fgd, c.g2, c.tir) == (v.fgd, v.g2, v.tir))
        {
            chosen.push(v);
        }
    }
    chosen
}

/// Builds (or loads) the tables `variants` sample into the disk cache, and compiles into the
/// SPIR-V cache every entry point a frame of theirs runs: the forward pass in each variant,
/// the sky, the environment's kernels. What `lamina table-worker` runs.
pub fn prepare(gpu: &Gpu, variants: &[VariantKey]) -> Result<()> {
    let mut inputs = ShadingInputs::new(gpu)?;
    for entry in sky::ENTRIES
        .into_iter()
        .chain([CONVERT_KERNEL.entry, PREFILTER_KERNEL.entry])
    {
        gpu.shaders.compile(entry, &[])?;
    }
    for &variant in variants {
        inputs.prepare(variant)?;
        for entry in forward::ENTRIES {
            gpu.shaders.compile(entry, &variant.defines())?;
        }
    }
    Ok(())
}

/// Runs `exe table-worker` for `variants` with lavapipe's default thread count,
/// `global_args` (device, validation) before the subcommand; returns how long it took.
pub fn run(exe: &Path, global_args: &[String], variants: &[VariantKey]) -> Result<Duration> {
    let started = Instant::now();
    let mut command = Command::new(exe);
    command
        .args(global_args)
        .arg("table-worker")
        .env_remove("LP_NUM_THREADS");
    for v in variants {
        command.arg("--variant").arg(v.to_string());
    }
    let out = command
        .output()
        .map_err(|e| Error::Unsupported(format!("starting the table worker: {e}")))?;
    if !out.status.success() {
        return Err(Error::Unsupported(format!(
            "the table worker failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    Ok(started.elapsed())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_variant_per_set_of_tables() {
        let key = |s: &str| s.parse::<VariantKey>().unwrap();
        let chosen = table_variants([
            key("model=tm2,fgd=4d"),
            key("model=tm6,fgd=4d,max_layers=8"),
            key("model=tm2,fgd=4d,g2=earl"),
            key("model=tm2,tir=lut32"),
            key("model=ggx"),
            key("model=tm2"),
        ]);
        assert_eq!(
            chosen,
            vec![
                key("model=tm2,fgd=4d"),
                key("model=tm2,fgd=4d,g2=earl"),
                key("model=tm2,tir=lut32"),
                key("model=ggx"),
            ]
        );
    }
}
