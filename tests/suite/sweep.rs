//! `lamina sweep` and `lamina report`: result files, charts and bad sweep files.

use crate::common;

use std::process::Command;

use common::{lamina, text};
use lamina::material::presets;
use lamina::profile::counter::CounterSizes;
use lamina::render::scene::Scene;
use lamina::study;

const SMALL: &str = r#"
name = "small"
title = "Small sweep"
materials = ["varnished-gold"]
size = "64x64"
frames = 3
warmup = 1
[[axis]]
name = "model"
values = ["ggx", "tm2", "tm6"]
[[published]]
label = "2-flux"
match = "model=tm2"
ms = 1.433
[[published]]
label = "6-flux"
match = "model=tm6"
ms = 23.275
"#;

#[test]
fn a_sweep_writes_schema_json_matching_csv_charts_and_a_report() {
    let dir = common::scratch_dir("sweep-small");
    std::fs::write(dir.join("small.toml"), SMALL).unwrap();
    let out = lamina(
        &["--validation", "sweep", "small.toml", "--out", "res"],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}\n{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let res = dir.join("res");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(res.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["size"], serde_json::json!([64, 64]));
    let runs = common::check_results(&json, 3);
    assert_eq!(runs.len(), 3, "3 variants, the ggx one is the baseline");
    assert_eq!(json["scene"], "fullscreen", "a sweep file's default scene");
    let csv = std::fs::read_to_string(res.join("results.csv")).unwrap();
    common::check_csv(&csv, &runs);
    for chart in ["chart-time.png", "chart-time.svg"] {
        let len = std::fs::metadata(res.join(chart)).unwrap().len();
        assert!(len > 2000, "{chart}: {len} bytes");
    }
    let svg = std::fs::read_to_string(res.join("chart-time.svg")).unwrap();
    assert!(svg.contains("Small sweep") && svg.contains("tm6"));
    let report = std::fs::read_to_string(res.join("REPORT.md")).unwrap();
    assert!(report.contains("## Small sweep"));
    assert!(report.contains("| 6-flux | 23.275 | 16.24× |"), "{report}");
    assert!(report.contains("chart-time.png"));
    assert!(
        text(&out.stdout).contains("REPORT.md"),
        "the report's path is printed"
    );

    // `lamina report` over the same directory writes the same document elsewhere.
    let out = lamina(&["report", "res", "--out", "again/REPORT.md"], &dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let again = std::fs::read_to_string(dir.join("again/REPORT.md")).unwrap();
    assert!(again.contains("](../res/chart-time.png)"), "{again}");
}

fn load_error(name: &str, body: &str) -> String {
    let dir = common::scratch_dir(&format!("sweep-bad-{name}"));
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, body).unwrap();
    match study::load(&file) {
        Ok(_) => panic!("{name}: accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_sweep_files_are_refused_before_any_gpu_work() {
    let e = load_error("axis", "[[axis]]\nname = \"colour\"\nvalues = [1]\n");
    assert!(
        e.contains("axis[0].name")
            && e.contains("unknown axis `colour`")
            && e.contains("max_layers"),
        "{e}"
    );
    let e = load_error("empty", "[[axis]]\nname = \"model\"\nvalues = []\n");
    assert!(e.contains("axis[0].values") && e.contains("empty"), "{e}");
    let e = load_error(
        "nofit",
        "materials = [\"five-layers\"]\n[[axis]]\nname = \"max_layers\"\nvalues = [1, 2]\n",
    );
    assert!(e.contains("product is empty"), "{e}");
    for size in ["0x10", "64", "64x99999", "axb"] {
        let e = load_error("size", &format!("size = \"{size}\"\n"));
        assert!(
            e.contains("`size`") && e.contains(size) && e.contains("WxH"),
            "{e}"
        );
    }
    let e = load_error(
        "value",
        "[[axis]]\nname = \"g2\"\nvalues = [\"smith\", \"nope\"]\n",
    );
    assert!(e.contains("nope") && e.contains("height-correlated"), "{e}");
    for (name, body) in [
        ("nothing", ""),
        ("nothing-named", "name = \"x\"\nsize = \"64x64\"\n"),
    ] {
        let e = load_error(name, body);
        assert!(e.contains("names nothing to measure"), "{e}");
    }
    let e = load_error("key", "colour = 1\n");
    assert!(e.contains("colour"), "{e}");
    let e = load_error("counter", "counter = \"cycles\"\n");
    assert!(e.contains("`counter`") && e.contains("instructions"), "{e}");
    let e = load_error("scene", "scene = \"cube\"\n");
    assert!(
        e.contains("`scene`") && e.contains("sphere, fullscreen"),
        "{e}"
    );
    let counted = "counter = \"instructions\"\n";
    for (sizes, words) in [
        (
            "[\"48x48\", \"48x48\"]",
            vec!["counter_sizes", "both have 2304 pixels"],
        ),
        (
            "[\"96x96\", \"48x48\"]",
            vec!["counter_sizes", "smaller size first"],
        ),
        (
            "[\"48x48\"]",
            vec!["counter_sizes", "1 size(s)", "give two"],
        ),
        (
            "[\"48x48\", \"0x96\"]",
            vec!["counter_sizes", "`0x96`", "WxH"],
        ),
    ] {
        let e = load_error("sizes", &format!("{counted}counter_sizes = {sizes}\n"));
        for w in words {
            assert!(e.contains(w), "{sizes}: `{w}` missing from {e}");
        }
    }
    for (body, words) in [
        (
            "tile_width = 128\nsize = \"320x64\"\n",
            vec![
                "`size`",
                "320x64",
                "not a multiple of the study's tile_width 128",
            ],
        ),
        (
            "tile_width = 128\nsize = \"256x64\"\n",
            vec![
                "`counter_sizes`",
                "48x48 and 96x96",
                "multiples of the study's tile_width 128",
            ],
        ),
        ("tile_width = 0\n", vec!["`tile_width`", "1 pixel or more"]),
    ] {
        let e = load_error("tile-width", body);
        for w in words {
            assert!(e.contains(w), "`{w}` missing from {e}");
        }
    }
    let e = load_error("old-size", "counter_size = \"24x24\"\n");
    assert!(
        e.contains("`counter_size`") && e.contains("counter_sizes = ["),
        "{e}"
    );
    let baked = "[[axis]]\nname = \"variant\"\nvalues = [\"mode=specialized\", \"mode=baked\"]\n";
    for (body, words) in [
        (
            "[[target]]\nlabel = \"t\"\nmatch = \"mode=baked\"\nmaterial = \"gold\"\nmax = 1.5\n",
            vec!["target[0].match", "no run of the study on gold"],
        ),
        (
            "[[target]]\nlabel = \"t\"\nmatch = \"mode=baked\"\nmaterial = \"varnished-gold\"\nmax = -1\n",
            vec!["target[0].max", "-1", "positive ratio"],
        ),
        (
            "[[target]]\nlabel = \"t\"\nmatch = \"mode=baked\"\nagainst = \"mode=fast\"\nmaterial = \"varnished-gold\"\nmax = 1\n",
            vec!["target[0].against", "fast"],
        ),
        (
            "[bake_error]\nsizes = [64, 32]\n",
            vec!["bake_error.sizes", "increasing order"],
        ),
        (
            "[bake_error]\nsizes = [1, 32]\n",
            vec!["bake_error.sizes", "1: allowed: 2..=4096"],
        ),
        (
            "[bake_error]\nsizes = [32]\nimage_size = 4\n",
            vec!["bake_error.image_size", "4: allowed: 8..=2048"],
        ),
    ] {
        let e = load_error("target", &format!("{baked}{body}"));
        for w in words {
            assert!(e.contains(w), "`{w}` missing from {e}");
        }
    }
    let e = load_error("unbaked", "[bake_error]\nsizes = [32]\n");
    assert!(
        e.contains("bake_error") && e.contains("no mode=baked run"),
        "{e}"
    );
    let e = load_error("suite", "studies = [\"missing.toml\"]\n");
    assert!(e.contains("missing.toml"), "{e}");

    let reference = "materials = [\"gold\"]\n[reference]\n";
    for (body, words) in [
        (
            "cosines = [0.0]\npaths = 10\n",
            vec!["reference.cosines", "(0, 1]"],
        ),
        (
            "cosines = []\npaths = 10\n",
            vec!["reference.cosines", "empty"],
        ),
        (
            "cosines = [0.5]\npaths = 0\n",
            vec!["reference.paths", "1 to"],
        ),
        ("cosines = [0.5]\n", vec!["paths"]),
        (
            "cosines = [0.5]\npaths = 10\ninterfaces = [\"double\"]\n",
            vec![
                "reference.interfaces",
                "no value `double`",
                "single, multiple",
            ],
        ),
        (
            "cosines = [0.5]\npaths = 10\ninterfaces = []\n",
            vec!["reference.interfaces", "empty"],
        ),
        (
            "cosines = [0.5]\npaths = 10\n[reference.random]\ncount = 0\nseed = 1\n",
            vec!["reference.random.count", "1 to 1000"],
        ),
        (
            "cosines = [0.5]\npaths = 10\n[reference.random]\ncount = 2\nseed = 1\npaths = 0\n",
            vec!["reference.random.paths", "1 to"],
        ),
    ] {
        let e = load_error("reference", &format!("{reference}{body}"));
        for w in words {
            assert!(e.contains(w), "{body}: `{w}` missing from {e}");
        }
    }
    let e = load_error(
        "reference-axis",
        "materials = [\"gold\"]\n[[axis]]\nname = \"g2\"\nvalues = [\"smith\"]\n\
         [reference]\ncosines = [1.0]\npaths = 10\n",
    );
    assert!(e.contains("`reference`") && e.contains("not `axis`"), "{e}");
    let e = load_error(
        "reference-ggx",
        &format!("base = \"model=ggx\"\n{reference}cosines = [1.0]\npaths = 10\n"),
    );
    assert!(e.contains("model=ggx is not a layered model"), "{e}");

    // Through the command line: exit status 1, the file and field named, no output written.
    let dir = common::scratch_dir("sweep-bad-cli");
    std::fs::write(
        dir.join("bad.toml"),
        "[[axis]]\nname = \"colour\"\nvalues = [1]\n",
    )
    .unwrap();
    let out = lamina(&["sweep", "bad.toml", "--out", "res"], &dir);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(
        err.contains("bad.toml") && err.contains("unknown axis `colour`"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(!dir.join("res").exists());
}

/// A `[reference]` study: each material's model against the stochastic reference in both
/// truths, paper and corrected, in the study's JSON, its charts and the report's tables;
/// nothing timed or counted.
#[test]
fn a_reference_study_compares_each_material_with_the_reference() {
    let dir = common::scratch_dir("sweep-reference");
    std::fs::write(
        dir.join("ref.toml"),
        "name = \"ref\"\nmaterials = [\"gold\", \"dusty-varnish\"]\ncounter = \"instructions\"\n\
         [reference]\ncosines = [1.0, 0.4]\npaths = 2000\ninterfaces = [\"single\", \"multiple\"]\n\
         [reference.random]\ncount = 2\nseed = 5\npaths = 1000\n",
    )
    .unwrap();
    let out = lamina(&["--validation", "sweep", "ref.toml", "--out", "res"], &dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("res/study.json")).unwrap())
            .unwrap();
    let compared = meta["reference"].as_array().unwrap();
    // Per truth: the two materials, then the two random stacks.
    assert_eq!(compared.len(), 8);
    assert!(compared[2]["random_stack"]
        .as_str()
        .unwrap()
        .contains("[[layer]]"));
    assert_eq!(compared[2]["paths"], 1000);
    for stack in ["random-00", "random-01"] {
        let toml = dir.join(format!("res/random-stacks/{stack}.toml"));
        assert!(lamina::material::Stack::load(&toml).is_ok(), "{stack}");
    }
    assert_eq!(compared[1]["model"], "tm6");
    assert_eq!(compared[0]["interfaces"], "single");
    assert_eq!(compared[4]["interfaces"], "multiple");
    for m in compared {
        assert_eq!(m["rows"].as_array().unwrap().len(), 2);
        assert_eq!(m["rows"][0]["slice_model"].as_array().unwrap().len(), 90);
        assert_eq!(
            m["rows"][0]["slice_corrected"].as_array().unwrap().len(),
            90
        );
    }
    // The corrected slice's error with the lobes below the top leaving through it: gold has
    // no coat, so it is the corrected slice's; dusty varnish's coat reshapes its base's lobes.
    let exit = |m: usize| compared[m]["rows"][1]["slice_exit"].as_f64().unwrap();
    let corrected = |m: usize| {
        let row = &compared[m]["rows"][1];
        serde_json::from_value::<lamina::reference::compare::ReferenceRow>(row.clone()).unwrap()
    };
    let slice_c = |m: usize| {
        let row = corrected(m);
        row.slice_error_of(&row.slice_corrected).0
    };
    assert_eq!(exit(0), slice_c(0));
    assert!(exit(1) > 0.0);
    assert_ne!(exit(1), slice_c(1));
    // Gold alone: the model's FGD is the reference's single scattering, to its noise.
    let row = &compared[0]["rows"][0];
    for c in 0..3 {
        let (r, se) = (
            row["reference"]["mean"][c].as_f64().unwrap(),
            row["reference"]["std_error"][c].as_f64().unwrap(),
        );
        let m = row["model"][c].as_f64().unwrap();
        assert!(
            (m - r).abs() <= 4.0 * se + 1e-3,
            "channel {c}: {m} vs {r} ± {se}"
        );
    }
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("res/results.json")).unwrap())
            .unwrap();
    assert!(results["runs"].as_array().unwrap().is_empty());
    for chart in [
        "reference-gold",
        "reference-dusty-varnish",
        "reference-gold-multiple",
        "reference-dusty-varnish-multiple",
    ] {
        assert!(dir.join(format!("res/{chart}.png")).is_file(), "{chart}");
        assert!(dir.join(format!("res/{chart}.svg")).is_file(), "{chart}");
    }
    assert!(!dir.join("res/chart-time.png").exists());
    let report = std::fs::read_to_string(dir.join("res/REPORT.md")).unwrap();
    for expected in [
        "| material | model | cos θ | reference R | paper R | paper error | without TIR | \
         corrected R | corrected error (worst channel) |",
        "#### Against the `interfaces=single` reference",
        "#### Against the `interfaces=multiple` reference",
        "| gold | tm2 | 1.00 |",
        "| dusty varnish | tm6 | 0.40 |",
        "of 4 (material, view) points",
        "](reference-gold.png)",
        "](reference-gold-multiple.png)",
        "#### Random stacks",
        "| single | corrected | 4 |",
        "](reference-distribution.png)",
        "corrected, lobes below the top leaving through it |",
        "shades the top interface's with its Fresnel factor",
        "With the lobes below the top leaving through it as the walk's do",
    ] {
        assert!(
            report.contains(expected),
            "`{expected}` missing from {report}"
        );
    }
}

/// `reference_spp`: every run's image against the reference image of its material and scene,
/// in results.json and .csv, an error map per run, the Pareto charts and the report's table.
#[test]
fn a_sweep_measures_each_run_against_the_reference_image() {
    let dir = common::scratch_dir("sweep-image-error");
    std::fs::write(
        dir.join("err.toml"),
        "name = \"err\"\nmaterials = [\"gold\"]\nbase = \"model=tm2\"\nsize = \"48x32\"\n\
         frames = 1\nwarmup = 0\nreference_spp = 64\n\
         [[axis]]\nname = \"fp16\"\nvalues = [\"off\", \"on\"]\n",
    )
    .unwrap();
    let out = lamina(&["--validation", "sweep", "err.toml", "--out", "res"], &dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("res/results.json")).unwrap())
            .unwrap();
    let runs = results["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 3, "the ggx baseline and two variants");
    for (i, run) in runs.iter().enumerate() {
        let e = &run["image_error"];
        let flip = e["flip"].as_f64().unwrap();
        assert!((0.0..1.0).contains(&flip), "run {i}: FLIP {flip}");
        assert!(e["rmse"].as_f64().unwrap() >= 0.0);
        assert!(run["reference_noise"].as_f64().unwrap() > 0.0);
        assert!(dir.join(format!("res/error-maps/run-{i}.png")).is_file());
        for part in ["lighting_error", "model_error"] {
            let flip = run[part]["flip"].as_f64().unwrap();
            assert!((0.0..1.0).contains(&flip), "run {i}: {part} FLIP {flip}");
        }
    }
    // Gold is one conductor lobe, whose energy under fgd=karis is the ggx baseline's F0·A + B:
    // the two runs' own lobes are one, and so are their model parts, which the split sum's
    // lighting part dwarfs.
    let part = |i: usize, p: &str| runs[i][p]["flip"].as_f64().unwrap();
    assert!(runs[0]["variant"]
        .as_str()
        .unwrap()
        .starts_with("model=ggx"));
    let single = (0..runs.len())
        .find(|&i| {
            let v = runs[i]["variant"].as_str().unwrap();
            v.starts_with("model=tm2") && v.contains("fp16=off")
        })
        .unwrap();
    assert!(
        (part(0, "model_error") - part(single, "model_error")).abs() < 1e-3,
        "ggx {} against tm2 {}",
        part(0, "model_error"),
        part(single, "model_error")
    );
    for i in [0, single] {
        assert!(
            part(i, "lighting_error") > 2.0 * part(i, "model_error"),
            "run {i}: lighting {} against model {}",
            part(i, "lighting_error"),
            part(i, "model_error")
        );
    }
    // fp16 against its fp32 twin: only for the fp16 run.
    let halves: Vec<usize> = (0..runs.len())
        .filter(|&i| runs[i].get("image_error_vs_fp32").is_some())
        .collect();
    assert_eq!(halves.len(), 1, "{runs:?}");
    let half = &runs[halves[0]];
    assert!(half["variant"].as_str().unwrap().contains("fp16=on"));
    let flip = half["image_error_vs_fp32"]["flip"].as_f64().unwrap();
    assert!((0.0..1.0).contains(&flip), "{flip}");
    assert!(dir
        .join(format!("res/error-maps/run-{}-vs-fp32.png", halves[0]))
        .is_file());
    let csv = std::fs::read_to_string(dir.join("res/results.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with(
        ",flip,rmse,max_relative_error,flip_vs_fp32,flip_floor,flip_lighting,flip_model"
    ));
    assert!(dir.join("res/chart-pareto-time.png").is_file());
    let report = std::fs::read_to_string(dir.join("res/REPORT.md")).unwrap();
    for expected in [
        "| run | material | FLIP | lighting | model | RMSE | max rel. error | median ms | Pareto | error map |",
        "| ggx baseline | gold |",
        "](error-maps/run-0.png)",
        "chart-pareto-time.png",
        "| FLIP vs fp32 |",
    ] {
        assert!(
            report.contains(expected),
            "`{expected}` missing from {report}"
        );
    }
}

#[test]
fn every_committed_sweep_file_expands() {
    let dir = common::repo_path("profiling/sweeps");
    let (studies, suite) = study::load(&dir.join("reproduce.toml")).unwrap();
    assert!(suite);
    assert!(studies.len() >= 8);
    let static_size = studies
        .iter()
        .find(|s| s.name == "static-array-size")
        .unwrap();
    // 5 sizes × 5 active counts, less the 4 + 3 + 1 that do not fit (1, 2 and 4 layers).
    assert_eq!(static_size.points.len(), 25 - 8);
    for s in &studies {
        if let Some(r) = &s.reference {
            // The model against the stochastic reference: every preset, nothing timed.
            assert_eq!(r.cases.len(), presets().len(), "{}", s.name);
            assert!(s.points.is_empty() && s.counter.is_none(), "{}", s.name);
            continue;
        }
        // The divergence study keeps its own sizes: the suite's widths are not multiples of
        // its `tile_width`; specialized-maps its own counter sizes (`own_counter_sizes`).
        let (size, counted) = match s.name.as_str() {
            "divergence" => ((256, 128), "128x32,128x64"),
            "specialized-maps" => ((160, 90), "96x96,192x192"),
            _ => ((160, 90), "24x24,48x48"),
        };
        assert_eq!((s.width, s.height), size, "{}: suite size applies", s.name);
        assert_eq!(
            s.counter.map(|c| c.to_string()).as_deref(),
            Some(counted),
            "{}: suite counter sizes apply",
            s.name
        );
    }
    for name in [
        "quick",
        "static-array-size",
        "fp16",
        "fp16-6flux",
        "tir",
        "fgd",
        "g2",
        "lights",
        "flux",
        "growth",
        "specialization",
        "specialized-scaling",
        "channels",
    ] {
        let (studies, _) = study::load(&dir.join(format!("{name}.toml"))).unwrap();
        assert_eq!(
            studies[0].scene,
            Scene::FullScreen,
            "{name}: studies shade every pixel"
        );
        let mut study = studies[0].clone();
        study.count_instructions();
        assert_eq!(study.counter, Some(CounterSizes::DEFAULT));
    }
    // The old method's study stays on the sphere; issue 11's targets and bake-error study load.
    let (dilution, _) = study::load(&dir.join("dilution.toml")).unwrap();
    assert_eq!(dilution[0].scene, Scene::Sphere);
    let (specialization, _) = study::load(&dir.join("specialization.toml")).unwrap();
    assert_eq!(specialization[0].targets.len(), 2);
    assert_eq!(specialization[0].targets[0].material, "varnished gold");
    assert_eq!(
        specialization[0].bake_error,
        Some((vec![32, 64, 128, 256, 512], 128))
    );
    // The real-GPU suite: the same studies, at the talk's resolution, timed only.
    let (gpu, suite) = study::load(&dir.join("reproduce-gpu.toml")).unwrap();
    assert!(suite);
    let names = |list: &[study::Study]| list.iter().map(|s| s.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&gpu), names(&studies));
    for s in &gpu {
        // 1920 is a multiple of the divergence study's `tile_width`.
        assert_eq!((s.width, s.height), (1920, 1080), "{}", s.name);
        assert_eq!(s.counter, None, "{}: nothing to count on a GPU", s.name);
    }
}

#[test]
fn a_suite_runs_the_studies_named_and_refuses_others() {
    let dir = common::scratch_dir("sweep-select");
    let suite = common::repo_path("profiling/sweeps/reproduce.toml");
    let suite = suite.to_str().unwrap();
    let out = lamina(
        &[
            "sweep",
            suite,
            "--study",
            "tir",
            "--study",
            "fgd",
            "--dry-run",
        ],
        &dir,
    );
    let plan = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(plan.contains(": 2 studies,"), "{plan}");
    assert!(plan.contains("tir:") && plan.contains("fgd:"), "{plan}");
    assert!(!plan.contains("growth"), "{plan}");

    let out = lamina(&["sweep", suite, "--study", "nope", "--dry-run"], &dir);
    let err = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("--study nope") && err.contains("reproduce.toml") && err.contains("growth"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// Runs a suite of `studies` (name, file text) in `dir` and answers, per study, the JIT
/// instructions per shaded pixel of its first run whose variant holds `variant`.
fn suite_counts(dir: &std::path::Path, studies: &[(&str, String)], variant: &str) -> Vec<f64> {
    for (name, body) in studies {
        std::fs::write(dir.join(format!("{name}.toml")), body).unwrap();
    }
    let files: Vec<String> = studies
        .iter()
        .map(|(n, _)| format!("\"{n}.toml\""))
        .collect();
    std::fs::write(
        dir.join("suite.toml"),
        format!("name = \"both\"\nstudies = [{}]\n", files.join(", ")),
    )
    .unwrap();
    let out = lamina(
        &["--validation", "sweep", "suite.toml", "--out", "res"],
        dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    studies
        .iter()
        .map(|(name, _)| {
            let path = dir.join("res").join(name).join("results.json");
            let json: serde_json::Value =
                serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
            let runs = json["runs"].as_array().unwrap();
            let run = runs
                .iter()
                .find(|r| r["variant"].as_str().unwrap().contains(variant))
                .unwrap();
            run["instructions_per_pixel"].as_f64().unwrap()
        })
        .collect()
}

#[test]
fn a_suite_counts_studies_lit_differently_each_under_its_own_lights() {
    let dir = common::scratch_dir("sweep-lit-suite");
    let study = |name: &str, lights: &str| {
        format!(
            "name = \"{name}\"\nmaterials = [\"gold\"]\n{lights}size = \"16x16\"\nframes = 1\n\
             warmup = 0\ncounter = \"instructions\"\ncounter_sizes = [\"8x8\", \"16x16\"]\n\
             [[axis]]\nname = \"model\"\nvalues = [\"ggx\"]\n"
        )
    };
    let studies = [
        ("dark", study("dark", "")),
        ("lit", study("lit", "lights = \"sun-only\"\n")),
    ];
    let [dark, lit] = suite_counts(&dir, &studies, "model=ggx")[..] else {
        unreachable!("one count per study");
    };
    // The sun's loop runs only in the lit study's pipeline.
    assert!(lit > dark + 50.0, "lit {lit} against dark {dark}");
}

/// A study with its own `env` is counted under it: an `ibl=lamps` pass compiles the lamps of
/// its map (the studio's four, the sunset's one), so the two studies' counts differ.
#[test]
fn a_suite_counts_a_study_under_its_own_environment() {
    let dir = common::scratch_dir("sweep-env-suite");
    std::fs::copy(
        common::repo_path("assets/env/sunset.exr"),
        dir.join("sunset.exr"),
    )
    .unwrap();
    let study = |name: &str, env: &str| {
        format!(
            "name = \"{name}\"\nmaterials = [\"gold\"]\nbase = \"model=tm2,mode=specialized\"\n\
             {env}size = \"16x16\"\nframes = 1\nwarmup = 0\ncounter = \"instructions\"\n\
             counter_sizes = [\"8x8\", \"16x16\"]\n[[axis]]\nname = \"ibl\"\nvalues = [\"lamps\"]\n"
        )
    };
    let studies = [
        ("studio", study("studio", "")),
        ("sunset", study("sunset", "env = \"sunset.exr\"\n")),
    ];
    let [studio, sunset] = suite_counts(&dir, &studies, "ibl=lamps")[..] else {
        unreachable!("one count per study");
    };
    assert!(
        studio > sunset + 50.0,
        "studio {studio} against sunset {sunset}"
    );
}

/// On lavapipe pinned to one thread, the tables are built first in a child process on every
/// core, into the cache the run then reads.
#[test]
fn a_pinned_lavapipe_run_builds_its_tables_first_on_every_core() {
    let dir = common::scratch_dir("sweep-prebuild");
    let cache = dir.join("cache");
    std::fs::write(
        dir.join("tir.toml"),
        "materials = [\"varnished-gold\"]\nsize = \"16x16\"\nframes = 1\nwarmup = 0\n\
         [[axis]]\nname = \"tir\"\nvalues = [\"lut32\"]\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lamina"))
        .args(["--validation", "sweep", "tir.toml", "--out", "res"])
        .current_dir(&dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("LP_NUM_THREADS", "0")
        .env("LAMINA_CACHE", &cache)
        .output()
        .unwrap();
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if cores > 1 {
        assert!(stdout.contains("tables on every core"), "{stdout}");
    }
    let tables: Vec<String> = std::fs::read_dir(cache.join("tables"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(tables.iter().any(|t| t.starts_with("tir")), "{tables:?}");
}

/// A study's own `env`: it lights that study (recorded in its results and report), relative
/// to its file; a missing map is refused naming the file and the field.
#[test]
fn a_study_is_lit_by_its_own_environment() {
    let dir = common::scratch_dir("sweep-env");
    std::fs::copy(
        common::repo_path("assets/env/white.exr"),
        dir.join("white.exr"),
    )
    .unwrap();
    let study = |env: &str| {
        format!(
            "name = \"lit\"\nmaterials = [\"gold\"]\nbase = \"model=tm2\"\nsize = \"16x16\"\n\
             frames = 1\nwarmup = 0\nreference_spp = 16\nenv = \"{env}\"\n\
             [[axis]]\nname = \"ibl\"\nvalues = [\"split-sum\", \"matched\"]\n"
        )
    };
    std::fs::write(dir.join("lit.toml"), study("white.exr")).unwrap();
    let out = lamina(&["--validation", "sweep", "lit.toml", "--out", "res"], &dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("res/results.json")).unwrap())
            .unwrap();
    assert_eq!(results["environment"], "white.exr");
    // Under the white environment both cubes are uniform: the two values' images are one, and
    // their lighting parts too.
    let runs = results["runs"].as_array().unwrap();
    let lighting = |i: usize| runs[i]["lighting_error"]["flip"].as_f64().unwrap();
    assert_eq!(runs.len(), 3);
    assert!((lighting(1) - lighting(2)).abs() < 1e-3, "{runs:?}");
    let md = std::fs::read_to_string(dir.join("res/REPORT.md")).unwrap();
    assert!(md.contains("Environment: `white.exr`"), "{md}");

    std::fs::write(dir.join("lit.toml"), study("missing.exr")).unwrap();
    let out = lamina(&["sweep", "lit.toml", "--out", "bad"], &dir);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("lit.toml") && stderr.contains("env") && stderr.contains("missing.exr"),
        "{stderr}"
    );
}

/// A combination a pass would refuse (a baked table for a stack with maps) is refused
/// when the file is read, naming the file, the field and the material: before any GPU work.
#[test]
fn a_study_a_pass_would_refuse_is_refused_before_it_runs() {
    let dir = common::scratch_dir("sweep-refused");
    std::fs::write(
        dir.join("maps.toml"),
        "name = \"maps\"\nmaterials = [\"gold\", \"worn-lacquered-copper\"]\n\
         base = \"mode=baked\"\n[[axis]]\nname = \"ibl\"\nvalues = [\"split-sum\"]\n",
    )
    .unwrap();
    let out = lamina(&["sweep", "maps.toml", "--dry-run"], &dir);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    for part in [
        "maps.toml",
        "materials",
        "worn lacquered copper",
        "mode=generic",
    ] {
        assert!(stderr.contains(part), "`{part}` missing from {stderr}");
    }
}
