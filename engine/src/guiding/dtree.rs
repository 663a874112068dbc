//! The directional part of the guide: a quadtree over the unit square, which the cylindrical
//! (Lambert equal-area) map takes onto the sphere of directions, each node holding the energy
//! of its four quadrants (Müller, Gross and Novák 2017, "Practical Path Guiding for Efficient
//! Light-Transport Simulation", EGSR: the "D-tree").

use glam::{Vec2, Vec3A};

/// A node: the share of its energy in its lower half along x, the shares of the lower halves
/// along y in each half along x, and its children (0: the quadrant is a leaf). Quadrant `q`
/// covers `x` in its lower (`q & 1 == 0`) or upper half and `y` in its lower (`q & 2 == 0`) or
/// upper half; its density factor (its share of the energy over its quarter of the area) is 4
/// times the product of its shares along x and y.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    low_x: f32,
    low_y: [f32; 2],
    child: [u32; 4],
}

impl Node {
    /// The node of the quadrants' energies `s` (their sum > 0).
    fn of(s: [f32; 4], child: [u32; 4]) -> Node {
        let total = s[0] + s[1] + s[2] + s[3];
        let share = |a: f32, b: f32| if a + b > 0.0 { a / (a + b) } else { 0.5 };
        Node { low_x: (s[0] + s[2]) / total, low_y: [share(s[0], s[2]), share(s[1], s[3])], child }
    }
}

/// A piecewise-constant density over directions. Built by [`DTree::build`] from weighted
/// points of the square; empty (no node) where no energy arrived.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DTree {
    nodes: Vec<Node>,
}

/// How a tree refines: a quadrant holding more than `fraction` of the energy, reached by at
/// least `min_points` points, splits, down to `max_depth` levels.
#[derive(Clone, Copy, Debug)]
pub struct Refine {
    /// The share of the tree's energy above which a quadrant splits (Müller et al.: 0.01).
    pub fraction: f32,
    /// The fewest points a quadrant must hold to split (noise in a few points is not a lobe).
    pub min_points: usize,
    /// The deepest level (a leaf at depth `d` spans `4^-d` of the sphere).
    pub max_depth: u32,
}

impl Refine {
    /// The refinement the guide uses.
    pub const DEFAULT: Refine = Refine { fraction: 0.01, min_points: 16, max_depth: 14 };
}

/// The point of the unit square of the unit direction `d`: `x = (z + 1) / 2`, `y` the azimuth
/// in turns.
#[inline]
pub fn to_square(d: Vec3A) -> Vec2 {
    let x = ((d.z + 1.0) * 0.5).clamp(0.0, 1.0);
    let phi = crate::math::atan2(d.y, d.x) * (0.5 * std::f32::consts::FRAC_1_PI);
    let y = if phi < 0.0 { phi + 1.0 } else { phi };
    Vec2::new(x, y.clamp(0.0, 1.0))
}

/// The unit direction of the point `s` of the unit square ([`to_square`]'s inverse).
#[inline]
pub fn from_square(s: Vec2) -> Vec3A {
    let z = 2.0 * s.x - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (c, sn) = crate::math::cos_sin_turn(s.y);
    Vec3A::new(r * c, r * sn, z)
}

/// The density in solid angle of a density `p` over the square (the map preserves area, the
/// square's 1 to the sphere's 4 pi).
pub const SQUARE_TO_SPHERE: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

impl DTree {
    /// The tree of the points `points` (a point of the square and its energy, >= 0 and
    /// finite), refined as `refine` says; the sums follow the points' order.
    pub fn build(points: &[(Vec2, f32)], refine: Refine) -> DTree {
        let total: f32 = points.iter().map(|p| p.1).sum();
        if !(total > 0.0 && total.is_finite()) {
            return DTree::default();
        }
        let mut tree = DTree { nodes: vec![Node::default()] };
        // (node, its points, its corner, its side, its depth)
        let mut stack = vec![(0usize, points.to_vec(), Vec2::ZERO, 1.0f32, 1u32)];
        while let Some((n, pts, corner, side, depth)) = stack.pop() {
            let half = side * 0.5;
            let mut quads: [Vec<(Vec2, f32)>; 4] = Default::default();
            for &(s, w) in &pts {
                let q = (s.x >= corner.x + half) as usize | ((s.y >= corner.y + half) as usize) << 1;
                quads[q].push((s, w));
            }
            let (mut sum, mut child) = ([0.0; 4], [0; 4]);
            for (q, qp) in quads.into_iter().enumerate() {
                sum[q] = qp.iter().map(|p| p.1).sum();
                if sum[q] > refine.fraction * total
                    && qp.len() >= refine.min_points
                    && depth < refine.max_depth.min(MAX_LEVELS)
                {
                    child[q] = tree.nodes.len() as u32;
                    tree.nodes.push(Node::default());
                    let at = corner + Vec2::new((q & 1) as f32, (q >> 1) as f32) * half;
                    stack.push((child[q] as usize, qp, at, half, depth + 1));
                }
            }
            // A node holds energy (its parent split it for its share of the total).
            tree.nodes[n] = Node::of(sum, child);
        }
        tree
    }

