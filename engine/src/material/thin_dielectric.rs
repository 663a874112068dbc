//! Thin dielectric: a pane of glass too thin to see its thickness (a window, a soap bubble, the
//! wall of a water-filled balloon), as Mitsuba 3's `thindielectric`
//! (`src/bsdfs/thindielectric.cpp`). Light is reflected with the pane's total reflectance, the
//! interface's Fresnel reflectance R summed with the light that bounces inside the pane and
//! leaves on the side it came from, R' = R + T^2 R / (1 - R^2) = 2R / (1 + R) (T = 1 - R); the
//! rest, 1 - R', goes straight through unbent (both interfaces refract it back).
//!
//! The straight transmission is a null lobe ([`BsdfSample::null`]): the ray goes on as if the
//! pane were not there, so the path keeps its MIS state and the crossing is not a bounce of
//! `max_depth` (Mitsuba's volumetric path tracer counts it so too). Shadow rays pass through
//! the pane, attenuated by 1 - R' ([`MaterialModel::null_transmission`]), so that light
//! sampling reaches what lies behind it, as in Mitsuba.

use super::dielectric::fresnel_exact;
use super::{BsdfSample, Colors, MaterialModel, Reads, Shading, Specular};
use crate::format::Positive;
use glam::{Vec2, Vec3, Vec3A};

/// A pane too thin to see (a window, a bubble; Mitsuba 3's `thindielectric`): reflects with the
/// pane's reflectance R' = R + T^2 R / (1 - R^2) = 2R / (1 + R) (R the exact Fresnel reflectance at
/// the angle of incidence, either side, T = 1 - R), else lets the ray through unbent. The straight
/// transmission is a null lobe: the path keeps its MIS state and the crossing is no bounce of
/// `max_depth` (as Mitsuba's volumetric path tracer counts it), and shadow rays cross the pane
/// attenuated by 1 - R' (up to 256 crossings), so light sampling reaches what lies behind it.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct ThinDielectricDesc {
    /// Index of refraction of the pane relative to its surroundings (> 0).
    pub ior: Positive,
}

/// A thin pane of dielectric: Fresnel reflection with the inter-reflections inside the pane,
/// straight transmission.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// Index of refraction of the pane relative to its surroundings.
    pub ior: f32,
}

impl ThinDielectric {
    /// The pane's reflectance R' = 2R / (1 + R) for light arriving at `cos` (either side) from
    /// the normal.
    #[inline(always)]
    pub fn reflectance(&self, cos: f32) -> f32 {
        let r = fresnel_exact(cos.abs(), self.ior);
        r * 2.0 / (1.0 + r)
    }

    /// [`MaterialModel::sample`] on plain numbers and without branches: the one source of the
    /// one-path code and the lane kernel. The direction (the mirror's, or straight on), its
    /// probability, and whether it goes straight on (the null lobe); both weigh 1.
    #[inline(always)]
    pub fn sample_plain(&self, wo: Vec3, n: Vec3, uc: f32) -> (Vec3, f32, bool) {
        let cos = wo.dot(n);
        let r = self.reflectance(cos);
        let nf = if cos >= 0.0 { n } else { -n };
        let reflects = uc < r;
        let wi = if reflects { 2.0 * wo.dot(nf) * nf - wo } else { -wo };
        (wi, if reflects { r } else { 1.0 - r }, !reflects)
    }
}

impl MaterialModel for ThinDielectric {
    type Desc = ThinDielectricDesc;
    const SHADING: Shading = Shading::Sampled;

    fn build(desc: &ThinDielectricDesc, _colors: &mut Colors) -> Self {
        Self { ior: desc.ior.0 }
    }

    /// Reflection with probability R', else straight on; both weigh 1.
    #[inline]
    fn sample(&self, wo: Vec3A, n: Vec3A, _u: Vec2, uc: f32) -> Option<BsdfSample> {
        let (wi, pdf, null) = self.sample_plain(wo.into(), n.into(), uc);
        Some(BsdfSample { wi: wi.into(), weight: Vec3::ONE, pdf, eta: 1.0, delta: true, null })
    }

    /// Glass shows as white in the albedo guide.
    fn albedo(&self) -> Vec3 {
        Vec3::ONE
    }

    /// Only the choice between reflection and transmission.
    fn reads(&self) -> Reads {
        Reads { dir: false, lobe: true }
    }

    /// The guides look through it, unbent (glass of index 1).
    fn specular(&self) -> Specular {
        Specular::Glass { ior: 1.0 }
    }

    fn null_transmission(&self, cos: f32) -> f32 {
        1.0 - self.reflectance(cos)
    }

    fn has_null_lobe(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::reflect;

    #[test]
    fn reflectance_sums_the_inter_reflections() {
        // Water against air at normal incidence: R = ((n - 1) / (n + 1))^2, and the pane
        // reflects R + T^2 R (1 + R^2 + R^4 + ..) = R + T^2 R / (1 - R^2).
        let m = ThinDielectric { ior: 1.333 };
        let r = ((1.333f32 - 1.0) / (1.333 + 1.0)).powi(2);
        let series = r + (1.0 - r).powi(2) * r / (1.0 - r * r);
        assert!((m.reflectance(1.0) - series).abs() < 1e-6, "{} vs {series}", m.reflectance(1.0));
        // The same from either side, and everything at grazing incidence.
        assert_eq!(m.reflectance(-0.3), m.reflectance(0.3));
        assert!(m.reflectance(1e-4) > 0.99);
        // R' + (1 - R') = 1: what is not reflected is transmitted.
        for c in [0.1f32, 0.5, 0.9] {
            assert!((m.reflectance(c) + m.null_transmission(c) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn samples_reflect_with_the_pane_reflectance_and_pass_straight_otherwise() {
        let m = ThinDielectric { ior: 1.5 };
        let n = Vec3A::Z;
        for wo in [Vec3A::new(0.6, 0.0, 0.8), Vec3A::new(-0.3, 0.4, -0.866).normalize()] {
            let r = m.reflectance(wo.dot(n));
            let mut rnd = crate::testing::uniform(3);
            let total = 100_000;
            let mut reflected = 0;
            for _ in 0..total {
                let s = m.sample(wo, n, Vec2::ZERO, rnd()).unwrap();
                assert_eq!(s.weight, Vec3::ONE);
                assert!(s.delta && s.eta == 1.0);
                match s.null {
                    // Straight on, to the other side.
                    true => {
                        assert_eq!(s.wi, -wo);
                        assert!((s.pdf - (1.0 - r)).abs() < 1e-6);
                    }
                    // The mirror direction, on wo's side.
                    false => {
                        reflected += 1;
                        assert!((s.wi - reflect(wo, if wo.z > 0.0 { n } else { -n })).length() < 1e-6);
                        assert!(s.wi.dot(n) * wo.dot(n) > 0.0 && (s.pdf - r).abs() < 1e-6);
                    }
                }
            }
            let p = reflected as f32 / total as f32;
            assert!((p - r).abs() < 4.0 * (r * (1.0 - r) / total as f32).sqrt(), "{p} vs {r}");
        }
    }
}
