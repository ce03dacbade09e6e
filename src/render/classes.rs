//! A varying stack under `mode=specialized`: its pixels grouped into classes by the layers
//! their coverage leaves, each class shaded by a pipeline specialized for that structure
//! which reads its layers' varying values from their maps.
//!
//! The forward pass routes pixels with an 8-bit stencil. One draw per coverage map that
//! differs over the surface (a *mark*, `classify.frag.glsl`) sets that map's bit wherever it
//! holds its layer, by the test the generic pass makes (`tm_covered`); then each class's
//! pipeline draws the mesh with the stencil test "the marked bits equal mine", so it shades
//! exactly its own pixels and the hardware skips the others before shading (early fragment
//! tests). This is the material-classification idea of UE5's Nanite (each material's pass
//! tested against a per-pixel material id, there in the depth buffer) on a forward pass.
//!
//! The classes are the combinations of coverage that occur: over the maps' texels when every
//! coverage map is read in the same coordinates (a pixel reads the same texel of each), else
//! every combination. Layers whose coverage maps are equal share a bit; a coverage that holds
//! its layer everywhere or nowhere needs none. A map that varies a value a structural test
//! reads (η, α, depth) is ranged over its texels (`SurfaceMaps::range`), and the test is a
//! constant of the class's pipeline where the range stays on one side of its threshold, else
//! made at run time (`Structure::dynamic_mask`).

use std::collections::BTreeSet;

use crate::material::surface::{Field, SurfaceMaps};
use crate::model::LayerParams;
use crate::shader::specialize::{SpecializeError, Spread, Structure};
use crate::variant::Model;

/// Stencil bits: the most coverage maps a routed stack may vary through.
pub const STENCIL_BITS: usize = 8;

/// The pixels whose coverage leaves the same layers.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Class {
    /// The marked bits these pixels carry (the stencil's reference).
    pub bits: u32,
    /// The material layers present, top first (empty: the coverage leaves none).
    pub layers: Vec<usize>,
    /// The structure of those layers, which the class's pipeline is specialized for.
    pub structure: Structure,
    /// The class's stack ends in a diffuse base (its pipeline's `DIFFUSE_BASE`).
    pub diffuse: bool,
    /// Per layer of the class, a byte of the fields it reads from maps
    /// (`SurfaceMaps::mapped_fields`), four layers per word: the pass compiles those lookups
    /// only.
    pub slot_maps: [u32; 4],
}

/// How a varying stack's pixels reach their pipelines.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Routing {
    /// Per stencil bit (bit k at index k), the material layer whose coverage sets it.
    pub marks: Vec<usize>,
    /// Every class that occurs, the most layers first.
    pub classes: Vec<Class>,
    /// The stack's layers, whatever its coverage leaves (a pipeline that shades every class,
    /// the generic one, holds them all).
    pub layer_count: usize,
}

impl Routing {
    /// The routing of `layers` (the stack's constants) varying by `maps` under `model`.
    pub fn plan(
        model: Model,
        layers: &[LayerParams],
        maps: &SurfaceMaps,
    ) -> Result<Self, SpecializeError> {
        let (groups, presence) = coverage_groups(maps, layers.len());
        if groups.len() > STENCIL_BITS {
            return Err(SpecializeError::TooManyCoverages {
                count: groups.len(),
                bits: STENCIL_BITS,
            });
        }
        let spreads: Vec<Spread> = (0..layers.len())
            .map(|i| Spread {
                ior: maps.range(i, Field::Ior),
                roughness: maps.range(i, Field::Roughness),
                depth: maps.range(i, Field::Depth),
            })
            .collect();
        let mut classes = combinations(&groups)
            .into_iter()
            .map(|bits| {
                let present: Vec<usize> = presence
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| match p {
                        Presence::Always => true,
                        Presence::Never => false,
                        Presence::Marked(k) => bits & (1 << k) != 0,
                    })
                    .map(|(i, _)| i)
                    .collect();
                let structure = Structure::of_class(model, layers, &spreads, &present)?;
                let diffuse = present.last().is_some_and(|&m| layers[m].is_diffuse());
                let mut slot_maps = [0u32; 4];
                for (i, &m) in present.iter().enumerate() {
                    slot_maps[i / 4] |= maps.mapped_fields(m) << (8 * (i % 4));
                }
                Ok(Class {
                    bits,
                    layers: present,
                    structure,
                    diffuse,
                    slot_maps,
                })
            })
            .collect::<Result<Vec<_>, SpecializeError>>()?;
        classes.sort_by(|a, b| {
            b.layers
                .len()
                .cmp(&a.layers.len())
                .then(a.bits.cmp(&b.bits))
        });
        Ok(Self {
            marks: groups.into_iter().map(|g| g.layer).collect(),
            classes,
            layer_count: layers.len(),
        })
    }

    /// The stencil bits the classes compare: one per mark.
    pub fn compare_mask(&self) -> u32 {
        (1u32 << self.marks.len()) - 1
    }
}

