//! Environment lighting: equirectangular EXR → cube map → GGX-prefiltered mips.
//!
//! 1. The equirect map is uploaded as RGBA16F and resampled into mip 0 of a source cube by
//!    `equirect_to_cube.comp.glsl`; the source cube's other mips are box-filtered blits.
//! 2. The prefiltered cube copies the source's mip 0 (α = 0 is a mirror) and fills mip m ≥ 1
//!    with `prefilter.comp.glsl` at α = (m / (M − 1))², the mapping `lib/ibl.glsl` reads back.
//!    The filter importance-samples D and reads the source mip matching each sample's solid
//!    angle, so a few dozen samples give a smooth lobe. It weighs its samples by n·l and reads
//!    a source mip one level blurrier than their solid angle, as Karis 2013 does.
//! 3. The matched cube ([`Weighting::Matched`], which `ibl=matched` and `ibl=taps` read) is
//!    built the same way the first time a pass needs it, from the source cube kept for it, but
//!    weighs each sample by the lobe's own G2 at normal view (the BRDF times the cosine over
//!    D's pdf), reads the source mip of its solid angle, and takes [`MATCHED_SAMPLES`] times
//!    the samples. Its levels are spaced in log α ([`matched_alpha_of_mip`]).
//! 4. The lamps' cube (`ibl=lamps`) is built the first time a pass needs it: the map without
//!    its lamps ([`crate::tables::lamps`]) converted to a source cube of its own, its mips 0
//!    and 1 the whole map's (a sharp lobe reads each lamp's own shape there). It is
//!    prefiltered as the matched cube is, at the levels of Karis's, so that `ibl=lamps` reads
//!    it with the split sum's fetch: Karis's blurrier source mips spread a lamp over the dark
//!    around it, which a near-mirror lobe reading mip 1 saw (profiling/README.md). With it the
//!    host sums the rest's irradiance into a small cube ([`irradiance_cube`]), which lights a
//!    diffuse base under `ibl=lamps` where the others read the order-2 harmonics.

use std::f64::consts::PI;

use glam::DVec3;
use half::f16;

use crate::error::{Error, Result};
use crate::gpu::{ComputeKernel, Gpu};
use crate::imageio::HdrImage;
use crate::shader::kernel::{KernelInterface, KernelSpec, LOCAL_SIZE_2D};
use crate::tables::irradiance::{irradiance_cube, irradiance_sh, IRRADIANCE_FACE};
use crate::tables::lamps::{self, Lamp, Lamps};
use crate::vk::{
    submit_and_wait, upload_image, BindingKind, Buffer, BufferUsageFlags, DescriptorSet, Format,
    Image, ImageDesc, ImageState, ImageUsageFlags, ImageView, Recorder, Resource, Sampler,
    SamplerDesc,
};

/// Size and quality of the prefiltered cube.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnvDesc {
    pub face_size: u32,
    /// Mips of the prefiltered cube: roughness r = mip / (mip_count − 1).
    pub mip_count: u32,
    /// GGX samples per prefiltered texel.
    pub samples: u32,
}

