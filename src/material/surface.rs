//! Spatially varying stacks: any layer parameter from a texture or a procedural pattern, and a
//! per-layer coverage that takes the layer away where it is 0.
//!
//! ```toml
//! map_resolution = 512                      # texels per side of the baked maps (top level)
//! [[layer]]
//! ior = [1.5, 1.5, 1.5]
//! roughness = { texture = "wear.png", space = "linear", channel = "r", range = [0.05, 0.4] }
//! coverage = { pattern = "noise", scale = 6, octaves = 4, seed = 2, threshold = 0.45 }
//! ```
//!
//! A source is an inline table in place of a field's number (or RGB array):
//!
//! | key | for | meaning |
//! |---|---|---|
//! | `texture` | textures | a PNG or OpenEXR file, relative to the material file |
//! | `space` | textures, required | `srgb` (PNG only) or `linear`: how the stored values decode |
//! | `channel` | textures | `r`, `g`, `b` or `a`: the channel a scalar field reads (required when the image has more than one); RGB fields read R, G and B |
//! | `pattern` | patterns | `checker` (cells alternating 0 and 1), `noise` (smooth value noise, summed over `octaves`), `cells` (one uniform random value per cell) |
//! | `scale` | both | repeats per unit of the coordinates: cells of a pattern, tiles of a texture, an integer in [1, 4096] so that maps tile without a seam |
//! | `octaves`, `seed` | `noise`, `cells` | octaves in [1, 8] (noise; default 4) and the random stream (default 0) |
//! | `threshold` | patterns | in [0, 1]: the value becomes 1 where it exceeds the threshold, 0 elsewhere (patches) |
//! | `range` | both | `[low, high]`: the value v ∈ [0, 1] maps to low + v·(high − low); each end a number or, for RGB fields, an RGB array, inside the field's own range. Default [0, 1] where the field's range holds it (roughness, coverage, edge tint; f0 up to 0.99), required elsewhere |
//! | `coords` | both | `uv` (default: the mesh's texture coordinates) or `screen`: texel (x, y) of the map is pixel (x mod N, y mod N) of the frame, exactly — for masks sized in pixels (the divergence study) |
//!
//! `coverage` (in [0, 1], a number or a source) is the fraction of the surface the layer covers.
//! Every texel of the baked coverage map holds the layer or not: a texel is covered where its
//! coverage exceeds a per-texel hash in [0, 1), so 0 removes the layer, 1 keeps it, and 0.3 keeps
//! it on 30 % of the texels (a stipple at the map's resolution). The shader tests the covered
//! layers of each pixel first and runs the model over those only (`glsl/include/lib/
//! tm_common.glsl`): an absent layer costs no loop iteration, and the pixel is shaded exactly as
//! the stack without that layer ([`SurfaceMaps::layers_at`] is the CPU twin).
//!
//! Everything is baked on load into square maps of `map_resolution` texels (textures resampled
//! bilinearly, repeated), one per varying field, which the GPU samples (bilinear, repeat; the
//! coverage nearest). The artist form (f0, edge tint) is converted to (η, κ) per texel.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use toml::Value;

use super::artist::gulbrandsen;
use super::MaterialError;
use crate::model::LayerParams;

/// Default texels per side of the baked maps.
pub const DEFAULT_RESOLUTION: u32 = 512;
/// Allowed `map_resolution`.
pub const RESOLUTION_RANGE: std::ops::RangeInclusive<u32> = 4..=4096;
/// Largest `scale`.
pub const MAX_SCALE: u32 = 4096;
/// Most slices a stack's maps may hold: the shader's per-field code is 7 bits, 0 meaning none.
pub const MAX_SLICES: usize = 127;

/// A layer parameter that may vary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Field {
    Ior,
    Kappa,
    F0,
    EdgeTint,
    Roughness,
    Depth,
    SigmaS,
    SigmaA,
    G,
    Coverage,
    Diffuse,
}

