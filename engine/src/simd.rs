//! Run-time choice of the instruction set for the loops that compute across lanes (ray
//! streams, sample numbers, shading kernels).
//!
//! The build's baseline is AVX2 + FMA (`x86-64-v3`). Where the CPU also has AVX-512 (F, DQ, BW,
//! VL), [`lanes`] runs its closure compiled for it: 16 lanes of `f32` per instruction instead of
//! 8, and native 64-bit integer multiplies for the sample hashes. The loops are lane-parallel
//! IEEE operations (no reductions across lanes, no FMA contraction: Rust never fuses a multiply
//! and an add on its own), so both instruction sets give the same bits, which
//! `tests/isa.rs` checks on a whole render. `PATHWAVE_ISA=avx2` keeps the baseline (to compare,
//! or to work around a CPU that clocks down under AVX-512).
//!
//! Why not the `multiversion` crate: it offers no way to choose the baseline at run time on a
//! CPU that has the wider set, which the equal-bits test and the override need; the mechanism
//! is the one below, a `#[target_feature]` function into which the closure is inlined.

#![cfg_attr(
    target_arch = "x86_64",
    expect(
        unsafe_code,
        reason = "a `#[target_feature]` function called after the run-time check, and a movemask"
    )
)]

use std::sync::OnceLock;

/// The environment variable that chooses the lane loops' instruction set: `avx2` (the
/// baseline), `avx512` or `auto` (the default: AVX-512 where the CPU has it).
pub const ISA_VAR: &str = "PATHWAVE_ISA";

/// Whether the lane loops run with AVX-512 (decided once per process). A value of
/// [`ISA_VAR`] that names no set, or AVX-512 on a CPU without it, is reported as a warning and
/// the CPU's best set is used.
#[inline]
pub fn avx512() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| {
        let wanted = std::env::var(ISA_VAR).unwrap_or_default().to_ascii_lowercase();
        match wanted.as_str() {
            "avx2" => false,
            "" | "auto" => cpu_has_avx512(),
            "avx512" if cpu_has_avx512() => true,
            "avx512" => {
                tracing::warn!("{ISA_VAR}=avx512, but this CPU lacks AVX-512 (F, DQ, BW, VL): using AVX2");
                false
            }
            other => {
                tracing::warn!(
                    "{ISA_VAR}={other:?} names no instruction set (avx2, avx512 or auto): using auto"
                );
                cpu_has_avx512()
            }
        }
    })
}

/// Whether the CPU has the AVX-512 subsets the lane loops use, whatever [`ISA_VAR`] says.
#[cfg(target_arch = "x86_64")]
pub fn cpu_has_avx512() -> bool {
    is_x86_feature_detected!("avx512f")
        && is_x86_feature_detected!("avx512dq")
        && is_x86_feature_detected!("avx512bw")
        && is_x86_feature_detected!("avx512vl")
}

/// Whether the CPU has the AVX-512 subsets the lane loops use (never, off x86-64).
#[cfg(not(target_arch = "x86_64"))]
pub fn cpu_has_avx512() -> bool {
    false
}

/// The instruction set the lane loops run with, for logs and benchmark records.
pub fn isa_name() -> &'static str {
    if avx512() { "avx512" } else { "avx2" }
}

/// Runs `f`, compiled for AVX-512 when [`avx512`] allows. Mark the closure
/// `#[inline(always)]` and keep its hot callees `#[inline]`: only code inlined into it is
/// compiled for the wider set.
#[inline(always)]
pub fn lanes<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if avx512() {
        // SAFETY: `avx512` checked at run time that the CPU has every feature enabled below.
        return unsafe { with_avx512(f) };
    }
    f()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512bw,avx512vl")]
unsafe fn with_avx512<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// The bit mask of 16 flags, flag `l` at bit `l`: one shift and a byte `movemask` on x86-64.
/// The loop `m |= (b[l] as u32) << l` vectorises as a tree of variable shifts and ORs (nine
/// instructions where one does), 4-5% of spheres-sky's time in its BVH packets.
#[inline(always)]
pub fn mask16(b: &[bool; 16]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of x86-64; the load reads the 16 bytes of `b` (a bool is the byte 0
    // or 1, so shifting each byte's low bit to its top gives `movemask` the flags).
    unsafe {
        use std::arch::x86_64::*;
        let v = _mm_loadu_si128(b.as_ptr().cast());
        _mm_movemask_epi8(_mm_slli_epi16::<7>(v)) as u32
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let mut m = 0u32;
        for (l, &x) in b.iter().enumerate() {
            m |= (x as u32) << l;
        }
        m
    }
}
