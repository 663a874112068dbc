//! A light tree: a binary BVH over the lights that have bounds (emitting primitives, point,
//! spot and projector lights), walked from a shading point down to one light, each step
//! choosing a child by an importance that bounds what the child's lights can send to the
//! point (pbrt-v4's `BVHLightSampler` and `LightBounds`, after Conty Estevez and Kulla 2018,
//! "Importance Sampling of Many Lights with Adaptive Tree Splitting"; Cycles' light tree
//! is the same idea). Lights at infinity stay outside the tree: the light table chooses them
//! first, each with the share pbrt-v4's `pInfinite` gives it.
//!
//! The importance takes the shading normal at a surface (pbrt-v4's `cos theta_i` bound) and
//! none in a medium (zero); a path keeps its vertex's normal beside its point for the density
//! of the next hit's emitter, so that the choice and its probability are one function.
//!
//! A light that moves while the shutter is open is bounded by its box swept over the shutter
//! (`LightInputs::shutter`): the choice cannot depend on a path's time, or the density of an
//! emitter hit would have to know it.

use crate::math::{acos, cos_sin_turn};
use glam::Vec3A;
use std::f32::consts::{FRAC_PI_2, PI};

/// What a light, or a set of lights, can send, as pbrt-v4's `LightBounds`: a box holding
/// them, their power, and a cone holding their normals (axis `w`, half angle `theta_o`)
/// beyond which light leaves within `theta_e` (a surface's `pi / 2`, a point light's `pi /
/// 2` around the whole sphere of `theta_o = pi`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// The box's low corner.
    pub lo: Vec3A,
    /// Its high corner.
    pub hi: Vec3A,
    /// Power, in the light table's unit (luminance times area for a surface).
    pub phi: f32,
    /// Unit axis of the cone of normals.
    pub w: Vec3A,
    /// Cosine of the cone's half angle.
    pub cos_theta_o: f32,
    /// Cosine of the angle beyond the normals within which light leaves.
    pub cos_theta_e: f32,
    /// Whether light leaves both sides of the normals (a two-sided emitter).
    pub two_sided: bool,
}

/// `cos(a - b)` given the sines and cosines, 1 where `a < b` (pbrt-v4's `cosSubClamped`).
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
}

/// `sin(a - b)`, 0 where `a < b` (pbrt-v4's `sinSubClamped`).
#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
}

/// `sqrt(1 - c^2)`, 0 where rounding makes `|c|` exceed 1.
#[inline]
fn sin_of(c: f32) -> f32 {
    (1.0 - c * c).max(0.0).sqrt()
}

/// `cos(x)` with the same bits on every machine ([`cos_sin_turn`] of the reduced turn).
fn cos(x: f32) -> f32 {
    let t = x as f64 / std::f64::consts::TAU;
    cos_sin_turn((t - t.floor()) as f32).0
}

impl LightBounds {
    /// The box's centre.
    #[inline]
    fn centroid(&self) -> Vec3A {
        (self.lo + self.hi) * 0.5
    }

    /// Bounds of the lights of both (pbrt-v4's `Union` of `LightBounds`): the boxes' union, the
    /// powers' sum, the cone holding both cones, the smaller spread `cos_theta_e`.
    pub fn union(&self, b: &LightBounds) -> LightBounds {
        let (w, cos_theta_o) = cone_union((self.w, self.cos_theta_o), (b.w, b.cos_theta_o));
        LightBounds {
            lo: self.lo.min(b.lo),
            hi: self.hi.max(b.hi),
            phi: self.phi + b.phi,
            w,
            cos_theta_o,
            cos_theta_e: self.cos_theta_e.min(b.cos_theta_e),
            two_sided: self.two_sided | b.two_sided,
        }
    }

    /// pbrt-v4's `EvaluateCost` of a child with these bounds, split along `dim` of the parent's
    /// box `lo..hi`: power times the solid angle measure of the cones times the box's surface
    /// area, times the parent's longest side over its side along `dim`.
    fn cost(&self, lo: Vec3A, hi: Vec3A, dim: usize) -> f32 {
        let (theta_o, theta_e) = (acos(self.cos_theta_o), acos(self.cos_theta_e));
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = sin_of(self.cos_theta_o);
        let m_omega = 2.0 * PI * (1.0 - self.cos_theta_o)
            + FRAC_PI_2
                * (2.0 * theta_w * sin_o - cos(theta_o - 2.0 * theta_w) - 2.0 * theta_o * sin_o
                    + self.cos_theta_o);
        let diag = hi - lo;
        let kr = diag.max_element() / diag[dim];
        let d = self.hi - self.lo;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        self.phi * m_omega * kr * area
    }
}

