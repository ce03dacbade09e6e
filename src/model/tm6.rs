//! The 6-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021) as the reference
//! code defines it (ALGORITHMS.md §5): fluxes (1,2) primary down/up, (3,4) secondary forward
//! class, (5,6) secondary backward class; components alternate interface, medium, …,
//! substrate. The f64 twin of `glsl/include/lib/tm6.glsl`. Components are composed by the
//! adding equations with 3×3 operators between the flux classes (`adding.rs`), which equal the
//! reference's 6×6 matrix products and 3×3 extraction where those exist and stay finite where
//! they do not (thick media, opaque components).
//!
//! The media's two-stream factors are [`super::medium`]'s.

use super::adding::{avg, bound, map3, Component, Component6, Rgb, Slab6};
use super::hg::{self, safe_ratio};
use super::medium::medium_factors;
use super::tm2;
use super::{albedo, diffuse, Evaluation, Fgd, LayerParams, Lobe, Tir, INDEX_MATCHED, IOR_AIR};

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
    let mut walk = Walk::new(cos_theta);
    for (i, layer) in stack.iter().enumerate() {
        walk.layer = i;
        if let Some(rho) = layer.diffuse {
            walk.diffuse_base(&stack[..i], rho);
            break;
        }
        if layer.is_conductor() {
            let step = walk.substrate(layer, fgd);
            walk.add(step);
            break;
        }
        let step = walk.interface(stack, i, fgd, tir);
        walk.add(step);
        let step = walk.medium(layer);
        walk.add(step);
    }
    walk.finish(stack)
}

/// The walk down the stack so far: the energy slab `e` and the asymmetry slab `g` (their
/// upward fluxes as they grow: the lobes are their increments), the g of the primary and
/// secondary paths transmitted down to the current component, which lobes the components so
/// far allow (§5.7), and the mean direction's cosine in the current layer.
struct Walk {
    e: Slab6,
    g: Slab6,
    prev: [Rgb; 3],
    prev_g: [Rgb; 3],
    g_t0i: f64,
    g_st0i: f64,
    primary: bool,
    backward: bool,
    eta_above: f64,
    cos_i: f64,
    transmittance: Rgb,
    lobes: Vec<Lobe>,
    /// The layer whose components are being added, and each lobe's.
    layer: usize,
    lobe_layers: Vec<usize>,
    retro_mask: u32,
}

impl Walk {
    fn new(cos_theta: f64) -> Self {
        Self {
            e: Slab6::empty(),
            g: Slab6::empty(),
            prev: [[0.0; 3]; 3],
            prev_g: [[0.0; 3]; 3],
            g_t0i: 1.0,
            g_st0i: 1.0,
            primary: false,
            backward: false,
            eta_above: IOR_AIR,
            cos_i: cos_theta,
            transmittance: [0.0; 3],
            lobes: Vec::new(),
            layer: 0,
            lobe_layers: Vec::new(),
            retro_mask: 0,
        }
    }

    /// A Lambertian base under the layers `above` (`diffuse`): every flux class that reaches
    /// it feeds one diffuse lobe.
    fn diffuse_base(&mut self, above: &[LayerParams], rho: Rgb) {
        let e = &self.e;
        let t_view = map3(|c| e.down[0][c] + e.down[1][c] + e.down[2][c]);
        let weight = diffuse::lobe_weight(t_view, rho, &diffuse::slab(above, true));
        self.lobes.push(Lobe {
            weight,
            roughness: 1.0,
            diffuse: true,
        });
        self.lobe_layers.push(self.layer);
        self.prev[0] = map3(|c| self.prev[0][c] + weight[c]);
        self.transmittance = [0.0; 3];
    }

    /// A conductor substrate, which ends the stack.
    fn substrate(&self, layer: &LayerParams, fgd: &dyn Fgd) -> Step {
        let r_c = map3(|c| {
            albedo(
                fgd,
                self.cos_i,
                layer.roughness,
                layer.ior[c] / self.eta_above,
                layer.kappa[c] / self.eta_above,
            )
        });
        Step::Substrate {
            r_c,
            g_r: hg::g_of_alpha(layer.roughness),
        }
    }

