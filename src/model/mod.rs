//! The CPU reference in f64: pure functions the GPU is tested against.
//!
//! The transfer-matrix model of Randrianandrasana, Callet & Lucas 2021 as its reference code
//! defines it (ALGORITHMS.md §4–5): [`tm2`] (2-flux: rough dielectric interfaces over a
//! conductor, or a dielectric stack that transmits) and [`tm6`] (6-flux: adds homogeneous
//! scattering media below each dielectric interface). The directional albedo (FGD) the model
//! consumes and the TIR correction come from providers ([`Fgd`], [`Tir`]) so the same model
//! runs with exact quadrature (the oracle) or with the very tables the GPU samples.
//!
//! Conventions: the medium above the stack is [`IOR_AIR`]; a dielectric's η is averaged over RGB
//! (no dispersion), a conductor's (η, κ) is per channel; relative IORs are η_{i+1}/η_i and
//! κ_{i+1}/η_i; roughness is GGX α.

pub(crate) mod adding;
pub mod angular;
pub mod diffuse;
pub mod fgd;
pub mod fresnel;
pub mod hg;
pub mod light;
pub mod medium;
pub mod microfacet;
pub mod microsurface;
pub mod oracle;
pub mod random;
pub mod tir;
pub mod tir_fit;
pub mod tm2;
pub mod tm6;
pub mod transport;

/// IOR of the medium above the top layer. lamina uses vacuum (1.0), so a single conductor layer
/// has exactly the F0 the `ggx` baseline uses; the reference's Mitsuba air is 1.000277.
pub const IOR_AIR: f64 = 1.0;

/// |η − 1| below which a dielectric interface is index-matched and skipped (the reference's
/// `ENoComponent`).
pub const INDEX_MATCHED: f64 = 1e-5;

/// |η − 1| below which a dielectric interface reflects nothing: the FGD tables do not resolve
/// it (`fgd=karis`'s B term does not vanish as η → 1).
pub const REFLECTS_NOTHING: f64 = 1e-3;

/// The 6-flux model's largest lobe count, `TM6_LOBES_PER_LAYER`·n − `TM6_LOBES_LESS` for n
/// layers ([`max_lobes`]).
pub const TM6_LOBES_PER_LAYER: u32 = 6;
pub const TM6_LOBES_LESS: u32 = 2;

/// Most lobes one evaluation of a stack of `layers` layers can emit under `model` (the
/// shaders' `TM_MAX_LOBES`, generated from the constants above): one per layer (2-flux); in
/// 6-flux, the first interface emits its primary lobe alone and each later component (medium,
/// interface, …) up to three, most when every layer is a dielectric with a medium:
/// 1 + 3·(2n − 1) = 6n − 2.
pub fn max_lobes(model: crate::variant::Model, layers: usize) -> usize {
    match model {
        crate::variant::Model::Tm6 => {
            TM6_LOBES_PER_LAYER as usize * layers - TM6_LOBES_LESS as usize
        }
        _ => layers,
    }
}

/// One layer as the model consumes it: the interface at its top (complex IOR of the layer,
/// GGX α of the interface) and, for the 6-flux model, the homogeneous medium filling it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerParams {
    pub ior: [f64; 3],
    /// κ > 0 in any channel: a conductor, which ends the stack.
    pub kappa: [f64; 3],
    pub roughness: f64,
    /// Thickness of the medium (6-flux only; 0 = no medium).
    pub depth: f64,
    pub sigma_s: [f64; 3],
    pub sigma_a: [f64; 3],
    /// Henyey–Greenstein asymmetry of the medium's phase function.
    pub g: f64,
    /// `Some(ρ)`: a Lambertian base of albedo ρ (RGB) in the medium above, which ends the
    /// stack ([`diffuse`]); its interface fields are unused.
    pub diffuse: Option<[f64; 3]>,
}

/// Gold's complex IOR per RGB channel (ALGORITHMS.md §12.2): the baseline's default material.
pub const GOLD_IOR: [f64; 3] = [0.143245, 0.377423, 1.43919];
pub const GOLD_KAPPA: [f64; 3] = [3.98479, 2.3847, 1.60434];

impl LayerParams {
    /// A dielectric interface of IOR `ior` in every channel and GGX roughness `roughness`,
    /// with no medium below it.
    pub fn dielectric(ior: f64, roughness: f64) -> Self {
        Self {
            ior: [ior; 3],
            kappa: [0.0; 3],
            roughness,
            depth: 0.0,
            sigma_s: [0.0; 3],
            sigma_a: [0.0; 3],
            g: 0.0,
            diffuse: None,
        }
    }

    /// A conductor of complex IOR (`ior`, `kappa`) per channel and GGX roughness `roughness`.
    pub fn conductor(ior: [f64; 3], kappa: [f64; 3], roughness: f64) -> Self {
        Self {
            ior,
            kappa,
            ..Self::dielectric(1.0, roughness)
        }
    }

    /// Rough gold ([`GOLD_IOR`], [`GOLD_KAPPA`]).
    pub fn gold(roughness: f64) -> Self {
        Self::conductor(GOLD_IOR, GOLD_KAPPA, roughness)
    }

    /// A Lambertian base of albedo `rho` ([`diffuse`]); its interface fields are unused.
    pub fn diffuse_base(rho: [f64; 3]) -> Self {
        Self {
            roughness: 1.0,
            diffuse: Some(rho),
            ..Self::dielectric(1.0, 0.0)
        }
    }