impl Field {
    pub fn from_key(key: &str) -> Option<Self> {
        Some(match key {
            "ior" => Self::Ior,
            "kappa" => Self::Kappa,
            "f0" => Self::F0,
            "edge_tint" => Self::EdgeTint,
            "roughness" => Self::Roughness,
            "depth" => Self::Depth,
            "sigma_s" => Self::SigmaS,
            "sigma_a" => Self::SigmaA,
            "g" => Self::G,
            "coverage" => Self::Coverage,
            "diffuse" => Self::Diffuse,
            _ => return None,
        })
    }

    pub fn key(self) -> &'static str {
        match self {
            Self::Ior => "ior",
            Self::Kappa => "kappa",
            Self::F0 => "f0",
            Self::EdgeTint => "edge_tint",
            Self::Roughness => "roughness",
            Self::Depth => "depth",
            Self::SigmaS => "sigma_s",
            Self::SigmaA => "sigma_a",
            Self::G => "g",
            Self::Coverage => "coverage",
            Self::Diffuse => "diffuse",
        }
    }

    /// Whether the field is an RGB triple.
    pub fn is_rgb(self) -> bool {
        matches!(
            self,
            Self::Ior
                | Self::Kappa
                | Self::F0
                | Self::EdgeTint
                | Self::SigmaS
                | Self::SigmaA
                | Self::Diffuse
        )
    }
}

/// Where a map is looked up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coords {
    /// The mesh's texture coordinates.
    Uv,
    /// The pixel: texel (x mod N, y mod N).
    Screen,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatternKind {
    Checker,
    Noise,
    Cells,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    pub kind: PatternKind,
    pub scale: u32,
    pub octaves: u32,
    pub seed: u32,
}

/// How a texture's stored values decode to [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    Srgb,
    Linear,
}

/// A decoded texture: linear values, rows top to bottom, grey images spread over RGB.
#[derive(Clone, PartialEq)]
pub struct TextureImage {
    pub path: PathBuf,
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub texels: Vec<[f32; 4]>,
}

impl std::fmt::Debug for TextureImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "TextureImage({}, {}x{}, {} channel(s))",
            self.path.display(),
            self.width,
            self.height,
            self.channels
        )
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Pattern(Pattern),
    Texture {
        image: Arc<TextureImage>,
        /// The channel a scalar field reads; `None` for RGB fields.
        channel: Option<usize>,
        scale: u32,
    },
    /// One value everywhere (a numeric `coverage`).
    Uniform(f64),
}

/// One varying field: its shape, the map from [0, 1] to the field's values, and its table as
/// written (texture path made absolute), which [`super::Stack::to_toml`] writes back.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    pub shape: Shape,
    pub threshold: Option<f64>,
    pub range: [[f64; 3]; 2],
    pub coords: Coords,
    pub table: Value,
}

impl Source {
    /// The field's value at texture coordinates (u, v).
    pub fn value(&self, u: f64, v: f64) -> [f64; 3] {
        let t = match &self.shape {
            Shape::Pattern(p) => [pattern_value(p, u, v); 3],
            Shape::Texture {
                image,
                channel,
                scale,
            } => {
                let s = f64::from(*scale);
                let texel = sample_bilinear(image, u * s, v * s);
                match channel {
                    Some(c) => [f64::from(texel[*c]); 3],
                    None => [texel[0], texel[1], texel[2]].map(f64::from),
                }
            }
            Shape::Uniform(c) => return [*c; 3],
        };
        let t = t.map(|t| match self.threshold {
            Some(th) => f64::from(u8::from(t > th)),
            None => t.clamp(0.0, 1.0),
        });
        let [lo, hi] = self.range;
        [0, 1, 2].map(|c| lo[c] + t[c] * (hi[c] - lo[c]))
    }
}

/// The varying fields of one layer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerSurface {
    pub sources: Vec<(Field, Source)>,
    /// The artist form's constants (f0, edge tint) where one of the two varies.
    pub artist: Option<([f64; 3], [f64; 3])>,
}

impl LayerSurface {
    pub fn source(&self, field: Field) -> Option<&Source> {
        self.sources
            .iter()
            .find(|(f, _)| *f == field)
            .map(|(_, s)| s)
    }
}

