//! Analytic lights: the lighting description a scene carries besides its environment map
//! (`assets/lights/*.toml`, `--lights`, `--light`), validated, and packed for the shaders
//! (`glsl/include/shared/light.glsl`). How a lobe answers a light: `model::light`.
//!
//! ```toml
//! environment = 1.0          # scale of the environment's light; 0: the lights alone
//! [[light]]
//! kind = "directional"
//! direction = [0.4, 1.0, 0.6]   # towards the light (normalised here)
//! color = [1.0, 0.95, 0.9]      # linear RGB, ≥ 0
//! intensity = 3.0               # irradiance at normal incidence
//! angular_radius = 0.27         # degrees (the sun); 0: an ideal directional light
//! [[light]]
//! kind = "point"
//! position = [2.0, 2.0, 3.0]
//! intensity = 20.0              # radiant intensity: irradiance intensity / distance²
//! ```

use std::path::{Path, PathBuf};

use toml::{Table, Value};

use crate::error::{Error, Result};
use crate::shader::interface::LightGpu;

/// Most lights a scene holds (the light buffer's size is the scene's own; this bounds the
/// per-pixel loop a user can ask for).
pub const MAX_LIGHTS: usize = 16;

/// Largest angular radius of a directional light, in degrees.
pub const MAX_ANGULAR_RADIUS_DEG: f64 = 45.0;

/// Largest intensity and environment scale accepted: beyond, a half-float target overflows.
pub const MAX_INTENSITY: f64 = 1e4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Light from a direction (unit, towards the light), from a disk of this angular radius
    /// (radians).
    Directional {
        direction: [f64; 3],
        angular_radius: f64,
    },
    /// Light from a point.
    Point { position: [f64; 3] },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub kind: LightKind,
    pub color: [f64; 3],
    pub intensity: f64,
}

/// What lights a scene: the environment map, scaled, and analytic lights.
#[derive(Clone, Debug, PartialEq)]
pub struct Lighting {
    /// Scale of the environment's light (1: as the map says; 0: lights only).
    pub environment: f64,
    pub lights: Vec<Light>,
}

impl Default for Lighting {
    /// The environment alone: what lamina rendered before it had lights.
    fn default() -> Self {
        Self {
            environment: 1.0,
            lights: Vec::new(),
        }
    }
}

/// The bundled lighting presets (`assets/lights/NAME.toml`).
pub const PRESETS: &[&str] = &["sun", "studio-keys", "sun-only"];

const TOP_KEYS: &[&str] = &["environment", "light"];
const DIRECTIONAL_KEYS: &[&str] = &["kind", "direction", "color", "intensity", "angular_radius"];
const POINT_KEYS: &[&str] = &["kind", "position", "color", "intensity"];

impl Lighting {
    /// Reads a lighting file, or a preset's (`sun`, …) from `assets/lights/`.
    pub fn load(name_or_path: &str) -> Result<Self> {
        let path = resolve(name_or_path);
        let text = std::fs::read_to_string(&path).map_err(|e| Error::Input {
            path: path.clone(),
            message: if PRESETS.contains(&name_or_path) || !name_or_path.ends_with(".toml") {
                format!(
                    "cannot read ({e}); lighting presets: {}",
                    PRESETS.join(", ")
                )
            } else {
                format!("cannot read: {e}")
            },
        })?;
        Self::parse(&text, &path)
    }