    /// Whether the tree holds any energy (an empty one can be neither sampled nor evaluated).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Nodes in the tree (what its tests check of its refinement).
    #[cfg(test)]
    fn len(&self) -> usize {
        self.nodes.len()
    }

    /// The tree's density integrated over the bins of a `side` x `side` grid on the square
    /// (`side` a power of two), bin `(i, j)` (x in `[i, i + 1) / side`, y in `[j, j + 1) / side`)
    /// at `i * side + j`: the shares of the energy, which sum to 1 (empty: all 0).
    pub fn masses(&self, side: usize) -> Vec<f64> {
        assert!(side.is_power_of_two(), "a power-of-two grid");
        let mut m = vec![0.0f64; side * side];
        if self.is_empty() {
            return m;
        }
        // (node, its corner and side in bins, its mass)
        let mut stack = vec![(0usize, (0.0f64, 0.0f64), side as f64, 1.0f64)];
        while let Some((n, (x, y), size, mass)) = stack.pop() {
            let node = &self.nodes[n];
            let half = size * 0.5;
            for q in 0..4 {
                let (hx, hy) = (q & 1 == 1, q & 2 == 2);
                let sx = if hx { 1.0 - node.low_x as f64 } else { node.low_x as f64 };
                let sy = node.low_y[hx as usize] as f64;
                let sy = if hy { 1.0 - sy } else { sy };
                let (qx, qy) = (x + if hx { half } else { 0.0 }, y + if hy { half } else { 0.0 });
                let mq = mass * sx * sy;
                if node.child[q] != 0 && half > 1.0 {
                    stack.push((node.child[q] as usize, (qx, qy), half, mq));
                } else if half >= 1.0 {
                    // A leaf (or a node as large as a bin) spreads evenly over its bins.
                    let k = half as usize;
                    let (i0, j0) = (qx as usize, qy as usize);
                    for i in i0..i0 + k {
                        for j in j0..j0 + k {
                            m[i * side + j] += mq / (k * k) as f64;
                        }
                    }
                } else {
                    // Within one bin.
                    m[qx as usize * side + qy as usize] += mq;
                }
            }
        }
        m
    }
}

/// The deepest a tree refines ([`Refine::max_depth`] is at most this: its corners stay exact in `f32`).
pub const MAX_LEVELS: u32 = 20;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform;

    /// Points clustered about `(0.7, 0.2)` and spread over the square, energies uneven.
    fn points(n: usize) -> Vec<(Vec2, f32)> {
        let mut u = uniform(7);
        (0..n)
            .map(|k| {
                if k % 3 == 0 {
                    (Vec2::new(u(), u()), 0.1 + u())
                } else {
                    (Vec2::new(0.7 + 0.01 * u(), 0.2 + 0.02 * u()), 2.0 * u())
                }
            })
            .collect()
    }

    #[test]
    fn square_map_round_trips() {
        let mut u = uniform(3);
        for _ in 0..1000 {
            let s = Vec2::new(u(), u());
            let d = from_square(s);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let t = to_square(d);
            assert!((t - s).abs().max_element() < 2e-4 || (s.y - t.y).abs() > 0.999, "{s} {t}");
        }
    }

    #[test]
    fn masses_sum_to_one_and_follow_the_energy() {
        let pts = points(20_000);
        let tree = DTree::build(&pts, Refine::DEFAULT);
        assert!(tree.len() > 10, "the cluster refines: {} nodes", tree.len());
        for side in [1, 4, 32, 256] {
            let m = tree.masses(side);
            assert!((m.iter().sum::<f64>() - 1.0).abs() < 1e-9, "{side}");
        }
        // At 32 a side, each bin holds about the energy of the points in it (the tree's leaves
        // are finer than the bins where the points crowd, coarser where they are few).
        let m = tree.masses(32);
        let total: f64 = pts.iter().map(|p| p.1 as f64).sum();
        let mut in_bins = vec![0.0f64; 32 * 32];
        for (s, w) in &pts {
            in_bins[(s.x * 32.0) as usize * 32 + (s.y * 32.0) as usize] += *w as f64 / total;
        }
        let cluster = (0.705 * 32.0) as usize * 32 + (0.21 * 32.0) as usize;
        assert!((m[cluster] / in_bins[cluster] - 1.0).abs() < 0.05, "{} {}", m[cluster], in_bins[cluster]);
        assert!(m[cluster] > 100.0 * m[(0.2 * 32.0) as usize * 32 + (0.7 * 32.0) as usize]);
        // A finer grid splits a bin's mass among its bins.
        let fine = tree.masses(64);
        let (i, j) = (cluster / 32, cluster % 32);
        let four: f64 =
            [(0, 0), (0, 1), (1, 0), (1, 1)].iter().map(|(a, b)| fine[(2 * i + a) * 64 + 2 * j + b]).sum();
        assert!((four - m[cluster]).abs() < 1e-12);
        assert!(DTree::build(&[], Refine::DEFAULT).is_empty());
        assert!(DTree::build(&[(Vec2::splat(0.3), 0.0)], Refine::DEFAULT).is_empty());
        assert!(DTree::default().masses(8).iter().all(|&x| x == 0.0));
    }
}
