//! `lamina devices`: every Vulkan device and the features lamina uses, and with
//! `--calibrate` the selected device's compute-to-fragment throughput
//! (`lamina::profile::calibrate`).

use anyhow::Result;
use lamina::profile::calibrate::{calibrate, CalibrationSetup};
use lamina::Size;

use super::{check_validation, GlobalArgs};

#[derive(clap::Args)]
pub struct DevicesArgs {
    /// Time the same arithmetic loop as a fragment draw and as a compute dispatch over the
    /// same pixels on the selected device (--device): what compute gives against fragment
    /// shading there, so a reader knows what a fragment timing stands for.
    #[arg(long)]
    calibrate: bool,
    /// With --calibrate: the pixels (a W×H target, W·H invocations).
    #[arg(
        long,
        value_name = "WxH",
        default_value = "1920x1080",
        requires = "calibrate"
    )]
    size: Size,
    /// With --calibrate: multiply-adds per pixel, 1 to 65536.
    #[arg(long, value_name = "N", default_value_t = 256, requires = "calibrate",
          value_parser = clap::value_parser!(u32).range(1..=65536))]
    iterations: u32,
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

pub fn run(global: &GlobalArgs, args: &DevicesArgs) -> Result<()> {
    if args.calibrate {
        return run_calibration(global, args);
    }
    let instance = lamina::vk::Instance::new(global.instance(false))?;
    for d in lamina::vk::enumerate(&instance)? {
        println!("[{}] {} ({})", d.index, d.name, d.device_type);
        println!(
            "    driver:                 {} — {}",
            d.driver_name, d.driver_info
        );
        println!("    Vulkan API:             {}", d.api_version);
        println!("    vendor id:              {:#06x}", d.vendor_id);
        println!("    shaderFloat16 (fp16):   {}", yes(d.shader_float16));
        println!(
            "    timestamps:             {} ({} valid bits, {} ns/tick)",
            yes(d.timestamps),
            d.timestamp_valid_bits,
            d.timestamp_period_ns
        );
        println!("    pipeline statistics:    {}", yes(d.pipeline_statistics));
        println!(
            "    pipeline executables:   {}",
            yes(d.pipeline_executable_properties)
        );
        println!(
            "    1.3 core (dyn. rendering, sync2, host query reset): {}",
            yes(d.dynamic_rendering && d.synchronization2 && d.host_query_reset)
        );
        println!("    max 3-D image side:     {}", d.max_image_dimension_3d);
    }
    Ok(())
}

/// `--calibrate`: the calibration pair on the selected device, printed.
fn run_calibration(global: &GlobalArgs, args: &DevicesArgs) -> Result<()> {
    let gpu = global.open_gpu()?;
    let setup = CalibrationSetup {
        width: args.size.width,
        height: args.size.height,
        iterations: args.iterations,
        ..CalibrationSetup::default()
    };
    let c = calibrate(&gpu, setup)?;
    check_validation(&gpu)?;
    let invocations = |n: Option<u64>| n.map_or(String::new(), |n| format!(" ({n} invocations)"));
    println!(
        "device:            {} ({})",
        gpu.device.report.name, gpu.device.report.driver_info
    );
    println!(
        "calibration:       {}x{} pixels, {} multiply-adds each, median of {} runs",
        c.width, c.height, c.iterations, c.repeats
    );
    println!(
        "fragment draw:     {:.3} ms{}",
        c.fragment_ms,
        invocations(c.fragment_invocations)
    );
    println!(
        "compute dispatch:  {:.3} ms{}",
        c.compute_ms,
        invocations(c.compute_invocations)
    );
    println!(
        "compute/fragment:  {:.2}× (the same work's fragment time over its compute time)",
        c.compute_to_fragment()
    );
    Ok(())
}
