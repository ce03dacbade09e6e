//! Property test of static simplification (issue 11): random stacks of both models, planted
//! with every rule's trigger — index-matched layers inserted anywhere above the substrate (with
//! the roughness of the layer below them or another, with a medium, with coefficients at depth
//! 0, or none), layers given the η of the layer above, media emptied to depth 0, media made
//! opaque or just short of it — at random view cosines. The simplified stack's evaluation must
//! equal the original's within 1e-9: reflectance, transmittance and the lobes (2-flux: lobe k
//! belongs to layer k, so the lobes pair by layer and a removed layer's lobe must weigh 0;
//! 6-flux: lobes are per component, so both lists are compared without the lobes that weigh
//! exactly 0 in every channel). Every rule is exact to the bit, and the largest difference
//! seen is printed (0 so far).
//!
//! Two provider sets: the CPU oracle itself (`oracle::evaluate`: FGD integrated at 512², no
//! TIR), for a few hundred cases because it is slow, and the model with a coarse FGD
//! quadrature and each TIR provider the CPU has without a GPU (none, constant, the analytic
//! estimator, the exact trapped fraction), for the bulk. The test counts how often each rule
//! fired and fails below [`MIN_FIRES`], so it cannot pass by no longer exercising a rule. The
//! seed is printed; `LAMINA_PROPERTY_SEED=N` replays a run, and a failure prints the stack as
//! given and simplified as material files.

use std::collections::BTreeMap;
use std::time::Instant;

use super::random::random_stack;
use super::simplify::{roles, simplify, Role, Simplified, Step};
use super::Stack;
use crate::model::fgd::ExactFgd;
use crate::model::oracle;
use crate::model::random::{case_seed, Rng};
use crate::model::tir::{trapped_fraction, AnalyticTir, ConstantTir, FitTir, CONSTANT_FRACTION};
use crate::model::tir_fit::COEFFICIENTS;
use crate::model::{hg, Evaluation, Fgd, LayerParams, Lobe, NoTir, Tir, IOR_AIR};
use crate::variant::{Model, G2, MAX_LAYERS_LIMIT};

/// Cases per model with the coarse FGD and the TIR providers (about 2 s for both models).
const CASES: usize = 40_000;
/// Cases per model with the oracle itself (FGD at 512²: about 0.1 s per case and core), of
/// stacks that start from at most [`ORACLE_LAYERS`] layers.
const ORACLE_CASES: usize = 48;
const ORACLE_LAYERS: usize = 4;
/// How far the simplified stack's values may be from the original's.
pub(super) const TOLERANCE: f64 = 1e-9;
/// How often each rule must fire per model over the coarse cases.
const MIN_FIRES: usize = 500;

/// The exact trapped fraction (what the TIR table tabulates), coarse.
pub(super) struct ExactTir;

impl Tir for ExactTir {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        trapped_fraction(mu, alpha, eta, 6)
    }
}

/// The lobes that carry energy in some channel.
fn carrying(lobes: &[Lobe]) -> Vec<Lobe> {
    lobes
        .iter()
        .filter(|l| l.weight != [0.0; 3])
        .copied()
        .collect()
}

/// Whether `after` (the simplified stack's evaluation) equals `before` (the original's)
/// within [`TOLERANCE`], pairing lobes as the model allows (module docs); the largest
/// difference if so.
pub(super) fn agree(
    simplified: &Simplified,
    before: &Evaluation,
    after: &Evaluation,
) -> Result<f64, String> {
    let mut worst = 0.0f64;
    let mut check = |what: &str, a: f64, b: f64| {
        let d = (a - b).abs();
        worst = worst.max(d);
        if d <= TOLERANCE {
            Ok(())
        } else {
            Err(format!("{what}: {a} before, {b} after"))
        }
    };
    for c in 0..3 {
        check(
            &format!("R[{c}]"),
            before.reflectance[c],
            after.reflectance[c],
        )?;
        check(
            &format!("T[{c}]"),
            before.transmittance[c],
            after.transmittance[c],
        )?;
    }
    let pairs: Vec<(Lobe, Lobe)> = match simplified.stack.model {
        Model::Tm6 => {
            let (b, a) = (carrying(&before.lobes), carrying(&after.lobes));
            if a.len() != b.len() {
                return Err(format!(
                    "{} lobes with energy before, {} after",
                    b.len(),
                    a.len()
                ));
            }
            b.into_iter().zip(a).collect()
        }
        _ => {
            if after.lobes.len() != simplified.origin.len() {
                return Err(format!(
                    "{} lobes for {} layers",
                    after.lobes.len(),
                    simplified.origin.len()
                ));
            }
            for (k, l) in before.lobes.iter().enumerate() {
                if !simplified.origin.contains(&k) && l.weight != [0.0; 3] {
                    return Err(format!(
                        "removed layer {}'s lobe weighs {:?}",
                        k + 1,
                        l.weight
                    ));
                }
            }
            let kept = simplified.origin.iter().map(|&o| before.lobes[o]);
            kept.zip(after.lobes.iter().copied()).collect()
        }
    };
    for (k, (b, a)) in pairs.iter().enumerate() {
        for c in 0..3 {
            check(&format!("lobe {k} weight[{c}]"), b.weight[c], a.weight[c])?;
        }
        check(&format!("lobe {k} roughness"), b.roughness, a.roughness)?;
    }
    Ok(worst)
}

