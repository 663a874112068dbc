//! Sphere: the numerically robust quadratic of Ray Tracing Gems ch. 7, and for emitters
//! sampling of the cone of directions it subtends (Shirley, "Ray Tracing: The Rest of Your
//! Life"; pbrt-v4's `Sphere::Sample` from a reference point).

use super::{
    Closed, LightSample, MeshPoint, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint,
    TransformedSphere, area_to_solid_angle,
};
use crate::format::{Positive, V3};
use crate::math::{cos_sin_turn, dot3 as dot, gamma, uniform_sphere};
use glam::{Affine3A, Mat3A, Vec2, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use std::f32::consts::PI;

/// A sphere light as plain numbers, for sampling many points at once (see
/// [`cone_sample`]): centre, radius, the error bound of its points and its emission.
#[derive(Clone, Copy, Debug)]
pub struct SphereLight {
    /// Centre.
    pub center: [f32; 3],
    /// Radius.
    pub radius: f32,
    /// [`Sphere::point_error`].
    pub err: f32,
    /// Emitted radiance.
    pub emit: [f32; 3],
    /// Emits on both sides (inwards too).
    pub two_sided: bool,
}

/// The squared distance from `from` to the centre `c`.
#[inline(always)]
fn center_distance2(c: [f32; 3], from: [f32; 3]) -> f32 {
    let d = [c[0] - from[0], c[1] - from[1], c[2] - from[2]];
    dot(d, d)
}

/// A point of the sphere (`center`, `radius`) seen from `from`, uniform in the cone of
/// directions it subtends, for the numbers `u`: its unit normal and the density in solid angle,
/// and whether `from` is inside (then neither means anything). pbrt-v4's `Sphere::Sample`
/// (with its Taylor expansion of `1 - cos` for small cones) on plain numbers, branch-free, so
/// that [`Sphere`]'s light samples and the integrator's lanes compute the same bits.
#[inline(always)]
pub fn cone_sample(center: [f32; 3], radius: f32, from: [f32; 3], u: [f32; 2]) -> ([f32; 3], f32, bool) {
    let dc2 = center_distance2(center, from);
    let r2 = radius * radius;
    let sin2_max = r2 / dc2;
    let sin_max = sin2_max.sqrt();
    let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
    // Small cones: the Taylor expansion keeps 1 - cos precise.
    let small = sin2_max < 0.000_685_23;
    let cos_big = (cos_max - 1.0) * u[0] + 1.0;
    let sin2_small = sin2_max * u[0];
    let sin2_t = if small { sin2_small } else { (1.0 - cos_big * cos_big).max(0.0) };
    let cos_t = if small { (1.0 - sin2_small).sqrt() } else { cos_big };
    let one_minus_cos_max = if small { sin2_max / 2.0 } else { 1.0 - cos_max };
    let cos_alpha = sin2_t / sin_max + cos_t * (1.0 - sin2_t / sin2_max).max(0.0).sqrt();
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let (cos_phi, sin_phi) = cos_sin_turn(u[1]);
    // The direction -w in the frame about the axis to the centre (`Frame::from_normal`).
    let w = [-(sin_alpha * cos_phi), -(sin_alpha * sin_phi), -cos_alpha];
    let dc = dc2.sqrt();
    let a = [(center[0] - from[0]) / dc, (center[1] - from[1]) / dc, (center[2] - from[2]) / dc];
    let sign = 1f32.copysign(a[2]);
    let k = -1.0 / (sign + a[2]);
    let b = a[0] * a[1] * k;
    let t = [1.0 + sign * a[0] * a[0] * k, sign * b, -sign * a[0]];
    let bt = [b, sign + a[1] * a[1] * k, -a[1]];
    let n = std::array::from_fn(|i| t[i] * w[0] + bt[i] * w[1] + a[i] * w[2]);
    (n, 1.0 / (2.0 * PI * one_minus_cos_max), dc2 <= r2)
}

/// A sphere. `uv` as its [`Poles`] say, of the unit vector n from the centre to the point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
    /// The axis of its uv.
    pub poles: Poles,
}

