//! The reference against exact answers: Fresnel, the adding equations of smooth coats,
//! Beer–Lambert, energy conservation, the FGD of a single rough interface and the closed form
//! of a smooth coat over a Lambertian base. Every bound is a number of standard errors the
//! run itself reports (4σ: a correct walk fails one check in about 16 000), plus the
//! quadrature error of the exact side where it has one.

use std::sync::atomic::AtomicBool;

use super::*;
use crate::model::fgd::ExactFgd;
use crate::model::tm2::tests::{coat, gold};
use crate::model::{diffuse, fresnel, Fgd};
use crate::variant::Interfaces;
use crate::variant::VariantKey;

fn run(layers: &[LayerParams], media: bool, g2: G2, mu: f64, paths: u64) -> Reference {
    run_in(Interfaces::Single, layers, media, g2, mu, paths)
}

fn run_in(
    interfaces: Interfaces,
    layers: &[LayerParams],
    media: bool,
    g2: G2,
    mu: f64,
    paths: u64,
) -> Reference {
    let settings = Settings {
        paths,
        seed: 0x5eed,
        g2,
        interfaces,
        media,
    };
    simulate(layers, &settings, mu, &mut |_| {}, &AtomicBool::new(false))
        .expect("valid settings")
        .expect("not stopped")
}

/// |estimate − exact| ≤ 4 standard errors + `slack` in every channel.
fn agrees(what: &str, estimate: &Estimate, exact: [f64; 3], slack: f64) {
    for (c, exact) in exact.iter().enumerate() {
        let (got, se) = (estimate.mean[c], estimate.std_error[c]);
        assert!(
            (got - exact).abs() <= 4.0 * se + slack,
            "{what}, channel {c}: {got} ± {se} against {exact}"
        );
    }
}

/// Cosine of the refracted direction for incidence cosine μ into relative IOR η > 1.
fn refracted(mu: f64, eta: f64) -> f64 {
    (1.0 - (1.0 - mu * mu) / (eta * eta)).sqrt()
}

#[test]
fn a_smooth_interface_reflects_fresnel() {
    for mu in [1.0, 0.5, 0.15] {
        let r = run(&[coat(1.5, 0.0)], false, G2::Smith, mu, 20_000);
        let f = fresnel::dielectric(mu, 1.5);
        agrees("R", &r.reflectance, [f; 3], 0.0);
        agrees("T", &r.transmittance, [1.0 - f; 3], 0.0);
    }
}

#[test]
fn smooth_coats_over_a_conductor_follow_the_adding_equations() {
    // Two smooth coats (1.5, then 2.0) over smooth gold: add from the bottom up, with the
    // symmetric Fresnel of each interface at its pair of angles.
    let stack = [coat(1.5, 0.0), coat(2.0, 0.0), gold(0.0)];
    let gold_ior = stack[2].ior;
    let gold_kappa = stack[2].kappa;
    for mu in [0.9, 0.35] {
        let mu1 = refracted(mu, 1.5);
        let mu2 = refracted(mu1, 2.0 / 1.5);
        let exact = std::array::from_fn(|c| {
            let base = fresnel::conductor(mu2, gold_ior[c] / 2.0, gold_kappa[c] / 2.0);
            let r1 = fresnel::dielectric(mu1, 2.0 / 1.5);
            let below = r1 + (1.0 - r1).powi(2) * base / (1.0 - r1 * base);
            let r0 = fresnel::dielectric(mu, 1.5);
            r0 + (1.0 - r0).powi(2) * below / (1.0 - r0 * below)
        });
        let r = run(&stack, false, G2::Smith, mu, 20_000);
        agrees("R", &r.reflectance, exact, 0.0);
        assert_eq!(r.transmittance.mean, [0.0; 3]);
    }
}