impl Default for EnvDesc {
    /// 512² faces match the 1024×512 equirect maps' texel density at the equator.
    fn default() -> Self {
        Self {
            face_size: 512,
            mip_count: 8,
            samples: 64,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ConvertPush {
    face_size: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PrefilterPush {
    alpha: f32,
    source_size: u32,
    destination_size: u32,
    sample_count: u32,
    /// 1: [`Weighting::Matched`].
    matched: u32,
}

/// `equirect_to_cube.comp.glsl`: one invocation per texel of a cube face, z the face.
pub const CONVERT_KERNEL: KernelInterface = KernelInterface {
    entry: "equirect_to_cube.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::SampledImage, BindingKind::StorageImage],
    push: crate::push_block!(ConvertPush { face_size }),
    local_size: [LOCAL_SIZE_2D, LOCAL_SIZE_2D],
};

/// `prefilter.comp.glsl`: one invocation per texel of a mip's cube face, z the face.
pub const PREFILTER_KERNEL: KernelInterface = KernelInterface {
    entry: "prefilter.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::SampledImage, BindingKind::StorageImage],
    push: crate::push_block!(PrefilterPush {
        alpha,
        source_size,
        destination_size,
        sample_count,
        matched
    }),
    local_size: [LOCAL_SIZE_2D, LOCAL_SIZE_2D],
};

/// How a prefiltered cube weighs its samples (`prefilter.comp.glsl`'s `matched`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// n·l, and a source mip one level blurrier than a sample's solid angle (Karis 2013).
    Karis,
    /// G2(l, n), the lobe's own, and the source mip of a sample's solid angle.
    Matched,
}

/// Where a prefiltered cube's levels are: the α each mip m ≥ 1 is filtered at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Levels {
    /// α = (m / (M − 1))², Karis's (`lib/ibl.glsl`'s `ibl_mip_of_alpha`).
    Karis,
    /// [`matched_alpha_of_mip`], evenly spaced in log α (`ibl_matched_mip_of_alpha`).
    LogAlpha,
}

/// How one of the environment's cubes is prefiltered, and its name.
struct Prefilter {
    name: &'static str,
    weighting: Weighting,
    levels: Levels,
}

/// The split sum's cube (Karis 2013).
const KARIS_CUBE: Prefilter = Prefilter {
    name: "environment prefiltered cube",
    weighting: Weighting::Karis,
    levels: Levels::Karis,
};

/// The matched cube (`ibl=matched`, `taps`, `anisotropic`).
const MATCHED_CUBE: Prefilter = Prefilter {
    name: "environment matched cube",
    weighting: Weighting::Matched,
    levels: Levels::LogAlpha,
};

/// The lamps' cube (`ibl=lamps`): the matched cube's weights at Karis's levels.
const LAMPS_CUBE: Prefilter = Prefilter {
    name: "environment lamps cube",
    weighting: Weighting::Matched,
    levels: Levels::Karis,
};

/// The matched cube's samples per texel, as a multiple of [`EnvDesc::samples`].
pub const MATCHED_SAMPLES: u32 = 4;

/// The α of the matched cube's mip `mip` of `mip_count`: 0 at mip 0 (a mirror), 1/(M − 1)² at
/// mip 1 (where Karis's cube has it) and, above, evenly spaced in log α up to 1 at the last
/// mip. `lib/ibl.glsl`'s `ibl_matched_mip_of_alpha` is its inverse, and between mips 0 and 1
/// reads √α·(M − 1) as Karis's cube does.
pub fn matched_alpha_of_mip(mip: u32, mip_count: u32) -> f64 {
    let last = f64::from(mip_count.max(2) - 1);
    if mip == 0 {
        return 0.0;
    }
    let steps = f64::from(mip_count.saturating_sub(2).max(1));
    (last * last).powf((f64::from(mip) - last) / steps)
}

/// Largest finite half float: brighter texels (a bare sun) are clamped to it on upload.
const HALF_MAX: f32 = 65504.0;

pub struct Environment {
    /// RGBA16F cube, `desc.mip_count` mips, in `FragmentRead` state: [`Weighting::Karis`].
    pub cube: Image,
    pub view: ImageView,
    /// The same, [`Weighting::Matched`], once [`Environment::build_matched`] built it.
    matched: Option<(Image, ImageView)>,
    /// The map split into its lamps and the rest (`ibl=lamps`).
    lamps: Lamps,
    /// Karis's cube of the rest, once [`Environment::build_lamps`] built it.
    lamps_cube: Option<(Image, ImageView)>,
    /// The rest's irradiance ([`irradiance_cube`], RGBA16F, one mip), built with the lamps'
    /// cube: what an `ibl=lamps` pass lights a diffuse base with, adding the lamps as lights.
    lamps_irradiance: Option<(Image, ImageView)>,
    /// The source cube (every mip, `ComputeRead`), kept for the matched cube.
    source: Image,
    source_view: ImageView,
    cube_sampler: Sampler,
    pub desc: EnvDesc,
    /// The irradiance's order-2 spherical harmonics ([`irradiance_sh`]), which the forward
    /// pass lights a diffuse base with (but under `ibl=lamps`).
    pub irradiance: [[f32; 4]; 9],
    /// [`sampling_tables`], the scene set's `EnvironmentSampling`.
    pub sampling: Buffer,
}

impl Environment {
    pub fn build(gpu: &Gpu, equirect: &HdrImage, desc: EnvDesc) -> Result<Self> {
        let max_mips = 32 - desc.face_size.max(1).leading_zeros();
        if desc.face_size < 4 || desc.mip_count < 2 || desc.mip_count > max_mips {
            return Err(Error::Unsupported(format!(
                "environment cube of {} texels needs 2..={max_mips} mips (got {})",
                desc.face_size, desc.mip_count
            )));
        }
        let device = &gpu.device;
        let cube_sampler = Sampler::new(device, SamplerDesc::linear_clamp(), "cube source")?;
        let (source, source_view) = source_cube(gpu, equirect, desc)?;
        let (cube, view) = prefiltered_cube(
            gpu,
            CubeSources::whole(&source, &source_view, &cube_sampler),
            desc,
            &KARIS_CUBE,
        )?;
        let lamps = lamps::extract(equirect);
        Ok(Self {
            cube,
            view,
            matched: None,
            lamps,
            lamps_cube: None,
            lamps_irradiance: None,
            source,
            source_view,
            cube_sampler,
            desc,
            irradiance: irradiance_sh(equirect),
            sampling: Buffer::with_data(
                device,
                BufferUsageFlags::STORAGE_BUFFER,
                &sampling_tables(equirect),
                "environment sampling",
            )?,
        })
    }

    /// Builds the matched cube ([`Weighting::Matched`]) unless built.
    pub fn build_matched(&mut self, gpu: &Gpu) -> Result<()> {
        if self.matched.is_none() {
            self.matched = Some(prefiltered_cube(
                gpu,
                CubeSources::whole(&self.source, &self.source_view, &self.cube_sampler),
                self.desc,
                &MATCHED_CUBE,
            )?);
        }
        Ok(())
    }

    /// The matched cube's view, once built.
    pub fn matched_view(&self) -> Option<&ImageView> {
        self.matched.as_ref().map(|(_, view)| view)
    }

    /// The environment's lamps (`ibl=lamps`), brightest first.
    pub fn lamps(&self) -> &[Lamp] {
        &self.lamps.lamps
    }

    /// Builds the lamps' cube (`ibl=lamps`) unless built: prefiltered with the matched cube's
    /// weights at Karis's levels, its mips 0 and 1 from the whole map, the others from the map
    /// without its lamps (converted to a cube of its own). A lobe sharp enough to read mips 0–1 sees each lamp's own shape there;
    /// from mip 2 the lamps come from the analytic disks alone (shade.glsl's lobe_lamps).
    pub fn build_lamps(&mut self, gpu: &Gpu) -> Result<()> {
        if self.lamps_cube.is_none() {
            let (_source, residual_view) = source_cube(gpu, &self.lamps.residual, self.desc)?;
            let sources = CubeSources {
                whole_mips: LAMPS_WHOLE_MIPS,
                rest: &residual_view,
                ..CubeSources::whole(&self.source, &self.source_view, &self.cube_sampler)
            };
            self.lamps_cube = Some(prefiltered_cube(gpu, sources, self.desc, &LAMPS_CUBE)?);
        }
        if self.lamps_irradiance.is_none() {
            let texels = irradiance_cube(&self.lamps.residual, IRRADIANCE_FACE);
            self.lamps_irradiance = Some(upload_cube(gpu, &texels, IRRADIANCE_FACE, "irradiance")?);
        }
        Ok(())
    }

    /// The lamps' cube, once built.
    pub fn lamps_view(&self) -> Option<&ImageView> {
        self.lamps_cube.as_ref().map(|(_, view)| view)
    }

    /// What the scene set binds as the irradiance of the map without its lamps: its cube once
    /// built with the lamps' cube, until then Karis's cube, for passes that never read it.
    pub fn lamps_irradiance_binding(&self) -> &ImageView {
        self.lamps_irradiance
            .as_ref()
            .map_or(&self.view, |(_, view)| view)
    }

    /// Reads mip `mip` of the cube of `weighting` back as RGBA f32 texels, face-major (faces in
    /// Vulkan order), rows top to bottom; the matched cube must have been built.
    pub fn read_mip(&self, gpu: &Gpu, weighting: Weighting, mip: u32) -> Result<Vec<[f32; 4]>> {
        let cube = match weighting {
            Weighting::Karis => &self.cube,
            Weighting::Matched => {
                &self
                    .matched
                    .as_ref()
                    .ok_or_else(|| Error::Unsupported("the matched cube is not built".into()))?
                    .0
            }
        };
        let bytes = crate::vk::read_image_mip(&gpu.device, cube, mip, ImageState::FragmentRead)?;
        let halves: &[f16] = bytemuck::cast_slice(&bytes);
        Ok(halves
            .chunks_exact(4)
            .map(|c| [c[0].to_f32(), c[1].to_f32(), c[2].to_f32(), c[3].to_f32()])
            .collect())
    }
}

fn cube_usage() -> ImageUsageFlags {
    ImageUsageFlags::STORAGE
        | ImageUsageFlags::SAMPLED
        | ImageUsageFlags::TRANSFER_SRC
        | ImageUsageFlags::TRANSFER_DST
}

/// The source cube of a `desc.face_size` environment, with its view, in `ComputeRead`: mip 0
/// converted from the map, the others blitted down.
fn source_cube(gpu: &Gpu, equirect: &HdrImage, desc: EnvDesc) -> Result<(Image, ImageView)> {
    let device = &gpu.device;
    let size = desc.face_size;
    let (_source_2d, source_2d_view) = upload_equirect(gpu, equirect)?;
    let equirect_sampler = Sampler::new(device, SamplerDesc::equirect(), "equirect")?;
    let image = ImageDesc::new_cube(Format::R16G16B16A16_SFLOAT, size).all_mips();
    let source = Image::new(device, image.usage(cube_usage()), "environment source cube")?;
    let source_view = source.view("environment source cube")?;
    let source_mip0 = source.mip_view(0, "environment source mip 0")?;
    let convert = ComputeKernel::build(gpu, &CONVERT_KERNEL, &[], &[], KernelSpec::default())?;
    let mut convert_set = DescriptorSet::new(device, &convert.set_layout, "equirect to cube")?;
    convert_set
        .write(0, Resource::Sampled(&source_2d_view, &equirect_sampler))
        .write(1, Resource::Storage(&source_mip0));
    submit_and_wait(device, "environment source", |rec| {
        rec.begin_label("equirect to cube");
        rec.transition(
            &source,
            0..1,
            ImageState::Undefined,
            ImageState::ComputeWrite,
        );
        convert.record_dispatch(
            rec,
            &[&convert_set],
            &ConvertPush { face_size: size },
            [size, size, 6],
        );
        record_mip_chain(rec, &source);
        rec.end_label();
        Ok(())
    })?;
    Ok((source, source_view))
}

/// How many mips of the lamps' cube hold the whole map, lamps included.
const LAMPS_WHOLE_MIPS: u32 = 2;

/// The source cubes (in `ComputeRead`) a prefiltered cube reads: mips below `whole_mips` from
/// the whole map's (`whole`, with its view), the others from `rest` (the whole map's view
/// again, or the view of a cube of the map without its lamps), all through `sampler`.
struct CubeSources<'a> {
    whole: (&'a Image, &'a ImageView),
    whole_mips: u32,
    rest: &'a ImageView,
    sampler: &'a Sampler,
}

impl<'a> CubeSources<'a> {
    /// Every mip from the whole map's source cube.
    fn whole(image: &'a Image, view: &'a ImageView, sampler: &'a Sampler) -> Self {
        Self {
            whole: (image, view),
            whole_mips: 1,
            rest: view,
            sampler,
        }
    }
}

/// A prefiltered cube of `desc.mip_count` mips from `sources`, filtered as `filter` says: mip
/// 0 a copy of the whole map's source, mips ≥ 1 the GGX prefilter of the source
/// [`CubeSources`] names for each. Left in `FragmentRead`, the sources back in `ComputeRead`.
fn prefiltered_cube(
    gpu: &Gpu,
    sources: CubeSources,
    desc: EnvDesc,
    filter: &Prefilter,
) -> Result<(Image, ImageView)> {
    let (mirror, whole_view) = sources.whole;
    let device = &gpu.device;
    let name = filter.name;
    let image = ImageDesc::new_cube(Format::R16G16B16A16_SFLOAT, desc.face_size)
        .mips(desc.mip_count)
        .usage(cube_usage());
    let cube = Image::new(device, image, name)?;
    let prefilter = ComputeKernel::build(gpu, &PREFILTER_KERNEL, &[], &[], KernelSpec::default())?;
    let mut targets = Vec::new();
    for mip in 1..desc.mip_count {
        let view = cube.mip_view(mip, &format!("{name} mip {mip}"))?;
        let mut set = DescriptorSet::new(device, &prefilter.set_layout, "prefilter")?;
        let source_view = if mip < sources.whole_mips {
            whole_view
        } else {
            sources.rest
        };
        set.write(0, Resource::Sampled(source_view, sources.sampler))
            .write(1, Resource::Storage(&view));
        targets.push((mip, view, set));
    }
    submit_and_wait(device, name, |rec| {
        rec.begin_label("GGX prefilter");
        rec.transition(
            mirror,
            0..1,
            ImageState::ComputeRead,
            ImageState::TransferSrc,
        );
        rec.transition(&cube, 0..1, ImageState::Undefined, ImageState::TransferDst);
        rec.copy_mip0(mirror, &cube);
        rec.transition(
            &cube,
            0..1,
            ImageState::TransferDst,
            ImageState::FragmentRead,
        );
        rec.transition(
            mirror,
            0..1,
            ImageState::TransferSrc,
            ImageState::ComputeRead,
        );
        record_prefilter(rec, &prefilter, &targets, &cube, desc, filter);
        rec.end_label();
        Ok(())
    })?;
    let view = cube.view(name)?;
    Ok((cube, view))
}

/// A half-float cube of one mip holding `texels` (`face` a side, face-major, rows top to
/// bottom), in `FragmentRead` state.
fn upload_cube(
    gpu: &Gpu,
    texels: &[[f32; 4]],
    face: u32,
    name: &str,
) -> Result<(Image, ImageView)> {
    let desc = ImageDesc::new_cube(Format::R16G16B16A16_SFLOAT, face);
    upload_halves(gpu, desc, texels, ImageState::FragmentRead, name)
}

/// The equirectangular map as a half-float 2-D image the conversion samples.
fn upload_equirect(gpu: &Gpu, equirect: &HdrImage) -> Result<(Image, ImageView)> {
    let desc = ImageDesc::new_2d(
        Format::R16G16B16A16_SFLOAT,
        equirect.width as u32,
        equirect.height as u32,
    );
    upload_halves(
        gpu,
        desc,
        &equirect.pixels,
        ImageState::ComputeRead,
        "equirect",
    )
}

/// An RGBA16F image of `desc` holding `texels` (alpha 1, brighter texels clamped to the
/// largest half float), left in `state`, with its view.
fn upload_halves(
    gpu: &Gpu,
    desc: ImageDesc,
    texels: &[[f32; 4]],
    state: ImageState,
    name: &str,
) -> Result<(Image, ImageView)> {
    let device = &gpu.device;
    let halves: Vec<f16> = texels
        .iter()
        .flat_map(|p| [p[0], p[1], p[2], 1.0])
        .map(|c| f16::from_f32(c.min(HALF_MAX)))
        .collect();
    let image = Image::new(device, desc, name)?;
    upload_image(device, &image, bytemuck::cast_slice(&halves), state)?;
    let view = image.view(name)?;
    Ok((image, view))
}

/// Records the source cube's mip chain (each mip blitted from the one above, after mip 0 was
/// written by the conversion), leaving every mip in `ComputeRead`.
fn record_mip_chain(rec: &mut Recorder, source: &Image) {
    let source_levels = source.desc.mip_levels;
    rec.transition(
        source,
        0..1,
        ImageState::ComputeWrite,
        ImageState::TransferSrc,
    );
    for mip in 1..source_levels {
        rec.transition(
            source,
            mip..mip + 1,
            ImageState::Undefined,
            ImageState::TransferDst,
        );
        rec.blit_mip_down(source, mip);
        rec.transition(
            source,
            mip..mip + 1,
            ImageState::TransferDst,
            ImageState::TransferSrc,
        );
    }
    rec.transition(
        source,
        0..source_levels,
        ImageState::TransferSrc,
        ImageState::ComputeRead,
    );
}

/// Records the GGX prefilter of every mip of `cube` below the first from the source cube
/// (`targets`: each mip with its view and descriptor set).
fn record_prefilter(
    rec: &mut Recorder,
    prefilter: &ComputeKernel,
    targets: &[(u32, ImageView, DescriptorSet)],
    cube: &Image,
    desc: EnvDesc,
    filter: &Prefilter,
) {
    let mips = 1..desc.mip_count;
    rec.transition(
        cube,
        mips.clone(),
        ImageState::Undefined,
        ImageState::ComputeWrite,
    );
    for (mip, _, set) in targets {
        let (w, _, _) = cube.desc.mip_extent(*mip);
        let alpha = match filter.levels {
            Levels::Karis => (*mip as f64 / (desc.mip_count - 1) as f64).powi(2),
            Levels::LogAlpha => matched_alpha_of_mip(*mip, desc.mip_count),
        };
        prefilter.record_dispatch(
            rec,
            &[set],
            &PrefilterPush {
                alpha: alpha as f32,
                source_size: desc.face_size,
                destination_size: w,
                sample_count: match filter.weighting {
                    Weighting::Karis => desc.samples,
                    Weighting::Matched => MATCHED_SAMPLES * desc.samples,
                },
                matched: u32::from(filter.weighting == Weighting::Matched),
            },
            [w, w, 6],
        );
    }
    rec.transition(
        cube,
        mips,
        ImageState::ComputeWrite,
        ImageState::FragmentRead,
    );
}

/// Direction through cube face `face` at face coordinates (u, v) ∈ [0,1]²: the CPU mirror of
/// `cube_direction` in `glsl/include/lib/cubemap.glsl` (Vulkan face order and orientation).
pub fn cube_direction(face: u32, u: f64, v: f64) -> DVec3 {
    let (x, y) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    let d = match face {
        0 => DVec3::new(1.0, -y, -x),
        1 => DVec3::new(-1.0, -y, x),
        2 => DVec3::new(x, 1.0, y),
        3 => DVec3::new(x, -1.0, -y),
        4 => DVec3::new(x, -y, 1.0),
        _ => DVec3::new(-x, -y, -1.0),
    };
    d.normalize()
}

/// Columns and rows of the grid [`sampling_tables`] tabulates (fewer for a smaller image: one
/// cell per texel).
pub const SAMPLING_GRID: (u32, u32) = (1024, 512);

/// The environment's importance sampling, as `bindings/scene.glsl`'s `EnvironmentSampling`
/// reads it: a header (the grid's columns and rows, 0, 0) then, over [`SAMPLING_GRID`]'s
/// equirect cells, each weighted by its mean radiance (mean of RGB) times sin θ at its centre
/// (its share of the sphere), the rows' marginal CDF and each row's CDF over its cells, as
/// f32 bits. Every cell also gets 10⁻⁴ of the mean weight, so that no direction the
/// environment lights has zero density.
pub fn sampling_tables(equirect: &HdrImage) -> Vec<u32> {
    let (w, h) = (equirect.width, equirect.height);
    let (cols, rows) = (SAMPLING_GRID.0.min(w as u32), SAMPLING_GRID.1.min(h as u32));
    let mut weight = vec![0.0f64; (cols * rows) as usize];
    for (k, p) in equirect.pixels.iter().enumerate() {
        let (x, y) = (k % w, k / w);
        let cell = (y * rows as usize / h) * cols as usize + x * cols as usize / w;
        weight[cell] += f64::from(p[0] + p[1] + p[2]) / 3.0;
    }
    for i in 0..rows as usize {
        let sin = ((i as f64 + 0.5) / f64::from(rows) * PI).sin();
        for wgt in &mut weight[i * cols as usize..(i + 1) * cols as usize] {
            *wgt *= sin;
        }
    }
    let floor = 1e-4 * weight.iter().sum::<f64>() / weight.len() as f64 + f64::MIN_POSITIVE;
    weight.iter_mut().for_each(|w| *w += floor);
    let row_sums: Vec<f64> = weight
        .chunks(cols as usize)
        .map(|row| row.iter().sum())
        .collect();
    let total: f64 = row_sums.iter().sum();
    let mut out = vec![cols, rows, 0, 0];
    let mut running = 0.0;
    for s in &row_sums {
        running += s;
        out.push(((running / total) as f32).to_bits());
    }
    for (row, sum) in weight.chunks(cols as usize).zip(&row_sums) {
        let mut running = 0.0;
        for w in row {
            running += w;
            out.push(((running / sum) as f32).to_bits());
        }
    }
    out
}

/// Direction through the centre of texel (x, y) of a `w`×`h` equirect map: [`equirect_uv`]'s
/// mapping, inverted.
pub fn equirect_direction(x: usize, y: usize, w: usize, h: usize) -> DVec3 {
    let theta = PI * (y as f64 + 0.5) / h as f64;
    let phi = 2.0 * PI * ((x as f64 + 0.5) / w as f64 - 0.5);
    DVec3::new(
        theta.sin() * phi.sin(),
        theta.cos(),
        -theta.sin() * phi.cos(),
    )
}

/// Solid angle of a texel in row `y` of a `w`×`h` equirect map.
pub fn texel_solid_angle(y: usize, w: usize, h: usize) -> f64 {
    let theta = PI * (y as f64 + 0.5) / h as f64;
    (2.0 * PI / w as f64) * (PI / h as f64) * theta.sin()
}

/// Equirect texture coordinates of unit direction `d`: the CPU mirror of `equirect_uv` in
/// `glsl/include/lib/equirect.glsl`.
pub fn equirect_uv(d: DVec3) -> (f64, f64) {
    let u = d.x.atan2(-d.z) / (2.0 * PI) + 0.5;
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    (u, v)
}

/// A bilinear lookup: the filtered value and, per channel, the spread (max − min) of the four
/// texels it blends. A sampler whose weights carry `b` fractional bits can differ from the
/// exact blend by at most spread·2⁻ᵇ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bilinear {
    pub value: [f64; 3],
    pub spread: [f64; 3],
}

