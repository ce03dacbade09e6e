//! The variant key: every axis the published study swept, as one typed value.
//!
//! It prints and parses as
//! `model=tm2,max_layers=5,fp16=off,tir=none,fgd=karis,g2=height-correlated,ndf=ggx,mode=generic`
//! so the CLI, sweep files and result rows share one spelling. Parsing accepts any subset of
//! the axes (the rest take their defaults) in any order; printing always gives the axes above
//! in that order, then `transport`, `interfaces` and `ibl` where they are off their defaults
//! (added after the published study: keys written before them print as they did).
//!
//! | axis | values | mechanism |
//! |---|---|---|
//! | model | `ggx`, `tm2`, `tm6` | spec constant 0 |
//! | max_layers | 1 … 16 | spec constant 1 (sizes function-local arrays) |
//! | fp16 | `off`, `on` | `#define LAMINA_FP16` (types change; needs `shaderFloat16`) |
//! | tir | `none`, `constant`, `analytic`, `lut32`, `lut16`, `fit` | spec constant 2 |
//! | fgd | `karis`, `belcour`, `4d`, `resampled4d` | spec constant 3 |
//! | g2 | `height-correlated`, `smith`, `schlick`, `earl` | spec constant 4 |
//! | ndf | `ggx`, `karis` | spec constant 5 |
//! | mode | `generic`, `specialized`, `specialized-values`, `baked` | spec constant 7 (+ the material's structure, ids 8…17, and values, ids 32…) |
//! | transport | `paper`, `corrected` | spec constant 21 (+ the material's energy ratios in its buffer) |
//! | interfaces | `single`, `multiple` | which ratios the host computes for `corrected` |
//! | ibl | `split-sum`, `matched`, `taps`, `anisotropic` | spec constant 23 (+ the matched cube, built when a pass needs it) |
//!
//! `mode` picks how much of the material the pipeline knows: nothing (`generic`, the talk's
//! shader: parameters read at run time, arrays sized by `max_layers`), its structure
//! (`specialized`: layer count and each layer's kind as constants, so loops unroll and dead
//! paths go), its structure and values (`specialized-values`), or its lobes tabulated over the
//! view cosine (`baked`). Under every mode but `generic` one pipeline serves one material, and
//! `max_layers` does not matter: the arrays have the material's own size.
//!
//! Every combination is valid as a key; whether a device can run it (fp16) or a material fits
//! it (`max_layers`) is checked where those are known.
//!
//! The model, the materials, the shaders and the tables all name variant axes, so the key lives
//! below them and imports none of them (only `vk`, for [`ShadeSpec`]'s specialization constants).

use std::fmt;
use std::str::FromStr;

/// Largest static layer-array size a variant may ask for.
pub const MAX_LAYERS_LIMIT: u32 = 16;

#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum VariantError {
    #[error("variant key `{0}`: expected `axis=value` pairs separated by commas")]
    Malformed(String),
    #[error("unknown variant axis `{key}`; axes are: {allowed}")]
    UnknownAxis { key: String, allowed: String },
    #[error("variant axis `{key}` has no value `{value}`; allowed: {allowed}")]
    BadValue {
        key: String,
        value: String,
        allowed: String,
    },
    #[error("variant axis `{0}` is given twice")]
    Duplicate(String),
    #[error("`{given}` needs `{needs}`: {why}")]
    Needs {
        given: String,
        needs: &'static str,
        why: &'static str,
    },
}

