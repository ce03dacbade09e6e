//! The scenes: the default unit sphere at the origin seen by a fixed camera, and the
//! full-screen grid the measurements shade (every pixel once).

use glam::camera::rh::{proj, view};
use glam::{Mat4, Vec3};

/// A perspective camera looking at a target, with Vulkan's clip conventions (y down, depth 0..1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub fov_y_degrees: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: Vec3::new(0.0, 0.6, 3.4),
            target: Vec3::ZERO,
            fov_y_degrees: 40.0,
        }
    }
}

impl Camera {
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        // Vulkan clip space: depth 0..1 and y pointing down, so the image is upright and
        // counter-clockwise triangles stay front-facing.
        let proj = proj::vulkan::perspective(self.fov_y_degrees.to_radians(), aspect, 0.05, 100.0);
        proj * view::look_at_mat4(self.eye, self.target, Vec3::Y)
    }

    /// World-space unit direction through the centre of pixel (x, y) of a `width`×`height`
    /// frame, as the sky shader reconstructs its view rays.
    pub fn ray(&self, x: u32, y: u32, width: u32, height: u32) -> Vec3 {
        let inverse = self.view_proj(width as f32 / height as f32).inverse();
        let ndc = glam::Vec4::new(
            2.0 * (x as f32 + 0.5) / width as f32 - 1.0,
            2.0 * (y as f32 + 0.5) / height as f32 - 1.0,
            1.0,
            1.0,
        );
        let far = inverse * ndc;
        (far.truncate() / far.w - self.eye).normalize()
    }
}

/// Interleaved position, normal and texture coordinates, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// Texture coordinates: one unit square over the mesh (the surface maps repeat).
    pub uv: [f32; 2],
}

pub struct Mesh {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
}

/// A UV sphere of radius 1, triangles counter-clockwise seen from outside.
pub fn uv_sphere(stacks: u32, slices: u32) -> Mesh {
    let mut vertices = Vec::new();
    for i in 0..=stacks {
        let theta = std::f32::consts::PI * i as f32 / stacks as f32;
        for j in 0..=slices {
            let phi = std::f32::consts::TAU * j as f32 / slices as f32;
            let p = [
                theta.sin() * phi.sin(),
                theta.cos(),
                theta.sin() * phi.cos(),
            ];
            // u around the pole axis, from 0.5 at φ = 0 (+z, facing the default camera) so
            // that the seam of a texture that does not tile is at the back; v from the north
            // pole down.
            vertices.push(Vertex {
                position: p,
                normal: p,
                uv: [0.5 + j as f32 / slices as f32, i as f32 / stacks as f32],
            });
        }
    }
    let mut indices = Vec::new();
    let row = slices + 1;
    for i in 0..stacks {
        for j in 0..slices {
            let a = i * row + j;
            let (b, c, d) = (a + row, a + 1, a + row + 1);
            if i != 0 {
                indices.extend([a, b, c]);
            }
            if i != stacks - 1 {
                indices.extend([c, b, d]);
            }
        }
    }
    Mesh { vertices, indices }
}

/// What the measured draw shades (`bench --scene`, `scene` in sweep files).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Scene {
    /// The unit sphere of `render` ([`sphere`]) in the default camera's view: about a third of
    /// a 16:9 frame, in 16 128 small triangles.
    #[serde(rename = "sphere")]
    Sphere,
    /// [`full_screen`]: every pixel shaded once, as in the talk's measurements.
    #[serde(rename = "fullscreen")]
    FullScreen,
}

impl Scene {
    pub const NAMES: [&'static str; 2] = ["sphere", "fullscreen"];

    pub fn name(self) -> &'static str {
        match self {
            Self::Sphere => "sphere",
            Self::FullScreen => "fullscreen",
        }
    }

    /// The mesh of this scene seen by `camera` in a `width`×`height` frame.
    pub fn mesh(self, camera: &Camera, width: u32, height: u32) -> Mesh {
        match self {
            Self::Sphere => sphere(),
            Self::FullScreen => full_screen(camera, width, height),
        }
    }

    /// The pixels this scene shades in a `width`×`height` frame seen by `camera`: its mesh's
    /// [`Mesh::coverage`], summed. `width`×`height` for [`Scene::FullScreen`].
    pub fn shaded_pixels(self, camera: &Camera, width: u32, height: u32) -> u64 {
        let view_proj = camera.view_proj(width as f32 / height as f32);
        self.mesh(camera, width, height)
            .coverage(view_proj, width, height)
            .iter()
            .map(|&n| u64::from(n))
            .sum()
    }
}

