//! The directions' distributions as the render reads them: each cell's directional tree
//! ([`DTree`](super::DTree)) integrated over a fixed grid of bins on the square, with an alias
//! table (Walker 1977, "An efficient method for generating discrete random variables with
//! general distributions", ACM TOMS; Vose 1991's construction) to draw a bin. A lookup or a draw
//! is then a few loads, the same for every lane, where a walk down a tree goes level by level
//! and lane by lane: the guided Lambertian kernel ran at 5.5 M hits/s with the walks, and the
//! tree's detail below a bin (1/16 of the square a side) bought little (veach-bidir: the trees
//! cut at 16x16 gave 1.1x the variance of the full trees).

/// Bins a side of a cell's grid.
pub const SIDE: usize = 16;
/// Bins a cell.
pub const BINS: usize = SIDE * SIDE;
/// Bits of a bin's number.
const BIN_BITS: u32 = BINS.trailing_zeros();

/// Every cell's grid: bin `b` of grid `g` at `g * BINS + b`. A bin takes 8 bytes, a cell 2 KiB:
/// a guide's few hundred cells stay near a core's L2 cache, where loads from 32x32 grids of
/// 12 bytes a bin missed (the guided Lambertian stage on veach-bidir, 512x512, one thread: 6.6 M
/// hits/s with those, 8.5 with these).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Grids {
    /// The density over the square in each bin.
    pdf: Vec<f32>,
    /// The alias table, one word a bin: the probability of keeping the bin when it is drawn
    /// uniformly (fixed point, the high bits) and the bin taken otherwise (the low bits).
    alias: Vec<u32>,
}

impl Grids {
    /// Grids held.
    pub(super) fn len(&self) -> usize {
        self.pdf.len() / BINS
    }

