//! What a shading pass is, in one value: a [`PassKey`] built once from the variant, the stack
//! and the lighting, from which the pass's specialization constants are filled; and the
//! [`PassCache`] through which every caller that shades several cases finds a pass for a key,
//! or prepares one.
//!
//! Two cases share a pass exactly when their keys are equal: under `mode=generic` every stack
//! that fits (a key holds no layers), under `specialized` every stack of one structure, under
//! `specialized-values` and `baked` one stack. The spatial variation of a stack (the fields its
//! maps vary), a diffuse base and analytic lights are part of the key too, because each of
//! them compiles code in or out.

use crate::error::{Error, Result};
use crate::material::Surface;
use crate::model::transport::top_reflects;
use crate::model::{ends_diffuse, ends_transmissive, LayerParams};
use crate::shader::specialize::{
    check_generic_fit, specialize_values, BakedShape, SpecializeError, Structure,
};

use crate::variant::{
    Fgd, Mode, Model, ShadeSpec, Transport, VariantKey, FGD_PAST_EDGE_SHIFT, LAMP_VALUES,
};

use super::classes::{Class, Routing};
use super::forward::ForwardPass;
use super::lights::Lighting;
use super::renderer::Renderer;

/// What a pass knows of the material it shades.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKey {
    /// `mode=generic`: any stack that fits `max_layers`, read at run time.
    Any,
    /// `mode=specialized`: every stack of this structure.
    Structure(Structure),
    /// `mode=specialized`, a varying stack: its pixels routed to one pipeline per class of
    /// structure (`render::classes`).
    Classes(Routing),
    /// `mode=specialized-values` and `baked`: this stack.
    Values {
        structure: Structure,
        layers: Vec<LayerParams>,
    },
    /// A reference pass (`render::reference`): this stack's exact lobes, integrated by Monte
    /// Carlo.
    Reference(Vec<LayerParams>),
    /// A reference pass that evaluates each pixel's lobes with its variant's shader library
    /// (any stack that fits, maps included) and integrates them by Monte Carlo
    /// (`render::reference::render_evaluated`).
    Evaluated,
}

/// One shading pass's identity.
#[derive(Clone, Debug, PartialEq)]
pub struct PassKey {
    pub variant: VariantKey,
    pub material: MaterialKey,
    /// `SURFACE_MAPS`: 0 for a uniform stack, else the fields its maps vary
    /// (`SurfaceMaps::spec_bits`).
    pub surface: u32,
    /// The stack ends in a diffuse base (`DIFFUSE_BASE`).
    pub diffuse: bool,
    /// The stack ends in a dielectric and transmits (`TRANSMITS`).
    pub transmits: bool,
    /// The scene has analytic lights (`LIGHTS`).
    pub lights: bool,
    /// Some FGD lookup of the stack may fall past the 4-D table's η, κ ≤ 4
    /// ([`past_fgd_edge`]): the pass holds the code that carries FGD on from the table's edge
    /// (`FGD_PAST_EDGE`); without it that code folds away.
    pub fgd_past_edge: bool,
    /// `ibl=lamps`: the environment's lamps (`tables::lamps::lamp_values`), which the
    /// renderer sets when it builds the pass; zero otherwise.
    pub lamps: [f32; LAMP_VALUES],
}

