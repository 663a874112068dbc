//! The Lambertian vertex where a guide was learned ([`pathwave_engine::guiding`]): the next
//! direction comes from the BSDF (cosine-weighted) or from the guide's distribution of the light
//! arriving there, each half the time, and is weighted by the density of the mixture (one-sample
//! MIS with the balance heuristic, Müller et al. 2017). Path by path, in both integrators.

use crate::lambert_vertex::{
    LANES, LambertIn, LambertInLanes, LambertOut, LambertOutLanes, cosine_about, light_part, scatter_out,
};
use crate::plain::{dot, sel3};
use glam::Vec3;
use pathwave_engine::guiding::Guide;
use std::f32::consts::FRAC_1_PI;

/// Where a guide was learned, the share of directions drawn from the BSDF (Müller et al.'s
/// 0.5); the rest come from the guide.
pub const BSDF_SHARE: f32 = 0.5;

/// The Lambertian kernel ([`crate::lambert_vertex::lambert`]) where `guide` was learned: a lane
/// whose point lies in a cell that learned directions draws its next direction from the
/// mixture of the BSDF and the cell's distribution (the first number chooses which, and is
/// stretched back to [0, 1), the two then draw the direction) and weights it by the mixture's
/// density; the others draw as the plain kernel does. The light sample and MIS read the BSDF's
/// own density ([`LambertOut::mis_pdf`]). Each lane's numbers are those of the lane alone.
pub fn lambert_guided_lanes(guide: &Guide, i: &LambertInLanes, o: &mut LambertOutLanes) {
    *o = pathwave_engine::simd::lanes(
        #[inline(always)]
        || {
            let cells = guide.cells(&i.p);
            const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;
            let (mut from_guide, mut share, mut u) = ([false; LANES], [1.0f32; LANES], [[0.0f32; LANES]; 2]);
            let (mut b, mut z) = ([[0.0f32; LANES]; 3], [0.0f32; LANES]);
            for l in 0..LANES {
                // Outside the learned cells the BSDF draws alone, with the number as it is.
                share[l] = if cells[l] == Guide::EMPTY { 1.0 } else { BSDF_SHARE };
                let u0 = i.u_dir[0][l];
                from_guide[l] = u0 >= share[l];
                let stretched =
                    if from_guide[l] { (u0 - share[l]) / (1.0 - share[l]) } else { u0 / share[l] };
                (u[0][l], u[1][l]) = (stretched.min(BELOW_ONE), i.u_dir[1][l]);
                let (n, wo) = (
                    Vec3::new(i.n[0][l], i.n[1][l], i.n[2][l]),
                    Vec3::new(i.wo[0][l], i.wo[1][l], i.wo[2][l]),
                );
                let nf = sel3(dot(wo, n) < 0.0, -n, n);
                let (v, cos) = cosine_about(nf, [u[0][l], u[1][l]]);
                (b[0][l], b[1][l], b[2][l], z[l]) = (v.x, v.y, v.z, cos);
            }
            // The guide's direction where it draws, its density at the BSDF's elsewhere.
            let (d, g) = guide.lookup_lanes(&cells, &from_guide, &u, &b);
            // Into a local (the caller's arrays might alias the inputs, for all the compiler
            // knows through the closure: it kept this loop scalar, 7.9 M hits/s against 10.2).
            let mut out = LambertOutLanes::default();
            for l in 0..LANES {
                let d = Vec3::new(d[0][l], d[1][l], d[2][l]);
                out.set(l, &guided(&i.get(l), (d, from_guide[l], z[l]), share[l], g[l]));
            }
            out
        },
    );
}

/// [`lambert_guided_lanes`] for one path.
pub fn lambert_guided(guide: &Guide, i: &LambertIn) -> LambertOut {
    let (mut ins, mut outs) = (LambertInLanes::default(), LambertOutLanes::default());
    ins.set(0, i);
    lambert_guided_lanes(guide, &ins, &mut outs);
    outs.get(0)
}

/// One lane's outputs: the next direction `d`, drawn from the guide or else from the BSDF (then
/// `z` its cosine), the BSDF's `share` of the mixture and the guide's density `g` of `d`. With a
/// share of 1 these are the plain kernel's numbers.
#[inline(always)]
fn guided(i: &LambertIn, (d, from_guide, z): (Vec3, bool, f32), share: f32, g: f32) -> LambertOut {
    let (n, ng) = (i.n, i.ng);
    let light = light_part(i);
    let co = dot(i.wo, n);
    let nf = sel3(co < 0.0, -n, n);
    let cos = if from_guide { dot(d, nf) } else { z };
    let c = cos.max(0.0) * FRAC_1_PI;
    let pdf = share * c + (1.0 - share) * g;
    let (dg, ds) = (dot(d, ng), dot(d, n));
    let leaves = (!from_guide || cos > 0.0) && ((ds > 0.0 && co > 0.0) || dg * ds > 0.0);
    scatter_out(i, light, (d, ds, pdf, c, leaves), i.beta * i.albedo * (c / pdf))
}

