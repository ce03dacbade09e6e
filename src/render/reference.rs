//! Reference images (`lamina render --reference`): the scene with each pixel's lobes — those
//! of the f64 model with its FGD and TIR correction integrated exactly — integrated against
//! the environment and the lights by Monte Carlo on the GPU (`forward.frag.glsl` under
//! `LAMINA_REFERENCE`): no split sum, no prefiltering, no FGD table, no fp16. What a variant's
//! image differs from it by is the error of its real-time approximations alone; the model's
//! own error is the reference study's (`reference::compare`).
//!
//! The model runs on the host at [`TABLE_SIZE`] view cosines (uniform in √μ, as a baked
//! table: `render::baked`) with the masking form [`G2`] (height-correlated, GGX D): each lobe's
//! weight divided by the albedo E of its white GGX lobe (so that each lobe's samples need no
//! table), its α floored at the lights' [`MIN_ALPHA`]. The pass interpolates between samples
//! (the baked table's error study: below 5e-4 at 512 samples). Each frame draws
//! [`SAMPLES_PER_FRAME`] samples per lobe and light disk per pixel, the next of one scrambled
//! Sobol sequence per integral and pixel that runs on over the frames (randomised quasi-Monte
//! Carlo: unbiased, and the frames so far stratified together); the host averages frames in
//! f64 and estimates each pixel's standard error from their spread. Stratified together, the
//! frames are not independent and that spread overstates the error of their mean; two seeds
//! measure it, as the studies' noise floor does.
//!
//! A stack that varies over the surface has a stack per pixel, which no table over the view
//! cosine holds: its references evaluate each pixel's lobes in the pass from its maps, with a
//! variant's shader library ([`render_evaluated`]), and integrate them alike. The exact model's
//! is then stood in for by its finest tables ([`exact_stand_in`]).
//!
//! Which model is exact is the image's [`Truth`]: the paper's transport (the talk's shader's
//! model), or the stack's energies from the transport that follows light's angles in one of the
//! reference walk's interface modes (`transport=corrected`'s, from the exact model: the
//! transport within 1.4 % of the walk's R, the corrected model, its ratios interpolated between
//! view cosines, within 2.8 % on the presets; the lobes' shapes the paper's). A variant's image
//! is measured against the truth of its own transport and interfaces ([`Truth::of`]). A stack
//! with maps stands in with the finest tables ([`exact_stand_in`]), its ratios taken at its
//! nominal values as every variant's are.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::material::{Stack, Surface};
use crate::model::fgd::ExactFgd;
use crate::model::light::{lobe_albedo, MIN_ALPHA};
use crate::model::oracle::evaluate_model;
use crate::model::transport::Correction;
use crate::model::Fgd;
use crate::model::{ends_transmissive, Evaluation, LayerParams, Lobe, TopFresnel};
use crate::reference::compare::ExactTir;
use crate::shader::specialize::{BakedShape, MAX_BAKED_LOBES};
use crate::tables::split_sum::SplitSumTable;
use crate::variant::{
    self, Classify, Ibl, Interfaces, Mode, Model, ShadePath, Tir, Transport, VariantKey, G2,
};

use super::baked::{sample_cos, BakedTable};
use super::eval::GpuEvaluator;
use super::forward::ForwardPass;
use super::Renderer;

/// View cosines the host evaluates the model at.
pub const TABLE_SIZE: u32 = 512;

/// The masking form of the reference's lobes and FGD.
pub const G2_FORM: G2 = G2::HeightCorrelated;

/// Samples per lobe (and per light disk) per pixel and frame: `REFERENCE_SAMPLES` in
/// `forward.frag.glsl`.
pub const SAMPLES_PER_FRAME: u32 = 16;

/// Most samples per lobe a reference takes.
pub const MAX_SPP: u32 = 1 << 20;

/// Grid side of the exact FGD integral at each tabulated cosine.
const FGD_GRID: u32 = 256;

/// Which model a reference image holds exact.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Truth {
    /// The paper's transport: the model the talk's shader computes, with its FGD and TIR
    /// correction integrated exactly.
    #[default]
    Paper,
    /// Each layer's energy from the discrete-ordinates transport of the walk's interfaces in
    /// this mode (`model::transport`'s ratios, the paper's side exact), the lobes' shapes the
    /// paper's: the reference study's truth as near as lobes hold it.
    Transport(Interfaces),
}

