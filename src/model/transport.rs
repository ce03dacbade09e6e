//! `transport=corrected`: the transfer-matrix model's lobes with each layer's energy taken
//! from the discrete-ordinates transport of the same stack ([`super::angular`]), in either
//! interface mode.
//!
//! The paper's model (`transport=paper`) composes each interface as one directional
//! reflectance and 1 − r, and traps every upward crossing with the first crossing's TIR ratio.
//! Measured against the walk, that makes every rough coat too bright (+8 … +43 % on the
//! presets, ALGORITHMS.md §17). Remedies in the model's own terms — later crossings as a
//! diffuse class with hemispherical constants, the first crossing's TIR ratio kept per lobe —
//! stay short where it matters: light that total internal reflection sends back stays near
//! grazing and a glossy base returns it near grazing, so it is trapped far more often than
//! diffuse light and far less often than light beyond the critical angle taken as uniform;
//! and at grazing views the lobe's centre sits at the critical angle, where Fresnel's
//! transmission changes fastest, which one ratio per lobe cannot resolve. Light's angles
//! must be followed, which [`super::angular`] does.
//!
//! So each layer's energy comes from that transport, per material, tabulated at [`POINTS`]
//! view cosines as the ratio of its energy to the paper model's (layers the paper gives almost
//! nothing share a ratio with the next: [`GROUP_SHARE`]), and the model's lobes are scaled by
//! their layer's ratio, interpolated at the view's cosine: the lobes keep the
//! paper's shapes (their asymmetry composition), the energies follow light's angles, and a
//! material with maps keeps its per-pixel variation (the ratio is taken at its nominal
//! values). The stack's transmittance is scaled the same way.

use super::adding::avg;
use super::angular::Transport;
use super::oracle::evaluate_model;
use super::{Evaluation, Fgd, LayerParams, Tir, TopFresnel, INDEX_MATCHED};
use crate::variant::{Interfaces, Model};

/// View cosines at which a material's ratios are tabulated: k/(POINTS − 1). The transport
/// is computed at [`point`]`(k)`; the curve's first point is the ratio's linear extension to
/// μ = 0 (μ = 0 is no view at all) through its values at [`LOWEST`] and 1/(POINTS − 1), so the
/// curve is linear between evenly spaced cosines and a shader finds its interval with one
/// multiply (`glsl/include/lib/tm_common.glsl`'s `tm_transport_at`).
pub const POINTS: usize = 16;

/// The lowest view cosine the transport is computed at.
pub const LOWEST: f64 = 0.01;

/// Largest ratio a layer takes, a guard: layers the paper gives almost nothing are grouped
/// ([`GROUP_SHARE`]), but a variant's own approximations can still leave a layer an order of
/// magnitude short (`fgd=karis` under a layer denser above, on random stacks), and a map
/// that raised such a layer's energy would carry the ratio anywhere.
pub const MAX_RATIO: f64 = 64.0;

/// The view cosine the transport is computed at for point k.
pub fn point(k: usize) -> f64 {
    (k as f64 / (POINTS - 1) as f64).max(LOWEST)
}

/// One material's energy ratios.
#[derive(Clone, Debug, PartialEq)]
pub struct Correction {
    /// Per layer, per point, per channel: the transport's energy over the paper's.
    pub layers: Vec<[[f64; 3]; POINTS]>,
    /// Per point and channel: the same for the stack's transmittance.
    pub transmittance: [[f64; 3]; POINTS],
    /// The top interface's layer and relative IOR where its lobe is shaded with Fresnel's
    /// factor ([`top_reflects`]).
    pub top: Option<(usize, f64)>,
}

