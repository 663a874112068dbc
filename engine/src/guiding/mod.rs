//! Path guiding: a distribution of the light arriving at each place of the scene, learned from
//! the paths of training passes, from which diffuse vertices draw part of their directions
//! (Müller, Gross and Novák 2017, "Practical Path Guiding for Efficient Light-Transport
//! Simulation", EGSR: the "SD-tree").
//!
//! The spatial part is a binary tree over the scene's box, each node split at its middle along
//! x, y and z in turn, refined where the training paths recorded many vertices; each leaf holds
//! a `DTree` of the energy that arrived there by direction, which the render reads integrated
//! over a grid of bins (`grid`). Unlike Müller et al.'s, the tree is built at once from one
//! pass's records (kept in memory), in their order: the guide is a function of the records,
//! whatever thread recorded them.

mod dtree;
mod grid;

use dtree::{DTree, SQUARE_TO_SPHERE, from_square};
pub use dtree::{Refine, to_square};
use glam::{Vec2, Vec3A};
use rayon::prelude::*;

/// Whether a render learns and uses a guide (`render: (guiding: On)`, `--guiding on`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
pub enum Guiding {
    /// Directions from the BSDF alone (default).
    #[default]
    Off,
    /// The render's first samples train in stages, each learning the guide of the next, and
    /// Lambertian vertices draw half their directions from their stage's guide.
    On,
}

impl Guiding {
    /// The names, as the command line spells them.
    pub const NAMES: [(&'static str, Guiding); 2] = [("off", Guiding::Off), ("on", Guiding::On)];
}

impl std::str::FromStr for Guiding {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        crate::format::by_name(&Self::NAMES, s, "guiding")
    }
}

/// What a training path recorded at a vertex: where it was, the direction it left along (as a
/// point of the square, [`to_square`]) and the energy that came back along it (the luminance
/// of the radiance estimate times the cosine, divided by the direction's density).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Record {
    /// The vertex.
    pub p: [f32; 3],
    /// The direction, on the square.
    pub square: Vec2,
    /// Radiance (luminance) times the cosine, over density.
    pub energy: f32,
}

/// The learned distribution of incident light over the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Guide {
    /// The box the spatial tree divides.
    lo: Vec3A,
    /// Its inverse extent per axis.
    inv_size: Vec3A,
    /// The spatial tree's nodes, the root first. A node at depth `k` splits along the axis
    /// `k % 3`: an inner one holds the first of its two children (the lower half, the upper
    /// next to it), a leaf [`Self::LEAF`] and its cell's grid in `directions` ([`Guide::EMPTY`]:
    /// nothing was learned there). Padded to a power of two.
    nodes: Vec<u32>,
    /// Leaves of the spatial tree (cells).
    cells: usize,
    /// Every cell's directions, as a grid (the first one uniform, which empty cells' lanes
    /// read and ignore).
    directions: grid::Grids,
}

/// A [`Guide`]'s arrays as a file keeps them ([`Guide::to_parts`], [`Guide::from_parts`]).
#[derive(Clone, Debug, PartialEq)]
pub struct GuideParts {
    /// The box's lower corner.
    pub lo: [f32; 3],
    /// Its inverse extent per axis.
    pub inv_size: [f32; 3],
    /// Leaves of the spatial tree.
    pub cells: u64,
    /// The spatial tree's nodes.
    pub nodes: Vec<u32>,
    /// The cells' grids: per bin its density, then its alias word (16 x 16 bins a grid).
    pub grids: (Vec<f32>, Vec<u32>),
}

/// How the spatial tree refines: a cell with more than `max_records` records splits, down to
/// `max_depth` levels.
#[derive(Clone, Copy, Debug)]
pub struct SpatialRefine {
    /// The most records a leaf keeps (Müller et al. use 12000 sqrt(2^k) at iteration k).
    pub max_records: usize,
    /// The deepest level.
    pub max_depth: u32,
}

