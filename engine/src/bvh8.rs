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

#![expect(
    unsafe_code,
    reason = "AVX2 intrinsics for the node tests, prefetches, and uninitialised traversal stacks"
)]

use crate::math::gamma;
use glam::Vec3A;
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2};
use std::time::Duration;

/// Children per node.
pub const WIDTH: usize = 8;

/// An unused child slot.
const EMPTY: u32 = u32::MAX;
/// Set in a child reference that names a leaf.
const LEAF: u32 = 1 << 31;
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
    child: [u32; WIDTH],
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
fn leaf_range(c: u32) -> (u32, u32) {
    ((c & !LEAF) >> 3, (c & 7) + 1)
}

/// The 8-wide BVH. Node 0 is the root; children come after their parents.
#[derive(Clone, Debug, Default)]
pub struct Bvh8 {
    nodes: Vec<Node>,
    /// Bounds of everything.
    pub bounds: Aabb,
}

/// A ray prepared for box tests.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    o: [f32; 3],
    inv: [f32; 3],
    /// Per axis, the index in [`Node::planes`] of the near plane (the far one is `near ^ 1`).
    near: [usize; 3],
}

impl BoxRay {
    /// Prepares origin `o` and direction `d`. Direction components near zero are replaced by
    /// `+-1e-20` of their sign, so that `1/d` stays finite and `(lo - o) / d` cannot be NaN
    /// (coordinates are at most 1e15, products at most 1e35).
    /// The three axes at once (one vector division and compare).
    #[inline(always)]
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        let d = d + Vec3A::ZERO; // -0.0 -> +0.0: the sign test and 1/d then agree
        let tiny = Vec3A::splat(1e-20);
        let inv = Vec3A::ONE / Vec3A::select(d.abs().cmplt(tiny), tiny.copysign(d), d);
        let neg = inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        Self { o: o.to_array(), inv: inv.to_array(), near: [neg & 1, 2 + (neg >> 1 & 1), 4 + (neg >> 2 & 1)] }
    }
}

/// Widening of the box exit distance that covers the rounding of `(lo - o) * inv`.
const EXIT_SCALE: f32 = 1.0 + 2.0 * gamma(3);

/// Entry distances of the children the ray enters before `tmax`, and which ones they are.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn test_node(node: &Node, r: &BoxRay, tmax: f32) -> (u32, [f32; WIDTH]) {
    use std::arch::x86_64::*;
    // SAFETY: the loads read whole 32-byte-aligned lane arrays of `node` (the node is 64-byte
    // aligned, each array 32 bytes); AVX2 is enabled for the whole build.
    unsafe {
        let scale = _mm256_set1_ps(EXIT_SCALE);
        let mut n = [_mm256_setzero_ps(); 3];
        let mut f = n;
        for a in 0..3 {
            let (near, far) = (&node.planes[r.near[a]], &node.planes[r.near[a] ^ 1]);
            let (o, inv) = (_mm256_set1_ps(r.o[a]), _mm256_set1_ps(r.inv[a]));
            n[a] = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(near.as_ptr()), o), inv);
            f[a] = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(far.as_ptr()), o), inv);
        }
        // Never NaN: `inv` is finite and non-zero, box corners finite or infinite. Reduced as
        // trees (two levels, not three) to shorten the dependency chain.
        let tnear = _mm256_max_ps(_mm256_max_ps(n[0], n[1]), _mm256_max_ps(n[2], _mm256_setzero_ps()));
        let exit = _mm256_min_ps(_mm256_min_ps(f[0], f[1]), f[2]);
        let tfar = _mm256_min_ps(_mm256_mul_ps(exit, scale), _mm256_set1_ps(tmax));
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar)) as u32;
        let mut out = [0.0f32; WIDTH];
        _mm256_storeu_ps(out.as_mut_ptr(), tnear);
        (mask, out)
    }
}

