//! An 8-wide BVH with uncompressed child boxes, collapsed from an obvhs binary BVH (PLOC build,
//! reinsertion, SAH leaf collapse), and its traversals: one ray at a time, or a packet of
//! [`PACKET`] rays at a time (each node read once for the packet; every ray gets the hit it
//! gets alone).
//!
//! obvhs's CWBVH quantises child boxes and decodes them per node; here a node holds its eight
//! child boxes as plain `f32` lanes, so one node test is six subtractions, six multiplications
//! and a few min/max over 8 lanes (AVX2 with `target-cpu=x86-64-v3`). The traversal tests
//! nodes from `t = 0` (no absolute node epsilon), widens each box exit by `1 + 2 gamma(3)`
//! (Ize 2013: rounding cannot make a ray miss a box it touches), and visits hit children
//! nearest first. What a leaf holds is the caller's business: a leaf is a range
//! `(first, count)` that the caller assigned when building, and the caller tests it.
//!
//! Crowds of primitives that PLOC cannot order (copies of one primitive, primitives nested
//! about one centre) are built top-down instead, and no tree is deeper than [`MAX_DEPTH`]
//! levels, which the traversal stacks hold ([`build`]).

use glam::Vec3A;
use obvhs::{BvhBuildParams, aabb::Aabb};

/// Children per node.
pub const WIDTH: usize = 8;

/// An unused child slot.
pub(super) const EMPTY: u32 = u32::MAX;
/// Set in a child reference that names a leaf.
pub(super) const LEAF: u32 = 1 << 31;
/// Largest leaf range start.
const MAX_FIRST: u32 = (1 << 28) - 1;

/// One node: the boxes of up to eight children (empty slots have inverted boxes that no ray
/// enters) and what each child is.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node {
    /// Per child: lower x, upper x, lower y, upper y, lower z, upper z (a ray picks its near
    /// and far planes by index, computed once per ray).
    pub planes: [[f32; WIDTH]; 6],
    /// Per child: an inner node index, a leaf (`LEAF | first << 3 | count - 1`) or `EMPTY`.
    pub(super) child: [u32; WIDTH],
}

impl Node {
    const EMPTY: Node = Node {
        planes: [
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
    };

    fn set_box(&mut self, i: usize, b: &Aabb) {
        for a in 0..3 {
            self.planes[2 * a][i] = b.min[a];
            self.planes[2 * a + 1][i] = b.max[a];
        }
    }

    fn child_box(&self, i: usize) -> Aabb {
        Aabb {
            min: Vec3A::new(self.planes[0][i], self.planes[2][i], self.planes[4][i]),
            max: Vec3A::new(self.planes[1][i], self.planes[3][i], self.planes[5][i]),
        }
    }
}

/// A leaf as the caller sees it: `count` (1..=8) items from `first`.
#[inline(always)]
pub(super) fn leaf_range(c: u32) -> (u32, u32) {
    ((c & !LEAF) >> 3, (c & 7) + 1)
}

/// The 8-wide BVH. Node 0 is the root; children come after their parents.
#[derive(Clone, Debug, Default)]
pub struct Bvh8 {
    pub(super) nodes: Vec<Node>,
    /// Bounds of everything.
    pub bounds: Aabb,
}

mod build;
mod packet;
mod traverse;

pub use build::{BuildStats, MAX_DEPTH};
use build::{Kind, Tree};
pub use packet::PACKET;
pub use traverse::BoxRay;

impl Bvh8 {
    /// Builds a binary BVH over `aabbs` (with obvhs, crowds top-down: [`build`]) and
    /// collapses it. `leaf` receives the indices (into `aabbs`) of each leaf's primitives,
    /// every subtree of at most `max_leaf` of them as one leaf, stores them as it likes and
    /// returns the `(first, count)` range (count 1..=8) that [`Self::closest`] and
    /// [`Self::any`] will hand back for that leaf.
    pub fn build(aabbs: &[Aabb], max_leaf: u32, leaf: impl FnMut(&[u32]) -> (u32, u32)) -> Self {
        Self::build_with_stats(aabbs, max_leaf, leaf).0
    }

