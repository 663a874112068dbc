//! Voxel grids for heterogeneous media, from Mitsuba's `.vol` files ([`crate::format::vol`]),
//! looked up by trilinear interpolation.
//!
//! A grid fills the unit cube `[0, 1]^3` of its own space. Voxel values stand at the voxel
//! centres `(i + 1/2) / res`, and a point nearer an edge than half a voxel takes the edge's
//! values (Mitsuba's default `clamp` wrap mode), as Dr.Jit's textures interpolate.

use crate::format::vol::VolHeader;
use glam::{Vec3, Vec3A};

/// A grid of one or three channels of finite, non-negative values.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelGrid {
    res: [usize; 3],
    channels: usize,
    data: Vec<f32>,
    max: f32,
    majorants: MajorantGrid,
}

impl VoxelGrid {
    /// The grid of a `.vol` file's bytes; `path` names the file in errors. Refuses a truncated
    /// or overlong file, grids of other than 1 or 3 channels, and values that are not finite
    /// or are negative.
    pub fn parse_vol(bytes: &[u8], path: &std::path::Path) -> Result<Self, String> {
        let h = VolHeader::parse(bytes, path, "grid")?;
        if h.channels != 1 && h.channels != 3 {
            return Err(format!(
                "the grid {}: {} channels: a medium's grid has 1 or 3",
                path.display(),
                h.channels
            ));
        }
        let data = h.values(bytes, path, "grid")?;
        if let Some(i) = data.iter().position(|v| *v < 0.0) {
            return Err(format!(
                "the grid {}: {} at {}: the values must be >= 0",
                path.display(),
                data[i],
                h.place(i)
            ));
        }
        Ok(Self::new(h.size, h.channels, data))
    }

    /// A grid from its values (x fastest, then y, then z, channels interleaved), which must be
    /// finite and non-negative.
    pub fn new(res: [usize; 3], channels: usize, data: Vec<f32>) -> Self {
        assert_eq!(data.len(), res.iter().product::<usize>() * channels);
        debug_assert!(data.iter().all(|v| v.is_finite() && *v >= 0.0));
        let max = data.iter().fold(0.0f32, |m, &v| m.max(v));
        let mut g =
            Self { res, channels, data, max, majorants: MajorantGrid { res: [1; 3], max: vec![max] } };
        g.majorants = MajorantGrid::new(&g);
        g
    }

    /// Voxels along x, y and z.
    pub fn res(&self) -> [usize; 3] {
        self.res
    }

    /// Values per voxel (1 or 3).
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The largest value of any channel.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// Bounds of the first channel over coarse cells.
    pub fn majorants(&self) -> &MajorantGrid {
        &self.majorants
    }

    /// The eight voxels around `p` (grid space) and their trilinear weights: the voxel index
    /// of the lower corner along each axis, the upper, and the fraction towards the upper.
    #[inline]
    fn corners(&self, p: Vec3A) -> ([usize; 3], [usize; 3], Vec3A) {
        let res = Vec3A::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        // Points beyond a voxel of the cube read the edge: clamped first, so that an infinite
        // point gives finite weights.
        let x = p.clamp(Vec3A::splat(-1.0), Vec3A::splat(2.0)) * res - 0.5;
        let lo = x.floor();
        let f = x - lo;
        let (mut i0, mut i1) = ([0usize; 3], [0usize; 3]);
        for a in 0..3 {
            let top = self.res[a] as f32 - 1.0;
            // Clamped in f32 first: a point far outside stays a valid index.
            i0[a] = lo[a].clamp(0.0, top) as usize;
            i1[a] = (lo[a] + 1.0).clamp(0.0, top) as usize;
        }
        (i0, i1, f)
    }

    /// Channel `c` of the voxel `(x, y, z)`.
    #[inline]
    fn at(&self, x: usize, y: usize, z: usize, c: usize) -> f32 {
        let (rx, ry) = (self.res[0], self.res[1]);
        self.data[((z * ry + y) * rx + x) * self.channels + c]
    }

    /// Channel `c` interpolated at `p`.
    #[inline]
    fn trilinear(&self, p: Vec3A, c: usize) -> f32 {
        let (i0, i1, f) = self.corners(p);
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let row = |y, z| lerp(self.at(i0[0], y, z, c), self.at(i1[0], y, z, c), f.x);
        let plane = |z| lerp(row(i0[1], z), row(i1[1], z), f.y);
        lerp(plane(i0[2]), plane(i1[2]), f.z)
    }

    /// The value at `p` in grid space: the first channel (a density).
    #[inline]
    pub fn value(&self, p: Vec3A) -> f32 {
        self.trilinear(p, 0)
    }

