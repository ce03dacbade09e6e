//! Per-material pipelines: the specialization constants that tell the shading passes a
//! material's structure (`mode=specialized`), its values too (`mode=specialized-values`), or
//! its baked lobes (`mode=baked`), mirrored in `glsl/include/shared/variant.glsl`.
//!
//! The structure is decided here, in f64, by the same tests the model makes (`model::tm2`,
//! `model::tm6`: the conductor ends the stack, `INDEX_MATCHED`, `REFLECTS_NOTHING`, η ≥ 1,
//! α = 0, depth > 0), so a specialized pipeline takes the branches the CPU oracle takes; the
//! generic pipeline makes the same tests in f32 at run time (`glsl/include/lib/tm_common.glsl`).

use crate::model::{LayerParams, INDEX_MATCHED, IOR_AIR, REFLECTS_NOTHING};
use crate::variant::{Mode, Model, ShadeSpec, VariantKey, MAX_LAYERS_LIMIT};

/// Why a material cannot have a per-material pipeline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecializeError {
    #[error("a per-material pipeline (mode={mode}) needs 1..={MAX_LAYERS_LIMIT} layers; the stack has {count}")]
    LayerCount { mode: Mode, count: usize },
    #[error("layer {layer} is a conductor above another layer; a conductor ends the stack")]
    ConductorAbove { layer: usize },
    #[error("mode=baked holds at most {max} lobes; the stack has {count} (use mode=specialized)")]
    TooManyLobes { count: usize, max: usize },
    #[error("the stack's layers vary through {count} different coverage maps; mode=specialized routes each pixel to its class's pipeline by an {bits}-bit stencil, one bit per map: shade it under mode=generic")]
    TooManyCoverages { count: usize, bits: usize },
    #[error("layer {layer} is a diffuse base; mode=specialized-values pipelines hold no diffuse albedo among their constants: shade it under mode=specialized, generic or baked")]
    DiffuseBase { layer: usize },
}

/// A material's structure: what a specialized pipeline knows about it. Masks hold bit `i` for
/// layer `i`, top first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Structure {
    pub layer_count: u32,
    /// α = 0: the interface reflects its Fresnel reflectance, no FGD lookup.
    pub smooth_mask: u32,
    /// The last layer is a conductor.
    pub conductor_base: bool,
    /// 6-flux layers with a medium (depth > 0); 0 under the 2-flux model.
    pub medium_mask: u32,
    /// Dielectric interfaces with η_ij ≥ 1 (TIR only for light going up).
    pub denser_mask: u32,
    /// Index-matched interfaces: the model skips them.
    pub matched_mask: u32,
    /// Interfaces that refract but reflect nothing.
    pub clear_mask: u32,
    /// A varying stack's class (`render::classes`): the layers whose maps carry a value
    /// across one of the tests above, which the pass makes at run time; their bits in the
    /// other masks are 0.
    pub dynamic_mask: u32,
    /// A varying stack's class: the material layer of each of its layers, 4 bits per layer
    /// (layer i in bits 4i…4i + 3); 0 for a uniform stack.
    pub slots: u64,
}

/// How far a layer's maps let the values the structure depends on range over the surface:
/// (lowest, highest) where a map varies them (`SurfaceMaps::range`), `None` where constant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    /// The mean of the layer's RGB η.
    pub ior: Option<(f64, f64)>,
    pub roughness: Option<(f64, f64)>,
    pub depth: Option<(f64, f64)>,
}

/// How far a mapped value must stay from a test's threshold for the test to be a constant of
/// the pipeline: the GPU reads the maps in f32 and filters them, the host decides in f64.
const MAPPED_MARGIN: f64 = 1e-6;

/// The test `x > 0` over `[lo, hi]`: its one value there, or `None`.
fn positive((lo, hi): (f64, f64)) -> Option<bool> {
    match (lo > 0.0, hi <= 0.0) {
        (true, _) => Some(true),
        (_, true) => Some(false),
        _ => None,
    }
}

