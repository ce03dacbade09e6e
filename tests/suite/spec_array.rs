//! A function-local array sized by the `max_layers` specialization constant has exactly that
//! size on the device.

use crate::common;

use lamina::gpu::ComputeKernel;
use lamina::shader::kernel;
use lamina::variant::VariantKey;
use lamina::vk::{submit_and_wait, Access, Buffer, BufferDesc, DescriptorSet, Resource};

#[test]
fn spec_constant_sizes_the_local_array() {
    let gpu = common::gpu();
    for max_layers in [1u32, 2, 4, 8, 16] {
        let variant = VariantKey {
            max_layers,
            ..VariantKey::default()
        };
        let kernel =
            ComputeKernel::build(&gpu, &kernel::SPEC_ARRAY, &[], &[], variant.spec()).unwrap();
        let result = Buffer::new(&gpu.device, BufferDesc::readback(8), "result").unwrap();
        let mut set = DescriptorSet::new(&gpu.device, &kernel.set_layout, "spec array").unwrap();
        set.write(0, Resource::Buffer(&result));
        submit_and_wait(&gpu.device, "spec array", |rec| {
            kernel.record_dispatch(rec, &[&set], &(), [1, 1, 1]);
            rec.barrier(Access::ComputeWrite, Access::HostRead);
            Ok(())
        })
        .unwrap();
        let [length, sum]: [u32; 2] = result.read::<u32>().try_into().unwrap();
        println!("max_layers={max_layers}: length {length}, sum {sum}");
        assert_eq!(length, max_layers);
        assert_eq!(sum, max_layers * (max_layers + 1) / 2);
    }
    common::assert_validation_clean(&gpu);
}