/// An axis whose values are a closed set of names, each with its spec-constant code.
pub trait Axis: Copy + Eq + Sized + 'static {
    const NAME: &'static str;
    /// (spelling, value); the index is the spec-constant code.
    const VALUES: &'static [(&'static str, Self)];

    fn name(self) -> &'static str {
        Self::VALUES
            .iter()
            .find(|(_, v)| *v == self)
            .map(|(n, _)| *n)
            .expect("every value is listed")
    }

    fn code(self) -> u32 {
        Self::VALUES
            .iter()
            .position(|(_, v)| *v == self)
            .expect("every value is listed") as u32
    }

    fn parse_value(value: &str) -> Result<Self, VariantError> {
        Self::VALUES
            .iter()
            .find(|(n, _)| *n == value)
            .map(|(_, v)| *v)
            .ok_or_else(|| VariantError::BadValue {
                key: Self::NAME.into(),
                value: value.into(),
                allowed: Self::allowed(),
            })
    }

    fn allowed() -> String {
        Self::VALUES
            .iter()
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

macro_rules! axis {
    ($(#[$doc:meta])* $ty:ident, $name:literal, { $($(#[$vdoc:meta])* $variant:ident = $spelling:literal),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $ty { $($(#[$vdoc])* $variant),+ }
        impl Axis for $ty {
            const NAME: &'static str = $name;
            const VALUES: &'static [(&'static str, Self)] = &[$(($spelling, Self::$variant)),+];
        }
        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

axis!(
    /// Which reflectance model the forward pass evaluates.
    Model, "model", {
        /// One GGX lobe with split-sum IBL: the yardstick.
        Ggx = "ggx",
        /// Transfer-matrix 2-flux model.
        Tm2 = "tm2",
        /// Transfer-matrix 6-flux model (scattering media).
        Tm6 = "tm6",
    }
);
axis!(
    /// Total-internal-reflection correction.
    Tir, "tir", {
        None = "none",
        /// The talk's dummy constant in place of the table fetch.
        Constant = "constant",
        /// The talk's naive analytic estimator (ALGORITHMS.md §9.2).
        Analytic = "analytic",
        /// The 3-D table in 32-bit floats.
        Lut32 = "lut32",
        /// The same table rounded to half floats.
        Lut16 = "lut16",
        /// A closed form least-squares fitted to the table (`lamina tables tir-fit`).
        Fit = "fit",
    }
);
axis!(
    /// Where the FGD (directional albedo) comes from.
    Fgd, "fgd", {
        Karis = "karis",
        Belcour = "belcour",
        /// The full 64⁴ table as a 64×64×4096 3-D image.
        Full4d = "4d",
        /// The talk's 64×64×2048 resampling.
        Resampled4d = "resampled4d",
    }
);
axis!(
    /// Masking-shadowing term.
    G2, "g2", {
        HeightCorrelated = "height-correlated",
        Smith = "smith",
        Schlick = "schlick",
        Earl = "earl",
    }
);
axis!(
    /// Normal distribution function form.
    Ndf, "ndf", {
        Ggx = "ggx",
        /// Karis' algebraically equal form of GGX D.
        Karis = "karis",
    }
);

axis!(
    /// How much of the material a pipeline is built for.
    Mode, "mode", {
        /// Parameters read at run time, arrays sized by `max_layers`: one pipeline for every
        /// material.
        Generic = "generic",
        /// The layer count and each layer's structure as constants: one pipeline per
        /// material structure.
        Specialized = "specialized",
        /// Structure and every numeric parameter as constants: one pipeline per material.
        SpecializedValues = "specialized-values",
        /// A spatially uniform material's lobes tabulated over the view cosine: one table
        /// fetch and one environment fetch per lobe.
        Baked = "baked",
    }
);

axis!(
    /// How a rough interface scatters in the reference (and, with issue 27's corrected
    /// transport, in the model): `single`, the microfacet BSDF of one scattering event, which
    /// loses what its masking removes; `multiple`, the walk on the microsurface (Heitz,
    /// Hanika, d'Eon & Dachsbacher 2016), which conserves it.
    Interfaces, "interfaces", {
        Single = "single",
        Multiple = "multiple",
    }
);

axis!(
    /// How the layered models carry energy between their layers (issue 27).
    Transport, "transport", {
        /// The paper's: each interface one directional reflectance and 1 − r, every upward
        /// crossing trapped with the first crossing's TIR ratio. The talk's reproduction.
        Paper = "paper",
        /// Each layer's energy from the discrete-ordinates transport of the material in the
        /// variant's `interfaces` mode (`model::transport`), per material over the view cosine;
        /// the lobes' shapes the paper's.
        Corrected = "corrected",
    }
);

axis!(
    /// How each lobe is lit by the environment (issue 30; ALGORITHMS.md §8.2).
    Ibl, "ibl", {
        /// One fetch per lobe along its dominant direction from the cube prefiltered as Karis
        /// 2013 does (N = V = R, samples weighted by n·l): the talk's reproduction.
        SplitSum = "split-sum",
        /// One fetch per lobe from a cube prefiltered with the lobe's own weighting at normal
        /// view (D·G2, the BRDF times the cosine), with more samples and no blur bias
        /// (`tables::environment`), where that cube's kernel comes closest to the lobe in L²
        /// (`tables::lobe_fit`): the lean towards the normal and the mip that minimise the
        /// mean squared error under a point light.
        Matched = "matched",
        /// Filtered importance sampling (Křivánek & Colbert 2008): `taps` directions (default
        /// [`IBL_TAP_COUNT`]) through the lobe's visible normals, each read from the matched cube at the mip
        /// whose blur covers its share of the lobe, weighted G2/G1.
        Taps = "taps",
        /// Two fetches of the matched cube, the lobe matched in its first and second moments
        /// (`tables::lobe_moments`): placed symmetrically about its mean direction along its
        /// major axis, each blurred as much as the lobe spreads across that axis. A grazing
        /// lobe, narrower across the plane of incidence than along it, keeps that shape.
        Anisotropic = "anisotropic",
        /// The environment's lamps taken out of the map (`tables::lamps`: its small regions
        /// far brighter than its mean) and lit as disk lights, each lobe evaluated at each
        /// lamp as an analytic light is (the pass holds them as constants); the rest, a smooth
        /// map, read in one fetch along the lobe's mean direction (`tables::lobe_moments`) at
        /// the mip of `Matched`'s L² fit (`tables::lobe_fit::polynomial`: two polynomials in
        /// place of the tables), from a cube of the map without them prefiltered with the
        /// lobe's own weights (as the matched cube is) at Karis's levels.
        Lamps = "lamps",
    }
);

axis!(
    /// Where the stack is shaded (issue 28).
    ShadePath, "path", {
        /// In the fragment shader of the mesh's draw: the talk's.
        Forward = "forward",
        /// In compute: the mesh's draw writes a G-buffer (the world position, normal and
        /// texture coordinates the fragment shader would receive), then one invocation per
        /// pixel shades what it holds (`render::deferred`).
        Deferred = "deferred",
    }
);

axis!(
    /// How the deferred path sends pixels to its shading pipelines (issue 28;
    /// `render::deferred`). Under `mode=specialized` a varying stack's pixels fall into
    /// classes by the layers their coverage leaves (`render::classes`), each with its own
    /// pipeline.
    Classify, "classify", {
        /// One dispatch over every pixel; a varying stack's classes are not told apart, so
        /// `mode=specialized` refuses one.
        None = "none",
        /// Each 8×8 tile (one work group) goes to the pipeline of its pixels' class where
        /// they share one, else to the generic pipeline fitted to the stack: one indirect
        /// dispatch per class.
        Tiles = "tiles",
        /// Each class's pixels are compacted into a list and its pipeline shades exactly
        /// them: one indirect dispatch per class.
        Pixels = "pixels",
    }
);

axis!(
    /// How many colour channels one walk of the 6-flux model carries (issue 28 item 5;
    /// `lib/tm6.glsl`).
    Channels, "channels", {
        /// All three at once: the energy and g-weighted slabs are 198 floats.
        Rgb = "rgb",
        /// One at a time, the walk repeated per channel: a third of the slabs live at once,
        /// each walk's scalar factors computed three times.
        Serial = "serial",
    }
);

/// The directions `ibl=taps` reads per lobe unless `taps` says otherwise.
pub const IBL_TAP_COUNT: u32 = 32;

/// The most directions `taps` may ask of `ibl=taps` per lobe: the count rides in the `ibl`
/// specialization constant's bits above its code ([`VariantKey::spec`]).
pub const IBL_TAP_LIMIT: u32 = 4096;

impl Mode {
    /// Whether a pipeline of this mode is built for one material.
    pub fn per_material(self) -> bool {
        self != Mode::Generic
    }
}

/// One shader variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VariantKey {
    pub model: Model,
    pub max_layers: u32,
    pub fp16: bool,
    pub tir: Tir,
    pub fgd: Fgd,
    pub g2: G2,
    pub ndf: Ndf,
    pub mode: Mode,
    pub transport: Transport,
    /// The interface mode `transport=corrected` takes its energies in (and the reference's
    /// truth it is meant to meet); `paper` has one.
    pub interfaces: Interfaces,
    /// How the environment lights each lobe.
    pub ibl: Ibl,
    /// The directions `ibl=taps` reads per lobe ([`IBL_TAP_COUNT`] unless another `ibl` value).
    pub taps: u32,
    /// Where the stack is shaded: the mesh's fragment shader, or compute over a G-buffer.
    pub path: ShadePath,
    /// How the deferred path sends pixels to its pipelines (`none` on the forward path).
    pub classify: Classify,
    /// How many colour channels a 6-flux walk carries.
    pub channels: Channels,
}

impl Default for VariantKey {
    fn default() -> Self {
        Self {
            model: Model::Ggx,
            max_layers: 4,
            fp16: false,
            tir: Tir::None,
            fgd: Fgd::Karis,
            g2: G2::HeightCorrelated,
            ndf: Ndf::Ggx,
            mode: Mode::Generic,
            transport: Transport::Paper,
            interfaces: Interfaces::Single,
            ibl: Ibl::SplitSum,
            taps: IBL_TAP_COUNT,
            path: ShadePath::Forward,
            classify: Classify::None,
            channels: Channels::Rgb,
        }
    }
}

pub const AXES: &[&str] = &[
    "model",
    "max_layers",
    "fp16",
    "tir",
    "fgd",
    "g2",
    "ndf",
    "mode",
    "transport",
    "interfaces",
    "ibl",
    "taps",
    "path",
    "classify",
    "channels",
];

/// Layers whose numeric values a `specialized-values` pipeline holds as constants, and the
/// constants per layer: ids `VALUE_ID_BASE + VALUES_PER_LAYER·layer + field`, the fields in
/// [`LayerValue`]'s order.
pub const VALUE_ID_BASE: u32 = 32;
pub const VALUES_PER_LAYER: u32 = 16;

/// The numeric fields of a layer as `specialized-values` constants (field index = position).
pub const LAYER_VALUES: [&str; 15] = [
    "IOR_R",
    "IOR_G",
    "IOR_B",
    "KAPPA_R",
    "KAPPA_G",
    "KAPPA_B",
    "SIGMA_S_R",
    "SIGMA_S_G",
    "SIGMA_S_B",
    "SIGMA_A_R",
    "SIGMA_A_G",
    "SIGMA_A_B",
    "ALPHA",
    "DEPTH",
    "G",
];

/// The specialization constants of the shading passes, mirrored in
/// `glsl/include/shared/variant.glsl`: the variant's axes (ids 0…7), the structure of the
/// material a per-material pipeline is built for (ids 8…17, zero under `mode=generic`) and its
/// values (`specialized-values`: ids [`VALUE_ID_BASE`]…). Layer masks hold bit `i` for layer
/// `i` (top first).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadeSpec {
    pub model: u32,
    pub max_layers: u32,
    pub tir: u32,
    pub fgd: u32,
    pub g2: u32,
    pub ndf: u32,
    /// The work-group width of a compute entry point that shades, set from its interface when
    /// the pipeline is made (`shader::kernel::WorkGroupSpec`); the fragment pass has none.
    pub local_size_x: u32,
    pub mode: u32,
    /// The material's layer count (per-material modes).
    pub layer_count: u32,
    /// Interfaces with α = 0: Fresnel, no FGD lookup.
    pub smooth_mask: u32,
    /// 1 when the last layer is a conductor.
    pub conductor_base: u32,
    /// Layers with a medium (6-flux, depth > 0).
    pub medium_mask: u32,
    /// Dielectric interfaces denser below than above (η_ij ≥ 1): TIR only for light going up.
    pub denser_mask: u32,
    /// Index-matched interfaces (the model's skip).
    pub matched_mask: u32,
    /// Interfaces that refract but reflect nothing (|η_ij − 1| below the model's threshold).
    pub clear_mask: u32,
    /// `baked`: the lobe count and which lobes are lit around the view (back-scatter).
    pub lobe_count: u32,
    pub retro_mask: u32,
    /// `baked`: view-cosine samples per lobe.
    pub baked_size: u32,
    /// 1: the stack varies over the surface (`material::surface`): the forward pass reads its
    /// maps and each pixel's covered layers. A property of the material, not an axis: a
    /// generic pass is built per (variant, varying or not).
    pub surface_maps: u32,
    /// 1: the stack may end in a diffuse base (`model::diffuse`). Its lobe's code folds away
    /// where this is 0: lavapipe runs both sides of every branch, and a stack without a
    /// diffuse base must not pay for one. Set per material for the forward pass, always for
    /// the GPU evaluator.
    pub diffuse_base: u32,
    /// 1: the scene has analytic lights (`render::lights`): the forward pass loops over them.
    /// 0 removes the loops, which lavapipe would otherwise compile into every pass.
    pub lights: u32,
    /// The `transport` axis (id 21).
    pub transport: u32,
    /// 1: the stack may end in a dielectric and transmit (`model::ends_transmissive`): the
    /// forward pass shades the transmitted lobe; 0 folds its code away. Set per material for
    /// the forward pass, always for the GPU evaluator's generic kernel.
    pub transmits: u32,
    /// The `ibl` axis (id 23): its code in the low byte, `taps` above.
    pub ibl: u32,
    /// A varying stack's class pass (`render::classes`): the slots whose maps carry a value
    /// across one of the model's tests, which the pass makes at run time (id 24).
    pub dynamic_mask: u32,
    /// The class's material layer per slot, 4 bits each: slots 0–7, then 8–15 (ids 25, 26).
    pub layer_slots_lo: u32,
    pub layer_slots_hi: u32,
    /// `classify.frag.glsl`: the layer whose coverage a stencil mark tests (id 27).
    pub mark_layer: u32,
    /// A class pass: per slot, a byte of the fields its layer reads from maps, four slots
    /// per word (ids 28–31; `render::classes::Class::slot_maps`).
    pub slot_maps: [u32; 4],
    /// `specialized-values`: the layers' values (see [`LAYER_VALUES`]).
    pub values: [[f32; VALUES_PER_LAYER as usize]; MAX_LAYERS_LIMIT as usize],
    /// `ibl=lamps`: the environment's lamps (`tables::lamps::lamp_values`; ids from
    /// [`LAMP_ID_BASE`]).
    pub lamps: [f32; LAMP_VALUES],
}