/// An interface's tests over the interval `[lo, hi]` of its relative η: index-matched, clear
/// (reflects nothing), denser below; each a constant, or `None` where the interval reaches
/// its threshold (within `margin`). An index-matched interface is neither of the others.
fn interface_tests(
    (lo, hi): (f64, f64),
    margin: f64,
) -> (Option<bool>, Option<bool>, Option<bool>) {
    // |η − 1| < t over [lo, hi].
    let near = |t: f64| {
        let far = (lo - 1.0).abs().max((hi - 1.0).abs());
        let nearest = if lo <= 1.0 && hi >= 1.0 {
            0.0
        } else {
            (lo - 1.0).abs().min((hi - 1.0).abs())
        };
        if far < t - margin {
            Some(true)
        } else if nearest >= t + margin {
            Some(false)
        } else {
            None
        }
    };
    let matched = near(INDEX_MATCHED);
    if matched == Some(true) {
        return (matched, Some(false), Some(false));
    }
    let denser = below(lo, hi, 1.0, margin).map(|b| !b);
    (matched, near(REFLECTS_NOTHING), denser)
}

/// A test `x < t` (or `x ≥ t` as its negation) over the interval `[lo, hi]`: its one value
/// there, or `None` where the interval reaches the threshold (within `margin`).
fn below(lo: f64, hi: f64, t: f64, margin: f64) -> Option<bool> {
    if hi < t - margin {
        Some(true)
    } else if lo >= t + margin {
        Some(false)
    } else if margin == 0.0 && lo == hi {
        Some(lo < t)
    } else {
        None
    }
}

fn mean(v: [f64; 3]) -> f64 {
    (v[0] + v[1] + v[2]) / 3.0
}

impl Structure {
    /// The structure of `layers` (top first) under `model`.
    pub fn of(model: Model, layers: &[LayerParams]) -> Result<Self, SpecializeError> {
        if layers.is_empty() || layers.len() > MAX_LAYERS_LIMIT as usize {
            return Err(SpecializeError::LayerCount {
                mode: Mode::Specialized,
                count: layers.len(),
            });
        }
        let mut s = Self::walk(model, layers.iter().map(|l| (l, Spread::default())))?;
        s.slots = 0;
        Ok(s)
    }

    /// The structure of one class of a varying stack's pixels (`render::classes`): the
    /// layers `present` (material indices, top first; possibly none) of `layers`, each
    /// with the spread its maps give it (`spreads`, per material layer). A test that a map
    /// carries across its threshold is left to run time (`dynamic_mask`).
    pub fn of_class(
        model: Model,
        layers: &[LayerParams],
        spreads: &[Spread],
        present: &[usize],
    ) -> Result<Self, SpecializeError> {
        let mut s = Self::walk(model, present.iter().map(|&m| (&layers[m], spreads[m])))?;
        s.slots = present
            .iter()
            .enumerate()
            .fold(0, |acc, (i, &m)| acc | (m as u64) << (4 * i));
        Ok(s)
    }

    /// The structure of `layers` as the models' tests see them (`Structure::of`), each
    /// test over the interval its layer's spread gives: a constant where the interval lies
    /// on one side of the threshold, else a bit of `dynamic_mask`.
    fn walk<'a>(
        model: Model,
        layers: impl ExactSizeIterator<Item = (&'a LayerParams, Spread)>,
    ) -> Result<Self, SpecializeError> {
        let count = layers.len();
        let mut s = Self {
            layer_count: count as u32,
            ..Self::default()
        };
        // The η of the medium above, as an interval (mapped when some map varies it).
        let (mut above, mut above_mapped) = ((IOR_AIR, IOR_AIR), false);
        for (i, (layer, spread)) in layers.enumerate() {
            let bit = 1u32 << i;
            if layer.is_diffuse() {
                // The base, which ends the stack: the pass's DIFFUSE_BASE code emits its lobe
                // (the baked table's diffuse row under mode=baked).
                continue;
            }
            // α = 0 exactly (a map's α is never negative).
            let roughness = spread
                .roughness
                .unwrap_or((layer.roughness, layer.roughness));
            let smooth = positive(roughness).map(|rough| !rough);
            if layer.is_conductor() {
                if i + 1 != count {
                    return Err(SpecializeError::ConductorAbove { layer: i + 1 });
                }
                s.conductor_base = true;
                s.settle(
                    bit,
                    [smooth, Some(false), Some(false), Some(false), Some(false)],
                );
                continue;
            }
            let medium = if model == Model::Tm6 {
                positive(spread.depth.unwrap_or((layer.depth, layer.depth)))
            } else {
                Some(false)
            };
            let eta_mean = mean(layer.ior);
            let (e_lo, e_hi) = spread.ior.unwrap_or((eta_mean, eta_mean));
            let margin = if above_mapped || spread.ior.is_some() {
                MAPPED_MARGIN
            } else {
                0.0
            };
            let (matched, clear, denser) =
                interface_tests((e_lo / above.1, e_hi / above.0), margin);
            s.settle(bit, [smooth, medium, matched, clear, denser]);
            match matched {
                // No interface: the medium above stays.
                Some(true) => {}
                Some(false) => {
                    above = (e_lo, e_hi);
                    above_mapped = spread.ior.is_some();
                }
                // Either: the medium above is one or the other.
                None => {
                    above = (above.0.min(e_lo), above.1.max(e_hi));
                    above_mapped = true;
                }
            }
        }
        Ok(s)
    }
}

