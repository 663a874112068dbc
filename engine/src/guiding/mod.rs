//! Path guiding: a distribution of the light arriving at each place of the scene, learned from
//! the paths of training passes, from which diffuse vertices draw part of their directions
//! (Müller, Gross and Novák 2017, "Practical Path Guiding for Efficient Light-Transport
//! Simulation", EGSR: the "SD-tree").
//!
//! The spatial part is a binary tree over the scene's box, each node split at its middle along
//! x, y and z in turn, refined where the training paths recorded many vertices; each leaf holds
//! a [`DTree`] of the energy that arrived there by direction. Unlike Müller et al.'s, the tree
//! is built at once from one pass's records (kept in memory), in their order: the guide is a
//! function of the records, whatever thread recorded them.

mod dtree;

use dtree::Node as DNode;
pub use dtree::{DTree, MAX_LEVELS, Refine, SQUARE_TO_SPHERE, from_square, to_square};
use glam::{Vec2, Vec3A};
use rayon::prelude::*;

/// Whether a render learns and uses a guide (`render: (guiding: On)`, `--guiding on`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
pub enum Guiding {
    /// Directions from the BSDF alone (default).
    #[default]
    Off,
    /// Training passes learn a guide before the render, and Lambertian vertices draw half
    /// their directions from it.
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
/// of the radiance estimate divided by the direction's density).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Record {
    /// The vertex.
    pub p: [f32; 3],
    /// The direction, on the square.
    pub square: Vec2,
    /// Radiance (luminance) over density.
    pub energy: f32,
}

/// A node of the spatial tree: split along `axis` (0-2) with its two children at `child` and
/// `child + 1`, or a leaf (`axis` 3) whose directional tree is `child`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    axis: u8,
    child: u32,
}

