//! The vector unit the SIMD kernels run on, chosen at run time.
//!
//! [`Kernels`] holds the [`pulp::Arch`] detected once (AVX-512, AVX2+FMA or scalar on x86-64), so
//! the one generic binary uses the widest unit the machine has; dispatching a kernel is then a
//! branch on an enum. The kernels themselves live beside the physics they serve, as inherent
//! methods of [`Kernels`]: the FD step's passes over the string in `tanpura/fd/kernels.rs`, the
//! modal step's passes over the modes in `tanpura/modal/lanes.rs`.

use pulp::Arch;

/// The detected vector unit; the kernels are its methods.
#[derive(Debug, Clone, Copy)]
pub struct Kernels {
    pub(crate) arch: Arch,
}

impl Default for Kernels {
    fn default() -> Self {
        Self::detect()
    }
}

impl Kernels {
    /// The widest vector unit of this CPU.
    pub fn detect() -> Self {
        Self { arch: Arch::new() }
    }

    /// The vector unit in use, for reports ("AVX-512", "AVX2+FMA" or "scalar").
    pub fn name(&self) -> &'static str {
        match self.arch {
            #[cfg(target_arch = "x86_64")]
            Arch::V4(_) => "AVX-512",
            #[cfg(target_arch = "x86_64")]
            Arch::V3(_) => "AVX2+FMA",
            _ => "scalar",
        }
    }
}