impl Truth {
    /// The truth a variant's image is measured against: that of its own transport, in its
    /// interface mode.
    pub fn of(variant: VariantKey) -> Self {
        match variant.transport {
            Transport::Paper => Truth::Paper,
            Transport::Corrected => Truth::Transport(variant.interfaces),
        }
    }

    /// The transport and interfaces axes of a variant that computes this truth's lobes.
    fn axes(self, variant: VariantKey) -> VariantKey {
        let (transport, interfaces) = match self {
            Truth::Paper => (Transport::Paper, Interfaces::Single),
            Truth::Transport(mode) => (Transport::Corrected, mode),
        };
        VariantKey {
            transport,
            interfaces,
            ..variant
        }
    }
}

impl std::fmt::Display for Truth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Truth::Paper => f.write_str("the paper's transport"),
            Truth::Transport(mode) => write!(f, "the corrected transport, interfaces={mode}"),
        }
    }
}

/// The exact model's lobes over the view cosine under `truth`, as the reference pass reads
/// them ([`table_of`]).
pub fn lobe_table(model: Model, layers: &[LayerParams], truth: Truth) -> Result<BakedTable> {
    let fgd = ExactFgd {
        g2: G2_FORM,
        resolution: FGD_GRID,
    };
    let correction = match truth {
        Truth::Paper => None,
        Truth::Transport(mode) => Some(Correction::new(layers, model, mode, &fgd, &ExactTir)),
    };
    let evaluations: Vec<_> = (0..TABLE_SIZE)
        .into_par_iter()
        .map(|j| {
            let mu = sample_cos(j, TABLE_SIZE);
            let mut e = evaluate_model(model, layers, mu, &fgd, &ExactTir);
            if let Some(c) = &correction {
                c.apply(&mut e, mu);
            }
            e
        })
        .collect();
    table_of(&evaluations, layers)
}

/// The lobes `variant`'s real-time pass computes for `layers`, over the view cosine, as the
/// reference pass reads them ([`table_of`]): the transfer-matrix models evaluated on the GPU
/// by the variant's own shader library (`render::eval`: its tables, precision and TIR mode;
/// `mode=baked`'s lobes are `mode=generic`'s, which it tabulates), `model=ggx`'s one lobe of
/// energy F0·A + B from the split-sum table its pass reads (the thin slab's 1 − that where
/// the stack transmits). Integrated exactly, they are what the pass would show with perfect
/// lighting: the reference of its lighting's error alone.
pub fn variant_lobe_table(
    gpu: &Gpu,
    variant: VariantKey,
    layers: &[LayerParams],
    split_sum: &SplitSumTable,
) -> Result<BakedTable> {
    let cosines: Vec<f64> = (0..TABLE_SIZE).map(|j| sample_cos(j, TABLE_SIZE)).collect();
    let evaluations = if variant.model == Model::Ggx {
        let top = layers.first().ok_or_else(|| {
            Error::Unsupported("a reference needs a stack of at least one layer".into())
        })?;
        cosines
            .iter()
            .map(|&mu| ggx_evaluation(top, mu, split_sum, ends_transmissive(layers)))
            .collect()
    } else {
        let evaluated = VariantKey {
            mode: if variant.mode == Mode::Baked {
                Mode::Generic
            } else {
                variant.mode
            },
            ..variant
        };
        GpuEvaluator::new(gpu, evaluated)?.evaluate(layers, &cosines)?
    };
    table_of(&evaluations, layers)
}

/// `model=ggx`'s lobe at view cosine `mu` (`forward.frag.glsl`'s shade_ggx).
fn ggx_evaluation(
    top: &LayerParams,
    mu: f64,
    split_sum: &SplitSumTable,
    transmits: bool,
) -> Evaluation {
    let alpha = top.roughness;
    let albedo: [f64; 3] =
        std::array::from_fn(|c| split_sum.fgd(mu, alpha, top.ior[c], top.kappa[c]));
    let through = albedo.map(|a| if transmits { (1.0 - a).max(0.0) } else { 0.0 });
    Evaluation {
        reflectance: albedo,
        transmittance: through,
        transmitted_roughness: alpha,
        lobes: vec![Lobe {
            weight: albedo,
            roughness: alpha,
            diffuse: false,
        }],
        lobe_layers: Vec::new(),
        retro_mask: 0,
        top_fresnel: None,
    }
}

