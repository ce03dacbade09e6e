//! The 6-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021) as the reference
//! code defines it (ALGORITHMS.md §5): fluxes (1,2) primary down/up, (3,4) secondary forward
//! class, (5,6) secondary backward class; components alternate interface, medium, …,
//! substrate. The f64 twin of `glsl/include/lib/tm6.glsl`. Components are composed by the
//! adding equations with 3×3 operators between the flux classes (`adding.rs`), which equal the
//! reference's 6×6 matrix products and 3×3 extraction where those exist and stay finite where
//! they do not (thick media, opaque components).
//!
//! One departure from the reference, where it returned wrong values rather than failing: its
//! medium clamped the optical depth τ to 45/max(σ_ext) (and 45/max(γ)) to keep sinh, cosh and
//! 1/T finite. The same τ also drives the scattered flux, which decays at γ ≪ σ_ext in a
//! scattering medium, so a medium of optical depth 10⁴ transmitted like one of 45/σ_ext·γ
//! (T = 0.003 through four layers of σ_s = 222, depth 49). The two-stream factors are written
//! here in forms that only decay (e^{−γτ}, e^{−2γτ}), so no clamp is needed.

use super::adding::{avg, bound, map3, Component, Component6, Rgb, Slab6};
use super::hg::{self, safe_ratio};
use super::tm2;
use super::{albedo, diffuse, Evaluation, Fgd, LayerParams, Lobe, Tir, INDEX_MATCHED, IOR_AIR};

/// 1 − e^{−x} for x ≥ 0, without cancellation at small x.
fn one_minus_exp_neg(x: f64) -> f64 {
    -(-x).exp_m1()
}

/// A medium's two-stream factors (§5.3, numerics §5.8).
pub(crate) struct Medium {
    pub t: Rgb,
    pub r_fb: Rgb,
    pub t_ff: Rgb,
    pub g_rfb: f64,
    pub g_tff: f64,
}

/// Back-reflection and forward transmission of the two-stream system (a, b) over optical
/// depth τ: with S = sinh(γτ), C = cosh(γτ), r = S·b/(Cγ + S·a) and t = γ/(Cγ + S·a), here
/// divided through by e^{γτ}/2 so that nothing grows with τ. γ² = a² − b² is taken as
/// (a − b)(a + b) from those sums as the caller forms them: a − b is the absorption alone in a
/// nearly lossless medium, and a² − b² lost it to f32 rounding (γ = 0, then 0/0 on the GPU).
fn two_stream(a: f64, b: f64, a_minus_b: f64, a_plus_b: f64, tau: f64) -> (f64, f64) {
    let gamma = (a_minus_b * a_plus_b).max(0.0).sqrt();
    let x = gamma * tau;
    let (decay, spread) = ((-x).exp(), one_minus_exp_neg(2.0 * x));
    let den = gamma * (2.0 - spread) + a * spread;
    (b * spread / den, 2.0 * gamma * decay / den)
}

/// The two-stream factors of a medium (energies, then g-weighted), with a = σ_ext − σ_sf and
/// b = σ_sb, resp. a_g = σ_ext − g·σ_sf and b_g = −g·σ_sb; their sums and differences written
/// as sums of non-negative terms.
pub(crate) fn medium_factors(layer: &LayerParams, mu: f64) -> Medium {
    let g = layer.g;
    let tau = layer.depth / mu.max(1e-7);
    let (mut r_fb, mut t_ff) = ([0.0; 3], [0.0; 3]);
    let (mut rg, mut tg) = ([0.0; 3], [0.0; 3]);
    let mut t = [0.0; 3];
    for c in 0..3 {
        let sigma_k = layer.sigma_a[c].max(1e-7);
        let sigma_sb = layer.sigma_s[c] * hg::lh_norm(g);
        let sigma_sf = layer.sigma_s[c] - sigma_sb;
        let sigma_ext = layer.sigma_s[c] + sigma_k;
        let a = sigma_sb + sigma_k;
        (r_fb[c], t_ff[c]) = two_stream(a, sigma_sb, sigma_k, 2.0 * sigma_sb + sigma_k, tau);
        let a_g = sigma_ext - sigma_sf * g;
        let minus = sigma_sf * (1.0 - g) + sigma_sb * (1.0 + g) + sigma_k;
        let plus = layer.sigma_s[c] * (1.0 - g) + sigma_k;
        (rg[c], tg[c]) = two_stream(a_g, -sigma_sb * g, minus, plus, tau);
        t[c] = (-sigma_ext * tau).exp();
    }
    Medium {
        t,
        r_fb,
        t_ff,
        g_rfb: avg(map3(|c| safe_ratio(rg[c], r_fb[c]))),
        g_tff: avg(map3(|c| safe_ratio(tg[c], t_ff[c]))),
    }
}

