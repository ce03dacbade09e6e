//! The stack's energy by discrete ordinates: the same interfaces as the stochastic reference's
//! `interfaces=single` walk (single-scattering microfacet BSDFs with exact Fresnel), composed
//! over a grid of directions instead of followed one path at a time.
//!
//! For rotationally symmetric interfaces the reflected and transmitted *energies* depend only
//! on the azimuthal average of each scattering event (the zeroth Fourier mode of the adding
//! equations, Jakob, d'Eon, Jakob & Marschner 2014, "A comprehensive framework for rendering
//! layered materials"): a direction is its cosine μ, and an interface is four operators
//! between [`BINS`] bins of equal width in μ (reflection and transmission, from above and
//! from below), each column filled by the interface's own visible-normal quadrature at the
//! bin's centre. Light keeps every angle it is scattered to — light that total internal
//! reflection sends back stays near grazing, and a glossy base sends it back near grazing
//! again — which is what the transfer-matrix model's one TIR ratio per interface cannot
//! follow (ALGORITHMS.md §17).
//!
//! The stack is composed from the top down: the slab above the next boundary is known by
//! what it sends back down of light arriving from below ([`Slab::back`]) and the energy that
//! escapes from each bin upward ([`Slab::escape`]); adding a boundary (an interface or the
//! base) under it adds to R the light it reflects that eventually escapes. R after each
//! boundary is the reflectance of the stack down to it with an open bottom, so the increments
//! are the energies of the model's per-layer lobes.
//!
//! What it leaves out: media (the 6-flux model's) — [`reflectances`] refuses a stack with one.
//! Its accuracy is the bins' (tested against the walk: within 1.5 % of R on every 2-flux
//! preset at every view cosine).

use glam::DVec3;

use super::adding::{avg, map3};
use super::microfacet::{
    for_each_visible_normal, for_each_vndf_sample, masking_g1, masking_shadowing, reflect,
};
use super::microsurface::{self, Exit};
use super::random::{case_seed, Rng};
use super::{fresnel, LayerParams, INDEX_MATCHED, IOR_AIR};
use crate::variant::{Interfaces, G2};

/// Bins of the direction cosine μ, equal width.
pub const BINS: usize = 48;

/// Side of the visible-normal midpoint grid that fills a bin's column.
const GRID: u32 = 24;

/// Side of the grid for the view's own column (the exact μ, not a bin's centre).
const VIEW_GRID: u32 = 64;

/// Below this roughness an interface is smooth: exact Fresnel into the mirror and refracted
/// directions.
const SMOOTH: f64 = 1e-3;

type Row = [f64; BINS];

/// An operator on the bins: `m[j][k]`, the energy light in bin j sends to bin k.
#[derive(Clone, Debug)]
struct Operator(Vec<Row>);

impl Operator {
    fn zero() -> Self {
        Self(vec![[0.0; BINS]; BINS])
    }

    /// x·M: where the light `x` (energy per bin) goes.
    fn apply(&self, x: &Row) -> Row {
        let mut y = [0.0; BINS];
        for (j, &xj) in x.iter().enumerate() {
            if xj != 0.0 {
                for (yk, m) in y.iter_mut().zip(&self.0[j]) {
                    *yk += xj * m;
                }
            }
        }
        y
    }

    /// `self`, then `then`.
    fn then(&self, then: &Operator) -> Operator {
        Operator(self.0.iter().map(|row| then.apply(row)).collect())
    }