/// Lobes over the view cosine (`evaluations` at [`TABLE_SIZE`] cosines, [`sample_cos`]), as the
/// reference pass reads them: two rows per lobe, (weight / E, √α) then (E, behind, η, 0) per
/// sample, √α = −1 for a diffuse base's lobe (E = 1); η > 0 for the top's Fresnel lobe
/// (`Evaluation::top_fresnel`), whose E is the model's albedo A. A stack that transmits
/// (`model::ends_transmissive`) adds, last, the lobe it transmits as the forward pass shades
/// it (a thin slab: weight T, roughness `Evaluation::transmitted_roughness`), with behind = 1:
/// lit from behind the surface. The table's `lobe_count` counts rows; its `retro_mask`,
/// lobes; its `kept`, the reflected ones.
fn table_of(evaluations: &[Evaluation], layers: &[LayerParams]) -> Result<BakedTable> {
    let size = TABLE_SIZE;
    let first = &evaluations[0];
    if evaluations.iter().any(|e| {
        e.lobes.len() != first.lobes.len()
            || e.retro_mask != first.retro_mask
            || e.top_fresnel.is_some() != first.top_fresnel.is_some()
    }) {
        return Err(Error::Unsupported(
            "the model emitted a different lobe set at different view cosines; the reference \
             needs one lobe set"
                .into(),
        ));
    }
    let kept: Vec<usize> = (0..first.lobes.len())
        .filter(|&k| {
            evaluations
                .iter()
                .any(|e| e.lobes[k].weight.iter().any(|&w| w > 0.0))
        })
        .collect();
    let transmits = ends_transmissive(layers);
    let slots = kept.len() + usize::from(transmits);
    if slots > MAX_BAKED_LOBES {
        return Err(Error::Unsupported(format!(
            "the reference holds at most {MAX_BAKED_LOBES} lobes; the stack has {slots} \
             (the transmitted one included)"
        )));
    }
    let mut retro_mask = 0;
    for (slot, &k) in kept.iter().enumerate() {
        if k < 32 && first.retro_mask & (1 << k) != 0 {
            retro_mask |= 1 << slot;
        }
    }
    let rows: Vec<[[f32; 4]; 2]> = (0..slots * size as usize)
        .into_par_iter()
        .map(|t| {
            let (slot, j) = (t / size as usize, t % size as usize);
            let e = &evaluations[j];
            match kept.get(slot) {
                Some(&k) => {
                    let top = e.top_fresnel.filter(|t| t.lobe == k);
                    table_rows(e.lobes[k], sample_cos(j as u32, size), 0.0, top)
                }
                None => {
                    let through = Lobe {
                        weight: e.transmittance,
                        roughness: e.transmitted_roughness,
                        diffuse: false,
                    };
                    table_rows(through, sample_cos(j as u32, size), 1.0, None)
                }
            }
        })
        .collect();
    // Lobe k's first row, then its second.
    let mut texels = Vec::with_capacity(rows.len() * 2);
    for lobe in rows.chunks(size as usize) {
        texels.extend(lobe.iter().map(|r| r[0]));
        texels.extend(lobe.iter().map(|r| r[1]));
    }
    Ok(BakedTable {
        shape: BakedShape {
            lobe_count: 2 * slots as u32,
            retro_mask,
            size,
        },
        texels,
        kept,
    })
}

/// A lobe's two rows at view cosine `mu` (`behind`: 1 for the transmitted lobe): (weight / E,
/// √α) and (E, behind, η, 0), √α = −1 and E = 1 for a diffuse base's lobe, E = A and η the
/// interface's for the top's Fresnel lobe (`top`), η = 0 otherwise.
fn table_rows(lobe: Lobe, mu: f64, behind: f32, top: Option<TopFresnel>) -> [[f32; 4]; 2] {
    let w = lobe.weight;
    if lobe.diffuse {
        return [
            [w[0] as f32, w[1] as f32, w[2] as f32, -1.0],
            [1.0, 0.0, 0.0, 0.0],
        ];
    }
    let alpha = lobe.roughness.max(MIN_ALPHA);
    let (white, eta) = match top {
        Some(t) => (t.albedo, t.eta),
        None => (lobe_albedo(G2_FORM, mu, alpha), 0.0),
    };
    // A top that reflects nothing (its albedo 0) has a lobe of weight 0.
    let w = w.map(|w| if white > 0.0 { (w / white) as f32 } else { 0.0 });
    [
        [w[0], w[1], w[2], alpha.sqrt() as f32],
        [white as f32, behind, eta as f32, 0.0],
    ]
}

