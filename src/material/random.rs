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

/// The ranges the presets span (assets/materials), per field: where the reference study's
/// random stacks are drawn ([`preset_like_stack`]).
#[derive(Clone, Debug)]
pub struct PresetRanges {
    /// Dielectric coats per stack, at most.
    pub max_coats: usize,
    /// A coat's IOR, roughness; a medium's depth, σs, σa (per channel) and g.
    pub ior: (f64, f64),
    pub roughness: (f64, f64),
    pub depth: (f64, f64),
    pub sigma_s: (f64, f64),
    pub sigma_a: (f64, f64),
    pub g: (f64, f64),
    /// A Lambertian base's albedo (per channel).
    pub albedo: (f64, f64),
    /// The presets' conductor bases, as they are.
    pub conductors: Vec<LayerParams>,
}

fn widen(range: &mut Option<(f64, f64)>, v: f64) {
    let (lo, hi) = range.get_or_insert((v, v));
    *lo = lo.min(v);
    *hi = hi.max(v);
}

impl PresetRanges {
    /// The ranges of the presets (assets/materials).
    pub fn of_presets() -> Result<Self, super::MaterialError> {
        let presets = super::presets()
            .iter()
            .map(|p| Stack::load(p))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self::of(&presets))
    }

    /// The ranges of `stacks` (each at its nominal values: a map's middle value).
    pub fn of(stacks: &[Stack]) -> Self {
        let (mut ior, mut roughness, mut depth, mut sigma_s, mut sigma_a, mut g, mut albedo) =
            (None, None, None, None, None, None, None);
        let mut conductors: Vec<LayerParams> = Vec::new();
        let mut max_coats = 1;
        for stack in stacks {
            let layers = stack.params();
            let coats = layers
                .iter()
                .filter(|l| !l.is_conductor() && l.diffuse.is_none());
            max_coats = max_coats.max(coats.clone().count());
            for l in coats {
                widen(&mut ior, l.ior[0]);
                widen(&mut roughness, l.roughness);
                if l.depth > 0.0 {
                    widen(&mut depth, l.depth);
                    widen(&mut g, l.g);
                    for c in 0..3 {
                        widen(&mut sigma_s, l.sigma_s[c]);
                        widen(&mut sigma_a, l.sigma_a[c]);
                    }
                }
            }
            for l in &layers {
                if let Some(rho) = l.diffuse {
                    rho.iter().for_each(|&r| widen(&mut albedo, r));
                }
                if l.is_conductor() && !conductors.contains(l) {
                    conductors.push(*l);
                }
            }
        }
        let or = |r: Option<(f64, f64)>, d: (f64, f64)| r.unwrap_or(d);
        Self {
            max_coats,
            ior: or(ior, (1.5, 1.5)),
            roughness: or(roughness, (0.1, 0.1)),
            depth: or(depth, (0.0, 0.0)),
            sigma_s: or(sigma_s, (0.0, 0.0)),
            sigma_a: or(sigma_a, (0.0, 0.0)),
            g: or(g, (0.0, 0.0)),
            albedo: or(albedo, (0.5, 0.5)),
            conductors,
        }
    }
}

/// A random stack within `ranges`, named `name`: 1 to `max_coats` dielectric coats (each with
/// a medium half the time under `tm6`) over one of the presets' conductors (60 %), a
/// Lambertian base (20 %) or nothing, so that it transmits (20 %); uniform within each range.
pub fn preset_like_stack(rng: &mut Rng, ranges: &PresetRanges, model: Model, name: &str) -> Stack {
    let within = |rng: &mut Rng, (lo, hi): (f64, f64)| rng.range(lo, hi);
    let coats = 1 + (rng.unit() * ranges.max_coats as f64) as usize % ranges.max_coats;
    let mut layers: Vec<LayerParams> = (0..coats)
        .map(|_| {
            let coat =
                LayerParams::dielectric(within(rng, ranges.ior), within(rng, ranges.roughness));
            if model == Model::Tm6 && rng.unit() < 0.5 {
                let depth = within(rng, ranges.depth);
                let sigma_s = std::array::from_fn(|_| within(rng, ranges.sigma_s));
                let sigma_a = std::array::from_fn(|_| within(rng, ranges.sigma_a));
                coat.with_medium(depth, sigma_s, sigma_a, within(rng, ranges.g))
            } else {
                coat
            }
        })
        .collect();
    let base = rng.unit();
    if base < 0.6 && !ranges.conductors.is_empty() {
        let k = (rng.unit() * ranges.conductors.len() as f64) as usize;
        layers.push(ranges.conductors[k.min(ranges.conductors.len() - 1)]);
    } else if base < 0.8 {
        layers.push(LayerParams::diffuse_base(std::array::from_fn(|_| {
            within(rng, ranges.albedo)
        })));
    }
    Stack {
        name: name.into(),
        model,
        layers,
        source: PathBuf::from(format!("<{name}>")),
        surface: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preset_like_stacks_are_valid_and_within_the_presets_ranges() {
        let ranges = PresetRanges::of_presets().expect("the presets");
        assert!(
            ranges.ior.0 < ranges.ior.1 && ranges.conductors.len() >= 4,
            "{ranges:?}"
        );
        let inside = |v: f64, (lo, hi): (f64, f64)| (lo..=hi).contains(&v);
        let mut rng = Rng(27);
        for k in 0..200 {
            let model = if k % 2 == 0 { Model::Tm2 } else { Model::Tm6 };
            let stack = preset_like_stack(&mut rng, &ranges, model, "random");
            // Valid as the format's parser would have it: it round-trips through TOML.
            let reparsed = Stack::from_toml(&stack.to_toml(), std::path::Path::new("random.toml"))
                .unwrap_or_else(|e| panic!("{e}\n{}", stack.to_toml()));
            assert_eq!(reparsed.layers.len(), stack.layers.len());
            for l in &stack.layers {
                if l.is_conductor() {
                    assert!(ranges.conductors.contains(l));
                } else if let Some(rho) = l.diffuse {
                    assert!(rho.iter().all(|&r| inside(r, ranges.albedo)));
                } else {
                    assert!(inside(l.ior[0], ranges.ior) && inside(l.roughness, ranges.roughness));
                    if l.depth > 0.0 {
                        assert!(inside(l.depth, ranges.depth) && inside(l.g, ranges.g));
                    }
                }
            }
        }
    }
}
