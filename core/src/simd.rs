//! The vector unit the SIMD kernels run on, chosen at run time.
//!
//! [`Kernels`] holds the [`pulp::Arch`] detected once (AVX-512, AVX2+FMA or scalar on x86-64), so
//! the one generic binary uses the widest unit the machine has; dispatching a kernel is then a
//! branch on an enum. The kernels themselves live beside the physics they serve, as inherent
//! methods of [`Kernels`]: the FD step's passes over the string in `tanpura/fd/kernels.rs`, the
//! modal step's passes over the modes in `tanpura/modal/lanes.rs`.
//!
//! **Capping the unit.** The environment variable `JAVARI_VECTOR_UNIT` (`avx512`, `avx2` or
//! `scalar`) caps the unit at that level, never above what the machine has: so that one build
//! can be timed on each unit of one machine (`docs/performance.md`, stop 65: AVX-512 against
//! AVX2 on a Zen 4, whose 512-bit operations are two 256-bit halves), and so that a user whose
//! machine slows down on the wider unit can choose the narrower one. It is read once per
//! process, at the first detection (the constructors, never the audio thread's steps); an
//! unknown value leaves the unit uncapped.

use pulp::Arch;
use std::sync::OnceLock;

/// The environment variable that caps the vector unit.
pub const VECTOR_UNIT_VARIABLE: &str = "JAVARI_VECTOR_UNIT";

/// The most a cap lets the detection choose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Level {
    Scalar,
    Avx2,
    Avx512,
}

/// The level named by `JAVARI_VECTOR_UNIT`'s value, if it names one.
fn level_named(value: &str) -> Option<Level> {
    match value.trim().to_ascii_lowercase().as_str() {
        "avx512" | "avx-512" => Some(Level::Avx512),
        "avx2" => Some(Level::Avx2),
        "scalar" => Some(Level::Scalar),
        _ => None,
    }
}

/// The widest unit of this CPU no wider than `cap`.
fn arch_at_most(cap: Level) -> Arch {
    #[cfg(target_arch = "x86_64")]
    {
        if cap >= Level::Avx512 {
            if let Some(simd) = pulp::x86::V4::try_new() {
                return Arch::V4(simd);
            }
        }
        if cap >= Level::Avx2 {
            if let Some(simd) = pulp::x86::V3::try_new() {
                return Arch::V3(simd);
            }
        }
        Arch::Scalar
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = cap;
        Arch::new()
    }
}

/// The unit every kernel runs on: detected once, under the environment's cap.
pub fn vector_unit() -> Arch {
    static UNIT: OnceLock<Arch> = OnceLock::new();
    *UNIT.get_or_init(|| {
        let cap = std::env::var(VECTOR_UNIT_VARIABLE)
            .ok()
            .and_then(|value| level_named(&value))
            .unwrap_or(Level::Avx512);
        arch_at_most(cap)
    })
}

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
    /// The widest vector unit of this CPU (under `JAVARI_VECTOR_UNIT`'s cap, if set).
    pub fn detect() -> Self {
        Self {
            arch: vector_unit(),
        }
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
    fn a_cap_names_a_level_and_never_widens_the_unit() {
        assert_eq!(level_named("avx512"), Some(Level::Avx512));
        assert_eq!(level_named(" AVX2 "), Some(Level::Avx2));
        assert_eq!(level_named("scalar"), Some(Level::Scalar));
        assert_eq!(level_named("sse9"), None);
        let widest = Kernels {
            arch: arch_at_most(Level::Avx512),
        };
        assert_eq!(widest.name(), Kernels { arch: Arch::new() }.name());
        let scalar = Kernels {
            arch: arch_at_most(Level::Scalar),
        };
        assert_eq!(scalar.name(), "scalar");
        let avx2 = Kernels {
            arch: arch_at_most(Level::Avx2),
        };
        assert_ne!(avx2.name(), "AVX-512");
    }

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
