//! The variant key: every axis the published study swept, as one typed value.
//!
//! It prints and parses as `model=tm2,max_layers=5,fp16=off,tir=none,fgd=karis,g2=height-correlated,ndf=ggx`
//! so the CLI, sweep files and result rows share one spelling. Parsing accepts any subset of
//! the axes (the rest take their defaults) in any order; printing always gives all axes in the
//! order above.
//!
//! | axis | values | mechanism |
//! |---|---|---|
//! | model | `ggx`, `tm2`, `tm6` | spec constant 0 |
//! | max_layers | 1 … 16 | spec constant 1 (sizes function-local arrays) |
//! | fp16 | `off`, `on` | `#define LAMINA_FP16` (types change; needs `shaderFloat16`) |
//! | tir | `none`, `constant`, `analytic`, `lut32`, `lut16` | spec constant 2 |
//! | fgd | `karis`, `belcour`, `4d`, `resampled4d` | spec constant 3 |
//! | g2 | `height-correlated`, `smith`, `schlick`, `earl` | spec constant 4 |
//! | ndf | `ggx`, `karis` | spec constant 5 |
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
        Constant = "constant",
        Analytic = "analytic",
        Lut32 = "lut32",
        Lut16 = "lut16",
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
        }
    }
}

pub const AXES: &[&str] = &["model", "max_layers", "fp16", "tir", "fgd", "g2", "ndf"];

/// The specialization constants of the shading passes, mirrored in
/// `glsl/include/shared/variant.glsl` (ids 0…6).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
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
}

crate::spec_constants!(ShadeSpec {
    model = 0,
    max_layers = 1,
    tir = 2,
    fgd = 3,
    g2 = 4,
    ndf = 5,
    local_size_x = 6,
});

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
        }
    }

    /// Preprocessor definitions: only the axes that change types or layouts.
    pub fn defines(&self) -> Vec<(&'static str, &'static str)> {
        if self.fp16 {
            vec![("LAMINA_FP16", "1")]
        } else {
            Vec::new()
        }
    }
}

impl fmt::Display for VariantKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "model={},max_layers={},fp16={},tir={},fgd={},g2={},ndf={}",
            self.model,
            self.max_layers,
            if self.fp16 { "on" } else { "off" },
            self.tir,
            self.fgd,
            self.g2,
            self.ndf
        )
    }
}

impl FromStr for VariantKey {
    type Err = VariantError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse_over(s, Self::default())
    }
}

impl VariantKey {
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
                "max_layers" => {
                    key.max_layers = value
                        .parse()
                        .ok()
                        .filter(|n| (1..=MAX_LAYERS_LIMIT).contains(n))
                        .ok_or_else(|| VariantError::BadValue {
                            key: axis.into(),
                            value: value.into(),
                            allowed: format!("an integer in 1..={MAX_LAYERS_LIMIT}"),
                        })?
                }
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
                _ => {
                    return Err(VariantError::UnknownAxis {
                        key: axis.into(),
                        allowed: AXES.join(", "),
                    })
                }
            }
            seen.push(AXES.iter().find(|a| **a == axis).expect("matched above"));
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
            "model=ggx,max_layers=4,fp16=off,tir=none,fgd=karis,g2=height-correlated,ndf=ggx"
        );
        assert_eq!(text.parse::<VariantKey>().unwrap(), VariantKey::default());
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
                                    keys.push(VariantKey {
                                        model,
                                        max_layers,
                                        fp16,
                                        tir,
                                        fgd,
                                        g2,
                                        ndf,
                                    });
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
    fn spec_codes_follow_the_value_tables() {
        let k: VariantKey = "model=tm6,max_layers=9,tir=lut16,fgd=resampled4d,g2=earl,ndf=karis"
            .parse()
            .unwrap();
        assert_eq!(
            k.spec(),
            ShadeSpec {
                model: 2,
                max_layers: 9,
                tir: 4,
                fgd: 3,
                g2: 3,
                ndf: 1,
                local_size_x: 1,
            }
        );
        assert!(k.defines().is_empty());
        let fp16: VariantKey = "fp16=on".parse().unwrap();
        assert_eq!(fp16.defines(), vec![("LAMINA_FP16", "1")]);
    }
}
