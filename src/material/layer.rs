//! Validation of one `[[layer]]` table into [`LayerParams`]: keys, types, lengths, ranges (the
//! table in the module docs), the interface form and the medium rules.

use std::cell::{Cell, RefCell};
use std::ops::RangeInclusive;
use std::path::Path;

use toml::{Table, Value};

use super::artist::gulbrandsen;
use super::source::SourceReader;
use super::surface::{Coords, Field, LayerSurface, Shape, Source};
use super::MaterialError;
use crate::model::LayerParams;
use crate::variant::Model;

const LAYER_KEYS: &[&str] = &[
    "ior",
    "kappa",
    "f0",
    "edge_tint",
    "roughness",
    "depth",
    "sigma_s",
    "sigma_a",
    "g",
    "coverage",
    "diffuse",
];
const MEDIUM_KEYS: &[&str] = &["depth", "sigma_s", "sigma_a", "g"];
const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// An allowed range, inclusive unless `open_low`/`open_high` exclude an end.
struct Range {
    span: RangeInclusive<f64>,
    open_low: bool,
    open_high: bool,
    text: &'static str,
}

impl Range {
    const fn closed(low: f64, high: f64, text: &'static str) -> Self {
        Self {
            span: low..=high,
            open_low: false,
            open_high: false,
            text,
        }
    }

    fn contains(&self, v: f64) -> bool {
        self.span.contains(&v)
            && !(self.open_low && v == *self.span.start())
            && !(self.open_high && v == *self.span.end())
    }
}

const IOR: Range = Range::closed(1e-3, 400.0, "[0.001, 400]");
const KAPPA: Range = Range::closed(0.0, 200.0, "[0, 200]");
const UNIT: Range = Range::closed(0.0, 1.0, "[0, 1]");
const F0: Range = Range::closed(0.0, 0.99, "[0, 0.99]");
const DEPTH: Range = Range::closed(0.0, 100.0, "[0, 100]");
const SIGMA: Range = Range::closed(0.0, 1000.0, "[0, 1000]");
const HG_G: Range = Range {
    open_low: true,
    open_high: true,
    ..Range::closed(-1.0, 1.0, "(-1, 1)")
};

/// One `[[layer]]` table with what its error messages and rules need.
pub(super) struct LayerReader<'a> {
    pub path: &'a Path,
    /// 0-based; messages print it 1-based.
    pub index: usize,
    pub is_last: bool,
    pub model: Model,
    pub table: &'a Table,
    /// The maps found so far (fields given as tables).
    pub sources: RefCell<Vec<(Field, Source)>>,
    /// The artist form's (f0, edge tint), a map's middle where one varies.
    pub artist_base: Cell<Option<([f64; 3], [f64; 3])>>,
}