impl Default for ShadeSpec {
    fn default() -> Self {
        VariantKey::default().spec()
    }
}

const AXIS_ENTRIES: usize = 32;
const VALUE_ENTRIES: usize = (MAX_LAYERS_LIMIT * VALUES_PER_LAYER) as usize;

/// The bit of the `fgd` constant (id 3, `FGD_SPEC`) above the axis's code that holds a pass's
/// `FGD_PAST_EDGE`: the stack's lookups may fall past the 4-D table's domain
/// (`render::pass::past_fgd_edge`), and the code that carries FGD on from its edge stays.
pub const FGD_PAST_EDGE_SHIFT: u32 = 8;

/// Lamp slots an `ibl=lamps` pass holds (`tables::lamps::MAX_LAMPS`).
pub const LAMP_SLOTS: usize = 4;

/// Specialization constants an `ibl=lamps` pass holds its environment's lamps in: two
/// vectors per slot (`tables::lamps::lamp_values`, `generated/layer_values.glsl`'s
/// `ibl_lamp`).
pub const LAMP_VALUES: usize = 8 * LAMP_SLOTS;

/// The first id of the lamps' constants, after the layers' values.
pub const LAMP_ID_BASE: u32 = VALUE_ID_BASE + VALUE_ENTRIES as u32;

