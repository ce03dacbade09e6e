//! A varying field's source as the material file gives it (`material::surface`'s format): a
//! procedural pattern or a texture file, each key checked and named in its errors, and the
//! texture's texels read from PNG or OpenEXR and decoded to linear values.

use std::path::Path;

use toml::{Table, Value};

use std::sync::Arc;

use super::surface::{
    ColorSpace, Coords, Field, Pattern, PatternKind, Shape, Source, TextureImage,
    DEFAULT_RESOLUTION, MAX_SCALE, RESOLUTION_RANGE,
};
use super::MaterialError;

/// An error about source key `key` of field `field`.
pub(super) struct SourceReader<'a> {
    pub path: &'a Path,
    pub layer: usize,
    pub field: Field,
    pub table: &'a Table,
    /// The field's allowed range: a test and its text.
    pub allowed: (&'a dyn Fn(f64) -> bool, &'a str),
    /// The default `range`, where the field's own range holds [0, 1]-like values.
    pub default_range: Option<[f64; 2]>,
}

const PATTERN_KEYS: &[&str] = &[
    "pattern",
    "scale",
    "octaves",
    "seed",
    "threshold",
    "range",
    "coords",
];
const TEXTURE_KEYS: &[&str] = &["texture", "space", "channel", "scale", "range", "coords"];

