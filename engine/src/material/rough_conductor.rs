//! Rough conductor: a microfacet reflector (Walter et al. 2007) with the GGX or the Beckmann
//! distribution, one-sided, with separable Smith shadowing-masking, sampled by visible normals
//! (see [`super::microfacet`]).
//!
//! `f(wo, wi) = tint F(wo.h) D(h) G1(wo) G1(wi) / (4 |cos wo| |cos wi|)` with `h` the half
//! vector, and `F` = 1 without a complex index of refraction, else the exact conductor Fresnel
//! reflectance for unpolarised light. Single scattering only: light that would scatter again
//! between microfacets is lost (GGX with F = 1: about 5% at alpha 0.2, where its long tail tilts
//! 4% of the normals beyond 45 degrees, and 69% at alpha 1 and normal incidence, 1 - ln 2
//! being left; Beckmann's shorter tail loses less). Below [`SMOOTH_ALPHA`] it is a smooth
//! mirror.
//!
//! Anisotropic with `alpha_v`: `alpha` is then the roughness along the surface's tangent (its
//! `dp/du` made orthogonal to the shading normal, as Mitsuba's shading frame) and `alpha_v`
//! along the bitangent. The hit sets the tangent ([`MaterialModel::set_tangent`]); where
//! the two are equal the isotropic code runs.

use super::microfacet::{
    Beckmann, BeckmannAniso, Distribution, Ggx, GgxAniso, Microfacet, PlainFrame, Roughness, SMOOTH_ALPHA,
    Smith,
};
use super::{BsdfEval, BsdfSample, Colors, MaterialModel, Shading, Specular};
use crate::format::{Albedo, Color, Rgb, Scalar};
use crate::math::{Frame, reflect};
use glam::{Vec2, Vec3, Vec3A};

/// Microfacet reflector (Walter et al. 2007) with the `distribution` `Ggx` (default) or `Beckmann`
/// (Mitsuba 3's definitions: its rational Smith `G1` and Jakob's visible-normal sampling; `alpha`
/// is then the RMS slope); Smith shadowing-masking `Separable` (default, `G1(wo) G1(wi)`, as
/// Mitsuba) or `HeightCorrelated` (`1 / (1 + Lambda(wo) + Lambda(wi))`, as pbrt-v4); visible-normal
/// sampling (GGX: Heitz 2018); one-sided: black from below the normal, unless `two_sided: true`
/// (default false), which reflects on both sides alike (Mitsuba's `twosided`). `tint` (or a
/// texture) in [0, 1] multiplies the Fresnel reflectance, which is 1 without `eta`/`k` and
/// otherwise the exact conductor Fresnel of the complex index `eta + i k` per channel (`eta` > 0,
/// `k` >= 0, both optional: a missing `eta` is 1, a missing `k` 0). `alpha` in [0, 1] or a texture
/// (its luminance, limited to [0, 1]); below 0.001 a smooth mirror. With `alpha_v` (the same kinds
/// of value) anisotropic, as Mitsuba's `alpha_u`/`alpha_v`: `alpha` along the surface's tangent
/// (`dp/du` made orthogonal to the shading normal: meshes from their uvs, quads along their `u`
/// edge, spheres along their parallels; other shapes take an arbitrary tangent) and `alpha_v`
/// across it. Single scattering: rough surfaces lose energy (GGX: about 5% at alpha 0.2, 69% at
/// alpha 1 and normal incidence; Beckmann's short tail loses under 1% at alpha 0.2).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RoughConductorDesc {
    /// Colour multiplying the reflectance, components in [0, 1], or a texture.
    pub tint: Color<Albedo>,
    /// Roughness in [0, 1] or a texture (its luminance, limited to [0, 1]); below 1e-3 a smooth
    /// mirror. With `alpha_v`: the roughness along the tangent (`u`).
    pub alpha: Scalar<Roughness>,
    /// Roughness along the bitangent (`v`), as `alpha`; by default `alpha` (isotropic).
    #[serde(default)]
    pub alpha_v: Option<Scalar<Roughness>>,
    /// `Ggx` (default) or `Beckmann`.
    #[serde(default)]
    pub distribution: Distribution,
    /// Real part of the complex index of refraction per channel (> 0). With neither `eta` nor
    /// `k` the Fresnel factor is 1; with only one of them the other is 1 (`eta`) or 0 (`k`).
    #[serde(default)]
    pub eta: Option<PositiveRgb>,
    /// Imaginary part (absorption) of the complex index of refraction per channel (>= 0).
    #[serde(default)]
    pub k: Option<Rgb>,
    /// `Separable` (default) or `HeightCorrelated` Smith shadowing-masking.
    #[serde(default)]
    pub smith: Smith,
    /// Reflects on both sides (Mitsuba's `twosided` around a conductor); by default the side
    /// the normal points to reflects and the other is black.
    #[serde(default)]
    pub two_sided: bool,
}

/// Three finite numbers > 0 `(r, g, b)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositiveRgb(pub Vec3);

impl<'de> serde::Deserialize<'de> for PositiveRgb {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (x, y, z) = <(f32, f32, f32)>::deserialize(d)?;
        let v = Vec3::new(x, y, z);
        if v.is_finite() && v.min_element() > 0.0 {
            Ok(PositiveRgb(v))
        } else {
            Err(serde::de::Error::custom(format!(
                "expected an index of refraction with finite components > 0, found ({x}, {y}, {z})"
            )))
        }
    }
}

/// A complex index of refraction `eta + i k` per channel, relative to the outside medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ComplexIor {
    /// Real part (> 0).
    pub eta: Vec3,
    /// Imaginary part, the absorption (>= 0).
    pub k: Vec3,
}