    /// (I − self)⁻¹ by Gauss–Jordan elimination with partial pivoting. `self` sends back at
    /// most what it receives (an energy operator of a gap between two boundaries), so I − self
    /// is diagonally dominant by columns' sums and the elimination is stable — but for a closed
    /// lossless mode: bins that both boundaries reflect whole into themselves (a smooth layer
    /// denser than both its neighbours traps by total internal reflection every direction
    /// beyond both critical angles). No light from outside reaches such bins through smooth
    /// boundaries, and I − self is singular there; a pivot below [`PIVOT_FLOOR`] is such a
    /// mode, taken as one pass (its 1 kept) rather than divided by.
    fn resolvent(&self) -> Operator {
        let mut a: Vec<Row> = self
            .0
            .iter()
            .enumerate()
            .map(|(j, row)| std::array::from_fn(|k| f64::from(u8::from(j == k)) - row[k]))
            .collect();
        let mut inv: Vec<Row> = (0..BINS)
            .map(|j| std::array::from_fn(|k| f64::from(u8::from(j == k))))
            .collect();
        for col in 0..BINS {
            let pivot = (col..BINS)
                .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
                .unwrap_or(col);
            a.swap(col, pivot);
            inv.swap(col, pivot);
            if a[col][col].abs() < PIVOT_FLOOR {
                a[col][col] = 1.0;
            }
            let p = a[col][col];
            for k in 0..BINS {
                a[col][k] /= p;
                inv[col][k] /= p;
            }
            for r in 0..BINS {
                let f = a[r][col];
                if r != col && f != 0.0 {
                    for k in 0..BINS {
                        a[r][k] -= f * a[col][k];
                        inv[r][k] -= f * inv[col][k];
                    }
                }
            }
        }
        Operator(inv)
    }
}

/// Pivots of the resolvent below which a bin is a closed lossless mode ([`Operator::resolvent`]).
const PIVOT_FLOOR: f64 = 1e-12;

fn bin_of(mu: f64) -> usize {
    ((mu.clamp(0.0, 1.0) * BINS as f64) as usize).min(BINS - 1)
}

fn bin_centre(k: usize) -> f64 {
    (k as f64 + 0.5) / BINS as f64
}

/// Where light arriving at cosine `mu` on one side of a dielectric interface goes: the energy
/// reflected per bin (same side) and transmitted per bin (other side). `eta`: the other side's
/// IOR over this side's. The walk's single scattering: F·G2/G1(i) into reflections (the
/// height-correlated form), (1 − F)·G1(o) into transmissions; the rest is lost.
fn interface_column(mu: f64, eta: f64, alpha: f64, grid: u32, mode: Interfaces) -> (Row, Row) {
    let (mut r, mut t) = ([0.0; BINS], [0.0; BINS]);
    if alpha < SMOOTH {
        let f = fresnel::dielectric(mu, eta);
        r[bin_of(mu)] += f;
        let ct2 = 1.0 - (1.0 - mu * mu) / (eta * eta);
        if ct2 > 0.0 {
            t[bin_of(ct2.sqrt())] += 1.0 - f;
        }
        return (r, t);
    }
    if mode == Interfaces::Multiple {
        let paths = WALKS_PER_CELL * grid * grid;
        let mut rng = walk_rng(mu, eta, alpha);
        let v = view(mu);
        for _ in 0..paths {
            if let Exit::Left(o, e) = microsurface::dielectric(v, eta, alpha, &mut rng) {
                let row = if o.z > 0.0 { &mut r } else { &mut t };
                row[bin_of(o.z.abs())] += e / f64::from(paths);
            }
        }
        return (r, t);
    }
    let v = view(mu);
    let w = 1.0 / f64::from(grid * grid);
    let g = G2::HeightCorrelated;
    for_each_visible_normal(v, alpha, grid, |m| {
        let c = v.dot(m).clamp(0.0, 1.0);
        let f = fresnel::dielectric(c, eta);
        let l = reflect(v, m);
        if l.z > 0.0 {
            r[bin_of(l.z)] +=
                w * f * masking_shadowing(g, v.z, l.z, alpha) / masking_g1(g, v.z, alpha);
        }
        let ct2 = 1.0 - (1.0 - c * c) / (eta * eta);
        if ct2 > 0.0 && f < 1.0 {
            let o = (-v / eta + (c / eta - ct2.sqrt()) * m).normalize();
            if o.z < 0.0 {
                t[bin_of(-o.z)] += w * (1.0 - f) * masking_g1(G2::Smith, -o.z, alpha);
            }
        }
    });
    (r, t)
}

