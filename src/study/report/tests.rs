//! The report's arithmetic, readings, tables and verdicts on small made-up studies.

use std::path::{Path, PathBuf};

use super::ratios::linear_fit;
use super::reading::reading;
use super::runs::{executable_stats_table, FLAG_BIT};
use super::sections::target_verdict;
use super::*;
use crate::profile::results::{CounterInfo, DeviceInfo, Results, Run};
use crate::render::reference::Truth;
use crate::render::scene::Scene;
use crate::study::meta::{BakeErrorRow, MaterialBakeError, PointMeta, StudyMeta};
use crate::study::{Published, Target};
use crate::variant::VariantKey;

/// Results of an llvmpipe run of `scene` with every field a test does not look at filled in;
/// tests override what they read.
fn llvmpipe_results(scene: Scene) -> Results {
    Results {
        device: DeviceInfo {
            name: "llvmpipe".into(),
            driver: "llvmpipe Mesa".into(),
            api_version: "1.3".into(),
            vendor_id: 0x10005,
            subgroup_size: None,
        },
        git_rev: "0".into(),
        command: "c".into(),
        size: [8, 8],
        lp_num_threads: Some("0".into()),
        scene,
        counter: None,
        lighting: None,
        environment: None,
        calibration: None,
        runs: Vec::new(),
    }
}

#[test]
fn a_line_is_fitted_exactly() {
    let (a, b, r2) = linear_fit(&[(1.0, 3.0), (2.0, 5.0), (4.0, 9.0)]).unwrap();
    assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
    assert!(linear_fit(&[(1.0, 2.0)]).is_none());
    let (_, _, r2) = linear_fit(&[(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)]).unwrap();
    assert!(r2 < 0.5);
}

fn run(variant: &str, ms: f64, jit: u64, total: u64) -> Run {
    Run {
        variant: variant.parse().unwrap(),
        material: "gold".into(),
        frames: 3,
        min_ms: ms,
        median_ms: ms,
        mean_ms: ms,
        max_ms: ms,
        stdev_ms: 0.0,
        ratio_to_baseline: 1.0,
        fragment_invocations: None,
        pipeline_ms: 0.0,
        pipeline_cache_hit: None,
        spirv_bytes: 0,
        instructions: Some(jit),
        instructions_total: Some(total),
        instructions_large: None,
        instructions_total_large: None,
        instructions_per_pixel: None,
        instructions_per_pixel_ratio: None,
        executable_stats: None,
        active_layers: None,
        image_error: None,
        reference_noise: None,
        reference_flip_floor: None,
        image_error_vs_fp32: None,
        lighting_error: None,
        model_error: None,
    }
}

fn published(label: &str, matches: &str, ms: f64) -> Published {
    Published {
        label: label.into(),
        matches: matches.into(),
        ms,
        source: None,
    }
}

