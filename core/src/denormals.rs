//! Flush-to-zero on the audio thread: a scoped guard that makes the CPU treat subnormal
//! (denormal) floats as zero while it lives, and restores the thread's previous mode when dropped.
//!
//! Why: a decaying string's state passes through the subnormal range (below 1.2e-38 in f32,
//! 2.2e-308 in f64) on its way to zero, and a two-pole recursion rounded there can linger in it.
//! Arithmetic on subnormals costs tens to hundreds of cycles on x86, so a string that has rung for
//! a minute could cost more per block than a fresh one. Values that small are 700 dB below any
//! audible level; flushing them changes nothing a listener can hear.
//!
//! Where the platform allows:
//! - x86-64: MXCSR's FTZ (bit 15, results that would be subnormal become 0) and DAZ (bit 6,
//!   subnormal inputs read as 0). Every x86-64 CPU has both;
//! - AArch64: FPCR's FZ (bit 24), which flushes inputs and results alike;
//! - anything else: the guard does nothing.
//!
//! The control register belongs to the thread, so the guard is neither `Send` nor `Sync`: it is
//! set and restored on the thread that runs the audio. The offline renderer does not use it, so
//! that its output stays the plain IEEE result; the plugin's `process` and `cargo xtask soak`
//! (which drives the engine as the plugin does) do.

use std::marker::PhantomData;

#[cfg(target_arch = "x86_64")]
const MXCSR_FLUSH_TO_ZERO: u32 = 1 << 15;
#[cfg(target_arch = "x86_64")]
const MXCSR_DENORMALS_ARE_ZERO: u32 = 1 << 6;
#[cfg(target_arch = "aarch64")]
const FPCR_FLUSH_TO_ZERO: u64 = 1 << 24;

/// Subnormals flushed to zero on this thread until dropped (see the module doc).
pub struct FlushDenormals {
    /// The control register's value before the guard, restored on drop.
    #[cfg(target_arch = "x86_64")]
    saved_mxcsr: u32,
    #[cfg(target_arch = "aarch64")]
    saved_fpcr: u64,
    /// The register is per thread: keep the guard on the thread that made it.
    _same_thread: PhantomData<*const ()>,
}

impl FlushDenormals {
    /// Turns flushing on for the current thread (a no-op where the platform has no such mode).
    #[must_use = "flushing ends when the guard is dropped"]
    pub fn enable() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            let saved_mxcsr = read_mxcsr();
            write_mxcsr(saved_mxcsr | MXCSR_FLUSH_TO_ZERO | MXCSR_DENORMALS_ARE_ZERO);
            Self {
                saved_mxcsr,
                _same_thread: PhantomData,
            }
        }
        #[cfg(target_arch = "aarch64")]
        {
            let saved_fpcr = read_fpcr();
            write_fpcr(saved_fpcr | FPCR_FLUSH_TO_ZERO);
            Self {
                saved_fpcr,
                _same_thread: PhantomData,
            }
        }
        #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
        {
            Self {
                _same_thread: PhantomData,
            }
        }
    }

    /// Whether this platform flushes subnormals under the guard.
    pub const fn is_supported() -> bool {
        cfg!(any(target_arch = "x86_64", target_arch = "aarch64"))
    }
}

impl Drop for FlushDenormals {
    fn drop(&mut self) {
        #[cfg(target_arch = "x86_64")]
        write_mxcsr(self.saved_mxcsr);
        #[cfg(target_arch = "aarch64")]
        write_fpcr(self.saved_fpcr);
    }
}

// `_mm_getcsr`/`_mm_setcsr` are deprecated (Rust 1.75) because the compiler may move float
// operations across them; the inline assembly below is a compiler barrier for memory, which is
// all a scope guard around a call needs.
#[cfg(target_arch = "x86_64")]
fn read_mxcsr() -> u32 {
    let mut mxcsr: u32 = 0;
    // SAFETY: stmxcsr stores the 32-bit MXCSR to the given address, a valid local.
    unsafe { std::arch::asm!("stmxcsr [{}]", in(reg) &mut mxcsr, options(nostack)) };
    mxcsr
}

#[cfg(target_arch = "x86_64")]
fn write_mxcsr(mxcsr: u32) {
    // SAFETY: ldmxcsr loads MXCSR from a valid local; only the FTZ and DAZ bits differ from the
    // value read, and both are defined on every x86-64 CPU.
    unsafe { std::arch::asm!("ldmxcsr [{}]", in(reg) &mxcsr, options(nostack)) };
}

#[cfg(target_arch = "aarch64")]
fn read_fpcr() -> u64 {
    let fpcr: u64;
    // SAFETY: reading FPCR has no side effects.
    unsafe { std::arch::asm!("mrs {}, fpcr", out(reg) fpcr, options(nomem, nostack)) };
    fpcr
}

#[cfg(target_arch = "aarch64")]
fn write_fpcr(fpcr: u64) {
    // SAFETY: only the FZ bit differs from the value read.
    unsafe { std::arch::asm!("msr fpcr, {}", in(reg) fpcr, options(nostack)) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hint::black_box;

    /// The smallest normal f32 halved: a subnormal, unless flushed.
    fn halved_smallest_normal() -> f32 {
        black_box(f32::MIN_POSITIVE) * black_box(0.5)
    }

    #[test]
    fn the_guard_flushes_subnormals_and_restores_the_mode() {
        assert!(halved_smallest_normal() > 0.0, "IEEE arithmetic by default");
        {
            let _flush = FlushDenormals::enable();
            if FlushDenormals::is_supported() {
                assert_eq!(halved_smallest_normal(), 0.0, "result flushed");
                let subnormal = black_box(f64::from_bits(1));
                assert_eq!(subnormal * black_box(1.0), 0.0, "input read as zero");
            }
            {
                let _nested = FlushDenormals::enable();
            }
            if FlushDenormals::is_supported() {
                assert_eq!(
                    halved_smallest_normal(),
                    0.0,
                    "a nested guard keeps flushing"
                );
            }
        }
        assert!(halved_smallest_normal() > 0.0, "the previous mode is back");
    }
}
