//! The model evaluated on the GPU at given view cosines, with the same shader library as the
//! forward pass (`tm_eval.comp.glsl`): `lamina eval --backend gpu`, and the GPU side of the
//! GPU-vs-CPU tests.

use crate::error::{Error, Result};
use crate::gpu::{ComputeKernel, Gpu};
use crate::model::transport::Correction;
use crate::model::{Evaluation, LayerParams, Lobe, TopFresnel};
use crate::shader::interface::material_buffer;
use crate::shader::kernel::{KernelInterface, LOCAL_SIZE_1D};
use crate::tables::fgd::FgdLookup;
use crate::variant::{Mode, Model, ShadeSpec, Transport, VariantKey};
use crate::vk::{
    submit_and_wait, Access, BindingKind, Buffer, BufferDesc, BufferUsageFlags, DescriptorSet,
    Resource,
};

use super::inputs::ShadingInputs;
use super::lights::Lighting;
use super::pass::PassKey;

/// How far the GPU evaluation may lie from the f64 model run with the same tables (the tables'
/// CPU twins: `tables::fgd::FgdLookup`, `tables::tir::provider`), as absolute differences of
/// the energies (R, T, lobe weights; all in [0, 1]) and of the HG g of lobes that carry at
/// least 1 % of the light (their GGX α mapped back to g, hg::g_of_alpha: α(g) is steep near
/// α = 1). tests/suite/model_vs_cpu.rs holds them over random valid stacks (range
/// ends, grazing angles, thick media, TIR traps) in every variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    pub energy: f64,
    pub lobe_g: f64,
}

impl Tolerance {
    /// The 2-flux model in f32: what is left is rounding and the sampler's filtering against
    /// the twins' (at most 3e-4 and 9e-4 over eight seeds of 7 000 cases).
    pub const TM2: Self = Self {
        energy: 1e-3,
        lobe_g: 5e-3,
    };
    /// The 6-flux model, in f32 under fp16 too (tm6.glsl). Light trapped between two
    /// near-lossless thick scatterers (σ_a = 0: r_fb = 1 − 3e-5) leaks through a gap whose
    /// 3×3 system has a condition number of ~1e4, and f32 resolves it to ~1e-3 of the energy
    /// (6.1e-3 at most over eight seeds).
    pub const TM6: Self = Self {
        energy: 1e-2,
        lobe_g: 5e-3,
    };
    /// The 2-flux model in half floats (11-bit mantissas): 9e-3 at most in energy; a lobe's g
    /// is a difference of g-weighted sums over a difference of energies, so a lobe of 1 % of
    /// the light resolves it to ~1e-3 / 1e-2 (6e-2 at most).
    pub const TM2_FP16: Self = Self {
        energy: 2e-2,
        lobe_g: 0.1,
    };

    /// The tolerance of `variant`'s evaluation.
    pub fn of(variant: VariantKey) -> Self {
        match (variant.model, variant.fp16) {
            (Model::Tm2, true) => Self::TM2_FP16,
            (Model::Tm6, _) => Self::TM6,
            _ => Self::TM2,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    sample_count: u32,
    stride: u32,
    lit: u32,
    angular_radius: f32,
}

/// `tm_eval.comp.glsl`: one invocation per view cosine, after the shading set.
pub const KERNEL: KernelInterface = KernelInterface {
    entry: "tm_eval.comp.glsl",
    shades: true,
    scene: false,
    bindings: &[BindingKind::StorageBuffer, BindingKind::StorageBuffer],
    push: crate::push_block!(Push {
        sample_count,
        stride,
        lit,
        angular_radius
    }),
    local_size: [LOCAL_SIZE_1D, 1],
};

pub struct GpuEvaluator<'g> {
    gpu: &'g Gpu,
    pub variant: VariantKey,
    /// Set 0: the tables the variant samples (and their CPU twins).
    pub inputs: ShadingInputs<'g>,
    /// Set 1: the view cosines in, the results out. `None` under a per-material mode, whose
    /// kernel is built for each stack evaluated.
    kernel: Option<ComputeKernel>,
    /// The generic kernel with a diffuse base's code (`ShadeSpec::diffuse_base`), built the
    /// first time a stack ends in one: lavapipe runs that code masked for every stack it is
    /// compiled into.
    diffuse_kernel: std::cell::OnceCell<ComputeKernel>,
}

/// One evaluation on the GPU, its lobes' kinds in `retro_mask` (`LOBE_RETRO`).
pub struct GpuEvaluation {
    pub evaluation: Evaluation,
}

impl<'g> GpuEvaluator<'g> {
    pub fn new(gpu: &'g Gpu, variant: VariantKey) -> Result<Self> {
        crate::model::oracle::check_transport(variant)?;
        if variant.model == Model::Ggx {
            return Err(Error::Unsupported(
                "eval evaluates the transfer-matrix models; use model=tm2 or model=tm6".into(),
            ));
        }
        if variant.fp16 && !gpu.device.supports_fp16() {
            return Err(Error::Unsupported(format!(
                "fp16=on needs the shaderFloat16 feature, which `{}` lacks",
                gpu.device.report.name
            )));
        }
        if variant.mode == Mode::Baked {
            return Err(Error::Unsupported(format!(
                "variant {variant}: mode=baked tabulates the lobes of mode=generic (the \
                 evaluator runs the model); evaluate mode=generic, specialized or \
                 specialized-values"
            )));
        }
        let mut inputs = ShadingInputs::new(gpu)?;
        inputs.prepare(variant)?;
        let kernel = if variant.mode.per_material() {
            None
        } else {
            // With the transmitted lobe's code, so that every stack reports its roughness,
            // and the code past the 4-D FGD table's edge, which any stack may reach.
            let mut spec = variant.spec();
            spec.transmits = 1;
            spec.fgd |= 1 << crate::variant::FGD_PAST_EDGE_SHIFT;
            Some(Self::kernel(gpu, &inputs, variant, spec)?)
        };
        Ok(Self {
            gpu,
            variant,
            inputs,
            kernel,
            diffuse_kernel: std::cell::OnceCell::new(),
        })
    }