/// Where a layer is, by its coverage.
enum Presence {
    /// Everywhere: no coverage, or one that holds it at every texel.
    Always,
    /// Nowhere: a coverage that holds it at no texel.
    Never,
    /// Where stencil bit k (its coverage map's group) is set.
    Marked(usize),
}

/// The coverage maps that differ over the surface, equal ones once: each marks a bit.
struct Group {
    /// The first layer with this map, whose coverage the mark tests.
    layer: usize,
    /// The map, texel by texel.
    held: Vec<bool>,
    /// Read in screen coordinates.
    screen: bool,
}

/// The groups of `maps`' varying coverages, and each of its `count` layers' presence.
fn coverage_groups(maps: &SurfaceMaps, count: usize) -> (Vec<Group>, Vec<Presence>) {
    let mut groups: Vec<Group> = Vec::new();
    let presence = (0..count)
        .map(|i| {
            let Some((held, screen)) = maps.coverage_texels(i) else {
                return Presence::Always;
            };
            if held.iter().all(|&h| h) {
                return Presence::Always;
            }
            if held.iter().all(|&h| !h) {
                return Presence::Never;
            }
            let found = groups
                .iter()
                .position(|g| g.held == held && g.screen == screen);
            Presence::Marked(found.unwrap_or_else(|| {
                groups.push(Group {
                    layer: i,
                    held,
                    screen,
                });
                groups.len() - 1
            }))
        })
        .collect();
    (groups, presence)
}

