//! The principled BSDF, its thin variant and glTF's metallic-roughness material across lanes, as [`crate::glossy_lanes`]' kinds:
//! their lobes' numbers gathered per path (the tangent frame, and what needs the C library's
//! `ln`, `pow` and `sin_cos`), the engine's `eval_plain` and `sample_plain` run over
//! [`LANES`] paths at a time.

use crate::glossy_lanes::{
    ConductorOut, ConductorOutLanes, EvalLanes, EvalOut, GlossyLanes, Kernel, each_lane, set_wi,
};
use crate::lambert_vertex::{LANES, lanes};
use crate::path::ScatterSamples;
use glam::{Vec2, Vec3};
use pathwave_engine::material::metallic_roughness::MetallicRoughness;
use pathwave_engine::material::microfacet::{Distribution, PlainFrame};
use pathwave_engine::material::principled::{Lobes, Principled};
use pathwave_engine::material::principled_thin::{PrincipledThin, ThinLobes};
use pathwave_engine::material::rough_conductor::RoughConductor;
use pathwave_engine::material::{BsdfEval, BsdfSample, Material};

lanes!(pub LobesLanes for Lobes {
    base: v3, base_sqrt: v3, tint: v3, roughness: f32, metallic: f32, spec_tint: f32, sheen: f32,
    sheen_tint: f32, flatness: f32, clearcoat: f32, brdf: f32, bsdf: f32, ax: f32, ay: f32, eta: f32,
    rate_spec: f32, rate_cc: f32, rate_diff: f32, cc_alpha: f32, cc_a2: f32, cc_ln_a2: f32,
});

/// What the principled kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct PrincipledIn {
    /// Unit direction back along the ray.
    pub wo: Vec3,
    /// Unit direction to the light sample (any unit vector where there is none).
    pub wi: Vec3,
    /// The shading frame ([`Principled::frame`]): the tangent, ...
    pub t: Vec3,
    /// ... the bitangent ...
    pub b: Vec3,
    /// ... and the normal.
    pub n: Vec3,
    /// The BSDF sample's numbers: the direction's.
    pub u: [f32; 2],
    /// The lobe's.
    pub uc: f32,
    /// The clearcoat normal's cosine squared ([`Lobes::clearcoat_cos2`]).
    pub cc_cos2: f32,
    /// The material's numbers.
    pub lobes: Lobes,
}

lanes!(pub PrincipledInLanes for PrincipledIn {
    wo: v3, wi: v3, t: v3, b: v3, n: v3, u: f2, uc: f32, cc_cos2: f32, lobes: (lanes LobesLanes),
});

/// What the principled kernel writes for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct PrincipledOut {
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
    /// The relative IOR it crossed (1: reflected).
    pub eta: f32,
    /// A direction was sampled.
    pub sampled: bool,
}

lanes!(pub PrincipledOutLanes for PrincipledOut {
    f_cos: v3, eval_pdf: f32, wi: v3, weight: v3, pdf: f32, eta: f32, sampled: bool,
});

/// The principled kernel for one path: [`Principled`]'s `eval` and `sample` in its frame.
#[inline(always)]
fn principled(i: &PrincipledIn) -> PrincipledOut {
    let f = PlainFrame { t: i.t, b: i.b, n: i.n };
    let lo = f.local(i.wo);
    let e = principled_eval(i);
    let (li, eta, s, sampled) = i.lobes.sample_plain(lo, Vec2::new(i.u[0], i.u[1]), i.uc, i.cc_cos2);
    PrincipledOut {
        f_cos: e.f_cos,
        eval_pdf: e.pdf,
        wi: f.world_unit(li),
        weight: s.f_cos / s.pdf,
        pdf: s.pdf,
        eta,
        sampled,
    }
}

/// The principled BSDF towards `i.wi`.
#[inline(always)]
fn principled_eval(i: &PrincipledIn) -> BsdfEval {
    let f = PlainFrame { t: i.t, b: i.b, n: i.n };
    i.lobes.eval_plain(f.local(i.wo), f.local(i.wi))
}

impl GlossyLanes for Principled {
    type In = PrincipledInLanes;
    type Out = PrincipledOutLanes;