impl LayerReader<'_> {
    /// The validated layer (maps read at their range's middle) and its maps.
    pub fn read(&self) -> Result<(LayerParams, LayerSurface), MaterialError> {
        self.check_keys()?;
        if self.has("diffuse") {
            return self.diffuse_base();
        }
        let (ior, kappa) = self.interface()?;
        let roughness = self.scalar("roughness", &UNIT)?.ok_or_else(|| {
            self.error(
                "roughness",
                "missing; the GGX α of the layer's top interface, in [0, 1]",
            )
        })?;
        let layer = LayerParams::conductor(ior, kappa, roughness).with_medium(
            self.scalar("depth", &DEPTH)?.unwrap_or(0.0),
            self.rgb("sigma_s", &SIGMA)?.unwrap_or([0.0; 3]),
            self.rgb("sigma_a", &SIGMA)?.unwrap_or([0.0; 3]),
            self.scalar("g", &HG_G)?.unwrap_or(0.0),
        );
        self.check_conductor_and_medium(&layer)?;
        self.coverage()?;
        let sources = self.sources.take();
        let artist = self.artist_base.get().filter(|_| {
            sources
                .iter()
                .any(|(f, _)| matches!(f, Field::F0 | Field::EdgeTint))
        });
        Ok((layer, LayerSurface { sources, artist }))
    }

    /// A Lambertian base (`diffuse = [r, g, b]`, albedo in [0, 1]): the last layer, with no
    /// interface of its own (it lies in the medium above) and no other field but `coverage`.
    /// Its roughness is the roughest, α = 1: the asymmetry of its reflection that the layers
    /// above see (`model::diffuse`).
    fn diffuse_base(&self) -> Result<(LayerParams, LayerSurface), MaterialError> {
        if !self.is_last {
            return Err(self.error(
                "diffuse",
                "a diffuse base is opaque and ends the stack: it must be the last layer",
            ));
        }
        if let Some(key) = self
            .table
            .keys()
            .find(|k| !matches!(k.as_str(), "diffuse" | "coverage"))
        {
            return Err(self.error(
                key,
                "a diffuse base has only `diffuse` (its albedo) and `coverage`: it has no \
                 interface of its own and no medium",
            ));
        }
        let rho = self.rgb("diffuse", &UNIT)?.expect("checked above");
        let layer = LayerParams::diffuse_base(rho);
        self.coverage()?;
        let sources = self.sources.take();
        Ok((
            layer,
            LayerSurface {
                sources,
                artist: None,
            },
        ))
    }

    /// `coverage`: a number in [0, 1] (one value everywhere) or a map.
    fn coverage(&self) -> Result<(), MaterialError> {
        let Some(value) = self.table.get("coverage") else {
            return Ok(());
        };
        if let Value::Table(_) = value {
            self.scalar("coverage", &UNIT)?;
            return Ok(());
        }
        let c = self.number("coverage", None, value, &UNIT)?;
        self.sources.borrow_mut().push((
            Field::Coverage,
            Source {
                shape: Shape::Uniform(c),
                threshold: None,
                range: [[0.0; 3], [1.0; 3]],
                coords: Coords::Uv,
                table: value.clone(),
            },
        ));
        Ok(())
    }

    /// A map given in place of `field`'s value, recorded; its base value is the middle of
    /// its range.
    fn source(&self, field: &str, table: &Table, range: &Range) -> Result<[f64; 3], MaterialError> {
        let field_id = Field::from_key(field).expect("a layer key");
        let allowed = |v: f64| range.contains(v);
        let default_range = (*range.span.start() >= 0.0 && *range.span.end() <= 1.0)
            .then(|| [*range.span.start(), *range.span.end()]);
        let source = SourceReader {
            path: self.path,
            layer: self.index,
            field: field_id,
            table,
            allowed: (&allowed, range.text),
            default_range,
        }
        .read()?;
        let [lo, hi] = source.range;
        let middle = [0, 1, 2].map(|c| 0.5 * (lo[c] + hi[c]));
        let mut sources = self.sources.borrow_mut();
        if !sources.iter().any(|(f, _)| *f == field_id) {
            sources.push((field_id, source));
        }
        Ok(middle)
    }

    fn error(&self, field: &str, message: impl Into<String>) -> MaterialError {
        MaterialError::Field {
            path: self.path.to_owned(),
            layer: self.index + 1,
            field: field.to_owned(),
            message: message.into(),
        }
    }

    fn has(&self, field: &str) -> bool {
        self.table.contains_key(field)
    }

    /// Unknown keys, and medium keys outside `tm6`.
    fn check_keys(&self) -> Result<(), MaterialError> {
        if let Some(key) = self
            .table
            .keys()
            .find(|k| !LAYER_KEYS.contains(&k.as_str()))
        {
            let known = LAYER_KEYS.join(", ");
            return Err(self.error(key, format!("unknown key; layer keys are {known}")));
        }
        match MEDIUM_KEYS.iter().find(|k| self.has(k)) {
            Some(key) if self.model == Model::Tm2 => {
                Err(self.error(key, "a medium field, allowed only with model = \"tm6\""))
            }
            _ => Ok(()),
        }
    }

    /// A conductor ends the stack and holds no medium; a medium needs its depth.
    fn check_conductor_and_medium(&self, layer: &LayerParams) -> Result<(), MaterialError> {
        if layer.is_conductor() {
            let field = if self.has("f0") { "f0" } else { "kappa" };
            if !self.is_last {
                return Err(self.error(field, "a conductor (κ > 0) must be the last layer"));
            }
            if let Some(key) = MEDIUM_KEYS.iter().find(|k| self.has(k)) {
                return Err(self.error(key, "a conductor (κ > 0) is opaque and has no medium"));
            }
        }
        match ["sigma_s", "sigma_a"].iter().find(|k| self.has(k)) {
            Some(key) if !self.has("depth") => Err(self.error(
                "depth",
                format!(
                    "missing: `{key}` needs the medium's depth, in {}",
                    DEPTH.text
                ),
            )),
            _ => Ok(()),
        }
    }

    /// A finite number in `range`; `channel` (R, G or B) locates an element of an RGB array.
    fn number(
        &self,
        field: &str,
        channel: Option<&str>,
        value: &Value,
        range: &Range,
    ) -> Result<f64, MaterialError> {
        let at = channel.map(|c| format!("{c}: ")).unwrap_or_default();
        let v = match value {
            Value::Float(f) => *f,
            Value::Integer(i) => *i as f64,
            other => {
                let found = other.type_str();
                return Err(self.error(field, format!("{at}expected a number, found {found}")));
            }
        };
        let allowed = range.text;
        if !v.is_finite() {
            return Err(self.error(field, format!("{at}{v} is not finite; allowed {allowed}")));
        }
        if !range.contains(v) {
            let message = format!("{at}{v} is out of range; allowed {allowed}");
            return Err(self.error(field, message));
        }
        Ok(v)
    }

    fn scalar(&self, field: &str, range: &Range) -> Result<Option<f64>, MaterialError> {
        match self.table.get(field) {
            None => Ok(None),
            Some(Value::Table(t)) => Ok(Some(self.source(field, t, range)?[0])),
            Some(v) => self.number(field, None, v, range).map(Some),
        }
    }

    fn rgb(&self, field: &str, range: &Range) -> Result<Option<[f64; 3]>, MaterialError> {
        let Some(value) = self.table.get(field) else {
            return Ok(None);
        };
        let items = match value {
            Value::Table(t) => return Ok(Some(self.source(field, t, range)?)),
            Value::Array(items) if items.len() == 3 => items,
            Value::Array(items) => {
                let found = items.len();
                return Err(self.error(field, format!("expected 3 numbers (RGB), found {found}")));
            }
            other => {
                let found = other.type_str();
                let message = format!("expected an array of 3 numbers (RGB), found {found}");
                return Err(self.error(field, message));
            }
        };
        let mut out = [0.0; 3];
        for ((o, item), channel) in out.iter_mut().zip(items).zip(CHANNELS) {
            *o = self.number(field, Some(channel), item, range)?;
        }
        Ok(Some(out))
    }

    /// (η, κ) from the physical form, or from the artist form.
    fn interface(&self) -> Result<([f64; 3], [f64; 3]), MaterialError> {
        let physical = self.has("ior") || self.has("kappa");
        let artist = self.has("f0") || self.has("edge_tint");
        match (physical, artist) {
            (true, true) => Err(self.error(
                "f0",
                "give either ior/kappa (physical) or f0/edge_tint (artist), not both",
            )),
            (false, false) => Err(self.error(
                "ior",
                "missing; give ior (and kappa for a conductor), or f0 and edge_tint",
            )),
            (true, false) => self.physical(),
            (false, true) => self.artist(),
        }
    }

    fn physical(&self) -> Result<([f64; 3], [f64; 3]), MaterialError> {
        let ior = self.rgb("ior", &IOR)?.ok_or_else(|| {
            self.error("ior", format!("missing (kappa needs ior), in {}", IOR.text))
        })?;
        Ok((ior, self.rgb("kappa", &KAPPA)?.unwrap_or([0.0; 3])))
    }

    /// Gulbrandsen 2014 per channel (ALGORITHMS.md §10.5). With r ≤ 0.99 the result lies in
    /// the physical form's ranges: η ≤ (1+√r)/(1−√r) ≈ 398 and κ ≤ √(((1+r)/(1−r))² − 1) ≈ 199.
    fn artist(&self) -> Result<([f64; 3], [f64; 3]), MaterialError> {
        let f0 = self.rgb("f0", &F0)?.ok_or_else(|| {
            self.error(
                "f0",
                format!("missing (edge_tint needs f0), in {}", F0.text),
            )
        })?;
        let tint = self.rgb("edge_tint", &UNIT)?.ok_or_else(|| {
            self.error(
                "edge_tint",
                format!("missing (f0 needs edge_tint), in {}", UNIT.text),
            )
        })?;
        self.artist_base.set(Some((f0, tint)));
        let (mut ior, mut kappa) = ([0.0; 3], [0.0; 3]);
        for c in 0..3 {
            (ior[c], kappa[c]) = gulbrandsen(f0[c], tint[c]);
        }
        Ok((ior, kappa))
    }
}