/// A sampled direction on plain numbers, from the lane kernel's code
/// ([`RoughConductor::sample_plain`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct PlainSample {
    /// The unit direction (world space).
    pub wi: Vec3,
    /// `f cos / pdf`.
    pub weight: Vec3,
    /// Its solid-angle density.
    pub pdf: f32,
}

impl From<PlainSample> for BsdfSample {
    #[inline(always)]
    fn from(s: PlainSample) -> Self {
        BsdfSample { wi: s.wi.into(), weight: s.weight, pdf: s.pdf, eta: 1.0, delta: false, null: false }
    }
}

/// A microfacet reflector tinted by `tint`, with Fresnel 1 or that of a complex IOR.
///
/// 52 bytes, which keeps [`super::Material`] at 56: the index is stored with a flag beside it,
/// not as an `Option` (whose tag would take 4 more).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    /// Colour multiplying the reflectance.
    pub tint: Vec3,
    /// Roughness in [0, 1] (along the tangent when it differs from `alpha_v`).
    pub alpha: f32,
    /// Roughness in [0, 1] along the bitangent.
    pub alpha_v: f32,
    /// The tangent's angle about the shading normal `n`, from [`Frame::from_normal`]`(n).t`
    /// towards its `b` (set at each hit when anisotropic).
    pub tangent: f32,
    /// Complex index of refraction, used when `fresnel`.
    pub ior: ComplexIor,
    /// Fresnel of `ior`; false: Fresnel 1.
    pub fresnel: bool,
    /// The distribution of microfacet normals.
    pub distribution: Distribution,
    /// The shadowing-masking term's form.
    pub smith: Smith,
    /// Reflects on both sides.
    pub two_sided: bool,
}

/// A complex index of refraction whose Fresnel factor is never used (`fresnel: false`).
pub const NO_IOR: ComplexIor = ComplexIor { eta: Vec3::ONE, k: Vec3::ZERO };

