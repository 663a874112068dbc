//! The film: per-pixel exact sums and sums of squares of sample radiance (for the mean and its
//! variance), and the count of discarded non-finite samples (and absurdly large ones).

use crate::aov::Aovs;
use crate::costs::PixelCosts;
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
    /// Per pixel (row-major, row 0 on top): the samples' exact sums.
    pub pixels: Vec<PixelAccumulator>,
    /// The denoiser's guides over the same samples, when the integrator recorded them.
    pub guides: Option<Aovs>,
    /// What the pixels cost, when the integrator measured it: over the samples it rendered
    /// (a film resumed from a checkpoint has costs of the samples rendered since).
    pub costs: Option<PixelCosts>,
}

impl Film {
    /// An empty film. Its pixels are allocated zeroed (`bytemuck::zeroed_vec`), so that the
    /// memory is faulted in where the samples are first written, not here as well: a
    /// 256x256 film is 6.8 MB, and `vec![PixelAccumulator::default(); n]` wrote every byte.
    pub fn new(width: u32, height: u32) -> Self {
        let pixels = bytemuck::zeroed_vec(width as usize * height as usize);
        Self { width, height, spp: 0, pixels, guides: None, costs: None }
    }

    /// Per-pixel mean.
    pub fn mean(&self) -> Vec<Vec3> {
        let k = 1.0 / self.spp.max(1) as f64;
        self.pixels
            .iter()
            .map(|p| {
                let s = p.sum();
                Vec3::new((s[0] * k) as f32, (s[1] * k) as f32, (s[2] * k) as f32)
            })
            .collect()
    }

    /// Adds the samples of another film of the same size (other sample indices of the same
    /// pixels): the sums are exact, so the result has the same bits as rendering them all at
    /// once.
    pub fn merge(&mut self, o: &Film) {
        assert_eq!((self.width, self.height), (o.width, o.height), "films of different sizes");
        // Guides over all the samples: weighted means where both have them (or only one film
        // has samples), none where some samples have none.
        self.guides = match (self.guides.take(), &o.guides) {
            (Some(mut a), Some(b)) => {
                let (wa, wb) = (self.spp as f32, o.spp as f32);
                let mix = |x: &mut Vec<Vec3>, y: &Vec<Vec3>| {
                    x.iter_mut().zip(y).for_each(|(x, y)| *x = (*x * wa + *y * wb) / (wa + wb).max(1.0))
                };
                mix(&mut a.albedo, &b.albedo);
                mix(&mut a.normal, &b.normal);
                mix(&mut a.emission, &b.emission);
                Some(a)
            }
            (a, b) if self.spp == 0 => b.clone().or(a),
            (a, _) if o.spp == 0 => a,
            _ => None,
        };
        match (&mut self.costs, &o.costs) {
            (Some(a), Some(b)) => a.merge(b),
            (a @ None, Some(b)) => *a = Some(b.clone()),
            _ => {}
        }
        self.spp += o.spp;
        self.pixels.iter_mut().zip(&o.pixels).for_each(|(a, b)| a.merge(b));
    }

    /// [`Self::merge`] of a film this one may keep: an empty film (no samples, guides or costs)
    /// takes `o` as it is, so the first pass of a render costs no second image's memory
    /// (zeroed pages faulted in, then a pass adding every pixel: 3-5 ms of a 256x256 render).
    pub fn absorb(&mut self, o: Film) {
        assert_eq!((self.width, self.height), (o.width, o.height), "films of different sizes");
        match self.spp == 0 && self.guides.is_none() && self.costs.is_none() {
            true => *self = o,
            false => self.merge(&o),
        }
    }

    /// Samples whose value was NaN, infinite or above [`MAX_SAMPLE`]; they were counted as zero.
    pub fn non_finite(&self) -> u64 {
        self.pixels.iter().fold(0u64, |n, p| n.saturating_add(p.non_finite))
    }

