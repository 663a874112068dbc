//! The microfacet distributions shared by the rough materials: GGX (Trowbridge-Reitz) and
//! Beckmann ([`beckmann`]), isotropic and anisotropic, behind the [`Microfacet`] trait the
//! materials are generic over.
//!
//! Sources:
//! - Walter, Marschner, Li and Torrance 2007, "Microfacet Models for Refraction through Rough
//!   Surfaces" (EGSR): the GGX and Beckmann distributions `D`, their Smith shadowing `G1`, and
//!   the reflection and transmission BSDFs through the half vector.
//! - Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs" (JCGT
//!   3(2)): the distribution of visible normals `D_wo(m) = G1(wo) max(0, wo.m) D(m) / cos(wo)`,
//!   which integrates to one, and `G1 = 1 / (1 + Lambda)`.
//! - Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)): the sampling
//!   routine of [`Ggx`].
//!
//! Everything here works in a local frame whose z axis is the (macro) normal: use [`to_local`]
//! with [`Frame::from_normal`]. Shadowing-masking is the separable Smith form
//! `G(wo, wi) = G1(wo) G1(wi)` (not the height-correlated one).

mod beckmann;

use crate::math::Frame;
pub use beckmann::{Beckmann, BeckmannAniso};
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::PI;

/// Below this alpha a rough material is treated as smooth (a delta mirror or smooth glass): the
/// lobe is then under a milliradian wide, a mirror in any image, while its density (up to
/// `1 / (pi alpha^2)`) grows huge and ill-conditioned in f32. pbrt-v4's
/// `TrowbridgeReitzDistribution::EffectivelySmooth` (Pharr, Jakob and Humphreys 2023) uses the
/// same threshold.
pub const SMOOTH_ALPHA: f32 = 1e-3;

/// A roughness `alpha` in [0, 1] as a scene writes it: the width of the distribution, the scale
/// of the microfacet slopes (0 is smooth; for Beckmann the RMS slope).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roughness(pub f32);

impl<'de> serde::Deserialize<'de> for Roughness {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f32::deserialize(d)?;
        if (0.0..=1.0).contains(&v) {
            Ok(Roughness(v))
        } else {
            Err(serde::de::Error::custom(format!("expected a roughness alpha in [0, 1], found {v}")))
        }
    }
}

impl From<Roughness> for f32 {
    fn from(r: Roughness) -> f32 {
        r.0
    }
}

/// `v` in the frame `f`: (v.t, v.b, v.n).
#[inline]
pub fn to_local(f: &Frame, v: Vec3A) -> Vec3A {
    Vec3A::new(v.dot(f.t), v.dot(f.b), v.dot(f.n))
}

/// A local frame on plain numbers ([`Vec3`], the lane kernels'): [`crate::math::basis`] about a
/// unit normal, the same axes as [`Frame::from_normal`].
#[derive(Clone, Copy, Debug)]
pub struct PlainFrame {
    /// First tangent.
    pub t: Vec3,
    /// Second tangent.
    pub b: Vec3,
    /// The normal.
    pub n: Vec3,
}

impl PlainFrame {
    /// About the unit normal `n`.
    #[inline(always)]
    pub fn new(n: Vec3) -> Self {
        let (t, b) = crate::math::basis(n);
        Self { t, b, n }
    }

    /// About `n` turned to `wo`'s side where `two_sided` (else `n` as it is).
    #[inline(always)]
    pub fn facing(wo: Vec3, n: Vec3, two_sided: bool) -> Self {
        Self::new(if two_sided && wo.dot(n) < 0.0 { -n } else { n })
    }

    /// `v` in the frame: (v.t, v.b, v.n).
    #[inline(always)]
    pub fn local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// The local `v` in world space (as [`Frame::to_world`]).
    #[inline(always)]
    pub fn world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }

    /// The local `v` in world space, normalised (by a division, as glam's `Vec3A::normalize`).
    #[inline(always)]
    pub fn world_unit(&self, v: Vec3) -> Vec3 {
        crate::math::normalized(self.t * v.x + self.b * v.y + self.n * v.z)
    }
}