#[test]
fn an_absorbing_medium_follows_beer_lambert() {
    let film = LayerParams {
        depth: 0.5,
        sigma_a: [0.2, 1.0, 3.0],
        ..coat(1.5, 0.0)
    };
    for mu in [1.0, 0.3] {
        let f = fresnel::dielectric(mu, 1.5);
        let mu_t = refracted(mu, 1.5);
        let r = run(&[film], true, G2::Smith, mu, 20_000);
        agrees("R", &r.reflectance, [f; 3], 0.0);
        let exact = film
            .sigma_a
            .map(|s| (1.0 - f) * (-s * film.depth / mu_t).exp());
        agrees("T", &r.transmittance, exact, 0.0);
        // Over gold, light crosses the film twice per round trip.
        let over_gold = [film, gold(0.0)];
        let exact = std::array::from_fn(|c| {
            let a2 = (-2.0 * film.sigma_a[c] * film.depth / mu_t).exp();
            let base = fresnel::conductor(mu_t, gold(0.0).ior[c] / 1.5, gold(0.0).kappa[c] / 1.5);
            f + (1.0 - f).powi(2) * base * a2 / (1.0 - f * base * a2)
        });
        let r = run(&over_gold, true, G2::Smith, mu, 20_000);
        agrees("R over gold", &r.reflectance, exact, 0.0);
    }
}

#[test]
fn a_smooth_lossless_slab_conserves_energy() {
    // Smooth interfaces and media that scatter without absorbing lose nothing: every path
    // leaves above or below, so R + T + unresolved is 1 up to rounding.
    let stack = [
        LayerParams {
            depth: 1.0,
            sigma_s: [2.0, 0.5, 8.0],
            g: 0.6,
            ..coat(1.5, 0.0)
        },
        LayerParams {
            depth: 0.5,
            sigma_s: [1.0; 3],
            g: -0.3,
            ..coat(1.3, 0.0)
        },
    ];
    for mu in [1.0, 0.4, 0.05] {
        let r = run(&stack, true, G2::Smith, mu, 5_000);
        for c in 0..3 {
            let sum = r.reflectance.mean[c] + r.transmittance.mean[c] + r.unresolved[c];
            assert!(
                (sum - 1.0).abs() < 1e-9,
                "μ {mu}, channel {c}: R + T = {sum}"
            );
        }
        // The media do scatter light back: more than the top interface's Fresnel alone.
        assert!(r.reflectance.mean[2] > fresnel::dielectric(mu, 1.5) + 0.05);
    }
}

#[test]
fn a_rough_interface_reflects_its_fgd() {
    for g2 in [G2::HeightCorrelated, G2::Smith] {
        let fgd = ExactFgd::new(g2);
        for (mu, alpha) in [(0.9, 0.3), (0.3, 0.6)] {
            let r = run(&[gold(alpha)], false, g2, mu, 20_000);
            let exact =
                std::array::from_fn(|c| fgd.fgd(mu, alpha, gold(0.0).ior[c], gold(0.0).kappa[c]));
            // ExactFgd's midpoint rule is good to 1e-3 (model::fgd).
            agrees("conductor R", &r.reflectance, exact, 1e-3);
            let r = run(&[coat(1.5, alpha)], false, g2, mu, 20_000);
            let exact = fgd.fgd(mu, alpha, 1.5, 0.0);
            agrees("dielectric R", &r.reflectance, [exact; 3], 1e-3);
            // Single scattering loses light through the rough interface: R + T < 1.
            let lost = 1.0 - r.reflectance.mean[0] - r.transmittance.mean[0];
            assert!(
                lost > 4.0 * r.transmittance.std_error[0],
                "{g2:?} μ {mu}: {lost}"
            );
        }
    }
}

#[test]
fn a_smooth_coat_over_a_lambertian_base_is_the_closed_form() {
    let n = 1.5;
    let rho = [0.2, 0.5, 0.9];
    let base = LayerParams {
        diffuse: Some(rho),
        ..coat(1.0, 0.0)
    };
    // Light leaving the base escapes unless the coat reflects it; inside, the coat reflects
    // 1 − (1 − F̄)/n² of a diffuse flux (F̄: its hemispherical average from outside).
    let inside = 1.0 - (1.0 - diffuse::fresnel_hemispherical(n)) / (n * n);
    for mu in [1.0, 0.5, 0.1] {
        let f = fresnel::dielectric(mu, n);
        let exact = rho.map(|p| f + (1.0 - f) * p * (1.0 - inside) / (1.0 - p * inside));
        let r = run(&[coat(n, 0.0), base], false, G2::Smith, mu, 20_000);
        agrees("R", &r.reflectance, exact, 1e-4);
    }
}

