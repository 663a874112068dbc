//! Plastic: a diffuse base under a smooth dielectric coating, as Mitsuba 3's `plastic`
//! (`src/bsdfs/plastic.cpp`, after Weidlich and Wilkie 2007, "Arbitrarily Layered Micro-Facet
//! Surfaces", with the internal scattering of Mitsuba 0.5's documentation).
//!
//! Light meets the coating first: a mirror reflection of exact Fresnel reflectance `F(cos wo)`
//! (a delta lobe, times `tint`), and the rest refracts into the layer, scatters off the base
//! and may reflect back from the inside of the coating many times before it leaves. The sum of
//! those bounces is the diffuse lobe
//!
//! `f(wo, wi) = (1 - F(cos wo)) (1 - F(cos wi)) / eta^2 * R / (1 - Fdr) / pi`,
//!
//! where `R` is the base's albedo and `Fdr` the coating's diffuse reflectance seen from inside,
//! the cosine-weighted mean of `F` over the hemisphere for the relative index `1 / eta`
//! ([`fresnel_diffuse_reflectance`]); `nonlinear` takes `R / (1 - R Fdr)` instead, the exact sum
//! of the inner bounces, which saturates colours as real plastic does. The lobe is chosen with
//! probability proportional to `F(cos wo) w` (mirror) and `(1 - F(cos wo)) (1 - w)` (diffuse),
//! with `w`, Mitsuba's `specular_sampling_weight`, the mean of the tint over the means of the
//! tint and the albedo. One-sided: black from below the normal unless `two_sided`.
//!
//! Mitsuba also computes `m_fdr_ext`, the same fit at `eta`, and uses it nowhere: with exact
//! integrals `eta^2 (1 - Fdr(1 / eta)) = 1 - Fdr(eta)`, which is what makes the linear model's
//! albedo `F + (1 - F) albedo` (the tests check both).

use super::lambertian::cosine_hemisphere_plain;
use super::rough_conductor::PlainSample;
use super::{BsdfEval, BsdfSample, Colors, MaterialModel, Shading};
use crate::format::{Albedo, Color};
use crate::material::dielectric::fresnel_exact;
use crate::math::basis;
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// A diffuse base under a smooth dielectric coating, as Mitsuba 3's `plastic`: a mirror of exact
/// Fresnel reflectance times `tint` (default white) and a diffuse lobe `(1 - F(wo)) (1 - F(wi)) /
/// ior^2 * albedo / (1 - Fdr) / pi`, `Fdr` the coating's diffuse reflectance from inside (Mitsuba's
/// fits); `nonlinear: true` takes `albedo / (1 - albedo Fdr)`, which saturates colours. `albedo`
/// and `tint` are colours in [0, 1] or textures; `ior` (coating over outside, default 1.49,
/// polypropylene) in [0.1, 10]. Lobes chosen by Fresnel and Mitsuba's `specular_sampling_weight`.
/// One-sided (black from below) unless `two_sided: true` (Mitsuba's `twosided`).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct PlasticDesc {
    /// The diffuse base's reflectance (Mitsuba's `diffuse_reflectance`), components in
    /// [0, 1], or a texture.
    pub albedo: Color<Albedo>,
    /// Colour multiplying the coating's mirror reflection (Mitsuba's `specular_reflectance`),
    /// components in [0, 1], or a texture; default white.
    #[serde(default = "white")]
    pub tint: Color<Albedo>,
    /// Index of refraction of the coating relative to the outside, in [0.1, 10]; default 1.49
    /// (polypropylene, Mitsuba's default `int_ior`).
    #[serde(default = "polypropylene")]
    pub ior: CoatingIor,
    /// The base's inner bounces as `albedo / (1 - albedo Fdr)` (saturating colours) rather than
    /// `albedo / (1 - Fdr)`; default false.
    #[serde(default)]
    pub nonlinear: bool,
    /// Reflects on both sides alike (Mitsuba's `twosided`); by default black from below.
    #[serde(default)]
    pub two_sided: bool,
}

/// White, the default tint.
pub(super) fn white() -> Color<Albedo> {
    Color::Value(Albedo(Vec3::ONE))
}

/// Mitsuba's default coating, polypropylene (1.49).
pub(super) fn polypropylene() -> CoatingIor {
    CoatingIor(1.49)
}

