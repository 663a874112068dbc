//! Rough dielectric: microfacet reflection and transmission after Walter, Marschner, Li and
//! Torrance 2007, "Microfacet Models for Refraction through Rough Surfaces", with the GGX or the
//! Beckmann distribution, separable Smith shadowing-masking and visible-normal sampling (see
//! [`super::microfacet`]).
//! Two-sided: from inside (`wo . n < 0`) the relative index of refraction is `1 / ior`.
//!
//! With `eta` the relative IOR (`n_t / n_i`, from the side of `wo`), the half vector `h`, and
//! `F` the exact dielectric Fresnel reflectance at `wo . h`:
//! - reflection: `f = F D(h) G1(wo) G1(wi) / (4 |cos wo| |cos wi|)`, `h = normalize(wo + wi)`;
//! - transmission (Walter et al. eq. 21, pbrt-v4's `DielectricBxDF`):
//!   `f = (1 - F) D(h) G1(wo) G1(wi) |wi.h| |wo.h| / (|cos wo| |cos wi| (wi.h + wo.h / eta)^2)`,
//!   `h = +-normalize(wo + eta wi)` on the side of `n`, and the radiance scaled by `1 / eta^2` as
//!   the smooth [`super::dielectric::Dielectric`] does.
//!
//! Sampling picks a visible normal, then reflects with probability `F` and refracts otherwise,
//! so the pdf is `D_wo(h) / (4 |wo.h|) F` or `D_wo(h) |wi.h| / (wi.h + wo.h / eta)^2 (1 - F)`.
//! Single scattering only (energy that would scatter again between microfacets is lost).
//! Below [`SMOOTH_ALPHA`] (or with `ior` 1) it is the smooth dielectric.

use super::dielectric::{Fresnel, fresnel_exact, refract_plain};
use super::microfacet::{
    Beckmann, Distribution, Ggx, Microfacet, PlainFrame, Roughness, SMOOTH_ALPHA, Smith,
};
use super::{BsdfEval, BsdfSample, Colors, MaterialModel, Shading, Specular};
use crate::format::{Positive, Scalar};
use crate::math::normalized;
use glam::{Vec2, Vec3, Vec3A};

/// Rough glass (Walter et al. 2007), `distribution` `Ggx` (default) or `Beckmann` as
/// `RoughConductor`'s: reflection or refraction through the sampled microfacet chosen by exact
/// Fresnel, radiance scaled by 1/eta^2 on refraction as `Dielectric`; two-sided. `alpha` in [0, 1]
/// or a texture as `RoughConductor`'s; below 0.001 (or with `ior` 1) the smooth `Dielectric`.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RoughDielectricDesc {
    /// Index of refraction inside (> 0; outside is 1).
    pub ior: Positive,
    /// Roughness in [0, 1] or a texture (its luminance, limited to [0, 1]); below 1e-3 smooth
    /// glass.
    pub alpha: Scalar<Roughness>,
    /// `Ggx` (default) or `Beckmann`.
    #[serde(default)]
    pub distribution: Distribution,
    /// `Separable` (default) or `HeightCorrelated` Smith shadowing-masking.
    #[serde(default)]
    pub smith: Smith,
}

/// Rough clear dielectric: microfacet reflection and transmission weighted by Fresnel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// Index of refraction inside (outside is 1).
    pub ior: f32,
    /// Roughness in [0, 1].
    pub alpha: f32,
    /// The distribution of microfacet normals.
    pub distribution: Distribution,
    /// The shadowing-masking term's form.
    pub smith: Smith,
}

impl RoughDielectric {
    /// Smooth glass: alpha below [`SMOOTH_ALPHA`], or an index of 1 (light passes straight
    /// through, a delta the microfacet formulas cannot express).
    #[inline]
    pub fn is_smooth(&self) -> bool {
        self.alpha < SMOOTH_ALPHA || self.ior == 1.0
    }

