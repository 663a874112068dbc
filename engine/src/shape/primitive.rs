//! The scene's primitives: every shape kind the primitive BVH holds, behind one enum whose
//! methods dispatch to the kind's own file.

use super::{Quad, Sphere, SurfacePoint, TransformedSphere, Triangle};
use glam::Vec3A;
use obvhs::aabb::Aabb;

/// One primitive of the scene, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Primitive {
    /// A sphere (translated and uniformly scaled spheres are baked into this form).
    Sphere(Sphere),
    /// A parallelogram (quads take any affine transform exactly).
    Quad(Quad),
    /// A sphere under a general affine transform.
    TransformedSphere(TransformedSphere),
    /// A triangle (watertight intersection).
    Triangle(Triangle),
}

impl Primitive {
    /// World-space bounds.
    pub fn aabb(&self) -> Aabb {
        match self {
            Primitive::Sphere(s) => s.aabb(),
            Primitive::Quad(q) => q.aabb(),
            Primitive::TransformedSphere(s) => s.aabb(),
            Primitive::Triangle(t) => t.aabb(),
        }
    }

    /// Smallest `t` in `(0, tmax)` or `f32::INFINITY`.
    #[inline]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        match self {
            Primitive::Sphere(s) => s.intersect(o, d, tmax),
            Primitive::Quad(q) => q.intersect(o, d, tmax),
            Primitive::TransformedSphere(s) => s.intersect(o, d, tmax),
            Primitive::Triangle(t) => t.intersect(o, d, tmax),
        }
    }

    /// Surface data at a point found by [`Self::intersect`]; spheres leave their texture
    /// coordinates at zero unless `uv` (quads and triangles have theirs for free).
    #[inline(always)]
    pub fn surface(&self, p: Vec3A, uv: bool) -> SurfacePoint {
        match self {
            Primitive::Sphere(s) => s.surface_with(p, uv),
            Primitive::Quad(q) => q.surface(p),
            Primitive::TransformedSphere(s) => s.surface_with(p, uv),
            Primitive::Triangle(t) => t.surface(p),
        }
    }
}
