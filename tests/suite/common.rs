//! Shared by the integration tests: a validated device on lavapipe (or whatever is present) and
//! the rule that any validation message fails the test.
#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use lamina::imageio::{self, HdrImage};
use lamina::model::LayerParams;
use lamina::vk::{DeviceSelector, InstanceDesc};
use lamina::Gpu;

/// How far apart two counts of one draw may be, relatively: the JIT instructions of the same
/// shaded draw, counted twice in one worker, have differed by up to 3 of 2.1–15 M (about
/// 1.5e-6) — while other tests loaded both cores — so counts repeat to ~1e-5 (DESIGN.md §7),
/// not to the instruction.
pub const COUNT_REPEATABILITY: f64 = 1e-5;

/// Whether counts `a` and `b` of one draw agree within [`COUNT_REPEATABILITY`].
pub fn same_count(a: u64, b: u64) -> bool {
    (a as f64 - b as f64).abs() <= COUNT_REPEATABILITY * a.max(b) as f64
}

/// A device with the Khronos validation layer on.
pub fn gpu() -> Gpu {
    Gpu::validated().expect("a Vulkan device with the validation layer (run scripts/setup.sh)")
}

/// [`gpu`] with its pipeline cache's file in `dir` (the tests' default keeps it in memory).
pub fn gpu_with_pipeline_cache(dir: &Path) -> Gpu {
    Gpu::with_pipeline_cache(InstanceDesc::validated(), &DeviceSelector::Best, Some(dir))
        .expect("a Vulkan device with the validation layer (run scripts/setup.sh)")
}

/// Fails when the validation layer said anything of warning or error severity.
pub fn assert_validation_clean(gpu: &Gpu) {
    let messages = gpu.device.instance().messages();
    assert_eq!(
        messages.problems(),
        0,
        "validation layer messages: {:?}",
        messages.first_errors()
    );
}

pub fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub fn studio() -> HdrImage {
    imageio::read_exr(&repo_path("assets/env/studio.exr")).expect("bundled environment map")
}

/// A fresh, empty directory under the target directory for one test's files.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

/// A single rough gold layer (ALGORITHMS.md §12.2 n, k): the baseline's default material.
pub fn gold() -> Vec<LayerParams> {
    vec![LayerParams::gold(0.2)]
}

/// `lamina ARGS` in `dir`, with a private runtime directory.
pub fn lamina_command(args: &[&str], dir: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lamina"));
    command
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir());
    command
}

/// Runs `lamina ARGS` in `dir` to its end.
pub fn lamina(args: &[&str], dir: &Path) -> Output {
    lamina_command(args, dir).output().expect("run lamina")
}

/// A process's output as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Checks a results.json against its schema (issue #5's fields, every run's fields, each run's
/// times ordered, `frames` measured frames, baselines at ratio 1) and returns its runs.
pub fn check_results(json: &serde_json::Value, frames: u64) -> Vec<serde_json::Value> {
    for key in [
        "device",
        "git_rev",
        "command",
        "size",
        "lp_num_threads",
        "runs",
    ] {
        assert!(json.get(key).is_some(), "missing `{key}`");
    }
    for key in ["name", "driver", "api_version", "vendor_id"] {
        assert!(json["device"].get(key).is_some(), "missing device `{key}`");
    }
    let runs = json["runs"].as_array().expect("runs").clone();
    for run in &runs {
        for key in [
            "variant",
            "material",
            "frames",
            "min_ms",
            "median_ms",
            "mean_ms",
            "max_ms",
            "stdev_ms",
            "ratio_to_baseline",
            "fragment_invocations",
            "pipeline_ms",
            "spirv_bytes",
            "instructions",
            "executable_stats",
        ] {
            assert!(run.get(key).is_some(), "run lacks `{key}`: {run}");
        }
        let ms = |k: &str| run[k].as_f64().unwrap();
        assert!(ms("min_ms") <= ms("median_ms") && ms("median_ms") <= ms("max_ms"));
        assert!(ms("min_ms") <= ms("mean_ms") && ms("mean_ms") <= ms("max_ms"));
        assert!(ms("stdev_ms") >= 0.0);
        assert_eq!(run["frames"], frames);
        if run["variant"].as_str().unwrap().starts_with("model=ggx") {
            assert_eq!(run["ratio_to_baseline"].as_f64().unwrap(), 1.0);
        }
    }
    runs
}

/// Checks that results.csv has one row per run of `runs`, in order, with its variant and
/// median time.
pub fn check_csv(csv: &str, runs: &[serde_json::Value]) {
    // Variant keys hold commas: find the median's column counting from the end.
    let header: Vec<&str> = csv.lines().next().expect("a header").split(',').collect();
    let from_end = header.len() - header.iter().position(|&c| c == "median_ms").unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), runs.len());
    for (row, run) in rows.iter().zip(runs) {
        assert!(row.starts_with(&format!("\"{}\"", run["variant"].as_str().unwrap())));
        let fields: Vec<&str> = row.split(',').collect();
        let median: f64 = fields[fields.len() - from_end].parse().unwrap();
        assert_eq!(median, run["median_ms"].as_f64().unwrap());
    }
}

/// The largest difference of image `b` from image `a` over pixels and RGB, relative to `a`'s
/// value, values below `floor` counting as `floor`.
pub fn largest_relative(a: &[[f32; 4]], b: &[[f32; 4]], floor: f32) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c], q[c])))
        .map(|(p, q)| f64::from((p - q).abs()) / f64::from(p.abs().max(floor)))
        .fold(0.0, f64::max)
}

/// The mean over pixels and RGB of an image.
pub fn mean_radiance(image: &[[f32; 4]]) -> f32 {
    image.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / (3 * image.len()) as f32
}
