//! Static simplification of a stack (DESIGN.md §8, issue 11): the layers and media the model
//! provably ignores, taken out before the stack is shaded, so that a specialized shader carries
//! no dead layer. [`simplify`] applies each rule only where the f64 model (`model/tm2.rs`,
//! `model/tm6.rs`) gives the same reflectance, transmittance and lobes — to the bit, not merely
//! to a tolerance — and says why in a [`Step`]; the property test (`simplify_properties.rs`)
//! holds it to 1e-9 over random stacks planted with every rule's trigger, and finds no
//! difference at all.
//!
//! Rules, in the order they run:
//! 1. **Unreachable layers** (6-flux): below a medium whose transmission is exactly 0 in f64
//!    ([`OPAQUE_OPTICAL_DEPTH`]) no light arrives, so the layers there are removed — all but
//!    the first, whose roughness the opaque layer's own interface reads, unless that interface
//!    is index-matched ([`Step::Unreachable`]).
//!    A conductor above another layer would be the obvious case, but validation refuses it
//!    (a conductor is the last layer, `layer.rs`), and the model stops there anyway.
//! 2. **Index-matched interfaces**: the model skips an interface whose relative IOR is within
//!    [`INDEX_MATCHED`] of 1 ([`Step::IndexMatched`]); such a layer goes where nothing else in
//!    the model reads it ([`Step::MatchedKept`] says what does).
//! 3. **Zero-depth media** (6-flux): a medium of depth 0 is never evaluated; its coefficients
//!    are cleared, which makes the layer a 2-flux one ([`Step::ZeroDepthMedium`]).
//!
//! Refused, because the model does not give the same values:
//! - **Merging two media** under an index-matched interface into one of summed depth (or an
//!   index-matched layer's medium into the medium-less layer above it). The model's
//!   two-stream factors compose exactly only in exact arithmetic and for grey media (the
//!   asymmetries g_rfb and g_tff are averaged over RGB, `tm6.rs` `medium_factors`); each medium
//!   emits its own lobes, which a merged medium emits as one; and the interface above a
//!   medium reads that medium's g_tff at its own depth (`tm6.rs`: `let g_st0j_r = g_st0j *
//!   g_medium * g_next * g_medium;`). The unit tests `merging_equal_media_changes_the_lobes`
//!   and `a_matched_layer_with_a_medium_stays` show the values change.
//! - **Switching a 6-flux stack without media to the 2-flux model**: the two agree on
//!   reflectance and transmittance (to rounding), not on the lobes — the 6-flux model emits
//!   one per component (a zero one per empty medium) and averages each lobe's asymmetry per
//!   channel, the 2-flux one averages the energies first (unit test
//!   `without_media_tm2_and_tm6_differ_in_the_lobes`). [`Step::NoMedium`] reports it and the
//!   model stays.
//!
//! Layer numbers in steps are 1-based, top first, in the stack as given (as in the material
//! errors).

use std::fmt;

use super::Stack;
use crate::model::adding::avg;
use crate::model::{hg, LayerParams, INDEX_MATCHED, IOR_AIR};
use crate::variant::Model;

/// σ_a·depth at and above which a 6-flux medium transmits exactly nothing in f64, at every
/// view cosine in (0, 1]: e^−746 is below half the smallest subnormal, so `exp` returns 0.
///
/// Why every exponent the medium forms is at least this (`tm6.rs` `medium_factors` and
/// `two_stream`): τ = depth / max(μ, 1e-7) ≥ depth since μ ≤ 1; the primary transmission is
/// `(-sigma_ext * tau).exp()` with σ_ext = σ_s + max(σ_a, 1e-7) ≥ σ_a; the scattered one is
/// 2γ·`(-x).exp()`/den with x = γτ and γ = √(σ_k(2σ_sb + σ_k)) ≥ σ_k ≥ σ_a (the square root of
/// a rounded square is exact, and rounding is monotonic, so each bound holds for the rounded
/// values too). Then the medium's operator t is 0 (`Component6::medium`: T, t_ff − T and t_ff),
/// and so is the g-weighted one (bounded by it, `adding.rs` `bound`): every downward flux
/// below is 0 and adds 0 to what goes up (`Slab6::over`: `up += T′·r·(W·down)`, with W finite by
/// its floored determinant), the transmittance is 0 with or without the layers below, and
/// their lobes weigh exactly 0 (the 6-flux lobes are per component, so the list loses only
/// zero lobes).
pub const OPAQUE_OPTICAL_DEPTH: f64 = 746.0;

