//! The interface of each compute entry point, declared once beside the code that dispatches
//! it: its own descriptor bindings, its push-constant block (size and member offsets), its
//! work-group size and whether it shades (binds the shading set as set 0). The host creates
//! the pipeline from it (`gpu::ComputeKernel::build`), sizes dispatches by it, and
//! tests/suite/reflection.rs compares it with what the SPIR-V declares.
//!
//! Work-group sizes reach the shaders as specialization constants: [`KernelSpec`] for the
//! table and utility kernels (`glsl/include/shared/kernel.glsl`), `ShadeSpec::local_size_x`
//! for the compute entry points that shade.

use crate::vk::BindingKind;

use crate::variant::{Axis, ShadeSpec, VariantKey, G2};

/// Specialization constants of the table and utility kernels, mirrored in
/// `glsl/include/shared/kernel.glsl` (ids 0…2).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct KernelSpec {
    pub local_size_x: u32,
    pub local_size_y: u32,
    /// The G2 form a table is built for (its code).
    pub g2: u32,
}

crate::spec_constants!(KernelSpec {
    local_size_x = 0,
    local_size_y = 1,
    g2 = 2,
});

impl KernelSpec {
    /// For a table built with the G2 form `g2` (the work-group size is set from the
    /// kernel's interface when the pipeline is made).
    pub fn for_g2(g2: G2) -> Self {
        Self {
            local_size_x: 1,
            local_size_y: 1,
            g2: g2.code(),
        }
    }
}

/// The default G2 form (for kernels whose output does not depend on it).
impl Default for KernelSpec {
    fn default() -> Self {
        Self::for_g2(VariantKey::default().g2)
    }
}

/// Specialization constants that carry a work-group size.
pub trait WorkGroupSpec: crate::vk::SpecConstants {
    /// `self` with the work-group size `local_size` (x, y).
    fn with_local_size(self, local_size: [u32; 2]) -> Self;
}

impl WorkGroupSpec for KernelSpec {
    fn with_local_size(self, [x, y]: [u32; 2]) -> Self {
        Self {
            local_size_x: x,
            local_size_y: y,
            ..self
        }
    }
}

/// The shading passes' constants carry the work group's width only: a shading kernel's
/// height is 1, or fixed in its source where it has rows (`deferred.comp.glsl`'s, which its
/// interface states and tests/suite/reflection.rs holds to the SPIR-V).
impl WorkGroupSpec for ShadeSpec {
    fn with_local_size(self, [x, _]: [u32; 2]) -> Self {
        Self {
            local_size_x: x,
            ..self
        }
    }
}

/// One member of a push-constant block: its GLSL name and byte offset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PushMember {
    pub name: &'static str,
    pub offset: u32,
}

/// A push-constant block as the host lays it out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PushBlock {
    pub size: u32,
    pub members: &'static [PushMember],
}

impl PushBlock {
    /// No push constants.
    pub const NONE: Self = Self {
        size: 0,
        members: &[],
    };
}

/// The [`PushBlock`] of a `#[repr(C)]` struct whose fields are named as the GLSL block's
/// members: `push_block!(Push { size, sample_count })`.
#[macro_export]
macro_rules! push_block {
    ($ty:ty { $($field:ident),* $(,)? }) => {
        $crate::shader::kernel::PushBlock {
            size: ::core::mem::size_of::<$ty>() as u32,
            members: &[$($crate::shader::kernel::PushMember {
                name: stringify!($field),
                offset: ::core::mem::offset_of!($ty, $field) as u32,
            }),*],
        }
    };
}

/// What the host declares for one compute entry point.
#[derive(Clone, Copy, Debug)]
pub struct KernelInterface {
    /// The entry point under `glsl/`.
    pub entry: &'static str,
    /// Whether set 0 is the shading set (`shader::interface::SHADING_BINDINGS`); the kernel's
    /// own set follows the shared ones.
    pub shades: bool,
    /// Whether the scene set (`shader::interface::SCENE_BINDINGS`: frame constants, the
    /// environment, the lights) follows the shading set: a kernel that lights what it shades.
    pub scene: bool,
    /// The kernel's own set, binding i = element i.
    pub bindings: &'static [BindingKind],
    pub push: PushBlock,
    /// Work-group size (x, y); z is 1.
    pub local_size: [u32; 2],
}

impl KernelInterface {
    /// The index of the kernel's own descriptor set.
    pub fn own_set(&self) -> u32 {
        u32::from(self.shades) + u32::from(self.scene)
    }

    /// Work groups covering `invocations` (x, y, z) with this kernel's work-group size.
    pub fn groups(&self, [x, y, z]: [u32; 3]) -> [u32; 3] {
        [
            x.div_ceil(self.local_size[0]),
            y.div_ceil(self.local_size[1]),
            z,
        ]
    }
}

/// The work-group edge of lamina's 2-D table kernels.
pub const LOCAL_SIZE_2D: u32 = 8;

/// The work-group width of the one-dimensional kernels (the shading ones, the FGD grid's).
pub const LOCAL_SIZE_1D: u32 = 64;

/// `spec_array.comp.glsl`: the test that a MAX_LAYERS-sized array has that size on the device
/// (tests/suite/spec_array.rs).
pub const SPEC_ARRAY: KernelInterface = KernelInterface {
    entry: "spec_array.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::StorageBuffer],
    push: PushBlock::NONE,
    local_size: [1, 1],
};