impl Guide {
    /// The guide learned from `records` inside the box `lo`..`hi` (points outside belong to
    /// the nearest cell).
    pub fn build(
        records: &[Record],
        lo: Vec3A,
        hi: Vec3A,
        spatial: SpatialRefine,
        directional: Refine,
    ) -> Guide {
        let size = (hi - lo).max(Vec3A::splat(1e-6));
        let mut guide =
            Guide { lo, inv_size: size.recip(), nodes: vec![0], cells: 0, directions: Default::default() };
        // The records' unit coordinates and indices, partitioned in place node by node: a
        // leaf's records are a range of them. Leaves are listed in the order they are made
        // (their nodes, their ranges); their directional trees are built in parallel after.
        let mut pts: Vec<(Vec3A, u32)> =
            records.iter().enumerate().map(|(k, r)| (guide.unit(Vec3A::from(r.p)), k as u32)).collect();
        let mut leaves: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
        // (node, its records, depth)
        let mut stack = vec![(0usize, 0..pts.len(), 0u32)];
        while let Some((n, range, depth)) = stack.pop() {
            if range.len() <= spatial.max_records || depth >= spatial.max_depth {
                leaves.push((n, range));
                continue;
            }
            let axis = (depth % 3) as usize;
            let part = &mut pts[range.clone()];
            let mut low = 0;
            for j in 0..part.len() {
                let hi_side = part[j].0[axis] >= 0.5;
                part[j].0[axis] = 2.0 * part[j].0[axis] - hi_side as u32 as f32;
                if !hi_side {
                    part.swap(low, j);
                    low += 1;
                }
            }
            let c = guide.nodes.len();
            guide.nodes[n] = c as u32;
            guide.nodes.extend([0, 0]);
            let mid = range.start + low;
            stack.push((c + 1, mid..range.end, depth + 1));
            stack.push((c, range.start..mid, depth + 1));
        }
        let energy = |&(_, k): &(Vec3A, u32)| {
            let r = &records[k as usize];
            (r.square, if r.energy.is_finite() { r.energy.max(0.0) } else { 0.0 })
        };
        let trees: Vec<DTree> = leaves
            .par_iter()
            .map(|(_, range)| {
                let points: Vec<(Vec2, f32)> = pts[range.clone()].iter().map(energy).collect();
                DTree::build(&points, directional)
            })
            .collect();
        let masses: Vec<Vec<f64>> = trees.par_iter().map(|t| t.masses(grid::SIDE)).collect();
        guide.directions.push(&[1.0 / grid::BINS as f64; grid::BINS]);
        for ((t, m), &(n, _)) in trees.iter().zip(&masses).zip(&leaves) {
            guide.nodes[n] = if t.is_empty() { Self::EMPTY } else { Self::LEAF | guide.directions.push(m) };
        }
        assert!(guide.directions.len() < Self::LEAF as usize, "grids fit below the leaf mark");
        guide.cells = trees.len();
        // Padded to a power of two, which the walk's index mask relies on.
        let len = guide.nodes.len().next_power_of_two();
        guide.nodes.resize(len, Self::EMPTY);
        guide
    }

    /// A cell where nothing was learned ([`Guide::cells`]).
    pub const EMPTY: u32 = u32::MAX;

    /// The mark of a leaf among the spatial tree's nodes.
    const LEAF: u32 = 1 << 31;

    /// `p`'s coordinates in the box, in [0, 1] on each axis.
    #[inline]
    fn unit(&self, p: Vec3A) -> Vec3A {
        ((p - self.lo) * self.inv_size).clamp(Vec3A::ZERO, Vec3A::ONE)
    }

    /// The cells holding the points `p` (per lane: `p[axis]`), as their grids for
    /// [`Self::lookup_lanes`]; [`Guide::EMPTY`] where nothing was learned. The lanes walk down
    /// together (their loads gather).
    #[inline(always)]
    pub fn cells<const N: usize>(&self, p: &[[f32; N]; 3]) -> [u32; N] {
        let mut u = [[0.0f32; N]; 3];
        for l in 0..N {
            let q = self.unit(Vec3A::new(p[0][l], p[1][l], p[2][l]));
            (u[0][l], u[1][l], u[2][l]) = (q.x, q.y, q.z);
        }
        let mut n = [0u32; N];
        // Masked indices into the power-of-two array (no bounds checks in the lanes' loop: it
        // gathers).
        let nodes = &self.nodes[..];
        assert!(nodes.len().is_power_of_two(), "a power-of-two array of nodes");
        let mask = nodes.len() - 1;
        for depth in 0..64 {
            // Every lane still walking is at this depth, so splits along the same axis.
            let u = &mut u[depth % 3];
            let mut any = false;
            for l in 0..N {
                let c = nodes[n[l] as usize & mask];
                let inner = c & Self::LEAF == 0;
                let hi_side = u[l] >= 0.5;
                u[l] = if inner { 2.0 * u[l] - hi_side as u32 as f32 } else { u[l] };
                n[l] = if inner { c + hi_side as u32 } else { n[l] };
                any |= inner;
            }
            if !any {
                break;
            }
        }
        n.map(|n| match nodes[n as usize & mask] {
            Self::EMPTY => Self::EMPTY,
            leaf => leaf & !Self::LEAF,
        })
    }

