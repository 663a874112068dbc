//! The Beckmann distribution, isotropic and anisotropic, as Mitsuba 3 defines it
//! (`include/mitsuba/render/microfacet.h`, `MicrofacetDistribution` of type `Beckmann`).
//!
//! Sources:
//! - Walter, Marschner, Li and Torrance 2007, "Microfacet Models for Refraction through Rough
//!   Surfaces" (EGSR), its Beckmann section: `D(m) = exp(-tan^2 / alpha^2) / (pi alpha^2
//!   cos^4)`, and the rational approximation of its Smith masking `G1` (relative error below
//!   0.35%) that Mitsuba evaluates, so that the pdfs and weights here are Mitsuba's.
//! - Heitz and d'Eon 2014, "Importance Sampling Microfacet-Based BSDFs using the Distribution of
//!   Visible Normals" (EGSR): sampling visible normals as slopes of the unit-roughness
//!   configuration, stretched by `alpha`.
//! - Jakob 2014, "An Improved Visible Normal Sampling Routine for the Beckmann Distribution"
//!   (technical note): the slope's first coordinate by Newton iterations on its CDF in the
//!   domain of `erf`, continuous in the random numbers (what Mitsuba and pbrt-v3 do).
//! - Abramowitz and Stegun 1964, 7.1.26: `erf`; Giles 2010, "Approximating the erfinv function"
//!   (GPU Computing Gems Jade, ch. 10), single precision: `erf_inv`.

use super::Microfacet;
use crate::math::{exp_branch_free as exp, ln_branch_free as ln};
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::PI;

/// `1 / sqrt(pi)`.
const INV_SQRT_PI: f32 = 0.564_189_6;

/// The isotropic Beckmann distribution of width `alpha` (> 0), the RMS slope of the
/// microfacets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beckmann {
    /// Width: the roughness.
    pub alpha: f32,
}

impl Microfacet<Vec3> for Beckmann {
    /// `D(m) = exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4)`; as Mitsuba, 0 where `D cos` falls
    /// below 1e-20 (far in the tail, where the terms would underflow).
    #[inline(always)]
    fn d(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let d = exp(-(m.x * m.x + m.y * m.y) / (c2 * a2)) / (PI * a2 * c2 * c2);
        if m.z > 0.0 && d * m.z > 1e-20 { d } else { 0.0 }
    }

    /// Walter et al.'s rational approximation in `a = 1 / (alpha tan)`:
    /// `(3.535 a + 2.181 a^2) / (1 + 2.276 a + 2.577 a^2)` below `a = 1.6`, 1 above (and along
    /// the normal), 0 at grazing.
    #[inline(always)]
    fn g1(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let a = c / (self.alpha * (w.x * w.x + w.y * w.y).sqrt());
        let g = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
        if c == 0.0 {
            0.0
        } else if a >= 1.6 {
            1.0
        } else {
            g
        }
    }

    /// With `a = |cos| / (alpha sin)`: `1 / |cos|` from `a = 1.6` on, and below it the rational
    /// form divided by `|cos|`, `(3.535 + 2.181 a) / (alpha sin (1 + 2.276 a + 2.577 a^2))`,
    /// finite at grazing (`3.535 / alpha`).
    #[inline(always)]
    fn g1_over_cos(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let s = self.alpha * (w.x * w.x + w.y * w.y).sqrt();
        let a = c / s;
        let g = (3.535 + 2.181 * a) / (s * (1.0 + 2.276 * a + 2.577 * a * a));
        if c >= 1.6 * s { if c > 0.0 { 1.0 / c } else { 0.0 } } else { g }
    }

    /// Heitz and d'Eon's stretch, slopes of unit roughness from [`sample_slopes`], rotation to
    /// `wo`'s azimuth and unstretch, as Mitsuba's `MicrofacetDistribution::sample`.
    #[inline(always)]
    fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        sample_visible(self.alpha, self.alpha, wo, u)
    }
}

super::through_plain!(Beckmann);