    /// [`Self::build`], and what the build did.
    pub fn build_with_stats(
        aabbs: &[Aabb],
        max_leaf: u32,
        leaf: impl FnMut(&[u32]) -> (u32, u32),
    ) -> (Self, BuildStats) {
        assert!((1..=255).contains(&max_leaf));
        if aabbs.is_empty() {
            return (Self::default(), BuildStats::default());
        }
        // obvhs's fast preset (PLOC, light reinsertion), its leaf collapse made to take every
        // subtree that fits (a traversal cost far above the intersection cost): on the
        // 1M-triangle knot, diffuse-bounce traversal as fast as the slow preset for half the
        // build time (0.38 s against 0.81 s); SAH-chosen leaves (cost 3 or 6) leave more,
        // emptier blocks and trace 4-12% slower (benches/RESULTS.md).
        let params = BvhBuildParams {
            max_prims_per_leaf: max_leaf,
            collapse_traversal_cost: 1e6,
            ..BvhBuildParams::fast_build()
        };
        let (tree, stats) = Tree::build(aabbs, max_leaf, params);
        if stats.crowds + stats.rebuilt > 0 {
            tracing::debug!(
                primitives = aabbs.len(),
                crowds = stats.crowds,
                crowd_primitives = stats.crowd_prims,
                rebuilt = stats.rebuilt,
                height = stats.height,
                "BVH: crowds built top-down"
            );
        }
        let bvh = Self::collapse(&tree, leaf);
        // The build bounds the binary tree's height; the traversal stacks rely on it.
        let depth = bvh.depth();
        assert!(depth <= MAX_DEPTH, "BVH depth {depth} beyond {MAX_DEPTH} (binary height {})", stats.height);
        if tracing::enabled!(tracing::Level::DEBUG) {
            tracing::debug!(
                primitives = aabbs.len(),
                nodes = bvh.nodes.len(),
                depth,
                sah_cost = bvh.sah_cost(),
                "BVH built"
            );
        }
        (bvh, stats)
    }

    /// Collapses a binary BVH: each node takes the two children of its binary counterpart and
    /// repeatedly opens the largest (by surface area) inner child until it has eight.
    fn collapse(tree: &Tree, mut leaf: impl FnMut(&[u32]) -> (u32, u32)) -> Self {
        let n2 = &tree.nodes;
        let mut out = Self { nodes: vec![Node::EMPTY], bounds: n2[0].aabb };
        // (binary node, wide node to fill)
        let mut todo = vec![(0usize, 0usize)];
        let mut leaf_ref = |first: u32, n: u32| {
            let (first, count) = leaf(&tree.prims[first as usize..(first + n) as usize]);
            assert!(first <= MAX_FIRST && (1..=8).contains(&count), "leaf range {first}, {count}");
            LEAF | first << 3 | (count - 1)
        };
        while let Some((bi, wi)) = todo.pop() {
            let root = &n2[bi];
            let (l, r) = match root.kind {
                Kind::Leaf(first, n) => {
                    // A tree that is one leaf: a root with one child.
                    let c = leaf_ref(first, n);
                    out.nodes[wi].set_box(0, &root.aabb);
                    out.nodes[wi].child[0] = c;
                    continue;
                }
                Kind::Inner(l, r) => (l, r),
            };
            let mut kids = vec![l as usize, r as usize];
            while kids.len() < WIDTH {
                let open = kids
                    .iter()
                    .enumerate()
                    .filter_map(|(pos, &k)| match n2[k].kind {
                        Kind::Inner(l, r) => Some((pos, (l, r), n2[k].aabb.half_area())),
                        Kind::Leaf(..) => None,
                    })
                    .max_by(|a, b| a.2.total_cmp(&b.2));
                let Some((pos, (l, r), _)) = open else { break };
                kids.swap_remove(pos);
                kids.extend([l as usize, r as usize]);
            }
            for (slot, &k) in kids.iter().enumerate() {
                out.nodes[wi].set_box(slot, &n2[k].aabb);
                out.nodes[wi].child[slot] = match n2[k].kind {
                    Kind::Leaf(first, n) => leaf_ref(first, n),
                    Kind::Inner(..) => {
                        out.nodes.push(Node::EMPTY);
                        let w = out.nodes.len() - 1;
                        todo.push((k, w));
                        w as u32
                    }
                };
            }
        }
        out
    }

    /// Most nodes on a path from the root to a leaf (0 for an empty tree).
    pub fn depth(&self) -> usize {
        // Children come after their parents.
        let mut depth = vec![0usize; self.nodes.len()];
        if let Some(root) = depth.first_mut() {
            *root = 1;
        }
        for i in 0..self.nodes.len() {
            for &c in &self.nodes[i].child {
                if c != EMPTY && c & LEAF == 0 {
                    depth[c as usize] = depth[i] + 1;
                }
            }
        }
        depth.into_iter().max().unwrap_or(0)
    }

