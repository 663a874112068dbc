//! Geometric primitives in world space: each file holds one shape with its intersection,
//! surface data, sampling and tests.

pub(crate) mod quad;
pub(crate) mod sphere;
mod transformed_sphere;
mod triangle;

pub use quad::{Quad, SPHERICAL_MIN_ESTIMATE};
pub use sphere::Sphere;
pub use transformed_sphere::TransformedSphere;
pub use triangle::Triangle;

use glam::{Vec2, Vec3A};

/// What a shape reports about the point a ray hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// The hit point, re-projected onto the surface where that is cheap.
    pub p: Vec3A,
    /// Unit geometric normal on the shape's outside (for a quad: along `u x v`): rays leave
    /// the surface along it.
    pub n: Vec3A,
    /// Unit shading normal, on the side of `n`: BSDFs are evaluated about it. It differs from
    /// `n` only on meshes with vertex normals.
    pub ns: Vec3A,
    /// Surface parameterisation (see each shape).
    pub uv: Vec2,
    /// Bound on the absolute error of each coordinate of `p` (for spawning rays off it).
    pub err: f32,
}

/// A point sampled on an emitter, with its density in solid angle as seen from the reference point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Point on the emitter.
    pub p: Vec3A,
    /// Unit outward normal there.
    pub n: Vec3A,
    /// Density with respect to solid angle at the reference point.
    pub pdf: f32,
    /// Bound on the absolute error of each coordinate of `p`.
    pub err: f32,
}

/// Converts an area density at `p` (normal `n`) to a solid-angle density seen from `from`.
#[inline]
pub(crate) fn area_to_solid_angle(pdf_area: f32, from: Vec3A, p: Vec3A, n: Vec3A) -> f32 {
    let d = p - from;
    let dist2 = d.length_squared();
    let cos = (n.dot(d) / dist2.sqrt()).abs();
    if cos <= 0.0 { 0.0 } else { pdf_area * dist2 / cos }
}