/// The layer and relative IOR (mean over RGB) of the stack's top interface — the first that
/// light from the air meets, every layer above it index-matched to the air and, in `model`
/// `tm6`, without a medium — where it is a dielectric that reflects that light: not
/// index-matched and denser than air. `transport=corrected` shades its lobe with its Fresnel
/// factor under lights ([`Evaluation::top_fresnel`]; `tm_top_reflects` in
/// lib/tm_common.glsl). An index-matched layer above changes nothing, as `lamina simplify`,
/// which removes it, needs.
pub fn top_reflects(layers: &[LayerParams], model: Model) -> Option<(usize, f64)> {
    for (i, layer) in layers.iter().enumerate() {
        if layer.is_conductor() || layer.is_diffuse() {
            return None;
        }
        let eta = avg(layer.ior) / super::IOR_AIR;
        if (eta - 1.0).abs() >= INDEX_MATCHED {
            return (eta >= 1.0).then_some((i, eta));
        }
        if model == Model::Tm6 && layer.depth > 0.0 {
            return None;
        }
    }
    None
}

fn ratio(truth: f64, paper: f64) -> f64 {
    if paper > 1e-9 {
        (truth / paper).clamp(0.0, MAX_RATIO)
    } else {
        1.0
    }
}

/// Share of the paper's reflectance below which a layer's energy does not get a ratio of its
/// own: a nearly index-matched rough layer reflects almost nothing in the paper's model, yet
/// adding it to the transport changes R by redirecting light towards the interfaces below —
/// a large ratio of two small numbers. Such layers share one ratio with the layers after them
/// until the group holds this share of R (the last group joins the one before it).
pub const GROUP_SHARE: f64 = 0.02;

/// Per layer, the ratio of the transport's energies `truth` to the paper's `paper` (one
/// channel), layers grouped until each group holds [`GROUP_SHARE`] of the paper's R.
fn grouped_ratios(truth: &[f64], paper: &[f64]) -> Vec<f64> {
    let floor = (GROUP_SHARE * paper.iter().sum::<f64>()).max(1e-9);
    let mut groups: Vec<(Vec<usize>, f64, f64)> = Vec::new();
    let mut open: (Vec<usize>, f64, f64) = (Vec::new(), 0.0, 0.0);
    for (i, (&a, &p)) in truth.iter().zip(paper).enumerate() {
        open.0.push(i);
        open.1 += a;
        open.2 += p;
        if open.2 >= floor {
            groups.push(std::mem::take(&mut open));
        }
    }
    if !open.0.is_empty() {
        match groups.last_mut() {
            Some(last) => {
                last.0.extend(open.0);
                last.1 += open.1;
                last.2 += open.2;
            }
            None => groups.push(open),
        }
    }
    let mut out = vec![1.0; truth.len()];
    for (members, a, p) in groups {
        let r = ratio(a, p);
        for i in members {
            out[i] = r;
        }
    }
    out
}

impl Correction {
    /// The ratios of the stack `layers` in `model` (its media exist under `tm6`), the paper's
    /// side with the given FGD and TIR providers, the transport's in interface mode `mode`.
    pub fn new(
        layers: &[LayerParams],
        model: Model,
        mode: Interfaces,
        fgd: &dyn Fgd,
        tir: &dyn Tir,
    ) -> Self {
        let transport = Transport::new(layers, model == Model::Tm6, mode);
        let mut per_layer = vec![[[1.0; 3]; POINTS]; layers.len()];
        let mut transmittance = [[1.0; 3]; POINTS];
        for k in 0..POINTS {
            let mu = point(k);
            let (cumulative, t) = transport.reflectances(mu);
            let paper = evaluate_model(model, layers, mu, fgd, tir);
            let mut energy = vec![[0.0; 3]; layers.len()];
            for (lobe, &layer) in paper.lobes.iter().zip(&paper.lobe_layers) {
                for (sum, w) in energy[layer].iter_mut().zip(lobe.weight) {
                    *sum += w;
                }
            }
            let mut below = [0.0; 3];
            let truth: Vec<[f64; 3]> = cumulative
                .iter()
                .map(|r| {
                    let d = std::array::from_fn(|c| r[c] - below[c]);
                    below = *r;
                    d
                })
                .collect();
            for c in 0..3 {
                let a: Vec<f64> = truth.iter().map(|d| d[c]).collect();
                let p: Vec<f64> = energy.iter().map(|e| e[c]).take(a.len()).collect();
                for (i, r) in grouped_ratios(&a, &p).into_iter().enumerate() {
                    per_layer[i][k][c] = r;
                }
            }
            transmittance[k] = std::array::from_fn(|c| ratio(t[c], paper.transmittance[c]));
        }
        for curve in per_layer.iter_mut().chain([&mut transmittance]) {
            extend_to_zero(curve);
        }
        Self {
            layers: per_layer,
            transmittance,
            top: top_reflects(layers, model),
        }
    }