    /// The colour at `p` in grid space: three channels, or one for all three.
    #[inline]
    pub fn color(&self, p: Vec3A) -> Vec3 {
        match self.channels {
            3 => Vec3::new(self.trilinear(p, 0), self.trilinear(p, 1), self.trilinear(p, 2)),
            _ => Vec3::splat(self.trilinear(p, 0)),
        }
    }
}

/// The largest value that lookups in each cell of a coarse grid over a [`VoxelGrid`] can give
/// (pbrt-v4's `MajorantGrid`, 4th ed. 11.4.3): delta and ratio tracking take their tentative
/// collisions at a cell's bound where they would take them at the whole grid's, so that sparse
/// smoke costs steps only where it is, and empty cells none.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    res: [usize; 3],
    max: Vec<f32>,
}

/// Voxels along an axis per majorant cell (at most [`MAX_MAJORANT_CELLS`] cells).
const VOXELS_PER_CELL: usize = 4;
/// The most majorant cells along an axis.
const MAX_MAJORANT_CELLS: usize = 64;

impl MajorantGrid {
    /// The bounds of `grid`'s first channel over cells of about [`VOXELS_PER_CELL`] voxels.
    pub fn new(grid: &VoxelGrid) -> Self {
        let res = grid.res.map(|n| n.div_ceil(VOXELS_PER_CELL).clamp(1, MAX_MAJORANT_CELLS));
        // The voxels a lookup in cell `c` of `cells` along an axis of `n` voxels reads: those
        // around x = p n - 1/2 for p in [c / cells, (c + 1) / cells], and one more on each
        // side: a point the walk puts in a cell may lie a rounding outside it.
        let span = |c: usize, cells: usize, n: usize| {
            let x = |p: f64| p * n as f64 - 0.5;
            let lo = (x(c as f64 / cells as f64).floor() - 1.0).max(0.0) as usize;
            let hi = (x((c + 1) as f64 / cells as f64).floor() + 2.0).clamp(0.0, (n - 1) as f64) as usize;
            lo.min(n - 1)..=hi
        };
        // A cell's bound is the largest value over the box of its spans, taken one axis at a
        // time (the same maxima, in three passes over ever smaller arrays): along x for every
        // row of voxels, then along y, then along z. About 2 reads a voxel where the box by
        // box loop made 5 (the spans overlap), in the order the values lie in memory.
        let n = grid.res;
        let spans = |a: usize| (0..res[a]).map(|c| span(c, res[a], n[a])).collect::<Vec<_>>();
        let (sx, sy, sz) = (spans(0), spans(1), spans(2));
        fn largest(r: &std::ops::RangeInclusive<usize>, v: impl Fn(usize) -> f32) -> f32 {
            r.clone().fold(0.0f32, |m, i| m.max(v(i)))
        }
        let mut rows = Vec::with_capacity(res[0] * n[1] * n[2]);
        for z in 0..n[2] {
            for y in 0..n[1] {
                rows.extend(sx.iter().map(|r| largest(r, |x| grid.at(x, y, z, 0))));
            }
        }
        let mut slabs = Vec::with_capacity(res[0] * res[1] * n[2]);
        for z in 0..n[2] {
            for r in &sy {
                slabs.extend((0..res[0]).map(|cx| largest(r, |y| rows[(z * n[1] + y) * res[0] + cx])));
            }
        }
        let mut max = Vec::with_capacity(res.iter().product());
        for r in &sz {
            for cy in 0..res[1] {
                max.extend((0..res[0]).map(|cx| largest(r, |z| slabs[(z * res[1] + cy) * res[0] + cx])));
            }
        }
        Self { res, max }
    }