    /// This layer with a homogeneous medium (6-flux) of thickness `depth`, coefficients
    /// `sigma_s` and `sigma_a` per channel and HG asymmetry `g`.
    pub fn with_medium(self, depth: f64, sigma_s: [f64; 3], sigma_a: [f64; 3], g: f64) -> Self {
        Self {
            depth,
            sigma_s,
            sigma_a,
            g,
            ..self
        }
    }

    pub fn is_conductor(&self) -> bool {
        self.kappa.iter().any(|&k| k > 0.0)
    }

    pub fn is_diffuse(&self) -> bool {
        self.diffuse.is_some()
    }

    /// Whether the layer ends the stack: a conductor or a diffuse base.
    pub fn is_opaque_base(&self) -> bool {
        self.is_conductor() || self.is_diffuse()
    }
}

/// Whether a stack ends in a diffuse base ([`diffuse`]): a pass for it keeps that lobe's code
/// (`ShadeSpec::diffuse_base`).
pub fn ends_diffuse(layers: &[LayerParams]) -> bool {
    layers.last().is_some_and(LayerParams::is_diffuse)
}

/// Whether a stack ends in a dielectric (neither a conductor nor a diffuse base), so that it
/// transmits: a pass for it shades what it transmits (`ShadeSpec::transmits`).
pub fn ends_transmissive(layers: &[LayerParams]) -> bool {
    layers.last().is_some_and(|l| !l.is_opaque_base())
}

/// The roughness of the lobe a stack transmits, as the forward pass shades it (a thin slab:
/// the base's back face is parallel to the stack, so light leaves it along the direction it
/// entered): the primary path's asymmetry in the base, `g_t0` (§4.4's first-order
/// transmitted asymmetry), refracted back out through that face into the outside medium of
/// the base's index `eta_base` (mean over RGB). `tm_transmitted_alpha` in lib/tm_common.glsl.
pub fn transmitted_alpha(g_t0: f64, eta_base: f64) -> f64 {
    hg::alpha_of_g(hg::refract(g_t0, eta_base / IOR_AIR))
}

/// One reflected lobe: its RGB energy (directional albedo) and GGX roughness α.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobe {
    pub weight: [f64; 3],
    pub roughness: f64,
    /// A diffuse base's Lambertian lobe (`roughness` then unused; [`diffuse`]).
    pub diffuse: bool,
}

/// What the model gives for one view direction.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// Total reflectance R (the lobe weights sum to it).
    pub reflectance: [f64; 3],
    /// Total transmittance T below the stack (0 for a stack ending in a conductor).
    pub transmittance: [f64; 3],
    /// TM2: one lobe per layer, top first (lobe k belongs to layer k, zero-energy lobes
    /// included). TM6: per component, primary then secondary-forward then secondary-backward,
    /// as the reference emits them.
    pub lobes: Vec<Lobe>,
    /// The layer each lobe belongs to (the layer whose interface, medium or base emitted it),
    /// lobe by lobe; empty in an evaluation read back from the GPU, which does not report it.
    pub lobe_layers: Vec<usize>,
    /// Bit k: lobe k is centred on the view rather than its mirror direction (a 6-flux
    /// secondary-backward lobe, lit around the view; the first 32 lobes).
    pub retro_mask: u32,
    /// The GGX roughness of the lobe the stack transmits ([`transmitted_alpha`]); what it
    /// carries is `transmittance`.
    pub transmitted_roughness: f64,
    /// `transport=corrected`: the top interface's lobe, shaded under lights as that
    /// interface's microfacet lobe with its Fresnel factor (`model::light`); `None` for the
    /// paper's transport and for a stack whose top does not reflect from the air
    /// (`transport::top_reflects`).
    pub top_fresnel: Option<TopFresnel>,
}

/// The top interface whose lobe `transport=corrected` shades with Fresnel's factor: which lobe
/// it is, the interface's relative IOR (mean over RGB) and the directional albedo the model
/// gave it at the view (the lobe's weight before the transport's ratio: nothing above
/// reflects), which normalises the lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TopFresnel {
    pub lobe: usize,
    pub eta: f64,
    pub albedo: f64,
}

/// Directional albedo of a rough interface: FGD(μ, α, η, κ) = ∫ F·D·G2 / (4μ) dω_o.
pub trait Fgd {
    fn fgd(&self, mu: f64, alpha: f64, eta: f64, kappa: f64) -> f64;
}

/// The directional albedo the model consumes: `fgd`'s value, within [0, 1]. Tables hold half
/// floats and interpolate, and `fgd=karis`'s F0·A + B overshoots 1 for a near-perfect mirror
/// (A + B of a smooth interface rounds above 1): an albedo above 1 is a component that makes
/// light, and under a near-lossless scatterer the gap's denominator 1 − R′r went negative (the
/// f64 model reflected 67 676).
///
/// A smooth interface (α = 0) reflects exactly its Fresnel reflectance (the directional albedo
/// of a mirror), which no table is needed for: every FGD source gives it, and the shaders skip
/// the table there too (`tm_albedo_rgb`; a specialized pipeline knows it statically).
pub fn albedo(fgd: &dyn Fgd, mu: f64, alpha: f64, eta: f64, kappa: f64) -> f64 {
    if alpha == 0.0 {
        return fresnel::conductor(mu, eta, kappa);
    }
    fgd.fgd(mu, alpha, eta, kappa).clamp(0.0, 1.0)
}

/// Total-internal-reflection correction: the fraction of a rough lobe (incidence μ, roughness α)
/// trapped by an interface of relative IOR η < 1 (ALGORITHMS.md §4.5, §6.3).
pub trait Tir {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64;
}

/// `tir=none`: no correction.
pub struct NoTir;

impl Tir for NoTir {
    fn tir(&self, _mu: f64, _alpha: f64, _eta: f64) -> f64 {
        0.0
    }
}