/// What simplification did to one part of the stack, or why it left it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step {
    /// Layers `first..=last` lie below the medium of layer `opaque`, which transmits nothing
    /// ([`OPAQUE_OPTICAL_DEPTH`]): removed. `kept` is the layer just below the opaque one when
    /// it stays: the opaque layer's interface reads its roughness (`tm6.rs`: `let g_next =
    /// next.map_or(0.0, |l| hg::g_of_alpha(l.roughness));`) for the light its medium sends
    /// back up. It is `None` when the opaque layer's interface is index-matched (skipped, so
    /// nothing reads the roughness).
    Unreachable {
        opaque: usize,
        kept: Option<usize>,
        first: usize,
        last: usize,
    },
    /// Layer `layer` (mean η `eta`) is index-matched with layer `above` (`None`: the medium
    /// above the stack, η = [`IOR_AIR`]) — the model skips its interface — and nothing else
    /// reads it: removed.
    ///
    /// Exact because the skipped interface contributes nothing: 2-flux, `tm2.rs`: `Some(eta)
    /// if (eta - 1.0).abs() < INDEX_MATCHED => (r_prev, g_prev, g_t0i),` — no component, the
    /// direction, η above and the path's g unchanged, and a lobe of weight exactly 0 (lobe k
    /// belongs to layer k, so the lobes of the other layers stay theirs); 6-flux, `tm6.rs`:
    /// `steps.push(Step::Nothing);` for the interface and (depth 0) for the medium, whose
    /// lobes are Δ = 0. The one other read of a layer is its roughness, by the refracting
    /// layer directly above it as the next interface's reflection g (`tm2.rs`/`tm6.rs`: `let
    /// g_next = stack.get(i + 1)…`); removal keeps it where that layer is absent or skipped,
    /// where the layer below has the same g, or where nothing under the reading interface
    /// scatters light back up through it (the layer is the last, and in 6-flux the reader has
    /// no medium): g_next only shapes the interface's upward factors (r′, t′ and their g's,
    /// and the TIR correction for η ≥ 1), which then meet no light. The last layer of a
    /// stack stays ([`Kept::OnlyLayer`]).
    IndexMatched {
        layer: usize,
        eta: f64,
        above: Option<usize>,
    },
    /// Layer `layer` is index-matched with layer `above` (`None`: the medium above the stack)
    /// but stays, for the reason `why`. The model already skips its interface.
    MatchedKept {
        layer: usize,
        eta: f64,
        above: Option<usize>,
        why: Kept,
    },
    /// Layer `layer`'s medium has depth 0 but non-zero coefficients: they are cleared.
    ///
    /// Exact because the model reads a medium only behind `layer.depth > 0.0` (`tm6.rs`: the
    /// medium step, `if layer.depth > 0.0 {`, else `steps.push(Step::Nothing);`, and the
    /// interface's `let g_medium = if layer.depth > 0.0 {`).
    ZeroDepthMedium { layer: usize },
    /// A 6-flux stack with no medium left. The 2-flux model would give the same reflectance
    /// and transmittance but other lobes (module docs), so the model stays.
    NoMedium,
}

/// Why an index-matched layer stays ([`Step::MatchedKept`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kept {
    /// It holds a medium of this depth, which the model evaluates: the interface is skipped,
    /// the medium is not, and it cannot be merged into the layer above (module docs).
    Medium { depth: f64 },
    /// The refracting layer above reads its roughness α (`g_next`), and removing it would
    /// change what that layer reads: the layer below has another g, or (6-flux) it is the
    /// last and the reader's medium sends light back up through the reader's interface.
    RoughnessRead { roughness: f64 },
    /// It is the only layer left, and a stack holds at least one (the model gives an empty
    /// stack no transmission, a skipped layer transmits everything).
    OnlyLayer,
}

impl Step {
    /// Whether the step changed the stack (rather than explaining why a part stays).
    pub fn changes_stack(&self) -> bool {
        match self {
            Step::Unreachable { .. } | Step::IndexMatched { .. } | Step::ZeroDepthMedium { .. } => {
                true
            }
            Step::MatchedKept { .. } | Step::NoMedium => false,
        }
    }

    /// A stable name of the rule, for `lamina simplify --json`.
    pub fn kind(&self) -> &'static str {
        match self {
            Step::Unreachable { .. } => "unreachable",
            Step::IndexMatched { .. } => "index-matched",
            Step::MatchedKept { .. } => "index-matched-kept",
            Step::ZeroDepthMedium { .. } => "zero-depth-medium",
            Step::NoMedium => "no-medium",
        }
    }

    /// The layer the step is about (1-based, in the stack as given): the removed, kept or
    /// demoted one, the first removed for unreachable layers; `None` for the whole stack.
    pub fn layer(&self) -> Option<usize> {
        match *self {
            Step::Unreachable { first, .. } => Some(first),
            Step::IndexMatched { layer, .. }
            | Step::MatchedKept { layer, .. }
            | Step::ZeroDepthMedium { layer } => Some(layer),
            Step::NoMedium => None,
        }
    }
}