/// The relative index of refraction of a coating: a finite number in [0.1, 10] (beyond, the
/// factor `1 / eta^2` and the diffuse reflectance fits leave f32's range or their own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatingIor(pub f32);

impl<'de> serde::Deserialize<'de> for CoatingIor {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f32::deserialize(d)?;
        if (0.1..=10.0).contains(&v) {
            Ok(CoatingIor(v))
        } else {
            Err(serde::de::Error::custom(format!(
                "expected a coating index of refraction in [0.1, 10], found {v}"
            )))
        }
    }
}

/// A diffuse base under a smooth dielectric coating.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// The base's reflectance in [0, 1].
    pub albedo: Vec3,
    /// Colour multiplying the mirror reflection, in [0, 1].
    pub tint: Vec3,
    /// Index of refraction of the coating relative to the outside.
    pub ior: f32,
    /// `albedo / (1 - albedo Fdr)` for the inner bounces, else `albedo / (1 - Fdr)`.
    pub nonlinear: bool,
    /// Reflects on both sides.
    pub two_sided: bool,
    /// Mitsuba's `specular_sampling_weight`: `mean(tint) / (mean(tint) + mean(albedo))` from
    /// the colours (or their textures' means) as built.
    pub specular_weight: f32,
    /// The coating's diffuse reflectance from inside, [`fresnel_diffuse_reflectance`] of
    /// `1 / ior` (Mitsuba's `m_fdr_int`).
    pub fdr_int: f32,
}

impl Plastic {
    /// A plastic of these colours and coating; the sampling weight comes from these colours.
    pub fn new(albedo: Vec3, tint: Vec3, ior: f32, nonlinear: bool, two_sided: bool) -> Self {
        Self {
            albedo,
            tint,
            ior,
            nonlinear,
            two_sided,
            specular_weight: specular_sampling_weight(albedo, tint),
            fdr_int: fresnel_diffuse_reflectance(1.0 / ior),
        }
    }

    /// The normal it reflects about: `n`, turned to `wo`'s side when two-sided.
    #[inline(always)]
    fn facing(&self, wo: Vec3, n: Vec3) -> Vec3 {
        if self.two_sided && wo.dot(n) < 0.0 { -n } else { n }
    }

    /// The diffuse lobe's `f` towards a direction of cosine `cos_o`, where `f_i` is the
    /// Fresnel reflectance towards `wo`.
    #[inline(always)]
    fn diffuse(&self, f_i: f32, cos_o: f32) -> Vec3 {
        let f_o = fresnel_exact(cos_o, self.ior);
        inner_bounces(self.albedo, self.fdr_int, self.nonlinear)
            * ((1.0 - f_i) * (1.0 - f_o) * FRAC_1_PI / (self.ior * self.ior))
    }

    /// [`MaterialModel::eval`] on plain numbers and without branches: the one source of the
    /// one-path code and the lane kernel, whose loop over lanes vectorises.
    #[inline(always)]
    pub fn eval_plain(&self, wo: Vec3, wi: Vec3, n: Vec3) -> BsdfEval {
        let n = self.facing(wo, n);
        let (cos_i, cos_o) = (wo.dot(n), wi.dot(n));
        let f_i = fresnel_exact(cos_i.min(1.0), self.ior);
        let (p, some) = lobe_probability_plain(f_i, self.specular_weight);
        let cos_o1 = cos_o.min(1.0);
        let e = BsdfEval { f_cos: self.diffuse(f_i, cos_o1) * cos_o1, pdf: (1.0 - p) * cos_o1 * FRAC_1_PI };
        match cos_i > 0.0 && cos_o > 0.0 && some {
            true => e,
            false => BsdfEval::ZERO,
        }
    }

