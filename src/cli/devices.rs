//! `lamina devices`: every Vulkan device and the features lamina uses.

use anyhow::Result;

use super::GlobalArgs;

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

pub fn run(global: &GlobalArgs) -> Result<()> {
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