/// Errs unless a generic pipeline of `variant` holds `layers`: 1..=`max_layers` of them.
pub fn check_generic_fit(variant: VariantKey, layers: &[LayerParams]) -> crate::error::Result<()> {
    let max_layers = variant.max_layers as usize;
    if layers.is_empty() || layers.len() > max_layers {
        return Err(crate::error::Error::Unsupported(format!(
            "the stack has {} layer(s); variant {variant} holds 1..={max_layers}",
            layers.len()
        )));
    }
    Ok(())
}

/// The lobes of a baked material (`render::baked`): how many, which are lit around the view,
/// and the view-cosine samples per lobe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BakedShape {
    pub lobe_count: u32,
    pub retro_mask: u32,
    pub size: u32,
}

/// Most lobes a baked table holds (one bit each in `RETRO_MASK`).
pub const MAX_BAKED_LOBES: usize = 32;

/// The specialization constants of `variant`'s shading passes for `layers`. Under
/// `mode=generic` the material does not matter (the variant's own constants); `baked` needs
/// the baked table's shape.
pub fn shade_spec(
    variant: VariantKey,
    layers: &[LayerParams],
    baked: Option<BakedShape>,
) -> Result<ShadeSpec, SpecializeError> {
    let mut spec = variant.spec();
    if variant.mode == Mode::Generic {
        return Ok(spec);
    }
    Structure::for_variant(variant, layers)?.specialize(&mut spec);
    if variant.mode == Mode::SpecializedValues {
        specialize_values(layers, &mut spec);
    }
    if let Some(b) = baked {
        b.specialize(&mut spec);
    }
    Ok(spec)
}

impl Structure {
    /// The structure of `layers` for a per-material pipeline of `variant`, whose mode a
    /// layer-count error names.
    /// `mode=specialized-values` refuses a diffuse base: its constants hold no albedo
    /// (`variant::LAYER_VALUES`). `specialized` emits the base's lobe with the pass's
    /// DIFFUSE_BASE code; `baked` reads it from its table.
    pub fn for_variant(
        variant: VariantKey,
        layers: &[LayerParams],
    ) -> Result<Self, SpecializeError> {
        if variant.mode == Mode::SpecializedValues {
            if let Some(i) = layers.iter().position(LayerParams::is_diffuse) {
                return Err(SpecializeError::DiffuseBase { layer: i + 1 });
            }
        }
        Self::of(variant.model, layers).map_err(|e| match e {
            SpecializeError::LayerCount { count, .. } => SpecializeError::LayerCount {
                mode: variant.mode,
                count,
            },
            other => other,
        })
    }

    /// Sets layer `bit`'s masks from its tests (smooth, medium, index-matched, clear, denser),
    /// or its `dynamic_mask` bit where one of them is not a constant.
    fn settle(&mut self, bit: u32, tests: [Option<bool>; 5]) {
        if tests.iter().any(Option::is_none) {
            self.dynamic_mask |= bit;
            return;
        }
        let masks = [
            &mut self.smooth_mask,
            &mut self.medium_mask,
            &mut self.matched_mask,
            &mut self.clear_mask,
            &mut self.denser_mask,
        ];
        for (mask, test) in masks.into_iter().zip(tests) {
            if test == Some(true) {
                *mask |= bit;
            }
        }
    }

    /// Tells `spec` this structure; the arrays get the material's own size (`max_layers`
    /// does not matter).
    pub fn specialize(&self, spec: &mut ShadeSpec) {
        // A class whose coverage leaves no layer still declares one-element arrays.
        spec.max_layers = self.layer_count.max(1);
        spec.layer_count = self.layer_count;
        spec.dynamic_mask = self.dynamic_mask;
        spec.layer_slots_lo = self.slots as u32;
        spec.layer_slots_hi = (self.slots >> 32) as u32;
        spec.smooth_mask = self.smooth_mask;
        spec.conductor_base = u32::from(self.conductor_base);
        spec.medium_mask = self.medium_mask;
        spec.denser_mask = self.denser_mask;
        spec.matched_mask = self.matched_mask;
        spec.clear_mask = self.clear_mask;
    }
}

