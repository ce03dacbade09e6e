//! Analytic lights: the GPU's light term against the ggx baseline's and the f64 oracle's
//! (`model::light`), the white furnace over the hemisphere of light directions, and the axes
//! (ndf, g2) that only a light makes visible.

use crate::common;

use glam::DVec3;
use lamina::material::Stack;
use lamina::model::fgd::ExactFgd;
use lamina::model::light::{self, lobe_quadrature, lobe_view, LightShading, LitLobes, LobeKind};
use lamina::model::{oracle, Fgd, LayerParams};
use lamina::render::eval::GpuEvaluator;
use lamina::render::lights::{Light, LightKind, Lighting};
use lamina::render::{Renderer, TargetFormat};
use lamina::tables::environment::EnvDesc;
use lamina::variant::{Ndf, VariantKey, G2};

fn small_env() -> EnvDesc {
    EnvDesc {
        face_size: 64,
        mip_count: 5,
        samples: 16,
    }
}

fn key(text: &str) -> VariantKey {
    text.parse().unwrap()
}

fn preset(name: &str) -> Vec<LayerParams> {
    Stack::resolve(name).unwrap().params()
}

/// A key light from the upper left and a point light to the right, no environment.
fn lights_only() -> Lighting {
    Lighting {
        environment: 0.0,
        lights: vec![
            Light {
                kind: LightKind::Directional {
                    direction: DVec3::new(-0.5, 0.8, 0.6).normalize().to_array(),
                    angular_radius: 0.0,
                },
                color: [1.0, 0.9, 0.8],
                intensity: 2.0,
            },
            Light {
                kind: LightKind::Point {
                    position: [2.5, 0.5, 2.0],
                },
                color: [1.0; 3],
                intensity: 8.0,
            },
        ],
    }
}

/// Renders `layers` under `variant` into a float target.
fn render(
    renderer: &mut Renderer<'_>,
    variant: VariantKey,
    layers: &[LayerParams],
) -> Vec<[f32; 4]> {
    let pass = renderer.prepare_uniform(variant, layers).unwrap();
    renderer.render(&pass, layers, 96, 64).unwrap().pixels
}

#[test]
fn a_single_conductor_under_lights_is_the_ggx_baseline() {
    let gpu = common::gpu();
    let mut renderer =
        Renderer::with_target(&gpu, &common::studio(), small_env(), TargetFormat::Float).unwrap();
    renderer.lighting = lights_only();
    let gold = common::gold();
    let ggx = render(&mut renderer, key("model=ggx"), &gold);
    let mut lit = 0;
    for variant in [
        "model=tm2,fgd=karis",
        "model=tm2,fgd=karis,mode=specialized",
    ] {
        let tm = render(&mut renderer, key(variant), &gold);
        let mut worst: f64 = 0.0;
        for (a, b) in tm.iter().zip(&ggx) {
            for c in 0..3 {
                let (a, b) = (f64::from(a[c]), f64::from(b[c]));
                worst = worst.max((a - b).abs() / b.abs().max(1.0));
            }
        }
        lit = ggx.iter().filter(|p| p[0] > 1e-3).count();
        println!("{variant}: largest difference from ggx {worst:.2e} (relative above 1)");
        assert!(worst <= 1e-4, "{variant}: {worst}");
    }
    assert!(lit > 500, "only {lit} lit pixels");
    common::assert_validation_clean(&gpu);
}

#[test]
fn ndf_and_g2_change_the_image_only_where_a_light_falls() {
    let gpu = common::gpu();
    let mut renderer =
        Renderer::with_target(&gpu, &common::studio(), small_env(), TargetFormat::Float).unwrap();
    let layers = preset("varnished-gold");
    let base = key("model=tm2,fgd=karis");
    // The environment alone evaluates no D: the ndf axis changes nothing.
    let env_ggx = render(&mut renderer, base, &layers);
    let env_karis = render(
        &mut renderer,
        VariantKey {
            ndf: Ndf::Karis,
            ..base
        },
        &layers,
    );
    assert_eq!(env_ggx, env_karis, "ndf changed an image without lights");

    renderer.lighting = lights_only();
    let reference = render(&mut renderer, base, &layers);
    let lit: Vec<bool> = reference
        .iter()
        .map(|p| p[..3].iter().any(|&c| c > 0.0))
        .collect();
    let lit_count = lit.iter().filter(|&&l| l).count();
    assert!(lit_count > 500, "{lit_count} lit pixels");
    let alternatives = [
        VariantKey {
            ndf: Ndf::Karis,
            ..base
        },
        VariantKey {
            g2: G2::Smith,
            ..base
        },
        VariantKey {
            g2: G2::Schlick,
            ..base
        },
        VariantKey {
            g2: G2::Earl,
            ..base
        },
    ];
    for variant in alternatives {
        let image = render(&mut renderer, variant, &layers);
        let mut changed = 0;
        for (i, (a, b)) in image.iter().zip(&reference).enumerate() {
            if a != b {
                assert!(lit[i], "{variant}: pixel {i} changed where no light falls");
                changed += 1;
            }
        }
        println!("{variant}: {changed} of {lit_count} lit pixels changed");
        assert!(
            changed > lit_count / 10,
            "{variant}: {changed} of {lit_count} lit pixels changed"
        );
    }
    common::assert_validation_clean(&gpu);
}

