//! What each pixel cost: time, paths, bounces and rays, as pbrt-v4's pixel statistics
//! (`--pixelstats`) give them, here from the wavefront's queues. A stage's time is shared out
//! evenly among the items (rays or paths) it took, and each item's share goes to the pixel of
//! the path that owns it: a stage that runs a tile's paths in lanes has no finer clock, and
//! pixels whose paths reach costly stages more often (or go on longer) cost more.

/// Per-pixel costs over some samples of a set of pixels (row-major).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PixelCosts {
    /// Seconds of stage time apportioned to the pixel's paths.
    pub time: Vec<f64>,
    /// Paths (samples) finished.
    pub paths: Vec<u32>,
    /// Bounces of the finished paths, summed (null crossings left out).
    pub bounces: Vec<u64>,
    /// Rays cast: closest-hit and shadow rays.
    pub rays: Vec<u64>,
}

impl PixelCosts {
    /// No costs yet, for `n` pixels.
    pub fn new(n: usize) -> Self {
        Self { time: vec![0.0; n], paths: vec![0; n], bounces: vec![0; n], rays: vec![0; n] }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether there are no pixels.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Adds the costs of other samples of the same pixels.
    pub fn merge(&mut self, o: &PixelCosts) {
        assert_eq!(self.len(), o.len(), "costs of different pixels");
        self.time.iter_mut().zip(&o.time).for_each(|(a, b)| *a += b);
        self.paths.iter_mut().zip(&o.paths).for_each(|(a, b)| *a += b);
        self.bounces.iter_mut().zip(&o.bounces).for_each(|(a, b)| *a += b);
        self.rays.iter_mut().zip(&o.rays).for_each(|(a, b)| *a += b);
    }

    /// Copies pixel `from` of `o` to pixel `to`.
    pub fn set(&mut self, to: usize, o: &PixelCosts, from: usize) {
        self.time[to] = o.time[from];
        self.paths[to] = o.paths[from];
        self.bounces[to] = o.bounces[from];
        self.rays[to] = o.rays[from];
    }

    /// Mean bounces per path of each pixel (0 where no path finished).
    pub fn mean_bounces(&self) -> Vec<f32> {
        self.bounces.iter().zip(&self.paths).map(|(&b, &n)| b as f32 / n.max(1) as f32).collect()
    }

    /// Total seconds over all pixels.
    pub fn total_time(&self) -> f64 {
        self.time.iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merging_adds_pixel_by_pixel() {
        let mut a = PixelCosts::new(2);
        a.time[0] = 1.0;
        a.paths[1] = 3;
        a.bounces[1] = 7;
        a.rays[0] = 5;
        let mut b = a.clone();
        b.time[1] = 0.5;
        a.merge(&b);
        assert_eq!(a.time, [2.0, 0.5]);
        assert_eq!(a.mean_bounces(), [0.0, 14.0 / 6.0]);
        assert_eq!((a.paths, a.bounces, a.rays), (vec![0, 6], vec![0, 14], vec![10, 0]));
    }
}