/// [`test_node`] without AVX2, lane by lane.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn test_node(node: &Node, r: &BoxRay, tmax: f32) -> (u32, [f32; WIDTH]) {
    let mut tnear = [0.0f32; WIDTH];
    let mut tfar = [tmax; WIDTH];
    for a in 0..3 {
        let (near, far) = (&node.planes[r.near[a]], &node.planes[r.near[a] ^ 1]);
        for l in 0..WIDTH {
            tnear[l] = tnear[l].max((near[l] - r.o[a]) * r.inv[a]);
            tfar[l] = tfar[l].min((far[l] - r.o[a]) * r.inv[a] * EXIT_SCALE);
        }
    }
    let mut mask = 0u32;
    for l in 0..WIDTH {
        mask |= ((tnear[l] <= tfar[l]) as u32) << l;
    }
    (mask, tnear)
}

/// Asks for the four cache lines of the inner children in `mask` while the traversal sorts
/// them and finishes the current branch: on the 1M-triangle knot, where nodes come from L3,
/// bounce rays trace 7% faster to the closest hit and 12% faster to any hit (two of the four
/// lines: no gain). Leaf children go to `leaf(first, count)`, for the caller's own prefetch.
#[inline(always)]
fn prefetch_children(nodes: &[Node], node: &Node, mut mask: u32, leaf: &impl Fn(u32, u32)) {
    while mask != 0 {
        let c = node.child[mask.trailing_zeros() as usize & 7];
        mask &= mask - 1;
        if c & LEAF != 0 {
            let (first, count) = leaf_range(c);
            leaf(first, count);
        } else {
            let p = nodes.as_ptr().wrapping_add(c as usize).cast::<i8>();
            #[cfg(target_arch = "x86_64")]
            for line in 0..4 {
                // SAFETY: a prefetch is only a hint; it does not fault on any address.
                unsafe {
                    std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                        p.wrapping_add(64 * line),
                    )
                };
            }
        }
    }
}

/// Traversal stack depth: at most seven entries per level.
const STACK: usize = 8 * 64;

/// A fixed-size traversal stack left uninitialised: zeroing 4 KB per ray cost measurable time.
struct Stack<T: Copy> {
    items: [std::mem::MaybeUninit<T>; STACK],
    len: usize,
}

impl<T: Copy> Stack<T> {
    #[inline(always)]
    fn new() -> Self {
        Self { items: [const { std::mem::MaybeUninit::uninit() }; STACK], len: 0 }
    }

