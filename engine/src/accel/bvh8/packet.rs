//! [`PACKET`] rays at a time through a [`Bvh8`].

use super::traverse::{BoxRay, EXIT_SCALE, Stack};
use super::{Bvh8, EMPTY, LEAF, Node, WIDTH, leaf_range};
use glam::Vec3A;

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
