//! The stochastic reference of a layered BSDF: the stack's reflectance, transmittance and
//! reflected distribution estimated by following light paths through it one interface and one
//! collision at a time ([`walk`]), in f64, on every core — the ground truth the
//! transfer-matrix model approximates, in the spirit of the stochastic simulation the paper
//! validated against (Guo, Hašan & Zhao 2018, "Position-free Monte Carlo simulation for
//! arbitrary layered BSDFs").
//!
//! For one view cosine μ, light arrives against the view v = (√(1 − μ²), 0, μ); each channel
//! walks its own paths (a conductor's Fresnel and a medium's coefficients are per channel; a
//! dielectric's IOR is averaged over RGB as the model does). Estimates come with their standard
//! errors. Paths run in chunks with seeds of their own, summed in chunk order, so a seed gives
//! the same numbers on any number of threads.
//!
//! The reflected light is binned two ways, each bin's value the BRDF averaged over the bin
//! with weight cos θ_o (the bin's energy over its projected solid angle):
//! - the plane of incidence ([`SLICE_BINS`] bins of 2° in signed θ_o, positive on the mirror
//!   side, within ±[`SLICE_HALF_WIDTH_DEG`] of azimuth);
//! - the hemisphere ([`HEMISPHERE_RINGS`] rings of equal sin² θ_o × [`HEMISPHERE_SECTORS`]
//!   sectors of azimuth from the mirror direction; every bin has the same projected solid
//!   angle).

pub mod compare;
pub mod flows;
pub mod slice;
pub mod walk;

use std::f64::consts::{PI, TAU};
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::model::random::{case_seed, Rng};
use crate::model::LayerParams;
use crate::variant::{Interfaces, G2};
use flows::{FlowRow, Flows};
use walk::{Outcome, Walker};

/// Most paths per channel and view cosine a run accepts (about a day on two cores).
pub const MAX_PATHS: u64 = 10_000_000_000;

/// Bins of the plane-of-incidence slice: 2° each over θ_o ∈ [−90°, 90°].
pub const SLICE_BINS: usize = 90;

/// Azimuthal half-width of the slice around the plane of incidence, in degrees.
pub const SLICE_HALF_WIDTH_DEG: f64 = 5.0;

/// Rings of the hemisphere's bins, equal steps of sin² θ_o.
pub const HEMISPHERE_RINGS: usize = 16;

/// Azimuthal sectors of the hemisphere's bins, from the mirror direction.
pub const HEMISPHERE_SECTORS: usize = 32;

/// Paths per channel a chunk follows with one seed.
const CHUNK: u64 = 1024;

/// Chunks run in parallel between two progress reports (and checks for a stop).
const BATCH: u64 = 64;

/// What a run follows.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Paths per channel and view cosine.
    pub paths: u64,
    pub seed: u64,
    /// Masking form of the interfaces' reflections (the model's FGD's) under
    /// `interfaces=single`.
    pub g2: G2,
    /// How rough interfaces scatter: single scattering or the microsurface walk.
    pub interfaces: Interfaces,
    /// Whether the layers' media exist (the 6-flux model's).
    pub media: bool,
}

impl Settings {
    /// Refuses a path count of 0 or above [`MAX_PATHS`].
    pub fn check(&self) -> Result<()> {
        if self.paths == 0 || self.paths > MAX_PATHS {
            return Err(Error::Unsupported(format!(
                "--paths {}: a reference follows 1 to {MAX_PATHS} paths per channel and view cosine",
                self.paths
            )));
        }
        Ok(())
    }
}

/// A mean per channel with its standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    pub mean: [f64; 3],
    pub std_error: [f64; 3],
}