    /// The relative IOR seen from `wo` and the normal on its side, or `None` at grazing (for
    /// the tests: the BSDF's code takes [`Self::side_plain`]).
    #[cfg(test)]
    fn side(&self, wo: Vec3A, n: Vec3A) -> Option<(f32, Vec3A)> {
        let cos_o = wo.dot(n);
        if cos_o > 0.0 {
            Some((self.ior, n))
        } else if cos_o < 0.0 {
            Some((1.0 / self.ior, -n))
        } else {
            None
        }
    }

    /// Whether the lane kernel shades it ([`Self::eval_plain`], [`Self::sample_plain`]): rough.
    #[inline]
    pub fn shaded_in_lanes(&self) -> bool {
        !self.is_smooth()
    }

    /// The relative IOR seen from `wo` (of cosine `cos_o` with `n`) and the normal on its side.
    #[inline(always)]
    fn side_plain(&self, cos_o: f32, n: Vec3) -> (f32, Vec3) {
        if cos_o > 0.0 { (self.ior, n) } else { (1.0 / self.ior, -n) }
    }

    /// [`MaterialModel::sample`] off the smooth limit with the distribution `md` (a visible
    /// normal from `u`, then reflection if `uc < F`, refraction otherwise), on plain numbers
    /// and without branches: the one source of the one-path code and the lane kernel. The
    /// sample, and whether there is one (none at grazing, or when the direction ends on the
    /// wrong side of the surface: single-scattering loss).
    #[inline(always)]
    pub fn sample_plain<M: Microfacet<Vec3>>(
        &self,
        md: M,
        wo: Vec3,
        n: Vec3,
        u: Vec2,
        uc: f32,
    ) -> (DielectricSample, bool) {
        let cos_o = wo.dot(n);
        let (eta, nf) = self.side_plain(cos_o, n);
        let f = PlainFrame::new(nf);
        let lo = f.local(wo);
        let m = md.sample_visible(lo, u);
        let cos_om = lo.dot(m);
        let pdf_m = md.pdf_visible(lo, m);
        let fr = fresnel_exact(cos_om.min(1.0), eta);
        // Both lobes, then the one `uc` chose.
        let lr = 2.0 * lo.dot(m) * m - lo;
        // f cos_i / pdf = G / G1(wo): F, D and G1(wo) / cos_o cancel.
        let (pdf_r, weight_r) = (pdf_m / (4.0 * cos_om) * fr, md.shadowing(self.smith, lo, lr));
        let (lt, refracts) = refract_plain(lo, m, eta);
        let lt = normalized(lt);
        let cos_im = lt.dot(m);
        let den = (cos_im + cos_om / eta).powi(2);
        // f cos_i / pdf = G / G1(wo) / eta^2 (the radiance scaling).
        let pdf_t = pdf_m * -cos_im / den * (1.0 - fr);
        let weight_t = md.shadowing(self.smith, lo, lt) / (eta * eta);
        let reflects = uc < fr;
        let (li, pdf, weight, eta) = match reflects {
            true => (lr, pdf_r, weight_r, 1.0),
            false => (lt, pdf_t, weight_t, eta),
        };
        let leaves = match reflects {
            true => lr.z > 0.0,
            false => refracts && lt.z < 0.0 && cos_im < 0.0,
        };
        let valid =
            cos_o != 0.0 && lo.z > 0.0 && m.z > 0.0 && cos_om > 0.0 && leaves && pdf > 0.0 && pdf.is_finite();
        let wi = f.world_unit(li);
        (DielectricSample { wi, weight, pdf, eta }, valid)
    }

