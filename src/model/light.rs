//! Analytic lights on the model's lobes, in f64: the CPU side of `glsl/include/lib/light.glsl`.
//!
//! The model gives, for a view direction, lobes of energy e_k (their directional albedo) and GGX
//! roughness α_k (ALGORITHMS.md §4). Image-based lighting reads each lobe from the prefiltered
//! environment; a light needs the lobe's value in one direction, so each lobe is shaded as the
//! microfacet lobe of its roughness (Walter et al. 2007, "Microfacet Models for Refraction
//! through Rough Surfaces", eq. 20, with the Fresnel factor left out: the model already put
//! the energy in e_k), scaled so that its directional albedo is e_k:
//!
//!   f_k(l, v) = e_k · D(h; α_k) · G2(l, v; α_k) / (4 μ_l μ_v) / E(μ_v; α_k),
//!   E(μ_v; α) = ∫ D G2 / (4 μ_l μ_v) μ_l dω_l,
//!
//! so that ∫ f_k μ_l dω_l = e_k exactly: the lobe's light response carries the energy the
//! model computed, and no more (the white furnace of `tests/suite/lights.rs`). E is the albedo of a
//! white GGX lobe — the A + B of Karis 2013's split sum ("Real Shading in Unreal Engine 4") —
//! with the variant's G2, which the shaders read from a table (`tables::lobe_albedo`). D is
//! the `ndf` axis's form, G2 the `g2` axis's.
//!
//! A lobe the 6-flux model lights around the view (back-scatter, `LOBE_RETRO`) is the same lobe
//! about the view's mirror image v' = 2(n·v)n − v: its peak is at l = v and μ_v' = μ_v.
//!
//! Under `transport=corrected` the top interface's lobe ([`Evaluation::top_fresnel`],
//! `LOBE_FRESNEL`) is that interface's own microfacet lobe, Fresnel's factor kept:
//!
//!   f_0(l, v) = e_0 · D(h; α) · G2(l, v; α) · F(v·h; η) / (4 μ_l μ_v) / A,
//!
//! A the directional albedo the model gave the interface at the view, e_0 / A the transport's
//! ratio: the interface's reflection as the walk has it, whose Fresnel factor rises across
//! the lobe towards grazing (ALGORITHMS.md §17), scaled to the corrected energy. A is
//! ∫ D G2 F / (4 μ_v) dω_l at the lobe's roughness (exactly so for the f64 model, to its
//! table's accuracy for a variant's), so the lobe still integrates to e_0; a light that
//! widens it keeps A.
//!
//! Punctual lights make a mirror's highlight a delta; lobes are shaded at α ≥
//! [`MIN_ALPHA`] ([`MIN_ALPHA_FP16`] under `fp16=on`, where α² must stay a normal half).
//! A directional light of angular radius θ_r (the sun: 0.27°) widens each lobe — the
//! roughness-widening idea of Karis 2013's sphere lights, the half vector moving half as far as
//! the light — in quadrature: α' = min(1, √(α² + tan²(θ_r / 2))). In slope space the disk's half
//! vectors fill a disk of radius w = tan(θ_r / 2), and GGX's slopes within radius w hold
//! w² / (α² + w²) of the lobe, so the lobe averaged over the disk peaks at 1 / (π (α² + w²)):
//! GGX's peak at α'. Karis's linear α + w is wider, and a wider GGX lobe has a heavier tail
//! (∝ α'²), which lit the dark between a studio's lamps (profiling/README.md). The lobe stays
//! normalised at α', so the disk spreads the highlight without adding or removing energy.

use glam::DVec3;

use super::microfacet::{self, masking_shadowing};
use super::{fresnel, Evaluation};
use crate::variant::{Ndf, G2};

/// Smallest roughness a lobe is shaded with under a light (f32 shaders and the oracle).
pub const MIN_ALPHA: f64 = 2e-3;

/// [`MIN_ALPHA`] under `fp16=on`: α² = 1e-4 is a normal half (smallest 6.1e-5).
pub const MIN_ALPHA_FP16: f64 = 1e-2;

