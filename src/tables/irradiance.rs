//! The irradiance E(n) = ∫ L(ω) max(n·ω, 0) dω of an equirectangular environment, which
//! lights a diffuse base: as order-2 spherical harmonics ([`irradiance_sh`], the frame
//! constants of every pass but `ibl=lamps`'s), and summed exactly into a small cube
//! ([`irradiance_cube`]), which an `ibl=lamps` pass reads for the map without its lamps.

use std::f64::consts::PI;

use glam::DVec3;

use crate::imageio::HdrImage;

use super::environment::{cube_direction, equirect_direction, texel_solid_angle};

/// The real spherical harmonics of order ≤ 2 at unit direction `d`, in the order Y00, Y1−1,
/// Y10, Y11, Y2−2, Y2−1, Y20, Y21, Y22 (Ramamoorthi & Hanrahan 2001, eq. 3; the constants of
/// `ibl_irradiance` in `glsl/include/lib/ibl.glsl`).
pub fn sh9(d: DVec3) -> [f64; 9] {
    [
        0.282095,
        0.488603 * d.y,
        0.488603 * d.z,
        0.488603 * d.x,
        1.092548 * d.x * d.y,
        1.092548 * d.y * d.z,
        0.315392 * (3.0 * d.z * d.z - 1.0),
        1.092548 * d.x * d.z,
        0.546274 * (d.x * d.x - d.y * d.y),
    ]
}

/// The irradiance E(n) = ∫ L(ω) max(n·ω, 0) dω of an equirectangular environment, as the
/// coefficients of its order-2 spherical harmonics, each times its band's cosine-lobe factor
/// Â_l = π, 2π/3, π/4 (Ramamoorthi & Hanrahan, "An Efficient Representation for Irradiance
/// Environment Maps", 2001): E(n) = Σ_k c_k·Y_k(n), within about 1 % of the exact convolution
/// for natural lighting (their §3; exact for a uniform environment). Projected by summing every
/// texel, each the solid angle it spans (2π/W)(π/H)·sin θ, the direction through its centre by
/// [`equirect_uv`]'s mapping.
pub fn irradiance_sh(equirect: &HdrImage) -> [[f32; 4]; 9] {
    let (w, h) = (equirect.width, equirect.height);
    let mut sum = [[0.0f64; 3]; 9];
    for y in 0..h {
        let d_omega = texel_solid_angle(y, w, h);
        for x in 0..w {
            let d = equirect_direction(x, y, w, h);
            let p = equirect.pixel(x, y);
            for (k, y_k) in sh9(d).iter().enumerate() {
                for c in 0..3 {
                    sum[k][c] += f64::from(p[c]) * y_k * d_omega;
                }
            }
        }
    }
    let band = [PI, 2.0 * PI / 3.0, PI / 4.0];
    std::array::from_fn(|k| {
        let a = band[if k == 0 {
            0
        } else if k < 4 {
            1
        } else {
            2
        }];
        [
            (a * sum[k][0]) as f32,
            (a * sum[k][1]) as f32,
            (a * sum[k][2]) as f32,
            0.0,
        ]
    })
}

/// Texels per face of the lamps' irradiance cube ([`irradiance_cube`]): 2.8° apart, where the
/// irradiance changes over the cosine lobe's 90°.
pub const IRRADIANCE_FACE: u32 = 32;

/// Columns and rows of the cells [`irradiance_cube`] sums over: 2.8° apart.
const IRRADIANCE_CELLS: (usize, usize) = (128, 64);