/// A converged reference image.
pub struct ReferenceImage {
    pub width: u32,
    pub height: u32,
    /// Linear radiance, rows top to bottom (alpha 1).
    pub pixels: Vec<[f32; 4]>,
    /// Each pixel's standard error (mean of RGB), from the spread of its frames: above the
    /// error of their stratified mean (module docs).
    pub std_error: Vec<f32>,
    /// Samples per lobe per pixel.
    pub spp: u32,
    /// The image's relative noise: the RMS over the pixels that vary between frames of each
    /// one's standard error over its radiance (mean of RGB; radiances below 1 % of the image's
    /// mean count as that), so a few bright pixels do not hide the rest. Above the noise
    /// two seeds show, as each pixel's standard error is.
    pub noise: f64,
}

/// When a reference stops, and which samples it draws.
#[derive(Clone, Copy, Debug)]
pub struct Convergence {
    /// Samples per lobe per pixel at most (rounded up to whole frames).
    pub spp: u32,
    /// Stop earlier once [`ReferenceImage::noise`] is at most this (checked from the fourth
    /// frame on).
    pub noise: Option<f64>,
    /// The samples' seed: any u64 ([`stream`]); two seeds give two independent estimates of
    /// the same image, whose difference is the reference's noise.
    pub seed: u64,
}

/// The pass's 32-bit sample stream for `seed` (`Renderer::seed`, mixed into every frame's
/// hash): 0 for seed 0 — the images of earlier references — else SplitMix64's finaliser of
/// the seed, folded to 32 bits.
pub fn stream(seed: u64) -> u32 {
    if seed == 0 {
        return 0;
    }
    let mut z = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    ((z ^ (z >> 32)) as u32).max(1)
}

impl Convergence {
    /// Refuses sample counts outside 1..=[`MAX_SPP`] and noise targets outside (0, 1).
    pub fn check(&self) -> Result<()> {
        if self.spp == 0 || self.spp > MAX_SPP {
            return Err(Error::Unsupported(format!(
                "--spp {}: a reference takes 1 to {MAX_SPP} samples per lobe and pixel",
                self.spp
            )));
        }
        if let Some(n) = self.noise {
            if !(n.is_finite() && n > 0.0 && n < 1.0) {
                return Err(Error::Unsupported(format!(
                    "--noise {n}: give a relative noise in (0, 1), e.g. 0.01"
                )));
            }
        }
        Ok(())
    }
}

/// Per-pixel sums of the frames' values and of their squares, in f64.
struct Accumulator {
    sum: Vec<[f64; 3]>,
    sum_sq: Vec<[f64; 3]>,
    frames: u32,
}

impl Accumulator {
    fn new(pixels: usize) -> Self {
        Self {
            sum: vec![[0.0; 3]; pixels],
            sum_sq: vec![[0.0; 3]; pixels],
            frames: 0,
        }
    }

    fn add(&mut self, pixels: &[[f32; 4]]) {
        for ((s, q), p) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(pixels) {
            for c in 0..3 {
                let v = f64::from(p[c]);
                s[c] += v;
                q[c] += v * v;
            }
        }
        self.frames += 1;
    }

    /// The mean image, each pixel's standard error and the image's relative noise
    /// ([`ReferenceImage`]).
    fn estimate(&self) -> (Vec<[f32; 4]>, Vec<f32>, f64) {
        let n = f64::from(self.frames);
        let mut pixels = Vec::with_capacity(self.sum.len());
        let mut errors = Vec::with_capacity(self.sum.len());
        let mut means = Vec::with_capacity(self.sum.len());
        for (s, q) in self.sum.iter().zip(&self.sum_sq) {
            let mean = s.map(|v| v / n);
            let mut se2 = 0.0;
            for c in 0..3 {
                // The frames' unbiased variance, over the frame count: the mean's.
                let variance = (q[c] / n - mean[c] * mean[c]).max(0.0) * n / (n - 1.0).max(1.0);
                se2 += variance / n / 3.0;
            }
            pixels.push([mean[0] as f32, mean[1] as f32, mean[2] as f32, 1.0]);
            errors.push(se2.sqrt() as f32);
            means.push((mean[0] + mean[1] + mean[2]) / 3.0);
        }
        let floor = 0.01 * means.iter().sum::<f64>() / means.len().max(1) as f64;
        let (mut sum, mut count) = (0.0, 0usize);
        for (&se, &m) in errors.iter().zip(&means) {
            if se > 0.0 {
                sum += (f64::from(se) / m.max(floor).max(f64::MIN_POSITIVE)).powi(2);
                count += 1;
            }
        }
        let noise = if count > 0 {
            (sum / count as f64).sqrt()
        } else {
            0.0
        };
        (pixels, errors, noise)
    }
}

