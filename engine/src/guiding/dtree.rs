//! The directional part of the guide: a quadtree over the unit square, which the cylindrical
//! (Lambert equal-area) map takes onto the sphere of directions, each node holding the energy
//! of its four quadrants (Müller, Gross and Novák 2017, "Practical Path Guiding for Efficient
//! Light-Transport Simulation", EGSR: the "D-tree").

use glam::{Vec2, Vec3A};

/// A node: its quadrants' shares of its energy as density factors (4 times the share: a
/// quadrant covers a quarter of the node), the shares of its lower half along x and of the
/// lower halves along y in each half along x (for sampling), and its children (0: the quadrant
/// is a leaf). Quadrant `q` covers `x` in its lower (`q & 1 == 0`) or upper half and `y` in its
/// lower (`q & 2 == 0`) or upper half.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    factor: [f32; 4],
    low_x: f32,
    low_y: [f32; 2],
    child: [u32; 4],
}

impl Node {
    /// The node of the quadrants' energies `s` (their sum > 0).
    fn of(s: [f32; 4], child: [u32; 4]) -> Node {
        let total = s[0] + s[1] + s[2] + s[3];
        let share = |a: f32, b: f32| if a + b > 0.0 { a / (a + b) } else { 0.5 };
        Node {
            factor: s.map(|x| 4.0 * x / total),
            low_x: (s[0] + s[2]) / total,
            low_y: [share(s[0], s[2]), share(s[1], s[3])],
            child,
        }
    }
}

/// A piecewise-constant density over directions. Built by [`DTree::build`] from weighted
/// points of the square; empty (no node) where no energy arrived.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DTree {
    nodes: Vec<Node>,
}

/// The density factors and children of an array of nodes, four a node (quadrant `q` of node
/// `n` at `4 n + q`), as [`pdf_square_lanes`] reads them: plain arrays, so that its loop over
/// lanes gathers from them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Flat {
    factor: Vec<f32>,
    child: Vec<u32>,
    /// Per node, the share of its lower half along x; two a node, the shares of the lower
    /// halves along y in each half along x.
    low_x: Vec<f32>,
    low_y: Vec<f32>,
    /// The inverses of those shares and of their complements, which stretch a number that
    /// chose a half back to [0, 1) (a multiply rather than a division at each level): two a
    /// node along x (lower, upper half), four along y (lower and upper in the lower half
    /// along x, then in the upper).
    stretch_x: Vec<f32>,
    stretch_y: Vec<f32>,
}

impl Flat {
    /// Nodes held (a power of two).
    pub fn len(&self) -> usize {
        self.low_x.len()
    }

    /// The factors and children of `nodes` (a power of two of them).
    pub fn of(nodes: &[Node]) -> Flat {
        Flat {
            factor: nodes.iter().flat_map(|n| n.factor).collect(),
            child: nodes.iter().flat_map(|n| n.child).collect(),
            low_x: nodes.iter().map(|n| n.low_x).collect(),
            low_y: nodes.iter().flat_map(|n| n.low_y).collect(),
            stretch_x: nodes.iter().flat_map(|n| [1.0 / n.low_x, 1.0 / (1.0 - n.low_x)]).collect(),
            stretch_y: (nodes.iter())
                .flat_map(|n| n.low_y.map(|y| [1.0 / y, 1.0 / (1.0 - y)]))
                .flatten()
                .collect(),
        }
    }
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

    /// Nodes in the tree.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// The tree's nodes, their children renumbered from `first` (to lie in one array with
    /// other trees' from there).
    pub(super) fn nodes_from(&self, first: u32) -> impl Iterator<Item = Node> + '_ {
        self.nodes
            .iter()
            .map(move |n| Node { child: n.child.map(|c| if c == 0 { 0 } else { c + first }), ..*n })
    }
}

/// The deepest a walk down a tree goes ([`Refine::max_depth`] is at most this).
pub const MAX_LEVELS: u32 = 20;

