//! `objects: [..]`: a shape with a material (a surface) or a medium (a volume), its transform,
//! motion and keyframes; checked as placed (`placement::primitives`) at load.

use super::assets::{MeshFile, open_edge};
use super::material::MaterialRef;
use super::transform::{TransformOp, compose};
use crate::format::registry::{fields, registry};
use crate::format::{Albedo, Color, Positive, Rgb, V3, context};
use crate::placement::{Form, primitives};
use crate::shape::ShapeModel;
use serde::Deserialize;
use serde::de::{Error, VariantAccess};

/// One object: a shape with either a material (a surface) or a medium (a volume), and an
/// optional list of transforms.
#[derive(Deserialize, Debug, Clone)]
#[serde(try_from = "RawObject")]
pub struct ObjectDesc {
    /// The shape, in object space.
    pub shape: ShapeDesc,
    /// What the shape is.
    pub body: Body,
    /// Light the surface emits besides what its material reflects (default none).
    pub emit: Option<EmitDesc>,
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

/// `emit: (radiance: (r, g, b), two_sided: false)`: the surface emits `radiance` (or a
/// texture's value at the point, by name) besides what its material reflects, as Mitsuba 3's
/// `area` emitter on a shape with a BSDF: on the side of the geometric normal only, unless
/// `two_sided`. Sampled as a light like an emitter's surface.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, rename = "Emit")]
pub struct EmitDesc {
    /// Emitted radiance, or the name of a texture.
    pub radiance: Color<Rgb>,
    /// Emit on both sides (default false: only on the side of the normal).
    #[serde(default)]
    pub two_sided: bool,
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
    emit: Option<EmitDesc>,
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
        match (&body, &r.emit) {
            (Body::Volume(_), Some(_)) => return Err("a medium does not emit: `emit` is for surfaces".into()),
            (Body::Surface(name), Some(_))
                if context::names(|n| n.is_some_and(|n| n.lights.contains(&name.0))) =>
            {
                return Err(format!(
                    "material \"{}\" is a DiffuseLight, which emits already: `emit` is for surfaces whose material reflects",
                    name.0
                ));
            }
            _ => {}
        }
        if r.motion.is_some() && matches!(body, Body::Volume(_)) {
            return Err("media do not move: `motion` is for surfaces".into());
        }
        if r.animate.is_some() && matches!(body, Body::Volume(_)) {
            return Err("media do not move: `animate` is for surfaces".into());
        }
        primitives(&r.shape.form(), &compose(&r.transform), &mut Vec::new()).map_err(|e| e.to_string())?;
        Ok(Self {
            shape: r.shape,
            body,
            emit: r.emit,
            transform: r.transform,
            motion: r.motion,
            animate: r.animate,
        })
    }
}

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

/// `Mesh(file: "assets/knot.obj")`: the triangles of an OBJ file (relative to the scene file),
/// read as the scene is parsed, smooth-shaded where the file gives vertex normals;
/// `face_normals: true` shades it flat all the same (Mitsuba's `face_normals`). Meshes are not
/// in the shape registry: their runtime form is the shared mesh data the world instances, not
/// a [`ShapeModel`] that places primitives.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDesc {
    file: MeshFile,
    #[serde(default)]
    face_normals: bool,
}

fn read_mesh<'de, A: VariantAccess<'de>>(variant: A) -> Result<MeshFile, A::Error> {
    let MeshDesc { file, face_normals } = fields::<MeshDesc, A>(variant)?;
    if !face_normals || file.mesh.normals.is_none() {
        return Ok(file);
    }
    // One flat copy per file, shared by the objects that ask for it (one BLAS).
    let key =
        crate::format::context::scene_dir().map(|d| d.join(format!("{}#face_normals", file.path.display())));
    let cached = key.as_deref().and_then(crate::format::context::mesh);
    let mesh = cached.unwrap_or_else(|| {
        let flat =
            std::sync::Arc::new(crate::accel::mesh::MeshData { normals: None, ..(*file.mesh).clone() });
        if let Some(k) = key {
            crate::format::context::keep_mesh(k, flat.clone());
        }
        flat
    });
    Ok(MeshFile { path: file.path, mesh })
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