/// The cone holding the cones `a` and `b` (axis, cosine of the half angle; pbrt-v4's `Union`
/// of `DirectionCone`s).
fn cone_union(a: (Vec3A, f32), b: (Vec3A, f32)) -> (Vec3A, f32) {
    let (theta_a, theta_b) = (acos(a.1.clamp(-1.0, 1.0)), acos(b.1.clamp(-1.0, 1.0)));
    let theta_d = acos(a.0.dot(b.0).clamp(-1.0, 1.0));
    // One inside the other.
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = (theta_a + theta_d + theta_b) * 0.5;
    let whole = (Vec3A::Z, -1.0);
    if theta_o >= PI {
        return whole;
    }
    // Rotate a's axis towards b's by theta_o - theta_a about their common normal.
    let Some(k) = crate::math::unit(a.0.cross(b.0)) else { return whole };
    let (c, s) = cos_sin_turn((theta_o - theta_a) / std::f32::consts::TAU);
    let w = (a.0 * c + k.cross(a.0) * s).normalize();
    (w, cos(theta_o))
}

/// [`LightBounds`] as the importance reads them, with what depends on the bounds alone
/// computed once: the box's centre, half its diagonal's length, its bounding sphere's squared
/// radius, the sine of `theta_o`.
#[derive(Clone, Copy, Debug)]
struct Cone {
    center: Vec3A,
    w: Vec3A,
    half_diagonal: f32,
    r2: f32,
    /// Its radius.
    r: f32,
    phi: f32,
    cos_theta_o: f32,
    sin_theta_o: f32,
    cos_theta_e: f32,
    two_sided: bool,
}

impl From<&LightBounds> for Cone {
    fn from(b: &LightBounds) -> Self {
        let center = b.centroid();
        Cone {
            center,
            w: b.w,
            half_diagonal: (b.hi - b.lo).length() * 0.5,
            r2: (b.hi - center).length_squared(),
            r: (b.hi - center).length_squared().sqrt(),
            phi: b.phi,
            cos_theta_o: b.cos_theta_o,
            sin_theta_o: sin_of(b.cos_theta_o),
            cos_theta_e: b.cos_theta_e,
            two_sided: b.two_sided,
        }
    }
}

impl Cone {
    /// A bound on what the lights send to the point `p` of normal `n` (zero: none; pbrt-v4's
    /// `LightBounds::Importance`): the power over the squared distance to the box's centre (at
    /// least half the box's diagonal, as pbrt-v4 clamps it), times the cosine of the smallest
    /// angle between a direction from the box to `p` and a direction the lights emit in, times
    /// (with a normal) the cosine of the smallest angle between a direction to the box and the
    /// normal's line; 0 where no light of the box can reach `p`.
    #[inline]
    fn importance(&self, p: Vec3A, n: Vec3A) -> f32 {
        self.importance_at(p.to_array(), n.to_array())
    }

    /// [`Self::importance`] on plain numbers, every branch a select and the operations in a
    /// fixed order: a loop of it over lanes vectorises and gives each lane the scalar call's
    /// bits ([`LightTree::importance_lanes`]).
    #[inline(always)]
    fn importance_at(&self, p: [f32; 3], n: [f32; 3]) -> f32 {
        let c = self.center;
        let d = [p[0] - c.x, p[1] - c.y, p[2] - c.z];
        let d2_true = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let d2 = d2_true.max(self.half_diagonal);
        // The unit direction from the box's centre to `p` (zero at the centre).
        let inv = 1.0 / d2_true.sqrt();
        let inv = if inv.is_finite() { inv } else { 0.0 };
        let wi = [d[0] * inv, d[1] * inv, d[2] * inv];
        // The angle between the cone's axis and the direction from the box to `p`.
        let cos_w = self.w.x * wi[0] + self.w.y * wi[1] + self.w.z * wi[2];
        let cos_w = if self.two_sided { cos_w.abs() } else { cos_w };
        let sin_w = sin_of(cos_w);
        // The half angle the box subtends from `p` (its bounding sphere's; all directions from
        // inside it).
        // (sin_b = r / d, cos_b = sqrt(1 - sin_b^2): one root fewer than both from cos_b.)
        let inside = d2_true < self.r2;
        let sin_b = if inside { 0.0 } else { (self.r * inv).min(1.0) };
        let cos_b = if inside { -1.0 } else { sin_of(sin_b) };
        // theta' = max(0, theta_w - theta_o - theta_b).
        let (cos_o, sin_o) = (self.cos_theta_o, self.sin_theta_o);
        let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, cos_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, cos_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        let importance = self.phi * cos_p / d2;
        let cos_i = (wi[0] * n[0] + wi[1] * n[1] + wi[2] * n[2]).abs();
        let facing = importance * cos_sub_clamped(sin_of(cos_i), cos_i, sin_b, cos_b);
        let in_medium = n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0;
        let importance = if in_medium { importance } else { facing };
        if cos_p <= self.cos_theta_e { 0.0 } else { importance.max(0.0) }
    }
}