/// The axis through the poles of a sphere's uv; v runs up it from 0 to 1.
#[derive(serde::Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Poles {
    /// u = (atan2(-z, x) + pi) / 2pi around +y (u = 0 and 1 at -x, 0.5 at +x, 0.75 at -z),
    /// v = acos(-y) / pi (default).
    #[default]
    Y,
    /// Mitsuba 3's sphere (its `src/shapes/sphere.cpp`) with pathwave's v (1 - Mitsuba's):
    /// u = atan2(y, x) / 2pi wrapped to [0, 1) (u = 0 at +x, 0.25 at +y), v = acos(-z) / pi.
    Z,
}

impl Sphere {
    /// The sphere of centre `center` and radius `radius`, its uv about +y.
    pub const fn new(center: Vec3A, radius: f32) -> Self {
        Self { center, radius, poles: Poles::Y }
    }

    /// The sphere as a light for lanes of points, emitting `emit` (inwards too if
    /// `two_sided`): see [`SphereLight`].
    pub fn light(&self, emit: [f32; 3], two_sided: bool) -> SphereLight {
        SphereLight {
            center: self.center.to_array(),
            radius: self.radius,
            err: self.point_error(),
            emit,
            two_sided,
        }
    }

    /// Error bound of points computed as `center + r n`: it scales with |center| + r (the huge
    /// ground sphere of spheres-sky has an error of ~ulp(1000) at points near y = 0).
    #[inline]
    pub fn point_error(&self) -> f32 {
        gamma(6) * (self.center.abs().max_element() + self.radius)
    }
}

/// The sphere test on plain numbers, branch-free so that a loop over many rays vectorises; the
/// stream tests use it, and [`sphere_t_single`] gives the same bits for single rays.
#[inline(always)]
pub fn sphere_t(c: [f32; 3], r: f32, o: [f32; 3], d: [f32; 3], tmax: f32) -> f32 {
    let [a, b, cc, disc] = quadratic(c, r, o, d);
    let t = nearest_root(a, b, cc, disc.max(0.0), tmax);
    if disc >= 0.0 { t } else { f32::INFINITY }
}

/// [`sphere_t`] for one ray: a ray that misses (or a NaN discriminant) returns before the
/// square root and the two divisions. The roots of a ray that hits are computed by the same
/// operations, so both give the same bits; spheres-sky traces 3% faster with the early exit.
#[inline(always)]
pub fn sphere_t_single(c: [f32; 3], r: f32, o: [f32; 3], d: [f32; 3], tmax: f32) -> f32 {
    let [a, b, cc, disc] = quadratic(c, r, o, d);
    if !(disc >= 0.0) {
        return f32::INFINITY;
    }
    nearest_root(a, b, cc, disc, tmax)
}

/// The quadratic `a t^2 + 2 b t + cc` of the ray `o + t d` against the sphere, and its
/// discriminant (over 4) computed as `a (r^2 - |f - (b / a) d|^2)`: `[a, b, cc, disc]`.
#[inline(always)]
fn quadratic(c: [f32; 3], r: f32, o: [f32; 3], d: [f32; 3]) -> [f32; 4] {
    let f = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
    let a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
    let k = b / a;
    let l = [f[0] - k * d[0], f[1] - k * d[1], f[2] - k * d[2]];
    let r2 = r * r;
    let disc = a * (r2 - (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]));
    let cc = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) - r2;
    [a, b, cc, disc]
}

/// The smallest root in `(0, tmax)` (or infinity) of a quadratic with `disc >= 0`, as `cc / q`
/// and `q / a`.
#[inline(always)]
fn nearest_root(a: f32, b: f32, cc: f32, disc: f32, tmax: f32) -> f32 {
    let q = -(b + disc.sqrt().copysign(b));
    let (t0, t1) = (cc / q, q / a);
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    if lo > 0.0 && lo < tmax {
        lo
    } else if hi > 0.0 && hi < tmax {
        hi
    } else {
        f32::INFINITY
    }
}

