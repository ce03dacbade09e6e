//! One light path through a layer stack, in f64: the random walk [`super`] averages.
//!
//! The stack as the walk sees it: boundaries top to bottom (rough dielectric interfaces, an
//! index-matched interface that light crosses untouched, the conductor or Lambertian base, or
//! the open bottom of a stack that transmits) with a slab between each pair (a homogeneous
//! medium under `tm6`, or nothing). A path starts above the top boundary, travelling against
//! the view, and ends when it leaves above (reflected) or below (transmitted), is absorbed, or
//! loses its energy to the interfaces' single scattering.
//!
//! A rough boundary scatters in one of two modes ([`Interfaces`]):
//! - `single`: the single-scattering microfacet BSDF (Walter et al. 2007) sampled through its
//!   visible normals (Heitz 2018, [`microfacet::sample_vndf`]): at a normal m drawn for the
//!   incident direction, reflect with probability F(i·m) (exact dielectric Fresnel, total
//!   internal reflection included) or refract. The path keeps G2/G1(i): the reflection masking
//!   of the model's FGD (the `g2` form) for reflections, separable Smith G1(o) for
//!   transmissions (Walter's form; the model has no transmission masking: it sets t = 1 − r).
//!   A direction sampled below the side it should leave by is single scattering's loss. The
//!   conductor reflects with its exact complex Fresnel and the same masking.
//! - `multiple`: the walk on the microsurface ([`microsurface`]), which loses nothing to
//!   masking (its masking is Smith's height-correlated form whatever `g2` says).
//!
//! The Lambertian base reflects its albedo into a cosine-distributed direction. In a medium,
//! flight distances are drawn from the extinction, each collision keeps the single-scattering
//! albedo σs/σt and turns the path by Henyey–Greenstein's phase function. Every arrival at a
//! boundary is tallied by its order ([`flows`]).
//!
//! [`microfacet::sample_vndf`]: crate::model::microfacet::sample_vndf
//! [`microsurface`]: crate::model::microsurface
//! [`flows`]: super::flows

use glam::DVec3;

use crate::model::fresnel;
use crate::model::microfacet::{masking_shadowing, reflect, sample_vndf, smith_lambda};
use crate::model::random::Rng;
use crate::model::{LayerParams, INDEX_MATCHED, IOR_AIR};
use crate::variant::{Interfaces, G2};

use super::flows::{Arrivals, Fate, Flows, Side, MAX_BOUNDARIES};
use crate::model::microsurface::{self, Exit};

/// Events (boundary crossings and collisions) after which a path is given up and its energy
/// counted as unresolved rather than guessed: a path in a thick, nearly lossless medium can
/// wander for millions of collisions.
pub const MAX_EVENTS: u32 = 100_000;

/// Below this energy a path plays Russian roulette: it survives with probability w / this and
/// carries this energy on (unbiased; it only stops spending time on faint paths).
const ROULETTE_BELOW: f64 = 0.05;

/// What separates two slabs.
#[derive(Clone, Copy, Debug)]
enum Boundary {
    /// A rough dielectric interface: IOR above and below, GGX α.
    Dielectric { above: f64, below: f64, alpha: f64 },
    /// An index-matched interface: light crosses it unchanged (the model skips it too).
    Pass,
    /// The conductor base: relative complex IOR per channel, GGX α.
    Conductor {
        eta: [f64; 3],
        kappa: [f64; 3],
        alpha: f64,
    },
    /// A Lambertian base of this albedo.
    Lambert([f64; 3]),
    /// The bottom of a stack that transmits: light reaching it is transmitted.
    Open,
}

/// A homogeneous medium between two boundaries (depth 0: nothing).
#[derive(Clone, Copy, Debug, Default)]
struct Slab {
    depth: f64,
    sigma_s: [f64; 3],
    sigma_t: [f64; 3],
    g: f64,
}

/// How a path ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// Left the stack upward in this direction, with this energy.
    Reflected(DVec3, f64),
    /// Left through the open bottom in this direction, with this energy.
    Transmitted(DVec3, f64),
    /// Absorbed, lost to single scattering, or ended by Russian roulette.
    Lost,
    /// Still travelling after [`MAX_EVENTS`] events, with this energy.
    Unresolved(f64),
}

/// A layer stack made ready for walking.
#[derive(Clone, Debug)]
pub struct Walker {
    boundaries: Vec<Boundary>,
    slabs: Vec<Slab>,
    g2: G2,
    interfaces: Interfaces,
}

/// What a boundary did with a path.
enum Event {
    /// It left along this direction with this fraction of its energy.
    Out(DVec3, f64),
    /// Lost to single scattering (or a walk's direction out of its side).
    Lost,
    /// A microsurface walk gave up, with this fraction of the energy.
    Unresolved(f64),
}

