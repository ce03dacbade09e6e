//! `--capture FILE.rdc` on `render` and `bench`: the capture opens in RenderDoc's own Python
//! module and holds the shaded draw with the variant's pipeline; a file that is not a capture
//! is refused before anything runs.

use std::path::Path;
use std::process::Command;

use crate::common::{self, lamina, text};

/// `scripts/capture-summary.py CAPTURE --expect-pipeline "forward VARIANT"` under the system's
/// Python, which RenderDoc's module (Debian: python3-renderdoc) is built for. RenderDoc 1.24's
/// replay on lavapipe dies of a segmentation fault in `SetFrameEvent` now and then (about one
/// run in ten on a loaded machine, the same capture replaying cleanly the next time): a run
/// killed by a signal is run again, up to three times; an answer — the draw found or not — is
/// final.
fn holds_shaded_draw(capture: &Path, variant: &str) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/capture-summary.py");
    let run = || {
        Command::new("/usr/bin/python3")
            .arg(&script)
            .arg(capture)
            .args(["--expect-pipeline", &format!("forward {variant}")])
            .output()
            .expect("/usr/bin/python3 runs")
    };
    let mut out = run();
    for _ in 1..3 {
        if out.status.code().is_some() {
            break;
        }
        eprintln!(
            "{}: the replay died ({}); again",
            capture.display(),
            out.status
        );
        out = run();
    }
    assert!(
        out.status.success(),
        "{}: {}{}",
        capture.display(),
        text(&out.stdout),
        text(&out.stderr)
    );
}

/// The value after `label` on a line of `stdout`, up to `end`.
fn printed<'a>(stdout: &'a str, label: &str, end: &str) -> &'a str {
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix(label))
        .unwrap_or_else(|| panic!("no `{label}` line in {stdout}"));
    line.trim().split(end).next().unwrap()
}

#[test]
fn render_and_bench_capture_the_shaded_draw_of_their_variant() {
    let dir = common::scratch_dir("capture");
    let out = lamina(
        &[
            "--validation",
            "render",
            "--size",
            "16x16",
            "--material",
            "varnished-gold",
            "--variant",
            "mode=specialized",
            "--out",
            "r.exr",
            "--png",
            "r.png",
            "--capture",
            "frames/render.rdc",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("capture:     frames/render.rdc"),
        "{stdout}"
    );
    holds_shaded_draw(
        &dir.join("frames/render.rdc"),
        printed(&stdout, "variant:", "\n"),
    );

    let out = lamina(
        &[
            "--validation",
            "bench",
            "--size",
            "16x16",
            "--frames",
            "1",
            "--warmup",
            "1",
            "--material",
            "gold",
            "--variant",
            "ibl=matched",
            "--capture",
            "bench.rdc",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let variant = printed(&stdout, "capture: bench.rdc (", " | ");
    assert!(variant.contains("ibl=matched"), "{stdout}");
    holds_shaded_draw(&dir.join("bench.rdc"), variant);
    // Nothing but the captures is left beside them.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .chain(std::fs::read_dir(dir.join("frames")).unwrap())
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

#[test]
fn a_capture_file_that_is_not_rdc_is_refused_before_anything_runs() {
    let dir = common::scratch_dir("capture-bad");
    for command in ["render", "bench"] {
        let out = lamina(
            &[command, "--variant", "tir=none", "--capture", "frame.png"],
            &dir,
        );
        assert!(!out.status.success(), "{command}");
        let stderr = text(&out.stderr);
        assert!(
            stderr.contains("--capture frame.png") && stderr.contains(".rdc"),
            "{command}: {stderr}"
        );
        assert!(!dir.join("frame.png").exists());
    }
}
