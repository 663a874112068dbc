//! The Henyey-Greenstein phase function (Henyey and Greenstein, "Diffuse radiation in the
//! galaxy", Astrophysical Journal 93, 1941), sampled exactly by inverting its distribution of
//! cos theta (pbrt-v4 11.3.1; Mitsuba 3's `hg`).
//!
//! Directions point away from the scattering point: `wo` back towards where the path came
//! from, `wi` where it goes next. `g > 0` scatters forwards (`wi` near `-wo`), `g < 0`
//! backwards, `g = 0` is isotropic.

use crate::math::Frame;
use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, TAU};

/// The phase function's value (and density) for `cos = wo . wi`.
#[inline]
pub fn hg(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * cos;
    0.25 * FRAC_1_PI * (1.0 - g * g) / (denom * denom.max(0.0).sqrt())
}

/// A direction `wi` drawn from the phase function about `wo` with the numbers `u`, and its
/// density.
#[inline]
pub fn sample_hg(wo: Vec3A, g: f32, u: Vec2) -> (Vec3A, f32) {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u.x
    } else {
        let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
        (-(1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (sp, cp) = (TAU * u.y).sin_cos();
    let wi = Frame::from_normal(wo).to_world(Vec3A::new(sin * cp, sin * sp, cos));
    (wi, hg(cos, g))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::chi2::{chi2, chi2_critical};

    /// Sampled directions follow the density, for forward, backward, mild and isotropic
    /// scattering. Injected errors that this catches: the sign of `g` flipped in the
    /// sampler, and the density's `2 g cos` term with the wrong sign.
    #[test]
    fn sampling_matches_the_density() {
        let wo = Vec3A::new(0.3, -0.5, 0.8).normalize();
        for g in [0.9, 0.5, -0.7, 0.2, 0.0] {
            let (stat, dof) =
                chi2(|u, _| Some(sample_hg(wo, g, u).0), |wi| hg(wo.dot(wi), g), -wo, -1.0, 400_000);
            assert!(stat < chi2_critical(dof), "g {g}: chi-square {stat} over {dof} degrees of freedom");
        }
    }

    /// It integrates to one over the sphere, and the density the sampler returns is its value.
    #[test]
    fn normalised_and_consistent() {
        for g in [0.95, 0.3, -0.5, 0.0] {
            let n = 200_000;
            let integral: f64 =
                (0..n).map(|k| hg(-1.0 + 2.0 * (k as f32 + 0.5) / n as f32, g) as f64).sum::<f64>() * 2.0
                    / n as f64
                    * std::f64::consts::TAU;
            assert!((integral - 1.0).abs() < 1e-3, "g {g}: {integral}");
            let wo = Vec3A::Z;
            let (wi, pdf) = sample_hg(wo, g, Vec2::new(0.3, 0.7));
            assert!((pdf - hg(wo.dot(wi), g)).abs() < 1e-4 * pdf, "g {g}");
            assert!((wi.length() - 1.0).abs() < 1e-5);
        }
    }
}