/// What a component contributes: an interface's or a medium's operators (energy, asymmetry),
/// a substrate, or nothing (an index-matched interface, an empty medium).
enum Step {
    Interface(Component6, Component6),
    Medium(Component6, Component6),
    Substrate { r_c: Rgb, g_r: f64 },
    Nothing,
}

/// Evaluates the 6-flux model for view cosine `cos_theta` (§5.5–5.7).
pub fn evaluate(stack: &[LayerParams], cos_theta: f64, fgd: &dyn Fgd, tir: &dyn Tir) -> Evaluation {
    let mut e = Slab6::empty();
    let mut g = Slab6::empty();
    let mut prev = [[0.0; 3]; 3];
    let mut prev_g = [[0.0; 3]; 3];
    let (mut g_t0i, mut g_st0i) = (1.0, 1.0);
    let (mut primary, mut backward) = (false, false);
    let mut eta_above = IOR_AIR;
    let mut cos_i = cos_theta;
    let mut transmittance = [0.0; 3];
    let mut lobes = Vec::new();
    let mut retro_mask = 0u32;
    for (i, layer) in stack.iter().enumerate() {
        if let Some(rho) = layer.diffuse {
            // A Lambertian base under the layers above (`diffuse`): every flux class that
            // reaches it feeds one diffuse lobe.
            let t_view = map3(|c| e.down[0][c] + e.down[1][c] + e.down[2][c]);
            let weight = diffuse::lobe_weight(t_view, rho, &diffuse::slab(&stack[..i], true));
            lobes.push(Lobe {
                weight,
                roughness: 1.0,
                diffuse: true,
            });
            prev[0] = map3(|c| prev[0][c] + weight[c]);
            transmittance = [0.0; 3];
            break;
        }
        let mut steps = Vec::with_capacity(2);
        if layer.is_conductor() {
            let r_c = map3(|c| {
                albedo(
                    fgd,
                    cos_i,
                    layer.roughness,
                    layer.ior[c] / eta_above,
                    layer.kappa[c] / eta_above,
                )
            });
            steps.push(Step::Substrate {
                r_c,
                g_r: hg::g_of_alpha(layer.roughness),
            });
        } else {
            let eta = avg(layer.ior) / eta_above;
            if (eta - 1.0).abs() < INDEX_MATCHED {
                steps.push(Step::Nothing);
            } else {
                let f = tm2::dielectric(cos_i, eta, layer.roughness, fgd);
                let next = stack.get(i + 1);
                let g_next = next.map_or(0.0, |l| hg::g_of_alpha(l.roughness));
                let g_medium = if layer.depth > 0.0 {
                    medium_factors(layer, f.mu_t).g_tff
                } else {
                    1.0
                };
                // Primary path (§4.4) and secondary path through the medium down and up (§5.5).
                let g_t0j = hg::refract(g_t0i, 1.0 / eta) * f.g_t;
                let g_t0j_r = g_t0j * g_next;
                let g_t0j_rt = hg::refract(g_t0j_r, eta) * f.g_tp;
                let g_st0j = hg::refract(g_st0i, 1.0 / eta) * f.g_t;
                let g_st0j_r = g_st0j * g_medium * g_next * g_medium;
                let g_st0j_rt = hg::refract(g_st0j_r, eta) * f.g_tp;
                let (gt, gtp) = (safe_ratio(g_t0j, g_t0i), safe_ratio(g_t0j_rt, g_t0j_r));
                let (gst, gstp) = (safe_ratio(g_st0j, g_st0i), safe_ratio(g_st0j_rt, g_st0j_r));
                let (mut r, mut t, mut rp, mut tp) = (f.r, 1.0 - f.r, f.r, 1.0 - f.r);
                let (mut rs, mut ts, mut rsp, mut tsp) = (r, t, rp, tp);
                if eta < 1.0 {
                    let tau = tir.tir(f.mu, hg::alpha_of_g(g_t0i), eta) * t;
                    r += tau;
                    t -= tau;
                    let tau = tir.tir(f.mu, hg::alpha_of_g(g_st0i), eta) * ts;
                    rs += tau;
                    ts -= tau;
                } else {
                    let tau = tir.tir(f.mu_t, hg::alpha_of_g(g_t0j_r), 1.0 / eta) * tp;
                    rp += tau;
                    tp -= tau;
                    let tau = tir.tir(f.mu_t, hg::alpha_of_g(g_st0j_r), 1.0 / eta) * tsp;
                    rsp += tau;
                    tsp -= tau;
                }
                let energy = Component6::interface(
                    Component::lossless(r, t, rp, tp),
                    Component::lossless(rs, ts, rsp, tsp),
                );
                let asym = Component6::interface(
                    Component::weighted(r * f.g_r, t * gt, rp * f.g_r, tp * gtp),
                    Component::weighted(rs * f.g_r, ts * gst, rsp * f.g_r, tsp * gstp),
                );
                steps.push(Step::Interface(energy, asym));
                g_t0i = g_t0j;
                g_st0i = g_st0j;
                cos_i = f.mu_t;
                eta_above = avg(layer.ior);
            }
            if layer.depth > 0.0 {
                let m = medium_factors(layer, cos_i);
                let gr = map3(|c| m.r_fb[c] * m.g_rfb);
                let gt = map3(|c| m.t_ff[c] * m.g_tff);
                steps.push(Step::Medium(
                    Component6::medium(m.t, m.r_fb, m.t_ff),
                    Component6::medium_weighted(m.t, m.r_fb, m.t_ff, gr, gt),
                ));
            } else {
                steps.push(Step::Nothing);
            }
        }
        for step in steps {
            let (up, up_g) = match step {
                Step::Substrate { r_c, g_r } => {
                    primary = true;
                    transmittance = [0.0; 3];
                    let up = e.over_base(r_c);
                    let up_g = g.over_base(map3(|c| r_c[c] * g_r));
                    let up_g = std::array::from_fn(|k| map3(|c| bound(up_g[k][c], up[k][c])));
                    (up, up_g)
                }
                Step::Interface(energy, asym) | Step::Medium(energy, asym) => {
                    // Request flags (§5.7): primary after the first interface, backward after
                    // the first medium, forward once both exist.
                    if matches!(step, Step::Interface(..)) {
                        primary = true;
                    } else {
                        backward = true;
                    }
                    e = e.over(&energy);
                    g = g.over(&asym).bounded_by(&e);
                    transmittance = map3(|c| e.down[0][c] + e.down[1][c] + e.down[2][c]);
                    (e.up, g.up)
                }
                Step::Nothing => {
                    transmittance = map3(|c| e.down[0][c] + e.down[1][c] + e.down[2][c]);
                    (e.up, g.up)
                }
            };
            // Primary, secondary-forward, secondary-backward lobes, as the flags allow (§5.7).
            let emit = [primary, primary && backward, backward];
            for k in 0..3 {
                if emit[k] {
                    if k == 2 && lobes.len() < 32 {
                        retro_mask |= 1 << lobes.len();
                    }
                    let g_lobe = avg(map3(|c| {
                        safe_ratio(up_g[k][c] - prev_g[k][c], up[k][c] - prev[k][c])
                    }));
                    lobes.push(Lobe {
                        weight: map3(|c| (up[k][c] - prev[k][c]).max(0.0)),
                        roughness: hg::alpha_of_g(g_lobe.min(1.0)),
                        diffuse: false,
                    });
                }
                prev[k] = up[k];
                prev_g[k] = up_g[k];
            }
        }
        if layer.is_conductor() {
            break;
        }
    }
    Evaluation {
        reflectance: map3(|c| prev[0][c] + prev[1][c] + prev[2][c]),
        transmittance,
        lobes,
        retro_mask,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::fgd::ExactFgd;
    use crate::model::random::Rng;
    use crate::model::tm2::tests::{coat, gold};
    use crate::model::NoTir;
    use crate::variant::G2;

    fn medium(
        ior: f64,
        roughness: f64,
        depth: f64,
        sigma_s: f64,
        sigma_a: f64,
        g: f64,
    ) -> LayerParams {
        LayerParams {
            depth,
            sigma_s: [sigma_s; 3],
            sigma_a: [sigma_a; 3],
            g,
            ..coat(ior, roughness)
        }
    }

    #[test]
    fn without_media_it_equals_the_2_flux_model() {
        let fgd = ExactFgd {
            g2: G2::HeightCorrelated,
            resolution: 96,
        };
        let stacks = [
            vec![gold(0.3)],
            vec![coat(1.5, 0.1), gold(0.2)],
            vec![coat(1.5, 0.1), coat(1.3, 0.3), gold(0.4)],
            vec![coat(1.5, 0.2), coat(1.2, 0.05)],
        ];
        for stack in &stacks {
            for mu in [0.1, 0.6, 1.0] {
                let two = tm2::evaluate(stack, mu, &fgd, &NoTir);
                let six = evaluate(stack, mu, &fgd, &NoTir);
                for c in 0..3 {
                    assert!((two.reflectance[c] - six.reflectance[c]).abs() < 1e-12);
                    assert!((two.transmittance[c] - six.transmittance[c]).abs() < 1e-12);
                }
                // Same energies; the 6-flux list adds zero lobes for the empty media.
                let nonzero = |e: &Evaluation| -> Vec<Rgb> {
                    e.lobes
                        .iter()
                        .map(|l| l.weight)
                        .filter(|w| w.iter().any(|&v| v > 0.0))
                        .collect()
                };
                let (a, b) = (nonzero(&two), nonzero(&six));
                assert_eq!(a.len(), b.len(), "{stack:?}");
                for (x, y) in a.iter().zip(&b) {
                    assert!(
                        (0..3).all(|c| (x[c] - y[c]).abs() < 1e-12),
                        "{x:?} vs {y:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn medium_limits_hold() {
        // No scattering: t_ff = exp(−σ_k τ) = T and r_fb = 0.
        let m = medium_factors(&medium(1.5, 0.1, 0.7, 0.0, 0.8, 0.3), 0.6);
        for c in 0..3 {
            let want = (-0.8f64 * 0.7 / 0.6).exp();
            assert!((m.t_ff[c] - want).abs() < 1e-12 && (m.t[c] - want).abs() < 1e-12);
            assert_eq!(m.r_fb[c], 0.0);
        }
        // No absorption: everything scattered is either reflected or transmitted.
        let m = medium_factors(&medium(1.5, 0.1, 0.7, 3.0, 0.0, 0.3), 0.6);
        for c in 0..3 {
            assert!(
                (m.r_fb[c] + m.t_ff[c] - 1.0).abs() < 1e-5,
                "{} {}",
                m.r_fb[c],
                m.t_ff[c]
            );
        }
    }

    #[test]
    fn energy_is_conserved_over_a_random_sweep() {
        let fgd = ExactFgd {
            g2: G2::HeightCorrelated,
            resolution: 64,
        };
        let mut rng = Rng(0x51ed_2701_9c3a_77b1);
        for _ in 0..60 {
            let n = 1 + (rng.unit() * 3.0) as usize;
            let mut stack: Vec<LayerParams> = (0..n)
                .map(|_| {
                    medium(
                        1.05 + rng.unit(),
                        rng.unit() * 0.8,
                        rng.unit(),
                        3.0 * rng.unit(),
                        0.0,
                        rng.unit() * 1.6 - 0.7,
                    )
                })
                .collect();
            let mu = 0.05 + 0.95 * rng.unit();
            let e = evaluate(&stack, mu, &fgd, &NoTir);
            for c in 0..3 {
                let total = e.reflectance[c] + e.transmittance[c];
                assert!(
                    (total - 1.0).abs() < 1e-4,
                    "lossless stack: R + T = {total} for {stack:?} at {mu}"
                );
            }
            stack.push(gold(rng.unit()));
            let e = evaluate(&stack, mu, &fgd, &NoTir);
            for c in 0..3 {
                assert!(
                    (0.0..=1.0).contains(&e.reflectance[c]),
                    "{stack:?} {mu}: {e:?}"
                );
                assert!(e
                    .lobes
                    .iter()
                    .all(|l| l.weight[c] >= 0.0 && l.roughness.is_finite()));
            }
        }
    }
}
