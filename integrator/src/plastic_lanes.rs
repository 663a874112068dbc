//! Plastics across lanes, as [`crate::glossy_lanes`]' kinds: the engine's
//! `RoughPlastic::eval_plain` and `sample_plain` over [`LANES`] paths at a time, each lane
//! reading its coating's tables through a pointer, and the smooth-coated `Plastic`'s (its
//! mirror a delta lobe, its base's lobe evaluated).

use crate::glossy_lanes::{
    ConductorOut, ConductorOutLanes, EvalLanes, EvalOut, GlossyLanes, Kernel, each_lane, set_wi,
};
use crate::lambert_vertex::{LANES, lanes};
use crate::path::ScatterSamples;
use glam::{Vec2, Vec3};
use pathwave_engine::material::microfacet::{Beckmann, Distribution, Ggx, Microfacet};
use pathwave_engine::material::plastic::Plastic;
use pathwave_engine::material::rough_conductor::{PlainSample, RoughConductor};
use pathwave_engine::material::rough_plastic::{Coating, RoughPlastic};
use pathwave_engine::material::{BsdfEval, BsdfSample, Material};

/// A rough plastic's coating tables, as a lane holds them (by default [`Coating::OPAQUE`]).
#[derive(Clone, Copy, Debug)]
pub struct CoatingRef(pub &'static Coating);

impl Default for CoatingRef {
    fn default() -> Self {
        CoatingRef(&Coating::OPAQUE)
    }
}

/// What the plastic kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlasticIn {
    /// Unit direction back along the ray.
    pub wo: Vec3,
    /// Unit shading normal.
    pub n: Vec3,
    /// Unit direction to the light sample (any unit vector where there is none).
    pub wi: Vec3,
    /// The BSDF sample's numbers: the direction's.
    pub u: [f32; 2],
    /// The lobe's.
    pub uc: f32,
    /// The base's reflectance.
    pub albedo: Vec3,
    /// Colour multiplying the coating's reflection.
    pub tint: Vec3,
    /// The coating's index of refraction.
    pub ior: f32,
    /// Roughness.
    pub alpha: f32,
    /// The base's inner bounces are nonlinear.
    pub nonlinear: bool,
    /// Reflects on both sides.
    pub two_sided: bool,
    /// The glossy lobe's sampling weight.
    pub specular_weight: f32,
    /// The coating's tables.
    pub coating: CoatingRef,
}

lanes!(pub PlasticInLanes for PlasticIn {
    wo: v3, n: v3, wi: v3, u: f2, uc: f32, albedo: v3, tint: v3, ior: f32, alpha: f32, nonlinear: bool,
    two_sided: bool, specular_weight: f32, coating: CoatingRef,
});

impl PlasticIn {
    /// The plastic, with the distribution `distribution`.
    #[inline(always)]
    fn plastic(&self, distribution: Distribution) -> RoughPlastic {
        RoughPlastic {
            albedo: self.albedo,
            tint: self.tint,
            ior: self.ior,
            alpha: self.alpha,
            distribution,
            nonlinear: self.nonlinear,
            two_sided: self.two_sided,
            specular_weight: self.specular_weight,
            coating: self.coating.0,
        }
    }
}

/// The plastic kernel for one path, with the distribution `md` of its roughness (its outputs
/// are the conductor's).
#[inline(always)]
fn plastic<M: Microfacet<Vec3>>(i: &PlasticIn, distribution: Distribution, md: M) -> ConductorOut {
    let g = i.plastic(distribution);
    let e = g.eval_plain(md, i.wo, i.wi, i.n);
    let (s, sampled) = g.sample_plain(md, i.wo, i.n, Vec2::new(i.u[0], i.u[1]), i.uc);
    ConductorOut { f_cos: e.f_cos, eval_pdf: e.pdf, wi: s.wi, weight: s.weight, pdf: s.pdf, sampled }
}