const SPEC_ENTRIES: usize = AXIS_ENTRIES + VALUE_ENTRIES + LAMP_VALUES;

const fn shade_spec_entries() -> [crate::vk::SpecEntry; SPEC_ENTRIES] {
    let mut out = [crate::vk::SpecEntry {
        id: 0,
        offset: 0,
        size: 4,
    }; SPEC_ENTRIES];
    // ids 0…31 are the u32 fields in declaration order, 4 bytes apart from offset 0.
    let mut i = 0;
    while i < AXIS_ENTRIES {
        out[i].id = i as u32;
        out[i].offset = 4 * i;
        i += 1;
    }
    let mut v = 0;
    while v < VALUE_ENTRIES {
        out[AXIS_ENTRIES + v].id = VALUE_ID_BASE + v as u32;
        out[AXIS_ENTRIES + v].offset = std::mem::offset_of!(ShadeSpec, values) + 4 * v;
        v += 1;
    }
    let mut l = 0;
    while l < LAMP_VALUES {
        out[AXIS_ENTRIES + VALUE_ENTRIES + l].id = LAMP_ID_BASE + l as u32;
        out[AXIS_ENTRIES + VALUE_ENTRIES + l].offset =
            std::mem::offset_of!(ShadeSpec, lamps) + 4 * l;
        l += 1;
    }
    out
}

