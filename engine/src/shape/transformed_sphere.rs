//! A sphere under an arbitrary affine transform (an ellipsoid, possibly sheared): the ray moves
//! to object space, the hit point back, the normal by the inverse transpose (SEED.md section 9).

use super::{Sphere, SurfacePoint};
use crate::math::gamma;
use glam::{Affine3A, Mat3A, Vec3A};
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

    /// World bounding box (the transformed object box: conservative).
    pub fn aabb(&self) -> Aabb {
        let b = self.sphere.aabb();
        let mut out = Aabb::empty();
        for i in 0..8 {
            let c = Vec3A::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            out.extend(self.world_from_object.transform_point3a(c));
        }
        out
    }

    /// Smallest `t` in `(0, tmax)`; the object-space direction is not renormalised, so `t` is the
    /// same in both spaces.
    #[inline]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let lo = self.object_from_world.transform_point3a(o);
        let ld = self.object_from_world.transform_vector3a(d);
        self.sphere.intersect(lo, ld, tmax)
    }

    /// Surface data at the world point `p`.
    #[inline]
    pub fn surface(&self, p: Vec3A) -> SurfacePoint {
        let local = self.sphere.surface(self.object_from_world.transform_point3a(p));
        let m = self.world_from_object;
        // |M| times the object-space error, plus the rounding of M p + t.
        let norm = m.matrix3.x_axis.abs() + m.matrix3.y_axis.abs() + m.matrix3.z_axis.abs();
        let scale = norm.max_element();
        let magnitude = scale * local.p.abs().max_element() + m.translation.abs().max_element();
        SurfacePoint {
            p: m.transform_point3a(local.p),
            n: (self.normal_to_world * local.n).normalize(),
            uv: local.uv,
            err: scale * local.err + gamma(4) * magnitude,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn ellipsoid_matches_analytic_hit_and_normal() {
        // x^2/4 + y^2 + z^2/9 = 1
        let s = Sphere { center: Vec3A::ZERO, radius: 1.0 };
        let ts = TransformedSphere::new(s, Affine3A::from_scale(Vec3::new(2.0, 1.0, 3.0))).unwrap();
        let t = ts.intersect(Vec3A::new(-10.0, 0.0, 0.0), Vec3A::X, f32::INFINITY);
        assert!((t - 8.0).abs() < 1e-5);
        // A hit at a general point: the normal is the gradient (x/4, y, z/9).
        let o = Vec3A::new(0.5, 0.3, -20.0);
        let t = ts.intersect(o, Vec3A::Z, f32::INFINITY);
        let sp = ts.surface(o + t * Vec3A::Z);
        let p = sp.p;
        assert!((p.x * p.x / 4.0 + p.y * p.y + p.z * p.z / 9.0 - 1.0).abs() < 1e-5);
        let g = Vec3A::new(p.x / 4.0, p.y, p.z / 9.0).normalize();
        assert!((sp.n - g).length() < 1e-5, "{} vs {}", sp.n, g);
    }

    #[test]
    fn singular_transform_is_rejected() {
        let s = Sphere { center: Vec3A::ZERO, radius: 1.0 };
        assert!(TransformedSphere::new(s, Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0))).is_none());
    }
}
