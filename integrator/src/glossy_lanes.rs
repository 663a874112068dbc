//! Rough conductors and dielectrics (and, in [`crate::plastic_lanes`] and
//! [`crate::principled_lanes`], rough plastics and the principled BSDFs) across lanes: the BSDF evaluated towards each
//! path's light sample and sampled for its next direction, [`LANES`] paths at a time. The
//! kernels are the engine's own `eval_plain` and `sample_plain` (plain numbers, no branches),
//! which the one-path code calls too: one source, so both integrators compute the same bits.
//! The light sample before and the path's bookkeeping after stay path by path
//! ([`crate::path::light_shadow`], [`crate::path::scatter_sampled`]); the wavefront's
//! `shading` stage runs them for every kind that implements [`GlossyLanes`].

use crate::lambert_vertex::{LANES, lanes};
use crate::path::ScatterSamples;
use glam::{Vec2, Vec3};
use pathwave_engine::material::microfacet::{
    Beckmann, BeckmannAniso, Distribution, Ggx, GgxAniso, Microfacet, PlainFrame, SMOOTH_ALPHA, Smith,
};
use pathwave_engine::material::rough_conductor::{ComplexIor, PlainSample, RoughConductor};
use pathwave_engine::material::rough_dielectric::{DielectricSample, RoughDielectric};
use pathwave_engine::material::{BsdfEval, BsdfSample, Material};

/// A material kind whose BSDF the wavefront evaluates and samples across lanes.
pub trait GlossyLanes {
    /// The kernel's inputs for every lane.
    type In: Default;
    /// Its outputs for every lane.
    type Out: Default;

    /// The material as the kernel takes it, and the kernel that shades it; `None` where no
    /// kernel does (smooth): path by path then.
    fn lane_material(m: &Material) -> Option<(Self, Kernel)>
    where
        Self: Sized;

    /// Sets lane `l`'s inputs: the material `m`, the unit directions back along the ray (`wo`)
    /// and to the light sample (`wi`, any unit vector where there is none), the shading normal
    /// and the BSDF's numbers.
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples);

    /// Runs the kernel `k` on every lane (lanes of another kernel are computed too, and not
    /// read).
    fn run(i: &Self::In, k: Kernel, o: &mut Self::Out);

    /// Lane `l`'s BSDF towards its light sample, and its sampled direction (if any).
    fn result(o: &Self::Out, l: usize) -> (BsdfEval, Option<BsdfSample>);

    /// Sets lane `l`'s direction to the light sample (for [`Self::eval`]: the environment's,
    /// sampled apart; any unit vector where there is none).
    fn set_wi(i: &mut Self::In, l: usize, wi: Vec3);

    /// The BSDF towards every lane's light sample by the kernel `k`, across lanes: its
    /// evaluation alone.
    fn eval(i: &Self::In, k: Kernel, o: &mut EvalLanes);
}

/// Which of a kind's kernels shades a lane: its roughness's distribution, whether the
/// roughness is anisotropic (rough conductors only) and its shadowing-masking (rough conductors
/// and dielectrics: the others' is separable).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kernel {
    /// The distribution of microfacet normals.
    pub distribution: Distribution,
    /// Anisotropic roughness, in the tangent frame.
    pub anisotropic: bool,
    /// Smith's shadowing-masking, separable or height-correlated.
    pub smith: Smith,
}

impl Kernel {
    /// How many kernels there are.
    pub const COUNT: usize = 8;

    /// Every kernel, in [`Self::index`] order.
    pub const ALL: [Kernel; Self::COUNT] = {
        let mut all = [Kernel::isotropic(Distribution::Ggx); Self::COUNT];
        let mut i = 0;
        while i < Self::COUNT {
            all[i] = Kernel {
                distribution: if i & 1 == 0 { Distribution::Ggx } else { Distribution::Beckmann },
                anisotropic: i & 2 != 0,
                smith: if i & 4 == 0 { Smith::Separable } else { Smith::HeightCorrelated },
            };
            i += 1;
        }
        all
    };

    /// The isotropic kernel of `distribution`, with separable shadowing-masking.
    pub const fn isotropic(distribution: Distribution) -> Self {
        Kernel { distribution, anisotropic: false, smith: Smith::Separable }
    }

    /// Its place in [`Self::ALL`].
    #[inline]
    pub fn index(self) -> usize {
        let d = match self.distribution {
            Distribution::Ggx => 0,
            Distribution::Beckmann => 1,
        };
        let s = match self.smith {
            Smith::Separable => 0,
            Smith::HeightCorrelated => 1,
        };
        d + 2 * self.anisotropic as usize + 4 * s
    }
}