#[test]
fn the_slice_and_the_hemisphere_hold_the_reflected_energy() {
    // Σ BRDF · projected solid angle over the hemisphere is R; a glossy conductor's slice
    // peaks at the mirror direction (within a bin: a rough lobe's peak moves off-specular).
    let r = run(&[gold(0.1)], false, G2::HeightCorrelated, 0.7, 20_000);
    for c in 0..3 {
        let sum: f64 = r
            .hemisphere
            .iter()
            .map(|e| e.mean[c] * hemisphere_projected_solid_angle())
            .sum();
        assert!((sum - r.reflectance.mean[c]).abs() < 1e-9);
    }
    let peak = (0..SLICE_BINS)
        .max_by(|&a, &b| r.slice[a].mean[0].total_cmp(&r.slice[b].mean[0]))
        .expect("bins");
    let (lo, hi) = slice_bin_edges(peak);
    let mirror = 0.7_f64.acos();
    let step = hi - lo;
    assert!(
        lo - step <= mirror && mirror <= hi + step,
        "peak at [{lo}, {hi}]"
    );
}

#[test]
fn a_seed_gives_the_same_numbers_on_any_number_of_threads() {
    let stack = [
        LayerParams {
            depth: 0.3,
            sigma_s: [1.0, 2.0, 3.0],
            sigma_a: [0.1; 3],
            g: 0.5,
            ..coat(1.5, 0.2)
        },
        gold(0.4),
    ];
    let on = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
            .install(|| run(&stack, true, G2::HeightCorrelated, 0.6, 3_000))
    };
    assert_eq!(on(1), on(2));
}

#[test]
fn settings_out_of_range_are_refused() {
    let stop = AtomicBool::new(false);
    for paths in [0, MAX_PATHS + 1] {
        let settings = Settings {
            paths,
            seed: 1,
            g2: G2::Smith,
            interfaces: Interfaces::Single,
            media: false,
        };
        let err = simulate(&[gold(0.1)], &settings, 0.5, &mut |_| {}, &stop).unwrap_err();
        assert!(err.to_string().contains("--paths"), "{err}");
    }
    let settings = Settings {
        paths: 10,
        seed: 1,
        g2: G2::Smith,
        interfaces: Interfaces::Single,
        media: false,
    };
    for mu in [0.0, 1.5, f64::NAN] {
        assert!(simulate(&[gold(0.1)], &settings, mu, &mut |_| {}, &stop).is_err());
    }
    // A stop before the first batch returns nothing.
    let stopped = AtomicBool::new(true);
    assert!(
        simulate(&[gold(0.1)], &settings, 0.5, &mut |_| {}, &stopped)
            .unwrap()
            .is_none()
    );
}

#[test]
fn the_model_meets_the_reference_where_it_is_exact() {
    // Smooth coats over a smooth grey conductor: the transfer-matrix model is the adding
    // equations there, and both put every reflected path in the mirror direction's bin. (Over
    // gold the model widens its base lobe: its asymmetry products average the channels.)
    let grey = LayerParams {
        ior: [0.2; 3],
        kappa: [3.0; 3],
        ..coat(1.0, 0.0)
    };
    let stack = [coat(1.5, 0.0), coat(2.0, 0.0), grey];
    let variant = VariantKey::default();
    let stop = AtomicBool::new(false);
    // Mirror directions at bins' centres (25°, 67°): the model's lobes (α ≥ MIN_ALPHA) are
    // narrow, not deltas.
    let cosines = [25f64.to_radians().cos(), 67f64.to_radians().cos()];
    let m = compare::compare(
        "smooth",
        &stack,
        variant,
        Interfaces::Single,
        &cosines,
        (20_000, 3),
        &mut |_| {},
        &stop,
    )
    .unwrap()
    .unwrap();
    for row in &m.rows {
        let r = (row.reference.mean[0] + row.reference.mean[1] + row.reference.mean[2]) / 3.0;
        let se = row
            .reference
            .std_error
            .iter()
            .fold(0.0f64, |a, &b| a.max(b));
        assert!(
            row.relative_error().abs() <= 4.0 * se / r,
            "μ {}: {}",
            row.cos_theta,
            row.relative_error()
        );
        // What GGX at the model's floor α puts beyond the peak bin (half vectors more than
        // half a bin, 0.5°, off the normal: α²/(α² + tan² 0.5°) of them), missing from the
        // peak and present elsewhere.
        let a2 = crate::model::light::MIN_ALPHA.powi(2);
        let tail = a2 / (a2 + 0.5f64.to_radians().tan().powi(2));
        let (slice, noise) = row.slice_error();
        assert!(
            slice <= 2.0 * (noise + tail),
            "μ {}: slice {slice}, noise {noise}, tail {tail}",
            row.cos_theta
        );
    }
}