/// The reference at one view cosine.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Reference {
    pub cos_theta: f64,
    /// Paths per channel.
    pub paths: u64,
    pub reflectance: Estimate,
    pub transmittance: Estimate,
    /// Mean energy of the paths given up after [`walk::MAX_EVENTS`] events: R + T is short of
    /// the truth by at most this much.
    pub unresolved: [f64; 3],
    /// BRDF (sr⁻¹) per plane-of-incidence bin ([`slice_bin`]).
    pub slice: Vec<Estimate>,
    /// BRDF (sr⁻¹) per hemisphere bin, ring-major ([`hemisphere_bin`]).
    pub hemisphere: Vec<Estimate>,
    /// Energy per path at each boundary by side and crossing order ([`flows`]).
    pub flows: Vec<FlowRow>,
}

/// The slice bin of an outgoing direction (unit, above the surface, the view in the +x half of
/// the plane y = 0), if it is within the slice's azimuth.
pub fn slice_bin(l: DVec3) -> Option<usize> {
    let half = SLICE_HALF_WIDTH_DEG.to_radians();
    let phi = l.y.atan2(-l.x);
    let theta = l.z.clamp(-1.0, 1.0).acos();
    let signed = if phi.abs() <= half {
        theta
    } else if PI - phi.abs() <= half {
        -theta
    } else {
        return None;
    };
    let step = PI / SLICE_BINS as f64;
    Some((((signed + 0.5 * PI) / step) as usize).min(SLICE_BINS - 1))
}

/// Signed θ_o of a slice bin's edges, in radians (positive on the mirror side).
pub fn slice_bin_edges(i: usize) -> (f64, f64) {
    let step = PI / SLICE_BINS as f64;
    (
        -0.5 * PI + step * i as f64,
        -0.5 * PI + step * (i + 1) as f64,
    )
}

/// ∫ cos θ dω over a slice bin.
pub fn slice_projected_solid_angle(i: usize) -> f64 {
    let (a, b) = slice_bin_edges(i);
    let (lo, hi) = (a.abs().min(b.abs()), a.abs().max(b.abs()));
    0.5 * (hi.sin().powi(2) - lo.sin().powi(2)) * 2.0 * SLICE_HALF_WIDTH_DEG.to_radians()
}

/// The hemisphere bin of an outgoing direction above the surface.
pub fn hemisphere_bin(l: DVec3) -> usize {
    let sin2 = (1.0 - l.z * l.z).clamp(0.0, 1.0);
    let ring = ((sin2 * HEMISPHERE_RINGS as f64) as usize).min(HEMISPHERE_RINGS - 1);
    let phi = l.y.atan2(-l.x).rem_euclid(TAU);
    let sector = ((phi / TAU * HEMISPHERE_SECTORS as f64) as usize).min(HEMISPHERE_SECTORS - 1);
    ring * HEMISPHERE_SECTORS + sector
}

/// ∫ cos θ dω over any hemisphere bin (all are equal).
pub fn hemisphere_projected_solid_angle() -> f64 {
    PI / (HEMISPHERE_RINGS * HEMISPHERE_SECTORS) as f64
}

/// Sums of a per-path quantity and of its square.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    sum: [f64; 3],
    sum_sq: [f64; 3],
}

impl Moments {
    fn add(&mut self, c: usize, w: f64) {
        self.sum[c] += w;
        self.sum_sq[c] += w * w;
    }

    fn merge(&mut self, other: &Moments) {
        for c in 0..3 {
            self.sum[c] += other.sum[c];
            self.sum_sq[c] += other.sum_sq[c];
        }
    }

    /// The mean over `n` paths (those that added nothing count as 0) and its standard error,
    /// divided by `scale`.
    fn estimate(&self, n: f64, scale: f64) -> Estimate {
        let mut e = Estimate::default();
        for c in 0..3 {
            let mean = self.sum[c] / n;
            let variance = (self.sum_sq[c] / n - mean * mean).max(0.0);
            e.mean[c] = mean / scale;
            e.std_error[c] = (variance / n).sqrt() / scale;
        }
        e
    }
}

/// What a set of paths added up to.
#[derive(Clone, Debug)]
struct Tally {
    reflected: Moments,
    transmitted: Moments,
    unresolved: [f64; 3],
    slice: Vec<Moments>,
    hemisphere: Vec<Moments>,
    flows: Flows,
}

