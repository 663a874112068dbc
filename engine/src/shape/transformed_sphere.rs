//! A sphere under an arbitrary affine transform (an ellipsoid, possibly sheared): the ray moves
//! to object space, the hit point back, the normal by the inverse transpose (Pharr, Jakob and
//! Humphreys, "Physically Based Rendering", 4th edition, section 3.10).

use super::{LightSample, MeshPoint, PrimitiveShape, Sphere, SurfacePoint, area_to_solid_angle};
use crate::math::{cos_sin_turn, dot3 as dot, gamma};
use glam::{Affine3A, Mat3A, Vec2, Vec3A};
use obvhs::aabb::Aabb;

/// A sphere in object space placed by `world_from_object`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransformedSphere {
    /// The sphere in object space.
    pub sphere: Sphere,
    /// Object to world.
    pub world_from_object: Affine3A,
    /// World to object.
    pub object_from_world: Affine3A,
    /// Inverse transpose of the linear part: maps object normals to world normals.
    pub normal_to_world: Mat3A,
}

impl TransformedSphere {
    /// `None` when the transform is singular.
    pub fn new(sphere: Sphere, world_from_object: Affine3A) -> Option<Self> {
        let det = world_from_object.matrix3.determinant();
        if !(det.abs() > 0.0) || !det.is_finite() {
            return None;
        }
        let object_from_world = world_from_object.inverse();
        Some(Self {
            sphere,
            world_from_object,
            object_from_world,
            normal_to_world: object_from_world.matrix3.transpose(),
        })
    }
}

/// An ellipsoid light as plain numbers, for sampling many points at once (see
/// [`ellipsoid_sample`]): the object-space sphere, its placement, and the light's emission.
#[derive(Clone, Copy, Debug)]
pub struct EllipsoidLight {
    /// Centre of the object-space sphere.
    pub center: [f32; 3],
    /// Its radius.
    pub radius: f32,
    /// Columns of the linear part of world from object, then the translation.
    pub world: [[f32; 3]; 4],
    /// Columns of the inverse transpose of the linear part (object normals to world).
    pub normal: [[f32; 3]; 3],
    /// `|det|` of the linear part.
    pub det: f32,
    /// Largest column sum of `|M|` (how much the map scales errors).
    pub scale: f32,
    /// Largest `|translation|` component.
    pub shift: f32,
    /// The object-space sphere's [`Sphere::point_error`].
    pub sphere_err: f32,
    /// Emitted radiance.
    pub emit: [f32; 3],
    /// Emits on both sides.
    pub two_sided: bool,
}

/// `m v` for the columns `m`, summed as glam sums them.
#[inline(always)]
fn mat_vec(m: &[[f32; 3]], v: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|i| m[0][i] * v[0] + m[1][i] * v[1] + m[2][i] * v[2])
}

/// A point of the ellipsoid `l` sampled uniformly over the object-space sphere's area for the
/// numbers `u`, seen from `from`: the world point, its unit normal, the density in solid angle
/// (zero seen edge-on) and the point's error bound. On plain numbers and branch-free, so that
/// [`TransformedSphere`]'s light samples and the integrator's lanes compute the same bits.
#[inline(always)]
pub fn ellipsoid_sample(l: &EllipsoidLight, from: [f32; 3], u: [f32; 2]) -> ([f32; 3], [f32; 3], f32, f32) {
    // A uniform direction on the unit sphere.
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (cos_phi, sin_phi) = cos_sin_turn(u[1]);
    let n_obj = [r * cos_phi, r * sin_phi, z];
    let po: [f32; 3] = std::array::from_fn(|i| l.center[i] + l.radius * n_obj[i]);
    let m = mat_vec(&l.world[..3], po);
    let p: [f32; 3] = std::array::from_fn(|i| m[i] + l.world[3][i]);
    // The object point's error, scaled by the map, plus the rounding of M p + t.
    let magnitude = l.scale * po[0].abs().max(po[1].abs()).max(po[2].abs()) + l.shift;
    let err = l.scale * l.sphere_err + gamma(4) * magnitude;
    let nw = mat_vec(&l.normal, n_obj);
    let len = dot(nw, nw).sqrt();
    let n = nw.map(|x| x / len);
    // Area density 1 / (4 pi r^2 area_scale), area_scale = |det| |M^-T n_obj|, to solid angle.
    let pdf_area = 1.0 / (4.0 * std::f32::consts::PI * l.radius * l.radius * (l.det * len));
    let d: [f32; 3] = std::array::from_fn(|i| p[i] - from[i]);
    let dist2 = dot(d, d);
    let cos = (dot(n, d) / dist2.sqrt()).abs();
    (p, n, if cos <= 0.0 { 0.0 } else { pdf_area * dist2 / cos }, err)
}