    /// Layer `layer`'s ratio at view cosine `mu`, linear between the points.
    pub fn at(&self, layer: usize, mu: f64) -> [f64; 3] {
        self.layers
            .get(layer)
            .map_or([1.0; 3], |curve| interpolate(curve, mu))
    }

    /// `evaluation` (the paper's f64 model's at view cosine `mu`: its lobes' layers known)
    /// with each lobe scaled by its layer's ratio, and R and T to match; the top interface's
    /// first lobe marked as its Fresnel lobe where it reflects ([`top_reflects`]), with the
    /// albedo the paper gave it (nothing above reflects, so its weight is the interface's own
    /// albedo).
    pub fn apply(&self, evaluation: &mut Evaluation, mu: f64) {
        assert_eq!(
            evaluation.lobes.len(),
            evaluation.lobe_layers.len(),
            "a corrected evaluation needs each lobe's layer (the f64 model's)"
        );
        evaluation.top_fresnel = self.top.and_then(|(layer, eta)| {
            let lobe = evaluation.lobe_layers.iter().position(|&l| l == layer)?;
            Some(TopFresnel {
                lobe,
                eta,
                albedo: evaluation.lobes[lobe].weight[0],
            })
        });
        let mut reflectance = [0.0; 3];
        for (lobe, &layer) in evaluation.lobes.iter_mut().zip(&evaluation.lobe_layers) {
            let r = self.at(layer, mu);
            for c in 0..3 {
                lobe.weight[c] *= r[c];
                reflectance[c] += lobe.weight[c];
            }
        }
        evaluation.reflectance = reflectance;
        let t = interpolate(&self.transmittance, mu);
        for (transmitted, ratio) in evaluation.transmittance.iter_mut().zip(t) {
            *transmitted *= ratio;
        }
    }
}

/// Replaces point 0 (computed at [`LOWEST`]) by the line through it and point 1, taken to
/// μ = 0 and kept within the ratios' range.
fn extend_to_zero(curve: &mut [[f64; 3]; POINTS]) {
    let step = point(1) - LOWEST;
    let next = curve[1];
    for (v, upper) in curve[0].iter_mut().zip(next) {
        let slope = (upper - *v) / step;
        *v = (*v - slope * LOWEST).clamp(0.0, MAX_RATIO);
    }
}

/// A tabulated curve at `mu` (clamped to [0, 1]), linear between the evenly spaced points.
fn interpolate(curve: &[[f64; 3]; POINTS], mu: f64) -> [f64; 3] {
    let x = mu.clamp(0.0, 1.0) * (POINTS - 1) as f64;
    let k = (x as usize).min(POINTS - 2);
    let f = x - k as f64;
    std::array::from_fn(|c| curve[k][c] + f * (curve[k + 1][c] - curve[k][c]))
}