    /// [`MaterialModel::eval`] off the smooth limit with the distribution `md`, on plain
    /// numbers and without branches as [`Self::sample_plain`].
    #[inline(always)]
    pub fn eval_plain<M: Microfacet<Vec3>>(&self, md: M, wo: Vec3, wi: Vec3, n: Vec3) -> BsdfEval {
        let cos_o = wo.dot(n);
        let (eta, nf) = self.side_plain(cos_o, n);
        let f = PlainFrame::new(nf);
        let (lo, li) = (f.local(wo), f.local(wi));
        let reflection = li.z > 0.0;
        // The (generalised) half vector on the side of the normal.
        let h = if reflection { lo + li } else { lo + eta * li };
        let m = if h.z < 0.0 { -h } else { h }.normalize_or_zero();
        let (cos_om, cos_im) = (lo.dot(m), li.dot(m));
        let fr = fresnel_exact(cos_om.min(1.0), eta);
        // D_wo(m) = G1(wo) (wo.m) D(m) / cos_o: the density of the sampled normal.
        let d_wo = md.g1_over_cos(lo) * cos_om * md.d(m);
        let g = md.shadowing(self.smith, lo, li);
        let pdf_r = d_wo / (4.0 * cos_om);
        let den = (cos_im + cos_om / eta).powi(2);
        // |d h / d wi| = |wi.h| / (wi.h + wo.h / eta)^2 (Walter et al. eq. 17).
        let pdf_t = d_wo * -cos_im / den;
        let (f_cos, pdf) = match reflection {
            true => (pdf_r * fr * g, pdf_r * fr),
            false => (pdf_t * (1.0 - fr) * g / (eta * eta), pdf_t * (1.0 - fr)),
        };
        // Microfacets seen from behind by either direction do not scatter.
        let valid = cos_o != 0.0
            && lo.z > 0.0
            && li.z != 0.0
            && m.z > 0.0
            && cos_om > 0.0
            && (cos_im > 0.0) == reflection
            && cos_im != 0.0
            && pdf > 0.0
            && pdf.is_finite()
            && f_cos.is_finite();
        match valid {
            true => BsdfEval { f_cos: Vec3::splat(f_cos), pdf },
            false => BsdfEval::ZERO,
        }
    }

    /// [`Self::sample_plain`] as a [`BsdfSample`].
    #[inline(always)]
    fn sample_rough<M: Microfacet<Vec3>>(
        &self,
        md: M,
        wo: Vec3A,
        n: Vec3A,
        u: Vec2,
        uc: f32,
    ) -> Option<BsdfSample> {
        let (s, valid) = self.sample_plain(md, wo.into(), n.into(), u, uc);
        valid.then(|| s.into())
    }

    /// [`Self::sample_rough`] with Beckmann, out of line: inlined beside GGX's, it made the
    /// compiler lay out GGX's path less well (0.4% more instructions on materials-env).
    #[inline(never)]
    fn sample_beckmann(&self, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
        self.sample_rough(Beckmann { alpha: self.alpha }, wo, n, u, uc)
    }

    /// [`Self::eval_plain`] with Beckmann, out of line as [`Self::sample_beckmann`].
    #[inline(never)]
    fn eval_beckmann(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        self.eval_plain(Beckmann { alpha: self.alpha }, wo.into(), wi.into(), n.into())
    }
}

/// A sampled direction of [`RoughDielectric::sample_plain`], on plain numbers.
#[derive(Clone, Copy, Debug, Default)]
pub struct DielectricSample {
    /// The unit direction (world space).
    pub wi: Vec3,
    /// `f cos / pdf` (grey).
    pub weight: f32,
    /// Its solid-angle density.
    pub pdf: f32,
    /// The relative IOR crossed (1 on reflection).
    pub eta: f32,
}

impl From<DielectricSample> for BsdfSample {
    #[inline(always)]
    fn from(s: DielectricSample) -> Self {
        BsdfSample {
            wi: s.wi.into(),
            weight: Vec3::splat(s.weight),
            pdf: s.pdf,
            eta: s.eta,
            delta: false,
            null: false,
        }
    }
}

impl MaterialModel for RoughDielectric {
    type Desc = RoughDielectricDesc;
    const SHADING: Shading = Shading::Glossy;

    fn build(desc: &RoughDielectricDesc, colors: &mut Colors) -> Self {
        let alpha = colors.scalar(&desc.alpha);
        Self { ior: desc.ior.0, alpha, distribution: desc.distribution, smith: desc.smith }
    }

    #[inline]
    fn set_scalar(&mut self, _slot: usize, value: f32) {
        self.alpha = value.clamp(0.0, 1.0);
    }