/// The form of the Smith shadowing-masking term.
#[derive(serde::Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Smith {
    /// `G = G1(wo) G1(wi)` (the default, as Mitsuba 3's microfacet plugins).
    #[default]
    Separable,
    /// `G = 1 / (1 + Lambda(wo) + Lambda(wi))` (Heitz 2014, section 6; pbrt-v4's): correlates
    /// masking and shadowing by microfacet height, so slightly brighter at grazing angles.
    HeightCorrelated,
}

/// Which distribution of microfacet normals a rough material has.
#[derive(serde::Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Distribution {
    /// GGX (Trowbridge-Reitz): long tails (the default).
    #[default]
    Ggx,
    /// Beckmann: Gaussian slopes, shorter tails (Mitsuba's default).
    Beckmann,
}

/// The vectors the [`Microfacet`] functions take: [`Vec3A`] for the materials' one-path code,
/// [`Vec3`] (plain numbers) for the lane kernels, whose loops over lanes vectorise only on
/// scalar operations.
pub trait LocalVector: Copy {
    /// The component along the normal: the cosine of a unit vector's polar angle.
    fn cos(self) -> f32;
    /// The dot product.
    fn dot_with(self, o: Self) -> f32;
}

impl LocalVector for Vec3A {
    #[inline(always)]
    fn cos(self) -> f32 {
        self.z
    }
    #[inline(always)]
    fn dot_with(self, o: Self) -> f32 {
        self.dot(o)
    }
}

impl LocalVector for Vec3 {
    #[inline(always)]
    fn cos(self) -> f32 {
        self.z
    }
    #[inline(always)]
    fn dot_with(self, o: Self) -> f32 {
        self.dot(o)
    }
}

/// A distribution of microfacet normals, in the local frame of the macro normal (for the
/// anisotropic ones, x along the surface's tangent). The rough materials are generic over it,
/// so each distribution's code is compiled on its own. The isotropic [`Ggx`] and [`Beckmann`]
/// implement it on plain numbers ([`Vec3`], written without branches, for the lane kernels)
/// and on [`Vec3A`] through those: one source for both.
pub trait Microfacet<V: LocalVector = Vec3A>: Copy {
    /// The distribution of normals at the unit local microfacet normal `m`, normalised so that
    /// the integral of `D(m) cos(theta_m)` over the hemisphere is 1; 0 below the surface.
    fn d(&self, m: V) -> f32;

    /// Smith masking `G1 = 1 / (1 + Lambda)` of the unit local direction `w` (either side; the
    /// side tests are the BSDF's). 1 along the normal, 0 at grazing.
    fn g1(&self, w: V) -> f32;

    /// `G1(w) / |cos(w)|`, finite at grazing.
    fn g1_over_cos(&self, w: V) -> f32;

    /// Samples a visible microfacet normal from `wo` (local, `wo.z > 0`) and `u` in [0, 1]^2,
    /// with density [`Self::pdf_visible`]. The result may be degenerate (`m.z <= 0`, or zero)
    /// at the boundary of the domain; callers check.
    fn sample_visible(&self, wo: V, u: Vec2) -> V;

    /// `G(wo, wi) / G1(wo)` under `smith`: what is left of the shadowing-masking in a sample's
    /// weight once visible-normal sampling has divided out `G1(wo)`. Separable: `G1(wi)`;
    /// height-correlated: `(1 + Lambda(wo)) / (1 + Lambda(wo) + Lambda(wi))`, written with
    /// `1 + Lambda = 1 / G1` so that grazing directions give 0, not infinities.
    // Always inlined, as `pdf_visible`: with two distributions the compiler left it out of line
    // in the rough materials' sampling (callgrind, materials-env).
    #[inline(always)]
    fn shadowing(&self, smith: Smith, wo: V, wi: V) -> f32 {
        let gi = self.g1(wi);
        match smith {
            Smith::Separable => gi,
            Smith::HeightCorrelated => {
                let go = self.g1(wo);
                let den = gi + go - go * gi;
                if den > 0.0 { gi / den } else { 0.0 }
            }
        }
    }

    /// Density of visible normals seen from `wo` (local, `wo.z > 0`):
    /// `D_wo(m) = G1(wo) max(0, wo.m) D(m) / cos(wo)` (Heitz 2014, eq. 2 of Heitz 2018).
    #[inline(always)]
    fn pdf_visible(&self, wo: V, m: V) -> f32 {
        let pdf = self.g1_over_cos(wo) * wo.dot_with(m).max(0.0) * self.d(m);
        if wo.cos() > 0.0 { pdf } else { 0.0 }
    }
}