/// A stack's variation: per layer (top first) its sources, and the maps baked from them.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    pub resolution: u32,
    pub layers: Vec<LayerSurface>,
    pub maps: SurfaceMaps,
}

/// The GPU's form of a [`Surface`]: square slices of `resolution`² RGBA texels, and per layer
/// three codes of four bytes, one per field — x: η, κ, σs, σa; y: α, depth, g, coverage; z:
/// the diffuse albedo — each 0 (constant) or 1 + the slice's index, with bit 7 set for screen
/// coordinates.
#[derive(Clone, PartialEq)]
pub struct SurfaceMaps {
    pub resolution: u32,
    pub slices: Vec<Vec<[f32; 4]>>,
    pub codes: Vec<[u32; 3]>,
}

impl std::fmt::Debug for SurfaceMaps {
    /// The shape and the codes; the texels would be megabytes of text.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurfaceMaps")
            .field("resolution", &self.resolution)
            .field("slices", &self.slices.len())
            .field("codes", &self.codes)
            .finish()
    }
}

/// The bit of [`SurfaceMaps::spec_bits`] that says a stack varies at all.
pub const SURFACE_ON: u32 = 1 << 31;

/// Bit of a field's code byte marking screen coordinates.
pub const SCREEN_BIT: u32 = 0x80;

/// The GPU field order of the code bytes: (code word, byte).
fn gpu_slot(field: Field) -> (usize, u32) {
    match field {
        Field::Ior | Field::F0 => (0, 0),
        Field::Kappa | Field::EdgeTint => (0, 8),
        Field::SigmaS => (0, 16),
        Field::SigmaA => (0, 24),
        Field::Roughness => (1, 0),
        Field::Depth => (1, 8),
        Field::G => (1, 16),
        Field::Coverage => (1, 24),
        Field::Diffuse => (2, 0),
    }
}

impl SurfaceMaps {
    /// The code byte of `field` in layer `layer`: 0 or (1 + slice) | screen bit.
    fn code(&self, layer: usize, field: Field) -> u32 {
        let (word, shift) = gpu_slot(field);
        (self.codes[layer][word] >> shift) & 0xff
    }

    fn texel(&self, slice: usize, x: i64, y: i64) -> [f32; 4] {
        let n = i64::from(self.resolution);
        let (x, y) = (x.rem_euclid(n), y.rem_euclid(n));
        self.slices[slice][(y * n + x) as usize]
    }

