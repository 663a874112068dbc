//! `shape: Kind(..)`: [`ShapeDesc`] from the shape registry, and `Mesh(file: ..)`, the
//! triangles of a mesh file, beside it. Meshes are not in the shape registry: their runtime form
//! is the shared mesh data the world instances, not a [`ShapeModel`] that places primitives.

use crate::format::registry::{fields, registry};
use crate::placement::Form;
use crate::scene::assets::{MeshFile, MeshPath, MeshSource};
use crate::shape::ShapeModel;
use serde::Deserialize;
use serde::de::{Error, VariantAccess};
use std::sync::Arc;

/// `ShapeDesc` from the shape registry ([`crate::shape::with_shapes`]), with meshes beside it.
macro_rules! shape_descs {
    ($($(#[$attr:meta])* $variant:ident($ty:ty),)+) => {
        registry! {
            /// Shapes, in their own space: `Kind(field: value, ...)`, each checked as a whole.
            #[derive(Debug, Clone, PartialEq)]
            pub enum ShapeDesc, ShapeKind: dyn ShapeForm, "Shape",
                "a shape such as Sphere(center: (0, 0, 0), radius: 1)", read_shape {
                $($(#[$attr])* $variant($ty),)+
                Mesh(MeshFile) = read_mesh,
            }
        }
    };
}
crate::shape::with_shapes!(shape_descs);

/// Reads a shape kind's fields and builds it, checked once its `)` is read, so that an error
/// points there.
fn read_shape<'de, T: ShapeModel, A: VariantAccess<'de>>(variant: A) -> Result<T, A::Error> {
    T::build(fields::<T::Desc, A>(variant)?).map_err(A::Error::custom)
}

/// The triangles of a mesh file, relative to the scene file, read as the scene is parsed: OBJ
/// (tobj, faces triangulated), PLY (ASCII or binary of either byte order; polygons triangulated as
/// fans; positions, normals `nx ny nz`, uv `u v`, `s t` or `texture_u texture_v`, and the other
/// vertex and face properties as mesh attributes, grouped and named as Mitsuba 3 names them:
/// `vertex_color` from `red green blue`, `face_weight` from `weight_0`, ...; see `MeshAttribute`)
/// glTF 2.0 (`.gltf` with its buffers, or `.glb`; `mesh: "name"` or `mesh: 3` picks one of its
/// meshes, which may be left out when the file has one; all its primitives, or `primitive: 1`
/// alone; see [glTF input](#gltf-input)) or Mitsuba's `.serialized` (`shape_index` picks one of its
/// meshes, default 0; its vertex colours are the attribute `vertex_color`). The format is told by
/// the file's first bytes where they tell it (`ply`, `glTF` or a JSON `{`, the `.serialized` code),
/// else by its extension; another file is refused, naming the formats there are. Every count in a
/// file is checked against its length before anything is allocated. Triangles without area dropped.
/// `flip_normals: true` turns the mesh inside out (faces wound the other way, vertex normals
/// reversed), `flip_tex_coords: true` reads each v as 1 - v (both default false). With vertex
/// normals (`vn`) the mesh is smooth shaded, unless `face_normals: true` (Mitsuba's `face_normals`;
/// one flat copy of the file, shared by the objects that ask for it): BSDFs use the interpolated
/// normal, bent towards the triangle's where the ray arrives from behind it or would reflect into
/// the facet (Keller et al. 2017, as Cycles does), and rays leaving on the side the normals point
/// to start at the smooth surface they describe (Hanika's shadow-terminator offset, 2021), so the
/// terminator and the silhouette of a coarse mesh shade like the smooth surface's
/// (`tests/smooth.rs`); a reflection on the outer side leaves whatever the facet's normal says,
/// other directions on opposite sides of the two normals end the path; with vertex texture
/// coordinates (`vt`) uv interpolates them (else uv is the barycentric weights of the second and
/// third vertex). Objects naming the same file share one mesh and one BLAS: each is an instance
/// (transform, material, motion) under the TLAS, so 10,000 objects of one mesh cost 10,000 instance
/// records (`scenes/instances.ron`, written by `scenes/instances.py`); still objects whose mesh
/// no other object uses are traced together, their triangles in world space under one BVH
/// (`accel::instances`). Meshes with an emitting
/// material are baked into world-space flat-shaded triangles instead, so that light sampling finds
/// them.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDesc {
    file: MeshPath,
    #[serde(default)]
    shape_index: u32,
    #[serde(default)]
    mesh: Option<crate::scene::gltf::MeshRef>,
    #[serde(default)]
    primitive: Option<u32>,
    #[serde(default)]
    face_normals: bool,
    #[serde(default)]
    flip_normals: bool,
    #[serde(default)]
    flip_tex_coords: bool,
}

fn read_mesh<'de, A: VariantAccess<'de>>(variant: A) -> Result<MeshFile, A::Error> {
    let d = fields::<MeshDesc, A>(variant)?;
    let MeshPath { path, full, source } = d.file;
    let gltf_only = match (&d.mesh, d.primitive) {
        (Some(_), _) => Some("mesh"),
        (None, Some(_)) => Some("primitive"),
        (None, None) => None,
    };
    let mesh = match source {
        MeshSource::Unread => return Ok(MeshFile { path, mesh: Default::default() }),
        MeshSource::Mesh(_) | MeshSource::Serialized(_) if gltf_only.is_some() => {
            let message = format!("`{}` picks a mesh of a glTF file", gltf_only.unwrap());
            return Err(A::Error::custom(message));
        }
        MeshSource::Mesh(_) | MeshSource::Gltf(_) if d.shape_index != 0 => {
            let message = format!("shape_index {} picks a mesh of a .serialized file", d.shape_index);
            return Err(A::Error::custom(message));
        }
        MeshSource::Mesh(m) => m,
        MeshSource::Gltf(file) => {
            let key = full.join(format!("#{:?}#{:?}", d.mesh, d.primitive));
            match crate::format::context::read_before(&key) {
                Some(m) => m,
                None => {
                    let m = file.mesh_data(d.mesh.as_ref(), d.primitive, &full).map_err(A::Error::custom)?;
                    let m = Arc::new(m);
                    crate::format::context::keep(key, m.clone());
                    m
                }
            }
        }
        MeshSource::Serialized(file) => {
            let key = full.join(format!("#{}", d.shape_index));
            match crate::format::context::read_before(&key) {
                Some(m) => m,
                None => {
                    let m = Arc::new(file.mesh(d.shape_index as usize, &full).map_err(A::Error::custom)?);
                    crate::format::context::keep(key, m.clone());
                    m
                }
            }
        }
    };
    let face_normals = d.face_normals && mesh.normals.is_some();
    let flip_v = d.flip_tex_coords && mesh.uvs.is_some();
    if !(face_normals || flip_v || d.flip_normals) {
        return Ok(MeshFile { path, mesh });
    }
    // One changed copy per file, mesh and options, shared by the objects that ask for it (one
    // BLAS).
    let key = full.join(format!(
        "#{}#{:?}#{:?}#{face_normals}#{}#{flip_v}",
        d.shape_index, d.mesh, d.primitive, d.flip_normals
    ));
    let cached = crate::format::context::read_before(&key);
    let mesh = cached.unwrap_or_else(|| {
        let mut m = (*mesh).clone();
        if face_normals {
            m.normals = None;
        }
        if flip_v {
            m.uvs.iter_mut().flatten().for_each(|uv| uv.y = 1.0 - uv.y);
        }
        if d.flip_normals {
            m.triangles.iter_mut().for_each(|t| t.swap(1, 2));
            m.normals.iter_mut().flatten().for_each(|n| *n = -*n);
        }
        let m = Arc::new(m);
        crate::format::context::keep(key, m.clone());
        m
    });
    Ok(MeshFile { path, mesh })
}

/// What a shape description becomes in the world.
pub trait ShapeForm {
    /// The shape as the world holds it (a mesh shared, not copied).
    fn form(&self) -> Form;
}

impl<T: ShapeModel> ShapeForm for T
where
    Form: From<T>,
{
    fn form(&self) -> Form {
        self.clone().into()
    }
}

impl ShapeForm for MeshFile {
    fn form(&self) -> Form {
        Form::Mesh(self.mesh.clone())
    }
}

impl ShapeDesc {
    /// The shape as the world holds it (the mesh shared, not copied).
    pub fn form(&self) -> Form {
        self.model().form()
    }
}
