//! The random walk on a rough interface's microsurface (Heitz, Hanika, d'Eon & Dachsbacher
//! 2016, "Multiple-scattering microfacet BSDFs with the Smith model"): the interface mode
//! `interfaces=multiple` of the reference's walk and of the discrete-ordinates transport.
//!
//! The microsurface is the Smith model's: microfacet normals from the GGX distribution, heights
//! independent of the normals, and a ray meets the surface as Smith's masking says — a ray
//! leaving height h along w escapes with probability C₁(h)^Λ(w) (upward), and otherwise meets
//! it at the height whose probability follows from the same law (§4 of the paper). At each
//! meeting the ray sees a normal from the distribution of visible normals and scatters by that
//! microfacet's Fresnel: a dielectric reflects or refracts, a conductor reflects and keeps the
//! Fresnel factor. The walk goes on until the ray leaves the microsurface, so nothing is lost
//! to masking: a lossless dielectric reflects and transmits all the energy it receives, and a
//! conductor loses only what its Fresnel absorbs. Its first scattering order is exactly the
//! single-scattering BSDF with the height-correlated masking-shadowing term.
//!
//! Heights are uniform on [−1, 1]: the walk's result does not depend on the height
//! distribution (§4.1 of the paper), and the uniform one inverts in closed form. A refracted
//! ray continues on the other side of the same microsurface; the walk then flips the frame
//! (z and heights negated), which leaves the Smith statistics unchanged, so one routine
//! serves both sides.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::model::fresnel;
use crate::model::microfacet::{reflect, smith_lambda};
use crate::model::random::Rng;

/// Scattering events on one microsurface after which a path is given up and counted as
/// unresolved. At α = 1 and grazing incidence a dielectric's walk averages a few events; this
/// many leave a fraction far below any estimate's standard error.
pub const MAX_BOUNCES: u32 = 10_000;

/// Roughness floor of the walk: below it the visible-normal sampler's stretch degenerates at
/// grazing directions, and the surface is a mirror to far better than any estimate resolves.
const MIN_ALPHA: f64 = 1e-6;

/// How a walk on a microsurface ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exit {
    /// Left the microsurface along this direction (the incident side's frame: z > 0 is back
    /// where the ray came from) with this fraction of its energy.
    Left(DVec3, f64),
    /// Still on the microsurface after [`MAX_BOUNCES`] events, with this fraction.
    Unresolved(f64),
}

/// C₁ of the uniform height distribution on [−1, 1].
fn c1(h: f64) -> f64 {
    (0.5 * (h + 1.0)).clamp(0.0, 1.0)
}

fn inverse_c1(u: f64) -> f64 {
    (2.0 * u - 1.0).clamp(-1.0, 1.0)
}

/// Smith's Λ for a direction on either side of the macro-surface: Λ(w) above, −1 − Λ(−w)
/// below (the paper's Eq. 12).
fn lambda(w: DVec3, alpha: f64) -> f64 {
    if w.z >= 0.0 {
        smith_lambda(w.z, alpha)
    } else {
        -1.0 - smith_lambda(-w.z, alpha)
    }
}

/// The height of the ray leaving height `h` along `w` where it next meets the microsurface,
/// or `None` when it leaves it (only upward rays can); `u` uniform in [0, 1).
fn next_height(w: DVec3, h: f64, alpha: f64, u: f64) -> Option<f64> {
    let l = lambda(w, alpha);
    if w.z > 0.0 {
        // Unmasked with probability C₁(h)^Λ: the ray escapes.
        if l <= 0.0 || u >= 1.0 - c1(h).powf(l) {
            return None;
        }
    }
    Some(inverse_c1(c1(h) / (1.0 - u).powf(1.0 / l)))
}

/// A microfacet normal from the distribution of normals visible from `wi` (unit, on either
/// side of the macro-surface), D_wi(m) ∝ max(0, wi·m) D(m), by spherical caps (Dupuy &
/// Benyoub 2023, "Sampling visible GGX normals with spherical caps"): in the configuration
/// stretched to α = 1 the visible normals are those of a hemisphere, and normalize(c + v) with
/// c uniform on the unit sphere's cap above −v.z gives them for any v, below the horizon too.
pub fn visible_normal(wi: DVec3, alpha: f64, u: (f64, f64)) -> DVec3 {
    let v = DVec3::new(alpha * wi.x, alpha * wi.y, wi.z).normalize();
    let phi = TAU * u.0;
    let z = (1.0 - u.1) * (1.0 + v.z) - v.z;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let h = DVec3::new(s * phi.cos(), s * phi.sin(), z) + v;
    DVec3::new(alpha * h.x, alpha * h.y, h.z.max(0.0)).normalize()
}