    /// The value of a code's slice at (u, v) or at pixel `pixel`: bilinear and repeated for
    /// texture coordinates (the GPU sampler's filter), the texel itself for screen coordinates
    /// and for coverage (`nearest`).
    fn lookup(&self, code: u32, uv: (f64, f64), pixel: (u32, u32), nearest: bool) -> [f32; 4] {
        let slice = (code & !SCREEN_BIT) as usize - 1;
        if code & SCREEN_BIT != 0 {
            return self.texel(slice, i64::from(pixel.0), i64::from(pixel.1));
        }
        let n = f64::from(self.resolution);
        if nearest {
            let x = (uv.0 * n).floor() as i64;
            let y = (uv.1 * n).floor() as i64;
            return self.texel(slice, x, y);
        }
        let (x, y) = (uv.0 * n - 0.5, uv.1 * n - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mix = |a: [f32; 4], b: [f32; 4], t: f32| [0, 1, 2, 3].map(|c| a[c] + (b[c] - a[c]) * t);
        let top = mix(self.texel(slice, x0, y0), self.texel(slice, x0 + 1, y0), fx);
        let bottom = mix(
            self.texel(slice, x0, y0 + 1),
            self.texel(slice, x0 + 1, y0 + 1),
            fx,
        );
        mix(top, bottom, fy)
    }

    /// The stack at texture coordinates `uv` and frame pixel `pixel`: `base` (the constants)
    /// with each varying field read from its map, and the layers whose coverage map does not
    /// hold them there left out — the CPU twin of the forward shader's surface lookups.
    pub fn layers_at(
        &self,
        base: &[LayerParams],
        uv: (f64, f64),
        pixel: (u32, u32),
    ) -> Vec<LayerParams> {
        let mut out = Vec::with_capacity(base.len());
        for (i, layer) in base.iter().enumerate() {
            let coverage = self.code(i, Field::Coverage);
            if coverage != 0 && self.lookup(coverage, uv, pixel, true)[0] <= 0.5 {
                continue;
            }
            let mut layer = *layer;
            let rgb = |code: u32| {
                let t = self.lookup(code, uv, pixel, false);
                [t[0], t[1], t[2]].map(f64::from)
            };
            let scalar = |code: u32| f64::from(self.lookup(code, uv, pixel, false)[0]);
            for field in [Field::Ior, Field::Kappa, Field::SigmaS, Field::SigmaA] {
                let code = self.code(i, field);
                if code != 0 {
                    let v = rgb(code);
                    match field {
                        Field::Ior => layer.ior = v,
                        Field::Kappa => layer.kappa = v,
                        Field::SigmaS => layer.sigma_s = v,
                        _ => layer.sigma_a = v,
                    }
                }
            }
            let code = self.code(i, Field::Diffuse);
            if code != 0 {
                layer.diffuse = Some(rgb(code));
            }
            for field in [Field::Roughness, Field::Depth, Field::G] {
                let code = self.code(i, field);
                if code != 0 {
                    let v = scalar(code);
                    match field {
                        Field::Roughness => layer.roughness = v,
                        Field::Depth => layer.depth = v,
                        _ => layer.g = v,
                    }
                }
            }
            out.push(layer);
        }
        out
    }

    /// The forward pass's `SURFACE_MAPS` constant for these maps: [`SURFACE_ON`], and bit
    /// 4·word + byte for each field some layer reads from a map (bits 0–3: η, κ, σs, σa; 4–7:
    /// α, depth, g, coverage; 8: the diffuse albedo). The shader reads only those fields'
    /// maps: lavapipe runs both sides of a branch, so a lookup the stack never needs would
    /// still cost every pixel its texture fetch.
    pub fn spec_bits(&self) -> u32 {
        let mut bits = SURFACE_ON;
        for code in &self.codes {
            for (word, value) in code.iter().enumerate() {
                for byte in 0..4 {
                    if (value >> (8 * byte)) & 0xff != 0 {
                        bits |= 1 << (4 * word + byte);
                    }
                }
            }
        }
        bits
    }

    /// The fields layer `layer` reads from maps, a bit each: η, κ, σs, σa, α, depth, g, the
    /// diffuse albedo from bit 0 (a class pass's `SLOT_MAPS` byte; the coverage, which the
    /// stencil marks read, is not among them).
    pub fn mapped_fields(&self, layer: usize) -> u32 {
        [
            Field::Ior,
            Field::Kappa,
            Field::SigmaS,
            Field::SigmaA,
            Field::Roughness,
            Field::Depth,
            Field::G,
            Field::Diffuse,
        ]
        .iter()
        .enumerate()
        .filter(|(_, &field)| self.code(layer, field) != 0)
        .fold(0, |bits, (k, _)| bits | 1 << k)
    }

    /// Layer `layer`'s coverage map as the shader tests it, texel by texel (held where its
    /// value exceeds 1/2), and whether it is read in screen coordinates; `None` without one.
    pub fn coverage_texels(&self, layer: usize) -> Option<(Vec<bool>, bool)> {
        let code = self.code(layer, Field::Coverage);
        if code == 0 {
            return None;
        }
        let slice = &self.slices[(code & !SCREEN_BIT) as usize - 1];
        Some((
            slice.iter().map(|t| t[0] > 0.5).collect(),
            code & SCREEN_BIT != 0,
        ))
    }

    /// The lowest and highest value layer `layer`'s map of `field` takes (η: the mean of its
    /// RGB, as the model's tests read it; a scalar field: its value): what any point of the
    /// surface reads lies between them, the sampler's bilinear filter included. `None` where
    /// the field is constant.
    pub fn range(&self, layer: usize, field: Field) -> Option<(f64, f64)> {
        let code = self.code(layer, field);
        if code == 0 {
            return None;
        }
        let slice = &self.slices[(code & !SCREEN_BIT) as usize - 1];
        let value = |t: &[f32; 4]| match field {
            Field::Ior => (f64::from(t[0]) + f64::from(t[1]) + f64::from(t[2])) / 3.0,
            _ => f64::from(t[0]),
        };
        slice.iter().map(value).fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((f64::min(lo, v), f64::max(hi, v))),
        })
    }

    /// The fraction of the map's texels holding layer `layer` (1 without a coverage map).
    pub fn coverage_fraction(&self, layer: usize) -> f64 {
        let code = self.code(layer, Field::Coverage);
        if code == 0 {
            return 1.0;
        }
        let slice = &self.slices[(code & !SCREEN_BIT) as usize - 1];
        slice.iter().filter(|t| t[0] > 0.5).count() as f64 / slice.len() as f64
    }
}