#[test]
fn the_reading_names_agreement_rebuilds_and_fp16_emulation() {
    let key = |k: &str| k.parse::<VariantKey>().unwrap().to_string();
    let tm2 = key("model=tm2,max_layers=2");
    let study = StudyDir {
        dir: PathBuf::from("x"),
        results: Results {
            device: DeviceInfo {
                name: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
                ..llvmpipe_results(Scene::Sphere).device
            },
            runs: vec![
                run(&key("model=ggx"), 1.0, 2_000_000, 8_000_000),
                // 34 M outside the JIT code against the baseline's 6 M: rebuilt.
                run(&tm2, 4.0, 3_000_000, 37_000_000),
                run(
                    &key("model=tm2,max_layers=2,fp16=on"),
                    6.0,
                    3_600_000,
                    43_000_000,
                ),
                run(&key("model=tm6,max_layers=2"), 20.0, 15_000_000, 21_000_000),
                run(&key("model=tm2,max_layers=4"), 4.4, 6_000_000, 12_000_000),
            ],
            ..llvmpipe_results(Scene::Sphere)
        },
        meta: StudyMeta {
            name: "n".into(),
            title: "t".into(),
            description: String::new(),
            sweep_file: "s".into(),
            axes: Vec::new(),
            points: Vec::new(),
            skipped: Vec::new(),
            published: vec![
                published("2-flux", "model=tm2,max_layers=2,fp16=off", 1.0),
                published("6-flux", "model=tm6", 16.24),
                published("wide array", "model=tm2,max_layers=4", 1.05),
            ],
            fit: false,
            counter_size: None,
            counter_sizes: None,
            targets: Vec::new(),
            bake_error: Vec::new(),
            reference: Vec::new(),
            shard: None,
        },
    };
    let lines = reading(&study);
    assert_eq!(lines.len(), 4, "{lines:#?}");
    assert_eq!(
        lines[0],
        "6-flux against 2-flux: the talk 16.24×; ours by time 5.00×, 0.31× the talk's, \
         by JIT instructions 5.00×, 0.31× the talk's."
    );
    assert_eq!(
        lines[1],
        "wide array against 2-flux: the talk 1.05×; ours by time 1.10×, agrees, \
         by JIT instructions 2.00×, 1.90× the talk's."
    );
    assert!(
        lines[2].contains("`model=tm2,max_layers=2` on gold (34.000 M"),
        "{}",
        lines[2]
    );
    assert!(
        lines[2].contains("`model=tm2,max_layers=2,fp16=on` on gold"),
        "{}",
        lines[2]
    );
    assert!(!lines[2].contains("tm6"), "{}", lines[2]);
    assert!(lines[2].contains("a published figure's run is among them"));
    assert!(
        lines[3].contains("runs at 1.50× its `fp16=off` twin's time, 1.20× in JIT"),
        "{}",
        lines[3]
    );
    let md = render(std::slice::from_ref(&study), Path::new("REPORT.md"));
    assert!(
        md.contains(
            "| [t](#t) | 6-flux | 2-flux | 16.24× | 5.00×, 0.31× the talk's | \
             5.00×, 0.31× the talk's |"
        ),
        "{md}"
    );
    assert!(md.contains("- wide array against 2-flux"), "{md}");
}

#[test]
fn per_pixel_counts_are_the_main_figure() {
    let key = |k: &str| k.parse::<VariantKey>().unwrap().to_string();
    let counted = |variant: &str, jit: u64, per_pixel: f64, ratio: f64| Run {
        instructions_large: Some(jit * 3),
        instructions_total_large: Some(jit * 4),
        instructions_per_pixel: Some(per_pixel),
        instructions_per_pixel_ratio: Some(ratio),
        ..run(&key(variant), 1.0, jit, jit * 2)
    };
    let study = StudyDir {
        dir: PathBuf::from("x"),
        results: Results {
            counter: Some(CounterInfo {
                sizes: [[48, 48], [96, 96]],
                shaded_pixels: [2304, 9216],
            }),
            runs: vec![
                counted("model=ggx", 1_000_000, 300.0, 1.0),
                counted("model=tm2,max_layers=4", 5_000_000, 2400.0, 8.0),
            ],
            ..llvmpipe_results(Scene::FullScreen)
        },
        meta: StudyMeta {
            name: "n".into(),
            title: "t".into(),
            description: String::new(),
            sweep_file: "s".into(),
            axes: vec!["model".into()],
            points: vec![PointMeta {
                run: 1,
                coords: vec!["tm2".into()],
            }],
            skipped: Vec::new(),
            published: vec![
                published("ggx", "model=ggx", 1.0),
                published("2-flux", "model=tm2", 8.0),
            ],
            fit: false,
            counter_size: Some([48, 48]),
            counter_sizes: Some([[48, 48], [96, 96]]),
            targets: Vec::new(),
            bake_error: Vec::new(),
            reference: Vec::new(),
            shard: None,
        },
    };
    let md = render(std::slice::from_ref(&study), Path::new("REPORT.md"));
    assert!(
        md.contains("fullscreen scene, 8x8") && md.contains("at 48x48 and 96x96"),
        "{md}"
    );
    assert!(
        md.contains(
            "| model | material | median ms | min–max ms | ×ggx (time) | JIT instr. per \
             pixel | ×ggx (per pixel) | JIT instructions | ×ggx (JIT instr.) | all \
             instructions |"
        ),
        "{md}"
    );
    assert!(
        md.contains("| tm2 | gold | 1.000 | 1.000–1.000 | 1.00× | 2400.0 | 8.00× | 5.000 M | 5.00× | 10.000 M |"),
        "{md}"
    );
    assert!(
        md.contains("2-flux against ggx: the talk 8.00×; ours by time 1.00×, 0.12× the talk's, by JIT instructions per pixel 8.00×, agrees."),
        "{md}"
    );
}

