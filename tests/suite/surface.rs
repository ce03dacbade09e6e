//! Spatially varying stacks on the GPU (`material::surface`): a coverage of 0 shades exactly
//! the stack without the layer, a coverage of 1 exactly the stack, a screen-space mask picks
//! one of the two per pixel, and a varying field matches the CPU twin's stack at the pixel.

use crate::common;

use std::path::Path;

use lamina::material::Stack;
use lamina::model::LayerParams;
use lamina::render::lights::Lighting;
use lamina::render::scene::{full_screen, Camera};
use lamina::render::{PassKey, Renderer, TargetFormat};
use lamina::tables::environment::EnvDesc;
use lamina::variant::{Model, VariantKey};

const W: u32 = 64;
const H: u32 = 48;

fn small_env() -> EnvDesc {
    EnvDesc {
        face_size: 64,
        mip_count: 5,
        samples: 16,
    }
}

fn stack(text: &str) -> Stack {
    Stack::from_toml(text, Path::new("test.toml")).unwrap()
}

const COAT: &str = "ior = [1.5, 1.5, 1.5]\nroughness = 0.1\n";
const FILM: &str = "ior = [1.9, 1.8, 1.7]\nroughness = 0.3\n";
const GOLD: &str = "ior = [0.143, 0.374, 1.442]\nkappa = [3.983, 2.385, 1.603]\nroughness = 0.2\n";
const MEDIUM: &str = "depth = 0.5\nsigma_s = [1.0, 0.8, 0.6]\nsigma_a = [0.1, 0.2, 0.3]\ng = 0.4\n";

/// Model `model`'s stack of `layers` (each a layer table's body), top first.
fn toml(model: &str, layers: &[String]) -> String {
    let mut out = format!("model = \"{model}\"\n");
    if layers
        .iter()
        .any(|l| l.contains("coverage") || l.contains('{'))
    {
        out += "map_resolution = 16\n";
    }
    for layer in layers {
        out += &format!("[[layer]]\n{layer}\n");
    }
    out
}

/// Renders `stack` (its surface set) under `variant` over the full-screen grid.
fn render(renderer: &mut Renderer<'_>, variant: &str, stack: &Stack) -> Vec<[f32; 4]> {
    let variant: VariantKey = variant.parse().unwrap();
    let key = PassKey::new(
        variant,
        &stack.layers,
        stack.surface.as_deref(),
        &renderer.lighting,
    )
    .unwrap();
    let pass = renderer.prepare(&key).unwrap();
    renderer.set_surface(stack.surface.as_ref()).unwrap();
    renderer.render(&pass, &stack.layers, W, H).unwrap().pixels
}

fn renderer(gpu: &lamina::Gpu) -> Renderer<'_> {
    let mut renderer =
        Renderer::with_target(gpu, &common::studio(), small_env(), TargetFormat::Float).unwrap();
    renderer
        .set_mesh(&full_screen(&Camera::default(), W, H))
        .unwrap();
    renderer
}