/// The learned distribution of incident light over the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Guide {
    /// The box the spatial tree divides.
    lo: Vec3A,
    /// Its inverse extent per axis.
    inv_size: Vec3A,
    nodes: Vec<Node>,
    /// Each cell's directional tree: its root in `directions` ([`Guide::EMPTY`]: nothing was
    /// learned there).
    roots: Vec<u32>,
    /// The nodes of every cell's directional tree, in one set of arrays.
    directions: dtree::Flat,
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
        let mut guide = Guide {
            lo,
            inv_size: size.recip(),
            nodes: vec![],
            roots: vec![],
            directions: Default::default(),
        };
        // Leaves in the order they are made, with their records; built in parallel after.
        let mut leaves: Vec<Vec<(Vec2, f32)>> = Vec::new();
        // (node, its records' unit coordinates and indices, depth)
        let unit: Vec<(Vec3A, u32)> =
            records.iter().enumerate().map(|(k, r)| (guide.unit(Vec3A::from(r.p)), k as u32)).collect();
        guide.nodes.push(Node { axis: 3, child: 0 });
        let mut stack = vec![(0usize, unit, 0u32)];
        while let Some((n, pts, depth)) = stack.pop() {
            if pts.len() <= spatial.max_records || depth >= spatial.max_depth {
                guide.nodes[n] = Node { axis: 3, child: leaves.len() as u32 };
                let energy = |&(_, k): &(Vec3A, u32)| {
                    let r = &records[k as usize];
                    (r.square, if r.energy.is_finite() { r.energy.max(0.0) } else { 0.0 })
                };
                leaves.push(pts.iter().map(energy).collect());
                continue;
            }
            let axis = (depth % 3) as usize;
            let (mut low, mut high) = (Vec::new(), Vec::new());
            for (mut u, k) in pts {
                let hi_side = u[axis] >= 0.5;
                u[axis] = 2.0 * u[axis] - hi_side as u32 as f32;
                if hi_side { high.push((u, k)) } else { low.push((u, k)) }
            }
            let c = guide.nodes.len();
            guide.nodes[n] = Node { axis: axis as u8, child: c as u32 };
            guide.nodes.push(Node { axis: 3, child: 0 });
            guide.nodes.push(Node { axis: 3, child: 0 });
            stack.push((c + 1, high, depth + 1));
            stack.push((c, low, depth + 1));
        }
        let trees: Vec<DTree> = leaves.par_iter().map(|pts| DTree::build(pts, directional)).collect();
        let mut directions = Vec::new();
        for t in &trees {
            let first = directions.len() as u32;
            guide.roots.push(if t.is_empty() { Self::EMPTY } else { first });
            directions.extend(t.nodes_from(first));
        }
        // Padded to powers of two, which the walks' index masks rely on.
        directions.resize(directions.len().max(1).next_power_of_two(), DNode::default());
        guide.directions = dtree::Flat::of(&directions);
        let len = guide.nodes.len().next_power_of_two();
        guide.nodes.resize(len, Node { axis: 3, child: 0 });
        guide
    }

    /// A cell where nothing was learned ([`Guide::cells`]).
    pub const EMPTY: u32 = u32::MAX;

    /// `p`'s coordinates in the box, in [0, 1] on each axis.
    #[inline]
    fn unit(&self, p: Vec3A) -> Vec3A {
        ((p - self.lo) * self.inv_size).clamp(Vec3A::ZERO, Vec3A::ONE)
    }

    /// The directional trees of the cells holding the points `p` (per lane: `p[axis]`), as
    /// roots for [`Self::pdf_lanes`] and [`Self::sample_lanes`]; [`Guide::EMPTY`] where
    /// nothing was learned. The lanes walk down together (their loads overlap).
    #[inline(always)]
    pub fn cells<const N: usize>(&self, p: &[[f32; N]; 3]) -> [u32; N] {
        let mut u = [[0.0f32; N]; 3];
        for l in 0..N {
            let q = self.unit(Vec3A::new(p[0][l], p[1][l], p[2][l]));
            (u[0][l], u[1][l], u[2][l]) = (q.x, q.y, q.z);
        }
        let mut n = [0u32; N];
        // Masked indices into the power-of-two array (no bounds checks in the lanes' loop).
        let nodes = &self.nodes[..];
        assert!(nodes.len().is_power_of_two(), "a power-of-two array of nodes");
        let mask = nodes.len() - 1;
        for _ in 0..64 {
            let mut any = false;
            for l in 0..N {
                let node = nodes[n[l] as usize & mask];
                let inner = node.axis != 3;
                let v = match node.axis {
                    0 => u[0][l],
                    1 => u[1][l],
                    _ => u[2][l],
                };
                let hi_side = v >= 0.5;
                let w = if inner { 2.0 * v - hi_side as u32 as f32 } else { v };
                u[0][l] = if node.axis == 0 { w } else { u[0][l] };
                u[1][l] = if node.axis == 1 { w } else { u[1][l] };
                u[2][l] = if node.axis == 2 { w } else { u[2][l] };
                n[l] = if inner { node.child + hi_side as u32 } else { n[l] };
                any |= inner;
            }
            if !any {
                break;
            }
        }
        n.map(|n| self.roots[self.nodes[n as usize].child as usize])
    }

    /// The densities in solid angle of the unit directions `d` (per lane: `d[axis]`) in the
    /// cells `root` ([`Self::cells`]); 0 in an empty cell.
    #[inline(always)]
    pub fn pdf_lanes<const N: usize>(&self, root: &[u32; N], d: &[[f32; N]; 3]) -> [f32; N] {
        let mut s = [[0.0f32; N]; 2];
        let mut r = [0u32; N];
        for l in 0..N {
            let q = to_square(Vec3A::new(d[0][l], d[1][l], d[2][l]));
            (s[0][l], s[1][l]) = (q.x, q.y);
            r[l] = if root[l] == Self::EMPTY { 0 } else { root[l] };
        }
        let pdf = dtree::pdf_square_lanes(&self.directions, &r, &s);
        std::array::from_fn(|l| if root[l] == Self::EMPTY { 0.0 } else { pdf[l] * SQUARE_TO_SPHERE })
    }

    /// Unit directions drawn with the numbers `u` (in [0, 1)) in the cells `root`, and their
    /// densities in solid angle (meaningless in an empty cell).
    #[inline(always)]
    pub fn sample_lanes<const N: usize>(
        &self,
        root: &[u32; N],
        u: &[[f32; N]; 2],
    ) -> ([[f32; N]; 3], [f32; N]) {
        let r = root.map(|r| if r == Self::EMPTY { 0 } else { r });
        let (s, pdf) = dtree::sample_square_lanes(&self.directions, &r, u);
        let mut d = [[0.0f32; N]; 3];
        for l in 0..N {
            let v = from_square(Vec2::new(s[0][l], s[1][l]));
            (d[0][l], d[1][l], d[2][l]) = (v.x, v.y, v.z);
        }
        (d, pdf.map(|p| p * SQUARE_TO_SPHERE))
    }

    /// The directional tree of the cell holding `p`, as its root ([`Guide::EMPTY`]: none).
    #[inline]
    pub fn cell(&self, p: Vec3A) -> u32 {
        self.cells::<1>(&[[p.x], [p.y], [p.z]])[0]
    }

    /// The density in solid angle of the unit direction `d` in the cell `root`.
    #[inline]
    pub fn pdf(&self, root: u32, d: Vec3A) -> f32 {
        self.pdf_lanes::<1>(&[root], &[[d.x], [d.y], [d.z]])[0]
    }

    /// Cells of the spatial tree, and nodes of all its directional trees (for reports).
    pub fn size(&self) -> (usize, usize) {
        (self.roots.len(), self.directions.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform;

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
        assert!(g.pdf(left, Vec3A::Z) > 10.0 && g.pdf(left, -Vec3A::Z) == 0.0);
        assert!(g.pdf(right, -Vec3A::Z) > 10.0 && g.pdf(right, Vec3A::Z) == 0.0);
        // Outside the box: the nearest cell.
        assert_eq!(g.cell(Vec3A::new(-5.0, 0.5, 0.5)), left);
        // Lanes walk as one lane does.
        let p = [[0.1, 0.9, 0.3], [0.5, 0.2, 0.8], [0.5, 0.7, 0.1]];
        let cells = g.cells(&p);
        let d = [[0.0, 0.6, 0.0], [0.0, 0.0, 0.6], [1.0, -0.8, -0.8]];
        let pdf = g.pdf_lanes(&cells, &d);
        let (s, spdf) = g.sample_lanes(&cells, &[[0.3, 0.7, 0.9], [0.1, 0.5, 0.99]]);
        for l in 0..3 {
            let at = Vec3A::new(p[0][l], p[1][l], p[2][l]);
            assert_eq!(cells[l], g.cell(at));
            assert_eq!(pdf[l], g.pdf(cells[l], Vec3A::new(d[0][l], d[1][l], d[2][l])));
            let (s1, p1) = g.sample_lanes::<1>(&[cells[l]], &[[[0.3, 0.7, 0.9][l]], [[0.1, 0.5, 0.99][l]]]);
            assert_eq!((s1[0][0], s1[1][0], s1[2][0], p1[0]), (s[0][l], s[1][l], s[2][l], spdf[l]));
        }
        // The same records give the same guide.
        assert_eq!(g, Guide::build(&records, Vec3A::ZERO, Vec3A::ONE, spatial, Refine::DEFAULT));
        // Nothing learned: no tree.
        let none = Guide::build(&[], Vec3A::ZERO, Vec3A::ONE, spatial, Refine::DEFAULT);
        assert_eq!(none.cell(Vec3A::splat(0.5)), Guide::EMPTY);
    }
}
