//! `ibl=lamps`: the environment's lamps taken out of the map and lit as analytic disk lights.
//!
//! A studio map holds most of its light in a few small bright regions (the bundled studio:
//! four lamps of 2–6° radius, 85 % of its power). One fetch of a prefiltered cube blurs such a
//! lamp with a kernel of the cube's shape, not the lobe's; a lobe evaluated at the lamp's
//! direction keeps its own shape, its grazing stretch and its peak (`lib/light.glsl`'s
//! `light_lobe`).
//! So the map is split into a residual, which the split sum reads from a cube of its own
//! (`tables::environment`), and lamps:
//!
//! - A texel belongs to a lamp where its luminance exceeds a threshold T, a multiple of the
//!   map's mean ([`THRESHOLDS`]). Its light above T (its colour, scaled to luminance
//!   `lum − T`) goes to the lamp; the residual keeps it scaled to luminance T, so that the
//!   residual and the lamps add up to the map, texel by texel.
//! - The texels above T form connected regions (8-neighbours, wrapping in longitude). A region
//!   is a lamp where it is compact: the disk of its solid angle is at most
//!   [`MAX_LAMP_RADIUS_DEG`]. A larger one (a bright sky) is tried again at the next, higher
//!   threshold, where its brightest core may be compact.
//! - A lamp is the disk light at its excess's mean direction, with the irradiance its excess
//!   brings (Σ excess·dω per channel) and the angular radius of the uniform disk with the same
//!   mean squared angle from that direction (θ²/2). The [`MAX_LAMPS`] brightest that take
//!   at least [`MIN_LAMP_SHARE`] of the map's power are kept; the rest stay in the residual.

use std::collections::VecDeque;
use std::f64::consts::PI;

use glam::DVec3;

use crate::imageio::HdrImage;

use super::environment::{equirect_direction, texel_solid_angle};

pub use crate::variant::LAMP_VALUES;

/// Most lamps an environment gives (each lobe evaluates every slot, dark or not).
pub const MAX_LAMPS: usize = crate::variant::LAMP_SLOTS;

/// The thresholds tried, as multiples of the map's mean luminance, lowest first.
pub const THRESHOLDS: [f64; 4] = [2.0, 8.0, 32.0, 128.0];

/// Largest radius of the disk with a lamp's solid angle, in degrees.
pub const MAX_LAMP_RADIUS_DEG: f64 = 15.0;

/// Least share of the map's luminous power a lamp takes out (smaller regions, a glint or
/// a lit edge, stay in the residual).
pub const MIN_LAMP_SHARE: f64 = 1e-3;

/// Rec. 709 luminance weights.
const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// One lamp: a disk light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lamp {
    /// Unit direction towards the lamp, in the environment's frame.
    pub direction: DVec3,
    /// Irradiance it brings at normal incidence, linear RGB.
    pub irradiance: [f64; 3],
    /// Radius of the disk, radians.
    pub angular_radius: f64,
}

/// The map split into its lamps and the rest.
#[derive(Clone, Debug)]
pub struct Lamps {
    /// Brightest first, at most [`MAX_LAMPS`].
    pub lamps: Vec<Lamp>,
    /// The map without the lamps' light.
    pub residual: HdrImage,
}

fn luminance(p: [f32; 4]) -> f64 {
    (0..3)
        .map(|c| LUMINANCE[c] * f64::from(p[c]).max(0.0))
        .sum()
}

/// `lamps` as an `ibl=lamps` pass holds them: per slot the direction with tan(θ/2) of the
/// angular radius θ (the roughness a disk adds to a lobe, `lib/light.glsl`'s `light_alpha`),
/// then the irradiance and 1; the slots past the lamps all 0, so that a pass specialized to
/// them drops their code.
pub fn lamp_values(lamps: &[Lamp]) -> [f32; LAMP_VALUES] {
    let mut out = [0.0; LAMP_VALUES];
    for (slot, lamp) in out.chunks_exact_mut(8).zip(lamps) {
        let (d, e) = (lamp.direction, lamp.irradiance);
        let t = (0.5 * lamp.angular_radius).tan();
        let v = [d.x, d.y, d.z, t, e[0], e[1], e[2], 1.0];
        slot.iter_mut().zip(v).for_each(|(o, v)| *o = v as f32);
    }
    out
}

/// A region found above a threshold: its texels and that threshold.
struct Region {
    texels: Vec<usize>,
    threshold: f64,
}