    fn kernel(
        gpu: &Gpu,
        inputs: &ShadingInputs<'_>,
        variant: VariantKey,
        spec: ShadeSpec,
    ) -> Result<ComputeKernel> {
        ComputeKernel::build(
            gpu,
            &KERNEL,
            &variant.defines(),
            &[&inputs.layout.set_layout],
            spec,
        )
    }

    /// The CPU twin of the FGD lookups the kernel makes.
    pub fn fgd_lookup(&self) -> FgdLookup<'_> {
        self.inputs
            .fgd_lookup(self.variant)
            .expect("prepared by GpuEvaluator::new")
    }

    /// The CPU twin of the kernel's TIR term.
    pub fn tir_lookup(&self) -> Box<dyn crate::model::Tir + '_> {
        self.inputs.tir_lookup(self.variant)
    }

    /// Most lobes one evaluation of a stack of `layers` layers can emit under this variant
    /// (the shader's `TM_MAX_LOBES`, whose MAX_LAYERS is the stack's own size under a
    /// per-material mode).
    pub fn max_lobes(&self, layers: usize) -> usize {
        let n = if self.variant.mode.per_material() {
            layers
        } else {
            self.variant.max_layers as usize
        };
        crate::model::max_lobes(self.variant.model, n)
    }

    /// Evaluates `layers` (top first) at each view cosine.
    pub fn evaluate(&self, layers: &[LayerParams], cosines: &[f64]) -> Result<Vec<Evaluation>> {
        Ok(self
            .evaluate_lobes(layers, cosines)?
            .into_iter()
            .map(|e| e.evaluation)
            .collect())
    }

    /// [`GpuEvaluator::evaluate`], with each evaluation's lobe kinds.
    pub fn evaluate_lobes(
        &self,
        layers: &[LayerParams],
        cosines: &[f64],
    ) -> Result<Vec<GpuEvaluation>> {
        let samples: Vec<[f32; 4]> = cosines.iter().map(|&c| [c as f32, 0.0, 0.0, 0.0]).collect();
        self.run(layers, &samples, None)
    }

    /// The model's response to a light: for each (μ, l) — the view (√(1 − μ²), 0, μ), the
    /// light's unit direction l, the normal +z — the evaluation at μ with each lobe's weight
    /// replaced by its response to a unit irradiance from l (`model::light::light_term`'s
    /// terms), for a light of `angular_radius` radians. The lobes' roughness is the model's.
    pub fn evaluate_lit(
        &self,
        layers: &[LayerParams],
        samples: &[(f64, glam::DVec3)],
        angular_radius: f64,
    ) -> Result<Vec<GpuEvaluation>> {
        let samples: Vec<[f32; 4]> = samples
            .iter()
            .map(|&(mu, l)| [mu as f32, l.x as f32, l.y as f32, l.z as f32])
            .collect();
        self.run(layers, &samples, Some(angular_radius))
    }

    /// `transport=corrected`: the energy ratios of `layers`, from the tables' CPU twins.
    fn correction(&self, layers: &[LayerParams]) -> Option<Correction> {
        (self.variant.transport == Transport::Corrected).then(|| {
            let tir = self.tir_lookup();
            Correction::new(
                layers,
                self.variant.model,
                self.variant.interfaces,
                &self.fgd_lookup(),
                tir.as_ref(),
            )
        })
    }

    fn run(
        &self,
        layers: &[LayerParams],
        samples: &[[f32; 4]],
        light: Option<f64>,
    ) -> Result<Vec<GpuEvaluation>> {
        // The kernel's constants come from the pass key of the stack, as a forward pass's do
        // (no lights: the kernel takes its light per sample).
        let key = PassKey::uniform(self.variant, layers, &Lighting::default())?;
        let specialized;
        let kernel = match &self.kernel {
            Some(kernel) => {
                key.admits(layers)?;
                if key.diffuse {
                    if self.diffuse_kernel.get().is_none() {
                        let built =
                            Self::kernel(self.gpu, &self.inputs, self.variant, key.spec(None))?;
                        let _ = self.diffuse_kernel.set(built);
                    }
                    self.diffuse_kernel.get().expect("set above")
                } else {
                    kernel
                }
            }
            None => {
                specialized = Self::kernel(self.gpu, &self.inputs, self.variant, key.spec(None))?;
                &specialized
            }
        };
        if samples.is_empty() {
            return Ok(Vec::new());
        }
        let device = &self.gpu.device;
        let stride = 3 + self.max_lobes(layers.len());
        let correction = self.correction(layers);
        let material = material_buffer(device, layers, None, correction.as_ref(), "eval material")?;
        let shading = self
            .inputs
            .bind(self.variant, &material, None, None, "eval shading")?;
        let results = Buffer::new(
            device,
            BufferDesc::readback((samples.len() * stride * 16) as u64),
            "eval results",
        )?;
        let count = samples.len() as u32;
        let samples = Buffer::with_data(
            device,
            BufferUsageFlags::STORAGE_BUFFER,
            samples,
            "eval samples",
        )?;
        let mut set = DescriptorSet::new(device, &kernel.set_layout, "eval")?;
        set.write(0, Resource::Buffer(&samples))
            .write(1, Resource::Buffer(&results));
        submit_and_wait(device, "eval", |rec| {
            kernel.record_dispatch(
                rec,
                &[&shading, &set],
                &Push {
                    sample_count: count,
                    stride: stride as u32,
                    lit: u32::from(light.is_some()),
                    angular_radius: light.unwrap_or(0.0) as f32,
                },
                [count, 1, 1],
            );
            rec.barrier(Access::ComputeWrite, Access::HostRead);
            Ok(())
        })?;
        let values: Vec<[f32; 4]> = results.read();
        Ok(values.chunks(stride).map(unpack).collect())
    }
}