/// Grid side of the quadrature [`lobe_albedo`] integrates with ([`for_each_lobe_direction`]).
const ALBEDO_GRID: u32 = 256;

/// How a lobe is oriented: about the mirror direction of the view, or about the view itself;
/// or a diffuse base's Lambertian lobe (`model::diffuse`), the same for every view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    Mirror,
    Retro,
    Diffuse,
}

/// The roughness a lobe of roughness `alpha` is shaded with under a light of angular radius
/// `angular_radius` (radians; 0 for a point or an ideal directional light).
pub fn shading_alpha(alpha: f64, angular_radius: f64, fp16: bool) -> f64 {
    let floor = if fp16 { MIN_ALPHA_FP16 } else { MIN_ALPHA };
    alpha
        .max(floor)
        .hypot((0.5 * angular_radius).tan())
        .min(1.0)
}

/// Calls `f(l, dω)` over an n×n grid of reflected directions for the view
/// v = (√(1 − μ²), 0, μ) and a GGX lobe of roughness `alpha`, where dω is the solid angle the
/// direction l stands for: Σ dω·g(l) ≈ ∫ g(l) dω_l for a g concentrated like the lobe. Only
/// directions above the surface are given.
///
/// The half vector runs over GGX's own measure, D(h)·cos θ_h dω_h = dξ dφ / 2π with
/// ξ = t² / (1 + t²), t = tan θ_h / α (Walter et al. 2007, eq. 35–36), written as
/// ξ = sin² θ′ with θ′ = atan t taken at midpoints of [0, π/2): uniform steps in θ′ put
/// most rows in the lobe's tail, where the reflected direction crosses the horizon and a
/// uniform ξ grid (or a visible-normal grid) has a row or two — those converge near 1e-2,
/// this near 1e-5 for the albedo. Then dω_l = 4 (v·h) dω_h.
pub fn for_each_lobe_direction(mu: f64, alpha: f64, n: u32, mut f: impl FnMut(DVec3, f64)) {
    use std::f64::consts::{FRAC_PI_2, TAU};
    let v = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let (n_f, alpha) = (f64::from(n), alpha.max(1e-6));
    for a in 0..n {
        let theta = FRAC_PI_2 * (f64::from(a) + 0.5) / n_f;
        // dξ = sin 2θ′ dθ′; the φ step is 2π/n and D cos θ_h dω_h = dξ dφ / 2π.
        let d_xi = (2.0 * theta).sin() * FRAC_PI_2 / n_f;
        let t = alpha * theta.tan();
        let cos_h = 1.0 / (1.0 + t * t).sqrt();
        let sin_h = t * cos_h;
        let d_measure = d_xi / n_f;
        let d = microfacet::ggx_d(cos_h, alpha);
        for b in 0..n {
            let phi = TAU * (f64::from(b) + 0.5) / n_f;
            let h = DVec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
            let v_dot_h = v.dot(h);
            if v_dot_h <= 0.0 || d <= 0.0 {
                continue;
            }
            let l = 2.0 * v_dot_h * h - v;
            if l.z > 0.0 {
                f(l, 4.0 * v_dot_h * d_measure / (d * cos_h));
            }
        }
    }
}

/// E(μ; α): the directional albedo of a white GGX lobe with the `g2` form,
/// ∫ D G2 / (4 μ_v) dω_l over [`for_each_lobe_direction`]'s grid.
pub fn lobe_albedo(g2: G2, mu: f64, alpha: f64) -> f64 {
    let mut sum = 0.0;
    for_each_lobe_direction(mu, alpha, ALBEDO_GRID, |l, d_omega| {
        sum += d_omega * unnormalised_lobe(g2, Ndf::Ggx, view(mu), l, alpha);
    });
    sum
}