    /// A visible normal from `u`, then reflection if `uc < F`, refraction otherwise; `None` when
    /// the direction ends on the wrong side of the surface (single-scattering loss).
    fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
        if self.is_smooth() {
            return super::dielectric::sample(self.ior, Fresnel::Exact, wo, n, uc);
        }
        match self.distribution {
            Distribution::Ggx => self.sample_rough(Ggx { alpha: self.alpha }, wo, n, u, uc),
            Distribution::Beckmann => self.sample_beckmann(wo, n, u, uc),
        }
    }

    fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        if self.is_smooth() {
            return BsdfEval::ZERO;
        }
        match self.distribution {
            Distribution::Ggx => self.eval_plain(Ggx { alpha: self.alpha }, wo.into(), wi.into(), n.into()),
            Distribution::Beckmann => self.eval_beckmann(wo, wi, n),
        }
    }

    /// Clear glass shows as white in the albedo guide.
    /// Its width.
    fn sharpest_alpha(&self) -> Option<f32> {
        Some(self.alpha)
    }

    fn albedo(&self) -> Vec3 {
        Vec3::ONE
    }

    fn specular(&self) -> Specular {
        if self.is_smooth() { Specular::Glass { ior: self.ior } } else { Specular::No }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::dielectric::refract;
    use crate::material::microfacet::testing::assert_chi2;
    use crate::math::{Frame, reflect};

    /// A normal that is not an axis, and the direction `deg` degrees from it, outside or inside.
    fn setup(deg: f32, inside: bool) -> (Vec3A, Vec3A) {
        let n = Vec3A::new(0.2, -0.3, 0.9).normalize();
        let t = deg.to_radians();
        let z = if inside { -t.cos() } else { t.cos() };
        (n, Frame::from_normal(n).to_world(Vec3A::new(t.sin(), 0.0, z)))
    }

    /// Rough glass of index 1.5, separable shadowing.
    fn glass(alpha: f32, distribution: Distribution) -> RoughDielectric {
        RoughDielectric { ior: 1.5, alpha, distribution, smith: Smith::Separable }
    }

    /// Both distributions.
    const DISTRIBUTIONS: [Distribution; 2] = [Distribution::Ggx, Distribution::Beckmann];
    const ALPHAS: [f32; 3] = [0.05, 0.2, 0.6];
    const ANGLES: [f32; 3] = [1.0, 60.0, 85.0];

    /// Reflection and transmission separately, each about its own (smooth) direction, so that
    /// narrow lobes get their own cells.
    fn chi2_both_lobes(inside: bool, distribution: Distribution) {
        for alpha in ALPHAS {
            for deg in ANGLES {
                let m = glass(alpha, distribution);
                let (n, wo) = setup(deg, inside);
                let (eta, nf) = m.side(wo, n).unwrap();
                let what = format!("{distribution:?}, inside {inside}, alpha {alpha}, {deg} deg");
                let on_side = |wi: Vec3A, up: bool| (wi.dot(nf) > 0.0) == up;
                let dof = assert_chi2(
                    &format!("{what}, reflection"),
                    |u, uc| m.sample(wo, n, u, uc).map(|s| s.wi).filter(|&w| on_side(w, true)),
                    |wi| if on_side(wi, true) { m.eval(wo, wi, n).pdf } else { 0.0 },
                    (nf, reflect(wo, nf), alpha),
                    400_000,
                );
                assert!(dof > 20, "{what}, reflection: {dof}");
                let dof = assert_chi2(
                    &format!("{what}, transmission"),
                    |u, uc| m.sample(wo, n, u, uc).map(|s| s.wi).filter(|&w| on_side(w, false)),
                    |wi| if on_side(wi, false) { m.eval(wo, wi, n).pdf } else { 0.0 },
                    // From outside the transmitted lobe is narrower than the reflected one (by
                    // about 1 - 1 / eta): cells a third as wide resolve Beckmann's Gaussian peak.
                    (
                        nf,
                        refract(wo, nf, eta).map_or(-nf, |w| w.normalize()),
                        if inside { alpha } else { alpha / 3.0 },
                    ),
                    400_000,
                );
                // From inside beyond the critical angle, little is transmitted.
                if !inside || deg < 40.0 {
                    assert!(dof > 20, "{what}, transmission: {dof}");
                }
            }
        }
    }

    #[test]
    fn sampling_matches_eval_pdf_chi2_from_outside() {
        chi2_both_lobes(false, Distribution::Ggx);
    }

    #[test]
    fn sampling_matches_eval_pdf_chi2_from_inside() {
        chi2_both_lobes(true, Distribution::Ggx);
    }

    #[test]
    fn beckmann_sampling_matches_eval_pdf_chi2_from_outside() {
        chi2_both_lobes(false, Distribution::Beckmann);
    }

    #[test]
    fn beckmann_sampling_matches_eval_pdf_chi2_from_inside() {
        chi2_both_lobes(true, Distribution::Beckmann);
    }

    #[test]
    fn sample_weight_and_pdf_agree_with_eval() {
        let mut r = crate::testing::uniform(7);
        for (inside, distribution) in DISTRIBUTIONS.iter().flat_map(|&d| [(false, d), (true, d)]) {
            for alpha in [0.01f32, 0.05, 0.2, 0.6, 1.0] {
                for deg in [0.0f32, 30.0, 60.0, 85.0, 89.5] {
                    let m = glass(alpha, distribution);
                    let (n, wo) = setup(deg, inside);
                    let (eta, nf) = m.side(wo, n).unwrap();
                    let (mut reflected, mut transmitted) = (0, 0);
                    for _ in 0..400 {
                        let Some(s) = m.sample(wo, n, Vec2::new(r(), r()), r()) else { continue };
                        let e = m.eval(wo, s.wi, n);
                        let what = format!("{distribution:?}, inside {inside}, alpha {alpha}, {deg} deg");
                        assert!(!s.delta && (s.wi.length() - 1.0).abs() < 1e-5, "{what}");
                        if s.wi.dot(nf) > 0.0 {
                            reflected += 1;
                            assert_eq!(s.eta, 1.0, "{what}");
                        } else {
                            transmitted += 1;
                            assert_eq!(s.eta, eta, "{what}");
                        }
                        let w = e.f_cos / e.pdf;
                        assert!(
                            (s.weight - w).abs().max_element() <= 1e-3 * w.max_element(),
                            "{what}: {} vs {w}",
                            s.weight
                        );
                        // Ill-conditioned for a very narrow lobe at grazing incidence (the half
                        // vector cancels), as for the conductor.
                        let tol = if alpha < 0.05 && deg > 89.0 { 5e-3 } else { 1e-3 };
                        assert!((s.pdf - e.pdf).abs() <= tol * e.pdf, "{what}: {} vs {}", s.pdf, e.pdf);
                    }
                    assert!(reflected > 0 && (transmitted > 0 || inside), "{inside} {alpha} {deg}");
                }
            }
        }
    }

    /// Mean of `weight * eta^2` (the energy: the radiance scaling removed, as the smooth
    /// dielectric's test does), absorbed samples counting 0, and its standard error.
    fn energy_by_sampling(m: &RoughDielectric, wo: Vec3A, n: Vec3A, count: usize) -> (f64, f64) {
        let mut r = crate::testing::uniform(13);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..count {
            if let Some(s) = m.sample(wo, n, Vec2::new(r(), r()), r()) {
                let w = (s.weight.x * s.eta * s.eta) as f64;
                sum += w;
                sum2 += w * w;
            }
        }
        let mean = sum / count as f64;
        // At least 0: rounding may take it below when every weight is the same.
        (mean, ((sum2 / count as f64 - mean * mean) / count as f64).max(0.0).sqrt())
    }

    /// The same by quadrature of `eval` over the sphere (uniform grid in (cos theta, phi)),
    /// transmission times `eta^2`: independent of `sample`.
    fn energy_by_quadrature(m: &RoughDielectric, wo: Vec3A, n: Vec3A) -> f64 {
        let (eta, nf) = m.side(wo, n).unwrap();
        let frame = Frame::from_normal(nf);
        let (nz, np) = (4000, 500);
        let mut sum = 0.0f64;
        for i in 0..nz {
            let z = -1.0 + 2.0 * (i as f32 + 0.5) / nz as f32;
            let s = (1.0 - z * z).sqrt();
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                let wi = frame.to_world(Vec3A::new(s * phi.cos(), s * phi.sin(), z));
                let scale = if z > 0.0 { 1.0 } else { eta * eta };
                sum += (m.eval(wo, wi, n).f_cos.x * scale) as f64;
            }
        }
        sum * 2.0 * std::f64::consts::TAU / (nz * np) as f64
    }

    #[test]
    fn white_furnace_never_exceeds_one() {
        for (inside, distribution) in DISTRIBUTIONS.iter().flat_map(|&d| [(false, d), (true, d)]) {
            for alpha in [0.05f32, 0.2, 0.6, 1.0] {
                for deg in [0.0f32, 30.0, 60.0, 85.0] {
                    let (n, wo) = setup(deg, inside);
                    let (e, se) = energy_by_sampling(&glass(alpha, distribution), wo, n, 50_000);
                    let what = format!("{distribution:?}, inside {inside}, alpha {alpha}, {deg} deg");
                    assert!(e <= 1.0 + 3.0 * se + 1e-4, "{what}: {e}");
                    // Single scattering loses much at alpha 1 and grazing incidence (0.39).
                    assert!(e > 0.3, "{what}: {e}");
                }
            }
        }
    }

    #[test]
    fn energy_by_quadrature_matches_sampling() {
        for (inside, distribution) in DISTRIBUTIONS.iter().flat_map(|&d| [(false, d), (true, d)]) {
            for alpha in [0.3f32, 1.0] {
                for deg in [0.0f32, 60.0] {
                    let m = glass(alpha, distribution);
                    let (n, wo) = setup(deg, inside);
                    let q = energy_by_quadrature(&m, wo, n);
                    let (e, se) = energy_by_sampling(&m, wo, n, 100_000);
                    let what = format!("{distribution:?}, inside {inside}, alpha {alpha}, {deg} deg");
                    assert!(q <= 1.0 + 2e-3, "{what}: {q}");
                    // Beckmann's sampling has the exact masking, its weights the rational one
                    // (0.35%).
                    assert!((q - e).abs() < 4.0 * se + 5e-3, "{what}: {q} vs {e}");
                }
            }
        }
    }

    #[test]
    fn btdf_obeys_generalised_reciprocity() {
        // f(wo, wi) / n(wo)^2 = f(wi, wo) / n(wi)^2 for radiance (Veach 1997, section 5.2), and
        // plain reciprocity for reflection on either side.
        let mut r = crate::testing::uniform(29);
        let n = Vec3A::new(-0.4, 0.1, 0.8).normalize();
        let frame = Frame::from_normal(n);
        let mut dir = |up: bool| {
            let (z, phi) = (r().max(0.01), r() * std::f32::consts::TAU);
            let s = (1.0 - z * z).sqrt();
            frame.to_world(Vec3A::new(s * phi.cos(), s * phi.sin(), if up { z } else { -z }))
        };
        let ior = 1.5f32;
        let index = |w: Vec3A| if w.dot(n) > 0.0 { 1.0 } else { ior };
        let mut nonzero = 0;
        for (alpha, distribution) in DISTRIBUTIONS.iter().flat_map(|&d| [(0.1f32, d), (0.3, d), (1.0, d)]) {
            let m = RoughDielectric { ior, alpha, distribution, smith: Smith::Separable };
            for k in 0..2000 {
                let (wo, wi) = (dir(k % 2 == 0), dir(k % 3 == 0));
                let a = m.eval(wo, wi, n).f_cos.x / wi.dot(n).abs() / index(wo).powi(2);
                let b = m.eval(wi, wo, n).f_cos.x / wo.dot(n).abs() / index(wi).powi(2);
                assert!((a - b).abs() <= 1e-3 * a.max(b) + 1e-6, "{alpha} {wo} {wi}: {a} vs {b}");
                nonzero += (a > 1e-3) as u32;
            }
        }
        assert!(nonzero > 4000, "{nonzero}");
    }

    #[test]
    fn smooth_alpha_is_the_smooth_dielectric() {
        for m in [glass(0.0, Distribution::Ggx), glass(5e-4, Distribution::Beckmann)] {
            for inside in [false, true] {
                let (n, wo) = setup(40.0, inside);
                for uc in [0.01f32, 0.5, 0.99] {
                    let s = m.sample(wo, n, Vec2::new(0.3, 0.6), uc).unwrap();
                    let t = super::super::dielectric::sample(1.5, Fresnel::Exact, wo, n, uc).unwrap();
                    assert!(
                        s.delta && s.wi == t.wi && s.weight == t.weight && s.pdf == t.pdf && s.eta == t.eta
                    );
                    assert_eq!(m.eval(wo, s.wi, n), BsdfEval::ZERO);
                }
            }
            assert_eq!(m.specular(), Specular::Glass { ior: 1.5 });
        }
        let index_matched = RoughDielectric { ior: 1.0, ..glass(0.3, Distribution::Ggx) };
        let wo = Vec3A::new(0.6, 0.0, 0.8);
        let s = index_matched.sample(wo, Vec3A::Z, Vec2::new(0.3, 0.6), 0.5).unwrap();
        assert!(s.delta && (s.wi + wo).length() < 1e-6, "passes straight through");
        assert_eq!(glass(0.2, Distribution::Ggx).specular(), Specular::No);
        assert_eq!(glass(0.2, Distribution::Ggx).albedo(), Vec3::ONE);
    }

    #[test]
    fn grazing_and_degenerate_directions_give_nothing() {
        for m in DISTRIBUTIONS.map(|d| glass(0.3, d)) {
            grazing_and_degenerate(m);
        }
    }

    fn grazing_and_degenerate(m: RoughDielectric) {
        let n = Vec3A::Z;
        assert!(m.sample(Vec3A::X, n, Vec2::splat(0.4), 0.5).is_none());
        assert_eq!(m.eval(Vec3A::X, Vec3A::Z, n), BsdfEval::ZERO);
        assert_eq!(m.eval(Vec3A::Z, Vec3A::X, n), BsdfEval::ZERO);
        // Straight through at normal incidence: the generalised half vector is (1 - eta) n, fine;
        // but wo = -wi with eta = 1 would be degenerate, which is why ior 1 is smooth.
        let e = m.eval(Vec3A::Z, -Vec3A::Z, n);
        assert!(e.pdf > 0.0 && e.f_cos.is_finite());
        for u in [Vec2::ZERO, Vec2::ONE, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)] {
            for deg in [0.0f32, 89.9] {
                let (n, wo) = setup(deg, false);
                if let Some(s) = m.sample(wo, n, u, 0.5) {
                    assert!(s.weight.is_finite() && s.pdf.is_finite() && s.wi.is_finite());
                }
            }
        }
    }

    #[test]
    fn descriptions_parse_and_bad_values_are_refused() {
        let parse = crate::testing::material_desc;
        let d = parse("RoughDielectric(ior: 1.5, alpha: 0.1)").unwrap();
        let (m, _) = crate::material::Material::build(&d, &mut |_| unreachable!());
        assert_eq!(m, crate::material::Material::RoughDielectric(glass(0.1, Distribution::Ggx)));
        let d = parse("RoughDielectric(ior: 1.5, alpha: 0.1, distribution: Beckmann)").unwrap();
        let (m, _) = crate::material::Material::build(&d, &mut |_| unreachable!());
        assert_eq!(m, crate::material::Material::RoughDielectric(glass(0.1, Distribution::Beckmann)));
        assert_eq!(m.shading(), Shading::Glossy);
        let e = parse("RoughDielectric(ior: 1.5, alpha: 2)").unwrap_err();
        assert!(e.contains("expected a roughness alpha in [0, 1], found 2"), "{e}");
        let e = parse("RoughDielectric(ior: 0, alpha: 0.1)").unwrap_err();
        assert!(e.contains("expected a finite number > 0"), "{e}");
    }
}