impl PassKey {
    /// The pass that shades `layers` (top first; with the maps of `surface` when the stack
    /// varies over the surface) in `variant` under `lighting`. Refuses what no pass of the
    /// variant can shade: a per-material mode of the `ggx` baseline or of a varying stack, a
    /// stack a per-material pipeline cannot hold, and a baked table of `transport=corrected`
    /// lobes under lights where the top's lobe is shaded with its Fresnel factor (the table
    /// holds each lobe's weight and roughness, not that lobe's interface and albedo).
    pub fn new(
        variant: VariantKey,
        layers: &[LayerParams],
        surface: Option<&Surface>,
        lighting: &Lighting,
    ) -> Result<Self> {
        if variant.mode == Mode::Baked
            && variant.transport == Transport::Corrected
            && !lighting.lights.is_empty()
            && top_reflects(layers, variant.model).is_some()
        {
            return Err(Error::Unsupported(format!(
                "variant {variant}: under lights, transport=corrected shades the top \
                 interface's lobe with its Fresnel factor, which a baked table does not hold \
                 (it keeps each lobe's weight and roughness); use mode=specialized, or \
                 mode=baked without lights"
            )));
        }
        let material = if variant.mode.per_material() {
            if variant.model == Model::Ggx {
                return Err(Error::Unsupported(format!(
                    "variant {variant}: model=ggx is the generic baseline; it has no \
                     per-material mode (use mode=generic)"
                )));
            }
            if let Some(surface) = surface {
                if variant.mode != Mode::Specialized {
                    return Err(Error::Unsupported(format!(
                        "variant {variant}: this stack varies over the surface (textures, \
                         patterns or coverage); it shades under mode=generic, which reads its \
                         maps per pixel, or mode=specialized, whose pipelines shade each \
                         pixel's structure"
                    )));
                }
                let routing = Routing::plan(variant.model, layers, &surface.maps)
                    .map_err(|e| specialize(variant, e))?;
                return Ok(Self {
                    variant,
                    material: MaterialKey::Classes(routing),
                    surface: surface.maps.spec_bits(),
                    diffuse: ends_diffuse(layers),
                    transmits: ends_transmissive(layers),
                    lights: !lighting.lights.is_empty(),
                    fgd_past_edge: reads_past_fgd_edge(variant, layers, Some(surface)),
                    lamps: [0.0; LAMP_VALUES],
                });
            }
            let structure =
                Structure::for_variant(variant, layers).map_err(|e| specialize(variant, e))?;
            if variant.mode == Mode::Specialized {
                MaterialKey::Structure(structure)
            } else {
                MaterialKey::Values {
                    structure,
                    layers: layers.to_vec(),
                }
            }
        } else {
            MaterialKey::Any
        };
        Ok(Self {
            variant,
            material,
            surface: surface.map_or(0, |s| s.maps.spec_bits()),
            diffuse: ends_diffuse(layers),
            transmits: ends_transmissive(layers),
            lights: !lighting.lights.is_empty(),
            fgd_past_edge: reads_past_fgd_edge(variant, layers, surface),
            lamps: [0.0; LAMP_VALUES],
        })
    }

    /// The key of a uniform stack's pass.
    pub fn uniform(
        variant: VariantKey,
        layers: &[LayerParams],
        lighting: &Lighting,
    ) -> Result<Self> {
        Self::new(variant, layers, None, lighting)
    }

    /// The key of the reference pass of the uniform stack `layers` in `model`.
    pub fn reference(model: Model, layers: &[LayerParams], lighting: &Lighting) -> Self {
        Self {
            variant: VariantKey {
                model,
                mode: Mode::Baked,
                ..VariantKey::default()
            },
            material: MaterialKey::Reference(layers.to_vec()),
            surface: 0,
            diffuse: ends_diffuse(layers),
            transmits: ends_transmissive(layers),
            lights: !lighting.lights.is_empty(),
            fgd_past_edge: false,
            lamps: [0.0; LAMP_VALUES],
        }
    }

    /// The key of the reference pass that evaluates `variant`'s lobes of `layers` (with the
    /// maps of `surface`) per pixel: `variant` is the lobes' (`render::reference::
    /// evaluated_variant`).
    pub fn evaluated_reference(
        variant: VariantKey,
        layers: &[LayerParams],
        surface: Option<&Surface>,
        lighting: &Lighting,
    ) -> Self {
        Self {
            variant,
            material: MaterialKey::Evaluated,
            surface: surface.map_or(0, |s| s.maps.spec_bits()),
            diffuse: ends_diffuse(layers),
            transmits: ends_transmissive(layers),
            lights: !lighting.lights.is_empty(),
            fgd_past_edge: reads_past_fgd_edge(variant, layers, surface),
            lamps: [0.0; LAMP_VALUES],
        }
    }

    /// Whether this is a reference pass (`LAMINA_REFERENCE`).
    pub fn is_reference(&self) -> bool {
        matches!(
            self.material,
            MaterialKey::Reference(_) | MaterialKey::Evaluated
        )
    }