/// "layer 2 above it" or "the medium above the stack".
fn matched_with(above: Option<usize>) -> String {
    match above {
        Some(k) => format!("layer {k} above it"),
        None => format!("the medium above the stack (η {IOR_AIR})"),
    }
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Step::Unreachable {
                opaque,
                kept,
                first,
                last,
            } => {
                let layers = if first == last {
                    format!("layer {first} below receives")
                } else {
                    format!("layers {first}–{last} below receive")
                };
                write!(
                    f,
                    "layer {opaque}'s medium transmits nothing (σ_a·depth ≥ \
                     {OPAQUE_OPTICAL_DEPTH} in every channel): {layers} no light: removed"
                )?;
                if let Some(k) = kept {
                    write!(
                        f,
                        " (layer {k} stays: layer {opaque}'s interface reads its roughness)"
                    )?;
                }
                Ok(())
            }
            Step::IndexMatched { layer, eta, above } => write!(
                f,
                "layer {layer} (η {eta:.2}) is index-matched with {}: removed",
                matched_with(above)
            ),
            Step::MatchedKept {
                layer,
                eta,
                above,
                why,
            } => {
                write!(
                    f,
                    "layer {layer} (η {eta:.2}) is index-matched with {} but kept: ",
                    matched_with(above)
                )?;
                match (why, above) {
                    (Kept::Medium { depth }, _) => write!(
                        f,
                        "the model skips its interface, not its medium (depth {depth})"
                    ),
                    (Kept::RoughnessRead { roughness }, Some(k)) => write!(
                        f,
                        "layer {k}'s interface reads its roughness (α {roughness:.2}) for the \
                         light it sends back up"
                    ),
                    (Kept::RoughnessRead { roughness }, None) => write!(
                        f,
                        "the interface above reads its roughness (α {roughness:.2})"
                    ),
                    (Kept::OnlyLayer, _) => write!(f, "a stack holds at least one layer"),
                }
            }
            Step::ZeroDepthMedium { layer } => write!(
                f,
                "layer {layer}'s medium has depth 0: demoted to a 2-flux layer"
            ),
            Step::NoMedium => write!(
                f,
                "no layer holds a medium: tm2 would give the same reflectance and transmittance \
                 but not the same lobes (tm6 emits one per component and averages lobe \
                 asymmetry per channel): model kept at tm6"
            ),
        }
    }
}

/// A stack after [`simplify`]: the same evaluation by the model, with fewer layers or media
/// where the rules allow.
#[derive(Clone, Debug, PartialEq)]
pub struct Simplified {
    /// The simplified stack (same name, model and source).
    pub stack: Stack,
    /// What was done, and why some parts stay, in the order the rules ran.
    pub steps: Vec<Step>,
    /// For each layer of `stack`, its index (0-based) in the stack as given.
    pub origin: Vec<usize>,
    /// The number of layers of the stack as given.
    pub layers_before: usize,
}

fn layer_count(n: usize) -> String {
    format!("{n} layer{}", if n == 1 { "" } else { "s" })
}

impl fmt::Display for Simplified {
    /// `NAME: 5 layers → 3` and one line per step, or `NAME: 2 layers, nothing to simplify`
    /// (then the reasons parts stay, if any).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let before = layer_count(self.layers_before);
        if self.steps.iter().any(Step::changes_stack) {
            writeln!(
                f,
                "{}: {before} → {}",
                self.stack.name,
                self.stack.layers.len()
            )?;
        } else {
            writeln!(f, "{}: {before}, nothing to simplify", self.stack.name)?;
        }
        for step in &self.steps {
            writeln!(f, "  {step}")?;
        }
        Ok(())
    }
}

/// What `lamina simplify --json` prints, in this order; other tools may parse it, so keep it
/// stable.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SimplifyReport {
    pub material: String,
    pub model: String,
    pub layers_before: usize,
    pub layers_after: usize,
    pub steps: Vec<StepReport>,
    /// The simplified stack's material file (the TOML of [`Stack::to_toml`]) as JSON.
    pub stack: serde_json::Value,
}