    /// [`MaterialModel::sample`] on plain numbers and without branches as [`Self::eval_plain`]:
    /// the sample, whether it is the mirror's (a delta lobe, its `pdf` the lobe's
    /// probability), and whether there is one (none from below the normal).
    #[inline(always)]
    pub fn sample_plain(&self, wo: Vec3, n: Vec3, u: Vec2, uc: f32) -> (PlainSample, bool, bool) {
        let n = self.facing(wo, n);
        let cos_i = wo.dot(n);
        let f_i = fresnel_exact(cos_i.min(1.0), self.ior);
        let (p, some) = lobe_probability_plain(f_i, self.specular_weight);
        let mirror = PlainSample { wi: 2.0 * cos_i * n - wo, weight: self.tint * (f_i / p), pdf: p };
        let local = cosine_hemisphere_plain(u);
        let (t, b) = basis(n);
        let diffuse = PlainSample {
            wi: t * local.x + b * local.y + n * local.z,
            // f cos / pdf: the cosines and 1 / pi cancel.
            weight: self.diffuse(f_i, local.z) * (std::f32::consts::PI / (1.0 - p)),
            pdf: (1.0 - p) * local.z * FRAC_1_PI,
        };
        let is_mirror = uc < p;
        let s = if is_mirror { mirror } else { diffuse };
        (s, is_mirror, cos_i > 0.0 && some && (is_mirror || diffuse.pdf > 0.0))
    }
}

/// `mean(tint) / (mean(tint) + mean(albedo))`, Mitsuba's `specular_sampling_weight` (one half
/// for a black material, where Mitsuba's is undefined).
pub(super) fn specular_sampling_weight(albedo: Vec3, tint: Vec3) -> f32 {
    let (d, s) = (albedo.element_sum() / 3.0, tint.element_sum() / 3.0);
    if d + s > 0.0 { s / (d + s) } else { 0.5 }
}

/// The probability of sampling the specular lobe when the coating reflects `r` of the light
/// (`F`, or `1 - T` for a rough coating) and the specular sampling weight is `w`: proportional
/// to `r w` against `(1 - r) (1 - w)`. `None` when both are 0.
#[inline]
pub(super) fn lobe_probability(r: f32, w: f32) -> Option<f32> {
    let (p, some) = lobe_probability_plain(r, w);
    some.then_some(p)
}

/// [`lobe_probability`] without branches, for the lane kernels: the probability and whether
/// there is one.
#[inline(always)]
pub(super) fn lobe_probability_plain(r: f32, w: f32) -> (f32, bool) {
    let (s, d) = (r * w, (1.0 - r) * (1.0 - w));
    (s / (s + d), s + d > 0.0)
}

/// The base's albedo after its inner bounces under a coating of inner diffuse reflectance
/// `fdr`: `albedo / (1 - albedo fdr)` when `nonlinear`, else `albedo / (1 - fdr)`.
#[inline(always)]
pub(super) fn inner_bounces(albedo: Vec3, fdr: f32, nonlinear: bool) -> Vec3 {
    match nonlinear {
        true => albedo / (Vec3::ONE - albedo * fdr),
        false => albedo / (1.0 - fdr),
    }
}

/// The diffuse Fresnel reflectance of an interface of relative index `eta`: the
/// cosine-weighted hemispherical mean `2 integral of F(mu) mu dmu`, by Mitsuba 3's fits
/// (`include/mitsuba/render/fresnel.h`): Egan and Hilgeman 1973 below `eta` 1 (0.1% in 1 to
/// 1.5), d'Eon and Irving 2011 ("A Quantized-Diffusion Model for Rendering Translucent
/// Materials", 0.2% up to 10) above.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        0.919317 + inv * (-3.4793 + inv * (6.75335 + inv * (-7.80989 + inv * (4.98554 + inv * -1.36881))))
    }
}

impl MaterialModel for Plastic {
    type Desc = PlasticDesc;
    const SHADING: Shading = Shading::Glossy;

    fn build(desc: &PlasticDesc, colors: &mut Colors) -> Self {
        let albedo = colors.get(&desc.albedo).min(Vec3::ONE);
        let tint = colors.get(&desc.tint).min(Vec3::ONE);
        Self::new(albedo, tint, desc.ior.0, desc.nonlinear, desc.two_sided)
    }

    /// Slot 0 is the albedo, slot 1 the tint; the sampling weight stays the built one (from
    /// the textures' means), as Mitsuba's.
    #[inline]
    fn set_color(&mut self, slot: usize, value: Vec3) {
        let value = value.clamp(Vec3::ZERO, Vec3::ONE);
        match slot {
            0 => self.albedo = value,
            _ => self.tint = value,
        }
    }