    /// The stack a per-material pass is built for (`None` under `mode=generic` and
    /// `specialized`).
    pub fn layers(&self) -> Option<&[LayerParams]> {
        match &self.material {
            MaterialKey::Values { layers, .. } | MaterialKey::Reference(layers) => Some(layers),
            MaterialKey::Any
            | MaterialKey::Structure(_)
            | MaterialKey::Classes(_)
            | MaterialKey::Evaluated => None,
        }
    }

    /// The pass's specialization constants, with a baked table's shape (`mode=baked` and the
    /// reference pass).
    pub fn spec(&self, baked: Option<BakedShape>) -> ShadeSpec {
        let mut spec = self.variant.spec();
        match &self.material {
            MaterialKey::Any
            | MaterialKey::Reference(_)
            | MaterialKey::Classes(_)
            | MaterialKey::Evaluated => {}
            MaterialKey::Structure(structure) => structure.specialize(&mut spec),
            MaterialKey::Values { structure, layers } => {
                structure.specialize(&mut spec);
                if self.variant.mode == Mode::SpecializedValues {
                    specialize_values(layers, &mut spec);
                }
            }
        }
        if let Some(shape) = baked {
            shape.specialize(&mut spec);
        }
        spec.surface_maps = self.surface;
        spec.diffuse_base = u32::from(self.diffuse);
        spec.transmits = u32::from(self.transmits);
        spec.lights = u32::from(self.lights);
        spec.fgd |= u32::from(self.fgd_past_edge) << FGD_PAST_EDGE_SHIFT;
        spec.lamps = self.lamps;
        spec
    }

    /// Errs unless a routed key's classes are `planned` (`Routing::plan` of the stack and
    /// the maps a frame renders; nothing to check for the other keys).
    pub fn routes(&self, planned: &Routing) -> Result<()> {
        match &self.material {
            MaterialKey::Classes(own) if own != planned => Err(Error::Unsupported(format!(
                "this pass ({}) was built for a varying stack whose pixels fall into other \
                 classes; prepare one for this stack",
                self.variant
            ))),
            _ => Ok(()),
        }
    }

    /// The specialization constants of class `class`'s pipeline (a routed key's).
    pub fn class_spec(&self, class: &Class) -> ShadeSpec {
        let mut spec = self.spec(None);
        class.structure.specialize(&mut spec);
        spec.diffuse_base = u32::from(class.diffuse);
        spec.slot_maps = class.slot_maps;
        spec
    }

    /// The specialization constants of the stencil mark of material layer `layer`'s
    /// coverage (a routed key's).
    pub fn mark_spec(&self, layer: usize) -> ShadeSpec {
        let mut spec = self.spec(None);
        spec.mark_layer = layer as u32;
        spec
    }

    /// Errs unless the pass of this key shades `layers` as its variant says: any stack that
    /// fits a generic pass, a stack of the same structure under `specialized`, the same stack
    /// under the other modes.
    pub fn admits(&self, layers: &[LayerParams]) -> Result<()> {
        // What ends the stack decides which lobe code the pass holds (DIFFUSE_BASE, TRANSMITS).
        let base = |diffuse: bool, transmits: bool| match (diffuse, transmits) {
            (true, _) => "ends in a diffuse base",
            (false, true) => "ends in a dielectric and transmits",
            (false, false) => "ends in a conductor",
        };
        let (diffuse, transmits) = (ends_diffuse(layers), ends_transmissive(layers));
        if (diffuse, transmits) != (self.diffuse, self.transmits) {
            return Err(Error::Unsupported(format!(
                "this pass ({}) was built for a stack that {} and this one {}; prepare a pass \
                 for this stack",
                self.variant,
                base(self.diffuse, self.transmits),
                base(diffuse, transmits)
            )));
        }
        if reads_past_fgd_edge(self.variant, layers, None) && !self.fgd_past_edge {
            return Err(Error::Unsupported(format!(
                "this pass ({}) was built for a stack whose FGD lookups stay within the 4-D \
                 table's η, κ ≤ {}, and this one reaches past it; prepare a pass for this stack",
                self.variant,
                crate::tables::fgd::KAPPA_MAX
            )));
        }
        let same = match &self.material {
            MaterialKey::Any | MaterialKey::Evaluated => {
                return check_generic_fit(self.variant, layers)
            }
            MaterialKey::Structure(own) => {
                Structure::of(self.variant.model, layers).ok().as_ref() == Some(own)
            }
            // The routing depends on the maps too, which the renderer checks
            // (`Renderer::check_pass`, by `PassKey::routes`).
            MaterialKey::Classes(own) => own
                .classes
                .iter()
                .all(|c| c.layers.iter().all(|&m| m < layers.len())),
            MaterialKey::Values { layers: own, .. } | MaterialKey::Reference(own) => {
                own.as_slice() == layers
            }
        };
        if same {
            Ok(())
        } else {
            Err(Error::Unsupported(format!(
                "this pass ({}) was built for another material; prepare one for this stack",
                self.variant
            )))
        }
    }
}