/// Splits `equirect` into lamps and the residual (module docs).
pub fn extract(equirect: &HdrImage) -> Lamps {
    let (w, h) = (equirect.width, equirect.height);
    let lum: Vec<f64> = equirect.pixels.iter().map(|&p| luminance(p)).collect();
    let solid: Vec<f64> = (0..h).map(|y| texel_solid_angle(y, w, h)).collect();
    let power: f64 = lum.iter().enumerate().map(|(k, l)| l * solid[k / w]).sum();
    let mean = power / (4.0 * PI);
    let mut found = Vec::new();
    if mean > 0.0 && mean.is_finite() {
        let max_solid = PI * MAX_LAMP_RADIUS_DEG.to_radians().powi(2);
        // Texels no lamp took yet and that lay in a region too large at the last threshold.
        let mut open = vec![true; w * h];
        for t in THRESHOLDS.map(|m| m * mean) {
            let mut seen = vec![false; w * h];
            let mut still_open = vec![false; w * h];
            for start in 0..w * h {
                if seen[start] || !open[start] || lum[start] <= t {
                    continue;
                }
                let texels = flood(start, w, h, &mut seen, |k| open[k] && lum[k] > t);
                let area: f64 = texels.iter().map(|&k| solid[k / w]).sum();
                if area <= max_solid {
                    found.push(Region {
                        texels,
                        threshold: t,
                    });
                } else {
                    texels.iter().for_each(|&k| still_open[k] = true);
                }
            }
            open = still_open;
        }
    }
    let mut lamps: Vec<(f64, Lamp, Region)> = found
        .into_iter()
        .map(|region| {
            let (excess, lamp) = lamp_of(&region, equirect, &lum, &solid);
            (excess, lamp, region)
        })
        .collect();
    lamps.retain(|(excess, _, _)| *excess >= MIN_LAMP_SHARE * power);
    lamps.sort_by(|a, b| b.0.total_cmp(&a.0));
    lamps.truncate(MAX_LAMPS);
    let mut residual = equirect.clone();
    for (_, _, region) in &lamps {
        for &k in &region.texels {
            let keep = (region.threshold / lum[k]) as f32;
            let p = &mut residual.pixels[k];
            for c in p.iter_mut().take(3) {
                *c *= keep;
            }
        }
    }
    Lamps {
        lamps: lamps.into_iter().map(|(_, lamp, _)| lamp).collect(),
        residual,
    }
}

/// The texels connected to `start` (8-neighbours, wrapping in x) for which `inside` holds,
/// marking them in `seen`.
fn flood(
    start: usize,
    w: usize,
    h: usize,
    seen: &mut [bool],
    inside: impl Fn(usize) -> bool,
) -> Vec<usize> {
    let mut texels = Vec::new();
    let mut queue = VecDeque::from([start]);
    seen[start] = true;
    while let Some(k) = queue.pop_front() {
        texels.push(k);
        let (x, y) = ((k % w) as i64, (k / w) as i64);
        for dy in -1..=1 {
            for dx in -1..=1 {
                let ny = y + dy;
                if (dx, dy) == (0, 0) || ny < 0 || ny >= h as i64 {
                    continue;
                }
                let n = ny as usize * w + (x + dx).rem_euclid(w as i64) as usize;
                if !seen[n] && inside(n) {
                    seen[n] = true;
                    queue.push_back(n);
                }
            }
        }
    }
    texels
}

