//! Piecewise-constant densities on [0, 1) and [0, 1)^2 (pbrt-v4's `PiecewiseConstant1D` and
//! `PiecewiseConstant2D`, appendix A.4 and A.5 of "Physically Based Rendering", 4th edition):
//! what importance-samples environment maps and analytic backgrounds.

use glam::Vec2;

/// The largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// The cell of [0, 1) split in `n` that holds `x` (x = 1 is in the last one).
#[inline]
pub(crate) fn cell_of(x: f32, n: usize) -> usize {
    ((x * n as f32) as usize).min(n - 1)
}

/// A weight as the distributions use it: negative, NaN and infinite weights count as 0.
#[inline]
pub(crate) fn clean(w: f32) -> f32 {
    if w.is_finite() && w > 0.0 { w } else { 0.0 }
}

/// A piecewise-constant density on [0, 1) made of `n` equal cells, each proportional to its
/// weight (pbrt-v4's `PiecewiseConstant1D`, appendix A.4).
///
/// A cell of weight 0 is never sampled and has density 0. Weights are accumulated in f64;
/// the CDF and the densities are stored in f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    /// The normalised CDF: `n + 1` non-decreasing entries from 0 to exactly 1.
    cdf: Vec<f32>,
    /// The density of each cell on [0, 1): weight * n / sum of weights.
    density: Vec<f32>,
    /// Sum of the weights / n (pbrt's `funcInt`: the integral of the step function).
    integral: f64,
    /// Per `k` of `n` equal slices of [0, 1), the cell that [`Self::sample_continuous`]
    /// finds for `u = k / n`: a search for `u` in slice `k` starts there and steps a cell or
    /// two (the guide table of Chen and Asau 1974, "On generating random variates from an
    /// empirical distribution"), where a binary search waited on about log2(n) dependent loads
    /// (materials-env: 17% of its time in the environment map's two searches per sample).
    guide: Vec<u32>,
}

impl Distribution1D {
    /// Builds the distribution of non-negative `weights` (negative, NaN and infinite ones count
    /// as 0). `None` when there is nothing to sample: no weights, or all of them 0.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let n = weights.len();
        let mut sum = vec![0f64; n + 1];
        for (i, &w) in weights.iter().enumerate() {
            sum[i + 1] = sum[i] + clean(w) as f64;
        }
        let total = sum[n];
        if total <= 0.0 {
            return None;
        }
        // A cell of weight 0 adds exactly 0, so its two CDF entries are equal and it is never
        // sampled; the last entry is total / total = 1 exactly.
        let cdf: Vec<f32> = sum.iter().map(|&s| (s / total) as f32).collect();
        let density = weights.iter().map(|&w| (clean(w) as f64 * n as f64 / total) as f32).collect();
        // One pass: the slices' starts grow, and so do their cells.
        let mut guide = Vec::with_capacity(n);
        let mut i = 0;
        for k in 0..n {
            let u = k as f32 / n as f32;
            while i + 1 < n && cdf[i + 1] <= u {
                i += 1;
            }
            guide.push(i as u32);
        }
        Some(Self { cdf, density, integral: total / n as f64, guide })
    }

    /// The number of cells.
    pub fn cells(&self) -> usize {
        self.density.len()
    }

    /// The integral of the step function of the weights over [0, 1]: their mean.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// The normalised CDF at the `cells() + 1` cell boundaries.
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// Inverts the CDF at `u` in [0, 1) (clamped there): returns x in [0, 1) and its density.
    /// The density is positive (it is the density of a cell of positive weight) unless that
    /// weight is below about 1e-45 of the sum of the weights.
    pub fn sample_continuous(&self, u: f32) -> (f32, f32) {
        let u = if u > 0.0 { u.min(ONE_MINUS_EPSILON) } else { 0.0 }; // NaN becomes 0
        let n = self.cells();
        // The last boundary at or below u: cdf[i] <= u < cdf[i + 1], so cdf[i + 1] > cdf[i] and
        // the cell's weight is positive (pbrt-v4's FindInterval), from the guide's cell for
        // u's slice (back a cell where the slice's rounding overshot).
        let mut i = self.guide[cell_of(u, n)] as usize;
        while i > 0 && self.cdf[i] > u {
            i -= 1;
        }
        while i + 1 < n && self.cdf[i + 1] <= u {
            i += 1;
        }
        let (c0, c1) = (self.cdf[i], self.cdf[i + 1]);
        let du = if c1 > c0 { ((u - c0) / (c1 - c0)).clamp(0.0, 1.0) } else { 0.0 };
        let x = into_cell((i as f32 + du) / n as f32, i, n);
        (x, self.density[i])
    }

    /// The density at `x` (0 outside [0, 1]).
    pub fn pdf(&self, x: f32) -> f32 {
        if (0.0..=1.0).contains(&x) { self.density[cell_of(x, self.cells())] } else { 0.0 }
    }
}