/// Evaluates `$body` with `$s` bound to `$smith`'s value, known where `$body` is compiled: the
/// kernels' loops are compiled once for each shadowing-masking (a separable lane computes no
/// `G1(wo)`).
macro_rules! with_smith {
    ($smith:expr, |$s:ident| $body:expr) => {
        match $smith {
            Smith::Separable => {
                let $s = Smith::Separable;
                $body
            }
            Smith::HeightCorrelated => {
                let $s = Smith::HeightCorrelated;
                $body
            }
        }
    };
}

/// A lane's BSDF towards a direction, as [`GlossyLanes::eval`] writes it.
#[derive(Clone, Copy, Debug, Default)]
pub struct EvalOut {
    /// `f cos`.
    pub f_cos: Vec3,
    /// The BSDF's density of the direction.
    pub pdf: f32,
}

impl From<BsdfEval> for EvalOut {
    #[inline(always)]
    fn from(e: BsdfEval) -> Self {
        Self { f_cos: e.f_cos, pdf: e.pdf }
    }
}

lanes!(pub EvalLanes for EvalOut { f_cos: v3, pdf: f32 });

impl EvalLanes {
    /// Lane `l`'s evaluation.
    #[inline(always)]
    pub fn eval(&self, l: usize) -> BsdfEval {
        let x = self.get(l);
        BsdfEval { f_cos: x.f_cos, pdf: x.pdf }
    }
}

/// Sets lane `$l`'s `wi` of the lane inputs `$i` to `$wi`.
macro_rules! set_wi {
    ($i:expr, $l:expr, $wi:expr) => {
        ($i.wi[0][$l], $i.wi[1][$l], $i.wi[2][$l]) = ($wi.x, $wi.y, $wi.z)
    };
}

pub(crate) use set_wi;

/// Runs `$kernel` (a lane's outputs from its inputs `$x` and its distribution `$md`) on every
/// lane of `$i` into `$o` (of type `$out`), in the AVX-512 region where the CPU has it, with a
/// loop for each distribution (each compiled with its distribution's code; one loop for a kind
/// of one distribution, whose kernel takes `$x` alone). The loop writes a
/// local output, copied to `$o` after it: writing `$o` itself, the plastic's loop, whose kernel
/// reads its coating tables through each lane's pointer, did not vectorise (LLVM could not tell
/// its stores from those tables).
macro_rules! each_lane {
    ($i:expr, $o:expr, $out:ty, |$x:ident| $kernel:expr) => {
        *$o = pathwave_engine::simd::lanes(
            #[inline(always)]
            || {
                let mut out = <$out>::default();
                for l in 0..LANES {
                    let $x = $i.get(l);
                    out.set(l, &$kernel);
                }
                out
            },
        )
    };
    ($i:expr, $d:expr, $o:expr, $out:ty, |$x:ident, $md:ident| $kernel:expr) => {
        *$o = pathwave_engine::simd::lanes(
            #[inline(always)]
            || {
                let mut out = <$out>::default();
                match $d {
                    Distribution::Ggx => {
                        for l in 0..LANES {
                            let $x = $i.get(l);
                            let $md = Ggx { alpha: $x.alpha };
                            out.set(l, &$kernel);
                        }
                    }
                    Distribution::Beckmann => {
                        for l in 0..LANES {
                            let $x = $i.get(l);
                            let $md = Beckmann { alpha: $x.alpha };
                            out.set(l, &$kernel);
                        }
                    }
                }
                out
            },
        )
    };
}