fn view(mu: f64) -> DVec3 {
    DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// D of the `ndf` form.
pub fn ndf(ndf: Ndf, cos_h: f64, alpha: f64) -> f64 {
    match ndf {
        Ndf::Ggx => microfacet::ggx_d(cos_h, alpha),
        Ndf::Karis => microfacet::ggx_d_karis(cos_h, alpha),
    }
}

/// The microfacet lobe of roughness `alpha` (the shading α, [`shading_alpha`]) without its
/// normalisation, times μ_l: D·G2 / (4 μ_v), for unit directions in the frame where the normal
/// is +z. Zero below the horizon.
pub fn unnormalised_lobe(g2: G2, ndf_form: Ndf, v: DVec3, l: DVec3, alpha: f64) -> f64 {
    if l.z <= 0.0 || v.z <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize();
    ndf(ndf_form, h.z, alpha) * masking_shadowing(g2, l.z, v.z, alpha) / (4.0 * v.z)
}

/// The view a lobe of `kind` is evaluated with: `v`, or its mirror image about the normal.
pub fn lobe_view(v: DVec3, kind: LobeKind) -> DVec3 {
    match kind {
        LobeKind::Mirror | LobeKind::Diffuse => v,
        LobeKind::Retro => DVec3::new(-v.x, -v.y, v.z),
    }
}

/// What a light's response depends on besides the lobes: the variant's microfacet forms and
/// precision, and the light's angular radius (radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightShading {
    pub g2: G2,
    pub ndf: Ndf,
    pub fp16: bool,
    pub angular_radius: f64,
}

/// An evaluation's lobes made ready for lights at one view: each lobe's weight, kind, shading
/// roughness, white albedo E (integrated once here, not per light direction) and, for the
/// top's Fresnel lobe, its interface's η (0 for any other lobe, whose E then normalises it;
/// the Fresnel lobe's E is the model's albedo A).
pub struct LitLobes {
    shading: LightShading,
    v: DVec3,
    lobes: Vec<([f64; 3], LobeKind, f64, f64, f64)>,
}

impl LitLobes {
    /// The lobes of `evaluation`, made at the view v = (√(1 − μ²), 0, μ) (+z is the normal);
    /// `retro_mask` bit k: lobe k is lit around the view.
    pub fn new(shading: LightShading, evaluation: &Evaluation, retro_mask: u32, mu: f64) -> Self {
        let lobes = evaluation
            .lobes
            .iter()
            .enumerate()
            .map(|(k, lobe)| {
                let kind = if lobe.diffuse {
                    LobeKind::Diffuse
                } else if k < 32 && retro_mask & (1 << k) != 0 {
                    LobeKind::Retro
                } else {
                    LobeKind::Mirror
                };
                let alpha = shading_alpha(lobe.roughness, shading.angular_radius, shading.fp16);
                match evaluation.top_fresnel {
                    Some(top) if k == top.lobe => (lobe.weight, kind, alpha, top.albedo, top.eta),
                    _ => (
                        lobe.weight,
                        kind,
                        alpha,
                        lobe_albedo(shading.g2, mu, alpha),
                        0.0,
                    ),
                }
            })
            .collect();
        Self {
            shading,
            v: DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu),
            lobes,
        }
    }

    /// Each lobe's term under a unit-irradiance light from `l`: e_k f_k μ_l (radiance per unit
    /// irradiance, RGB).
    pub fn terms(&self, l: DVec3) -> Vec<[f64; 3]> {
        self.lobes
            .iter()
            .map(|&(weight, kind, alpha, e, eta)| {
                if kind == LobeKind::Diffuse {
                    // Lambertian: μ_l/π, which integrates to 1 over the light directions.
                    return weight.map(|w| w * l.z.max(0.0) / std::f64::consts::PI);
                }
                if e <= 0.0 {
                    return [0.0; 3];
                }
                let v = lobe_view(self.v, kind);
                let mut value = unnormalised_lobe(self.shading.g2, self.shading.ndf, v, l, alpha);
                if eta > 0.0 {
                    value *= fresnel::dielectric(v.dot((v + l).normalize()).max(0.0), eta);
                }
                weight.map(|w| w * value / e)
            })
            .collect()
    }

    /// The light term: Σ_k e_k f_k μ_l ([`LitLobes::terms`], summed).
    pub fn term(&self, l: DVec3) -> [f64; 3] {
        self.terms(l)
            .iter()
            .fold([0.0; 3], |a, t| [a[0] + t[0], a[1] + t[1], a[2] + t[2]])
    }
}

