//! The `ibl` axis (issue 30): every value compiles and runs on every preset (maps, diffuse
//! bases, 6-flux and thin slabs included); under a uniform environment every value gives the
//! split sum's image (the white furnace, which the split sum holds, holds for all), a mirror
//! lobe is lit the same by every value, under a real environment the values differ, and a
//! near-mirror glaze keeps the sun's reflection under `lamps`.

use crate::common;

use lamina::imageio::HdrImage;
use lamina::material::{presets, Stack};
use lamina::model::LayerParams;
use lamina::render::lights::Lighting;
use lamina::render::{PassKey, Renderer, TargetFormat};
use lamina::tables::environment::EnvDesc;
use lamina::variant::{Axis, Ibl, VariantKey};

const DESC: EnvDesc = EnvDesc {
    face_size: 32,
    mip_count: 5,
    samples: 16,
};

fn uniform() -> HdrImage {
    HdrImage {
        width: 64,
        height: 32,
        pixels: vec![[0.75, 0.75, 0.75, 1.0]; 64 * 32],
    }
}

/// `stack`'s image under `renderer`'s environment, in each `ibl` value (split-sum first).
fn images(renderer: &mut Renderer<'_>, stack: &Stack, size: u32) -> Vec<Vec<[f32; 4]>> {
    let layers = stack.params();
    renderer.set_surface(stack.surface.as_ref()).unwrap();
    Ibl::VALUES
        .iter()
        .map(|&(_, ibl)| {
            let variant = VariantKey {
                model: stack.model,
                max_layers: (layers.len() as u32).max(4),
                ibl,
                ..VariantKey::default()
            };
            let key = PassKey::new(
                variant,
                &layers,
                stack.surface.as_deref(),
                &Lighting::default(),
            )
            .unwrap();
            let pass = renderer.prepare(&key).unwrap();
            let frame = renderer.render(&pass, &layers, size, size).unwrap();
            assert!(
                frame.pixels.iter().flatten().all(|c| c.is_finite()),
                "{}: a non-finite pixel under ibl={ibl}",
                stack.name
            );
            frame.pixels
        })
        .collect()
}

