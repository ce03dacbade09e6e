//! The variant a material is shaded with: the one rule that turns a material and an optional
//! variant key into a [`VariantKey`], shared by the commands (`render`, `eval`, `furnace`,
//! `bench`, `view`), the sweep files, the contact sheet and the instruction counter's worker.
//!
//! Axes the key leaves out take their defaults, except two that follow the material: the model
//! (a 6-flux stack is shaded by `tm6`) and `max_layers`, grown from its default to hold the
//! stack — never shrunk, so the static array size of a shallow stack stays the default's.

use crate::variant::{Model, VariantKey};

use super::{MaterialError, Stack};

/// The variant a key's missing axes come from: the defaults with `model`, and `max_layers`
/// grown to hold `layers` layers.
pub fn base_variant(model: Model, layers: usize) -> VariantKey {
    let defaults = VariantKey::default();
    VariantKey {
        model,
        max_layers: defaults.max_layers.max(layers as u32),
        ..defaults
    }
}

/// Loads a material (a preset name or a file, [`Stack::resolve`]) and the variant `key` names
/// for it ([`Stack::variant`]).
pub fn resolve_with_variant(
    material: &str,
    key: Option<&str>,
) -> Result<(Stack, VariantKey), MaterialError> {
    let stack = Stack::resolve(material)?;
    let variant = stack.variant(key)?;
    Ok((stack, variant))
}

impl Stack {
    /// [`base_variant`] for this stack's model and depth.
    pub fn base_variant(&self) -> VariantKey {
        base_variant(self.model, self.layers.len())
    }

    /// The variant `key` names over [`Stack::base_variant`] (the base itself for `None`),
    /// checked to hold the stack ([`Stack::check_fits`]: a key may set `max_layers` lower;
    /// a per-material pipeline has the stack's own array size, whatever `max_layers` says).
    pub fn variant(&self, key: Option<&str>) -> Result<VariantKey, MaterialError> {
        let base = self.base_variant();
        let variant = match key {
            Some(k) => VariantKey::parse_over(k, base)?,
            None => base,
        };
        if !variant.mode.per_material() {
            self.check_fits(variant.max_layers)?;
        }
        Ok(variant)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_model_and_max_layers_follow_the_stack() {
        let (stack, variant) = resolve_with_variant("five-layers", None).unwrap();
        assert_eq!(variant.model, stack.model);
        assert_eq!(variant.max_layers, 5);
        assert_eq!(base_variant(Model::Tm6, 1).max_layers, 4, "never shrunk");
        let v = stack.variant(Some("fp16=on,max_layers=8")).unwrap();
        assert_eq!((v.fp16, v.max_layers, v.model), (true, 8, stack.model));
        let e = stack.variant(Some("max_layers=4")).unwrap_err().to_string();
        assert!(e.contains("5 layers") && e.contains("max_layers=4"), "{e}");
        let v = stack
            .variant(Some("max_layers=4,mode=specialized"))
            .unwrap();
        assert_eq!(v.max_layers, 4, "kept as given, and irrelevant");
    }
}