const _: () = assert!(std::mem::offset_of!(ShadeSpec, slot_maps) + 12 == 4 * (AXIS_ENTRIES - 1));

impl crate::vk::SpecConstants for ShadeSpec {
    const ENTRIES: &'static [crate::vk::SpecEntry] = &shade_spec_entries();
}

impl VariantKey {
    pub fn spec(&self) -> ShadeSpec {
        ShadeSpec {
            model: self.model.code(),
            max_layers: self.max_layers,
            tir: self.tir.code(),
            fgd: self.fgd.code(),
            g2: self.g2.code(),
            ndf: self.ndf.code(),
            local_size_x: 1,
            mode: self.mode.code(),
            layer_count: 0,
            smooth_mask: 0,
            conductor_base: 0,
            medium_mask: 0,
            denser_mask: 0,
            matched_mask: 0,
            clear_mask: 0,
            lobe_count: 0,
            retro_mask: 0,
            baked_size: 0,
            surface_maps: 0,
            diffuse_base: 0,
            lights: 0,
            transport: self.transport.code(),
            transmits: 0,
            ibl: self.ibl.code() | self.taps << 8,
            dynamic_mask: 0,
            layer_slots_lo: 0,
            layer_slots_hi: 0,
            mark_layer: 0,
            slot_maps: [0; 4],
            values: [[0.0; VALUES_PER_LAYER as usize]; MAX_LAYERS_LIMIT as usize],
            lamps: [0.0; LAMP_VALUES],
        }
    }

    /// Preprocessor definitions: only the axes that change types or layouts (the serial
    /// 6-flux walk's values are floats, not vectors).
    pub fn defines(&self) -> Vec<(&'static str, &'static str)> {
        let mut defines = Vec::new();
        if self.fp16 {
            defines.push(("LAMINA_FP16", "1"));
        }
        if self.channels == Channels::Serial {
            defines.push(("LAMINA_TM6_SERIAL", "1"));
        }
        defines
    }
}

impl fmt::Display for VariantKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "model={},max_layers={},fp16={},tir={},fgd={},g2={},ndf={},mode={}",
            self.model,
            self.max_layers,
            if self.fp16 { "on" } else { "off" },
            self.tir,
            self.fgd,
            self.g2,
            self.ndf,
            self.mode
        )?;
        // The axes added after the published study's print only off their defaults, so a key
        // written before they existed prints as it did.
        if self.transport != Transport::Paper {
            write!(f, ",transport={}", self.transport)?;
        }
        if self.interfaces != Interfaces::Single {
            write!(f, ",interfaces={}", self.interfaces)?;
        }
        if self.ibl != Ibl::SplitSum {
            write!(f, ",ibl={}", self.ibl)?;
        }
        if self.taps != IBL_TAP_COUNT {
            write!(f, ",taps={}", self.taps)?;
        }
        if self.path != ShadePath::Forward {
            write!(f, ",path={}", self.path)?;
        }
        if self.classify != Classify::None {
            write!(f, ",classify={}", self.classify)?;
        }
        if self.channels != Channels::Rgb {
            write!(f, ",channels={}", self.channels)?;
        }
        Ok(())
    }
}