/// The Lambertian vertices a training path recorded (at most [`Trail::MAX`], the first
/// ones), to learn from once it ends: at each, the light that came back along the direction it
/// left is what the path gathered after it, divided by the throughput after it, less the light
/// the vertex found directly (by its light sample, or on the emitter or background its
/// direction met): light sampling finds that, so the guide learns where the rest comes from,
/// weighted by the cosine.
#[derive(Clone, Copy, Debug, Default)]
pub struct Trail {
    /// The path records ([`Trail::records`]).
    pub keep: bool,
    len: u8,
    v: [TrailVertex; Trail::MAX],
}

/// A recorded vertex.
#[derive(Clone, Copy, Debug, Default)]
struct TrailVertex {
    p: [f32; 3],
    d: Vec3,
    /// The BSDF's (cosine-weighted) density of `d` over the density it was drawn with.
    weight: f32,
    /// Throughput after the vertex (its BSDF sample and roulette).
    beta: Vec3,
    /// The path's radiance when the vertex was made, and what its own light sample added.
    before: Vec3,
    own: Vec3,
    /// The path's vertex count after it (its light sample's shadow ray comes with it).
    depth: u32,
}

impl Trail {
    /// The most vertices recorded per path.
    pub const MAX: usize = 8;

    /// Whether the path of pixel `(x, y)`'s sample `sample` is among the `share` of paths that
    /// record (a hash of the three: the same paths whoever renders them).
    #[inline]
    pub fn records((x, y): (u32, u32), sample: u32, share: f32) -> bool {
        let key = crate::sampler::mix64((y as u64) << 32 | x as u64) ^ sample as u64;
        let u = (crate::sampler::mix64(key) >> 40) as f32 * (1.0 / (1u32 << 24) as f32);
        u < share
    }

    /// Records the vertex at `p` that left along `d` drawn with density `pdf` (the BSDF's
    /// being `bsdf_pdf`), its throughput after being `beta` and the path's radiance `l` and
    /// depth `depth` after it.
    #[inline]
    #[expect(clippy::too_many_arguments, reason = "one vertex's numbers, as the kernel gave them")]
    pub fn push(&mut self, p: Vec3, d: Vec3, pdf: f32, bsdf_pdf: f32, beta: Vec3, l: Vec3, depth: u32) {
        if self.keep && (self.len as usize) < Self::MAX {
            let weight = bsdf_pdf / pdf;
            let v = TrailVertex { p: p.into(), d, weight, beta, before: l, own: Vec3::ZERO, depth };
            self.v[self.len as usize] = v;
            self.len += 1;
        }
    }

    /// Light `c` that the path's vertex `depth` found directly (by its shadow ray, or where
    /// its next ray met an emitter or left the scene): the last recorded vertex's own when it
    /// is that vertex.
    #[inline]
    pub fn direct(&mut self, depth: u32, c: Vec3) {
        if let Some(v) = self.v[..self.len as usize].last_mut()
            && v.depth == depth
        {
            v.own += c;
        }
    }

    /// The records of the ended path whose radiance is `l`, appended to `out`; the trail is
    /// emptied.
    pub fn finish(&mut self, l: Vec3, out: &mut Vec<pathwave_engine::guiding::Record>) {
        for v in &self.v[..self.len as usize] {
            let back = l - v.before - v.own;
            let div = |a: f32, b: f32| if b > 0.0 { a / b } else { 0.0 };
            let li = Vec3::new(div(back.x, v.beta.x), div(back.y, v.beta.y), div(back.z, v.beta.z));
            // The radiance times the cosine, over the density: the guide learns the product
            // that a Lambertian vertex's ideal density follows (but for the albedo). Learning
            // the radiance alone left 1.04-1.08x the variance (guiding.md).
            let energy = pathwave_engine::math::luminance(li).max(0.0) * v.weight;
            out.push(pathwave_engine::guiding::Record {
                p: v.p,
                square: pathwave_engine::guiding::to_square(v.d.into()),
                energy: if energy.is_finite() { energy } else { 0.0 },
            });
        }
        self.len = 0;
    }
}