#[test]
fn the_model_slice_bins_each_lobe() {
    // Under an index-matched coat a diffuse base's lobe is all there is: ρ/π in every bin.
    let base = LayerParams {
        diffuse: Some([0.5, 0.3, 0.1]),
        ..coat(1.0, 0.0)
    };
    let fgd = ExactFgd::new(G2::HeightCorrelated);
    let variant = VariantKey::default();
    let e = crate::model::tm2::evaluate(&[coat(1.0, 0.3), base], 0.6, &fgd, &crate::model::NoTir);
    for bin in super::slice::model_slice(&e, 0.6, variant) {
        for c in 0..3 {
            let want = [0.5, 0.3, 0.1][c] / std::f64::consts::PI;
            assert!((bin[c] - want).abs() < 1e-12, "{} vs {want}", bin[c]);
        }
    }
    // A glossy lobe peaks in the mirror direction's bin.
    let e = crate::model::tm2::evaluate(&[gold(0.05)], 0.6, &fgd, &crate::model::NoTir);
    let slice = super::slice::model_slice(&e, 0.6, variant);
    let peak = (0..SLICE_BINS)
        .max_by(|&a, &b| slice[a][0].total_cmp(&slice[b][0]))
        .expect("bins");
    let (lo, hi) = slice_bin_edges(peak);
    assert!(
        lo <= 0.6_f64.acos() && 0.6_f64.acos() <= hi,
        "peak at [{lo}, {hi}]"
    );
}

#[test]
fn a_lossless_rough_slab_reflects_and_transmits_everything_in_multiple() {
    // Rough interfaces walked on their microsurface lose nothing: a glass slab in air (two
    // rough interfaces, one seen from inside), and a slab under a second, index-mismatched
    // coat, reflect and transmit all the light, R + T + unresolved = 1 up to rounding, at
    // any roughness and angle.
    for alpha in [0.05, 0.5, 1.0] {
        let slab = [coat(1.5, alpha), coat(1.0, alpha)];
        let coated = [coat(1.3, 0.2), coat(1.8, alpha), coat(1.0, 0.7)];
        for stack in [&slab[..], &coated[..]] {
            for mu in [1.0, 0.4, 0.05] {
                let r = run_in(
                    Interfaces::Multiple,
                    stack,
                    false,
                    G2::HeightCorrelated,
                    mu,
                    4_000,
                );
                for c in 0..3 {
                    let sum = r.reflectance.mean[c] + r.transmittance.mean[c] + r.unresolved[c];
                    assert!((sum - 1.0).abs() < 1e-9, "α {alpha}, μ {mu}: R + T = {sum}");
                }
                // What the interfaces did: nothing lost at any of them.
                for row in &r.flows {
                    assert!(row.flow.lost.iter().all(|l| l.abs() < 1e-12), "{row:?}");
                }
            }
        }
    }
}