/// The densities over the square at the points `s` (per lane: `s[0]` the x, `s[1]` the y) of
/// the trees whose roots in `nodes` are `root`. The lanes walk down together, each on its own
/// tree, so that their loads overlap; each lane's numbers are those of a walk on its own.
#[inline(always)]
pub fn pdf_square_lanes<const N: usize>(nodes: &Flat, root: &[u32; N], s: &[[f32; N]; 2]) -> [f32; N] {
    let (mut n, mut x, mut y) = (*root, s[0], s[1]);
    let (mut pdf, mut live) = ([1.0f32; N], [true; N]);
    // Indices within the (power-of-two) arrays by construction: the mask spares the bounds
    // checks, so that the loop over lanes may gather.
    let (factor, child) = (&nodes.factor[..], &nodes.child[..nodes.factor.len()]);
    assert!(factor.len().is_power_of_two(), "a power-of-two array of nodes");
    let mask = factor.len() - 1;
    for _ in 0..MAX_LEVELS {
        let mut any = false;
        for l in 0..N {
            let (hx, hy) = (x[l] >= 0.5, y[l] >= 0.5);
            let k = (n[l] as usize * 4 + (hx as usize | (hy as usize) << 1)) & mask;
            let (f, c) = (factor[k], child[k]);
            pdf[l] = if live[l] { pdf[l] * f } else { pdf[l] };
            let go = live[l] && c != 0;
            x[l] = if go { 2.0 * x[l] - hx as u32 as f32 } else { x[l] };
            y[l] = if go { 2.0 * y[l] - hy as u32 as f32 } else { y[l] };
            n[l] = if go { c } else { n[l] };
            live[l] = go;
            any |= go;
        }
        if !any {
            break;
        }
    }
    pdf
}

