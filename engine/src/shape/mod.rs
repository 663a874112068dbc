//! Shapes: the kinds a scene places (`Sphere`, `Quad`, `Triangle`, `Box`, `Disk`, `Cylinder`,
//! `SdfGrid`;
//! meshes are the world's business) and the primitives they become in world space. Each file
//! holds one kind: its RON description and its checks, its shape in its own space
//! ([`ShapeModel`]: built from the description, the primitives it becomes under a transform,
//! the volume it closes), its primitive ([`PrimitiveShape`]: bounds, intersection, surface data, light sampling) where it
//! has one, and their tests.
//!
//! Two lists below name the kinds. [`with_shapes!`] is the registry of the shapes a scene
//! places: `Variant(Type)`, the variant being the name a scene writes. From it come the scene
//! format's `ShapeDesc` (the RON enum `Kind(field: value, ...)`, read by the registry of
//! `format::registry`, with meshes beside it: see `scene/object.rs`) and `placement::Form`
//! (what an entity's shape component holds). `primitives!` lists the primitives the BVH holds,
//! generating [`Primitive`]. The two lists differ because a shape and a primitive are not one to
//! one: a `Box` becomes six quads and has no primitive of its own, a `Sphere` becomes a `Sphere`
//! or, under a transform that is not a uniform scale, a `TransformedSphere`, and a mesh's
//! triangles are `Triangle`s. A new kind is its file (description, [`ShapeModel`], and where it
//! needs one a [`PrimitiveShape`]), its `mod` line, its line in [`with_shapes!`] and, if it has
//! a primitive, its line in `primitives!`; its README row, its description's doc comment, is
//! checked (and written with `PATHWAVE_BLESS=1`) by `tests/readme_kinds.rs`.

mod boxes;
mod cylinder;
mod disk;
mod primitive;
pub(crate) mod quad;
mod sdf_grid;
pub(crate) mod sphere;
#[cfg(feature = "test-shape")]
pub mod test_disk;
mod transformed_sphere;
mod triangle;

pub use boxes::{BoxShape, BoxUv};
pub use cylinder::{Cylinder, CylinderShape};
pub use disk::{Disk, DiskShape};
pub use primitive::PrimitiveShape;
use primitive::primitives;
pub use quad::{Quad, QuadLight, QuadShape, SPHERICAL_MIN_ESTIMATE};
pub use sdf_grid::{SdfGridData, SdfGridShape, SdfNormals, SdfVoxel};
pub use sphere::{Poles, Sphere, SphereLight, SphereShape, cone_sample};
pub use transformed_sphere::{EllipsoidLight, TransformedSphere, ellipsoid_sample};
pub use triangle::{Triangle, TriangleShape};

use glam::{Affine3A, Vec2, Vec3A};
use obvhs::aabb::Aabb;

primitives! {
    Sphere(Sphere),
    Quad(Quad),
    TransformedSphere(TransformedSphere),
    Triangle(Triangle),
    Disk(Disk),
    Cylinder(Cylinder),
    SdfVoxel(SdfVoxel),
    #[cfg(feature = "test-shape")]
    TestDisk(test_disk::TestDisk),
}

/// The registry of shapes: calls the macro `$then!` with the list of shape kinds a scene places,
/// `Variant(Type),` each (the variant is the name a scene writes, the type a [`ShapeModel`]).
/// `placement` makes its `Form` of it, the scene format its `ShapeDesc`.
#[macro_export]
#[doc(hidden)]
macro_rules! with_shapes {
    ($then:ident) => {
        $then! {
            Sphere($crate::shape::SphereShape),
            Quad($crate::shape::QuadShape),
            Triangle($crate::shape::TriangleShape),
            Box($crate::shape::BoxShape),
            Disk($crate::shape::DiskShape),
            Cylinder($crate::shape::CylinderShape),
            SdfGrid($crate::shape::SdfGridShape),
            #[cfg(feature = "test-shape")]
            TestDisk($crate::shape::test_disk::TestDiskShape),
        }
    };
}
pub use with_shapes;

/// One kind of shape in its own space, as a scene places it.
pub trait ShapeModel: Clone + std::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// Its parameters as a scene writes them, inside `Kind(...)`: a struct that denies unknown
    /// fields, of validated values (`format::V3`, `format::Positive`, ...).
    type Desc: serde::de::DeserializeOwned;

    /// The shape of a description, or why the description is not one (a scene's error shows the
    /// message at the `)` that closes the shape).
    fn build(desc: Self::Desc) -> Result<Self, String>;

    /// Appends the world-space primitives of the shape placed by `m`, or says why the placed
    /// shape cannot be rendered (a flattening transform). The caller checks the distance from
    /// the origin ([`MAX_COORDINATE`]).
    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError>;

    /// The volume it closes, for a medium to fill; `None` for an open surface.
    fn closed(&self) -> Option<Closed> {
        None
    }
}