    /// Looks up the directions' grids of the cells `root` ([`Self::cells`]), lane by lane: a
    /// lane that `draw`s draws a unit direction with the numbers `u` (in [0, 1)), the
    /// others find the unit direction `d`. Returns the directions (drawn, or `d`) and the
    /// densities in solid angle there (0 in an empty cell, where nothing is drawn).
    #[inline(always)]
    pub fn lookup_lanes<const N: usize>(
        &self,
        root: &[u32; N],
        draw: &[bool; N],
        u: &[[f32; N]; 2],
        d: &[[f32; N]; 3],
    ) -> ([[f32; N]; 3], [f32; N]) {
        let mut at = [[0.0f32; N]; 2];
        let (mut r, mut draws) = ([0u32; N], [false; N]);
        for l in 0..N {
            let q = to_square(Vec3A::new(d[0][l], d[1][l], d[2][l]));
            let empty = root[l] == Self::EMPTY;
            draws[l] = draw[l] && !empty;
            (at[0][l], at[1][l]) = if draws[l] { (u[0][l], u[1][l]) } else { (q.x, q.y) };
            r[l] = if empty { 0 } else { root[l] };
        }
        let (s, pdf) = self.directions.lookup_lanes(&r, &draws, &at);
        let mut out = *d;
        for l in 0..N {
            let v = from_square(Vec2::new(s[0][l], s[1][l]));
            if draws[l] {
                (out[0][l], out[1][l], out[2][l]) = (v.x, v.y, v.z);
            }
        }
        (out, std::array::from_fn(|l| if root[l] == Self::EMPTY { 0.0 } else { pdf[l] * SQUARE_TO_SPHERE }))
    }

    /// The guide as plain arrays, for a file to keep ([`Guide::from_parts`]).
    pub fn to_parts(&self) -> GuideParts {
        GuideParts {
            lo: self.lo.to_array(),
            inv_size: self.inv_size.to_array(),
            cells: self.cells as u64,
            nodes: self.nodes.clone(),
            grids: self.directions.to_parts(),
        }
    }

    /// The guide of `parts` ([`Guide::to_parts`]), checked: every node within the tree and
    /// after its parent, every leaf's grid among the grids, densities finite and not negative.
    /// A guide read from a file (which its checksum does not make right) is refused with what
    /// is wrong rather than walked out of bounds.
    pub fn from_parts(p: GuideParts) -> Result<Guide, String> {
        let finite = |v: [f32; 3]| v.iter().all(|x| x.is_finite());
        if !finite(p.lo) || !finite(p.inv_size) || p.inv_size.iter().any(|&x| x <= 0.0) {
            return Err(format!(
                "a guide's box is not finite: from {:?}, inverse size {:?}",
                p.lo, p.inv_size
            ));
        }
        let n = p.nodes.len();
        if !n.is_power_of_two() {
            return Err(format!("a guide's {n} nodes are not a power of two"));
        }
        let directions = grid::Grids::from_parts(p.grids)?;
        let grids = directions.len() as u32;
        for (k, &c) in p.nodes.iter().enumerate() {
            let ok = match c {
                Self::EMPTY => true,
                c if c & Self::LEAF != 0 => c & !Self::LEAF < grids && c & !Self::LEAF > 0,
                c => (c as usize) > k && (c as usize) + 1 < n,
            };
            if !ok {
                return Err(format!(
                    "a guide's node {k} names {c:#x}, outside its {n} nodes and {grids} grids"
                ));
            }
        }
        if p.cells > n as u64 {
            return Err(format!("a guide counts {} cells in {n} nodes", p.cells));
        }
        Ok(Guide {
            lo: Vec3A::from_array(p.lo),
            inv_size: Vec3A::from_array(p.inv_size),
            nodes: p.nodes,
            cells: p.cells as usize,
            directions,
        })
    }