    /// Recomputes every box from the leaves' bounds (`bounds(first, count)`), keeping the
    /// tree: for primitives that moved a little. Bounds of a tree that holds nothing stay empty.
    pub fn refit(&mut self, mut bounds: impl FnMut(u32, u32) -> Aabb) {
        // Children come after their parents: a reverse sweep sees every child first.
        for i in (0..self.nodes.len()).rev() {
            for slot in 0..WIDTH {
                let c = self.nodes[i].child[slot];
                let b = match c {
                    EMPTY => continue,
                    c if c & LEAF != 0 => {
                        let (first, count) = leaf_range(c);
                        bounds(first, count)
                    }
                    c => self.node_bounds(c as usize),
                };
                self.nodes[i].set_box(slot, &b);
            }
        }
        if !self.nodes.is_empty() {
            self.bounds = self.node_bounds(0);
        }
    }

    fn node_bounds(&self, i: usize) -> Aabb {
        let n = &self.nodes[i];
        (0..WIDTH).filter(|&s| n.child[s] != EMPTY).fold(Aabb::empty(), |b, s| b.union(&n.child_box(s)))
    }

    /// Sum of the surface areas of all child boxes relative to the root's: the expected number
    /// of node tests of a random ray that meets the root, up to a constant. Refitting after
    /// large motion makes it grow; then a rebuild pays.
    pub fn sah_cost(&self) -> f32 {
        let root = self.bounds.half_area();
        if self.nodes.is_empty() || !(root > 0.0) {
            return 0.0;
        }
        let mut sum = 0.0;
        for n in &self.nodes {
            for s in (0..WIDTH).filter(|&s| n.child[s] != EMPTY) {
                sum += n.child_box(s).half_area();
            }
        }
        sum / root
    }