/// A study of two materials over the mode: the pivot, the targets (met and missed, by how
/// much), the per-mode reading, the dilution line and the bake-error table.
#[test]
fn targets_pivot_dilution_and_bake_error_are_reported() {
    let key = |k: &str| k.parse::<VariantKey>().unwrap().to_string();
    let counted = |variant: &str, material: &str, jit: u64, per_pixel: f64, ratio: f64| Run {
        material: material.into(),
        instructions_per_pixel: Some(per_pixel),
        instructions_per_pixel_ratio: Some(ratio),
        ..run(&key(variant), 1.0, jit, jit * 2)
    };
    let generic = "model=tm2,max_layers=16";
    let baked = "model=tm2,mode=baked";
    let runs = vec![
        counted("model=ggx", "gold", 1_000_000, 300.0, 1.0),
        counted("model=ggx", "copper", 1_000_000, 300.0, 1.0),
        counted(generic, "gold", 4_000_000, 3000.0, 10.0),
        counted(baked, "gold", 1_100_000, 360.0, 1.2),
        counted(generic, "copper", 3_000_000, 1800.0, 6.0),
        counted(baked, "copper", 1_500_000, 480.0, 1.6),
    ];
    let point = |run: usize, v: &str| PointMeta {
        run,
        coords: vec![v.into()],
    };
    let target = |label: &str, material: &str| Target {
        label: label.into(),
        matches: "mode=baked".into(),
        against: None,
        material: material.into(),
        against_material: None,
        max: 1.5,
        tolerance: None,
    };
    let study = StudyDir {
        dir: PathBuf::from("x"),
        results: Results {
            counter: Some(CounterInfo {
                sizes: [[24, 24], [48, 48]],
                shaded_pixels: [300, 1200],
            }),
            runs,
            ..llvmpipe_results(Scene::Sphere)
        },
        meta: StudyMeta {
            name: "n".into(),
            title: "t".into(),
            description: String::new(),
            sweep_file: "s".into(),
            axes: vec!["variant".into()],
            points: vec![
                point(2, "generic"),
                point(3, "baked"),
                point(4, "generic"),
                point(5, "baked"),
            ],
            skipped: Vec::new(),
            published: Vec::new(),
            fit: false,
            counter_size: Some([24, 24]),
            counter_sizes: Some([[24, 24], [48, 48]]),
            targets: vec![
                target("baked on gold", "gold"),
                target("baked on copper", "copper"),
                // `mode=generic` fits the ggx baseline's key too; it means the study's run.
                Target {
                    against: Some("mode=generic".into()),
                    ..target("baked against generic", "gold")
                },
                // Against another material's run.
                Target {
                    against: Some("mode=baked".into()),
                    against_material: Some("copper".into()),
                    ..target("gold against copper", "gold")
                },
            ],
            bake_error: vec![MaterialBakeError {
                material: "gold".into(),
                variant: baked.parse().unwrap(),
                image_size: 64,
                rows: vec![
                    BakeErrorRow {
                        size: 32,
                        lobe_error: 5e-3,
                        image_error: 2e-2,
                    },
                    BakeErrorRow {
                        size: 256,
                        lobe_error: 3e-4,
                        image_error: 8e-4,
                    },
                ],
            }],
            reference: Vec::new(),
            shard: None,
        },
    };
    let md = render(std::slice::from_ref(&study), Path::new("REPORT.md"));
    for expected in [
        "| material | generic | baked |",
        "| gold | 10.00× | 1.20× |",
        "| copper | 6.00× | 1.60× |",
        "| baked on gold | `model=tm2,max_layers=4,mode=baked` on gold | `model=ggx,max_layers=4` | 1.20× (JIT instructions per pixel) | ≤ 1.50× | met |",
        "| 1.60× (JIT instructions per pixel) | ≤ 1.50× | missed by 7 % |",
        "| baked against generic | `model=tm2,max_layers=4,mode=baked` on gold | `model=tm2,max_layers=16` | 0.12× (JIT instructions per pixel) |",
        "| gold against copper | `model=tm2,max_layers=4,mode=baked` on gold | `model=tm2,max_layers=4,mode=baked` on copper |",
        "`generic` 6.00–10.00× (median 10.00×); `baked` 1.20–1.60× (median 1.60×)",
        "`generic` costs 3.75–8.33× (median 8.33×) `baked` on the same material.",
        "Whole-draw counts dilute the ratios: a run's whole-draw ×ggx at 24x24 is 0.40–0.94× (median 0.92×) of its per-pixel ×ggx",
        "| gold | 5.0e-3 / 2.0e-2 | 3.0e-4 / 8.0e-4 |",
        "| **worst** | 5.0e-3 / 2.0e-2 | 3.0e-4 / 8.0e-4 |",
        "## Summary: targets",
    ] {
        assert!(md.contains(expected), "`{expected}` missing from\n{md}");
    }
}

