//! A spatially varying stack's maps on the GPU (`material::surface`): one RGBA32F 2-D array,
//! a slice per varying field, bound as the shading set's `layer_maps`.

use std::sync::Arc;

use crate::error::Result;
use crate::gpu::Gpu;
use crate::material::Surface;
use crate::vk::{upload_image, Format, Image, ImageDesc, ImageState, ImageView};

/// The `SURFACE_MAPS` constant of a pass for a stack with `surface` (0: uniform).
pub fn spec_bits(surface: Option<&Arc<Surface>>) -> u32 {
    surface.map_or(0, |s| s.maps.spec_bits())
}

pub struct SurfaceTexture {
    /// What was uploaded: a later [`SurfaceTexture::holds`] with the same `Arc` reuses it.
    pub surface: Arc<Surface>,
    _image: Image,
    pub view: ImageView,
}

impl SurfaceTexture {
    pub fn upload(gpu: &Gpu, surface: &Arc<Surface>) -> Result<Self> {
        let maps = &surface.maps;
        let n = maps.resolution;
        // A surface always has a slice: a coverage or a varying field made one.
        let layers = maps.slices.len().max(1) as u32;
        let image = Image::new(
            &gpu.device,
            ImageDesc::new_2d_array(Format::R32G32B32A32_SFLOAT, n, n, layers),
            "layer maps",
        )?;
        let texels: Vec<[f32; 4]> = maps.slices.iter().flatten().copied().collect();
        upload_image(
            &gpu.device,
            &image,
            bytemuck::cast_slice(&texels),
            ImageState::FragmentRead,
        )?;
        let view = image.view("layer maps")?;
        Ok(Self {
            surface: surface.clone(),
            _image: image,
            view,
        })
    }

    /// Whether this texture holds `surface`'s maps.
    pub fn holds(&self, surface: &Arc<Surface>) -> bool {
        Arc::ptr_eq(&self.surface, surface) || *self.surface == **surface
    }
}
