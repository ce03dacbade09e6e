//! The model's BRDF in the plane of incidence, binned as the reference bins its paths
//! ([`super::slice_bin`]): each lobe as lamina shades it under a light (`model::light`: a GGX
//! lobe of its roughness normalised to its energy, a diffuse base's lobe Lambertian), and the
//! same lobes reshaped as the walk's are, the diagnosis of what the slices still miss
//! ([`Shaping`]).
//!
//! The model's lobes keep the paper's shapes whatever their energies: a rough lobe is a white
//! GGX lobe, where the walk's top interface reflects by Fresnel's factor at each microfacet
//! (which rises across the lobe towards grazing), and a lobe from below the top leaves through
//! it with the top's transmittance towards each direction (which falls to 0 at grazing).
//! [`Shaping`] puts either factor into the lobes, each lobe renormalised to its energy, so the
//! reference study can say how much of a slice's error is shape and how much is energy. The
//! dielectric's IOR is the mean over RGB, as the walk takes it.

use std::f64::consts::PI;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::{slice_bin, slice_bin_edges, slice_projected_solid_angle, SLICE_BINS};
use crate::model::fresnel;
use crate::model::light::{
    for_each_lobe_direction, lobe_albedo, lobe_view, unnormalised_lobe, LobeKind, MIN_ALPHA,
};
use crate::model::{Evaluation, LayerParams, INDEX_MATCHED};
use crate::variant::{Ndf, VariantKey};

/// Grid side of each lobe's quadrature.
const LOBE_GRID: u32 = 256;

/// Roughness from which a lobe is integrated over each bin's own midpoint grid.
const BROAD: f64 = 0.05;

/// Side of each bin's midpoint grid (θ × azimuth).
const BIN_GRID: usize = 16;

/// Steps of the midpoint rule that normalises a reshaped Lambertian lobe.
const COSINE_STEPS: usize = 1024;

/// How the diagnosis reshapes a stack's lobes (under a reflecting dielectric top; otherwise
/// nothing changes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shaping {
    /// The top interface's lobe times the top's Fresnel factor F(v·h).
    TopFresnel,
    /// Every lobe from below the top times the top's transmittance 1 − F(μ_l) towards l.
    Exit,
    /// Both.
    Both,
}

/// The corrected model's slice errors under each [`Shaping`] (`ReferenceRow::slice_error`'s
/// measure), beside the unshaped one the row holds.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize)]
pub struct ShapedErrors {
    pub top_fresnel: f64,
    pub exit: f64,
    pub both: f64,
}

/// What multiplies one lobe before it is renormalised to its energy.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Factor {
    One,
    /// F(v·h) of a dielectric of relative IOR η.
    Fresnel(f64),
    /// 1 − F(μ_l) of a dielectric of relative IOR η.
    Exit(f64),
}

impl Factor {
    fn at(self, v: DVec3, l: DVec3) -> f64 {
        match self {
            Self::One => 1.0,
            Self::Fresnel(eta) => fresnel::dielectric(v.dot((v + l).normalize()), eta),
            Self::Exit(eta) => 1.0 - fresnel::dielectric(l.z, eta),
        }
    }
}

/// The model's BRDF per slice bin: each lobe of `evaluation` (made at view cosine `mu`)
/// integrated over the bin, over its projected solid angle.
///
/// A lobe at least [`BROAD`] rough is integrated over each bin's own midpoint grid
/// ([`BIN_GRID`]² points in θ and azimuth); a sharper one over its own quadrature, each point's
/// energy landing in the bin of its direction (a bin grid would miss its peak; its quadrature's
/// azimuths, once they fall inside the slice, all do: it is narrow beside the slice's width).
pub fn model_slice(evaluation: &Evaluation, mu: f64, variant: VariantKey) -> Vec<[f64; 3]> {
    let factors = vec![Factor::One; evaluation.lobes.len()];
    slice_with(evaluation, mu, variant, &factors)
}