    /// Pixels (row-major index) that discarded non-finite samples, with how many.
    pub fn non_finite_pixels(&self) -> Vec<(u32, u64)> {
        let bad = self.pixels.iter().enumerate().filter(|(_, p)| p.non_finite > 0);
        bad.map(|(i, p)| (i as u32, p.non_finite)).collect()
    }

    /// Per-pixel variance of the mean (sample variance / spp).
    pub fn variance_of_mean(&self) -> Vec<Vec3> {
        let n = self.spp as f64;
        if n < 2.0 {
            return vec![Vec3::splat(f32::INFINITY); self.pixels.len()];
        }
        self.pixels
            .iter()
            .map(|p| {
                let (s, q) = (p.sum(), p.sum_sq());
                let v = |c: usize| (((q[c] - s[c] * s[c] / n) / (n - 1.0)).max(0.0) / n) as f32;
                Vec3::new(v(0), v(1), v(2))
            })
            .collect()
    }
}

/// With `Some(max)`, scales a sample down so that its largest component is at most `max`
/// (trades bias for fewer fireflies; off by default). Non-finite samples pass unchanged, to be
/// counted by the accumulator.
#[inline]
pub fn clamp_sample(v: Vec3, max: Option<f32>) -> Vec3 {
    match max {
        Some(m) if v.max_element() > m => v * (m / v.max_element()),
        _ => v,
    }
}

/// Fixed-point scale of the exact sums: 2^50 (values below 1e-15 vanish).
const FIXED: f64 = (1u64 << 50) as f64;

/// Samples with a component above this are treated like infinite ones (discarded and counted):
/// it keeps every pixel sum exact for up to 1.5e11 samples. Squares of samples above about
/// 4e11 saturate the sum of squares, and the pixel's variance reads as infinite.
pub const MAX_SAMPLE: f32 = 1e12;

/// `v as i128` (truncated, saturating), through one `i64` conversion instruction when `v`
/// fits (samples below 8192): the `i128` conversion is a library call.
#[inline(always)]
fn fixed(v: f64) -> i128 {
    if v.abs() < 9.2e18 { v as i64 as i128 } else { v as i128 }
}

/// Sums of one pixel's samples, with non-finite samples replaced by zero and counted.
///
/// The sums are exact fixed-point integers: adding samples in any order gives the same bits, so
/// an integrator may finish a pixel's samples in whatever order its scheduling produces and
/// still write the image that the sequential reference writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
pub struct PixelAccumulator {
    sum: [i128; 3],
    sum_sq: [i128; 3],
    /// Non-finite (or above [`MAX_SAMPLE`]) samples seen.
    pub non_finite: u64,
}

impl PixelAccumulator {
    /// Adds one sample value.
    #[inline]
    pub fn add(&mut self, v: Vec3) {
        if !(v.is_finite() && v.abs().max_element() <= MAX_SAMPLE) {
            self.non_finite += 1;
            return;
        }
        for c in 0..3 {
            let x = v[c] as f64;
            // Saturating (`as` saturates too): for the non-negative values of radiance the
            // result is the same in any order.
            self.sum[c] = self.sum[c].saturating_add(fixed(x * FIXED));
            self.sum_sq[c] = self.sum_sq[c].saturating_add(fixed(x * x * FIXED));
        }
    }

    /// Adds another accumulator's samples.
    #[inline]
    pub fn merge(&mut self, o: &PixelAccumulator) {
        for c in 0..3 {
            self.sum[c] = self.sum[c].saturating_add(o.sum[c]);
            self.sum_sq[c] = self.sum_sq[c].saturating_add(o.sum_sq[c]);
        }
        self.non_finite = self.non_finite.saturating_add(o.non_finite);
    }

    /// The exact state: fixed-point sums and sums of squares (2^50 units) and the count of
    /// discarded samples, for checkpoints.
    pub fn raw(&self) -> ([i128; 3], [i128; 3], u64) {
        (self.sum, self.sum_sq, self.non_finite)
    }

    /// An accumulator from [`Self::raw`]'s parts.
    pub fn from_raw(sum: [i128; 3], sum_sq: [i128; 3], non_finite: u64) -> Self {
        Self { sum, sum_sq, non_finite }
    }