impl Tally {
    fn new() -> Self {
        Self {
            reflected: Moments::default(),
            transmitted: Moments::default(),
            unresolved: [0.0; 3],
            slice: vec![Moments::default(); SLICE_BINS],
            hemisphere: vec![Moments::default(); HEMISPHERE_RINGS * HEMISPHERE_SECTORS],
            flows: Flows::new(),
        }
    }

    fn merge(&mut self, other: &Tally) {
        self.reflected.merge(&other.reflected);
        self.transmitted.merge(&other.transmitted);
        for c in 0..3 {
            self.unresolved[c] += other.unresolved[c];
        }
        for (a, b) in self.slice.iter_mut().zip(&other.slice) {
            a.merge(b);
        }
        for (a, b) in self.hemisphere.iter_mut().zip(&other.hemisphere) {
            a.merge(b);
        }
        self.flows.merge(&other.flows);
    }
}

/// Follows chunk `k`'s paths.
fn chunk(walker: &Walker, wi: DVec3, seed: u64, k: u64, paths: u64) -> Tally {
    let mut rng = Rng(case_seed(seed, k as usize));
    let mut tally = Tally::new();
    for c in 0..3 {
        for _ in 0..paths {
            match walker.walk(c, wi, &mut rng, &mut tally.flows) {
                Outcome::Reflected(l, w) => {
                    tally.reflected.add(c, w);
                    if let Some(i) = slice_bin(l) {
                        tally.slice[i].add(c, w);
                    }
                    tally.hemisphere[hemisphere_bin(l)].add(c, w);
                }
                Outcome::Transmitted(_, w) => tally.transmitted.add(c, w),
                Outcome::Unresolved(w) => tally.unresolved[c] += w,
                Outcome::Lost => {}
            }
        }
    }
    tally
}

/// The reference of the stack `layers` (top first) at view cosine `mu` ∈ (0, 1].
/// `progress(paths)` is called with the paths per channel followed so far; a run stops early,
/// returning `None`, once `stop` is set.
pub fn simulate(
    layers: &[LayerParams],
    settings: &Settings,
    mu: f64,
    progress: &mut dyn FnMut(u64),
    stop: &AtomicBool,
) -> Result<Option<Reference>> {
    settings.check()?;
    if !(mu.is_finite() && mu > 0.0 && mu <= 1.0) {
        return Err(Error::Unsupported(format!(
            "view cosine {mu}: a reference needs one in (0, 1]"
        )));
    }
    let walker = Walker::new(layers, settings.media, settings.g2, settings.interfaces);
    let wi = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    // The seed of each view cosine's paths differs, so two cosines are independent.
    let seed = settings.seed ^ mu.to_bits().rotate_left(17);
    let chunks = settings.paths.div_ceil(CHUNK);
    let mut total = Tally::new();
    let mut first = 0;
    while first < chunks {
        if stop.load(Ordering::Relaxed) {
            return Ok(None);
        }
        let last = (first + BATCH).min(chunks);
        let tallies: Vec<Tally> = (first..last)
            .into_par_iter()
            .map(|k| {
                let n = CHUNK.min(settings.paths - k * CHUNK);
                chunk(&walker, wi, seed, k, n)
            })
            .collect();
        for tally in &tallies {
            total.merge(tally);
        }
        first = last;
        progress((first * CHUNK).min(settings.paths));
    }
    let n = settings.paths as f64;
    Ok(Some(Reference {
        cos_theta: mu,
        paths: settings.paths,
        reflectance: total.reflected.estimate(n, 1.0),
        transmittance: total.transmitted.estimate(n, 1.0),
        unresolved: total.unresolved.map(|u| u / n),
        slice: (0..SLICE_BINS)
            .map(|i| total.slice[i].estimate(n, slice_projected_solid_angle(i)))
            .collect(),
        hemisphere: total
            .hemisphere
            .iter()
            .map(|m| m.estimate(n, hemisphere_projected_solid_angle()))
            .collect(),
        flows: total.flows.rows(n),
    }))
}

#[cfg(test)]
mod tests;