/// Mirror through the macro-surface's plane: the other side's frame.
fn flip(w: DVec3) -> DVec3 {
    DVec3::new(w.x, w.y, -w.z)
}

/// A rough dielectric interface walked from the incident side: `wi` points back to where the
/// light comes from (wi.z > 0), `eta` is the other side's IOR over the incident side's. The
/// exit direction has z > 0 for reflection and z < 0 for transmission; the energy is kept.
pub fn dielectric(wi: DVec3, eta: f64, alpha: f64, rng: &mut Rng) -> Exit {
    dielectric_walk(wi, eta, alpha, rng, MAX_BOUNCES)
}

/// [`dielectric`] given up after `bounces` events.
fn dielectric_walk(wi: DVec3, eta: f64, alpha: f64, rng: &mut Rng, bounces: u32) -> Exit {
    let alpha = alpha.max(MIN_ALPHA);
    let mut w = -wi;
    let mut h = 1.0;
    let mut outside = true;
    for bounce in 0..=bounces {
        match next_height(w, h, alpha, rng.unit()) {
            None => return Exit::Left(if outside { w } else { flip(w) }, 1.0),
            Some(_) if bounce == bounces => break,
            Some(next) => h = next,
        }
        let v = -w;
        let m = visible_normal(v, alpha, (rng.unit(), rng.unit()));
        let e = if outside { eta } else { 1.0 / eta };
        let cos = v.dot(m).clamp(0.0, 1.0);
        if rng.unit() < fresnel::dielectric(cos, e) {
            w = reflect(v, m);
        } else {
            let ct2 = (1.0 - (1.0 - cos * cos) / (e * e)).max(0.0);
            let t = (-v / e + (cos / e - ct2.sqrt()) * m).normalize();
            w = flip(t);
            h = -h;
            outside = !outside;
        }
    }
    Exit::Unresolved(1.0)
}

/// A rough conductor of relative complex IOR η + iκ walked from above (wi.z > 0): the exit
/// direction (z > 0) and the product of the Fresnel factors of the path's reflections.
pub fn conductor(wi: DVec3, eta: f64, kappa: f64, alpha: f64, rng: &mut Rng) -> Exit {
    conductor_walk(wi, eta, kappa, alpha, rng, MAX_BOUNCES)
}

