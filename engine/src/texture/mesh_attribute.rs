//! `MeshAttribute(name: "vertex_color", scale: 1)`: a mesh's own values as a colour, Mitsuba
//! 3's `mesh_attribute` texture (`src/textures/mesh_attribute.cpp`). Per-vertex values are
//! interpolated by the hit's barycentric weights, per-face values are constant over the face;
//! one channel is grey. A mesh file names its attributes (a PLY file's properties other than
//! positions, normals and uv, grouped as Mitsuba groups them: see `scene::ply`); the scene
//! loader refuses a material with this texture on an object that is not a mesh having it.

use super::{Texture, TextureId, TextureModel};
use crate::format::{Color, Rgb};
use serde::{Deserialize, Deserializer, de::Error};

/// A mesh's attribute `name` (`vertex_...`: interpolated by the hit's barycentric weights;
/// `face_...`: constant over a face; one channel is grey) times `scale` (>= 0, default 1):
/// Mitsuba's `mesh_attribute`. PLY integer properties are scaled to [0, 1] and read as sRGB, as
/// Mitsuba reads them. A material reading one must be on a `Mesh` that has it (checked at load,
/// naming the attributes the mesh has) and must not emit.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshAttribute {
    /// `vertex_` or `face_` and the attribute's name (`vertex_color`, `face_weight`).
    pub name: AttributeName,
    /// Multiplies the values (default 1, at least 0).
    #[serde(default = "one")]
    pub scale: crate::format::NonNegative,
}

fn one() -> crate::format::NonNegative {
    crate::format::NonNegative(1.0)
}

/// A mesh attribute's name: `vertex_...` or `face_...` (Mitsuba's rule), checked where written.
#[derive(Debug, Clone, PartialEq)]
pub struct AttributeName(pub String);

impl<'de> Deserialize<'de> for AttributeName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        let kind = name.strip_prefix("vertex_").or_else(|| name.strip_prefix("face_"));
        match kind {
            Some(rest) if !rest.is_empty() => Ok(AttributeName(name)),
            _ => Err(D::Error::custom(format!(
                "mesh attribute \"{name}\": its name starts with vertex_ or face_ (as vertex_color)"
            ))),
        }
    }
}

impl TextureModel for MeshAttribute {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::MeshAttribute { name: self.name.0.clone(), scale: self.scale.0 }
    }
}