    /// The mirror with probability `F w / (F w + (1 - F)(1 - w))` (a delta lobe), else the cosine
    /// lobe; `None` from below the normal.
    #[inline]
    fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
        let (s, delta, valid) = self.sample_plain(wo.into(), n.into(), u, uc);
        valid.then(|| BsdfSample { delta, ..s.into() })
    }

    /// The diffuse lobe (the mirror is a delta).
    #[inline]
    fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        self.eval_plain(wo.into(), wi.into(), n.into())
    }

    /// The base's albedo.
    /// The smooth coating is a delta lobe.
    fn sharpest_alpha(&self) -> Option<f32> {
        Some(0.0)
    }

    #[inline]
    fn albedo(&self) -> Vec3 {
        self.albedo
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::material::microfacet::testing::assert_chi2;
    use crate::math::{Frame, reflect};
    use crate::testing::{material as build, material_desc as parse};

    /// A normal that is not an axis, and the direction `deg` degrees from it.
    fn setup(deg: f32) -> (Vec3A, Vec3A) {
        let n = Vec3A::new(0.2, -0.3, 0.9).normalize();
        let t = deg.to_radians();
        (n, Frame::from_normal(n).to_world(Vec3A::new(t.sin(), 0.0, t.cos())))
    }

    fn plastic(albedo: Vec3, ior: f32, nonlinear: bool) -> Plastic {
        Plastic::new(albedo, Vec3::ONE, ior, nonlinear, false)
    }

    /// `2 integral of F(mu) mu dmu` by the midpoint rule in f64 (with f32's Fresnel).
    fn fdr_by_quadrature(eta: f32) -> f64 {
        let n = 200_000;
        (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                2.0 * fresnel_exact(mu as f32, eta) as f64 * mu
            })
            .sum::<f64>()
            / n as f64
    }

    #[test]
    fn diffuse_reflectance_fits_match_the_integral() {
        // Inside (eta < 1, Egan and Hilgeman) and outside (d'Eon and Irving) of a coating.
        for (eta, tol) in [(1.0 / 1.49, 2e-3), (1.0 / 1.9, 6e-3), (1.49, 2e-3), (1.9, 2e-3), (3.0, 2e-3)] {
            let (fit, q) = (fresnel_diffuse_reflectance(eta) as f64, fdr_by_quadrature(eta));
            assert!((fit - q).abs() < tol * q.max(0.05), "eta {eta}: fit {fit}, integral {q}");
        }
        // Index 1 reflects nothing, to the fits' accuracy.
        assert!(fresnel_diffuse_reflectance(1.0).abs() < 2e-3);
        // Seen from inside, eta^2 (1 - Fdr(1 / eta)) = 1 - Fdr(eta) (what the diffuse lobe's
        // energy balance rests on).
        let eta = 1.5f64;
        let (inner, outer) = (fdr_by_quadrature(1.0 / eta as f32), fdr_by_quadrature(eta as f32));
        assert!((eta * eta * (1.0 - inner) - (1.0 - outer)).abs() < 1e-4, "{inner} {outer}");
    }

    /// The diffuse lobe's directions follow eval's density (the mirror's, a delta, are left
    /// out: `pdf` then integrates to the probability of the diffuse lobe).
    #[test]
    fn sampling_matches_eval_pdf_chi2() {
        for (albedo, ior) in [(Vec3::new(0.1, 0.27, 0.36), 1.9), (Vec3::splat(0.8), 1.49)] {
            for deg in [1.0f32, 60.0, 85.0] {
                let m = plastic(albedo, ior, false);
                let (n, wo) = setup(deg);
                let what = format!("{albedo}, ior {ior}, {deg} deg");
                let dof = assert_chi2(
                    &what,
                    |u, uc| m.sample(wo, n, u, uc).filter(|s| !s.delta).map(|s| s.wi),
                    |wi| m.eval(wo, wi, n).pdf,
                    (n, n, 1.0),
                    300_000,
                );
                assert!(dof > 100, "{what}: {dof}");
            }
        }
    }

    /// Every sample's weight is `f cos / pdf` of eval (diffuse) or `tint F / P(mirror)`, with
    /// the mirror chosen as often as its probability says.
    #[test]
    fn sample_weight_and_pdf_agree_with_eval() {
        let mut r = crate::testing::uniform(7);
        for nonlinear in [false, true] {
            for deg in [0.0f32, 30.0, 60.0, 85.0, 89.5] {
                let m =
                    Plastic::new(Vec3::new(0.9, 0.5, 0.1), Vec3::new(0.8, 0.9, 1.0), 1.6, nonlinear, false);
                let (n, wo) = setup(deg);
                let f_i = fresnel_exact(wo.dot(n), m.ior);
                let p = lobe_probability(f_i, m.specular_weight).unwrap();
                let (mut mirrors, count) = (0, 4000);
                for _ in 0..count {
                    let s = m.sample(wo, n, Vec2::new(r(), r()), r()).unwrap();
                    assert!(s.eta == 1.0 && (s.wi.length() - 1.0).abs() < 1e-5);
                    if s.delta {
                        mirrors += 1;
                        assert!((s.wi - reflect(wo, n)).length() < 1e-6);
                        assert_eq!((s.weight, s.pdf), (m.tint * (f_i / p), p));
                        continue;
                    }
                    let e = m.eval(wo, s.wi, n);
                    let w = e.f_cos / e.pdf;
                    assert!(
                        (s.weight - w).abs().max_element() <= 1e-4 * w.max_element(),
                        "{} vs {w}",
                        s.weight
                    );
                    assert!((s.pdf - e.pdf).abs() <= 1e-5 * e.pdf, "{} vs {}", s.pdf, e.pdf);
                }
                let se = (p * (1.0 - p) / count as f32).sqrt();
                assert!(
                    (mirrors as f32 / count as f32 - p).abs() < 4.0 * se + 1e-3,
                    "{deg}: {mirrors} mirrors, p {p}"
                );
            }
        }
    }

    /// Directional albedo: the mirror's `F(cos wo) tint` plus the diffuse lobe integrated by
    /// quadrature over the hemisphere (independent of `sample`).
    fn albedo_by_quadrature(m: &Plastic, wo: Vec3A, n: Vec3A) -> Vec3 {
        let frame = Frame::from_normal(n);
        let (nz, np) = (2000, 64);
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
        let diffuse = (sum * std::f64::consts::TAU / (nz * np) as f64).as_vec3();
        diffuse + m.tint * fresnel_exact(wo.dot(n), m.ior)
    }

    /// Mean sample weight and its standard error (largest channel).
    fn albedo_by_sampling(m: &Plastic, wo: Vec3A, n: Vec3A, count: usize) -> (Vec3, f32) {
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
        let var = (sum2 / count as f64 - mean * mean).max_element().max(0.0) / count as f64;
        (mean.as_vec3(), var.sqrt() as f32)
    }

    /// The linear model keeps energy: its albedo is `F + (1 - F) R` exactly when `Fdr` is the
    /// exact integral (here to the fits' accuracy, a few tenths of a percent), so a white base
    /// reflects everything; the nonlinear one reflects less, `F + (1 - F) R (1 - Fdr) / (1 - R
    /// Fdr)`. Sampling agrees with quadrature.
    #[test]
    fn energy_is_conserved_as_the_layer_model_says() {
        for ior in [1.2f32, 1.49, 1.9] {
            let fdr_int = fdr_by_quadrature(1.0 / ior) as f32;
            for deg in [0.0f32, 45.0, 80.0] {
                let (n, wo) = setup(deg);
                let f = fresnel_exact(wo.dot(n), ior);
                for (albedo, nonlinear) in [(1.0f32, false), (0.5, false), (1.0, true), (0.5, true)] {
                    let m = plastic(Vec3::splat(albedo), ior, nonlinear);
                    let q = albedo_by_quadrature(&m, wo, n).x;
                    let want = match nonlinear {
                        false => f + (1.0 - f) * albedo,
                        true => f + (1.0 - f) * albedo * (1.0 - fdr_int) / (1.0 - albedo * fdr_int),
                    };
                    let what = format!("ior {ior}, {deg} deg, albedo {albedo}, nonlinear {nonlinear}");
                    assert!((q - want).abs() < 4e-3, "{what}: {q} vs {want}");
                    let (e, se) = albedo_by_sampling(&m, wo, n, 50_000);
                    assert!((q - e.x).abs() < 4.0 * se + 1e-3, "{what}: {q} vs {e}");
                }
            }
        }
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
        let m = Plastic::new(Vec3::new(0.9, 0.6, 0.3), Vec3::ONE, 1.7, true, false);
        for _ in 0..500 {
            let (wo, wi) = (dir(), dir());
            let a = m.eval(wo, wi, n).f_cos / wi.dot(n);
            let b = m.eval(wi, wo, n).f_cos / wo.dot(n);
            assert!((a - b).abs().max_element() <= 1e-5 * a.max_element().max(1e-3), "{a} {b}");
        }
    }

    #[test]
    fn black_from_below_unless_two_sided() {
        let one = plastic(Vec3::splat(0.5), 1.5, false);
        let two = Plastic { two_sided: true, ..one };
        let (n, wo) = setup(30.0);
        let (_, wi) = setup(50.0);
        for uc in [0.01f32, 0.99] {
            assert!(one.sample(-wo, n, Vec2::splat(0.3), uc).is_none());
            let (a, b) = (
                two.sample(-wo, n, Vec2::splat(0.3), uc).unwrap(),
                one.sample(-wo, -n, Vec2::splat(0.3), uc).unwrap(),
            );
            assert_eq!((a.wi, a.weight, a.pdf, a.delta), (b.wi, b.weight, b.pdf, b.delta));
        }
        assert_eq!(one.eval(-wo, -wi, n), BsdfEval::ZERO);
        assert_eq!(one.eval(wo, -wi, n), BsdfEval::ZERO);
        assert_eq!(two.eval(-wo, -wi, n), one.eval(-wo, -wi, -n));
        assert!(one.eval(wo, wi, n).pdf > 0.0);
    }

    /// `((theta, phi) of wo, (theta, phi) of wi, f cos, pdf)` in degrees about the normal z.
    type MitsubaEval = ((i32, i32), (i32, i32), [f32; 3], f32);

    /// The direction of polar angle `theta` and azimuth `phi` (degrees) about z.
    fn polar(theta: i32, phi: i32) -> Vec3A {
        let (t, p) = ((theta as f32).to_radians(), (phi as f32).to_radians());
        Vec3A::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    /// Mitsuba 3.9.1's `eval_pdf` (scalar_rgb) of the same materials for the same directions,
    /// printed by `scripts/mitsuba-plastic/eval.py` (Mitsuba's `si.wi` is our `wo`).
    #[test]
    fn eval_and_pdf_match_mitsuba() {
        let bk7 = 1.5046 / 1.000277;
        let cases: [(Plastic, [MitsubaEval; 8]); 2] = [
            (
                Plastic::new(Vec3::new(0.1, 0.27, 0.36), Vec3::ONE, 1.9 / 1.000277, false, false),
                [
                    ((0, 0), (30, 0), [0.02633883, 0.07111483, 0.09481978], 0.1917526),
                    ((30, 0), (30, 180), [0.02628431, 0.07096764, 0.09462352], 0.1905028),
                    ((30, 0), (45, 90), [0.02122437, 0.05730579, 0.07640773], 0.1555449),
                    ((60, 0), (20, 200), [0.02698125, 0.07284937, 0.0971325], 0.1743976),
                    ((80, 0), (70, 180), [0.005691415, 0.01536682, 0.0204891], 0.02706923),
                    ((10, 0), (85, 45), [0.001086283, 0.002932964, 0.003910619], 0.01929641),
                    ((45, 0), (45, 180), [0.02099029, 0.05667379, 0.07556506], 0.1502682),
                    ((70, 0), (10, 30), [0.02570066, 0.06939178, 0.09252238], 0.1424519),
                ],
            ),
            (
                Plastic::new(Vec3::new(0.8, 0.5, 0.2), Vec3::ONE, bk7, true, false),
                [
                    ((0, 0), (30, 0), [0.1720965, 0.07994701, 0.02544616], 0.2541862),
                    ((30, 0), (30, 180), [0.1718218, 0.0798194, 0.02540555], 0.2534075),
                    ((30, 0), (45, 90), [0.1390094, 0.06457648, 0.02055391], 0.2069064),
                    ((60, 0), (20, 200), [0.1773658, 0.08239486, 0.02622528], 0.249779),
                    ((80, 0), (70, 180), [0.03745577, 0.01739999, 0.005538205], 0.04795692),
                    ((10, 0), (85, 45), [0.006992185, 0.003248202, 0.001033863], 0.02558019),
                    ((45, 0), (45, 180), [0.1377386, 0.06398612, 0.02036601], 0.2033063),
                    ((70, 0), (10, 30), [0.1691901, 0.07859683, 0.02501642], 0.2215459),
                ],
            ),
        ];
        for (m, evals) in cases {
            for ((to, po), (ti, pi), f_cos, pdf) in evals {
                let e = m.eval(polar(to, po), polar(ti, pi), Vec3A::Z);
                let want = Vec3::from(f_cos);
                let what = format!("{m:?}, wo ({to}, {po}), wi ({ti}, {pi})");
                assert!(
                    (e.f_cos - want).abs().max_element() <= 1e-4 * want.max_element(),
                    "{what}: {} vs {want}",
                    e.f_cos
                );
                assert!((e.pdf - pdf).abs() <= 1e-4 * pdf, "{what}: pdf {} vs {pdf}", e.pdf);
            }
        }
    }

    /// Textured colours: the albedo is slot 0 and the tint slot 1, as `set_color` sets them at
    /// a hit; the sampling weight comes from the textures' means and stays.
    #[test]
    fn textured_colours_fill_their_slots() {
        let means = |name: &str| match name {
            "wood" => (3, Vec3::new(0.6, 0.4, 0.2)),
            _ => (5, Vec3::splat(0.5)),
        };
        for text in [
            r#"Plastic(albedo: "wood", tint: "grey")"#,
            r#"RoughPlastic(albedo: "wood", tint: "grey", alpha: 0.2)"#,
        ] {
            let (mut m, slots) = Material::build(&parse(text).unwrap(), &mut |n| means(n));
            assert_eq!(slots.colors, [Some(3), Some(5)], "{text}");
            let weight = |m: &Material| match m {
                Material::Plastic(p) => (p.albedo, p.tint, p.specular_weight),
                Material::RoughPlastic(p) => (p.albedo, p.tint, p.specular_weight),
                _ => unreachable!(),
            };
            let (albedo, tint, w) = weight(&m);
            assert_eq!((albedo, tint), (Vec3::new(0.6, 0.4, 0.2), Vec3::splat(0.5)), "{text}");
            assert!((w - 0.5 / (0.5 + 0.4)).abs() < 1e-6, "{text}: {w}");
            m.set_color(0, Vec3::new(0.1, 0.2, 0.3));
            m.set_color(1, Vec3::new(0.9, 1.5, 0.7));
            assert_eq!(weight(&m), (Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.9, 1.0, 0.7), w), "{text}");
        }
    }

    #[test]
    fn descriptions_parse_and_bad_values_are_refused() {
        let m = build("Plastic(albedo: (0.1, 0.27, 0.36))");
        assert_eq!(
            m,
            Material::Plastic(Plastic::new(Vec3::new(0.1, 0.27, 0.36), Vec3::ONE, 1.49, false, false))
        );
        assert_eq!(m.shading(), Shading::Glossy);
        let Material::Plastic(p) = m else { unreachable!() };
        // Mitsuba's weight for this colour: 1 / (1 + 0.2433).
        assert!((p.specular_weight - 1.0 / (1.0 + 0.73 / 3.0)).abs() < 1e-6);
        let m = build(
            "Plastic(albedo: (0.5, 0.5, 0.5), tint: (0.5, 1, 1), ior: 1.9, nonlinear: true, two_sided: true)",
        );
        assert_eq!(
            m,
            Material::Plastic(Plastic::new(Vec3::splat(0.5), Vec3::new(0.5, 1.0, 1.0), 1.9, true, true))
        );
        for (text, message) in [
            ("Plastic(albedo: (1.5, 0.5, 0.5))", "albedo with components in [0, 1]"),
            ("Plastic(albedo: (0.5, 0.5, 0.5), tint: (-1, 1, 1))", "albedo with components in [0, 1]"),
            ("Plastic(albedo: (0.5, 0.5, 0.5), ior: 0)", "coating index of refraction in [0.1, 10], found 0"),
            ("Plastic(albedo: (0.5, 0.5, 0.5), ior: 11)", "in [0.1, 10], found 11"),
            ("Plastic(tint: (1, 1, 1))", "albedo"),
            ("Plastic(albedo: (0.5, 0.5, 0.5), alpha: 0.1)", "alpha"),
        ] {
            let e = parse(text).unwrap_err();
            assert!(e.contains(message), "{text}: {e}");
        }
    }
}