/// In result files a key is its text, the spelling the command line and sweep files share.
impl serde::Serialize for VariantKey {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for VariantKey {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let text = String::deserialize(deserializer)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

impl FromStr for VariantKey {
    type Err = VariantError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse_over(s, Self::default())
    }
}

/// An axis's count `value`: an integer in 1..=`limit`.
fn parse_count(axis: &str, value: &str, limit: u32) -> Result<u32, VariantError> {
    value
        .parse()
        .ok()
        .filter(|n| (1..=limit).contains(n))
        .ok_or_else(|| VariantError::BadValue {
            key: axis.into(),
            value: value.into(),
            allowed: format!("an integer in 1..={limit}"),
        })
}

impl VariantKey {
    /// Whether this key has every axis value `pattern` names (`model=tm6,fp16=on`), as the
    /// key prints them.
    pub fn matches(&self, pattern: &str) -> bool {
        let text = self.to_string();
        let pairs: Vec<&str> = text.split(',').collect();
        pattern
            .split(',')
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .all(|want| pairs.contains(&want))
    }

    /// The key for prose: model and max_layers, then only the axes off their defaults.
    pub fn short(&self) -> String {
        let defaults = Self::default().to_string();
        let defaults: Vec<&str> = defaults.split(',').skip(2).collect();
        self.to_string()
            .split(',')
            .filter(|part| !defaults.contains(part))
            .collect::<Vec<_>>()
            .join(",")
    }

    /// Parses `s`, taking the axes it does not name from `base` (e.g. the material's model).
    pub fn parse_over(s: &str, base: Self) -> Result<Self, VariantError> {
        let mut key = base;
        let mut seen: Vec<&str> = Vec::new();
        for pair in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (axis, value) = pair
                .split_once('=')
                .ok_or_else(|| VariantError::Malformed(s.into()))?;
            let (axis, value) = (axis.trim(), value.trim());
            if seen.contains(&axis) {
                return Err(VariantError::Duplicate(axis.into()));
            }
            match axis {
                "model" => key.model = Model::parse_value(value)?,
                "max_layers" => key.max_layers = parse_count(axis, value, MAX_LAYERS_LIMIT)?,
                "fp16" => {
                    key.fp16 = match value {
                        "on" => true,
                        "off" => false,
                        _ => {
                            return Err(VariantError::BadValue {
                                key: axis.into(),
                                value: value.into(),
                                allowed: "on, off".into(),
                            })
                        }
                    }
                }
                "tir" => key.tir = Tir::parse_value(value)?,
                "fgd" => key.fgd = Fgd::parse_value(value)?,
                "g2" => key.g2 = G2::parse_value(value)?,
                "ndf" => key.ndf = Ndf::parse_value(value)?,
                "mode" => key.mode = Mode::parse_value(value)?,
                "transport" => key.transport = Transport::parse_value(value)?,
                "interfaces" => key.interfaces = Interfaces::parse_value(value)?,
                "ibl" => key.ibl = Ibl::parse_value(value)?,
                "taps" => key.taps = parse_count(axis, value, IBL_TAP_LIMIT)?,
                "path" => key.path = ShadePath::parse_value(value)?,
                "classify" => key.classify = Classify::parse_value(value)?,
                "channels" => key.channels = Channels::parse_value(value)?,
                _ => {
                    return Err(VariantError::UnknownAxis {
                        key: axis.into(),
                        allowed: AXES.join(", "),
                    })
                }
            }
            seen.push(AXES.iter().find(|a| **a == axis).expect("matched above"));
        }
        if key.taps != IBL_TAP_COUNT && key.ibl != Ibl::Taps {
            return Err(VariantError::Needs {
                given: format!("taps={}", key.taps),
                needs: "ibl=taps",
                why: "it is how many directions `ibl=taps` reads per lobe; the other values \
                      read one or two",
            });
        }
        if key.classify != Classify::None && key.path != ShadePath::Deferred {
            return Err(VariantError::Needs {
                given: format!("classify={}", key.classify),
                needs: "path=deferred",
                why: "it sorts the deferred path's pixels by class; the forward path's \
                      routing is the stencil's",
            });
        }
        if key.channels != Channels::Rgb && key.model != Model::Tm6 {
            return Err(VariantError::Needs {
                given: format!("channels={}", key.channels),
                needs: "model=tm6",
                why: "it walks the 6-flux model's slabs one colour channel at a time",
            });
        }
        Ok(key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_prints_every_axis_and_round_trips() {
        let text = VariantKey::default().to_string();
        assert_eq!(
            text,
            "model=ggx,max_layers=4,fp16=off,tir=none,fgd=karis,g2=height-correlated,ndf=ggx,mode=generic"
        );
        assert_eq!(text.parse::<VariantKey>().unwrap(), VariantKey::default());
    }

    #[test]
    fn the_axes_added_after_the_published_study_print_only_off_their_defaults() {
        let key: VariantKey = "model=tm2,ibl=taps,transport=corrected,interfaces=multiple"
            .parse()
            .unwrap();
        assert!(
            key.to_string()
                .ends_with(",mode=generic,transport=corrected,interfaces=multiple,ibl=taps"),
            "{key}"
        );
        assert_eq!(key.to_string().parse::<VariantKey>().unwrap(), key);
        let split: VariantKey = "model=tm2,ibl=split-sum".parse().unwrap();
        assert!(split.to_string().ends_with(",mode=generic"), "{split}");
        let paper: VariantKey = "model=tm2,transport=paper".parse().unwrap();
        assert!(paper.to_string().ends_with(",mode=generic"), "{paper}");
        for (text, allowed) in [
            ("transport=fixed", "paper, corrected"),
            ("interfaces=double", "single, multiple"),
            ("ibl=exact", "split-sum, matched, taps"),
        ] {
            let e = text.parse::<VariantKey>().unwrap_err().to_string();
            assert!(e.contains(allowed), "{e}");
        }
    }

    #[test]
    fn taps_counts_ibl_taps_directions_and_needs_it() {
        let key: VariantKey = "model=tm2,ibl=taps,taps=128".parse().unwrap();
        assert_eq!(key.taps, 128);
        assert_eq!(key.spec().ibl, Ibl::Taps.code() | 128 << 8);
        assert!(key.to_string().ends_with(",ibl=taps,taps=128"), "{key}");
        let default: VariantKey = "model=tm2,ibl=taps,taps=32".parse().unwrap();
        assert!(default.to_string().ends_with(",ibl=taps"), "{default}");
        let e = "model=tm2,ibl=matched,taps=64"
            .parse::<VariantKey>()
            .unwrap_err();
        assert!(
            e.to_string().starts_with("`taps=64` needs `ibl=taps`"),
            "{e}"
        );
        for bad in ["0", "4097", "-1", "many"] {
            let e = format!("ibl=taps,taps={bad}")
                .parse::<VariantKey>()
                .unwrap_err();
            assert!(e.to_string().contains("1..=4096"), "{e}");
        }
    }

    #[test]
    fn classify_needs_the_deferred_path() {
        let key: VariantKey = "model=tm2,classify=pixels,path=deferred".parse().unwrap();
        assert!(
            key.to_string().ends_with(",path=deferred,classify=pixels"),
            "{key}"
        );
        let e = "model=tm2,classify=tiles"
            .parse::<VariantKey>()
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("`classify=tiles` needs `path=deferred`"),
            "{e}"
        );
        let e = "path=deferred,classify=cells"
            .parse::<VariantKey>()
            .unwrap_err();
        assert!(e.to_string().contains("none, tiles, pixels"), "{e}");
        let none: VariantKey = "path=deferred,classify=none".parse().unwrap();
        assert!(none.to_string().ends_with(",path=deferred"), "{none}");
    }