#[test]
fn links_are_relative_to_the_report() {
    assert_eq!(
        relative(
            Path::new("profiling/results/lavapipe/fp16/chart-time.png"),
            Path::new("profiling")
        ),
        "results/lavapipe/fp16/chart-time.png"
    );
    assert_eq!(
        relative(Path::new("a/b.png"), Path::new("c/d")),
        "../../a/b.png"
    );
}

#[test]
fn the_stats_table_shows_what_differs_and_strips_the_flag_bit() {
    let stats = |regs: u64, local: u64| {
        serde_json::json!([
            {"name": "VS", "description": "vertex", "statistics": [
                {"name": "Register Count", "value": 9}]},
            {"name": "FS", "description": "fragment", "statistics": [
                {"name": "Register Count", "value": regs},
                {"name": "Local Memory Size", "value": FLAG_BIT + local},
                {"name": "Binary Size", "value": 4096}]},
        ])
    };
    let mut a = run("model=tm2,max_layers=4", 1.0, 1, 1);
    a.executable_stats = Some(stats(115, 896));
    let mut b = run("model=tm2,max_layers=8", 2.0, 1, 1);
    b.executable_stats = Some(stats(115, 1792));
    let rows = vec![(vec!["4".to_string()], &a), (vec!["8".to_string()], &b)];
    let mut md = String::new();
    executable_stats_table(&mut md, "max_layers", &rows);
    assert!(
        md.contains("| max_layers | material | Local Memory Size |"),
        "{md}"
    );
    assert!(
        md.contains("| 4 | gold | 896 |") && md.contains("| 8 | gold | 1792 |"),
        "{md}"
    );
    assert!(
        md.contains("Register Count 115") && md.contains("Binary Size 4096"),
        "{md}"
    );
    assert!(md.contains("without bit 36"), "{md}");

    // A deferred run's shading pipeline is a compute kernel: its executable's statistics.
    let mut c = run("model=tm2,max_layers=4,path=deferred", 1.0, 1, 1);
    c.executable_stats = Some(serde_json::json!([
        {"name": "CS", "description": "compute", "statistics": [
            {"name": "Register Count", "value": 72},
            {"name": "Local Memory Size", "value": FLAG_BIT},
            {"name": "Binary Size", "value": 4096}]},
    ]));
    let mut deferred = String::new();
    executable_stats_table(
        &mut deferred,
        "path",
        &[
            (vec!["forward".to_string()], &a),
            (vec!["deferred".to_string()], &c),
        ],
    );
    assert!(
        deferred.contains("| path | material | Register Count | Local Memory Size |")
            && deferred.contains("| deferred | gold | 72 | 0 |"),
        "{deferred}"
    );

    let mut none = String::new();
    let plain = run("model=ggx", 1.0, 1, 1);
    executable_stats_table(&mut none, "model", &[(vec!["ggx".to_string()], &plain)]);
    assert!(none.is_empty());
}