impl Walker {
    /// The stack `layers` (top first, as the model takes it); `media`: whether the layers'
    /// media exist (the 6-flux model's; the 2-flux model has none); `g2`: the reflection
    /// masking form of `single` interfaces; `interfaces`: how rough boundaries scatter.
    pub fn new(layers: &[LayerParams], media: bool, g2: G2, interfaces: Interfaces) -> Self {
        let mut boundaries = Vec::with_capacity(layers.len() + 1);
        let mut slabs = Vec::with_capacity(layers.len());
        let mut above = IOR_AIR;
        for layer in layers {
            if let Some(rho) = layer.diffuse {
                boundaries.push(Boundary::Lambert(rho));
                break;
            }
            if layer.is_conductor() {
                boundaries.push(Boundary::Conductor {
                    eta: layer.ior.map(|n| n / above),
                    kappa: layer.kappa.map(|k| k / above),
                    alpha: layer.roughness,
                });
                break;
            }
            let below = layer.ior.iter().sum::<f64>() / 3.0;
            boundaries.push(if (below / above - 1.0).abs() < INDEX_MATCHED {
                Boundary::Pass
            } else {
                Boundary::Dielectric {
                    above,
                    below,
                    alpha: layer.roughness,
                }
            });
            slabs.push(if media && layer.depth > 0.0 {
                Slab {
                    depth: layer.depth,
                    sigma_s: layer.sigma_s,
                    sigma_t: std::array::from_fn(|c| layer.sigma_s[c] + layer.sigma_a[c]),
                    g: layer.g,
                }
            } else {
                Slab::default()
            });
            above = below;
        }
        if slabs.len() == boundaries.len() {
            boundaries.push(Boundary::Open);
        }
        debug_assert!(boundaries.len() <= MAX_BOUNDARIES);
        Self {
            boundaries,
            slabs,
            g2,
            interfaces,
        }
    }

    /// Boundary `b` in words, for the flows' table ("1.50 → 1.00, α 0.20").
    pub fn describe(&self, b: usize) -> String {
        match self.boundaries.get(b) {
            Some(Boundary::Dielectric {
                above,
                below,
                alpha,
            }) => format!("interface {above:.2} → {below:.2}, α {alpha:.2}"),
            Some(Boundary::Pass) => "index-matched interface".into(),
            Some(Boundary::Conductor { alpha, .. }) => format!("conductor base, α {alpha:.2}"),
            Some(Boundary::Lambert(_)) => "Lambertian base".into(),
            Some(Boundary::Open) | None => "open bottom".into(),
        }
    }

    /// Whether light can leave through the bottom (the stack ends in a dielectric).
    pub fn transmits(&self) -> bool {
        matches!(self.boundaries.last(), Some(Boundary::Open))
    }

    /// One path of channel `c` (0, 1, 2) for light arriving against the view `wi` (unit,
    /// wi.z > 0), its arrivals at the boundaries recorded in `flows`.
    pub fn walk(&self, c: usize, wi: DVec3, rng: &mut Rng, flows: &mut Flows) -> Outcome {
        let mut d = -wi;
        let mut w = 1.0;
        let mut b = 0;
        let mut events = 0;
        let mut arrivals = Arrivals::new();
        loop {
            // At boundary b, travelling along d.
            let event = match self.boundaries[b] {
                Boundary::Pass => Event::Out(d, 1.0),
                Boundary::Open => return Outcome::Transmitted(d, w),
                boundary => {
                    let event = self.scatter(boundary, c, d, rng);
                    let from = if d.z < 0.0 { Side::Above } else { Side::Below };
                    let fate = match event {
                        Event::Out(next, f) if (next.z > 0.0) != (d.z > 0.0) => {
                            Fate::SentBack(w * f)
                        }
                        Event::Out(_, f) => Fate::Passed(w * f),
                        Event::Lost => Fate::Lost,
                        Event::Unresolved(_) => Fate::Unresolved,
                    };
                    flows.record(c, b, from, arrivals.next(b, from), w, fate);
                    event
                }
            };
            match event {
                Event::Out(next, factor) => {
                    d = next;
                    w *= factor;
                }
                Event::Lost => return Outcome::Lost,
                Event::Unresolved(factor) => return Outcome::Unresolved(w * factor),
            }
            if !roulette(&mut w, rng) {
                return Outcome::Lost;
            }
            events += 1;
            // Into the slab on d's side of boundary b.
            let slab = if d.z > 0.0 {
                if b == 0 {
                    return Outcome::Reflected(d, w);
                }
                b - 1
            } else {
                b
            };
            match self.cross(slab, c, &mut d, &mut w, &mut events, rng) {
                Crossing::Boundary(next_b) => b = next_b,
                Crossing::Lost => return Outcome::Lost,
                Crossing::Unresolved => return Outcome::Unresolved(w),
            }
            if events >= MAX_EVENTS {
                return Outcome::Unresolved(w);
            }
        }
    }