impl RoughConductor {
    /// Anisotropic roughness: `alpha` and `alpha_v` differ.
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        self.alpha != self.alpha_v
    }

    /// The shading frame of an anisotropic conductor at `n` (the normal the integrators gave)
    /// facing `nf` (`n` or its opposite, see [`Self::facing`]): the tangent at its angle,
    /// the bitangent completing a right-handed frame about `nf`.
    #[inline]
    fn tangent_frame(&self, n: Vec3A, nf: Vec3A) -> PlainFrame {
        let f = Frame::from_normal(n);
        let (s, c) = self.tangent.sin_cos();
        let t = c * f.t + s * f.b;
        PlainFrame { t: t.into(), b: nf.cross(t).into(), n: nf.into() }
    }

    /// The normal a two-sided conductor reflects about: `n` turned to `wo`'s side.
    #[inline]
    fn facing(&self, wo: Vec3A, n: Vec3A) -> Vec3A {
        if self.two_sided && wo.dot(n) < 0.0 { -n } else { n }
    }

    /// A smooth mirror: alpha below [`SMOOTH_ALPHA`].
    #[inline]
    pub fn is_smooth(&self) -> bool {
        self.alpha.max(self.alpha_v) < SMOOTH_ALPHA
    }

    /// Fresnel reflectance at the cosine `cos_i` between the direction and the (micro) normal.
    #[inline(always)]
    pub fn fresnel(&self, cos_i: f32) -> Vec3 {
        match self.fresnel {
            false => Vec3::ONE,
            true => fresnel_conductor(cos_i, self.ior.eta, self.ior.k),
        }
    }

    /// Whether the lane kernels shade it ([`Self::eval_plain`] and [`Self::sample_plain`],
    /// or [`Self::eval_in`] and [`Self::sample_in`] in its [`Self::anisotropic_frame`]): rough.
    #[inline]
    pub fn shaded_in_lanes(&self) -> bool {
        !self.is_smooth()
    }

    /// The frame of an anisotropic conductor at the shading normal `n` seen from `wo`: its
    /// tangent at its angle, its normal facing `wo` where it is two-sided.
    #[inline]
    pub fn anisotropic_frame(&self, wo: Vec3A, n: Vec3A) -> PlainFrame {
        self.tangent_frame(n, self.facing(wo, n))
    }

    /// The anisotropic distribution's widths along the tangent and across (at least
    /// [`SMOOTH_ALPHA`]).
    #[inline(always)]
    pub fn anisotropic_widths(&self) -> (f32, f32) {
        (self.alpha.max(SMOOTH_ALPHA), self.alpha_v.max(SMOOTH_ALPHA))
    }

    /// [`MaterialModel::eval`] of an isotropic rough conductor with the distribution `md`, on
    /// plain numbers and without branches: the one source of the one-path code and the lane
    /// kernel, whose loop over lanes vectorises.
    #[inline(always)]
    pub fn eval_plain<M: Microfacet<Vec3>>(&self, md: M, wo: Vec3, wi: Vec3, n_given: Vec3) -> BsdfEval {
        self.eval_in(PlainFrame::facing(wo, n_given, self.two_sided), md, wo, wi)
    }

    /// [`Self::eval_plain`] in the frame `f` (its normal facing `wo`; the anisotropic one's
    /// tangent along the roughness `alpha`'s direction).
    #[inline(always)]
    pub fn eval_in<M: Microfacet<Vec3>>(&self, f: PlainFrame, md: M, wo: Vec3, wi: Vec3) -> BsdfEval {
        let (lo, li) = (f.local(wo), f.local(wi));
        let m = (lo + li).normalize_or_zero();
        let cos_om = lo.dot(m);
        // D_wo(m) / (4 wo.m) = D G1(wo) / (4 cos_o), which is also f cos_i / (F G / G1(wo))
        // with f cos_i = F D G / (4 cos_o).
        let pdf = md.d(m) * md.g1_over_cos(lo) * 0.25;
        let f_cos = self.tint * self.fresnel(cos_om.min(1.0)) * (pdf * md.shadowing(self.smith, lo, li));
        let valid = lo.z > 0.0 && li.z > 0.0 && m.z > 0.0 && cos_om > 0.0 && pdf > 0.0 && pdf.is_finite();
        match valid {
            true => BsdfEval { f_cos, pdf },
            false => BsdfEval::ZERO,
        }
    }

    /// [`MaterialModel::sample`] of an isotropic rough conductor with the distribution `md`
    /// (visible-normal sampling, mirroring about the normal), on plain numbers and without
    /// branches as [`Self::eval_plain`]: the sample and whether there is one (none seen from
    /// below the normal, or when the mirrored direction falls below the surface:
    /// single-scattering loss).
    #[inline(always)]
    pub fn sample_plain<M: Microfacet<Vec3>>(
        &self,
        md: M,
        wo: Vec3,
        n_given: Vec3,
        u: Vec2,
    ) -> (PlainSample, bool) {
        self.sample_in(PlainFrame::facing(wo, n_given, self.two_sided), md, wo, u)
    }

    /// [`Self::sample_plain`] in the frame `f`, as [`Self::eval_in`].
    #[inline(always)]
    pub fn sample_in<M: Microfacet<Vec3>>(
        &self,
        f: PlainFrame,
        md: M,
        wo: Vec3,
        u: Vec2,
    ) -> (PlainSample, bool) {
        let lo = f.local(wo);
        let m = md.sample_visible(lo, u);
        let cos_om = lo.dot(m);
        let li = 2.0 * lo.dot(m) * m - lo;
        // D_wo(m) / (4 wo.m), the Jacobian of the reflection (Walter et al. 2007, eq. 14).
        let pdf = md.pdf_visible(lo, m) / (4.0 * cos_om);
        // f cos_i / pdf: D and G1(wo) / cos_o cancel, leaving F G / G1(wo) (F G1(wi) when
        // separable).
        let weight = self.tint * self.fresnel(cos_om.min(1.0)) * md.shadowing(self.smith, lo, li);
        let wi = f.world_unit(li);
        let valid = lo.z > 0.0 && m.z > 0.0 && cos_om > 0.0 && li.z > 0.0 && pdf > 0.0 && pdf.is_finite();
        (PlainSample { wi, weight, pdf }, valid)
    }

    /// [`Self::sample_plain`] as a [`BsdfSample`].
    #[inline(always)]
    fn sample_isotropic<M: Microfacet<Vec3>>(
        &self,
        md: M,
        wo: Vec3A,
        n: Vec3A,
        u: Vec2,
    ) -> Option<BsdfSample> {
        let (s, valid) = self.sample_plain(md, wo.into(), n.into(), u);
        valid.then(|| s.into())
    }

    /// [`Self::sample_isotropic`] with Beckmann, out of line: inlined beside GGX's, it made the
    /// compiler lay out GGX's path less well (0.4% more instructions on materials-env).
    #[inline(never)]
    fn sample_beckmann(&self, wo: Vec3A, n: Vec3A, u: Vec2) -> Option<BsdfSample> {
        self.sample_isotropic(Beckmann { alpha: self.alpha }, wo, n, u)
    }

    /// [`Self::eval_plain`] with Beckmann, out of line as [`Self::sample_beckmann`].
    #[inline(never)]
    fn eval_beckmann(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        self.eval_plain(Beckmann { alpha: self.alpha }, wo.into(), wi.into(), n.into())
    }

    /// [`Self::sample_in`] when anisotropic, out of line (`n` as the integrators gave it, `nf`
    /// facing `wo`).
    #[inline(never)]
    fn sample_anisotropic(&self, wo: Vec3A, n: Vec3A, nf: Vec3A, u: Vec2) -> Option<BsdfSample> {
        let f = self.tangent_frame(n, nf);
        let (ax, ay) = self.anisotropic_widths();
        let (s, valid) = match self.distribution {
            Distribution::Ggx => self.sample_in(f, GgxAniso { ax, ay }, wo.into(), u),
            Distribution::Beckmann => self.sample_in(f, BeckmannAniso { ax, ay }, wo.into(), u),
        };
        valid.then(|| s.into())
    }

    /// [`Self::eval_in`] when anisotropic, out of line as [`Self::sample_anisotropic`].
    #[inline(never)]
    fn eval_anisotropic(&self, wo: Vec3A, wi: Vec3A, n: Vec3A, nf: Vec3A) -> BsdfEval {
        let f = self.tangent_frame(n, nf);
        let (ax, ay) = self.anisotropic_widths();
        match self.distribution {
            Distribution::Ggx => self.eval_in(f, GgxAniso { ax, ay }, wo.into(), wi.into()),
            Distribution::Beckmann => self.eval_in(f, BeckmannAniso { ax, ay }, wo.into(), wi.into()),
        }
    }
}

impl MaterialModel for RoughConductor {
    type Desc = RoughConductorDesc;
    const SHADING: Shading = Shading::Glossy;

    fn build(desc: &RoughConductorDesc, colors: &mut Colors) -> Self {
        let ior =
            ComplexIor { eta: desc.eta.map_or(Vec3::ONE, |e| e.0), k: desc.k.map_or(Vec3::ZERO, |k| k.0) };
        let tint = colors.get(&desc.tint).min(Vec3::ONE);
        let alpha = colors.scalar(&desc.alpha);
        // Isotropic: slot 1 is `alpha` again (read twice where textured), so that the two are
        // equal at every hit.
        let alpha_v = colors.scalar(desc.alpha_v.as_ref().unwrap_or(&desc.alpha));
        if desc.alpha_v.is_some() {
            colors.tangent();
        }
        Self {
            tint,
            alpha,
            alpha_v,
            tangent: 0.0,
            ior,
            fresnel: desc.eta.is_some() || desc.k.is_some(),
            distribution: desc.distribution,
            smith: desc.smith,
            two_sided: desc.two_sided,
        }
    }

