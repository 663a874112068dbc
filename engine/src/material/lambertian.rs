//! Lambertian diffuse reflection, sampled with the cosine density (Shirley, "Ray Tracing: The
//! Rest of Your Life"): two-sided by default, or one-sided as Mitsuba 3's `diffuse`
//! (`src/bsdfs/diffuse.cpp`: black where `wo` or `wi` lies below the shading normal).
//! The integrators shade it with their Lambertian lane kernel (light sampling and MIS);
//! [`sample`] and [`eval`] here are the reference that kernel is tested against.

use super::{BsdfEval, BsdfSample, Colors, MaterialModel, Reads, Shading};
use crate::format::{Albedo, Color};
use crate::math::{Frame, concentric_disk};
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// Diffuse; albedo components in [0, 1]; two-sided unless `two_sided: false` (default true), which
/// makes it black seen from behind its shading normal (Mitsuba's `diffuse`: a path that meets its
/// back ends there).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct LambertianDesc {
    /// Reflectance, components in [0, 1], or a texture (clamped to [0, 1]).
    pub albedo: Color<Albedo>,
    /// Reflects on both sides alike (default); false: black seen from behind its shading
    /// normal.
    #[serde(default = "yes")]
    pub two_sided: bool,
}

fn yes() -> bool {
    true
}

/// Ideal diffuse reflector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambertian {
    /// Reflectance in [0, 1].
    pub albedo: Vec3,
    /// Reflects on both sides; else only where `wo` and `wi` lie above the shading normal.
    pub two_sided: bool,
}

impl MaterialModel for Lambertian {
    type Desc = LambertianDesc;
    const SHADING: Shading = Shading::Diffuse;

    fn build(desc: &LambertianDesc, colors: &mut Colors) -> Self {
        Self { albedo: colors.get(&desc.albedo).min(Vec3::ONE), two_sided: desc.two_sided }
    }

    #[inline]
    fn set_color(&mut self, _slot: usize, value: Vec3) {
        self.albedo = value.clamp(Vec3::ZERO, Vec3::ONE);
    }

    #[inline]
    fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, _uc: f32) -> Option<BsdfSample> {
        if self.black_behind(wo, n) {
            return None;
        }
        sample(self.albedo, wo, n, u)
    }

    /// The cosine lobe's value and density, for hits shaded path by path (a bump or normal
    /// map tilts the normal: see [`crate::material::wrap`]); the lane kernel computes the same.
    #[inline]
    fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        if self.black_behind(wo, n) {
            return BsdfEval::ZERO;
        }
        let (f_cos, pdf) = eval(self.albedo, wo, wi, n);
        BsdfEval { f_cos, pdf }
    }

    fn one_sided(&self) -> bool {
        !self.two_sided
    }

    /// A diffuse kind: light tracing connects it to the camera.
    fn sharpest_alpha(&self) -> Option<f32> {
        Some(f32::INFINITY)
    }

    #[inline]
    fn albedo(&self) -> Vec3 {
        self.albedo
    }

    /// The cosine lobe's two numbers, no lobe choice.
    fn reads(&self) -> Reads {
        Reads { dir: true, lobe: false }
    }
}

impl Lambertian {
    /// One-sided and seen from behind (or edge-on): black, the path ends here.
    #[inline]
    pub fn black_behind(&self, wo: Vec3A, n: Vec3A) -> bool {
        !self.two_sided && !(wo.dot(n) > 0.0)
    }
}

/// Cosine-weighted direction about +z: density `cos(theta) / pi`.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3A {
    cosine_hemisphere_plain(u).into()
}

/// [`cosine_hemisphere`] on plain numbers, for the lane kernels.
#[inline(always)]
pub fn cosine_hemisphere_plain(u: Vec2) -> glam::Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    glam::Vec3::new(d.x, d.y, z)
}

