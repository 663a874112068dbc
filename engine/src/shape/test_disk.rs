//! A shape that exists to test the shape registry (cargo feature `test-shape`): a disk, its
//! RON description, its primitive and its placement in this one file, registered by one line
//! in each list of `shape/mod.rs` and written `TestDisk(center: .., normal: .., radius: ..)` in
//! a scene.
//! Light sampling picks points uniformly by area.

use super::{
    LightSample, MeshPoint, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint,
    area_to_solid_angle,
};
use crate::format::{Positive, V3};
use crate::math::{Frame, concentric_disk, gamma};
use glam::{Affine3A, Vec2, Vec3A};
use obvhs::aabb::Aabb;
use std::f32::consts::PI;

/// A disk in world space: the points within `radius` of `center` in the plane through it
/// normal to `n` (unit), facing along `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestDisk {
    /// Centre.
    pub center: Vec3A,
    /// Unit normal.
    pub n: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
}

impl TestDisk {
    /// Bound on the error of a point re-projected onto the plane.
    fn point_error(&self) -> f32 {
        gamma(7) * (self.center.abs().max_element() + self.radius)
    }
}

impl PrimitiveShape for TestDisk {
    fn aabb(&self) -> Aabb {
        // Along each axis the disk reaches radius * sin(angle between the axis and n).
        let reach =
            self.radius * (Vec3A::ONE - self.n * self.n).max(Vec3A::ZERO).powf(0.5) + self.point_error();
        Aabb { min: self.center - reach, max: self.center + reach }
    }

    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let t = self.n.dot(self.center - o) / self.n.dot(d);
        let inside = (o + t * d - self.center).length_squared() <= self.radius * self.radius;
        if t > 0.0 && t < tmax && inside { t } else { f32::INFINITY }
    }

    fn surface(&self, p: Vec3A, _uv: bool) -> SurfacePoint {
        let p = p - self.n.dot(p - self.center) * self.n;
        let f = Frame::from_normal(self.n);
        let local = (p - self.center) / self.radius;
        let uv = Vec2::new(local.dot(f.t), local.dot(f.b)) * 0.5 + 0.5;
        SurfacePoint {
            p,
            n: self.n,
            ns: self.n,
            ns_base: self.n,
            uv,
            err: self.point_error(),
            on: MeshPoint::NONE,
        }
    }

    fn area(&self) -> f32 {
        PI * self.radius * self.radius
    }

    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        let f = Frame::from_normal(self.n);
        let q = concentric_disk(u) * self.radius;
        let p = self.center + q.x * f.t + q.y * f.b;
        let pdf = area_to_solid_angle(1.0 / self.area(), from, p, self.n);
        LightSample { p, n: self.n, pdf, err: self.point_error() }
    }

    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, _n: Vec3A) -> f32 {
        area_to_solid_angle(1.0 / self.area(), from, p, self.n)
    }
}

/// The disk in its own space, as a scene places it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestDiskShape {
    /// Centre.
    pub center: Vec3A,
    /// Normal (any length but zero).
    pub normal: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
}

/// `TestDisk(center: .., normal: .., radius: r)`.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct TestDiskDesc {
    /// Centre.
    pub center: V3,
    /// Normal (any length but zero).
    pub normal: V3,
    /// Radius (> 0).
    pub radius: Positive,
}

impl ShapeModel for TestDiskShape {
    type Desc = TestDiskDesc;

    fn build(d: TestDiskDesc) -> Result<Self, String> {
        Ok(Self { center: d.center.0.into(), normal: d.normal.0.into(), radius: d.radius.0 })
    }

    /// Exact under rotations, translations and uniform scales (the radius scales by the cube
    /// root of the determinant); other transforms place the disk of the same area.
    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let det = m.matrix3.determinant();
        let n = (m.matrix3.inverse().transpose() * self.normal).normalize_or_zero();
        if !(det.abs() > 0.0) || n == Vec3A::ZERO {
            return Err(ShapeError::Flattened);
        }
        let radius = self.radius * det.abs().cbrt();
        out.push(Primitive::TestDisk(TestDisk { center: m.transform_point3a(self.center), n, radius }));
        Ok(())
    }
}
