//! glTF 2.0 (`.gltf` with its `.bin` and images, and `.glb`): meshes for `Mesh(file: ..)`, and
//! whole scenes read into the same [`crate::scene::SceneDesc`] as RON scenes.
//!
//! The `gltf` crate parses and validates the document; `format::gltf` resolves its buffers and reads
//! accessors within bounds, [`mesh`] turns a mesh's primitives into pathwave's mesh, and
//! [`convert`] writes a scene as RON text (which the RON loader then reads, as Mitsuba scenes
//! are: `pathwave convert` is the first half of loading), its meshes named by file and index.

pub mod convert;
pub mod mesh;

#[cfg(test)]
mod tests;

pub use crate::format::gltf::GltfFile;
pub use convert::{load, to_ron};
pub use mesh::MeshRef;

/// Whether `bytes` start as a glTF file does: the `.glb` magic `glTF`, or (after white space)
/// the `{` of a JSON document.
pub fn is_gltf(bytes: &[u8]) -> bool {
    bytes.starts_with(b"glTF") || bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{')
}

/// Whether `path` names a glTF scene (by its extension: `.gltf` or `.glb`).
pub fn is_gltf_scene(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}
