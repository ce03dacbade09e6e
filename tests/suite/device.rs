//! Device creation, the feature report, shader compilation of every entry point, and that
//! every GPU allocation is released when its owner goes.

use crate::common;

use lamina::render::eval::GpuEvaluator;
use lamina::render::Renderer;
use lamina::shader::{entry_points, ShaderCompiler};
use lamina::tables::environment::EnvDesc;
use lamina::variant::VariantKey;

#[test]
fn device_is_created_and_reports_lamina_features() {
    let gpu = common::gpu();
    let report = &gpu.device.report;
    println!("{report:#?}");
    assert!(!report.name.is_empty());
    let (major, minor) = {
        let mut parts = report
            .api_version
            .split('.')
            .map(|p| p.parse::<u32>().unwrap());
        (parts.next().unwrap(), parts.next().unwrap())
    };
    assert!(
        (major, minor) >= (1, 3),
        "Vulkan {} < 1.3",
        report.api_version
    );
    assert!(report.dynamic_rendering && report.synchronization2 && report.host_query_reset);
    assert!(report.timestamps, "lamina measures with timestamps");
    assert!(report.timestamp_valid_bits > 0 && report.timestamp_period_ns > 0.0);
    assert!(
        report.pipeline_statistics,
        "lamina counts fragment invocations"
    );
    common::assert_validation_clean(&gpu);
}

#[test]
fn every_glsl_entry_point_compiles() {
    let compiler = ShaderCompiler::new().unwrap();
    let entries = entry_points();
    assert!(entries.contains(&"forward.frag.glsl"), "{entries:?}");
    for entry in &entries {
        let spirv = compiler
            .compile(entry, &[])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(spirv[0], 0x0723_0203, "{entry}: not SPIR-V");
    }
    // The variant-compiled entries also build with every define a variant can set.
    let fp16: VariantKey = "fp16=on".parse().unwrap();
    for entry in lamina::render::forward::ENTRIES {
        assert!(entries.contains(&entry), "{entry}");
        compiler
            .compile(entry, &fp16.defines())
            .unwrap_or_else(|e| panic!("{e}"));
    }
}

/// A render and a GPU evaluation in several variants (tables, targets, read-backs, profiler
/// pools, a TIR and an FGD table), then every owner dropped: nothing is left in the allocator
/// — the leak report the device prints at exit would be empty.
#[test]
fn no_allocation_outlives_its_owner() {
    let gpu = common::gpu();
    {
        let env = EnvDesc {
            face_size: 16,
            mip_count: 4,
            samples: 8,
        };
        let mut renderer = Renderer::new(&gpu, &common::studio(), env).unwrap();
        for key in ["model=tm2,tir=lut32", "model=tm6,fgd=belcour"] {
            let pass = renderer
                .prepare_uniform(key.parse().unwrap(), &common::gold())
                .unwrap();
            renderer.render(&pass, &common::gold(), 16, 16).unwrap();
        }
        let evaluator = GpuEvaluator::new(&gpu, "model=tm2".parse().unwrap()).unwrap();
        evaluator.evaluate(&common::gold(), &[0.5, 1.0]).unwrap();
        assert!(!gpu.device.live_allocations().is_empty());
    }
    let live = gpu.device.live_allocations();
    assert!(live.is_empty(), "still allocated: {live:?}");
    common::assert_validation_clean(&gpu);
}

/// `lamina devices --calibrate`: the same loop as a fragment draw and a compute dispatch over
/// the same pixels, both timed; the dispatch runs one invocation per pixel and the draw at
/// least one per pixel; the validation layer silent; bad sizes refused by name.
#[test]
fn the_calibration_pair_times_both_paths_over_the_same_pixels() {
    use lamina::profile::calibrate::{calibrate, CalibrationSetup};

    let gpu = common::gpu();
    let setup = CalibrationSetup {
        width: 64,
        height: 32,
        iterations: 64,
        repeats: 3,
    };
    let c = calibrate(&gpu, setup).unwrap();
    println!("{c:?}: compute/fragment {:.2}", c.compute_to_fragment());
    assert!(c.fragment_ms > 0.0 && c.compute_ms > 0.0, "{c:?}");
    assert!(c.compute_to_fragment().is_finite());
    if let (Some(f), Some(k)) = (c.fragment_invocations, c.compute_invocations) {
        assert_eq!(k, 64 * 32, "one compute invocation per pixel");
        assert!(f >= 64 * 32, "a fragment per pixel at least, {f}");
    }
    common::assert_validation_clean(&gpu);

    let dir = common::scratch_dir("calibrate");
    let out = common::lamina(
        &[
            "--validation",
            "devices",
            "--calibrate",
            "--size",
            "32x16",
            "--iterations",
            "16",
        ],
        &dir,
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("compute/fragment:") && stdout.contains("32x16 pixels"),
        "{stdout}"
    );
    let out = common::lamina(&["devices", "--calibrate", "--iterations", "0"], &dir);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--iterations"));
}