/// [`model_slice`] with the lobes reshaped by `shaping` under the top layer `top` of the
/// stack `evaluation` was made of. The top interface's lobe is the evaluation's first, when
/// the top is a dielectric that reflects (both models emit it first).
pub fn shaped_slice(
    evaluation: &Evaluation,
    mu: f64,
    variant: VariantKey,
    top: &LayerParams,
    shaping: Shaping,
) -> Vec<[f64; 3]> {
    let eta = (top.ior[0] + top.ior[1] + top.ior[2]) / 3.0;
    let reflects =
        !top.is_conductor() && top.diffuse.is_none() && (eta - 1.0).abs() >= INDEX_MATCHED;
    let top_lobe = reflects && evaluation.lobe_layers.first() == Some(&0);
    let factors: Vec<Factor> = (0..evaluation.lobes.len())
        .map(|k| match (reflects, top_lobe && k == 0, shaping) {
            (false, _, _) => Factor::One,
            (true, true, Shaping::TopFresnel | Shaping::Both) => Factor::Fresnel(eta),
            (true, true, Shaping::Exit) => Factor::One,
            (true, false, Shaping::TopFresnel) => Factor::One,
            (true, false, Shaping::Exit | Shaping::Both) => Factor::Exit(eta),
        })
        .collect();
    slice_with(evaluation, mu, variant, &factors)
}

/// The slice of `evaluation`'s lobes, lobe k times `factors[k]` renormalised to its energy.
fn slice_with(
    evaluation: &Evaluation,
    mu: f64,
    variant: VariantKey,
    factors: &[Factor],
) -> Vec<[f64; 3]> {
    let v = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let mut energy = vec![[0.0; 3]; SLICE_BINS];
    let mut diffuse = [0.0; 3];
    for ((k, lobe), &factor) in evaluation.lobes.iter().enumerate().zip(factors) {
        if lobe.weight.iter().all(|&w| w <= 0.0) {
            continue;
        }
        let mut add = |i: usize, e: f64| {
            for (sum, w) in energy[i].iter_mut().zip(lobe.weight) {
                *sum += w * e;
            }
        };
        if lobe.diffuse {
            if factor == Factor::One {
                // ρ/π everywhere: the same in every bin.
                for (d, w) in diffuse.iter_mut().zip(lobe.weight) {
                    *d += w / PI;
                }
            } else {
                let g = |l: DVec3| factor.at(l, l) * l.z / PI;
                let norm = lambertian_norm(factor);
                for i in 0..SLICE_BINS {
                    add(i, bin_integral(i, &g) / norm);
                }
            }
            continue;
        }
        let kind = if k < 32 && evaluation.retro_mask & (1 << k) != 0 {
            LobeKind::Retro
        } else {
            LobeKind::Mirror
        };
        let alpha = lobe.roughness.max(MIN_ALPHA);
        let lobe_v = lobe_view(v, kind);
        // f·μ_l of this lobe per unit weight, before its normalisation.
        let shape = |l: DVec3| {
            unnormalised_lobe(variant.g2, Ndf::Ggx, lobe_v, l, alpha) * factor.at(lobe_v, l)
        };
        let white = if factor == Factor::One {
            lobe_albedo(variant.g2, mu, alpha)
        } else {
            let mut sum = 0.0;
            for_each_lobe_direction(mu, alpha, LOBE_GRID, |l, d_omega| {
                sum += shape(lobe_view(l, kind)) * d_omega;
            });
            sum
        };
        if white <= 0.0 {
            continue;
        }
        let term = |l: DVec3| shape(l) / white;
        if alpha >= BROAD {
            for i in 0..SLICE_BINS {
                add(i, bin_integral(i, &term));
            }
        } else {
            for_each_lobe_direction(mu, alpha, LOBE_GRID, |l, d_omega| {
                // The grid follows the mirror lobe; a retro lobe is its mirror image.
                let l = lobe_view(l, kind);
                if let Some(i) = slice_bin(l) {
                    add(i, term(l) * d_omega);
                }
            });
        }
    }
    (0..SLICE_BINS)
        .map(|i| {
            let omega = slice_projected_solid_angle(i);
            std::array::from_fn(|c| energy[i][c] / omega + diffuse[c])
        })
        .collect()
}

/// ∫ factor(l) μ_l / π dω_l over the hemisphere (a factor of μ_l alone): 2 ∫ factor μ dμ.
fn lambertian_norm(factor: Factor) -> f64 {
    let n = COSINE_STEPS as f64;
    (0..COSINE_STEPS)
        .map(|j| {
            let mu = (j as f64 + 0.5) / n;
            let l = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            2.0 * factor.at(l, l) * mu / n
        })
        .sum()
}