    /// Adds the grid of the bins' masses `m` ([`BINS`] of them, summing to 1, bin `(i, j)` at
    /// `i * SIDE + j`) and returns its index.
    pub fn push(&mut self, m: &[f64]) -> u32 {
        assert_eq!(m.len(), BINS, "a grid's bins");
        let g = self.len() as u32;
        let total: f64 = m.iter().sum();
        let scaled: Vec<f64> = m.iter().map(|&x| x / total * BINS as f64).collect();
        self.pdf.extend(scaled.iter().map(|&x| x as f32));
        // Vose: bins under the mean are topped up by one above it, which then takes their
        // place below or above. Rounding leaves some with about 1: they keep themselves.
        let (mut keep, mut alias) = (vec![1.0f64; BINS], (0..BINS as u32).collect::<Vec<_>>());
        let mut work = scaled;
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..BINS).partition(|&b| work[b] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            keep[s] = work[s];
            alias[s] = l as u32;
            work[l] -= 1.0 - work[s];
            if work[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        for b in small.into_iter().chain(large) {
            (keep[b], alias[b]) = (1.0, b as u32);
        }
        // A kept share as the fixed point `k / 2^(32 - BIN_BITS)`, below 1 (a bin kept
        // whole is its own alias).
        let one = (1u64 << (32 - BIN_BITS)) as f64;
        let fixed = |k: f64| ((k * one).round().min(one - 1.0) as u32) << BIN_BITS;
        self.alias.extend(keep.iter().zip(&alias).map(|(&k, &a)| fixed(k) | a));
        g
    }

    /// The densities and alias words ([`super::Guide::to_parts`]).
    pub(super) fn to_parts(&self) -> (Vec<f32>, Vec<u32>) {
        (self.pdf.clone(), self.alias.clone())
    }

    /// The grids of densities `pdf` and alias words `alias`, checked: whole grids, at least
    /// one, the densities finite and not negative (an alias word names a bin of its grid
    /// whatever its bits).
    pub(super) fn from_parts((pdf, alias): (Vec<f32>, Vec<u32>)) -> Result<Grids, String> {
        if pdf.is_empty() || pdf.len() % BINS != 0 || alias.len() != pdf.len() {
            return Err(format!(
                "a guide's grids hold {} densities and {} alias words: whole grids of {BINS} bins expected",
                pdf.len(),
                alias.len()
            ));
        }
        if let Some(k) = pdf.iter().position(|p| !(p.is_finite() && *p >= 0.0)) {
            return Err(format!("a guide's bin {k} has the density {}", pdf[k]));
        }
        Ok(Grids { pdf, alias })
    }

    /// Looks up the grids `g` (an index below [`Self::len`]), lane by lane: a lane that
    /// `draw`s draws a point of the square with the numbers `at` (in [0, 1)), the others find
    /// the point `at` (in [0, 1]). Returns the points (drawn, or `at`) and the densities over the
    /// square there.
    #[inline(always)]
    pub fn lookup_lanes<const N: usize>(
        &self,
        g: &[u32; N],
        draw: &[bool; N],
        at: &[[f32; N]; 2],
    ) -> ([[f32; N]; 2], [f32; N]) {
        const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;
        let (pdf, alias) = (&self.pdf[..], &self.alias[..self.pdf.len()]);
        assert!(!pdf.is_empty(), "a grid at least");
        let (last, side) = (pdf.len() - 1, SIDE as f32);
        let fixed = 1.0 / (1u64 << (32 - BIN_BITS)) as f32;
        let (mut s, mut p) = (*at, [0.0f32; N]);
        for l in 0..N {
            // (Indices in u32, which the lanes convert to and from floats in vector registers.)
            let base = g[l] as usize * BINS;
            // A drawn bin: uniform, then kept or swapped for its alias by the rest of the number.
            let t = at[0][l] * BINS as f32;
            let k = (t as u32).min(BINS as u32 - 1);
            let coin = t - k as f32;
            let word = alias[(base + k as usize).min(last)];
            let keep = (word >> BIN_BITS) as f32 * fixed;
            let kept = coin < keep;
            let drawn = if kept { k } else { word & (BINS as u32 - 1) };
            let rest = if kept { coin / keep } else { (coin - keep) / (1.0 - keep) };
            // A found bin.
            let (fx, fy) = ((at[0][l] * side) as u32, (at[1][l] * side) as u32);
            let found = fx.min(SIDE as u32 - 1) * SIDE as u32 + fy.min(SIDE as u32 - 1);
            let b = if draw[l] { drawn } else { found };
            p[l] = pdf[(base + b as usize).min(last)];
            // The drawn point within its bin (rounding must not carry it over the far edges).
            let (bx, by) = ((b / SIDE as u32) as f32, (b % SIDE as u32) as f32);
            let inside = |c: f32, u: f32| {
                // (Bins are powers of two a side: multiplying by the inverse divides exactly.)
                let (end, q) = ((c + 1.0) * (1.0 / side), (c + u.clamp(0.0, BELOW_ONE)) * (1.0 / side));
                // The float below `end` (> 0).
                q.min(f32::from_bits(end.to_bits() - 1))
            };
            if draw[l] {
                (s[0][l], s[1][l]) = (inside(bx, rest), inside(by, at[1][l]));
            }
        }
        (s, p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform;

    /// Masses clustered in a few bins and spread thinly over the rest, some bins empty.
    fn masses() -> Vec<f64> {
        let mut u = uniform(9);
        let mut m: Vec<f64> = (0..BINS).map(|b| if b % 7 == 0 { 0.0 } else { 0.01 * u() as f64 }).collect();
        for b in [30, 31, 133, 200] {
            m[b] = 1.0 + u() as f64;
        }
        let total: f64 = m.iter().sum();
        m.iter().map(|x| x / total).collect()
    }

    #[test]
    fn draws_follow_the_masses_and_find_their_density() {
        let m = masses();
        let mut grids = Grids::default();
        assert_eq!((grids.push(&vec![1.0 / BINS as f64; BINS]), grids.push(&m)), (0, 1));
        let mut u = uniform(4);
        let mut hist = vec![0u32; BINS];
        let draws = 2_000_000;
        for _ in 0..draws {
            let at = [[u(), u()], [u(), u()]];
            let (s, pdf) = grids.lookup_lanes::<2>(&[1, 1], &[true, false], &at);
            let bin = |x: f32, y: f32| ((x * SIDE as f32) as usize) * SIDE + (y * SIDE as f32) as usize;
            let b = bin(s[0][0], s[1][0]);
            hist[b] += 1;
            // The drawn point's density is its bin's; the found one keeps its point.
            let density = |b: usize| m[b] * BINS as f64;
            assert!(pdf[0] > 0.0 && (pdf[0] as f64 / density(b) - 1.0).abs() < 1e-5, "{b}");
            assert_eq!((s[0][1], s[1][1]), (at[0][1], at[1][1]));
            let found = density(bin(at[0][1], at[1][1]));
            assert!((pdf[1] as f64 - found).abs() <= 1e-5 * found);
        }
        for b in 0..BINS {
            let expected = m[b] * draws as f64;
            let got = hist[b] as f64;
            assert!(
                (got - expected).abs() <= 5.0 * expected.sqrt() + 1e-3 * expected + 1.0,
                "{b}: {got} {expected}"
            );
        }
        // The uniform grid draws uniformly, its density 1 everywhere.
        let (_, pdf) = grids.lookup_lanes::<1>(&[0], &[true], &[[0.37], [0.81]]);
        assert_eq!(pdf[0], 1.0);
    }
}
