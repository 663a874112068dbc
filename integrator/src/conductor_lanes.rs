//! Rough conductors across lanes: the BSDF evaluated towards each path's light sample and
//! sampled for its next direction, [`LANES`] paths at a time. The kernel is the engine's own
//! [`RoughConductor::eval_plain`] and [`RoughConductor::sample_plain`] (plain numbers, no
//! branches), which the one-path code calls too: one source, so both integrators compute the
//! same bits. The light sample before and the path's bookkeeping after stay path by path
//! ([`crate::path::light_shadow`], [`crate::path::scatter_sampled`]).

use crate::lambert_vertex::{LANES, lanes};
use glam::{Vec2, Vec3};
use pathwave_engine::material::microfacet::{Beckmann, Distribution, Ggx, Microfacet, Smith};
use pathwave_engine::material::rough_conductor::{ComplexIor, PlainSample, RoughConductor};
use pathwave_engine::material::{BsdfEval, BsdfSample};

/// What the kernel reads for one path: the directions, the normal, the BSDF's numbers and the
/// conductor's parameters (textures applied).
#[derive(Clone, Copy, Debug, Default)]
pub struct ConductorIn {
    /// Unit direction back along the ray.
    pub wo: Vec3,
    /// Unit shading normal.
    pub n: Vec3,
    /// Unit direction to the light sample (any unit vector where there is none).
    pub wi: Vec3,
    /// The BSDF sample's numbers.
    pub u: [f32; 2],
    /// Colour multiplying the reflectance.
    pub tint: Vec3,
    /// Roughness.
    pub alpha: f32,
    /// Complex index of refraction: real part.
    pub eta: Vec3,
    /// Complex index of refraction: imaginary part.
    pub k: Vec3,
    /// Fresnel of the index (else 1).
    pub fresnel: bool,
    /// Reflects on both sides.
    pub two_sided: bool,
}

impl ConductorIn {
    /// The inputs of a path that meets `c` ([`RoughConductor::shaded_in_lanes`]).
    #[inline(always)]
    pub fn new(c: &RoughConductor, wo: Vec3, n: Vec3, wi: Vec3, u: Vec2) -> Self {
        Self {
            wo,
            n,
            wi,
            u: [u.x, u.y],
            tint: c.tint,
            alpha: c.alpha,
            eta: c.ior.eta,
            k: c.ior.k,
            fresnel: c.fresnel,
            two_sided: c.two_sided,
        }
    }

    /// The conductor again, with the distribution `distribution`.
    #[inline(always)]
    fn conductor(&self, distribution: Distribution) -> RoughConductor {
        RoughConductor {
            tint: self.tint,
            alpha: self.alpha,
            alpha_v: self.alpha,
            tangent: 0.0,
            ior: ComplexIor { eta: self.eta, k: self.k },
            fresnel: self.fresnel,
            distribution,
            smith: Smith::Separable,
            two_sided: self.two_sided,
        }
    }
}

/// What the kernel writes for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct ConductorOut {
    /// `f cos` towards the light sample.
    pub f_cos: Vec3,
    /// The BSDF's density of that direction.
    pub eval_pdf: f32,
    /// The sampled direction.
    pub wi: Vec3,
    /// Its weight, `f cos / pdf`.
    pub weight: Vec3,
    /// Its density.
    pub pdf: f32,
    /// A direction was sampled.
    pub sampled: bool,
}

impl ConductorOut {
    /// The evaluation towards the light sample.
    #[inline(always)]
    pub fn eval(&self) -> BsdfEval {
        BsdfEval { f_cos: self.f_cos, pdf: self.eval_pdf }
    }

    /// The sampled direction, if any.
    #[inline(always)]
    pub fn sample(&self) -> Option<BsdfSample> {
        self.sampled.then(|| PlainSample { wi: self.wi, weight: self.weight, pdf: self.pdf }.into())
    }
}

lanes!(pub ConductorInLanes for ConductorIn {
    wo: v3, n: v3, wi: v3, u: f2, tint: v3, alpha: f32, eta: v3, k: v3, fresnel: bool, two_sided: bool,
});

lanes!(pub ConductorOutLanes for ConductorOut {
    f_cos: v3, eval_pdf: f32, wi: v3, weight: v3, pdf: f32, sampled: bool,
});

/// The kernel for one path, with the distribution `md` of its roughness.
#[inline(always)]
fn conductor<M: Microfacet<Vec3>>(i: &ConductorIn, distribution: Distribution, md: M) -> ConductorOut {
    let c = i.conductor(distribution);
    let e = c.eval_plain(md, i.wo, i.wi, i.n);
    let (s, sampled) = c.sample_plain(md, i.wo, i.n, Vec2::new(i.u[0], i.u[1]));
    ConductorOut { f_cos: e.f_cos, eval_pdf: e.pdf, wi: s.wi, weight: s.weight, pdf: s.pdf, sampled }
}

/// Runs the kernel on all lanes with the distribution `distribution` (lanes of another are
/// computed too, and not read).
#[inline(never)]
pub fn conductor_lanes(i: &ConductorInLanes, distribution: Distribution, o: &mut ConductorOutLanes) {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || match distribution {
            Distribution::Ggx => {
                for l in 0..LANES {
                    let x = i.get(l);
                    o.set(l, &conductor(&x, distribution, Ggx { alpha: x.alpha }));
                }
            }
            Distribution::Beckmann => {
                for l in 0..LANES {
                    let x = i.get(l);
                    o.set(l, &conductor(&x, distribution, Beckmann { alpha: x.alpha }));
                }
            }
        },
    )
}