/// [`conductor`] given up after `bounces` events.
fn conductor_walk(
    wi: DVec3,
    eta: f64,
    kappa: f64,
    alpha: f64,
    rng: &mut Rng,
    bounces: u32,
) -> Exit {
    let alpha = alpha.max(MIN_ALPHA);
    let mut w = -wi;
    let mut h = 1.0;
    let mut energy = 1.0;
    for bounce in 0..=bounces {
        match next_height(w, h, alpha, rng.unit()) {
            None => return Exit::Left(w, energy),
            Some(_) if bounce == bounces => break,
            Some(next) => h = next,
        }
        let v = -w;
        let m = visible_normal(v, alpha, (rng.unit(), rng.unit()));
        energy *= fresnel::conductor(v.dot(m).clamp(0.0, 1.0), eta, kappa);
        w = reflect(v, m);
    }
    Exit::Unresolved(energy)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::diffuse::gauss_legendre_unit;
    use crate::model::fgd::ExactFgd;
    use crate::model::light::lobe_albedo;
    use crate::model::microfacet::sample_vndf;
    use crate::model::{Fgd, LayerParams};
    use crate::variant::G2;

    #[test]
    fn visible_normals_match_the_hemisphere_sampler_above_the_horizon() {
        // Same distribution as Heitz 2018's sampler for directions above: the means of m agree.
        let mut rng = Rng(11);
        for (wi, alpha) in [
            (DVec3::new(0.6, 0.0, 0.8), 0.3),
            (DVec3::new(0.99, 0.0, 0.141).normalize(), 0.8),
        ] {
            let n = 200_000;
            let (mut a, mut b) = (DVec3::ZERO, DVec3::ZERO);
            for _ in 0..n {
                a += visible_normal(wi, alpha, (rng.unit(), rng.unit()));
                b += sample_vndf(wi, (rng.unit(), rng.unit()), alpha);
            }
            let d = (a - b) / f64::from(n);
            // Each component's variance is at most 1: 5 standard errors of the difference.
            assert!(
                d.abs().max_element() < 5.0 * (2.0 / f64::from(n)).sqrt(),
                "{d}"
            );
        }
    }

    #[test]
    fn visible_normals_face_the_direction_from_either_side() {
        let mut rng = Rng(3);
        for wi in [
            DVec3::new(0.6, 0.0, -0.8),
            DVec3::new(-0.3, 0.95, -0.1).normalize(),
            DVec3::new(0.01, 0.0, -1.0).normalize(),
        ] {
            for _ in 0..10_000 {
                let m = visible_normal(wi, 0.5, (rng.unit(), rng.unit()));
                assert!(m.z >= 0.0 && wi.dot(m) >= -1e-12, "{wi} {m}");
                assert!((m.length() - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn a_downward_ray_always_meets_the_surface_below_it() {
        let mut rng = Rng(5);
        let w = DVec3::new(0.8, 0.0, -0.6);
        for _ in 0..1000 {
            let h = rng.range(-1.0, 1.0);
            let next = next_height(w, h, 0.4, rng.unit()).expect("downward rays meet it");
            assert!(next <= h);
        }
        // A vertical upward ray on a smooth surface escapes.
        assert_eq!(next_height(DVec3::Z, -0.5, 0.0, 0.7), None);
    }

    #[test]
    fn a_smooth_interface_refracts_by_snell_and_reflects_by_fresnel() {
        // α = 0 walks at the floor α 1e-6, whose GGX normals tilt by more than t with
        // probability about (α/t)²: at t = 0.01 no path in this many does.
        let mut rng = Rng(9);
        let wi = DVec3::new(0.6, 0.0, 0.8);
        let mut reflected = 0;
        let n = 100_000;
        for _ in 0..n {
            match dielectric(wi, 1.5, 0.0, &mut rng) {
                Exit::Left(wo, e) => {
                    assert_eq!(e, 1.0);
                    if wo.z > 0.0 {
                        reflected += 1;
                        assert!((wo - DVec3::new(-0.6, 0.0, 0.8)).length() < 1e-2, "{wo}");
                    } else {
                        let sin_t = (1.0 - wo.z * wo.z).sqrt();
                        assert!((1.5 * sin_t - 0.6).abs() < 1e-2, "{wo}");
                    }
                }
                Exit::Unresolved(_) => panic!("a smooth interface resolves at once"),
            }
        }
        let f = fresnel::dielectric(0.8, 1.5);
        let p = f64::from(reflected) / f64::from(n);
        assert!((p - f).abs() < 5.0 * (f * (1.0 - f) / f64::from(n)).sqrt());
    }

    fn view(mu: f64) -> DVec3 {
        DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
    }

    /// Mean and standard error of `f` over `n` draws.
    fn mean(n: u32, mut f: impl FnMut() -> f64) -> (f64, f64) {
        let (mut sum, mut sq) = (0.0, 0.0);
        for _ in 0..n {
            let x = f();
            sum += x;
            sq += x * x;
        }
        let n = f64::from(n);
        let m = sum / n;
        (m, ((sq / n - m * m).max(0.0) / n).sqrt())
    }

    fn energy(exit: Exit) -> f64 {
        match exit {
            Exit::Left(_, e) => e,
            Exit::Unresolved(_) => 0.0,
        }
    }

    #[test]
    fn the_first_order_is_the_single_scattering_fgd() {
        // Paths that leave after one event: the microfacet BSDF with the height-correlated
        // masking-shadowing term, whose albedo the exact FGD integrates (to 1e-3).
        let fgd = ExactFgd::new(G2::HeightCorrelated);
        let gold = LayerParams::gold(0.0);
        let mut rng = Rng(21);
        for (mu, alpha) in [(0.9, 0.3), (0.3, 0.8), (0.6, 1.0)] {
            let (eta, kappa) = (gold.ior[1], gold.kappa[1]);
            let (e, se) = mean(100_000, || {
                energy(conductor_walk(view(mu), eta, kappa, alpha, &mut rng, 1))
            });
            let exact = fgd.fgd(mu, alpha, eta, kappa);
            assert!(
                (e - exact).abs() <= 4.0 * se + 1e-3,
                "conductor μ {mu} α {alpha}: {e} ± {se} against {exact}"
            );
            let (r, se) = mean(100_000, || {
                match dielectric_walk(view(mu), 1.5, alpha, &mut rng, 1) {
                    Exit::Left(wo, e) if wo.z > 0.0 => e,
                    _ => 0.0,
                }
            });
            let exact = fgd.fgd(mu, alpha, 1.5, 0.0);
            assert!(
                (r - exact).abs() <= 4.0 * se + 1e-3,
                "dielectric μ {mu} α {alpha}: {r} ± {se} against {exact}"
            );
        }
    }

    #[test]
    fn a_perfect_conductor_and_a_lossless_dielectric_keep_every_path() {
        // κ = 10⁶: each reflection keeps all but about 10⁻⁸ of the energy.
        let mut rng = Rng(5);
        for alpha in [0.05, 0.5, 1.0] {
            for mu in [1.0, 0.4, 0.05] {
                for _ in 0..20_000 {
                    match conductor(view(mu), 1.0, 1e6, alpha, &mut rng) {
                        Exit::Left(wo, e) => assert!(wo.z > 0.0 && e > 1.0 - 1e-6, "{wo} {e}"),
                        Exit::Unresolved(_) => panic!("unresolved at α {alpha}, μ {mu}"),
                    }
                    for eta in [1.5, 1.0 / 1.5] {
                        match dielectric(view(mu), eta, alpha, &mut rng) {
                            Exit::Left(_, e) => assert_eq!(e, 1.0),
                            Exit::Unresolved(_) => panic!("unresolved at α {alpha}, μ {mu}"),
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_nearly_white_conductor_meets_kulla_and_conty() {
        // Kulla & Conty 2017 ("Revisiting physically based shading at Imageworks", SIGGRAPH
        // course) compute the multiple-scattering albedo independently of any walk: the single-
        // scattering albedo E_F(μ) plus (1 − E(μ)) F̄² Ē / (1 − F̄ (1 − Ē)), with E the white
        // albedo, Ē and F̄ the cosine-weighted hemispherical averages of E and of the
        // Fresnel. Their approximations — every later event sees F̄, and the orders fall
        // geometrically with Ē — are tight for a conductor whose Fresnel varies little and for
        // α ≤ 0.5, where the multiple-scattering share 1 − E stays below 0.4: there the two
        // agree to 1 %. (At α = 1 the geometric orders undercount: 2–4 % for aluminium;
        // gold's blue channel, whose Fresnel doubles towards grazing, is further off.)
        let aluminium = LayerParams {
            ior: [1.66058, 0.88143, 0.521467],
            kappa: [9.2282, 6.27077, 4.83803],
            ..LayerParams::gold(0.0)
        };
        let fgd = ExactFgd::new(G2::HeightCorrelated);
        let q = gauss_legendre_unit(32);
        let hemispherical =
            |f: &dyn Fn(f64) -> f64| -> f64 { q.iter().map(|&(m, w)| 2.0 * w * m * f(m)).sum() };
        let mut rng = Rng(17);
        for alpha in [0.1, 0.25, 0.5] {
            let white = |mu: f64| lobe_albedo(G2::HeightCorrelated, mu, alpha);
            let e_avg = hemispherical(&white);
            for c in 0..3 {
                let (eta, kappa) = (aluminium.ior[c], aluminium.kappa[c]);
                let f_avg = hemispherical(&|m| fresnel::conductor(m, eta, kappa));
                for mu in [1.0, 0.5, 0.2] {
                    let kc = fgd.fgd(mu, alpha, eta, kappa)
                        + (1.0 - white(mu)) * f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
                    let (e, se) = mean(100_000, || {
                        energy(conductor(view(mu), eta, kappa, alpha, &mut rng))
                    });
                    assert!(
                        (e - kc).abs() <= 4.0 * se + 0.01 * kc,
                        "α {alpha}, channel {c}, μ {mu}: walk {e} ± {se}, Kulla–Conty {kc}"
                    );
                }
            }
        }
    }
}