    /// The dielectric interface at the top of layer `i` (nothing when index-matched): its
    /// energy and asymmetry operators for the primary and secondary classes, with the TIR
    /// correction; moves the walk into the layer.
    fn interface(&mut self, stack: &[LayerParams], i: usize, fgd: &dyn Fgd, tir: &dyn Tir) -> Step {
        let layer = &stack[i];
        let eta = avg(layer.ior) / self.eta_above;
        if (eta - 1.0).abs() < INDEX_MATCHED {
            return Step::Nothing;
        }
        let f = tm2::dielectric(self.cos_i, eta, layer.roughness, fgd);
        let next = stack.get(i + 1);
        let g_next = next.map_or(0.0, |l| hg::g_of_alpha(l.roughness));
        let g_medium = if layer.depth > 0.0 {
            medium_factors(layer, f.mu_t).g_tff
        } else {
            1.0
        };
        let (g_t0i, g_st0i) = (self.g_t0i, self.g_st0i);
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
        self.g_t0i = g_t0j;
        self.g_st0i = g_st0j;
        self.cos_i = f.mu_t;
        self.eta_above = avg(layer.ior);
        Step::Interface(energy, asym)
    }

    /// The medium filling `layer`, crossed along the mean direction (nothing at depth 0).
    fn medium(&self, layer: &LayerParams) -> Step {
        if layer.depth <= 0.0 {
            return Step::Nothing;
        }
        let m = medium_factors(layer, self.cos_i);
        let gr = map3(|c| m.r_fb[c] * m.g_rfb);
        let gt = map3(|c| m.t_ff[c] * m.g_tff);
        Step::Medium(
            Component6::medium(m.t, m.r_fb, m.t_ff),
            Component6::medium_weighted(m.t, m.r_fb, m.t_ff, gr, gt),
        )
    }

    /// Adds `step` below the slabs and emits the lobes the flags allow.
    fn add(&mut self, step: Step) {
        let (up, up_g) = match step {
            Step::Substrate { r_c, g_r } => {
                self.primary = true;
                self.transmittance = [0.0; 3];
                let up = self.e.over_base(r_c);
                let up_g = self.g.over_base(map3(|c| r_c[c] * g_r));
                let up_g = std::array::from_fn(|k| map3(|c| bound(up_g[k][c], up[k][c])));
                (up, up_g)
            }
            Step::Interface(energy, asym) | Step::Medium(energy, asym) => {
                // Request flags (§5.7): primary after the first interface, backward after the
                // first medium, forward once both exist.
                if matches!(step, Step::Interface(..)) {
                    self.primary = true;
                } else {
                    self.backward = true;
                }
                self.e = self.e.over(&energy);
                self.g = self.g.over(&asym).bounded_by(&self.e);
                self.transmittance = self.down();
                (self.e.up, self.g.up)
            }
            Step::Nothing => {
                self.transmittance = self.down();
                (self.e.up, self.g.up)
            }
        };
        self.emit(up, up_g);
    }

    /// The energy transmitted down to the current component, over every flux class.
    fn down(&self) -> Rgb {
        let e = &self.e;
        map3(|c| e.down[0][c] + e.down[1][c] + e.down[2][c])
    }

    /// Primary, secondary-forward and secondary-backward lobes, as the flags allow (§5.7):
    /// each the increment of its class's upward flux.
    fn emit(&mut self, up: [Rgb; 3], up_g: [Rgb; 3]) {
        let emit = [self.primary, self.primary && self.backward, self.backward];
        for k in 0..3 {
            if emit[k] {
                if k == 2 && self.lobes.len() < 32 {
                    self.retro_mask |= 1 << self.lobes.len();
                }
                let (prev, prev_g) = (self.prev[k], self.prev_g[k]);
                let g_lobe = avg(map3(|c| {
                    safe_ratio(up_g[k][c] - prev_g[c], up[k][c] - prev[c])
                }));
                self.lobes.push(Lobe {
                    weight: map3(|c| (up[k][c] - prev[c]).max(0.0)),
                    roughness: hg::alpha_of_g(g_lobe.min(1.0)),
                    diffuse: false,
                });
                self.lobe_layers.push(self.layer);
            }
            self.prev[k] = up[k];
            self.prev_g[k] = up_g[k];
        }
    }

    fn finish(self, stack: &[LayerParams]) -> Evaluation {
        let prev = self.prev;
        let eta_base = stack.last().map_or(IOR_AIR, |l| avg(l.ior));
        Evaluation {
            transmitted_roughness: super::transmitted_alpha(self.g_t0i, eta_base),
            reflectance: map3(|c| prev[0][c] + prev[1][c] + prev[2][c]),
            transmittance: self.transmittance,
            lobes: self.lobes,
            lobe_layers: self.lobe_layers,
            retro_mask: self.retro_mask,
            top_fresnel: None,
        }
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
        coat(ior, roughness).with_medium(depth, [sigma_s; 3], [sigma_a; 3], g)
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