/// One [`Step`]: [`Step::kind`], [`Step::layer`] and its sentence.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepReport {
    pub kind: &'static str,
    pub layer: Option<usize>,
    pub text: String,
}

impl Simplified {
    /// The report as `lamina simplify --json` prints it.
    pub fn to_report(&self) -> SimplifyReport {
        let stack = toml::from_str(&self.stack.to_toml())
            .expect("Stack::to_toml writes TOML that loads back (material tests)");
        SimplifyReport {
            material: self.stack.name.clone(),
            model: self.stack.model.to_string(),
            layers_before: self.layers_before,
            layers_after: self.stack.layers.len(),
            steps: self
                .steps
                .iter()
                .map(|s| StepReport {
                    kind: s.kind(),
                    layer: s.layer(),
                    text: s.to_string(),
                })
                .collect(),
            stack,
        }
    }
}

/// What the model does with a layer's top interface, given the layers above it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Role {
    Conductor,
    /// Skipped: index-matched with layer `above` (current index; `None`: the medium above).
    Matched {
        above: Option<usize>,
    },
    Refracts,
}

/// Each layer's [`Role`], by the model's own chain: η relative to the last refracting layer
/// above (`tm2.rs` `relative_eta` and `eta_above = avg(layer.ior);`, the same in `tm6.rs`),
/// compared with [`INDEX_MATCHED`] by the same expression, so the verdict is the model's.
pub(super) fn roles(layers: &[LayerParams]) -> Vec<Role> {
    let mut eta_above = IOR_AIR;
    let mut above = None;
    layers
        .iter()
        .enumerate()
        .map(|(i, layer)| {
            // A diffuse base ends the stack as a conductor does; it has no interface to match.
            if layer.is_opaque_base() {
                return Role::Conductor;
            }
            let eta = avg(layer.ior) / eta_above;
            if (eta - 1.0).abs() < INDEX_MATCHED {
                Role::Matched { above }
            } else {
                eta_above = avg(layer.ior);
                above = Some(i);
                Role::Refracts
            }
        })
        .collect()
}

/// Whether a 6-flux layer's medium transmits exactly nothing ([`OPAQUE_OPTICAL_DEPTH`]).
fn opaque(layer: &LayerParams) -> bool {
    !layer.is_conductor()
        && layer
            .sigma_a
            .iter()
            .all(|&s| s * layer.depth >= OPAQUE_OPTICAL_DEPTH)
}

/// Whether a layer holds a medium the 6-flux model evaluates.
fn has_medium(layer: &LayerParams) -> bool {
    layer.depth > 0.0
}

/// The stack being simplified, with each layer's index in the stack as given.
struct Work {
    model: Model,
    layers: Vec<LayerParams>,
    origin: Vec<usize>,
    steps: Vec<Step>,
}

impl Work {
    /// 1-based number, in the stack as given, of current layer `i`.
    fn number(&self, i: usize) -> usize {
        self.origin[i] + 1
    }

    fn remove(&mut self, range: std::ops::Range<usize>) {
        self.layers.drain(range.clone());
        self.origin.drain(range);
    }

    /// Rule 1: the layers under the first opaque medium, but the one whose roughness the
    /// opaque layer's interface reads.
    fn drop_unreachable(&mut self) {
        if self.model != Model::Tm6 {
            return;
        }
        let Some(p) = self.layers.iter().position(opaque) else {
            return;
        };
        let skipped = matches!(roles(&self.layers)[p], Role::Matched { .. });
        let first = if skipped { p + 1 } else { p + 2 };
        let n = self.layers.len();
        if first >= n {
            return;
        }
        self.steps.push(Step::Unreachable {
            opaque: self.number(p),
            kept: (!skipped).then(|| self.number(p + 1)),
            first: self.number(first),
            last: self.number(n - 1),
        });
        self.remove(first..n);
    }

    /// Whether index-matched layer `i` can go (see [`Step::IndexMatched`]), else why not.
    fn removable(&self, i: usize, roles: &[Role]) -> Result<(), Kept> {
        let layer = &self.layers[i];
        let six_flux = self.model == Model::Tm6;
        if six_flux && has_medium(layer) {
            return Err(Kept::Medium { depth: layer.depth });
        }
        if self.layers.len() == 1 {
            return Err(Kept::OnlyLayer);
        }
        let Some(p) = i.checked_sub(1) else {
            return Ok(());
        };
        if roles[p] != Role::Refracts {
            return Ok(());
        }
        let read = hg::g_of_alpha(layer.roughness);
        match self.layers.get(i + 1) {
            Some(next) if hg::g_of_alpha(next.roughness) == read => Ok(()),
            None if !(six_flux && has_medium(&self.layers[p])) => Ok(()),
            _ => Err(Kept::RoughnessRead {
                roughness: layer.roughness,
            }),
        }
    }