/// A closed volume in a shape's own space, as a medium's boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Closed {
    /// The axis-aligned box between two corners.
    Box {
        /// Minimum corner.
        min: Vec3A,
        /// Maximum corner.
        max: Vec3A,
    },
    /// A ball.
    Sphere {
        /// Centre.
        center: Vec3A,
        /// Radius.
        radius: f32,
    },
}

/// How far from the origin anything may lie, in world units. Beyond it the BVH's surface-area
/// arithmetic (extent squared times primitive count) overflows `f32`.
pub const MAX_COORDINATE: f32 = 1e15;

/// Why a placed shape cannot be rendered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A triangle whose corners are collinear.
    #[error("a triangle {0}, {1}, {2} has no area")]
    FlatTriangle(Vec3A, Vec3A, Vec3A),
    /// A quad whose edges are parallel (or tiny).
    #[error("a quad with edges {0} and {1} has no area (or less than 1e-38)")]
    FlatQuad(Vec3A, Vec3A),
    /// A cylinder placed so that its cross-section is not a circle at right angles to its axis.
    #[error(
        "the transform makes the cylinder's cross-section an ellipse or shears its axis: pathwave's \
         cylinders stay circular (scale it the same across its axis)"
    )]
    OvalCylinder,
    /// A sphere under a singular transform.
    #[error("the transform flattens the sphere")]
    FlatSphere,
    /// Another shape under a singular transform.
    #[error("the transform flattens the shape")]
    Flattened,
    /// Coordinates beyond [`MAX_COORDINATE`].
    #[error("the object reaches beyond {MAX_COORDINATE:e} units from the origin")]
    TooFar,
}

/// What a shape reports about the point a ray hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// The hit point, re-projected onto the surface where that is cheap. On a mesh with vertex
    /// normals it is moved along `n` halfway to the smooth surface they describe and `err` grows
    /// to match, so that rays leaving on `n`'s side start at that surface and the others where
    /// they would have (see [`crate::accel::mesh::terminator_lift`]).
    pub p: Vec3A,
    /// Unit geometric normal on the shape's outside (for a quad: along `u x v`): rays leave
    /// the surface along it.
    pub n: Vec3A,
    /// Unit shading normal, on the side of `n`: BSDFs are evaluated about it. It differs from
    /// `n` only on meshes with vertex normals, where it is adapted to the ray that hit
    /// ([`adapt_shading_normal`]), and where a bump or normal map tilts it
    /// ([`crate::material::wrap`]).
    pub ns: Vec3A,
    /// The shading normal before a bump or normal map tilted `ns` (`ns` itself where none
    /// did): the directions a ray may leave in are judged by it, as by the surface the map
    /// decorates.
    pub ns_base: Vec3A,
    /// Surface parameterisation (see each shape).
    pub uv: Vec2,
    /// Bound on the absolute error of each coordinate of `p` (for spawning rays off it).
    pub err: f32,
    /// Where on a mesh the point lies ([`MeshPoint::NONE`] off meshes), for the mesh's
    /// attributes.
    pub on: MeshPoint,
}

/// A point of a placed mesh's triangle, by which the `MeshAttribute` texture reads the mesh's
/// per-vertex and per-face values: the mesh (its index in the scene's list of meshes,
/// `accel::instances::Instances::blas`), the triangle and its barycentric weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshPoint {
    /// Index of the mesh among the scene's meshes, or `u32::MAX` off meshes.
    pub mesh: u32,
    /// Index of the triangle in the mesh; off meshes, the index of the primitive hit among the
    /// scene's primitives (`accel::geometry::Geometry::prims`).
    pub triangle: u32,
    /// Barycentric weights of the triangle's second and third vertices.
    pub b: Vec2,
    /// Index of the placed mesh among the scene's instances (`accel::instances::Instances::list`),
    /// or `u32::MAX` off meshes.
    pub instance: u32,
}

impl SurfacePoint {
    /// A point at the origin of a flat surface with normal `n` (shading normal the same), for
    /// tests.
    #[cfg(test)]
    pub(crate) fn flat(n: Vec3A, uv: Vec2) -> Self {
        Self { p: Vec3A::ZERO, n, ns: n, ns_base: n, uv, err: 0.0, on: MeshPoint::NONE }
    }
}

impl MeshPoint {
    /// Not on a mesh.
    pub const NONE: MeshPoint = MeshPoint { mesh: u32::MAX, triangle: 0, b: Vec2::ZERO, instance: u32::MAX };
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
