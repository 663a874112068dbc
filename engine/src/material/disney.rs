//! The pieces the Disney BSDFs share ([`super::principled`], [`super::principled_thin`]), as
//! Mitsuba 3 defines them (`src/bsdfs/principledhelpers.h`): Schlick's Fresnel weight, the
//! dielectric Fresnel factor, GGX's widths from roughness and anisotropy, and the microfacet
//! side tests.

use super::microfacet::{GgxAniso, LocalVector, Microfacet};
use glam::Vec3;

/// `a` to `b` by `t`.
#[inline]
pub(super) fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// `(1 - cos)^5`, `cos` limited to [0, 1].
#[inline]
pub(super) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Mitsuba's `calc_dist_params`: GGX of width `roughness^2` stretched along the tangent by
/// `1 / sqrt(1 - 0.9 anisotropic)` and narrowed across by as much, at least 0.001.
#[inline]
pub(super) fn ggx(roughness: f32, anisotropic: f32) -> GgxAniso {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    GgxAniso { ax: (r2 / aspect).max(1e-3), ay: (r2 * aspect).max(1e-3) }
}

/// The weight `w` of Mitsuba's `calc_schlick`, whose Fresnel factor is `r0 + (1 - r0) w`:
/// Schlick's at the cosine `cos_i` (signed: below 0 from inside), through the refracted angle
/// where the light leaves the denser side.
#[inline]
pub(super) fn schlick_w(cos_i: f32, eta: f32) -> f32 {
    let (eta_it, eta_ti) = if cos_i >= 0.0 { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        schlick_weight((1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti).max(0.0).sqrt())
    }
}

/// Schlick's Fresnel factor from `r0` (see [`schlick_w`]).
#[inline]
pub(super) fn schlick(r0: f32, cos_i: f32, eta: f32) -> f32 {
    let w = schlick_w(cos_i, eta);
    r0 + (1.0 - r0) * w
}

/// Mitsuba's dielectric `fresnel(cos_theta_i, eta)`: the reflectance, the signed cosine of the
/// refracted direction, and the relative indices `eta_it` and `eta_ti` seen from `cos_i`'s side.
#[inline]
pub(super) fn fresnel(cos_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let (eta_it, eta_ti) = if cos_i >= 0.0 { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
    let (ci, ct) = (cos_i.abs(), cos_t2.max(0.0).sqrt());
    let r = if eta == 1.0 {
        0.0
    } else if ci == 0.0 {
        1.0
    } else {
        let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
        let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    (r, if cos_i >= 0.0 { -ct } else { ct }, eta_it, eta_ti)
}

/// Mitsuba's `mac_mic_compatibility`: `wo` and `wi` on the sides of the microfacet normal `m`
/// (turned to `wo`'s side of the surface) that a reflection or a refraction puts them.
#[inline(always)]
pub(super) fn compatible<V: LocalVector + std::ops::Neg<Output = V>>(
    m: V,
    lo: V,
    li: V,
    cos_i: f32,
    reflection: bool,
) -> bool {
    let m = if cos_i < 0.0 { -m } else { m };
    let (o, i) = (lo.dot_with(m), li.dot_with(m));
    o > 0.0 && if reflection { i > 0.0 } else { i < 0.0 }
}

/// Mitsuba's `smith_g1` of its GGX: [`Microfacet::g1`], and 0 where `v` sees the microfacet
/// `m` from its back.
#[inline(always)]
pub(super) fn smith_g1<V: LocalVector>(ggx: &impl Microfacet<V>, v: V, m: V) -> f32 {
    let g = ggx.g1(v);
    if v.dot_with(m) * v.cos() <= 0.0 { 0.0 } else { g }
}

/// [`crate::math::reflect`] on plain numbers.
#[inline(always)]
pub(super) fn reflect_plain(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * wo.dot(n) * n - wo
}
