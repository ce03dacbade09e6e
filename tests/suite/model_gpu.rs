//! The transfer-matrix shaders on the GPU: identities that need no CPU oracle.

use crate::common;

use lamina::model::LayerParams;
use lamina::render::eval::GpuEvaluator;
use lamina::render::furnace;
use lamina::render::Renderer;
use lamina::tables::environment::EnvDesc;

fn small_env() -> EnvDesc {
    EnvDesc {
        face_size: 64,
        mip_count: 5,
        samples: 16,
    }
}

/// A single conductor layer is plain GGX: the 2-flux and 6-flux renders equal the baseline's.
/// The lobe's α goes through the α → g → α round trip of the model (pow in f32), so a few
/// pixels may land one half-float step away; nothing more is allowed.
#[test]
fn single_conductor_renders_exactly_like_the_ggx_baseline() {
    let gpu = common::gpu();
    let mut renderer = Renderer::new(&gpu, &common::studio(), small_env()).unwrap();
    let stack = common::gold();
    let render = |renderer: &mut Renderer, key: &str| {
        let pass = renderer
            .prepare_uniform(key.parse().unwrap(), &stack)
            .unwrap();
        renderer.render(&pass, &stack, 128, 96).unwrap().pixels
    };
    let ggx = render(&mut renderer, "model=ggx");
    for model in ["model=tm2", "model=tm6"] {
        let tm = render(&mut renderer, model);
        let mut differing = 0;
        for (&a, &b) in ggx.iter().flatten().zip(tm.iter().flatten()) {
            if a != b {
                differing += 1;
                let step = a.abs().max(b.abs()) * 2f32.powi(-10);
                assert!((a - b).abs() <= step, "{model}: {a} vs {b}");
            }
        }
        println!("{model}: {differing} channel values one half-float step from ggx");
        assert!(
            differing * 1000 < ggx.len() * 4,
            "{model}: {differing} values differ"
        );
    }
    common::assert_validation_clean(&gpu);
}

/// Lossless dielectric stacks: R + T = 1 (no TIR correction), in both models.
#[test]
fn dielectric_stacks_conserve_energy_on_the_gpu() {
    let gpu = common::gpu();
    let coat = LayerParams::dielectric;
    let stacks = [
        vec![coat(1.5, 0.1)],
        vec![coat(1.5, 0.3), coat(1.2, 0.05)],
        vec![coat(1.33, 0.2), coat(1.8, 0.4), coat(1.5, 0.1)],
    ];
    let cosines: Vec<f64> = (1..=20).map(|i| f64::from(i) / 20.0).collect();
    let mut worst = 0.0f64;
    for model in ["model=tm2", "model=tm6"] {
        let evaluator = GpuEvaluator::new(&gpu, model.parse().unwrap()).unwrap();
        for stack in &stacks {
            for e in evaluator.evaluate(stack, &cosines).unwrap() {
                for c in 0..3 {
                    let total = e.reflectance[c] + e.transmittance[c];
                    worst = worst.max((total - 1.0).abs());
                }
            }
        }
    }
    println!("max |R + T − 1| = {worst:.2e}");
    assert!(worst < 1e-5, "{worst}");
    common::assert_validation_clean(&gpu);
}

/// White furnace: a lossless coat reflects at most what arrives, within 0.5%.
#[test]
fn furnace_shows_no_energy_gain_for_lossless_stacks() {
    let gpu = common::gpu();
    let coat = LayerParams::dielectric(1.5, 0.2);
    for model in ["model=tm2", "model=tm6"] {
        let bins = furnace::gpu(&gpu, model.parse().unwrap(), &[coat], 128, 12).unwrap();
        let (min, mean, max) = furnace::summary(&bins);
        println!("{model}: furnace min {min:.4} mean {mean:.4} max {max:.4}");
        assert!(max <= 1.005, "{model}: energy gain, max {max}");
        assert!(min > 0.0);
    }
    common::assert_validation_clean(&gpu);
}

/// Every preset renders at 256×256 in tm2 and tm6 with no NaN/Inf pixel (the sheet renderer
/// refuses non-finite pixels) and no validation message.
#[test]
fn every_preset_renders_in_tm2_and_tm6() {
    use lamina::material::{presets, Stack};
    use lamina::render::sheet;
    use lamina::variant::VariantKey;

    let gpu = common::gpu();
    let rows: Vec<sheet::SheetRow> = presets()
        .iter()
        .map(|p| {
            let stack = Stack::load(p).unwrap();
            sheet::SheetRow {
                name: stack.name.clone(),
                layers: stack.params(),
                surface: stack.surface.clone(),
            }
        })
        .collect();
    assert!(rows.len() >= 8);
    let columns: Vec<sheet::Column> = ["model=tm2,max_layers=5", "model=tm6,max_layers=5"]
        .iter()
        .map(|k| sheet::Column {
            label: (*k).to_owned(),
            variant: k.parse::<VariantKey>().unwrap(),
        })
        .collect();
    let (w, h, _) = sheet::render(
        &gpu,
        &common::studio(),
        &rows,
        &columns,
        256,
        0.0,
        &Default::default(),
    )
    .unwrap();
    assert!(w > 512 && h > 256 * rows.len());
    common::assert_validation_clean(&gpu);
}