impl GlossyLanes for RoughPlastic {
    type In = PlasticInLanes;
    type Out = ConductorOutLanes;

    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::RoughPlastic(g) if g.shaded_in_lanes() => Some((*g, Kernel::isotropic(g.distribution))),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        let x = PlasticIn {
            wo,
            n,
            wi,
            u: [u.dir.x, u.dir.y],
            uc: u.lobe,
            albedo: m.albedo,
            tint: m.tint,
            ior: m.ior,
            alpha: m.alpha,
            nonlinear: m.nonlinear,
            two_sided: m.two_sided,
            specular_weight: m.specular_weight,
            coating: CoatingRef(m.coating),
        };
        i.set(l, &x);
    }

    #[inline(never)]
    fn run(i: &Self::In, k: Kernel, o: &mut Self::Out) {
        let d = k.distribution;
        each_lane!(i, d, o, ConductorOutLanes, |x, md| plastic(&x, d, md));
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
    fn eval(i: &Self::In, k: Kernel, o: &mut EvalLanes) {
        let d = k.distribution;
        each_lane!(i, d, o, EvalLanes, |x, md| EvalOut::from(x.plastic(d).eval_plain(md, x.wo, x.wi, x.n)));
    }
}

/// What the smooth-coated plastic's kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct SmoothIn {
    /// Unit direction back along the ray.
    pub wo: Vec3,
    /// Unit shading normal.
    pub n: Vec3,
    /// Unit direction to the light sample (any unit vector where there is none).
    pub wi: Vec3,
    /// The BSDF sample's numbers: the direction's.
    pub u: [f32; 2],
    /// The lobe's.
    pub uc: f32,
    /// The plastic (textures applied).
    pub plastic: SmoothPlastic,
}

/// A [`Plastic`] as a lane holds it (by default black, index 1.5).
#[derive(Clone, Copy, Debug)]
pub struct SmoothPlastic(pub Plastic);

impl Default for SmoothPlastic {
    fn default() -> Self {
        SmoothPlastic(Plastic::new(Vec3::ZERO, Vec3::ZERO, 1.5, false, false))
    }
}

lanes!(pub SmoothInLanes for SmoothIn { wo: v3, n: v3, wi: v3, u: f2, uc: f32, plastic: SmoothPlastic });

/// What the smooth-coated plastic's kernel writes for one path: the conductor's outputs, and
/// whether the sample is the mirror's.
#[derive(Clone, Copy, Debug, Default)]
pub struct SmoothOut {
    /// The outputs a conductor's kernel writes.
    pub out: ConductorOut,
    /// The sample is the mirror's (a delta lobe).
    pub delta: bool,
}

lanes!(pub SmoothOutLanes for SmoothOut { out: (lanes ConductorOutLanes), delta: bool });

/// The smooth-coated plastic's kernel for one path.
#[inline(always)]
fn smooth(i: &SmoothIn) -> SmoothOut {
    let g = &i.plastic.0;
    let e = g.eval_plain(i.wo, i.wi, i.n);
    let (s, delta, sampled) = g.sample_plain(i.wo, i.n, Vec2::new(i.u[0], i.u[1]), i.uc);
    let out =
        ConductorOut { f_cos: e.f_cos, eval_pdf: e.pdf, wi: s.wi, weight: s.weight, pdf: s.pdf, sampled };
    SmoothOut { out, delta }
}

impl GlossyLanes for Plastic {
    type In = SmoothInLanes;
    type Out = SmoothOutLanes;

    /// Every smooth-coated plastic, with one kernel.
    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::Plastic(g) => Some((*g, Kernel::isotropic(Distribution::Ggx))),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        i.set(l, &SmoothIn { wo, n, wi, u: [u.dir.x, u.dir.y], uc: u.lobe, plastic: SmoothPlastic(*m) });
    }

    #[inline(never)]
    fn run(i: &Self::In, _: Kernel, o: &mut Self::Out) {
        each_lane!(i, o, SmoothOutLanes, |x| smooth(&x));
    }

    #[inline(always)]
    fn result(o: &Self::Out, l: usize) -> (BsdfEval, Option<BsdfSample>) {
        let x = o.get(l);
        let s = PlainSample { wi: x.out.wi, weight: x.out.weight, pdf: x.out.pdf };
        let e = BsdfEval { f_cos: x.out.f_cos, pdf: x.out.eval_pdf };
        (e, x.out.sampled.then(|| BsdfSample { delta: x.delta, ..s.into() }))
    }

    #[inline(always)]
    fn set_wi(i: &mut Self::In, l: usize, wi: Vec3) {
        set_wi!(i, l, wi);
    }

    #[inline(never)]
    fn eval(i: &Self::In, _: Kernel, o: &mut EvalLanes) {
        each_lane!(i, o, EvalLanes, |x| EvalOut::from(x.plastic.0.eval_plain(x.wo, x.wi, x.n)));
    }
}
