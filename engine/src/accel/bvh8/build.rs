//! The binary BVH that [`Bvh8::build`](super::Bvh8::build) collapses to eight wide: obvhs's
//! PLOC build where PLOC can order the primitives, a top-down median build for the crowds it
//! cannot, and a bound on the tree's height that the traversal stacks are sized for.
//!
//! PLOC (Meister and Bittner, "Parallel Locally-Ordered Clustering for Bounding Volume
//! Hierarchy Construction", IEEE TVCG 2018; obvhs's `ploc/mod.rs`) sorts the primitives by the
//! Morton code of their centroids and, pass after pass, merges the pairs that are each other's
//! nearest neighbour (by the surface area of their union) among the next few in that order.
//! Primitives that share a Morton cell are in no order, and where their unions tie (copies of
//! one box, boxes nested about one centre) the neighbour each picks is not the one that picks
//! it: one pair merges per pass at the end of the run. k such primitives take k passes over
//! the list (quadratic time: 10k duplicate faces took 1 s, 160k over a minute) and make a chain
//! k levels deep, whose 7 pushed siblings per level overflowed the traversal stack. So
//!
//! - the primitives of a Morton cell (obvhs's grid: 2^21 cells a side over the boxes' bounds)
//!   that holds more than [`CROWD`] of them are built top-down into a balanced subtree first,
//!   and PLOC clusters that subtree as one item;
//! - a subtree that is still too deep (boxes nested across cells, which PLOC chains the same
//!   way) is rebuilt top-down, so that no leaf lies more than [`MAX_DEPTH`] inner nodes down.
//!
//! Ordinary primitive sets have neither, and get obvhs's tree unchanged.

use obvhs::bvh2::{Bvh2, leaf_collapser::collapse, reinsertion::ReinsertionOptimizer};
use obvhs::ploc::PlocBuilder;
use obvhs::{BvhBuildParams, aabb::Aabb};
use std::cmp::Ordering;

/// Most inner nodes on a path from the root to a leaf, in the binary tree and so in the
/// collapsed one (each of its levels takes at least one binary level): the traversal stacks
/// hold the seven siblings per level this allows. A balanced tree of 2^32 primitives needs 32.
pub const MAX_DEPTH: usize = 64;

/// Primitives one Morton cell may hold and still go to PLOC as they are. A few tied
/// primitives cost PLOC a few passes and levels; ordinary scenes have no cell this full.
const CROWD: usize = 8;

/// Morton cells a side, as obvhs's 64-bit codes (21 bits per axis).
const CELLS: f64 = (1u64 << 21) as f64;

/// A binary node: its box, and two children or a range of [`Tree::prims`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Node2 {
    pub aabb: Aabb,
    pub kind: Kind,
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    Inner(u32, u32),
    Leaf(u32, u32),
}

/// A binary BVH; node 0 is the root. Nodes and primitive ranges that a rebuild replaced stay
/// behind, unreached.
pub(super) struct Tree {
    pub nodes: Vec<Node2>,
    pub prims: Vec<u32>,
}

/// What a build did, for the log and the tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildStats {
    /// Items PLOC clustered: the primitives outside crowds, and one per crowd.
    pub ploc_items: usize,
    /// Crowds built top-down first.
    pub crowds: usize,
    /// Primitives in those crowds.
    pub crowd_prims: usize,
    /// Subtrees rebuilt top-down to bound the height.
    pub rebuilt: usize,
    /// Primitives the top-down builds partitioned, summed over the nodes they split: about
    /// `n log2(n / max_leaf)` for `n` primitives.
    pub split_work: usize,
    /// Most inner nodes on a path from the root to a leaf.
    pub height: usize,
}

/// Height of the tree [`Tree::top_down`] makes of `n` primitives.
fn balanced_height(mut n: usize, max_leaf: usize) -> usize {
    let mut h = 0;
    while n > max_leaf {
        n -= n / 2;
        h += 1;
    }
    h
}

fn bounds(aabbs: &[Aabb], prims: &[u32]) -> Aabb {
    prims.iter().fold(Aabb::empty(), |b, &p| b.union(&aabbs[p as usize]))
}

