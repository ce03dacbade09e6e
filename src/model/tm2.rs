//! The 2-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021) as the reference
//! code defines it (ALGORITHMS.md §4): per-interface energy and asymmetry factors composed top
//! to bottom — by the adding equations, which equal the reference's transfer-matrix products
//! where those exist and stay finite where they do not (`adding.rs`) — one lobe per layer. The
//! f64 twin of `glsl/include/lib/tm2.glsl`.

use super::adding::{avg, bound, map3, Component, Slab};
use super::{
    albedo, diffuse, hg, Evaluation, Fgd, LayerParams, Lobe, Tir, INDEX_MATCHED, IOR_AIR,
    REFLECTS_NOTHING,
};

/// |cos| of the mean direction refracted from `cos_i` through relative IOR η; 0 when the mean
/// direction itself is totally reflected.
pub(crate) fn refracted_cos(cos_i: f64, eta: f64) -> f64 {
    let c2 = 1.0 - (1.0 - cos_i * cos_i) / (eta * eta);
    if c2 > 0.0 {
        c2.sqrt()
    } else {
        0.0
    }
}

/// One dielectric interface's factors (§4.1): energy, HG g's, mean cosines.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Interface {
    pub r: f64,
    pub g_r: f64,
    pub g_t: f64,
    pub g_tp: f64,
    pub mu: f64,
    pub mu_t: f64,
}

/// Factors of the dielectric interface of relative IOR `eta`, roughness `alpha`, at `cos_i`.
pub(crate) fn dielectric(cos_i: f64, eta: f64, alpha: f64, fgd: &dyn Fgd) -> Interface {
    let cos_t = refracted_cos(cos_i, eta);
    // Rough transmission widens less than reflection (§3.4).
    let s_down = (1.0 - cos_i / (eta * cos_t.max(1e-7))).abs();
    let s_up = (1.0 - eta * cos_t / cos_i.max(1e-7)).abs();
    let r = if (eta - 1.0).abs() < REFLECTS_NOTHING {
        0.0
    } else {
        albedo(fgd, cos_i, alpha, eta, 0.0)
    };
    Interface {
        r,
        g_r: hg::g_of_alpha(alpha),
        g_t: hg::g_of_alpha(0.5 * s_down * alpha),
        g_tp: hg::g_of_alpha(0.5 * s_up * alpha),
        mu: cos_i,
        mu_t: cos_t,
    }
}

/// The layer's relative interface: `None` for a conductor, otherwise η_ij (mean over RGB).
fn relative_eta(layer: &LayerParams, eta_above: f64) -> Option<f64> {
    (!layer.is_conductor()).then(|| avg(layer.ior) / eta_above)
}

