//! Shapes placed in the world: a shape in its own space ([`Form`], what an entity's `Shape`
//! component holds) and an object-to-world transform become world-space [`Primitive`]s, or an
//! error that says why the placed shape cannot be rendered. The scene format checks its objects
//! with [`primitives`] at load; the world builds its BVH with it.

use crate::mesh::MeshData;
use crate::shape::{Primitive, Quad, Sphere, TransformedSphere, Triangle};
use glam::{Affine3A, Vec3, Vec3A};
use std::sync::Arc;

/// A shape in its own space.
#[derive(Clone, Debug, PartialEq)]
pub enum Form {
    /// A sphere.
    Sphere {
        /// Centre.
        center: Vec3A,
        /// Radius (> 0).
        radius: f32,
    },
    /// The points q + a u + b v, a, b in [0, 1]; normal u x v.
    Quad {
        /// Corner.
        q: Vec3A,
        /// First edge.
        u: Vec3A,
        /// Second edge.
        v: Vec3A,
    },
    /// A triangle with normal (b - a) x (c - a).
    Triangle {
        /// First vertex.
        a: Vec3A,
        /// Second vertex.
        b: Vec3A,
        /// Third vertex.
        c: Vec3A,
    },
    /// The axis-aligned box between two opposite corners, six quads facing out.
    Box {
        /// Minimum corner.
        min: Vec3A,
        /// Maximum corner.
        max: Vec3A,
    },
    /// A triangle mesh (triangles without area are dropped).
    Mesh(Arc<MeshData>),
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
    /// A sphere under a singular transform.
    #[error("the transform flattens the sphere")]
    FlatSphere,
    /// Coordinates beyond [`MAX_COORDINATE`].
    #[error("the object reaches beyond {MAX_COORDINATE:e} units from the origin")]
    TooFar,
}

/// Appends the world-space primitives of `shape` placed by `m`; an error says why the placed
/// shape cannot be rendered (a quad or ellipsoid flattened to nothing, or coordinates beyond
/// [`MAX_COORDINATE`]).
pub fn primitives(shape: &Form, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
    let start = out.len();
    match *shape {
        Form::Mesh(ref mesh) => {
            let world: Vec<Vec3A> = mesh.positions.iter().map(|&p| m.transform_point3a(p)).collect();
            let mirrored = m.matrix3.determinant() < 0.0;
            for &[a, b, c] in mesh.triangles.iter() {
                let [a, b, c] = [a, b, c].map(|i| world[i as usize]);
                let (b, c) = if mirrored { (c, b) } else { (b, c) };
                // Triangles without area cannot be hit: meshes often hold a few; drop them.
                if let Some(t) = Triangle::new(a, b, c) {
                    out.push(Primitive::Triangle(t));
                }
            }
        }
        Form::Sphere { center, radius } => {
            let sphere = Sphere { center, radius };
            // Translation and uniform scale keep a sphere a sphere (and its uv frame); anything
            // else is intersected in object space.
            let lin = m.matrix3;
            let s = lin.x_axis.x;
            let diagonal_uniform = s > 0.0 && lin == glam::Mat3A::from_diagonal(Vec3::splat(s));
            if diagonal_uniform {
                let center = m.transform_point3a(sphere.center);
                out.push(Primitive::Sphere(Sphere { center, radius: radius * s }));
            } else {
                let ts = TransformedSphere::new(sphere, *m).ok_or(ShapeError::FlatSphere)?;
                out.push(Primitive::TransformedSphere(ts));
            }
        }
        Form::Quad { q, u, v } => push_quad(m, q, u, v, out)?,
        Form::Triangle { a, b, c } => {
            let [a, b, c] = [a, b, c].map(|p| m.transform_point3a(p));
            // A mirroring transform flips the winding; keep the normal facing the same side.
            let (b, c) = if m.matrix3.determinant() < 0.0 { (c, b) } else { (b, c) };
            let t = Triangle::new(a, b, c).ok_or(ShapeError::FlatTriangle(a, b, c))?;
            out.push(Primitive::Triangle(t));
        }
        Form::Box { min, max } => {
            let (a, b) = (min, max);
            let d = b - a;
            let (dx, dy, dz) = (Vec3A::X * d.x, Vec3A::Y * d.y, Vec3A::Z * d.z);
            push_quad(m, Vec3A::new(a.x, a.y, b.z), dx, dy, out)?; // front (+z)
            push_quad(m, Vec3A::new(b.x, a.y, b.z), -dz, dy, out)?; // right (+x)
            push_quad(m, Vec3A::new(b.x, a.y, a.z), -dx, dy, out)?; // back (-z)
            push_quad(m, a, dz, dy, out)?; // left (-x)
            push_quad(m, Vec3A::new(a.x, b.y, b.z), dx, -dz, out)?; // top (+y)
            push_quad(m, a, dx, dz, out)?; // bottom (-y)
        }
    }
    let far = out[start..].iter().map(Primitive::aabb).any(|b| {
        let m = b.min.abs().max(b.max.abs()).max_element();
        !(m <= MAX_COORDINATE)
    });
    if far {
        out.truncate(start);
        return Err(ShapeError::TooFar);
    }
    Ok(())
}

fn push_quad(m: &Affine3A, q: Vec3A, u: Vec3A, v: Vec3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
    let (q, mut u, mut v) = (m.transform_point3a(q), m.transform_vector3a(u), m.transform_vector3a(v));
    // A mirroring transform flips u x v; swap the edges so the normal keeps facing out.
    if m.matrix3.determinant() < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let quad = Quad::new(q, u, v).ok_or(ShapeError::FlatQuad(u, v))?;
    out.push(Primitive::Quad(quad));
    Ok(())
}