/// ∫ g(l) dω over slice bin `i` by a [`BIN_GRID`]² midpoint rule.
fn bin_integral(i: usize, g: &impl Fn(DVec3) -> f64) -> f64 {
    let (a, b) = slice_bin_edges(i);
    let half = super::SLICE_HALF_WIDTH_DEG.to_radians();
    let n = BIN_GRID as f64;
    let (d_theta, d_phi) = ((b - a) / n, 2.0 * half / n);
    let mut sum = 0.0;
    for p in 0..BIN_GRID {
        let signed = a + (p as f64 + 0.5) * d_theta;
        let theta = signed.abs();
        let (sin, cos) = theta.sin_cos();
        // Positive θ on the mirror side (−x), negative on the view's side (+x).
        let side = if signed >= 0.0 { -1.0 } else { 1.0 };
        for q in 0..BIN_GRID {
            let phi = -half + (q as f64 + 0.5) * d_phi;
            let l = DVec3::new(side * sin * phi.cos(), sin * phi.sin(), cos);
            sum += g(l) * sin * d_theta * d_phi;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::fgd::ExactFgd;
    use crate::model::tm2::{self, tests::coat, tests::gold};
    use crate::model::NoTir;
    use crate::variant::G2;

    fn evaluate(stack: &[LayerParams], mu: f64) -> Evaluation {
        tm2::evaluate(stack, mu, &ExactFgd::new(G2::HeightCorrelated), &NoTir)
    }

    #[test]
    fn a_reshaped_lambertian_lobe_is_normalised_by_what_the_top_transmits() {
        assert!((lambertian_norm(Factor::One) - 1.0).abs() < 1e-6);
        // Glass reflects 9.18 % of diffuse light from outside (Fresnel's cosine-weighted
        // hemispherical average at η = 1.5): a Lambertian lobe leaving through it keeps the rest.
        let norm = lambertian_norm(Factor::Exit(1.5));
        assert!((norm - (1.0 - 0.0918)).abs() < 1e-3, "{norm}");
    }

    #[test]
    fn shaping_leaves_a_stack_without_a_reflecting_top_alone() {
        let variant = VariantKey::default();
        let matched = [coat(1.0, 0.3), coat(1.5, 0.2), gold(0.2)];
        for stack in [&[gold(0.3)][..], &matched[..]] {
            let e = evaluate(stack, 0.4);
            let plain = model_slice(&e, 0.4, variant);
            for shaping in [Shaping::TopFresnel, Shaping::Exit, Shaping::Both] {
                assert_eq!(shaped_slice(&e, 0.4, variant, &stack[0], shaping), plain);
            }
        }
    }

    #[test]
    fn fresnel_leans_the_top_lobe_towards_the_horizon_and_exit_dims_the_base_there() {
        // A rough coat over gold seen at grazing: Fresnel rises across the coat's lobe, so the
        // reshaped slice is brighter than the plain one near the horizon on the mirror side and
        // darker towards the normal; the base's lobe leaves with less near the horizon.
        let variant = VariantKey::default();
        let stack = [coat(1.5, 0.3), gold(0.3)];
        let mu = 0.15;
        let e = evaluate(&stack, mu);
        let plain = model_slice(&e, mu, variant);
        let mean = |b: [f64; 3]| (b[0] + b[1] + b[2]) / 3.0;
        let bin = |deg: f64| {
            slice_bin(DVec3::new(
                -deg.to_radians().sin(),
                0.0,
                deg.to_radians().cos(),
            ))
        };
        let (horizon, inner) = (bin(87.0).expect("bin"), bin(50.0).expect("bin"));
        let top = shaped_slice(&e, mu, variant, &stack[0], Shaping::TopFresnel);
        assert!(mean(top[horizon]) > 1.05 * mean(plain[horizon]), "{top:?}");
        assert!(mean(top[inner]) < 0.95 * mean(plain[inner]), "{top:?}");
        let exit = shaped_slice(&e, mu, variant, &stack[0], Shaping::Exit);
        assert!(mean(exit[horizon]) < mean(plain[horizon]), "{exit:?}");
    }
}
