//! The model's BRDF in the plane of incidence, binned as the reference bins its paths
//! ([`super::slice_bin`]): each lobe as lamina shades it under a light (`model::light`: a GGX
//! lobe of its roughness normalised to its energy, a diffuse base's lobe Lambertian, and under
//! `transport=corrected` the top interface's lobe with its Fresnel factor), and the same lobes
//! with those from below the top reshaped as the walk's are, the diagnosis of what the slices
//! still miss ([`exit_shaped_slice`]).
//!
//! The paper's lobes are white GGX lobes, where the walk's top interface reflects by Fresnel's
//! factor at each microfacet (which rises across the lobe towards grazing): the corrected
//! transport shades its top lobe so (`Evaluation::top_fresnel`). A lobe from below the top
//! still leaves with a white shape, where the walk's leaves through the top with its
//! transmittance towards each direction (which falls to 0 at grazing); the diagnosis puts that
//! factor in, each lobe renormalised to its energy, so the reference study can say how much
//! of a slice's error is still shape. The dielectric's IOR is the mean over RGB, as the walk
//! takes it.

use std::f64::consts::PI;

use glam::DVec3;

use super::{slice_bin, slice_bin_edges, slice_projected_solid_angle, SLICE_BINS};
use crate::model::fresnel;
use crate::model::light::{
    for_each_lobe_direction, lobe_albedo, lobe_view, unnormalised_lobe, LobeKind, MIN_ALPHA,
};
use crate::model::transport::top_reflects;
use crate::model::{Evaluation, LayerParams, TopFresnel};
use crate::variant::{Ndf, VariantKey};

/// Grid side of each lobe's quadrature.
const LOBE_GRID: u32 = 256;

/// Roughness from which a lobe is integrated over each bin's own midpoint grid.
const BROAD: f64 = 0.05;

/// Side of each bin's midpoint grid (θ × azimuth).
const BIN_GRID: usize = 16;

/// Steps of the midpoint rule that normalises a reshaped Lambertian lobe.
const COSINE_STEPS: usize = 1024;

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
    slice_with(evaluation, mu, variant, None)
}

/// [`model_slice`] with every lobe from below the top interface of `layers` (the stack
/// `evaluation` was made of, in `variant`'s model, its lobes' layers known) times the top's
/// transmittance 1 − F(μ_l) towards the light and renormalised to its energy: the diagnosis of
/// how much of the slice's error is the shape of the light leaving through the top. A stack
/// whose top does not reflect ([`top_reflects`]) is left as it is.
pub fn exit_shaped_slice(
    evaluation: &Evaluation,
    mu: f64,
    variant: VariantKey,
    layers: &[LayerParams],
) -> Vec<[f64; 3]> {
    slice_with(evaluation, mu, variant, top_reflects(layers, variant.model))
}