/// Morton cell of each primitive's centroid as `(cell, primitive)`, sorted.
fn cells(aabbs: &[Aabb]) -> Vec<(u64, u32)> {
    let total = aabbs.iter().fold(Aabb::empty(), |b, a| b.union(a));
    let (lo, size) = (total.min.as_dvec3(), (total.max - total.min).as_dvec3());
    let mut keyed: Vec<(u64, u32)> = aabbs
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let u = (b.center().as_dvec3() - lo) / size * CELLS;
            // A flat axis (0 / 0) or an infinite one is one cell; `as` saturates.
            let q = |x: f64| if x.is_finite() { x.clamp(0.0, CELLS - 1.0) as u64 } else { 0 };
            (q(u.x) << 42 | q(u.y) << 21 | q(u.z), i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed
}

/// obvhs's binary BVH of `aabbs`: the steps of its `bvh2::builder::build_bvh2` (PLOC,
/// reinsertion, leaf collapse, reinsertion) without its validation, which debug builds run and
/// which asserts the tree no deeper than obvhs's own stack bound. Boxes nested across Morton
/// cells make PLOC chain them thousands of levels deep (the reinsertion can add one more than
/// PLOC counted): [`Tree::bound_height`] rebuilds such chains, but the assertion panicked first
/// (found by the `bvh` fuzzer, `fuzz/seeds/bvh/line-and-scatter`).
fn ploc(aabbs: &[Aabb], params: BvhBuildParams) -> Bvh2 {
    let indices = (0..aabbs.len() as u32).collect();
    let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
        params.ploc_search_distance,
        aabbs,
        indices,
        params.sort_precision,
        params.search_depth_threshold,
    );
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh2, params.reinsertion_batch_ratio, None);
    collapse(&mut bvh2, params.max_prims_per_leaf.clamp(1, 255), params.collapse_traversal_cost);
    let ratio = params.reinsertion_batch_ratio * params.post_collapse_reinsertion_batch_ratio_multiplier;
    reinsertion.run(&mut bvh2, ratio, None);
    bvh2
}

impl Tree {
    /// Builds the tree of `aabbs` (not empty) with leaves of at most `max_leaf` primitives.
    pub fn build(aabbs: &[Aabb], max_leaf: u32, params: BvhBuildParams) -> (Self, BuildStats) {
        let mut stats = BuildStats::default();
        let keyed = cells(aabbs);
        let mut crowds: Vec<Vec<u32>> = Vec::new();
        let mut in_crowd = vec![false; aabbs.len()];
        for run in keyed.chunk_by(|a, b| a.0 == b.0).filter(|run| run.len() > CROWD) {
            crowds.push(run.iter().map(|&(_, p)| p).collect());
            for &(_, p) in run {
                in_crowd[p as usize] = true;
            }
        }
        drop(keyed);
        let mut tree = if crowds.is_empty() {
            stats.ploc_items = aabbs.len();
            let bvh2 = ploc(aabbs, params);
            let nodes = bvh2.nodes.iter().map(|n| Node2 {
                aabb: *n.aabb(),
                kind: match n.is_leaf() {
                    true => Kind::Leaf(n.first_index, n.prim_count),
                    false => Kind::Inner(n.first_index, n.first_index + 1),
                },
            });
            Self { nodes: nodes.collect(), prims: bvh2.primitive_indices }
        } else {
            Self::build_around_crowds(aabbs, max_leaf, params, crowds, &in_crowd, &mut stats)
        };
        tree.bound_height(aabbs, max_leaf as usize, &mut stats);
        (tree, stats)
    }

