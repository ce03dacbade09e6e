//! The diffuse base on the GPU (`model::diffuse`): its lobe as the f64 oracle gives it, with the
//! variant's own tables (GPU evaluator against `VariantOracle`), and the white furnace of a
//! white base under lossless coats, which returns at most — and, lossless, all of — the light.

use crate::common;

use lamina::model::LayerParams;
use lamina::render::eval::GpuEvaluator;
use lamina::render::furnace;
use lamina::render::oracle::VariantOracle;
use lamina::variant::VariantKey;

use LayerParams as L;

fn coat(ior: f64, roughness: f64) -> LayerParams {
    L::dielectric(ior, roughness)
}

fn base(rho: [f64; 3]) -> LayerParams {
    L::diffuse_base(rho)
}

fn stacks() -> Vec<Vec<LayerParams>> {
    vec![
        vec![base([0.7, 0.3, 0.1])],
        vec![coat(1.5, 0.0), base([0.62, 0.16, 0.10])],
        vec![coat(1.5, 0.05), coat(1.3, 0.3), base([0.9, 0.9, 0.2])],
        vec![
            coat(1.6, 0.2).with_medium(0.8, [1.5, 1.0, 0.5], [0.1, 0.2, 0.4], 0.3),
            base([0.5, 0.6, 0.7]),
        ],
    ]
}

#[test]
fn the_gpu_diffuse_lobe_is_the_oracles() {
    let gpu = common::gpu();
    let cosines = [1e-3, 0.05, 0.3, 0.7, 1.0];
    let mut worst = 0.0f64;
    for key in ["model=tm2,max_layers=4", "model=tm6,max_layers=4"] {
        let variant: VariantKey = key.parse().unwrap();
        let oracle = VariantOracle::new(&gpu, variant).unwrap();
        let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
        for stack in stacks() {
            let want = oracle.evaluate(&stack, &cosines).unwrap();
            let got = evaluator.evaluate(&stack, &cosines).unwrap();
            for ((w, g), mu) in want.iter().zip(&got).zip(cosines) {
                let (w_lobe, g_lobe) = (w.lobes.last().unwrap(), g.lobes.last().unwrap());
                assert!(
                    w_lobe.diffuse && g_lobe.diffuse,
                    "{key} μ {mu}: the last lobe is diffuse"
                );
                for c in 0..3 {
                    let d = (w_lobe.weight[c] - g_lobe.weight[c]).abs();
                    let r = (w.reflectance[c] - g.reflectance[c]).abs();
                    worst = worst.max(d).max(r);
                    assert!(
                        d < 2e-4 && r < 2e-4,
                        "{key} {stack:?} μ {mu}: lobe {d:.2e}, R {r:.2e}"
                    );
                }
            }
        }
    }
    println!(
        "diffuse lobe and reflectance, GPU against the oracle: largest difference {worst:.1e}"
    );
    common::assert_validation_clean(&gpu);
}

#[test]
fn a_white_base_under_lossless_coats_returns_the_white_furnace() {
    let gpu = common::gpu();
    let lossless = [
        vec![base([1.0; 3])],
        vec![coat(1.5, 0.0), base([1.0; 3])],
        vec![coat(1.5, 0.2), coat(1.33, 0.5), base([1.0; 3])],
    ];
    for key in ["model=tm2,max_layers=4", "model=tm6,max_layers=4"] {
        for stack in &lossless {
            let bins = furnace::gpu(&gpu, key.parse().unwrap(), stack, 128, 12).unwrap();
            let (min, mean, max) = furnace::summary(&bins);
            println!(
                "{key}, {} layer(s): furnace min {min:.4} mean {mean:.4} max {max:.4}",
                stack.len()
            );
            assert!(max <= 1.0 + 2e-3, "{key} {stack:?}: energy gain, max {max}");
            assert!(min >= 0.98, "{key} {stack:?}: energy lost, min {min}");
        }
    }
    common::assert_validation_clean(&gpu);
}

/// The per-material modes take a diffuse base: every stack here renders under
/// `mode=specialized` as `mode=generic` does (the same arithmetic, the base known to be the
/// last layer), and under `mode=baked` (its table holds the base's Lambertian lobe, √α = −1)
/// within the table's interpolation between its samples (`baked::max_lobe_error`, ≤ 1e-3 of
/// R); `mode=specialized-values`, whose constants hold no albedo, refuses it by name.
#[test]
fn diffuse_bases_render_as_generic_under_specialized_and_baked() {
    use lamina::profile::bench::place_scene;
    use lamina::render::lights::Lighting;
    use lamina::render::scene::Scene;
    use lamina::render::{PassKey, Renderer, TargetFormat};
    use lamina::tables::environment::EnvDesc;
    use lamina::variant::Mode;

    let gpu = common::gpu();
    let desc = EnvDesc {
        face_size: 32,
        mip_count: 5,
        samples: 16,
    };
    let mut renderer =
        Renderer::with_target(&gpu, &common::studio(), desc, TargetFormat::Float).unwrap();
    let (w, h) = (32, 32);
    place_scene(&mut renderer, Scene::FullScreen, w, h).unwrap();
    let lighting = Lighting::default();
    let (mut worst_baked, mut worst_specialized) = (0.0f64, 0.0f64);
    for key in ["model=tm2,max_layers=4", "model=tm6,max_layers=4"] {
        let generic: VariantKey = key.parse().unwrap();
        for stack in stacks() {
            let mut image = |mode: Mode| {
                let variant = VariantKey { mode, ..generic };
                let pass = renderer
                    .prepare(&PassKey::uniform(variant, &stack, &lighting).unwrap())
                    .unwrap();
                renderer.render(&pass, &stack, w, h).unwrap().pixels
            };
            let want = image(Mode::Generic);
            let floor = 0.01 * common::mean_radiance(&want);
            let d = common::largest_relative(&want, &image(Mode::Baked), floor);
            worst_baked = worst_baked.max(d);
            assert!(d < 2e-3, "{key} {stack:?}: baked {d:.1e} from generic");
            let d = common::largest_relative(&want, &image(Mode::Specialized), floor);
            worst_specialized = worst_specialized.max(d);
            assert!(
                d < 1e-4,
                "{key} {stack:?}: specialized {d:.1e} from generic"
            );
            let values = VariantKey {
                mode: Mode::SpecializedValues,
                ..generic
            };
            let e = PassKey::uniform(values, &stack, &lighting)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("diffuse base")
                    && e.contains("mode=specialized-values")
                    && e.contains("mode=specialized,"),
                "{e}"
            );
        }
    }
    println!(
        "diffuse bases, largest relative difference from generic: specialized \
         {worst_specialized:.1e}, baked {worst_baked:.1e}"
    );
    common::assert_validation_clean(&gpu);
}