/// A sphere in its own space, as a scene places it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereShape {
    /// Centre.
    pub center: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
    /// The axis of its uv.
    pub poles: Poles,
}

/// The uv of the unit vector (x, y, z) from the centre: with `poles: Y` (default) u = (atan2(-z,
/// x) + pi) / 2pi, v = acos(-y) / pi; with `poles: Z` (Mitsuba 3's sphere, v flipped as pathwave's
/// images) u = atan2(y, x) / 2pi wrapped to [0, 1), v = acos(-z) / pi.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct SphereDesc {
    /// Centre.
    pub center: V3,
    /// Radius (> 0).
    pub radius: Positive,
    /// The axis of its uv, in its own space (default `Y`).
    #[serde(default)]
    pub poles: Poles,
}

impl ShapeModel for SphereShape {
    type Desc = SphereDesc;

    fn build(d: SphereDesc) -> Result<Self, String> {
        Ok(Self { center: d.center.0.into(), radius: d.radius.0, poles: d.poles })
    }

    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let sphere = Sphere { center: self.center, radius: self.radius, poles: self.poles };
        // Translation and uniform scale keep a sphere a sphere (and its uv frame); anything
        // else is intersected in object space.
        let lin = m.matrix3;
        let s = lin.x_axis.x;
        let diagonal_uniform = s > 0.0 && lin == Mat3A::from_diagonal(Vec3::splat(s));
        if diagonal_uniform {
            let center = m.transform_point3a(sphere.center);
            out.push(Primitive::Sphere(Sphere { center, radius: self.radius * s, poles: self.poles }));
        } else {
            let ts = TransformedSphere::new(sphere, *m).ok_or(ShapeError::FlatSphere)?;
            out.push(Primitive::TransformedSphere(ts));
        }
        Ok(())
    }

    fn closed(&self) -> Option<Closed> {
        Some(Closed::Sphere { center: self.center, radius: self.radius })
    }
}

impl PrimitiveShape for Sphere {
    /// Bounding box.
    fn aabb(&self) -> Aabb {
        Aabb::new(self.center - Vec3A::splat(self.radius), self.center + Vec3A::splat(self.radius))
    }