impl TransformedSphere {
    /// The ellipsoid as a light for lanes of points, emitting `emit` (on both sides if
    /// `two_sided`): see [`EllipsoidLight`].
    pub fn light(&self, emit: [f32; 3], two_sided: bool) -> EllipsoidLight {
        let m = self.world_from_object;
        let cols = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
        let n = self.normal_to_world;
        EllipsoidLight {
            center: self.sphere.center.to_array(),
            radius: self.sphere.radius,
            world: [cols[0].to_array(), cols[1].to_array(), cols[2].to_array(), m.translation.to_array()],
            normal: [n.x_axis.to_array(), n.y_axis.to_array(), n.z_axis.to_array()],
            det: m.matrix3.determinant().abs(),
            scale: (cols[0].abs() + cols[1].abs() + cols[2].abs()).max_element(),
            shift: m.translation.abs().max_element(),
            sphere_err: self.sphere.point_error(),
            emit,
            two_sided,
        }
    }

    /// `dA_world / dA_object` at the object-space unit normal `n`: `|det M| |M^-T n|`.
    #[inline]
    fn area_scale(&self, n_obj: Vec3A) -> f32 {
        self.world_from_object.matrix3.determinant().abs() * (self.normal_to_world * n_obj).length()
    }
}

impl PrimitiveShape for TransformedSphere {
    /// World bounding box (the transformed object box: conservative).
    fn aabb(&self) -> Aabb {
        crate::math::transform_box(&self.sphere.aabb(), &self.world_from_object)
    }

