//! Kensler's correlated multi-jittered samples ("Correlated Multi-Jittered Sampling", Pixar
//! Technical Memo 13-01, 2013), the `stratified` sampler, with their hashed permutation and
//! jitter.

use super::to_unit;
use glam::Vec2;

/// Sample `s` of `n` of a correlated multi-jittered pattern seeded by `h`: stratified in 2D and
/// in both 1D projections, then shifted by a random toroidal offset so that every sample is
/// uniform on its own (an unbiased estimator even when `n` is not a product of strata counts).
#[inline]
pub(super) fn cmj_2d(s: u32, n: u32, h: u64) -> Vec2 {
    let p = h as u32;
    let m = ((n as f32).sqrt() as u32).max(1);
    let rows = n.div_ceil(m);
    let s = permute(s % n, n, p.wrapping_mul(0x5163_3e2d));
    let sx = permute(s % m, m, p.wrapping_mul(0x68bc_21eb));
    let sy = permute(s / m, rows, p.wrapping_mul(0x02e5_be93));
    let jx = randfloat(s, p.wrapping_mul(0x967a_889b));
    let jy = randfloat(s, p.wrapping_mul(0x368c_c8b7));
    let x = ((s % m) as f32 + (sy as f32 + jx) / rows as f32) / m as f32;
    let y = ((s / m) as f32 + (sx as f32 + jy) / m as f32) / rows as f32;
    let shift = Vec2::new(to_unit((h >> 32) as u32), to_unit((h >> 8) as u32));
    let v = Vec2::new(x, y) + shift;
    v - v.floor()
}

/// Sample `s` of `n` jittered strata in a random order seeded by `h`.
#[inline]
pub(super) fn stratified_1d(s: u32, n: u32, h: u64) -> f32 {
    let p = h as u32;
    let k = permute(s % n, n, p.wrapping_mul(0x5163_3e2d));
    let x = (k as f32 + randfloat(s, p.wrapping_mul(0x967a_889b))) / n as f32;
    // Rounding can reach 1 for large n.
    x.min(1.0 - f32::EPSILON / 2.0)
}

/// Kensler's hashed permutation of [0, l): rounds of [`hash_round`] until the value falls in
/// [0, l) (cycle walking).
fn permute(mut i: u32, l: u32, p: u32) -> u32 {
    if l == 1 {
        return 0;
    }
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i = hash_round(i, w, p);
        if i < l {
            break;
        }
    }
    (i.wrapping_add(p)) % l
}

/// [`permute`] for a power of two `mask + 1`: the first round already falls in range, so it is
/// branch-free (the Sobol sampler's index shuffle runs it across lanes).
#[inline(always)]
pub(super) fn permute_pow2(i: u32, mask: u32, p: u32) -> u32 {
    hash_round(i, mask, p).wrapping_add(p) & mask
}

/// One round of Kensler's invertible hash on the bits of `w` (a power of two less one).
#[inline(always)]
fn hash_round(mut i: u32, w: u32, p: u32) -> u32 {
    i ^= p;
    i = i.wrapping_mul(0xe170_893d);
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i = i.wrapping_mul(0x0929_eb3f);
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i = i.wrapping_mul(1 | (p >> 27));
    i = i.wrapping_mul(0x6935_fa69);
    i ^= (i & w) >> 11;
    i = i.wrapping_mul(0x74dc_b303);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0x9e50_1cc3);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0xc860_a3df);
    i &= w;
    i ^ (i >> 5)
}

/// Kensler's hashed jitter in [0, 1).
fn randfloat(mut i: u32, p: u32) -> f32 {
    i ^= p;
    i ^= i >> 17;
    i ^= i >> 10;
    i = i.wrapping_mul(0xb365_34e5);
    i ^= i >> 12;
    i ^= i >> 21;
    i = i.wrapping_mul(0x93fc_4795);
    i ^= 0xdf6e_307f;
    i ^= i >> 17;
    i = i.wrapping_mul(1 | (p >> 18));
    (i >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}
