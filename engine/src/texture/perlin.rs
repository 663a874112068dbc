//! Ken Perlin's lattice noise (Shirley's "Ray Tracing: The Next Week", ch. 5): the blocky,
//! smooth, turbulence and marble noise textures' shared table.

use glam::Vec3;
use std::sync::OnceLock;

/// Ken Perlin's lattice noise with random unit gradients (RTNW ch. 5), from a fixed seed.
#[derive(Debug)]
pub struct Perlin {
    values: [f32; 256],
    gradients: [Vec3; 256],
    perm: [[u8; 256]; 3],
}

impl Perlin {
    /// The table every texture uses (built once).
    pub fn shared() -> &'static Perlin {
        static P: OnceLock<Perlin> = OnceLock::new();
        P.get_or_init(|| Perlin::new(0x5eed))
    }

    /// Tables from a seed (splitmix64).
    pub fn new(seed: u64) -> Self {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        };
        let values = std::array::from_fn(|_| next());
        let gradients = std::array::from_fn(|_| {
            loop {
                let v = Vec3::new(2.0 * next() - 1.0, 2.0 * next() - 1.0, 2.0 * next() - 1.0);
                let l = v.length();
                if l > 0.1 && l <= 1.0 {
                    break v / l;
                }
            }
        });
        let perm = std::array::from_fn(|_| {
            let mut p: [u8; 256] = std::array::from_fn(|i| i as u8);
            for i in (1..256).rev() {
                let j = ((next() * (i + 1) as f32) as usize).min(i);
                p.swap(i, j);
            }
            p
        });
        Self { values, gradients, perm }
    }

    #[inline]
    fn hash(&self, i: i32, j: i32, k: i32) -> usize {
        (self.perm[0][(i & 255) as usize]
            ^ self.perm[1][(j & 255) as usize]
            ^ self.perm[2][(k & 255) as usize]) as usize
    }

    /// The value of the lattice cell containing `p`, in [0, 1).
    pub fn blocky(&self, p: Vec3) -> f32 {
        let c = p.floor();
        self.values[self.hash(c.x as i32, c.y as i32, c.z as i32)]
    }

    /// Gradient noise, in [-1, 1] (in fact within sqrt(3)/2).
    pub fn noise(&self, p: Vec3) -> f32 {
        let c = p.floor();
        let f = p - c;
        let (i, j, k) = (c.x as i32, c.y as i32, c.z as i32);
        // Hermite smoothing of the interpolation weights.
        let s = f * f * (3.0 - 2.0 * f);
        let mut acc = 0.0;
        for di in 0..2 {
            for dj in 0..2 {
                for dk in 0..2 {
                    let g = self.gradients[self.hash(i + di, j + dj, k + dk)];
                    let w = Vec3::new(f.x - di as f32, f.y - dj as f32, f.z - dk as f32);
                    let wx = if di == 1 { s.x } else { 1.0 - s.x };
                    let wy = if dj == 1 { s.y } else { 1.0 - s.y };
                    let wz = if dk == 1 { s.z } else { 1.0 - s.z };
                    acc += wx * wy * wz * g.dot(w);
                }
            }
        }
        acc
    }

    /// Sum over `depth` octaves of |noise|, weights 1, 1/2, 1/4, ..: in [0, 2).
    pub fn turbulence(&self, p: Vec3, depth: u32) -> f32 {
        let (mut acc, mut weight, mut q) = (0.0, 1.0, p);
        for _ in 0..depth {
            acc += weight * self.noise(q).abs();
            weight *= 0.5;
            q *= 2.0;
        }
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::{NoiseKind, Texture, Textures};
    use glam::Vec2;

    fn points() -> impl Iterator<Item = Vec3> {
        (0..20_000).map(|i| {
            let f = |a: f32| ((0.5 + i as f32 * a).fract() - 0.5) * 40.0;
            Vec3::new(f(0.754_877_7), f(0.569_840_3), f(0.362_229_6))
        })
    }

    #[test]
    fn noise_values_stay_in_their_documented_ranges() {
        let p = Perlin::shared();
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        for q in points() {
            let n = p.noise(q);
            (lo, hi) = (lo.min(n), hi.max(n));
            assert!(n.abs() <= 3f32.sqrt() / 2.0, "noise {n}");
            assert!((0.0..1.0).contains(&p.blocky(q)));
            let t = p.turbulence(q, 7);
            assert!((0.0..2.0).contains(&t), "turbulence {t}");
        }
        // Not degenerate: it uses a good part of its range.
        assert!(lo < -0.4 && hi > 0.4, "noise spans only [{lo}, {hi}]");
        let textures = Textures {
            list: vec![Texture::Noise { kind: NoiseKind::Marble, scale: 4.0, depth: 7, color: Vec3::ONE }],
        };
        for q in points() {
            let c = textures.eval(0, Vec2::ZERO, q.into());
            assert!((0.0..=1.0).contains(&c.x), "marble {c}");
        }
    }

    #[test]
    fn noise_is_continuous_and_zero_on_the_lattice() {
        let p = Perlin::shared();
        assert_eq!(p.noise(Vec3::new(3.0, -2.0, 7.0)), 0.0);
        let q = Vec3::new(1.3, 2.7, -0.4);
        assert!((p.noise(q) - p.noise(q + Vec3::splat(1e-4))).abs() < 1e-3);
    }
}