/// A node of the tree as plain data: an inner node's first child follows it, its second is at
/// `index`; a leaf's light is `index`.
#[derive(Clone, Copy, Debug)]
struct Node {
    cone: Cone,
    index: u32,
    leaf: bool,
}

/// The tree over the bounded lights, stored flat; over at most [`FEW_LIGHTS`] lights, the
/// leaves alone (`few`).
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// Per light (the table's index), the way down to its leaf: bit `d` set where the walk
    /// takes the second child at depth `d` (pbrt-v4's bit trail); with few lights, its leaf's
    /// index.
    trail: Vec<u64>,
    /// Whether the nodes are the leaves alone: a pick weighs every light by its own importance
    /// at the point, one importance per light, across lanes where the points come in lanes
    /// ([`Self::importances_lanes`]), where the walk takes two per level, one point at a time,
    /// and weighs a light by its cluster's bounds.
    few: bool,
}

/// The most lights a tree holds as its leaves alone. A Cornell box under six ceiling panels
/// (benches/results/sampling.md, "A few lights"): the walk took 1.3-1.8x the table's time per
/// sample, the leaves alone across lanes 1.1x, for 0.63x its variance. Above 8 the walk is
/// kept (where the leaves alone stop paying was not measured).
pub const FEW_LIGHTS: usize = 8;

/// Buckets per axis in the build's split search (pbrt-v4's 12).
const BUCKETS: usize = 12;

/// Depth after which the build splits at the median (so that trails fit 64 bits: a balanced
/// split of 2^32 lights takes 32 more levels).
const SAH_DEPTH: u32 = 32;

impl LightTree {
    /// Builds the tree over `lights` (the table's light index and bounds of each, at least
    /// one); `count` is the table's number of lights.
    pub fn build(lights: &[(u32, LightBounds)], count: usize) -> Self {
        assert!(!lights.is_empty(), "a light tree needs a light");
        let mut tree =
            LightTree { nodes: Vec::with_capacity(2 * lights.len()), trail: vec![0; count], few: false };
        if lights.len() <= FEW_LIGHTS {
            for (k, (light, bounds)) in lights.iter().enumerate() {
                tree.nodes.push(Node { cone: Cone::from(bounds), index: *light, leaf: true });
                tree.trail[*light as usize] = k as u64;
            }
            tree.few = true;
            return tree;
        }
        let mut lights = lights.to_vec();
        tree.build_node(&mut lights, 0, 0);
        tree
    }