/// The irradiance E(n) = ∫ L(ω) max(n·ω, 0) dω of an equirectangular environment at the
/// centre of each texel of a cube of `face` texels a side, as RGBA f32 (alpha 1), face-major
/// in Vulkan order, rows top to bottom ([`cube_direction`]'s mapping). Exact where
/// [`irradiance_sh`]'s order-2 harmonics ring, up to its cells: a sum over
/// [`IRRADIANCE_CELLS`] equirect cells, each its power L·dω at its power-weighted mean
/// direction (a lamp's own where one lies in the cell). A map finer than the cells is summed
/// into them texel by texel, a coarser one split into them.
pub fn irradiance_cube(equirect: &HdrImage, face: u32) -> Vec<[f32; 4]> {
    use rayon::prelude::*;
    let (w, h) = (equirect.width, equirect.height);
    let (cols, rows) = IRRADIANCE_CELLS;
    // The finer of the map and the cells: each of its points one texel's radiance.
    let (fine_w, fine_h) = (w.max(cols), h.max(rows));
    let mut cells = vec![(DVec3::ZERO, [0.0f64; 3]); cols * rows];
    for y in 0..fine_h {
        let d_omega = texel_solid_angle(y, fine_w, fine_h);
        for x in 0..fine_w {
            let p = equirect.pixel(x * w / fine_w, y * h / fine_h);
            let weight = f64::from(p[0] + p[1] + p[2]).max(1e-6) * d_omega;
            let (dir, power) = &mut cells[(y * rows / fine_h) * cols + x * cols / fine_w];
            *dir += equirect_direction(x, y, fine_w, fine_h) * weight;
            for c in 0..3 {
                power[c] += f64::from(p[c]) * d_omega;
            }
        }
    }
    let cells: Vec<(DVec3, [f64; 3])> = cells
        .into_iter()
        .map(|(dir, power)| (dir.normalize_or_zero(), power))
        .collect();
    let texels = (face * face) as usize;
    (0..6 * texels)
        .into_par_iter()
        .map(|k| {
            let (f, i) = ((k / texels) as u32, k % texels);
            let (x, y) = ((i % face as usize) as f64, (i / face as usize) as f64);
            let n = cube_direction(f, (x + 0.5) / f64::from(face), (y + 0.5) / f64::from(face));
            let mut e = [0.0f64; 3];
            for (d, power) in &cells {
                let cos = n.dot(*d);
                if cos > 0.0 {
                    for c in 0..3 {
                        e[c] += power[c] * cos;
                    }
                }
            }
            [e[0] as f32, e[1] as f32, e[2] as f32, 1.0]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w`×`h` equirect map of radiance `f(d)` (grey) at each texel's centre.
    fn map_of(w: usize, h: usize, f: impl Fn(DVec3) -> f64) -> HdrImage {
        let pixels = (0..w * h)
            .map(|k| {
                let v = f(equirect_direction(k % w, k / w, w, h)) as f32;
                [v, v, v, 1.0]
            })
            .collect();
        HdrImage {
            width: w,
            height: h,
            pixels,
        }
    }

    /// Each texel's normal and its value in `irradiance_cube`'s (grey) cube.
    fn cube_texels(cube: &[[f32; 4]], face: u32) -> impl Iterator<Item = (DVec3, f64)> + '_ {
        let texels = (face * face) as usize;
        cube.iter().enumerate().map(move |(k, e)| {
            let (f, i) = ((k / texels) as u32, (k % texels) as u32);
            let (u, v) = (f64::from(i % face) + 0.5, f64::from(i / face) + 0.5);
            let n = cube_direction(f, u / f64::from(face), v / f64::from(face));
            (n, f64::from(e[0]))
        })
    }

    /// The (grey) irradiance `irradiance_sh`'s coefficients give at normal `n`.
    fn grey_harmonics_at(sh: &[[f32; 4]; 9], n: DVec3) -> f64 {
        sh9(n)
            .iter()
            .zip(sh)
            .map(|(y, c)| y * f64::from(c[0]))
            .sum()
    }

    #[test]
    fn the_irradiance_cube_of_a_linear_map_is_its_exact_irradiance_within_its_cells() {
        // L(ω) = 1 + b·ω: E(n) = π + (2π/3) b·n, which the order-2 harmonics hold exactly too.
        // The cube's cells that the normal's horizon cuts count whole: within 0.2 %.
        let b = DVec3::new(0.25, 0.5, -0.125);
        let map = map_of(512, 256, |d| 1.0 + b.dot(d));
        let cube = irradiance_cube(&map, IRRADIANCE_FACE);
        assert_eq!(cube.len(), 6 * (IRRADIANCE_FACE * IRRADIANCE_FACE) as usize);
        let sh = irradiance_sh(&map);
        let mut worst = 0.0f64;
        for (n, e) in cube_texels(&cube, IRRADIANCE_FACE) {
            let exact = PI + 2.0 * PI / 3.0 * b.dot(n);
            let harmonics = grey_harmonics_at(&sh, n);
            assert!(
                (harmonics - exact).abs() < 1e-3 * exact,
                "{n}: {harmonics} {exact}"
            );
            worst = worst.max((e - exact).abs() / exact);
        }
        assert!(worst < 2e-3, "worst relative error {worst}");
    }

    #[test]
    fn the_irradiance_cube_holds_a_small_lamp_that_the_harmonics_ring_around() {
        // A 3° lamp of radiance 400 over a sky of 0.1: away from the lamp's horizon the
        // irradiance is π·0.1 plus the lamp's power times n·d.
        let lamp = DVec3::new(0.3, 0.8, -0.5).normalize();
        let cos_radius = 3f64.to_radians().cos();
        let map = map_of(
            512,
            256,
            |d| if d.dot(lamp) > cos_radius { 400.0 } else { 0.1 },
        );
        let (w, h) = (map.width, map.height);
        let power: f64 = (0..w * h)
            .filter(|k| equirect_direction(k % w, k / w, w, h).dot(lamp) > cos_radius)
            .map(|k| (400.0 - 0.1) * texel_solid_angle(k / w, w, h))
            .sum();
        let cube = irradiance_cube(&map, IRRADIANCE_FACE);
        let sh = irradiance_sh(&map);
        let (mut worst, mut worst_sh) = (0.0f64, 0.0f64);
        for (n, e) in cube_texels(&cube, IRRADIANCE_FACE) {
            let cos = n.dot(lamp);
            if cos.abs() < 0.1 {
                continue;
            }
            let exact = PI * 0.1 + power * cos.max(0.0);
            let harmonics = grey_harmonics_at(&sh, n);
            worst = worst.max((e - exact).abs() / exact);
            worst_sh = worst_sh.max((harmonics - exact).abs() / exact);
        }
        assert!(worst < 5e-3, "cube: worst relative error {worst}");
        assert!(worst_sh > 0.5, "harmonics: worst relative error {worst_sh}");
    }
}