#[test]
fn coverage_zero_is_the_stack_without_the_layer_and_one_the_stack() {
    let gpu = common::gpu();
    let mut renderer = renderer(&gpu);
    for (model, film) in [
        ("tm2", FILM.to_string()),
        ("tm6", format!("{FILM}{MEDIUM}")),
    ] {
        let variant = format!("model={model},max_layers=4");
        let coat = COAT.to_string();
        let gold = GOLD.to_string();
        let plain = render(
            &mut renderer,
            &variant,
            &stack(&toml(model, &[coat.clone(), film.clone(), gold.clone()])),
        );
        let without = render(
            &mut renderer,
            &variant,
            &stack(&toml(model, &[coat.clone(), gold.clone()])),
        );
        let zero = stack(&toml(
            model,
            &[coat.clone(), format!("{film}coverage = 0\n"), gold.clone()],
        ));
        assert_eq!(
            zero.surface.as_ref().unwrap().maps.coverage_fraction(1),
            0.0
        );
        let one = stack(&toml(
            model,
            &[
                coat.clone(),
                format!("{film}coverage = 1.0\n"),
                gold.clone(),
            ],
        ));
        let covered_zero = render(&mut renderer, &variant, &zero);
        let covered_one = render(&mut renderer, &variant, &one);
        let differing =
            |a: &[[f32; 4]], b: &[[f32; 4]]| a.iter().zip(b).filter(|(x, y)| x != y).count();
        assert!(
            differing(&plain, &without) > (W * H / 2) as usize,
            "{model}: the film must change the image for the test to mean anything"
        );
        assert_eq!(differing(&covered_zero, &without), 0, "{model}: coverage 0");
        assert_eq!(differing(&covered_one, &plain), 0, "{model}: coverage 1");
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn a_screen_mask_shades_each_pixel_as_its_own_stack() {
    let gpu = common::gpu();
    let mut renderer = renderer(&gpu);
    let variant = "model=tm2,max_layers=4";
    let all = render(
        &mut renderer,
        variant,
        &stack(&toml("tm2", &[COAT.into(), FILM.into(), GOLD.into()])),
    );
    let without = render(
        &mut renderer,
        variant,
        &stack(&toml("tm2", &[COAT.into(), GOLD.into()])),
    );
    // 4-pixel checker blocks: a 16-texel map with 4 cells per side, tiling the frame.
    let masked = stack(&toml(
        "tm2",
        &[
            COAT.into(),
            format!(
                "{FILM}coverage = {{ pattern = \"checker\", scale = 4, coords = \"screen\" }}\n"
            ),
            GOLD.into(),
        ],
    ));
    let maps = &masked.surface.as_ref().unwrap().maps;
    assert_eq!(maps.coverage_fraction(1), 0.5);
    let image = render(&mut renderer, variant, &masked);
    let mut covered = 0;
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let layers = maps.layers_at(&masked.layers, (0.0, 0.0), (x, y));
            let want = if layers.len() == 3 {
                all[i]
            } else {
                without[i]
            };
            covered += usize::from(layers.len() == 3);
            assert_eq!(
                (((x / 4) + (y / 4)) % 2 == 1),
                layers.len() == 3,
                "({x}, {y})"
            );
            assert_eq!(
                image[i],
                want,
                "pixel ({x}, {y}) with {} layers",
                layers.len()
            );
        }
    }
    assert_eq!(covered, (W * H / 2) as usize);
    common::assert_validation_clean(&gpu);
}

#[test]
fn a_varying_roughness_shades_as_the_cpu_twins_stack_at_each_pixel() {
    let gpu = common::gpu();
    let mut renderer = renderer(&gpu);
    let variant = "model=tm2,max_layers=4";
    // Screen coordinates: each pixel reads one texel, so the stack at a pixel is exact.
    let varying = stack(&toml(
        "tm2",
        &[
            COAT.into(),
            GOLD.replace(
                "roughness = 0.2",
                "roughness = { pattern = \"cells\", scale = 16, range = [0.05, 0.6], coords = \"screen\" }",
            ),
        ],
    ));
    let image = render(&mut renderer, variant, &varying);
    let maps = &varying.surface.as_ref().unwrap().maps;
    let mut checked = 0;
    for (x, y) in [(3, 5), (17, 9), (40, 30), (63, 47), (8, 20)] {
        let layers: Vec<LayerParams> = maps.layers_at(&varying.layers, (0.0, 0.0), (x, y));
        let uniform = Stack {
            layers: layers.clone(),
            surface: None,
            ..varying.clone()
        };
        let reference = render(&mut renderer, variant, &uniform);
        let i = (y * W + x) as usize;
        assert_eq!(
            image[i], reference[i],
            "pixel ({x}, {y}), α = {}",
            layers[1].roughness
        );
        checked += 1;
    }
    assert_eq!(checked, 5);
    common::assert_validation_clean(&gpu);
}

#[test]
fn varying_stacks_refuse_the_per_material_modes_but_specialized() {
    let masked = stack(&toml(
        "tm2",
        &[format!("{COAT}coverage = 0.5\n"), GOLD.into()],
    ));
    for mode in ["specialized-values", "baked"] {
        let err = PassKey::new(
            format!("model=tm2,mode={mode}").parse().unwrap(),
            &masked.layers,
            masked.surface.as_deref(),
            &Lighting::default(),
        )
        .expect_err("a varying stack under a per-value mode")
        .to_string();
        assert!(
            err.contains("mode=generic") && err.contains("mode=specialized"),
            "{err}"
        );
    }
    PassKey::new(
        "model=tm2,mode=specialized".parse().unwrap(),
        &masked.layers,
        masked.surface.as_deref(),
        &Lighting::default(),
    )
    .expect("mode=specialized routes a varying stack's pixels by class");
}