    #[test]
    fn every_value_of_every_axis_round_trips() {
        let mut keys = Vec::new();
        for &(_, model) in Model::VALUES {
            for &(_, tir) in Tir::VALUES {
                for &(_, fgd) in Fgd::VALUES {
                    for &(_, g2) in G2::VALUES {
                        for &(_, ndf) in Ndf::VALUES {
                            for fp16 in [false, true] {
                                for max_layers in [1, 7, 16] {
                                    for &(_, mode) in Mode::VALUES {
                                        for (transport, interfaces) in [
                                            (Transport::Paper, Interfaces::Single),
                                            (Transport::Corrected, Interfaces::Single),
                                            (Transport::Corrected, Interfaces::Multiple),
                                            (Transport::Paper, Interfaces::Multiple),
                                        ] {
                                            keys.push(VariantKey {
                                                model,
                                                max_layers,
                                                fp16,
                                                tir,
                                                fgd,
                                                g2,
                                                ndf,
                                                mode,
                                                transport,
                                                interfaces,
                                                ibl: Ibl::VALUES[keys.len() % Ibl::VALUES.len()].1,
                                                taps: if Ibl::VALUES[keys.len() % Ibl::VALUES.len()]
                                                    .1
                                                    == Ibl::Taps
                                                {
                                                    1 + keys.len() as u32 % IBL_TAP_LIMIT
                                                } else {
                                                    IBL_TAP_COUNT
                                                },
                                                path: ShadePath::VALUES
                                                    [keys.len() % ShadePath::VALUES.len()]
                                                .1,
                                                classify: if keys.len() % 2 == 1 {
                                                    Classify::VALUES[keys.len() / 2 % 3].1
                                                } else {
                                                    Classify::None
                                                },
                                                channels: if model == Model::Tm6
                                                    && keys.len() % 3 == 0
                                                {
                                                    Channels::Serial
                                                } else {
                                                    Channels::Rgb
                                                },
                                            });
                                        }
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        for key in keys {
            assert_eq!(key.to_string().parse::<VariantKey>().unwrap(), key);
        }
    }

    #[test]
    fn unnamed_axes_come_from_the_base() {
        let base = VariantKey {
            model: Model::Tm6,
            max_layers: 7,
            ..VariantKey::default()
        };
        let k = VariantKey::parse_over("fp16=on", base).unwrap();
        assert_eq!((k.model, k.max_layers, k.fp16), (Model::Tm6, 7, true));
        let k = VariantKey::parse_over("model=ggx", base).unwrap();
        assert_eq!(k.model, Model::Ggx);
    }

    #[test]
    fn partial_keys_take_defaults_in_any_order() {
        let k: VariantKey = "fp16=on, model=tm2".parse().unwrap();
        assert_eq!(k.model, Model::Tm2);
        assert!(k.fp16);
        assert_eq!(k.max_layers, VariantKey::default().max_layers);
    }

    #[test]
    fn errors_name_the_axis_and_the_allowed_values() {
        let e = "modle=ggx".parse::<VariantKey>().unwrap_err().to_string();
        assert!(e.contains("modle") && e.contains("max_layers"), "{e}");
        let e = "model=phong".parse::<VariantKey>().unwrap_err().to_string();
        assert!(e.contains("phong") && e.contains("tm6"), "{e}");
        let e = "max_layers=0"
            .parse::<VariantKey>()
            .unwrap_err()
            .to_string();
        assert!(e.contains("1..=16"), "{e}");
        let e = "max_layers=17"
            .parse::<VariantKey>()
            .unwrap_err()
            .to_string();
        assert!(e.contains("17"), "{e}");
        let e = "fp16=yes".parse::<VariantKey>().unwrap_err().to_string();
        assert!(e.contains("on, off"), "{e}");
        let e = "model=ggx,model=tm2".parse::<VariantKey>().unwrap_err();
        assert_eq!(e, VariantError::Duplicate("model".into()));
        let e = "model".parse::<VariantKey>().unwrap_err();
        assert!(matches!(e, VariantError::Malformed(_)));
    }

    #[test]
    fn spec_entries_are_the_fields_in_order_then_the_values_then_the_lamps() {
        use crate::vk::SpecConstants;
        let entries = ShadeSpec::ENTRIES;
        assert_eq!(entries.len(), AXIS_ENTRIES + VALUE_ENTRIES + LAMP_VALUES);
        let first_lamp = &entries[AXIS_ENTRIES + VALUE_ENTRIES];
        assert_eq!(first_lamp.id, LAMP_ID_BASE);
        assert_eq!(first_lamp.offset, std::mem::offset_of!(ShadeSpec, lamps));
        assert_eq!(entries[7].offset, std::mem::offset_of!(ShadeSpec, mode));
        assert_eq!(
            entries[17].offset,
            std::mem::offset_of!(ShadeSpec, baked_size)
        );
        assert_eq!(
            entries[18].offset,
            std::mem::offset_of!(ShadeSpec, surface_maps)
        );
        assert_eq!(
            entries[19].offset,
            std::mem::offset_of!(ShadeSpec, diffuse_base)
        );
        assert_eq!(entries[20].offset, std::mem::offset_of!(ShadeSpec, lights));
        assert_eq!(
            entries[25].offset,
            std::mem::offset_of!(ShadeSpec, layer_slots_lo)
        );
        let last = entries.last().unwrap();
        assert_eq!(last.id, LAMP_ID_BASE + LAMP_VALUES as u32 - 1);
        assert_eq!(last.offset + last.size, std::mem::size_of::<ShadeSpec>());
    }

    #[test]
    fn spec_codes_follow_the_value_tables() {
        let k: VariantKey =
            "model=tm6,max_layers=9,tir=lut16,fgd=resampled4d,g2=earl,ndf=karis,mode=baked"
                .parse()
                .unwrap();
        let spec = k.spec();
        assert_eq!(
            [
                spec.model,
                spec.max_layers,
                spec.tir,
                spec.fgd,
                spec.g2,
                spec.ndf,
                spec.local_size_x,
                spec.mode
            ],
            [2, 9, 4, 3, 3, 1, 1, 3]
        );
        // The material's structure comes from shader::specialize, not from the key.
        assert_eq!(spec.layer_count, 0);
        assert!(k.defines().is_empty());
        let fp16: VariantKey = "fp16=on".parse().unwrap();
        assert_eq!(fp16.defines(), vec![("LAMINA_FP16", "1")]);
        let serial: VariantKey = "model=tm6,channels=serial,fp16=on".parse().unwrap();
        assert_eq!(
            serial.defines(),
            vec![("LAMINA_FP16", "1"), ("LAMINA_TM6_SERIAL", "1")]
        );
    }

    #[test]
    fn serial_channels_need_the_six_flux_model() {
        let key: VariantKey = "model=tm6,channels=serial".parse().unwrap();
        assert!(
            key.to_string().ends_with(",mode=generic,channels=serial"),
            "{key}"
        );
        let rgb: VariantKey = "model=tm2,channels=rgb".parse().unwrap();
        assert!(rgb.to_string().ends_with(",mode=generic"), "{rgb}");
        let e = "model=tm2,channels=serial"
            .parse::<VariantKey>()
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("`channels=serial` needs `model=tm6`"),
            "{e}"
        );
        let e = "model=tm6,channels=mono".parse::<VariantKey>().unwrap_err();
        assert!(e.to_string().contains("rgb, serial"), "{e}");
    }
}