/// A dielectric layer without medium.
fn clear(ior: [f64; 3], roughness: f64) -> LayerParams {
    LayerParams {
        ior,
        kappa: [0.0; 3],
        roughness,
        depth: 0.0,
        sigma_s: [0.0; 3],
        sigma_a: [0.0; 3],
        g: 0.0,
        diffuse: None,
    }
}

/// Random medium coefficients, at `depth`.
fn with_medium(rng: &mut Rng, layer: LayerParams, depth: f64) -> LayerParams {
    LayerParams {
        depth,
        sigma_s: [
            rng.range(0.0, 20.0),
            rng.range(0.0, 20.0),
            rng.range(0.0, 20.0),
        ],
        sigma_a: [
            rng.range(0.0, 5.0),
            rng.range(0.0, 5.0),
            rng.range(0.0, 5.0),
        ],
        g: rng.range(-0.9, 0.9),
        ..layer
    }
}

/// The layers above the substrate (all of them when the stack ends in a dielectric).
fn coats(stack: &Stack) -> usize {
    let n = stack.layers.len();
    match stack.layers.last() {
        Some(l) if l.is_conductor() => n - 1,
        _ => n,
    }
}

fn index(rng: &mut Rng, n: usize) -> usize {
    ((rng.unit() * n as f64) as usize).min(n.saturating_sub(1))
}

/// Plants one rule's trigger in `stack` (module docs).
fn plant(rng: &mut Rng, stack: &mut Stack) {
    let six_flux = stack.model == Model::Tm6;
    let coats = coats(stack);
    match index(rng, 5) {
        // An index-matched layer: the η of the layer above it (1 at the top), so its relative
        // IOR is exactly 1, or within rounding of the above layer's own ratio when that one is
        // matched too.
        0 | 1 if stack.layers.len() < MAX_LAYERS_LIMIT as usize => {
            let k = index(rng, coats + 1);
            let ior = if k == 0 {
                [IOR_AIR; 3]
            } else {
                stack.layers[k - 1].ior
            };
            let roughness = match stack.layers.get(k) {
                Some(next) if rng.unit() < 0.5 => next.roughness,
                _ => rng.unit(),
            };
            let mut layer = clear(ior, roughness);
            if six_flux {
                match rng.unit() {
                    x if x < 0.3 => {
                        let depth = rng.range(0.01, 3.0);
                        layer = with_medium(rng, layer, depth);
                    }
                    x if x < 0.6 => layer = with_medium(rng, layer, 0.0),
                    _ => {}
                }
            }
            stack.layers.insert(k, layer);
        }
        // An existing coat given the η of the coat above it.
        2 if coats >= 2 => {
            let i = 1 + index(rng, coats - 1);
            stack.layers[i].ior = stack.layers[i - 1].ior;
        }
        // A medium emptied to depth 0, its coefficients kept (or given some).
        3 if six_flux && coats >= 1 => {
            let i = index(rng, coats);
            let layer = stack.layers[i];
            stack.layers[i] = if layer.sigma_s == [0.0; 3] && layer.sigma_a == [0.0; 3] {
                with_medium(rng, layer, 0.0)
            } else {
                LayerParams {
                    depth: 0.0,
                    ..layer
                }
            };
        }
        // A medium made opaque (σ_a·depth ≥ 746 in every channel), or, one time in four, just
        // short of it in one channel.
        4 if six_flux && coats >= 1 => {
            let i = index(rng, coats);
            let depth = rng.range(10.0, 100.0);
            let mut sigma_a = [0.0; 3].map(|_: f64| 746.0 / depth * rng.range(1.0, 3.0));
            if rng.unit() < 0.25 {
                sigma_a[index(rng, 3)] = 745.0 / depth;
            }
            stack.layers[i] = LayerParams {
                depth,
                sigma_a,
                ..with_medium(rng, stack.layers[i], depth)
            };
        }
        _ => {}
    }
}

/// A random stack of `model` (1 to `max_layers` layers) with 1 to 4 triggers planted, and a
/// view cosine.
fn planted_stack(rng: &mut Rng, model: Model, max_layers: usize) -> (Stack, f64) {
    let (mut stack, mu) = random_stack(rng, Some(model), max_layers);
    for _ in 0..1 + index(rng, 4) {
        plant(rng, &mut stack);
    }
    (stack, mu)
}

