//! Smooth dielectric (glass): reflection with probability F and refraction otherwise, with the
//! exact Fresnel equations for unpolarised light or Schlick's approximation, and total internal
//! reflection (Shirley, "Ray Tracing in One Weekend", dielectrics). Radiance is scaled by
//! 1/eta^2 on refraction.

use super::rough_dielectric::DielectricSample;
use super::{BsdfSample, Colors, MaterialModel, Reads, Shading, Specular};
use crate::format::Positive;
use crate::math::normalized;
use glam::{Vec2, Vec3, Vec3A};

/// How a dielectric computes its reflectance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize)]
pub enum Fresnel {
    /// The exact Fresnel equations for unpolarised light (default).
    #[default]
    Exact,
    /// Schlick's approximation (what "Ray Tracing in One Weekend" uses).
    Schlick,
}

/// Smooth glass of index of refraction `ior` (> 0), reflection/refraction chosen by exact Fresnel
/// (or Schlick's approximation with `fresnel: Schlick`; default `Exact`), total internal
/// reflection.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct DielectricDesc {
    /// Index of refraction (> 0).
    pub ior: Positive,
    /// `Exact` (default) or `Schlick`.
    #[serde(default)]
    pub fresnel: Fresnel,
}

/// Smooth clear dielectric (glass), with reflection and refraction weighted by Fresnel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Index of refraction inside (outside is 1).
    pub ior: f32,
    /// Exact or Schlick reflectance.
    pub fresnel: Fresnel,
}

impl MaterialModel for Dielectric {
    type Desc = DielectricDesc;
    const SHADING: Shading = Shading::Sampled;

    fn build(desc: &DielectricDesc, _colors: &mut Colors) -> Self {
        Self { ior: desc.ior.0, fresnel: desc.fresnel }
    }

    #[inline]
    fn sample(&self, wo: Vec3A, n: Vec3A, _u: Vec2, uc: f32) -> Option<BsdfSample> {
        sample(self.ior, self.fresnel, wo, n, uc)
    }

    /// Glass shows as white in the albedo guide.
    /// Delta lobes.
    fn sharpest_alpha(&self) -> Option<f32> {
        Some(0.0)
    }

    fn albedo(&self) -> Vec3 {
        Vec3::ONE
    }

    /// Only the choice between reflection and refraction.
    fn reads(&self) -> Reads {
        Reads { dir: false, lobe: true }
    }

    fn specular(&self) -> Specular {
        Specular::Glass { ior: self.ior }
    }
}

/// Exact unpolarised Fresnel reflectance. `cos_i` >= 0 is measured on the incident side and
/// `eta` = n_transmitted / n_incident.
/// Without branches (total internal reflection selected), for the lane kernels too.
#[inline(always)]
pub fn fresnel_exact(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    let cos_t = (1.0 - sin2_t).sqrt();
    let parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let f = 0.5 * (parl * parl + perp * perp);
    if sin2_t >= 1.0 { 1.0 } else { f }
}

/// Schlick's approximation, using the cosine on the optically thinner side, with total internal
/// reflection. Without branches.
#[inline(always)]
pub fn fresnel_schlick(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let c = if eta < 1.0 { (1.0 - sin2_t).sqrt() } else { cos_i };
    let f = r0 + (1.0 - r0) * (1.0 - c).powi(5);
    if sin2_t >= 1.0 { 1.0 } else { f }
}

/// Refraction of `wo` through a surface with normal `n` on the side of `wo`; `None` on total
/// internal reflection.
#[inline]
pub fn refract(wo: Vec3A, n: Vec3A, eta: f32) -> Option<Vec3A> {
    let (wt, refracts) = refract_plain(wo.into(), n.into(), eta);
    refracts.then(|| wt.into())
}

/// [`refract`] on plain numbers and without branches, for the lane kernels: the direction
/// (meaningless on total internal reflection) and whether it refracts.
#[inline(always)]
pub fn refract_plain(wo: Vec3, n: Vec3, eta: f32) -> (Vec3, bool) {
    let cos_i = wo.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    let cos_t = (1.0 - sin2_t).sqrt();
    (-wo / eta + (cos_i / eta - cos_t) * n, sin2_t < 1.0)
}

/// Chooses reflection or refraction with probability F; `uc` in [0, 1).
#[inline]
pub fn sample(ior: f32, fresnel: Fresnel, wo: Vec3A, n: Vec3A, uc: f32) -> Option<BsdfSample> {
    let (s, valid) = sample_plain(ior, fresnel, wo.into(), n.into(), uc);
    valid.then(|| BsdfSample { delta: true, ..s.into() })
}

