//! The calibration pair (`lamina devices --calibrate`): one arithmetic loop
//! (`glsl/include/lib/calibrate.glsl`) run at every pixel of a W×H target by a fragment draw
//! and by a compute dispatch of W·H invocations, each timed by GPU timestamps, interleaved,
//! median of several repeats. Their ratio is what the device gives compute against fragment
//! shading for the same work: on a part whose graphics run on a few of its cores (an H100
//! runs fragments on 4 of its 132 SMs), a fragment timing describes that share of the chip,
//! and this says how large it is.

use crate::error::Result;
use crate::gpu::{ComputeKernel, Gpu};
use crate::shader::kernel::{KernelInterface, KernelSpec, PushBlock, LOCAL_SIZE_1D};
use crate::stats::Summary;
use crate::vk::{
    submit_and_wait, Access, BindingKind, Buffer, BufferDesc, DescriptorSet, Format, GpuProfiler,
    GraphicsDesc, Image, ImageDesc, ImageState, ImageView, Pipeline, PipelineLayout, Resource,
    ScopeTiming, Stages,
};

/// The fragment side's entry points (the full-screen triangle is the sky's).
pub const ENTRIES: [&str; 2] = ["sky.vert.glsl", "calibrate.frag.glsl"];

/// The push constants of both sides: the loop's length, and the target's width (fragment) or
/// the pixel count (compute).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Push {
    pub iterations: u32,
    pub width: u32,
}

/// The fragment side's push block as the host lays it out (tests/suite/reflection.rs compares
/// it with calibrate.frag.glsl's).
pub const FRAGMENT_PUSH: PushBlock = crate::push_block!(Push { iterations, width });

/// The compute side's push block: the same layout, the second member named for what it holds.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ComputePush {
    iterations: u32,
    count: u32,
}

/// `calibrate.comp.glsl`.
pub const KERNEL: KernelInterface = KernelInterface {
    entry: "calibrate.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::StorageBuffer],
    push: crate::push_block!(ComputePush { iterations, count }),
    local_size: [LOCAL_SIZE_1D, 1],
};

/// What to run: the target's size, the loop's length, how many timed repeats of each side.
#[derive(Clone, Copy, Debug)]
pub struct CalibrationSetup {
    pub width: u32,
    pub height: u32,
    pub iterations: u32,
    pub repeats: u32,
}

impl Default for CalibrationSetup {
    fn default() -> Self {
        Self {
            width: 1920,
            height: 1080,
            iterations: 256,
            repeats: 5,
        }
    }
}

/// The calibration's result: each side's median time and invocation count.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Calibration {
    pub width: u32,
    pub height: u32,
    pub iterations: u32,
    pub repeats: u32,
    pub fragment_ms: f64,
    pub compute_ms: f64,
    /// The invocations each side ran, where the device counts them (pipeline statistics).
    pub fragment_invocations: Option<u64>,
    pub compute_invocations: Option<u64>,
}

impl Calibration {
    /// How much faster compute runs the same work than fragment shading: the fragment time
    /// over the compute time.
    pub fn compute_to_fragment(&self) -> f64 {
        self.fragment_ms / self.compute_ms
    }
}

/// What the pair runs on: the draw's layout and pipeline, the kernel, the draw's target and
/// the dispatch's output with its set.
struct Pair {
    layout: PipelineLayout,
    draw: Pipeline,
    kernel: ComputeKernel,
    target: Image,
    view: ImageView,
    set: DescriptorSet,
    _output: Buffer,
}

impl Pair {
    fn new(gpu: &Gpu, width: u32, height: u32) -> Result<Self> {
        let device = &gpu.device;
        let vertex = gpu.shaders.compile(ENTRIES[0], &[])?;
        let fragment = gpu.shaders.compile(ENTRIES[1], &[])?;
        let format = Format::R32G32B32A32_SFLOAT;
        let push_bytes = std::mem::size_of::<Push>() as u32;
        let layout = PipelineLayout::new(device, &[], push_bytes, Stages::Graphics, "calibrate")?;
        let desc = GraphicsDesc {
            vertex: &vertex,
            fragment: &fragment,
            vertex_stride: 0,
            attributes: &[],
            color_formats: &[format],
            cull_back: false,
            stencil: None,
        };
        let draw = gpu.graphics_pipeline(&layout, &desc, &(), "calibrate draw")?;
        let kernel = ComputeKernel::build(gpu, &KERNEL, &[], &[], KernelSpec::default())?;
        let target = Image::new(
            device,
            ImageDesc::render_target(format, width, height),
            "calibrate target",
        )?;
        let view = target.view("calibrate target")?;
        let pixels = u64::from(width) * u64::from(height);
        let output = Buffer::new(device, BufferDesc::storage(pixels * 16), "calibrate output")?;
        let mut set = DescriptorSet::new(device, &kernel.set_layout, "calibrate")?;
        set.write(0, Resource::Buffer(&output));
        Ok(Self {
            layout,
            draw,
            kernel,
            target,
            view,
            set,
            _output: output,
        })
    }

    /// One timed run of each side, the draw first: their scopes.
    fn run(&self, gpu: &Gpu, setup: CalibrationSetup) -> Result<(ScopeTiming, ScopeTiming)> {
        let (width, height, iterations) = (setup.width, setup.height, setup.iterations);
        let mut profiler = GpuProfiler::new(&gpu.device, 2, "calibrate")?;
        submit_and_wait(&gpu.device, "calibrate", |rec| {
            rec.transition(
                &self.target,
                0..1,
                ImageState::Undefined,
                ImageState::ColorAttachment,
            );
            rec.bind_pipeline(&self.draw);
            rec.push_constants(&self.layout, &Push { iterations, width });
            let scope = profiler.begin(rec, "fragment").expect("a fresh profiler");
            rec.begin_rendering(&self.view, width, height, [0.0; 4]);
            rec.draw(3);
            rec.end_rendering();
            profiler.end(rec, scope);
            let scope = profiler
                .begin(rec, "compute")
                .expect("the draw's scope is closed");
            let count = width * height;
            let push = ComputePush { iterations, count };
            self.kernel
                .record_dispatch(rec, &[&self.set], &push, [count, 1, 1]);
            profiler.end(rec, scope);
            rec.barrier(Access::ComputeWrite, Access::HostRead);
            Ok(())
        })?;
        let mut scopes = profiler.results()?.into_iter();
        Ok((
            scopes.next().expect("the draw's scope"),
            scopes.next().expect("the dispatch's scope"),
        ))
    }
}

/// Runs the calibration pair on `gpu`: `setup.repeats` runs of each side, interleaved.
pub fn calibrate(gpu: &Gpu, setup: CalibrationSetup) -> Result<Calibration> {
    let pair = Pair::new(gpu, setup.width, setup.height)?;
    let repeats = setup.repeats.max(1);
    let (mut fragments, mut computes) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        let (f, c) = pair.run(gpu, setup)?;
        fragments.push(f);
        computes.push(c);
    }
    let ms = |s: &[ScopeTiming]| {
        let times: Vec<f64> = s.iter().map(|t| t.duration.as_ms()).collect();
        Summary::of(&times).map_or(f64::NAN, |s| s.median)
    };
    Ok(Calibration {
        width: setup.width,
        height: setup.height,
        iterations: setup.iterations,
        repeats,
        fragment_ms: ms(&fragments),
        compute_ms: ms(&computes),
        fragment_invocations: fragments[0].fragment_invocations,
        compute_invocations: computes[0].compute_invocations,
    })
}