/// Renders the reference image of the uniform stack `layers` in `model` under `truth` with
/// `renderer`'s scene, environment and lights (`renderer` must render into a float target).
/// `progress(frame, frames)` follows the frames; `None` when `stop` was set.
#[allow(clippy::too_many_arguments)]
pub fn render(
    renderer: &mut Renderer<'_>,
    model: Model,
    layers: &[LayerParams],
    truth: Truth,
    (width, height): (u32, u32),
    convergence: Convergence,
    progress: &mut dyn FnMut(u32, u32),
    stop: &AtomicBool,
) -> Result<Option<ReferenceImage>> {
    convergence.check()?;
    if model == Model::Ggx {
        return Err(Error::Unsupported(
            "model=ggx has no reference; the reference integrates the transfer-matrix model's \
             lobes"
                .into(),
        ));
    }
    let table = lobe_table(model, layers, truth)?;
    render_table(
        renderer,
        model,
        layers,
        table,
        (width, height),
        convergence,
        progress,
        stop,
    )
}

/// The reference image of the lobes `variant`'s real-time pass computes for the uniform stack
/// `layers` ([`variant_lobe_table`]), otherwise as [`render`]: against it, the pass's image
/// differs by its lighting alone; it differs from [`render`]'s by the variant's lobes.
pub fn render_variant(
    renderer: &mut Renderer<'_>,
    variant: VariantKey,
    layers: &[LayerParams],
    size: (u32, u32),
    convergence: Convergence,
    progress: &mut dyn FnMut(u32, u32),
    stop: &AtomicBool,
) -> Result<Option<ReferenceImage>> {
    convergence.check()?;
    renderer.inputs.prepare(variant)?;
    let table = variant_lobe_table(
        renderer.gpu(),
        variant,
        layers,
        renderer.inputs.split_sum(variant)?,
    )?;
    render_table(
        renderer,
        variant.model,
        layers,
        table,
        size,
        convergence,
        progress,
        stop,
    )
}

/// Integrates the lobes of `table` (two rows per lobe, [`table_of`]) over `renderer`'s scene.
#[allow(clippy::too_many_arguments)]
fn render_table(
    renderer: &mut Renderer<'_>,
    model: Model,
    layers: &[LayerParams],
    table: BakedTable,
    size: (u32, u32),
    convergence: Convergence,
    progress: &mut dyn FnMut(u32, u32),
    stop: &AtomicBool,
) -> Result<Option<ReferenceImage>> {
    let pass = renderer.prepare_reference(model, layers, table)?;
    accumulate(renderer, &pass, layers, size, convergence, progress, stop)
}

/// The variant whose lobes stand for the exact model's under `truth` where they cannot be
/// tabulated (a stack that varies over the surface, [`render_evaluated`]): the model's tables
/// at their finest — the TIR table in 32-bit floats, the full 4-D FGD table — in single
/// precision, with the truth's transport (whose ratios it takes at the stack's nominal
/// values, as every variant does). How far its references lie from the exact model's is
/// measured on the uniform presets (`cargo test --test suite reference_maps::`,
/// profiling/README.md "Image-based lighting").
pub fn exact_stand_in(model: Model, truth: Truth) -> VariantKey {
    truth.axes(VariantKey {
        model,
        tir: Tir::Lut32,
        fgd: variant::Fgd::Full4d,
        ..VariantKey::default()
    })
}

/// The variant an evaluated reference pass of `variant`'s lobes is built with, for a stack of
/// `layer_count` layers: the lobes are the model's at the variant's tables, precision aside,
/// so the pass is the generic one (the specialized pipelines' lobes are its, within 1e-5:
/// `cargo test --test suite specialized::`), in the forward path, its layer array fitted to
/// the stack, in single precision (the reference's integration is written in floats; an
/// `fp16=on` variant's lobes stand in by its single-precision twin's, so its rounding counts
/// in the lighting part), lit by nothing of its own (`ibl` only lights a real-time pass).
pub fn evaluated_variant(variant: VariantKey, layer_count: usize) -> VariantKey {
    VariantKey {
        max_layers: (layer_count as u32).clamp(1, crate::variant::MAX_LAYERS_LIMIT),
        fp16: false,
        mode: Mode::Generic,
        ibl: Ibl::SplitSum,
        path: ShadePath::Forward,
        classify: Classify::None,
        ..variant
    }
}