/// [`sample`] on plain numbers and without branches: the one source of the one-path code and
/// the lane kernel. The sample (the mirror direction, or the refracted one with its weight
/// `1 / eta^2`), and whether there is one (none on total internal reflection's refraction,
/// which Fresnel's reflectance 1 leaves only to rounding).
#[inline(always)]
pub fn sample_plain(ior: f32, fresnel: Fresnel, wo: Vec3, n: Vec3, uc: f32) -> (DielectricSample, bool) {
    let cos_o = wo.dot(n);
    let outside = cos_o >= 0.0;
    let (eta, nf) = (if outside { ior } else { 1.0 / ior }, if outside { n } else { -n });
    let cos_i = cos_o.abs();
    let (exact, schlick) = (fresnel_exact(cos_i, eta), fresnel_schlick(cos_i, eta));
    let f = if fresnel == Fresnel::Schlick { schlick } else { exact };
    let reflects = uc < f;
    let (wt, refracts) = refract_plain(wo, nf, eta);
    let reflected = DielectricSample { wi: 2.0 * wo.dot(nf) * nf - wo, weight: 1.0, pdf: f, eta: 1.0 };
    let refracted = DielectricSample { wi: normalized(wt), weight: 1.0 / (eta * eta), pdf: 1.0 - f, eta };
    (if reflects { reflected } else { refracted }, reflects || refracts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_known_values() {
        // Normal incidence: ((n-1)/(n+1))^2 = 0.04 for n = 1.5, from either side.
        assert!((fresnel_exact(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_exact(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        // Brewster angle: the parallel polarisation vanishes, F = perp^2 / 2.
        let tb = 1.5f32.atan();
        let ct = (1.0 - (tb.sin() / 1.5).powi(2)).sqrt();
        let perp = (tb.cos() - 1.5 * ct) / (tb.cos() + 1.5 * ct);
        assert!((fresnel_exact(tb.cos(), 1.5) - 0.5 * perp * perp).abs() < 1e-6);
        // Grazing: F -> 1. Beyond the critical angle inside glass: total internal reflection.
        assert!(fresnel_exact(1e-4, 1.5) > 0.99);
        assert_eq!(fresnel_exact(0.5, 1.0 / 1.5), 1.0);
        assert_eq!(fresnel_schlick(0.5, 1.0 / 1.5), 1.0);
        // Schlick stays within 0.025 of exact for glass (worst near cos 0.5: 0.070 vs 0.089).
        for c in [0.3f32, 0.5, 0.6, 0.9] {
            assert!((fresnel_schlick(c, 1.5) - fresnel_exact(c, 1.5)).abs() < 0.025, "{c}");
        }
        assert!((fresnel_schlick(0.5, 1.5) - 0.07).abs() < 1e-4);
    }

    #[test]
    fn refraction_obeys_snell() {
        let n = Vec3A::Y;
        let wo = Vec3A::new(0.5, 0.8, 0.0).normalize();
        let wi = refract(wo, n, 1.5).unwrap();
        let sin_i = wo.cross(n).length();
        let sin_t = wi.cross(-n).length();
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-5);
        assert!(wi.dot(n) < 0.0 && (wi.length() - 1.0).abs() < 1e-5);
        // Reversibility: light travelling back along -wi leaves along wo.
        let back = refract(wi, -n, 1.0 / 1.5).unwrap();
        assert!((back - wo).length() < 1e-5, "{back} {wo}");
    }

    #[test]
    fn reflect_probability_is_fresnel_and_energy_is_conserved() {
        // Throughput times 1/eta^2-compensation sums to one: the interface neither creates nor
        // destroys energy (before the radiance scaling).
        let n = Vec3A::Z;
        let wo = Vec3A::new(0.7, 0.0, 0.3).normalize();
        let f = fresnel_exact(wo.z, 1.5);
        let mut r = crate::testing::uniform(9);
        let total = 200_000;
        let mut reflected = 0;
        for _ in 0..total {
            let b = sample(1.5, Fresnel::Exact, wo, n, r()).unwrap();
            if b.wi.dot(n) > 0.0 {
                reflected += 1;
                assert_eq!(b.weight, Vec3::ONE);
            } else {
                assert!((b.weight * b.eta * b.eta - Vec3::ONE).length() < 1e-5);
            }
        }
        let p = reflected as f32 / total as f32;
        assert!((p - f).abs() < 4.0 * (f * (1.0 - f) / total as f32).sqrt(), "{p} vs {f}");
    }
}
