//! Reference images of stacks that vary over the surface (`render::reference::
//! render_evaluated`): each pixel's lobes evaluated by the pass's shader library from its maps,
//! then integrated by Monte Carlo like a tabulated stack's. Held to the tabulated reference on
//! uniform stacks, and to the real-time pass under a white environment on varying ones.

use crate::common;

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use lamina::imageio::HdrImage;
use lamina::material::{Stack, Surface};
use lamina::render::reference::{self, Convergence, ReferenceImage, Truth};
use lamina::render::scene::{full_screen, Camera};
use lamina::render::{PassKey, Renderer, TargetFormat};
use lamina::tables::environment::EnvDesc;
use lamina::variant::VariantKey;

const W: u32 = 48;
const H: u32 = 27;

fn small_env() -> EnvDesc {
    EnvDesc {
        face_size: 32,
        mip_count: 6,
        samples: 16,
    }
}

fn renderer<'g>(gpu: &'g lamina::Gpu, env: &HdrImage) -> Renderer<'g> {
    let mut renderer = Renderer::with_target(gpu, env, small_env(), TargetFormat::Float).unwrap();
    renderer
        .set_mesh(&full_screen(&Camera::default(), W, H))
        .unwrap();
    renderer
}

fn convergence(spp: u32) -> Convergence {
    Convergence {
        spp,
        noise: None,
        seed: 3,
    }
}

fn evaluated(
    renderer: &mut Renderer<'_>,
    variant: VariantKey,
    stack: &Stack,
    surface: Option<&Arc<Surface>>,
    spp: u32,
) -> ReferenceImage {
    reference::render_evaluated(
        renderer,
        variant,
        &stack.params(),
        surface,
        (W, H),
        convergence(spp),
        &mut |_, _| {},
        &AtomicBool::new(false),
    )
    .unwrap()
    .unwrap()
}