    /// Cells of the spatial tree, and those of them that learned directions (for reports).
    pub fn size(&self) -> (usize, usize) {
        (self.cells, self.directions.len() - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform;

    /// One-lane walks.
    impl Guide {
        fn cell(&self, p: Vec3A) -> u32 {
            self.cells::<1>(&[[p.x], [p.y], [p.z]])[0]
        }

        fn pdf(&self, root: u32, d: Vec3A) -> f32 {
            self.lookup_lanes::<1>(&[root], &[false], &[[0.0], [0.0]], &[[d.x], [d.y], [d.z]]).1[0]
        }
    }

    #[test]
    fn cells_split_where_records_crowd_and_keep_their_directions() {
        let mut u = uniform(5);
        // Records over the unit cube; those with x < 0.25 all arrive from one direction (+z),
        // the others from -z.
        let records: Vec<Record> = (0..40_000)
            .map(|_| {
                let p = [u(), u(), u()];
                let d = if p[0] < 0.25 { Vec3A::Z } else { -Vec3A::Z };
                let jitter = Vec3A::new(0.01 * u(), 0.01 * u(), 0.0);
                Record { p, square: to_square((d + jitter).normalize()), energy: 1.0 }
            })
            .collect();
        let spatial = SpatialRefine { max_records: 2000, max_depth: 30 };
        let g = Guide::build(&records, Vec3A::ZERO, Vec3A::ONE, spatial, Refine::DEFAULT);
        let (leaves, _) = g.size();
        assert!(leaves >= 20, "{leaves} leaves");
        let (left, right) = (g.cell(Vec3A::new(0.1, 0.5, 0.5)), g.cell(Vec3A::new(0.9, 0.5, 0.5)));
        assert!(g.pdf(left, Vec3A::Z) > 2.0 && g.pdf(left, -Vec3A::Z) == 0.0);
        assert!(g.pdf(right, -Vec3A::Z) > 2.0 && g.pdf(right, Vec3A::Z) == 0.0);
        // Outside the box: the nearest cell.
        assert_eq!(g.cell(Vec3A::new(-5.0, 0.5, 0.5)), left);
        // Lanes walk as one lane does.
        let p = [[0.1, 0.9, 0.3], [0.5, 0.2, 0.8], [0.5, 0.7, 0.1]];
        let cells = g.cells(&p);
        let d = [[0.0, 0.6, 0.0], [0.0, 0.0, 0.6], [1.0, -0.8, -0.8]];
        let u = [[0.3, 0.7, 0.9], [0.1, 0.5, 0.99]];
        // The first and last lanes find `d`, the middle one draws.
        let (out, pdf) = g.lookup_lanes(&cells, &[false, true, false], &u, &d);
        for l in 0..3 {
            let at = Vec3A::new(p[0][l], p[1][l], p[2][l]);
            assert_eq!(cells[l], g.cell(at));
            let one = g.lookup_lanes::<1>(
                &[cells[l]],
                &[l == 1],
                &[[u[0][l]], [u[1][l]]],
                &[[d[0][l]], [d[1][l]], [d[2][l]]],
            );
            assert_eq!(
                (one.0[0][0], one.0[1][0], one.0[2][0], one.1[0]),
                (out[0][l], out[1][l], out[2][l], pdf[l])
            );
            let at = Vec3A::new(out[0][l], out[1][l], out[2][l]);
            let found = g.pdf(cells[l], at);
            assert!(pdf[l] == found || (pdf[l] / found - 1.0).abs() < 1e-2, "{l}: {} {found}", pdf[l]);
        }
        assert_eq!((out[0][0], out[2][2]), (d[0][0], d[2][2]));
        // The same records give the same guide.
        assert_eq!(g, Guide::build(&records, Vec3A::ZERO, Vec3A::ONE, spatial, Refine::DEFAULT));
        // Its parts give it back; parts that would walk out of bounds or draw NaN are refused.
        assert_eq!(Guide::from_parts(g.to_parts()), Ok(g.clone()));
        let inner = g.nodes.iter().position(|&c| c & Guide::LEAF == 0).expect("an inner node");
        let mut bad = g.to_parts();
        bad.nodes[inner] = bad.nodes.len() as u32;
        assert!(Guide::from_parts(bad).unwrap_err().contains("outside"));
        let mut bad = g.to_parts();
        bad.nodes[inner] = 0;
        assert!(Guide::from_parts(bad).is_err(), "a node that points back up");
        let mut bad = g.to_parts();
        bad.grids.0[300] = f32::NAN;
        assert!(Guide::from_parts(bad).unwrap_err().contains("density NaN"));
        let mut bad = g.to_parts();
        bad.grids.1.pop();
        assert!(Guide::from_parts(bad).is_err(), "a grid cut short");
        // Nothing learned: no tree.
        let none = Guide::build(&[], Vec3A::ZERO, Vec3A::ONE, spatial, Refine::DEFAULT);
        assert_eq!(none.cell(Vec3A::splat(0.5)), Guide::EMPTY);
    }
}