    /// Rule 2, to a fixed point: one removal can make another exact (a matched layer under a
    /// matched one, then that one at the bottom). Removals are reported top first, then the
    /// matched layers that stay.
    fn remove_index_matched(&mut self) {
        let mut removed = Vec::new();
        loop {
            let roles = roles(&self.layers);
            let found = roles.iter().enumerate().find_map(|(i, role)| match *role {
                Role::Matched { above } if self.removable(i, &roles).is_ok() => Some((i, above)),
                _ => None,
            });
            let Some((i, above)) = found else {
                break;
            };
            removed.push(Step::IndexMatched {
                layer: self.number(i),
                eta: avg(self.layers[i].ior),
                above: above.map(|k| self.number(k)),
            });
            self.remove(i..i + 1);
        }
        removed.sort_by_key(|s| s.layer());
        self.steps.extend(removed);
        let roles = roles(&self.layers);
        for (i, role) in roles.iter().enumerate() {
            if let (Role::Matched { above }, Err(why)) = (*role, self.removable(i, &roles)) {
                self.steps.push(Step::MatchedKept {
                    layer: self.number(i),
                    eta: avg(self.layers[i].ior),
                    above: above.map(|k| self.number(k)),
                    why,
                });
            }
        }
    }

    /// Rule 3: zero-depth media lose their unread coefficients.
    fn demote_empty_media(&mut self) {
        if self.model != Model::Tm6 {
            return;
        }
        for i in 0..self.layers.len() {
            let layer = &mut self.layers[i];
            let coefficients =
                layer.sigma_s != [0.0; 3] || layer.sigma_a != [0.0; 3] || layer.g != 0.0;
            if layer.is_conductor() || has_medium(layer) || !coefficients {
                continue;
            }
            *layer = LayerParams {
                depth: 0.0,
                sigma_s: [0.0; 3],
                sigma_a: [0.0; 3],
                g: 0.0,
                ..*layer
            };
            let layer = self.number(i);
            self.steps.push(Step::ZeroDepthMedium { layer });
        }
    }
}