/// Where light arriving at cosine `mu` on a conductor goes (relative complex IOR η + iκ).
fn conductor_column(mu: f64, eta: f64, kappa: f64, alpha: f64, grid: u32, mode: Interfaces) -> Row {
    let mut r = [0.0; BINS];
    if alpha < SMOOTH {
        r[bin_of(mu)] = fresnel::conductor(mu, eta, kappa);
        return r;
    }
    if mode == Interfaces::Multiple {
        let paths = WALKS_PER_CELL * grid * grid;
        let mut rng = walk_rng(mu, eta + kappa, alpha);
        let v = view(mu);
        for _ in 0..paths {
            if let Exit::Left(o, e) = microsurface::conductor(v, eta, kappa, alpha, &mut rng) {
                r[bin_of(o.z)] += e / f64::from(paths);
            }
        }
        return r;
    }
    let g = G2::HeightCorrelated;
    for_each_vndf_sample(mu, alpha, grid, |v, h, l| {
        r[bin_of(l.z)] += fresnel::conductor(v.dot(h).clamp(0.0, 1.0), eta, kappa)
            * masking_shadowing(g, v.z, l.z, alpha)
            / masking_g1(g, v.z, alpha)
            / f64::from(grid * grid);
    });
    r
}

/// Walks per cell of the single-scattering grid a column of `interfaces=multiple` follows.
const WALKS_PER_CELL: u32 = 16;

fn view(mu: f64) -> DVec3 {
    DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu.max(1e-4))
}

/// A column's walks' generator: seeded by what the column is, so the same stack gives the
/// same numbers every time.
fn walk_rng(mu: f64, eta: f64, alpha: f64) -> Rng {
    Rng(case_seed(
        mu.to_bits() ^ eta.to_bits().rotate_left(21) ^ alpha.to_bits().rotate_left(42),
        0,
    ))
}

/// A Lambertian base's column: albedo ρ spread over the bins by cosine weight.
fn lambert_column(rho: f64) -> Row {
    std::array::from_fn(|k| {
        let (lo, hi) = (k as f64 / BINS as f64, (k + 1) as f64 / BINS as f64);
        rho * (hi * hi - lo * lo)
    })
}

/// Optical depth of the thin layer a medium's operator starts from before doubling.
const THIN: f64 = 1e-4;

/// Azimuths and sub-bins over which the phase function is averaged into a bin.
const PHASE_AZIMUTHS: usize = 96;
const PHASE_SUBBINS: usize = 6;

/// Henyey–Greenstein's phase function averaged over azimuth, from bin j into bin k, on the
/// same side (`forward`: both travelling the same way along z) or the other: rows normalised
/// so each direction scatters all its energy (the quadrature's error taken out of the energy).
fn phase_operators(g: f64) -> (Operator, Operator) {
    let hg = |cos: f64| {
        (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * cos).powf(1.5))
    };
    let (mut same, mut other) = (Operator::zero(), Operator::zero());
    let d_phi = std::f64::consts::TAU / PHASE_AZIMUTHS as f64;
    let d_mu = 1.0 / (BINS * PHASE_SUBBINS) as f64;
    for j in 0..BINS {
        let mu_j = bin_centre(j);
        let s_j = (1.0 - mu_j * mu_j).sqrt();
        for k in 0..BINS {
            let (mut a, mut b) = (0.0, 0.0);
            for q in 0..PHASE_SUBBINS {
                let mu_k = (k * PHASE_SUBBINS + q) as f64 * d_mu + 0.5 * d_mu;
                let s_k = (1.0 - mu_k * mu_k).sqrt();
                for p in 0..PHASE_AZIMUTHS {
                    let c = ((p as f64 + 0.5) * d_phi).cos() * s_j * s_k;
                    a += hg(mu_j * mu_k + c) * d_phi * d_mu;
                    b += hg(-mu_j * mu_k + c) * d_phi * d_mu;
                }
            }
            same.0[j][k] = a;
            other.0[j][k] = b;
        }
        let total: f64 = same.0[j].iter().chain(&other.0[j]).sum();
        for k in 0..BINS {
            same.0[j][k] /= total;
            other.0[j][k] /= total;
        }
    }
    (same, other)
}