#[test]
fn a_verdict_agrees_with_the_figure_it_prints() {
    let bound = |max: f64, tolerance: Option<f64>| Target {
        label: "t".into(),
        matches: "model=tm2".into(),
        against: None,
        material: "gold".into(),
        against_material: None,
        max,
        tolerance,
    };
    let counts = "JIT instructions per pixel";
    // A narrow miss of a count is not rounded to a figure that meets the bound.
    assert_eq!(
        target_verdict(1.0004, counts, &bound(1.0, None)),
        (
            "1.0004× (JIT instructions per pixel)".to_string(),
            "missed by 0.04 %".to_string()
        )
    );
    assert_eq!(
        target_verdict(1.07, counts, &bound(1.0, None)).1,
        "missed by 7 %"
    );
    assert_eq!(target_verdict(1.0, counts, &bound(1.0, None)).1, "met");
    assert_eq!(
        target_verdict(1.00003, counts, &bound(1.0, None)),
        (
            "1.00003× (JIT instructions per pixel)".to_string(),
            "missed by 0.003 %".to_string()
        )
    );
    // A count is deterministic: a stated tolerance does not widen its bound.
    assert_eq!(
        target_verdict(1.01, counts, &bound(1.0, Some(0.02))).1,
        "missed by 1 %"
    );
    // Times are judged within the stated tolerance, and not at all without one.
    let time = "median time";
    assert!(target_verdict(1.0003, time, &bound(1.0, None))
        .1
        .starts_with("no verdict"));
    assert_eq!(
        target_verdict(1.0003, time, &bound(1.0, Some(0.02))),
        (
            "1.0003× (median time)".to_string(),
            "met within the stated 2 % tolerance".to_string()
        )
    );
    assert_eq!(
        target_verdict(1.05, time, &bound(1.0, Some(0.02))).1,
        "missed by 5 %"
    );
}

#[test]
fn a_study_on_two_devices_gets_a_table_of_both_ratios() {
    let key = |k: &str| k.parse::<VariantKey>().unwrap().to_string();
    let on = |device: &str, ratio: f64| {
        let mut tm2 = run(&key("model=tm2"), 2.0, 0, 0);
        tm2.ratio_to_baseline = ratio;
        StudyDir {
            dir: PathBuf::from(device),
            results: Results {
                device: DeviceInfo {
                    name: device.into(),
                    driver: "d".into(),
                    api_version: "1.3".into(),
                    vendor_id: 0,
                    subgroup_size: None,
                },
                git_rev: "0".into(),
                command: "c".into(),
                size: [8, 8],
                lp_num_threads: None,
                scene: crate::render::scene::Scene::FullScreen,
                counter: None,
                lighting: None,
                environment: None,
                calibration: None,
                runs: vec![run(&key("model=ggx"), 1.0, 0, 0), tm2],
            },
            meta: StudyMeta {
                name: "n".into(),
                title: "T".into(),
                description: String::new(),
                sweep_file: "s".into(),
                axes: vec!["model".into()],
                points: vec![PointMeta {
                    run: 1,
                    coords: vec!["tm2".into()],
                }],
                skipped: Vec::new(),
                published: Vec::new(),
                fit: false,
                counter_size: None,
                counter_sizes: None,
                targets: Vec::new(),
                bake_error: Vec::new(),
                reference: Vec::new(),
                shard: None,
            },
        }
    };
    let mut h100 = on("H100", 21.75);
    h100.results.calibration = Some(crate::profile::calibrate::Calibration {
        width: 1920,
        height: 1080,
        iterations: 256,
        repeats: 5,
        fragment_ms: 2.0,
        compute_ms: 0.25,
        fragment_invocations: None,
        compute_invocations: None,
    });
    let md = render(&[on("lavapipe", 2.5), h100], Path::new("R.md"));
    assert!(md.contains("## Across devices"), "{md}");
    assert!(
        md.contains(
            "a fragment draw 2.000 ms, the same work as a compute dispatch 0.250 ms: \
             compute runs it 8.00× as fast on this device"
        ),
        "{md}"
    );
    assert!(
        md.contains("| model | material | lavapipe | H100 |"),
        "{md}"
    );
    assert!(md.contains("| tm2 | gold | 2.50× | 21.75× |"), "{md}");
    let alone = render(&[on("lavapipe", 2.5)], Path::new("R.md"));
    assert!(!alone.contains("## Across devices"), "one device: no table");
}