fn mean(p: &[f32; 4]) -> f64 {
    (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0
}

/// A uniform stack's evaluated reference of a variant's lobes is the tabulated one
/// (`reference::render_variant`: the same lobes evaluated at 512 view cosines and interpolated)
/// under the studio environment: per pixel within 5 of the two images' standard errors
/// combined, plus 2e-3 of the pixel for the table's interpolation and the lobes' emission
/// order (the two draw their samples lobe by lobe in their own order). Sixteen frames each: a
/// pixel's standard error is its frames' spread, which four frames (three degrees of freedom)
/// left too uncertain for a bound of five (about one pixel in a thousand past it by chance). A
/// 2-flux coat, a 6-flux medium, a diffuse base and a thin slab that transmits.
#[test]
fn a_uniform_stacks_evaluated_reference_is_its_tabulated_one() {
    let gpu = common::gpu();
    let env = common::studio();
    for material in [
        "varnished-gold",
        "dusty-varnish",
        "glazed-ceramic",
        "amber-glass",
    ] {
        let stack = Stack::resolve(material).unwrap();
        let layers = stack.params();
        let variant = stack.variant(Some("tir=lut32")).unwrap();
        let mut renderer = renderer(&gpu, &env);
        let tabulated = reference::render_variant(
            &mut renderer,
            variant,
            &layers,
            (W, H),
            convergence(256),
            &mut |_, _| {},
            &AtomicBool::new(false),
        )
        .unwrap()
        .unwrap();
        let own = evaluated(&mut renderer, variant, &stack, None, 256);
        let (mut worst, mut sum) = (0.0f64, 0.0f64);
        for (i, (t, e)) in tabulated.pixels.iter().zip(&own.pixels).enumerate() {
            let (t, e) = (mean(t), mean(e));
            let noise = f64::from(tabulated.std_error[i]).hypot(f64::from(own.std_error[i]));
            let bound = 5.0 * noise + 2e-3 * t.abs();
            assert!(
                (t - e).abs() <= bound,
                "{material}, pixel {i}: tabulated {t}, evaluated {e} (bound {bound})"
            );
            worst = worst.max((t - e).abs() / t.abs().max(1e-6));
            sum += t - e;
        }
        let total: f64 = tabulated.pixels.iter().map(mean).sum();
        println!(
            "{material}: worst relative difference {worst:.2e}, of the sum {:.2e}",
            sum / total
        );
    }
    common::assert_validation_clean(&gpu);
}

/// Under a white environment every lobe's integral is its weight, so the evaluated reference
/// of a varying stack is, pixel by pixel, the real-time generic pass of the same variant
/// reading the same maps (both sum the lobes' weights): within two half-float steps (2⁻¹⁰
/// each) of the pixel, as the `ibl` values' images under a uniform environment
/// (tests/suite/ibl.rs): the cube both read is half floats, each texel within a step of the
/// environment's 1, and the two read other texels of it. The textured presets (a coverage and a roughness texture in
/// 2-flux, coverage and a depth pattern in 6-flux), so each pixel's stack is the one its maps
/// give, coverage leaving one layer or all.
#[test]
fn a_varying_stacks_reference_under_a_white_environment_is_its_lobes_weights() {
    let gpu = common::gpu();
    let white = HdrImage {
        width: 64,
        height: 32,
        pixels: vec![[1.0; 4]; 64 * 32],
    };
    for material in [
        "worn-lacquered-copper",
        "dusty-varnished-gold",
        "patchy-patina",
    ] {
        let stack = Stack::resolve(material).unwrap();
        let surface = stack.surface.as_ref().expect("a textured preset");
        let variant = stack.variant(Some("tir=lut32")).unwrap();
        let mut renderer = renderer(&gpu, &white);
        let image = evaluated(&mut renderer, variant, &stack, Some(surface), 16);
        let key = PassKey::new(variant, &stack.layers, Some(surface), &renderer.lighting).unwrap();
        let pass = renderer.prepare(&key).unwrap();
        renderer.set_surface(Some(surface)).unwrap();
        let real_time = renderer.render(&pass, &stack.layers, W, H).unwrap().pixels;
        let worst = common::largest_relative(&real_time, &image.pixels, 1e-3);
        assert!(worst <= 2.0 / 1024.0, "{material}: {worst:.2e}");
        // The maps vary the image: it is not one stack's.
        let (lo, hi) = image
            .pixels
            .iter()
            .map(mean)
            .fold((f64::MAX, 0.0f64), |(lo, hi), m| (lo.min(m), hi.max(m)));
        assert!(hi > 1.2 * lo, "{material}: pixels from {lo} to {hi}");
        println!("{material}: largest relative difference {worst:.2e}");
    }
    common::assert_validation_clean(&gpu);
}

/// What the exact model's reference of a varying stack stands on (`reference::exact_stand_in`:
/// the model's finest tables in place of its exact integrals), measured where both exist: on
/// the uniform presets under the studio environment, the stand-in's image against the exact
/// model's (same seed) within 1 % of the image's summed radiance.
#[test]
fn the_exact_models_stand_in_is_near_the_exact_model() {
    let gpu = common::gpu();
    let env = common::studio();
    for material in [
        "varnished-gold",
        "five-layers",
        "dusty-varnish",
        "glazed-ceramic",
        "amber-glass",
    ] {
        let stack = Stack::resolve(material).unwrap();
        let layers = stack.params();
        let mut renderer = renderer(&gpu, &env);
        let exact = reference::render(
            &mut renderer,
            stack.model,
            &layers,
            Truth::Paper,
            (W, H),
            convergence(64),
            &mut |_, _| {},
            &AtomicBool::new(false),
        )
        .unwrap()
        .unwrap();
        let stand_in = evaluated(
            &mut renderer,
            reference::exact_stand_in(stack.model, Truth::Paper),
            &stack,
            None,
            64,
        );
        let total: f64 = exact.pixels.iter().map(mean).sum();
        let difference: f64 = exact
            .pixels
            .iter()
            .zip(&stand_in.pixels)
            .map(|(a, b)| mean(b) - mean(a))
            .sum();
        let worst = common::largest_relative(&exact.pixels, &stand_in.pixels, 1e-2);
        println!(
            "{material}: stand-in − exact {:+.2e} of the sum, largest pixel {worst:.2e}",
            difference / total
        );
        assert!(
            (difference / total).abs() <= 0.01,
            "{material}: {:+.3e}",
            difference / total
        );
    }
    common::assert_validation_clean(&gpu);
}

/// `render --reference` takes a textured preset, says what its lobes stand on, and writes
/// finite images.
#[test]
fn render_reference_takes_a_varying_stack() {
    let dir = common::scratch_dir("reference-maps-cli");
    let out = common::lamina(
        &[
            "render",
            "--reference",
            "--material",
            "patchy-patina",
            "--size",
            "16x16",
            "--spp",
            "16",
            "--out",
            "r.exr",
            "--png",
            "r.png",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("each pixel's lobes evaluated from its maps with model=tm6"),
        "{err}"
    );
    let image = lamina::imageio::read_exr(&dir.join("r.exr")).unwrap();
    assert!(image.pixels.iter().flatten().all(|c| c.is_finite()));
    assert!(dir.join("r.png").exists());
}