/// A boundary under the slab: what it does to light arriving from above, and (interfaces
/// only) from below.
struct Boundary {
    /// From above: reflected up (bins above), transmitted down (bins below).
    down_r: Operator,
    down_t: Operator,
    /// From below: reflected down, transmitted up.
    up_r: Operator,
    up_t: Operator,
}

impl Boundary {
    fn interface(eta: f64, alpha: f64, mode: Interfaces) -> Self {
        let side = |eta: f64| {
            let (mut r, mut t) = (Operator::zero(), Operator::zero());
            for j in 0..BINS {
                (r.0[j], t.0[j]) = interface_column(bin_centre(j), eta, alpha, GRID, mode);
            }
            (r, t)
        };
        let (down_r, down_t) = side(eta);
        let (up_r, up_t) = side(1.0 / eta);
        Self {
            down_r,
            down_t,
            up_r,
            up_t,
        }
    }

    /// A homogeneous medium of optical depth `tau` (extinction × depth), single-scattering
    /// albedo `albedo` and HG asymmetry `g`: a thin layer's first-order scattering, doubled
    /// (R₂ = R + T R (I − R R)⁻¹ T, T₂ = T (I − R R)⁻¹ T: the slab is the same from both
    /// sides) until it is `tau` thick.
    fn medium(tau: f64, albedo: f64, g: f64) -> Self {
        let mut doublings = 0;
        let mut thin = tau;
        while thin > THIN {
            thin *= 0.5;
            doublings += 1;
        }
        let (same, other) = phase_operators(g);
        let mut r = Operator::zero();
        let mut t = Operator::zero();
        for j in 0..BINS {
            let direct = (-thin / bin_centre(j)).exp();
            let scattered = albedo * (1.0 - direct);
            for k in 0..BINS {
                r.0[j][k] = scattered * other.0[j][k];
                t.0[j][k] = scattered * same.0[j][k];
            }
            t.0[j][j] += direct;
        }
        for _ in 0..doublings {
            let loop_ = r.then(&r).resolvent();
            let t_loop = t.then(&loop_);
            let r2 = t_loop.then(&r).then(&t);
            let t2 = t_loop.then(&t);
            r = Operator(
                (0..BINS)
                    .map(|j| std::array::from_fn(|k| r.0[j][k] + r2.0[j][k]))
                    .collect(),
            );
            t = t2;
        }
        Self {
            down_r: r.clone(),
            down_t: t.clone(),
            up_r: r,
            up_t: t,
        }
    }

    /// An opaque base whose column for bin j is `column(μ_j)`.
    fn base(column: impl Fn(f64) -> Row) -> Self {
        Self {
            down_r: Operator((0..BINS).map(|j| column(bin_centre(j))).collect()),
            down_t: Operator::zero(),
            up_r: Operator::zero(),
            up_t: Operator::zero(),
        }
    }
}

/// The stack above a gap, as light in the gap sees it.
#[derive(Clone, Debug)]
struct Slab {
    /// Light travelling down in the gap, per bin (from the view's light, through every
    /// boundary above).
    down: Row,
    /// What the slab sends back down of light arriving from below, bin to bin.
    back: Operator,
    /// The energy that escapes above the stack per unit of light arriving from below, per bin.
    escape: Row,
}

impl Slab {
    /// Nothing above: the view's light going down at cosine `mu` (its bin), everything from
    /// below escaping.
    fn open(mu: f64) -> Self {
        let mut down = [0.0; BINS];
        down[bin_of(mu)] = 1.0;
        Self {
            down,
            back: Operator::zero(),
            escape: [1.0; BINS],
        }
    }