/// Implements [`Microfacet`] on [`Vec3A`] for an isotropic distribution through its
/// implementation on [`Vec3`].
macro_rules! through_plain {
    ($t:ty) => {
        impl Microfacet for $t {
            #[inline(always)]
            fn d(&self, m: Vec3A) -> f32 {
                Microfacet::<Vec3>::d(self, m.into())
            }
            #[inline(always)]
            fn g1(&self, w: Vec3A) -> f32 {
                Microfacet::<Vec3>::g1(self, w.into())
            }
            #[inline(always)]
            fn g1_over_cos(&self, w: Vec3A) -> f32 {
                Microfacet::<Vec3>::g1_over_cos(self, w.into())
            }
            #[inline(always)]
            fn sample_visible(&self, wo: Vec3A, u: Vec2) -> Vec3A {
                Microfacet::<Vec3>::sample_visible(self, wo.into(), u).into()
            }
        }
    };
}
use through_plain;

/// The isotropic GGX distribution of width `alpha` (> 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Width: the roughness.
    pub alpha: f32,
}

impl Microfacet<Vec3> for Ggx {
    /// `D(m) = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2)`, written as
    /// `alpha^2 / (pi (alpha^2 cos^2 + sin^2)^2)` (no division by cos).
    #[inline(always)]
    fn d(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let t = a2 * m.z * m.z + (m.x * m.x + m.y * m.y);
        let d = a2 / (PI * t * t);
        if m.z > 0.0 && t > 0.0 { d } else { 0.0 }
    }

    /// `G1 = 2 / (1 + sqrt(1 + alpha^2 tan^2))`, written as
    /// `2 |cos| / (|cos| + sqrt(cos^2 + alpha^2 sin^2))`.
    #[inline(always)]
    fn g1(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let den = c + (c * c + self.alpha * self.alpha * (w.x * w.x + w.y * w.y)).sqrt();
        if den > 0.0 { 2.0 * c / den } else { 0.0 }
    }

    /// `2 / (|cos| + sqrt(cos^2 + alpha^2 sin^2))`.
    #[inline(always)]
    fn g1_over_cos(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let den = c + (c * c + self.alpha * self.alpha * (w.x * w.x + w.y * w.y)).sqrt();
        if den > 0.0 { 2.0 / den } else { 0.0 }
    }

    /// Heitz 2018, listing 1 (isotropic).
    #[inline(always)]
    fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        ggx_sample_visible(self.alpha, self.alpha, wo, u)
    }
}

through_plain!(Ggx);

/// Heitz 2018, listing 1: a visible normal of GGX with widths `ax` along x and `ay` along y.
#[inline(always)]
fn ggx_sample_visible(ax: f32, ay: f32, wo: Vec3, u: Vec2) -> Vec3 {
    // Section 3.2: stretch the view direction to the hemisphere configuration.
    let vh = crate::math::normalized(Vec3::new(ax * wo.x, ay * wo.y, wo.z));
    // Section 4.1: orthonormal basis about it.
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { Vec3::X };
    let t2 = vh.cross(t1);
    // Section 4.2: a point of the projected area, a disk warped towards the visible half.
    let r = u.x.clamp(0.0, 1.0).sqrt();
    let (cos_phi, sin_phi) = crate::math::cos_sin_turn(u.y);
    let p1 = r * cos_phi;
    let p2 = r * sin_phi;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    // Section 4.3: reprojection onto the hemisphere.
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    // Section 3.4: back to the ellipsoid configuration.
    Vec3::new(ax * nh.x, ay * nh.y, nh.z.max(0.0)).normalize_or_zero()
}

/// The anisotropic GGX distribution of widths `ax` along the local x axis (the tangent) and
/// `ay` along y (both > 0), as Mitsuba's `MicrofacetDistribution` with `alpha_u` and `alpha_v`:
/// `D(m) = 1 / (pi ax ay ((m.x / ax)^2 + (m.y / ay)^2 + m.z^2)^2)` and `Lambda` with
/// `alpha^2 sin^2` replaced by `(ax w.x)^2 + (ay w.y)^2` (Heitz 2014, section 5.3). The
/// isotropic [`Ggx`] stays separate, so that its images keep their bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GgxAniso {
    /// Width along x.
    pub ax: f32,
    /// Width along y.
    pub ay: f32,
}