    /// Sum of the values.
    pub fn sum(&self) -> [f64; 3] {
        self.sum.map(|s| s as f64 / FIXED)
    }

    /// Sum of the squared values (infinite where it saturated).
    pub fn sum_sq(&self) -> [f64; 3] {
        self.sum_sq.map(|s| if s == i128::MAX { f64::INFINITY } else { s as f64 / FIXED })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_do_not_depend_on_order() {
        let values: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::splat((i as f32 * 0.7368).sin().abs() * 10f32.powi(i % 13 - 6)))
            .collect();
        let mut a = PixelAccumulator::default();
        let mut b = PixelAccumulator::default();
        values.iter().for_each(|v| a.add(*v));
        values.iter().rev().for_each(|v| b.add(*v));
        assert_eq!(a, b);
        let exact: f64 = values.iter().map(|v| v.x as f64).sum();
        assert!((a.sum()[0] - exact).abs() < 1e-9 * exact);
    }

    #[test]
    fn a_new_film_holds_no_samples() {
        let film = Film::new(3, 2);
        assert_eq!(film.pixels, vec![PixelAccumulator::default(); 6]);
        assert_eq!((film.spp, film.non_finite()), (0, 0));
    }

    #[test]
    fn absorbing_a_film_equals_merging_it() {
        let film = |spp: u32, v: f32| {
            let mut f = Film::new(2, 1);
            f.spp = spp;
            for _ in 0..spp {
                f.pixels.iter_mut().for_each(|p| p.add(Vec3::splat(v)));
            }
            f
        };
        for (a, b) in
            [(film(0, 0.0), film(3, 0.5)), (film(2, 0.25), film(3, 0.5)), (film(2, 0.25), film(0, 0.0))]
        {
            let (mut merged, mut absorbed) = (a.clone(), a);
            merged.merge(&b);
            absorbed.absorb(b);
            assert_eq!(merged, absorbed);
        }
    }

    #[test]
    fn clamping_scales_bright_samples_only() {
        assert_eq!(clamp_sample(Vec3::new(8.0, 4.0, 2.0), Some(2.0)), Vec3::new(2.0, 1.0, 0.5));
        assert_eq!(clamp_sample(Vec3::new(1.0, 0.5, 0.0), Some(2.0)), Vec3::new(1.0, 0.5, 0.0));
        assert_eq!(clamp_sample(Vec3::splat(100.0), None), Vec3::splat(100.0));
        assert!(clamp_sample(Vec3::splat(f32::NAN), Some(1.0)).is_nan());
    }

    #[test]
    fn non_finite_samples_are_counted_not_summed() {
        let mut a = PixelAccumulator::default();
        a.add(Vec3::new(f32::NAN, 1.0, 1.0));
        a.add(Vec3::splat(f32::INFINITY));
        a.add(Vec3::ONE);
        assert_eq!(a.non_finite, 2);
        assert_eq!(a.sum(), [1.0; 3]);
    }

    #[test]
    fn huge_samples_neither_overflow_nor_depend_on_order() {
        // Found by the fuzzer: an emitter of 6.7e28 overflowed the fixed-point sums.
        let mut a = PixelAccumulator::default();
        a.add(Vec3::splat(2e12));
        assert_eq!((a.non_finite, a.sum()), (1, [0.0; 3]));
        let values = [Vec3::splat(9e11), Vec3::splat(1.0), Vec3::splat(9e11), Vec3::splat(0.25)];
        let (mut a, mut b) = (PixelAccumulator::default(), PixelAccumulator::default());
        values.iter().for_each(|v| a.add(*v));
        values.iter().rev().for_each(|v| b.add(*v));
        assert_eq!(a, b);
        assert_eq!(a.sum()[0], 2.0 * 9e11f32 as f64 + 1.25);
        assert_eq!(a.sum_sq()[0], f64::INFINITY, "the squares saturate: the variance is unknown");
    }
}