impl Surface {
    /// Bakes the sources of every layer over `base` (the stack's constants) into maps of
    /// `resolution`² texels. Errs when a layer changes kind across its surface (a conductor
    /// somewhere, a dielectric elsewhere) or the maps need more than [`MAX_SLICES`] slices.
    pub(super) fn bake(
        resolution: u32,
        layers: Vec<LayerSurface>,
        base: &[LayerParams],
        path: &Path,
    ) -> Result<Self, MaterialError> {
        let mut baker = Baker {
            n: resolution as usize,
            path,
            slices: Vec::new(),
            codes: vec![[0u32; 3]; layers.len()],
        };
        for (index, surface) in layers.iter().enumerate() {
            // The artist form: both maps come from f0 and the edge tint together.
            if let Some((f0, tint)) = surface.artist {
                baker.artist(index, surface, &base[index], (f0, tint))?;
            }
            for (field, source) in &surface.sources {
                match field {
                    Field::F0 | Field::EdgeTint => {}
                    Field::Coverage => baker.coverage(index, source)?,
                    _ => baker.field(index, *field, source)?,
                }
            }
        }
        Ok(Self {
            resolution,
            layers,
            maps: SurfaceMaps {
                resolution,
                slices: baker.slices,
                codes: baker.codes,
            },
        })
    }

    /// Whether any layer has a coverage.
    pub fn has_coverage(&self) -> bool {
        self.layers
            .iter()
            .any(|l| l.source(Field::Coverage).is_some())
    }
}

/// The maps of a surface as they are baked: `n`² texels per slice, and each layer's slice
/// codes (`SurfaceMaps::codes`).
struct Baker<'a> {
    n: usize,
    path: &'a Path,
    slices: Vec<Vec<[f32; 4]>>,
    codes: Vec<[u32; 3]>,
}