    /// Builds the subtree over `lights`, reached by `trail` at `depth`, as pbrt-v4's
    /// `buildBVH`: the split of least cost among 12 buckets of the centroids along each axis
    /// (both sides non-empty), else at the median of the centroids along the widest axis.
    /// Returns the subtree's bounds.
    fn build_node(&mut self, lights: &mut [(u32, LightBounds)], trail: u64, depth: u32) -> LightBounds {
        if let [(light, bounds)] = *lights {
            self.nodes.push(Node { cone: Cone::from(&bounds), index: light, leaf: true });
            self.trail[light as usize] = trail;
            return bounds;
        }
        let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        let (mut clo, mut chi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        for (_, b) in lights.iter() {
            (lo, hi) = (lo.min(b.lo), hi.max(b.hi));
            (clo, chi) = (clo.min(b.centroid()), chi.max(b.centroid()));
        }
        let bucket = |b: &LightBounds, dim: usize| {
            let t = (b.centroid()[dim] - clo[dim]) / (chi[dim] - clo[dim]);
            ((BUCKETS as f32 * t) as usize).min(BUCKETS - 1)
        };
        let mut best: Option<(f32, usize, usize)> = None;
        for dim in (0..3).filter(|&d| depth < SAH_DEPTH && chi[d] > clo[d]) {
            let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
            for (_, b) in lights.iter() {
                let k = bucket(b, dim);
                buckets[k] = Some(buckets[k].map_or(*b, |a| a.union(b)));
            }
            let merge = |bs: &[Option<LightBounds>]| {
                bs.iter()
                    .flatten()
                    .fold(None, |acc: Option<LightBounds>, b| Some(acc.map_or(*b, |a| a.union(b))))
            };
            for split in 0..BUCKETS - 1 {
                let (Some(b0), Some(b1)) = (merge(&buckets[..=split]), merge(&buckets[split + 1..])) else {
                    continue;
                };
                let cost = b0.cost(lo, hi, dim) + b1.cost(lo, hi, dim);
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, dim, split));
                }
            }
        }
        let mid = match best {
            Some((_, dim, split)) => partition(lights, |b| bucket(b, dim) <= split),
            None => {
                let dim = (chi - clo).max_position();
                let mid = lights.len() / 2;
                lights.select_nth_unstable_by(mid, |a, b| {
                    a.1.centroid()[dim].total_cmp(&b.1.centroid()[dim]).then(a.0.cmp(&b.0))
                });
                mid
            }
        };
        let at = self.nodes.len();
        self.nodes.push(Node { cone: Cone::from(&lights[0].1), index: 0, leaf: false });
        let (first, second) = lights.split_at_mut(mid);
        let b0 = self.build_node(first, trail, depth + 1);
        self.nodes[at].index = self.nodes.len() as u32;
        let b1 = self.build_node(second, trail | 1 << depth, depth + 1);
        let bounds = b0.union(&b1);
        self.nodes[at].cone = Cone::from(&bounds);
        bounds
    }

    /// The importances of the children of the inner node `at` seen from `p` (normal `n`).
    #[inline]
    fn children(&self, at: usize, p: Vec3A, n: Vec3A) -> [f32; 2] {
        let second = self.nodes[at].index as usize;
        [self.nodes[at + 1].cone.importance(p, n), self.nodes[second].cone.importance(p, n)]
    }

    /// Picks a light for the point `p` of normal `n` (zero: none) with `u` in [0, 1): (light,
    /// probability), the probability 0 (and the light meaningless) where no light of the tree
    /// can reach `p`.
    #[inline]
    pub fn pick(&self, mut u: f32, p: Vec3A, n: Vec3A) -> (u32, f32) {
        if self.few {
            // One lane of the lanes' choice: the same operations, so the same bits.
            let mut importance = [[0.0; 1]; FEW_LIGHTS];
            let (p, n) = (p.to_array().map(|c| [c]), n.to_array().map(|c| [c]));
            self.importances_lanes(&p, &n, &mut importance);
            let (k, pmf) = choose_lanes(&importance, self.nodes.len(), &[u]);
            return (self.nodes[k[0] as usize].index, pmf[0]);
        }
        let (mut at, mut pmf) = (0, 1.0f32);
        loop {
            let node = &self.nodes[at];
            if node.leaf {
                return (node.index, pmf);
            }
            let c = self.children(at, p, n);
            let sum = c[0] + c[1];
            if !(sum > 0.0) {
                // The first light below (an inner node's first child follows it).
                let leaf = at + self.nodes[at..].iter().position(|n| n.leaf).unwrap_or(0);
                return (self.nodes[leaf].index, 0.0);
            }
            let p0 = c[0] / sum;
            if u < p0 {
                (at, pmf, u) = (at + 1, pmf * (c[0] / sum), u / p0);
            } else {
                (at, pmf, u) = (node.index as usize, pmf * (c[1] / sum), (u - p0) / (1.0 - p0));
            }
            u = u.min(1.0 - f32::EPSILON / 2.0);
        }
    }

    /// The probability that [`Self::pick`] picks `light` for the point `p` of normal `n`
    /// (pbrt-v4's `PMF`): the same products along the light's trail, so the same bits.
    #[inline]
    pub fn pmf(&self, light: u32, p: Vec3A, n: Vec3A) -> f32 {
        if self.few {
            // The sum in `choose_lanes`'s order.
            let (mut sum, mut own) = (0.0, 0.0);
            for (k, node) in self.nodes.iter().enumerate() {
                let i = node.cone.importance(p, n);
                sum += i;
                own = if k as u64 == self.trail[light as usize] { i } else { own };
            }
            return if sum > 0.0 { own / sum } else { 0.0 };
        }
        let (mut at, mut pmf, mut trail) = (0, 1.0f32, self.trail[light as usize]);
        loop {
            let node = &self.nodes[at];
            if node.leaf {
                return pmf;
            }
            let c = self.children(at, p, n);
            let sum = c[0] + c[1];
            if !(sum > 0.0) {
                return 0.0;
            }
            let second = trail & 1 == 1;
            pmf *= c[second as usize] / sum;
            at = if second { node.index as usize } else { at + 1 };
            trail >>= 1;
        }
    }

    /// How many lights it holds as leaves alone ([`FEW_LIGHTS`]), if it does: then
    /// [`Self::importances_lanes`] and [`choose_lanes`] pick for points in lanes.
    #[inline]
    pub fn few(&self) -> Option<usize> {
        self.few.then_some(self.nodes.len())
    }

    /// With few lights, the importance of each leaf (`[k][lane]`, the first [`Self::few`]
    /// rows) at the points `p` of normals `n` in lanes: the bits [`Self::pick`] computes for
    /// each point.
    #[inline]
    pub fn importances_lanes<const N: usize>(
        &self,
        p: &[[f32; N]; 3],
        n: &[[f32; N]; 3],
        out: &mut [[f32; N]; FEW_LIGHTS],
    ) {
        for (row, node) in out.iter_mut().zip(&self.nodes) {
            let cone = &node.cone;
            for l in 0..N {
                row[l] = cone.importance_at([p[0][l], p[1][l], p[2][l]], [n[0][l], n[1][l], n[2][l]]);
            }
        }
    }

    /// A bound on what all its lights send to the point `p` of normal `n`: with few lights,
    /// the sum of their importances in [`choose_lanes`]'s order (the bits of one lane of
    /// [`Self::importances_lanes`] summed as [`importance_sums`] sums them); else the root's.
    #[inline]
    pub fn importance_total(&self, p: Vec3A, n: Vec3A) -> f32 {
        if self.few {
            let mut importance = [[0.0; 1]; FEW_LIGHTS];
            let (p, n) = (p.to_array().map(|c| [c]), n.to_array().map(|c| [c]));
            self.importances_lanes(&p, &n, &mut importance);
            return importance_sums(&importance, self.nodes.len())[0];
        }
        self.nodes[0].cone.importance(p, n)
    }

    /// The light of leaf `k` (with few lights).
    #[inline]
    pub fn leaf_light(&self, k: usize) -> u32 {
        self.nodes[k].index
    }

    /// How many nodes it has.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether it has none.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// The sum of each lane's importances `importance[..few][l]`, in row order: the sum