/// What one worker found: failures, the largest difference, how often each rule fired.
#[derive(Default)]
struct Tally {
    failures: Vec<String>,
    worst: f64,
    fired: BTreeMap<&'static str, usize>,
    cases: usize,
}

impl Tally {
    fn merge(mut self, other: Tally) -> Tally {
        self.failures.extend(other.failures);
        self.worst = self.worst.max(other.worst);
        for (k, n) in other.fired {
            *self.fired.entry(k).or_default() += n;
        }
        self.cases += other.cases;
        self
    }
}

/// Which of the reasons a removal is exact applied (`Step::IndexMatched`,
/// `Step::Unreachable`), read from the stack as given: for a matched layer, that it is the top
/// one, that the interface above it is skipped, that the layer below has the same roughness,
/// or else that it ended up last (its layers below removed first, or none).
fn path(stack: &Stack, step: &Step) -> Option<&'static str> {
    match *step {
        Step::IndexMatched { layer, .. } => {
            let (o, layers) = (layer - 1, &stack.layers);
            let same_g = |a: &LayerParams, b: &LayerParams| {
                hg::g_of_alpha(a.roughness) == hg::g_of_alpha(b.roughness)
            };
            Some(if o == 0 {
                "index-matched: top"
            } else if roles(layers)[o - 1] != Role::Refracts {
                "index-matched: under a skipped interface"
            } else if layers
                .get(o + 1)
                .is_some_and(|next| same_g(next, &layers[o]))
            {
                "index-matched: same roughness below"
            } else {
                "index-matched: last"
            })
        }
        Step::Unreachable { kept: None, .. } => Some("unreachable: under a skipped interface"),
        _ => None,
    }
}

/// One case: simplify (which must leave nothing to simplify again), evaluate both stacks with
/// `evaluate`, compare.
fn run_case(
    tally: &mut Tally,
    label: &str,
    stack: &Stack,
    mu: f64,
    evaluate: impl Fn(&Stack) -> Evaluation,
) {
    let simplified = simplify(stack);
    tally.cases += 1;
    for step in &simplified.steps {
        *tally.fired.entry(step.kind()).or_default() += 1;
        if let Some(path) = path(stack, step) {
            *tally.fired.entry(path).or_default() += 1;
        }
    }
    if let Some(step) = simplify(&simplified.stack)
        .steps
        .into_iter()
        .find(Step::changes_stack)
    {
        tally.failures.push(format!(
            "{label}: simplifying again: {step}\n{simplified}--- simplified:\n{}",
            simplified.stack.to_toml()
        ));
    }
    match agree(&simplified, &evaluate(stack), &evaluate(&simplified.stack)) {
        Ok(d) => tally.worst = tally.worst.max(d),
        Err(why) => tally.failures.push(format!(
            "{label}, μ = {mu}: {why}\n{simplified}--- as given:\n{}--- simplified:\n{}",
            stack.to_toml(),
            simplified.stack.to_toml()
        )),
    }
}

/// Runs `cases` cases of `model` on all cores; `case(k, tally)` runs case k.
fn parallel(cases: usize, case: impl Fn(usize, &mut Tally) + Sync) -> Tally {
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|worker| {
                let case = &case;
                scope.spawn(move || {
                    let mut tally = Tally::default();
                    for k in (worker..cases).step_by(threads) {
                        case(k, &mut tally);
                    }
                    tally
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().expect("a property worker panicked"))
            .fold(Tally::default(), Tally::merge)
    })
}