/// Evaluates the 2-flux model for view cosine `cos_theta` (§4.6), composing the components by
/// the adding equations (`adding.rs`).
pub fn evaluate(stack: &[LayerParams], cos_theta: f64, fgd: &dyn Fgd, tir: &dyn Tir) -> Evaluation {
    let mut e = Slab::empty();
    let mut g = Slab::empty();
    let (mut r_prev, mut g_prev) = ([0.0; 3], 0.0);
    let mut g_t0i = 1.0;
    let mut eta_above = IOR_AIR;
    let mut cos_i = cos_theta;
    let mut transmittance = [0.0; 3];
    let mut lobes = Vec::with_capacity(stack.len());
    for (i, layer) in stack.iter().enumerate() {
        if let Some(rho) = layer.diffuse {
            // A Lambertian base under the layers above (`diffuse`): one diffuse lobe.
            let weight = diffuse::lobe_weight(e.t, rho, &diffuse::slab(&stack[..i], false));
            lobes.push(Lobe {
                weight,
                roughness: 1.0,
                diffuse: true,
            });
            r_prev = map3(|c| r_prev[c] + weight[c]);
            transmittance = [0.0; 3];
            break;
        }
        let (r_total, g_total, g_t0j) = match relative_eta(layer, eta_above) {
            None => {
                let r_c = map3(|c| {
                    albedo(
                        fgd,
                        cos_i,
                        layer.roughness,
                        layer.ior[c] / eta_above,
                        layer.kappa[c] / eta_above,
                    )
                });
                let g_r = hg::g_of_alpha(layer.roughness);
                let r_total = e.over_base(r_c);
                let g_total = g.over_base([avg(r_c) * g_r; 3]);
                (r_total, bound(avg(g_total), avg(r_total)), g_t0i)
            }
            Some(eta) if (eta - 1.0).abs() < INDEX_MATCHED => (r_prev, g_prev, g_t0i),
            Some(eta) => {
                let f = dielectric(cos_i, eta, layer.roughness, fgd);
                // First-order transmitted-asymmetry correction (§4.4).
                let g_next = stack
                    .get(i + 1)
                    .map_or(0.0, |l| hg::g_of_alpha(l.roughness));
                let g_t0j = hg::refract(g_t0i, 1.0 / eta) * f.g_t;
                let g_t0j_r = g_t0j * g_next;
                let g_t0j_rt = hg::refract(g_t0j_r, eta) * f.g_tp;
                let g_t = hg::safe_ratio(g_t0j, g_t0i);
                let g_tp = hg::safe_ratio(g_t0j_rt, g_t0j_r);
                let (mut r, mut t, mut rp, mut tp) = (f.r, 1.0 - f.r, f.r, 1.0 - f.r);
                // Total internal reflection moves energy from transmission to reflection (§4.5).
                if eta < 1.0 {
                    let tau = tir.tir(f.mu, hg::alpha_of_g(g_t0i), eta) * t;
                    r += tau;
                    t -= tau;
                } else {
                    let tau = tir.tir(f.mu_t, hg::alpha_of_g(g_t0j_r), 1.0 / eta) * tp;
                    rp += tau;
                    tp -= tau;
                }
                e = e.over(&Component::lossless(r, t, rp, tp));
                g = g
                    .over(&Component::weighted(
                        r * f.g_r,
                        t * g_t,
                        rp * f.g_r,
                        tp * g_tp,
                    ))
                    .bounded_by(&e);
                cos_i = f.mu_t;
                eta_above = avg(layer.ior);
                (e.r, avg(g.r), g_t0j)
            }
        };
        transmittance = if layer.is_conductor() { [0.0; 3] } else { e.t };
        let weight = map3(|c| r_total[c] - r_prev[c]);
        let energy = avg(weight);
        let lobe_g = if energy > 0.0 {
            ((g_total - g_prev) / energy).min(1.0)
        } else {
            0.0
        };
        lobes.push(Lobe {
            weight,
            roughness: hg::alpha_of_g(lobe_g),
            diffuse: false,
        });
        r_prev = r_total;
        g_prev = g_total;
        g_t0i = g_t0j;
        if layer.is_conductor() {
            break;
        }
    }
    let eta_base = stack.last().map_or(IOR_AIR, |l| avg(l.ior));
    Evaluation {
        reflectance: r_prev,
        transmittance,
        transmitted_roughness: super::transmitted_alpha(g_t0i, eta_base),
        // One lobe per layer, in order.
        lobe_layers: (0..lobes.len()).collect(),
        lobes,
        retro_mask: 0,
        top_fresnel: None,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::fgd::ExactFgd;
    use crate::model::random::Rng;
    use crate::model::{fresnel, NoTir};
    use crate::variant::G2;

    pub fn coat(ior: f64, roughness: f64) -> LayerParams {
        LayerParams::dielectric(ior, roughness)
    }

    pub fn gold(roughness: f64) -> LayerParams {
        LayerParams::gold(roughness)
    }

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|c| (a[c] - b[c]).abs() <= tol)
    }

    #[test]
    fn one_smooth_interface_is_fresnel() {
        let fgd = ExactFgd::new(G2::Smith);
        for mu in [0.1, 0.4, 0.8, 1.0] {
            let e = evaluate(&[coat(1.5, 0.0)], mu, &fgd, &NoTir);
            let f = fresnel::dielectric(mu, 1.5);
            assert!(close(e.reflectance, [f; 3], 1e-12), "{mu}: {e:?}");
            assert!(close(e.transmittance, [1.0 - f; 3], 1e-12));
            let e = evaluate(&[gold(0.0)], mu, &fgd, &NoTir);
            let g = gold(0.0);
            let want = map3(|c| fresnel::conductor(mu, g.ior[c], g.kappa[c]));
            assert!(close(e.reflectance, want, 1e-12) && close(e.lobes[0].weight, want, 1e-12));
        }
    }

    #[test]
    fn an_index_matched_layer_disappears() {
        let fgd = ExactFgd {
            g2: G2::Smith,
            resolution: 128,
        };
        for mu in [0.2, 0.7] {
            let with = evaluate(
                &[coat(1.0, 0.3), coat(1.5, 0.1), gold(0.2)],
                mu,
                &fgd,
                &NoTir,
            );
            let without = evaluate(&[coat(1.5, 0.1), gold(0.2)], mu, &fgd, &NoTir);
            assert_eq!(with.reflectance, without.reflectance);
            assert_eq!(with.lobes[0].weight, [0.0; 3]);
            assert_eq!(with.lobes[1..], without.lobes[..]);
        }
    }

    /// Adding equations for one smooth interface over a smooth base of reflectance r12 seen
    /// from inside: R = R01 + T01² R12 / (1 − R10 R12).
    fn adding(mu: f64, eta: f64, r12: impl Fn(f64) -> f64) -> f64 {
        let r01 = fresnel::dielectric(mu, eta);
        let mu_t = refracted_cos(mu, eta);
        let r10 = fresnel::dielectric(mu_t, 1.0 / eta);
        let r12 = r12(mu_t);
        r01 + (1.0 - r01).powi(2) * r12 / (1.0 - r10 * r12)
    }

    #[test]
    fn smooth_stacks_follow_the_adding_equations() {
        let fgd = ExactFgd::new(G2::Smith);
        let g = gold(0.0);
        for mu in [0.15, 0.5, 0.9] {
            let e = evaluate(&[coat(1.5, 0.0), gold(0.0)], mu, &fgd, &NoTir);
            for c in 0..3 {
                let want = adding(mu, 1.5, |m| {
                    fresnel::conductor(m, g.ior[c] / 1.5, g.kappa[c] / 1.5)
                });
                assert!(
                    (e.reflectance[c] - want).abs() < 1e-12,
                    "{mu} ch {c}: {} vs {want}",
                    e.reflectance[c]
                );
            }
            // Two coats: the lower coat over gold is itself the base of the upper one.
            let e = evaluate(
                &[coat(1.3, 0.0), coat(1.7, 0.0), gold(0.0)],
                mu,
                &fgd,
                &NoTir,
            );
            for c in 0..3 {
                let inner = |m: f64| {
                    adding(m, 1.7 / 1.3, |m2| {
                        fresnel::conductor(m2, g.ior[c] / 1.7, g.kappa[c] / 1.7)
                    })
                };
                let want = adding(mu, 1.3, inner);
                assert!(
                    (e.reflectance[c] - want).abs() < 1e-12,
                    "{mu} ch {c}: {} vs {want}",
                    e.reflectance[c]
                );
            }
        }
    }

    #[test]
    fn energy_is_conserved_over_a_random_sweep() {
        let fgd = ExactFgd {
            g2: G2::HeightCorrelated,
            resolution: 96,
        };
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for _ in 0..60 {
            let n = 1 + (rng.unit() * 3.0) as usize;
            let mut stack: Vec<LayerParams> = (0..n)
                .map(|_| coat(1.05 + rng.unit(), rng.unit() * 0.8))
                .collect();
            let mu = 0.02 + 0.98 * rng.unit();
            let e = evaluate(&stack, mu, &fgd, &NoTir);
            for c in 0..3 {
                assert!(
                    (e.reflectance[c] + e.transmittance[c] - 1.0).abs() < 1e-9,
                    "{stack:?} {mu}: {e:?}"
                );
            }
            stack.push(gold(rng.unit()));
            let e = evaluate(&stack, mu, &fgd, &NoTir);
            let sum = map3(|c| e.lobes.iter().map(|l| l.weight[c]).sum());
            for (s, r) in sum.iter().zip(e.reflectance) {
                assert!((0.0..=1.0).contains(&r), "{stack:?} {mu}: {e:?}");
                assert!((s - r).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn a_single_conductor_is_plain_ggx() {
        let fgd = ExactFgd {
            g2: G2::HeightCorrelated,
            resolution: 128,
        };
        let g = gold(0.3);
        for mu in [0.1, 0.5, 1.0] {
            let e = evaluate(&[g], mu, &fgd, &NoTir);
            let want = map3(|c| fgd.fgd(mu, 0.3, g.ior[c], g.kappa[c]));
            assert_eq!(e.lobes.len(), 1);
            assert_eq!(e.lobes[0].weight, want);
            assert!((e.lobes[0].roughness - 0.3).abs() < 1e-9);
        }
    }
}