/// One lobe's integral over the hemisphere of light directions, by the GPU and by the oracle,
/// and what it should be: the lobe's weight, or for the top's Fresnel lobe (`transport=
/// corrected`) its weight times the interface's exact albedo E_F at the shading roughness over
/// the albedo A the model normalised it by (1 where the model's FGD is exact).
struct Furnace {
    gpu: [f64; 3],
    oracle: [f64; 3],
    weight: [f64; 3],
    expected: [f64; 3],
    gpu_weight: [f64; 3],
    kind: LobeKind,
    alpha: f64,
    /// The top's Fresnel lobe.
    fresnel: bool,
    /// The largest difference between the GPU's and the oracle's response at one light
    /// direction, over the oracle's largest response (mean of RGB): the lobes' shapes agree.
    shape: f64,
}

/// For each lobe of `layers` at view cosine `mu`: its light response integrated over the
/// hemisphere of light directions (a quadrature adapted to the lobe), on the GPU and with the
/// f64 oracle, beside the lobe's weight from the oracle's model (with the GPU's tables, so
/// the model's arithmetic is all that differs).
fn furnace(
    evaluator: &GpuEvaluator<'_>,
    layers: &[LayerParams],
    mu: f64,
    radius: f64,
) -> Vec<Furnace> {
    let variant = evaluator.variant;
    let fgd = evaluator.fgd_lookup();
    let tir = evaluator.tir_lookup();
    let oracle = oracle::evaluate_variant(variant, layers, &[mu], &fgd, tir.as_ref()).remove(0);
    let plain = evaluator.evaluate_lobes(layers, &[mu]).unwrap().remove(0);
    let retro = plain.evaluation.retro_mask;
    assert_eq!(oracle.retro_mask, retro, "the CPU model's lobe kinds");
    match (oracle.top_fresnel, plain.evaluation.top_fresnel) {
        (None, None) => {}
        (Some(cpu), Some(gpu)) => {
            assert!((cpu.eta - gpu.eta).abs() < 1e-6, "{cpu:?} vs {gpu:?}");
            assert!((cpu.albedo - gpu.albedo).abs() < 1e-4, "{cpu:?} vs {gpu:?}");
        }
        (cpu, gpu) => panic!("the top's Fresnel lobe: CPU {cpu:?}, GPU {gpu:?}"),
    }
    let shading = LightShading {
        g2: variant.g2,
        ndf: variant.ndf,
        fp16: variant.fp16,
        angular_radius: radius,
    };
    let lit_lobes = LitLobes::new(shading, &oracle, retro, mu);
    let mut out = Vec::new();
    for (k, lobe) in oracle.lobes.iter().enumerate() {
        if lobe.weight.iter().all(|&w| w < 1e-4) {
            continue;
        }
        let kind = if retro & (1 << k) != 0 {
            LobeKind::Retro
        } else {
            LobeKind::Mirror
        };
        let alpha = light::shading_alpha(lobe.roughness, radius, variant.fp16);
        let scale = match oracle.top_fresnel {
            Some(top) if k == 0 => {
                ExactFgd::new(variant.g2).fgd(mu, alpha, top.eta, 0.0) / top.albedo
            }
            _ => 1.0,
        };
        let points: Vec<(DVec3, f64)> = lobe_quadrature(mu, alpha, 96)
            .into_iter()
            .map(|(l, w)| (lobe_view(l, kind), w))
            .collect();
        let samples: Vec<(f64, DVec3)> = points.iter().map(|&(l, _)| (mu, l)).collect();
        let lit = evaluator.evaluate_lit(layers, &samples, radius).unwrap();
        let mut gpu = [0.0; 3];
        let mut cpu = [0.0; 3];
        let (mut largest, mut apart) = (0.0_f64, 0.0_f64);
        let mean = |v: [f64; 3]| (v[0] + v[1] + v[2]) / 3.0;
        for (&(l, w), result) in points.iter().zip(&lit) {
            let term = result.evaluation.lobes[k].weight;
            let oracle_term = lit_lobes.terms(l)[k];
            for c in 0..3 {
                gpu[c] += w * term[c];
                cpu[c] += w * oracle_term[c];
            }
            largest = largest.max(mean(oracle_term));
            apart = apart.max((mean(term) - mean(oracle_term)).abs());
        }
        out.push(Furnace {
            gpu,
            oracle: cpu,
            weight: lobe.weight,
            expected: lobe.weight.map(|w| w * scale),
            gpu_weight: plain.evaluation.lobes[k].weight,
            kind,
            alpha,
            fresnel: oracle.top_fresnel.is_some_and(|t| t.lobe == k),
            shape: apart / largest.max(1e-12),
        });
    }
    out
}

