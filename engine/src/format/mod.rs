//! The RON vocabulary that the scene file and every registered description (materials,
//! animation keys) share: validated values, colours that may name a texture, bounded file
//! reads, and the parse context those checks consult. It depends on nothing else of the
//! engine but the mesh type the context caches, so that the scene format above it and the
//! kinds it lists can both use it.

mod color;
pub(crate) mod context;
pub mod files;
pub mod registry;
mod values;

pub use color::Color;
pub(crate) use values::white;
pub use values::*;