impl Baker<'_> {
    /// Texel i's centre in texture coordinates, rows top to bottom.
    fn centre(&self, i: usize) -> (f64, f64) {
        let at = |k: usize| (k as f64 + 0.5) / self.n as f64;
        (at(i % self.n), at(i / self.n))
    }

    fn error(&self, index: usize, field: &str, message: String) -> MaterialError {
        MaterialError::Field {
            path: self.path.to_owned(),
            layer: index + 1,
            field: field.to_owned(),
            message,
        }
    }

    /// Adds a slice for `field` of layer `index`, read in `coords`.
    fn push(
        &mut self,
        index: usize,
        field: Field,
        coords: Coords,
        texels: Vec<[f32; 4]>,
    ) -> Result<(), MaterialError> {
        if self.slices.len() >= MAX_SLICES {
            return Err(self.error(
                index,
                field.key(),
                format!("the stack's maps need more than {MAX_SLICES} slices"),
            ));
        }
        self.slices.push(texels);
        let screen = if coords == Coords::Screen {
            SCREEN_BIT
        } else {
            0
        };
        let (word, shift) = gpu_slot(field);
        self.codes[index][word] |= (self.slices.len() as u32 | screen) << shift;
        Ok(())
    }

    /// The artist form's η and κ maps, from f0 and the edge tint (each a map or the layer's
    /// constant) together; the layer keeps its kind (conductor or not) everywhere.
    fn artist(
        &mut self,
        index: usize,
        surface: &LayerSurface,
        layer: &LayerParams,
        (f0, tint): ([f64; 3], [f64; 3]),
    ) -> Result<(), MaterialError> {
        let f0_source = surface.source(Field::F0);
        let tint_source = surface.source(Field::EdgeTint);
        let space = f0_source.or(tint_source).map_or(Coords::Uv, |s| s.coords);
        let (etas, kappas): (Vec<[f64; 3]>, Vec<[f64; 3]>) = (0..self.n * self.n)
            .map(|i| {
                let (u, v) = self.centre(i);
                let r = f0_source.map_or(f0, |s| s.value(u, v));
                let g = tint_source.map_or(tint, |s| s.value(u, v));
                let pairs = [0, 1, 2].map(|c| gulbrandsen(r[c], g[c]));
                (pairs.map(|p| p.0), pairs.map(|p| p.1))
            })
            .unzip();
        let conductor = layer.is_conductor();
        if let Some(k) = kappas
            .iter()
            .find(|k| k.iter().any(|&k| k > 0.0) != conductor)
        {
            let kind = if conductor { "conductor" } else { "dielectric" };
            let field = if f0_source.is_some() {
                "f0"
            } else {
                "edge_tint"
            };
            return Err(self.error(
                index,
                field,
                format!(
                    "the layer is a {kind} at its base value but κ = {k:?} somewhere on its \
                     surface; a layer keeps its kind everywhere"
                ),
            ));
        }
        self.push(index, Field::Ior, space, to_slice(&etas))?;
        self.push(index, Field::Kappa, space, to_slice(&kappas))
    }

    /// The coverage map: a texel holds the layer where the coverage exceeds the texel's hash.
    fn coverage(&mut self, index: usize, source: &Source) -> Result<(), MaterialError> {
        let n = self.n;
        let salt = hash(index as u32 ^ 0x5bd1_e995);
        let texels = (0..n * n)
            .map(|i| {
                let (u, v) = self.centre(i);
                let c = source.value(u, v);
                let h = unit(hash3((i % n) as u32, (i / n) as u32, salt));
                let covered = f32::from(u8::from(c[0] > h));
                [covered, 0.0, 0.0, 0.0]
            })
            .collect();
        self.push(index, Field::Coverage, source.coords, texels)
    }

    /// The map of any other field; κ keeps above 0 (a layer is a conductor everywhere or
    /// nowhere).
    fn field(&mut self, index: usize, field: Field, source: &Source) -> Result<(), MaterialError> {
        let [lo, hi] = source.range;
        let reaches_zero = (0..3).any(|c| lo[c].min(hi[c]) <= 0.0);
        if field == Field::Kappa && reaches_zero {
            return Err(self.error(
                index,
                "kappa",
                format!(
                    "range {lo:?} to {hi:?} reaches κ = 0; a layer is a conductor everywhere or \
                     nowhere: give a range above 0"
                ),
            ));
        }
        let values: Vec<[f64; 3]> = (0..self.n * self.n)
            .map(|i| {
                let (u, v) = self.centre(i);
                source.value(u, v)
            })
            .collect();
        self.push(index, field, source.coords, to_slice(&values))
    }
}

fn to_slice(values: &[[f64; 3]]) -> Vec<[f32; 4]> {
    values
        .iter()
        .map(|v| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0])
        .collect()
}

/// lowbias32 (Chris Wellons' integer hash): a well-mixed u32 of a u32.
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

fn hash3(a: u32, b: u32, c: u32) -> u32 {
    hash(a ^ hash(b ^ hash(c)))
}

/// A hash as a number in [0, 1) with 24 bits.
fn unit(h: u32) -> f64 {
    f64::from(h >> 8) / f64::from(1u32 << 24)
}

/// Value noise of period `period` cells: hashed lattice values, smoothstep-interpolated.
fn value_noise(x: f64, y: f64, period: u32, salt: u32) -> f64 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let p = i64::from(period);
    let at = |i: i64, j: i64| unit(hash3(i.rem_euclid(p) as u32, j.rem_euclid(p) as u32, salt));
    let (i, j) = (x0 as i64, y0 as i64);
    let s = |t: f64| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let top = at(i, j) + (at(i + 1, j) - at(i, j)) * sx;
    let bottom = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * sx;
    top + (bottom - top) * sy
}