impl BakedShape {
    /// Tells `spec` the baked table's shape.
    pub fn specialize(&self, spec: &mut ShadeSpec) {
        spec.lobe_count = self.lobe_count;
        spec.retro_mask = self.retro_mask;
        spec.baked_size = self.size;
    }
}

/// Tells `spec` the values of `layers` (`mode=specialized-values`).
pub fn specialize_values(layers: &[LayerParams], spec: &mut ShadeSpec) {
    for (dst, l) in spec.values.iter_mut().zip(layers) {
        let f = |v: f64| v as f32;
        *dst = [
            f(l.ior[0]),
            f(l.ior[1]),
            f(l.ior[2]),
            f(l.kappa[0]),
            f(l.kappa[1]),
            f(l.kappa[2]),
            f(l.sigma_s[0]),
            f(l.sigma_s[1]),
            f(l.sigma_s[2]),
            f(l.sigma_a[0]),
            f(l.sigma_a[1]),
            f(l.sigma_a[2]),
            f(l.roughness),
            f(l.depth),
            f(l.g),
            0.0,
        ];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layer(ior: f64, kappa: f64, roughness: f64, depth: f64) -> LayerParams {
        LayerParams::conductor([ior; 3], [kappa; 3], roughness)
            .with_medium(depth, [1.0; 3], [0.1; 3], 0.3)
    }

    #[test]
    fn structure_follows_the_models_tests() {
        let stack = [
            layer(1.5, 0.0, 0.0, 0.5),
            layer(1.5, 0.0, 0.1, 0.0),
            layer(1.2, 0.0, 0.2, 0.3),
            layer(1.2005, 0.0, 0.2, 0.0),
            layer(0.2, 3.0, 0.3, 0.0),
        ];
        let s = Structure::of(Model::Tm6, &stack).unwrap();
        assert_eq!(s.layer_count, 5);
        assert_eq!(s.smooth_mask, 0b00001);
        assert!(s.conductor_base);
        assert_eq!(s.medium_mask, 0b00101);
        assert_eq!(s.matched_mask, 0b00010);
        assert_eq!(s.clear_mask, 0b01000);
        // 1.5 over air: denser; 1.2 under 1.5: lighter; 1.2005 under 1.2: denser.
        assert_eq!(s.denser_mask, 0b01001);
        let tm2 = Structure::of(Model::Tm2, &stack).unwrap();
        assert_eq!(tm2.medium_mask, 0, "the 2-flux model has no media");
    }

    #[test]
    fn generic_ignores_the_material_and_specialized_ignores_max_layers() {
        let stack = [layer(1.5, 0.0, 0.1, 0.0), layer(0.2, 3.0, 0.3, 0.0)];
        let generic: VariantKey = "model=tm2,max_layers=8".parse().unwrap();
        assert_eq!(
            shade_spec(generic, &stack, None).unwrap(),
            generic.spec(),
            "generic"
        );
        let a = shade_spec(
            "model=tm2,max_layers=4,mode=specialized".parse().unwrap(),
            &stack,
            None,
        )
        .unwrap();
        let b = shade_spec(
            "model=tm2,max_layers=16,mode=specialized".parse().unwrap(),
            &stack,
            None,
        )
        .unwrap();
        assert_eq!(a, b);
        assert_eq!((a.max_layers, a.layer_count, a.conductor_base), (2, 2, 1));
        assert!(a.values.iter().flatten().all(|&v| v == 0.0));
        let v = shade_spec(
            "model=tm2,mode=specialized-values".parse().unwrap(),
            &stack,
            None,
        )
        .unwrap();
        assert_eq!(v.values[1][3], 3.0, "κ of the conductor");
        assert_eq!(v.values[0][12], 0.1, "α of the varnish");
    }

    #[test]
    fn errors_name_the_problem() {
        let e = Structure::of(
            Model::Tm2,
            &[layer(0.2, 3.0, 0.3, 0.0), layer(1.5, 0.0, 0.1, 0.0)],
        )
        .unwrap_err();
        assert_eq!(e, SpecializeError::ConductorAbove { layer: 1 });
        let e = shade_spec("mode=specialized".parse().unwrap(), &[], None).unwrap_err();
        assert!(e.to_string().contains("mode=specialized"), "{e}");
    }
}