    /// Adds `b` under the slab: the new slab and the energy `b` adds to R.
    fn over(&self, b: &Boundary) -> (Slab, f64) {
        // Light bouncing in the gap: up-going u = (down + u·back)·down_r, so
        // u = down·down_r·(I − back·down_r)⁻¹.
        let loop_ = self.back.then(&b.down_r).resolvent();
        let up = loop_.apply(&b.down_r.apply(&self.down));
        let added: f64 = up.iter().zip(&self.escape).map(|(u, e)| u * e).sum();
        // Down-going in the gap: down + up·back; through b.
        let back_up = self.back.apply(&up);
        let gap_down: Row = std::array::from_fn(|k| self.down[k] + back_up[k]);
        let down = b.down_t.apply(&gap_down);
        // From below b: up through b, then bouncing in the gap.
        let through = b.up_t.then(&loop_);
        let escape = std::array::from_fn(|j| {
            through.0[j]
                .iter()
                .zip(&self.escape)
                .map(|(u, e)| u * e)
                .sum()
        });
        let back_in_gap = through.then(&self.back).then(&b.down_t);
        let back = Operator(
            (0..BINS)
                .map(|j| std::array::from_fn(|k| b.up_r.0[j][k] + back_in_gap.0[j][k]))
                .collect(),
        );
        (Slab { down, back, escape }, added)
    }
}

/// What light meets, top to bottom.
enum Step {
    /// A dielectric interface (relative IOR `eta`, roughness `alpha`), the same in every
    /// channel: the model averages a dielectric's IOR over RGB.
    Interface {
        eta: f64,
        alpha: f64,
        boundary: Boundary,
    },
    /// A medium, per channel (`None`: one that does nothing in that channel).
    Medium([Option<Boundary>; 3]),
    /// The opaque base, per channel, with what the view's own column needs.
    Base {
        channels: [Boundary; 3],
        layer: LayerParams,
        above: f64,
    },
}

/// A stack made ready for evaluation at any view cosine: every boundary's operators, built
/// once.
pub struct Transport {
    /// Per layer (top first), its steps.
    layers: Vec<Vec<Step>>,
    mode: Interfaces,
}

impl Transport {
    /// The stack `layers` (top first); `media`: whether the layers' media exist (the 6-flux
    /// model's); `mode`: how rough boundaries scatter.
    pub fn new(layers: &[LayerParams], media: bool, mode: Interfaces) -> Self {
        let mut steps = Vec::with_capacity(layers.len());
        let mut above = IOR_AIR;
        for layer in layers {
            let mut own = Vec::new();
            if layer.diffuse.is_some() || layer.is_conductor() {
                own.push(Step::Base {
                    channels: std::array::from_fn(|c| base_boundary(layer, above, c, mode)),
                    layer: *layer,
                    above,
                });
                steps.push(own);
                break;
            }
            let eta = avg(layer.ior) / above;
            // An index-matched interface is none, and the index above the next one stays the
            // last refracting layer's, as in the model (whose skip it is): so a stack reads the
            // same with such a layer or without it (`material::simplify`).
            if (eta - 1.0).abs() >= INDEX_MATCHED {
                own.push(Step::Interface {
                    eta,
                    alpha: layer.roughness,
                    boundary: Boundary::interface(eta, layer.roughness, mode),
                });
                above = avg(layer.ior);
            }
            if media && layer.depth > 0.0 {
                own.push(Step::Medium(std::array::from_fn(|c| {
                    let sigma_t = layer.sigma_s[c] + layer.sigma_a[c];
                    (sigma_t > 0.0).then(|| {
                        Boundary::medium(sigma_t * layer.depth, layer.sigma_s[c] / sigma_t, layer.g)
                    })
                })));
            }
            steps.push(own);
        }
        Self {
            layers: steps,
            mode,
        }
    }