    /// Smallest `t` in `(0, tmax)`; the object-space direction is not renormalised, so `t` is the
    /// same in both spaces.
    #[inline]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let lo = self.object_from_world.transform_point3a(o);
        let ld = self.object_from_world.transform_vector3a(d);
        self.sphere.intersect(lo, ld, tmax)
    }

    /// Surface data at the world point `p`, with texture coordinates only if `uv` (as a
    /// [`Sphere`]'s).
    #[inline]
    fn surface(&self, p: Vec3A, uv: bool) -> SurfacePoint {
        let local = self.sphere.surface(self.object_from_world.transform_point3a(p), uv);
        let m = self.world_from_object;
        // |M| times the object-space error, plus the rounding of M p + t.
        let norm = m.matrix3.x_axis.abs() + m.matrix3.y_axis.abs() + m.matrix3.z_axis.abs();
        let scale = norm.max_element();
        let magnitude = scale * local.p.abs().max_element() + m.translation.abs().max_element();
        let n = (self.normal_to_world * local.n).normalize();
        SurfacePoint {
            p: m.transform_point3a(local.p),
            n,
            ns: n,
            ns_base: n,
            uv: local.uv,
            err: scale * local.err + gamma(4) * magnitude,
            on: MeshPoint::NONE,
        }
    }

    /// Surface area of the ellipsoid, estimated from the area scale at 256 Fibonacci-sphere
    /// points (within 0.5% for axis ratios up to 10; only the light-choice probabilities use it).
    fn area(&self) -> f32 {
        const N: usize = 256;
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        let mean = (0..N)
            .map(|i| {
                let z = 1.0 - (2 * i + 1) as f32 / N as f32;
                let r = (1.0 - z * z).sqrt();
                // In f64, rounded: a C library's last bits reach the f32 only at a rounding tie.
                let phi = golden as f64 * i as f64;
                self.area_scale(Vec3A::new(r * phi.cos() as f32, r * phi.sin() as f32, z))
            })
            .sum::<f32>()
            / N as f32;
        self.sphere.area() * mean
    }

    /// Samples a point uniformly over the object-space sphere's area, mapped to world space:
    /// the world area density is `1 / (4 pi r^2 area_scale)` ([`ellipsoid_sample`]).
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        let (p, n, pdf, err) = ellipsoid_sample(&self.light([0.0; 3], false), from.to_array(), u.to_array());
        LightSample { p: p.into(), n: n.into(), pdf, err }
    }

    /// Solid-angle density of [`Self::sample_solid_angle`] for the point `p` (normal `n`) seen
    /// from `from`.
    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, n: Vec3A) -> f32 {
        let n_obj = (self.object_from_world.transform_point3a(p) - self.sphere.center).normalize();
        let pdf_area = 1.0 / (self.sphere.area() * self.area_scale(n_obj));
        area_to_solid_angle(pdf_area, from, p, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::uniform_sphere;
    use glam::Vec3;

    #[test]
    fn ellipsoid_matches_analytic_hit_and_normal() {
        // x^2/4 + y^2 + z^2/9 = 1
        let s = Sphere::new(Vec3A::ZERO, 1.0);
        let ts = TransformedSphere::new(s, Affine3A::from_scale(Vec3::new(2.0, 1.0, 3.0))).unwrap();
        let t = ts.intersect(Vec3A::new(-10.0, 0.0, 0.0), Vec3A::X, f32::INFINITY);
        assert!((t - 8.0).abs() < 1e-5);
        // A hit at a general point: the normal is the gradient (x/4, y, z/9).
        let o = Vec3A::new(0.5, 0.3, -20.0);
        let t = ts.intersect(o, Vec3A::Z, f32::INFINITY);
        let sp = ts.surface(o + t * Vec3A::Z, true);
        let p = sp.p;
        assert!((p.x * p.x / 4.0 + p.y * p.y + p.z * p.z / 9.0 - 1.0).abs() < 1e-5);
        let g = Vec3A::new(p.x / 4.0, p.y, p.z / 9.0).normalize();
        assert!((sp.n - g).length() < 1e-5, "{} vs {}", sp.n, g);
    }

    #[test]
    fn light_sampling_estimates_the_same_irradiance_as_direction_sampling() {
        // A sheared, non-uniformly scaled ellipsoid seen from a point x: the integral of
        // cos(theta) over its solid angle, by sampling the light (a point faces x iff it is
        // visible, the body being convex) and by sampling directions uniformly.
        let m = Affine3A::from_translation(glam::Vec3::new(0.5, 3.0, 0.2))
            * Affine3A::from_mat3(glam::Mat3::from_cols_array(&[
                1.5, 0.0, 0.4, 0.6, 0.7, 0.0, 0.0, 0.3, 1.1,
            ]));
        let ts = TransformedSphere::new(Sphere::new(Vec3A::ZERO, 1.0), m).unwrap();
        let x = Vec3A::ZERO;
        let n = 200_000;
        // The R2 low-discrepancy sequence (Roberts), shifted differently for the two estimates.
        let u = |i: usize, shift: f64| {
            let f = |a: f64| ((shift + i as f64 * a).fract()) as f32;
            Vec2::new(f(0.754_877_666_246_693), f(0.569_840_290_998_053))
        };
        let (mut by_light, mut by_dir) = (0.0f64, 0.0f64);
        for i in 0..n {
            let ls = ts.sample_solid_angle(x, u(i, 0.5));
            let wi = (ls.p - x).normalize();
            if ls.n.dot(-wi) > 0.0 && ls.pdf > 0.0 {
                by_light += (wi.y.max(0.0) / ls.pdf) as f64;
                assert!((ts.pdf_solid_angle(x, ls.p, ls.n) / ls.pdf - 1.0).abs() < 1e-3);
            }
            let d = uniform_sphere(u(i, 0.25));
            if ts.intersect(x, d, f32::INFINITY).is_finite() {
                by_dir += (d.y.max(0.0) * 4.0 * std::f32::consts::PI) as f64;
            }
        }
        let (a, b) = (by_light / n as f64, by_dir / n as f64);
        assert!((a / b - 1.0).abs() < 0.01, "light sampling {a}, direction sampling {b}");
    }

    #[test]
    fn ellipsoid_area() {
        // Semi-axes 2, 1, 1 (prolate): 2 pi (1 + 2 asin(e) / e), e = sqrt(3) / 2.
        let s = Sphere::new(Vec3A::ZERO, 1.0);
        let ts = TransformedSphere::new(s, Affine3A::from_scale(glam::Vec3::new(2.0, 1.0, 1.0))).unwrap();
        let e = 3f32.sqrt() / 2.0;
        let exact = 2.0 * std::f32::consts::PI * (1.0 + 2.0 * e.asin() / e);
        assert!((ts.area() / exact - 1.0).abs() < 0.005, "{} vs {exact}", ts.area());
    }

    #[test]
    fn singular_transform_is_rejected() {
        let s = Sphere::new(Vec3A::ZERO, 1.0);
        assert!(TransformedSphere::new(s, Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0))).is_none());
    }
}
