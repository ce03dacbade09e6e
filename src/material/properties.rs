//! Property test of the f64 model over the whole documented parameter space (issue 14): random
//! stacks with every field inside the material format's ranges — the range ends included (α 0
//! and 1, η at and near 1, η < 1, κ up to 200, depth up to 100, σ up to 1000, g near ±1) — at
//! view cosines that include 1e-4 (the renderer's clamp of n·v) and 1, with FGD and TIR
//! providers that include the exact quadratures and adversarial ones returning 0 and 1.
//!
//! Every value must be finite, and every stack conserves energy: R + T ≤ 1 + 1e-6 and R, T ≥
//! −1e-6 (a lossless stack is the tightest case). Over seeds 0–9 the largest excess is 1.3e-11,
//! a 6-flux medium's I − R′ formed as a difference (`model/adding.rs`); elsewhere it is
//! rounding (≤ 2e-15). The seed is printed; `LAMINA_PROPERTY_SEED=N` replays a run, and a
//! failure prints the stack as a material file.
//!
//! It lives with the materials, not in `model`, because its cases are material stacks
//! (`random.rs`) and a failure prints one as a file: the model itself names no material.

use super::random::random_stack;
use super::Stack;
use crate::model::fgd::ExactFgd;
use crate::model::random::{case_seed, Rng};
use crate::model::tir::{trapped_fraction, AnalyticTir, ConstantTir, FitTir, CONSTANT_FRACTION};
use crate::model::tir_fit::COEFFICIENTS;
use crate::model::{tm2, tm6, Evaluation, Fgd, NoTir, Tir};
use crate::variant::{Model, G2};

/// How many random stacks the test evaluates.
const CASES: usize = 100_000;

/// FGD or TIR values from {0, 1, a hash of the arguments}: the ends of what a table may hold.
struct Adversarial;

fn hash01(values: &[f64]) -> f64 {
    let h = values.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
        (h ^ v.to_bits()).wrapping_mul(0x0000_0100_0000_01b3)
    });
    (h >> 11) as f64 / (1u64 << 53) as f64
}

fn adversarial(values: &[f64]) -> f64 {
    match hash01(values) {
        x if x < 0.3 => 0.0,
        x if x < 0.6 => 1.0,
        x => (x - 0.6) / 0.4,
    }
}

impl Fgd for Adversarial {
    fn fgd(&self, mu: f64, alpha: f64, eta: f64, kappa: f64) -> f64 {
        adversarial(&[mu, alpha, eta, kappa])
    }
}

impl Tir for Adversarial {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        adversarial(&[mu, alpha, eta, 1.0])
    }
}

/// The exact trapped fraction (what the TIR table tabulates), coarse.
struct ExactTir;

impl Tir for ExactTir {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        trapped_fraction(mu, alpha, eta, 6)
    }
}

fn finite(e: &Evaluation) -> bool {
    e.reflectance
        .iter()
        .chain(&e.transmittance)
        .chain(e.lobes.iter().flat_map(|l| &l.weight))
        .chain(e.lobes.iter().map(|l| &l.roughness))
        .all(|v| v.is_finite())
}

/// What is wrong with one case, if anything; else how far R + T exceeds 1 (≤ 0 mostly).
fn check(stack: &Stack, mu: f64, fgd: &dyn Fgd, tir: &dyn Tir) -> Result<f64, String> {
    let e = match stack.model {
        Model::Tm6 => tm6::evaluate(&stack.layers, mu, fgd, tir),
        _ => tm2::evaluate(&stack.layers, mu, fgd, tir),
    };
    if !finite(&e) {
        return Err(format!("non-finite values: {e:?}"));
    }
    let mut excess = f64::NEG_INFINITY;
    for c in 0..3 {
        let (r, t) = (e.reflectance[c], e.transmittance[c]);
        if r > 1.0 + 1e-6 || r + t > 1.0 + 1e-6 || r < -1e-6 || t < -1e-6 {
            return Err(format!("channel {c}: R = {r}, T = {t}: {e:?}"));
        }
        excess = excess.max(r + t - 1.0).max(-r).max(-t);
    }
    Ok(excess)
}

#[test]
fn every_valid_stack_gives_finite_energy_conserving_values() {
    let seed = std::env::var("LAMINA_PROPERTY_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .unwrap_or(0x5eed_1a31_2026_1123);
    println!("property test seed: {seed} (LAMINA_PROPERTY_SEED={seed} replays it)");
    let exact = ExactFgd {
        g2: G2::HeightCorrelated,
        resolution: 4,
    };
    let fgds: [&(dyn Fgd + Sync); 2] = [&exact, &Adversarial];
    let constant = ConstantTir(CONSTANT_FRACTION);
    let fit = FitTir(COEFFICIENTS);
    let tirs: [&(dyn Tir + Sync); 6] = [
        &NoTir,
        &constant,
        &AnalyticTir,
        &fit,
        &ExactTir,
        &Adversarial,
    ];
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let (failures, worst) = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|worker| {
                scope.spawn(move || {
                    let mut failures = Vec::new();
                    let mut worst = f64::NEG_INFINITY;
                    for k in (worker..CASES).step_by(threads) {
                        let mut rng = Rng(case_seed(seed, k));
                        let (stack, mu) = random_stack(&mut rng, None, 16);
                        let (f, t) = (k % fgds.len(), (k / fgds.len()) % tirs.len());
                        match check(&stack, mu, fgds[f], tirs[t]) {
                            Ok(excess) => worst = worst.max(excess),
                            Err(why) => failures.push(format!(
                                "case {k} (FGD provider {f}, TIR provider {t}), μ = {mu}: \
                                 {why}\n{}",
                                stack.to_toml()
                            )),
                        }
                    }
                    (failures, worst)
                })
            })
            .collect();
        workers.into_iter().fold(
            (Vec::new(), f64::NEG_INFINITY),
            |(mut failures, worst), w| {
                let (f, x) = w.join().expect("a property worker panicked");
                failures.extend(f);
                (failures, worst.max(x))
            },
        )
    });
    println!("{CASES} cases; largest R + T − 1, −R or −T: {worst:.3e}");
    assert!(
        failures.is_empty(),
        "{} of {CASES} cases failed (seed {seed}); the first:\n{}",
        failures.len(),
        failures[0]
    );
}
