//! The RON vocabulary that the scene file and every registered description (materials,
//! shapes, lights, textures, animation keys) share: validated values, colours that may name a
//! texture, bounded file reads (glTF containers among them), frame-numbered file names, the parse context those checks
//! consult, and the registries' common macro. It depends on nothing else of the engine, so that the scene format above it
//! and the kinds it lists (the shapes below the acceleration structures among them) can all
//! use it.

mod color;
pub(crate) mod context;
pub mod files;
pub mod frames;
pub mod gltf;
pub mod registry;
mod values;
pub mod vdb;
pub mod vol;

pub(crate) use color::check_texture_name;
pub use color::{Color, Scalar};
pub(crate) use values::white;
pub use values::*;
