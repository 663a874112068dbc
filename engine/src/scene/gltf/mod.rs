//! glTF 2.0 (`.gltf` with its `.bin` and images, and `.glb`): meshes for `Mesh(file: ..)`.
//!
//! The `gltf` crate parses and validates the document; [`file`] resolves its buffers and reads
//! accessors within bounds, [`mesh`] turns a mesh's primitives into pathwave's mesh.

pub mod file;
pub mod mesh;

#[cfg(test)]
mod tests;

pub use file::GltfFile;
pub use mesh::MeshRef;

/// Whether `bytes` start as a glTF file does: the `.glb` magic `glTF`, or (after white space)
/// the `{` of a JSON document.
pub fn is_gltf(bytes: &[u8]) -> bool {
    bytes.starts_with(b"glTF") || bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{')
}
