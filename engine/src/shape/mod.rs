//! Geometric primitives in world space: each file holds one shape with its intersection,
//! surface data, sampling and tests.

mod primitive;
pub(crate) mod quad;
pub(crate) mod sphere;
mod transformed_sphere;
mod triangle;

pub use primitive::{Primitive, PrimitiveShape};
pub use quad::{Quad, QuadLight, SPHERICAL_MIN_ESTIMATE};
pub use sphere::Sphere;
pub use transformed_sphere::TransformedSphere;
pub use triangle::Triangle;

use glam::{Vec2, Vec3A};

/// What a shape reports about the point a ray hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// The hit point, re-projected onto the surface where that is cheap. On a mesh with vertex
    /// normals it is moved along `n` halfway to the smooth surface they describe and `err` grows
    /// to match, so that rays leaving on `n`'s side start at that surface and the others where
    /// they would have (see [`crate::mesh::terminator_lift`]).
    pub p: Vec3A,
    /// Unit geometric normal on the shape's outside (for a quad: along `u x v`): rays leave
    /// the surface along it.
    pub n: Vec3A,
    /// Unit shading normal, on the side of `n`: BSDFs are evaluated about it. It differs from
    /// `n` only on meshes with vertex normals, where it is adapted to the ray that hit
    /// ([`adapt_shading_normal`]).
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

/// The shading normal `ns` of a smooth-shaded surface with unit geometric normal `n` (on the
/// side of `ns`), adapted to a ray arriving from the unit direction `wo`, so that `wo` lies on
/// the same side of both normals and its mirror reflection about the result leaves the
/// surface on that side, at least as steeply as `min(0.9 |wo . n|, 0.01)` (the cosine with `n`).
///
/// Interpolated normals tilt away from the facet's: near a coarse mesh's silhouette the camera
/// sees facets from behind their shading normal, where a BSDF about `ns` reflects into the
/// surface (or, one-sided, not at all) and the pixel goes black. This is the adaptation of
/// Keller et al., "The Iray Light Transport Simulation and Rendering System" (SIGGRAPH 2017
/// Talks, section "Local Shading Normal Adaption"), as Blender Cycles writes it
/// (`ensure_valid_specular_reflection`): where the reflection falls short, `ns` turns towards
/// `n` in the plane of the two, just far enough. It depends on `wo` only, so every BSDF sees
/// one normal at the vertex and light and BSDF sampling stay consistent; `ns` is returned
/// unchanged wherever the reflection is valid (away from silhouettes and grazing views).
#[inline]
pub fn adapt_shading_normal(n: Vec3A, ns: Vec3A, wo: Vec3A) -> Vec3A {
    // Work on the side wo comes from: g . wo > 0, and N on g's side (n . ns >= 0).
    let side = if wo.dot(n) < 0.0 { -1.0 } else { 1.0 };
    let (g, nn) = (side * n, side * ns);
    let iz = wo.dot(g);
    let threshold = (0.9 * iz).min(0.01);
    // The mirror direction's cosine with g: 2 (N . wo)(N . g) - wo . g.
    if 2.0 * nn.dot(wo) * nn.dot(g) - iz >= threshold {
        return ns;
    }
    // N' = nx x + nz g in the plane of g and N (x: N's part across g), with the reflection of
    // wo about N' at cosine `threshold` with g: 2 (N' . wo) nz - iz = threshold. Squaring gives
    // 4 a nz^4 - 2 b nz^2 + c = 0 with the coefficients below. Of its two roots the unsquared
    // equation keeps the larger where wo leans away from N (ix < 0: 2 (N' . wo) nz - iz must
    // come from nz^2 > 1/2), else the smaller.
    let x = (nn - nn.dot(g) * g).normalize_or_zero();
    if x == Vec3A::ZERO {
        return ns;
    }
    let ix = wo.dot(x);
    let a = ix * ix + iz * iz;
    let b = 2.0 * (a + iz * threshold);
    let c = (iz + threshold) * (iz + threshold);
    let root = (b * b - 4.0 * a * c).max(0.0).sqrt();
    let nz2 = if a < 1e-6 {
        0.5
    } else if ix < 0.0 {
        0.25 * (b + root) / a
    } else {
        0.25 * (b - root) / a
    };
    let (nx, nz) = ((1.0 - nz2).max(0.0).sqrt(), nz2.max(0.0).sqrt());
    let adapted = (nx * x + nz * g).normalize();
    // At grazing arrival the root loses its digits: where the reflection would still not
    // leave, the geometric normal (whose reflection always does) shades.
    if 2.0 * adapted.dot(wo) * adapted.dot(g) - iz > 0.0 { side * adapted } else { n }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adapted_shading_normals_reflect_above_the_surface() {
        let mut rnd = crate::testing::signed(11);
        let mut unit = move || Vec3A::new(rnd(), rnd(), rnd()).normalize();
        let reflect = |wo: Vec3A, n: Vec3A| 2.0 * wo.dot(n) * n - wo;
        let mut adapted = 0;
        for _ in 0..200_000 {
            let n = unit();
            let mut ns = unit();
            if ns.dot(n) < 0.0 {
                ns = -ns;
            }
            let wo = unit();
            let a = adapt_shading_normal(n, ns, wo);
            assert!((a.length() - 1.0).abs() < 1e-5 && a.dot(n) >= -1e-6, "{n} {ns} {wo} -> {a}");
            let side = wo.dot(n).signum();
            let want = (0.9 * wo.dot(n).abs()).min(0.01);
            let r = reflect(wo, a).dot(n) * side;
            // Always above the surface, and up to rounding at grazing arrival at the threshold.
            assert!(r > 0.0 && r >= want - 1e-3, "{n} {ns} {wo} -> {a}: reflection at {r}, want {want}");
            assert!(wo.dot(a) * side > 0.0, "{n} {ns} {wo} -> {a}");
            if a != ns {
                adapted += 1;
                // Just far enough: the reflection grazes the threshold, and the normal turned
                // towards n in the plane of n and ns.
                assert!(r <= want + 2e-3, "{n} {ns} {wo} -> {a}: reflection at {r}, want {want}");
                assert!(a.dot(n) >= ns.dot(n) - 1e-6);
                assert!(n.cross(ns).normalize().dot(a).abs() < 1e-4);
            }
        }
        assert!(adapted > 10_000, "{adapted}");
    }
}