/// [`for_each_lobe_direction`]'s directions and solid angles, collected.
pub fn lobe_quadrature(mu: f64, alpha: f64, n: u32) -> Vec<(DVec3, f64)> {
    let mut out = Vec::with_capacity((n * n) as usize);
    for_each_lobe_direction(mu, alpha, n, |l, d_omega| out.push((l, d_omega)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_normalised_lobe_integrates_to_one() {
        for &g2 in &[G2::HeightCorrelated, G2::Smith, G2::Schlick, G2::Earl] {
            for &(mu, alpha) in &[(0.9, 0.05), (0.5, 0.3), (0.2, 0.7), (0.95, 1.0)] {
                let e = lobe_albedo(g2, mu, alpha);
                for kind in [LobeKind::Mirror, LobeKind::Retro] {
                    let v = lobe_view(view(mu), kind);
                    let sum: f64 = lobe_quadrature(mu, alpha, 128)
                        .iter()
                        .map(|&(l, w)| {
                            // The retro lobe's peak is at the view: integrate it around there.
                            let l = lobe_view(l, kind);
                            w * unnormalised_lobe(g2, Ndf::Ggx, v, l, alpha) / e
                        })
                        .sum();
                    assert!(
                        (sum - 1.0).abs() < 1e-3,
                        "{g2:?} μ={mu} α={alpha} {kind:?}: {sum}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_white_lobe_albedo_is_the_published_split_sum() {
        // A + B of ALGORITHMS.md §12.4 (height-correlated Smith) at perceptual roughness r.
        for (r, mu, expected) in [
            (0.25, 0.5, 0.9557 + 0.0326),
            (0.5, 0.5, 0.8349 + 0.0223),
            (0.5, 1.0, 0.9158),
            (1.0, 0.5, 0.4477 + 0.0030),
            (1.0, 0.1, 0.7364 + 0.0239),
        ] {
            let e = lobe_albedo(G2::HeightCorrelated, mu, r * r);
            assert!(
                (e - expected).abs() < 2e-3,
                "r {r} μ {mu}: {e} vs {expected}"
            );
        }
    }

    #[test]
    fn a_disk_light_widens_and_the_floor_holds() {
        assert_eq!(shading_alpha(0.0, 0.0, false), MIN_ALPHA);
        assert_eq!(shading_alpha(0.0, 0.0, true), MIN_ALPHA_FP16);
        let sun = 0.27_f64.to_radians();
        let w = (0.5 * sun).tan();
        assert!((shading_alpha(0.1, sun, false) - (0.01 + w * w).sqrt()).abs() < 1e-15);
        assert_eq!(shading_alpha(0.9, 1.0, false), 1.0);
    }

    /// The widened lobe's peak is the lobe's mean over the disk's half vectors in slope space:
    /// GGX's slope density D·cos⁴θ_h averaged over the slopes within w = tan(θ_r/2) (the area
    /// element dω / cos³θ_h), against D at α' at the centre, where Karis's linear α + w is
    /// 1.2–2.0× too low in these cases.
    #[test]
    fn the_widened_lobe_peaks_where_the_disk_averaged_lobe_does() {
        for (alpha, radius_deg) in [(0.05, 6.0), (0.05, 2.0), (0.2, 12.0), (0.3, 4.0)] {
            let radius = f64::to_radians(radius_deg);
            let cap = (0.5 * radius).tan().atan();
            let n = 20_000;
            let (mut lobe, mut slope_area) = (0.0, 0.0);
            for i in 0..n {
                let theta = cap * (f64::from(i) + 0.5) / f64::from(n);
                let (c, ring) = (theta.cos(), theta.sin() * cap / f64::from(n));
                lobe += microfacet::ggx_d(c, alpha) * c * ring;
                slope_area += ring / (c * c * c);
            }
            let mean = lobe / slope_area;
            let peak = microfacet::ggx_d(1.0, shading_alpha(alpha, radius, false));
            assert!(
                (peak / mean - 1.0).abs() < 0.02,
                "α {alpha}, radius {radius_deg}°: widened peak {peak}, disk mean {mean}"
            );
        }
    }
}