/// A region's lamp and the luminous power of its excess (Σ (lum − T)·dω).
fn lamp_of(region: &Region, image: &HdrImage, lum: &[f64], solid: &[f64]) -> (f64, Lamp) {
    let (w, h) = (image.width, image.height);
    let mut weight = 0.0;
    let mut sum = DVec3::ZERO;
    let mut irradiance = [0.0; 3];
    for &k in &region.texels {
        let d_omega = solid[k / w];
        let share = 1.0 - region.threshold / lum[k];
        let p = image.pixels[k];
        for c in 0..3 {
            irradiance[c] += f64::from(p[c]).max(0.0) * share * d_omega;
        }
        let e = (lum[k] - region.threshold) * d_omega;
        weight += e;
        sum += e * equirect_direction(k % w, k / w, w, h);
    }
    let direction = sum.normalize_or(DVec3::Y);
    let squared: f64 = region
        .texels
        .iter()
        .map(|&k| {
            let d = equirect_direction(k % w, k / w, w, h);
            let angle = d.dot(direction).clamp(-1.0, 1.0).acos();
            (lum[k] - region.threshold) * solid[k / w] * angle * angle
        })
        .sum();
    let angular_radius = (2.0 * squared / weight.max(f64::MIN_POSITIVE)).sqrt();
    (
        weight,
        Lamp {
            direction,
            irradiance,
            angular_radius,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform(w: usize, h: usize, value: f32) -> HdrImage {
        HdrImage {
            width: w,
            height: h,
            pixels: vec![[value, value, value, 1.0]; w * h],
        }
    }

    #[test]
    fn a_uniform_map_has_no_lamps_and_is_its_own_residual() {
        let map = uniform(64, 32, 0.7);
        let split = extract(&map);
        assert!(split.lamps.is_empty());
        assert_eq!(split.residual.pixels, map.pixels);
    }

    #[test]
    fn a_bright_spot_becomes_a_lamp_that_with_the_residual_adds_up_to_the_map() {
        let (w, h) = (256, 128);
        let mut map = uniform(w, h, 0.1);
        // A 3×3 texel spot, warm, around texel (200, 40).
        for y in 39..=41 {
            for x in 199..=201 {
                map.pixels[y * w + x] = [400.0, 300.0, 200.0, 1.0];
            }
        }
        let split = extract(&map);
        assert_eq!(split.lamps.len(), 1);
        let lamp = split.lamps[0];
        let centre = equirect_direction(200, 40, w, h);
        assert!(lamp.direction.dot(centre) > 0.9999, "{:?}", lamp.direction);
        // Light conserved per channel: the map's irradiance-weighted sum equals the
        // residual's plus the lamp's.
        for c in 0..3 {
            let total = |img: &HdrImage| -> f64 {
                (0..w * h)
                    .map(|k| f64::from(img.pixels[k][c]) * texel_solid_angle(k / w, w, h))
                    .sum()
            };
            let (whole, rest) = (total(&map), total(&split.residual));
            let gap = (whole - rest - lamp.irradiance[c]).abs() / whole;
            assert!(
                gap < 1e-5,
                "channel {c}: {whole} vs {rest} + {}",
                lamp.irradiance[c]
            );
        }
        assert!(lamp.irradiance[0] > lamp.irradiance[2]);
        // A spot of 3 texels (about 4.2° across at this size) has a radius of a few degrees.
        let r = lamp.angular_radius.to_degrees();
        assert!(r > 0.5 && r < 4.0, "{r}°");
    }

    #[test]
    fn a_bright_sky_is_not_a_lamp_but_its_sun_is() {
        // A sky of 22.5° around the zenith (rows 0..16), brighter than twice the map's mean
        // and larger than a lamp, with a one-texel sun in it.
        let (w, h) = (256, 128);
        let mut map = uniform(w, h, 0.05);
        for k in 0..w * 16 {
            map.pixels[k] = [1.0, 1.0, 1.0, 1.0];
        }
        map.pixels[8 * w + 60] = [5000.0, 5000.0, 5000.0, 1.0];
        let split = extract(&map);
        assert_eq!(split.lamps.len(), 1, "{:?}", split.lamps);
        assert!(
            split.lamps[0]
                .direction
                .dot(equirect_direction(60, 8, w, h))
                > 0.9999
        );
        assert_eq!(split.residual.pixels[10 * w + 10], map.pixels[10 * w + 10]);
    }

    /// The share of `map`'s luminous power each of its lamps takes (`cargo test --lib lamps --
    /// --nocapture` prints them).
    fn shares(name: &str) -> Vec<(f64, Lamp)> {
        let path = format!("{}/assets/env/{name}.exr", env!("CARGO_MANIFEST_DIR"));
        let map = crate::imageio::read_exr(std::path::Path::new(&path)).unwrap();
        let (w, h) = (map.width, map.height);
        let power: f64 = (0..w * h)
            .map(|k| luminance(map.pixels[k]) * texel_solid_angle(k / w, w, h))
            .sum();
        let split = extract(&map);
        split
            .lamps
            .iter()
            .map(|lamp| {
                let e: f64 = (0..3).map(|c| LUMINANCE[c] * lamp.irradiance[c]).sum();
                let share = e / power;
                println!(
                    "{name}: lamp of {:.2}° towards {:.3}, {:.1} % of the light",
                    lamp.angular_radius.to_degrees(),
                    lamp.direction,
                    100.0 * share
                );
                (share, *lamp)
            })
            .collect()
    }

    #[test]
    fn the_bundled_studio_gives_four_lamps_of_a_few_degrees_and_most_of_its_light() {
        let lamps = shares("studio");
        assert_eq!(lamps.len(), MAX_LAMPS);
        for (_, lamp) in &lamps {
            let r = lamp.angular_radius.to_degrees();
            assert!(r > 1.0 && r < MAX_LAMP_RADIUS_DEG, "{lamp:?}");
        }
        let total: f64 = lamps.iter().map(|(share, _)| share).sum();
        println!("studio: the lamps take {:.1} % of the light", 100.0 * total);
        assert!(total > 0.8, "{total}");
    }

    #[test]
    fn the_bundled_sunset_gives_its_sun_and_leaves_its_sky() {
        let lamps = shares("sunset");
        let (share, sun) = lamps[0];
        assert!(sun.angular_radius.to_degrees() < 5.0, "{sun:?}");
        assert!(share > 0.01 && share < 0.05, "{share}");
    }

    #[test]
    fn the_bundled_courtyard_gives_patches_wider_than_the_studio_lamps() {
        let widest = |name| {
            shares(name)
                .iter()
                .map(|(_, lamp)| lamp.angular_radius)
                .fold(0.0, f64::max)
        };
        assert!(widest("courtyard") > widest("studio"));
    }
}