#[test]
fn a_uniform_environment_gives_every_ibl_value_the_split_sums_image() {
    let gpu = common::gpu();
    let mut renderer = Renderer::with_target(&gpu, &uniform(), DESC, TargetFormat::Float).unwrap();
    for path in presets() {
        let stack = Stack::load(&path).unwrap();
        let images = images(&mut renderer, &stack, 24);
        for (&(name, _), image) in Ibl::VALUES.iter().zip(&images).skip(1) {
            let d = common::largest_relative(&images[0], image, 1e-6);
            println!("{}: ibl={name} within {d:.1e} of the split sum", stack.name);
            // The two cubes are half floats, each texel within a half-float step of the
            // environment (tests/suite/environment.rs): their images, within two.
            assert!(
                d <= 2.0 / 1024.0,
                "{}: ibl={name} differs by {d:.2e}",
                stack.name
            );
        }
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn a_mirror_lobe_is_lit_alike_by_every_ibl_value_and_a_rough_one_is_not() {
    let gpu = common::gpu();
    let mut renderer =
        Renderer::with_target(&gpu, &common::studio(), DESC, TargetFormat::Float).unwrap();
    let stack = |roughness: f64| Stack {
        layers: vec![LayerParams::gold(roughness)],
        ..Stack::resolve("gold").unwrap()
    };
    let mirror = images(&mut renderer, &stack(0.0), 32);
    for (&(name, _), image) in Ibl::VALUES.iter().zip(&mirror).skip(1) {
        assert_eq!(image, &mirror[0], "a mirror under ibl={name}");
    }
    let rough = images(&mut renderer, &stack(0.2), 32);
    for (&(name, _), image) in Ibl::VALUES.iter().zip(&rough).skip(1) {
        let d = common::largest_relative(&rough[0], image, 1e-6);
        assert!(
            d > 1e-2,
            "ibl={name} within {d:.1e} of the split sum on rough gold"
        );
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn an_unknown_ibl_value_is_refused_by_name() {
    let dir = common::scratch_dir("ibl-bad");
    let out = common::lamina(&["render", "--variant", "ibl=exact"], &dir);
    assert!(!out.status.success());
    let stderr = common::text(&out.stderr);
    assert!(
        stderr.contains("`exact`")
            && stderr.contains("split-sum, matched, taps, anisotropic, lamps"),
        "{stderr}"
    );
}

/// Under the studio environment, on gold (one GGX lobe, where the lighting's error is the
/// whole error), the lighting's part of FLIP falls from the split sum to `matched` (the cube
/// prefiltered with the lobe's weights, read where its kernel comes closest to the lobe in
/// L²) and again to `taps`, and from `matched` to `anisotropic` (its two fetches along the
/// lobe's major axis) and to `lamps` (the studio's lamps lit as disk lights): the orderings of
/// one run, against one reference.
#[test]
fn under_the_studio_the_lighting_error_falls_from_split_sum_to_matched_to_taps() {
    use lamina::profile::bench::BenchConfig;
    use lamina::profile::image_error::{self, References};
    use lamina::profile::plan::{Case, Plan};
    use lamina::render::scene::Scene;

    let gpu = common::gpu();
    let stack = Stack::resolve("gold").unwrap();
    let cases = Ibl::VALUES
        .iter()
        .map(|&(_, ibl)| Case {
            variant: VariantKey {
                ibl,
                ..stack.variant(None).unwrap()
            },
            stack: stack.clone(),
        })
        .collect();
    let config = BenchConfig {
        plan: Plan::new(cases),
        scene: Scene::FullScreen,
        width: 96,
        height: 54,
        frames: 1,
        warmup: 0,
        lighting: Lighting::default(),
    };
    let (errors, _) = image_error::measure(
        &gpu,
        &common::studio(),
        &config,
        (256, 0),
        &mut References::default(),
        &mut |_, _, _| {},
    )
    .unwrap();
    let skip = config.plan.added_baselines();
    let lighting: Vec<f64> = errors[skip..]
        .iter()
        .map(|e| e.lighting.unwrap().flip)
        .collect();
    assert!(
        lighting[1] < lighting[0]
            && lighting[2] < lighting[1]
            && lighting[3] < lighting[1]
            && lighting[4] < lighting[1],
        "lighting FLIP split-sum, matched, taps, anisotropic, lamps: {lighting:?}"
    );
    common::assert_validation_clean(&gpu);
}

/// Under the studio every preset (maps, diffuse base, 6-flux, thin slab) renders finite under
/// `ibl=lamps`, and its lamps change the image the split sum gives: through a lobe rougher
/// than the lamps' cube's mip 1, or a diffuse base (glazed ceramic's glaze, α = 0.02, reads
/// the whole map within mip 1 and so sees the split sum's image; its base does not).
#[test]
fn every_preset_renders_under_the_studio_lamps() {
    let gpu = common::gpu();
    let mut renderer =
        Renderer::with_target(&gpu, &common::studio(), DESC, TargetFormat::Float).unwrap();
    let lamps_at = Ibl::VALUES
        .iter()
        .position(|&(_, ibl)| ibl == Ibl::Lamps)
        .unwrap();
    for path in presets() {
        let stack = Stack::load(&path).unwrap();
        // `images` checks every pixel is finite.
        let images = images(&mut renderer, &stack, 24);
        let (split, lamps) = (&images[0], &images[lamps_at]);
        let d = common::largest_relative(split, lamps, 1e-6);
        assert!(
            d > 1e-2,
            "{}: ibl=lamps within {d:.1e} of the split sum",
            stack.name
        );
    }
    common::assert_validation_clean(&gpu);
}

/// An `ibl=lamps` pass holds its environment's lamps as constants: under another environment
/// the renderer refuses it by name, the pass cache no longer finds it (the viewer asks it
/// first) and prepares it again.
#[test]
fn a_lamps_pass_is_refused_under_another_environment_and_the_cache_prepares_it_again() {
    use lamina::render::PassCache;

    let gpu = common::gpu();
    let mut renderer =
        Renderer::with_target(&gpu, &common::studio(), DESC, TargetFormat::Float).unwrap();
    let stack = Stack::resolve("gold").unwrap();
    let layers = stack.params();
    let variant = VariantKey {
        ibl: Ibl::Lamps,
        ..stack.variant(None).unwrap()
    };
    let key = PassKey::uniform(variant, &layers, &Lighting::default()).unwrap();
    let mut cache = PassCache::new();
    let under_studio = {
        let pass = cache.get(&mut renderer, &key).unwrap();
        renderer.render(pass, &layers, 16, 16).unwrap().pixels
    };
    let stale = renderer.prepare(&key).unwrap();
    renderer.set_environment(&uniform(), DESC).unwrap();
    let Err(err) = renderer.render(&stale, &layers, 16, 16) else {
        panic!("a lamps pass rendered under another environment");
    };
    let err = err.to_string();
    assert!(err.contains("lamps of another environment"), "{err}");
    assert!(cache.find(&renderer, &key).is_none());
    let pass = cache.get(&mut renderer, &key).unwrap();
    let under_uniform = renderer.render(pass, &layers, 16, 16).unwrap().pixels;
    assert_ne!(under_studio, under_uniform);
    common::assert_validation_clean(&gpu);
}

/// `stack`'s image under the sunset in `ibl=lamps` and the reference of its own lobes (256
/// samples), on the full-screen scene at 96×54 (whose edges are grazing views).
fn lamps_and_reference_under_the_sunset(
    gpu: &lamina::gpu::Gpu,
    stack: &Stack,
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    use lamina::profile::bench::place_scene;
    use lamina::render::reference::{render_evaluated, Convergence};
    use lamina::render::scene::Scene;
    use std::sync::atomic::AtomicBool;

    let sunset = lamina::imageio::read_exr(&common::repo_path("assets/env/sunset.exr")).unwrap();
    let mut renderer =
        Renderer::with_target(gpu, &sunset, EnvDesc::default(), TargetFormat::Float).unwrap();
    place_scene(
        &mut renderer,
        Scene::FullScreen,
        SUNSET_SIZE.0,
        SUNSET_SIZE.1,
    )
    .unwrap();
    let layers = stack.params();
    let variant = VariantKey {
        ibl: Ibl::Lamps,
        ..stack.variant(None).unwrap()
    };
    let key = PassKey::uniform(variant, &layers, &Lighting::default()).unwrap();
    let pass = renderer.prepare(&key).unwrap();
    let lamps = renderer
        .render(&pass, &layers, SUNSET_SIZE.0, SUNSET_SIZE.1)
        .unwrap()
        .pixels;
    let convergence = Convergence {
        spp: 256,
        noise: None,
        seed: 0,
    };
    let reference = render_evaluated(
        &mut renderer,
        variant,
        &layers,
        None,
        SUNSET_SIZE,
        convergence,
        &mut |_, _| {},
        &AtomicBool::new(false),
    )
    .unwrap()
    .expect("not stopped");
    (lamps, reference.pixels)
}

/// The full-screen scene's size in [`lamps_and_reference_under_the_sunset`].
const SUNSET_SIZE: (u32, u32) = (96, 54);

/// A near-mirror glaze keeps the sun's reflection under `lamps`. Glazed ceramic's glaze
/// (α = 0.02) reads the sunset's sun from the lamps' cube below its mip 2, which holds the
/// whole map, so on the full-screen scene (whose edges are grazing views) the image carries in
/// each channel the light of the reference of its own lobes. Leaning that fetch as far as
/// the lobe's mean leans put it past the sun's reflection at grazing views, and the image's
/// red, much of it the sun's reflection at one edge, fell 11 % below the reference's.
#[test]
fn a_near_mirror_glaze_keeps_the_suns_reflection_under_lamps() {
    let gpu = common::gpu();
    let stack = Stack::resolve("glazed-ceramic").unwrap();
    let (lamps, reference) = lamps_and_reference_under_the_sunset(&gpu, &stack);
    let mean = |pixels: &[[f32; 4]]| -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for p in pixels {
            for (s, c) in sum.iter_mut().zip(p) {
                *s += f64::from(*c);
            }
        }
        sum.map(|s| s / pixels.len() as f64)
    };
    let (lamps, reference) = (mean(&lamps), mean(&reference));
    let ratios: Vec<f64> = lamps.iter().zip(&reference).map(|(l, r)| l / r).collect();
    println!(
        "glazed ceramic under the sunset, lamps / its lobes' reference per channel: {ratios:.3?}"
    );
    assert!(
        ratios.iter().all(|r| (r - 1.0).abs() < 0.05),
        "lamps / reference per channel: {ratios:?}"
    );
    common::assert_validation_clean(&gpu);
}

/// A Lambertian body under `lamps` takes the irradiance of the map without its lamps exactly
/// (its irradiance cube) and the lamps as lights: over blocks of 12×9 pixels of the
/// full-screen scene, each a spread of normals, the image follows the reference of its own
/// lobe (within 0.5 %). The order-2 harmonics of that map, which lit it before, ring around
/// the sunset's bright horizon: they put a block 5.3 % off.
#[test]
fn a_diffuse_body_under_lamps_takes_the_irradiance_of_the_map_without_its_lamps() {
    let gpu = common::gpu();
    let stack = Stack {
        layers: vec![LayerParams::diffuse_base([0.62, 0.16, 0.10])],
        ..Stack::resolve("glazed-ceramic").unwrap()
    };
    let (lamps, reference) = lamps_and_reference_under_the_sunset(&gpu, &stack);
    let (block_w, block_h) = (12, 9);
    let luminance = |pixels: &[[f32; 4]], bx: u32, by: u32| -> f64 {
        let mut sum = 0.0;
        for y in by * block_h..(by + 1) * block_h {
            for x in bx * block_w..(bx + 1) * block_w {
                let p = pixels[(y * SUNSET_SIZE.0 + x) as usize];
                sum +=
                    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]);
            }
        }
        sum
    };
    let mut worst = 0.0f64;
    for by in 0..SUNSET_SIZE.1 / block_h {
        for bx in 0..SUNSET_SIZE.0 / block_w {
            let ratio = luminance(&lamps, bx, by) / luminance(&reference, bx, by);
            worst = worst.max((ratio - 1.0).abs());
        }
    }
    println!(
        "a Lambertian body under the sunset's lamps: blocks within {worst:.4} of the reference"
    );
    assert!(worst < 0.01, "a block {worst:.4} off the reference");
    common::assert_validation_clean(&gpu);
}
