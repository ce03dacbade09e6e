//! Per-frame constants shared with GLSL (`glsl/include/shared/frame.glsl`, std140).

use std::mem::{offset_of, size_of};

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameConstants {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    /// xyz: world-space eye.
    pub camera_pos: [f32; 4],
    /// x: mip count of the prefiltered environment.
    pub params: [f32; 4],
}

const _: () = assert!(size_of::<FrameConstants>() == 160);
const _: () = assert!(offset_of!(FrameConstants, inv_view_proj) == 64);
const _: () = assert!(offset_of!(FrameConstants, camera_pos) == 128);
const _: () = assert!(offset_of!(FrameConstants, params) == 144);
