//! What a stack that ends in a dielectric transmits, rendered (a thin slab, `forward.frag.glsl`):
//! the white furnace of lossless transmissive stacks returns R + T = 1 in every path that
//! shades them, and a smooth slab shows, per channel, R times the environment in the mirror
//! direction plus T times the environment straight behind it — in the real-time pass and in
//! the reference image, against the f64 model. The baked mode, whose table holds the
//! transmitted lobe as its last row, renders such a stack as the generic pass does.

use std::sync::atomic::AtomicBool;

use glam::DVec3;

use crate::common;

use lamina::imageio::HdrImage;
use lamina::model::{oracle, LayerParams};
use lamina::render::furnace;
use lamina::render::reference::{self, Convergence, Truth};
use lamina::render::renderer::{Renderer, TargetFormat};
use lamina::tables::environment::EnvDesc;
use lamina::variant::{Model, VariantKey};

use LayerParams as L;

#[test]
fn lossless_transmissive_stacks_return_the_white_furnace() {
    let gpu = common::gpu();
    let lossless = [
        vec![L::dielectric(1.5, 0.3)],
        vec![L::dielectric(1.5, 0.05), L::dielectric(1.8, 0.3)],
        vec![L::dielectric(1.5, 0.2).with_medium(0.8, [1.0; 3], [0.0; 3], 0.3)],
    ];
    let keys = [
        "model=ggx",
        "model=tm2",
        "model=tm2,mode=specialized",
        "model=tm2,mode=baked",
        "model=tm2,transport=corrected,interfaces=multiple",
        "model=tm6",
        "model=tm6,mode=specialized",
        "model=tm6,mode=baked",
        "model=tm6,transport=corrected,interfaces=multiple,mode=specialized",
    ];
    for key in keys {
        for stack in &lossless {
            let bins = furnace::gpu(&gpu, key.parse().unwrap(), stack, 96, 10).unwrap();
            let (min, mean, max) = furnace::summary(&bins);
            println!(
                "{key}, {} layer(s): furnace min {min:.4} mean {mean:.4} max {max:.4}",
                stack.len()
            );
            assert!(max <= 1.0 + 2e-3, "{key} {stack:?}: energy gain, max {max}");
            assert!(min >= 0.995, "{key} {stack:?}: energy lost, min {min}");
        }
    }
    common::assert_validation_clean(&gpu);
}

/// An environment of radiance 1 + y/2 along direction (x, y, z): linear in the direction, so
/// that a narrow lobe's prefiltered value is its centre's and a lookup in the wrong direction
/// shows.
fn gradient() -> (HdrImage, impl Fn(DVec3) -> f64) {
    let (width, height) = (64usize, 32usize);
    let pixels = (0..height)
        .flat_map(|i| {
            let y = (std::f64::consts::PI * (i as f64 + 0.5) / height as f64).cos();
            let value = (1.0 + 0.5 * y) as f32;
            (0..width).map(move |_| [value, value, value, 1.0])
        })
        .collect();
    let image = HdrImage {
        width,
        height,
        pixels,
    };
    (image, |d: DVec3| 1.0 + 0.5 * d.normalize().y)
}

/// Where the camera ray `dir` from `eye` meets the unit sphere at the origin, well inside its
/// silhouette: the normal there.
fn sphere_normal(eye: DVec3, dir: DVec3) -> Option<DVec3> {
    let b = eye.dot(dir);
    let closest = eye - b * dir;
    if closest.length() > 0.9 {
        return None;
    }
    let t = -b - (1.0 - closest.length_squared()).sqrt();
    Some((eye + t * dir).normalize())
}