    /// Boundary `boundary` hit along `d` in channel `c`.
    fn scatter(&self, boundary: Boundary, c: usize, d: DVec3, rng: &mut Rng) -> Event {
        let single = |event: Option<(DVec3, f64)>| match event {
            Some((next, f)) => Event::Out(next, f),
            None => Event::Lost,
        };
        match (boundary, self.interfaces) {
            (Boundary::Lambert(rho), _) => Event::Out(lambert(rng), rho[c]),
            (
                Boundary::Dielectric {
                    above,
                    below,
                    alpha,
                },
                Interfaces::Single,
            ) => single(dielectric(d, above, below, alpha, self.g2, rng)),
            (Boundary::Conductor { eta, kappa, alpha }, Interfaces::Single) => {
                single(conductor(d, eta[c], kappa[c], alpha, self.g2, rng))
            }
            (
                Boundary::Dielectric {
                    above,
                    below,
                    alpha,
                },
                Interfaces::Multiple,
            ) => {
                let from_below = d.z > 0.0;
                let wi = to_side(-d, from_below);
                if wi.z <= 0.0 {
                    return Event::Lost;
                }
                let eta = if from_below {
                    above / below
                } else {
                    below / above
                };
                match microsurface::dielectric(wi, eta, alpha, rng) {
                    Exit::Left(wo, f) => Event::Out(to_side(wo, from_below), f),
                    Exit::Unresolved(f) => Event::Unresolved(f),
                }
            }
            (Boundary::Conductor { eta, kappa, alpha }, Interfaces::Multiple) => {
                if d.z >= 0.0 {
                    return Event::Lost;
                }
                match microsurface::conductor(-d, eta[c], kappa[c], alpha, rng) {
                    Exit::Left(wo, f) => Event::Out(wo, f),
                    Exit::Unresolved(f) => Event::Unresolved(f),
                }
            }
            // Neither scatters: light goes on as it came.
            (Boundary::Pass | Boundary::Open, _) => Event::Out(d, 1.0),
        }
    }

    /// Flies through slab `s` from the boundary the direction enters by, scattering in its
    /// medium, to the boundary the path reaches.
    fn cross(
        &self,
        s: usize,
        c: usize,
        d: &mut DVec3,
        w: &mut f64,
        events: &mut u32,
        rng: &mut Rng,
    ) -> Crossing {
        let slab = &self.slabs[s];
        let sigma_t = slab.sigma_t[c];
        if slab.depth <= 0.0 || sigma_t <= 0.0 {
            return Crossing::Boundary(if d.z < 0.0 { s + 1 } else { s });
        }
        // Depth below the slab's top.
        let mut u = if d.z < 0.0 { 0.0 } else { slab.depth };
        loop {
            let to_edge = if d.z < 0.0 {
                (slab.depth - u) / -d.z
            } else {
                u / d.z
            };
            let flight = -(1.0 - rng.unit()).ln() / sigma_t;
            if flight >= to_edge {
                return Crossing::Boundary(if d.z < 0.0 { s + 1 } else { s });
            }
            u = (u - flight * d.z).clamp(0.0, slab.depth);
            *w *= slab.sigma_s[c] / sigma_t;
            if !roulette(w, rng) {
                return Crossing::Lost;
            }
            *d = henyey_greenstein(*d, slab.g, rng);
            *events += 1;
            if *events >= MAX_EVENTS {
                return Crossing::Unresolved;
            }
        }
    }
}

/// Where a flight through a slab ended.
enum Crossing {
    Boundary(usize),
    Lost,
    Unresolved,
}

/// Russian roulette on a faint path; false when it ends.
fn roulette(w: &mut f64, rng: &mut Rng) -> bool {
    if *w <= 0.0 {
        return false;
    }
    if *w >= ROULETTE_BELOW {
        return true;
    }
    if rng.unit() * ROULETTE_BELOW < *w {
        *w = ROULETTE_BELOW;
        true
    } else {
        false
    }
}

/// Smith's separable G1 for a direction of cosine `cos` to the macro-normal.
fn smith_g1(cos: f64, alpha: f64) -> f64 {
    1.0 / (1.0 + smith_lambda(cos, alpha))
}

/// Flips z when the incident side is below: the local frame of an event has the incident side
/// on +z.
fn to_side(v: DVec3, below: bool) -> DVec3 {
    if below {
        DVec3::new(v.x, v.y, -v.z)
    } else {
        v
    }
}