impl GgxAniso {
    /// `alpha^2 sin^2` of the isotropic forms: the squared projected width seen along `w`.
    #[inline]
    fn width2(&self, w: Vec3) -> f32 {
        let (x, y) = (self.ax * w.x, self.ay * w.y);
        x * x + y * y
    }
}

impl Microfacet<Vec3> for GgxAniso {
    #[inline]
    fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (m.x / self.ax, m.y / self.ay);
        let t = x * x + y * y + m.z * m.z;
        if t <= 0.0 {
            return 0.0;
        }
        1.0 / (PI * self.ax * self.ay * t * t)
    }

    #[inline]
    fn g1(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let den = c + (c * c + self.width2(w)).sqrt();
        if den > 0.0 { 2.0 * c / den } else { 0.0 }
    }

    #[inline]
    fn g1_over_cos(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let den = c + (c * c + self.width2(w)).sqrt();
        if den > 0.0 { 2.0 / den } else { 0.0 }
    }

    #[inline]
    fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        ggx_sample_visible(self.ax, self.ay, wo, u)
    }
}

through_plain!(GgxAniso);

/// Test support: chi-square of a direction sampler with the cells packed about a lobe.
#[cfg(test)]
pub(crate) mod testing {
    use super::*;
    use crate::material::chi2::{chi2, chi2_critical};
    use std::f64::consts::PI as PI64;

