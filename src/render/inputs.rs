//! What a shading pass samples, in one owner: the split-sum, TIR and FGD tables behind every
//! variant, bound with the layer stack as the shading set — set 0 of every entry point that
//! evaluates the model (`forward.frag`, `tm_eval.comp`, `fgd_probe.comp`), declared once in
//! `glsl/include/bindings/shading.glsl` and on this side in `shader::interface`.
//!
//! The tables are built (or loaded from the disk cache) when a variant that samples them is
//! prepared, and kept for later variants; [`ShadingInputs::fgd_lookup`] and
//! [`ShadingInputs::tir_lookup`] give their CPU twins, so the f64 model can run with exactly
//! what the GPU samples.

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::shader::interface::{InputViews, ShadingLayout};
use crate::tables::fgd::{FgdImages, FgdLookup};
use crate::tables::lobe_albedo::LobeAlbedoTable;
use crate::tables::split_sum::{self, SplitSumTable};
use crate::tables::tir::{self, TirTable};
use crate::variant::{Fgd, Tir, VariantKey, G2};
use crate::vk::{Buffer, DescriptorSet, ImageView};

/// The shading set's layout and the tables of every variant prepared so far.
pub struct ShadingInputs<'g> {
    gpu: &'g Gpu,
    pub layout: ShadingLayout,
    split_sums: HashMap<G2, SplitSumTable>,
    lobe_albedos: HashMap<G2, LobeAlbedoTable>,
    /// Built (or loaded from the disk cache) when a LUT variant is prepared.
    tir: Option<TirTable>,
    /// Zeros bound in place of the TIR table for the other variants.
    tir_unused: TirTable,
    /// Per (fgd, G2), built when a variant needing them is prepared.
    fgd_tables: HashMap<(Fgd, G2), FgdImages>,
}

impl<'g> ShadingInputs<'g> {
    pub fn new(gpu: &'g Gpu) -> Result<Self> {
        Ok(Self {
            gpu,
            layout: ShadingLayout::new(&gpu.device)?,
            split_sums: HashMap::new(),
            lobe_albedos: HashMap::new(),
            tir: None,
            tir_unused: TirTable::for_variant(gpu, Tir::None)?,
            fgd_tables: HashMap::new(),
        })
    }

    /// Builds or loads the tables `variant` samples (once per table).
    pub fn prepare(&mut self, variant: VariantKey) -> Result<()> {
        if !self.split_sums.contains_key(&variant.g2) {
            let table = SplitSumTable::load_or_build(
                self.gpu,
                variant.g2,
                split_sum::DEFAULT_SIZE,
                split_sum::DEFAULT_SAMPLES,
            )?;
            self.split_sums.insert(variant.g2, table);
        }
        if !self.lobe_albedos.contains_key(&variant.g2) {
            let table = LobeAlbedoTable::load_or_build(self.gpu, variant.g2)?;
            self.lobe_albedos.insert(variant.g2, table);
        }
        if matches!(variant.tir, Tir::Lut32 | Tir::Lut16) && self.tir.is_none() {
            self.tir = Some(TirTable::for_variant(self.gpu, variant.tir)?);
        }
        let key = (variant.fgd, variant.g2);
        if !self.fgd_tables.contains_key(&key) {
            let images = FgdImages::for_variant(self.gpu, variant.fgd, variant.g2)?;
            self.fgd_tables.insert(key, images);
        }
        Ok(())
    }

    fn unprepared(variant: VariantKey) -> Error {
        Error::Unsupported(format!("variant {variant} was not prepared"))
    }

    /// The split-sum table of `variant` (its G2 form).
    pub fn split_sum(&self, variant: VariantKey) -> Result<&SplitSumTable> {
        self.split_sums
            .get(&variant.g2)
            .ok_or_else(|| Self::unprepared(variant))
    }

    /// The white lobe's albedo table of `variant` (its G2 form), which the lights read.
    pub fn lobe_albedo(&self, variant: VariantKey) -> Result<&LobeAlbedoTable> {
        self.lobe_albedos
            .get(&variant.g2)
            .ok_or_else(|| Self::unprepared(variant))
    }

    /// The TIR table `variant` samples (zeros unless a LUT mode).
    pub fn tir(&self, variant: VariantKey) -> &TirTable {
        match variant.tir {
            Tir::Lut32 | Tir::Lut16 => self.tir.as_ref().unwrap_or(&self.tir_unused),
            _ => &self.tir_unused,
        }
    }

    /// The FGD tables of `variant`.
    pub fn fgd(&self, variant: VariantKey) -> Result<&FgdImages> {
        self.fgd_tables
            .get(&(variant.fgd, variant.g2))
            .ok_or_else(|| Self::unprepared(variant))
    }

    /// The shading set for `variant` and the stack in `material`, with a `mode=baked`
    /// material's lobe table (`baked`; other passes never read binding 5, which then holds
    /// the split-sum table again) and a spatially varying stack's maps (`layer_maps`).
    pub fn bind(
        &self,
        variant: VariantKey,
        material: &Buffer,
        baked: Option<&ImageView>,
        layer_maps: Option<&ImageView>,
        name: &str,
    ) -> Result<DescriptorSet> {
        let fgd = self.fgd(variant)?;
        let split_sum = &self.split_sum(variant)?.view;
        let views = InputViews {
            material,
            split_sum,
            lobe_albedo: &self.lobe_albedo(variant)?.view,
            tir: self.tir(variant).view_for(variant.tir),
            fgd_volume: &fgd.volume_view,
            fgd_plane: &fgd.plane_view,
            baked: baked.unwrap_or(split_sum),
            layer_maps,
        };
        Ok(self.layout.bind(&self.gpu.device, &views, name)?)
    }

    /// The CPU twin of `variant`'s FGD lookups.
    pub fn fgd_lookup(&self, variant: VariantKey) -> Result<FgdLookup<'_>> {
        Ok(FgdLookup {
            twin: &self.fgd(variant)?.twin,
            split_sum: self.split_sum(variant)?,
        })
    }

    /// The CPU twin of `variant`'s TIR term.
    pub fn tir_lookup(&self, variant: VariantKey) -> Box<dyn crate::model::Tir + '_> {
        tir::provider(variant.tir, self.tir(variant))
    }
}