/// `x` moved by at most a few ulps so that [`cell_of`] puts it in cell `i` and it stays below 1:
/// the density [`Distribution1D::pdf`] then reads at a sampled point is the sampled cell's.
fn into_cell(x: f32, i: usize, n: usize) -> f32 {
    let mut x = x.clamp(0.0, ONE_MINUS_EPSILON);
    while cell_of(x, n) > i && x > 0.0 {
        x = x.next_down();
    }
    while cell_of(x, n) < i && x < ONE_MINUS_EPSILON {
        x = x.next_up();
    }
    x
}

/// A piecewise-constant density on [0, 1)^2 over a grid of `nu` x `nv` cells, proportional to
/// the cells' weights: a marginal density in v (one cell per row) times each row's conditional
/// density in u (pbrt-v4's `PiecewiseConstant2D`, appendix A.5). Rows whose weights are all 0
/// have no conditional density: the marginal never picks them and their density is 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    /// One density in u per row; `None` for a row of zero weight.
    conditionals: Vec<Option<Distribution1D>>,
    /// The density in v, from the rows' integrals.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// Builds the distribution of `weights`, `nu` per row, row-major: row j covers
    /// v in [j / nv, (j + 1) / nv). Negative, NaN and infinite weights count as 0. `None` when
    /// there is nothing to sample (an empty grid, or every weight 0).
    ///
    /// # Panics
    /// If `weights.len() != nu * nv`.
    pub fn new(nu: usize, nv: usize, weights: &[f32]) -> Option<Self> {
        assert_eq!(weights.len(), nu * nv, "Distribution2D: {nu} x {nv} cells need as many weights");
        if nu == 0 || nv == 0 {
            return None;
        }
        let conditionals: Vec<_> = weights.chunks_exact(nu).map(Distribution1D::new).collect();
        let rows: Vec<f32> =
            conditionals.iter().map(|c| c.as_ref().map_or(0.0, |c| c.integral() as f32)).collect();
        let marginal = Distribution1D::new(&rows)?;
        Some(Self { conditionals, marginal })
    }

    /// The integral of the step function of the weights over the unit square: their mean.
    pub fn integral(&self) -> f64 {
        self.marginal.integral()
    }

    /// Maps `u` in [0, 1)^2 to a point of [0, 1)^2 (`u.y` picks the row, `u.x` the point in it)
    /// and returns it with its density, which equals [`Self::pdf`] there exactly.
    pub fn sample_continuous(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v) = self.marginal.sample_continuous(u.y);
        // The marginal only picks rows of positive weight, which have a conditional density.
        match &self.conditionals[cell_of(v, self.marginal.cells())] {
            Some(row) => {
                let (x, pdf_u) = row.sample_continuous(u.x);
                (Vec2::new(x, v), pdf_v * pdf_u)
            }
            None => (Vec2::new(u.x.clamp(0.0, ONE_MINUS_EPSILON), v), 0.0),
        }
    }

    /// The density at `p` (0 outside the unit square).
    pub fn pdf(&self, p: Vec2) -> f32 {
        let pdf_v = self.marginal.pdf(p.y);
        if pdf_v == 0.0 {
            return 0.0;
        }
        match &self.conditionals[cell_of(p.y, self.marginal.cells())] {
            Some(row) => pdf_v * row.pdf(p.x),
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform;

    /// The cell of the last boundary of `cdf` at or below `u` (the last cell for u >= 1): the
    /// binary search that the guide table replaces.
    fn search(cdf: &[f32], u: f32) -> usize {
        (cdf.partition_point(|&c| c <= u) - 1).min(cdf.len() - 2)
    }

    /// The guided search finds the binary search's cell for every u: at and beside every CDF
    /// entry (runs of equal entries from zero weights included), at and just below slice
    /// starts, 0 and the largest u, over weights from uniform (1 to 199 cells) to a spike.
    /// (Starting the search at the slice's guide without stepping back, or stopping the steps
    /// forward before equal entries, fails.)
    #[test]
    fn guided_search_finds_the_binary_searchs_cell() {
        let mut r = crate::testing::signed(11);
        let spike: Vec<f32> = (0..97).map(|i| if i == 40 { 1e6 } else { 1.0 }).collect();
        let gaps: Vec<f32> = (0..64).map(|i| if i % 5 < 2 { 0.0 } else { (i % 7) as f32 + 0.5 }).collect();
        let noisy: Vec<f32> = (0..300).map(|_| (1.0 + r()).powi(8)).collect();
        let uniform = (1..200).map(|n| vec![1.0; n]);
        for weights in [spike, gaps, noisy].into_iter().chain(uniform) {
            let d = Distribution1D::new(&weights).unwrap();
            let n = d.cells();
            let mut us: Vec<f32> = vec![0.0, ONE_MINUS_EPSILON];
            for &c in &d.cdf {
                us.extend([c, c.next_up(), c.next_down()]);
            }
            us.extend((0..n).flat_map(|k| [k as f32 / n as f32, (k as f32 / n as f32).next_down()]));
            us.extend((0..1000).map(|_| 0.5 + 0.5 * r()));
            for u in us.into_iter().filter(|u| (0.0..1.0).contains(u)) {
                let (x, _) = d.sample_continuous(u);
                assert_eq!(cell_of(x, n), search(&d.cdf, u), "u {u}");
            }
        }
    }

    #[test]
    fn distribution_1d_samples_cells_in_proportion_and_never_zero_ones() {
        let d = Distribution1D::new(&[0.0, 1.0, 0.0, 3.0, f32::NAN, -2.0]).unwrap();
        assert_eq!(d.cdf(), &[0.0, 0.0, 0.25, 0.25, 1.0, 1.0, 1.0]);
        assert_eq!(d.cells(), 6);
        assert!((d.integral() - 4.0 / 6.0).abs() < 1e-12);
        assert_eq!(d.sample_continuous(0.0), (1.0 / 6.0, 1.5));
        assert_eq!(d.sample_continuous(0.25), (0.5, 4.5));
        for u in [1.0, 2.0, f32::NAN, -1.0, ONE_MINUS_EPSILON] {
            let (x, p) = d.sample_continuous(u);
            assert!((0.0..1.0).contains(&x) && p > 0.0 && p == d.pdf(x), "{u} {x} {p}");
        }
        assert_eq!((d.pdf(0.1), d.pdf(0.2), d.pdf(0.4), d.pdf(0.6), d.pdf(0.9)), (0.0, 1.5, 0.0, 4.5, 0.0));
        assert_eq!((d.pdf(-0.1), d.pdf(1.1), d.pdf(f32::NAN)), (0.0, 0.0, 0.0));
        let mut r = uniform(7);
        let mut count = [0usize; 6];
        let n = 100_000;
        for _ in 0..n {
            let (x, p) = d.sample_continuous(r());
            assert!((0.0..1.0).contains(&x) && p > 0.0 && p == d.pdf(x));
            count[cell_of(x, 6)] += 1;
        }
        assert_eq!((count[0], count[2], count[4], count[5]), (0, 0, 0, 0));
        assert!((count[3] as f64 / n as f64 - 0.75).abs() < 0.01, "{count:?}");
        // Nothing to sample.
        assert!(Distribution1D::new(&[]).is_none());
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
        assert!(Distribution1D::new(&[f32::INFINITY, -1.0]).is_none());
        // Boundaries that f32 cannot place exactly: the sample stays in its cell.
        let d = Distribution1D::new(&[1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]).unwrap();
        for k in 0..=1000 {
            let (x, p) = d.sample_continuous(k as f32 / 1000.0);
            assert!(p > 0.0 && d.pdf(x) == p, "{k} {x}");
        }
    }

    #[test]
    fn distribution_2d_skips_zero_rows_and_integrates_to_one() {
        let (nu, nv) = (5, 4);
        let w = [
            0.0, 0.0, 0.0, 0.0, 0.0, //
            1.0, 2.0, 0.0, 0.0, 4.0, //
            0.0, 0.0, 0.0, 0.0, 0.0, //
            0.0, 0.0, 3.0, 0.0, 0.0,
        ];
        let d = Distribution2D::new(nu, nv, &w).unwrap();
        assert!((d.integral() - 10.0 / 20.0).abs() < 1e-12);
        let mut total = 0.0;
        for j in 0..nv {
            for i in 0..nu {
                let p = d.pdf(Vec2::new((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nv as f32));
                assert!((p - w[j * nu + i] * 20.0 / 10.0).abs() < 1e-6);
                total += p / (nu * nv) as f32;
            }
        }
        assert!((total - 1.0).abs() < 1e-6);
        let mut r = uniform(9);
        for _ in 0..10000 {
            let (p, pdf) = d.sample_continuous(Vec2::new(r(), r()));
            assert!(pdf > 0.0 && pdf == d.pdf(p), "{p} {pdf}");
        }
        assert!(Distribution2D::new(3, 2, &[0.0; 6]).is_none());
        assert!(Distribution2D::new(0, 2, &[]).is_none());
    }
}