    /// Reflectance of the stack down to each layer (top first, an open bottom below it; a
    /// layer past the base is not listed) and the stack's transmittance, per channel, at view
    /// cosine `mu` ∈ (0, 1].
    pub fn reflectances(&self, mu: f64) -> (Vec<[f64; 3]>, [f64; 3]) {
        let mut out = Vec::with_capacity(self.layers.len());
        let mut slabs: [Option<Slab>; 3] = [None, None, None];
        let mut r = [0.0; 3];
        let mut opaque = false;
        for steps in &self.layers {
            for step in steps {
                for c in 0..3 {
                    let (b, first) = match step {
                        Step::Interface {
                            eta,
                            alpha,
                            boundary,
                        } => (Some(boundary), Some(First::Interface(*eta, *alpha))),
                        Step::Medium(channels) => (channels[c].as_ref(), None),
                        Step::Base {
                            channels,
                            layer,
                            above,
                        } => {
                            opaque = true;
                            (Some(&channels[c]), Some(First::Base(layer, *above)))
                        }
                    };
                    let Some(b) = b else { continue };
                    let slab = match (slabs[c].take(), first) {
                        (Some(slab), _) => slab,
                        // A medium under no boundary (an index-matched top): the view's light
                        // enters it in its bin.
                        (None, None) => Slab::open(mu),
                        (None, Some(first)) => {
                            // The top boundary, met at the view's own cosine.
                            let (reflected, slab) = first.at(mu, b, c, self.mode);
                            r[c] = reflected;
                            slabs[c] = Some(slab);
                            continue;
                        }
                    };
                    let (next, added) = slab.over(b);
                    r[c] += added;
                    slabs[c] = Some(next);
                }
            }
            out.push(r);
        }
        let t = if opaque {
            [0.0; 3]
        } else {
            map3(|c| slabs[c].as_ref().map_or(1.0, |s| s.down.iter().sum()))
        };
        (out, t)
    }
}

/// The top boundary, which the view's light meets at its own cosine rather than a bin's.
enum First<'a> {
    Interface(f64, f64),
    Base(&'a LayerParams, f64),
}

impl First<'_> {
    /// R of the boundary alone at `mu` and the slab it makes (its operators `b` from below).
    fn at(&self, mu: f64, b: &Boundary, c: usize, mode: Interfaces) -> (f64, Slab) {
        let (reflected, down) = match *self {
            First::Interface(eta, alpha) => {
                let (r, t) = interface_column(mu, eta, alpha, VIEW_GRID, mode);
                (r.iter().sum(), t)
            }
            First::Base(layer, above) => match layer.diffuse {
                Some(rho) => (rho[c], [0.0; BINS]),
                None => {
                    let col = conductor_column(
                        mu,
                        layer.ior[c] / above,
                        layer.kappa[c] / above,
                        layer.roughness,
                        VIEW_GRID,
                        mode,
                    );
                    (col.iter().sum(), [0.0; BINS])
                }
            },
        };
        let slab = Slab {
            down,
            back: b.up_r.clone(),
            escape: std::array::from_fn(|j| b.up_t.0[j].iter().sum()),
        };
        (reflected, slab)
    }
}