/// The divergence reading takes each path against its own coherent runs (never the ggx
/// baseline's), and names the variant when a study has several.
#[test]
fn divergence_is_read_per_variant_against_its_own_coherent_runs() {
    use super::reading::divergence;
    use crate::profile::results::ActiveLayers;
    let with =
        |variant: &str, material: &str, per_pixel: f64, (min, mean, max): (u32, f64, u32)| Run {
            material: material.into(),
            instructions_per_pixel: Some(per_pixel),
            active_layers: Some(ActiveLayers { min, mean, max }),
            ..run(variant, 1.0, 1, 1)
        };
    let (forward, deferred) = (
        "model=tm2,max_layers=5",
        "model=tm2,max_layers=5,path=deferred",
    );
    let results = Results {
        runs: vec![
            with("model=ggx", "low", 100.0, (1, 1.0, 1)),
            with(forward, "low", 1000.0, (1, 1.0, 1)),
            with(forward, "high", 5000.0, (5, 5.0, 5)),
            with(forward, "noise", 4000.0, (1, 3.0, 5)),
            with(deferred, "low", 1200.0, (1, 1.0, 1)),
            with(deferred, "high", 5400.0, (5, 5.0, 5)),
            with(deferred, "noise", 3300.0, (1, 3.0, 5)),
        ],
        ..llvmpipe_results(Scene::FullScreen)
    };
    let lines = divergence(&results);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(
        lines[0].starts_with("noise (model=tm2,max_layers=5):")
            && lines[0].contains("JIT instructions per pixel +33 % (50 % of the way"),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].starts_with("noise (model=tm2,max_layers=5,path=deferred):")
            && lines[1].contains("JIT instructions per pixel +0 % (0 % of the way"),
        "{}",
        lines[1]
    );
}

#[test]
fn the_pareto_front_steps_only_by_resolvable_differences() {
    use crate::profile::results::ImageError;
    use crate::study::charts::pareto_front;
    let scored = |variant: &str, cost: f64, flip: f64, floor: Option<f64>| {
        let mut r = run(variant, cost, 1, 1);
        r.image_error = Some(ImageError {
            flip,
            rmse: 0.0,
            max_relative: 0.0,
        });
        r.reference_flip_floor = floor;
        r
    };
    // Cheapest first: 0.30; 0.27 is within four floors (0.04) of it; 0.20 is not, and the
    // dearest run is not below 0.20 by four floors either.
    let mut results = llvmpipe_results(Scene::FullScreen);
    results.runs = vec![
        scored("model=tm2,ibl=taps", 9.0, 0.19, Some(0.01)),
        scored("model=tm2", 1.0, 0.30, Some(0.01)),
        scored("model=tm2,ibl=matched", 2.0, 0.27, Some(0.01)),
        scored("model=tm2,max_layers=8", 3.0, 0.20, Some(0.01)),
    ];
    assert_eq!(
        pareto_front(&results, "gold", Truth::Paper, false),
        vec![1, 3]
    );
    // Unmeasured floors: the classic front, every strictly closer dearer run.
    for r in &mut results.runs {
        r.reference_flip_floor = None;
    }
    assert_eq!(
        pareto_front(&results, "gold", Truth::Paper, false),
        vec![1, 2, 3, 0]
    );
}
