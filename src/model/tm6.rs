//! The 6-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021) as the reference
//! code defines it (ALGORITHMS.md §5): fluxes (1,2) primary down/up, (3,4) secondary forward
//! class, (5,6) secondary backward class; components alternate interface, medium, …,
//! substrate. The f64 twin of `glsl/include/lib/tm6.glsl`: dense 6×6 matrices per channel, and
//! the three reflectances extracted by solving the downward boundary conditions (the same
//! algebra as the reference's 20-entry sparse products).

use super::tm2::{self, avg, map3, Matrix2};
use super::{hg, Evaluation, Fgd, LayerParams, Lobe, Tir, IOR_AIR};

type Rgb = [f64; 3];

#[derive(Clone, Copy)]
struct Matrix6([[Rgb; 6]; 6]);

impl Matrix6 {
    fn identity() -> Self {
        let mut m = [[[0.0; 3]; 6]; 6];
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = [1.0; 3];
        }
        Self(m)
    }

    fn mul(&self, b: &Self) -> Self {
        let mut c = [[[0.0; 3]; 6]; 6];
        for (i, row) in c.iter_mut().enumerate() {
            for (j, out) in row.iter_mut().enumerate() {
                *out = map3(|ch| (0..6).map(|k| self.0[i][k][ch] * b.0[k][j][ch]).sum());
            }
        }
        Self(c)
    }

    /// Block-diagonal interface: the primary block from `p`, both secondary blocks from `s`.
    fn interface(p: Matrix2, s: Matrix2) -> Self {
        let mut a = Self::identity();
        let mut block = |o: usize, m: Matrix2| {
            a.0[o][o] = m.m11;
            a.0[o][o + 1] = m.m12;
            a.0[o + 1][o] = m.m21;
            a.0[o + 1][o + 1] = m.m22;
        };
        block(0, p);
        block(2, s);
        block(4, s);
        a
    }

    /// Homogeneous medium from T, r_fb, t_ff (§5.4); the backward pair mirrors the forward pair.
    fn medium(t: Rgb, r_fb: Rgb, t_ff: Rgb) -> Self {
        let mut a = Self::identity();
        let m = &mut a.0;
        m[0][0] = map3(|c| 1.0 / t[c]);
        m[1][1] = t;
        m[2][2] = map3(|c| 1.0 / t_ff[c]);
        m[3][3] = map3(|c| t_ff[c] - r_fb[c] * r_fb[c] / t_ff[c]);
        m[2][5] = map3(|c| -r_fb[c] / t_ff[c]);
        m[4][1] = m[2][5];
        m[3][4] = map3(|c| r_fb[c] / t_ff[c]);
        m[5][0] = m[3][4];
        m[2][0] = map3(|c| m[2][2][c] - m[0][0][c]);
        m[3][1] = map3(|c| m[3][3][c] - t[c]);
        m[4][4] = m[2][2];
        m[5][5] = m[3][3];
        m[4][3] = m[2][5];
        m[5][2] = m[3][4];
        a
    }

    /// Upward fluxes (r, r_f, r_b) above the stack and downward fluxes (b1, b3, b5) below it,
    /// for a bottom that reflects every class with `r_c`, from a1 = 1, a3 = a5 = 0 (§5.6).
    fn extract(&self, r_c: Rgb) -> ([Rgb; 3], [Rgb; 3]) {
        let mut up = [[0.0; 3]; 3];
        let mut down = [[0.0; 3]; 3];
        for ch in 0..3 {
            let m = |i: usize, j: usize| self.0[i][j][ch];
            let col = |row: usize, k: usize| m(row, 2 * k) + m(row, 2 * k + 1) * r_c[ch];
            let c: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|k| col(2 * r, k)));
            let det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1])
                - c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0])
                + c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0]);
            let b = [
                (c[1][1] * c[2][2] - c[1][2] * c[2][1]) / det,
                -(c[1][0] * c[2][2] - c[1][2] * c[2][0]) / det,
                (c[1][0] * c[2][1] - c[1][1] * c[2][0]) / det,
            ];
            for k in 0..3 {
                down[k][ch] = b[k];
                up[k][ch] = (0..3).map(|j| col(2 * k + 1, j) * b[j]).sum();
            }
        }
        (up, down)
    }
}