#[test]
fn a_smooth_slab_shows_the_environment_behind_it() {
    let gpu = common::gpu();
    let (env, radiance) = gradient();
    let desc = EnvDesc {
        face_size: 32,
        mip_count: 6,
        samples: 16,
    };
    let stacks = [
        ("nothing (η = 1)", Model::Tm2, vec![L::dielectric(1.0, 0.0)]),
        ("glass", Model::Tm2, vec![L::dielectric(1.5, 0.0)]),
        (
            "tinted film",
            Model::Tm6,
            vec![L::dielectric(1.5, 0.0).with_medium(0.5, [0.0; 3], [0.1, 0.8, 1.6], 0.0)],
        ),
    ];
    let size = 64;
    let mut worst = 0.0f64;
    for (name, model, layers) in &stacks {
        let variant = VariantKey {
            model: *model,
            ..VariantKey::default()
        };
        let specialized: VariantKey = format!("model={model},mode=specialized").parse().unwrap();
        let mut renderer = Renderer::with_target(&gpu, &env, desc, TargetFormat::Float).unwrap();
        let mut images = Vec::new();
        for v in [variant, specialized] {
            let pass = renderer.prepare_uniform(v, layers).unwrap();
            images.push((
                v.to_string(),
                renderer.render(&pass, layers, size, size).unwrap().pixels,
            ));
        }
        let converged = reference::render(
            &mut renderer,
            *model,
            layers,
            Truth::Paper,
            (size, size),
            Convergence {
                spp: 32,
                noise: None,
                seed: 0,
            },
            &mut |_, _| {},
            &AtomicBool::new(false),
        )
        .unwrap()
        .unwrap();
        images.push(("reference".into(), converged.pixels));
        let camera = renderer.camera;
        let eye = camera.eye.as_dvec3();
        let mut pixels = 0;
        for y in 0..size {
            for x in 0..size {
                let dir = camera.ray(x, y, size, size).as_dvec3().normalize();
                let Some(n) = sphere_normal(eye, dir) else {
                    continue;
                };
                let v = -dir;
                let mu = n.dot(v);
                let mirror = 2.0 * mu * n - v;
                let e = oracle::evaluate(variant, layers, mu);
                for (what, image) in &images {
                    let p = image[(y * size + x) as usize];
                    for (c, &value) in p.iter().take(3).enumerate() {
                        let expected = e.reflectance[c] * radiance(mirror)
                            + e.transmittance[c] * radiance(dir);
                        let error = (f64::from(value) - expected).abs() / expected;
                        assert!(
                            error < 0.01,
                            "{name}, {what}: pixel ({x}, {y}) channel {c}: {value} against \
                             R·L(mirror) + T·L(behind) = {expected:.4} (R {:.4}, T {:.4})",
                            e.reflectance[c],
                            e.transmittance[c]
                        );
                        worst = worst.max(error);
                    }
                }
                pixels += 1;
            }
        }
        assert!(pixels > 1000, "{name}: {pixels} pixels inside the sphere");
    }
    println!("thin slabs against R·L(mirror) + T·L(behind): largest relative error {worst:.2e}");
    common::assert_validation_clean(&gpu);
}

/// Under `mode=baked` a thin slab renders as under `mode=generic` (float target, the gradient
/// environment, whose wrong lookups show), within the table's interpolation between its
/// samples (`baked::max_lobe_error`, ≤ 1e-3 of R + T): the transmitted lobe, the table's last
/// row, lit from behind the surface like the generic pass's.
#[test]
fn the_baked_mode_renders_a_thin_slab_as_the_generic_pass() {
    use lamina::profile::bench::place_scene;
    use lamina::render::scene::Scene;
    use lamina::variant::Mode;

    let gpu = common::gpu();
    let (env, _) = gradient();
    let mut renderer =
        Renderer::with_target(&gpu, &env, EnvDesc::default(), TargetFormat::Float).unwrap();
    let (w, h) = (32, 32);
    place_scene(&mut renderer, Scene::FullScreen, w, h).unwrap();
    let stacks = [
        ("model=tm2", vec![L::dielectric(1.5, 0.1)]),
        (
            "model=tm2",
            vec![L::dielectric(1.5, 0.05), L::dielectric(1.8, 0.3)],
        ),
        (
            "model=tm6",
            vec![L::dielectric(1.5, 0.2).with_medium(0.8, [0.9, 0.7, 0.4], [0.1, 0.2, 0.4], 0.3)],
        ),
    ];
    let mut worst = 0.0f64;
    for (key, stack) in &stacks {
        let generic: VariantKey = key.parse().unwrap();
        let mut image = |mode: Mode| {
            let pass = renderer
                .prepare_uniform(VariantKey { mode, ..generic }, stack)
                .unwrap();
            renderer.render(&pass, stack, w, h).unwrap().pixels
        };
        let (want, got) = (image(Mode::Generic), image(Mode::Baked));
        let d = common::largest_relative(&want, &got, 0.01 * common::mean_radiance(&want));
        worst = worst.max(d);
        assert!(d < 2e-3, "{key} {stack:?}: {d:.1e} from generic");
    }
    println!("baked against generic, thin slabs: largest relative difference {worst:.1e}");
    common::assert_validation_clean(&gpu);
}