    /// Parses and validates a lighting document; errors name `path`, the light and the field.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let input = |message: String| Error::Input {
            path: path.to_owned(),
            message,
        };
        let table: Table = text
            .parse()
            .map_err(|e: toml::de::Error| input(format!("not valid TOML: {}", e.message())))?;
        if let Some(key) = table.keys().find(|k| !TOP_KEYS.contains(&k.as_str())) {
            return Err(input(format!(
                "`{key}`: unknown key; top-level keys are {}",
                TOP_KEYS.join(", ")
            )));
        }
        let environment = match table.get("environment") {
            None => 1.0,
            Some(value) => number(value, 0.0, MAX_INTENSITY)
                .map_err(|m| input(format!("`environment`: {m}")))?,
        };
        let lights = match table.get("light") {
            None => Vec::new(),
            Some(Value::Array(items)) => {
                if items.len() > MAX_LIGHTS {
                    return Err(input(format!(
                        "`light`: {} lights; a scene holds at most {MAX_LIGHTS}",
                        items.len()
                    )));
                }
                items
                    .iter()
                    .enumerate()
                    .map(|(i, item)| match item {
                        Value::Table(t) => {
                            read_light(t).map_err(|m| input(format!("light {}: {m}", i + 1)))
                        }
                        other => Err(input(format!(
                            "light {}: expected a [[light]] table, found {}",
                            i + 1,
                            other.type_str()
                        ))),
                    })
                    .collect::<Result<_>>()?
            }
            Some(other) => {
                return Err(input(format!(
                    "`light`: write [[light]] tables, found {}",
                    other.type_str()
                )))
            }
        };
        Ok(Self {
            environment,
            lights,
        })
    }

    /// Adds lights given on the command line (`--light`, [`Light::parse_arg`]).
    pub fn with_lights(mut self, extra: &[Light]) -> Result<Self> {
        self.lights.extend_from_slice(extra);
        if self.lights.len() > MAX_LIGHTS {
            return Err(Error::Unsupported(format!(
                "{} lights; a scene holds at most {MAX_LIGHTS}",
                self.lights.len()
            )));
        }
        Ok(self)
    }

    /// The lighting as a lighting file ([`Lighting::parse`] reads it back): what result files
    /// record and the instruction counter's worker receives.
    pub fn to_toml(&self) -> String {
        let v = |v: [f64; 3]| format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2]);
        let mut out = format!("environment = {:?}\n", self.environment);
        for light in &self.lights {
            out.push_str("\n[[light]]\n");
            match light.kind {
                LightKind::Directional {
                    direction,
                    angular_radius,
                } => {
                    out.push_str("kind = \"directional\"\n");
                    out.push_str(&format!("direction = {}\n", v(direction)));
                    out.push_str(&format!(
                        "angular_radius = {:?}\n",
                        angular_radius.to_degrees()
                    ));
                }
                LightKind::Point { position } => {
                    out.push_str("kind = \"point\"\n");
                    out.push_str(&format!("position = {}\n", v(position)));
                }
            }
            out.push_str(&format!("color = {}\n", v(light.color)));
            out.push_str(&format!("intensity = {:?}\n", light.intensity));
        }
        out
    }
}

