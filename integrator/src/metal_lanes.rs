//! Fuzzy metals across lanes, as [`crate::glossy_lanes`]' kinds: the engine's
//! `metal::eval_plain` and `sample_plain` (the ball's density about the mirror direction, and a
//! point of the ball added to it) over [`LANES`] paths at a time. A perfect mirror (fuzz 0) is a
//! delta lobe, shaded path by path.

use crate::glossy_lanes::{
    ConductorOut, ConductorOutLanes, EvalLanes, EvalOut, GlossyLanes, Kernel, each_lane, set_wi,
};
use crate::lambert_vertex::{LANES, lanes};
use crate::path::ScatterSamples;
use glam::{Vec2, Vec3};
use pathwave_engine::material::metal::{self, Metal};
use pathwave_engine::material::microfacet::Distribution;
use pathwave_engine::material::rough_conductor::RoughConductor;
use pathwave_engine::material::{BsdfEval, BsdfSample, Material};

/// What the metal kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct MetalIn {
    /// Unit direction back along the ray.
    pub wo: Vec3,
    /// Unit shading normal.
    pub n: Vec3,
    /// Unit direction to the light sample (any unit vector where there is none).
    pub wi: Vec3,
    /// The ball's numbers: its direction's ...
    pub u: [f32; 2],
    /// ... and its radius'.
    pub uc: f32,
    /// Reflectance.
    pub albedo: Vec3,
    /// The ball's radius.
    pub fuzz: f32,
}

lanes!(pub MetalInLanes for MetalIn { wo: v3, n: v3, wi: v3, u: f2, uc: f32, albedo: v3, fuzz: f32 });

/// The metal kernel for one path (its outputs are the conductor's).
#[inline(always)]
fn fuzzy(i: &MetalIn) -> ConductorOut {
    let e = metal::eval_plain(i.albedo, i.fuzz, i.wo, i.wi, i.n);
    let (s, sampled) = metal::sample_plain(i.albedo, i.fuzz, i.wo, i.n, Vec2::new(i.u[0], i.u[1]), i.uc);
    ConductorOut { f_cos: e.f_cos, eval_pdf: e.pdf, wi: s.wi, weight: s.weight, pdf: s.pdf, sampled }
}

impl GlossyLanes for Metal {
    type In = MetalInLanes;
    type Out = ConductorOutLanes;

    /// A fuzzy metal, with one kernel (its distribution is not a microfacet one).
    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::Metal(g) if g.fuzz > 0.0 => Some((*g, Kernel::isotropic(Distribution::Ggx))),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        let x = MetalIn { wo, n, wi, u: [u.dir.x, u.dir.y], uc: u.lobe, albedo: m.albedo, fuzz: m.fuzz };
        i.set(l, &x);
    }

    #[inline(never)]
    fn run(i: &Self::In, _: Kernel, o: &mut Self::Out) {
        each_lane!(i, o, ConductorOutLanes, |x| fuzzy(&x));
    }

    #[inline(always)]
    fn result(o: &Self::Out, l: usize) -> (BsdfEval, Option<BsdfSample>) {
        <RoughConductor as GlossyLanes>::result(o, l)
    }

    #[inline(always)]
    fn set_wi(i: &mut Self::In, l: usize, wi: Vec3) {
        set_wi!(i, l, wi);
    }

    #[inline(never)]
    fn eval(i: &Self::In, _: Kernel, o: &mut EvalLanes) {
        each_lane!(i, o, EvalLanes, |x| EvalOut::from(metal::eval_plain(x.albedo, x.fuzz, x.wo, x.wi, x.n)));
    }
}