#[test]
fn both_interface_modes_agree_as_roughness_vanishes() {
    let stack = [coat(1.5, 1e-3), coat(1.2, 1e-3), gold(1e-3)];
    for mu in [0.9, 0.3] {
        let single = run_in(
            Interfaces::Single,
            &stack,
            false,
            G2::HeightCorrelated,
            mu,
            40_000,
        );
        let multiple = run_in(
            Interfaces::Multiple,
            &stack,
            false,
            G2::HeightCorrelated,
            mu,
            40_000,
        );
        for c in 0..3 {
            let (a, b) = (single.reflectance, multiple.reflectance);
            let se = a.std_error[c].hypot(b.std_error[c]);
            assert!(
                (a.mean[c] - b.mean[c]).abs() <= 4.0 * se,
                "μ {mu}, channel {c}: single {} multiple {} ± {se}",
                a.mean[c],
                b.mean[c]
            );
        }
    }
    // …and part as it grows: the microsurface keeps what single scattering's masking loses.
    let rough = [coat(1.5, 0.5), gold(0.6)];
    let single = run_in(
        Interfaces::Single,
        &rough,
        false,
        G2::HeightCorrelated,
        0.5,
        20_000,
    );
    let multiple = run_in(
        Interfaces::Multiple,
        &rough,
        false,
        G2::HeightCorrelated,
        0.5,
        20_000,
    );
    assert!(multiple.reflectance.mean[0] > single.reflectance.mean[0] + 0.05);
}

#[test]
fn the_flows_of_a_smooth_coat_over_a_lambertian_base_are_the_closed_form() {
    // Top interface from above, first arrival: everything arrives, F(μ) is sent back. The
    // base's first arrival is 1 − F(μ), of which ρ comes back up; from below, every arrival
    // at the interface is diffuse light, of which the coat sends back K = 1 − (1 − F̄)/n².
    let n = 1.5;
    let rho = [0.2, 0.5, 0.9];
    let base = LayerParams {
        diffuse: Some(rho),
        ..coat(1.0, 0.0)
    };
    let k = 1.0 - (1.0 - diffuse::fresnel_hemispherical(n)) / (n * n);
    let mu = 0.6;
    let f = fresnel::dielectric(mu, n);
    let paths = 40_000.0;
    let r = run(&[coat(n, 0.0), base], false, G2::Smith, mu, paths as u64);
    let row = |b: usize, from: flows::Side, order: &str| {
        r.flows
            .iter()
            .find(|row| row.boundary == b && row.from == from && row.order == order)
            .unwrap_or_else(|| panic!("no row {b} {from:?} {order}"))
            .flow
    };
    // A share p of N Bernoulli arrivals has standard error √(p(1−p)/N).
    let share = |what: &str, got: f64, arriving: f64, p: f64| {
        let se = (p * (1.0 - p) / (arriving * paths)).sqrt();
        assert!(
            (got / arriving - p).abs() <= 4.0 * se,
            "{what}: {} against {p}",
            got / arriving
        );
    };
    for (c, &rho) in rho.iter().enumerate() {
        let top = row(0, flows::Side::Above, "1");
        assert_eq!(top.arriving[c], 1.0);
        share("top, sent back", top.sent_back[c], 1.0, f);
        let base = row(1, flows::Side::Above, "1");
        share("base, first arrival", base.arriving[c], 1.0, 1.0 - f);
        assert!((base.sent_back[c] - rho * base.arriving[c]).abs() < 1e-9);
        for order in ["1", "2"] {
            let up = row(0, flows::Side::Below, order);
            share("inside, sent back", up.sent_back[c], up.arriving[c], k);
            assert_eq!(up.lost[c], 0.0);
        }
    }
}