pub(crate) use each_lane;

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
    /// Anisotropic roughness across the tangent (`alpha` along it).
    pub alpha_v: f32,
    /// The anisotropic kernel's frame ([`RoughConductor::anisotropic_frame`]): the tangent, ...
    pub t: Vec3,
    /// ... the bitangent ...
    pub b: Vec3,
    /// ... and the normal facing `wo`.
    pub nf: Vec3,
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
            ..Default::default()
        }
    }

    /// The conductor again, with the distribution `distribution` and shadowing-masking `smith`.
    #[inline(always)]
    fn conductor(&self, distribution: Distribution, smith: Smith) -> RoughConductor {
        RoughConductor {
            tint: self.tint,
            alpha: self.alpha,
            alpha_v: self.alpha,
            tangent: 0.0,
            ior: ComplexIor { eta: self.eta, k: self.k },
            fresnel: self.fresnel,
            distribution,
            smith,
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

lanes!(pub ConductorInLanes for ConductorIn {
    wo: v3, n: v3, wi: v3, u: f2, tint: v3, alpha: f32, eta: v3, k: v3, fresnel: bool, two_sided: bool,
    alpha_v: f32, t: v3, b: v3, nf: v3,
});

lanes!(pub ConductorOutLanes for ConductorOut {
    f_cos: v3, eval_pdf: f32, wi: v3, weight: v3, pdf: f32, sampled: bool,
});

/// The kernel for one path of the kernel `k`, with the distribution `md` of its roughness.
#[inline(always)]
fn conductor<M: Microfacet<Vec3>>(i: &ConductorIn, k: Kernel, md: M) -> ConductorOut {
    let c = i.conductor(k.distribution, k.smith);
    let e = c.eval_plain(md, i.wo, i.wi, i.n);
    let (s, sampled) = c.sample_plain(md, i.wo, i.n, Vec2::new(i.u[0], i.u[1]));
    ConductorOut { f_cos: e.f_cos, eval_pdf: e.pdf, wi: s.wi, weight: s.weight, pdf: s.pdf, sampled }
}

/// The anisotropic kernel for one path of the kernel `k`, with the distribution `md` of its
/// widths, in its tangent frame.
#[inline(always)]
fn conductor_anisotropic<M: Microfacet<Vec3>>(i: &ConductorIn, k: Kernel, md: M) -> ConductorOut {
    let (c, f) = (i.conductor(k.distribution, k.smith), PlainFrame { t: i.t, b: i.b, n: i.nf });
    let e = c.eval_in(f, md, i.wo, i.wi);
    let (s, sampled) = c.sample_in(f, md, i.wo, Vec2::new(i.u[0], i.u[1]));
    ConductorOut { f_cos: e.f_cos, eval_pdf: e.pdf, wi: s.wi, weight: s.weight, pdf: s.pdf, sampled }
}

/// Runs `$kernel` on every lane of `$i` into `$o` (of type `$out`) with the anisotropic
/// distribution `$md` of `$k`'s (the lanes' `alpha` and `alpha_v`, at least `SMOOTH_ALPHA`).
macro_rules! each_anisotropic_lane {
    ($i:expr, $k:expr, $o:expr, $out:ty, |$x:ident, $md:ident| $kernel:expr) => {
        *$o = pathwave_engine::simd::lanes(
            #[inline(always)]
            || {
                let mut out = <$out>::default();
                let widths = |x: &ConductorIn| (x.alpha.max(SMOOTH_ALPHA), x.alpha_v.max(SMOOTH_ALPHA));
                match $k.distribution {
                    Distribution::Ggx => {
                        for l in 0..LANES {
                            let $x = $i.get(l);
                            let (ax, ay) = widths(&$x);
                            let $md = GgxAniso { ax, ay };
                            out.set(l, &$kernel);
                        }
                    }
                    Distribution::Beckmann => {
                        for l in 0..LANES {
                            let $x = $i.get(l);
                            let (ax, ay) = widths(&$x);
                            let $md = BeckmannAniso { ax, ay };
                            out.set(l, &$kernel);
                        }
                    }
                }
                out
            },
        )
    };
}

impl GlossyLanes for RoughConductor {
    type In = ConductorInLanes;
    type Out = ConductorOutLanes;

    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::RoughConductor(c) if c.shaded_in_lanes() => Some((
                *c,
                Kernel { distribution: c.distribution, anisotropic: c.is_anisotropic(), smith: c.smith },
            )),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        let mut x = ConductorIn::new(m, wo, n, wi, u.dir);
        if m.is_anisotropic() {
            let f = m.anisotropic_frame(wo.into(), n.into());
            (x.alpha_v, x.t, x.b, x.nf) = (m.alpha_v, f.t, f.b, f.n);
        }
        i.set(l, &x);
    }

    #[inline(never)]
    fn run(i: &Self::In, k: Kernel, o: &mut Self::Out) {
        with_smith!(k.smith, |smith| {
            let k = Kernel { smith, ..k };
            match k.anisotropic {
                false => each_lane!(i, k.distribution, o, ConductorOutLanes, |x, md| conductor(&x, k, md)),
                true => {
                    each_anisotropic_lane!(i, k, o, ConductorOutLanes, |x, md| conductor_anisotropic(
                        &x, k, md
                    ))
                }
            }
        })
    }

    #[inline(always)]
    fn result(o: &Self::Out, l: usize) -> (BsdfEval, Option<BsdfSample>) {
        let x = o.get(l);
        let s = PlainSample { wi: x.wi, weight: x.weight, pdf: x.pdf };
        (BsdfEval { f_cos: x.f_cos, pdf: x.eval_pdf }, x.sampled.then(|| s.into()))
    }

    #[inline(always)]
    fn set_wi(i: &mut Self::In, l: usize, wi: Vec3) {
        set_wi!(i, l, wi);
    }

    #[inline(never)]
    fn eval(i: &Self::In, k: Kernel, o: &mut EvalLanes) {
        let d = k.distribution;
        with_smith!(k.smith, |smith| match k.anisotropic {
            false => each_lane!(i, d, o, EvalLanes, |x, md| {
                EvalOut::from(x.conductor(d, smith).eval_plain(md, x.wo, x.wi, x.n))
            }),
            true => each_anisotropic_lane!(i, k, o, EvalLanes, |x, md| {
                let f = PlainFrame { t: x.t, b: x.b, n: x.nf };
                EvalOut::from(x.conductor(d, smith).eval_in(f, md, x.wo, x.wi))
            }),
        })
    }
}

/// What the dielectric kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct DielectricIn {
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
    /// Index of refraction inside.
    pub ior: f32,
    /// Roughness.
    pub alpha: f32,
}

