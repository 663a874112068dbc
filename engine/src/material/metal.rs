//! Metal: mirror reflection scaled by the albedo, optionally fuzzed by adding a point uniform in
//! a ball of radius `fuzz` to the mirror direction (Shirley, "Ray Tracing in One Weekend",
//! fuzzy reflection). Directions that end below the surface are absorbed.
//!
//! The fuzzed lobe is evaluated as well as sampled: its density in solid angle is the ball's
//! volume seen along a direction ([`fuzz_pdf`]), so `f |cos|` is the albedo times that density
//! above the surface, and the kind is shaded as the glossy ones are (a light sample weighted
//! against the lobe by MIS): under a point or spot light a fuzzy metal shows its highlight,
//! which BSDF sampling alone never finds. A perfect mirror (fuzz 0) is a delta lobe, as before.

use super::rough_conductor::PlainSample;
use super::{BsdfEval, BsdfSample, Colors, MaterialModel, Reads, Shading, Specular};
use crate::format::{Albedo, Color, UnitInterval};
use glam::{Vec2, Vec3, Vec3A};

/// Mirror scaled by albedo; fuzz adds a point of a ball of that radius to the mirror direction;
/// directions below the surface are absorbed. A fuzzy metal's lobe is evaluated too (its density is
/// the ball's volume seen along a direction), so it samples lights with MIS like the rough kinds
/// and shows highlights of point and spot lights.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct MetalDesc {
    /// Reflectance, components in [0, 1], or a texture (clamped to [0, 1]).
    pub albedo: Color<Albedo>,
    /// Blur in [0, 1] (default 0).
    #[serde(default = "no_fuzz")]
    pub fuzz: UnitInterval,
}

fn no_fuzz() -> UnitInterval {
    UnitInterval(0.0)
}

/// Mirror reflection scaled by `albedo`, blurred by `fuzz` in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metal {
    /// Reflectance.
    pub albedo: Vec3,
    /// Radius of the ball added to the mirror direction; 0 is a perfect mirror.
    pub fuzz: f32,
}

impl MaterialModel for Metal {
    type Desc = MetalDesc;
    const SHADING: Shading = Shading::Glossy;

    fn build(desc: &MetalDesc, colors: &mut Colors) -> Self {
        Self { albedo: colors.get(&desc.albedo).min(Vec3::ONE), fuzz: desc.fuzz.0 }
    }

    #[inline]
    fn set_color(&mut self, _slot: usize, value: Vec3) {
        self.albedo = value.clamp(Vec3::ZERO, Vec3::ONE);
    }

    #[inline]
    fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
        sample(self.albedo, self.fuzz, wo, n, u, uc)
    }

    /// The fuzzed lobe: the albedo times the ball's density towards `wi` above the surface
    /// (a mirror's delta lobe has none).
    #[inline]
    fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        eval_plain(self.albedo, self.fuzz, wo.into(), wi.into(), n.into())
    }

    /// A perfect mirror is a delta lobe; a fuzzed one has no density to weigh.
    fn sharpest_alpha(&self) -> Option<f32> {
        (self.fuzz == 0.0).then_some(0.0)
    }

    #[inline]
    fn albedo(&self) -> Vec3 {
        self.albedo
    }

    /// A perfect mirror reads no number; a fuzzy one the ball's three.
    fn reads(&self) -> Reads {
        Reads { dir: self.fuzz > 0.0, lobe: self.fuzz > 0.0 }
    }

    fn specular(&self) -> Specular {
        if self.fuzz == 0.0 { Specular::Mirror } else { Specular::No }
    }
}

/// Uniform point in the unit ball from three uniform numbers.
#[inline(always)]
pub fn uniform_ball(u: Vec2, uc: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (cos_phi, sin_phi) = crate::math::cos_sin_turn(u.y);
    Vec3::new(r * cos_phi, r * sin_phi, z) * crate::math::cbrt(uc)
}

/// `n` turned to the side of `wo`, and the mirror direction of `wo` about it: a perfect
/// mirror's sample, and the centre of a fuzzy one's ball.
#[inline(always)]
fn mirror(wo: Vec3, n: Vec3) -> (Vec3, Vec3) {
    let nf = if wo.dot(n) < 0.0 { -n } else { n };
    (nf, 2.0 * wo.dot(nf) * nf - wo)
}

/// [`MaterialModel::eval`] of a metal of fuzz `fuzz`, on plain numbers and without branches:
/// the one source of the one-path code and the lane kernel, whose loop over lanes vectorises.
/// The albedo times [`fuzz_pdf`] above the surface; nothing for a mirror (`fuzz` 0).
#[inline(always)]
pub fn eval_plain(albedo: Vec3, fuzz: f32, wo: Vec3, wi: Vec3, n: Vec3) -> BsdfEval {
    let (nf, r) = mirror(wo, n);
    let pdf = fuzz_pdf(r, fuzz, wi);
    match fuzz > 0.0 && wi.dot(nf) > 0.0 {
        true => BsdfEval { f_cos: albedo * pdf, pdf },
        false => BsdfEval::ZERO,
    }
}