fn specialize(variant: VariantKey, e: SpecializeError) -> Error {
    Error::Unsupported(format!("variant {variant}: {e}"))
}

/// The passes prepared so far, by key: every caller that shades several cases (the bench, the
/// counter, the image errors, the contact sheet, the viewer) finds its pass here or prepares
/// it here, once.
#[derive(Default)]
pub struct PassCache {
    passes: Vec<ForwardPass>,
    /// At most this many passes are kept (the least recently used goes first); `None`: all.
    capacity: Option<usize>,
}

impl PassCache {
    pub fn new() -> Self {
        Self::default()
    }

    /// A cache that keeps the `capacity` passes used last (the viewer, whose every edit may
    /// name a new pass).
    pub fn bounded(capacity: usize) -> Self {
        Self {
            passes: Vec::new(),
            capacity: Some(capacity.max(1)),
        }
    }

    /// The pass of `key`, prepared on `renderer` the first time it is asked for.
    /// A pass that holds lamps other than the renderer's environment's (`ibl=lamps`, after
    /// `Renderer::set_environment`) is prepared again.
    pub fn get(&mut self, renderer: &mut Renderer<'_>, key: &PassKey) -> Result<&ForwardPass> {
        let lamps = renderer.lamps_of(key.variant);
        self.passes
            .retain(|p| !(requested(p, key) && p.key.lamps != lamps));
        match self.passes.iter().position(|p| requested(p, key)) {
            Some(i) => {
                let pass = self.passes.remove(i);
                self.passes.push(pass);
            }
            None => {
                let pass = renderer.prepare(key)?;
                if let Some(capacity) = self.capacity {
                    while self.passes.len() >= capacity {
                        self.passes.remove(0);
                    }
                }
                self.passes.push(pass);
            }
        }
        Ok(self.passes.last().expect("pushed above"))
    }

    /// The pass of `key`, if prepared and holding `renderer`'s lamps.
    pub fn find(&self, renderer: &Renderer<'_>, key: &PassKey) -> Option<&ForwardPass> {
        let lamps = renderer.lamps_of(key.variant);
        self.passes
            .iter()
            .find(|p| requested(p, key) && p.key.lamps == lamps)
    }
}

/// Whether some FGD lookup of `layers` (with the maps of `surface`) may fall past the 4-D
/// table's domain, η and κ in [0, 4] (`tables::fgd::beyond_the_table`): an interface whose
/// relative η (either way for a dielectric, from above for a conductor) or relative κ lies
/// past it in some channel, each layer against the one above it (air at the top), or maps that vary η or κ (`SurfaceMaps::spec_bits`' bits 0
/// and 1), whose values the host does not bound.
pub fn past_fgd_edge(layers: &[LayerParams], surface: Option<&Surface>) -> bool {
    use crate::tables::fgd::{ETA_MAX, KAPPA_MAX};
    if surface.is_some_and(|s| s.maps.spec_bits() & 0b11 != 0) {
        return true;
    }
    let mut above = [crate::model::IOR_AIR; 3];
    for layer in layers.iter().filter(|l| !l.is_diffuse()) {
        let past = (0..3).any(|c| {
            let (a, b) = (above[c], layer.ior[c]);
            // A conductor is looked up from above only; a dielectric both ways.
            let upward = !layer.is_conductor() && a > ETA_MAX * b;
            b > ETA_MAX * a || upward || layer.kappa[c] > KAPPA_MAX * a
        });
        if past {
            return true;
        }
        above = layer.ior;
    }
    false
}