/// Bilinear lookup of `image` at (u, v) with the sampler `SamplerDesc::equirect` describes:
/// u wraps, v clamps, texel centres at (i + ½)/n.
pub fn sample_bilinear(image: &HdrImage, u: f64, v: f64) -> Bilinear {
    let (w, h) = (image.width as i64, image.height as i64);
    let x = u * w as f64 - 0.5;
    let y = v * h as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |xi: i64, yi: i64| {
        let xi = xi.rem_euclid(w);
        let yi = yi.clamp(0, h - 1);
        let p = image.pixels[(yi * w + xi) as usize];
        [p[0] as f64, p[1] as f64, p[2] as f64]
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    let mut out = [0.0; 3];
    let mut low = [f64::INFINITY; 3];
    let mut high = [f64::NEG_INFINITY; 3];
    for (dx, dy, wgt) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let t = texel(x0 + dx, y0 + dy);
        for c in 0..3 {
            out[c] += wgt * t[c];
            low[c] = low[c].min(t[c]);
            high[c] = high[c].max(t[c]);
        }
    }
    Bilinear {
        value: out,
        spread: std::array::from_fn(|c| high[c] - low[c]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_faces_point_along_their_axes() {
        let axes = [
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        for (face, axis) in axes.iter().enumerate() {
            let d = cube_direction(face as u32, 0.5, 0.5);
            assert!((d - *axis).length() < 1e-12, "face {face}: {d}");
        }
    }

    #[test]
    fn matched_levels_step_evenly_in_log_alpha_from_karis_first_level_to_one() {
        for mip_count in [2, 5, 6, 7, 8, 10] {
            let last = mip_count - 1;
            let karis_first = (1.0 / f64::from(last)).powi(2);
            assert_eq!(matched_alpha_of_mip(0, mip_count), 0.0);
            assert!((matched_alpha_of_mip(1, mip_count) - karis_first).abs() < 1e-12);
            assert!((matched_alpha_of_mip(last, mip_count) - 1.0).abs() < 1e-12);
            let ratios: Vec<f64> = (1..last)
                .map(|m| {
                    matched_alpha_of_mip(m + 1, mip_count) / matched_alpha_of_mip(m, mip_count)
                })
                .collect();
            for r in &ratios {
                assert!(
                    (r - ratios[0]).abs() < 1e-9 && *r > 1.0,
                    "{mip_count}: {ratios:?}"
                );
            }
        }
        // Eight levels: about twice α a level, where √α steps quadruple mip 1's α at mip 2.
        let ratio = matched_alpha_of_mip(2, 8) / matched_alpha_of_mip(1, 8);
        assert!((ratio - 49f64.powf(1.0 / 6.0)).abs() < 1e-12 && ratio < 2.0);
    }

    #[test]
    fn equirect_mapping_covers_the_sphere() {
        let (u, v) = equirect_uv(DVec3::Y);
        assert!(v.abs() < 1e-12, "{u} {v}");
        let (u, v) = equirect_uv(-DVec3::Z);
        assert!((u - 0.5).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
        let (u, _) = equirect_uv(DVec3::X);
        assert!((u - 0.75).abs() < 1e-12);
    }
}