/// [`choose_lanes`] divides by.
#[inline]
pub fn importance_sums<const N: usize>(importance: &[[f32; N]; FEW_LIGHTS], few: usize) -> [f32; N] {
    let mut sum = [0.0f32; N];
    for row in &importance[..few] {
        for l in 0..N {
            sum[l] += row[l];
        }
    }
    sum
}

/// Chooses, for each lane `l`, one of the lights of importances `importance[..few][l]` with
/// `u[l]` in [0, 1): its index and its importance over their sum; the probability 0 (the index
/// meaningless) where all are 0. The light is the first whose running sum exceeds `u` times
/// the sum (so one of some importance): the count of running sums at or below it, without
/// branches (32-bit indices and masks: selects of 64-bit indices or of kept values compiled
/// to branches). One lane ([`LightTree::pick`]) gives the bits of many.
#[inline]
pub fn choose_lanes<const N: usize>(
    importance: &[[f32; N]; FEW_LIGHTS],
    few: usize,
    u: &[f32; N],
) -> ([u32; N], [f32; N]) {
    let rows = &importance[..few];
    let sum = importance_sums(importance, few);
    let (mut acc, mut below, mut last) = ([0.0f32; N], [0u32; N], [0u32; N]);
    for (k, row) in rows.iter().enumerate() {
        for l in 0..N {
            acc[l] += row[l];
            below[l] += (acc[l] <= u[l] * sum[l]) as u32;
            last[l] = if row[l] > 0.0 { k as u32 } else { last[l] };
        }
    }
    for l in 0..N {
        below[l] = if below[l] < few as u32 { below[l] } else { last[l] };
    }
    // The chosen light's importance, then its probability.
    let mut pmf = [0.0f32; N];
    for (k, row) in rows.iter().enumerate() {
        for l in 0..N {
            // A sum of one term, each term masked by its bits: selects compile to branches.
            let mask = 0u32.wrapping_sub((below[l] == k as u32) as u32);
            pmf[l] += f32::from_bits(row[l].to_bits() & mask);
        }
    }
    for l in 0..N {
        pmf[l] /= sum[l];
    }
    for l in 0..N {
        let none = !(sum[l] > 0.0);
        (below[l], pmf[l]) = if none { (0, 0.0) } else { (below[l], pmf[l]) };
    }
    (below, pmf)
}