impl SourceReader<'_> {
    fn error(&self, key: &str, message: impl Into<String>) -> MaterialError {
        MaterialError::Field {
            path: self.path.to_owned(),
            layer: self.layer + 1,
            field: format!("{}.{key}", self.field.key()),
            message: message.into(),
        }
    }

    /// The source this table describes.
    pub fn read(&self) -> Result<Source, MaterialError> {
        let (shape, keys) = match (self.table.get("pattern"), self.table.get("texture")) {
            (Some(_), Some(_)) => {
                return Err(self.error("texture", "give `pattern` or `texture`, not both"))
            }
            (None, None) => {
                return Err(MaterialError::Field {
                    path: self.path.to_owned(),
                    layer: self.layer + 1,
                    field: self.field.key().to_owned(),
                    message: "a table here is a map: give `pattern = \"checker\" | \"noise\" | \
                              \"cells\"` or `texture = \"FILE.png\"`"
                        .into(),
                })
            }
            (Some(_), None) => (Shape::Pattern(self.pattern()?), PATTERN_KEYS),
            (None, Some(_)) => (self.texture()?, TEXTURE_KEYS),
        };
        if let Some(key) = self.table.keys().find(|k| !keys.contains(&k.as_str())) {
            return Err(self.error(
                key,
                format!("unknown key here; allowed: {}", keys.join(", ")),
            ));
        }
        let threshold = self
            .table
            .get("threshold")
            .map(|v| self.number("threshold", v, &|t| (0.0..=1.0).contains(&t), "[0, 1]"))
            .transpose()?;
        let coords = match self.table.get("coords") {
            None => Coords::Uv,
            Some(Value::String(s)) if s == "uv" => Coords::Uv,
            Some(Value::String(s)) if s == "screen" => Coords::Screen,
            Some(other) => {
                return Err(self.error("coords", format!("{other}: allowed: \"uv\", \"screen\"")))
            }
        };
        let mut table = Value::Table(self.table.clone());
        if let (Shape::Texture { image, .. }, Value::Table(t)) = (&shape, &mut table) {
            t.insert(
                "texture".into(),
                Value::String(image.path.to_string_lossy().into_owned()),
            );
        }
        Ok(Source {
            shape,
            threshold,
            range: self.range()?,
            coords,
            table,
        })
    }

    fn number(
        &self,
        key: &str,
        value: &Value,
        allowed: &dyn Fn(f64) -> bool,
        text: &str,
    ) -> Result<f64, MaterialError> {
        let v = match value {
            Value::Float(f) => *f,
            Value::Integer(i) => *i as f64,
            other => {
                return Err(self.error(
                    key,
                    format!("expected a number, found {}", other.type_str()),
                ))
            }
        };
        if !v.is_finite() || !allowed(v) {
            return Err(self.error(key, format!("{v} is out of range; allowed {text}")));
        }
        Ok(v)
    }

    fn integer(&self, key: &str, low: u32, high: u32, default: u32) -> Result<u32, MaterialError> {
        match self.table.get(key) {
            None => Ok(default),
            Some(Value::Integer(i)) if (i64::from(low)..=i64::from(high)).contains(i) => {
                Ok(*i as u32)
            }
            Some(other) => Err(self.error(
                key,
                format!("{other}: allowed: an integer in [{low}, {high}]"),
            )),
        }
    }

    fn pattern(&self) -> Result<Pattern, MaterialError> {
        let kind = match self.table.get("pattern") {
            Some(Value::String(s)) if s == "checker" => PatternKind::Checker,
            Some(Value::String(s)) if s == "noise" => PatternKind::Noise,
            Some(Value::String(s)) if s == "cells" => PatternKind::Cells,
            other => {
                let found = other.map(ToString::to_string).unwrap_or_default();
                return Err(self.error(
                    "pattern",
                    format!("{found}: allowed: \"checker\", \"noise\", \"cells\""),
                ));
            }
        };
        if kind != PatternKind::Noise && self.table.contains_key("octaves") {
            return Err(self.error("octaves", "only a `noise` pattern has octaves"));
        }
        let scale = self.integer("scale", 1, MAX_SCALE, 2)?;
        if kind == PatternKind::Checker && scale % 2 == 1 {
            return Err(self.error(
                "scale",
                format!(
                    "{scale}: a checker tiles without a seam with an even scale (cells per side)"
                ),
            ));
        }
        Ok(Pattern {
            kind,
            scale,
            octaves: self.integer("octaves", 1, 8, 4)?,
            seed: self.integer("seed", 0, u32::MAX, 0)?,
        })
    }

    fn texture(&self) -> Result<Shape, MaterialError> {
        if self.table.contains_key("threshold") {
            return Err(self.error("threshold", "only a pattern has a threshold"));
        }
        let Some(Value::String(name)) = self.table.get("texture") else {
            return Err(self.error("texture", "expected a file name (a string)"));
        };
        let path = self.path.parent().unwrap_or(Path::new(".")).join(name);
        // Absolute, so that the stack written back (`Stack::to_toml`) finds it from anywhere.
        let path = path.canonicalize().unwrap_or(path);
        let space = match self.table.get("space") {
            Some(Value::String(s)) if s == "srgb" => ColorSpace::Srgb,
            Some(Value::String(s)) if s == "linear" => ColorSpace::Linear,
            None => {
                return Err(self.error(
                    "space",
                    "missing: declare the texture's colour space, \"srgb\" or \"linear\"",
                ))
            }
            Some(other) => {
                return Err(self.error("space", format!("{other}: allowed: \"srgb\", \"linear\"")))
            }
        };
        let image = read_texture(&path, space).map_err(|m| self.error("texture", m))?;
        let channel = match (self.field.is_rgb(), self.table.get("channel")) {
            (true, None) => {
                if image.channels < 3 {
                    return Err(self.error(
                        "texture",
                        format!(
                            "{}: {} channel(s); the RGB field `{}` needs an RGB or RGBA image",
                            path.display(),
                            image.channels,
                            self.field.key()
                        ),
                    ));
                }
                None
            }
            (true, Some(_)) => {
                return Err(self.error(
                    "channel",
                    "an RGB field reads R, G and B; `channel` is for scalar fields",
                ))
            }
            (false, None) if image.channels == 1 => Some(0),
            (false, None) => {
                return Err(self.error(
                    "channel",
                    format!(
                        "missing: {} has {} channels; name the one `{}` reads (r, g, b or a)",
                        path.display(),
                        image.channels,
                        self.field.key()
                    ),
                ))
            }
            (false, Some(Value::String(c))) => {
                let index = match c.as_str() {
                    "r" => 0,
                    "g" => 1,
                    "b" => 2,
                    "a" => 3,
                    _ => usize::MAX,
                };
                let available = match image.channels {
                    1 => 1,
                    2 => 4,
                    n => n,
                };
                let grey_alpha_colour = image.channels == 2 && (1..3).contains(&index);
                if index >= available || grey_alpha_colour {
                    return Err(self.error(
                        "channel",
                        format!(
                            "`{c}`: {} has {} channel(s) ({}); allowed: {}",
                            path.display(),
                            image.channels,
                            channel_names(image.channels),
                            channel_names(image.channels)
                        ),
                    ));
                }
                Some(index)
            }
            (false, Some(other)) => {
                return Err(self.error(
                    "channel",
                    format!("{other}: allowed: \"r\", \"g\", \"b\", \"a\""),
                ))
            }
        };
        Ok(Shape::Texture {
            image: Arc::new(image),
            channel,
            scale: self.integer("scale", 1, MAX_SCALE, 1)?,
        })
    }

    /// `range`, or the field's default; each end inside the field's range.
    fn range(&self) -> Result<[[f64; 3]; 2], MaterialError> {
        let (allowed, text) = self.allowed;
        let Some(value) = self.table.get("range") else {
            return match self.default_range {
                Some([lo, hi]) => Ok([[lo; 3], [hi; 3]]),
                None => Err(self.error(
                    "range",
                    format!(
                        "missing: give `range = [low, high]`, the values 0 and 1 map to, in {text}"
                    ),
                )),
            };
        };
        let ends = match value {
            Value::Array(ends) if ends.len() == 2 => ends,
            _ => return Err(self.error("range", format!("expected [low, high], each in {text}"))),
        };
        let mut out = [[0.0; 3]; 2];
        for (o, end) in out.iter_mut().zip(ends) {
            *o = match end {
                Value::Array(rgb) if self.field.is_rgb() && rgb.len() == 3 => {
                    let mut v = [0.0; 3];
                    for (c, x) in v.iter_mut().zip(rgb) {
                        *c = self.number("range", x, allowed, text)?;
                    }
                    v
                }
                Value::Array(_) => {
                    let what = if self.field.is_rgb() {
                        "a number or an RGB array"
                    } else {
                        "a number"
                    };
                    return Err(self.error("range", format!("each end is {what}, in {text}")));
                }
                x => [self.number("range", x, allowed, text)?; 3],
            };
        }
        Ok(out)
    }
}