/// The reference image of `variant`'s lobes of `layers`, each pixel's evaluated by the
/// variant's shader library from its maps (those of `surface`, which `renderer` then holds,
/// [`Renderer::set_surface`]; none for a uniform stack) and integrated as [`render`]
/// integrates tabulated ones. With [`exact_stand_in`] it stands in for [`render`]'s exact
/// model where the stack varies over the surface; with a real-time variant it is
/// [`render_variant`]'s for such a stack.
#[allow(clippy::too_many_arguments)]
pub fn render_evaluated(
    renderer: &mut Renderer<'_>,
    variant: VariantKey,
    layers: &[LayerParams],
    surface: Option<&Arc<Surface>>,
    size: (u32, u32),
    convergence: Convergence,
    progress: &mut dyn FnMut(u32, u32),
    stop: &AtomicBool,
) -> Result<Option<ReferenceImage>> {
    convergence.check()?;
    let variant = evaluated_variant(variant, layers.len());
    renderer.set_surface(surface)?;
    let pass = renderer.prepare_evaluated_reference(variant, layers, surface.map(|s| &**s))?;
    accumulate(renderer, &pass, layers, size, convergence, progress, stop)
}

/// The exact model's reference image of `stack` under `truth`: [`render`]'s where it is
/// uniform, and where it varies over the surface [`render_evaluated`]'s with
/// [`exact_stand_in`].
pub fn render_stack(
    renderer: &mut Renderer<'_>,
    stack: &Stack,
    truth: Truth,
    size: (u32, u32),
    convergence: Convergence,
    progress: &mut dyn FnMut(u32, u32),
    stop: &AtomicBool,
) -> Result<Option<ReferenceImage>> {
    let layers = stack.params();
    match &stack.surface {
        None => render(
            renderer,
            stack.model,
            &layers,
            truth,
            size,
            convergence,
            progress,
            stop,
        ),
        Some(surface) => render_evaluated(
            renderer,
            exact_stand_in(stack.model, truth),
            &layers,
            Some(surface),
            size,
            convergence,
            progress,
            stop,
        ),
    }
}

/// Renders `pass`'s frames of `layers` until `convergence` holds and averages them.
fn accumulate(
    renderer: &mut Renderer<'_>,
    pass: &ForwardPass,
    layers: &[LayerParams],
    (width, height): (u32, u32),
    convergence: Convergence,
    progress: &mut dyn FnMut(u32, u32),
    stop: &AtomicBool,
) -> Result<Option<ReferenceImage>> {
    let frames = convergence.spp.div_ceil(SAMPLES_PER_FRAME);
    let mut accumulator = Accumulator::new((width * height) as usize);
    renderer.seed = stream(convergence.seed);
    for f in 0..frames {
        if stop.load(Ordering::Relaxed) {
            return Ok(None);
        }
        renderer.frame_index = f;
        let frame = renderer.render(pass, layers, width, height)?;
        if frame
            .pixels
            .iter()
            .any(|p| p[..3].iter().any(|c| !c.is_finite()))
        {
            return Err(Error::Unsupported(format!(
                "frame {f} of the reference has a non-finite pixel"
            )));
        }
        accumulator.add(&frame.pixels);
        progress(f + 1, frames);
        if let Some(target) = convergence.noise {
            if f >= 3 && accumulator.estimate().2 <= target {
                break;
            }
        }
    }
    let (pixels, std_error, noise) = accumulator.estimate();
    Ok(Some(ReferenceImage {
        width,
        height,
        pixels,
        std_error,
        spp: accumulator.frames * SAMPLES_PER_FRAME,
        noise,
    }))
}

#[cfg(test)]
mod tests {
    use super::stream;

    #[test]
    fn seed_zero_keeps_the_earlier_images_and_other_seeds_get_streams_of_their_own() {
        assert_eq!(stream(0), 0);
        let mut seen: Vec<u32> = (1..10_000u64).chain([u64::MAX]).map(stream).collect();
        assert!(seen.iter().all(|&s| s != 0));
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 10_000, "distinct streams");
    }
}