impl std::fmt::Display for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Scene {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        match text {
            "sphere" => Ok(Self::Sphere),
            "fullscreen" => Ok(Self::FullScreen),
            _ => Err(format!(
                "unknown scene `{text}`; allowed: {}",
                Self::NAMES.join(", ")
            )),
        }
    }
}

/// The default scene's sphere, as `Renderer::new` and the viewer tessellate it.
pub fn sphere() -> Mesh {
    uv_sphere(64, 128)
}

/// Cells per side of [`full_screen`]'s grid.
const FULL_SCREEN_CELLS: u32 = 8;

/// A grid that covers exactly the frame `camera` sees at `width`×`height`, so every pixel is
/// shaded once: a rectangle facing the camera in the plane through its target, cut into
/// `FULL_SCREEN_CELLS`² quads of two counter-clockwise triangles.
///
/// The normals are those of a hemisphere bulging toward the camera, spread over the whole
/// rectangle, so the shading sees the sphere's view cosines, from 1 at the centre to grazing at
/// the frame's border, in about the same proportions. The frame's normalised coordinates
/// `s ∈ [-1, 1]²` go to the unit disk by Shirley and Chiu's concentric map ("A Low Distortion
/// Map Between Disk and Square", 1997), which preserves area up to the factor π/4; the disk
/// point `d` gets the normal `√(1 − |d|²)·v + d.x·a + d.y·b`, with `v` the unit vector from the
/// vertex to the eye and `a`, `b` the camera's right and up made orthogonal to `v`, so that
/// `n·v = √(1 − |d|²)` at every vertex whatever the perspective. Pixels are uniform in `s`,
/// hence in the disk: `|d|²` is uniform on [0, 1] and the view cosine `c` has the density `2c`
/// on [0, 1] — that of a sphere seen from afar, whose outline encloses a uniformly covered disk
/// with `c = √(1 − |d|²)` at the point `d`. An aspect ratio other than 1 stretches the disk into
/// the frame's ellipse without changing the proportions.
///
/// Between vertices the normal is interpolated and renormalised, which pulls a cell toward its
/// most grazing corner; the cosine falls fastest near the border, so the grid lines sit at
/// `sin(π/2·u)` for `u` uniform in [-1, 1], closer together there. With 8 cells the cosine's
/// deciles and quartiles are within 0.03 of the default sphere's at 160x90 (the test
/// `full_screen_sees_the_spheres_cosines`), with 4 % of the pixels below 0.1 against the
/// sphere's 1 % (uniformly spaced lines: about 8 %). The grid is coarse on
/// purpose: each triangle costs the draw a fixed amount (vertex shading, setup), and where an
/// edge crosses one of llvmpipe's 4×4 pixel blocks, both triangles shade the whole block. That
/// cost grows with the frame's side, not its area, so the per-pixel count keeps a share of it
/// (profiling/README.md).
pub fn full_screen(camera: &Camera, width: u32, height: u32) -> Mesh {
    let cells = FULL_SCREEN_CELLS;
    let view_proj = camera.view_proj(width as f32 / height as f32);
    let inverse = view_proj.inverse();
    let target = view_proj * camera.target.extend(1.0);
    let depth = target.z / target.w;
    let forward = (camera.target - camera.eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let mut vertices = Vec::new();
    let line = |k: u32| (std::f32::consts::FRAC_PI_2 * (2.0 * k as f32 / cells as f32 - 1.0)).sin();
    for i in 0..=cells {
        // Vulkan NDC: y points down, row 0 is the top of the frame.
        let y = line(i);
        for j in 0..=cells {
            let x = line(j);
            let p = inverse * glam::Vec4::new(x, y, depth, 1.0);
            let position = p.truncate() / p.w;
            let v = (camera.eye - position).normalize();
            let a = (right - right.dot(v) * v).normalize();
            let b = v.cross(a);
            let d = concentric_disk(x, -y);
            let normal = (1.0 - d.length_squared()).max(0.0).sqrt() * v + d.x * a + d.y * b;
            // Texture coordinates are the frame's: (0, 0) at the top left, (1, 1) at the
            // bottom right, linear in pixels (the rectangle faces the camera).
            vertices.push(Vertex {
                position: position.to_array(),
                normal: normal.normalize().to_array(),
                uv: [0.5 * (x + 1.0), 0.5 * (y + 1.0)],
            });
        }
    }
    let mut indices = Vec::new();
    let row = cells + 1;
    for i in 0..cells {
        for j in 0..cells {
            // a: top left, b: top right, c: bottom left, d: bottom right (on screen).
            let a = i * row + j;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            indices.extend([a, c, b, b, c, d]);
        }
    }
    Mesh { vertices, indices }
}

/// Shirley and Chiu's concentric map of the square [-1, 1]² onto the unit disk: area-preserving
/// up to the factor π/4, the square's border onto the circle.
fn concentric_disk(x: f32, y: f32) -> glam::Vec2 {
    use std::f32::consts::FRAC_PI_4;
    if x == 0.0 && y == 0.0 {
        return glam::Vec2::ZERO;
    }
    let (r, phi) = if x.abs() > y.abs() {
        (x, FRAC_PI_4 * (y / x))
    } else {
        (y, 2.0 * FRAC_PI_4 - FRAC_PI_4 * (x / y))
    };
    glam::Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Sub-pixel precision of [`Mesh::coverage`]: vertices snap to 1/256 pixel (8 bits, as
/// llvmpipe's rasteriser).
const SUBPIXEL: f32 = 256.0;

impl Mesh {
    /// How many front-facing triangles cover each pixel centre of a `width`×`height` frame
    /// seen through `view_proj`, rows top to bottom — the pixels the forward pass shades, and
    /// how often. Vulkan's rasterisation in integers: vertices snapped to 1/256 pixel, a pixel
    /// centre on an edge counted for the triangle whose edge is a top or left edge, back faces
    /// (clockwise on screen) culled. Nothing is clipped: every vertex must lie in front of the
    /// camera, as in lamina's scenes.
    pub fn coverage(&self, view_proj: Mat4, width: u32, height: u32) -> Vec<u32> {
        let (w, h) = (width as usize, height as usize);
        let mut covered = vec![0u32; w * h];
        let snapped: Vec<[i64; 2]> = self
            .vertices
            .iter()
            .map(|v| {
                let clip = view_proj * Vec3::from(v.position).extend(1.0);
                assert!(clip.w > 0.0, "a vertex behind the camera: {v:?}");
                let (x, y) = (clip.x / clip.w, clip.y / clip.w);
                [
                    ((x + 1.0) * 0.5 * width as f32 * SUBPIXEL).round() as i64,
                    ((y + 1.0) * 0.5 * height as f32 * SUBPIXEL).round() as i64,
                ]
            })
            .collect();
        let cross = |a: [i64; 2], b: [i64; 2], p: [i64; 2]| {
            (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
        };
        let half = SUBPIXEL as i64 / 2;
        for tri in self.indices.chunks_exact(3) {
            let (a, mut b, mut c) = (
                snapped[tri[0] as usize],
                snapped[tri[1] as usize],
                snapped[tri[2] as usize],
            );
            // Framebuffer y points down: counter-clockwise on screen is a negative cross
            // product, and front-facing (`FrontFace::COUNTER_CLOCKWISE`).
            if cross(a, b, c) >= 0 {
                continue;
            }
            std::mem::swap(&mut b, &mut c);
            let edges = [(a, b), (b, c), (c, a)];
            // With this winding a top edge runs along +x, a left edge along -y.
            let top_left = edges.map(|(p, q)| {
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                dy < 0 || (dy == 0 && dx > 0)
            });
            let lo = |k: usize| a[k].min(b[k]).min(c[k]);
            let hi = |k: usize| a[k].max(b[k]).max(c[k]);
            // Pixel centres (i + ½) inside the bounding box, clamped to the frame.
            let first = |k: usize| ((lo(k) - half).max(0) + SUBPIXEL as i64 - 1) / SUBPIXEL as i64;
            let last = |k: usize, n: usize| {
                let end = hi(k) - half;
                if end < 0 {
                    -1
                } else {
                    (end / SUBPIXEL as i64).min(n as i64 - 1)
                }
            };
            for y in first(1)..=last(1, h) {
                for x in first(0)..=last(0, w) {
                    let p = [x * SUBPIXEL as i64 + half, y * SUBPIXEL as i64 + half];
                    let inside = edges.iter().zip(top_left).all(|(&(q, r), tl)| {
                        let e = cross(q, r, p);
                        e > 0 || (e == 0 && tl)
                    });
                    if inside {
                        covered[y as usize * w + x as usize] += 1;
                    }
                }
            }
        }
        covered
    }
}

/// A torus around the y axis (ring radius `major`, tube radius `minor`), triangles
/// counter-clockwise seen from outside: the viewer's second mesh, whose saddle and concave
/// regions show the lobes at angles a sphere does not.
pub fn torus(major: f32, minor: f32, rings: u32, sides: u32) -> Mesh {
    let mut vertices = Vec::new();
    for i in 0..=rings {
        let u = std::f32::consts::TAU * i as f32 / rings as f32;
        let (su, cu) = u.sin_cos();
        for j in 0..=sides {
            let v = std::f32::consts::TAU * j as f32 / sides as f32;
            let (sv, cv) = v.sin_cos();
            let normal = [cv * su, sv, cv * cu];
            let r = major + minor * cv;
            vertices.push(Vertex {
                position: [r * su, minor * sv, r * cu],
                normal,
                uv: [i as f32 / rings as f32, j as f32 / sides as f32],
            });
        }
    }
    let mut indices = Vec::new();
    let row = sides + 1;
    for i in 0..rings {
        for j in 0..sides {
            let a = i * row + j;
            let (b, c, d) = (a + row, a + 1, a + row + 1);
            indices.extend([a, b, c, c, b, d]);
        }
    }
    Mesh { vertices, indices }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torus_triangles_face_along_their_normals() {
        let mesh = torus(0.7, 0.3, 24, 16);
        for tri in mesh.indices.chunks(3) {
            let v = |i: u32| mesh.vertices[i as usize];
            let p = |i: u32| Vec3::from(v(i).position);
            let (a, b, c) = (p(tri[0]), p(tri[1]), p(tri[2]));
            let face = (b - a).cross(c - a);
            let normal = Vec3::from(v(tri[0]).normal)
                + Vec3::from(v(tri[1]).normal)
                + Vec3::from(v(tri[2]).normal);
            assert!(face.dot(normal) > 0.0, "inward triangle {tri:?}");
        }
    }

    #[test]
    fn sphere_triangles_face_outwards() {
        let mesh = uv_sphere(16, 32);
        for tri in mesh.indices.chunks(3) {
            let p = |i: u32| Vec3::from(mesh.vertices[i as usize].position);
            let (a, b, c) = (p(tri[0]), p(tri[1]), p(tri[2]));
            let normal = (b - a).cross(c - a);
            assert!(normal.length() > 0.0, "degenerate triangle {tri:?}");
            assert!(normal.dot(a + b + c) > 0.0, "inward triangle {tri:?}");
        }
    }

    /// The view cosine at each pixel centre a front-facing triangle covers, as the forward
    /// pass computes it: normal and position interpolated perspective-correctly, the normal
    /// renormalised, `v` toward the eye.
    fn view_cosines(mesh: &Mesh, camera: &Camera, width: u32, height: u32) -> Vec<f32> {
        let view_proj = camera.view_proj(width as f32 / height as f32);
        let clip: Vec<glam::Vec4> = mesh
            .vertices
            .iter()
            .map(|v| view_proj * Vec3::from(v.position).extend(1.0))
            .collect();
        let screen = |c: glam::Vec4| {
            glam::Vec2::new(
                (c.x / c.w + 1.0) * 0.5 * width as f32,
                (c.y / c.w + 1.0) * 0.5 * height as f32,
            )
        };
        let area = |a: glam::Vec2, b: glam::Vec2, c: glam::Vec2| (b - a).perp_dot(c - a);
        let mut cosines = vec![None; (width * height) as usize];
        for tri in mesh.indices.chunks_exact(3) {
            let k = [tri[0], tri[1], tri[2]].map(|i| i as usize);
            let p = k.map(|i| screen(clip[i]));
            let total = area(p[0], p[1], p[2]);
            // Counter-clockwise on screen (y down) is front-facing: a negative area.
            if total >= 0.0 {
                continue;
            }
            for y in 0..height {
                for x in 0..width {
                    let c = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let l = [
                        area(c, p[1], p[2]) / total,
                        area(p[0], c, p[2]) / total,
                        area(p[0], p[1], c) / total,
                    ];
                    if l.iter().any(|&l| l < 0.0) {
                        continue;
                    }
                    let w = [0, 1, 2].map(|j| l[j] / clip[k[j]].w);
                    let sum = w[0] + w[1] + w[2];
                    let lerp = |f: &dyn Fn(&Vertex) -> [f32; 3]| {
                        (0..3).fold(Vec3::ZERO, |acc, j| {
                            acc + Vec3::from(f(&mesh.vertices[k[j]])) * (w[j] / sum)
                        })
                    };
                    let n = lerp(&|v| v.normal).normalize();
                    let v = (camera.eye - lerp(&|v| v.position)).normalize();
                    cosines[(y * width + x) as usize].get_or_insert(n.dot(v).clamp(1e-4, 1.0));
                }
            }
        }
        cosines.into_iter().flatten().collect()
    }

    fn quantiles(mut cosines: Vec<f32>) -> [f32; 5] {
        cosines.sort_by(f32::total_cmp);
        [0.1, 0.25, 0.5, 0.75, 0.9].map(|q| cosines[((cosines.len() - 1) as f32 * q) as usize])
    }

    #[test]
    fn full_screen_sees_the_spheres_cosines() {
        let camera = Camera::default();
        let (w, h) = (160, 90);
        let cosines = view_cosines(&full_screen(&camera, w, h), &camera, w, h);
        assert_eq!(cosines.len(), (w * h) as usize);
        let (lo, hi) = cosines
            .iter()
            .fold((1.0f32, 0.0f32), |(lo, hi), &c| (lo.min(c), hi.max(c)));
        assert!(lo < 0.02 && hi > 0.999, "cosines span {lo}..{hi}");
        let grazing = |c: &[f32]| c.iter().filter(|&&c| c < 0.1).count() as f32 / c.len() as f32;
        let sphere_cosines = view_cosines(&sphere(), &camera, w, h);
        println!(
            "below 0.1: full screen {:.3}, sphere {:.3}",
            grazing(&cosines),
            grazing(&sphere_cosines)
        );
        let full = quantiles(cosines);
        let sphere = quantiles(sphere_cosines);
        println!("10/25/50/75/90 % quantiles: full screen {full:.3?}, sphere {sphere:.3?}");
        for (f, s) in full.iter().zip(sphere) {
            assert!(
                (f - s).abs() < 0.03,
                "full screen {full:?}, sphere {sphere:?}"
            );
        }
    }

    #[test]
    fn full_screen_covers_every_pixel_once() {
        let camera = Camera::default();
        for (w, h) in [(48, 48), (96, 96), (37, 23), (1, 1), (3, 200), (640, 360)] {
            let view_proj = camera.view_proj(w as f32 / h as f32);
            let coverage = full_screen(&camera, w, h).coverage(view_proj, w, h);
            let wrong = coverage.iter().filter(|&&n| n != 1).count();
            assert_eq!(wrong, 0, "{w}x{h}: {wrong} pixels not covered exactly once");
            let pixels = Scene::FullScreen.shaded_pixels(&camera, w, h);
            assert_eq!(pixels, u64::from(w * h));
        }
    }

    #[test]
    fn coverage_counts_a_shared_edge_once_and_culls_back_faces() {
        // Two triangles on the frame's diagonal, which runs through pixel centres of a square
        // frame: each centre on it goes to exactly one of them.
        let corner = |x: f32, y: f32| Vertex {
            position: [x, y, 0.5],
            normal: [0.0, 0.0, 1.0],
            uv: [0.0; 2],
        };
        let mut mesh = Mesh {
            vertices: vec![
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(-1.0, 1.0),
                corner(1.0, 1.0),
            ],
            // Counter-clockwise on screen (NDC y points down).
            indices: vec![0, 2, 1, 1, 2, 3],
        };
        let coverage = mesh.coverage(Mat4::IDENTITY, 8, 8);
        assert!(coverage.iter().all(|&n| n == 1), "{coverage:?}");
        mesh.indices = vec![0, 1, 2];
        assert!(mesh.coverage(Mat4::IDENTITY, 8, 8).iter().all(|&n| n == 0));
        // The sphere's front faces do not overlap.
        let camera = Camera::default();
        let coverage = sphere().coverage(camera.view_proj(2.0), 64, 32);
        assert!(coverage.iter().all(|&n| n <= 1));
        assert!(coverage.iter().filter(|&&n| n == 1).count() > 200);
    }

    #[test]
    fn scenes_parse_and_print() {
        for name in Scene::NAMES {
            let scene: Scene = name.parse().unwrap();
            assert_eq!(scene.to_string(), name);
            assert_eq!(
                serde_json::to_string(&scene).unwrap(),
                format!("\"{name}\"")
            );
        }
        let e = "cube".parse::<Scene>().unwrap_err();
        assert!(
            e.contains("`cube`") && e.contains("sphere, fullscreen"),
            "{e}"
        );
    }

    #[test]
    fn camera_sees_the_origin_in_the_centre() {
        let clip = Camera::default().view_proj(16.0 / 9.0) * glam::Vec4::new(0.0, 0.0, 0.0, 1.0);
        let ndc = clip / clip.w;
        assert!(ndc.x.abs() < 1e-6 && ndc.y.abs() < 1e-6 && (0.0..1.0).contains(&ndc.z));
        // World up maps to the top of the framebuffer (negative y in Vulkan NDC).
        let up = Camera::default().view_proj(1.0) * glam::Vec4::new(0.0, 0.5, 0.0, 1.0);
        assert!(up.y / up.w < 0.0);
    }
}
