//! `lamina reference` from the command line: bad input refused by name, the JSON complete and
//! identical on stdout and in `--out`, and Ctrl-C leaving no file behind.

mod common;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn lamina(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lamina"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run lamina")
}

#[test]
fn bad_arguments_are_refused_by_name() {
    let dir = common::scratch_dir("reference-bad");
    for (args, expected) in [
        (vec!["--paths", "0"], "--paths 0"),
        (vec!["--paths", "99999999999999"], "1 to 10000000000 paths"),
        (vec!["--cos", "0"], "--cos: 0"),
        (vec!["--cos", "1.2"], "--cos: 1.2"),
        (vec!["--g2", "beckmann"], "--g2"),
    ] {
        let mut full = vec!["reference", "--material", "gold"];
        if !args.contains(&"--cos") {
            full.extend_from_slice(&["--cos", "0.5"]);
        }
        full.extend_from_slice(&args);
        full.extend_from_slice(&["--out", "r.json"]);
        let out = lamina(&full, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(
            err.contains(expected),
            "{args:?}: `{expected}` missing from {err}"
        );
        assert!(!dir.join("r.json").exists());
    }
}

#[test]
fn the_json_holds_every_estimate_and_the_file_is_the_same() {
    let dir = common::scratch_dir("reference-json");
    let args = [
        "reference",
        "--material",
        "dusty-varnish",
        "--cos",
        "1,0.4",
        "--paths",
        "3000",
        "--json",
        "--out",
        "r.json",
    ];
    let out = lamina(&args, &dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(printed, written);
    assert_eq!(printed["model"], "tm6");
    assert_eq!(printed["slice_theta_deg"].as_array().unwrap().len(), 90);
    let samples = printed["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 2);
    for s in samples {
        let r = s["reflectance"]["mean"][0].as_f64().unwrap();
        let se = s["reflectance"]["std_error"][0].as_f64().unwrap();
        assert!(r > 0.1 && r < 1.0 && se > 0.0 && se < 0.05, "{r} ± {se}");
        assert_eq!(s["slice"].as_array().unwrap().len(), 90);
        assert_eq!(s["hemisphere"].as_array().unwrap().len(), 16 * 32);
    }
}

/// Ctrl-C stops a long run: a clear message, a failing status, and no file, temporary or not.
#[test]
fn an_interrupted_reference_writes_nothing() {
    let dir = common::scratch_dir("reference-interrupt");
    let child = Command::new(env!("CARGO_BIN_EXE_lamina"))
        .args([
            "reference",
            "--material",
            "dusty-varnish",
            "--cos",
            "1",
            "--paths",
            "10000000000",
            "--out",
            "r.json",
        ])
        .current_dir(&dir)
        .stderr(Stdio::piped())
        .spawn()
        .expect("run lamina");
    // Let it load the material and start walking.
    let start = Instant::now();
    std::thread::sleep(Duration::from_millis(1500));
    // SAFETY: kill() on our own child's pid with a valid signal number.
    let sent = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    assert_eq!(sent, 0);
    let out = child.wait_with_output().expect("wait");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("interrupted after"), "{err}");
    assert!(
        start.elapsed() < Duration::from_secs(60),
        "stopping took {:?}",
        start.elapsed()
    );
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}