/// The corrected model at one view cosine (builds the material's ratios: for one cosine or
/// a few; keep a [`Correction`] for many).
pub fn evaluate(
    model: Model,
    mode: Interfaces,
    layers: &[LayerParams],
    mu: f64,
    fgd: &dyn Fgd,
    tir: &dyn Tir,
) -> Evaluation {
    let correction = Correction::new(layers, model, mode, fgd, tir);
    let mut evaluation = evaluate_model(model, layers, mu, fgd, tir);
    correction.apply(&mut evaluation, mu);
    evaluation
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::fgd::ExactFgd;
    use crate::model::tm2::tests::{coat, gold};
    use crate::model::NoTir;
    use crate::variant::G2;

    #[test]
    fn at_the_points_the_energies_are_the_transports() {
        let fgd = ExactFgd::new(G2::HeightCorrelated);
        let film = LayerParams {
            depth: 0.4,
            sigma_s: [1.0, 2.0, 0.5],
            sigma_a: [0.3, 0.1, 0.6],
            g: 0.4,
            ..coat(1.5, 0.3)
        };
        let cases: [(&[LayerParams], Model); 3] = [
            (&[coat(1.5, 0.05), gold(0.25)], Model::Tm2),
            (&[film, gold(0.2)], Model::Tm6),
            (&[film, coat(1.3, 0.1)], Model::Tm6),
        ];
        for (layers, model) in cases {
            let correction = Correction::new(layers, model, Interfaces::Single, &fgd, &NoTir);
            let transport = Transport::new(layers, model == Model::Tm6, Interfaces::Single);
            for k in [0, 5, POINTS - 1] {
                let mu = point(k);
                let mut e = evaluate_model(model, layers, mu, &fgd, &NoTir);
                correction.apply(&mut e, mu);
                let (r, t) = transport.reflectances(mu);
                let r = *r.last().expect("layers");
                for c in 0..3 {
                    assert!(
                        (e.reflectance[c] - r[c]).abs() < 1e-9,
                        "{model} μ {mu}: {e:?} {r:?}"
                    );
                    assert!(
                        (e.transmittance[c] - t[c]).abs() < 1e-9,
                        "{model} μ {mu}: T {t:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn layers_with_little_energy_share_a_ratio() {
        // The second layer holds 1e-4 of the paper's R but 0.01 of the truth: alone its
        // ratio would be 100; grouped with the third, both take (0.01 + 0.4)/(1e-4 + 0.5).
        let r = grouped_ratios(&[0.1, 0.01, 0.4], &[0.1, 1e-4, 0.5]);
        assert_eq!(r[0], 1.0);
        assert!(
            (r[1] - 0.41 / 0.5001).abs() < 1e-12 && r[1] == r[2],
            "{r:?}"
        );
        // A small last layer joins the group before it; the energies add up either way.
        let (a, p) = ([0.2, 0.3, 0.001], [0.25, 0.35, 1e-5]);
        let r = grouped_ratios(&a, &p);
        let total: f64 = r.iter().zip(&p).map(|(r, p)| r * p).sum();
        assert!((total - a.iter().sum::<f64>()).abs() < 1e-12, "{r:?}");
    }

    #[test]
    fn between_the_points_the_ratio_is_interpolated() {
        let mut curve = [[0.0; 3]; POINTS];
        for (k, v) in curve.iter_mut().enumerate() {
            *v = [point(k); 3];
        }
        // A ratio linear in μ, computed at the points, is reproduced exactly, below the
        // lowest computed cosine too.
        extend_to_zero(&mut curve);
        for mu in [0.0, 0.001, 0.05, 0.33, 0.5, 0.99, 1.0] {
            assert!((interpolate(&curve, mu)[0] - mu).abs() < 1e-12, "μ {mu}");
        }
        // A line that would fall below zero at μ = 0 stops there at 0.
        let mut steep = [[1.0; 3]; POINTS];
        steep[0] = [0.0; 3];
        extend_to_zero(&mut steep);
        assert_eq!(steep[0], [0.0; 3]);
        assert!((interpolate(&steep, 1.0 / 15.0)[0] - 1.0).abs() < 1e-12);
    }
}