/// The fuzzed direction of a metal of fuzz `fuzz` > 0 ([`sample`]), on plain numbers and
/// without branches as [`eval_plain`]: the sample and whether there is one (none where the
/// direction falls below the surface: absorbed).
#[inline(always)]
pub fn sample_plain(albedo: Vec3, fuzz: f32, wo: Vec3, n: Vec3, u: Vec2, uc: f32) -> (PlainSample, bool) {
    let (nf, r) = mirror(wo, n);
    let wi = (r + fuzz * uniform_ball(u, uc)).normalize_or_zero();
    let pdf = fuzz_pdf(r, fuzz, wi);
    (PlainSample { wi, weight: albedo, pdf }, wi.dot(nf) > 0.0 && pdf > 0.0)
}

/// Samples the reflected direction: the mirror's (a delta) or the fuzzed one with its density
/// ([`fuzz_pdf`]; `f |cos| / pdf` is the albedo).
#[inline]
pub fn sample(albedo: Vec3, fuzz: f32, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
    if fuzz == 0.0 {
        let (_, r) = mirror(wo.into(), n.into());
        return Some(BsdfSample {
            wi: r.into(),
            weight: albedo,
            pdf: 1.0,
            eta: 1.0,
            delta: true,
            null: false,
        });
    }
    let (s, valid) = sample_plain(albedo, fuzz, wo.into(), n.into(), u, uc);
    valid.then(|| s.into())
}

