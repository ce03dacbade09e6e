//! The layer stack as the shaders read it (`glsl/include/shared/material.glsl`, std140).

use std::mem::{offset_of, size_of};

use crate::model::LayerParams;
use crate::shader::variant::MAX_LAYERS_LIMIT;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LayerGpu {
    pub ior: [f32; 4],
    pub kappa: [f32; 4],
    pub sigma_s: [f32; 4],
    pub sigma_a: [f32; 4],
    /// x: GGX α of the top interface, y: medium depth, z: HG g.
    pub params: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaterialGpu {
    /// x: layer count.
    pub info: [u32; 4],
    pub layers: [LayerGpu; MAX_LAYERS_LIMIT as usize],
}

const _: () = assert!(size_of::<LayerGpu>() == 80);
const _: () = assert!(offset_of!(LayerGpu, params) == 64);
const _: () = assert!(size_of::<MaterialGpu>() == 16 + 80 * MAX_LAYERS_LIMIT as usize);
const _: () = assert!(offset_of!(MaterialGpu, layers) == 16);

impl MaterialGpu {
    /// Packs `layers` (top first); at most [`MAX_LAYERS_LIMIT`] layers, which the material
    /// module's validation guarantees (a caller bug otherwise).
    pub fn new(layers: &[LayerParams]) -> Self {
        assert!(
            layers.len() <= MAX_LAYERS_LIMIT as usize,
            "stack exceeds the buffer"
        );
        let rgb = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0];
        let mut gpu = Self {
            info: [layers.len() as u32, 0, 0, 0],
            layers: [LayerGpu::default(); MAX_LAYERS_LIMIT as usize],
        };
        for (dst, src) in gpu.layers.iter_mut().zip(layers) {
            *dst = LayerGpu {
                ior: rgb(src.ior),
                kappa: rgb(src.kappa),
                sigma_s: rgb(src.sigma_s),
                sigma_a: rgb(src.sigma_a),
                params: [src.roughness as f32, src.depth as f32, src.g as f32, 0.0],
            };
        }
        gpu
    }
}