    /// PLOC over the primitives outside `crowds` and one item per crowd, each crowd built
    /// top-down; a PLOC leaf that holds crowds becomes a balanced join of its parts.
    fn build_around_crowds(
        aabbs: &[Aabb],
        max_leaf: u32,
        params: BvhBuildParams,
        crowds: Vec<Vec<u32>>,
        in_crowd: &[bool],
        stats: &mut BuildStats,
    ) -> Self {
        // Items: the other primitives in their order, then the crowds.
        enum Item {
            Prim(u32),
            Crowd(usize),
        }
        let mut item: Vec<Item> =
            (0..aabbs.len() as u32).filter(|&p| !in_crowd[p as usize]).map(Item::Prim).collect();
        let mut boxes: Vec<Aabb> =
            aabbs.iter().zip(in_crowd).filter(|(_, c)| !**c).map(|(b, _)| *b).collect();
        for (c, members) in crowds.iter().enumerate() {
            item.push(Item::Crowd(c));
            boxes.push(bounds(aabbs, members));
        }
        stats.ploc_items = item.len();
        stats.crowds = crowds.len();
        stats.crowd_prims = crowds.iter().map(Vec::len).sum();
        let bvh2 = ploc(&boxes, params);
        let mut tree = Self {
            nodes: bvh2
                .nodes
                .iter()
                .map(|n| Node2 { aabb: *n.aabb(), kind: Kind::Inner(n.first_index, n.first_index + 1) })
                .collect(),
            prims: Vec::with_capacity(aabbs.len()),
        };
        let roots: Vec<u32> =
            crowds.into_iter().map(|m| tree.top_down(aabbs, m, max_leaf as usize, stats)).collect();
        for (i, n) in bvh2.nodes.iter().enumerate().filter(|(_, n)| n.is_leaf()) {
            let items =
                &bvh2.primitive_indices[n.first_index as usize..(n.first_index + n.prim_count) as usize];
            let first = tree.prims.len();
            let mut parts = Vec::new();
            for &it in items {
                match item[it as usize] {
                    Item::Crowd(c) => parts.push(roots[c]),
                    Item::Prim(p) => tree.prims.push(p),
                }
            }
            if tree.prims.len() > first {
                let count = (tree.prims.len() - first) as u32;
                let aabb = bounds(aabbs, &tree.prims[first..]);
                parts.push(tree.push(Node2 { aabb, kind: Kind::Leaf(first as u32, count) }));
            }
            // Pairs of parts, then pairs of those, ...
            while parts.len() > 1 {
                parts = parts
                    .chunks(2)
                    .map(|pair| match *pair {
                        [a, b] => {
                            let aabb = tree.nodes[a as usize].aabb.union(&tree.nodes[b as usize].aabb);
                            tree.push(Node2 { aabb, kind: Kind::Inner(a, b) })
                        }
                        _ => pair[0],
                    })
                    .collect();
            }
            tree.nodes[i] = tree.nodes[parts[0] as usize];
        }
        tree
    }

    fn push(&mut self, node: Node2) -> u32 {
        self.nodes.push(node);
        self.nodes.len() as u32 - 1
    }

    /// Builds a subtree of `prims` top-down and returns its root. Each node splits its
    /// primitives in two halves of equal count (so the height is `log2(n / max_leaf)`
    /// rounded up), at the median of one of four orders: the centroids along x, y or z, or
    /// the boxes' surface areas (which sorts boxes nested about one centre small to large, so
    /// that a ray skips the small ones it misses), each with ties by index; the order whose
    /// halves have the smallest summed surface area (the surface area heuristic of two halves
    /// of equal count) wins.
    fn top_down(&mut self, aabbs: &[Aabb], prims: Vec<u32>, max_leaf: usize, stats: &mut BuildStats) -> u32 {
        let first = self.prims.len();
        self.prims.extend(prims);
        self.split(aabbs, first, self.prims.len(), max_leaf, stats)
    }

    fn split(
        &mut self,
        aabbs: &[Aabb],
        lo: usize,
        hi: usize,
        max_leaf: usize,
        stats: &mut BuildStats,
    ) -> u32 {
        let aabb = bounds(aabbs, &self.prims[lo..hi]);
        if hi - lo <= max_leaf {
            return self.push(Node2 { aabb, kind: Kind::Leaf(lo as u32, (hi - lo) as u32) });
        }
        stats.split_work += hi - lo;
        let key = |order: usize, p: u32| {
            let b = &aabbs[p as usize];
            if order < 3 { b.center()[order] } else { b.half_area() }
        };
        let by =
            |order: usize| move |a: &u32, b: &u32| key(order, *a).total_cmp(&key(order, *b)).then(a.cmp(b));
        let range = &mut self.prims[lo..hi];
        let mid = range.len() / 2;
        let mut best = (f32::INFINITY, 0);
        for order in 0..4 {
            range.select_nth_unstable_by(mid, by(order));
            let cost = bounds(aabbs, &range[..mid]).half_area() + bounds(aabbs, &range[mid..]).half_area();
            if cost.total_cmp(&best.0) == Ordering::Less {
                best = (cost, order);
            }
        }
        if best.1 != 3 {
            range.select_nth_unstable_by(mid, by(best.1));
        }
        let node = self.push(Node2 { aabb, kind: Kind::Leaf(0, 0) });
        let left = self.split(aabbs, lo, lo + mid, max_leaf, stats);
        let right = self.split(aabbs, lo + mid, hi, max_leaf, stats);
        self.nodes[node as usize].kind = Kind::Inner(left, right);
        node
    }