/// The slice of `evaluation`'s lobes, the top's Fresnel lobe (`Evaluation::top_fresnel`) as
/// lamina shades it; with `exit` (the top's layer and η), every lobe of a layer below it times
/// [`Factor::Exit`] renormalised to its energy.
fn slice_with(
    evaluation: &Evaluation,
    mu: f64,
    variant: VariantKey,
    exit: Option<(usize, f64)>,
) -> Vec<[f64; 3]> {
    let v = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let mut energy = vec![[0.0; 3]; SLICE_BINS];
    let mut diffuse = [0.0; 3];
    for (k, lobe) in evaluation.lobes.iter().enumerate() {
        if lobe.weight.iter().all(|&w| w <= 0.0) {
            continue;
        }
        let (factor, own) = factor_of(evaluation, k, exit);
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
        // The Fresnel lobe is normalised by the model's albedo, as the shaders do.
        let white = match (own, factor) {
            (Some(top), _) => top.albedo,
            (None, Factor::One) => lobe_albedo(variant.g2, mu, alpha),
            _ => quadrature(mu, alpha, kind, &shape),
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

/// ∫ shape(l) dω_l over the quadrature of a lobe of roughness `alpha` and `kind` at view
/// cosine `mu`.
fn quadrature(mu: f64, alpha: f64, kind: LobeKind, shape: &impl Fn(DVec3) -> f64) -> f64 {
    let mut sum = 0.0;
    for_each_lobe_direction(mu, alpha, LOBE_GRID, |l, d_omega| {
        sum += shape(lobe_view(l, kind)) * d_omega;
    });
    sum
}

/// Lobe k's factor in [`slice_with`]: the top's Fresnel lobe its own (returned too), a lobe of
/// a layer below the top `exit`'s, any other none.
fn factor_of(
    evaluation: &Evaluation,
    k: usize,
    exit: Option<(usize, f64)>,
) -> (Factor, Option<TopFresnel>) {
    let own = evaluation.top_fresnel.filter(|t| t.lobe == k);
    let below = |top: usize| evaluation.lobe_layers.get(k).is_some_and(|&l| l > top);
    let factor = match (own, exit) {
        (Some(top), _) => Factor::Fresnel(top.eta),
        (None, Some((top, eta))) if below(top) => Factor::Exit(eta),
        _ => Factor::One,
    };
    (factor, own)
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
    use crate::model::transport;
    use crate::model::NoTir;
    use crate::variant::G2;
    use crate::variant::{Interfaces, Transport};

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
        let stack = [gold(0.3)];
        let e = evaluate(&stack, 0.4);
        assert_eq!(top_reflects(&stack, variant.model), None);
        let plain = model_slice(&e, 0.4, variant);
        assert_eq!(exit_shaped_slice(&e, 0.4, variant, &stack), plain);
    }

    #[test]
    fn an_index_matched_layer_above_the_top_changes_no_slice() {
        // The corrected transport shades the coat's lobe with its Fresnel factor whether or
        // not an index-matched layer (which `lamina simplify` removes) lies above it.
        let variant = VariantKey {
            transport: Transport::Corrected,
            ..VariantKey::default()
        };
        let bare = [coat(1.5, 0.2), gold(0.2)];
        let matched = [coat(1.0, 0.3), coat(1.5, 0.2), gold(0.2)];
        assert_eq!(top_reflects(&matched, variant.model), Some((1, 1.5)));
        let fgd = ExactFgd::new(G2::HeightCorrelated);
        let mu = 0.3;
        let slices = [&bare[..], &matched[..]].map(|stack| {
            let e = transport::evaluate(variant.model, Interfaces::Single, stack, mu, &fgd, &NoTir);
            let top = e.top_fresnel.expect("the coat reflects");
            assert_eq!(e.lobe_layers[top.lobe], stack.len() - 2);
            (
                model_slice(&e, mu, variant),
                exit_shaped_slice(&e, mu, variant, stack),
            )
        });
        let close = |a: &[[f64; 3]], b: &[[f64; 3]]| {
            a.iter()
                .flatten()
                .zip(b.iter().flatten())
                .all(|(x, y)| (x - y).abs() <= 1e-9 * x.abs().max(1e-3))
        };
        assert!(close(&slices[0].0, &slices[1].0), "{:?}", slices);
        assert!(close(&slices[0].1, &slices[1].1), "{:?}", slices);
        assert!(
            !close(&slices[0].0, &slices[0].1),
            "the base's lobe reshaped"
        );
    }

    #[test]
    fn fresnel_leans_the_top_lobe_towards_the_horizon_and_exit_dims_the_base_there() {
        // A rough coat over gold seen at grazing: Fresnel rises across the coat's lobe, so the
        // top's Fresnel lobe is brighter than the white lobe near the horizon on the mirror side
        // and darker towards the normal; the base's lobe leaves with less near the horizon.
        let variant = VariantKey::default();
        let stack = [coat(1.5, 0.3), gold(0.3)];
        let mu = 0.15;
        let e = evaluate(&stack, mu);
        assert_eq!(top_reflects(&stack, variant.model), Some((0, 1.5)));
        let fresnel = Evaluation {
            top_fresnel: Some(TopFresnel {
                lobe: 0,
                eta: 1.5,
                albedo: e.lobes[0].weight[0],
            }),
            ..e.clone()
        };
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
        let top = model_slice(&fresnel, mu, variant);
        assert!(mean(top[horizon]) > 1.05 * mean(plain[horizon]), "{top:?}");
        assert!(mean(top[inner]) < 0.95 * mean(plain[inner]), "{top:?}");
        let exit = exit_shaped_slice(&e, mu, variant, &stack);
        assert!(mean(exit[horizon]) < mean(plain[horizon]), "{exit:?}");
    }
}
