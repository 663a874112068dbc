//! Shapes placed in the world: a shape in its own space ([`Form`], what an entity's `Shape`
//! component holds) and an object-to-world transform become world-space [`Primitive`]s, or an
//! error that says why the placed shape cannot be rendered. The scene format checks its objects
//! with [`primitives`] at load; the world builds its BVH with it.
//!
//! [`Form`] has one variant per kind of the shape list ([`crate::shape::with_shapes`]), each a
//! [`ShapeModel`], and one for triangle meshes, which the world instances.

use crate::accel::mesh::MeshData;
use crate::shape::{Closed, Primitive, ShapeModel, Triangle, with_shapes};
use glam::Affine3A;
use std::sync::Arc;

pub use crate::shape::{MAX_COORDINATE, ShapeError};

/// Generates [`Form`] from the shape list, with a variant for meshes, and its dispatch.
macro_rules! forms {
    ($($(#[$attr:meta])* $variant:ident($ty:ty),)+) => {
        /// A shape in its own space.
        #[derive(Clone, Debug, PartialEq)]
        pub enum Form {
            $($(#[$attr])* #[doc = concat!("A [`", stringify!($ty), "`].")] $variant($ty),)+
            /// A triangle mesh (triangles without area are dropped).
            Mesh(Arc<MeshData>),
        }

        impl Form {
            /// The volume it closes, for a medium (a mesh's depends on its edges: see
            /// `scene::open_edge`); `None` for an open surface.
            pub fn closed(&self) -> Option<Closed> {
                match self {
                    $($(#[$attr])* Form::$variant(s) => s.closed(),)+
                    Form::Mesh(_) => None,
                }
            }

            /// Appends its primitives placed by `m` (see [`ShapeModel::place`]).
            fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
                match self {
                    $($(#[$attr])* Form::$variant(s) => s.place(m, out),)+
                    Form::Mesh(mesh) => {
                        place_mesh(mesh, m, out);
                        Ok(())
                    }
                }
            }
        }

        $($(#[$attr])*
        impl From<$ty> for Form {
            fn from(s: $ty) -> Self {
                Form::$variant(s)
            }
        })+
    };
}
with_shapes!(forms);

/// Appends the triangles of `mesh` placed by `m`, leaving out those without area.
fn place_mesh(mesh: &MeshData, m: &Affine3A, out: &mut Vec<Primitive>) {
    let world: Vec<_> = mesh.positions.iter().map(|&p| m.transform_point3a(p)).collect();
    let mirrored = m.matrix3.determinant() < 0.0;
    for &corners in mesh.triangles.iter() {
        let [a, b, c] = corners.map(|i| world[i as usize]);
        let (b, c) = if mirrored { (c, b) } else { (b, c) };
        // Triangles without area cannot be hit: meshes often hold a few; drop them.
        if let Some(mut t) = Triangle::new(a, b, c) {
            // The file's texture coordinates, in the order the corners took.
            t.uv = mesh.uvs.as_ref().map(|uv| {
                let [ta, tb, tc] = corners.map(|i| uv[i as usize]);
                if mirrored { [ta, tc, tb] } else { [ta, tb, tc] }
            });
            out.push(Primitive::Triangle(t));
        }
    }
}

/// Appends the world-space primitives of `shape` placed by `m`; an error says why the placed
/// shape cannot be rendered (a quad or ellipsoid flattened to nothing, or coordinates beyond
/// [`MAX_COORDINATE`]).
pub fn primitives(shape: &Form, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
    let start = out.len();
    shape.place(m, out)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::PrimitiveShape;
    use glam::{Vec2, Vec3, Vec3A};

    /// A mesh's baked triangles read its texture coordinates, also under a mirroring transform
    /// (which reverses their corners), as an instance of it does.
    #[test]
    fn baked_triangles_keep_the_files_uvs() {
        let mesh = MeshData {
            positions: vec![Vec3A::ZERO, Vec3A::X, Vec3A::Y],
            triangles: vec![[0, 1, 2]],
            normals: None,
            uvs: Some(vec![Vec2::new(0.2, 0.9), Vec2::new(0.8, 0.9), Vec2::new(0.2, 0.1)]),
            attributes: Vec::new(),
        };
        // The point a/4 + b/2 of the triangle: uv (0.2, 0.9) + (0.6, 0) / 4 + (0, -0.8) / 2.
        let want = Vec2::new(0.35, 0.5);
        for m in [Affine3A::IDENTITY, Affine3A::from_scale(Vec3::new(-2.0, 1.0, 1.0))] {
            let mut out = Vec::new();
            primitives(&Form::Mesh(Arc::new(mesh.clone())), &m, &mut out).unwrap();
            let [Primitive::Triangle(t)] = out.as_slice() else { panic!("{out:?}") };
            let p = m.transform_point3a(Vec3A::new(0.25, 0.5, 0.0));
            let uv = PrimitiveShape::surface(t, p, true).uv;
            assert!((uv - want).abs().max_element() < 1e-6, "{uv} under {m:?}");
        }
        // Without texture coordinates: the barycentric weights, as before.
        let plain = MeshData { uvs: None, ..mesh };
        let mut out = Vec::new();
        primitives(&Form::Mesh(Arc::new(plain)), &Affine3A::IDENTITY, &mut out).unwrap();
        assert_eq!(out[0].surface(Vec3A::new(0.25, 0.5, 0.0), true).uv, Vec2::new(0.25, 0.5));
    }
}