fn safe_ratio(num: f64, den: f64) -> f64 {
    if den.abs() > 1e-7 {
        num / den
    } else {
        0.0
    }
}

/// A medium's two-stream factors (§5.3, numerics §5.8).
struct Medium {
    t: Rgb,
    r_fb: Rgb,
    t_ff: Rgb,
    g_rfb: f64,
    g_tff: f64,
}

fn medium_factors(layer: &LayerParams, mu: f64) -> Medium {
    let sigma_k = map3(|c| layer.sigma_a[c].max(1e-7));
    let sigma_sb = map3(|c| layer.sigma_s[c] * hg::lh_norm(layer.g));
    let sigma_sf = map3(|c| layer.sigma_s[c] - sigma_sb[c]);
    let sigma_ext = map3(|c| layer.sigma_s[c] + sigma_k[c]);
    let a = map3(|c| sigma_ext[c] - sigma_sf[c]);
    let b = sigma_sb;
    let gamma = map3(|c| (a[c] * a[c] - b[c] * b[c]).max(0.0).sqrt());
    let a_g = map3(|c| sigma_ext[c] - sigma_sf[c] * layer.g);
    let b_g = map3(|c| -sigma_sb[c] * layer.g);
    let gamma_g = map3(|c| (a_g[c] * a_g[c] - b_g[c] * b_g[c]).max(0.0).sqrt());
    let max3 = |v: Rgb| v[0].max(v[1]).max(v[2]);
    let fastest = max3(gamma).max(max3(gamma_g));
    let tau = (layer.depth / mu.max(1e-7))
        .min(45.0 / fastest.max(1e-7))
        .min(45.0 / max3(sigma_ext).max(1e-7));
    let x = map3(|c| {
        let s = (gamma[c] * tau).sinh();
        1.0 / ((1.0 + s * s).sqrt() * gamma[c] + s * a[c])
    });
    let x_g = map3(|c| {
        let s = (gamma_g[c] * tau).sinh();
        1.0 / ((1.0 + s * s).sqrt() * gamma_g[c] + s * a_g[c])
    });
    let r_fb = map3(|c| (gamma[c] * tau).sinh() * b[c] * x[c]);
    let t_ff = map3(|c| gamma[c] * x[c]);
    Medium {
        t: map3(|c| (-sigma_ext[c] * tau).exp()),
        r_fb,
        t_ff,
        g_rfb: avg(map3(|c| {
            safe_ratio((gamma_g[c] * tau).sinh() * b_g[c] * x_g[c], r_fb[c])
        })),
        g_tff: avg(map3(|c| safe_ratio(gamma_g[c] * x_g[c], t_ff[c]))),
    }
}

/// What a component contributes: an interface's or a medium's matrices (energy, asymmetry),
/// a substrate, or nothing (an index-matched interface, an empty medium).
enum Step {
    Interface(Matrix6, Matrix6),
    Medium(Matrix6, Matrix6),
    Substrate { r_c: Rgb, g_r: f64 },
    Nothing,
}