/// [`Beckmann::sample_visible`] with widths `ax` along x and `ay` along y.
#[inline(always)]
fn sample_visible(ax: f32, ay: f32, wo: Vec3, u: Vec2) -> Vec3 {
    // The view direction in the configuration of unit roughness.
    let v = crate::math::normalized(Vec3::new(ax * wo.x, ay * wo.y, wo.z));
    let sin = (v.x * v.x + v.y * v.y).sqrt();
    let (cos_phi, sin_phi) = if sin > 0.0 { (v.x / sin, v.y / sin) } else { (1.0, 0.0) };
    let (sx, sy) = sample_slopes(sin, v.z, u);
    let (tx, ty) = ((cos_phi * sx - sin_phi * sy) * ax, (sin_phi * sx + cos_phi * sy) * ay);
    let m = Vec3::new(-tx, -ty, 1.0).normalize_or_zero();
    if m.is_finite() { m } else { Vec3::ZERO }
}

/// The anisotropic Beckmann distribution of widths `ax` along the local x axis (the tangent)
/// and `ay` along y (both > 0), as Mitsuba's with `alpha_u` and `alpha_v`:
/// `D(m) = exp(-((m.x / ax)^2 + (m.y / ay)^2) / cos^2) / (pi ax ay cos^4)`, and [`Beckmann`]'s
/// `G1` with `alpha sin` replaced by `sqrt((ax w.x)^2 + (ay w.y)^2)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeckmannAniso {
    /// Width along x.
    pub ax: f32,
    /// Width along y.
    pub ay: f32,
}

impl BeckmannAniso {
    /// `alpha sin` of the isotropic forms: the projected width seen along `w`.
    #[inline]
    fn width(&self, w: Vec3) -> f32 {
        let (x, y) = (self.ax * w.x, self.ay * w.y);
        (x * x + y * y).sqrt()
    }
}

impl Microfacet<Vec3> for BeckmannAniso {
    #[inline]
    fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (m.x / self.ax, m.y / self.ay);
        let c2 = m.z * m.z;
        let d = exp(-(x * x + y * y) / c2) / (PI * self.ax * self.ay * c2 * c2);
        if d * m.z > 1e-20 { d } else { 0.0 }
    }

    #[inline]
    fn g1(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        if c == 0.0 {
            return 0.0;
        }
        let a = c / self.width(w);
        if a >= 1.6 {
            return 1.0;
        }
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    }

    #[inline]
    fn g1_over_cos(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let s = self.width(w);
        if c >= 1.6 * s {
            return if c > 0.0 { 1.0 / c } else { 0.0 };
        }
        let a = c / s;
        (3.535 + 2.181 * a) / (s * (1.0 + 2.276 * a + 2.577 * a * a))
    }

    #[inline]
    fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        sample_visible(self.ax, self.ay, wo, u)
    }
}

super::through_plain!(BeckmannAniso);

/// Slopes of a visible normal of the Beckmann distribution of unit roughness seen from a direction
/// in the xz plane with sine `sin` and cosine `cos` (> 0) of its polar angle (Jakob 2014). The
/// second slope is Gaussian and independent; the first has, in the variable `x = erf(slope)`
/// on [-1, erf(cot)], the unnormalised CDF `1 + x + tan exp(-erfinv(x)^2) / sqrt(pi)`, inverted
/// by three Newton steps from the exact inverse at grazing incidence.
#[inline(always)]
fn sample_slopes(sin: f32, cos: f32, u: Vec2) -> (f32, f32) {
    let tan = sin / cos;
    let cot = cos / sin;
    // The upper end of the interval: facets steeper than cot face away.
    let top = erf(cot);
    let u = u.clamp(Vec2::splat(1e-6), Vec2::splat(1.0 - 1e-6));
    let x = top - (top + 1.0) * erf((-ln(u.x)).sqrt());
    // The CDF's normalisation (its value at `top`), as the target's scale.
    let target = u.x * (1.0 + top + INV_SQRT_PI * tan * exp(-cot * cot));
    // One Newton step, kept in the interval (a step past `top`, where the derivative
    // vanishes, or a 0/0, lands on its ends).
    #[inline(always)]
    fn newton(x: f32, tan: f32, top: f32, target: f32) -> f32 {
        let slope = erf_inv(x);
        let value = 1.0 + x + INV_SQRT_PI * tan * exp(-slope * slope) - target;
        let derivative = 1.0 - slope * tan;
        (x - value / derivative).max(-1.0).min(top)
    }
    // Three steps written out: as a loop, it stayed one (too large to unroll), and the lane
    // kernel's loop over lanes, which contains it, did not vectorise.
    let x = newton(x, tan, top, target);
    let x = newton(x, tan, top, target);
    let x = newton(x, tan, top, target);
    (erf_inv(x), erf_inv(2.0 * u.y - 1.0))
}