    /// Smallest `t` in `(0, tmax)` where `o + t d` meets the sphere, or `f32::INFINITY`.
    ///
    /// The discriminant is computed as `r^2 - |f - (f.d / d.d) d|^2` and the roots as `c / q`,
    /// `q / a`, which avoids the cancellation of the textbook formula for huge, tiny or distant
    /// spheres (the radius-1000 ground of spheres-sky).
    #[inline]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        sphere_t_single(self.center.to_array(), self.radius, o.to_array(), d.to_array(), tmax)
    }

    /// `dp/du` along the parallel, the way u grows: 2 pi times `(z, 0, -x)` about +y, and
    /// times `(-y, x, 0)` about +z (Mitsuba's sphere's `dp_du`), of the point seen from the
    /// centre; `dp/dv` along the meridian towards the pole where v is 1, pi r long. `None` at
    /// the poles, where the parameterisation folds.
    fn derivatives(&self, sp: &SurfacePoint) -> Option<(Vec3A, Vec3A)> {
        let d = sp.p - self.center;
        let (dpdu, axis) = match self.poles {
            Poles::Y => (Vec3A::new(d.z, 0.0, -d.x), Vec3A::Y),
            Poles::Z => (Vec3A::new(-d.y, d.x, 0.0), Vec3A::Z),
        };
        let n = d / d.length();
        let meridian = axis - n * n.dot(axis);
        let sin = meridian.length();
        (sin > 0.0).then(|| (2.0 * PI * dpdu, (PI * self.radius / sin) * meridian))
    }

    /// Surface data at the point `p` (re-projected onto the sphere), with the texture
    /// coordinates (an `atan2` and an `acos`) only if `uv` (else zero): scenes without textures
    /// never read them.
    #[inline]
    fn surface(&self, p: Vec3A, uv: bool) -> SurfacePoint {
        let d = p - self.center;
        let n = d / d.length();
        let p = self.center + self.radius * n;
        let uv = match (uv, self.poles) {
            (true, Poles::Y) => Vec2::new(
                (crate::math::atan2(-n.z, n.x) + PI) / (2.0 * PI),
                crate::math::acos((-n.y).clamp(-1.0, 1.0)) / PI,
            ),
            (true, Poles::Z) => {
                let phi = crate::math::atan2(n.y, n.x);
                let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
                // 2 pi rounded up for phi just below 0: u stays below 1.
                Vec2::new(
                    (phi / (2.0 * PI)).min(1.0 - f32::EPSILON / 2.0),
                    crate::math::acos((-n.z).clamp(-1.0, 1.0)) / PI,
                )
            }
            (false, _) => Vec2::ZERO,
        };
        SurfacePoint { p, n, ns: n, ns_base: n, uv, err: self.point_error(), on: MeshPoint::NONE }
    }

    /// Surface area.
    fn area(&self) -> f32 {
        4.0 * PI * self.radius * self.radius
    }

    fn sample_area(&self, u: Vec2) -> Option<LightSample> {
        let n = uniform_sphere(u);
        Some(LightSample {
            p: self.center + self.radius * n,
            n,
            pdf: 1.0 / self.area(),
            err: self.point_error(),
        })
    }

    /// Samples a point of the sphere visible from `from`: uniformly in the cone it subtends when
    /// `from` is outside, uniformly by area when inside.
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        let (n, pdf, inside) =
            cone_sample(self.center.to_array(), self.radius, from.to_array(), u.to_array());
        if inside {
            let n = uniform_sphere(u);
            let p = self.center + self.radius * n;
            return LightSample {
                p,
                n,
                pdf: area_to_solid_angle(1.0 / self.area(), from, p, n),
                err: self.point_error(),
            };
        }
        let n = Vec3A::from(n);
        LightSample { p: self.center + self.radius * n, n, pdf, err: self.point_error() }
    }

    /// Solid-angle density of [`Self::sample_solid_angle`] for the point `p` (normal `n`) seen from `from`.
    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, n: Vec3A) -> f32 {
        let dc2 = center_distance2(self.center.to_array(), from.to_array());
        let r2 = self.radius * self.radius;
        if dc2 <= r2 {
            return area_to_solid_angle(1.0 / self.area(), from, p, n);
        }
        let sin2_max = r2 / dc2;
        let one_minus_cos_max =
            if sin2_max < 0.000_685_23 { sin2_max / 2.0 } else { 1.0 - (1.0 - sin2_max).sqrt() };
        1.0 / (2.0 * PI * one_minus_cos_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Sphere {
        Sphere::new(Vec3A::ZERO, 1.0)
    }

    /// `dp/du` is orthogonal to the normal and points where u grows, for both pole axes (the
    /// opposite sign about +y failed).
    #[test]
    fn dpdu_points_where_u_grows() {
        let mut r = crate::testing::signed(8);
        for poles in [Poles::Y, Poles::Z] {
            let s = Sphere { center: Vec3A::new(1.0, -2.0, 0.5), radius: 2.0, poles };
            for _ in 0..200 {
                let dir = Vec3A::new(r(), r(), r()).normalize();
                let sp = s.surface(s.center + 2.0 * dir, true);
                let (t, _) = s.derivatives(&sp).unwrap();
                assert!(t.dot(sp.n).abs() < 1e-5 * t.length().max(1e-3), "{poles:?}");
                let ahead = s.surface(sp.p + 1e-3 * t.normalize(), true);
                let du = ahead.uv.x - sp.uv.x;
                // Across the seam u wraps from 1 to 0.
                assert!(du > 0.0 || du < -0.5, "{poles:?} {} {}", sp.uv.x, ahead.uv.x);
            }
        }
    }

    #[test]
    fn hit_from_outside_takes_near_root() {
        let t = unit().intersect(Vec3A::new(0.0, 0.0, -5.0), Vec3A::Z, f32::INFINITY);
        assert!((t - 4.0).abs() < 1e-6);
    }

    #[test]
    fn miss_and_behind_origin() {
        let s = unit();
        assert_eq!(s.intersect(Vec3A::new(0.0, 2.0, -5.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(s.intersect(Vec3A::new(0.0, 0.0, 5.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(s.intersect(Vec3A::new(0.0, 0.0, -5.0), Vec3A::Z, 3.9), f32::INFINITY, "tmax");
    }

    #[test]
    fn inside_takes_far_root() {
        let t = unit().intersect(Vec3A::ZERO, Vec3A::new(0.0, 2.0, 0.0), f32::INFINITY);
        assert!((t - 0.5).abs() < 1e-6, "unnormalised direction keeps t parametric: {t}");
    }

    #[test]
    fn grazing_ray_touches_tangent() {
        let s = unit();
        let t = s.intersect(Vec3A::new(-5.0, 1.0 - 1e-4, 0.0), Vec3A::X, f32::INFINITY);
        assert!(t.is_finite() && (t - 5.0).abs() < 0.02, "{t}");
        let miss = s.intersect(Vec3A::new(-5.0, 1.0 + 1e-4, 0.0), Vec3A::X, f32::INFINITY);
        assert_eq!(miss, f32::INFINITY);
    }

    #[test]
    fn huge_sphere_is_precise() {
        // The spheres-sky ground: a ray from the camera height hitting y = 0 far away.
        let s = Sphere::new(Vec3A::new(0.0, -1000.0, 0.0), 1000.0);
        let o = Vec3A::new(13.0, 2.0, 3.0);
        let d = Vec3A::new(-13.0, -2.0, -3.0).normalize();
        let t = s.intersect(o, d, f32::INFINITY);
        let p = o + t * d;
        let err = ((p - s.center).length() - 1000.0).abs();
        assert!(err < 1e-3, "hit point {err} off the surface");
        assert!(p.y.abs() < 1e-3, "p = {p}");
    }

    #[test]
    fn single_ray_test_gives_the_stream_tests_bits() {
        let mut rnd = crate::testing::signed(31);
        let mut hits = 0;
        for i in 0..20_000 {
            let c = [rnd() * 5.0, rnd() * 5.0, rnd() * 5.0];
            let r = [0.01, 1.0, 4.0, 1000.0][i % 4];
            let o = [rnd() * 10.0, rnd() * 10.0, rnd() * 10.0];
            // Many rays aimed near the sphere's rim, where the discriminant is close to zero.
            let aim = [c[0] + r * rnd(), c[1] + r * rnd(), c[2] + r * rnd()];
            let d = [aim[0] - o[0], aim[1] - o[1], aim[2] - o[2]];
            let tmax = [f32::INFINITY, 1.0, 0.5][i % 3];
            let (a, b) = (sphere_t(c, r, o, d, tmax), sphere_t_single(c, r, o, d, tmax));
            assert_eq!(a.to_bits(), b.to_bits(), "sphere {c:?} {r}, ray {o:?} {d:?}");
            hits += a.is_finite() as u32;
        }
        assert!((2_000..18_000).contains(&hits), "hits and misses both exercised: {hits}");
        // A NaN direction misses in both.
        let nan = [f32::NAN, 0.0, 1.0];
        assert_eq!(sphere_t([0.0; 3], 1.0, [0.0, 0.0, -5.0], nan, f32::INFINITY), f32::INFINITY);
        assert_eq!(sphere_t_single([0.0; 3], 1.0, [0.0, 0.0, -5.0], nan, f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn surface_uv_conventions() {
        let s = unit();
        let sp = s.surface(Vec3A::new(0.0, -1.0, 0.0), true);
        assert!(sp.uv.y.abs() < 1e-6, "v = 0 at the bottom pole");
        let sp = s.surface(Vec3A::new(1.0, 0.0, 0.0), true);
        assert!((sp.uv - Vec2::new(0.5, 0.5)).length() < 1e-6, "{:?}", sp.uv);
    }

    /// `Poles::Z` is Mitsuba's sphere uv (`src/shapes/sphere.cpp`: u = phi / 2pi, phi =
    /// atan2(y, x) in [0, 2pi); v = theta / pi, theta from +z) with v flipped.
    #[test]
    fn z_poles_are_mitsubas_uv_with_v_flipped() {
        let s = Sphere { poles: Poles::Z, ..unit() };
        let mitsuba = |p: Vec3| {
            let phi = (p.y as f64).atan2(p.x as f64).rem_euclid(std::f64::consts::TAU);
            let theta = (p.z as f64).acos();
            Vec2::new((phi / std::f64::consts::TAU) as f32, (theta / std::f64::consts::PI) as f32)
        };
        for p in [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-1.0, 0.1, 0.0),
            Vec3::new(0.3, -0.8, 0.5),
            Vec3::new(-0.2, -0.3, -0.9),
            Vec3::new(0.0, 0.0, 1.0),
        ] {
            let p = p.normalize();
            let uv = s.surface(p.into(), true).uv;
            let want = mitsuba(p);
            assert!((uv - Vec2::new(want.x, 1.0 - want.y)).length() < 1e-5, "{p}: {uv} vs Mitsuba's {want}");
        }
        // Just below phi = 0 the wrapped u stays in [0, 1).
        let uv = s.surface(Vec3A::new(1.0, -1e-9, 0.0), true).uv;
        assert!(uv.x < 1.0, "{uv}");
    }

    #[test]
    fn cone_samples_lie_on_visible_cap_with_constant_pdf() {
        let s = Sphere::new(Vec3A::new(0.0, 0.0, 10.0), 2.0);
        let from = Vec3A::ZERO;
        for i in 0..64 {
            let u = Vec2::new((i as f32 + 0.5) / 64.0, ((i * 37) % 64) as f32 / 64.0);
            let ls = s.sample_solid_angle(from, u);
            assert!(((ls.p - s.center).length() - 2.0).abs() < 1e-4);
            assert!(ls.n.dot(from - ls.p) >= -1e-4, "sampled point faces the reference");
            let expected = s.pdf_solid_angle(from, ls.p, ls.n);
            assert!((ls.pdf - expected).abs() < 1e-3 * expected);
        }
        // The pdf integrates to one over the cone: pdf * solid angle = 1.
        let cos_max = (1.0f32 - 0.04).sqrt();
        let omega = 2.0 * PI * (1.0 - cos_max);
        assert!((s.pdf_solid_angle(from, s.center, Vec3A::Z) * omega - 1.0).abs() < 1e-3);
    }

    #[test]
    fn cone_samples_are_uniform_in_the_cone() {
        use crate::material::chi2::{chi2, chi2_critical};
        // A wide cone, and one narrow enough for the Taylor expansion of 1 - cos.
        for radius in [4.0f32, 0.2] {
            let s = Sphere::new(Vec3A::new(0.0, 0.0, 10.0), radius);
            let sin2_max = (radius as f64 / 10.0).powi(2);
            let cos_max = (1.0 - sin2_max).sqrt();
            let density = 1.0 / (2.0 * std::f64::consts::PI * (1.0 - cos_max));
            let (stat, dof) = chi2(
                |u, _| Some(s.sample_solid_angle(Vec3A::ZERO, u).p.normalize()),
                |w| if w.z as f64 >= cos_max { density as f32 } else { 0.0 },
                Vec3A::Z,
                cos_max - 1e-3 * (1.0 - cos_max),
                200_000,
            );
            assert!(stat < chi2_critical(dof), "radius {radius}: chi2 {stat} with {dof} dof");
        }
    }
}