/// The stack with every rule of the module docs applied where it is exact in the model.
pub fn simplify(stack: &Stack) -> Simplified {
    let mut work = Work {
        model: stack.model,
        layers: stack.layers.clone(),
        origin: (0..stack.layers.len()).collect(),
        steps: Vec::new(),
    };
    work.drop_unreachable();
    work.remove_index_matched();
    work.demote_empty_media();
    if work.model == Model::Tm6 && !work.layers.iter().any(has_medium) {
        work.steps.push(Step::NoMedium);
    }
    Simplified {
        stack: Stack {
            layers: work.layers,
            ..stack.clone()
        },
        steps: work.steps,
        origin: work.origin,
        layers_before: stack.layers.len(),
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;
    use crate::material::presets;
    use crate::material::simplify_properties::{agree, ExactTir, TOLERANCE};
    use crate::model::fgd::ExactFgd;
    use crate::model::oracle::evaluate_model;
    use crate::model::tir::AnalyticTir;
    use crate::model::tm2::tests::{coat, gold};
    use crate::model::{Evaluation, NoTir, Tir};
    use crate::variant::G2;

    fn medium(layer: LayerParams, depth: f64, sigma_s: f64, sigma_a: f64) -> LayerParams {
        LayerParams {
            depth,
            sigma_s: [sigma_s; 3],
            sigma_a: [sigma_a; 3],
            g: 0.3,
            ..layer
        }
    }

    fn stack(model: Model, layers: Vec<LayerParams>) -> Stack {
        Stack {
            name: "case".into(),
            model,
            layers,
            source: PathBuf::from("<simplify test>"),
            surface: None,
        }
    }

    const COSINES: [f64; 4] = [0.05, 0.4, 0.9, 1.0];

    fn evaluate(stack: &Stack, mu: f64, tir: &dyn Tir) -> Evaluation {
        let fgd = ExactFgd {
            g2: G2::Smith,
            resolution: 24,
        };
        evaluate_model(stack.model, &stack.layers, mu, &fgd, tir)
    }

    /// Simplifies `stack` and checks that it evaluates as before (without and with TIR).
    fn simplified(stack: &Stack) -> Simplified {
        let s = simplify(stack);
        for mu in COSINES {
            for tir in [&NoTir as &dyn Tir, &AnalyticTir] {
                let (before, after) = (evaluate(stack, mu, tir), evaluate(&s.stack, mu, tir));
                if let Err(why) = agree(&s, &before, &after) {
                    panic!("μ = {mu}: {why}\n{s}{}", s.stack.to_toml());
                }
            }
        }
        s
    }

    /// Whether two evaluations differ beyond the tolerance somewhere (R, T, or the lobes that
    /// carry energy).
    fn differ(a: &Evaluation, b: &Evaluation) -> bool {
        let carrying = |e: &Evaluation| -> Vec<f64> {
            e.lobes
                .iter()
                .filter(|l| l.weight != [0.0; 3])
                .flat_map(|l| [l.weight[0], l.weight[1], l.weight[2], l.roughness])
                .collect()
        };
        let (x, y) = (carrying(a), carrying(b));
        x.len() != y.len()
            || x.iter().zip(&y).any(|(p, q)| (p - q).abs() > TOLERANCE)
            || (0..3).any(|c| {
                (a.reflectance[c] - b.reflectance[c]).abs() > TOLERANCE
                    || (a.transmittance[c] - b.transmittance[c]).abs() > TOLERANCE
            })
    }

    /// Whether `stack` with `layers` instead of its own evaluates otherwise, without TIR or
    /// with the exact trapped fraction: a simplification the rules refuse, shown to change
    /// the model's values.
    fn refused(stack: &Stack, layers: Vec<LayerParams>) -> bool {
        let other = Stack {
            layers,
            ..stack.clone()
        };
        let tirs = [&NoTir as &dyn Tir, &ExactTir];
        COSINES.iter().any(|&mu| {
            tirs.iter()
                .any(|&tir| differ(&evaluate(stack, mu, tir), &evaluate(&other, mu, tir)))
        })
    }

    #[test]
    fn an_index_matched_top_layer_goes() {
        let s = simplified(&stack(
            Model::Tm2,
            vec![coat(1.0, 0.3), coat(1.5, 0.1), gold(0.2)],
        ));
        let step = Step::IndexMatched {
            layer: 1,
            eta: 1.0,
            above: None,
        };
        assert_eq!(s.steps, [step]);
        assert_eq!(s.stack.layers, [coat(1.5, 0.1), gold(0.2)]);
        assert_eq!(s.origin, [1, 2]);
        // Nothing but index-matched layers: one stays, a stack is never empty.
        let s = simplified(&stack(Model::Tm2, vec![coat(1.0, 0.3), coat(1.0, 0.5)]));
        let kept = Step::MatchedKept {
            layer: 2,
            eta: 1.0,
            above: None,
            why: Kept::OnlyLayer,
        };
        assert_eq!(s.steps, [step, kept]);
        assert_eq!(s.stack.layers, [coat(1.0, 0.5)]);
        assert!(kept
            .to_string()
            .ends_with("but kept: a stack holds at least one layer"));
    }

    #[test]
    fn a_matched_layer_goes_where_nothing_reads_its_roughness() {
        // The layer below has the same roughness: the coat above reads the same g either way.
        let s = simplified(&stack(
            Model::Tm2,
            vec![coat(1.5, 0.1), coat(1.5, 0.2), gold(0.2)],
        ));
        assert_eq!(s.stack.layers, [coat(1.5, 0.1), gold(0.2)]);
        // The last layer, under a coat without medium: nothing comes back up to the coat.
        for model in [Model::Tm2, Model::Tm6] {
            let s = simplified(&stack(model, vec![coat(1.5, 0.1), coat(1.5, 0.3)]));
            assert_eq!(s.stack.layers, [coat(1.5, 0.1)], "{model}");
        }
        // A matched layer under a matched layer (whose interface is skipped), then that one.
        let s = simplified(&stack(
            Model::Tm2,
            vec![coat(1.5, 0.1), coat(1.5, 0.3), coat(1.5, 0.5)],
        ));
        let removed = |layer| Step::IndexMatched {
            layer,
            eta: 1.5,
            above: Some(1),
        };
        assert_eq!(s.steps, [removed(2), removed(3)]);
        assert_eq!(s.origin, [0]);
    }

    #[test]
    fn a_matched_layer_whose_roughness_is_read_stays() {
        let cases = [
            // Another roughness below it.
            stack(Model::Tm2, vec![coat(1.5, 0.1), coat(1.5, 0.3), gold(0.2)]),
            // The last layer, under a coat whose medium sends light back up (forward
            // scattering, so that the path's g stays above 0.2284, where α(g) clamps at 1).
            stack(
                Model::Tm6,
                vec![
                    LayerParams {
                        g: 0.95,
                        ..medium(coat(1.5, 0.1), 0.5, 0.5, 0.1)
                    },
                    coat(1.5, 0.3),
                ],
            ),
        ];
        for case in cases {
            let s = simplified(&case);
            let kept = Step::MatchedKept {
                layer: 2,
                eta: 1.5,
                above: Some(1),
                why: Kept::RoughnessRead { roughness: 0.3 },
            };
            assert_eq!(s.steps, [kept], "{}", case.model);
            assert!(
                s.to_string().contains(
                    "layer 2 (η 1.50) is index-matched with layer 1 above it but kept: layer 1's \
                     interface reads its roughness (α 0.30) for the light it sends back up"
                ),
                "{s}"
            );
            assert_eq!(s.stack, case);
            let mut without = case.layers.clone();
            without.remove(1);
            assert!(refused(&case, without), "{}: removal is exact", case.model);
        }
    }

    #[test]
    fn a_matched_layer_with_a_medium_stays() {
        let case = stack(
            Model::Tm6,
            vec![
                coat(1.5, 0.1),
                medium(coat(1.5, 0.2), 0.5, 2.0, 0.1),
                gold(0.2),
            ],
        );
        let s = simplified(&case);
        let kept = Step::MatchedKept {
            layer: 2,
            eta: 1.5,
            above: Some(1),
            why: Kept::Medium { depth: 0.5 },
        };
        assert_eq!(s.steps, [kept]);
        assert_eq!(s.stack, case);
        // Its medium moved up into the medium-less coat above: the coat's interface then reads
        // the medium's g_tff (and the gold's roughness), so the lobes change.
        let moved = vec![medium(coat(1.5, 0.1), 0.5, 2.0, 0.1), gold(0.2)];
        assert!(refused(&case, moved));
    }

    #[test]
    fn merging_equal_media_changes_the_lobes() {
        // Two equal media with an index-matched interface between them, the lower layer with
        // the substrate's roughness so that the coat above reads the same g either way.
        let case = stack(
            Model::Tm6,
            vec![
                medium(coat(1.5, 0.1), 0.3, 2.0, 0.1),
                medium(coat(1.5, 0.2), 0.4, 2.0, 0.1),
                gold(0.2),
            ],
        );
        let s = simplified(&case);
        assert!(!s.steps.iter().any(Step::changes_stack), "{s}");
        let merged = vec![medium(coat(1.5, 0.1), 0.7, 2.0, 0.1), gold(0.2)];
        assert!(refused(&case, merged));
    }

    #[test]
    fn zero_depth_media_are_demoted() {
        let case = stack(
            Model::Tm6,
            vec![
                medium(coat(1.5, 0.1), 0.0, 2.0, 0.5),
                medium(coat(1.3, 0.2), 0.4, 1.0, 0.1),
                gold(0.2),
            ],
        );
        let s = simplified(&case);
        assert_eq!(s.steps, [Step::ZeroDepthMedium { layer: 1 }]);
        assert_eq!(s.stack.layers[0], coat(1.5, 0.1));
        assert_eq!(s.stack.layers[1..], case.layers[1..]);
        // No medium left: reported, the model stays.
        let case = stack(Model::Tm6, vec![medium(coat(1.5, 0.1), 0.0, 2.0, 0.5)]);
        let s = simplified(&case);
        assert_eq!(
            s.steps,
            [Step::ZeroDepthMedium { layer: 1 }, Step::NoMedium]
        );
        assert_eq!(s.stack.model, Model::Tm6);
    }

    #[test]
    fn layers_under_an_opaque_medium_go() {
        assert_eq!((-OPAQUE_OPTICAL_DEPTH).exp(), 0.0);
        assert!((-(OPAQUE_OPTICAL_DEPTH - 1.0)).exp() > 0.0);
        let opaque = |ior| medium(coat(ior, 0.1), 10.0, 3.0, 80.0);
        let below = vec![coat(1.3, 0.2), coat(1.7, 0.3), gold(0.2)];
        let s = simplified(&stack(
            Model::Tm6,
            [vec![opaque(1.5)], below.clone()].concat(),
        ));
        let step = Step::Unreachable {
            opaque: 1,
            kept: Some(2),
            first: 3,
            last: 4,
        };
        assert_eq!(s.steps, [step]);
        assert_eq!(s.stack.layers, [opaque(1.5), coat(1.3, 0.2)]);
        assert_eq!(
            step.to_string(),
            "layer 1's medium transmits nothing (σ_a·depth ≥ 746 in every channel): layers 3–4 \
             below receive no light: removed (layer 2 stays: layer 1's interface reads its \
             roughness)"
        );
        // Under an index-matched interface nothing reads the next layer's roughness.
        let s = simplified(&stack(
            Model::Tm6,
            [vec![opaque(1.0)], below.clone()].concat(),
        ));
        let removed = s.steps.iter().find(|s| s.kind() == "unreachable");
        let step = Step::Unreachable {
            opaque: 1,
            kept: None,
            first: 2,
            last: 4,
        };
        assert_eq!(removed, Some(&step));
        assert_eq!(s.stack.layers, [opaque(1.0)]);
        // Just short of opaque in one channel: everything stays.
        let mut short = opaque(1.5);
        short.sigma_a[2] = 74.5;
        let case = stack(Model::Tm6, [vec![short], below].concat());
        assert_eq!(simplified(&case).stack, case);
    }

    #[test]
    fn without_media_tm2_and_tm6_differ_in_the_lobes() {
        let layers = vec![coat(1.5, 0.05), coat(1.3, 0.1), gold(0.1)];
        let (two, six) = (stack(Model::Tm2, layers.clone()), stack(Model::Tm6, layers));
        assert_eq!(simplify(&six).steps, [Step::NoMedium]);
        let mut lobes_differ = false;
        for mu in COSINES {
            let (a, b) = (evaluate(&two, mu, &NoTir), evaluate(&six, mu, &NoTir));
            for c in 0..3 {
                assert!((a.reflectance[c] - b.reflectance[c]).abs() < TOLERANCE);
                assert!((a.transmittance[c] - b.transmittance[c]).abs() < TOLERANCE);
            }
            lobes_differ |= differ(&a, &b);
        }
        assert!(lobes_differ, "tm2 and tm6 agree on the lobes too");
    }

    #[test]
    fn the_report_names_each_step() {
        let case = Stack {
            name: "report case".into(),
            ..stack(
                Model::Tm6,
                vec![
                    medium(coat(1.5, 0.1), 0.0, 2.0, 0.5),
                    coat(1.5, 0.3),
                    gold(0.3),
                ],
            )
        };
        let s = simplified(&case);
        assert_eq!(
            s.to_string(),
            "report case: 3 layers → 2\n  \
             layer 2 (η 1.50) is index-matched with layer 1 above it: removed\n  \
             layer 1's medium has depth 0: demoted to a 2-flux layer\n  \
             no layer holds a medium: tm2 would give the same reflectance and transmittance \
             but not the same lobes (tm6 emits one per component and averages lobe asymmetry \
             per channel): model kept at tm6\n"
        );
        let json = serde_json::to_value(s.to_report()).unwrap();
        assert_eq!(json["material"], "report case");
        assert_eq!(json["model"], "tm6");
        assert_eq!(
            (
                json["layers_before"].as_u64(),
                json["layers_after"].as_u64()
            ),
            (Some(3), Some(2))
        );
        let kinds: Vec<_> = json["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| (s["kind"].as_str().unwrap(), s["layer"].as_u64()))
            .collect();
        assert_eq!(
            kinds,
            [
                ("index-matched", Some(2)),
                ("zero-depth-medium", Some(1)),
                ("no-medium", None)
            ]
        );
        assert_eq!(json["steps"][0]["text"], s.steps[0].to_string());
        let layers = json["stack"]["layer"].as_array().unwrap();
        assert_eq!(layers.len(), 2);
        assert_eq!(layers[0]["depth"], 0.0);
        // The matched layer of a kept case, and one at the top.
        let kept = Step::MatchedKept {
            layer: 3,
            eta: 1.5,
            above: Some(2),
            why: Kept::Medium { depth: 0.25 },
        };
        assert_eq!(
            kept.to_string(),
            "layer 3 (η 1.50) is index-matched with layer 2 above it but kept: the model skips \
             its interface, not its medium (depth 0.25)"
        );
        let top = Step::IndexMatched {
            layer: 1,
            eta: 1.0,
            above: None,
        };
        assert_eq!(
            top.to_string(),
            "layer 1 (η 1.00) is index-matched with the medium above the stack (η 1): removed"
        );
    }

    #[test]
    fn presets_have_nothing_to_simplify() {
        for path in presets() {
            let stack = Stack::load(&path).unwrap();
            let s = simplify(&stack);
            assert_eq!(s.stack, stack, "{}", path.display());
            assert!(s.to_string().contains("nothing to simplify"), "{s}");
        }
        let gold = Stack::resolve("gold").unwrap();
        assert_eq!(
            simplify(&gold).to_string(),
            "gold: 1 layer, nothing to simplify\n"
        );
    }
}