/// The error function, Abramowitz and Stegun 7.1.26 (absolute error below 1.5e-7, as pbrt-v3's
/// `Erf`); odd, 1 at infinity.
#[inline(always)]
fn erf(x: f32) -> f32 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * z);
    let p =
        t * (0.254_829_6 + t * (-0.284_496_74 + t * (1.421_413_8 + t * (-1.453_152_1 + t * 1.061_405_4))));
    (1.0 - p * exp(-z * z)).copysign(x)
}

/// The inverse error function on (-1, 1), Giles 2010's single-precision polynomials (relative
/// error about 1e-7, as pbrt-v4's `ErfInv`); arguments are first clamped to the largest `f32`
/// below 1 in magnitude, so the result is finite (|erf_inv| <= 3.9).
#[inline(always)]
fn erf_inv(x: f32) -> f32 {
    let x = x.clamp(-0.999_999_94, 0.999_999_94);
    let w = -ln((1.0 - x) * (1.0 + x));
    // Both polynomials, then the one for `w` (no branch: the lane kernels run it).
    let central = {
        let w = w - 2.5;
        let mut p = 2.810_226_4e-8;
        p = 3.432_739_4e-7 + p * w;
        p = -3.523_387_7e-6 + p * w;
        p = -4.391_506_5e-6 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725 + p * w;
        p = -0.004_177_681_6 + p * w;
        p = 0.246_640_73 + p * w;
        1.501_409_4 + p * w
    };
    let tail = {
        let w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_26;
        p = 0.000_100_950_56 + p * w;
        p = 0.001_349_343_2 + p * w;
        p = -0.003_673_428_4 + p * w;
        p = 0.005_739_507_7 + p * w;
        p = -0.007_622_461 + p * w;
        p = 0.009_438_870_5 + p * w;
        p = 1.001_674 + p * w;
        2.832_976_8 + p * w
    };
    let p = if w < 5.0 { central } else { tail };
    p * x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::microfacet::testing::assert_chi2;
    use crate::material::microfacet::testing::hemisphere;

    /// `erf` in f64 by its Taylor series (Abramowitz and Stegun 7.1.5), for |z| <= 4 (error
    /// below 1e-9).
    fn erf64(z: f64) -> f64 {
        let z2 = z * z;
        let (mut term, mut sum) = (z, z);
        for n in 1..200 {
            term *= -z2 / n as f64;
            sum += term / (2 * n + 1) as f64;
        }
        sum * std::f64::consts::FRAC_2_SQRT_PI
    }

    #[test]
    fn erf_and_its_inverse_match_the_series() {
        for i in -400..=400 {
            let z = i as f64 / 100.0;
            assert!((erf(z as f32) as f64 - erf64(z)).abs() < 3e-7, "erf({z})");
        }
        assert_eq!(erf(f32::INFINITY), 1.0);
        assert_eq!(erf(-f32::INFINITY), -1.0);
        for i in -380..=380 {
            let z = i as f64 / 100.0;
            let x = erf64(z);
            let back = erf_inv(x as f32) as f64;
            // Near +-1 the f32 argument itself is the limit: compare through erf's slope.
            let slope = std::f64::consts::FRAC_2_SQRT_PI * (-z * z).exp();
            assert!((back - z).abs() * slope < 2e-7 + 1e-6 * x.abs(), "erf_inv(erf({z})) = {back}");
        }
        assert!(erf_inv(1.0).is_finite() && erf_inv(-1.0).is_finite() && erf_inv(1.0) < 4.0);
    }

    #[test]
    fn d_cos_integrates_to_one() {
        for alpha in [0.01f32, 0.05, 0.2, 0.6, 1.0] {
            let b = Beckmann { alpha };
            let i = hemisphere(200_000, 1, |m| (b.d(m) * m.z) as f64);
            assert!((i - 1.0).abs() < 1e-3, "alpha {alpha}: {i}");
        }
    }

    #[test]
    fn d_matches_the_textbook_form() {
        let b = Beckmann { alpha: 0.3 };
        for t in [0.0f32, 0.2, 0.7, 1.0] {
            let m = Vec3A::new(t.sin(), 0.0, t.cos());
            let reference = (-(t.tan() / 0.3).powi(2)).exp() / (PI * 0.09 * t.cos().powi(4));
            assert!((b.d(m) - reference).abs() <= 1e-5 * reference, "{t}: {} vs {reference}", b.d(m));
        }
        assert_eq!(b.d(Vec3A::new(1.0, 0.0, 0.0)), 0.0);
        assert_eq!(b.d(-Vec3A::Z), 0.0);
        assert_eq!(b.d(Vec3A::new(1.0, 0.0, 1e-3).normalize()), 0.0, "far in the tail");
    }

    /// The rational `G1` stays within 0.35% of the exact `1 / (1 + Lambda)`, with
    /// `Lambda(a) = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi))` (Walter et al.), and
    /// `G1 / cos` agrees with it.
    #[test]
    fn g1_approximates_the_exact_smith_masking() {
        for alpha in [0.05f32, 0.3, 1.0] {
            let b = Beckmann { alpha };
            for i in 0..=300 {
                let t = i as f32 / 300.0 * 1.5;
                let w = Vec3A::new(t.sin(), 0.0, t.cos());
                let a = 1.0 / (alpha as f64 * (t as f64).tan());
                // Beyond a = 3, Lambda is below 2e-5.
                let lambda = if a > 3.0 {
                    0.0
                } else {
                    (erf64(a) - 1.0) / 2.0 + (-a * a).exp() / (2.0 * a * std::f64::consts::PI.sqrt())
                };
                let exact = 1.0 / (1.0 + lambda);
                assert!((b.g1(w) as f64 / exact - 1.0).abs() < 3.6e-3, "{alpha} {t}: {} vs {exact}", b.g1(w));
                assert!((b.g1_over_cos(w) * t.cos() - b.g1(w)).abs() < 1e-5, "{alpha} {t}");
            }
            assert_eq!(b.g1(Vec3A::X), 0.0);
            assert_eq!(b.g1(Vec3A::Z), 1.0);
            assert_eq!(b.g1(-Vec3A::Z), 1.0);
            assert!(b.g1_over_cos(Vec3A::X).is_finite());
        }
    }

    /// `D_wo` integrates to one up to the rational `G1`'s error (it is `G1` that normalises it).
    #[test]
    fn visible_normals_integrate_to_one() {
        for alpha in [0.05f32, 0.3, 1.0] {
            let b = Beckmann { alpha };
            for deg in [0.0f32, 60.0, 85.0] {
                let t = deg.to_radians();
                let wo = Vec3A::new(t.sin(), 0.0, t.cos());
                let i = hemisphere(4000, 180, |m| b.pdf_visible(wo, m) as f64);
                assert!((i - 1.0).abs() < 5e-3, "alpha {alpha}, {deg} deg: {i}");
            }
        }
    }

    #[test]
    fn visible_normal_sampling_matches_its_pdf_chi2() {
        for alpha in [0.05f32, 0.2, 0.6, 1.0] {
            let b = Beckmann { alpha };
            // Not closer to grazing: from 88 to 89.5 degrees the cells' numerical integrals of
            // the density fail GGX's sampling as well.
            for deg in [0.0f32, 5.0, 60.0, 85.0, 88.0] {
                let t = deg.to_radians();
                let wo = Vec3A::new(t.sin(), 0.0, t.cos());
                let dof = assert_chi2(
                    &format!("alpha {alpha}, {deg} deg"),
                    |u, _| Some(b.sample_visible(wo, u)).filter(|m| m.z > 0.0),
                    |m| b.pdf_visible(wo, m),
                    (Vec3A::Z, Vec3A::Z, alpha),
                    300_000,
                );
                assert!(dof > 50, "{dof}");
            }
        }
    }

    /// Every number in [0, 1]^2, the ends included, gives a unit normal facing `wo`, or zero;
    /// never NaN, at any incidence.
    #[test]
    fn sampling_is_finite_everywhere() {
        let b = Beckmann { alpha: 0.3 };
        let ends = [0.0f32, 1e-7, 0.5, 1.0 - 6e-8, 1.0];
        for wo in [Vec3A::Z, Vec3A::new(1.0, 0.0, 1e-7).normalize(), Vec3A::new(0.0, -1.0, 1e-30)] {
            for ux in ends {
                for uy in ends {
                    let m = b.sample_visible(wo, Vec2::new(ux, uy));
                    assert!(m.is_finite(), "{wo} {ux} {uy}");
                    assert!(m == Vec3A::ZERO || (m.length() - 1.0).abs() < 1e-5);
                }
            }
        }
    }
}