/// Whether a pass of `variant` must hold the code past the 4-D FGD tables' edge for `layers`:
/// it reads one of them (`fgd=4d`, `resampled4d`) and the stack reaches past it
/// ([`past_fgd_edge`]).
fn reads_past_fgd_edge(
    variant: VariantKey,
    layers: &[LayerParams],
    surface: Option<&Surface>,
) -> bool {
    matches!(variant.fgd, Fgd::Full4d | Fgd::Resampled4d) && past_fgd_edge(layers, surface)
}

/// Whether `pass` was prepared for `key`: the same key but for the lamps, which the renderer
/// sets.
fn requested(pass: &ForwardPass, key: &PassKey) -> bool {
    pass.key.variant == key.variant
        && PassKey {
            lamps: key.lamps,
            ..pass.key.clone()
        } == *key
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lights::{Light, LightKind};

    #[test]
    fn a_baked_table_of_corrected_lobes_under_lights_is_refused_by_name() {
        let sun = Lighting {
            environment: 1.0,
            lights: vec![Light {
                kind: LightKind::Directional {
                    direction: [0.0, 1.0, 0.0],
                    angular_radius: 0.0,
                },
                color: [1.0; 3],
                intensity: 1.0,
            }],
        };
        let varnished = crate::material::Stack::resolve("varnished-gold")
            .unwrap()
            .params();
        let gold = crate::material::Stack::resolve("gold").unwrap().params();
        let key = |text: &str| -> VariantKey { text.parse().unwrap() };
        let baked = key("model=tm2,mode=baked,transport=corrected");
        let error = match PassKey::uniform(baked, &varnished, &sun) {
            Ok(_) => panic!("a baked corrected pass under lights was not refused"),
            Err(e) => e.to_string(),
        };
        assert!(
            error.contains("mode=baked") && error.contains("Fresnel"),
            "{error}"
        );
        // Without lights, under the paper's transport, or with no dielectric top: shaded.
        assert!(PassKey::uniform(baked, &varnished, &Lighting::default()).is_ok());
        assert!(PassKey::uniform(key("model=tm2,mode=baked"), &varnished, &sun).is_ok());
        assert!(PassKey::uniform(baked, &gold, &sun).is_ok());
    }

    #[test]
    fn only_stacks_past_the_4d_fgd_tables_edge_hold_its_code() {
        let preset = |name: &str| crate::material::Stack::resolve(name).unwrap().params();
        // Gold's η 0.14 is a conductor's, looked up from above only; its κ ≤ 4.
        for name in ["gold", "varnished-gold", "glazed-ceramic", "amber-glass"] {
            assert!(!past_fgd_edge(&preset(name), None), "{name}");
        }
        // Aluminium's κ 9.2; under a coat of 1.5, 6.2: past either way.
        assert!(past_fgd_edge(&preset("aluminium"), None));
        assert!(past_fgd_edge(&preset("absorbing-film"), None));
        // A dielectric of η 4.5 under air; one of 0.45 under 2 (4.4 going up), not 2 alone.
        assert!(past_fgd_edge(&[LayerParams::dielectric(4.5, 0.2)], None));
        let two = LayerParams::dielectric(2.0, 0.2);
        assert!(past_fgd_edge(
            &[two, LayerParams::dielectric(0.45, 0.2)],
            None
        ));
        assert!(!past_fgd_edge(&[two], None));
        // A pass built without the code refuses a stack that needs it, by name.
        let variant: VariantKey = "model=tm2,fgd=4d".parse().unwrap();
        let lighting = Lighting::default();
        // Only the 4-D tables read past their edge.
        let karis: VariantKey = "model=tm2".parse().unwrap();
        let plain = PassKey::uniform(karis, &preset("gold"), &lighting).unwrap();
        assert!(plain.admits(&preset("aluminium")).is_ok());
        let gold = PassKey::uniform(variant, &preset("gold"), &lighting).unwrap();
        assert!(!gold.fgd_past_edge);
        let error = gold.admits(&preset("aluminium")).unwrap_err().to_string();
        assert!(error.contains("4-D table"), "{error}");
        let aluminium = PassKey::uniform(variant, &preset("aluminium"), &lighting).unwrap();
        assert!(aluminium.admits(&preset("gold")).is_ok());
        assert_eq!(aluminium.spec(None).fgd >> FGD_PAST_EDGE_SHIFT, 1);
        assert_eq!(gold.spec(None).fgd, variant.spec().fgd);
    }
}