    /// Calls `out(ta, tb, bound)` for the cells that `o + t d` (grid space) crosses for `t` in
    /// `[t0, t1]`, in order, where the bound is positive; the pieces meet end to end. The
    /// stretch must lie in the unit cube (up to rounding: the cells at its faces take what
    /// lies just outside). A 3D digital differential analyser (Amanatides and Woo, "A Fast
    /// Voxel Traversal Algorithm for Ray Tracing", Eurographics 1987).
    #[inline]
    pub fn walk(&self, o: Vec3A, d: Vec3A, t0: f32, t1: f32, mut out: impl FnMut(f32, f32, f32)) {
        let res = Vec3A::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        let start = (o + t0 * d) * res;
        let mut cell = [0i64; 3];
        let (mut next, mut delta, mut step) = ([f32::INFINITY; 3], [f32::INFINITY; 3], [0i64; 3]);
        for a in 0..3 {
            cell[a] = (start[a].floor() as i64).clamp(0, self.res[a] as i64 - 1);
            if d[a] != 0.0 {
                step[a] = if d[a] > 0.0 { 1 } else { -1 };
                let plane = (cell[a] + (d[a] > 0.0) as i64) as f32 / res[a];
                next[a] = (plane - o[a]) / d[a];
                delta[a] = 1.0 / (res[a] * d[a].abs());
            }
        }
        let mut t = t0;
        for _ in 0..self.res.iter().sum::<usize>() + 3 {
            let a = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            let end = next[a].min(t1);
            if end > t {
                let i = (cell[2] as usize * self.res[1] + cell[1] as usize) * self.res[0] + cell[0] as usize;
                if self.max[i] > 0.0 {
                    out(t, end, self.max[i]);
                }
                t = end;
            }
            if next[a] >= t1 {
                return;
            }
            cell[a] += step[a];
            if !(0..self.res[a] as i64).contains(&cell[a]) {
                return;
            }
            next[a] += delta[a];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::vol::tests::vol_bytes;
    use std::path::Path;

    #[test]
    fn trilinear_between_voxel_centres_and_clamped_outside() {
        // 2x1x1: values 1 and 3 at x = 1/4 and 3/4.
        let g = VoxelGrid::parse_vol(&vol_bytes([2, 1, 1], 1, &[1.0, 3.0]), Path::new("t.vol")).unwrap();
        let at = |x: f32| g.value(Vec3A::new(x, 0.5, 0.5));
        assert_eq!(at(0.25), 1.0);
        assert_eq!(at(0.75), 3.0);
        assert_eq!(at(0.5), 2.0);
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(-7.0), 1.0);
        assert_eq!(at(1e30), 3.0);
        assert_eq!(at(f32::INFINITY), 3.0);
        assert_eq!(g.max(), 3.0);
        // Along z with x fastest: a 1x1x2 grid holds 0 at z = 1/4 and 4 at z = 3/4.
        let g = VoxelGrid::parse_vol(&vol_bytes([1, 1, 2], 1, &[0.0, 4.0]), Path::new("t.vol")).unwrap();
        assert_eq!(g.value(Vec3A::new(0.5, 0.5, 0.375)), 1.0);
    }

    #[test]
    fn three_channels_interleave() {
        let data = [0.1, 0.2, 0.3, 0.5, 0.6, 0.7];
        let g = VoxelGrid::parse_vol(&vol_bytes([1, 2, 1], 3, &data), Path::new("t.vol")).unwrap();
        assert_eq!(g.color(Vec3A::new(0.5, 0.75, 0.5)), Vec3::new(0.5, 0.6, 0.7));
        assert_eq!(g.value(Vec3A::new(0.5, 0.75, 0.5)), 0.5);
    }

    #[test]
    fn negative_values_and_six_channels_are_refused() {
        let err = |b: &[u8]| VoxelGrid::parse_vol(b, Path::new("m.vol")).unwrap_err();
        assert!(
            err(&vol_bytes([1, 1, 2], 1, &[0.0, -1.0]))
                .contains("-1 at point (0, 0, 1): the values must be >= 0")
        );
        assert!(err(&vol_bytes([1, 1, 1], 6, &[0.0; 6])).contains("6 channels: a medium's grid has 1 or 3"));
    }

    /// Every lookup along random rays is within its cell's bound, and the walk covers the
    /// stretch end to end; cells of a grid that is zero over half its extent are skipped.
    #[test]
    fn majorant_cells_bound_every_lookup_along_a_ray() {
        let (nx, ny, nz) = (13usize, 9usize, 20usize);
        let data: Vec<f32> = (0..nx * ny * nz)
            .map(|i| {
                let (x, z) = (i % nx, i / (nx * ny));
                if z < nz / 2 { 0.0 } else { ((x * 7 + z * 3) % 11) as f32 }
            })
            .collect();
        let g = VoxelGrid::new([nx, ny, nz], 1, data);
        let m = MajorantGrid::new(&g);
        let mut rnd = crate::testing::uniform(3);
        for _ in 0..2000 {
            let o = Vec3A::new(rnd(), rnd(), rnd());
            let d = Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            // From o to where the ray leaves the unit cube.
            let exit = (0..3)
                .map(|a| {
                    if d[a] > 0.0 {
                        (1.0 - o[a]) / d[a]
                    } else if d[a] < 0.0 {
                        -o[a] / d[a]
                    } else {
                        f32::INFINITY
                    }
                })
                .fold(f32::INFINITY, f32::min);
            let (mut pieces, mut last) = (Vec::new(), 0.0f32);
            m.walk(o, d, 0.0, exit, |ta, tb, bound| {
                assert!(ta >= last && tb > ta, "pieces out of order: {ta}..{tb} after {last}");
                for k in 0..=8 {
                    let t = ta + (tb - ta) * k as f32 / 8.0;
                    let v = g.value(o + t * d);
                    assert!(v <= bound, "{v} above the cell's bound {bound} at t = {t}");
                }
                pieces.push((ta, tb));
                last = tb;
            });
            // Zero cells are left out; every positive lookup lies in a piece walked.
            for k in 0..64 {
                let t = exit * (k as f32 + 0.5) / 64.0;
                if g.value(o + t * d) > 0.0 {
                    assert!(
                        pieces.iter().any(|&(a, b)| a <= t && t <= b),
                        "a positive lookup at t = {t} outside {pieces:?}"
                    );
                }
            }
        }
        assert!(m.max.iter().filter(|&&v| v == 0.0).count() > m.max.len() / 4, "{:?}", m.max);
    }

    /// The axis-by-axis passes give each cell the largest value over the box of its spans,
    /// as the plain loop over each box would, on grids of 1 voxel, sizes that are no multiple
    /// of the cell's, and an axis of more than 64 cells' worth.
    #[test]
    fn majorant_cells_hold_the_largest_value_of_their_box() {
        let mut rnd = crate::testing::uniform(11);
        for res in [[1, 1, 1], [13, 9, 20], [300, 3, 5], [7, 260, 2]] {
            let data: Vec<f32> = (0..res.iter().product::<usize>()).map(|_| (rnd() * 8.0).floor()).collect();
            let g = VoxelGrid::new(res, 1, data);
            let m = MajorantGrid::new(&g);
            let cells = m.res;
            let within = |c: usize, a: usize, i: usize| {
                // The span of cell `c` along axis `a` (as `MajorantGrid::new` defines it).
                let x = |p: f64| p * res[a] as f64 - 0.5;
                let lo = (x(c as f64 / cells[a] as f64).floor() - 1.0).max(0.0) as usize;
                let hi = (x((c + 1) as f64 / cells[a] as f64).floor() + 2.0).clamp(0.0, (res[a] - 1) as f64);
                lo.min(res[a] - 1) <= i && i <= hi as usize
            };
            for cz in 0..cells[2] {
                for cy in 0..cells[1] {
                    for cx in 0..cells[0] {
                        let mut want = 0.0f32;
                        for z in (0..res[2]).filter(|&z| within(cz, 2, z)) {
                            for y in (0..res[1]).filter(|&y| within(cy, 1, y)) {
                                for x in (0..res[0]).filter(|&x| within(cx, 0, x)) {
                                    want = want.max(g.at(x, y, z, 0));
                                }
                            }
                        }
                        let got = m.max[(cz * cells[1] + cy) * cells[0] + cx];
                        assert_eq!(got, want, "cell ({cx}, {cy}, {cz}) of {res:?}");
                    }
                }
            }
        }
    }

    /// The fuzzer's find: in a 6x4x5 grid with 2.5e27 in voxel (0, 3, 1), a ray whose
    /// crossing of the cell face z = 1/2 rounds to z = 0.49999997 reads that voxel's 1e-9
    /// share in the cell above, whose bound (without the margin of a voxel) was 24.
    #[test]
    fn a_lookup_a_rounding_outside_its_cell_stays_within_the_bound() {
        let mut data = vec![0.0f32; 6 * 4 * 5];
        for (i, v) in [
            (3, 12.0),
            (6, 24.0),
            (9, 8.0),
            (12, 20.0),
            (42, 2.4758801e27),
            (76, 2.0),
            (111, 24.0),
            (114, 8.0),
            (117, 20.0),
        ] {
            data[i] = v;
        }
        let g = VoxelGrid::new([6, 4, 5], 1, data);
        let o = Vec3A::new(0.30188566, 0.41964608, 0.032498382);
        let d = Vec3A::new(-0.02687031, 0.1517402, 0.23298919);
        let mut walked = 0;
        g.majorants().walk(o, d, 0.0, 3.82, |ta, tb, bound| {
            for t in [ta, tb, 0.5 * (ta + tb)] {
                let v = g.value(o + t * d);
                assert!(v <= bound, "{v} above the cell's bound {bound} at t = {t}");
            }
            walked += 1;
        });
        assert!(walked >= 2, "the ray crosses the face z = 1/2");
    }
}