/// The opaque base `layer` in channel `c` under a medium of IOR `above`.
fn base_boundary(layer: &LayerParams, above: f64, c: usize, mode: Interfaces) -> Boundary {
    match layer.diffuse {
        Some(rho) => Boundary::base(|_| lambert_column(rho[c])),
        None => {
            let (eta, kappa, alpha) = (
                layer.ior[c] / above,
                layer.kappa[c] / above,
                layer.roughness,
            );
            Boundary::base(|m| conductor_column(m, eta, kappa, alpha, GRID, mode))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::tm2::tests::{coat, gold};

    fn run(
        layers: &[LayerParams],
        mu: f64,
        media: bool,
        mode: Interfaces,
    ) -> (Vec<[f64; 3]>, [f64; 3]) {
        Transport::new(layers, media, mode).reflectances(mu)
    }

    #[test]
    fn smooth_coats_over_a_conductor_follow_the_adding_equations() {
        // Smooth interfaces keep every direction in its bin, so the composition is the adding
        // equations with each interface's Fresnel at the centre of the bin its light is in:
        // exact up to R's change across half a bin (1/96 in μ).
        let stack = [coat(1.5, 0.0), coat(2.0, 0.0), gold(0.0)];
        let refracted = |mu: f64, eta: f64| (1.0 - (1.0 - mu * mu) / (eta * eta)).sqrt();
        for mu in [0.9, 0.35] {
            let mu1 = refracted(mu, 1.5);
            let mu2 = refracted(mu1, 2.0 / 1.5);
            let exact: [f64; 3] = std::array::from_fn(|c| {
                let base = fresnel::conductor(mu2, stack[2].ior[c] / 2.0, stack[2].kappa[c] / 2.0);
                let r1 = fresnel::dielectric(mu1, 2.0 / 1.5);
                let below = r1 + (1.0 - r1).powi(2) * base / (1.0 - r1 * base);
                let r0 = fresnel::dielectric(mu, 1.5);
                r0 + (1.0 - r0).powi(2) * below / (1.0 - r0 * below)
            });
            let (r, t) = run(&stack, mu, false, Interfaces::Single);
            assert_eq!(r.len(), 3);
            assert_eq!(t, [0.0; 3]);
            for c in 0..3 {
                assert!(
                    (r[2][c] - exact[c]).abs() < 5e-3,
                    "μ {mu}: {} against {}",
                    r[2][c],
                    exact[c]
                );
            }
            // The first layer alone: its Fresnel, exactly (met at the view's own cosine).
            assert!((r[0][0] - fresnel::dielectric(mu, 1.5)).abs() < 1e-12);
        }
    }

    #[test]
    fn a_lossless_stack_conserves_energy_with_multiple_scattering_interfaces() {
        // Rough interfaces walked on their microsurface and media that scatter without
        // absorbing: everything is reflected or transmitted, up to the walks given up.
        let stack = [
            LayerParams {
                depth: 0.5,
                sigma_s: [2.0, 0.5, 8.0],
                g: 0.6,
                ..coat(1.5, 0.4)
            },
            coat(1.2, 0.9),
            coat(1.0, 0.2),
        ];
        for mu in [1.0, 0.4, 0.05] {
            let (r, t) = run(&stack, mu, true, Interfaces::Multiple);
            for c in 0..3 {
                let sum = r[2][c] + t[c];
                assert!(
                    (sum - 1.0).abs() < 1e-6,
                    "μ {mu}, channel {c}: R + T = {sum}"
                );
            }
        }
        // Single scattering loses light at the same stack.
        let (r, t) = run(&stack, 0.4, true, Interfaces::Single);
        assert!(r[2][0] + t[0] < 0.99);
    }

    #[test]
    fn a_smooth_layer_that_traps_light_by_total_internal_reflection_stays_finite() {
        // η 3.2 between 2.9 and 2.28, smooth: the directions beyond both critical angles are
        // a closed lossless mode, where I − R′R is singular (it gave NaN). Exact refraction
        // never enters it; the bins' centres let a little in, which stays there, as trapped
        // light does: R + T is finite, at most 1, and short of it by that leak only.
        let stack = [coat(2.9, 0.0), coat(3.2, 0.0), coat(2.28, 0.0)];
        for mode in [Interfaces::Single, Interfaces::Multiple] {
            for mu in [1.0, 0.5, 0.05] {
                let (r, t) = run(&stack, mu, false, mode);
                let sum = r[2][0] + t[0];
                assert!(
                    sum.is_finite() && sum <= 1.0 + 1e-9 && sum > 0.95,
                    "{mode}, μ {mu}: R + T = {sum}"
                );
            }
        }
    }

    #[test]
    fn what_changes_nothing_changes_nothing() {
        // An index-matched interface, whatever its roughness, and a medium of zero depth.
        let base = [coat(1.5, 0.2), gold(0.3)];
        let with = [
            coat(1.5, 0.2),
            LayerParams {
                depth: 0.0,
                sigma_s: [5.0; 3],
                ..coat(1.5, 0.9)
            },
            gold(0.3),
        ];
        for mode in [Interfaces::Single, Interfaces::Multiple] {
            let (a, _) = run(&base, 0.6, true, mode);
            let (b, _) = run(&with, 0.6, true, mode);
            assert_eq!(a[1], b[2]);
        }
    }
}