#[test]
fn a_light_only_furnace_integrates_to_the_lobe_weights() {
    let gpu = common::gpu();
    let cases = [
        ("model=tm2", "gold"),
        ("model=tm2", "varnished-gold"),
        ("model=tm2", "lacquered-copper"),
        ("model=tm6", "dusty-varnish"),
        ("model=tm2,g2=smith", "gold"),
        ("model=tm2,g2=schlick", "varnished-gold"),
        ("model=tm2,g2=earl", "gold"),
        ("model=tm2,ndf=karis", "gold"),
        ("model=tm2,transport=corrected,fgd=4d", "varnished-gold"),
        ("model=tm2,transport=corrected", "lacquered-copper"),
        ("model=tm6,transport=corrected", "dusty-varnish"),
    ];
    let mut worst_gpu: f64 = 0.0;
    let mut worst_oracle: f64 = 0.0;
    let mut worst_shape: f64 = 0.0;
    let mut lobes = 0;
    let mut fresnel = 0;
    for (variant, material) in cases {
        let evaluator = GpuEvaluator::new(&gpu, key(variant)).unwrap();
        let layers = preset(material);
        for mu in [0.25, 0.6, 0.95] {
            for f in furnace(&evaluator, &layers, mu, 0.0) {
                lobes += 1;
                fresnel += usize::from(f.fresnel);
                worst_shape = worst_shape.max(f.shape);
                assert!(
                    f.shape <= 0.02,
                    "{variant} {material} μ={mu}: {:?} α={} (Fresnel: {}): the GPU's response \
                     is {:.1} % of the peak away from the oracle's",
                    f.kind,
                    f.alpha,
                    f.fresnel,
                    100.0 * f.shape
                );
                for c in 0..3 {
                    let gpu_error = (f.gpu[c] - f.expected[c]).abs();
                    let oracle_error = (f.oracle[c] - f.expected[c]).abs();
                    worst_gpu = worst_gpu.max(gpu_error);
                    worst_oracle = worst_oracle.max(oracle_error);
                    assert!(
                        gpu_error <= 1e-3 && oracle_error <= 1e-3,
                        "{variant} {material} μ={mu}: {:?} α={} weight {:?} (expected {:?}, \
                         GPU {:?}), GPU {:?}, oracle {:?}",
                        f.kind,
                        f.alpha,
                        f.weight,
                        f.expected,
                        f.gpu_weight,
                        f.gpu,
                        f.oracle
                    );
                }
            }
        }
    }
    println!(
        "{lobes} lobes ({fresnel} the top's Fresnel lobe): |∫ light term − lobe weight| at \
         most {worst_gpu:.2e} (GPU), {worst_oracle:.2e} (oracle); responses apart by at most \
         {:.2} % of the peak",
        100.0 * worst_shape
    );
    assert!(lobes >= 20, "{lobes} lobes");
    assert!(fresnel >= 9, "{fresnel} Fresnel lobes");
    common::assert_validation_clean(&gpu);
}

#[test]
fn a_disk_light_spreads_the_highlight_and_keeps_its_energy() {
    let gpu = common::gpu();
    let evaluator = GpuEvaluator::new(&gpu, key("model=tm2")).unwrap();
    let layers = common::gold();
    let mu: f64 = 0.7;
    let mirror = DVec3::new(-(1.0 - mu * mu).sqrt(), 0.0, mu);
    let at_peak = |radius: f64| {
        evaluator
            .evaluate_lit(&layers, &[(mu, mirror)], radius)
            .unwrap()[0]
            .evaluation
            .lobes[0]
            .weight[0]
    };
    let sharp = at_peak(0.0);
    let radius = 20_f64.to_radians();
    let wide = at_peak(radius);
    // The disk-averaged GGX peak falls to α² / (α² + w²), w = tan(θ_r/2) (model::light): 0.56
    // for gold's α = 0.2 under a 20° disk. G2 at the widened α moves it by a little.
    let (alpha, w) = (layers[0].roughness, (0.5 * radius).tan());
    let fall = alpha * alpha / (alpha * alpha + w * w);
    assert!(
        (wide / sharp / fall - 1.0).abs() < 0.05,
        "peak {sharp} → {wide} under a 20° disk, {} of it where the disk's mean is {fall}",
        wide / sharp
    );
    for f in furnace(&evaluator, &layers, mu, radius) {
        for c in 0..3 {
            assert!(
                (f.gpu[c] - f.expected[c]).abs() <= 1e-3,
                "{:?} vs {:?}",
                f.gpu,
                f.weight
            );
        }
    }
    common::assert_validation_clean(&gpu);
}