/// Points of the square drawn with the numbers `u` (in [0, 1)) from the trees whose roots in
/// `nodes` are `root`, and their densities over the square; the lanes walk down together as in
/// [`pdf_square_lanes`].
#[inline(always)]
pub fn sample_square_lanes<const N: usize>(
    nodes: &Flat,
    root: &[u32; N],
    u: &[[f32; N]; 2],
) -> ([[f32; N]; 2], [f32; N]) {
    const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;
    let (mut n, mut ux, mut uy) = (*root, u[0], u[1]);
    let (mut pdf, mut live) = ([1.0f32; N], [true; N]);
    let (mut cx, mut cy, mut side) = ([0.0f32; N], [0.0f32; N], [1.0f32; N]);
    // As in `pdf_square_lanes`: masked indices into power-of-two arrays.
    let (factor, child) = (&nodes.factor[..], &nodes.child[..nodes.factor.len()]);
    let (low_xs, low_ys) = (&nodes.low_x[..factor.len() / 4], &nodes.low_y[..factor.len() / 2]);
    let (stretch_x, stretch_y) = (&nodes.stretch_x[..factor.len() / 2], &nodes.stretch_y[..factor.len()]);
    assert!(factor.len().is_power_of_two(), "a power-of-two array of nodes");
    let mask = factor.len() - 1;
    for _ in 0..MAX_LEVELS {
        let mut any = false;
        for l in 0..N {
            let m = n[l] as usize;
            // The half along x in proportion to its energy, then the half along y within it.
            let low_x = low_xs[m & (mask >> 2)];
            let hx = ux[l] >= low_x;
            let sx = stretch_x[(2 * m + hx as usize) & (mask >> 1)];
            let vx = ((ux[l] - if hx { low_x } else { 0.0 }) * sx).clamp(0.0, BELOW_ONE);
            let iy = 2 * m + hx as usize;
            let low_y = low_ys[iy & (mask >> 1)];
            let hy = uy[l] >= low_y;
            let sy = stretch_y[(2 * iy + hy as usize) & mask];
            let vy = ((uy[l] - if hy { low_y } else { 0.0 }) * sy).clamp(0.0, BELOW_ONE);
            let k = (4 * m + (hx as usize | (hy as usize) << 1)) & mask;
            let (f, c) = (factor[k], child[k]);
            let half = side[l] * 0.5;
            let on = live[l];
            ux[l] = if on { vx } else { ux[l] };
            uy[l] = if on { vy } else { uy[l] };
            pdf[l] = if on { pdf[l] * f } else { pdf[l] };
            cx[l] = if on && hx { cx[l] + half } else { cx[l] };
            cy[l] = if on && hy { cy[l] + half } else { cy[l] };
            side[l] = if on { half } else { side[l] };
            let go = on && c != 0;
            n[l] = if go { c } else { n[l] };
            live[l] = go;
            any |= go;
        }
        if !any {
            break;
        }
    }
    // Rounding must not carry a point over its cell's far edges.
    let mut s = [[0.0f32; N]; 2];
    for l in 0..N {
        let inside = |c: f32, u: f32| {
            let (end, p) = (c + side[l], c + u * side[l]);
            if p >= end { end.next_down() } else { p }
        };
        (s[0][l], s[1][l]) = (inside(cx[l], ux[l]), inside(cy[l], uy[l]));
    }
    (s, pdf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform;

    /// A tree's walks one point at a time, on its own padded arrays.
    struct Walks(Flat);

    impl Walks {
        fn of(t: &DTree) -> Walks {
            let mut nodes = t.nodes.clone();
            nodes.resize(nodes.len().next_power_of_two(), Node::default());
            Walks(Flat::of(&nodes))
        }

        fn pdf_square(&self, s: Vec2) -> f32 {
            pdf_square_lanes::<1>(&self.0, &[0], &[[s.x], [s.y]])[0]
        }

        fn pdf(&self, d: Vec3A) -> f32 {
            self.pdf_square(to_square(d)) * SQUARE_TO_SPHERE
        }

        fn sample_square(&self, u: Vec2) -> (Vec2, f32) {
            let (s, pdf) = sample_square_lanes::<1>(&self.0, &[0], &[[u.x], [u.y]]);
            (Vec2::new(s[0][0], s[1][0]), pdf[0])
        }
    }

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
    fn density_integrates_to_one_and_follows_energy() {
        let tree = DTree::build(&points(20_000), Refine::DEFAULT);
        assert!(tree.len() > 10, "the cluster refines: {} nodes", tree.len());
        let t = Walks::of(&tree);
        // Midpoint rule on a 512^2 grid, finer than the deepest leaves the cluster reaches.
        let n = 512;
        let mut total = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let s = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                total += t.pdf_square(s) as f64;
            }
        }
        assert!((total / (n * n) as f64 - 1.0).abs() < 1e-3, "{}", total / (n * n) as f64);
        assert!(t.pdf_square(Vec2::new(0.705, 0.21)) > 100.0 * t.pdf_square(Vec2::new(0.2, 0.7)));
        assert!(DTree::build(&[], Refine::DEFAULT).is_empty());
        assert!(DTree::build(&[(Vec2::splat(0.3), 0.0)], Refine::DEFAULT).is_empty());
    }

    #[test]
    fn samples_have_the_density_evaluated() {
        let t = Walks::of(&DTree::build(&points(20_000), Refine::DEFAULT));
        let mut u = uniform(11);
        // A histogram of samples against the density's integral over its cells.
        let n = 16;
        let mut hist = vec![0u32; n * n];
        let draws = 400_000;
        for _ in 0..draws {
            let (s, pdf) = t.sample_square(Vec2::new(u(), u()));
            assert!((pdf / t.pdf_square(s) - 1.0).abs() < 1e-4, "{pdf} {}", t.pdf_square(s));
            let d = from_square(s);
            assert!((t.pdf(d) / (pdf * SQUARE_TO_SPHERE) - 1.0).abs() < 1e-2 || pdf < 1.0);
            hist[(s.x * n as f32) as usize * n + (s.y * n as f32) as usize] += 1;
        }
        let m = 64;
        for ci in 0..n {
            for cj in 0..n {
                let mut mass = 0.0f64;
                for i in 0..m {
                    for j in 0..m {
                        let s = Vec2::new(
                            (ci as f32 + (i as f32 + 0.5) / m as f32) / n as f32,
                            (cj as f32 + (j as f32 + 0.5) / m as f32) / n as f32,
                        );
                        mass += t.pdf_square(s) as f64 / (m * m * n * n) as f64;
                    }
                }
                let expected = mass * draws as f64;
                let got = hist[ci * n + cj] as f64;
                assert!(
                    (got - expected).abs() <= 5.0 * expected.sqrt() + 0.01 * expected + 2.0,
                    "{ci},{cj}: {got} {expected}"
                );
            }
        }
    }
}