/// The combinations of the groups' bits that occur: over the texels when every map is read
/// in the same coordinates (a pixel then reads the same texel of each), else all of them.
fn combinations(groups: &[Group]) -> BTreeSet<u32> {
    if groups.is_empty() {
        return BTreeSet::from([0]);
    }
    if groups.windows(2).any(|w| w[0].screen != w[1].screen) {
        return (0..1u32 << groups.len()).collect();
    }
    (0..groups[0].held.len())
        .map(|t| {
            groups
                .iter()
                .enumerate()
                .filter(|(_, g)| g.held[t])
                .fold(0, |bits, (k, _)| bits | 1 << k)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::material::Stack;

    const GOLD: &str =
        "ior = [0.143, 0.374, 1.442]\nkappa = [3.983, 2.385, 1.603]\nroughness = 0.2\n";

    fn routing(model: &str, layers: &[&str]) -> Result<Routing, SpecializeError> {
        let mut text = format!("model = \"{model}\"\nmap_resolution = 8\n");
        for layer in layers {
            text += &format!("[[layer]]\n{layer}\n");
        }
        let stack = Stack::from_toml(&text, Path::new("test.toml")).unwrap();
        let surface = stack.surface.as_ref().expect("a varying stack");
        Routing::plan(stack.model, &stack.layers, &surface.maps)
    }

    fn checker(seed: u32) -> String {
        format!("coverage = {{ pattern = \"cells\", scale = 4, seed = {seed}, threshold = 0.5 }}\n")
    }

    #[test]
    fn equal_coverage_maps_share_a_bit_and_constant_ones_need_none() {
        let coat = "ior = [1.5, 1.5, 1.5]\nroughness = 0.1\n";
        let r = routing(
            "tm2",
            &[
                &format!("{coat}{}", checker(1)),
                &format!("{coat}{}", checker(1)),
                &format!("{coat}coverage = 1\n"),
                &format!("{coat}coverage = 0\n"),
                GOLD,
            ],
        )
        .unwrap();
        assert_eq!(r.marks, vec![0], "one map, marked by its first layer");
        assert_eq!(r.compare_mask(), 1);
        let layers: Vec<_> = r
            .classes
            .iter()
            .map(|c| (c.bits, c.layers.clone()))
            .collect();
        assert_eq!(layers, vec![(1, vec![0, 1, 2, 4]), (0, vec![2, 4])]);
        let full = &r.classes[0].structure;
        assert_eq!((full.layer_count, full.slots), (4, 0x4210));
        assert!(full.conductor_base);
        assert_eq!(full.dynamic_mask, 0);
    }

    #[test]
    fn classes_are_the_combinations_the_texels_hold() {
        let coat = "ior = [1.5, 1.5, 1.5]\nroughness = 0.1\n";
        let r = routing(
            "tm2",
            &[
                &format!("{coat}{}", checker(1)),
                &format!("{coat}{}", checker(2)),
                GOLD,
            ],
        )
        .unwrap();
        assert_eq!(r.marks, vec![0, 1]);
        // Two independent maps of 16 cells: every combination occurs.
        let bits: BTreeSet<u32> = r.classes.iter().map(|c| c.bits).collect();
        assert_eq!(bits, BTreeSet::from([0, 1, 2, 3]));
        // A map and its complement: only "one or the other".
        let r = routing(
            "tm2",
            &[
                &format!("{coat}{}", checker(1)),
                &format!(
                    "{coat}coverage = {{ pattern = \"cells\", scale = 4, seed = 1, threshold = 0.5, coords = \"screen\" }}\n"
                ),
                GOLD,
            ],
        )
        .unwrap();
        assert_eq!(
            r.classes.len(),
            4,
            "maps in different coordinates meet in every combination"
        );
    }

    #[test]
    fn a_class_may_hold_no_layer() {
        let r = routing("tm2", &[&format!("{GOLD}{}", checker(3))]).unwrap();
        let counts: Vec<u32> = r.classes.iter().map(|c| c.structure.layer_count).collect();
        assert_eq!(counts, vec![1, 0]);
    }

    #[test]
    fn a_map_across_a_threshold_leaves_its_test_to_run_time() {
        // α 0 (smooth) on half the cells, 0.3 on the others: the smooth test cannot be a
        // constant.
        let r = routing(
            "tm2",
            &[
                "ior = [1.5, 1.5, 1.5]\nroughness = { pattern = \"checker\", scale = 2, range = [0.0, 0.3] }\n",
                GOLD,
            ],
        )
        .unwrap();
        assert_eq!(r.classes.len(), 1);
        assert_eq!(r.classes[0].structure.dynamic_mask, 0b01);
        // Slot 0 reads α (bit 4) from a map; the gold reads nothing.
        assert_eq!(r.classes[0].slot_maps, [0x10, 0, 0, 0]);
        // η from 0.9 to 1.1 over a coat of 1.0: index-matched, lighter and denser all occur,
        // and the layer below it sees either medium above.
        let r = routing(
            "tm2",
            &[
                "ior = { pattern = \"noise\", scale = 2, range = [0.9, 1.1] }\nroughness = 0.1\n",
                "ior = [1.5, 1.5, 1.5]\nroughness = 0.1\n",
                GOLD,
            ],
        )
        .unwrap();
        let s = r.classes[0].structure;
        assert_eq!(s.dynamic_mask, 0b001);
        assert_eq!(
            s.denser_mask, 0b010,
            "1.5 under 0.9…1.1 is denser either way"
        );
        // A map that stays on one side is a constant: α in [0.1, 0.3], η in [1.4, 1.6].
        let r = routing(
            "tm2",
            &[
                "ior = { pattern = \"noise\", scale = 2, range = [1.4, 1.6] }\nroughness = { pattern = \"noise\", scale = 2, range = [0.1, 0.3] }\n",
                GOLD,
            ],
        )
        .unwrap();
        let s = r.classes[0].structure;
        assert_eq!((s.dynamic_mask, s.denser_mask, s.smooth_mask), (0, 0b01, 0));
    }

    #[test]
    fn more_coverage_maps_than_stencil_bits_are_refused_by_name() {
        let coat = "ior = [1.5, 1.5, 1.5]\nroughness = 0.1\n";
        let layers: Vec<String> = (0..9)
            .map(|seed| format!("{coat}{}", checker(seed + 10)))
            .chain([GOLD.to_string()])
            .collect();
        let refs: Vec<&str> = layers.iter().map(String::as_str).collect();
        let e = routing("tm2", &refs).unwrap_err();
        assert_eq!(e, SpecializeError::TooManyCoverages { count: 9, bits: 8 });
        assert!(e.to_string().contains("mode=generic"), "{e}");
    }
}