    #[inline(always)]
    fn push(&mut self, v: T) {
        // Bounds-checked: an overflow panics.
        self.items[self.len] = std::mem::MaybeUninit::new(v);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below `len` were written by `push`.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

impl Bvh8 {
    /// Builds a binary BVH over `aabbs` with obvhs and collapses it. `leaf` receives the
    /// indices (into `aabbs`) of each leaf's primitives, every subtree of at most `max_leaf`
    /// of them as one leaf, stores them as it likes and returns the `(first, count)` range
    /// (count 1..=8) that [`Self::closest`] and [`Self::any`] will hand back for that leaf.
    pub fn build(aabbs: &[Aabb], max_leaf: u32, leaf: impl FnMut(&[u32]) -> (u32, u32)) -> Self {
        assert!((1..=255).contains(&max_leaf));
        if aabbs.is_empty() {
            return Self::default();
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
        let bvh2 = obvhs::bvh2::builder::build_bvh2(aabbs, params, &mut Duration::default());
        Self::collapse(&bvh2, leaf)
    }

    /// Collapses a binary BVH: each node takes the two children of its binary counterpart and
    /// repeatedly opens the largest (by surface area) inner child until it has eight.
    pub fn collapse(bvh2: &Bvh2, mut leaf: impl FnMut(&[u32]) -> (u32, u32)) -> Self {
        let n2 = &bvh2.nodes;
        let mut out = Self { nodes: vec![Node::EMPTY], bounds: *n2[0].aabb() };
        // (binary node, wide node to fill)
        let mut todo = vec![(0usize, 0usize)];
        let mut leaf_ref = |i: usize| {
            let b = &n2[i];
            let prims =
                &bvh2.primitive_indices[b.first_index as usize..(b.first_index + b.prim_count) as usize];
            let (first, count) = leaf(prims);
            assert!(first <= MAX_FIRST && (1..=8).contains(&count), "leaf range {first}, {count}");
            LEAF | first << 3 | (count - 1)
        };
        while let Some((bi, wi)) = todo.pop() {
            let root = &n2[bi];
            if root.is_leaf() {
                // A tree that is one leaf: a root with one child.
                let c = leaf_ref(bi);
                out.nodes[wi].set_box(0, root.aabb());
                out.nodes[wi].child[0] = c;
                continue;
            }
            let mut kids = vec![root.first_index as usize, root.first_index as usize + 1];
            while kids.len() < WIDTH {
                let open = kids
                    .iter()
                    .enumerate()
                    .filter(|(_, k)| !n2[**k].is_leaf())
                    .max_by(|a, b| n2[*a.1].aabb().half_area().total_cmp(&n2[*b.1].aabb().half_area()));
                let Some((pos, &k)) = open else { break };
                kids.swap_remove(pos);
                kids.extend([n2[k].first_index as usize, n2[k].first_index as usize + 1]);
            }
            for (slot, &k) in kids.iter().enumerate() {
                out.nodes[wi].set_box(slot, n2[k].aabb());
                out.nodes[wi].child[slot] = if n2[k].is_leaf() {
                    leaf_ref(k)
                } else {
                    out.nodes.push(Node::EMPTY);
                    let w = out.nodes.len() - 1;
                    todo.push((k, w));
                    w as u32
                };
            }
        }
        out
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

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes held by the nodes.
    pub fn node_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
    }

    /// Closest-hit traversal of the ray `o + t d`, `t` in `(0, tmax)`. `leaf(first, count,
    /// best)` tests a leaf against the closest distance so far and returns the new closest
    /// (or `best` unchanged); the traversal returns the final closest.
    #[inline(always)]
    pub fn closest(&self, o: Vec3A, d: Vec3A, tmax: f32, leaf: impl FnMut(u32, u32, f32) -> f32) -> f32 {
        self.closest_prefetching(o, d, tmax, leaf, |_, _| {})
    }

    /// [`Self::closest`], calling `prefetch_leaf(first, count)` for each leaf the ray enters as
    /// soon as its parent is tested, so that the caller can ask for the leaf's data early.
    #[inline(always)]
    pub fn closest_prefetching(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        leaf: impl FnMut(u32, u32, f32) -> f32,
        prefetch_leaf: impl Fn(u32, u32),
    ) -> f32 {
        if self.nodes.is_empty() {
            return tmax;
        }
        self.closest_from(0, &BoxRay::new(o, d), tmax, leaf, prefetch_leaf)
    }

    /// [`Self::closest_prefetching`] from node (or leaf reference) `start` down.
    #[inline(always)]
    fn closest_from(
        &self,
        start: u32,
        r: &BoxRay,
        tmax: f32,
        mut leaf: impl FnMut(u32, u32, f32) -> f32,
        prefetch_leaf: impl Fn(u32, u32),
    ) -> f32 {
        let mut best = tmax;
        let mut stack = Stack::<(u32, f32)>::new();
        let mut cur = start;
        loop {
            if cur & LEAF != 0 {
                let (first, count) = leaf_range(cur);
                best = leaf(first, count, best);
            } else {
                let node = &self.nodes[cur as usize];
                let (mut mask, tnear) = test_node(node, r, best);
                prefetch_children(&self.nodes, node, mask, &prefetch_leaf);
                if mask != 0 {
                    let a = mask.trailing_zeros() as usize & 7;
                    mask &= mask - 1;
                    if mask == 0 {
                        cur = node.child[a];
                        continue;
                    }
                    let b = mask.trailing_zeros() as usize & 7;
                    mask &= mask - 1;
                    if mask == 0 {
                        // Push the farther, go to the nearer.
                        let (near, far) = if tnear[a] <= tnear[b] { (a, b) } else { (b, a) };
                        stack.push((node.child[far], tnear[far]));
                        cur = node.child[near];
                        continue;
                    }
                    // Sort the hit children far to near, push all but the nearest.
                    let mut keys = [0u64; WIDTH];
                    let key = |s: usize| (tnear[s].to_bits() as u64) << 32 | s as u64;
                    let (ka, kb) = (key(a), key(b));
                    (keys[0], keys[1]) = if ka > kb { (ka, kb) } else { (kb, ka) };
                    let mut n = 2;
                    while mask != 0 {
                        let s = mask.trailing_zeros() as usize & 7;
                        mask &= mask - 1;
                        let key = key(s);
                        let mut j = n;
                        while j > 0 && keys[j - 1] < key {
                            keys[j] = keys[j - 1];
                            j -= 1;
                        }
                        keys[j] = key;
                        n += 1;
                    }
                    for &k in &keys[..n - 1] {
                        let s = (k & 7) as usize;
                        stack.push((node.child[s], tnear[s]));
                    }
                    cur = node.child[(keys[n - 1] & 7) as usize];
                    continue;
                }
            }
            // Pop the nearest entry still closer than the best hit.
            loop {
                let Some((c, t)) = stack.pop() else { return best };
                if t <= best {
                    cur = c;
                    break;
                }
            }
        }
    }

    /// Any-hit traversal: true when `leaf(first, count)` reports a hit for some leaf the ray
    /// `o + t d`, `t` in `(0, tmax)`, enters.
    #[inline(always)]
    pub fn any(&self, o: Vec3A, d: Vec3A, tmax: f32, leaf: impl FnMut(u32, u32) -> bool) -> bool {
        self.any_prefetching(o, d, tmax, leaf, |_, _| {})
    }

    /// [`Self::any`] with `prefetch_leaf` as in [`Self::closest_prefetching`].
    #[inline(always)]
    pub fn any_prefetching(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        leaf: impl FnMut(u32, u32) -> bool,
        prefetch_leaf: impl Fn(u32, u32),
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        self.any_from(0, &BoxRay::new(o, d), tmax, leaf, prefetch_leaf)
    }

    /// [`Self::any_prefetching`] from node (or leaf reference) `start` down.
    #[inline(always)]
    fn any_from(
        &self,
        start: u32,
        r: &BoxRay,
        tmax: f32,
        mut leaf: impl FnMut(u32, u32) -> bool,
        prefetch_leaf: impl Fn(u32, u32),
    ) -> bool {
        let mut stack = Stack::<u32>::new();
        let mut cur = start;
        loop {
            if cur & LEAF != 0 {
                let (first, count) = leaf_range(cur);
                if leaf(first, count) {
                    return true;
                }
            } else {
                let node = &self.nodes[cur as usize];
                let (mut mask, _) = test_node(node, r, tmax);
                prefetch_children(&self.nodes, node, mask, &prefetch_leaf);
                while mask != 0 {
                    let s = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    stack.push(node.child[s]);
                }
            }
            let Some(c) = stack.pop() else { return false };
            cur = c;
        }
    }
}

/// Rays traced together by [`Bvh8::closest_packet`] and [`Bvh8::any_packet`].
pub const PACKET: usize = 16;

/// A packet's subtree entered by at most this many of its rays is traced ray by ray (2 and 4
/// gave the same rates on spheres-sky).
const SOLO: u32 = 4;

/// Ray `l` of a packet, prepared alone.
#[inline(always)]
fn lane_ray(o: &[[f32; PACKET]; 3], d: &[[f32; PACKET]; 3], l: usize) -> BoxRay {
    BoxRay::new(Vec3A::new(o[0][l], o[1][l], o[2][l]), Vec3A::new(d[0][l], d[1][l], d[2][l]))
}

/// A packet's rays prepared for box tests, lane by lane as [`BoxRay::new`] prepares one.
struct PacketRays<'a> {
    o: &'a [[f32; PACKET]; 3],
    inv: [[f32; PACKET]; 3],
    neg: [[bool; PACKET]; 3],
}

impl<'a> PacketRays<'a> {
    #[inline(always)]
    fn new(o: &'a [[f32; PACKET]; 3], d: &[[f32; PACKET]; 3]) -> Self {
        let (mut inv, mut neg) = ([[0.0f32; PACKET]; 3], [[false; PACKET]; 3]);
        for a in 0..3 {
            for l in 0..PACKET {
                let x = d[a][l] + 0.0;
                let x = if x.abs() < 1e-20 { 1e-20f32.copysign(x) } else { x };
                inv[a][l] = 1.0 / x;
                neg[a][l] = inv[a][l] < 0.0;
            }
        }
        Self { o, inv, neg }
    }

    /// Child `c` of `node` against every ray, with the numbers of `test_node`: the entry
    /// distances and the bit mask of the rays that enter the box before their `tmax`.
    #[inline(always)]
    fn enter(&self, node: &Node, c: usize, tmax: &[f32; PACKET]) -> ([f32; PACKET], u32) {
        let (o, inv, neg) = (self.o, &self.inv, &self.neg);
        let mut tnear = [0.0f32; PACKET];
        let mut hit = [false; PACKET];
        for l in 0..PACKET {
            let mut near = [0.0f32; 3];
            let mut far = [0.0f32; 3];
            for a in 0..3 {
                let (lo, hi) = (node.planes[2 * a][c], node.planes[2 * a + 1][c]);
                let (pn, pf) = if neg[a][l] { (hi, lo) } else { (lo, hi) };
                near[a] = (pn - o[a][l]) * inv[a][l];
                far[a] = (pf - o[a][l]) * inv[a][l];
            }
            // The operations and order of `test_node`.
            tnear[l] = near[0].max(near[1]).max(near[2].max(0.0));
            let exit = far[0].min(far[1]).min(far[2]);
            hit[l] = tnear[l] <= (exit * EXIT_SCALE).min(tmax[l]);
        }
        (tnear, crate::simd::mask16(&hit))
    }
}

impl Bvh8 {
    /// Closest hits of [`PACKET`] rays `o + t d` traced together: for rays that start close
    /// together and point the same way (the samples of one pixel), each node is read once for
    /// all of them and tested against every ray still active, in loops over the rays that
    /// vectorise (in a [`crate::simd::lanes`] region, 16 rays per AVX-512 vector). `best[l]`
    /// holds ray `l`'s `tmax` on entry and its closest distance on return; `leaf(first, count,
    /// active, best)` tests a leaf against the rays in the bit mask `active` and lowers their
    /// `best`.
    ///
    /// A subtree that at most four of the packet's rays enter is traced ray by ray (a node's
    /// eight children tested at once, as [`Self::closest`] does), after Benthin et al.,
    /// "Combining Single and Packet-Ray Tracing for Arbitrary Ray Distributions on the Intel MIC
    /// Architecture" (IEEE TVCG 2012): bounce rays part ways after a few levels, and spheres-sky's
    /// closest hits ran 9% faster, its shadow rays 6%.
    ///
    /// Every ray gets the result of [`Self::closest`]: a box test computes the same numbers
    /// (each ray's near plane chosen by the sign of its direction, the exit widened alike), and
    /// a box is skipped only when it lies beyond the ray's closest hit so far; only the order
    /// of the leaves differs, which matters for exact ties alone.
    #[inline(always)]
    pub fn closest_packet(
        &self,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
        best: &mut [f32; PACKET],
        mut leaf: impl FnMut(u32, u32, u32, &mut [f32; PACKET]),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let r = PacketRays::new(o, d);
        let all = (1u32 << PACKET) - 1;
        // Entries: a node, the rays that enter it and their entry distances (a ray whose
        // closest hit has come nearer by the time the entry is taken leaves it).
        let mut stack = Stack::<(u32, u32, [f32; PACKET])>::new();
        let (mut cur, mut active) = (0u32, all);
        loop {
            if cur & LEAF != 0 {
                let (first, count) = leaf_range(cur);
                leaf(first, count, active, best);
            } else if active.count_ones() <= SOLO {
                // Few rays left in this subtree: each goes on alone, testing a node's children
                // at once rather than each child against the whole packet.
                let mut m = active;
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let start = best[l];
                    let one = |first, count, _| {
                        leaf(first, count, 1 << l, best);
                        best[l]
                    };
                    self.closest_from(cur, &lane_ray(o, d, l), start, one, |_, _| {});
                }
            } else {
                let node = &self.nodes[cur as usize];
                // Per child: the rays that enter it and, for ordering, the entry distance of
                // the first active ray.
                let lead = active.trailing_zeros() as usize;
                let (mut masks, mut keys, mut n) = ([0u32; WIDTH], [0u64; WIDTH], 0);
                let mut entry = [[0.0f32; PACKET]; WIDTH];
                for c in 0..WIDTH {
                    if node.child[c] == EMPTY {
                        continue;
                    }
                    let (tnear, m) = r.enter(node, c, best);
                    let m = m & active;
                    if m != 0 {
                        let t = if m >> lead & 1 != 0 { tnear[lead] } else { f32::INFINITY };
                        masks[n] = m;
                        keys[n] = (t.to_bits() as u64) << 32 | c as u64;
                        entry[c] = tnear;
                        n += 1;
                    }
                }
                if n > 0 {
                    // Far to near by the first ray's entry, then all but the nearest pushed.
                    let (keys, masks) = (&mut keys[..n], &mut masks[..n]);
                    for i in 1..n {
                        let mut j = i;
                        while j > 0 && keys[j - 1] < keys[j] {
                            keys.swap(j - 1, j);
                            masks.swap(j - 1, j);
                            j -= 1;
                        }
                    }
                    for i in 0..n - 1 {
                        let c = (keys[i] & 7) as usize;
                        stack.push((node.child[c], masks[i], entry[c]));
                    }
                    (cur, active) = (node.child[(keys[n - 1] & 7) as usize], masks[n - 1]);
                    continue;
                }
            }
            // Take the next entry that some ray still enters before its closest hit.
            loop {
                let Some((c, m, tnear)) = stack.pop() else { return };
                let mut still = [false; PACKET];
                for l in 0..PACKET {
                    still[l] = tnear[l] <= best[l];
                }
                let still = crate::simd::mask16(&still);
                if m & still != 0 {
                    (cur, active) = (c, m & still);
                    break;
                }
            }
        }
    }

    /// Any hits of [`PACKET`] rays `o + t d`, `t` in `(0, tmax[l])`, traced together (see
    /// [`Self::closest_packet`]): returns the bit mask of the rays for which `leaf(first, count,
    /// active)` reported a hit (its result: a mask among `active`) in some leaf they enter. Each
    /// ray gets the answer of [`Self::any`]; a ray that has one leaves the packet.
    #[inline(always)]
    pub fn any_packet(
        &self,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
        tmax: &[f32; PACKET],
        mut leaf: impl FnMut(u32, u32, u32) -> u32,
    ) -> u32 {
        if self.nodes.is_empty() {
            return 0;
        }
        let r = PacketRays::new(o, d);
        let mut done = 0u32;
        let mut stack = Stack::<(u32, u32)>::new();
        let (mut cur, mut active) = (0u32, (1u32 << PACKET) - 1);
        loop {
            if cur & LEAF != 0 {
                let (first, count) = leaf_range(cur);
                done |= leaf(first, count, active) & active;
            } else if active.count_ones() <= SOLO {
                // Few rays left in this subtree: each goes on alone (see `closest_packet`).
                let mut m = active;
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let one = |first, count| leaf(first, count, 1 << l) & 1 << l != 0;
                    if self.any_from(cur, &lane_ray(o, d, l), tmax[l], one, |_, _| {}) {
                        done |= 1 << l;
                    }
                }
            } else {
                let node = &self.nodes[cur as usize];
                for c in 0..WIDTH {
                    if node.child[c] == EMPTY {
                        continue;
                    }
                    let m = r.enter(node, c, tmax).1 & active;
                    if m != 0 {
                        stack.push((node.child[c], m));
                    }
                }
            }
            loop {
                let Some((c, m)) = stack.pop() else { return done };
                if m & !done != 0 {
                    (cur, active) = (c, m & !done);
                    break;
                }
            }
        }
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
            bvh.refit(|first, count| {
                order[first as usize..(first + count) as usize]
                    .iter()
                    .fold(Aabb::empty(), |a, &i| a.union(&aabbs[i as usize]))
            });
            assert!(bvh.sah_cost() >= before * 0.9);
        }
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
}