impl Light {
    /// A light from the command line: `directional:X,Y,Z[:INTENSITY[:RADIUS_DEG]]` or
    /// `point:X,Y,Z[:INTENSITY]` (white), or a TOML inline table with a light's keys
    /// (`{kind = "point", position = [1, 2, 3], color = [1, 0.5, 0.2], intensity = 8}`).
    pub fn parse_arg(text: &str) -> std::result::Result<Self, String> {
        let text = text.trim();
        if text.starts_with('{') {
            let table: Table = format!("light = {text}")
                .parse::<Table>()
                .map_err(|e| format!("`{text}`: not a TOML inline table: {}", e.message()))?;
            return match table.get("light") {
                Some(Value::Table(t)) => read_light(t),
                _ => Err(format!("`{text}`: not a TOML inline table")),
            };
        }
        let usage = "write directional:X,Y,Z[:INTENSITY[:RADIUS_DEG]], point:X,Y,Z[:INTENSITY] \
                     or a TOML inline table";
        let mut parts = text.split(':');
        let kind = parts.next().unwrap_or_default();
        let vector = parts
            .next()
            .ok_or_else(|| format!("`{text}`: {usage}"))?
            .split(',')
            .map(|c| {
                c.trim()
                    .parse::<f64>()
                    .map_err(|_| format!("`{text}`: `{c}` is not a number; {usage}"))
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let scalar = |part: Option<&str>, default: f64| match part {
            None => Ok(default),
            Some(p) => p
                .trim()
                .parse::<f64>()
                .map_err(|_| format!("`{text}`: `{p}` is not a number; {usage}")),
        };
        let intensity = scalar(parts.next(), 1.0)?;
        let radius = scalar(parts.next(), 0.0)?;
        if parts.next().is_some() {
            return Err(format!("`{text}`: too many fields; {usage}"));
        }
        let mut table = Table::new();
        table.insert("kind".into(), Value::String(kind.into()));
        let vector = Value::Array(vector.into_iter().map(Value::Float).collect());
        match kind {
            "directional" => {
                table.insert("direction".into(), vector);
                table.insert("angular_radius".into(), Value::Float(radius));
            }
            "point" => {
                if radius != 0.0 {
                    return Err(format!("`{text}`: a point light has no radius; {usage}"));
                }
                table.insert("position".into(), vector);
            }
            _ => return Err(format!("`{text}`: unknown light `{kind}`; {usage}")),
        }
        table.insert("intensity".into(), Value::Float(intensity));
        read_light(&table)
    }
}

/// A preset's file, relative to the working directory first and then in the source tree (as
/// material presets are found); anything else is a path.
fn resolve(name_or_path: &str) -> PathBuf {
    if !PRESETS.contains(&name_or_path) {
        return PathBuf::from(name_or_path);
    }
    let file = format!("assets/lights/{name_or_path}.toml");
    let local = PathBuf::from(&file);
    if local.is_file() {
        local
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(file)
    }
}

/// A finite number in [low, high].
fn number(value: &Value, low: f64, high: f64) -> std::result::Result<f64, String> {
    let x = match value {
        Value::Float(x) => *x,
        Value::Integer(i) => *i as f64,
        other => return Err(format!("expected a number, found {}", other.type_str())),
    };
    if !x.is_finite() {
        return Err(format!("{x} is not finite; allowed {low} … {high}"));
    }
    if !(low..=high).contains(&x) {
        return Err(format!("{x} is out of range; allowed {low} … {high}"));
    }
    Ok(x)
}

/// Three finite numbers, each in [low, high].
fn vector(table: &Table, key: &str, low: f64, high: f64) -> std::result::Result<[f64; 3], String> {
    let items = match table.get(key) {
        Some(Value::Array(items)) if items.len() == 3 => items,
        Some(Value::Array(items)) => {
            return Err(format!("`{key}`: {} numbers; needs 3", items.len()))
        }
        Some(other) => {
            return Err(format!(
                "`{key}`: expected 3 numbers, found {}",
                other.type_str()
            ))
        }
        None => return Err(format!("`{key}`: missing")),
    };
    let mut out = [0.0; 3];
    for (o, item) in out.iter_mut().zip(items) {
        *o = number(item, low, high).map_err(|m| format!("`{key}`: {m}"))?;
    }
    Ok(out)
}

fn read_light(table: &Table) -> std::result::Result<Light, String> {
    let kind = match table.get("kind") {
        Some(Value::String(s)) => s.as_str(),
        Some(other) => {
            return Err(format!(
                "`kind`: expected a string, found {}",
                other.type_str()
            ))
        }
        None => return Err("`kind`: missing; allowed \"directional\", \"point\"".into()),
    };
    let keys = match kind {
        "directional" => DIRECTIONAL_KEYS,
        "point" => POINT_KEYS,
        other => {
            return Err(format!(
                "`kind`: `{other}`; allowed \"directional\", \"point\""
            ))
        }
    };
    if let Some(key) = table.keys().find(|k| !keys.contains(&k.as_str())) {
        return Err(format!(
            "`{key}`: unknown key for a {kind} light; keys are {}",
            keys.join(", ")
        ));
    }
    let color = match table.get("color") {
        None => [1.0; 3],
        Some(_) => vector(table, "color", 0.0, MAX_INTENSITY)?,
    };
    let intensity = match table.get("intensity") {
        None => 1.0,
        Some(v) => number(v, 0.0, MAX_INTENSITY).map_err(|m| format!("`intensity`: {m}"))?,
    };
    let kind = if kind == "directional" {
        let d = vector(table, "direction", -1e6, 1e6)?;
        let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if length < 1e-9 {
            return Err("`direction`: the zero vector has no direction".into());
        }
        let radius = match table.get("angular_radius") {
            None => 0.0,
            Some(v) => number(v, 0.0, MAX_ANGULAR_RADIUS_DEG)
                .map_err(|m| format!("`angular_radius` (degrees): {m}"))?,
        };
        LightKind::Directional {
            direction: d.map(|c| c / length),
            angular_radius: radius.to_radians(),
        }
    } else {
        LightKind::Point {
            position: vector(table, "position", -1e6, 1e6)?,
        }
    };
    Ok(Light {
        kind,
        color,
        intensity,
    })
}

/// The `Lights` block of `bindings/scene.glsl`: a `uvec4` header (x: count) and the lights,
/// as bytes. One zeroed light follows an empty list, so the buffer is never smaller than the
/// block's declared minimum.
pub fn lights_block(lights: &[Light]) -> Vec<u8> {
    let mut bytes = bytemuck::bytes_of(&[lights.len() as u32, 0, 0, 0]).to_vec();
    let packed: Vec<LightGpu> = lights
        .iter()
        .map(|light| {
            let c = light.color.map(|c| (c * light.intensity) as f32);
            let (position, radius) = match light.kind {
                LightKind::Directional {
                    direction,
                    angular_radius,
                } => (direction.map(|d| d as f32), angular_radius as f32),
                LightKind::Point { position } => (position.map(|p| p as f32), 0.0),
            };
            let w = if matches!(light.kind, LightKind::Point { .. }) {
                1.0
            } else {
                0.0
            };
            LightGpu {
                position: [position[0], position[1], position[2], w],
                radiance: [c[0], c[1], c[2], radius],
            }
        })
        .chain(lights.is_empty().then(LightGpu::default))
        .collect();
    bytes.extend_from_slice(bytemuck::cast_slice(&packed));
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> std::result::Result<Lighting, String> {
        Lighting::parse(text, Path::new("scene.toml")).map_err(|e| e.to_string())
    }

    #[test]
    fn a_lighting_file_reads_and_normalises() {
        let l = parse(
            "environment = 0.5\n[[light]]\nkind = \"directional\"\ndirection = [0, 2, 0]\n\
             angular_radius = 0.5\n[[light]]\nkind = \"point\"\nposition = [1, 2, 3]\n\
             intensity = 4\ncolor = [1, 0.5, 0]\n",
        )
        .unwrap();
        assert_eq!(l.environment, 0.5);
        assert_eq!(
            l.lights[0].kind,
            LightKind::Directional {
                direction: [0.0, 1.0, 0.0],
                angular_radius: 0.5_f64.to_radians()
            }
        );
        assert_eq!(l.lights[1].intensity, 4.0);
        assert_eq!(l.lights[1].color, [1.0, 0.5, 0.0]);
    }

    #[test]
    fn a_lighting_survives_its_toml() {
        let l = Lighting::load("studio-keys").unwrap();
        let back = Lighting::parse(&l.to_toml(), Path::new("x.toml")).unwrap();
        assert_eq!(back.lights.len(), l.lights.len());
        for (a, b) in back.lights.iter().zip(&l.lights) {
            assert_eq!(a.color, b.color);
            assert_eq!(a.intensity, b.intensity);
            match (a.kind, b.kind) {
                (LightKind::Point { position: p }, LightKind::Point { position: q }) => {
                    assert_eq!(p, q)
                }
                (
                    LightKind::Directional {
                        direction: d,
                        angular_radius: r,
                    },
                    LightKind::Directional {
                        direction: e,
                        angular_radius: s,
                    },
                ) => {
                    assert!((r - s).abs() < 1e-15);
                    for c in 0..3 {
                        assert!((d[c] - e[c]).abs() < 1e-15);
                    }
                }
                _ => panic!("kinds differ"),
            }
        }
    }

    #[test]
    fn bad_lights_are_refused_by_name() {
        let cases = [
            (
                "[[light]]\nkind = \"directional\"\ndirection = [0, 0, 0]\n",
                "light 1: `direction`: the zero vector",
            ),
            (
                "[[light]]\nkind = \"directional\"\ndirection = [0, nan, 1]\n",
                "light 1: `direction`: NaN is not finite",
            ),
            (
                "[[light]]\nkind = \"directional\"\ndirection = [0, inf, 1]\n",
                "`direction`: inf is not finite",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [0, 1]\n",
                "`position`: 2 numbers; needs 3",
            ),
            ("[[light]]\nkind = \"spot\"\n", "`kind`: `spot`"),
            (
                "[[light]]\nkind = \"point\"\nposition = [0, 1, 2]\nintensity = -1\n",
                "`intensity`: -1 is out of range",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [0, 1, 2]\nangular_radius = 1\n",
                "`angular_radius`: unknown key for a point light",
            ),
            (
                "[[light]]\nkind = \"directional\"\ndirection = [0, 1, 0]\nangular_radius = 90\n",
                "`angular_radius` (degrees): 90 is out of range; allowed 0 … 45",
            ),
            ("environment = -2\n", "`environment`: -2 is out of range"),
            ("lights = 2\n", "`lights`: unknown key"),
        ];
        for (text, expected) in cases {
            let err = parse(text).unwrap_err();
            assert!(err.starts_with("scene.toml: "), "{err}");
            assert!(err.contains(expected), "{text:?}: {err}");
        }
    }

    #[test]
    fn command_line_lights_parse_both_forms() {
        let d = Light::parse_arg("directional:0,1,0:3:0.27").unwrap();
        assert_eq!(d.intensity, 3.0);
        assert!(
            matches!(d.kind, LightKind::Directional { angular_radius, .. }
            if (angular_radius - 0.27_f64.to_radians()).abs() < 1e-15)
        );
        let p =
            Light::parse_arg("{kind = \"point\", position = [1, 2, 3], intensity = 8}").unwrap();
        assert_eq!(
            p.kind,
            LightKind::Point {
                position: [1.0, 2.0, 3.0]
            }
        );
        for (bad, expected) in [
            ("directional:0,0,0", "zero vector"),
            ("sphere:0,1,0", "unknown light `sphere`"),
            ("point:1,2,3:1:5", "a point light has no radius"),
            ("directional:a,1,0", "`a` is not a number"),
            ("directional:0,1,0:nan", "NaN is not finite"),
        ] {
            let err = Light::parse_arg(bad).unwrap_err();
            assert!(err.contains(expected), "{bad}: {err}");
        }
    }
}
