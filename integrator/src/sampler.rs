//! Counter-based random numbers: every value is a hash of (seed, pixel, sample index, dimension),
//! so an image does not depend on thread count, scheduling or batch size.

use glam::Vec2;

/// MurmurHash3's 64-bit finaliser: a bijective mixer with full avalanche.
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    x ^ (x >> 33)
}

/// The random numbers of one pixel sample, drawn one dimension after the other.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
    dim: u64,
}

impl Sampler {
    /// The stream of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    pub fn new(seed: u64, pixel: u32, sample: u32) -> Self {
        let key = mix64(mix64(seed) ^ (((pixel as u64) << 32) | sample as u64));
        Self { key, dim: 0 }
    }

    /// Next value, uniform in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let h = mix64(self.key ^ self.dim.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        self.dim += 1;
        (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// The value [`Self::next_1d`] would return, without consuming it.
    #[inline]
    pub fn peek_1d(&self) -> f32 {
        let mut s = *self;
        s.next_1d()
    }

    /// Next two values.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}

/// Position of sample `s` of `n` inside pixel `pixel` (in [0,1)^2): correlated multi-jittered
/// sampling (Kensler 2013), stratified in 2D and in both 1D projections for any `n`, then
/// shifted by a per-pixel random toroidal offset so that every sample is uniform over the pixel
/// (an unbiased box filter even when `n` is not a product of two strata counts).
#[inline]
pub fn pixel_sample(seed: u64, pixel: u32, s: u32, n: u32) -> Vec2 {
    let h = mix64(mix64(seed ^ 0x5bd1_e995) ^ pixel as u64);
    let p = h as u32;
    let m = ((n as f32).sqrt() as u32).max(1);
    let rows = n.div_ceil(m);
    let s = permute(s, n, p.wrapping_mul(0x5163_3e2d));
    let sx = permute(s % m, m, p.wrapping_mul(0x68bc_21eb));
    let sy = permute(s / m, rows, p.wrapping_mul(0x02e5_be93));
    let jx = randfloat(s, p.wrapping_mul(0x967a_889b));
    let jy = randfloat(s, p.wrapping_mul(0x368c_c8b7));
    let x = ((s % m) as f32 + (sy as f32 + jx) / rows as f32) / m as f32;
    let y = ((s / m) as f32 + (sx as f32 + jy) / m as f32) / rows as f32;
    let shift = Vec2::new((h >> 40) as f32, ((h >> 16) & 0xff_ffff) as f32) * (1.0 / (1u32 << 24) as f32);
    let v = Vec2::new(x, y) + shift;
    v - v.floor()
}

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
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    (i.wrapping_add(p)) % l
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_deterministic_and_distinct() {
        let a: Vec<f32> = (0..8)
            .map({
                let mut s = Sampler::new(7, 3, 1);
                move |_| s.next_1d()
            })
            .collect();
        let b: Vec<f32> = (0..8)
            .map({
                let mut s = Sampler::new(7, 3, 1);
                move |_| s.next_1d()
            })
            .collect();
        let c = Sampler::new(7, 3, 2).next_1d();
        assert_eq!(a, b);
        assert_ne!(a[0], c);
        assert!(a.iter().all(|x| (0.0..1.0).contains(x)));
    }

    #[test]
    fn uniform_mean_and_variance() {
        let n = 200_000;
        let (mut m, mut m2) = (0.0f64, 0.0f64);
        for i in 0..n {
            let x = Sampler::new(1, i, 0).next_1d() as f64;
            m += x;
            m2 += x * x;
        }
        let (mean, var) = (m / n as f64, m2 / n as f64 - (m / n as f64).powi(2));
        assert!((mean - 0.5).abs() < 0.003, "{mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.002, "{var}");
    }

    #[test]
    fn pixel_samples_are_stratified_for_any_count() {
        for n in [1u32, 4, 7, 16, 33, 64] {
            let pts: Vec<Vec2> = (0..n).map(|s| pixel_sample(0, 42, s, n)).collect();
            assert!(pts.iter().all(|p| (0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y)));
            // 1D projections: one sample per stratum of width 1/n (up to the toroidal shift, which
            // moves every point by the same amount: strata counts stay at most 2).
            for axis in 0..2 {
                let mut count = vec![0; n as usize];
                for p in &pts {
                    count[((p[axis] * n as f32) as usize).min(n as usize - 1)] += 1;
                }
                assert!(count.iter().all(|&c| c <= 2), "n {n} axis {axis} {count:?}");
            }
        }
    }

    #[test]
    fn pixel_samples_are_uniform_over_pixels() {
        // Averaged over many pixels, every sample index covers the pixel uniformly (unbiased
        // box filter): the mean position is the pixel centre for each index.
        for n in [3u32, 10] {
            for s in 0..n {
                let mean = (0..20_000).map(|px| pixel_sample(5, px, s, n)).sum::<Vec2>() / 20_000.0;
                assert!((mean - Vec2::splat(0.5)).length() < 0.01, "n {n} s {s}: {mean}");
            }
        }
    }
}