/// A pattern's value in [0, 1] at (u, v), periodic over the unit square.
fn pattern_value(p: &Pattern, u: f64, v: f64) -> f64 {
    let s = f64::from(p.scale);
    match p.kind {
        PatternKind::Checker => {
            let cell = (u * s).floor() as i64 + (v * s).floor() as i64;
            f64::from(u8::from(cell.rem_euclid(2) == 1))
        }
        PatternKind::Cells => {
            let n = i64::from(p.scale);
            let i = ((u * s).floor() as i64).rem_euclid(n) as u32;
            let j = ((v * s).floor() as i64).rem_euclid(n) as u32;
            unit(hash3(i, j, hash(p.seed)))
        }
        PatternKind::Noise => {
            let (mut sum, mut weight, mut amplitude) = (0.0, 0.0, 1.0);
            for octave in 0..p.octaves {
                let period = p.scale << octave;
                let f = f64::from(period);
                let salt = hash(p.seed ^ hash(octave));
                sum += amplitude * value_noise(u * f, v * f, period, salt);
                weight += amplitude;
                amplitude *= 0.5;
            }
            sum / weight
        }
    }
}

/// A texture's value at texel coordinates (x, y) in units of the image (repeated), bilinear.
fn sample_bilinear(image: &TextureImage, u: f64, v: f64) -> [f32; 4] {
    let (w, h) = (image.width as i64, image.height as i64);
    let (x, y) = (u * w as f64 - 0.5, v * h as f64 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let at = |i: i64, j: i64| image.texels[(j.rem_euclid(h) * w + i.rem_euclid(w)) as usize];
    let (i, j) = (x0 as i64, y0 as i64);
    let mix = |a: [f32; 4], b: [f32; 4], t: f32| [0, 1, 2, 3].map(|c| a[c] + (b[c] - a[c]) * t);
    mix(
        mix(at(i, j), at(i + 1, j), fx),
        mix(at(i, j + 1), at(i + 1, j + 1), fx),
        fy,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(kind: PatternKind, scale: u32) -> Pattern {
        Pattern {
            kind,
            scale,
            octaves: 4,
            seed: 7,
        }
    }

    #[test]
    fn patterns_are_periodic_over_the_unit_square_and_in_range() {
        for kind in [PatternKind::Checker, PatternKind::Noise, PatternKind::Cells] {
            let p = pattern(kind, if kind == PatternKind::Checker { 6 } else { 5 });
            for k in 0..200 {
                let (u, v) = (k as f64 * 0.0137, k as f64 * 0.0291);
                let a = pattern_value(&p, u, v);
                assert!((0.0..=1.0).contains(&a), "{kind:?} {a}");
                let b = pattern_value(&p, u + 1.0, v - 2.0);
                assert!((a - b).abs() < 1e-9, "{kind:?} not periodic: {a} {b}");
            }
        }
    }

    #[test]
    fn checker_cells_alternate_and_cover_half() {
        let p = pattern(PatternKind::Checker, 4);
        let n = 64;
        let covered = (0..n * n)
            .filter(|i| {
                let (u, v) = (
                    ((i % n) as f64 + 0.5) / n as f64,
                    ((i / n) as f64 + 0.5) / n as f64,
                );
                pattern_value(&p, u, v) > 0.5
            })
            .count();
        assert_eq!(covered * 2, n * n);
        assert_ne!(
            pattern_value(&p, 0.1, 0.1),
            pattern_value(&p, 0.1 + 0.25, 0.1)
        );
    }

    #[test]
    fn noise_is_smooth_and_spread() {
        let p = pattern(PatternKind::Noise, 4);
        let values: Vec<f64> = (0..1000)
            .map(|k| pattern_value(&p, k as f64 / 1000.0, 0.3))
            .collect();
        let step = values
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(step < 0.05, "jump of {step} between neighbours");
        let (lo, hi) = values
            .iter()
            .fold((1.0f64, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(hi - lo > 0.3, "flat noise: {lo}..{hi}");
    }
}