    #[inline]
    fn set_color(&mut self, _slot: usize, value: Vec3) {
        self.tint = value.clamp(Vec3::ZERO, Vec3::ONE);
    }

    #[inline]
    fn set_scalar(&mut self, slot: usize, value: f32) {
        match slot {
            0 => self.alpha = value.clamp(0.0, 1.0),
            _ => self.alpha_v = value.clamp(0.0, 1.0),
        }
    }

    #[inline]
    fn set_tangent(&mut self, n: Vec3A, dpdu: Vec3A) {
        self.tangent = tangent_angle(n, dpdu);
    }

    /// Visible-normal sampling and mirroring about the normal; `None` seen from below `n` or
    /// when the mirrored direction falls below the surface (single-scattering loss).
    fn sample(&self, wo: Vec3A, n_given: Vec3A, u: Vec2, _uc: f32) -> Option<BsdfSample> {
        let n = self.facing(wo, n_given);
        let cos_o = wo.dot(n);
        if cos_o <= 0.0 {
            return None;
        }
        if self.is_smooth() {
            let weight = self.tint * self.fresnel(cos_o.min(1.0));
            return Some(BsdfSample {
                wi: reflect(wo, n),
                weight,
                pdf: 1.0,
                eta: 1.0,
                delta: true,
                null: false,
            });
        }
        if self.is_anisotropic() {
            return self.sample_anisotropic(wo, n_given, n, u);
        }
        match self.distribution {
            Distribution::Ggx => self.sample_isotropic(Ggx { alpha: self.alpha }, wo, n_given, u),
            Distribution::Beckmann => self.sample_beckmann(wo, n_given, u),
        }
    }

    fn eval(&self, wo: Vec3A, wi: Vec3A, n_given: Vec3A) -> BsdfEval {
        if self.is_smooth() {
            return BsdfEval::ZERO;
        }
        if self.is_anisotropic() {
            return self.eval_anisotropic(wo, wi, n_given, self.facing(wo, n_given));
        }
        match self.distribution {
            Distribution::Ggx => {
                self.eval_plain(Ggx { alpha: self.alpha }, wo.into(), wi.into(), n_given.into())
            }
            Distribution::Beckmann => self.eval_beckmann(wo, wi, n_given),
        }
    }

    /// The narrower of its two widths.
    fn sharpest_alpha(&self) -> Option<f32> {
        Some(self.alpha.min(self.alpha_v))
    }

    #[inline]
    fn albedo(&self) -> Vec3 {
        self.tint
    }

    fn specular(&self) -> Specular {
        if self.is_smooth() { Specular::Mirror } else { Specular::No }
    }
}

/// The angle about the unit normal `n` from [`Frame::from_normal`]`(n).t` to `dpdu` made
/// orthogonal to `n` (0 where `dpdu` is along `n` or zero).
#[inline]
pub fn tangent_angle(n: Vec3A, dpdu: Vec3A) -> f32 {
    let f = Frame::from_normal(n);
    let s = dpdu - n * n.dot(dpdu);
    let (x, y) = (s.dot(f.t), s.dot(f.b));
    if (x == 0.0 && y == 0.0) || !(x.is_finite() && y.is_finite()) { 0.0 } else { y.atan2(x) }
}