#[test]
fn simplified_stacks_evaluate_as_the_originals() {
    let seed = std::env::var("LAMINA_PROPERTY_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .unwrap_or(0x51b1_1f1e_2026_0011);
    println!("simplify property test seed: {seed} (LAMINA_PROPERTY_SEED={seed} replays it)");
    let coarse = ExactFgd {
        g2: G2::Smith,
        resolution: 4,
    };
    let constant = ConstantTir(CONSTANT_FRACTION);
    let fit = FitTir(COEFFICIENTS);
    let tirs: [(&str, &(dyn Tir + Sync)); 5] = [
        ("no TIR", &NoTir),
        ("constant TIR", &constant),
        ("analytic TIR", &AnalyticTir),
        ("fitted TIR", &fit),
        ("exact TIR", &ExactTir),
    ];
    let mut failures = Vec::new();
    for (salt, model) in [(0x2f, Model::Tm2), (0x6f, Model::Tm6)] {
        let model_seed = seed ^ salt;
        let start = Instant::now();
        let tally = parallel(CASES, |k, tally| {
            let mut rng = Rng(case_seed(model_seed, k));
            let (stack, mu) = planted_stack(&mut rng, model, 8);
            let (name, tir) = tirs[k % tirs.len()];
            let label = format!("{model} case {k} (coarse FGD, {name})");
            run_case(tally, &label, &stack, mu, |s| {
                oracle::evaluate_model(model, &s.layers, mu, &coarse as &dyn Fgd, tir)
            });
        });
        let coarse_time = start.elapsed().as_secs_f64();
        let exact = parallel(ORACLE_CASES, |k, tally| {
            let mut rng = Rng(case_seed(model_seed ^ 0x0ac1e, k));
            let (stack, mu) = planted_stack(&mut rng, model, ORACLE_LAYERS);
            let label = format!("{model} oracle case {k}");
            run_case(tally, &label, &stack, mu, |s| {
                oracle::evaluate(s.base_variant(), &s.layers, mu)
            });
        });
        println!(
            "{model}: {} cases with the coarse FGD and 4 TIR providers in {coarse_time:.1} s, {} \
             with the oracle in {:.1} s; largest difference {:.1e}\n  rules fired: {:?}\n  in \
             the oracle cases: {:?}",
            tally.cases,
            exact.cases,
            start.elapsed().as_secs_f64() - coarse_time,
            tally.worst.max(exact.worst),
            tally.fired,
            exact.fired
        );
        let rules: &[&str] = match model {
            Model::Tm6 => &[
                "unreachable",
                "index-matched",
                "index-matched-kept",
                "zero-depth-medium",
                "no-medium",
            ],
            _ => &["index-matched", "index-matched-kept"],
        };
        let paths = [
            "index-matched: top",
            "index-matched: under a skipped interface",
            "index-matched: same roughness below",
            "index-matched: last",
        ];
        let paths = match model {
            Model::Tm6 => [&paths[..], &["unreachable: under a skipped interface"]].concat(),
            _ => paths.to_vec(),
        };
        let wanted = rules.iter().map(|r| (*r, MIN_FIRES));
        for (rule, min) in wanted.chain(paths.into_iter().map(|p| (p, MIN_FIRES / 5))) {
            let n = tally.fired.get(rule).copied().unwrap_or(0);
            assert!(
                n >= min,
                "{model}: {rule} fired {n} times in {CASES} cases (at least {min} wanted): the \
                 generator no longer exercises it"
            );
        }
        failures.extend(tally.merge(exact).failures);
    }
    assert!(
        failures.is_empty(),
        "{} cases failed (seed {seed}); the first:\n{}",
        failures.len(),
        failures[0]
    );
}

/// Cases per model under `transport=corrected` with single-scattering interfaces (each builds
/// the material's energy ratios twice), and with multiple-scattering ones, whose columns are
/// walks and cost more.
const CORRECTED_CASES: [usize; 2] = [32, 8];

/// `transport=corrected` ignores what simplification removes: its ratios come from the paper's
/// lobes (unchanged, above) and from the discrete-ordinates transport, to which an
/// index-matched interface of any roughness and a zero-depth medium are nothing
/// (`model::angular`'s `what_changes_nothing_changes_nothing`). The same planted stacks, both
/// models, both interface modes: the corrected evaluation of the simplified stack equals the
/// original's within the same tolerance.
#[test]
fn simplified_stacks_evaluate_as_the_originals_under_the_corrected_transport() {
    use crate::model::transport;
    use crate::variant::Interfaces;

    let coarse = ExactFgd {
        g2: G2::Smith,
        resolution: 4,
    };
    let mut failures = Vec::new();
    for (salt, model) in [(0x3c, Model::Tm2), (0x7c, Model::Tm6)] {
        for (mode, cases) in [Interfaces::Single, Interfaces::Multiple]
            .into_iter()
            .zip(CORRECTED_CASES)
        {
            let start = Instant::now();
            let tally = parallel(cases, |k, tally| {
                let mut rng = Rng(case_seed(0x51b1_1f1e_2027_0027 ^ salt, k));
                let (stack, mu) = planted_stack(&mut rng, model, 6);
                let label = format!("{model} case {k}, transport=corrected, interfaces={mode}");
                run_case(tally, &label, &stack, mu, |s| {
                    transport::evaluate(model, mode, &s.layers, mu, &coarse, &ExactTir)
                });
            });
            println!(
                "{model}, interfaces={mode}: {} corrected cases in {:.1} s, largest difference \
                 {:.1e}; rules fired: {:?}",
                tally.cases,
                start.elapsed().as_secs_f64(),
                tally.worst,
                tally.fired
            );
            let fired = tally.fired.get("index-matched").copied().unwrap_or(0);
            assert!(
                fired >= cases / 4,
                "{model}: index-matched fired {fired} times"
            );
            failures.extend(tally.failures);
        }
    }
    assert!(
        failures.is_empty(),
        "{} corrected cases failed; the first:\n{}",
        failures.len(),
        failures[0]
    );
}