    /// Rebuilds top-down the subtrees that reach deeper than [`MAX_DEPTH`], keeping as much of
    /// the tree above them as still leaves room for a balanced subtree below: a node at depth
    /// `d` is descended into only while each child's balanced rebuild would still fit at
    /// `d + 1`, which holds at the root (a balanced tree needs at most 32 levels), so every
    /// node reached either fits as it is or is rebuilt to fit.
    fn bound_height(&mut self, aabbs: &[Aabb], max_leaf: usize, stats: &mut BuildStats) {
        let (height, count) = self.heights();
        stats.height = height[0] as usize;
        if stats.height <= MAX_DEPTH {
            return;
        }
        let mut todo = vec![(0u32, 0usize)];
        while let Some((v, depth)) = todo.pop() {
            if depth + height[v as usize] as usize <= MAX_DEPTH {
                continue;
            }
            let fits =
                |c: u32| depth + 1 + balanced_height(count[c as usize] as usize, max_leaf) <= MAX_DEPTH;
            match self.nodes[v as usize].kind {
                Kind::Inner(l, r) if fits(l) && fits(r) => todo.extend([(l, depth + 1), (r, depth + 1)]),
                _ => {
                    let prims = self.subtree_prims(v);
                    let root = self.top_down(aabbs, prims, max_leaf, stats);
                    self.nodes[v as usize] = self.nodes[root as usize];
                    stats.rebuilt += 1;
                }
            }
        }
        stats.height = self.heights().0[0] as usize;
    }

    /// Per node reached from the root: the most inner nodes on a path down to a leaf, and the
    /// primitives below it.
    fn heights(&self) -> (Vec<u32>, Vec<u32>) {
        let mut height = vec![0u32; self.nodes.len()];
        let mut count = vec![0u32; self.nodes.len()];
        // Post-order: a node is finished when popped the second time.
        let mut todo = vec![(0u32, false)];
        while let Some((v, done)) = todo.pop() {
            match (self.nodes[v as usize].kind, done) {
                (Kind::Leaf(_, n), _) => count[v as usize] = n,
                (Kind::Inner(l, r), false) => todo.extend([(v, true), (l, false), (r, false)]),
                (Kind::Inner(l, r), true) => {
                    let (l, r) = (l as usize, r as usize);
                    height[v as usize] = 1 + height[l].max(height[r]);
                    count[v as usize] = count[l] + count[r];
                }
            }
        }
        (height, count)
    }

