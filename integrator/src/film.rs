//! The film: per-pixel sums and sums of squares of sample radiance (for the mean and its
//! variance), and the count of discarded non-finite samples.

use glam::Vec3;

/// Accumulated samples of an image.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel accumulated.
    pub spp: u32,
    /// Per pixel (row-major, row 0 on top): sum of sample values.
    pub sum: Vec<[f64; 3]>,
    /// Per pixel: sum of squared sample values.
    pub sum_sq: Vec<[f64; 3]>,
    /// Samples whose value was NaN or infinite; they were counted as zero.
    pub non_finite: u64,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        Self { width, height, spp: 0, sum: vec![[0.0; 3]; n], sum_sq: vec![[0.0; 3]; n], non_finite: 0 }
    }

    /// Per-pixel mean.
    pub fn mean(&self) -> Vec<Vec3> {
        let k = 1.0 / self.spp.max(1) as f64;
        self.sum.iter().map(|s| Vec3::new((s[0] * k) as f32, (s[1] * k) as f32, (s[2] * k) as f32)).collect()
    }

    /// Per-pixel variance of the mean (sample variance / spp).
    pub fn variance_of_mean(&self) -> Vec<Vec3> {
        let n = self.spp as f64;
        if n < 2.0 {
            return vec![Vec3::splat(f32::INFINITY); self.sum.len()];
        }
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, q)| {
                let v = |c: usize| (((q[c] - s[c] * s[c] / n) / (n - 1.0)).max(0.0) / n) as f32;
                Vec3::new(v(0), v(1), v(2))
            })
            .collect()
    }
}

/// Sums of one pixel's samples, with non-finite samples replaced by zero and counted.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelAccumulator {
    /// Sum of values.
    pub sum: [f64; 3],
    /// Sum of squares.
    pub sum_sq: [f64; 3],
    /// Non-finite samples seen.
    pub non_finite: u64,
}

impl PixelAccumulator {
    /// Adds one sample value.
    #[inline]
    pub fn add(&mut self, v: Vec3) {
        if !v.is_finite() {
            self.non_finite += 1;
            return;
        }
        for c in 0..3 {
            let x = v[c] as f64;
            self.sum[c] += x;
            self.sum_sq[c] += x * x;
        }
    }
}
