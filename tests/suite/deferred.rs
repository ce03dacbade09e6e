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
use lamina::variant::{Mode, ShadePath, VariantKey};
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

/// `stack` under `variant` on both paths: the largest relative difference per pixel.
fn both_paths(renderer: &mut Renderer<'_>, variant: VariantKey, stack: &Stack) -> f64 {
    let mut image = |path: ShadePath| {
        let variant = VariantKey { path, ..variant };
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
    let forward = image(ShadePath::Forward);
    let deferred = image(ShadePath::Deferred);
    assert!(common::mean_radiance(&forward) > 0.0);
    common::largest_relative(&forward, &deferred, 1e-3)
}

/// Every preset under every mode it takes (the varying ones under generic), and the
/// divergence study's masked stacks, over the full-screen grid; then the sphere, whose
/// uncovered pixels must keep the sky.
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
    let mut cases = 0;
    for stack in &stacks {
        let generic: VariantKey =
            format!("model={},max_layers={}", stack.model, stack.layers.len())
                .parse()
                .unwrap();
        let modes: &[Mode] = if stack.surface.is_some() {
            &[Mode::Generic]
        } else {
            &[Mode::Generic, Mode::Specialized, Mode::Baked]
        };
        for &mode in modes {
            let variant = VariantKey { mode, ..generic };
            let d = both_paths(&mut renderer, variant, stack);
            assert!(
                d <= 1e-5,
                "{} {variant}: deferred {d:.1e} from forward",
                stack.name
            );
            cases += 1;
        }
    }
    assert!(cases > 30, "{cases} cases");
    renderer.set_mesh(&uv_sphere(32, 64)).unwrap();
    let gold = Stack::load(&common::repo_path("assets/materials/varnished-gold.toml")).unwrap();
    let d = both_paths(
        &mut renderer,
        "model=tm2,mode=specialized".parse().unwrap(),
        &gold,
    );
    assert!(d <= 1e-5, "sphere: deferred {d:.1e} from forward");
    common::assert_validation_clean(&gpu);
}

#[test]
fn the_deferred_path_refuses_a_varying_stack_under_specialization_by_name() {
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
        err.contains("path=forward") && err.contains("mode=generic"),
        "{err}"
    );
    let err = "model=tm2,path=sideways"
        .parse::<VariantKey>()
        .unwrap_err()
        .to_string();
    assert!(err.contains("forward") && err.contains("deferred"), "{err}");
    common::assert_validation_clean(&gpu);
}