impl DielectricIn {
    /// The dielectric, with the distribution `distribution` and shadowing-masking `smith`.
    #[inline(always)]
    fn dielectric(&self, distribution: Distribution, smith: Smith) -> RoughDielectric {
        RoughDielectric { ior: self.ior, alpha: self.alpha, distribution, smith }
    }
}

/// What the dielectric kernel writes for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct DielectricOut {
    /// `f cos` towards the light sample (grey).
    pub f_cos: f32,
    /// The BSDF's density of that direction.
    pub eval_pdf: f32,
    /// The sampled direction.
    pub wi: Vec3,
    /// Its weight, `f cos / pdf` (grey).
    pub weight: f32,
    /// Its density.
    pub pdf: f32,
    /// The relative IOR it crossed (1: reflected).
    pub eta: f32,
    /// A direction was sampled.
    pub sampled: bool,
}

lanes!(pub DielectricInLanes for DielectricIn { wo: v3, n: v3, wi: v3, u: f2, uc: f32, ior: f32, alpha: f32 });

lanes!(pub DielectricOutLanes for DielectricOut {
    f_cos: f32, eval_pdf: f32, wi: v3, weight: f32, pdf: f32, eta: f32, sampled: bool,
});

/// The dielectric kernel for one path of the kernel `k`, with the distribution `md` of its
/// roughness.
#[inline(always)]
fn dielectric<M: Microfacet<Vec3>>(i: &DielectricIn, k: Kernel, md: M) -> DielectricOut {
    let g = i.dielectric(k.distribution, k.smith);
    let e = g.eval_plain(md, i.wo, i.wi, i.n);
    let (s, sampled) = g.sample_plain(md, i.wo, i.n, Vec2::new(i.u[0], i.u[1]), i.uc);
    DielectricOut {
        f_cos: e.f_cos.x,
        eval_pdf: e.pdf,
        wi: s.wi,
        weight: s.weight,
        pdf: s.pdf,
        eta: s.eta,
        sampled,
    }
}

impl GlossyLanes for RoughDielectric {
    type In = DielectricInLanes;
    type Out = DielectricOutLanes;

    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::RoughDielectric(g) if g.shaded_in_lanes() => {
                Some((*g, Kernel { smith: g.smith, ..Kernel::isotropic(g.distribution) }))
            }
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        let x = DielectricIn { wo, n, wi, u: [u.dir.x, u.dir.y], uc: u.lobe, ior: m.ior, alpha: m.alpha };
        i.set(l, &x);
    }

    #[inline(never)]
    fn run(i: &Self::In, k: Kernel, o: &mut Self::Out) {
        with_smith!(k.smith, |smith| {
            let k = Kernel { smith, ..k };
            each_lane!(i, k.distribution, o, DielectricOutLanes, |x, md| dielectric(&x, k, md))
        })
    }

    #[inline(always)]
    fn result(o: &Self::Out, l: usize) -> (BsdfEval, Option<BsdfSample>) {
        let x = o.get(l);
        let s = DielectricSample { wi: x.wi, weight: x.weight, pdf: x.pdf, eta: x.eta };
        (BsdfEval { f_cos: Vec3::splat(x.f_cos), pdf: x.eval_pdf }, x.sampled.then(|| s.into()))
    }

    #[inline(always)]
    fn set_wi(i: &mut Self::In, l: usize, wi: Vec3) {
        set_wi!(i, l, wi);
    }

    #[inline(never)]
    fn eval(i: &Self::In, k: Kernel, o: &mut EvalLanes) {
        let d = k.distribution;
        with_smith!(k.smith, |smith| each_lane!(i, d, o, EvalLanes, |x, md| EvalOut::from(
            x.dielectric(d, smith).eval_plain(md, x.wo, x.wi, x.n)
        )));
    }
}