    /// Every principled material, with its one distribution (GGX).
    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::Principled(p) => Some((*p, Kernel::isotropic(Distribution::Ggx))),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        let f = m.frame(n.into());
        let lobes = m.lobes();
        let cc_cos2 = lobes.clearcoat_cos2(u.dir.y);
        let x = PrincipledIn {
            wo,
            wi,
            t: f.t,
            b: f.b,
            n: f.n,
            u: [u.dir.x, u.dir.y],
            uc: u.lobe,
            cc_cos2,
            lobes,
        };
        i.set(l, &x);
    }

    #[inline(never)]
    fn run(i: &Self::In, _: Kernel, o: &mut Self::Out) {
        each_lane!(i, o, PrincipledOutLanes, |x| principled(&x));
    }

    #[inline(always)]
    fn set_wi(i: &mut Self::In, l: usize, wi: Vec3) {
        set_wi!(i, l, wi);
    }

    #[inline(never)]
    fn eval(i: &Self::In, _: Kernel, o: &mut EvalLanes) {
        each_lane!(i, o, EvalLanes, |x| EvalOut::from(principled_eval(&x)));
    }

    #[inline(always)]
    fn result(o: &Self::Out, l: usize) -> (BsdfEval, Option<BsdfSample>) {
        let x = o.get(l);
        let s = BsdfSample {
            wi: x.wi.into(),
            weight: x.weight,
            pdf: x.pdf,
            eta: x.eta,
            delta: false,
            null: false,
        };
        (BsdfEval { f_cos: x.f_cos, pdf: x.eval_pdf }, x.sampled.then_some(s))
    }
}

lanes!(pub ThinLobesLanes for ThinLobes {
    base: v3, tint: v3, roughness: f32, spec_trans: f32, diff_trans: f32, spec_tint: f32, sheen: f32,
    sheen_tint: f32, flatness: f32, eta: f32, spec_ax: f32, spec_ay: f32, trans_ax: f32, trans_ay: f32,
    p_spec_reflect: f32, p_spec_trans: f32, p_diff_reflect: f32, p_diff_trans: f32,
});

/// What the thin principled kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct ThinIn {
    /// Unit direction back along the ray.
    pub wo: Vec3,
    /// Unit direction to the light sample (any unit vector where there is none).
    pub wi: Vec3,
    /// The shading frame ([`PrincipledThin::frame`]): the tangent, ...
    pub t: Vec3,
    /// ... the bitangent ...
    pub b: Vec3,
    /// ... and the normal.
    pub n: Vec3,
    /// The BSDF sample's numbers: the direction's.
    pub u: [f32; 2],
    /// The lobe's.
    pub uc: f32,
    /// The material's numbers.
    pub lobes: ThinLobes,
}

lanes!(pub ThinInLanes for ThinIn {
    wo: v3, wi: v3, t: v3, b: v3, n: v3, u: f2, uc: f32, lobes: (lanes ThinLobesLanes),
});

/// The thin principled kernel for one path: [`PrincipledThin`]'s `eval` and `sample` in its
/// frame, both sides alike (the directions turned to `wo`'s side). Its outputs are the
/// conductor's (it does not refract).
#[inline(always)]
fn thin(i: &ThinIn) -> ConductorOut {
    let f = PlainFrame { t: i.t, b: i.b, n: i.n };
    let lo = f.local(i.wo);
    let side = if lo.z < 0.0 { -1.0 } else { 1.0 };
    let e = thin_eval(i);
    let (li, s, sampled) = i.lobes.sample_plain(lo * side, Vec2::new(i.u[0], i.u[1]), i.uc);
    ConductorOut {
        f_cos: e.f_cos,
        eval_pdf: e.pdf,
        wi: f.world_unit(li * side),
        weight: s.f_cos / s.pdf,
        pdf: s.pdf,
        sampled: sampled && lo.z != 0.0,
    }
}

/// The thin principled BSDF towards `i.wi`, both sides alike.
#[inline(always)]
fn thin_eval(i: &ThinIn) -> BsdfEval {
    let f = PlainFrame { t: i.t, b: i.b, n: i.n };
    let lo = f.local(i.wo);
    let side = if lo.z < 0.0 { -1.0 } else { 1.0 };
    i.lobes.eval_plain(lo * side, f.local(i.wi) * side)
}