/// Moves the lights that `first` holds for ahead of the others; returns how many there are,
/// or half the lights where that leaves a side empty.
fn partition(lights: &mut [(u32, LightBounds)], first: impl Fn(&LightBounds) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..lights.len() {
        if first(&lights[i].1) {
            lights.swap(i, mid);
            mid += 1;
        }
    }
    if mid == 0 || mid == lights.len() { lights.len() / 2 } else { mid }
}

/// How next-event estimation chooses the light to sample ([`crate::lighting::lights`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
pub enum LightSamplerKind {
    /// From a table fixed for the scene, by power and evenly among objects.
    Power,
    /// By the light tree ([`crate::lighting::tree`]): each shading point weighs the lights by
    /// what they can send it (lights at infinity keep their shares).
    Tree,
    /// The tree where the scene has more than [`crate::lighting::lights::TREE_MIN_LIGHTS`]
    /// light with bounds (two or more), else the table.
    #[default]
    Auto,
}

impl LightSamplerKind {
    /// The names, as the command line spells them.
    pub const NAMES: [(&'static str, LightSamplerKind); 3] = [
        ("power", LightSamplerKind::Power),
        ("tree", LightSamplerKind::Tree),
        ("auto", LightSamplerKind::Auto),
    ];
}

impl std::str::FromStr for LightSamplerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        crate::format::by_name(&Self::NAMES, s, "light sampler")
    }
}

#[cfg(test)]
mod tests {
    use super::LightSamplerKind;
    use crate::accel::geometry::Geometry;
    use crate::lighting::area::AreaEmission;
    use crate::lighting::lights::{
        BackgroundSampling, LightInputs, LightTable, OtherLight, PunctualLight, SpotFalloff,
    };
    use crate::material::chi2::chi2_critical;
    use crate::shape::{Disk, Primitive, Quad, Sphere, Triangle};
    use crate::texture::Textures;
    use glam::{Vec3, Vec3A};

    /// A table choosing by the tree among lights of every kind with bounds: quads facing up
    /// and down (one-sided and two-sided), spheres, triangles, a disk, point, spot and
    /// projector lights, with a directional light and the environment at infinity.
    fn many_lights() -> (Geometry, LightTable) {
        let (geo, table) = lights_of_every_kind(40, 20, 30);
        assert_eq!(table.tree.as_ref().unwrap().few(), None);
        (geo, table)
    }

    /// [`many_lights`] with two quads, a sphere and a triangle: eight lights with bounds,
    /// which the tree holds as leaves alone.
    fn few_lights() -> (Geometry, LightTable) {
        let (geo, table) = lights_of_every_kind(2, 1, 1);
        assert_eq!(table.tree.as_ref().unwrap().few(), Some(8));
        (geo, table)
    }

    /// The scene of [`many_lights`] with `quads`, `spheres` and `triangles` emitters.
    fn lights_of_every_kind(quads: usize, spheres: usize, triangles: usize) -> (Geometry, LightTable) {
        let mut r = crate::testing::uniform(5);
        let mut at = |s: f32| Vec3A::new(s * (r() - 0.5), s * r(), s * (r() - 0.5));
        let (mut prims, mut material) = (Vec::new(), Vec::new());
        for k in 0..quads {
            let c = at(10.0);
            let flip = if k % 3 == 0 { -1.0 } else { 1.0 };
            let quad = Quad::new(c, Vec3A::X * 0.3, Vec3A::Z * 0.2 * flip).unwrap();
            prims.push(Primitive::Quad(quad));
            material.push(k as u32 % 2);
        }
        for k in 0..spheres {
            prims.push(Primitive::Sphere(Sphere::new(at(10.0), 0.1 + 0.01 * k as f32)));
            material.push(0);
        }
        for _ in 0..triangles {
            let c = at(10.0);
            prims.push(Primitive::Triangle(Triangle::new(c, c + at(0.5), c + at(0.5)).unwrap()));
            material.push(1);
        }
        prims.push(Primitive::Disk(Disk::new(at(10.0), Vec3A::X * 0.2, Vec3A::Y * 0.2, false).unwrap()));
        material.push(0);
        // A floor that does not emit.
        prims.push(Primitive::Quad(
            Quad::new(Vec3A::new(-5.0, 0.0, 5.0), Vec3A::X * 10.0, -Vec3A::Z * 10.0).unwrap(),
        ));
        material.push(2);
        let geo = Geometry::build(prims, material);
        let emit = |radiance: Vec3, two_sided| Some(AreaEmission { radiance, texture: None, two_sided });
        let emission = vec![emit(Vec3::new(1.0, 2.0, 3.0), false), emit(Vec3::splat(4.0), true), None];
        let punctual = [
            PunctualLight::Point { position: at(10.0), intensity: Vec3::splat(3.0) },
            PunctualLight::Spot {
                position: at(10.0),
                axis: -Vec3A::Y,
                intensity: Vec3::splat(5.0),
                cos_falloff: 0.9,
                cos_total: 0.8,
                falloff: SpotFalloff::Smoothstep,
                texture: None,
            },
            PunctualLight::Projector {
                position: at(10.0),
                frame: [Vec3A::X, Vec3A::Z, -Vec3A::Y],
                tan_x: 0.5,
                tan_y: 0.3,
                irradiance: Vec3::ONE,
                texture: None,
            },
            PunctualLight::Directional { to_light: Vec3A::Y, irradiance: Vec3::ONE },
        ];
        let inputs = LightInputs {
            punctual: &punctual,
            environment: BackgroundSampling::Always,
            sampler: LightSamplerKind::Tree,
            ..Default::default()
        };
        let table = LightTable::build(&geo, emission, inputs);
        assert!(table.tree.is_some());
        (geo, table)
    }