/// Density in solid angle of the direction `normalize(r + fuzz * ball)` about the unit mirror
/// direction `r` (`w` unit), before absorption: the ball's volume along the ray `t w`,
/// `(t1^3 - t0^3) / 3` between the ray's entry and exit, over its total volume. The entry and
/// exit solve `t^2 - 2 c t + 1 - fuzz^2 = 0` (`c = w . r`), their gap `2 s` with
/// `s^2 = fuzz^2 - |w x r|^2` (no cancellation near the mirror direction), and
/// `t1^3 - t0^3 = (t1 - t0)(t1^2 + t1 t0 + t0^2)` where both are ahead. Without branches.
#[inline(always)]
pub fn fuzz_pdf(r: Vec3, fuzz: f32, w: Vec3) -> f32 {
    let c = w.dot(r);
    let disc = fuzz * fuzz - w.cross(r).length_squared();
    let s = disc.max(0.0).sqrt();
    let (t0, t1) = (c - s, c + s);
    let volume = match t0 > 0.0 {
        true => 2.0 * s * (t1 * t1 + t1 * t0 + t0 * t0),
        // The origin is inside the ball (fuzz >= 1): from 0.
        false => t1 * t1 * t1,
    };
    let pdf = volume / (4.0 * std::f32::consts::PI * fuzz * fuzz * fuzz);
    if disc < 0.0 || t1 <= 0.0 { 0.0 } else { pdf }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::chi2::{chi2, chi2_critical};
    use crate::math::reflect;

    #[test]
    fn perfect_mirror_reflects() {
        let s =
            sample(Vec3::ONE, 0.0, Vec3A::new(1.0, 1.0, 0.0).normalize(), Vec3A::Y, Vec2::ZERO, 0.0).unwrap();
        assert!((s.wi - Vec3A::new(-1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn fuzzed_directions_follow_the_ball_projection_chi2() {
        for fuzz in [0.3f32, 0.7, 1.0] {
            // Normal incidence: no direction falls below the surface for fuzz < 1.
            let n = Vec3A::Z;
            let wo = Vec3A::new(0.0, 0.2, 1.0).normalize();
            let r = reflect(wo, n);
            let (stat, dof) = chi2(
                |u, uc| {
                    let wi = (r + fuzz * Vec3A::from(uniform_ball(u, uc))).normalize();
                    Some(wi)
                },
                |w| fuzz_pdf(r.into(), fuzz, w.into()),
                r,
                // The lobe lies within the cone of half-angle asin(fuzz) about r.
                if fuzz < 1.0 { ((1.0 - fuzz * fuzz) as f64).sqrt() - 1e-6 } else { -1.0 },
                500_000,
            );
            assert!(stat < chi2_critical(dof), "fuzz {fuzz}: chi2 {stat} dof {dof}");
        }
    }

    #[test]
    fn fuzz_pdf_integrates_to_one() {
        let r = Vec3::Z;
        for fuzz in [0.1f32, 0.5, 1.0] {
            let (nt, np) = (4000, 16);
            let mut sum = 0.0f64;
            for i in 0..nt {
                let z = -1.0 + 2.0 * (i as f32 + 0.5) / nt as f32;
                for _ in 0..np {
                    sum += fuzz_pdf(r, fuzz, Vec3::new((1.0 - z * z).sqrt(), 0.0, z)) as f64;
                }
            }
            let integral = sum * 4.0 * std::f64::consts::PI / (nt * np) as f64;
            assert!((integral - 1.0).abs() < 0.01, "fuzz {fuzz}: {integral}");
        }
    }

    #[test]
    fn absorbed_fraction_matches_the_density_below_the_surface() {
        // Grazing incidence with full fuzz: the fraction of sampled directions below the surface
        // equals the integral of the fuzz density over the lower hemisphere (by quadrature).
        let n = Vec3A::Z;
        let wo = Vec3A::new(1.0, 0.0, 0.3).normalize();
        let r = reflect(wo, n);
        let albedo = Vec3::new(0.8, 0.6, 0.4);
        let mut rng = crate::testing::uniform(3);
        let total = 200_000;
        let mut absorbed = 0;
        for _ in 0..total {
            match sample(albedo, 1.0, wo, n, Vec2::new(rng(), rng()), rng()) {
                Some(b) => assert!(b.wi.dot(n) > 0.0 && b.weight == albedo),
                None => absorbed += 1,
            }
        }
        let (nt, np) = (1000, 400);
        let mut below = 0.0f64;
        for i in 0..nt {
            let z = -(i as f32 + 0.5) / nt as f32;
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                let sz = (1.0 - z * z).sqrt();
                below += fuzz_pdf(r.into(), 1.0, Vec3::new(sz * phi.cos(), sz * phi.sin(), z)) as f64;
            }
        }
        below *= std::f64::consts::TAU / (nt * np) as f64;
        let p = absorbed as f64 / total as f64;
        assert!(p > 0.05, "grazing full fuzz absorbs: {p}");
        assert!(
            (p - below).abs() < 4.0 * (below * (1.0 - below) / total as f64).sqrt() + 1e-3,
            "{p} vs {below}"
        );
    }

    /// Each fuzzed sample carries the density and weight that `eval` gives its direction
    /// (`f |cos| / pdf` is the albedo), and `eval` integrated over the hemisphere is the albedo
    /// times the share of the ball's directions that stay above the surface, so that light
    /// sampling weighted by it and BSDF sampling estimate one integral. A mirror is a delta
    /// that `eval` does not see. (The density left at 1 on samples, or `eval` without the
    /// albedo, fails.)
    #[test]
    fn eval_agrees_with_sampling() {
        let n = Vec3A::Z;
        let albedo = Vec3::new(0.8, 0.6, 0.4);
        let mut rng = crate::testing::uniform(5);
        for (fuzz, wo) in [(0.2f32, Vec3A::new(0.3, 0.1, 1.0)), (1.0, Vec3A::new(1.0, 0.0, 0.3))] {
            let m = Metal { albedo, fuzz };
            let wo = wo.normalize();
            let (mut kept, total) = (0, 100_000);
            for _ in 0..total {
                let Some(b) = m.sample(wo, n, Vec2::new(rng(), rng()), rng()) else { continue };
                kept += 1;
                let e = m.eval(wo, b.wi, n);
                assert!(!b.delta && (b.pdf - e.pdf).abs() <= 1e-4 * e.pdf, "{} vs {}", b.pdf, e.pdf);
                assert!((b.weight - e.f_cos / e.pdf).abs().max_element() < 1e-5);
            }
            // Quadrature of eval over the upper hemisphere (in cos theta and phi).
            let (nt, np) = (2000, 400);
            let mut integral = glam::DVec3::ZERO;
            for i in 0..nt {
                let z = (i as f32 + 0.5) / nt as f32;
                for j in 0..np {
                    let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                    let sz = (1.0 - z * z).sqrt();
                    integral += m.eval(wo, Vec3A::new(sz * phi.cos(), sz * phi.sin(), z), n).f_cos.as_dvec3();
                }
            }
            integral *= std::f64::consts::TAU / (nt * np) as f64;
            let kept = kept as f64 / total as f64;
            let want = albedo.as_dvec3() * kept;
            assert!((integral - want).abs().max_element() < 0.01, "fuzz {fuzz}: {integral} vs {want}");
        }
        let mirror = Metal { albedo, fuzz: 0.0 };
        let wo = Vec3A::new(0.3, 0.1, 1.0).normalize();
        let b = mirror.sample(wo, n, Vec2::ZERO, 0.0).unwrap();
        assert!(b.delta);
        assert_eq!(mirror.eval(wo, b.wi, n), BsdfEval::ZERO);
    }
}