    /// Checks the tree's invariants (the tests run it after every build and refit, as obvhs
    /// validates its trees): every inner node is reached exactly once, from a parent before
    /// it; empty slots hold no box; each leaf range has 1..=8 items and its box holds
    /// `leaf_bounds(first, count)`; each inner child's box holds every box of that child; the
    /// root's boxes lie within [`Self::bounds`]. The first broken rule is named.
    pub fn validate(&self, mut leaf_bounds: impl FnMut(u32, u32) -> Aabb) -> Result<(), String> {
        let holds =
            |outer: &Aabb, inner: &Aabb| inner.min.cmpge(outer.min).all() && inner.max.cmple(outer.max).all();
        let mut reached = vec![false; self.nodes.len()];
        if let Some(root) = reached.first_mut() {
            *root = true;
        }
        for (i, node) in self.nodes.iter().enumerate() {
            for slot in 0..WIDTH {
                let (c, b) = (node.child[slot], node.child_box(slot));
                match c {
                    EMPTY if b.min.cmple(b.max).any() => {
                        return Err(format!("node {i} slot {slot}: an empty slot has the box {b:?}"));
                    }
                    EMPTY => {}
                    c if c & LEAF != 0 => {
                        let (first, count) = leaf_range(c);
                        let items = leaf_bounds(first, count);
                        if !holds(&b, &items) {
                            return Err(format!(
                                "node {i} slot {slot}: leaf {first}+{count} has bounds {items:?} outside its box {b:?}"
                            ));
                        }
                    }
                    c if c as usize <= i || c as usize >= self.nodes.len() => {
                        return Err(format!("node {i} slot {slot}: child {c} is not a node after it"));
                    }
                    c if std::mem::replace(&mut reached[c as usize], true) => {
                        return Err(format!("node {c} has two parents (the second is node {i})"));
                    }
                    c if !holds(&b, &self.node_bounds(c as usize)) => {
                        return Err(format!(
                            "node {i} slot {slot}: child node {c} reaches outside its box {b:?}"
                        ));
                    }
                    _ => {}
                }
                if i == 0 && c != EMPTY && !holds(&self.bounds, &b) {
                    return Err(format!("root slot {slot}: box {b:?} outside the bounds {:?}", self.bounds));
                }
            }
        }
        match reached.iter().position(|r| !r) {
            Some(i) => Err(format!("node {i} is not reached from the root")),
            None => Ok(()),
        }
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes held by the nodes.
    pub fn node_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes() -> Vec<Aabb> {
        let mut rnd = crate::testing::uniform(1);
        (0..2000)
            .map(|_| {
                let c = Vec3A::new(rnd(), rnd(), rnd()) * 100.0;
                let e = Vec3A::new(rnd(), rnd(), rnd()) * [0.1, 2.0, 10.0][(rnd() * 3.0) as usize % 3];
                Aabb { min: c - e, max: c + e }
            })
            .collect()
    }

    /// Slab test of one box, for comparison.
    fn enters(b: &Aabb, o: Vec3A, d: Vec3A, tmax: f32) -> Option<f32> {
        let (t0, t1) = ((b.min - o) / d, (b.max - o) / d);
        let (near, far) = (t0.min(t1).max_element().max(0.0), t0.max(t1).min_element().min(tmax));
        (near <= far).then_some(near)
    }

    #[test]
    fn traversal_finds_what_a_scan_finds_and_refit_keeps_it() {
        let mut aabbs = boxes();
        let mut order = Vec::new();
        let mut bvh = Bvh8::build(&aabbs, 4, |p| {
            order.extend_from_slice(p);
            ((order.len() - p.len()) as u32, p.len() as u32)
        });
        assert!(bvh.node_count() > 1);
        let bounds_of = |order: &[u32], aabbs: &[Aabb], first: u32, count: u32| {
            order[first as usize..(first + count) as usize]
                .iter()
                .fold(Aabb::empty(), |a, &i| a.union(&aabbs[i as usize]))
        };
        bvh.validate(|first, count| bounds_of(&order, &aabbs, first, count)).unwrap();
        for round in 0..2 {
            let mut rnd = crate::testing::signed(77);
            let mut hits = 0;
            for _ in 0..500 {
                let o = Vec3A::new(rnd(), rnd(), rnd()) * 150.0;
                // Aimed at the cloud of boxes, so that most rays hit something.
                let d = (Vec3A::new(rnd(), rnd(), rnd()) + 1.0) * 50.0 - o;
                let want = aabbs.iter().filter_map(|b| enters(b, o, d, 1e9)).fold(f32::INFINITY, f32::min);
                // "Primitives" are the boxes themselves.
                let got = bvh.closest(o, d, f32::INFINITY, |first, count, best| {
                    let items = &order[first as usize..(first + count) as usize];
                    items.iter().filter_map(|&i| enters(&aabbs[i as usize], o, d, best)).fold(best, f32::min)
                });
                assert_eq!(want, got, "round {round}, ray {o} {d}");
                let any = bvh.any(o, d, f32::INFINITY, |first, count| {
                    order[first as usize..(first + count) as usize]
                        .iter()
                        .any(|&i| enters(&aabbs[i as usize], o, d, f32::INFINITY).is_some())
                });
                assert_eq!(any, want.is_finite());
                hits += want.is_finite() as u32;
            }
            assert!(hits > 250, "{hits}");
            // Move every box and refit.
            for b in &mut aabbs {
                let shift = Vec3A::new(3.0, -1.0, 0.5) * (b.min.x % 1.0);
                (b.min, b.max) = (b.min + shift, b.max + shift);
            }
            let before = bvh.sah_cost();
            bvh.refit(|first, count| bounds_of(&order, &aabbs, first, count));
            bvh.validate(|first, count| bounds_of(&order, &aabbs, first, count)).unwrap();
            assert!(bvh.sah_cost() >= before * 0.9);
        }
    }

    /// `validate` names each kind of broken tree.
    #[test]
    fn validate_finds_broken_trees() {
        let aabbs = boxes();
        let mut order = Vec::new();
        let bvh = Bvh8::build(&aabbs, 4, |p| {
            order.extend_from_slice(p);
            ((order.len() - p.len()) as u32, p.len() as u32)
        });
        let bounds = |first: u32, count: u32| {
            order[first as usize..(first + count) as usize]
                .iter()
                .fold(Aabb::empty(), |a, &i| a.union(&aabbs[i as usize]))
        };
        assert_eq!(bvh.validate(bounds), Ok(()));
        let inner = |n: &Node| (0..WIDTH).find(|&s| n.child[s] != EMPTY && n.child[s] & LEAF == 0);
        let leaf = |n: &Node| (0..WIDTH).find(|&s| n.child[s] != EMPTY && n.child[s] & LEAF != 0);
        let broken = |edit: &dyn Fn(&mut Bvh8), what: &str| {
            let mut b = bvh.clone();
            edit(&mut b);
            let err = b.validate(bounds).expect_err(what);
            assert!(err.contains(what), "{what}: {err}");
        };
        // A root slot that points at a second parent's child.
        broken(
            &|b| {
                let s = inner(&b.nodes[0]).unwrap();
                let c = b.nodes[0].child[s] as usize;
                let t = inner(&b.nodes[c]).unwrap();
                let grandchild = b.nodes[c].child[t];
                let free = (0..WIDTH).find(|&s| b.nodes[0].child[s] == EMPTY);
                let slot = free.unwrap_or((s + 1) % WIDTH);
                b.nodes[0].child[slot] = grandchild;
                let all = b.bounds;
                b.nodes[0].set_box(slot, &all);
            },
            "two parents",
        );
        // A leaf box shrunk below its items.
        broken(
            &|b| {
                let i = (0..b.nodes.len()).find(|&i| leaf(&b.nodes[i]).is_some()).unwrap();
                let s = leaf(&b.nodes[i]).unwrap();
                b.nodes[i].planes[1][s] = b.nodes[i].planes[0][s];
            },
            "outside its box",
        );
        // A child before its parent.
        broken(
            &|b| {
                let i = b.nodes.len() - 1;
                let s = (0..WIDTH).find(|&s| b.nodes[i].child[s] != EMPTY).unwrap();
                b.nodes[i].child[s] = 0;
            },
            "not a node after it",
        );
        // An empty slot with a box.
        broken(
            &|b| {
                let i = (0..b.nodes.len()).find(|&i| b.nodes[i].child.contains(&EMPTY)).unwrap();
                let s = (0..WIDTH).find(|&s| b.nodes[i].child[s] == EMPTY).unwrap();
                b.nodes[i].set_box(s, &aabbs[0]);
            },
            "an empty slot",
        );
        // A root box beyond the bounds.
        broken(&|b| b.bounds.max -= Vec3A::ONE, "outside the bounds");
    }

    #[test]
    fn a_packet_finds_what_each_ray_finds_alone() {
        let aabbs = boxes();
        let mut order = Vec::new();
        let bvh = Bvh8::build(&aabbs, 2, |p| {
            order.extend_from_slice(p);
            ((order.len() - p.len()) as u32, p.len() as u32)
        });
        let mut rnd = crate::testing::signed(5);
        let mut hits = 0;
        for round in 0..300 {
            // Packets from one point, spread a little (as a pixel's samples) or a lot, some
            // directions with zero components; their tmax finite or not.
            let from = Vec3A::new(rnd(), rnd(), rnd()) * 150.0;
            let spread = [0.02, 0.5, 3.0][round % 3];
            let aim = (Vec3A::new(rnd(), rnd(), rnd()) + 1.0) * 50.0 - from;
            let (mut o, mut d) = ([[0.0; PACKET]; 3], [[0.0; PACKET]; 3]);
            let mut best = [0.0; PACKET];
            for l in 0..PACKET {
                let mut dir = aim.normalize() + Vec3A::new(rnd(), rnd(), rnd()) * spread;
                if l == 3 {
                    dir.y = 0.0;
                }
                let start = from + Vec3A::new(rnd(), rnd(), rnd());
                for a in 0..3 {
                    (o[a][l], d[a][l]) = (start[a], dir[a]);
                }
                best[l] = if l % 4 == 1 { 20.0 + 100.0 * rnd().abs() } else { f32::INFINITY };
            }
            let ray =
                |l: usize| (Vec3A::new(o[0][l], o[1][l], o[2][l]), Vec3A::new(d[0][l], d[1][l], d[2][l]));
            let want: [f32; PACKET] = std::array::from_fn(|l| {
                let (o, d) = ray(l);
                bvh.closest(o, d, best[l], |first, count, best| {
                    let items = &order[first as usize..(first + count) as usize];
                    items.iter().filter_map(|&i| enters(&aabbs[i as usize], o, d, best)).fold(best, f32::min)
                })
            });
            // Any hit, each ray up to its closest box (some rays then hit nothing before it).
            let tmax: [f32; PACKET] = std::array::from_fn(|l| want[l] * [0.5, 1.0, 2.0][l % 3]);
            let occluded = bvh.any_packet(&o, &d, &tmax, |first, count, active| {
                let mut hit = 0;
                for l in (0..PACKET).filter(|l| active >> l & 1 != 0) {
                    let (o, d) = ray(l);
                    let items = &order[first as usize..(first + count) as usize];
                    hit |= (items.iter().any(|&i| enters(&aabbs[i as usize], o, d, tmax[l]).is_some())
                        as u32)
                        << l;
                }
                hit
            });
            for l in 0..PACKET {
                let (o, d) = ray(l);
                let alone = bvh.any(o, d, tmax[l], |first, count| {
                    order[first as usize..(first + count) as usize]
                        .iter()
                        .any(|&i| enters(&aabbs[i as usize], o, d, tmax[l]).is_some())
                });
                assert_eq!(occluded >> l & 1 != 0, alone, "round {round}, lane {l}: any hit");
            }
            bvh.closest_packet(&o, &d, &mut best, |first, count, active, best| {
                for l in (0..PACKET).filter(|l| active >> l & 1 != 0) {
                    let (o, d) = ray(l);
                    let items = &order[first as usize..(first + count) as usize];
                    best[l] = items
                        .iter()
                        .filter_map(|&i| enters(&aabbs[i as usize], o, d, best[l]))
                        .fold(best[l], f32::min);
                }
            });
            for l in 0..PACKET {
                assert_eq!(best[l].to_bits(), want[l].to_bits(), "round {round}, lane {l}");
                hits += want[l].is_finite() as u32;
            }
        }
        assert!(hits > 1000, "{hits}");
    }

    /// Boxes no PLOC can order: many copies of one box, boxes nested about one centre (and
    /// about centres a rounding apart, and about centres spread along a line), duplicates of
    /// ordinary boxes around a crowd, and a cloud beside one far box (one Morton cell).
    fn crowds() -> Vec<(&'static str, Vec<Aabb>)> {
        let cube = |c: Vec3A, r: f32| Aabb { min: c - r, max: c + r };
        let mut rnd = crate::testing::uniform(9);
        let c = Vec3A::new(10.1, 20.3, 30.7);
        let mut mixed: Vec<Aabb> = boxes().into_iter().flat_map(|b| [b; 3]).collect();
        mixed.extend([cube(Vec3A::splat(50.0), 1.0); 2000]);
        let mut far: Vec<Aabb> =
            (0..3000).map(|_| cube(Vec3A::new(rnd(), rnd(), rnd()), 1e-3 * (rnd() + 0.5))).collect();
        far.push(cube(Vec3A::splat(1e6), 1.0));
        vec![
            ("identical", vec![cube(c, 1.0); 3000]),
            ("concentric", (0..3000).map(|i| cube(Vec3A::ZERO, 1.0 + i as f32)).collect()),
            (
                "concentric about a centre that rounds",
                (0..3000).map(|i| cube(c, 0.37 * (1 + i) as f32)).collect(),
            ),
            (
                "nested along a line",
                (0..3000).map(|i| cube(Vec3A::X * (i as f32 * 0.01), 1.0 + i as f32)).collect(),
            ),
            ("duplicates around a crowd", mixed),
            ("a cloud and a far box", far),
        ]
    }

    /// Every crowd builds a valid, shallow tree that every traversal answers as a scan of the
    /// boxes does (PLOC alone chained the crowds, and the chains overflowed the traversal
    /// stacks).
    #[test]
    fn crowds_are_traversed_as_a_scan_finds() {
        for (name, aabbs) in crowds() {
            for max_leaf in [1, 2, 24] {
                // Leaf `k` (handed back as `(k, 1)`) holds `order[leaves[k].0..leaves[k].1]`.
                let (mut order, mut leaves) = (Vec::new(), Vec::new());
                let (bvh, stats) = Bvh8::build_with_stats(&aabbs, max_leaf, |p| {
                    leaves.push((order.len(), order.len() + p.len()));
                    order.extend_from_slice(p);
                    (leaves.len() as u32 - 1, 1)
                });
                // A chain of 3000 would be hundreds of levels deep; eight wide, log8(3000) is 4.
                assert!(bvh.depth() < 20, "{name}, leaves of {max_leaf}: depth {}, {stats:?}", bvh.depth());
                let items = |leaf: u32, _| &order[leaves[leaf as usize].0..leaves[leaf as usize].1];
                bvh.validate(|first, count| {
                    items(first, count).iter().fold(Aabb::empty(), |a, &i| a.union(&aabbs[i as usize]))
                })
                .unwrap_or_else(|e| panic!("{name}, leaves of {max_leaf}: {e}"));
                assert!(
                    leaves.iter().all(|(a, b)| b - a <= max_leaf as usize),
                    "{name}: leaves of {max_leaf}"
                );
                let bounds = aabbs.iter().fold(Aabb::empty(), |a, b| a.union(b));
                let size = (bounds.max - bounds.min).max_element();
                let mut rnd = crate::testing::uniform(31);
                let mut aim = || {
                    let b = &aabbs[(rnd() * (aabbs.len() - 1) as f32) as usize];
                    b.center() + (b.max - b.min) * (rnd() - 0.5)
                };
                let mut dir = crate::testing::signed(37);
                let mut hits = 0;
                for r in 0..200 {
                    // From outside the crowd (or 2000 away) towards a box of it, and from inside a box.
                    let to = aim();
                    let out = Vec3A::new(dir(), dir(), dir()).normalize_or(Vec3A::Y);
                    let reach = size.min(1e3) * 2.0;
                    let (o, d) = if r % 4 == 3 { (to, out) } else { (to + out * reach, -out) };
                    let want =
                        aabbs.iter().filter_map(|b| enters(b, o, d, 1e30)).fold(f32::INFINITY, f32::min);
                    let got = bvh.closest(o, d, f32::INFINITY, |first, count, best| {
                        items(first, count)
                            .iter()
                            .filter_map(|&i| enters(&aabbs[i as usize], o, d, best))
                            .fold(best, f32::min)
                    });
                    assert_eq!(want, got, "{name}, leaves of {max_leaf}, ray {r}");
                    let any = bvh.any(o, d, f32::INFINITY, |first, count| {
                        items(first, count)
                            .iter()
                            .any(|&i| enters(&aabbs[i as usize], o, d, f32::INFINITY).is_some())
                    });
                    assert_eq!(any, want.is_finite(), "{name}, leaves of {max_leaf}, ray {r}");
                    hits += want.is_finite() as u32;
                }
                assert!(hits > 100, "{name}: {hits}");
                // A packet of rays from one point into the crowd.
                let from = aim() + Vec3A::new(0.3, 0.9, -0.2).normalize() * size.min(1e3) * 2.0;
                let (mut o, mut d) = ([[0.0; PACKET]; 3], [[0.0; PACKET]; 3]);
                for l in 0..PACKET {
                    let dir = aim() - from;
                    for a in 0..3 {
                        (o[a][l], d[a][l]) = (from[a], dir[a]);
                    }
                }
                let ray =
                    |l: usize| (Vec3A::new(o[0][l], o[1][l], o[2][l]), Vec3A::new(d[0][l], d[1][l], d[2][l]));
                let mut best = [f32::INFINITY; PACKET];
                bvh.closest_packet(&o, &d, &mut best, |first, count, active, best| {
                    for l in (0..PACKET).filter(|l| active >> l & 1 != 0) {
                        let (o, d) = ray(l);
                        best[l] = items(first, count)
                            .iter()
                            .filter_map(|&i| enters(&aabbs[i as usize], o, d, best[l]))
                            .fold(best[l], f32::min);
                    }
                });
                let tmax = [f32::INFINITY; PACKET];
                let occluded = bvh.any_packet(&o, &d, &tmax, |first, count, active| {
                    let mut hit = 0;
                    for l in (0..PACKET).filter(|l| active >> l & 1 != 0) {
                        let (o, d) = ray(l);
                        let any = items(first, count)
                            .iter()
                            .any(|&i| enters(&aabbs[i as usize], o, d, tmax[l]).is_some());
                        hit |= (any as u32) << l;
                    }
                    hit
                });
                for l in 0..PACKET {
                    let (o, d) = ray(l);
                    let want =
                        aabbs.iter().filter_map(|b| enters(b, o, d, 1e30)).fold(f32::INFINITY, f32::min);
                    assert_eq!(best[l], want, "{name}, leaves of {max_leaf}, packet lane {l}");
                    assert_eq!(
                        occluded >> l & 1 != 0,
                        want.is_finite(),
                        "{name}, leaves of {max_leaf}, lane {l}"
                    );
                }
            }
        }
    }
}
