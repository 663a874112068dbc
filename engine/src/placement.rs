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
    for &[a, b, c] in mesh.triangles.iter() {
        let [a, b, c] = [a, b, c].map(|i| world[i as usize]);
        let (b, c) = if mirrored { (c, b) } else { (b, c) };
        // Triangles without area cannot be hit: meshes often hold a few; drop them.
        if let Some(t) = Triangle::new(a, b, c) {
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
