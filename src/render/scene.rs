//! The default scene: a unit sphere at the origin seen by a fixed camera.

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

/// Interleaved position + normal, 24 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
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
            vertices.push(Vertex {
                position: p,
                normal: p,
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
