//! `objects: [..]`: a shape with a material (a surface) or a medium (a volume), its transform,
//! motion and keyframes; checked as placed (`placement::primitives`) at load.

use super::assets::{MeshFile, open_edge};
use super::material::MaterialRef;
use super::transform::{TransformOp, compose};
use crate::format::{Albedo, Positive, V3};
use crate::placement::{Form, primitives};
use crate::shape::{BoxShape, QuadShape, SphereShape, TriangleShape};
use glam::Vec3;
use serde::Deserialize;

/// One object: a shape with either a material (a surface) or a medium (a volume), and an
/// optional list of transforms.
#[derive(Deserialize, Debug, Clone)]
#[serde(try_from = "RawObject")]
pub struct ObjectDesc {
    /// The shape, in object space.
    pub shape: ShapeDesc,
    /// What the shape is.
    pub body: Body,
    /// Transforms applied in order, first to last (default none).
    pub transform: Vec<TransformOp>,
    /// How it moves (default: it does not).
    pub motion: Option<MotionDesc>,
    /// Keyframed placement, applied after `transform` (default none).
    pub animate: Option<crate::animation::ObjectAnimation>,
}

/// Linear motion: at time `t` the object lies translated by `velocity * t` from where its
/// transform puts it.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, rename = "Motion")]
pub struct MotionDesc {
    /// World units per unit of time.
    pub velocity: V3,
}

/// What an object's shape bounds.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// `material: "name"`: a surface with a material from `materials`.
    Surface(MaterialRef),
    /// `medium: (density: .., albedo: ..)`: an invisible, index-matched boundary (a closed
    /// shape: sphere or box) filled with a homogeneous medium.
    Volume(MediumDesc),
}