impl GlossyLanes for PrincipledThin {
    type In = ThinInLanes;
    type Out = ConductorOutLanes;

    /// Every thin principled material, with its one distribution (GGX).
    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::PrincipledThin(p) => Some((*p, Kernel::isotropic(Distribution::Ggx))),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        let f = m.frame(n.into());
        let x =
            ThinIn { wo, wi, t: f.t, b: f.b, n: f.n, u: [u.dir.x, u.dir.y], uc: u.lobe, lobes: m.lobes() };
        i.set(l, &x);
    }

    #[inline(never)]
    fn run(i: &Self::In, _: Kernel, o: &mut Self::Out) {
        each_lane!(i, o, ConductorOutLanes, |x| thin(&x));
    }

    #[inline(always)]
    fn set_wi(i: &mut Self::In, l: usize, wi: Vec3) {
        set_wi!(i, l, wi);
    }

    #[inline(never)]
    fn eval(i: &Self::In, _: Kernel, o: &mut EvalLanes) {
        each_lane!(i, o, EvalLanes, |x| EvalOut::from(thin_eval(&x)));
    }

    #[inline(always)]
    fn result(o: &Self::Out, l: usize) -> (BsdfEval, Option<BsdfSample>) {
        <RoughConductor as GlossyLanes>::result(o, l)
    }
}

lanes!(pub MetallicRoughnessLanes for MetallicRoughness {
    base_color: v3, metallic: f32, alpha: f32, f0: f32, clearcoat: f32, alpha_coat: f32,
    e_avg: f32, fms_dielectric: f32, diffuse_scale: f32, fms_coat: f32,
});

/// What the glTF metallic-roughness kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct GltfIn {
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
    /// The material (textures applied).
    pub material: MetallicRoughness,
}

lanes!(pub GltfInLanes for GltfIn {
    wo: v3, n: v3, wi: v3, u: f2, uc: f32, material: (lanes MetallicRoughnessLanes),
});

/// The glTF material towards `i.wi`, both sides alike.
#[inline(always)]
fn gltf_eval(i: &GltfIn) -> BsdfEval {
    let f = MetallicRoughness::frame(i.wo, i.n);
    i.material.eval_plain(f.local(i.wo), f.local(i.wi))
}

/// The glTF metallic-roughness kernel for one path: [`MetallicRoughness`]'s `eval` and
/// `sample` in its frame (its outputs are the conductor's: it does not refract).
#[inline(always)]
fn gltf(i: &GltfIn) -> ConductorOut {
    let f = MetallicRoughness::frame(i.wo, i.n);
    let e = gltf_eval(i);
    let (li, s, sampled) = i.material.sample_plain(f.local(i.wo), Vec2::new(i.u[0], i.u[1]), i.uc);
    ConductorOut {
        f_cos: e.f_cos,
        eval_pdf: e.pdf,
        wi: f.world(li),
        weight: s.f_cos / s.pdf,
        pdf: s.pdf,
        sampled,
    }
}

impl GlossyLanes for MetallicRoughness {
    type In = GltfInLanes;
    type Out = ConductorOutLanes;

    /// Every glTF material, with its one distribution (GGX).
    #[inline(always)]
    fn lane_material(m: &Material) -> Option<(Self, Kernel)> {
        match m {
            Material::MetallicRoughness(g) => Some((*g, Kernel::isotropic(Distribution::Ggx))),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut Self::In, l: usize, m: &Self, wo: Vec3, n: Vec3, wi: Vec3, u: &ScatterSamples) {
        i.set(l, &GltfIn { wo, n, wi, u: [u.dir.x, u.dir.y], uc: u.lobe, material: *m });
    }

    #[inline(never)]
    fn run(i: &Self::In, _: Kernel, o: &mut Self::Out) {
        each_lane!(i, o, ConductorOutLanes, |x| gltf(&x));
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
        each_lane!(i, o, EvalLanes, |x| EvalOut::from(gltf_eval(&x)));
    }
}