    /// Integral over the hemisphere of `g(theta, phi)` in spherical coordinates, midpoint rule
    /// in theta (fine, for narrow lobes) and phi, in f64.
    pub(crate) fn hemisphere(nt: usize, np: usize, g: impl Fn(Vec3A) -> f64) -> f64 {
        let (dt, dp) = (std::f64::consts::FRAC_PI_2 / nt as f64, std::f64::consts::TAU / np as f64);
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            for j in 0..np {
                let p = (j as f64 + 0.5) * dp;
                let m = Vec3A::new((t.sin() * p.cos()) as f32, (t.sin() * p.sin()) as f32, t.cos() as f32);
                sum += g(m) * t.sin();
            }
        }
        sum * dt * dp
    }

    /// A monotone map of [a, b] onto [0, 1] that spends its resolution near `c` (scale `s`):
    /// `x' = (asinh((x - c) / s) - A) / (B - A)`, with A and B its values at a and b.
    #[derive(Clone, Copy, Debug)]
    struct Squeeze {
        c: f64,
        s: f64,
        lo: f64,
        hi: f64,
    }

    impl Squeeze {
        fn new(a: f64, b: f64, c: f64, s: f64) -> Self {
            let c = c.clamp(a, b);
            Self { c, s, lo: ((a - c) / s).asinh(), hi: ((b - c) / s).asinh() }
        }

        fn fwd(&self, x: f64) -> f64 {
            ((((x - self.c) / self.s).asinh() - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0)
        }

        /// The inverse and its derivative `dx / dx'`.
        fn inv(&self, y: f64) -> (f64, f64) {
            let t = self.lo + y * (self.hi - self.lo);
            (self.c + self.s * t.sinh(), self.s * (self.hi - self.lo) * t.cosh())
        }
    }

    /// A bijection of the sphere, in the frame of a normal, made of one map of `z = cos(theta)`
    /// per hemisphere (each onto itself, so the horizon stays on a boundary of [`chi2`]'s
    /// rings: the densities jump there) and one of the azimuth, both packed about a centre
    /// direction. Solid angle is `dz dphi`, so densities scale by `dz/dz' dphi/dphi'`.
    pub(crate) struct Warp {
        frame: Frame,
        up: Squeeze,
        down: Squeeze,
        phi: Squeeze,
        phi_c: f64,
    }

    impl Warp {
        /// Packs the cells about `centre` (unit) over a width of about `width` radians.
        pub(crate) fn new(n: Vec3A, centre: Vec3A, width: f64) -> Self {
            let frame = Frame::from_normal(n);
            let c = to_local(&frame, centre);
            let (z, sin) = (c.z as f64, ((c.x * c.x + c.y * c.y) as f64).sqrt());
            // Widths of the lobe in z (about width^2 at the pole) and in azimuth.
            let sz = width * width.max(sin);
            let sp = width / width.max(sin);
            Self {
                frame,
                up: Squeeze::new(0.0, 1.0, z, sz),
                down: Squeeze::new(-1.0, 0.0, z, sz),
                phi: Squeeze::new(-PI64, PI64, 0.0, sp),
                phi_c: (c.y as f64).atan2(c.x as f64),
            }
        }

        /// Angle in [-pi, pi) relative to `phi_c`.
        fn wrap(&self, phi: f64) -> f64 {
            (phi - self.phi_c + PI64).rem_euclid(2.0 * PI64) - PI64
        }

        fn direction(&self, z: f64, phi: f64) -> Vec3A {
            let s = (1.0 - z * z).max(0.0).sqrt();
            self.frame.to_world(Vec3A::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32))
        }

        pub(crate) fn fwd(&self, w: Vec3A) -> Vec3A {
            let l = to_local(&self.frame, w);
            let z = l.z as f64;
            let z2 = if z >= 0.0 { self.up.fwd(z) } else { self.down.fwd(z) - 1.0 };
            let p2 = -PI64 + 2.0 * PI64 * self.phi.fwd(self.wrap((l.y as f64).atan2(l.x as f64)));
            self.direction(z2, p2)
        }

        /// The inverse and the Jacobian `|dz/dz'| |dphi/dphi'|`.
        pub(crate) fn inv(&self, w: Vec3A) -> (Vec3A, f64) {
            let l = to_local(&self.frame, w);
            let z2 = l.z as f64;
            let (z, jz) = if z2 >= 0.0 { self.up.inv(z2) } else { self.down.inv(z2 + 1.0) };
            let (p, jp) = self.phi.inv(((l.y as f64).atan2(l.x as f64) + PI64) / (2.0 * PI64));
            (self.direction(z, p + self.phi_c), jz * jp / (2.0 * PI64))
        }
    }

    /// Chi-square statistic of `sample` against the solid-angle density `pdf` over the whole
    /// sphere, in the cells of [`chi2`] about `n` after a [`Warp`] about `centre` with `width`
    /// (`count` draws; `None` draws count nowhere, so `pdf` integrates to the probability of
    /// `Some`); asserts it is below the critical value at significance 1e-4 and returns the
    /// degrees of freedom.
    pub(crate) fn assert_chi2(
        what: &str,
        mut sample: impl FnMut(Vec2, f32) -> Option<Vec3A>,
        pdf: impl Fn(Vec3A) -> f32,
        (n, centre, width): (Vec3A, Vec3A, f32),
        count: usize,
    ) -> usize {
        let warp = Warp::new(n, centre, width as f64);
        let (stat, dof) = chi2(
            |u, uc| sample(u, uc).map(|w| warp.fwd(w)),
            |w| {
                let (v, jac) = warp.inv(w);
                (pdf(v) as f64 * jac) as f32
            },
            n,
            -1.0,
            count,
        );
        assert!(stat < chi2_critical(dof.max(1)), "{what}: chi2 {stat} dof {dof}");
        dof
    }

    #[test]
    fn warp_round_trips_and_its_jacobian_integrates_to_the_sphere() {
        let n = Vec3A::new(0.3, -0.5, 0.8).normalize();
        let f = Frame::from_normal(n);
        for (centre, width) in [(n, 0.05), (f.to_world(Vec3A::new(0.99, 0.0, 0.1)), 0.2), (-n, 0.6)] {
            let warp = Warp::new(n, centre.normalize(), width);
            let mut r = crate::testing::signed(5);
            for _ in 0..1000 {
                let w = Vec3A::new(r(), r(), r()).normalize();
                let w2 = warp.fwd(w);
                assert_eq!(w.dot(n) >= 0.0, w2.dot(n) >= 0.0, "hemispheres map onto themselves");
                let (back, _) = warp.inv(w2);
                assert!((back - w).length() < 1e-4, "{w} {back}");
            }
            // The Jacobian integrates to the sphere's solid angle (midpoint rule in z', phi').
            let (nz, np) = (400, 400);
            let mut sum = 0.0;
            for i in 0..nz {
                for j in 0..np {
                    let z = -1.0 + 2.0 * (i as f64 + 0.5) / nz as f64;
                    let p = -PI64 + 2.0 * PI64 * (j as f64 + 0.5) / np as f64;
                    let s = (1.0 - z * z).sqrt();
                    let l = Vec3A::new((s * p.cos()) as f32, (s * p.sin()) as f32, z as f32);
                    sum += warp.inv(f.to_world(l)).1;
                }
            }
            let area = sum * 4.0 * PI64 / (nz * np) as f64;
            assert!((area / (4.0 * PI64) - 1.0).abs() < 1e-3, "{area}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::testing::hemisphere;
    use super::*;

    #[test]
    fn d_cos_integrates_to_one() {
        for alpha in [0.01f32, 0.05, 0.2, 0.6, 1.0] {
            let ggx = Ggx { alpha };
            // Isotropic: one azimuth suffices.
            let i = hemisphere(200_000, 1, |m| (ggx.d(m) * m.z) as f64);
            assert!((i - 1.0).abs() < 1e-3, "alpha {alpha}: {i}");
        }
    }

    #[test]
    fn d_matches_the_textbook_form() {
        let ggx = Ggx { alpha: 0.3 };
        for t in [0.0f32, 0.2, 0.7, 1.2, 1.5] {
            let m = Vec3A::new(t.sin(), 0.0, t.cos());
            let a2 = 0.09f32;
            let reference = a2 / (PI * t.cos().powi(4) * (a2 + t.tan().powi(2)).powi(2));
            assert!((ggx.d(m) - reference).abs() <= 1e-4 * reference, "{t}");
        }
        assert_eq!(ggx.d(Vec3A::new(1.0, 0.0, 0.0)), 0.0);
        assert_eq!(ggx.d(-Vec3A::Z), 0.0);
    }

    #[test]
    fn g1_matches_one_over_one_plus_lambda() {
        for alpha in [0.05f32, 0.5, 1.0] {
            let ggx = Ggx { alpha };
            for t in [0.0f32, 0.5, 1.0, 1.4, 1.55] {
                let w = Vec3A::new(t.sin(), 0.0, t.cos());
                let lambda = ((1.0 + alpha * alpha * t.tan().powi(2)).sqrt() - 1.0) / 2.0;
                assert!((ggx.g1(w) - 1.0 / (1.0 + lambda)).abs() < 1e-5, "{alpha} {t}");
                assert!((ggx.g1_over_cos(w) * t.cos() - ggx.g1(w)).abs() < 1e-5);
            }
            assert_eq!(ggx.g1(Vec3A::X), 0.0);
            assert_eq!(ggx.g1(Vec3A::Z), 1.0);
        }
    }

    /// Height-correlated: `G / G1(wo) = G1(wo)^-1 / (1 + Lambda(wo) + Lambda(wi))`, never below
    /// the separable form, equal to it when one direction is normal.
    #[test]
    fn height_correlated_shadowing_matches_its_lambda_form() {
        for alpha in [0.05f32, 0.5, 1.0] {
            let ggx = Ggx { alpha };
            let lambda = |t: f32| ((1.0 + alpha * alpha * t.tan().powi(2)).sqrt() - 1.0) / 2.0;
            for to in [0.0f32, 0.7, 1.3, 1.55] {
                for ti in [0.0f32, 0.4, 1.2, 1.5] {
                    let (wo, wi) = (Vec3A::new(to.sin(), 0.0, to.cos()), Vec3A::new(0.0, ti.sin(), ti.cos()));
                    let g2 = 1.0 / (1.0 + lambda(to) + lambda(ti));
                    let hc = ggx.shadowing(Smith::HeightCorrelated, wo, wi) * ggx.g1(wo);
                    let sep = ggx.shadowing(Smith::Separable, wo, wi) * ggx.g1(wo);
                    assert!((hc - g2).abs() < 1e-5, "{alpha} {to} {ti}: {hc} vs {g2}");
                    assert!(hc >= sep - 1e-6);
                    if to == 0.0 || ti == 0.0 {
                        assert!((hc - sep).abs() < 1e-6);
                    }
                }
            }
            assert_eq!(ggx.shadowing(Smith::HeightCorrelated, Vec3A::Z, Vec3A::X), 0.0);
        }
    }

    #[test]
    fn visible_normals_integrate_to_one() {
        // The integral of D_wo(m) over the hemisphere is 1 exactly when G1 is D's Smith masking.
        for alpha in [0.05f32, 0.3, 1.0] {
            let ggx = Ggx { alpha };
            for deg in [0.0f32, 60.0, 85.0] {
                let t = deg.to_radians();
                let wo = Vec3A::new(t.sin(), 0.0, t.cos());
                let i = hemisphere(4000, 180, |m| ggx.pdf_visible(wo, m) as f64);
                assert!((i - 1.0).abs() < 2e-3, "alpha {alpha}, {deg} deg: {i}");
            }
        }
    }

    #[test]
    fn visible_normal_sampling_matches_its_pdf_chi2() {
        for alpha in [0.05f32, 0.2, 0.6] {
            let ggx = Ggx { alpha };
            for deg in [5.0f32, 60.0, 85.0] {
                let t = deg.to_radians();
                let wo = Vec3A::new(t.sin(), 0.0, t.cos());
                let dof = testing::assert_chi2(
                    &format!("alpha {alpha}, {deg} deg"),
                    |u, _| Some(ggx.sample_visible(wo, u)).filter(|m| m.z > 0.0),
                    |m| ggx.pdf_visible(wo, m),
                    (Vec3A::Z, Vec3A::Z, alpha),
                    300_000,
                );
                assert!(dof > 50, "{dof}");
            }
        }
    }

    /// The anisotropic distributions: `D cos` integrates to one, visible normals too (so `G1`
    /// is `D`'s Smith masking), their sampling follows their density (chi-square, viewed
    /// across and along the long axis), and with equal widths they are the isotropic ones.
    /// Swapping `ax` and `ay` in `GgxAniso::d` (still normalised) failed the chi-square here
    /// and in the rough conductor's test.
    #[test]
    fn anisotropic_distributions_are_normalised_and_sampled_by_their_density() {
        fn check<M: Microfacet + std::fmt::Debug>(md: M, width: f32) {
            let i = hemisphere(4000, 720, |m| (md.d(m) * m.z) as f64);
            assert!((i - 1.0).abs() < 2e-3, "{md:?}: {i}");
            for (deg, phi) in [(0.0f32, 0.0f32), (60.0, 0.0), (60.0, 90.0), (80.0, 30.0)] {
                let (t, p) = (deg.to_radians(), phi.to_radians());
                let wo = Vec3A::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                let i = hemisphere(4000, 720, |m| md.pdf_visible(wo, m) as f64);
                assert!((i - 1.0).abs() < 3e-3, "{md:?}, {deg} deg, phi {phi}: {i}");
                testing::assert_chi2(
                    &format!("{md:?}, {deg} deg, phi {phi}"),
                    |u, _| Some(md.sample_visible(wo, u)).filter(|m| m.z > 0.0),
                    |m| md.pdf_visible(wo, m),
                    (Vec3A::Z, Vec3A::Z, width),
                    300_000,
                );
            }
        }
        check(GgxAniso { ax: 0.05, ay: 0.4 }, 0.2);
        check(GgxAniso { ax: 0.6, ay: 0.15 }, 0.4);
        check(BeckmannAniso { ax: 0.05, ay: 0.4 }, 0.2);
        check(BeckmannAniso { ax: 0.6, ay: 0.15 }, 0.4);
        let mut r = crate::testing::signed(3);
        for _ in 0..200 {
            let w = Vec3A::new(r(), r(), r().abs()).normalize();
            let (a, b) = (Ggx { alpha: 0.3 }, GgxAniso { ax: 0.3, ay: 0.3 });
            let close = |x: f32, y: f32| (x - y).abs() <= 1e-5 * x.abs().max(1.0);
            assert!(close(a.d(w), b.d(w)) && close(a.g1(w), b.g1(w)), "{w}");
            let (a, b) = (Beckmann { alpha: 0.3 }, BeckmannAniso { ax: 0.3, ay: 0.3 });
            assert!(close(a.d(w), b.d(w)) && close(a.g1(w), b.g1(w)), "{w}");
        }
    }
}
