//! `lamina view` under Xvfb: a screenshot with the scene and the UI in it, a resize that
//! recreates the swapchain, and a saved stack that loads back unchanged — all with the
//! validation layer on.

use crate::common;

use std::path::Path;
use std::process::{Command, Output};

use lamina::material::Stack;

/// Runs `lamina --validation view ARGS` on a private X server.
fn view(args: &[&str], dir: &Path) -> Output {
    let available = Command::new("sh")
        .args(["-c", "command -v xvfb-run"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        available,
        "xvfb-run is missing: scripts/setup.sh installs it (Debian package xvfb)"
    );
    Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1600x1200x24"])
        .arg(env!("CARGO_BIN_EXE_lamina"))
        .args(["--validation", "view"])
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("run xvfb-run")
}

fn check(out: &Output) -> String {
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "lamina view failed: {text}");
    assert!(!text.contains("[vulkan"), "validation messages: {text}");
    text
}

/// (width, height, RGBA8 pixels) of a PNG.
fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).expect("the screenshot exists"),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgba);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Mean RGB (0..1) of a box of the image.
fn mean(image: &(u32, u32, Vec<u8>), x0: u32, y0: u32, w: u32, h: u32) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            let i = ((y * image.0 + x) * 4) as usize;
            for (c, s) in sum.iter_mut().enumerate() {
                *s += f64::from(image.2[i + c]) / 255.0;
            }
        }
    }
    sum.map(|s| s / f64::from(w * h))
}

/// Distinct colours in a box.
fn distinct(image: &(u32, u32, Vec<u8>), x0: u32, y0: u32, w: u32, h: u32) -> usize {
    let mut seen = std::collections::HashSet::new();
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            let i = ((y * image.0 + x) * 4) as usize;
            seen.insert([image.2[i], image.2[i + 1], image.2[i + 2]]);
        }
    }
    seen.len()
}

#[test]
fn screenshot_shows_the_scene_and_the_ui() {
    let dir = common::scratch_dir("viewer-shot");
    let out = view(
        &[
            "--material",
            "varnished-gold",
            "--size",
            "720x420",
            "--frames",
            "30",
            "--screenshot",
            "shot.png",
        ],
        &dir,
    );
    let text = check(&out);
    assert!(text.contains("30 frame(s)"), "{text}");
    let image = read_png(&dir.join("shot.png"));
    assert_eq!((image.0, image.1), (720, 420));
    // The side panel (330 points wide at scale 1) holds text and widgets.
    assert!(
        distinct(&image, 8, 8, 300, 400) > 20,
        "the UI region is empty"
    );
    // The scene fills the rest: the sphere sits in its centre, the sky at its corner.
    let (x0, w) = (330, 720 - 330);
    let sphere = mean(&image, x0 + w / 2 - 15, 210 - 15, 30, 30);
    let sky = mean(&image, x0 + 4, 4, 30, 30);
    let difference: f64 = (0..3).map(|c| (sphere[c] - sky[c]).abs()).sum();
    assert!(
        difference > 0.1,
        "sphere {sphere:?} and background {sky:?} look alike"
    );
}

#[test]
fn resizing_recreates_the_swapchain_cleanly() {
    let dir = common::scratch_dir("viewer-resize");
    let out = view(
        &[
            "--size",
            "640x400",
            "--frames",
            "16",
            "--resize",
            "560x360",
            "--screenshot",
            "resized.png",
        ],
        &dir,
    );
    let text = check(&out);
    let image = read_png(&dir.join("resized.png"));
    assert_eq!((image.0, image.1), (560, 360), "{text}");
    let builds: u32 = text
        .split("swapchain built ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no swapchain count in: {text}"));
    assert!(builds >= 2, "the swapchain was not recreated: {text}");
}

#[test]
fn a_saved_stack_loads_back_through_render() {
    let dir = common::scratch_dir("viewer-save");
    let out = view(
        &[
            "--material",
            "dusty-varnish",
            "--size",
            "480x320",
            "--frames",
            "2",
            "--save-stack",
            "saved.toml",
        ],
        &dir,
    );
    check(&out);
    let saved = Stack::load(&dir.join("saved.toml")).unwrap();
    let preset = Stack::resolve("dusty-varnish").unwrap();
    assert_eq!(saved.name, preset.name);
    assert_eq!(saved.model, preset.model);
    assert_eq!(saved.layers, preset.layers);
    let render = Command::new(env!("CARGO_BIN_EXE_lamina"))
        .args([
            "--validation",
            "render",
            "--material",
            "saved.toml",
            "--size",
            "48x32",
            "--out",
            "r.exr",
            "--png",
            "r.png",
        ])
        .current_dir(&dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    assert!(
        render.status.success(),
        "{}",
        String::from_utf8_lossy(&render.stderr)
    );
}