/// Evaluates the 6-flux model for view cosine `cos_theta` (§5.5–5.7).
pub fn evaluate(stack: &[LayerParams], cos_theta: f64, fgd: &dyn Fgd, tir: &dyn Tir) -> Evaluation {
    let mut e = Matrix6::identity();
    let mut g = Matrix6::identity();
    let mut prev = [[0.0; 3]; 3];
    let mut prev_g = [[0.0; 3]; 3];
    let (mut g_t0i, mut g_st0i) = (1.0, 1.0);
    let (mut primary, mut backward) = (false, false);
    let mut eta_above = IOR_AIR;
    let mut cos_i = cos_theta;
    let mut transmittance = [0.0; 3];
    let mut lobes = Vec::new();
    for (i, layer) in stack.iter().enumerate() {
        let mut steps = Vec::with_capacity(2);
        if layer.is_conductor() {
            let r_c = map3(|c| {
                fgd.fgd(
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
            if (eta - 1.0).abs() < 1e-5 {
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
                let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
                let (gt, gtp) = (ratio(g_t0j, g_t0i), ratio(g_t0j_rt, g_t0j_r));
                let (gst, gstp) = (ratio(g_st0j, g_st0i), ratio(g_st0j_rt, g_st0j_r));
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
                let m2 = |r: f64, t: f64, rp: f64, tp: f64| {
                    Matrix2::interface([r; 3], [t; 3], [rp; 3], [tp; 3])
                };
                let energy = Matrix6::interface(m2(r, t, rp, tp), m2(rs, ts, rsp, tsp));
                let asym = Matrix6::interface(
                    m2(r * f.g_r, t * gt, rp * f.g_r, tp * gtp),
                    m2(rs * f.g_r, ts * gst, rsp * f.g_r, tsp * gstp),
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
                    Matrix6::medium(m.t, m.r_fb, m.t_ff),
                    Matrix6::medium(m.t, gr, gt),
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
                    (e.extract(r_c).0, g.extract(map3(|c| r_c[c] * g_r)).0)
                }
                Step::Interface(energy, asym) | Step::Medium(energy, asym) => {
                    // Request flags (§5.7): primary after the first interface, backward after
                    // the first medium, forward once both exist.
                    if matches!(step, Step::Interface(..)) {
                        primary = true;
                    } else {
                        backward = true;
                    }
                    e = e.mul(&energy);
                    g = g.mul(&asym);
                    let (up, down) = e.extract([0.0; 3]);
                    transmittance = map3(|c| down[0][c] + down[1][c] + down[2][c]);
                    (up, g.extract([0.0; 3]).0)
                }
                Step::Nothing => {
                    let (up, down) = e.extract([0.0; 3]);
                    transmittance = map3(|c| down[0][c] + down[1][c] + down[2][c]);
                    (up, g.extract([0.0; 3]).0)
                }
            };
            // Primary, secondary-forward, secondary-backward lobes, as the flags allow (§5.7).
            let emit = [primary, primary && backward, backward];
            for k in 0..3 {
                if emit[k] {
                    let g_lobe = avg(map3(|c| {
                        safe_ratio(up_g[k][c] - prev_g[k][c], up[k][c] - prev[k][c])
                    }));
                    lobes.push(Lobe {
                        weight: map3(|c| (up[k][c] - prev[k][c]).max(0.0)),
                        roughness: hg::alpha_of_g(g_lobe.min(1.0)),
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::fgd::ExactFgd;
    use crate::model::tm2::tests::{coat, gold, Rng};
    use crate::model::NoTir;
    use crate::shader::G2;

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
            let n = 1 + (rng.next() * 3.0) as usize;
            let mut stack: Vec<LayerParams> = (0..n)
                .map(|_| {
                    medium(
                        1.05 + rng.next(),
                        rng.next() * 0.8,
                        rng.next(),
                        3.0 * rng.next(),
                        0.0,
                        rng.next() * 1.6 - 0.7,
                    )
                })
                .collect();
            let mu = 0.05 + 0.95 * rng.next();
            let e = evaluate(&stack, mu, &fgd, &NoTir);
            for c in 0..3 {
                let total = e.reflectance[c] + e.transmittance[c];
                assert!(
                    (total - 1.0).abs() < 1e-4,
                    "lossless stack: R + T = {total} for {stack:?} at {mu}"
                );
            }
            stack.push(gold(rng.next()));
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
