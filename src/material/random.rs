//! Random material stacks over the whole documented parameter space, for the property tests of
//! the f64 model (`properties.rs`) and of the GPU (tests/suite/model_vs_cpu.rs): every field inside
//! the material format's ranges (`material/mod.rs`), the range ends and the awkward values hit
//! often — α 0 and 1, relative η at, next to and far from 1 on both sides, κ up to 200, depth
//! up to 100, σ up to 1000, g near ±1, view cosines 1e-4 (the renderer's clamp of n·v) and 1.

use std::path::PathBuf;

use super::Stack;
use crate::model::random::Rng;
use crate::model::LayerParams;
use crate::variant::Model;

/// A value of `[lo, hi]` that lands on the ends (and on `special`) often.
fn pick(rng: &mut Rng, lo: f64, hi: f64, special: &[f64]) -> f64 {
    let u = rng.unit();
    if u < 0.1 {
        lo
    } else if u < 0.2 {
        hi
    } else if u < 0.3 && !special.is_empty() {
        special[(rng.unit() * special.len() as f64) as usize % special.len()]
    } else {
        lo + (hi - lo) * rng.unit()
    }
}

fn rgb(rng: &mut Rng, lo: f64, hi: f64, special: &[f64]) -> [f64; 3] {
    if rng.unit() < 0.5 {
        [pick(rng, lo, hi, special); 3]
    } else {
        [
            pick(rng, lo, hi, special),
            pick(rng, lo, hi, special),
            pick(rng, lo, hi, special),
        ]
    }
}

/// A random valid stack (the material format's rules) of 1 to `max_layers` layers, for `model`
/// (either when `None`), and a view cosine.
pub fn random_stack(rng: &mut Rng, model: Option<Model>, max_layers: usize) -> (Stack, f64) {
    let model = model.unwrap_or(if rng.unit() < 0.5 {
        Model::Tm2
    } else {
        Model::Tm6
    });
    let n = 1 + (rng.unit() * max_layers as f64) as usize;
    let conductor_base = rng.unit() < 0.6;
    let mut eta_above = 1.0;
    let layers = (0..n)
        .map(|i| {
            let conductor = conductor_base && i == n - 1;
            let roughness = pick(rng, 0.0, 1.0, &[1e-4, 0.5]);
            if conductor {
                let ior = rgb(rng, 1e-3, 400.0, &[0.05, 1.0, 1.5]);
                let kappa = rgb(rng, 1e-6, 200.0, &[1e-3, 1.0, 5.0]);
                return LayerParams::conductor(ior, kappa, roughness);
            }
            // Relative IORs at, next to and far from 1, below 1 as often as above.
            let relative = match rng.unit() {
                x if x < 0.15 => 1.0,
                x if x < 0.3 => 1.0 + pick(rng, -1e-4, 1e-4, &[1e-6, -1e-6, 2e-5, -9e-4, 2e-3]),
                x if x < 0.65 => pick(rng, 0.05, 1.0, &[0.7, 0.99]),
                _ => pick(rng, 1.0, 3.0, &[1.01, 1.5]),
            };
            let eta = (eta_above * relative).clamp(1e-3, 400.0);
            eta_above = eta;
            let medium = model == Model::Tm6 && rng.unit() < 0.7;
            let lossless = rng.unit() < 0.3;
            // Drawn in this order: depth, σs, σa, g.
            let depth = if medium {
                pick(rng, 0.0, 100.0, &[1e-6, 49.0])
            } else {
                0.0
            };
            let sigma_s = if medium {
                rgb(rng, 0.0, 1000.0, &[222.0, 1e-6])
            } else {
                [0.0; 3]
            };
            let sigma_a = if medium && !lossless {
                rgb(rng, 0.0, 1000.0, &[1e-6, 0.1])
            } else {
                [0.0; 3]
            };
            let g = if medium {
                pick(rng, -0.99, 0.99, &[0.0, 0.999_999, -0.999_999])
            } else {
                0.0
            };
            LayerParams::dielectric(eta, roughness).with_medium(depth, sigma_s, sigma_a, g)
        })
        .collect();
    let mu = pick(rng, 1e-4, 1.0, &[1e-3, 0.5]);
    let stack = Stack {
        name: "property case".into(),
        model,
        layers,
        source: PathBuf::from("<property test>"),
        surface: None,
    };
    (stack, mu)
}