/// A complex number, for the conductor Fresnel equations.
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    #[inline(always)]
    fn new(re: f32, im: f32) -> Self {
        Self { re, im }
    }

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }

    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Self::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }

    #[inline(always)]
    fn scale(self, s: f32) -> Self {
        Self::new(self.re * s, self.im * s)
    }

    /// Squared modulus.
    #[inline(always)]
    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }

    #[inline(always)]
    fn div(self, o: Self) -> Self {
        let d = o.norm();
        Self::new((self.re * o.re + self.im * o.im) / d, (self.im * o.re - self.re * o.im) / d)
    }

    /// Principal square root.
    #[inline(always)]
    fn sqrt(self) -> Self {
        let n = self.norm().sqrt();
        if n == 0.0 {
            return Self::new(0.0, 0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 { Self::new(t1, t2) } else { Self::new(t2.abs(), t1.copysign(self.im)) }
    }
}

/// Exact Fresnel reflectance of a conductor for unpolarised light, at the cosine `cos_i` of the
/// incident direction and the complex relative index of refraction `eta + i k` (> 0 real part),
/// as pbrt-v4's `FrComplex` (Pharr, Jakob and Humphreys 2023, "The Fresnel Equations for
/// Conductors").
#[inline(always)]
pub fn fresnel_complex(cos_i: f32, eta: f32, k: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = Complex::new(eta, k);
    let one = Complex::new(1.0, 0.0);
    let sin2_i = Complex::new(1.0 - cos_i * cos_i, 0.0);
    let sin2_t = sin2_i.div(eta.mul(eta));
    let cos_t = one.sub(sin2_t).sqrt();
    let ec = eta.scale(cos_i);
    let r_parl = ec.sub(cos_t).div(ec.add(cos_t));
    let ect = eta.mul(cos_t);
    let ci = Complex::new(cos_i, 0.0);
    let r_perp = ci.sub(ect).div(ci.add(ect));
    let f = 0.5 * (r_parl.norm() + r_perp.norm());
    if f.is_finite() { f.clamp(0.0, 1.0) } else { 1.0 }
}

/// [`fresnel_complex`] per channel.
#[inline(always)]
pub fn fresnel_conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    Vec3::new(
        fresnel_complex(cos_i, eta.x, k.x),
        fresnel_complex(cos_i, eta.y, k.y),
        fresnel_complex(cos_i, eta.z, k.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::material::dielectric::fresnel_exact;
    use crate::material::microfacet::testing::assert_chi2;
    use crate::testing::{material as build, material_desc as parse};

    /// Gold (pbrt-v4's `metal-Au` at about 650, 550 and 450 nm).
    const GOLD: ComplexIor =
        ComplexIor { eta: Vec3::new(0.143, 0.374, 1.442), k: Vec3::new(3.983, 2.385, 1.603) };

    fn conductor(alpha: f32, ior: Option<ComplexIor>) -> RoughConductor {
        RoughConductor {
            tint: Vec3::ONE,
            alpha,
            alpha_v: alpha,
            tangent: 0.0,
            distribution: Distribution::Ggx,
            ior: ior.unwrap_or(NO_IOR),
            fresnel: ior.is_some(),
            smith: Smith::Separable,
            two_sided: false,
        }
    }

    /// Both distributions.
    const DISTRIBUTIONS: [Distribution; 2] = [Distribution::Ggx, Distribution::Beckmann];

    /// A normal that is not an axis, and the direction `deg` degrees from it.
    fn setup(deg: f32) -> (Vec3A, Vec3A) {
        let n = Vec3A::new(0.2, -0.3, 0.9).normalize();
        let t = deg.to_radians();
        (n, Frame::from_normal(n).to_world(Vec3A::new(t.sin(), 0.0, t.cos())))
    }

    /// Directional albedo `integral of f |cos wi|` by the midpoint rule on a uniform grid in
    /// (cos theta, phi) over the upper hemisphere: independent of `sample`.
    fn albedo_by_quadrature(m: &RoughConductor, wo: Vec3A, n: Vec3A) -> Vec3 {
        let frame = Frame::from_normal(n);
        let (nz, np) = (2000, 500);
        let mut sum = glam::DVec3::ZERO;
        for i in 0..nz {
            let z = (i as f32 + 0.5) / nz as f32;
            let s = (1.0 - z * z).sqrt();
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                let wi = frame.to_world(Vec3A::new(s * phi.cos(), s * phi.sin(), z));
                sum += m.eval(wo, wi, n).f_cos.as_dvec3();
            }
        }
        (sum * std::f64::consts::TAU / (nz * np) as f64).as_vec3()
    }

    /// Mean sample weight (absorbed samples count 0) and its standard error (largest channel).
    fn albedo_by_sampling(m: &RoughConductor, wo: Vec3A, n: Vec3A, count: usize) -> (Vec3, f32) {
        let mut r = crate::testing::uniform(11);
        let (mut sum, mut sum2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for _ in 0..count {
            if let Some(s) = m.sample(wo, n, Vec2::new(r(), r()), r()) {
                let w = s.weight.as_dvec3();
                sum += w;
                sum2 += w * w;
            }
        }
        let mean = sum / count as f64;
        // At least 0: rounding may take it below when every weight is the same.
        let var = (sum2 / count as f64 - mean * mean).max_element().max(0.0) / count as f64;
        (mean.as_vec3(), var.sqrt() as f32)
    }

    #[test]
    fn sampling_matches_eval_pdf_chi2() {
        for distribution in DISTRIBUTIONS {
            for alpha in [0.05f32, 0.2, 0.6] {
                for deg in [1.0f32, 60.0, 85.0] {
                    let m = RoughConductor { distribution, ..conductor(alpha, Some(GOLD)) };
                    let (n, wo) = setup(deg);
                    let what = format!("{distribution:?}, alpha {alpha}, {deg} deg");
                    let dof = assert_chi2(
                        &what,
                        |u, uc| m.sample(wo, n, u, uc).map(|s| s.wi),
                        |wi| m.eval(wo, wi, n).pdf,
                        (n, reflect(wo, n), alpha),
                        500_000,
                    );
                    // Beckmann's lobe, without GGX's tails, fills fewer cells.
                    assert!(dof > 40, "{what}: {dof}");
                }
            }
        }
    }

    #[test]
    fn sample_weight_and_pdf_agree_with_eval() {
        let mut r = crate::testing::uniform(7);
        for (ior, smith, distribution) in [
            (None, Smith::Separable, Distribution::Ggx),
            (Some(GOLD), Smith::Separable, Distribution::Ggx),
            (None, Smith::HeightCorrelated, Distribution::Ggx),
            (Some(GOLD), Smith::Separable, Distribution::Beckmann),
            (None, Smith::HeightCorrelated, Distribution::Beckmann),
        ] {
            for alpha in [0.01f32, 0.05, 0.2, 0.6, 1.0] {
                for deg in [0.0f32, 30.0, 60.0, 85.0, 89.5] {
                    let m = RoughConductor {
                        tint: Vec3::new(0.9, 0.6, 0.3),
                        alpha,
                        alpha_v: alpha,
                        tangent: 0.0,
                        distribution,
                        ior: ior.unwrap_or(NO_IOR),
                        fresnel: ior.is_some(),
                        smith,
                        two_sided: false,
                    };
                    let (n, wo) = setup(deg);
                    for _ in 0..200 {
                        let Some(s) = m.sample(wo, n, Vec2::new(r(), r()), r()) else { continue };
                        let e = m.eval(wo, s.wi, n);
                        assert!(!s.delta && s.eta == 1.0 && (s.wi.length() - 1.0).abs() < 1e-5);
                        let w = e.f_cos / e.pdf;
                        assert!(
                            (s.weight - w).abs().max_element() <= 1e-3 * w.max_element(),
                            "{alpha} {deg}: {} vs {w}",
                            s.weight
                        );
                        // The pdf is ill-conditioned for a very narrow lobe at grazing incidence:
                        // eval's half vector wo + wi cancels to a hundredth of its terms.
                        let tol = if alpha < 0.05 && deg > 89.0 { 5e-3 } else { 1e-3 };
                        assert!(
                            (s.pdf - e.pdf).abs() <= tol * e.pdf,
                            "{alpha} {deg}: {} vs {}",
                            s.pdf,
                            e.pdf
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn white_furnace_never_exceeds_one() {
        for distribution in DISTRIBUTIONS {
            for alpha in [0.05f32, 0.2, 0.6, 1.0] {
                for deg in [0.0f32, 30.0, 60.0, 85.0] {
                    let (n, wo) = setup(deg);
                    let m = RoughConductor { distribution, ..conductor(alpha, None) };
                    let (e, se) = albedo_by_sampling(&m, wo, n, 50_000);
                    let what = format!("{distribution:?}, alpha {alpha}, {deg} deg");
                    assert!(e.max_element() <= 1.0 + 3.0 * se + 1e-4, "{what}: {e}");
                    assert!(e.min_element() > 0.3, "{what}: {e}");
                }
            }
        }
    }

    #[test]
    fn albedo_by_quadrature_matches_sampling_and_shows_the_single_scattering_loss() {
        for distribution in DISTRIBUTIONS {
            for alpha in [0.2f32, 0.6, 1.0] {
                for deg in [0.0f32, 60.0, 80.0] {
                    let (n, wo) = setup(deg);
                    let m = RoughConductor { distribution, ..conductor(alpha, None) };
                    let q = albedo_by_quadrature(&m, wo, n).x;
                    let (e, se) = albedo_by_sampling(&m, wo, n, 100_000);
                    let what = format!("{distribution:?}, alpha {alpha}, {deg} deg");
                    assert!(q <= 1.0 + 1e-3, "{what}: {q}");
                    // Beckmann's sampling has the exact masking, its weights the rational one
                    // (0.35%).
                    assert!((q - e.x).abs() < 4.0 * se + 4e-3, "{what}: {q} vs {e}");
                }
            }
        }
        // Single scattering loses energy at high roughness: at alpha 1, D = 1 / pi and
        // G1(w) = 2 cos / (1 + cos), so at normal incidence the albedo is
        // integral of cos_i / (1 + cos_i) / (2 pi) = 1 - ln 2 (0.307) ...
        let (n, wo) = setup(0.0);
        let q = albedo_by_quadrature(&conductor(1.0, None), wo, n).x;
        assert!((q - (1.0 - 2f32.ln())).abs() < 1e-3, "{q}");
        // ... and 0.41 at 60 deg (far more than several percent lost).
        let (n, wo) = setup(60.0);
        let q = albedo_by_quadrature(&conductor(1.0, None), wo, n).x;
        assert!(q < 0.9 && q > 0.3, "{q}");
        // At alpha 0.2 the loss is the GGX tail: 4% of the normals tilt by more than 45 deg
        // (P(tan^2 > 1) = alpha^2 / (1 + alpha^2)) and mirror below the surface.
        let q = albedo_by_quadrature(&conductor(0.2, None), setup(0.0).1, setup(0.0).0).x;
        assert!(q > 0.93 && q < 0.97, "{q}");
        // Beckmann's tail is Gaussian: exp(-1 / alpha^2) of the normals tilt beyond 45 degrees.
        let beckmann = RoughConductor { distribution: Distribution::Beckmann, ..conductor(0.2, None) };
        let q = albedo_by_quadrature(&beckmann, setup(0.0).1, setup(0.0).0).x;
        assert!(q > 0.99 && q <= 1.0, "{q}");
    }

    /// A one-sided conductor is black seen from behind; a two-sided one reflects there as the
    /// same conductor facing the other way.
    #[test]
    fn two_sided_conductors_reflect_from_behind() {
        let (n, wo) = setup(30.0);
        for alpha in [0.0f32, 0.3] {
            let one = conductor(alpha, Some(GOLD));
            let two = RoughConductor { two_sided: true, ..one };
            let flipped = |u: Vec2| (one.sample(-wo, -n, u, 0.5), two.sample(-wo, n, u, 0.5));
            for u in [Vec2::new(0.3, 0.6), Vec2::new(0.8, 0.1)] {
                assert!(one.sample(-wo, n, u, 0.5).is_none(), "one-sided, seen from behind");
                let (want, got) = flipped(u);
                let (want, got) = (want.unwrap(), got.unwrap());
                assert_eq!((got.wi, got.weight, got.pdf), (want.wi, want.weight, want.pdf));
                assert!(got.wi.dot(n) < 0.0);
                if alpha > 0.0 {
                    assert_eq!(one.eval(-wo, got.wi, n), BsdfEval::ZERO);
                    assert_eq!(two.eval(-wo, got.wi, n), one.eval(-wo, got.wi, -n));
                }
            }
        }
    }

    /// Anisotropic conductors sample by their density (chi-square), their weights are `f cos /
    /// pdf`, and their BRDF is reciprocal, for tangents at several angles about a tilted normal
    /// and both sides of a two-sided one.
    #[test]
    fn anisotropic_sampling_matches_eval_and_is_reciprocal() {
        let mut r = crate::testing::uniform(31);
        for distribution in DISTRIBUTIONS {
            for (alpha, alpha_v, turn) in [(0.05f32, 0.4f32, 0.3f32), (0.5, 0.1, 2.0)] {
                let (n, wo) = setup(50.0);
                let mut m = RoughConductor {
                    alpha,
                    alpha_v,
                    distribution,
                    two_sided: true,
                    ..conductor(alpha, Some(GOLD))
                };
                let f = Frame::from_normal(n);
                m.set_tangent(n, turn.cos() * f.t + turn.sin() * f.b + 0.3 * n);
                assert!((m.tangent - turn).abs() < 1e-5, "{} {turn}", m.tangent);
                for (wo, side) in [(wo, "front"), (-wo, "back")] {
                    let what = format!("{distribution:?}, alpha {alpha}/{alpha_v}, {side}");
                    assert_chi2(
                        &what,
                        |u, uc| m.sample(wo, n, u, uc).map(|s| s.wi),
                        |wi| m.eval(wo, wi, n).pdf,
                        (n, reflect(wo, n), alpha.max(alpha_v)),
                        300_000,
                    );
                    for _ in 0..300 {
                        let Some(s) = m.sample(wo, n, Vec2::new(r(), r()), r()) else { continue };
                        let e = m.eval(wo, s.wi, n);
                        let w = e.f_cos / e.pdf;
                        assert!((s.weight - w).abs().max_element() <= 1e-3 * w.max_element(), "{what}");
                        assert!((s.pdf - e.pdf).abs() <= 1e-3 * e.pdf, "{what}");
                        let back = m.eval(s.wi, wo, n).f_cos / wo.dot(n).abs();
                        let fwd = e.f_cos / s.wi.dot(n).abs();
                        assert!((back - fwd).abs().max_element() <= 1e-3 * fwd.max_element(), "{what}");
                    }
                }
            }
        }
    }

    /// Anisotropic roughness as Mitsuba's: `alpha` along the tangent (`dp/du`), `alpha_v`
    /// along the bitangent. Mitsuba 3.9.1's `roughconductor` (Beckmann, alpha_u 0.05, alpha_v
    /// 0.3, shading frame s = x) evaluates `f cos` 1.97115 for `wi` tilted along x and 5.18625
    /// along y, `wo` normal.
    #[test]
    fn anisotropic_lobes_lie_along_the_tangent_as_mitsubas() {
        let mut m = RoughConductor {
            alpha: 0.05,
            alpha_v: 0.3,
            distribution: Distribution::Beckmann,
            ..conductor(0.05, None)
        };
        m.set_tangent(Vec3A::Z, Vec3A::new(2.0, 0.0, 0.5));
        let along = |x: f32, y: f32| m.eval(Vec3A::Z, Vec3A::new(x, y, 1.0).normalize(), Vec3A::Z).f_cos.x;
        assert!((along(0.1, 0.0) - 1.97115).abs() < 1e-3 * 1.97115, "{}", along(0.1, 0.0));
        assert!((along(0.0, 0.1) - 5.18625).abs() < 1e-3 * 5.18625, "{}", along(0.0, 0.1));
    }

    #[test]
    fn brdf_is_reciprocal() {
        let mut r = crate::testing::uniform(23);
        let n = Vec3A::new(-0.4, 0.1, 0.8).normalize();
        let frame = Frame::from_normal(n);
        let mut dir = || {
            let (z, phi) = (r().max(0.01), r() * std::f32::consts::TAU);
            let s = (1.0 - z * z).sqrt();
            frame.to_world(Vec3A::new(s * phi.cos(), s * phi.sin(), z))
        };
        for (alpha, distribution) in DISTRIBUTIONS.iter().flat_map(|&d| [(0.05f32, d), (0.3, d), (1.0, d)]) {
            let m = RoughConductor {
                tint: Vec3::new(0.9, 0.6, 0.3),
                alpha,
                alpha_v: alpha,
                tangent: 0.0,
                distribution,
                ior: GOLD,
                fresnel: true,
                smith: Smith::Separable,
                two_sided: false,
            };
            for _ in 0..500 {
                let (wo, wi) = (dir(), dir());
                let a = m.eval(wo, wi, n).f_cos / wi.dot(n);
                let b = m.eval(wi, wo, n).f_cos / wo.dot(n);
                assert!((a - b).abs().max_element() <= 1e-4 * a.max_element().max(1e-3), "{a} {b}");
            }
        }
    }

    #[test]
    fn black_from_below() {
        let m = conductor(0.3, None);
        let n = Vec3A::Z;
        let below = Vec3A::new(0.3, 0.0, -0.9).normalize();
        let above = Vec3A::new(-0.3, 0.2, 0.9).normalize();
        assert!(m.sample(below, n, Vec2::splat(0.3), 0.5).is_none());
        assert_eq!(m.eval(below, above, n), BsdfEval::ZERO);
        assert_eq!(m.eval(above, below, n), BsdfEval::ZERO);
        assert_eq!(m.eval(Vec3A::X, above, n), BsdfEval::ZERO, "grazing");
        assert!(m.sample(Vec3A::X, n, Vec2::splat(0.3), 0.5).is_none(), "grazing");
        assert!(conductor(0.0, None).sample(below, n, Vec2::ZERO, 0.0).is_none());
    }

    #[test]
    fn smooth_alpha_is_a_tinted_fresnel_mirror() {
        for alpha in [0.0f32, 5e-4] {
            let m = RoughConductor {
                tint: Vec3::new(0.9, 0.6, 0.3),
                alpha,
                alpha_v: alpha,
                tangent: 0.0,
                distribution: Distribution::Beckmann,
                ior: GOLD,
                fresnel: true,
                smith: Smith::Separable,
                two_sided: false,
            };
            let n = Vec3A::Z;
            let wo = Vec3A::new(0.6, 0.0, 0.8);
            let s = m.sample(wo, n, Vec2::new(0.3, 0.7), 0.2).unwrap();
            assert!((s.wi - Vec3A::new(-0.6, 0.0, 0.8)).length() < 1e-6);
            assert!(s.delta && s.pdf == 1.0 && s.eta == 1.0);
            assert!((s.weight - m.tint * fresnel_conductor(0.8, GOLD.eta, GOLD.k)).length() < 1e-6);
            assert_eq!(m.eval(wo, s.wi, n), BsdfEval::ZERO);
            assert_eq!(m.specular(), Specular::Mirror);
        }
        assert_eq!(conductor(SMOOTH_ALPHA, None).specular(), Specular::No);
        assert_eq!(
            conductor(0.0, None).sample(Vec3A::Z, Vec3A::Z, Vec2::ZERO, 0.0).unwrap().weight,
            Vec3::ONE
        );
    }

    #[test]
    fn conductor_fresnel_known_values() {
        // k = 0 is a dielectric.
        for c in [0.05f32, 0.3, 0.7, 1.0] {
            for eta in [1.5f32, 1.0 / 1.5, 2.4] {
                assert!((fresnel_complex(c, eta, 0.0) - fresnel_exact(c, eta)).abs() < 1e-5, "{c} {eta}");
            }
        }
        // Normal incidence: ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2).
        for (eta, k) in [(0.143f32, 3.983f32), (1.442, 1.603), (2.0, 0.5)] {
            let r = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
            assert!((fresnel_complex(1.0, eta, k) - r).abs() < 1e-5, "{eta} {k}");
        }
        // Grazing: 1; and within [0, 1] in between, dipping below normal incidence for metals.
        assert!(fresnel_complex(0.0, 0.143, 3.983) > 0.999);
        let f = fresnel_conductor(0.5, GOLD.eta, GOLD.k);
        assert!(f.min_element() >= 0.0 && f.max_element() <= 1.0);
        assert!(f.x > f.z, "gold reflects red more than blue: {f}");
    }

    /// A textured alpha takes a number slot (the tint the colour slot) and holds the texture's
    /// mean until a hit sets it, limited to [0, 1].
    #[test]
    fn textured_alpha_fills_a_number_slot() {
        let text = r#"RoughConductor(tint: "tint", alpha: "bumps")"#;
        let (mut m, slots) = Material::build(&parse(text).unwrap(), &mut |n| match n {
            "bumps" => (4, Vec3::new(0.1, 0.2, 0.3)),
            _ => (2, Vec3::ONE),
        });
        assert_eq!(slots.colors, [Some(2), None]);
        // alpha_v, not written, is alpha again.
        assert_eq!(&slots.scalars[..3], [Some(4), Some(4), None]);
        assert!(!slots.tangent);
        let alpha = |m: &Material| match m {
            Material::RoughConductor(c) => c.alpha,
            _ => unreachable!(),
        };
        assert_eq!(alpha(&m), crate::texture::scalar(Vec3::new(0.1, 0.2, 0.3)));
        for (value, want) in [(0.25, 0.25), (1.5, 1.0), (-0.5, 0.0)] {
            m.set_scalar(0, value);
            assert_eq!(alpha(&m), want);
        }
    }

    #[test]
    fn descriptions_parse_and_bad_values_are_refused() {
        let m = build("RoughConductor(tint: (0.9, 0.6, 0.3), alpha: 0.15)");
        assert_eq!(
            m,
            Material::RoughConductor(RoughConductor {
                tint: Vec3::new(0.9, 0.6, 0.3),
                alpha: 0.15,
                alpha_v: 0.15,
                tangent: 0.0,
                distribution: Distribution::Ggx,
                ior: NO_IOR,
                fresnel: false,
                smith: Smith::Separable,
                two_sided: false,
            })
        );
        assert_eq!(m.shading(), Shading::Glossy);
        let m = build(
            "RoughConductor(tint: (1, 1, 1), alpha: 0.3, distribution: Beckmann, eta: (0.143, 0.374, 1.442), k: (3.983, 2.385, 1.603))",
        );
        assert_eq!(
            m,
            Material::RoughConductor(RoughConductor {
                tint: Vec3::ONE,
                alpha: 0.3,
                alpha_v: 0.3,
                tangent: 0.0,
                distribution: Distribution::Beckmann,
                ior: GOLD,
                fresnel: true,
                smith: Smith::Separable,
                two_sided: false,
            })
        );
        let Material::RoughConductor(c) = build("RoughConductor(tint: (1, 1, 1), alpha: 0.3, k: (3, 2, 1))")
        else {
            unreachable!()
        };
        assert_eq!((c.ior, c.fresnel), (ComplexIor { eta: Vec3::ONE, k: Vec3::new(3.0, 2.0, 1.0) }, true));
        for (text, message) in [
            (
                "RoughConductor(tint: (1, 1, 1), alpha: -0.1)",
                "expected a roughness alpha in [0, 1], found -0.1",
            ),
            (
                "RoughConductor(tint: (1, 1, 1), alpha: 1.5)",
                "expected a roughness alpha in [0, 1], found 1.5",
            ),
            (
                "RoughConductor(tint: (1, 1, 1), alpha: 0.2, eta: (0, 1, 1))",
                "components > 0, found (0, 1, 1)",
            ),
            ("RoughConductor(tint: (1, 1, 1), alpha: 0.2, k: (-1, 1, 1))", "components >= 0"),
            ("RoughConductor(tint: (1.5, 1, 1), alpha: 0.2)", "albedo with components in [0, 1]"),
            ("RoughConductor(tint: (1, 1, 1))", "alpha"),
            ("RoughConductor(tint: (1, 1, 1), alpha: 0.2, distribution: Phong)", "`Ggx` or `Beckmann`"),
        ] {
            let e = parse(text).unwrap_err();
            assert!(e.contains(message), "{text}: {e}");
        }
    }
}