/// Samples `wi` on the side of `wo`.
#[inline]
pub fn sample(albedo: Vec3, wo: Vec3A, n: Vec3A, u: Vec2) -> Option<BsdfSample> {
    let nf = if wo.dot(n) < 0.0 { -n } else { n };
    let local = cosine_hemisphere(u);
    let pdf = local.z * FRAC_1_PI;
    if pdf <= 0.0 {
        return None;
    }
    let wi = Frame::from_normal(nf).to_world(local);
    Some(BsdfSample { wi, weight: albedo, pdf, eta: 1.0, delta: false, null: false })
}

/// `f |cos|` and pdf.
#[inline]
pub fn eval(albedo: Vec3, wo: Vec3A, wi: Vec3A, n: Vec3A) -> (Vec3, f32) {
    let (co, ci) = (wo.dot(n), wi.dot(n));
    if co * ci <= 0.0 {
        return (Vec3::ZERO, 0.0);
    }
    let c = ci.abs() * FRAC_1_PI;
    (albedo * c, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::chi2::{chi2, chi2_critical};

    #[test]
    fn sampling_matches_cosine_pdf_chi2() {
        let n = Vec3A::new(0.3, 0.5, -0.8).normalize();
        let wo = Vec3A::new(0.1, 0.2, -1.0).normalize();
        let (stat, dof) = chi2(
            |u, _| sample(Vec3::ONE, wo, n, u).map(|s| s.wi),
            |wi| eval(Vec3::ONE, wo, wi, n).1,
            n,
            -1.0,
            1_000_000,
        );
        assert!(stat < chi2_critical(dof), "chi2 {stat} dof {dof}");
    }

    #[test]
    fn sampled_pdf_and_weight_agree_with_eval() {
        let n = Vec3A::Y;
        let wo = Vec3A::new(0.0, 1.0, 1.0).normalize();
        let albedo = Vec3::new(0.2, 0.5, 0.9);
        for i in 0..100 {
            let u = Vec2::new((i as f32 + 0.5) / 100.0, ((i * 7 % 100) as f32 + 0.5) / 100.0);
            let s = sample(albedo, wo, n, u).unwrap();
            let (f, pdf) = eval(albedo, wo, s.wi, n);
            assert!((pdf - s.pdf).abs() < 1e-4 * pdf.max(1.0));
            assert!((f / pdf - s.weight).length() < 1e-4);
        }
    }

    /// One-sided, it scatters only seen from the front; two-sided, from both sides.
    #[test]
    fn one_sided_is_black_from_behind() {
        let n = Vec3A::Z;
        let (front, back) = (Vec3A::new(0.3, 0.0, 0.9).normalize(), Vec3A::new(0.3, 0.0, -0.9).normalize());
        let u = Vec2::new(0.3, 0.6);
        for two_sided in [false, true] {
            let m = Lambertian { albedo: Vec3::splat(0.5), two_sided };
            assert!(m.sample(front, n, u, 0.0).is_some_and(|s| s.wi.dot(n) > 0.0));
            assert_eq!(m.sample(back, n, u, 0.0).is_some(), two_sided);
            assert_eq!(m.black_behind(back, n), !two_sided);
            assert!(!m.black_behind(front, n));
        }
    }

    #[test]
    fn reflectance_equals_albedo_by_quadrature() {
        // Directional albedo: integral of f |cos| over the hemisphere, midpoint rule in (cos, phi).
        let albedo = Vec3::new(0.73, 0.4, 0.1);
        let n = Vec3A::Z;
        let wo = Vec3A::new(0.6, 0.0, 0.8);
        let (nt, np) = (400, 200);
        let mut sum = Vec3::ZERO;
        for i in 0..nt {
            for j in 0..np {
                let z = (i as f32 + 0.5) / nt as f32;
                let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                let s = (1.0 - z * z).sqrt();
                let wi = Vec3A::new(s * phi.cos(), s * phi.sin(), z);
                sum += eval(albedo, wo, wi, n).0;
            }
        }
        let r = sum * (std::f32::consts::TAU / (nt * np) as f32);
        assert!((r - albedo).abs().max_element() < 1e-3, "{r}");
    }
}