#[test]
fn discrete_ordinates_meet_the_walk_in_both_interface_modes() {
    // The same interfaces and media composed over 48 bins of μ instead of followed path by
    // path (model::angular): R within 4 standard errors plus 2 % (the bins' resolution; on
    // every preset the two are within 1.4 %, the 6-flux ones included).
    let dusty = LayerParams {
        depth: 0.3,
        sigma_s: [2.0; 3],
        sigma_a: [0.05, 0.06, 0.08],
        g: 0.3,
        ..coat(1.5, 0.1)
    };
    let stacks: [(&[LayerParams], bool); 3] = [
        (&[coat(1.5, 0.05), gold(0.25)], false),
        (
            &[coat(1.5, 0.04), coat(1.35, 0.1), coat(1.7, 0.2), gold(0.25)],
            false,
        ),
        (&[dusty, gold(0.15)], true),
    ];
    for mode in [Interfaces::Single, Interfaces::Multiple] {
        for (stack, media) in stacks {
            let transport = crate::model::angular::Transport::new(stack, media, mode);
            for mu in [0.8, 0.3] {
                let walk = run_in(mode, stack, media, G2::HeightCorrelated, mu, 30_000);
                let (r, _) = transport.reflectances(mu);
                let r = *r.last().expect("layers");
                for (c, r) in r.iter().enumerate() {
                    let (got, se) = (walk.reflectance.mean[c], walk.reflectance.std_error[c]);
                    assert!(
                        (r - got).abs() <= 4.0 * se + 0.02 * got,
                        "{mode} μ {mu} channel {c}: ordinates {r} walk {got} ± {se}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_corrected_transport_keeps_the_physical_invariances_on_random_stacks() {
    // Over random stacks within the presets' ranges: an index-matched interface of any
    // roughness and a medium of zero depth change nothing, and a lossless stack walked on its
    // microsurfaces reflects and transmits everything. At the tabulated cosines the corrected
    // energies are the transport's (exact); between them the ratios are interpolated, and the
    // change stays within 1 % of R.
    use crate::material::random::{preset_like_stack, PresetRanges};
    use crate::model::fgd::ExactFgd;
    use crate::model::transport;
    use crate::model::NoTir;
    use crate::variant::Model;

    let ranges = PresetRanges::of_presets().expect("the presets");
    let fgd = ExactFgd::new(G2::HeightCorrelated);
    let mut rng = crate::model::random::Rng(0x1d_e5);
    let corrected = |layers: &[LayerParams], model: Model, mode: Interfaces, cosines: &[f64]| {
        let variant = VariantKey {
            model,
            transport: crate::variant::Transport::Corrected,
            interfaces: mode,
            ..VariantKey::default()
        };
        crate::model::oracle::evaluate_variant(variant, layers, cosines, &fgd, &NoTir)
    };
    for k in 0..8 {
        let model = if k % 2 == 0 { Model::Tm2 } else { Model::Tm6 };
        let stack = preset_like_stack(&mut rng, &ranges, model, "case");
        let layers = stack.params();
        // An index-matched rough layer under the top coat, and a zero-depth medium in it.
        let mut with = layers.clone();
        let matched = LayerParams {
            roughness: rng.range(0.0, 1.0),
            depth: 0.0,
            sigma_s: [rng.range(0.0, 3.0); 3],
            ..LayerParams::dielectric(layers[0].ior[0], 0.0)
        };
        if layers[0].diffuse.is_none() && !layers[0].is_conductor() {
            with.insert(1, matched);
        } else {
            continue;
        }
        let cosines = [transport::point(4), transport::point(11), 0.37];
        let a = corrected(&layers, model, Interfaces::Single, &cosines);
        let b = corrected(&with, model, Interfaces::Single, &cosines);
        let bounds = cosines.iter().zip([1e-9, 1e-9, 1e-2]);
        for ((a, b), (mu, tolerance)) in a.iter().zip(&b).zip(bounds) {
            for c in 0..3 {
                let (a, b) = (a.reflectance[c], b.reflectance[c]);
                assert!(
                    (a - b).abs() <= tolerance * a.max(1e-3),
                    "case {k}, μ {mu}: {b} against {a}\n{}",
                    stack.to_toml()
                );
            }
        }
    }
    // Lossless: coats without absorption over nothing, multiple-scattering interfaces.
    for k in 0..4 {
        let model = if k % 2 == 0 { Model::Tm2 } else { Model::Tm6 };
        let mut layers: Vec<LayerParams> = (0..2)
            .map(|_| {
                LayerParams::dielectric(rng.range(ranges.ior.0, ranges.ior.1), rng.range(0.05, 0.6))
                    .with_medium(0.3, [rng.range(0.5, 3.0); 3], [0.0; 3], 0.3)
            })
            .collect();
        layers.push(LayerParams::dielectric(1.0, 0.2));
        let e = &corrected(&layers, model, Interfaces::Multiple, &[transport::point(9)])[0];
        for c in 0..3 {
            let sum = e.reflectance[c] + e.transmittance[c];
            assert!((sum - 1.0).abs() < 1e-6, "case {k}: R + T = {sum}");
        }
    }
}
