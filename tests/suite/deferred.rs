//! The deferred path (`path=deferred`, `render::deferred`): a G-buffer of the fragment
//! shader's inputs, then the forward pass's shading in compute. It must render what the
//! forward path renders, pixel for pixel, under every mode it takes, with the validation
//! layer's synchronization checks silent; and refuse by name what it cannot shade.

use crate::common;

use lamina::gpu::Gpu;
use lamina::material::{presets, Stack};
use lamina::render::lights::Lighting;
use lamina::render::scene::{full_screen, uv_sphere, Camera};
use lamina::render::{PassKey, Renderer, TargetFormat};
use lamina::tables::environment::EnvDesc;
use lamina::variant::{Classify, Mode, ShadePath, VariantKey};
use lamina::vk::{DeviceSelector, InstanceDesc};

const W: u32 = 48;
const H: u32 = 32;

fn sync_validated() -> Gpu {
    let desc = InstanceDesc {
        sync_validation: true,
        ..InstanceDesc::validated()
    };
    Gpu::with_pipeline_cache(desc, &DeviceSelector::Best, None).expect("a validated device")
}

fn renderer(gpu: &Gpu) -> Renderer<'_> {
    let env = EnvDesc {
        face_size: 32,
        mip_count: 5,
        samples: 16,
    };
    let mut renderer =
        Renderer::with_target(gpu, &common::studio(), env, TargetFormat::Float).unwrap();
    renderer.lighting = Lighting::load("sun").unwrap();
    renderer
}

/// `stack` under `variant` on the forward path and on the deferred path under each of
/// `classify`: the largest relative difference per pixel.
fn both_paths(
    renderer: &mut Renderer<'_>,
    variant: VariantKey,
    stack: &Stack,
    classify: &[Classify],
) -> f64 {
    let mut image = |path: ShadePath, classify: Classify| {
        let variant = VariantKey {
            path,
            classify,
            ..variant
        };
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
    };
    let forward = image(ShadePath::Forward, Classify::None);
    assert!(common::mean_radiance(&forward) > 0.0);
    classify
        .iter()
        .map(|&c| {
            let deferred = image(ShadePath::Deferred, c);
            common::largest_relative(&forward, &deferred, 1e-3)
        })
        .fold(0.0, f64::max)
}

/// Every preset under every mode it takes, and the divergence study's masked stacks, over
/// the full-screen grid, each classified by tiles and by pixels under `mode=specialized` (a
/// varying stack's classes each with its own pipeline, its mixed tiles with the generic one);
/// then the sphere, whose uncovered pixels and tiles must keep the sky.
#[test]
fn the_deferred_path_renders_what_the_forward_path_does() {
    let gpu = sync_validated();
    let mut renderer = renderer(&gpu);
    renderer
        .set_mesh(&full_screen(&Camera::default(), W, H))
        .unwrap();
    let mut stacks: Vec<Stack> = presets().iter().map(|p| Stack::load(p).unwrap()).collect();
    for mask in ["noise", "blocks-8"] {
        let path = common::repo_path(&format!("profiling/sweeps/divergence/{mask}.toml"));
        stacks.push(Stack::load(&path).unwrap());
    }
    let (mut cases, mut routed) = (0, 0);
    let every = [Classify::None, Classify::Tiles, Classify::Pixels];
    let sorted = [Classify::Tiles, Classify::Pixels];
    for stack in &stacks {
        let generic: VariantKey =
            format!("model={},max_layers={}", stack.model, stack.layers.len())
                .parse()
                .unwrap();
        let modes: &[(Mode, &[Classify])] = if stack.surface.is_some() {
            routed += 1;
            &[(Mode::Generic, &every), (Mode::Specialized, &sorted)]
        } else {
            &[
                (Mode::Generic, &[Classify::None]),
                (Mode::Specialized, &every),
                (Mode::Baked, &[Classify::None]),
            ]
        };
        for &(mode, classify) in modes {
            let variant = VariantKey { mode, ..generic };
            let d = both_paths(&mut renderer, variant, stack, classify);
            assert!(
                d <= 1e-5,
                "{} {variant} {classify:?}: deferred {d:.1e} from forward",
                stack.name
            );
            cases += classify.len();
        }
    }
    assert!(cases > 60 && routed >= 5, "{cases} cases, {routed} varying");
    renderer.set_mesh(&uv_sphere(32, 64)).unwrap();
    for material in ["varnished-gold", "worn-lacquered-copper"] {
        let stack = Stack::load(&common::repo_path(&format!(
            "assets/materials/{material}.toml"
        )))
        .unwrap();
        let variant = format!("model={},mode=specialized", stack.model);
        let d = both_paths(&mut renderer, variant.parse().unwrap(), &stack, &sorted);
        assert!(
            d <= 1e-5,
            "sphere, {material}: deferred {d:.1e} from forward"
        );
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn unclassified_deferred_shading_refuses_a_stack_of_several_classes_by_name() {
    let gpu = common::gpu();
    let mut renderer = renderer(&gpu);
    let stack = Stack::load(&common::repo_path(
        "assets/materials/worn-lacquered-copper.toml",
    ))
    .unwrap();
    let variant: VariantKey = "model=tm2,mode=specialized,path=deferred".parse().unwrap();
    let key = PassKey::new(
        variant,
        &stack.layers,
        stack.surface.as_deref(),
        &renderer.lighting,
    )
    .unwrap();
    let err = renderer.prepare(&key).err().expect("refused").to_string();
    assert!(
        err.contains("classify=pixels") && err.contains("path=forward"),
        "{err}"
    );
    let err = "model=tm2,path=sideways"
        .parse::<VariantKey>()
        .unwrap_err()
        .to_string();
    assert!(err.contains("forward") && err.contains("deferred"), "{err}");
    common::assert_validation_clean(&gpu);
}