    /// The primitives in the leaves below `v`.
    fn subtree_prims(&self, v: u32) -> Vec<u32> {
        let (mut out, mut todo) = (Vec::new(), vec![v]);
        while let Some(v) = todo.pop() {
            match self.nodes[v as usize].kind {
                Kind::Leaf(first, n) => {
                    out.extend_from_slice(&self.prims[first as usize..(first + n) as usize])
                }
                Kind::Inner(l, r) => todo.extend([r, l]),
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    fn params(max_leaf: u32) -> BvhBuildParams {
        BvhBuildParams {
            max_prims_per_leaf: max_leaf,
            collapse_traversal_cost: 1e6,
            ..BvhBuildParams::fast_build()
        }
    }

    /// Boxes of the triangles of a mesh of `faces` distinct faces, each given `copies` times
    /// (as an OBJ file that repeats its faces).
    fn duplicate_faces(faces: usize, copies: usize) -> Vec<Aabb> {
        let mut rnd = crate::testing::uniform(3);
        let distinct: Vec<Aabb> = (0..faces)
            .map(|_| {
                let p = [(); 3].map(|_| Vec3A::new(rnd(), rnd(), rnd()) * 10.0);
                Aabb { min: p[0].min(p[1]).min(p[2]), max: p[0].max(p[1]).max(p[2]) }
            })
            .collect();
        (0..copies).flat_map(|_| distinct.iter().copied()).collect()
    }

    /// Duplicate faces cost PLOC nothing more than the distinct faces, and the top-down builds
    /// partition each primitive once per level of a balanced tree: the work grows as
    /// n log n while the faces are copied 10k to 160k times over (before, PLOC took one
    /// pass per copy: 1 s for 10k, over a minute for 160k).
    #[test]
    fn duplicate_faces_build_in_n_log_n_work() {
        for copies in [10_000, 40_000, 160_000] {
            let aabbs = duplicate_faces(3, copies);
            let n = aabbs.len();
            let (tree, stats) = Tree::build(&aabbs, 24, params(24));
            assert_eq!((stats.ploc_items, stats.crowds, stats.crowd_prims), (3, 3, n), "{copies}: {stats:?}");
            let levels = balanced_height(copies, 24);
            assert!(stats.split_work <= n * levels, "{copies}: {stats:?}");
            assert!(stats.height <= levels + 2 && stats.rebuilt == 0, "{copies}: {stats:?}");
            // Every primitive in exactly one leaf of at most 24.
            let mut seen = vec![0u8; n];
            for p in tree.subtree_prims(0) {
                seen[p as usize] += 1;
            }
            assert!(seen.iter().all(|&s| s == 1), "{copies}");
        }
    }

    /// Ordinary boxes, and a few duplicates among them, go to PLOC as they are.
    #[test]
    fn ordinary_boxes_keep_obvhs_tree() {
        let mut aabbs = duplicate_faces(5000, 1);
        aabbs.extend_from_within(..CROWD);
        let (_, stats) = Tree::build(&aabbs, 2, params(2));
        assert_eq!((stats.ploc_items, stats.crowds, stats.rebuilt), (aabbs.len(), 0, 0), "{stats:?}");
        assert!(stats.height < 40, "{stats:?}");
    }

    /// Boxes nested about centres spread along a line fall in different Morton cells, and
    /// PLOC chains them as deep as there are boxes: the chain's lower part is rebuilt, and
    /// the tree ends within [`MAX_DEPTH`] levels.
    #[test]
    fn nested_boxes_across_cells_are_rebuilt_within_the_bound() {
        let aabbs: Vec<Aabb> = (0..3000)
            .map(|i| {
                let (c, r) = (Vec3A::X * (i as f32 * 0.01), 1.0 + i as f32);
                Aabb { min: c - r, max: c + r }
            })
            .collect();
        let (tree, stats) = Tree::build(&aabbs, 2, params(2));
        assert_eq!(stats.crowds, 0, "{stats:?}");
        assert!(stats.rebuilt > 0 && stats.height <= MAX_DEPTH, "{stats:?}");
        let mut seen = tree.subtree_prims(0);
        seen.sort_unstable();
        assert_eq!(seen, (0..3000).collect::<Vec<u32>>());
    }

    /// Boxes nested about one centre are crowds; their subtree orders them by size, so that
    /// the half of the smaller ones has the box of the middle one.
    #[test]
    fn a_crowd_of_nested_boxes_splits_small_from_large() {
        let aabbs: Vec<Aabb> = (0..1000)
            .map(|i| Aabb { min: Vec3A::splat(-1.0 - i as f32), max: Vec3A::splat(1.0 + i as f32) })
            .collect();
        let (tree, stats) = Tree::build(&aabbs, 2, params(2));
        assert_eq!(
            (stats.crowds, stats.ploc_items, stats.height),
            (1, 1, balanced_height(1000, 2)),
            "{stats:?}"
        );
        let Kind::Inner(l, r) = tree.nodes[0].kind else { panic!("a leaf") };
        let (l, r) = (tree.nodes[l as usize].aabb, tree.nodes[r as usize].aabb);
        assert_eq!((l.max.x, r.max.x), (500.0, 1000.0));
    }
}