/// A homogeneous medium with an isotropic phase function.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, rename = "Medium")]
pub struct MediumDesc {
    /// Extinction coefficient sigma_t per unit length, the same in every channel (> 0).
    pub density: Positive,
    /// Single-scattering albedo sigma_s / sigma_t, components in [0, 1].
    pub albedo: Albedo,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Object")]
struct RawObject {
    shape: ShapeDesc,
    #[serde(default)]
    material: Option<MaterialRef>,
    #[serde(default)]
    medium: Option<MediumDesc>,
    #[serde(default)]
    transform: Vec<TransformOp>,
    #[serde(default)]
    motion: Option<MotionDesc>,
    #[serde(default)]
    animate: Option<crate::animation::ObjectAnimation>,
}

impl TryFrom<RawObject> for ObjectDesc {
    type Error = String;
    /// The object must survive its transform: no quad flattened to no area, every coordinate
    /// within [`MAX_COORDINATE`]; a medium needs a closed shape.
    fn try_from(r: RawObject) -> Result<Self, String> {
        let body = match (r.material, r.medium) {
            (Some(m), None) => Body::Surface(m),
            (None, Some(_))
                if !matches!(r.shape, ShapeDesc::Mesh(_)) && r.shape.form().closed().is_none() =>
            {
                return Err("a medium needs a closed shape: Sphere, Box or a closed Mesh".into());
            }
            (None, Some(_)) if matches!(&r.shape, ShapeDesc::Mesh(m) if open_edge(&m.mesh).is_some()) => {
                let ShapeDesc::Mesh(m) = &r.shape else { unreachable!() };
                let (a, b, n) = open_edge(&m.mesh).unwrap();
                return Err(format!(
                    "a medium needs a closed mesh, but in {} the edge from {a} to {b} borders {n} triangle(s)",
                    m.path.display()
                ));
            }
            (None, Some(m)) => Body::Volume(m),
            (Some(_), Some(_)) => return Err("an object has a `material` or a `medium`, not both".into()),
            (None, None) => {
                return Err("an object needs a `material` (a surface) or a `medium` (a volume)".into());
            }
        };
        if r.motion.is_some() && matches!(body, Body::Volume(_)) {
            return Err("media do not move: `motion` is for surfaces".into());
        }
        if r.animate.is_some() && matches!(body, Body::Volume(_)) {
            return Err("media do not move: `animate` is for surfaces".into());
        }
        primitives(&r.shape.form(), &compose(&r.transform), &mut Vec::new()).map_err(|e| e.to_string())?;
        Ok(Self { shape: r.shape, body, transform: r.transform, motion: r.motion, animate: r.animate })
    }
}

/// Shapes.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(try_from = "RawShape")]
pub enum ShapeDesc {
    /// `Sphere(center: (x, y, z), radius: r)`.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// `Quad(q: .., u: .., v: ..)`: the points q + a u + b v, a, b in [0, 1]; normal u x v.
    Quad {
        /// Corner.
        q: Vec3,
        /// First edge.
        u: Vec3,
        /// Second edge (not parallel to u).
        v: Vec3,
    },
    /// `Triangle(a: .., b: .., c: ..)`: normal (b - a) x (c - a); uv = barycentric weights of
    /// b and c.
    Triangle {
        /// First vertex.
        a: Vec3,
        /// Second vertex.
        b: Vec3,
        /// Third vertex.
        c: Vec3,
    },
    /// `Mesh(file: "assets/knot.obj")`: the triangles of an OBJ file (relative to the scene
    /// file), flat shaded; triangles without area are dropped.
    Mesh(MeshFile),
    /// `Box(a: .., b: ..)`: the axis-aligned box between two opposite corners, six quads facing out.
    Box {
        /// Minimum corner.
        min: Vec3,
        /// Maximum corner.
        max: Vec3,
    },
    /// `TestDisk(center: .., normal: .., radius: r)` (feature `test-shape`).
    #[cfg(feature = "test-shape")]
    TestDisk(crate::shape::test_disk::TestDiskShape),
}

impl ShapeDesc {
    /// The shape as the world holds it (the mesh shared, not copied).
    pub fn form(&self) -> Form {
        match *self {
            ShapeDesc::Sphere { center, radius } => {
                Form::Sphere(SphereShape { center: center.into(), radius })
            }
            ShapeDesc::Quad { q, u, v } => Form::Quad(QuadShape { q: q.into(), u: u.into(), v: v.into() }),
            ShapeDesc::Triangle { a, b, c } => {
                Form::Triangle(TriangleShape { a: a.into(), b: b.into(), c: c.into() })
            }
            ShapeDesc::Mesh(ref file) => Form::Mesh(file.mesh.clone()),
            ShapeDesc::Box { min, max } => Form::Box(BoxShape { min: min.into(), max: max.into() }),
            #[cfg(feature = "test-shape")]
            ShapeDesc::TestDisk(d) => Form::TestDisk(d),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Shape")]
enum RawShape {
    Sphere {
        center: V3,
        radius: Positive,
    },
    Quad {
        q: V3,
        u: V3,
        v: V3,
    },
    Triangle {
        a: V3,
        b: V3,
        c: V3,
    },
    Mesh {
        file: MeshFile,
    },
    Box {
        a: V3,
        b: V3,
    },
    #[cfg(feature = "test-shape")]
    TestDisk {
        center: V3,
        normal: V3,
        radius: Positive,
    },
}

impl TryFrom<RawShape> for ShapeDesc {
    type Error = String;
    fn try_from(r: RawShape) -> Result<Self, String> {
        Ok(match r {
            RawShape::Sphere { center, radius } => ShapeDesc::Sphere { center: center.0, radius: radius.0 },
            RawShape::Quad { q, u, v } => {
                let c = u.0.cross(v.0);
                if !(c.length_squared() > 0.0) {
                    return Err(format!("Quad has no area: u {} and v {} are parallel or zero", u.0, v.0));
                }
                ShapeDesc::Quad { q: q.0, u: u.0, v: v.0 }
            }
            RawShape::Triangle { a, b, c } => {
                if !((b.0 - a.0).cross(c.0 - a.0).length_squared() > 0.0) {
                    return Err(format!("Triangle has no area: {}, {} and {} are collinear", a.0, b.0, c.0));
                }
                ShapeDesc::Triangle { a: a.0, b: b.0, c: c.0 }
            }
            RawShape::Mesh { file } => ShapeDesc::Mesh(file),
            #[cfg(feature = "test-shape")]
            RawShape::TestDisk { center, normal, radius } => {
                ShapeDesc::TestDisk(crate::shape::test_disk::TestDiskShape {
                    center: center.0.into(),
                    normal: normal.0.into(),
                    radius: radius.0,
                })
            }
            RawShape::Box { a, b } => {
                let (min, max) = (a.0.min(b.0), a.0.max(b.0));
                if (max - min).min_element() <= 0.0 {
                    return Err(format!("Box is flat: corners {} and {} share a coordinate", a.0, b.0));
                }
                ShapeDesc::Box { min, max }
            }
        })
    }
}