fn channel_names(channels: usize) -> &'static str {
    match channels {
        1 => "r",
        2 => "r (grey), a",
        3 => "r, g, b",
        _ => "r, g, b, a",
    }
}

/// sRGB's transfer function, decoded.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads a PNG (8 or 16 bits, grey, grey + alpha, RGB, RGBA or palette) or an OpenEXR (R, G,
/// B and optional A) texture into linear values; the message names the file.
pub fn read_texture(path: &Path, space: ColorSpace) -> Result<TextureImage, String> {
    let shown = path.display();
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !path.is_file() {
        return Err(format!("{shown}: no such file"));
    }
    if is_exr {
        if space != ColorSpace::Linear {
            return Err(format!(
                "{shown}: OpenEXR holds linear values; declare space = \"linear\""
            ));
        }
        let meta = exr::meta::MetaData::read_from_file(path, false)
            .map_err(|e| format!("{shown}: not a readable OpenEXR image ({e})"))?;
        let names: Vec<String> = meta.headers[0]
            .channels
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect();
        if !["R", "G", "B"].iter().all(|c| names.iter().any(|n| n == c)) {
            return Err(format!(
                "{shown}: channels {names:?}; an OpenEXR texture needs R, G and B (a grey map: \
                 store it in all three and read `channel = \"r\"`)"
            ));
        }
        let channels = if names.iter().any(|n| n == "A") { 4 } else { 3 };
        let image = crate::imageio::read_exr(path).map_err(|e| e.to_string())?;
        return Ok(TextureImage {
            path: path.to_owned(),
            width: image.width,
            height: image.height,
            channels,
            texels: image.pixels,
        });
    }
    let file = std::fs::File::open(path).map_err(|e| format!("{shown}: {e}"))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("{shown}: not a readable PNG or OpenEXR image ({e})"))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("{shown}: image too large"))?;
    let mut buffer = vec![0; size];
    let info = reader
        .next_frame(&mut buffer)
        .map_err(|e| format!("{shown}: not a readable PNG image ({e})"))?;
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err(format!("{shown}: palette not expanded")),
    };
    let (width, height) = (info.width as usize, info.height as usize);
    if width == 0 || height == 0 {
        return Err(format!("{shown}: image has no pixels"));
    }
    let samples: Vec<f32> = match info.bit_depth {
        png::BitDepth::Sixteen => buffer[..info.buffer_size()]
            .chunks_exact(2)
            .map(|b| f32::from(u16::from_be_bytes([b[0], b[1]])) / 65535.0)
            .collect(),
        _ => buffer[..info.buffer_size()]
            .iter()
            .map(|&b| f32::from(b) / 255.0)
            .collect(),
    };
    let decode = |c: f32| match space {
        ColorSpace::Srgb => srgb_to_linear(c),
        ColorSpace::Linear => c,
    };
    let row = width * channels;
    let texels = (0..width * height)
        .map(|i| {
            let (y, x) = (i / width, i % width);
            let s = &samples[y * row + x * channels..][..channels];
            match channels {
                1 => [decode(s[0]), decode(s[0]), decode(s[0]), 1.0],
                2 => [decode(s[0]), decode(s[0]), decode(s[0]), s[1]],
                3 => [decode(s[0]), decode(s[1]), decode(s[2]), 1.0],
                _ => [decode(s[0]), decode(s[1]), decode(s[2]), s[3]],
            }
        })
        .collect();
    Ok(TextureImage {
        path: path.to_owned(),
        width,
        height,
        channels,
        texels,
    })
}

/// The top-level `map_resolution`, or the default; the error names the file.
pub(super) fn resolution(table: &Table, path: &Path) -> Result<u32, MaterialError> {
    match table.get("map_resolution") {
        None => Ok(DEFAULT_RESOLUTION),
        Some(Value::Integer(i))
            if (i64::from(*RESOLUTION_RANGE.start())..=i64::from(*RESOLUTION_RANGE.end()))
                .contains(i) =>
        {
            Ok(*i as u32)
        }
        Some(other) => Err(MaterialError::File {
            path: path.to_owned(),
            message: format!(
                "`map_resolution`: {other}: allowed: an integer in [{}, {}] (texels per side)",
                RESOLUTION_RANGE.start(),
                RESOLUTION_RANGE.end()
            ),
        }),
    }
}

/// The TOML text of a source's table, inline.
pub(super) fn source_text(source: &Source) -> String {
    source.table.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decodes_the_ends_and_the_middle() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
    }
}