/// A rough dielectric interface hit along `d`: the new direction and the energy factor, or
/// `None` when single scattering loses the path.
fn dielectric(
    d: DVec3,
    above: f64,
    below: f64,
    alpha: f64,
    g2: G2,
    rng: &mut Rng,
) -> Option<(DVec3, f64)> {
    let from_below = d.z > 0.0;
    let wi = to_side(-d, from_below);
    if wi.z <= 0.0 {
        return None;
    }
    let eta = if from_below {
        above / below
    } else {
        below / above
    };
    let m = sample_vndf(wi, (rng.unit(), rng.unit()), alpha);
    let cos_m = wi.dot(m).clamp(0.0, 1.0);
    let f = fresnel::dielectric(cos_m, eta);
    if rng.unit() < f {
        let wo = reflect(wi, m);
        if wo.z <= 0.0 {
            return None;
        }
        let factor = masking_shadowing(g2, wi.z, wo.z, alpha) / smith_g1(wi.z, alpha);
        Some((to_side(wo, from_below), factor))
    } else {
        let ct2 = 1.0 - (1.0 - cos_m * cos_m) / (eta * eta);
        let wo = -wi / eta + (cos_m / eta - ct2.max(0.0).sqrt()) * m;
        let wo = wo.normalize();
        if wo.z >= 0.0 {
            return None;
        }
        Some((to_side(wo, from_below), smith_g1(-wo.z, alpha)))
    }
}

/// The conductor base hit along `d` (from above): its exact Fresnel and the reflection
/// masking.
fn conductor(
    d: DVec3,
    eta: f64,
    kappa: f64,
    alpha: f64,
    g2: G2,
    rng: &mut Rng,
) -> Option<(DVec3, f64)> {
    let wi = -d;
    if wi.z <= 0.0 {
        return None;
    }
    let m = sample_vndf(wi, (rng.unit(), rng.unit()), alpha);
    let cos_m = wi.dot(m).clamp(0.0, 1.0);
    let wo = reflect(wi, m);
    if wo.z <= 0.0 {
        return None;
    }
    let factor = fresnel::conductor(cos_m, eta, kappa) * masking_shadowing(g2, wi.z, wo.z, alpha)
        / smith_g1(wi.z, alpha);
    Some((wo, factor))
}

/// A cosine-distributed direction above the surface (the Lambertian base's reflection).
fn lambert(rng: &mut Rng) -> DVec3 {
    let (u1, u2) = (rng.unit(), rng.unit());
    let r = u1.sqrt();
    let phi = std::f64::consts::TAU * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// A direction scattered from `d` by Henyey–Greenstein's phase function of asymmetry `g`.
fn henyey_greenstein(d: DVec3, g: f64, rng: &mut Rng) -> DVec3 {
    let (u1, u2) = (rng.unit(), rng.unit());
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u1
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u1);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * u2;
    let (t, b) = orthonormal_basis(d);
    (sin * phi.cos() * t + sin * phi.sin() * b + cos * d).normalize()
}

/// Two unit vectors completing `n` (unit) to an orthonormal basis (Duff et al. 2017).
fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0_f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn henyey_greenstein_has_mean_cosine_g() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let d = DVec3::new(0.3, -0.4, -0.866).normalize();
        for g in [-0.6, 0.0, 0.3, 0.9] {
            let n = 200_000;
            let mean: f64 = (0..n)
                .map(|_| henyey_greenstein(d, g, &mut rng).dot(d))
                .sum::<f64>()
                / f64::from(n);
            // The cosine's variance is at most 1: 5 standard errors are 0.011.
            assert!((mean - g).abs() < 0.011, "g {g}: mean cosine {mean}");
        }
    }

    #[test]
    fn the_basis_is_orthonormal() {
        for n in [DVec3::Z, -DVec3::Z, DVec3::new(0.6, 0.0, -0.8), DVec3::X] {
            let (t, b) = orthonormal_basis(n);
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-12);
            }
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn refraction_follows_snell() {
        // A smooth interface: every transmitted path obeys n₁ sin θ₁ = n₂ sin θ₂.
        let mut rng = Rng(7);
        let wi = DVec3::new(0.6, 0.0, 0.8);
        for _ in 0..100 {
            if let Some((wo, f)) = dielectric(-wi, 1.0, 1.5, 0.0, G2::Smith, &mut rng) {
                if wo.z < 0.0 {
                    let sin_t = (1.0 - wo.z * wo.z).sqrt();
                    assert!((1.5 * sin_t - 0.6).abs() < 1e-12);
                    assert!((f - 1.0).abs() < 1e-12);
                }
            }
        }
    }
}
