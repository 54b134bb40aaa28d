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

/// A fixed-length array of `T` whose first element lies on a cache line (64 bytes), for the
/// arrays the kernels stream through: a 512-bit load from an address that is not a multiple of
/// 64 spans two cache lines, and the modal string's free-step kernel takes 45 % longer on such
/// an array (divan, `cargo bench -p javari-core --bench tanpura -- free_steps`, AVX-512 on AMD
/// EPYC: 47.8 ns on a cache line, 69.3 ns 16 bytes off it). `Vec` only promises the alignment of
/// `T`, so the storage holds one cache line more and the slice starts at its first aligned
/// element, found again at each access (the storage never moves while the array lives; a clone
/// finds its own).
pub struct CacheAligned<T> {
    storage: Vec<T>,
    len: usize,
}

const CACHE_LINE_BYTES: usize = 64;

impl<T: Copy> CacheAligned<T> {
    /// `len` copies of `value`. Allocates.
    pub fn new(len: usize, value: T) -> Self {
        let spare = CACHE_LINE_BYTES / std::mem::size_of::<T>().max(1);
        Self {
            storage: vec![value; len + spare],
            len,
        }
    }

    /// Where the aligned slice starts in the storage (the storage's start if no element is
    /// aligned, which no element type the kernels use can cause).
    fn start(&self) -> usize {
        let offset = self.storage.as_ptr().align_offset(CACHE_LINE_BYTES);
        if offset <= self.storage.len() - self.len {
            offset
        } else {
            0
        }
    }
}

impl<T: Copy> std::ops::Deref for CacheAligned<T> {
    type Target = [T];

    #[inline]
    fn deref(&self) -> &[T] {
        let start = self.start();
        &self.storage[start..start + self.len]
    }
}

impl<T: Copy> std::ops::DerefMut for CacheAligned<T> {
    #[inline]
    fn deref_mut(&mut self) -> &mut [T] {
        let start = self.start();
        &mut self.storage[start..start + self.len]
    }
}

impl<T: Copy + Default> Clone for CacheAligned<T> {
    /// The same elements in new storage, at that storage's own aligned start.
    fn clone(&self) -> Self {
        let mut copy = Self::new(self.len, T::default());
        copy.copy_from_slice(self);
        copy
    }
}

impl<T: Copy + std::fmt::Debug> std::fmt::Debug for CacheAligned<T> {
    fn fmt(&self, formatter: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        formatter.debug_list().entries(self.iter()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_aligned_arrays_start_on_a_cache_line_and_clone_their_contents() {
        for len in [1, 31, 96, 4608] {
            let mut values = CacheAligned::new(len, 0.0f32);
            for (i, value) in values.iter_mut().enumerate() {
                *value = i as f32;
            }
            let copy = values.clone();
            for array in [&values, &copy] {
                assert_eq!(array.as_ptr() as usize % CACHE_LINE_BYTES, 0);
                assert_eq!(array.len(), len);
                assert!(array.iter().enumerate().all(|(i, &v)| v == i as f32));
            }
        }
    }
}