/// `mode=specialized` on a varying stack (render::classes: stencil marks, then one pipeline
/// per class of pixels) renders what `mode=generic` renders, pixel by pixel: the textured
/// presets, the divergence study's masked stacks, and stacks at the edges of what routing
/// handles — maps that carry a structural test across its threshold (α reaching 0, η
/// crossing 1, a depth reaching 0), a coverage that leaves some pixels no layer at all, a
/// diffuse base that comes and goes, maps in different coordinates.
#[test]
fn specialized_classes_shade_what_the_generic_pass_does() {
    let gpu = common::gpu();
    let mut renderer = renderer(&gpu);
    let presets = [
        "worn-lacquered-copper",
        "patchy-patina",
        "dusty-varnished-gold",
    ];
    let mut stacks: Vec<(String, Stack)> = presets
        .iter()
        .map(|name| {
            let path = common::repo_path(&format!("assets/materials/{name}.toml"));
            (name.to_string(), Stack::load(&path).unwrap())
        })
        .collect();
    for mask in ["noise", "blocks-2", "blocks-64", "uniform", "low", "high"] {
        let path = common::repo_path(&format!("profiling/sweeps/divergence/{mask}.toml"));
        stacks.push((format!("divergence {mask}"), Stack::load(&path).unwrap()));
    }
    let checker = |seed: u32, coords: &str| {
        format!(
            "coverage = {{ pattern = \"cells\", scale = 4, seed = {seed}, threshold = 0.5, \
             coords = \"{coords}\" }}\n"
        )
    };
    let edges = [
        (
            "α reaching 0, η crossing 1",
            "tm2",
            vec![
                "ior = { pattern = \"noise\", scale = 3, range = [0.9, 1.1] }\nroughness = 0.1\n"
                    .to_string(),
                format!(
                    "ior = [1.5, 1.5, 1.5]\nroughness = {{ pattern = \"checker\", scale = 4, \
                     range = [0.0, 0.3] }}\n{}",
                    checker(1, "uv")
                ),
                GOLD.to_string(),
            ],
        ),
        (
            "no layer left",
            "tm2",
            vec![
                format!("{COAT}{}", checker(2, "uv")),
                format!("{GOLD}{}", checker(3, "screen")),
            ],
        ),
        (
            "depth reaching 0, a diffuse base that comes and goes",
            "tm6",
            vec![
                format!(
                    "{FILM}depth = {{ pattern = \"checker\", scale = 2, range = [0.0, 0.5] }}\n\
                     sigma_s = [1.0, 0.8, 0.6]\nsigma_a = [0.1, 0.2, 0.3]\ng = 0.4\n"
                ),
                format!("diffuse = [0.6, 0.5, 0.4]\n{}", checker(4, "uv")),
            ],
        ),
        (
            "a thin slab with a coat that comes and goes",
            "tm2",
            vec![format!("{COAT}{}", checker(5, "uv")), FILM.to_string()],
        ),
    ];
    for (name, model, layers) in edges {
        stacks.push((name.to_string(), stack(&toml(model, &layers))));
    }
    for (name, stack) in &stacks {
        let model = stack.model;
        let n = stack.layers.len();
        let generic = render(
            &mut renderer,
            &format!("model={model},max_layers={n}"),
            stack,
        );
        // A 6-flux stack's classes also walk one colour channel at a time.
        let keys: &[&str] = if model == Model::Tm6 {
            &["mode=specialized", "mode=specialized,channels=serial"]
        } else {
            &["mode=specialized"]
        };
        for key in keys {
            let specialized = render(&mut renderer, &format!("model={model},{key}"), stack);
            let worst = common::largest_relative(&generic, &specialized, 1e-3);
            assert!(
                worst <= 1e-4,
                "{name}: {key} differs from generic by {worst:.2e}"
            );
        }
        assert!(
            common::mean_radiance(&generic) > 0.0,
            "{name}: the image must show something"
        );
    }
    common::assert_validation_clean(&gpu);
}