fn unpack(chunk: &[[f32; 4]]) -> GpuEvaluation {
    let rgb = |v: [f32; 4]| [f64::from(v[0]), f64::from(v[1]), f64::from(v[2])];
    let lobe_count = chunk[0][3] as usize;
    GpuEvaluation {
        evaluation: Evaluation {
            reflectance: rgb(chunk[0]),
            transmittance: rgb(chunk[1]),
            transmitted_roughness: f64::from(chunk[2][0]),
            lobes: chunk[3..3 + lobe_count]
                .iter()
                .map(|&v| Lobe {
                    weight: rgb(v),
                    // A diffuse base's lobe reads back with α = −1 (tm_eval.comp.glsl).
                    roughness: if v[3] < 0.0 { 1.0 } else { f64::from(v[3]) },
                    diffuse: v[3] < 0.0,
                })
                .collect(),
            // The kernel does not report which layer emitted each lobe.
            lobe_layers: Vec::new(),
            // The kernel stores the mask's bits, not a value (tm_eval.comp.glsl).
            retro_mask: chunk[1][3].to_bits(),
            // η, A and the index of the LOBE_FRESNEL lobe, else 0.
            top_fresnel: (chunk[2][1] > 0.0).then(|| TopFresnel {
                lobe: chunk[2][3] as usize,
                eta: f64::from(chunk[2][1]),
                albedo: f64::from(chunk[2][2]),
            }),
        },
    }
}
