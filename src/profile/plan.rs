//! What one run measures: its cases, each a variant shading one material, and the plan they
//! run in — expanded once, with the `ggx` baselines the ratios divide by — which every
//! measurement of the run (the timing, the image errors, the instruction counts) takes its
//! cases from, in the same order.

use crate::error::Result;
use crate::material::Stack;
use crate::render::lights::Lighting;
use crate::render::PassKey;
use crate::variant::{Model, VariantKey};

/// One measured combination: a variant shading one material.
#[derive(Clone, Debug)]
pub struct Case {
    pub variant: VariantKey,
    pub stack: Stack,
}

impl Case {
    /// The key of the pass that shades this case under `lighting`.
    pub fn pass_key(&self, lighting: &Lighting) -> Result<PassKey> {
        PassKey::new(
            self.variant,
            &self.stack.params(),
            self.stack.surface.as_deref(),
            lighting,
        )
    }

    pub fn is_baseline(&self) -> bool {
        self.variant.model == Model::Ggx
    }
}

/// The cases one run measures, in run order: a `ggx` baseline on each material that lacks one
/// first, so every ratio divides by a baseline measured in the same run on the same stack;
/// then the cases as given.
#[derive(Clone, Debug)]
pub struct Plan {
    cases: Vec<Case>,
    added_baselines: usize,
}

impl Plan {
    pub fn new(given: Vec<Case>) -> Self {
        let mut cases: Vec<Case> = Vec::new();
        for case in &given {
            let has_baseline = given
                .iter()
                .chain(&cases)
                .any(|c| c.stack.name == case.stack.name && c.is_baseline());
            if !has_baseline {
                cases.push(Case {
                    variant: VariantKey {
                        max_layers: case.variant.max_layers,
                        ..baseline()
                    },
                    ..case.clone()
                });
            }
        }
        let added_baselines = cases.len();
        cases.extend(given);
        Self {
            cases,
            added_baselines,
        }
    }

    /// Every case, the added baselines first.
    pub fn cases(&self) -> &[Case] {
        &self.cases
    }

    /// How many baselines [`Plan::new`] added in front of the given cases.
    pub fn added_baselines(&self) -> usize {
        self.added_baselines
    }

    /// The index of the `ggx` case on the material of case `i`.
    pub fn baseline_of(&self, i: usize) -> usize {
        let material = &self.cases[i].stack.name;
        self.cases
            .iter()
            .position(|c| c.stack.name == *material && c.is_baseline())
            .expect("Plan::new gives every material a ggx case")
    }
}

/// The `ggx` baseline every run is divided by.
pub fn baseline() -> VariantKey {
    VariantKey {
        model: Model::Ggx,
        ..VariantKey::default()
    }
}