    /// From points above and below the lights, the tree's probabilities of all lights sum to
    /// at most 1 (the rest: walks that find no light), every light that reaches the point has
    /// some, `pmf_from` gives each picked light the bits `pick` gave it, and the picks' counts
    /// fit the probabilities (chi-square at significance 1e-4). (The pmf of the other child
    /// in `LightTree::pmf` fails the sum; a pick that takes the first child where `u < p0 / 2`
    /// fails the chi-square.)
    #[test]
    fn picks_follow_the_pmf() {
        let (geo, table) = many_lights();
        check_picks(&geo, &table);
        let (geo, table) = few_lights();
        check_picks(&geo, &table);
    }

    /// [`picks_follow_the_pmf`] for one table.
    fn check_picks(geo: &Geometry, table: &LightTable) {
        let n = table.len();
        let mut r = crate::testing::uniform(11);
        for k in 0..6 {
            let p = Vec3A::new(12.0 * (r() - 0.5), 14.0 * r() - 2.0, 12.0 * (r() - 0.5));
            // Half the points in a medium, half on surfaces facing a random way.
            let normal = match k % 2 {
                0 => Vec3A::ZERO,
                _ => Vec3A::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize(),
            };
            // The environment beside the other lights is sampled apart, never picked.
            let apart = table.apart();
            let pmf: Vec<f32> =
                (0..n).map(|l| if Some(l) == apart { 0.0 } else { table.pmf_from(l, p, normal) }).collect();
            let sum: f64 = pmf.iter().map(|&x| x as f64).sum();
            assert!(sum <= 1.0 + 1e-6 && sum > 0.99, "point {k} at {p}: the pmf sums to {sum}");
            // Every light that sends something to the point may be picked.
            for (l, &q) in pmf.iter().enumerate() {
                let reaches = match table.other(l) {
                    Some(OtherLight::Punctual(light)) => {
                        light.illuminate(p, &Textures::default()).2 != Vec3::ZERO
                    }
                    Some(OtherLight::Environment) => apart.is_none(),
                    None => {
                        let prim = table.prims[l] as usize;
                        let two_sided = table.emission[geo.material[prim] as usize].unwrap().two_sided;
                        let s = table.sample(geo, l, p, glam::Vec2::new(r(), r()), 0.0);
                        two_sided || s.n.dot(p - s.p) > 0.0
                    }
                };
                assert!(q > 0.0 || !reaches, "light {l} reaches {p} with probability 0");
            }
            let draws = 200_000;
            // The last cell counts the walks that end where both children have importance 0
            // though their parent has some (the bounds of both are looser than each's):
            // probability 0 and no light, with the probability the lights' pmfs leave.
            let mut counts = vec![0f64; n + 1];
            for _ in 0..draws {
                let (l, q) = table.pick(r(), p, normal);
                match q {
                    0.0 => counts[n] += 1.0,
                    _ => {
                        assert_eq!(q.to_bits(), pmf[l].to_bits(), "light {l} from {p}");
                        counts[l] += 1.0;
                    }
                }
            }
            let expected = pmf.iter().map(|&q| q as f64).chain([(1.0 - sum).max(0.0)]);
            let (mut stat, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
            for (o, q) in counts.iter().zip(expected) {
                let e = q * draws as f64;
                if e < 5.0 {
                    (pool_o, pool_e) = (pool_o + o, pool_e + e);
                    continue;
                }
                stat += (o - e) * (o - e) / e;
                dof += 1;
            }
            if pool_e >= 5.0 {
                stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                dof += 1;
            }
            let critical = chi2_critical(dof - 1);
            assert!(stat < critical, "point {k} at {p}: chi-square {stat} against {critical} ({dof} cells)");
        }
    }

    /// The density of an emitter hit ([`LightTable::pdf`]) holds the probability the tree
    /// gives the light from the point the ray left.
    #[test]
    fn emitter_densities_hold_the_trees_pmf() {
        for (geo, table) in [many_lights(), few_lights()] {
            check_densities(&geo, &table);
        }
    }

    /// [`emitter_densities_hold_the_trees_pmf`] for one table.
    fn check_densities(geo: &Geometry, table: &LightTable) {
        let (from, normal) = (Vec3A::new(0.5, 1.0, -0.5), Vec3A::new(0.6, 0.8, 0.0));
        for (l, &prim) in table.prims.iter().enumerate() {
            let s = table.sample(geo, l, from, glam::Vec2::new(0.3, 0.6), 0.0);
            let want =
                geo.prims[prim as usize].pdf_solid_angle(from, s.p, s.n) * table.pmf_from(l, from, normal);
            let got = table.pdf(geo, prim, from, normal, s.p, s.n, 0.0);
            assert_eq!(got.to_bits(), want.to_bits(), "light {l}");
        }
    }

    /// With few lights, picks for points in lanes have the bits of picks one point at a time,
    /// on surfaces and in a medium, near the lights and far, and with numbers next to 1. (Fails
    /// with the tree's share left out of the lanes' probability; the sum in another order than
    /// `LightTree::pmf`'s fails `picks_follow_the_pmf`.)
    #[test]
    fn lanes_pick_as_one_point_does() {
        const N: usize = 16;
        let (_, table) = few_lights();
        let mut r = crate::testing::uniform(12);
        let mut lights = std::collections::HashSet::new();
        for group in 0..400 {
            let (mut p, mut n, mut u) = ([[0.0; N]; 3], [[0.0; N]; 3], [0.0; N]);
            for l in 0..N {
                let scale = if l % 3 == 0 { 0.5 } else { 14.0 };
                let at = Vec3A::new(scale * (r() - 0.5), scale * r() - 2.0, scale * (r() - 0.5));
                let normal = match (group + l) % 4 {
                    0 => Vec3A::ZERO,
                    _ => Vec3A::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize(),
                };
                for a in 0..3 {
                    (p[a][l], n[a][l]) = (at[a], normal[a]);
                }
                u[l] = if l == 5 { 1.0 - f32::EPSILON / 2.0 } else { r() };
            }
            let got = table.pick_lanes(&u, &p, &n);
            for l in 0..N {
                let at = |a: &[[f32; N]; 3]| Vec3A::new(a[0][l], a[1][l], a[2][l]);
                let want = table.pick(u[l], at(&p), at(&n));
                assert_eq!(
                    (got[l].0, got[l].1.to_bits()),
                    (want.0, want.1.to_bits()),
                    "lane {l} at {}",
                    at(&p)
                );
                lights.insert(want.0);
            }
        }
        // Every light was picked (the environment is sampled apart).
        assert_eq!(lights.len(), table.len() - 1, "the lights picked");
    }

    /// Behind a one-sided quad, alone in the tree, nothing it sends arrives: probability 0.
    #[test]
    fn behind_a_one_sided_light_nothing_is_picked() {
        let quad = Quad::new(Vec3A::ZERO, Vec3A::X, Vec3A::Z).unwrap();
        let up = if quad.n.y > 0.0 { 1.0 } else { -1.0 };
        let geo = Geometry::build(vec![Primitive::Quad(quad); 2], vec![0; 2]);
        let emission = vec![Some(AreaEmission { radiance: Vec3::ONE, texture: None, two_sided: false })];
        let inputs = LightInputs { sampler: LightSamplerKind::Tree, ..Default::default() };
        let table = LightTable::build(&geo, emission, inputs);
        let none = Vec3A::ZERO;
        assert!(table.pick(0.3, Vec3A::new(0.5, up, 0.5), none).1 > 0.0);
        assert_eq!(table.pick(0.3, Vec3A::new(0.5, -up, 0.5), none).1, 0.0);
        assert_eq!(table.pmf_from(0, Vec3A::new(0.5, -up, 0.5), none), 0.0);
    }
}
